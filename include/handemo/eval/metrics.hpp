// Numeric comparison of motions, the evaluation the hand paper names as future work (Section 5): keyframe
// joint-angle RMSE between a transferred clip and the captured clip of the target emotion, and Table 1's
// characteristics as measurable quantities: range of motion (mean over channels of max - min of the
// unwrapped angle) and speed (mean absolute angular velocity, degrees per second).
#pragma once

#include <handemo/core/error.hpp>
#include <handemo/motion/clip.hpp>
#include <handemo/motion/keyframes.hpp>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

namespace handemo::eval {

/// @brief RMSE in degrees between the K uniform keyframes of two clips of the same skeleton.
/// @throws shape_error when the joint counts differ.
template <std::size_t K = 9>
double keyframe_rmse(const clip& a, const clip& b)
{
    if (a.skel.size() != b.skel.size())
        throw shape_error("keyframe_rmse: clips have " + std::to_string(a.skel.size()) + " and " +
                          std::to_string(b.skel.size()) + " joints");
    const auto ka = extract_keyframes<K>(a), kb = extract_keyframes<K>(b);
    double s = 0;
    for (std::size_t i = 0; i < ka.angles.size(); ++i) {
        const double d = ka.angles[i] - kb.angles[i];
        s += d * d;
    }
    return std::sqrt(s / static_cast<double>(ka.angles.size()));
}

/// @brief Mean over joints and axes of the range (max - min, degrees) of the unwrapped angle tracks.
inline double range_of_motion(const clip& c)
{
    if (c.frames == 0 || c.skel.size() == 0) throw value_error("range_of_motion: empty clip");
    clip u = c;
    unwrap_angles(u);
    const std::size_t J3 = c.skel.size() * 3;
    double total = 0;
    for (std::size_t k = 0; k < J3; ++k) {
        double lo = u.angles[k], hi = lo;
        for (std::size_t f = 1; f < c.frames; ++f) {
            lo = std::min(lo, u.angles[f * J3 + k]);
            hi = std::max(hi, u.angles[f * J3 + k]);
        }
        total += hi - lo;
    }
    return total / static_cast<double>(J3);
}

/// @brief Mean absolute angular velocity (degrees per second) over joints, axes and frames.
inline double mean_speed(const clip& c)
{
    if (c.frames < 2) throw value_error("mean_speed: a clip of " + std::to_string(c.frames) + " frames has no speed");
    clip u = c;
    unwrap_angles(u);
    const std::size_t J3 = c.skel.size() * 3;
    double total = 0;
    for (std::size_t f = 1; f < c.frames; ++f)
        for (std::size_t k = 0; k < J3; ++k) total += std::abs(u.angles[f * J3 + k] - u.angles[(f - 1) * J3 + k]);
    return total * c.fps / static_cast<double>((c.frames - 1) * J3);
}

}  // namespace handemo::eval
