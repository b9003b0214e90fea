// Convolution ops of handemo's autodiff tape: conv2d (stride, zero padding, optional bias) and
// conv_transpose2d, as PyTorch's Conv2d / ConvTranspose2d, the layers of the StarGAN generator and
// discriminator of the hand paper (Sec. 3.3, Fig. 3). They call the kernels of handemo/kernels/conv.hpp
// and split the batch over the tape's thread pool when it has one. For the WGAN-GP penalty every
// convolution also has a graph backward: the input gradient of conv2d is conv_transpose2d with the same
// weight node, the weight gradient is a `conv_weight_grad` node, the bias gradient a channel sum, and
// those nodes are themselves differentiable, so the gradient of the penalty reaches D's weights exactly.
#pragma once

#include <handemo/autodiff/ops.hpp>
#include <handemo/autodiff/tape.hpp>

#include <handemo/kernels/conv.hpp>
#include <handemo/core/thread_pool.hpp>

#include <algorithm>
#include <cstring>
#include <utility>

namespace handemo::autodiff {
namespace detail {

namespace ck = handemo::kernels;
using kernels::conv_geometry;

// The parameter record of conv2d, conv_transpose2d and conv_weight_grad is the kernels' conv_geometry
// (conv_transpose2d and conv_weight_grad store the geometry of the conv they are the adjoints of).
template <class T>
conv_geometry geometry_of(const node<T>& n)
{
    return n.template params<conv_geometry>();
}

/// Samples [first, second) of chunk c of P of a batch of `batch`.
inline std::pair<int, int> chunk_range(int batch, int P, int c) noexcept
{
    return {int(long(batch) * c / P), int(long(batch) * (c + 1) / P)};
}

/// Number of batch chunks to run in parallel (1 without a pool): the most, up to the pool's size, whose every chunk
/// the kernels compute with the whole batch's bits (kernels::conv2d_batch_part_keeps_bits()), so that the result
/// does not depend on the thread count.
template <class T>
int chunks(tape<T>& t, const conv_geometry& g) noexcept
{
    if (!t.pool()) return 1;
    for (int P = std::max(1, std::min<int>(g.batch, int(t.pool()->size()))); P > 1; --P) {
        bool same = true;
        for (int c = 0; c < P && same; ++c) {
            const auto [n0, n1] = chunk_range(g.batch, P, c);
            conv_geometry gc = g;
            gc.batch = n1 - n0;
            same = ck::conv2d_batch_part_keeps_bits<T>(g, gc);
        }
        if (same) return P;
    }
    return 1;
}

/// Runs f(geometry of a batch chunk, first sample, chunk index) for every chunk; scratch per chunk.
template <class T, class F>
void for_batch_chunks(tape<T>& t, const conv_geometry& g, F&& f)
{
    const int P = chunks(t, g);
    const std::size_t ss = ck::conv2d_scratch_size<T>(g);
    T* scratch = ss ? t.scratch(ss * P) : nullptr;
    auto run = [&](int c) {
        const auto [n0, n1] = chunk_range(g.batch, P, c);
        conv_geometry gc = g;
        gc.batch = n1 - n0;
        if (gc.batch > 0) f(gc, n0, c, scratch ? scratch + ss * c : nullptr);
    };
    if (P == 1)
        run(0);
    else
        t.pool()->parallel_for(0, P, run);
}

/// The weights of node w packed for `use` over geometry g, once per tape (tape::packed) when w is a parameter
/// (caller memory, unchanged until the tape's reset()) and that call of g takes packed panels; else nullptr, and
/// the kernel packs them at the call. In a training step's G phase G's weights are read by three or four forward
/// and as many backward-data passes, in its D phase D's by three forward passes and the penalty's double backward:
/// the same panels, so the same bits.
template <class T>
const T* weight_panels(tape<T>& t, int w, const conv_geometry& g, ck::conv_panels use)
{
    const node<T>& n = t.at(w);
    if (!n.external_value || !t.panel_cache()) return nullptr;
    const std::size_t m = ck::conv2d_panel_elements<T>(g, use);
    if (m == 0) return nullptr;
    const T* v = n.value;
    return t.packed(v, int(use), m, [&](T* dst) { ck::conv2d_pack_panels<T>(g, use, v, dst); });
}

// ---- raw kernels over a whole batch, threaded when the tape has a pool --------------------------
// y = conv(x, w) + b (panels: w packed ahead, or nullptr)
template <class T>
void conv_fwd(tape<T>& t, const conv_geometry& g, const T* x, const T* w, const T* b, T* y, const T* panels = nullptr)
{
    const std::size_t xs = std::size_t(g.in_channels) * g.in_h * g.in_w;
    const std::size_t ys = std::size_t(g.out_channels) * g.out_h() * g.out_w();
    for_batch_chunks(t, g, [&](const conv_geometry& gc, int n0, int, T* s) {
        ck::conv2d_forward<T>(gc, x + n0 * xs, w, b, y + n0 * ys, s, panels);
    });
}
// gx += conv^T(gy, w) (panels: w packed ahead, or nullptr)
template <class T>
void conv_bwd_data(tape<T>& t, const conv_geometry& g, const T* gy, const T* w, T* gx, const T* panels = nullptr)
{
    const std::size_t xs = std::size_t(g.in_channels) * g.in_h * g.in_w;
    const std::size_t ys = std::size_t(g.out_channels) * g.out_h() * g.out_w();
    for_batch_chunks(t, g, [&](const conv_geometry& gc, int n0, int, T* s) {
        ck::conv2d_backward_data<T>(gc, gy + n0 * ys, w, gx + n0 * xs, s, panels);
    });
}
// gw += sum_n x[n] (*) gy[n], split over the pool by output channels, never by samples
// (kernels::conv2d_backward_weight_parts()): each weight is summed by one thread in the order of one pass, so the
// bits do not depend on the thread count. A geometry no split keeps the bits of runs on one thread.
template <class T>
void conv_bwd_weight(tape<T>& t, const conv_geometry& g, const T* x, const T* gy, T* gw)
{
    const int P = t.pool() ? ck::conv2d_backward_weight_parts<T>(g, int(t.pool()->size())) : 1;
    if (P == 1) {
        const std::size_t ss = ck::conv2d_scratch_size<T>(g);
        ck::conv2d_backward_weight<T>(g, x, gy, gw, ss ? t.scratch(ss) : nullptr);
        return;
    }
    // per part: gy's channels of the part, image by image, then the kernel's scratch (each 64-byte aligned)
    const std::size_t pix = std::size_t(g.out_h()) * g.out_w(), wk = std::size_t(g.in_channels) * g.kernel_h * g.kernel_w;
    constexpr std::size_t round = 64 / sizeof(T);
    const auto up = [](std::size_t n) { return (n + round - 1) / round * round; };
    const auto part = [&](int k) {  // part k's first channel and geometry
        const auto [o0, o1] = ck::conv2d_backward_weight_part<T>(g, P, k);
        conv_geometry gp = g;
        gp.out_channels = o1 - o0;
        return std::pair{o0, gp};
    };
    std::size_t per = 0;
    for (int k = 0; k < P; ++k) {
        const conv_geometry gp = part(k).second;
        per = std::max(per, up(gp.y_size()) + up(ck::conv2d_scratch_size<T>(gp)));
    }
    T* base = t.scratch(per * std::size_t(P));
    t.pool()->parallel_for(0, P, [&](int k) {
        const auto [o0, gp] = part(k);
        T* gyp = base + per * std::size_t(k);
        for (int n = 0; n < g.batch; ++n)
            std::memcpy(gyp + std::size_t(n) * gp.out_channels * pix, gy + (std::size_t(n) * g.out_channels + std::size_t(o0)) * pix,
                        sizeof(T) * std::size_t(gp.out_channels) * pix);
        ck::conv2d_backward_weight<T>(gp, x, gyp, gw + std::size_t(o0) * wk, gyp + up(gp.y_size()));
    });
}
// dst += src
template <class T>
void add_into(T* dst, const T* src, std::size_t n) noexcept
{
    for (std::size_t i = 0; i < n; ++i) dst[i] += src[i];
}

template <class T>
int conv_raw(tape<T>& t, int x, int w, int b, const conv_geometry& g);
template <class T>
int conv_transpose_raw(tape<T>& t, int x, int w, const conv_geometry& g);
template <class T>
int conv_weight_grad_raw(tape<T>& t, int x, int gy, const conv_geometry& g);

// ---- conv2d --------------------------------------------------------------------------------------
// y[n,o,i,j] = b[o] + sum_{c,u,v} x[n,c,i s-p+u, j s-p+v] w[o,c,u,v]
// d/dx = conv_transpose(g, w)             (kernels: conv2d_backward_data)
// d/dw[o,c,u,v] = sum_{n,i,j} g[n,o,i,j] x[n,c,i s-p+u, j s-p+v]   (conv2d_backward_weight)
// d/db[o] = sum_{n,i,j} g[n,o,i,j]
template <class T>
void conv_backward(tape<T>& t, int self)
{
    const node<T>& n = t.at(self);
    const conv_geometry g = geometry_of(n);
    if (T* gx = t.adj(n.in[0]))
        conv_bwd_data(t, g, n.adjoint, t.at(n.in[1]).value, gx, weight_panels(t, n.in[1], g, ck::conv_panels::backward_data));
    if (T* gw = t.adj(n.in[1])) conv_bwd_weight(t, g, t.at(n.in[0]).value, n.adjoint, gw);
    if (T* gb = t.adj(n.in[2])) ck::conv2d_backward_bias<T>(g, n.adjoint, gb);
}
// Graph backward: the three gradients above as nodes (conv_transpose, conv_weight_grad, channel_sum).
template <class T>
void conv_graph(tape<T>& t, int self)
{
    const node<T> n = t.at(self);
    const conv_geometry g = geometry_of(n);
    if (t.at(n.in[0]).mark) t.accumulate_grad(n.in[0], conv_transpose_raw(t, n.grad, n.in[1], g));
    if (t.at(n.in[1]).mark) t.accumulate_grad(n.in[1], conv_weight_grad_raw(t, n.in[0], n.grad, g));
    if (n.in[2] >= 0 && t.at(n.in[2]).mark)
        t.accumulate_grad(n.in[2], channel_sum_raw(t, n.grad, g.batch, g.out_channels, g.out_h() * g.out_w()));
}
/// y = conv(x, w) + b over geometry g (b = -1: no bias).
template <class T>
int conv_raw(tape<T>& t, int x, int w, int b, const conv_geometry& g)
{
    const int id = t.make("conv2d", g.y_size(), {x, w, b}, &conv_backward<T>, &conv_graph<T>, g);
    conv_fwd(t, g, t.at(x).value, t.at(w).value, b >= 0 ? t.at(b).value : static_cast<const T*>(nullptr),
             t.at(id).value, weight_panels(t, w, g, ck::conv_panels::forward));
    return id;
}

// ---- conv_transpose2d, stored as the adjoint of the conv of geometry g (x is g's output side) ---------
// z = conv^T(x, w): z = backward_data_g(x, w), x [N, g.out_channels, oh, ow], z [N, g.in_channels, in_h, in_w].
// d/dx = conv_g(G, w) (no bias);   d/dw = backward_weight_g(G, x)   (z is linear in x and in w)
template <class T>
void conv_transpose_backward(tape<T>& t, int self)
{
    const node<T>& n = t.at(self);
    const conv_geometry g = geometry_of(n);
    if (T* gx = t.adj(n.in[0])) {
        T* tmp = t.alloc(g.y_size());
        conv_fwd(t, g, n.adjoint, t.at(n.in[1]).value, static_cast<const T*>(nullptr), tmp,
                 weight_panels(t, n.in[1], g, ck::conv_panels::forward));
        add_into(gx, tmp, g.y_size());
    }
    if (T* gw = t.adj(n.in[1])) conv_bwd_weight(t, g, n.adjoint, t.at(n.in[0]).value, gw);
}
template <class T>
void conv_transpose_graph(tape<T>& t, int self)
{
    const node<T> n = t.at(self);
    const conv_geometry g = geometry_of(n);
    if (t.at(n.in[0]).mark) t.accumulate_grad(n.in[0], conv_raw(t, n.grad, n.in[1], -1, g));
    if (t.at(n.in[1]).mark) t.accumulate_grad(n.in[1], conv_weight_grad_raw(t, n.grad, n.in[0], g));
}
template <class T>
int conv_transpose_raw(tape<T>& t, int x, int w, const conv_geometry& g)
{
    const int id = t.make("conv_transpose2d", g.x_size(), {x, w}, &conv_transpose_backward<T>,
                          &conv_transpose_graph<T>, g);
    T* z = t.at(id).value;
    std::memset(z, 0, g.x_size() * sizeof(T));
    conv_bwd_data(t, g, t.at(x).value, t.at(w).value, z, weight_panels(t, w, g, ck::conv_panels::backward_data));
    return id;
}

// ---- conv_weight_grad: gw = backward_weight_g(x, gy), a node so that it can be differentiated ---------
// gw[o,c,u,v] = sum_{n,i,j} gy[n,o,i,j] x[n,c,i s-p+u, j s-p+v], bilinear in (x, gy):
// d/dx = conv_transpose_g(gy, G) (G as the weight);   d/dgy = conv_g(x, G)
template <class T>
void conv_weight_grad_backward(tape<T>& t, int self)
{
    const node<T>& n = t.at(self);
    const conv_geometry g = geometry_of(n);
    if (T* gx = t.adj(n.in[0])) conv_bwd_data(t, g, t.at(n.in[1]).value, n.adjoint, gx);
    if (T* ggy = t.adj(n.in[1])) {
        T* tmp = t.alloc(g.y_size());
        conv_fwd(t, g, t.at(n.in[0]).value, n.adjoint, static_cast<const T*>(nullptr), tmp);
        add_into(ggy, tmp, g.y_size());
    }
}
template <class T>
void conv_weight_grad_graph(tape<T>& t, int self)
{
    const node<T> n = t.at(self);
    const conv_geometry g = geometry_of(n);
    if (t.at(n.in[0]).mark) t.accumulate_grad(n.in[0], conv_transpose_raw(t, n.in[1], n.grad, g));
    if (t.at(n.in[1]).mark) t.accumulate_grad(n.in[1], conv_raw(t, n.in[0], n.grad, -1, g));
}
template <class T>
int conv_weight_grad_raw(tape<T>& t, int x, int gy, const conv_geometry& g)
{
    const int id = t.make("conv_weight_grad", g.w_size(), {x, gy}, &conv_weight_grad_backward<T>,
                          &conv_weight_grad_graph<T>, g);
    T* gw = t.at(id).value;
    std::memset(gw, 0, g.w_size() * sizeof(T));
    conv_bwd_weight(t, g, t.at(x).value, t.at(gy).value, gw);
    return id;
}

}  // namespace detail

/// @brief PyTorch Conv2d without bias: x [N, Ci, H, W], w [Co, Ci, KH, KW] -> [N, Co, OH, OW],
/// OH = (H + 2 Pad - KH) / Stride + 1.
template <std::size_t Stride, std::size_t Pad, class T, std::size_t N, std::size_t Ci, std::size_t H,
          std::size_t W, std::size_t Co, std::size_t Ci2, std::size_t KH, std::size_t KW>
    requires(H + 2 * Pad >= KH && W + 2 * Pad >= KW && Stride > 0)
var<T, shape<N, Co, conv_out(H, KH, Stride, Pad), conv_out(W, KW, Stride, Pad)>>
conv2d(const var<T, shape<N, Ci, H, W>>& x, const var<T, shape<Co, Ci2, KH, KW>>& w)
{
    require_same_shape<"conv2d (input channels of x and w)", shape<Ci>, shape<Ci2>>();
    const kernels::conv_geometry g{int(N), int(Ci), int(H), int(W), int(Co), int(KH), int(KW), int(Stride), int(Pad)};
    return {x.t, detail::conv_raw(*x.t, x.id, w.id, -1, g)};
}
/// @brief PyTorch Conv2d with bias b [Co].
template <std::size_t Stride, std::size_t Pad, class T, std::size_t N, std::size_t Ci, std::size_t H,
          std::size_t W, std::size_t Co, std::size_t Ci2, std::size_t KH, std::size_t KW, std::size_t Co2>
    requires(H + 2 * Pad >= KH && W + 2 * Pad >= KW && Stride > 0)
var<T, shape<N, Co, conv_out(H, KH, Stride, Pad), conv_out(W, KW, Stride, Pad)>>
conv2d(const var<T, shape<N, Ci, H, W>>& x, const var<T, shape<Co, Ci2, KH, KW>>& w, const var<T, shape<Co2>>& b)
{
    require_same_shape<"conv2d (input channels of x and w)", shape<Ci>, shape<Ci2>>();
    require_same_shape<"conv2d (output channels of w and bias)", shape<Co>, shape<Co2>>();
    const kernels::conv_geometry g{int(N), int(Ci), int(H), int(W), int(Co), int(KH), int(KW), int(Stride), int(Pad)};
    return {x.t, detail::conv_raw(*x.t, x.id, w.id, b.id, g)};
}
/// @brief PyTorch ConvTranspose2d without bias: x [N, Ci, H, W], w [Ci, Co, KH, KW] ->
/// [N, Co, (H-1) Stride - 2 Pad + KH, (W-1) Stride - 2 Pad + KW].
template <std::size_t Stride, std::size_t Pad, class T, std::size_t N, std::size_t Ci, std::size_t H,
          std::size_t W, std::size_t Ci2, std::size_t Co, std::size_t KH, std::size_t KW>
    requires((H - 1) * Stride + KH >= 2 * Pad + 1 && Stride > 0)
var<T, shape<N, Co, conv_transpose_out(H, KH, Stride, Pad), conv_transpose_out(W, KW, Stride, Pad)>>
conv_transpose2d(const var<T, shape<N, Ci, H, W>>& x, const var<T, shape<Ci2, Co, KH, KW>>& w)
{
    require_same_shape<"conv_transpose2d (input channels of x and w)", shape<Ci>, shape<Ci2>>();
    constexpr std::size_t OH = conv_transpose_out(H, KH, Stride, Pad), OW = conv_transpose_out(W, KW, Stride, Pad);
    static_assert(conv_out(OH, KH, Stride, Pad) == H && conv_out(OW, KW, Stride, Pad) == W,
                  "conv_transpose2d: output size is not the exact adjoint of a conv (output_padding unsupported)");
    const kernels::conv_geometry g{int(N), int(Co), int(OH), int(OW), int(Ci), int(KH), int(KW), int(Stride), int(Pad)};
    return {x.t, detail::conv_transpose_raw(*x.t, x.id, w.id, g)};
}

}  // namespace handemo::autodiff
