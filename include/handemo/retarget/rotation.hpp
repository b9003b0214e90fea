// Rotation helpers of the retargeting module: orthonormal bone frames built from two directions, matrix
// transpose, and the inverse of a joint's Euler channels (a rotation matrix back to the angles of any of the
// six Tait-Bryan channel orders BVH allows, choosing the solution nearest given reference angles so that a
// motion stays continuous from frame to frame).
#pragma once

#include <handemo/motion/skeleton.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <numbers>

namespace handemo::retarget {

inline constexpr mat3 identity3{1, 0, 0, 0, 1, 0, 0, 0, 1};

inline mat3 transpose(const mat3& a) noexcept { return {a[0], a[3], a[6], a[1], a[4], a[7], a[2], a[5], a[8]}; }

inline vec3 sub(const vec3& a, const vec3& b) noexcept { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
inline vec3 add(const vec3& a, const vec3& b) noexcept { return {a[0] + b[0], a[1] + b[1], a[2] + b[2]}; }
inline vec3 scale(const vec3& a, double s) noexcept { return {a[0] * s, a[1] * s, a[2] * s}; }
inline double dot(const vec3& a, const vec3& b) noexcept { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
inline double norm(const vec3& a) noexcept { return std::sqrt(dot(a, a)); }
inline vec3 cross(const vec3& a, const vec3& b) noexcept
{
    return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}

/// @brief The rotation whose columns are p, s and p x s, with p normalised and s made orthogonal to p and
/// normalised (Gram-Schmidt). Returns false (and leaves `out` alone) when |p| is 0 or s is within
/// `min_sine` (the sine of the angle) of being parallel to p.
inline bool frame_from(const vec3& p, const vec3& s, mat3& out, double min_sine = 0.05) noexcept
{
    const double np = norm(p), ns = norm(s);
    if (!(np > 0) || !(ns > 0)) return false;
    const vec3 a = scale(p, 1 / np);
    const vec3 so = sub(scale(s, 1 / ns), scale(a, dot(a, s) / ns));
    const double n2 = norm(so);
    if (!(n2 >= min_sine)) return false;
    const vec3 b = scale(so, 1 / n2), c = cross(a, b);
    out = {a[0], b[0], c[0], a[1], b[1], c[1], a[2], b[2], c[2]};
    return true;
}

/// diag(1, 1, -1) * m * diag(1, 1, -1): a relative frame seen in a mirror (the third axis of both frames flips).
inline mat3 mirrored(const mat3& m) noexcept { return {m[0], m[1], -m[2], m[3], m[4], -m[5], -m[6], -m[7], m[8]}; }

namespace detail {

/// `a` plus the multiple of 360 that brings it nearest `ref`.
inline double unwrap_near(double a, double ref) noexcept { return a + 360.0 * std::round((ref - a) / 360.0); }

inline double rad2deg(double r) noexcept { return r * 180.0 / std::numbers::pi; }

}  // namespace detail

/// @brief Euler angles (degrees, indexed x, y, z) of rotation `r` for a joint's channel order, such that
/// local_rotation(j, angles) equals r. Of the two solutions (and their 360-degree multiples) the one nearest
/// `ref` (same indexing) is returned; in gimbal lock the first angle keeps its reference value.
inline vec3 euler_from_matrix(const mat3& r, const std::array<axis, 3>& order, const vec3& ref) noexcept
{
    const auto i = static_cast<std::size_t>(order[0]), j = static_cast<std::size_t>(order[1]),
               k = static_cast<std::size_t>(order[2]);
    // R = R_i(a) R_j(b) R_k(c); e is the sign of the permutation (i, j, k): R[i][k] = e sin b,
    // R[j][k] = -e sin a cos b, R[k][k] = cos a cos b.
    const double e = ((i + 1) % 3 == j) ? 1.0 : -1.0;
    const auto at = [&](std::size_t row, std::size_t col) { return r[row * 3 + col]; };
    const double sb = std::clamp(e * at(i, k), -1.0, 1.0);
    const double cb = std::sqrt(std::max(0.0, 1 - sb * sb));
    double a0;
    if (cb > 1e-9) a0 = std::atan2(-e * at(j, k), at(k, k));
    else a0 = ref[i] * std::numbers::pi / 180.0;
    const double b0 = std::atan2(sb, cb);
    vec3 best{};
    double best_d = -1;
    for (int sol = 0; sol < 2; ++sol) {
        const double a = sol == 0 ? a0 : a0 + std::numbers::pi;
        const double b = sol == 0 ? b0 : std::numbers::pi - b0;
        // c from the residual R_j(-b) R_i(-a) R, a rotation about k: its [k2][k1] is sin c and [k1][k1] cos c
        const mat3 q = matmul(axis_rotation(order[1], -detail::rad2deg(b)), matmul(axis_rotation(order[0], -detail::rad2deg(a)), r));
        const std::size_t k1 = (k + 1) % 3, k2 = (k + 2) % 3;
        const double c = std::atan2(q[k2 * 3 + k1], q[k1 * 3 + k1]);
        vec3 ang{};
        ang[i] = detail::unwrap_near(detail::rad2deg(a), ref[i]);
        ang[j] = detail::unwrap_near(detail::rad2deg(b), ref[j]);
        ang[k] = detail::unwrap_near(detail::rad2deg(c), ref[k]);
        const double d = std::abs(ang[0] - ref[0]) + std::abs(ang[1] - ref[1]) + std::abs(ang[2] - ref[2]);
        if (best_d < 0 || d < best_d) best = ang, best_d = d;
    }
    return best;
}

}  // namespace handemo::retarget
