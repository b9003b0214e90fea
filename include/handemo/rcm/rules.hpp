// The heuristic rules of Aristidou et al. 2017, Table 2 (Section 4), and their counterparts for the
// 23-joint hand. A rule moves control points of every keyframe (pelvis, head, hands for a body; wrist and
// finger tips for the hand) as a function of coefficients; g4 scales the frame rate. Every rule is built on
// handemo's reverse-mode tape, so the features of the moved points (features_ad.hpp) and the objective of
// Eq. 6 (synth.hpp) are differentiable in all coefficients at once.
//
// Coefficients: handemo stores a = 0 for "no change" in every rule (the paper's c = 1.0):
//   body  a[0] g1 pelvis height, c1 = exp(a[0]);   a[1] g2 torso, c2 = exp(a[1]);
//         a[2..9] g3 hands, c = 1 + a for (L head, L chest, L pelvis, L ground, R head, R chest, R pelvis,
//         R ground);   a[10] g4 frame rate, c4 = exp(a[10]).
//   hand  a[0] h1 wrist excursion, c1 = exp(a[0]);   a[1] h2 hand opening, c2 = exp(a[1]);   a[2..5] h3
//         finger tips (fingers->palm, fingers->tip centroid, thumb->palm, thumb->tip centroid), c = 1 + a;
//         a[6] g4 frame rate, c4 = exp(a[6]).
// Body rules as Table 2, with three readings made explicit: (1) d_pelvis is taken as the pelvis's height
// above the ground (the paper's "vector from the pelvis to the ground" with its sign turned, so c1 < 1
// lowers the pelvis, as its text and Figure 6 describe) and the branch c1 > 1 above the T-pose height uses
// (c1 - 1), so every branch is the identity at c1 = 1; (2) the T-pose of a BVH skeleton is its standing
// pose, not its zero-angle pose (Bandai's zero pose lies along +X): pelvis height = leg chain length + the
// lowest foot height, torso = the spine chain length straight up; (3) the rules are applied in order and
// each moves what hangs below the joint it moves: g1 carries the upper body with the pelvis (feet stay),
// g2 carries chest, shoulders and hands with a share of the head's move (their height along the torso),
// g3 then moves each hand along its vectors to head, chest, pelvis and ground.
// Hand rules: h1 scales the wrist's excursion about its mean path (the whole hand moves with it, like g1
// moves the body with the pelvis); h2 moves each tip toward (c2 > 1) or beyond (c2 < 1) its open-hand
// (zero-angle, the hand's T-pose) position in the palm's frame, p += (u_T - u)(1 - 1/c2), as g2 does with
// the torso; h3 moves tips along their vectors to the palm and to the tips' centroid (curl, spread), as g3
// moves hands along their vectors to head/chest/pelvis/ground.
#pragma once

#include <handemo/core/error.hpp>
#include <handemo/motion/clip.hpp>
#include <handemo/motion/hand.hpp>
#include <handemo/motion/skeleton.hpp>
#include <handemo/rcm/detail/ops.hpp>
#include <handemo/rcm/ik.hpp>
#include <handemo/rcm/roles.hpp>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstddef>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace handemo::rcm {

enum class rig_kind { body, hand };

/// Control points of a body, in this order.
namespace body_point {
enum : int { pelvis, chest, head, l_shoulder, r_shoulder, l_hand, r_hand, l_foot, r_foot, count };
}
/// Control points of a hand, in this order (tips are the fingertip End Sites, bases the finger roles'
/// base joints of roles.hpp).
namespace hand_point {
enum : int { wrist, palm, thumb_tip, index_tip, middle_tip, ring_tip, pinky_tip, thumb_base, index_base, middle_base,
              ring_base, pinky_base, count };
}

inline constexpr std::size_t body_coefficient_count = 11;
inline constexpr std::size_t hand_coefficient_count = 7;

/// @brief Number of rule coefficients of a rig kind.
constexpr std::size_t coefficient_count(rig_kind k) noexcept
{
    return k == rig_kind::body ? body_coefficient_count : hand_coefficient_count;
}
/// @brief Which rule (0 = g1 .. 3 = g4) coefficient i belongs to.
constexpr int rule_of(rig_kind k, std::size_t i) noexcept
{
    const std::size_t n = coefficient_count(k);
    if (i == 0) return 0;
    if (i == 1) return 1;
    if (i + 1 == n) return 3;
    return 2;
}
/// @brief Names of the coefficients (for reports).
inline std::vector<std::string> coefficient_names(rig_kind k)
{
    if (k == rig_kind::body)
        return {"g1.pelvis", "g2.torso", "g3.L.head", "g3.L.chest", "g3.L.pelvis", "g3.L.ground",
                "g3.R.head", "g3.R.chest", "g3.R.pelvis", "g3.R.ground", "g4.rate"};
    return {"h1.wrist", "h2.open", "h3.fingers.palm", "h3.fingers.centroid", "h3.thumb.palm", "h3.thumb.centroid",
            "g4.rate"};
}
/// @brief Frame-rate factor c4 of coefficients `a` (the last one): c4 = exp(a.back()).
inline double time_scale(std::span<const double> a) noexcept { return a.empty() ? 1.0 : std::exp(a.back()); }

namespace detail {

/// Sum of bone lengths (rest offsets) from joint `from` up to its ancestor `to`.
inline double chain_length(const skeleton& s, int from, int to)
{
    double len = 0;
    for (int j = from; j >= 0 && j != to; j = s.joints[static_cast<std::size_t>(j)].parent) {
        const auto& o = s.joints[static_cast<std::size_t>(j)].offset;
        len += std::sqrt(o[0] * o[0] + o[1] * o[1] + o[2] * o[2]);
    }
    return len;
}

}  // namespace detail

/// @brief The skeleton point of a point index of point_names() (joints, then End Sites).
/// @throws shape_error when the index is outside the skeleton's points.
inline skeleton_point to_skeleton_point(const skeleton& s, std::size_t point)
{
    if (point < s.size()) return {static_cast<int>(point), false};
    std::size_t e = s.size();
    for (std::size_t j = 0; j < s.size(); ++j)
        if (s.joints[j].end_site && e++ == point) return {static_cast<int>(j), true};
    throw shape_error("rcm: point " + std::to_string(point) + " is outside the skeleton's " + std::to_string(e) + " points");
}

/// @brief The control points of a skeleton and the constants its rules need.
struct rig {
    rig_kind kind = rig_kind::body;
    std::vector<skeleton_point> points;  ///< body_point / hand_point order
    std::vector<std::size_t> point_index;  ///< the same points as indices of point_names() (lma.hpp's positions)
    std::vector<double> ik_weights;      ///< weight of each control point in the IK
    int translation_joint = -1;          ///< joint whose position channels the IK moves
    int up = 1;                          ///< up axis (0 x, 1 y, 2 z) of a body; the ground is its minimum
    // body
    double torso_length = 0;       ///< pelvis -> head along the spine (the T-pose torso)
    double leg_length = 0;         ///< pelvis -> foot along the leg, mean of both sides
    double chest_share = 0.5;      ///< share of the head's g2 move carried by the chest
    double shoulder_share = 0.75;  ///< ... by the shoulders and hands
    // hand: tip - palm at rest (zero angles), in the palm's frame
    std::array<vec3, 5> tip_rest{};

    std::size_t coefficients() const noexcept { return coefficient_count(kind); }
};

/// @brief The rig of a skeleton from its role map (roles.hpp): the hand rig when the map has the hand roles
/// (detect_feature_set), else the body rig; `up` is the up axis of a body (BVH: y).
/// @throws value_error naming a missing role, or when a body has no position channels at or above the pelvis.
inline rig make_rig(const skeleton& s, const role_map& roles, int up = 1)
{
    rig r;
    r.up = up;
    auto add = [&](role x, double w) {
        const std::size_t i = roles.at(x);
        r.point_index.push_back(i);
        r.points.push_back(to_skeleton_point(s, i));
        r.ik_weights.push_back(w);
    };
    if (detect_feature_set(roles) == feature_set::hand) {
        r.kind = rig_kind::hand;
        add(role::wrist, 4.0);
        add(role::palm, 1.0);
        for (role x : {role::thumb_tip, role::index_tip, role::middle_tip, role::ring_tip, role::pinky_tip}) add(x, 1.0);
        // finger bases: moved by h1 only, not IK goals (they span the hand frame of the hand volume)
        for (role x : {role::thumb_base, role::index_base, role::middle_base, role::ring_base, role::pinky_base}) add(x, 0.0);
        for (std::size_t j = 0; j < s.size() && r.translation_joint < 0; ++j)
            if (s.joints[j].has_position()) r.translation_joint = static_cast<int>(j);
        // The hand's T-pose is its zero-angle pose (the open, flat hand of hand_skeleton()).
        std::vector<double> zero(s.size() * 3, 0.0);
        const pose_positions fk = forward_kinematics(s, zero.data());
        const auto pj = static_cast<std::size_t>(r.points[hand_point::palm].joint);
        const vec3 palm = fk.joints[pj];
        const mat3& R = fk.rotations[pj];
        for (std::size_t f = 0; f < 5; ++f) {
            const auto& tp = r.points[hand_point::thumb_tip + f];
            const vec3 tip = tp.end_site ? fk.end_sites[static_cast<std::size_t>(tp.joint)] : fk.joints[static_cast<std::size_t>(tp.joint)];
            const vec3 d{tip[0] - palm[0], tip[1] - palm[1], tip[2] - palm[2]};
            r.tip_rest[f] = {R[0] * d[0] + R[3] * d[1] + R[6] * d[2], R[1] * d[0] + R[4] * d[1] + R[7] * d[2],
                             R[2] * d[0] + R[5] * d[1] + R[8] * d[2]};  // R^T d: in the palm's frame
        }
        return r;
    }
    r.kind = rig_kind::body;
    add(role::pelvis, 4.0);
    add(role::chest, 0.25);
    add(role::head, 1.0);
    add(role::left_shoulder, 0.0);
    add(role::right_shoulder, 0.0);
    add(role::left_hand, 1.0);
    add(role::right_hand, 1.0);
    add(role::left_foot, 4.0);
    add(role::right_foot, 4.0);
    using namespace body_point;
    const int pel = r.points[pelvis].joint;
    for (int j = pel; j >= 0 && r.translation_joint < 0; j = s.joints[static_cast<std::size_t>(j)].parent)
        if (s.joints[static_cast<std::size_t>(j)].has_position()) r.translation_joint = j;
    if (r.translation_joint < 0)
        throw value_error("rcm::make_rig: skeleton '" + s.name + "' has no position channels at or above the pelvis");
    r.torso_length = detail::chain_length(s, r.points[head].joint, pel);
    r.leg_length = 0.5 * (detail::chain_length(s, r.points[l_foot].joint, pel) + detail::chain_length(s, r.points[r_foot].joint, pel));
    const double chest_len = detail::chain_length(s, r.points[chest].joint, pel);
    const double shoulder_len =
        0.5 * (detail::chain_length(s, r.points[l_shoulder].joint, pel) + detail::chain_length(s, r.points[r_shoulder].joint, pel));
    if (r.torso_length > 0) {
        r.chest_share = std::clamp(chest_len / r.torso_length, 0.0, 1.0);
        r.shoulder_share = std::clamp(shoulder_len / r.torso_length, 0.0, 1.0);
    }
    return r;
}

/// @brief make_rig() with the roles found from the skeleton's joint names (find_roles).
inline rig make_rig(const skeleton& s, int up = 1) { return make_rig(s, find_roles(s), up); }

/// @brief Control points of the keyframes of one clip and the per-keyframe constants of the rules.
struct keyframe_points {
    std::size_t count = 0;                ///< K keyframes
    std::vector<std::size_t> frames;      ///< source frame of each keyframe
    std::vector<double> times;            ///< [K] seconds in the source
    std::vector<std::vector<double>> p;   ///< [points][K, 3] world positions
    double ground = 0;                    ///< body: lowest up-coordinate of any joint over the keyframes
    std::vector<double> height, height_tpose;  ///< body: pelvis height above ground and in the T-pose [K]
    std::vector<double> torso_delta;      ///< body: u_T - u, u = head - pelvis, u_T = torso length * up [K, 3]
    std::vector<double> wrist_excursion;  ///< hand: wrist - its mean over the keyframes [K, 3]
    std::vector<std::vector<double>> tip_delta;  ///< hand: u_T - u per tip, u = tip - palm [5][K, 3]
};

/// @brief Keyframes every `step` frames (and the last frame): 0, step, 2 step, ..., frames - 1.
inline std::vector<std::size_t> keyframe_indices(std::size_t frames, std::size_t step = 5)
{
    if (frames < 2) throw value_error("rcm::keyframe_indices: " + std::to_string(frames) + " frames, expected at least 2");
    if (step < 1) throw value_error("rcm::keyframe_indices: step 0");
    std::vector<std::size_t> k;
    for (std::size_t f = 0; f < frames; f += step) k.push_back(f);
    if (k.back() != frames - 1) k.push_back(frames - 1);
    return k;
}

/// @brief Samples the control points of `c` at `frames` and the constants of the rules.
inline keyframe_points sample_control_points(const rig& r, const clip& c, std::span<const std::size_t> frames)
{
    keyframe_points kp;
    const std::size_t K = frames.size(), P = r.points.size(), J = c.skel.size();
    kp.count = K;
    kp.frames.assign(frames.begin(), frames.end());
    kp.p.assign(P, std::vector<double>(K * 3));
    kp.times.resize(K);
    std::vector<mat3> palm_rot(K);
    double ground = 1e300;
    for (std::size_t k = 0; k < K; ++k) {
        if (frames[k] >= c.frames)
            throw shape_error("rcm::sample_control_points: frame " + std::to_string(frames[k]) + " of a clip of " +
                              std::to_string(c.frames));
        kp.times[k] = static_cast<double>(frames[k]) / c.fps;
        const pose_positions fk = forward_kinematics(c.skel, c.frame_angles(frames[k]), c.frame_positions(frames[k]));
        for (std::size_t q = 0; q < P; ++q) {
            const auto j = static_cast<std::size_t>(r.points[q].joint);
            const vec3& v = r.points[q].end_site ? fk.end_sites[j] : fk.joints[j];
            for (int a = 0; a < 3; ++a) kp.p[q][k * 3 + a] = v[a];
        }
        for (std::size_t j = 0; j < J; ++j) ground = std::min({ground, fk.joints[j][r.up], fk.end_sites[j][r.up]});
        if (r.kind == rig_kind::hand) palm_rot[k] = fk.rotations[static_cast<std::size_t>(r.points[hand_point::palm].joint)];
    }
    if (r.kind == rig_kind::body) {
        kp.ground = ground;
        kp.height.resize(K);
        kp.height_tpose.resize(K);
        kp.torso_delta.resize(K * 3);
        double lowest_foot = 1e300;
        for (std::size_t k = 0; k < K; ++k)
            for (int f : {body_point::l_foot, body_point::r_foot})
                lowest_foot = std::min(lowest_foot, kp.p[static_cast<std::size_t>(f)][k * 3 + static_cast<std::size_t>(r.up)] - ground);
        for (std::size_t k = 0; k < K; ++k) {
            const double* pel = &kp.p[body_point::pelvis][k * 3];
            const double* head = &kp.p[body_point::head][k * 3];
            kp.height[k] = pel[r.up] - ground;
            kp.height_tpose[k] = r.leg_length + lowest_foot;
            for (int a = 0; a < 3; ++a)
                kp.torso_delta[k * 3 + static_cast<std::size_t>(a)] = (a == r.up ? r.torso_length : 0.0) - (head[a] - pel[a]);
        }
    } else {
        kp.wrist_excursion.resize(K * 3);
        vec3 mean{};
        for (std::size_t k = 0; k < K; ++k)
            for (int a = 0; a < 3; ++a) mean[a] += kp.p[hand_point::wrist][k * 3 + a] / static_cast<double>(K);
        for (std::size_t k = 0; k < K; ++k)
            for (int a = 0; a < 3; ++a) kp.wrist_excursion[k * 3 + a] = kp.p[hand_point::wrist][k * 3 + a] - mean[a];
        kp.tip_delta.assign(5, std::vector<double>(K * 3));
        for (std::size_t f = 0; f < 5; ++f)
            for (std::size_t k = 0; k < K; ++k) {
                const vec3 uT = matvec(palm_rot[k], r.tip_rest[f]);
                for (int a = 0; a < 3; ++a)
                    kp.tip_delta[f][k * 3 + a] =
                        uT[a] - (kp.p[hand_point::thumb_tip + f][k * 3 + a] - kp.p[hand_point::palm][k * 3 + a]);
            }
    }
    return kp;
}

/// @brief Tape nodes of the moved control points ([K, 3] each, rig order) and of c4, c4^2, c4^3.
struct rule_nodes {
    std::vector<int> points;
    int c4 = -1, c4_2 = -1, c4_3 = -1;
};

/// @brief Records the four rules on `t`: `a` is a node of the rig's coefficients (a = 0: identity).
inline rule_nodes apply_rules(autodiff::tape<double>& t, const rig& r, const keyframe_points& kp, int a)
{
    namespace ad = autodiff::detail;
    if (t.at(a).size != r.coefficients())
        throw shape_error("rcm::apply_rules: " + std::to_string(t.at(a).size) + " coefficients, the " +
                          (r.kind == rig_kind::body ? "body" : "hand") + " rules take " + std::to_string(r.coefficients()));
    const std::size_t K = kp.count;
    auto coef = [&](int i) { const int idx[1] = {i}; return detail::gather(t, a, idx); };
    auto cst = [&](const std::vector<double>& v) { return detail::constant<double>(t, v); };
    rule_nodes out;
    std::vector<int> P(r.points.size());
    for (std::size_t q = 0; q < P.size(); ++q) P[q] = cst(kp.p[q]);
    const int n = static_cast<int>(r.coefficients());
    if (r.kind == rig_kind::body) {
        using namespace body_point;
        std::vector<double> upmask(K * 3, 0.0);
        for (std::size_t k = 0; k < K; ++k) upmask[k * 3 + static_cast<std::size_t>(r.up)] = 1.0;
        const int up = cst(upmask);
        // g1: the pelvis height changes by dh (Table 2, with c1 = exp(a0)); the upper body moves with it.
        const int c1 = detail::exp(t, coef(0));
        const int dh = detail::g1_height<double>(t, c1, kp.height, kp.height_tpose);
        const int D1 = ad::mul_raw(t, detail::repeat3(t, dh), up);
        for (int q : {pelvis, chest, head, l_shoulder, r_shoulder, l_hand, r_hand}) P[q] = ad::add_raw(t, P[q], D1);
        // g2: p_h += (d_T - d)(1 - 1/c2) with c2 = exp(a1); chest, shoulders, hands carry their share.
        const int k2 = ad::affine_raw(t, detail::exp(t, ad::affine_raw(t, coef(1), -1.0, 0.0)), -1.0, 1.0);
        const int Dh = detail::scale_by(t, cst(kp.torso_delta), k2);
        P[head] = ad::add_raw(t, P[head], Dh);
        P[chest] = ad::add_raw(t, P[chest], ad::affine_raw(t, Dh, r.chest_share, 0.0));
        const int Ds = ad::affine_raw(t, Dh, r.shoulder_share, 0.0);
        for (int q : {l_shoulder, r_shoulder, l_hand, r_hand}) P[q] = ad::add_raw(t, P[q], Ds);
        // g3: p_hand += [d_head (c - 1) + d_chest (c - 1) + d_pelvis (c - 1) + d_ground (c - 1)] / 4.
        const int upcol[1] = {r.up};
        for (int side = 0; side < 2; ++side) {
            const int h = side == 0 ? l_hand : r_hand;
            std::vector<int> upidx(K);
            for (std::size_t k = 0; k < K; ++k) upidx[k] = static_cast<int>(k * 3) + upcol[0];
            const int hu = detail::gather(t, P[h], upidx);
            const int dg = ad::mul_raw(t, detail::repeat3(t, ad::affine_raw(t, hu, -1.0, kp.ground)), up);
            const int refs[4] = {ad::sub_raw(t, P[head], P[h]), ad::sub_raw(t, P[chest], P[h]),
                                 ad::sub_raw(t, P[pelvis], P[h]), dg};
            int acc = -1;
            for (int j = 0; j < 4; ++j) {
                const int term = detail::scale_by(t, refs[j], coef(2 + side * 4 + j));
                acc = acc < 0 ? term : ad::add_raw(t, acc, term);
            }
            P[h] = ad::add_raw(t, P[h], ad::affine_raw(t, acc, 0.25, 0.0));
        }
    } else {
        using namespace hand_point;
        // h1: the wrist's excursion about its mean path scales by c1 = exp(a0); the whole hand moves with it.
        const int k1 = ad::affine_raw(t, detail::exp(t, coef(0)), 1.0, -1.0);
        const int D1 = detail::scale_by(t, cst(kp.wrist_excursion), k1);
        for (auto& q : P) q = ad::add_raw(t, q, D1);
        // h2: tip += (u_T - u)(1 - 1/c2), c2 = exp(a1): toward the open hand (c2 > 1) or more curled.
        const int k2 = ad::affine_raw(t, detail::exp(t, ad::affine_raw(t, coef(1), -1.0, 0.0)), -1.0, 1.0);
        for (std::size_t f = 0; f < 5; ++f)
            P[thumb_tip + f] = ad::add_raw(t, P[thumb_tip + f], detail::scale_by(t, cst(kp.tip_delta[f]), k2));
        // h3: tip += [d_palm (c - 1) + d_centroid (c - 1)] / 2, fingers and thumb with their own c.
        int centroid = P[thumb_tip];
        for (std::size_t f = 1; f < 5; ++f) centroid = ad::add_raw(t, centroid, P[thumb_tip + f]);
        centroid = ad::affine_raw(t, centroid, 0.2, 0.0);
        const int palm_c[2] = {coef(2), coef(4)}, cent_c[2] = {coef(3), coef(5)};
        std::vector<int> moved(5);
        for (std::size_t f = 0; f < 5; ++f) {
            const int g = f == 0 ? 1 : 0;
            const int tip = P[thumb_tip + f];
            const int term = ad::add_raw(t, detail::scale_by(t, ad::sub_raw(t, P[palm], tip), palm_c[g]),
                                         detail::scale_by(t, ad::sub_raw(t, centroid, tip), cent_c[g]));
            moved[f] = ad::add_raw(t, tip, ad::affine_raw(t, term, 0.5, 0.0));
        }
        for (std::size_t f = 0; f < 5; ++f) P[thumb_tip + f] = moved[f];
    }
    // g4: v *= c4 with c4 = exp(a_last); velocities scale by c4, accelerations by c4^2, jerk by c4^3.
    const int a4 = coef(n - 1);
    out.c4 = detail::exp(t, a4);
    out.c4_2 = detail::exp(t, ad::affine_raw(t, a4, 2.0, 0.0));
    out.c4_3 = detail::exp(t, ad::affine_raw(t, a4, 3.0, 0.0));
    out.points = std::move(P);
    return out;
}

/// @brief The moved control points and c4 in plain doubles.
struct rule_result {
    std::vector<std::vector<double>> points;  ///< [points][K, 3]
    double time_scale = 1.0;
};

/// @brief Applies the rules with coefficients `a` (no gradient).
inline rule_result apply_rules(const rig& r, const keyframe_points& kp, std::span<const double> a)
{
    autodiff::tape<double> t(std::size_t{1} << 16);
    const int an = t.leaf_copy(a.data(), a.size(), false);
    const rule_nodes rn = apply_rules(t, r, kp, an);
    rule_result res;
    res.time_scale = t.at(rn.c4).value[0];
    for (int id : rn.points) res.points.emplace_back(t.at(id).value, t.at(id).value + t.at(id).size);
    return res;
}

}  // namespace handemo::rcm
