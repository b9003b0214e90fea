// The inference instance normalisation (kernels::instance_norm_channels) against a long-double reference and
// against the per-channel loop (kernels::instance_norm_per_channel, channel_moments + scale_shift as the tape's
// instance_norm): every channel
// count around the double vector's width, lengths with and without a tail, ReLU on and off, nothing written
// outside the channels.
#include <doctest/doctest.h>

#include <handemo/kernels/norm.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>
#include <vector>

namespace hk = handemo::kernels;

namespace {

/// gamma (x - mean) / sqrt(var + eps) + beta per channel in long double, then ReLU; `scale` gets each value's
/// scale in float arithmetic: max(1, |k mean| + |beta|, |value|), k = gamma / sqrt(var + eps) (the float kernel
/// subtracts the mean rounded to float and multiplies by k, so its error grows with |k mean|).
std::vector<double> reference_norm(const std::vector<float>& x, const std::vector<float>& g, const std::vector<float>& b, int C, int M,
                                   bool relu, float eps, std::vector<double>& scale)
{
    std::vector<double> y(x.size());
    scale.assign(x.size(), 1.0);
    for (int c = 0; c < C; ++c) {
        long double s = 0, q = 0;
        for (int m = 0; m < M; ++m) s += x[std::size_t(c) * M + m];
        const long double mean = s / M;
        for (int m = 0; m < M; ++m) q += (x[std::size_t(c) * M + m] - mean) * (x[std::size_t(c) * M + m] - mean);
        const long double k = g[std::size_t(c)] / std::sqrt(q / M + (long double)eps);
        for (int m = 0; m < M; ++m) {
            const long double v = k * (x[std::size_t(c) * M + m] - mean) + b[std::size_t(c)];
            y[std::size_t(c) * M + m] = double(relu ? std::max(v, 0.0L) : v);
            scale[std::size_t(c) * M + m] = double(std::max({1.0L, std::abs(k * mean) + std::abs((long double)b[std::size_t(c)]), std::abs(v)}));
        }
    }
    return y;
}

}  // namespace

TEST_CASE("instance_norm_channels: the normalisation of every channel, every group size and tail, within 1e-6 of its scale")
{
    std::mt19937 rng(20261206u);
    std::normal_distribution<float> nd(0.0f, 1.0f);
    const float eps = 1e-5f;
    int cases = 0;
    for (int C : {1, 3, 7, 8, 9, 16, 17, 31, 64, 128, 129, 200})
        for (int M : {1, 2, 3, 7, 8, 9, 15, 16, 17, 18, 33, 72, 288})
            for (int relu = 0; relu < 2; ++relu) {
                CAPTURE(C);
                CAPTURE(M);
                CAPTURE(relu);
                const std::size_t n = std::size_t(C) * M;
                std::vector<float> x(n), g(static_cast<std::size_t>(C)), b(static_cast<std::size_t>(C));
                // channels with an offset far from zero and a small spread, as after a convolution with a bias
                for (int c = 0; c < C; ++c) {
                    const float off = 3.0f * nd(rng), sc = 0.05f + std::abs(nd(rng));
                    for (int m = 0; m < M; ++m) x[std::size_t(c) * M + m] = off + sc * nd(rng);
                    g[std::size_t(c)] = 1.0f + 0.3f * nd(rng), b[std::size_t(c)] = 0.2f * nd(rng);
                }
                std::vector<double> scale;
                const auto want = reference_norm(x, g, b, C, M, relu, eps, scale);
                constexpr int guard = 19;
                std::vector<float> got(n + guard, 7.0f);
                std::copy(x.begin(), x.end(), got.begin());
                hk::instance_norm_channels(got.data(), g.data(), b.data(), C, M, relu != 0, eps);
                double err = 0;
                for (std::size_t i = 0; i < n; ++i) {
                    err = std::max(err, std::abs(double(got[i]) - want[i]) / scale[i]);
                }
                CHECK(err <= 1e-6);
                for (int i = 0; i < guard; ++i) CHECK(got[n + std::size_t(i)] == 7.0f);  // nothing past the last channel

                // the per-channel loop of the tape's norm: the same values up to the last bits of float
                std::vector<float> loop = x;
                hk::instance_norm_per_channel(loop.data(), g.data(), b.data(), C, M, relu != 0, eps);
                double diff = 0;
                for (std::size_t i = 0; i < n; ++i) diff = std::max(diff, double(std::abs(got[i] - loop[i])) / std::max(1.0f, std::abs(loop[i])));
                CHECK(diff <= 1e-6);
                ++cases;
            }
    CHECK(cases == 312);
}

TEST_CASE("instance_norm_channels: a channel's bits do not depend on the channels normalised with it")
{
    // every channel of a call (blocks of norm_block_channels channels, groups of a double vector, tails) against the
    // same channel normalised alone, bit for bit: the block and group bookkeeping reads and writes its own values
    std::mt19937 rng(20261208u);
    std::normal_distribution<float> nd(0.0f, 1.0f);
    for (const int C : {1, 9, 127, 128, 129, 300})
        for (const int M : {1, 7, 18, 72, 289})
            for (const bool relu : {false, true}) {
                CAPTURE(C);
                CAPTURE(M);
                const std::size_t n = std::size_t(C) * M;
                std::vector<float> x(n), g(static_cast<std::size_t>(C)), b(static_cast<std::size_t>(C));
                for (auto& v : x) v = 2.0f + nd(rng);
                for (int c = 0; c < C; ++c) g[std::size_t(c)] = 1.0f + 0.3f * nd(rng), b[std::size_t(c)] = 0.2f * nd(rng);
                std::vector<float> all = x;
                hk::instance_norm_channels(all.data(), g.data(), b.data(), C, M, relu, 1e-5f);
                int differ = 0;
                for (int c = 0; c < C; ++c) {
                    std::vector<float> alone(x.begin() + std::ptrdiff_t(c) * M, x.begin() + std::ptrdiff_t(c + 1) * M);
                    hk::instance_norm_channels(alone.data(), g.data() + c, b.data() + c, 1, M, relu, 1e-5f);
                    differ += std::memcmp(alone.data(), all.data() + std::ptrdiff_t(c) * M, std::size_t(M) * sizeof(float)) != 0;
                }
                CHECK(differ == 0);
            }
}

TEST_CASE("instance_norm_channels: double takes the per-channel loop, bit for bit")
{
    std::mt19937 rng(7u);
    std::normal_distribution<double> nd(0.5, 2.0);
    const int C = 9, M = 18;
    std::vector<double> x(static_cast<std::size_t>(C * M)), g(static_cast<std::size_t>(C), 1.25), b(static_cast<std::size_t>(C), -0.5);
    for (auto& v : x) v = nd(rng);
    auto got = x, loop = x;
    hk::instance_norm_channels(got.data(), g.data(), b.data(), C, M, true, 1e-5);
    hk::instance_norm_per_channel(loop.data(), g.data(), b.data(), C, M, true, 1e-5);
    CHECK(got == loop);
}
