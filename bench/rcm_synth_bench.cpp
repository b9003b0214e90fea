// Synthesis of Aristidou et al. 2017, Section 4, on a 680-frame motion (the paper: 12 s in MATLAB on an
// i7-2700K; target here: under 0.1 s on one core): keyframes every fifth frame (137), the joint BFGS fit of
// all rule coefficients to 11 (body) / 9 (hand) desired features, the damped least-squares IK of every
// keyframe and the spline back to full rate. The motions are the synthetic ones of the tests: the 21-joint
// humanoid dance and the 23-joint hand (a pointing take repeated to 680 frames), and the desired features
// are those that known coefficients give (reachable), so every run does the same work.
#include "../tests/rcm_synth/helpers.hpp"

#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

using namespace handemo;

namespace {

std::vector<rcm::feature_target> reachable_targets(const clip& c, const std::vector<double>& truth, const std::vector<std::string>& features)
{
    clip u = c;
    unwrap_angles(u);
    const rcm::rig r = rcm::make_rig(u.skel);
    const auto kp = rcm::sample_control_points(r, u, rcm::keyframe_indices(u.frames));
    const auto moved = rcm::apply_rules(r, kp, truth);
    std::vector<std::string> names;
    const auto f = rcm::feature_values(r, kp.times, kp.ground, moved.points, moved.time_scale, &names);
    std::vector<rcm::feature_target> tg;
    for (const auto& n : features) {
        const auto i = static_cast<std::size_t>(std::find(names.begin(), names.end(), n) - names.begin());
        double m = 0;
        for (double v : f[i]) m += v / static_cast<double>(f[i].size());
        tg.push_back({n, rcm::statistic::mean, m, 1.0, std::max(1.0, std::abs(m))});
    }
    return tg;
}

clip hand_680()
{
    const clip one = synthesize(hand_motion::pointing, emotion::neutral, 0, 2, 30.0);
    clip c = clip::make(one.skel, 680, 30.0);
    const std::size_t J3 = one.skel.size() * 3;
    for (std::size_t f = 0; f < 680; ++f) {
        const std::size_t g = f % one.frames;
        std::copy(one.frame_angles(g), one.frame_angles(g) + J3, c.angles.begin() + static_cast<std::ptrdiff_t>(f * J3));
        std::copy(one.frame_positions(g), one.frame_positions(g) + J3, c.positions.begin() + static_cast<std::ptrdiff_t>(f * J3));
    }
    return c;
}

// The IK as before the warm start and the stall rule (the _as_before benchmarks: the same results as
// before, with the faster solve); the others run stylise's defaults.
rcm::synth_options as_before_options()
{
    rcm::synth_options o;
    o.ik_warm_start = false;
    o.ik.stall_tolerance = 1e-9;
    o.ik.stall_iterations = 1;
    return o;
}

void run(benchmark::State& state, const clip& c, const std::vector<rcm::feature_target>& tg, const rcm::synth_options& opt = {})
{
    rcm::synth_result res;
    for (auto _ : state) {
        res = rcm::stylise(c, tg, opt);
        benchmark::DoNotOptimize(res.motion.angles.data());
    }
    // What the run reached (the same every iteration): Eq. 6 of the rule-moved points (the fit) and of the
    // points the IK reached, the weighted RMS distance to the IK targets over all keyframes and at the worst
    // keyframe, and the IK iterations per keyframe.
    state.counters["frames"] = static_cast<double>(c.frames);
    state.counters["eq6_fit"] = res.fit.loss_final;
    state.counters["eq6_ik"] = res.loss_after_ik;
    state.counters["ik_rms_cm"] = res.ik_rms;
    state.counters["ik_rms_max_cm"] = res.ik_rms_max;
    state.counters["ik_iters_kf"] = static_cast<double>(res.ik_iterations) / static_cast<double>(std::max<std::size_t>(1, res.keyframes.size()));
}

std::vector<rcm::feature_target> body_targets(const clip& c)
{
    return reachable_targets(c, {std::log(0.8), std::log(0.7), 0.3, 0, -0.2, 0, 0, 0.25, 0, -0.2, std::log(1.3)},
                             {"hip_ground", "torso_height", "l_hand_head", "r_hand_chest", "hands_distance", "l_hand_hip",
                              "r_hand_hip", "l_hand_velocity", "pelvis_velocity", "hands_height", "volume_5"});
}

std::vector<rcm::feature_target> hand_targets(const clip& c)
{
    return reachable_targets(c, {std::log(1.4), std::log(0.6), 0.3, -0.2, 0.1, 0.0, std::log(0.8)},
                             {"thumb_palm", "index_palm", "middle_palm", "ring_palm", "index_middle", "thumb_index",
                              "hand_volume", "wrist_velocity", "index_velocity"});
}

void BM_stylise_body_680(benchmark::State& state)
{
    const clip c = test::humanoid_dance(680);
    run(state, c, body_targets(c));
}
BENCHMARK(BM_stylise_body_680)->Unit(benchmark::kMillisecond);

void BM_stylise_body_680_as_before(benchmark::State& state)
{
    const clip c = test::humanoid_dance(680);
    run(state, c, body_targets(c), as_before_options());
}
BENCHMARK(BM_stylise_body_680_as_before)->Unit(benchmark::kMillisecond);

void BM_stylise_hand_680(benchmark::State& state)
{
    const clip c = hand_680();
    run(state, c, hand_targets(c));
}
BENCHMARK(BM_stylise_hand_680)->Unit(benchmark::kMillisecond);

void BM_stylise_hand_680_as_before(benchmark::State& state)
{
    const clip c = hand_680();
    run(state, c, hand_targets(c), as_before_options());
}
BENCHMARK(BM_stylise_hand_680_as_before)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
