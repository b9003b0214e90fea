// StarGAN training for emotion transfer (Section 3.3 of the hand paper, Eq. 4-5; the losses exactly as
// StarGAN trains them, Choi et al. 2018):
//   L_D = -mean D_src(x) + mean D_src(G(x,c)) + lambda_cls CE(D_cls(x), c_org) + lambda_gp GP,
//   GP  = mean_n (||grad_{x_hat} D_src(x_hat)||_2 - 1)^2,  x_hat = a x + (1-a) G(x,c),  a ~ U(0,1) per sample,
//   L_G = -mean D_src(G(x,c)) + lambda_cls CE(D_cls(G(x,c)), c) + lambda_rec mean |x - G(G(x,c), c_org)|,
// G updated every n_critic D steps, Adam (beta1 0.5, beta2 0.999), target labels a shuffle of the batch's
// labels, the learning rate constant and then decaying linearly to 0 over the last part of training.
// Data: K keyframes per clip (uniform in time), Eq. 3 with the training set's p_min/p_max (quantised to
// 8 bits as the paper's BMP images), mapped to [-1, 1] and zero-padded from K x J to the network's H x W
// (bottom and right; G's two stride-2 stages and D's stride-2 convolutions need H, W divisible by 4 and
// zero is the middle of the tanh range, so padding adds no spurious signal). Outputs are cropped back.
// Checkpoints (one safetensors file, atomic, FNV-1a checksum) hold everything needed for a bitwise resume.
#pragma once

#include <handemo/core/error.hpp>
#include <handemo/core/io.hpp>
#include <handemo/core/progress.hpp>
#include <handemo/core/thread_pool.hpp>
#include <handemo/dist/exchange.hpp>
#include <handemo/motion/bvh.hpp>
#include <handemo/motion/codec.hpp>
#include <handemo/motion/detail_layer.hpp>
#include <handemo/motion/keyframes.hpp>
#include <handemo/nn/adam.hpp>
#include <handemo/nn/init.hpp>
#include <handemo/nn/rng.hpp>
#include <handemo/nn/safetensors.hpp>
#include <handemo/stargan/configs.hpp>
#include <handemo/stargan/dataset.hpp>
#include <handemo/stargan/lag.hpp>
#include <handemo/stargan/model.hpp>
#include <handemo/stargan/tempo_neighbours.hpp>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <set>
#include <numeric>
#include <optional>
#include <string>
#include <thread>
#include <tuple>
#include <utility>
#include <vector>

namespace handemo::stargan {

/// @brief The point of each channel the amplitude stage scales excursions about (train_options::amplitude_anchor):
/// the channel's mean over the keyframes, or the mean of its first and last keyframes (the take's ends, where a
/// gesture starts from and returns to its rest pose, so the excursion is the movement away from rest).
enum class amplitude_anchor { mean, ends };

/// @brief "mean" or "ends".
inline const char* anchor_name(amplitude_anchor a) noexcept { return a == amplitude_anchor::ends ? "ends" : "mean"; }

/// @brief How amplitude_factors() measures a pair's amplitude ratio (train_options::amplitude_estimator): `sum`, the
/// ratio of the clips' summed per-channel excursions (keyframe_excursion()); `channel`, per channel that moves in
/// the neutral clip (its excursion at least a tenth of the clip's largest), the ratio of that channel's excursions,
/// so that channels held still, whose excursion is capture noise, tremor or a posture's wobble, do not pull the
/// ratio toward 1.
enum class amplitude_estimator { sum, channel };

/// @brief "sum" or "channel".
inline const char* estimator_name(amplitude_estimator e) noexcept { return e == amplitude_estimator::channel ? "channel" : "sum"; }

/// @brief "sum" or "channel" as an amplitude_estimator.
/// @throws value_error naming `who` for any other text.
inline amplitude_estimator parse_amplitude_estimator(std::string_view s, std::string_view who)
{
    if (s == "sum") return amplitude_estimator::sum;
    if (s == "channel") return amplitude_estimator::channel;
    throw value_error(std::string(who) + ": amplitude estimator '" + std::string(s) + "' is not 'sum' or 'channel'");
}

/// @brief "mean" or "ends" as an amplitude_anchor.
/// @throws value_error naming `who` and the value otherwise.
inline amplitude_anchor parse_amplitude_anchor(std::string_view s, std::string_view who)
{
    if (s == "mean") return amplitude_anchor::mean;
    if (s == "ends") return amplitude_anchor::ends;
    throw value_error(std::string(who) + ": amplitude anchor '" + std::string(s) + "' is not 'mean' or 'ends'");
}

/// @brief Hyper-parameters and run options of training (defaults: the StarGAN paper's).
struct train_options {
    long iters = 4000;          ///< D iterations (G every n_critic of them)
    int n_critic = 5;
    double lambda_cls = 1.0, lambda_rec = 10.0, lambda_gp = 10.0;
    double g_lr = 1e-4, d_lr = 1e-4, beta1 = 0.5, beta2 = 0.999;
    double decay_start = 0.5;   ///< the learning rate decays linearly to 0 over [decay_start * iters, iters]
    std::uint64_t seed = 1;
    unsigned threads = 0;       ///< 0: all cores
    /// data-parallel parts of a batch (trainer::train_step): 2 halves on their own tapes and threads, or 1 (the
    /// whole batch on one tape, its convolutions split over the threads); 0: 1 on one thread, else 2. The
    /// result depends on it (float sums in another order), not on the thread count (autodiff/conv.hpp).
    std::size_t shards = 0;
    long checkpoint_every = 500;
    long log_every = 10;
    long stop_at = -1;          ///< stop (after a checkpoint) at this step, as if interrupted; -1: never
    std::FILE* progress_out = stderr;
    /// data parallelism across processes (dist/exchange.hpp, e.g. dist::mpi_exchange): with 2 processes each
    /// computes the part of the batch its rank numbers (the same halves as shards 2), the parts are shared and
    /// added in part order, so 2 processes train bit for bit what one process with shards 2 trains; only rank 0
    /// writes files. The change gate's inner trainings are shared the same way. nullptr or 1 process: off. Not
    /// stored in checkpoints (a run option, as threads)
    dist::shard_exchange* exchange = nullptr;
    // ---- beyond the paper (all off by default, which is the paper's and StarGAN's setup; see handemo_options())
    bool residual = false;      ///< G outputs x + tanh(last conv), the last conv zero-initialised: G is the identity at init
    double lambda_id = 0.0;     ///< identity loss mean |G(x, c_org) - x| (CycleGAN's)
    double lambda_pair = 0.0;   ///< paired loss mean |G(x, c) - y|, y the same content and take performed in emotion c
    double lambda_delta = 0.0;  ///< size of the change mean |G(x, c) - x|
    /// share of each batch's slots led by a neutral take: the slot's source is a neutral clip drawn at random and its
    /// target a domain drawn uniformly among the others (the mapping a transfer runs); the other slots keep StarGAN's
    /// sampling (a clip in turn from the shuffled data, the target the batch's own labels permuted), which gives a
    /// neutral source to 1 slot in C. round(share x N) slots, spread evenly over the batch; 0: off (StarGAN's
    /// sampling in every slot, the same bits as before the option)
    double neutral_share = 0.0;
    double ema = 0.0;           ///< decay of an exponential moving average of G's weights used for transfer; 0: off
    std::string range = "global";  ///< Eq. 3 range: "global" (the paper's one p_min/p_max) or "channel" (handemo-range/2)
    /// transfer scales the output keyframes' excursions about their per-channel anchor (amplitude_anchor) by
    /// amplitude[target] / amplitude[source], learned from the training pairs as the tempo is (amplitude_factors())
    bool amplitude = false;
    /// the amplitude stage's anchor (amplitude_anchor): "mean" (each channel's mean over the keyframes), "ends" (the
    /// mean of its first and last keyframes: the movement away from the rest pose a take starts and ends in) or "auto"
    /// (the ends when leave-one-content-out on the training clips finds scaling about them closer to the left-out
    /// contents' takes, fit_amplitude()). G trains in the amplitude-normalised space, so it reaches G
    std::string amplitude_anchor = "mean";
    /// how the amplitude factors measure a training pair's ratio (amplitude_estimator): "sum" (the clips' summed
    /// channel excursions) or "channel" (the median of the ratios of the channels that move in the neutral clip).
    /// G trains in the amplitude-normalised space, so it reaches G
    std::string amplitude_estimator = "sum";
    /// per-channel offset jitter: every training image (and its paired target) gets the same random offset per
    /// channel, N(0, augment) in network units, so G's change cannot hinge on the absolute pose; 0: off
    double augment = 0.0;
    /// change gate (gate.hpp): before training, G is trained gate_folds more times, each without one group of
    /// the training contents, and on those held-out contents a blend of G's change is chosen per target
    /// emotion (its keyframe mean, the posture, and the rest, the motion, each x 0, 0.25, ..., 1); transfer
    /// applies it. Leave-content-out inside the training set: the held-out evaluation fold is never seen.
    /// 0: off (G's whole change, as StarGAN); otherwise at least 2.
    int gate_folds = 0;
    /// change gate: also offer the training set's mean posture change per target emotion (the keyframe mean
    /// of mean-offset's difference emotion - neutral, a "posture prior") as a third gated part, 0 .. 1
    bool gate_prior = false;
    /// change gate: G's posture part (its change averaged over the keyframes) is taken about its own average: minus
    /// the mean of that part over the training set's neutral takes transferred to the same target, per target and
    /// channel (posture_centre_of(), stored in the checkpoint as gate.posture_centre). With the posture prior at
    /// full weight, (1, 1, 1) is then the prior plus what G says is particular to the input instead of two estimates
    /// of the emotion's average posture added; (0, 0, 1), the statistics setting, is unchanged. G is the same with or
    /// without it, so a stored model takes it by refit_gate(). No effect without the gate (gate_folds 0)
    bool gate_centre = false;
    /// change gate: keep the posture prior at full weight, choosing only G's (posture, motion) weights (25 settings
    /// instead of 125; gate_settings::prior_full): the statistics setting (0, 0, 1) stays among them. No effect
    /// without gate_prior
    bool gate_prior_full = false;
    /// change gate: the setting chosen per target is the lowest-RMSE one among those whose held-out outputs
    /// the independent emotion classifier (trained on the inner training clips) recognises at a rate no more
    /// than gate_margin below the real held-out clips' rate (a negative margin asks for more than it); when
    /// none does, the most recognised one. <= -1: off (lowest RMSE only, the first gate)
    double gate_margin = -1.0;
    /// change gate: score recognition (for gate_margin) by the classifier's posterior probability of the
    /// target (its linear-discriminant reading, metrics::nearest_centroid_classifier::posterior) averaged over the
    /// held-out pairs, for outputs and real clips alike, instead of the share recognised: a finer estimate on
    /// few pairs (7 per target on Bandai), where the share moves in steps of 14 points
    bool gate_posterior = false;
    /// change gate: choose the margin inside the training set (gate.hpp, gate_margin_candidates()): the gate's
    /// rule is checked across its own groups (choices made on one group's pairs, scored on the other's), and
    /// the least strict margin from gate_margin down whose checked recognition, pooled over the targets, is at
    /// most gate_margin below the real clips' rate is used; when none is, the best checked one. No effect
    /// when the rule is off (gate_margin <= -1)
    bool gate_auto_margin = false;
    /// change gate: keep the statistics setting (the posture prior alone, gate_settings::statistics()) for a target
    /// unless the rule's choices, checked across the gate's own groups, have a keyframe RMSE at least this share
    /// below the statistics setting's on the same pairs and recognition at least as high (gate.hpp). < 0: off
    double gate_guard = -1.0;
    /// change gate: the inner models train for this share of `iters` (at least 1 step). They train on about half
    /// of the training contents, so 0.5 gives them about as many passes over their clips as the final G makes over
    /// its own; 1: as many steps as the final G. The final G is the same whatever the share
    double gate_iters_scale = 1.0;
    /// tempo: shrink the learned duration factors toward 1 in log space by the weight in {0, 0.25, ..., 1} that
    /// predicts left-out training contents' durations best (tempo_fit(..., true), tempo_shrink_fit()); G is the
    /// same with or without it (the images are time-normalised), so a stored model takes it by refit_gate()
    bool tempo_shrink = false;
    /// tempo: what the learned factors are ratios of (tempo_basis): "duration" (the clips' durations), "cadence"
    /// (their cadence_time(): how fast each moves through its own range, whatever the number of cycles it holds) or
    /// "auto" (the cadence when the training pairs' durations and cadences disagree, tempo_basis_check()); like
    /// tempo_shrink it never reaches G, so a stored model takes it by refit_gate()
    std::string tempo_basis = "duration";
    /// tempo: give each input the mean tempo of the K training contents whose neutral clips are most like it
    /// (tempo_neighbours.hpp), K in {3, 2, 1} or the learned factors as they are, whichever leave-one-content-out on
    /// the training clips finds closest to the left-out contents' durations; like tempo_shrink it never reaches G,
    /// so a stored model takes it by refit_gate()
    bool tempo_neighbours = false;
    /// the joint lag (lag.hpp): per target emotion and joint, a time shift of the joint's keyframes learned from the
    /// training pairs, each emotion's kept only when leave-one-content-out on the training clips says it carries
    /// over; applied after G's change and before the amplitude stage. Like the tempo it never reaches G, so a
    /// stored model takes it by refit_gate()
    bool lag = false;

    /// @throws value_error naming the option.
    void validate() const
    {
        auto bad = [](const std::string& what) { throw value_error("train: " + what); };
        if (iters < 1) bad("iters " + std::to_string(iters) + " is below 1");
        if (n_critic < 1) bad("n_critic " + std::to_string(n_critic) + " is below 1");
        for (double v : {lambda_cls, lambda_rec, lambda_gp, g_lr, d_lr, lambda_id, lambda_pair, lambda_delta})
            if (!(v >= 0) || !std::isfinite(v)) bad("a loss weight or learning rate is negative or not finite");
        if (!(beta1 >= 0 && beta1 < 1) || !(beta2 >= 0 && beta2 < 1)) bad("betas must be in [0, 1)");
        if (!(decay_start >= 0 && decay_start <= 1)) bad("decay_start must be in [0, 1]");
        if (checkpoint_every < 1) bad("checkpoint_every is below 1");
        if (log_every < 1) bad("log_every is below 1");
        if (!(augment >= 0 && augment < 1)) bad("augment " + std::to_string(augment) + " is not in [0, 1)");
        if (!(ema >= 0 && ema < 1)) bad("ema decay " + std::to_string(ema) + " is not in [0, 1)");
        if (range != "global" && range != "channel") bad("range '" + range + "' is not 'global' or 'channel'");
        if (gate_folds != 0 && (gate_folds < 2 || gate_folds > 16)) bad("gate_folds " + std::to_string(gate_folds) + " is not 0 or in [2, 16]");
        if (gate_folds != 0 && !residual) bad("gate_folds needs a residual G (the gate blends G's change)");
        if (shards > 2) bad("shards " + std::to_string(shards) + " is not 0, 1 or 2");
        if (!(gate_margin <= 1) || std::isnan(gate_margin)) bad("gate_margin " + std::to_string(gate_margin) + " is not below 1 (a share; <= -1: off)");
        if (!(gate_guard < 1) || std::isnan(gate_guard)) bad("gate_guard " + std::to_string(gate_guard) + " is not below 1 (a share; < 0: off)");
        if (!(neutral_share >= 0 && neutral_share <= 1))
            bad("neutral_share " + std::to_string(neutral_share) + " is not in [0, 1] (a share of the batch)");
        if (!(gate_iters_scale > 0 && gate_iters_scale <= 1))
            bad("gate_iters_scale " + std::to_string(gate_iters_scale) + " is not in (0, 1] (a share of iters)");
        parse_tempo_basis(tempo_basis, "train: tempo_basis");
        if (amplitude_anchor != "auto") parse_amplitude_anchor(amplitude_anchor, "train: amplitude_anchor");
        parse_amplitude_estimator(amplitude_estimator, "train: amplitude_estimator");
    }
    nlohmann::json to_json() const
    {
        nlohmann::json j = {{"iters", iters},       {"n_critic", n_critic}, {"lambda_cls", lambda_cls}, {"lambda_rec", lambda_rec},
                {"lambda_gp", lambda_gp}, {"g_lr", g_lr},        {"d_lr", d_lr},             {"beta1", beta1},
                {"beta2", beta2},       {"decay_start", decay_start}, {"seed", seed},
                {"residual", residual}, {"lambda_id", lambda_id}, {"lambda_pair", lambda_pair},
                {"lambda_delta", lambda_delta}, {"ema", ema}, {"range", range}, {"amplitude", amplitude},
                {"augment", augment}, {"gate_folds", gate_folds}, {"gate_prior", gate_prior}, {"gate_margin", gate_margin}};
        if (gate_posterior) j["gate_posterior"] = true;
        if (gate_auto_margin) j["gate_auto_margin"] = true;  // written only when on: older checkpoints' options stay equal
        if (gate_guard >= 0) j["gate_guard"] = gate_guard;
        if (gate_centre) j["gate_centre"] = true;  // written only when on: older checkpoints' options stay equal
        if (gate_prior_full) j["gate_prior_full"] = true;
        if (gate_iters_scale != 1.0) j["gate_iters_scale"] = gate_iters_scale;  // written only when not 1
        if (tempo_shrink) j["tempo_shrink"] = true;
        if (tempo_basis != "duration") j["tempo_basis"] = tempo_basis;  // written only when not the duration
        if (tempo_neighbours) j["tempo_neighbours"] = true;
        if (lag) j["lag"] = true;
        if (amplitude_anchor != "mean") j["amplitude_anchor"] = amplitude_anchor;  // written only when not the mean
        if (amplitude_estimator != "sum") j["amplitude_estimator"] = amplitude_estimator;  // written only when not the sum
        if (neutral_share > 0) j["neutral_share"] = neutral_share;  // written only when on
        return j;
    }
};

/// @brief Whether this process writes the training's files: always, unless it is one of several processes of
/// train_options::exchange and not rank 0.
inline bool writes_files(const train_options& o) noexcept { return !o.exchange || o.exchange->writes_files(); }

/// @brief How many of a batch's n slots train_options::neutral_share leads by a neutral take: round(share x n).
inline std::size_t neutral_led_slots(double share, std::size_t n) noexcept
{
    return std::min(n, static_cast<std::size_t>(std::llround(share * static_cast<double>(n))));
}

/// @brief Whether slot `slot` of a batch of n is one of its `led` neutral-led slots: the slots where floor(slot x
/// led / n) steps up, so they spread evenly (led = n / 2: every second slot, each half of the batch the same count).
inline bool neutral_led(std::size_t slot, std::size_t led, std::size_t n) noexcept
{
    return led > 0 && (slot + 1) * led / n != slot * led / n;
}

/// @brief StarGAN exactly as the paper and the reference train it (Eq. 3's one range, G = tanh(...), the
/// three losses of Eq. 4-5 with StarGAN's weights).
inline train_options paper_options() { return train_options{}; }

/// @brief handemo's default training: what makes the transfer beat the baselines on unseen motions (the
/// evaluation's ablation in the README measures each piece). A residual G that starts as the identity and
/// adds a bounded change; an identity loss; a paired loss to the same take performed in the target emotion
/// (the data sets are recorded in pairs: every content in every emotion); an EMA of G's weights for
/// transfer (StarGAN v2); per-channel ranges wrapped against a reference angle; the learned amplitude
/// factors, about the take's ends where the training set says so (amplitude_anchor "auto"); a change gate with
/// the posture prior kept whole and G's posture about its own average (gate_centre, gate_prior_full); lambda_cls 5 (with 1, D's domain classifier stays at chance on the synthetic training set: the
/// gradient penalty dominates); n_critic 1 and 2000 iterations (G gets 2000 updates, not 400: with
/// n_critic 5 G did not fit its training contents better than identity). Chosen from training-set numbers
/// only: the seen-content diagnostic and an inner validation content inside the demo fold's training set
/// (README, "How the defaults were chosen").
inline train_options handemo_options()
{
    train_options o;
    o.residual = true;
    o.lambda_cls = 5.0;
    o.lambda_id = 10.0;
    o.lambda_pair = 10.0;
    o.lambda_delta = 5.0;
    o.ema = 0.999;
    o.range = "channel";
    o.amplitude = true;
    o.amplitude_anchor = "auto";
    o.augment = 0.1;
    o.n_critic = 1;
    o.iters = 2000;
    o.gate_folds = 2;
    o.gate_prior = true;
    o.gate_margin = 0.10;
    o.gate_auto_margin = true;
    o.gate_posterior = true;
    o.gate_guard = 0.02;
    o.gate_centre = true;
    o.gate_prior_full = true;
    return o;
}

/// @brief A named preset: "paper" (paper_options()) or "handemo" (handemo_options()).
/// @throws value_error naming the unknown preset.
inline train_options preset_options(std::string_view name)
{
    if (name == "paper") return paper_options();
    if (name == "handemo") return handemo_options();
    throw value_error("train: unknown preset '" + std::string(name) + "', expected 'paper' or 'handemo'");
}

/// Columns of the loss log (log.csv): D terms as in L_D, G terms as in L_G, the learning rate, and the
/// accuracy of D's domain classifier on the real batch.
inline const std::vector<std::string>& loss_columns()
{
    static const std::vector<std::string> c{"D/real", "D/fake", "D/cls", "D/gp",   "D/total", "D/acc", "G/fake",
                                            "G/cls",  "G/rec",  "G/total", "lr",   "G/id",    "G/pair", "G/delta"};
    return c;
}

/// @brief A training set in network form.
struct prepared_data {
    std::size_t H = 0, W = 0, K = 0, J = 0;
    std::vector<float> images;             ///< [M, 3, H, W] in [-1, 1], zero padded
    std::vector<int> labels;               ///< [M] domain index
    std::vector<std::string> contents;     ///< [M] content (motion type) names
    std::vector<std::string> sources;      ///< [M] file names, for messages
    angle_range range;                     ///< p_min/p_max of Eq. 3
    std::vector<double> tempo;             ///< [C] tempo factor per domain
    tempo_neighbours tempo_table;          ///< the tempo neighbours (train_options::tempo_neighbours); empty without
    std::vector<double> amplitude;         ///< [C] amplitude factor per domain (amplitude_factors())
    /// amplitude_cv() on the training clips: mean RMSE without / with the factors; when scaling does not
    /// beat identity there, `amplitude` is set to all 1 (the data set carries no usable amplitude style)
    std::pair<double, double> amplitude_check{std::nan(""), std::nan("")};
    /// what the amplitude stage scales about (train_options::amplitude_anchor as fit_amplitude() resolved it)
    handemo::stargan::amplitude_anchor amplitude_anchor = handemo::stargan::amplitude_anchor::mean;
    /// with the anchor "auto": amplitude_prior_cv()'s RMSE about the mean and about the ends (NaN otherwise)
    std::pair<double, double> amplitude_anchor_check{std::nan(""), std::nan("")};
    /// the joint lag and its check (train_options::lag; lag.hpp); empty lags without the option
    joint_lag_fit lag;
    std::vector<std::string> joint_names;  ///< skeleton the model is trained for
    skeleton skel;                         ///< that skeleton (the first training clip's: hierarchy, offsets, channels)
    /// [M, C] for every image and domain, the index of the same content and take performed in that domain
    /// (another take of the content when that take is missing; the image itself for its own domain); -1: none
    std::vector<int> partner;
    /// [3, H, W] weight of each pixel in the paired loss: the channel's degrees per network unit over their
    /// mean (1 for a global range), so the loss counts degrees as the evaluation does; 0 in the padding
    std::vector<float> pair_weight;
    std::size_t domains = 0;               ///< C
    int neutral = -1;                      ///< the neutral domain's index (config_info::neutral); -1: none
    /// [C] change gate per target domain (fit_change_gate()): the weight of G's change averaged over the
    /// keyframes (posture) and of the rest (motion); empty: 1 (G's whole change)
    std::vector<double> gate_posture, gate_motion;
    /// [C] weight of the posture prior per target (train_options::gate_prior); empty: 0
    std::vector<double> gate_prior;
    /// [C][J*3] the posture prior: the training pairs' mean keyframe-mean change (deg) per target and channel
    std::vector<std::vector<double>> prior_posture;
    /// [C][J*3] G's average posture per target (train_options::gate_centre): set after G's last step
    /// (train_model()), so empty while G trains; written to the checkpoint when set
    std::vector<std::vector<double>> posture_centre;
    /// the detail layer's per-emotion statistics of the training clips (motion/detail_layer.hpp)
    std::optional<detail_layer> detail;
    std::size_t size() const noexcept { return labels.size(); }
};

/// @brief The anchor of channel `ch` of `kf` (see amplitude_anchor).
template <std::size_t K>
double excursion_anchor(const keyframes<K>& kf, std::size_t ch, amplitude_anchor a) noexcept
{
    const std::size_t C = kf.joints * 3, n = kf.count();
    if (a == amplitude_anchor::ends) return 0.5 * (kf.angles[ch] + kf.angles[(n - 1) * C + ch]);
    double m = 0;
    for (std::size_t i = 0; i < n; ++i) m += kf.angles[i * C + ch];
    return m / static_cast<double>(n);
}

/// @brief Scales every channel's excursion about its anchor (its mean over the keyframes by default) by `f`
/// (in place). Scaling about the ends keeps the ends' mean, so dividing by f undoes it exactly as about the mean.
template <std::size_t K>
void scale_keyframe_excursions(keyframes<K>& kf, double f, amplitude_anchor a = amplitude_anchor::mean) noexcept
{
    if (f == 1.0) return;
    const std::size_t C = kf.joints * 3, n = kf.count();
    for (std::size_t ch = 0; ch < C; ++ch) {
        const double m = excursion_anchor(kf, ch, a);
        for (std::size_t i = 0; i < n; ++i) kf.angles[i * C + ch] = m + f * (kf.angles[i * C + ch] - m);
    }
}

/// @brief Each channel's root mean square distance from its anchor over the keyframes ([J*3]; about the mean: its
/// standard deviation).
template <std::size_t K>
std::vector<double> channel_excursions(const keyframes<K>& kf, amplitude_anchor a = amplitude_anchor::mean)
{
    const std::size_t C = kf.joints * 3, n = kf.count();
    std::vector<double> out(C);
    for (std::size_t ch = 0; ch < C; ++ch) {
        const double m = excursion_anchor(kf, ch, a);
        double q = 0;
        for (std::size_t i = 0; i < n; ++i) q += (kf.angles[i * C + ch] - m) * (kf.angles[i * C + ch] - m);
        out[ch] = std::sqrt(q / static_cast<double>(n));
    }
    return out;
}

/// @brief Excursion of keyframes: the sum over channels of channel_excursions(), in channel order.
template <std::size_t K>
double keyframe_excursion(const keyframes<K>& kf, amplitude_anchor a = amplitude_anchor::mean)
{
    double total = 0;
    for (double e : channel_excursions(kf, a)) total += e;
    return total;
}

/// @brief amplitude_estimator::channel's threshold: a channel counts as moving in a neutral clip when its excursion
/// is at least this share of the clip's largest channel excursion.
inline constexpr double amplitude_moving_share = 0.1;

namespace detail {

/// The training pairs of the amplitude stage: for every clip of a domain other than `neutral`, the neutral clip of
/// the same content and take (the last one, should a take name repeat), else the content's first neutral clip
/// (-1: none).
inline std::vector<int> amplitude_partners(const std::vector<labelled_clip>& clips, const std::string& neutral)
{
    std::map<std::pair<std::string, std::string>, int> by_take;
    std::map<std::string, int> first;
    for (std::size_t m = 0; m < clips.size(); ++m)
        if (clips[m].emotion == neutral) {
            by_take[{clips[m].content, clips[m].take}] = static_cast<int>(m);
            first.try_emplace(clips[m].content, static_cast<int>(m));
        }
    std::vector<int> out(clips.size(), -1);
    for (std::size_t m = 0; m < clips.size(); ++m) {
        if (clips[m].emotion == neutral) continue;
        if (auto it = by_take.find({clips[m].content, clips[m].take}); it != by_take.end())
            out[m] = it->second;
        else if (auto f = first.find(clips[m].content); f != first.end())
            out[m] = f->second;
    }
    return out;
}

}  // namespace detail

/// @brief Amplitude factor per domain, relative to `neutral` (Table 1's "amplitude", learned as the tempo is):
/// the median over training pairs (a clip of the domain, the neutral clip of the same content and take, or
/// the content's first neutral take) of the ratio of their keyframe excursions about `anchor`. 1 for the neutral
/// domain and for a domain without pairs.
template <std::size_t K>
std::vector<double> amplitude_factors(const std::vector<labelled_clip>& clips, const std::vector<keyframes<K>>& kfs,
                                      const std::vector<std::string>& domains, const std::string& neutral,
                                      amplitude_anchor anchor = amplitude_anchor::mean,
                                      amplitude_estimator estimator = amplitude_estimator::sum)
{
    const auto partner = detail::amplitude_partners(clips, neutral);
    std::vector<double> excursion(clips.size());
    std::vector<std::vector<double>> channel(estimator == amplitude_estimator::channel ? clips.size() : 0);
    for (std::size_t m = 0; m < clips.size(); ++m) {
        if (estimator == amplitude_estimator::channel)
            channel[m] = channel_excursions(kfs[m], anchor);
        else
            excursion[m] = keyframe_excursion(kfs[m], anchor);
    }
    std::vector<double> out(domains.size(), 1.0);
    for (std::size_t d = 0; d < domains.size(); ++d) {
        if (domains[d] == neutral) continue;
        std::vector<double> r;
        for (std::size_t m = 0; m < clips.size(); ++m) {
            if (clips[m].emotion != domains[d] || partner[m] < 0) continue;
            if (estimator == amplitude_estimator::channel) {
                const auto& base = channel[static_cast<std::size_t>(partner[m])];
                const auto& e = channel[m];
                const double largest = base.empty() ? 0.0 : *std::max_element(base.begin(), base.end());
                for (std::size_t ch = 0; ch < base.size() && ch < e.size(); ++ch)
                    if (base[ch] > 1e-9 && base[ch] >= amplitude_moving_share * largest && std::isfinite(e[ch])) r.push_back(e[ch] / base[ch]);
                continue;
            }
            const double base = excursion[static_cast<std::size_t>(partner[m])];
            const double e = excursion[m];
            if (base > 1e-9 && std::isfinite(e)) r.push_back(e / base);
        }
        if (r.empty()) continue;
        std::sort(r.begin(), r.end());
        out[d] = r.size() % 2 ? r[r.size() / 2] : 0.5 * (r[r.size() / 2 - 1] + r[r.size() / 2]);
    }
    return out;
}

/// @brief What scaling about the ends moves the keyframe mean by, per domain and channel, on the training pairs:
/// [C][J*3], for domain d the mean over its pairs (amplitude_factors()' pairs) of (f_d - 1) x (the neutral clip's
/// keyframe mean - its ends' mean). Scaling about the mean leaves the mean alone (all zeros). The posture prior
/// subtracts it (posture_prior()), so that the prior and the scaling together move the mean by the training
/// pairs' mean change, as the prior alone does about the mean.
template <std::size_t K>
std::vector<std::vector<double>> anchor_mean_shift(const std::vector<labelled_clip>& clips, const std::vector<keyframes<K>>& kfs,
                                                   const std::vector<std::string>& domains, const std::string& neutral,
                                                   const std::vector<double>& factors, amplitude_anchor anchor)
{
    const std::size_t C = kfs.empty() ? 0 : kfs.front().joints * 3;
    std::vector<std::vector<double>> out(domains.size(), std::vector<double>(C, 0.0));
    if (anchor == amplitude_anchor::mean) return out;
    const auto partner = detail::amplitude_partners(clips, neutral);
    for (std::size_t d = 0; d < domains.size(); ++d) {
        if (domains[d] == neutral || factors[d] == 1.0) continue;
        std::size_t n = 0;
        for (std::size_t m = 0; m < clips.size(); ++m) {
            if (clips[m].emotion != domains[d] || partner[m] < 0) continue;
            const auto& base = kfs[static_cast<std::size_t>(partner[m])];
            for (std::size_t ch = 0; ch < C; ++ch)
                out[d][ch] += excursion_anchor(base, ch, amplitude_anchor::mean) - excursion_anchor(base, ch, anchor);
            ++n;
        }
        if (n)
            for (auto& v : out[d]) v *= (factors[d] - 1.0) / static_cast<double>(n);
    }
    return out;
}

namespace detail {

/// Keyframe RMSE in wrapped degrees.
template <std::size_t K>
double amplitude_rmse(const keyframes<K>& a, const keyframes<K>& b)
{
    double q = 0;
    for (std::size_t i = 0; i < a.angles.size(); ++i) q += std::pow(wrap_angle_deg(a.angles[i] - b.angles[i]), 2);
    return std::sqrt(q / static_cast<double>(a.angles.size()));
}

/// Leave-one-content-out over `clips` (their contents in order of first appearance): f(held, the other contents'
/// clips, their keyframes) for each content. False, calling nothing, when there are fewer than two contents.
template <std::size_t K, class F>
bool for_each_left_out_content(const std::vector<labelled_clip>& clips, const std::vector<keyframes<K>>& kfs, F&& f)
{
    std::vector<std::string> contents;
    for (const auto& c : clips)
        if (std::find(contents.begin(), contents.end(), c.content) == contents.end()) contents.push_back(c.content);
    if (contents.size() < 2) return false;
    for (const auto& held : contents) {
        std::vector<labelled_clip> other_c;
        std::vector<keyframes<K>> other_k;
        for (std::size_t m = 0; m < clips.size(); ++m)
            if (clips[m].content != held) other_c.push_back(clips[m]), other_k.push_back(kfs[m]);
        f(held, other_c, other_k);
    }
    return true;
}

}  // namespace detail

/// @brief Leave-one-content-out check of the amplitude factors on training clips: for each content, the
/// factors fitted on the other contents scale that content's neutral keyframes toward each of its emotional
/// takes. Returns the mean keyframe RMSE (wrapped degrees) over those pairs without scaling (identity) and
/// with it; NaN when there are fewer than two contents or no pairs.
template <std::size_t K>
std::pair<double, double> amplitude_cv(const std::vector<labelled_clip>& clips, const std::vector<keyframes<K>>& kfs,
                                       const std::vector<std::string>& domains, const std::string& neutral,
                                       amplitude_estimator estimator = amplitude_estimator::sum)
{
    const auto partner = detail::amplitude_partners(clips, neutral);
    double s_id = 0, s_amp = 0;
    std::size_t n = 0;
    const bool split = detail::for_each_left_out_content<K>(clips, kfs, [&](const std::string& held, const auto& other_c, const auto& other_k) {
        const auto f = amplitude_factors<K>(other_c, other_k, domains, neutral, amplitude_anchor::mean, estimator);
        for (std::size_t m = 0; m < clips.size(); ++m) {
            if (clips[m].content != held || partner[m] < 0) continue;
            const auto& base = kfs[static_cast<std::size_t>(partner[m])];
            const auto d = static_cast<std::size_t>(std::find(domains.begin(), domains.end(), clips[m].emotion) - domains.begin());
            if (d >= domains.size()) continue;
            auto scaled = base;
            scale_keyframe_excursions(scaled, f[d]);
            s_id += detail::amplitude_rmse(base, kfs[m]);
            s_amp += detail::amplitude_rmse(scaled, kfs[m]);
            ++n;
        }
    });
    if (!split || !n) return {std::nan(""), std::nan("")};
    return {s_id / static_cast<double>(n), s_amp / static_cast<double>(n)};
}

/// @brief Leave-one-content-out check of the amplitude stage with the posture prior, as the statistics transfer
/// combines them, about `anchor`: for each content, the factors, the prior (the pairs' mean keyframe-mean change) and
/// the anchor's mean shift (anchor_mean_shift()) fitted on the other contents; each of the content's emotional takes
/// against its neutral take (amplitude_factors()' pairs) with the prior (first) and with the prior corrected by the
/// shift, then scaled about the anchor (second). Mean keyframe RMSE (wrapped degrees) over those pairs; NaN when there
/// are fewer than two contents or no pairs.
template <std::size_t K>
std::pair<double, double> amplitude_prior_cv(const std::vector<labelled_clip>& clips, const std::vector<keyframes<K>>& kfs,
                                             const std::vector<std::string>& domains, const std::string& neutral, amplitude_anchor anchor,
                                             amplitude_estimator estimator = amplitude_estimator::sum)
{
    if (kfs.empty()) return {std::nan(""), std::nan("")};
    const std::size_t C = kfs.front().joints * 3;
    const auto partner = detail::amplitude_partners(clips, neutral);
    const auto domain_of = [&](const labelled_clip& c) {
        return static_cast<std::size_t>(std::find(domains.begin(), domains.end(), c.emotion) - domains.begin());
    };
    double s_id = 0, s_amp = 0;
    std::size_t n = 0;
    const bool split = detail::for_each_left_out_content<K>(clips, kfs, [&](const std::string& held, const auto& other_c, const auto& other_k) {
        const auto f = amplitude_factors<K>(other_c, other_k, domains, neutral, anchor, estimator);
        const auto shift = anchor_mean_shift<K>(other_c, other_k, domains, neutral, f, anchor);
        // the prior on the other contents: the pairs' mean keyframe-mean change per domain and channel
        std::vector<std::vector<double>> prior(domains.size(), std::vector<double>(C, 0.0));
        std::vector<std::size_t> count(domains.size(), 0);
        const auto other_partner = detail::amplitude_partners(other_c, neutral);
        for (std::size_t m = 0; m < other_c.size(); ++m) {
            const std::size_t d = domain_of(other_c[m]);
            if (other_partner[m] < 0 || d >= domains.size()) continue;
            const auto& base = other_k[static_cast<std::size_t>(other_partner[m])];
            for (std::size_t ch = 0; ch < C; ++ch)
                prior[d][ch] += excursion_anchor(other_k[m], ch, amplitude_anchor::mean) - excursion_anchor(base, ch, amplitude_anchor::mean);
            ++count[d];
        }
        for (std::size_t d = 0; d < domains.size(); ++d)
            if (count[d])
                for (auto& v : prior[d]) v /= static_cast<double>(count[d]);
        for (std::size_t m = 0; m < clips.size(); ++m) {
            const std::size_t d = domain_of(clips[m]);
            if (clips[m].content != held || partner[m] < 0 || d >= domains.size()) continue;
            const auto& base = kfs[static_cast<std::size_t>(partner[m])];
            auto plain = base, scaled = base;
            for (std::size_t i = 0; i < base.angles.size(); ++i) {
                plain.angles[i] += prior[d][i % C];
                scaled.angles[i] += prior[d][i % C] - shift[d][i % C];
            }
            scale_keyframe_excursions(scaled, f[d], anchor);
            s_id += detail::amplitude_rmse(plain, kfs[m]);
            s_amp += detail::amplitude_rmse(scaled, kfs[m]);
            ++n;
        }
    });
    if (!split || !n) return {std::nan(""), std::nan("")};
    return {s_id / static_cast<double>(n), s_amp / static_cast<double>(n)};
}

/// @brief The amplitude stage's factors, the anchor they scale about and their checks (checked_amplitude_factors()).
struct amplitude_fit {
    std::vector<double> factors;  ///< [C]; all 1 when the check finds that scaling does not beat identity
    amplitude_anchor anchor = amplitude_anchor::mean;
    /// the check that kept or dropped the factors: mean RMSE without / with them (amplitude_cv() about the mean,
    /// amplitude_prior_cv() about the ends)
    std::pair<double, double> check{std::nan(""), std::nan("")};
    /// with the anchor "auto": amplitude_prior_cv()'s RMSE with scaling about the mean and about the ends, which
    /// chose the anchor (NaN otherwise)
    std::pair<double, double> anchor_check{std::nan(""), std::nan("")};
};

/// @brief The amplitude factors the amplitude stage uses, about the anchor `anchor` names ("mean", "ends" or "auto":
/// the ends when amplitude_prior_cv() finds scaling about them, with the prior, closer to the left-out contents'
/// takes than scaling about the mean, the mean otherwise, a tie included). About the mean the factors are kept when
/// amplitude_cv() finds that scaling beats identity; about the ends when amplitude_prior_cv() finds that the prior
/// with scaling beats the prior alone. Otherwise all 1.
/// @throws value_error for an anchor name other than mean, ends or auto.
template <std::size_t K>
amplitude_fit fit_amplitude(const std::vector<labelled_clip>& clips, const std::vector<keyframes<K>>& kfs,
                            const std::vector<std::string>& domains, const std::string& neutral, std::string_view anchor = "mean",
                            amplitude_estimator estimator = amplitude_estimator::sum)
{
    amplitude_fit r;
    std::optional<std::pair<double, double>> about_ends;  // amplitude_prior_cv() about the ends, once computed
    if (anchor == "auto") {
        const auto about_mean = amplitude_prior_cv<K>(clips, kfs, domains, neutral, amplitude_anchor::mean, estimator);
        about_ends = amplitude_prior_cv<K>(clips, kfs, domains, neutral, amplitude_anchor::ends, estimator);
        r.anchor_check = {about_mean.second, about_ends->second};
        r.anchor = about_ends->second < about_mean.second ? amplitude_anchor::ends : amplitude_anchor::mean;
    } else {
        r.anchor = parse_amplitude_anchor(anchor, "train: amplitude_anchor");
    }
    r.factors = amplitude_factors<K>(clips, kfs, domains, neutral, r.anchor, estimator);
    if (r.anchor == amplitude_anchor::mean)
        r.check = amplitude_cv<K>(clips, kfs, domains, neutral, estimator);
    else
        r.check = about_ends ? *about_ends : amplitude_prior_cv<K>(clips, kfs, domains, neutral, r.anchor, estimator);
    if (!(r.check.second < r.check.first)) r.factors.assign(r.factors.size(), 1.0);
    return r;
}

/// @brief The amplitude factors the amplitude stage uses and their check: amplitude_factors(), all 1 when
/// amplitude_cv() finds that scaling does not beat identity on the training clips (first: the check). About the mean.
template <std::size_t K>
std::pair<std::pair<double, double>, std::vector<double>> checked_amplitude_factors(const std::vector<labelled_clip>& clips,
                                                                                   const std::vector<keyframes<K>>& kfs,
                                                                                   const std::vector<std::string>& domains,
                                                                                   const std::string& neutral)
{
    auto r = fit_amplitude<K>(clips, kfs, domains, neutral, "mean");
    return {r.check, std::move(r.factors)};
}

/// @brief Pads a [3, K, J] network image into [3, H, W] (zeros bottom/right).
inline void pad_image(const float* src, std::size_t K, std::size_t J, float* dst, std::size_t H, std::size_t W) noexcept
{
    for (std::size_t c = 0; c < 3; ++c)
        for (std::size_t i = 0; i < H; ++i)
            for (std::size_t j = 0; j < W; ++j)
                dst[(c * H + i) * W + j] = (i < K && j < J) ? src[(c * K + i) * J + j] : 0.0f;
}

/// @brief Crops a [3, H, W] network image back to [3, K, J].
inline void crop_image(const float* src, std::size_t H, std::size_t W, float* dst, std::size_t K, std::size_t J) noexcept
{
    for (std::size_t c = 0; c < 3; ++c)
        for (std::size_t i = 0; i < K; ++i)
            for (std::size_t j = 0; j < J; ++j) dst[(c * K + i) * J + j] = src[(c * H + i) * W + j];
}

/// @brief Keyframes, Eq. 3 images, labels and tempo factors of a labelled dataset for a configuration.
/// @param range the Eq. 3 range to use (a resumed run keeps its own); default: computed over `clips`.
/// @param range_mode "global" (the paper's one p_min/p_max) or "channel" (compute_channel_range()), when
///        `range` is not given.
/// @param tempo_shrink the tempo factors shrunk by the checked weight (train_options::tempo_shrink)
/// @param basis what the tempo factors are ratios of (train_options::tempo_basis)
/// @param lag fit the joint lag (train_options::lag, joint_lags_checked())
/// @param amplitude_normalise train in the amplitude-normalised space of the amplitude stage
///        (train_options::amplitude): every image's excursions about its per-channel keyframe mean are divided
///        by its emotion's amplitude factor, so G learns what the emotions change besides amplitude and
///        transfer scales G's output by the target's factor (inputs by 1/the source's); no-op when the
///        factors are 1 (amplitude_cv() found none worth using).
/// @throws shape_error when the clips' joint count is not the configuration's; value_error for an
///         emotion the configuration does not know (naming the file).
template <stargan_config Config>
prepared_data prepare_data(const std::vector<labelled_clip>& clips, const config_info& info,
                           std::optional<angle_range> range = {}, std::string_view range_mode = "global",
                           bool amplitude_normalise = false, bool tempo_shrink = false,
                           tempo_basis basis = tempo_basis::duration, bool lag = false, std::string_view anchor = "mean",
                           amplitude_estimator estimator = amplitude_estimator::sum)
{
    constexpr std::size_t K = Config::keyframes, J = Config::joints, H = dims<Config>::H, W = dims<Config>::W;
    if (clips.empty()) throw value_error("train: no clips to train on");
    prepared_data p;
    p.H = H, p.W = W, p.K = K, p.J = J;
    std::vector<keyframes<K>> kfs;
    for (const auto& c : clips) {
        if (c.motion.skel.size() != J)
            throw shape_error("train: " + c.path.string() + " has " + std::to_string(c.motion.skel.size()) +
                              " joints, configuration " + info.name + " expects " + std::to_string(J) +
                              " (wrong skeleton for this configuration)");
        p.labels.push_back(static_cast<int>(domain_index(info, c.emotion)));
        p.contents.push_back(c.content);
        p.sources.push_back(c.path.filename().string());
        kfs.push_back(extract_keyframes<K>(c.motion));
    }
    for (const auto& j : clips.front().motion.skel.joints) p.joint_names.push_back(j.name);
    p.skel = clips.front().motion.skel;
    for (std::size_t d = 0; d < info.domain_names.size(); ++d)
        if (info.domain_names[d] == info.neutral) p.neutral = static_cast<int>(d);
    if (range_mode != "global" && range_mode != "channel")
        throw value_error("train: range '" + std::string(range_mode) + "' is not 'global' or 'channel'");
    p.range = range ? *range : range_mode == "channel" ? compute_channel_range(kfs) : compute_range(kfs);
    p.range.keyframes = K;
    p.range.joints = J;
    p.range.validate("train: range");
    p.domains = info.domains;
    {
        double mean_half = 0;
        for (std::size_t ch = 0; ch < J * 3; ++ch) mean_half += p.range.half_span(ch) / static_cast<double>(J * 3);
        p.pair_weight.assign(3 * H * W, 0.f);
        for (std::size_t c = 0; c < 3; ++c)
            for (std::size_t i = 0; i < K; ++i)
                for (std::size_t j = 0; j < J; ++j)
                    p.pair_weight[(c * H + i) * W + j] = static_cast<float>(p.range.half_span(j * 3 + c) / mean_half);
    }
    p.partner.assign(clips.size() * info.domains, -1);
    for (std::size_t m = 0; m < clips.size(); ++m) {
        // preference: the image itself, then the same take, then the first other take of the content
        const auto rank = [&](int i) {
            if (i < 0) return 0;
            const auto u = static_cast<std::size_t>(i);
            return u == m ? 3 : clips[u].take == clips[m].take ? 2 : 1;
        };
        for (std::size_t q = 0; q < clips.size(); ++q) {
            if (clips[q].content != clips[m].content) continue;
            int& slot = p.partner[m * info.domains + static_cast<std::size_t>(p.labels[q])];
            if (rank(static_cast<int>(q)) > rank(slot)) slot = static_cast<int>(q);
        }
    }
    p.tempo = tempo_factors(clips, info.domain_names, info.neutral, tempo_shrink, basis);
    {
        auto amp = fit_amplitude<K>(clips, kfs, info.domain_names, info.neutral, anchor, estimator);
        p.amplitude = std::move(amp.factors);
        p.amplitude_check = amp.check;
        p.amplitude_anchor = amp.anchor;
        p.amplitude_anchor_check = amp.anchor_check;
    }
    {
        std::vector<detail_layer::sample> d;
        for (const auto& c : clips) d.push_back({&c.motion, c.emotion, c.content, c.take});
        p.detail = detail_layer::fit_checked(d, info.neutral, K);
    }
    if (lag) p.lag = joint_lags_checked<K>(clips, kfs, info.domain_names, info.neutral, amplitude_normalise ? p.amplitude : std::vector<double>(p.amplitude.size(), 1.0));
    p.images.resize(clips.size() * 3 * H * W);
    for (std::size_t m = 0; m < clips.size(); ++m) {
        auto kf = kfs[m];
        if (amplitude_normalise) scale_keyframe_excursions(kf, 1.0 / p.amplitude[static_cast<std::size_t>(p.labels[m])], p.amplitude_anchor);
        const auto net = to_network(encode(kf, p.range));
        pad_image(net.data.data(), K, J, p.images.data() + m * 3 * H * W, H, W);
    }
    return p;
}

/// @brief The tempo neighbours training stores for `opt` (tempo_neighbours_fit() on `clips`): empty when
/// opt.tempo_neighbours is off or the check keeps the learned factors. refit_gate() and the change gate take it this way.
inline tempo_neighbours tempo_table_of(const std::vector<labelled_clip>& clips, const config_info& info, const train_options& opt)
{
    if (!opt.tempo_neighbours) return {};
    return tempo_neighbours_fit(clips, info.domain_names, info.neutral, opt.tempo_shrink, parse_tempo_basis(opt.tempo_basis, "train: tempo_basis"));
}

/// @brief prepare_data() with the range mode, amplitude normalisation, tempo (shrinking, basis, neighbours) and joint
/// lag of `opt`.
template <stargan_config Config>
prepared_data prepare_data(const std::vector<labelled_clip>& clips, const config_info& info, const train_options& opt,
                           std::optional<angle_range> range = {})
{
    auto p = prepare_data<Config>(clips, info, std::move(range), opt.range, opt.amplitude, opt.tempo_shrink,
                                  parse_tempo_basis(opt.tempo_basis, "train: tempo_basis"), opt.lag, opt.amplitude_anchor,
                                  parse_amplitude_estimator(opt.amplitude_estimator, "train: amplitude_estimator"));
    p.tempo_table = tempo_table_of(clips, info, opt);
    return p;
}

/// @brief The joint lag prepare_data() fits for `opt` ([C][J], keyframe intervals), without the rest of the data:
/// empty when opt.lag is off. refit_gate() and the change gate's reused inner models take it this way.
template <stargan_config Config>
std::vector<std::vector<double>> joint_lag_of(const std::vector<labelled_clip>& clips, const config_info& info, const train_options& opt)
{
    if (!opt.lag) return {};
    constexpr std::size_t K = Config::keyframes;
    std::vector<keyframes<K>> kfs;
    for (const auto& c : clips) kfs.push_back(extract_keyframes<K>(c.motion));
    const auto amp = opt.amplitude ? fit_amplitude<K>(clips, kfs, info.domain_names, info.neutral, opt.amplitude_anchor,
                                                      parse_amplitude_estimator(opt.amplitude_estimator, "train: amplitude_estimator"))
                                         .factors
                                   : std::vector<double>(info.domain_names.size(), 1.0);
    return joint_lags_checked<K>(clips, kfs, info.domain_names, info.neutral, amp).lag;
}

namespace detail {

/// FNV-1a 64 over bytes.
inline std::uint64_t fnv1a(std::string_view s, std::uint64_t h = 14695981039346656037ULL) noexcept
{
    for (unsigned char ch : s) h = (h ^ ch) * 1099511628211ULL;
    return h;
}

/// Checksum of a checkpoint: every tensor's name, dtype, shape and bytes, and every metadata entry but
/// the checksum itself.
inline std::string checkpoint_checksum(const safetensors_file& f)
{
    std::uint64_t h = 14695981039346656037ULL;
    for (const auto& t : f.tensors) {
        h = fnv1a(t.name, h);
        h = fnv1a(st_dtype_name(t.dtype), h);
        for (auto d : t.shape) h = fnv1a(std::to_string(d) + ",", h);
        h = fnv1a(t.data, h);
    }
    for (const auto& [k, v] : f.metadata)
        if (k != "checksum") h = fnv1a(k + "=" + v + ";", h);
    char buf[24];
    std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(h));
    return buf;
}

inline std::vector<double> json_doubles(const nlohmann::json& j)
{
    std::vector<double> v;
    for (const auto& x : j) v.push_back(x.get<double>());
    return v;
}

/// A skeleton's joint limits as the checkpoint stores them (metadata 'handemo', field 'joint_limits': "lower" and
/// "upper", joints x 3 degrees each); null when every limit is -180..180 (a skeleton read from BVH).
inline nlohmann::json joint_limits_json(const skeleton& s)
{
    if (!s.has_limits()) return nullptr;
    std::vector<double> lo, hi;
    for (const auto& j : s.joints)
        for (std::size_t a = 0; a < 3; ++a) lo.push_back(j.lower_limit[a]), hi.push_back(j.upper_limit[a]);
    return {{"lower", lo}, {"upper", hi}};
}

/// The tempo neighbours as the checkpoint stores them (metadata 'handemo', field 'tempo_neighbours'); a domain a
/// content has no pair of is null.
inline nlohmann::json tempo_neighbours_json(const tempo_neighbours& t)
{
    nlohmann::json ratios = nlohmann::json::array();
    for (const auto& row : t.log_ratios) {
        nlohmann::json r = nlohmann::json::array();
        for (double v : row) r.push_back(std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr));
        ratios.push_back(std::move(r));
    }
    return {{"k", t.k}, {"contents", t.contents}, {"descriptors", t.descriptors}, {"log_ratios", ratios}, {"mean", t.mean}, {"scale", t.scale}};
}

/// The tempo neighbours of a checkpoint's field, checked: k in 1..N, N contents each with a finite descriptor of
/// the standardisation's length and C log ratios (null or |r| < log 100, at least one per content), finite means
/// and non-negative finite scales. `fail` makes the error naming the file.
template <class Fail>
tempo_neighbours parse_tempo_neighbours(const nlohmann::json& j, std::size_t C, Fail&& fail)
{
    const auto bad = [&](const std::string& what) { return fail("metadata field 'tempo_neighbours' " + what); };
    if (!j.is_object()) throw bad("is not an object");
    tempo_neighbours t;
    const auto& k = j.at("k");
    if (!k.is_number_unsigned() || k.get<std::uint64_t>() < 1 || k.get<std::uint64_t>() > tempo_neighbour_grid.front())
        throw bad("k is " + k.dump() + ", expected an integer in 1.." + std::to_string(tempo_neighbour_grid.front()));
    t.k = k.get<std::size_t>();
    t.contents = j.at("contents").get<std::vector<std::string>>();
    for (const auto& row : j.at("descriptors")) t.descriptors.push_back(json_doubles(row));
    t.mean = json_doubles(j.at("mean"));
    t.scale = json_doubles(j.at("scale"));
    for (const auto& row : j.at("log_ratios")) {
        std::vector<double> r;
        for (const auto& v : row) r.push_back(v.is_null() ? std::nan("") : v.get<double>());
        t.log_ratios.push_back(std::move(r));
    }
    const std::size_t N = t.contents.size(), F = t.mean.size();
    if (N < t.k) throw bad("has " + std::to_string(N) + " contents for k " + std::to_string(t.k));
    if (t.descriptors.size() != N || t.log_ratios.size() != N)
        throw bad("has " + std::to_string(t.descriptors.size()) + " descriptors and " + std::to_string(t.log_ratios.size()) +
                  " rows of log ratios for " + std::to_string(N) + " contents");
    if (F != tempo_descriptor_size || t.scale.size() != F)
        throw bad("has a standardisation of " + std::to_string(F) + " means and " + std::to_string(t.scale.size()) + " scales, expected " +
                  std::to_string(tempo_descriptor_size));
    for (std::size_t f = 0; f < F; ++f)
        if (!std::isfinite(t.mean[f]) || !std::isfinite(t.scale[f]) || t.scale[f] < 0)
            throw bad("has a mean or scale of feature " + std::to_string(f) + " that is not finite (or a negative scale)");
    for (std::size_t i = 0; i < N; ++i) {
        if (t.descriptors[i].size() != F) throw bad("descriptor of content '" + t.contents[i] + "' has " + std::to_string(t.descriptors[i].size()) + " values");
        for (double v : t.descriptors[i])
            if (!std::isfinite(v)) throw bad("descriptor of content '" + t.contents[i] + "' has a value that is not finite");
        if (t.log_ratios[i].size() != C)
            throw bad("log ratios of content '" + t.contents[i] + "' have " + std::to_string(t.log_ratios[i].size()) + " entries for " +
                      std::to_string(C) + " domains");
        bool any = false;
        for (double v : t.log_ratios[i]) {
            if (std::isnan(v)) continue;
            if (!(std::abs(v) < std::log(100.0))) throw bad("log ratios of content '" + t.contents[i] + "' hold " + std::to_string(v) + ", outside +-log(100)");
            any = true;
        }
        if (!any) throw bad("log ratios of content '" + t.contents[i] + "' are all null");
    }
    return t;
}

}  // namespace detail

/// @brief The run-time description stored in a checkpoint.
struct checkpoint_info {
    std::string source;  ///< the checkpoint file, named in error messages
    std::string config;
    std::vector<std::string> domains;
    std::string neutral;
    angle_range range;
    std::vector<double> tempo;
    /// the tempo neighbours (train_options::tempo_neighbours, tempo_neighbours.hpp); empty (k 0) for models trained
    /// without them
    tempo_neighbours tempo_table;
    std::vector<double> amplitude;  ///< [C] (all 1 for checkpoints written before it existed)
    /// what the amplitude stage scales about (metadata field 'amplitude_anchor'; the mean when absent)
    handemo::stargan::amplitude_anchor amplitude_anchor = handemo::stargan::amplitude_anchor::mean;
    /// [C] change gate per target domain (prepared_data::gate_posture/gate_motion; all 1 for checkpoints
    /// written before it existed or trained without it)
    std::vector<double> gate_posture, gate_motion;
    /// [C] weight of the posture prior (all 0 for checkpoints written before it existed) and [C][J*3] the
    /// prior itself in degrees (empty when every weight is 0)
    std::vector<double> gate_prior;
    std::vector<std::vector<double>> prior_posture;
    /// [C][J*3] G's average posture per target (train_options::gate_centre, posture_centre_of()), subtracted from
    /// G's change before the gate weighs it; empty: none (trained without the option, or before it existed)
    std::vector<std::vector<double>> posture_centre;
    /// [C][J] the joint lag per domain and joint in keyframe intervals (train_options::lag, lag.hpp); empty: none
    /// (checkpoints trained without it)
    std::vector<std::vector<double>> lag;
    /// the detail layer learned from the training clips (absent in checkpoints written before it existed)
    std::optional<detail_layer> detail;
    std::vector<std::string> joint_names;
    /// the training skeleton (metadata 'skeleton', a one-frame BVH at rest), which retargeting moves a user's
    /// capture onto; absent in checkpoints written before it was stored
    std::optional<skeleton> skel;
    long step = 0;
    nlohmann::json options;
};

/// @brief Verifies a checkpoint held in memory (format, checksum, metadata fields, each value's type and range).
/// @param f the parsed safetensors file; its `source` names the file in error messages.
/// @throws format_error naming the file and the field for a corrupted or foreign file.
inline std::pair<safetensors_file, checkpoint_info> parse_checkpoint(safetensors_file f)
{
    const std::filesystem::path path = f.source;
    const auto fail = [&](const std::string& what) -> format_error {
        return format_error("checkpoint: " + path.string() + ": " + what);
    };
    auto meta = [&](const char* key) -> const std::string& {
        auto it = f.metadata.find(key);
        if (it == f.metadata.end()) throw fail(std::string("metadata field '") + key + "' is missing");
        return it->second;
    };
    if (meta("format") != "handemo-checkpoint/1")
        throw fail("format '" + meta("format") + "' is not handemo-checkpoint/1");
    if (meta("checksum") != detail::checkpoint_checksum(f))
        throw fail("checksum mismatch (stored " + meta("checksum") + ", computed " + detail::checkpoint_checksum(f) +
                   "): the file is corrupted");
    checkpoint_info info;
    info.source = path.string();
    std::vector<double> limits_lower, limits_upper;
    try {
        const auto j = nlohmann::json::parse(meta("handemo"), [&](int depth, nlohmann::json::parse_event_t, nlohmann::json&) {
            if (depth > 4) throw fail("metadata 'handemo' nests JSON deeper than 4 levels");
            return true;
        });
        info.config = j.at("config").get<std::string>();
        info.domains = j.at("domains").get<std::vector<std::string>>();
        info.neutral = j.at("neutral").get<std::string>();
        info.range.p_min = j.at("p_min").get<double>();
        info.range.p_max = j.at("p_max").get<double>();
        // Integers are read only from JSON integers: nlohmann converts a float such as 1e300 to an integer
        // type with a plain cast, which is undefined behaviour out of range.
        auto count = [&](const char* key, std::uint64_t max) -> std::uint64_t {
            const auto& v = j.at(key);
            if (!v.is_number_unsigned() || v.get<std::uint64_t>() > max)
                throw fail(std::string("metadata field '") + key + "' is " + v.dump() + ", expected an integer in 0.." +
                           std::to_string(max));
            return v.get<std::uint64_t>();
        };
        info.range.keyframes = count("keyframes", 1u << 16);
        info.range.joints = count("joints", bvh_max_joints);
        if (j.contains("range")) {  // per-channel ranges (handemo-range/2); older checkpoints have p_min/p_max only
            const auto r = parse_range(j.at("range").dump(), path.string() + " (metadata 'range')");
            if (r.keyframes != info.range.keyframes || r.joints != info.range.joints)
                throw fail("metadata 'range' is for another image size");
            info.range = r;
        }
        info.tempo = detail::json_doubles(j.at("tempo"));
        info.amplitude = j.contains("amplitude") ? detail::json_doubles(j.at("amplitude")) : std::vector<double>(info.tempo.size(), 1.0);
        if (j.contains("amplitude_anchor")) {
            const auto& a = j.at("amplitude_anchor");
            if (a == "ends")
                info.amplitude_anchor = amplitude_anchor::ends;
            else if (a != "mean")
                throw fail("metadata field 'amplitude_anchor' is " + a.dump() + ", expected \"mean\" or \"ends\"");
        }
        info.gate_posture = info.gate_motion = std::vector<double>(info.tempo.size(), 1.0);
        if (j.contains("gate")) {
            info.gate_posture = detail::json_doubles(j.at("gate").at("posture"));
            info.gate_motion = detail::json_doubles(j.at("gate").at("motion"));
            if (j.at("gate").contains("prior")) info.gate_prior = detail::json_doubles(j.at("gate").at("prior"));
            if (j.at("gate").contains("prior_posture"))
                for (const auto& row : j.at("gate").at("prior_posture")) info.prior_posture.push_back(detail::json_doubles(row));
            if (j.at("gate").contains("posture_centre"))
                for (const auto& row : j.at("gate").at("posture_centre")) info.posture_centre.push_back(detail::json_doubles(row));
        }
        if (info.gate_prior.empty()) info.gate_prior.assign(info.tempo.size(), 0.0);
        if (j.contains("lag"))
            for (const auto& row : j.at("lag")) info.lag.push_back(detail::json_doubles(row));
        if (j.contains("tempo_neighbours")) info.tempo_table = detail::parse_tempo_neighbours(j.at("tempo_neighbours"), info.domains.size(), fail);
        if (j.contains("detail")) info.detail = detail_layer::from_json(j.at("detail"), "checkpoint: " + path.string() + " (metadata 'detail')");
        if (j.contains("joint_limits")) {
            limits_lower = detail::json_doubles(j.at("joint_limits").at("lower"));
            limits_upper = detail::json_doubles(j.at("joint_limits").at("upper"));
        }
        info.joint_names = j.at("joint_names").get<std::vector<std::string>>();
        info.step = static_cast<long>(count("step", std::uint64_t{1} << 53));
        info.options = j.at("options");
        // the fields transfer reads from the options must have their types (a JSON type error would escape otherwise)
        if (!info.options.is_object()) throw fail("metadata field 'options' is " + info.options.dump() + ", expected an object");
        for (const char* key : {"amplitude", "residual"})
            if (info.options.contains(key) && !info.options.at(key).is_boolean())
                throw fail(std::string("metadata field 'options.") + key + "' is " + info.options.at(key).dump() + ", expected true or false");
    } catch (const nlohmann::json::exception& e) {
        throw fail(std::string("metadata 'handemo' is malformed: ") + e.what());
    }
    if (const auto it = f.metadata.find("skeleton"); it != f.metadata.end()) {
        const clip rest = parse_bvh(it->second, path.string() + " (metadata 'skeleton')");
        if (rest.skel.size() != info.joint_names.size())
            throw fail("metadata 'skeleton' has " + std::to_string(rest.skel.size()) + " joints, joint_names " + std::to_string(info.joint_names.size()));
        for (std::size_t k = 0; k < rest.skel.size(); ++k)
            if (rest.skel.joints[k].name != info.joint_names[k])
                throw fail("metadata 'skeleton' joint " + std::to_string(k) + " is '" + rest.skel.joints[k].name + "', joint_names says '" +
                           info.joint_names[k] + "'");
        info.skel = rest.skel;
    }
    if (!limits_lower.empty() || !limits_upper.empty()) {
        if (!info.skel) throw fail("metadata field 'joint_limits' without a 'skeleton'");
        const std::size_t C = info.skel->size() * 3;
        if (limits_lower.size() != C || limits_upper.size() != C)
            throw fail("metadata field 'joint_limits' has " + std::to_string(limits_lower.size()) + " lower and " +
                       std::to_string(limits_upper.size()) + " upper limits for " + std::to_string(C) + " joint axes");
        for (std::size_t c = 0; c < C; ++c) {
            if (!std::isfinite(limits_lower[c]) || !std::isfinite(limits_upper[c]) || limits_lower[c] > limits_upper[c])
                throw fail("metadata field 'joint_limits': joint '" + info.skel->joints[c / 3].name + "' axis " + "xyz"[c % 3] + " has limits " +
                           std::to_string(limits_lower[c]) + ".." + std::to_string(limits_upper[c]));
            info.skel->joints[c / 3].lower_limit[c % 3] = limits_lower[c];
            info.skel->joints[c / 3].upper_limit[c % 3] = limits_upper[c];
        }
    }
    info.range.validate(("checkpoint: " + path.string() + ": range").c_str());
    if (info.tempo.size() != info.domains.size()) throw fail("tempo has " + std::to_string(info.tempo.size()) + " entries for " + std::to_string(info.domains.size()) + " domains");
    if (info.amplitude.size() != info.domains.size())
        throw fail("amplitude has " + std::to_string(info.amplitude.size()) + " entries for " + std::to_string(info.domains.size()) + " domains");
    for (std::size_t d = 0; d < info.domains.size(); ++d)
        if (!(info.tempo[d] > 0.01 && info.tempo[d] < 100) || !(info.amplitude[d] > 0.01 && info.amplitude[d] < 100))
            throw fail("tempo or amplitude of domain '" + info.domains[d] + "' is not in (0.01, 100)");
    if (info.gate_posture.size() != info.domains.size() || info.gate_motion.size() != info.domains.size())
        throw fail("gate has " + std::to_string(info.gate_posture.size()) + " posture and " + std::to_string(info.gate_motion.size()) +
                   " motion entries for " + std::to_string(info.domains.size()) + " domains");
    for (std::size_t d = 0; d < info.domains.size(); ++d)
        if (!(info.gate_posture[d] >= 0 && info.gate_posture[d] <= 1) || !(info.gate_motion[d] >= 0 && info.gate_motion[d] <= 1))
            throw fail("gate of domain '" + info.domains[d] + "' is not in [0, 1]");
    if (info.gate_prior.size() != info.domains.size())
        throw fail("gate prior has " + std::to_string(info.gate_prior.size()) + " weights for " + std::to_string(info.domains.size()) + " domains");
    bool any_prior = false;
    for (std::size_t d = 0; d < info.domains.size(); ++d) {
        if (!(info.gate_prior[d] >= 0 && info.gate_prior[d] <= 1)) throw fail("gate prior of domain '" + info.domains[d] + "' is not in [0, 1]");
        any_prior |= info.gate_prior[d] != 0;
    }
    // a [domains][joints*3] table of degrees in the gate's metadata: its shape and its values
    const auto check_degrees = [&](const char* field, const std::vector<std::vector<double>>& table) {
        const std::size_t ch = info.range.joints * 3;
        const std::string name = std::string("gate ") + field;
        if (table.size() != info.domains.size())
            throw fail(name + " has " + std::to_string(table.size()) + " rows for " + std::to_string(info.domains.size()) + " domains");
        for (std::size_t d = 0; d < info.domains.size(); ++d) {
            if (table[d].size() != ch)
                throw fail(name + " of domain '" + info.domains[d] + "' has " + std::to_string(table[d].size()) + " channels, expected joints*3 = " +
                           std::to_string(ch));
            for (double v : table[d])
                if (!(std::abs(v) <= 360)) throw fail(name + " of domain '" + info.domains[d] + "' has a value outside [-360, 360] deg");
        }
    };
    if (any_prior || !info.prior_posture.empty()) check_degrees("prior_posture", info.prior_posture);
    if (!info.posture_centre.empty()) check_degrees("posture_centre", info.posture_centre);
    if (!info.lag.empty()) {
        if (info.lag.size() != info.domains.size())
            throw fail("lag has " + std::to_string(info.lag.size()) + " rows for " + std::to_string(info.domains.size()) + " domains");
        for (std::size_t d = 0; d < info.domains.size(); ++d) {
            if (info.lag[d].size() != info.range.joints)
                throw fail("lag of domain '" + info.domains[d] + "' has " + std::to_string(info.lag[d].size()) + " joints, the model has " +
                           std::to_string(info.range.joints));
            for (std::size_t jt = 0; jt < info.lag[d].size(); ++jt)
                if (!(std::abs(info.lag[d][jt]) <= static_cast<double>(info.range.keyframes)))
                    throw fail("lag of domain '" + info.domains[d] + "' at joint " + std::to_string(jt) + " is " + std::to_string(info.lag[d][jt]) +
                               ", outside +-" + std::to_string(info.range.keyframes) + " keyframes");
        }
    }
    if (info.detail) {
        if (info.detail->channels != info.range.joints * 3 || info.detail->keyframes != info.range.keyframes)
            throw fail("metadata 'detail' is for " + std::to_string(info.detail->channels / 3) + " joints and " +
                       std::to_string(info.detail->keyframes) + " keyframes, the model has " + std::to_string(info.range.joints) + " and " +
                       std::to_string(info.range.keyframes));
        for (const auto& e : info.detail->emotions)
            if (std::find(info.domains.begin(), info.domains.end(), e) == info.domains.end())
                throw fail("metadata 'detail' has emotion '" + e + "', which is not a domain of the model");
    }
    if (std::find(info.domains.begin(), info.domains.end(), info.neutral) == info.domains.end())
        throw fail("neutral domain '" + info.neutral + "' is not one of the " + std::to_string(info.domains.size()) + " domains");
    if (std::set<std::string>(info.domains.begin(), info.domains.end()).size() != info.domains.size())
        throw fail("a domain name appears twice");
    return {std::move(f), std::move(info)};
}

/// @brief The inference part of a verified checkpoint: its metadata and the generator's weights (the EMA weights
/// when it has them), without D, the optimiser state, the random state and the log, with its checksum made anew
/// and metadata 'inference_only' set. load_model() reads it like the whole checkpoint; `train --resume` cannot.
/// `half`: the float weights stored as IEEE binary16 (half the bytes; load_model() widens them back, so the model
/// is the trained one with its weights rounded, as kernels::weight_storage::f16 rounds them), metadata
/// 'weights' = 'binary16'. A weight binary16 cannot hold is refused naming the tensor.
inline safetensors_file inference_checkpoint(const safetensors_file& f, bool half = false)
{
    const std::string prefix = f.find("G_ema.main.0.weight") ? "G_ema." : "G.";
    safetensors_file out;
    out.source = f.source;
    out.metadata = f.metadata;
    for (const auto& t : f.tensors) {
        if (t.name.compare(0, prefix.size(), prefix) != 0) continue;
        if (!half || t.dtype != st_dtype::f32) {
            out.tensors.push_back(t);
            continue;
        }
        st_tensor h{t.name, st_dtype::f16, t.shape, std::string(t.numel() * 2, '\0')};
        for (std::size_t i = 0; i < t.numel(); ++i) {
            const float v = handemo::detail::read_element<float>(t.data.data(), t.dtype, i);
            const std::uint16_t b = float_to_half(v);
            if (std::isfinite(v) && !std::isfinite(half_to_float(b)))
                throw value_error("export: " + f.source + ": weight " + std::to_string(i) + " of " + t.name + " (" + std::to_string(v) +
                                  ") is beyond binary16's range");
            handemo::detail::store_le(h.data.data() + 2 * i, b);
        }
        out.tensors.push_back(std::move(h));
    }
    if (half) out.metadata["weights"] = "binary16";
    out.metadata["inference_only"] = "true";
    out.metadata["checksum"] = detail::checkpoint_checksum(out);
    return out;
}

/// @brief The checkpoint file of a model path: `path/checkpoint.safetensors` for a training output folder, else
/// `path` itself.
inline std::filesystem::path checkpoint_file(const std::filesystem::path& path)
{
    return is_folder(path) ? path / "checkpoint.safetensors" : path;
}

/// @brief Reads and verifies a checkpoint file (format, checksum, metadata fields).
/// @throws io_error for a missing file; format_error naming the file and the field for a truncated,
///         corrupted or foreign file.
inline std::pair<safetensors_file, checkpoint_info> read_checkpoint(const std::filesystem::path& path)
{
    return parse_checkpoint(read_safetensors(path));
}

/// @brief One row of the loss log.
struct loss_row {
    long step = 0;
    std::vector<double> values;  ///< loss_columns() order
};

/// @brief Writes the loss log as CSV (`step,D/real,...`).
inline std::string loss_log_csv(const std::vector<loss_row>& rows)
{
    std::string s = "step";
    for (const auto& c : loss_columns()) s += "," + c;
    s += "\n";
    char buf[64];
    for (const auto& r : rows) {
        s += std::to_string(r.step);
        for (double v : r.values) {
            std::snprintf(buf, sizeof buf, ",%.9g", v);
            s += buf;
        }
        s += "\n";
    }
    return s;
}

/// @brief StarGAN trainer for one configuration and batch size.
template <stargan_config Base, std::size_t Batch = 16>
class trainer {
public:
    using cfg = with_batch<Base, Batch>;
    static constexpr std::size_t N = Batch, C = Base::domains, H = dims<cfg>::H, W = dims<cfg>::W;
    using image_shape = shape<N, 3, H, W>;
    using label_shape = shape<N, C>;
    /// the most data-parallel parts of a batch (train_step) and the batch of each
    static constexpr std::size_t S = N % 2 == 0 ? 2 : 1, M = N / S;

    trainer(config_info info, prepared_data data, train_options opt)
        : info_(std::move(info)), data_(std::move(data)), opt_(validated(opt)),
          shards_(resolve_shards(opt_)),
          pool_(shards_ == 1 || distributed(opt_) ? all_threads(opt_.threads) : std::min(all_threads(opt_.threads), unsigned(shards_))),
          gen_(opt.seed)
    {
        if (distributed(opt_)) {  // this process's part only, its convolutions split over the process's threads
            tapes_[opt_.exchange->rank()] = std::make_unique<autodiff::tape<float>>(std::size_t{1} << 22, pool_.size() > 1 ? &pool_ : nullptr);
        } else if (shards_ == 1) {  // the whole batch on one tape, its convolutions split over every thread
            tapes_[0] = std::make_unique<autodiff::tape<float>>(std::size_t{1} << 22, pool_.size() > 1 ? &pool_ : nullptr);
        } else {  // a tape per half; with 4 or more threads each half splits its convolutions again
            const unsigned per_shard = all_threads(opt_.threads) / unsigned(shards_);
            for (std::size_t s = 0; s < shards_; ++s) {
                thread_pool* p = per_shard > 1 ? shard_pools_.emplace_back(std::make_unique<thread_pool>(per_shard)).get() : nullptr;
                tapes_[s] = std::make_unique<autodiff::tape<float>>(std::size_t{1} << 22, p);
            }
        }
        g_.set_grad_shards(shards_);
        d_.set_grad_shards(shards_);
        logits_.resize(N * C);
        if (data_.H != H || data_.W != W) throw shape_error("train: prepared data is for another configuration");
        rng init_rng(opt_.seed ^ 0x9E3779B97F4A7C15ULL);
        init_pytorch_default(g_, init_rng);
        init_pytorch_default(d_, init_rng);
        g_.set_residual(opt_.residual);
        if (opt_.residual) g_.zero_last_conv();
        if ((opt_.lambda_pair > 0) && (data_.partner.size() != data_.size() * C || data_.pair_weight.size() != 3 * H * W))
            throw value_error("train: lambda_pair needs the prepared data's partner table (prepare_data)");
        if ((!data_.gate_posture.empty() || !data_.gate_motion.empty()) && (data_.gate_posture.size() != C || data_.gate_motion.size() != C))
            throw value_error("train: the prepared data's change gate has " + std::to_string(data_.gate_posture.size()) + " posture and " +
                              std::to_string(data_.gate_motion.size()) + " motion entries for " + std::to_string(C) + " domains");
        if ((!data_.gate_prior.empty() && data_.gate_prior.size() != C) || (!data_.prior_posture.empty() && data_.prior_posture.size() != C))
            throw value_error("train: the prepared data's posture prior has " + std::to_string(data_.gate_prior.size()) + " weights and " +
                              std::to_string(data_.prior_posture.size()) + " rows for " + std::to_string(C) + " domains");
        if (opt_.ema > 0) {
            ema_.emplace();
            ema_->set_residual(opt_.residual);
            zip_parameters(g_, *ema_, [](std::span<const float> g, std::span<float> v) { std::copy(g.begin(), g.end(), v.begin()); });
        }
        adam_options ao;
        ao.beta1 = opt_.beta1;
        ao.beta2 = opt_.beta2;
        og_.emplace(g_, ao);
        od_.emplace(d_, ao);
        if (opt_.neutral_share > 0) {
            for (std::size_t m = 0; m < data_.size(); ++m)
                if (data_.labels[m] == data_.neutral) neutral_clips_.push_back(m);
            if (neutral_clips_.empty() || C < 2)
                throw value_error("train: neutral_share " + std::to_string(opt_.neutral_share) +
                                  " needs neutral clips in the training data and another domain to go to");
        }
        perm_.resize(data_.size());
        std::iota(perm_.begin(), perm_.end(), 0);
        cursor_ = perm_.size();  // shuffle before the first batch
        x_.resize(image_shape::size);
        xh_.resize(image_shape::size);
        y_.resize(image_shape::size);
        mask_.resize(image_shape::size);
        org_.resize(label_shape::size);
        trg_.resize(label_shape::size);
    }

    generator<float, cfg>& gen() noexcept { return g_; }
    /// @brief The generator transfer uses: the EMA of G's weights when options.ema > 0, else G.
    generator<float, cfg>& inference_gen() noexcept { return ema_ ? *ema_ : g_; }
    discriminator<float, cfg>& disc() noexcept { return d_; }
    long step() const noexcept { return step_; }
    const std::vector<loss_row>& log() const noexcept { return log_; }
    const prepared_data& data() const noexcept { return data_; }

    /// @brief One D iteration (and a G iteration every n_critic).
    /// Data-parallel (shards() = 2, the default on 2 or more threads): the batch is cut into two halves, each
    /// recorded on its own tape and run on its own thread (every loss is a mean over samples, so a half's
    /// terms scaled by 1/2 add up to the batch's loss); the halves' gradients are then added in a fixed
    /// order, so the same seed gives the same bits on any thread count up to 3. One shard (the default on one
    /// thread): the whole batch on one tape, its convolutions split over the threads.
    /// @throws value_error naming the step and the term when a loss is not finite (before any update).
    void train_step()
    {
        next_batch();
        const double lr_d = lr_schedule{opt_.d_lr, opt_.iters, opt_.decay_start}(step_);
        const double lr_g = lr_schedule{opt_.g_lr, opt_.iters, opt_.decay_start}(step_);
        for (std::size_t n = 0; n < N; ++n) alpha_[n] = static_cast<float>(gen_.uniform01());
        if constexpr (S == 1) step_parts<N>(lr_d, lr_g);
        else if (shards_ == 1) step_parts<N>(lr_d, lr_g);
        else step_parts<M>(lr_d, lr_g);
        last_[10] = lr_d;
        ++step_;
        if (step_ % opt_.log_every == 0 || step_ == opt_.iters) log_.push_back({step_, std::vector<double>(last_.begin(), last_.end())});
    }

    /// @brief The domains of the last train_step()'s batch, slot by slot: each source's, and the target G was asked
    /// for (train_options::neutral_share).
    const std::array<int, N>& batch_sources() const noexcept { return lab_; }
    const std::array<int, N>& batch_targets() const noexcept { return tl_; }

    /// @brief Parts a batch is cut into by train_step (train_options::shards, resolved).
    std::size_t shards() const noexcept { return shards_; }
    /// @brief The most parts a batch of N can be cut into: 2 for an even batch, else 1.
    static constexpr std::size_t max_shards() noexcept { return S; }
    /// @brief Whether the training tapes keep each parameter's packed panels for all the convolutions of a phase
    /// that read it, and G's from a step's D phase for its G phase (autodiff::tape::set_panel_cache; on by
    /// default). Off: the same bits, more time, less memory.
    void set_panel_cache(bool on) noexcept
    {
        for (auto& t : tapes_)
            if (t) t->set_panel_cache(on);
    }

private:
    /// The step on parts of B samples (N / B of them, each on tapes_[part]).
    template <std::size_t B>
    void step_parts(double lr_d, double lr_g)
    {
        using namespace handemo::autodiff;
        using part_image = shape<B, 3, H, W>;
        using part_label = shape<B, C>;
        constexpr std::size_t per = image_shape::size / N;
        constexpr float share = float(B) / float(N);  // exact: 1 or 1/2
        // ---- D: real, fake (G without gradients), gradient penalty at x_hat
        d_.zero_grad();
        g_.set_requires_grad(false);
        d_.set_requires_grad(true);
        run_parts<N / B>([&](tape<float>& t, std::size_t s) {
            const std::size_t o = s * B;
            auto xv = t.template input<part_image>(x_.data() + o * per);
            auto real = d_.forward(t, xv, s);
            auto fake = g_.forward(t, xv, t.template input<part_label>(trg_.data() + o * C), s);
            auto fk = d_.forward(t, fake, s);
            for (std::size_t n = 0; n < B; ++n) {
                const float a = alpha_[o + n];
                const float* f = fake.data() + n * per;
                const float* x = x_.data() + (o + n) * per;
                float* xh = xh_.data() + (o + n) * per;
                for (std::size_t i = 0; i < per; ++i) xh[i] = a * x[i] + (1 - a) * f[i];
            }
            auto xhv = t.template input<part_image>(xh_.data() + o * per, true);
            auto oh = d_.forward(t, xhv, s);
            auto gp = share * mean(square(l2_norm_per_sample(t.grad(sum(oh.src), xhv)) - 1.0f));
            auto d_real = -share * mean(real.src);
            auto d_fake = share * mean(fk.src);
            auto d_cls = share * cross_entropy(real.cls, std::span<const int, B>(lab_.data() + o, B));
            auto ld = d_real + d_fake + float(opt_.lambda_cls) * d_cls + float(opt_.lambda_gp) * gp;
            std::copy_n(real.cls.data(), B * C, logits_.data() + o * C);
            part_[s] = {d_real.item(), d_fake.item(), d_cls.item(), gp.item(), ld.item()};
            t.backward(ld);
        });
        share_parts<N / B, B>(d_, true);
        const auto dl = sum_parts<N / B>();
        check_finite({{"D/real", dl[0]}, {"D/fake", dl[1]}, {"D/cls", dl[2]}, {"D/gp", dl[3]}});
        for (std::size_t k = 0; k < 5; ++k) last_[k] = dl[k];
        last_[5] = accuracy(logits_.data());
        d_.reduce_grad_shards(&pool_);
        od_->step(d_, lr_d, &pool_);
        // ---- G: adversarial + classification + reconstruction
        if ((step_ + 1) % opt_.n_critic == 0) {
            g_.zero_grad();
            g_.set_requires_grad(true);
            d_.set_requires_grad(false);
            const float pair_scale = paired_ > 0 ? float(double(part_image::size) / double(paired_)) : 0.f;
            run_parts<N / B>([&](tape<float>& t, std::size_t s) {
                const std::size_t o = s * B;
                auto x2 = t.template input<part_image>(x_.data() + o * per);
                auto f2 = g_.forward(t, x2, t.template input<part_label>(trg_.data() + o * C), s);
                auto o2 = d_.forward(t, f2, s);
                auto rec = g_.forward(t, f2, t.template input<part_label>(org_.data() + o * C), s);
                auto g_fake = -share * mean(o2.src);
                auto g_cls = share * cross_entropy(o2.cls, std::span<const int, B>(tl_.data() + o, B));
                auto g_rec = share * l1_loss(x2, rec);
                auto lg = g_fake + float(opt_.lambda_cls) * g_cls + float(opt_.lambda_rec) * g_rec;
                std::array<float, 7> p{g_fake.item(), g_cls.item(), g_rec.item(), 0.f, 0.f, 0.f, 0.f};
                if (opt_.lambda_id > 0) {  // identity: G(x, c_org) = x
                    auto g_id = share * l1_loss(x2, g_.forward(t, x2, t.template input<part_label>(org_.data() + o * C), s));
                    p[4] = g_id.item();
                    lg = lg + float(opt_.lambda_id) * g_id;
                }
                if (opt_.lambda_pair > 0 && paired_ > 0) {  // paired: G(x, c) = the same take performed in c
                    auto yv = t.template input<part_image>(y_.data() + o * per);
                    auto mv = t.template input<part_image>(mask_.data() + o * per);
                    auto g_pair = pair_scale * mean(abs((f2 - yv) * mv));  // the batch's sum / paired_
                    p[5] = g_pair.item();
                    lg = lg + float(opt_.lambda_pair) * g_pair;
                }
                if (opt_.lambda_delta > 0) {  // size of the change
                    auto g_delta = share * l1_loss(f2, x2);
                    p[6] = g_delta.item();
                    lg = lg + float(opt_.lambda_delta) * g_delta;
                }
                p[3] = lg.item();
                part_[s] = p;
                t.backward(lg);
            }, g_.parameter_values());  // G has not changed since this step's D phase packed its panels
            share_parts<N / B, B>(g_, false);
            const auto gl = sum_parts<N / B>();
            check_finite({{"G/fake", gl[0]}, {"G/cls", gl[1]}, {"G/rec", gl[2]}, {"G/id", gl[4]}, {"G/pair", gl[5]},
                          {"G/total", gl[3]}});
            last_[6] = gl[0], last_[7] = gl[1], last_[8] = gl[2], last_[9] = gl[3];
            last_[11] = gl[4], last_[12] = gl[5], last_[13] = gl[6];
            g_.reduce_grad_shards(&pool_);
            og_->step(g_, lr_g, &pool_);
            if (ema_) update_ema();
            d_.set_requires_grad(true);
        }
    }

public:
    /// @brief Trains to opt.iters (or opt.stop_at) with progress, checkpoints into `out_dir`.
    /// With `resume`, continues from out_dir/checkpoint.safetensors.
    void run(const std::filesystem::path& out_dir, bool resume = false)
    {
        namespace fs = std::filesystem;
        const bool writer = writes_files(opt_);
        if (writer) make_directories(out_dir);
        const fs::path ck = out_dir / "checkpoint.safetensors";
        if (resume) {
            if (!path_exists(ck)) throw io_error("train: --resume: no checkpoint at " + ck.string());
            load(ck);
        }
        progress bar("train " + info_.name, opt_.iters, opt_.progress_out);
        const long end = opt_.stop_at >= 0 ? std::min(opt_.stop_at, opt_.iters) : opt_.iters;
        char status[160];
        while (step_ < end) {
            train_step();
            std::snprintf(status, sizeof status, "D %.3f (cls %.3f gp %.3f acc %.0f%%) G %.3f (cls %.3f rec %.4f)", last_[4],
                          last_[2], last_[3], 100 * last_[5], last_[9], last_[7], last_[8]);
            bar.update(step_, status);
            if (writer && (step_ % opt_.checkpoint_every == 0 || step_ == end)) save(out_dir);
        }
        bar.finish();
    }

    /// @brief Writes checkpoint.safetensors (everything, checkpoint()), generator.safetensors (G only, PyTorch
    /// names), range.json and log.csv into `out_dir`, each atomically.
    void save(const std::filesystem::path& out_dir)
    {
        if (posture_centre_hook_) data_.posture_centre.clear();  // the hook reads the weights' checkpoint without a centre
        safetensors_file f = checkpoint((out_dir / "checkpoint.safetensors").string());
        if (posture_centre_hook_) {
            // G's average posture belongs to the weights being saved: computed from them, added to the same checkpoint
            data_.posture_centre = posture_centre_hook_(f);
            auto j = nlohmann::json::parse(f.metadata.at("handemo"));
            j["gate"]["posture_centre"] = data_.posture_centre;
            f.metadata["handemo"] = j.dump();
            f.metadata["checksum"] = detail::checkpoint_checksum(f);
        }
        write_safetensors(out_dir / "checkpoint.safetensors", f);
        save_parameters(out_dir / "generator.safetensors", inference_gen(),
                        {{"format", "pytorch-state-dict"}, {"config", info_.name}, {"step", std::to_string(step_)},
                         {"residual", opt_.residual ? "true" : "false"}, {"ema", ema_ ? "true" : "false"}});
        save_range(out_dir / "range.json", data_.range);
        write_file_atomic(out_dir / "log.csv", loss_log_csv(log_));
    }

    /// @brief Computes G's average posture before every save() (train_options::gate_centre): `hook` gets the
    /// checkpoint of the weights being saved, without a centre, and returns the centre they are saved with, so that
    /// every checkpoint a run leaves behind (a killed run's too) holds the centre of its own G. train_model() sets it.
    void set_posture_centre_hook(std::function<std::vector<std::vector<double>>(const safetensors_file&)> hook)
    {
        posture_centre_hook_ = std::move(hook);
    }

    /// @brief The checkpoint save() writes, in memory (`source`: the file it is named as in error messages).
    safetensors_file checkpoint(const std::string& source)
    {
        safetensors_file f;
        f.source = source;
        add_parameters(f, g_, "G.");
        add_parameters(f, d_, "D.");
        if (ema_) add_parameters(f, *ema_, "G_ema.");
        add_adam(f, "adam.G.", *og_);
        add_adam(f, "adam.D.", *od_);
        const auto st = gen_.state();
        f.add<std::uint64_t>("rng.state", std::span<const std::uint64_t>(st.data(), st.size()), {st.size()});
        std::vector<std::int64_t> perm(perm_.begin(), perm_.end());
        perm.push_back(static_cast<std::int64_t>(cursor_));
        f.add<std::int64_t>("data.perm_cursor", perm, {perm.size()});
        std::vector<double> lg;
        for (const auto& r : log_) {
            lg.push_back(static_cast<double>(r.step));
            lg.insert(lg.end(), r.values.begin(), r.values.end());
        }
        f.add<double>("log", lg, {log_.size(), loss_columns().size() + 1});
        nlohmann::json j = {{"config", info_.name},
                            {"domains", info_.domain_names},
                            {"neutral", info_.neutral},
                            {"p_min", data_.range.p_min},
                            {"p_max", data_.range.p_max},
                            {"range", range_to_json(data_.range)},
                            {"keyframes", Base::keyframes},
                            {"joints", Base::joints},
                            {"tempo", data_.tempo},
                            {"amplitude", data_.amplitude},
                            {"gate", {{"posture", data_.gate_posture.empty() ? std::vector<double>(C, 1.0) : data_.gate_posture},
                                      {"motion", data_.gate_motion.empty() ? std::vector<double>(C, 1.0) : data_.gate_motion},
                                      {"prior", data_.gate_prior.empty() ? std::vector<double>(C, 0.0) : data_.gate_prior},
                                      {"prior_posture", data_.prior_posture}}},
                            {"joint_names", data_.joint_names},
                            {"step", step_},
                            {"options", opt_.to_json()}};
        if (data_.detail) j["detail"] = data_.detail->to_json();
        if (!data_.lag.lag.empty()) j["lag"] = data_.lag.lag;
        if (!data_.posture_centre.empty()) j["gate"]["posture_centre"] = data_.posture_centre;
        // written only about the ends: a checkpoint without the field scales about the mean, as all did before it
        if (data_.amplitude_anchor != amplitude_anchor::mean) j["amplitude_anchor"] = anchor_name(data_.amplitude_anchor);
        if (!data_.tempo_table.empty()) j["tempo_neighbours"] = detail::tempo_neighbours_json(data_.tempo_table);
        // the skeleton's joint limits, which its BVH text cannot hold: written only when a joint has one (a skeleton
        // read from BVH has none, and its checkpoints keep their bytes)
        if (const auto limits = detail::joint_limits_json(data_.skel); !limits.is_null()) j["joint_limits"] = limits;
        f.metadata["format"] = "handemo-checkpoint/1";
        f.metadata["handemo"] = j.dump();
        if (!data_.skel.joints.empty()) f.metadata["skeleton"] = to_bvh_string(clip::make(data_.skel, 1, 30), -1);
        f.metadata["checksum"] = detail::checkpoint_checksum(f);
        return f;
    }

    /// @brief Restores every piece of state from a checkpoint written by save().
    /// @throws format_error / shape_error naming the file and field; value_error when the checkpoint is
    ///         of another configuration.
    void load(const std::filesystem::path& path)
    {
        auto [f, info] = read_checkpoint(path);
        if (info.config != info_.name)
            throw value_error("train: " + path.string() + " is a " + info.config + " checkpoint, not " + info_.name);
        load_parameters(f, g_, "G.");
        load_parameters(f, d_, "D.");
        if (ema_) load_parameters(f, *ema_, "G_ema.");
        load_adam(f, "adam.G.", *og_);
        load_adam(f, "adam.D.", *od_);
        const auto st = f.get<std::uint64_t>("rng.state", std::vector<std::size_t>{rng::state_size});
        gen_.set_state(st);
        const auto pc = f.get<std::int64_t>("data.perm_cursor", std::vector<std::size_t>{perm_.size() + 1});
        for (std::size_t i = 0; i < perm_.size(); ++i) {
            if (pc[i] < 0 || static_cast<std::size_t>(pc[i]) >= perm_.size())
                throw format_error("checkpoint: " + path.string() + ": data.perm_cursor entry out of range (different data set?)");
            perm_[i] = static_cast<std::size_t>(pc[i]);
        }
        if (pc.back() < 0 || static_cast<std::size_t>(pc.back()) > perm_.size())
            throw format_error("checkpoint: " + path.string() + ": data.perm_cursor position out of range (different data set?)");
        cursor_ = static_cast<std::size_t>(pc.back());
        const auto& lt = f.at("log");
        const auto lg = lt.to_vector<double>();
        // a log written with fewer columns (an older version) is padded with NaN
        const std::size_t cols = lt.shape.size() == 2 ? lt.shape[1] : loss_columns().size() + 1;
        if (cols < 2 || cols > loss_columns().size() + 1)
            throw format_error("checkpoint: " + path.string() + ": log has " + std::to_string(cols) + " columns, expected at most " +
                               std::to_string(loss_columns().size() + 1));
        log_.clear();
        for (std::size_t i = 0; i + cols <= lg.size(); i += cols)
            if (!(lg[i] >= 0 && lg[i] <= 9e15))  // the step column becomes a long below
                throw format_error("checkpoint: " + path.string() + ": log row " + std::to_string(i / cols) + " has step " +
                                   std::to_string(lg[i]) + ", expected a non-negative integer");
        for (std::size_t i = 0; i + cols <= lg.size(); i += cols) {
            std::vector<double> v(lg.begin() + long(i) + 1, lg.begin() + long(i + cols));
            v.resize(loss_columns().size(), std::nan(""));
            log_.push_back({static_cast<long>(lg[i]), std::move(v)});
        }
        data_.range = info.range;
        data_.gate_posture = info.gate_posture;
        data_.gate_motion = info.gate_motion;
        data_.gate_prior = info.gate_prior;
        data_.prior_posture = info.prior_posture;
        if (info.detail) data_.detail = info.detail;
        step_ = info.step;
    }

private:
    template <class A>
    static void add_adam(safetensors_file& f, const std::string& p, const A& a)
    {
        f.add<float>(p + "m", std::span<const float>(a.m()), {a.m().size()});
        f.add<float>(p + "v", std::span<const float>(a.v()), {a.v().size()});
        f.add<std::int64_t>(p + "steps", std::span<const std::int64_t>(a.steps()), {a.steps().size()});
    }
    template <class A>
    static void load_adam(const safetensors_file& f, const std::string& p, A& a)
    {
        const auto m = f.get<float>(p + "m", std::vector<std::size_t>{a.m().size()});
        const auto v = f.get<float>(p + "v", std::vector<std::size_t>{a.v().size()});
        const auto s = f.get<std::int64_t>(p + "steps", std::vector<std::size_t>{a.steps().size()});
        std::copy(m.begin(), m.end(), a.m().begin());
        std::copy(v.begin(), v.end(), a.v().begin());
        std::copy(s.begin(), s.end(), a.steps().begin());
    }

    void next_batch()
    {
        constexpr std::size_t per = 3 * H * W;
        const std::size_t led = neutral_led_slots(opt_.neutral_share, N);
        for (std::size_t n = 0; n < N; ++n) {
            if (neutral_led(n, led, N)) {
                const std::size_t m = neutral_clips_[gen_.below(neutral_clips_.size())];
                std::copy_n(data_.images.data() + m * per, per, x_.data() + n * per);
                lab_[n] = data_.labels[m];
                idx_[n] = m;
                continue;
            }
            if (cursor_ >= perm_.size()) {
                for (std::size_t i = perm_.size(); i > 1; --i) std::swap(perm_[i - 1], perm_[gen_.below(i)]);
                cursor_ = 0;
            }
            const std::size_t m = perm_[cursor_++];
            std::copy_n(data_.images.data() + m * per, per, x_.data() + n * per);
            lab_[n] = data_.labels[m];
            idx_[n] = m;
        }
        // target labels: a random permutation of the batch's own labels (as the StarGAN reference); with neutral-led
        // slots, of the other slots' labels among those slots, and each led slot a domain other than neutral
        std::array<std::size_t, N> idx;
        std::size_t others = 0;
        for (std::size_t n = 0; n < N; ++n)
            if (!neutral_led(n, led, N)) idx[others++] = n;
        for (std::size_t i = others; i > 1; --i) std::swap(idx[i - 1], idx[gen_.below(i)]);
        std::fill(org_.begin(), org_.end(), 0.f);
        std::fill(trg_.begin(), trg_.end(), 0.f);
        for (std::size_t n = 0, k = 0; n < N; ++n) {
            if (neutral_led(n, led, N)) {
                const auto d = static_cast<int>(gen_.below(C - 1));
                tl_[n] = d >= data_.neutral ? d + 1 : d;
            } else {
                tl_[n] = lab_[idx[k++]];
            }
            org_[n * C + static_cast<std::size_t>(lab_[n])] = 1.f;
            trg_[n * C + static_cast<std::size_t>(tl_[n])] = 1.f;
        }
        // paired targets: the same content and take performed in the target emotion, masked to the K x J image
        paired_ = 0;
        if (opt_.lambda_pair > 0) {
            std::fill(y_.begin(), y_.end(), 0.f);
            std::fill(mask_.begin(), mask_.end(), 0.f);
            for (std::size_t n = 0; n < N; ++n) {
                const int q = data_.partner[idx_[n] * C + static_cast<std::size_t>(tl_[n])];
                if (q < 0) continue;
                std::copy_n(data_.images.data() + static_cast<std::size_t>(q) * per, per, y_.data() + n * per);
                std::copy_n(data_.pair_weight.data(), per, mask_.data() + n * per);
                paired_ += 3 * data_.K * data_.J;
            }
        }
        if (opt_.augment > 0)
            for (std::size_t n = 0; n < N; ++n)
                for (std::size_t c = 0; c < 3; ++c)
                    for (std::size_t j = 0; j < data_.J; ++j) {
                        const float off = static_cast<float>(opt_.augment * gen_.normal());
                        for (std::size_t i = 0; i < data_.K; ++i) {
                            const std::size_t at = n * per + (c * H + i) * W + j;
                            x_[at] += off;
                            y_[at] += off;
                        }
                    }
    }

    /// ema = d ema + (1 - d) g after every G update, d = min(options.ema, (1 + u) / (10 + u)) for the u-th
    /// update (TensorFlow's ExponentialMovingAverage warm-up, so early weights do not dominate a short run).
    void update_ema()
    {
        const double u = static_cast<double>((step_ + 1) / opt_.n_critic);
        const float d = static_cast<float>(std::min(opt_.ema, (1.0 + u) / (10.0 + u)));
        zip_parameters(g_, *ema_, [&](std::span<const float> g, std::span<float> v) {
            parallel_blocks(pool_, v.size(), [&](std::size_t lo, std::size_t hi) {
                for (std::size_t k = lo; k < hi; ++k) v[k] = d * v[k] + (1 - d) * g[k];
            });
        });
    }

    double accuracy(const float* logits) const noexcept
    {
        int ok = 0;
        for (std::size_t n = 0; n < N; ++n) {
            const float* z = logits + n * C;
            if (std::max_element(z, z + C) - z == lab_[n]) ++ok;
        }
        return static_cast<double>(ok) / N;
    }

    /// Runs f(tape, part) for parts 0..P-1, each on tapes_[part], on the pool's threads when P > 1. Each tape is
    /// reset first, keeping the panels it packed of the values in `unchanged` (parameters no optimiser has updated
    /// since the tape's last phase; empty: none).
    template <std::size_t P, class F>
    void run_parts(F&& f, std::span<const float> unchanged = {})
    {
        auto one = [&](int s) {
            tapes_[std::size_t(s)]->reset_keeping_packed(unchanged.data(), unchanged.data() + unchanged.size());
            f(*tapes_[std::size_t(s)], std::size_t(s));
        };
        if constexpr (P == 1) one(0);
        else if (distributed(opt_)) one(int(opt_.exchange->rank()));
        else pool_.parallel_for(0, int(P), one);
    }
    /// Data parallelism across processes: each process's part of the phase (its loss terms, with `logits` D's
    /// class logits of its samples, and m's gradient shard) copied to every process, bit for bit, so that
    /// sum_parts() and reduce_grad_shards() then add the same values in the same part order as one process.
    template <std::size_t P, std::size_t B, class Model>
    void share_parts([[maybe_unused]] Model& m, [[maybe_unused]] bool logits)
    {
        if constexpr (P > 1) {
            if (!distributed(opt_)) return;
            std::array<float*, P> at{};
            for (std::size_t s = 0; s < P; ++s) at[s] = part_[s].data();
            opt_.exchange->share(at, part_[0].size());
            if (logits) {
                for (std::size_t s = 0; s < P; ++s) at[s] = logits_.data() + s * B * C;
                opt_.exchange->share(at, B * C);
            }
            for (std::size_t s = 0; s < P; ++s) at[s] = m.grad_shard(s).data();
            opt_.exchange->share(at, m.grad_shard(0).size());
        }
    }
    /// Whether the parts of a batch are computed by several processes (train_options::exchange).
    static bool distributed(const train_options& o) noexcept { return o.exchange && o.exchange->ranks() > 1; }
    /// The loss terms of parts 0..P-1 added up in part order.
    template <std::size_t P>
    std::array<double, 7> sum_parts() const noexcept
    {
        std::array<double, 7> r{};
        for (std::size_t s = 0; s < P; ++s)
            for (std::size_t k = 0; k < r.size(); ++k) r[k] += double(part_[s][k]);
        return r;
    }
    static unsigned all_threads(unsigned requested) noexcept
    {
        return requested ? requested : std::max(1u, std::thread::hardware_concurrency());
    }
    /// The options, validated before anything is built from them.
    static train_options validated(train_options o)
    {
        o.validate();
        return o;
    }
    /// train_options::shards (validated: 0, 1 or 2) resolved: 0 = 1 on one thread, else max_shards().
    static std::size_t resolve_shards(const train_options& o)
    {
        if (distributed(o)) {  // one part per process
            const std::size_t p = o.exchange->ranks();
            if (p > S)
                throw value_error("train: " + std::to_string(p) + " processes for a batch of " + std::to_string(N) + ", which is cut into at most " +
                                  std::to_string(S) + " parts (one per process)");
            if (o.shards == 1) throw value_error("train: shards 1 across " + std::to_string(p) + " processes (each computes one part)");
            return p;
        }
        if (o.shards == 2 && S == 1)
            throw value_error("train: shards 2 for a batch of " + std::to_string(N) + " (2 needs an even batch)");
        if (o.shards) return o.shards;
        return all_threads(o.threads) == 1 ? 1 : S;
    }
    void check_finite(std::initializer_list<std::pair<const char*, double>> terms) const
    {
        for (const auto& [name, v] : terms)
            if (!std::isfinite(v))
                throw value_error("train: step " + std::to_string(step_ + 1) + ": loss term " + name + " is " +
                                  (std::isnan(v) ? "NaN" : "infinite") +
                                  "; stopped, the last good checkpoint is kept");
    }

    config_info info_;
    prepared_data data_;
    train_options opt_;
    std::function<std::vector<std::vector<double>>(const safetensors_file&)> posture_centre_hook_;
    std::size_t shards_;  ///< parts of a batch (train_options::shards resolved)
    thread_pool pool_;  ///< runs the shards (or one tape's convolutions) and splits the optimiser's elements
    std::vector<std::unique_ptr<thread_pool>> shard_pools_;  ///< each shard's convolutions, with threads to spare
    std::array<std::unique_ptr<autodiff::tape<float>>, S> tapes_;
    std::array<std::array<float, 7>, S> part_{};  ///< each shard's loss terms of the current phase
    std::array<float, N> alpha_{};                ///< the gradient penalty's interpolation factors
    std::vector<float> logits_;                   ///< D's class logits of the real batch (accuracy)
    rng gen_;
    generator<float, cfg> g_;
    discriminator<float, cfg> d_;
    std::optional<adam<float>> og_, od_;
    std::vector<std::size_t> perm_;
    std::size_t cursor_ = 0;
    std::vector<std::size_t> neutral_clips_;  ///< the neutral clips, for the neutral-led slots (train_options::neutral_share)
    std::optional<generator<float, cfg>> ema_;
    std::vector<float> x_, xh_, org_, trg_, y_, mask_;
    std::array<int, N> lab_{}, tl_{};
    std::array<std::size_t, N> idx_{};
    std::size_t paired_ = 0;  ///< unmasked values of the batch's paired targets
    std::array<double, 14> last_{};
    std::vector<loss_row> log_;
    long step_ = 0;
};

}  // namespace handemo::stargan
