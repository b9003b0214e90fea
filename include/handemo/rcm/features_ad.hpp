// Differentiable versions of the LMA features that the synthesis rules of Aristidou et al. 2017 target
// (Table 2's "affected features", defined in Table 1), computed per keyframe from the control points moved
// by the rules (rules.hpp) on handemo's reverse-mode tape, so that Eq. 6 can be optimised by gradient.
// Body: distances between control joints (BODY f1-f14), velocities, accelerations and jerk (EFFORT
// f16-f26, scaled by g4's frame-rate factor c4, c4^2, c4^3), the 5-joint bounding volume (SHAPE f27),
// torso height (f29) and hands level (SPACE f30). Hand (the hand variant of the feature set): tip-palm and
// adjacent tip-tip distances, the hand's bounding volume, wrist and tip velocities, tip accelerations,
// jerk. Time derivatives are finite differences over the keyframes' own times (non-uniform at the last
// keyframe): v_k = (p_{k+1} - p_{k-1}) / (t_{k+1} - t_{k-1}) (one-sided at the ends),
// a_k = 2 [(p_{k+1} - p_k)/h_k - (p_k - p_{k-1})/h_{k-1}] / (h_{k-1} + h_k) (the end rows copy their
// neighbours), jerk = the velocity stencil applied to a. feature_values() evaluates the same definitions on
// any positions in double precision (e.g. every frame of a clip, with dt = 1/fps).
#pragma once

#include <handemo/rcm/detail/ops.hpp>
#include <handemo/rcm/rules.hpp>

#include <cstddef>
#include <span>
#include <string>
#include <vector>

namespace handemo::rcm {

/// @brief Named per-keyframe feature nodes ([K] each) on a tape.
struct feature_nodes {
    std::vector<std::string> names;
    std::vector<int> ids;
    /// @brief The node of a feature.
    /// @throws value_error when no feature has that name.
    int at(std::string_view name) const
    {
        for (std::size_t i = 0; i < names.size(); ++i)
            if (names[i] == name) return ids[i];
        throw value_error("rcm: no differentiable feature named '" + std::string(name) + "'");
    }
};

namespace detail {

/// Velocity stencil over times `tm` (see the file comment).
inline std::vector<std::vector<stencil_entry>> velocity_stencil(std::span<const double> tm)
{
    const std::size_t K = tm.size();
    std::vector<std::vector<stencil_entry>> rows(K);
    if (K < 2) return rows;
    for (std::size_t k = 0; k < K; ++k) {
        const std::size_t a = k == 0 ? 0 : k - 1, b = k + 1 == K ? K - 1 : k + 1;
        const double w = 1.0 / (tm[b] - tm[a]);
        rows[k] = {{static_cast<int>(b), w}, {static_cast<int>(a), -w}};
    }
    return rows;
}
/// Acceleration stencil over times `tm` (see the file comment).
inline std::vector<std::vector<stencil_entry>> acceleration_stencil(std::span<const double> tm)
{
    const std::size_t K = tm.size();
    std::vector<std::vector<stencil_entry>> rows(K);
    if (K < 3) return rows;
    for (std::size_t k = 0; k < K; ++k) {
        const std::size_t c = std::clamp<std::size_t>(k, 1, K - 2);
        const double h0 = tm[c] - tm[c - 1], h1 = tm[c + 1] - tm[c], s = 2.0 / (h0 + h1);
        rows[k] = {{static_cast<int>(c + 1), s / h1}, {static_cast<int>(c), -s / h1 - s / h0}, {static_cast<int>(c - 1), s / h0}};
    }
    return rows;
}

}  // namespace detail

/// @brief Records the differentiable features of the moved points `rn` on `t`.
/// @param times [K] seconds of the keyframes in the source (before g4)
inline feature_nodes differentiable_features(autodiff::tape<double>& t, const rig& r, std::span<const double> times,
                                             double ground, const rule_nodes& rn)
{
    namespace ad = autodiff::detail;
    using detail::distance;
    const std::size_t K = times.size();
    feature_nodes f;
    auto add = [&](std::string name, int id) {
        f.names.push_back(std::move(name));
        f.ids.push_back(id);
    };
    const auto& P = rn.points;
    const auto V = detail::velocity_stencil(times), A = detail::acceleration_stencil(times);
    auto speed = [&](int p) { return detail::scale_by(t, detail::norm3(t, detail::stencil(t, p, 3, V)), rn.c4); };
    auto accel = [&](int p) { return detail::scale_by(t, detail::norm3(t, detail::stencil(t, p, 3, A)), rn.c4_2); };
    auto jerk_of = [&](int p) {
        return detail::norm3(t, detail::stencil(t, detail::stencil(t, p, 3, A), 3, V));
    };
    auto column = [&](int p, int axis) {
        std::vector<int> idx(K);
        for (std::size_t k = 0; k < K; ++k) idx[k] = static_cast<int>(k * 3) + axis;
        return detail::gather(t, p, idx);
    };
    if (r.kind == rig_kind::body) {
        using namespace body_point;
        const int lfh = distance(t, P[l_foot], P[pelvis]), rfh = distance(t, P[r_foot], P[pelvis]);
        add("l_foot_hip", lfh);
        add("r_foot_hip", rfh);
        add("l_hand_shoulder", distance(t, P[l_hand], P[l_shoulder]));
        add("r_hand_shoulder", distance(t, P[r_hand], P[r_shoulder]));
        add("hands_distance", distance(t, P[l_hand], P[r_hand]));
        add("l_hand_head", distance(t, P[l_hand], P[head]));
        add("r_hand_head", distance(t, P[r_hand], P[head]));
        add("l_hand_hip", distance(t, P[l_hand], P[pelvis]));
        add("r_hand_hip", distance(t, P[r_hand], P[pelvis]));
        const int hg = ad::affine_raw(t, column(P[pelvis], r.up), 1.0, -ground);
        add("hip_ground", hg);
        add("hip_ground_minus_feet_hip", ad::sub_raw(t, hg, ad::affine_raw(t, ad::add_raw(t, lfh, rfh), 0.5, 0.0)));
        add("feet_distance", distance(t, P[l_foot], P[r_foot]));
        add("l_hand_chest", distance(t, P[l_hand], P[chest]));
        add("r_hand_chest", distance(t, P[r_hand], P[chest]));
        const std::pair<const char*, int> movers[] = {
            {"pelvis", pelvis}, {"l_hand", l_hand}, {"r_hand", r_hand}, {"l_foot", l_foot}, {"r_foot", r_foot}};
        for (const auto& [n, q] : movers) add(std::string(n) + "_velocity", speed(P[q]));
        for (const auto& [n, q] : movers) add(std::string(n) + "_acceleration", accel(P[q]));
        int j = -1;
        for (const auto& [n, q] : movers) j = j < 0 ? jerk_of(P[q]) : ad::add_raw(t, j, jerk_of(P[q]));
        add("jerk", detail::scale_by(t, ad::affine_raw(t, j, 0.2, 0.0), rn.c4_3));
        // 5-joint volume: head, hands, feet as [K, 5, 3].
        std::vector<int> idx(K * 15);
        const int five[5] = {head, l_hand, r_hand, l_foot, r_foot};
        int cat = -1;
        for (int q : five) cat = cat < 0 ? P[q] : ad::concat_raw(t, cat, P[q], 1, static_cast<int>(t.at(cat).size), static_cast<int>(K * 3), 1);
        for (std::size_t k = 0; k < K; ++k)
            for (std::size_t q = 0; q < 5; ++q)
                for (std::size_t a = 0; a < 3; ++a) idx[(k * 5 + q) * 3 + a] = static_cast<int>(q * K * 3 + k * 3 + a);
        add("volume_5", detail::bbox_volume(t, detail::gather(t, cat, idx), 5));
        add("torso_height", distance(t, P[head], P[pelvis]));
        const int hands_up = ad::affine_raw(t, ad::add_raw(t, column(P[l_hand], r.up), column(P[r_hand], r.up)), 0.5, 0.0);
        add("hands_level", ad::sub_raw(t, hands_up, column(P[pelvis], r.up)));
    } else {
        using namespace hand_point;
        static constexpr const char* tips[5] = {"thumb", "index", "middle", "ring", "pinky"};
        for (int i = 0; i < 5; ++i) add(std::string(tips[i]) + "_palm", distance(t, P[thumb_tip + i], P[palm]));
        for (int i = 0; i < 4; ++i)
            add(std::string(tips[i]) + "_" + tips[i + 1], distance(t, P[thumb_tip + i], P[thumb_tip + i + 1]));
        const std::size_t Q = P.size();
        int cat = -1;
        for (int q : P) cat = cat < 0 ? q : ad::concat_raw(t, cat, q, 1, static_cast<int>(t.at(cat).size), static_cast<int>(K * 3), 1);
        std::vector<int> idx(K * Q * 3);
        for (std::size_t k = 0; k < K; ++k)
            for (std::size_t q = 0; q < Q; ++q)
                for (std::size_t a = 0; a < 3; ++a) idx[(k * Q + q) * 3 + a] = static_cast<int>(q * K * 3 + k * 3 + a);
        add("hand_volume", detail::bbox_volume(t, detail::gather(t, cat, idx), Q));
        add("wrist_velocity", speed(P[wrist]));
        for (int i = 0; i < 5; ++i) add(std::string(tips[i]) + "_velocity", speed(P[thumb_tip + i]));
        for (int i = 0; i < 5; ++i) add(std::string(tips[i]) + "_acceleration", accel(P[thumb_tip + i]));
        int j = -1;
        for (int i = 0; i < 5; ++i) j = j < 0 ? jerk_of(P[thumb_tip + i]) : ad::add_raw(t, j, jerk_of(P[thumb_tip + i]));
        add("jerk", detail::scale_by(t, ad::affine_raw(t, j, 0.2, 0.0), rn.c4_3));
    }
    return f;
}

/// @brief The features in double precision of control points `points` ([points][K, 3], rig order) at
/// `times`, with frame-rate factor `c4`: [feature][K], names in `names` (same order as
/// differentiable_features).
inline std::vector<std::vector<double>> feature_values(const rig& r, std::span<const double> times, double ground,
                                                       const std::vector<std::vector<double>>& points, double c4,
                                                       std::vector<std::string>* names = nullptr)
{
    autodiff::tape<double> t(std::size_t{1} << 16);
    rule_nodes rn;
    for (const auto& p : points) rn.points.push_back(t.leaf_copy(p.data(), p.size(), false));
    const double c[3] = {c4, c4 * c4, c4 * c4 * c4};
    rn.c4 = t.leaf_copy(&c[0], 1, false);
    rn.c4_2 = t.leaf_copy(&c[1], 1, false);
    rn.c4_3 = t.leaf_copy(&c[2], 1, false);
    const feature_nodes f = differentiable_features(t, r, times, ground, rn);
    if (names) *names = f.names;
    std::vector<std::vector<double>> out;
    for (int id : f.ids) out.emplace_back(t.at(id).value, t.at(id).value + t.at(id).size);
    return out;
}

}  // namespace handemo::rcm
