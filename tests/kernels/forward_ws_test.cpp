// The weight-stationary path for convolutions whose weights change between calls (training:
// kernels/detail/packed_conv.hpp's forward_ws behind conv2d_forward, the stride-1 backward-data and the
// transposed convolution's backward-data, and backward_weight_ws behind both weight gradients). It must give
// conv_simd.hpp's packed and stride-1 paths bit for bit, so that a model trains to the same bits whichever path
// ran: compared with memcmp, float and double, with and without bias, overwriting and accumulating, on the
// StarGAN layers and on random geometries, batches across the image groups and pixel blocks, and with nothing
// written past the scratch it asks for.
#include <doctest/doctest.h>

#include <handemo/kernels/conv.hpp>

#include <cstdint>
#include <cstdio>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "random_values.hpp"

namespace hk = handemo::kernels;
namespace hkd = handemo::kernels::detail;

namespace forward_ws_test {

using kernel_test::describe;
using kernel_test::random_values;
using kernel_test::cast;

constexpr std::size_t guard = 64;
constexpr double guard_value = 12345.0;

/// Scratch of conv2d_scratch_size elements followed by a guard; true when the guard is untouched.
template <class T>
struct guarded_scratch {
    explicit guarded_scratch(const hk::conv_geometry& g) : n(hk::conv2d_scratch_size<T>(g)), v(n + guard, T(guard_value)) {}
    T* data() { return v.data(); }
    bool intact() const
    {
        for (std::size_t i = n; i < v.size(); ++i)
            if (v[i] != T(guard_value)) return false;
        return true;
    }
    std::size_t n;
    std::vector<T> v;
};

/// Two forward passes of geometry g, run(bias, y, scratch, accumulate), from the same y0, overwriting and accumulating,
/// with the bias b and without: the same bits, and the first within the scratch the geometry asks for.
template <class T, class RunA, class RunB>
void same_forward_bits(const hk::conv_geometry& g, const std::vector<T>& b, const std::vector<T>& y0, RunA&& run_a, RunB&& run_b)
{
    for (const bool accumulate : {false, true})
        for (const bool with_bias : {false, true}) {
            CAPTURE(accumulate);
            CAPTURE(with_bias);
            const T* bias = with_bias ? b.data() : nullptr;
            std::vector<T> ya = y0, yb = y0;
            guarded_scratch<T> sa(g), sb(g);
            run_a(bias, ya.data(), sa.data(), accumulate);
            run_b(bias, yb.data(), sb.data(), accumulate);
            CHECK(std::memcmp(ya.data(), yb.data(), ya.size() * sizeof(T)) == 0);
            CHECK(sa.intact());
        }
}

/// forward_any (weight-stationary where use_forward_ws) against conv_simd.hpp's forward, backward_data_any
/// against backward_data and backward_weight_any against backward_weight, each bit for bit. Returns how many of
/// the three took the weight-stationary path.
template <class T>
int check_same_bits(const hk::conv_geometry& g, unsigned seed)
{
    INFO(describe(g), (sizeof(T) == 4 ? " float" : " double"));
    std::mt19937 rng(seed);
    const auto x = cast<T>(random_values(g.x_size(), rng)), w = cast<T>(random_values(g.w_size(), rng));
    const auto b = cast<T>(random_values(std::size_t(g.out_channels), rng));
    const auto y0 = cast<T>(random_values(g.y_size(), rng)), gx0 = cast<T>(random_values(g.x_size(), rng));
    int took = 0;
    same_forward_bits<T>(g, b, y0, [&](const T* bias, T* y, T* scratch, bool accumulate) {
        hkd::forward_any<T>(g, x.data(), w.data(), bias, y, scratch, accumulate);
    }, [&](const T* bias, T* y, T* scratch, bool accumulate) {
        hkd::forward<T>(g, x.data(), w.data(), bias, y, scratch, accumulate);
    });
    took += hkd::use_forward_ws<T>(g) ? 1 : 0;
    // backward-data accumulates into gx
    std::vector<T> ga = gx0, gb = gx0;
    guarded_scratch<T> sa(g), sb(g);
    hkd::backward_data_any<T>(g, y0.data(), w.data(), ga.data(), sa.data());
    hkd::backward_data<T>(g, y0.data(), w.data(), gb.data(), sb.data());
    CHECK(std::memcmp(ga.data(), gb.data(), ga.size() * sizeof(T)) == 0);
    CHECK(sa.intact());
    took += hkd::backward_data_by_forward(g) && hkd::use_forward_ws<T>(hkd::flipped_geometry(g)) ? 1 : 0;
    // backward-weight accumulates into gw
    const auto gw0 = cast<T>(random_values(g.w_size(), rng));
    std::vector<T> wa = gw0, wb = gw0;
    guarded_scratch<T> sc(g), sd(g);
    hkd::backward_weight_any<T>(g, x.data(), y0.data(), wa.data(), sc.data());
    hkd::backward_weight<T>(g, x.data(), y0.data(), wb.data(), sd.data());
    CHECK(std::memcmp(wa.data(), wb.data(), wa.size() * sizeof(T)) == 0);
    CHECK(sc.intact());
    took += hkd::use_backward_weight_ws<T>(g) ? 1 : 0;
    return took;
}

/// The StarGAN generator's and discriminator's convolutions of a conv_dim (12 x 24 images, 8 input channels).
std::vector<hk::conv_geometry> stargan_layers(int n, int c)
{
    return {{n, 8, 12, 24, c, 7, 7, 1, 3},      {n, c, 12, 24, 2 * c, 4, 4, 2, 1}, {n, 2 * c, 6, 12, 4 * c, 4, 4, 2, 1},
            {n, 4 * c, 3, 6, 4 * c, 3, 3, 1, 1}, {n, c, 12, 24, 3, 7, 7, 1, 3},     {n, 3, 12, 24, c, 4, 4, 2, 1},
            {n, c, 6, 12, 2 * c, 4, 4, 2, 1}};
}

}  // namespace forward_ws_test

using forward_ws_test::check_same_bits;
using forward_ws_test::describe;
using forward_ws_test::random_values;
using forward_ws_test::cast;
using forward_ws_test::stargan_layers;

TEST_CASE("forward_ws: conv_simd.hpp's bits on the StarGAN layers (float and double, batches 1 to 17)")
{
    int took = 0, cases = 0;
    for (const int n : {1, 3, 16, 17})
        for (const int c : {8, 16, 32})
            for (const auto& g : stargan_layers(n, c)) {
                took += check_same_bits<float>(g, unsigned(7 * n + c));
                took += check_same_bits<double>(g, unsigned(11 * n + c));
                cases += 6;
            }
    MESSAGE(took, " of ", cases, " passes took the weight-stationary path");
    CHECK(took >= cases / 3);  // the test must reach the path it checks
}

TEST_CASE("forward_ws: conv_simd.hpp's bits on random geometries (strides 1-3, long reductions, image groups)")
{
    std::mt19937 rng(2024);
    std::uniform_int_distribution<int> batch(1, 19), ch(1, 40), co(8, 70), hw(4, 20), k(1, 5), stride(1, 3);
    int took = 0, cases = 0;
    for (int i = 0; i < 120; ++i) {
        hk::conv_geometry g{batch(rng), ch(rng), hw(rng), hw(rng), co(rng), k(rng), 0, stride(rng), 0};
        g.kernel_w = g.kernel_h;
        g.pad = std::uniform_int_distribution<int>(0, g.kernel_h - 1)(rng);
        if (!g.valid()) continue;
        took += check_same_bits<float>(g, unsigned(i));
        cases += 3;
    }
    // a reduction of several chains (K = 300 > 256) and images too large for a group of 16; for the weight
    // gradients, rows longer than a pixel block (150 > wg_block_pixels), 20 images of 3 pixels in two groups, and
    // channels that end within a panel and within a vector (100 = 64 + 36 on AVX-512)
    took += check_same_bits<float>({5, 75, 6, 6, 20, 2, 2, 1, 0}, 1u);
    took += check_same_bits<float>({3, 64, 90, 90, 16, 3, 3, 1, 1}, 2u);
    took += check_same_bits<float>({2, 5, 3, 150, 24, 3, 3, 1, 1}, 3u);
    took += check_same_bits<float>({20, 40, 1, 3, 100, 1, 1, 1, 0}, 4u);
    took += check_same_bits<double>({20, 40, 1, 3, 100, 1, 1, 1, 0}, 5u);
    cases += 15;
    MESSAGE(took, " of ", cases, " passes took the weight-stationary path");
    CHECK(took >= cases / 4);
}

namespace forward_ws_test {

/// forward_stride1 (groups of simd_lanes<T> images one per lane, the rest image by image) against
/// forward_stride1_tiles on the whole batch (image by image), bit for bit, overwriting and accumulating, with and
/// without bias, within the scratch the geometry asks for. Returns whether a group of images was taken.
template <class T>
bool check_image_groups(const hk::conv_geometry& g, unsigned seed)
{
    INFO(describe(g), (sizeof(T) == 4 ? " float" : " double"));
    std::mt19937 rng(seed);
    auto x = cast<T>(random_values(g.x_size(), rng));
    for (std::size_t i = 0; i < x.size(); i += 5) x[i] = T(0);  // zeros and negative zeros inside the image too
    for (std::size_t i = 2; i < x.size(); i += 9) x[i] = T(-0.0);
    const auto w = cast<T>(random_values(g.w_size(), rng)), b = cast<T>(random_values(std::size_t(g.out_channels), rng));
    const auto y0 = cast<T>(random_values(g.y_size(), rng));
    same_forward_bits<T>(g, b, y0, [&](const T* bias, T* y, T* scratch, bool accumulate) {
        hkd::forward_stride1<T>(g, x.data(), w.data(), bias, y, scratch, accumulate);
    }, [&](const T* bias, T* y, T* scratch, bool accumulate) {
        hkd::forward_stride1_tiles<T, hkd::stride1_few_nv, hkd::stride1_few_channels>(g, x.data(), w.data(), bias, y, scratch,
                                                                                    accumulate);
    });
    return hkd::stride1_images_fits<T>(g) && g.batch >= hkd::simd_lanes<T>;
}

}  // namespace forward_ws_test

TEST_CASE("forward_stride1: groups of images one per lane give each image the bits of one image at a time (few output channels)")
{
    if constexpr (!hkd::has_simd) return;
    using forward_ws_test::check_image_groups;
    constexpr int L = hkd::simd_lanes<float>;
    int grouped = 0, cases = 0;
    // the generator's last layer (7 x 7, 32 -> 3 channels: 1568 taps, seven blocks of forward_kc) at one group, two
    // groups and three images more, and the batch of a training step
    for (const int n : {L, 2 * L + 3, 16}) {
        grouped += check_image_groups<float>({n, 32, 12, 24, 3, 7, 7, 1, 3}, unsigned(n));
        grouped += check_image_groups<double>({n, 32, 12, 24, 3, 7, 7, 1, 3}, unsigned(n + 1));
        cases += 2;
    }
    // random geometries: 1-3 output channels, kernels up to 7 x 7, padding up to 3, images of one row or column,
    // batches below, at and above the groups
    std::mt19937 rng(20261208u);
    auto pick = [&](int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(rng); };
    while (cases < 90) {
        hk::conv_geometry g{pick(1, 2 * L + 5), pick(1, 12), pick(1, 14), pick(1, 30), pick(1, 3), pick(1, 7), pick(1, 7), 1, pick(0, 3)};
        if (!g.valid()) continue;
        grouped += check_image_groups<float>(g, unsigned(cases));
        if (cases % 3 == 0) grouped += check_image_groups<double>(g, unsigned(cases) + 100u);
        ++cases;
    }
    MESSAGE(grouped, " of the checks took a group of images");
    CHECK(grouped >= 30);  // the test must reach the path it checks
}

TEST_CASE("backward-data GEMM path: the same bits whatever the pixel tile (4 or 8 pixels per micro-tile)")
{
    // conv_simd.hpp's backward_data takes 8-pixel tiles where there are 32 vector registers; the bits must be those
    // of the 4-pixel tiles that trained every earlier model: each lane's chain over the output channels and col2im's
    // order of additions do not depend on the tile
    std::mt19937 rng(31);
    std::uniform_int_distribution<int> batch(1, 4), ch(1, 40), co(1, 70), hw(4, 20), k(1, 5), stride(2, 3);
    std::vector<hk::conv_geometry> shapes;
    for (const int c : {8, 16, 32}) {
        shapes.push_back({3, c, 12, 24, 2 * c, 4, 4, 2, 1});
        shapes.push_back({2, 2 * c, 6, 12, 4 * c, 4, 4, 2, 1});
    }
    while (shapes.size() < 40) {
        hk::conv_geometry g{batch(rng), ch(rng), hw(rng), hw(rng), co(rng), k(rng), 0, stride(rng), 0};
        g.kernel_w = g.kernel_h;
        g.pad = std::uniform_int_distribution<int>(0, g.kernel_h - 1)(rng);
        if (g.valid()) shapes.push_back(g);
    }
    auto same = [&]<class T>(const hk::conv_geometry& g, unsigned seed) {
        INFO(describe(g), (sizeof(T) == 4 ? " float" : " double"));
        std::mt19937 r(seed);
        const auto w = cast<T>(random_values(g.w_size(), r)), gy = cast<T>(random_values(g.y_size(), r));
        const auto gx0 = cast<T>(random_values(g.x_size(), r));
        std::vector<T> a = gx0, b = gx0;
        forward_ws_test::guarded_scratch<T> sa(g), sb(g);
        hkd::backward_data<T, 4>(g, gy.data(), w.data(), a.data(), sa.data());
        hkd::backward_data<T, 8>(g, gy.data(), w.data(), b.data(), sb.data());
        CHECK(std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0);
        CHECK(sa.intact());
        CHECK(sb.intact());
    };
    unsigned seed = 0;
    for (const auto& g : shapes) {
        REQUIRE_FALSE(hkd::backward_data_by_forward(g));  // the GEMM path, not the flipped forward pass
        same.template operator()<float>(g, ++seed);
        same.template operator()<double>(g, ++seed);
    }
}

TEST_CASE("forward_ws: the image groups stay within the scratch the geometry asks for")
{
    const hk::conv_geometry big{3, 64, 90, 90, 16, 3, 3, 1, 1};
    const hkd::ws_scratch_layout<float> lay(big);
    CHECK(lay.group >= 1);
    CHECK(lay.group < big.batch);  // several groups: the loop over them is exercised
    CHECK(hkd::forward_ws_scratch_elements<float>(big) <= hk::conv2d_scratch_size<float>(big));
    const hk::conv_geometry small{40, 32, 3, 6, 32, 3, 3, 1, 1};
    CHECK(hkd::ws_scratch_layout<float>(small).group == hkd::ws_group_max);
    // the size does not depend on the batch (callers size scratch once for every chunk of a batch)
    hk::conv_geometry one = small;
    one.batch = 1;
    CHECK(hk::conv2d_scratch_size<float>(one) == hk::conv2d_scratch_size<float>(small));
    // the weight gradients' groups and blocks: several images of a few pixels, or one row per block
    const hkd::wg_scratch_layout<float> few({40, 32, 3, 6, 32, 3, 3, 1, 1});
    CHECK(few.group == hkd::wg_block_pixels / 18);
    CHECK(few.runs == hkd::wg_block_pixels / 6);
    const hkd::wg_scratch_layout<float> wide({2, 5, 3, 150, 24, 3, 3, 1, 1});
    CHECK(wide.group == 1);
    CHECK(wide.runs == 1);
    CHECK(hkd::backward_weight_ws_scratch_elements<float>(big) <= hk::conv2d_scratch_size<float>(big));
    CHECK(hkd::backward_weight_ws_scratch_elements<float>(small) <= hk::conv2d_scratch_size<float>(small));
}

TEST_CASE_TEMPLATE("forward_ws: the panel packers (blocks transposed in registers, or gathers) write what ws_pack writes", T,
                   float, double)
{
    std::mt19937 rng(5);
    using kernel_test::random_values;
    for (const int kk : {1, 9, 16, 49})  // 1x1, 3x3, 4x4 and 7x7 kernels: taps in one block, a block and a tail
        for (const int co : {8, 16, 17, 40, 64, 70, 128})
            for (const int ci : {3, 16, 33}) {
                const int K = ci * kk;
                const auto w = kernel_test::cast<T>(random_values(std::size_t(co) * K, rng));
                std::vector<T> a(hkd::ws_packed_elements<T>(co, K) + 64), b(a.size());
                auto* pa = reinterpret_cast<T*>((reinterpret_cast<std::uintptr_t>(a.data()) + 63) / 64 * 64);
                auto* pb = reinterpret_cast<T*>((reinterpret_cast<std::uintptr_t>(b.data()) + 63) / 64 * 64);
                hkd::ws_pack_rows<T>(co, K, w.data(), pa);
                hkd::ws_pack<T>(co, K, pb, [&](int o, int k) { return w[std::size_t(o) * K + k]; });
                CHECK(std::memcmp(pa, pb, hkd::ws_packed_elements<T>(co, K) * sizeof(T)) == 0);
                // flipped: a convolution with ci output channels, K' = co kk
                const int Kf = co * kk;
                std::vector<T> c(hkd::ws_packed_elements<T>(ci, Kf) + 64), d(c.size());
                auto* pc = reinterpret_cast<T*>((reinterpret_cast<std::uintptr_t>(c.data()) + 63) / 64 * 64);
                auto* pd = reinterpret_cast<T*>((reinterpret_cast<std::uintptr_t>(d.data()) + 63) / 64 * 64);
                hkd::ws_pack_flipped<T>(co, ci, kk, w.data(), pc);
                hkd::ws_pack<T>(ci, Kf, pd, [&](int c2, int k) {
                    const int o = k / kk, t = k % kk;
                    return w[(std::size_t(o) * ci + c2) * kk + kk - 1 - t];
                });
                CHECK(std::memcmp(pc, pd, hkd::ws_packed_elements<T>(ci, Kf) * sizeof(T)) == 0);
            }
}

namespace forward_ws_test {

/// Products of a pass of geometry g whose input row lies in the image (not in the padding above or below it):
/// what no path can skip, counted one (output row, kernel row) pair at a time.
double products_in_rows(const hk::conv_geometry& g)
{
    double pairs = 0;
    for (int h = 0; h < g.out_h(); ++h)
        for (int u = 0; u < g.kernel_h; ++u) {
            const int row = h * g.stride + u;
            pairs += (row >= g.pad && row < g.pad + g.in_h) ? 1 : 0;
        }
    return pairs * g.in_channels * g.kernel_w * g.out_w() * g.out_channels * g.batch;
}

}  // namespace forward_ws_test

TEST_CASE("conv2d_performed_macs: a hand count at the residual blocks, bounds on random geometries")
{
    using hk::conv_pass;
    // the generator's residual geometry at batch 16: 3 x 6 pixels, 3 x 3 kernels, padding 1. The top output row's
    // window puts kernel row 0 on the padding, the bottom row's kernel row 2, so 7 of the 9 (output row, kernel
    // row) pairs are performed on each weight-stationary pass (48 taps per kernel row: every tile of the weight
    // gradients lies on one kernel row, with 6 or 12 taps)
    const hk::conv_geometry g{16, 16, 3, 6, 32, 3, 3, 1, 1};
    REQUIRE(hkd::use_forward_ws<float>(g));
    REQUIRE(hkd::backward_data_ws<float>(g));
    REQUIRE(hkd::use_backward_weight_ws<float>(g));
    const double full = 16.0 * 32 * 18 * 16 * 9;
    CHECK(g.macs() == full);
    for (const conv_pass p : {conv_pass::forward, conv_pass::backward_data, conv_pass::backward_weight}) {
        CAPTURE(int(p));
        CHECK(hk::conv2d_performed_macs<float>(g, p) == full * 7 / 9);
        CHECK(hk::conv2d_performed_macs<long double>(g, p) == full);  // the reference loops skip nothing
    }
    // a weight-gradient tile across two kernel rows sums over the rows either keeps: 5 input channels give 15 taps
    // per kernel row, so with 12-tap tiles taps 12-23 span rows 0 and 1 and the tile keeps all three output rows
    const hk::conv_geometry odd{16, 5, 3, 6, 32, 3, 3, 1, 1};
    if (hkd::use_backward_weight_ws<float>(odd) && hkd::ws_tile_for<float>(32).nr == 12) {
        // tiles [0,12) row 0: 2 rows; [12,24) rows 0-1: 3; [24,36) rows 1-2: 3; [36,45) row 2: 2
        const double per_pixel = 12.0 * 2 + 12 * 3 + 12 * 3 + 9 * 2;
        CHECK(hk::conv2d_performed_macs<float>(odd, conv_pass::backward_weight) == per_pixel * 6 * 32 * 16);
    }
    // on random geometries: at least the products over the image's rows, at most the full count
    std::mt19937 rng(77);
    std::uniform_int_distribution<int> batch(1, 19), ch(1, 40), co(8, 70), hw(2, 20), k(1, 5), stride(1, 3);
    int skipped = 0;
    for (int i = 0; i < 300; ++i) {
        hk::conv_geometry r{batch(rng), ch(rng), hw(rng), hw(rng), co(rng), k(rng), 0, stride(rng), 0};
        r.kernel_w = r.kernel_h;
        r.pad = std::uniform_int_distribution<int>(0, r.kernel_h - 1)(rng);
        if (!r.valid()) continue;
        INFO(describe(r));
        const double f = hk::conv2d_performed_macs<float>(r, conv_pass::forward),
                     w = hk::conv2d_performed_macs<float>(r, conv_pass::backward_weight),
                     d = hk::conv2d_performed_macs<float>(r, conv_pass::backward_data);
        CHECK(f >= forward_ws_test::products_in_rows(r));
        CHECK(f <= r.macs());
        CHECK(w >= forward_ws_test::products_in_rows(r));
        CHECK(w <= r.macs());
        if (hkd::backward_data_by_forward(r)) {
            const hk::conv_geometry fl = hkd::flipped_geometry(r);
            CHECK(d >= forward_ws_test::products_in_rows(fl));
            CHECK(d <= fl.macs());
        } else {
            CHECK(d == r.macs());
        }
        skipped += (f < r.macs()) + (w < r.macs());
    }
    CHECK(skipped > 50);  // the skipping paths are reached

    // the generator's last layer (3 output channels, 7 x 7, padding 3, 12 output rows): its groups of simd_lanes
    // images leave out the kernel rows over the padding, 4, 5, 6, 7 x 6, 6, 5, 4 of 7 per output row (72 of 84);
    // the images past the last group and the batch below one group compute every product
    if constexpr (hkd::has_simd) {
        constexpr int L = hkd::simd_lanes<float>;
        const hk::conv_geometry last{2 * L + 3, 32, 12, 24, 3, 7, 7, 1, 3};
        REQUIRE(hkd::stride1_images_fits<float>(last));
        const double per_image = last.macs() / last.batch;
        CHECK(hk::conv2d_performed_macs<float>(last, conv_pass::forward) == 2 * L * per_image * 72 / 84 + 3 * per_image);
        hk::conv_geometry few = last;
        few.batch = L - 1;
        CHECK(hk::conv2d_performed_macs<float>(few, conv_pass::forward) == few.macs());
    }
}

TEST_CASE("performed_macs_count: every pass and the transposed convolution add what they perform")
{
    using hk::conv_pass;
    const hk::conv_geometry g{16, 16, 3, 6, 32, 3, 3, 1, 1}, s2{4, 8, 12, 24, 16, 4, 4, 2, 1};
    std::mt19937 rng(3);
    std::uint64_t expected = 0;
    std::uint64_t counted = 0;
    {
        const hk::performed_macs_count count;
        for (const auto& geo : {g, s2}) {
            const auto x = cast<float>(random_values(geo.x_size(), rng)), w = cast<float>(random_values(geo.w_size(), rng));
            const auto gy = cast<float>(random_values(geo.y_size(), rng));
            std::vector<float> y(geo.y_size()), gx(geo.x_size()), gw(geo.w_size()), xt(geo.x_size());
            std::vector<float> scratch(hk::conv2d_scratch_size<float>(geo));
            hk::conv2d_forward<float>(geo, x.data(), w.data(), nullptr, y.data(), scratch.data());
            hk::conv2d_backward_data<float>(geo, gy.data(), w.data(), gx.data(), scratch.data());
            hk::conv2d_backward_weight<float>(geo, x.data(), gy.data(), gw.data(), scratch.data());
            hk::conv_transpose2d_forward<float>(geo, gy.data(), w.data(), xt.data(), scratch.data());
            hk::conv_transpose2d_backward_weight<float>(geo, gy.data(), x.data(), gw.data(), scratch.data());
            expected += std::uint64_t(hk::conv2d_performed_macs<float>(geo, conv_pass::forward)) +
                        2 * std::uint64_t(hk::conv2d_performed_macs<float>(geo, conv_pass::backward_data)) +
                        2 * std::uint64_t(hk::conv2d_performed_macs<float>(geo, conv_pass::backward_weight));
        }
        counted = count.macs();
    }
    CHECK(counted == expected);
    CHECK(expected < std::uint64_t(5 * (g.macs() + s2.macs())));  // the residual geometry's padding rows are skipped
    // nothing is counted while no count is alive, and a new count starts from zero
    std::vector<float> x(g.x_size(), 1.0f), w(g.w_size(), 1.0f), y(g.y_size()), scratch(hk::conv2d_scratch_size<float>(g));
    hk::conv2d_forward<float>(g, x.data(), w.data(), nullptr, y.data(), scratch.data());
    CHECK(hkd::macs_counted.load() == counted);
    const hk::performed_macs_count fresh;
    CHECK(fresh.macs() == 0);
}
