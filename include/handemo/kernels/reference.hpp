// Reference convolution kernels: plain loops, any arithmetic T, no SIMD, no scratch. They define what
// handemo's fast kernels (kernels/conv.hpp) must compute and are the ground truth of their tests. The
// convolution is the one of PyTorch's Conv2d (cross-correlation, NCHW, zero padding), the building block
// of the StarGAN generator and discriminator of Chan et al. 2020 (Sec. 3.3, Fig. 3); ConvTranspose2d is
// its adjoint in the input. No paper equation is implemented here beyond the convolution itself.
#pragma once

#include <cstddef>

namespace handemo::kernels {

/// @brief Geometry of one 2-D convolution (NCHW, weight [out_channels, in_channels, kernel_h, kernel_w]).
struct conv_geometry {
    int batch, in_channels, in_h, in_w, out_channels, kernel_h, kernel_w, stride, pad;
    /// @brief Output height, PyTorch's floor((in_h + 2 pad - kernel_h) / stride) + 1.
    constexpr int out_h() const { return (in_h + 2 * pad - kernel_h) / stride + 1; }
    /// @brief Output width, PyTorch's floor((in_w + 2 pad - kernel_w) / stride) + 1.
    constexpr int out_w() const { return (in_w + 2 * pad - kernel_w) / stride + 1; }
    /// @brief Elements of x: batch * in_channels * in_h * in_w.
    constexpr std::size_t x_size() const { return std::size_t(batch) * in_channels * in_h * in_w; }
    /// @brief Elements of y: batch * out_channels * out_h * out_w.
    constexpr std::size_t y_size() const { return std::size_t(batch) * out_channels * out_h() * out_w(); }
    /// @brief Elements of w: out_channels * in_channels * kernel_h * kernel_w.
    constexpr std::size_t w_size() const
    {
        return std::size_t(out_channels) * in_channels * kernel_h * kernel_w;
    }
    /// @brief Multiply-adds of one forward pass (the same count for backward-data and backward-weight).
    constexpr double macs() const
    {
        return double(batch) * out_channels * out_h() * out_w() * in_channels * kernel_h * kernel_w;
    }
    /// @brief True when every field is positive (pad >= 0) and the output is at least 1x1.
    constexpr bool valid() const
    {
        return batch > 0 && in_channels > 0 && in_h > 0 && in_w > 0 && out_channels > 0 && kernel_h > 0 &&
               kernel_w > 0 && stride > 0 && pad >= 0 && in_h + 2 * pad >= kernel_h &&
               in_w + 2 * pad >= kernel_w;
    }
};

/// @brief The plain-loop kernels. Same contracts as the fast ones in handemo::kernels; `scratch` is
/// accepted for signature compatibility and never touched (conv2d_scratch_size is 0).
namespace reference {

/// @brief Scratch elements the reference kernels need: none.
template <class T>
std::size_t conv2d_scratch_size(const conv_geometry&) noexcept
{
    return 0;
}

/// @brief y = conv(x, w) + bias, PyTorch Conv2d.
/// y[n,o,i,j] = b[o] + sum_{c,u,v} x[n,c,i*s-p+u, j*s-p+v] w[o,c,u,v]   (x outside the image is 0)
/// @param x [batch, in_channels, in_h, in_w]  @param w [out_channels, in_channels, kh, kw]
/// @param bias_or_null [out_channels] or nullptr  @param y [batch, out_channels, out_h, out_w] (written)
template <class T>
void conv2d_forward(const conv_geometry& g, const T* x, const T* w, const T* bias_or_null, T* y, T*) noexcept
{
    const int oh = g.out_h(), ow = g.out_w();
    for (int n = 0; n < g.batch; ++n)
        for (int o = 0; o < g.out_channels; ++o)
            for (int i = 0; i < oh; ++i)
                for (int j = 0; j < ow; ++j) {
                    T acc = bias_or_null ? bias_or_null[o] : T(0);
                    for (int c = 0; c < g.in_channels; ++c)
                        for (int u = 0; u < g.kernel_h; ++u) {
                            const int ih = i * g.stride - g.pad + u;
                            if (ih < 0 || ih >= g.in_h) continue;
                            for (int v = 0; v < g.kernel_w; ++v) {
                                const int iw = j * g.stride - g.pad + v;
                                if (iw < 0 || iw >= g.in_w) continue;
                                acc += x[((std::size_t(n) * g.in_channels + c) * g.in_h + ih) * g.in_w + iw] *
                                       w[((std::size_t(o) * g.in_channels + c) * g.kernel_h + u) * g.kernel_w + v];
                            }
                        }
                    y[((std::size_t(n) * g.out_channels + o) * oh + i) * ow + j] = acc;
                }
}

/// @brief gx += dL/dx given gy = dL/dy.
/// dL/dx[n,c,h,w] = sum_{o,u,v : h = i*s-p+u, w = j*s-p+v} gy[n,o,i,j] w[o,c,u,v]
template <class T>
void conv2d_backward_data(const conv_geometry& g, const T* gy, const T* w, T* gx, T*) noexcept
{
    const int oh = g.out_h(), ow = g.out_w();
    for (int n = 0; n < g.batch; ++n)
        for (int o = 0; o < g.out_channels; ++o)
            for (int i = 0; i < oh; ++i)
                for (int j = 0; j < ow; ++j) {
                    const T d = gy[((std::size_t(n) * g.out_channels + o) * oh + i) * ow + j];
                    for (int c = 0; c < g.in_channels; ++c)
                        for (int u = 0; u < g.kernel_h; ++u) {
                            const int ih = i * g.stride - g.pad + u;
                            if (ih < 0 || ih >= g.in_h) continue;
                            for (int v = 0; v < g.kernel_w; ++v) {
                                const int iw = j * g.stride - g.pad + v;
                                if (iw < 0 || iw >= g.in_w) continue;
                                gx[((std::size_t(n) * g.in_channels + c) * g.in_h + ih) * g.in_w + iw] +=
                                    d * w[((std::size_t(o) * g.in_channels + c) * g.kernel_h + u) * g.kernel_w + v];
                            }
                        }
                }
}

/// @brief gw += dL/dw given x and gy.
/// dL/dw[o,c,u,v] = sum_{n,i,j} gy[n,o,i,j] x[n,c,i*s-p+u, j*s-p+v]
template <class T>
void conv2d_backward_weight(const conv_geometry& g, const T* x, const T* gy, T* gw, T*) noexcept
{
    const int oh = g.out_h(), ow = g.out_w();
    for (int o = 0; o < g.out_channels; ++o)
        for (int c = 0; c < g.in_channels; ++c)
            for (int u = 0; u < g.kernel_h; ++u)
                for (int v = 0; v < g.kernel_w; ++v) {
                    T acc = T(0);
                    for (int n = 0; n < g.batch; ++n)
                        for (int i = 0; i < oh; ++i) {
                            const int ih = i * g.stride - g.pad + u;
                            if (ih < 0 || ih >= g.in_h) continue;
                            for (int j = 0; j < ow; ++j) {
                                const int iw = j * g.stride - g.pad + v;
                                if (iw < 0 || iw >= g.in_w) continue;
                                acc += gy[((std::size_t(n) * g.out_channels + o) * oh + i) * ow + j] *
                                       x[((std::size_t(n) * g.in_channels + c) * g.in_h + ih) * g.in_w + iw];
                            }
                        }
                    gw[((std::size_t(o) * g.in_channels + c) * g.kernel_h + u) * g.kernel_w + v] += acc;
                }
}

/// @brief gb += dL/db:  dL/db[o] = sum_{n,i,j} gy[n,o,i,j]
template <class T>
void conv2d_backward_bias(const conv_geometry& g, const T* gy, T* gb) noexcept
{
    const std::size_t plane = std::size_t(g.out_h()) * g.out_w();
    for (int n = 0; n < g.batch; ++n)
        for (int o = 0; o < g.out_channels; ++o) {
            T acc = T(0);
            const T* p = gy + (std::size_t(n) * g.out_channels + o) * plane;
            for (std::size_t k = 0; k < plane; ++k) acc += p[k];
            gb[o] += acc;
        }
}

/// @brief y = ConvTranspose2d(x, w) (no bias). `g` is the geometry of the convolution this layer is the
/// transpose of: x is [batch, g.out_channels, g.out_h(), g.out_w()], w is PyTorch's ConvTranspose2d
/// weight [g.out_channels, g.in_channels, k, k] (= the conv weight), y is [batch, g.in_channels, g.in_h, g.in_w].
/// y = conv2d_backward_data(g, gy = x) starting from zero.
template <class T>
void conv_transpose2d_forward(const conv_geometry& g, const T* x, const T* w, T* y, T* scratch) noexcept
{
    const std::size_t ny = g.x_size();
    for (std::size_t k = 0; k < ny; ++k) y[k] = T(0);
    reference::conv2d_backward_data(g, x, w, y, scratch);
}

/// @brief gx += dL/dx of conv_transpose2d_forward: the forward convolution of gy (no bias).
/// dL/dx[n,o,i,j] = sum_{c,u,v} gy[n,c,i*s-p+u, j*s-p+v] w[o,c,u,v]
template <class T>
void conv_transpose2d_backward_data(const conv_geometry& g, const T* gy, const T* w, T* gx, T*) noexcept
{
    const int oh = g.out_h(), ow = g.out_w();
    for (int n = 0; n < g.batch; ++n)
        for (int o = 0; o < g.out_channels; ++o)
            for (int i = 0; i < oh; ++i)
                for (int j = 0; j < ow; ++j) {
                    T acc = T(0);
                    for (int c = 0; c < g.in_channels; ++c)
                        for (int u = 0; u < g.kernel_h; ++u) {
                            const int ih = i * g.stride - g.pad + u;
                            if (ih < 0 || ih >= g.in_h) continue;
                            for (int v = 0; v < g.kernel_w; ++v) {
                                const int iw = j * g.stride - g.pad + v;
                                if (iw < 0 || iw >= g.in_w) continue;
                                acc += gy[((std::size_t(n) * g.in_channels + c) * g.in_h + ih) * g.in_w + iw] *
                                       w[((std::size_t(o) * g.in_channels + c) * g.kernel_h + u) * g.kernel_w + v];
                            }
                        }
                    gx[((std::size_t(n) * g.out_channels + o) * oh + i) * ow + j] += acc;
                }
}

/// @brief gw += dL/dw of conv_transpose2d_forward: conv2d_backward_weight with the roles of x and gy
/// swapped. dL/dw[o,c,u,v] = sum_{n,i,j} x[n,o,i,j] gy[n,c,i*s-p+u, j*s-p+v]
template <class T>
void conv_transpose2d_backward_weight(const conv_geometry& g, const T* x, const T* gy, T* gw, T* scratch) noexcept
{
    reference::conv2d_backward_weight(g, gy, x, gw, scratch);
}

}  // namespace reference
}  // namespace handemo::kernels
