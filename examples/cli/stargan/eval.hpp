// `handemo eval --data DIR --config NAME --report OUT_DIR [...]`: the leave-one-content-out evaluation of
// emotion transfer against captured motion and baselines (the hand paper's Section 5 future work); writes
// report.md, results.csv, summary.csv, summary.svg and per-fold models and loss curves into OUT_DIR.
// `--synth-seed S` (the synthetic hand set's seed) adds the "oracle" row (synthesize_as(), synth.hpp). Built with
// xtensor-blas, cmd_rcm.cpp adds the circumplex method (on by default, `--no-rcm`) through eval_extensions(). Built
// with MPI, `--mpi` deals the trainings over the processes mpirun or srun starts (cmd_mpi.cpp; docs/scale-out.md).
#pragma once

#include "../build_info.hpp"
#include "../registry.hpp"
#include "options.hpp"

#include <handemo/eval/protocol.hpp>

#include <cstdint>
#include <cstdlib>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

namespace handemo::cli::eval_cmd {

struct eval_cli {
    std::string data, config = "hand-embedded", report;
    handemo::cli::train_overrides ov;
    std::uint64_t synth_seed = 0;
    bool has_synth_seed = false;
    handemo::eval::eval_options opt{.train = handemo::eval::default_train_options()};
    std::string command;
    bool continuous = false;  ///< measure the continuous control (eval_options::continuous) with the --circumplex table
    std::string circumplex;
    std::string rate_blend;  ///< --rate-blend (eval_options::continuous_rates), with --continuous only
    bool mpi = false;  ///< --mpi: the trainings dealt over the MPI processes (eval_options::group, cmd_mpi.cpp)
};

void run_eval_cli(eval_cli& o)
{
    using namespace handemo;
    finish_train_options(o.opt.train, o.ov);
    o.opt.command = o.command;
    o.opt.commit = handemo::cli::build_commit();  // printed in the report: the code that made it
    if (o.has_synth_seed) o.opt.synth_seed = o.synth_seed;
    if (o.continuous) o.opt.continuous = o.circumplex.empty() ? transfer_cmd::default_circumplex().string() : o.circumplex;
    if (!o.rate_blend.empty()) {
        if (!o.continuous) throw value_error("eval: --rate-blend is how the continuous control blends the labels' rates: give --continuous too");
        o.opt.continuous_rates = stargan::parse_rate_blend(o.rate_blend, "eval: --rate-blend");
    }
    if (o.mpi) {
        o.opt.group = handemo::cli::mpi().group();  // one process: as without --mpi
    } else {  // started by a launcher as one of several processes: each would run the whole evaluation into one folder
        for (const char* var : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE"})
            if (const char* n = std::getenv(var); n && std::atoi(n) > 1)
                throw value_error(std::string("eval: started as one of ") + n + " processes (" + var + ") without --mpi: each would " +
                                  "run the whole evaluation into the same report folder; add --mpi" +
                                  (handemo::cli::mpi().group ? "" : " (in a handemo built with MPI)") + " or start one process");
    }
    if (o.opt.group && !o.opt.group->writes_files()) {  // process 0 alone prints and writes the report
        o.opt.progress_out = nullptr;
        (void)eval::run_eval_named(o.data, o.config, o.opt, o.report);
        return;
    }
    const auto r = eval::run_eval_named(o.data, o.config, o.opt, o.report);
    std::cout << "eval: " << r.folds.size() << " folds, " << r.samples.size() << " scored clips in " << r.seconds / 60.0
              << " min; wrote " << o.report << "/report.md, results.csv, summary.csv, summary.svg\n";
    for (const std::string& m : eval::method_names()) {
        if (!eval::has_method(r, m)) continue;
        std::cout << "eval: " << m << ":";
        for (const auto& d : eval::metric_defs()) {
            if (d.better == 0) continue;
            const auto v = eval::over_folds(r, d, "all", m);
            if (v.n == 0) continue;  // an optional metric no extension measured
            std::cout << "  " << d.key << " " << v.mean << " +- " << v.std;
        }
        std::cout << "\n";
    }
}

}  // namespace handemo::cli::eval_cmd

static handemo::cli::add_command reg_eval{55, [](CLI::App& app) {
    using namespace handemo::cli::eval_cmd;
    auto* sub = app.add_subcommand("eval", "Leave-one-content-out evaluation of emotion transfer against real motion and baselines");
    auto o = std::make_shared<eval_cli>();
    auto& t = o->opt.train;
    sub->add_option("--data", o->data, "Folder of <prefix>_<content>_<emotion>_<take>.bvh|csv clips or with a manifest.csv")->required();
    sub->add_option("--config", o->config, "hand-embedded | hand-paper | body-embedded | hand-micro | hand-tiny")->capture_default_str();
    sub->add_option("--report", o->report, "Report folder (report.md, results.csv, summary.csv, summary.svg, folds/)")->required();
    sub->add_option("--iters", t.iters, "D iterations per fold (G every --n-critic)")->capture_default_str();
    sub->add_option("--seed", t.seed, "Random seed (fold i trains with seed + i)")->capture_default_str();
    sub->add_option("--folds", o->opt.folds, "Held-out contents to run, comma separated (default: all)")->delimiter(',');
    sub->add_flag("--retargeted,!--no-retargeted", o->opt.retargeted,
                  "Also score stargan-retargeted on a body set: each input moved onto a foreign rig (CMU names, another rest pose, "
                  "proportions, units and channel order), transferred through the retargeting and scored back (default on)");
    sub->add_flag("--reuse-models", o->opt.reuse_models,
                  "Reuse each fold's model already in the report folder when it was trained with the same options and steps "
                  "(when only the change gate's options differ, the gate is fitted again from the stored inner models)");
    handemo::cli::add_train_options(sub, t, o->ov);
    sub->add_option("--jobs", o->opt.jobs,
                    "Trainings at once, each with --threads threads (1 when --threads is 0), the last to start with --jobs times as "
                    "many: above 1 every model is trained first, the folds then scored one by one; the models are bit for bit "
                    "those of --jobs 1")
        ->capture_default_str()
        ->check(CLI::Range(std::size_t{1}, std::size_t{64}));
    if (!handemo::cli::mpi().group)  // built without MPI: --mpi says why it is absent
        sub->add_flag_callback("--mpi", [] {
            throw handemo::value_error("eval: --mpi: this handemo was built without MPI (libopenmpi-dev; docs/scale-out.md)");
        }, "Run as one of several MPI processes (not built here: needs MPI)");
    else
        sub->add_flag("--mpi", o->mpi,
                      "Run as one of the MPI processes mpirun or srun starts: the trainings dealt round the processes in two waves "
                      "(the change gate's inner models, then the folds' final Gs; --jobs at a time on each), the report folder "
                      "on a file system every process sees; process 0 scores the folds, prints and writes the report, that of "
                      "one process bit for bit");
    sub->add_option_function<std::string>(
           "--gate-groups", [o](const std::string& v) { o->opt.gate_grouping = handemo::eval::parse_gate_groups(v); },
           "The change gate's inner groups: shared (inner models shared by the folds: 8 trainings instead of 14 for 7 contents), "
           "ring (runs of consecutive contents: 7 for 7 contents, the shared plan's for an even number) or per-fold (each "
           "fold's own, as `handemo train` forms them); default shared");
    auto* seed_opt = sub->add_option("--synth-seed", o->synth_seed,
                                     "Seed of a synthetic hand set (`handemo synth --seed`): adds the 'oracle' method, the input "
                                     "take re-synthesised in the target's style");
    sub->add_option("--synth-fps", o->opt.synth_fps, "Frame rate the synthetic set was made at (`handemo synth --fps`)")
        ->capture_default_str()
        ->needs(seed_opt);
    handemo::cli::add_inference_weights_option(sub, o->opt.inference_weights,
                                               "score the transfers of G's convolution weights as trained, or rounded to IEEE "
                                               "binary16 (with --reuse-models: the same trained models, the accuracy cost of "
                                               "binary16 weights)");
    sub->add_option_function<std::string>(
           "--judge-inputs",
           [o](const std::string& v) {
               if (v != "auto" && v != "pooled" && v != "joints" && v != "absolute")
                   throw handemo::value_error("eval: --judge-inputs '" + v + "': expected auto, pooled, joints or absolute");
               o->opt.judge_inputs = v == "auto" ? handemo::metrics::all_full_rate_inputs()
                                                 : std::vector{handemo::metrics::parse_full_rate_inputs(v)};
           },
           "The full-rate judge's input set: pooled (the posture pooled over the joints, the judge of earlier reports), joints "
           "(every joint's posture besides), absolute (and the clip's own features, not read against the neutral clip) or auto "
           "(each fold keeps the one its leave-one-content-out check on the training clips recognises best; docs/evaluation.md); "
           "default auto");
    sub->add_option("--shrinkage", o->opt.shrinkage, "Covariance shrinkage of the emotion classifier, in [0, 1]")->capture_default_str();
    sub->add_flag("--continuous", o->continuous,
                  "Also measure the continuous control on every fold (equality at the labels' points, monotone paths from neutral, "
                  "the Lipschitz bound, halfway points, and with --rcm the Spearman correlation of targets and analysis; docs/continuous.md)");
    sub->add_option("--circumplex", o->circumplex, "The labels' circumplex coordinates for --continuous (default: the shipped data/rcm/circumplex.json)");
    sub->add_option("--rate-blend", o->rate_blend,
                    "With --continuous: how the labels' tempo and amplitude factors are blended between their points, linear or "
                    "geometric (in log space; docs/continuous.md); default linear");
    // methods from other translation units (cmd_rcm.cpp: --rcm, the circumplex method of Aristidou et al. 2017)
    for (const auto& e : handemo::cli::eval_extensions()) e.add_options(sub);
    if (!sub->get_option_no_throw("--rcm")) {  // built without it: --no-rcm is accepted, --rcm says why it is absent
        sub->add_flag_callback("--rcm", [] {
            throw handemo::value_error("eval: --rcm: this handemo was built without xtensor-blas (libxtensor-blas-dev), so without "
                                       "the circumplex method");
        }, "Circumplex method (not built here: needs xtensor-blas)");
        sub->add_flag_callback("--no-rcm", [] {}, "Leave the circumplex method out (it is not built here)");
    }
    sub->callback([o, sub, seed_opt] {
        for (const auto& e : handemo::cli::eval_extensions())
            if (auto x = e.make()) o->opt.extensions.push_back(std::move(x));
        o->has_synth_seed = seed_opt->count() > 0;
        o->command = "handemo eval";
        for (const auto* opt : sub->get_options())
            if (opt->count() > 0 && opt->get_name() != "--help") {
                if (opt->get_expected_min() == 0) {
                    o->command += " " + opt->get_name();
                    continue;
                }
                for (const auto& v : opt->as<std::vector<std::string>>()) o->command += " " + opt->get_name() + " " + v;
            }
        run_eval_cli(*o);
    });
}};
