// OpenGloves / LucidGloves: ASCII lines in the "alpha encoding" over USB serial (115200 baud) or Bluetooth
// serial. A line is keys followed by decimal values: A..E the curl of thumb, index, middle, ring, pinky;
// (AB)..(EB) each finger's splay; (AAA)..(EAD) per-joint values, four per finger (joint 0..3 from the
// palm); F, G the joystick x and y; P the analog trigger; H joystick click, I trigger button, J and K the
// A and B buttons, L grab, M pinch, N menu, O calibrate (a button key without a value means pressed);
// (ZV) firmware version, (ZG) device type, (ZH) hand (0 left, 1 right). Analog values run from 0 to the
// firmware's maximum, 1023 or 4095 (`analog_max`).
// Into the solve: per joint, a joint's own value when the line has one, else its finger's curl (as the
// driver does); joints 0, 1, 2 of a finger are its MCP, PIP and DIP joints (thumb: CMC, MCP, IP), joint 3 is
// kept but not mapped. A value v / analog_max in [0, 1] is a flex reading with flat 0 and fist 1 standing
// for the joint's fist angle (MCP 90, PIP 110, DIP 80; thumb CMC 45, MCP 60, IP 80 degrees), calibrated by
// `glove calibrate`; a splay v / analog_max in [0, 1] is centred (0.5: the flat hand's spread) and reads as
// MCP abduction up to +-20 degrees (thumb CMC 30), away from the middle finger. What a glove can sense: the
// flexion of each joint (with joint values) or of each finger (curls only, every joint at the same fraction)
// and the spread; no twist, no metacarpal bend, values clamped to [0, analog_max].
// A line is refused whole (and counted) when it has a character outside keys and digits, an analog key
// without a value or a value above analog_max; an unknown key is a warning and the rest is used.
// Going out: force feedback "A<t>B<i>C<m>D<r>E<p>\n" (0 = free .. 1000 = locked per finger) and a haptic
// pulse "F<frequency>G<duration>H<amplitude>\n", the driver's two command lines.
#pragma once

#include <handemo/core/error.hpp>
#include <handemo/glove/profile.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace handemo {

/// @brief Every field of the alpha encoding, normalised: analog values in [0, 1], NaN where never sent.
struct opengloves_state {
    static constexpr double none = std::numeric_limits<double>::quiet_NaN();
    std::array<double, 5> curl{none, none, none, none, none};
    std::array<double, 5> splay{none, none, none, none, none};
    std::array<std::array<double, 4>, 5> joint{{{none, none, none, none}, {none, none, none, none}, {none, none, none, none},
                                                {none, none, none, none}, {none, none, none, none}}};
    double joy_x = none, joy_y = none, trigger = none;  ///< joystick in [0, 1] (0.5 centred), analog trigger
    bool joy_click = false, trigger_button = false, a = false, b = false, grab = false, pinch = false, menu = false, calibrate = false;
    std::string firmware_version, device_type, hand;  ///< the info fields as sent ((ZV), (ZG), (ZH))
};

/// Per-joint fist angles (degrees) of opengloves_profile(): [finger][MCP, PIP, DIP].
inline constexpr std::array<std::array<double, 3>, 5> opengloves_fist_angles{{{45, 60, 80}, {90, 110, 80}, {90, 110, 80}, {90, 110, 80}, {90, 110, 80}}};
/// Abduction (degrees) at full splay, per finger (negative: toward the thumb).
inline constexpr std::array<double, 5> opengloves_splay_angles{-30, -20, 10, 20, 20};

/// @brief The sensors of an OpenGloves glove for the solve: 15 joint flexions (finger-major: MCP, PIP,
/// DIP) then 5 splays, readings normalised to [0, 1] by the decoder.
inline glove_profile opengloves_profile()
{
    glove_profile p;
    p.name = "opengloves";
    p.description = "OpenGloves/LucidGloves alpha encoding over serial (curls, splay, per-joint values)";
    p.rate_hz = 60;
    glove_report_layout L;
    for (std::size_t f = 0; f < 5; ++f)
        for (std::size_t k = 0; k < 3; ++k) {
            glove_field g;
            g.kind = field_kind::flex;
            g.bone = std::string(hand_finger_names[f]) + "_" + std::string(hand_segment_names[k + 1]);
            g.name = g.bone;
            g.flat = 0, g.fist = 1, g.fist_angle = opengloves_fist_angles[f][k], g.range_min = 0, g.range_max = 1;
            L.fields.push_back(g);
        }
    for (std::size_t f = 0; f < 5; ++f) {
        glove_field g;
        g.kind = field_kind::flex;
        g.name = std::string(hand_finger_names[f]) + "_splay";
        g.bone = std::string(hand_finger_names[f]) + "_proximal";
        g.rotation_axis = axis::z;
        g.flat = 0.5, g.fist = 1, g.fist_angle = opengloves_splay_angles[f], g.range_min = 0, g.range_max = 1;
        g.fist_calibrated = false;
        L.fields.push_back(g);
    }
    p.reports.push_back(std::move(L));
    p.index();
    return p;
}

/// @brief Parses alpha-encoded lines (see the file comment) into opengloves_state and samples.
class opengloves_decoder : public glove_decoder {
public:
    /// @param analog_max the firmware's largest analog value (1023 or 4095). @throws value_error otherwise.
    explicit opengloves_decoder(int analog_max = 4095) : p_(opengloves_profile()), max_(analog_max)
    {
        if (analog_max < 1 || analog_max > 65535) throw value_error("opengloves: analog maximum " + std::to_string(analog_max) + " is not in 1..65535");
        reset();
    }
    const glove_profile& profile() const noexcept override { return p_; }
    void reset() override
    {
        state_ = {};
        flex_.assign(20, 0.0);
        for (std::size_t f = 0; f < 5; ++f) flex_[15 + f] = 0.5;
    }
    int analog_max() const noexcept { return max_; }
    /// Every field of the newest lines.
    const opengloves_state& state() const noexcept { return state_; }

    decode_result decode(std::span<const std::uint8_t> bytes, double host_time, glove_sample& out) override
    {
        decode_result r;
        opengloves_state s = state_;
        // buttons are held only while their key is in the line
        s.joy_click = s.trigger_button = s.a = s.b = s.grab = s.pinch = s.menu = s.calibrate = false;
        bool finger_data = false;
        std::size_t i = 0;
        const std::size_t n = bytes.size();
        auto digits = [&](long& v) {
            const std::size_t start = i;
            v = 0;
            while (i < n && bytes[i] >= '0' && bytes[i] <= '9' && i - start < 9) v = v * 10 + (bytes[i++] - '0');
            return i > start;
        };
        while (i < n) {
            const std::uint8_t c = bytes[i];
            std::string key;
            if (c == '(') {
                const std::size_t start = i++;
                while (i < n && bytes[i] >= 'A' && bytes[i] <= 'Z') key += static_cast<char>(bytes[i++]);
                if (i >= n || bytes[i] != ')' || key.empty()) return fault(r, report_fault::syntax, "unclosed or empty key at column " + std::to_string(start + 1));
                ++i;
                key = "(" + key + ")";
            } else if (c >= 'A' && c <= 'Z') {
                key = static_cast<char>(c);
                ++i;
            } else if ((c == ' ' || c == '\t' || c == '\r') ) {
                ++i;
                continue;
            } else {
                char b[8];
                std::snprintf(b, sizeof b, c >= 0x20 && c < 0x7f ? "'%c'" : "0x%02x", c);
                return fault(r, report_fault::syntax, std::string("unexpected character ") + b + " at column " + std::to_string(i + 1));
            }
            long v = 0;
            const bool has_value = digits(v);
            if (i < n && bytes[i] >= '0' && bytes[i] <= '9') return fault(r, report_fault::out_of_range, "value of " + key + " has too many digits");
            const double x = static_cast<double>(v) / max_;
            auto analog = [&](double& dst) {
                if (!has_value) return fault(r, report_fault::syntax, "key " + key + " has no value"), false;
                if (v > max_) return fault(r, report_fault::out_of_range, key + " " + std::to_string(v) + " is above " + std::to_string(max_)), false;
                dst = x;
                return true;
            };
            if (key.size() == 1 && key[0] <= 'E') {
                if (!analog(s.curl[static_cast<std::size_t>(key[0] - 'A')])) return r;
                finger_data = true;
            } else if (key.size() == 4 && key[1] >= 'A' && key[1] <= 'E' && key[2] == 'B') {
                if (!analog(s.splay[static_cast<std::size_t>(key[1] - 'A')])) return r;
                finger_data = true;
            } else if (key.size() == 5 && key[1] >= 'A' && key[1] <= 'E' && key[2] == 'A' && key[3] >= 'A' && key[3] <= 'D') {
                if (!analog(s.joint[static_cast<std::size_t>(key[1] - 'A')][static_cast<std::size_t>(key[3] - 'A')])) return r;
                finger_data = true;
            } else if (key == "F" || key == "G" || key == "P") {
                if (!analog(key == "F" ? s.joy_x : key == "G" ? s.joy_y : s.trigger)) return r;
            } else if (key.size() == 1 && key[0] >= 'H' && key[0] <= 'O') {
                bool* b[] = {&s.joy_click, &s.trigger_button, &s.a, &s.b, &s.grab, &s.pinch, &s.menu, &s.calibrate};
                *b[key[0] - 'H'] = !has_value || v != 0;
            } else if (key == "(ZV)" || key == "(ZG)" || key == "(ZH)") {
                if (!has_value) return fault(r, report_fault::syntax, "info key " + key + " has no value");
                (key == "(ZV)" ? s.firmware_version : key == "(ZG)" ? s.device_type : s.hand) = std::to_string(v);
            } else if (r.warning == report_fault::none) {
                r.warning = report_fault::unknown_key;
                r.warning_message = "unknown key " + key + " ignored";
            }
        }
        state_ = s;
        if (!finger_data) return r;
        for (std::size_t f = 0; f < 5; ++f) {
            for (std::size_t k = 0; k < 3; ++k) {
                const double j = state_.joint[f][k];
                const double v = std::isnan(j) ? state_.curl[f] : j;
                flex_[f * 3 + k] = std::isnan(v) ? 0.0 : v;
            }
            flex_[15 + f] = std::isnan(state_.splay[f]) ? 0.5 : state_.splay[f];
        }
        r.frame = true;
        out.imu.clear();
        out.flex = flex_;
        out.host_time = host_time;
        out.device_time = std::numeric_limits<double>::quiet_NaN();
        out.sequence = -1;
        return r;
    }

private:
    static decode_result& fault(decode_result& r, report_fault f, std::string m)
    {
        r.fault = f;
        r.message = std::move(m);
        r.warning = report_fault::none;
        r.warning_message.clear();
        return r;
    }
    glove_profile p_;
    int max_;
    opengloves_state state_;
    std::vector<double> flex_;
};

/// @brief An alpha-encoded line (no line end) of `s`: curls A..E, splay (AB)..(EB) and, with `joints`, the
/// per-joint values (AAA)..(EAC) of opengloves_profile() readings (each finger's curl is its PIP value,
/// the firmware's curl sensor); then the other fields of `extra` (joystick, trigger, buttons, info).
inline std::string opengloves_line(const glove_sample& s, int analog_max, bool joints = true, const opengloves_state* extra = nullptr)
{
    auto val = [&](double x) { return std::to_string(std::lround(std::clamp(x, 0.0, 1.0) * analog_max)); };
    std::string line;
    for (std::size_t f = 0; f < 5; ++f) line += static_cast<char>('A' + f) + val(s.flex[f * 3 + 1]);
    for (std::size_t f = 0; f < 5; ++f) line += "(" + std::string(1, static_cast<char>('A' + f)) + "B)" + val(s.flex[15 + f]);
    if (joints)
        for (std::size_t f = 0; f < 5; ++f)
            for (std::size_t k = 0; k < 3; ++k) line += "(" + std::string(1, static_cast<char>('A' + f)) + "A" + static_cast<char>('A' + k) + ")" + val(s.flex[f * 3 + k]);
    if (extra) {
        const auto& e = *extra;
        if (!std::isnan(e.joy_x)) line += "F" + val(e.joy_x);
        if (!std::isnan(e.joy_y)) line += "G" + val(e.joy_y);
        if (!std::isnan(e.trigger)) line += "P" + val(e.trigger);
        const bool b[] = {e.joy_click, e.trigger_button, e.a, e.b, e.grab, e.pinch, e.menu, e.calibrate};
        for (int k = 0; k < 8; ++k)
            if (b[k]) line += static_cast<char>('H' + k);
        if (!e.firmware_version.empty()) line += "(ZV)" + e.firmware_version;
        if (!e.device_type.empty()) line += "(ZG)" + e.device_type;
        if (!e.hand.empty()) line += "(ZH)" + e.hand;
    }
    return line;
}

/// @brief The force-feedback command line: per finger (thumb..pinky) 0 = free .. 1 = locked. @throws value_error.
inline std::string opengloves_force_feedback(const std::array<double, 5>& lock)
{
    std::string line;
    for (std::size_t f = 0; f < 5; ++f) {
        if (!(lock[f] >= 0 && lock[f] <= 1)) throw value_error("opengloves force feedback: " + std::string(hand_finger_names[f]) + " " + std::to_string(lock[f]) + " is not in [0, 1]");
        line += static_cast<char>('A' + f) + std::to_string(std::lround(lock[f] * 1000));
    }
    return line + "\n";
}

/// @brief The haptic pulse command line. @throws value_error for a negative or non-finite value or an amplitude above 1.
inline std::string opengloves_haptics(double frequency_hz, double duration_s, double amplitude)
{
    if (!(frequency_hz >= 0 && duration_s >= 0 && amplitude >= 0 && amplitude <= 1) || !std::isfinite(frequency_hz) || !std::isfinite(duration_s))
        throw value_error("opengloves haptics: frequency, duration >= 0 and amplitude in [0, 1] expected");
    char b[96];
    std::snprintf(b, sizeof b, "F%.2fG%.2fH%.2f\n", frequency_hz, duration_s, amplitude);
    return b;
}

}  // namespace handemo
