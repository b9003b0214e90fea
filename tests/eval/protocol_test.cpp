#include <doctest/doctest.h>
#include <handemo/eval/protocol.hpp>
#include <handemo/motion/synth.hpp>

#include "../stargan/helpers.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <set>
#include <stdlib.h>
#include <string>
#include <unistd.h>

namespace fs = std::filesystem;
using namespace handemo;
using namespace handemo::eval;
using namespace handemo::stargan;
using handemo::test::toy_set;

TEST_CASE("end to end: hand-tiny, two folds, report written")
{
    const auto clips = toy_set(3);
    const auto info = make_info<hand_tiny>("hand-tiny", hand_domains(), "neutral");
    eval_options o = {};
    o.train = default_train_options();
    o.train.iters = 12;
    o.train.threads = 2;
    o.folds = {"patting", "gripping"};
    o.progress_out = nullptr;
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
    // 2 folds x 4 targets x 1 take x 8 methods (the handemo preset's amplitude stage adds stargan-g and
    // amplitude-only; the detail layer adds stargan+detail), and stargan-ungated in each fold whose change gate is not all 1
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
    const std::size_t n_samples = 64 + 4 * gated_folds;
    CHECK(r.samples.size() == n_samples);
    std::set<std::string> methods;
    for (const auto& s : r.samples) {
        methods.insert(s.method);
        CHECK(std::isfinite(s.rmse_real));
        CHECK(s.target != "neutral");
        if (s.method == "identity") {
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
    }
    CHECK(methods.size() == (gated_folds ? 9u : 8u));
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
    CHECK(cmp.size() == 4 * 7 * 5);  // identity, mean-offset, amplitude-only, nearest-neighbour x 7 metrics x (pooled + 4 targets)
    for (const auto& f : r.folds) {
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
        if (r.samples[i].method == "stargan") moved = std::max(moved, d);
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
    // 1 fold x 4 targets x 1 take x 9 methods (+ stargan-ungated when the fold's change gate is not all 1)
    const auto n_ungated = std::count_if(r.samples.begin(), r.samples.end(), [](const sample_record& s) { return s.method == "stargan-ungated"; });
    CHECK((n_ungated == 0 || n_ungated == 4));
    REQUIRE(r.samples.size() == 36 + static_cast<std::size_t>(n_ungated));
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
