// Shared helpers of the render tests: small skeletons and clips built in code, an FNV-1a hash of pixels.
#pragma once

#include <handemo/motion/clip.hpp>
#include <handemo/motion/hand.hpp>

#include <cmath>
#include <cstdint>
#include <vector>

namespace handemo::test {

/// FNV-1a (64-bit) of a byte buffer.
inline std::uint64_t fnv1a(const std::vector<std::uint8_t>& bytes)
{
    std::uint64_t h = 14695981039346656037ull;
    for (auto b : bytes) {
        h ^= b;
        h *= 1099511628211ull;
    }
    return h;
}

/// A hand clip whose fingers flex (x, toward the palm) and open again, the wrist flexing a little.
inline clip flexing_hand(std::size_t frames = 40, double amplitude = 60)
{
    clip c = clip::make(hand_skeleton(), frames, 30);
    for (std::size_t f = 0; f < frames; ++f) {
        const double t = std::sin(static_cast<double>(f) / static_cast<double>(frames - 1) * 3.141592653589793);
        for (std::size_t finger = 0; finger < 5; ++finger)
            for (std::size_t seg = 1; seg < 4; ++seg)
                c.angle(f, hand_index::finger_joint(finger, seg), 0) = amplitude * t * (finger == 0 ? 0.5 : 1.0);
        c.angle(f, hand_index::wrist, 0) = 15 * t;
    }
    return c;
}

/// A 12-joint stick body, Y up, facing +Z: hips (root, 6 channels) with two legs and a spine up to a
/// chest with a neck/head and two arms. Arms swing over the clip; the root walks along +X.
inline clip stick_body(std::size_t frames = 30)
{
    skeleton s;
    s.name = "stick";
    auto add = [&](const char* name, int parent, vec3 off, bool six = false) {
        joint j;
        j.name = name;
        j.parent = parent;
        j.offset = off;
        if (six)
            j.channels = {channel::xposition, channel::yposition, channel::zposition,
                          channel::zrotation, channel::xrotation, channel::yrotation};
        s.joints.push_back(j);
        return static_cast<int>(s.joints.size() - 1);
    };
    const int hips = add("hips", -1, {0, 100, 0}, true);
    const int lk = add("left_knee", add("left_hip", hips, {10, 0, 0}), {0, -45, 0});
    s.joints[static_cast<std::size_t>(add("left_ankle", lk, {0, -45, 0}))].end_site = vec3{0, -5, 12};
    const int rk = add("right_knee", add("right_hip", hips, {-10, 0, 0}), {0, -45, 0});
    s.joints[static_cast<std::size_t>(add("right_ankle", rk, {0, -45, 0}))].end_site = vec3{0, -5, 12};
    const int chest = add("chest", add("spine", hips, {0, 20, 0}), {0, 25, 0});
    s.joints[static_cast<std::size_t>(add("head", chest, {0, 15, 0}))].end_site = vec3{0, 20, 0};
    s.joints[static_cast<std::size_t>(add("left_arm", chest, {18, 0, 0}))].end_site = vec3{0, -50, 0};
    s.joints[static_cast<std::size_t>(add("right_arm", chest, {-18, 0, 0}))].end_site = vec3{0, -50, 0};
    clip c = clip::make(s, frames, 30);
    for (std::size_t f = 0; f < frames; ++f) {
        const double t = static_cast<double>(f) / static_cast<double>(frames);
        c.position(f, 0, 0) = 200 * t;  // walks along +X
        c.angle(f, s.index_of("left_arm"), 0) = 40 * std::sin(6.283185307179586 * t);
        c.angle(f, s.index_of("right_arm"), 0) = -40 * std::sin(6.283185307179586 * t);
    }
    return c;
}

}  // namespace handemo::test
