// handemo::float_to_half / half_to_float (core/half.hpp) against PyTorch's Tensor.half()
// (tests/fixtures/f16.safetensors, written by scripts/make_golden.py): special values, overflow, the
// subnormal range, exact ties between neighbouring halves, and random values of every scale.
#include <doctest/doctest.h>

#include <handemo/core/half.hpp>
#include <handemo/nn/safetensors.hpp>

#include <bit>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <random>
#include <vector>

#if defined(__F16C__) && (defined(__x86_64__) || defined(__i386__))
#include <immintrin.h>
#endif

TEST_CASE("float_to_half rounds as PyTorch's Tensor.half(), bit for bit; half_to_float is exact")
{
    const auto f = handemo::read_safetensors(std::filesystem::path(HANDEMO_FIXTURE_DIR) / "f16.safetensors");
    const auto x = f.get<float>("x");
    const auto bits = f.get<std::uint16_t>("half_bits");
    const auto back = f.get<float>("half_as_float");
    REQUIRE(x.size() > 60000);
    REQUIRE(bits.size() == x.size());
    REQUIRE(back.size() == x.size());
    std::size_t wrong = 0, wrong_back = 0, ties = 0, subnormal = 0, overflow = 0;
    for (std::size_t i = 0; i < x.size(); ++i) {
        const std::uint16_t h = handemo::float_to_half(x[i]);
        if (h != bits[i] && wrong++ < 5) FAIL_CHECK("x = ", x[i], ": ", h, " against PyTorch's ", bits[i]);
        const float b = handemo::half_to_float(bits[i]);
        const bool same = std::isnan(b) ? std::isnan(back[i]) : std::bit_cast<std::uint32_t>(b) == std::bit_cast<std::uint32_t>(back[i]);
        if (!same && wrong_back++ < 5) FAIL_CHECK("half ", bits[i], ": ", b, " against PyTorch's ", back[i]);
        const std::uint16_t mag = bits[i] & 0x7FFFu;
        subnormal += mag > 0 && mag < 0x400u;
        overflow += mag == 0x7C00u && std::isfinite(x[i]);
        // a tie: |x| exactly halfway between the half it rounded to and the neighbour on its other side
        const double ax = std::abs(double(x[i])), ar = handemo::half_to_float(mag);
        if (mag < 0x7C00u && std::isfinite(x[i]) && ax != ar && (ax > ar || mag > 0)) {
            const double an = handemo::half_to_float(std::uint16_t(ax > ar ? mag + 1 : mag - 1));
            ties += std::abs(ax - ar) == std::abs(an - ax);
        }
    }
    CHECK(wrong == 0);
    CHECK(wrong_back == 0);
    INFO("ties ", ties, ", subnormal results ", subnormal, ", overflows ", overflow);
    CHECK(ties > 1000);     // the fixture's ties reach the round-half-to-even rule
    CHECK(subnormal > 100);  // and the subnormal range
    CHECK(overflow >= 4);    // 65520 and 1e6, both signs
    CHECK(handemo::half_to_float(handemo::float_to_half(handemo::half_max)) == handemo::half_max);
}

#if defined(__F16C__) && (defined(__x86_64__) || defined(__i386__))
TEST_CASE("float_to_half agrees with the F16C instruction on a sweep of every 4099th float bit pattern")
{
    std::size_t wrong = 0, n = 0;
    for (std::uint64_t u = 0; u < (std::uint64_t(1) << 32); u += 4099, ++n) {
        const float v = std::bit_cast<float>(std::uint32_t(u));
        const std::uint16_t want = _cvtss_sh(v, _MM_FROUND_TO_NEAREST_INT);
        if (handemo::float_to_half(v) != want && wrong++ < 5) FAIL_CHECK("bits ", std::uint32_t(u), ": ", handemo::float_to_half(v), " != ", want);
    }
    CHECK(n > 1000000);
    CHECK(wrong == 0);
}
#endif
