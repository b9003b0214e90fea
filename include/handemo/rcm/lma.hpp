// Laban Movement Analysis (LMA) features of Aristidou et al. 2017, "Emotion control of unstructured dance
// movements" (SCA 2017), Section 3.1 and Table 1: 37 basic per-frame features (BODY, EFFORT, SHAPE, SPACE)
// of joint world positions, turned into 121 derived features (max, min, std, mean of the basic ones over a
// sliding window of 35 frames at 30 fps, scaled with the frame rate), averaged over the windows of a clip
// and normalised to [0, 1] over a training set. The derived features keep the paper's numbering f~1..f~121
// (Table 1 prints a few indices twice; the order below is the one that makes its columns add up to 121).
// A hand variant (28 basic, 83 derived) does the same for the 23-joint hand of hand.hpp.
//
// Everything here is a function of a `[frames, points, 3]` world-position array, the frame rate and a
// role_map (roles.hpp), so the synthesis (rcm/synth.hpp) evaluates the same features on its own poses.
//
// BODY features (units of the file, e.g. cm; "pelvis" is the hip/root joint; the up axis is Y):
//   f1  left foot - pelvis distance          f8  left hand - pelvis distance
//   f2  right foot - pelvis distance         f9  right hand - pelvis distance
//   f3  left hand - left shoulder distance   f10 pelvis height above the ground (lowest point of the clip)
//   f4  right hand - right shoulder distance f11 f10 minus the mean of f1 and f2 (knee bend / crouch)
//   f5  distance between the hands           f12 distance between the feet
//   f6  left hand - head distance            f13 left hand - chest distance
//   f7  right hand - head distance           f14 right hand - chest distance
// EFFORT (central finite differences of positions; per second):
//   f15 deceleration peaks per second: local minima (< 0) of the time derivative of the mean speed of
//       pelvis, hands and feet
//   f16..f20 speed of pelvis, left hand, right hand, left foot, right foot
//   f21..f25 acceleration magnitude of the same five joints
//   f26 jerk: mean magnitude of the third derivative over the same five joints
// SHAPE:
//   f27 volume of the box around head, hands and feet (5 joints), in the body frame (up axis, the
//       horizontal shoulder line and their cross product), so turning in place does not change it
//   f28 volume of the body-frame box around all points
//   f29 torso height: head - pelvis distance
// SPACE:
//   f30 hands level: share of the two hands below the pelvis (low), between pelvis and head (middle),
//       above the head (high): three per-frame columns
//   f31..f34 body-frame box volume of the upper body (head, neck, chest, shoulders, elbows, hands), the lower
//       body (pelvis, hips, knees, feet), the right side and the left side (shoulder, elbow, hand, hip,
//       knee, foot)
//   f35 total distance: horizontal path length of the pelvis within the window
//   f36 area per second: horizontal bounding-rectangle area of the pelvis path over the second around
//       each frame, divided by that second
//   f37 total volume: world-axis box around all points over all frames of the window
// Derived (Table 1): f~1..f~48 = max, min, std, mean of f1..f12; f~49 mean f15; f~50..f~64 = max, std,
// mean of f16..f20; f~65..f~76 = max, std of f21..f26; f~77..f~88 = max, min, std, mean of f27..f29;
// f~89..f~91 = mean of f30 low, middle, high; f~92 = f35; f~93..f~96 = max, min, std, mean of f36;
// f~97..f~112 = max, min, std, mean of f31..f34; f~113..f~120 = max, min, std, mean of f13, f14; f~121 = f37.
//
// HAND features (23-joint hand; tips are the fingertip End Sites, bases the proximal finger joints):
//   h1..h5   fingertip - palm distance (thumb, index, middle, ring, pinky): how far each finger is open
//   h6..h9   distance between neighbouring fingertips (thumb-index, index-middle, middle-ring, ring-pinky)
//   h10      thumb tip - pinky tip distance (hand span)
//   h11      finger spread: mean angle (radians) between the base->tip directions of neighbouring fingers
//            index-middle, middle-ring, ring-pinky
//   h12      hand volume: box around wrist, palm, finger bases and tips in the hand frame (wrist->palm,
//            pinky base->index base, their normal)
//   h13..h17 fingertip speed (thumb .. pinky); h18..h22 fingertip acceleration magnitude
//   h23      fingertip jerk: mean third-derivative magnitude over the five tips
//   h24      wrist speed; h25 wrist acceleration magnitude
//   h26      wrist path: wrist path length within the window
//   h27      deceleration peaks per second of the mean fingertip speed (as f15)
//   h28      fingertip space: world-axis box around the five tips over all frames of the window
// Derived: h~1..h~48 = max, min, std, mean of h1..h12; h~49..h~66 = max, std, mean of h13..h17 and h24;
// h~67..h~80 = max, std of h18..h22, h25 and h23; h~81 = h26; h~82 = mean h27; h~83 = h28.
#pragma once

#include <handemo/core/error.hpp>
#include <handemo/motion/clip.hpp>
#include <handemo/motion/skeleton.hpp>
#include <handemo/rcm/roles.hpp>

#include <xtensor/xadapt.hpp>
#include <xtensor/xtensor.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <string>
#include <string_view>
#include <vector>

namespace handemo::rcm {

/// World positions of the points of a clip: `[frames, points, 3]` (points as in point_names()).
using positions_type = xt::xtensor<double, 3>;

/// @brief Options of the feature computation.
struct lma_options {
    int up_axis = 1;                   ///< index of the vertical axis (BVH: 1 = Y)
    double window_frames_at_30 = 35;   ///< sliding window length at 30 fps (the paper's 35)
};

/// @brief Sliding-window length in frames for a frame rate: round(35 * fps / 30), at least 2.
inline std::size_t window_length(double fps, const lma_options& opt = {})
{
    if (!(fps > 0) || !std::isfinite(fps)) throw value_error("rcm::window_length: frame rate " + std::to_string(fps) + " is not positive");
    return std::max<std::size_t>(2, static_cast<std::size_t>(std::lround(opt.window_frames_at_30 * fps / 30.0)));
}

/// @brief Forward kinematics of every frame: joint origins, then the End Sites (`[F, P, 3]`).
inline positions_type world_positions(const clip& c)
{
    const std::size_t J = c.skel.size();
    std::size_t E = 0;
    for (const auto& j : c.skel.joints) E += j.end_site ? 1 : 0;
    positions_type out = xt::zeros<double>({c.frames, J + E, std::size_t{3}});
    for (std::size_t f = 0; f < c.frames; ++f) {
        const auto p = forward_kinematics(c.skel, c.frame_angles(f), c.frame_positions(f));
        std::size_t e = J;
        for (std::size_t j = 0; j < J; ++j)
            for (std::size_t k = 0; k < 3; ++k) out(f, j, k) = p.joints[j][k];
        for (std::size_t j = 0; j < J; ++j)
            if (c.skel.joints[j].end_site) {
                for (std::size_t k = 0; k < 3; ++k) out(f, e, k) = p.end_sites[j][k];
                ++e;
            }
    }
    return out;
}

/// @brief The statistic a derived feature takes of a basic column over a window.
enum class stat : std::uint8_t { max, min, std, mean, sum, window_box };
constexpr std::string_view to_string(stat s) noexcept
{
    constexpr std::string_view n[] = {"max", "min", "std", "mean", "sum", "box"};
    return n[static_cast<int>(s)];
}

/// @brief One basic feature (a row of Table 1 or of the hand table).
struct basic_feature {
    std::string_view key;          ///< f1 .. f37, h1 .. h28
    std::string_view component;    ///< BODY, EFFORT, SHAPE, SPACE
    std::string_view description;
};

/// @brief One derived feature: a statistic of a per-frame column over the window.
struct derived_feature {
    std::size_t basic;   ///< index into the basic features (0-based: f1 is 0)
    std::size_t column;  ///< per-frame column of basic_table() (unused for stat::window_box)
    stat s;
    std::string name;    ///< e.g. "f~1 max f1 left foot - pelvis distance"
};

namespace detail {

inline const std::vector<basic_feature>& body_basic()
{
    static const std::vector<basic_feature> v{
        {"f1", "BODY", "left foot - pelvis distance"},         {"f2", "BODY", "right foot - pelvis distance"},
        {"f3", "BODY", "left hand - left shoulder distance"},  {"f4", "BODY", "right hand - right shoulder distance"},
        {"f5", "BODY", "hands distance"},                      {"f6", "BODY", "left hand - head distance"},
        {"f7", "BODY", "right hand - head distance"},          {"f8", "BODY", "left hand - pelvis distance"},
        {"f9", "BODY", "right hand - pelvis distance"},        {"f10", "BODY", "pelvis height above ground"},
        {"f11", "BODY", "pelvis height minus mean foot - pelvis distance"}, {"f12", "BODY", "feet distance"},
        {"f13", "BODY", "left hand - chest distance"},         {"f14", "BODY", "right hand - chest distance"},
        {"f15", "EFFORT", "deceleration peaks per second"},    {"f16", "EFFORT", "pelvis speed"},
        {"f17", "EFFORT", "left hand speed"},                  {"f18", "EFFORT", "right hand speed"},
        {"f19", "EFFORT", "left foot speed"},                  {"f20", "EFFORT", "right foot speed"},
        {"f21", "EFFORT", "pelvis acceleration"},              {"f22", "EFFORT", "left hand acceleration"},
        {"f23", "EFFORT", "right hand acceleration"},          {"f24", "EFFORT", "left foot acceleration"},
        {"f25", "EFFORT", "right foot acceleration"},          {"f26", "EFFORT", "jerk (pelvis, hands, feet)"},
        {"f27", "SHAPE", "volume of head, hands, feet"},       {"f28", "SHAPE", "volume of all joints"},
        {"f29", "SHAPE", "torso height"},                      {"f30", "SPACE", "hands level (low, middle, high)"},
        {"f31", "SPACE", "volume of the upper body"},          {"f32", "SPACE", "volume of the lower body"},
        {"f33", "SPACE", "volume of the right side"},          {"f34", "SPACE", "volume of the left side"},
        {"f35", "SPACE", "total distance of the pelvis"},      {"f36", "SPACE", "area per second of the pelvis path"},
        {"f37", "SPACE", "total volume over the window"},
    };
    return v;
}

inline const std::vector<basic_feature>& hand_basic()
{
    static const std::vector<basic_feature> v{
        {"h1", "BODY", "thumb tip - palm distance"},   {"h2", "BODY", "index tip - palm distance"},
        {"h3", "BODY", "middle tip - palm distance"},  {"h4", "BODY", "ring tip - palm distance"},
        {"h5", "BODY", "pinky tip - palm distance"},   {"h6", "BODY", "thumb tip - index tip distance"},
        {"h7", "BODY", "index tip - middle tip distance"}, {"h8", "BODY", "middle tip - ring tip distance"},
        {"h9", "BODY", "ring tip - pinky tip distance"},   {"h10", "BODY", "thumb tip - pinky tip distance (span)"},
        {"h11", "SHAPE", "finger spread (mean angle between neighbouring fingers)"},
        {"h12", "SHAPE", "hand volume"},
        {"h13", "EFFORT", "thumb tip speed"},  {"h14", "EFFORT", "index tip speed"},  {"h15", "EFFORT", "middle tip speed"},
        {"h16", "EFFORT", "ring tip speed"},   {"h17", "EFFORT", "pinky tip speed"},
        {"h18", "EFFORT", "thumb tip acceleration"},  {"h19", "EFFORT", "index tip acceleration"},
        {"h20", "EFFORT", "middle tip acceleration"}, {"h21", "EFFORT", "ring tip acceleration"},
        {"h22", "EFFORT", "pinky tip acceleration"},  {"h23", "EFFORT", "fingertip jerk"},
        {"h24", "EFFORT", "wrist speed"},             {"h25", "EFFORT", "wrist acceleration"},
        {"h26", "SPACE", "wrist path length"},        {"h27", "EFFORT", "deceleration peaks per second"},
        {"h28", "SPACE", "fingertip space over the window"},
    };
    return v;
}

/// Per-frame columns: basic index of each column (f30 has three columns; f37 / h28 none).
inline constexpr std::size_t body_columns = 38, hand_columns = 27;

inline std::vector<derived_feature> make_body_derived()
{
    const auto& b = body_basic();
    std::vector<derived_feature> d;
    // column of basic feature i (0-based): f1..f29 -> i; f30 -> 29,30,31; f31..f34 -> 32..35; f35 -> 36; f36 -> 37
    auto col = [](std::size_t i) -> std::size_t { return i < 29 ? i : i == 29 ? 29 : i + 2; };
    auto add = [&](std::size_t i, stat s, std::size_t column) {
        d.push_back({i, column, s, ""});
        auto& x = d.back();
        x.name = "f~" + std::to_string(d.size()) + " " + std::string(to_string(s)) + " " + std::string(b[i].key) + " " +
                 std::string(b[i].description);
    };
    auto four = [&](std::size_t i) {
        for (stat s : {stat::max, stat::min, stat::std, stat::mean}) add(i, s, col(i));
    };
    for (std::size_t i = 0; i < 12; ++i) four(i);                         // f~1..48
    add(14, stat::mean, col(14));                                         // f~49
    for (std::size_t i = 15; i < 20; ++i)                                 // f~50..64
        for (stat s : {stat::max, stat::std, stat::mean}) add(i, s, col(i));
    for (std::size_t i = 20; i < 26; ++i)                                 // f~65..76
        for (stat s : {stat::max, stat::std}) add(i, s, col(i));
    for (std::size_t i = 26; i < 29; ++i) four(i);                        // f~77..88
    for (std::size_t k = 0; k < 3; ++k) {                                 // f~89..91
        add(29, stat::mean, 29 + k);
        d.back().name += k == 0 ? " (low)" : k == 1 ? " (middle)" : " (high)";
    }
    add(34, stat::sum, col(34));                                          // f~92
    four(35);                                                             // f~93..96
    for (std::size_t i = 30; i < 34; ++i) four(i);                        // f~97..112
    four(12);                                                             // f~113..116
    four(13);                                                             // f~117..120
    add(36, stat::window_box, 0);                                         // f~121
    return d;
}

inline std::vector<derived_feature> make_hand_derived()
{
    const auto& b = hand_basic();
    std::vector<derived_feature> d;
    auto add = [&](std::size_t i, stat s) {
        d.push_back({i, i, s, ""});
        d.back().name = "h~" + std::to_string(d.size()) + " " + std::string(to_string(s)) + " " + std::string(b[i].key) + " " +
                        std::string(b[i].description);
    };
    for (std::size_t i = 0; i < 12; ++i)
        for (stat s : {stat::max, stat::min, stat::std, stat::mean}) add(i, s);  // h~1..48
    for (std::size_t i : {12, 13, 14, 15, 16, 23})
        for (stat s : {stat::max, stat::std, stat::mean}) add(i, s);            // h~49..66
    for (std::size_t i : {17, 18, 19, 20, 21, 24, 22})
        for (stat s : {stat::max, stat::std}) add(i, s);                        // h~67..80
    add(25, stat::sum);                                                          // h~81
    add(26, stat::mean);                                                         // h~82
    add(27, stat::window_box);                                                   // h~83
    return d;
}

inline double dist(const positions_type& p, std::size_t f, std::size_t a, std::size_t b) noexcept
{
    const double dx = p(f, a, 0) - p(f, b, 0), dy = p(f, a, 1) - p(f, b, 1), dz = p(f, a, 2) - p(f, b, 2);
    return std::sqrt(dx * dx + dy * dy + dz * dz);
}

/// Finite-difference derivative of order 1..3 of point `a` at frame f (central differences, indices
/// clamped at the ends; exact for polynomials of the order's degree inside the clip), as a magnitude.
inline double derivative_norm(const positions_type& p, std::size_t a, std::size_t f, int order, double fps) noexcept
{
    const long F = static_cast<long>(p.shape()[0]);
    if (F < 2) return 0.0;
    auto at = [&](long t, std::size_t k) { return p(static_cast<std::size_t>(std::clamp(t, 0L, F - 1)), a, k); };
    // velocity at t: (x(t+1) - x(t-1)) / (t+1 - t-1) with clamped indices
    auto vel = [&](long t, std::size_t k) {
        const long t0 = std::max(0L, t - 1), t1 = std::min(F - 1, t + 1);
        return (at(t1, k) - at(t0, k)) * fps / static_cast<double>(t1 - t0);
    };
    auto acc = [&](long t, std::size_t k) {
        const long t0 = std::max(0L, t - 1), t1 = std::min(F - 1, t + 1);
        return (vel(t1, k) - vel(t0, k)) * fps / static_cast<double>(t1 - t0);
    };
    auto jerk = [&](long t, std::size_t k) {
        const long t0 = std::max(0L, t - 1), t1 = std::min(F - 1, t + 1);
        return (acc(t1, k) - acc(t0, k)) * fps / static_cast<double>(t1 - t0);
    };
    double s = 0;
    for (std::size_t k = 0; k < 3; ++k) {
        const long t = static_cast<long>(f);
        const double v = order == 1 ? vel(t, k) : order == 2 ? acc(t, k) : jerk(t, k);
        s += v * v;
    }
    return std::sqrt(s);
}

/// Volume of the box around `pts` at frame f along three orthonormal axes.
inline double box_volume(const positions_type& p, std::size_t f, const std::vector<std::size_t>& pts,
                         const std::array<vec3, 3>& axes) noexcept
{
    double v = 1.0;
    for (const auto& ax : axes) {
        double lo = std::numeric_limits<double>::infinity(), hi = -lo;
        for (std::size_t q : pts) {
            const double x = p(f, q, 0) * ax[0] + p(f, q, 1) * ax[1] + p(f, q, 2) * ax[2];
            lo = std::min(lo, x);
            hi = std::max(hi, x);
        }
        v *= hi - lo;
    }
    return v;
}

inline vec3 cross(const vec3& a, const vec3& b) noexcept
{
    return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
inline double dot(const vec3& a, const vec3& b) noexcept { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
inline vec3 unit_or(const vec3& a, const vec3& fallback) noexcept
{
    const double n = std::sqrt(dot(a, a));
    return n > 1e-12 ? vec3{a[0] / n, a[1] / n, a[2] / n} : fallback;
}
inline vec3 point(const positions_type& p, std::size_t f, std::size_t q) noexcept { return {p(f, q, 0), p(f, q, 1), p(f, q, 2)}; }
inline vec3 sub(const vec3& a, const vec3& b) noexcept { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }

/// Body frame at frame f: the horizontal shoulder line, the up axis, and their cross product.
inline std::array<vec3, 3> body_axes(const positions_type& p, std::size_t f, const role_map& r, int up) noexcept
{
    vec3 u{0, 0, 0};
    u[static_cast<std::size_t>(up)] = 1;
    vec3 lat = sub(point(p, f, r.index[static_cast<std::size_t>(role::right_shoulder)]),
                   point(p, f, r.index[static_cast<std::size_t>(role::left_shoulder)]));
    lat[static_cast<std::size_t>(up)] = 0;
    vec3 fallback{0, 0, 0};
    fallback[static_cast<std::size_t>((up + 1) % 3)] = 1;
    lat = unit_or(lat, fallback);
    const vec3 fwd = unit_or(cross(u, lat), vec3{0, 0, 1});
    return {lat, u, fwd};
}

/// Deceleration-peak indicator (times fps, so its window mean is peaks per second) of a speed signal.
inline std::vector<double> deceleration_peaks(const std::vector<double>& speed, double fps)
{
    const std::size_t F = speed.size();
    std::vector<double> ds(F, 0.0), out(F, 0.0);
    if (F < 3) return out;
    for (std::size_t t = 0; t < F; ++t) {
        const std::size_t t0 = t == 0 ? 0 : t - 1, t1 = std::min(F - 1, t + 1);
        ds[t] = (speed[t1] - speed[t0]) * fps / static_cast<double>(t1 - t0);
    }
    for (std::size_t t = 1; t + 1 < F; ++t)
        if (ds[t] < 0 && ds[t] < ds[t - 1] && ds[t] <= ds[t + 1]) out[t] = fps;
    return out;
}

inline void check_positions(const positions_type& p, double fps, const char* who)
{
    if (p.shape()[2] != 3) throw shape_error(std::string(who) + ": positions have " + std::to_string(p.shape()[2]) + " components, expected 3");
    if (p.shape()[0] == 0) throw shape_error(std::string(who) + ": no frames");
    if (!(fps > 0) || !std::isfinite(fps)) throw value_error(std::string(who) + ": frame rate " + std::to_string(fps) + " is not positive");
}

}  // namespace detail

/// @brief The basic features of a feature set (37 body rows of Table 1, or 28 hand rows).
inline const std::vector<basic_feature>& basic_features(feature_set fs)
{
    return fs == feature_set::body ? detail::body_basic() : detail::hand_basic();
}

/// @brief The derived features of a feature set (121 body, 83 hand), in the paper's numbering.
inline const std::vector<derived_feature>& derived_features(feature_set fs)
{
    static const std::vector<derived_feature> body = detail::make_body_derived();
    static const std::vector<derived_feature> hand = detail::make_hand_derived();
    return fs == feature_set::body ? body : hand;
}

/// @brief Number of derived features: 121 (body) or 83 (hand).
inline std::size_t derived_count(feature_set fs) { return derived_features(fs).size(); }

namespace detail {

/// Columns first..first+4 of frame f: the speed of each of five points; first+5..first+9 their acceleration;
/// first+10 their mean jerk. Returns their mean speed.
inline double five_point_derivatives(xt::xtensor<double, 2>& t, const positions_type& p, const std::array<std::size_t, 5>& points,
                                     std::size_t f, double fps, std::size_t first)
{
    double jerk = 0, speed = 0;
    for (std::size_t k = 0; k < 5; ++k) {
        const double v = derivative_norm(p, points[k], f, 1, fps);
        t(f, first + k) = v;
        t(f, first + 5 + k) = derivative_norm(p, points[k], f, 2, fps);
        jerk += derivative_norm(p, points[k], f, 3, fps);
        speed += v / 5.0;
    }
    t(f, first + 10) = jerk / 5.0;
    return speed;
}

/// Checks the positions and the roles basic_table() reads.
inline void check_basic_table(const positions_type& p, double fps, const role_map& r, feature_set fs)
{
    detail::check_positions(p, fps, "rcm::basic_table");
    r.require(fs);
    const std::size_t P = p.shape()[1];
    for (std::size_t k = 0; k < role_count; ++k)
        if (r.index[k] >= static_cast<int>(P))
            throw shape_error("rcm::basic_table: role '" + std::string(to_string(static_cast<role>(k))) + "' is point " +
                              std::to_string(r.index[k]) + " but positions have " + std::to_string(P) + " points");
}

}  // namespace detail

/// @brief The body's per-frame basic feature columns `[F, 38]`: f1..f29, three f30 columns, f31..f36 (see
/// basic_table(); positions and roles already checked).
inline xt::xtensor<double, 2> body_basic_table(const positions_type& p, double fps, const role_map& r, const lma_options& opt = {})
{
    const std::size_t F = p.shape()[0], P = p.shape()[1];
    const std::size_t up = static_cast<std::size_t>(opt.up_axis);
    using detail::dist;
    auto R = [&](role x) { return r.at(x); };
    xt::xtensor<double, 2> t = xt::zeros<double>({F, detail::body_columns});
    double ground = std::numeric_limits<double>::infinity();
    for (std::size_t f = 0; f < F; ++f)
        for (std::size_t q = 0; q < P; ++q) ground = std::min(ground, p(f, q, up));
    const std::size_t pel = R(role::pelvis), lh = R(role::left_hand), rh = R(role::right_hand), lf = R(role::left_foot),
                      rf = R(role::right_foot), head = R(role::head), chest = R(role::chest);
    const std::array<std::size_t, 5> eff{pel, lh, rh, lf, rf};
    std::vector<std::size_t> all(P);
    for (std::size_t q = 0; q < P; ++q) all[q] = q;
    const std::vector<std::size_t> five{head, lh, rh, lf, rf};
    const std::vector<std::size_t> upper{head, R(role::neck), chest, R(role::left_shoulder), R(role::right_shoulder),
                                         R(role::left_elbow), R(role::right_elbow), lh, rh};
    const std::vector<std::size_t> lower{pel, R(role::left_hip), R(role::right_hip), R(role::left_knee), R(role::right_knee), lf, rf};
    const std::vector<std::size_t> right{R(role::right_shoulder), R(role::right_elbow), rh, R(role::right_hip), R(role::right_knee), rf};
    const std::vector<std::size_t> left{R(role::left_shoulder), R(role::left_elbow), lh, R(role::left_hip), R(role::left_knee), lf};
    std::vector<double> mean_speed(F, 0.0);
    const std::size_t h0 = (up + 1) % 3, h1 = (up + 2) % 3;
    const long half = std::max(1L, std::lround(fps / 2));
    for (std::size_t f = 0; f < F; ++f) {
        t(f, 0) = dist(p, f, lf, pel);
        t(f, 1) = dist(p, f, rf, pel);
        t(f, 2) = dist(p, f, lh, R(role::left_shoulder));
        t(f, 3) = dist(p, f, rh, R(role::right_shoulder));
        t(f, 4) = dist(p, f, lh, rh);
        t(f, 5) = dist(p, f, lh, head);
        t(f, 6) = dist(p, f, rh, head);
        t(f, 7) = dist(p, f, lh, pel);
        t(f, 8) = dist(p, f, rh, pel);
        t(f, 9) = p(f, pel, up) - ground;
        t(f, 10) = t(f, 9) - 0.5 * (t(f, 0) + t(f, 1));
        t(f, 11) = dist(p, f, lf, rf);
        t(f, 12) = dist(p, f, lh, chest);
        t(f, 13) = dist(p, f, rh, chest);
        mean_speed[f] = detail::five_point_derivatives(t, p, eff, f, fps, 15);
        const auto axes = detail::body_axes(p, f, r, opt.up_axis);
        t(f, 26) = detail::box_volume(p, f, five, axes);
        t(f, 27) = detail::box_volume(p, f, all, axes);
        t(f, 28) = dist(p, f, head, pel);
        for (std::size_t hnd : {lh, rh}) {
            const double y = p(f, hnd, up);
            const std::size_t level = y < p(f, pel, up) ? 0 : y > p(f, head, up) ? 2 : 1;
            t(f, 29 + level) += 0.5;
        }
        t(f, 32) = detail::box_volume(p, f, upper, axes);
        t(f, 33) = detail::box_volume(p, f, lower, axes);
        t(f, 34) = detail::box_volume(p, f, right, axes);
        t(f, 35) = detail::box_volume(p, f, left, axes);
        if (f > 0) {
            const double dx = p(f, pel, h0) - p(f - 1, pel, h0), dz = p(f, pel, h1) - p(f - 1, pel, h1);
            t(f, 36) = std::sqrt(dx * dx + dz * dz);
        }
        const std::size_t a = static_cast<std::size_t>(std::max(0L, static_cast<long>(f) - half));
        const std::size_t b = std::min(F - 1, f + static_cast<std::size_t>(half));
        double lo0 = p(a, pel, h0), hi0 = lo0, lo1 = p(a, pel, h1), hi1 = lo1;
        for (std::size_t g = a; g <= b; ++g) {
            lo0 = std::min(lo0, p(g, pel, h0)), hi0 = std::max(hi0, p(g, pel, h0));
            lo1 = std::min(lo1, p(g, pel, h1)), hi1 = std::max(hi1, p(g, pel, h1));
        }
        const double seconds = static_cast<double>(b - a + 1) / fps;
        t(f, 37) = (hi0 - lo0) * (hi1 - lo1) / seconds;
    }
    const auto peaks = detail::deceleration_peaks(mean_speed, fps);
    for (std::size_t f = 0; f < F; ++f) t(f, 14) = peaks[f];
    return t;
}

/// @brief The hand's per-frame basic feature columns `[F, 27]`: h1..h27 (see basic_table(); positions and roles
/// already checked).
inline xt::xtensor<double, 2> hand_basic_table(const positions_type& p, double fps, const role_map& r)
{
    const std::size_t F = p.shape()[0];
    using detail::dist;
    auto R = [&](role x) { return r.at(x); };
    xt::xtensor<double, 2> t = xt::zeros<double>({F, detail::hand_columns});
    const std::size_t wrist = R(role::wrist), palm = R(role::palm);
    std::array<std::size_t, 5> tip{}, base{};
    for (std::size_t k = 0; k < 5; ++k) {
        tip[k] = R(static_cast<role>(static_cast<int>(role::thumb_tip) + static_cast<int>(k)));
        base[k] = R(static_cast<role>(static_cast<int>(role::thumb_base) + static_cast<int>(k)));
    }
    std::vector<std::size_t> hand_pts{wrist, palm};
    for (std::size_t k = 0; k < 5; ++k) hand_pts.push_back(base[k]), hand_pts.push_back(tip[k]);
    std::vector<double> mean_speed(F, 0.0);
    for (std::size_t f = 0; f < F; ++f) {
        for (std::size_t k = 0; k < 5; ++k) t(f, k) = dist(p, f, tip[k], palm);
        for (std::size_t k = 0; k < 4; ++k) t(f, 5 + k) = dist(p, f, tip[k], tip[k + 1]);
        t(f, 9) = dist(p, f, tip[0], tip[4]);
        double spread = 0;
        for (std::size_t k = 1; k < 4; ++k) {
            const vec3 a = detail::unit_or(detail::sub(detail::point(p, f, tip[k]), detail::point(p, f, base[k])), vec3{0, 1, 0});
            const vec3 b = detail::unit_or(detail::sub(detail::point(p, f, tip[k + 1]), detail::point(p, f, base[k + 1])), vec3{0, 1, 0});
            spread += std::acos(std::clamp(detail::dot(a, b), -1.0, 1.0));
        }
        t(f, 10) = spread / 3.0;
        const vec3 y = detail::unit_or(detail::sub(detail::point(p, f, palm), detail::point(p, f, wrist)), vec3{0, 1, 0});
        vec3 x = detail::sub(detail::point(p, f, base[1]), detail::point(p, f, base[4]));
        const double xy = detail::dot(x, y);
        x = detail::unit_or({x[0] - xy * y[0], x[1] - xy * y[1], x[2] - xy * y[2]}, vec3{1, 0, 0});
        const vec3 z = detail::unit_or(detail::cross(x, y), vec3{0, 0, 1});
        t(f, 11) = detail::box_volume(p, f, hand_pts, {x, y, z});
        mean_speed[f] = detail::five_point_derivatives(t, p, tip, f, fps, 12);
        t(f, 23) = detail::derivative_norm(p, wrist, f, 1, fps);
        t(f, 24) = detail::derivative_norm(p, wrist, f, 2, fps);
        if (f > 0) {
            double s2 = 0;
            for (std::size_t k = 0; k < 3; ++k) s2 += (p(f, wrist, k) - p(f - 1, wrist, k)) * (p(f, wrist, k) - p(f - 1, wrist, k));
            t(f, 25) = std::sqrt(s2);
        }
    }
    const auto peaks = detail::deceleration_peaks(mean_speed, fps);
    for (std::size_t f = 0; f < F; ++f) t(f, 26) = peaks[f];
    return t;
}

/// @brief Per-frame basic feature columns `[F, C]` (C = 38 body: f1..f29, three f30 columns, f31..f36;
/// C = 27 hand: h1..h27). Window-level features (f37, h28) have no column.
/// @param p `[F, P, 3]` world positions (world_positions()), @param fps frame rate
/// @throws value_error naming a role the feature set needs and the skeleton lacks; shape_error for bad shapes.
inline xt::xtensor<double, 2> basic_table(const positions_type& p, double fps, const role_map& r, feature_set fs,
                                          const lma_options& opt = {})
{
    detail::check_basic_table(p, fps, r, fs);
    return fs == feature_set::body ? body_basic_table(p, fps, r, opt) : hand_basic_table(p, fps, r);
}

/// @brief First frame of each sliding window: 0, 1, ..., F - L (stride 1); one window of the whole clip
/// when it is shorter than the window.
inline std::vector<std::size_t> window_starts(std::size_t frames, std::size_t length)
{
    std::vector<std::size_t> s;
    if (frames <= length) return {0};
    for (std::size_t a = 0; a + length <= frames; ++a) s.push_back(a);
    return s;
}

/// @brief Raw (unnormalised) derived features of every sliding window: `[W, D]`, row w covers frames
/// `[window_starts()[w], + min(L, F))`.
/// @throws as basic_table().
inline xt::xtensor<double, 2> window_features(const positions_type& p, double fps, const role_map& r, feature_set fs,
                                              const lma_options& opt = {})
{
    const auto table = basic_table(p, fps, r, fs, opt);
    const std::size_t F = p.shape()[0], P = p.shape()[1];
    const std::size_t L = std::min(F, window_length(fps, opt));
    const auto starts = window_starts(F, L);
    const auto& defs = derived_features(fs);
    std::vector<std::size_t> box_pts;
    if (fs == feature_set::body) {
        for (std::size_t q = 0; q < P; ++q) box_pts.push_back(q);
    } else {
        for (std::size_t k = 0; k < 5; ++k) box_pts.push_back(r.at(static_cast<role>(static_cast<int>(role::thumb_tip) + static_cast<int>(k))));
    }
    xt::xtensor<double, 2> out = xt::zeros<double>({starts.size(), defs.size()});
    for (std::size_t w = 0; w < starts.size(); ++w) {
        const std::size_t a = starts[w], b = a + L;
        for (std::size_t d = 0; d < defs.size(); ++d) {
            const auto& def = defs[d];
            double v = 0;
            if (def.s == stat::window_box) {
                v = 1.0;
                for (std::size_t k = 0; k < 3; ++k) {
                    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
                    for (std::size_t f = a; f < b; ++f)
                        for (std::size_t q : box_pts) lo = std::min(lo, p(f, q, k)), hi = std::max(hi, p(f, q, k));
                    v *= hi - lo;
                }
            } else {
                double mx = -std::numeric_limits<double>::infinity(), mn = -mx, sum = 0, sq = 0;
                for (std::size_t f = a; f < b; ++f) {
                    const double x = table(f, def.column);
                    mx = std::max(mx, x), mn = std::min(mn, x), sum += x;
                }
                const double mean = sum / static_cast<double>(L);
                for (std::size_t f = a; f < b; ++f) sq += (table(f, def.column) - mean) * (table(f, def.column) - mean);
                switch (def.s) {
                case stat::max: v = mx; break;
                case stat::min: v = mn; break;
                case stat::std: v = std::sqrt(sq / static_cast<double>(L)); break;
                case stat::mean: v = mean; break;
                case stat::sum: v = sum; break;
                default: break;
                }
            }
            out(w, d) = v;
        }
    }
    return out;
}

/// @brief Raw derived features of a clip: the mean of window_features() over its windows, `[D]`.
inline xt::xtensor<double, 1> clip_features(const positions_type& p, double fps, const role_map& r, feature_set fs,
                                            const lma_options& opt = {})
{
    const auto w = window_features(p, fps, r, fs, opt);
    xt::xtensor<double, 1> m = xt::zeros<double>({w.shape()[1]});
    for (std::size_t i = 0; i < w.shape()[0]; ++i)
        for (std::size_t d = 0; d < w.shape()[1]; ++d) m(d) += w(i, d) / static_cast<double>(w.shape()[0]);
    return m;
}

/// @brief Min-max normalisation of derived features to [0, 1], fitted on a training set (Section 3.1).
struct feature_normaliser {
    std::vector<double> lo, hi;  ///< [D] training minimum and maximum of each feature

    /// @brief Fits on rows of a `[N, D]` matrix.
    /// @throws shape_error when it has no rows.
    static feature_normaliser fit(const xt::xtensor<double, 2>& x)
    {
        if (x.shape()[0] == 0) throw shape_error("rcm::feature_normaliser::fit: no rows");
        feature_normaliser n;
        const std::size_t D = x.shape()[1];
        n.lo.assign(D, std::numeric_limits<double>::infinity());
        n.hi.assign(D, -std::numeric_limits<double>::infinity());
        for (std::size_t i = 0; i < x.shape()[0]; ++i)
            for (std::size_t d = 0; d < D; ++d) n.lo[d] = std::min(n.lo[d], x(i, d)), n.hi[d] = std::max(n.hi[d], x(i, d));
        return n;
    }
    /// @brief (x - lo) / (hi - lo) clamped to [0, 1]; 0.5 for a feature constant over the training set.
    xt::xtensor<double, 1> apply(const xt::xtensor<double, 1>& x) const
    {
        if (x.size() != lo.size())
            throw shape_error("rcm::feature_normaliser: " + std::to_string(x.size()) + " features, expected " + std::to_string(lo.size()));
        xt::xtensor<double, 1> y = xt::zeros<double>({x.size()});
        for (std::size_t d = 0; d < x.size(); ++d) {
            const double span = hi[d] - lo[d];
            y(d) = span > 1e-12 * std::max(1.0, std::abs(hi[d])) ? std::clamp((x(d) - lo[d]) / span, 0.0, 1.0) : 0.5;
        }
        return y;
    }
    /// @brief apply() to every row.
    xt::xtensor<double, 2> apply_rows(const xt::xtensor<double, 2>& x) const
    {
        xt::xtensor<double, 2> y = xt::zeros<double>(x.shape());
        for (std::size_t i = 0; i < x.shape()[0]; ++i) {
            xt::xtensor<double, 1> row = xt::zeros<double>({x.shape()[1]});
            for (std::size_t d = 0; d < x.shape()[1]; ++d) row(d) = x(i, d);
            const auto n = apply(row);
            for (std::size_t d = 0; d < x.shape()[1]; ++d) y(i, d) = n(d);
        }
        return y;
    }
};

}  // namespace handemo::rcm
