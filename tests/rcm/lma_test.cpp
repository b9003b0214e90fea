// The LMA features (Table 1 and the hand variant) on hand-made motions with known answers.
#include "helpers.hpp"

#include <doctest/doctest.h>

#include <cmath>
#include <numbers>

using namespace handemo;
using doctest::Approx;

namespace {

rcm::role_map body_roles() { return rcm::find_roles(rcm_test::body_names()); }
rcm::role_map hand_roles() { return rcm::find_roles(rcm_test::hand_names()); }

/// Derived feature by its 1-based paper number.
double fd(const xt::xtensor<double, 1>& f, std::size_t paper_index) { return f(paper_index - 1); }

}  // namespace

TEST_CASE("lma: the derived feature tables add up to Table 1's 121 (and 83 for the hand)")
{
    CHECK(rcm::basic_features(rcm::feature_set::body).size() == 37);
    CHECK(rcm::derived_count(rcm::feature_set::body) == 121);
    CHECK(rcm::basic_features(rcm::feature_set::hand).size() == 28);
    CHECK(rcm::derived_count(rcm::feature_set::hand) == 83);
    const auto& d = rcm::derived_features(rcm::feature_set::body);
    // spot checks of the paper's numbering
    CHECK(d[3].name == "f~4 mean f1 left foot - pelvis distance");
    CHECK(d[48].name.rfind("f~49 mean f15", 0) == 0);
    CHECK(d[49].name.rfind("f~50 max f16", 0) == 0);
    CHECK(d[64].name.rfind("f~65 max f21", 0) == 0);
    CHECK(d[88].name.rfind("f~89 mean f30", 0) == 0);
    CHECK(d[91].name.rfind("f~92 sum f35", 0) == 0);
    CHECK(d[96].name.rfind("f~97 max f31", 0) == 0);
    CHECK(d[112].name.rfind("f~113 max f13", 0) == 0);
    CHECK(d[120].name.rfind("f~121 box f37", 0) == 0);
}

TEST_CASE("lma: window length scales with the frame rate")
{
    CHECK(rcm::window_length(30) == 35);
    CHECK(rcm::window_length(60) == 70);
    CHECK(rcm::window_length(120) == 140);
    CHECK(rcm::window_length(15) == 18);
    CHECK(rcm::window_starts(50, 35).size() == 16);
    CHECK(rcm::window_starts(20, 35).size() == 1);
    CHECK_THROWS_AS(rcm::window_length(0), value_error);
}

TEST_CASE("lma: body features of a still figure")
{
    const auto p = rcm_test::animate(rcm_test::body_points(), 35);
    const auto f = rcm::clip_features(p, 30, body_roles(), rcm::feature_set::body);
    REQUIRE(f.size() == 121);
    CHECK(fd(f, 1) == Approx(std::sqrt(10200.0)));  // max f1 left foot - pelvis
    CHECK(fd(f, 2) == Approx(std::sqrt(10200.0)));  // min
    CHECK(fd(f, 3) == Approx(0.0));                 // std of a constant
    CHECK(fd(f, 8) == Approx(std::sqrt(10100.0)));  // mean f2
    CHECK(fd(f, 12) == Approx(50.0));               // mean f3 hand - shoulder
    CHECK(fd(f, 20) == Approx(140.0));              // mean f5 hands distance
    CHECK(fd(f, 24) == Approx(std::sqrt(5800.0)));  // mean f6 hand - head
    CHECK(fd(f, 32) == Approx(std::sqrt(6500.0)));  // mean f8 hand - pelvis
    CHECK(fd(f, 40) == Approx(100.0));              // mean f10 pelvis height
    CHECK(fd(f, 44) == Approx(100.0 - 0.5 * (std::sqrt(10200.0) + std::sqrt(10100.0))));  // mean f11
    CHECK(fd(f, 48) == Approx(std::sqrt(500.0)));   // mean f12 feet distance
    CHECK(fd(f, 49) == Approx(0.0));                // no deceleration peaks
    CHECK(fd(f, 52) == Approx(0.0));                // pelvis speed
    CHECK(fd(f, 80) == Approx(140.0 * 170 * 10));   // mean f27 volume of 5 joints
    CHECK(fd(f, 84) == Approx(140.0 * 170 * 10));   // mean f28 volume of all
    CHECK(fd(f, 88) == Approx(70.0));               // mean f29 torso height
    CHECK(fd(f, 89) == Approx(0.0));                // hands low
    CHECK(fd(f, 90) == Approx(1.0));                // hands middle
    CHECK(fd(f, 91) == Approx(0.0));                // hands high
    CHECK(fd(f, 92) == Approx(0.0));                // pelvis path
    CHECK(fd(f, 100) == Approx(0.0));               // upper body is flat
    CHECK(fd(f, 104) == Approx(20.0 * 100 * 10));   // lower body
    CHECK(fd(f, 108) == Approx(0.0));               // right side is flat
    CHECK(fd(f, 112) == Approx(60.0 * 140 * 10));   // left side
    CHECK(fd(f, 116) == Approx(std::sqrt(5000.0))); // mean f13 hand - chest
    CHECK(fd(f, 121) == Approx(140.0 * 170 * 10));  // f37 total volume
}

TEST_CASE("lma: hands above the head and below the pelvis")
{
    auto pts = rcm_test::body_points();
    pts[8] = {-30, 200, 0};  // left hand up
    pts[9] = {30, 80, 0};    // right hand down
    const auto f = rcm::clip_features(rcm_test::animate(pts, 35), 30, body_roles(), rcm::feature_set::body);
    CHECK(fd(f, 89) == Approx(0.5));
    CHECK(fd(f, 90) == Approx(0.0));
    CHECK(fd(f, 91) == Approx(0.5));
}

TEST_CASE("lma: body-frame volumes do not change when the figure turns")
{
    auto pts = rcm_test::body_points();
    for (auto& q : pts) q = {q[2], q[1], -q[0]};  // 90 degrees about the up axis
    const auto f = rcm::clip_features(rcm_test::animate(pts, 35), 30, body_roles(), rcm::feature_set::body);
    CHECK(fd(f, 80) == Approx(140.0 * 170 * 10));
    CHECK(fd(f, 104) == Approx(20.0 * 100 * 10));
    CHECK(fd(f, 112) == Approx(60.0 * 140 * 10));
}

TEST_CASE("lma: constant velocity gives speed, no acceleration or jerk, path length and area")
{
    const auto p = rcm_test::animate(rcm_test::body_points(), 35, {3, 0, 4});  // 5 units per frame
    const auto t = rcm::basic_table(p, 30, body_roles(), rcm::feature_set::body);
    for (std::size_t f : {0u, 10u, 34u}) {
        CHECK(t(f, 15) == Approx(150.0));  // pelvis speed
        CHECK(t(f, 16) == Approx(150.0));  // left hand speed
        CHECK(t(f, 20) == Approx(0.0).epsilon(1e-9));  // pelvis acceleration
        CHECK(t(f, 25) == Approx(0.0).epsilon(1e-9));  // jerk
    }
    CHECK(t(17, 37) == Approx(90.0 * 120.0 * 30 / 31));  // area per second over frames 2..32
    const auto f = rcm::clip_features(p, 30, body_roles(), rcm::feature_set::body);
    CHECK(fd(f, 92) == Approx(34 * 5.0));  // f35 total distance in the window
    CHECK(fd(f, 50) == Approx(150.0));     // max pelvis speed
    CHECK(fd(f, 51) == Approx(0.0).epsilon(1e-9));  // std pelvis speed
}

TEST_CASE("lma: constant acceleration inside the clip")
{
    const double a = 200, fps = 30;
    auto p = rcm_test::animate(rcm_test::body_points(), 40);
    for (std::size_t f = 0; f < 40; ++f)
        for (std::size_t q = 0; q < 16; ++q) p(f, q, 0) += 0.5 * a * std::pow(static_cast<double>(f) / fps, 2);
    const auto t = rcm::basic_table(p, fps, body_roles(), rcm::feature_set::body);
    CHECK(t(20, 15) == Approx(a * 20 / fps));  // speed a t
    CHECK(t(20, 20) == Approx(a));             // acceleration
    CHECK(t(20, 25) == Approx(0.0).epsilon(1e-5));
}

TEST_CASE("lma: deceleration peaks of a periodic speed: one per period")
{
    std::vector<double> s(300);
    for (std::size_t t = 0; t < s.size(); ++t) s[t] = 2 + std::sin(2 * std::numbers::pi * static_cast<double>(t) / 30.0 + 0.3);
    const auto ind = rcm::detail::deceleration_peaks(s, 30);
    double peaks = 0;
    for (double v : ind) peaks += v / 30;
    CHECK(peaks == Approx(10.0).epsilon(0.11));  // 10 periods, minus possibly one at an end
}

TEST_CASE("lma: hand features of a flat hand and of fanned fingers")
{
    const auto r = hand_roles();
    REQUIRE(rcm::detect_feature_set(r) == rcm::feature_set::hand);
    auto f = rcm::clip_features(rcm_test::animate(rcm_test::hand_points(), 70), 60, r, rcm::feature_set::hand);
    REQUIRE(f.size() == 83);
    CHECK(fd(f, 4) == Approx(std::sqrt(38.0)));    // mean h1 thumb tip - palm
    CHECK(fd(f, 8) == Approx(std::sqrt(109.0)));   // mean h2 index tip - palm
    CHECK(fd(f, 24) == Approx(std::sqrt(57.0)));   // mean h6 thumb - index tips
    CHECK(fd(f, 28) == Approx(2.0));               // mean h7 index - middle tips
    CHECK(fd(f, 40) == Approx(std::sqrt(117.0)));  // mean h10 span
    CHECK(fd(f, 44) == Approx(0.0));               // mean h11 spread of parallel fingers
    CHECK(fd(f, 48) == Approx(8.0 * 15 * 2));      // mean h12 hand volume
    CHECK(fd(f, 51) == Approx(0.0));               // mean thumb tip speed
    CHECK(fd(f, 83) == Approx(8.0 * 7 * 2));       // h28 tip box: x -3..5, y 8..15, z 0..2

    auto pts = rcm_test::hand_points();
    const double ang[] = {-0.3, -0.1, 0.1, 0.3};  // index .. pinky: neighbours 0.2 rad apart
    for (std::size_t k = 0; k < 4; ++k)
        pts[8 + k] = {pts[3 + k][0] + 7 * std::sin(ang[k]), pts[3 + k][1] + 7 * std::cos(ang[k]), 0};
    f = rcm::clip_features(rcm_test::animate(pts, 70), 60, r, rcm::feature_set::hand);
    CHECK(fd(f, 44) == Approx(0.2));
}

TEST_CASE("lma: hand speeds and wrist path")
{
    const auto p = rcm_test::animate(rcm_test::hand_points(), 70, {1, 0, 0});
    const auto f = rcm::clip_features(p, 60, hand_roles(), rcm::feature_set::hand);
    CHECK(fd(f, 49) == Approx(60.0));  // max thumb tip speed
    CHECK(fd(f, 64) == Approx(60.0));  // max wrist speed
    CHECK(fd(f, 81) == Approx(69.0));  // wrist path in the one 70-frame window
    CHECK(fd(f, 83) == Approx(77.0 * 7 * 2));  // the tips sweep 69 more units along x
}

TEST_CASE("lma: world positions of a clip include the End Sites")
{
    const auto c = clip::make(hand_skeleton(), 3, 30);
    const auto p = rcm::world_positions(c);
    CHECK(p.shape()[0] == 3);
    CHECK(p.shape()[1] == hand_joint_count + 5);
    const auto fk = forward_kinematics(c.skel, c.frame_angles(0), c.frame_positions(0));
    const std::size_t tip = hand_joint_count + 1;  // index_distal_end
    CHECK(p(0, tip, 1) == Approx(fk.end_sites[hand_index::finger_joint(1, 3)][1]));
}

TEST_CASE("lma: errors for missing roles and bad shapes")
{
    auto names = rcm_test::body_names();
    names[9] = "Paw_R";
    const auto r = rcm::find_roles(names);
    CHECK_THROWS_WITH_AS(rcm::clip_features(rcm_test::animate(rcm_test::body_points(), 35), 30, r, rcm::feature_set::body),
                         doctest::Contains("right_hand"), value_error);
    CHECK_THROWS_AS(rcm::clip_features(rcm_test::animate(rcm_test::body_points(), 35), 0, body_roles(), rcm::feature_set::body), value_error);
}

TEST_CASE("lma: min-max normaliser")
{
    xt::xtensor<double, 2> x = {{0, 5, 1}, {10, 5, 3}, {5, 5, 2}};
    const auto n = rcm::feature_normaliser::fit(x);
    const auto y = n.apply(xt::xtensor<double, 1>{5, 5, 4});
    CHECK(y(0) == Approx(0.5));
    CHECK(y(1) == Approx(0.5));  // constant feature
    CHECK(y(2) == Approx(1.0));  // clamped
    CHECK_THROWS_AS(n.apply(xt::xtensor<double, 1>{1, 2}), shape_error);
}
