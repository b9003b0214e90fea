// Unit quaternions for the glove reader: products, conjugates, conversion to and from the row-major
// rotation matrices of skeleton.hpp, sign-aligned averaging (calibration) and the ZXY Euler split
// R = Rz(a) Rx(b) Ry(c) used by the hand's finger joints (channels `Zrotation Xrotation Yrotation`).
#pragma once

#include <handemo/motion/skeleton.hpp>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <span>

namespace handemo {

/// @brief A quaternion w + xi + yj + zk; a unit one is the rotation v -> q v q*.
struct quat {
    double w = 1, x = 0, y = 0, z = 0;
};

inline quat operator*(const quat& a, const quat& b) noexcept
{
    return {a.w * b.w - a.x * b.x - a.y * b.y - a.z * b.z, a.w * b.x + a.x * b.w + a.y * b.z - a.z * b.y,
            a.w * b.y - a.x * b.z + a.y * b.w + a.z * b.x, a.w * b.z + a.x * b.y - a.y * b.x + a.z * b.w};
}
inline quat conjugate(const quat& q) noexcept { return {q.w, -q.x, -q.y, -q.z}; }
inline double norm(const quat& q) noexcept { return std::sqrt(q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z); }
inline quat normalized(const quat& q) noexcept
{
    const double n = norm(q);
    return {q.w / n, q.x / n, q.y / n, q.z / n};
}
inline double dot(const quat& a, const quat& b) noexcept { return a.w * b.w + a.x * b.x + a.y * b.y + a.z * b.z; }

/// Angle of the rotation between two unit quaternions, in degrees.
inline double angle_between_deg(const quat& a, const quat& b) noexcept
{
    const double d = std::min(1.0, std::abs(dot(a, b)));
    return 2 * std::acos(d) * 180 / std::numbers::pi;
}

/// Rotation matrix (row-major) of a unit quaternion.
inline mat3 to_mat3(const quat& q) noexcept
{
    const double w = q.w, x = q.x, y = q.y, z = q.z;
    return {1 - 2 * (y * y + z * z), 2 * (x * y - w * z),     2 * (x * z + w * y),
            2 * (x * y + w * z),     1 - 2 * (x * x + z * z), 2 * (y * z - w * x),
            2 * (x * z - w * y),     2 * (y * z + w * x),     1 - 2 * (x * x + y * y)};
}

/// Unit quaternion of a rotation matrix (Shepperd's method), w >= 0.
inline quat from_mat3(const mat3& m) noexcept
{
    const double tr = m[0] + m[4] + m[8];
    quat q;
    if (tr > 0) {
        const double s = 2 * std::sqrt(1 + tr);
        q = {s / 4, (m[7] - m[5]) / s, (m[2] - m[6]) / s, (m[3] - m[1]) / s};
    } else if (m[0] > m[4] && m[0] > m[8]) {
        const double s = 2 * std::sqrt(1 + m[0] - m[4] - m[8]);
        q = {(m[7] - m[5]) / s, s / 4, (m[1] + m[3]) / s, (m[2] + m[6]) / s};
    } else if (m[4] > m[8]) {
        const double s = 2 * std::sqrt(1 + m[4] - m[0] - m[8]);
        q = {(m[2] - m[6]) / s, (m[1] + m[3]) / s, s / 4, (m[5] + m[7]) / s};
    } else {
        const double s = 2 * std::sqrt(1 + m[8] - m[0] - m[4]);
        q = {(m[3] - m[1]) / s, (m[2] + m[6]) / s, (m[5] + m[7]) / s, s / 4};
    }
    if (q.w < 0) q = {-q.w, -q.x, -q.y, -q.z};
    return normalized(q);
}

/// @brief Mean orientation of nearby unit quaternions: signs aligned to the first, summed, normalised
/// (the chordal L2 mean, accurate for the small spread of a held pose).
inline quat average(std::span<const quat> qs) noexcept
{
    if (qs.empty()) return {};
    quat s{0, 0, 0, 0};
    for (const auto& q : qs) {
        const double k = dot(q, qs.front()) < 0 ? -1.0 : 1.0;
        s = {s.w + k * q.w, s.x + k * q.x, s.y + k * q.y, s.z + k * q.z};
    }
    return normalized(s);
}

/// @brief ZXY Euler angles (degrees) {a, b, c} with R = Rz(a) Rx(b) Ry(c), the branch with the smaller
/// |a| + |c| (finger abduction and twist are small; flexion b may pass 90 degrees, e.g. MCP + PIP of a fist).
/// At b = +-90 only a + c is defined; c is then 0.
inline vec3 euler_zxy_deg(const mat3& r) noexcept
{
    constexpr double deg = 180 / std::numbers::pi;
    const double sb = std::clamp(r[7], -1.0, 1.0);
    const double b = std::asin(sb);
    double a, c;
    if (std::abs(std::cos(b)) < 1e-9) {
        // R = Rz(a +- c) Rx(+-90): take everything as a.
        c = 0;
        a = std::atan2(r[3], r[0]);
    } else {
        a = std::atan2(-r[1], r[4]);
        c = std::atan2(-r[6], r[8]);
    }
    double A = a * deg, B = b * deg, C = c * deg;
    // The other branch: (a + 180, 180 - b, c + 180), wrapped to (-180, 180].
    auto wrap = [](double v) { return v > 180 ? v - 360 : (v <= -180 ? v + 360 : v); };
    const double A2 = wrap(A + 180), B2 = wrap(180 - B), C2 = wrap(C + 180);
    if (std::abs(A2) + std::abs(C2) < std::abs(A) + std::abs(C)) return {A2, B2, C2};
    return {A, B, C};
}

}  // namespace handemo
