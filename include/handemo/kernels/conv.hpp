// The convolution kernels of handemo's StarGAN (Chan et al. 2020, Sec. 3.3 and Fig. 3: the generator's
// 7x7 / 4x4-stride-2 / 3x3 residual / transposed 4x4 layers and the PatchGAN discriminator): forward,
// backward-data, backward-weight and bias gradient of PyTorch's Conv2d (cross-correlation, NCHW, zero
// padding), and ConvTranspose2d as the adjoint of Conv2d. The kernels are noexcept, single-threaded,
// allocate nothing (the caller provides `scratch` of conv2d_scratch_size<T>(g) elements) and exist for
// T = float and double. Semantics: forward functions overwrite their output (y =), backward functions
// accumulate into theirs (g +=). The plain-loop versions in kernels::reference define the results.
#pragma once

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <type_traits>
#include <utility>

#include <handemo/kernels/detail/conv_simd.hpp>
#include <handemo/kernels/detail/packed_conv.hpp>
#include <handemo/kernels/reference.hpp>

namespace handemo::kernels {

/// @brief The two uses of a convolution's weights that can take them packed ahead of the call.
enum class conv_panels {
    forward,        ///< conv2d_forward (and conv_transpose2d_backward_data, the same pass)
    backward_data,  ///< conv2d_backward_data
};

/// @brief A pass of a convolution (conv2d_performed_macs()).
enum class conv_pass {
    forward,          ///< conv2d_forward, conv_transpose2d_backward_data
    backward_data,    ///< conv2d_backward_data, conv_transpose2d_forward
    backward_weight,  ///< conv2d_backward_weight, conv_transpose2d_backward_weight (its geometry g)
};

namespace detail {
/// performed_macs_count's state: whether one is alive, and its count.
inline std::atomic<bool> macs_counting{false};
inline std::atomic<std::uint64_t> macs_counted{0};

/// float and double take the xsimd path when xsimd has an instruction set for the target; any other T,
/// or a target without SIMD, the reference loops.
template <class T>
inline constexpr bool fast_type = has_simd && (std::is_same_v<T, float> || std::is_same_v<T, double>);

/// Fewest output pixels per image for forward_ws: an image of a few pixels reuses each loaded weight too little
/// (the discriminator's 1 x 3 layer ran at 91 against 117 GFLOP/s on the weight-stationary kernel).
inline constexpr int ws_min_pixels = 16;

/// Whether a forward pass of geometry g takes the weight-stationary kernel with its weights packed at the call
/// (detail::forward_ws, kernels/detail/packed_conv.hpp): where its panels fill the vectors (at least one vector of
/// output channels), its images have ws_min_pixels, and conv_simd.hpp would take its packed or stride-1 path,
/// whose sums it gives bit for bit. The dot path (few pixels) sums in another order and keeps its layers.
/// Measured per layer in bench_conv (`cd32/...` rows: the embedded G's residual conv at batch 16 from 65% to 80%
/// of the FMA peak, its first conv and first down-sampling conv at 0.66x the time).
template <class T>
inline bool use_forward_ws(const conv_geometry& g) noexcept
{
    return fast_type<T> && g.out_channels >= simd_lanes<T> && g.out_h() * g.out_w() >= ws_min_pixels && !use_dot_forward<T>(g);
}

/// Whether a stride-1 backward-data of geometry g runs as the forward pass of its flipped kernel on forward_ws.
template <class T>
inline bool backward_data_ws(const conv_geometry& g) noexcept
{
    return backward_data_by_forward(g) && use_forward_ws<T>(flipped_geometry(g));
}

/// Whether a backward-weight pass of geometry g takes backward_weight_ws (kernels/detail/packed_conv.hpp, the same
/// bits as conv_simd.hpp's packed path): where its tiles fill the vectors (at least one vector of output channels)
/// and conv_simd.hpp would take its packed path (the stride-1 path for few output channels sums in another order).
template <class T>
inline bool use_backward_weight_ws(const conv_geometry& g) noexcept
{
    return fast_type<T> && g.out_channels >= simd_lanes<T> && !use_stride1_backward_weight<T>(g);
}

/// Multiply-adds a pass of geometry g performs (conv2d_performed_macs()).
template <class T>
inline double performed_macs(const conv_geometry& g, conv_pass pass) noexcept
{
    if constexpr (fast_type<T>) {
        if (pass == conv_pass::forward) return use_forward_ws<T>(g) ? forward_ws_macs(g) : forward_macs<T>(g);
        if (pass == conv_pass::backward_data && backward_data_by_forward(g))
            return backward_data_ws<T>(g) ? forward_ws_macs(flipped_geometry(g)) : forward_macs<T>(flipped_geometry(g));
        if (pass == conv_pass::backward_weight && use_backward_weight_ws<T>(g)) return backward_weight_ws_macs<T>(g);
    }
    return g.macs();
}

/// Adds the pass's multiply-adds to the count of a live performed_macs_count.
template <class T>
inline void count_macs(const conv_geometry& g, conv_pass pass) noexcept
{
    if (macs_counting.load(std::memory_order_relaxed))
        macs_counted.fetch_add(std::uint64_t(performed_macs<T>(g, pass)), std::memory_order_relaxed);
}

/// gw += dL/dw: backward_weight_ws where use_backward_weight_ws, else conv_simd.hpp's backward_weight.
template <class T>
inline void backward_weight_any(const conv_geometry& g, const T* x, const T* gy, T* gw, T* scratch) noexcept
{
    count_macs<T>(g, conv_pass::backward_weight);
    if (use_backward_weight_ws<T>(g)) return backward_weight_ws<T>(g, x, gy, gw, scratch);
    backward_weight(g, x, gy, gw, scratch);
}

/// Packs w [out_channels, in_channels, kh, kw] of geometry g for `use` into dst: the rows for the forward pass, the
/// flipped, channel-swapped kernel for the stride-1 backward-data.
template <class T>
inline void pack_panels(const conv_geometry& g, conv_panels use, const T* w, T* dst) noexcept
{
    if (use == conv_panels::forward)
        ws_pack_rows<T>(g.out_channels, g.in_channels * g.kernel_h * g.kernel_w, w, dst);
    else
        ws_pack_flipped<T>(g.out_channels, g.in_channels, g.kernel_h * g.kernel_w, w, dst);
}

/// forward_ws's pack argument for the weights w of geometry g and `use`: `panels` when given (packed ahead by
/// pack_panels), else w packed into the scratch's panels at the call.
template <class T>
inline auto panels_or_pack(const conv_geometry& g, conv_panels use, const T* w, const T* panels) noexcept
{
    return [g, use, w, panels](T* dst) -> const T* {
        if (panels) return panels;
        pack_panels<T>(g, use, w, dst);
        return dst;
    };
}

/// y (+)= conv(x, w) + bias: forward_ws where use_forward_ws (its weights `panels` when given, else packed at the
/// call), else conv_simd.hpp's forward.
template <class T>
inline void forward_any(const conv_geometry& g, const T* x, const T* w, const T* bias, T* y, T* scratch,
                        bool accumulate_out, const T* panels = nullptr) noexcept
{
    count_macs<T>(g, conv_pass::forward);
    if (use_forward_ws<T>(g))
        return forward_ws<T>(g, x, panels_or_pack<T>(g, conv_panels::forward, w, panels), bias, y, scratch, accumulate_out);
    forward(g, x, w, bias, y, scratch, accumulate_out);
}

/// gx += dL/dx: a stride-1 backward-data whose flipped forward pass takes forward_ws packs the flipped kernel
/// straight into its panels (or takes `panels` when given); everything else is conv_simd.hpp's backward_data.
template <class T>
inline void backward_data_any(const conv_geometry& g, const T* gy, const T* w, T* gx, T* scratch,
                              const T* panels = nullptr) noexcept
{
    count_macs<T>(g, conv_pass::backward_data);
    if (backward_data_ws<T>(g))
        return forward_ws<T>(flipped_geometry(g), gy, panels_or_pack<T>(g, conv_panels::backward_data, w, panels),
                             static_cast<const T*>(nullptr), gx, scratch, true);
    backward_data(g, gy, w, gx, scratch);
}
}  // namespace detail

/// @brief Multiply-adds a pass of geometry g performs on T's kernels: g.macs(), less the products with the zero
/// padding that the path it takes leaves out. The weight-stationary paths (forward and stride-1 backward-data of
/// at least one vector of output channels, and the weight gradients) skip the kernel rows an output row places over
/// the padding above or below the image, with the bits of the full sum, and so does the stride-1 forward pass of a
/// layer with few output channels on its groups of images one per lane; the other paths compute them. A stride-1
/// backward-data that runs as the forward pass of its flipped kernel over the padded output gradient counts that
/// pass's products (g.macs() where the padding keeps the size, as in every StarGAN layer). Idle vector lanes and
/// columns computed and dropped are not counted. What a benchmark reports as the FLOPs a step performs
/// (performed_macs_count).
template <class T>
double conv2d_performed_macs(const conv_geometry& g, conv_pass pass) noexcept
{
    return detail::performed_macs<T>(g, pass);
}

/// @brief While one is alive, every convolution of this file (forward, backward-data, backward-weight, plain and
/// transposed, in any thread) adds the multiply-adds it performs (conv2d_performed_macs()) to its count: how a
/// benchmark counts the FLOPs a training step performs. One at a time; the cost while none is alive is one relaxed
/// atomic load per call.
class performed_macs_count {
public:
    performed_macs_count() noexcept
    {
        detail::macs_counted.store(0);
        detail::macs_counting.store(true);
    }
    ~performed_macs_count() { detail::macs_counting.store(false); }
    performed_macs_count(const performed_macs_count&) = delete;
    performed_macs_count& operator=(const performed_macs_count&) = delete;
    /// Multiply-adds counted since construction.
    std::uint64_t macs() const noexcept { return detail::macs_counted.load(); }
};

/// @brief Elements of the panels conv2d_pack_panels writes for geometry g and `use`, or 0 when that call of
/// geometry g does not take packed panels (it then reads w as it is). Training packs each weight once per tape
/// instead of at every call: the same panels and kernels, so the same bits.
template <class T>
std::size_t conv2d_panel_elements(const conv_geometry& g, conv_panels use) noexcept
{
    if constexpr (detail::fast_type<T>) {
        if (use == conv_panels::forward)
            return detail::use_forward_ws<T>(g) ? detail::ws_packed_elements<T>(g.out_channels, g.in_channels * g.kernel_h * g.kernel_w)
                                                : 0;
        return detail::backward_data_ws<T>(g)
                   ? detail::ws_packed_elements<T>(g.in_channels, g.out_channels * g.kernel_h * g.kernel_w)
                   : 0;
    } else {
        return 0;
    }
}

/// @brief Packs w [out_channels, in_channels, kh, kw] for `use` into `panels` (conv2d_panel_elements(g, use)
/// elements, 64-byte aligned); only where that count is not 0.
template <class T>
void conv2d_pack_panels(const conv_geometry& g, conv_panels use, const T* w, T* panels) noexcept
{
    if constexpr (detail::fast_type<T>) detail::pack_panels<T>(g, use, w, panels);
}

/// @brief Elements of T the kernels of this file need as `scratch` for geometry g (the maximum over all
/// of conv2d_forward / backward_data / backward_weight and the conv_transpose2d functions). It does not
/// depend on g.batch, so one scratch sized for a batch serves every chunk of that batch.
template <class T>
std::size_t conv2d_scratch_size(const conv_geometry& g) noexcept
{
    if constexpr (detail::fast_type<T>)
        return std::max({detail::scratch_elements<T>(g), detail::forward_ws_scratch_elements<T>(g),
                         detail::use_backward_weight_ws<T>(g) ? detail::backward_weight_ws_scratch_elements<T>(g) : std::size_t(0),
                         detail::backward_data_by_forward(g) ? detail::forward_ws_scratch_elements<T>(detail::flipped_geometry(g))
                                                            : std::size_t(0)});
    else return reference::conv2d_scratch_size<T>(g);
}

/// @brief y = conv(x, w) + bias (PyTorch Conv2d).
/// y[n,o,i,j] = b[o] + sum_{c,u,v} x[n,c,i*s-p+u, j*s-p+v] w[o,c,u,v]
/// @param g geometry (must satisfy g.valid())
/// @param x [batch, in_channels, in_h, in_w]
/// @param w [out_channels, in_channels, kernel_h, kernel_w]
/// @param bias_or_null [out_channels] or nullptr for no bias
/// @param y [batch, out_channels, out_h, out_w], overwritten
/// @param scratch conv2d_scratch_size<T>(g) elements
/// @param panels nullptr, or w packed by conv2d_pack_panels(g, conv_panels::forward) where that packing exists
template <class T>
void conv2d_forward(const conv_geometry& g, const T* x, const T* w, const T* bias_or_null, T* y, T* scratch,
                    const T* panels = nullptr) noexcept
{
    if constexpr (detail::fast_type<T>) detail::forward_any(g, x, w, bias_or_null, y, scratch, false, panels);
    else reference::conv2d_forward(g, x, w, bias_or_null, y, scratch);
}

/// @brief gx += dL/dx.  dL/dx[n,c,h,w] = sum_{o,u,v: h = i*s-p+u, w = j*s-p+v} gy[n,o,i,j] w[o,c,u,v]
/// @param gy [batch, out_channels, out_h, out_w]  @param w [out_channels, in_channels, kh, kw]
/// @param gx [batch, in_channels, in_h, in_w], accumulated into  @param scratch conv2d_scratch_size<T>(g)
/// @param panels nullptr, or w packed by conv2d_pack_panels(g, conv_panels::backward_data) where that packing exists
template <class T>
void conv2d_backward_data(const conv_geometry& g, const T* gy, const T* w, T* gx, T* scratch,
                          const T* panels = nullptr) noexcept
{
    if constexpr (detail::fast_type<T>) detail::backward_data_any(g, gy, w, gx, scratch, panels);
    else reference::conv2d_backward_data(g, gy, w, gx, scratch);
}

/// @brief gw += dL/dw.  dL/dw[o,c,u,v] = sum_{n,i,j} gy[n,o,i,j] x[n,c,i*s-p+u, j*s-p+v]
/// @param x [batch, in_channels, in_h, in_w]  @param gy [batch, out_channels, out_h, out_w]
/// @param gw [out_channels, in_channels, kh, kw], accumulated into  @param scratch conv2d_scratch_size<T>(g)
template <class T>
void conv2d_backward_weight(const conv_geometry& g, const T* x, const T* gy, T* gw, T* scratch) noexcept
{
    if constexpr (detail::fast_type<T>) detail::backward_weight_any(g, x, gy, gw, scratch);
    else reference::conv2d_backward_weight(g, x, gy, gw, scratch);
}

/// @brief Output channels [first, second) of part k of `parts` of a backward-weight pass of geometry g
/// (conv2d_backward_weight_parts()): consecutive runs of whole SIMD vectors, the last part taking the rest.
template <class T>
std::pair<int, int> conv2d_backward_weight_part(const conv_geometry& g, int parts, int k) noexcept
{
    const int L = detail::simd_lanes<T>, vectors = g.out_channels / L;
    const auto at = [&](int i) { return i >= parts ? g.out_channels : vectors * i / parts * L; };
    return {at(k), at(k + 1)};
}

/// @brief Into how many parts of output channels (at most `most`) a backward-weight pass of geometry g can be cut
/// with every weight's sum the same bits as in one pass: each part is the same pass over its channels
/// (conv2d_backward_weight() with gy's channels of the part), so each weight is summed by one call in one order.
/// That holds where the whole and every part take the weight-stationary path, whose per-weight order does not
/// depend on the channel count (tested part by part against the whole); 1 elsewhere.
template <class T>
int conv2d_backward_weight_parts(const conv_geometry& g, int most) noexcept
{
    if constexpr (!detail::fast_type<T>) return 1;
    else {
        if (most < 2 || !detail::use_backward_weight_ws<T>(g)) return 1;
        for (int p = std::min(most, g.out_channels / std::max(16, detail::simd_lanes<T>)); p > 1; --p) {
            bool same = true;
            for (int k = 0; k < p && same; ++k) {
                const auto [o0, o1] = conv2d_backward_weight_part<T>(g, p, k);
                conv_geometry gp = g;
                gp.out_channels = o1 - o0;
                same = o1 - o0 >= 16 && detail::use_backward_weight_ws<T>(gp);
            }
            if (same) return p;
        }
        return 1;
    }
}

/// @brief Whether the forward and backward-data passes of a batch `part` of geometry g give each image the bits the
/// whole batch's pass gives it. Each image's sums run in one order on every path; what the batch changes is the
/// path: the dot-product path serves at most dot_max_pixels pixels of the batch, so a smaller part can take it
/// where the whole batch does not (forward, and backward-data through its flipped forward pass).
template <class T>
bool conv2d_batch_part_keeps_bits(const conv_geometry& g, const conv_geometry& part) noexcept
{
    if constexpr (!detail::fast_type<T>) return true;
    else
        return detail::use_dot_forward<T>(g) == detail::use_dot_forward<T>(part) &&
               detail::use_dot_forward<T>(detail::flipped_geometry(g)) == detail::use_dot_forward<T>(detail::flipped_geometry(part));
}

/// @brief gb += dL/db.  dL/db[o] = sum_{n,i,j} gy[n,o,i,j]
/// @param gy [batch, out_channels, out_h, out_w]  @param gb [out_channels], accumulated into
template <class T>
void conv2d_backward_bias(const conv_geometry& g, const T* gy, T* gb) noexcept
{
    reference::conv2d_backward_bias(g, gy, gb);
}

/// @brief y = ConvTranspose2d(x, w), no bias. PyTorch ConvTranspose2d(in=Ci, out=Co, k, s, p) on an
/// H x W input is the backward-data of the convolution with geometry
/// g = {batch, in_channels = Co, in_h = (H-1)s - 2p + k, in_w = (W-1)s - 2p + k, out_channels = Ci, k, k, s, p}.
/// y[n,c,h,w] = sum_{o,u,v: h = i*s-p+u, w = j*s-p+v} x[n,o,i,j] w[o,c,u,v]
/// @param x [batch, g.out_channels, g.out_h(), g.out_w()] (= [batch, Ci, H, W])
/// @param w [g.out_channels, g.in_channels, k, k] (= PyTorch's [Ci, Co, k, k])
/// @param y [batch, g.in_channels, g.in_h, g.in_w], overwritten  @param scratch conv2d_scratch_size<T>(g)
template <class T>
void conv_transpose2d_forward(const conv_geometry& g, const T* x, const T* w, T* y, T* scratch) noexcept
{
    if constexpr (detail::fast_type<T>) {
        const std::size_t ny = g.x_size();
        for (std::size_t k = 0; k < ny; ++k) y[k] = T(0);
        detail::backward_data_any(g, x, w, y, scratch);
    } else {
        reference::conv_transpose2d_forward(g, x, w, y, scratch);
    }
}

/// @brief gx += dL/dx of conv_transpose2d_forward = conv2d_forward(g, gy, w) without bias.
/// dL/dx[n,o,i,j] = sum_{c,u,v} gy[n,c,i*s-p+u, j*s-p+v] w[o,c,u,v]
/// @param gy [batch, g.in_channels, g.in_h, g.in_w]  @param gx [batch, g.out_channels, g.out_h(), g.out_w()]
template <class T>
void conv_transpose2d_backward_data(const conv_geometry& g, const T* gy, const T* w, T* gx, T* scratch) noexcept
{
    if constexpr (detail::fast_type<T>) detail::forward_any(g, gy, w, static_cast<const T*>(nullptr), gx, scratch, true);
    else reference::conv_transpose2d_backward_data(g, gy, w, gx, scratch);
}

/// @brief gw += dL/dw of conv_transpose2d_forward = conv2d_backward_weight(g, x := gy, gy := x).
/// dL/dw[o,c,u,v] = sum_{n,i,j} x[n,o,i,j] gy[n,c,i*s-p+u, j*s-p+v]
/// @param x [batch, g.out_channels, g.out_h(), g.out_w()]  @param gy [batch, g.in_channels, g.in_h, g.in_w]
/// @param gw [g.out_channels, g.in_channels, k, k], accumulated into
template <class T>
void conv_transpose2d_backward_weight(const conv_geometry& g, const T* x, const T* gy, T* gw, T* scratch) noexcept
{
    if constexpr (detail::fast_type<T>) detail::backward_weight_any(g, gy, x, gw, scratch);
    else reference::conv_transpose2d_backward_weight(g, x, gy, gw, scratch);
}

}  // namespace handemo::kernels
