// The fast convolution path behind kernels/conv.hpp (the StarGAN convs of Chan et al. 2020, Sec. 3.3).
// Every pass is a small GEMM computed by register-blocked xsimd micro-kernels with 12 FMA accumulators;
// which formulation runs is chosen per geometry by measured rules (see each use_* function):
//   packed GEMM     C[j][i] += sum_k V[k][i] S[j][k], 3 vectors along i x 4 broadcast rows along j; V is
//                   packed (implicit im2col, zero-padded), S read in place with arbitrary strides.
//                   forward: i = output pixel (batch folded in), j = out channel, k = (c,u,v);
//                   backward-data: i = (c,u,v), j = pixel, k = out channel, then a col2im scatter-add;
//                   backward-weight: i = (c,u,v), j = out channel, k = pixel (summed over the batch).
//   stride 1        the same micro-kernel reading shifted windows of one zero-padded image (no packing),
//                   outputs on a "wide" grid whose extra columns are dropped; backward-data of a stride-1
//                   conv = this forward with the flipped kernel; backward-weight for few out channels =
//                   dot products of contiguous rows on the same wide grid.
//   dot             for <= 64 output pixels: vectorised along (c,u,v), 4 out channels x 3 pixels.
// The architecture is whatever xsimd's default_arch is for the target's -march (AVX2 + FMA here; SSE2
// without flags; NEON64 on aarch64, where FMA is native). Tuned for AVX2 on Zen 3 (32 KiB L1d, 512 KiB L2).
// On a target xsimd has no architecture for (32-bit ARM without NEON, a Cortex-M) kernels/conv.hpp takes
// the plain-loop reference kernels instead (has_simd).
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <type_traits>
#include <utility>

#include <xsimd/xsimd.hpp>
#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#endif

#include <handemo/kernels/reference.hpp>
#include <handemo/tensor/aligned.hpp>

namespace handemo::kernels::detail {

/// rows rows of `width` elements from src (row stride ss) to dst (row stride ds). Widths up to 16 are copies of
/// a size known at compile time, which the compiler turns into a few moves; a call to memcpy per row of 3 to 9
/// floats (the generator's inner layers) cost more than the copy.
template <class T>
inline void copy_rows(T* dst, std::ptrdiff_t ds, const T* src, std::ptrdiff_t ss, int rows, int width) noexcept
{
    auto fixed = [&]<int Wd>() {
        for (int r = 0; r < rows; ++r) std::memcpy(dst + r * ds, src + r * ss, std::size_t(Wd) * sizeof(T));
    };
    const bool done = [&]<int... I>(std::integer_sequence<int, I...>) {
        return ((width == I + 1 ? (fixed.template operator()<I + 1>(), true) : false) || ...);
    }(std::make_integer_sequence<int, 16>{});
    if (!done)
        for (int r = 0; r < rows; ++r) std::memcpy(dst + r * ds, src + r * ss, std::size_t(width) * sizeof(T));
}

/// x [C, H, W] into a [C, Hp, Wp] buffer with its top-left corner at (top, left): the image copy of every path
/// that reads a zero-padded input. The padding is not written (the caller zeroes the buffer once).
template <class T>
inline void copy_into_padded(T* dst, int Hp, int Wp, int top, int left, const T* x, int C, int H, int W) noexcept
{
    for (int c = 0; c < C; ++c)
        copy_rows(dst + (std::ptrdiff_t(c) * Hp + top) * Wp + left, Wp, x + std::ptrdiff_t(c) * H * W, W, H, W);
}

/// Whether xsimd found a SIMD instruction set for this target (false: conv.hpp uses the reference kernels).
inline constexpr bool has_simd = !std::is_same_v<xsimd::default_arch, xsimd::unavailable>;

template <class T>
using simd_t = xsimd::batch<T>;

template <class T>
inline constexpr int simd_lanes = int(simd_t<T>::size);

/// The register file the blocking is chosen for: 32 vector registers with AVX-512 (zmm0-31), 16 with AVX2
/// and SSE (and on NEON, whose 32 registers are not used by these blockings: they were not measured there).
#if defined(__AVX512F__) && (defined(__x86_64__) || defined(__i386__))
inline constexpr bool wide_register_file = true;
#else
inline constexpr bool wide_register_file = false;
#endif

/// Vectors per micro-tile along i, broadcast rows along j. 16 registers (AVX2): NV * NR = 12 accumulators
/// + NV + 1 <= 16. 32 registers (AVX-512): chosen by measurement (docs/performance.md): 3 x 4 on 16 and on
/// 32 registers, no wider tile measured faster.
inline constexpr int micro_nv = 3;
inline constexpr int micro_nr = 4;
static_assert(micro_nv >= 1 && micro_nr >= 4, "micro_nr >= 4: backward_weight_stride1 and the dot path assume it");
template <class T>
inline constexpr int micro_mr = micro_nv * simd_lanes<T>;

/// Tile of the dot-product micro-kernel (micro_dot): out channels x pixels, NO * NP accumulators + NP + 1
/// registers. At least 4 x 3 (backward_weight_stride1 uses 4 x 3 tiles).
inline constexpr int dot_no = wide_register_file ? 6 : 4;
inline constexpr int dot_np = wide_register_file ? 4 : 3;
static_assert(dot_no >= 4 && dot_np >= 3, "backward_weight_stride1 calls micro_dot with 4 x 3 tiles");
/// Pixels per tile of the backward-data GEMM (micro_kernel<T, NR>, NV = micro_nv): 8 with the 32 registers of
/// AVX-512 (24 accumulators, 3 + 8 loads per 24 FMAs), micro_nr elsewhere. Each lane's sum over the output
/// channels is the same chain whatever the tile, and col2im adds the tiles' pixels in the same order, so the bits
/// do not depend on it.
inline constexpr int backward_data_nr = wide_register_file ? 8 : micro_nr;
/// Reduction block of the forward pass: the packed V block (kc x MR) stays in L1.
inline constexpr int forward_kc = 256;

/// Put before a loop over a register tile (a compile-time bound): the loop is unrolled before GCC decides
/// where the tile's array lives, so the accumulators stay in registers. Without it GCC 12 for aarch64 kept the
/// micro-kernels' accumulator tiles on the stack and loaded and stored all of them at every reduction step
/// (12 fmla among about 40 instructions; found with bench/aarch64_icount.sh). x86 code is the same either way.
#define HANDEMO_UNROLL_TILE _Pragma("GCC unroll 32")

/// Makes the compiler keep a loaded V vector in a register: without it GCC folds the load into each of
/// the NR FMAs that use it (NV*NR + NR loads per k instead of NV + NR) and the load ports, not the FMA
/// units, bound the micro-kernel (measured in isolation: 51 -> 99 GFLOP/s of a 102 GFLOP/s peak).
/// On aarch64 the same empty asm with a NEON register ("w"); on any other target the value as is.
template <class B>
inline B keep_in_register(B a) noexcept
{
#if defined(__GNUC__) && (defined(__x86_64__) || defined(__i386__))
    // "v": any EVEX-encodable register (xmm/ymm/zmm 0-31 with AVX-512; the same 16 as "x" without it)
    auto r = static_cast<typename B::register_type>(a);
    __asm__("" : "+v"(r));
    return B(r);
#elif defined(__GNUC__) && defined(__aarch64__)
    auto r = static_cast<typename B::register_type>(a);
    __asm__("" : "+w"(r));
    return B(r);
#else
    return a;
#endif
}

/// tile[j][0..MR) (+)= sum_{k<kc} v[k*vk + 0..MR) * s[j*sj + k*sk], j < NR.
/// accumulate = false starts from zero, true from the current tile.
template <class T, int NR>
[[gnu::noinline]] inline void micro_kernel(int kc, const T* __restrict v, std::ptrdiff_t vk, const T* __restrict s,
                         std::ptrdiff_t sj, std::ptrdiff_t sk, T* __restrict tile, bool accumulate) noexcept
{
    using B = simd_t<T>;
    constexpr int L = simd_lanes<T>, NV = micro_nv, MR = micro_mr<T>;
    B acc[NR][NV];
    if (accumulate) {
        HANDEMO_UNROLL_TILE
        for (int j = 0; j < NR; ++j)
            HANDEMO_UNROLL_TILE
            for (int q = 0; q < NV; ++q) acc[j][q] = B::load_unaligned(tile + j * MR + q * L);
    } else {
        HANDEMO_UNROLL_TILE
        for (int j = 0; j < NR; ++j)
            HANDEMO_UNROLL_TILE
            for (int q = 0; q < NV; ++q) acc[j][q] = B(T(0));
    }
    const T* sp[NR];
    HANDEMO_UNROLL_TILE
    for (int j = 0; j < NR; ++j) sp[j] = s + j * sj;
    if (sk == 1) {
        for (int k = 0; k < kc; ++k) {
            B a[NV];
            HANDEMO_UNROLL_TILE
            for (int q = 0; q < NV; ++q) a[q] = keep_in_register(B::load_unaligned(v + q * L));
            HANDEMO_UNROLL_TILE
            for (int j = 0; j < NR; ++j) {
                const B b(sp[j][k]);
                HANDEMO_UNROLL_TILE
                for (int q = 0; q < NV; ++q) acc[j][q] = xsimd::fma(a[q], b, acc[j][q]);
            }
            v += vk;
        }
    } else {
        std::ptrdiff_t off = 0;
        for (int k = 0; k < kc; ++k) {
            B a[NV];
            HANDEMO_UNROLL_TILE
            for (int q = 0; q < NV; ++q) a[q] = keep_in_register(B::load_unaligned(v + q * L));
            HANDEMO_UNROLL_TILE
            for (int j = 0; j < NR; ++j) {
                const B b(sp[j][off]);
                HANDEMO_UNROLL_TILE
                for (int q = 0; q < NV; ++q) acc[j][q] = xsimd::fma(a[q], b, acc[j][q]);
            }
            v += vk;
            off += sk;
        }
    }
    HANDEMO_UNROLL_TILE
    for (int j = 0; j < NR; ++j)
        HANDEMO_UNROLL_TILE
        for (int q = 0; q < NV; ++q) acc[j][q].store_unaligned(tile + j * MR + q * L);
}

/// Calls f.template operator()<n>() with n = min(width, N) fixed at compile time (n >= 1): the register tile of a
/// micro-kernel instantiated for the width of a row's last, narrower tile. Every micro-kernel's dispatch below.
template <int N, class F>
inline void with_tile_width(int width, F&& f)
{
    if constexpr (N <= 1) f.template operator()<1>();
    else if (width >= N) f.template operator()<N>();
    else with_tile_width<N - 1>(width, f);
}

/// micro_kernel<T, nr> for nr = 1..micro_nr.
template <class T, int N = micro_nr>
inline void micro_dispatch(int nr, int kc, const T* v, std::ptrdiff_t vk, const T* s, std::ptrdiff_t sj,
                           std::ptrdiff_t sk, T* tile, bool accumulate) noexcept
{
    with_tile_width<N>(nr, [&]<int R>() { micro_kernel<T, R>(kc, v, vk, s, sj, sk, tile, accumulate); });
}

/// tile[j][0..MR) = sum_{k<kc} v[koff[k] + 0..MR) * s[j*sj + k], j < NR, MR = NV lanes: the V rows of the
/// stride-1 path are shifted windows of one zero-padded image (implicit im2col, nothing packed). Each lane sums
/// its products in k order whatever NV is, so a wider tile gives the same bits.
template <class T, int NR, int NV = micro_nv>
[[gnu::noinline]] inline void micro_kernel_idx(int kc, const T* __restrict v, const int* __restrict koff, const T* __restrict s,
                             std::ptrdiff_t sj, T* __restrict tile) noexcept
{
    using B = simd_t<T>;
    constexpr int L = simd_lanes<T>, MR = NV * L;
    B acc[NR][NV];
    HANDEMO_UNROLL_TILE
    for (int j = 0; j < NR; ++j)
        HANDEMO_UNROLL_TILE
        for (int q = 0; q < NV; ++q) acc[j][q] = B(T(0));
    const T* sp[NR];
    HANDEMO_UNROLL_TILE
    for (int j = 0; j < NR; ++j) sp[j] = s + j * sj;
    for (int k = 0; k < kc; ++k) {
        const T* vk = v + koff[k];
        B a[NV];
        HANDEMO_UNROLL_TILE
        for (int q = 0; q < NV; ++q) a[q] = keep_in_register(B::load_unaligned(vk + q * L));
        HANDEMO_UNROLL_TILE
        for (int j = 0; j < NR; ++j) {
            const B b(sp[j][k]);
            HANDEMO_UNROLL_TILE
            for (int q = 0; q < NV; ++q) acc[j][q] = xsimd::fma(a[q], b, acc[j][q]);
        }
    }
    HANDEMO_UNROLL_TILE
    for (int j = 0; j < NR; ++j)
        HANDEMO_UNROLL_TILE
        for (int q = 0; q < NV; ++q) acc[j][q].store_unaligned(tile + j * MR + q * L);
}

/// micro_kernel_idx<T, nr, NV> for nr = 1..N.
template <class T, int N = micro_nr, int NV = micro_nv>
inline void micro_idx_dispatch(int nr, int kc, const T* v, const int* koff, const T* s, std::ptrdiff_t sj,
                               T* tile) noexcept
{
    with_tile_width<N>(nr, [&]<int R>() { micro_kernel_idx<T, R, NV>(kc, v, koff, s, sj, tile); });
}

/// The stride-1 forward pass of a layer with few output channels (at most stride1_few_channels, G's last conv:
/// 3) takes tiles of stride1_few_nv vectors along the pixels instead of micro_nv: with 3 channels a 3 x 3 tile
/// loads 3 unaligned pixel vectors (most of them split across cache lines) and 3 broadcast weights for 9 FMAs
/// and is bound by the loads; 3 x 6 loads 6 + 3 for 18. It needs 18 accumulators + 6 + 1 registers: only with
/// the 32 of AVX-512 (elsewhere the two are the same). The same sums per lane, so the same bits.
inline constexpr int stride1_few_channels = 3;
inline constexpr int stride1_few_nv = wide_register_file ? 6 : micro_nv;

/// The kernel rows [first, second) whose taps output row r of a convolution (stride, padding pad, kernel_h rows,
/// in_h input rows) places over the image; the rows outside read only the zero padding above or below it (an empty
/// range when no row reaches the image).
inline std::pair<int, int> window_rows(int r, int stride, int pad, int kernel_h, int in_h) noexcept
{
    const int lo = std::clamp(pad - r * stride, 0, kernel_h);
    return {lo, std::clamp(pad + in_h - r * stride, lo, kernel_h)};
}

/// Output channels x pixels of the image-per-lane tile (micro_images): 3 x 8 = 24 accumulators + 3 weights + 1 with
/// the 32 registers of AVX-512, 3 x 3 with 16.
inline constexpr int stride1_images_np = wide_register_file ? 8 : 3;
/// Most elements of each of forward_stride1_images's buffers (one channel's interleaved padded plane, the output and
/// the block sums of a group): a layer with larger images keeps forward_stride1_tiles.
inline constexpr std::size_t stride1_images_max_elements = std::size_t(1) << 16;

/// Whether a stride-1 forward pass of geometry g (up to stride1_few_channels output channels) may take
/// forward_stride1_images for its groups of simd_lanes<T> images (a batch of fewer keeps forward_stride1_tiles):
/// one kernel row's taps at most forward_kc and both buffers within stride1_images_max_elements.
template <class T>
inline bool stride1_images_fits(const conv_geometry& g) noexcept
{
    constexpr std::size_t L = simd_lanes<T>;
    const std::size_t Hp = std::size_t(g.in_h) + 2 * g.pad, Wp = std::size_t(g.in_w) + 2 * g.pad;
    const std::size_t P = std::size_t(g.out_h()) * g.out_w();
    return g.stride == 1 && g.out_channels <= stride1_few_channels && g.kernel_h * g.kernel_w <= forward_kc &&
           Hp * Wp * L <= stride1_images_max_elements && std::size_t(g.out_channels) * P * L <= stride1_images_max_elements;
}

/// Scratch elements of forward_stride1_images: an interleaved padded plane, the block sums and the output of a
/// group, with room to align them.
template <class T>
inline std::size_t stride1_images_scratch_elements(const conv_geometry& g) noexcept
{
    constexpr std::size_t L = simd_lanes<T>;
    const std::size_t Hp = std::size_t(g.in_h) + 2 * g.pad, Wp = std::size_t(g.in_w) + 2 * g.pad;
    const std::size_t P = std::size_t(g.out_h()) * g.out_w();
    return Hp * Wp * L + 2 * std::size_t(g.out_channels) * P * L + 3 * (tensor_alignment / sizeof(T) + L);
}

/// Images of a stride-1 forward pass of geometry g (few output channels) that forward_stride1 takes in groups of
/// simd_lanes<T>, one per lane (forward_stride1_images); the others go image by image (forward_stride1_tiles).
template <class T>
inline int stride1_images_grouped(const conv_geometry& g) noexcept
{
    return stride1_images_fits<T>(g) ? g.batch / simd_lanes<T> * simd_lanes<T> : 0;
}

/// Multiply-adds forward_stride1 performs for geometry g with up to stride1_few_channels output channels: its groups
/// of simd_lanes<T> images (forward_stride1_images) leave out the kernel rows an output row places over the zero
/// padding above or below the image; the other images (forward_stride1_tiles) compute every product.
template <class T>
inline double forward_stride1_few_macs(const conv_geometry& g) noexcept
{
    const int grouped = stride1_images_grouped<T>(g);
    if (grouped == 0) return g.macs();
    double rows = 0;  // kernel rows over the image, summed over the output rows
    for (int r = 0; r < g.out_h(); ++r) {
        const auto [lo, hi] = window_rows(r, 1, g.pad, g.kernel_h, g.in_h);
        rows += hi - lo;
    }
    const double per_image = g.macs() / g.batch;
    return rows * g.kernel_w * g.in_channels * g.out_w() * g.out_channels * grouped + per_image * (g.batch - grouped);
}

/// Elements of the zero-padded image (plus read-past slack) of the stride-1 path.
inline std::size_t padded_image_elements(const conv_geometry& g, int mr) noexcept
{
    const std::size_t Hp = std::size_t(g.in_h) + 2 * g.pad, Wp = std::size_t(g.in_w) + 2 * g.pad;
    return std::size_t(g.in_channels) * Hp * Wp + std::size_t(mr) + Wp;
}

/// Lanes of the stride-1 path that carry a real output pixel (the rest are the dropped wide columns and
/// the last partial panel of each image).
template <class T>
inline double stride1_lane_efficiency(const conv_geometry& g) noexcept
{
    constexpr long MR = micro_mr<T>;
    const long wide = long(g.out_h() - 1) * (g.in_w + 2 * g.pad) + g.out_w();
    return double(long(g.out_h()) * g.out_w()) / double((wide + MR - 1) / MR * MR);
}

/// Stride 1: the unpacked path (no im2col packing, some idle lanes) or the packed, batch-folded path?
/// Cost per im2col element in lane-multiply-adds: packed = Co / packed_efficiency + ~24 (the gather),
/// unpacked = Co / stride1_efficiency. Calibrated on this machine: conv7 3+5 -> 32 at 12x24 runs at 59 vs
/// 41 GFLOP/s unpacked, the 3x3 residual conv at batch 16 at 74 packed vs 56 unpacked.
template <class T>
inline bool use_stride1_forward(const conv_geometry& g) noexcept
{
    if (g.stride != 1) return false;
    constexpr long MR = micro_mr<T>;
    const long ptot = long(g.batch) * g.out_h() * g.out_w();
    const double packed_eff = double(ptot) / double((ptot + MR - 1) / MR * MR);
    const double co = g.out_channels;
    return co / stride1_lane_efficiency<T>(g) < co / packed_eff + 24.0;
}

/// Backward-weight on the wide grid (backward_weight_stride1) pays for stride 1, few output channels and
/// enough pixels per image for its dot products (D's 1x3 heads stay on the packed path: 6 vs 1 GFLOP/s).
template <class T>
inline bool use_stride1_backward_weight(const conv_geometry& g) noexcept
{
    const long wide = long(g.out_h() - 1) * (g.in_w + 2 * g.pad) + g.out_w();
    return g.stride == 1 && g.out_channels < 16 && wide >= 8 * simd_lanes<T>;
}

/// Reduction block of the dot path (multiple of every SIMD width): long blocks amortise the horizontal
/// sums (measured on the residual conv at batch 1: 62 GFLOP/s with 512, 66 with 2304).
inline constexpr int dot_kc = 4096;
/// Largest batch * out_h * out_w the dot path handles.
inline constexpr int dot_max_pixels = 64;

/// The dot path pays when the pixel panels of the GEMM path would leave >= 10% of the lanes idle; it needs
/// K = in_channels * kh * kw a multiple of the SIMD width (weight rows are read in place, never past a row).
template <class T>
inline bool use_dot_forward(const conv_geometry& g) noexcept
{
    constexpr int MR = micro_mr<T>;
    const long K = long(g.in_channels) * g.kernel_h * g.kernel_w;
    const long ptot = long(g.batch) * g.out_h() * g.out_w();
    const double eff = use_stride1_forward<T>(g) ? stride1_lane_efficiency<T>(g)
                                                 : double(ptot) / double((ptot + MR - 1) / MR * MR);
    return K % simd_lanes<T> == 0 && K >= 64 && ptot <= dot_max_pixels && eff < 0.9;
}

/// Whether forward() of geometry g takes forward_stride1's path for few output channels (forward_stride1_images for
/// its groups of images where stride1_images_fits).
template <class T>
inline bool forward_takes_stride1_few(const conv_geometry& g) noexcept
{
    return !use_dot_forward<T>(g) && use_stride1_forward<T>(g) && g.out_channels <= stride1_few_channels;
}

/// Multiply-adds forward() performs for geometry g: forward_stride1_few_macs() on the stride-1 path of a layer with
/// few output channels, else every product (g.macs()).
template <class T>
inline double forward_macs(const conv_geometry& g) noexcept
{
    return forward_takes_stride1_few<T>(g) ? forward_stride1_few_macs<T>(g) : g.macs();
}

template <class T>
inline std::size_t dot_scratch_elements(const conv_geometry& g) noexcept
{
    const std::size_t K = std::size_t(g.in_channels) * g.kernel_h * g.kernel_w;
    const std::size_t padded = std::size_t(g.in_channels) * (g.in_h + 2 * g.pad) * (g.in_w + 2 * g.pad);
    return std::size_t(dot_max_pixels) * K + padded + 16;
}

/// Scratch elements of the forward pass alone (any batch size).
template <class T>
inline std::size_t forward_scratch_elements(const conv_geometry& g) noexcept
{
    constexpr std::size_t MR = micro_mr<T>, NR = micro_nr;
    // The maximum over every path some batch size could take, so that the size does not depend on
    // g.batch: callers size scratch for a whole batch and run the kernels on chunks of it.
    const std::size_t K = std::size_t(g.in_channels) * g.kernel_h * g.kernel_w;
    std::size_t n = std::min<std::size_t>(K, forward_kc) * MR + NR * MR;
    if (g.stride == 1) n = std::max(n, padded_image_elements(g, int(MR)) + NR * MR);
    if (g.stride == 1 && g.out_channels <= stride1_few_channels) {
        constexpr std::size_t MRw = std::size_t(stride1_few_nv) * simd_lanes<T>;
        n = std::max(n, padded_image_elements(g, int(MRw)) + std::size_t(stride1_few_channels) * MRw);
        if (stride1_images_fits<T>(g)) n = std::max(n, stride1_images_scratch_elements<T>(g));
    }
    if (K % simd_lanes<T> == 0 && K >= 64 && long(g.out_h()) * g.out_w() <= dot_max_pixels)
        n = std::max(n, dot_scratch_elements<T>(g));
    return n;
}

/// The geometry whose stride-1 forward pass is g's backward-data (gy padded by k-1-p, flipped weights).
inline conv_geometry flipped_geometry(const conv_geometry& g) noexcept
{
    return {g.batch, g.out_channels, g.out_h(), g.out_w(), g.in_channels, g.kernel_h, g.kernel_w, 1,
            g.kernel_h - 1 - g.pad};
}

/// Stride 1, square kernels, pad <= k-1: backward-data as the flipped forward pass (measured on this
/// machine against the GEMM + col2im route: 3x3 residual conv 54 vs 37 GFLOP/s, conv7 with 8 input
/// channels 59 vs 40).
inline bool backward_data_by_forward(const conv_geometry& g) noexcept
{
    return g.stride == 1 && g.kernel_h == g.kernel_w && g.pad <= g.kernel_h - 1;
}

/// Elements of the packed weight panels of backward_data (all of w, in panels of MR rows, zero-padded).
template <class T>
inline std::size_t packed_panels_elements(const conv_geometry& g) noexcept
{
    constexpr std::size_t MR = micro_mr<T>;
    const std::size_t K = std::size_t(g.in_channels) * g.kernel_h * g.kernel_w;
    return (K + MR - 1) / MR * MR * std::size_t(g.out_channels);
}

/// Scratch elements of the fast path for geometry g (max over all passes and over every batch size <= and >=
/// g.batch: the result does not depend on g.batch), see each pass for its parts.
template <class T>
inline std::size_t scratch_elements(const conv_geometry& g) noexcept
{
    constexpr std::size_t MR = micro_mr<T>, NR = micro_nr;
    const std::size_t P = std::size_t(g.out_h()) * g.out_w();
    const std::size_t co_r = (std::size_t(g.out_channels) + NR - 1) / NR * NR;
    const std::size_t fwd = forward_scratch_elements<T>(g);
    const std::size_t bwd_data = packed_panels_elements<T>(g) + std::size_t(backward_data_nr) * MR +
                                 std::size_t(g.in_channels) * (g.in_h + 2 * g.pad) * (g.in_w + 2 * g.pad);
    const std::size_t Pwl = (std::size_t(g.out_h() - 1) * (g.in_w + 2 * g.pad) + g.out_w() + simd_lanes<T> - 1) /
                            simd_lanes<T> * simd_lanes<T>;
    const std::size_t bwd_weight = use_stride1_backward_weight<T>(g) ? padded_image_elements(g, int(MR)) + std::size_t(g.out_channels) * Pwl
                                                          : P * MR + co_r * MR;
    const std::size_t s1 = backward_data_by_forward(g) ? forward_scratch_elements<T>(flipped_geometry(g)) + g.w_size() : 0;
    return std::max({fwd, bwd_data, bwd_weight, s1}) + 64 / sizeof(T);
}

/// Dot-product micro-kernel for outputs with few pixels: out[o][p] = sum_{s<steps} <w_o[s*L..], c_p[s*L..]>,
/// vectorised along the reduction (c,u,v), so no lane is wasted when a layer has only 1..20 output
/// pixels (the residual convs at 3x6, the discriminator's last layers at 1x3). 12 accumulators, 3 + 4
/// loads per 12 FMAs, one horizontal sum per output at the end.
template <class T, int NO, int NP>
[[gnu::noinline]] inline void micro_dot(int steps, const T* __restrict w, std::ptrdiff_t ldw, const T* __restrict c,
                                        std::ptrdiff_t ldc, T* __restrict out) noexcept
{
    using B = simd_t<T>;
    constexpr int L = simd_lanes<T>;
    B acc[NO][NP];
    HANDEMO_UNROLL_TILE
    for (int o = 0; o < NO; ++o)
        HANDEMO_UNROLL_TILE
        for (int p = 0; p < NP; ++p) acc[o][p] = B(T(0));
    for (int s = 0; s < steps; ++s) {
        B cv[NP];
        HANDEMO_UNROLL_TILE
        for (int p = 0; p < NP; ++p) cv[p] = keep_in_register(B::load_unaligned(c + p * ldc + s * L));
        HANDEMO_UNROLL_TILE
        for (int o = 0; o < NO; ++o) {
            const B wv = keep_in_register(B::load_unaligned(w + o * ldw + s * L));
            HANDEMO_UNROLL_TILE
            for (int p = 0; p < NP; ++p) acc[o][p] = xsimd::fma(wv, cv[p], acc[o][p]);
        }
    }
    HANDEMO_UNROLL_TILE
    for (int o = 0; o < NO; ++o)
        HANDEMO_UNROLL_TILE
        for (int p = 0; p < NP; ++p) out[o * NP + p] = xsimd::hadd(acc[o][p]);
}

/// micro_dot<T, NO, np> for np = 1..N.
template <class T, int NO, int N = dot_np>
inline void micro_dot_np(int np, int steps, const T* w, std::ptrdiff_t ldw, const T* c, std::ptrdiff_t ldc, T* out) noexcept
{
    with_tile_width<N>(np, [&]<int R>() { micro_dot<T, NO, R>(steps, w, ldw, c, ldc, out); });
}

/// micro_dot<T, no, np> for no = 1..dot_no, np = 1..dot_np; out gets no x np values (row-major).
template <class T, int N = dot_no>
inline void micro_dot_dispatch(int no, int np, int steps, const T* w, std::ptrdiff_t ldw, const T* c,
                               std::ptrdiff_t ldc, T* out) noexcept
{
    with_tile_width<N>(no, [&]<int R>() { micro_dot_np<T, R>(np, steps, w, ldw, c, ldc, out); });
}

/// Forward pass through micro_dot: col^T [pixels, K] packed once, weights read in place. The im2col reads
/// a zero-padded copy of each image, so it has no bounds checks (it took 10% of the paper G's inference
/// time with them, AVX-512).
template <class T>
inline void forward_dot(const conv_geometry& g, const T* x, const T* w, const T* bias, T* y, T* scratch,
                        bool accumulate_out) noexcept
{
    const int oh = g.out_h(), ow = g.out_w(), P = oh * ow, Ptot = P * g.batch;
    const int kh = g.kernel_h, kw = g.kernel_w, K = g.in_channels * kh * kw, Co = g.out_channels;
    const int Hp = g.in_h + 2 * g.pad, Wp = g.in_w + 2 * g.pad, Ci = g.in_channels;
    const std::ptrdiff_t HW = std::ptrdiff_t(g.in_h) * g.in_w, HWp = std::ptrdiff_t(Hp) * Wp;
    T* col = scratch;
    T* xp = scratch + std::ptrdiff_t(dot_max_pixels) * K;
    std::ptrdiff_t ybase[dot_max_pixels];
    for (int n = 0; n < g.batch; ++n) {
        const T* xn = x + std::ptrdiff_t(n) * Ci * HW;
        if (g.pad > 0) std::fill(xp, xp + Ci * HWp, T(0));
        copy_into_padded(xp, Hp, Wp, g.pad, g.pad, xn, Ci, g.in_h, g.in_w);
        for (int r = 0; r < P; ++r) {
            const int p = n * P + r;
            ybase[p] = std::ptrdiff_t(n) * Co * P + r;
            const T* src = xp + std::ptrdiff_t((r / ow) * g.stride) * Wp + (r % ow) * g.stride;  // padded coordinates
            T* dst = col + std::ptrdiff_t(p) * K;
            for (int c = 0; c < Ci; ++c, src += HWp)
                for (int u = 0; u < kh; ++u) {
                    const T* sr = src + std::ptrdiff_t(u) * Wp;
                    for (int v = 0; v < kw; ++v) *dst++ = sr[v];
                }
        }
    }
    for (int o = 0; o < Co; ++o) {
        const T b = bias ? bias[o] : T(0);
        for (int p = 0; p < Ptot; ++p) {
            T& dst = y[ybase[p] + std::ptrdiff_t(o) * P];
            dst = (accumulate_out ? dst : T(0)) + b;
        }
    }
    T out[dot_no * dot_np];
    for (int k0 = 0; k0 < K; k0 += dot_kc) {
        const int steps = std::min(dot_kc, K - k0) / simd_lanes<T>;
        for (int o0 = 0; o0 < Co; o0 += dot_no) {
            const int no = std::min(dot_no, Co - o0);
            for (int p0 = 0; p0 < Ptot; p0 += dot_np) {
                const int np = std::min(dot_np, Ptot - p0);
                micro_dot_dispatch<T>(no, np, steps, w + std::ptrdiff_t(o0) * K + k0, K, col + std::ptrdiff_t(p0) * K + k0, K, out);
                for (int o = 0; o < no; ++o)
                    for (int p = 0; p < np; ++p) y[ybase[p0 + p] + std::ptrdiff_t(o0 + o) * P] += out[o * np + p];
            }
        }
    }
}

/// y[i] = ((add ? y[i] : 0) + t[i]) + b for i < n, whole vectors first: the same sums, in the same order, as
/// the element-by-element loop.
template <class T>
inline void store_run(T* y, const T* t, int n, T b, bool add) noexcept
{
    using B = simd_t<T>;
    constexpr int L = simd_lanes<T>;
    int i = 0;
    for (; i + L <= n; i += L) {
        const B r = ((add ? B::load_unaligned(y + i) : B(T(0))) + B::load_unaligned(t + i)) + B(b);
        r.store_unaligned(y + i);
    }
    for (; i < n; ++i) y[i] = ((add ? y[i] : T(0)) + t[i]) + b;
}

/// koff[i] = (c Hp + u) Wp + v for the reduction indices k = k0 .. k0 + n - 1, k = (c, u, v) of a kh x kw kernel:
/// where tap k's window starts in a zero-padded [C, Hp, Wp] image.
inline void padded_window_offsets(int k0, int n, int kh, int kw, int Hp, int Wp, int* koff) noexcept
{
    for (int i = 0, c = k0 / (kh * kw), u = (k0 / kw) % kh, v = k0 % kw; i < n; ++i) {
        koff[i] = (c * Hp + u) * Wp + v;
        if (++v == kw) {
            v = 0;
            if (++u == kh) u = 0, ++c;
        }
    }
}

/// koff[k] = (c Hp + u) Wp + v for k = (u, c, v), kernel row first, of a C-channel kh x kw kernel: the taps of
/// kernel row u are the run [u C kw, (u + 1) C kw), so those of the rows that read only the zero padding above or
/// below the image lie at either end of k (packed_conv's row ranges, backward_weight_ws's tiles).
inline void padded_window_offsets_row_first(int C, int kh, int kw, int Hp, int Wp, int* koff) noexcept
{
    for (int u = 0, k = 0; u < kh; ++u)
        for (int c = 0; c < C; ++c)
            for (int v = 0; v < kw; ++v) koff[k++] = (c * Hp + u) * Wp + v;
}

/// Forward pass for stride 1: per image, x is copied once into a zero-padded [C, H+2p, W+2p] buffer and
/// the output is computed on the "wide" grid p' = i*(W+2p) + j, where im2col row (c,u,v) is the window
/// starting at c*(H+2p)*(W+2p) + u*(W+2p) + v; columns j >= out_w are computed and dropped.
template <class T, int NV = micro_nv, int NR = micro_nr>
inline void forward_stride1_tiles(const conv_geometry& g, const T* x, const T* w, const T* bias, T* y, T* scratch,
                                  bool accumulate_out) noexcept
{
    constexpr int MR = NV * simd_lanes<T>;
    const int Hp = g.in_h + 2 * g.pad, Wp = g.in_w + 2 * g.pad, oh = g.out_h(), ow = g.out_w(), P = oh * ow;
    const int kh = g.kernel_h, kw = g.kernel_w, K = g.in_channels * kh * kw, Co = g.out_channels;
    const int Pw = (oh - 1) * Wp + ow;  // last wide index that is a real output, + 1
    const std::size_t npad = padded_image_elements(g, MR);
    T* xp = scratch;
    T* tile = scratch + npad;
    int koff[forward_kc];
    for (std::size_t i = 0; i < npad; ++i) xp[i] = T(0);
    for (int n = 0; n < g.batch; ++n) {
        const T* xn = x + std::ptrdiff_t(n) * g.in_channels * g.in_h * g.in_w;
        copy_into_padded(xp, Hp, Wp, g.pad, g.pad, xn, g.in_channels, g.in_h, g.in_w);
        T* yn = y + std::ptrdiff_t(n) * Co * P;
        for (int k0 = 0; k0 < K; k0 += forward_kc) {
            const int kc = std::min(forward_kc, K - k0);
            padded_window_offsets(k0, kc, kh, kw, Hp, Wp, koff);
            const bool first = k0 == 0, add = !first || accumulate_out;
            for (int p0 = 0; p0 < Pw; p0 += MR) {
                for (int o0 = 0; o0 < Co; o0 += NR) {
                    const int nr = std::min(NR, Co - o0);
                    micro_idx_dispatch<T, NR, NV>(nr, kc, xp + p0, koff, w + std::ptrdiff_t(o0) * K + k0, K, tile);
                    for (int j = 0; j < nr; ++j) {
                        const T b = (first && bias) ? bias[o0 + j] : T(0);
                        const T* t = tile + j * MR;
                        T* yo = yn + std::ptrdiff_t(o0 + j) * P;
                        int r = p0 / Wp, q = p0 % Wp;
                        for (int i = 0; i < MR && r < oh;) {  // the lanes of each output row at once; wide columns dropped
                            if (q < ow) {
                                const int len = std::min(ow - q, MR - i);
                                store_run(yo + r * ow + q, t + i, len, b, add);
                                i += len, q += len;
                            } else {
                                i += Wp - q, q = 0, ++r;
                            }
                        }
                    }
                }
            }
        }
    }
}

/// Whether the packing loops gather whole vectors (float, int32 indices: one index vector per float vector) instead
/// of one element at a time. The indices are offsets into one batch chunk of the input, so it must have fewer than
/// 2^31 elements.
/// (xsimd 8's batch::gather does not reach the AVX2 / AVX-512 gather instructions, it inserts lane by lane, so the
/// gather is written with the intrinsics, and only for those two.)
template <class T>
inline constexpr bool vector_gather_type =
#if defined(__AVX512F__) && (defined(__x86_64__) || defined(__i386__))
    std::is_same_v<T, float> && simd_t<T>::size == 16 && xsimd::batch<std::int32_t>::size == 16;
#elif defined(__AVX2__) && (defined(__x86_64__) || defined(__i386__))
    std::is_same_v<T, float> && simd_t<T>::size == 8 && xsimd::batch<std::int32_t>::size == 8;
#else
    false;
#endif
template <class T>
inline bool use_vector_gather(std::size_t input_elements) noexcept
{
    return vector_gather_type<T> && input_elements < std::size_t(INT32_MAX);
}

/// Whether ws_transpose_block has an in-register transpose for T on this target (float with AVX-512 or AVX2, the
/// types vector_gather_type names); elsewhere the panels are packed one gathered vector at a time.
template <class T>
inline constexpr bool ws_transpose_type = vector_gather_type<T>;

/// out[j] for j < L = simd_lanes<T>: lane i is row(i)[j] for i < rows and j < cols, else 0. An L x L block of
/// rows transposed in registers: L contiguous (masked) loads and 4 log2(L) / 2 shuffles per vector, where packing
/// by gathers issues one L-lane gather per vector. Only where ws_transpose_type<T>.
template <class T, class Row>
inline void ws_transpose_rows(Row&& row, int rows, int cols, simd_t<T>* out) noexcept
{
#if defined(__AVX512F__) && (defined(__x86_64__) || defined(__i386__))
    if constexpr (ws_transpose_type<T>) {
        const __mmask16 m = cols >= 16 ? __mmask16(0xffff) : __mmask16((1u << cols) - 1u);
        __m512 r[16], t[16];
        for (int i = 0; i < 16; ++i) r[i] = i < rows ? _mm512_maskz_loadu_ps(m, row(i)) : _mm512_setzero_ps();
        for (int i = 0; i < 16; i += 2) {
            t[i] = _mm512_unpacklo_ps(r[i], r[i + 1]);
            t[i + 1] = _mm512_unpackhi_ps(r[i], r[i + 1]);
        }
        for (int i = 0; i < 16; i += 4) {
            const __m512d a = _mm512_castps_pd(t[i]), b = _mm512_castps_pd(t[i + 1]), c = _mm512_castps_pd(t[i + 2]),
                          d = _mm512_castps_pd(t[i + 3]);
            r[i] = _mm512_castpd_ps(_mm512_unpacklo_pd(a, c));
            r[i + 1] = _mm512_castpd_ps(_mm512_unpackhi_pd(a, c));
            r[i + 2] = _mm512_castpd_ps(_mm512_unpacklo_pd(b, d));
            r[i + 3] = _mm512_castpd_ps(_mm512_unpackhi_pd(b, d));
        }
        for (int i = 0; i < 16; i += 8)
            for (int j = 0; j < 4; ++j) {
                t[i + j] = _mm512_shuffle_f32x4(r[i + j], r[i + j + 4], 0x88);
                t[i + j + 4] = _mm512_shuffle_f32x4(r[i + j], r[i + j + 4], 0xdd);
            }
        for (int j = 0; j < 8; ++j) {
            out[j] = simd_t<T>(_mm512_shuffle_f32x4(t[j], t[j + 8], 0x88));
            out[j + 8] = simd_t<T>(_mm512_shuffle_f32x4(t[j], t[j + 8], 0xdd));
        }
        return;
    }
#elif defined(__AVX2__) && (defined(__x86_64__) || defined(__i386__))
    if constexpr (ws_transpose_type<T>) {
        const __m256i m = _mm256_cmpgt_epi32(_mm256_set1_epi32(cols), _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7));
        __m256 r[8], t[8];
        for (int i = 0; i < 8; ++i) r[i] = i < rows ? _mm256_maskload_ps(row(i), m) : _mm256_setzero_ps();
        for (int i = 0; i < 8; i += 2) {
            t[i] = _mm256_unpacklo_ps(r[i], r[i + 1]);
            t[i + 1] = _mm256_unpackhi_ps(r[i], r[i + 1]);
        }
        for (int i = 0; i < 8; i += 4) {
            r[i] = _mm256_shuffle_ps(t[i], t[i + 2], _MM_SHUFFLE(1, 0, 1, 0));
            r[i + 1] = _mm256_shuffle_ps(t[i], t[i + 2], _MM_SHUFFLE(3, 2, 3, 2));
            r[i + 2] = _mm256_shuffle_ps(t[i + 1], t[i + 3], _MM_SHUFFLE(1, 0, 1, 0));
            r[i + 3] = _mm256_shuffle_ps(t[i + 1], t[i + 3], _MM_SHUFFLE(3, 2, 3, 2));
        }
        for (int j = 0; j < 4; ++j) {
            out[j] = simd_t<T>(_mm256_permute2f128_ps(r[j], r[j + 4], 0x20));
            out[j + 4] = simd_t<T>(_mm256_permute2f128_ps(r[j], r[j + 4], 0x31));
        }
        return;
    }
#endif
    (void)row, (void)rows, (void)cols, (void)out;
}

/// ws_transpose_rows over the rows of a row-major matrix: lane i of out[j] is p[i * stride + j].
template <class T>
inline void ws_transpose_block(const T* p, std::ptrdiff_t stride, int rows, int cols, simd_t<T>* out) noexcept
{
    ws_transpose_rows<T>([&](int i) { return p + i * stride; }, rows, cols, out);
}

/// dst[(h * dst_row + q) * L + l] = image(l)[h * cols + q] for h < rows, q < cols, l < L = simd_lanes<T>: the
/// planes of L images interleaved one image per lane (ws_transpose_rows where it transposes in registers).
template <class T, class Image>
inline void interleave_images(Image&& image, int rows, int cols, T* dst, int dst_row) noexcept
{
    constexpr int L = simd_lanes<T>;
    for (int h = 0; h < rows; ++h) {
        T* d = dst + std::ptrdiff_t(h) * dst_row * L;
        if constexpr (ws_transpose_type<T>) {
            simd_t<T> v[L];
            for (int q0 = 0; q0 < cols; q0 += L) {
                const int n = std::min(L, cols - q0);
                ws_transpose_rows<T>([&](int l) { return image(l) + std::ptrdiff_t(h) * cols + q0; }, L, n, v);
                for (int j = 0; j < n; ++j) v[j].store_aligned(d + std::ptrdiff_t(q0 + j) * L);
            }
        } else {
            for (int l = 0; l < L; ++l)
                for (int q = 0; q < cols; ++q) d[std::ptrdiff_t(q) * L + l] = image(l)[std::ptrdiff_t(h) * cols + q];
        }
    }
}

/// image(l)[p] = src[p * L + l] for p < n, l < L = simd_lanes<T>: the inverse of interleave_images on one row.
template <class T, class Image>
inline void deinterleave_images(const T* src, int n, Image&& image) noexcept
{
    constexpr int L = simd_lanes<T>;
    if constexpr (ws_transpose_type<T>) {
        simd_t<T> v[L];
        alignas(64) T last[L];
        for (int p0 = 0; p0 < n; p0 += L) {
            const int m = std::min(L, n - p0);
            ws_transpose_rows<T>([&](int i) { return src + std::ptrdiff_t(p0 + i) * L; }, m, L, v);
            for (int l = 0; l < L; ++l) {
                if (m == L) {
                    v[l].store_unaligned(image(l) + p0);
                    continue;
                }
                v[l].store_aligned(last);
                std::copy_n(last, m, image(l) + p0);
            }
        }
    } else {
        for (int l = 0; l < L; ++l)
            for (int p = 0; p < n; ++p) image(l)[p] = src[std::ptrdiff_t(p) * L + l];
    }
}

/// One tile of forward_stride1_images: NO output channels x NP pixels of one output row, each vector the L images of
/// a group. acc = (from_tb ? tb : 0) + sum over the n taps of w[o * K + k] * src[koff[k] + j L], in k order; then
/// stored to tb, or, when yi is given, yi = ((add ? yi : 0) + acc) + b[o] (the block's end: forward_stride1_tiles's
/// store_run per lane). tb and yi: [NO][P][L] from the tile's first pixel, channel stride co_stride.
template <class T, int NO, int NP>
[[gnu::noinline]] inline void micro_images(int n, const int* __restrict koff, const T* __restrict w, std::ptrdiff_t K,
                                           const T* __restrict src, T* __restrict tb, std::ptrdiff_t co_stride,
                                           bool from_tb, T* __restrict yi, bool add, const T* b) noexcept
{
    using B = simd_t<T>;
    constexpr int L = simd_lanes<T>;
    B acc[NO][NP];
    HANDEMO_UNROLL_TILE
    for (int o = 0; o < NO; ++o)
        HANDEMO_UNROLL_TILE
        for (int j = 0; j < NP; ++j) acc[o][j] = from_tb ? B::load_aligned(tb + o * co_stride + j * L) : B(T(0));
    for (int k = 0; k < n; ++k) {
        const T* s = src + koff[k];
        B wv[NO];
        HANDEMO_UNROLL_TILE
        for (int o = 0; o < NO; ++o) wv[o] = B(w[o * K + k]);
        HANDEMO_UNROLL_TILE
        for (int j = 0; j < NP; ++j) {
            const B a = keep_in_register(B::load_aligned(s + j * L));
            HANDEMO_UNROLL_TILE
            for (int o = 0; o < NO; ++o) acc[o][j] = xsimd::fma(a, wv[o], acc[o][j]);
        }
    }
    if (!yi) {
        HANDEMO_UNROLL_TILE
        for (int o = 0; o < NO; ++o)
            HANDEMO_UNROLL_TILE
            for (int j = 0; j < NP; ++j) acc[o][j].store_aligned(tb + o * co_stride + j * L);
        return;
    }
    HANDEMO_UNROLL_TILE
    for (int o = 0; o < NO; ++o)
        HANDEMO_UNROLL_TILE
        for (int j = 0; j < NP; ++j) {
            T* yo = yi + o * co_stride + j * L;
            (((add ? B::load_aligned(yo) : B(T(0))) + acc[o][j]) + B(b[o])).store_aligned(yo);
        }
}

/// The stride-1 forward pass of a layer with few output channels (stride1_images_fits) on images [0, images) of x,
/// images a multiple of L = simd_lanes<T>: the L images of a group go in the lanes of every vector, so that no lane is
/// idle (forward_stride1_tiles's wide grid leaves a quarter of them idle on the generator's last layer), the loads
/// are aligned, and an output row skips the kernel rows that read only the zero padding above or below the image.
/// Each lane gets forward_stride1_tiles's bits: its products in the same k = (c, u, v) order within the same blocks of
/// forward_kc, each block summed from zero and added to the output as store_run adds it; the products left out are
/// +-0 and a sum started at +0 never becomes -0, so leaving them out changes no bit. One channel of the group is
/// interleaved at a time; a block's sums are carried from channel to channel in tb.
template <class T>
inline void forward_stride1_images(const conv_geometry& g, const T* x, const T* w, const T* bias, T* y, T* scratch,
                                   bool accumulate_out, int images) noexcept
{
    constexpr int L = simd_lanes<T>, NP = stride1_images_np;
    const int Hp = g.in_h + 2 * g.pad, Wp = g.in_w + 2 * g.pad, oh = g.out_h(), ow = g.out_w(), P = oh * ow;
    const int kh = g.kernel_h, kw = g.kernel_w, khw = kh * kw, Ci = g.in_channels, K = Ci * khw, Co = g.out_channels;
    const std::ptrdiff_t HW = std::ptrdiff_t(g.in_h) * g.in_w, co_stride = std::ptrdiff_t(P) * L;
    T* xi = align_up(scratch);
    T* tb = align_up(xi + std::ptrdiff_t(Hp) * Wp * L);
    T* yi = align_up(tb + Co * co_stride);
    int koff[forward_kc];
    for (int u = 0; u < kh; ++u)
        for (int v = 0; v < kw; ++v) koff[u * kw + v] = (u * Wp + v) * L;
    std::memset(xi, 0, std::size_t(Hp) * Wp * L * sizeof(T));
    for (int n0 = 0; n0 < images; n0 += L) {
        const T* xg = x + std::ptrdiff_t(n0) * Ci * HW;
        T* yg = y + std::ptrdiff_t(n0) * Co * P;
        if (accumulate_out)
            for (int o = 0; o < Co; ++o)
                interleave_images<T>([&](int l) { return yg + (std::ptrdiff_t(l) * Co + o) * P; }, 1, P, yi + o * co_stride, P);
        for (int k0 = 0; k0 < K; k0 += forward_kc) {
            const int k1 = std::min(K, k0 + forward_kc), c0 = k0 / khw, c1 = (k1 - 1) / khw;
            const bool add = k0 > 0 || accumulate_out;
            T b[stride1_few_channels] = {};
            for (int o = 0; o < Co; ++o) b[o] = (k0 == 0 && bias) ? bias[o] : T(0);
            for (int c = c0; c <= c1; ++c) {
                interleave_images<T>([&](int l) { return xg + (std::ptrdiff_t(l) * Ci + c) * HW; }, g.in_h, g.in_w,
                                     xi + (std::ptrdiff_t(g.pad) * Wp + g.pad) * L, Wp);
                // the channel's taps in this block, (u, v) order
                const int ka = std::max(k0, c * khw) - c * khw, kb = std::min(k1, (c + 1) * khw) - c * khw;
                const bool from_tb = c > c0;
                for (int r = 0; r < oh; ++r) {
                    const auto [u0, u1] = window_rows(r, 1, g.pad, kh, g.in_h);
                    const int ta = std::max(ka, u0 * kw), n = std::max(0, std::min(kb, u1 * kw) - ta);
                    const T* src = xi + std::ptrdiff_t(r) * Wp * L;
                    for (int q0 = 0; q0 < ow; q0 += NP) {
                        const std::ptrdiff_t t0 = std::ptrdiff_t(r * ow + q0) * L;
                        with_tile_width<NP>(ow - q0, [&]<int NPr>() {
                            with_tile_width<stride1_few_channels>(Co, [&]<int NO>() {
                                micro_images<T, NO, NPr>(n, koff + ta, w + std::ptrdiff_t(c) * khw + ta, K, src + q0 * L, tb + t0,
                                                         co_stride, from_tb, c == c1 ? yi + t0 : nullptr, add, b);
                            });
                        });
                    }
                }
            }
        }
        for (int o = 0; o < Co; ++o)
            deinterleave_images<T>(yi + o * co_stride, P, [&](int l) { return yg + (std::ptrdiff_t(l) * Co + o) * P; });
    }
}

/// Stride-1 forward pass: forward_stride1_tiles with the wide tile for few output channels.
template <class T>
inline void forward_stride1(const conv_geometry& g, const T* x, const T* w, const T* bias, T* y, T* scratch,
                            bool accumulate_out) noexcept
{
    if (g.out_channels <= stride1_few_channels) {
        // whole groups of simd_lanes<T> images one image per lane, the rest image by image: the same bits
        const int grouped = stride1_images_grouped<T>(g);
        if (grouped) forward_stride1_images(g, x, w, bias, y, scratch, accumulate_out, grouped);
        if (grouped == g.batch) return;
        conv_geometry rest = g;
        rest.batch = g.batch - grouped;
        return forward_stride1_tiles<T, stride1_few_nv, stride1_few_channels>(
            rest, x + std::ptrdiff_t(grouped) * g.in_channels * g.in_h * g.in_w, w, bias,
            y + std::ptrdiff_t(grouped) * g.out_channels * g.out_h() * g.out_w(), scratch, accumulate_out);
    }
    forward_stride1_tiles<T>(g, x, w, bias, y, scratch, accumulate_out);
}


/// One vector of a packing loop: x[index] in each lane whose row is in [0, h) and column in [0, w), else 0: a masked
/// gather (out-of-range lanes read nothing), so every lane holds exactly what the element-wise loop stores.
template <class T>
inline simd_t<T> gather_window(const T* x, const xsimd::batch<std::int32_t>& index, const xsimd::batch<std::int32_t>& row,
                               const xsimd::batch<std::int32_t>& col, std::int32_t h, std::int32_t w) noexcept
{
    using I = xsimd::batch<std::int32_t>;
#if (defined(__AVX512F__) || defined(__AVX2__)) && (defined(__x86_64__) || defined(__i386__))
    static_assert(vector_gather_type<T>, "gather_window: float with as many int32 lanes");
    const auto ri = static_cast<typename I::register_type>(row), ci = static_cast<typename I::register_type>(col);
    const auto ii = static_cast<typename I::register_type>(index);
#if defined(__AVX512F__)
    // unsigned compares: a negative row or column is a large unsigned number, out of range like one past the end
    const __mmask16 in = _mm512_cmplt_epu32_mask(ri, _mm512_set1_epi32(h)) & _mm512_cmplt_epu32_mask(ci, _mm512_set1_epi32(w));
    return simd_t<T>(_mm512_mask_i32gather_ps(_mm512_setzero_ps(), in, ii, x, int(sizeof(float))));
#else
    const __m256i row_in = _mm256_and_si256(_mm256_cmpgt_epi32(ri, _mm256_set1_epi32(-1)), _mm256_cmpgt_epi32(_mm256_set1_epi32(h), ri));
    const __m256i col_in = _mm256_and_si256(_mm256_cmpgt_epi32(ci, _mm256_set1_epi32(-1)), _mm256_cmpgt_epi32(_mm256_set1_epi32(w), ci));
    const __m256 in = _mm256_castsi256_ps(_mm256_and_si256(row_in, col_in));
    return simd_t<T>(_mm256_mask_i32gather_ps(_mm256_setzero_ps(), x, ii, in, int(sizeof(float))));
#endif
#else
    // element by element (no target here takes this path: vector_gather_type is false without AVX2 or AVX-512)
    constexpr int L = simd_lanes<T>;
    static_assert(int(I::size) == L, "gather_window: as many int32 lanes as T lanes");
    alignas(64) std::int32_t ix[L], r[L], c[L];
    alignas(64) T out[L];
    index.store_aligned(ix), row.store_aligned(r), col.store_aligned(c);
    for (int i = 0; i < L; ++i) out[i] = unsigned(r[i]) < unsigned(h) && unsigned(c[i]) < unsigned(w) ? x[ix[i]] : T(0);
    return simd_t<T>::load_aligned(out);
#endif
}

/// Forward pass (also the backward-data of the transposed convolution).
/// mode 0: y = conv + bias (bias may be null); mode 1: y += conv.
template <class T>
inline void forward(const conv_geometry& g, const T* x, const T* w, const T* bias, T* y, T* scratch,
                    bool accumulate_out) noexcept
{
    if (use_dot_forward<T>(g)) return forward_dot(g, x, w, bias, y, scratch, accumulate_out);
    if (use_stride1_forward<T>(g)) return forward_stride1(g, x, w, bias, y, scratch, accumulate_out);
    constexpr int MR = micro_mr<T>, NR = micro_nr, L = simd_lanes<T>;
    const int oh = g.out_h(), ow = g.out_w(), P = oh * ow, Ptot = P * g.batch;
    const int kh = g.kernel_h, kw = g.kernel_w, K = g.in_channels * kh * kw, Co = g.out_channels;
    const std::ptrdiff_t HW = std::ptrdiff_t(g.in_h) * g.in_w;
    T* vp = scratch;
    T* tile = scratch + std::size_t(std::min(K, forward_kc)) * MR;
    // per-lane geometry of the current panel
    std::ptrdiff_t xbase[MR], ybase[MR];
    int ih0[MR], iw0[MR];
    for (int p0 = 0; p0 < Ptot; p0 += MR) {
        const int np = std::min(MR, Ptot - p0);
        for (int i = 0; i < MR; ++i) {
            const int p = p0 + std::min(i, np - 1), n = p / P, r = p % P, oy = r / ow, ox = r % ow;
            ih0[i] = i < np ? oy * g.stride - g.pad : -1000000;  // dead lanes always read as padding
            iw0[i] = ox * g.stride - g.pad;
            xbase[i] = std::ptrdiff_t(n) * g.in_channels * HW + std::ptrdiff_t(ih0[i]) * g.in_w + iw0[i];
            ybase[i] = std::ptrdiff_t(n) * Co * P + r;
        }
        // the lanes as runs of consecutive outputs: one run for a panel inside one image, more for a panel across
        // images (or a short last one)
        int run_at[MR + 1], runs = 0;
        for (int i = 0; i < np; ++i)
            if (i == 0 || ybase[i] != ybase[i - 1] + 1) run_at[runs++] = i;
        run_at[runs] = np;
        for (int k0 = 0; k0 < K; k0 += forward_kc) {
            const int kc = std::min(forward_kc, K - k0);
            // pack V[k][i] = x[n_i, c, ih0_i + u, iw0_i + v] (0 outside), k = (c, u, v)
            bool packed = false;
            if constexpr (vector_gather_type<T>)
                if (use_vector_gather<T>(std::size_t(g.batch) * g.in_channels * HW)) {
                packed = true;
                using I = xsimd::batch<std::int32_t>;
                I rows[micro_nv], cols[micro_nv], bases[micro_nv];
                for (int q = 0; q < micro_nv; ++q) {
                    alignas(64) std::int32_t r[L], cl[L], b[L];
                    for (int i = 0; i < L; ++i) r[i] = ih0[q * L + i], cl[i] = iw0[q * L + i], b[i] = std::int32_t(xbase[q * L + i]);
                    rows[q] = I::load_aligned(r), cols[q] = I::load_aligned(cl), bases[q] = I::load_aligned(b);
                }
                int c = k0 / (kh * kw), u = (k0 / kw) % kh, v = k0 % kw;
                T* dst = vp;
                for (int k = 0; k < kc; ++k) {
                    const std::int32_t off = std::int32_t(c * HW + std::ptrdiff_t(u) * g.in_w + v);
                    for (int q = 0; q < micro_nv; ++q)
                        gather_window<T>(x, bases[q] + I(off), rows[q] + I(u), cols[q] + I(v), g.in_h, g.in_w).store_unaligned(dst + q * L);
                    dst += MR;
                    if (++v == kw) {
                        v = 0;
                        if (++u == kh) u = 0, ++c;
                    }
                }
            }
            if (!packed) {
                int c = k0 / (kh * kw), u = (k0 / kw) % kh, v = k0 % kw;
                T* dst = vp;
                for (int k = 0; k < kc; ++k) {
                    const std::ptrdiff_t off = c * HW + std::ptrdiff_t(u) * g.in_w + v;
                    for (int i = 0; i < MR; ++i) {
                        const bool in = unsigned(ih0[i] + u) < unsigned(g.in_h) && unsigned(iw0[i] + v) < unsigned(g.in_w);
                        dst[i] = in ? x[xbase[i] + off] : T(0);
                    }
                    dst += MR;
                    if (++v == kw) {
                        v = 0;
                        if (++u == kh) u = 0, ++c;
                    }
                }
            }
            const bool first = k0 == 0, add = !first || accumulate_out;
            for (int o0 = 0; o0 < Co; o0 += NR) {
                const int nr = std::min(NR, Co - o0);
                micro_dispatch<T>(nr, kc, vp, MR, w + std::ptrdiff_t(o0) * K + k0, K, 1, tile, false);
                for (int j = 0; j < nr; ++j) {
                    const T b = (first && bias) ? bias[o0 + j] : T(0);
                    const T* t = tile + j * MR;
                    const std::ptrdiff_t yo = std::ptrdiff_t(o0 + j) * P;
                    for (int r = 0; r < runs; ++r)
                        store_run(y + ybase[run_at[r]] + yo, t + run_at[r], run_at[r + 1] - run_at[r], b, add);
                }
            }
        }
    }
}

template <class T>
inline void forward(const conv_geometry& g, const T* x, const T* w, const T* bias, T* y, T* scratch,
                    bool accumulate_out) noexcept;

/// Backward-data of a stride-1 convolution as the stride-1 forward pass of gy (padded by k-1-p) with the
/// flipped, channel-swapped kernel w'[c,o,u,v] = w[o,c,k-1-u,k-1-v]:
/// gx[c,h,w] = sum_{o,u,v} gy[o, h+p-u, w+p-v] w[o,c,u,v] = sum_{o,u',v'} gy_pad'[o, h+u', w+v'] w'[c,o,u',v'].
template <class T>
inline void backward_data_stride1(const conv_geometry& g, const T* gy, const T* w, T* gx, T* scratch) noexcept
{
    const int kh = g.kernel_h, kw = g.kernel_w, Ci = g.in_channels, Co = g.out_channels;
    T* wf = scratch;
    // (kh - 1 - u) kw + (kw - 1 - v) = kk - 1 - (u kw + v): each (o, c) block of kk taps is written reversed into
    // block (c, o), in the order the blocks are written
    // blocks of 16 input channels: each o reads one contiguous run of w, and each c of the block writes on
    // where it left off (reading w's blocks Ci * kk apart, one per o, missed the cache on the wide layers)
    const int kk = kh * kw;
    constexpr int cb = 16;
    for (int c0 = 0; c0 < Ci; c0 += cb) {
        const int c1 = std::min(Ci, c0 + cb);
        for (int o = 0; o < Co; ++o)
            for (int c = c0; c < c1; ++c) {
                const T* src = w + (std::ptrdiff_t(o) * Ci + c) * kk;
                T* dst = wf + (std::ptrdiff_t(c) * Co + o) * kk;
                for (int t = 0; t < kk; ++t) dst[t] = src[kk - 1 - t];
            }
    }
    forward(flipped_geometry(g), gy, wf, static_cast<const T*>(nullptr), gx, scratch + g.w_size(), true);
}

/// d[0..4) += t[0..4): one vector of 4 lanes (GCC's vector extension: SSE on x86, NEON on aarch64), the same four
/// additions as a scalar loop, which GCC 12 left scalar in col2im (a load, an add and a store per element).
template <class T>
inline void add_run4(T* d, const T* t) noexcept
{
    typedef T v4 __attribute__((vector_size(4 * sizeof(T))));
    v4 a, b;
    std::memcpy(&a, d, sizeof(v4));
    std::memcpy(&b, t, sizeof(v4));
    a += b;
    std::memcpy(d, &a, sizeof(v4));
}

/// Backward-data pass: gx += col2im(W^T gy). The GEMM runs per image with V = packed panels of W (rows
/// of W are contiguous along (c,u,v); read in place, their out_channels rows sit K apart and thrash L1:
/// 36 -> 46 GFLOP/s on the convT 4x4 s2 layers at batch 1) and S = gy read in place, NR pixels per tile
/// (backward_data_nr). The col2im scatter-add goes into a zero-padded image so that it needs no bounds checks, and
/// runs of 4 consecutive (u, v) lanes are added as one 4-lane vector (add_run4); the padded image's interior is then
/// added to gx. Every element of gx receives its additions in the order (block of MR lanes, pixel, lane).
template <class T, int NR = backward_data_nr>
inline void backward_data(const conv_geometry& g, const T* gy, const T* w, T* gx, T* scratch) noexcept
{
    if (backward_data_by_forward(g)) return backward_data_stride1(g, gy, w, gx, scratch);
    constexpr int MR = micro_mr<T>;
    const int oh = g.out_h(), ow = g.out_w(), P = oh * ow;
    const int kh = g.kernel_h, kw = g.kernel_w, K = g.in_channels * kh * kw, Co = g.out_channels;
    const int Hp = g.in_h + 2 * g.pad, Wp = g.in_w + 2 * g.pad, s = g.stride;
    const std::ptrdiff_t HW = std::ptrdiff_t(g.in_h) * g.in_w, HWp = std::ptrdiff_t(Hp) * Wp;
    T* vpack = scratch;
    T* tile = vpack + packed_panels_elements<T>(g);
    T* gpad = tile + NR * MR;
    for (int k0 = 0; k0 < K; k0 += MR) {
        const int nk = std::min(MR, K - k0);
        T* dst = vpack + std::ptrdiff_t(k0) * Co;
        for (int o = 0; o < Co; ++o)
            for (int i = 0; i < MR; ++i) dst[std::ptrdiff_t(o) * MR + i] = i < nk ? w[std::ptrdiff_t(o) * K + k0 + i] : T(0);
    }
    // every aligned group of 4 lanes is 4 consecutive v of one (c, u): needs MR and so every panel start k0 to
    // be a multiple of 4 (not so for double on 128-bit NEON or SSE, MR = 3 x 2 lanes = 6)
    const bool runs4 = kw % 4 == 0 && MR % 4 == 0;
    std::ptrdiff_t koff[MR];
    for (int n = 0; n < g.batch; ++n) {
        for (std::ptrdiff_t i = 0; i < std::ptrdiff_t(g.in_channels) * HWp; ++i) gpad[i] = T(0);
        const T* gyn = gy + std::ptrdiff_t(n) * Co * P;
        for (int k0 = 0; k0 < K; k0 += MR) {
            const int nk = std::min(MR, K - k0);
            for (int i = 0, c = k0 / (kh * kw), u = (k0 / kw) % kh, v = k0 % kw; i < nk; ++i) {
                koff[i] = c * HWp + std::ptrdiff_t(u) * Wp + v;
                if (++v == kw) {
                    v = 0;
                    if (++u == kh) u = 0, ++c;
                }
            }
            const T* vsrc = vpack + std::ptrdiff_t(k0) * Co;
            for (int p0 = 0; p0 < P; p0 += NR) {
                const int nr = std::min(NR, P - p0);
                micro_dispatch<T, NR>(nr, Co, vsrc, MR, gyn + p0, 1, P, tile, false);
                for (int j = 0; j < nr; ++j) {
                    const int p = p0 + j;
                    T* base = gpad + std::ptrdiff_t((p / ow) * s) * Wp + (p % ow) * s;  // padded coordinates
                    const T* t = tile + j * MR;
                    if (runs4 && nk == MR) {
                        for (int i = 0; i < MR; i += 4) add_run4(base + koff[i], t + i);
                    } else {
                        for (int i = 0; i < nk; ++i) base[koff[i]] += t[i];
                    }
                }
            }
        }
        T* gxn = gx + std::ptrdiff_t(n) * g.in_channels * HW;
        for (int c = 0; c < g.in_channels; ++c)
            for (int h = 0; h < g.in_h; ++h) {
                const T* src = gpad + c * HWp + std::ptrdiff_t(h + g.pad) * Wp + g.pad;
                T* d = gxn + c * HW + std::ptrdiff_t(h) * g.in_w;
                for (int q = 0; q < g.in_w; ++q) d[q] += src[q];
            }
    }
}

/// Backward-weight for stride 1 and few output channels (the packed path would pack every im2col element
/// to reuse it only out_channels times): with x zero-padded and gy laid out on the same wide grid (zeros
/// in the dropped columns), gw[o,(c,u,v)] = sum_n sum_p' gy_wide[o,p'] xpad[c*Hp*Wp + u*Wp + v + p'],
/// one dot product of contiguous rows per weight; consecutive v share the call (c rows 1 element apart).
template <class T>
inline void backward_weight_stride1(const conv_geometry& g, const T* x, const T* gy, T* gw, T* scratch) noexcept
{
    constexpr int L = simd_lanes<T>, MR = micro_mr<T>;
    const int Hp = g.in_h + 2 * g.pad, Wp = g.in_w + 2 * g.pad, oh = g.out_h(), ow = g.out_w(), P = oh * ow;
    const int kh = g.kernel_h, kw = g.kernel_w, K = g.in_channels * kh * kw, Co = g.out_channels;
    const int Pw = (oh - 1) * Wp + ow, Pwl = (Pw + L - 1) / L * L;
    const std::size_t npad = padded_image_elements(g, MR);
    T* xp = scratch;
    T* gyw = scratch + npad;
    for (std::size_t i = 0; i < npad; ++i) xp[i] = T(0);
    for (std::ptrdiff_t i = 0; i < std::ptrdiff_t(Co) * Pwl; ++i) gyw[i] = T(0);
    T out[dot_no * dot_np];
    for (int n = 0; n < g.batch; ++n) {
        const T* xn = x + std::ptrdiff_t(n) * g.in_channels * g.in_h * g.in_w;
        copy_into_padded(xp, Hp, Wp, g.pad, g.pad, xn, g.in_channels, g.in_h, g.in_w);
        const T* gyn = gy + std::ptrdiff_t(n) * Co * P;
        for (int o = 0; o < Co; ++o)
            for (int r = 0; r < oh; ++r)
                for (int q = 0; q < ow; ++q) gyw[std::ptrdiff_t(o) * Pwl + r * Wp + q] = gyn[std::ptrdiff_t(o) * P + r * ow + q];
        for (int c = 0; c < g.in_channels; ++c)
            for (int u = 0; u < kh; ++u)
                for (int v0 = 0; v0 < kw; v0 += 3) {
                    const int nv = std::min(3, kw - v0), k0 = (c * kh + u) * kw + v0;
                    const T* xr = xp + (std::ptrdiff_t(c) * Hp + u) * Wp + v0;
                    for (int o0 = 0; o0 < Co; o0 += 4) {
                        const int no = std::min(4, Co - o0);
                        micro_dot_dispatch<T>(no, nv, Pwl / L, gyw + std::ptrdiff_t(o0) * Pwl, Pwl, xr, 1, out);
                        for (int o = 0; o < no; ++o)
                            for (int j = 0; j < nv; ++j) gw[std::ptrdiff_t(o0 + o) * K + k0 + j] += out[o * nv + j];
                    }
                }
    }
}

/// Backward-weight pass: gw[o, k] += sum_{n,p} gy[n,o,p] col_n[k,p]; V = col_n^T packed per image
/// (P x MR), S = gy rows in place, partial sums for all out channels kept in scratch across the batch.
/// `x` plays the role of the input, `gy` of the output gradient (swapped for the transposed conv).
template <class T>
inline void backward_weight(const conv_geometry& g, const T* x, const T* gy, T* gw, T* scratch) noexcept
{
    if (use_stride1_backward_weight<T>(g)) return backward_weight_stride1(g, x, gy, gw, scratch);
    constexpr int MR = micro_mr<T>, NR = micro_nr, L = simd_lanes<T>;
    using B = simd_t<T>;
    const int oh = g.out_h(), ow = g.out_w(), P = oh * ow;
    const int kh = g.kernel_h, kw = g.kernel_w, K = g.in_channels * kh * kw, Co = g.out_channels;
    const std::ptrdiff_t HW = std::ptrdiff_t(g.in_h) * g.in_w;
    T* vp = scratch;
    T* acc = scratch + std::size_t(P) * MR;
    std::ptrdiff_t koff[MR];
    int ku[MR], kv[MR];
    for (int k0 = 0; k0 < K; k0 += MR) {
        const int nk = std::min(MR, K - k0);
        for (int i = 0; i < MR; ++i) {
            const int k = k0 + std::min(i, nk - 1), c = k / (kh * kw), u = (k / kw) % kh, v = k % kw;
            ku[i] = i < nk ? u : -1000000;  // dead lanes always read as padding
            kv[i] = v;
            koff[i] = c * HW + std::ptrdiff_t(u) * g.in_w + v;
        }
        const bool gather = use_vector_gather<T>(std::size_t(g.in_channels) * HW);
        using I = xsimd::batch<std::int32_t>;
        I rows[micro_nv], cols[micro_nv], offs[micro_nv];
        if constexpr (vector_gather_type<T>)
            if (gather)
                for (int q = 0; q < micro_nv; ++q) {
                alignas(64) std::int32_t r[L], cl[L], o[L];
                for (int i = 0; i < L; ++i) r[i] = ku[q * L + i], cl[i] = kv[q * L + i], o[i] = std::int32_t(koff[q * L + i]);
                rows[q] = I::load_aligned(r), cols[q] = I::load_aligned(cl), offs[q] = I::load_aligned(o);
            }
        for (int n = 0; n < g.batch; ++n) {
            const T* xn = x + std::ptrdiff_t(n) * g.in_channels * HW;
            T* dst = vp;
            for (int p = 0; p < P; ++p) {
                const int ih0 = (p / ow) * g.stride - g.pad, iw0 = (p % ow) * g.stride - g.pad;
                if constexpr (vector_gather_type<T>)
                    if (gather) {
                        // x[n, c, ih0 + u, iw0 + v] for the lanes' (c, u, v), as offsets from the image's start
                        const std::int32_t at = std::int32_t(std::ptrdiff_t(ih0) * g.in_w + iw0);
                        for (int q = 0; q < micro_nv; ++q)
                            gather_window<T>(xn, offs[q] + I(at), rows[q] + I(ih0), cols[q] + I(iw0), g.in_h, g.in_w)
                                .store_unaligned(dst + q * L);
                        dst += MR;
                        continue;
                    }
                const T* base = xn + std::ptrdiff_t(ih0) * g.in_w + iw0;
                for (int i = 0; i < MR; ++i) {
                    const bool in = unsigned(ih0 + ku[i]) < unsigned(g.in_h) && unsigned(iw0 + kv[i]) < unsigned(g.in_w);
                    dst[i] = in ? base[koff[i]] : T(0);
                }
                dst += MR;
            }
            const T* gyn = gy + std::ptrdiff_t(n) * Co * P;
            for (int o0 = 0; o0 < Co; o0 += NR)
                micro_dispatch<T>(std::min(NR, Co - o0), P, vp, MR, gyn + std::ptrdiff_t(o0) * P, P, 1,
                                  acc + std::ptrdiff_t(o0) * MR, n > 0);
        }
        for (int o = 0; o < Co; ++o) {
            T* dst = gw + std::ptrdiff_t(o) * K + k0;
            const T* src = acc + std::ptrdiff_t(o) * MR;
            if (nk == MR) {
                for (int q = 0; q < MR; q += L) (B::load_unaligned(dst + q) + B::load_unaligned(src + q)).store_unaligned(dst + q);
            } else {
                for (int i = 0; i < nk; ++i) dst[i] += src[i];
            }
        }
    }
}

}  // namespace handemo::kernels::detail
