// handemo's 22-joint body, the body counterpart of hand.hpp: a floor root, hips, spine, chest, neck, head and
// per side clavicle, upper arm, forearm, hand, thigh, shin, foot and toes, in a T pose (cm, +Y up, facing +Z,
// the body's left on +X). Its joint names are those of the Bandai-Namco motion dataset's skeleton, so a model
// trained on that data accepts it; its proportions are a 50th-percentile adult of about 175 cm (segment
// lengths as fractions of stature after Drillis & Contini 1966, "Body segment parameters", and Winter,
// "Biomechanics and Motor Control of Human Movement", Fig. 4.1). It is the target of `handemo retarget --to body`.
#pragma once

#include <handemo/core/error.hpp>
#include <handemo/motion/skeleton.hpp>

#include <cmath>
#include <string>

namespace handemo {

/// @brief Builds the 22-joint T-pose body.
/// @param height_cm stature in cm.
/// @throws value_error when the height is not a positive finite number.
inline skeleton body_skeleton(double height_cm = 175.0)
{
    if (!(height_cm > 0) || !std::isfinite(height_cm))
        throw value_error("body_skeleton: height " + std::to_string(height_cm) + " cm is not positive");
    const double H = height_cm;
    skeleton s;
    s.name = "body";
    auto add = [&](const std::string& name, int parent, vec3 offset_fraction) {
        joint j;
        j.name = name;
        j.parent = parent;
        j.offset = {offset_fraction[0] * H, offset_fraction[1] * H, offset_fraction[2] * H};
        s.joints.push_back(std::move(j));
        return static_cast<int>(s.joints.size() - 1);
    };
    const int root = add("joint_Root", -1, {0, 0, 0});
    s.joints[0].channels = {channel::xposition, channel::yposition, channel::zposition, channel::zrotation, channel::xrotation, channel::yrotation};
    const int hips = add("Hips", root, {0, 0.530, 0});          // greater trochanter height
    s.joints[static_cast<std::size_t>(hips)].channels = s.joints[0].channels;
    const int spine = add("Spine", hips, {0, 0.060, 0});
    const int chest = add("Chest", spine, {0, 0.130, 0});
    const int neck = add("Neck", chest, {0, 0.100, 0});         // shoulder height 0.818
    const int head = add("Head", neck, {0, 0.052, 0});
    s.joints[static_cast<std::size_t>(head)].end_site = vec3{0, 0.13 * H, 0};
    for (const double side : {1.0, -1.0}) {
        const std::string suf = side > 0 ? "_L" : "_R";
        const int cl = add("Shoulder" + suf, chest, {side * 0.020, 0.080, 0});
        const int ua = add("UpperArm" + suf, cl, {side * 0.110, 0.005, 0});   // shoulder width 0.259
        const int la = add("LowerArm" + suf, ua, {side * 0.186, 0, 0});       // upper arm
        const int hd = add("Hand" + suf, la, {side * 0.146, 0, 0});           // forearm
        s.joints[static_cast<std::size_t>(hd)].end_site = vec3{side * 0.108 * H, 0, 0};  // hand
        const int th = add("UpperLeg" + suf, hips, {side * 0.055, -0.025, 0});
        const int sh = add("LowerLeg" + suf, th, {0, -0.245, 0});             // thigh
        const int ft = add("Foot" + suf, sh, {0, -0.246, 0});                 // shank
        const int to = add("Toes" + suf, ft, {0, -0.035, 0.110});
        s.joints[static_cast<std::size_t>(to)].end_site = vec3{0, 0, 0.045 * H};
        (void)sh;
        (void)to;
    }
    (void)neck;
    return s;
}

}  // namespace handemo
