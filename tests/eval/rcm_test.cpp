// The circumplex method of the leave-one-content-out evaluation (eval/rcm.hpp, the extension the protocol
// calls): the regression numbers must be those of rcm::evaluate_loo() on the same folds (so the fold model is
// fitted on the fold's training clips only), every (input, target) must give an rcm output, and the analysis
// of a real clip as an output must be the fold model's analysis of that clip. No StarGAN is trained here.
#include <doctest/doctest.h>
#include <handemo/eval/rcm.hpp>
#include <handemo/motion/synth.hpp>

#include "../stargan/helpers.hpp"

#include <algorithm>
#include <map>

using namespace handemo;
using namespace handemo::eval;
using namespace handemo::stargan;
using handemo::test::toy_set;

namespace {

/// The fold that holds pointing out: its held-out clips in fc.test, the others copied into `train`.
fold_context pointing_fold(const std::vector<labelled_clip>& clips, std::vector<labelled_clip>& train)
{
    fold_context fc;
    fc.held_out = "pointing";
    for (const auto& c : clips) (c.content == "pointing" ? fc.test.push_back(&c) : train.push_back(c));
    fc.train = &train;
    return fc;
}

}  // namespace

TEST_CASE("rcm extension: regression as rcm eval, rcm outputs, every output analysed, one report section")
{
    // The protocol calls begin_fold() with the fold's training clips, transfer() for each (neutral input,
    // target), score() on every method's output and end_fold(); done here by hand for two folds (the wiring
    // through run_eval() is tested end to end by eval_rcm_cli, which counts the rows in results.csv).
    const auto clips = toy_set(4, 30.0);
    rcm_eval_options ro;
    ro.table = rcm::load_circumplex(HANDEMO_RCM_CIRCUMPLEX);
    ro.table_name = "circumplex.json";
    ro.fit.selection.min_features = 8;
    ro.stylise.iterations = 15;
    rcm_extension ext(ro);
    CHECK(ext.options_text().find("rcm min_features 8") != std::string::npos);
    eval_result r;
    std::map<std::string, sample_record> real_score;  // held-out clip name -> score() of the clip itself
    std::size_t outputs = 0;
    for (const std::string held : {"patting", "gripping"}) {
        std::vector<labelled_clip> train;
        fold_context fc;
        fc.held_out = held;
        fc.neutral = "neutral";
        for (const auto& c : clips) (c.content == held ? fc.test.push_back(&c) : train.push_back(c));
        fc.train = &train;
        ext.begin_fold(fc);
        const labelled_clip* in = nullptr;
        for (const auto* c : fc.test)
            if (c->emotion == "neutral") in = c;
        REQUIRE(in != nullptr);
        for (const auto* real : fc.test) {
            sample_record s;
            s.target = real->emotion == "neutral" ? "angry" : real->emotion;
            ext.score(s, real->motion);
            real_score[real->path.filename().string()] = s;
            if (real->emotion == "neutral") continue;
            const auto out = ext.transfer(*in, real->emotion);
            REQUIRE(out.size() == 1);
            CHECK(out[0].first == "rcm");
            const clip& o = out[0].second;
            CHECK_NOTHROW(o.validate("rcm output"));
            CHECK(o.skel.same_topology(in->motion.skel));
            double change = 0;  // the synthesis moved the clip
            const std::size_t n = std::min(o.angles.size(), in->motion.angles.size());
            for (std::size_t i = 0; i < n; ++i) change = std::max(change, std::abs(o.angles[i] - in->motion.angles[i]));
            CHECK((change > 0.1 || o.frames != in->motion.frames));
            sample_record so;
            so.target = real->emotion;
            ext.score(so, o);
            CHECK(!std::isnan(so.circumplex_quadrant_ok));
            ++outputs;
        }
        r.folds.push_back({});
        r.folds.back().held_out = held;
        ext.end_fold(r);
    }
    CHECK(outputs == 8);

    // (a) regression: the same numbers as `handemo rcm eval` (rcm::evaluate_loo) holding out the same contents,
    // so the fold model saw the training clips only
    std::vector<rcm::training_clip> tc;
    std::vector<std::string> group;
    for (const auto& c : clips) tc.push_back({&c.motion, c.emotion, c.content, c.path.filename().string()}), group.push_back(c.content);
    rcm::fit_options fo = ro.fit;
    fo.cluster = false;
    const auto loo = rcm::evaluate_loo(tc, group, ro.table, "circumplex.json", fo);
    std::map<std::string, rcm::eval_sample> by_name;
    for (const auto& s : loo.samples) by_name[s.name] = s;
    const auto& reg = ext.regression();
    REQUIRE(reg.size() == 10);  // 2 folds x 5 held-out clips
    for (const auto& s : reg) {
        CAPTURE(s.name);
        REQUIRE(by_name.count(s.name) == 1);
        const auto& e = by_name[s.name];
        CHECK(e.held_out == s.fold);
        CHECK(s.valence == doctest::Approx(e.valence).epsilon(1e-9));
        CHECK(s.arousal == doctest::Approx(e.arousal).epsilon(1e-9));
        CHECK(s.distance == doctest::Approx(e.distance).epsilon(1e-9));
        CHECK(s.quadrant_ok == e.quadrant_ok);
        CHECK(s.baseline_distance == doctest::Approx(e.baseline_distance).epsilon(1e-9));
        // (b) a score of the real clip (the "real" row) is the regression's analysis of that clip
        const auto& rs = real_score[s.name];
        CHECK(rs.circumplex_valence == doctest::Approx(s.valence).epsilon(1e-9));
        CHECK(rs.circumplex_arousal == doctest::Approx(s.arousal).epsilon(1e-9));
        if (s.emotion != "neutral") CHECK((rs.circumplex_quadrant_ok > 0.5) == s.quadrant_ok);
    }
    const auto pooled = rcm_extension::pool(reg);
    double d = 0, q = 0;  // rcm eval's pooled numbers over the same two folds (it ran all three)
    for (const auto& s : loo.samples)
        if (s.held_out != "pointing") d += s.distance / 10.0, q += s.quadrant_ok / 10.0;
    CHECK(pooled.distance == doctest::Approx(d).epsilon(1e-9));
    CHECK(pooled.quadrant == doctest::Approx(q));
    REQUIRE(ext.folds().size() == 2);
    for (const auto& f : ext.folds()) {
        CHECK(f.error.empty());
        CHECK(f.selected == 8);
        CHECK(f.stylise_failed == 0);
        CHECK(f.stylised == 4);
    }

    // (c) one section, replaced after each fold, and its per-clip CSV
    REQUIRE(r.sections.size() == 1);
    const auto& sec = r.sections[0];
    CHECK(sec.title == "Circumplex (Aristidou et al. 2017)");
    CHECK(sec.markdown.find("| patting | 5 |") != std::string::npos);
    CHECK(sec.markdown.find("| gripping | 5 |") != std::string::npos);
    CHECK(sec.markdown.find("Pooled over the 10 held-out clips") != std::string::npos);
    CHECK(sec.file == "rcm_regression.csv");
    CHECK(std::count(sec.file_text.begin(), sec.file_text.end(), '\n') == 11);  // header + 10 clips
}

TEST_CASE("rcm extension: regression only, no rcm rows")
{
    const auto clips = toy_set(4, 30.0);
    rcm_eval_options ro;
    ro.table = rcm::load_circumplex(HANDEMO_RCM_CIRCUMPLEX);
    ro.fit.selection.min_features = 8;
    ro.synthesis = false;
    rcm_extension ext(ro);
    std::vector<labelled_clip> train;
    fold_context fc;
    fc.held_out = "pointing";
    fc.neutral = "neutral";
    for (const auto& c : clips) (c.content == "pointing" ? fc.test.push_back(&c) : train.push_back(c));
    fc.train = &train;
    ext.begin_fold(fc);
    CHECK(ext.regression().size() == 5);
    const labelled_clip* in = fc.test.front();
    CHECK(ext.transfer(*in, "happy").empty());
    sample_record s;
    s.target = "sad";
    ext.score(s, in->motion);
    CHECK((s.circumplex_quadrant_ok == 0.0 || s.circumplex_quadrant_ok == 1.0));
    eval_result r;
    ext.end_fold(r);
    ext.end_fold(r);  // replaces its section, never adds a second one
    REQUIRE(r.sections.size() == 1);
    CHECK(r.sections[0].file == "rcm_regression.csv");
    CHECK(r.sections[0].markdown.find("rcm outputs") == std::string::npos);
}

TEST_CASE("rcm extension: a label without coordinates fails the fold's fit, named in the report")
{
    auto clips = toy_set(4, 30.0);
    for (auto& c : clips)
        if (c.emotion == "fearful") c.emotion = "bored";  // not in the table
    rcm_eval_options ro;
    ro.table = rcm::load_circumplex(HANDEMO_RCM_CIRCUMPLEX);
    rcm_extension ext(ro);
    std::vector<labelled_clip> train;
    const fold_context fc = pointing_fold(clips, train);
    ext.begin_fold(fc);
    REQUIRE(ext.folds().size() == 1);
    CHECK(ext.folds()[0].error.find("'bored'") != std::string::npos);
    CHECK(ext.regression().empty());
    CHECK(ext.transfer(*fc.test.front(), "happy").empty());
    eval_result r;
    ext.end_fold(r);
    REQUIRE(r.sections.size() == 1);
    CHECK(r.sections[0].markdown.find("fit failed") != std::string::npos);
}

TEST_CASE("rcm extension: a held-out clip or target it cannot place is counted and named, the fold goes on")
{
    auto clips = toy_set(4, 30.0);
    for (auto& c : clips)
        if (c.content == "pointing" && c.emotion == "fearful") c.emotion = "bored";  // held out only: the fit works
    rcm_eval_options ro;
    ro.table = rcm::load_circumplex(HANDEMO_RCM_CIRCUMPLEX);
    ro.fit.selection.min_features = 8;
    ro.stylise.iterations = 5;
    rcm_extension ext(ro);
    std::vector<labelled_clip> train;
    const fold_context fc = pointing_fold(clips, train);
    ext.begin_fold(fc);
    REQUIRE(ext.folds().size() == 1);
    CHECK(ext.folds()[0].error.empty());
    CHECK(ext.folds()[0].analyse_failed == 1);
    CHECK(ext.folds()[0].first_analyse_error.find("hand_pointing_fearful_0.bvh: rcm: label 'bored'") != std::string::npos);
    CHECK(ext.regression().size() == 4);
    const labelled_clip* in = nullptr;
    for (const auto* c : fc.test)
        if (c->emotion == "neutral") in = c;
    REQUIRE(in != nullptr);
    CHECK(ext.transfer(*in, "bored").empty());
    CHECK(ext.folds()[0].stylise_failed == 1);
    CHECK(ext.transfer(*in, "sad").size() == 1);
    sample_record s;
    s.target = "bored";
    ext.score(s, in->motion);
    CHECK(std::isnan(s.circumplex_quadrant_ok));
    eval_result r;
    ext.end_fold(r);
    REQUIRE(r.sections.size() == 1);
    CHECK(r.sections[0].markdown.find("1 held-out clip(s) could not be analysed") != std::string::npos);
    CHECK(r.sections[0].markdown.find("1 (input, target) pair(s) could not be stylised") != std::string::npos);
}
