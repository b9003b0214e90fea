// Full-body inverse kinematics for the synthesis of Aristidou et al. 2017 (Section 4: "we then pass these
// joint positions to an Inverse Kinematics solver ... to solve for the fullbody poses", FBBIK in the
// paper). Here: damped least squares (Levenberg-Marquardt) over all joint angles and the translation of one
// joint (the pelvis, or the hand's forearm). The solver's forward kinematics writes the world axis of every
// rotation DOF as it goes, so the Jacobian of the control points is w x (p - o) per axis above the point
// (the same as the tape node `fk_points`, which the finite-difference tests check, without a reverse sweep
// per row). Bone lengths are kept exactly because the unknowns are angles (positions follow from forward
// kinematics with the skeleton's fixed offsets and position-channel values); joint limits are kept by
// projection with an active set (a DOF that a step would push past its limit is held at the limit and the
// step solved again without it). Axes whose range is 360 degrees or more (BVH's +-180) are unlimited.
#pragma once

#include <handemo/autodiff.hpp>
#include <handemo/core/error.hpp>
#include <handemo/motion/skeleton.hpp>

#include <algorithm>
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

/// True when `a` is `b` or one of its ancestors.
inline bool is_ancestor_or_self(const skeleton& s, int a, int b) noexcept
{
    for (int j = b; j >= 0; j = s.joints[static_cast<std::size_t>(j)].parent)
        if (j == a) return true;
    return false;
}

/// Positions of `points` and their Jacobian d p / d q ([3 P, n], degrees for angles) at q. `base_positions`
/// [J, 3] are the position-channel values (or offsets) of every joint; the translation joint's come from q.
inline void fk_with_jacobian(const skeleton& s, const dof_layout& L, const double* q, const double* base_positions,
                             std::span<const skeleton_point> points, double* out_pos, double* jac)
{
    const std::size_t J = s.size(), n = L.size(), P = points.size();
    thread_local std::vector<double> pos;
    pos.assign(base_positions, base_positions + J * 3);
    if (L.translation_joint >= 0)
        for (int c = 0; c < 3; ++c) pos[static_cast<std::size_t>(L.translation_joint) * 3 + c] = q[J * 3 + c];
    const pose_positions fk = forward_kinematics(s, q, pos.data());
    constexpr double rad = std::numbers::pi / 180.0;
    if (jac) std::fill(jac, jac + 3 * P * n, 0.0);
    for (std::size_t k = 0; k < P; ++k) {
        const auto j = static_cast<std::size_t>(points[k].joint);
        const vec3 p = points[k].end_site ? fk.end_sites[j] : fk.joints[j];
        for (int c = 0; c < 3; ++c) out_pos[k * 3 + c] = p[c];
        if (!jac) continue;
        double* row0 = jac + (k * 3) * n;
        // Rotations of every joint whose rotation moves p: the joint itself for an End Site, then ancestors.
        int a = points[k].end_site ? static_cast<int>(j) : s.joints[j].parent;
        for (; a >= 0; a = s.joints[static_cast<std::size_t>(a)].parent) {
            const auto au = static_cast<std::size_t>(a);
            const joint& ja = s.joints[au];
            mat3 R = ja.parent >= 0 ? fk.rotations[static_cast<std::size_t>(ja.parent)] : mat3{1, 0, 0, 0, 1, 0, 0, 0, 1};
            const vec3& o = fk.joints[au];
            const vec3 r{p[0] - o[0], p[1] - o[1], p[2] - o[2]};
            for (axis ax : ja.rotation_order()) {
                const int ai = static_cast<int>(ax);
                const vec3 w{R[0 * 3 + ai], R[1 * 3 + ai], R[2 * 3 + ai]};  // world axis = R e_ax
                // d p / d theta = (w x r) pi/180 for theta in degrees
                const vec3 d{w[1] * r[2] - w[2] * r[1], w[2] * r[0] - w[0] * r[2], w[0] * r[1] - w[1] * r[0]};
                const std::size_t col = au * 3 + static_cast<std::size_t>(ai);
                for (int c = 0; c < 3; ++c) row0[c * n + col] += d[c] * rad;
                R = matmul(R, axis_rotation(ax, q[au * 3 + static_cast<std::size_t>(ai)]));
            }
        }
        // Translation: p_t = p_parent + R_parent t, so d p / d t = R_parent for every point below t.
        if (L.translation_joint >= 0 && is_ancestor_or_self(s, L.translation_joint, static_cast<int>(j))) {
            const joint& jt = s.joints[static_cast<std::size_t>(L.translation_joint)];
            const mat3 R = jt.parent >= 0 ? fk.rotations[static_cast<std::size_t>(jt.parent)] : mat3{1, 0, 0, 0, 1, 0, 0, 0, 1};
            for (int c = 0; c < 3; ++c)
                for (int e = 0; e < 3; ++e) row0[c * n + J * 3 + static_cast<std::size_t>(e)] += R[c * 3 + e];
        }
    }
}

/// Context of an fk_points node: what its forward pass needs (the backward reads only the stored Jacobian).
struct fk_context {
    const skeleton* skel = nullptr;
    dof_layout layout;
    const double* base_positions = nullptr;
    std::span<const skeleton_point> points;
};

// y = FK(q) at the requested points, [3 P]. The forward pass stores the local Jacobian d y / d q [3P, n]
// (rows: d p / d theta = (w x (p - o)) pi/180 for each rotation axis w through joint origin o above the
// point; d p / d t = R_parent for the translation).  d/dq = J^T g.
inline void fk_points_backward(autodiff::tape<double>& t, int self)
{
    const auto& nd = t.at(self);
    double* gq = t.adj(nd.in[0]);
    if (!gq) return;
    const std::size_t m = nd.size, n = t.at(nd.in[0]).size;
    for (std::size_t r = 0; r < m; ++r) {
        const double g = nd.adjoint[r];
        if (g == 0.0) continue;
        const double* row = nd.aux + r * n;
        for (std::size_t c = 0; c < n; ++c) gq[c] += g * row[c];
    }
}

/// @brief Positions of the context's points as a tape node of q (a node of size dof_layout::size()).
inline int fk_points(autodiff::tape<double>& t, int q, const fk_context& ctx)
{
    const std::size_t n = ctx.layout.size(), m = ctx.points.size() * 3;
    if (t.at(q).size != n)
        throw shape_error("rcm::fk_points: q has " + std::to_string(t.at(q).size) + " values, expected " + std::to_string(n));
    double* aux = t.alloc(m * n);
    const int id = t.make("fk_points", m, {q}, &fk_points_backward, nullptr);
    t.at(id).aux = aux;
    fk_with_jacobian(*ctx.skel, ctx.layout, t.at(q).value, ctx.base_positions, ctx.points, t.at(id).value, aux);
    return id;
}

/// @brief d out / d in ([size(out), size(in)], row-major) by one reverse sweep per output element over the
/// nodes recorded between `in` and `out` (the vector-Jacobian products of their backward functions).
inline void reverse_jacobian(autodiff::tape<double>& t, int out, int in, double* jac)
{
    const std::size_t m = t.at(out).size, n = t.at(in).size;
    for (std::size_t r = 0; r < m; ++r) {
        for (int i = in; i <= out; ++i) {
            auto& nd = t.at(i);
            if (nd.requires_grad) std::fill(nd.adjoint, nd.adjoint + nd.size, 0.0);
        }
        t.at(out).adjoint[r] = 1.0;
        for (int i = out; i > in; --i) {
            auto& nd = t.at(i);
            if (nd.requires_grad && nd.backward) nd.backward(t, i);
        }
        std::copy(t.at(in).adjoint, t.at(in).adjoint + n, jac + r * n);
    }
}

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
    ik_solver(const skeleton& s, int translation_joint, ik_options opt = {}) : skel_(&s), opt_(opt)
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
        const std::size_t n = layout_.size();
        lo_.assign(n, -1e300);
        hi_.assign(n, 1e300);
        for (std::size_t j = 0; j < s.size(); ++j)
            for (std::size_t a = 0; a < 3; ++a) {
                const double l = s.joints[j].lower_limit[a], u = s.joints[j].upper_limit[a];
                if (u - l < 360.0) lo_[j * 3 + a] = l, hi_[j * 3 + a] = u;
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

    /// @brief Number of unknowns: 3 angles per joint (+ 3 translation values).
    std::size_t dof_count() const noexcept { return layout_.size(); }
    /// @brief True when angle (joint, axis) is limited (range below 360 degrees).
    bool limited(std::size_t j, std::size_t a) const noexcept { return hi_[j * 3 + a] < 1e299; }

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
        const std::size_t J = s.size(), n = layout_.size(), P = targets.size(), m = 3 * P;
        if (angles.size() != J * 3 || positions.size() != J * 3)
            throw shape_error("ik_solver::solve: pose holds " + std::to_string(angles.size()) + "/" +
                              std::to_string(positions.size()) + " values, expected joints*3 = " + std::to_string(J * 3));
        const bool alt = !start_angles.empty();
        if (alt && (start_angles.size() != J * 3 || start_positions.size() != J * 3))
            throw shape_error("ik_solver::solve: start pose holds " + std::to_string(start_angles.size()) + "/" +
                              std::to_string(start_positions.size()) + " values, expected joints*3 = " + std::to_string(J * 3));
        const int tj = layout_.translation_joint;
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
                sw[k * 3 + c] = std::sqrt(std::max(0.0, targets[k].weight));
            }
            for (int a = targets[k].point.end_site ? pj : kin_[static_cast<std::size_t>(pj)].parent; a >= 0;
                 a = kin_[static_cast<std::size_t>(a)].parent)
                chain.push_back(a);
            chain_at[k + 1] = static_cast<int>(chain.size());
            translated[k] = tj >= 0 && detail::is_ancestor_or_self(s, tj, pj);
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
        // Forward kinematics into the solver's buffers: global rotations, origins, End Sites and (for the
        // Jacobian) the world axis of each of a joint's rotations in its order, w = R_parent R_a0 .. e_a.
        std::vector<mat3> R(J);
        std::vector<vec3> org(J), tip(J), waxis(J * 3);
        std::vector<double> cur(m);
        auto fk = [&](const std::vector<double>& qq, bool axes) {
            constexpr double rad = std::numbers::pi / 180.0;
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
            double e = 0;
            for (std::size_t k = 0; k < P; ++k) {
                const auto j = static_cast<std::size_t>(targets[k].point.joint);
                const vec3& p = targets[k].point.end_site ? tip[j] : org[j];
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
                constexpr double rad = std::numbers::pi / 180.0;
                fk(q, true);
                for (std::size_t i = 0; i < m; ++i) r[i] = (tgt[i] - cur[i]) * sw[i];
                std::fill(jt.begin(), jt.end(), 0.0);
                for (std::size_t k = 0; k < P; ++k) {
                    const double* p = cur.data() + k * 3;
                    const double s0 = -sw[k * 3] * rad, s1 = -sw[k * 3 + 1] * rad, s2 = -sw[k * 3 + 2] * rad;
                    for (int ci = chain_at[k]; ci < chain_at[k + 1]; ++ci) {
                        const auto a = static_cast<std::size_t>(chain[static_cast<std::size_t>(ci)]);
                        const double r0 = p[0] - org[a][0], r1 = p[1] - org[a][1], r2 = p[2] - org[a][2];
                        for (std::size_t slot = 0; slot < 3; ++slot) {  // in rotation order (an axis may repeat)
                            const vec3& w = waxis[a * 3 + slot];  // d p / d theta = (w x (p - o)) pi/180, theta in degrees
                            const auto ax = static_cast<std::size_t>(kin_[a].order[slot]);
                            double* col = jt.data() + (a * 3 + ax) * m + k * 3;
                            col[0] += s0 * (w[1] * r2 - w[2] * r1);
                            col[1] += s1 * (w[2] * r0 - w[0] * r2);
                            col[2] += s2 * (w[0] * r1 - w[1] * r0);
                        }
                    }
                    if (translated[k]) {  // p = p_parent + R_parent t: d p / d t = R_parent
                        const int tp = kin_[static_cast<std::size_t>(tj)].parent;
                        const mat3 Rp = tp >= 0 ? R[static_cast<std::size_t>(tp)] : mat3{1, 0, 0, 0, 1, 0, 0, 0, 1};
                        for (std::size_t e = 0; e < 3; ++e)
                            for (std::size_t c = 0; c < 3; ++c) jt[(J * 3 + e) * m + k * 3 + c] -= sw[k * 3 + c] * Rp[c * 3 + e];
                    }
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
    struct kin {  // what forward kinematics needs of a joint
        int parent = -1;
        vec3 offset{}, end{};
        bool has_position = false, has_end = false;
        std::array<int, 3> order{};
    };
    const skeleton* skel_;
    detail::dof_layout layout_;
    ik_options opt_;
    std::vector<double> lo_, hi_;
    std::vector<kin> kin_;
};

}  // namespace handemo::rcm
