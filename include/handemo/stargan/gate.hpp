// The change gate (beyond the paper; train_options::gate_folds): how much of a residual G's change to apply
// to a motion of a content it never saw, chosen per target emotion from the training set alone.
//
// G fits the contents it trains on, but on a new motion type part of its change can be content-specific and
// make the motion worse than no change at all. Whether it does is measurable inside the training set:
// fit_change_gate() splits the training contents into gate_folds groups, trains G once per group without that
// group (same options and steps), and transfers the held-out group's neutral takes to every other emotion.
// G's change is split into its mean over the keyframes per channel (the posture: a held wrist, a sunk hand)
// and the rest (the motion), each weighted by 0, 0.25, 0.5, 0.75 or 1. With train_options::gate_prior a third
// part is offered: the posture prior, the training pairs' mean keyframe-mean change of the target emotion per
// channel (mean-offset's difference emotion - neutral averaged over the keyframes; posture_prior()), which
// does not depend on the input's content, also weighted 0 .. 1. Every setting is scored on the held-out pairs
// by keyframe RMSE to the real take of the target emotion (the evaluation's measure) and, with
// train_options::gate_margin >= 0, by how often the independent emotion classifier (nearest centroid, trained
// on the inner training clips, as the evaluation's) recognises the target. Each target emotion gets the
// lowest-RMSE setting whose recognition rate is at most gate_margin below the real held-out clips' rate (when
// none is, the most recognised one); with gate_margin <= -1 simply the lowest-RMSE one (the first gate).
// The rule is also checked inside the training set: for each group, the setting it chooses from the other
// groups' pairs alone, scored on this group's pairs (gate_fit::row::rmse_cross, emotion_cross); choosing on
// 7 pairs and scoring on the same 7 is optimistic (on Bandai, 76% recognised inside against 60% checked).
// With train_options::gate_auto_margin that check chooses the margin too: the least strict of
// gate_margin_candidates() whose checked recognition, pooled over the targets, is at most gate_margin below
// the real clips' (work_dir/gate_margins.csv). train_options::gate_posterior scores recognition by the
// classifier's posterior of the target instead of hits (finer on few pairs; the reported shares stay hits).
// (1, 1, 0) is G's whole change, as StarGAN; (0, 0, 0) leaves the input as it is, with the amplitude stage
// and tempo. The final G is then trained on every training content and the gate (and the prior, from every
// training content) is stored in its checkpoint; transfer applies it (emotion_model::transfer).
// Cost: gate_folds more trainings (each on fewer clips); train_model() runs them first, then the final one.
#pragma once

#include <handemo/core/error.hpp>
#include <handemo/core/io.hpp>
#include <handemo/eval/baselines.hpp>
#include <handemo/eval/classifier.hpp>
#include <handemo/eval/metrics.hpp>
#include <handemo/stargan/dataset.hpp>
#include <handemo/stargan/train.hpp>
#include <handemo/stargan/transfer.hpp>

#include <algorithm>
#include <array>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <utility>
#include <set>
#include <string>
#include <vector>

namespace handemo::stargan {

/// @brief The outcome of fit_change_gate().
struct gate_fit {
    std::vector<double> posture, motion;  ///< [C] the chosen weights of G's change per target domain (1 for neutral)
    std::vector<double> prior;            ///< [C] the chosen weight of the posture prior (0 for neutral or without gate_prior)
    /// One row per target domain that had validation pairs.
    struct row {
        std::string target;
        double posture = 1, motion = 1, prior = 0;
        double rmse_gated = 0, rmse_full = 0, rmse_none = 0;  ///< mean keyframe RMSE (deg): chosen, (1, 1, 0), (0, 0, 0)
        /// share of held-out outputs the inner classifier recognises as the target: chosen, (1, 1, 0), and the
        /// real held-out clips' share (NaN when gate_margin < 0: no classifier)
        double emotion_gated = std::nan(""), emotion_full = std::nan(""), emotion_real = std::nan("");
        std::size_t pairs = 0;  ///< (held-out neutral take, real target take) pairs
        /// The rule checked inside the training set: for each inner group, the setting the same rule chooses
        /// from the other groups' pairs alone, scored on this group's pairs (pooled over the groups). Unlike
        /// rmse_gated and emotion_gated, which score the setting on the pairs that chose it and so are
        /// optimistic, these estimate what the rule gives on contents it did not choose on (with fewer pairs
        /// to choose from than the final gate has, so if anything pessimistic). NaN without a second group.
        double rmse_cross = std::nan(""), emotion_cross = std::nan("");
    };
    std::vector<row> rows;
    double margin = std::nan("");   ///< the recognition margin used (train_options::gate_margin, or the one gate_auto_margin chose)
    std::size_t folds = 0;          ///< inner trainings run or reused
    std::size_t reused_folds = 0;   ///< inner models reused (fit_change_gate(..., reuse = true))

    /// @brief The rows as CSV (target,posture,motion,prior,rmse_gated,rmse_full,rmse_none,emotion_gated,emotion_full,emotion_real,pairs,
    /// rmse_cross,emotion_cross).
    std::string csv() const
    {
        std::string s =
            "target,posture,motion,prior,rmse_gated,rmse_full,rmse_none,emotion_gated,emotion_full,emotion_real,pairs,rmse_cross,emotion_cross\n";
        char b[400];
        for (const auto& r : rows) {
            std::snprintf(b, sizeof b, "%s,%.2f,%.2f,%.2f,%.6f,%.6f,%.6f,%.4f,%.4f,%.4f,%zu,%.6f,%.4f\n", r.target.c_str(), r.posture, r.motion,
                          r.prior, r.rmse_gated, r.rmse_full, r.rmse_none, r.emotion_gated, r.emotion_full, r.emotion_real, r.pairs, r.rmse_cross,
                          r.emotion_cross);
            s += b;
        }
        return s;
    }
};

/// @brief The margins train_options::gate_auto_margin chooses from, least strict first: `margin`, then 0.1,
/// 0.2 and 0.3 stricter (a negative margin asks for more than the real clips' rate), then -0.99 (in effect: the
/// most recognised setting, then the lowest RMSE).
inline std::vector<double> gate_margin_candidates(double margin)
{
    std::vector<double> m;
    for (int i = 0; i < 4; ++i)
        if (margin - 0.1 * i > -0.99) m.push_back(margin - 0.1 * i);
    m.push_back(-0.99);
    return m;
}

/// The weights fit_change_gate() chooses from, for the posture and for the motion part of G's change (and the prior).
inline constexpr std::array<double, 5> gate_grid{1.0, 0.75, 0.5, 0.25, 0.0};

/// @brief The posture prior of train_options::gate_prior: for every domain, the mean over the training pairs
/// (an emotional take and the neutral take of the same content and take) of their keyframe difference, averaged
/// over the keyframes per channel, in degrees: [C][J*3]; zeros for the neutral domain and for a domain without pairs.
/// It is the keyframe mean of mean-offset's difference, so it does not depend on the amplitude stage (which
/// scales excursions about that mean).
/// @throws value_error when no clip is neutral; shape_error for clips of different skeletons.
template <std::size_t K>
std::vector<std::vector<double>> posture_prior(const std::vector<labelled_clip>& clips, const config_info& info)
{
    if (clips.empty()) throw value_error("posture_prior: no clips");
    const std::size_t J = clips.front().motion.skel.size(), C = J * 3;
    for (const auto& c : clips)
        if (c.motion.skel.size() != J)
            throw shape_error("posture_prior: " + c.path.string() + " has " + std::to_string(c.motion.skel.size()) + " joints, " +
                              clips.front().path.string() + " has " + std::to_string(J));
    const auto b = eval::mean_offset_baseline<K>::fit(clips, info.neutral);
    std::vector<std::vector<double>> prior(info.domains, std::vector<double>(C, 0.0));
    for (std::size_t d = 0; d < info.domains; ++d) {
        const std::string& e = info.domain_names[d];
        if (e == info.neutral || !b.has(e)) continue;
        const auto delta = b.delta(e, J);
        for (std::size_t k = 0; k < delta.count(); ++k)
            for (std::size_t ch = 0; ch < C; ++ch) prior[d][ch] += delta.angles[k * C + ch] / static_cast<double>(delta.count());
    }
    return prior;
}

namespace detail {

/// The training options without the gate's own (gate_folds, gate_prior, gate_margin): two checkpoints whose
/// options agree on these trained the same G, whatever gate was fitted around it.
inline nlohmann::json options_without_gate(nlohmann::json o)
{
    if (o.is_object())
        for (const char* k : {"gate_folds", "gate_prior", "gate_margin", "gate_posterior", "gate_auto_margin"}) o.erase(k);
    return o;
}

/// Whether a checkpoint holds the G that `opt` trains: the same options (the gate's aside) and opt.iters steps.
inline bool trained_same_g(const checkpoint_info& ck, const train_options& opt)
{
    return ck.step == opt.iters && options_without_gate(ck.options) == options_without_gate(opt.to_json());
}

}  // namespace detail

/// @brief Chooses the change gate of a residual G by leave-content-group-out inside `clips` (see the header
/// comment). Inner models are written to work_dir/inner<i>/ and the table to work_dir/gate.csv.
/// @param opt the options the final G is trained with (gate_folds inner trainings of them, each with its own seed)
/// @param reuse keep an inner model already in work_dir/inner<i>/ when it was trained with the same options
///        (the gate's own aside) and steps, instead of training it again (`handemo eval --reuse-models`)
/// @return all-1 weights (and no rows) when the clips have fewer contents than opt.gate_folds or no neutral take
///         with a real target in a held-out group.
/// @throws value_error when opt is not residual; the errors of training and transfer otherwise.
template <stargan_config Config>
gate_fit fit_change_gate(const std::vector<labelled_clip>& clips, const config_info& info, const train_options& opt,
                         const std::filesystem::path& work_dir, bool reuse = false)
{
    constexpr std::size_t K = Config::keyframes;
    const std::size_t C = info.domains;
    if (!opt.residual) throw value_error("train: the change gate needs a residual G (--residual true)");
    gate_fit g;
    g.posture.assign(C, 1.0);
    g.motion.assign(C, 1.0);
    g.prior.assign(C, 0.0);
    const std::size_t F = static_cast<std::size_t>(std::max(opt.gate_folds, 2));
    std::set<std::string> content_set;
    for (const auto& c : clips) content_set.insert(c.content);
    const std::vector<std::string> contents(content_set.begin(), content_set.end());
    if (contents.size() < F) {
        if (opt.progress_out)
            std::fprintf(opt.progress_out, "gate: %zu contents, fewer than the %zu groups the gate needs: G's whole change is used\n",
                         contents.size(), F);
        return g;
    }
    const auto group_of = [&](const std::string& content) {
        return static_cast<std::size_t>(std::find(contents.begin(), contents.end(), content) - contents.begin()) % F;
    };
    constexpr std::size_t G = gate_grid.size();
    const std::size_t P = opt.gate_prior ? G : 1;  // prior weights tried: the grid, or only 0
    const auto prior_weight = [&](std::size_t c) { return opt.gate_prior ? gate_grid[c] : 0.0; };
    const bool use_emotion = opt.gate_margin > -1;  // margins in (-1, 0) ask for more than the real rate
    if (use_emotion) g.margin = opt.gate_margin;
    const std::size_t S = G * G * P;  // settings, index (a * G + b) * P + c
    // What the held-out pairs of a target gave, per inner group ([F][C]) or pooled over groups (pooled()): per
    // setting the summed RMSE, the recognised outputs and what the rule scores recognition by (hits, or the
    // classifier's posterior with gate_posterior); the pairs and the real clips' hits and score.
    struct tally {
        std::vector<double> rmse, hits, score;  // [S]
        double pairs = 0, real_hits = 0, real_score = 0;
    };
    const tally empty{std::vector<double>(S, 0.0), std::vector<double>(S, 0.0), std::vector<double>(S, 0.0)};
    std::vector<std::vector<tally>> tallies(F, std::vector<tally>(C, empty));
    make_directories(work_dir);
    for (std::size_t f = 0; f < F; ++f) {
        std::vector<labelled_clip> train;
        std::vector<const labelled_clip*> held;
        std::string names;
        for (const auto& c : clips) {
            if (group_of(c.content) == f) {
                held.push_back(&c);
            } else {
                train.push_back(c);
            }
        }
        for (const auto& c : contents)
            if (group_of(c) == f) names += (names.empty() ? "" : ", ") + c;
        auto inner = opt;
        inner.gate_folds = 0;
        inner.seed = opt.seed + 7919 * (f + 1);
        inner.checkpoint_every = inner.iters;
        inner.stop_at = -1;
        const auto dir = work_dir / ("inner" + std::to_string(f + 1));
        const auto ck_path = dir / "checkpoint.safetensors";
        std::optional<std::pair<safetensors_file, checkpoint_info>> ck;
        if (reuse && std::filesystem::exists(ck_path))
            if (auto stored = read_checkpoint(ck_path); detail::trained_same_g(stored.second, inner)) ck = std::move(stored);
        if (ck) {
            if (opt.progress_out)
                std::fprintf(opt.progress_out, "gate %zu/%zu: reusing the G trained without %s (%s)\n", f + 1, F, names.c_str(),
                             ck_path.string().c_str());
            ++g.reused_folds;
        } else {
            if (opt.progress_out)
                std::fprintf(opt.progress_out, "gate %zu/%zu: training G without %s (%zu clips) to choose the change gate\n", f + 1, F,
                             names.c_str(), train.size());
            {
                trainer<Config> tr(info, prepare_data<Config>(train, info, inner), inner);
                tr.run(dir);
            }
            ck = read_checkpoint(ck_path);
        }
        detail::emotion_model_impl<Config> model(ck->first, ck->second);
        if (opt.gate_prior) model.set_prior_posture(posture_prior<K>(train, info));
        auto ws = model.make_workspace();  // the generator's scratch, reused by every transfer below
        // the independent emotion classifier of the evaluation, fitted on this inner training set only
        eval::nearest_centroid_classifier clf;
        // adds to `hits` whether the classifier recognises `target` (class index) from x, and to `score` what
        // the rule counts; the distances are computed once for both
        const auto recognise = [&](const std::vector<double>& x, std::size_t target, double& hits, double& score) {
            const auto d = clf.distances(x);
            const bool hit = static_cast<std::size_t>(std::min_element(d.begin(), d.end()) - d.begin()) == target;
            hits += hit;
            score += opt.gate_posterior ? eval::nearest_centroid_classifier::posterior_of(d, target) : static_cast<double>(hit);
        };
        if (use_emotion) {
            std::vector<std::vector<double>> x;
            std::vector<std::string> y;
            for (const auto& c : train) x.push_back(eval::motion_features(extract_keyframes<K>(c.motion), c.motion.duration())), y.push_back(c.emotion);
            clf.fit(x, y);
        }
        for (const auto* in : held) {
            if (in->emotion != info.neutral) continue;
            for (std::size_t t = 0; t < C; ++t) {
                const std::string& target = info.domain_names[t];
                if (target == info.neutral) continue;
                const labelled_clip* real = nullptr;
                for (const auto* r : held)
                    if (r->content == in->content && r->emotion == target && r->take == in->take) real = r;
                if (!real) continue;
                const auto real_kf = extract_keyframes<K>(real->motion);
                tally& ty = tallies[f][t];
                const std::size_t label = use_emotion ? clf.index_of(target) : 0;
                if (use_emotion) recognise(eval::motion_features(real_kf, real->motion.duration()), label, ty.real_hits, ty.real_score);
                const auto parts = model.parts(in->motion, target, {}, ws);
                for (std::size_t a = 0; a < G; ++a)
                    for (std::size_t b = 0; b < G; ++b)
                        for (std::size_t c = 0; c < P; ++c) {
                            const clip out = model.finish(in->motion, parts, gate_grid[a], gate_grid[b], prior_weight(c));
                            const auto kf = extract_keyframes<K>(out);
                            const std::size_t s = (a * G + b) * P + c;
                            ty.rmse[s] += eval::keyframe_rmse(kf, real_kf);
                            if (use_emotion) recognise(eval::motion_features(kf, out.duration()), label, ty.hits[s], ty.score[s]);
                        }
                ty.pairs += 1;
            }
        }
        ++g.folds;
    }
    // G's whole change (1, 1, prior 0) and no change (0, 0, 0): gate_grid runs from 1 down to 0
    const std::size_t full_s = (0 * G + 0) * P + (P - 1);
    const std::size_t none_s = ((G - 1) * G + (G - 1)) * P + (P - 1);
    // the tallies of target t pooled over the inner groups in `use`
    const auto pooled = [&](std::size_t t, const std::vector<bool>& use) {
        tally p = empty;
        for (std::size_t f = 0; f < F; ++f)
            if (use[f]) {
                const tally& x = tallies[f][t];
                p.pairs += x.pairs, p.real_hits += x.real_hits, p.real_score += x.real_score;
                for (std::size_t s = 0; s < S; ++s) p.rmse[s] += x.rmse[s], p.hits[s] += x.hits[s], p.score[s] += x.score[s];
            }
        return p;
    };
    // the rule on pooled pairs: the chosen setting (S when there are none)
    const auto choose = [&](const tally& p, double margin) {
        const auto& rs = p.rmse;
        const auto& os = p.score;
        const double n = p.pairs;
        std::size_t best = S;
        if (n == 0) return best;
        if (use_emotion) {
            for (std::size_t s = 0; s < S; ++s)
                if (os[s] / n >= p.real_score / n - margin - 1e-12 && (best == S || rs[s] < rs[best])) best = s;
            if (best == S)  // no setting is recognised well enough: the most recognised, then the lowest RMSE
                for (std::size_t s = 0; s < S; ++s)
                    if (best == S || os[s] > os[best] || (os[s] == os[best] && rs[s] < rs[best])) best = s;
        } else {
            best = 0;
            for (std::size_t s = 0; s < S; ++s)
                if (rs[s] < rs[best]) best = s;
        }
        return best;
    };
    // the rule checked inside the training set for target t: chosen without group f, scored on group f, pooled
    // over the groups: {summed RMSE, recognised outputs, recognised real clips, pairs}
    const auto cross_check = [&](std::size_t t, double margin) {
        std::array<double, 4> r{0, 0, 0, 0};
        for (std::size_t f = 0; f < F; ++f) {
            const tally& x = tallies[f][t];
            std::vector<bool> others(F, true);
            others[f] = false;
            const std::size_t s = x.pairs > 0 ? choose(pooled(t, others), margin) : S;
            if (s == S) continue;
            r[0] += x.rmse[s], r[1] += x.hits[s], r[2] += x.real_hits, r[3] += x.pairs;
        }
        return r;
    };
    // train_options::gate_auto_margin: the least strict margin whose cross-checked recognition, pooled over
    // the targets, is at most gate_margin below the real clips'; else the best cross-checked one
    double margin = opt.gate_margin;
    if (use_emotion && opt.gate_auto_margin) {
        std::string table = "margin,rmse_cross,emotion_cross,emotion_real,pairs,chosen\n";
        std::vector<std::array<double, 4>> pooled;
        const auto candidates = gate_margin_candidates(opt.gate_margin);
        std::size_t pick = candidates.size(), top = 0;
        for (std::size_t i = 0; i < candidates.size(); ++i) {
            std::array<double, 4> p{0, 0, 0, 0};
            for (std::size_t t = 0; t < C; ++t) {
                const auto r = cross_check(t, candidates[i]);
                for (std::size_t k = 0; k < 4; ++k) p[k] += r[k];
            }
            pooled.push_back(p);
            if (p[3] > 0 && pick == candidates.size() && p[1] / p[3] >= p[2] / p[3] - opt.gate_margin - 1e-12) pick = i;
            if (p[1] > pooled[top][1]) top = i;
        }
        if (pick == candidates.size()) pick = top;
        margin = candidates[pick];
        g.margin = margin;
        char b[200];
        for (std::size_t i = 0; i < candidates.size(); ++i) {
            const auto& p = pooled[i];
            std::snprintf(b, sizeof b, "%.2f,%.6f,%.4f,%.4f,%.0f,%d\n", candidates[i], p[3] > 0 ? p[0] / p[3] : std::nan(""),
                          p[3] > 0 ? p[1] / p[3] : std::nan(""), p[3] > 0 ? p[2] / p[3] : std::nan(""), p[3], i == pick ? 1 : 0);
            table += b;
        }
        write_file_atomic(work_dir / "gate_margins.csv", table);
        if (opt.progress_out) {
            const auto& p = pooled[pick];
            std::fprintf(opt.progress_out,
                         "gate: margin %.2f chosen inside the training set (its choices, made on one group and scored on the other: "
                         "recognised %.0f%% against the real clips' %.0f%%, %.3f deg; %s)\n",
                         margin, 100 * p[1] / std::max(1.0, p[3]), 100 * p[2] / std::max(1.0, p[3]), p[0] / std::max(1.0, p[3]),
                         (work_dir / "gate_margins.csv").string().c_str());
        }
    }
    for (std::size_t t = 0; t < C; ++t) {
        const tally all = pooled(t, std::vector<bool>(F, true));
        if (all.pairs == 0) continue;
        const double n = all.pairs;
        const auto& rsum = all.rmse;
        const auto& osum = all.hits;
        const double real_rate = all.real_hits / n;
        const std::size_t best = choose(all, margin);
        const auto cross = cross_check(t, margin);
        const double cross_r = cross[0], cross_o = cross[1], cross_n = cross[3];
        const std::size_t a = best / (G * P), b = (best / P) % G, c = best % P;
        g.posture[t] = gate_grid[a];
        g.motion[t] = gate_grid[b];
        g.prior[t] = prior_weight(c);
        gate_fit::row r{info.domain_names[t], g.posture[t], g.motion[t], g.prior[t], rsum[best] / n, rsum[full_s] / n, rsum[none_s] / n};
        if (use_emotion) r.emotion_gated = osum[best] / n, r.emotion_full = osum[full_s] / n, r.emotion_real = real_rate;
        r.pairs = static_cast<std::size_t>(all.pairs);
        if (cross_n > 0) {
            r.rmse_cross = cross_r / cross_n;
            if (use_emotion) r.emotion_cross = cross_o / cross_n;
        }
        g.rows.push_back(r);
        if (opt.progress_out)
            std::fprintf(opt.progress_out,
                         "gate: %-10s posture %.2f motion %.2f prior %.2f (held-out contents: %.3f deg, G's whole change %.3f, no change %.3f; "
                         "recognised %.0f%%, G's whole change %.0f%%, real %.0f%%; %zu pairs)\n",
                         info.domain_names[t].c_str(), r.posture, r.motion, r.prior, r.rmse_gated, r.rmse_full, r.rmse_none,
                         100 * r.emotion_gated, 100 * r.emotion_full, 100 * r.emotion_real, r.pairs);
    }
    write_file_atomic(work_dir / "gate.csv", g.csv());
    return g;
}

/// @brief Fits the change gate again around a model already trained into `out_dir` (its inner models reused
/// when they match, see fit_change_gate()) and rewrites the checkpoint's gate, prior and options in place
/// (atomically, new checksum); G's weights are untouched. `handemo eval --reuse-models` uses it when only
/// the gate options changed since the model was trained.
/// @throws value_error when the checkpoint was trained with other options (the gate's aside) or steps.
template <stargan_config Config>
gate_fit refit_gate(const std::vector<labelled_clip>& clips, const config_info& info, const train_options& opt,
                    const std::filesystem::path& out_dir)
{
    const auto ck_path = out_dir / "checkpoint.safetensors";
    auto [f, stored] = read_checkpoint(ck_path);
    if (!detail::trained_same_g(stored, opt))
        throw value_error("train: " + ck_path.string() + " was not trained with these options (the gate's aside) and " +
                          std::to_string(opt.iters) + " steps: its gate cannot be refitted");
    gate_fit g;
    if (opt.gate_folds > 0) g = fit_change_gate<Config>(clips, info, opt, out_dir / "gate", true);
    auto j = nlohmann::json::parse(f.metadata.at("handemo"));
    const std::size_t C = info.domains;
    j["gate"] = {{"posture", g.posture.empty() ? std::vector<double>(C, 1.0) : g.posture},
                 {"motion", g.motion.empty() ? std::vector<double>(C, 1.0) : g.motion},
                 {"prior", g.prior.empty() ? std::vector<double>(C, 0.0) : g.prior},
                 {"prior_posture", opt.gate_prior && opt.gate_folds > 0 ? posture_prior<Config::keyframes>(clips, info)
                                                                        : std::vector<std::vector<double>>{}}};
    j["options"] = opt.to_json();
    f.metadata["handemo"] = j.dump();
    f.metadata["checksum"] = detail::checkpoint_checksum(f);
    write_safetensors(ck_path, f);
    read_checkpoint(ck_path);  // the rewritten file passes every check
    return g;
}

/// @brief Trains a model into `out_dir`: the change gate first when opt.gate_folds > 0 (inner models under
/// out_dir/gate/), then G on every clip, with the gate stored in its checkpoint. A resumed run keeps the
/// checkpoint's range and gate.
/// @param gate_out receives the gate fit (rows empty when no gate was fitted)
/// @throws the errors of prepare_data(), fit_change_gate() and trainer::run().
template <stargan_config Config>
std::unique_ptr<trainer<Config>> train_model(const std::vector<labelled_clip>& clips, const config_info& info, const train_options& opt,
                                             const std::filesystem::path& out_dir, bool resume = false,
                                             std::optional<angle_range> range = {}, gate_fit* gate_out = nullptr)
{
    gate_fit g;
    if (opt.gate_folds > 0 && !resume) g = fit_change_gate<Config>(clips, info, opt, out_dir / "gate");
    auto data = prepare_data<Config>(clips, info, opt, range);
    if (!g.posture.empty()) data.gate_posture = g.posture, data.gate_motion = g.motion, data.gate_prior = g.prior;
    if (opt.gate_prior && opt.gate_folds > 0 && !resume) data.prior_posture = posture_prior<Config::keyframes>(clips, info);
    auto tr = std::make_unique<trainer<Config>>(info, std::move(data), opt);
    tr->run(out_dir, resume);
    if (gate_out) *gate_out = std::move(g);
    return tr;
}

}  // namespace handemo::stargan
