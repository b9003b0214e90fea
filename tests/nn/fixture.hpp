// Helpers shared by the nn tests that compare against the PyTorch golden fixtures
// (tests/fixtures/*.safetensors, written by scripts/make_golden.py).
#pragma once

#include <doctest/doctest.h>
#include <handemo/nn/safetensors.hpp>

#include <cmath>
#include <string>
#include <vector>

namespace handemo::test {

inline safetensors_file fixture(const std::string& name)
{
    return read_safetensors(std::string(HANDEMO_FIXTURE_DIR) + "/" + name);
}

/// Largest |a - b| / (|b| + floor) over the elements; floor keeps near-zero references meaningful.
template <class A, class B>
double max_rel_error(const A& a, const B& b, double floor)
{
    REQUIRE(a.size() == b.size());
    double e = 0;
    for (std::size_t i = 0; i < a.size(); ++i) {
        const double x = static_cast<double>(a[i]), y = static_cast<double>(b[i]);
        e = std::max(e, std::abs(x - y) / (std::abs(y) + floor));
    }
    return e;
}

}  // namespace handemo::test
