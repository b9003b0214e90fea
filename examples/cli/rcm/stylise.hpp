// `handemo rcm stylise --model MODEL IN.bvh --valence V --arousal A --out OUT.bvh`: Section 4 of Aristidou
// et al. 2017. The model's multiquadric RBF (Eq. 3-4) gives the selected, normalised features at (V, A);
// each one that the synthesis can differentiate (a max/min/std/mean over the sliding window of a basic
// feature in features_ad.hpp) becomes a target of Eq. 6 in the feature's units (lo + f (hi - lo), residual
// scaled by hi - lo, then calibrated for keyframe sampling, see below); the rule coefficients are fitted jointly, every fifth frame is moved by IK and the
// clip is splined back to full rate (duration / c4). Prints what it targeted, the Eq. 6 losses, the
// coefficients and `rcm analyse` of the input and of the output.
#pragma once

#include "common.hpp"

#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>

namespace handemo::cli::rcm_cmd {

struct stylise_run {
    std::string model, input, out;
    double valence = 0, arousal = 0;
    int iterations = 100;
    double bound = 0.7;
    bool frame_rate = false;
};

inline void run_stylise(const stylise_run& o)
{
    namespace rc = handemo::rcm;
    if (!(std::abs(o.valence) <= 1) || !(std::abs(o.arousal) <= 1))
        throw handemo::value_error("rcm stylise: --valence and --arousal must be in [-1, 1] (got " + std::to_string(o.valence) +
                                   ", " + std::to_string(o.arousal) + ")");
    const auto m = rc::load_model(o.model);
    const std::filesystem::path in(o.input);
    const auto ext = in.extension().string();
    handemo::clip c = (ext == ".csv" || ext == ".CSV") ? handemo::read_csv(in, handemo::hand_skeleton()) : handemo::read_bvh(in);
    c.validate(in.string());
    rc::role_map roles;
    try {
        roles = m.roles_for(c.skel);
    } catch (const handemo::error& e) {
        throw handemo::value_error("rcm stylise: " + in.string() + ": " + e.what());
    }
    const auto desired = m.desired_features(o.valence, o.arousal);
    const auto& derived = rc::derived_features(m.features);
    const auto& basic = rc::basic_features(m.features);
    // The differentiable features of this skeleton's rig (their lma.hpp keys).
    std::vector<std::string> keys;
    {
        clip u = c;
        unwrap_angles(u);
        const rc::rig r = rc::make_rig(u.skel, roles, m.lma.up_axis);
        const auto kp = rc::sample_control_points(r, u, rc::keyframe_indices(u.frames));
        std::vector<std::string> names;
        rc::feature_values(r, kp.times, kp.ground, kp.p, 1.0, &names, &keys);
    }
    std::vector<rc::feature_target> targets;
    std::vector<std::string> skipped;
    std::vector<std::size_t> target_index;  // derived-feature index of each target
    for (std::size_t i = 0; i < m.selected.size(); ++i) {
        const auto& d = derived[m.selected[i]];
        const std::string key(basic[d.basic].key);
        const double lo = m.normaliser.lo[m.selected[i]], hi = m.normaliser.hi[m.selected[i]];
        rc::statistic st{};
        bool ok = std::find(keys.begin(), keys.end(), key) != keys.end() && hi > lo;
        switch (d.s) {
        case rc::stat::max: st = rc::statistic::window_max; break;
        case rc::stat::min: st = rc::statistic::window_min; break;
        case rc::stat::std: st = rc::statistic::window_std; break;
        case rc::stat::mean: st = rc::statistic::window_mean; break;
        default: ok = false;
        }
        if (!ok) {
            skipped.push_back(d.name);
            continue;
        }
        const double f = std::clamp(desired(i), 0.0, 1.0);
        targets.push_back({key, st, lo + f * (hi - lo), 1.0, hi - lo});
        target_index.push_back(m.selected[i]);
    }
    rc::synth_options opt;
    opt.roles = roles;
    opt.up = m.lma.up_axis;
    opt.max_iterations = o.iterations;
    opt.bound = o.bound;
    opt.window = std::max<std::size_t>(1, static_cast<std::size_t>(std::lround(static_cast<double>(rc::window_length(c.fps, m.lma)) /
                                                                            static_cast<double>(opt.keyframe_step))));
    if (o.frame_rate) opt.time = rc::time_mode::frame_rate;
    // Calibration: the model's features are taken on every frame, the synthesis sees keyframes 5 frames
    // apart, which smooths accelerations and jerk. Each target is scaled by (keyframe statistic / frame
    // statistic) of the input, so the fit asks for the model's relative change, not for the sampling bias.
    if (!targets.empty()) {
        clip u = c;
        unwrap_angles(u);
        const rc::rig r = rc::make_rig(u.skel, roles, opt.up);
        const auto kp = rc::sample_control_points(r, u, rc::keyframe_indices(u.frames, opt.keyframe_step));
        rc::objective obj(r, kp, targets, opt.window, opt.bound);
        const auto at_keyframes = obj.statistics(std::vector<double>(r.coefficients(), 0.0));
        const auto at_frames = rc::clip_features(rc::world_positions(c), c.fps, roles, m.features, m.lma);
        for (std::size_t t = 0; t < targets.size(); ++t) {
            const double kf = at_keyframes[t], fr = at_frames(target_index[t]);
            if (std::abs(kf) > 1e-12 && std::abs(fr) > 1e-12 && (kf > 0) == (fr > 0)) {
                targets[t].value *= kf / fr;
                targets[t].scale *= kf / fr;
            }
        }
    }
    std::cout << "rcm stylise: " << targets.size() << " of " << m.selected.size() << " selected features targeted";
    if (!skipped.empty()) {
        std::cout << " (not differentiable from the control points:";
        for (const auto& s : skipped) std::cout << " [" << s << "]";
        std::cout << ")";
    }
    std::cout << "\n";
    if (targets.empty())
        throw handemo::value_error("rcm stylise: none of the model's selected features is one the rules can reach; nothing to optimise");
    const auto res = rc::stylise(c, targets, opt);
    handemo::write_bvh(o.out, res.motion);
    const auto names = rc::coefficient_names(res.fit.coefficients.size() == rc::body_coefficient_count ? rc::rig_kind::body : rc::rig_kind::hand);
    char line[256];
    std::snprintf(line, sizeof line, "Eq. 6 loss %.6g -> %.6g (rules), %.6g (after IK); %d BFGS iterations; IK max rms %.4g",
                  res.fit.loss_initial, res.fit.loss_final, res.loss_after_ik, res.fit.iterations, res.ik_rms_max);
    std::cout << line << "\ncoefficients (0 = unchanged):";
    for (std::size_t i = 0; i < names.size(); ++i) std::cout << " " << names[i] << "=" << res.fit.coefficients[i];
    std::snprintf(line, sizeof line, "\nframes %zu -> %zu at %.4g fps (c4 = %.4f)", c.frames, res.motion.frames, res.motion.fps,
                  rc::time_scale(res.fit.coefficients));
    std::cout << line << "\n";
    const auto a0 = m.analyse(c), a1 = m.analyse(res.motion);
    std::snprintf(line, sizeof line, "input  valence %.3f arousal %.3f quadrant %d\noutput valence %.3f arousal %.3f quadrant %d\n",
                  a0.valence, a0.arousal, a0.quadrant, a1.valence, a1.arousal, a1.quadrant);
    std::cout << line << "target valence " << o.valence << " arousal " << o.arousal << " quadrant " << rc::quadrant(o.valence, o.arousal)
              << "\nwrote " << o.out << "\n";
}

inline void add_stylise(CLI::App& rcm)
{
    auto* sub = rcm.add_subcommand("stylise", "Move a motion to a circumplex point (rules + IK, Section 4 of Aristidou et al. 2017)");
    auto o = std::make_shared<stylise_run>();
    sub->add_option("--model", o->model, "Model file written by `handemo rcm fit`")->required();
    sub->add_option("input", o->input, "Motion to stylise (.bvh; .csv for the hand)")->required();
    sub->add_option("--valence", o->valence, "Target valence in [-1, 1]")->required();
    sub->add_option("--arousal", o->arousal, "Target arousal in [-1, 1]")->required();
    sub->add_option("--out", o->out, "Output BVH")->required();
    sub->add_option("--iters", o->iterations, "BFGS iterations of the joint coefficient fit")->capture_default_str();
    sub->add_option("--bound", o->bound, "Largest |coefficient| (c = e^a within [e^-bound, e^bound] for g1, g2, g4)")->capture_default_str();
    sub->add_flag("--frame-rate", o->frame_rate, "Apply g4 as a frame rate (same frames, fps * c4) instead of resampling");
    sub->callback([o] { run_stylise(*o); });
}

}  // namespace handemo::cli::rcm_cmd
