// The Senso glove (the hand paper's glove: 7 IMUs per hand) through its vendor's local server, which
// streams one JSON object per line over TCP (ports 53450 and up) and takes vibration commands the same way.
// What is read, per line: {"src": device address, "type": "position", "data": {"type": "rh" | "lh",
// "palm": {"pos": [x, y, z], "quat": [w, x, y, z]}, "wrist": {"quat": [...]}, "shoulder": {"quat": [...]},
// "fingers": [5 x {"quat": [w, x, y, z], "ang": [a, b], "bend": v}]}}, the thumb (fingers[0]) with a
// second IMU on its proximal phalanx as "quat2". Other packet types ("battery", pings) are skipped; a
// packet of the other hand is counted, not decoded.
// Into the solve (solve.hpp): the palm IMU is the back sensor, the finger IMUs sit on the intermediate
// phalanges (thumb: distal and proximal phalanx), the quaternions go through the IMU solve; a finger's
// bend value is a flex reading of its distal joint, which the IMU on the intermediate phalanx cannot see
// (flat 0 and fist 1 by default, 90 degrees; `glove calibrate` measures both). A left hand is mirrored
// onto the right-hand model (x kept, y and z negated in every quaternion: flexion is kept, abduction and
// twist change sign). Going out: vibration of one finger, {"dst": address, "type": "vibration", "data":
// {"type": finger, "dur": milliseconds, "str": 0..10}}.
#pragma once

#include <handemo/core/error.hpp>
#include <handemo/glove/detail/quat.hpp>
#include <handemo/glove/profile.hpp>

#include <nlohmann/json.hpp>

#include <array>
#include <cmath>
#include <cstdio>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace handemo {

/// Mirrors a rotation of a left hand onto the right-hand model (x kept, y and z negated) and back.
constexpr quat mirror_hand(const quat& q) noexcept { return {q.w, q.x, -q.y, -q.z}; }

/// @brief The sensors of a Senso glove for the solve: 7 IMUs (palm, thumb distal, four intermediate
/// phalanges, thumb proximal phalanx) and the bend values of the four fingers on their distal joints.
inline glove_profile senso_profile()
{
    glove_profile p;
    p.name = "senso";
    p.description = "Senso glove through its server's JSON lines (7 IMUs per hand and a bend value per finger)";
    p.rate_hz = 100;
    p.back_sensor = "palm";
    glove_report_layout L;
    auto imu = [&](const char* name, const char* bone) {
        glove_field f;
        f.name = name, f.kind = field_kind::quaternion, f.bone = bone;
        L.fields.push_back(f);
    };
    imu("palm", "palm");
    imu("thumb", "thumb_distal");
    imu("index", "index_intermediate");
    imu("middle", "middle_intermediate");
    imu("ring", "ring_intermediate");
    imu("pinky", "pinky_intermediate");
    imu("thumb2", "thumb_intermediate");
    for (std::size_t f = 1; f < 5; ++f) {
        glove_field g;
        g.name = std::string(hand_finger_names[f]) + "_bend", g.kind = field_kind::flex;
        g.bone = std::string(hand_finger_names[f]) + "_distal";
        g.flat = 0, g.fist = 1, g.fist_angle = 90, g.range_min = -0.5, g.range_max = 1.5;
        L.fields.push_back(g);
    }
    p.reports.push_back(std::move(L));
    p.index();
    return p;
}

/// @brief Everything a position packet carries besides what the solve uses.
struct senso_packet {
    std::string source;                      ///< the glove's address ("src")
    hand_side hand = hand_side::right;
    std::array<double, 3> palm_position{};   ///< "palm.pos" as sent (NaN when absent)
    quat wrist, shoulder;                    ///< as sent (identity when absent)
    std::array<std::array<double, 2>, 5> angles{};  ///< each finger's "ang"
    std::array<double, 5> bend{};            ///< each finger's "bend" (the thumb's is not used by the solve)
};

/// @brief Decodes the server's JSON lines of one hand (see the file comment).
class senso_decoder : public glove_decoder {
public:
    explicit senso_decoder(hand_side hand = hand_side::right, double unit_tolerance = 0.05) : p_(senso_profile()), hand_(hand)
    {
        p_.unit_tolerance = unit_tolerance;
        reset();
    }
    const glove_profile& profile() const noexcept override { return p_; }
    void reset() override
    {
        imu_.assign(7, quat{});
        flex_.assign(4, 0.0);
    }
    hand_side hand() const noexcept { return hand_; }
    /// The newest position packet of this hand.
    const senso_packet& last_packet() const noexcept { return packet_; }
    /// Packets of the other hand and of other types, skipped.
    std::size_t other_hand() const noexcept { return other_hand_; }
    std::size_t other_packets() const noexcept { return other_packets_; }

    decode_result decode(std::span<const std::uint8_t> bytes, double host_time, glove_sample& out) override
    {
        decode_result r;
        using nlohmann::json;
        const std::string_view text(reinterpret_cast<const char*>(bytes.data()), bytes.size());
        json j;
        bool too_deep = false;
        try {
            // a position packet nests 5 levels: deeper input is refused before it is built
            j = json::parse(text, [&](int depth, json::parse_event_t, json&) { return !(too_deep = too_deep || depth > 8); }, true);
        } catch (const json::exception& e) {
            return fault(r, report_fault::syntax, std::string("not a JSON object: ") + e.what());
        }
        if (too_deep) return fault(r, report_fault::syntax, "JSON nested deeper than 8 levels");
        if (!j.is_object()) return fault(r, report_fault::syntax, "not a JSON object");
        const auto type = j.find("type");
        if (type == j.end() || !type->is_string()) return fault(r, report_fault::missing_field, "no \"type\"");
        if (*type != "position") {
            ++other_packets_;
            return r;
        }
        const auto data = j.find("data");
        if (data == j.end() || !data->is_object()) return fault(r, report_fault::missing_field, "position packet without \"data\"");
        const auto side = data->find("type");
        if (side == data->end() || !side->is_string() || (*side != "rh" && *side != "lh"))
            return fault(r, report_fault::missing_field, "position packet without \"data.type\" \"rh\" or \"lh\"");
        const hand_side h = *side == "rh" ? hand_side::right : hand_side::left;
        if (h != hand_) {
            ++other_hand_;
            return r;
        }
        std::array<quat, 7> q;
        senso_packet pk;
        pk.hand = h;
        if (const auto s = j.find("src"); s != j.end() && s->is_string()) pk.source = s->get<std::string>();
        std::string why;
        report_fault f = report_fault::none;
        auto read_quat = [&](const json& o, const char* key, const std::string& what, quat& dst, bool required) {
            if (f != report_fault::none) return;
            const auto v = o.is_object() ? o.find(key) : o.end();
            if (!o.is_object() || v == o.end()) {
                if (required) f = report_fault::missing_field, why = what + ": no \"" + key + "\"";
                return;
            }
            if (!v->is_array() || v->size() != 4 || !(*v)[0].is_number() || !(*v)[1].is_number() || !(*v)[2].is_number() || !(*v)[3].is_number()) {
                f = report_fault::syntax, why = what + ": \"" + key + "\" is not [w, x, y, z]";
                return;
            }
            const quat c{(*v)[0].get<double>(), (*v)[1].get<double>(), (*v)[2].get<double>(), (*v)[3].get<double>()};
            const double n = norm(c);
            if (!std::isfinite(n)) f = report_fault::not_finite, why = what + ": quaternion has a NaN or infinite component";
            else if (std::abs(n - 1) > p_.unit_tolerance)
                f = report_fault::non_unit_quaternion, why = what + ": quaternion norm " + std::to_string(n) + " is not 1";
            else dst = normalized(c);
        };
        auto read_number = [&](const json& o, const char* key, const std::string& what, double& dst) {
            if (f != report_fault::none) return;
            const auto v = o.find(key);
            if (v == o.end()) return (void)(f = report_fault::missing_field, why = what + ": no \"" + key + "\"");
            if (!v->is_number()) return (void)(f = report_fault::syntax, why = what + ": \"" + key + "\" is not a number");
            dst = v->get<double>();
        };
        const json& palm = data->contains("palm") ? (*data)["palm"] : json();
        read_quat(palm, "quat", "palm", q[0], true);
        if (f == report_fault::none && palm.is_object() && palm.contains("pos")) {
            const auto& v = palm["pos"];
            if (!v.is_array() || v.size() != 3 || !v[0].is_number() || !v[1].is_number() || !v[2].is_number())
                f = report_fault::syntax, why = "palm: \"pos\" is not [x, y, z]";
            else pk.palm_position = {v[0].get<double>(), v[1].get<double>(), v[2].get<double>()};
        }
        if (data->contains("wrist")) read_quat((*data)["wrist"], "quat", "wrist", pk.wrist, false);
        if (data->contains("shoulder")) read_quat((*data)["shoulder"], "quat", "shoulder", pk.shoulder, false);
        const auto fingers = data->find("fingers");
        if (f == report_fault::none && (fingers == data->end() || !fingers->is_array() || fingers->size() != 5))
            f = report_fault::missing_field, why = "\"fingers\" is not an array of 5";
        for (std::size_t k = 0; k < 5 && f == report_fault::none; ++k) {
            const json& fo = (*fingers)[k];
            const std::string what = "finger " + std::string(hand_finger_names[k]);
            if (!fo.is_object()) {
                f = report_fault::syntax, why = what + " is not an object";
                break;
            }
            read_quat(fo, "quat", what, q[1 + k], true);
            if (k == 0) read_quat(fo, "quat2", what, q[6], true);
            read_number(fo, "bend", what, pk.bend[k]);
            if (f == report_fault::none && fo.contains("ang")) {
                const auto& a = fo["ang"];
                if (!a.is_array() || a.size() != 2 || !a[0].is_number() || !a[1].is_number()) f = report_fault::syntax, why = what + ": \"ang\" is not [a, b]";
                else pk.angles[k] = {a[0].get<double>(), a[1].get<double>()};
            }
            if (f == report_fault::none && k > 0) {
                const auto* fl = p_.flexes[k - 1];
                if (!std::isfinite(pk.bend[k])) f = report_fault::not_finite, why = what + ": bend is NaN or infinite";
                else if (pk.bend[k] < fl->range_min || pk.bend[k] > fl->range_max)
                    f = report_fault::out_of_range, why = what + ": bend " + std::to_string(pk.bend[k]) + " is outside [" +
                                                         std::to_string(fl->range_min) + ", " + std::to_string(fl->range_max) + "]";
            }
        }
        if (f != report_fault::none) return fault(r, f, why);
        for (std::size_t k = 0; k < 7; ++k) imu_[k] = h == hand_side::left ? mirror_hand(q[k]) : q[k];
        for (std::size_t k = 0; k < 4; ++k) flex_[k] = pk.bend[k + 1];
        packet_ = std::move(pk);
        r.frame = true;
        out.imu = imu_;
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
        return r;
    }
    glove_profile p_;
    hand_side hand_;
    std::vector<quat> imu_;
    std::vector<double> flex_;
    senso_packet packet_;
    std::size_t other_hand_ = 0, other_packets_ = 0;
};

/// @brief A position packet line (no line end) of sample `s` of senso_profile() sensors: the Senso
/// server's format, for simulation and tests. A left hand's quaternions are mirrored back.
inline std::string senso_position_line(const glove_sample& s, hand_side hand, const std::string& source = "00:00:00:00:00:01")
{
    auto q = [&](std::size_t k) {
        quat v = k < s.imu.size() ? s.imu[k] : quat{};
        if (hand == hand_side::left) v = mirror_hand(v);
        char b[128];
        std::snprintf(b, sizeof b, "[%.9f,%.9f,%.9f,%.9f]", v.w, v.x, v.y, v.z);
        return std::string(b);
    };
    auto num = [](double v) {
        char b[32];
        std::snprintf(b, sizeof b, "%.9f", v);
        return std::string(b);
    };
    std::string line = "{\"src\":\"" + source + "\",\"type\":\"position\",\"data\":{\"type\":\"" + (hand == hand_side::right ? "rh" : "lh") +
                       "\",\"palm\":{\"pos\":[0.0,0.0,0.0],\"quat\":" + q(0) + "},\"wrist\":{\"quat\":[1,0,0,0]},\"fingers\":[";
    for (std::size_t k = 0; k < 5; ++k) {
        const double bend = k > 0 && k - 1 < s.flex.size() ? s.flex[k - 1] : 0.0;
        line += std::string(k ? "," : "") + "{\"quat\":" + q(1 + k) + (k == 0 ? ",\"quat2\":" + q(6) : std::string()) +
                ",\"ang\":[0.0,0.0],\"bend\":" + num(bend) + "}";
    }
    return line + "]}}";
}

/// @brief The vibration command line (with its line end) for one finger of the glove at `address`.
/// @param finger thumb, index, middle, ring or pinky. @param strength 0..10. @throws value_error.
inline std::string senso_vibration(const std::string& address, std::string_view finger, int duration_ms, int strength)
{
    bool ok = false;
    for (auto n : hand_finger_names) ok = ok || n == finger;
    if (!ok) throw value_error("senso vibration: finger '" + std::string(finger) + "' is not thumb, index, middle, ring or pinky");
    if (duration_ms < 0 || duration_ms > 65535 || strength < 0 || strength > 10)
        throw value_error("senso vibration: duration " + std::to_string(duration_ms) + " ms (0..65535) or strength " + std::to_string(strength) + " (0..10) out of range");
    return nlohmann::json{{"dst", address}, {"type", "vibration"}, {"data", {{"type", finger}, {"dur", duration_ms}, {"str", strength}}}}.dump() + "\n";
}

}  // namespace handemo
