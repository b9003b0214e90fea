// Numeric comparison of motions, the evaluation the hand paper names as future work (Section 5): keyframe
// joint-angle RMSE between a transferred clip and the captured clip of the target emotion (on the K uniform
// keyframes of Eq. 2, so clips of different durations compare keyframe by keyframe; each difference is
// wrapped into (-180, 180] so a 359-degree step of an unwrapped yaw counts as 1 degree), and Table 1's
// characteristics as measurable quantities: range of motion (mean over channels of max - min of the
// angle, taken within 180 degrees of the first frame) and speed (mean absolute angular velocity, degrees per second). The ratios of the
// evaluation are taken on each clip's keyframe view (K keyframes reconstructed at the clip's own frame
// count, Section 3.4), so a transferred clip, which only ever has K keyframes of detail, is not compared
// with the tremor and noise of a raw capture.
#pragma once

#include <handemo/core/error.hpp>
#include <handemo/motion/cadence.hpp>
#include <handemo/motion/clip.hpp>
#include <handemo/motion/detail_layer.hpp>
#include <handemo/motion/keyframes.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

namespace handemo::metrics {

using ::handemo::wrap_degrees;  // motion/keyframes.hpp: an angle difference wrapped into (-180, 180]

/// @brief RMSE in degrees between two keyframe sets of equal shape (differences wrapped, see wrap_degrees).
/// @throws shape_error naming both shapes when K or J differ.
template <std::size_t K>
double keyframe_rmse(const keyframes<K>& a, const keyframes<K>& b)
{
    if (a.count() != b.count() || a.joints != b.joints || a.angles.size() != b.angles.size())
        throw shape_error("keyframe_rmse: keyframes are " + std::to_string(a.count()) + "x" + std::to_string(a.joints) + " and " +
                          std::to_string(b.count()) + "x" + std::to_string(b.joints) + " (keyframes x joints)");
    if (a.angles.empty()) throw value_error("keyframe_rmse: empty keyframes");
    double s = 0;
    for (std::size_t i = 0; i < a.angles.size(); ++i) {
        const double d = wrap_degrees(a.angles[i] - b.angles[i]);
        s += d * d;
    }
    return std::sqrt(s / static_cast<double>(a.angles.size()));
}

/// @brief RMSE in degrees between the K uniform keyframes of two clips of the same skeleton.
/// @throws shape_error when the joint counts differ.
template <std::size_t K = 9>
double keyframe_rmse(const clip& a, const clip& b)
{
    if (a.skel.size() != b.skel.size())
        throw shape_error("keyframe_rmse: clips " + a.skel.name + " and " + b.skel.name + " have " +
                          std::to_string(a.skel.size()) + " and " + std::to_string(b.skel.size()) + " joints");
    return keyframe_rmse(extract_keyframes<K>(a), extract_keyframes<K>(b));
}

/// @brief Mean over joints and axes of the range (max - min, degrees) of each angle track, every frame's
/// angle taken within 180 degrees of the track's first frame (first + wrap(angle - first)). A channel's range
/// is so at most 360 degrees: an Euler track that unwraps by several turns (a gimbal flip repeated, as in
/// some Bandai spine tracks, which unwrap to +-1980 degrees) cannot dominate the mean.
inline double range_of_motion(const clip& c)
{
    if (c.frames == 0 || c.skel.size() == 0) throw value_error("range_of_motion: clip " + c.skel.name + " is empty");
    const std::size_t J3 = c.skel.size() * 3;
    if (c.angles.size() != c.frames * J3)
        throw shape_error("range_of_motion: clip holds " + std::to_string(c.angles.size()) + " angles, expected frames*joints*3 = " +
                          std::to_string(c.frames * J3));
    return ::handemo::detail::range_of_motion_of(c);  // motion/detail_layer.hpp: shared with the detail layer's check
}

/// @brief Mean absolute angular velocity (degrees per second) over joints, axes and frames.
inline double mean_speed(const clip& c)
{
    if (c.frames < 2) throw value_error("mean_speed: clip " + c.skel.name + " of " + std::to_string(c.frames) + " frames has no speed");
    return ::handemo::detail::mean_speed_of(c);
}

/// @brief The clip as the network sees it: K uniform keyframes (Eq. 2) reconstructed by Catmull-Rom at the
/// clip's own frame count and rate (Section 3.4). Position channels are kept.
/// @throws value_error for fewer than 2 frames.
template <std::size_t K = 9>
clip keyframe_view(const clip& c)
{
    clip v = reconstruct(extract_keyframes<K>(c), c.skel, c.frames, c.fps);
    v.positions = c.positions;
    return v;
}

/// @brief Table 1's characteristics of one clip, measured on its keyframe view.
struct characteristics {
    double range_of_motion = 0;  ///< degrees, see range_of_motion()
    double speed = 0;            ///< degrees per second, see mean_speed()
    double duration = 0;         ///< seconds
    double cadence = 0;          ///< seconds, cadence_time() (measure_full() only; 0 when the clip does not move)
};

/// @brief Range of motion, speed and duration of the keyframe view of `c`.
template <std::size_t K = 9>
characteristics measure(const clip& c)
{
    const clip v = keyframe_view<K>(c);
    return {range_of_motion(v), mean_speed(v), c.duration()};
}

/// @brief Range of motion, speed, duration and cadence of `c` as it is (full rate: a capture's tremor and noise
/// count in the first two; the cadence is measured on the smoothed tracks, motion/cadence.hpp).
inline characteristics measure_full(const clip& c)
{
    return {range_of_motion(c), mean_speed(c), c.duration(), ::handemo::detail::cadence_time_of(c, cadence_smooth_seconds)};
}

/// @brief `num / den` of a characteristic; a ratio to a motionless input is undefined.
/// @throws value_error naming `what` when den is not positive.
inline double ratio(double num, double den, const char* what)
{
    if (!(den > 0) || !std::isfinite(num))
        throw value_error(std::string("ratio: ") + what + ": " + std::to_string(num) + " / " + std::to_string(den) +
                          " is undefined (the input does not move)");
    return num / den;
}

/// @brief |log(a / b)|: how far a ratio is from a reference ratio, symmetric in over- and undershoot
/// (0 when equal; log 2 = 0.69 when one is twice the other).
inline double log_ratio_error(double a, double b)
{
    if (!(a > 0) || !(b > 0)) return std::numeric_limits<double>::infinity();
    return std::abs(std::log(a / b));
}

/// @brief Duration-ratio error of an output against the real clip of its target: |log(duration out / duration
/// real)|. Both ratios to the input share the input's duration, so this is |log(out ratio / real ratio)| of
/// Table 1's "fast" and "slow"; an output that keeps the input's duration (identity) scores
/// |log(duration in / duration real)|. Infinite when a clip has no duration.
inline double duration_error(const clip& out, const clip& real) { return log_ratio_error(out.duration(), real.duration()); }

}  // namespace handemo::metrics
