// The motion-as-image codec of the hand paper (Section 3.3.1 and 3.4): keyframes [K, J, 3] become a
// K-row, J-column RGB image whose R, G, B are the x, y, z angles, rescaled by Eq. 3,
//     v = round(255 (p - p_min) / (p_max - p_min))   (clamped to [0, 255]),
// and are decoded by Eq. 6, p = v / 255 (p_max - p_min) + p_min, so one angle's round-trip error is at most
// (p_max - p_min) / 510. p_min/p_max are the extremes over the whole dataset (angle_range, saved as JSON).
// The network works on tanh-range images: x = v / 127.5 - 1 (to_network / from_network), laid out [3, K, J]
// (channel-first, as PyTorch's StarGAN). Conversions to handemo::rgb_image are in codec_image.hpp so this
// header needs no stb.
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

/// @brief The dataset-wide angle extremes of Eq. 3 / Eq. 6, plus the image shape they were computed for.
struct angle_range {
    double p_min = 0.0;
    double p_max = 0.0;
    std::size_t keyframes = 0;  ///< K (image rows); 0 when unknown
    std::size_t joints = 0;     ///< J (image columns); 0 when unknown

    double span() const noexcept { return p_max - p_min; }
    /// Largest round-trip error of one angle through encode/decode: (p_max - p_min) / 510.
    double max_roundtrip_error() const noexcept { return span() / 510.0; }
    /// @throws value_error naming `what` when the extremes are not finite or p_max <= p_min.
    void validate(const std::string& what = "angle_range") const
    {
        if (!std::isfinite(p_min) || !std::isfinite(p_max) || !(p_max > p_min))
            throw value_error(what + ": p_max " + std::to_string(p_max) + " is not above p_min " + std::to_string(p_min));
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

/// @brief Writes the range as JSON `{"format": "handemo-range/1", "p_min", "p_max", "keyframes", "joints"}`
/// atomically (temporary file + rename).
/// @throws value_error for an invalid range; io_error when the file cannot be written.
inline void save_range(const std::filesystem::path& path, const angle_range& r)
{
    r.validate("save_range: " + path.string());
    nlohmann::json j;
    j["format"] = "handemo-range/1";
    j["p_min"] = r.p_min;
    j["p_max"] = r.p_max;
    j["keyframes"] = r.keyframes;
    j["joints"] = r.joints;
    write_file_atomic(path, j.dump(2) + "\n");
}

/// @brief Parses a range JSON document; `source` names it in errors.
/// @throws format_error naming the source and the field for malformed JSON, a missing or mistyped field,
///         a wrong format tag, or p_max <= p_min.
inline angle_range parse_range(std::string_view text, const std::string& source)
{
    nlohmann::json j;
    try {
        j = nlohmann::json::parse(text);
    } catch (const nlohmann::json::parse_error& e) {
        throw format_error("range: " + source + ": malformed JSON at byte " + std::to_string(e.byte) + ": " + e.what());
    }
    if (!j.is_object()) throw format_error("range: " + source + ": top level is " + std::string(j.type_name()) + ", expected an object");
    auto field = [&](const char* name) -> const nlohmann::json& {
        auto it = j.find(name);
        if (it == j.end()) throw format_error("range: " + source + ": field '" + name + "' is missing");
        return *it;
    };
    const auto& fmt = field("format");
    if (!fmt.is_string() || fmt.get<std::string>() != "handemo-range/1")
        throw format_error("range: " + source + ": field 'format' is " + fmt.dump() + ", expected \"handemo-range/1\"");
    auto number = [&](const char* name) {
        const auto& v = field(name);
        if (!v.is_number()) throw format_error("range: " + source + ": field '" + name + "' is " + v.dump() + ", expected a number");
        return v.get<double>();
    };
    auto count = [&](const char* name) {
        const auto& v = field(name);
        if (!v.is_number_unsigned())
            throw format_error("range: " + source + ": field '" + name + "' is " + v.dump() + ", expected a non-negative integer");
        return v.get<std::size_t>();
    };
    angle_range r;
    r.p_min = number("p_min");
    r.p_max = number("p_max");
    r.keyframes = count("keyframes");
    r.joints = count("joints");
    if (!std::isfinite(r.p_min) || !std::isfinite(r.p_max) || !(r.p_max > r.p_min))
        throw format_error("range: " + source + ": field 'p_max' " + std::to_string(r.p_max) +
                           " is not above field 'p_min' " + std::to_string(r.p_min));
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

/// @brief Encodes keyframes as an image by Eq. 3.
/// @throws value_error for an invalid range; shape_error when the range records a different K or J.
template <std::size_t K>
keyframe_pixels<K> encode(const keyframes<K>& kf, const angle_range& r)
{
    r.validate("encode: range");
    if ((r.keyframes && r.keyframes != kf.count()) || (r.joints && r.joints != kf.joints))
        throw shape_error("encode: keyframes are " + std::to_string(kf.count()) + "x" + std::to_string(kf.joints) +
                          " (keyframes x joints), the range file is for " + std::to_string(r.keyframes) + "x" +
                          std::to_string(r.joints));
    if (kf.angles.size() != kf.count() * kf.joints * 3)
        throw shape_error("encode: keyframes hold " + std::to_string(kf.angles.size()) + " angles, expected " +
                          std::to_string(kf.count() * kf.joints * 3));
    keyframe_pixels<K> px;
    px.count_ = kf.count();
    px.joints = kf.joints;
    px.values.resize(kf.angles.size());
    for (std::size_t i = 0; i < kf.angles.size(); ++i) px.values[i] = encode_angle(kf.angles[i], r);
    return px;
}

/// @brief Decodes an image by Eq. 6. The result has no duration/fps (set them from a reference clip).
/// @throws value_error for an invalid range; shape_error for an inconsistent pixel array.
template <std::size_t K>
keyframes<K> decode(const keyframe_pixels<K>& px, const angle_range& r)
{
    r.validate("decode: range");
    if (px.values.size() != px.count() * px.joints * 3)
        throw shape_error("decode: image holds " + std::to_string(px.values.size()) + " values, expected " +
                          std::to_string(px.count() * px.joints * 3));
    auto kf = keyframes<K>::make(px.joints, px.count());
    for (std::size_t i = 0; i < px.values.size(); ++i) kf.angles[i] = decode_angle(px.values[i], r);
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

/// @brief Pixels to network range: x = v / 127.5 - 1, reordered [K, J, 3] -> [3, K, J].
template <std::size_t K>
network_image<K> to_network(const keyframe_pixels<K>& px)
{
    network_image<K> n;
    n.count_ = px.count();
    n.joints = px.joints;
    const std::size_t plane = px.count() * px.joints;
    n.data.resize(plane * 3);
    for (std::size_t p = 0; p < plane; ++p)
        for (std::size_t c = 0; c < 3; ++c)
            n.data[c * plane + p] = static_cast<float>(static_cast<double>(px.values[p * 3 + c]) / 127.5 - 1.0);
    return n;
}

/// @brief Network output back to pixels: v = round((x + 1) 127.5) clamped to [0, 255] (NaN -> 0).
/// @throws shape_error when the data size is not 3 K J.
template <std::size_t K>
keyframe_pixels<K> from_network(const network_image<K>& n)
{
    const std::size_t plane = n.count() * n.joints;
    if (n.data.size() != plane * 3)
        throw shape_error("from_network: " + std::to_string(n.data.size()) + " values, expected 3*K*J = " +
                          std::to_string(plane * 3));
    keyframe_pixels<K> px;
    px.count_ = n.count();
    px.joints = n.joints;
    px.values.resize(plane * 3);
    for (std::size_t p = 0; p < plane; ++p)
        for (std::size_t c = 0; c < 3; ++c) {
            const double v = std::round((static_cast<double>(n.data[c * plane + p]) + 1.0) * 127.5);
            px.values[p * 3 + c] = !(v >= 0.0) ? std::uint8_t{0} : v >= 255.0 ? std::uint8_t{255} : static_cast<std::uint8_t>(v);
        }
    return px;
}

}  // namespace handemo
