// Continuous emotion control with a fitted model (Aristidou et al. 2017, Section 4 driven by Section 3): a
// motion moved to any point (valence, arousal) of the circumplex, and to a sequence of points along a path
// on it. The model's multiquadric RBF (Eq. 3-4) gives the selected, normalised features at the point; each
// one the synthesis can differentiate (a max/min/std/mean over the sliding window of a basic feature of
// features_ad.hpp) becomes an Eq. 6 target in the feature's units (lo + f (hi - lo), residual scaled by
// hi - lo), calibrated for keyframe sampling (the model measures every frame, the synthesis keyframes 5
// frames apart: each target is scaled by the input's keyframe/frame ratio of that statistic), and
// stylise() (synth.hpp) fits the rules jointly, runs the IK and splines back to full rate. A path is a
// polyline through labels or explicit points, sampled with `steps` points per segment.
#pragma once

#include <handemo/core/error.hpp>
#include <handemo/motion/clip.hpp>
#include <handemo/rcm/circumplex.hpp>
#include <handemo/rcm/model.hpp>
#include <handemo/rcm/synth.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

namespace handemo::rcm {

/// @brief Options of stylise_to_point().
struct point_options {
    int iterations = 100;   ///< BFGS iterations of the joint coefficient fit
    double bound = 0.7;     ///< largest |a| (c = e^a within [e^-bound, e^bound] for g1, g2, g4)
    bool frame_rate = false;  ///< apply g4 as a frame rate (time_mode::frame_rate) instead of resampling
};

/// @brief Result of stylise_to_point().
struct point_result {
    synth_result synth;                 ///< the stylised clip and the fit
    std::vector<std::string> targeted;  ///< names of the selected features that became Eq. 6 targets
    std::vector<std::string> skipped;   ///< selected features the rules cannot reach (not differentiable)
};

/// @brief Moves `c` to the circumplex point (valence, arousal) with the model `m` (see the file comment).
/// @param c a clip whose skeleton has the roles of the model's feature set
/// @throws value_error for a point outside [-1, 1]^2, a skeleton missing a role (naming it), or a model none
///         of whose selected features the rules can reach.
inline point_result stylise_to_point(const rcm_model& m, const clip& c, double valence, double arousal, const point_options& o = {})
{
    if (!(std::abs(valence) <= 1) || !(std::abs(arousal) <= 1))
        throw value_error("rcm stylise: valence and arousal must be in [-1, 1] (got " + std::to_string(valence) + ", " +
                          std::to_string(arousal) + ")");
    c.validate("rcm stylise");
    role_map roles;
    try {
        roles = m.roles_for(c.skel);
    } catch (const error& e) {
        throw value_error(std::string("rcm stylise: ") + e.what());
    }
    const auto desired = m.desired_features(valence, arousal);
    const auto& derived = derived_features(m.features);
    const auto& basic = basic_features(m.features);
    // the differentiable features of this skeleton's rig (their lma.hpp keys)
    std::vector<std::string> keys;
    {
        clip u = c;
        unwrap_angles(u);
        const rig r = make_rig(u.skel, roles, m.lma.up_axis);
        const auto kp = sample_control_points(r, u, keyframe_indices(u.frames));
        std::vector<std::string> names;
        feature_values(r, kp.times, kp.ground, kp.p, 1.0, &names, &keys);
    }
    point_result out;
    std::vector<feature_target> targets;
    std::vector<std::size_t> target_index;  // derived-feature index of each target
    for (std::size_t i = 0; i < m.selected.size(); ++i) {
        const auto& d = derived[m.selected[i]];
        const std::string key(basic[d.basic].key);
        const double lo = m.normaliser.lo[m.selected[i]], hi = m.normaliser.hi[m.selected[i]];
        statistic st{};
        bool ok = std::find(keys.begin(), keys.end(), key) != keys.end() && hi > lo;
        switch (d.s) {
        case stat::max: st = statistic::window_max; break;
        case stat::min: st = statistic::window_min; break;
        case stat::std: st = statistic::window_std; break;
        case stat::mean: st = statistic::window_mean; break;
        default: ok = false;
        }
        if (!ok) {
            out.skipped.push_back(d.name);
            continue;
        }
        const double f = std::clamp(desired(i), 0.0, 1.0);
        targets.push_back({key, st, lo + f * (hi - lo), 1.0, hi - lo});
        target_index.push_back(m.selected[i]);
        out.targeted.push_back(d.name);
    }
    if (targets.empty())
        throw value_error("rcm stylise: none of the model's selected features is one the rules can reach; nothing to optimise");
    synth_options opt;
    opt.roles = roles;
    opt.up = m.lma.up_axis;
    opt.max_iterations = o.iterations;
    opt.bound = o.bound;
    opt.window = std::max<std::size_t>(1, static_cast<std::size_t>(std::lround(static_cast<double>(window_length(c.fps, m.lma)) /
                                                                             static_cast<double>(opt.keyframe_step))));
    if (o.frame_rate) opt.time = time_mode::frame_rate;
    // Calibration: the model's features are taken on every frame, the synthesis sees keyframes 5 frames
    // apart, which smooths accelerations and jerk. Each target is scaled by (keyframe statistic / frame
    // statistic) of the input, so the fit asks for the model's relative change, not for the sampling bias.
    {
        clip u = c;
        unwrap_angles(u);
        const rig r = make_rig(u.skel, roles, opt.up);
        const auto kp = sample_control_points(r, u, keyframe_indices(u.frames, opt.keyframe_step));
        objective obj(r, kp, targets, opt.window, opt.bound);
        const auto at_keyframes = obj.statistics(std::vector<double>(r.coefficients(), 0.0));
        const auto at_frames = clip_features(world_positions(c), c.fps, roles, m.features, m.lma);
        for (std::size_t t = 0; t < targets.size(); ++t) {
            const double kf = at_keyframes[t], fr = at_frames(target_index[t]);
            if (std::abs(kf) > 1e-12 && std::abs(fr) > 1e-12 && (kf > 0) == (fr > 0)) {
                targets[t].value *= kf / fr;
                targets[t].scale *= kf / fr;
            }
        }
    }
    out.synth = stylise(c, targets, opt);
    return out;
}

// Paths of waypoints (motion/circumplex.hpp), their messages starting "rcm path".
using handemo::path_point;
using handemo::path_title;

/// @brief handemo::parse_path() for `handemo rcm path`.
inline std::vector<path_point> parse_path(const std::string& text, const std::vector<label_point>& labels)
{
    return handemo::parse_path(text, labels, "rcm path");
}

/// @brief handemo::sample_path() for `handemo rcm path`.
inline std::vector<path_point> sample_path(const std::vector<path_point>& waypoints, std::size_t steps)
{
    return handemo::sample_path(waypoints, steps, "rcm path");
}

}  // namespace handemo::rcm
