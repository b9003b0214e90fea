// The motion-as-image codec of the hand paper (Section 3.3.1 and 3.4): keyframes [K, J, 3] become a
// K-row, J-column RGB image whose R, G, B are the x, y, z angles, rescaled by Eq. 3,
//     v = round(255 (p - p_min) / (p_max - p_min))   (clamped to [0, 255]),
// and are decoded by Eq. 6, p = v / 255 (p_max - p_min) + p_min, so one angle's round-trip error is at most
// (p_max - p_min) / 510. p_min/p_max are the extremes over the whole dataset (angle_range, saved as JSON).
// The network works on tanh-range images: x = v / 127.5 - 1 (to_network / from_network), laid out [3, K, J]
// (channel-first, as PyTorch's StarGAN). Conversions to handemo::rgb_image are in image/keyframe_image.hpp so this
// header needs no stb.
// Beyond the paper (range format handemo-range/2, `compute_channel_range`): one range per channel (joint x
// axis) instead of one for the whole data set, each angle first wrapped against the channel's reference
// angle (its circular mean over the training keyframes) into (ref - 180, ref + 180], and the range taken
// from robust percentiles widened by a margin. The paper's single range spends its 256 levels on the
// widest channel (on Bandai, Euler tracks near gimbal lock that wind to +-1983 deg make one level 15.5
// deg); per channel, every joint gets its own resolution and a wound track is brought back next to its
// reference. handemo-range/1 files still load (as one range for every channel).
#pragma once

#include <handemo/core/error.hpp>
#include <handemo/core/io.hpp>
#include <handemo/motion/keyframes.hpp>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <span>
#include <string>
#include <vector>

namespace handemo {

/// @brief An angle difference wrapped into (-180, 180] degrees.
inline double wrap_angle_deg(double d) noexcept
{
    d = std::fmod(d, 360.0);
    if (d > 180.0) d -= 360.0;
    if (d <= -180.0) d += 360.0;
    return d;
}

/// @brief The angle range of Eq. 3 / Eq. 6: the paper's one dataset-wide p_min/p_max (handemo-range/1) or,
/// when `lo`/`hi` are set, one range per channel with a reference angle per channel (handemo-range/2).
/// Channels are numbered as in keyframes::angles: ch = joint * 3 + axis.
struct angle_range {
    double p_min = 0.0;
    double p_max = 0.0;
    std::size_t keyframes = 0;  ///< K (image rows); 0 when unknown
    std::size_t joints = 0;     ///< J (image columns); 0 when unknown
    std::vector<double> center; ///< [J*3] reference angle per channel (per-channel ranges only)
    std::vector<double> lo, hi; ///< [J*3] per-channel extremes, in the wrapped frame of `center`; empty: global

    bool per_channel() const noexcept { return !lo.empty(); }
    double span() const noexcept { return p_max - p_min; }
    /// Largest round-trip error of one angle through encode/decode: (p_max - p_min) / 510 (the widest channel).
    double max_roundtrip_error() const noexcept { return span() / 510.0; }
    /// Lower / upper bound of channel `ch` (the global ones for a handemo-range/1 range).
    double lo_of(std::size_t ch) const noexcept { return per_channel() ? lo[ch] : p_min; }
    double hi_of(std::size_t ch) const noexcept { return per_channel() ? hi[ch] : p_max; }
    /// Half the span of channel `ch`: degrees per unit of the network's [-1, 1] range.
    double half_span(std::size_t ch) const noexcept { return 0.5 * (hi_of(ch) - lo_of(ch)); }
    /// Round-trip bound of channel `ch`: (hi - lo) / 510.
    double channel_roundtrip_error(std::size_t ch) const noexcept { return (hi_of(ch) - lo_of(ch)) / 510.0; }
    /// `p` in the frame the range is expressed in: wrapped against the reference of `ch` (per channel), as is (global).
    double to_frame(double p, std::size_t ch) const noexcept
    {
        return per_channel() ? center[ch] + wrap_angle_deg(p - center[ch]) : p;
    }
    /// Whether `p` lies inside channel `ch`'s range (Eq. 3 clamps it otherwise).
    bool contains(double p, std::size_t ch) const noexcept
    {
        const double q = to_frame(p, ch);
        return q >= lo_of(ch) && q <= hi_of(ch);
    }
    /// @throws value_error naming `what` when the extremes are not finite, p_max <= p_min, or a per-channel
    ///         array has the wrong size, a non-finite value or hi <= lo.
    void validate(const std::string& what = "angle_range") const
    {
        if (!std::isfinite(p_min) || !std::isfinite(p_max) || !(p_max > p_min) || !std::isfinite(p_max - p_min))
            throw value_error(what + ": p_max " + std::to_string(p_max) + " is not above p_min " + std::to_string(p_min));
        if (!per_channel() && center.empty() && hi.empty()) return;
        const std::size_t n = lo.size();
        if (hi.size() != n || center.size() != n || (joints && n != joints * 3))
            throw value_error(what + ": per-channel arrays have " + std::to_string(center.size()) + "/" + std::to_string(lo.size()) +
                              "/" + std::to_string(hi.size()) + " entries (center/lo/hi), expected joints*3 = " +
                              std::to_string(joints * 3));
        for (std::size_t c = 0; c < n; ++c)
            if (!std::isfinite(center[c]) || !std::isfinite(lo[c]) || !std::isfinite(hi[c]) || !(hi[c] > lo[c]) ||
                !std::isfinite(hi[c] - lo[c]))
                throw value_error(what + ": channel " + std::to_string(c) + " (joint " + std::to_string(c / 3) + ", axis " +
                                  "xyz"[c % 3] + "): hi " + std::to_string(hi[c]) + " is not above lo " + std::to_string(lo[c]) +
                                  " or a value is not finite");
    }
};

/// @brief Range over a set of keyframed motions (Eq. 3: "the maximum and minimum values among all the
/// joint angles existed in the dataset"). A constant dataset gets a 1-degree span to stay decodable.
/// @throws value_error for an empty set; shape_error when the motions differ in K or J.
template <std::size_t K>
angle_range compute_range(std::span<const keyframes<K>> set)
{
    if (set.empty()) throw value_error("compute_range: no keyframed motions");
    angle_range r;
    r.p_min = std::numeric_limits<double>::infinity();
    r.p_max = -r.p_min;
    r.keyframes = set.front().count();
    r.joints = set.front().joints;
    for (std::size_t s = 0; s < set.size(); ++s) {
        const auto& k = set[s];
        if (k.count() != r.keyframes || k.joints != r.joints)
            throw shape_error("compute_range: motion " + std::to_string(s) + " is " + std::to_string(k.count()) + "x" +
                              std::to_string(k.joints) + " (keyframes x joints), expected " +
                              std::to_string(r.keyframes) + "x" + std::to_string(r.joints));
        for (double v : k.angles) {
            if (!std::isfinite(v)) throw value_error("compute_range: motion " + std::to_string(s) + " has a non-finite angle");
            r.p_min = std::min(r.p_min, v);
            r.p_max = std::max(r.p_max, v);
        }
    }
    if (!(r.p_max > r.p_min)) r.p_max = r.p_min + 1.0;
    return r;
}

template <std::size_t K>
angle_range compute_range(const std::vector<keyframes<K>>& set)
{
    return compute_range(std::span<const keyframes<K>>(set));
}

/// @brief How compute_channel_range() sets each channel's range.
struct channel_range_options {
    double quantile = 0.01;   ///< the range starts at the quantile..1-quantile percentiles of the wrapped values
    double margin = 0.25;     ///< then is widened by this fraction of its span on each side (unseen motions)
    double min_span = 20.0;   ///< and is at least this wide, in degrees, around its middle
};

/// @brief Per-channel ranges (handemo-range/2) over a set of keyframed motions: for every channel (joint x
/// axis) the reference angle is the circular mean of its values; values are wrapped against it into
/// (ref - 180, ref + 180]; the range is [q, 1 - q] percentiles widened by `margin` x span per side, at least
/// `min_span` wide and never wider than the full circle around the reference. p_min/p_max are the widest
/// channel's bounds (so max_roundtrip_error() still bounds every channel).
/// @throws value_error for an empty set, a non-finite angle or bad options; shape_error when the motions
///         differ in K or J.
template <std::size_t K>
angle_range compute_channel_range(std::span<const keyframes<K>> set, const channel_range_options& opt = {})
{
    if (!(opt.quantile >= 0 && opt.quantile < 0.5) || !(opt.margin >= 0) || !(opt.min_span > 0) || !std::isfinite(opt.margin) ||
        !std::isfinite(opt.min_span))
        throw value_error("compute_channel_range: quantile must be in [0, 0.5), margin >= 0 and min_span > 0");
    angle_range r = compute_range(set);  // shape and finiteness checks, K and J
    const std::size_t C = r.joints * 3;
    r.center.assign(C, 0.0);
    r.lo.assign(C, 0.0);
    r.hi.assign(C, 0.0);
    std::vector<double> v;
    v.reserve(set.size() * r.keyframes);
    for (std::size_t ch = 0; ch < C; ++ch) {
        double s = 0, c = 0;
        for (const auto& k : set)
            for (std::size_t i = 0; i < r.keyframes; ++i) {
                const double a = k.angles[i * C + ch] * (M_PI / 180.0);
                s += std::sin(a), c += std::cos(a);
            }
        // circular mean; an undefined one (values spread evenly on the circle) falls back to the plain mean
        const double ref = std::hypot(s, c) > 1e-9 * static_cast<double>(set.size() * r.keyframes) ? std::atan2(s, c) * (180.0 / M_PI) : 0.0;
        v.clear();
        for (const auto& k : set)
            for (std::size_t i = 0; i < r.keyframes; ++i) v.push_back(ref + wrap_angle_deg(k.angles[i * C + ch] - ref));
        const auto at = [&](double q) {
            const auto idx = static_cast<std::size_t>(std::llround(q * static_cast<double>(v.size() - 1)));
            std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(idx), v.end());
            return v[idx];
        };
        double lo = at(opt.quantile), hi = at(1.0 - opt.quantile);
        const double w = hi - lo;
        lo -= opt.margin * w, hi += opt.margin * w;
        if (hi - lo < opt.min_span) {
            const double mid = 0.5 * (lo + hi);
            lo = mid - 0.5 * opt.min_span, hi = mid + 0.5 * opt.min_span;
        }
        r.center[ch] = ref;
        r.lo[ch] = std::max(lo, ref - 180.0);
        r.hi[ch] = std::min(hi, ref + 180.0);
    }
    r.p_min = *std::min_element(r.lo.begin(), r.lo.end());
    r.p_max = *std::max_element(r.hi.begin(), r.hi.end());
    return r;
}

template <std::size_t K>
angle_range compute_channel_range(const std::vector<keyframes<K>>& set, const channel_range_options& opt = {})
{
    return compute_channel_range(std::span<const keyframes<K>>(set), opt);
}

/// @brief The JSON form of a range (see save_range()).
inline nlohmann::json range_to_json(const angle_range& r)
{
    nlohmann::json j;
    j["format"] = r.per_channel() ? "handemo-range/2" : "handemo-range/1";
    j["p_min"] = r.p_min;
    j["p_max"] = r.p_max;
    j["keyframes"] = r.keyframes;
    j["joints"] = r.joints;
    if (r.per_channel()) {
        j["center"] = r.center;
        j["lo"] = r.lo;
        j["hi"] = r.hi;
    }
    return j;
}

/// @brief Writes the range as JSON atomically (temporary file + rename): `{"format": "handemo-range/1", "p_min",
/// "p_max", "keyframes", "joints"}`, plus `"center"`, `"lo"`, `"hi"` arrays ([J*3]) as "handemo-range/2" for a
/// per-channel range.
/// @throws value_error for an invalid range; io_error when the file cannot be written.
inline void save_range(const std::filesystem::path& path, const angle_range& r)
{
    r.validate("save_range: " + path.string());
    write_file_atomic(path, range_to_json(r).dump(2) + "\n");
}

/// @brief Parses a range JSON document; `source` names it in errors.
/// @throws format_error naming the source and the field for malformed JSON, a missing or mistyped field,
///         a wrong format tag, or p_max <= p_min.
inline angle_range parse_range(std::string_view text, const std::string& source)
{
    nlohmann::json j;
    try {
        // range.json is flat: deeper nesting is refused while parsing (nlohmann's dump, used in the
        // messages below, recurses once per level)
        j = nlohmann::json::parse(text, [&](int depth, nlohmann::json::parse_event_t, nlohmann::json&) {
            if (depth > 2) throw format_error("range: " + source + ": JSON nested deeper than 2 levels");
            return true;
        });
    } catch (const nlohmann::json::parse_error& e) {
        throw format_error("range: " + source + ": malformed JSON at byte " + std::to_string(e.byte) + ": " + e.what());
    } catch (const nlohmann::json::exception& e) {  // out_of_range.406: a number such as 1e400 overflows
        throw format_error("range: " + source + ": number out of range: " + e.what());
    }
    if (!j.is_object()) throw format_error("range: " + source + ": top level is " + std::string(j.type_name()) + ", expected an object");
    auto field = [&](const char* name) -> const nlohmann::json& {
        auto it = j.find(name);
        if (it == j.end()) throw format_error("range: " + source + ": field '" + name + "' is missing");
        return *it;
    };
    const auto& fmt = field("format");
    const bool v2 = fmt.is_string() && fmt.get<std::string>() == "handemo-range/2";
    if (!v2 && !(fmt.is_string() && fmt.get<std::string>() == "handemo-range/1"))
        throw format_error("range: " + source + ": field 'format' is " + fmt.dump() +
                           ", expected \"handemo-range/1\" or \"handemo-range/2\"");
    auto number = [&](const char* name) {
        const auto& v = field(name);
        if (!v.is_number()) throw format_error("range: " + source + ": field '" + name + "' is " + v.dump() + ", expected a number");
        return v.get<double>();
    };
    // at most 65536 keyframes and 10000 joints (bvh_max_joints), so joints * 3 cannot wrap around
    auto count = [&](const char* name, std::uint64_t max) {
        const auto& v = field(name);
        if (!v.is_number_unsigned() || v.get<std::uint64_t>() > max)
            throw format_error("range: " + source + ": field '" + name + "' is " + v.dump() + ", expected an integer in 0.." +
                               std::to_string(max));
        return static_cast<std::size_t>(v.get<std::uint64_t>());
    };
    angle_range r;
    r.p_min = number("p_min");
    r.p_max = number("p_max");
    r.keyframes = count("keyframes", 65536);
    r.joints = count("joints", 10000);
    if (!std::isfinite(r.p_min) || !std::isfinite(r.p_max) || !(r.p_max > r.p_min) || !std::isfinite(r.p_max - r.p_min))
        throw format_error("range: " + source + ": field 'p_max' " + std::to_string(r.p_max) +
                           " is not above field 'p_min' " + std::to_string(r.p_min));
    if (v2) {
        auto array = [&](const char* name) {
            const auto& v = field(name);
            if (!v.is_array() || v.size() != r.joints * 3)
                throw format_error("range: " + source + ": field '" + name + "' is not an array of joints*3 = " +
                                   std::to_string(r.joints * 3) + " numbers");
            std::vector<double> out;
            for (const auto& x : v) {
                if (!x.is_number()) throw format_error("range: " + source + ": field '" + name + "' holds " + x.dump() + ", expected numbers");
                out.push_back(x.get<double>());
            }
            return out;
        };
        r.center = array("center");
        r.lo = array("lo");
        r.hi = array("hi");
        try {
            r.validate("range");
        } catch (const value_error& e) {
            throw format_error("range: " + source + ": " + e.what());
        }
    }
    return r;
}

/// @brief Reads a range file written by save_range().
/// @throws io_error when unreadable; format_error (see parse_range) naming the file and field.
inline angle_range load_range(const std::filesystem::path& path)
{
    return parse_range(read_file(path), path.string());
}

/// @brief An encoded motion image: K rows (keyframes) x J columns (joints) x 3 (R, G, B = x, y, z).
template <std::size_t K = 9>
struct keyframe_pixels {
    static constexpr std::size_t static_count = K;
    std::size_t count_ = K;             ///< K (rows)
    std::size_t joints = 0;             ///< J (columns)
    std::vector<std::uint8_t> values;   ///< [K, J, 3] row-major RGB

    constexpr std::size_t count() const noexcept { return K == dynamic_keyframes ? count_ : K; }
    std::uint8_t at(std::size_t i, std::size_t j, std::size_t c) const noexcept { return values[(i * joints + j) * 3 + c]; }
};

/// @brief Eq. 3 for one angle: round(255 (p - p_min) / (p_max - p_min)) clamped to [0, 255].
inline std::uint8_t encode_angle(double p, const angle_range& r) noexcept
{
    const double v = std::round(255.0 * (p - r.p_min) / (r.p_max - r.p_min));
    if (!(v >= 0.0)) return 0;  // also NaN
    return v >= 255.0 ? std::uint8_t{255} : static_cast<std::uint8_t>(v);
}

/// @brief Eq. 6 for one pixel value: v / 255 (p_max - p_min) + p_min.
inline double decode_angle(double v, const angle_range& r) noexcept { return v / 255.0 * (r.p_max - r.p_min) + r.p_min; }

/// @brief Eq. 3 for channel `ch` (ch = joint * 3 + axis): the angle wrapped against the channel's reference,
/// then round(255 (p - lo) / (hi - lo)) clamped to [0, 255]. The global range's Eq. 3 for a handemo-range/1 range.
inline std::uint8_t encode_angle(double p, const angle_range& r, std::size_t ch) noexcept
{
    if (!r.per_channel()) return encode_angle(p, r);
    const double v = std::round(255.0 * (r.to_frame(p, ch) - r.lo[ch]) / (r.hi[ch] - r.lo[ch]));
    if (!(v >= 0.0)) return 0;
    return v >= 255.0 ? std::uint8_t{255} : static_cast<std::uint8_t>(v);
}

/// @brief Eq. 6 for channel `ch`: v / 255 (hi - lo) + lo (in the wrapped frame of the channel's reference).
inline double decode_angle(double v, const angle_range& r, std::size_t ch) noexcept
{
    return v / 255.0 * (r.hi_of(ch) - r.lo_of(ch)) + r.lo_of(ch);
}

/// @brief encode() into `px`, its storage reused.
template <std::size_t K>
void encode_into(const keyframes<K>& kf, const angle_range& r, keyframe_pixels<K>& px)
{
    r.validate("encode: range");
    if ((r.keyframes && r.keyframes != kf.count()) || (r.joints && r.joints != kf.joints))
        throw shape_error("encode: keyframes are " + std::to_string(kf.count()) + "x" + std::to_string(kf.joints) +
                          " (keyframes x joints), the range file is for " + std::to_string(r.keyframes) + "x" +
                          std::to_string(r.joints));
    if (kf.angles.size() != kf.count() * kf.joints * 3)
        throw shape_error("encode: keyframes hold " + std::to_string(kf.angles.size()) + " angles, expected " +
                          std::to_string(kf.count() * kf.joints * 3));
    px.count_ = kf.count();
    px.joints = kf.joints;
    px.values.resize(kf.angles.size());
    const std::size_t C = kf.joints * 3;
    for (std::size_t i = 0; i < kf.angles.size(); ++i) px.values[i] = encode_angle(kf.angles[i], r, i % C);
}

/// @brief Encodes keyframes as an image by Eq. 3.
/// @throws value_error for an invalid range; shape_error when the range records a different K or J.
template <std::size_t K>
keyframe_pixels<K> encode(const keyframes<K>& kf, const angle_range& r)
{
    keyframe_pixels<K> px;
    encode_into(kf, r, px);
    return px;
}

/// @brief decode() into `kf`, its storage reused (duration, fps and source frames set to 0).
template <std::size_t K>
void decode_into(const keyframe_pixels<K>& px, const angle_range& r, keyframes<K>& kf)
{
    r.validate("decode: range");
    if (px.values.size() != px.count() * px.joints * 3)
        throw shape_error("decode: image holds " + std::to_string(px.values.size()) + " values, expected " +
                          std::to_string(px.count() * px.joints * 3));
    if (px.count() < 2) throw value_error("keyframes: " + std::to_string(px.count()) + " keyframes, expected at least 2");
    if (r.per_channel() && r.lo.size() != px.joints * 3)
        throw shape_error("decode: image has " + std::to_string(px.joints) + " joints, the range file is for " +
                          std::to_string(r.lo.size() / 3));
    kf.count_ = px.count();
    kf.joints = px.joints;
    kf.angles.resize(px.values.size());
    kf.duration = 0, kf.fps = 0, kf.source_frames = 0;
    const std::size_t C = px.joints * 3;
    for (std::size_t i = 0; i < px.values.size(); ++i) kf.angles[i] = decode_angle(px.values[i], r, i % C);
}

/// @brief Decodes an image by Eq. 6. The result has no duration/fps (set them from a reference clip).
/// @throws value_error for an invalid range; shape_error for an inconsistent pixel array.
template <std::size_t K>
keyframes<K> decode(const keyframe_pixels<K>& px, const angle_range& r)
{
    keyframes<K> kf;
    decode_into(px, r, kf);
    return kf;
}

/// @brief A network input/output: [3, K, J] floats in [-1, 1] (channel-first).
template <std::size_t K = 9>
struct network_image {
    static constexpr std::size_t static_count = K;
    std::size_t count_ = K;
    std::size_t joints = 0;
    std::vector<float> data;  ///< [3, K, J]

    constexpr std::size_t count() const noexcept { return K == dynamic_keyframes ? count_ : K; }
};

/// @brief Pixels to network range: x = v / 127.5 - 1, reordered [K, J, 3] -> [3, K, J], into `n` (storage reused).
template <std::size_t K>
void to_network_into(const keyframe_pixels<K>& px, network_image<K>& n)
{
    n.count_ = px.count();
    n.joints = px.joints;
    const std::size_t plane = px.count() * px.joints;
    n.data.resize(plane * 3);
    for (std::size_t p = 0; p < plane; ++p)
        for (std::size_t c = 0; c < 3; ++c)
            n.data[c * plane + p] = static_cast<float>(static_cast<double>(px.values[p * 3 + c]) / 127.5 - 1.0);
}

/// @brief to_network_into() a new image.
template <std::size_t K>
network_image<K> to_network(const keyframe_pixels<K>& px)
{
    network_image<K> n;
    to_network_into(px, n);
    return n;
}

/// @brief Network output back to pixels: v = round((x + 1) 127.5) clamped to [0, 255] (NaN -> 0).
/// @throws shape_error when the data size is not 3 K J.
template <std::size_t K>
void from_network_into(const network_image<K>& n, keyframe_pixels<K>& px)
{
    const std::size_t plane = n.count() * n.joints;
    if (n.data.size() != plane * 3)
        throw shape_error("from_network: " + std::to_string(n.data.size()) + " values, expected 3*K*J = " +
                          std::to_string(plane * 3));
    px.count_ = n.count();
    px.joints = n.joints;
    px.values.resize(plane * 3);
    for (std::size_t p = 0; p < plane; ++p)
        for (std::size_t c = 0; c < 3; ++c) {
            const double v = std::round((static_cast<double>(n.data[c * plane + p]) + 1.0) * 127.5);
            px.values[p * 3 + c] = !(v >= 0.0) ? std::uint8_t{0} : v >= 255.0 ? std::uint8_t{255} : static_cast<std::uint8_t>(v);
        }
}

/// @brief from_network_into() new pixels.
/// @throws shape_error when the data size is not 3 K J.
template <std::size_t K>
keyframe_pixels<K> from_network(const network_image<K>& n)
{
    keyframe_pixels<K> px;
    from_network_into(n, px);
    return px;
}

}  // namespace handemo
