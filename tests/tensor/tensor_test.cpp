// Compile-time tensors: shapes, alignment, indexing, the xtensor view, and the shape messages that
// a mismatch prints (the mismatch itself is checked not to compile by shape_mismatch_fail.cpp).
#include <handemo/tensor.hpp>

#include <doctest/doctest.h>

#include <cstdint>
#include <string_view>

using namespace handemo;

static_assert(shape<16, 3, 12, 24>::size == 16 * 3 * 12 * 24);
static_assert(shape<>::size == 1 && shape<>::rank == 0);
static_assert(shape<2, 5>::dims[1] == 5);
static_assert(conv_out(12, 4, 2, 1) == 6 && conv_out(3, 4, 2, 1) == 1 && conv_out(12, 7, 1, 3) == 12);
static_assert(conv_transpose_out(3, 4, 2, 1) == 6);
static_assert(round_up(9, 4) == 12 && round_up(23, 4) == 24);
static_assert(shape_like<shape<1, 2>> && !shape_like<int>);
static_assert(std::is_same_v<tensor<float, 2, 3>::shape_type, shape<2, 3>>);
static_assert(tensor<double, 4, 5, 6>::size == 120);

TEST_CASE("tensor: zero-initialised, 64-byte aligned, row-major indexing, copy is deep")
{
    tensor<float, 2, 3, 4> t;
    CHECK(reinterpret_cast<std::uintptr_t>(t.data()) % 64 == 0);
    for (float v : t) CHECK(v == 0.f);
    t(1, 2, 3) = 7.f;
    CHECK(t[23] == 7.f);
    CHECK(t.offset(1, 0, 2) == 14);
    auto u = t;
    u(0, 0, 0) = 1.f;
    CHECK(t(0, 0, 0) == 0.f);
    CHECK(u(1, 2, 3) == 7.f);
    tensor<double, 3> f(2.5);
    CHECK(f[2] == 2.5);
}

TEST_CASE("tensor: xtensor view shares memory and has the same shape")
{
    tensor<float, 2, 3> a(1.f), b(2.f);
    auto c = a + b;
    auto x = as_xtensor(c);
    CHECK(x.shape()[0] == 2);
    CHECK(x.shape()[1] == 3);
    CHECK(x(1, 2) == 3.f);
    x(0, 1) = 9.f;
    CHECK(c(0, 1) == 9.f);
    const auto& cc = c;
    CHECK(as_xtensor(cc)(0, 1) == 9.f);
}

TEST_CASE("tensor: the mismatch message names both shapes")
{
    constexpr auto m = detail::mismatch_message<"add", shape<16, 3, 12, 24>, shape<16, 3, 12, 23>>("do not match");
    CHECK(std::string_view(m.text.data()) == "add: shapes [16,3,12,24] and [16,3,12,23] do not match");
    constexpr auto s = detail::mismatch_message<"x", shape<>, shape<1>>("differ");
    CHECK(std::string_view(s.text.data()) == "x: shapes [] and [1] differ");
}
