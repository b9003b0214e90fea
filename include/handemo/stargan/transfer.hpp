// Emotion transfer of new motions with a trained model (Section 3.4 of the hand paper): keyframes ->
// Eq. 3 image -> G(image, target) -> image -> Eq. 6 keyframes -> full-rate motion by interpolation.
// Tempo: the output lasts the input's duration times tempo[target] / tempo[source] (duration ratios
// to neutral learned from the training data by tempo_fit(), see dataset.hpp), because time-normalised keyframes cannot carry
// Table 1's "fast" and "slow"; with tempo neighbours (train_options::tempo_neighbours, tempo_neighbours.hpp) the
// factors are those of the training contents nearest the input. Position channels (a body's root translation) are kept from the input and
// stretched in time to the new length.
// A residual model (train_options::residual) changes the input rather than redraw it: its output image is
// x + change, and transfer adds the change to the input's own keyframe angles (change x half the channel's
// span, in degrees), so the Eq. 3 quantisation and clamping of the input never reach the output and a model
// that changes nothing returns the input's keyframes exactly.
#pragma once

#include <handemo/core/error.hpp>
#include <handemo/motion/codec.hpp>
#include <handemo/motion/hand.hpp>
#include <handemo/motion/keyframes.hpp>
#include <handemo/stargan/train.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace handemo::stargan {

/// @brief What transfer() combines, computed once: fit_change_gate() scores many gate settings on it
/// without running G again.
struct transfer_parts {
    handemo::keyframes<dynamic_keyframes> base;  ///< the input's keyframes in the model's (amplitude-normalised) space; decoded G output when not residual
    /// [K*C] G's change in degrees (residual models; empty otherwise), less the target's row of the model's
    /// posture centre at every keyframe when it has one (emotion_model::set_posture_centre())
    std::vector<double> change;
    std::vector<double> change_mean;    ///< [C] its mean over the keyframes per channel (the posture part)
    std::vector<double> prior;          ///< [C] the target's posture prior in degrees (empty when the model has none)
    /// [J] the joint lag applied before the amplitude stage, target's minus source's, in keyframe intervals (empty
    /// when the model has none; lag.hpp)
    std::vector<double> lag;
    std::size_t target = 0;
    double amplitude = 1, tempo = 1;    ///< the target's excursion scale (applied after the change) and tempo factor
    std::size_t frames = 0;             ///< output frame count
    double fps = 0;
    keyframe_pixels<dynamic_keyframes> image;  ///< G's own output image (Eq. 3 pixels); empty when G was not run (run_generator false)
    std::size_t clamped_values = 0;
    /// whether G ran: a transfer whose gate weighs G's whole change 0 for the target (the statistics setting) skips it
    bool run_generator = true;
};

/// @brief The result of one transfer.
struct transfer_result {
    clip motion;                      ///< the full-rate output clip
    /// the output's K x J motion image: the keyframes `motion` passes through, by Eq. 3 (what G itself produced,
    /// before the gate, the posture prior, the joint lag and the amplitude stage, is transfer_parts::image)
    keyframe_pixels<dynamic_keyframes> image;
    /// input keyframe angles outside the model's range, which G saw clamped by Eq. 3 (0 when G did not run; a
    /// residual model adds G's change to the unclamped angles)
    std::size_t clamped_values = 0;
    /// output keyframe angles the model's joint limits held (emotion_model::clamp_to_limits(): the transfer would
    /// have moved them past a limit of the skeleton; 0 for a skeleton without limits)
    std::size_t limited_values = 0;
    double tempo = 1.0;               ///< duration factor applied
    double amplitude = 1.0;           ///< excursion factor applied (1 unless the model learned amplitudes)
    /// what the excursions were scaled about (the model's anchor, checkpoint_info::amplitude_anchor)
    handemo::stargan::amplitude_anchor amplitude_anchor = handemo::stargan::amplitude_anchor::mean;
};

using handemo::stretch_positions;

/// @brief A trained emotion-transfer model loaded from a checkpoint, whatever its configuration.
/// Thread safety: the const members (transfer(), parts(), generate(), ...) may run on any number of threads at
/// once on one model; each call takes its scratch memory from a `workspace`, the caller's (one per thread, reused
/// across calls) or a fresh one. The mutating members (set_gate(), set_prior_posture()) must not overlap any other
/// call; they give the strong guarantee (a refused argument leaves the model as it was).
class emotion_model {
public:
    virtual ~emotion_model() = default;

    /// @brief Per-thread scratch of the generator (padded images and the packed generator's buffers): make one
    /// per thread with make_workspace() and pass it to the calls that take one; never share one between threads.
    class workspace {
    public:
        struct scratch {
            virtual ~scratch() = default;
            /// what one transfer computes on the way, kept so that the next transfer of a clip as long
            /// reuses the storage (transfer() with a workspace allocates nothing then)
            std::vector<double> unwrapped;
            keyframe_pixels<dynamic_keyframes> pixels;
            network_image<dynamic_keyframes> net, gen;
            handemo::keyframes<dynamic_keyframes> out_keys;
            transfer_parts parts;
        };
        workspace() = default;
        explicit workspace(std::unique_ptr<scratch> s) : s_(std::move(s)) {}
        scratch* get() const noexcept { return s_.get(); }

    private:
        std::unique_ptr<scratch> s_;
    };

    /// @brief Per-thread scratch of transfer_batch(): a workspace per clip of a batch and the generator's buffers
    /// for a batch (make_batch_workspace()); never shared between threads.
    class batch_workspace {
    public:
        /// what the generator of a model needs for a batch of `capacity` images
        struct generator_scratch {
            virtual ~generator_scratch() = default;
        };
        batch_workspace() = default;
        /// @brief The most clips one generator call of transfer_batch() takes.
        std::size_t capacity() const noexcept { return clips_.size(); }

    private:
        friend class emotion_model;
        std::vector<workspace> clips_;
        std::unique_ptr<generator_scratch> g_;
        std::vector<const float*> x_;
        std::vector<float*> y_;
        std::vector<std::size_t> targets_;
    };

    /// @brief A workspace for this model's generator.
    workspace make_workspace() const { return workspace(new_scratch()); }

    /// @brief A workspace for transfer_batch() with batches of `batch` clips (at least 1).
    batch_workspace make_batch_workspace(std::size_t batch) const
    {
        batch_workspace ws;
        batch = std::max<std::size_t>(batch, 1);
        for (std::size_t i = 0; i < batch; ++i) ws.clips_.push_back(make_workspace());
        ws.g_ = new_batch_scratch(batch);
        ws.x_.resize(batch), ws.y_.resize(batch), ws.targets_.resize(batch);
        return ws;
    }
    const checkpoint_info& info() const noexcept { return info_; }
    /// @brief How G computes its residual convolutions (load_model()'s algorithm; direct where winograd takes no geometry).
    virtual kernels::conv_algorithm conv_algorithm() const noexcept { return kernels::conv_algorithm::direct; }
    std::size_t joints() const noexcept { return info_.range.joints; }
    std::size_t keyframes() const noexcept { return info_.range.keyframes; }

    /// @brief Index of an emotion. @throws value_error naming it and the known ones.
    std::size_t domain(std::string_view emotion) const
    {
        for (std::size_t i = 0; i < info_.domains.size(); ++i)
            if (info_.domains[i] == emotion) return i;
        return domain_index(info_.domains, emotion, "transfer: model " + info_.source + " (" + info_.config + ")");  // throws
    }

    /// @brief Duration factor of a transfer from `source` (default: the neutral domain) to `target`:
    /// tempo[target] / tempo[source], the learned duration ratios to neutral (tempo_fit()).
    double tempo(std::string_view target, std::optional<std::string_view> source = {}) const
    {
        return info_.tempo[domain(target)] / info_.tempo[domain(source ? *source : std::string_view(info_.neutral))];
    }

    /// @brief The tempo factors [C] of an input: the learned ones (info().tempo), or with tempo neighbours
    /// (train_options::tempo_neighbours, tempo_neighbours.hpp) those of the training contents nearest the input.
    std::vector<double> input_tempo(const clip& in) const
    {
        if (info_.tempo_table.empty()) return info_.tempo;
        return info_.tempo_table.factors(tempo_descriptor(in), info_.tempo);
    }

    /// @brief Duration factor of a transfer of `in` from `source` (default: neutral) to `target`: the factors'
    /// ratio (input_tempo()), equal to tempo(target, source) for a model without tempo neighbours.
    double tempo(const clip& in, std::string_view target, std::optional<std::string_view> source = {}) const
    {
        if (info_.tempo_table.empty()) return tempo(target, source);
        const auto f = input_tempo(in);
        return f[domain(target)] / f[domain(source ? *source : std::string_view(info_.neutral))];
    }

    /// @brief Amplitude factor of a transfer from `source` (default: neutral) to `target`: amplitude[target] /
    /// amplitude[source], the learned median excursion ratios to neutral (applied when the model was trained
    /// with train_options::amplitude).
    double amplitude(std::string_view target, std::optional<std::string_view> source = {}) const
    {
        return info_.amplitude[domain(target)] / info_.amplitude[domain(source ? *source : std::string_view(info_.neutral))];
    }


    /// @brief Frame count of an output lasting `tempo` times an input of `frames` frames (at least 2).
    static std::size_t output_frames(std::size_t frames, double tempo) noexcept
    {
        return static_cast<std::size_t>(std::max(2.0, std::round(static_cast<double>(frames) * tempo)));
    }

    /// @brief Translates one K x J motion image to the target domain (G of the paper, batch 1).
    /// @throws shape_error for a wrong image size; value_error when G produces a non-finite value.
    keyframe_pixels<dynamic_keyframes> translate(const keyframe_pixels<dynamic_keyframes>& px, std::size_t target) const
    {
        workspace ws = make_workspace();
        return translate(px, target, ws);
    }

    /// @brief translate() with the caller's workspace.
    keyframe_pixels<dynamic_keyframes> translate(const keyframe_pixels<dynamic_keyframes>& px, std::size_t target, workspace& ws) const
    {
        if (px.count() != keyframes() || px.joints != joints())
            throw shape_error("transfer: model " + info_.source + ": motion image is " + std::to_string(px.count()) + "x" + std::to_string(px.joints) +
                              " (keyframes x joints), the model expects " + std::to_string(keyframes()) + "x" +
                              std::to_string(joints()));
        if (target >= info_.domains.size())
            throw value_error("transfer: model " + info_.source + ": target domain " + std::to_string(target) + " out of range (" +
                              std::to_string(info_.domains.size()) + " domains)");
        return from_network(generate(to_network(px), target, ws));
    }

    /// @brief The joint lag from `source` (default neutral) to target domain `t`, per joint in keyframe intervals,
    /// into `out` (its storage reused); empty when the model has no lag or the lags are all 0 (lag.hpp).
    void lag_of(std::size_t t, std::optional<std::string_view> source, std::vector<double>& out) const
    {
        out.clear();
        if (info_.lag.empty()) return;
        const auto& to = info_.lag[t];
        const auto& from = info_.lag[domain(source ? *source : std::string_view(info_.neutral))];
        bool any = false;
        for (std::size_t j = 0; j < to.size(); ++j) any |= to[j] != from[j];
        if (!any) return;
        out.resize(to.size());
        for (std::size_t j = 0; j < to.size(); ++j) out[j] = to[j] - from[j];
    }
    /// @brief Whether the model was trained with the amplitude stage (train_options::amplitude).
    bool amplitude_stage() const { return info_.options.is_object() && info_.options.value("amplitude", false); }

    /// @brief Whether the model's G is residual (its output is x + change).
    bool residual() const { return info_.options.is_object() && info_.options.value("residual", false); }

    /// @brief Sets the change gate of every target domain (train_options::gate_folds): the weight of G's change
    /// averaged over the keyframes (posture) and of the rest (motion), each in [0, 1]; (1, 1) is G's whole
    /// change, (0, 0) no change (a residual model then returns its input, amplitude stage and tempo aside).
    /// Only a residual model has a change to gate.
    /// @throws value_error for a wrong size, a value outside [0, 1], or a model that is not residual.
    /// `prior` (optional, one per domain in [0, 1]) weights the model's posture prior (train_options::gate_prior);
    /// a model without one (trained before it existed or without it) takes only zeros.
    void set_gate(std::vector<double> posture, std::vector<double> motion, std::vector<double> prior = {})
    {
        if (prior.empty()) prior.assign(info_.domains.size(), 0.0);
        if (prior.size() != info_.domains.size())
            throw value_error("transfer: a change gate needs one prior weight per domain (" + std::to_string(info_.domains.size()) + ")");
        for (std::size_t d = 0; d < prior.size(); ++d) {
            if (!(prior[d] >= 0 && prior[d] <= 1)) throw value_error("transfer: prior weight of domain '" + info_.domains[d] + "' is not in [0, 1]");
            if (prior[d] != 0 && info_.prior_posture.empty())
                throw value_error("transfer: model " + info_.source + " has no posture prior (trained without --gate-prior)");
        }
        if (!residual()) throw value_error("transfer: the change gate needs a residual model (" + info_.config + " is not)");
        if (posture.size() != info_.domains.size() || motion.size() != info_.domains.size())
            throw value_error("transfer: a change gate needs one posture and one motion weight per domain (" +
                              std::to_string(info_.domains.size()) + ")");
        for (std::size_t d = 0; d < posture.size(); ++d)
            if (!(posture[d] >= 0 && posture[d] <= 1) || !(motion[d] >= 0 && motion[d] <= 1))
                throw value_error("transfer: change gate of domain '" + info_.domains[d] + "' is not in [0, 1]");
        info_.gate_prior = std::move(prior);  // every check passed: the model changes only now
        info_.gate_posture = std::move(posture);
        info_.gate_motion = std::move(motion);
    }

    /// @brief Sets the posture prior (train_options::gate_prior): [domains][joints*3] degrees added, times the
    /// gate's prior weight, to every keyframe of the output in that domain (posture_prior() computes it).
    /// @throws value_error for a wrong size or a value that is not finite.
    void set_prior_posture(std::vector<std::vector<double>> prior)
    {
        check_degree_table(prior, "posture prior");
        info_.prior_posture = std::move(prior);
    }

    /// @brief Sets G's average posture per target (train_options::gate_centre): [domains][joints*3] degrees
    /// subtracted from G's change at every keyframe (so from its posture part, its mean over the keyframes, and not
    /// from the rest) before the gate weighs it; posture_centre_of() computes it. An empty table removes it (G's
    /// change as G gives it).
    /// @throws value_error for a wrong size, a value that is not finite, or a model that is not residual.
    void set_posture_centre(std::vector<std::vector<double>> centre)
    {
        if (!centre.empty()) {
            if (!residual()) throw value_error("transfer: a posture centre needs a residual model (" + info_.config + " is not)");
            check_degree_table(centre, "posture centre");
        }
        info_.posture_centre = std::move(centre);
    }

    /// @brief G's average posture per target subtracted from its change (set_posture_centre()); empty: none.
    const std::vector<std::vector<double>>& posture_centre() const noexcept { return info_.posture_centre; }

    /// @brief G on a network image [3, K, J] in [-1, 1] (float output, not quantised).
    /// @throws value_error when G produces a non-finite value.
    network_image<dynamic_keyframes> generate(const network_image<dynamic_keyframes>& net, std::size_t target) const
    {
        workspace ws = make_workspace();
        return generate(net, target, ws);
    }

    /// @brief generate() with the caller's workspace.
    /// @throws value_error also for a workspace made by another model.
    network_image<dynamic_keyframes> generate(const network_image<dynamic_keyframes>& net, std::size_t target, workspace& ws) const
    {
        network_image<dynamic_keyframes> out;
        generate_into(net, target, ws, out);
        return out;
    }

    /// @brief generate() into `out` (its storage reused; `out` must not be `net`).
    void generate_into(const network_image<dynamic_keyframes>& net, std::size_t target, workspace& ws, network_image<dynamic_keyframes>& out) const
    {
        if (net.count() != keyframes() || net.joints != joints() || net.data.size() != 3 * keyframes() * joints())
            throw shape_error("transfer: model " + info_.source + ": network image is " + std::to_string(net.count()) + "x" + std::to_string(net.joints) +
                              ", the model expects " + std::to_string(keyframes()) + "x" + std::to_string(joints()));
        if (target >= info_.domains.size())
            throw value_error("transfer: model " + info_.source + ": target domain " + std::to_string(target) + " out of range (" +
                              std::to_string(info_.domains.size()) + " domains)");
        if (!ws.get()) ws = make_workspace();
        out.count_ = net.count_;
        out.joints = net.joints;
        out.data.resize(net.data.size());
        run_generator(net.data.data(), target, out.data.data(), *ws.get());
        for (float v : out.data)
            if (!std::isfinite(v)) throw value_error("transfer: model " + info_.source + ": the generator produced a non-finite value (corrupted weights?)");
    }


    /// @brief The parts of a transfer (see transfer()).
    /// @throws shape_error when the clip's skeleton is not the model's (joint count or names).
    transfer_parts parts(const clip& in, std::string_view target, std::optional<std::string_view> source = {}) const
    {
        workspace ws = make_workspace();
        return parts(in, target, source, ws);
    }

    /// @brief parts() with the caller's workspace.
    transfer_parts parts(const clip& in, std::string_view target, std::optional<std::string_view> source, workspace& ws) const
    {
        transfer_parts r;
        parts_into(in, target, source, ws, r);
        return r;
    }

    /// @brief parts() into `r`, its storage reused (as the workspace's): no allocation when both already
    /// hold a clip as long.
    void parts_into(const clip& in, std::string_view target, std::optional<std::string_view> source, workspace& ws, transfer_parts& r) const
    {
        if (!ws.get()) ws = make_workspace();
        workspace::scratch& s = *ws.get();
        parts_before_generator(in, target, source, ws, r);
        generate_into(s.net, r.target, ws, s.gen);
        parts_after_generator(in, target, source, s, r);
    }

    /// @brief combine_into() with the model's own gate for the parts' target (info().gate_posture, gate_motion, gate_prior).
    void combine_gated_into(const transfer_parts& p, handemo::keyframes<dynamic_keyframes>& out) const
    {
        const std::size_t t = p.target;
        combine_into(p, info_.gate_posture[t], info_.gate_motion[t], info_.gate_prior.empty() ? 0.0 : info_.gate_prior[t], out);
    }

    /// @brief parts_into() for the model's own gate: G runs only when the target's gate weighs some of its change
    /// (a residual model's statistics setting weighs none; transfer_parts::run_generator says whether it ran). What
    /// transfer() and the continuous control combine with the model's gate, the same bits as parts_into().
    void gated_parts_into(const clip& in, std::string_view target, std::optional<std::string_view> source, workspace& ws,
                          transfer_parts& r) const
    {
        if (!ws.get()) ws = make_workspace();
        workspace::scratch& s = *ws.get();
        parts_before_generator(in, target, source, ws, r);
        parts_after_generator(in, target, source, s, r, generate_if_gated(ws, r));
    }

    /// @brief transfer() of many clips to one target, with G run on batches of ws.capacity() clips (each layer over
    /// the batch before the next: frozen_generator::infer_batch), one thread. out[i] is what transfer(in[i], target,
    /// source) gives, bit for bit: G computes every image of a batch as it computes it alone.
    /// @throws as transfer(), for the first clip that fails (its name in the message); `out` is valid only when the
    /// call returns normally. value_error when out is shorter than in.
    void transfer_batch(std::span<const clip> in, std::string_view target, std::optional<std::string_view> source, batch_workspace& ws,
                        std::span<transfer_result> out) const
    {
        if (out.size() < in.size())
            throw value_error("transfer: transfer_batch of " + std::to_string(in.size()) + " clips into " + std::to_string(out.size()) + " results");
        if (ws.capacity() == 0) ws = make_batch_workspace(1);
        for (std::size_t first = 0; first < in.size(); first += ws.capacity()) {
            const std::size_t count = std::min(ws.capacity(), in.size() - first);
            std::size_t with_g = 0;  // the clips whose transfer needs G (gate_uses_generator()), first in x_, y_
            for (std::size_t i = 0; i < count; ++i) {
                workspace::scratch& s = *ws.clips_[i].get();
                parts_before_generator(in[first + i], target, source, ws.clips_[i], s.parts);
                if (!gate_uses_generator(s.parts.target)) continue;
                s.gen.count_ = s.net.count_;
                s.gen.joints = s.net.joints;
                s.gen.data.resize(s.net.data.size());
                ws.x_[with_g] = s.net.data.data();
                ws.y_[with_g] = s.gen.data.data();
                ws.targets_[with_g] = s.parts.target;
                ++with_g;
            }
            if (with_g) run_generator_batch(ws.x_.data(), ws.targets_.data(), ws.y_.data(), with_g, *ws.g_);
            for (std::size_t i = 0; i < count; ++i) {
                workspace::scratch& s = *ws.clips_[i].get();
                const bool g = gate_uses_generator(s.parts.target);
                if (g)
                    for (float v : s.gen.data)
                        if (!std::isfinite(v)) throw value_error("transfer: model " + info_.source + ": the generator produced a non-finite value (corrupted weights?)");
                parts_after_generator(in[first + i], target, source, s, s.parts, g);
                finish_transfer(in[first + i], target, source, s, out[first + i]);
            }
        }
    }

private:
    /// A [domains][joints*3] table of finite degrees (set_prior_posture(), set_posture_centre()), named `what` in errors.
    void check_degree_table(const std::vector<std::vector<double>>& table, const char* what) const
    {
        if (table.size() != info_.domains.size())
            throw value_error(std::string("transfer: a ") + what + " needs one row per domain (" + std::to_string(info_.domains.size()) + ")");
        for (const auto& row : table) {
            if (row.size() != joints() * 3)
                throw value_error(std::string("transfer: a ") + what + " row has " + std::to_string(row.size()) + " channels, expected " +
                                  std::to_string(joints() * 3));
            for (double v : row)
                if (!std::isfinite(v)) throw value_error(std::string("transfer: a ") + what + " value is not finite");
        }
    }

    /// parts_into() up to G: the input's keyframes in the model's space, its network image in s.net, the target.
    void parts_before_generator(const clip& in, std::string_view target, std::optional<std::string_view> source, workspace& ws,
                                transfer_parts& r) const
    {
        check_skeleton(in.skel);
        in.validate("transfer: input");
        if (!ws.get()) ws = make_workspace();
        workspace::scratch& s = *ws.get();
        extract_keyframes_into<dynamic_keyframes>(in, r.base, s.unwrapped, keyframes());
        keyframes_before_generator(target, source, s, r);
    }

    /// parts_before_generator() from the input's keyframes, already in r.base.
    void keyframes_before_generator(std::string_view target, std::optional<std::string_view> source, workspace::scratch& s,
                                    transfer_parts& r) const
    {
        auto& kf = r.base;
        const bool amp = amplitude_stage();
        // a model trained with the amplitude stage works in the amplitude-normalised space (prepare_data)
        const double a_src = info_.amplitude[domain(source ? *source : std::string_view(info_.neutral))];
        if (amp) scale_keyframe_excursions(kf, 1.0 / a_src, info_.amplitude_anchor);
        const std::size_t C = joints() * 3;
        r.clamped_values = 0;
        for (std::size_t i = 0; i < kf.angles.size(); ++i) r.clamped_values += info_.range.contains(kf.angles[i], i % C) ? 0 : 1;
        encode_into(kf, info_.range, s.pixels);
        to_network_into(s.pixels, s.net);
        r.target = domain(target);
    }

    /// parts_into() after G (its output in s.gen when `ran`): the change or the decoded keyframes, amplitude, tempo, length.
    void parts_after_generator(const clip& in, std::string_view target, std::optional<std::string_view> source, workspace::scratch& s,
                               transfer_parts& r, bool ran = true) const
    {
        keyframes_after_generator(source, s, r, ran);
        r.tempo = tempo(in, target, source);
        r.frames = output_frames(in.frames, r.tempo);
        r.fps = in.fps;
    }

    /// parts_after_generator() but the tempo and the length, which read the input clip. Without G (`ran` false, a
    /// residual model only) the parts hold no change and no image.
    void keyframes_after_generator(std::optional<std::string_view> source, workspace::scratch& s, transfer_parts& r, bool ran) const
    {
        auto& kf = r.base;
        const std::size_t C = joints() * 3;
        const bool amp = amplitude_stage();
        r.run_generator = ran;
        r.change.clear();
        r.change_mean.clear();
        r.prior.clear();
        if (ran) from_network_into(s.gen, r.image);
        if (!ran) {
            r.image.values.clear();
            // what a run of G fills, sized as it would size it: a later transfer that runs G allocates nothing
            s.gen.data.resize(s.net.data.size());
            r.image.values.reserve(s.net.data.size());
            r.change.reserve(kf.angles.size());
            r.change_mean.reserve(C);
            if (!info_.prior_posture.empty()) r.prior.assign(info_.prior_posture[r.target].begin(), info_.prior_posture[r.target].end());
        } else if (residual()) {
            // angle-space residual: input angles + G's change (network units x degrees per unit of the channel)
            const std::size_t plane = keyframes() * joints();
            r.change.resize(kf.angles.size());
            for (std::size_t p = 0; p < plane; ++p)
                for (std::size_t c = 0; c < 3; ++c) {
                    const std::size_t ch = (p % joints()) * 3 + c;
                    r.change[p * 3 + c] = double(s.gen.data[c * plane + p] - s.net.data[c * plane + p]) * info_.range.half_span(ch);
                }
            r.change_mean.assign(C, 0.0);
            for (std::size_t ch = 0; ch < C; ++ch) {
                for (std::size_t k = 0; k < keyframes(); ++k) r.change_mean[ch] += r.change[k * C + ch];
                r.change_mean[ch] /= static_cast<double>(keyframes());
            }
            if (!info_.posture_centre.empty()) {
                // G's posture about its own average for this target: the posture part loses it, the motion part is unchanged
                const auto& centre = info_.posture_centre[r.target];
                for (std::size_t ch = 0; ch < C; ++ch) {
                    r.change_mean[ch] -= centre[ch];
                    for (std::size_t k = 0; k < keyframes(); ++k) r.change[k * C + ch] -= centre[ch];
                }
            }
            if (!info_.prior_posture.empty()) r.prior.assign(info_.prior_posture[r.target].begin(), info_.prior_posture[r.target].end());
        } else {
            decode_into(r.image, info_.range, kf);
        }
        lag_of(r.target, source, r.lag);
        // back from the normalised space: the target's excursions (net: amplitude[target] / amplitude[source])
        r.amplitude = amp ? info_.amplitude[r.target] : 1.0;
    }

    bool gate_uses_generator(std::size_t t) const noexcept
    {
        return !residual() || info_.gate_posture[t] != 0.0 || info_.gate_motion[t] != 0.0;
    }

    /// G on the workspace's network image (s.net into s.gen) when the gate of r.target uses it; whether it ran.
    bool generate_if_gated(workspace& ws, const transfer_parts& r) const
    {
        if (!gate_uses_generator(r.target)) return false;
        generate_into(ws.get()->net, r.target, ws, ws.get()->gen);
        return true;
    }

public:
    /// @brief Whether transfer() to `target` runs G: not when the model is residual and its gate weighs both parts
    /// of G's change 0 for the target (the statistics setting), since none of it would reach the output.
    /// @throws value_error for an unknown emotion.
    bool uses_generator(std::string_view target) const { return gate_uses_generator(domain(target)); }

private:

public:
    /// @brief The output keyframes of `p` with a change gate (posture, motion, prior weights; see set_gate()), then
    /// the joint lag and the amplitude stage. (1, 1, 0) is G's whole change, (0, 0, 0) the input with the lag and the
    /// amplitude stage. Not residual: G's output. G's change is left out where both its weights are 0, and is
    /// absent from parts made without G (transfer_parts::run_generator false).
    handemo::keyframes<dynamic_keyframes> combine(const transfer_parts& p, double posture, double motion, double prior) const
    {
        handemo::keyframes<dynamic_keyframes> out;
        combine_into(p, posture, motion, prior, out);
        return out;
    }

    /// @brief combine() into `out`, its storage reused.
    void combine_into(const transfer_parts& p, double posture, double motion, double prior, handemo::keyframes<dynamic_keyframes>& out) const
    {
        out = p.base;
        const std::size_t C = joints() * 3;
        if (!p.change.empty() && (posture != 0.0 || motion != 0.0)) {
            if (posture == 1.0 && motion == 1.0) {
                for (std::size_t i = 0; i < p.change.size(); ++i) out.angles[i] += p.change[i];
            } else {
                // the change gate: posture (the change's mean over the keyframes) and motion (the rest) weighted apart
                for (std::size_t k = 0; k < keyframes(); ++k)
                    for (std::size_t ch = 0; ch < C; ++ch) {
                        const double m = p.change_mean[ch];
                        out.angles[k * C + ch] += posture * m + motion * (p.change[k * C + ch] - m);
                    }
            }
        }
        if (prior != 0.0 && !p.prior.empty())
            for (std::size_t k = 0; k < keyframes(); ++k)
                for (std::size_t ch = 0; ch < C; ++ch) out.angles[k * C + ch] += prior * p.prior[ch];
        if (!p.lag.empty()) shift_joints(out, p.lag);
        if (p.amplitude != 1.0) scale_keyframe_excursions(out, p.amplitude, info_.amplitude_anchor);
    }

    /// @brief The full-rate output clip of `p` (the parts of `in`) with a change gate: combine(), then the
    /// keyframe spline at the target's tempo. transfer() is finish() with the model's gate.
    clip finish(const clip& in, const transfer_parts& p, double posture, double motion, double prior) const
    {
        auto kf = combine(p, posture, motion, prior);
        clamp_to_limits(kf);
        clip out = reconstruct(kf, in.skel, p.frames, in.fps);
        clamp_to_limits(out);
        return out;
    }

    /// @brief Every learned part of the model but G, each at its learned setting: the input's keyframes with the
    /// amplitude stage (when the model was trained with it), the posture prior at full weight (when the model has
    /// one), the joint lag (when it has one) and the target's tempo; no G, no detail layer. For a residual model this is finish(in, parts(in,
    /// target), 0, 0, 1) (G's change weighted 0, the prior 1) without running G: what a user gets without a
    /// network, the bar G has to clear (the evaluation's `statistics` row).
    /// @throws shape_error when the clip's skeleton is not the model's; value_error for an unknown emotion.
    transfer_result statistics(const clip& in, std::string_view target, std::optional<std::string_view> source = {}) const
    {
        check_skeleton(in.skel);
        in.validate("transfer: input");
        const std::size_t t = domain(target);
        const bool amp = amplitude_stage();
        auto kf = extract_keyframes<dynamic_keyframes>(in, keyframes());
        // the order of parts() and combine(): into the amplitude-normalised space, the prior, back out at the target's
        if (amp) scale_keyframe_excursions(kf, 1.0 / info_.amplitude[domain(source ? *source : std::string_view(info_.neutral))], info_.amplitude_anchor);
        if (!info_.prior_posture.empty()) {
            const std::size_t C = joints() * 3;
            for (std::size_t k = 0; k < keyframes(); ++k)
                for (std::size_t ch = 0; ch < C; ++ch) kf.angles[k * C + ch] += 1.0 * info_.prior_posture[t][ch];
        }
        std::vector<double> lag;
        lag_of(t, source, lag);
        if (!lag.empty()) shift_joints(kf, lag);
        if (amp && info_.amplitude[t] != 1.0) scale_keyframe_excursions(kf, info_.amplitude[t], info_.amplitude_anchor);
        transfer_result r;
        r.limited_values = clamp_to_limits(kf);
        encode_into(kf, info_.range, r.image);
        r.tempo = tempo(in, target, source);
        r.amplitude = amp ? amplitude(target, source) : 1.0;
        r.amplitude_anchor = info_.amplitude_anchor;
        const std::size_t frames = output_frames(in.frames, r.tempo);
        r.motion = reconstruct(kf, in.skel, frames, in.fps);
        clamp_to_limits(r.motion);
        r.motion.positions = stretch_positions(in, frames);
        return r;
    }

    /// @brief Transfers a clip to `target` emotion (source emotion defaults to the neutral domain).
    /// @throws shape_error when the clip's skeleton is not the model's (joint count or names).
    transfer_result transfer(const clip& in, std::string_view target, std::optional<std::string_view> source = {}) const
    {
        workspace ws = make_workspace();
        return transfer(in, target, source, ws);
    }

    /// @brief transfer() with the caller's workspace (one per thread, reused across calls).
    transfer_result transfer(const clip& in, std::string_view target, std::optional<std::string_view> source, workspace& ws) const
    {
        transfer_result r;
        transfer(in, target, source, ws, r);
        return r;
    }

    /// @brief transfer() into `out` with the caller's workspace: after the first call for a given clip length
    /// (and skeleton), with the same workspace and `out`, a transfer allocates nothing. `out` is valid only
    /// when the call returns normally.
    void transfer(const clip& in, std::string_view target, std::optional<std::string_view> source, workspace& ws, transfer_result& out) const
    {
        if (!ws.get()) ws = make_workspace();
        workspace::scratch& s = *ws.get();
        gated_parts_into(in, target, source, ws, s.parts);
        finish_transfer(in, target, source, s, out);
    }

    /// @brief transfer() of an input given by its keyframes alone (the model's K x J, in degrees; a motion image
    /// decoded by Eq. 6, for one): the output's keyframes, before the spline. The same steps as transfer() (the
    /// amplitude stage, G, the model's gate, the posture prior, the joint lag); the output lasts tempo(target,
    /// source) times the input (no clip to read tempo neighbours from).
    /// @throws shape_error for keyframes of another count or joint count; value_error for an angle that is not
    ///         finite or an unknown emotion.
    handemo::keyframes<dynamic_keyframes> transfer_keyframes(const handemo::keyframes<dynamic_keyframes>& kf, std::string_view target,
                                                            std::optional<std::string_view> source = {}) const
    {
        if (kf.count() != keyframes() || kf.joints != joints() || kf.angles.size() != keyframes() * joints() * 3)
            throw shape_error("transfer: model " + info_.source + ": keyframes are " + std::to_string(kf.count()) + "x" +
                              std::to_string(kf.joints) + " (keyframes x joints), the model expects " + std::to_string(keyframes()) +
                              "x" + std::to_string(joints()));
        for (std::size_t i = 0; i < kf.angles.size(); ++i)
            if (!std::isfinite(kf.angles[i]))
                throw value_error("transfer: keyframe " + std::to_string(i / (joints() * 3)) + ", joint '" +
                                  info_.joint_names[(i / 3) % joints()] + "': angle is not finite");
        workspace ws = make_workspace();
        workspace::scratch& s = *ws.get();
        s.parts.base = kf;
        keyframes_before_generator(target, source, s, s.parts);
        keyframes_after_generator(source, s, s.parts, generate_if_gated(ws, s.parts));
        combine_gated_into(s.parts, s.out_keys);
        clamp_to_limits(s.out_keys);
        return s.out_keys;
    }

private:
    /// transfer() after parts_into(): the gate, the spline at the target's tempo, the positions.
    void finish_transfer(const clip& in, std::string_view target, std::optional<std::string_view> source, workspace::scratch& s,
                         transfer_result& out) const
    {
        const transfer_parts& p = s.parts;
        combine_gated_into(p, s.out_keys);
        out.limited_values = clamp_to_limits(s.out_keys);
        reconstruct_into(s.out_keys, in.skel, p.frames, in.fps, out.motion);
        clamp_to_limits(out.motion);
        out.clamped_values = p.run_generator ? p.clamped_values : 0;
        encode_into(s.out_keys, info_.range, out.image);
        out.amplitude = amplitude_stage() ? amplitude(target, source) : 1.0;
        out.amplitude_anchor = info_.amplitude_anchor;
        out.tempo = p.tempo;
        stretch_positions_into(in, p.frames, out.motion.positions);
    }

public:
    /// @brief Whether the checkpoint carries the detail layer (checkpoints written before it existed do not).
    bool has_detail() const noexcept { return info_.detail.has_value(); }

    /// @brief `out`, a transfer of `in` to `target` (transfer()), with the detail layer learned from the model's
    /// training clips (motion/detail_layer.hpp): the input's own full-rate detail, played back and scaled by the
    /// target's statistics against the source's, zero at the output's keyframes, within the model's joint limits (clamp_to_limits()).
    /// @throws value_error when the model has no detail layer or no statistics for the source or the target.
    clip add_detail(const clip& out, const clip& in, std::string_view target, std::optional<std::string_view> source = {}) const
    {
        if (!info_.detail)
            throw value_error("transfer: model " + info_.source + " has no detail layer (trained before it existed): train it again");
        clip r = info_.detail->apply(out, in, std::string(source ? *source : std::string_view(info_.neutral)), std::string(target));
        clamp_to_limits(r);  // the detail keeps the joint limits, as the transfer does
        return r;
    }

    /// @brief The skeleton the model was trained on: stored in the checkpoint, or handemo's hand when the model's
    /// joints are the hand's (a checkpoint written before the skeleton was stored).
    /// @throws value_error for an older checkpoint of another skeleton.
    skeleton model_skeleton() const
    {
        if (auto s = trained_skeleton()) {
            s->name = "model " + info_.config;
            return *s;
        }
        throw value_error("transfer: model " + info_.source + " stores no skeleton (written before skeletons were stored): train it again "
                          "to transfer captures of other skeletons");
    }

    /// @brief The joint limits every output of the model keeps, per channel (joint j, axis a at 3j + a; degrees):
    /// those of the skeleton the model was trained on, or handemo's hand's when that skeleton is the hand without
    /// limits of its own (adopt_hand_limits(): a hand read from BVH, which carries none). A channel whose limits
    /// span the whole circle (a BVH body's -180..180) is not limited: -inf and inf here.
    const std::vector<double>& lower_limits() const noexcept { return lower_; }
    /// @brief The upper joint limits, as lower_limits().
    const std::vector<double>& upper_limits() const noexcept { return upper_; }

    /// @brief Replaces the joint limits the outputs keep (per channel, as lower_limits(); -inf and inf leave a channel
    /// unlimited): a rig's own limits, or none. Like set_gate(), it must not overlap any other call, and a refused
    /// argument leaves the model as it was.
    /// @throws value_error for vectors that are not joints x 3 long, a NaN, or a lower limit above its upper one
    ///         (naming the joint and axis).
    void set_limits(std::vector<double> lower, std::vector<double> upper)
    {
        const std::size_t C = joints() * 3;
        if (lower.size() != C || upper.size() != C)
            throw value_error("transfer: joint limits need " + std::to_string(C) + " values each (joints x 3), got " +
                              std::to_string(lower.size()) + " and " + std::to_string(upper.size()));
        for (std::size_t c = 0; c < C; ++c)
            if (std::isnan(lower[c]) || std::isnan(upper[c]) || lower[c] > upper[c])
                throw value_error("transfer: joint '" + info_.joint_names[c / 3] + "' axis " + "xyz"[c % 3] + ": limits " +
                                  std::to_string(lower[c]) + ".." + std::to_string(upper[c]) + " are not a range");
        lower_ = std::move(lower), upper_ = std::move(upper);
    }

    /// @brief Clamps every angle of keyframes on the model's skeleton into lower_limits()..upper_limits(); how many
    /// it moved. The transfers do this to their output keyframes, after the amplitude stage, and to the full-rate
    /// frames of their spline, so that no output leaves the skeleton's joint limits.
    /// @throws shape_error for keyframes of another joint count.
    std::size_t clamp_to_limits(handemo::keyframes<dynamic_keyframes>& kf) const
    {
        check_channels(kf.joints, kf.angles.size(), kf.count(), "keyframes", {});
        return clamp_angles(kf.angles.data(), kf.count());
    }
    /// @brief clamp_to_limits() on every frame of a clip on the model's skeleton (its rotation angles).
    /// @throws shape_error for a clip of another joint count.
    std::size_t clamp_to_limits(clip& c) const
    {
        check_channels(c.skel.size(), c.angles.size(), c.frames, "clip ", c.skel.name);
        return clamp_angles(c.angles.data(), c.frames);
    }

    /// @brief Checks a skeleton against the one the model was trained on.
    void check_skeleton(const skeleton& s) const
    {
        if (s.size() != joints())
            throw shape_error("transfer: clip " + s.name + " has " + std::to_string(s.size()) + " joints, the model " +
                              info_.source + " (" + info_.config + ") was trained on " + std::to_string(joints()) + " (wrong skeleton for the model)");
        for (std::size_t j = 0; j < s.size() && j < info_.joint_names.size(); ++j)
            if (s.joints[j].name != info_.joint_names[j])
                throw shape_error("transfer: clip " + s.name + ": joint " + std::to_string(j) + " is '" + s.joints[j].name + "', the model expects '" +
                                  info_.joint_names[j] + "' (wrong skeleton for the model " + info_.source + ")");
    }

protected:
    explicit emotion_model(checkpoint_info info) : info_(std::move(info)) { limits_from_skeleton(); }
    /// x, out: [3, K, J] in [-1, 1]; `ws` made by new_scratch() of this model.
    virtual void run_generator(const float* x, std::size_t target, float* out, workspace::scratch& ws) const = 0;
    virtual std::unique_ptr<workspace::scratch> new_scratch() const = 0;
    /// x[i], out[i]: [3, K, J] in [-1, 1], i < count <= the capacity `ws` was made for (new_batch_scratch()).
    /// This default runs run_generator() one image at a time; a model with a batched generator overrides both.
    virtual void run_generator_batch(const float* const* x, const std::size_t* targets, float* const* out, std::size_t count,
                                     batch_workspace::generator_scratch& ws) const
    {
        auto& one = dynamic_cast<one_at_a_time&>(ws);
        for (std::size_t i = 0; i < count; ++i) run_generator(x[i], targets[i], out[i], *one.ws.get());
    }
    virtual std::unique_ptr<batch_workspace::generator_scratch> new_batch_scratch(std::size_t) const
    {
        auto s = std::make_unique<one_at_a_time>();
        s->ws = make_workspace();
        return s;
    }
    struct one_at_a_time final : batch_workspace::generator_scratch {
        workspace ws;
    };
    checkpoint_info info_;

private:
    /// The skeleton the model was trained on: the stored one, or handemo's hand for a checkpoint written before
    /// skeletons were stored whose joints are the hand's; none for another such checkpoint.
    std::optional<skeleton> trained_skeleton() const
    {
        if (info_.skel) return *info_.skel;
        skeleton h = hand_skeleton();
        if (h.size() != info_.joint_names.size()) return std::nullopt;
        for (std::size_t j = 0; j < h.size(); ++j)
            if (h.joints[j].name != info_.joint_names[j]) return std::nullopt;
        return h;
    }

    /// lower_limits(), upper_limits() from trained_skeleton() (none without one), the hand's adopted by a hand
    /// without limits of its own
    void limits_from_skeleton()
    {
        const std::size_t C = info_.joint_names.size() * 3;
        lower_.assign(C, -std::numeric_limits<double>::infinity());
        upper_.assign(C, std::numeric_limits<double>::infinity());
        auto s = trained_skeleton();
        if (!s || s->size() * 3 != C) return;
        adopt_hand_limits(*s);
        for (std::size_t j = 0; j < s->size(); ++j)
            for (std::size_t a = 0; a < 3; ++a)
                if (s->joints[j].limited(a)) lower_[j * 3 + a] = s->joints[j].lower_limit[a], upper_[j * 3 + a] = s->joints[j].upper_limit[a];
    }

    /// The shape check of clamp_to_limits(); the message (`what` then `name`) is built only when it fails, so the
    /// transfers' clamp allocates nothing.
    void check_channels(std::size_t joints, std::size_t values, std::size_t rows, const char* what, std::string_view name) const
    {
        if (joints * 3 != lower_.size() || values != rows * lower_.size())
            throw shape_error("transfer: joint limits: " + std::string(what) + std::string(name) + " has " + std::to_string(joints) +
                              " joints (" + std::to_string(values) + " angles), the model " + info_.source + " has " +
                              std::to_string(lower_.size() / 3));
    }

    std::size_t clamp_angles(double* v, std::size_t rows) const noexcept
    {
        const std::size_t C = lower_.size();
        std::size_t moved = 0;
        for (std::size_t r = 0; r < rows; ++r)
            for (std::size_t c = 0; c < C; ++c) {
                double& x = v[r * C + c];
                if (x < lower_[c]) x = lower_[c], ++moved;
                else if (x > upper_[c]) x = upper_[c], ++moved;
            }
        return moved;
    }

    std::vector<double> lower_, upper_;
};

namespace detail {

template <stargan_config Base>
class emotion_model_impl final : public emotion_model {
public:
    using cfg = with_batch<Base, 1>;
    static constexpr std::size_t H = dims<cfg>::H, W = dims<cfg>::W, K = Base::keyframes, J = Base::joints;
    emotion_model_impl(const safetensors_file& f, checkpoint_info info,
                       kernels::weight_storage storage = kernels::weight_storage::native,
                       kernels::conv_algorithm algorithm = kernels::conv_algorithm::direct)
        : emotion_model(std::move(info))
    {
        if (info_.range.keyframes != K || info_.range.joints != J)
            throw format_error("checkpoint: " + f.source + ": range is for " + std::to_string(info_.range.keyframes) + "x" +
                               std::to_string(info_.range.joints) + ", configuration " + info_.config + " is " +
                               std::to_string(K) + "x" + std::to_string(J));
        // Every field the generator indexes with is checked against the configuration: a target index is
        // a position in info_.domains and becomes label[target] in run_generator (Base::domains floats).
        if (info_.domains.size() != Base::domains)
            throw format_error("checkpoint: " + f.source + ": " + std::to_string(info_.domains.size()) +
                               " domain names, configuration " + info_.config + " has " + std::to_string(Base::domains));
        if (info_.joint_names.size() != J)
            throw format_error("checkpoint: " + f.source + ": " + std::to_string(info_.joint_names.size()) +
                               " joint names, configuration " + info_.config + " has " + std::to_string(J) + " joints");
        generator<float, cfg> g;
        load_parameters(f, g, f.find("G_ema.main.0.weight") ? "G_ema." : "G.");  // the EMA weights when trained with them
        g.set_residual(residual());
        // weights packed once for every transfer of this model (g itself is not kept); a weight binary16
        // cannot hold (storage f16) is refused naming the checkpoint and the parameter
        try {
            frozen_.emplace(g, storage, algorithm);
        } catch (const value_error& e) {
            throw value_error("checkpoint: " + f.source + ": " + e.what());
        }
    }

private:
    /// One thread's scratch: the padded input and output images, the label and the packed generator's buffers.
    struct scratch_impl final : workspace::scratch {
        explicit scratch_impl(const frozen_generator<float, cfg>& g) : fws(g) {}
        typename frozen_generator<float, cfg>::workspace fws;
        std::vector<float> in = std::vector<float>(3 * H * W), out = std::vector<float>(3 * H * W), label = std::vector<float>(Base::domains);
    };

    std::unique_ptr<workspace::scratch> new_scratch() const override { return std::make_unique<scratch_impl>(*frozen_); }

    void run_generator(const float* x, std::size_t target, float* out, workspace::scratch& ws) const override
    {
        auto* s = dynamic_cast<scratch_impl*>(&ws);
        if (!s) throw value_error("transfer: model " + info_.source + ": the workspace was made by another model");
        if (target >= Base::domains) throw value_error("transfer: target domain " + std::to_string(target) + " out of range");
        std::fill(s->label.begin(), s->label.end(), 0.f);
        s->label[target] = 1.f;
        pad_image(x, K, J, s->in.data(), H, W);
        frozen_->infer(s->in.data(), s->label.data(), s->out.data(), s->fws);
        crop_image(s->out.data(), H, W, out, K, J);
    }

    /// A batch's padded inputs, labels and outputs, and the packed generator's buffers for `capacity` images.
    struct batch_impl final : batch_workspace::generator_scratch {
        batch_impl(const frozen_generator<float, cfg>& g, std::size_t capacity)
            : fws(g, capacity), in(capacity * 3 * H * W), out(capacity * 3 * H * W), label(capacity * Base::domains)
        {
        }
        typename frozen_generator<float, cfg>::workspace fws;
        std::vector<float> in, out, label;
    };

    std::unique_ptr<batch_workspace::generator_scratch> new_batch_scratch(std::size_t capacity) const override
    {
        return std::make_unique<batch_impl>(*frozen_, capacity);
    }

    void run_generator_batch(const float* const* x, const std::size_t* targets, float* const* out, std::size_t count,
                             batch_workspace::generator_scratch& ws) const override
    {
        auto* s = dynamic_cast<batch_impl*>(&ws);
        if (!s) throw value_error("transfer: model " + info_.source + ": the batch workspace was made by another model");
        constexpr std::size_t per = 3 * H * W, C = Base::domains;
        std::fill(s->label.begin(), s->label.end(), 0.f);
        for (std::size_t i = 0; i < count; ++i) {
            if (targets[i] >= C) throw value_error("transfer: target domain " + std::to_string(targets[i]) + " out of range");
            s->label[i * C + targets[i]] = 1.f;
            pad_image(x[i], K, J, s->in.data() + i * per, H, W);
        }
        frozen_->infer_batch(s->in.data(), s->label.data(), s->out.data(), count, s->fws);  // throws when count > capacity
        for (std::size_t i = 0; i < count; ++i) crop_image(s->out.data() + i * per, H, W, out[i], K, J);
    }

    kernels::conv_algorithm conv_algorithm() const noexcept override { return frozen_->algorithm(); }

    std::optional<frozen_generator<float, cfg>> frozen_;
};

}  // namespace detail

/// @brief Builds a model from a verified checkpoint (parse_checkpoint / read_checkpoint). storage f16: G's
/// convolution weights rounded to binary16 for inference (kernels::weight_storage; README "Performance").
/// algorithm winograd: G's residual convolutions by Winograd's F(3x2, 3x3) (kernels::conv_algorithm; faster on the
/// batches of transfer_batch, the results differ from direct's in the last bits).
/// @throws format_error when a field does not fit the configuration (domain or joint count, image size,
///         missing or misshapen tensors), value_error (unknown configuration; with f16, a weight binary16
///         cannot hold).
/// A template only so that it is compiled where it is called (see with_config()).
template <class = void>
std::unique_ptr<emotion_model> load_model(const safetensors_file& f, const checkpoint_info& info,
                                                 kernels::weight_storage storage = kernels::weight_storage::native,
                                                 kernels::conv_algorithm algorithm = kernels::conv_algorithm::direct)
{
    // train_model() stores G's average posture with every save: a checkpoint without it would be weighed by a gate
    // chosen for the centred change with G's change as it is
    if (info.options.is_object() && info.options.value("gate_centre", false) && info.options.value("gate_folds", 0) > 0 &&
        info.posture_centre.empty())
        throw value_error("transfer: checkpoint " + info.source + " was trained with --gate-centre but holds no gate.posture_centre (train_model() "
                          "and handemo train store it with every save; a trainer run on its own does not: train it with gate_centre false)");
    return with_config(info.config, [&]<stargan_config Config>(const config_info&) -> std::unique_ptr<emotion_model> {
        return std::make_unique<detail::emotion_model_impl<Config>>(f, info, storage, algorithm);
    });
}

/// @brief Loads a model from a checkpoint file, or from a training output folder holding one (storage, algorithm:
/// as above).
/// @throws io_error, format_error (corrupted, truncated, foreign file), value_error (unknown configuration).
/// A template only so that it is compiled where it is called (see with_config()).
template <class = void>
std::unique_ptr<emotion_model> load_model(const std::filesystem::path& path,
                                                 kernels::weight_storage storage = kernels::weight_storage::native,
                                                 kernels::conv_algorithm algorithm = kernels::conv_algorithm::direct)
{
    const auto file = checkpoint_file(path);
    // No structured binding here: clang 14 cannot capture one in a lambda (C++20's P1091 came in clang 16).
    const auto loaded = read_checkpoint(file);
    return load_model(loaded.first, loaded.second, storage, algorithm);
}

}  // namespace handemo::stargan
