// Results of the leave-one-content-out evaluation (the hand paper's Section 5 future work: numeric
// comparison of transferred motion with captured motion of the target emotion) and their report: one record
// per (fold, target emotion, take, method), per-fold means, a summary (mean and std over folds), the
// plain statements of where StarGAN beats each baseline and where it does not, a CSV of every number, a
// Markdown report and an SVG bar chart. Metrics: keyframe RMSE (Eq. 2 keyframes, degrees), independent
// emotion recognition, content preservation and Table 1's range-of-motion and speed ratios.
#pragma once

#include <handemo/core/error.hpp>
#include <handemo/core/io.hpp>
#include <handemo/render/svg.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <map>
#include <string>
#include <vector>

namespace handemo::eval {

/// @brief Method names in report order; "real" is the captured target clip (the reference row), "statistics" every
/// learned part of the model but G (amplitude, tempo, posture prior at full weight; emotion_model::statistics()),
/// "oracle" the synthetic set's input take re-synthesised in the target's style (only with eval_options::synth_seed), "rcm"
/// the circumplex synthesis of Aristidou et al. 2017 (only with the extension of eval/rcm.hpp), "stargan-retargeted"
/// the transfer from a foreign rig of a body skeleton (eval/retargeted.hpp).
inline const std::vector<std::string>& method_names()
{
    static const std::vector<std::string> m{"stargan", "stargan+detail", "stargan-g", "stargan-ungated", "stargan-retargeted", "identity", "mean-offset", "amplitude-only",
                                            "statistics", "nearest-neighbour", "rcm", "real", "oracle"};
    return m;
}

/// @brief The numbers of one transferred clip.
struct sample_record {
    std::string fold, target, take, method;
    double rmse_real = 0;         ///< keyframe RMSE to the real target clip (degrees)
    double rmse_input = 0;        ///< keyframe RMSE to the input (degrees)
    bool emotion_ok = false;      ///< the independent classifier says `target`
    /// The second judge (metrics::full_rate_classifier, the output's full-rate features against the input's) says `target`
    bool emotion_ok_full = false;
    std::string predicted_emotion_full;
    bool content_ok = false;      ///< the nearest neutral motion (any content) is of the input's content
    std::string predicted_emotion, predicted_content;
    double rom_ratio = 0, speed_ratio = 0;            ///< output / input
    double real_rom_ratio = 0, real_speed_ratio = 0;  ///< real target / input
    double rom_error = 0, speed_error = 0;            ///< |log(ratio / real ratio)|
    double duration_ratio = 0, real_duration_ratio = 0;  ///< duration output / input, real target / input
    double duration_error = 0;                        ///< |log(duration output / duration real)| (metrics::duration_error())
    /// The same three on the full-rate clips as they are (a capture's tremor and noise included; the detail layer's
    /// measure), not on their 9-keyframe reconstructions.
    double rom_ratio_full = 0, speed_ratio_full = 0, real_rom_ratio_full = 0, real_speed_ratio_full = 0;
    double rom_error_full = 0, speed_error_full = 0;
    /// cadence_time() (motion/cadence.hpp) output / input and real target / input, and |log(ratio / real ratio)|: the
    /// tempo a viewer sees, whatever the number of cycles the clips hold (NaN when a clip does not move)
    double cadence_ratio_full = std::nan(""), real_cadence_ratio_full = std::nan(""), cadence_error_full = std::nan("");
    /// The fold's circumplex model's analysis of the output (eval/rcm.hpp; NaN when not measured) and whether it
    /// lies in the target label's quadrant (1 or 0; NaN when not measured).
    double circumplex_valence = std::nan(""), circumplex_arousal = std::nan(""), circumplex_quadrant_ok = std::nan("");
};

/// @brief What happened in one fold besides the samples.
struct fold_summary {
    std::string held_out;
    std::size_t train_clips = 0, test_inputs = 0, missing_targets = 0;
    double train_seconds = 0, eval_seconds = 0;
    double train_d_acc = 0;  ///< mean D/acc (domain classifier on real training batches) over the last 10% of logged steps
    double train_g_cls = 0;  ///< mean G/cls over the same steps
    double classifier_train_acc = 0;  ///< the emotion classifier's accuracy on its own training clips
    /// The full-rate judge: its leave-one-content-out accuracy inside the training clips and the L2 weight it chose
    double judge_cv_acc = std::nan(""), judge_lambda = std::nan("");
    /// The input set it kept (metrics::full_rate_inputs) and each candidate's cross-validated accuracy ("pooled 71%, joints 83%")
    std::string judge_inputs, judge_candidates;
    /// Seen-content diagnostic: mean keyframe RMSE to the real target when the neutral takes of the
    /// training contents are transferred (StarGAN, and identity for scale): tells a model that does not fit
    /// its training data from one that does not generalise to the held-out content.
    double seen_rmse_stargan = 0, seen_rmse_identity = 0;
    bool reused_model = false;  ///< the fold's model was loaded (--reuse-models), not trained in this run
    double detail_strength = std::nan("");  ///< the detail layer's strength chosen on the fold's training clips
    /// The tempo's check on the fold's training clips (stargan::tempo_fit(), tempo_shrink_fit()): the estimator
    /// chosen, the shrink weight the check chooses, its error and the unshrunk factors' error (mean |log| over
    /// left-out contents), and whether the model applies the weight (train_options::tempo_shrink)
    std::string tempo_estimator;
    double tempo_shrink_weight = std::nan(""), tempo_shrink_error = std::nan(""), tempo_unshrunk_error = std::nan("");
    bool tempo_shrink_applied = false;
    /// The joint lag's check on the fold's training clips (stargan::joint_lags_checked()), per emotion "name kept|not
    /// used (with / without deg)", and whether the model applies it (train_options::lag)
    std::string lag_check;
    bool lag_applied = false;
    /// The amplitude stage's check on the fold's training clips (stargan::amplitude_prior_cv(), the statistics transfer
    /// left out content by content): "RMSE about the mean / about the ends" in degrees, and the anchor the model scales
    /// about (train_options::amplitude_anchor); empty without the amplitude stage
    std::string amplitude_check, amplitude_anchor;
    /// The tempo neighbours' check on the fold's training clips (stargan::tempo_neighbours_fit()): each candidate's
    /// mean left-out error ("learned 0.799, 3: 0.620, ..."), the count it chose (0: the learned factors) and whether
    /// the model applies it (train_options::tempo_neighbours)
    std::string tempo_neighbours_check;
    std::size_t tempo_neighbours_k = 0;
    bool tempo_neighbours_applied = false;
    /// the basis of the tempo factors (duration or cadence) and, when train_options::tempo_basis is "auto", the
    /// median disagreement of the training pairs' duration and cadence ratios that chose it (NaN otherwise)
    std::string tempo_basis;
    double tempo_basis_disagreement = std::nan("");
};

/// @brief A report section written by an extension (eval/extension.hpp): Markdown placed after the summary, and
/// optionally a file of its own in the report folder.
struct report_section {
    std::string title;     ///< `## title`
    std::string markdown;  ///< the section's body
    std::string file;      ///< a file name in the report folder (empty: none)
    std::string file_text;
};

/// @brief Everything one evaluation run produced.
struct eval_result {
    std::string config, data, command;
    std::string commit;  ///< the source commit the program was built from (eval_options::commit; empty: not recorded)
    std::vector<std::string> domains;
    std::string neutral;
    std::string options_text;  ///< training and evaluation options, one `key value` per line
    std::vector<fold_summary> folds;
    std::size_t planned_folds = 0;  ///< folds the run was asked for (more than folds.size() in a partial report)
    std::vector<sample_record> samples;
    std::vector<report_section> sections;  ///< from extensions, in the order they were added
    double seconds = 0;
};

/// @brief Whether any sample of `r` is of `method` (the report leaves out rows of methods that were not run).
inline bool has_method(const eval_result& r, const std::string& method)
{
    return std::any_of(r.samples.begin(), r.samples.end(), [&](const sample_record& s) { return s.method == method; });
}

/// @brief One metric of the report.
struct metric_def {
    std::string key, title;
    int better;  ///< -1 lower is better, +1 higher is better, 0 descriptive
    std::function<double(const sample_record&)> get;
    bool optional = false;  ///< measured only by an extension: a NaN is "not measured" and is left out of means
};

/// @brief The metrics in report order.
inline const std::vector<metric_def>& metric_defs()
{
    static const std::vector<metric_def> m{
        {"rmse_real", "RMSE to real target (deg)", -1, [](const sample_record& r) { return r.rmse_real; }},
        {"emotion_acc", "emotion recognised (%)", +1, [](const sample_record& r) { return r.emotion_ok ? 100.0 : 0.0; }},
        {"emotion_acc_full", "recognised, full-rate judge (%)", +1, [](const sample_record& r) { return r.emotion_ok_full ? 100.0 : 0.0; }},
        {"content_acc", "content kept (%)", +1, [](const sample_record& r) { return r.content_ok ? 100.0 : 0.0; }},
        {"rmse_input", "RMSE to input (deg)", 0, [](const sample_record& r) { return r.rmse_input; }},
        {"rom_ratio", "ROM ratio out/in", 0, [](const sample_record& r) { return r.rom_ratio; }},
        {"speed_ratio", "speed ratio out/in", 0, [](const sample_record& r) { return r.speed_ratio; }},
        {"rom_error", "ROM ratio error (abs log out/real)", -1, [](const sample_record& r) { return r.rom_error; }},
        {"speed_error", "speed ratio error (abs log out/real)", -1, [](const sample_record& r) { return r.speed_error; }},
        {"duration_ratio", "duration ratio out/in", 0, [](const sample_record& r) { return r.duration_ratio; }},
        {"duration_error", "duration ratio error (abs log out/real)", -1, [](const sample_record& r) { return r.duration_error; }},
        {"rom_error_full", "full-rate ROM ratio error", -1, [](const sample_record& r) { return r.rom_error_full; }},
        {"speed_error_full", "full-rate speed ratio error", -1, [](const sample_record& r) { return r.speed_error_full; }},
        {"cadence_error", "cadence ratio error (abs log out/real)", -1, [](const sample_record& r) { return r.cadence_error_full; }, true},
        {"circumplex_quadrant", "circumplex quadrant reached (%)", +1,
         [](const sample_record& r) { return 100.0 * r.circumplex_quadrant_ok; }, true},
    };
    return m;
}

/// @brief Whether any sample of `r` has a value of `m` (an optional metric is left out of the report when not).
inline bool has_metric(const eval_result& r, const metric_def& m)
{
    return !m.optional || std::any_of(r.samples.begin(), r.samples.end(), [&](const sample_record& s) { return !std::isnan(m.get(s)); });
}

/// @brief The metrics of metric_defs() that `r` has values of, in report order.
inline std::vector<metric_def> metrics_of(const eval_result& r)
{
    std::vector<metric_def> out;
    for (const auto& m : metric_defs())
        if (has_metric(r, m)) out.push_back(m);
    return out;
}

/// @brief Mean and sample standard deviation (n - 1; 0 for one value).
struct mean_std {
    double mean = 0, std = 0;
    std::size_t n = 0;
};
inline mean_std mean_and_std(const std::vector<double>& v)
{
    mean_std r;
    r.n = v.size();
    if (v.empty()) return r;
    for (double x : v) r.mean += x / static_cast<double>(v.size());
    if (v.size() > 1) {
        double s = 0;
        for (double x : v) s += (x - r.mean) * (x - r.mean);
        r.std = std::sqrt(s / static_cast<double>(v.size() - 1));
    }
    return r;
}

/// @brief Per-fold mean of a metric for (fold, target, method); target "all" pools every target. NaN when
/// there is no sample.
inline double fold_mean(const eval_result& r, const metric_def& m, const std::string& fold, const std::string& target,
                        const std::string& method)
{
    double s = 0;
    std::size_t n = 0;
    for (const auto& x : r.samples)
        if (x.fold == fold && x.method == method && (target == "all" || x.target == target)) {
            const double v = m.get(x);
            if (m.optional && std::isnan(v)) continue;
            s += v, ++n;
        }
    return n ? s / static_cast<double>(n) : std::nan("");
}

/// @brief Mean and std over folds of the per-fold means (folds without samples are skipped).
inline mean_std over_folds(const eval_result& r, const metric_def& m, const std::string& target, const std::string& method)
{
    std::vector<double> v;
    for (const auto& f : r.folds) {
        const double x = fold_mean(r, m, f.held_out, target, method);
        if (std::isfinite(x)) v.push_back(x);
    }
    return mean_and_std(v);
}

/// @brief The target emotions that occur in the samples, in domain order.
inline std::vector<std::string> targets_of(const eval_result& r)
{
    std::vector<std::string> t;
    for (const auto& d : r.domains)
        for (const auto& s : r.samples)
            if (s.target == d) {
                t.push_back(d);
                break;
            }
    return t;
}

namespace detail {

inline std::string fmt(double v, int prec = 2)
{
    if (!std::isfinite(v)) return "n/a";
    char b[48];
    std::snprintf(b, sizeof b, "%.*f", prec, v);
    return b;
}

inline std::string csv_num(double v)
{
    char b[48];
    std::snprintf(b, sizeof b, "%.9g", v);
    return b;
}

}  // namespace detail

/// @brief Every number: one CSV row per (fold, target, take, method).
inline std::string samples_csv(const eval_result& r)
{
    // the circumplex columns only when an extension measured them (the file is unchanged otherwise)
    const bool circ = std::any_of(r.samples.begin(), r.samples.end(), [](const sample_record& x) { return !std::isnan(x.circumplex_quadrant_ok); });
    std::string s = "fold,target,take,method,rmse_real,rmse_input,emotion_ok,predicted_emotion,content_ok,predicted_content,"
                    "rom_ratio,speed_ratio,real_rom_ratio,real_speed_ratio,rom_error,speed_error,rom_ratio_full,speed_ratio_full,"
                    "real_rom_ratio_full,real_speed_ratio_full,rom_error_full,speed_error_full,duration_ratio,real_duration_ratio,"
                    "duration_error,emotion_ok_full,predicted_emotion_full,cadence_ratio_full,real_cadence_ratio_full,cadence_error_full";
    s += circ ? ",circumplex_valence,circumplex_arousal,circumplex_quadrant_ok\n" : "\n";
    for (const auto& x : r.samples) {
        s += x.fold + "," + x.target + "," + x.take + "," + x.method + "," + detail::csv_num(x.rmse_real) + "," +
             detail::csv_num(x.rmse_input) + "," + (x.emotion_ok ? "1" : "0") + "," + x.predicted_emotion + "," +
             (x.content_ok ? "1" : "0") + "," + x.predicted_content + "," + detail::csv_num(x.rom_ratio) + "," +
             detail::csv_num(x.speed_ratio) + "," + detail::csv_num(x.real_rom_ratio) + "," + detail::csv_num(x.real_speed_ratio) +
             "," + detail::csv_num(x.rom_error) + "," + detail::csv_num(x.speed_error) + "," + detail::csv_num(x.rom_ratio_full) + "," +
             detail::csv_num(x.speed_ratio_full) + "," + detail::csv_num(x.real_rom_ratio_full) + "," +
             detail::csv_num(x.real_speed_ratio_full) + "," + detail::csv_num(x.rom_error_full) + "," + detail::csv_num(x.speed_error_full) +
             "," + detail::csv_num(x.duration_ratio) + "," + detail::csv_num(x.real_duration_ratio) + "," + detail::csv_num(x.duration_error) + "," +
             (x.emotion_ok_full ? "1" : "0") + "," + x.predicted_emotion_full + "," + detail::csv_num(x.cadence_ratio_full) + "," +
             detail::csv_num(x.real_cadence_ratio_full) + "," + detail::csv_num(x.cadence_error_full);
        if (circ)
            s += "," + detail::csv_num(x.circumplex_valence) + "," + detail::csv_num(x.circumplex_arousal) + "," +
                 (std::isnan(x.circumplex_quadrant_ok) ? std::string("nan") : x.circumplex_quadrant_ok > 0.5 ? "1" : "0");
        s += "\n";
    }
    return s;
}

/// @brief Summary CSV: `target,method,metric,mean,std,folds` (target "all" pools the targets).
inline std::string summary_csv(const eval_result& r)
{
    std::string s = "target,method,metric,mean,std,folds\n";
    auto targets = targets_of(r);
    targets.insert(targets.begin(), "all");
    for (const auto& t : targets)
        for (const auto& me : method_names())
            for (const auto& m : metric_defs()) {
                const auto ms = over_folds(r, m, t, me);
                if (ms.n == 0) continue;
                s += t + "," + me + "," + m.key + "," + detail::csv_num(ms.mean) + "," + detail::csv_num(ms.std) + "," +
                     std::to_string(ms.n) + "\n";
            }
    return s;
}

/// @brief One comparison of StarGAN with a baseline on one metric and target.
struct comparison {
    std::string baseline, metric, target;
    double stargan = 0, other = 0;
    std::size_t folds_better = 0, folds = 0;
    bool better = false;  ///< StarGAN's mean over folds is strictly better
};

/// @brief The methods StarGAN is compared with, in the order of the report's statements.
inline const std::vector<std::string>& baseline_names()
{
    static const std::vector<std::string> b{"identity", "mean-offset", "amplitude-only", "statistics", "nearest-neighbour", "rcm"};
    return b;
}

/// @brief StarGAN vs every baseline on every metric with a direction, per target emotion and pooled ("all").
inline std::vector<comparison> compare_with_baselines(const eval_result& r)
{
    std::vector<comparison> out;
    auto targets = targets_of(r);
    targets.insert(targets.begin(), "all");
    for (const auto& b : baseline_names())
        for (const auto& m : metrics_of(r)) {
            if (m.better == 0) continue;
            for (const auto& t : targets) {
                comparison c{b, m.key, t};
                c.stargan = over_folds(r, m, t, "stargan").mean;
                c.other = over_folds(r, m, t, b).mean;
                for (const auto& f : r.folds) {
                    const double s = fold_mean(r, m, f.held_out, t, "stargan"), o = fold_mean(r, m, f.held_out, t, b);
                    if (!std::isfinite(s) || !std::isfinite(o)) continue;
                    ++c.folds;
                    if (m.better < 0 ? s < o : s > o) ++c.folds_better;
                }
                c.better = m.better < 0 ? c.stargan < c.other : c.stargan > c.other;
                if (c.folds && std::isfinite(c.stargan) && std::isfinite(c.other)) out.push_back(c);
            }
        }
    return out;
}

/// @brief The bar that says the network is worth having: StarGAN against `statistics` (every learned part of the
/// model but G). Cleared when StarGAN's RMSE to the real clip is lower on the mean over folds, lower in at least
/// `min_share` of the (fold, target emotion) pairs, and its recognition is at least as high on the mean.
struct network_bar {
    bool present = false;             ///< the report has both rows
    double rmse_stargan = 0, rmse_statistics = 0;
    std::size_t pairs_lower = 0, pairs = 0;  ///< (fold, target) pairs where StarGAN's mean RMSE is lower, and all pairs
    double emotion_stargan = 0, emotion_statistics = 0;  ///< recognised (%), mean over folds
    double min_share = 0.7;
    bool rmse_lower() const { return rmse_stargan < rmse_statistics; }
    bool pairs_enough() const { return pairs > 0 && static_cast<double>(pairs_lower) >= min_share * static_cast<double>(pairs); }
    bool emotion_kept() const { return emotion_stargan >= emotion_statistics; }
    bool cleared() const { return present && rmse_lower() && pairs_enough() && emotion_kept(); }
};

/// @brief network_bar of a report (present is false when it lacks the stargan or the statistics row).
inline network_bar network_bar_of(const eval_result& r, double min_share = 0.7)
{
    network_bar b;
    b.min_share = min_share;
    if (!has_method(r, "stargan") || !has_method(r, "statistics")) return b;
    const auto& defs = metric_defs();
    const auto def = [&](const char* key) -> const metric_def& {
        return *std::find_if(defs.begin(), defs.end(), [&](const metric_def& m) { return m.key == key; });
    };
    const metric_def &rmse = def("rmse_real"), &emo = def("emotion_acc");
    b.rmse_stargan = over_folds(r, rmse, "all", "stargan").mean;
    b.rmse_statistics = over_folds(r, rmse, "all", "statistics").mean;
    b.emotion_stargan = over_folds(r, emo, "all", "stargan").mean;
    b.emotion_statistics = over_folds(r, emo, "all", "statistics").mean;
    for (const auto& f : r.folds)
        for (const auto& t : targets_of(r)) {
            const double s = fold_mean(r, rmse, f.held_out, t, "stargan"), o = fold_mean(r, rmse, f.held_out, t, "statistics");
            if (!std::isfinite(s) || !std::isfinite(o)) continue;
            ++b.pairs;
            b.pairs_lower += s < o;
        }
    b.present = b.pairs > 0;
    return b;
}

/// @brief The two emotion judges side by side: how often each recognises the real held-out clips (the `real` row)
/// and StarGAN's outputs (mean over folds). The stronger judge is the one with the higher real recognition (the
/// nearest-centroid one on a tie; the rule of docs/evaluation.md); StarGAN is held to real minus `margin` points
/// on it.
struct judge_bar {
    bool present = false;  ///< the report has both the real and the stargan rows
    double real_centroid = 0, real_full = 0;        ///< real clips recognised (%), nearest-centroid and full-rate judge
    double stargan_centroid = 0, stargan_full = 0;  ///< StarGAN's outputs recognised (%)
    double margin = 10;
    bool full_stronger() const { return real_full > real_centroid; }
    const char* stronger() const { return full_stronger() ? "full-rate" : "nearest-centroid"; }
    double real_stronger() const { return full_stronger() ? real_full : real_centroid; }
    double stargan_stronger() const { return full_stronger() ? stargan_full : stargan_centroid; }
    bool cleared() const { return present && stargan_stronger() >= real_stronger() - margin; }
};

/// @brief judge_bar of a report.
inline judge_bar judge_bar_of(const eval_result& r, double margin = 10)
{
    judge_bar b;
    b.margin = margin;
    if (!has_method(r, "stargan") || !has_method(r, "real")) return b;
    const auto& defs = metric_defs();
    const auto def = [&](const char* key) -> const metric_def& {
        return *std::find_if(defs.begin(), defs.end(), [&](const metric_def& m) { return m.key == key; });
    };
    const metric_def &c = def("emotion_acc"), &f = def("emotion_acc_full");
    b.real_centroid = over_folds(r, c, "all", "real").mean, b.real_full = over_folds(r, f, "all", "real").mean;
    b.stargan_centroid = over_folds(r, c, "all", "stargan").mean, b.stargan_full = over_folds(r, f, "all", "stargan").mean;
    b.present = true;
    return b;
}

/// @brief The report's paragraph on the two emotion judges (judge_bar_of()): empty without the real and stargan rows.
inline std::string report_judges(const eval_result& r)
{
    const auto b = judge_bar_of(r);
    if (!b.present) return {};
    std::string s = "## The two emotion judges\n\n";
    s += "Real held-out clips recognised: " + detail::fmt(b.real_centroid, 1) + "% by the nearest-centroid judge (keyframes), " +
         detail::fmt(b.real_full, 1) + "% by the full-rate judge (the change against the neutral input at full rate); StarGAN's "
         "outputs: " + detail::fmt(b.stargan_centroid, 1) + "% and " + detail::fmt(b.stargan_full, 1) + "%. The stronger judge on "
         "this set is the **" + b.stronger() + "** one; StarGAN at least real minus " + detail::fmt(b.margin, 0) + " points on it (" +
         detail::fmt(b.stargan_stronger(), 1) + "% vs " + detail::fmt(b.real_stronger() - b.margin, 1) + "%): **" +
         (b.cleared() ? "yes" : "no") + "**. The full-rate judge recognises at least 85% of the real clips: " +
         (b.real_full >= 85 ? "yes" : "no") + ".\n\n";
    return s;
}

/// @brief The summary bar chart: pooled mean +- std over folds per metric with a direction and per method.
inline std::string summary_svg(const eval_result& r)
{
    std::vector<bar_entry> bars;
    for (const auto& m : metric_defs()) {
        if (m.better == 0) continue;
        for (const auto& me : method_names()) {
            const auto ms = over_folds(r, m, "all", me);
            if (ms.n == 0 || !std::isfinite(ms.mean)) continue;
            bars.push_back({m.title, me, ms.mean, ms.std});
        }
    }
    bar_plot_options o;
    o.title = "handemo eval " + r.config + ": mean +- std over " + std::to_string(r.folds.size()) + " folds";
    o.panels_per_row = 3;
    o.panel_width = 300;
    return plot_bars_svg(bars, o);
}

/// @brief The per-fold plot: one panel per metric with a direction, one line per method over the folds (the
/// per-fold means pooled over targets that over_folds() averages), so a fold where a method breaks shows.
inline std::string folds_svg(const eval_result& r)
{
    std::vector<fold_point> pts;
    for (const auto& m : metric_defs()) {
        if (m.better == 0) continue;
        for (const auto& me : method_names())
            for (const auto& f : r.folds) {
                const double v = fold_mean(r, m, f.held_out, "all", me);
                if (std::isfinite(v)) pts.push_back({m.title, me, f.held_out, v});
            }
    }
    fold_plot_options o;
    o.title = "handemo eval " + r.config + ": per fold (held-out motion)";
    return plot_folds_svg(pts, o);
}

/// @brief The report's opening: title, command, what was run, the methods and metrics, the options.
inline std::string report_introduction(const eval_result& r, const std::vector<metric_def>& ms)
{
    std::string s;
    s += "# handemo eval: " + r.config + " on " + r.data + "\n\n";
    s += "Command: `" + r.command + "`\n\n";
    if (!r.commit.empty()) s += "Commit: `" + r.commit + "`\n\n";
    if (r.planned_folds > r.folds.size())
        s += "**Partial report: " + std::to_string(r.folds.size()) + " of " + std::to_string(r.planned_folds) +
             " folds done.**\n\n";
    s += "Leave-one-content-out: " + std::to_string(r.folds.size()) +
         " fold(s); in each, StarGAN is trained on every other content (motion type), then every held-out `" + r.neutral +
         "` take is transferred to each other emotion and compared with the held-out take of that emotion (same take "
         "index). Total time " + detail::fmt(r.seconds / 60.0, 1) + " min.\n\n";
    s += "Methods: **stargan** (the trained G, tempo from the training set's duration ratios); ";
    if (has_method(r, "stargan+detail"))
        s += "**stargan+detail** (stargan's output with the detail layer: the input's own full-rate detail about its keyframe "
             "spline, played back and scaled by the per-emotion statistics of the fold's training clips, zero at the "
             "output's keyframes, so only the full-rate columns can differ from stargan's; motion/detail_layer.hpp); ";
    s += "**identity** (output = input); "
         "**mean-offset** (input keyframes + the training-set mean keyframe difference emotion - neutral over same content "
         "and take pairs, same tempo as stargan); **nearest-neighbour** (the training clip of the target emotion with the "
         "closest keyframes); **real** (the captured target clip itself: the reference)";
    if (has_method(r, "stargan-g"))
        s += "; **stargan-g** (the same trained G and gate without the learned amplitude stage and joint lag: what G alone does); "
             "**amplitude-only** (the input with the learned amplitude and tempo, no G: what the amplitude stage alone does)";
    if (has_method(r, "statistics"))
        s += "; **statistics** (every learned part of the model but G, at its learned setting: the amplitude stage, the joint "
             "lag (when the model has one), the tempo and the posture prior at full weight, no G and no detail layer; emotion_model::statistics(): what a user gets "
             "without a network, so StarGAN's margin over it is what G is worth)";
    if (has_method(r, "stargan-ungated"))
        s += "; **stargan-ungated** (the same model with G's whole change, without the change gate chosen on held-out "
             "training contents: what the gate buys)";
    if (has_method(r, "rcm"))
        s += "; **rcm** (the circumplex synthesis of Aristidou et al. 2017, no neural network: a circumplex model fitted on the "
             "fold's training clips only, and the input moved to the target label's (valence, arousal) by its rules and IK, "
             "`handemo rcm stylise`; see the circumplex section below)";
    if (has_method(r, "oracle"))
        s += "; **oracle** (synthetic set only: the neutral input's take synthesised again with the target emotion's "
             "style parameters and the input take's own per-take variation, synthesize_as(); its distance to the real "
             "take is the floor that per-take variation leaves)";
    s += ".\n\n";
    s += "Metrics: RMSE over the 9 uniform keyframes (differences wrapped to (-180, 180]); emotion recognised: a "
         "nearest-centroid classifier (shrunk pooled within-class covariance) on keyframe features, trained only on the "
         "real training clips of the fold, never on the discriminator; recognised, full-rate judge: a second, independent "
         "classifier (metrics::full_rate_judge: the change of full-rate features (per joint range, speed and tremor, "
         "the posture pooled over the joints or also per joint, with or without the clip's own features, duration, acceleration, tremor frequency, joint lags) "
         "against the neutral input, an L2 logistic regression whose weight and input set are chosen by leave-one-content-out "
         "cross-validation inside the fold's real training clips); content kept: the nearest `" + r.neutral +
         "` clip (keyframe RMSE, over every content, held-out included) is of the input's content; ROM and speed ratios: "
         "output / input measured on 9-keyframe reconstructions; ratio errors: the absolute log of (output ratio / real ratio); "
         "duration ratio error: |log(duration out / duration real)| (identity keeps the input's duration); "
         "full-rate ratio errors: the same on the clips as they are (a capture's tremor and noise, and the detail layer's, "
         "included; a keyframe-spline output has none, identity keeps the input's). "
         "Caveat: nearest-neighbour outputs are clips the emotion classifier was trained on, so its emotion score is "
         "in-sample (an upper bound), and it keeps no content by construction.";
    if (std::any_of(ms.begin(), ms.end(), [](const metric_def& m) { return m.key == "circumplex_quadrant"; }))
        s += " Circumplex quadrant reached: the fold's circumplex model (fitted on its training clips only, the one the rcm "
             "row uses) analyses the output (`handemo rcm analyse`) into the quadrant of the target label's (valence, "
             "arousal); the real row is how often the analysis places real held-out clips of the target emotion there.";
    s += "\n\n";
    s += "Options:\n\n```\n" + r.options_text + "```\n\n";

    return s;
}

/// @brief The summary table (mean +- std over folds) of every target ("all" first) and method, and its plots.
inline std::string report_summary(const eval_result& r, const std::vector<metric_def>& ms, const std::vector<std::string>& targets)
{
    std::string s;
    s += "## Summary (mean +- std over folds)\n\n| target | method |";
    for (const auto& m : ms) s += " " + m.title + " |";
    s += "\n|---|---|";
    for (std::size_t i = 0; i < ms.size(); ++i) s += "---|";
    s += "\n";
    auto all_targets = targets;
    all_targets.insert(all_targets.begin(), "all");
    for (const auto& t : all_targets)
        for (const auto& me : method_names()) {
            if (!has_method(r, me)) continue;
            s += "| " + t + " | " + me + " |";
            for (const auto& m : ms) {
                const auto v = over_folds(r, m, t, me);
                s += " " + (v.n ? detail::fmt(v.mean) + " +- " + detail::fmt(v.std) : std::string("n/a")) + " |";
            }
            s += "\n";
        }
    s += "\n![summary](summary.svg)\n\n";
    if (!r.samples.empty()) s += "![per fold](folds.svg)\n\n";

    return s;
}

/// @brief Plain statements of where StarGAN beats each baseline and where it does not; `losses` receives the
/// pooled (baseline, metric) pairs it does not beat.
inline std::string report_versus_baselines(const eval_result& r, const std::vector<metric_def>& ms, std::vector<std::string>& losses)
{
    std::string s;
    s += "## Where StarGAN beats each baseline and where it does not\n\n";
    const auto cmp = compare_with_baselines(r);
    for (const std::string& b : baseline_names()) {
        if (!has_method(r, b)) continue;
        s += "**vs " + b + "**\n\n";
        {  // keyframe RMSE pair by pair: (fold, target emotion) pairs where StarGAN's mean is lower
            int better = 0, n = 0;
            for (const auto& c : cmp)
                if (c.baseline == b && c.metric == "rmse_real" && c.target != "all") better += c.folds_better, n += c.folds;
            if (n) s += "- RMSE to real, (fold, target emotion) pairs: StarGAN lower in " + std::to_string(better) + " of " + std::to_string(n) +
                        " (" + detail::fmt(100.0 * better / n, 0) + "%).\n";
        }
        if (b == "statistics")
            if (const auto bar = network_bar_of(r); bar.present) {
                const auto yes = [](bool v) { return std::string(v ? "yes" : "no"); };
                s += "- The bar that says the network is worth having (StarGAN against every learned part but G): mean RMSE lower (" +
                     detail::fmt(bar.rmse_stargan) + " vs " + detail::fmt(bar.rmse_statistics) + "): " + yes(bar.rmse_lower()) +
                     "; lower in at least " + detail::fmt(100 * bar.min_share, 0) + "% of the (fold, target emotion) pairs (" +
                     std::to_string(bar.pairs_lower) + " of " + std::to_string(bar.pairs) + "): " + yes(bar.pairs_enough()) +
                     "; recognised at least as often (" + detail::fmt(bar.emotion_stargan, 1) + "% vs " +
                     detail::fmt(bar.emotion_statistics, 1) + "%): " + yes(bar.emotion_kept()) + ". **Cleared: " + yes(bar.cleared()) +
                     ".**\n";
            }
        for (const auto& m : ms) {
            if (m.better == 0) continue;
            std::string win, lose;
            for (const auto& c : cmp) {
                if (c.baseline != b || c.metric != m.key) continue;
                const std::string item = (c.target == "all" ? std::string("pooled") : c.target) + " (" + detail::fmt(c.stargan) + " vs " + detail::fmt(c.other) + ", " +
                                         std::to_string(c.folds_better) + "/" + std::to_string(c.folds) + " folds)";
                (c.better ? win : lose) += (c.better ? (win.empty() ? "" : ", ") : (lose.empty() ? "" : ", ")) + item;
                if (!c.better && c.target == "all") losses.push_back(b + " on " + m.title);
            }
            s += "- " + m.title + (m.better < 0 ? " (lower is better)" : " (higher is better)") + ": StarGAN better for " +
                 (win.empty() ? "none" : win) + "; not better for " + (lose.empty() ? "none" : lose) + ".\n";
        }
        s += "\n";
    }

    return s;
}

namespace detail {
/// The per-fold text of the tempo's basis: nothing for durations chosen by the option (the text of reports before
/// the option existed), else which basis and, when chosen automatically, the disagreement that chose it.
inline std::string tempo_basis_text(const fold_summary& f)
{
    const bool automatic = !std::isnan(f.tempo_basis_disagreement);
    if (f.tempo_basis.empty() || (f.tempo_basis == "duration" && !automatic)) return {};
    return " of the " + f.tempo_basis + "s" +
           (automatic ? " (--tempo-basis auto: the training pairs' duration and cadence ratios differ by a factor " +
                            fmt(std::exp(f.tempo_basis_disagreement), 2) + " in the median pair)"
                      : std::string());
}
}  // namespace detail

/// @brief One table per fold, with the fold's training and evaluation facts.
inline std::string report_folds(const eval_result& r, const std::vector<metric_def>& ms, const std::vector<std::string>& targets)
{
    std::string s;
    s += "## Per fold\n\n";
    for (const auto& f : r.folds) {
        s += "### held out: " + f.held_out + "\n\n";
        s += std::to_string(f.train_clips) + " training clips, " + std::to_string(f.test_inputs) + " neutral inputs" +
             (f.missing_targets ? ", " + std::to_string(f.missing_targets) + " (input, target) pairs without a real target clip skipped" : "") +
             "; training " + detail::fmt(f.train_seconds / 60.0, 1) + " min, evaluation " + detail::fmt(f.eval_seconds, 1) +
             " s; training-set diagnostics: D/acc " + detail::fmt(100 * f.train_d_acc, 0) + "%, G/cls " + detail::fmt(f.train_g_cls, 3) +
             ", emotion classifier on its training clips " + detail::fmt(100 * f.classifier_train_acc, 0) +
             "%, full-rate judge " + detail::fmt(100 * f.judge_cv_acc, 0) + "% by leave-one-content-out inside them (L2 weight " +
             detail::fmt(f.judge_lambda, 3) +
             (f.judge_inputs.empty() ? std::string() : ", inputs " + f.judge_inputs + " of " + f.judge_candidates) + "); seen-content transfer (training contents' neutral takes to their real targets) RMSE " +
             detail::fmt(f.seen_rmse_stargan) + " deg for StarGAN vs " + detail::fmt(f.seen_rmse_identity) + " for identity" +
             (f.tempo_estimator.empty() ? std::string()
                                        : "; tempo " + f.tempo_estimator + detail::tempo_basis_text(f) + ", shrink weight " + detail::fmt(f.tempo_shrink_weight) +
                                              " by the check on the training contents (" + (f.tempo_basis == "cadence" ? "cadence" : "duration") +
                                              " error " + detail::fmt(f.tempo_shrink_error, 3) +
                                              " against " + detail::fmt(f.tempo_unshrunk_error, 3) + " unshrunk), " +
                                              (f.tempo_shrink_applied ? "applied" : "not applied (--tempo-shrink false)")) +
             (f.lag_check.empty() ? std::string()
                                  : "; joint lag by the check on the training contents (excursion RMSE with / without): " + f.lag_check + ", " +
                                        (f.lag_applied ? "applied" : "not applied (--lag false)")) +
             (f.amplitude_check.empty()
                  ? std::string()
                  : "; amplitude stage by the check on the training contents (statistics RMSE scaling about the mean / the ends): " +
                        f.amplitude_check + " deg, the model scales about the " + f.amplitude_anchor) +
             (f.tempo_neighbours_check.empty()
                  ? std::string()
                  : "; tempo neighbours by the check on the training contents (left-out error " + f.tempo_neighbours_check + "): " +
                        (f.tempo_neighbours_k ? std::to_string(f.tempo_neighbours_k) + " nearest contents" : std::string("the learned factors")) + ", " +
                        (f.tempo_neighbours_applied ? "applied" : "not applied (--tempo-neighbours false)")) +
             (f.reused_model ? "; model reused from an earlier run" : "") + ". Loss curves: `folds/" +
             f.held_out + "/losses.svg`.\n\n| target | method |";
        for (const auto& m : ms) s += " " + m.title + " |";
        s += "\n|---|---|";
        for (std::size_t i = 0; i < ms.size(); ++i) s += "---|";
        s += "\n";
        for (const auto& t : targets)
            for (const auto& me : method_names()) {
                if (!std::isfinite(fold_mean(r, ms.front(), f.held_out, t, me))) continue;
                s += "| " + t + " | " + me + " |";
                for (const auto& m : ms) s += " " + detail::fmt(fold_mean(r, m, f.held_out, t, me)) + " |";
                s += "\n";
            }
        s += "\n";
    }

    return s;
}

/// @brief The closing note: what StarGAN does not beat (report_versus_baselines()'s losses) and why it may be.
inline std::string report_closing_note(const eval_result& r, const std::vector<std::string>& losses)
{
    std::string s;
    s += "## Closing note\n\n";
    if (losses.empty()) {
        s += "Pooled over targets, StarGAN is better than every baseline on every metric with a direction.\n";
    } else {
        s += "Pooled over targets, StarGAN is not better than: ";
        for (std::size_t i = 0; i < losses.size(); ++i) s += (i ? "; " : "") + losses[i];
        s += ".\n\n";
        double seen_s = 0, seen_i = 0;
        for (const auto& f : r.folds) seen_s += f.seen_rmse_stargan, seen_i += f.seen_rmse_identity;
        if (!r.folds.empty() && seen_s > seen_i)
            s += "StarGAN does not fit even the contents it was trained on: transferring their neutral takes gives a mean "
                 "keyframe RMSE of " + detail::fmt(seen_s / double(r.folds.size())) + " deg to the real targets, against " +
                 detail::fmt(seen_i / double(r.folds.size())) + " for doing nothing. The failure is one of fitting before "
                 "it is one of generalisation: G cannot yet re-synthesise a motion image to the precision of the emotional "
                 "differences (one Eq. 3 level is (p_max - p_min) / 255 degrees, and G's cycle L1 stays at several levels). "
                 "What would likely fix it: far longer training (StarGAN's reference trains 200k iterations) judged by G/rec "
                 "on the training set, a residual generator (output = input + a learned change, so that identity is free), "
                 "and for bodies an angle range not set by unwrapping outliers.\n\n";
        s += "Further: where identity or mean-offset win on RMSE, G changes the held-out motion "
             "in ways that do not generalise to an unseen motion type (too few contents to learn a content-independent "
             "style: more motion types, or a content-preserving term such as a keyframe-space L1 to the input); where "
             "nearest-neighbour wins on emotion recognition it copies a real emotional clip of another content (see its "
             "content-kept column), which no transfer method can match without giving up content; where the ROM or speed "
             "ratio errors lose, G's amplitude change is too small (raise lambda_cls or train longer, judged on the training "
             "set) and the tempo is the training-set estimate (tempo_fit()), not the take's.\n";
    }
    return s;
}

/// @brief The Markdown report (see write_report()): report_introduction(), report_summary(),
/// report_versus_baselines(), the extensions' sections, report_folds() and report_closing_note().
inline std::string markdown_report(const eval_result& r)
{
    const auto ms = metrics_of(r);
    const auto targets = targets_of(r);
    std::vector<std::string> losses;
    std::string s = report_introduction(r, ms);
    s += report_summary(r, ms, targets);
    s += report_judges(r);
    s += report_versus_baselines(r, ms, losses);
    for (const auto& sec : r.sections) s += "## " + sec.title + "\n\n" + sec.markdown + "\n";
    s += report_folds(r, ms, targets);
    s += report_closing_note(r, losses);
    return s;
}

/// @brief Writes report.md, results.csv (every sample), summary.csv, summary.svg and folds.svg into `dir`
/// (atomically).
/// @throws io_error when a file cannot be written.
inline void write_report(const eval_result& r, const std::filesystem::path& dir)
{
    make_directories(dir);
    write_file_atomic(dir / "results.csv", samples_csv(r));
    write_file_atomic(dir / "summary.csv", summary_csv(r));
    if (!r.samples.empty()) write_file_atomic(dir / "summary.svg", summary_svg(r));
    if (!r.samples.empty()) write_file_atomic(dir / "folds.svg", folds_svg(r));
    for (const auto& sec : r.sections)
        if (!sec.file.empty()) write_file_atomic(dir / sec.file, sec.file_text);
    write_file_atomic(dir / "report.md", markdown_report(r));
}

}  // namespace handemo::eval
