// Inference-only StarGAN generator for small targets (a glove's Cortex-M7 or Cortex-M55): G(x, c) of Chan,
// Irimia & Ho 2020 (Sec. 3.3, Fig. 3) exactly as stargan::generator::infer computes it, with no exceptions, no
// heap, no RTTI, no iostreams and no SIMD library: the weights are one flat constexpr float array in PyTorch
// state_dict order (written by `handemo export --header`, so they sit in flash), the activations live in a
// workspace whose size is a compile-time constant (static storage or the stack), and the convolutions are
// plain loops without bounds checks in the inner loop (the order of kernels/reference.hpp, whose
// conv_geometry they use), or on a core with Helium (MVE floating point) the same loops on MVE vectors
// through the compiler's <arm_mve.h>. This file needs only <cmath>, <concepts>, <cstddef>, <cstdint>, that
// header and <arm_mve.h>, so an arm-none-eabi build with -fno-exceptions -fno-rtti pulls in nothing else.
#pragma once

#include <cmath>
#include <concepts>
#include <cstddef>
#include <cstdint>

#include <handemo/kernels/reference.hpp>

// Helium (MVE with floating point, e.g. -mcpu=cortex-m55): the convolutions' register tiles become MVE vectors
// (detail::mve below). HANDEMO_MICRO_NO_MVE keeps the plain loops (whatever the compiler vectorises itself).
#if defined(__ARM_FEATURE_MVE) && (__ARM_FEATURE_MVE & 2) && !defined(HANDEMO_MICRO_NO_MVE)
#define HANDEMO_MICRO_MVE 1
#include <arm_mve.h>
#else
#define HANDEMO_MICRO_MVE 0
#endif

namespace handemo::micro {

/// @brief What a generated model header provides (see `handemo export --header`): the configuration
/// (joints J, keyframes K, domains C, conv_dim, res_blocks, residual) and `weights`, every G parameter
/// in state_dict order, densely packed.
template <class M>
concept generator_model = requires {
    { M::joints } -> std::convertible_to<std::size_t>;
    { M::keyframes } -> std::convertible_to<std::size_t>;
    { M::domains } -> std::convertible_to<std::size_t>;
    { M::conv_dim } -> std::convertible_to<std::size_t>;
    { M::res_blocks } -> std::convertible_to<std::size_t>;
    { M::residual } -> std::convertible_to<bool>;
    { M::weights[0] } -> std::convertible_to<float>;
};

namespace detail {

/// Convolution i of G on an h x w image with in_ch input channels and conv_dim c: conv7, down1, down2, the
/// residual conv3, up1 and up2 (as the convolution they are the adjoint of), conv7.
constexpr kernels::conv_geometry generator_geometry(int h, int w, int in_ch, int c, int i) noexcept
{
    switch (i) {
    case 0: return {1, in_ch, h, w, c, 7, 7, 1, 3};
    case 1: return {1, c, h, w, 2 * c, 4, 4, 2, 1};
    case 2: return {1, 2 * c, h / 2, w / 2, 4 * c, 4, 4, 2, 1};
    case 3: return {1, 4 * c, h / 4, w / 4, 4 * c, 3, 3, 1, 1};
    case 4: return {1, 2 * c, h / 2, w / 2, 4 * c, 4, 4, 2, 1};
    case 5: return {1, c, h, w, 2 * c, 4, 4, 2, 1};
    default: return {1, c, h, w, 3, 7, 7, 1, 3};
    }
}
/// Whether layer i of generator_geometry runs as a transposed convolution (up1, up2).
constexpr bool transposed_layer(int i) noexcept { return i == 4 || i == 5; }

/// Zero rows/columns a transposed convolution's input needs on each side so that every tap reads inside the
/// padded copy: tap u of output h reads input i = (h + pad - u) / stride, -kernel/stride <= i < out + kernel/stride.
constexpr int convt_margin(int kernel, int stride) noexcept { return (kernel + stride - 1) / stride + 1; }

/// Elements of the zero-padded input copy conv_forward<G> needs.
constexpr std::size_t conv_pad_elements(const kernels::conv_geometry& g) noexcept
{
    return std::size_t(g.in_channels) * (g.in_h + 2 * g.pad) * (g.in_w + 2 * g.pad);
}
/// Elements of the zero-padded input copy conv_transpose<G> needs.
constexpr std::size_t convt_pad_elements(const kernels::conv_geometry& g) noexcept
{
    const int mh = convt_margin(g.kernel_h, g.stride), mw = convt_margin(g.kernel_w, g.stride);
    return std::size_t(g.out_channels) * (g.out_h() + 2 * mh) * (g.out_w() + 2 * mw);
}
/// The largest zero-padded input copy over G's seven layers.
constexpr std::size_t generator_pad_elements(int h, int w, int in_ch, int c) noexcept
{
    std::size_t m = 0;
    for (int i = 0; i < 7; ++i) {
        const kernels::conv_geometry g = generator_geometry(h, w, in_ch, c, i);
        const std::size_t n = transposed_layer(i) ? convt_pad_elements(g) : conv_pad_elements(g);
        m = n > m ? n : m;
    }
    return m;
}

}  // namespace detail

/// @brief Sizes of G for a configuration (K keyframes, J joints, C domains, conv_dim cd, R residual blocks).
template <std::size_t K, std::size_t J, std::size_t C, std::size_t cd, std::size_t R>
struct generator_layout {
    static constexpr std::size_t H = (K + 3) / 4 * 4, W = (J + 3) / 4 * 4, HW = H * W;
    static constexpr std::size_t in_ch = 3 + C;
    /// Scalar parameters, in the order stargan::generator declares them (conv7, IN, 2 x down + IN,
    /// R x [conv3, IN, conv3, IN], 2 x up + IN, conv7).
    static constexpr std::size_t parameter_count = cd * in_ch * 49 + 2 * cd + 2 * cd * cd * 16 + 4 * cd +
                                                   4 * cd * 2 * cd * 16 + 8 * cd +
                                                   R * 2 * (4 * cd * 4 * cd * 9 + 8 * cd) + 4 * cd * 2 * cd * 16 +
                                                   4 * cd + 2 * cd * cd * 16 + 2 * cd + 3 * cd * 49;
    /// Elements of the three full-size activation buffers and of the small one (a residual branch).
    static constexpr std::size_t big_elements = (cd > in_ch ? cd : in_ch) * HW;
    static constexpr std::size_t small_elements = 4 * cd * HW / 16;
    /// Elements of the zero-padded copy of a convolution's input that conv_forward and conv_transpose make:
    /// the largest over the seven layers.
    static constexpr std::size_t pad_elements = detail::generator_pad_elements(int(H), int(W), int(in_ch), int(cd));
    /// Bytes of generator::workspace (padded input and output, three big buffers, one small one, the
    /// convolutions' zero-padded input).
    static constexpr std::size_t workspace_bytes =
        sizeof(float) * (6 * HW + 3 * big_elements + small_elements + pad_elements);
    /// Convolution geometries: conv7, down1, down2, residual conv3, up1 and up2 (as the adjoint conv), conv7.
    static constexpr kernels::conv_geometry geometry(int i) noexcept
    {
        return detail::generator_geometry(int(H), int(W), int(in_ch), int(cd), i);
    }
    /// Multiply-adds of one inference as generator::infer_padded runs it: the first layer on the image's 3
    /// channels (the tiled label's taps are added as window sums, detail::add_label_taps), the others whole.
    static constexpr double macs() noexcept
    {
        return geometry(0).macs() * 3.0 / double(in_ch) + geometry(1).macs() + geometry(2).macs() +
               2.0 * R * geometry(3).macs() + geometry(4).macs() + geometry(5).macs() + geometry(6).macs();
    }
};

namespace detail {

/// Pixels of one register tile along an output row: the largest divisor of n that is at most 8 (8
/// accumulators, a weight and the loaded inputs fit a Cortex-M7's 32 single-precision registers).
constexpr int row_tile(int n) noexcept
{
    for (int t = 8; t > 1; --t)
        if (n % t == 0) return t;
    return 1;
}

/// xp [ch][h + 2 * ph][w + 2 * pw] = x [ch][h][w] framed by ph zero rows and pw zero columns on each side.
template <int ch, int h, int w, int ph, int pw>
inline void pad_copy(const float* x, float* xp) noexcept
{
    constexpr int Wp = w + 2 * pw, Hp = h + 2 * ph;
    for (int i = 0; i < ch * Hp * Wp; ++i) xp[i] = 0.f;
    for (int c = 0; c < ch; ++c)
        for (int i = 0; i < h; ++i)
            for (int j = 0; j < w; ++j) xp[(c * Hp + i + ph) * Wp + pw + j] = x[(c * h + i) * w + j];
}

/// y = conv(x, w) at batch 1, no bias (PyTorch Conv2d), geometry G fixed at compile time. Output-stationary:
/// row_tile(out_w) output pixels of one row accumulate in registers over (c, u, v), the order of
/// kernels::reference::conv2d_forward, reading a zero-padded copy of x (xp, conv_pad_elements(G)), so no
/// loop has a bounds check and each weight is loaded once per tile (the zero taps add exact zeros; the
/// compiler also keeps the inputs a tile shares between kernel columns in registers). hand-micro on a
/// Cortex-M7, firmware at -O2, under qemu -icount: 6.7 M instructions per inference (with the tiled label's
/// channels convolved), against 22.1 M with the weight-stationary loops (one multiply-add into the output plane
/// per weight and pixel) this replaced.
/// LDW: the weights of output channel o start at w + o * LDW (G's first layer reads the image's 3 channels out
/// of weights laid out for 3 + C).
template <kernels::conv_geometry G, int LDW = G.in_channels * G.kernel_h * G.kernel_w>
inline void conv_forward(const float* x, const float* w, float* y, float* xp) noexcept
{
    constexpr int Cin = G.in_channels, KH = G.kernel_h, KW = G.kernel_w, S = G.stride, P = G.pad;
    constexpr int Hp = G.in_h + 2 * P, Wp = G.in_w + 2 * P, oh = G.out_h(), ow = G.out_w(), NB = row_tile(ow);
    static_assert(G.batch == 1 && G.valid(), "micro::conv_forward: batch-1 geometry");
    static_assert(LDW >= Cin * KH * KW, "micro::conv_forward: weight stride shorter than a filter");
    pad_copy<Cin, G.in_h, G.in_w, P, P>(x, xp);
    for (int o = 0; o < G.out_channels; ++o) {
        const float* wo = w + o * LDW;
        for (int i = 0; i < oh; ++i)
            for (int j0 = 0; j0 < ow; j0 += NB) {
                float acc[NB];
#pragma GCC unroll 8
                for (int t = 0; t < NB; ++t) acc[t] = 0.f;
                const float* wk = wo;
                for (int c = 0; c < Cin; ++c)
                    for (int u = 0; u < KH; ++u) {
                        const float* xr = xp + (c * Hp + i * S + u) * Wp + j0 * S;
#pragma GCC unroll 7
                        for (int v = 0; v < KW; ++v) {
                            const float wv = *wk++;
#pragma GCC unroll 8
                            for (int t = 0; t < NB; ++t) acc[t] += wv * xr[t * S + v];
                        }
                    }
                float* yr = y + (o * oh + i) * ow + j0;
#pragma GCC unroll 8
                for (int t = 0; t < NB; ++t) yr[t] = acc[t];
            }
    }
}

/// y = ConvTranspose2d(x, w) at batch 1, no bias; G is the convolution it is the adjoint of (as in
/// kernels::reference::conv_transpose2d_forward): x [G.out_channels, oh, ow], w [G.out_channels,
/// G.in_channels, k, k], y [G.in_channels, G.in_h, G.in_w]. Output-stationary like conv_forward: output
/// (h, q) takes the taps u = (h + pad) mod stride + m * stride of input row (h + pad - u) / stride (and the
/// same along q), so the outputs q of one residue class read consecutive inputs; a tile of them accumulates
/// in registers over (o, u, v), reading a zero-padded copy of x (xp, convt_pad_elements(G)).
template <kernels::conv_geometry G>
inline void conv_transpose(const float* x, const float* w, float* y, float* xp) noexcept
{
    constexpr int Co = G.out_channels, Cy = G.in_channels, KH = G.kernel_h, KW = G.kernel_w, S = G.stride, P = G.pad;
    constexpr int oh = G.out_h(), ow = G.out_w(), MH = convt_margin(KH, S), MW = convt_margin(KW, S);
    constexpr int Hp = oh + 2 * MH, Wp = ow + 2 * MW, cnt = G.in_w / S, NB = row_tile(cnt);
    static_assert(G.batch == 1 && G.valid() && G.in_w % S == 0, "micro::conv_transpose: batch-1 geometry, width a multiple of the stride");
    pad_copy<Co, oh, ow, MH, MW>(x, xp);
    for (int c = 0; c < Cy; ++c)
        for (int h = 0; h < G.in_h; ++h) {
            const int rh = (h + P) % S;
            for (int rw = 0; rw < S; ++rw) {
                const int q0 = ((rw - P) % S + S) % S;  // first output column with (q + P) mod S == rw
                for (int t0 = 0; t0 < cnt; t0 += NB) {
                    float acc[NB];
#pragma GCC unroll 8
                    for (int t = 0; t < NB; ++t) acc[t] = 0.f;
                    for (int o = 0; o < Co; ++o)
                        for (int u = rh; u < KH; u += S) {
                            const float* xr = xp + (o * Hp + (h + P - u) / S + MH) * Wp + MW;
                            const float* wr = w + ((o * Cy + c) * KH + u) * KW;
                            for (int v = rw; v < KW; v += S) {
                                const float wv = wr[v];
                                const float* xt = xr + (q0 + S * t0 + P - v) / S;
#pragma GCC unroll 8
                                for (int t = 0; t < NB; ++t) acc[t] += wv * xt[t];
                            }
                        }
                    float* yr = y + (c * G.in_h + h) * G.in_w + q0 + S * t0;
#pragma GCC unroll 8
                    for (int t = 0; t < NB; ++t) yr[S * t] = acc[t];
                }
            }
        }
}

#if HANDEMO_MICRO_MVE
/// The convolutions of detail:: with their register tile in MVE vectors: the tile's NB <= 8 accumulators are
/// two float32x4_t, each tap adds the weight (a scalar) times the tile's inputs with one vfma per vector, and
/// the inputs of a strided tile come in one gather; a part of fewer than 4 lanes is predicated (vctp). The
/// loop order and the padded copies are those of detail::conv_forward and detail::conv_transpose, so the
/// results agree up to rounding (the Cortex-M55 firmware checks them against each other within 1e-6).
namespace mve {

/// Word offsets {0, S, 2 S, 3 S} of a tile part whose elements are S apart.
template <int S>
inline uint32x4_t lane_offsets() noexcept
{
    alignas(16) static constexpr std::uint32_t o[4] = {0, std::uint32_t(S), std::uint32_t(2 * S),
                                                       std::uint32_t(3 * S)};
    return vldrwq_u32(o);
}

/// x[S t] for t < L (L <= 4) in lanes 0..L-1, zeros above.
template <int S, int L>
inline float32x4_t load(const float* x, uint32x4_t off) noexcept
{
    if constexpr (S == 1 && L == 4) return vldrwq_f32(x);
    else if constexpr (S == 1) return vldrwq_z_f32(x, vctp32q(L));
    else if constexpr (L == 4) return vldrwq_gather_shifted_offset_f32(x, off);
    else return vldrwq_gather_shifted_offset_z_f32(x, off, vctp32q(L));
}

/// y[S t] = lane t of v for t < L (L <= 4).
template <int S, int L>
inline void store(float* y, float32x4_t v, uint32x4_t off) noexcept
{
    if constexpr (S == 1 && L == 4) vstrwq_f32(y, v);
    else if constexpr (S == 1) vstrwq_p_f32(y, v, vctp32q(L));
    else if constexpr (L == 4) vstrwq_scatter_shifted_offset_f32(y, off, v);
    else vstrwq_scatter_shifted_offset_p_f32(y, off, v, vctp32q(L));
}

/// NB <= 8 accumulators of one tile: lanes 0..L0-1 of a0 and 0..L1-1 of a1; the inputs of accumulator t are
/// S apart (SX) and its outputs SY apart.
template <int NB, int SX, int SY>
struct tile {
    static_assert(NB >= 1 && NB <= 8, "micro::mve::tile: 1 to 8 accumulators");
    static constexpr int L0 = NB < 4 ? NB : 4, L1 = NB - L0;
    float32x4_t a0 = vdupq_n_f32(0.f), a1 = vdupq_n_f32(0.f);

    /// acc[t] += wv x[SX t], t < NB
    void fma(float wv, const float* x, uint32x4_t off) noexcept
    {
        const float32x4_t x0 = load<SX, L0>(x, off);  // not inside the intrinsic: arm_mve.h's are macros
        a0 = vfmaq_n_f32(a0, x0, wv);
        if constexpr (L1 > 0) {
            const float32x4_t x1 = load<SX, L1>(x + 4 * SX, off);
            a1 = vfmaq_n_f32(a1, x1, wv);
        }
    }
    /// y[SY t] = acc[t], t < NB
    void store_to(float* y, uint32x4_t off) const noexcept
    {
        store<SY, L0>(y, a0, off);
        if constexpr (L1 > 0) store<SY, L1>(y + 4 * SY, a1, off);
    }
};

/// detail::conv_forward with MVE tiles (same arguments, same result up to rounding). Out of line: inlined into
/// generator::infer_padded, GCC 12 spills more and the inference takes 7% more instructions.
template <kernels::conv_geometry G, int LDW = G.in_channels * G.kernel_h * G.kernel_w>
[[gnu::noinline]] inline void conv_forward(const float* x, const float* w, float* y, float* xp) noexcept
{
    constexpr int Cin = G.in_channels, KH = G.kernel_h, KW = G.kernel_w, S = G.stride, P = G.pad;
    constexpr int Hp = G.in_h + 2 * P, Wp = G.in_w + 2 * P, oh = G.out_h(), ow = G.out_w(), NB = row_tile(ow);
    static_assert(G.batch == 1 && G.valid(), "micro::mve::conv_forward: batch-1 geometry");
    static_assert(LDW >= Cin * KH * KW, "micro::mve::conv_forward: weight stride shorter than a filter");
    pad_copy<Cin, G.in_h, G.in_w, P, P>(x, xp);
    const uint32x4_t off = lane_offsets<S>();
    for (int o = 0; o < G.out_channels; ++o) {
        const float* wo = w + o * LDW;
        for (int i = 0; i < oh; ++i)
            for (int j0 = 0; j0 < ow; j0 += NB) {
                tile<NB, S, 1> acc;
                const float* wk = wo;
                for (int c = 0; c < Cin; ++c)
#pragma GCC unroll 7
                    for (int u = 0; u < KH; ++u) {
                        const float* xr = xp + (c * Hp + i * S + u) * Wp + j0 * S;
#pragma GCC unroll 7
                        for (int v = 0; v < KW; ++v) acc.fma(*wk++, xr + v, off);
                    }
                acc.store_to(y + (o * oh + i) * ow + j0, off);
            }
    }
}

/// detail::conv_transpose with MVE tiles (same arguments, same result up to rounding): a tile's inputs are
/// consecutive, its outputs G.stride apart. When the stride divides the kernel (G's 4 x 4, stride 2), every
/// output takes kernel / stride taps along each axis whatever its residue class, so those loops have a
/// compile-time count and unroll; other geometries run detail::conv_transpose.
template <kernels::conv_geometry G>
[[gnu::noinline]] inline void conv_transpose(const float* x, const float* w, float* y, float* xp) noexcept
{
    constexpr int Co = G.out_channels, Cy = G.in_channels, KH = G.kernel_h, KW = G.kernel_w, S = G.stride, P = G.pad;
    constexpr int oh = G.out_h(), ow = G.out_w(), MH = convt_margin(KH, S), MW = convt_margin(KW, S);
    constexpr int Hp = oh + 2 * MH, Wp = ow + 2 * MW, cnt = G.in_w / S, NB = row_tile(cnt);
    static_assert(G.batch == 1 && G.valid() && G.in_w % S == 0,
                  "micro::mve::conv_transpose: batch-1 geometry, width a multiple of the stride");
    if constexpr (KH % S != 0 || KW % S != 0) {
        detail::conv_transpose<G>(x, w, y, xp);
    } else {
        pad_copy<Co, oh, ow, MH, MW>(x, xp);
        const uint32x4_t off = lane_offsets<S>();
        for (int c = 0; c < Cy; ++c)
            for (int h = 0; h < G.in_h; ++h) {
                const int rh = (h + P) % S;
                for (int rw = 0; rw < S; ++rw) {
                    const int q0 = ((rw - P) % S + S) % S;  // first output column with (q + P) mod S == rw
                    // tap (rh + S mu, rw + S mv) reads input row (h + P - rh) / S - mu and column
                    // (q0 + P - rw) / S - mv of the tile's first output: both divisions are exact
                    const float* xc = xp + ((h + P - rh) / S + MH) * Wp + MW + (q0 + P - rw) / S;
                    const float* wc = w + (c * KH + rh) * KW + rw;
                    for (int t0 = 0; t0 < cnt; t0 += NB) {
                        tile<NB, 1, S> acc;
                        for (int o = 0; o < Co; ++o) {
                            const float* xo = xc + o * Hp * Wp + t0;
                            const float* wo = wc + o * Cy * KH * KW;
#pragma GCC unroll 4
                            for (int mu = 0; mu < KH / S; ++mu)
#pragma GCC unroll 4
                                for (int mv = 0; mv < KW / S; ++mv)
                                    acc.fma(wo[S * mu * KW + S * mv], xo - mu * Wp - mv, off);
                        }
                        acc.store_to(y + (c * G.in_h + h) * G.in_w + q0 + S * t0, off);
                    }
                }
            }
    }
}

}  // namespace mve
#endif

/// y [co][h][w] += what G's first 7x7 convolution (padding 3) adds for a label tiled as C constant channels: per
/// output channel the label-weighted sum of the C label channels' 7 x 7 weights over the taps that land inside the
/// image. w: the first layer's weights [co][3 + C][7][7]. A 2-D running sum of the label-weighted kernel makes
/// every pixel's window sum four reads, so the C x 49 multiply-adds per output value of the tiled label become
/// C x 49 per output channel.
template <int co, int C, int h, int w>
inline void add_label_taps(const float* wt, const float* label, float* y) noexcept
{
    constexpr int T = 7, taps = T * T, in = 3 + C;
    for (int o = 0; o < co; ++o) {
        float s[T + 1][T + 1];  // s[u][v]: the label-weighted kernel summed over rows < u and columns < v
        for (int u = 0; u <= T; ++u) s[u][0] = 0.f;
        for (int v = 0; v <= T; ++v) s[0][v] = 0.f;
        for (int u = 0; u < T; ++u)
            for (int v = 0; v < T; ++v) {
                float k = 0.f;
                for (int c = 0; c < C; ++c) k += label[c] * wt[(o * in + 3 + c) * taps + u * T + v];
                s[u + 1][v + 1] = k + s[u][v + 1] + s[u + 1][v] - s[u][v];
            }
        for (int i = 0; i < h; ++i) {
            const int u0 = i < 3 ? 3 - i : 0, u1 = i + 3 < h ? T : h + 3 - i;  // taps u in [u0, u1) land inside
            for (int j = 0; j < w; ++j) {
                const int v0 = j < 3 ? 3 - j : 0, v1 = j + 3 < w ? T : w + 3 - j;
                y[(o * h + i) * w + j] += s[u1][v1] - s[u0][v1] - s[u1][v0] + s[u0][v0];
            }
        }
    }
}

}  // namespace detail

/// @brief In-place InstanceNorm (affine, biased variance, eps 1e-5) and optional ReLU over [ch, m], two-pass
/// statistics in float (the host's infer accumulates in double: the results agree within ~1e-6).
inline void instance_norm_relu(float* x, const float* gamma, const float* beta, int ch, int m, bool relu) noexcept
{
    for (int c = 0; c < ch; ++c) {
        float* v = x + std::size_t(c) * m;
        float s = 0.f;
        for (int i = 0; i < m; ++i) s += v[i];
        const float mu = s / float(m);
        float q = 0.f;
        for (int i = 0; i < m; ++i) q += (v[i] - mu) * (v[i] - mu);
        const float k = gamma[c] / std::sqrt(q / float(m) + 1e-5f), b = beta[c];
        for (int i = 0; i < m; ++i) {
            const float y = k * (v[i] - mu) + b;
            v[i] = (relu && y < 0.f) ? 0.f : y;
        }
    }
}

/// @brief G(x, c) at batch 1 with the weights of a generated model header.
/// @tparam Model a generator_model (the struct `handemo export --header` writes)
template <generator_model Model>
class generator {
public:
    using layout = generator_layout<Model::keyframes, Model::joints, Model::domains, Model::conv_dim, Model::res_blocks>;
    static constexpr std::size_t K = Model::keyframes, J = Model::joints, C = Model::domains, H = layout::H,
                                 W = layout::W, cd = Model::conv_dim, R = Model::res_blocks;
    static_assert(sizeof(Model::weights) / sizeof(Model::weights[0]) == layout::parameter_count,
                  "micro::generator: the model header's weight count does not match its configuration");

    /// @brief Activation memory of one inference: the padded input and output images and four buffers.
    struct workspace {
        alignas(16) float x[3 * H * W];
        alignas(16) float y[3 * H * W];
        alignas(16) float a[layout::big_elements];
        alignas(16) float b[layout::big_elements];
        alignas(16) float c[layout::big_elements];
        alignas(16) float d[layout::small_elements];
        alignas(16) float pad[layout::pad_elements];  // the zero-padded input of the convolution running
    };

    /// @brief G on the padded image: x [3, H, W], label [C] (one-hot target), out [3, H, W] written.
    /// x and out may be ws.x and ws.y.
    static void infer_padded(const float* x, const float* label, float* out, workspace& ws) noexcept
    {
        constexpr std::size_t HW = layout::HW;
        const float* p = Model::weights;
        float* a = ws.a;
        float* b = ws.b;
        float* c = ws.c;
        float* d = ws.d;
        auto norm = [&](float* v, std::size_t ch, std::size_t m, bool relu) {
            instance_norm_relu(v, p, p + ch, int(ch), int(m), relu);
            p += 2 * ch;
        };
        first_layer(x, label, p, b, ws.pad);
        norm(b, cd, HW, true);
        conv<1>(b, p, a, ws.pad);
        norm(a, 2 * cd, HW / 4, true);
        conv<2>(a, p, b, ws.pad);
        norm(b, 4 * cd, HW / 16, true);
        for (std::size_t r = 0; r < R; ++r) {
            conv<3>(b, p, c, ws.pad);
            norm(c, 4 * cd, HW / 16, true);
            conv<3>(c, p, d, ws.pad);
            norm(d, 4 * cd, HW / 16, false);
            for (std::size_t i = 0; i < layout::small_elements; ++i) b[i] += d[i];
        }
        conv<4>(b, p, a, ws.pad);
        norm(a, 2 * cd, HW / 4, true);
        conv<5>(a, p, c, ws.pad);
        norm(c, cd, HW, true);
        conv<6>(c, p, a, ws.pad);
        for (std::size_t i = 0; i < 3 * HW; ++i) out[i] = (Model::residual ? x[i] : 0.f) + std::tanh(a[i]);
    }

    /// @brief G on a motion image: in [3, K, J] (Eq. 3, in [-1, 1]), target domain index, out [3, K, J].
    /// Pads into ws.x (zeros at the bottom and right, as training does) and crops from ws.y.
    /// @return false, with `out` set to zeros and G not run, when `target` is not a domain index (< C): this
    /// path has no exceptions, so the caller checks.
    static bool infer(const float* in, std::size_t target, float* out, workspace& ws) noexcept
    {
        if (target >= C) {
            for (std::size_t i = 0; i < 3 * K * J; ++i) out[i] = 0.f;
            return false;
        }
        for (std::size_t ch = 0; ch < 3; ++ch)
            for (std::size_t i = 0; i < H; ++i)
                for (std::size_t j = 0; j < W; ++j)
                    ws.x[(ch * H + i) * W + j] = (i < K && j < J) ? in[(ch * K + i) * J + j] : 0.f;
        float label[C];
        for (std::size_t k = 0; k < C; ++k) label[k] = k == target ? 1.f : 0.f;
        infer_padded(ws.x, label, ws.y, ws);
        for (std::size_t ch = 0; ch < 3; ++ch)
            for (std::size_t i = 0; i < K; ++i)
                for (std::size_t j = 0; j < J; ++j) out[(ch * K + i) * J + j] = ws.y[(ch * H + i) * W + j];
        return true;
    }

private:
    /// G's first layer on the image x [3, H, W] and the label [C] into o, the weights at p (advanced past them):
    /// the 7 x 7 convolution of the image's 3 channels, then what the label tiled as C constant channels adds
    /// (detail::add_label_taps), instead of convolving 3 + C channels. The same sums up to rounding; for
    /// hand-micro a fifth of G's multiply-adds.
    static void first_layer(const float* x, const float* label, const float*& p, float* o, float* pad) noexcept
    {
        constexpr kernels::conv_geometry g = layout::geometry(0);
        constexpr kernels::conv_geometry gi{1, 3, g.in_h, g.in_w, g.out_channels, g.kernel_h, g.kernel_w, g.stride, g.pad};
        static_assert(g.in_channels == int(3 + C) && g.kernel_h == 7 && g.kernel_w == 7 && g.stride == 1 && g.pad == 3,
                      "micro::generator: the first layer is a 7x7 convolution, padding 3, on the image and the tiled label");
        constexpr int ldw = g.in_channels * 49;
#if HANDEMO_MICRO_MVE
        detail::mve::conv_forward<gi, ldw>(x, p, o, pad);
#else
        detail::conv_forward<gi, ldw>(x, p, o, pad);
#endif
        detail::add_label_taps<int(cd), int(C), int(H), int(W)>(p, label, o);
        p += g.w_size();
    }

    /// Layer gi of layout::geometry (a transposed convolution for up1 and up2) on `in` with the weights at p
    /// (advanced past them) into o; `pad` holds the padded input copy (layout::pad_elements).
    template <int gi>
    static void conv(const float* in, const float*& p, float* o, float* pad) noexcept
    {
        constexpr kernels::conv_geometry g = layout::geometry(gi);
#if HANDEMO_MICRO_MVE
        if constexpr (detail::transposed_layer(gi)) detail::mve::conv_transpose<g>(in, p, o, pad);
        else detail::mve::conv_forward<g>(in, p, o, pad);
#else
        if constexpr (detail::transposed_layer(gi)) detail::conv_transpose<g>(in, p, o, pad);
        else detail::conv_forward<g>(in, p, o, pad);
#endif
        p += g.w_size();
    }
};

}  // namespace handemo::micro
