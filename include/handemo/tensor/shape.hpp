// Compile-time shapes for handemo's tensors and autodiff variables. A shape is a type, `shape<N, C, H, W>`,
// so the batch size and the motion image size [N, 3, K, J] (Eq. 3 of the hand paper, padded for the
// StarGAN) are checked by the compiler. A mismatch is a static_assert whose diagnostic carries a
// message built at compile time that names both shapes: "add: shapes [16,3,12,24] and [16,3,12,23] do
// not match" (GCC and Clang print the template argument that holds it).
#pragma once

#include <array>
#include <cstddef>
#include <type_traits>

namespace handemo {

/// @brief A compile-time shape; `shape<>` is a scalar (size 1).
template <std::size_t... D>
struct shape {
    static constexpr std::size_t rank = sizeof...(D);
    static constexpr std::size_t size = (std::size_t{1} * ... * D);
    static constexpr std::array<std::size_t, sizeof...(D)> dims{D...};
    /// @brief Extent of dimension `i` (0 for i >= rank).
    static constexpr std::size_t dim(std::size_t i) noexcept { return i < rank ? dims[i] : 0; }
};

template <class S>
inline constexpr bool is_shape_v = false;
template <std::size_t... D>
inline constexpr bool is_shape_v<shape<D...>> = true;

/// @brief A type that is a `handemo::shape<...>`.
template <class S>
concept shape_like = is_shape_v<S>;

/// @brief A fixed-capacity string usable as a template argument (message text for diagnostics).
template <std::size_t N>
struct fixed_string {
    char text[N]{};
    constexpr fixed_string() = default;
    constexpr fixed_string(const char (&s)[N]) noexcept
    {
        for (std::size_t i = 0; i < N; ++i) text[i] = s[i];
    }
    static constexpr std::size_t capacity = N;
};

namespace detail {

/// A message buffer for shape diagnostics; printed by the compiler as the template argument.
struct shape_message {
    std::array<char, 160> text{};
};

constexpr void append(shape_message& m, std::size_t& n, const char* s) noexcept
{
    while (*s && n + 1 < m.text.size()) m.text[n++] = *s++;
}

constexpr void append_number(shape_message& m, std::size_t& n, std::size_t v) noexcept
{
    char t[24]{};
    int k = 0;
    do {
        t[k++] = static_cast<char>('0' + v % 10);
        v /= 10;
    } while (v);
    while (k && n + 1 < m.text.size()) m.text[n++] = t[--k];
}

template <shape_like S>
constexpr void append_shape(shape_message& m, std::size_t& n) noexcept
{
    append(m, n, "[");
    for (std::size_t i = 0; i < S::rank; ++i) {
        if (i) append(m, n, ",");
        append_number(m, n, S::dims[i]);
    }
    append(m, n, "]");
}

/// "<op>: shapes [a] and [b] <what>"
template <fixed_string Op, shape_like A, shape_like B>
constexpr shape_message mismatch_message(const char* what) noexcept
{
    shape_message m{};
    std::size_t n = 0;
    append(m, n, Op.text);
    append(m, n, ": shapes ");
    append_shape<A>(m, n);
    append(m, n, " and ");
    append_shape<B>(m, n);
    append(m, n, " ");
    append(m, n, what);
    return m;
}

/// Always false; instantiated with the message so that the compiler prints it next to the failed assert.
template <shape_message Message>
inline constexpr bool shapes_do_not_match = false;

}  // namespace detail

/// @brief True when two shapes are equal.
template <shape_like A, shape_like B>
inline constexpr bool same_shape_v = std::is_same_v<A, B>;

/// @brief Compile-time check that two shapes are equal, for use inside an op. On failure the compiler
/// reports "<Op>: shapes differ" and, in the note that follows, the built message
/// "<Op>: shapes [a] and [b] do not match" naming both shapes.
template <fixed_string Op, shape_like A, shape_like B>
constexpr void require_same_shape() noexcept
{
    static_assert(std::is_same_v<A, B> ||
                      detail::shapes_do_not_match<detail::mismatch_message<Op, A, B>("do not match")>,
                  "handemo: shapes differ (the note names both shapes)");
}

/// @brief Output extent of a convolution: floor((in + 2 pad - k) / stride) + 1.
constexpr std::size_t conv_out(std::size_t in, std::size_t k, std::size_t stride, std::size_t pad) noexcept
{
    return (in + 2 * pad - k) / stride + 1;
}
/// @brief Output extent of a transposed convolution: (in - 1) stride - 2 pad + k.
constexpr std::size_t conv_transpose_out(std::size_t in, std::size_t k, std::size_t stride, std::size_t pad) noexcept
{
    return (in - 1) * stride + k - 2 * pad;
}
/// @brief Smallest multiple of `m` that is >= `v`.
constexpr std::size_t round_up(std::size_t v, std::size_t m) noexcept { return (v + m - 1) / m * m; }

}  // namespace handemo
