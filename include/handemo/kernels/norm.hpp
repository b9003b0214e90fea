// Vectorised pieces of the instance normalisation that follows every convolution of the StarGAN generator
// (Chan et al. 2020, Sec. 3.3, Fig. 3; PyTorch InstanceNorm2d): the two-pass mean and biased variance of
// one channel, accumulated in double as the tape's instance_norm does, and the affine map with optional
// ReLU. Shared by generator inference and the autodiff op.
#pragma once

#include <algorithm>
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

}  // namespace handemo::kernels
