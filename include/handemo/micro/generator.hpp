// Inference-only StarGAN generator for small targets (a glove's Cortex-M7): G(x, c) of Chan, Irimia & Ho
// 2020 (Sec. 3.3, Fig. 3) exactly as stargan::generator::infer computes it, with no exceptions, no heap,
// no RTTI, no iostreams and no SIMD library: the weights are one flat constexpr float array in PyTorch
// state_dict order (written by `handemo export --header`, so they sit in flash), the activations live in a
// workspace whose size is a compile-time constant (static storage or the stack), and the convolutions are
// plain loops without bounds checks in the inner loop (the order of kernels/reference.hpp, whose
// conv_geometry they use). This file needs only <cmath>, <concepts>, <cstddef> and that header, so an
// arm-none-eabi build with -fno-exceptions -fno-rtti pulls in nothing else.
#pragma once

#include <cmath>
#include <concepts>
#include <cstddef>

#include <handemo/kernels/reference.hpp>

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
    /// Bytes of generator::workspace (padded input and output, three big buffers, one small one).
    static constexpr std::size_t workspace_bytes = sizeof(float) * (6 * HW + 3 * big_elements + small_elements);
    /// Convolution geometries: conv7, down1, down2, residual conv3, up1 and up2 (as the adjoint conv), conv7.
    static constexpr kernels::conv_geometry geometry(int i) noexcept
    {
        const int h = int(H), w = int(W), c = int(cd);
        switch (i) {
        case 0: return {1, int(in_ch), h, w, c, 7, 7, 1, 3};
        case 1: return {1, c, h, w, 2 * c, 4, 4, 2, 1};
        case 2: return {1, 2 * c, h / 2, w / 2, 4 * c, 4, 4, 2, 1};
        case 3: return {1, 4 * c, h / 4, w / 4, 4 * c, 3, 3, 1, 1};
        case 4: return {1, 2 * c, h / 2, w / 2, 4 * c, 4, 4, 2, 1};
        case 5: return {1, c, h, w, 2 * c, 4, 4, 2, 1};
        default: return {1, c, h, w, 3, 7, 7, 1, 3};
        }
    }
    /// Multiply-adds of one inference.
    static constexpr double macs() noexcept
    {
        return geometry(0).macs() + geometry(1).macs() + geometry(2).macs() + 2.0 * R * geometry(3).macs() +
               geometry(4).macs() + geometry(5).macs() + geometry(6).macs();
    }
};

namespace detail {

/// First and one-past-last output index i with 0 <= i*s - p + u < n (the taps of kernel offset u that read
/// inside the input), clamped to [0, out).
constexpr void tap_range(int n, int out, int s, int p, int u, int& i0, int& i1) noexcept
{
    i0 = p - u > 0 ? (p - u + s - 1) / s : 0;
    const int last = n - 1 + p - u;
    i1 = last < 0 ? 0 : (last / s + 1 < out ? last / s + 1 : out);
}

/// y = conv(x, w) at batch 1, no bias (PyTorch Conv2d): for each weight w[o,c,u,v] in memory order, add
/// w * (the shifted input window) to the output plane of o, over the outputs whose tap reads inside x only.
/// The sum over (c, u, v) runs in the order of kernels::reference::conv2d_forward; the inner loop has no
/// bounds checks (hand-micro on a Cortex-M7: 22.1 M instructions per inference against 40.3 M with the
/// reference kernels, measured under qemu -icount).
inline void conv_forward(const kernels::conv_geometry& g, const float* x, const float* w, float* y) noexcept
{
    const int oh = g.out_h(), ow = g.out_w(), s = g.stride, p = g.pad;
    for (int o = 0; o < g.out_channels; ++o) {
        float* yo = y + std::size_t(o) * oh * ow;
        for (int i = 0; i < oh * ow; ++i) yo[i] = 0.f;
        for (int c = 0; c < g.in_channels; ++c) {
            const float* xc = x + std::size_t(c) * g.in_h * g.in_w;
            for (int u = 0; u < g.kernel_h; ++u) {
                int i0, i1;
                tap_range(g.in_h, oh, s, p, u, i0, i1);
                for (int v = 0; v < g.kernel_w; ++v) {
                    const float wv = *w++;
                    int j0, j1;
                    tap_range(g.in_w, ow, s, p, v, j0, j1);
                    for (int i = i0; i < i1; ++i) {
                        const float* xr = xc + (i * s - p + u) * g.in_w + (j0 * s - p + v);
                        float* yr = yo + i * ow;
                        for (int j = j0; j < j1; ++j, xr += s) yr[j] += wv * *xr;
                    }
                }
            }
        }
    }
}

/// y = ConvTranspose2d(x, w) at batch 1, no bias; g is the convolution it is the adjoint of (as in
/// kernels::reference::conv_transpose2d_forward): x [g.out_channels, oh, ow], w [g.out_channels,
/// g.in_channels, k, k], y [g.in_channels, g.in_h, g.in_w]. Scatter-adds over (o, u, v), where the reference
/// goes over (o, i, j): the same terms, summed in another order (equal to rounding).
inline void conv_transpose(const kernels::conv_geometry& g, const float* x, const float* w, float* y) noexcept
{
    const int oh = g.out_h(), ow = g.out_w(), s = g.stride, p = g.pad;
    for (std::size_t i = 0; i < g.x_size(); ++i) y[i] = 0.f;
    for (int o = 0; o < g.out_channels; ++o) {
        const float* xo = x + std::size_t(o) * oh * ow;
        for (int c = 0; c < g.in_channels; ++c) {
            float* yc = y + std::size_t(c) * g.in_h * g.in_w;
            for (int u = 0; u < g.kernel_h; ++u) {
                int i0, i1;
                tap_range(g.in_h, oh, s, p, u, i0, i1);
                for (int v = 0; v < g.kernel_w; ++v) {
                    const float wv = *w++;
                    int j0, j1;
                    tap_range(g.in_w, ow, s, p, v, j0, j1);
                    for (int i = i0; i < i1; ++i) {
                        float* yr = yc + (i * s - p + u) * g.in_w + (j0 * s - p + v);
                        const float* xr = xo + i * ow;
                        for (int j = j0; j < j1; ++j, yr += s) *yr += wv * xr[j];
                    }
                }
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
        for (std::size_t i = 0; i < 3 * HW; ++i) a[i] = x[i];
        for (std::size_t k = 0; k < C; ++k)
            for (std::size_t i = 0; i < HW; ++i) a[(3 + k) * HW + i] = label[k];
        auto conv = [&](int gi, const float* in, float* o) {
            const kernels::conv_geometry g = layout::geometry(gi);
            detail::conv_forward(g, in, p, o);
            p += g.w_size();
        };
        auto convt = [&](int gi, const float* in, float* o) {
            const kernels::conv_geometry g = layout::geometry(gi);
            detail::conv_transpose(g, in, p, o);
            p += g.w_size();
        };
        auto norm = [&](float* v, std::size_t ch, std::size_t m, bool relu) {
            instance_norm_relu(v, p, p + ch, int(ch), int(m), relu);
            p += 2 * ch;
        };
        conv(0, a, b);
        norm(b, cd, HW, true);
        conv(1, b, a);
        norm(a, 2 * cd, HW / 4, true);
        conv(2, a, b);
        norm(b, 4 * cd, HW / 16, true);
        for (std::size_t r = 0; r < R; ++r) {
            conv(3, b, c);
            norm(c, 4 * cd, HW / 16, true);
            conv(3, c, d);
            norm(d, 4 * cd, HW / 16, false);
            for (std::size_t i = 0; i < layout::small_elements; ++i) b[i] += d[i];
        }
        convt(4, b, a);
        norm(a, 2 * cd, HW / 4, true);
        convt(5, a, c);
        norm(c, cd, HW, true);
        conv(6, c, a);
        for (std::size_t i = 0; i < 3 * HW; ++i) out[i] = (Model::residual ? x[i] : 0.f) + std::tanh(a[i]);
    }

    /// @brief G on a motion image: in [3, K, J] (Eq. 3, in [-1, 1]), target domain index, out [3, K, J].
    /// Pads into ws.x (zeros at the bottom and right, as training does) and crops from ws.y.
    static void infer(const float* in, std::size_t target, float* out, workspace& ws) noexcept
    {
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
    }
};

}  // namespace handemo::micro
