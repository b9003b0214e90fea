// The rules of Table 2 (body) and their hand counterparts: zero coefficients are the identity, each rule
// moves what it says, g4 changes the duration by 1/c4.
#include "helpers.hpp"

#include <doctest/doctest.h>

using namespace handemo;

namespace {

rcm::keyframe_points points_of(const clip& c, rcm::rig& r)
{
    clip u = c;
    unwrap_angles(u);
    r = rcm::make_rig(u.skel);
    return rcm::sample_control_points(r, u, rcm::keyframe_indices(u.frames));
}

}  // namespace

TEST_CASE("rcm rules: the rig takes its control points from the role map (body: Bandai names; hand: tips are End Sites)")
{
    const skeleton s = test::humanoid();
    const rcm::rig r = rcm::make_rig(s);
    REQUIRE(r.kind == rcm::rig_kind::body);
    auto name = [&](int q) { return s.joints[static_cast<std::size_t>(r.points[static_cast<std::size_t>(q)].joint)].name; };
    CHECK(name(rcm::body_point::pelvis) == "Hips");
    CHECK(name(rcm::body_point::chest) == "Chest");
    CHECK(name(rcm::body_point::head) == "Head");
    CHECK(name(rcm::body_point::l_hand) == "Hand_L");
    CHECK(name(rcm::body_point::r_foot) == "Foot_R");
    CHECK(s.joints[static_cast<std::size_t>(r.translation_joint)].name == "Hips");
    CHECK(r.torso_length == doctest::Approx(12 + 18 + 20 + 10));
    CHECK(r.leg_length == doctest::Approx(std::hypot(9.0, 5.0) + 42 + 40));
    const skeleton h = hand_skeleton();
    const rcm::rig rh = rcm::make_rig(h);
    REQUIRE(rh.kind == rcm::rig_kind::hand);
    CHECK(rh.points[rcm::hand_point::index_tip].end_site);
    CHECK(rh.points[rcm::hand_point::index_tip].joint == static_cast<int>(hand_index::finger_joint(1, 3)));
    CHECK(rh.translation_joint == static_cast<int>(hand_index::forearm));
    skeleton bad = s;
    bad.joints[4].name = "Skull";
    CHECK_THROWS_WITH_AS(rcm::make_rig(bad), doctest::Contains("head"), value_error);
}

TEST_CASE("rcm rules: zero coefficients are the identity (body and hand)")
{
    for (const clip& c : {test::humanoid_dance(61), synthesize(hand_motion::gripping, emotion::sad, 0, 3, 30.0)}) {
        rcm::rig r;
        const auto kp = points_of(c, r);
        const std::vector<double> zero(r.coefficients(), 0.0);
        const auto res = rcm::apply_rules(r, kp, zero);
        CHECK(res.time_scale == 1.0);
        REQUIRE(res.points.size() == kp.p.size());
        for (std::size_t q = 0; q < kp.p.size(); ++q)
            for (std::size_t i = 0; i < kp.p[q].size(); ++i) CHECK(res.points[q][i] == doctest::Approx(kp.p[q][i]).epsilon(1e-14).scale(1e-12));
    }
}

TEST_CASE("rcm rules: g1 lowers and raises the pelvis, g2 moves the head toward the upright torso, g3 the hands")
{
    rcm::rig r;
    const auto kp = points_of(test::humanoid_dance(61), r);
    using namespace rcm::body_point;
    std::vector<double> a(r.coefficients(), 0.0);
    a[0] = std::log(0.5);  // c1 = 0.5: pelvis at half its height
    auto res = rcm::apply_rules(r, kp, a);
    for (std::size_t k = 0; k < kp.count; ++k) {
        CHECK(res.points[pelvis][k * 3 + 1] - kp.ground == doctest::Approx(0.5 * kp.height[k]));
        CHECK(res.points[l_foot][k * 3 + 1] == kp.p[l_foot][k * 3 + 1]);  // feet stay
        CHECK(res.points[head][k * 3 + 1] - kp.p[head][k * 3 + 1] == doctest::Approx(-0.5 * kp.height[k]));
    }
    a[0] = std::log(4.0);  // c1 = 4: toward the T-pose height (the dance is crouched)
    res = rcm::apply_rules(r, kp, a);
    for (std::size_t k = 0; k < kp.count; ++k) {
        const double h = kp.height[k], hT = kp.height_tpose[k];
        REQUIRE(h < hT);
        CHECK(res.points[pelvis][k * 3 + 1] - kp.ground == doctest::Approx(h + (hT - h) * 0.75));
    }
    a[0] = 0;
    a[1] = 20;  // c2 -> infinity: the torso becomes the upright T-pose torso
    res = rcm::apply_rules(r, kp, a);
    for (std::size_t k = 0; k < kp.count; ++k) {
        CHECK(res.points[head][k * 3 + 0] - res.points[pelvis][k * 3 + 0] == doctest::Approx(0).scale(1e-6));
        CHECK(res.points[head][k * 3 + 1] - res.points[pelvis][k * 3 + 1] == doctest::Approx(r.torso_length));
    }
    a[1] = 0;
    a[2] = 3;  // c_head = 4 for the left hand: 3/4 of the way to the head
    res = rcm::apply_rules(r, kp, a);
    for (std::size_t k = 0; k < kp.count; ++k)
        for (int ax = 0; ax < 3; ++ax)
            CHECK(res.points[l_hand][k * 3 + ax] ==
                  doctest::Approx(kp.p[l_hand][k * 3 + ax] + 0.75 * (kp.p[head][k * 3 + ax] - kp.p[l_hand][k * 3 + ax])));
}

TEST_CASE("rcm rules: the hand's h2 opens the hand to its rest shape, h3 curls toward the palm")
{
    rcm::rig r;
    const auto kp = points_of(synthesize(hand_motion::gripping, emotion::angry, 0, 3, 30.0), r);
    REQUIRE(r.kind == rcm::rig_kind::hand);
    using namespace rcm::hand_point;
    std::vector<double> a(r.coefficients(), 0.0);
    a[1] = 30;  // c2 -> infinity: tips at the open hand's tip - palm vectors
    auto res = rcm::apply_rules(r, kp, a);
    for (std::size_t f = 0; f < 5; ++f)
        for (std::size_t k = 0; k < kp.count; ++k) {
            double d = 0, d0 = 0;
            for (int ax = 0; ax < 3; ++ax) {
                d += std::pow(res.points[thumb_tip + f][k * 3 + ax] - res.points[palm][k * 3 + ax], 2);
                d0 += r.tip_rest[f][ax] * r.tip_rest[f][ax];
            }
            CHECK(std::sqrt(d) == doctest::Approx(std::sqrt(d0)));
        }
    a[1] = 0;
    a[2] = 1;  // fingers (not thumb) move half way to the palm
    res = rcm::apply_rules(r, kp, a);
    for (std::size_t k = 0; k < kp.count; ++k)
        for (int ax = 0; ax < 3; ++ax) {
            CHECK(res.points[index_tip][k * 3 + ax] == doctest::Approx(0.5 * (kp.p[index_tip][k * 3 + ax] + kp.p[palm][k * 3 + ax])));
            CHECK(res.points[thumb_tip][k * 3 + ax] == doctest::Approx(kp.p[thumb_tip][k * 3 + ax]));
        }
}

TEST_CASE("rcm rules: g4 changes the duration by 1/c4 (resampled and as a frame rate) and speeds by c4")
{
    const clip c = test::humanoid_dance(121);
    for (double c4 : {0.8, 1.25, 2.0}) {
        const double a4 = std::log(c4);
        // Fix every coefficient but g4's: a target on the left hand's mean speed that c4 alone reaches.
        rcm::rig r;
        const auto kp = points_of(c, r);
        const auto f0 = rcm::feature_values(r, kp.times, kp.ground, kp.p, 1.0);
        const auto f1 = rcm::feature_values(r, kp.times, kp.ground, kp.p, c4);
        std::vector<std::string> names;
        rcm::feature_values(r, kp.times, kp.ground, kp.p, 1.0, &names);
        for (std::size_t i = 0; i < names.size(); ++i) {
            const double power = names[i].ends_with("_velocity") ? 1 : names[i].ends_with("_acceleration") ? 2 : names[i] == "jerk" ? 3 : 0;
            for (std::size_t k = 0; k < kp.count; ++k) CHECK(f1[i][k] == doctest::Approx(f0[i][k] * std::pow(c4, power)));
        }
        double mean_speed = 0;
        for (double v : f1[static_cast<std::size_t>(std::find(names.begin(), names.end(), "l_hand_velocity") - names.begin())])
            mean_speed += v / static_cast<double>(kp.count);
        rcm::synth_options opt;
        opt.rules = {false, false, false, true};
        const std::vector<rcm::feature_target> tg{{"l_hand_velocity", rcm::statistic::mean, mean_speed, 1, 10}};
        const auto res = rcm::stylise(c, tg, opt);
        CHECK(res.fit.coefficients.back() == doctest::Approx(a4).epsilon(1e-4));
        CHECK(res.motion.fps == c.fps);
        CHECK(res.motion.frames == static_cast<std::size_t>(std::llround(120.0 / c4)) + 1);
        CHECK(res.motion.duration() == doctest::Approx((c.duration() - 1 / c.fps) / c4 + 1 / c.fps).epsilon(0.02));
        opt.time = rcm::time_mode::frame_rate;
        const auto res2 = rcm::stylise(c, tg, opt);
        CHECK(res2.motion.frames == c.frames);
        CHECK(res2.motion.fps == doctest::Approx(c.fps * c4).epsilon(1e-4));
        CHECK(res2.motion.duration() == doctest::Approx(c.duration() / c4).epsilon(1e-4));
    }
}
