// The circumplex method inside the leave-one-content-out evaluation (eval/rcm.hpp through the protocol's
// extension hook): the regression numbers must be those of rcm::evaluate_loo() on the same folds (so the fold
// model is fitted on the fold's training clips only), the "rcm" rows must be scored like every other method,
// and every output's circumplex analysis must agree with the fold model's analysis of the same clip.
#include <doctest/doctest.h>
#include <handemo/eval/protocol.hpp>
#include <handemo/eval/rcm.hpp>
#include <handemo/motion/synth.hpp>

#include <filesystem>
#include <map>
#include <set>
#include <unistd.h>

namespace fs = std::filesystem;
using namespace handemo;
using namespace handemo::eval;
using namespace handemo::stargan;

namespace {

/// 3 motion types x 5 emotions x 1 take of the synthetic hand set at 30 fps (small and quick).
std::vector<labelled_clip> toy_set()
{
    std::vector<labelled_clip> out;
    for (auto& it : synthesize_dataset(1, 4, 30.0)) {
        if (it.motion != hand_motion::gripping && it.motion != hand_motion::patting && it.motion != hand_motion::pointing) continue;
        labelled_clip c;
        c.path = it.file_stem + ".bvh";
        const auto n = parse_clip_name(it.file_stem);
        c.content = n.content, c.emotion = n.emotion, c.take = n.take, c.motion = it.c;
        out.push_back(std::move(c));
    }
    return out;
}

std::string read_text(const fs::path& p) { return read_file(p); }

}  // namespace

TEST_CASE("rcm extension: regression as rcm eval, rcm rows scored like the others, one report")
{
    const auto clips = toy_set();
    const auto info = make_info<hand_tiny>("hand-tiny", hand_domains(), "neutral");
    rcm_eval_options ro;
    ro.table = rcm::load_circumplex(HANDEMO_RCM_CIRCUMPLEX);
    ro.table_name = "circumplex.json";
    ro.fit.selection.min_features = 8;
    ro.stylise.iterations = 15;
    auto ext = std::make_shared<rcm_extension>(ro);

    eval_options o = {};
    o.train = default_train_options();
    o.train.iters = 4;
    o.train.threads = 1;
    o.train.gate_folds = 0;
    o.folds = {"patting", "gripping"};
    o.progress_out = nullptr;
    o.command = "test";
    o.data = "toy";
    o.extensions = {ext};
    const fs::path dir = fs::temp_directory_path() / ("handemo_eval_rcm_test_" + std::to_string(::getpid()));
    fs::remove_all(dir);
    const auto r = run_eval<hand_tiny>(clips, info, o, dir);
    write_report(r, dir);

    // (a) regression: the same numbers as `handemo rcm eval` (rcm::evaluate_loo) holding out the same contents
    std::vector<rcm::training_clip> tc;
    std::vector<std::string> group;
    for (const auto& c : clips) tc.push_back({&c.motion, c.emotion, c.content, c.path.filename().string()}), group.push_back(c.content);
    rcm::fit_options fo = ro.fit;
    fo.cluster = false;
    const auto loo = rcm::evaluate_loo(tc, group, ro.table, "circumplex.json", fo);
    std::map<std::string, rcm::eval_sample> by_name;
    for (const auto& s : loo.samples) by_name[s.name] = s;
    const auto& reg = ext->regression();
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
    }
    REQUIRE(ext->folds().size() == 2);
    for (const auto& f : ext->folds()) {
        CHECK(f.error.empty());
        CHECK(f.selected == 8);
        CHECK(f.stylise_failed == 0);
        CHECK(f.stylised == 4);  // the held-out neutral take to each of the 4 other emotions
    }

    // (b) the rcm rows: one per (fold, target), scored with every metric
    std::size_t n_rcm = 0;
    std::map<std::string, const sample_record*> real_of, identity_of;  // fold/target -> record
    for (const auto& s : r.samples) {
        CAPTURE(s.method);
        CHECK(!std::isnan(s.circumplex_quadrant_ok));  // every method's output analysed by the fold model
        if (s.method == "real") real_of[s.fold + "/" + s.target] = &s;
        if (s.method == "identity") identity_of[s.fold + "/" + s.target] = &s;
        if (s.method != "rcm") continue;
        ++n_rcm;
        CHECK(std::isfinite(s.rmse_real));
        CHECK(s.rmse_input > 0);  // the synthesis moved the clip
        CHECK(std::isfinite(s.rom_error));
        CHECK(std::isfinite(s.speed_error));
        CHECK(!s.predicted_emotion.empty());
        CHECK(!s.predicted_content.empty());
    }
    CHECK(n_rcm == 8);
    // the real row's circumplex analysis is the regression's analysis of that held-out clip; identity's is the
    // neutral input's
    for (const auto& s : reg) {
        const sample_record* rec = nullptr;
        if (s.emotion == "neutral") {
            rec = identity_of["" + s.fold + "/angry"];
        } else {
            rec = real_of[s.fold + "/" + s.emotion];
        }
        REQUIRE(rec != nullptr);
        CHECK(rec->circumplex_valence == doctest::Approx(s.valence).epsilon(1e-9));
        CHECK(rec->circumplex_arousal == doctest::Approx(s.arousal).epsilon(1e-9));
        if (s.emotion != "neutral") CHECK((rec->circumplex_quadrant_ok > 0.5) == s.quadrant_ok);
    }

    // (c) one report: the rcm row in the summary, the circumplex column, the section and its CSV
    const std::string md = read_text(dir / "report.md");
    CHECK(md.find("| all | rcm |") != std::string::npos);
    CHECK(md.find("circumplex quadrant reached (%)") != std::string::npos);
    CHECK(md.find("## Circumplex (Aristidou et al. 2017)") != std::string::npos);
    CHECK(md.find("**vs rcm**") != std::string::npos);
    CHECK(md.find("| patting | 5 |") != std::string::npos);
    const std::string csv = read_text(dir / "results.csv");
    CHECK(csv.find(",circumplex_valence,circumplex_arousal,circumplex_quadrant_ok\n") != std::string::npos);
    CHECK(csv.find(",rcm,") != std::string::npos);
    const std::string sum = read_text(dir / "summary.csv");
    CHECK(sum.find("all,rcm,rmse_real,") != std::string::npos);
    CHECK(sum.find("all,real,circumplex_quadrant,") != std::string::npos);
    const std::string rc = read_text(dir / "rcm_regression.csv");
    CHECK(std::count(rc.begin(), rc.end(), '\n') == 11);  // header + 10 clips
    CHECK(read_text(dir / "summary.svg").find("circumplex quadrant reached") != std::string::npos);
    fs::remove_all(dir);
}

TEST_CASE("rcm extension: regression only, no rcm rows")
{
    const auto clips = toy_set();
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
    auto clips = toy_set();
    for (auto& c : clips)
        if (c.emotion == "fearful") c.emotion = "bored";  // not in the table
    rcm_eval_options ro;
    ro.table = rcm::load_circumplex(HANDEMO_RCM_CIRCUMPLEX);
    rcm_extension ext(ro);
    std::vector<labelled_clip> train;
    fold_context fc;
    fc.held_out = "pointing";
    for (const auto& c : clips) (c.content == "pointing" ? fc.test.push_back(&c) : train.push_back(c));
    fc.train = &train;
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
