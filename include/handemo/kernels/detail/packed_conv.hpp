// The weight-stationary convolution path behind kernels/packed.hpp: for inference, where the weights do not
// change between calls, they are reordered once into panels [panel][k][MR] (MR = NV SIMD vectors of output
// channels, zero-padded) and every output tile is
//     tile[j][0..MR) = sum_k panel[k][0..MR) * src[koff[k] + j * SJ],   j < NR output pixels of one row,
// a register-blocked GEMM whose vectors run along the output channels and whose broadcasts gather the input
// straight from a zero-padded copy of the image (no im2col). One kernel serves both layers of the StarGAN
// generator (Chan et al. 2020, Sec. 3.3, Fig. 3) that dominate inference:
//   - convolutions, any stride: koff[(c,u,v)] = c*Hp*Wp + u*Wp + v, pixel j of a row at j*stride;
//   - transposed convolutions, split into stride^2 phases (output pixels h = m*s + r - p of one residue r):
//     each phase is a stride-1 convolution of the zero-padded input with the taps u = r, r+s, ... of the
//     kernel, so there is no col2im scatter and no per-call repacking of the weights.
// Why: at batch 1 the generator's layers have 18-288 output pixels. The paths of conv_simd.hpp vectorise
// along pixels (lanes idle) or along the reduction (a horizontal sum per output) and read the weights in
// their PyTorch layout with strides; here every weight is loaded once per 6-12 output pixels, contiguously,
// and the pixel count never leaves lanes idle. Measured per layer in bench_conv (`packed/...`).
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <type_traits>
#include <utility>
#include <vector>

#include <handemo/core/half.hpp>
#include <handemo/kernels/detail/conv_simd.hpp>
#include <handemo/tensor/aligned.hpp>

#if defined(__aarch64__) && defined(__ARM_NEON)
#include <arm_neon.h>
#endif

namespace handemo::kernels::detail {

/// Register tile of the weight-stationary kernel: NV vectors of output channels x NR output pixels.
/// 32 registers (AVX-512): 4 x 6 and 2 x 12 (24 accumulators + NV + 1 broadcast); 16 registers (AVX2,
/// SSE, and NEON, not measured there with 32): 2 x 6 and 1 x 12 (12 accumulators).
struct ws_tile {
    int nv, nr;
};

/// The tile for `co` output channels: the widest panel that leaves at most a quarter of its lanes idle.
template <class T>
constexpr ws_tile ws_tile_for(int co) noexcept
{
    constexpr int L = simd_lanes<T>;
    if constexpr (wide_register_file) {
        if (co >= 3 * L) return {4, 6};
        if (co > L) return {2, 12};
        return {1, 12};
    } else {
        if (co > L) return {2, 6};
        return {1, 12};
    }
}

/// Reduction block: one block of the panel ([kc][MR], stored as W) stays in L1 (32 KiB) while every pixel
/// tile of the layer uses it.
template <class T, class W = T>
constexpr int ws_kc(int nv) noexcept
{
    return std::max(16, int(32768 / (sizeof(W) * std::size_t(nv) * simd_lanes<T>)));
}

/// How many reduction blocks ahead the tiles of a block prefetch the weight stream (2 and 4 measured no faster).
inline constexpr int ws_prefetch_blocks = 1;

/// Whether the panels of float weights can be stored as IEEE binary16 and widened in the micro-kernel by
/// one instruction per vector: AVX-512 (vcvtph2ps zmm), AVX2 with F16C (vcvtph2ps ymm), aarch64 NEON
/// (fcvtl). Elsewhere kernels/packed.hpp keeps binary16-rounded weights as floats (same values, no saving).
#if defined(__AVX512F__) && (defined(__x86_64__) || defined(__i386__))
inline constexpr int ws_f16_lanes = 16;
#elif defined(__F16C__) && defined(__AVX2__) && (defined(__x86_64__) || defined(__i386__))
inline constexpr int ws_f16_lanes = 8;
#elif defined(__aarch64__) && defined(__ARM_NEON)
inline constexpr int ws_f16_lanes = 4;
#else
inline constexpr int ws_f16_lanes = 0;
#endif
template <class T>
inline constexpr bool ws_f16_native = std::is_same_v<T, float> && simd_lanes<float> == ws_f16_lanes;

/// One vector of panel weights: an aligned load of T, or of binary16 widened to float (ws_f16_native).
template <class T, class W>
inline simd_t<T> ws_load(const W* p) noexcept
{
    if constexpr (std::is_same_v<W, T>) {
        return simd_t<T>::load_aligned(p);
    } else {
        static_assert(std::is_same_v<W, std::uint16_t> && ws_f16_native<T>, "binary16 panels need ws_f16_native");
#if defined(__AVX512F__) && (defined(__x86_64__) || defined(__i386__))
        if constexpr (simd_lanes<float> == 16)
            return simd_t<T>(_mm512_cvtph_ps(_mm256_load_si256(reinterpret_cast<const __m256i*>(p))));
#endif
#if defined(__F16C__) && (defined(__x86_64__) || defined(__i386__))
        if constexpr (simd_lanes<float> == 8)
            return simd_t<T>(_mm256_cvtph_ps(_mm_load_si128(reinterpret_cast<const __m128i*>(p))));
#endif
#if defined(__aarch64__) && defined(__ARM_NEON)
        if constexpr (simd_lanes<float> == 4) return simd_t<T>(vcvt_f32_f16(vreinterpret_f16_u16(vld1_u16(p))));
#endif
        return simd_t<T>(T(0));  // unreachable: ws_f16_native<T> is false for every other target
    }
}

/// The accumulators of a register tile (NV vectors of output channels x NR pixels or taps, rows of MR = NV lanes in
/// `tile`): loaded from `tile` when accumulating, else zero.
template <class T, int NV, int NR>
[[gnu::always_inline]] inline void ws_tile_begin(simd_t<T> (&acc)[NR][NV], const T* tile, bool accumulate) noexcept
{
    using B = simd_t<T>;
    constexpr int L = simd_lanes<T>, MR = NV * L;
    if (accumulate) {
        HANDEMO_UNROLL_TILE
        for (int j = 0; j < NR; ++j)
            HANDEMO_UNROLL_TILE
            for (int q = 0; q < NV; ++q) acc[j][q] = B::load_aligned(tile + j * MR + q * L);
    } else {
        HANDEMO_UNROLL_TILE
        for (int j = 0; j < NR; ++j)
            HANDEMO_UNROLL_TILE
            for (int q = 0; q < NV; ++q) acc[j][q] = B(T(0));
    }
}

/// The accumulators of a register tile stored back into `tile`.
template <class T, int NV, int NR>
[[gnu::always_inline]] inline void ws_tile_end(const simd_t<T> (&acc)[NR][NV], T* tile) noexcept
{
    constexpr int L = simd_lanes<T>, MR = NV * L;
    HANDEMO_UNROLL_TILE
    for (int j = 0; j < NR; ++j)
        HANDEMO_UNROLL_TILE
        for (int q = 0; q < NV; ++q) acc[j][q].store_aligned(tile + j * MR + q * L);
}

/// One step of the tile: acc[j] += w[0..MR) * s[j * step] for its NR pixels (W: T or binary16, ws_load).
template <class T, class W, int NV, int NR>
[[gnu::always_inline]] inline void ws_tile_fma(simd_t<T> (&acc)[NR][NV], const W* w, const T* s, int step) noexcept
{
    using B = simd_t<T>;
    constexpr int L = simd_lanes<T>;
    B a[NV];
    HANDEMO_UNROLL_TILE
    for (int q = 0; q < NV; ++q) a[q] = keep_in_register(ws_load<T>(w + q * L));
    HANDEMO_UNROLL_TILE
    for (int j = 0; j < NR; ++j) {
        const B b(s[j * step]);
        HANDEMO_UNROLL_TILE
        for (int q = 0; q < NV; ++q) acc[j][q] = xsimd::fma(a[q], b, acc[j][q]);
    }
}

/// tile[j][0..MR) (+)= sum_{k<kc} wp[k*MR + 0..MR) * src[koff[k] + j*sj], j < NR. SJ > 0 fixes sj at
/// compile time (stride 1 and 2 of the generator); SJ = 0 reads it from `sj`. PF: also prefetch (into L2)
/// pf_rows rows (MR elements each) of the weight stream starting at `pf`, one row per iteration. W: the
/// stored weight type, T or binary16 (std::uint16_t, widened exactly by ws_load).
template <class T, class W, int NV, int NR, int SJ, bool PF = false>
[[gnu::noinline]] inline void micro_ws(int kc, const W* __restrict wp, const int* __restrict koff,
                                       const T* __restrict src, int sj, T* __restrict tile, bool accumulate,
                                       const W* pf = nullptr, int pf_rows = 0) noexcept
{
    using B = simd_t<T>;
    constexpr int L = simd_lanes<T>, MR = NV * L;
    B acc[NR][NV];
    ws_tile_begin<T, NV, NR>(acc, tile, accumulate);
    const int step = SJ > 0 ? SJ : sj;
    for (int k = 0; k < kc; ++k) {
        if constexpr (PF) {
            // one cache line per vector of the panel row: row k of this tile's share of the next block
            if (k < pf_rows)
                for (int q = 0; q < NV * L * int(sizeof(W)); q += 64)
                    __builtin_prefetch(reinterpret_cast<const char*>(pf + std::ptrdiff_t(k) * MR) + q, 0, 2);
        }
        ws_tile_fma<T, W, NV, NR>(acc, wp, src + koff[k], step);
        wp += MR;
    }
    ws_tile_end<T, NV, NR>(acc, tile);
}

/// micro_ws<T, W, NV, nr, SJ> for nr = 1..N.
template <class T, class W, int NV, int N, int SJ>
inline void micro_ws_dispatch(int nr, int kc, const W* wp, const int* koff, const T* src, int sj, T* tile,
                              bool accumulate) noexcept
{
    with_tile_width<N>(nr, [&]<int R>() { micro_ws<T, W, NV, R, SJ>(kc, wp, koff, src, sj, tile, accumulate); });
}

/// micro_ws over the taps idx[0..n) only: tile[j] (+)= sum_i wp[idx[i]*MR ..] * src[koff[idx[i]] + j*sj], in the
/// order of idx. For the output rows of a training convolution whose window reaches over the image's top or bottom
/// edge: the taps left out read only the zero padding.
template <class T, int NV, int NR, int SJ>
[[gnu::noinline]] inline void micro_ws_idx(int n, const int* __restrict idx, const T* __restrict wp, const int* __restrict koff,
                                           const T* __restrict src, int sj, T* __restrict tile, bool accumulate) noexcept
{
    using B = simd_t<T>;
    constexpr int L = simd_lanes<T>, MR = NV * L;
    B acc[NR][NV];
    ws_tile_begin<T, NV, NR>(acc, tile, accumulate);
    const int step = SJ > 0 ? SJ : sj;
    for (int i = 0; i < n; ++i) {
        const int k = idx[i];
        ws_tile_fma<T, T, NV, NR>(acc, wp + std::ptrdiff_t(k) * MR, src + koff[k], step);
    }
    ws_tile_end<T, NV, NR>(acc, tile);
}

/// micro_ws_idx<T, NV, nr, SJ> for nr = 1..N.
template <class T, int NV, int N, int SJ>
inline void micro_ws_idx_dispatch(int nr, int n, const int* idx, const T* wp, const int* koff, const T* src, int sj, T* tile,
                                  bool accumulate) noexcept
{
    with_tile_width<N>(nr, [&]<int R>() { micro_ws_idx<T, NV, R, SJ>(n, idx, wp, koff, src, sj, tile, accumulate); });
}

/// One weight-stationary GEMM: `co` output channels from the panels `wp` ([ceil(co/MR)][K][MR]) and the
/// offsets `koff` [K]; `rows` output rows of `cols` pixels each; pixel (r, q) reads the padded input at
/// src + r*src_row + q*sj and is written to y[o*y_chan + y_row0 + r*y_row + q*y_col]. row_k: nullptr (every
/// row sums over k in [0, K)), or per row r the range [row_k[2r], row_k[2r + 1]) outside which every tap of
/// the row reads the zero padding (the caller orders k so that those taps lie at the ends: kernel row first).
/// prefetch: whether the tiles prefetch the next block of the weight stream into L2 (what a stream from beyond the
/// L2 needs; where the weights were just streamed for an image before, the prefetches only cost).
struct ws_job {
    int K, co, rows, cols, sj;
    const int* koff;
    std::ptrdiff_t src_row;
    std::ptrdiff_t y_chan, y_row0, y_row, y_col;
    const int* row_k = nullptr;
    bool prefetch = true;
};

/// Elements of the accumulator scratch of a job: every pixel tile of one panel.
template <class T>
inline std::size_t ws_acc_elements(int co, int rows, int cols) noexcept
{
    const ws_tile t = ws_tile_for<T>(co);
    return std::size_t(rows) * ((cols + t.nr - 1) / t.nr) * t.nr * t.nv * simd_lanes<T>;
}

template <class T, class W, int NV, int NR, int SJ>
inline void ws_run_tiled(const ws_job& j, const W* wp, const T* src, const T* bias, T* y, T* acc) noexcept
{
    constexpr int L = simd_lanes<T>, MR = NV * L;
    // the block is sized in bytes of the stored weights (binary16 panels: twice the rows per block); the
    // tiles accumulate over the blocks in k order, so the block size does not change the sums
    const int kc_max = ws_kc<T, W>(NV);
    const int panels = (j.co + MR - 1) / MR;
    for (int pn = 0; pn < panels; ++pn) {
        const W* wpanel = wp + std::ptrdiff_t(pn) * j.K * MR;
        for (int k0 = 0; k0 < j.K; k0 += kc_max) {
            const int kc = std::min(kc_max, j.K - k0);
            // the weights of the next block (of this panel or the next: the panels are contiguous)
            const std::ptrdiff_t next = std::ptrdiff_t(pn) * j.K + k0 + kc * ws_prefetch_blocks;
            const bool pf = j.prefetch && next + kc <= std::ptrdiff_t(panels) * j.K;
            // the next block's kc rows are prefetched in equal shares by the full tiles of this block, each
            // share spread over the start of the tile's loop (one burst of a whole block overflowed the
            // outstanding-miss queues on the 18-pixel layers)
            const int full_tiles = j.rows * (j.cols / NR);
            const int share = full_tiles ? (kc + full_tiles - 1) / full_tiles : 0;
            int ti = 0;
            T* tile = acc;
            for (int r = 0; r < j.rows; ++r) {
                const T* srow = src + r * j.src_row;
                // the row's taps within this block that can read the image: [ka, kb); the others read zeros
                const int klo = j.row_k ? j.row_k[2 * r] : 0, khi = j.row_k ? j.row_k[2 * r + 1] : j.K;
                const int ka = std::max(k0, klo), kb = std::min(k0 + kc, khi);
                for (int q0 = 0; q0 < j.cols; q0 += NR, tile += NR * MR) {
                    const int nr = std::min(NR, j.cols - q0);
                    const T* sp = srow + std::ptrdiff_t(q0) * (SJ > 0 ? SJ : j.sj);
                    int r0 = 0, rows = 0;
                    if (pf && nr == NR) {
                        r0 = std::min(kc, ti * share), rows = std::min(kc - r0, share);
                        ++ti;
                    }
                    if (ka >= kb) {
                        // no tap of this block reaches the image: the tile keeps its sums (an empty row: zeros),
                        // and its share of the next block's weights is still prefetched
                        if (k0 == 0 && klo >= khi)
                            for (int i = 0; i < NR * MR; ++i) tile[i] = T(0);
                        for (int k = 0; k < rows; ++k)
                            for (int b = 0; b < MR * int(sizeof(W)); b += 64)
                                __builtin_prefetch(reinterpret_cast<const char*>(wp + (next + r0 + k) * MR) + b, 0, 2);
                        continue;
                    }
                    const bool accumulate = ka > klo;
                    if (rows > 0)
                        micro_ws<T, W, NV, NR, SJ, true>(kb - ka, wpanel + std::ptrdiff_t(ka) * MR, j.koff + ka, sp, j.sj, tile,
                                                          accumulate, wp + (next + r0) * MR, rows);
                    else
                        micro_ws_dispatch<T, W, NV, NR, SJ>(nr, kb - ka, wpanel + std::ptrdiff_t(ka) * MR, j.koff + ka, sp, j.sj,
                                                         tile, accumulate);
                }
            }
        }
        // write the panel's tiles out: tile[q][i] -> y[o0 + i][pixel q]
        const int o0 = pn * MR, no = std::min(MR, j.co - o0);
        // On a job whose output channels are whole planes of its rows back to back, a tile's pixels of each channel are
        // written as one vector (a block of L channels transposed in registers): the lanes past the tile's pixels land on
        // pixels of the same plane that a later tile writes; the tiles whose vector would run past the plane are
        // written element by element. The same single addition of the bias per value.
        const bool whole_planes = ws_transpose_type<T> && NR <= L && j.y_col == 1 && j.y_row0 == 0 && j.y_row == j.cols &&
                                  j.y_chan == std::ptrdiff_t(j.rows) * j.cols;
        const std::ptrdiff_t plane = std::ptrdiff_t(j.rows) * j.cols;
        const T* tile = acc;
        for (int r = 0; r < j.rows; ++r)
            for (int q0 = 0; q0 < j.cols; q0 += NR, tile += NR * MR) {
                const int nr = std::min(NR, j.cols - q0);
                const std::ptrdiff_t p = std::ptrdiff_t(r) * j.cols + q0;
                if (whole_planes && p + L <= plane) {
                    simd_t<T> out[L];
                    for (int v = 0; v * L < no; ++v) {
                        ws_transpose_rows<T>([&](int q) { return tile + q * MR + v * L; }, nr, L, out);
                        for (int c = 0, o = o0 + v * L; c < L && o < o0 + no; ++c, ++o)
                            (out[c] + simd_t<T>(bias ? bias[o] : T(0))).store_unaligned(y + std::ptrdiff_t(o) * j.y_chan + p);
                    }
                    continue;
                }
                for (int i = 0; i < no; ++i) {
                    const T b = bias ? bias[o0 + i] : T(0);
                    T* yo = y + std::ptrdiff_t(o0 + i) * j.y_chan + j.y_row0 + r * j.y_row + q0 * j.y_col;
                    for (int q = 0; q < nr; ++q) {
                        yo[q * j.y_col] = tile[q * MR + i] + b;
                    }
                }
            }
    }
}

/// Calls f.template operator()<NV, NR, SJ>() with the tile ws_tile_for<T>(co) and the pixel step sj fixed at
/// compile time when it is 1 or 2 (SJ = 0: read at run time). The instantiations follow that one table.
template <class T, class F>
inline void ws_with_tile(int co, int sj, F&& f)
{
    constexpr int L = simd_lanes<T>;
    auto with_step = [&]<int CO>() {
        constexpr ws_tile t = ws_tile_for<T>(CO);
        if (sj == 1) f.template operator()<t.nv, t.nr, 1>();
        else if (sj == 2) f.template operator()<t.nv, t.nr, 2>();
        else f.template operator()<t.nv, t.nr, 0>();
    };
    switch (ws_tile_for<T>(co).nv) {
    case 4: with_step.template operator()<4 * L>(); break;
    case 2: with_step.template operator()<2 * L>(); break;
    default: with_step.template operator()<L>(); break;
    }
}

/// Runs a job (y = result + bias, overwritten) with the tile ws_tile_for<T>(co) and the compile-time pixel
/// stride when it is 1 or 2. W: the stored weight type (T, or std::uint16_t binary16 when ws_f16_native<T>).
template <class T, class W>
inline void ws_run(const ws_job& j, const W* wp, const T* src, const T* bias, T* y, T* acc) noexcept
{
    ws_with_tile<T>(j.co, j.sj, [&]<int NV, int NR, int SJ>() { ws_run_tiled<T, W, NV, NR, SJ>(j, wp, src, bias, y, acc); });
}

/// Packs weights into panels: dst[(pn*K + k)*MR + i] = value(o = pn*MR + i, k), 0 for o >= co.
template <class T, class F>
inline void ws_pack(int co, int K, T* dst, F&& value)
{
    const ws_tile t = ws_tile_for<T>(co);
    const int MR = t.nv * simd_lanes<T>, panels = (co + MR - 1) / MR;
    for (int pn = 0; pn < panels; ++pn)
        for (int k = 0; k < K; ++k)
            for (int i = 0; i < MR; ++i) {
                const int o = pn * MR + i;
                dst[(std::ptrdiff_t(pn) * K + k) * MR + i] = o < co ? value(o, k) : T(0);
            }
}

/// Elements of the packed panels of `co` output channels and reduction length K.
template <class T>
inline std::size_t ws_packed_elements(int co, int K) noexcept
{
    const ws_tile t = ws_tile_for<T>(co);
    const std::size_t MR = std::size_t(t.nv) * simd_lanes<T>;
    return (std::size_t(co) + MR - 1) / MR * MR * std::size_t(K);
}


// ------------------------------------------------------------------------- convolutions whose weights change
// Training calls the convolutions with new weights every step, so frozen panels do not apply; but packing
// costs O(weights) against O(weights x pixels x images) multiply-adds, so kernels/conv.hpp packs them at each
// call (forward_ws) and runs the weight-stationary micro-kernel over the images of the batch in groups that
// share each block of panel rows. The sums are those of conv_simd.hpp's packed and stride-1 forward paths, bit for bit, so a model
// trains to the same bits on either: each output's products are summed in k = (c, u, v) order in chains of
// forward_kc products, each chain starting from zero (the kernel's reduction blocks never cross a chain's
// end), and the chains are added to the output as those paths add them: ((y or 0) + chain) + bias for the
// first, (y + chain) + 0 for each later one. Output rows whose window reaches over the image's top or bottom edge
// leave out the taps on the kernel rows that read only the zero padding (micro_ws_idx): their products are +-0,
// which leave a sum that starts at +0 as it is, so the bits are the same, for fewer multiply-adds.

/// The output rows of a convolution whose window reaches over the image's top edge ([0, top)) or bottom edge
/// ([bottom, rows)); the rows between place every kernel row over the image. forward_ws runs the edge rows over
/// their other taps only (`skip`) where there are at most ws_max_edge_rows of them.
inline constexpr int ws_max_edge_rows = 8;
struct ws_edges {
    int top, bottom;
    bool skip;
};
inline ws_edges ws_edge_rows(const conv_geometry& g) noexcept
{
    const int rows = g.out_h(), kh = g.kernel_h;
    const auto full = [&](int r) { return window_rows(r, g.stride, g.pad, kh, g.in_h) == std::pair{0, kh}; };
    ws_edges e{0, rows, false};
    while (e.top < rows && !full(e.top)) ++e.top;
    while (e.bottom > e.top && !full(e.bottom - 1)) --e.bottom;
    e.skip = e.top + (rows - e.bottom) <= ws_max_edge_rows && (e.top > 0 || e.bottom < rows);
    return e;
}

/// Multiply-adds forward_ws performs for geometry g (every image): an edge row it runs over its other taps counts
/// those only.
inline double forward_ws_macs(const conv_geometry& g) noexcept
{
    const ws_edges e = ws_edge_rows(g);
    double taps = 0;  // summed over the output rows
    for (int r = 0; r < g.out_h(); ++r) {
        const auto [lo, hi] = window_rows(r, g.stride, g.pad, g.kernel_h, g.in_h);
        taps += double(e.skip && (r < e.top || r >= e.bottom) ? hi - lo : g.kernel_h) * g.in_channels * g.kernel_w;
    }
    return taps * g.out_w() * g.out_channels * g.batch;
}

/// Images forward_ws runs together: each block of panel weights is loaded into L1 once for all of them (one image
/// at a time streamed the paper G's 2 MB panels from L3 once per image, for 18 output pixels each), as many as
/// fit ws_group_elements elements of padded input and tiles, at least 1 and at most 16.
inline constexpr int ws_group_max = 16;
inline constexpr std::size_t ws_group_elements = std::size_t(1) << 20;

/// The parts of forward_ws's scratch (elements of T, each part 64-byte aligned) for geometry g.
template <class T>
struct ws_scratch_layout {
    std::size_t panels, tiles, padded;  // per call; per image; per image
    int group;                          // images per group
    std::size_t total;
    explicit ws_scratch_layout(const conv_geometry& g) noexcept
    {
        constexpr std::size_t a = 64 / sizeof(T);
        auto up = [](std::size_t n) { return (n + a - 1) / a * a; };
        panels = up(ws_packed_elements<T>(g.out_channels, g.in_channels * g.kernel_h * g.kernel_w));
        tiles = up(ws_acc_elements<T>(g.out_channels, g.out_h(), g.out_w()));
        padded = up(std::size_t(g.in_channels) * (g.in_h + 2 * g.pad) * (g.in_w + 2 * g.pad));
        const std::size_t per_image = 2 * tiles + padded;
        group = int(std::clamp<std::size_t>(ws_group_elements / per_image, 1, ws_group_max));
        total = a + panels + std::size_t(group) * per_image;
    }
};

/// Elements (of T) of forward_ws's scratch for geometry g: the panels and, per image of a group, two sets of
/// pixel tiles (the chain and the running sums) and the zero-padded image. It does not depend on g.batch.
template <class T>
inline std::size_t forward_ws_scratch_elements(const conv_geometry& g) noexcept
{
    return ws_scratch_layout<T>(g).total;
}

/// y (+)= conv(x, w) + bias on the `images` images of a group (g.batch is ignored): padded inputs at
/// src + n * src_image, outputs at y + n * y_image, tiles at acc / sum + n * tile_image. The sums in chains of
/// forward_kc (see above); every block of panel rows serves all the group's images before the next is read.
template <class T, int NV, int NR, int SJ>
inline void ws_run_chains(const conv_geometry& g, int Hp, int Wp, const T* wp, int images, const T* src,
                          std::size_t src_image, const T* bias, T* y, std::size_t y_image, T* acc, T* sum,
                          std::size_t tile_image, bool accumulate_out) noexcept
{
    using B = simd_t<T>;
    constexpr int L = simd_lanes<T>, MR = NV * L;
    const int kh = g.kernel_h, kw = g.kernel_w, K = g.in_channels * kh * kw, co = g.out_channels;
    const int rows = g.out_h(), cols = g.out_w(), sj = g.stride;
    const std::ptrdiff_t src_row = std::ptrdiff_t(g.stride) * Wp, y_chan = std::ptrdiff_t(rows) * cols;
    // reduction blocks within a chain: each is cut at its chain's end (kc below)
    const int kc_max = ws_kc<T>(NV);
    const int panels = (co + MR - 1) / MR, tiles_per_row = (cols + NR - 1) / NR;
    const std::size_t n_acc = std::size_t(rows) * tiles_per_row * NR * MR;
    int koff[forward_kc];
    alignas(64) T bv[MR];
    // Output rows whose window reaches over the image's top edge (the first `top`) or bottom edge (from `bottom`
    // on): their taps on kernel rows outside [u_lo, u_hi) read only the zero padding, and a product with +-0 leaves
    // a chain's sum as it is (each chain starts at +0), so those rows run over their other taps only (micro_ws_idx),
    // with the bits of the full sum. Per edge row and chain, the chain-relative taps it keeps.
    constexpr int max_edge_rows = ws_max_edge_rows;
    const auto rows_of = [&](int r) { return window_rows(r, g.stride, g.pad, kh, g.in_h); };
    const ws_edges edges = ws_edge_rows(g);
    const int top = edges.top, bottom = edges.bottom;
    const bool skip = edges.skip;
    int edge_taps[max_edge_rows][forward_kc];
    int edge_count[max_edge_rows];
    auto edge_index = [&](int r) { return r < top ? r : r >= bottom ? top + (r - bottom) : -1; };
    for (int pn = 0; pn < panels; ++pn) {
        const T* wpanel = wp + std::ptrdiff_t(pn) * K * MR;
        const int o0 = pn * MR, no = std::min(MR, co - o0);
        if (accumulate_out)
            for (int n = 0; n < images; ++n) {
                T* t = sum + n * tile_image;
                const T* yn = y + n * y_image;
                for (int r = 0; r < rows; ++r)
                    for (int q0 = 0; q0 < cols; q0 += NR, t += NR * MR)
                        for (int q = 0; q < NR; ++q)
                            for (int i = 0; i < MR; ++i)
                                t[q * MR + i] = (i < no && q0 + q < cols) ? yn[std::ptrdiff_t(o0 + i) * y_chan + r * cols + q0 + q] : T(0);
            }
        for (int s0 = 0; s0 < K; s0 += forward_kc) {
            const int s1 = std::min(K, s0 + forward_kc);
            padded_window_offsets(s0, s1 - s0, kh, kw, Hp, Wp, koff);
            if (skip)
                for (int r = 0; r < rows; ++r) {
                    const int e = edge_index(r);
                    if (e < 0) continue;
                    const auto [u_lo, u_hi] = rows_of(r);
                    int m = 0;
                    for (int k = s0, u = (s0 / kw) % kh, v = s0 % kw; k < s1; ++k) {
                        if (u >= u_lo && u < u_hi) edge_taps[e][m++] = k - s0;
                        if (++v == kw) v = 0, u = u + 1 == kh ? 0 : u + 1;
                    }
                    edge_count[e] = m;
                }
            int cursor[max_edge_rows] = {};  // per edge row: its first tap at or after the block
            for (int k0 = s0; k0 < s1; k0 += kc_max) {
                const int kc = std::min(kc_max, s1 - k0);
                int block_end[max_edge_rows] = {};
                if (skip)
                    for (int e = 0; e < top + (rows - bottom); ++e) {
                        int i = cursor[e];
                        while (i < edge_count[e] && edge_taps[e][i] < k0 + kc - s0) ++i;
                        block_end[e] = i;
                    }
                for (int n = 0; n < images; ++n) {
                    T* tile = acc + n * tile_image;
                    const T* sn = src + n * src_image;
                    for (int r = 0; r < rows; ++r) {
                        const T* srow = sn + r * src_row;
                        const int e = skip ? edge_index(r) : -1;
                        for (int q0 = 0; q0 < cols; q0 += NR, tile += NR * MR) {
                            const T* sp = srow + std::ptrdiff_t(q0) * (SJ > 0 ? SJ : sj);
                            if (e < 0) {
                                micro_ws_dispatch<T, T, NV, NR, SJ>(std::min(NR, cols - q0), kc, wpanel + std::ptrdiff_t(k0) * MR,
                                                                    koff + (k0 - s0), sp, sj, tile, k0 > s0);
                            } else if (block_end[e] > cursor[e]) {
                                micro_ws_idx_dispatch<T, NV, NR, SJ>(std::min(NR, cols - q0), block_end[e] - cursor[e],
                                                                     edge_taps[e] + cursor[e], wpanel + std::ptrdiff_t(s0) * MR, koff,
                                                                     sp, sj, tile, k0 > s0);
                            } else if (k0 == s0) {
                                for (int i = 0; i < NR * MR; ++i) tile[i] = T(0);  // no tap of the block: the chain starts at 0
                            }
                        }
                    }
                }
                if (skip)
                    for (int e = 0; e < top + (rows - bottom); ++e) cursor[e] = block_end[e];
            }
            // the chain into the running sums: (sum + chain) + bias (the first chain) or + 0
            for (int i = 0; i < MR; ++i) bv[i] = (s0 == 0 && bias && i < no) ? bias[o0 + i] : T(0);
            B b[NV];
            for (int q = 0; q < NV; ++q) b[q] = B::load_aligned(bv + q * L);
            const bool from_zero = s0 == 0 && !accumulate_out;  // (0 + chain) + bias, without reading sum
            for (int n = 0; n < images; ++n) {
                T* sn = sum + n * tile_image;
                const T* an = acc + n * tile_image;
                for (std::size_t e = 0; e < n_acc; e += MR)
                    for (int q = 0; q < NV; ++q) {
                        const B before = from_zero ? B(T(0)) : B::load_aligned(sn + e + q * L);
                        ((before + B::load_aligned(an + e + q * L)) + b[q]).store_aligned(sn + e + q * L);
                    }
            }
        }
        for (int n = 0; n < images; ++n) {
            const T* t = sum + n * tile_image;
            T* yn = y + n * y_image;
            for (int r = 0; r < rows; ++r)
                for (int q0 = 0; q0 < cols; q0 += NR, t += NR * MR) {
                    const int nr = std::min(NR, cols - q0);
                    for (int i = 0; i < no; ++i) {
                        T* yo = yn + std::ptrdiff_t(o0 + i) * y_chan + r * cols + q0;
                        for (int q = 0; q < nr; ++q) yo[q] = t[q * MR + i];
                    }
                }
        }
    }
}

/// Lanes [0, valid) of one vector of panel weights: p[lane * stride] (the other lanes 0). One gather where the
/// target has it for T (conv_simd.hpp's vector_gather_type), else lane by lane.
template <class T>
inline simd_t<T> ws_strided(const T* p, std::int32_t stride, int valid) noexcept
{
    constexpr int L = simd_lanes<T>;
#if (defined(__AVX512F__) || defined(__AVX2__)) && (defined(__x86_64__) || defined(__i386__))
    if constexpr (vector_gather_type<T>) {
        using I = xsimd::batch<std::int32_t>;
        const auto idx = static_cast<typename I::register_type>(I(stride) * I(xsimd::detail::make_sequence_as_batch<I>()));
#if defined(__AVX512F__)
        const __mmask16 m = valid >= L ? __mmask16(0xffff) : __mmask16((1u << valid) - 1u);
        return simd_t<T>(_mm512_mask_i32gather_ps(_mm512_setzero_ps(), m, idx, p, int(sizeof(float))));
#else
        const __m256 m = _mm256_castsi256_ps(_mm256_cmpgt_epi32(_mm256_set1_epi32(valid), _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7)));
        return simd_t<T>(_mm256_mask_i32gather_ps(_mm256_setzero_ps(), p, idx, m, int(sizeof(float))));
#endif
    }
#endif
    alignas(64) T v[L];
    for (int i = 0; i < L; ++i) v[i] = i < valid ? p[std::ptrdiff_t(i) * stride] : T(0);
    return simd_t<T>::load_aligned(v);
}

/// Panels as ws_pack writes them, one vector of channels at a time: block(o, n, d, MR) writes
/// rows 0 .. K - 1 of channels o .. o + n - 1 (n <= L, the other lanes 0) at d + k MR. Channels past co are zeros.
template <class T, class Block>
inline void ws_pack_blocks(int co, int K, T* dst, Block&& block) noexcept
{
    constexpr int L = simd_lanes<T>;
    const int NV = ws_tile_for<T>(co).nv, MR = NV * L, panels = (co + MR - 1) / MR;
    for (int pn = 0; pn < panels; ++pn)
        for (int q = 0; q < NV; ++q) {
            const int o = pn * MR + q * L;
            T* d = dst + std::ptrdiff_t(pn) * K * MR + q * L;
            if (o >= co) {
                for (int k = 0; k < K; ++k) simd_t<T>(T(0)).store_aligned(d + std::ptrdiff_t(k) * MR);
                continue;
            }
            block(o, std::min(L, co - o), d, MR);
        }
}

/// Panels as ws_pack writes them, one vector of channels at a time: vec(o, k, n) gives channels o .. o + n - 1 of
/// row k (n <= simd_lanes<T>, the other lanes 0).
template <class T, class Vec>
inline void ws_pack_vectors(int co, int K, T* dst, Vec&& vec) noexcept
{
    ws_pack_blocks<T>(co, K, dst, [&](int o, int n, T* d, int MR) {
        for (int k = 0; k < K; ++k) vec(o, k, n).store_aligned(d + std::ptrdiff_t(k) * MR);
    });
}

/// ws_pack of a weight matrix w [co, K] (row o at w + o K): value(o, k) = w[o K + k]; transposed in blocks of L x L
/// where ws_transpose_type<T>, else gathered K apart.
template <class T>
inline void ws_pack_rows(int co, int K, const T* w, T* dst) noexcept
{
    if constexpr (ws_transpose_type<T>) {
        constexpr int L = simd_lanes<T>;
        ws_pack_blocks<T>(co, K, dst, [&](int o, int n, T* d, int MR) {
            simd_t<T> v[L];
            for (int k0 = 0; k0 < K; k0 += L) {
                const int nc = std::min(L, K - k0);
                ws_transpose_block<T>(w + std::ptrdiff_t(o) * K + k0, K, n, nc, v);
                for (int j = 0; j < nc; ++j) v[j].store_aligned(d + std::ptrdiff_t(k0 + j) * MR);
            }
        });
    } else {
        ws_pack_vectors<T>(co, K, dst, [&](int o, int k, int n) { return ws_strided<T>(w + std::ptrdiff_t(o) * K + k, K, n); });
    }
}

/// ws_pack of the flipped, channel-swapped kernel whose stride-1 forward pass is the backward-data of a
/// convolution with weights w [co, ci, kk taps] (conv_simd.hpp's backward_data_stride1): a convolution with ci
/// output channels and K = co kk, value(c, (o, t)) = w[(o ci + c) kk + kk - 1 - t]; for each o, the taps of L
/// channels transposed in blocks of L where ws_transpose_type<T>, else gathered kk apart.
template <class T>
inline void ws_pack_flipped(int co, int ci, int kk, const T* w, T* dst) noexcept
{
    if constexpr (ws_transpose_type<T>) {
        constexpr int L = simd_lanes<T>;
        ws_pack_blocks<T>(ci, co * kk, dst, [&](int c, int n, T* d, int MR) {
            simd_t<T> v[L];
            for (int o = 0; o < co; ++o)
                for (int t0 = 0; t0 < kk; t0 += L) {
                    const int nc = std::min(L, kk - t0);
                    ws_transpose_block<T>(w + (std::ptrdiff_t(o) * ci + c) * kk + t0, kk, n, nc, v);
                    for (int j = 0; j < nc; ++j)  // tap t0 + j is row k = o kk + kk - 1 - (t0 + j)
                        v[j].store_aligned(d + (std::ptrdiff_t(o) * kk + kk - 1 - t0 - j) * MR);
                }
        });
    } else {
        ws_pack_vectors<T>(ci, co * kk, dst, [&](int c, int k, int n) {
            const int o = k / kk, t = k % kk;
            return ws_strided<T>(w + (std::ptrdiff_t(o) * ci + c) * kk + kk - 1 - t, kk, n);
        });
    }
}

/// y (+)= conv(x, W) + bias for a convolution of geometry g with at least simd_lanes<T> output channels, the
/// weights given by pack(panels), which either writes them into `panels` (scratch) as ws_pack does (value(o, k) of
/// w [out, in, kh, kw]: w[o K + k]) and returns `panels`, or returns panels packed so before (a tape packs a
/// parameter once for all of its convolutions). scratch: forward_ws_scratch_elements<T>(g) elements (any
/// alignment). The same bits as conv_simd.hpp's packed and stride-1 forward paths (not its dot path).
template <class T, class Pack>
inline void forward_ws(const conv_geometry& g, const T* x, Pack&& pack, const T* bias, T* y, T* scratch,
                       bool accumulate_out) noexcept
{
    const ws_scratch_layout<T> lay(g);
    const int Hp = g.in_h + 2 * g.pad, Wp = g.in_w + 2 * g.pad;
    T* wp = align_up(scratch);
    T* acc = wp + lay.panels;
    T* sum = acc + std::size_t(lay.group) * lay.tiles;
    T* xp = sum + std::size_t(lay.group) * lay.tiles;
    const T* const panels = pack(wp);
    const std::size_t x_per = std::size_t(g.in_channels) * g.in_h * g.in_w, y_per = std::size_t(g.out_channels) * g.out_h() * g.out_w();
    // the padding of each image's buffer is written once; the interiors at every group
    std::memset(xp, 0, std::size_t(std::min(lay.group, g.batch)) * lay.padded * sizeof(T));
    ws_with_tile<T>(g.out_channels, g.stride, [&]<int NV, int NR, int SJ>() {
        for (int n0 = 0; n0 < g.batch; n0 += lay.group) {
            const int images = std::min(lay.group, g.batch - n0);
            for (int n = 0; n < images; ++n)
                copy_into_padded(xp + n * lay.padded, Hp, Wp, g.pad, g.pad, x + (n0 + n) * x_per, g.in_channels, g.in_h, g.in_w);
            ws_run_chains<T, NV, NR, SJ>(g, Hp, Wp, panels, images, xp, lay.padded, bias, y + n0 * y_per, y_per, acc, sum,
                                         lay.tiles, accumulate_out);
        }
    });
}

// ------------------------------------------------------------------------------------------- weight gradients
// gw[o, k] += sum_{n,p} gy[n,o,p] x[n, c, window of p + (u, v)], k = (c, u, v). conv_simd.hpp's packed
// backward_weight vectorises along k, so it packs every image's im2col windows (kh kw copies of each input
// element, one gather per vector) to reuse each only out_channels times. Here the tile of the weight-stationary
// kernel is turned around: its vectors run along the output channels, read from gy transposed into blocks of
// [pixel][channel] (one copy of each gradient element), and its broadcasts read the NR taps k straight from a
// zero-padded copy of the image, as the forward pass reads its pixels. Each (o, k) lane sums its products in
// the packed path's order, images then pixels, from zero, and the sums are added to gw once at the end: the
// same bits. The tiles take the taps kernel row first (k' = (u, c, v)), so that most tiles lie on one kernel row
// and skip the output rows whose window puts that row on the zero padding above or below the image: those
// products are +-0, which leave a sum that starts at +0 as it is (the same bits, for fewer multiply-adds; at the
// generator's residual blocks, 3 rows of pixels and a 3 x 3 kernel, 2 in 9).

/// Pixels of gy per transposed block: one block of a panel ([pixels][MR], 32 KiB for 128 pixels and 64 float
/// channels) stays in L1 while every tile of taps runs over it. Images with fewer pixels go in groups.
inline constexpr int wg_block_pixels = 128;

/// The parts of backward_weight_ws's scratch (elements of T, each part 64-byte aligned) for geometry g.
template <class T>
struct wg_scratch_layout {
    std::size_t sums, block, offsets, padded;  // per call ([panel][K][MR]); one block of one panel; K tap
                                               // offsets and K rows of the sums (int); per image
    int group;                        // images per group
    int runs;                         // output rows (runs of out_w pixels) per block
    std::size_t total;
    explicit wg_scratch_layout(const conv_geometry& g) noexcept
    {
        constexpr std::size_t a = 64 / sizeof(T);
        auto up = [](std::size_t n) { return (n + a - 1) / a * a; };
        const ws_tile t = ws_tile_for<T>(g.out_channels);
        const std::size_t MR = std::size_t(t.nv) * simd_lanes<T>;
        sums = up(ws_packed_elements<T>(g.out_channels, g.in_channels * g.kernel_h * g.kernel_w));
        runs = std::max(1, wg_block_pixels / g.out_w());
        block = up(std::size_t(runs) * g.out_w() * MR);
        const std::size_t K = std::size_t(g.in_channels) * g.kernel_h * g.kernel_w;
        offsets = up((2 * K * sizeof(int) + sizeof(T) - 1) / sizeof(T));
        padded = up(std::size_t(g.in_channels) * (g.in_h + 2 * g.pad) * (g.in_w + 2 * g.pad));
        group = std::clamp(wg_block_pixels / (g.out_h() * g.out_w()), 1, ws_group_max);
        total = a + sums + block + offsets + std::size_t(group) * padded;
    }
};

/// The kernel rows [first, second] of backward_weight_ws's tile of taps [k0, k0 + nr) in the kernel-row-first order
/// (ck = C kw taps per kernel row).
inline std::pair<int, int> wg_tile_rows(int k0, int nr, int ck) noexcept
{
    return {k0 / ck, (k0 + nr - 1) / ck};
}

/// Whether backward_weight_ws's tile of taps on kernel rows [u0, u1] sums over output row h: some of those rows
/// lie over the image in h's window.
inline bool wg_row_kept(const conv_geometry& g, int h, int u0, int u1) noexcept
{
    const auto [lo, hi] = window_rows(h, g.stride, g.pad, g.kernel_h, g.in_h);
    return lo < hi && lo <= u1 && hi > u0;
}

/// Multiply-adds backward_weight_ws performs for geometry g (every image): each tile of taps over the output rows
/// it keeps (wg_row_kept).
template <class T>
inline double backward_weight_ws_macs(const conv_geometry& g) noexcept
{
    const int NR = ws_tile_for<T>(g.out_channels).nr, ck = g.in_channels * g.kernel_w, K = ck * g.kernel_h;
    double m = 0;
    for (int k0 = 0; k0 < K; k0 += NR) {
        const int nr = std::min(NR, K - k0);
        const auto [u0, u1] = wg_tile_rows(k0, nr, ck);
        int kept = 0;
        for (int h = 0; h < g.out_h(); ++h) kept += wg_row_kept(g, h, u0, u1) ? 1 : 0;
        m += double(nr) * kept;
    }
    return m * g.out_w() * g.out_channels * g.batch;
}

/// Elements (of T) of backward_weight_ws's scratch for geometry g. It does not depend on g.batch.
template <class T>
inline std::size_t backward_weight_ws_scratch_elements(const conv_geometry& g) noexcept
{
    return wg_scratch_layout<T>(g).total;
}

/// tile[j][0..MR) (+)= sum_{i < runs} sum_{w < len} v[(r len + w) MR + 0..MR) * src[run_off[r] + koff[j] + w sj],
/// r = run[i], j < NR taps: v is a block of gy transposed ([pixel][channel]), src the zero-padded images, run r one
/// output row (run lists the block's rows the tile does not skip, in order). SJ > 0 fixes the stride at compile
/// time, as in micro_ws.
template <class T, int NV, int NR, int SJ>
[[gnu::noinline]] inline void micro_wg(int runs, const int* __restrict run, const std::ptrdiff_t* __restrict run_off, int len,
                                       const T* __restrict vb, const T* __restrict src, const int* __restrict koff, int sj,
                                       T* __restrict tile, bool accumulate) noexcept
{
    using B = simd_t<T>;
    constexpr int L = simd_lanes<T>, MR = NV * L;
    B acc[NR][NV];
    ws_tile_begin<T, NV, NR>(acc, tile, accumulate);
    const int step = SJ > 0 ? SJ : sj;
    for (int i = 0; i < runs; ++i) {
        const int r = run[i];
        const T* v = vb + std::ptrdiff_t(r) * len * MR;
        const T* sp[NR];
        HANDEMO_UNROLL_TILE
        for (int j = 0; j < NR; ++j) sp[j] = src + run_off[r] + koff[j];
        for (int w = 0; w < len; ++w) {
            B a[NV];
            HANDEMO_UNROLL_TILE
            for (int q = 0; q < NV; ++q) a[q] = keep_in_register(B::load_aligned(v + q * L));
            HANDEMO_UNROLL_TILE
            for (int j = 0; j < NR; ++j) {
                const B b(sp[j][w * step]);
                HANDEMO_UNROLL_TILE
                for (int q = 0; q < NV; ++q) acc[j][q] = xsimd::fma(a[q], b, acc[j][q]);
            }
            v += MR;
        }
    }
    ws_tile_end<T, NV, NR>(acc, tile);
}

/// micro_wg<T, NV, nr, SJ> for nr = 1..N.
template <class T, int NV, int N, int SJ>
inline void micro_wg_dispatch(int nr, int runs, const int* run, const std::ptrdiff_t* run_off, int len, const T* v,
                              const T* src, const int* koff, int sj, T* tile, bool accumulate) noexcept
{
    with_tile_width<N>(nr, [&]<int R>() { micro_wg<T, NV, R, SJ>(runs, run, run_off, len, v, src, koff, sj, tile, accumulate); });
}

/// dst[p MR + l] = gy[(o0 + l) P + p] for p < pixels, l < MR (0 for channels past co): pixels of one image's
/// gradient (channel stride P) transposed into a block of a panel.
template <class T>
inline void wg_transpose(const T* gy, std::ptrdiff_t P, int o0, int co, int MR, int pixels, T* dst) noexcept
{
    constexpr int L = simd_lanes<T>;
    for (int q = 0; q < MR; q += L) {
        const int o = o0 + q, n = std::clamp(co - o, 0, L);
        if constexpr (ws_transpose_type<T>) {
            simd_t<T> v[L];
            for (int p0 = 0; p0 < pixels; p0 += L) {
                const int nc = std::min(L, pixels - p0);
                if (n > 0) ws_transpose_block<T>(gy + std::ptrdiff_t(o) * P + p0, P, n, nc, v);
                for (int j = 0; j < nc; ++j)
                    (n > 0 ? v[j] : simd_t<T>(T(0))).store_aligned(dst + std::ptrdiff_t(p0 + j) * MR + q);
            }
        } else {
            for (int p = 0; p < pixels; ++p)
                for (int l = 0; l < L; ++l) dst[std::ptrdiff_t(p) * MR + q + l] = l < n ? gy[std::ptrdiff_t(o + l) * P + p] : T(0);
        }
    }
}

/// gw[o K + k] += sums[(pn K + sum_row[k]) MR + o - pn MR], pn = o / MR: the sums' panels (their rows in the
/// order `sum_row` gives) added to the weight gradient [co][K], in blocks of L x L transposed in registers where
/// ws_transpose_type<T> (one strided read per element was a fifth of the residual conv's time: each a different
/// cache line of a panel larger than L2).
template <class T>
inline void wg_add_sums(int co, int K, int MR, const T* sums, const int* sum_row, T* gw) noexcept
{
    constexpr int L = simd_lanes<T>;
    for (int o = 0; o < co; o += L) {
        const int pn = o / MR, n = std::min(L, co - o);
        const T* src = sums + std::ptrdiff_t(pn) * K * MR + (o - pn * MR);
        if constexpr (ws_transpose_type<T>) {
            simd_t<T> v[L];
            alignas(64) T row[L];
            for (int k0 = 0; k0 < K; k0 += L) {
                const int nk = std::min(L, K - k0);
                ws_transpose_rows<T>([&](int i) { return src + std::ptrdiff_t(sum_row[k0 + i]) * MR; }, nk, n, v);  // v[i]: channel o + i, taps k0..
                for (int i = 0; i < n; ++i) {
                    T* dst = gw + std::ptrdiff_t(o + i) * K + k0;
                    if (nk == L) {
                        (simd_t<T>::load_unaligned(dst) + v[i]).store_unaligned(dst);
                    } else {
                        v[i].store_aligned(row);
                        for (int k = 0; k < nk; ++k) dst[k] += row[k];
                    }
                }
            }
        } else {
            for (int k0 = 0; k0 < K; k0 += L)
                for (int i = 0; i < n; ++i)
                    for (int k = k0; k < std::min(K, k0 + L); ++k) gw[std::ptrdiff_t(o + i) * K + k] += src[std::ptrdiff_t(sum_row[k]) * MR + i];
        }
    }
}

/// gw += dL/dw of a convolution of geometry g (x the input, gy the output gradient; swapped for the transposed
/// convolution, as for conv_simd.hpp's backward_weight) with the vectors along the output channels (see above).
/// scratch: backward_weight_ws_scratch_elements<T>(g) elements (any alignment). The same bits as conv_simd.hpp's
/// packed backward_weight.
template <class T>
inline void backward_weight_ws(const conv_geometry& g, const T* x, const T* gy, T* gw, T* scratch) noexcept
{
    const wg_scratch_layout<T> lay(g);
    const int Hp = g.in_h + 2 * g.pad, Wp = g.in_w + 2 * g.pad, oh = g.out_h(), ow = g.out_w(), P = oh * ow;
    const int C = g.in_channels, kh = g.kernel_h, kw = g.kernel_w, K = C * kh * kw, co = g.out_channels, ck = C * kw;
    T* sums = align_up(scratch);
    T* vb = sums + lay.sums;
    int* koff = reinterpret_cast<int*>(vb + lay.block);
    int* row = koff + K;
    T* xp = vb + lay.block + lay.offsets;
    // the tiles' taps kernel row first: k' = (u, c, v) reads its window at koff[k'] and sums into row k' of the
    // panels; tap k = (c, u, v) of the weights is row[k]
    padded_window_offsets_row_first(C, kh, kw, Hp, Wp, koff);
    for (int u = 0, k = 0; u < kh; ++u)
        for (int c = 0; c < C; ++c)
            for (int v = 0; v < kw; ++v) row[(c * kh + u) * kw + v] = k++;
    const std::size_t x_per = std::size_t(g.in_channels) * g.in_h * g.in_w, y_per = std::size_t(co) * P;
    std::memset(xp, 0, std::size_t(std::min(lay.group, g.batch)) * lay.padded * sizeof(T));
    ws_with_tile<T>(co, g.stride, [&]<int NV, int NR, int SJ>() {
        constexpr int MR = NV * simd_lanes<T>;
        const int panels = (co + MR - 1) / MR;
        std::ptrdiff_t run_off[wg_block_pixels];
        int run_row[wg_block_pixels];  // each run's output row in its image
        int kept[wg_block_pixels];     // the runs a tile sums over
        for (int n0 = 0; n0 < g.batch; n0 += lay.group) {
            const int images = std::min(lay.group, g.batch - n0);
            for (int n = 0; n < images; ++n)
                copy_into_padded(xp + n * lay.padded, Hp, Wp, g.pad, g.pad, x + (n0 + n) * x_per, g.in_channels, g.in_h, g.in_w);
            const int runs = images * oh;
            for (int pn = 0; pn < panels; ++pn)
                for (int r0 = 0; r0 < runs; r0 += lay.runs) {
                    const int nruns = std::min(lay.runs, runs - r0);
                    // the block's runs: their offsets in the padded images and their gradients transposed
                    for (int r = r0; r < r0 + nruns;) {
                        const int n = r / oh, h = r % oh, rows = std::min(oh - h, r0 + nruns - r);
                        for (int i = 0; i < rows; ++i) {
                            run_off[r - r0 + i] = std::ptrdiff_t(n) * lay.padded + std::ptrdiff_t(h + i) * g.stride * Wp;
                            run_row[r - r0 + i] = h + i;
                        }
                        wg_transpose<T>(gy + (n0 + n) * y_per + std::ptrdiff_t(h) * ow, P, pn * MR, co, MR, rows * ow,
                                        vb + std::ptrdiff_t(r - r0) * ow * MR);
                        r += rows;
                    }
                    const bool accumulate = n0 > 0 || r0 > 0;
                    int u_first = -1, u_last = -1, nkept = 0;  // the kernel rows `kept` was listed for
                    for (int k0 = 0; k0 < K; k0 += NR) {
                        const int nr = std::min(NR, K - k0);
                        const auto [u0, u1] = wg_tile_rows(k0, nr, ck);
                        if (u0 != u_first || u1 != u_last) {
                            // the runs that place one of the tile's kernel rows [u0, u1] over the image
                            u_first = u0, u_last = u1, nkept = 0;
                            for (int r = 0; r < nruns; ++r)
                                if (wg_row_kept(g, run_row[r], u0, u1)) kept[nkept++] = r;
                        }
                        if (nkept == 0 && accumulate) continue;
                        micro_wg_dispatch<T, NV, NR, SJ>(nr, nkept, kept, run_off, ow, vb, xp, koff + k0, g.stride,
                                                         sums + (std::ptrdiff_t(pn) * K + k0) * MR, accumulate);
                    }
                }
        }
        wg_add_sums<T>(co, K, MR, sums, row, gw);
    });
}

}  // namespace handemo::kernels::detail
