// The cadence of a motion: how fast it moves through its own range, whatever the number of cycles a take holds.
//
// cadence_time(c) = sum over rotation channels of the range / sum of the mean absolute speed, both on the angle
// tracks unwrapped and smoothed by a quadratic Savitzky-Golay filter of 0.2 s (capture noise and tremor removed).
// A track that moves monotonically between its extremes travels twice its range per cycle, so for it the value is
// half the cycle period: two cycles or five of the same movement give the same value, a take played k times slower
// gives k times the value, and scaling every excursion about the pose leaves it unchanged. The duration of a take
// has none of these properties when takes differ in how many cycles they hold (a capture cut to a fragment of a
// cycle, a walk of three steps against one of eight), which is why the tempo can be learned from it
// (stargan::tempo_basis::cadence, dataset.hpp).
#pragma once

#include <handemo/core/error.hpp>
#include <handemo/motion/clip.hpp>
#include <handemo/motion/keyframes.hpp>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <string>
#include <vector>

namespace handemo {

/// @brief The smoothing cadence_time() measures on by default (seconds): the window of the full-rate judge's tremor
/// residual, so a fast tremor is left out of the cadence as it is kept out of that judge's motion.
inline constexpr double cadence_smooth_seconds = 0.2;

namespace detail {

/// Savitzky-Golay smoothing (a least-squares quadratic over 2h + 1 frames, the centre's value):
///   s_i = sum_{k=-h..h} c_k v_{i+k},  c_k = (3 (3h^2 + 3h - 1) - 15 k^2) / ((2h + 1)(4h^2 + 4h - 3)).
/// It keeps a track's curvature, so a slow large motion leaves almost nothing in v - s while a tremor faster than
/// the window stays there. Near the ends the window shrinks to stay centred (h = i or n - 1 - i; h = 0 keeps v_i).
inline std::vector<double> quadratic_smooth(const std::vector<double>& v, std::size_t h)
{
    const std::size_t n = v.size();
    std::vector<double> out(n);
    for (std::size_t i = 0; i < n; ++i) {
        const std::size_t r = std::min({h, i, n - 1 - i});
        if (r == 0) {
            out[i] = v[i];
            continue;
        }
        const double R = static_cast<double>(r), norm = (2 * R + 1) * (4 * R * R + 4 * R - 3);
        double s = 0;
        for (std::size_t k = i - r; k <= i + r; ++k) {
            const double d = static_cast<double>(k) - static_cast<double>(i);
            s += (3 * (3 * R * R + 3 * R - 1) - 15 * d * d) / norm * v[k];
        }
        out[i] = s;
    }
    return out;
}

/// cadence_time() without its checks: 0 for a clip of fewer than 3 frames, a non-positive or non-finite frame
/// rate, a non-finite angle or no motion (the tempo fit skips such clips).
inline double cadence_time_of(const clip& c, double smooth_seconds)
{
    const std::size_t n = c.frames, C = c.skel.size() * 3;
    if (n < 3 || C == 0 || c.angles.size() != n * C || !(c.fps > 0) || !std::isfinite(c.fps)) return 0.0;
    const std::size_t h = std::min<std::size_t>(static_cast<std::size_t>(std::lround(0.5 * smooth_seconds * c.fps)), (n - 1) / 2);
    double range = 0, speed = 0;
    std::vector<double> u(n);
    for (std::size_t ch = 0; ch < C; ++ch) {
        u[0] = c.angles[ch];
        for (std::size_t i = 1; i < n; ++i) u[i] = u[i - 1] + wrap_degrees(c.angles[i * C + ch] - c.angles[(i - 1) * C + ch]);
        const auto s = h > 0 ? quadratic_smooth(u, h) : u;
        const auto [lo, hi] = std::minmax_element(s.begin(), s.end());
        range += *hi - *lo;
        double sp = 0;
        for (std::size_t i = 1; i < n; ++i) sp += std::abs(s[i] - s[i - 1]);
        speed += sp * c.fps / static_cast<double>(n - 1);
    }
    if (!std::isfinite(range) || !std::isfinite(speed) || !(speed > 0)) return 0.0;
    return range / speed;
}

}  // namespace detail

/// @brief The clip's characteristic time in seconds (see the header comment): the summed range of its rotation
/// channels over their summed mean speed, on tracks unwrapped and smoothed over `smooth_seconds`.
/// @throws value_error naming the clip for fewer than 3 frames, a non-positive frame rate, non-finite angles or a
/// clip that does not move.
inline double cadence_time(const clip& c, double smooth_seconds = cadence_smooth_seconds)
{
    const auto bad = [&](const std::string& why) { throw value_error("cadence_time: clip " + c.skel.name + " " + why); };
    if (c.frames < 3) bad("has " + std::to_string(c.frames) + " frames, at least 3 are needed");
    if (!(c.fps > 0) || !std::isfinite(c.fps)) bad("has frame rate " + std::to_string(c.fps));
    if (!(smooth_seconds >= 0) || !std::isfinite(smooth_seconds)) bad("smoothing " + std::to_string(smooth_seconds) + " s is not a duration");
    const double t = detail::cadence_time_of(c, smooth_seconds);
    if (!(t > 0)) bad("does not move, or holds a non-finite angle: it has no cadence");
    return t;
}

}  // namespace handemo
