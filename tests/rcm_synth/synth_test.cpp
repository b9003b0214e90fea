// Synthesis end to end: the joint optimisation of all rule coefficients (handemo) against each rule alone
// and against the paper's sequential order, on targets that a known set of coefficients reaches; stylise()
// keeps bone lengths and limits and is the identity for targets the input already has.
#include "helpers.hpp"

#include <doctest/doctest.h>

using namespace handemo;

namespace {

struct problem {
    clip u;
    rcm::rig r;
    rcm::keyframe_points kp;
    std::vector<rcm::feature_target> targets;
};

// Targets = the windowed features of the input moved by `truth` (reachable by construction).
problem make_problem(const clip& c, const std::vector<double>& truth, const std::vector<std::string>& features)
{
    problem p;
    p.u = c;
    unwrap_angles(p.u);
    p.r = rcm::make_rig(p.u.skel);
    p.kp = rcm::sample_control_points(p.r, p.u, rcm::keyframe_indices(p.u.frames));
    const auto moved = rcm::apply_rules(p.r, p.kp, truth);
    std::vector<std::string> names;
    const auto f = rcm::feature_values(p.r, p.kp.times, p.kp.ground, moved.points, moved.time_scale, &names);
    for (const auto& n : features) {
        const auto i = static_cast<std::size_t>(std::find(names.begin(), names.end(), n) - names.begin());
        REQUIRE(i < names.size());
        double mean = 0, lo = 1e300, hi = -1e300;
        for (double v : f[i]) mean += v / static_cast<double>(f[i].size()), lo = std::min(lo, v), hi = std::max(hi, v);
        p.targets.push_back({n, rcm::statistic::mean, mean, 1.0, std::max(1.0, std::abs(mean))});
    }
    return p;
}

}  // namespace

TEST_CASE("rcm synth: the joint optimisation reaches a reachable body target better than any rule alone and than the paper's sequential order")
{
    const std::vector<double> truth{std::log(0.8), std::log(0.7), 0.3, 0, -0.2, 0, 0, 0.25, 0, -0.2, std::log(1.3)};
    const problem p = make_problem(test::humanoid_dance(120), truth,
                                   {"hip_ground", "torso_height", "l_hand_head", "r_hand_chest", "hands_distance",
                                    "l_hand_hip", "r_hand_hip", "l_hand_velocity", "pelvis_velocity", "hands_height", "volume_5"});
    rcm::synth_options opt;
    opt.max_iterations = 200;
    const auto joint = rcm::fit_coefficients(p.r, p.kp, p.targets, opt);
    MESSAGE("joint: loss " << joint.loss_initial << " -> " << joint.loss_final << " in " << joint.iterations << " iterations");
    CHECK(joint.loss_final < 1e-6 * joint.loss_initial);
    for (int rule = 0; rule < 4; ++rule) {
        rcm::synth_options one = opt;
        one.rules = {rule == 0, rule == 1, rule == 2, rule == 3};
        const auto alone = rcm::fit_coefficients(p.r, p.kp, p.targets, one);
        MESSAGE("rule g" << rule + 1 << " alone: loss " << alone.loss_final);
        CHECK(joint.loss_final < 0.01 * alone.loss_final);
    }
    rcm::synth_options seq = opt;
    seq.mode = rcm::strategy::sequential;
    const auto sequential = rcm::fit_coefficients(p.r, p.kp, p.targets, seq);
    MESSAGE("sequential (paper): loss " << sequential.loss_final);
    CHECK(joint.loss_final < sequential.loss_final);
}

TEST_CASE("rcm synth: the joint optimisation reaches a reachable hand target better than any rule alone")
{
    const std::vector<double> truth{std::log(1.4), std::log(0.6), 0.3, -0.2, 0.1, 0.0, std::log(0.8)};
    const problem p = make_problem(synthesize(hand_motion::pointing, emotion::neutral, 0, 2, 30.0), truth,
                                   {"thumb_palm", "index_palm", "middle_palm", "ring_palm", "index_middle", "thumb_index",
                                    "hand_volume", "wrist_velocity", "index_velocity"});
    rcm::synth_options opt;
    opt.max_iterations = 200;
    const auto joint = rcm::fit_coefficients(p.r, p.kp, p.targets, opt);
    MESSAGE("hand joint: loss " << joint.loss_initial << " -> " << joint.loss_final);
    CHECK(joint.loss_final < 1e-6 * joint.loss_initial);
    for (int rule = 0; rule < 4; ++rule) {
        rcm::synth_options one = opt;
        one.rules = {rule == 0, rule == 1, rule == 2, rule == 3};
        const auto alone = rcm::fit_coefficients(p.r, p.kp, p.targets, one);
        CHECK(joint.loss_final < 0.01 * alone.loss_final);
    }
}

TEST_CASE("rcm synth: stylise keeps bone lengths and joint limits, and reaches its keyframe targets")
{
    const std::vector<double> truth{std::log(0.85), std::log(0.8), 0.2, 0, 0, 0, 0, 0.2, 0, 0, std::log(1.2)};
    const clip c = test::humanoid_dance(150);
    const problem p = make_problem(c, truth, {"hip_ground", "torso_height", "l_hand_head", "r_hand_chest", "l_hand_velocity"});
    const auto res = rcm::stylise(c, p.targets);
    MESSAGE("stylise: Eq.6 " << res.fit.loss_initial << " -> " << res.fit.loss_final << ", after IK " << res.loss_after_ik
                             << ", IK rms max " << res.ik_rms_max);
    CHECK(res.fit.loss_final < 1e-3 * res.fit.loss_initial);
    CHECK(res.loss_after_ik < 0.05 * res.fit.loss_initial);
    res.motion.validate();
    const auto L = test::bone_lengths(res.motion);
    for (const auto& frame : L)
        for (std::size_t j = 1; j < c.skel.size(); ++j) {
            const auto& o = c.skel.joints[j].offset;
            CHECK(frame[j] == doctest::Approx(std::hypot(o[0], o[1], o[2])).epsilon(1e-12));
        }
    for (std::size_t f = 0; f < res.motion.frames; ++f)
        for (std::size_t j = 0; j < c.skel.size(); ++j)
            for (std::size_t a = 0; a < 3; ++a) {
                CHECK(res.motion.angle(f, j, a) > -180.0 - 1e-9);
                CHECK(res.motion.angle(f, j, a) <= 180.0 + 1e-9);
            }
}

TEST_CASE("rcm synth: targets the input already has leave it unchanged; unknown features are errors")
{
    const clip c = synthesize(hand_motion::patting, emotion::happy, 0, 4, 30.0);
    const problem p = make_problem(c, std::vector<double>(rcm::hand_coefficient_count, 0.0), {"index_palm", "hand_volume"});
    const auto res = rcm::stylise(c, p.targets);
    CHECK(res.fit.loss_initial < 1e-20);
    REQUIRE(res.motion.frames == c.frames);
    double worst = 0;
    for (std::size_t i = 0; i < c.angles.size(); ++i) {
        double d = std::fmod(std::abs(res.motion.angles[i] - c.angles[i]), 360.0);
        worst = std::max(worst, std::min(d, 360.0 - d));
    }
    CHECK(worst < 1e-3);
    CHECK_THROWS_WITH_AS(rcm::stylise(c, {{"no_such_feature"}}), doctest::Contains("no_such_feature"), value_error);
    // hand limits hold in the output of a real change
    const problem q = make_problem(c, {0.3, std::log(0.5), 0.4, 0, 0, 0, 0}, {"index_palm", "middle_palm", "thumb_palm"});
    const auto moved = rcm::stylise(c, q.targets);
    for (std::size_t f = 0; f < moved.motion.frames; ++f)
        for (std::size_t j = 0; j < c.skel.size(); ++j)
            for (std::size_t a = 0; a < 3; ++a) {
                CHECK(moved.motion.angle(f, j, a) >= c.skel.joints[j].lower_limit[a] - 1e-9);
                CHECK(moved.motion.angle(f, j, a) <= c.skel.joints[j].upper_limit[a] + 1e-9);
            }
}

TEST_CASE("rcm synth: the IK's warm start from the previous keyframe reaches the hand's targets at least as well")
{
    const clip c = synthesize(hand_motion::pointing, emotion::neutral, 0, 2, 30.0);
    const problem p = make_problem(c, {std::log(1.4), std::log(0.6), 0.3, -0.2, 0.1, 0.0, std::log(0.8)},
                                   {"thumb_palm", "index_palm", "middle_palm", "ring_palm", "index_middle", "thumb_index"});
    rcm::synth_options cold;
    cold.ik_warm_start = false;
    const rcm::synth_options warm;  // the default: warm start, stall rule 1e-3 over 2 steps
    const auto rc = rcm::stylise(c, p.targets, cold);
    const auto rw = rcm::stylise(c, p.targets, warm);
    MESSAGE("hand IK: cold rms " << rc.ik_rms << " cm (max " << rc.ik_rms_max << "), " << rc.ik_iterations << " iterations, Eq.6 after IK "
                                 << rc.loss_after_ik << "; warm rms " << rw.ik_rms << " cm (max " << rw.ik_rms_max << "), "
                                 << rw.ik_iterations << " iterations, Eq.6 after IK " << rw.loss_after_ik);
    CHECK(rw.ik_rms <= rc.ik_rms);
    CHECK(rw.loss_after_ik <= rc.loss_after_ik);
    CHECK(rw.ik_iterations < rc.ik_iterations);
}

TEST_CASE("rcm synth: a hand read back from BVH, which carries no limits, is stylised within the hand's joint limits")
{
    const clip c = parse_bvh(to_bvh_string(synthesize(hand_motion::gripping, emotion::neutral, 0, 2, 30.0)), "hand.bvh");
    const skeleton hand = hand_skeleton();
    // the premise: the hand read back has no limits (adopt_hand_limits()'s cases are in tests/motion/hand_test.cpp)
    REQUIRE(c.skel.joints[4].upper_limit == vec3{180, 180, 180});

    // an exaggerated target (a wider, faster hand) pushes the fingers toward and past their limits; the output stays
    // within the hand's, on the input's own skeleton
    const std::vector<double> truth{std::log(1.8), std::log(0.5), 0.6, -0.5, 0.4, 0.0, std::log(0.7)};
    const problem p = make_problem(c, truth, {"thumb_palm", "index_palm", "middle_palm", "ring_palm", "index_middle", "hand_volume"});
    const auto res = rcm::stylise(c, p.targets);
    res.motion.validate();
    CHECK(res.motion.skel.joints[4].upper_limit == vec3{180, 180, 180});
    std::size_t at_limit = 0;
    for (std::size_t f = 0; f < res.motion.frames; ++f)
        for (std::size_t j = 0; j < hand.size(); ++j)
            for (std::size_t a = 0; a < 3; ++a) {
                const double v = res.motion.angle(f, j, a);
                CHECK(v >= hand.joints[j].lower_limit[a] - 1e-9);
                CHECK(v <= hand.joints[j].upper_limit[a] + 1e-9);
                at_limit += std::abs(v - hand.joints[j].lower_limit[a]) < 1e-6 || std::abs(v - hand.joints[j].upper_limit[a]) < 1e-6;
            }
    MESSAGE("angles held at a limit: " << at_limit);
}
