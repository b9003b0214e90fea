// The circumplex method of the leave-one-content-out evaluation (eval/rcm.hpp, the extension the protocol
// calls): the regression numbers must be those of rcm::evaluate_loo() with the same candidate inputs and weights on
// the same folds (so the fold's analysis is fitted and chosen on the fold's training clips only), every (input,
// target) must give an rcm output, and the analysis of a real clip as an output must be the fold's analysis of that
// clip. No StarGAN is trained here.
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

/// The fold that holds `held` out: its held-out clips in fc.test, the others copied into `train`.
fold_context fold_of(const std::vector<labelled_clip>& clips, const std::string& held, std::vector<labelled_clip>& train)
{
    fold_context fc;
    fc.held_out = held;
    fc.neutral = "neutral";
    for (const auto& c : clips) (c.content == held ? fc.test.push_back(&c) : train.push_back(c));
    fc.train = &train;
    return fc;
}

fold_context pointing_fold(const std::vector<labelled_clip>& clips, std::vector<labelled_clip>& train) { return fold_of(clips, "pointing", train); }

/// What `handemo rcm eval` gives for every content held out in turn, with the extension's fit options and candidates.
rcm::eval_report loo_of(const std::vector<labelled_clip>& clips, const rcm_eval_options& ro)
{
    std::vector<rcm::training_clip> tc;
    std::vector<std::string> group;
    for (const auto& c : clips) tc.push_back({&c.motion, c.emotion, c.content, c.path.filename().string()}), group.push_back(c.content);
    rcm::fit_options fo = ro.fit;
    fo.cluster = false;
    return rcm::evaluate_loo(tc, group, ro.table, "circumplex.json", fo, {rcm::relative_features::off, "neutral", ro.inputs, ro.shrink});
}

}  // namespace

TEST_CASE("rcm extension: regression as rcm eval, rcm outputs, every output analysed, one report section")
{
    // The protocol calls begin_fold() with the fold's training clips, transfer() for each (neutral input,
    // target), score() on every method's output and end_fold(); done here by hand for two folds (the wiring
    // through run_eval() is tested end to end by eval_rcm_cli, which counts the rows in results.csv).
    const auto clips = toy_set(4, 30.0);
    // the default analysis (every input and weight, chosen per fold) and the paper's
    for (const bool paper : {false, true}) {
    CAPTURE(paper);
    rcm_eval_options ro;
    ro.table = rcm::load_circumplex(HANDEMO_RCM_CIRCUMPLEX);
    ro.table_name = "circumplex.json";
    ro.fit.selection.min_features = 8;
    ro.stylise.iterations = 15;
    if (paper) ro.inputs = {rcm::analysis_input::paper}, ro.shrink = {1.0};
    rcm_extension ext(ro);
    CHECK(ext.options_text().find("rcm min_features 8") != std::string::npos);
    CHECK(ext.options_text().find(paper ? "rcm analysis input paper shrink none" : "rcm analysis input auto shrink auto") != std::string::npos);
    eval_result r;
    std::map<std::string, sample_record> real_score;  // held-out clip name -> score() of the clip itself
    std::map<std::string, std::pair<double, double>> real_rank;  // and its circumplex_rank_point()
    std::size_t outputs = 0;
    for (const std::string held : {"patting", "gripping"}) {
        std::vector<labelled_clip> train;
        const fold_context fc = fold_of(clips, held, train);
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
            real_rank[real->path.filename().string()] = ext.circumplex_rank_point(real->motion);
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
    const auto loo = loo_of(clips, ro);
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
        // (c) the point the Spearman correlations rank: the analysis before the pull toward the fold's constant c
        // (the training clips' mean label point), so that the analysis is c + w (point - c), w the fold's weight
        double cv = 0, ca = 0, n = 0;
        for (const auto& c : clips)
            if (c.content != s.fold) cv += ro.table.at(c.emotion, "t").valence, ca += ro.table.at(c.emotion, "t").arousal, n += 1;
        cv /= n, ca /= n;
        const auto& rr = real_rank[s.name];
        CHECK(s.valence == doctest::Approx(cv + e.shrink * (rr.first - cv)).epsilon(1e-9));
        CHECK(s.arousal == doctest::Approx(ca + e.shrink * (rr.second - ca)).epsilon(1e-9));
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
        if (paper) CHECK(f.input == "paper");
        for (const auto& e : loo.samples)
            if (e.held_out == f.fold) CHECK((f.input == e.input && f.shrink == e.shrink));
        if (f.input != "judge") CHECK(f.selected == 8);
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

TEST_CASE("rcm extension: the analysis chosen per fold among every input and weight, as rcm eval chooses it")
{
    // the seven contents of the synthetic set, so that each fold's inner leave-one-content-out has contents to choose on (with the three of
    // toy_set the inner fits cannot run and the choice falls to its first pair, the paper's analysis)
    std::vector<labelled_clip> clips;
    for (auto& it : synthesize_dataset(1, 7, 30.0)) {
        labelled_clip c;
        c.path = it.file_stem + ".bvh";
        const auto n = stargan::parse_clip_name(it.file_stem);
        c.content = n.content, c.emotion = n.emotion, c.take = n.take, c.motion = it.c;
        clips.push_back(std::move(c));
    }
    rcm_eval_options ro;
    ro.table = rcm::load_circumplex(HANDEMO_RCM_CIRCUMPLEX);
    ro.fit.selection.min_features = 12;
    ro.fit.clustering.max_samples = 300;
    ro.synthesis = false;
    rcm_extension ext(ro);
    const auto loo = loo_of(clips, ro);
    std::map<std::string, rcm::eval_sample> by_name;
    for (const auto& s : loo.samples) by_name[s.name] = s;
    bool other_than_paper = false;
    for (const std::string held : {"pushing", "patting"}) {
        std::vector<labelled_clip> train;
        const fold_context fc = fold_of(clips, held, train);
        ext.begin_fold(fc);
        const auto& fi = ext.folds().back();
        CAPTURE(fi.error);
        REQUIRE(fi.error.empty());
        other_than_paper = other_than_paper || fi.input != "paper" || fi.shrink != 1.0;
        for (const auto* c : fc.test) {
            const auto& e = by_name.at(c->path.filename().string());
            CHECK((fi.input == e.input && fi.shrink == e.shrink));
            sample_record s;
            s.target = c->emotion;
            ext.score(s, c->motion);
            CHECK(s.circumplex_valence == doctest::Approx(e.valence).epsilon(1e-9));
            CHECK(s.circumplex_arousal == doctest::Approx(e.arousal).epsilon(1e-9));
        }
    }
    CHECK(other_than_paper);  // the choice did choose
    CHECK(ext.regression().size() == 10);
}
