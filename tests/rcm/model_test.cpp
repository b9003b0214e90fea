// The whole analysis on a small synthetic hand set: fit, exactness at the emotion centres (Eq. 1 and 3),
// analysis, the model file round trip and malformed files, the circumplex table, the evaluation.
#include <handemo/rcm.hpp>
#include <handemo/motion.hpp>

#include <doctest/doctest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>

using namespace handemo;
using doctest::Approx;

namespace {

struct fixture {
    std::vector<synth_item> data = synthesize_dataset(1, 7, 30.0);
    std::vector<rcm::training_clip> clips;
    rcm::circumplex_table table = rcm::load_circumplex(HANDEMO_RCM_CIRCUMPLEX);
    rcm::fit_options opt;
    fixture()
    {
        for (const auto& it : data) clips.push_back({&it.c, std::string(to_string(it.emo)), std::string(to_string(it.motion)), it.file_stem});
        opt.clustering.max_samples = 300;
        opt.selection.min_features = 12;
    }
};

const fixture& shared()
{
    static const fixture f;
    return f;
}

const rcm::rcm_model& fitted()
{
    static const rcm::rcm_model m = rcm::fit_model(shared().clips, shared().table, "circumplex.json", shared().opt);
    return m;
}

/// Each clip's content, the group of a leave-one-content-out.
std::vector<std::string> content_groups()
{
    std::vector<std::string> group;
    for (const auto& c : shared().clips) group.push_back(c.performer);
    return group;
}

/// The fixture's fit options without pose clusters (the evaluation's).
rcm::fit_options loo_fit_options()
{
    auto opt = shared().opt;
    opt.cluster = false;
    return opt;
}

/// The fixture's clips of every content but one.
std::vector<rcm::training_clip> clips_without(const std::string& content)
{
    std::vector<rcm::training_clip> out;
    for (const auto& c : shared().clips)
        if (c.performer != content) out.push_back(c);
    return out;
}

/// The fixture's first content held out: its clips and neutral clips; the training clips are the others.
struct held_out_fold {
    std::string held;
    std::vector<rcm::training_clip> train;
    std::vector<const clip*> neutrals, test;
};

held_out_fold first_content_held_out()
{
    held_out_fold f;
    f.held = shared().clips.front().performer;
    f.train = clips_without(f.held);
    for (const auto& c : shared().clips)
        if (c.performer == f.held) {
            f.test.push_back(c.motion);
            if (c.emotion == "neutral") f.neutrals.push_back(c.motion);
        }
    return f;
}

std::filesystem::path tmp_dir()
{
    const auto d = std::filesystem::temp_directory_path() / "handemo_rcm_model_test";
    std::filesystem::create_directories(d);
    return d;
}

}  // namespace

TEST_CASE("circumplex: the label table with its citation")
{
    const auto& t = shared().table;
    CHECK(t.source.find("Warriner") != std::string::npos);
    CHECK(t.at("happy").valence == Approx((8.47 - 5) / 4));
    CHECK(t.at("happy").arousal == Approx((6.05 - 5) / 4));
    CHECK(t.at("sad").valence < 0);
    CHECK(t.at("sad").arousal < 0);
    for (const char* l : {"active", "angry", "happy", "normal", "not-confident", "proud", "sad", "tired", "neutral", "fearful"})
        CHECK_NOTHROW(t.at(l));
    CHECK_THROWS_WITH_AS(t.at("bored", "x.json"), doctest::Contains("'bored'"), value_error);
    CHECK(rcm::quadrant(0.5, 0.5) == 1);
    CHECK(rcm::quadrant(-0.5, 0.5) == 2);
    CHECK(rcm::quadrant(-0.5, -0.5) == 3);
    CHECK(rcm::quadrant(0.5, -0.5) == 4);
    CHECK_THROWS_WITH_AS(rcm::parse_circumplex(R"({"format": "handemo-rcm-circumplex", "version": 1, "labels": {}})", "c.json"),
                         doctest::Contains("c.json: missing field 'source'"), format_error);
    CHECK_THROWS_WITH_AS(rcm::parse_circumplex(R"({"format": "handemo-rcm-circumplex", "version": 1, "source": "x",
                                                  "labels": {"a": {"valence": 2, "arousal": 0}}})", "c.json"),
                         doctest::Contains("labels.a."), format_error);
}

TEST_CASE("model: fit on the synthetic hand set")
{
    const auto& m = fitted();
    CHECK(m.features == rcm::feature_set::hand);
    CHECK(m.labels.size() == 5);
    CHECK(m.selected.size() >= 12);
    CHECK(m.pca.dims() >= 1);
    CHECK(m.pca.dims() <= m.selected.size());
    CHECK(m.has_clusters);
    CHECK(m.clusters.count() == 5);
    CHECK(m.cluster_selected.size() == 5);
    CHECK(m.selection.performers == 7);  // the contents
    CHECK(m.selection.emotions == 5);
    // Eq. 1 passes through each emotion's coordinates at that emotion's mean features
    for (std::size_t k = 0; k < m.labels.size(); ++k) {
        const rcm::vector c = xt::view(m.to_emotion.centres, k, xt::all());
        const auto e = m.to_emotion(c);
        CHECK(e(0) == Approx(m.labels[k].valence));
        CHECK(e(1) == Approx(m.labels[k].arousal));
    }
    // Eq. 3 gives each emotion's mean selected features at its coordinates
    const auto& sh = shared();
    const std::string emo = "sad";
    const auto& d = rcm::derived_features(m.features);
    (void)d;
    rcm::vector mean = xt::zeros<double>({m.selected.size()});
    double n = 0;
    for (const auto& c : sh.clips) {
        if (c.emotion != emo) continue;
        const auto r = m.roles_for(c.motion->skel);
        mean += m.selected_features(rcm::world_positions(*c.motion), c.motion->fps, r);
        n += 1;
    }
    mean /= n;
    const auto& l = sh.table.at(emo);
    const auto want = m.desired_features(l.valence, l.arousal);
    for (std::size_t i = 0; i < mean.size(); ++i) CHECK(want(i) == Approx(mean(i)).epsilon(1e-6));
}

TEST_CASE("model: analysis is Eq. 1 at each emotion's mean features, clamped to the diagram beyond it")
{
    const auto& m = fitted();
    const auto& sh = shared();
    // PCA is affine, so each emotion's mean selected features project onto its centre, where Eq. 1 gives that
    // emotion's coordinates: inside the diagram, nothing is clamped
    std::map<std::string, rcm::vector> mean;
    std::map<std::string, double> count;
    for (const auto& c : sh.clips) {
        const auto s = m.selected_features(rcm::world_positions(*c.motion), c.motion->fps, m.roles_for(c.motion->skel));
        if (!mean.count(c.emotion)) mean[c.emotion] = xt::zeros<double>({m.selected.size()});
        mean[c.emotion] += s;
        count[c.emotion] += 1;
    }
    REQUIRE(mean.size() == 5);
    std::set<int> quadrants;
    for (auto& [emo, s] : mean) {
        CAPTURE(emo);
        s /= count[emo];
        const auto& l = sh.table.at(emo);
        const auto a = m.analyse_features(s);
        CHECK(a.valence == Approx(l.valence).epsilon(1e-6));
        CHECK(a.arousal == Approx(l.arousal).epsilon(1e-6));
        CHECK(a.raw_valence == a.valence);
        CHECK(a.raw_arousal == a.arousal);
        CHECK(a.quadrant == rcm::quadrant(l.valence, l.arousal));
        quadrants.insert(a.quadrant);
    }
    CHECK(quadrants == std::set<int>{1, 2, 3, 4});  // the five emotions cover every quadrant
    // a clip's analysis is that of its selected features
    const clip& first = sh.data.front().c;
    const auto a = m.analyse(first);
    const auto b = m.analyse_features(m.selected_features(rcm::world_positions(first), first.fps, m.roles_for(first.skel)));
    CHECK(a.valence == b.valence);
    CHECK(a.arousal == b.arousal);
    CHECK(a.raw_valence == b.raw_valence);
    // far beyond happy on the line from sad (Eq. 1's linear term grows without bound there): the raw values pass
    // the edge, the analysis stops at it and keeps the raw point
    rcm::analysis far;
    for (double t = 1; t < 1e9 && std::max(std::abs(far.raw_valence), std::abs(far.raw_arousal)) <= 1.5; t *= 2)
        far = m.analyse_features(mean["happy"] + t * (mean["happy"] - mean["sad"]));
    REQUIRE(std::max(std::abs(far.raw_valence), std::abs(far.raw_arousal)) > 1.5);
    const auto edge = [](double raw) { return raw > 1 ? 1.0 : raw < -1 ? -1.0 : raw; };
    CHECK(far.valence == edge(far.raw_valence));
    CHECK(far.arousal == edge(far.raw_arousal));
    CHECK(std::max(std::abs(far.valence), std::abs(far.arousal)) == 1.0);
    CHECK(far.quadrant == rcm::quadrant(far.raw_valence, far.raw_arousal));
    // a body clip has no hand roles
    auto body = clip::make(skeleton{"b", {joint{"Hips", -1}, joint{"Head", 0}}}, 40, 30);
    CHECK_THROWS_WITH_AS(m.analyse(body), doctest::Contains("role 'wrist'"), value_error);
}

TEST_CASE("model: file round trip")
{
    const auto& m = fitted();
    const auto path = tmp_dir() / "model.json";
    rcm::save_model(m, path);
    const auto m2 = rcm::load_model(path);
    CHECK(rcm::model_to_json(m2) == rcm::model_to_json(m));
    const auto a = m.analyse(shared().data[3].c), b = m2.analyse(shared().data[3].c);
    CHECK(a.valence == b.valence);
    CHECK(a.arousal == b.arousal);
}

TEST_CASE("model: malformed files are errors naming the file and the field")
{
    const auto good = rcm::model_to_json(fitted());
    const auto dir = tmp_dir();
    auto expect = [&](nlohmann::json j, const std::string& field) {
        const auto p = dir / "bad.json";
        std::ofstream(p) << j.dump();
        const std::string want = "bad.json: field '" + field + "'";
        CHECK_THROWS_WITH_AS(rcm::load_model(p), doctest::Contains(want.c_str()), format_error);
    };
    auto j = good;
    j.erase("pca");
    expect(j, "pca");
    j = good;
    j["version"] = 3;  // 1 and 2 are read
    expect(j, "version");
    j = good;
    j["format"] = "something-else";
    expect(j, "format");
    j = good;
    j["pca"]["mean"].push_back(1.0);
    expect(j, "pca.mean");
    j = good;
    j["to_emotion"]["sigma"] = -1;
    expect(j, "to_emotion.sigma");
    j = good;
    j["to_features"]["lambda"][0][0] = "x";
    expect(j, "to_features.lambda[0][0]");
    j = good;
    j["selected"][0] = 5000;
    expect(j, "selected[0]");
    j = good;
    j["labels"][0]["valence"] = 3;
    expect(j, "labels[0].valence");
    j = good;
    j["feature_set"] = "tail";
    expect(j, "feature_set");
    j = good;
    j["clusters"]["medoids"][0]["q"].erase(0);
    expect(j, "clusters.medoids[0].q");
    std::ofstream(dir / "notjson.json") << "{ nope";
    CHECK_THROWS_WITH_AS(rcm::load_model(dir / "notjson.json"), doctest::Contains("notjson.json: not JSON"), format_error);
    CHECK_THROWS_AS(rcm::load_model(dir / "missing.json"), io_error);
}

TEST_CASE("model: leave-one-content-out evaluation runs every fold")
{
    const auto& sh = shared();
    std::vector<std::string> group;
    for (const auto& c : sh.clips) group.push_back(c.performer);
    auto opt = sh.opt;
    opt.cluster = false;
    const auto r = rcm::evaluate_loo(sh.clips, group, sh.table, "circumplex.json", opt);
    CHECK(r.folds.size() == 7);
    // every fold fits and analyses its five held-out clips (a fold that failed would leave its clips out)
    CHECK(r.failed_folds.empty());
    REQUIRE(r.samples.size() == sh.clips.size());
    std::map<std::string, std::set<std::string>> held;  // fold -> emotions of its held-out clips
    double distance = 0, quadrant_ok = 0;
    for (std::size_t i = 0; i < r.samples.size(); ++i) {
        const auto& s = r.samples[i];
        CAPTURE(s.name);
        held[s.held_out].insert(s.emotion);
        const auto& l = sh.table.at(s.emotion);
        CHECK(s.true_valence == l.valence);
        CHECK(s.true_arousal == l.arousal);
        CHECK(s.distance == Approx(std::hypot(s.valence - l.valence, s.arousal - l.arousal)));
        CHECK(s.quadrant_ok == (rcm::quadrant(s.valence, s.arousal) == rcm::quadrant(l.valence, l.arousal)));
        distance += s.distance / static_cast<double>(r.samples.size());
        quadrant_ok += s.quadrant_ok ? 1 : 0;
    }
    CHECK(held.size() == 7);
    for (const auto& [fold, emotions] : held) CHECK(emotions.size() == 5);
    CHECK(r.mean_distance == Approx(distance));
    CHECK(r.quadrant_accuracy == Approx(quadrant_ok / static_cast<double>(r.samples.size())));
    CHECK(r.mean_distance > 0);  // held-out clips are not the training means
    CHECK(r.mean_selected >= 12);
    CHECK(r.mean_pca_dims >= 1);
}

TEST_CASE("model: relative features are read against the same content's neutral clips")
{
    const auto& sh = shared();
    rcm::feature_set fs{};
    const auto roles = rcm::training_roles(sh.clips.front().motion->skel, nlohmann::json::object(), &fs);
    const auto feats = rcm::compute_features(sh.clips, roles, fs, sh.opt.lma, false);
    const auto rel = rcm::detail::relative_to_neutral(sh.clips, feats, "neutral");
    REQUIRE(rel.size() == feats.size());
    for (std::size_t i = 0; i < sh.clips.size(); ++i) {
        CAPTURE(sh.clips[i].name);
        // one neutral take per content here: its relative features are exactly zero, every other clip's are its
        // features minus that take's
        std::size_t ref = sh.clips.size();
        for (std::size_t j = 0; j < sh.clips.size(); ++j)
            if (sh.clips[j].performer == sh.clips[i].performer && sh.clips[j].emotion == "neutral") ref = j;
        REQUIRE(ref < sh.clips.size());
        for (std::size_t d = 0; d < feats[i].mean.size(); ++d) CHECK(rel[i].mean(d) == feats[i].mean(d) - feats[ref].mean(d));
    }
    // two neutral takes of a content: the reference is their mean
    auto two = sh.clips;
    auto feats2 = feats;
    for (std::size_t i = 0; i < sh.clips.size(); ++i)
        if (sh.clips[i].emotion == "neutral") {
            two.push_back(sh.clips[i]);
            feats2.push_back(feats[i]);
            feats2.back().mean = feats[i].mean + 2.0;
            break;
        }
    const auto rel2 = rcm::detail::relative_to_neutral(two, feats2, "neutral");
    CHECK(rel2.back().mean(0) == Approx(1.0));  // (x + 2) - mean(x, x + 2)
    // a content without a neutral clip is named
    std::vector<rcm::training_clip> none;
    for (const auto& c : sh.clips)
        if (!(c.performer == sh.clips.front().performer && c.emotion == "neutral")) none.push_back(c);
    std::vector<rcm::clip_feature_data> feats3;
    for (std::size_t i = 0; i < sh.clips.size(); ++i)
        if (!(sh.clips[i].performer == sh.clips.front().performer && sh.clips[i].emotion == "neutral")) feats3.push_back(feats[i]);
    const std::string missing = "'" + sh.clips.front().performer + "' has no 'neutral' clip";
    CHECK_THROWS_WITH_AS(rcm::detail::relative_to_neutral(none, feats3, "neutral"), doctest::Contains(missing.c_str()), value_error);
    CHECK(rcm::parse_relative_features("auto") == rcm::relative_features::automatic);
    CHECK_THROWS_WITH_AS(rcm::parse_relative_features("yes"), doctest::Contains("--relative yes"), value_error);
}

TEST_CASE("model: leave-one-content-out with relative features: every fold, the non-neutral means, the choice")
{
    const auto& sh = shared();
    std::vector<std::string> group;
    for (const auto& c : sh.clips) group.push_back(c.performer);
    auto opt = sh.opt;
    opt.cluster = false;
    CHECK_THROWS_WITH_AS(rcm::evaluate_loo(sh.clips, group, sh.table, "circumplex.json", opt, {rcm::relative_features::on, ""}),
                         doctest::Contains("need the neutral label"), value_error);
    const auto off = rcm::evaluate_loo(sh.clips, group, sh.table, "circumplex.json", opt, {rcm::relative_features::off, "neutral"});
    const auto on = rcm::evaluate_loo(sh.clips, group, sh.table, "circumplex.json", opt, {rcm::relative_features::on, "neutral"});
    const auto aut = rcm::evaluate_loo(sh.clips, group, sh.table, "circumplex.json", opt, {rcm::relative_features::automatic, "neutral"});
    // off is the paper's analysis: the numbers of the call without loo_options
    const auto plain = rcm::evaluate_loo(sh.clips, group, sh.table, "circumplex.json", opt);
    CHECK(off.mean_distance == plain.mean_distance);
    CHECK(off.relative_folds == 0);
    REQUIRE(on.failed_folds.empty());
    CHECK(on.relative_folds == 7);
    CHECK(on.mean_distance != off.mean_distance);
    for (const auto* r : {&off, &on, &aut}) {
        double d = 0, b = 0, n = 0;
        for (const auto& s : r->samples) {
            CHECK(s.neutral == (s.emotion == "neutral"));
            if (s.neutral) continue;
            d += s.distance, b += s.baseline_distance, n += 1;
        }
        REQUIRE(n == 28);
        CHECK(r->emotional_distance == Approx(d / n));
        CHECK(r->emotional_baseline_distance == Approx(b / n));
    }
    // auto takes, fold by fold, exactly the samples of off or of on
    std::size_t relative_folds = 0;
    for (const auto& f : aut.folds) {
        bool rel = false, seen = false;
        for (std::size_t i = 0; i < aut.samples.size(); ++i) {
            if (aut.samples[i].held_out != f) continue;
            const auto& same = aut.samples[i].relative ? on.samples[i] : off.samples[i];
            CHECK(aut.samples[i].valence == same.valence);
            CHECK(aut.samples[i].arousal == same.arousal);
            if (seen) CHECK(aut.samples[i].relative == rel);
            rel = aut.samples[i].relative, seen = true;
        }
        relative_folds += rel ? 1 : 0;
        // the rule: relative when an inner leave-one-content-out on the fold's training clips (itself an
        // evaluate_loo on them) gives relative features the lower mean distance over the non-neutral clips
        std::vector<rcm::training_clip> inner;
        std::vector<std::string> inner_group;
        for (const auto& c : sh.clips)
            if (c.performer != f) inner.push_back(c), inner_group.push_back(c.performer);
        const auto io = rcm::evaluate_loo(inner, inner_group, sh.table, "circumplex.json", opt, {rcm::relative_features::off, "neutral"});
        const auto ir = rcm::evaluate_loo(inner, inner_group, sh.table, "circumplex.json", opt, {rcm::relative_features::on, "neutral"});
        REQUIRE((io.failed_folds.empty() && ir.failed_folds.empty()));
        CAPTURE(f);
        CHECK(rel == (ir.emotional_distance < io.emotional_distance));
    }
    CHECK(aut.relative_folds == relative_folds);
}

TEST_CASE("model: the variants' parts: shrinkage toward the constant, the inner choice, cluster weights")
{
    // shrink_toward: s = 1 keeps the point, s = 0 answers the constant, s = 0.5 the midpoint, quadrant anew
    rcm::analysis p;
    p.valence = p.raw_valence = 0.6, p.arousal = 0.4, p.raw_arousal = 1.4;
    const auto keep = rcm::shrink_toward(p, -0.2, -0.4, 1.0);
    CHECK(keep.valence == Approx(0.6));
    CHECK(keep.raw_arousal == Approx(1.4));
    const auto none = rcm::shrink_toward(p, -0.2, -0.4, 0.0);
    CHECK(none.valence == Approx(-0.2));
    CHECK(none.arousal == Approx(-0.4));
    CHECK(none.quadrant == 3);
    const auto half = rcm::shrink_toward(p, -0.2, -0.4, 0.5);
    CHECK(half.valence == Approx(0.2));
    CHECK(half.arousal == Approx(0.0));
    CHECK(half.raw_arousal == Approx(0.5));
    // choose_variant: input 0 points away from the labels (best weight 0: the constant), input 1 overshoots them
    // twice (weight 0.5 lands on them)
    const std::vector<rcm::label_point> truth{{"a", 0.8, 0.2}, {"b", -0.6, -0.4}}, constant{{"c", 0, 0}, {"c", 0, 0}};
    auto point = [](double v, double a) {
        rcm::analysis x;
        x.valence = x.raw_valence = v, x.arousal = x.raw_arousal = a;
        return x;
    };
    const std::vector<std::vector<rcm::analysis>> pred{{point(-0.8, -0.2), point(0.6, 0.4)}, {point(1.6, 0.4), point(-1.2, -0.8)}};
    const auto grid = rcm::shrink_grid();
    REQUIRE(grid.size() == 11);
    CHECK(grid.front() == 1.0);
    CHECK(grid.back() == 0.0);
    const auto both = rcm::choose_variant(pred, constant, truth, grid);
    CHECK(both.input == 1);
    CHECK(both.shrink == Approx(0.5));
    CHECK(both.distance == Approx(0.0).epsilon(1e-12));
    const auto only0 = rcm::choose_variant({pred[0]}, constant, truth, grid);
    CHECK(only0.input == 0);
    CHECK(only0.shrink == 0.0);
    CHECK(only0.distance == Approx((std::hypot(0.8, 0.2) + std::hypot(0.6, 0.4)) / 2));
    const auto fixed = rcm::choose_variant(pred, constant, truth, {1.0});  // no shrinkage: |2l - l| = |l| beats input 0
    CHECK(fixed.input == 1);
    CHECK(fixed.distance == Approx((std::hypot(0.8, 0.2) + std::hypot(0.6, 0.4)) / 2));
    const auto tie = rcm::choose_variant({pred[1], pred[1]}, constant, truth, grid);  // a tie goes to the earlier input
    CHECK(tie.input == 0);
    CHECK_THROWS_AS(rcm::choose_variant({{point(0, 0)}}, constant, truth, grid), shape_error);
    // weighted_point: weights normalised to sum to 1
    const auto w = rcm::weighted_point({point(1, 0), point(0, 1)}, {30, 10});
    CHECK(w.valence == Approx(0.75));
    CHECK(w.arousal == Approx(0.25));
    CHECK_THROWS_AS(rcm::weighted_point({point(1, 0)}, {0}), value_error);
    // window shares: per cluster, summing to 1
    const auto sh = rcm::detail::window_shares({0, 0, 2, 1}, 3);
    CHECK(sh == std::vector<double>{0.5, 0.25, 0.25});
    // the options' text
    CHECK(rcm::parse_shrink("none") == std::vector<double>{1.0});
    CHECK(rcm::parse_shrink("0.3") == std::vector<double>{0.3});
    CHECK_THROWS_WITH_AS(rcm::parse_shrink("1.5"), doctest::Contains("--shrink 1.5"), value_error);
    CHECK_THROWS_AS(rcm::parse_shrink("0.3x"), value_error);
    CHECK(rcm::parse_analysis_inputs("auto").size() == 4);
    CHECK(rcm::parse_analysis_inputs("judge") == std::vector<rcm::analysis_input>{rcm::analysis_input::judge});
    CHECK_THROWS_WITH_AS(rcm::parse_analysis_inputs("pca"), doctest::Contains("--input pca"), value_error);
}

TEST_CASE("model: the judge's features are read against the same content's neutral clips")
{
    const auto& sh = shared();
    const auto judge = rcm::detail::judge_features(sh.clips, "neutral");
    REQUIRE(judge.size() == sh.clips.size());
    const std::size_t J = sh.clips.front().motion->skel.size();
    for (std::size_t i = 0; i < sh.clips.size(); ++i) {
        CAPTURE(sh.clips[i].name);
        REQUIRE(judge[i].mean.size() == metrics::full_rate_change_count(J));
        std::size_t ref = 0;
        for (std::size_t j = 0; j < sh.clips.size(); ++j)
            if (sh.clips[j].performer == sh.clips[i].performer && sh.clips[j].emotion == "neutral") ref = j;
        // one neutral take per content: exactly the judge's change against it (zero for that take itself)
        const auto want = metrics::full_rate_change(metrics::full_rate_features(*sh.clips[i].motion), metrics::full_rate_features(*sh.clips[ref].motion));
        for (std::size_t d = 0; d < want.size(); ++d) CHECK(judge[i].mean(d) == Approx(want[d]));
    }
}

TEST_CASE("model: leave-one-content-out with candidate inputs and shrinkage")
{
    const auto& sh = shared();
    const std::vector<std::string> group = content_groups();
    const auto opt = loo_fit_options();
    const std::string file = "circumplex.json";
    using rcm::analysis_input;
    // weight 0 is the constant predictor, exactly
    const auto zero = rcm::evaluate_loo(sh.clips, group, sh.table, file, opt, {rcm::relative_features::off, "neutral", {}, {0.0}});
    REQUIRE(zero.samples.size() == sh.clips.size());
    for (const auto& s : zero.samples) CHECK(s.distance == Approx(s.baseline_distance).epsilon(1e-12));
    CHECK(zero.mean_shrink == 0.0);
    // each input alone fits every fold; the judge keeps every one of its features
    std::map<analysis_input, rcm::eval_report> single;
    for (auto v : {analysis_input::paper, analysis_input::relative, analysis_input::clusters, analysis_input::judge}) {
        CAPTURE(rcm::to_string(v));
        single[v] = rcm::evaluate_loo(sh.clips, group, sh.table, file, opt, {rcm::relative_features::off, "neutral", {v}, {}});
        CHECK(single[v].failed_folds.empty());
        CHECK(single[v].input_folds.at(rcm::to_string(v)) == 7);
        for (const auto& s : single[v].samples) CHECK((std::abs(s.valence) <= 1 && std::abs(s.arousal) <= 1));
    }
    CHECK(single[analysis_input::judge].mean_selected == metrics::full_rate_change_count(sh.clips.front().motion->skel.size()));
    CHECK(single[analysis_input::clusters].mean_distance != single[analysis_input::paper].mean_distance);
    const auto plain = rcm::evaluate_loo(sh.clips, group, sh.table, file, opt);
    CHECK(single[analysis_input::paper].mean_distance == plain.mean_distance);
    CHECK(single[analysis_input::relative].mean_distance ==
          rcm::evaluate_loo(sh.clips, group, sh.table, file, opt, {rcm::relative_features::on, "neutral"}).mean_distance);
    CHECK_THROWS_WITH_AS(rcm::evaluate_loo(sh.clips, group, sh.table, file, opt, {rcm::relative_features::on, "neutral", {analysis_input::judge}, {}}),
                         doctest::Contains("not both"), value_error);
    CHECK_THROWS_WITH_AS(rcm::evaluate_loo(sh.clips, group, sh.table, file, opt, {rcm::relative_features::off, "", {analysis_input::judge}, {}}),
                         doctest::Contains("judge features need the neutral label"), value_error);
    // the choice: per fold, the pair of the least inner mean distance; its samples are those of that input alone,
    // shrunk toward the fold's constant predictor by that weight
    const std::vector<analysis_input> cand{analysis_input::paper, analysis_input::relative, analysis_input::judge};
    const auto aut = rcm::evaluate_loo(sh.clips, group, sh.table, file, opt, {rcm::relative_features::off, "neutral", cand, rcm::shrink_grid()});
    REQUIRE(aut.failed_folds.empty());
    REQUIRE(aut.samples.size() == sh.clips.size());
    std::size_t folds = 0;
    for (const auto& [name, n] : aut.input_folds) folds += n;
    CHECK(folds == 7);
    for (const auto& f : aut.folds) {
        CAPTURE(f);
        std::string input;
        double weight = -1;
        for (std::size_t i = 0; i < aut.samples.size(); ++i) {
            const auto& s = aut.samples[i];
            if (s.held_out != f) continue;
            if (weight < 0) input = s.input, weight = s.shrink;
            CHECK(s.input == input);
            CHECK(s.shrink == weight);
            const auto v = rcm::parse_analysis_inputs(input).front();
            const auto& one = single[v].samples[i];
            // the constant point c of the fold: the baseline of the weight-0 run, same fold, same clip
            const auto& c = zero.samples[i];
            CHECK(s.valence == Approx(c.valence + weight * (one.valence - c.valence)).epsilon(1e-12));
            CHECK(s.arousal == Approx(c.arousal + weight * (one.arousal - c.arousal)).epsilon(1e-12));
        }
        // the rule, from inner runs of each input alone on the fold's training clips
        std::vector<rcm::training_clip> inner;
        std::vector<std::string> inner_group;
        for (const auto& c : sh.clips)
            if (c.performer != f) inner.push_back(c), inner_group.push_back(c.performer);
        std::vector<std::vector<rcm::analysis>> pred;
        std::vector<rcm::label_point> constant, truth;
        const auto inner_zero = rcm::evaluate_loo(inner, inner_group, sh.table, file, opt, {rcm::relative_features::off, "neutral", {}, {0.0}});
        for (auto v : cand) {
            const auto r = rcm::evaluate_loo(inner, inner_group, sh.table, file, opt, {rcm::relative_features::off, "neutral", {v}, {}});
            REQUIRE(r.failed_folds.empty());
            pred.emplace_back();
            for (const auto& s : r.samples)
                if (!s.neutral) {
                    rcm::analysis a;
                    a.valence = s.valence, a.arousal = s.arousal;
                    pred.back().push_back(a);
                }
        }
        for (const auto& s : inner_zero.samples)
            if (!s.neutral) constant.push_back({"c", s.valence, s.arousal}), truth.push_back({s.emotion, s.true_valence, s.true_arousal});
        const auto want = rcm::choose_variant(pred, constant, truth, rcm::shrink_grid());
        CHECK(input == rcm::to_string(cand[want.input]));
        CHECK(weight == want.shrink);
    }
}

TEST_CASE("model: a chosen analysis fitted on a fold's training clips gives that fold's evaluate_loo points")
{
    const auto& sh = shared();
    const std::vector<std::string> group = content_groups();
    const auto opt = loo_fit_options();
    const std::string file = "circumplex.json";
    using rcm::analysis_input;
    const auto all = rcm::parse_analysis_inputs("auto");
    // every input alone (each path of analyse_unshrunk) and the full choice with shrinkage
    std::vector<rcm::loo_options> cases;
    for (auto v : all) cases.push_back({rcm::relative_features::off, "neutral", {v}, {}});
    cases.push_back({rcm::relative_features::off, "neutral", all, rcm::shrink_grid()});
    for (const auto& lo : cases) {
        const std::string name = lo.inputs.size() == 1 ? rcm::to_string(lo.inputs.front()) : "auto";
        CAPTURE(name);
        const auto want = rcm::evaluate_loo(sh.clips, group, sh.table, file, opt, lo);
        REQUIRE(want.failed_folds.empty());
        for (const auto& f : want.folds) {
            CAPTURE(f);
            std::vector<rcm::training_clip> train;
            std::vector<const clip*> neutrals;
            for (const auto& c : sh.clips) {
                if (c.performer != f) train.push_back(c);
                else if (c.emotion == "neutral") neutrals.push_back(c.motion);
            }
            const auto ca = rcm::fit_chosen(train, sh.table, file, opt, lo);
            const auto ref = ca.reference(neutrals, f);
            std::size_t seen = 0;
            for (const auto& s : want.samples) {  // the samples come fold by fold: found by name
                if (s.held_out != f) continue;
                CAPTURE(s.name);
                const auto it = std::find_if(sh.clips.begin(), sh.clips.end(), [&](const rcm::training_clip& c) { return c.name == s.name; });
                REQUIRE(it != sh.clips.end());
                ++seen;
                CHECK(rcm::to_string(ca.input()) == s.input);
                CHECK(ca.shrink() == s.shrink);
                const auto a = ca.analyse(*it->motion, ref, s.name);
                CHECK(a.valence == Approx(s.valence).epsilon(1e-12));
                CHECK(a.arousal == Approx(s.arousal).epsilon(1e-12));
                // the pull toward the constant is an increasing map of the unshrunk point
                const auto u = ca.analyse_unshrunk(*it->motion, ref, s.name);
                CHECK(a.valence == Approx(ca.constant().valence + ca.shrink() * (u.valence - ca.constant().valence)).epsilon(1e-12));
            }
            CHECK(seen == 5);  // the fold's five clips, one per emotion
        }
    }
}

TEST_CASE("model: a chosen analysis names what it cannot read")
{
    const auto& sh = shared();
    const auto opt = loo_fit_options();
    const auto train = clips_without(sh.clips.front().performer);
    for (auto v : {rcm::analysis_input::relative, rcm::analysis_input::judge}) {
        CAPTURE(rcm::to_string(v));
        const auto ca = rcm::fit_chosen(train, sh.table, "circumplex.json", opt, {rcm::relative_features::off, "neutral", {v}, {}});
        CHECK_THROWS_WITH_AS(ca.reference({}, "waving"), doctest::Contains("'waving' has no neutral clip"), value_error);
        CHECK_THROWS_WITH_AS(ca.analyse(*sh.clips.front().motion, rcm::neutral_reference{}, "out.csv"), doctest::Contains("out.csv has no neutral clip"),
                             value_error);
    }
    const auto paper = rcm::fit_chosen(train, sh.table, "circumplex.json", opt, {rcm::relative_features::off, "neutral", {rcm::analysis_input::paper}, {}});
    clip other = *sh.clips.front().motion;
    other.skel.joints.pop_back();
    CHECK_THROWS_WITH_AS(paper.analyse(other, paper.reference({}, "x"), "body.bvh"), doctest::Contains("body.bvh has a skeleton other"), shape_error);
    CHECK_THROWS_WITH_AS(rcm::fit_chosen({}, sh.table, "circumplex.json", opt, {}), doctest::Contains("no training clips"), value_error);
}

TEST_CASE("model: a chosen analysis written with its model and read back analyses as before")
{
    const auto& sh = shared();
    auto opt = sh.opt;
    opt.cluster = false;
    const auto [held, train, neutrals, test] = first_content_held_out();
    const auto m = rcm::fit_model(train, sh.table, "circumplex.json", opt);
    const auto path = tmp_dir() / "chosen.json";
    std::vector<rcm::loo_options> cases;
    for (auto v : rcm::parse_analysis_inputs("auto")) cases.push_back({rcm::relative_features::off, "neutral", {v}, {0.6}});
    cases.push_back({rcm::relative_features::off, "neutral", rcm::parse_analysis_inputs("auto"), rcm::shrink_grid()});
    for (const auto& lo : cases) {
        const std::string name = lo.inputs.size() == 1 ? rcm::to_string(lo.inputs.front()) : "auto";
        CAPTURE(name);
        const auto ca = rcm::fit_chosen(train, sh.table, "circumplex.json", opt, lo);
        rcm::save_model(m, ca, path);
        const auto back = rcm::load_analysis(path);
        CHECK(back.input() == ca.input());
        CHECK(back.shrink() == ca.shrink());
        CHECK(back.needs_neutral() == ca.needs_neutral());
        CHECK(back.neutral_label() == "neutral");
        const auto r0 = ca.reference(neutrals, held), r1 = back.reference(neutrals, held);
        for (const clip* c : test) {
            const auto a = ca.analyse(*c, r0), b = back.analyse(*c, r1);
            CHECK(b.valence == Approx(a.valence).epsilon(1e-9));
            CHECK(b.arousal == Approx(a.arousal).epsilon(1e-9));
        }
        // the file still reads as the model it was (the synthesis uses it)
        CHECK(rcm::load_model(path).selected == m.selected);
    }
    // a version 1 file (no analysis block) is the paper's analysis of its model
    rcm::save_model(m, path);
    const auto paper = rcm::load_analysis(path);
    CHECK(paper.input() == rcm::analysis_input::paper);
    CHECK(paper.shrink() == 1.0);
    for (const clip* c : test) CHECK(paper.analyse(*c, paper.reference({}, held)).valence == Approx(m.analyse(*c).valence).epsilon(1e-9));
}

TEST_CASE("model: the model and the chosen analysis fitted together are the two fitted apart")
{
    const auto& sh = shared();
    const auto& opt = sh.opt;  // pose clusters on: the shared features feed the model's clusters too
    const auto [held, train, neutrals, test] = first_content_held_out();
    const rcm::loo_options lo{rcm::relative_features::off, "neutral", rcm::parse_analysis_inputs("auto"), rcm::shrink_grid()};
    const auto both = rcm::fit_model_and_chosen(train, sh.table, "circumplex.json", opt, lo);
    const auto m = rcm::fit_model(train, sh.table, "circumplex.json", opt);
    const auto ca = rcm::fit_chosen(train, sh.table, "circumplex.json", opt, lo);
    CHECK(both.model.selected == m.selected);
    CHECK(both.model.has_clusters == m.has_clusters);
    CHECK(both.model.cluster_selected == m.cluster_selected);
    CHECK(both.analysis.input() == ca.input());
    CHECK(both.analysis.shrink() == ca.shrink());
    CHECK(both.analysis.inner_distance() == ca.inner_distance());
    const auto r0 = ca.reference(neutrals, held), r1 = both.analysis.reference(neutrals, held);
    for (const clip* c : test) {
        const auto a = m.analyse(*c), b = both.model.analyse(*c);
        CHECK(b.valence == a.valence);
        CHECK(b.arousal == a.arousal);
        const auto x = ca.analyse(*c, r0), y = both.analysis.analyse(*c, r1);
        CHECK(y.valence == x.valence);
        CHECK(y.arousal == x.arousal);
    }
    CHECK_THROWS_WITH_AS(rcm::fit_model_and_chosen({}, sh.table, "circumplex.json", opt, lo), doctest::Contains("rcm fit: no training clips"),
                         value_error);
}

TEST_CASE("model: a malformed analysis block is an error naming the file and the field")
{
    const auto& sh = shared();
    const auto opt = loo_fit_options();
    const auto train = clips_without(sh.clips.front().performer);
    const auto m = rcm::fit_model(train, sh.table, "circumplex.json", opt);
    const auto judge = rcm::fit_chosen(train, sh.table, "circumplex.json", opt, {rcm::relative_features::off, "neutral", {rcm::analysis_input::judge}, {}});
    const auto clusters = rcm::fit_chosen(train, sh.table, "circumplex.json", opt, {rcm::relative_features::off, "neutral", {rcm::analysis_input::clusters}, {}});
    const auto path = tmp_dir() / "bad_analysis.json";
    auto edit = [&](const rcm::chosen_analysis& a, auto&& change) {
        rcm::save_model(m, a, path);
        auto j = nlohmann::json::parse(read_file(path));
        change(j);
        write_file_atomic(path, j.dump());
    };
    auto fails = [&](const std::string& field) {
        CAPTURE(field);
        const std::string want = path.string() + ": field '" + field;
        CHECK_THROWS_WITH_AS(rcm::load_analysis(path), doctest::Contains(want.c_str()), format_error);
    };
    edit(judge, [](auto& j) { j["analysis"]["input"] = "pca"; });
    fails("analysis.input");
    edit(judge, [](auto& j) { j["analysis"]["input"] = "auto"; });
    fails("analysis.input");
    edit(judge, [](auto& j) { j["analysis"]["shrink"] = 1.5; });
    fails("analysis.shrink");
    edit(judge, [](auto& j) { j["analysis"]["neutral"] = ""; });
    fails("analysis.neutral");
    edit(judge, [](auto& j) { j["analysis"]["map"]["pca"].erase("mean"); });
    fails("analysis.map.pca.mean");
    edit(judge, [](auto& j) { j["analysis"]["map"]["selected"][0] = 100000; });
    fails("analysis.map.selected[0]");
    edit(judge, [](auto& j) { j["analysis"]["map"]["to_emotion"]["sigma"] = -1; });
    fails("analysis.map.to_emotion.sigma");
    edit(judge, [](auto& j) { j["analysis"]["candidates"]["inputs"][0] = "x"; });
    fails("analysis.candidates.inputs[0]");
    edit(clusters, [](auto& j) { j["analysis"]["clusters"]["maps"].erase(0); });
    fails("analysis.clusters.maps");
    edit(clusters, [](auto& j) { j["analysis"]["clusters"]["medoids"][0]["q"] = nlohmann::json::array(); });
    fails("analysis.clusters.medoids[0].q");
    edit(judge, [](auto& j) { j.erase("analysis"); });
    fails("analysis");  // version 2 without its block
    edit(judge, [](auto& j) { j["version"] = 3; });
    fails("version");
}
