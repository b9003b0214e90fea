// The training hyper-parameters as command-line options, shared by `train`, `demo` and `eval`: a preset
// (`--preset handemo`, the default, or `--preset paper`, StarGAN exactly as the paper trains it) and any
// single hyper-parameter on top of it.
#pragma once

#include <handemo/stargan/train.hpp>

#include <CLI/CLI.hpp>

#include <optional>
#include <string>

namespace handemo::cli {

/// @brief The method options given on the command line; each one absent keeps the preset's value.
struct train_overrides {
    std::string preset = "handemo";
    double lr = -1;
    std::optional<double> g_lr, d_lr, lambda_cls, lambda_rec, lambda_gp, beta1, beta2, decay_start, lambda_id, lambda_pair,
        lambda_delta, ema, augment, neutral_share;
    std::optional<int> n_critic, gate_folds;
    std::optional<bool> residual, amplitude, gate_prior, gate_posterior, gate_auto_margin, gate_centre, gate_prior_full, tempo_shrink, tempo_neighbours, lag;
    std::optional<double> gate_margin, gate_guard, gate_iters_scale;
    std::optional<std::string> range, tempo_basis, amplitude_anchor, amplitude_estimator;
};

/// @brief Adds `--inference-weights native|f16` (kernels::weight_storage) to `sub`, read into `w` (which must
/// outlive the parse); `what` is the rest of the help text (what the command does with the weights).
inline void add_inference_weights_option(CLI::App* sub, kernels::weight_storage& w, const std::string& what)
{
    sub->add_option_function<std::string>(
           "--inference-weights",
           [&w](const std::string& name) { w = name == "f16" ? kernels::weight_storage::f16 : kernels::weight_storage::native; },
           "native | f16: " + what)
        ->check(CLI::IsMember({"native", "f16"}))
        ->default_str(kernels::weight_storage_name(w));
}

/// @brief Adds --conv direct|winograd: how G computes its residual 3x3 convolutions (kernels::conv_algorithm).
inline void add_conv_algorithm_option(CLI::App* sub, kernels::conv_algorithm& a, const std::string& what)
{
    sub->add_option_function<std::string>(
           "--conv", [&a](const std::string& name) { a = name == "winograd" ? kernels::conv_algorithm::winograd : kernels::conv_algorithm::direct; },
           "direct | winograd: " + what)
        ->check(CLI::IsMember({"direct", "winograd"}))
        ->default_str(kernels::conv_algorithm_name(a));
}

/// @brief Adds the preset and every hyper-parameter to `sub`; `t` receives the run options (threads).
inline void add_train_options(CLI::App* sub, stargan::train_options& t, train_overrides& o)
{
    sub->add_option("--preset", o.preset,
                    "Method preset: 'handemo' (residual G, identity and paired losses, EMA, per-channel ranges) or "
                    "'paper' (StarGAN as the paper trains it); the options below override it")
        ->capture_default_str();
    sub->add_option("--threads", t.threads, "Worker threads (0: all cores)")->capture_default_str();
    sub->add_option("--shards", t.shards,
                    "Data-parallel parts of a batch: 2 = two halves, each on its own thread; 1 = the whole batch on one tape; "
                    "0 = 1 on one thread, else 2. The result depends on it, not on the thread count")
        ->check(CLI::Range(0, 2))
        ->capture_default_str();
    sub->add_option("--lr", o.lr, "Learning rate of both G and D (overrides --g-lr and --d-lr)");
    sub->add_option("--g-lr", o.g_lr, "Learning rate of G (preset: 1e-4)");
    sub->add_option("--d-lr", o.d_lr, "Learning rate of D (preset: 1e-4)");
    sub->add_option("--lambda-cls", o.lambda_cls, "Weight of the domain classification loss (handemo 5, paper 1)");
    sub->add_option("--lambda-rec", o.lambda_rec, "Weight of the cycle reconstruction loss (10)");
    sub->add_option("--lambda-gp", o.lambda_gp, "Weight of the gradient penalty (10)");
    sub->add_option("--n-critic", o.n_critic, "D iterations per G iteration (5)");
    sub->add_option("--beta1", o.beta1, "Adam beta1 (0.5)");
    sub->add_option("--beta2", o.beta2, "Adam beta2 (0.999)");
    sub->add_option("--decay-start", o.decay_start, "Fraction of training after which the learning rate decays linearly to 0 (0.5)");
    sub->add_option("--residual", o.residual, "G outputs input + change, identity at initialisation (handemo true, paper false)");
    sub->add_option("--lambda-id", o.lambda_id, "Weight of the identity loss |G(x, c_org) - x| (handemo 10, paper 0)");
    sub->add_option("--lambda-pair", o.lambda_pair,
                    "Weight of the paired loss |G(x, c) - same take in emotion c| (handemo 10, paper 0)");
    sub->add_option("--lambda-delta", o.lambda_delta, "Weight of the change-size penalty |G(x, c) - x| (handemo 5, paper 0)");
    sub->add_option("--neutral-share", o.neutral_share,
                    "Share of each training batch whose source is a neutral take with a target drawn among the emotions (the "
                    "mapping a transfer runs); the rest keep StarGAN's sampling, a neutral source in 1 slot of C; 0 = off (0)")
        ->check(CLI::Range(0.0, 1.0));
    sub->add_option("--ema", o.ema, "Decay of the EMA of G's weights used for transfer, 0 = off (handemo 0.999, paper 0)");
    sub->add_option("--amplitude", o.amplitude,
                    "Scale the output's excursions by the learned amplitude ratio of the emotions, as the tempo (handemo true)");
    sub->add_option("--amplitude-anchor", o.amplitude_anchor,
                    "What --amplitude scales each channel's excursions about: 'mean' (its mean over the keyframes), 'ends' (the "
                    "mean of its first and last keyframes: the movement away from the rest pose a take starts and ends in) or "
                    "'auto' (the ends when leave-one-content-out on the training clips finds that closer to the left-out "
                    "contents' takes) (handemo auto)")
        ->check(CLI::IsMember({"mean", "ends", "auto"}));
    sub->add_option("--amplitude-estimator", o.amplitude_estimator,
                    "How --amplitude measures a training pair's amplitude ratio: 'sum' (the ratio of the clips' summed channel "
                    "excursions) or 'channel' (the median of the ratios of the channels that move in the neutral clip, so that "
                    "channels held still do not pull it toward 1) (handemo sum)")
        ->check(CLI::IsMember({"sum", "channel"}));
    sub->add_option("--augment", o.augment,
                    "Per-channel offset jitter of training images and paired targets, std in network units (handemo 0.1, paper 0)");
    sub->add_option("--gate-folds", o.gate_folds,
                    "Change gate: train G this many more times, each without a group of the training contents, and blend "
                    "G's change per target emotion by what helps those held-out contents; 0 = off (handemo 2, paper 0)");
    sub->add_option("--gate-prior", o.gate_prior,
                    "Change gate: also offer the training pairs' mean posture change of the target emotion, weighted 0..1 "
                    "(handemo true)");
    sub->add_option("--gate-margin", o.gate_margin,
                    "Change gate: choose the lowest-RMSE setting whose held-out outputs the emotion classifier recognises at most "
                    "this share below the real clips (negative: above them); <= -1 = lowest RMSE only (handemo 0.10)");
    sub->add_option("--gate-posterior", o.gate_posterior,
                    "Change gate: score recognition for --gate-margin by the classifier's mean posterior of the target instead "
                    "of the share recognised (finer on few held-out pairs) (handemo true)");
    sub->add_option("--gate-auto-margin", o.gate_auto_margin,
                    "Change gate: choose the margin inside the training set: the least strict of --gate-margin, 0.1, 0.2, 0.3 "
                    "stricter and 'most recognised' whose choices, checked across the gate's own groups, are recognised at "
                    "most --gate-margin below the real clips; no effect with --gate-margin <= -1 (handemo true)");
    sub->add_option("--gate-guard", o.gate_guard,
                    "Change gate: keep the statistics setting (the posture prior alone, no G) for a target unless the gate's "
                    "choices, checked across its own groups, have an RMSE at least this share lower and recognition at least "
                    "as high; < 0 = off (handemo 0.02)");
    sub->add_option("--gate-centre", o.gate_centre,
                    "Change gate: weigh G's posture about its own average (G's mean change over the training set's neutral "
                    "takes per target, stored in the checkpoint), so that with the posture prior G adds only what is particular "
                    "to the input (handemo true)");
    sub->add_option("--gate-prior-full", o.gate_prior_full,
                    "Change gate: keep the posture prior at full weight and choose only G's posture and motion weights "
                    "(25 settings instead of 125; the statistics setting stays among them) (handemo true)");
    sub->add_option("--gate-iters-scale", o.gate_iters_scale,
                    "Change gate: train its inner models for this share of --iters (in (0, 1]); they train on about half "
                    "of the training contents, so 0.5 gives them as many passes over their clips as the final G (handemo 1)");
    sub->add_option("--tempo-shrink", o.tempo_shrink,
                    "Shrink the learned tempo factors toward keeping the duration by the weight (0, 0.25, .., 1) that best "
                    "predicts left-out training contents' durations (handemo false)");
    sub->add_option("--tempo-basis", o.tempo_basis,
                    "What the learned tempo factors are ratios of: 'duration' (the clips' durations), 'cadence' (how fast each "
                    "clip moves through its own range, whatever the number of cycles it holds) or 'auto' (the cadence when the "
                    "training pairs' durations and cadences disagree by more than a quarter in the median pair) (handemo duration)")
        ->check(CLI::IsMember({"duration", "cadence", "auto"}));
    sub->add_option("--tempo-neighbours", o.tempo_neighbours,
                    "Give each input the mean tempo of the 1-3 training contents whose neutral clips are most like it (speed, "
                    "acceleration, duration, tremor, joint lags), when leave-one-content-out on the training clips finds that "
                    "closer to the left-out contents' durations than the learned factors (handemo false)");
    sub->add_option("--lag", o.lag,
                    "Learn a time shift per target emotion and joint (a fearful hand's fingers trailing its wrist) from the "
                    "training pairs, applied after G's change and before the amplitude stage; each emotion keeps its lags only "
                    "when leave-one-content-out on the training clips finds them closer to the left-out real takes (handemo false)");
    sub->add_option("--range", o.range, "Eq. 3 range: 'channel' (per channel, wrapped against a reference) or 'global' (the paper's)");
}

/// @brief Applies the preset, then every option given, and validates.
/// @throws value_error for an unknown preset or an invalid value (naming it).
inline void finish_train_options(stargan::train_options& t, const train_overrides& o)
{
    const auto p = stargan::preset_options(o.preset);
    t.g_lr = o.g_lr.value_or(p.g_lr);
    t.d_lr = o.d_lr.value_or(p.d_lr);
    if (o.lr >= 0) t.g_lr = t.d_lr = o.lr;
    t.lambda_cls = o.lambda_cls.value_or(p.lambda_cls);
    t.lambda_rec = o.lambda_rec.value_or(p.lambda_rec);
    t.lambda_gp = o.lambda_gp.value_or(p.lambda_gp);
    t.n_critic = o.n_critic.value_or(p.n_critic);
    t.beta1 = o.beta1.value_or(p.beta1);
    t.beta2 = o.beta2.value_or(p.beta2);
    t.decay_start = o.decay_start.value_or(p.decay_start);
    t.residual = o.residual.value_or(p.residual);
    t.lambda_id = o.lambda_id.value_or(p.lambda_id);
    t.lambda_pair = o.lambda_pair.value_or(p.lambda_pair);
    t.lambda_delta = o.lambda_delta.value_or(p.lambda_delta);
    t.ema = o.ema.value_or(p.ema);
    t.neutral_share = o.neutral_share.value_or(p.neutral_share);
    t.range = o.range.value_or(p.range);
    t.amplitude = o.amplitude.value_or(p.amplitude);
    t.amplitude_anchor = o.amplitude_anchor.value_or(p.amplitude_anchor);
    t.amplitude_estimator = o.amplitude_estimator.value_or(p.amplitude_estimator);
    t.augment = o.augment.value_or(p.augment);
    t.gate_folds = o.gate_folds.value_or(p.gate_folds);
    t.gate_prior = o.gate_prior.value_or(p.gate_prior);
    t.gate_margin = o.gate_margin.value_or(p.gate_margin);
    t.gate_posterior = o.gate_posterior.value_or(p.gate_posterior);
    t.gate_auto_margin = o.gate_auto_margin.value_or(p.gate_auto_margin);
    t.gate_guard = o.gate_guard.value_or(p.gate_guard);
    t.gate_iters_scale = o.gate_iters_scale.value_or(p.gate_iters_scale);
    t.gate_centre = o.gate_centre.value_or(p.gate_centre);
    t.gate_prior_full = o.gate_prior_full.value_or(p.gate_prior_full);
    t.tempo_shrink = o.tempo_shrink.value_or(p.tempo_shrink);
    t.tempo_basis = o.tempo_basis.value_or(p.tempo_basis);
    t.tempo_neighbours = o.tempo_neighbours.value_or(p.tempo_neighbours);
    t.lag = o.lag.value_or(p.lag);
    t.validate();
}

}  // namespace handemo::cli
