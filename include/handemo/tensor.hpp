// Tensor module: compile-time shapes (`shape<...>`, shape checks whose diagnostics name both shapes),
// 64-byte aligned fixed-size tensors, and their xtensor view. These carry the batched motion images
// [N, 3, K, J] of Eq. 3 of the hand paper through the StarGAN.
#pragma once

#include <handemo/tensor/aligned.hpp>
#include <handemo/tensor/shape.hpp>
#include <handemo/tensor/tensor.hpp>

#include <xtensor/xadapt.hpp>

namespace handemo {

/// @brief Non-owning xtensor view (`xt::adapt`) of a tensor, same shape, row-major.
template <class T, std::size_t... D>
auto as_xtensor(tensor<T, D...>& t)
{
    return xt::adapt(t.data(), tensor<T, D...>::size, xt::no_ownership(),
                     std::array<std::size_t, sizeof...(D)>{D...});
}
/// @brief Read-only xtensor view of a tensor.
template <class T, std::size_t... D>
auto as_xtensor(const tensor<T, D...>& t)
{
    return xt::adapt(t.data(), tensor<T, D...>::size, xt::no_ownership(),
                     std::array<std::size_t, sizeof...(D)>{D...});
}

/// @brief Element-wise sum of two tensors of the same shape (a shape mismatch does not compile).
template <class T, std::size_t... A, std::size_t... B>
tensor<T, A...> operator+(const tensor<T, A...>& a, const tensor<T, B...>& b)
{
    require_same_shape<"add", shape<A...>, shape<B...>>();
    tensor<T, A...> r;
    for (std::size_t i = 0; i < r.size; ++i) r[i] = a[i] + b[i];
    return r;
}

}  // namespace handemo
