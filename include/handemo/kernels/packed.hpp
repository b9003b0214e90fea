// Convolutions whose weights are reordered once, for inference (the StarGAN generator of Chan et al. 2020,
// Sec. 3.3, run many times with the same weights: stargan::frozen_generator). packed_conv<T> copies the
// weights of one Conv2d or ConvTranspose2d into the panels of the weight-stationary kernel
// (kernels/detail/packed_conv.hpp) when the layer has enough output channels to fill its vectors, and keeps
// them as they are (and calls the kernels of kernels/conv.hpp) otherwise. The results are those of
// conv2d_forward / conv_transpose2d_forward up to the order of the floating-point sums. The taps are ordered
// kernel row first, so that an output row whose window reaches over the image's top or bottom edge skips the
// kernel rows that would only multiply the zero padding: at the generator's residual blocks (3 x 6 pixels, 3 x 3
// kernels) two of every nine multiply-adds.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>
#include <utility>
#include <vector>

#include <handemo/core/error.hpp>
#include <handemo/core/half.hpp>
#include <handemo/kernels/conv.hpp>
#include <handemo/kernels/detail/packed_conv.hpp>
#include <handemo/tensor/aligned.hpp>

namespace handemo::kernels {

/// @brief How packed_conv keeps its weights.
/// - native: as given (T).
/// - f16: every weight rounded to IEEE binary16 (to nearest, ties to even, as PyTorch's Tensor.half()), the
///   activations and the sums staying in T. Where the weight-stationary kernel can widen binary16 in one
///   instruction (float with AVX-512, AVX2 + F16C or aarch64 NEON: detail::ws_f16_native) the panels are
///   stored as binary16, half the bytes to stream per inference; elsewhere (and for the layers that keep
///   the kernels of kernels/conv.hpp) the rounded weights are stored as T. Either way the result is that of
///   the native storage of the rounded weights, bit for bit (tests/kernels/packed_test.cpp). Weights whose
///   magnitude rounds above 65504 (binary16's largest) are refused.
enum class weight_storage { native, f16 };

/// @brief "native" or "f16".
inline const char* weight_storage_name(weight_storage s) noexcept { return s == weight_storage::f16 ? "f16" : "native"; }

/// @brief The n weights at w each rounded to binary16 and back (what weight_storage::f16 computes with).
/// @throws value_error naming the index of a weight that is not finite or rounds beyond binary16's range.
template <class T>
std::vector<T> binary16_rounded(const T* w, std::size_t n)
{
    std::vector<T> rounded(n);
    for (std::size_t i = 0; i < n; ++i) {
        const float r = half_to_float(float_to_half(static_cast<float>(w[i])));
        if (!std::isfinite(w[i]) || !std::isfinite(r))
            throw value_error("packed_conv: weight " + std::to_string(i) + " is " + std::to_string(double(w[i])) +
                              ", which binary16 storage (weight_storage::f16) cannot hold (largest 65504)");
        rounded[i] = static_cast<T>(r);
    }
    return rounded;
}

/// @brief One convolution with its weights packed for repeated forward passes.
/// A snapshot: later changes to the weights it was built from do not reach it (build it again).
template <class T>
class packed_conv {
public:
    packed_conv() = default;

    /// @brief Conv2d with geometry g and weights w [out_channels, in_channels, kernel_h, kernel_w].
    /// @throws value_error when g is not valid() (naming its fields), or with weight_storage::f16 when a
    /// weight is not finite or rounds beyond binary16's range (naming its index).
    static packed_conv conv2d(const conv_geometry& g, const T* w, weight_storage ws = weight_storage::native)
    {
        return packed_conv(g, w, false, ws);
    }
    /// @brief ConvTranspose2d as in conv_transpose2d_forward: g is the convolution it is the adjoint of,
    /// w [g.out_channels, g.in_channels, k, k] (PyTorch's [in, out, k, k] of the transposed layer).
    static packed_conv conv_transpose2d(const conv_geometry& g, const T* w, weight_storage ws = weight_storage::native)
    {
        return packed_conv(g, w, true, ws);
    }

    /// @brief Elements of T that forward() needs as scratch (any alignment).
    std::size_t scratch_size() const noexcept { return scratch_; }
    /// @brief The geometry given at construction.
    const conv_geometry& geometry() const noexcept { return g_; }
    /// @brief Whether the weight-stationary kernel runs (false: the kernels of kernels/conv.hpp).
    bool weight_stationary() const noexcept { return ws_; }
    /// @brief The storage asked for at construction.
    weight_storage storage() const noexcept { return storage_; }
    /// @brief Bytes of the stored weights (packed panels with their zero padding, or the plain copy): what
    /// one forward pass streams.
    std::size_t weight_bytes() const noexcept { return w_.size() * sizeof(T) + wh_.size() * sizeof(std::uint16_t); }
    /// @brief Multiply-adds a forward pass on one image performs: the geometry's (conv_geometry::macs() of a batch
    /// of 1) for the kernels of kernels/conv.hpp; on the weight-stationary path, every output row's taps but the
    /// kernel rows that read only the zero padding above or below the image (fewer than the geometry's at the
    /// image's top and bottom edges).
    double macs_per_image() const noexcept
    {
        if (!ws_) return g_.macs() / double(g_.batch);
        double m = 0;
        for (const auto& ph : phases_)
            for (int r = 0; r < ph.job.rows; ++r)
                m += double(row_k_[ph.row_k_off + 2 * std::size_t(r) + 1] - row_k_[ph.row_k_off + 2 * std::size_t(r)]) * ph.job.cols * ph.job.co;
        return m;
    }
    /// @brief Multiply-adds forward() on `images` images performs: macs_per_image() each, but where a stride-1 layer
    /// with few output channels takes its groups of images one per lane (kernels::conv2d_performed_macs()), which
    /// leave out the kernel rows over the zero padding too.
    double macs(std::size_t images) const noexcept
    {
        if (!batched_fallback(images)) return macs_per_image() * double(images);
        conv_geometry g = g_;
        g.batch = int(images);
        return conv2d_performed_macs<T>(g, conv_pass::forward);
    }

    /// @brief conv2d: y = conv(x, w) + bias, x [batch, in_channels, in_h, in_w], y [batch, out_channels,
    /// out_h, out_w]. conv_transpose2d: y = ConvTranspose2d(x, w) + bias, x [batch, g.out_channels,
    /// g.out_h(), g.out_w()], y [batch, g.in_channels, g.in_h, g.in_w]. bias_or_null: one value per output
    /// channel, or nullptr. y is overwritten.
    void forward(const T* x, const T* bias_or_null, T* y, T* scratch) const noexcept
    {
        forward(x, bias_or_null, y, scratch, std::size_t(g_.batch));
    }

    /// @brief forward() on `images` images instead of the geometry's batch (any count, more or fewer): x
    /// [images, ...], y [images, ...]. The images are computed one after the other with the same scratch
    /// (scratch_size() does not depend on the count), so image n of a batch gets the bits a call on that
    /// image alone gets.
    void forward(const T* x, const T* bias_or_null, T* y, T* scratch, std::size_t images) const noexcept
    {
        if (!ws_) return fallback(x, bias_or_null, y, scratch, int(images));
        T* acc = align_up(scratch);
        T* xp = acc + acc_elements_;
        const std::size_t x_per = std::size_t(in_c_) * in_h_ * in_w_, y_per = std::size_t(out_c_) * out_h_ * out_w_;
        const std::size_t HWp = std::size_t(Hp_) * Wp_;
        std::memset(xp, 0, std::size_t(in_c_) * HWp * sizeof(T));
        for (std::size_t n = 0; n < images; ++n) {
            const T* xn = x + n * x_per;
            detail::copy_into_padded(xp, Hp_, Wp_, pad_h_, pad_w_, xn, in_c_, in_h_, in_w_);
            for (const auto& ph : phases_) {
                detail::ws_job j = ph.job;
                j.koff = koff_.data() + ph.koff_off;
                j.row_k = row_k_.data() + ph.row_k_off;
                // the first image streams the weights and prefetches them; the next ones find them in cache, where
                // the prefetches only cost time
                j.prefetch = n == 0;
                if constexpr (detail::ws_f16_native<T>) {
                    if (wh_.size()) {
                        detail::ws_run(j, wh_.data() + ph.w_off, xp + ph.src0, bias_or_null, y + n * y_per, acc);
                        continue;
                    }
                }
                detail::ws_run(j, w_.data() + ph.w_off, xp + ph.src0, bias_or_null, y + n * y_per, acc);
            }
        }
    }

private:
    struct phase {
        detail::ws_job job;      // koff filled in at run time
        std::size_t w_off = 0;   // first element of this phase's panels in w_
        std::size_t koff_off = 0;
        std::size_t row_k_off = 0; // first of the job's rows' tap ranges in row_k_
        std::ptrdiff_t src0 = 0; // offset of the phase's first source pixel in the padded input
    };

    packed_conv(const conv_geometry& g, const T* w, bool transposed, weight_storage storage)
        : g_(g), transposed_(transposed), storage_(storage)
    {
        if (!g.valid())
            throw value_error("packed_conv: invalid geometry (batch " + std::to_string(g.batch) + ", " +
                              std::to_string(g.in_channels) + "x" + std::to_string(g.in_h) + "x" + std::to_string(g.in_w) +
                              " -> " + std::to_string(g.out_channels) + ", kernel " + std::to_string(g.kernel_h) + "x" +
                              std::to_string(g.kernel_w) + ", stride " + std::to_string(g.stride) + ", pad " +
                              std::to_string(g.pad) + ")");
        const int k_h = g.kernel_h, k_w = g.kernel_w, s = g.stride;
        // the sub-pixel split of a transposed conv needs every phase to have a tap
        const bool phases_ok = !transposed || (k_h >= s && k_w >= s);
        const int co = transposed ? g.in_channels : g.out_channels;
        ws_ = detail::fast_type<T> && phases_ok && co >= detail::simd_lanes<T>;
        std::vector<T> rounded;
        if (storage == weight_storage::f16) {
            rounded = binary16_rounded(w, g.w_size());
            w = rounded.data();
        }
        if (!ws_) {
            w_ = aligned_buffer<T>(g.w_size());
            std::memcpy(w_.data(), w, g.w_size() * sizeof(T));
            scratch_ = conv2d_scratch_size<T>(g);
            return;
        }
        if (!transposed) build_conv(w);
        else build_transposed(w);
        if constexpr (detail::ws_f16_native<T>) {
            if (storage == weight_storage::f16) {  // exact: every panel value is a binary16 value already
                wh_ = aligned_buffer<std::uint16_t>(w_.size());
                for (std::size_t i = 0; i < w_.size(); ++i) wh_.data()[i] = float_to_half(w_.data()[i]);
                w_ = aligned_buffer<T>();
            }
        }
        scratch_ = acc_elements_ + std::size_t(in_c_) * Hp_ * Wp_ + tensor_alignment / sizeof(T);
    }

    void build_conv(const T* w)
    {
        const conv_geometry& g = g_;
        in_c_ = g.in_channels, in_h_ = g.in_h, in_w_ = g.in_w;
        out_c_ = g.out_channels, out_h_ = g.out_h(), out_w_ = g.out_w();
        pad_h_ = pad_w_ = g.pad;
        Hp_ = g.in_h + 2 * g.pad, Wp_ = g.in_w + 2 * g.pad;
        const int C = g.in_channels, kh = g.kernel_h, kw = g.kernel_w, K = C * kh * kw;
        // k = (u, c, v), kernel row first: the taps of kernel row u are one run of C * kw, so the rows of the
        // kernel that read the padding above or below the image are a run at either end of k (row_k_)
        koff_.resize(std::size_t(K));
        detail::padded_window_offsets_row_first(C, kh, kw, Hp_, Wp_, koff_.data());
        w_ = aligned_buffer<T>(detail::ws_packed_elements<T>(out_c_, K));
        detail::ws_pack<T>(out_c_, K, w_.data(), [&](int o, int k) {
            const int u = k / (C * kw), c = (k / kw) % C, v = k % kw;
            return w[((std::ptrdiff_t(o) * C + c) * kh + u) * kw + v];
        });
        phase ph;
        ph.job = {K, out_c_, out_h_, out_w_, g.stride, nullptr, std::ptrdiff_t(g.stride) * Wp_,
                  std::ptrdiff_t(out_h_) * out_w_, 0, out_w_, 1};
        // output row r reads padded rows r * stride + u: the image for u in [pad - r s, pad + in_h - r s)
        ph.row_k_off = row_k_.size();
        for (int r = 0; r < out_h_; ++r) {
            const auto [u0, u1] = detail::window_rows(r, g.stride, g.pad, kh, g.in_h);
            row_k_.push_back(u0 * C * kw);
            row_k_.push_back(u1 * C * kw);
        }
        phases_.push_back(ph);
        acc_elements_ = detail::ws_acc_elements<T>(out_c_, out_h_, out_w_);
    }

    // y[c][h][w] = sum_{o,i,j,u,v: h = i*s - p + u, w = j*s - p + v} x[o][i][j] w[o][c][u][v]. Outputs with
    // (h + p) mod s = rh use the taps u = rh + t*s (t = 0, 1, ...) and i = m - t with m = (h + p - rh) / s:
    // per residue pair (rh, rw), a stride-1 convolution of x (zero-padded) with a (taps_h x taps_w) kernel.
    void build_transposed(const T* w)
    {
        const conv_geometry& g = g_;
        const int s = g.stride, p = g.pad, kh = g.kernel_h, kw = g.kernel_w;
        in_c_ = g.out_channels, in_h_ = g.out_h(), in_w_ = g.out_w();  // x of the transposed conv
        out_c_ = g.in_channels, out_h_ = g.in_h, out_w_ = g.in_w;       // y of the transposed conv
        auto ceil_div = [](int a, int b) { return a >= 0 ? (a + b - 1) / b : -((-a) / b); };
        struct range {
            int r, taps, lo, hi;  // residue, taps, first and last m (hi < lo: no output pixel)
        };
        auto ranges = [&](int k, int out) {
            std::vector<range> v;
            for (int r = 0; r < s; ++r) {
                const int taps = (k - r + s - 1) / s;
                const int lo = std::max(0, ceil_div(p - r, s)), hi = (out - 1 + p - r) >= 0 ? (out - 1 + p - r) / s : -1;
                v.push_back({r, taps, lo, hi});
            }
            return v;
        };
        const auto rh = ranges(kh, out_h_), rw = ranges(kw, out_w_);
        auto pads = [](const std::vector<range>& v, int in) {
            int lo = 0, hi = 0;
            for (const auto& r : v)
                if (r.hi >= r.lo) lo = std::max(lo, r.taps - 1 - r.lo), hi = std::max(hi, r.hi - (in - 1));
            return std::pair{lo, hi};
        };
        const auto [plh, phh] = pads(rh, in_h_);
        const auto [plw, phw] = pads(rw, in_w_);
        pad_h_ = plh, pad_w_ = plw;
        Hp_ = in_h_ + plh + phh, Wp_ = in_w_ + plw + phw;
        std::size_t wtotal = 0;
        for (const auto& a : rh)
            for (const auto& b : rw)
                if (a.hi >= a.lo && b.hi >= b.lo) wtotal += detail::ws_packed_elements<T>(out_c_, in_c_ * a.taps * b.taps);
        w_ = aligned_buffer<T>(wtotal);
        std::size_t woff = 0;
        for (const auto& a : rh)
            for (const auto& b : rw) {
                if (a.hi < a.lo || b.hi < b.lo) continue;
                const int K = in_c_ * a.taps * b.taps;
                phase ph;
                ph.koff_off = koff_.size();
                // k = (t, o, q), tap row first, as in build_conv()
                for (int t = 0; t < a.taps; ++t)
                    for (int o = 0; o < in_c_; ++o)
                        for (int q = 0; q < b.taps; ++q) koff_.push_back((o * Hp_ + plh - t) * Wp_ + plw - q);
                detail::ws_pack<T>(out_c_, K, w_.data() + woff, [&](int c, int k) {
                    const int t = k / (in_c_ * b.taps), o = (k / b.taps) % in_c_, q = k % b.taps;
                    const int u = a.r + t * s, v = b.r + q * s;
                    return w[((std::ptrdiff_t(o) * out_c_ + c) * kh + u) * kw + v];
                });
                ph.w_off = woff;
                woff += detail::ws_packed_elements<T>(out_c_, K);
                const int rows = a.hi - a.lo + 1, cols = b.hi - b.lo + 1;
                const int h0 = a.lo * s + a.r - p, w0 = b.lo * s + b.r - p;
                ph.src0 = std::ptrdiff_t(a.lo) * Wp_ + b.lo;
                ph.job = {K, out_c_, rows, cols, 1, nullptr, Wp_, std::ptrdiff_t(out_h_) * out_w_,
                          std::ptrdiff_t(h0) * out_w_ + w0, std::ptrdiff_t(s) * out_w_, s};
                // row r of the phase (m = a.lo + r) reads x's row m - t: the image for t in [m - in_h + 1, m]
                ph.row_k_off = row_k_.size();
                for (int r = 0; r < rows; ++r) {
                    const int m = a.lo + r;
                    const int t0 = std::clamp(m - in_h_ + 1, 0, a.taps), t1 = std::clamp(m + 1, t0, a.taps);
                    row_k_.push_back(t0 * in_c_ * b.taps);
                    row_k_.push_back(t1 * in_c_ * b.taps);
                }
                phases_.push_back(ph);
                acc_elements_ = std::max(acc_elements_, detail::ws_acc_elements<T>(out_c_, rows, cols));
            }
    }

    // Whether fallback() runs `images` images in one call (conv2d_forward's stride-1 path for few output channels,
    // whose groups of images get the bits of one image at a time).
    bool batched_fallback(std::size_t images) const noexcept
    {
        if constexpr (detail::fast_type<T>) {
            conv_geometry g = g_;
            g.batch = int(std::min<std::size_t>(images, 1u << 20));
            return !ws_ && !transposed_ && images > 1 && detail::forward_takes_stride1_few<T>(g) &&
                   detail::stride1_images_fits<T>(g);
        }
        return false;
    }

    // One image at a time (a batch-1 geometry), as the weight-stationary path: the bits of an image do not depend
    // on the images computed with it. A stride-1 layer with few output channels (the generator's last) takes the
    // whole batch at once: its groups of images one per lane (detail::forward_stride1_images) get the bits of the
    // image-by-image path.
    void fallback(const T* x, const T* bias, T* y, T* scratch, int images) const noexcept
    {
        conv_geometry g = g_;
        if (batched_fallback(std::size_t(images))) {
            g.batch = images;
            return conv2d_forward<T>(g, x, w_.data(), bias, y, scratch);
        }
        g.batch = 1;
        const std::size_t in = g.x_size(), out = g.y_size();
        for (int n = 0; n < images; ++n) {
            if (!transposed_) {
                conv2d_forward<T>(g, x + n * in, w_.data(), bias, y + n * out, scratch);
                continue;
            }
            T* yn = y + n * in;  // the transposed conv maps g's y-sized input to its x-sized output
            conv_transpose2d_forward<T>(g, x + n * out, w_.data(), yn, scratch);
            if (bias) {
                const std::size_t hw = std::size_t(g.in_h) * g.in_w;
                for (int c = 0; c < g.in_channels; ++c)
                    for (std::size_t i = 0; i < hw; ++i) yn[std::size_t(c) * hw + i] += bias[c];
            }
        }
    }


    conv_geometry g_{};
    bool transposed_ = false, ws_ = false;
    weight_storage storage_ = weight_storage::native;
    aligned_buffer<T> w_;
    aligned_buffer<std::uint16_t> wh_;  // binary16 panels (weight_storage::f16 where ws_f16_native), else empty
    std::vector<int> koff_;
    std::vector<int> row_k_;  // per job row: the range of k whose taps can read the image (ws_job::row_k)
    std::vector<phase> phases_;
    int in_c_ = 0, in_h_ = 0, in_w_ = 0, out_c_ = 0, out_h_ = 0, out_w_ = 0, pad_h_ = 0, pad_w_ = 0, Hp_ = 0, Wp_ = 0;
    std::size_t acc_elements_ = 0, scratch_ = 0;
};

}  // namespace handemo::kernels
