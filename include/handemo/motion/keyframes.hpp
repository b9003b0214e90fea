// Keyframes of a motion clip (Section 3.2, Eq. 2: M = [Pk_0 .. Pk_{k-1}], k = 9) and the way back
// (Section 3.4: "the new motion is produced by interpolation on those keyframes"). Angles are first
// unwrapped in time so a joint passing +-180 deg does not jump by 360. Keyframes are taken uniformly in
// time, by linear interpolation at frame positions i (n-1)/(K-1) (exact frames when (n-1) is a multiple of
// K-1), or after dynamic time warping (Berndt & Clifford 1994, the paper's [BC94]) against a reference
// clip. Reconstruction uses a uniform Catmull-Rom spline by default (C1, local, exact at the keyframes,
// overshoot bounded by the neighbouring keyframe differences, so one bad generated keyframe disturbs only
// its two neighbouring intervals) or a natural cubic spline (C2, more accurate on smooth data but global).
#pragma once

#include <handemo/core/error.hpp>
#include <handemo/motion/clip.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <span>
#include <string>
#include <vector>

namespace handemo {

/// Keyframe count chosen at run time (`--keyframes K`), like std::dynamic_extent.
inline constexpr std::size_t dynamic_keyframes = 0;

/// @brief A keyframed motion M (Eq. 2): K keyframes x J joints x 3 angles (degrees, x y z).
/// @tparam K keyframe count, or dynamic_keyframes to choose it at run time.
template <std::size_t K = 9>
struct keyframes {
    static constexpr std::size_t static_count = K;
    std::size_t count_ = K;         ///< K (equal to the template argument unless it is dynamic)
    std::size_t joints = 0;         ///< J
    std::vector<double> angles;     ///< [K, J, 3] degrees
    double duration = 0.0;          ///< source clip duration in seconds (0 when unknown, e.g. decoded)
    double fps = 0.0;               ///< source frame rate (0 when unknown)
    std::size_t source_frames = 0;  ///< source frame count (0 when unknown)

    constexpr std::size_t count() const noexcept { return K == dynamic_keyframes ? count_ : K; }
    double& at(std::size_t i, std::size_t j, std::size_t c) noexcept { return angles[(i * joints + j) * 3 + c]; }
    double at(std::size_t i, std::size_t j, std::size_t c) const noexcept { return angles[(i * joints + j) * 3 + c]; }

    /// @brief Zero keyframes of the given size.
    /// @throws value_error when k differs from a static K or is below 2.
    static keyframes make(std::size_t j, std::size_t k = K)
    {
        if (K != dynamic_keyframes && k != K)
            throw value_error("keyframes: " + std::to_string(k) + " keyframes requested, the type holds " +
                              std::to_string(K));
        if (k < 2) throw value_error("keyframes: " + std::to_string(k) + " keyframes, expected at least 2");
        keyframes r;
        r.count_ = k;
        r.joints = j;
        r.angles.assign(k * j * 3, 0.0);
        return r;
    }
};

/// @brief Converts between static and dynamic keyframe counts.
/// @throws shape_error when a dynamic source's count differs from a static target's K.
template <std::size_t To, std::size_t From>
keyframes<To> keyframe_cast(const keyframes<From>& k)
{
    static_assert(To == From || To == dynamic_keyframes || From == dynamic_keyframes,
                  "keyframe_cast: keyframes<From> and keyframes<To> have different static keyframe counts");
    if (To != dynamic_keyframes && k.count() != To)
        throw shape_error("keyframe_cast: " + std::to_string(k.count()) + " keyframes, expected " + std::to_string(To));
    keyframes<To> r;
    r.count_ = k.count();
    r.joints = k.joints;
    r.angles = k.angles;
    r.duration = k.duration;
    r.fps = k.fps;
    r.source_frames = k.source_frames;
    return r;
}

/// @brief An angle difference wrapped into (-180, 180] degrees.
inline double wrap_degrees(double d) noexcept
{
    d = std::fmod(d, 360.0);
    if (d > 180.0) d -= 360.0;
    if (d <= -180.0) d += 360.0;
    return d;
}

/// @brief Unwraps every joint/axis angle track in time: each step is moved by a multiple of 360 deg so
/// that it lies in (-180, 180]. A joint passing 180 deg then continues to 181 instead of jumping to -179.
inline void unwrap_angles(double* angles, std::size_t frames, std::size_t channels) noexcept
{
    for (std::size_t f = 1; f < frames; ++f)
        for (std::size_t ch = 0; ch < channels; ++ch) {
            const double prev = angles[(f - 1) * channels + ch];
            double& cur = angles[f * channels + ch];
            const double d = cur - prev;
            if (d > 180.0 || d <= -180.0) cur -= 360.0 * std::ceil((d - 180.0) / 360.0);
        }
}

/// @brief unwrap_angles() of every track of a clip.
inline void unwrap_angles(clip& c) noexcept { unwrap_angles(c.angles.data(), c.frames, c.skel.size() * 3); }

namespace detail {

inline void check_keyframe_args(const clip& c, std::size_t k, const char* fn)
{
    if (k < 2) throw value_error(std::string(fn) + ": " + std::to_string(k) + " keyframes, expected at least 2");
    if (c.frames < 2)
        throw value_error(std::string(fn) + ": clip " + (c.skel.name.empty() ? std::string("(unnamed)") : c.skel.name) +
                          " has " + std::to_string(c.frames) + " frames, expected at least 2");
    const std::size_t n = c.frames * c.skel.size() * 3;
    if (c.angles.size() != n)
        throw shape_error(std::string(fn) + ": clip holds " + std::to_string(c.angles.size()) +
                          " angles, expected frames*joints*3 = " + std::to_string(n));
}

/// Angles of clip `u` (already unwrapped) at fractional frame position `t`, linear interpolation.
inline void sample_linear(const double* angles, std::size_t frames, std::size_t J3, double t, double* out)
{
    const double tc = std::clamp(t, 0.0, static_cast<double>(frames - 1));
    const auto f0 = static_cast<std::size_t>(std::floor(tc));
    const std::size_t f1 = std::min(f0 + 1, frames - 1);
    const double w = tc - static_cast<double>(f0);
    const double* a = angles + f0 * J3;
    const double* b = angles + f1 * J3;
    for (std::size_t i = 0; i < J3; ++i) out[i] = w == 0.0 ? a[i] : a[i] + w * (b[i] - a[i]);
}
inline void sample_linear(const clip& u, double t, double* out) { sample_linear(u.angles.data(), u.frames, u.skel.size() * 3, t, out); }

template <std::size_t K>
keyframes<K> start_keyframes(const clip& c, std::size_t k)
{
    auto r = keyframes<K>::make(c.skel.size(), k);
    r.duration = c.duration();
    r.fps = c.fps;
    r.source_frames = c.frames;
    return r;
}

/// Dynamic time warping (Berndt & Clifford 1994) of a [n, D] against b [m, D], Euclidean local cost,
/// steps (1,0), (0,1), (1,1). Returns for every frame of b the mean index of the frames of a matched to
/// it (fractional when several frames of a match one frame of b).
inline std::vector<double> dtw_match(const double* a, std::size_t n, const double* b, std::size_t m, std::size_t D)
{
    constexpr double inf = std::numeric_limits<double>::infinity();
    std::vector<std::uint8_t> step(n * m);  // 0 diagonal, 1 from (i-1, j), 2 from (i, j-1)
    std::vector<double> prev(m, inf), cur(m, inf);
    for (std::size_t i = 0; i < n; ++i) {
        for (std::size_t j = 0; j < m; ++j) {
            double d = 0;
            const double* x = a + i * D;
            const double* y = b + j * D;
            for (std::size_t e = 0; e < D; ++e) d += (x[e] - y[e]) * (x[e] - y[e]);
            d = std::sqrt(d);
            double best = 0;
            std::uint8_t s = 0;
            if (i == 0 && j == 0) {
                best = 0;
            } else {
                const double diag = (i > 0 && j > 0) ? prev[j - 1] : inf;
                const double up = i > 0 ? prev[j] : inf;
                const double left = j > 0 ? cur[j - 1] : inf;
                best = diag, s = 0;
                if (up < best) best = up, s = 1;
                if (left < best) best = left, s = 2;
            }
            cur[j] = best + d;
            step[i * m + j] = s;
        }
        std::swap(prev, cur);
    }
    std::vector<double> sum(m, 0.0), cnt(m, 0.0);
    std::size_t i = n - 1, j = m - 1;
    for (;;) {
        sum[j] += static_cast<double>(i);
        cnt[j] += 1.0;
        if (i == 0 && j == 0) break;
        const std::uint8_t s = step[i * m + j];
        if (s == 0) --i, --j;
        else if (s == 1) --i;
        else --j;
    }
    for (std::size_t q = 0; q < m; ++q) sum[q] /= cnt[q];
    return sum;
}

}  // namespace detail

/// @brief Extracts K keyframes uniformly in time after unwrapping: keyframe i is the clip linearly
/// interpolated at frame position i (n-1)/(K-1) (an exact frame whenever that position is an integer).
/// @tparam K keyframe count; with dynamic_keyframes pass it as `k`.
/// @return keyframes [K, J, 3] with the source duration, fps and frame count.
/// @throws value_error for fewer than 2 frames or keyframes; shape_error for inconsistent clip arrays.
/// @brief extract_keyframes() into `out`, with `unwrapped` as scratch for the unwrapped angles: no allocation
/// when both already hold enough (a transfer's workspace reuses them).
/// @throws as extract_keyframes().
template <std::size_t K = 9>
void extract_keyframes_into(const clip& c, keyframes<K>& out, std::vector<double>& unwrapped, std::size_t k = K)
{
    detail::check_keyframe_args(c, k, "extract_keyframes");
    if (K != dynamic_keyframes && k != K)
        throw value_error("keyframes: " + std::to_string(k) + " keyframes requested, the type holds " + std::to_string(K));
    const std::size_t J3 = c.skel.size() * 3;
    unwrapped.assign(c.angles.begin(), c.angles.end());
    unwrap_angles(unwrapped.data(), c.frames, J3);
    out.count_ = k;
    out.joints = c.skel.size();
    out.angles.resize(k * J3);
    out.duration = c.duration();
    out.fps = c.fps;
    out.source_frames = c.frames;
    for (std::size_t i = 0; i < k; ++i) {
        const double t = static_cast<double>(i) * static_cast<double>(c.frames - 1) / static_cast<double>(k - 1);
        detail::sample_linear(unwrapped.data(), c.frames, J3, t, out.angles.data() + i * J3);
    }
}

template <std::size_t K = 9>
keyframes<K> extract_keyframes(const clip& c, std::size_t k = K)
{
    keyframes<K> r;
    std::vector<double> unwrapped;
    extract_keyframes_into(c, r, unwrapped, k);
    return r;
}

/// @brief Keyframes of `c` temporally aligned to `reference` by dynamic time warping (Section 3.2):
/// both clips are unwrapped, DTW matches every reference frame to frames of `c` on the [J*3] joint-angle
/// vectors, and keyframe i is `c` at the (mean) frame matched to the reference's uniform keyframe
/// position i (m-1)/(K-1). Cost O(n m) time, n m bytes of memory.
/// @throws shape_error when the skeletons differ in joint count; value_error as extract_keyframes.
template <std::size_t K = 9>
keyframes<K> extract_keyframes_aligned(const clip& c, const clip& reference, std::size_t k = K)
{
    detail::check_keyframe_args(c, k, "extract_keyframes_aligned");
    detail::check_keyframe_args(reference, k, "extract_keyframes_aligned (reference)");
    if (c.skel.size() != reference.skel.size())
        throw shape_error("extract_keyframes_aligned: clip has " + std::to_string(c.skel.size()) +
                          " joints, reference has " + std::to_string(reference.skel.size()));
    clip u = c, v = reference;
    unwrap_angles(u);
    unwrap_angles(v);
    const std::size_t J3 = c.skel.size() * 3;
    const std::vector<double> match = detail::dtw_match(u.angles.data(), u.frames, v.angles.data(), v.frames, J3);
    auto r = detail::start_keyframes<K>(c, k);
    for (std::size_t i = 0; i < k; ++i) {
        const double t = static_cast<double>(i) * static_cast<double>(v.frames - 1) / static_cast<double>(k - 1);
        const double t0 = std::floor(t);
        const auto f0 = static_cast<std::size_t>(t0);
        const std::size_t f1 = std::min(f0 + 1, v.frames - 1);
        const double pos = match[f0] + (t - t0) * (match[f1] - match[f0]);
        detail::sample_linear(u, pos, r.angles.data() + i * J3);
    }
    return r;
}

/// Interpolant used by reconstruct().
enum class interpolation {
    catmull_rom,     ///< uniform Catmull-Rom: C1, local, one-sided end tangents (default)
    natural_spline,  ///< natural cubic spline: C2, global, zero second derivative at both ends
    linear,          ///< piecewise linear: C0, never overshoots
};

namespace detail {

/// Second derivatives of the natural cubic spline through y[0..k-1] at unit spacing (Thomas algorithm on
/// M_{i-1} + 4 M_i + M_{i+1} = 6 (y_{i+1} - 2 y_i + y_{i-1}), M_0 = M_{k-1} = 0).
inline std::vector<double> natural_spline_m(const std::vector<double>& y)
{
    const std::size_t k = y.size();
    std::vector<double> m(k, 0.0);
    if (k < 3) return m;
    const std::size_t n = k - 2;
    std::vector<double> c(n), d(n);
    for (std::size_t i = 0; i < n; ++i) {
        const double rhs = 6.0 * (y[i + 2] - 2.0 * y[i + 1] + y[i]);
        const double denom = 4.0 - (i > 0 ? c[i - 1] : 0.0);
        c[i] = 1.0 / denom;
        d[i] = (rhs - (i > 0 ? d[i - 1] : 0.0)) / denom;
    }
    m[n] = d[n - 1];
    for (std::size_t i = n - 1; i-- > 0;) m[i + 1] = d[i] - c[i] * m[i + 2];
    return m;
}

/// Every angle track of `kf` sampled with `method` at keyframe positions u(f) in [0, K-1], f < frames, into `out`
/// (already sized): the interpolation of reconstruct() and reconstruct_at().
template <std::size_t K, class Position>
void interpolate_tracks(const keyframes<K>& kf, std::size_t frames, clip& out, interpolation method, Position position)
{
    const std::size_t k = kf.count(), J = kf.joints;
    std::vector<double> track, m2;  // only the natural spline needs the track as a vector
    for (std::size_t j = 0; j < J; ++j)
        for (std::size_t a = 0; a < 3; ++a) {
            const auto y = [&](std::size_t i) { return kf.at(i, j, a); };
            if (method == interpolation::natural_spline) {
                track.resize(k);
                for (std::size_t i = 0; i < k; ++i) track[i] = y(i);
                m2 = natural_spline_m(track);
            }
            for (std::size_t f = 0; f < frames; ++f) {
                const double u = position(f);
                const std::size_t i = std::min(static_cast<std::size_t>(std::floor(u)), k - 2);
                const double t = u - static_cast<double>(i);
                const double p0 = y(i), p1 = y(i + 1);
                double v = 0;
                if (method == interpolation::linear) {
                    v = p0 + t * (p1 - p0);
                } else if (method == interpolation::natural_spline) {
                    // S(t) = (1-t) p0 + t p1 + ((1-t)^3 - (1-t)) M_i / 6 + (t^3 - t) M_{i+1} / 6
                    const double s = 1.0 - t;
                    v = s * p0 + t * p1 + ((s * s * s - s) * m2[i] + (t * t * t - t) * m2[i + 1]) / 6.0;
                } else {
                    // Cubic Hermite with tangents m_i = (p_{i+1} - p_{i-1}) / 2, one-sided at the ends.
                    const double m0 = i > 0 ? 0.5 * (p1 - y(i - 1)) : p1 - p0;
                    const double m1 = i + 2 < k ? 0.5 * (y(i + 2) - p0) : p1 - p0;
                    const double t2 = t * t, t3 = t2 * t;
                    v = (2 * t3 - 3 * t2 + 1) * p0 + (t3 - 2 * t2 + t) * m0 + (-2 * t3 + 3 * t2) * p1 + (t3 - t2) * m1;
                }
                out.angle(f, j, a) = v;
            }
        }
}

}  // namespace detail

/// @brief Full-rate clip from keyframes (Section 3.4): keyframe i sits at frame position i (N-1)/(K-1),
/// every angle track is interpolated with `method` (exact at the keyframes).
/// @param kf keyframes [K, J, 3]
/// @param skel skeleton with J joints (channels, offsets and limits of the output)
/// @param frames N >= 2 output frames; @param fps output frame rate
/// @param root_translation optional [N, 3] values for the position channels of root joints (bodies);
///        empty: every position is the joint's rest offset
/// @throws shape_error when J or the translation track's size does not match; value_error for N < 2 or
///         a non-positive fps.
template <std::size_t K>
void reconstruct_into(const keyframes<K>& kf, const skeleton& skel, std::size_t frames, double fps, clip& out,
                      std::span<const double> root_translation = {}, interpolation method = interpolation::catmull_rom)
{
    const std::size_t k = kf.count(), J = skel.size();
    if (kf.joints != J)
        throw shape_error("reconstruct: keyframes have " + std::to_string(kf.joints) + " joints, skeleton '" +
                          skel.name + "' has " + std::to_string(J));
    if (kf.angles.size() != k * J * 3)
        throw shape_error("reconstruct: keyframes hold " + std::to_string(kf.angles.size()) + " angles, expected " +
                          std::to_string(k * J * 3));
    if (frames < 2) throw value_error("reconstruct: " + std::to_string(frames) + " frames, expected at least 2");
    if (!(fps > 0) || !std::isfinite(fps)) throw value_error("reconstruct: fps " + std::to_string(fps) + " is not positive");
    if (!root_translation.empty() && root_translation.size() != frames * 3)
        throw shape_error("reconstruct: root translation holds " + std::to_string(root_translation.size()) +
                          " values, expected frames*3 = " + std::to_string(frames * 3));
    out.reset(skel, frames, fps);
    detail::interpolate_tracks(kf, frames, out, method,
                               [&](std::size_t f) { return static_cast<double>(f) * static_cast<double>(k - 1) / static_cast<double>(frames - 1); });
    if (!root_translation.empty())
        for (std::size_t j = 0; j < J; ++j)
            if (skel.joints[j].parent < 0 && skel.joints[j].has_position())
                for (std::size_t f = 0; f < frames; ++f)
                    for (std::size_t a = 0; a < 3; ++a) out.position(f, j, a) = root_translation[f * 3 + a];
}

/// @brief reconstruct_into() a new clip.
template <std::size_t K>
clip reconstruct(const keyframes<K>& kf, const skeleton& skel, std::size_t frames, double fps,
                 std::span<const double> root_translation = {}, interpolation method = interpolation::catmull_rom)
{
    clip out;
    reconstruct_into(kf, skel, frames, fps, out, root_translation, method);
    return out;
}

/// @brief A full-rate clip from keyframes at keyframe positions of one's own choosing: frame f of the output is the
/// interpolant of reconstruct() at keyframe position positions[f] in [0, K-1] (reconstruct() takes f (K-1)/(N-1)),
/// so a time warp (an emotion whose tempo changes over the clip) moves along the same curves.
/// @throws shape_error when J does not match; value_error for fewer than 2 positions, a position outside
/// [0, K-1] or a non-positive fps.
template <std::size_t K>
void reconstruct_at(const keyframes<K>& kf, const skeleton& skel, std::span<const double> positions, double fps, clip& out,
                    interpolation method = interpolation::catmull_rom)
{
    const std::size_t k = kf.count(), J = skel.size(), frames = positions.size();
    if (kf.joints != J)
        throw shape_error("reconstruct_at: keyframes have " + std::to_string(kf.joints) + " joints, skeleton '" + skel.name + "' has " +
                          std::to_string(J));
    if (kf.angles.size() != k * J * 3 || k < 2)
        throw shape_error("reconstruct_at: keyframes hold " + std::to_string(kf.angles.size()) + " angles, expected " + std::to_string(k * J * 3) +
                          " of at least 2 keyframes");
    if (frames < 2) throw value_error("reconstruct_at: " + std::to_string(frames) + " frames, expected at least 2");
    if (!(fps > 0) || !std::isfinite(fps)) throw value_error("reconstruct_at: fps " + std::to_string(fps) + " is not positive");
    for (std::size_t f = 0; f < frames; ++f)
        if (!(positions[f] >= 0 && positions[f] <= static_cast<double>(k - 1)))
            throw value_error("reconstruct_at: frame " + std::to_string(f) + ": keyframe position " + std::to_string(positions[f]) +
                              " is outside [0, " + std::to_string(k - 1) + "]");
    out.reset(skel, frames, fps);
    detail::interpolate_tracks(kf, frames, out, method, [&](std::size_t f) { return positions[f]; });
}

/// @brief Resamples every position channel of `c` to `frames` frames (linear in time), into `out`.
inline void stretch_positions_into(const clip& c, std::size_t frames, std::vector<double>& out)
{
    const std::size_t J3 = c.skel.size() * 3;
    out.resize(frames * J3);
    for (std::size_t f = 0; f < frames; ++f) {
        const double t = frames > 1 ? static_cast<double>(f) * static_cast<double>(c.frames - 1) / static_cast<double>(frames - 1) : 0.0;
        const auto f0 = static_cast<std::size_t>(std::floor(t));
        const std::size_t f1 = std::min(f0 + 1, c.frames - 1);
        const double a = t - static_cast<double>(f0);
        for (std::size_t i = 0; i < J3; ++i)
            out[f * J3 + i] = (1 - a) * c.positions[f0 * J3 + i] + a * c.positions[f1 * J3 + i];
    }
}

/// @brief stretch_positions_into() a new vector.
inline std::vector<double> stretch_positions(const clip& c, std::size_t frames)
{
    std::vector<double> out;
    stretch_positions_into(c, frames, out);
    return out;
}

}  // namespace handemo
