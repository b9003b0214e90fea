// Runtime-sized autodiff ops for the synthesis of Aristidou et al. 2017 (Section 4): the rules of Table 2,
// the LMA features they target and the objective of Eq. 6 are built from these and from autodiff/'s
// untyped ops (add_raw, sub_raw, mul_raw, affine_raw, row_sum_raw, row_broadcast_raw, row_norm_raw,
// unary_raw). A motion's length is known only at run time, so these work on node ids and sizes rather than
// on typed `var<T, shape<...>>` handles. Each op records one tape node with a first-order backward whose
// derivative is written above it; tests/rcm_synth/ops_test.cpp checks every one against central finite
// differences in double precision.
#pragma once

#include <handemo/autodiff.hpp>
#include <handemo/core/error.hpp>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <span>
#include <string>
#include <utility>
#include <vector>

namespace handemo::rcm::detail {

using autodiff::tape;

// ---------------------------------------------------------------- gather
// y[i] = x[idx[i]] (idx in aux, stored as T).  d/dx[j] = sum_{i: idx[i] = j} g[i]  (scatter-add).
template <class T>
void gather_backward(tape<T>& t, int self)
{
    const auto& n = t.at(self);
    T* gx = t.adj(n.in[0]);
    if (!gx) return;
    for (std::size_t i = 0; i < n.size; ++i) gx[static_cast<std::size_t>(n.aux[i])] += n.adjoint[i];
}
/// @brief y[i] = x[idx[i]].
/// @throws shape_error if an index is outside x.
template <class T>
int gather(tape<T>& t, int x, std::span<const int> idx)
{
    const std::size_t m = t.at(x).size;
    for (int i : idx)
        if (i < 0 || static_cast<std::size_t>(i) >= m)
            throw shape_error("rcm::gather: index " + std::to_string(i) + " is outside [0, " + std::to_string(m) + ")");
    T* aux = t.alloc(idx.size());
    const int id = t.make("gather", idx.size(), {x}, &gather_backward<T>, nullptr);
    auto& n = t.at(id);
    n.aux = aux;
    const T* xv = t.at(x).value;
    for (std::size_t i = 0; i < idx.size(); ++i) {
        n.aux[i] = static_cast<T>(idx[i]);
        n.value[i] = xv[idx[i]];
    }
    return id;
}

// ---------------------------------------------------------------- sparse row combination (stencil)
// x is [R_in, C], y is [R_out, C] with y[r, c] = sum_{(s, w) in row r} w x[s, c]: finite differences in time,
// sliding-window means, any fixed linear map between rows. aux holds the CSR matrix: R_out + 1 offsets,
// then (source, weight) pairs.  d/dx[s, c] = sum_{r, (s, w) in row r} w g[r, c]  (the transpose).
struct stencil_entry {
    int source;
    double weight;
};
struct stencil_params {
    std::size_t rows;  ///< R_out
    std::size_t cols;  ///< C
};
template <class T>
void stencil_backward(tape<T>& t, int self)
{
    const auto& n = t.at(self);
    T* gx = t.adj(n.in[0]);
    if (!gx) return;
    const auto [R, C] = n.template params<stencil_params>();
    const T* off = n.aux;
    const T* pairs = n.aux + R + 1;
    for (std::size_t r = 0; r < R; ++r)
        for (auto e = static_cast<std::size_t>(off[r]); e < static_cast<std::size_t>(off[r + 1]); ++e) {
            const auto s = static_cast<std::size_t>(pairs[2 * e]);
            const T w = pairs[2 * e + 1];
            for (std::size_t c = 0; c < C; ++c) gx[s * C + c] += w * n.adjoint[r * C + c];
        }
}
/// @brief y[r, :] = sum_{(s, w) in rows[r]} w x[s, :], x of `cols` columns.
/// @throws shape_error if a source row is outside x.
template <class T>
int stencil(tape<T>& t, int x, std::size_t cols, const std::vector<std::vector<stencil_entry>>& rows)
{
    const std::size_t R_in = t.at(x).size / cols, R = rows.size();
    std::size_t nnz = 0;
    for (const auto& r : rows) {
        nnz += r.size();
        for (const auto& e : r)
            if (e.source < 0 || static_cast<std::size_t>(e.source) >= R_in)
                throw shape_error("rcm::stencil: source row " + std::to_string(e.source) + " is outside [0, " +
                                  std::to_string(R_in) + ")");
    }
    T* aux = t.alloc(R + 1 + 2 * nnz);
    const int id = t.make("stencil", R * cols, {x}, &stencil_backward<T>, nullptr, stencil_params{R, cols});
    auto& n = t.at(id);
    n.aux = aux;
    const T* xv = t.at(x).value;
    std::size_t e = 0;
    for (std::size_t r = 0; r < R; ++r) {
        aux[r] = static_cast<T>(e);
        for (std::size_t c = 0; c < cols; ++c) n.value[r * cols + c] = T(0);
        for (const auto& en : rows[r]) {
            aux[R + 1 + 2 * e] = static_cast<T>(en.source);
            aux[R + 1 + 2 * e + 1] = static_cast<T>(en.weight);
            for (std::size_t c = 0; c < cols; ++c)
                n.value[r * cols + c] += static_cast<T>(en.weight) * xv[static_cast<std::size_t>(en.source) * cols + c];
            ++e;
        }
    }
    aux[R] = static_cast<T>(e);
    return id;
}

// ---------------------------------------------------------------- exp
// y = exp(x).  d/dx = g y.
template <class T>
void exp_backward(tape<T>& t, int self)
{
    const auto& n = t.at(self);
    if (T* gx = t.adj(n.in[0]))
        for (std::size_t i = 0; i < n.size; ++i) gx[i] += n.adjoint[i] * n.value[i];
}
template <class T>
int exp(tape<T>& t, int x)
{
    const int id = t.make("exp", t.at(x).size, {x}, &exp_backward<T>, nullptr);
    const T* xv = t.at(x).value;
    T* y = t.at(id).value;
    for (std::size_t i = 0; i < t.at(id).size; ++i) y[i] = std::exp(xv[i]);
    return id;
}

// ---------------------------------------------------------------- axis-aligned bounding-box volume
// x is [R, Q, 3] (Q points per row), y[r] = prod_a (max_q x[r, q, a] - min_q x[r, q, a]).
// d/dx[r, q*, a] = +g[r] prod_{b != a} e_b at the arg max q*, and -g[r] prod_{b != a} e_b at the arg min
// (the extent e_a has these two sub-gradients; ties go to the first point, as in the forward pass).
// aux holds, per row, e[3], arg max[3], arg min[3].
struct bbox_volume_params {
    std::size_t rows;    ///< R
    std::size_t points;  ///< Q
};
template <class T>
void bbox_volume_backward(tape<T>& t, int self)
{
    const auto& n = t.at(self);
    T* gx = t.adj(n.in[0]);
    if (!gx) return;
    const auto [R, Q] = n.template params<bbox_volume_params>();
    for (std::size_t r = 0; r < R; ++r) {
        const T* a = n.aux + r * 9;  // e[3], arg max[3], arg min[3]
        for (std::size_t ax = 0; ax < 3; ++ax) {
            T other = T(1);
            for (std::size_t b = 0; b < 3; ++b)
                if (b != ax) other *= a[b];
            const T v = n.adjoint[r] * other;
            gx[(r * Q + static_cast<std::size_t>(a[3 + ax])) * 3 + ax] += v;
            gx[(r * Q + static_cast<std::size_t>(a[6 + ax])) * 3 + ax] -= v;
        }
    }
}
/// @brief Volume of the axis-aligned bounding box of each row's Q points: [R, Q, 3] -> [R].
template <class T>
int bbox_volume(tape<T>& t, int x, std::size_t points)
{
    const std::size_t R = t.at(x).size / (points * 3);
    T* aux = t.alloc(R * 9);
    const int id = t.make("bbox_volume", R, {x}, &bbox_volume_backward<T>, nullptr, bbox_volume_params{R, points});
    auto& n = t.at(id);
    n.aux = aux;
    const T* xv = t.at(x).value;
    for (std::size_t r = 0; r < R; ++r) {
        T vol = T(1);
        for (std::size_t ax = 0; ax < 3; ++ax) {
            std::size_t imax = 0, imin = 0;
            for (std::size_t q = 1; q < points; ++q) {
                const T v = xv[(r * points + q) * 3 + ax];
                if (v > xv[(r * points + imax) * 3 + ax]) imax = q;
                if (v < xv[(r * points + imin) * 3 + ax]) imin = q;
            }
            const T e = xv[(r * points + imax) * 3 + ax] - xv[(r * points + imin) * 3 + ax];
            aux[r * 9 + ax] = e;
            aux[r * 9 + 3 + ax] = static_cast<T>(imax);
            aux[r * 9 + 6 + ax] = static_cast<T>(imin);
            vol *= e;
        }
        n.value[r] = vol;
    }
    return id;
}

// ---------------------------------------------------------------- rule g1's pelvis height (Table 2)
// Pelvis height h above the ground, its T-pose height h_T (both per row, constants in aux), c = c_1 a scalar
// node. The height change dh = h' - h is
//   c <= 1:             dh = h (c - 1)                         d dh/dc = h
//   c > 1, h <= h_T:    dh = (h_T - h)(1 - 1/c)                d dh/dc = (h_T - h) / c^2
//   c > 1, h >  h_T:    dh = (h - h_T)(c - 1)                  d dh/dc = h - h_T
// (c < 1 crouches toward the ground, c > 1 stands up toward the T-pose height or, in the air, jumps higher;
// every branch is the identity at c = 1.)
template <class T>
T g1_height_change(T h, T hT, T c, T* dc) noexcept
{
    if (c <= T(1)) {
        if (dc) *dc = h;
        return h * (c - T(1));
    }
    if (h <= hT) {
        if (dc) *dc = (hT - h) / (c * c);
        return (hT - h) * (T(1) - T(1) / c);
    }
    if (dc) *dc = h - hT;
    return (h - hT) * (c - T(1));
}
template <class T>
void g1_backward(tape<T>& t, int self)
{
    const auto& n = t.at(self);
    T* gc = t.adj(n.in[0]);
    if (!gc) return;
    const T c = t.at(n.in[0]).value[0];
    T acc = 0;
    for (std::size_t r = 0; r < n.size; ++r) {
        T d = 0;
        g1_height_change(n.aux[2 * r], n.aux[2 * r + 1], c, &d);
        acc += n.adjoint[r] * d;
    }
    gc[0] += acc;
}
/// @brief Height change of rule g1 for every row: c is a scalar node, h and h_T constants.
template <class T>
int g1_height(tape<T>& t, int c, std::span<const T> h, std::span<const T> h_tpose)
{
    const std::size_t R = h.size();
    T* aux = t.alloc(2 * R);
    const int id = t.make("g1_height", R, {c}, &g1_backward<T>, nullptr);
    auto& n = t.at(id);
    n.aux = aux;
    const T cv = t.at(c).value[0];
    for (std::size_t r = 0; r < R; ++r) {
        aux[2 * r] = h[r];
        aux[2 * r + 1] = h_tpose[r];
        n.value[r] = g1_height_change(h[r], h_tpose[r], cv, static_cast<T*>(nullptr));
    }
    return id;
}

// ---------------------------------------------------------------- per-row constant rotation
// x is [R, 3], M [R, 3, 3] constants (aux, row-major): y[r] = M_r x[r].  d/dx[r] = M_r^T g[r].
template <class T>
void rotate_rows_backward(tape<T>& t, int self)
{
    const auto& n = t.at(self);
    T* gx = t.adj(n.in[0]);
    if (!gx) return;
    for (std::size_t r = 0; r < n.size / 3; ++r) {
        const T* M = n.aux + r * 9;
        const T* g = n.adjoint + r * 3;
        for (std::size_t c = 0; c < 3; ++c) gx[r * 3 + c] += M[c] * g[0] + M[3 + c] * g[1] + M[6 + c] * g[2];
    }
}
/// @brief y[r] = M_r x[r] for constant 3x3 matrices `mats` ([R, 3, 3], row-major).
template <class T>
int rotate_rows(tape<T>& t, int x, std::span<const T> mats)
{
    const std::size_t R = t.at(x).size / 3;
    if (mats.size() != R * 9)
        throw shape_error("rcm::rotate_rows: " + std::to_string(mats.size()) + " matrix values for " + std::to_string(R) + " rows");
    T* aux = t.alloc(R * 9);
    const int id = t.make("rotate_rows", R * 3, {x}, &rotate_rows_backward<T>, nullptr);
    auto& n = t.at(id);
    n.aux = aux;
    std::copy(mats.begin(), mats.end(), aux);
    const T* xv = t.at(x).value;
    for (std::size_t r = 0; r < R; ++r)
        for (std::size_t i = 0; i < 3; ++i)
            n.value[r * 3 + i] = aux[r * 9 + i * 3] * xv[r * 3] + aux[r * 9 + i * 3 + 1] * xv[r * 3 + 1] + aux[r * 9 + i * 3 + 2] * xv[r * 3 + 2];
    return id;
}

// ---------------------------------------------------------------- angle between row vectors
// a, b [R, 3]: y[r] = acos(clamp(a.b / (|a| |b|), -1, 1)) (radians). With u = a/|a|, v = b/|b|, c = u.v,
// s = sqrt(1 - c^2): d/da = -g (v - c u) / (|a| s), d/db = -g (u - c v) / (|b| s) (0 where s or a norm is 0).
template <class T>
void row_angle_backward(tape<T>& t, int self)
{
    const auto& n = t.at(self);
    T* ga = t.adj(n.in[0]);
    T* gb = t.adj(n.in[1]);
    const T *a = t.at(n.in[0]).value, *b = t.at(n.in[1]).value;
    for (std::size_t r = 0; r < n.size; ++r) {
        const T* x = a + r * 3;
        const T* y = b + r * 3;
        const T na = std::sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]), nb = std::sqrt(y[0] * y[0] + y[1] * y[1] + y[2] * y[2]);
        if (!(na > 0) || !(nb > 0)) continue;
        const T c = std::clamp((x[0] * y[0] + x[1] * y[1] + x[2] * y[2]) / (na * nb), T(-1), T(1));
        const T s = std::sqrt(T(1) - c * c);
        if (!(s > T(1e-12))) continue;
        for (std::size_t k = 0; k < 3; ++k) {
            const T u = x[k] / na, v = y[k] / nb;
            if (ga) ga[r * 3 + k] -= n.adjoint[r] * (v - c * u) / (na * s);
            if (gb) gb[r * 3 + k] -= n.adjoint[r] * (u - c * v) / (nb * s);
        }
    }
}
/// @brief Angle (radians) between the rows of two [R, 3] nodes -> [R].
template <class T>
int row_angle(tape<T>& t, int a, int b)
{
    const std::size_t R = t.at(a).size / 3;
    const int id = t.make("row_angle", R, {a, b}, &row_angle_backward<T>, nullptr);
    const T *x = t.at(a).value, *y = t.at(b).value;
    for (std::size_t r = 0; r < R; ++r) {
        const T* p = x + r * 3;
        const T* q = y + r * 3;
        const T na = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]), nb = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2]);
        const T c = na > 0 && nb > 0 ? (p[0] * q[0] + p[1] * q[1] + p[2] * q[2]) / (na * nb) : T(1);
        t.at(id).value[r] = std::acos(std::clamp(c, T(-1), T(1)));
    }
    return id;
}

// ---------------------------------------------------------------- max / min over windows
// x [R]; windows w = [start_w, start_w + len): y[w] = max (sign = +1) or min (sign = -1) of x over w.
// d/dx[i*_w] = g[w] at the window's arg max / arg min (first on ties), stored in aux.
template <class T>
void window_extreme_backward(tape<T>& t, int self)
{
    const auto& n = t.at(self);
    if (T* gx = t.adj(n.in[0]))
        for (std::size_t w = 0; w < n.size; ++w) gx[static_cast<std::size_t>(n.aux[w])] += n.adjoint[w];
}
/// @brief Max (sign > 0) or min (sign < 0) of x over each window [starts[w], starts[w] + length).
template <class T>
int window_extreme(tape<T>& t, int x, std::span<const std::size_t> starts, std::size_t length, int sign)
{
    const std::size_t R = t.at(x).size;
    for (std::size_t s : starts)
        if (s + length > R || length == 0)
            throw shape_error("rcm::window_extreme: window [" + std::to_string(s) + ", " + std::to_string(s + length) +
                              ") outside [0, " + std::to_string(R) + ")");
    T* aux = t.alloc(starts.size());
    const int id = t.make(sign > 0 ? "window_max" : "window_min", starts.size(), {x}, &window_extreme_backward<T>, nullptr);
    auto& n = t.at(id);
    n.aux = aux;
    const T* xv = t.at(x).value;
    for (std::size_t w = 0; w < starts.size(); ++w) {
        std::size_t best = starts[w];
        for (std::size_t i = starts[w] + 1; i < starts[w] + length; ++i)
            if (sign > 0 ? xv[i] > xv[best] : xv[i] < xv[best]) best = i;
        aux[w] = static_cast<T>(best);
        n.value[w] = xv[best];
    }
    return id;
}

// ---------------------------------------------------------------- small compositions
/// Constant leaf holding a copy of `v`.
template <class T>
int constant(tape<T>& t, std::span<const T> v)
{
    return t.leaf_copy(v.data(), v.size(), false);
}
/// y = x * s for a scalar node s: a broadcast and an element-wise product.
template <class T>
int scale_by(tape<T>& t, int x, int s)
{
    return autodiff::detail::mul_raw(t, x, autodiff::detail::row_broadcast_raw(t, s, static_cast<int>(t.at(x).size), T(1)));
}
/// Per-row Euclidean norm of [R, 3] -> [R].
template <class T>
int norm3(tape<T>& t, int x)
{
    return autodiff::detail::row_norm_raw(t, x, static_cast<int>(t.at(x).size / 3));
}
/// Euclidean distance per row of two [R, 3] nodes.
template <class T>
int distance(tape<T>& t, int a, int b)
{
    return norm3(t, autodiff::detail::sub_raw(t, a, b));
}
/// [R] -> [R, 3] with every row (v, v, v).
template <class T>
int repeat3(tape<T>& t, int x)
{
    return autodiff::detail::row_broadcast_raw(t, x, 3, T(1));
}
/// Mean of all elements -> scalar.
template <class T>
int mean_all(tape<T>& t, int x)
{
    return autodiff::detail::row_sum_raw(t, x, 1, T(1) / static_cast<T>(t.at(x).size));
}

}  // namespace handemo::rcm::detail
