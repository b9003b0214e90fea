// Winograd's F(m x m', 3x3) convolutions (kernels/winograd.hpp) against the plain-loop reference in double: the
// 1-D transforms, the generator's residual geometry and others (tiles that overhang the image, channel counts that
// leave panel lanes idle), batches split over groups, binary16 storage, and the geometries it refuses.
#include <doctest/doctest.h>

#include <handemo/core/error.hpp>
#include <handemo/kernels/winograd.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "random_values.hpp"

namespace hk = handemo::kernels;
using kernel_test::random_values;

namespace {

template <int M>
void check_1d()
{
    constexpr auto& t = hk::detail::winograd_matrices<M>;
    constexpr int n = M + 2;
    std::mt19937 rng(M);
    for (int trial = 0; trial < 20; ++trial) {
        const auto d = random_values(n, rng), g = random_values(3, rng);
        for (int i = 0; i < M; ++i) {
            double want = 0, got = 0;
            for (int k = 0; k < 3; ++k) want += d[std::size_t(i + k)] * g[std::size_t(k)];
            for (int a = 0; a < n; ++a) {
                double gg = 0, bd = 0;
                for (int k = 0; k < 3; ++k) gg += t.g[std::size_t(a)][std::size_t(k)] * g[std::size_t(k)];
                for (int j = 0; j < n; ++j) bd += t.bt[std::size_t(a)][std::size_t(j)] * d[std::size_t(j)];
                got += t.at[std::size_t(i)][std::size_t(a)] * gg * bd;
            }
            CHECK(got == doctest::Approx(want).epsilon(1e-13));
        }
    }
    for (const auto& row : t.bt) CHECK(*std::max_element(row.begin(), row.end(), [](double a, double b) { return std::abs(a) < std::abs(b); }) != 0.0);
}

/// Relative max error of winograd_conv3x3 (and of the direct packed kernel, for scale) against the double reference
/// on `images` images in groups of `group`, with and without a bias; checks nothing is written past y or the scratch.
template <class T>
std::pair<double, double> errors(const hk::conv_geometry& g1, int images, int group, unsigned seed, bool with_bias)
{
    std::mt19937 rng(seed);
    hk::conv_geometry g = g1;
    g.batch = images;
    const auto w = random_values(g.w_size(), rng), x = random_values(g.x_size(), rng), b = random_values(std::size_t(g.out_channels), rng);
    std::vector<double> want(g.y_size());
    hk::reference::conv2d_forward<double>(g, x.data(), w.data(), with_bias ? b.data() : nullptr, want.data(), nullptr);
    const auto wt = kernel_test::cast<T>(w), xt = kernel_test::cast<T>(x), bt = kernel_test::cast<T>(b);
    const hk::winograd_conv3x3<T> wc(g1, wt.data(), hk::weight_storage::native, group);
    CHECK(wc.group() == group);
    constexpr int guard = 17;
    std::vector<T> y(g.y_size() + guard, T(7)), scratch(wc.scratch_size() + guard, std::numeric_limits<T>::quiet_NaN());
    wc.forward(xt.data(), with_bias ? bt.data() : nullptr, y.data(), scratch.data(), std::size_t(images));
    for (int i = 0; i < guard; ++i) {
        CHECK(y[g.y_size() + std::size_t(i)] == T(7));
        CHECK(std::isnan(double(scratch[scratch.size() - 1 - std::size_t(i)])));
    }
    const auto pc = hk::packed_conv<T>::conv2d(g1, wt.data());
    std::vector<T> yd(g.y_size()), sd(pc.scratch_size());
    pc.forward(xt.data(), with_bias ? bt.data() : nullptr, yd.data(), sd.data(), std::size_t(images));
    double ew = 0, ed = 0, scale = 1e-30;
    for (std::size_t i = 0; i < want.size(); ++i) {
        ew = std::max(ew, std::abs(double(y[i]) - want[i]));
        ed = std::max(ed, std::abs(double(yd[i]) - want[i]));
        scale = std::max(scale, std::abs(want[i]));
    }
    return {ew / scale, ed / scale};
}

}  // namespace

TEST_CASE("Winograd's 1-D transforms F(2, 3) and F(3, 3) compute the correlation")
{
    check_1d<2>();
    check_1d<3>();
    // the transforms' zeros are exact (the tile transforms skip them), and B^T's rows are scaled to magnitude 1
    CHECK(hk::detail::winograd_matrices<2>.bt[0][1] == 0.0);
    CHECK(hk::detail::winograd_matrices<3>.bt[1][0] == 0.0);
}

TEST_CASE("winograd_conv3x3 matches the reference as closely as the direct kernel, tiles overhanging or not")
{
    if constexpr (!hk::detail::has_simd) return;
    constexpr int L = hk::detail::simd_lanes<float>;
    struct shape {
        int ci, h, w, co, mh, mw;
    };
    // the generator's residual geometry (3 x 6: one tile of 3 rows, tiles of 2 columns); tiles of 3 overhanging an
    // odd size; tiles of 2; an output channel count that leaves panel lanes idle; a 1 x 1 image (a tile of 2 x 2
    // overhanging it); the image size of the generator's input
    // ... and more input channels than one reduction block of the GEMM holds (the blocks' sums accumulate)
    const int deep = hk::detail::ws_kc<float>(hk::detail::ws_tile_for<float>(L).nv) + 2 * L;
    const shape shapes[] = {{4 * L, 3, 6, 4 * L, 3, 2}, {2 * L, 5, 7, 2 * L, 3, 3}, {L, 4, 4, 3 * L, 2, 2},
                            {2 * L, 9, 3, L + 5, 3, 3}, {L, 1, 1, L, 2, 2},         {L, 12, 24, 2 * L, 2, 2},
                            {deep, 3, 6, L, 3, 2}};
    unsigned seed = 1;
    for (const auto& s : shapes) {
        const hk::conv_geometry g{1, s.ci, s.h, s.w, s.co, 3, 3, 1, 1};
        CAPTURE(s.ci);
        CAPTURE(s.h);
        CAPTURE(s.w);
        CAPTURE(s.co);
        REQUIRE(hk::winograd_conv3x3<float>::supported(g));
        const hk::winograd_conv3x3<float> wc(g, std::vector<float>(g.w_size(), 0.5f).data());
        CHECK(wc.tile_h() == s.mh);
        CHECK(wc.tile_w() == s.mw);
        for (bool bias : {false, true}) {
            const auto [ew, ed] = errors<float>(g, 5, 2, seed++, bias);
            CAPTURE(bias);
            CAPTURE(ed);
            CHECK(ew <= 1e-5);       // packed_test.cpp's tolerance for the direct kernels
            CHECK(ew <= std::max(4 * ed, 2e-6));  // and of the direct kernel's own error's order (or 2e-6: 16 ulps)
        }
        if (s.ci <= 2 * L) {
            const auto [ew, ed] = errors<double>(g, 3, 2, seed++, true);
            CHECK(ew <= 1e-13);
            (void)ed;
        }
    }
}

TEST_CASE("winograd_conv3x3: an image's bits do not depend on the images computed with it")
{
    if constexpr (!hk::detail::has_simd) return;
    constexpr int L = hk::detail::simd_lanes<float>;
    const hk::conv_geometry g{1, 2 * L, 3, 6, 2 * L, 3, 3, 1, 1};
    std::mt19937 rng(11);
    const auto w = kernel_test::cast<float>(random_values(g.w_size(), rng));
    const std::size_t per = std::size_t(2 * L) * 18, images = 7;
    const auto x = kernel_test::cast<float>(random_values(per * images, rng)), b = kernel_test::cast<float>(random_values(2 * L, rng));
    std::vector<std::vector<float>> outs;
    for (int group : {1, 3, 16}) {
        const hk::winograd_conv3x3<float> wc(g, w.data(), hk::weight_storage::native, group);
        std::vector<float> y(per * images), s(wc.scratch_size()), y1(per);
        wc.forward(x.data(), b.data(), y.data(), s.data(), images);
        for (std::size_t n = 0; n < images; ++n) {
            wc.forward(x.data() + n * per, b.data(), y1.data(), s.data(), 1);
            CAPTURE(group);
            CAPTURE(n);
            CHECK(std::equal(y1.begin(), y1.end(), y.begin() + std::ptrdiff_t(n * per)));
        }
        outs.push_back(y);
    }
    CHECK(outs[0] == outs[1]);
    CHECK(outs[0] == outs[2]);
}

TEST_CASE("winograd_conv3x3 with binary16 storage: the result on the rounded weights, bit for bit")
{
    if constexpr (!hk::detail::has_simd) return;
    constexpr int L = hk::detail::simd_lanes<float>;
    const hk::conv_geometry g{1, L, 3, 6, 2 * L, 3, 3, 1, 1};
    std::mt19937 rng(5);
    const auto w = kernel_test::cast<float>(random_values(g.w_size(), rng)), x = kernel_test::cast<float>(random_values(std::size_t(L) * 18, rng));
    const auto rounded = hk::binary16_rounded(w.data(), w.size());
    const hk::winograd_conv3x3<float> half(g, w.data(), hk::weight_storage::f16), want(g, rounded.data()), plain(g, w.data());
    CHECK(half.storage() == hk::weight_storage::f16);
    std::vector<float> s(half.scratch_size()), y1(std::size_t(2 * L) * 18), y2(y1.size()), y3(y1.size());
    half.forward(x.data(), nullptr, y1.data(), s.data(), 1);
    want.forward(x.data(), nullptr, y2.data(), s.data(), 1);
    plain.forward(x.data(), nullptr, y3.data(), s.data(), 1);
    CHECK(y1 == y2);
    CHECK(y1 != y3);
    std::vector<float> big(w);
    big[4] = 1e5f;
    CHECK_THROWS_WITH_AS(hk::winograd_conv3x3<float>(g, big.data(), hk::weight_storage::f16), doctest::Contains("weight 4 is 100000"),
                         handemo::value_error);
}

TEST_CASE("winograd_conv3x3 refuses the geometries it does not take, naming them")
{
    if constexpr (!hk::detail::has_simd) return;
    constexpr int L = hk::detail::simd_lanes<float>;
    const std::vector<float> w(std::size_t(4 * L) * 4 * L * 16, 0.f);
    const hk::conv_geometry refused[] = {{1, 2 * L, 6, 6, 2 * L, 3, 3, 2, 1},  // stride 2
                                         {1, 2 * L, 6, 6, 2 * L, 4, 4, 1, 1},  // 4x4
                                         {1, 2 * L, 6, 6, 2 * L, 3, 3, 1, 0},  // no padding
                                         {1, L + 1, 6, 6, 2 * L, 3, 3, 1, 1},  // not a multiple of the SIMD width
                                         {1, 2 * L, 6, 6, L - 1, 3, 3, 1, 1}}; // fewer outputs than a vector
    for (const auto& g : refused) {
        CHECK_FALSE(hk::winograd_conv3x3<float>::supported(g));
        CHECK_THROWS_WITH_AS(hk::winograd_conv3x3<float>(g, w.data()), doctest::Contains("is not a 3x3 stride-1 pad-1 convolution"),
                             handemo::value_error);
    }
    const hk::conv_geometry ok{1, L, 3, 6, L, 3, 3, 1, 1};
    CHECK_THROWS_WITH_AS(hk::winograd_conv3x3<float>(ok, w.data(), hk::weight_storage::native, -1), doctest::Contains("group -1"),
                         handemo::value_error);
    CHECK_FALSE(hk::winograd_conv3x3<int>::supported(ok));
}
