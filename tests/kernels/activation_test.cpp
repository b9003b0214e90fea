// The vectorised output activation (kernels::tanh_inplace) against std::tanh: within a few units in the last
// place, the residual form, every length (whole vectors and the padded tail), and bits that do not depend on
// where an element sits in the buffer.
#include <doctest/doctest.h>

#include <handemo/kernels/activation.hpp>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

namespace hk = handemo::kernels;

namespace {

template <class T>
std::vector<T> activation_inputs(std::size_t n, unsigned seed)
{
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> d(-6.0, 6.0);
    std::vector<T> v(n);
    for (auto& x : v) x = T(d(rng));
    // the polynomial's and the exponential branch's ends, zero, the saturated tails and the signs
    const T special[] = {T(0), T(-0.0), T(0.6249), T(0.6251), T(-0.625), T(1e-6), T(-1e-6), T(9), T(-9), T(40), T(-40)};
    for (std::size_t i = 0; i < std::size(special) && i < n; ++i) v[i * 3 % n] = special[i];
    return v;
}

template <class T>
void check_against_std(double ulps)
{
    const double eps = std::numeric_limits<T>::epsilon();
    for (std::size_t n : {1u, 3u, 7u, 15u, 16u, 17u, 33u, 621u}) {
        CAPTURE(n);
        const auto in = activation_inputs<T>(n, unsigned(n));
        const auto res = activation_inputs<T>(n, unsigned(n) + 100);
        auto v = in;
        hk::tanh_inplace(v.data(), n);
        auto r = in;
        hk::tanh_inplace(r.data(), n, res.data());
        for (std::size_t i = 0; i < n; ++i) {
            const double want = std::tanh(double(in[i]));
            CHECK(std::abs(double(v[i]) - want) <= ulps * eps * std::max(std::abs(want), 1e-30) + 1e-300);
            CHECK(std::abs(double(r[i]) - (double(res[i]) + want)) <= ulps * eps * (std::abs(double(res[i])) + 1.0));
            CHECK(std::signbit(v[i]) == std::signbit(in[i]));
        }
    }
}

}  // namespace

TEST_CASE("tanh_inplace: std::tanh within a few ulp, the residual form, every length")
{
    check_against_std<float>(4);
    check_against_std<double>(4);
}

TEST_CASE("tanh_inplace: an element's bits do not depend on its place in the buffer (a batch gives each image its own bits)")
{
    // one hand image (3 x 23 x 9 values) alone and three of them back to back, where the lone image's last
    // partial vector falls inside whole vectors; many images, since the SIMD tanh and std::tanh differ in the last
    // bit for only some inputs
    for (unsigned seed = 0; seed < 100; ++seed) {
        CAPTURE(seed);
        const auto in = activation_inputs<float>(621, 2 * seed);
        const auto res = activation_inputs<float>(621, 2 * seed + 1);
        auto alone = in;
        hk::tanh_inplace(alone.data(), alone.size(), res.data());
        std::vector<float> batch, batch_res;
        for (int k = 0; k < 3; ++k) {
            batch.insert(batch.end(), in.begin(), in.end());
            batch_res.insert(batch_res.end(), res.begin(), res.end());
        }
        hk::tanh_inplace(batch.data(), batch.size(), batch_res.data());
        for (int k = 0; k < 3; ++k) CHECK(std::memcmp(batch.data() + k * 621, alone.data(), 621 * sizeof(float)) == 0);
    }
}
