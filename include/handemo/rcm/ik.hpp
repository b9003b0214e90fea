// Full-body inverse kinematics for the synthesis of Aristidou et al. 2017 (Section 4: "we then pass these
// joint positions to an Inverse Kinematics solver ... to solve for the fullbody poses", FBBIK in the
// paper). Here: damped least squares (Levenberg-Marquardt) over all joint angles and the translation of one
// joint (the pelvis, or the hand's forearm). The solver's forward kinematics (detail::ik_kinematics, without
// allocation) writes the world axis of every rotation DOF as it goes, so the Jacobian of the control points is
// w x (p - o) per axis above the point; ik_kinematics::residuals_with_jacobian gives that same Jacobian for the
// finite-difference test (tests/rcm_synth/ik_test.cpp). Bone lengths are kept exactly because the unknowns
// are angles (positions follow from forward kinematics with the skeleton's fixed offsets and position-channel
// values); joint limits are kept by projection with an active set (a DOF that a step would push past its
// limit is held at the limit and the step solved again without it). Axes whose range is 360 degrees or more
// (BVH's +-180) are unlimited.
#pragma once

#include <handemo/core/error.hpp>
#include <handemo/motion/skeleton.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <numbers>
#include <span>
#include <string>
#include <vector>

namespace handemo::rcm {

/// @brief A point of the skeleton: a joint's origin, or its End Site.
struct skeleton_point {
    int joint = 0;
    bool end_site = false;
};

/// @brief One IK goal: `point` should reach `position`, with a weight on its squared distance.
struct ik_target {
    skeleton_point point;
    vec3 position{};
    double weight = 1.0;
};

/// @brief Options of the damped least-squares solve.
struct ik_options {
    int max_iterations = 40;
    double tolerance = 1e-4;      ///< stop when the weighted RMS distance to the targets is below this
    double damping = 1.0;         ///< initial Levenberg-Marquardt damping lambda (units of the Jacobian)
    double min_damping = 1e-6;
    /// Stall rule for targets out of reach: stop after `stall_iterations` accepted steps in a row that each
    /// lowered the weighted squared distance by at most this fraction of its new value (0: never). Default
    /// 1e-3 over 2 steps; 1e-9 over 1 step is the rule before (with synth_options::ik_warm_start off, the
    /// results as before).
    double stall_tolerance = 1e-3;
    int stall_iterations = 2;
};

/// @brief Outcome of one solve.
struct ik_report {
    double rms_before = 0, rms_after = 0;  ///< weighted RMS distance to the targets (before: of the given pose)
    int iterations = 0;
    bool warm = false;  ///< the solve started from the alternative start (solve()'s `start_angles`)
};

namespace detail {

/// Degrees of freedom of a skeleton for IK: 3 angles per joint (x, y, z, degrees), then the 3 position
/// channel values of `translation_joint` (if >= 0).
struct dof_layout {
    std::size_t joints = 0;
    int translation_joint = -1;
    std::size_t size() const noexcept { return joints * 3 + (translation_joint >= 0 ? 3 : 0); }
};

/// Buffers of one forward-kinematics pass of ik_kinematics, [J] each ([J, 3] for `waxis`); from
/// ik_kinematics::make_state, reused across passes.
struct ik_fk_state {
    std::vector<mat3> R;      ///< global rotation of every joint
    std::vector<vec3> org;    ///< joint origins
    std::vector<vec3> tip;    ///< End Sites (the joint's origin when it has none)
    std::vector<vec3> waxis;  ///< world axis of each of a joint's rotations, in its rotation order (forward with axes)
};

/// @brief The IK solver's forward kinematics and Jacobian (what ik_solver::solve runs, allocation-free once a
/// state is made). The unknowns q are dof_layout's: 3 angles per joint (x, y, z, degrees), then the position
/// channel values of the translation joint. The same positions as handemo::forward_kinematics (to rounding:
/// a rotation is applied in place to two columns instead of as a matrix product).
class ik_kinematics {
public:
    ik_kinematics() = default;
    /// @throws value_error when translation_joint (>= 0) is not a joint with position channels;
    ///         format_error when the skeleton is malformed.
    ik_kinematics(const skeleton& s, int translation_joint)
    {
        s.validate();
        layout_.joints = s.size();
        if (translation_joint >= 0) {
            if (static_cast<std::size_t>(translation_joint) >= s.size() ||
                !s.joints[static_cast<std::size_t>(translation_joint)].has_position())
                throw value_error("ik_solver: translation joint " + std::to_string(translation_joint) +
                                  " has no position channels in skeleton '" + s.name + "'");
            layout_.translation_joint = translation_joint;
        }
        kin_.resize(s.size());
        for (std::size_t j = 0; j < s.size(); ++j) {
            const joint& jt = s.joints[j];
            kin_[j].parent = jt.parent;
            kin_[j].offset = jt.offset;
            kin_[j].has_position = jt.has_position();
            kin_[j].has_end = jt.end_site.has_value();
            if (jt.end_site) kin_[j].end = *jt.end_site;
            const auto order = jt.rotation_order();
            for (int a = 0; a < 3; ++a) kin_[j].order[static_cast<std::size_t>(a)] = static_cast<int>(order[static_cast<std::size_t>(a)]);
        }
    }

    const dof_layout& layout() const noexcept { return layout_; }
    ik_fk_state make_state() const
    {
        const std::size_t J = kin_.size();
        return {std::vector<mat3>(J), std::vector<vec3>(J), std::vector<vec3>(J), std::vector<vec3>(J * 3)};
    }

    /// Forward kinematics at q [layout().size()] into `st`: global rotations, origins, End Sites and (when
    /// `axes`) the world axis of each of a joint's rotations in its order, w = R_parent R_a0 .. e_a.
    /// `positions` [J, 3]: position-channel values of the joints that have them (the translation joint's come
    /// from q); other joints use their offsets.
    void forward(const double* qq, const double* positions, ik_fk_state& st, bool axes) const noexcept
    {
        constexpr double rad = std::numbers::pi / 180.0;
        const std::size_t J = kin_.size();
        const int tj = layout_.translation_joint;
        std::vector<mat3>& R = st.R;
        std::vector<vec3>& org = st.org;
        std::vector<vec3>& tip = st.tip;
        std::vector<vec3>& waxis = st.waxis;
        for (std::size_t i = 0; i < J; ++i) {
            const kin& k = kin_[i];
            vec3 t = k.offset;
            if (static_cast<int>(i) == tj) t = {qq[J * 3], qq[J * 3 + 1], qq[J * 3 + 2]};
            else if (k.has_position) t = {positions[i * 3], positions[i * 3 + 1], positions[i * 3 + 2]};
            mat3 M{1, 0, 0, 0, 1, 0, 0, 0, 1};
            if (k.parent >= 0) {
                const auto p = static_cast<std::size_t>(k.parent);
                M = R[p];
                for (int c = 0; c < 3; ++c) org[i][c] = org[p][c] + M[c * 3] * t[0] + M[c * 3 + 1] * t[1] + M[c * 3 + 2] * t[2];
            } else {
                org[i] = t;
            }
            for (std::size_t slot = 0; slot < 3; ++slot) {
                const int ax = k.order[slot];
                if (axes) waxis[i * 3 + slot] = {M[ax], M[3 + ax], M[6 + ax]};
                // M <- M rot(ax, angle): only the other two columns change
                const double th = qq[i * 3 + static_cast<std::size_t>(ax)] * rad, cs = std::cos(th), sn = std::sin(th);
                const int u = ax == 0 ? 1 : ax == 1 ? 2 : 0, v = ax == 0 ? 2 : ax == 1 ? 0 : 1;  // (u, v, ax) cyclic
                for (int r = 0; r < 3; ++r) {
                    const double mu = M[r * 3 + u], mv = M[r * 3 + v];
                    M[r * 3 + u] = mu * cs + mv * sn;
                    M[r * 3 + v] = mv * cs - mu * sn;
                }
            }
            R[i] = M;
            tip[i] = org[i];
            if (k.has_end)
                for (int c = 0; c < 3; ++c)
                    tip[i][c] = org[i][c] + M[c * 3] * k.end[0] + M[c * 3 + 1] * k.end[1] + M[c * 3 + 2] * k.end[2];
        }
    }

    /// Position of a point after forward().
    static const vec3& point(const ik_fk_state& st, skeleton_point p) noexcept
    {
        const auto j = static_cast<std::size_t>(p.joint);
        return p.end_site ? st.tip[j] : st.org[j];
    }

    /// Appends the joints whose rotations move point p (the joint itself for an End Site, then its ancestors).
    void append_chain(skeleton_point p, std::vector<int>& chain) const
    {
        for (int a = p.end_site ? p.joint : kin_[static_cast<std::size_t>(p.joint)].parent; a >= 0;
             a = kin_[static_cast<std::size_t>(a)].parent)
            chain.push_back(a);
    }
    /// True when the translation moves point p (the translation joint is p's joint or an ancestor).
    bool translated(skeleton_point p) const noexcept
    {
        const int tj = layout_.translation_joint;
        if (tj < 0) return false;
        for (int j = p.joint; j >= 0; j = kin_[static_cast<std::size_t>(j)].parent)
            if (j == tj) return true;
        return false;
    }

    /// Square root of a target's weight (0 for a negative weight): the factor of its residual.
    static double sqrt_weight(const ik_target& t) noexcept { return std::sqrt(std::max(0.0, t.weight)); }

    /// Adds d r / d q of the residual r = sqrt_w (target - p) of one point p (after forward with axes) to rows
    /// `row`..`row + 2` of the transposed Jacobian jt ([layout().size(), m], DOF c's column at jt + c m), with
    /// the angles in degrees. `chain` and `translated` from append_chain and translated. The derivatives:
    ///   d p / d theta = (w x (p - o)) pi/180 for each rotation axis w through joint origin o above p;
    ///   d p / d t = R_parent of the translation joint (p = p_parent + R_parent t + ...).
    void add_residual_jacobian(const ik_fk_state& st, const double* p, std::span<const int> chain, bool translated,
                               const double* sqrt_w, double* jt, std::size_t m, std::size_t row) const noexcept
    {
        constexpr double rad = std::numbers::pi / 180.0;
        const std::size_t J = kin_.size();
        const double s0 = -sqrt_w[0] * rad, s1 = -sqrt_w[1] * rad, s2 = -sqrt_w[2] * rad;
        for (const int ci : chain) {
            const auto a = static_cast<std::size_t>(ci);
            const vec3& o = st.org[a];
            const double r0 = p[0] - o[0], r1 = p[1] - o[1], r2 = p[2] - o[2];
            for (std::size_t slot = 0; slot < 3; ++slot) {  // in rotation order (each axis once, joint::rotation_order())
                const vec3& w = st.waxis[a * 3 + slot];
                const auto ax = static_cast<std::size_t>(kin_[a].order[slot]);
                double* col = jt + (a * 3 + ax) * m + row;
                col[0] += s0 * (w[1] * r2 - w[2] * r1);
                col[1] += s1 * (w[2] * r0 - w[0] * r2);
                col[2] += s2 * (w[0] * r1 - w[1] * r0);
            }
        }
        if (translated) {
            const int tp = kin_[static_cast<std::size_t>(layout_.translation_joint)].parent;
            const mat3 Rp = tp >= 0 ? st.R[static_cast<std::size_t>(tp)] : mat3{1, 0, 0, 0, 1, 0, 0, 0, 1};
            for (std::size_t e = 0; e < 3; ++e)
                for (std::size_t c = 0; c < 3; ++c) jt[(J * 3 + e) * m + row + c] -= sqrt_w[c] * Rp[c * 3 + e];
        }
    }

    /// @brief The residuals r = sqrt(weight) (target - p) of `targets` ([3 P]) and their Jacobian d r / d q
    /// ([3 P, layout().size()], row-major, per degree for the angles) at q, computed by forward() and
    /// add_residual_jacobian() as ik_solver::solve computes them (for tests; allocates).
    /// @throws shape_error when a target names a joint outside the skeleton.
    void residuals_with_jacobian(const double* q, const double* positions, std::span<const ik_target> targets,
                                 double* out_r, double* jac) const
    {
        const std::size_t n = layout_.size(), m = 3 * targets.size();
        ik_fk_state st = make_state();
        forward(q, positions, st, true);
        std::vector<double> jt(n * m, 0.0);
        std::vector<int> chain;
        for (std::size_t k = 0; k < targets.size(); ++k) {
            const skeleton_point pt = targets[k].point;
            if (pt.joint < 0 || static_cast<std::size_t>(pt.joint) >= kin_.size())
                throw shape_error("ik_kinematics: target " + std::to_string(k) + " names joint " + std::to_string(pt.joint) +
                                  ", the skeleton has " + std::to_string(kin_.size()));
            const vec3& p = point(st, pt);
            const double sw = sqrt_weight(targets[k]), sw3[3] = {sw, sw, sw};
            for (std::size_t c = 0; c < 3; ++c) out_r[k * 3 + c] = (targets[k].position[c] - p[c]) * sw;
            chain.clear();
            append_chain(pt, chain);
            add_residual_jacobian(st, p.data(), chain, translated(pt), sw3, jt.data(), m, k * 3);
        }
        for (std::size_t r = 0; r < m; ++r)
            for (std::size_t c = 0; c < n; ++c) jac[r * n + c] = jt[c * m + r];
    }

private:
    struct kin {  // what forward kinematics needs of a joint
        int parent = -1;
        vec3 offset{}, end{};
        bool has_position = false, has_end = false;
        std::array<int, 3> order{};
    };
    std::vector<kin> kin_;
    dof_layout layout_;
};

/// Solves the symmetric positive definite system A x = b (A [m, m], overwritten) by Cholesky.
/// Returns false when A is not positive definite.
inline bool cholesky_solve(std::vector<double>& A, std::vector<double>& b, std::size_t m) noexcept
{
    for (std::size_t j = 0; j < m; ++j) {
        double d = A[j * m + j];
        for (std::size_t k = 0; k < j; ++k) d -= A[j * m + k] * A[j * m + k];
        if (!(d > 0)) return false;
        d = std::sqrt(d);
        A[j * m + j] = d;
        for (std::size_t i = j + 1; i < m; ++i) {
            double v = A[i * m + j];
            for (std::size_t k = 0; k < j; ++k) v -= A[i * m + k] * A[j * m + k];
            A[i * m + j] = v / d;
        }
    }
    for (std::size_t i = 0; i < m; ++i) {
        double v = b[i];
        for (std::size_t k = 0; k < i; ++k) v -= A[i * m + k] * b[k];
        b[i] = v / A[i * m + i];
    }
    for (std::size_t i = m; i-- > 0;) {
        double v = b[i];
        for (std::size_t k = i + 1; k < m; ++k) v -= A[k * m + i] * b[k];
        b[i] = v / A[i * m + i];
    }
    return true;
}

}  // namespace detail

/// @brief Damped least-squares IK on one skeleton. Construct once, solve many poses.
class ik_solver {
public:
    /// @param s the skeleton (limits from its joints; a range of 360 degrees or more is unlimited)
    /// @param translation_joint joint whose position channels are free (the pelvis, the hand's forearm), or -1
    /// @throws value_error when translation_joint is not a joint with position channels.
    ik_solver(const skeleton& s, int translation_joint, ik_options opt = {})
        : skel_(&s), opt_(opt), kin_(s, translation_joint)
    {
        const std::size_t n = kin_.layout().size();
        lo_.assign(n, -1e300);
        hi_.assign(n, 1e300);
        for (std::size_t j = 0; j < s.size(); ++j)
            for (std::size_t a = 0; a < 3; ++a)
                if (s.joints[j].limited(a)) lo_[j * 3 + a] = s.joints[j].lower_limit[a], hi_[j * 3 + a] = s.joints[j].upper_limit[a];
    }

    /// @brief Number of unknowns: 3 angles per joint (+ 3 translation values).
    std::size_t dof_count() const noexcept { return kin_.layout().size(); }
    /// @brief True when angle (joint, axis) is limited (range below 360 degrees).
    bool limited(std::size_t j, std::size_t a) const noexcept { return hi_[j * 3 + a] < 1e299; }
    /// @brief The forward kinematics and Jacobian that solve() runs (its finite-difference test reads them).
    const detail::ik_kinematics& kinematics() const noexcept { return kin_; }

    /// @brief Moves one pose so that its points reach the targets as well as they can.
    /// @param angles [J, 3] degrees, updated in place (clamped into the limits first)
    /// @param positions [J, 3] position-channel values (offsets for joints without), updated in place
    ///        for the translation joint only
    /// @param start_angles, start_positions an alternative start ([J, 3] each, or empty), e.g. the previous
    ///        keyframe's solution moved to this one: the solve starts from whichever of the two poses is nearer
    ///        the targets (of start_positions only the translation joint's values are read)
    /// @throws shape_error when a target names a joint outside the skeleton or a start has the wrong size.
    ik_report solve(std::span<double> angles, std::span<double> positions, std::span<const ik_target> targets,
                    std::span<const double> start_angles = {}, std::span<const double> start_positions = {}) const
    {
        const skeleton& s = *skel_;
        const std::size_t J = s.size(), n = kin_.layout().size(), P = targets.size(), m = 3 * P;
        if (angles.size() != J * 3 || positions.size() != J * 3)
            throw shape_error("ik_solver::solve: pose holds " + std::to_string(angles.size()) + "/" +
                              std::to_string(positions.size()) + " values, expected joints*3 = " + std::to_string(J * 3));
        const bool alt = !start_angles.empty();
        if (alt && (start_angles.size() != J * 3 || start_positions.size() != J * 3))
            throw shape_error("ik_solver::solve: start pose holds " + std::to_string(start_angles.size()) + "/" +
                              std::to_string(start_positions.size()) + " values, expected joints*3 = " + std::to_string(J * 3));
        const int tj = kin_.layout().translation_joint;
        std::vector<double> tgt(m), sw(m);
        // Per target: the rotation DOFs' joints that move it (chain[chain_at[k] .. chain_at[k + 1]]) and whether
        // the translation moves it.
        std::vector<int> chain, chain_at(P + 1, 0);
        std::vector<char> translated(P, 0);
        for (std::size_t k = 0; k < P; ++k) {
            const int pj = targets[k].point.joint;
            if (pj < 0 || static_cast<std::size_t>(pj) >= J)
                throw shape_error("ik_solver::solve: target " + std::to_string(k) + " names joint " + std::to_string(pj) +
                                  ", the skeleton has " + std::to_string(J));
            for (int c = 0; c < 3; ++c) {
                tgt[k * 3 + c] = targets[k].position[c];
                sw[k * 3 + c] = detail::ik_kinematics::sqrt_weight(targets[k]);
            }
            kin_.append_chain(targets[k].point, chain);
            chain_at[k + 1] = static_cast<int>(chain.size());
            translated[k] = kin_.translated(targets[k].point);
        }
        std::vector<double> q(n), qn(n);
        auto load = [&](std::vector<double>& qq, std::span<const double> a, std::span<const double> p) {
            std::copy(a.begin(), a.end(), qq.begin());
            if (tj >= 0)
                for (int c = 0; c < 3; ++c) qq[J * 3 + c] = p[static_cast<std::size_t>(tj) * 3 + c];
            for (std::size_t i = 0; i < n; ++i) qq[i] = std::clamp(qq[i], lo_[i], hi_[i]);
        };
        load(q, angles, positions);

        double wsum = 0;
        for (std::size_t i = 0; i < m; ++i) wsum += sw[i] * sw[i];
        wsum = std::max(wsum / 3.0, 1e-300);
        // Forward kinematics into the solver's buffers (with the world axes when the Jacobian is wanted), then
        // the points' positions and the weighted squared distance to the targets.
        detail::ik_fk_state st = kin_.make_state();
        std::vector<double> cur(m);
        auto fk = [&](const std::vector<double>& qq, bool axes) {
            kin_.forward(qq.data(), positions.data(), st, axes);
            double e = 0;
            for (std::size_t k = 0; k < P; ++k) {
                const vec3& p = detail::ik_kinematics::point(st, targets[k].point);
                for (int c = 0; c < 3; ++c) cur[k * 3 + static_cast<std::size_t>(c)] = p[c];
            }
            for (std::size_t i = 0; i < m; ++i) e += sw[i] * sw[i] * (tgt[i] - cur[i]) * (tgt[i] - cur[i]);
            return e;
        };
        ik_report rep;
        double err = fk(q, false);
        rep.rms_before = std::sqrt(err / wsum);
        if (alt) {
            load(qn, start_angles, start_positions);
            const double ea = fk(qn, false);
            if (ea < err) {
                q.swap(qn);
                err = ea;
                rep.warm = true;
            }
        }
        double lambda = opt_.damping;
        // jt: the residual's Jacobian d r / d q transposed ([n, m], a DOF's column contiguous), r = sqrt(w) (target - p)
        std::vector<double> jt(n * m), A0(m * m), G(m * m), A(m * m), y(m), dq(n), r(m);
        std::vector<char> locked(n), locked0(n);
        // A DOF without range (lower = upper limit) is held from the start; the others are free at first.
        for (std::size_t c = 0; c < n; ++c) locked0[c] = lo_[c] >= hi_[c];
        bool fresh = false;  // jt, r and A0 belong to the current q
        int stalled = 0;
        // G = J_free J_free^T (lower triangle, all cholesky_solve reads) as a sum of rank-1 updates over the
        // free DOFs, in DOF order: the inner loop is contiguous and vectorises. Once per Jacobian; a DOF locked
        // by a later pass is taken out by a rank-1 downdate, and a rejected step reuses it with more damping.
        auto rank1 = [&](std::vector<double>& S, std::size_t c, double sign) {
            const double* col = jt.data() + c * m;
            for (std::size_t a = 0; a < m; ++a) {
                const double ca = sign * col[a];
                double* row = S.data() + a * m;
                for (std::size_t b = 0; b <= a; ++b) row[b] += ca * col[b];
            }
        };
        for (int it = 0; it < opt_.max_iterations && std::sqrt(err / wsum) > opt_.tolerance; ++it) {
            rep.iterations = it + 1;
            if (!fresh) {
                fk(q, true);
                for (std::size_t i = 0; i < m; ++i) r[i] = (tgt[i] - cur[i]) * sw[i];
                std::fill(jt.begin(), jt.end(), 0.0);
                for (std::size_t k = 0; k < P; ++k) {
                    const std::span<const int> ch(chain.data() + chain_at[k], chain.data() + chain_at[k + 1]);
                    kin_.add_residual_jacobian(st, cur.data() + k * 3, ch, translated[k] != 0, sw.data() + k * 3, jt.data(), m, k * 3);
                }
                std::fill(A0.begin(), A0.end(), 0.0);
                for (std::size_t c = 0; c < n; ++c)
                    if (!locked0[c]) rank1(A0, c, 1.0);
                fresh = true;
            }
            // Minimise |r + J dq|^2 + lambda^2 |dq|^2 over the free DOFs: dq = -J^T (J J^T + lambda^2 I)^-1 r.
            locked = locked0;
            G = A0;
            bool solved = false;
            for (int pass = 0; pass < 4; ++pass) {
                if (pass > 0)
                    for (std::size_t c = 0; c < n; ++c)
                        if (locked[c] == 2) rank1(G, c, -1.0), locked[c] = 1;  // locked by the last pass
                A = G;
                for (std::size_t a = 0; a < m; ++a) A[a * m + a] += lambda * lambda;
                for (std::size_t a = 0; a < m; ++a) y[a] = -r[a];
                if (!detail::cholesky_solve(A, y, m)) break;
                solved = true;
                bool again = false;
                for (std::size_t c = 0; c < n; ++c) {
                    double v = 0;
                    if (!locked[c]) {
                        const double* col = jt.data() + c * m;
                        for (std::size_t a = 0; a < m; ++a) v += col[a] * y[a];
                    }
                    dq[c] = v;
                    const double nv = q[c] + v;
                    if (!locked[c] && (nv < lo_[c] || nv > hi_[c]) && pass < 3) {
                        locked[c] = 2;  // would leave its range: hold it at the limit, solve again
                        again = true;
                    }
                }
                if (!again) break;
            }
            if (!solved) std::fill(dq.begin(), dq.end(), 0.0);  // counts as a failed step: more damping
            for (std::size_t c = 0; c < n; ++c) qn[c] = std::clamp(q[c] + dq[c], lo_[c], hi_[c]);
            const double en = fk(qn, false);
            if (en < err) {
                q.swap(qn);
                const double gain = err - en;
                err = en;
                fresh = false;
                lambda = std::max(opt_.min_damping, lambda * 0.3);
                // out of reach: progress has stalled (the best pose seen is q, every accepted step lowers err)
                stalled = gain <= opt_.stall_tolerance * err ? stalled + 1 : 0;
                if (stalled >= std::max(1, opt_.stall_iterations)) break;
            } else {
                lambda *= 4.0;
                if (lambda > 1e8) break;
            }
        }
        rep.rms_after = std::sqrt(err / wsum);
        std::copy(q.begin(), q.begin() + static_cast<std::ptrdiff_t>(J * 3), angles.begin());
        if (tj >= 0)
            for (int c = 0; c < 3; ++c) positions[static_cast<std::size_t>(tj) * 3 + c] = q[J * 3 + c];
        return rep;
    }

private:
    const skeleton* skel_;
    ik_options opt_;
    detail::ik_kinematics kin_;
    std::vector<double> lo_, hi_;
};

}  // namespace handemo::rcm
