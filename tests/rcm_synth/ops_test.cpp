// Every op the synthesis adds to the tape, every differentiable feature and the Eq. 6 objective, checked
// against central finite differences in double precision (tests/autodiff/gradcheck.hpp).
#include "../autodiff/gradcheck.hpp"
#include "helpers.hpp"

#include <doctest/doctest.h>

#include <random>

using namespace handemo;
namespace ad = handemo::autodiff::detail;
namespace rd = handemo::rcm::detail;
using handemo::test::gc_param;
using handemo::test::gradcheck;
using handemo::test::random_param;

namespace {

// loss = sum_i w_i y_i with fixed random weights, so every output element's derivative is checked.
int weighted_sum(autodiff::tape<double>& t, int y, unsigned seed = 3)
{
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-1, 1);
    std::vector<double> w(t.at(y).size);
    for (auto& v : w) v = u(rng);
    return ad::row_sum_raw(t, ad::mul_raw(t, y, t.leaf_copy(w.data(), w.size(), false)), 1, 1.0);
}
int param(autodiff::tape<double>& t, gc_param& p) { return t.leaf_ref(p.value.data(), p.grad.data(), p.value.size()); }

}  // namespace

TEST_CASE("rcm ops: gather, stencil, exp, bbox_volume, g1_height match finite differences")
{
    std::mt19937 rng(1);
    std::vector<gc_param> ps{random_param(12, rng)};
    SUBCASE("gather (repeated indices scatter-add)")
    {
        const std::vector<int> idx{0, 3, 3, 11, 5, 0};
        gradcheck(ps, [&](auto& t) { return weighted_sum(t, rd::gather(t, param(t, ps[0]), idx)); });
    }
    SUBCASE("stencil")
    {
        const std::vector<std::vector<rd::stencil_entry>> rows{{{0, 1.0}, {1, -2.0}}, {{3, 0.5}}, {}, {{2, 1.0}, {2, 1.0}, {0, 3.0}}};
        gradcheck(ps, [&](auto& t) { return weighted_sum(t, rd::stencil(t, param(t, ps[0]), 3, rows)); });
    }
    SUBCASE("exp") { gradcheck(ps, [&](auto& t) { return weighted_sum(t, rd::exp(t, param(t, ps[0]))); }); }
    SUBCASE("bbox_volume of [2, 2, 3]")
    {
        gradcheck(ps, [&](auto& t) { return weighted_sum(t, rd::bbox_volume(t, param(t, ps[0]), 2)); });
    }
    SUBCASE("rotate_rows")
    {
        const std::vector<double> M{0.2, -1, 0.5, 1, 0.3, 0, -0.4, 0.1, 2, 1, 0, 0, 0, 0, 1, 0, -1, 0,
                                    0.5, 0.5, 0.5, -1, 2, 0, 0.1, 0.2, 0.3, 3, 0, 1, 0, 1, 1, 1, 0, -2};
        gradcheck(ps, [&](auto& t) { return weighted_sum(t, rd::rotate_rows<double>(t, param(t, ps[0]), M)); });
    }
    SUBCASE("row_angle")
    {
        std::vector<gc_param> two{random_param(12, rng), random_param(12, rng)};
        gradcheck(two, [&](auto& t) { return weighted_sum(t, rd::row_angle(t, param(t, two[0]), param(t, two[1]))); });
    }
    SUBCASE("window_max and window_min")
    {
        const std::vector<std::size_t> starts{0, 2, 5, 8};
        gradcheck(ps, [&](auto& t) {
            const int x = param(t, ps[0]);
            return ad::add_raw(t, weighted_sum(t, rd::window_extreme<double>(t, x, starts, 4, 1)),
                               weighted_sum(t, rd::window_extreme<double>(t, x, starts, 4, -1), 9));
        });
    }
    SUBCASE("g1_height, all three branches")
    {
        const std::vector<double> h{50, 120, 80, 30}, hT{100, 100, 100, 100};
        for (double c : {0.6, 1.3, 2.5}) {
            std::vector<gc_param> pc{gc_param{{c}, {0.0}, true}};
            gradcheck(pc, [&](auto& t) { return weighted_sum(t, rd::g1_height<double>(t, param(t, pc[0]), h, hT)); });
        }
        // identity at c = 1 in every branch
        autodiff::tape<double> t;
        const double one = 1.0;
        const int y = rd::g1_height<double>(t, t.leaf_copy(&one, 1, false), h, hT);
        for (std::size_t i = 0; i < h.size(); ++i) CHECK(t.at(y).value[i] == 0.0);
    }
}

namespace {

// Checks d feature / d coefficients for every differentiable feature of a rig, at random coefficients.
void check_features(const clip& c, double spread)
{
    clip u = c;
    unwrap_angles(u);
    const rcm::rig r = rcm::make_rig(u.skel);
    const auto kf = rcm::keyframe_indices(u.frames);
    const rcm::keyframe_points kp = rcm::sample_control_points(r, u, kf);
    std::mt19937 rng(11);
    std::vector<gc_param> ps{random_param(r.coefficients(), rng, spread, 0.02)};
    std::vector<std::string> names;
    std::vector<double> unit;  // 1 / (1 + mean |feature|): every checked sum is O(1), so rounding stays below h
    {
        autodiff::tape<double> t;
        const int a = t.leaf_copy(ps[0].value.data(), ps[0].value.size(), false);
        const auto f = rcm::differentiable_features(t, r, kp.times, kp.ground, rcm::apply_rules(t, r, kp, a));
        names = f.names;
        for (int id : f.ids) {
            double m = 0;
            for (std::size_t k = 0; k < t.at(id).size; ++k) m += std::abs(t.at(id).value[k]) / static_cast<double>(t.at(id).size);
            unit.push_back(1.0 / (1.0 + m));
        }
    }
    REQUIRE(names.size() >= 12);
    for (std::size_t i = 0; i < names.size(); ++i) {
        CAPTURE(names[i]);
        gradcheck(ps, [&](auto& t) {
            const int a = param(t, ps[0]);
            const auto f = rcm::differentiable_features(t, r, kp.times, kp.ground, rcm::apply_rules(t, r, kp, a));
            return weighted_sum(t, ad::affine_raw(t, f.ids[i], unit[i], 0.0), static_cast<unsigned>(i));
        }, 1e-5, 1e-8);
    }
}

}  // namespace

TEST_CASE("rcm features: every body feature's derivative in all 11 coefficients matches finite differences")
{
    check_features(test::humanoid_dance(40), 0.4);
}

TEST_CASE("rcm features: every hand feature's derivative in all 7 coefficients matches finite differences")
{
    check_features(synthesize(hand_motion::pointing, emotion::happy, 0, 1, 30.0), 0.4);
}

TEST_CASE("rcm objective: Eq. 6 gradient in z matches finite differences (windowed mean, mean, std)")
{
    clip u = test::humanoid_dance(60);
    unwrap_angles(u);
    const rcm::rig r = rcm::make_rig(u.skel);
    const rcm::keyframe_points kp = rcm::sample_control_points(r, u, rcm::keyframe_indices(u.frames));
    const std::vector<rcm::feature_target> tg{{"hip_ground", rcm::statistic::windowed_mean, 70, 1, 20},
                                              {"l_hand_velocity", rcm::statistic::mean, 80, 2, 50},
                                              {"hands_distance", rcm::statistic::std, 5, 1, 10},
                                              {"torso_height", rcm::statistic::windowed_mean, 60, 1, 10},
                                              {"r_hand_chest", rcm::statistic::windowed_mean, 40, 1, 10},
                                              {"f27", rcm::statistic::window_max, 2e5, 1, 1e5},
                                              {"f3", rcm::statistic::window_min, 30, 1, 10},
                                              {"f22", rcm::statistic::window_std, 50, 1, 100},
                                              {"f26", rcm::statistic::window_mean, 500, 1, 1000}};
    rcm::objective obj(r, kp, tg);
    std::mt19937 rng(2);
    std::uniform_real_distribution<double> u01(-0.5, 0.5);
    std::vector<double> z(obj.size()), g(obj.size());
    for (auto& v : z) v = u01(rng);
    obj(z, g);
    for (std::size_t i = 0; i < z.size(); ++i) {
        const double h = 1e-6, v = z[i];
        z[i] = v + h;
        const double fp = obj(z, {});
        z[i] = v - h;
        const double fm = obj(z, {});
        z[i] = v;
        CAPTURE(i);
        CHECK(g[i] == doctest::Approx((fp - fm) / (2 * h)).epsilon(1e-5).scale(1e-6));
    }
}
