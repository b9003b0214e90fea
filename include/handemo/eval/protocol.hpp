// The leave-one-content-out protocol of the evaluation (the hand paper leaves one motion type out of
// training, Section 4; numeric comparison with captured motion is its Section 5 future work). For each fold:
// train StarGAN (Eq. 4-5, train.hpp) on every other content, transfer each held-out neutral take to every
// other emotion (Section 3.4, transfer.hpp), run the baselines (baselines.hpp) and score everything against
// the held-out take of the target emotion (metrics.hpp, classifier.hpp). On the synthetic hand set (synth.hpp)
// with its seed known, an "oracle" row re-synthesises each neutral input take with the target's style and the
// input take's own per-take variation (synthesize_as()): the floor that per-take variation leaves. Templated on
// the configuration so a program instantiates only the networks it uses; run_eval_named() dispatches by name
// (all configurations).
#pragma once

#include <handemo/core/error.hpp>
#include <handemo/core/progress.hpp>
#include <handemo/dist/group.hpp>
#include <handemo/metrics/baselines.hpp>
#include <handemo/metrics/classifier.hpp>
#include <handemo/metrics/full_rate_judge.hpp>
#include <handemo/eval/continuous.hpp>
#include <handemo/eval/extension.hpp>
#include <handemo/metrics/compare.hpp>
#include <handemo/eval/report.hpp>
#include <handemo/eval/retargeted.hpp>
#include <handemo/eval/schedule.hpp>
#include <handemo/motion/detail_layer.hpp>
#include <handemo/motion/synth.hpp>
#include <handemo/render/svg.hpp>
#include <handemo/stargan/configs.hpp>
#include <handemo/stargan/dataset.hpp>
#include <handemo/stargan/gate.hpp>
#include <handemo/stargan/train.hpp>
#include <handemo/stargan/transfer.hpp>
#include <handemo/stargan/capture.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace handemo::eval {

/// @brief Options of an evaluation run.
struct eval_options {
    stargan::train_options train;   ///< per-fold training (seed of fold i is train.seed + i)
    std::vector<std::string> folds; ///< contents to hold out, in this order (default: every content, sorted)
    double shrinkage = 0.5;         ///< of the emotion classifier, see nearest_centroid_classifier
    std::FILE* progress_out = stderr;
    std::string command;            ///< recorded in the report
    /// The source commit of the program that runs the evaluation, printed in the report (the CLI gives the one it was
    /// built from, cmake/build_commit.cmake; "-dirty" when tracked files differed from it). Empty: not printed.
    std::string commit;
    std::string data;               ///< data set name recorded in the report
    bool write_partial = true;      ///< rewrite the report in out_dir after every fold (an interrupted run leaves one)
    /// Load a fold's model from out_dir/folds/<content>/checkpoint.safetensors instead of training it when that
    /// checkpoint was trained with exactly these options to the end (re-scoring after a metric change).
    bool reuse_models = false;
    /// Seed the synthetic hand set was generated with (`handemo synth --seed`): adds the method "oracle",
    /// synthesize_as() of each neutral input's take with the target emotion's style (see synth.hpp). Every clip
    /// name must parse with parse_file_stem() and every neutral clip must be reproduced by this seed and synth_fps.
    std::optional<std::uint64_t> synth_seed;
    double synth_fps = 60.0;  ///< frame rate the synthetic set was generated at (`handemo synth --fps`)
    /// How the trained G's convolution weights are held for the transfers scored (f16: rounded to binary16, the
    /// half-size inference of kernels::weight_storage; training is unchanged). With --reuse-models this scores
    /// the same trained models both ways: the accuracy cost of binary16 weights.
    kernels::weight_storage inference_weights = kernels::weight_storage::native;
    /// Methods and scores added from outside the core, in the same folds and tables (eval/extension.hpp; the
    /// circumplex method of eval/rcm.hpp).
    std::vector<std::shared_ptr<method_extension>> extensions;
    /// Also score "stargan-retargeted" on a body set: each input moved onto a foreign rig of the skeleton (other
    /// names, rest pose, proportions, units, channel order; eval/retargeted.hpp), transferred through the
    /// retargeting and scored back on the model's skeleton.
    bool retargeted = true;
    /// A circumplex table (data/rcm/circumplex.json): also measure the continuous control on every fold
    /// (eval/continuous.hpp: equality at the labels' points, monotone paths, the Lipschitz bound, halfway points)
    /// and report it. Empty: not measured.
    std::string continuous;
    /// How the continuous control blends the labels' tempo and amplitude factors between their points.
    stargan::rate_blend continuous_rates = stargan::default_rate_blend;
    /// How the change gate's inner groups are formed (schedule.hpp): shared (N + 1 inner trainings for N folds) or
    /// per fold (2 N, as `handemo train` forms them). Shared needs gate_folds 2 (the default); other gate_folds
    /// form per-fold groups.
    gate_groups gate_grouping = gate_groups::shared;
    /// Trainings run at once (each with train.threads threads, 1 when that is 0): above 1 every model is trained
    /// before the first fold is scored (schedule.hpp, train_all()), bit for bit the models of 1. In a group, per process.
    std::size_t jobs = 1;
    /// The processes the trainings are dealt over (dist/group.hpp; dist::mpi_group, `handemo eval --mpi`). Null or one
    /// process: this process trains everything. With R > 1, every process calls run_eval() with the same clips,
    /// options and out_dir (a folder every process sees); the plan's trainings run in waves dealt round the processes
    /// (schedule.hpp, run_training_waves()), then process 0 alone scores every fold, prints and writes the report, bit
    /// for bit the single-process one's models and results.csv with the same train.threads (0: each process's cores
    /// when jobs is 1, as one process with jobs 1). The other processes print nothing and return a result without
    /// folds. An error in a process is thrown there alone and the others wait for it at the wave's end: the caller
    /// ends them (the CLI: MPI_Abort).
    dist::process_group* group = nullptr;
    /// The input sets the full-rate judge chooses from in each fold (metrics::full_rate_judge: the set with the higher
    /// leave-one-content-out accuracy on the fold's training clips, the earlier on a tie). One set: that set, no choice
    /// ({pooled} is the judge of earlier reports).
    std::vector<metrics::full_rate_inputs> judge_inputs = metrics::all_full_rate_inputs();
};

/// @brief Training defaults of the evaluation: stargan::handemo_options() (the preset every command uses by
/// default; `--preset paper` gives StarGAN as the paper trains it) with its 2000 iterations per fold, a
/// checkpoint at the end of each fold only. Chosen from training-set numbers only, never from held-out results.
inline stargan::train_options default_train_options()
{
    stargan::train_options o = stargan::handemo_options();  // 2000 iterations, n_critic 1
    o.checkpoint_every = 1000000;  // the end of each fold only
    return o;
}

namespace detail {

template <std::size_t K>
struct prepared_clip {
    const labelled_clip* src;
    keyframes<K> kf;
    metrics::characteristics ch;
    metrics::characteristics full;  ///< measured on the clip as it is (measure_full())
    std::vector<double> full_f;     ///< metrics::full_rate_features() of the clip, for the full-rate judge
};

/// Mean of a loss column over the last 10% of logged rows.
inline double tail_mean(const std::vector<stargan::loss_row>& log, std::size_t col)
{
    if (log.empty()) return std::nan("");
    const std::size_t n = std::max<std::size_t>(1, log.size() / 10);
    double s = 0;
    for (std::size_t i = log.size() - n; i < log.size(); ++i) s += log[i].values[col];
    return s / static_cast<double>(n);
}

/// The lines of a CSV text, each split into its cells (stargan::detail::split_csv_line()).
inline std::vector<std::vector<std::string>> csv_rows(const std::string& text)
{
    std::vector<std::vector<std::string>> rows;
    std::size_t pos = 0;
    while (pos < text.size()) {
        const std::size_t nl = std::min(text.find('\n', pos), text.size());
        rows.push_back(stargan::detail::split_csv_line(std::string_view(text).substr(pos, nl - pos)));
        pos = nl + 1;
    }
    return rows;
}

/// Mean of the column `name` over the last 10% of the rows of a log.csv text (NaN when absent).
inline double csv_tail_mean(const std::string& text, const std::string& name)
{
    const auto rows = csv_rows(text);
    if (rows.size() < 2) return std::nan("");
    const auto it = std::find(rows[0].begin(), rows[0].end(), name);
    if (it == rows[0].end()) return std::nan("");
    const auto col = static_cast<std::size_t>(it - rows[0].begin());
    const std::size_t n = std::max<std::size_t>(1, (rows.size() - 1) / 10);
    double s = 0;
    for (std::size_t i = rows.size() - n; i < rows.size(); ++i) s += col < rows[i].size() ? std::atof(rows[i][col].c_str()) : std::nan("");
    return s / static_cast<double>(n);
}

inline std::string options_text(const eval_options& o)
{
    std::string s;
    const auto j = o.train.to_json();
    for (auto it = j.begin(); it != j.end(); ++it) s += it.key() + " " + it.value().dump() + "\n";
    s += "batch 16\nthreads " + std::to_string(o.train.threads) + "\nshards " + std::to_string(o.train.shards) +
         " (0: one on one thread, else two halves of the batch)\nfold seed train.seed + fold index\n";
    s += std::string("gate groups ") + to_string(o.gate_grouping) + "\ntrainings at once " + std::to_string(o.jobs) + "\n";
    if (o.group && o.group->ranks() > 1)
        s += "processes " + std::to_string(o.group->ranks()) + " (the trainings dealt round them in waves, the folds scored by process 0)\n";
    s += "classifier shrinkage " + std::to_string(o.shrinkage) + "\n";
    s += "full-rate judge inputs";
    for (std::size_t i = 0; i < o.judge_inputs.size(); ++i) s += std::string(i ? ", " : " ") + metrics::to_string(o.judge_inputs[i]);
    s += o.judge_inputs.size() > 1 ? " (each fold keeps the one its leave-one-content-out check recognises best)\n" : "\n";
    s += std::string("inference weights ") + kernels::weight_storage_name(o.inference_weights) + "\n";
    if (o.synth_seed) s += "synthetic set seed " + std::to_string(*o.synth_seed) + " at " + std::to_string(o.synth_fps) + " fps (oracle row)\n";
    for (const auto& x : o.extensions) s += x->options_text();
    return s;
}

/// Labels of a synthetic clip for the oracle, checking that `seed` and `fps` regenerate every neutral clip (a
/// wrong seed would make the oracle a different take). Angles are compared to 1e-3 degrees (BVH and CSV keep 6
/// decimals).
inline std::vector<stem_labels> synth_labels(const std::vector<labelled_clip>& clips, const std::string& neutral,
                                             std::uint64_t seed, double fps)
{
    std::vector<stem_labels> out;
    for (const auto& c : clips) {
        const std::string stem = c.path.stem().string();
        try {
            out.push_back(parse_file_stem(stem));
        } catch (const value_error& e) {
            throw value_error(std::string("eval: --synth-seed: ") + e.what() + " (file " + c.path.string() +
                              "; the oracle needs the synthetic hand set's names)");
        }
        if (c.emotion != neutral) continue;
        const auto& l = out.back();
        const clip again = synthesize(l.motion, l.emo, l.take, seed, fps);
        double worst = again.frames == c.motion.frames && again.angles.size() == c.motion.angles.size() ? 0.0 : std::numeric_limits<double>::infinity();
        for (std::size_t i = 0; worst < std::numeric_limits<double>::infinity() && i < again.angles.size(); ++i)
            worst = std::max(worst, std::abs(again.angles[i] - c.motion.angles[i]));
        if (!(worst <= 1e-3))
            throw value_error("eval: --synth-seed " + std::to_string(seed) + " at " + std::to_string(fps) + " fps does not reproduce " +
                              c.path.string() + " (" + std::to_string(again.frames) + " frames regenerated, " +
                              std::to_string(c.motion.frames) + " read" +
                              (worst < std::numeric_limits<double>::infinity() ? ", max angle difference " + std::to_string(worst) + " deg" : std::string()) +
                              "): give the seed and fps the set was generated with");
    }
    return out;
}

/// The contents to hold out, in order: opt.folds, or every content of the data set.
/// @throws value_error for a data set with a single content or a fold naming an unknown content.
inline std::vector<std::string> fold_contents(const std::vector<std::string>& contents, const eval_options& opt)
{
    if (contents.size() < 2)
        throw value_error("eval: data set " + opt.data + " has " + std::to_string(contents.size()) + " content(s); leave-one-content-out needs at least 2");
    std::vector<std::string> folds = opt.folds.empty() ? contents : opt.folds;
    for (const auto& f : folds)
        if (std::find(contents.begin(), contents.end(), f) == contents.end()) {
            std::string known;
            for (const auto& c : contents) known += (known.empty() ? "" : ", ") + c;
            throw value_error("eval: --folds: content '" + f + "' is not in the data set (contents: " + known + ")");
        }
    return folds;
}

/// The report's header fields, before any fold has run.
inline eval_result new_result(const stargan::config_info& info, const eval_options& opt, std::size_t planned_folds)
{
    eval_result res;
    res.config = info.name;
    res.data = opt.data;
    res.command = opt.command;
    res.commit = opt.commit;
    res.domains = info.domain_names;
    res.neutral = info.neutral;
    res.options_text = options_text(opt);
    res.planned_folds = planned_folds;
    return res;
}

/// Every clip's keyframes and characteristics, once.
template <std::size_t K>
std::vector<prepared_clip<K>> prepare_clips(const std::vector<labelled_clip>& clips)
{
    std::vector<prepared_clip<K>> all;
    all.reserve(clips.size());
    for (const auto& c : clips)
        all.push_back({&c, extract_keyframes<K>(c.motion), metrics::measure<K>(c.motion), metrics::measure_full(c.motion),
                       metrics::full_rate_features(c.motion)});
    return all;
}

/// The content a clip shows, as the content of the nearest neutral clip of the whole data set (keyframe RMSE).
template <std::size_t K>
class content_recogniser {
public:
    content_recogniser(const std::vector<prepared_clip<K>>& all, const std::string& neutral)
    {
        for (const auto& p : all)
            if (p.src->emotion == neutral) refs_.push_back(&p);
    }
    std::string operator()(const keyframes<K>& kf) const
    {
        double best = std::numeric_limits<double>::infinity();
        std::string c;
        for (const auto* r : refs_) {
            const double d = metrics::keyframe_rmse(kf, r->kf);
            if (d < best) best = d, c = r->src->content;
        }
        return c;
    }

private:
    std::vector<const prepared_clip<K>*> refs_;
};

/// One fold's clips: the held-out content's (test) and every other (train, also as copies to train on).
template <std::size_t K>
struct fold_split {
    std::vector<labelled_clip> train;
    std::vector<const prepared_clip<K>*> train_p, test_p;
};
template <std::size_t K>
fold_split<K> split_fold(const std::vector<prepared_clip<K>>& all, const std::string& held)
{
    fold_split<K> s;
    for (const auto& p : all) {
        if (p.src->content == held) {
            s.test_p.push_back(&p);
        } else {
            s.train.push_back(*p.src);
            s.train_p.push_back(&p);
        }
    }
    return s;
}

/// The training options of the fold holding out `held`.
inline stargan::train_options fold_train_options(const eval_options& opt, const std::vector<std::string>& contents,
                                                 const std::string& held)
{
    auto to = opt.train;
    // the seed follows the content's place among all contents, so `--folds X` trains X as the full run does
    to.seed = opt.train.seed + static_cast<std::uint64_t>(std::find(contents.begin(), contents.end(), held) - contents.begin());
    to.progress_out = opt.progress_out;
    return to;
}

/// The change gate's plan of the fold holding out `held`: the shared or the ring plan (schedule.hpp) under
/// <out_dir>/inner, or nothing (per-fold groups, no gate, or too few contents).
inline std::optional<stargan::gate_plan> fold_gate_plan(const eval_options& opt, const std::vector<std::string>& contents,
                                                        const std::string& held, const std::filesystem::path& out_dir)
{
    if (opt.gate_grouping == gate_groups::per_fold || opt.train.gate_folds != 2) return std::nullopt;
    if (opt.gate_grouping == gate_groups::ring) return ring_gate_plan(contents, held, out_dir / "inner", opt.train.seed);
    return shared_gate_plan(contents, held, out_dir / "inner", opt.train.seed);
}

/// Whether the gate stored in `fold_dir` was fitted with the inner groups this run forms (its gate/groups.txt).
inline bool stored_gate_groups_match(const std::filesystem::path& fold_dir, const std::vector<labelled_clip>& train,
                                     const stargan::train_options& to, const stargan::gate_plan* plan)
{
    const auto groups_path = fold_dir / "gate" / "groups.txt";
    return path_exists(groups_path) && read_file(groups_path) == stargan::gate_groups_text(train, to, plan);
}

/// --reuse-models: takes the fold's model in `fold_dir` (refitting its change gate when only the gate's options
/// differ) and its training numbers from log.csv.
/// @throws value_error when the checkpoint was trained for another configuration, step count or options.
template <stargan::stargan_config Config>
void reuse_fold_model(const std::vector<labelled_clip>& train, const stargan::config_info& info,
                      const stargan::train_options& to, const eval_options& opt, const std::filesystem::path& fold_dir,
                      fold_summary& fsum, const stargan::gate_plan* plan)
{
    namespace fs = std::filesystem;
    const fs::path ck_path = fold_dir / "checkpoint.safetensors";
    const auto ck = stargan::read_checkpoint(ck_path).second;
    const bool other_groups = to.gate_folds > 0 && !stored_gate_groups_match(fold_dir, train, to, plan);
    // only the gate's options or groups differ: G is the same, the gate is fitted again (inner models reused)
    const bool regate = ck.config == info.name && (ck.options != to.to_json() || other_groups) && stargan::detail::trained_same_g(ck, to);
    if (regate) {
        if (opt.progress_out)
            std::fprintf(opt.progress_out, "eval: --reuse-models: %s differs only in the gate's options or groups or the tempo options: "
                         "refitting the gate and the tempo\n", ck_path.string().c_str());
        stargan::refit_gate<Config>(train, info, to, fold_dir, plan);  // rewrites the checkpoint's options to `to`
    }
    if (ck.config != info.name || ck.step != to.iters || (!regate && ck.options != to.to_json()))
        throw value_error("eval: --reuse-models: " + ck_path.string() + " is a " + ck.config + " model of " +
                          std::to_string(ck.step) + " steps with options " + ck.options.dump() + ", this run wants " +
                          info.name + ", " + std::to_string(to.iters) + " steps, " + to.to_json().dump() +
                          " (remove the folder or drop --reuse-models)");
    const std::string log = path_exists(fold_dir / "log.csv") ? read_file(fold_dir / "log.csv") : std::string();
    fsum.train_d_acc = csv_tail_mean(log, "D/acc");
    fsum.train_g_cls = csv_tail_mean(log, "G/cls");
    fsum.reused_model = true;
}

/// Trains the fold's model into `fold_dir` (checkpoint, log, losses.svg) and records its training numbers.
template <stargan::stargan_config Config>
void train_fold_model(const std::vector<labelled_clip>& train, const stargan::config_info& info,
                      const stargan::train_options& to, const std::string& held, const std::filesystem::path& fold_dir,
                      fold_summary& fsum, const stargan::gate_plan* plan, bool reuse_inner = false)
{
    const auto trp = stargan::train_model<Config>(train, info, to, fold_dir, false, {}, nullptr, plan, reuse_inner);
    auto& tr = *trp;
    fsum.train_d_acc = tail_mean(tr.log(), 5);
    fsum.train_g_cls = tail_mean(tr.log(), 7);
    write_file_atomic(fold_dir / "losses.svg",
                      plot_losses_svg(stargan::loss_log_csv(tr.log()), {.title = "eval " + info.name + ": fold without " + held}));
}

/// The options of a training on `slots` job slots (training_job::run_on_slots): `slots` times the threads, the
/// shards the options resolve to on their own threads kept, so the same bits (a training's bits depend on its
/// shards, not on its threads: stargan::train_options::shards). Unchanged for one slot, for all cores (threads 0)
/// and for a training shared between processes.
template <stargan::stargan_config Config>
stargan::train_options on_slots(stargan::train_options o, std::size_t slots)
{
    if (slots <= 1 || o.threads == 0 || o.exchange) return o;
    if (o.shards == 0) o.shards = o.threads == 1 ? 1 : stargan::trainer<Config>::max_shards();
    o.threads = static_cast<unsigned>(o.threads * slots);
    return o;
}

/// @brief Trains every model the folds need, opt.jobs at a time (schedule.hpp): the change gates' inner models
/// (the shared plan's, or each fold's own), then each fold's final G once its inner models exist (its gate is
/// fitted around them, reused). With opt.reuse_models a fold whose checkpoint exists is left to the fold loop,
/// and only the inner models of a stored gate fitted with other groups are trained here. Each training runs with
/// train.threads threads (1 when that is 0 and opt.jobs > 1), the last to start with opt.jobs times as many and the
/// same bits (on_slots()), and no progress bar of its own; one line per finished training. With a group of several
/// processes, each trains its share of every wave (run_training_waves()).
/// @return per fold, the seconds its final G took (-1: left to the fold loop, reused)
template <stargan::stargan_config Config, std::size_t K>
std::vector<double> train_all(const std::vector<prepared_clip<K>>& all, const stargan::config_info& info, const eval_options& opt,
                              const std::vector<std::string>& contents, const std::vector<std::string>& folds,
                              const std::filesystem::path& out_dir)
{
    namespace fs = std::filesystem;
    struct fold_job {
        std::vector<labelled_clip> train;
        stargan::train_options to;
        std::optional<stargan::gate_plan> plan;
        fs::path dir;
        std::string held;
        bool stored = false;  ///< --reuse-models and a checkpoint exists: the fold loop reuses G
        fold_summary sum;
    };
    std::vector<fold_job> fj(folds.size());
    std::vector<std::vector<labelled_clip>> inner_train;  // the clips of each inner job, kept alive for its run
    std::vector<stargan::train_options> inner_opts;
    std::vector<fs::path> inner_dirs;
    std::vector<training_job> jobs;
    std::vector<double> seconds(folds.size(), -1.0);
    std::vector<std::size_t> final_job(folds.size(), SIZE_MAX);
    const std::size_t most = 16 * folds.size();  // gate_folds <= 16: the jobs keep pointers into these
    inner_train.reserve(most), inner_opts.reserve(most), inner_dirs.reserve(most);
    for (std::size_t fi = 0; fi < folds.size(); ++fi) {
        auto& f = fj[fi];
        f.held = folds[fi];
        f.train = split_fold(all, f.held).train;
        f.to = fold_train_options(opt, contents, f.held);
        f.to.progress_out = nullptr;
        if (f.to.threads == 0 && opt.jobs > 1) f.to.threads = 1;
        f.plan = fold_gate_plan(opt, contents, f.held, out_dir);
        f.dir = out_dir / "folds" / f.held;
        f.stored = opt.reuse_models && path_exists(f.dir / "checkpoint.safetensors");
    }
    std::vector<std::vector<std::size_t>> fold_inner(folds.size());  // the inner jobs each fold's gate needs
    for (std::size_t fi = 0; fi < folds.size(); ++fi) {
        auto& f = fj[fi];
        if (f.to.gate_folds <= 0) continue;
        const stargan::gate_plan* plan = f.plan ? &*f.plan : nullptr;
        // the inner groups fit_change_gate() forms, and the model that scores each: the plan's or the fold's own
        const auto groups = stargan::detail::make_content_groups(f.train, f.to, plan);
        // a stored gate is refitted by the fold loop; its inner models are trained here first when it was fitted
        // with other groups or inner models the options no longer train (gate_iters_scale)
        if (f.stored && stored_gate_groups_match(f.dir, f.train, f.to, plan)) {
            bool inner_match = true;
            for (std::size_t g = 0; g < groups.F && inner_match; ++g) {
                const fs::path ck = groups.dir(g, f.dir / "gate") / "checkpoint.safetensors";
                inner_match = path_exists(ck) &&
                              stargan::detail::trained_same_g(stargan::read_checkpoint(ck).second,
                                                              stargan::inner_gate_options(f.to, groups.seed(g, f.to)));
            }
            if (inner_match) continue;
        }
        for (std::size_t g = 0; g < groups.F; ++g) {
            const fs::path dir = groups.dir(g, f.dir / "gate");
            const auto it = std::find(inner_dirs.begin(), inner_dirs.end(), dir);
            if (it != inner_dirs.end()) {  // shared with an earlier fold
                fold_inner[fi].push_back(static_cast<std::size_t>(it - inner_dirs.begin()));
                continue;
            }
            // the clips fit_change_gate() trains group g's model on: the fold's, in order, without group g's contents
            std::vector<labelled_clip> tr;
            for (const auto& c : f.train)
                if (groups.of(c.content) != g) tr.push_back(c);
            inner_train.push_back(std::move(tr));
            inner_opts.push_back(stargan::inner_gate_options(f.to, groups.seed(g, f.to)));
            inner_dirs.push_back(dir);
            fold_inner[fi].push_back(inner_dirs.size() - 1);
        }
    }
    for (std::size_t i = 0; i < inner_dirs.size(); ++i) {
        std::string names;
        for (const auto& c : contents)
            if (std::any_of(inner_train[i].begin(), inner_train[i].end(), [&](const labelled_clip& x) { return x.content == c; }))
                names += (names.empty() ? "" : ", ") + c;
        jobs.push_back({"gate model " + inner_dirs[i].lexically_relative(out_dir).string() + " (on " + names + ")", {}, {}, 0,
                        inner_dirs[i] / "checkpoint.safetensors", [&, i](std::size_t slots) {
                            bool reused = false;
                            stargan::detail::inner_gate_model<Config>(inner_train[i], info, on_slots<Config>(inner_opts[i], slots),
                                                                      inner_dirs[i], true, "", reused);
                        }});
    }
    for (std::size_t fi = 0; fi < folds.size(); ++fi) {
        auto& f = fj[fi];
        if (f.stored) continue;
        std::vector<std::size_t> after = fold_inner[fi];
        final_job[fi] = jobs.size();
        jobs.push_back({"fold without " + f.held, {}, std::move(after), 0, f.dir / "checkpoint.safetensors", [&, fi](std::size_t slots) {
                            auto& g = fj[fi];
                            // its inner models were trained by the jobs it waits on
                            train_fold_model<Config>(g.train, info, on_slots<Config>(g.to, slots), g.held, g.dir, g.sum,
                                                     g.plan ? &*g.plan : nullptr, true);
                        }});
    }
    const std::size_t processes = opt.group ? opt.group->ranks() : 1;
    const std::string where = processes > 1 ? " on each of " + std::to_string(processes) + " processes" : "";
    if (opt.progress_out)
        std::fprintf(opt.progress_out, "eval: training %zu models (%zu for the change gates, %zu folds), %zu at a time%s\n", jobs.size(),
                     inner_dirs.size(), jobs.size() - inner_dirs.size(), opt.jobs, where.c_str()),
            std::fflush(opt.progress_out);
    if (processes > 1)
        run_training_waves(jobs, *opt.group, opt.jobs, opt.progress_out, "eval " + info.name + ": training");
    else
        run_training_jobs(jobs, opt.jobs, opt.progress_out, "eval " + info.name + ": training");
    for (std::size_t fi = 0; fi < folds.size(); ++fi)
        if (final_job[fi] != SIZE_MAX) seconds[fi] = jobs[final_job[fi]].seconds;
    return seconds;
}

/// The fold's trained model and its two ablations, built from one checkpoint.
template <stargan::stargan_config Config>
struct fold_models {
    using model_type = stargan::detail::emotion_model_impl<Config>;
    fold_models(const safetensors_file& f, const stargan::checkpoint_info& info, kernels::weight_storage storage)
        : model(f, info, storage),
          has_amp(model.amplitude_stage()),
          g_only(f, without_amplitude(info, has_amp), storage),
          gated(has_gate(info)),
          ungated(f, without_gate(info), storage)
    {
    }
    model_type model;
    bool has_amp;          ///< the model has a learned amplitude stage
    model_type g_only;     ///< the model without the amplitude stage and the joint lag: what G alone does (an ablation row)
    bool gated;            ///< the change gate is not all "G's whole change"
    model_type ungated;    ///< the model with G's whole change: what the change gate buys (an ablation row)

private:
    static stargan::checkpoint_info without_amplitude(stargan::checkpoint_info info, bool has_amp)
    {
        if (has_amp) info.options["amplitude"] = false;
        info.lag.clear();
        return info;
    }
    static bool has_gate(const stargan::checkpoint_info& info)
    {
        bool gated = false;
        for (std::size_t d = 0; d < info.gate_posture.size(); ++d)
            gated |= info.gate_posture[d] != 1.0 || info.gate_motion[d] != 1.0 || info.gate_prior[d] != 0.0;
        return gated;
    }
    static stargan::checkpoint_info without_gate(stargan::checkpoint_info info)
    {
        info.gate_posture.assign(info.gate_posture.size(), 1.0);
        info.gate_motion.assign(info.gate_motion.size(), 1.0);
        info.gate_prior.assign(info.gate_prior.size(), 0.0);
        info.posture_centre.clear();  // G's change as G gives it
        return info;
    }
};

/// The independent emotion classifier of a fold, fitted on its training clips; records its training accuracy.
template <std::size_t K>
metrics::nearest_centroid_classifier fit_classifier(const std::vector<const prepared_clip<K>*>& train_p, double shrinkage,
                                           fold_summary& fsum)
{
    metrics::nearest_centroid_classifier clf;
    std::vector<std::vector<double>> x;
    std::vector<std::string> y;
    for (const auto* p : train_p) x.push_back(metrics::motion_features(p->kf, p->ch.duration)), y.push_back(p->src->emotion);
    clf.fit(x, y, shrinkage);
    std::size_t ok = 0;
    for (std::size_t i = 0; i < x.size(); ++i) ok += clf.predict(x[i]) == y[i];
    fsum.classifier_train_acc = static_cast<double>(ok) / static_cast<double>(x.size());
    return clf;
}

/// The neutral clip the full-rate judge reads `p` against, among `clips`: the neutral clip of p's content and take,
/// else its content's first neutral clip; nullptr when its content has none.
template <std::size_t K>
const prepared_clip<K>* neutral_reference(const std::vector<const prepared_clip<K>*>& clips, const prepared_clip<K>& p, const std::string& neutral)
{
    const prepared_clip<K>* ref = nullptr;
    for (const auto* q : clips) {
        if (q->src->emotion != neutral || q->src->content != p.src->content) continue;
        if (q->src->take == p.src->take) return q;
        if (!ref) ref = q;
    }
    return ref;
}

/// The full-rate judge of a fold (metrics::full_rate_judge), fitted on its training clips only: each clip read
/// against the neutral clip of its content and take (its content's first neutral clip when that take has none;
/// a content without a neutral clip is left out), the contents as the groups of its cross-validation, the input set
/// chosen from `inputs` by that cross-validation. Records the set kept, its cross-validated accuracy and the weight.
/// @throws value_error when no training clip has a neutral reference.
template <std::size_t K>
metrics::full_rate_judge fit_full_rate_judge(const std::vector<const prepared_clip<K>*>& train_p, const std::string& neutral,
                                             const std::vector<metrics::full_rate_inputs>& inputs, fold_summary& fsum)
{
    std::vector<std::vector<double>> x, r;
    std::vector<std::string> y, g;
    for (const auto* p : train_p) {
        const auto* ref = neutral_reference(train_p, *p, neutral);
        if (!ref) continue;
        x.push_back(p->full_f), r.push_back(ref->full_f), y.push_back(p->src->emotion), g.push_back(p->src->content);
    }
    if (x.empty()) throw value_error("eval: the full-rate judge has no training clip with a '" + neutral + "' clip of its content");
    metrics::full_rate_judge judge;
    judge.fit(x, r, y, g, inputs);
    fsum.judge_cv_acc = judge.classifier().cv_accuracy_chosen();
    fsum.judge_lambda = judge.classifier().lambda();
    fsum.judge_inputs = metrics::to_string(judge.inputs());
    fsum.judge_candidates.clear();
    for (std::size_t i = 0; i < judge.candidates().size(); ++i)
        fsum.judge_candidates += (i ? ", " : "") + std::string(metrics::to_string(judge.candidates()[i])) + " " +
                                 detail::fmt(100 * judge.candidate_cv_accuracy()[i], 0) + "%";
    return judge;
}

/// Seen-content diagnostic: the training contents' neutral takes transferred to their real targets (StarGAN
/// and identity RMSE).
template <std::size_t K, class Model>
void seen_content_rmse(const Model& model, const std::vector<const prepared_clip<K>*>& train_p, const std::string& neutral,
                       fold_summary& fsum)
{
    double ss = 0, si = 0;
    std::size_t n = 0;
    for (const auto* in : train_p) {
        if (in->src->emotion != neutral) continue;
        for (const auto* t : train_p) {
            if (t->src->content != in->src->content || t->src->take != in->src->take || t->src->emotion == neutral) continue;
            ss += metrics::keyframe_rmse(extract_keyframes<K>(model.transfer(in->src->motion, t->src->emotion).motion), t->kf);
            si += metrics::keyframe_rmse(in->kf, t->kf);
            ++n;
        }
    }
    fsum.seen_rmse_stargan = n ? ss / static_cast<double>(n) : std::nan("");
    fsum.seen_rmse_identity = n ? si / static_cast<double>(n) : std::nan("");
}

/// The held-out clip of `target` with the input's take, or nullptr.
template <std::size_t K>
const prepared_clip<K>* real_target(const std::vector<const prepared_clip<K>*>& test_p, const prepared_clip<K>& in,
                                    const std::string& target)
{
    const prepared_clip<K>* real = nullptr;
    for (const auto* p : test_p)
        if (p->src->emotion == target && p->src->take == in.src->take) real = p;
    return real;
}

/// What every method makes of one held-out neutral input for one target emotion; rows() lists them, with the
/// clips that are not outputs (identity, nearest neighbour, real), in the order of the report.
struct method_outputs {
    stargan::transfer_result stargan;
    clip detailed, g_only, ungated, amp_only, statistics, mean_offset, oracle;
    const clip* input = nullptr;
    const clip* nearest = nullptr;
    const clip* real = nullptr;
    bool has_amp = false, gated = false, has_oracle = false;
    std::vector<std::pair<std::string, clip>> extra;

    std::vector<std::pair<const char*, const clip*>> rows() const
    {
        std::vector<std::pair<const char*, const clip*>> outs = {{"stargan", &stargan.motion}, {"stargan+detail", &detailed},
                                                                 {"identity", input},          {"mean-offset", &mean_offset},
                                                                 {"nearest-neighbour", nearest}, {"real", real}};
        if (has_amp) outs.push_back({"stargan-g", &g_only}), outs.push_back({"amplitude-only", &amp_only});
        outs.push_back({"statistics", &statistics});
        if (gated) outs.push_back({"stargan-ungated", &ungated});
        if (has_oracle) outs.push_back({"oracle", &oracle});
        for (const auto& [name, c] : extra) outs.push_back({name.c_str(), &c});
        return outs;
    }
};

/// Identity with the learned amplitude and tempo of a transfer, no G: what the amplitude stage alone buys (within
/// the model's joint limits, as its transfers).
template <std::size_t K>
clip amplitude_only(const clip& in, const stargan::transfer_result& tr, const stargan::emotion_model& model)
{
    auto k = extract_keyframes<dynamic_keyframes>(in, K);
    stargan::scale_keyframe_excursions(k, tr.amplitude, tr.amplitude_anchor);
    model.clamp_to_limits(k);
    clip out = reconstruct(k, in.skel, tr.motion.frames, in.fps);
    model.clamp_to_limits(out);
    out.positions = stargan::stretch_positions(in, tr.motion.frames);
    return out;
}

/// The detail layer's example picture: for one transfer, the channel where the real target clip has the most detail
/// (about its keyframe spline), as the real clip, stargan's output and stargan+detail's draw it over normalised time.
template <std::size_t K>
void add_detail_curves(std::vector<track_series>& curves, const std::string& target, const clip& real, const clip& plain, const clip& detailed)
{
    const auto st = measure_detail<K>(real);
    const std::size_t ch = static_cast<std::size_t>(std::max_element(st.amplitude.begin(), st.amplitude.end()) - st.amplitude.begin());
    const std::string panel = target + ": " + real.skel.joints[ch / 3].name + " " + axis_name(static_cast<axis>(ch % 3));
    double real_mean = 0;
    for (const auto& [name, c] : {std::pair<const char*, const clip*>{"real", &real}, {"stargan", &plain}, {"stargan+detail", &detailed}}) {
        clip u = *c;
        unwrap_angles(u);
        track_series t{panel, name, {}, {}};
        double mean = 0;
        for (std::size_t f = 0; f < u.frames; ++f) mean += u.angles[f * u.skel.size() * 3 + ch] / static_cast<double>(u.frames);
        if (c == &real) real_mean = mean;
        // the same angle drawn within 180 degrees of the real track's mean (Euler tracks may differ by whole turns)
        const double turns = 360.0 * std::round((mean - real_mean) / 360.0);
        for (std::size_t f = 0; f < u.frames; ++f)
            t.t.push_back(static_cast<double>(f) / static_cast<double>(u.frames - 1)), t.v.push_back(u.angles[f * u.skel.size() * 3 + ch] - turns);
        curves.push_back(std::move(t));
    }
}

/// The report section with the detail layer's example picture (detail.svg).
inline report_section detail_section(const std::vector<track_series>& curves, const std::string& held, const std::string& take,
                                     const std::vector<fold_summary>& folds)
{
    report_section sec;
    if (curves.empty()) return sec;
    sec.title = "The detail layer, one held-out example";
    track_plot_options o;
    o.title = "held out: " + held + " (take " + take + "): what 9 keyframes miss, put back";
    sec.file = "detail.svg";
    sec.file_text = plot_tracks_svg(curves, o);
    sec.markdown = "The first held-out neutral take of fold '" + held + "', transferred to each emotion. Per emotion the channel "
                   "where the real clip has the most detail about its own keyframe spline: **real** (the captured clip), **stargan** "
                   "(its 9-keyframe spline) and **stargan+detail** (the same with the input's own detail, played back at the target's "
                   "frequency and scaled to its amplitude, both learned from the fold's training clips; the keyframes are "
                   "unchanged). Time is normalised (the clips' durations differ). The full-rate ROM and speed columns of the tables "
                   "above measure it over every fold.\n\n![detail layer](detail.svg)\n\nThe layer's strength (the exponent of its "
                   "gains and rate: 0 keeps the input's detail as it is, 1 the statistics as learned), chosen per fold inside the "
                   "training set (`detail_layer::fit_checked()`):";
    for (const auto& f : folds) sec.markdown += " " + f.held_out + " " + fmt(f.detail_strength, 2) + (&f == &folds.back() ? "." : ",");
    sec.markdown += "\n";
    return sec;
}

/// Scores one method's output against the real target clip and the input (the columns of results.csv).
template <std::size_t K>
sample_record score_output(const clip& out, const prepared_clip<K>& in, const prepared_clip<K>& real, const std::string& held,
                           const std::string& target, const char* method, const metrics::nearest_centroid_classifier& clf,
                           const metrics::full_rate_judge& judge,
                           const content_recogniser<K>& content_of, double real_rom, double real_speed,
                           const std::vector<std::shared_ptr<method_extension>>& extensions)
{
    const auto kf = extract_keyframes<K>(out);
    const auto ch = metrics::measure<K>(out);
    const auto full = metrics::measure_full(out);
    sample_record s;
    s.fold = held, s.target = target, s.take = in.src->take, s.method = method;
    s.rmse_real = metrics::keyframe_rmse(kf, real.kf);
    s.rmse_input = metrics::keyframe_rmse(kf, in.kf);
    s.predicted_emotion = clf.predict(metrics::motion_features(kf, ch.duration));
    s.emotion_ok = s.predicted_emotion == target;
    s.predicted_emotion_full = judge.predict(metrics::full_rate_features(out), in.full_f);
    s.emotion_ok_full = s.predicted_emotion_full == target;
    s.predicted_content = content_of(kf);
    s.content_ok = s.predicted_content == held;
    s.rom_ratio = metrics::ratio(ch.range_of_motion, in.ch.range_of_motion, "range of motion");
    s.speed_ratio = metrics::ratio(ch.speed, in.ch.speed, "speed");
    s.real_rom_ratio = real_rom, s.real_speed_ratio = real_speed;
    s.rom_error = metrics::log_ratio_error(s.rom_ratio, real_rom);
    s.speed_error = metrics::log_ratio_error(s.speed_ratio, real_speed);
    s.rom_ratio_full = metrics::ratio(full.range_of_motion, in.full.range_of_motion, "range of motion (full rate)");
    s.speed_ratio_full = metrics::ratio(full.speed, in.full.speed, "speed (full rate)");
    s.real_rom_ratio_full = metrics::ratio(real.full.range_of_motion, in.full.range_of_motion, "range of motion (full rate)");
    s.real_speed_ratio_full = metrics::ratio(real.full.speed, in.full.speed, "speed (full rate)");
    s.rom_error_full = metrics::log_ratio_error(s.rom_ratio_full, s.real_rom_ratio_full);
    s.speed_error_full = metrics::log_ratio_error(s.speed_ratio_full, s.real_speed_ratio_full);
    s.duration_ratio = metrics::ratio(out.duration(), in.src->motion.duration(), "duration");
    s.real_duration_ratio = metrics::ratio(real.src->motion.duration(), in.src->motion.duration(), "duration");
    s.duration_error = metrics::duration_error(out, real.src->motion);
    if (full.cadence > 0 && in.full.cadence > 0 && real.full.cadence > 0) {
        s.cadence_ratio_full = full.cadence / in.full.cadence;
        s.real_cadence_ratio_full = real.full.cadence / in.full.cadence;
        s.cadence_error_full = metrics::log_ratio_error(s.cadence_ratio_full, s.real_cadence_ratio_full);
    }
    for (const auto& x : extensions) x->score(s, out);
    return s;
}

}  // namespace detail

namespace detail {

/// gate.csv rows pooled, weighted by their pairs: the chosen settings scored inside, the rule's check, the real
/// inner clips' recognition.
struct gate_check_sum {
    double pairs = 0, rmse_in = 0, emotion_in = 0, real = 0;  // sums weighted by pairs
    double cross_pairs = 0, rmse_cross = 0, emotion_cross = 0;
    /// the statistics setting on the checked pairs (tables with its columns only), and the targets the guard set to it
    double stat_pairs = 0, rmse_stat = 0, emotion_stat = 0, targets = 0, guarded = 0;
    void add(const gate_check_sum& o)
    {
        pairs += o.pairs, rmse_in += o.rmse_in, emotion_in += o.emotion_in, real += o.real;
        cross_pairs += o.cross_pairs, rmse_cross += o.rmse_cross, emotion_cross += o.emotion_cross;
        stat_pairs += o.stat_pairs, rmse_stat += o.rmse_stat, emotion_stat += o.emotion_stat, targets += o.targets, guarded += o.guarded;
    }
    /// The table cells "pairs | inside | checked | real | statistics checked | guarded |".
    std::string cells() const
    {
        return std::to_string(static_cast<long>(pairs)) + " | " + fmt(rmse_in / pairs) + " / " + fmt(100 * emotion_in / pairs, 1) + "% | " +
               fmt(rmse_cross / cross_pairs) + " / " + fmt(100 * emotion_cross / cross_pairs, 1) + "% | " + fmt(100 * real / pairs, 1) + "% | " +
               (stat_pairs > 0 ? fmt(rmse_stat / stat_pairs) + " / " + fmt(100 * emotion_stat / stat_pairs, 1) + "% | " +
                                     std::to_string(static_cast<long>(guarded)) + " of " + std::to_string(static_cast<long>(targets)) + " |"
                               : std::string("n/a | n/a |"));
    }
};

}  // namespace detail

/// @brief The report section "The change gate, checked inside the training sets" from the folds'
/// `gate/gate.csv` (and `gate/gate_margins.csv`) under out_dir/folds/: per fold, pooled over the target
/// emotions and weighted by their pairs, the chosen settings scored on the inner pairs that chose them, the
/// rule's check (chosen on one inner group, scored on the other), the real inner clips' recognition and the
/// margin used. Only training-set numbers. Empty (no title) when no fold has a gate table.
/// @throws format_error naming the file for a table it cannot read.
inline report_section gate_check_section(const eval_result& r, const std::filesystem::path& out_dir)
{
    report_section sec;
    std::string rows;
    detail::gate_check_sum total;
    for (const auto& f : r.folds) {
        const auto gate_dir = out_dir / "folds" / f.held_out / "gate";
        if (!path_exists(gate_dir / "gate.csv")) continue;
        const auto lines = detail::csv_rows(read_file(gate_dir / "gate.csv"));
        if (lines.empty()) continue;
        const auto& head = lines[0];
        if (std::find(head.begin(), head.end(), "rmse_cross") == head.end()) continue;  // made before the check existed
        const auto col = [&](const char* name) {
            const auto it = std::find(head.begin(), head.end(), name);
            if (it == head.end()) throw format_error((gate_dir / "gate.csv").string() + ": no column '" + name + "'");
            return static_cast<std::size_t>(it - head.begin());
        };
        const std::size_t c_pairs = col("pairs"), c_rg = col("rmse_gated"), c_eg = col("emotion_gated"), c_rc = col("rmse_cross"),
                          c_ec = col("emotion_cross"), c_er = col("emotion_real");
        const bool has_stat = std::find(head.begin(), head.end(), "guarded") != head.end();  // made before the guard: n/a
        const std::size_t c_rs = has_stat ? col("rmse_cross_statistics") : 0, c_es = has_stat ? col("emotion_cross_statistics") : 0,
                          c_gd = has_stat ? col("guarded") : 0;
        detail::gate_check_sum sum;
        for (std::size_t i = 1; i < lines.size(); ++i) {
            const auto& cells = lines[i];
            if (cells.size() == 1 && cells[0].empty()) continue;  // a blank line
            if (cells.size() != head.size())
                throw format_error((gate_dir / "gate.csv").string() + ": line " + std::to_string(i + 1) + " has " + std::to_string(cells.size()) +
                                   " cells, the header " + std::to_string(head.size()));
            const auto num = [&](std::size_t c) { return std::strtod(cells[c].c_str(), nullptr); };
            const double n = num(c_pairs);
            sum.pairs += n, sum.rmse_in += n * num(c_rg), sum.emotion_in += n * num(c_eg), sum.real += n * num(c_er);
            if (std::isfinite(num(c_rc))) sum.cross_pairs += n, sum.rmse_cross += n * num(c_rc), sum.emotion_cross += n * num(c_ec);
            if (has_stat) {
                if (std::isfinite(num(c_rs))) sum.stat_pairs += n, sum.rmse_stat += n * num(c_rs), sum.emotion_stat += n * num(c_es);
                sum.targets += 1, sum.guarded += num(c_gd);
            }
        }
        if (sum.pairs <= 0 || sum.cross_pairs <= 0) continue;
        std::string margin = "(fixed)";
        if (path_exists(gate_dir / "gate_margins.csv"))
            for (const auto& cells : detail::csv_rows(read_file(gate_dir / "gate_margins.csv")))
                if (cells.size() == 6 && cells[5] == "1") margin = cells[0];
        total.add(sum);
        rows += "| " + f.held_out + " | " + sum.cells() + " " + margin + " |\n";
    }
    if (rows.empty()) return sec;
    sec.title = "The change gate, checked inside the training sets";
    sec.markdown =
        "Training-set numbers only (each fold's `gate/gate.csv`, pooled over the target emotions, weighted by their inner held-out "
        "pairs): **inside** scores the chosen settings on the inner pairs that chose them (optimistic); **checked** is the rule's "
        "choice made on one inner group's pairs and scored on the other group's; **real** is how often the inner classifier "
        "recognises the real inner held-out clips; **margin** the recognition margin used (chosen by the check with "
        "`--gate-auto-margin`, `gate/gate_margins.csv`); **statistics checked** is the statistics setting (the posture prior "
        "alone, no G) on the pairs the check scored, and **guarded** how many target emotions the guard (`--gate-guard`) set to "
        "it because the check did not beat it. Compare checked with real, and with the held-out stargan row above.\n\n"
        "| held out | inner pairs | inside: RMSE (deg) / recognised | checked: RMSE (deg) / recognised | real recognised | "
        "statistics checked: RMSE (deg) / recognised | guarded | margin |\n"
        "|---|---|---|---|---|---|---|---|\n" +
        rows + "| all | " + total.cells() + " |\n";
    return sec;
}

/// @brief Runs the leave-one-content-out evaluation for one configuration.
/// @param clips the whole labelled data set (load_folder())
/// @param out_dir the report folder: per-fold models and loss curves go to out_dir/folds/<content>/
/// @return every record; the caller writes the report with write_report() (run_eval_named() does). In a group
///         (eval_options::group), only process 0's holds the folds; the others' has the header fields alone.
/// @throws value_error for an unknown held-out content, a data set with a single content, or no neutral takes
///         in a fold; with opt.synth_seed, for a clip name that is not a synthetic take or a neutral clip the seed
///         does not reproduce; the errors of training and transfer otherwise.
template <stargan::stargan_config Config>
eval_result run_eval(const std::vector<labelled_clip>& clips, const stargan::config_info& info, const eval_options& opt,
                     const std::filesystem::path& out_dir)
{
    namespace fs = std::filesystem;
    using clock = std::chrono::steady_clock;
    constexpr std::size_t K = Config::keyframes;
    const bool distributed = opt.group && opt.group->ranks() > 1;
    if (distributed && !opt.group->writes_files() && opt.progress_out) {  // process 0 alone prints
        eval_options quiet = opt;
        quiet.progress_out = nullptr;
        return run_eval<Config>(clips, info, quiet, out_dir);
    }
    const auto t_start = clock::now();
    opt.train.validate();
    const auto contents = stargan::contents_of(clips);
    const std::vector<std::string> folds = detail::fold_contents(contents, opt);
    for (const auto& c : clips) (void)stargan::domain_index(info, c.emotion);  // unknown emotion: error naming it
    // labels of the synthetic set, parallel to clips (empty without synth_seed)
    const std::vector<stem_labels> synth =
        opt.synth_seed ? detail::synth_labels(clips, info.neutral, *opt.synth_seed, opt.synth_fps) : std::vector<stem_labels>{};

    eval_result res = detail::new_result(info, opt, folds.size());
    const auto all = detail::prepare_clips<K>(clips);
    const detail::content_recogniser<K> content_of(all, info.neutral);  // content references: every neutral clip
    // the retargeted variant (eval/retargeted.hpp): bodies only, the rest pose of the first clip's first frame
    const std::optional<foreign_rig> rig = opt.retargeted && !clips.empty() ? make_foreign_rig(clips.front().motion.skel, clips.front().motion)
                                                                            : std::nullopt;

    std::vector<track_series> detail_curves;  // the detail layer's example: the first fold's first input
    std::string detail_take;
    // the continuous control's table, read and checked against the model's emotions before any fold trains
    std::optional<circumplex_table> continuous_table;
    std::vector<continuous_fold> continuous_folds;
    if (!opt.continuous.empty()) {
        continuous_table = load_circumplex(opt.continuous);
        for (const auto& d : info.domain_names) continuous_table->at(d, opt.continuous);
    }
    // with jobs > 1 or several processes, every model first (schedule.hpp), then the folds are scored with them one by
    // one, by process 0 alone
    std::vector<double> pretrained_seconds;
    if (opt.jobs > 1 || distributed) pretrained_seconds = detail::train_all<Config>(all, info, opt, contents, folds, out_dir);
    if (distributed && !opt.group->writes_files()) return res;
    // the folds' bar starts here, so that its ETA counts only the folds' own time (not the trainings done before)
    progress overall("eval " + info.name, static_cast<long>(folds.size()), opt.progress_out, 0.0);
    for (std::size_t fi = 0; fi < folds.size(); ++fi) {
        const std::string& held = folds[fi];
        const auto split = detail::split_fold(all, held);
        const auto& train = split.train;
        fold_summary fsum;
        fsum.held_out = held;
        fsum.train_clips = train.size();
        if (opt.progress_out)
            std::fprintf(opt.progress_out, "eval: fold %zu/%zu: holding out '%s' (%zu training clips, %zu held-out clips)\n", fi + 1,
                         folds.size(), held.c_str(), train.size(), split.test_p.size()),
                std::fflush(opt.progress_out);

        // ---- train StarGAN on the other contents (or take the model a previous run trained)
        const fs::path fold_dir = out_dir / "folds" / held;
        auto t0 = clock::now();
        const auto to = detail::fold_train_options(opt, contents, held);
        const auto plan = detail::fold_gate_plan(opt, contents, held, out_dir);
        if (!pretrained_seconds.empty() || (opt.reuse_models && path_exists(fold_dir / "checkpoint.safetensors")))
            detail::reuse_fold_model<Config>(train, info, to, opt, fold_dir, fsum, plan ? &*plan : nullptr);
        else
            detail::train_fold_model<Config>(train, info, to, held, fold_dir, fsum, plan ? &*plan : nullptr);
        fsum.train_seconds = std::chrono::duration<double>(clock::now() - t0).count();
        if (!pretrained_seconds.empty()) {  // trained by train_all(), not reused from an earlier run
            fsum.reused_model = pretrained_seconds[fi] < 0;
            if (pretrained_seconds[fi] >= 0) fsum.train_seconds = pretrained_seconds[fi];
        }
        t0 = clock::now();
        auto [ckf, ckinfo] = stargan::read_checkpoint(fold_dir / "checkpoint.safetensors");
        const detail::fold_models<Config> models(ckf, ckinfo, opt.inference_weights);
        auto ws = models.model.make_workspace(), ws_g_only = models.g_only.make_workspace(), ws_ungated = models.ungated.make_workspace();

        // ---- baselines and the independent emotion classifier, from the training clips only
        const auto offset = metrics::mean_offset_baseline<K>::fit(train, info.neutral);
        std::vector<detail_layer::sample> detail_data;
        for (const auto& c : train) detail_data.push_back({&c.motion, c.emotion, c.content, c.take});
        const auto fold_detail = detail_layer::fit_checked(detail_data, info.neutral, K);  // the detail layer, from training clips only
        fsum.detail_strength = fold_detail.strength;
        {  // the tempo's check on the training clips, reported whether or not the model applies its weight
            const auto tf = stargan::tempo_fit(train, info.domain_names, info.neutral, true, stargan::parse_tempo_basis(to.tempo_basis));
            fsum.tempo_estimator = std::string(stargan::to_string(tf.estimator));
            fsum.tempo_basis = std::string(stargan::to_string(tf.basis.basis));
            fsum.tempo_basis_disagreement = tf.basis.disagreement;
            fsum.tempo_shrink_weight = tf.shrink_weight;
            fsum.tempo_shrink_applied = to.tempo_shrink;
            for (std::size_t w = 0; w < tf.shrink_errors.size(); ++w) {
                if (stargan::tempo_shrink_grid[w] == tf.shrink_weight) fsum.tempo_shrink_error = tf.shrink_errors[w];
                if (stargan::tempo_shrink_grid[w] == 0.0) fsum.tempo_unshrunk_error = tf.shrink_errors[w];
            }
        }
        {  // the tempo neighbours' check on the training clips, reported whether or not the model applies them
            const auto tn = stargan::tempo_neighbours_fit(train, info.domain_names, info.neutral, to.tempo_shrink, stargan::parse_tempo_basis(to.tempo_basis));
            if (std::isfinite(tn.errors.front())) {
                fsum.tempo_neighbours_check = "learned " + detail::fmt(tn.errors.front(), 3);
                for (std::size_t i = 0; i < stargan::tempo_neighbour_grid.size(); ++i)
                    fsum.tempo_neighbours_check += ", " + std::to_string(stargan::tempo_neighbour_grid[i]) + ": " + detail::fmt(tn.errors[i + 1], 3);
            }
            fsum.tempo_neighbours_k = tn.k;
            fsum.tempo_neighbours_applied = to.tempo_neighbours;
        }
        {  // the joint lag's check on the training clips, reported whether or not the model applies it
            std::vector<keyframes<K>> kfs;  // the training clips' keyframes, in the order of `train`
            for (const auto* p : split.train_p) kfs.push_back(p->kf);
            const auto amp = models.model.amplitude_stage() ? ckinfo.amplitude : std::vector<double>(info.domains, 1.0);
            const auto lf = stargan::joint_lags_checked<K>(train, kfs, info.domain_names, info.neutral, amp);
            for (std::size_t d = 0; d < info.domains; ++d) {
                if (info.domain_names[d] == info.neutral) continue;
                fsum.lag_check += (fsum.lag_check.empty() ? "" : ", ") + info.domain_names[d] + (lf.kept[d] ? " kept (" : " not used (") +
                                  detail::fmt(lf.check[d].second, 3) + " / " + detail::fmt(lf.check[d].first, 3) + ")";
            }
            fsum.lag_applied = to.lag;
            // the amplitude stage's anchors checked on the training clips, reported whatever anchor the model uses
            if (models.model.amplitude_stage()) {
                const auto af = stargan::fit_amplitude<K>(train, kfs, info.domain_names, info.neutral, "auto",
                                                          stargan::parse_amplitude_estimator(to.amplitude_estimator, "eval"));
                fsum.amplitude_check = detail::fmt(af.anchor_check.first, 3) + " / " + detail::fmt(af.anchor_check.second, 3);
                fsum.amplitude_anchor = stargan::anchor_name(ckinfo.amplitude_anchor);
            }
        }
        const auto clf = detail::fit_classifier<K>(split.train_p, opt.shrinkage, fsum);
        const auto judge = detail::fit_full_rate_judge<K>(split.train_p, info.neutral, opt.judge_inputs, fsum);
        detail::seen_content_rmse<K>(models.model, split.train_p, info.neutral, fsum);

        // ---- extensions (eval/extension.hpp) fit on the fold's training clips only
        if (!opt.extensions.empty()) {
            fold_context fc{held, info.neutral, &train, {}, fi, opt.progress_out};
            for (const auto* p : split.test_p) fc.test.push_back(p->src);
            for (const auto& x : opt.extensions) x->begin_fold(fc);
        }

        // ---- transfer every held-out neutral take to every other emotion and score every method's output
        for (const auto* in : split.test_p) {
            if (in->src->emotion != info.neutral) continue;
            ++fsum.test_inputs;
            const clip& input = in->src->motion;
            for (const auto& target : info.domain_names) {
                if (target == info.neutral) continue;
                const detail::prepared_clip<K>* real = detail::real_target(split.test_p, *in, target);
                if (!real) {
                    ++fsum.missing_targets;
                    continue;
                }
                detail::method_outputs o;
                o.stargan = models.model.transfer(input, target, {}, ws);
                o.has_amp = models.has_amp, o.gated = models.gated;
                o.detailed = fold_detail.apply(o.stargan.motion, input, info.neutral, target);
                models.model.clamp_to_limits(o.detailed);  // the detail a transfer adds keeps its limits too
                if (fi == 0 && (detail_take.empty() || detail_take == in->src->take)) {
                    detail_take = in->src->take;
                    detail::add_detail_curves<K>(detail_curves, target, real->src->motion, o.stargan.motion, o.detailed);
                }
                if (o.has_amp) o.g_only = models.g_only.transfer(input, target, {}, ws_g_only).motion;
                if (o.gated) o.ungated = models.ungated.transfer(input, target, {}, ws_ungated).motion;
                if (o.has_amp) o.amp_only = detail::amplitude_only<K>(input, o.stargan, models.model);
                o.statistics = models.model.statistics(input, target).motion;  // every learned part but G
                o.nearest = &train[metrics::nearest_neighbour<K>(input, train, target)].motion;
                o.mean_offset = offset.transfer(input, target, o.stargan.tempo);
                o.input = &input, o.real = &real->src->motion;
                if (opt.synth_seed) {
                    const stem_labels& l = synth[static_cast<std::size_t>(in->src - clips.data())];
                    o.oracle = synthesize_as(l.motion, l.emo, emotion_from_string(target), l.take, *opt.synth_seed, opt.synth_fps);
                    o.has_oracle = true;
                }
                if (rig) {
                    // the same transfer from a foreign rig of the skeleton, scored back on the model's skeleton; both
                    // ways the Euler branches of the input's first frame (Bandai's files write a spine near gimbal
                    // lock on either branch: the variant measures the retargeting, not a choice between the two)
                    stargan::capture_options co;
                    co.reference.assign(input.frame_angles(0), input.frame_angles(0) + input.skel.size() * 3);
                    const auto cr = stargan::transfer_capture(models.model, retarget::retarget_clip(input, rig->to_foreign), target, {}, co);
                    o.extra.emplace_back("stargan-retargeted", retarget::retarget_clip(cr.motion, rig->to_model, co.reference));
                }
                for (const auto& x : opt.extensions)
                    for (auto& e : x->transfer(*in->src, target)) o.extra.push_back(std::move(e));
                const double real_rom = metrics::ratio(real->ch.range_of_motion, in->ch.range_of_motion, "range of motion");
                const double real_speed = metrics::ratio(real->ch.speed, in->ch.speed, "speed");
                for (const auto& [method, out] : o.rows())
                    res.samples.push_back(detail::score_output<K>(*out, *in, *real, held, target, method, clf, judge, content_of, real_rom,
                                                                  real_speed, opt.extensions));
            }
        }
        if (fsum.test_inputs == 0)
            throw value_error("eval: data set " + opt.data + ": fold '" + held + "' has no '" + info.neutral + "' clip to transfer");
        if (continuous_table) {  // the continuous control of the fold's model on its held-out clips
            const stargan::continuous_control control(models.model, *continuous_table, opt.continuous_rates, opt.continuous);
            std::vector<const clip*> inputs, real_refs;
            std::vector<std::pair<const clip*, std::string>> reals;
            for (const auto* p : split.test_p) {
                if (p->src->emotion == info.neutral) inputs.push_back(&p->src->motion);
                // the full-rate judge's reference, as in its training
                const auto* ref = detail::neutral_reference(split.test_p, *p, info.neutral);
                if (!ref) continue;  // no neutral clip of its content: nothing to read it against (nor to transfer)
                reals.emplace_back(&p->src->motion, p->src->emotion);
                real_refs.push_back(&ref->src->motion);
            }
            // the circumplex analysis of an extension that gives one (eval/rcm.hpp's, fitted on this fold's training clips)
            circumplex_analysis analyse;
            if (!opt.extensions.empty())
                analyse = [&](const clip& c) {
                    for (const auto& x : opt.extensions) {
                        const auto p = x->circumplex_rank_point(c);
                        if (std::isfinite(p.first) || std::isfinite(p.second)) return p;
                    }
                    return std::pair{std::nan(""), std::nan("")};
                };
            continuous_folds.push_back(measure_continuous<K>(models.model, control, clf, inputs, reals, held, 10, analyse, &judge, real_refs));
        }
        fsum.eval_seconds = std::chrono::duration<double>(clock::now() - t0).count();
        res.folds.push_back(fsum);
        for (const auto& x : opt.extensions) x->end_fold(res);
        res.seconds = std::chrono::duration<double>(clock::now() - t_start).count();
        if (opt.write_partial) write_report(res, out_dir);
        char status[160];
        std::snprintf(status, sizeof status, "fold '%s' done (train %.1f min, D/acc %.0f%%)", held.c_str(), fsum.train_seconds / 60,
                      100 * fsum.train_d_acc);
        overall.update(static_cast<long>(fi + 1), status);
    }
    res.seconds = std::chrono::duration<double>(clock::now() - t_start).count();
    if (auto sec = gate_check_section(res, out_dir); !sec.title.empty()) res.sections.push_back(std::move(sec));
    if (continuous_table) res.sections.push_back(continuous_section(continuous_folds, 10, opt.continuous_rates));
    if (auto sec = detail::detail_section(detail_curves, folds.front(), detail_take, res.folds); !sec.title.empty()) res.sections.push_back(std::move(sec));
    return res;
}

/// @brief Loads a data folder, runs the evaluation for the configuration called `config` and writes the
/// report into `out_dir` (report.md, results.csv, summary.csv, summary.svg, folds/<content>/...).
/// Instantiates every configuration where it is called: call it from one translation unit (a template only so that it
/// is compiled where it is called, see stargan::with_config()).
/// @throws value_error for an unknown configuration, plus the errors of load_folder() and run_eval().
template <class = void>
eval_result run_eval_named(const std::filesystem::path& data, const std::string& config, eval_options opt,
                                  const std::filesystem::path& out_dir)
{
    const auto clips = stargan::load_folder(data);
    if (opt.data.empty()) opt.data = data.string();
    auto res = stargan::with_config(config, [&]<stargan::stargan_config C>(const stargan::config_info& info) {
        return run_eval<C>(clips, info, opt, out_dir);
    });
    if (!opt.group || opt.group->writes_files()) write_report(res, out_dir);  // in a group, process 0 alone
    return res;
}

}  // namespace handemo::eval
