// Motion synthesis of Aristidou et al. 2017, Section 4: keyframes every fifth frame, the rules of Table 2
// (rules.hpp) with their coefficients optimised so that the features of the keyframes reach desired values
// (Eq. 6: min_c sum_t ||f*_t - f_t(c)||^2), a full-body IK to the moved control points (ik.hpp), and spline
// interpolation back to full rate, with g4 changing the frame rate. Unlike the paper, which optimises c1,
// then c2, c3, c4 one after another with an interior-reflective Newton method, handemo optimises all
// coefficients jointly (the paper's future work) by BFGS on gradients from the reverse-mode tape; the
// paper's sequential order is available as strategy::sequential for comparison. Coefficients are bounded,
// a = bound * tanh(z), and z = 0 is the identity.
#pragma once

#include <handemo/core/error.hpp>
#include <handemo/motion/clip.hpp>
#include <handemo/motion/hand.hpp>
#include <handemo/motion/keyframes.hpp>
#include <handemo/rcm/detail/ops.hpp>
#include <handemo/rcm/features_ad.hpp>
#include <handemo/rcm/ik.hpp>
#include <handemo/rcm/rules.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace handemo::rcm {

/// @brief Which statistic of a feature over the keyframes a target constrains.
enum class statistic {
    windowed_mean,  ///< every keyframe's mean over a sliding window (the paper's f_t, 35 frames = 7 keyframes)
    mean,           ///< the mean over all keyframes
    std,            ///< the standard deviation over all keyframes
    window_max,     ///< max over a sliding window of keyframes, averaged over the windows (lma.hpp's derived
    window_min,     ///< features: a statistic over each 35-frame window, averaged over the clip's windows)
    window_std,
    window_mean,
};

/// @brief One desired feature value f* (Eq. 6). The residual is (statistic - value) / scale, squared and
/// weighted; `scale` is the feature's normalisation range (hi - lo), so residuals of features in
/// different units are comparable, as after the paper's normalisation to [0, 1].
struct feature_target {
    std::string feature;
    statistic stat = statistic::windowed_mean;
    double value = 0;
    double weight = 1;
    double scale = 1;
};

/// @brief How g4's frame-rate factor c4 reaches the output clip.
enum class time_mode {
    resample,    ///< keep the frame rate, change the frame count: duration / c4 (default)
    frame_rate,  ///< keep the frame count, multiply the frame rate by c4 (the paper's v *= c4 literally)
};

/// @brief How the coefficients are optimised.
enum class strategy {
    joint,       ///< all rules at once (handemo)
    sequential,  ///< g1, then g2, g3, g4, each with the earlier ones fixed (the paper)
};

struct synth_options {
    std::size_t keyframe_step = 5;      ///< the paper's "every fifth frame"
    std::size_t window = 7;             ///< keyframes in the windowed mean (35 frames / 5)
    double bound = 1.5;                 ///< |a_i| <= bound (c1, c2, c4 within [0.22, 4.5])
    int max_iterations = 100;           ///< BFGS iterations (per rule when sequential)
    std::array<bool, 4> rules{true, true, true, true};  ///< which of g1..g4 may change
    strategy mode = strategy::joint;
    time_mode time = time_mode::resample;
    bool interpolate_offsets = true;    ///< spline the keyframes' IK changes onto the original frames
                                        ///< (keeps detail between keyframes); false: spline the keyframes
    ik_options ik{};
    bool ik_warm_start = true;          ///< also offer each keyframe's IK the previous keyframe's change (its
                                        ///< solution minus its input, added to this keyframe's input) as a
                                        ///< start; the IK starts from whichever is nearer the targets (README,
                                        ///< "Speed": faster and nearer the bench's targets, but through a model
                                        ///< `rcm path` gave a 3-18% higher Eq. 6 after IK)
    std::optional<role_map> roles;      ///< control joints (default: find_roles from the joint names)
    int up = 1;                         ///< up axis of a body
};

/// @brief Coefficients and losses of an optimisation.
struct fit_result {
    std::vector<double> coefficients;   ///< a (0 = identity), see rules.hpp for the layout
    double loss_initial = 0, loss_final = 0;
    int iterations = 0;
};

/// @brief The objective of Eq. 6 over bounded coefficients, value and gradient through the tape.
class objective {
public:
    /// @throws value_error when a target names no differentiable feature of the rig.
    objective(const rig& r, const keyframe_points& kp, std::vector<feature_target> targets, std::size_t window = 7,
              double bound = 1.5)
        : rig_(&r), kp_(&kp), targets_(std::move(targets)), bound_(bound), tape_(std::size_t{1} << 18)
    {
        const std::size_t K = kp.count, W = std::max<std::size_t>(1, std::min(window, K));
        window_.resize(K);
        for (std::size_t k = 0; k < K; ++k) {
            std::size_t lo = k >= W / 2 ? k - W / 2 : 0;
            if (lo + W > K) lo = K - W;
            for (std::size_t i = lo; i < lo + W; ++i) window_[k].push_back({static_cast<int>(i), 1.0 / static_cast<double>(W)});
        }
        if (K <= W) {
            starts_ = {0};
            wlen_ = K;
        } else {
            for (std::size_t k = 0; k + W <= K; ++k) starts_.push_back(k);
            wlen_ = W;
        }
        for (std::size_t s : starts_) {
            windows_.emplace_back();
            for (std::size_t i = s; i < s + wlen_; ++i) windows_.back().push_back({static_cast<int>(i), 1.0 / static_cast<double>(wlen_)});
        }
        mask_.assign(r.coefficients(), 1.0);
        fixed_.assign(r.coefficients(), 0.0);
        // Validate the feature names once.
        tape_.reset();
        const std::vector<double> z(r.coefficients(), 0.0);
        build(z, false);
    }

    std::size_t size() const noexcept { return rig_->coefficients(); }
    double bound() const noexcept { return bound_; }
    /// @brief Coefficients a of the free variables z: a_i = mask_i bound tanh(z_i) + fixed_i.
    std::vector<double> coefficients(std::span<const double> z) const
    {
        std::vector<double> a(z.size());
        for (std::size_t i = 0; i < z.size(); ++i) a[i] = mask_[i] * bound_ * std::tanh(z[i]) + fixed_[i];
        return a;
    }
    /// @brief Frees only the coefficients with mask 1; the others hold `fixed` values.
    void set_free(std::span<const double> mask, std::span<const double> fixed)
    {
        mask_.assign(mask.begin(), mask.end());
        fixed_.assign(fixed.begin(), fixed.end());
    }
    /// @brief Loss at z and, when `grad` is not empty, d loss / d z.
    double operator()(std::span<const double> z, std::span<double> grad)
    {
        tape_.reset();
        const auto [loss, zid] = build(z, !grad.empty());
        if (!grad.empty()) {
            std::fill(grad.begin(), grad.end(), 0.0);
            tape_.backward(loss);
            const double* g = tape_.at(zid).adjoint;
            std::copy(g, g + grad.size(), grad.begin());
        }
        return tape_.at(loss).value[0];
    }
    /// @brief The value of each target's statistic at z (what the residual compares with its value).
    std::vector<double> statistics(std::span<const double> z)
    {
        tape_.reset();
        build(z, false);
        std::vector<double> v;
        for (int id : stat_ids_) v.push_back(tape_.at(id).value[0]);
        return v;
    }
    /// @brief Loss of the rule-free points `points` ([points][K, 3]) with frame-rate factor exp(a4): how well
    /// an IK result achieves the targets.
    double loss_of_points(const std::vector<std::vector<double>>& points, double a4)
    {
        keyframe_points kp = *kp_;
        kp.p = points;
        const keyframe_points* keep = kp_;
        kp_ = &kp;
        std::vector<double> z(size(), 0.0), m(size(), 0.0), fx(size(), 0.0), sm = mask_, sf = fixed_;
        fx.back() = a4;
        set_free(m, fx);
        const double l = (*this)(z, {});
        set_free(sm, sf);
        kp_ = keep;
        return l;
    }

private:
    std::pair<int, int> build(std::span<const double> z, bool requires_grad)
    {
        namespace ad = autodiff::detail;
        auto& t = tape_;
        const std::size_t n = z.size();
        const int zid = t.leaf_copy(z.data(), n, requires_grad);
        std::vector<double> bm(n);
        for (std::size_t i = 0; i < n; ++i) bm[i] = bound_ * mask_[i];
        const int a = ad::add_raw(t, ad::mul_raw(t, ad::unary_raw(t, zid, ad::unary::tanh_), t.leaf_copy(bm.data(), n, false)),
                                  t.leaf_copy(fixed_.data(), n, false));
        const rule_nodes rn = apply_rules(t, *rig_, *kp_, a);
        const feature_nodes f = differentiable_features(t, *rig_, kp_->times, kp_->ground, rn);
        int loss = -1;
        stat_ids_.clear();
        for (const auto& tg : targets_) {
            const int x = f.at(tg.feature);
            int s = -1;
            switch (tg.stat) {
            case statistic::windowed_mean: s = detail::stencil(t, x, 1, window_); break;
            case statistic::mean: s = detail::mean_all(t, x); break;
            case statistic::window_max: s = detail::mean_all(t, detail::window_extreme<double>(t, x, starts_, wlen_, 1)); break;
            case statistic::window_min: s = detail::mean_all(t, detail::window_extreme<double>(t, x, starts_, wlen_, -1)); break;
            case statistic::window_mean: s = detail::mean_all(t, detail::stencil(t, x, 1, windows_)); break;
            case statistic::window_std: {
                // per window sqrt(E[x^2] - E[x]^2) (population std, as lma.hpp), then the mean over windows
                const int m = detail::stencil(t, x, 1, windows_);
                const int m2 = detail::stencil(t, ad::unary_raw(t, x, ad::unary::square_), 1, windows_);
                const int var = ad::sub_raw(t, m2, ad::unary_raw(t, m, ad::unary::square_));
                s = detail::mean_all(t, ad::unary_raw(t, ad::affine_raw(t, ad::leaky_relu_raw(t, var, 0.0), 1.0, 1e-12), ad::unary::sqrt_));
                break;
            }
            case statistic::std: {
                const int m = detail::mean_all(t, x);
                const int d = ad::sub_raw(t, x, ad::row_broadcast_raw(t, m, static_cast<int>(t.at(x).size), 1.0));
                s = ad::unary_raw(t, ad::affine_raw(t, detail::mean_all(t, ad::unary_raw(t, d, ad::unary::square_)), 1.0, 1e-12),
                                  ad::unary::sqrt_);
                break;
            }
            }
            stat_ids_.push_back(tg.stat == statistic::windowed_mean ? mean_all_id(s) : s);
            const double sc = tg.scale > 0 ? tg.scale : 1.0;
            const int r = ad::affine_raw(t, s, 1.0 / sc, -tg.value / sc);
            const int term = ad::affine_raw(t, detail::mean_all(t, ad::unary_raw(t, r, ad::unary::square_)), tg.weight, 0.0);
            loss = loss < 0 ? term : ad::add_raw(t, loss, term);
        }
        if (loss < 0) loss = t.fill(0.0, 1);
        return {loss, zid};
    }

    int mean_all_id(int x) { return detail::mean_all(tape_, x); }

    const rig* rig_;
    const keyframe_points* kp_;
    std::vector<int> stat_ids_;
    std::vector<feature_target> targets_;
    double bound_;
    autodiff::tape<double> tape_;
    std::vector<std::vector<detail::stencil_entry>> window_, windows_;
    std::vector<std::size_t> starts_;
    std::size_t wlen_ = 1;
    std::vector<double> mask_, fixed_;
};

namespace detail {

/// BFGS with Armijo backtracking on f(x) (value and gradient). Returns the iteration count; x is updated.
inline int bfgs(const std::function<double(std::span<const double>, std::span<double>)>& f, std::vector<double>& x,
                int max_iterations, double& fx)
{
    const std::size_t n = x.size();
    std::vector<double> g(n), gn(n), p(n), xn(n), s(n), y(n), H(n * n, 0.0), Hy(n);
    for (std::size_t i = 0; i < n; ++i) H[i * n + i] = 1.0;
    fx = f(x, g);
    int it = 0;
    for (; it < max_iterations; ++it) {
        double gmax = 0;
        for (double v : g) gmax = std::max(gmax, std::abs(v));
        if (gmax < 1e-10) break;
        double gp = 0;
        for (std::size_t i = 0; i < n; ++i) {
            double v = 0;
            for (std::size_t j = 0; j < n; ++j) v -= H[i * n + j] * g[j];
            p[i] = v;
            gp += v * g[i];
        }
        if (!(gp < 0)) {  // not a descent direction: restart from steepest descent
            std::fill(H.begin(), H.end(), 0.0);
            for (std::size_t i = 0; i < n; ++i) H[i * n + i] = 1.0, p[i] = -g[i];
            gp = 0;
            for (std::size_t i = 0; i < n; ++i) gp -= g[i] * g[i];
        }
        double pmax = 0;
        for (double v : p) pmax = std::max(pmax, std::abs(v));
        double step = pmax > 1.0 ? 1.0 / pmax : 1.0;  // at most one unit of z per step
        double fn = 0;
        bool ok = false;
        for (int ls = 0; ls < 40; ++ls, step *= 0.5) {
            for (std::size_t i = 0; i < n; ++i) xn[i] = x[i] + step * p[i];
            fn = f(xn, gn);
            if (fn <= fx + 1e-4 * step * gp) {
                ok = true;
                break;
            }
        }
        if (!ok) break;
        double sy = 0;
        for (std::size_t i = 0; i < n; ++i) {
            s[i] = xn[i] - x[i];
            y[i] = gn[i] - g[i];
            sy += s[i] * y[i];
        }
        const double df = fx - fn;
        x = xn;
        g = gn;
        fx = fn;
        if (sy > 1e-16) {
            // H <- (I - rho s y^T) H (I - rho y s^T) + rho s s^T
            const double rho = 1.0 / sy;
            double yHy = 0;
            for (std::size_t i = 0; i < n; ++i) {
                double v = 0;
                for (std::size_t j = 0; j < n; ++j) v += H[i * n + j] * y[j];
                Hy[i] = v;
                yHy += y[i] * v;
            }
            for (std::size_t i = 0; i < n; ++i)
                for (std::size_t j = 0; j < n; ++j)
                    H[i * n + j] += -rho * (Hy[i] * s[j] + s[i] * Hy[j]) + (rho * rho * yHy + rho) * s[i] * s[j];
        }
        if (df <= 1e-15 * (1.0 + std::abs(fx))) {
            ++it;
            break;
        }
    }
    return it;
}

}  // namespace detail

/// @brief Optimises the rule coefficients of `kp` to `targets` (Eq. 6).
/// @throws value_error when a target names no feature of the rig.
inline fit_result fit_coefficients(const rig& r, const keyframe_points& kp, const std::vector<feature_target>& targets,
                                   const synth_options& opt = {})
{
    objective obj(r, kp, targets, opt.window, opt.bound);
    const std::size_t n = r.coefficients();
    fit_result res;
    std::vector<double> z(n, 0.0), mask(n, 0.0), fixed(n, 0.0);
    auto fn = [&](std::span<const double> x, std::span<double> g) { return obj(x, g); };
    for (std::size_t i = 0; i < n; ++i) mask[i] = opt.rules[static_cast<std::size_t>(rule_of(r.kind, i))] ? 1.0 : 0.0;
    obj.set_free(mask, fixed);
    res.loss_initial = obj(z, {});
    double fx = res.loss_initial;
    if (opt.mode == strategy::joint) {
        res.iterations = detail::bfgs(fn, z, opt.max_iterations, fx);
        res.coefficients = obj.coefficients(z);
    } else {
        for (int rule = 0; rule < 4; ++rule) {
            if (!opt.rules[static_cast<std::size_t>(rule)]) continue;
            std::vector<double> m(n, 0.0);
            for (std::size_t i = 0; i < n; ++i) m[i] = rule_of(r.kind, i) == rule ? 1.0 : 0.0;
            obj.set_free(m, fixed);
            std::fill(z.begin(), z.end(), 0.0);
            res.iterations += detail::bfgs(fn, z, opt.max_iterations, fx);
            fixed = obj.coefficients(z);
        }
        res.coefficients = fixed;
    }
    res.loss_final = fx;
    return res;
}

/// @brief Result of stylise().
struct synth_result {
    clip motion;                   ///< the stylised clip
    fit_result fit;                ///< coefficients and Eq. 6 losses of the rule-moved points
    double loss_after_ik = 0;      ///< Eq. 6 loss of the control points the IK reached
    double ik_rms_max = 0;         ///< largest weighted RMS distance to the targets after IK
    double ik_rms = 0;             ///< weighted RMS distance to the targets after IK over all keyframes
    long ik_iterations = 0;        ///< IK iterations summed over the keyframes
    std::vector<std::size_t> keyframes;  ///< source frames of the keyframes
};

namespace detail {

/// Cubic Hermite interpolation through (xs[k], ys[k]) with finite-difference tangents (Catmull-Rom on
/// non-uniform knots; one-sided at the ends), evaluated at x (clamped to the knots).
inline double hermite(std::span<const double> xs, std::span<const double> ys, double x) noexcept
{
    const std::size_t K = xs.size();
    if (K == 1) return ys[0];
    x = std::clamp(x, xs[0], xs[K - 1]);
    const std::size_t i = std::min<std::size_t>(
        static_cast<std::size_t>(std::upper_bound(xs.begin(), xs.end(), x) - xs.begin()) - 1, K - 2);
    const double h = xs[i + 1] - xs[i], t = (x - xs[i]) / h;
    auto tangent = [&](std::size_t k) {
        const std::size_t a = k == 0 ? 0 : k - 1, b = k + 1 == K ? K - 1 : k + 1;
        return (ys[b] - ys[a]) / (xs[b] - xs[a]);
    };
    const double m0 = tangent(i) * h, m1 = tangent(i + 1) * h, t2 = t * t, t3 = t2 * t;
    return (2 * t3 - 3 * t2 + 1) * ys[i] + (t3 - 2 * t2 + t) * m0 + (-2 * t3 + 3 * t2) * ys[i + 1] + (t3 - t2) * m1;
}

/// Wraps an angle into (-180, 180].
inline double wrap180(double a) noexcept
{
    a = std::fmod(a, 360.0);
    if (a > 180.0) a -= 360.0;
    if (a <= -180.0) a += 360.0;
    return a;
}

}  // namespace detail

/// @brief Stylises `input` toward the desired features (Section 4): keyframes every `keyframe_step` frames,
/// rule coefficients fitted to `targets`, IK of every keyframe to the moved control points, spline back to
/// full rate, g4's frame-rate factor applied as `opt.time` says.
/// @throws value_error / shape_error for an invalid clip, unknown feature names or missing body roles.
inline synth_result stylise(const clip& input, const std::vector<feature_target>& targets, const synth_options& opt = {})
{
    input.validate("rcm::stylise");
    clip u = input;
    adopt_hand_limits(u.skel);
    unwrap_angles(u);
    const rig r = opt.roles ? make_rig(u.skel, *opt.roles, opt.up) : make_rig(u.skel, opt.up);
    synth_result out;
    out.keyframes = keyframe_indices(u.frames, opt.keyframe_step);
    const keyframe_points kp = sample_control_points(r, u, out.keyframes);
    out.fit = fit_coefficients(r, kp, targets, opt);
    const rule_result moved = apply_rules(r, kp, out.fit.coefficients);

    // IK of every keyframe to the moved control points.
    const std::size_t K = kp.count, J = u.skel.size(), J3 = J * 3;
    ik_solver ik(u.skel, r.translation_joint, opt.ik);
    std::vector<double> kf_angles(K * J3), kf_pos(K * J3);
    std::vector<std::vector<double>> reached(r.points.size(), std::vector<double>(K * 3));
    std::vector<ik_target> goals;
    std::vector<double> warm_angles(J3), warm_pos(J3);
    double ik_ss = 0;
    for (std::size_t k = 0; k < K; ++k) {
        const std::size_t f = out.keyframes[k];
        std::copy(u.frame_angles(f), u.frame_angles(f) + J3, kf_angles.begin() + static_cast<std::ptrdiff_t>(k * J3));
        std::copy(u.frame_positions(f), u.frame_positions(f) + J3, kf_pos.begin() + static_cast<std::ptrdiff_t>(k * J3));
        const bool warm = opt.ik_warm_start && k > 0;
        if (warm) {
            // this keyframe's input plus the previous keyframe's IK change (keyframes are a few frames apart)
            const std::size_t fp = out.keyframes[k - 1];
            for (std::size_t i = 0; i < J3; ++i) {
                warm_angles[i] = u.angles[f * J3 + i] + (kf_angles[(k - 1) * J3 + i] - u.angles[fp * J3 + i]);
                warm_pos[i] = u.positions[f * J3 + i] + (kf_pos[(k - 1) * J3 + i] - u.positions[fp * J3 + i]);
            }
        }
        goals.clear();
        for (std::size_t q = 0; q < r.points.size(); ++q)
            if (r.ik_weights[q] > 0)
                goals.push_back({r.points[q], {moved.points[q][k * 3], moved.points[q][k * 3 + 1], moved.points[q][k * 3 + 2]},
                                 r.ik_weights[q]});
        const ik_report rep = ik.solve(std::span<double>(kf_angles.data() + k * J3, J3),
                                       std::span<double>(kf_pos.data() + k * J3, J3), goals,
                                       warm ? std::span<const double>(warm_angles) : std::span<const double>(),
                                       warm ? std::span<const double>(warm_pos) : std::span<const double>());
        out.ik_rms_max = std::max(out.ik_rms_max, rep.rms_after);
        ik_ss += rep.rms_after * rep.rms_after;
        out.ik_iterations += rep.iterations;
        const pose_positions fk = forward_kinematics(u.skel, kf_angles.data() + k * J3, kf_pos.data() + k * J3);
        for (std::size_t q = 0; q < r.points.size(); ++q) {
            const auto j = static_cast<std::size_t>(r.points[q].joint);
            const vec3& v = r.points[q].end_site ? fk.end_sites[j] : fk.joints[j];
            for (int a = 0; a < 3; ++a) reached[q][k * 3 + static_cast<std::size_t>(a)] = v[a];
        }
    }
    out.ik_rms = K > 0 ? std::sqrt(ik_ss / static_cast<double>(K)) : 0.0;
    {
        objective obj(r, kp, targets, opt.window, opt.bound);
        out.loss_after_ik = obj.loss_of_points(reached, out.fit.coefficients.back());
    }

    // Back to full rate: frame i of the output shows source frame position x(i).
    const double c4 = time_scale(out.fit.coefficients);
    std::size_t frames = u.frames;
    double fps = u.fps, rate = 1.0;
    if (opt.time == time_mode::resample) {
        frames = static_cast<std::size_t>(std::llround(static_cast<double>(u.frames - 1) / c4)) + 1;
        frames = std::max<std::size_t>(frames, 2);
        rate = static_cast<double>(u.frames - 1) / static_cast<double>(frames - 1);
    } else {
        fps = u.fps * c4;
    }
    clip res = clip::make(input.skel, frames, fps);  // the input's own skeleton, its limits as given
    std::vector<double> xs(K), ys(K);
    for (std::size_t k = 0; k < K; ++k) xs[k] = static_cast<double>(out.keyframes[k]);
    const int tj = r.translation_joint;
    auto source_value = [&](const std::vector<double>& track, double x, std::size_t idx) {
        const double xc = std::clamp(x, 0.0, static_cast<double>(u.frames - 1));
        const auto f0 = static_cast<std::size_t>(std::floor(xc));
        const std::size_t f1 = std::min(f0 + 1, u.frames - 1);
        const double w = xc - static_cast<double>(f0);
        return (1 - w) * track[f0 * J3 + idx] + w * track[f1 * J3 + idx];
    };
    for (std::size_t idx = 0; idx < J3; ++idx) {
        const std::size_t j = idx / 3, a = idx % 3;
        const bool translated = tj >= 0 && j == static_cast<std::size_t>(tj);
        const bool limited = u.skel.joints[j].limited(a);
        // angles
        for (std::size_t k = 0; k < K; ++k)
            ys[k] = kf_angles[k * J3 + idx] - (opt.interpolate_offsets ? u.angles[out.keyframes[k] * J3 + idx] : 0.0);
        for (std::size_t i = 0; i < frames; ++i) {
            const double x = static_cast<double>(i) * rate;
            double v = detail::hermite(xs, ys, x) + (opt.interpolate_offsets ? source_value(u.angles, x, idx) : 0.0);
            if (limited) v = std::clamp(v, u.skel.joints[j].lower_limit[a], u.skel.joints[j].upper_limit[a]);
            else v = detail::wrap180(v);
            res.angle(i, j, a) = v;
        }
        // position channels: the translation joint's from its keyframes, the others from the source
        if (translated)
            for (std::size_t k = 0; k < K; ++k)
                ys[k] = kf_pos[k * J3 + idx] - (opt.interpolate_offsets ? u.positions[out.keyframes[k] * J3 + idx] : 0.0);
        for (std::size_t i = 0; i < frames; ++i) {
            const double x = static_cast<double>(i) * rate;
            double v = source_value(u.positions, x, idx);
            if (translated) v = detail::hermite(xs, ys, x) + (opt.interpolate_offsets ? v : 0.0);
            res.position(i, j, a) = v;
        }
    }
    out.motion = std::move(res);
    return out;
}

}  // namespace handemo::rcm
