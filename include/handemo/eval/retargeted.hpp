// The evaluation's retargeted variant: every held-out input is also moved onto a foreign rig of the model's
// skeleton (CMU joint names, the rest pose of a real frame instead of the file's own, other proportions, metres,
// another channel order), transferred from there through the retargeting (stargan/capture.hpp) and scored back
// on the model's skeleton. Its keyframe RMSE beside the direct transfer's says what retargeting costs a user
// whose capture is not on the model's skeleton.
#pragma once

#include <handemo/motion/clip.hpp>
#include <handemo/retarget.hpp>

#include <map>
#include <optional>
#include <string>

namespace handemo::eval {

/// @brief A foreign rig of a body skeleton and the maps between the two.
struct foreign_rig {
    skeleton skel;
    retarget::retarget_map to_foreign, to_model;
};

/// @brief Builds the foreign rig of `model_skel` (a body a built-in convention recognises; nullopt otherwise):
/// CMU names (a joint of no slot keeps its name with an `x_` prefix), the rest pose of `pose` (a clip on
/// `model_skel`) at its first frame, arms 1.15x and legs 0.9x as long, metres, channels Z Y X.
inline std::optional<foreign_rig> make_foreign_rig(const skeleton& model_skel, const clip& pose)
{
    const auto b = retarget::detect(model_skel);
    if (!b.has("hips") || !b.has("l.thigh") || !b.has("r.thigh") || !b.has("l.upperarm") || !b.has("r.upperarm")) return std::nullopt;
    static const std::map<std::string, std::string> cmu = {
        {"hips", "Hips"},          {"spine", "LowerBack"},      {"chest", "Spine1"},          {"neck", "Neck"},          {"head", "Head"},
        {"l.clavicle", "LeftShoulder"}, {"l.upperarm", "LeftArm"}, {"l.forearm", "LeftForeArm"}, {"l.hand", "LeftHand"},
        {"l.thigh", "LeftUpLeg"},  {"l.shin", "LeftLeg"},       {"l.foot", "LeftFoot"},       {"l.toe", "LeftToeBase"},
        {"r.clavicle", "RightShoulder"}, {"r.upperarm", "RightArm"}, {"r.forearm", "RightForeArm"}, {"r.hand", "RightHand"},
        {"r.thigh", "RightUpLeg"}, {"r.shin", "RightLeg"},      {"r.foot", "RightFoot"},      {"r.toe", "RightToeBase"}};
    std::vector<std::string> slot_of(model_skel.size());
    for (const auto& [k, j] : b.slots) slot_of[j] = k;
    const auto p = forward_kinematics(model_skel, pose.frame_angles(0), pose.frame_positions(0));
    auto limb_scale = [&](std::size_t j) {
        const std::string base(retarget::slot_base(slot_of[j]));
        if (base == "upperarm" || base == "forearm" || base == "hand") return 1.15;
        if (base == "shin" || base == "foot" || base == "toe") return 0.9;
        return 1.0;
    };
    foreign_rig r;
    r.skel.name = "foreign rig of " + model_skel.name;
    const vec3 origin{p.joints[b.at("hips")][0], 0, p.joints[b.at("hips")][2]};
    for (std::size_t j = 0; j < model_skel.size(); ++j) {
        const auto& mj = model_skel.joints[j];
        joint fj;
        const auto it = cmu.find(slot_of[j]);
        fj.name = it != cmu.end() ? it->second : "x_" + mj.name;
        fj.parent = mj.parent;
        const double s = 0.01 * limb_scale(j);
        const vec3 from = mj.parent < 0 ? origin : p.joints[static_cast<std::size_t>(mj.parent)];
        fj.offset = retarget::scale(retarget::sub(p.joints[j], from), s);
        if (mj.end_site) fj.end_site = retarget::scale(retarget::sub(p.end_sites[j], p.joints[j]), s);
        fj.channels = {channel::zrotation, channel::yrotation, channel::xrotation};
        if (mj.parent < 0) fj.channels.insert(fj.channels.begin(), {channel::xposition, channel::yposition, channel::zposition});
        r.skel.joints.push_back(std::move(fj));
    }
    r.to_foreign = retarget::make_map(model_skel, r.skel);
    r.to_model = retarget::make_map(r.skel, model_skel);
    return r;
}

}  // namespace handemo::eval
