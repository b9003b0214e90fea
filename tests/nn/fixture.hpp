// Helpers shared by the nn tests that compare against the PyTorch golden fixtures
// (tests/fixtures/*.safetensors, written by scripts/make_golden.py).
#pragma once

#include <doctest/doctest.h>
#include <handemo/nn/tensor_file.hpp>

#include <cmath>
#include <string>
#include <vector>

namespace handemo::test {

/// The fixture file `name` under HANDEMO_FIXTURE_DIR, parsed once per program (fixture.cpp, the only
/// translation unit of the golden tests that compiles the JSON parser).
const safetensors_file& fixture(const std::string& name);

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

/// CHECKs |got - want| <= rtol * max(|want|, floor_frac * max|want|) element-wise: the relative error,
/// with a floor at a fraction of the tensor's largest magnitude so that values that cancel to ~0 are
/// compared at the tensor's precision (floor_frac 1: error relative to the tensor's scale).
template <class A, class B>
void check_close(const std::string& what, const A& got, const B& want, double rtol, double floor_frac = 1e-2)
{
    INFO(what);
    REQUIRE(got.size() == want.size());
    double scale = 0;
    for (std::size_t i = 0; i < want.size(); ++i) scale = std::max(scale, std::abs(static_cast<double>(want[i])));
    const double floor = std::max(scale * floor_frac, 1e-30);
    double worst = 0;
    std::size_t at = 0;
    for (std::size_t i = 0; i < want.size(); ++i) {
        const double e = std::abs(static_cast<double>(got[i]) - static_cast<double>(want[i])) /
                         std::max(std::abs(static_cast<double>(want[i])), floor);
        if (!(e <= worst)) {
            worst = e;
            at = i;
        }
    }
    INFO("worst element " << at << ": got " << static_cast<double>(got[at]) << ", want "
                          << static_cast<double>(want[at]) << ", relative error " << worst);
    CHECK(worst <= rtol);
}

}  // namespace handemo::test
