// handemo's portable random number generator: the 64-bit Mersenne Twister (the exact engine the
// standard calls std::mt19937_64, so its output sequence is fixed by ISO C++) with handemo's own
// uniform and normal transforms, because std::uniform_real_distribution and std::normal_distribution
// produce different numbers under libstdc++, libc++ and MSVC. The engine is re-implemented here (and
// tested bit for bit against std::mt19937_64) only so that its whole state is one flat array that a
// checkpoint can store and restore exactly; the standard engine exposes its state solely through a
// textual stream format whose layout differs between standard libraries. It drives the weight
// initialisation of the StarGAN networks (Sec. 3.3 of the hand paper), batch sampling, target labels
// and the gradient-penalty interpolation factors.
#pragma once

#include <handemo/core/error.hpp>

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <numbers>
#include <span>
#include <string>

namespace handemo {

/// @brief Seeded, deterministic, portable random number generator (MT19937-64 engine).
///
/// Every draw is defined in terms of the 64-bit engine output, so a given seed produces the same
/// numbers on every platform and standard library. The complete state is `state_size` 64-bit words
/// (312 words of the twister plus the read position) and can be saved and restored exactly.
class rng {
public:
    using result_type = std::uint64_t;
    static constexpr std::size_t word_count = 312;
    static constexpr std::size_t state_size = word_count + 1;  ///< 312 words + read position
    static constexpr std::uint64_t default_seed = 5489u;

    /// @brief Seeds the engine exactly as std::mt19937_64(seed) does.
    explicit rng(std::uint64_t seed = default_seed) noexcept { reseed(seed); }

    /// @brief Re-seeds the engine (same sequence as std::mt19937_64::seed(seed)).
    void reseed(std::uint64_t seed) noexcept
    {
        s_[0] = seed;
        for (std::size_t i = 1; i < word_count; ++i)
            s_[i] = 6364136223846793005ULL * (s_[i - 1] ^ (s_[i - 1] >> 62)) + i;
        s_[word_count] = word_count;  // forces a twist on the first draw
    }

    static constexpr result_type min() noexcept { return 0; }
    static constexpr result_type max() noexcept { return ~result_type{0}; }

    /// @brief Next raw 64-bit output (identical to std::mt19937_64::operator()).
    result_type operator()() noexcept
    {
        if (s_[word_count] >= word_count) twist();
        std::uint64_t y = s_[s_[word_count]++];
        y ^= (y >> 29) & 0x5555555555555555ULL;
        y ^= (y << 17) & 0x71D67FFFEDA60000ULL;
        y ^= (y << 37) & 0xFFF7EEE000000000ULL;
        y ^= y >> 43;
        return y;
    }

    /// @brief Uniform double in [0, 1): the top 53 bits of one engine output times 2^-53.
    double uniform01() noexcept { return static_cast<double>((*this)() >> 11) * 0x1.0p-53; }

    /// @brief Uniform double in [lo, hi): lo + (hi - lo) * uniform01().
    double uniform(double lo, double hi) noexcept { return lo + (hi - lo) * uniform01(); }

    /// @brief Uniform integer in [0, n) without modulo bias (rejection sampling); n must be > 0.
    /// @throws value_error when n is 0.
    std::uint64_t below(std::uint64_t n)
    {
        if (n == 0) throw value_error("rng::below: n is 0, expected a positive bound");
        const std::uint64_t rem = (max() % n + 1) % n;  // 2^64 mod n
        const std::uint64_t limit = 0 - rem;             // 2^64 - rem: accept [0, limit), a multiple of n
        std::uint64_t x = (*this)();
        while (rem != 0 && x >= limit) x = (*this)();
        return x % n;
    }

    /// @brief Standard normal N(0, 1) by the Box-Muller transform, two uniforms per draw
    /// (the sine branch is discarded so that the state stays one flat array with no cached spare).
    double normal() noexcept
    {
        const double u1 = 1.0 - uniform01();  // (0, 1]: log is finite
        const double u2 = uniform01();
        return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * std::numbers::pi * u2);
    }

    /// @brief Normal N(mean, stddev^2).
    double normal(double mean, double stddev) noexcept { return mean + stddev * normal(); }

    /// @brief The complete state: 312 twister words followed by the read position (0..312).
    std::span<const std::uint64_t, state_size> state() const noexcept { return s_; }

    /// @brief Restores a state obtained from state().
    /// @param s `state_size` words; the last one is the read position.
    /// @throws value_error when the size is wrong, the position is beyond 312, or all words are 0.
    void set_state(std::span<const std::uint64_t> s)
    {
        if (s.size() != state_size)
            throw value_error("rng::set_state: state has " + std::to_string(s.size()) + " words, expected " +
                              std::to_string(state_size));
        if (s[word_count] > word_count)
            throw value_error("rng::set_state: read position " + std::to_string(s[word_count]) +
                              " is beyond " + std::to_string(word_count));
        bool any = false;
        for (std::size_t i = 0; i < word_count; ++i) any = any || s[i] != 0;
        if (!any) throw value_error("rng::set_state: all twister words are 0 (not a valid MT19937-64 state)");
        for (std::size_t i = 0; i < state_size; ++i) s_[i] = s[i];
    }

    friend bool operator==(const rng&, const rng&) = default;

private:
    void twist() noexcept
    {
        constexpr std::size_t n = word_count, m = 156;
        constexpr std::uint64_t upper = 0xFFFFFFFF80000000ULL, lower = 0x7FFFFFFFULL;
        constexpr std::uint64_t matrix = 0xB5026F5AA96619E9ULL;
        auto mix = [&](std::size_t i, std::size_t next, std::size_t far) {
            const std::uint64_t y = (s_[i] & upper) | (s_[next] & lower);
            s_[i] = s_[far] ^ (y >> 1) ^ ((y & 1u) ? matrix : 0u);
        };
        // the three index ranges of (i + 1) % n and (i + m) % n, without a modulo per word
        for (std::size_t i = 0; i < n - m; ++i) mix(i, i + 1, i + m);
        for (std::size_t i = n - m; i < n - 1; ++i) mix(i, i + 1, i + m - n);
        mix(n - 1, 0, m - 1);
        s_[word_count] = 0;
    }

    std::array<std::uint64_t, state_size> s_{};
};

}  // namespace handemo
