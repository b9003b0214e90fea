// Random test inputs and the geometry's description shared by the kernel tests (conv_test.cpp, packed_test.cpp,
// forward_ws_test.cpp).
#pragma once

#include <handemo/kernels/reference.hpp>

#include <cstddef>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

namespace kernel_test {

/// n values uniform in [-1, 1).
inline std::vector<double> random_values(std::size_t n, std::mt19937& rng)
{
    std::uniform_real_distribution<double> d(-1.0, 1.0);
    std::vector<double> v(n);
    for (auto& e : v) e = d(rng);
    return v;
}

/// The values of v as T.
template <class T>
std::vector<T> cast(const std::vector<double>& v)
{
    return std::vector<T>(v.begin(), v.end());
}

/// "b<batch> <in>x<h>x<w> -> <out> k<kh>x<kw> s<stride> p<pad>", for the tests' messages.
inline std::string describe(const handemo::kernels::conv_geometry& g)
{
    char buf[160];
    std::snprintf(buf, sizeof buf, "b%d %dx%dx%d -> %d k%dx%d s%d p%d", g.batch, g.in_channels, g.in_h, g.in_w,
                  g.out_channels, g.kernel_h, g.kernel_w, g.stride, g.pad);
    return buf;
}

}  // namespace kernel_test
