// Pose clustering of Aristidou et al. 2017, Section 3.5: every training pose is reduced to the height of
// the root (pelvis) and one unit quaternion per joint, with the root's planar position and facing direction
// (rotation about the up axis) discarded; two poses differ by Eq. 5 (after Lee et al. 2002),
//   d(p_u, p_v) = w_h |h_u - h_v| / s_h + sum_j w_j |log(q_uj^-1 q_vj)|^2,
// where |log q|^2 = (theta / 2)^2 for a rotation by theta. The paper writes the height term as a plain
// difference; we take its magnitude (a distance must not be negative) and divide it by s_h, the training
// poses' standard deviation of root height, so that it is unit-free (w_h = 1 by default). The weights
// favour the root and the arms, which carry emotion, over the legs, which mostly balance: root 2, shoulder
// girdle / shoulder / elbow / hand (and the joints below the hands) 2, hips / knees / feet (and below) 0.5,
// the rest 1. Poses are clustered by agglomerative (hierarchical) clustering with average linkage
// (nearest-neighbour chain, O(n^2) in time and memory) on an evenly spaced sample of at most 1500 poses,
// cut at 5 clusters; every pose then belongs to the cluster of its nearest cluster medoid, which is also
// how a new motion's poses are assigned.
#pragma once

#include <handemo/core/error.hpp>
#include <handemo/motion/clip.hpp>
#include <handemo/motion/skeleton.hpp>
#include <handemo/rcm/roles.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <limits>
#include <numbers>
#include <numeric>
#include <string>
#include <vector>

namespace handemo::rcm {

using quaternion = std::array<double, 4>;  ///< w, x, y, z

/// @brief A pose for Eq. 5: root height and one quaternion per joint (root without its facing).
struct pose {
    double height = 0;
    std::vector<quaternion> q;  ///< [J]
};

/// @brief Unit quaternion of a rotation matrix (row-major).
inline quaternion to_quaternion(const mat3& m) noexcept
{
    const double tr = m[0] + m[4] + m[8];
    quaternion q{};
    if (tr > 0) {
        const double s = std::sqrt(tr + 1.0) * 2;
        q = {0.25 * s, (m[7] - m[5]) / s, (m[2] - m[6]) / s, (m[3] - m[1]) / s};
    } else if (m[0] > m[4] && m[0] > m[8]) {
        const double s = std::sqrt(1.0 + m[0] - m[4] - m[8]) * 2;
        q = {(m[7] - m[5]) / s, 0.25 * s, (m[1] + m[3]) / s, (m[2] + m[6]) / s};
    } else if (m[4] > m[8]) {
        const double s = std::sqrt(1.0 + m[4] - m[0] - m[8]) * 2;
        q = {(m[2] - m[6]) / s, (m[1] + m[3]) / s, 0.25 * s, (m[5] + m[7]) / s};
    } else {
        const double s = std::sqrt(1.0 + m[8] - m[0] - m[4]) * 2;
        q = {(m[3] - m[1]) / s, (m[2] + m[6]) / s, (m[5] + m[7]) / s, 0.25 * s};
    }
    const double n = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    for (auto& v : q) v /= n;
    return q;
}

/// @brief |log(a^-1 b)|^2 = (theta / 2)^2 with theta the angle of the rotation between a and b.
inline double quaternion_log_distance2(const quaternion& a, const quaternion& b) noexcept
{
    const double d = std::min(1.0, std::abs(a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3]));
    const double half = std::acos(d);
    return half * half;
}

/// @brief The root joint of Eq. 5: the pelvis role when there is one, else joint 0.
inline std::size_t pose_root(const skeleton& s, const role_map& r)
{
    return r.has(role::pelvis) && r.at(role::pelvis) < s.size() ? r.at(role::pelvis) : 0;
}

/// @brief Eq. 5 joint weights (see the top of the file); joints above the root get 0.
inline std::vector<double> pose_weights(const skeleton& s, const role_map& r)
{
    const std::size_t J = s.size(), root = pose_root(s, r);
    std::vector<double> w(J, 1.0);
    auto is_below = [&](std::size_t j, std::size_t anc) {
        for (int k = static_cast<int>(j); k >= 0; k = s.joints[static_cast<std::size_t>(k)].parent)
            if (static_cast<std::size_t>(k) == anc) return true;
        return false;
    };
    for (std::size_t j = 0; j < J; ++j)
        if (j != root && !is_below(j, root)) w[j] = 0.0;  // above the root (Bandai's joint_Root)
    auto mark = [&](role ro, double v, bool parent_too) {
        if (!r.has(ro) || r.at(ro) >= J) return;
        const std::size_t a = r.at(ro);
        for (std::size_t j = 0; j < J; ++j)
            if (is_below(j, a)) w[j] = v;
        if (parent_too && s.joints[a].parent >= 0 && static_cast<std::size_t>(s.joints[a].parent) != root)
            w[static_cast<std::size_t>(s.joints[a].parent)] = v;
    };
    for (role ro : {role::left_shoulder, role::right_shoulder}) mark(ro, 2.0, true);
    for (role ro : {role::left_hip, role::right_hip}) mark(ro, 0.5, false);
    w[root] = 2.0;
    return w;
}

/// @brief The poses of a clip for Eq. 5 (root facing about the up axis removed).
inline std::vector<pose> clip_poses(const clip& c, const role_map& r, int up_axis = 1)
{
    const std::size_t J = c.skel.size(), root = pose_root(c.skel, r);
    const axis up = static_cast<axis>(up_axis);
    // a rotation about the up axis by phi turns axis a toward axis b (y up: z toward x)
    const std::size_t a_i = static_cast<std::size_t>((up_axis + 1) % 3), b_i = static_cast<std::size_t>((up_axis + 2) % 3);
    std::vector<pose> out(c.frames);
    for (std::size_t f = 0; f < c.frames; ++f) {
        const auto fk = forward_kinematics(c.skel, c.frame_angles(f), c.frame_positions(f));
        pose& p = out[f];
        p.height = fk.joints[root][static_cast<std::size_t>(up_axis)];
        p.q.resize(J);
        for (std::size_t j = 0; j < J; ++j) {
            if (j == root) {
                // facing: heading of the root's forward axis projected on the ground plane
                const mat3& g = fk.rotations[root];
                vec3 e{0, 0, 0};
                e[a_i] = 1;
                const vec3 d = matvec(g, e);
                const double heading = std::atan2(d[b_i], d[a_i]) * 180.0 / std::numbers::pi;
                p.q[j] = to_quaternion(matmul(axis_rotation(up, -heading), g));
            } else {
                p.q[j] = to_quaternion(local_rotation(c.skel.joints[j], c.frame_angles(f) + j * 3));
            }
        }
    }
    return out;
}

/// @brief Eq. 5 with the weights and the height scale of a clustering.
inline double pose_distance(const pose& u, const pose& v, const std::vector<double>& w, double height_weight, double height_scale)
{
    double d = height_weight * std::abs(u.height - v.height) / height_scale;
    const std::size_t J = std::min({u.q.size(), v.q.size(), w.size()});
    for (std::size_t j = 0; j < J; ++j)
        if (w[j] != 0) d += w[j] * quaternion_log_distance2(u.q[j], v.q[j]);
    return d;
}

/// @brief Options of cluster_poses().
struct pose_cluster_options {
    std::size_t clusters = 5;        ///< the paper's five
    std::size_t max_samples = 1500;  ///< poses clustered (evenly spaced sample); the rest go to the nearest medoid
    double height_weight = 1.0;      ///< w_h
};

/// @brief Average-linkage agglomerative clustering of `n` items with a symmetric `[n, n]` distance matrix
/// (row-major), cut at `k` clusters: cluster index per item, clusters numbered by first appearance.
/// @throws value_error when k is 0 or above n.
inline std::vector<std::size_t> average_linkage(std::vector<double> d, std::size_t n, std::size_t k)
{
    if (k == 0 || k > n) throw value_error("rcm::average_linkage: " + std::to_string(k) + " clusters for " + std::to_string(n) + " items");
    std::vector<bool> active(n, true);
    std::vector<double> size(n, 1.0);
    struct merge {
        std::size_t a, b;
        double h;
    };
    std::vector<merge> merges;
    std::vector<std::size_t> chain;
    std::size_t left = n;
    while (left > 1) {
        if (chain.empty())
            for (std::size_t i = 0; i < n; ++i)
                if (active[i]) {
                    chain.push_back(i);
                    break;
                }
        const std::size_t a = chain.back();
        std::size_t b = n;
        double best = std::numeric_limits<double>::infinity();
        if (chain.size() >= 2) b = chain[chain.size() - 2], best = d[a * n + b];
        for (std::size_t c = 0; c < n; ++c)
            if (active[c] && c != a && d[a * n + c] < best) best = d[a * n + c], b = c;
        if (chain.size() >= 2 && b == chain[chain.size() - 2]) {
            chain.pop_back();
            chain.pop_back();
            merges.push_back({a, b, best});
            // Lance-Williams update for average linkage; the merged cluster keeps index a
            for (std::size_t c = 0; c < n; ++c)
                if (active[c] && c != a && c != b) {
                    const double v = (size[a] * d[a * n + c] + size[b] * d[b * n + c]) / (size[a] + size[b]);
                    d[a * n + c] = d[c * n + a] = v;
                }
            size[a] += size[b];
            active[b] = false;
            --left;
        } else {
            chain.push_back(b);
        }
    }
    std::stable_sort(merges.begin(), merges.end(), [](const merge& x, const merge& y) { return x.h < y.h; });
    std::vector<std::size_t> parent(n);
    std::iota(parent.begin(), parent.end(), 0);
    auto find = [&](std::size_t x) {
        while (parent[x] != x) x = parent[x] = parent[parent[x]];
        return x;
    };
    for (std::size_t m = 0; m + k < n; ++m) parent[find(merges[m].a)] = find(merges[m].b);
    std::vector<std::size_t> label(n), id(n, n);
    std::size_t next = 0;
    for (std::size_t i = 0; i < n; ++i) {
        const std::size_t r = find(i);
        if (id[r] == n) id[r] = next++;
        label[i] = id[r];
    }
    return label;
}

/// @brief A fitted pose clustering: medoid poses and the Eq. 5 parameters.
struct pose_clustering {
    std::vector<pose> medoids;     ///< [C]
    std::vector<double> weights;   ///< [J] w_j
    double height_weight = 1.0, height_scale = 1.0;
    std::vector<std::size_t> sizes;  ///< [C] training poses per cluster (after assignment)

    std::size_t count() const noexcept { return medoids.size(); }
    /// @brief Cluster of a pose: the nearest medoid by Eq. 5.
    std::size_t assign(const pose& p) const
    {
        std::size_t best = 0;
        double bd = std::numeric_limits<double>::infinity();
        for (std::size_t c = 0; c < medoids.size(); ++c) {
            const double d = pose_distance(p, medoids[c], weights, height_weight, height_scale);
            if (d < bd) bd = d, best = c;
        }
        return best;
    }
};

/// @brief Clusters poses (Section 3.5; see the top of the file).
/// @throws value_error with fewer poses than clusters.
inline pose_clustering cluster_poses(const std::vector<pose>& poses, const std::vector<double>& weights,
                                     const pose_cluster_options& opt = {})
{
    const std::size_t N = poses.size();
    if (N < opt.clusters) throw value_error("rcm::cluster_poses: " + std::to_string(N) + " poses for " + std::to_string(opt.clusters) + " clusters");
    pose_clustering pc;
    pc.weights = weights;
    pc.height_weight = opt.height_weight;
    double mh = 0, sh = 0;
    for (const auto& p : poses) mh += p.height / static_cast<double>(N);
    for (const auto& p : poses) sh += (p.height - mh) * (p.height - mh) / static_cast<double>(N);
    pc.height_scale = std::sqrt(sh) > 1e-9 ? std::sqrt(sh) : 1.0;
    const std::size_t n = std::min(N, std::max(opt.max_samples, opt.clusters));
    std::vector<std::size_t> sample(n);
    for (std::size_t i = 0; i < n; ++i) sample[i] = i * N / n;
    std::vector<double> d(n * n, 0.0);
    for (std::size_t i = 0; i < n; ++i)
        for (std::size_t j = i + 1; j < n; ++j)
            d[i * n + j] = d[j * n + i] = pose_distance(poses[sample[i]], poses[sample[j]], weights, pc.height_weight, pc.height_scale);
    const auto label = average_linkage(d, n, opt.clusters);
    for (std::size_t c = 0; c < opt.clusters; ++c) {
        std::size_t best = n;
        double bs = std::numeric_limits<double>::infinity();
        for (std::size_t i = 0; i < n; ++i) {
            if (label[i] != c) continue;
            double s = 0;
            for (std::size_t j = 0; j < n; ++j)
                if (label[j] == c) s += d[i * n + j];
            if (s < bs) bs = s, best = i;
        }
        pc.medoids.push_back(poses[sample[best]]);
    }
    pc.sizes.assign(opt.clusters, 0);
    for (const auto& p : poses) ++pc.sizes[pc.assign(p)];
    return pc;
}

}  // namespace handemo::rcm
