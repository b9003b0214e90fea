#include <handemo/motion/bvh.hpp>
#include <handemo/motion/hand.hpp>
#include <handemo/motion/synth.hpp>

#include <doctest/doctest.h>

#include <cmath>

using namespace handemo;

namespace {
double point_distance(const vec3& a, const vec3& b)
{
    return std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
}
}  // namespace

TEST_CASE("hand skeleton: 23 joints, names, parents, channels, end sites")
{
    const skeleton s = hand_skeleton();
    REQUIRE(s.size() == hand_joint_count);
    CHECK_NOTHROW(s.validate());
    CHECK(s.joints[0].name == "forearm");
    CHECK(s.joints[0].parent == -1);
    CHECK(s.joints[0].channels.size() == 6);
    CHECK(s.joints[0].rotation_order() == std::array<axis, 3>{axis::z, axis::x, axis::y});
    // fewer than three rotation channels: the listed axes first, then the missing ones (z, x, y), none twice
    joint j;
    j.channels = {channel::xrotation, channel::yrotation};
    CHECK(j.rotation_order() == std::array<axis, 3>{axis::x, axis::y, axis::z});
    j.channels = {channel::xposition, channel::yposition, channel::zposition, channel::yrotation};
    CHECK(j.rotation_order() == std::array<axis, 3>{axis::y, axis::z, axis::x});
    j.channels = {};
    CHECK(j.rotation_order() == std::array<axis, 3>{axis::z, axis::x, axis::y});
    j.channels = {channel::yrotation, channel::xrotation, channel::zrotation};
    CHECK(j.rotation_order() == std::array<axis, 3>{axis::y, axis::x, axis::z});
    CHECK(s.index_of("wrist") == hand_index::wrist);
    CHECK(s.index_of("palm") == hand_index::palm);
    CHECK(s.index_of("thumb_metacarpal") == hand_index::finger_joint(0, 0));
    CHECK(s.index_of("pinky_distal") == 22);
    CHECK(s.index_of("middle_intermediate") == hand_index::finger_joint(2, 2));
    int end_sites = 0;
    for (std::size_t i = 1; i < s.size(); ++i) {
        CHECK(s.joints[i].channels.size() == 3);
        if (s.joints[i].end_site) {
            ++end_sites;
            CHECK(s.joints[i].name.ends_with("_distal"));
        }
        for (int a = 0; a < 3; ++a) CHECK(s.joints[i].lower_limit[a] <= s.joints[i].upper_limit[a]);
    }
    CHECK(end_sites == 5);
    CHECK(is_hand_skeleton(hand_skeleton(21.0)));
    CHECK_THROWS_AS(hand_skeleton(-1.0), value_error);
    // Rest pose inside every limit.
    for (const auto& j : s.joints)
        for (int a = 0; a < 3; ++a) CHECK((j.lower_limit[a] <= 0 && 0 <= j.upper_limit[a]));
}

TEST_CASE("hand skeleton: rest geometry is anatomically plausible")
{
    const double L = 18.5;
    const skeleton s = hand_skeleton(L);
    std::vector<double> zero(s.size() * 3, 0.0);
    const auto p = forward_kinematics(s, zero.data());
    const vec3 wrist = p.joints[hand_index::wrist];
    // Middle finger tip to wrist is the hand length (Buchholz's definition), within 5 %.
    const vec3 middle_tip = p.end_sites[hand_index::finger_joint(2, 3)];
    CHECK(point_distance(middle_tip, wrist) == doctest::Approx(L).epsilon(0.05));
    // Every finger tip lies 0.55..1.05 hand lengths from the wrist; fingers point +Y, spread in X.
    double prev_x = 1e9;
    for (std::size_t f = 0; f < 5; ++f) {
        const vec3 tip = p.end_sites[hand_index::finger_joint(f, 3)];
        const double d = point_distance(tip, wrist);
        CHECK(d > 0.5 * L);
        CHECK(d < 1.05 * L);
        CHECK(tip[1] > wrist[1]);
        if (f >= 1) {
            CHECK(tip[0] < prev_x);  // index .. pinky go from +X to -X
            prev_x = tip[0];
        }
    }
    // The thumb is on the radial (+X) side, angled away from the index and toward the palm (+Z).
    const vec3 thumb_tip = p.end_sites[hand_index::finger_joint(0, 3)];
    CHECK(thumb_tip[0] > p.end_sites[hand_index::finger_joint(1, 3)][0]);
    CHECK(thumb_tip[2] > 0.0);
    // Index tip is shorter than middle, pinky shortest of the four fingers.
    CHECK(point_distance(p.end_sites[hand_index::finger_joint(4, 3)], wrist) < point_distance(p.end_sites[hand_index::finger_joint(1, 3)], wrist));
}

TEST_CASE("hand skeleton: flexing a finger moves its tip toward the palm")
{
    const skeleton s = hand_skeleton();
    std::vector<double> a(s.size() * 3, 0.0);
    const auto rest = forward_kinematics(s, a.data());
    const vec3 palm = rest.joints[hand_index::palm];
    for (std::size_t f = 1; f < 5; ++f) {
        std::vector<double> b = a;
        b[hand_index::finger_joint(f, 1) * 3 + 0] = 80;  // MCP flexion
        b[hand_index::finger_joint(f, 2) * 3 + 0] = 90;  // PIP
        b[hand_index::finger_joint(f, 3) * 3 + 0] = 60;  // DIP
        const auto fist = forward_kinematics(s, b.data());
        const vec3 t0 = rest.end_sites[hand_index::finger_joint(f, 3)];
        const vec3 t1 = fist.end_sites[hand_index::finger_joint(f, 3)];
        CHECK(point_distance(t1, palm) < 0.6 * point_distance(t0, palm));
        CHECK(t1[2] > t0[2]);  // toward the palm side (+Z)
        // Other fingers did not move.
        const std::size_t g = f == 1 ? 2 : 1;
        CHECK(point_distance(fist.end_sites[hand_index::finger_joint(g, 3)], rest.end_sites[hand_index::finger_joint(g, 3)]) < 1e-12);
    }
    // Wrist flexion moves the middle tip toward +Z as well; extension toward -Z.
    std::vector<double> w = a;
    w[hand_index::wrist * 3] = 40;
    CHECK(forward_kinematics(s, w.data()).end_sites[hand_index::finger_joint(2, 3)][2] > 5.0);
    w[hand_index::wrist * 3] = -40;
    CHECK(forward_kinematics(s, w.data()).end_sites[hand_index::finger_joint(2, 3)][2] < -5.0);
}

TEST_CASE("hand skeleton: a hand read back from BVH, which carries no limits, adopts the hand's; others keep theirs")
{
    const clip c = parse_bvh(to_bvh_string(synthesize(hand_motion::gripping, emotion::neutral, 0, 2, 30.0)), "hand.bvh");
    const skeleton hand = hand_skeleton();
    for (const auto& j : c.skel.joints) {
        CHECK(j.lower_limit == vec3{-180, -180, -180});
        CHECK(j.upper_limit == vec3{180, 180, 180});
    }
    CHECK_FALSE(c.skel.has_limits());
    CHECK(hand.has_limits());
    skeleton s = c.skel;
    CHECK(adopt_hand_limits(s));
    for (std::size_t j = 0; j < s.size(); ++j) {
        CHECK(s.joints[j].lower_limit == hand.joints[j].lower_limit);
        CHECK(s.joints[j].upper_limit == hand.joints[j].upper_limit);
    }
    CHECK_FALSE(adopt_hand_limits(s));  // it has limits now
    // a hand with a limit of its own keeps every limit as it is
    skeleton own = c.skel;
    own.joints[4].upper_limit[0] = 90;
    CHECK_FALSE(adopt_hand_limits(own));
    CHECK(own.joints[4].upper_limit[0] == 90);
    CHECK(own.joints[5].upper_limit == vec3{180, 180, 180});
    // another skeleton (a hand with a joint renamed) keeps its own
    skeleton other = c.skel;
    other.joints[7].name = "index_knuckle";
    CHECK_FALSE(adopt_hand_limits(other));
    CHECK(other.joints[7].upper_limit == vec3{180, 180, 180});
}
