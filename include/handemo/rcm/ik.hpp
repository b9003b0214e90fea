// Full-body inverse kinematics for the synthesis of Aristidou et al. 2017 (Section 4: "we then pass these
// joint positions to an Inverse Kinematics solver ... to solve for the fullbody poses", FBBIK in the
// paper). Here: damped least squares (Levenberg-Marquardt) over all joint angles and the translation of one
// joint (the pelvis, or the hand's forearm), with the Jacobian of the control points taken through
// handemo's reverse-mode tape: forward kinematics is one tape node (`fk_points`) and every Jacobian row is
// one reverse sweep. Bone lengths are kept exactly because the unknowns are angles (positions follow from
// forward kinematics with the skeleton's fixed offsets and position-channel values); joint limits are kept
// by projection with an active set (a DOF that a step would push past its limit is held at the limit and
// the step is solved again without it). Axes whose range is 360 degrees or more (BVH's +-180) are
// unlimited.
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
};

/// @brief Outcome of one solve.
struct ik_report {
    double rms_before = 0, rms_after = 0;  ///< weighted RMS distance to the targets
    int iterations = 0;
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
    }

    /// @brief Number of unknowns: 3 angles per joint (+ 3 translation values).
    std::size_t dof_count() const noexcept { return layout_.size(); }
    /// @brief True when angle (joint, axis) is limited (range below 360 degrees).
    bool limited(std::size_t j, std::size_t a) const noexcept { return hi_[j * 3 + a] < 1e299; }

    /// @brief Moves one pose so that its points reach the targets as well as they can.
    /// @param angles [J, 3] degrees, updated in place (clamped into the limits first)
    /// @param positions [J, 3] position-channel values (offsets for joints without), updated in place
    ///        for the translation joint only
    /// @throws shape_error when a target names a joint outside the skeleton.
    ik_report solve(std::span<double> angles, std::span<double> positions, std::span<const ik_target> targets) const
    {
        const skeleton& s = *skel_;
        const std::size_t J = s.size(), n = layout_.size(), P = targets.size(), m = 3 * P;
        if (angles.size() != J * 3 || positions.size() != J * 3)
            throw shape_error("ik_solver::solve: pose holds " + std::to_string(angles.size()) + "/" +
                              std::to_string(positions.size()) + " values, expected joints*3 = " + std::to_string(J * 3));
        std::vector<skeleton_point> pts(P);
        std::vector<double> tgt(m), sw(m);
        for (std::size_t k = 0; k < P; ++k) {
            if (targets[k].point.joint < 0 || static_cast<std::size_t>(targets[k].point.joint) >= J)
                throw shape_error("ik_solver::solve: target " + std::to_string(k) + " names joint " +
                                  std::to_string(targets[k].point.joint) + ", the skeleton has " + std::to_string(J));
            pts[k] = targets[k].point;
            for (int c = 0; c < 3; ++c) {
                tgt[k * 3 + c] = targets[k].position[c];
                sw[k * 3 + c] = std::sqrt(std::max(0.0, targets[k].weight));
            }
        }
        std::vector<double> q(n);
        std::copy(angles.begin(), angles.end(), q.begin());
        if (layout_.translation_joint >= 0)
            for (int c = 0; c < 3; ++c) q[J * 3 + c] = positions[static_cast<std::size_t>(layout_.translation_joint) * 3 + c];
        for (std::size_t i = 0; i < n; ++i) q[i] = std::clamp(q[i], lo_[i], hi_[i]);

        double wsum = 0;
        for (std::size_t i = 0; i < m; ++i) wsum += sw[i] * sw[i];
        wsum = std::max(wsum / 3.0, 1e-300);
        std::vector<double> cur(m);
        auto error = [&](const std::vector<double>& qq) {
            detail::fk_with_jacobian(s, layout_, qq.data(), positions.data(), pts, cur.data(), nullptr);
            double e = 0;
            for (std::size_t i = 0; i < m; ++i) e += sw[i] * sw[i] * (tgt[i] - cur[i]) * (tgt[i] - cur[i]);
            return e;
        };
        ik_report rep;
        double err = error(q);
        rep.rms_before = std::sqrt(err / wsum);
        double lambda = opt_.damping;
        autodiff::tape<double> tp(std::size_t{1} << 14);
        detail::fk_context ctx{&s, layout_, positions.data(), pts};
        std::vector<double> jac(m * n), jt(n * m), A(m * m), y(m), dq(n), qn(n), r(m);
        std::vector<char> locked(n);
        bool fresh = false;  // jac and r belong to the current q
        for (int it = 0; it < opt_.max_iterations && std::sqrt(err / wsum) > opt_.tolerance; ++it) {
            rep.iterations = it + 1;
            if (!fresh) {
                // residual r = sqrt(w) (target - FK(q)) on the tape; its Jacobian by reverse sweeps.
                tp.reset();
                const int qid = tp.leaf_copy(q.data(), n, true);
                const int fk = detail::fk_points(tp, qid, ctx);
                const int res = autodiff::detail::mul_raw(
                    tp, autodiff::detail::sub_raw(tp, tp.leaf_copy(tgt.data(), m, false), fk), tp.leaf_copy(sw.data(), m, false));
                detail::reverse_jacobian(tp, res, qid, jac.data());
                std::copy(tp.at(res).value, tp.at(res).value + m, r.begin());
                fresh = true;
            }
            // Minimise |r + J dq|^2 + lambda^2 |dq|^2 over the free DOFs: dq = -J^T (J J^T + lambda^2 I)^-1 r.
            std::fill(locked.begin(), locked.end(), 0);
            for (std::size_t a = 0; a < m; ++a)  // J's columns contiguous, for the rank-1 updates below
                for (std::size_t c = 0; c < n; ++c) jt[c * m + a] = jac[a * n + c];
            for (int pass = 0; pass < 4; ++pass) {
                // A = J_free J_free^T + lambda^2 I as a sum of rank-1 updates over the free DOFs, in DOF order (the
                // same sums, element by element, as row-times-row products; the inner loop is contiguous and
                // vectorises, where a dot product with a per-DOF test did not: 85% of a 680-frame hand synthesis)
                std::fill(A.begin(), A.end(), 0.0);
                for (std::size_t c = 0; c < n; ++c) {
                    if (locked[c]) continue;
                    const double* col = jt.data() + c * m;
                    for (std::size_t a = 0; a < m; ++a) {
                        const double ca = col[a];
                        double* row = A.data() + a * m;
                        for (std::size_t b = 0; b <= a; ++b) row[b] += ca * col[b];
                    }
                }
                for (std::size_t a = 0; a < m; ++a) {
                    for (std::size_t b = 0; b < a; ++b) A[b * m + a] = A[a * m + b];
                    A[a * m + a] += lambda * lambda;
                }
                for (std::size_t a = 0; a < m; ++a) y[a] = -r[a];
                if (!detail::cholesky_solve(A, y, m)) break;
                bool again = false;
                for (std::size_t c = 0; c < n; ++c) {
                    double v = 0;
                    if (!locked[c])
                        for (std::size_t a = 0; a < m; ++a) v += jac[a * n + c] * y[a];
                    dq[c] = v;
                    const double nv = q[c] + v;
                    if (!locked[c] && (nv < lo_[c] || nv > hi_[c]) && pass < 3) {
                        locked[c] = 1;  // would leave its range: hold it at the limit, solve again
                        again = true;
                    }
                }
                if (!again) break;
            }
            for (std::size_t c = 0; c < n; ++c) qn[c] = std::clamp(q[c] + dq[c], lo_[c], hi_[c]);
            const double en = error(qn);
            if (en < err) {
                q.swap(qn);
                const double gain = err - en;
                err = en;
                fresh = false;
                lambda = std::max(opt_.min_damping, lambda * 0.3);
                if (gain <= 1e-9 * err) break;  // converged to what it can reach (targets out of reach)
            } else {
                lambda *= 4.0;
                if (lambda > 1e8) break;
            }
        }
        rep.rms_after = std::sqrt(err / wsum);
        std::copy(q.begin(), q.begin() + static_cast<std::ptrdiff_t>(J * 3), angles.begin());
        if (layout_.translation_joint >= 0)
            for (int c = 0; c < 3; ++c) positions[static_cast<std::size_t>(layout_.translation_joint) * 3 + c] = q[J * 3 + c];
        return rep;
    }

private:
    const skeleton* skel_;
    detail::dof_layout layout_;
    ik_options opt_;
    std::vector<double> lo_, hi_;
};

}  // namespace handemo::rcm
