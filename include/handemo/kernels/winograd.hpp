// Winograd's minimal filtering for 3x3 stride-1 convolutions with weights that do not change (the residual
// blocks of the StarGAN generator of Chan et al. 2020, Sec. 3.3, Fig. 3: 2 x 6 of the paper G's 3x3
// convolutions at 256 channels, about three quarters of its multiply-adds), after Lavin & Gray, "Fast Algorithms
// for Convolutional Neural Networks" (CVPR 2016). An output tile of m_h x m_w pixels is
//     Y = A_h^T [ U (.) V ] A_w,   U = G_h g G_w^T per (out, in) channel pair,   V = B_h^T d B_w per input tile d,
// where (.) multiplies element by element and the sum over the input channels runs inside it: for each of the
// (m_h + 2)(m_w + 2) transform points one GEMM of [out channels x in channels] by [in channels x tiles]. The
// generator's 3 x 6 bottleneck is one row of three F(3x2, 3x3) tiles: 20 multiplies per 6 outputs and input channel
// where the direct convolution does 54 (2.7x fewer). The transformed weights (20/9 of the direct weights' bytes)
// are made once.
//
// The 1-D transforms F(m, 3) are Toom-Cook's, built here from their interpolation points (0, 1, -1, 2 and
// infinity; m = 2 stops at -1): with E_k the n x k matrix whose row i is (1, p_i, p_i^2, ...) (the row of
// infinity (0, ..., 0, 1)), the correlation y = A^T [(G g) (.) (B^T d)] has A^T = E_m^T, G = E_3 and
// B^T = E_n^-T (the transposition principle applied to the polynomial product of Toom-Cook). Each row of B^T
// is scaled to largest magnitude 1 and G's row by the inverse. In binary32 these transforms keep the error within a
// few times the direct sum's (tests/kernels/winograd_test.cpp holds them to it against a double-precision convolution).
//
// Where: batched inference (stargan::frozen_generator with conv_algorithm::winograd), where the tiles of many
// images share each block of transformed weights. The transformed weights are 20/9 of the direct panels' bytes
// (68 MB for the paper G): at batch 1 the paper G streams them for three tiles each and is no faster than with the
// direct weight-stationary kernel; the embedded G's (9 MB) stay in the L3 (docs/performance.md).
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstring>
#include <string>
#include <vector>

#include <handemo/core/error.hpp>
#include <handemo/kernels/conv.hpp>
#include <handemo/kernels/detail/packed_conv.hpp>
#include <handemo/kernels/packed.hpp>
#include <handemo/tensor/aligned.hpp>

namespace handemo::kernels {

/// @brief How stargan::frozen_generator computes its 3x3 stride-1 (residual) convolutions.
/// - direct: the weight-stationary kernel of packed_conv, every image alone; the default.
/// - winograd: winograd_conv3x3, the tiles of a group of images per GEMM (faster on batches; the sums in
///   another order, so the results differ from direct's in the last bits: within a few times the direct sum's
///   rounding error, docs/engine.md).
enum class conv_algorithm { direct, winograd };

/// @brief "direct" or "winograd".
inline const char* conv_algorithm_name(conv_algorithm a) noexcept { return a == conv_algorithm::winograd ? "winograd" : "direct"; }

namespace detail {

constexpr double winograd_abs(double v) noexcept { return v < 0 ? -v : v; }

/// The 1-D transform matrices of F(M, 3) (see the file's comment), n = M + 2 points.
template <int M>
struct winograd_1d {
    static constexpr int n = M + 2;
    std::array<std::array<double, 3>, n> g{};   // G, n x 3
    std::array<std::array<double, n>, n> bt{};  // B^T, n x n
    std::array<std::array<double, n>, M> at{};  // A^T, M x n
};

template <int M>
constexpr winograd_1d<M> make_winograd_1d() noexcept
{
    static_assert(M == 2 || M == 3, "winograd: F(2, 3) and F(3, 3) only");
    constexpr int n = M + 2;
    constexpr double pts[] = {0.0, 1.0, -1.0, 2.0};
    // row i of E_k: p_i^j (j < k); the last row: infinity, (0, ..., 0, 1)
    auto e = [&](int i, int j, int k) {
        if (i == n - 1) return j == k - 1 ? 1.0 : 0.0;
        double v = 1.0;
        for (int t = 0; t < j; ++t) v *= pts[i];
        return v;
    };
    winograd_1d<M> r;
    for (int i = 0; i < M; ++i)
        for (int a = 0; a < n; ++a) r.at[std::size_t(i)][std::size_t(a)] = e(a, i, M);
    for (int a = 0; a < n; ++a)
        for (int k = 0; k < 3; ++k) r.g[std::size_t(a)][std::size_t(k)] = e(a, k, 3);
    // E_n^-1 by Gauss-Jordan with partial pivoting, then B^T = (E_n^-1)^T
    std::array<std::array<double, 2 * n>, n> aug{};
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
            aug[std::size_t(i)][std::size_t(j)] = e(i, j, n);
            aug[std::size_t(i)][std::size_t(n + j)] = i == j ? 1.0 : 0.0;
        }
    for (int c = 0; c < n; ++c) {
        int piv = c;
        for (int i = c + 1; i < n; ++i)
            if (winograd_abs(aug[std::size_t(i)][std::size_t(c)]) > winograd_abs(aug[std::size_t(piv)][std::size_t(c)])) piv = i;
        std::swap(aug[std::size_t(c)], aug[std::size_t(piv)]);
        const double d = aug[std::size_t(c)][std::size_t(c)];
        for (int j = 0; j < 2 * n; ++j) aug[std::size_t(c)][std::size_t(j)] /= d;
        for (int i = 0; i < n; ++i) {
            if (i == c) continue;
            const double f = aug[std::size_t(i)][std::size_t(c)];
            for (int j = 0; j < 2 * n; ++j) aug[std::size_t(i)][std::size_t(j)] -= f * aug[std::size_t(c)][std::size_t(j)];
        }
    }
    for (int a = 0; a < n; ++a)
        for (int j = 0; j < n; ++j) r.bt[std::size_t(a)][std::size_t(j)] = aug[std::size_t(j)][std::size_t(n + a)];
    // scale each row of B^T to largest magnitude 1, G's row by the inverse
    for (int a = 0; a < n; ++a) {
        double s = 0;
        for (int j = 0; j < n; ++j) s = std::max(s, winograd_abs(r.bt[std::size_t(a)][std::size_t(j)]));
        for (int j = 0; j < n; ++j) r.bt[std::size_t(a)][std::size_t(j)] /= s;
        for (int k = 0; k < 3; ++k) r.g[std::size_t(a)][std::size_t(k)] *= s;
    }
    // entries within rounding of a small integer or half are set to it: the zeros must be exact, so that the
    // transforms below skip them at compile time
    for (auto& row : r.bt)
        for (auto& v : row) {
            const double h = double(static_cast<long long>(v * 2 + (v < 0 ? -0.5 : 0.5))) / 2;
            if (winograd_abs(v - h) < 1e-12) v = h;
        }
    return r;
}

template <int M>
inline constexpr winograd_1d<M> winograd_matrices = make_winograd_1d<M>();

/// acc (+)= c * v for a coefficient known at compile time once the caller's loops are unrolled: nothing for 0,
/// an add or a subtract for +-1. first: acc is not yet set.
template <class B>
inline void winograd_axpy(B& acc, bool& first, double c, const B& v) noexcept
{
    using T = typename B::value_type;
    if (c == 0.0) return;
    if (first) {
        acc = c == 1.0 ? v : c == -1.0 ? -v : B(T(c)) * v;
        first = false;
        return;
    }
    if (c == 1.0) acc += v;
    else if (c == -1.0) acc -= v;
    else acc = xsimd::fma(B(T(c)), v, acc);
}

/// out(a, b) = (L x R^T)[a][b] for the RI x CI vectors x(i, j), a < RO, b < CO: the 2-D transform of one tile
/// with the compile-time matrices L (RO x RI) and R (CO x CI), as a 1-D transform of each column, then of each row.
template <class T, int RO, int RI, int CO, int CI, class M1, class M2, class In, class Out>
inline void winograd_transform_2d(const M1& l, const M2& r, In&& x, Out&& out) noexcept
{
    using B = simd_t<T>;
    B t[RO][CI];
    HANDEMO_UNROLL_TILE
    for (int j = 0; j < CI; ++j) {
        B col[RI];
        HANDEMO_UNROLL_TILE
        for (int i = 0; i < RI; ++i) col[i] = x(i, j);
        HANDEMO_UNROLL_TILE
        for (int a = 0; a < RO; ++a) {
            bool first = true;
            t[a][j] = B(T(0));
            HANDEMO_UNROLL_TILE
            for (int i = 0; i < RI; ++i) winograd_axpy(t[a][j], first, l[std::size_t(a)][std::size_t(i)], col[i]);
        }
    }
    HANDEMO_UNROLL_TILE
    for (int a = 0; a < RO; ++a)
        HANDEMO_UNROLL_TILE
        for (int b = 0; b < CO; ++b) {
            B acc(T(0));
            bool first = true;
            HANDEMO_UNROLL_TILE
            for (int j = 0; j < CI; ++j) winograd_axpy(acc, first, r[std::size_t(b)][std::size_t(j)], t[a][j]);
            out(a, b, acc);
        }
}

/// V[(a*NW + b) * v_point] = (B_h^T d B_w)[a][b] for one input tile d of NH x NW vectors (one vector of input
/// channels each) at d + i*d_row + j*d_col.
template <class T, int MH, int MW>
inline void winograd_input_tile(const T* d, std::ptrdiff_t d_row, std::ptrdiff_t d_col, T* v, std::ptrdiff_t v_point) noexcept
{
    using B = simd_t<T>;
    constexpr int NH = MH + 2, NW = MW + 2;
    winograd_transform_2d<T, NH, NH, NW, NW>(
        winograd_matrices<MH>.bt, winograd_matrices<MW>.bt, [&](int i, int j) { return B::load_aligned(d + i * d_row + j * d_col); },
        [&](int a, int b, const B& r) { r.store_aligned(v + (a * NW + b) * v_point); });
}

/// out[i*o_row + j*o_col] = (A_h^T m A_w)[i][j] for the NH x NW transform-point vectors at m + (a*NW + b)*m_point.
template <class T, int MH, int MW>
inline void winograd_output_tile(const T* m, std::ptrdiff_t m_point, T* out, std::ptrdiff_t o_row, std::ptrdiff_t o_col) noexcept
{
    using B = simd_t<T>;
    constexpr int NH = MH + 2, NW = MW + 2;
    winograd_transform_2d<T, MH, NH, MW, NW>(
        winograd_matrices<MH>.at, winograd_matrices<MW>.at, [&](int a, int b) { return B::load_aligned(m + (a * NW + b) * m_point); },
        [&](int i, int j, const B& r) { r.store_aligned(out + i * o_row + j * o_col); });
}

/// Calls f.template operator()<MH, MW>() for the runtime tile (mh, mw), each 2 or 3.
template <class F>
inline void winograd_with_tile(int mh, int mw, F&& f)
{
    if (mh == 3) {
        if (mw == 3) f.template operator()<3, 3>();
        else f.template operator()<3, 2>();
    } else {
        if (mw == 3) f.template operator()<2, 3>();
        else f.template operator()<2, 2>();
    }
}

}  // namespace detail

/// @brief A 3x3 stride-1 pad-1 convolution (any size, NCHW) with its weights transformed once for Winograd's
/// F(m_h x m_w, 3x3) (see the file's comment): m = 3 along a dimension whose tiles then waste no more pixels than
/// with m = 2, else 2. A snapshot of the weights, as packed_conv.
template <class T>
class winograd_conv3x3 {
public:
    winograd_conv3x3() = default;

    /// @brief Whether this kernel takes geometry g: kernel 3x3, stride 1, pad 1, T a SIMD type
    /// (kernels::detail::fast_type), in_channels a multiple of the SIMD width and out_channels at least one
    /// vector. Elsewhere use packed_conv.
    static bool supported(const conv_geometry& g) noexcept
    {
        if constexpr (!detail::fast_type<T>) return false;
        else
            return g.valid() && g.kernel_h == 3 && g.kernel_w == 3 && g.stride == 1 && g.pad == 1 &&
                   g.in_channels % detail::simd_lanes<T> == 0 && g.out_channels >= detail::simd_lanes<T>;
    }

    /// @brief Transforms the weights w [out_channels, in_channels, 3, 3] (in double precision, then rounded to T
    /// once). storage f16: the weights are first rounded to binary16 (as packed_conv's), the transformed weights
    /// kept in T. group: images per GEMM (0: the default, group_default).
    /// @throws value_error when !supported(g) (naming the geometry) or, with f16, for a weight binary16 cannot hold.
    winograd_conv3x3(const conv_geometry& g, const T* w, weight_storage storage = weight_storage::native, int group = 0)
        : g_(g), storage_(storage)
    {
        if (!supported(g))
            throw value_error("winograd_conv3x3: geometry " + std::to_string(g.in_channels) + "x" + std::to_string(g.in_h) +
                              "x" + std::to_string(g.in_w) + " -> " + std::to_string(g.out_channels) + ", kernel " +
                              std::to_string(g.kernel_h) + "x" + std::to_string(g.kernel_w) + ", stride " + std::to_string(g.stride) +
                              ", pad " + std::to_string(g.pad) + " is not a 3x3 stride-1 pad-1 convolution with a multiple of " +
                              std::to_string(detail::simd_lanes<T>) + " input channels");
        if (group < 0 || group > 4096) throw value_error("winograd_conv3x3: group " + std::to_string(group) + " (0 to 4096)");
        std::vector<T> rounded;
        if (storage == weight_storage::f16) {
            rounded = binary16_rounded(w, g.w_size());
            w = rounded.data();
        }
        // m = 3 only along an odd length, where tiles of 2 would overhang the image, and where it then needs no
        // more input pixels than m = 2 (ceil(len/3)*5 <= ceil(len/2)*4): it multiplies the sums' rounding errors
        // about three times as much as m = 2 (tests/kernels/winograd_test.cpp)
        auto pick = [](int len) { return len % 2 == 1 && (len + 2) / 3 * 5 <= (len + 1) / 2 * 4 ? 3 : 2; };
        mh_ = pick(g.in_h), mw_ = pick(g.in_w);
        th_ = (g.in_h + mh_ - 1) / mh_, tw_ = (g.in_w + mw_ - 1) / mw_;
        points_ = (mh_ + 2) * (mw_ + 2);
        group_ = group ? group : group_default;
        const detail::ws_tile t = detail::ws_tile_for<T>(g.out_channels);
        mr_ = t.nv * detail::simd_lanes<T>;
        panels_ = (g.out_channels + mr_ - 1) / mr_;
        panel_elements_ = detail::ws_packed_elements<T>(g.out_channels, g.in_channels);
        u_ = aligned_buffer<T>(panel_elements_ * std::size_t(points_));
        detail::winograd_with_tile(mh_, mw_, [&]<int MH, int MW>() { transform_weights<MH, MW>(w); });
        koff_.resize(std::size_t(g.in_channels));
        for (int c = 0; c < g.in_channels; ++c) koff_[std::size_t(c)] = c;
        // scratch: V [points][tiles][in], M [points][panels][tiles][MR], the padded transposed image
        // [Hp][Wp][in] and the output tiles [th*mh][tw*mw][panels*MR], each 64-byte aligned
        const std::size_t tiles = std::size_t(group_) * th_ * tw_;
        v_elements_ = round_up(std::size_t(points_) * tiles * g.in_channels);
        m_elements_ = round_up(std::size_t(points_) * panels_ * tiles * mr_);
        x_elements_ = round_up(std::size_t(th_ * mh_ + 2) * (tw_ * mw_ + 2) * g.in_channels);
        y_elements_ = round_up(std::size_t(th_ * mh_) * (tw_ * mw_) * panels_ * mr_);
    }

    /// @brief Elements of T that forward() needs as scratch (any alignment): the group's transformed tiles.
    std::size_t scratch_size() const noexcept
    {
        return v_elements_ + m_elements_ + x_elements_ + y_elements_ + tensor_alignment / sizeof(T);
    }
    /// @brief The geometry given at construction.
    const conv_geometry& geometry() const noexcept { return g_; }
    /// @brief Output tile height and width (m_h, m_w).
    int tile_h() const noexcept { return mh_; }
    int tile_w() const noexcept { return mw_; }
    /// @brief Images per GEMM.
    int group() const noexcept { return group_; }
    /// @brief The storage asked for at construction.
    weight_storage storage() const noexcept { return storage_; }
    /// @brief Bytes of the transformed weights (with the panels' zero padding).
    std::size_t weight_bytes() const noexcept { return u_.size() * sizeof(T); }
    /// @brief Multiply-adds of the GEMMs per image (the transforms' adds not counted): points x tiles x in x out.
    double macs_per_image() const noexcept { return double(points_) * th_ * tw_ * g_.in_channels * g_.out_channels; }

    /// @brief y = conv(x, w) + bias on `images` images: x [images, in, H, W], y [images, out, H, W] (overwritten),
    /// bias_or_null one value per output channel or nullptr. Each output's sums do not depend on the other images
    /// of the call, so image n of a batch gets the bits a call on that image alone gets.
    void forward(const T* x, const T* bias_or_null, T* y, T* scratch, std::size_t images) const noexcept
    {
        detail::winograd_with_tile(mh_, mw_, [&]<int MH, int MW>() { run<MH, MW>(x, bias_or_null, y, scratch, images); });
    }

    /// @brief Images per GEMM by default: chosen by measurement (docs/engine.md, "Winograd for batches").
    static constexpr int group_default = 16;

private:
    static std::size_t round_up(std::size_t n) noexcept
    {
        const std::size_t a = tensor_alignment / sizeof(T);
        return (n + a - 1) / a * a;
    }

    template <int MH, int MW>
    void transform_weights(const T* w)
    {
        constexpr auto& h = detail::winograd_matrices<MH>;
        constexpr auto& v = detail::winograd_matrices<MW>;
        constexpr int NH = MH + 2, NW = MW + 2;
        const int co = g_.out_channels, ci = g_.in_channels;
        std::vector<double> u(std::size_t(NH * NW) * co * ci);  // [point][o][c]
        for (int o = 0; o < co; ++o)
            for (int c = 0; c < ci; ++c) {
                const T* k = w + (std::ptrdiff_t(o) * ci + c) * 9;
                double t[NH][3];
                for (int a = 0; a < NH; ++a)
                    for (int q = 0; q < 3; ++q) {
                        double s = 0;
                        for (int p = 0; p < 3; ++p) s += h.g[std::size_t(a)][std::size_t(p)] * double(k[p * 3 + q]);
                        t[a][q] = s;
                    }
                for (int a = 0; a < NH; ++a)
                    for (int b = 0; b < NW; ++b) {
                        double s = 0;
                        for (int q = 0; q < 3; ++q) s += t[a][q] * v.g[std::size_t(b)][std::size_t(q)];
                        u[(std::size_t(a * NW + b) * co + o) * ci + c] = s;
                    }
            }
        for (int p = 0; p < NH * NW; ++p)
            detail::ws_pack<T>(co, ci, u_.data() + std::size_t(p) * panel_elements_,
                               [&](int o, int c) { return T(u[(std::size_t(p) * co + o) * ci + c]); });
    }

    template <int MH, int MW>
    void run(const T* x, const T* bias, T* y, T* scratch, std::size_t images) const noexcept
    {
        constexpr int L = detail::simd_lanes<T>;
        constexpr int NH = MH + 2, NW = MW + 2;
        const int ci = g_.in_channels, co = g_.out_channels, H = g_.in_h, W = g_.in_w;
        const int Wp = tw_ * MW + 2, Wo = tw_ * MW, cp = panels_ * mr_;
        const std::size_t tiles_max = std::size_t(group_) * th_ * tw_, HW = std::size_t(H) * W;
        T* v = align_up(scratch);
        T* m = v + v_elements_;
        T* xt = m + m_elements_;
        T* yt = xt + x_elements_;
        std::memset(xt, 0, x_elements_ * sizeof(T));  // the border stays zero: only the interior is written below
        const std::ptrdiff_t v_point = std::ptrdiff_t(tiles_max) * ci, m_point = std::ptrdiff_t(panels_) * tiles_max * mr_;
        for (std::size_t first = 0; first < images; first += std::size_t(group_)) {
            const std::size_t count = std::min<std::size_t>(std::size_t(group_), images - first);
            const int tiles = int(count) * th_ * tw_;
            // input tiles: the image transposed to [Hp][Wp][in] (zero-padded), transformed a vector of channels at a time
            for (std::size_t n = 0; n < count; ++n) {
                transpose_in(x + (first + n) * std::size_t(ci) * HW, xt, Wp);
                for (int ti = 0; ti < th_; ++ti)
                    for (int tj = 0; tj < tw_; ++tj) {
                        const std::ptrdiff_t q = std::ptrdiff_t(n) * th_ * tw_ + ti * tw_ + tj;
                        const T* d = xt + (std::size_t(ti * MH) * Wp + tj * MW) * ci;
                        for (int c0 = 0; c0 < ci; c0 += L)
                            detail::winograd_input_tile<T, MH, MW>(d + c0, std::ptrdiff_t(Wp) * ci, ci, v + q * ci + c0, v_point);
                    }
            }
            // one GEMM per transform point: M[p][panel][tile][MR] = sum_c U[p][panel][c][MR] V[p][tile][c]
            detail::ws_with_tile<T>(co, ci, [&]<int NV, int NR, int SJ>() {
                constexpr int MR = NV * L;
                const int kc_max = detail::ws_kc<T, T>(NV);
                for (int p = 0; p < NH * NW; ++p) {
                    const T* up = u_.data() + std::size_t(p) * panel_elements_;
                    const T* vp = v + p * v_point;
                    T* mp = m + p * m_point;
                    for (int pn = 0; pn < panels_; ++pn)
                        for (int k0 = 0; k0 < ci; k0 += kc_max) {
                            const int kc = std::min(kc_max, ci - k0);
                            const T* wp = up + (std::ptrdiff_t(pn) * ci + k0) * MR;
                            for (int q0 = 0; q0 < tiles; q0 += NR)
                                detail::micro_ws_dispatch<T, T, NV, NR, SJ>(std::min(NR, tiles - q0), kc, wp, koff_.data() + k0,
                                                                            vp + std::ptrdiff_t(q0) * ci, ci,
                                                                            mp + (std::ptrdiff_t(pn) * tiles_max + q0) * MR, k0 > 0);
                        }
                }
            });
            // output tiles: [Ho][Wo][panels*MR] per image, then transposed to [out][H][W] with the bias
            for (std::size_t n = 0; n < count; ++n) {
                for (int ti = 0; ti < th_; ++ti)
                    for (int tj = 0; tj < tw_; ++tj) {
                        const std::ptrdiff_t q = std::ptrdiff_t(n) * th_ * tw_ + ti * tw_ + tj;
                        T* out = yt + (std::size_t(ti * MH) * Wo + tj * MW) * cp;
                        for (int pn = 0; pn < panels_; ++pn)
                            for (int l = 0; l < mr_; l += L)
                                detail::winograd_output_tile<T, MH, MW>(m + (std::ptrdiff_t(pn) * tiles_max + q) * mr_ + l, m_point,
                                                                  out + pn * mr_ + l, std::ptrdiff_t(Wo) * cp, cp);
                    }
                transpose_out(yt, Wo, cp, bias, y + (first + n) * std::size_t(co) * HW);
            }
        }
    }

    // xt[(i + 1) * Wp + j + 1][c] = x[c][i][j]: blocks of L channels x L pixels transposed in registers where the
    // target has it (detail::ws_transpose_block), else element by element
    void transpose_in(const T* x, T* xt, int Wp) const noexcept
    {
        const int ci = g_.in_channels, W = g_.in_w, HW = g_.in_h * g_.in_w;
        if constexpr (detail::ws_transpose_type<T>) {
            constexpr int L = detail::simd_lanes<T>;
            detail::simd_t<T> v[L];
            for (int c0 = 0; c0 < ci; c0 += L)
                for (int p0 = 0; p0 < HW; p0 += L) {
                    const int np = std::min(L, HW - p0);
                    detail::ws_transpose_block<T>(x + std::ptrdiff_t(c0) * HW + p0, HW, L, np, v);
                    for (int k = 0; k < np; ++k) {
                        const int i = (p0 + k) / W, j = (p0 + k) % W;
                        v[k].store_aligned(xt + (std::ptrdiff_t(i + 1) * Wp + j + 1) * ci + c0);
                    }
                }
        } else {
            for (int c = 0; c < ci; ++c)
                for (int p = 0; p < HW; ++p) xt[(std::ptrdiff_t(p / W + 1) * Wp + p % W + 1) * ci + c] = x[std::ptrdiff_t(c) * HW + p];
        }
    }

    // y[o][i][j] = yt[i * Wo + j][o] + bias[o] (yt: the output tiles, [Ho][Wo][cp]); in registers as transpose_in
    // where the tiles cover the image exactly (the rows of yt are then y's pixels in order)
    void transpose_out(const T* yt, int Wo, int cp, const T* bias, T* y) const noexcept
    {
        const int co = g_.out_channels, W = g_.in_w, HW = g_.in_h * g_.in_w;
        if constexpr (detail::ws_transpose_type<T>) {
            if (Wo == W) {
                constexpr int L = detail::simd_lanes<T>;
                using B = detail::simd_t<T>;
                B v[L];
                alignas(64) T tail[L];
                for (int o0 = 0; o0 < co; o0 += L) {
                    const int no = std::min(L, co - o0);
                    for (int p0 = 0; p0 < HW; p0 += L) {
                        const int np = std::min(L, HW - p0);
                        detail::ws_transpose_block<T>(yt + std::ptrdiff_t(p0) * cp + o0, cp, np, L, v);
                        for (int k = 0; k < no; ++k) {
                            const B r = bias ? v[k] + B(bias[o0 + k]) : v[k];
                            T* dst = y + std::ptrdiff_t(o0 + k) * HW + p0;
                            if (np == L) r.store_unaligned(dst);
                            else {
                                r.store_aligned(tail);
                                std::copy_n(tail, np, dst);
                            }
                        }
                    }
                }
                return;
            }
        }
        for (int o = 0; o < co; ++o) {
            const T b = bias ? bias[o] : T(0);
            for (int p = 0; p < HW; ++p) y[std::ptrdiff_t(o) * HW + p] = yt[(std::ptrdiff_t(p / W) * Wo + p % W) * cp + o] + b;
        }
    }

    conv_geometry g_{};
    weight_storage storage_ = weight_storage::native;
    int mh_ = 2, mw_ = 2, th_ = 0, tw_ = 0, points_ = 0, group_ = 0, mr_ = 0, panels_ = 0;
    std::size_t panel_elements_ = 0, v_elements_ = 0, m_elements_ = 0, x_elements_ = 0, y_elements_ = 0;
    aligned_buffer<T> u_;
    std::vector<int> koff_;
};

}  // namespace handemo::kernels
