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
// With train_options::gate_guard >= 0 the simpler model is kept unless the check says G earns its place: per
// target, the rule's checked choices must have a keyframe RMSE at least gate_guard (a share) below that of the
// statistics setting (gate_settings::statistics(): the posture prior alone, (0, 0, 1), the evaluation's
// `statistics` row) on the same pairs, and (with recognition) a recognition score at least as high; else the
// target gets the statistics setting (gate_fit::row::guarded). The statistics setting involves no choice, so its
// score on those pairs is not optimistic; the rule's checked score is the one above (the margin chosen by
// gate_auto_margin is chosen on the same check, so the rule's side is, if anything, favoured).
// (1, 1, 0) is G's whole change, as StarGAN; (0, 0, 0) leaves the input as it is, with the amplitude stage
// and tempo. With train_options::gate_centre, G's posture part is taken about its own average over the training
// set's neutral takes (posture_centre_of(), each inner model's from its own training clips), so (1, 1, 1) is the
// prior plus what G says is particular to the input, and (1, 1, 0) G's change about that average. The final G is then trained on every training content and the gate (and the prior, from every
// training content) is stored in its checkpoint; transfer applies it (emotion_model::transfer).
// Cost: gate_folds more trainings (each on fewer clips); train_model() runs them first, then the final one.
#pragma once

#include <handemo/core/error.hpp>
#include <handemo/core/io.hpp>
#include <handemo/metrics/baselines.hpp>
#include <handemo/metrics/classifier.hpp>
#include <handemo/metrics/compare.hpp>
#include <handemo/stargan/dataset.hpp>
#include <handemo/stargan/train.hpp>
#include <handemo/stargan/transfer.hpp>

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <utility>
#include <string>
#include <vector>

namespace handemo::stargan {

/// @brief Inner groups and models chosen by the caller instead of fit_change_gate()'s own (the evaluation's
/// shared plan, eval/protocol.hpp: inner models that several folds share). groups[f] lists the contents of
/// inner group f (together, every content of the clips, each once); group f is scored with the G trained on the
/// clips of the other groups with seed seeds[f], kept in dirs[f] and reused from there whenever it holds the G
/// those options train. Two groups' entries may name the same directory only for the same training clips and seed.
struct gate_plan {
    std::vector<std::vector<std::string>> groups;
    std::vector<std::filesystem::path> dirs;
    std::vector<std::uint64_t> seeds;
};

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
        /// The statistics setting (gate_settings::statistics()) on the pairs the check scored: what
        /// train_options::gate_guard compares the check with. NaN without a second group.
        double rmse_cross_statistics = std::nan(""), emotion_cross_statistics = std::nan("");
        /// whether train_options::gate_guard replaced the rule's setting by the statistics setting
        bool guarded = false;
    };
    std::vector<row> rows;
    double margin = std::nan("");   ///< the recognition margin used (train_options::gate_margin, or the one gate_auto_margin chose)
    std::size_t folds = 0;          ///< inner trainings run or reused
    std::size_t reused_folds = 0;   ///< inner models reused (fit_change_gate(..., reuse = true))

    /// @brief The rows as CSV (target,posture,motion,prior,rmse_gated,rmse_full,rmse_none,emotion_gated,emotion_full,emotion_real,pairs,
    /// rmse_cross,emotion_cross,rmse_cross_statistics,emotion_cross_statistics,guarded).
    std::string csv() const
    {
        std::string s = "target,posture,motion,prior,rmse_gated,rmse_full,rmse_none,emotion_gated,emotion_full,emotion_real,pairs,rmse_cross,"
                        "emotion_cross,rmse_cross_statistics,emotion_cross_statistics,guarded\n";
        char b[480];
        for (const auto& r : rows) {
            std::snprintf(b, sizeof b, "%s,%.2f,%.2f,%.2f,%.6f,%.6f,%.6f,%.4f,%.4f,%.4f,%zu,%.6f,%.4f,%.6f,%.4f,%d\n", r.target.c_str(), r.posture,
                          r.motion, r.prior, r.rmse_gated, r.rmse_full, r.rmse_none, r.emotion_gated, r.emotion_full, r.emotion_real, r.pairs,
                          r.rmse_cross, r.emotion_cross, r.rmse_cross_statistics, r.emotion_cross_statistics, r.guarded ? 1 : 0);
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
/// It is the keyframe mean of mean-offset's difference, so it does not depend on an amplitude stage that scales
/// excursions about that mean. An amplitude stage that scales about the ends (`factors` about `anchor`, the model's:
/// train_options::amplitude) moves the mean too, by (f - 1) x (mean - ends' mean); the prior then subtracts the
/// training pairs' mean of that shift (anchor_mean_shift()), so the prior and the scaling together move the mean
/// by the pairs' mean change.
/// @throws value_error when no clip is neutral; shape_error for clips of different skeletons.
template <std::size_t K>
std::vector<std::vector<double>> posture_prior(const std::vector<labelled_clip>& clips, const config_info& info,
                                               const std::vector<double>& factors = {}, amplitude_anchor anchor = amplitude_anchor::mean)
{
    if (clips.empty()) throw value_error("posture_prior: no clips");
    const std::size_t J = clips.front().motion.skel.size(), C = J * 3;
    for (const auto& c : clips)
        if (c.motion.skel.size() != J)
            throw shape_error("posture_prior: " + c.path.string() + " has " + std::to_string(c.motion.skel.size()) + " joints, " +
                              clips.front().path.string() + " has " + std::to_string(J));
    const auto b = metrics::mean_offset_baseline<K>::fit(clips, info.neutral);
    std::vector<std::vector<double>> prior(info.domains, std::vector<double>(C, 0.0));
    for (std::size_t d = 0; d < info.domains; ++d) {
        const std::string& e = info.domain_names[d];
        if (e == info.neutral || !b.has(e)) continue;
        const auto delta = b.delta(e, J);
        for (std::size_t k = 0; k < delta.count(); ++k)
            for (std::size_t ch = 0; ch < C; ++ch) prior[d][ch] += delta.angles[k * C + ch] / static_cast<double>(delta.count());
    }
    if (anchor != amplitude_anchor::mean && factors.size() == info.domains) {
        std::vector<keyframes<K>> kfs;
        for (const auto& c : clips) kfs.push_back(extract_keyframes<K>(c.motion));
        const auto shift = anchor_mean_shift<K>(clips, kfs, info.domain_names, info.neutral, factors, anchor);
        for (std::size_t d = 0; d < info.domains; ++d)
            if (info.domain_names[d] != info.neutral && b.has(info.domain_names[d]))
                for (std::size_t ch = 0; ch < C; ++ch) prior[d][ch] -= shift[d][ch];
    }
    return prior;
}

/// @brief G's average posture per target (train_options::gate_centre): for every target but the neutral domain, the
/// mean over the neutral clips of `clips` of G's change averaged over the keyframes (transfer_parts::change_mean),
/// per channel, in degrees; the neutral domain's row is zeros. emotion_model::set_posture_centre() takes it, and the
/// gate then weighs G's posture about this average. One transfer per neutral clip and target, in clip order.
/// @param model a residual model holding no posture centre yet (its change as G gives it)
/// @throws value_error for a model that is not residual or already holds a centre, or clips without a neutral one;
///         the errors of emotion_model::parts() (a clip of another skeleton).
inline std::vector<std::vector<double>> posture_centre_of(const emotion_model& model, const std::vector<labelled_clip>& clips, const config_info& info)
{
    if (!model.residual()) throw value_error("posture_centre_of: the model's G is not residual");
    if (!model.posture_centre().empty()) throw value_error("posture_centre_of: the model already holds a posture centre");
    const std::size_t C = model.joints() * 3;
    std::vector<std::vector<double>> centre(info.domains, std::vector<double>(C, 0.0));
    std::size_t neutrals = 0;
    auto ws = model.make_workspace();
    transfer_parts p;
    for (const auto& c : clips) {
        if (c.emotion != info.neutral) continue;
        ++neutrals;
        for (std::size_t d = 0; d < info.domains; ++d) {
            if (info.domain_names[d] == info.neutral) continue;
            model.parts_into(c.motion, info.domain_names[d], {}, ws, p);
            for (std::size_t ch = 0; ch < C; ++ch) centre[d][ch] += p.change_mean[ch];
        }
    }
    if (neutrals == 0) throw value_error("posture_centre_of: no '" + info.neutral + "' clip to average G's change over");
    for (auto& row : centre)
        for (auto& v : row) v /= static_cast<double>(neutrals);
    return centre;
}

namespace detail {

/// The training options without the gate's own (gate_folds, gate_prior, gate_margin, ...), the tempo's (the
/// images are time-normalised: the tempo never reaches G) and the joint lag's (applied after G): two checkpoints
/// whose options agree on these trained the same G, whatever gate, tempo and lag were fitted around it.
inline nlohmann::json options_without_gate(nlohmann::json o)
{
    if (o.is_object())
        for (const char* k : {"gate_folds", "gate_prior", "gate_margin", "gate_posterior", "gate_auto_margin", "gate_guard", "gate_centre", "gate_prior_full", "gate_iters_scale", "tempo_shrink", "tempo_basis", "tempo_neighbours", "lag"}) o.erase(k);
    return o;
}

/// Whether a checkpoint holds the G that `opt` trains: the same options (the gate's and the tempo's aside) and
/// opt.iters steps.
inline bool trained_same_g(const checkpoint_info& ck, const train_options& opt)
{
    return ck.step == opt.iters && options_without_gate(ck.options) == options_without_gate(opt.to_json());
}

/// What makes a checkpoint not the G that `opt` trains (trained_same_g() false): its steps, or the first option
/// (the gate's and the tempo's aside) whose value differs or is missing on one side, as "name stored / wanted".
inline std::string g_difference(const checkpoint_info& ck, const train_options& opt)
{
    if (ck.step != opt.iters) return "steps " + std::to_string(ck.step) + " / " + std::to_string(opt.iters);
    const auto have = options_without_gate(ck.options), want = options_without_gate(opt.to_json());
    const auto dump = [](const nlohmann::json& o, const std::string& k) { return o.is_object() && o.contains(k) ? o.at(k).dump() : std::string("absent"); };
    if (want.is_object())
        for (const auto& [k, v] : want.items())
            if (!have.is_object() || !have.contains(k) || have.at(k) != v) return k + " " + dump(have, k) + " / " + dump(want, k);
    if (have.is_object())
        for (const auto& [k, v] : have.items())
            if (!want.contains(k)) return k + " " + v.dump() + " / absent";
    return "the options";
}

}  // namespace detail

/// @brief The settings fit_change_gate() chooses from: posture weight a, motion weight b (each from gate_grid)
/// and prior weight c (gate_grid with train_options::gate_prior, else only 0), setting index (a * G + b) * P + c.
struct gate_settings {
    static constexpr std::size_t G = gate_grid.size();
    bool prior = false;
    /// the prior at full weight in every setting (train_options::gate_prior_full): G's weights alone are chosen;
    /// full() is then (1, 1, 1) and none() (0, 0, 1), the statistics setting
    bool prior_full = false;
    std::size_t P() const noexcept { return prior && !prior_full ? G : 1; }
    std::size_t size() const noexcept { return G * G * P(); }
    std::size_t index(std::size_t a, std::size_t b, std::size_t c) const noexcept { return (a * G + b) * P() + c; }
    double posture(std::size_t s) const noexcept { return gate_grid[s / (G * P())]; }
    double motion(std::size_t s) const noexcept { return gate_grid[(s / P()) % G]; }
    double prior_weight(std::size_t s) const noexcept { return prior ? (prior_full ? 1.0 : gate_grid[s % P()]) : 0.0; }
    /// G's whole change without the prior, (1, 1, 0), and no change, (0, 0, 0): gate_grid runs from 1 down to 0
    std::size_t full() const noexcept { return index(0, 0, P() - 1); }
    std::size_t none() const noexcept { return index(G - 1, G - 1, P() - 1); }
    /// The setting train_options::gate_guard falls back to: the posture prior alone, (0, 0, 1), which with the
    /// amplitude stage and tempo is the evaluation's statistics row; without the prior, no change (0, 0, 0).
    std::size_t statistics() const noexcept { return prior ? index(G - 1, G - 1, 0) : none(); }
};

/// @brief What the held-out pairs of one target gave, per setting: the summed keyframe RMSE, the outputs the
/// classifier recognised as the target (hits) and what the rule scores recognition by (hits, or the
/// classifier's posterior with gate_posterior); the pairs and the real clips' hits and score.
struct gate_tally {
    std::vector<double> rmse, hits, score;  ///< [settings]
    double pairs = 0, real_hits = 0, real_score = 0;

    static gate_tally zeros(std::size_t settings)
    {
        return {std::vector<double>(settings, 0.0), std::vector<double>(settings, 0.0), std::vector<double>(settings, 0.0)};
    }
    void add(const gate_tally& x)
    {
        pairs += x.pairs, real_hits += x.real_hits, real_score += x.real_score;
        for (std::size_t s = 0; s < rmse.size(); ++s) rmse[s] += x.rmse[s], hits[s] += x.hits[s], score[s] += x.score[s];
    }
};

/// @brief The gate's rule on one target's pooled pairs: with recognition (use_emotion), the lowest RMSE among
/// the settings whose score share is at most `margin` below the real clips' (margins below 0 ask for more),
/// else the most recognised setting, then the lowest RMSE; without it, the lowest RMSE. Ties go to the lower
/// index (more of G's change). Returns the setting index, or rmse.size() when there are no pairs.
inline std::size_t choose_gate_setting(const gate_tally& p, double margin, bool use_emotion)
{
    const std::size_t S = p.rmse.size();
    const auto& rs = p.rmse;
    const auto& os = p.score;
    const double n = p.pairs;
    std::size_t best = S;
    if (n == 0) return best;
    if (!use_emotion) {
        best = 0;
        for (std::size_t s = 0; s < S; ++s)
            if (rs[s] < rs[best]) best = s;
        return best;
    }
    for (std::size_t s = 0; s < S; ++s)
        if (os[s] / n >= p.real_score / n - margin - 1e-12 && (best == S || rs[s] < rs[best])) best = s;
    if (best == S)  // no setting is recognised well enough: the most recognised, then the lowest RMSE
        for (std::size_t s = 0; s < S; ++s)
            if (best == S || os[s] > os[best] || (os[s] == os[best] && rs[s] < rs[best])) best = s;
    return best;
}

/// @brief The tallies of target t ([group][target]) pooled over the groups in `use`.
inline gate_tally pool_gate_tallies(const std::vector<std::vector<gate_tally>>& tallies, std::size_t t, const std::vector<bool>& use)
{
    gate_tally p = gate_tally::zeros(tallies.front()[t].rmse.size());
    for (std::size_t f = 0; f < tallies.size(); ++f)
        if (use[f]) p.add(tallies[f][t]);
    return p;
}

/// @brief The rule checked inside the training set for one target: pooled over the groups, what the setting
/// chosen without group f (from the other groups' pairs) gave on group f's pairs, and what one fixed setting
/// (`base`, for train_options::gate_guard) gave on the same pairs.
struct gate_cross {
    double rmse = 0, hits = 0, real_hits = 0, pairs = 0;  ///< sums over the scored pairs
    double score = 0;                                     ///< the rule's recognition score (hits, or posteriors with gate_posterior)
    double base_rmse = 0, base_hits = 0, base_score = 0;  ///< the fixed setting on the same pairs
    void add(const gate_cross& x)
    {
        rmse += x.rmse, hits += x.hits, real_hits += x.real_hits, pairs += x.pairs, score += x.score;
        base_rmse += x.base_rmse, base_hits += x.base_hits, base_score += x.base_score;
    }
};

/// @brief gate_cross of target t under `margin` (choose_gate_setting on the other groups, scored on each group),
/// with setting `base` scored on the same pairs (base_* stay 0 when `base` is not a setting).
inline gate_cross cross_check_gate(const std::vector<std::vector<gate_tally>>& tallies, std::size_t t, double margin, bool use_emotion,
                                   std::size_t base = static_cast<std::size_t>(-1))
{
    gate_cross r;
    const std::size_t F = tallies.size();
    for (std::size_t f = 0; f < F; ++f) {
        const gate_tally& x = tallies[f][t];
        if (x.pairs == 0) continue;
        std::vector<bool> others(F, true);
        others[f] = false;
        const std::size_t s = choose_gate_setting(pool_gate_tallies(tallies, t, others), margin, use_emotion);
        if (s == x.rmse.size()) continue;
        r.rmse += x.rmse[s], r.hits += x.hits[s], r.real_hits += x.real_hits, r.pairs += x.pairs, r.score += x.score[s];
        if (base < x.rmse.size()) r.base_rmse += x.rmse[base], r.base_hits += x.hits[base], r.base_score += x.score[base];
    }
    return r;
}

/// @brief train_options::gate_guard's test for one target's check (cross_check_gate() with the statistics setting
/// as `base`): whether the rule's checked choices beat the statistics setting on the same pairs, with a keyframe
/// RMSE at most (1 - guard) times its RMSE and, when `use_emotion`, a recognition score at least as high. False
/// when the check scored no pair (no evidence for G).
inline bool gate_guard_passes(const gate_cross& c, double guard, bool use_emotion)
{
    if (c.pairs == 0) return false;
    if (!(c.rmse <= (1 - guard) * c.base_rmse)) return false;
    return !use_emotion || c.score >= c.base_score - 1e-9 * c.pairs;
}

/// @brief train_options::gate_auto_margin's choice among `candidates` (gate_margin_candidates()): the least
/// strict margin whose cross-checked recognition, pooled over the targets, is at most `margin` below the real
/// clips'; else the one with the most cross-checked recognised outputs (the first of equals).
/// @param pooled receives each candidate's cross-check pooled over the targets
/// @return the index into `candidates`
inline std::size_t choose_gate_margin(const std::vector<std::vector<gate_tally>>& tallies, const std::vector<double>& candidates,
                                      double margin, std::vector<gate_cross>& pooled)
{
    const std::size_t C = tallies.front().size();
    pooled.assign(candidates.size(), gate_cross{});
    std::size_t pick = candidates.size(), top = 0;
    for (std::size_t i = 0; i < candidates.size(); ++i) {
        for (std::size_t t = 0; t < C; ++t) pooled[i].add(cross_check_gate(tallies, t, candidates[i], true));
        const auto& p = pooled[i];
        if (p.pairs > 0 && pick == candidates.size() && p.hits / p.pairs >= p.real_hits / p.pairs - margin - 1e-12) pick = i;
        if (p.hits > pooled[top].hits) top = i;
    }
    return pick == candidates.size() ? top : pick;
}

namespace detail {

/// The content groups of fit_change_gate(): content i (in sorted order) goes to group i mod F.
struct content_groups {
    std::vector<std::string> contents;
    std::size_t F = 0;
    const gate_plan* plan = nullptr;  ///< explicit groups, else content i of the sorted contents is in group i % F
    std::size_t of(const std::string& content) const
    {
        if (plan) {
            for (std::size_t f = 0; f < plan->groups.size(); ++f)
                if (std::find(plan->groups[f].begin(), plan->groups[f].end(), content) != plan->groups[f].end()) return f;
            return F;  // checked by fit_change_gate: every content has a group
        }
        return static_cast<std::size_t>(std::find(contents.begin(), contents.end(), content) - contents.begin()) % F;
    }
    /// The seed of the G that scores group f: the plan's, else opt.seed + 7919 (f + 1).
    std::uint64_t seed(std::size_t f, const train_options& opt) const { return plan ? plan->seeds[f] : opt.seed + 7919 * (f + 1); }
    /// Where that G is kept: the plan's directory, else work_dir/inner<f + 1>.
    std::filesystem::path dir(std::size_t f, const std::filesystem::path& work_dir) const
    {
        return plan ? plan->dirs[f] : work_dir / ("inner" + std::to_string(f + 1));
    }
    std::string names(std::size_t f) const
    {
        std::string s;
        for (const auto& c : contents)
            if (of(c) == f) s += (s.empty() ? "" : ", ") + c;
        return s;
    }
};

/// The inner groups of fit_change_gate(): the plan's, else the sorted contents dealt round max(gate_folds, 2).
/// @throws value_error for a plan without 2 groups, a directory and a seed per group, or one that does not list
/// every content of the clips exactly once.
inline content_groups make_content_groups(const std::vector<labelled_clip>& clips, const train_options& opt, const gate_plan* plan)
{
    content_groups groups;
    groups.F = plan ? plan->groups.size() : static_cast<std::size_t>(std::max(opt.gate_folds, 2));
    groups.plan = plan;
    for (const auto& c : clips)
        if (std::find(groups.contents.begin(), groups.contents.end(), c.content) == groups.contents.end()) groups.contents.push_back(c.content);
    std::sort(groups.contents.begin(), groups.contents.end());
    if (plan) {
        if (plan->groups.size() < 2 || plan->dirs.size() != plan->groups.size() || plan->seeds.size() != plan->groups.size())
            throw value_error("train: a gate plan needs at least 2 groups, each with a directory and a seed (" +
                              std::to_string(plan->groups.size()) + " groups, " + std::to_string(plan->dirs.size()) + " directories, " +
                              std::to_string(plan->seeds.size()) + " seeds)");
        std::size_t listed = 0;
        for (const auto& g : plan->groups) listed += g.size();
        for (const auto& c : groups.contents)
            if (groups.of(c) == groups.F) throw value_error("train: content '" + c + "' is in no group of the gate plan");
        if (listed != groups.contents.size())
            throw value_error("train: the gate plan lists " + std::to_string(listed) + " contents, the clips have " +
                              std::to_string(groups.contents.size()));
    }
    return groups;
}

/// The checkpoint of inner group f: trained on `train` with the inner options, or reused from dir when `reuse`
/// and it holds the G those options train. `reused` tells which.
template <stargan_config Config>
std::pair<safetensors_file, checkpoint_info> inner_gate_model(const std::vector<labelled_clip>& train, const config_info& info,
                                                             const train_options& inner, const std::filesystem::path& dir,
                                                             bool reuse, const std::string& label, bool& reused)
{
    const auto ck_path = dir / "checkpoint.safetensors";
    reused = false;
    if (reuse && path_exists(ck_path)) {
        if (auto stored = read_checkpoint(ck_path); trained_same_g(stored.second, inner)) {
            if (inner.progress_out)
                std::fprintf(inner.progress_out, "%s: reusing the G trained without those contents (%s)\n", label.c_str(), ck_path.string().c_str());
            reused = true;
            return stored;
        } else if (inner.progress_out) {
            std::fprintf(inner.progress_out, "%s: %s was trained otherwise (%s, stored / now): training it again\n", label.empty() ? "gate" : label.c_str(),
                         ck_path.string().c_str(), g_difference(stored.second, inner).c_str());
        }
    }
    if (inner.progress_out)
        std::fprintf(inner.progress_out, "%s: training G on the other %zu clips to choose the change gate\n", label.c_str(), train.size());
    {
        trainer<Config> tr(info, prepare_data<Config>(train, info, inner), inner);
        tr.run(dir);
        // a process that writes no files (train_options::exchange) holds the same model in memory
        if (!writes_files(inner)) return parse_checkpoint(tr.checkpoint(ck_path.string()));
    }
    return read_checkpoint(ck_path);
}

/// Scores every gate setting on the held-out pairs of one inner group: for each held-out neutral take and each
/// target with a real take of the same content and take, G's parts once, then every setting's output against
/// the real take (RMSE) and through the classifier fitted on the group's training clips. tallies: [targets].
template <stargan_config Config>
void score_gate_group(const emotion_model& model, const std::vector<labelled_clip>& train, const std::vector<const labelled_clip*>& held,
                      const config_info& info, const train_options& opt, const gate_settings& set, std::vector<gate_tally>& tallies)
{
    constexpr std::size_t K = Config::keyframes;
    const bool use_emotion = opt.gate_margin > -1;
    auto ws = model.make_workspace();  // the generator's scratch, reused by every transfer below
    metrics::nearest_centroid_classifier clf;  // the evaluation's independent classifier, fitted on this inner training set only
    if (use_emotion) {
        std::vector<std::vector<double>> x;
        std::vector<std::string> y;
        for (const auto& c : train) x.push_back(metrics::motion_features(extract_keyframes<K>(c.motion), c.motion.duration())), y.push_back(c.emotion);
        clf.fit(x, y);
    }
    // adds to `hits` whether the classifier recognises class `target` from x, and to `score` what the rule counts
    const auto recognise = [&](const std::vector<double>& x, std::size_t target, double& hits, double& score) {
        const auto d = clf.distances(x);
        const bool hit = static_cast<std::size_t>(std::min_element(d.begin(), d.end()) - d.begin()) == target;
        hits += hit;
        score += opt.gate_posterior ? metrics::nearest_centroid_classifier::posterior_of(d, target) : static_cast<double>(hit);
    };
    for (const auto* in : held) {
        if (in->emotion != info.neutral) continue;
        for (std::size_t t = 0; t < info.domains; ++t) {
            const std::string& target = info.domain_names[t];
            if (target == info.neutral) continue;
            const labelled_clip* real = nullptr;
            for (const auto* r : held)
                if (r->content == in->content && r->emotion == target && r->take == in->take) real = r;
            if (!real) continue;
            const auto real_kf = extract_keyframes<K>(real->motion);
            gate_tally& ty = tallies[t];
            const std::size_t label = use_emotion ? clf.index_of(target) : 0;
            if (use_emotion) recognise(metrics::motion_features(real_kf, real->motion.duration()), label, ty.real_hits, ty.real_score);
            const auto parts = model.parts(in->motion, target, {}, ws);
            for (std::size_t s = 0; s < set.size(); ++s) {
                const clip out = model.finish(in->motion, parts, set.posture(s), set.motion(s), set.prior_weight(s));
                const auto kf = extract_keyframes<K>(out);
                ty.rmse[s] += metrics::keyframe_rmse(kf, real_kf);
                if (use_emotion) recognise(metrics::motion_features(kf, out.duration()), label, ty.hits[s], ty.score[s]);
            }
            ty.pairs += 1;
        }
    }
}

/// gate_margins.csv: every candidate margin's cross-check pooled over the targets, and which was chosen.
inline std::string gate_margins_csv(const std::vector<double>& candidates, const std::vector<gate_cross>& pooled, std::size_t pick)
{
    std::string table = "margin,rmse_cross,emotion_cross,emotion_real,pairs,chosen\n";
    char b[200];
    for (std::size_t i = 0; i < candidates.size(); ++i) {
        const auto& p = pooled[i];
        const double n = p.pairs;
        std::snprintf(b, sizeof b, "%.2f,%.6f,%.4f,%.4f,%.0f,%d\n", candidates[i], n > 0 ? p.rmse / n : std::nan(""),
                      n > 0 ? p.hits / n : std::nan(""), n > 0 ? p.real_hits / n : std::nan(""), n, i == pick ? 1 : 0);
        table += b;
    }
    return table;
}

}  // namespace detail

/// @brief The gate of every target from the inner groups' tallies ([group][target]) under `margin`: the weights
/// choose_gate_setting() picks on the pairs pooled over the groups, and a row per target with pairs (its RMSE
/// and recognition at the chosen setting, G's whole change and no change, and the rule's cross-check). With
/// `guard` >= 0 (train_options::gate_guard) a target whose check fails gate_guard_passes() gets the statistics
/// setting instead.
inline gate_fit gate_from_tallies(const std::vector<std::vector<gate_tally>>& tallies, const config_info& info, const gate_settings& set,
                                  double margin, bool use_emotion, double guard = -1)
{
    const std::size_t C = info.domains;
    gate_fit g;
    g.posture.assign(C, 1.0);
    g.motion.assign(C, 1.0);
    g.prior.assign(C, 0.0);
    if (use_emotion) g.margin = margin;
    g.folds = tallies.size();
    if (tallies.empty()) return g;
    for (std::size_t t = 0; t < C; ++t) {
        const gate_tally all = pool_gate_tallies(tallies, t, std::vector<bool>(tallies.size(), true));
        if (all.pairs == 0) continue;
        const double n = all.pairs;
        std::size_t best = choose_gate_setting(all, margin, use_emotion);
        const gate_cross cross = cross_check_gate(tallies, t, margin, use_emotion, set.statistics());
        const bool guarded = guard >= 0 && best != set.statistics() && !gate_guard_passes(cross, guard, use_emotion);
        if (guarded) best = set.statistics();
        g.posture[t] = set.posture(best);
        g.motion[t] = set.motion(best);
        g.prior[t] = set.prior_weight(best);
        gate_fit::row r{info.domain_names[t], g.posture[t], g.motion[t], g.prior[t], all.rmse[best] / n, all.rmse[set.full()] / n,
                        all.rmse[set.none()] / n};
        if (use_emotion) r.emotion_gated = all.hits[best] / n, r.emotion_full = all.hits[set.full()] / n, r.emotion_real = all.real_hits / n;
        r.pairs = static_cast<std::size_t>(all.pairs);
        r.guarded = guarded;
        if (cross.pairs > 0) {
            r.rmse_cross = cross.rmse / cross.pairs;
            r.rmse_cross_statistics = cross.base_rmse / cross.pairs;
            if (use_emotion) r.emotion_cross = cross.hits / cross.pairs, r.emotion_cross_statistics = cross.base_hits / cross.pairs;
        }
        g.rows.push_back(r);
    }
    return g;
}

/// @brief The options an inner model of the change gate is trained with: `opt` without the gate, with its own
/// seed, one checkpoint at the end.
inline train_options inner_gate_options(const train_options& opt, std::uint64_t seed)
{
    auto inner = opt;
    inner.gate_folds = 0;
    inner.seed = seed;
    inner.iters = std::max(1L, std::lround(static_cast<double>(opt.iters) * opt.gate_iters_scale));
    inner.checkpoint_every = inner.iters;
    inner.stop_at = -1;
    return inner;
}

/// @brief The inner groups fit_change_gate() forms from `clips` with `opt` and `plan`, one line per group with
/// its contents and seed: what it writes to work_dir/groups.txt, so that a reused model's gate can be checked
/// against the groups a run would form now (`handemo eval --reuse-models`).
/// @throws the errors of detail::make_content_groups().
inline std::string gate_groups_text(const std::vector<labelled_clip>& clips, const train_options& opt, const gate_plan* plan)
{
    const auto groups = detail::make_content_groups(clips, opt, plan);
    std::string s;
    for (std::size_t f = 0; f < groups.F; ++f)
        s += "group " + std::to_string(f + 1) + ": " + groups.names(f) + " (scored by G trained with seed " +
             std::to_string(groups.seed(f, opt)) + " on the other groups)\n";
    return s;
}

/// @brief Chooses the change gate of a residual G by leave-content-group-out inside `clips` (see the header
/// comment). Inner models are written to work_dir/inner<i>/ and the table to work_dir/gate.csv.
/// @param opt the options the final G is trained with (gate_folds inner trainings of them, each with its own seed)
/// @param reuse keep an inner model already in work_dir/inner<i>/ when it was trained with the same options
///        (the gate's own aside) and steps, instead of training it again (`handemo eval --reuse-models`)
/// @param plan the inner groups, their models' directories and seeds (see gate_plan; its models are always reused
///        when they match), instead of the sorted contents dealt round the gate_folds groups under work_dir
/// @return all-1 weights (and no rows) when the clips have fewer contents than opt.gate_folds or no neutral take
///         with a real target in a held-out group.
/// @throws value_error when opt is not residual; the errors of training and transfer otherwise.
template <stargan_config Config>
gate_fit fit_change_gate(const std::vector<labelled_clip>& clips, const config_info& info, const train_options& opt,
                         const std::filesystem::path& work_dir, bool reuse = false, const gate_plan* plan = nullptr)
{
    constexpr std::size_t K = Config::keyframes;
    if (!opt.residual) throw value_error("train: the change gate needs a residual G (--residual true)");
    const auto groups = detail::make_content_groups(clips, opt, plan);
    const std::size_t F = groups.F;
    if (groups.contents.size() < F) {
        if (opt.progress_out)
            std::fprintf(opt.progress_out, "gate: %zu contents, fewer than the %zu groups the gate needs: G's whole change is used\n",
                         groups.contents.size(), F);
        return gate_from_tallies({}, info, gate_settings{opt.gate_prior, opt.gate_prior_full}, opt.gate_margin, false);
    }
    const gate_settings set{opt.gate_prior, opt.gate_prior_full};
    const bool use_emotion = opt.gate_margin > -1;  // margins in (-1, 0) ask for more than the real rate
    std::vector<std::vector<gate_tally>> tallies(F, std::vector<gate_tally>(info.domains, gate_tally::zeros(set.size())));
    const bool writer = writes_files(opt);
    if (writer) make_directories(work_dir);
    std::size_t reused_folds = 0;
    for (std::size_t f = 0; f < F; ++f) {
        std::vector<labelled_clip> train;
        std::vector<const labelled_clip*> held;
        for (const auto& c : clips)
            if (groups.of(c.content) == f)
                held.push_back(&c);
            else
                train.push_back(c);
        const auto inner = inner_gate_options(opt, groups.seed(f, opt));
        bool reused = false;
        const auto label = "gate " + std::to_string(f + 1) + "/" + std::to_string(F) + " (without " + groups.names(f) + ")";
        const auto ck = detail::inner_gate_model<Config>(train, info, inner, groups.dir(f, work_dir), reuse || plan, label, reused);
        reused_folds += reused;
        auto ck_info = ck.second;
        // a reused inner model may have been fitted with another tempo option: the tempo training would store now
        ck_info.tempo = tempo_factors(train, info.domain_names, info.neutral, opt.tempo_shrink, parse_tempo_basis(opt.tempo_basis));
        ck_info.tempo_table = tempo_table_of(train, info, opt);
        // and with or without the joint lag: the lag training would store now (G's options are the same)
        ck_info.lag = joint_lag_of<Config>(train, info, opt);
        detail::emotion_model_impl<Config> model(ck.first, ck_info);
        if (opt.gate_prior)
            model.set_prior_posture(opt.amplitude ? posture_prior<K>(train, info, ck_info.amplitude, ck_info.amplitude_anchor)
                                                  : posture_prior<K>(train, info));
        if (opt.gate_centre) model.set_posture_centre(posture_centre_of(model, train, info));
        detail::score_gate_group<Config>(model, train, held, info, opt, set, tallies[f]);
    }
    double margin = opt.gate_margin;
    if (use_emotion && opt.gate_auto_margin) {
        const auto candidates = gate_margin_candidates(opt.gate_margin);
        std::vector<gate_cross> pooled;
        const std::size_t pick = choose_gate_margin(tallies, candidates, opt.gate_margin, pooled);
        margin = candidates[pick];
        if (writer) write_file_atomic(work_dir / "gate_margins.csv", detail::gate_margins_csv(candidates, pooled, pick));
        if (opt.progress_out) {
            const auto& p = pooled[pick];
            const double n = std::max(1.0, p.pairs);
            std::fprintf(opt.progress_out,
                         "gate: margin %.2f chosen inside the training set (its choices, made on one group and scored on the other: "
                         "recognised %.0f%% against the real clips' %.0f%%, %.3f deg; %s)\n",
                         margin, 100 * p.hits / n, 100 * p.real_hits / n, p.rmse / n, (work_dir / "gate_margins.csv").string().c_str());
        }
    }
    gate_fit g = gate_from_tallies(tallies, info, set, margin, use_emotion, opt.gate_guard);
    g.reused_folds = reused_folds;
    if (opt.progress_out)
        for (const auto& r : g.rows)
            std::fprintf(opt.progress_out,
                         "gate: %-10s posture %.2f motion %.2f prior %.2f (held-out contents: %.3f deg, G's whole change %.3f, no change %.3f; "
                         "recognised %.0f%%, G's whole change %.0f%%, real %.0f%%; %zu pairs)%s\n",
                         r.target.c_str(), r.posture, r.motion, r.prior, r.rmse_gated, r.rmse_full, r.rmse_none, 100 * r.emotion_gated,
                         100 * r.emotion_full, 100 * r.emotion_real, r.pairs,
                         r.guarded ? "; the statistics setting kept: G's checked choices did not beat it" : "");
    if (writer) write_file_atomic(work_dir / "gate.csv", g.csv()), write_file_atomic(work_dir / "groups.txt", gate_groups_text(clips, opt, plan));
    return g;
}

/// @brief Fits the change gate again around a model already trained into `out_dir` (its inner models reused
/// when they match, see fit_change_gate()) and rewrites the checkpoint's gate, prior, tempo factors
/// (train_options::tempo_shrink, tempo_basis, tempo_neighbours), joint lag and options in place (atomically, new checksum); G's weights are untouched. `handemo eval --reuse-models` uses it when only
/// the gate options changed since the model was trained.
/// @throws value_error when the checkpoint was trained with other options (the gate's aside) or steps.
template <stargan_config Config>
gate_fit refit_gate(const std::vector<labelled_clip>& clips, const config_info& info, const train_options& opt,
                    const std::filesystem::path& out_dir, const gate_plan* plan = nullptr)
{
    const auto ck_path = out_dir / "checkpoint.safetensors";
    auto [f, stored] = read_checkpoint(ck_path);
    if (!detail::trained_same_g(stored, opt))
        throw value_error("train: " + ck_path.string() + " was not trained with these options (the gate's aside) and " +
                          std::to_string(opt.iters) + " steps: its gate cannot be refitted");
    gate_fit g;
    if (opt.gate_folds > 0) g = fit_change_gate<Config>(clips, info, opt, out_dir / "gate", true, plan);
    auto j = nlohmann::json::parse(f.metadata.at("handemo"));
    const std::size_t C = info.domains;
    j["gate"] = {{"posture", g.posture.empty() ? std::vector<double>(C, 1.0) : g.posture},
                 {"motion", g.motion.empty() ? std::vector<double>(C, 1.0) : g.motion},
                 {"prior", g.prior.empty() ? std::vector<double>(C, 0.0) : g.prior},
                 {"prior_posture", opt.gate_prior && opt.gate_folds > 0
                                       ? (opt.amplitude ? posture_prior<Config::keyframes>(clips, info, stored.amplitude, stored.amplitude_anchor)
                                                        : posture_prior<Config::keyframes>(clips, info))
                                       : std::vector<std::vector<double>>{}}};
    if (opt.gate_centre && opt.gate_folds > 0) {
        auto raw = stored;
        raw.posture_centre.clear();  // the stored G's change as G gives it, whatever centre the checkpoint held
        const detail::emotion_model_impl<Config> model(f, raw);
        j["gate"]["posture_centre"] = posture_centre_of(model, clips, info);
    }
    j["tempo"] = tempo_factors(clips, info.domain_names, info.neutral, opt.tempo_shrink, parse_tempo_basis(opt.tempo_basis));
    if (const auto lag = joint_lag_of<Config>(clips, info, opt); !lag.empty())
        j["lag"] = lag;
    else
        j.erase("lag");
    if (const auto table = tempo_table_of(clips, info, opt); !table.empty())
        j["tempo_neighbours"] = detail::tempo_neighbours_json(table);
    else
        j.erase("tempo_neighbours");
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
/// @param plan the change gate's inner groups and models (fit_change_gate()), else its own
/// @param reuse_inner keep an inner model already in its folder when it holds the G its options train (a plan's
///        models are always kept so)
/// @throws the errors of prepare_data(), fit_change_gate() and trainer::run().
template <stargan_config Config>
std::unique_ptr<trainer<Config>> train_model(const std::vector<labelled_clip>& clips, const config_info& info, const train_options& opt,
                                             const std::filesystem::path& out_dir, bool resume = false,
                                             std::optional<angle_range> range = {}, gate_fit* gate_out = nullptr,
                                             const gate_plan* plan = nullptr, bool reuse_inner = false)
{
    gate_fit g;
    if (opt.gate_folds > 0 && !resume) g = fit_change_gate<Config>(clips, info, opt, out_dir / "gate", reuse_inner, plan);
    auto data = prepare_data<Config>(clips, info, opt, range);
    if (!g.posture.empty()) data.gate_posture = g.posture, data.gate_motion = g.motion, data.gate_prior = g.prior;
    if (opt.gate_prior && opt.gate_folds > 0 && !resume)
        data.prior_posture = opt.amplitude ? posture_prior<Config::keyframes>(clips, info, data.amplitude, data.amplitude_anchor)
                                           : posture_prior<Config::keyframes>(clips, info);
    auto tr = std::make_unique<trainer<Config>>(info, std::move(data), opt);
    if (opt.gate_centre && opt.gate_folds > 0) {
        // G's average posture, computed from the weights of every save (the hook outlives this call: it keeps the
        // neutral clips, all posture_centre_of() reads)
        std::vector<labelled_clip> neutrals;
        for (const auto& c : clips)
            if (c.emotion == info.neutral) neutrals.push_back(c);
        tr->set_posture_centre_hook([neutrals = std::move(neutrals), info](const safetensors_file& f) {
            const auto ck = parse_checkpoint(f);
            const detail::emotion_model_impl<Config> model(ck.first, ck.second);
            return posture_centre_of(model, neutrals, info);
        });
    }
    tr->run(out_dir, resume);
    if (gate_out) *gate_out = std::move(g);
    return tr;
}

}  // namespace handemo::stargan
