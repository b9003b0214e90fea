// Joint naming conventions for retargeting: each table says, by name only, which joint of a skeleton plays
// which anatomical role ("slot": hips, l.upperarm, r.index1 ...), written from the published joint lists of
// handemo's hand, the Bandai-Namco motion dataset, CMU/Xia and Mixamo, SMPL/SMPL-H/SMPL-X, the OpenXR hand
// (XR_HAND_JOINT_*_EXT and its short forms) and the Unreal Engine mannequin (UE4 and UE5). A skeleton's
// convention is detected from its joint names (the table that recognises the most slots); any other rig is
// described by a JSON map file (map_file.hpp) in the same slot names.
//
// Slots: torso `root` (a floor-level parent of the hips), `hips`, `spine` (lowest spine joint), `chest`
// (highest spine joint, parent of neck and clavicles), `neck`, `head`, `head_end`; per side (`l.` / `r.`)
// `clavicle`, `upperarm`, `forearm`, `hand` (the wrist joint), `thigh`, `shin`, `foot`, `toe`, `toe_end`,
// `palm`, and the fingers `thumb0` (trapezium), `thumb1` (carpometacarpal), `thumb2` (metacarpophalangeal),
// `thumb3` (interphalangeal), `thumb_tip`, and for index, middle, ring and pinky `<f>0` (metacarpal, at the
// carpometacarpal joint), `<f>1` (knuckle, MCP), `<f>2` (PIP), `<f>3` (DIP), `<f>_tip`. Tip and end slots
// only orient the bone before them; they are never moved.
#pragma once

#include <handemo/motion/skeleton.hpp>

#include <algorithm>
#include <cstddef>
#include <map>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace handemo::retarget {

/// @brief One naming convention: slot -> candidate joint names (normalised: lower case, namespace prefix
/// removed). For a slot with several candidates the first one the skeleton has wins (CMU's spine is
/// `LowerBack`, Mixamo's `Spine`).
struct convention {
    std::string name;
    /// names carry no side (one hand per skeleton: OpenXR, handemo's hand): a side prefix or suffix
    /// (`left_`, `r_`, `_l` ...) is read off the name, and names without one take the default side
    bool sideless = false;
    std::vector<std::pair<std::string, std::vector<std::string>>> slots;
};

/// The finger names of the slots, thumb first.
inline constexpr std::string_view slot_fingers[] = {"thumb", "index", "middle", "ring", "pinky"};

namespace detail {

inline std::string lower(std::string_view s)
{
    std::string r(s);
    for (char& c : r)
        if (c >= 'A' && c <= 'Z') c = static_cast<char>(c - 'A' + 'a');
    return r;
}

inline std::string replace_all(std::string s, std::string_view what, std::string_view with)
{
    for (std::size_t p = s.find(what); p != std::string::npos; p = s.find(what, p + with.size())) s.replace(p, what.size(), with);
    return s;
}

/// Adds a slot for both sides: `{s}` in the key becomes l / r, `{side}` in the names the convention's side word.
inline void sided(convention& c, std::string_view key, std::vector<std::string> names, std::string_view left, std::string_view right)
{
    for (int k = 0; k < 2; ++k) {
        std::vector<std::string> n;
        for (const auto& x : names) n.push_back(replace_all(x, "{side}", k == 0 ? left : right));
        c.slots.emplace_back(std::string(k == 0 ? "l." : "r.") + std::string(key), std::move(n));
    }
}

inline convention handemo_hand_convention()
{
    convention c{"handemo-hand", true, {}};
    c.slots = {{"forearm", {"forearm"}}, {"hand", {"wrist"}}, {"palm", {"palm"}}};
    const char* seg[] = {"metacarpal", "proximal", "intermediate", "distal"};
    for (std::size_t f = 0; f < 5; ++f)
        for (std::size_t k = 0; k < 4; ++k)
            c.slots.push_back({std::string(slot_fingers[f]) + std::to_string(k), {std::string(slot_fingers[f]) + "_" + seg[k]}});
    return c;
}

inline convention openxr_convention()
{
    // XR_HAND_JOINT_<NAME>_EXT with the prefix and suffix removed (normalise_name), the common short forms
    convention c{"openxr", true, {}};
    c.slots = {{"hand", {"wrist"}}, {"palm", {"palm"}},
               {"thumb1", {"thumb_metacarpal"}}, {"thumb2", {"thumb_proximal"}}, {"thumb3", {"thumb_distal"}},
               {"thumb_tip", {"thumb_tip"}}};
    const char* fingers[] = {"index", "middle", "ring", "little"};
    const char* seg[] = {"metacarpal", "proximal", "intermediate", "distal", "tip"};
    for (std::size_t f = 0; f < 4; ++f)
        for (std::size_t k = 0; k < 5; ++k)
            c.slots.push_back({std::string(slot_fingers[f + 1]) + (k == 4 ? std::string("_tip") : std::to_string(k)),
                               {std::string(fingers[f]) + "_" + seg[k]}});
    return c;
}

inline convention bandai_convention()
{
    convention c{"bandai", false, {}};
    c.slots = {{"root", {"joint_root"}}, {"hips", {"hips"}}, {"spine", {"spine"}}, {"chest", {"chest"}},
               {"neck", {"neck"}}, {"head", {"head"}}};
    const std::pair<const char*, const char*> limbs[] = {{"clavicle", "shoulder_{side}"}, {"upperarm", "upperarm_{side}"},
                                                          {"forearm", "lowerarm_{side}"}, {"hand", "hand_{side}"},
                                                          {"thigh", "upperleg_{side}"},   {"shin", "lowerleg_{side}"},
                                                          {"foot", "foot_{side}"},        {"toe", "toes_{side}"}};
    for (const auto& [k, n] : limbs) sided(c, k, {n}, "l", "r");
    return c;
}

inline convention cmu_mixamo_convention()
{
    // CMU (and Xia, retargeted to it) and Mixamo share their limb names; the spine differs (CMU LowerBack,
    // Spine, Spine1; Mixamo Spine, Spine1, Spine2)
    convention c{"cmu/mixamo", false, {}};
    c.slots = {{"hips", {"hips"}}, {"spine", {"lowerback", "spine"}}, {"chest", {"spine2", "spine1"}},
               {"neck", {"neck"}}, {"head", {"head"}}, {"head_end", {"headtop_end"}}};
    const std::pair<const char*, const char*> limbs[] = {
        {"clavicle", "{side}shoulder"}, {"upperarm", "{side}arm"}, {"forearm", "{side}forearm"}, {"hand", "{side}hand"},
        {"thigh", "{side}upleg"},       {"shin", "{side}leg"},     {"foot", "{side}foot"},       {"toe", "{side}toebase"},
        {"toe_end", "{side}toe_end"}};
    for (const auto& [k, n] : limbs) sided(c, k, {n}, "left", "right");
    const char* fingers[] = {"thumb", "index", "middle", "ring", "pinky"};
    for (std::size_t f = 0; f < 5; ++f) {
        // Mixamo: Thumb1 carpometacarpal .. Thumb4 tip; Index1 knuckle .. Index4 tip
        const std::string base = std::string("{side}hand") + fingers[f];
        for (int k = 1; k <= 3; ++k) sided(c, std::string(slot_fingers[f]) + std::to_string(k), {base + std::to_string(k)}, "left", "right");
        sided(c, std::string(slot_fingers[f]) + "_tip", {base + "4"}, "left", "right");
    }
    return c;
}

inline convention smpl_convention()
{
    // SMPL / SMPL-H / SMPL-X joint names (left_shoulder is the upper arm's joint, left_collar the clavicle)
    convention c{"smpl", false, {}};
    c.slots = {{"root", {"root"}}, {"hips", {"pelvis"}}, {"spine", {"spine1"}}, {"chest", {"spine3", "spine2"}},
               {"neck", {"neck"}}, {"head", {"head"}}};
    const std::pair<const char*, const char*> limbs[] = {
        {"clavicle", "{side}_collar"}, {"upperarm", "{side}_shoulder"}, {"forearm", "{side}_elbow"}, {"hand", "{side}_wrist"},
        {"thigh", "{side}_hip"},       {"shin", "{side}_knee"},         {"foot", "{side}_ankle"},    {"toe", "{side}_foot"}};
    for (const auto& [k, n] : limbs) sided(c, k, {n}, "left", "right");
    for (std::size_t f = 0; f < 5; ++f) {
        const std::string base = std::string("{side}_") + std::string(slot_fingers[f]);
        for (int k = 1; k <= 3; ++k) sided(c, std::string(slot_fingers[f]) + std::to_string(k), {base + std::to_string(k)}, "left", "right");
        sided(c, std::string(slot_fingers[f]) + "_tip", {base}, "left", "right");  // SMPL-X's extra fingertip joints
    }
    return c;
}

inline convention unreal_convention()
{
    // Unreal Engine mannequin (UE4: spine_01..03, neck_01; UE5 adds spine_04/05, neck_02 and metacarpals)
    convention c{"unreal", false, {}};
    c.slots = {{"root", {"root"}}, {"hips", {"pelvis"}}, {"spine", {"spine_01"}}, {"chest", {"spine_05", "spine_03"}},
               {"neck", {"neck_01"}}, {"head", {"head"}}};
    const std::pair<const char*, const char*> limbs[] = {
        {"clavicle", "clavicle_{side}"}, {"upperarm", "upperarm_{side}"}, {"forearm", "lowerarm_{side}"}, {"hand", "hand_{side}"},
        {"thigh", "thigh_{side}"},       {"shin", "calf_{side}"},         {"foot", "foot_{side}"},        {"toe", "ball_{side}"}};
    for (const auto& [k, n] : limbs) sided(c, k, {n}, "l", "r");
    for (std::size_t f = 0; f < 5; ++f) {
        const std::string fn(slot_fingers[f]);
        if (f > 0) sided(c, fn + "0", {fn + "_metacarpal_{side}"}, "l", "r");
        for (int k = 1; k <= 3; ++k) sided(c, fn + std::to_string(k), {fn + "_0" + std::to_string(k) + "_{side}"}, "l", "r");
    }
    return c;
}

}  // namespace detail

/// @brief The built-in conventions, in the order ties are broken.
inline const std::vector<convention>& conventions()
{
    static const std::vector<convention> all{detail::handemo_hand_convention(), detail::bandai_convention(),
                                             detail::cmu_mixamo_convention(),   detail::smpl_convention(),
                                             detail::openxr_convention(),       detail::unreal_convention()};
    return all;
}

/// @brief Every slot name a map file may use (both sides spelled out).
inline std::vector<std::string> all_slots()
{
    std::vector<std::string> r = {"root", "hips", "spine", "chest", "neck", "head", "head_end"};
    std::vector<std::string> sided = {"clavicle", "upperarm", "forearm", "hand", "thigh", "shin", "foot", "toe", "toe_end", "palm",
                                      "thumb0", "thumb1", "thumb2", "thumb3", "thumb_tip"};
    for (std::size_t f = 1; f < 5; ++f) {
        for (int k = 0; k < 4; ++k) sided.push_back(std::string(slot_fingers[f]) + std::to_string(k));
        sided.push_back(std::string(slot_fingers[f]) + "_tip");
    }
    for (const char* s : {"l.", "r."})
        for (const auto& x : sided) r.push_back(s + x);
    return r;
}

/// @brief A joint name normalised for matching: lower case, without a namespace prefix (`mixamorig:Hips`
/// -> `hips`) and without the OpenXR `XR_HAND_JOINT_` prefix and `_EXT` suffix.
inline std::string normalise_name(std::string_view name)
{
    if (const auto p = name.rfind(':'); p != std::string_view::npos) name.remove_prefix(p + 1);
    std::string s = detail::replace_all(detail::lower(name), "xr_hand_joint_", "");
    if (s.size() > 4 && s.compare(s.size() - 4, 4, "_ext") == 0) s.erase(s.size() - 4);
    return s;
}

/// Side of a slot: 'l', 'r' or 0 for the torso.
inline char slot_side(std::string_view key) noexcept { return key.size() > 2 && key[1] == '.' ? key[0] : 0; }
/// The slot without its side (`r.index1` -> `index1`).
inline std::string_view slot_base(std::string_view key) noexcept { return slot_side(key) ? key.substr(2) : key; }

/// @brief Which joint of a skeleton fills each slot.
struct binding {
    std::string convention;                  ///< detected convention, or the map file it came from
    std::map<std::string, std::size_t> slots;  ///< slot -> joint index

    bool has(const std::string& key) const { return slots.count(key) != 0; }
    std::size_t at(const std::string& key) const { return slots.at(key); }
};

namespace detail {

/// Splits a side prefix or suffix off a normalised name: ("left_wrist") -> ('l', "wrist"); 0 when there is none.
inline std::pair<char, std::string> split_side(const std::string& n)
{
    struct affix {
        std::string_view text;
        char side;
        bool prefix;
    };
    static constexpr affix affixes[] = {{"left_", 'l', true},  {"right_", 'r', true}, {"l_", 'l', true},    {"r_", 'r', true},
                                        {"_left", 'l', false}, {"_right", 'r', false}, {"_l", 'l', false}, {"_r", 'r', false},
                                        {"left", 'l', true},   {"right", 'r', true}};
    for (const auto& a : affixes) {
        if (n.size() <= a.text.size()) continue;
        if (a.prefix && n.compare(0, a.text.size(), a.text) == 0) return {a.side, n.substr(a.text.size())};
        if (!a.prefix && n.compare(n.size() - a.text.size(), a.text.size(), a.text) == 0)
            return {a.side, n.substr(0, n.size() - a.text.size())};
    }
    return {0, n};
}

}  // namespace detail

/// @brief The binding of a skeleton under one convention. `default_side` ('l' or 'r') is the side of a
/// sideless convention's names that carry none.
inline binding bind(const skeleton& s, const convention& c, char default_side = 'r')
{
    // normalised name (with its side for a sideless convention) -> joint, first occurrence
    std::map<std::string, std::size_t> by_name;
    for (std::size_t j = 0; j < s.size(); ++j) {
        std::string n = normalise_name(s.joints[j].name);
        if (c.sideless) {
            auto [side, base] = detail::split_side(n);
            n = std::string(1, side ? side : default_side) + "." + base;
        }
        by_name.emplace(std::move(n), j);
    }
    binding b{c.name, {}};
    for (const auto& [key, names] : c.slots) {
        for (const char side : c.sideless ? std::string("lr") : std::string(1, '\0')) {
            const std::string full = c.sideless ? std::string(1, side) + "." + key : key;
            for (const auto& name : names) {
                const auto it = by_name.find(c.sideless ? std::string(1, side) + "." + name : name);
                if (it != by_name.end()) {
                    b.slots.emplace(full, it->second);
                    break;
                }
            }
        }
    }
    return b;
}

/// @brief The convention that recognises the most slots of `s` (ties: the order of conventions()).
/// The binding is empty when no convention recognises any joint.
inline binding detect(const skeleton& s, char default_side = 'r')
{
    binding best;
    for (const auto& c : conventions()) {
        auto b = bind(s, c, default_side);
        if (b.slots.size() > best.slots.size()) best = std::move(b);
    }
    return best;
}

}  // namespace handemo::retarget
