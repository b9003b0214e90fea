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
            a0 += D::load_unaligned(v + m);
            a1 += D::load_unaligned(v + m + L);
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
            const D d0 = D::load_unaligned(v + m) - mu, d1 = D::load_unaligned(v + m + L) - mu;
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
