// Element-wise, reduction, layout and loss ops of handemo's autodiff tape: what the StarGAN losses of
// the hand paper (Sec. 3.3; StarGAN's adversarial WGAN-GP, domain classification and L1 cycle terms)
// and the generator's label tiling / padding of the 9x23 motion image (Eq. 3) need. Each op has a
// first-order backward with its derivative in the comment above it; the ops the WGAN-GP penalty passes
// through twice (add, sub, mul, scale, relu/leaky_relu, sum/mean, broadcast, square) also have a graph
// backward that records the derivative as tape nodes (double backward).
#pragma once

#include <handemo/autodiff/tape.hpp>

#include <cmath>
#include <cstring>
#include <utility>

namespace handemo::autodiff {
namespace detail {

// ---------------------------------------------------------------- sub, mul, scale, add_scalar
// y = a - b.  d/da = g, d/db = -g.
template <class T>
void sub_backward(tape<T>& t, int self)
{
    const node<T>& n = t.at(self);
    if (T* ga = t.adj(n.in[0]))
        for (std::size_t i = 0; i < n.size; ++i) ga[i] += n.adjoint[i];
    if (T* gb = t.adj(n.in[1]))
        for (std::size_t i = 0; i < n.size; ++i) gb[i] -= n.adjoint[i];
}
template <class T>
int scale_raw(tape<T>& t, int a, T c);
template <class T>
void sub_graph(tape<T>& t, int self)
{
    const int g = t.at(self).grad, a = t.at(self).in[0], b = t.at(self).in[1];
    t.accumulate_grad(a, g);
    if (b >= 0 && t.at(b).mark) t.accumulate_grad(b, scale_raw(t, g, T(-1)));
}
template <class T>
int sub_raw(tape<T>& t, int a, int b)
{
    const int id = t.make("sub", t.at(a).size, {a, b}, &sub_backward<T>, &sub_graph<T>);
    const T *x = t.at(a).value, *y = t.at(b).value;
    T* z = t.at(id).value;
    for (std::size_t i = 0; i < t.at(id).size; ++i) z[i] = x[i] - y[i];
    return id;
}

// y = a * b (element-wise).  d/da = g b, d/db = g a.
template <class T>
void mul_backward(tape<T>& t, int self)
{
    const node<T>& n = t.at(self);
    const T *a = t.at(n.in[0]).value, *b = t.at(n.in[1]).value;
    if (T* ga = t.adj(n.in[0]))
        for (std::size_t i = 0; i < n.size; ++i) ga[i] += n.adjoint[i] * b[i];
    if (T* gb = t.adj(n.in[1]))
        for (std::size_t i = 0; i < n.size; ++i) gb[i] += n.adjoint[i] * a[i];
}
template <class T>
int mul_raw(tape<T>& t, int a, int b);
template <class T>
void mul_graph(tape<T>& t, int self)
{
    const int g = t.at(self).grad, a = t.at(self).in[0], b = t.at(self).in[1];
    if (t.at(a).mark) t.accumulate_grad(a, mul_raw(t, g, b));
    if (t.at(b).mark) t.accumulate_grad(b, mul_raw(t, g, a));
}
template <class T>
int mul_raw(tape<T>& t, int a, int b)
{
    const int id = t.make("mul", t.at(a).size, {a, b}, &mul_backward<T>, &mul_graph<T>);
    const T *x = t.at(a).value, *y = t.at(b).value;
    T* z = t.at(id).value;
    for (std::size_t i = 0; i < t.at(id).size; ++i) z[i] = x[i] * y[i];
    return id;
}

// y = c a + d  (c = scale, d = offset).  d/da = c g.
template <class T>
struct affine_params {
    T scale;
    T offset;
};
template <class T>
void affine_backward(tape<T>& t, int self)
{
    const node<T>& n = t.at(self);
    const T c = n.template params<affine_params<T>>().scale;
    if (T* ga = t.adj(n.in[0]))
        for (std::size_t i = 0; i < n.size; ++i) ga[i] += c * n.adjoint[i];
}
template <class T>
int affine_raw(tape<T>& t, int a, T c, T d);
template <class T>
void affine_graph(tape<T>& t, int self)
{
    const int g = t.at(self).grad, a = t.at(self).in[0];
    const T c = t.at(self).template params<affine_params<T>>().scale;
    t.accumulate_grad(a, c == T(1) ? g : affine_raw(t, g, c, T(0)));
}
template <class T>
int affine_raw(tape<T>& t, int a, T c, T d)
{
    const int id = t.make("affine", t.at(a).size, {a}, &affine_backward<T>, &affine_graph<T>, affine_params<T>{c, d});
    const T* x = t.at(a).value;
    T* z = t.at(id).value;
    for (std::size_t i = 0; i < t.at(id).size; ++i) z[i] = c * x[i] + d;
    return id;
}
template <class T>
int scale_raw(tape<T>& t, int a, T c)
{
    return affine_raw(t, a, c, T(0));
}

// ---------------------------------------------------------------- relu / leaky_relu and their masks
// y = g * m(x), m(x) = 1 if x > 0 else s  (x: a node used only for its values; s: the slope).
// This is the derivative of leaky_relu (s = 0.01) and relu (s = 0) recorded by a graph backward.
// m is piecewise constant, so d/dx = 0 (almost everywhere) and d/dg = G m(x).
template <class T>
struct mask_mul_params {
    int x;  ///< id of the node whose sign selects 1 or the slope
    T slope;
};
template <class T>
int mask_mul_raw(tape<T>& t, int g, int x, T slope);
template <class T>
void mask_mul_backward(tape<T>& t, int self)
{
    const node<T>& n = t.at(self);
    const auto prm = n.template params<mask_mul_params<T>>();
    const T* x = t.at(prm.x).value;
    const T s = prm.slope;
    if (T* gg = t.adj(n.in[0]))
        for (std::size_t i = 0; i < n.size; ++i) gg[i] += x[i] > T(0) ? n.adjoint[i] : s * n.adjoint[i];
}
template <class T>
void mask_mul_graph(tape<T>& t, int self)
{
    const int g = t.at(self).grad, a = t.at(self).in[0];
    const auto prm = t.at(self).template params<mask_mul_params<T>>();
    t.accumulate_grad(a, mask_mul_raw(t, g, prm.x, prm.slope));
}
template <class T>
int mask_mul_raw(tape<T>& t, int g, int x, T slope)
{
    const int id = t.make("leaky_relu_grad", t.at(g).size, {g}, &mask_mul_backward<T>, &mask_mul_graph<T>,
                          mask_mul_params<T>{x, slope});
    const T *gv = t.at(g).value, *xv = t.at(x).value;
    T* z = t.at(id).value;
    for (std::size_t i = 0; i < t.at(id).size; ++i) z[i] = xv[i] > T(0) ? gv[i] : slope * gv[i];
    return id;
}

// y = x if x > 0 else s x  (s: the slope; relu is s = 0).  d/dx = g m(x), m(x) = 1 if x > 0 else s.
template <class T>
struct leaky_relu_params {
    T slope;
};
template <class T>
void leaky_relu_backward(tape<T>& t, int self)
{
    const node<T>& n = t.at(self);
    const T* x = t.at(n.in[0]).value;
    const T s = n.template params<leaky_relu_params<T>>().slope;
    if (T* gx = t.adj(n.in[0]))
        for (std::size_t i = 0; i < n.size; ++i) gx[i] += x[i] > T(0) ? n.adjoint[i] : s * n.adjoint[i];
}
template <class T>
void leaky_relu_graph(tape<T>& t, int self)
{
    const int g = t.at(self).grad, a = t.at(self).in[0];
    t.accumulate_grad(a, mask_mul_raw(t, g, a, t.at(self).template params<leaky_relu_params<T>>().slope));
}
template <class T>
int leaky_relu_raw(tape<T>& t, int a, T slope)
{
    const int id = t.make(slope == T(0) ? "relu" : "leaky_relu", t.at(a).size, {a}, &leaky_relu_backward<T>,
                          &leaky_relu_graph<T>, leaky_relu_params<T>{slope});
    const T* x = t.at(a).value;
    T* z = t.at(id).value;
    for (std::size_t i = 0; i < t.at(id).size; ++i) z[i] = x[i] > T(0) ? x[i] : slope * x[i];
    return id;
}

// ---------------------------------------------------------------- unary maps (first order)
// tanh: y = tanh x, dy/dx = 1 - y^2.   square: y = x^2, dy/dx = 2x.   sqrt: y = sqrt x, dy/dx = 1/(2y).
// abs: y = |x|, dy/dx = sign(x) (0 at 0).   The node's unary_params select the map.
enum class unary : int { tanh_, square_, sqrt_, abs_ };
struct unary_params {
    unary map;
};
template <class T>
int unary_raw(tape<T>& t, int a, unary k);
template <class T>
void unary_backward(tape<T>& t, int self)
{
    const node<T>& n = t.at(self);
    T* gx = t.adj(n.in[0]);
    if (!gx) return;
    const T *x = t.at(n.in[0]).value, *y = n.value, *g = n.adjoint;
    switch (n.template params<unary_params>().map) {
    case unary::tanh_:
        for (std::size_t i = 0; i < n.size; ++i) gx[i] += g[i] * (T(1) - y[i] * y[i]);
        break;
    case unary::square_:
        for (std::size_t i = 0; i < n.size; ++i) gx[i] += T(2) * x[i] * g[i];
        break;
    case unary::sqrt_:
        for (std::size_t i = 0; i < n.size; ++i) gx[i] += y[i] > T(0) ? g[i] / (T(2) * y[i]) : T(0);
        break;
    case unary::abs_:
        for (std::size_t i = 0; i < n.size; ++i) gx[i] += x[i] > T(0) ? g[i] : (x[i] < T(0) ? -g[i] : T(0));
        break;
    }
}
// Graph backward of square: d/dx = 2 x G, recorded as mul and scale nodes. The others are first order.
template <class T>
void square_graph(tape<T>& t, int self)
{
    const int g = t.at(self).grad, a = t.at(self).in[0];
    t.accumulate_grad(a, scale_raw(t, mul_raw(t, g, a), T(2)));
}
template <class T>
int unary_raw(tape<T>& t, int a, unary k)
{
    static constexpr const char* names[] = {"tanh", "square", "sqrt", "abs"};
    const int id = t.make(names[static_cast<int>(k)], t.at(a).size, {a}, &unary_backward<T>,
                          k == unary::square_ ? &square_graph<T> : nullptr, unary_params{k});
    const T* x = t.at(a).value;
    T* z = t.at(id).value;
    const std::size_t m = t.at(id).size;
    switch (k) {
    case unary::tanh_:
        for (std::size_t i = 0; i < m; ++i) z[i] = std::tanh(x[i]);
        break;
    case unary::square_:
        for (std::size_t i = 0; i < m; ++i) z[i] = x[i] * x[i];
        break;
    case unary::sqrt_:
        for (std::size_t i = 0; i < m; ++i) z[i] = std::sqrt(x[i]);
        break;
    case unary::abs_:
        for (std::size_t i = 0; i < m; ++i) z[i] = std::abs(x[i]);
        break;
    }
    return id;
}

// ---------------------------------------------------------------- reductions and broadcasts
// Rows of a [R, M] view (rows = R, cols = M), factor c. row_sum and row_broadcast, each the other's
// adjoint, share the record:
// row_sum:       y[r] = c sum_m a[r, m].      d/da[r, m] = c g[r]      (a row_broadcast)
// row_broadcast: y[r, m] = c a[r].            d/da[r]    = c sum_m g[r, m]  (a row_sum)
template <class T>
struct row_reduce_params {
    int rows;
    int cols;
    T factor;
};
template <class T>
int row_sum_raw(tape<T>& t, int a, int rows, T c);
template <class T>
int row_broadcast_raw(tape<T>& t, int a, int cols, T c);
template <class T>
void row_sum_backward(tape<T>& t, int self)
{
    const node<T>& n = t.at(self);
    T* ga = t.adj(n.in[0]);
    if (!ga) return;
    const auto prm = n.template params<row_reduce_params<T>>();
    const std::size_t R = prm.rows, M = prm.cols;
    for (std::size_t r = 0; r < R; ++r) {
        const T v = prm.factor * n.adjoint[r];
        for (std::size_t m = 0; m < M; ++m) ga[r * M + m] += v;
    }
}
template <class T>
void row_sum_graph(tape<T>& t, int self)
{
    const node<T> n = t.at(self);
    const auto prm = n.template params<row_reduce_params<T>>();
    t.accumulate_grad(n.in[0], row_broadcast_raw(t, n.grad, prm.cols, prm.factor));
}
template <class T>
int row_sum_raw(tape<T>& t, int a, int rows, T c)
{
    const std::size_t M = t.at(a).size / std::size_t(rows);
    const int id = t.make("sum", std::size_t(rows), {a}, &row_sum_backward<T>, &row_sum_graph<T>,
                          row_reduce_params<T>{rows, static_cast<int>(M), c});
    node<T>& n = t.at(id);
    const T* x = t.at(a).value;
    for (std::size_t r = 0; r < std::size_t(rows); ++r) {
        T acc = 0;
        for (std::size_t m = 0; m < M; ++m) acc += x[r * M + m];
        n.value[r] = c * acc;
    }
    return id;
}
template <class T>
void row_broadcast_backward(tape<T>& t, int self)
{
    const node<T>& n = t.at(self);
    T* ga = t.adj(n.in[0]);
    if (!ga) return;
    const auto prm = n.template params<row_reduce_params<T>>();
    const std::size_t R = prm.rows, M = prm.cols;
    for (std::size_t r = 0; r < R; ++r) {
        T acc = 0;
        for (std::size_t m = 0; m < M; ++m) acc += n.adjoint[r * M + m];
        ga[r] += prm.factor * acc;
    }
}
template <class T>
void row_broadcast_graph(tape<T>& t, int self)
{
    const node<T> n = t.at(self);
    const auto prm = n.template params<row_reduce_params<T>>();
    t.accumulate_grad(n.in[0], row_sum_raw(t, n.grad, prm.rows, prm.factor));
}
template <class T>
int row_broadcast_raw(tape<T>& t, int a, int cols, T c)
{
    const std::size_t R = t.at(a).size, M = std::size_t(cols);
    const int id = t.make("broadcast", R * M, {a}, &row_broadcast_backward<T>, &row_broadcast_graph<T>,
                          row_reduce_params<T>{static_cast<int>(R), cols, c});
    node<T>& n = t.at(id);
    const T* x = t.at(a).value;
    for (std::size_t r = 0; r < R; ++r)
        for (std::size_t m = 0; m < M; ++m) n.value[r * M + m] = c * x[r];
    return id;
}

// Per-channel sum over batch and space of [N, C, S]: y[c] = sum_{n,s} a[n, c, s];
// d/da[n, c, s] = g[c] (a channel_broadcast). channel_broadcast: y[n, c, s] = a[c]; d/da[c] = sum g.
// Both record the layout [N, C, S] of their larger side.
struct channel_layout {
    int batch;
    int channels;
    int spatial;
};
template <class T>
int channel_sum_raw(tape<T>& t, int a, int N, int C, int S);
template <class T>
int channel_broadcast_raw(tape<T>& t, int a, int N, int C, int S);
template <class T>
void channel_sum_backward(tape<T>& t, int self)
{
    const node<T>& n = t.at(self);
    T* ga = t.adj(n.in[0]);
    if (!ga) return;
    const auto l = n.template params<channel_layout>();
    const std::size_t N = l.batch, C = l.channels, S = l.spatial;
    for (std::size_t b = 0; b < N; ++b)
        for (std::size_t c = 0; c < C; ++c)
            for (std::size_t s = 0; s < S; ++s) ga[(b * C + c) * S + s] += n.adjoint[c];
}
template <class T>
void channel_sum_graph(tape<T>& t, int self)
{
    const node<T> n = t.at(self);
    const auto l = n.template params<channel_layout>();
    t.accumulate_grad(n.in[0], channel_broadcast_raw(t, n.grad, l.batch, l.channels, l.spatial));
}
template <class T>
int channel_sum_raw(tape<T>& t, int a, int N, int C, int S)
{
    const int id = t.make("channel_sum", std::size_t(C), {a}, &channel_sum_backward<T>, &channel_sum_graph<T>,
                          channel_layout{N, C, S});
    node<T>& n = t.at(id);
    const T* x = t.at(a).value;
    for (int c = 0; c < C; ++c) {
        T acc = 0;
        for (int b = 0; b < N; ++b)
            for (int s = 0; s < S; ++s) acc += x[(std::size_t(b) * C + c) * S + s];
        n.value[c] = acc;
    }
    return id;
}
template <class T>
void channel_broadcast_backward(tape<T>& t, int self)
{
    const node<T>& n = t.at(self);
    T* ga = t.adj(n.in[0]);
    if (!ga) return;
    const auto l = n.template params<channel_layout>();
    const std::size_t N = l.batch, C = l.channels, S = l.spatial;
    for (std::size_t b = 0; b < N; ++b)
        for (std::size_t c = 0; c < C; ++c)
            for (std::size_t s = 0; s < S; ++s) ga[c] += n.adjoint[(b * C + c) * S + s];
}
template <class T>
void channel_broadcast_graph(tape<T>& t, int self)
{
    const node<T> n = t.at(self);
    const auto l = n.template params<channel_layout>();
    t.accumulate_grad(n.in[0], channel_sum_raw(t, n.grad, l.batch, l.channels, l.spatial));
}
template <class T>
int channel_broadcast_raw(tape<T>& t, int a, int N, int C, int S)
{
    const int id = t.make("channel_broadcast", std::size_t(N) * C * S, {a}, &channel_broadcast_backward<T>,
                          &channel_broadcast_graph<T>, channel_layout{N, C, S});
    node<T>& n = t.at(id);
    const T* x = t.at(a).value;
    for (std::size_t b = 0; b < std::size_t(N); ++b)
        for (std::size_t c = 0; c < std::size_t(C); ++c)
            for (std::size_t s = 0; s < std::size_t(S); ++s) n.value[(b * C + c) * S + s] = x[c];
    return id;
}

// ---------------------------------------------------------------- per-row L2 norm (first order)
// y[r] = sqrt(sum_m a[r, m]^2) over a [R, M] view.  d/da[r, m] = g[r] a[r, m] / y[r]  (0 where y = 0).
struct row_layout {
    int rows;
    int cols;
};
template <class T>
void row_norm_backward(tape<T>& t, int self)
{
    const node<T>& n = t.at(self);
    T* ga = t.adj(n.in[0]);
    if (!ga) return;
    const T* a = t.at(n.in[0]).value;
    const auto l = n.template params<row_layout>();
    const std::size_t R = l.rows, M = l.cols;
    for (std::size_t r = 0; r < R; ++r) {
        if (!(n.value[r] > T(0))) continue;
        const T f = n.adjoint[r] / n.value[r];
        for (std::size_t m = 0; m < M; ++m) ga[r * M + m] += f * a[r * M + m];
    }
}
template <class T>
int row_norm_raw(tape<T>& t, int a, int rows)
{
    const std::size_t M = t.at(a).size / std::size_t(rows);
    const int id = t.make("l2_norm", std::size_t(rows), {a}, &row_norm_backward<T>, nullptr,
                          row_layout{rows, static_cast<int>(M)});
    node<T>& n = t.at(id);
    const T* x = t.at(a).value;
    for (std::size_t r = 0; r < std::size_t(rows); ++r) {
        T acc = 0;
        for (std::size_t m = 0; m < M; ++m) acc += x[r * M + m] * x[r * M + m];
        n.value[r] = std::sqrt(acc);
    }
    return id;
}

// ---------------------------------------------------------------- losses (first order)
/// Max of z[0..C) and sum of exp(z - max): the stable log-sum-exp is max + log(sum).
template <class T>
std::pair<T, T> max_and_sum_exp(const T* z, int C) noexcept
{
    T mx = z[0];
    for (int c = 1; c < C; ++c) mx = std::max(mx, z[c]);
    T se = 0;
    for (int c = 0; c < C; ++c) se += std::exp(z[c] - mx);
    return {mx, se};
}

// Softmax cross-entropy, mean over the batch (PyTorch F.cross_entropy): logits z [N, C], labels y_n
// (stored in aux as T). L = 1/N sum_n (logsumexp(z_n) - z_n[y_n]);  dL/dz[n, c] = g/N (softmax(z_n)[c] - [c = y_n]).
struct cross_entropy_params {
    int batch;
    int classes;
};
template <class T>
void cross_entropy_backward(tape<T>& t, int self)
{
    const node<T>& n = t.at(self);
    T* gz = t.adj(n.in[0]);
    if (!gz) return;
    const T* z = t.at(n.in[0]).value;
    const auto prm = n.template params<cross_entropy_params>();
    const int N = prm.batch, C = prm.classes;
    const T f = n.adjoint[0] / T(N);
    for (int b = 0; b < N; ++b) {
        const T* zb = z + std::size_t(b) * C;
        const auto [mx, se] = max_and_sum_exp(zb, C);
        const int y = static_cast<int>(n.aux[b]);
        for (int c = 0; c < C; ++c)
            gz[std::size_t(b) * C + c] += f * (std::exp(zb[c] - mx) / se - (c == y ? T(1) : T(0)));
    }
}
/// @throws value_error if a label is outside [0, C).
template <class T>
int cross_entropy_raw(tape<T>& t, int logits, int N, int C, const int* labels)
{
    for (int b = 0; b < N; ++b)
        if (labels[b] < 0 || labels[b] >= C)
            throw value_error("autodiff::cross_entropy: label[" + std::to_string(b) + "] = " +
                              std::to_string(labels[b]) + " is outside [0, " + std::to_string(C) + ")");
    const int id = t.make("cross_entropy", 1, {logits}, &cross_entropy_backward<T>, nullptr,
                          cross_entropy_params{N, C});
    T* aux = t.alloc(std::size_t(N));
    node<T>& n = t.at(id);
    n.aux = aux;
    const T* z = t.at(logits).value;
    T loss = 0;
    for (int b = 0; b < N; ++b) {
        const T* zb = z + std::size_t(b) * C;
        const auto [mx, se] = max_and_sum_exp(zb, C);
        loss += mx + std::log(se) - zb[labels[b]];
        n.aux[b] = T(labels[b]);
    }
    n.value[0] = loss / T(N);
    return id;
}

// Binary cross-entropy with logits, mean over all M elements (PyTorch BCEWithLogitsLoss): targets y in
// aux. L = 1/M sum max(z,0) - z y + log(1 + exp(-|z|));  dL/dz = g/M (sigmoid(z) - y).
template <class T>
void bce_backward(tape<T>& t, int self)
{
    const node<T>& n = t.at(self);
    T* gz = t.adj(n.in[0]);
    if (!gz) return;
    const T* z = t.at(n.in[0]).value;
    const std::size_t M = t.at(n.in[0]).size;
    const T f = n.adjoint[0] / T(M);
    for (std::size_t i = 0; i < M; ++i) gz[i] += f * (T(1) / (T(1) + std::exp(-z[i])) - n.aux[i]);
}
template <class T>
int bce_raw(tape<T>& t, int logits, const T* targets)
{
    const std::size_t M = t.at(logits).size;
    const int id = t.make("bce_with_logits", 1, {logits}, &bce_backward<T>, nullptr);
    T* aux = t.alloc(M);
    node<T>& n = t.at(id);
    n.aux = aux;
    std::memcpy(n.aux, targets, M * sizeof(T));
    const T* z = t.at(logits).value;
    T loss = 0;
    for (std::size_t i = 0; i < M; ++i)
        loss += std::max(z[i], T(0)) - z[i] * targets[i] + std::log1p(std::exp(-std::abs(z[i])));
    n.value[0] = loss / T(M);
    return id;
}

// ---------------------------------------------------------------- layout: concat, tile, pad/crop
// Channel concat of a [N, Ca, S] and b [N, Cb, S]: y[n] = (a[n], b[n]).
// d/da = g[:, :Ca], d/db = g[:, Ca:].
struct concat_params {
    int batch;
    int channels_a;
    int channels_b;
    int spatial;
};
template <class T>
void concat_backward(tape<T>& t, int self)
{
    const node<T>& n = t.at(self);
    const auto prm = n.template params<concat_params>();
    const std::size_t N = prm.batch, A = std::size_t(prm.channels_a) * prm.spatial,
                      B = std::size_t(prm.channels_b) * prm.spatial;
    T* ga = t.adj(n.in[0]);
    T* gb = t.adj(n.in[1]);
    for (std::size_t b = 0; b < N; ++b) {
        const T* g = n.adjoint + b * (A + B);
        if (ga)
            for (std::size_t i = 0; i < A; ++i) ga[b * A + i] += g[i];
        if (gb)
            for (std::size_t i = 0; i < B; ++i) gb[b * B + i] += g[A + i];
    }
}
template <class T>
int concat_raw(tape<T>& t, int a, int b, int N, int Ca, int Cb, int S)
{
    const int id = t.make("concat", std::size_t(N) * (Ca + Cb) * S, {a, b}, &concat_backward<T>, nullptr,
                          concat_params{N, Ca, Cb, S});
    node<T>& n = t.at(id);
    const std::size_t A = std::size_t(Ca) * S, B = std::size_t(Cb) * S;
    for (std::size_t k = 0; k < std::size_t(N); ++k) {
        std::memcpy(n.value + k * (A + B), t.at(a).value + k * A, A * sizeof(T));
        std::memcpy(n.value + k * (A + B) + A, t.at(b).value + k * B, B * sizeof(T));
    }
    return id;
}

// Spatial zero pad (bottom/right) of [R, H, W] to [R, H2, W2] when H2 >= H, W2 >= W, or crop (top-left)
// when H2 <= H, W2 <= W. The two are each other's adjoint:
// d/da of pad = crop(g), d/da of crop = pad(g).
struct pad_params {
    int planes;  ///< R
    int in_h;    ///< H
    int in_w;    ///< W
    int out_h;   ///< H2
    int out_w;   ///< W2
};
template <class T>
void pad_copy(const T* x, T* y, int R, int H, int W, int H2, int W2, bool accumulate) noexcept
{
    const int h = std::min(H, H2), w = std::min(W, W2);
    for (int r = 0; r < R; ++r)
        for (int i = 0; i < h; ++i) {
            const T* src = x + (std::size_t(r) * H + i) * W;
            T* dst = y + (std::size_t(r) * H2 + i) * W2;
            for (int j = 0; j < w; ++j) dst[j] = accumulate ? dst[j] + src[j] : src[j];
        }
}
template <class T>
void pad_backward(tape<T>& t, int self)
{
    const node<T>& n = t.at(self);
    const auto prm = n.template params<pad_params>();
    if (T* ga = t.adj(n.in[0])) pad_copy(n.adjoint, ga, prm.planes, prm.out_h, prm.out_w, prm.in_h, prm.in_w, true);
}
template <class T>
int pad_raw(tape<T>& t, int a, int R, int H, int W, int H2, int W2)
{
    const int id = t.make(H2 >= H ? "pad" : "crop", std::size_t(R) * H2 * W2, {a}, &pad_backward<T>, nullptr,
                          pad_params{R, H, W, H2, W2});
    node<T>& n = t.at(id);
    std::memset(n.value, 0, n.size * sizeof(T));
    pad_copy(t.at(a).value, n.value, R, H, W, H2, W2, false);
    return id;
}

}  // namespace detail

// ==================================================================== typed API
/// @brief y = a + b (same shape; a mismatch does not compile and names both shapes).
template <class T, class A, class B>
var<T, A> operator+(const var<T, A>& a, const var<T, B>& b)
{
    require_same_shape<"add", A, B>();
    return {a.t, detail::add_raw(*a.t, a.id, b.id)};
}
/// @brief y = a - b.
template <class T, class A, class B>
var<T, A> operator-(const var<T, A>& a, const var<T, B>& b)
{
    require_same_shape<"sub", A, B>();
    return {a.t, detail::sub_raw(*a.t, a.id, b.id)};
}
/// @brief y = a * b element-wise.
template <class T, class A, class B>
var<T, A> operator*(const var<T, A>& a, const var<T, B>& b)
{
    require_same_shape<"mul", A, B>();
    return {a.t, detail::mul_raw(*a.t, a.id, b.id)};
}
/// @brief y = c a.
template <class T, class S>
var<T, S> operator*(T c, const var<T, S>& a)
{
    return {a.t, detail::affine_raw(*a.t, a.id, c, T(0))};
}
/// @brief y = a + c.
template <class T, class S>
var<T, S> operator+(const var<T, S>& a, T c)
{
    return {a.t, detail::affine_raw(*a.t, a.id, T(1), c)};
}
/// @brief y = a - c.
template <class T, class S>
var<T, S> operator-(const var<T, S>& a, T c)
{
    return {a.t, detail::affine_raw(*a.t, a.id, T(1), -c)};
}
/// @brief y = -a.
template <class T, class S>
var<T, S> operator-(const var<T, S>& a)
{
    return {a.t, detail::affine_raw(*a.t, a.id, T(-1), T(0))};
}
/// @brief y = max(x, 0).
template <class T, class S>
var<T, S> relu(const var<T, S>& x)
{
    return {x.t, detail::leaky_relu_raw(*x.t, x.id, T(0))};
}
/// @brief y = x if x > 0 else slope x.
template <class T, class S>
var<T, S> leaky_relu(const var<T, S>& x, T slope = T(0.01))
{
    return {x.t, detail::leaky_relu_raw(*x.t, x.id, slope)};
}
template <class T, class S>
var<T, S> tanh(const var<T, S>& x)
{
    return {x.t, detail::unary_raw(*x.t, x.id, detail::unary::tanh_)};
}
template <class T, class S>
var<T, S> square(const var<T, S>& x)
{
    return {x.t, detail::unary_raw(*x.t, x.id, detail::unary::square_)};
}
template <class T, class S>
var<T, S> sqrt(const var<T, S>& x)
{
    return {x.t, detail::unary_raw(*x.t, x.id, detail::unary::sqrt_)};
}
template <class T, class S>
var<T, S> abs(const var<T, S>& x)
{
    return {x.t, detail::unary_raw(*x.t, x.id, detail::unary::abs_)};
}
/// @brief Sum of all elements -> scalar.
template <class T, class S>
var<T, shape<>> sum(const var<T, S>& x)
{
    return {x.t, detail::row_sum_raw(*x.t, x.id, 1, T(1))};
}
/// @brief Mean of all elements -> scalar.
template <class T, class S>
var<T, shape<>> mean(const var<T, S>& x)
{
    return {x.t, detail::row_sum_raw(*x.t, x.id, 1, T(1) / T(S::size))};
}
/// @brief Per-sample sum over all but the first dimension: [N, ...] -> [N].
template <class T, class S>
    requires(S::rank >= 1)
var<T, shape<S::dims[0]>> sum_per_sample(const var<T, S>& x)
{
    return {x.t, detail::row_sum_raw(*x.t, x.id, int(S::dims[0]), T(1))};
}
/// @brief Per-sample mean: [N, ...] -> [N].
template <class T, class S>
    requires(S::rank >= 1)
var<T, shape<S::dims[0]>> mean_per_sample(const var<T, S>& x)
{
    return {x.t, detail::row_sum_raw(*x.t, x.id, int(S::dims[0]), T(S::dims[0]) / T(S::size))};
}
/// @brief Per-sample L2 norm over all but the first dimension: [N, ...] -> [N].
template <class T, class S>
    requires(S::rank >= 1)
var<T, shape<S::dims[0]>> l2_norm_per_sample(const var<T, S>& x)
{
    return {x.t, detail::row_norm_raw(*x.t, x.id, int(S::dims[0]))};
}
/// @brief Mean absolute difference (L1 loss, mean reduction) -> scalar.
template <class T, class A, class B>
var<T, shape<>> l1_loss(const var<T, A>& a, const var<T, B>& b)
{
    require_same_shape<"l1_loss", A, B>();
    return mean(abs(a - b));
}
/// @brief Softmax cross-entropy of logits [N, C] with integer labels [N], mean over the batch.
/// @throws value_error if a label is outside [0, C).
template <class T, std::size_t N, std::size_t C>
var<T, shape<>> cross_entropy(const var<T, shape<N, C>>& logits, std::span<const int, N> labels)
{
    return {logits.t, detail::cross_entropy_raw(*logits.t, logits.id, int(N), int(C), labels.data())};
}
/// @brief Binary cross-entropy with logits, mean over all elements; targets in [0, 1], same size.
template <class T, class S>
var<T, shape<>> bce_with_logits(const var<T, S>& logits, std::span<const T, S::size> targets)
{
    return {logits.t, detail::bce_raw(*logits.t, logits.id, targets.data())};
}
/// @brief Channel concat of [N, Ca, H, W] and [N, Cb, H, W] -> [N, Ca+Cb, H, W].
template <class T, std::size_t N, std::size_t Ca, std::size_t Cb, std::size_t H, std::size_t W, std::size_t N2,
          std::size_t H2, std::size_t W2>
var<T, shape<N, Ca + Cb, H, W>> concat_channels(const var<T, shape<N, Ca, H, W>>& a,
                                                const var<T, shape<N2, Cb, H2, W2>>& b)
{
    require_same_shape<"concat_channels (batch, height, width)", shape<N, H, W>, shape<N2, H2, W2>>();
    return {a.t, detail::concat_raw(*a.t, a.id, b.id, int(N), int(Ca), int(Cb), int(H * W))};
}
/// @brief Tiles a label [N, C] over space: y[n, c, i, j] = label[n, c] -> [N, C, H, W].
template <std::size_t H, std::size_t W, class T, std::size_t N, std::size_t C>
var<T, shape<N, C, H, W>> tile(const var<T, shape<N, C>>& label)
{
    return {label.t, detail::row_broadcast_raw(*label.t, label.id, int(H * W), T(1))};
}
/// @brief Zero-pads [N, C, H, W] at the bottom/right to [N, C, H2, W2] (H2 >= H, W2 >= W).
template <std::size_t H2, std::size_t W2, class T, std::size_t N, std::size_t C, std::size_t H, std::size_t W>
    requires(H2 >= H && W2 >= W)
var<T, shape<N, C, H2, W2>> pad(const var<T, shape<N, C, H, W>>& x)
{
    return {x.t, detail::pad_raw(*x.t, x.id, int(N * C), int(H), int(W), int(H2), int(W2))};
}
/// @brief Keeps the top-left [H2, W2] of [N, C, H, W] (H2 <= H, W2 <= W).
template <std::size_t H2, std::size_t W2, class T, std::size_t N, std::size_t C, std::size_t H, std::size_t W>
    requires(H2 <= H && W2 <= W)
var<T, shape<N, C, H2, W2>> crop(const var<T, shape<N, C, H, W>>& x)
{
    return {x.t, detail::pad_raw(*x.t, x.id, int(N * C), int(H), int(W), int(H2), int(W2))};
}

}  // namespace handemo::autodiff
