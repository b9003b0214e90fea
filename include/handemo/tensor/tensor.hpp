// Compile-time sized dense tensors, row-major (C order), 64-byte aligned. The shape is part of the type,
// `tensor<float, 16, 3, 12, 24>` holds a batch of 16 motion images [N, 3, K, J] (Eq. 3 of the hand paper,
// zero-padded to the StarGAN size). This header does not include xtensor; `handemo/tensor.hpp` adds the
// xtensor view (`as_xtensor`).
#pragma once

#include <handemo/tensor/aligned.hpp>
#include <handemo/tensor/shape.hpp>

#include <algorithm>
#include <array>
#include <cstddef>
#include <span>

namespace handemo {

/// @brief Dense row-major tensor of `T` with compile-time extents `D...`, stored 64-byte aligned.
/// @tparam T element type (float or double)
/// @tparam D extents, outermost first
template <class T, std::size_t... D>
class tensor {
public:
    using value_type = T;
    using shape_type = shape<D...>;
    static constexpr std::size_t rank = sizeof...(D);
    static constexpr std::size_t size = shape_type::size;
    static constexpr std::array<std::size_t, rank> dims{D...};

    /// @brief A zero tensor.
    tensor() : buf_(size) {}
    /// @brief A tensor filled with `v`.
    explicit tensor(T v) : buf_(size) { fill(v); }

    T* data() noexcept { return buf_.data(); }
    const T* data() const noexcept { return buf_.data(); }
    std::span<T, size> span() noexcept { return std::span<T, size>(data(), size); }
    std::span<const T, size> span() const noexcept { return std::span<const T, size>(data(), size); }
    T* begin() noexcept { return data(); }
    T* end() noexcept { return data() + size; }
    const T* begin() const noexcept { return data(); }
    const T* end() const noexcept { return data() + size; }

    T& operator[](std::size_t i) noexcept { return data()[i]; }
    const T& operator[](std::size_t i) const noexcept { return data()[i]; }

    /// @brief Element at a multi-index (one index per dimension).
    template <class... I>
        requires(sizeof...(I) == rank && (std::is_integral_v<I> && ...))
    T& operator()(I... idx) noexcept { return data()[offset(idx...)]; }
    template <class... I>
        requires(sizeof...(I) == rank && (std::is_integral_v<I> && ...))
    const T& operator()(I... idx) const noexcept { return data()[offset(idx...)]; }

    /// @brief Row-major offset of a multi-index.
    template <class... I>
    static constexpr std::size_t offset(I... idx) noexcept
    {
        const std::size_t ix[] = {static_cast<std::size_t>(idx)..., 0};
        std::size_t o = 0;
        for (std::size_t k = 0; k < rank; ++k) o = o * dims[k] + ix[k];
        return o;
    }

    void fill(T v) noexcept { std::fill(begin(), end(), v); }

private:
    aligned_buffer<T> buf_;
};

}  // namespace handemo
