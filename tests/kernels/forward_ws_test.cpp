// The weight-stationary path for convolutions whose weights change between calls (training:
// kernels/detail/packed_conv.hpp's forward_ws behind conv2d_forward, the stride-1 backward-data and the
// transposed convolution's backward-data, and backward_weight_ws behind both weight gradients). It must give
// conv_simd.hpp's packed and stride-1 paths bit for bit, so that a model trains to the same bits whichever path
// ran: compared with memcmp, float and double, with and without bias, overwriting and accumulating, on the
// StarGAN layers and on random geometries, batches across the image groups and pixel blocks, and with nothing
// written past the scratch it asks for.
#include <doctest/doctest.h>

#include <handemo/kernels/conv.hpp>

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
    for (const bool accumulate : {false, true})
        for (const bool with_bias : {false, true}) {
            CAPTURE(accumulate);
            CAPTURE(with_bias);
            const T* bias = with_bias ? b.data() : nullptr;
            std::vector<T> ya = y0, yb = y0;
            guarded_scratch<T> sa(g), sb(g);
            hkd::forward_any<T>(g, x.data(), w.data(), bias, ya.data(), sa.data(), accumulate);
            hkd::forward<T>(g, x.data(), w.data(), bias, yb.data(), sb.data(), accumulate);
            CHECK(std::memcmp(ya.data(), yb.data(), ya.size() * sizeof(T)) == 0);
            CHECK(sa.intact());
        }
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
