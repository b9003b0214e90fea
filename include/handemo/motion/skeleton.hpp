// Skeletons of any shape (a BVH hierarchy, the 23-joint hand, a 22-joint body) and forward kinematics:
// joint angles in degrees -> 3D joint positions. Rotations follow BVH: a joint's local rotation is the
// product of its rotation channels in the order they are listed (e.g. `Zrotation Xrotation Yrotation`
// gives R = Rz * Rx * Ry), and a child's position is parent_position + parent_rotation * child_offset.
#pragma once

#include <handemo/core/error.hpp>

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <numbers>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace handemo {

using vec3 = std::array<double, 3>;
/// Row-major 3x3 rotation matrix.
using mat3 = std::array<double, 9>;

enum class axis : std::uint8_t { x = 0, y = 1, z = 2 };

/// One BVH channel: a translation or a rotation about an axis.
enum class channel : std::uint8_t { xposition, yposition, zposition, xrotation, yrotation, zrotation };

constexpr bool is_rotation(channel c) noexcept { return c >= channel::xrotation; }
constexpr axis channel_axis(channel c) noexcept { return static_cast<axis>(static_cast<int>(c) % 3); }
constexpr std::string_view channel_name(channel c) noexcept
{
    constexpr std::string_view names[] = {"Xposition", "Yposition", "Zposition",
                                          "Xrotation", "Yrotation", "Zrotation"};
    return names[static_cast<int>(c)];
}
constexpr char axis_name(axis a) noexcept { return "xyz"[static_cast<int>(a)]; }

/// @brief One joint of a skeleton.
struct joint {
    std::string name;
    int parent = -1;  ///< index of the parent joint, -1 for a root
    vec3 offset{};    ///< rest offset from the parent (BVH OFFSET), in the file's units
    /// Channels in file order: 3 rotations, or 3 positions + 3 rotations (any order, any interleaving).
    std::vector<channel> channels{channel::zrotation, channel::xrotation, channel::yrotation};
    std::optional<vec3> end_site;  ///< BVH End Site offset of a leaf, if any
    vec3 lower_limit{-180, -180, -180};  ///< joint-angle limits in degrees, per axis x, y, z
    vec3 upper_limit{180, 180, 180};

    /// True when axis `a` (0 x, 1 y, 2 z) is limited: its limits span less than the whole circle (a BVH joint's
    /// -180..180, or anything wider, is not).
    bool limited(std::size_t a) const noexcept { return upper_limit[a] - lower_limit[a] < 360.0; }

    /// True when the joint has position channels (6-channel BVH joint).
    bool has_position() const noexcept
    {
        for (auto c : channels)
            if (!is_rotation(c)) return true;
        return false;
    }
    /// Rotation axes in application order (outermost first), e.g. {z, x, y} for ZXY.
    std::array<axis, 3> rotation_order() const noexcept
    {
        // the listed rotation axes first (each once), then the missing ones in the default order z, x, y: a joint
        // with fewer than three rotation channels (built in code; the BVH reader asks for three) never applies an
        // axis twice
        std::array<axis, 3> r{axis::z, axis::x, axis::y};
        std::array<bool, 3> used{};
        std::size_t k = 0;
        const auto take = [&](axis a) {
            if (k < 3 && !used[static_cast<std::size_t>(a)]) used[static_cast<std::size_t>(a)] = true, r[k++] = a;
        };
        for (auto c : channels)
            if (is_rotation(c)) take(channel_axis(c));
        for (axis a : {axis::z, axis::x, axis::y}) take(a);
        return r;
    }
};

/// @brief A joint hierarchy; parents always come before their children.
struct skeleton {
    std::string name;
    std::vector<joint> joints;

    std::size_t size() const noexcept { return joints.size(); }
    /// @brief True when some joint has a limit other than -180..180 (a skeleton read from BVH has none: the format
    /// holds no limits).
    bool has_limits() const noexcept
    {
        for (const auto& j : joints)
            for (std::size_t a = 0; a < 3; ++a)
                if (j.lower_limit[a] != -180.0 || j.upper_limit[a] != 180.0) return true;
        return false;
    }
    /// @brief Index of a joint by name.
    /// @throws value_error when no joint has that name.
    std::size_t index_of(std::string_view n) const
    {
        for (std::size_t i = 0; i < joints.size(); ++i)
            if (joints[i].name == n) return i;
        throw value_error("skeleton: no joint named '" + std::string(n) + "' in " +
                          (name.empty() ? std::string("skeleton") : name));
    }
    /// @brief True when both skeletons have the same joints (names and parents) in the same order.
    bool same_topology(const skeleton& o) const noexcept
    {
        if (o.joints.size() != joints.size()) return false;
        for (std::size_t i = 0; i < joints.size(); ++i)
            if (o.joints[i].name != joints[i].name || o.joints[i].parent != joints[i].parent) return false;
        return true;
    }
    /// @brief Checks that parents precede children and indices are valid.
    /// @throws format_error naming the offending joint.
    /// @param what what the skeleton was read from (a file name), put first in the message
    void validate(std::string_view what = "skeleton") const
    {
        // the message is built only on an error: a valid skeleton is checked without allocating
        const auto who = [&] {
            return std::string(what) + (name.empty() || what == name ? std::string() : " (skeleton '" + name + "')");
        };
        if (joints.empty()) throw format_error(who() + ": skeleton has no joints");
        for (std::size_t i = 0; i < joints.size(); ++i) {
            const int p = joints[i].parent;
            if (p >= static_cast<int>(i) || p < -1)
                throw format_error(who() + ": joint '" + joints[i].name + "' has parent index " + std::to_string(p) +
                                   ", expected -1 or below " + std::to_string(i));
        }
    }
};

/// Rotation about one axis by `deg` degrees.
inline mat3 axis_rotation(axis a, double deg) noexcept
{
    const double r = deg * std::numbers::pi / 180.0, c = std::cos(r), s = std::sin(r);
    switch (a) {
    case axis::x: return {1, 0, 0, 0, c, -s, 0, s, c};
    case axis::y: return {c, 0, s, 0, 1, 0, -s, 0, c};
    default: return {c, -s, 0, s, c, 0, 0, 0, 1};
    }
}

inline mat3 matmul(const mat3& a, const mat3& b) noexcept
{
    mat3 r{};
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            r[i * 3 + j] = a[i * 3] * b[j] + a[i * 3 + 1] * b[3 + j] + a[i * 3 + 2] * b[6 + j];
    return r;
}

inline vec3 matvec(const mat3& a, const vec3& v) noexcept
{
    return {a[0] * v[0] + a[1] * v[1] + a[2] * v[2], a[3] * v[0] + a[4] * v[1] + a[5] * v[2],
            a[6] * v[0] + a[7] * v[1] + a[8] * v[2]};
}

/// @brief Local rotation of a joint from its angles (degrees, indexed x, y, z), in its channel order.
inline mat3 local_rotation(const joint& j, const double* xyz_deg) noexcept
{
    mat3 r{1, 0, 0, 0, 1, 0, 0, 0, 1};
    for (axis a : j.rotation_order()) r = matmul(r, axis_rotation(a, xyz_deg[static_cast<int>(a)]));
    return r;
}

/// @brief Global positions of one pose.
struct pose_positions {
    std::vector<vec3> joints;     ///< [J] joint origins
    std::vector<vec3> end_sites;  ///< [J] end-site positions (equal to the joint's origin when it has none)
    std::vector<mat3> rotations;  ///< [J] global rotation of each joint
};

/// @brief Forward kinematics of one pose.
/// @param angles [J, 3] joint angles in degrees (x, y, z per joint).
/// @param positions [J, 3] position-channel values for joints that have them, or nullptr to use offsets.
inline pose_positions forward_kinematics(const skeleton& s, const double* angles, const double* positions = nullptr)
{
    const std::size_t n = s.size();
    pose_positions out;
    out.joints.resize(n);
    out.end_sites.resize(n);
    out.rotations.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
        const joint& j = s.joints[i];
        vec3 t = j.offset;
        if (positions && j.has_position()) t = {positions[i * 3], positions[i * 3 + 1], positions[i * 3 + 2]};
        const mat3 local = local_rotation(j, angles + i * 3);
        if (j.parent < 0) {
            out.joints[i] = t;
            out.rotations[i] = local;
        } else {
            const auto p = static_cast<std::size_t>(j.parent);
            const vec3 d = matvec(out.rotations[p], t);
            out.joints[i] = {out.joints[p][0] + d[0], out.joints[p][1] + d[1], out.joints[p][2] + d[2]};
            out.rotations[i] = matmul(out.rotations[p], local);
        }
        out.end_sites[i] = out.joints[i];
        if (j.end_site) {
            const vec3 d = matvec(out.rotations[i], *j.end_site);
            out.end_sites[i] = {out.joints[i][0] + d[0], out.joints[i][1] + d[1], out.joints[i][2] + d[2]};
        }
    }
    return out;
}

}  // namespace handemo
