// The paper's 23-joint right hand (Section 3.1, n = 23 in Eq. 1): forearm (root), wrist, palm and five
// fingers (thumb, index, middle, ring, pinky) x (metacarpal, proximal, intermediate, distal), with rest
// offsets in cm scaled from a hand length, End Sites at the five finger tips, and per-joint angle limits.
// Frame: +Y runs from the wrist along the middle finger, the palm faces +Z, the thumb is on +X. Angles:
// x = flexion (+, toward the palm) / extension (-), z = abduction / adduction (in-plane spread; + turns
// +Y toward -X, i.e. toward the little finger), y = axial twist. Channels: root `Xposition Yposition
// Zposition Zrotation Xrotation Yrotation`, others `Zrotation Xrotation Yrotation` (Blender, three.js).
//
// Segment lengths are fractions of hand length (wrist crease to middle finger tip) from Buchholz,
// Armstrong, Goldstein 1992, "Anthropometric data for describing the kinematics of the human hand",
// Ergonomics 35(3):261-273, Table 2. The thumb has no intermediate phalanx; as in the Leap Motion and
// Senso glove hand models its four joints are shifted one bone toward the carpus: thumb_metacarpal is the
// trapezium (scaphotrapezial, almost rigid), thumb_proximal the carpometacarpal joint (moves the first
// metacarpal), thumb_intermediate the MCP joint (moves the proximal phalanx) and thumb_distal the IP
// joint (moves the distal phalanx, End Site at the tip). Joint-angle limits follow Lee & Kunii 1995,
// "Model-based analysis of hand posture" (IEEE CG&A 15(5)) for the fingers and Hume et al. 1990,
// "Functional range of motion of the joints of the hand" (J. Hand Surg. 15A(2)) and Cobos et al. 2008,
// "Efficient human hand kinematics for manipulation tasks" (IROS) for the thumb and wrist.
#pragma once

#include <handemo/motion/skeleton.hpp>

#include <array>
#include <cmath>
#include <cstddef>
#include <string>
#include <string_view>

namespace handemo {

/// Number of joints of the hand model (Eq. 1: n = 23).
inline constexpr std::size_t hand_joint_count = 23;
/// Number of fingers and the joints per finger.
inline constexpr std::size_t hand_finger_count = 5;
inline constexpr std::size_t hand_joints_per_finger = 4;

/// Finger names in skeleton order.
inline constexpr std::array<std::string_view, 5> hand_finger_names{"thumb", "index", "middle", "ring", "pinky"};
/// Per-finger joint (segment) names in skeleton order.
inline constexpr std::array<std::string_view, 4> hand_segment_names{"metacarpal", "proximal", "intermediate",
                                                                    "distal"};

/// Joint indices of the hand skeleton that do not depend on a name lookup.
namespace hand_index {
inline constexpr std::size_t forearm = 0, wrist = 1, palm = 2;
/// @brief Index of joint `segment` (0 metacarpal .. 3 distal) of finger `finger` (0 thumb .. 4 pinky).
constexpr std::size_t finger_joint(std::size_t finger, std::size_t segment) noexcept
{
    return 3 + finger * hand_joints_per_finger + segment;
}
}  // namespace hand_index

namespace detail {

/// Per-finger geometry as fractions of hand length (Buchholz et al. 1992, Table 2).
struct finger_geometry {
    vec3 base;                      ///< position of the metacarpal joint relative to the palm joint
    vec3 direction;                 ///< direction of the finger at rest (normalised below)
    std::array<double, 4> lengths;  ///< segment lengths from the metacarpal joint outward (last: to tip)
};

inline constexpr std::array<finger_geometry, 5> hand_geometry{{
    // thumb: trapezium, first metacarpal 0.251, proximal phalanx 0.196, distal phalanx 0.158
    {{0.085, 0.02, 0.03}, {0.60, 1.0, 0.40}, {0.07, 0.251, 0.196, 0.158}},
    // index: metacarpal 0.374, proximal 0.265, middle 0.143, distal 0.097
    {{0.095, 0.04, 0.0}, {0.13, 1.0, 0.0}, {0.374, 0.265, 0.143, 0.097}},
    // middle: 0.373, 0.277, 0.170, 0.108
    {{0.030, 0.04, 0.0}, {0.03, 1.0, 0.0}, {0.373, 0.277, 0.170, 0.108}},
    // ring: 0.336, 0.259, 0.165, 0.107
    {{-0.035, 0.04, 0.0}, {-0.07, 1.0, 0.0}, {0.336, 0.259, 0.165, 0.107}},
    // pinky (little): 0.295, 0.206, 0.117, 0.093
    {{-0.095, 0.035, 0.0}, {-0.16, 1.0, 0.0}, {0.295, 0.206, 0.117, 0.093}},
}};

/// Angle limits in degrees, {lower x, y, z}, {upper x, y, z}.
struct limit_pair {
    vec3 lower, upper;
};

/// Limits for one finger joint. Fingers (Lee & Kunii 1995): CMC of index/middle almost rigid, ring/little
/// CMC flex 10-20 deg; MCP flexion 90, hyperextension 30, abduction +-20; PIP 0..110; DIP 0..90 (small
/// hyperextension allowed). Thumb (Hume 1990, Cobos 2008): CMC flex/ext -25..45, abd/add -45..15,
/// MCP -10..60, IP -15..80.
inline limit_pair finger_limits(std::size_t finger, std::size_t segment) noexcept
{
    if (finger == 0) {
        switch (segment) {
        case 0: return {{-10, -10, -10}, {10, 10, 10}};
        case 1: return {{-25, -20, -45}, {45, 20, 15}};
        case 2: return {{-10, -10, -10}, {60, 10, 10}};
        default: return {{-15, -5, -5}, {80, 5, 5}};
        }
    }
    switch (segment) {
    case 0: return finger >= 3 ? limit_pair{{-5, -5, -5}, {finger == 4 ? 20.0 : 10.0, 5, 5}}
                               : limit_pair{{-5, -5, -5}, {5, 5, 5}};
    case 1: return {{-30, -10, -20}, {90, 10, 20}};
    case 2: return {{-5, -5, -5}, {110, 5, 5}};
    default: return {{-10, -5, -5}, {90, 5, 5}};
    }
}

inline vec3 scaled(vec3 v, double s) noexcept { return {v[0] * s, v[1] * s, v[2] * s}; }

inline vec3 normalised(vec3 v) noexcept
{
    const double n = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    return {v[0] / n, v[1] / n, v[2] / n};
}

}  // namespace detail

/// @brief Builds the 23-joint right hand of the paper (Eq. 1, n = 23).
/// @param hand_length_cm wrist crease to middle finger tip, in cm (18.5: a 50th-percentile adult).
/// @return forearm (root, 6 channels, placed at the elbow), wrist, palm, then thumb..pinky x
///         metacarpal..distal; offsets in cm; End Sites on the five distal joints; limits in degrees.
/// @throws value_error when the hand length is not a positive finite number.
inline skeleton hand_skeleton(double hand_length_cm = 18.5)
{
    if (!(hand_length_cm > 0) || !std::isfinite(hand_length_cm))
        throw value_error("hand_skeleton: hand length " + std::to_string(hand_length_cm) + " cm is not positive");
    const double L = hand_length_cm;
    skeleton s;
    s.name = "hand";
    s.joints.reserve(hand_joint_count);

    joint forearm;
    forearm.name = "forearm";
    forearm.parent = -1;
    forearm.offset = {0, 0, 0};
    forearm.channels = {channel::xposition, channel::yposition, channel::zposition,
                        channel::zrotation, channel::xrotation, channel::yrotation};
    // Elbow/shoulder swing and pronation/supination (y, the forearm's long axis).
    forearm.lower_limit = {-90, -90, -90};
    forearm.upper_limit = {90, 90, 90};
    s.joints.push_back(forearm);

    joint wrist;
    wrist.name = "wrist";
    wrist.parent = static_cast<int>(hand_index::forearm);
    wrist.offset = {0, 1.4 * L, 0};  // forearm length ~1.4 hand lengths (elbow to wrist crease)
    // Wrist: flexion 80, extension 70, ulnar deviation 30 (+z), radial deviation 20 (-z).
    wrist.lower_limit = {-70, -10, -20};
    wrist.upper_limit = {80, 10, 30};
    s.joints.push_back(wrist);

    joint palm;
    palm.name = "palm";
    palm.parent = static_cast<int>(hand_index::wrist);
    palm.offset = {0, 0.02 * L, 0};  // carpal row
    palm.lower_limit = {-10, -10, -10};
    palm.upper_limit = {10, 10, 10};
    s.joints.push_back(palm);

    for (std::size_t f = 0; f < hand_finger_count; ++f) {
        const auto& g = detail::hand_geometry[f];
        const vec3 dir = detail::normalised(g.direction);
        for (std::size_t k = 0; k < hand_joints_per_finger; ++k) {
            joint j;
            j.name = std::string(hand_finger_names[f]) + "_" + std::string(hand_segment_names[k]);
            j.parent = static_cast<int>(k == 0 ? hand_index::palm : hand_index::finger_joint(f, k - 1));
            j.offset = k == 0 ? detail::scaled(g.base, L) : detail::scaled(dir, g.lengths[k - 1] * L);
            if (k == 3) j.end_site = detail::scaled(dir, g.lengths[3] * L);
            const auto lim = detail::finger_limits(f, k);
            j.lower_limit = lim.lower;
            j.upper_limit = lim.upper;
            s.joints.push_back(std::move(j));
        }
    }
    return s;
}

/// @brief True when `s` has the joint names and parents of hand_skeleton() (any hand length).
inline bool is_hand_skeleton(const skeleton& s)
{
    static const skeleton ref = hand_skeleton();
    return s.same_topology(ref);
}

/// @brief Gives `s` the joint limits of hand_skeleton() when it is handemo's hand (is_hand_skeleton(): its names
/// and parents) without limits of its own (every axis of every joint -180..180, as a BVH of the hand reads back:
/// the format carries no limits). Any other skeleton, or a hand with a limit of its own, is left as it is.
/// @return whether the limits were adopted
inline bool adopt_hand_limits(skeleton& s)
{
    if (!is_hand_skeleton(s) || s.has_limits()) return false;
    static const skeleton hand = hand_skeleton();
    for (std::size_t j = 0; j < s.joints.size(); ++j) {
        s.joints[j].lower_limit = hand.joints[j].lower_limit;
        s.joints[j].upper_limit = hand.joints[j].upper_limit;
    }
    return true;
}

}  // namespace handemo
