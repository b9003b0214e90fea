// The analysis on real captures (../shared/data, label shared-data): roles of the Bandai and Xia skeletons,
// features of a Bandai clip, and a fit + analysis on three Bandai contents.
#include <handemo/rcm.hpp>
#include <handemo/motion.hpp>
#include <handemo/stargan/dataset.hpp>

#include <doctest/doctest.h>

#include <cmath>
#include <filesystem>

// run by `<program> --shared-data` only (tests/test_main.cpp)
TEST_SUITE_BEGIN("shared-data");

using namespace handemo;

namespace {
const std::filesystem::path data = std::filesystem::path(HANDEMO_SHARED_DIR) / "data";
}

TEST_CASE("shared data: roles of the Bandai and Xia skeletons")
{
    const auto b = read_bvh(data / "bandai" / "dataset-1_walk_happy_001.bvh");
    const auto rb = rcm::find_roles(b.skel);
    CHECK_NOTHROW(rb.require(rcm::feature_set::body));
    CHECK(rcm::detect_feature_set(rb) == rcm::feature_set::body);
    CHECK(rb.points[rb.at(rcm::role::pelvis)] == "Hips");
    const auto x = read_bvh(data / "xia" / "neutral_16_000.bvh");
    const auto rx = rcm::find_roles(x.skel);
    CHECK_NOTHROW(rx.require(rcm::feature_set::body));
    CHECK(rx.points[rx.at(rcm::role::left_hand)] == "LeftHand");
    // Xia's features are finite
    const auto f = rcm::clip_features(rcm::world_positions(x), x.fps, rx, rcm::feature_set::body);
    for (double v : f) CHECK(std::isfinite(v));
}

TEST_CASE("shared data: Bandai features are finite and plausible")
{
    const auto c = read_bvh(data / "bandai" / "dataset-1_run_angry_001.bvh");
    const auto r = rcm::find_roles(c.skel);
    const auto f = rcm::clip_features(rcm::world_positions(c), c.fps, r, rcm::feature_set::body);
    for (double v : f) CHECK(std::isfinite(v));
    CHECK(f(39) > 50);   // mean pelvis height in cm
    CHECK(f(51) > 50);   // a run moves the pelvis faster than 50 cm/s
    CHECK(f(87) > 30);   // torso height
}

TEST_CASE("shared data: fit on three Bandai contents and analyse a held-out clip")
{
    stargan::load_options lo;
    for (const char* c : {"walk", "walk-back", "walk-left", "bye"})
        lo.exclude_contents.push_back(c);
    const auto items = stargan::load_folder(data / "bandai", lo);  // bow, dash, run
    std::vector<rcm::training_clip> clips;
    for (const auto& it : items) clips.push_back({&it.motion, it.emotion, it.content, it.path.filename().string()});
    REQUIRE(clips.size() >= 16);
    const auto table = rcm::load_circumplex(HANDEMO_RCM_CIRCUMPLEX);
    rcm::fit_options opt;
    opt.cluster = false;
    opt.selection.min_features = 8;
    const auto m = rcm::fit_model(clips, table, "circumplex.json", opt);
    CHECK(m.labels.size() == 8);
    const auto held = read_bvh(data / "bandai" / "dataset-1_walk_sad_001.bvh");
    const auto a = m.analyse(held);
    CHECK(std::abs(a.valence) <= 1);
    CHECK(std::abs(a.arousal) <= 1);
}

TEST_SUITE_END();
