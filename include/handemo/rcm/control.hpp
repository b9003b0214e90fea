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

/// @brief One point of a circumplex path.
struct path_point {
    std::string name;  ///< the label, `V:A` for an explicit point, or empty for a point between waypoints
    double valence = 0, arousal = 0;
    bool waypoint = false;  ///< one of the points the path was given (not one sampled between them)
};

/// @brief Parses a path `sad,neutral,happy` or `-0.7:-0.4,(0.1,-0.4),happy`: waypoints separated by commas,
/// each a label of `labels` or an explicit point `V:A` or `(V,A)` with V and A in [-1, 1].
/// @throws value_error naming the bad waypoint (an unknown label lists the known ones).
inline std::vector<path_point> parse_path(const std::string& text, const std::vector<label_point>& labels)
{
    std::vector<std::string> tokens;
    std::string cur;
    int depth = 0;
    for (char ch : text) {
        if (ch == '(') ++depth;
        if (ch == ')') --depth;
        if (ch == ',' && depth == 0) {
            tokens.push_back(cur);
            cur.clear();
        } else {
            cur += ch;
        }
        if (depth < 0) throw value_error("rcm path: '" + text + "': ')' without '('");
    }
    if (depth != 0) throw value_error("rcm path: '" + text + "': '(' without ')'");
    tokens.push_back(cur);
    auto trim = [](std::string s) {
        const auto b = s.find_first_not_of(" \t"), e = s.find_last_not_of(" \t");
        return b == std::string::npos ? std::string() : s.substr(b, e - b + 1);
    };
    auto number = [&](const std::string& s, const std::string& tok) {
        const std::string t = trim(s);
        char* end = nullptr;
        const double v = std::strtod(t.c_str(), &end);
        if (t.empty() || end != t.c_str() + t.size() || !std::isfinite(v))
            throw value_error("rcm path: waypoint '" + tok + "': '" + t + "' is not a number");
        if (std::abs(v) > 1) throw value_error("rcm path: waypoint '" + tok + "': " + t + " is outside [-1, 1]");
        return v;
    };
    std::vector<path_point> out;
    for (const auto& raw : tokens) {
        const std::string tok = trim(raw);
        if (tok.empty()) throw value_error("rcm path: '" + text + "' has an empty waypoint");
        path_point p;
        p.waypoint = true;
        p.name = tok;
        std::string body = tok;
        char sep = ':';
        if (body.front() == '(') {
            if (body.back() != ')') throw value_error("rcm path: waypoint '" + tok + "' does not end with ')'");
            body = body.substr(1, body.size() - 2);
            sep = ',';
        }
        const auto at = body.find(sep);
        if (tok.front() == '(' || at != std::string::npos) {
            if (at == std::string::npos || body.find(sep, at + 1) != std::string::npos)
                throw value_error("rcm path: waypoint '" + tok + "' is not two numbers V" + std::string(1, sep) + "A");
            p.valence = number(body.substr(0, at), tok);
            p.arousal = number(body.substr(at + 1), tok);
        } else {
            const auto it = std::find_if(labels.begin(), labels.end(), [&](const label_point& l) { return l.name == tok; });
            if (it == labels.end()) {
                std::string known;
                for (const auto& l : labels) known += (known.empty() ? "" : ", ") + l.name;
                throw value_error("rcm path: waypoint '" + tok + "' is not a label with coordinates (known: " + known +
                                  ") nor a point V:A");
            }
            p.valence = it->valence, p.arousal = it->arousal;
        }
        out.push_back(p);
    }
    return out;
}

/// @brief Samples a polyline through `waypoints`: each segment gives `steps` points (its start and steps - 1
/// evenly spaced points before its end), then the last waypoint, so every waypoint is a sample and there are
/// (W - 1) steps + 1 samples.
/// @throws value_error for no waypoints or steps == 0.
inline std::vector<path_point> sample_path(const std::vector<path_point>& waypoints, std::size_t steps)
{
    if (waypoints.empty()) throw value_error("rcm path: no waypoints");
    if (steps == 0) throw value_error("rcm path: --steps must be at least 1");
    std::vector<path_point> out;
    for (std::size_t w = 0; w + 1 < waypoints.size(); ++w) {
        const auto &a = waypoints[w], &b = waypoints[w + 1];
        out.push_back(a);
        for (std::size_t s = 1; s < steps; ++s) {
            const double t = static_cast<double>(s) / static_cast<double>(steps);
            path_point p;
            p.valence = a.valence + t * (b.valence - a.valence);
            p.arousal = a.arousal + t * (b.arousal - a.arousal);
            out.push_back(p);
        }
    }
    out.push_back(waypoints.back());
    return out;
}

/// @brief A short title for a path point: `sad` or `(0.30,-0.10)`.
inline std::string path_title(const path_point& p)
{
    char b[48];
    std::snprintf(b, sizeof b, "(%.2f,%.2f)", p.valence, p.arousal);
    if (p.name.empty() || p.name.find(':') != std::string::npos || p.name.front() == '(') return b;
    return p.name;
}

}  // namespace handemo::rcm
