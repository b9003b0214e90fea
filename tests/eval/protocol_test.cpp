#include <doctest/doctest.h>
#include <handemo/eval/protocol.hpp>
#include <handemo/motion/synth.hpp>

#include "../stargan/helpers.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <filesystem>
#include <map>
#include <mutex>
#include <set>
#include <span>
#include <stdlib.h>
#include <string>
#include <thread>
#include <unistd.h>

namespace fs = std::filesystem;
using namespace handemo;
using namespace handemo::eval;
using namespace handemo::stargan;
using handemo::test::toy_set;

namespace {
/// The options of the end-to-end tests: the evaluation's training defaults with `iters` steps on `threads` threads,
/// no progress output.
eval_options tiny_options(long iters, unsigned threads)
{
    eval_options o = {};
    o.train = default_train_options();
    o.train.iters = iters;
    o.train.threads = threads;
    o.progress_out = nullptr;
    return o;
}
}  // namespace

TEST_CASE("end to end: hand-tiny, two folds, report written")
{
    const auto clips = toy_set(3);
    const auto info = make_info<hand_tiny>("hand-tiny", hand_domains(), "neutral");
    eval_options o = tiny_options(12, 2);
    o.folds = {"patting", "gripping"};
    o.command = "test";
    o.data = "toy";
    const fs::path dir = fs::temp_directory_path() / ("handemo_eval_test_" + std::to_string(::getpid()));
    fs::remove_all(dir);
    const auto r = run_eval<hand_tiny>(clips, info, o, dir);
    write_report(r, dir);

    REQUIRE(r.folds.size() == 2);
    CHECK(r.folds[0].held_out == "patting");
    // the options that decide the trained bits, as the report lists them: the thread count and the shards
    CHECK(r.options_text.find("threads " + std::to_string(o.train.threads) + "\n") != std::string::npos);
    CHECK(r.options_text.find("shards " + std::to_string(o.train.shards) + " ") != std::string::npos);
    CHECK(r.folds[0].train_clips == 10);
    CHECK(r.folds[0].test_inputs == 1);
    // 2 folds x 4 targets x 1 take x 9 methods (the handemo preset's amplitude stage adds stargan-g and
    // amplitude-only; the detail layer adds stargan+detail; statistics is in every report), and stargan-ungated in
    // each fold whose change gate is not all 1
    std::size_t gated_folds = 0;
    for (const char* f : {"patting", "gripping"}) {
        const auto ck = read_checkpoint(dir / "folds" / f / "checkpoint.safetensors").second;
        REQUIRE(fs::exists(dir / "folds" / f / "gate" / "gate.csv"));  // the preset fits the gate in every fold
        bool gated = false;
        for (std::size_t d = 0; d < ck.gate_posture.size(); ++d)
            gated |= ck.gate_posture[d] != 1.0 || ck.gate_motion[d] != 1.0 || ck.gate_prior[d] != 0.0;
        // the fold's seed follows the content's place among all contents (gripping 0, patting 1, pointing 2), so
        // `--folds patting` trains what the full run trains
        CHECK(ck.options.at("seed").get<std::uint64_t>() == o.train.seed + (std::string(f) == "patting" ? 1u : 0u));
        gated_folds += gated;
        const auto n_ungated = std::count_if(r.samples.begin(), r.samples.end(), [&](const sample_record& s) {
            return s.fold == f && s.method == "stargan-ungated";
        });
        CHECK(n_ungated == (gated ? 4 : 0));
    }
    // the report's section of the gate's training-set check: one row per fold and the pooled one
    const auto sec = std::find_if(r.sections.begin(), r.sections.end(),
                                  [](const report_section& x) { return x.title == "The change gate, checked inside the training sets"; });
    REQUIRE(sec != r.sections.end());
    CHECK(sec->markdown.find("| patting | ") != std::string::npos);
    CHECK(sec->markdown.find("| gripping | ") != std::string::npos);
    // the statistics setting's check and the guard's count: each fold's 4 targets, pooled 8
    CHECK(sec->markdown.find("| guarded | margin |") != std::string::npos);
    for (const char* f : {"patting", "gripping"}) {
        const auto at = sec->markdown.find(std::string("| ") + f + " | ");
        const auto line = sec->markdown.substr(at, sec->markdown.find('\n', at) - at);
        CHECK(line.find(" of 4 | ") != std::string::npos);
        CHECK(line.find("n/a") == std::string::npos);
    }
    CHECK(sec->markdown.find(" of 8 |") != std::string::npos);
    long pairs = 0;
    for (const char* f : {"patting", "gripping"}) {
        const auto rows = handemo::eval::detail::csv_rows(read_file(dir / "folds" / f / "gate" / "gate.csv"));
        REQUIRE(rows.size() > 1);
        const auto col = std::find(rows[0].begin(), rows[0].end(), "pairs") - rows[0].begin();
        REQUIRE(col < static_cast<long>(rows[0].size()));
        for (std::size_t r = 1; r < rows.size(); ++r) pairs += std::stol(rows[r].at(static_cast<std::size_t>(col)));
    }
    CHECK(sec->markdown.find("| all | " + std::to_string(pairs) + " | ") != std::string::npos);
    CHECK(read_file(dir / "report.md").find("## The change gate, checked inside the training sets") != std::string::npos);
    // the detail layer's example picture: the first fold, one panel per target, real / stargan / stargan+detail in each
    const auto dsec = std::find_if(r.sections.begin(), r.sections.end(), [](const report_section& x) { return x.file == "detail.svg"; });
    REQUIRE(dsec != r.sections.end());
    CHECK(dsec->markdown.find("fold 'patting'") != std::string::npos);
    REQUIRE(fs::exists(dir / "detail.svg"));
    const std::string dsvg = read_file(dir / "detail.svg");
    std::size_t polylines = 0;
    for (std::size_t p = dsvg.find("<polyline"); p != std::string::npos; p = dsvg.find("<polyline", p + 1)) ++polylines;
    CHECK(polylines == 12);
    CHECK(dsvg.find("data-series=\"stargan+detail\"") != std::string::npos);
    CHECK(read_file(dir / "report.md").find("![detail layer](detail.svg)") != std::string::npos);
    {
        // a gate table it cannot read is an error naming the file and line, not a wrong number
        const fs::path bad = dir / "bad_copy";
        fs::create_directories(bad / "folds" / "patting" / "gate");
        const auto good = read_file(dir / "folds" / "patting" / "gate" / "gate.csv");
        write_file_atomic(bad / "folds" / "patting" / "gate" / "gate.csv", good + "angry,1,1\n");
        CHECK_THROWS_WITH_AS(gate_check_section(r, bad), doctest::Contains("gate.csv: line"), format_error);
    }
    const std::size_t n_samples = 72 + 4 * gated_folds;
    CHECK(r.samples.size() == n_samples);
    std::set<std::string> methods;
    for (const auto& s : r.samples) {
        methods.insert(s.method);
        CHECK(std::isfinite(s.rmse_real));
        CHECK(s.target != "neutral");
        // the duration ratio error of every method: |log(out / real)| of the ratios to the input
        CHECK(s.duration_error == doctest::Approx(std::abs(std::log(s.duration_ratio / s.real_duration_ratio))));
        if (s.method == "identity") {
            CHECK(s.duration_ratio == 1.0);  // identity keeps the input's duration: its error is |log(d_in / d_real)|
            CHECK(s.duration_error == doctest::Approx(std::abs(std::log(1.0 / s.real_duration_ratio))));
            CHECK(s.rom_ratio_full == doctest::Approx(1.0));
            CHECK(s.speed_ratio_full == doctest::Approx(1.0));
            CHECK(s.rmse_input == doctest::Approx(0.0));
            CHECK(s.content_ok);
            CHECK(s.rom_ratio == doctest::Approx(1.0));
            CHECK(s.speed_ratio == doctest::Approx(1.0));
        }
        if (s.method == "real") {
            CHECK(s.rmse_real == doctest::Approx(0.0));
            CHECK(s.rom_ratio == doctest::Approx(s.real_rom_ratio));
            CHECK(s.rom_error == doctest::Approx(0.0));
            CHECK(s.rom_error_full == doctest::Approx(0.0));
            CHECK(s.duration_error == 0.0);
            CHECK(s.speed_error_full == doctest::Approx(0.0));
        }
        if (s.method == "stargan+detail") {
            // the detail layer leaves the keyframes, so every keyframe number is stargan's; the full-rate ones move
            const auto g = std::find_if(r.samples.begin(), r.samples.end(), [&](const sample_record& x) {
                return x.method == "stargan" && x.fold == s.fold && x.target == s.target && x.take == s.take;
            });
            REQUIRE(g != r.samples.end());
            CHECK(s.rmse_real == doctest::Approx(g->rmse_real).epsilon(1e-9));
            CHECK(s.predicted_emotion == g->predicted_emotion);
            CHECK(s.rom_ratio == doctest::Approx(g->rom_ratio).epsilon(1e-6));
            CHECK(s.speed_ratio_full != doctest::Approx(g->speed_ratio_full).epsilon(1e-7));  // the input's detail is added
        }
        if (s.method == "nearest-neighbour") CHECK(s.predicted_content != s.fold);  // a clip of another content
        if (s.method == "statistics") {
            // the same learned tempo as stargan's, no G
            const auto g = std::find_if(r.samples.begin(), r.samples.end(), [&](const sample_record& x) {
                return x.method == "stargan" && x.fold == s.fold && x.target == s.target && x.take == s.take;
            });
            REQUIRE(g != r.samples.end());
            CHECK(s.duration_ratio == g->duration_ratio);
            CHECK(s.duration_error == g->duration_error);
        }
    }
    CHECK(methods.size() == (gated_folds ? 10u : 9u));
    for (const char* f : {"report.md", "results.csv", "summary.csv", "summary.svg", "folds.svg", "folds/patting/checkpoint.safetensors",
                          "folds/patting/losses.svg", "folds/gripping/log.csv"})
        CHECK_MESSAGE(fs::exists(dir / f), f);
    const std::string md = read_file(dir / "report.md");
    CHECK(md.find("## Where StarGAN beats each baseline") != std::string::npos);
    CHECK(md.find("![per fold](folds.svg)") != std::string::npos);
    CHECK(read_file(dir / "folds.svg").find("data-series=\"stargan\"") != std::string::npos);
    CHECK(md.find("### held out: gripping") != std::string::npos);
    CHECK(md.find("## Closing note") != std::string::npos);
    const std::string csv = read_file(dir / "results.csv");
    CHECK(static_cast<std::size_t>(std::count(csv.begin(), csv.end(), '\n')) == n_samples + 1);  // header + samples
    // comparisons exist for each baseline and metric with a direction, pooled and per target
    const auto cmp = compare_with_baselines(r);
    // identity, mean-offset, amplitude-only, statistics, nearest-neighbour x 10 metrics with a direction (the cadence
    // ratio error the tenth) x (pooled + 4 targets)
    CHECK(cmp.size() == 5 * 10 * 5);
    // the second judge: a prediction for every sample, its numbers in results.csv, its paragraph in the report, and
    // each fold's weight from the grid with its cross-validated accuracy
    for (const auto& s : r.samples) {
        CHECK(std::find(r.domains.begin(), r.domains.end(), s.predicted_emotion_full) != r.domains.end());
        CHECK(s.emotion_ok_full == (s.predicted_emotion_full == s.target));
    }
    CHECK(csv.find(",duration_error,emotion_ok_full,predicted_emotion_full,cadence_ratio_full,real_cadence_ratio_full,cadence_error_full\n") != std::string::npos);
    CHECK(md.find("## The two emotion judges") != std::string::npos);
    CHECK(md.find("recognised, full-rate judge (%)") != std::string::npos);
    for (const auto& f : r.folds) {
        CHECK(f.judge_cv_acc >= 0.0);
        CHECK(f.judge_cv_acc <= 1.0);
        const auto& grid = handemo::metrics::full_rate_classifier::lambda_grid;
        CHECK(std::find(grid.begin(), grid.end(), f.judge_lambda) != grid.end());
        CHECK((f.judge_inputs == "pooled" || f.judge_inputs == "joints" || f.judge_inputs == "absolute"));
        CHECK(f.judge_candidates.find("pooled ") == 0);
        CHECK(f.judge_candidates.find(", joints ") != std::string::npos);
        CHECK(f.judge_candidates.find(", absolute ") != std::string::npos);
        CHECK(md.find(", inputs " + f.judge_inputs + " of " + f.judge_candidates + ")") != std::string::npos);
    }
    CHECK(md.find("**vs statistics**") != std::string::npos);
    CHECK(md.find("duration ratio error (abs log out/real)") != std::string::npos);
    CHECK(csv.find(",duration_ratio,real_duration_ratio,duration_error,") != std::string::npos);
    for (const auto& f : r.folds) {
        // the tempo's check on the fold's training contents is reported; the preset does not apply its weight
        CHECK(f.tempo_estimator != "");
        CHECK(std::find(tempo_shrink_grid.begin(), tempo_shrink_grid.end(), f.tempo_shrink_weight) != tempo_shrink_grid.end());
        CHECK(f.tempo_shrink_error <= f.tempo_unshrunk_error);
        CHECK(!f.tempo_shrink_applied);
        CHECK(std::isfinite(f.seen_rmse_stargan));
        CHECK(f.seen_rmse_identity > 0);
        CHECK(!f.reused_model);
    }

    // re-scoring with the saved models gives the same numbers without training
    o.reuse_models = true;
    const auto again = run_eval<hand_tiny>(clips, info, o, dir);
    REQUIRE(again.samples.size() == r.samples.size());
    for (std::size_t i = 0; i < r.samples.size(); ++i) CHECK(again.samples[i].rmse_real == r.samples[i].rmse_real);
    CHECK(again.folds[0].reused_model);
    CHECK(again.folds[1].seen_rmse_stargan == r.folds[1].seen_rmse_stargan);
    // the same models scored with binary16 weights (kernels::weight_storage::f16): stargan's rows move by
    // rounding only, the baselines not at all, and the report says which weights were scored
    o.inference_weights = handemo::kernels::weight_storage::f16;
    const auto half = run_eval<hand_tiny>(clips, info, o, dir);
    REQUIRE(half.samples.size() == r.samples.size());
    double moved = 0;
    for (std::size_t i = 0; i < r.samples.size(); ++i) {
        const double d = std::abs(half.samples[i].rmse_real - r.samples[i].rmse_real);
        if (r.samples[i].method == "identity" || r.samples[i].method == "mean-offset") CHECK(d == 0);
        // G's own rows (the gate may give some targets the statistics setting, which no weight reaches)
        if (r.samples[i].method == "stargan" || r.samples[i].method == "stargan-ungated") moved = std::max(moved, d);
    }
    CHECK(moved > 0);
    CHECK(moved < 0.05);  // degrees, on clips whose transfers are a few degrees from the real ones
    CHECK(half.options_text.find("inference weights f16\n") != std::string::npos);
    CHECK(again.options_text.find("inference weights native\n") != std::string::npos);
    o.inference_weights = handemo::kernels::weight_storage::native;
    // only the gate's options differ: the same G, its gate fitted again from the stored inner models
    o.train.gate_margin = -1;
    o.train.gate_prior = false;
    const auto regated = run_eval<hand_tiny>(clips, info, o, dir);
    CHECK(regated.folds[0].reused_model);
    const auto ck2 = read_checkpoint(dir / "folds" / "patting" / "checkpoint.safetensors").second;
    auto want = o.train.to_json();
    want["seed"] = o.train.seed + 1;  // patting's seed
    CHECK(ck2.options == want);
    CHECK(ck2.gate_prior == std::vector<double>(5, 0.0));
    // the tempo shrink does not change G either: the stored models take it, their tempo refitted
    o.train.tempo_shrink = true;
    const auto shrunk = run_eval<hand_tiny>(clips, info, o, dir);
    CHECK(shrunk.folds[0].reused_model);
    CHECK(shrunk.folds[0].tempo_shrink_applied);
    {
        std::vector<labelled_clip> train;
        for (const auto& c : clips)
            if (c.content != "patting") train.push_back(c);
        const auto ck3 = read_checkpoint(dir / "folds" / "patting" / "checkpoint.safetensors").second;
        CHECK(ck3.tempo == tempo_factors(train, info.domain_names, info.neutral, true));
        CHECK(ck3.options.value("tempo_shrink", false));
    }
    o.train.tempo_shrink = false;
    // nor does the joint lag: the stored models take the lag their training clips give, and the report says so
    o.train.lag = true;
    const auto lagged = run_eval<hand_tiny>(clips, info, o, dir);
    CHECK(lagged.folds[0].reused_model);
    for (const auto& f : lagged.folds) {
        CHECK(f.lag_applied);
        CHECK(f.lag_check.find("fearful ") != std::string::npos);
    }
    {
        std::vector<labelled_clip> train;
        for (const auto& c : clips)
            if (c.content != "patting") train.push_back(c);
        const auto ck4 = read_checkpoint(dir / "folds" / "patting" / "checkpoint.safetensors").second;
        CHECK(ck4.lag == joint_lag_of<hand_tiny>(train, info, o.train));
        CHECK(ck4.lag.size() == info.domains);
        CHECK(ck4.options.value("lag", false));
        CHECK(read_file(dir / "report.md").find("joint lag by the check on the training contents") != std::string::npos);
    }
    o.train.lag = false;
    // nor do the tempo neighbours: the stored models take the table their training clips give (or none, when the
    // check keeps the learned factors), the report gives every fold's check, and the option off removes the table
    o.train.tempo_neighbours = true;
    const auto neighboured = run_eval<hand_tiny>(clips, info, o, dir);
    CHECK(neighboured.folds[0].reused_model);
    for (const auto& f : neighboured.folds) {
        CHECK(f.tempo_neighbours_applied);
        CHECK(f.tempo_neighbours_check.find("learned ") == 0);
        CHECK(f.tempo_neighbours_check.find(", 1: ") != std::string::npos);
    }
    {
        std::vector<labelled_clip> train;
        for (const auto& c : clips)
            if (c.content != "patting") train.push_back(c);
        const auto ck5 = read_checkpoint(dir / "folds" / "patting" / "checkpoint.safetensors").second;
        const auto want_table = tempo_table_of(train, info, o.train);
        CHECK(ck5.tempo_table.k == want_table.k);
        CHECK(ck5.tempo_table.contents == want_table.contents);
        CHECK(ck5.options.value("tempo_neighbours", false));
        CHECK(read_file(dir / "report.md").find("tempo neighbours by the check on the training contents (left-out error learned ") !=
              std::string::npos);
    }
    o.train.tempo_neighbours = false;
    const auto unlagged = run_eval<hand_tiny>(clips, info, o, dir);
    CHECK(read_checkpoint(dir / "folds" / "patting" / "checkpoint.safetensors").second.tempo_table.empty());
    CHECK(read_checkpoint(dir / "folds" / "patting" / "checkpoint.safetensors").second.lag.empty());
    REQUIRE(unlagged.samples.size() == regated.samples.size());
    for (std::size_t i = 0; i < regated.samples.size(); ++i) CHECK(unlagged.samples[i].rmse_real == regated.samples[i].rmse_real);
    // the gate's inner models trained for half the steps: trained again (the final G reused), the gates refitted
    o.train.gate_iters_scale = 0.5;
    const auto halved = run_eval<hand_tiny>(clips, info, o, dir);
    CHECK(halved.folds[0].reused_model);
    std::size_t inner_models = 0;
    for (const auto& e : fs::directory_iterator(dir / "inner")) {
        CHECK(read_checkpoint(e.path() / "checkpoint.safetensors").second.step == 6);
        ++inner_models;
    }
    CHECK(inner_models >= 2);
    CHECK(read_checkpoint(dir / "folds" / "patting" / "checkpoint.safetensors").second.step == 12);
    o.train.gate_iters_scale = 1.0;
    // ... but not when the options differ
    o.train.iters = 13;
    CHECK_THROWS_WITH_AS(run_eval<hand_tiny>(clips, info, o, dir), doctest::Contains("--reuse-models"), value_error);
    fs::remove_all(dir);
}

TEST_CASE("eval refuses an unknown held-out content and a one-content data set")
{
    auto clips = toy_set(3);
    const auto info = make_info<hand_tiny>("hand-tiny", hand_domains(), "neutral");
    eval_options o;
    o.train.iters = 1;
    o.progress_out = nullptr;
    o.folds = {"swimming"};
    // a folder of this run's own (mkdtemp): a leftover of an earlier run cannot be mistaken for one written here
    std::string base = (fs::temp_directory_path() / "handemo_eval_refuses_XXXXXX").string();
    REQUIRE(::mkdtemp(base.data()) != nullptr);
    const fs::path dir = fs::path(base) / "never_written";
    CHECK_THROWS_WITH_AS(run_eval<hand_tiny>(clips, info, o, dir), doctest::Contains("swimming"), value_error);
    CHECK(!fs::exists(dir));
    std::erase_if(clips, [](const labelled_clip& c) { return c.content != "patting"; });
    o.folds.clear();
    CHECK_THROWS_AS(run_eval<hand_tiny>(clips, info, o, dir), value_error);
    CHECK(!fs::exists(dir));
    fs::remove_all(base);
}

TEST_CASE("write_report names the folder it cannot create (io_error, not std::filesystem::filesystem_error)")
{
    std::string base = (fs::temp_directory_path() / "handemo_eval_report_XXXXXX").string();
    REQUIRE(::mkdtemp(base.data()) != nullptr);
    write_file_atomic(fs::path(base) / "file", "x");
    const fs::path dir = fs::path(base) / "file" / "report";  // below a file
    CHECK_THROWS_WITH_AS(write_report(eval_result{}, dir), doctest::Contains(dir.string().c_str()), io_error);
    fs::remove_all(base);
}

TEST_CASE("eval with the synthetic set's seed adds the oracle row; a wrong seed is refused before training")
{
    const auto clips = toy_set(3);  // synthesize_dataset(1, 3) at 60 fps
    const auto info = make_info<hand_tiny>("hand-tiny", hand_domains(), "neutral");
    eval_options o = {};
    o.train = default_train_options();
    o.train.iters = 4;
    o.train.threads = 1;
    o.folds = {"pointing"};
    o.progress_out = nullptr;
    o.write_partial = false;
    o.synth_seed = 3;
    const fs::path dir = fs::temp_directory_path() / ("handemo_eval_oracle_test_" + std::to_string(::getpid()));
    fs::remove_all(dir);
    const auto r = run_eval<hand_tiny>(clips, info, o, dir);
    // 1 fold x 4 targets x 1 take x 10 methods (+ stargan-ungated when the fold's change gate is not all 1)
    const auto n_ungated = std::count_if(r.samples.begin(), r.samples.end(), [](const sample_record& s) { return s.method == "stargan-ungated"; });
    CHECK((n_ungated == 0 || n_ungated == 4));
    REQUIRE(r.samples.size() == 40 + static_cast<std::size_t>(n_ungated));
    double oracle = 0, identity = 0;
    for (const auto& s : r.samples) {
        if (s.method == "oracle") {
            const clip expected = synthesize_as(hand_motion::pointing, emotion::neutral, emotion_from_string(s.target), 0, 3);
            CHECK(s.rmse_real > 0);  // the real take has its own per-take variation
            CHECK(s.rmse_real == doctest::Approx(metrics::keyframe_rmse(expected, synthesize(hand_motion::pointing, emotion_from_string(s.target), 0, 3))));
            oracle += s.rmse_real;
        }
        if (s.method == "identity") identity += s.rmse_real;
    }
    MESSAGE("pointing: mean keyframe RMSE to the real take, oracle " << oracle / 4 << " deg, identity " << identity / 4 << " deg");
    CHECK(oracle < identity);
    CHECK(has_method(r, "oracle"));
    const std::string md = markdown_report(r);
    CHECK(md.find("| all | oracle |") != std::string::npos);
    CHECK(md.find("**oracle**") != std::string::npos);
    CHECK(summary_csv(r).find("all,oracle,rmse_real,") != std::string::npos);
    CHECK(summary_svg(r).find("oracle") != std::string::npos);
    CHECK(folds_svg(r).find("data-series=\"oracle\"") != std::string::npos);  // one line per method over the folds

    // without the seed: no oracle row anywhere in the report
    o.synth_seed.reset();
    o.reuse_models = true;
    const auto plain = run_eval<hand_tiny>(clips, info, o, dir);
    CHECK(!has_method(plain, "oracle"));
    CHECK(markdown_report(plain).find("oracle") == std::string::npos);

    // a seed that does not regenerate the neutral takes, and names that are not synthetic takes
    o.synth_seed = 4;
    CHECK_THROWS_WITH_AS(run_eval<hand_tiny>(clips, info, o, dir), doctest::Contains("--synth-seed 4"), value_error);
    auto renamed = clips;
    renamed[0].path = "walk_neutral_0.bvh";
    o.synth_seed = 3;
    CHECK_THROWS_WITH_AS(run_eval<hand_tiny>(renamed, info, o, dir), doctest::Contains("walk_neutral_0.bvh"), value_error);
    fs::remove_all(dir);
}

TEST_CASE("report: the circumplex metric of an extension is optional")
{
    eval_result r;
    r.config = "hand-tiny", r.data = "toy", r.neutral = "neutral", r.domains = {"neutral", "angry"};
    r.folds.push_back({});
    r.folds.back().held_out = "patting";
    for (const char* m : {"stargan", "identity"}) {
        sample_record s;
        s.fold = "patting", s.target = "angry", s.take = "0", s.method = m;
        s.rmse_real = 2, s.rom_ratio = s.speed_ratio = s.real_rom_ratio = s.real_speed_ratio = 1;
        r.samples.push_back(s);
    }
    // no extension: the files are as they always were
    CHECK(samples_csv(r).find("circumplex") == std::string::npos);
    CHECK(markdown_report(r).find("circumplex") == std::string::npos);
    CHECK(summary_csv(r).find("circumplex") == std::string::npos);
    const auto& q = *std::find_if(metric_defs().begin(), metric_defs().end(), [](const metric_def& m) { return m.key == "circumplex_quadrant"; });
    CHECK(!has_metric(r, q));
    CHECK(over_folds(r, q, "all", "stargan").n == 0);
    // measured for one method only: its mean skips the others' NaN, the column appears
    r.samples[0].circumplex_quadrant_ok = 1, r.samples[0].circumplex_valence = 0.5, r.samples[0].circumplex_arousal = -0.25;
    CHECK(has_metric(r, q));
    CHECK(over_folds(r, q, "all", "stargan").mean == doctest::Approx(100.0));
    CHECK(over_folds(r, q, "all", "identity").n == 0);
    const std::string csv = samples_csv(r);
    CHECK(csv.find(",circumplex_valence,circumplex_arousal,circumplex_quadrant_ok\n") != std::string::npos);
    CHECK(csv.find(",0.5,-0.25,1\n") != std::string::npos);
    CHECK(csv.find(",nan,nan,nan\n") != std::string::npos);
    const std::string md = markdown_report(r);
    CHECK(md.find("circumplex quadrant reached (%)") != std::string::npos);
    CHECK(md.find("| all | identity |") != std::string::npos);
    // an extension's section is placed before the per-fold tables and written as a file
    r.sections.push_back({"Extra", "body text\n", "extra.csv", "a,b\n"});
    const std::string md2 = markdown_report(r);
    CHECK(md2.find("## Extra\n\nbody text") != std::string::npos);
    CHECK(md2.find("## Extra") < md2.find("## Per fold"));
    const fs::path dir = fs::temp_directory_path() / ("handemo_eval_section_test_" + std::to_string(::getpid()));
    write_report(r, dir);
    CHECK(read_file(dir / "extra.csv") == "a,b\n");
    fs::remove_all(dir);
}

TEST_CASE("report: the bar that says the network is worth having (stargan against statistics)")
{
    eval_result r;
    r.config = "hand-tiny", r.data = "toy", r.neutral = "neutral", r.domains = {"neutral", "angry", "sad"};
    // 5 folds x 2 targets = 10 (fold, target) pairs; stargan lower in exactly 7 of them
    int pair = 0;
    for (const char* f : {"a", "b", "c", "d", "e"}) {
        r.folds.push_back({});
        r.folds.back().held_out = f;
        for (const char* t : {"angry", "sad"}) {
            const bool lower = pair++ < 7;
            for (const char* m : {"stargan", "statistics"}) {
                sample_record s;
                s.fold = f, s.target = t, s.take = "0", s.method = m;
                s.rmse_real = std::string(m) == "stargan" ? (lower ? 2.0 : 3.5) : 3.0;
                s.emotion_ok = std::string(t) == "angry";  // both recognise angry only: 50% each
                s.rom_ratio = s.speed_ratio = s.real_rom_ratio = s.real_speed_ratio = 1;
                r.samples.push_back(s);
            }
        }
    }
    auto bar = network_bar_of(r);
    REQUIRE(bar.present);
    CHECK(bar.pairs == 10);
    CHECK(bar.pairs_lower == 7);
    CHECK(bar.rmse_stargan == doctest::Approx((7 * 2.0 + 3 * 3.5) / 10));
    CHECK(bar.rmse_statistics == doctest::Approx(3.0));
    CHECK(bar.emotion_stargan == doctest::Approx(50.0));
    CHECK(bar.emotion_statistics == doctest::Approx(50.0));
    CHECK(bar.pairs_enough());  // 70% is enough
    CHECK(bar.emotion_kept());  // as high is enough
    CHECK(bar.cleared());
    CHECK(markdown_report(r).find("(7 of 10): yes; recognised at least as often (50.0% vs 50.0%): yes. **Cleared: yes.**") != std::string::npos);
    CHECK(!network_bar_of(r, 0.75).cleared());  // 7 of 10 is not 75%
    // statistics recognised once more: stargan no longer clears the bar
    for (auto& s : r.samples)
        if (s.method == "statistics" && s.fold == "a" && s.target == "sad") s.emotion_ok = true;
    bar = network_bar_of(r);
    CHECK(!bar.emotion_kept());
    CHECK(!bar.cleared());
    CHECK(markdown_report(r).find("**Cleared: no.**") != std::string::npos);
    // without a statistics row there is no bar and no statement
    std::erase_if(r.samples, [](const sample_record& s) { return s.method == "statistics"; });
    CHECK(!network_bar_of(r).present);
    CHECK(markdown_report(r).find("Cleared") == std::string::npos);
}

TEST_CASE("report: the two emotion judges and the bar on the stronger one")
{
    eval_result r;
    r.config = "hand-tiny", r.data = "toy", r.neutral = "neutral", r.domains = {"neutral", "angry", "sad"};
    // 2 folds x 2 targets x 5 takes; real: nearest-centroid 60%, full-rate 90%; stargan: 50% and 80%
    for (const char* f : {"a", "b"}) {
        r.folds.push_back({});
        r.folds.back().held_out = f;
        for (const char* t : {"angry", "sad"})
            for (int k = 0; k < 5; ++k)
                for (const char* m : {"stargan", "real"}) {
                    sample_record s;
                    s.fold = f, s.target = t, s.take = std::to_string(k), s.method = m;
                    s.rom_ratio = s.speed_ratio = s.real_rom_ratio = s.real_speed_ratio = 1;
                    const int i = (std::string(t) == "sad") * 5 + k;  // 0..9 within the fold
                    const bool real = std::string(m) == "real";
                    s.emotion_ok = i < (real ? 6 : 5);
                    s.emotion_ok_full = i < (real ? 9 : 8);
                    r.samples.push_back(s);
                }
    }
    auto b = judge_bar_of(r);
    REQUIRE(b.present);
    CHECK(b.real_centroid == doctest::Approx(60.0));
    CHECK(b.real_full == doctest::Approx(90.0));
    CHECK(b.stargan_full == doctest::Approx(80.0));
    CHECK(std::string(b.stronger()) == "full-rate");
    CHECK(b.cleared());  // 80 >= 90 - 10
    CHECK(markdown_report(r).find("stronger judge on this set is the **full-rate** one; StarGAN at least real minus 10 points on it "
                                  "(80.0% vs 80.0%): **yes**. The full-rate judge recognises at least 85% of the real clips: yes.") !=
          std::string::npos);
    // stargan's outputs recognised once less by the full-rate judge: below real minus 10
    for (auto& s : r.samples)
        if (s.method == "stargan" && s.fold == "a" && s.target == "sad" && s.take == "2") s.emotion_ok_full = false;
    CHECK(!judge_bar_of(r).cleared());
    // a tie goes to the nearest-centroid judge
    for (auto& s : r.samples) s.emotion_ok_full = s.emotion_ok;
    b = judge_bar_of(r);
    CHECK(std::string(b.stronger()) == "nearest-centroid");
    CHECK(b.cleared());  // 50 >= 60 - 10
    CHECK(markdown_report(r).find("at least 85% of the real clips: no.") != std::string::npos);
    // the commit the program was built from, when given
    CHECK(markdown_report(r).find("Commit:") == std::string::npos);
    r.commit = "0123abc-dirty";
    CHECK(markdown_report(r).find("Command: ``\n\nCommit: `0123abc-dirty`\n\n") != std::string::npos);
    // without a real row there is no paragraph
    std::erase_if(r.samples, [](const sample_record& s) { return s.method == "real"; });
    CHECK(!judge_bar_of(r).present);
    CHECK(markdown_report(r).find("## The two emotion judges") == std::string::npos);
}

TEST_CASE("end to end: an emotion effect that depends on the content, which the statistics row cannot express")
{
    // 4 contents of the synthetic hand set; on three finger channels each content holds a posture of its own (+60
    // degrees, or -60 for crawling and patting), and every emotion moves those channels a further 0.75 x that
    // posture: the change depends on the input. Held out: patting, whose emotions move by -45 where the training
    // contents' mean change (the posture prior) is +15.
    std::vector<labelled_clip> clips;
    for (auto& it : synthesize_dataset(1, 3)) {
        if (it.motion != hand_motion::gripping && it.motion != hand_motion::patting && it.motion != hand_motion::pointing &&
            it.motion != hand_motion::crawling)
            continue;
        labelled_clip c;
        c.path = it.file_stem + ".bvh";
        const auto n = parse_clip_name(it.file_stem);
        c.content = n.content, c.emotion = n.emotion, c.take = n.take;
        c.motion = it.c;
        const double base = (c.content == "crawling" || c.content == "patting") ? -60.0 : 60.0;
        const double offset = base + (c.emotion == "neutral" ? 0.0 : 0.75 * base);
        for (std::size_t f = 0; f < c.motion.frames; ++f)
            for (std::size_t j : {5u, 9u, 13u}) c.motion.angle(f, j, 0) += offset;
        // postures past the hand's limits: this set's skeleton says it has none (limits wider than the circle; a hand
        // with exactly -180..180 everywhere, as BVH reads it, would take the hand's)
        for (auto& j : c.motion.skel.joints) j.lower_limit = {-360, -360, -360}, j.upper_limit = {360, 360, 360};
        clips.push_back(std::move(c));
    }
    REQUIRE(clips.size() == 20);
    const auto info = make_info<hand_tiny>("hand-tiny", hand_domains(), "neutral");
    eval_options o = {};
    o.train = default_train_options();
    o.train.iters = 12;
    o.train.threads = 2;
    o.folds = {"patting"};
    o.progress_out = nullptr;
    o.write_partial = false;
    const fs::path dir = fs::temp_directory_path() / ("handemo_eval_statistics_test_" + std::to_string(::getpid()));
    fs::remove_all(dir);
    const auto r = run_eval<hand_tiny>(clips, info, o, dir);
    write_report(r, dir);

    // the statistics row is there for every target, and is the fold model's statistics() scored against the real take
    const auto model = load_model(dir / "folds" / "patting");
    const auto clip_of = [&](const std::string& emotion) -> const clip& {
        return std::find_if(clips.begin(), clips.end(), [&](const labelled_clip& c) { return c.content == "patting" && c.emotion == emotion; })->motion;
    };
    const clip& input = clip_of("neutral");
    std::size_t n = 0;
    double stat = 0, g = 0;
    for (const auto& s : r.samples) {
        if (s.method != "statistics") continue;
        ++n;
        CAPTURE(s.target);
        const clip& real = clip_of(s.target);
        const auto out = model->statistics(input, s.target).motion;
        CHECK(s.rmse_real == doctest::Approx(metrics::keyframe_rmse(out, real)).epsilon(1e-12));
        CHECK(s.duration_error == doctest::Approx(metrics::duration_error(out, real)).epsilon(1e-12));
        const auto same = [&](const char* method) {
            return *std::find_if(r.samples.begin(), r.samples.end(), [&](const sample_record& x) { return x.method == method && x.target == s.target; });
        };
        // the prior carries the training contents' mean change (+15 on those channels) to a content that moves by
        // -45: further from the real take than doing nothing, and further than the amplitude stage alone
        CHECK(s.rmse_real > same("identity").rmse_real);
        CHECK(s.rmse_real > same("amplitude-only").rmse_real);
        stat += s.rmse_real, g += same("stargan").rmse_real;
    }
    CHECK(n == 4);
    MESSAGE("held-out patting: statistics " << stat / 4 << " deg, stargan " << g / 4 << " deg (12 steps: no claim on which is lower)");
    const auto bar = network_bar_of(r);
    CHECK(bar.present);
    CHECK(bar.pairs == 4);
    CHECK(bar.rmse_statistics == doctest::Approx(stat / 4));
    const std::string md = read_file(dir / "report.md");
    CHECK(md.find("| all | statistics |") != std::string::npos);
    CHECK(md.find("**vs statistics**") != std::string::npos);
    CHECK(md.find("**Cleared: ") != std::string::npos);
    const std::string sum = read_file(dir / "summary.csv");
    CHECK(sum.find("all,statistics,rmse_real,") != std::string::npos);
    CHECK(sum.find("all,statistics,duration_error,") != std::string::npos);
    CHECK(sum.find("all,identity,duration_error,") != std::string::npos);
    fs::remove_all(dir);
}

namespace {

/// dir -> (contents its G is trained on, seed), gathered over the folds of a gate plan
using plan_models = std::map<fs::path, std::pair<std::set<std::string>, std::uint64_t>>;

/// Checks the gate plan of the fold holding out `held`: two sorted, non-empty groups that partition the fold's
/// training contents, as even as dealing them round, each scored by a model trained on the other group, and the
/// same model (dir, contents, seed) wherever an earlier fold named the same dir (recorded in `models`).
void check_fold_plan(const stargan::gate_plan& plan, const std::vector<std::string>& contents, const std::string& held,
                     plan_models& models)
{
    REQUIRE(plan.groups.size() == 2);
    REQUIRE(plan.dirs.size() == 2);
    REQUIRE(plan.seeds.size() == 2);
    CHECK(plan.dirs[0] != plan.dirs[1]);
    std::set<std::string> all_listed;
    for (const auto& g : plan.groups) {
        CHECK(!g.empty());
        CHECK(std::is_sorted(g.begin(), g.end()));
        for (const auto& c : g) CHECK(all_listed.insert(c).second);  // no content twice
    }
    std::set<std::string> train(contents.begin(), contents.end());
    train.erase(held);
    CHECK(all_listed == train);  // a partition of the fold's training contents
    const auto a = plan.groups[0].size(), b = plan.groups[1].size();
    CHECK(std::max(a, b) - std::min(a, b) <= 1);  // as even as dealing them round
    for (std::size_t f = 0; f < 2; ++f) {
        // group f is scored by the G trained on the other group: the same model wherever the same dir is named
        std::set<std::string> on(plan.groups[1 - f].begin(), plan.groups[1 - f].end());
        const auto [it, fresh] = models.emplace(plan.dirs[f], std::pair{on, plan.seeds[f]});
        if (!fresh) {
            CHECK(it->second.first == on);
            CHECK(it->second.second == plan.seeds[f]);
        }
    }
}

}  // namespace

TEST_CASE("shared gate plan: every fold's groups partition its training contents, N + 1 inner models shared by the folds")
{
    for (std::size_t N : {3u, 4u, 7u, 12u}) {
        CAPTURE(N);
        std::vector<std::string> contents;
        for (std::size_t i = 0; i < N; ++i) contents.push_back(std::string(1, char('a' + i)) + "-content");
        plan_models models;
        for (const auto& held : contents) {
            CAPTURE(held);
            const auto plan = shared_gate_plan(contents, held, "inner", 5);
            REQUIRE(plan.has_value());
            check_fold_plan(*plan, contents, held, models);
        }
        CHECK(models.size() == N + 1);  // against 2 N with per-fold groups
        std::set<std::uint64_t> seeds;
        for (const auto& [dir, m] : models) seeds.insert(m.second);
        CHECK(seeds.size() == models.size());
    }
    CHECK(!shared_gate_plan({"a", "b"}, "a", "inner", 1).has_value());  // one training content: no two groups
    CHECK_THROWS_WITH_AS(shared_gate_plan({"a", "b", "c"}, "d", "inner", 1), doctest::Contains("'d'"), value_error);
    CHECK(parse_gate_groups("per-fold") == gate_groups::per_fold);
    CHECK_THROWS_WITH_AS(parse_gate_groups("random"), doctest::Contains("--gate-groups 'random'"), value_error);
}

TEST_CASE("ring gate plan: every fold's groups partition its training contents, N inner models for an odd N")
{
    for (std::size_t N : {3u, 5u, 7u, 9u, 4u, 12u}) {
        CAPTURE(N);
        std::vector<std::string> contents;
        for (std::size_t i = 0; i < N; ++i) contents.push_back(std::string(1, char('a' + i)) + "-content");
        plan_models models;
        std::map<fs::path, int> folds_using;
        for (const auto& held : contents) {
            CAPTURE(held);
            const auto plan = ring_gate_plan(contents, held, "inner", 5);
            REQUIRE(plan.has_value());
            check_fold_plan(*plan, contents, held, models);
            const auto a = plan->groups[0].size(), b = plan->groups[1].size();
            CHECK(std::max(a, b) - std::min(a, b) == (N % 2 == 1 ? 0u : 1u));
            for (std::size_t f = 0; f < 2; ++f) ++folds_using[plan->dirs[f]];
        }
        if (N % 2 == 1) {
            CHECK(models.size() == N);  // one fewer than the shared plan
            for (const auto& [dir, n] : folds_using) {
                CHECK(dir.filename().string().rfind("ring", 0) == 0);  // never a shared plan's folder
                CHECK(n == 2);
            }
        } else {
            CHECK(models.size() == N + 1);  // the shared plan's
            for (const auto& held : contents)
                CHECK(ring_gate_plan(contents, held, "inner", 5)->dirs == shared_gate_plan(contents, held, "inner", 5)->dirs);
        }
        std::set<std::uint64_t> seeds;
        for (const auto& [dir, m] : models) seeds.insert(m.second);
        CHECK(seeds.size() == models.size());
    }
    // the fold holding out the first of 7 contents: the runs of 3 after it
    const std::vector<std::string> seven{"a", "b", "c", "d", "e", "f", "g"};
    const auto p0 = ring_gate_plan(seven, "a", "inner", 1);
    REQUIRE(p0.has_value());
    CHECK(p0->groups[0] == std::vector<std::string>{"b", "c", "d"});
    CHECK(p0->groups[1] == std::vector<std::string>{"e", "f", "g"});
    const auto p6 = ring_gate_plan(seven, "g", "inner", 1);  // wraps round the ring
    REQUIRE(p6.has_value());
    CHECK(p6->groups[0] == std::vector<std::string>{"a", "b", "c"});
    CHECK(p6->groups[1] == std::vector<std::string>{"d", "e", "f"});
    CHECK(!ring_gate_plan({"a", "b"}, "a", "inner", 1).has_value());
    CHECK_THROWS_WITH_AS(ring_gate_plan({"a", "b", "c"}, "d", "inner", 1), doctest::Contains("'d'"), value_error);
    CHECK(parse_gate_groups("ring") == gate_groups::ring);
    CHECK(std::string(to_string(gate_groups::ring)) == "ring");
}

TEST_CASE("training jobs: a job starts only after those it waits on; the first error is rethrown")
{
    std::atomic<int> first_done{0};
    std::atomic<int> saw_first{-1};
    std::vector<training_job> jobs;
    jobs.push_back({"first", [&] {
                        std::this_thread::sleep_for(std::chrono::milliseconds(60));
                        first_done = 1;
                    },
                    {}, 0});
    jobs.push_back({"second", [&] { saw_first = first_done.load(); }, {0}, 0});
    jobs.push_back({"third", [] {}, {}, 0});
    run_training_jobs(jobs, 2, nullptr, "test");
    CHECK(saw_first == 1);
    for (const auto& j : jobs) CHECK(j.seconds >= 0);
    CHECK(jobs[0].seconds >= 0.05);

    std::atomic<int> ran_after_error{0};
    std::vector<training_job> failing;
    failing.push_back({"fails", [] { throw value_error("train: planted failure"); }, {}, 0});
    failing.push_back({"after it", [&] { ++ran_after_error; }, {0}, 0});
    CHECK_THROWS_WITH_AS(run_training_jobs(failing, 2, nullptr, "test"), doctest::Contains("planted failure"), value_error);
    CHECK(ran_after_error == 0);

    // the last job to start is offered every slot, the others one; a job without run_on_slots runs run()
    std::vector<std::size_t> slots(5, 0);
    std::atomic<int> plain{0};
    std::vector<training_job> offered;
    for (std::size_t i = 0; i < 4; ++i)
        offered.push_back({"job " + std::to_string(i), {}, {}, 0, {}, [&, i](std::size_t s) {
                               std::this_thread::sleep_for(std::chrono::milliseconds(10));
                               slots[i] = s;
                           }});
    offered.push_back({"plain", [&] { ++plain; }, {3}, 0});
    run_training_jobs(offered, 3, nullptr, "test");
    CHECK(slots[0] == 1);
    CHECK(slots[1] == 1);
    CHECK(slots[2] == 1);
    CHECK(slots[3] == 1);
    CHECK(plain == 1);
    std::vector<training_job> last;
    for (std::size_t i = 0; i < 3; ++i) last.push_back({"job " + std::to_string(i), {}, {}, 0, {}, [&, i](std::size_t s) { slots[i] = s; }});
    run_training_jobs(last, 2, nullptr, "test");
    CHECK(slots[0] == 1);
    CHECK(slots[1] == 1);
    CHECK(slots[2] == 2);

    std::vector<training_job> backwards;
    backwards.push_back({"waits on a later job", [] {}, {1}, 0});
    backwards.push_back({"later", [] {}, {}, 0});
    CHECK_THROWS_WITH_AS(run_training_jobs(backwards, 2, nullptr, "test"), doctest::Contains("waits on a job that is not before it"),
                         value_error);
}

namespace {
/// A process group of threads (dist/group.hpp) for the tests: a barrier by generations, all_gather through a shared
/// buffer between two barriers.
struct thread_group_state {
    explicit thread_group_state(std::size_t n) : ranks(n) {}
    std::size_t ranks;
    std::mutex m;
    std::condition_variable cv;
    std::size_t arrived = 0, generation = 0;
    std::vector<double> buffer;
};
class thread_group final : public dist::process_group {
public:
    thread_group(thread_group_state& s, std::size_t rank) : s_(s), rank_(rank) {}
    std::size_t rank() const noexcept override { return rank_; }
    std::size_t ranks() const noexcept override { return s_.ranks; }
    void barrier() override
    {
        std::unique_lock lock(s_.m);
        const std::size_t gen = s_.generation;
        if (++s_.arrived == s_.ranks) {
            s_.arrived = 0;
            ++s_.generation;
            s_.cv.notify_all();
        } else {
            s_.cv.wait(lock, [&] { return s_.generation != gen; });
        }
    }
    void all_gather(std::span<const double> mine, std::span<double> all) override
    {
        {
            std::lock_guard lock(s_.m);
            s_.buffer.resize(mine.size() * s_.ranks);
            std::copy(mine.begin(), mine.end(), s_.buffer.begin() + static_cast<std::ptrdiff_t>(rank_ * mine.size()));
        }
        barrier();
        {
            std::lock_guard lock(s_.m);
            std::copy(s_.buffer.begin(), s_.buffer.end(), all.begin());
        }
        barrier();
    }

private:
    thread_group_state& s_;
    std::size_t rank_;
};
}  // namespace

TEST_CASE("training waves over a group: each job once, on process (index in its wave) mod R, after its wave's barrier")
{
    CHECK(wave_rank(0, 3) == 0);
    CHECK(wave_rank(4, 3) == 1);
    CHECK(wave_rank(7, 1) == 0);
    const fs::path dir = fs::temp_directory_path() / ("handemo_eval_waves_" + std::to_string(::getpid()));
    fs::remove_all(dir);
    fs::create_directories(dir);
    // 5 inner models, then 4 final ones each waiting on two of them (as the shared plan of 4 folds), then one more
    constexpr std::size_t R = 3, n = 10;
    std::mutex m;
    std::vector<int> runs(n, 0);
    std::vector<std::size_t> ran_on(n, R);
    std::vector<int> order;  // jobs in the order they started, over every process
    auto plan = [&](std::size_t rank, bool skip) {
        std::vector<training_job> jobs;
        for (std::size_t i = 0; i < n; ++i) {
            std::vector<std::size_t> after;
            if (i >= 5 && i < 9) after = {i - 5, (i - 4) % 5};
            if (i == 9) after = {5};
            jobs.push_back({"job " + std::to_string(i),
                            [&, i, rank, skip] {
                                {
                                    std::lock_guard lock(m);
                                    ++runs[i], ran_on[i] = rank, order.push_back(static_cast<int>(i));
                                }
                                if (!skip) write_file_atomic(dir / ("job" + std::to_string(i)), "done");
                            },
                            std::move(after), 0, dir / ("job" + std::to_string(i))});
        }
        return jobs;
    };
    CHECK(job_waves(plan(0, false)) == std::vector<std::size_t>{0, 0, 0, 0, 0, 1, 1, 1, 1, 2});
    auto run_group = [&](std::size_t skip_rank, std::vector<std::vector<training_job>>& plans) {
        thread_group_state state(R);
        std::vector<std::string> errors(R);
        std::vector<std::thread> ranks;
        for (std::size_t r = 0; r < R; ++r) plans.push_back(plan(r, r == skip_rank));
        for (std::size_t r = 0; r < R; ++r)
            ranks.emplace_back([&, r] {
                thread_group g(state, r);
                try {
                    run_training_waves(plans[r], g, 2, nullptr, "test");
                } catch (const value_error& e) {
                    errors[r] = e.what();
                }
            });
        for (auto& t : ranks) t.join();
        return errors;
    };
    std::vector<std::vector<training_job>> plans;
    const auto errors = run_group(R, plans);
    for (const auto& e : errors) CHECK(e.empty());
    // waves {0..4}, {5..8}, {9}: index in its wave mod 3
    const std::vector<std::size_t> expect_rank{0, 1, 2, 0, 1, 0, 1, 2, 0, 0};
    for (std::size_t i = 0; i < n; ++i) {
        CHECK(runs[i] == 1);
        CHECK(ran_on[i] == expect_rank[i]);
    }
    // no job of a wave starts before every job of the waves before it has ended
    const auto at = [&](int i) { return std::find(order.begin(), order.end(), i) - order.begin(); };
    for (int late = 5; late < 9; ++late)
        for (int early = 0; early < 5; ++early) CHECK(at(early) < at(late));
    CHECK(at(9) > at(8));
    // every process knows every job's seconds, from the process that ran it
    for (std::size_t r = 0; r < R; ++r)
        for (std::size_t i = 0; i < n; ++i) CHECK(plans[r][i].seconds >= 0);

    // a process that leaves a job's file out: every process names the job and where the others looked
    fs::remove_all(dir);
    fs::create_directories(dir);
    std::fill(runs.begin(), runs.end(), 0);
    order.clear();
    std::vector<std::vector<training_job>> skipped;
    const auto failed = run_group(1, skipped);
    for (const auto& e : failed) {
        CHECK(e.find("process 1 of 3 was to leave " + (dir / "job1").string() + " ('job 1')") != std::string::npos);
        CHECK(e.find("file system every process sees") != std::string::npos);
    }
    CHECK(runs[5] == 0);  // wave 2 never started

    // processes that planned other jobs stop before any runs
    fs::remove_all(dir);
    fs::create_directories(dir);
    std::fill(runs.begin(), runs.end(), 0);
    thread_group_state state(2);
    std::vector<std::string> errs(2);
    std::vector<std::thread> two;
    std::vector<std::vector<training_job>> other{plan(0, false), plan(1, false)};
    other[1].pop_back();
    for (std::size_t r = 0; r < 2; ++r)
        two.emplace_back([&, r] {
            thread_group g(state, r);
            try {
                run_training_waves(other[r], g, 1, nullptr, "test");
            } catch (const value_error& e) {
                errs[r] = e.what();
            }
        });
    for (auto& t : two) t.join();
    for (const auto& e : errs) CHECK(e.find("every process needs the same data, options and report folder") != std::string::npos);
    CHECK(std::count(runs.begin(), runs.end(), 0) == static_cast<long>(n));
    fs::remove_all(dir);
}

TEST_CASE("eval --jobs 2: the models of --jobs 1 bit for bit, each shared inner model trained once; other groups refit the gate")
{
    const auto clips = toy_set(3);
    const auto info = make_info<hand_tiny>("hand-tiny", hand_domains(), "neutral");
    eval_options o = tiny_options(8, 1);
    o.retargeted = false;
    o.folds = {"gripping", "patting"};
    const fs::path base = fs::temp_directory_path() / ("handemo_eval_jobs_" + std::to_string(::getpid()));
    fs::remove_all(base);
    const auto one = run_eval<hand_tiny>(clips, info, o, base / "one");
    o.jobs = 2;
    const auto two = run_eval<hand_tiny>(clips, info, o, base / "two");
    REQUIRE(one.samples.size() == two.samples.size());
    for (std::size_t i = 0; i < one.samples.size(); ++i) CHECK(one.samples[i].rmse_real == two.samples[i].rmse_real);
    REQUIRE(two.folds.size() == 2);
    for (const auto& fs_ : two.folds) {
        const std::string f = fs_.held_out;
        CHECK(read_file(base / "one" / "folds" / f / "checkpoint.safetensors") == read_file(base / "two" / "folds" / f / "checkpoint.safetensors"));
        CHECK(!fs::exists(base / "two" / "folds" / f / "gate" / "inner1"));  // the shared models, not the fold's own
        CHECK(fs_.train_seconds > 0);
        CHECK(!fs_.reused_model);
    }
    // 3 contents, A = {gripping}, C = {patting, pointing}: holding out gripping needs G on C \ {patting} (model2) and G on
    // (A \ {gripping}) + {patting} (model4); holding out patting needs G on C \ {patting} again and G on A (model1)
    for (int m : {1, 2, 4})
        CHECK(read_file(base / "one" / "inner" / ("model" + std::to_string(m)) / "checkpoint.safetensors") ==
              read_file(base / "two" / "inner" / ("model" + std::to_string(m)) / "checkpoint.safetensors"));
    for (const char* absent : {"model3", "model5"}) CHECK(!fs::exists(base / "two" / "inner" / absent));
    CHECK(two.options_text.find("gate groups shared\ntrainings at once 2\n") != std::string::npos);

    // the same models with per-fold groups: G is reused, the gate fitted again around the fold's own inner models,
    // which --jobs 2 trains first, two at a time, bit for bit those the fold loop trains one by one
    o.reuse_models = true;
    o.gate_grouping = gate_groups::per_fold;
    o.jobs = 1;
    const auto per_fold_one = run_eval<hand_tiny>(clips, info, o, base / "one");
    o.jobs = 2;
    // runs the evaluation into base / "two" and returns it with what it printed
    auto run_printing = [&](std::string& printed) {
        std::FILE* log = std::tmpfile();
        REQUIRE(log != nullptr);
        o.progress_out = log;
        auto r = run_eval<hand_tiny>(clips, info, o, base / "two");
        o.progress_out = nullptr;
        printed.assign(static_cast<std::size_t>(std::ftell(log)), '\0');
        std::rewind(log);
        CHECK(std::fread(printed.data(), 1, printed.size(), log) == printed.size());
        std::fclose(log);
        return r;
    };
    std::string printed;
    const auto per_fold = run_printing(printed);
    // G reused in both folds; the two folds' own inner models (2 each) trained first, two at a time
    CHECK(printed.find("eval: training 4 models (4 for the change gates, 0 folds), 2 at a time") != std::string::npos);
    CHECK(per_fold.folds[0].reused_model);
    REQUIRE(per_fold.samples.size() == per_fold_one.samples.size());
    for (std::size_t i = 0; i < per_fold.samples.size(); ++i) CHECK(per_fold.samples[i].rmse_real == per_fold_one.samples[i].rmse_real);
    for (const char* f : {"gripping", "patting"})
        for (const char* inner : {"inner1", "inner2"})
            CHECK(read_file(base / "one" / "folds" / f / "gate" / inner / "checkpoint.safetensors") ==
                  read_file(base / "two" / "folds" / f / "gate" / inner / "checkpoint.safetensors"));
    std::vector<labelled_clip> train;
    for (const auto& c : clips)
        if (c.content != "gripping") train.push_back(c);
    auto to = o.train;
    to.seed = o.train.seed;  // gripping is the first content
    CHECK(read_file(base / "two" / "folds" / "gripping" / "gate" / "groups.txt") == gate_groups_text(train, to, nullptr));

    // the ring plan on the same models: the runs of one content after the held one, 3 inner models for 3 contents
    // (the shared plan's 4), each scoring for two folds; --jobs 2 trains them first, bit for bit --jobs 1's
    o.gate_grouping = gate_groups::ring;
    o.jobs = 1;
    const auto ring_one = run_eval<hand_tiny>(clips, info, o, base / "one");
    o.jobs = 2;
    std::string ring_printed;
    const auto ring = run_printing(ring_printed);
    CHECK(ring_printed.find("eval: training 3 models (3 for the change gates, 0 folds), 2 at a time") != std::string::npos);
    CHECK(ring.options_text.find("gate groups ring\n") != std::string::npos);
    REQUIRE(ring.samples.size() == ring_one.samples.size());
    for (std::size_t i = 0; i < ring.samples.size(); ++i) CHECK(ring.samples[i].rmse_real == ring_one.samples[i].rmse_real);
    for (int m : {1, 2, 3})
        CHECK(read_file(base / "one" / "inner" / ("ring" + std::to_string(m)) / "checkpoint.safetensors") ==
              read_file(base / "two" / "inner" / ("ring" + std::to_string(m)) / "checkpoint.safetensors"));
    CHECK(!fs::exists(base / "two" / "inner" / "ring4"));
    const std::vector<std::string> contents{"gripping", "patting", "pointing"};
    const auto ring_plan = ring_gate_plan(contents, "gripping", base / "two" / "inner", o.train.seed);
    REQUIRE(ring_plan.has_value());
    CHECK(read_file(base / "two" / "folds" / "gripping" / "gate" / "groups.txt") == gate_groups_text(train, to, &*ring_plan));
    fs::remove_all(base);
}

TEST_CASE("continuous control: a path's log posterior is monotone, peaks before the label, or dips and recovers")
{
    using eval::shape_of_path;
    // rising, flat steps included: monotone, and the label's point is the maximum
    auto p = shape_of_path({-3.0, -2.0, -2.0, -0.5});
    CHECK(p.monotone);
    CHECK_FALSE(p.peak_before_label);
    // peaks at a blend short of the label, then falls toward it
    p = shape_of_path({-3.0, -1.0, -0.4, -0.7});
    CHECK_FALSE(p.monotone);
    CHECK(p.peak_before_label);
    // dips on the way, ends at its maximum: not monotone, not a peak before the label
    p = shape_of_path({-3.0, -1.0, -1.5, -0.2});
    CHECK_FALSE(p.monotone);
    CHECK_FALSE(p.peak_before_label);
    // a fall within the rounding tolerance is not a fall
    p = shape_of_path({-2.0, -2.0 - 1e-12, -1.0});
    CHECK(p.monotone);
    // trivial paths
    CHECK(shape_of_path({}).monotone);
    CHECK(shape_of_path({-1.0}).monotone);
    CHECK_FALSE(shape_of_path({-1.0}).peak_before_label);
    // a peak before the label counts even when the path dipped earlier
    p = shape_of_path({-3.0, -3.5, -0.3, -0.9});
    CHECK(p.peak_before_label);
}
