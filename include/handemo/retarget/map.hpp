// The correspondence between two skeletons that retargeting moves motion through: which source joint drives
// which target joint (from the slots of conventions.hpp or a map file), and for every pair the bone frame of
// each joint at its skeleton's rest pose (all angles zero). A bone frame is a rotation fixed to the joint:
// its first axis points along the bone (to the next joint of the chain, the End Site, or on from the parent),
// its second is a reference direction made orthogonal to it: across the knuckles (index to little finger) for
// the fingers, palm, wrist and forearm, along the hand (wrist to middle knuckle) for the thumb, across the
// hips or shoulders for the legs and spine, and the body's forward direction for clavicles and arms. Both are
// physical directions, so two skeletons whose rest poses differ (T or A pose, a flat or relaxed hand, bones
// along the local X axis as in Bandai's files) still agree on what a bone frame means: motion moves by these
// frames in world space (apply.hpp), never by copying Euler angles.
#pragma once

#include <handemo/core/error.hpp>
#include <handemo/motion/skeleton.hpp>
#include <handemo/retarget/conventions.hpp>
#include <handemo/retarget/rotation.hpp>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace handemo::retarget {

/// @brief What a retarget moves: a whole body (the root's world motion included), or one hand relative to
/// its forearm (a hand model's frame of reference is its forearm, or the wrist where the source has none).
enum class target_kind { body, hand };

/// @brief One driven joint: the source joint, the target joint, their slot and rest bone frames.
struct joint_pair {
    std::size_t source = 0, target = 0;
    std::string slot;  ///< the target's slot (for a mirrored hand, the source's slot has the other side)
    mat3 ls{}, lt{};   ///< bone frames at rest, in the joint's own frame (world frame at rest: angles zero)
};

/// @brief Options of make_map().
struct map_options {
    /// the source hand to move onto a hand target: 'l', 'r', or 0 (the only hand the source has; an error
    /// when it has two)
    char hand = 0;
    /// slots of the source from a map file (map_file.hpp); default: detected from the joint names
    std::optional<binding> source_slots;
    /// slots of the target; default: detected
    std::optional<binding> target_slots;
};

/// @brief A correspondence between a source and a target skeleton, ready to move motion (apply.hpp).
struct retarget_map {
    skeleton source, target;
    binding source_slots, target_slots;
    target_kind kind = target_kind::body;
    std::vector<joint_pair> pairs;  ///< in target joint order
    std::vector<int> pair_of_source, pair_of_target;  ///< joint -> index into pairs, or -1
    // hand targets: the frame of reference (the forearm, or the wrist), never moved
    std::size_t source_anchor = 0, target_anchor = 0;
    mat3 ls_anchor{}, lt_anchor{};
    char source_side = 0, target_side = 0;
    bool mirror = false;  ///< a left hand moved onto a right-hand target or the reverse
    // body targets: the root translation's joints and the proportions
    std::size_t source_hips = 0, target_hips = 0;
    double scale = 1;  ///< target bone length / source bone length over the driven bones (cm to m, proportions)

    /// Names of the source joints that drive nothing (carried through a write-back untouched).
    std::vector<std::string> unmapped_source() const
    {
        std::vector<std::string> r;
        for (std::size_t j = 0; j < source.size(); ++j)
            if (pair_of_source[j] < 0 && !(kind == target_kind::hand && j == source_anchor)) r.push_back(source.joints[j].name);
        return r;
    }
};

namespace detail {

inline bool is_hand_slot_base(std::string_view b)
{
    if (b == "hand" || b == "palm") return true;
    for (auto f : slot_fingers)
        if (b.substr(0, f.size()) == f) return true;
    return false;
}

inline bool is_tip(std::string_view b) { return b.size() >= 4 && (b.substr(b.size() - 4) == "_tip" || b.substr(b.size() - 4) == "_end"); }

/// The slots whose joint the bone of `key` points to, in order of preference.
inline std::vector<std::string> next_slots(const std::string& key)
{
    const char side = slot_side(key);
    const std::string b(slot_base(key)), s = side ? std::string(1, side) + "." : std::string();
    auto S = [&](std::initializer_list<const char*> l) {
        std::vector<std::string> r;
        for (const char* x : l) r.push_back(s + x);
        return r;
    };
    if (b == "root") return S({"hips", "spine", "chest", "neck"});
    if (b == "hips") return S({"spine", "chest", "neck"});
    if (b == "spine") return S({"chest", "neck", "head"});
    if (b == "chest") return S({"neck", "head"});
    if (b == "neck") return S({"head", "head_end"});
    if (b == "head") return S({"head_end"});
    if (b == "clavicle") return S({"upperarm"});
    if (b == "upperarm") return S({"forearm"});
    if (b == "forearm") return S({"hand"});
    if (b == "hand" || b == "palm") return S({"middle1"});
    if (b == "thigh") return S({"shin"});
    if (b == "shin") return S({"foot"});
    if (b == "foot") return S({"toe"});
    if (b == "toe") return S({"toe_end"});
    for (auto f : slot_fingers) {
        const std::string fn(f);
        if (b.size() == fn.size() + 1 && b.compare(0, fn.size(), fn) == 0) {
            const int k = b.back() - '0';
            if (k == 3) return {s + fn + "_tip"};
            if (fn == "thumb" && k == 0) return {s + "thumb1", s + "thumb2"};
            return {s + fn + std::to_string(k + 1)};
        }
    }
    return {};
}

/// One skeleton's rest geometry and slots, for building bone frames.
struct rest_view {
    const skeleton& sk;
    const binding& slots;
    pose_positions rest;
    double eps = 0;  ///< lengths below this are zero (1e-9 of the skeleton's extent)
    std::string what;  ///< "source skeleton 'walk.bvh'" for messages

    rest_view(const skeleton& s, const binding& b, std::string role) : sk(s), slots(b)
    {
        for (const auto& j : s.joints)
            for (std::size_t k = 0; k < 3; ++k)
                if (!std::isfinite(j.offset[k]) || (j.end_site && !std::isfinite((*j.end_site)[k])))
                    throw value_error("retarget: " + role + " skeleton '" + s.name + "': joint '" + j.name + "' has a non-finite offset");
        const std::vector<double> zero(s.size() * 3, 0.0);
        rest = forward_kinematics(s, zero.data());
        double ext = 0;  // the skeleton's extent: the farthest joint or End Site from the root
        for (std::size_t j = 0; j < s.size(); ++j)
            ext = std::max({ext, norm(sub(rest.joints[j], rest.joints.front())), norm(sub(rest.end_sites[j], rest.joints.front()))});
        eps = std::max(ext, 1e-300) * 1e-9;
        what = role + " skeleton '" + s.name + "'";
    }
    const vec3& pos(const std::string& key) const { return rest.joints[slots.at(key)]; }

    [[noreturn]] void fail(std::size_t j, const std::string& key, const std::string& msg) const
    {
        throw value_error("retarget: " + what + ": joint '" + sk.joints[j].name + "' (slot " + key + "): " + msg);
    }

    /// The bone direction of joint j (slot key) at rest.
    vec3 primary(std::size_t j, const std::string& key) const
    {
        for (const auto& n : next_slots(key)) {
            if (!slots.has(n)) continue;
            const vec3 d = sub(pos(n), rest.joints[j]);
            if (norm(d) > eps) return d;
        }
        if (sk.joints[j].end_site) {
            const vec3 d = sub(rest.end_sites[j], rest.joints[j]);
            if (norm(d) > eps) return d;
        }
        if (const int p = sk.joints[j].parent; p >= 0) {
            const vec3 d = sub(rest.joints[j], rest.joints[static_cast<std::size_t>(p)]);
            if (norm(d) > eps) return d;
        }
        fail(j, key, "zero-length bone: the next joint of its chain, its End Site and its parent all lie at its own position, so "
                     "its direction is undefined (refused rather than divided by zero)");
    }

    vec3 difference(const std::string& a, const std::string& b, std::size_t j, const std::string& key, const char* what_dir) const
    {
        if (!slots.has(a) || !slots.has(b))
            fail(j, key, std::string("needs slots ") + a + " and " + b + " for its " + what_dir + " direction");
        const vec3 d = sub(pos(a), pos(b));
        if (norm(d) <= eps)
            fail(j, key, std::string("degenerate rest pose: ") + a + " and " + b + " coincide, so the " + what_dir + " direction is undefined");
        return d;
    }

    /// The reference direction of joint j's bone frame (see the header comment).
    vec3 secondary(std::size_t j, const std::string& key, bool hand_rules) const
    {
        const char side = slot_side(key);
        const std::string b(slot_base(key)), s = side ? std::string(1, side) + "." : std::string();
        if (hand_rules) {
            if (b.rfind("thumb", 0) == 0) return difference(s + "middle1", s + "hand", j, key, "along-the-hand");
            return difference(s + "index1", slots.has(s + "pinky1") ? s + "pinky1" : s + "ring1", j, key, "across-the-knuckles");
        }
        if (b == "root" || b == "hips" || b == "thigh" || b == "shin" || b == "foot" || b == "toe")
            return difference("l.thigh", "r.thigh", j, key, "across-the-hips");
        const std::string la = slots.has("l.upperarm") ? "l.upperarm" : "l.clavicle", ra = slots.has("r.upperarm") ? "r.upperarm" : "r.clavicle";
        const vec3 lat = difference(la, ra, j, key, "across-the-shoulders");
        if (b == "spine" || b == "chest" || b == "neck" || b == "head") return lat;
        const std::string top = slots.has("neck") ? "neck" : slots.has("head") ? "head" : "chest";
        const vec3 up = difference(top, "hips", j, key, "up");
        return cross(lat, up);  // forward
    }

    /// The bone frame of joint j at rest (its world frame: every rest rotation is the identity).
    mat3 frame(std::size_t j, const std::string& key, bool hand_rules) const
    {
        mat3 f{};
        if (!frame_from(primary(j, key), secondary(j, key, hand_rules), f))
            fail(j, key, "degenerate rest pose: the bone is parallel to its reference direction, so its twist is undefined");
        return f;
    }
};

inline std::string tried_conventions()
{
    std::string s;
    for (const auto& c : conventions()) s += (s.empty() ? "" : ", ") + c.name;
    return s;
}

/// Sides with a usable hand: a wrist and the index, middle and little (or ring) knuckles.
inline std::string hands_of(const binding& b)
{
    std::string r;
    for (char s : {'l', 'r'}) {
        const std::string p = std::string(1, s) + ".";
        if (b.has(p + "hand") && b.has(p + "index1") && b.has(p + "middle1") && (b.has(p + "pinky1") || b.has(p + "ring1"))) r += s;
    }
    return r;
}

inline bool has_body(const binding& b)
{
    return b.has("hips") && b.has("l.thigh") && b.has("r.thigh") && (b.has("l.upperarm") || b.has("l.clavicle")) &&
           (b.has("r.upperarm") || b.has("r.clavicle")) && (b.has("neck") || b.has("head") || b.has("chest"));
}

inline std::string side_word(char s) { return s == 'l' ? "left" : "right"; }

inline std::string hand_joint_names(const skeleton& sk, const binding& b, char s)
{
    const std::string p = std::string(1, s) + ".";
    return "'" + sk.joints[b.at(p + "hand")].name + "' with '" + sk.joints[b.at(p + "index1")].name + "'...";
}

/// true when `a` is a proper ancestor of `d`.
inline bool is_ancestor(const skeleton& s, std::size_t a, std::size_t d)
{
    for (int p = s.joints[d].parent; p >= 0; p = s.joints[static_cast<std::size_t>(p)].parent)
        if (static_cast<std::size_t>(p) == a) return true;
    return false;
}

}  // namespace detail

/// @brief Builds the correspondence of `source` onto `target`.
/// A target with a hand but no body (handemo's hand model, an OpenXR hand) takes one hand of the source,
/// relative to its forearm; a target with a body takes the whole body. Joints the target has and the source
/// lacks stay at rest; joints the source has and the target lacks drive nothing.
/// @throws value_error naming the skeleton, the conventions tried and the joints looked for when no hand
/// or body is recognised; naming the hands found when a body has two and `hand` is 0; naming the joint for a
/// zero-length bone or a degenerate rest pose; naming both slots when the map turns a chain around.
inline retarget_map make_map(const skeleton& source, const skeleton& target, const map_options& o = {})
{
    using namespace detail;
    source.validate("retarget: source");
    target.validate("retarget: target");
    if (o.hand != 0 && o.hand != 'l' && o.hand != 'r') throw value_error("retarget: hand must be 'l' or 'r'");
    retarget_map m;
    m.source = source;
    m.target = target;
    m.target_slots = o.target_slots ? *o.target_slots : detect(target, 'r');
    const std::string looked_hand =
        "looked for a wrist with the index, middle and little-finger knuckles (e.g. RightHand + RightHandIndex1 (Mixamo), "
        "right_wrist + right_index1 (SMPL-X), wrist + index_proximal (OpenXR, handemo), hand_r + index_01_r (Unreal))";
    const std::string looked_body =
        "looked for hips, both thighs, both upper arms and a neck (e.g. Hips, LeftUpLeg, LeftArm, Neck (CMU/Mixamo), pelvis, left_hip, "
        "left_shoulder (SMPL), Hips, UpperLeg_L, UpperArm_L (Bandai), pelvis, thigh_l, upperarm_l (Unreal))";
    const std::string target_hands = hands_of(m.target_slots);
    m.source_slots = o.source_slots ? *o.source_slots : detect(source, o.hand ? o.hand : 'r');
    // a body target takes a body; a hand target, or a body target from a source that is only a hand, takes a hand
    const bool target_body = has_body(m.target_slots) && (target_hands.empty() || has_body(m.source_slots));
    if (!has_body(m.target_slots) && target_hands.empty())
        throw value_error("retarget: target skeleton '" + target.name + "': no hand or body recognised (tried conventions " + tried_conventions() +
                          "; " + looked_hand + "; " + looked_body + "): describe it with a map file");
    m.kind = target_body ? target_kind::body : target_kind::hand;
    const std::string best = m.source_slots.slots.empty() ? std::string("none matched a joint")
                                                          : "best match " + m.source_slots.convention + " with " +
                                                                std::to_string(m.source_slots.slots.size()) + " joints";
    if (m.kind == target_kind::hand) {
        const std::string hands = hands_of(m.source_slots);
        if (hands.empty())
            throw value_error("retarget: source skeleton '" + source.name + "': no hand recognised (tried conventions " + tried_conventions() +
                              "; " + best + "; " + looked_hand + "): describe it with a map file (--map)");
        if (o.hand) {
            if (hands.find(o.hand) == std::string::npos)
                throw value_error("retarget: source skeleton '" + source.name + "' has no " + side_word(o.hand) + " hand (found: " +
                                  side_word(hands[0]) + " hand " + hand_joint_names(source, m.source_slots, hands[0]) + ")");
            m.source_side = o.hand;
        } else if (hands.size() == 2) {
            throw value_error("retarget: source skeleton '" + source.name + "' has two hands, left (" +
                              hand_joint_names(source, m.source_slots, 'l') + ") and right (" + hand_joint_names(source, m.source_slots, 'r') +
                              "): pick one with --hand left or --hand right");
        } else {
            m.source_side = hands[0];
        }
        m.target_side = target_hands.find(m.source_side) != std::string::npos ? m.source_side : target_hands[0];
        m.mirror = m.source_side != m.target_side;
    } else if (!has_body(m.source_slots)) {
        throw value_error("retarget: source skeleton '" + source.name + "': no body recognised (tried conventions " + tried_conventions() + "; " +
                          best + "; " + looked_body + "): describe it with a map file (--map)");
    }

    const rest_view sv(source, m.source_slots, "source"), tv(target, m.target_slots, "target");
    const std::string sp = std::string(1, m.source_side) + ".", tp = std::string(1, m.target_side) + ".";
    const std::string hands_both = [&] {
        std::string r;
        for (char s : hands_of(m.source_slots))
            if (hands_of(m.target_slots).find(s) != std::string::npos) r += s;
        return r;
    }();

    // the driven pairs, in target order
    m.pair_of_source.assign(source.size(), -1);
    m.pair_of_target.assign(target.size(), -1);
    if (m.kind == target_kind::hand) {
        const std::string anchor = m.source_slots.has(sp + "forearm") && m.target_slots.has(tp + "forearm") ? "forearm" : "hand";
        m.source_anchor = m.source_slots.at(sp + anchor);
        m.target_anchor = m.target_slots.at(tp + anchor);
        m.ls_anchor = sv.frame(m.source_anchor, sp + anchor, true);
        m.lt_anchor = tv.frame(m.target_anchor, tp + anchor, true);
        for (const auto& [key, tj] : m.target_slots.slots) {
            if (slot_side(key) != m.target_side) continue;
            const std::string b(slot_base(key));
            if (!is_hand_slot_base(b) || is_tip(b) || b == anchor) continue;
            if (!m.source_slots.has(sp + b)) continue;
            const std::size_t sj = m.source_slots.at(sp + b);
            if (!is_ancestor(source, m.source_anchor, sj))
                throw value_error("retarget: source skeleton '" + source.name + "': joint '" + source.joints[sj].name + "' (slot " + sp + b +
                                  ") is not below the " + anchor + " '" + source.joints[m.source_anchor].name + "'");
            m.pairs.push_back({sj, tj, key, sv.frame(sj, sp + b, true), tv.frame(tj, key, true)});
        }
    } else {
        for (const auto& [key, tj] : m.target_slots.slots) {
            if (is_tip(slot_base(key)) || !m.source_slots.has(key)) continue;
            const char side = slot_side(key);
            const std::string b(slot_base(key));
            const bool fingers = side && hands_both.find(side) != std::string::npos;
            if (is_hand_slot_base(b) && b != "hand" && !fingers) continue;  // a finger needs the knuckles in both skeletons
            const std::size_t sj = m.source_slots.at(key);
            const bool hand_rules = is_hand_slot_base(b) && fingers;
            m.pairs.push_back({sj, tj, key, sv.frame(sj, key, hand_rules), tv.frame(tj, key, hand_rules)});
        }
        m.source_hips = m.source_slots.at("hips");
        m.target_hips = m.target_slots.at("hips");
    }
    std::sort(m.pairs.begin(), m.pairs.end(), [](const joint_pair& a, const joint_pair& b) { return a.target < b.target; });
    for (std::size_t p = 0; p < m.pairs.size(); ++p) {
        const auto& pr = m.pairs[p];
        if (m.pair_of_source[pr.source] >= 0)
            throw value_error("retarget: source joint '" + source.joints[pr.source].name + "' fills two slots, " +
                              m.pairs[static_cast<std::size_t>(m.pair_of_source[pr.source])].slot + " and " + pr.slot);
        m.pair_of_source[pr.source] = static_cast<int>(p);
        m.pair_of_target[pr.target] = static_cast<int>(p);
    }
    if (m.pairs.empty()) throw value_error("retarget: no joint of '" + source.name + "' corresponds to a joint of '" + target.name + "'");
    // a chain must run the same way in both skeletons: the nearest driven ancestor of a target joint must be
    // driven by an ancestor of its source joint (a map that crosses two chains would make a cycle)
    double ls = 0, lt = 0;
    for (const auto& pr : m.pairs) {
        int a = target.joints[pr.target].parent;
        while (a >= 0 && m.pair_of_target[static_cast<std::size_t>(a)] < 0) a = target.joints[static_cast<std::size_t>(a)].parent;
        if (a < 0) continue;
        const auto& up = m.pairs[static_cast<std::size_t>(m.pair_of_target[static_cast<std::size_t>(a)])];
        if (!is_ancestor(source, up.source, pr.source))
            throw value_error("retarget: slot " + pr.slot + " ('" + source.joints[pr.source].name + "') is below slot " + up.slot + " in the target '" +
                              target.name + "' but its source joint is not below '" + source.joints[up.source].name +
                              "' in '" + source.name + "': the correspondence would turn a chain around (a cycle)");
        ls += norm(sub(sv.rest.joints[pr.source], sv.rest.joints[up.source]));
        lt += norm(sub(tv.rest.joints[pr.target], tv.rest.joints[up.target]));
    }
    if (m.kind == target_kind::body) {
        if (!(ls > 0) || !(lt > 0))
            throw value_error("retarget: the driven bones of '" + source.name + "' or '" + target.name + "' have zero total length");
        m.scale = lt / ls;
    }
    return m;
}

}  // namespace handemo::retarget
