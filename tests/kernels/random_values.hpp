// Random test inputs shared by the kernel tests (conv_test.cpp, packed_test.cpp).
#pragma once

#include <cstddef>
#include <random>
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

}  // namespace kernel_test
