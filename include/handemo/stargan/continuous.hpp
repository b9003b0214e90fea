// Continuous emotion control of the StarGAN transfer: a target anywhere on the circumplex (valence, arousal in the
// unit disc), or one that moves over the clip, instead of one of the model's discrete emotions. Every part of the
// discrete transfer that is per emotion -- the learned tempo and amplitude, G's change, the change gate's weights
// and the posture prior -- becomes a function of the point through circumplex_interpolation's weights over the
// model's labels (motion/circumplex.hpp, neutral at its own point):
//
//     keyframes(p) = A_p( sum_l w_l(p) K_l ),  tempo(p) = sum_l w_l(p) tempo_l / tempo_source,
//     amplitude(p) = sum_l w_l(p) amplitude_l
//
// (the rates linearly, rate_blend::linear; rate_blend::geometric blends them as exp(sum_l w_l(p) log f_l))
//
// where K_l is the discrete transfer's keyframes to label l before its amplitude stage (the input's keyframes
// plus G's change gated by l's posture, motion and prior weights, shifted by l's joint lag when the model has one,
// emotion_model::combine()) and A_p scales the
// excursions by amplitude(p). The weights are exactly one-hot at a label's point, so there the sums reduce to one
// term multiplied by 1 and the output is the discrete transfer bit for bit. docs/continuous.md gives the design.
#pragma once

#include <handemo/core/error.hpp>
#include <handemo/motion/circumplex.hpp>
#include <handemo/motion/keyframes.hpp>
#include <handemo/stargan/capture.hpp>
#include <handemo/stargan/transfer.hpp>

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>
#include <vector>

namespace handemo::stargan {

/// @brief How the continuous control blends the labels' rates (the tempo and amplitude factors) between their points.
enum class rate_blend {
    linear,     ///< sum_l w_l f_l
    geometric,  ///< exp(sum_l w_l log f_l): the log of the rate moves linearly with the weights
};

/// The blend continuous_control uses when none is given.
inline constexpr rate_blend default_rate_blend = rate_blend::linear;

/// @brief "linear" or "geometric".
inline const char* rate_blend_name(rate_blend b) noexcept { return b == rate_blend::geometric ? "geometric" : "linear"; }

/// @brief The blend called `name` ("linear" or "geometric"). @throws value_error naming `what` and the known names.
inline rate_blend parse_rate_blend(std::string_view name, const std::string& what = "rate blend")
{
    if (name == "linear") return rate_blend::linear;
    if (name == "geometric") return rate_blend::geometric;
    throw value_error(what + ": unknown rate blend '" + std::string(name) + "', expected linear or geometric");
}

/// @brief The blend of per-label rates `f` (one per domain, each positive) with weights `w`: sum_l w_l f_l, or
/// exp(sum_l w_l log f_l). A weight of exactly 1 gives that label's rate itself under both blends (the labels'
/// points reproduce the discrete transfer bit for bit). `what` names the rates in errors.
/// @throws value_error for a rate that is not positive and finite under the geometric blend.
inline double blend_rates(const std::vector<double>& f, const std::vector<double>& w, rate_blend b, const char* what)
{
    double s = 0;
    for (std::size_t d = 0; d < w.size(); ++d) {
        if (w[d] == 0) continue;
        if (b == rate_blend::linear) {
            s += w[d] * f[d];
            continue;
        }
        if (!(f[d] > 0) || !std::isfinite(f[d]))
            throw value_error(std::string("continuous transfer: the ") + what + " factor of label " + std::to_string(d) + " is " +
                              std::to_string(f[d]) + ", which a geometric blend cannot take (expected positive and finite)");
        if (w[d] == 1.0) return f[d];
        s += w[d] * std::log(f[d]);
    }
    return b == rate_blend::linear ? s : std::exp(s);
}

/// @brief The discrete transfers of one input to the labels a continuous target needs, before their amplitude
/// stage (emotion_model::combine() with the amplitude left at 1): what every point blends.
struct label_keyframes {
    std::vector<handemo::keyframes<dynamic_keyframes>> keys;  ///< [domains]; empty for a label not computed
    std::vector<bool> computed;                               ///< [domains]
    std::size_t source = 0;                                   ///< the input's domain
    std::size_t clamped_values = 0;                           ///< input keyframe angles G saw clamped by Eq. 3 (0: G not run)
    std::vector<double> tempo;  ///< [domains] the input's tempo factors (emotion_model::input_tempo())
};

/// @brief A continuous transfer: the output and the weights it used.
struct continuous_result : transfer_result {
    /// the weights per label (the model's domain order): one row for a point, one row per keyframe for a curve
    std::vector<std::vector<double>> weights;
    handemo::keyframes<dynamic_keyframes> keys;  ///< the output's keyframes (after the amplitude stage)
};

/// @brief A model's discrete emotions made continuous over the circumplex (see the header comment).
/// Thread safety: as the model's const members (the control holds a reference to the model and its own
/// immutable interpolation).
class continuous_control {
public:
    /// @param model the StarGAN model (it must outlive the control)
    /// @param table the circumplex coordinates of (at least) every domain of the model; `what` names it in errors
    /// @throws value_error naming a domain the table has no point for, or a table whose points the interpolation
    /// refuses (a label on neutral's point, two on one ray from it).
    continuous_control(const emotion_model& model, const circumplex_table& table, const std::string& what = "circumplex table")
        : continuous_control(model, table, default_rate_blend, what)
    {
    }

    /// @brief The control with the rates (tempo and amplitude factors) blended by `rates`.
    continuous_control(const emotion_model& model, const circumplex_table& table, rate_blend rates, const std::string& what = "circumplex table")
        : model_(&model), interp_(points_of(model, table, what), model.domain(model.info().neutral)), rates_(rates)
    {
    }

    const emotion_model& model() const noexcept { return *model_; }
    rate_blend rates() const noexcept { return rates_; }
    const circumplex_interpolation& interpolation() const noexcept { return interp_; }

    /// @brief The weights of a point, one per domain. @throws value_error outside the unit circle.
    std::vector<double> weights(double valence, double arousal) const { return interp_.weights(valence, arousal); }

    /// @brief The discrete transfers of `in` to the domains whose entry of `needed` is not zero (every domain when
    /// `needed` is empty), before their amplitude stage, with the caller's workspace.
    /// @throws what emotion_model::parts() throws (skeleton, unknown source).
    void prepare(const clip& in, std::optional<std::string_view> source, const std::vector<double>& needed, label_keyframes& out,
                 emotion_model::workspace& ws) const
    {
        const auto& info = model_->info();
        const std::size_t D = info.domains.size();
        out.keys.resize(D);
        out.computed.assign(D, false);
        out.clamped_values = 0;
        out.source = model_->domain(source ? *source : std::string_view(info.neutral));
        out.tempo = model_->input_tempo(in);
        transfer_parts p;
        for (std::size_t d = 0; d < D; ++d) {
            if (!needed.empty() && needed[d] == 0) continue;
            model_->gated_parts_into(in, info.domains[d], source, ws, p);  // G only where the gate keeps some of its change
            p.amplitude = 1.0;  // the amplitude stage comes after the blend
            model_->combine_gated_into(p, out.keys[d]);
            out.computed[d] = true;
            if (p.run_generator) out.clamped_values = p.clamped_values;
        }
    }

    /// @brief prepare() for every domain with a fresh workspace.
    label_keyframes prepare(const clip& in, std::optional<std::string_view> source = {}) const
    {
        label_keyframes out;
        auto ws = model_->make_workspace();
        prepare(in, source, {}, out, ws);
        return out;
    }

    /// @brief The duration factor of weights `w` for prepared label keyframes: the blend (rates()) of the input's tempo
    /// factors (emotion_model::input_tempo(): the learned ones, or its nearest training contents') over tempo_source.
    double tempo(const label_keyframes& lk, const std::vector<double>& w) const
    {
        const auto& f = lk.tempo.empty() ? model_->info().tempo : lk.tempo;
        return blend_rates(f, w, rates_, "tempo") / f[lk.source];
    }

    /// @brief The excursion factor of weights `w`: the blend (rates()) of the labels' amplitude factors (1 unless
    /// the model has the amplitude stage).
    double amplitude(const std::vector<double>& w) const
    {
        if (!model_->amplitude_stage()) return 1.0;
        return blend_rates(model_->info().amplitude, w, rates_, "amplitude");
    }

    /// @brief The output keyframes of a point with weights `w` from prepared label keyframes: the weighted sum,
    /// then the amplitude stage at amplitude(w), then the model's joint limits (emotion_model::clamp_to_limits()).
    /// @throws value_error when a label with a weight was not prepared.
    handemo::keyframes<dynamic_keyframes> blend(const label_keyframes& lk, const std::vector<double>& w) const
    {
        handemo::keyframes<dynamic_keyframes> out;
        blend_into(lk, w, out);
        return out;
    }

    /// @brief Transfers `in` to the point (valence, arousal): the discrete transfer at a label's point (bit for bit),
    /// a blend of at most three labels' transfers elsewhere (neutral and the two bracketing the point).
    /// @throws value_error for a point outside the unit circle; what emotion_model::transfer() throws.
    continuous_result transfer(const clip& in, double valence, double arousal, std::optional<std::string_view> source = {}) const
    {
        const auto w = weights(valence, arousal);
        label_keyframes lk;
        auto ws = model_->make_workspace();
        prepare(in, source, w, lk, ws);
        return finish(in, lk, w);
    }

    /// @brief transfer() from prepared label keyframes (prepare() of the same clip, with every label the weights
    /// of this point need): many points of one input cost one G run per label.
    continuous_result transfer(const clip& in, const label_keyframes& lk, double valence, double arousal) const
    {
        return finish(in, lk, weights(valence, arousal));
    }

    /// @brief Transfers `in` along a target that moves over the clip: keyframe k takes the weights of the curve at
    /// its time in the input (seconds from the first frame), the amplitude stage scales each keyframe's excursion
    /// by its own factor, and the tempo warps time frame by frame (each input frame lasts its own tempo factor,
    /// the output's frames evenly spaced over the warped duration).
    /// @throws value_error for a curve without points; what transfer() throws.
    continuous_result transfer(const clip& in, const va_curve& curve, std::optional<std::string_view> source = {}) const
    {
        if (curve.size() == 0) throw value_error("continuous transfer: the curve has no points");
        const std::size_t K = model_->keyframes(), N = in.frames, D = model_->info().domains.size();
        if (N < 2) throw value_error("continuous transfer: input " + in.skel.name + " has " + std::to_string(N) + " frames, expected at least 2");
        const double dt = 1.0 / in.fps;
        // the weights of every keyframe, and which labels any of them needs
        std::vector<std::vector<double>> wk(K);
        std::vector<double> needed(D, 0.0);
        for (std::size_t k = 0; k < K; ++k) {
            const double t = static_cast<double>(k) * static_cast<double>(N - 1) / static_cast<double>(K - 1) * dt;
            const auto [v, a] = curve.at(t);
            wk[k] = weights(v, a);
            for (std::size_t d = 0; d < D; ++d) needed[d] += wk[k][d];
        }
        label_keyframes lk;
        auto ws = model_->make_workspace();
        prepare(in, source, needed, lk, ws);
        continuous_result r;
        // per keyframe: the weighted sum of the labels' keyframes
        const std::size_t C = model_->joints() * 3;
        bool first = true;
        for (std::size_t d = 0; d < D; ++d) {
            if (!lk.computed[d]) continue;
            if (first) {
                r.keys = lk.keys[d];
                std::fill(r.keys.angles.begin(), r.keys.angles.end(), 0.0);
                first = false;
            }
            for (std::size_t k = 0; k < K; ++k)
                for (std::size_t ch = 0; ch < C; ++ch) r.keys.angles[k * C + ch] += wk[k][d] * lk.keys[d].angles[k * C + ch];
        }
        // the amplitude stage, each keyframe's excursion about the channel's anchor scaled by its own factor
        std::vector<double> amp(K);
        for (std::size_t k = 0; k < K; ++k) amp[k] = amplitude(wk[k]);
        for (std::size_t ch = 0; ch < C; ++ch) {
            const double m = excursion_anchor(r.keys, ch, model_->info().amplitude_anchor);
            for (std::size_t k = 0; k < K; ++k) r.keys.angles[k * C + ch] = m + amp[k] * (r.keys.angles[k * C + ch] - m);
        }
        r.limited_values = model_->clamp_to_limits(r.keys);
        // the time warp: input frame i lasts tempo(i) frames of output; T(i) the output time at input frame i
        std::vector<double> T(N, 0.0), w;
        double prev = 0;
        for (std::size_t i = 0; i < N; ++i) {
            const auto [v, a] = curve.at(static_cast<double>(i) * dt);
            interp_.weights_into(v, a, w);
            const double tau = tempo(lk, w);
            if (i > 0) T[i] = T[i - 1] + 0.5 * (prev + tau);
            prev = tau;
        }
        const double total = T[N - 1];
        const std::size_t M = emotion_model::output_frames(N, total / static_cast<double>(N - 1));
        std::vector<double> positions(M), input_frame(M);
        std::size_t i = 0;
        for (std::size_t f = 0; f < M; ++f) {
            const double u = static_cast<double>(f) * total / static_cast<double>(M - 1);
            while (i + 2 < N && T[i + 1] < u) ++i;
            const double span = T[i + 1] - T[i];
            const double x = static_cast<double>(i) + (span > 0 ? std::clamp((u - T[i]) / span, 0.0, 1.0) : 0.0);
            input_frame[f] = x;
            positions[f] = std::min(x * static_cast<double>(K - 1) / static_cast<double>(N - 1), static_cast<double>(K - 1));
        }
        reconstruct_at(r.keys, in.skel, positions, in.fps, r.motion);
        model_->clamp_to_limits(r.motion);
        // position channels (a body's root) follow the same warp
        const std::size_t J3 = in.skel.size() * 3;
        r.motion.positions.assign(M * J3, 0.0);
        for (std::size_t f = 0; f < M; ++f) {
            const auto f0 = static_cast<std::size_t>(std::floor(input_frame[f]));
            const std::size_t f1 = std::min(f0 + 1, N - 1);
            const double a = input_frame[f] - static_cast<double>(f0);
            for (std::size_t c = 0; c < J3; ++c) r.motion.positions[f * J3 + c] = (1 - a) * in.positions[f0 * J3 + c] + a * in.positions[f1 * J3 + c];
        }
        r.tempo = total / static_cast<double>(N - 1);
        double amp_mean = 0;
        for (double a : amp) amp_mean += a / static_cast<double>(K);
        r.amplitude = amp_mean / (model_->amplitude_stage() ? model_->info().amplitude[lk.source] : 1.0);
        r.clamped_values = lk.clamped_values;
        r.weights = std::move(wk);
        return r;
    }

private:
    static std::vector<label_point> points_of(const emotion_model& model, const circumplex_table& table, const std::string& what)
    {
        std::vector<label_point> pts;
        for (const auto& d : model.info().domains) pts.push_back(table.at(d, what));
        return pts;
    }

    static const handemo::keyframes<dynamic_keyframes>& need(const label_keyframes& lk, std::size_t d)
    {
        if (d >= lk.computed.size() || !lk.computed[d])
            throw value_error("continuous transfer: label " + std::to_string(d) + " has a weight but was not prepared");
        return lk.keys[d];
    }

    /// blend() into `out`; how many angles the joint limits held
    std::size_t blend_into(const label_keyframes& lk, const std::vector<double>& w, handemo::keyframes<dynamic_keyframes>& out) const
    {
        bool first = true;
        for (std::size_t d = 0; d < w.size(); ++d) {
            if (w[d] == 0) continue;
            const auto& k = need(lk, d);
            if (first) {
                out = k;
                for (auto& v : out.angles) v *= w[d];
                first = false;
            } else {
                for (std::size_t i = 0; i < out.angles.size(); ++i) out.angles[i] += w[d] * k.angles[i];
            }
        }
        if (first) throw value_error("continuous transfer: every weight is zero");
        const double a = amplitude(w);
        if (a != 1.0) scale_keyframe_excursions(out, a, model_->info().amplitude_anchor);
        return model_->clamp_to_limits(out);  // as the discrete transfer's keyframes
    }

    continuous_result finish(const clip& in, const label_keyframes& lk, const std::vector<double>& w) const
    {
        continuous_result r;
        r.limited_values = blend_into(lk, w, r.keys);
        r.tempo = tempo(lk, w);
        r.amplitude = amplitude(w) / (model_->amplitude_stage() ? model_->info().amplitude[lk.source] : 1.0);
        const std::size_t frames = emotion_model::output_frames(in.frames, r.tempo);
        reconstruct_into(r.keys, in.skel, frames, in.fps, r.motion);
        model_->clamp_to_limits(r.motion);
        stretch_positions_into(in, frames, r.motion.positions);
        r.clamped_values = lk.clamped_values;
        r.weights = {w};
        return r;
    }

    const emotion_model* model_;
    circumplex_interpolation interp_;
    rate_blend rates_ = default_rate_blend;
};

/// @brief A continuous transfer of a capture of any skeleton (transfer_capture() with a point or a curve
/// instead of an emotion): retargeted onto the model's skeleton when needed, transferred there, written back.
/// The detail layer is per emotion and is not blended: `o.detail` is refused.
/// @throws value_error for o.detail; what transfer_capture() and continuous_control::transfer() throw.
template <class Target>
capture_result transfer_capture(const continuous_control& control, const clip& in, const Target& target, std::optional<std::string_view> source = {},
                                const capture_options& o = {})
{
    if (o.detail) throw value_error("transfer: the detail layer is per emotion: it is not available with a continuous target");
    return transfer_capture_with(control.model(), in, o, [&](const clip& c) -> transfer_result {
        if constexpr (std::is_same_v<Target, va_curve>)
            return control.transfer(c, target, source);
        else
            return control.transfer(c, target.first, target.second, source);
    });
}

/// @brief transfer_capture() of `in` at each of `points` (va_grid()'s, say) with one prepare(): G runs once per label
/// on the clip the model sees (retargeted when needed), then each point costs one blend. out[k] is the motion of
/// transfer_capture(control, in, points[k], source, o).
/// @throws value_error for o.detail or a point outside the unit circle; what transfer_capture() throws.
inline std::vector<clip> transfer_capture_points(const continuous_control& control, const clip& in, const std::vector<std::pair<double, double>>& points,
                                                 std::optional<std::string_view> source = {}, const capture_options& o = {})
{
    if (o.detail) throw value_error("transfer: the detail layer is per emotion: it is not available with a continuous target");
    for (const auto& [v, a] : points) circumplex_interpolation::check_point(v, a, "continuous transfer");
    std::optional<label_keyframes> lk;  // prepared on the first point's clip: every point's is the same
    std::vector<clip> out;
    out.reserve(points.size());
    for (const auto& p : points)  // not a structured binding: clang 14 cannot capture one in the lambda
        out.push_back(transfer_capture_with(control.model(), in, o, [&](const clip& c) -> transfer_result {
                          if (!lk) lk = control.prepare(c, source);
                          return control.transfer(c, *lk, p.first, p.second);
                      }).motion);
    return out;
}

}  // namespace handemo::stargan
