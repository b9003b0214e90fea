// The generator's output activation (Chan et al. 2020, Sec. 3.3: a tanh after the last convolution, plus the
// input in the residual form), vectorised. Every element goes through the same SIMD tanh (xsimd's, within a few
// units in the last place of std::tanh), the last partial vector through a zero-padded copy, so an element's
// bits do not depend on where in the buffer it sits: a batch gives every image the bits it gets alone.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <type_traits>

#include <handemo/kernels/detail/conv_simd.hpp>

namespace handemo::kernels {

/// @brief v[i] = tanh(v[i]), or v[i] = x[i] + tanh(v[i]) when x is not null, for i < n.
template <class T>
void tanh_inplace(T* v, std::size_t n, const T* x = nullptr) noexcept
{
    if constexpr (detail::has_simd && (std::is_same_v<T, float> || std::is_same_v<T, double>)) {
        using B = xsimd::batch<T>;
        constexpr std::size_t L = B::size;
        std::size_t i = 0;
        for (; i + L <= n; i += L) {
            B y = xsimd::tanh(B::load_unaligned(v + i));
            if (x) y += B::load_unaligned(x + i);
            y.store_unaligned(v + i);
        }
        if (i < n) {
            alignas(64) T t[L] = {}, a[L] = {};
            std::copy(v + i, v + n, t);
            if (x) std::copy(x + i, x + n, a);
            B y = xsimd::tanh(B::load_unaligned(t));
            if (x) y += B::load_unaligned(a);
            y.store_unaligned(t);
            std::copy(t, t + (n - i), v + i);
        }
    } else {
        for (std::size_t i = 0; i < n; ++i) v[i] = x ? x[i] + std::tanh(v[i]) : std::tanh(v[i]);
    }
}

}  // namespace handemo::kernels
