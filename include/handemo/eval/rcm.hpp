// The circumplex method of Aristidou et al. 2017 inside `handemo eval`'s folds and tables, as an
// extension of the leave-one-content-out protocol (eval/extension.hpp): in each fold a circumplex model
// (rcm/model.hpp: LMA features, selection, PCA, the RBF maps of Eq. 1-4) is fitted on the fold's training
// clips only, with an analysis whose input and shrinkage are chosen on those clips (rcm::fit_chosen(), by
// default among every input and weight as `handemo rcm eval` chooses them), and
//  - regression: every held-out clip (every emotion) is analysed, read against its content's neutral clips
//    where the chosen input needs them; the report gets the mean circumplex distance between the predicted
//    and the label's (valence, arousal) and the share in the label's quadrant, next to a constant predictor
//    (the training clips' mean label point), per fold and pooled: the same numbers as `handemo rcm eval`
//    with the same --input and --shrink for the same folds (--input paper --shrink none: the paper's analysis);
//  - synthesis: each held-out neutral clip is moved to each target label's circumplex point
//    (rcm::stylise_to_point(), Section 4: rules, IK, spline), the method "rcm", scored with the metrics of
//    every other method (RMSE to the real clip, independent classifier, content kept, ROM and speed errors);
//  - every method's output (StarGAN, the baselines, rcm, the real clip) is analysed by the fold's analysis:
//    the metric "circumplex quadrant reached", and the continuous control's Spearman correlations
//    (circumplex_rank_point(): the chosen input's point before the pull toward the constant, whose ranks
//    are the analysis's whenever the weight is above 0).
// Needs the target handemo::rcm (xtensor-blas, LAPACK); the core evaluation does not include this file.
#pragma once

#include <handemo/eval/extension.hpp>
#include <handemo/eval/report.hpp>
#include <handemo/rcm.hpp>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace handemo::eval {

/// @brief Options of the circumplex rows.
struct rcm_eval_options {
    rcm::circumplex_table table;  ///< label coordinates (rcm::load_circumplex())
    std::string table_name = "circumplex table";  ///< for messages and the report
    rcm::fit_options fit;         ///< the per-fold fit (pose clusters are never fitted: neither side uses them here)
    rcm::point_options stylise;   ///< the synthesis of the "rcm" rows
    bool synthesis = true;        ///< add the "rcm" method rows (false: regression and quadrant scores only)
    /// the analysis's candidate inputs and shrinkage weights, chosen per fold on its training clips (rcm eval's
    /// --input and --shrink; the neutral label comes from the fold); {paper} and {1} are the paper's analysis
    std::vector<rcm::analysis_input> inputs = rcm::parse_analysis_inputs("auto");
    std::vector<double> shrink = rcm::shrink_grid();
};

/// @brief The names of candidate inputs as rcm eval's --input spells them: one name, or `auto` for all four.
inline std::string inputs_text(const std::vector<rcm::analysis_input>& v)
{
    if (v == rcm::parse_analysis_inputs("auto")) return "auto";
    std::string s;
    for (auto x : v) s += std::string(s.empty() ? "" : ",") + rcm::to_string(x);
    return s;
}

/// @brief Shrinkage weights as rcm eval's --shrink spells them: `auto`, `none`, or the weight.
inline std::string shrink_text(const std::vector<double>& v)
{
    if (v == rcm::shrink_grid()) return "auto";
    if (v.size() == 1 && v.front() == 1.0) return "none";
    std::string s;
    char b[32];
    for (double x : v) std::snprintf(b, sizeof b, "%s%g", s.empty() ? "" : ",", x), s += b;
    return s;
}

/// @brief One held-out clip analysed by its fold's model (the regression half).
struct rcm_regression_sample {
    std::string fold, name, emotion;
    double valence = 0, arousal = 0;            ///< predicted (clamped to [-1, 1])
    double true_valence = 0, true_arousal = 0;  ///< the label's coordinates
    double distance = 0;                        ///< Euclidean, on the circumplex
    bool quadrant_ok = false;
    double baseline_distance = 0;               ///< of the constant predictor (training clips' mean label point)
    bool baseline_quadrant_ok = false;
};

/// @brief Per-fold facts of the circumplex rows.
struct rcm_fold_info {
    std::string fold, error;  ///< error: why the fold's fit failed (empty when it did not)
    std::size_t selected = 0, pca_dims = 0, stylised = 0, stylise_failed = 0, analyse_failed = 0;
    std::string input = "paper";  ///< the analysis input chosen on the fold's training clips
    double shrink = 1;            ///< and its shrinkage weight
    double fit_seconds = 0, stylise_seconds = 0;
    std::string first_stylise_error, first_analyse_error;  ///< the first of each kind, for the report
};

/// @brief The extension that adds the circumplex method and numbers to handemo eval (see the file comment).
class rcm_extension final : public method_extension {
public:
    explicit rcm_extension(rcm_eval_options o) : opt_(std::move(o))
    {
        opt_.fit.cluster = false;
        opt_.fit.show_progress = false;
    }

    std::string options_text() const override
    {
        char b[256];
        std::snprintf(b, sizeof b, "rcm min_features %zu pca_variance %g window %g stylise_iters %d stylise_bound %g%s\n",
                      opt_.fit.selection.min_features, opt_.fit.pca_keep, static_cast<double>(opt_.fit.lma.window_frames_at_30),
                      opt_.stylise.iterations, opt_.stylise.bound, opt_.synthesis ? "" : " (no rcm rows)");
        return std::string(b) + "rcm labels " + opt_.table_name + "\nrcm analysis input " + inputs_text(opt_.inputs) + " shrink " +
               shrink_text(opt_.shrink) + "\n";
    }

    void begin_fold(const fold_context& f) override
    {
        using clock = std::chrono::steady_clock;
        const auto t0 = clock::now();
        model_.reset();
        analysis_.reset();
        info_.push_back({});
        auto& fi = info_.back();
        fi.fold = f.held_out;
        std::vector<rcm::training_clip> tc;
        for (const auto& c : *f.train) tc.push_back({&c.motion, c.emotion, c.content, c.path.filename().string()});
        std::vector<const clip*> neutrals;
        for (const auto* c : f.test)
            if (c->emotion == f.neutral) neutrals.push_back(&c->motion);
        try {
            const rcm::loo_options lo{rcm::relative_features::off, f.neutral, opt_.inputs, opt_.shrink};
            if (opt_.synthesis) {  // the synthesis's model (the paper's) and the analysis, on the same features
                auto both = rcm::fit_model_and_chosen(tc, opt_.table, opt_.table_name, opt_.fit, lo);
                model_ = std::move(both.model);
                analysis_ = std::move(both.analysis);
            } else {
                analysis_ = rcm::fit_chosen(tc, opt_.table, opt_.table_name, opt_.fit, lo);
            }
            reference_ = analysis_->reference(neutrals, f.held_out);
        } catch (const error& e) {
            model_.reset();
            analysis_.reset();
            fi.error = e.what();
            if (f.progress_out) std::fprintf(f.progress_out, "eval: rcm: fold '%s': fit failed: %s\n", f.held_out.c_str(), e.what());
            return;
        }
        fi.selected = analysis_->model().selected.size();
        fi.pca_dims = analysis_->model().pca.dims();
        fi.input = rcm::to_string(analysis_->input());
        fi.shrink = analysis_->shrink();
        const double bv = analysis_->constant().valence, ba = analysis_->constant().arousal;
        for (const auto* c : f.test) {
            rcm::analysis a;
            rcm::label_point l;
            try {  // a held-out clip the model cannot analyse is counted and named, not the end of the evaluation
                a = analysis_->analyse(c->motion, reference_, c->path.filename().string());
                l = opt_.table.at(c->emotion, opt_.table_name);
            } catch (const error& e) {
                if (fi.analyse_failed++ == 0) fi.first_analyse_error = c->path.filename().string() + ": " + e.what();
                continue;
            }
            rcm_regression_sample s;
            s.fold = f.held_out, s.name = c->path.filename().string(), s.emotion = c->emotion;
            s.valence = a.valence, s.arousal = a.arousal, s.true_valence = l.valence, s.true_arousal = l.arousal;
            s.distance = std::hypot(a.valence - l.valence, a.arousal - l.arousal);
            s.quadrant_ok = a.quadrant == rcm::quadrant(l.valence, l.arousal);
            s.baseline_distance = std::hypot(bv - l.valence, ba - l.arousal);
            s.baseline_quadrant_ok = rcm::quadrant(bv, ba) == rcm::quadrant(l.valence, l.arousal);
            regression_.push_back(s);
        }
        fi.fit_seconds = std::chrono::duration<double>(clock::now() - t0).count();
    }

    std::vector<std::pair<std::string, clip>> transfer(const labelled_clip& input, const std::string& target) override
    {
        if (!model_) return {};  // fitted only with the synthesis on
        const auto t0 = std::chrono::steady_clock::now();
        auto& fi = info_.back();
        std::vector<std::pair<std::string, clip>> out;
        try {
            const auto& l = opt_.table.at(target, opt_.table_name);
            out.emplace_back("rcm", rcm::stylise_to_point(*model_, input.motion, l.valence, l.arousal, opt_.stylise).synth.motion);
            ++fi.stylised;
        } catch (const error& e) {
            // one clip the synthesis cannot move must not end a long evaluation: counted and named in the report
            if (fi.stylise_failed++ == 0) fi.first_stylise_error = input.path.filename().string() + " to " + target + ": " + e.what();
        }
        fi.stylise_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        return out;
    }

    void score(sample_record& s, const clip& out) override
    {
        if (!analysis_) return;
        try {
            const auto& l = opt_.table.at(s.target, opt_.table_name);
            const rcm::analysis a = analysis_->analyse(out, reference_);
            s.circumplex_valence = a.valence, s.circumplex_arousal = a.arousal;
            s.circumplex_quadrant_ok = a.quadrant == rcm::quadrant(l.valence, l.arousal) ? 1.0 : 0.0;
        } catch (const error&) {
            // an output the features cannot be computed on (or a target without coordinates) stays "not measured"
        }
    }

    std::pair<double, double> circumplex_rank_point(const clip& out) override
    {
        if (!analysis_) return {std::nan(""), std::nan("")};
        try {
            const rcm::analysis a = analysis_->analyse_unshrunk(out, reference_);
            return {a.valence, a.arousal};
        } catch (const error&) {
            return {std::nan(""), std::nan("")};  // not measured, as in score()
        }
    }

    void end_fold(eval_result& r) override
    {
        report_section sec{"Circumplex (Aristidou et al. 2017)", markdown(), "rcm_regression.csv", regression_csv()};
        for (auto& x : r.sections)
            if (x.title == sec.title) {
                x = std::move(sec);
                return;
            }
        r.sections.push_back(std::move(sec));
    }

    /// @brief Every held-out clip's analysis so far.
    const std::vector<rcm_regression_sample>& regression() const noexcept { return regression_; }
    /// @brief Per-fold facts so far.
    const std::vector<rcm_fold_info>& folds() const noexcept { return info_; }

    /// @brief Regression numbers pooled over the clips of every fold (as `handemo rcm eval` prints them).
    struct pooled {
        std::size_t clips = 0;
        double distance = 0, quadrant = 0, baseline_distance = 0, baseline_quadrant = 0;  ///< quadrant shares in [0, 1]
    };
    static pooled pool(const std::vector<rcm_regression_sample>& v)
    {
        pooled p;
        p.clips = v.size();
        const double n = static_cast<double>(v.size());
        for (const auto& s : v) {
            p.distance += s.distance / n;
            p.quadrant += (s.quadrant_ok ? 1.0 : 0.0) / n;
            p.baseline_distance += s.baseline_distance / n;
            p.baseline_quadrant += (s.baseline_quadrant_ok ? 1.0 : 0.0) / n;
        }
        return p;
    }

private:
    std::string regression_csv() const
    {
        std::string t = "fold,clip,emotion,valence,arousal,true_valence,true_arousal,distance,quadrant_ok,constant_distance,constant_quadrant_ok\n";
        char b[512];
        for (const auto& s : regression_) {
            std::snprintf(b, sizeof b, "%s,%s,%s,%.6g,%.6g,%.6g,%.6g,%.6g,%d,%.6g,%d\n", s.fold.c_str(), s.name.c_str(), s.emotion.c_str(),
                          s.valence, s.arousal, s.true_valence, s.true_arousal, s.distance, s.quadrant_ok ? 1 : 0, s.baseline_distance,
                          s.baseline_quadrant_ok ? 1 : 0);
            t += b;
        }
        return t;
    }

    std::string markdown() const
    {
        using detail::fmt;
        std::string s =
            "A circumplex model (LMA features, effective/consistent selection with contents as performers, PCA, Gaussian RBF "
            "features -> (valence, arousal), Eq. 1-2) is fitted in each fold on the fold's training clips only (" +
            opt_.table_name + "), with the analysis input (`paper`: the clip's Table 1 features; `relative`: the same against "
            "its content's neutral clips; `clusters`: the per-pose-cluster maps; `judge`: the full-rate judge's features) and the "
            "pull toward the constant predictor chosen on those clips by an inner leave-one-content-out (candidates: input " +
            inputs_text(opt_.inputs) + ", shrink " + shrink_text(opt_.shrink) + "; as `handemo rcm eval`). **Regression**: every "
            "held-out clip is analysed; distance is the Euclidean distance on the circumplex between the predicted point and its "
            "label's coordinates, right quadrant counts predictions in the label's quadrant; the constant predictor answers the "
            "training clips' mean label point. Per clip: `rcm_regression.csv`.\n\n";
        s += "| held out | clips | mean distance | right quadrant (%) | constant: distance | constant: quadrant (%) | input, shrink | features kept | PCA dims |";
        if (opt_.synthesis) s += " rcm outputs | failed |";
        s += "\n|---|---|---|---|---|---|---|---|---|";
        if (opt_.synthesis) s += "---|---|";
        s += "\n";
        std::vector<double> fd, fq;
        for (const auto& fi : info_) {
            std::vector<rcm_regression_sample> v;
            for (const auto& x : regression_)
                if (x.fold == fi.fold) v.push_back(x);
            if (!fi.error.empty()) {
                s += "| " + fi.fold + " | fit failed: " + fi.error + " |\n";
                continue;
            }
            const pooled p = pool(v);
            fd.push_back(p.distance), fq.push_back(100 * p.quadrant);
            s += "| " + fi.fold + " | " + std::to_string(p.clips) + " | " + fmt(p.distance, 3) + " | " + fmt(100 * p.quadrant, 1) + " | " +
                 fmt(p.baseline_distance, 3) + " | " + fmt(100 * p.baseline_quadrant, 1) + " | " + fi.input + ", " + fmt(fi.shrink, 1) + " | " +
                 std::to_string(fi.selected) + " | " +
                 std::to_string(fi.pca_dims) + " |";
            if (opt_.synthesis) s += " " + std::to_string(fi.stylised) + " | " + std::to_string(fi.stylise_failed) + " |";
            s += "\n";
        }
        const pooled all = pool(regression_);
        const mean_std d = mean_and_std(fd), q = mean_and_std(fq);
        s += "\nPooled over the " + std::to_string(all.clips) + " held-out clips: mean distance **" + fmt(all.distance, 3) +
             "**, right quadrant **" + fmt(100 * all.quadrant, 1) + "%** (constant predictor " + fmt(all.baseline_distance, 3) + ", " +
             fmt(100 * all.baseline_quadrant, 1) + "%); over folds: distance " + fmt(d.mean, 3) + " +- " + fmt(d.std, 3) +
             ", right quadrant " + fmt(q.mean, 1) + " +- " + fmt(q.std, 1) + "%.\n\n";
        std::map<std::string, std::pair<double, double>> per;
        std::map<std::string, int> cnt;
        for (const auto& x : regression_) per[x.emotion].first += x.distance, per[x.emotion].second += x.quadrant_ok, ++cnt[x.emotion];
        if (!per.empty()) {
            s += "Per label (distance, right quadrant):";
            bool first = true;
            for (const auto& [e, v] : per) {
                s += std::string(first ? " " : "; ") + e + " " + fmt(v.first / cnt[e], 3) + ", " + fmt(100 * v.second / cnt[e], 0) + "%";
                first = false;
            }
            s += ".\n\n";
        }
        if (opt_.synthesis) {
            s += "**Synthesis**: the **rcm** rows of the tables above are each held-out neutral clip moved to the target label's "
                 "circumplex point by the fold's model (Eq. 3-4 desired features, the rules of Table 2 fitted jointly, IK, "
                 "spline; `handemo rcm stylise` with " + std::to_string(opt_.stylise.iterations) + " iterations, bound " +
                 fmt(opt_.stylise.bound, 2) + "; the paper's model of the fold, Table 1 features). The column *circumplex quadrant "
                 "reached* analyses every method's output with the fold's analysis above, read against the held-out content's "
                 "neutral clips.";
            std::size_t failed = 0;
            for (const auto& fi : info_) failed += fi.stylise_failed;
            if (failed) {
                s += " " + std::to_string(failed) + " (input, target) pair(s) could not be stylised and have no rcm row; the first: ";
                for (const auto& fi : info_)
                    if (!fi.first_stylise_error.empty()) {
                        s += fi.first_stylise_error;
                        break;
                    }
                s += ".";
            }
            s += "\n";
        }
        for (const auto& fi : info_)
            if (fi.analyse_failed)
                s += "\nFold " + fi.fold + ": " + std::to_string(fi.analyse_failed) + " held-out clip(s) could not be analysed; the first: " +
                     fi.first_analyse_error + ".\n";
        return s;
    }

    rcm_eval_options opt_;
    std::optional<rcm::rcm_model> model_;             // the paper's model: the synthesis of the rcm rows
    std::optional<rcm::chosen_analysis> analysis_;    // the analysis: regression, quadrant reached, Spearman
    rcm::neutral_reference reference_;                // the held-out content's neutral clips, for that analysis
    std::vector<rcm_regression_sample> regression_;
    std::vector<rcm_fold_info> info_;
};

}  // namespace handemo::eval
