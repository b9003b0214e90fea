// IEEE 754 binary16 ("half", safetensors' F16, PyTorch's torch.float16) <-> binary32, in portable code.
// float_to_half rounds to nearest, ties to even, as PyTorch's Tensor.half() and the F16C/AVX-512 conversion
// instructions do (checked against PyTorch in tests/core/half_test.cpp, fixture tests/fixtures/f16.safetensors).
// Used to read F16 tensors (nn/tensor_file.hpp) and for the half-precision weight storage of the packed
// inference kernels (kernels/packed.hpp, weight_storage::f16).
#pragma once

#include <bit>
#include <cstdint>

namespace handemo {

/// The largest finite binary16 value.
inline constexpr float half_max = 65504.f;

/// @brief binary16 -> binary32, exact (normals, subnormals, infinities, NaN).
constexpr float half_to_float(std::uint16_t h) noexcept
{
    const std::uint32_t sign = static_cast<std::uint32_t>(h & 0x8000u) << 16;
    const std::uint32_t exp = (h >> 10) & 0x1Fu;
    std::uint32_t man = h & 0x3FFu;
    std::uint32_t bits = 0;
    if (exp == 0) {
        if (man == 0) bits = sign;
        else {  // subnormal: normalise
            int e = -1;
            do {
                man <<= 1;
                ++e;
            } while ((man & 0x400u) == 0);
            bits = sign | static_cast<std::uint32_t>(127 - 15 - e) << 23 | (man & 0x3FFu) << 13;
        }
    } else if (exp == 0x1F) bits = sign | 0x7F800000u | man << 13;
    else bits = sign | (exp + 127 - 15) << 23 | man << 13;
    return std::bit_cast<float>(bits);
}

/// @brief binary32 -> binary16, rounded to nearest, ties to even. Magnitudes that round above half_max
/// become infinities, those below half the smallest subnormal (2^-25) signed zeros; NaN stays a (quiet) NaN.
constexpr std::uint16_t float_to_half(float f) noexcept
{
    const std::uint32_t x = std::bit_cast<std::uint32_t>(f);
    const std::uint16_t sign = static_cast<std::uint16_t>((x >> 16) & 0x8000u);
    const std::uint32_t ax = x & 0x7FFFFFFFu;
    if (ax >= 0x7F800000u)  // infinity or NaN (NaN keeps its top payload bits and is made quiet)
        return static_cast<std::uint16_t>(sign | 0x7C00u | (ax > 0x7F800000u ? 0x200u | ((ax >> 13) & 0x3FFu) : 0u));
    const int e = static_cast<int>(ax >> 23) - 127;  // unbiased exponent of f
    if (e > 15) return static_cast<std::uint16_t>(sign | 0x7C00u);  // >= 2^16: overflows
    if (e >= -14) {
        // normal half: 10 of the 23 mantissa bits, the other 13 rounded (a carry may raise the exponent,
        // up to infinity, which is the right result)
        std::uint32_t h = (static_cast<std::uint32_t>(e + 15) << 10) | ((ax >> 13) & 0x3FFu);
        const std::uint32_t rest = ax & 0x1FFFu;
        if (rest > 0x1000u || (rest == 0x1000u && (h & 1u))) ++h;
        return static_cast<std::uint16_t>(sign | h);
    }
    if (e < -25) return sign;  // below half of 2^-24: rounds to zero
    // subnormal half: value = m * 2^-24 with m = (1.mantissa) * 2^(e + 24), rounded
    const std::uint32_t m = (ax & 0x7FFFFFu) | 0x800000u;  // 24 significant bits, value m * 2^(e - 23)
    const int shift = -e - 1;                                // 14 .. 24: bits dropped to reach units of 2^-24
    std::uint32_t h = m >> shift;
    const std::uint32_t rest = m & ((1u << shift) - 1u), half = 1u << (shift - 1);
    if (rest > half || (rest == half && (h & 1u))) ++h;  // a carry into bit 10 gives the smallest normal
    return static_cast<std::uint16_t>(sign | h);
}

}  // namespace handemo
