// Vectorised pieces of the instance normalisation that follows every convolution of the StarGAN generator
// (Chan et al. 2020, Sec. 3.3, Fig. 3; PyTorch InstanceNorm2d): the two-pass mean and biased variance of
// one channel, accumulated in double as the tape's instance_norm does, and the affine map with optional
// ReLU. Shared by generator inference and the autodiff op.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <type_traits>

#include <handemo/kernels/detail/conv_simd.hpp>

namespace handemo::kernels {

namespace detail {

/// xsimd::batch<double>::size values of p as doubles (exact). For float with AVX2 or AVX-512 one converting
/// instruction (xsimd 8's converting load goes element by element).
template <class T>
inline xsimd::batch<double> load_as_double(const T* p) noexcept
{
    using D = xsimd::batch<double>;
#if defined(__AVX512F__) && (defined(__x86_64__) || defined(__i386__))
    if constexpr (std::is_same_v<T, float> && D::size == 8) return D(_mm512_cvtps_pd(_mm256_loadu_ps(p)));
#elif defined(__AVX2__) && (defined(__x86_64__) || defined(__i386__))
    if constexpr (std::is_same_v<T, float> && D::size == 4) return D(_mm256_cvtps_pd(_mm_loadu_ps(p)));
#endif
    return D::load_unaligned(p);
}

}  // namespace detail

/// @brief Mean and biased variance of v[0..M) (two passes, sums in double). M > 0.
template <class T>
void channel_moments(const T* v, int M, double& mean, double& var) noexcept
{
    double s = 0, q = 0;
    int m = 0;
    constexpr bool vec = detail::has_simd && (std::is_same_v<T, float> || std::is_same_v<T, double>);
    if constexpr (vec) {
        using D = xsimd::batch<double>;
        constexpr int L = int(D::size);
        D a0(0.0), a1(0.0);
        for (; m + 2 * L <= M; m += 2 * L) {
            a0 += detail::load_as_double(v + m);
            a1 += detail::load_as_double(v + m + L);
        }
        s = xsimd::hadd(a0 + a1);
    }
    for (; m < M; ++m) s += double(v[m]);
    mean = s / M;
    m = 0;
    if constexpr (vec) {
        using D = xsimd::batch<double>;
        constexpr int L = int(D::size);
        const D mu(mean);
        D a0(0.0), a1(0.0);
        for (; m + 2 * L <= M; m += 2 * L) {
            const D d0 = detail::load_as_double(v + m) - mu, d1 = detail::load_as_double(v + m + L) - mu;
            a0 = xsimd::fma(d0, d0, a0);
            a1 = xsimd::fma(d1, d1, a1);
        }
        q = xsimd::hadd(a0 + a1);
    }
    for (; m < M; ++m) q += (double(v[m]) - mean) * (double(v[m]) - mean);
    var = q / M;
}

/// @brief out[m] = k (v[m] - mu) + b, then max(., 0) when relu; out may be v.
template <class T>
void scale_shift(const T* v, int M, T k, T mu, T b, bool relu, T* out) noexcept
{
    int m = 0;
    if constexpr (detail::has_simd && (std::is_same_v<T, float> || std::is_same_v<T, double>)) {
        using B = xsimd::batch<T>;
        constexpr int L = int(B::size);
        const B kb(k), mb(mu), bb(b), zero(T(0));
        if (relu)
            for (; m + L <= M; m += L) xsimd::max(xsimd::fma(kb, B::load_unaligned(v + m) - mb, bb), zero).store_unaligned(out + m);
        else
            for (; m + L <= M; m += L) xsimd::fma(kb, B::load_unaligned(v + m) - mb, bb).store_unaligned(out + m);
    }
    for (; m < M; ++m) {
        const T y = k * (v[m] - mu) + b;
        out[m] = relu ? std::max(y, T(0)) : y;
    }
}

/// @brief Instance normalisation of C channels of M values each, in place, one channel after another:
/// v = gamma_c (v - mean_c) / sqrt(var_c + eps) + beta_c, then max(v, 0) when relu, the mean and biased variance
/// from channel_moments() (two passes, in double, as the tape's instance_norm). M > 0.
template <class T>
void instance_norm_per_channel(T* x, const T* gamma, const T* beta, int C, int M, bool relu, T eps) noexcept
{
    for (int c = 0; c < C; ++c) {
        T* v = x + std::ptrdiff_t(c) * M;
        double mu = 0, var = 0;
        channel_moments(v, M, mu, var);
        const double kd = gamma[c] / std::sqrt(var + double(eps));
        scale_shift(v, M, T(kd), T(mu), beta[c], relu, v);
    }
}

namespace detail {

/// Channels instance_norm_channels() takes per block of its three passes (means, scales, affine maps): the groups of
/// a block have no dependence on one another, so their reductions, divisions and square roots overlap.
inline constexpr int norm_block_channels = 128;

#if defined(__AVX512F__) && (defined(__x86_64__) || defined(__i386__))
inline constexpr bool grouped_norm = true;
/// The n < 8 floats at p as doubles, the other lanes `fill`: one masked load (no read past p + n).
inline xsimd::batch<double> tail_as_double(const float* p, int n, double fill) noexcept
{
    const auto k = static_cast<__mmask8>((1u << n) - 1u);
    return xsimd::batch<double>(_mm512_mask_cvtps_pd(_mm512_set1_pd(fill), k, _mm256_maskz_loadu_ps(k, p)));
}
#elif defined(__AVX2__) && (defined(__x86_64__) || defined(__i386__))
inline constexpr bool grouped_norm = true;
/// The n < 4 floats at p as doubles, the other lanes `fill`: one masked load (no read past p + n).
inline xsimd::batch<double> tail_as_double(const float* p, int n, double fill) noexcept
{
    const __m128i k = _mm_cmpgt_epi32(_mm_set1_epi32(n), _mm_setr_epi32(0, 1, 2, 3));
    const __m256d v = _mm256_cvtps_pd(_mm_maskload_ps(p, k));
    return xsimd::batch<double>(_mm256_blendv_pd(_mm256_set1_pd(fill), v, _mm256_castsi256_pd(_mm256_cvtepi32_epi64(k))));
}
#else
inline constexpr bool grouped_norm = false;
/// The n < lanes floats at p as doubles, the other lanes `fill` (declared for instance_norm_channels()'s
/// grouped branch, which is compiled out where grouped_norm is false).
inline xsimd::batch<double> tail_as_double(const float* p, int n, double fill) noexcept
{
    alignas(64) double t[xsimd::batch<double>::size];
    for (int i = 0; i < int(xsimd::batch<double>::size); ++i) t[i] = i < n ? double(p[i]) : fill;
    return xsimd::batch<double>::load_aligned(t);
}
#endif

}  // namespace detail

/// @brief Instance normalisation of C channels of M values each, in place, for inference:
/// v = gamma_c (v - mean_c) / sqrt(var_c + eps) + beta_c, then max(v, 0) when relu, with the mean and biased
/// variance of each channel accumulated in double over two passes, as channel_moments() does. For float on
/// AVX2 and AVX-512 the channels go in groups of as many as a double vector holds: each channel's sums are
/// folded to one vector (its last M mod lanes values by a masked load), the group's vectors are reduced
/// together (xsimd::haddp), and the group's square roots and divisions are one vector each. The per-channel
/// loop's fixed costs (two horizontal reductions, a scalar tail, a square root and a division in sequence)
/// were most of its time on the generator's small inner layers (18 values per channel). The sums are the same
/// in another order: the result can differ from channel_moments()'s in the last bit of the mean or variance.
/// Elsewhere, and for double, it is instance_norm_per_channel(). M > 0.
template <class T>
void instance_norm_channels(T* x, const T* gamma, const T* beta, int C, int M, bool relu, T eps) noexcept
{
    if constexpr (std::is_same_v<T, float> && detail::grouped_norm) {
        using D = xsimd::batch<double>;
        constexpr int L = int(D::size), CB = detail::norm_block_channels;
        const int full = M / L * L, rest = M - full;
        alignas(64) double mv[CB], kv[CB];
        for (int cb = 0; cb < C; cb += CB) {
            const int nc = std::min(CB, C - cb);
            T* xb = x + std::ptrdiff_t(cb) * M;
            // three passes over the block's channels, each group's reductions independent of the other groups'
            for (int c0 = 0; c0 < nc; c0 += L) {
                D r[L];
                for (int j = 0; j < L; ++j) {
                    if (c0 + j >= nc) {
                        r[j] = D(0.0);
                        continue;
                    }
                    const float* v = xb + std::ptrdiff_t(c0 + j) * M;
                    D a0(0.0), a1(0.0);
                    int m = 0;
                    for (; m + 2 * L <= full; m += 2 * L) a0 += detail::load_as_double(v + m), a1 += detail::load_as_double(v + m + L);
                    if (m < full) a0 += detail::load_as_double(v + m);
                    if (rest) a1 += detail::tail_as_double(v + full, rest, 0.0);
                    r[j] = a0 + a1;
                }
                (xsimd::haddp(r) / D(double(M))).store_aligned(mv + c0);
            }
            for (int c0 = 0; c0 < nc; c0 += L) {
                D r[L];
                alignas(64) double gv[L];
                for (int j = 0; j < L; ++j) {
                    gv[j] = c0 + j < nc ? double(gamma[cb + c0 + j]) : 1.0;
                    if (c0 + j >= nc) {
                        r[j] = D(0.0);
                        continue;
                    }
                    const float* v = xb + std::ptrdiff_t(c0 + j) * M;
                    const D mu(mv[c0 + j]);
                    D a0(0.0), a1(0.0);
                    int m = 0;
                    for (; m + 2 * L <= full; m += 2 * L) {
                        const D d0 = detail::load_as_double(v + m) - mu, d1 = detail::load_as_double(v + m + L) - mu;
                        a0 = xsimd::fma(d0, d0, a0), a1 = xsimd::fma(d1, d1, a1);
                    }
                    if (m < full) {
                        const D d0 = detail::load_as_double(v + m) - mu;
                        a0 = xsimd::fma(d0, d0, a0);
                    }
                    if (rest) {
                        const D d = detail::tail_as_double(v + full, rest, mv[c0 + j]) - mu;  // the fill's lanes add 0
                        a1 = xsimd::fma(d, d, a1);
                    }
                    r[j] = a0 + a1;
                }
                const D var = xsimd::haddp(r) / D(double(M));
                (D::load_aligned(gv) / xsimd::sqrt(var + D(double(eps)))).store_aligned(kv + c0);
            }
            for (int c = 0; c < nc; ++c) {
                float* v = xb + std::ptrdiff_t(c) * M;
                scale_shift(v, M, float(kv[c]), float(mv[c]), beta[cb + c], relu, v);
            }
        }
    } else {
        instance_norm_per_channel(x, gamma, beta, C, M, relu, eps);
    }
}

}  // namespace handemo::kernels
