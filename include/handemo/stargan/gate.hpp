// The change gate (beyond the paper; train_options::gate_folds): how much of a residual G's change to apply
// to a motion of a content it never saw, chosen per target emotion from the training set alone.
//
// G fits the contents it trains on, but on a new motion type part of its change can be content-specific and
// make the motion worse than no change at all. Whether it does is measurable inside the training set:
// fit_change_gate() splits the training contents into gate_folds groups, trains G once per group without that
// group (same options and steps), and transfers the held-out group's neutral takes to every other emotion.
// G's change is split into its mean over the keyframes per channel (the posture: a held wrist, a sunk hand)
// and the rest (the motion), and every pair of weights (posture, motion) in {0, 0.25, 0.5, 0.75, 1}^2 is
// scored by keyframe RMSE to the real take of the target emotion (the evaluation's measure); each target
// emotion gets the pair with the lowest mean. (1, 1) is G's whole change, as StarGAN; (0, 0) leaves the input
// as it is, with the amplitude stage and tempo. The final G is then trained on every training content and
// the gate is stored in its checkpoint; transfer applies it (emotion_model::transfer).
// Cost: gate_folds more trainings (each on fewer clips); train_model() runs them first, then the final one.
#pragma once

#include <handemo/core/error.hpp>
#include <handemo/core/io.hpp>
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
#include <set>
#include <string>
#include <vector>

namespace handemo::stargan {

/// @brief The outcome of fit_change_gate().
struct gate_fit {
    std::vector<double> posture, motion;  ///< [C] the chosen weights per target domain (1 for neutral)
    /// One row per target domain that had validation pairs.
    struct row {
        std::string target;
        double posture = 1, motion = 1;
        double rmse_gated = 0, rmse_full = 0, rmse_none = 0;  ///< mean keyframe RMSE (deg): chosen, (1, 1), (0, 0)
        std::size_t pairs = 0;                                ///< (held-out neutral take, real target take) pairs
    };
    std::vector<row> rows;
    std::size_t folds = 0;  ///< inner trainings run

    /// @brief The rows as CSV (target,posture,motion,rmse_gated,rmse_full,rmse_none,pairs).
    std::string csv() const
    {
        std::string s = "target,posture,motion,rmse_gated,rmse_full,rmse_none,pairs\n";
        char b[256];
        for (const auto& r : rows) {
            std::snprintf(b, sizeof b, "%s,%.2f,%.2f,%.6f,%.6f,%.6f,%zu\n", r.target.c_str(), r.posture, r.motion, r.rmse_gated,
                          r.rmse_full, r.rmse_none, r.pairs);
            s += b;
        }
        return s;
    }
};

/// The weights fit_change_gate() chooses from, for the posture and for the motion part of G's change.
inline constexpr std::array<double, 5> gate_grid{1.0, 0.75, 0.5, 0.25, 0.0};

/// @brief Chooses the change gate of a residual G by leave-content-group-out inside `clips` (see the header
/// comment). Inner models are written to work_dir/inner<i>/ and the table to work_dir/gate.csv.
/// @param opt the options the final G is trained with (gate_folds inner trainings of them, each with its own seed)
/// @return all-1 weights (and no rows) when the clips have fewer contents than opt.gate_folds or no neutral take
///         with a real target in a held-out group.
/// @throws value_error when opt is not residual; the errors of training and transfer otherwise.
template <stargan_config Config>
gate_fit fit_change_gate(const std::vector<labelled_clip>& clips, const config_info& info, const train_options& opt,
                         const std::filesystem::path& work_dir)
{
    constexpr std::size_t K = Config::keyframes;
    const std::size_t C = info.domains;
    if (!opt.residual) throw value_error("train: the change gate needs a residual G (--residual true)");
    gate_fit g;
    g.posture.assign(C, 1.0);
    g.motion.assign(C, 1.0);
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
    // [target][posture index][motion index]: sum of RMSE; count per target
    std::vector<std::array<std::array<double, G>, G>> sum(C);
    for (auto& a : sum)
        for (auto& b : a) b.fill(0.0);
    std::vector<std::size_t> count(C, 0);
    std::filesystem::create_directories(work_dir);
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
        if (opt.progress_out)
            std::fprintf(opt.progress_out, "gate %zu/%zu: training G without %s (%zu clips) to choose the change gate\n", f + 1, F,
                         names.c_str(), train.size());
        auto inner = opt;
        inner.gate_folds = 0;
        inner.seed = opt.seed + 7919 * (f + 1);
        inner.checkpoint_every = inner.iters;
        inner.stop_at = -1;
        const auto dir = work_dir / ("inner" + std::to_string(f + 1));
        {
            trainer<Config> tr(info, prepare_data<Config>(train, info, inner), inner);
            tr.run(dir);
        }
        auto [file, ckinfo] = read_checkpoint(dir / "checkpoint.safetensors");
        detail::emotion_model_impl<Config> model(file, ckinfo);
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
                for (std::size_t a = 0; a < G; ++a)
                    for (std::size_t b = 0; b < G; ++b) {
                        model.set_gate(std::vector<double>(C, gate_grid[a]), std::vector<double>(C, gate_grid[b]));
                        sum[t][a][b] += eval::keyframe_rmse(extract_keyframes<K>(model.transfer(in->motion, target).motion), real_kf);
                    }
                ++count[t];
            }
        }
        ++g.folds;
    }
    for (std::size_t t = 0; t < C; ++t) {
        if (count[t] == 0) continue;
        std::size_t ba = 0, bb = 0;
        for (std::size_t a = 0; a < G; ++a)
            for (std::size_t b = 0; b < G; ++b)
                if (sum[t][a][b] < sum[t][ba][bb]) ba = a, bb = b;
        const double n = static_cast<double>(count[t]);
        g.posture[t] = gate_grid[ba];
        g.motion[t] = gate_grid[bb];
        g.rows.push_back({info.domain_names[t], gate_grid[ba], gate_grid[bb], sum[t][ba][bb] / n, sum[t][0][0] / n,
                          sum[t][G - 1][G - 1] / n, count[t]});
        if (opt.progress_out)
            std::fprintf(opt.progress_out,
                         "gate: %-10s posture %.2f motion %.2f (held-out contents: %.3f deg, G's whole change %.3f, no change %.3f; "
                         "%zu pairs)\n",
                         info.domain_names[t].c_str(), g.posture[t], g.motion[t], g.rows.back().rmse_gated, g.rows.back().rmse_full,
                         g.rows.back().rmse_none, count[t]);
    }
    write_file_atomic(work_dir / "gate.csv", g.csv());
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
    if (!g.posture.empty()) data.gate_posture = g.posture, data.gate_motion = g.motion;
    auto tr = std::make_unique<trainer<Config>>(info, std::move(data), opt);
    tr->run(out_dir, resume);
    if (gate_out) *gate_out = std::move(g);
    return tr;
}

}  // namespace handemo::stargan
