// The continuous control's properties on a fold's held-out motion type (stargan/continuous.hpp,
// docs/continuous.md): at each label's point the output equals the discrete transfer; along straight paths from
// neutral to each label the fold's independent classifier's posterior for that label rises monotonically; the
// keyframes change at most so many degrees per unit of circumplex distance; and the halfway points are
// recognised as the label they lean to or as neutral, not as a third emotion more often than the real clips are;
// and, given an analysis of clips onto the circumplex fitted on the fold's training clips (the circumplex method's,
// eval/rcm.hpp), the Spearman correlation between target and analysed valence and arousal over a grid of targets
// per input, beside the real clips' own.
#pragma once

#include <handemo/eval/report.hpp>
#include <handemo/metrics/classifier.hpp>
#include <handemo/metrics/compare.hpp>
#include <handemo/metrics/correlation.hpp>
#include <handemo/metrics/full_rate_judge.hpp>
#include <handemo/motion/circumplex.hpp>
#include <handemo/motion/keyframes.hpp>
#include <handemo/stargan/continuous.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <string>
#include <utility>
#include <vector>

namespace handemo::eval {

/// @brief The continuous control's numbers on one fold.
struct continuous_fold {
    std::string held_out;
    std::size_t inputs = 0;
    std::size_t label_points = 0, label_equal = 0;  ///< (input, label) pairs, and those equal to the discrete transfer bit for bit
    std::size_t paths = 0, monotone = 0;            ///< paths neutral -> label, and those whose log posterior never falls
    /// the paths that are not monotone because the posterior peaks before the label's point: the label's own output
    /// (the discrete transfer) is recognised less surely than a point on the way (the rest dip and recover)
    std::size_t peak_before_label = 0;
    double lipschitz = 0;                           ///< largest keyframe change (deg, any channel) per unit circumplex distance between path steps
    std::size_t halfway = 0, halfway_third = 0;     ///< halfway points, and those recognised as neither the label nor neutral
    std::size_t real = 0, real_third = 0;           ///< the held-out real emotional clips, and those recognised as a third emotion
    /// Spearman's rho of target against analysed valence and arousal over the grid (mean over the inputs), and of
    /// the real held-out clips' labels' points against their analysis; NaN when no analysis was given
    double spearman_valence = std::nan(""), spearman_arousal = std::nan("");
    double real_spearman_valence = std::nan(""), real_spearman_arousal = std::nan("");
    /// the same path and halfway counts by the full-rate judge (metrics::full_rate_judge, each output read against
    /// its input, each real clip against its take's neutral clip), when one was given (`full_judge`)
    bool full_judge = false;
    std::size_t monotone_full = 0, peak_before_label_full = 0, halfway_third_full = 0, real_full = 0, real_third_full = 0;
};

/// @brief An analysis of a clip onto the circumplex, (valence, arousal); NaN where it cannot say.
using circumplex_analysis = std::function<std::pair<double, double>(const clip&)>;

/// @brief The shape of the label's log posterior along a path from neutral (steps 0..n): monotone when it never
/// falls (a relative tolerance of 1e-9 for rounding), and whether its value at the label's point (the last) is
/// below its maximum on the way (then the path falls toward its end, whatever it did before).
struct path_shape {
    bool monotone = true, peak_before_label = false;
};

/// @brief path_shape of a sequence of log posteriors (an empty or one-element sequence is monotone).
inline path_shape shape_of_path(const std::vector<double>& log_post)
{
    path_shape p;
    double best = -1e300;
    for (std::size_t s = 0; s < log_post.size(); ++s) {
        if (s > 0 && log_post[s] < log_post[s - 1] - 1e-9 * std::abs(log_post[s - 1])) p.monotone = false;
        if (s + 1 < log_post.size()) best = std::max(best, log_post[s]);
    }
    if (log_post.size() > 1) p.peak_before_label = log_post.back() < best - 1e-9 * std::abs(best);
    return p;
}

/// @brief The grid of targets the Spearman correlations are taken over: valence and arousal in -0.8, -0.4, 0, 0.4,
/// 0.8, the 21 points inside the unit circle.
inline std::vector<std::pair<double, double>> continuous_grid()
{
    std::vector<std::pair<double, double>> g;
    for (int i = -2; i <= 2; ++i)
        for (int j = -2; j <= 2; ++j) {
            const double v = 0.4 * i, a = 0.4 * j;
            if (v * v + a * a <= 1.0) g.emplace_back(v, a);
        }
    return g;
}

/// @brief The log of probability `i` of `p` (-1e300 for an index out of range or a zero probability).
inline double log_probability(const std::vector<double>& p, std::size_t i)
{
    return i < p.size() && p[i] > 0 ? std::log(p[i]) : -1e300;
}

/// @brief Measures the properties on a fold: `inputs` the held-out neutral takes, `reals` the held-out real clips
/// with their emotion, `steps` the path's steps from neutral to a label (its halfway point is step steps / 2).
/// With `full_judge` the paths and halfway points are also read by the full-rate judge, each output against its
/// input and each real clip against `real_refs` (one neutral clip per entry of `reals`).
/// @throws value_error when `full_judge` is given and `real_refs` does not match `reals`.
template <std::size_t K>
continuous_fold measure_continuous(const stargan::emotion_model& model, const stargan::continuous_control& control,
                                   const metrics::nearest_centroid_classifier& clf, const std::vector<const clip*>& inputs,
                                   const std::vector<std::pair<const clip*, std::string>>& reals, const std::string& held, std::size_t steps = 10,
                                   const circumplex_analysis& analyse = {}, const metrics::full_rate_judge* full_judge = nullptr,
                                   const std::vector<const clip*>& real_refs = {})
{
    if (full_judge && real_refs.size() != reals.size())
        throw value_error("measure_continuous: " + std::to_string(real_refs.size()) + " neutral references for " + std::to_string(reals.size()) +
                          " real clips");
    const auto& info = model.info();
    const auto& labels = control.interpolation().labels();
    const auto& neutral = labels[control.interpolation().neutral()];
    continuous_fold f;
    f.held_out = held;
    const auto features = [](const clip& c) { return metrics::motion_features(extract_keyframes<K>(c), metrics::measure<K>(c).duration); };
    const auto third = [&](const std::string& predicted, const std::string& label) { return predicted != label && predicted != info.neutral; };
    f.full_judge = full_judge != nullptr;
    for (std::size_t i = 0; i < reals.size(); ++i) {
        const auto& [c, emotion] = reals[i];
        if (emotion == info.neutral) continue;
        ++f.real;
        f.real_third += third(clf.predict(features(*c)), emotion);
        if (full_judge) {
            ++f.real_full;
            f.real_third_full += third(full_judge->predict(metrics::full_rate_features(*c), metrics::full_rate_features(*real_refs[i])), emotion);
        }
    }
    auto ws = model.make_workspace();
    std::vector<double> grid_v, grid_a;  // per input
    for (const clip* in : inputs) {
        ++f.inputs;
        const auto lk = control.prepare(*in);
        const std::vector<double> in_full = full_judge ? metrics::full_rate_features(*in) : std::vector<double>{};
        for (std::size_t d = 0; d < info.domains.size(); ++d) {
            const auto& label = labels[d];
            ++f.label_points;
            f.label_equal += control.transfer(*in, lk, label.valence, label.arousal).motion.angles == model.transfer(*in, info.domains[d], {}, ws).motion.angles;
            if (info.domains[d] == info.neutral) continue;
            ++f.paths;
            const std::size_t ci = clf.index_of(info.domains[d]);
            // (a label the judge never saw: past its classes, a path of -1e300)
            const std::size_t fi = full_judge ? full_judge->classifier().index_of(info.domains[d]) : 0;
            std::vector<double> log_posts, log_posts_full;
            std::vector<double> prev_keys;
            const double step_dist = std::hypot(label.valence - neutral.valence, label.arousal - neutral.arousal) / static_cast<double>(steps);
            for (std::size_t s = 0; s <= steps; ++s) {
                const double t = static_cast<double>(s) / static_cast<double>(steps);
                const auto r = control.transfer(*in, lk, neutral.valence + t * (label.valence - neutral.valence),
                                                neutral.arousal + t * (label.arousal - neutral.arousal));
                const auto x = features(r.motion);
                // the log posterior (it rises exactly when the posterior does; the posterior underflows far off)
                const auto dist = clf.distances(x);
                const double dmin = *std::min_element(dist.begin(), dist.end());
                double z = 0;
                for (double v : dist) z += std::exp(-0.5 * (v - dmin));
                const double log_post = ci < dist.size() ? -0.5 * (dist[ci] - dmin) - std::log(z) : -1e300;
                log_posts.push_back(log_post);
                std::vector<double> pf;
                if (full_judge) {
                    pf = full_judge->probabilities(metrics::full_rate_features(r.motion), in_full);
                    log_posts_full.push_back(log_probability(pf, fi));
                }
                if (!prev_keys.empty()) {
                    double m = 0;
                    for (std::size_t i = 0; i < prev_keys.size(); ++i) m = std::max(m, std::abs(r.keys.angles[i] - prev_keys[i]));
                    f.lipschitz = std::max(f.lipschitz, m / step_dist);
                }
                prev_keys = r.keys.angles;
                if (2 * s == steps) {
                    ++f.halfway;
                    f.halfway_third += third(clf.predict(x), info.domains[d]);
                    if (full_judge) {
                        const auto& classes = full_judge->classifier().classes();
                        f.halfway_third_full += third(classes[static_cast<std::size_t>(std::max_element(pf.begin(), pf.end()) - pf.begin())],
                                                      info.domains[d]);
                    }
                }
            }
            const path_shape shape = shape_of_path(log_posts);
            f.monotone += shape.monotone;
            f.peak_before_label += !shape.monotone && shape.peak_before_label;
            if (full_judge) {
                const path_shape sf = shape_of_path(log_posts_full);
                f.monotone_full += sf.monotone;
                f.peak_before_label_full += !sf.monotone && sf.peak_before_label;
            }
        }
        if (analyse) {  // the grid of targets against their analysis
            std::vector<double> tv, ta, av, aa;
            for (const auto& [v, a] : continuous_grid()) {
                const auto an = analyse(control.transfer(*in, lk, v, a).motion);
                tv.push_back(v), ta.push_back(a), av.push_back(an.first), aa.push_back(an.second);
            }
            grid_v.push_back(metrics::spearman(tv, av));
            grid_a.push_back(metrics::spearman(ta, aa));
        }
    }
    if (analyse) {
        const auto mean = [](const std::vector<double>& x) {
            double m = 0;
            std::size_t n = 0;
            for (double v : x)
                if (std::isfinite(v)) m += v, ++n;
            return n ? m / static_cast<double>(n) : std::nan("");
        };
        f.spearman_valence = mean(grid_v), f.spearman_arousal = mean(grid_a);
        std::vector<double> tv, ta, av, aa;
        for (const auto& [c, emotion] : reals) {
            const auto it = std::find(info.domains.begin(), info.domains.end(), emotion);
            if (it == info.domains.end()) continue;
            const auto& l = labels[static_cast<std::size_t>(it - info.domains.begin())];
            const auto an = analyse(*c);
            tv.push_back(l.valence), ta.push_back(l.arousal), av.push_back(an.first), aa.push_back(an.second);
        }
        f.real_spearman_valence = metrics::spearman(tv, av);
        f.real_spearman_arousal = metrics::spearman(ta, aa);
    }
    return f;
}

/// @brief The report's section on the continuous control: one row per fold and the total.
/// `rates`: how the control blended the labels' tempo and amplitude factors (named in the text).
inline report_section continuous_section(const std::vector<continuous_fold>& folds, std::size_t steps = 10,
                                         stargan::rate_blend rates = stargan::default_rate_blend)
{
    report_section sec;
    sec.title = "Continuous control (circumplex points through the StarGAN transfer)";
    std::string& m = sec.markdown;
    m += "Each held-out neutral take goes to every label's circumplex point and along the straight path from neutral's point to each "
         "label in " + std::to_string(steps) + " steps (docs/continuous.md), the labels' tempo and amplitude factors blended " +
         (rates == stargan::rate_blend::geometric ? "geometrically (`--rate-blend geometric`)" : "linearly (`--rate-blend linear`)") +
         ". *Equal*: outputs at the labels' points equal to the discrete "
         "transfer bit for bit. *Monotone*: paths along which the fold's classifier's posterior for the label never falls; *peak "
         "first*: of the others, those whose posterior at the label's point is below its maximum on the way (the discrete transfer "
         "is recognised less surely than a blend short of it; the rest dip and recover). *Lipschitz*: "
         "the largest keyframe change (degrees, any channel) per unit of circumplex distance between two steps. *Halfway, third*: halfway "
         "points recognised as neither the label nor neutral, against the held-out real emotional clips recognised as another emotion "
         "than their own and neutral. *Spearman*: with the circumplex method built and on (`--rcm`), its analysis (fitted on the fold's "
         "training clips) of the outputs at 21 grid targets per input against the targets' valence and arousal (mean over the inputs), "
         "and of the held-out real clips against their labels' points; n/a without it.\n\n";
    m += "| fold | inputs | equal at labels | monotone paths | not monotone: peak first | Lipschitz (deg per unit) | halfway: third emotion "
         "| real clips: third emotion | Spearman valence, arousal | real clips: Spearman valence, arousal |\n";
    m += "|---|---|---|---|---|---|---|---|---|---|\n";
    continuous_fold all;
    all.held_out = "all";
    char b[640];
    const auto rho = [](double x) {
        char t[16];
        if (!std::isfinite(x)) return std::string("n/a");
        std::snprintf(t, sizeof t, "%.2f", x);
        return std::string(t);
    };
    const auto pct = [](std::size_t a, std::size_t n) { return n ? 100.0 * static_cast<double>(a) / static_cast<double>(n) : std::nan(""); };
    const auto row = [&](const continuous_fold& f) {
        std::snprintf(b, sizeof b, "| %s | %zu | %zu / %zu | %zu / %zu (%.1f%%) | %zu / %zu | %.2f | %zu / %zu (%.1f%%) | %zu / %zu (%.1f%%) | %s, %s | %s, %s |\n",
                      f.held_out.c_str(), f.inputs, f.label_equal, f.label_points, f.monotone, f.paths, pct(f.monotone, f.paths),
                      f.peak_before_label, f.paths - f.monotone, f.lipschitz,
                      f.halfway_third, f.halfway, pct(f.halfway_third, f.halfway), f.real_third, f.real, pct(f.real_third, f.real),
                      rho(f.spearman_valence).c_str(), rho(f.spearman_arousal).c_str(), rho(f.real_spearman_valence).c_str(),
                      rho(f.real_spearman_arousal).c_str());
        m += b;
    };
    // the total's Spearman columns: the mean over the folds that have one
    double sv = 0, sa = 0, rv = 0, ra = 0;
    std::size_t nsv = 0, nsa = 0, nrv = 0, nra = 0;
    for (const auto& f : folds) {
        row(f);
        if (std::isfinite(f.spearman_valence)) sv += f.spearman_valence, ++nsv;
        if (std::isfinite(f.spearman_arousal)) sa += f.spearman_arousal, ++nsa;
        if (std::isfinite(f.real_spearman_valence)) rv += f.real_spearman_valence, ++nrv;
        if (std::isfinite(f.real_spearman_arousal)) ra += f.real_spearman_arousal, ++nra;
        all.inputs += f.inputs, all.label_points += f.label_points, all.label_equal += f.label_equal, all.paths += f.paths;
        all.monotone += f.monotone, all.peak_before_label += f.peak_before_label, all.halfway += f.halfway, all.halfway_third += f.halfway_third, all.real += f.real;
        all.real_third += f.real_third, all.lipschitz = std::max(all.lipschitz, f.lipschitz);
    }
    const auto avg = [](double s, std::size_t n) { return n ? s / static_cast<double>(n) : std::nan(""); };
    all.spearman_valence = avg(sv, nsv), all.spearman_arousal = avg(sa, nsa);
    all.real_spearman_valence = avg(rv, nrv), all.real_spearman_arousal = avg(ra, nra);
    row(all);
    // the same paths and halfway points read by the full-rate judge (the other judge of the report)
    if (!folds.empty() && std::all_of(folds.begin(), folds.end(), [](const continuous_fold& f) { return f.full_judge; })) {
        m += "\nThe same paths and halfway points read by the full-rate judge (each output against its input, each real clip against "
             "its take's neutral clip; its posterior is a softmax of linear functions of the features, so the argument of "
             "docs/continuous.md on paths that peak first holds for it too):\n\n";
        m += "| fold | monotone paths | not monotone: peak first | halfway: third emotion | real clips: third emotion |\n";
        m += "|---|---|---|---|---|\n";
        continuous_fold tot;
        tot.held_out = "all";
        const auto row_full = [&](const continuous_fold& f) {
            std::snprintf(b, sizeof b, "| %s | %zu / %zu (%.1f%%) | %zu / %zu | %zu / %zu (%.1f%%) | %zu / %zu (%.1f%%) |\n", f.held_out.c_str(),
                          f.monotone_full, f.paths, pct(f.monotone_full, f.paths), f.peak_before_label_full, f.paths - f.monotone_full,
                          f.halfway_third_full, f.halfway, pct(f.halfway_third_full, f.halfway), f.real_third_full, f.real_full,
                          pct(f.real_third_full, f.real_full));
            m += b;
        };
        for (const auto& f : folds) {
            row_full(f);
            tot.paths += f.paths, tot.halfway += f.halfway, tot.monotone_full += f.monotone_full;
            tot.peak_before_label_full += f.peak_before_label_full, tot.halfway_third_full += f.halfway_third_full;
            tot.real_full += f.real_full, tot.real_third_full += f.real_third_full;
        }
        row_full(tot);
    }
    return sec;
}

}  // namespace handemo::eval
