// Packed (weight-stationary) convolutions against the plain-loop reference: the generator's convolutions
// and transposed convolutions at every config width, random geometries for both the packed kernel and the
// fallback, float and double, bias or none, batch 1 and 2.
#include <doctest/doctest.h>

#include <handemo/core/half.hpp>
#include <handemo/kernels/packed.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "random_values.hpp"

namespace hk = handemo::kernels;
using kernel_test::random_values;

namespace {

std::string describe_packed(const hk::conv_geometry& g, bool transposed)
{
    char buf[176];
    std::snprintf(buf, sizeof buf, "%s b%d %dx%dx%d -> %d k%dx%d s%d p%d", transposed ? "convT of" : "conv", g.batch,
                  g.in_channels, g.in_h, g.in_w, g.out_channels, g.kernel_h, g.kernel_w, g.stride, g.pad);
    return buf;
}


constexpr int tail_guard = 17;

/// Checks packed conv2d and conv_transpose2d of g against the reference; returns how many of the two took
/// the weight-stationary kernel.
template <class T>
int check_packed(const hk::conv_geometry& g, double tol, unsigned seed)
{
    std::mt19937 rng(seed);
    const auto w = random_values(g.w_size(), rng), x = random_values(g.x_size(), rng), gy = random_values(g.y_size(), rng);
    const auto bo = random_values(std::size_t(g.out_channels), rng), bi = random_values(std::size_t(g.in_channels), rng);
    const std::vector<T> wt(w.begin(), w.end()), xt(x.begin(), x.end()), gyt(gy.begin(), gy.end()), bot(bo.begin(), bo.end()),
        bit(bi.begin(), bi.end());
    int ws = 0;
    for (int transposed = 0; transposed < 2; ++transposed) {
        const char* type_name = sizeof(T) == 4 ? "float" : "double";
        const std::string what = describe_packed(g, transposed);
        INFO(what, " T=", type_name);
        const auto p = transposed ? hk::packed_conv<T>::conv_transpose2d(g, wt.data()) : hk::packed_conv<T>::conv2d(g, wt.data());
        ws += p.weight_stationary();
        const std::size_t ny = transposed ? g.x_size() : g.y_size();
        const std::vector<T>& in = transposed ? gyt : xt;
        const std::vector<double>& ind = transposed ? gy : x;
        const std::vector<double>& bias = transposed ? bi : bo;
        const std::vector<T>& biast = transposed ? bit : bot;
        for (int with_bias = 0; with_bias < 2; ++with_bias) {
            std::vector<double> want(ny);
            if (transposed) {
                hk::reference::conv_transpose2d_forward<double>(g, ind.data(), w.data(), want.data(), nullptr);
                if (with_bias)
                    for (std::size_t i = 0; i < ny; ++i) want[i] += bias[(i / (std::size_t(g.in_h) * g.in_w)) % g.in_channels];
            } else {
                hk::reference::conv2d_forward<double>(g, ind.data(), w.data(), with_bias ? bias.data() : nullptr, want.data(), nullptr);
            }
            std::vector<T> got(ny + tail_guard, T(7));
            std::fill_n(got.begin(), ny, T(-3));  // forward overwrites
            std::vector<T> scratch(p.scratch_size() + tail_guard, std::numeric_limits<T>::quiet_NaN());
            p.forward(in.data(), with_bias ? biast.data() : nullptr, got.data(), scratch.data());
            double num = 0, den = 1e-30;
            for (std::size_t i = 0; i < ny; ++i) {
                num = std::max(num, std::abs(double(got[i]) - want[i]));
                den = std::max(den, std::abs(want[i]));
            }
            CHECK_MESSAGE(num / den <= tol, "bias=", with_bias, " weight-stationary=", p.weight_stationary());
            for (int i = 0; i < tail_guard; ++i) {
                CHECK(got[ny + std::size_t(i)] == T(7));                                 // nothing written past y
                CHECK(std::isnan(double(scratch[scratch.size() - 1 - std::size_t(i)])));  // nor past the scratch
            }
        }
    }
    return ws;
}

}  // namespace

TEST_CASE("packed convolutions match the reference on the generator's layers at every config width")
{
    for (int cd : {8, 16, 32, 64})
        for (int b : {1, 2}) {
            if (b == 2 && cd > 16) continue;  // batch 2 at the small widths is enough (and this runs under qemu too)
            const hk::conv_geometry layers[] = {
                {b, 8, 12, 24, cd, 7, 7, 1, 3},          // conv7 3+5 -> cd
                {b, cd, 12, 24, 2 * cd, 4, 4, 2, 1},     // down 1; its transpose is up 2
                {b, 2 * cd, 6, 12, 4 * cd, 4, 4, 2, 1},  // down 2; its transpose is up 1
                {b, 4 * cd, 3, 6, 4 * cd, 3, 3, 1, 1},   // residual conv
                {b, cd, 12, 24, 3, 7, 7, 1, 3},          // last conv7 -> 3 (fallback)
            };
            for (const auto& g : layers) {
                check_packed<float>(g, 1e-5, unsigned(cd + b));
                if (cd <= 32) check_packed<double>(g, 1e-12, unsigned(cd * 3 + b));
            }
        }
    // the generator's big layers take the packed kernel wherever xsimd has an instruction set
    if constexpr (hk::detail::has_simd) {
        CHECK(hk::packed_conv<float>::conv2d({1, 256, 3, 6, 256, 3, 3, 1, 1}, std::vector<float>(256 * 256 * 9).data())
                  .weight_stationary());
        CHECK(hk::packed_conv<float>::conv_transpose2d({1, 64, 12, 24, 128, 4, 4, 2, 1}, std::vector<float>(64 * 128 * 16).data())
                  .weight_stationary());
        CHECK_FALSE(hk::packed_conv<float>::conv2d({1, 64, 12, 24, 3, 7, 7, 1, 3}, std::vector<float>(3 * 64 * 49).data())
                        .weight_stationary());
    }
}

TEST_CASE("packed convolutions skip the kernel rows that read only the padding: multiply-adds by hand")
{
    if constexpr (!hk::detail::has_simd) return;
    constexpr int L = hk::detail::simd_lanes<float>;
    // the residual geometry (3 x 6 pixels, 3 x 3 kernel, pad 1): rows 0 and 2 use 2 of the 3 kernel rows
    const hk::conv_geometry res{1, L, 3, 6, L, 3, 3, 1, 1};
    const auto pr = hk::packed_conv<float>::conv2d(res, std::vector<float>(res.w_size(), 1.f).data());
    REQUIRE(pr.weight_stationary());
    CHECK(res.macs() == double(L) * L * 18 * 9);
    CHECK(pr.macs_per_image() == double(L) * L * 6 * 3 * (2 + 3 + 2));
    // the transposed 4 x 4 stride-2 layer onto 6 x 12 from 3 x 6: output row h reads x's rows m - t (t = 0, 1),
    // one of them outside x for h = 0 and h = 5: 1, 2, 2, 2, 2, 1 kernel rows of 2, each with 2 column taps
    const hk::conv_geometry up{1, L, 6, 12, L, 4, 4, 2, 1};
    const auto pt = hk::packed_conv<float>::conv_transpose2d(up, std::vector<float>(up.w_size(), 1.f).data());
    REQUIRE(pt.weight_stationary());
    CHECK(up.macs() == double(L) * L * 18 * 16);
    CHECK(pt.macs_per_image() == double(L) * L * 12 * 2 * (1 + 2 + 2 + 2 + 2 + 1));
    // a stride-2 4 x 4 conv 6 x 12 -> 3 x 6, pad 1: row 0 reads padded rows 0-3 (row 0 is padding), row 2 rows 4-7
    // (row 7 is padding): 3, 4, 3 kernel rows of 4
    const hk::conv_geometry down{1, L, 6, 12, L, 4, 4, 2, 1};
    const auto pd = hk::packed_conv<float>::conv2d(down, std::vector<float>(down.w_size(), 1.f).data());
    CHECK(pd.macs_per_image() == double(L) * L * 6 * 4 * (3 + 4 + 3));
    // a layer on the fallback kernels performs the geometry's multiply-adds
    const hk::conv_geometry last{1, L, 12, 24, 3, 7, 7, 1, 3};
    const auto pl = hk::packed_conv<float>::conv2d(last, std::vector<float>(last.w_size(), 1.f).data());
    CHECK_FALSE(pl.weight_stationary());
    CHECK(pl.macs_per_image() == last.macs());
    // ... but on a batch, its groups of L images one per lane leave out the kernel rows over the padding: 4, 5, 6,
    // 7 x 6, 6, 5, 4 of the 7 kernel rows per output row (72 of 84); the 3 images past the two groups take all 84
    CHECK(pl.macs(1) == last.macs());
    CHECK(pl.macs(2 * L + 3) == 2 * L * last.macs() * 72 / 84 + 3 * last.macs());
}

TEST_CASE("packed convolutions on a batch: the last layer's groups of images give each image its bits alone")
{
    if constexpr (!hk::detail::has_simd) return;
    constexpr int L = hk::detail::simd_lanes<float>;
    std::mt19937 rng(20261208u);
    for (const int co : {1, 3}) {
        const hk::conv_geometry g{1, 32, 12, 24, co, 7, 7, 1, 3};
        const int images = 2 * L + 3;
        const auto w = kernel_test::cast<float>(kernel_test::random_values(g.w_size(), rng));
        const auto b = kernel_test::cast<float>(kernel_test::random_values(std::size_t(co), rng));
        const auto x = kernel_test::cast<float>(kernel_test::random_values(g.x_size() * images, rng));
        const auto p = hk::packed_conv<float>::conv2d(g, w.data());
        std::vector<float> scratch(p.scratch_size()), batch(g.y_size() * images), one(g.y_size() * images);
        p.forward(x.data(), b.data(), batch.data(), scratch.data(), std::size_t(images));
        for (int n = 0; n < images; ++n)
            p.forward(x.data() + n * g.x_size(), b.data(), one.data() + n * g.y_size(), scratch.data(), 1);
        CAPTURE(co);
        CHECK(std::memcmp(batch.data(), one.data(), batch.size() * sizeof(float)) == 0);
    }
}

TEST_CASE("packed convolutions match the reference on random geometries (strides 1-3, any padding)")
{
    std::mt19937 rng(20261202u);
    auto pick = [&](int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(rng); };
    int tested = 0, ws = 0, fallback = 0;
    while (tested < 60) {
        const int kh = pick(1, 6), kw = pick(1, 6);
        // channel counts around the SIMD widths (4, 8, 16 lanes) and the panel widths (x2, x4)
        const int ch[] = {1, 3, 7, 8, 9, 15, 16, 17, 24, 33, 48, 64, 65};
        hk::conv_geometry g{pick(1, 2), ch[pick(0, 12)], pick(1, 13), pick(1, 13), ch[pick(0, 12)], kh, kw, pick(1, 3), pick(0, 3)};
        if (!g.valid()) continue;
        const int n = check_packed<float>(g, 1e-5, unsigned(tested) + 5u);
        ws += n;
        fallback += 2 - n;
        if (tested % 4 == 0) check_packed<double>(g, 1e-12, unsigned(tested) + 9u);
        ++tested;
    }
    INFO("weight-stationary ", ws, ", fallback ", fallback);
    CHECK(fallback > 0);
    if constexpr (hk::detail::has_simd) CHECK(ws > 20);
}

TEST_CASE("packed convolutions refuse an invalid geometry, naming it")
{
    const std::vector<float> w(64, 1.f);
    const hk::conv_geometry bad[] = {{1, 0, 4, 4, 2, 3, 3, 1, 1}, {1, 2, 2, 2, 2, 5, 5, 1, 0}, {1, 2, 4, 4, 2, 3, 3, 0, 1}};
    for (const auto& g : bad) {
        CHECK_THROWS_WITH_AS(hk::packed_conv<float>::conv2d(g, w.data()), doctest::Contains("packed_conv: invalid geometry"),
                             handemo::value_error);
        CHECK_THROWS_AS(hk::packed_conv<float>::conv_transpose2d(g, w.data()), handemo::value_error);
    }
}

namespace {

/// Packed conv2d and conv_transpose2d of g with weight_storage::f16 against the native storage of the same
/// weights rounded to binary16 beforehand: the same values through the same kernel, so the same bits.
/// Returns how many of the two stored binary16 panels.
int check_f16_storage(const hk::conv_geometry& g, unsigned seed)
{
    std::mt19937 rng(seed);
    const auto wd = random_values(g.w_size(), rng), xd = random_values(std::max(g.x_size(), g.y_size()), rng);
    std::vector<float> w(wd.begin(), wd.end()), x(xd.begin(), xd.end()), wr(w.size());
    for (auto& v : w) v *= 3.f;  // spread over several binary16 exponents
    for (std::size_t i = 0; i < w.size(); ++i) wr[i] = handemo::half_to_float(handemo::float_to_half(w[i]));
    int halves = 0;
    for (int transposed = 0; transposed < 2; ++transposed) {
        INFO(describe_packed(g, transposed));
        auto make = [&](const std::vector<float>& ww, hk::weight_storage s) {
            return transposed ? hk::packed_conv<float>::conv_transpose2d(g, ww.data(), s) : hk::packed_conv<float>::conv2d(g, ww.data(), s);
        };
        const auto half = make(w, hk::weight_storage::f16), rounded = make(wr, hk::weight_storage::native),
                   plain = make(w, hk::weight_storage::native);
        CHECK(half.storage() == hk::weight_storage::f16);
        const std::size_t ny = transposed ? g.x_size() : g.y_size();
        std::vector<float> a(ny), b(ny), c(ny), scratch(std::max(half.scratch_size(), rounded.scratch_size()) + 16);
        half.forward(x.data(), nullptr, a.data(), scratch.data());
        rounded.forward(x.data(), nullptr, b.data(), scratch.data());
        plain.forward(x.data(), nullptr, c.data(), scratch.data());
        CHECK(std::memcmp(a.data(), b.data(), ny * sizeof(float)) == 0);
        // and rounding the weights moves the output by about binary16's relative precision, no more
        double num = 0, den = 1e-30;
        for (std::size_t i = 0; i < ny; ++i) num = std::max(num, double(std::abs(a[i] - c[i]))), den = std::max(den, double(std::abs(c[i])));
        CHECK(num / den < 4e-3);
        const bool stored_half = half.weight_bytes() * 2 == plain.weight_bytes();
        CHECK((stored_half || half.weight_bytes() == plain.weight_bytes()));
        if (stored_half) CHECK(half.weight_stationary());
        halves += stored_half;
    }
    return halves;
}

}  // namespace

TEST_CASE("weight_storage::f16: the kernels' result on the rounded weights, bit for bit, in half the bytes")
{
    int halves = 0, cases = 0;
    for (int cd : {8, 16, 32, 64}) {
        const hk::conv_geometry layers[] = {
            {1, 8, 12, 24, cd, 7, 7, 1, 3}, {1, cd, 12, 24, 2 * cd, 4, 4, 2, 1}, {1, 2 * cd, 6, 12, 4 * cd, 4, 4, 2, 1},
            {1, 4 * cd, 3, 6, 4 * cd, 3, 3, 1, 1}, {1, cd, 12, 24, 3, 7, 7, 1, 3}};
        for (const auto& g : layers) halves += check_f16_storage(g, unsigned(cd) + 3u), cases += 2;
    }
    std::mt19937 rng(16u);
    auto pick = [&](int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(rng); };
    for (int tested = 0; tested < 20;) {
        const int ch[] = {3, 8, 16, 17, 33, 64};
        hk::conv_geometry g{pick(1, 2), ch[pick(0, 5)], pick(1, 9), pick(1, 9), ch[pick(0, 5)], pick(1, 5), pick(1, 5), pick(1, 3), pick(0, 2)};
        if (!g.valid()) continue;
        halves += check_f16_storage(g, unsigned(tested) + 40u), cases += 2;
        ++tested;
    }
    INFO("binary16 panels in ", halves, " of ", cases);
    if constexpr (hk::detail::ws_f16_native<float>) CHECK(halves > cases / 3);
    else CHECK(halves == 0);
}

TEST_CASE("weight_storage::f16 refuses weights binary16 cannot hold, naming the weight")
{
    const hk::conv_geometry g{1, 16, 4, 4, 32, 3, 3, 1, 1};
    std::vector<float> w(g.w_size(), 0.5f);
    w[77] = 65520.f;  // rounds to infinity in binary16 (65504 is the largest finite)
    CHECK_THROWS_WITH_AS(hk::packed_conv<float>::conv2d(g, w.data(), hk::weight_storage::f16),
                         doctest::Contains("weight 77 is 65520"), handemo::value_error);
    w[77] = 65519.f;  // rounds down to 65504: accepted
    CHECK_NOTHROW(hk::packed_conv<float>::conv2d(g, w.data(), hk::weight_storage::f16));
    w[5] = std::numeric_limits<float>::quiet_NaN();
    CHECK_THROWS_WITH_AS(hk::packed_conv<float>::conv_transpose2d(g, w.data(), hk::weight_storage::f16),
                         doctest::Contains("weight 5 is nan"), handemo::value_error);
    CHECK_NOTHROW(hk::packed_conv<float>::conv2d(g, w.data()));  // native storage keeps what it is given
}
