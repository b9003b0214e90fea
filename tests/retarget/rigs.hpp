// Test rigs for retargeting: one physical body with fingers (T pose, cm, +Y up, facing +Z, its left on +X),
// written in any naming convention with any rest pose, units, proportions and channel order, and smooth
// random motion for it.
#pragma once

#include <handemo/motion.hpp>
#include <handemo/retarget.hpp>

#include <cmath>
#include <functional>
#include <map>
#include <random>
#include <string>
#include <vector>

namespace handemo::test {

struct rig_joint {
    std::string slot, parent;  ///< slots of conventions.hpp, or x.<name> for joints no convention has
    vec3 pos;                  ///< world position at the physical T pose (cm)
};

/// The physical body: both sides, with fingers and a few joints of no slot (mid spine, jaw).
inline std::vector<rig_joint> physical_body()
{
    std::vector<rig_joint> r = {{"root", "", {0, 0, 0}},         {"hips", "root", {0, 95, 0}},     {"spine", "hips", {0, 105, 0}},
                                {"x.spine_mid", "spine", {0, 115, 1}}, {"chest", "x.spine_mid", {0, 127, 0}}, {"neck", "chest", {0, 146, 0}},
                                {"head", "neck", {0, 156, 2}},  {"x.jaw", "head", {0, 152, 8}},   {"head_end", "head", {0, 174, 2}}};
    struct L {
        const char* slot;
        const char* parent;
        vec3 pos;
    };
    const L left[] = {
        {"clavicle", "chest", {3, 143, 0}},   {"upperarm", "clavicle", {17, 143, -1}}, {"forearm", "upperarm", {45, 143, -1}},
        {"hand", "forearm", {70, 143, 0}},    {"palm", "hand", {73, 143, 0}},
        {"thumb0", "palm", {71.5, 142, 2}},   {"thumb1", "thumb0", {72.5, 141.5, 3}}, {"thumb2", "thumb1", {76, 141, 5.5}},
        {"thumb3", "thumb2", {79, 141, 7}},   {"thumb_tip", "thumb3", {81.5, 141, 8}},
        {"index0", "palm", {72, 143, 1.5}},   {"index1", "index0", {80, 143, 2.8}},   {"index2", "index1", {84.5, 143, 3.1}},
        {"index3", "index2", {87, 143, 3.2}}, {"index_tip", "index3", {89, 143, 3.3}},
        {"middle0", "palm", {72, 143, 0.5}},  {"middle1", "middle0", {80.5, 143, 0.9}}, {"middle2", "middle1", {85.5, 143, 0.9}},
        {"middle3", "middle2", {88.5, 143, 0.9}}, {"middle_tip", "middle3", {90.5, 143, 0.9}},
        {"ring0", "palm", {72, 143, -0.5}},   {"ring1", "ring0", {79.8, 143, -1.1}},  {"ring2", "ring1", {84.5, 143, -1.3}},
        {"ring3", "ring2", {87.3, 143, -1.4}}, {"ring_tip", "ring3", {89.3, 143, -1.5}},
        {"pinky0", "palm", {71.5, 143, -1.5}}, {"pinky1", "pinky0", {78.5, 143, -3.1}}, {"pinky2", "pinky1", {82, 143, -3.5}},
        {"pinky3", "pinky2", {84.2, 143, -3.7}}, {"pinky_tip", "pinky3", {86, 143, -3.9}},
        {"thigh", "hips", {9, 92, 0}},        {"shin", "thigh", {9.5, 50, 0.5}},      {"foot", "shin", {9.5, 8, -1}},
        {"toe", "foot", {10, 1, 12}},         {"toe_end", "toe", {10, 1, 18}}};
    for (const char side : {'l', 'r'}) {
        const std::string s = std::string(1, side) + ".";
        for (const auto& j : left) {
            const std::string parent = std::string(j.parent) == "chest" || std::string(j.parent) == "hips" ? j.parent : s + j.parent;
            r.push_back({s + j.slot, parent, {side == 'l' ? j.pos[0] : -j.pos[0], j.pos[1], j.pos[2]}});
        }
    }
    return r;
}

/// Names of a convention: slot (or x.<name>) -> joint name; slots not listed are absent from the rig.
using rig_names = std::map<std::string, std::string>;

inline void both_sides(rig_names& n, const std::string& slot, const std::string& l, const std::string& r)
{
    n["l." + slot] = l;
    n["r." + slot] = r;
}

inline rig_names mixamo_names(bool fingers = true, const std::string& prefix = "mixamorig:")
{
    rig_names n = {{"hips", "Hips"}, {"spine", "Spine"}, {"x.spine_mid", "Spine1"}, {"chest", "Spine2"}, {"neck", "Neck"}, {"head", "Head"},
                   {"head_end", "HeadTop_End"}};
    const std::pair<const char*, const char*> limbs[] = {{"clavicle", "Shoulder"}, {"upperarm", "Arm"}, {"forearm", "ForeArm"},
                                                         {"hand", "Hand"},         {"thigh", "UpLeg"},  {"shin", "Leg"},
                                                         {"foot", "Foot"},         {"toe", "ToeBase"},  {"toe_end", "Toe_End"}};
    for (const auto& [k, v] : limbs) both_sides(n, k, std::string("Left") + v, std::string("Right") + v);
    if (fingers) {
        const char* F[] = {"Thumb", "Index", "Middle", "Ring", "Pinky"};
        const char* f[] = {"thumb", "index", "middle", "ring", "pinky"};
        for (int i = 0; i < 5; ++i)
            for (int k = 1; k <= 4; ++k) {
                const std::string slot = std::string(f[i]) + (k == 4 ? std::string("_tip") : std::to_string(k));
                both_sides(n, slot, std::string("LeftHand") + F[i] + std::to_string(k), std::string("RightHand") + F[i] + std::to_string(k));
            }
    }
    for (auto& [k, v] : n) v = prefix + v;
    return n;
}

inline rig_names cmu_names()
{
    rig_names n = {{"hips", "Hips"}, {"spine", "LowerBack"}, {"x.spine_mid", "Spine"}, {"chest", "Spine1"}, {"neck", "Neck"}, {"head", "Head"}};
    const std::pair<const char*, const char*> limbs[] = {{"clavicle", "Shoulder"}, {"upperarm", "Arm"}, {"forearm", "ForeArm"}, {"hand", "Hand"},
                                                         {"thigh", "UpLeg"},       {"shin", "Leg"},     {"foot", "Foot"},       {"toe", "ToeBase"}};
    for (const auto& [k, v] : limbs) both_sides(n, k, std::string("Left") + v, std::string("Right") + v);
    return n;
}

inline rig_names smplx_names()
{
    rig_names n = {{"hips", "pelvis"}, {"spine", "spine1"}, {"x.spine_mid", "spine2"}, {"chest", "spine3"}, {"neck", "neck"}, {"head", "head"},
                   {"x.jaw", "jaw"}};
    const std::pair<const char*, const char*> limbs[] = {{"clavicle", "collar"}, {"upperarm", "shoulder"}, {"forearm", "elbow"}, {"hand", "wrist"},
                                                         {"thigh", "hip"},       {"shin", "knee"},         {"foot", "ankle"},    {"toe", "foot"}};
    for (const auto& [k, v] : limbs) both_sides(n, k, std::string("left_") + v, std::string("right_") + v);
    const char* f[] = {"thumb", "index", "middle", "ring", "pinky"};
    for (int i = 0; i < 5; ++i)
        for (int k = 1; k <= 3; ++k)
            both_sides(n, std::string(f[i]) + std::to_string(k), std::string("left_") + f[i] + std::to_string(k), std::string("right_") + f[i] + std::to_string(k));
    return n;
}

inline rig_names unreal_names()
{
    rig_names n = {{"root", "root"}, {"hips", "pelvis"}, {"spine", "spine_01"}, {"x.spine_mid", "spine_02"}, {"chest", "spine_03"},
                   {"neck", "neck_01"}, {"head", "head"}};
    const std::pair<const char*, const char*> limbs[] = {{"clavicle", "clavicle"}, {"upperarm", "upperarm"}, {"forearm", "lowerarm"}, {"hand", "hand"},
                                                         {"thigh", "thigh"},       {"shin", "calf"},         {"foot", "foot"},        {"toe", "ball"}};
    for (const auto& [k, v] : limbs) both_sides(n, k, std::string(v) + "_l", std::string(v) + "_r");
    const char* f[] = {"thumb", "index", "middle", "ring", "pinky"};
    for (int i = 0; i < 5; ++i) {
        if (i > 0) both_sides(n, std::string(f[i]) + "0", std::string(f[i]) + "_metacarpal_l", std::string(f[i]) + "_metacarpal_r");
        for (int k = 1; k <= 3; ++k)
            both_sides(n, std::string(f[i]) + std::to_string(k), std::string(f[i]) + "_0" + std::to_string(k) + "_l", std::string(f[i]) + "_0" + std::to_string(k) + "_r");
    }
    return n;
}

inline rig_names bandai_names()
{
    rig_names n = {{"root", "joint_Root"}, {"hips", "Hips"}, {"spine", "Spine"}, {"chest", "Chest"}, {"neck", "Neck"}, {"head", "Head"}};
    const std::pair<const char*, const char*> limbs[] = {{"clavicle", "Shoulder"}, {"upperarm", "UpperArm"}, {"forearm", "LowerArm"}, {"hand", "Hand"},
                                                         {"thigh", "UpperLeg"},    {"shin", "LowerLeg"},    {"foot", "Foot"},        {"toe", "Toes"}};
    for (const auto& [k, v] : limbs) both_sides(n, k, std::string(v) + "_L", std::string(v) + "_R");
    return n;
}

/// One hand of an OpenXR skeleton, XR_HAND_JOINT_*_EXT names (long) or short ones, with an optional side prefix.
inline rig_names openxr_names(char side, bool long_names, const std::string& side_prefix = "")
{
    rig_names n;
    const std::string s = std::string(1, side) + ".";
    auto name = [&](std::string v) {
        if (long_names) {
            for (auto& c : v) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
            return side_prefix + "XR_HAND_JOINT_" + v + "_EXT";
        }
        return side_prefix + v;
    };
    n[s + "forearm"] = side_prefix + "elbow_forearm";  // not an OpenXR joint: a root above the wrist, as exporters add
    n[s + "hand"] = name("wrist");
    n[s + "palm"] = name("palm");
    n[s + "thumb1"] = name("thumb_metacarpal");
    n[s + "thumb2"] = name("thumb_proximal");
    n[s + "thumb3"] = name("thumb_distal");
    n[s + "thumb_tip"] = name("thumb_tip");
    const char* f[] = {"index", "middle", "ring", "pinky"};
    const char* xr[] = {"index", "middle", "ring", "little"};
    const char* seg[] = {"metacarpal", "proximal", "intermediate", "distal", "tip"};
    for (int i = 0; i < 4; ++i)
        for (int k = 0; k < 5; ++k) n[s + f[i] + (k == 4 ? std::string("_tip") : std::to_string(k))] = name(std::string(xr[i]) + "_" + seg[k]);
    return n;
}

/// How a rig differs from the physical T pose.
struct rig_style {
    double units = 1;         ///< 0.01: metres
    double arm_scale = 1;     ///< proportions: arms and hands longer or shorter
    double a_pose_deg = 0;    ///< arms lowered by this angle about the forward axis (A pose)
    double finger_curl_deg = 0;  ///< fingers curled at rest (a relaxed hand)
    std::array<axis, 3> order{axis::z, axis::x, axis::y};  ///< rotation channel order of every joint
    bool end_sites = true;    ///< tip slots as End Sites (else tips are left out)
    std::string name = "rig";
};

/// Rotates p about the axis through c by deg degrees (Rodrigues).
inline vec3 rotate_about(const vec3& p, const vec3& c, const vec3& axis_dir, double deg)
{
    using namespace handemo::retarget;
    const vec3 k = scale(axis_dir, 1 / norm(axis_dir));
    const double t = deg * std::numbers::pi / 180, ct = std::cos(t), st = std::sin(t);
    const vec3 v = sub(p, c);
    const vec3 r = add(add(scale(v, ct), scale(cross(k, v), st)), scale(k, dot(k, v) * (1 - ct)));
    return add(c, r);
}

/// Builds a skeleton of the physical body (or the part of it that `names` lists) in a style.
inline skeleton make_rig(const rig_names& names, const rig_style& st)
{
    using namespace handemo::retarget;
    auto body = physical_body();
    std::map<std::string, std::size_t> idx;
    for (std::size_t i = 0; i < body.size(); ++i) idx[body[i].slot] = i;
    auto below = [&](std::size_t i, const std::string& ancestor) {
        for (std::string p = body[i].slot; !p.empty(); p = body[idx[p]].parent)
            if (p == ancestor) return true;
        return false;
    };
    // rest pose changes: A pose (about the forward axis +Z at the shoulder), curled fingers (about the knuckle line)
    for (const char side : {'l', 'r'}) {
        const std::string s = std::string(1, side) + ".";
        const double sgn = side == 'l' ? -1 : 1;
        if (st.a_pose_deg != 0) {
            const vec3 c = body[idx[s + "upperarm"]].pos;
            for (std::size_t i = 0; i < body.size(); ++i)
                if (below(i, s + "upperarm") && body[i].slot != s + "upperarm") body[i].pos = rotate_about(body[i].pos, c, {0, 0, 1}, sgn * st.a_pose_deg);
        }
        if (st.finger_curl_deg != 0) {
            for (const char* f : {"index", "middle", "ring", "pinky"}) {
                for (int k = 1; k <= 3; ++k) {
                    const std::string root = s + f + std::to_string(k);
                    const vec3 c = body[idx[root]].pos;
                    const vec3 ax = sub(body[idx[s + "index1"]].pos, body[idx[s + "pinky1"]].pos);
                    for (std::size_t i = 0; i < body.size(); ++i)
                        if (below(i, root) && body[i].slot != root) body[i].pos = rotate_about(body[i].pos, c, ax, (side == 'l' ? -1 : 1) * st.finger_curl_deg);
                }
            }
        }
        if (st.arm_scale != 1) {
            const vec3 c = body[idx[s + "upperarm"]].pos;
            for (std::size_t i = 0; i < body.size(); ++i)
                if (below(i, s + "upperarm")) body[i].pos = add(c, scale(sub(body[i].pos, c), st.arm_scale));
        }
    }
    skeleton sk;
    sk.name = st.name;
    std::map<std::string, int> made;  // slot -> joint index
    for (const auto& j : body) {
        const bool tip = j.slot.size() > 4 && (j.slot.substr(j.slot.size() - 4) == "_tip" || j.slot.substr(j.slot.size() - 4) == "_end");
        auto it = names.find(j.slot);
        // nearest ancestor present
        std::string p = j.parent;
        while (!p.empty() && !made.count(p)) p = body[idx[p]].parent;
        const vec3 ppos = p.empty() ? vec3{0, 0, 0} : body[idx[p]].pos;
        if (tip && st.end_sites && it == names.end()) {
            if (!p.empty()) {
                auto& pj = sk.joints[static_cast<std::size_t>(made[p])];
                if (!pj.end_site && j.parent == p) pj.end_site = scale(sub(j.pos, ppos), st.units);
            }
            continue;
        }
        if (it == names.end()) continue;
        joint jt;
        jt.name = it->second;
        jt.parent = p.empty() ? -1 : made[p];
        jt.offset = scale(sub(j.pos, ppos), st.units);
        std::vector<channel> ch;
        for (axis a : st.order) ch.push_back(static_cast<channel>(3 + static_cast<int>(a)));
        if (jt.parent < 0) ch.insert(ch.begin(), {channel::xposition, channel::yposition, channel::zposition});
        jt.channels = ch;
        made[j.slot] = static_cast<int>(sk.joints.size());
        sk.joints.push_back(std::move(jt));
    }
    // joints whose only child was dropped keep no End Site: leaves without one are fine in BVH for this module
    return sk;
}

/// Smooth random motion: every rotation channel a sum of two sines (up to `amp` degrees), the root also moving.
inline clip random_motion(const skeleton& s, std::size_t frames, unsigned seed, double amp = 30)
{
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(0, 1);
    clip c = clip::make(s, frames, 30);
    for (std::size_t j = 0; j < s.size(); ++j) {
        for (std::size_t a = 0; a < 3; ++a) {
            const double a1 = amp * (u(rng) - 0.5) * 2, a2 = amp * 0.4 * (u(rng) - 0.5) * 2, w1 = 0.05 + 0.2 * u(rng), w2 = 0.3 * u(rng),
                         p1 = 6.28 * u(rng), p2 = 6.28 * u(rng);
            for (std::size_t f = 0; f < frames; ++f)
                c.angle(f, j, a) = a1 * std::sin(w1 * static_cast<double>(f) + p1) + a2 * std::sin(w2 * static_cast<double>(f) + p2);
        }
        if (s.joints[j].has_position())
            for (std::size_t f = 0; f < frames; ++f)
                for (std::size_t a = 0; a < 3; ++a) c.position(f, j, a) = s.joints[j].offset[a] + 10 * std::sin(0.07 * static_cast<double>(f) + static_cast<double>(a));
    }
    return c;
}

}  // namespace handemo::test
