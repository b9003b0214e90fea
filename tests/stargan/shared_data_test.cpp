// StarGAN cases that read ../shared/data (label shared-data: without the data `--shared-data` exits 77 and is
// reported as skipped, see tests/test_main.cpp): transfer refuses a body clip (Xia) for a hand model,
// a body's root translation (Bandai walk) is stretched in time (both moved unchanged from train_test.cpp);
// load_folder on Bandai and on mixed skeletons, tempo_fit on Bandai (moved from dataset_test.cpp).
#include <doctest/doctest.h>
#include <handemo/motion/synth.hpp>
#include <handemo/stargan.hpp>
#include <handemo/metrics/compare.hpp>
#include <handemo/eval/retargeted.hpp>

#include "helpers.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>
#include <filesystem>

// run by `<program> --shared-data` only (tests/test_main.cpp)
TEST_SUITE_BEGIN("shared-data");

namespace fs = std::filesystem;
using namespace handemo;
using namespace handemo::stargan;

using namespace handemo::test;

TEST_CASE("transfer: shapes, durations from the tempo factors, skeleton and emotion checks")
{
    const auto clips = toy_set();
    const fs::path d = fresh_dir("handemo_train_transfer");
    trainer<hand_tiny> tr(tiny_info(), prepare_data<hand_tiny>(clips, tiny_info()), quiet(10));
    tr.run(d);
    const auto model = load_model(d);
    CHECK(model->info().config == "hand-tiny");
    const clip& in = clips[2].motion;  // gripping neutral
    REQUIRE(clips[2].emotion == "neutral");
    for (const char* e : {"angry", "sad", "neutral"}) {
        const auto r = model->transfer(in, e);
        CHECK(r.motion.skel.size() == 23);
        CHECK(r.motion.fps == in.fps);
        CHECK(r.image.count() == 9);
        CHECK(r.image.joints == 23);
        const double expect = std::round(double(in.frames) * tr.data().tempo[domain_index(tiny_info(), e)]);
        CHECK(double(r.motion.frames) == expect);
        r.motion.validate("out");
    }
    CHECK(model->transfer(in, "sad").motion.frames > in.frames);
    CHECK(model->transfer(in, "angry").motion.frames < in.frames);
    CHECK_THROWS_WITH_AS(model->transfer(in, "bored"), doctest::Contains("bored"), value_error);
    const clip body = read_bvh(fs::path(HANDEMO_SHARED_DIR) / "data" / "xia" / "neutral_16_000.bvh");
    CHECK_THROWS_WITH_AS(model->transfer(body, "sad"), doctest::Contains("wrong skeleton"), shape_error);
}

TEST_CASE("transfer keeps a body's root translation and stretches it in time")
{
    const clip walk = read_bvh(fs::path(HANDEMO_SHARED_DIR) / "data" / "bandai" / "dataset-1_walk_normal_001.bvh");
    const std::size_t n = 2 * walk.frames - 1, J3 = walk.skel.size() * 3;  // twice as slow
    const auto pos = stretch_positions(walk, n);
    REQUIRE(pos.size() == n * J3);
    // frame 2k of the output is frame k of the input; odd frames lie halfway between their neighbours
    for (std::size_t k = 0; k < walk.frames; ++k)
        for (std::size_t i = 0; i < J3; ++i) REQUIRE(pos[2 * k * J3 + i] == doctest::Approx(walk.positions[k * J3 + i]));
    const std::size_t hips = walk.skel.index_of("Hips");
    for (std::size_t k = 0; k + 1 < walk.frames; ++k)
        REQUIRE(pos[(2 * k + 1) * J3 + hips * 3 + 2] ==
                doctest::Approx(0.5 * (walk.position(k, hips, 2) + walk.position(k + 1, hips, 2))));
}

TEST_CASE("load_folder reads the Bandai clips with labels from names and leaves a content out")
{
    const fs::path dir = fs::path(HANDEMO_SHARED_DIR) / "data" / "bandai";
    REQUIRE(fs::is_directory(dir));
    stargan::load_options opt;
    opt.exclude_contents = {"walk", "run", "dash", "walk-back", "walk-left"};
    const auto d = stargan::load_folder(dir, opt);
    CHECK(d.size() == 16);  // bow and bye x 8 styles
    for (const auto& c : d) {
        CHECK((c.content == "bow" || c.content == "bye"));
        CHECK(c.motion.skel.size() == 22);
    }
    const auto contents = stargan::contents_of(d);
    CHECK(contents == std::vector<std::string>{"bow", "bye"});
}

TEST_CASE("load_folder refuses a folder whose clips have different skeletons")
{
    const fs::path dir = fs::temp_directory_path() / "handemo_mixed_skel_test";
    fs::remove_all(dir);
    fs::create_directories(dir);
    write_bvh(dir / "h_wave_neutral_0.bvh", clip::make(hand_skeleton(), 10, 30));
    fs::copy_file(fs::path(HANDEMO_SHARED_DIR) / "data" / "xia" / "neutral_16_000.bvh", dir / "h_wave_sad_0.bvh");
    CHECK_THROWS_AS(stargan::load_folder(dir), shape_error);
    fs::remove_all(dir);
}

TEST_CASE("tempo_fit on Bandai: its choice predicts left-out contents' durations no worse than keeping them")
{
    const fs::path dir = fs::path(HANDEMO_SHARED_DIR) / "data" / "bandai";
    const auto d = stargan::load_folder(dir);
    const std::vector<std::string> domains{"normal", "happy", "sad", "angry", "proud", "not-confident", "tired", "active"};
    const auto r = stargan::tempo_fit(d, domains, "normal");
    for (const auto& c : r.candidates) {
        std::string f;
        for (double x : c.factors) f += " " + std::to_string(x).substr(0, 4);
        MESSAGE("Bandai tempo " << stargan::to_string(c.estimator) << ": LOO-content mean |log error| " << c.cv_error << ", factors" << f);
    }
    MESSAGE("Bandai tempo: chosen " << stargan::to_string(r.estimator));
    CHECK(r.cv_contents == 7);
    CHECK(cv_error_of(r, r.estimator) <= cv_error_of(r, stargan::tempo_estimator::keep));
    // Nested: the whole procedure (including its choice) fitted without each content, scored on that content.
    double chosen = 0, keep = 0;
    const auto contents = stargan::contents_of(d);
    for (const auto& held : contents) {
        std::vector<handemo::labelled_clip> train, test;
        for (const auto& c : d) (c.content == held ? test : train).push_back(c);
        const auto f = stargan::tempo_fit(train, domains, "normal").factors;
        double e = 0, k = 0;
        std::size_t n = 0;
        for (const auto& c : test) {
            if (c.emotion == "normal") continue;
            const auto base = std::find_if(test.begin(), test.end(), [&](const auto& b) { return b.emotion == "normal" && b.take == c.take; });
            REQUIRE(base != test.end());
            const double real = c.motion.duration() / base->motion.duration();
            const auto i = static_cast<std::size_t>(std::find(domains.begin(), domains.end(), c.emotion) - domains.begin());
            e += std::abs(std::log(f[i] / real)), k += std::abs(std::log(real)), ++n;
        }
        chosen += e / static_cast<double>(n), keep += k / static_cast<double>(n);
    }
    chosen /= static_cast<double>(contents.size()), keep /= static_cast<double>(contents.size());
    MESSAGE("Bandai tempo, nested LOO-content mean |log error|: tempo_fit " << chosen << ", keep " << keep);
    CHECK(chosen <= keep);
}


TEST_CASE("retargeted transfer: Bandai held-out clips moved to a foreign CMU-named rig, transferred there and scored back")
{
    // a body model trained (briefly, with the handemo preset) without 'bow'; the held-out bow takes transferred
    // directly and from a foreign rig of the skeleton (CMU names, the rest pose of a real frame, other
    // proportions, metres, channels Z Y X): the keyframe RMSE to the real clip must agree within 0.5 deg
    const fs::path dir = fs::path(HANDEMO_SHARED_DIR) / "data" / "bandai";
    stargan::load_options lo;
    lo.exclude_contents = {"bow"};
    const auto train = stargan::load_folder(dir, lo);
    const auto info = make_info<body_embedded>("body-embedded", body_domains(), "normal");
    train_options opt = handemo_options();
    opt.iters = 20;
    opt.gate_folds = 0;
    opt.log_every = 1000;
    opt.checkpoint_every = 20;
    opt.progress_out = nullptr;
    const fs::path d = fresh_dir("handemo_retargeted_bandai");
    {
        trainer<body_embedded> tr(info, prepare_data<body_embedded>(train, info, opt), opt);
        tr.run(d);
    }
    const auto model = load_model(d);
    CHECK(model->info().skel.has_value());
    const clip input = read_bvh(dir / "dataset-1_bow_normal_001.bvh");
    const auto rig = eval::make_foreign_rig(input.skel, train.front().motion);
    REQUIRE(rig.has_value());
    CHECK(rig->skel.joints[rig->skel.index_of("LeftForeArm")].channels.size() == 3);
    for (const char* style : {"angry", "sad", "happy", "tired"}) {
        const clip real = read_bvh(dir / (std::string("dataset-1_bow_") + style + "_001.bvh"));
        const auto direct = model->transfer(input, style);
        // the Euler branches of the input's first frame, both ways (as the evaluation's variant does)
        capture_options co;
        co.reference.assign(input.frame_angles(0), input.frame_angles(0) + input.skel.size() * 3);
        const auto cr = transfer_capture(*model, retarget::retarget_clip(input, rig->to_foreign), style, {}, co);
        CHECK(cr.retargeted);
        const clip back = retarget::retarget_clip(cr.motion, rig->to_model, co.reference);
        REQUIRE(back.frames == direct.motion.frames);
        const double e_direct = metrics::keyframe_rmse(direct.motion, real), e_retargeted = metrics::keyframe_rmse(back, real);
        INFO(style << ": direct " << e_direct << " deg, retargeted " << e_retargeted << " deg");
        CHECK(std::abs(e_direct - e_retargeted) <= 0.5);
        CHECK(metrics::keyframe_rmse(back, direct.motion) < 0.5);
    }
}

TEST_SUITE_END();
