// Moving motion through a retarget_map (map.hpp). Every driven joint takes, in world space, the bone frame of
// its counterpart: with G a joint's global rotation and L its rest bone frame,
//     G_target * L_target = F_target * X * (F_source^T * G_source * L_source) * X,
// where F is the frame of reference (the identity for bodies; for a hand, the bone frame of its forearm, or of
// its wrist where the source has no forearm) and X = diag(1, 1, -1) for a mirrored hand (a left hand on a
// right-hand model: the reflection cancels out of every relative frame, so no mirror plane has to be chosen),
// else the identity. Local rotations follow from the globals down each skeleton's own hierarchy and become
// Euler angles in each joint's own channel order, nearest the previous frame's. So rest poses, channel orders,
// hierarchies and bone lengths may all differ; positions follow from each skeleton's own bones. A body's root
// translation is scaled by the ratio of the driven bones' lengths (proportions, cm and m).
//
// write_back() goes the other way onto the source skeleton: only the driven joints' rotation channels change;
// every other channel is the source's, resampled to the output's frame count when a transfer changed the tempo.
#pragma once

#include <handemo/core/error.hpp>
#include <handemo/motion/clip.hpp>
#include <handemo/retarget/map.hpp>
#include <handemo/retarget/rotation.hpp>

#include <cmath>
#include <cstddef>
#include <string>
#include <vector>

namespace handemo::retarget {

/// @brief `c` resampled to `frames` frames, every angle and position channel linear in time (the first and
/// last frames kept; the frame rate kept, so the duration scales). `frames == c.frames` returns `c` exactly, and a
/// channel that holds still keeps its value to the bit.
/// @throws value_error when `frames` is 0.
inline clip resample(const clip& c, std::size_t frames)
{
    if (frames == 0) throw value_error("retarget: cannot resample to 0 frames");
    if (frames == c.frames) return c;
    clip out = c;
    out.frames = frames;
    const std::size_t J3 = c.skel.size() * 3;
    out.angles.assign(frames * J3, 0.0);
    out.positions.assign(frames * J3, 0.0);
    for (std::size_t f = 0; f < frames; ++f) {
        const double t = frames > 1 ? static_cast<double>(f) * static_cast<double>(c.frames - 1) / static_cast<double>(frames - 1) : 0.0;
        const auto f0 = static_cast<std::size_t>(std::floor(t));
        const std::size_t f1 = std::min(f0 + 1, c.frames - 1);
        const double a = t - static_cast<double>(f0);
        // x0 + a (x1 - x0) with one rounding (std::fma): the same bits whatever the compiler contracts, and a
        // channel that holds still (x1 == x0) keeps its value exactly
        for (std::size_t i = 0; i < J3; ++i) {
            const double p0 = c.angles[f0 * J3 + i], q0 = c.positions[f0 * J3 + i];
            out.angles[f * J3 + i] = std::fma(a, c.angles[f1 * J3 + i] - p0, p0);
            out.positions[f * J3 + i] = std::fma(a, c.positions[f1 * J3 + i] - q0, q0);
        }
    }
    return out;
}

namespace detail {

inline mat3 reflect_if(bool mirror, const mat3& m) noexcept { return mirror ? mirrored(m) : m; }

/// The global rotation a driven joint takes from its counterpart: F_to * X (F_from^T G_from L_from) X * L_to^T.
inline mat3 carry(const mat3& f_to, const mat3& f_from, const mat3& g_from, const mat3& l_from, const mat3& l_to, bool mirror) noexcept
{
    const mat3 rel = matmul(transpose(f_from), matmul(g_from, l_from));
    return matmul(f_to, matmul(reflect_if(mirror, rel), transpose(l_to)));
}

}  // namespace detail

/// @brief Moves `in` (on m.source) onto m.target: same frames and frame rate. Driven joints take their
/// counterparts' bone frames; the target's other joints stay at rest (angles 0, positions their offsets),
/// except a body's hips, placed at the source hips' position times m.scale (through the position channels of
/// the hips or of their nearest ancestor that has some).
/// Of the two Euler solutions of a rotation (and their 360-degree turns) the first frame takes the one nearest
/// `reference` ([J*3] target angles; default all 0), every later frame the one nearest the frame before: a model
/// sees the branch its training data used when `reference` is its typical pose (transfer_capture() passes the
/// centre of the model's angle range).
/// @throws shape_error when the clip's skeleton is not m.source or the reference has the wrong size;
/// value_error for a non-finite clip.
inline clip retarget_clip(const clip& in, const retarget_map& m, const std::vector<double>& reference = {})
{
    if (!reference.empty() && reference.size() != m.target.size() * 3)
        throw shape_error("retarget: reference pose has " + std::to_string(reference.size()) + " angles, the target '" + m.target.name + "' needs " +
                          std::to_string(m.target.size() * 3));
    if (!in.skel.same_topology(m.source))
        throw shape_error("retarget: clip '" + in.skel.name + "' is not on the map's source skeleton '" + m.source.name + "'");
    in.validate("retarget: " + in.skel.name);
    const skeleton& T = m.target;
    const std::size_t J = T.size();
    clip out = clip::make(T, in.frames, in.fps);
    const bool hand = m.kind == target_kind::hand;
    std::vector<mat3> g(J);
    for (std::size_t f = 0; f < in.frames; ++f) {
        const auto src = forward_kinematics(in.skel, in.frame_angles(f), in.frame_positions(f));
        const mat3 fs = hand ? matmul(src.rotations[m.source_anchor], m.ls_anchor) : identity3;
        // the target above and at its anchor is at rest: its global rotation is the identity
        const mat3 ft = hand ? m.lt_anchor : identity3;
        for (std::size_t j = 0; j < J; ++j) {
            const int p = T.joints[j].parent;
            const mat3 gp = p < 0 ? identity3 : g[static_cast<std::size_t>(p)];
            if (const int k = m.pair_of_target[j]; k >= 0) {
                const auto& pr = m.pairs[static_cast<std::size_t>(k)];
                g[j] = detail::carry(ft, fs, src.rotations[pr.source], pr.ls, pr.lt, m.mirror);
                const vec3 ref = f > 0             ? vec3{out.angle(f - 1, j, 0), out.angle(f - 1, j, 1), out.angle(f - 1, j, 2)}
                                 : reference.empty() ? vec3{}
                                                     : vec3{reference[j * 3], reference[j * 3 + 1], reference[j * 3 + 2]};
                const vec3 a = euler_from_matrix(matmul(transpose(gp), g[j]), T.joints[j].rotation_order(), ref);
                for (std::size_t c = 0; c < 3; ++c) out.angle(f, j, c) = a[c];
            } else {
                g[j] = gp;
            }
        }
        if (!hand) {
            // the hips' world position: the source's, scaled; moved through the nearest position channels
            std::size_t a = m.target_hips;
            while (!T.joints[a].has_position() && T.joints[a].parent >= 0) a = static_cast<std::size_t>(T.joints[a].parent);
            if (T.joints[a].has_position()) {
                const auto now = forward_kinematics(T, out.frame_angles(f), out.frame_positions(f));
                const vec3 want = scale(src.joints[m.source_hips], m.scale);
                const vec3 d = sub(want, now.joints[m.target_hips]);
                const int pa = T.joints[a].parent;
                const vec3 local = pa < 0 ? d : matvec(transpose(now.rotations[static_cast<std::size_t>(pa)]), d);
                for (std::size_t c = 0; c < 3; ++c) out.position(f, a, c) += local[c];
            }
        }
    }
    return out;
}

/// @brief Writes motion on m.target (`out`, e.g. a transfer of retarget_clip(in, m)) back onto the source
/// skeleton of `in`: `in` resampled to out.frames (resample()), then the driven joints' rotation channels
/// replaced so that their bone frames follow `out`'s (relative to the hand's frame of reference for a hand,
/// which itself is not moved). Every other channel, and every position channel, stays as resampled.
/// @throws shape_error when `in` is not on m.source or `out` not on m.target; value_error for non-finite input.
inline clip write_back(const clip& in, const clip& out, const retarget_map& m)
{
    if (!in.skel.same_topology(m.source))
        throw shape_error("retarget: clip '" + in.skel.name + "' is not on the map's source skeleton '" + m.source.name + "'");
    if (!out.skel.same_topology(m.target))
        throw shape_error("retarget: clip '" + out.skel.name + "' is not on the map's target skeleton '" + m.target.name + "'");
    in.validate("retarget: " + in.skel.name);
    out.validate("retarget: " + out.skel.name);
    clip r = resample(in, out.frames);
    const skeleton& S = r.skel;
    const std::size_t J = S.size();
    const bool hand = m.kind == target_kind::hand;
    std::vector<mat3> g(J);
    for (std::size_t f = 0; f < r.frames; ++f) {
        const auto tgt = forward_kinematics(out.skel, out.frame_angles(f), out.frame_positions(f));
        const mat3 ft = hand ? matmul(tgt.rotations[m.target_anchor], m.lt_anchor) : identity3;
        mat3 fs = identity3;
        for (std::size_t j = 0; j < J; ++j) {
            const int p = S.joints[j].parent;
            const mat3 gp = p < 0 ? identity3 : g[static_cast<std::size_t>(p)];
            if (const int k = m.pair_of_source[j]; k >= 0) {
                const auto& pr = m.pairs[static_cast<std::size_t>(k)];
                g[j] = detail::carry(fs, ft, tgt.rotations[pr.target], pr.lt, pr.ls, m.mirror);
                const vec3 ref{r.angle(f, j, 0), r.angle(f, j, 1), r.angle(f, j, 2)};
                const vec3 a = euler_from_matrix(matmul(transpose(gp), g[j]), S.joints[j].rotation_order(), ref);
                for (std::size_t c = 0; c < 3; ++c) r.angle(f, j, c) = a[c];
            } else {
                g[j] = matmul(gp, local_rotation(S.joints[j], r.frame_angles(f) + j * 3));
            }
            if (hand && j == m.source_anchor) fs = matmul(g[j], m.ls_anchor);
        }
    }
    return r;
}

}  // namespace handemo::retarget
