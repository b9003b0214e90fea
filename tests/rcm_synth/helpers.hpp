// Synthetic motions for the synthesis tests: a 21-joint humanoid (Bandai's joint names, y up, cm, standing
// rest pose) dancing with sinusoidal joint angles, and a hand from the synthetic hand dataset.
#pragma once

#include <handemo/motion.hpp>
#include <handemo/rcm.hpp>

#include <cmath>
#include <numbers>
#include <string>
#include <vector>

namespace handemo::test {

inline skeleton humanoid()
{
    skeleton s;
    s.name = "humanoid";
    auto add = [&](std::string name, int parent, vec3 off, bool pos = false) {
        joint j;
        j.name = std::move(name);
        j.parent = parent;
        j.offset = off;
        if (pos)
            j.channels = {channel::xposition, channel::yposition, channel::zposition,
                          channel::zrotation, channel::xrotation, channel::yrotation};
        s.joints.push_back(j);
        return static_cast<int>(s.joints.size() - 1);
    };
    const int hips = add("Hips", -1, {0, 95, 0}, true);
    const int spine = add("Spine", hips, {0, 12, 0});
    const int chest = add("Chest", spine, {0, 18, 0});
    const int neck = add("Neck", chest, {0, 20, 0});
    add("Head", neck, {0, 10, 0});
    for (int side = 0; side < 2; ++side) {
        const double sx = side == 0 ? 1 : -1;
        const std::string sf = side == 0 ? "_L" : "_R";
        const int sh = add("Shoulder" + sf, chest, {sx * 8, 16, 0});
        const int ua = add("UpperArm" + sf, sh, {sx * 10, 0, 0});
        const int la = add("LowerArm" + sf, ua, {sx * 28, 0, 0});
        add("Hand" + sf, la, {sx * 25, 0, 0});
    }
    for (int side = 0; side < 2; ++side) {
        const double sx = side == 0 ? 1 : -1;
        const std::string sf = side == 0 ? "_L" : "_R";
        const int ul = add("UpperLeg" + sf, hips, {sx * 9, -5, 0});
        const int ll = add("LowerLeg" + sf, ul, {0, -42, 0});
        const int ft = add("Foot" + sf, ll, {0, -40, 0});
        add("Toes" + sf, ft, {0, -6, 12});
    }
    return s;
}

/// A humanoid clip: arms swing, the spine bends, the knees bend while the pelvis dips, at `fps`.
inline clip humanoid_dance(std::size_t frames = 120, double fps = 30.0, double amplitude = 1.0)
{
    clip c = clip::make(humanoid(), frames, fps);
    const auto& s = c.skel;
    for (std::size_t f = 0; f < frames; ++f) {
        const double t = static_cast<double>(f) / fps, w = 2 * std::numbers::pi * 0.6;
        const double ph = std::sin(w * t), ph2 = std::sin(2 * w * t + 0.4);
        auto set = [&](const char* n, int axis, double deg) { c.angle(f, s.index_of(n), static_cast<std::size_t>(axis)) = amplitude * deg; };
        set("Spine", 0, 10 + 8 * ph);
        set("Chest", 0, 5 + 5 * ph2);
        set("Neck", 0, 5 * ph);
        set("Shoulder_L", 2, 10 * ph2);
        set("UpperArm_L", 2, -60 + 40 * ph);
        set("UpperArm_L", 1, 20 * ph2);
        set("LowerArm_L", 1, 30 + 25 * ph2);
        set("UpperArm_R", 2, 60 - 35 * ph2);
        set("UpperArm_R", 0, 15 * ph);
        set("LowerArm_R", 1, -30 - 20 * ph);
        const double knee = 20 + 15 * ph;  // knee flexion; hip and ankle compensate to keep the feet flat
        for (const char* side : {"_L", "_R"}) {
            set((std::string("UpperLeg") + side).c_str(), 0, -knee / 2);
            set((std::string("LowerLeg") + side).c_str(), 0, knee);
            set((std::string("Foot") + side).c_str(), 0, -knee / 2);
        }
        const double drop = (42 + 40) * (1 - std::cos(knee / 2 * std::numbers::pi / 180));
        const std::size_t h = s.index_of("Hips");
        c.position(f, h, 0) = 3 * ph2;
        c.position(f, h, 1) = 95 - drop;
        c.position(f, h, 2) = 20 * t;
    }
    return c;
}

/// Euclidean length of every bone (joint origin to parent origin) of every frame: [frames][J].
inline std::vector<std::vector<double>> bone_lengths(const clip& c)
{
    std::vector<std::vector<double>> out;
    for (std::size_t f = 0; f < c.frames; ++f) {
        const auto fk = forward_kinematics(c.skel, c.frame_angles(f), c.frame_positions(f));
        std::vector<double> l(c.skel.size(), 0.0);
        for (std::size_t j = 0; j < c.skel.size(); ++j) {
            const int p = c.skel.joints[j].parent;
            if (p < 0) continue;
            double d = 0;
            for (int a = 0; a < 3; ++a) d += std::pow(fk.joints[j][a] - fk.joints[static_cast<std::size_t>(p)][a], 2);
            l[j] = std::sqrt(d);
        }
        out.push_back(l);
    }
    return out;
}

}  // namespace handemo::test
