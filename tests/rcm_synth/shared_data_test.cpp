// Synthesis on real Bandai motion (../shared/data/bandai, label shared-data): the differentiable features
// equal lma.hpp's on every frame, and stylising a clip toward other feature values keeps bone lengths,
// reaches the targets and changes the duration by 1/c4.
#include "lma_match.hpp"

#include <filesystem>

// run by `<program> --shared-data` only (tests/test_main.cpp)
TEST_SUITE_BEGIN("shared-data");

using namespace handemo;

namespace {
std::filesystem::path bandai(const char* f) { return std::filesystem::path(HANDEMO_SHARED_DIR) / "data" / "bandai" / f; }
}  // namespace

TEST_CASE("rcm features on Bandai: equal to lma.hpp on every frame")
{
    for (const char* f : {"dataset-1_bow_active_001.bvh", "dataset-1_bow_normal_001.bvh"}) {
        CAPTURE(f);
        CHECK(test::check_against_lma(read_bvh(bandai(f).string())) == 27);
    }
}

TEST_CASE("rcm stylise on Bandai: lower, slower and more closed reaches its targets and keeps the bones")
{
    const clip c = read_bvh(bandai("dataset-1_bow_normal_001.bvh").string());
    clip u = c;
    unwrap_angles(u);
    const rcm::rig r = rcm::make_rig(u.skel);
    const auto kp = rcm::sample_control_points(r, u, rcm::keyframe_indices(u.frames));
    // targets: what known coefficients give (pelvis 10% lower, torso bent, hands toward the chest, 20% slower)
    const std::vector<double> truth{std::log(0.9), std::log(0.8), 0, 0.3, 0, 0, 0, 0.3, 0, 0, std::log(0.8)};
    const auto moved = rcm::apply_rules(r, kp, truth);
    std::vector<std::string> names;
    const auto fv = rcm::feature_values(r, kp.times, kp.ground, moved.points, moved.time_scale, &names);
    std::vector<rcm::feature_target> tg;
    for (const char* n : {"hip_ground", "torso_height", "l_hand_chest", "r_hand_chest", "l_hand_velocity", "r_hand_velocity"}) {
        const auto i = static_cast<std::size_t>(std::find(names.begin(), names.end(), n) - names.begin());
        double m = 0;
        for (double v : fv[i]) m += v / static_cast<double>(fv[i].size());
        tg.push_back({n, rcm::statistic::mean, m, 1.0, std::max(1.0, m)});
    }
    const auto res = rcm::stylise(c, tg);
    MESSAGE("Bandai stylise: Eq.6 " << res.fit.loss_initial << " -> " << res.fit.loss_final << ", after IK " << res.loss_after_ik
                                    << ", IK rms max " << res.ik_rms_max << " cm, frames " << c.frames << " -> " << res.motion.frames);
    CHECK(res.fit.loss_final < 1e-4 * res.fit.loss_initial);
    CHECK(res.loss_after_ik < 0.1 * res.fit.loss_initial);
    const double c4 = rcm::time_scale(res.fit.coefficients);  // the targets do not pin c4 alone (g3 moves hands too)
    CHECK(c4 < 1.0);
    CHECK(res.motion.frames == static_cast<std::size_t>(std::llround(static_cast<double>(c.frames - 1) / c4)) + 1);
    const auto L0 = test::bone_lengths(c), L1 = test::bone_lengths(res.motion);
    for (std::size_t f = 0; f < res.motion.frames; f += 7)
        for (std::size_t j = 1; j < c.skel.size(); ++j)
            if (static_cast<int>(j) != r.translation_joint) CHECK(L1[f][j] == doctest::Approx(L0[0][j]).epsilon(1e-6));
}

TEST_SUITE_END();
