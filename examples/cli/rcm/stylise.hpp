// `handemo rcm stylise --model MODEL IN.bvh --valence V --arousal A --out OUT.bvh`: Section 4 of Aristidou
// et al. 2017 through rcm::stylise_to_point() (rcm/control.hpp): the model's multiquadric RBF (Eq. 3-4) gives
// the selected features at (V, A), the differentiable ones become Eq. 6 targets, the rule coefficients are
// fitted jointly, every fifth frame is moved by IK and the clip is splined back to full rate (duration / c4).
// Prints what it targeted, the Eq. 6 losses, the coefficients and `rcm analyse` of the input and the output (the
// model's chosen analysis; --neutral takes for one that reads them, --paper for the paper's).
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
    bool frame_rate = false, paper = false;
    std::vector<std::string> neutral;
};

inline void run_stylise(const stylise_run& o)
{
    namespace rc = handemo::rcm;
    if (!(std::abs(o.valence) <= 1) || !(std::abs(o.arousal) <= 1))
        throw handemo::value_error("rcm stylise: --valence and --arousal must be in [-1, 1] (got " + std::to_string(o.valence) +
                                   ", " + std::to_string(o.arousal) + ")");
    const auto m = rc::load_model(o.model);
    const std::filesystem::path in(o.input);
    const handemo::clip c = read_motion(in);
    const auto pa = printed_analysis_of(o.model, m, o.neutral, o.paper, "rcm stylise");
    rc::point_options po;
    po.iterations = o.iterations;
    po.bound = o.bound;
    po.frame_rate = o.frame_rate;
    rc::point_result pr;
    try {
        pr = rc::stylise_to_point(m, c, o.valence, o.arousal, po);
    } catch (const handemo::value_error& e) {
        throw handemo::value_error(std::string(e.what()) + " (" + in.string() + ")");
    }
    std::cout << "rcm stylise: " << pr.targeted.size() << " of " << m.selected.size() << " selected features targeted";
    if (!pr.skipped.empty()) {
        std::cout << " (not differentiable from the control points:";
        for (const auto& s : pr.skipped) std::cout << " [" << s << "]";
        std::cout << ")";
    }
    std::cout << "\n";
    const auto& res = pr.synth;
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
    rc::analysis a0, a1;
    try {
        a0 = pa.of(c, in.string());
        a1 = pa.of(res.motion, o.out);
    } catch (const handemo::error& e) {
        throw handemo::value_error(std::string("rcm stylise: ") + e.what());
    }
    std::cout << pa.line << "\n";
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
    sub->add_option("--neutral", o->neutral,
                    "Neutral takes of the input's content (.bvh, .csv): the model's analysis of the input and the output reads "
                    "them when its input is relative or judge (without them, the paper's analysis is printed)");
    sub->add_flag("--paper", o->paper, "Print the paper's analysis of the input and the output, whatever the model chose");
    sub->callback([o] { run_stylise(*o); });
}

}  // namespace handemo::cli::rcm_cmd
