// Differentiable versions of the LMA features that the synthesis rules of Aristidou et al. 2017 target
// (Table 2's "affected features", defined in Table 1), computed per keyframe from the control points moved
// by the rules (rules.hpp) on handemo's reverse-mode tape, so that Eq. 6 can be optimised by gradient.
// They are lma.hpp's definitions (the analysis side) restricted to what the control points determine, and
// carry its keys: body f1-f14 (distances), f16-f25 (speed and acceleration of pelvis, hands, feet), f26
// (jerk), f27 (head/hands/feet box in the body frame), f29 (torso height), plus `hands_height`, a smooth
// surrogate of the step function f30; hand h1-h12 (tip distances, span, spread, hand-frame volume),
// h13-h25 (tip and wrist speed, acceleration, jerk). Not here: f15/h27 (counts of peaks, no gradient),
// f28, f31-f34 (boxes of elbows, knees, hips: not control points), f35-f37, h26, h28 (window-level path
// and space measures). Time derivatives are lma.hpp's clamped central differences applied over the
// keyframes' own times, v_k = (p_{k+1} - p_{k-1}) / (t_{k+1} - t_{k-1}) (one-sided at the ends), the
// acceleration is that stencil applied twice and the jerk three times; g4's frame-rate factor c4 scales
// them by c4, c4^2, c4^3. feature_values() evaluates the same definitions on any positions in double
// precision (every frame of a clip with t = f / fps gives lma.hpp's basic_table columns; tested).
#pragma once

#include <handemo/rcm/detail/ops.hpp>
#include <handemo/rcm/rules.hpp>

#include <cstddef>
#include <span>
#include <string>
#include <vector>

namespace handemo::rcm {

/// @brief Named per-keyframe feature nodes ([K] each) on a tape, with the key of lma.hpp's basic feature
/// each one computes ("f5", "h12"; empty for a surrogate that lma.hpp does not have).
struct feature_nodes {
    std::vector<std::string> names, keys;
    std::vector<int> ids;
    /// @brief The node of a feature by name or key.
    /// @throws value_error when no feature has that name or key.
    int at(std::string_view name) const
    {
        for (std::size_t i = 0; i < names.size(); ++i)
            if (names[i] == name || (!keys[i].empty() && keys[i] == name)) return ids[i];
        throw value_error("rcm: no differentiable feature named '" + std::string(name) + "'");
    }
};

namespace detail {

/// Velocity stencil over times `tm` (see the file comment): lma.hpp's central difference with clamped ends.
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

/// Rows of three orthonormal axes (row-major 3x3) from a lateral vector and an up vector: (lateral made
/// horizontal/orthogonal, up, lateral x up), as lma.hpp's body_axes and hand frame.
inline std::array<double, 9> frame_rows(vec3 lat, vec3 up, bool make_horizontal, int up_axis, vec3 lat_fallback)
{
    auto unit = [](vec3 a, vec3 fb) {
        const double n = std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
        return n > 1e-12 ? vec3{a[0] / n, a[1] / n, a[2] / n} : fb;
    };
    auto cross = [](vec3 a, vec3 b) {
        return vec3{a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
    };
    if (make_horizontal) {
        lat[static_cast<std::size_t>(up_axis)] = 0;
    } else {
        const double d = lat[0] * up[0] + lat[1] * up[1] + lat[2] * up[2];
        lat = {lat[0] - d * up[0], lat[1] - d * up[1], lat[2] - d * up[2]};
    }
    lat = unit(lat, lat_fallback);
    const vec3 fwd = unit(make_horizontal ? cross(up, lat) : cross(lat, up), vec3{0, 0, 1});
    return {lat[0], lat[1], lat[2], up[0], up[1], up[2], fwd[0], fwd[1], fwd[2]};
}

}  // namespace detail

/// @brief Records the differentiable features of the moved points `rn` on `t`.
/// @param times [K] seconds of the keyframes in the source (before g4)
/// @param ground the ground height (lowest up-coordinate of the clip) of f10
inline feature_nodes differentiable_features(autodiff::tape<double>& t, const rig& r, std::span<const double> times,
                                             double ground, const rule_nodes& rn)
{
    namespace ad = autodiff::detail;
    using detail::distance;
    const std::size_t K = times.size();
    feature_nodes f;
    auto add = [&](std::string key, std::string name, int id) {
        f.keys.push_back(std::move(key));
        f.names.push_back(std::move(name));
        f.ids.push_back(id);
    };
    const auto& P = rn.points;
    const auto V = detail::velocity_stencil(times);
    auto vel = [&](int p) { return detail::stencil(t, p, 3, V); };
    auto speed = [&](int p) { return detail::scale_by(t, detail::norm3(t, vel(p)), rn.c4); };
    auto accel = [&](int p) { return detail::scale_by(t, detail::norm3(t, vel(vel(p))), rn.c4_2); };
    auto jerk = [&](std::span<const int> pts) {  // mean third-derivative magnitude, times c4^3
        int j = -1;
        for (int p : pts) {
            const int m = detail::norm3(t, vel(vel(vel(p))));
            j = j < 0 ? m : ad::add_raw(t, j, m);
        }
        return detail::scale_by(t, ad::affine_raw(t, j, 1.0 / static_cast<double>(pts.size()), 0.0), rn.c4_3);
    };
    auto column = [&](int p, int axis) {
        std::vector<int> idx(K);
        for (std::size_t k = 0; k < K; ++k) idx[k] = static_cast<int>(k * 3) + axis;
        return detail::gather(t, p, idx);
    };
    // Volume of the box around `pts` in per-keyframe frames `rows` ([K, 3, 3]): rotate, stack [K, Q, 3], box.
    auto frame_volume = [&](std::span<const int> pts, const std::vector<double>& rows) {
        const std::size_t Q = pts.size();
        int cat = -1;
        for (int q : pts) {
            const int rq = detail::rotate_rows<double>(t, q, rows);
            cat = cat < 0 ? rq : ad::concat_raw(t, cat, rq, 1, static_cast<int>(t.at(cat).size), static_cast<int>(K * 3), 1);
        }
        std::vector<int> idx(K * Q * 3);
        for (std::size_t k = 0; k < K; ++k)
            for (std::size_t q = 0; q < Q; ++q)
                for (std::size_t a = 0; a < 3; ++a) idx[(k * Q + q) * 3 + a] = static_cast<int>(q * K * 3 + k * 3 + a);
        return detail::bbox_volume(t, detail::gather(t, cat, idx), Q);
    };
    auto value3 = [&](int p, std::size_t k) {
        const double* v = t.at(p).value + k * 3;
        return vec3{v[0], v[1], v[2]};
    };
    if (r.kind == rig_kind::body) {
        using namespace body_point;
        const int lfh = distance(t, P[l_foot], P[pelvis]), rfh = distance(t, P[r_foot], P[pelvis]);
        add("f1", "l_foot_hip", lfh);
        add("f2", "r_foot_hip", rfh);
        add("f3", "l_hand_shoulder", distance(t, P[l_hand], P[l_shoulder]));
        add("f4", "r_hand_shoulder", distance(t, P[r_hand], P[r_shoulder]));
        add("f5", "hands_distance", distance(t, P[l_hand], P[r_hand]));
        add("f6", "l_hand_head", distance(t, P[l_hand], P[head]));
        add("f7", "r_hand_head", distance(t, P[r_hand], P[head]));
        add("f8", "l_hand_hip", distance(t, P[l_hand], P[pelvis]));
        add("f9", "r_hand_hip", distance(t, P[r_hand], P[pelvis]));
        const int hg = ad::affine_raw(t, column(P[pelvis], r.up), 1.0, -ground);
        add("f10", "hip_ground", hg);
        add("f11", "hip_ground_minus_feet_hip", ad::sub_raw(t, hg, ad::affine_raw(t, ad::add_raw(t, lfh, rfh), 0.5, 0.0)));
        add("f12", "feet_distance", distance(t, P[l_foot], P[r_foot]));
        add("f13", "l_hand_chest", distance(t, P[l_hand], P[chest]));
        add("f14", "r_hand_chest", distance(t, P[r_hand], P[chest]));
        const std::pair<const char*, int> movers[] = {
            {"pelvis", pelvis}, {"l_hand", l_hand}, {"r_hand", r_hand}, {"l_foot", l_foot}, {"r_foot", r_foot}};
        int key = 16;
        for (const auto& [n, q] : movers) add("f" + std::to_string(key++), std::string(n) + "_velocity", speed(P[q]));
        for (const auto& [n, q] : movers) add("f" + std::to_string(key++), std::string(n) + "_acceleration", accel(P[q]));
        const int five_movers[5] = {P[pelvis], P[l_hand], P[r_hand], P[l_foot], P[r_foot]};
        add("f26", "jerk", jerk(five_movers));
        // f27 in the body frame (horizontal shoulder line, up, their cross product). The rules move both
        // shoulders by the same vector, so the frame does not depend on the coefficients: a constant here.
        std::vector<double> rows(K * 9);
        vec3 upv{0, 0, 0};
        upv[static_cast<std::size_t>(r.up)] = 1;
        vec3 fb{0, 0, 0};
        fb[static_cast<std::size_t>((r.up + 1) % 3)] = 1;
        for (std::size_t k = 0; k < K; ++k) {
            const vec3 ls = value3(P[l_shoulder], k), rs = value3(P[r_shoulder], k);
            const auto m = detail::frame_rows({rs[0] - ls[0], rs[1] - ls[1], rs[2] - ls[2]}, upv, true, r.up, fb);
            std::copy(m.begin(), m.end(), rows.begin() + static_cast<std::ptrdiff_t>(k * 9));
        }
        const int five[5] = {P[head], P[l_hand], P[r_hand], P[l_foot], P[r_foot]};
        add("f27", "volume_5", frame_volume(five, rows));
        add("f29", "torso_height", distance(t, P[head], P[pelvis]));
        // A smooth surrogate of f30 (hands level, a step function of hand heights): mean hand height above
        // the pelvis.
        const int hands_up = ad::affine_raw(t, ad::add_raw(t, column(P[l_hand], r.up), column(P[r_hand], r.up)), 0.5, 0.0);
        add("", "hands_height", ad::sub_raw(t, hands_up, column(P[pelvis], r.up)));
    } else {
        using namespace hand_point;
        static constexpr const char* tips[5] = {"thumb", "index", "middle", "ring", "pinky"};
        for (int i = 0; i < 5; ++i) add("h" + std::to_string(1 + i), std::string(tips[i]) + "_palm", distance(t, P[thumb_tip + i], P[palm]));
        for (int i = 0; i < 4; ++i)
            add("h" + std::to_string(6 + i), std::string(tips[i]) + "_" + tips[i + 1], distance(t, P[thumb_tip + i], P[thumb_tip + i + 1]));
        add("h10", "thumb_pinky", distance(t, P[thumb_tip], P[pinky_tip]));
        int spread = -1;
        for (int i = 1; i < 4; ++i) {
            const int a = ad::sub_raw(t, P[thumb_tip + i], P[thumb_base + i]);
            const int b = ad::sub_raw(t, P[thumb_tip + i + 1], P[thumb_base + i + 1]);
            const int ang = detail::row_angle(t, a, b);
            spread = spread < 0 ? ang : ad::add_raw(t, spread, ang);
        }
        add("h11", "finger_spread", ad::affine_raw(t, spread, 1.0 / 3.0, 0.0));
        // h12 in the hand frame (wrist -> palm, pinky base -> index base, their normal). h1 translates the
        // whole hand and h2/h3 move only tips, so the frame does not depend on the coefficients.
        std::vector<double> rows(K * 9);
        for (std::size_t k = 0; k < K; ++k) {
            const vec3 w = value3(P[wrist], k), pm = value3(P[palm], k), bi = value3(P[index_base], k), bp = value3(P[pinky_base], k);
            vec3 y{pm[0] - w[0], pm[1] - w[1], pm[2] - w[2]};
            const double n = std::sqrt(y[0] * y[0] + y[1] * y[1] + y[2] * y[2]);
            y = n > 1e-12 ? vec3{y[0] / n, y[1] / n, y[2] / n} : vec3{0, 1, 0};
            const auto m = detail::frame_rows({bi[0] - bp[0], bi[1] - bp[1], bi[2] - bp[2]}, y, false, 1, vec3{1, 0, 0});
            std::copy(m.begin(), m.end(), rows.begin() + static_cast<std::ptrdiff_t>(k * 9));
        }
        const int hand_pts[12] = {P[wrist],         P[palm],          P[thumb_base],   P[thumb_tip],
                                  P[index_base],    P[index_tip],     P[middle_base],  P[middle_tip],
                                  P[ring_base],     P[ring_tip],      P[pinky_base],   P[pinky_tip]};
        add("h12", "hand_volume", frame_volume(hand_pts, rows));
        for (int i = 0; i < 5; ++i) add("h" + std::to_string(13 + i), std::string(tips[i]) + "_velocity", speed(P[thumb_tip + i]));
        for (int i = 0; i < 5; ++i) add("h" + std::to_string(18 + i), std::string(tips[i]) + "_acceleration", accel(P[thumb_tip + i]));
        const int tip_ids[5] = {P[thumb_tip], P[index_tip], P[middle_tip], P[ring_tip], P[pinky_tip]};
        add("h23", "jerk", jerk(tip_ids));
        add("h24", "wrist_velocity", speed(P[wrist]));
        add("h25", "wrist_acceleration", accel(P[wrist]));
    }
    return f;
}

/// @brief The features in double precision of control points `points` ([points][K, 3], rig order) at
/// `times`, with frame-rate factor `c4`: [feature][K], names in `names` (same order as
/// differentiable_features).
inline std::vector<std::vector<double>> feature_values(const rig& r, std::span<const double> times, double ground,
                                                       const std::vector<std::vector<double>>& points, double c4,
                                                       std::vector<std::string>* names = nullptr, std::vector<std::string>* keys = nullptr)
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
    if (keys) *keys = f.keys;
    std::vector<std::vector<double>> out;
    for (int id : f.ids) out.emplace_back(t.at(id).value, t.at(id).value + t.at(id).size);
    return out;
}

}  // namespace handemo::rcm
