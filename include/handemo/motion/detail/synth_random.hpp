// Portable random numbers for the synthetic dataset: std::mt19937_64 is specified bit-for-bit by the
// standard, but std::uniform_real_distribution / std::normal_distribution are not, so handemo draws its
// own uniforms (top 53 bits) and normals (Box-Muller) to be identical on every standard library.
#pragma once

#include <cmath>
#include <cstdint>
#include <numbers>
#include <random>

namespace handemo::detail {

/// SplitMix64 finaliser: decorrelates seeds derived from (seed, motion, emotion, take).
constexpr std::uint64_t splitmix64(std::uint64_t x) noexcept
{
    x += 0x9e3779b97f4a7c15ULL;
    x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
    x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
    return x ^ (x >> 31);
}

/// @brief Deterministic random source built on std::mt19937_64.
struct synth_rng {
    std::mt19937_64 engine;

    explicit synth_rng(std::uint64_t seed) : engine(seed) {}
    /// Uniform in [0, 1) from the top 53 bits.
    double uniform() noexcept { return static_cast<double>(engine() >> 11) * 0x1.0p-53; }
    double uniform(double lo, double hi) noexcept { return lo + (hi - lo) * uniform(); }
    /// Standard normal by Box-Muller (one value per call, the second is discarded for simplicity).
    double normal() noexcept
    {
        const double u1 = 1.0 - uniform();  // (0, 1]
        const double u2 = uniform();
        return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * std::numbers::pi * u2);
    }
};

}  // namespace handemo::detail
