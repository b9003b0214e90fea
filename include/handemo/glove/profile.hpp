// Device profiles as data and the report decoder. A profile (JSON, `handemo-glove-profile/1`) says which
// HID report id carries which values, the byte layout of each value (integer width or float, endianness,
// fixed-point scale), the kind of sensor (an IMU orientation quaternion or a flex-sensor reading) and the
// bone of the 23-joint hand (hand.hpp) it sits on; optional timestamp and sequence-counter fields give the
// device's own clock and let dropped reports be counted. The decoder turns report bytes into a
// glove_sample; a malformed report (short, unknown id, NaN, non-unit quaternion, value out of range,
// clock running backwards) is refused whole with a report_fault and a message saying what was wrong, and
// the decoder's state is left as it was. Offsets count from the first byte the transport returns, which
// is the report id for devices with numbered reports (hidapi's convention).
#pragma once

#include <handemo/core/error.hpp>
#include <handemo/core/io.hpp>
#include <handemo/glove/detail/quat.hpp>
#include <handemo/motion/hand.hpp>

#include <nlohmann/json.hpp>

#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <limits>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace handemo {

/// Which hand a glove is on.
enum class hand_side : std::uint8_t { right, left };
constexpr std::string_view to_string(hand_side h) noexcept { return h == hand_side::right ? "right" : "left"; }
/// @throws value_error for anything but "right" or "left".
inline hand_side hand_side_from_string(std::string_view s)
{
    if (s == "right") return hand_side::right;
    if (s == "left") return hand_side::left;
    throw value_error("glove: hand '" + std::string(s) + "' is not right or left");
}

/// Binary type of one value in a report.
enum class value_type : std::uint8_t { u8, i8, u16, i16, u32, i32, f32 };
/// What a field carries.
enum class field_kind : std::uint8_t { quaternion, flex, timestamp, sequence };

constexpr std::size_t value_size(value_type t) noexcept
{
    switch (t) {
    case value_type::u8:
    case value_type::i8: return 1;
    case value_type::u16:
    case value_type::i16: return 2;
    default: return 4;
    }
}

/// @brief One field of a report: a sensor (quaternion: 4 values; flex: 1) or the clock or a counter.
struct glove_field {
    std::string name;               ///< sensor name (unique in the profile), or "timestamp"/"sequence"
    field_kind kind = field_kind::quaternion;
    std::string bone;               ///< joint of the 23-joint hand the sensor sits on (sensors only)
    std::size_t offset = 0;         ///< byte offset from the first byte of the report
    value_type type = value_type::i16;
    bool big_endian = false;
    double scale = 1;               ///< raw units per 1.0 (Q14 quaternions: 16384; timestamp: ticks per second)
    std::array<int, 4> order{0, 1, 2, 3};  ///< quaternion component order in the report, indices into w,x,y,z
    // flex sensors
    double range_min = -std::numeric_limits<double>::infinity(), range_max = std::numeric_limits<double>::infinity();
    double flat = 0, fist = 1;      ///< nominal raw values with the hand flat and in a fist (calibration overrides)
    double fist_angle = 90;         ///< the joint angle (degrees) the fist value stands for
    bool fist_calibrated = true;    ///< a fist moves this sensor (bend); false for spread sensors, which keep `fist`
    axis rotation_axis = axis::x;   ///< which angle of the bone a flex sensor measures (x: flexion)
    std::size_t sensor = 0;         ///< index among the profile's sensors of this kind (set by the parser)
    std::size_t bytes() const noexcept { return value_size(type) * (kind == field_kind::quaternion ? 4 : 1); }
};

/// @brief One report id and the fields it carries.
struct glove_report_layout {
    int id = -1;                    ///< report id checked at byte 0, or -1 for devices without numbered reports
    std::size_t size = 0;           ///< minimum length in bytes (the end of the last field by default)
    bool completes_frame = true;    ///< a sample is emitted when this report arrives
    std::vector<glove_field> fields;
};

/// @brief How a finger's bend is split over its joints (sensors see one segment's orientation).
struct finger_coupling {
    double proximal_weight = 1.0;      ///< share of the bend at MCP (thumb: CMC)
    double intermediate_weight = 1.0;  ///< share at PIP (thumb: MCP)
    double distal_of_intermediate = 2.0 / 3.0;  ///< DIP = this x PIP (thumb: IP = this x MCP)
};

/// @brief A glove: its USB ids, reports, sensors, calibration defaults and finger coupling.
struct glove_profile {
    std::string name, description;
    std::optional<std::uint16_t> vendor_id, product_id;
    double rate_hz = 100;                    ///< nominal report (sample) rate
    double unit_tolerance = 0.05;            ///< | |q| - 1 | above this is a malformed quaternion
    std::string back_sensor;                 ///< the IMU on the back of the hand (orientations are made relative to it)
    quat back_mount;                         ///< the back sensor's axes in the hand frame (hand.hpp: +Y to the fingers, +Z palm)
    finger_coupling coupling;
    std::vector<std::vector<std::uint8_t>> init_features;  ///< feature reports sent after opening (e.g. start streaming)
    std::vector<glove_report_layout> reports;
    std::vector<const glove_field*> imus, flexes;  ///< sensors by kind, in profile order (point into reports)
    bool has_timestamp = false, has_sequence = false;

    glove_profile() = default;
    glove_profile(const glove_profile& o) { *this = o; }
    glove_profile& operator=(const glove_profile& o)
    {
        name = o.name, description = o.description, vendor_id = o.vendor_id, product_id = o.product_id;
        rate_hz = o.rate_hz, unit_tolerance = o.unit_tolerance, back_sensor = o.back_sensor, back_mount = o.back_mount;
        coupling = o.coupling, init_features = o.init_features, reports = o.reports;
        index();
        return *this;
    }
    /// Index of the back sensor among the IMUs, or -1 (flex gloves).
    int back_index() const noexcept
    {
        for (std::size_t i = 0; i < imus.size(); ++i)
            if (imus[i]->name == back_sensor) return static_cast<int>(i);
        return -1;
    }
    /// Rebuilds imus/flexes and the sensor indices (after editing `reports`).
    void index()
    {
        imus.clear(), flexes.clear();
        has_timestamp = has_sequence = false;
        for (auto& r : reports)
            for (auto& f : r.fields) {
                if (f.kind == field_kind::quaternion) f.sensor = imus.size(), imus.push_back(&f);
                else if (f.kind == field_kind::flex) f.sensor = flexes.size(), flexes.push_back(&f);
                else if (f.kind == field_kind::timestamp) has_timestamp = true;
                else has_sequence = true;
            }
    }
};

namespace detail {

inline std::uint64_t parse_hex_or_int(const nlohmann::json& v, const std::string& what)
{
    if (v.is_number_unsigned()) return v.get<std::uint64_t>();
    if (v.is_string()) {
        const std::string s = v.get<std::string>();
        try {
            std::size_t used = 0;
            const auto x = std::stoull(s, &used, 0);
            if (used == s.size()) return x;
        } catch (...) {
        }
    }
    throw format_error(what + ": '" + v.dump() + "' is not a non-negative integer (e.g. 4660 or \"0x1234\")");
}

inline value_type parse_value_type(const std::string& s, const std::string& what)
{
    static constexpr std::array<std::pair<std::string_view, value_type>, 7> names{
        {{"u8", value_type::u8}, {"i8", value_type::i8}, {"u16", value_type::u16}, {"i16", value_type::i16},
         {"u32", value_type::u32}, {"i32", value_type::i32}, {"f32", value_type::f32}}};
    for (auto& [n, t] : names)
        if (s == n) return t;
    throw format_error(what + ": type '" + s + "' is not one of u8, i8, u16, i16, u32, i32, f32");
}

}  // namespace detail

/// @brief Parses a profile from JSON text.
/// @param source file name used in messages.
/// @throws format_error naming the file and the field (unknown bone or kind, overlapping or missing offsets,
///         duplicate sensor names, no back sensor for an IMU glove).
inline glove_profile parse_glove_profile(std::string_view text, const std::string& source = "profile")
{
    using nlohmann::json;
    json j;
    try {
        j = json::parse(text, [&](int depth, json::parse_event_t, json&) {
            if (depth > 16) throw format_error("glove profile: " + source + ": JSON nested deeper than 16 levels");
            return true;
        });
    } catch (const json::exception& e) {
        throw format_error("glove profile: " + source + ": " + e.what());
    }
    const std::string where = "glove profile: " + source;
    auto need = [&](const json& o, const char* key, const std::string& ctx) -> const json& {
        if (!o.is_object() || !o.contains(key)) throw format_error(ctx + ": missing \"" + key + "\"");
        return o.at(key);
    };
    try {
        if (j.value("format", std::string()) != "handemo-glove-profile/1")
            throw format_error(where + ": \"format\" is '" + j.value("format", std::string("(missing)")) +
                               "', expected 'handemo-glove-profile/1'");
        glove_profile p;
        p.name = need(j, "name", where).get<std::string>();
        p.description = j.value("description", std::string());
        if (j.contains("vendor_id")) p.vendor_id = static_cast<std::uint16_t>(detail::parse_hex_or_int(j["vendor_id"], where + ": vendor_id"));
        if (j.contains("product_id")) p.product_id = static_cast<std::uint16_t>(detail::parse_hex_or_int(j["product_id"], where + ": product_id"));
        p.rate_hz = j.value("rate_hz", 100.0);
        if (!(p.rate_hz > 0 && p.rate_hz < 100000)) throw format_error(where + ": rate_hz " + std::to_string(p.rate_hz) + " is not in (0, 100000)");
        p.unit_tolerance = j.value("unit_tolerance", 0.05);
        p.back_sensor = j.value("back_sensor", std::string());
        if (j.contains("back_mount")) {
            const auto& m = j["back_mount"];
            if (!m.is_array() || m.size() != 4) throw format_error(where + ": back_mount is not [w, x, y, z]");
            p.back_mount = normalized({m[0].get<double>(), m[1].get<double>(), m[2].get<double>(), m[3].get<double>()});
        }
        if (j.contains("coupling")) {
            const auto& c = j["coupling"];
            p.coupling.proximal_weight = c.value("proximal_weight", p.coupling.proximal_weight);
            p.coupling.intermediate_weight = c.value("intermediate_weight", p.coupling.intermediate_weight);
            p.coupling.distal_of_intermediate = c.value("distal_of_intermediate", p.coupling.distal_of_intermediate);
            if (!(p.coupling.proximal_weight >= 0 && p.coupling.intermediate_weight >= 0 &&
                  p.coupling.proximal_weight + p.coupling.intermediate_weight > 0 && p.coupling.distal_of_intermediate >= 0))
                throw format_error(where + ": coupling weights must be non-negative with a positive sum");
        }
        for (const auto& fr : j.value("init_features", json::array())) {
            std::vector<std::uint8_t> bytes;
            for (const auto& b : fr) bytes.push_back(static_cast<std::uint8_t>(detail::parse_hex_or_int(b, where + ": init_features")));
            p.init_features.push_back(std::move(bytes));
        }
        const skeleton hand = hand_skeleton();
        std::vector<std::string> names;
        const auto& reps = need(j, "reports", where);
        if (!reps.is_array() || reps.empty()) throw format_error(where + ": \"reports\" is not a non-empty array");
        for (std::size_t ri = 0; ri < reps.size(); ++ri) {
            const auto& r = reps[ri];
            const std::string rw = where + ": reports[" + std::to_string(ri) + "]";
            glove_report_layout L;
            if (r.contains("id") && !r["id"].is_null()) L.id = static_cast<int>(detail::parse_hex_or_int(r["id"], rw + ".id"));
            if (L.id > 255) throw format_error(rw + ": id " + std::to_string(L.id) + " is not a byte");
            L.completes_frame = r.value("completes_frame", ri + 1 == reps.size());
            std::vector<std::pair<std::size_t, std::size_t>> used;
            if (L.id >= 0) used.emplace_back(0, 1);
            const auto& fields = need(r, "fields", rw);
            for (std::size_t fi = 0; fi < fields.size(); ++fi) {
                const auto& f = fields[fi];
                const std::string fw = rw + ".fields[" + std::to_string(fi) + "]";
                glove_field g;
                const std::string kind = need(f, "kind", fw).get<std::string>();
                if (kind == "quaternion") g.kind = field_kind::quaternion;
                else if (kind == "flex") g.kind = field_kind::flex;
                else if (kind == "timestamp") g.kind = field_kind::timestamp;
                else if (kind == "sequence") g.kind = field_kind::sequence;
                else throw format_error(fw + ": kind '" + kind + "' is not quaternion, flex, timestamp or sequence");
                g.name = f.value("name", kind);
                g.offset = static_cast<std::size_t>(detail::parse_hex_or_int(need(f, "offset", fw), fw + ".offset"));
                g.type = detail::parse_value_type(f.value("type", std::string(g.kind == field_kind::quaternion ? "i16" : "u16")), fw);
                const std::string endian = f.value("endian", std::string("little"));
                if (endian != "little" && endian != "big") throw format_error(fw + ": endian '" + endian + "' is not little or big");
                g.big_endian = endian == "big";
                g.scale = f.value("scale", g.kind == field_kind::timestamp ? 1000.0 : 1.0);
                if (!(g.scale > 0) || !std::isfinite(g.scale)) throw format_error(fw + ": scale must be positive");
                if (g.kind == field_kind::quaternion || g.kind == field_kind::flex) {
                    g.bone = need(f, "bone", fw).get<std::string>();
                    try {
                        (void)hand.index_of(g.bone);
                    } catch (const value_error&) {
                        throw format_error(fw + ": bone '" + g.bone + "' is not a joint of the 23-joint hand (e.g. index_intermediate)");
                    }
                    for (const auto& n : names)
                        if (n == g.name) throw format_error(fw + ": sensor name '" + g.name + "' is used twice");
                    names.push_back(g.name);
                }
                if (g.kind == field_kind::quaternion) {
                    const std::string ord = f.value("order", std::string("wxyz"));
                    std::array<bool, 4> seen{};
                    bool ok = ord.size() == 4;
                    for (std::size_t k = 0; ok && k < 4; ++k) {
                        const auto pos = std::string_view("wxyz").find(ord[k]);
                        ok = pos != std::string_view::npos && !seen[pos];
                        if (ok) seen[pos] = true, g.order[k] = static_cast<int>(pos);
                    }
                    if (!ok) throw format_error(fw + ": order '" + ord + "' is not a permutation of wxyz");
                }
                if (g.kind == field_kind::flex) {
                    if (f.contains("range")) g.range_min = f["range"].at(0).get<double>(), g.range_max = f["range"].at(1).get<double>();
                    g.flat = f.value("flat", 0.0);
                    g.fist = f.value("fist", 1.0);
                    g.fist_angle = f.value("fist_angle", 90.0);
                    if (g.flat == g.fist) throw format_error(fw + ": flat and fist raw values are equal");
                    const std::string ax = f.value("axis", std::string("x"));
                    if (ax != "x" && ax != "y" && ax != "z") throw format_error(fw + ": axis '" + ax + "' is not x, y or z");
                    g.rotation_axis = static_cast<axis>(ax[0] - 'x');
                }
                if ((g.kind == field_kind::timestamp || g.kind == field_kind::sequence) && g.type == value_type::f32)
                    throw format_error(fw + ": a " + kind + " must be an integer type");
                const std::size_t b = g.offset, e = g.offset + g.bytes();
                for (auto [ub, ue] : used)
                    if (b < ue && ub < e)
                        throw format_error(fw + ": bytes " + std::to_string(b) + ".." + std::to_string(e - 1) +
                                           " overlap another field (or the report id at byte 0)");
                used.emplace_back(b, e);
                L.size = std::max(L.size, e);
                L.fields.push_back(std::move(g));
            }
            if (r.contains("size")) {
                const auto s = static_cast<std::size_t>(detail::parse_hex_or_int(r["size"], rw + ".size"));
                if (s < L.size) throw format_error(rw + ": size " + std::to_string(s) + " is smaller than its fields (" + std::to_string(L.size) + " bytes)");
                L.size = s;
            }
            for (const auto& other : p.reports)
                if (other.id == L.id) throw format_error(rw + ": report id " + std::to_string(L.id) + " is listed twice");
            p.reports.push_back(std::move(L));
        }
        p.index();
        if (p.imus.empty() && p.flexes.empty()) throw format_error(where + ": no sensors (quaternion or flex fields)");
        if (!p.imus.empty() && p.back_index() < 0)
            throw format_error(where + ": back_sensor '" + p.back_sensor + "' is not a quaternion field (IMU gloves need the back-of-hand IMU)");
        if (p.back_index() >= 0 && p.imus[static_cast<std::size_t>(p.back_index())]->bone != "palm")
            throw format_error(where + ": back_sensor '" + p.back_sensor + "' sits on '" + p.imus[static_cast<std::size_t>(p.back_index())]->bone + "', expected 'palm'");
        return p;
    } catch (const json::exception& e) {
        throw format_error(where + ": " + e.what());
    }
}

/// @brief Reads a profile file. @throws io_error, format_error.
inline glove_profile read_glove_profile(const std::filesystem::path& path)
{
    return parse_glove_profile(read_file(path), path.string());
}

/// Why a report was refused.
enum class report_fault : std::uint8_t {
    none, short_report, unknown_id, not_finite, non_unit_quaternion, out_of_range, clock_backwards,
    syntax,         ///< a text line that is not the protocol's syntax (malformed JSON, garbage, a cut line)
    missing_field,  ///< a required value is absent
    unknown_key     ///< a key the protocol does not define (a warning: the rest of the line is used)
};
inline constexpr std::size_t report_fault_count = 10;
constexpr std::string_view to_string(report_fault f) noexcept
{
    constexpr std::string_view n[] = {"ok", "short", "unknown id", "NaN/inf", "non-unit quaternion", "out of range", "clock backwards",
                                      "syntax", "missing field", "unknown key"};
    return n[static_cast<int>(f)];
}

/// @brief One complete reading of every sensor.
struct glove_sample {
    double host_time = 0;     ///< seconds (steady clock of the host) when the completing report arrived
    double device_time = std::numeric_limits<double>::quiet_NaN();  ///< seconds from the device clock, unwrapped; NaN without one
    std::int64_t sequence = -1;  ///< unwrapped report counter, -1 without one
    std::vector<quat> imu;       ///< [imus] unit orientations, profile order
    std::vector<double> flex;    ///< [flexes] raw values (after scale)
    double time() const noexcept { return std::isnan(device_time) ? host_time : device_time; }
};

/// @brief The outcome of decoding one report.
struct decode_result {
    bool frame = false;                 ///< a complete sample is ready
    report_fault fault = report_fault::none;
    std::string message;                ///< what was wrong (empty when fine)
    std::uint64_t dropped = 0;          ///< reports missing before this one (sequence counter gap)
    report_fault warning = report_fault::none;  ///< something to report in a report that was still used
    std::string warning_message;
};

/// @brief Turns reports (HID report bytes or text lines) into samples of a profile's sensors. One per
/// glove protocol: report_decoder (HID profiles as data), senso_decoder, opengloves_decoder. A refused
/// report sets `fault` and changes no state.
class glove_decoder {
public:
    virtual ~glove_decoder() = default;
    /// The sensors the samples carry (bones, calibration defaults) for calibration and the solve.
    virtual const glove_profile& profile() const noexcept = 0;
    /// @brief Decodes one report received at `host_time`; on `frame`, `out` holds the sample.
    virtual decode_result decode(std::span<const std::uint8_t> bytes, double host_time, glove_sample& out) = 0;
    /// Forgets clocks and counters (after a reconnect: the device may have restarted).
    virtual void reset() = 0;
};

namespace detail {

inline std::uint64_t load_uint(const std::uint8_t* p, std::size_t n, bool big) noexcept
{
    std::uint64_t v = 0;
    for (std::size_t i = 0; i < n; ++i) v |= static_cast<std::uint64_t>(p[big ? n - 1 - i : i]) << (8 * i);
    return v;
}

/// Raw numeric value (before scale) of one value of type t.
inline double load_value(const std::uint8_t* p, value_type t, bool big) noexcept
{
    const std::uint64_t u = load_uint(p, value_size(t), big);
    switch (t) {
    case value_type::u8: return static_cast<double>(u);
    case value_type::i8: return static_cast<double>(static_cast<std::int8_t>(u));
    case value_type::u16: return static_cast<double>(u);
    case value_type::i16: return static_cast<double>(static_cast<std::int16_t>(u));
    case value_type::u32: return static_cast<double>(u);
    case value_type::i32: return static_cast<double>(static_cast<std::int32_t>(u));
    default: return static_cast<double>(std::bit_cast<float>(static_cast<std::uint32_t>(u)));
    }
}

inline void store_uint(std::uint8_t* p, std::uint64_t v, std::size_t n, bool big) noexcept
{
    for (std::size_t i = 0; i < n; ++i) p[big ? n - 1 - i : i] = static_cast<std::uint8_t>(v >> (8 * i));
}

/// Stores a raw value (rounded for integer types, saturated to the type's range).
inline void store_value(std::uint8_t* p, value_type t, bool big, double v) noexcept
{
    if (t == value_type::f32) return store_uint(p, std::bit_cast<std::uint32_t>(static_cast<float>(v)), 4, big);
    const std::size_t n = value_size(t);
    const bool is_signed = t == value_type::i8 || t == value_type::i16 || t == value_type::i32;
    const double hi = is_signed ? std::ldexp(1.0, static_cast<int>(8 * n - 1)) - 1 : std::ldexp(1.0, static_cast<int>(8 * n)) - 1;
    const double lo = is_signed ? -hi - 1 : 0;
    const auto r = static_cast<std::int64_t>(std::llround(std::clamp(v, lo, hi)));
    store_uint(p, static_cast<std::uint64_t>(r), n, big);
}

}  // namespace detail

/// @brief Turns report bytes into samples with one profile. Keeps the latest value of every sensor (a
/// device may spread its sensors over several report ids) and the unwrapping state of the device clock
/// and the sequence counter. Decoding allocates nothing after construction.
class report_decoder : public glove_decoder {
public:
    explicit report_decoder(const glove_profile& p) : p_(p) { reset(); }
    const glove_profile& profile() const noexcept override { return p_; }
    void reset() override
    {
        current_.imu.assign(p_.imus.size(), quat{});
        current_.flex.assign(p_.flexes.size(), 0.0);
        scratch_ = current_;
        has_ts_ = false, ts_time_ = 0, ts_raw_ = 0, seq_raw_ = 0, seq_ = -1;
    }

    /// @brief Decodes one report received at `host_time` (seconds); on `frame`, `out` holds the sample.
    /// A refused report changes nothing: not the sensors, the clock or the counter.
    decode_result decode(std::span<const std::uint8_t> bytes, double host_time, glove_sample& out) override
    {
        decode_result r;
        const glove_report_layout* L = nullptr;
        for (const auto& l : p_.reports)
            if (l.id < 0 || (!bytes.empty() && bytes[0] == l.id)) {
                L = &l;
                break;
            }
        if (!L) {
            r.fault = report_fault::unknown_id;
            r.message = bytes.empty() ? "empty report" : "report id " + std::to_string(bytes[0]) + " is not in the profile";
            return r;
        }
        if (bytes.size() < L->size) {
            r.fault = report_fault::short_report;
            r.message = (L->id >= 0 ? "report id " + std::to_string(L->id) : std::string("report")) + " has " + std::to_string(bytes.size()) +
                        " bytes, expected at least " + std::to_string(L->size);
            return r;
        }
        // Decode into scratch state, commit only when every field is fine.
        scratch_.imu = current_.imu;  // same sizes: no allocation
        scratch_.flex = current_.flex;
        double ts = ts_time_;
        std::uint64_t ts_raw = ts_raw_;
        std::int64_t seq = seq_;
        std::uint64_t seq_raw = seq_raw_;
        bool ts_seen = false;
        for (const auto& f : L->fields) {
            const std::uint8_t* b = bytes.data() + f.offset;
            switch (f.kind) {
            case field_kind::quaternion: {
                double c[4];
                const std::size_t w = value_size(f.type);
                for (int k = 0; k < 4; ++k) c[f.order[static_cast<std::size_t>(k)]] = detail::load_value(b + static_cast<std::size_t>(k) * w, f.type, f.big_endian) / f.scale;
                const quat q{c[0], c[1], c[2], c[3]};
                const double n = norm(q);
                if (!std::isfinite(n)) return fault(r, report_fault::not_finite, "sensor '" + f.name + "': quaternion has a NaN or infinite component");
                if (std::abs(n - 1) > p_.unit_tolerance)
                    return fault(r, report_fault::non_unit_quaternion, "sensor '" + f.name + "': quaternion norm " + std::to_string(n) + " is not 1 (tolerance " + std::to_string(p_.unit_tolerance) + ")");
                scratch_.imu[f.sensor] = {q.w / n, q.x / n, q.y / n, q.z / n};
                break;
            }
            case field_kind::flex: {
                const double v = detail::load_value(b, f.type, f.big_endian) / f.scale;
                if (!std::isfinite(v)) return fault(r, report_fault::not_finite, "sensor '" + f.name + "': value is NaN or infinite");
                if (v < f.range_min || v > f.range_max)
                    return fault(r, report_fault::out_of_range, "sensor '" + f.name + "': value " + std::to_string(v) + " is outside [" +
                                                                    std::to_string(f.range_min) + ", " + std::to_string(f.range_max) + "]");
                scratch_.flex[f.sensor] = v;
                break;
            }
            case field_kind::timestamp: {
                const std::size_t nb = value_size(f.type);
                const std::uint64_t raw = detail::load_uint(b, nb, f.big_endian);
                const std::uint64_t mod_mask = nb == 8 ? ~0ull : (1ull << (8 * nb)) - 1;
                if (has_ts_) {
                    const std::uint64_t d = (raw - ts_raw_) & mod_mask;
                    if (d > mod_mask / 2)
                        return fault(r, report_fault::clock_backwards, "timestamp " + std::to_string(raw) + " is before the previous " + std::to_string(ts_raw_));
                    ts = ts_time_ + static_cast<double>(d) / f.scale;
                } else {
                    ts = 0;
                }
                ts_raw = raw, ts_seen = true;
                break;
            }
            case field_kind::sequence: {
                const std::size_t nb = value_size(f.type);
                const std::uint64_t raw = detail::load_uint(b, nb, f.big_endian);
                const std::uint64_t mod_mask = (1ull << (8 * nb)) - 1;
                if (seq_ >= 0) {
                    const std::uint64_t d = (raw - seq_raw_) & mod_mask;
                    if (d == 0 || d > mod_mask / 2)
                        return fault(r, report_fault::out_of_range, "sequence " + std::to_string(raw) + " repeats or precedes " + std::to_string(seq_raw_));
                    r.dropped = d - 1;
                    seq = seq_ + static_cast<std::int64_t>(d);
                } else {
                    seq = 0;
                }
                seq_raw = raw;
                break;
            }
            }
        }
        std::swap(current_.imu, scratch_.imu);
        std::swap(current_.flex, scratch_.flex);
        if (ts_seen) ts_time_ = ts, ts_raw_ = ts_raw, has_ts_ = true;
        seq_ = seq, seq_raw_ = seq_raw;
        if (!L->completes_frame) return r;
        r.frame = true;
        out.imu = current_.imu;
        out.flex = current_.flex;
        out.host_time = host_time;
        out.device_time = has_ts_ ? ts_time_ : std::numeric_limits<double>::quiet_NaN();
        out.sequence = seq_;
        return r;
    }

private:
    static decode_result& fault(decode_result& r, report_fault f, std::string msg)
    {
        r.fault = f;
        r.message = std::move(msg);
        r.dropped = 0;
        return r;
    }
    glove_profile p_;
    glove_sample current_, scratch_;
    bool has_ts_ = false;
    double ts_time_ = 0;
    std::uint64_t ts_raw_ = 0, seq_raw_ = 0;
    std::int64_t seq_ = -1;
};

/// @brief The inverse of the decoder (simulation, tests, replay files from synthetic poses): writes
/// `s` into the reports of the profile, in profile order. `tick` is the report counter; the timestamp
/// field gets `time` seconds times its scale, both wrapped to the field's width.
inline std::vector<std::vector<std::uint8_t>> encode_reports(const glove_profile& p, const glove_sample& s, std::uint64_t tick, double time)
{
    std::vector<std::vector<std::uint8_t>> out;
    for (const auto& L : p.reports) {
        std::vector<std::uint8_t> b(L.size, 0);
        if (L.id >= 0) b[0] = static_cast<std::uint8_t>(L.id);
        for (const auto& f : L.fields) {
            std::uint8_t* d = b.data() + f.offset;
            switch (f.kind) {
            case field_kind::quaternion: {
                quat q = f.sensor < s.imu.size() ? s.imu[f.sensor] : quat{};
                if (q.w < 0) q = {-q.w, -q.x, -q.y, -q.z};
                const double c[4] = {q.w, q.x, q.y, q.z};
                const std::size_t w = value_size(f.type);
                for (std::size_t k = 0; k < 4; ++k) detail::store_value(d + k * w, f.type, f.big_endian, c[f.order[k]] * f.scale);
                break;
            }
            case field_kind::flex: detail::store_value(d, f.type, f.big_endian, (f.sensor < s.flex.size() ? s.flex[f.sensor] : 0.0) * f.scale); break;
            case field_kind::timestamp: {
                const auto ticks = static_cast<std::uint64_t>(std::llround(time * f.scale));
                detail::store_uint(d, ticks, value_size(f.type), f.big_endian);
                break;
            }
            case field_kind::sequence: detail::store_uint(d, tick, value_size(f.type), f.big_endian); break;
            }
        }
        out.push_back(std::move(b));
    }
    return out;
}

}  // namespace handemo
