// Fast (xsimd) convolution kernels against the plain-loop reference: every StarGAN conv shape of the
// generator and discriminator and random odd geometries, all passes, float and double.
#include <doctest/doctest.h>

#include <handemo/kernels/conv.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "random_values.hpp"

namespace hk = handemo::kernels;
using kernel_test::cast;
using kernel_test::describe;
using kernel_test::random_values;

namespace {

constexpr int guard = 17;  // trailing elements that must stay untouched

/// max |got - want| / max(max |want|, 1e-30) over the first want.size() elements; guard checked.
template <class T>
double rel_error(const std::vector<T>& got, const std::vector<double>& want)
{
    double num = 0, den = 1e-30;
    for (std::size_t i = 0; i < want.size(); ++i) {
        num = std::max(num, std::abs(double(got[i]) - want[i]));
        den = std::max(den, std::abs(want[i]));
    }
    for (std::size_t i = want.size(); i < got.size(); ++i)
        if (got[i] != T(7)) return 1e9;  // write past the end
    return num / den;
}

template <class T>
std::vector<T> with_guard(const std::vector<double>& v)
{
    std::vector<T> r(v.begin(), v.end());
    r.resize(v.size() + guard, T(7));
    return r;
}

template <class T>
void check_geometry(const hk::conv_geometry& g, double tol, unsigned seed)
{
    const char* type_name = sizeof(T) == 4 ? "float" : "double";  // INFO keeps a reference: no temporaries
    INFO(describe(g), " T=", type_name);
    std::mt19937 rng(seed);
    const auto x = random_values(g.x_size(), rng), w = random_values(g.w_size(), rng),
               b = random_values(std::size_t(g.out_channels), rng), gy = random_values(g.y_size(), rng),
               gx0 = random_values(g.x_size(), rng), gw0 = random_values(g.w_size(), rng),
               gb0 = random_values(std::size_t(g.out_channels), rng);
    const auto xt = cast<T>(x), wt = cast<T>(w), bt = cast<T>(b), gyt = cast<T>(gy);
    std::vector<T> scratch(hk::conv2d_scratch_size<T>(g) + guard, std::numeric_limits<T>::quiet_NaN());
    {  // independent of the batch size: a batch's scratch serves its chunks
        hk::conv_geometry g1 = g, g16 = g;
        g1.batch = 1;
        g16.batch = 16;
        CHECK(hk::conv2d_scratch_size<T>(g1) == hk::conv2d_scratch_size<T>(g));
        CHECK(hk::conv2d_scratch_size<T>(g16) == hk::conv2d_scratch_size<T>(g));
    }

    // forward with and without bias (y is pre-filled with garbage: forward must overwrite)
    for (int with_bias = 0; with_bias < 2; ++with_bias) {
        std::vector<double> want(g.y_size());
        hk::reference::conv2d_forward<double>(g, x.data(), w.data(), with_bias ? b.data() : nullptr, want.data(), nullptr);
        auto got = with_guard<T>(std::vector<double>(g.y_size(), 3.0));
        hk::conv2d_forward<T>(g, xt.data(), wt.data(), with_bias ? bt.data() : nullptr, got.data(), scratch.data());
        CHECK_MESSAGE(rel_error(got, want) <= tol, "forward bias=", with_bias);
    }
    {  // backward data accumulates
        auto want = gx0;
        hk::reference::conv2d_backward_data<double>(g, gy.data(), w.data(), want.data(), nullptr);
        auto got = with_guard<T>(gx0);
        hk::conv2d_backward_data<T>(g, gyt.data(), wt.data(), got.data(), scratch.data());
        CHECK_MESSAGE(rel_error(got, want) <= tol, "backward_data");
    }
    {  // backward weight accumulates
        auto want = gw0;
        hk::reference::conv2d_backward_weight<double>(g, x.data(), gy.data(), want.data(), nullptr);
        auto got = with_guard<T>(gw0);
        hk::conv2d_backward_weight<T>(g, xt.data(), gyt.data(), got.data(), scratch.data());
        CHECK_MESSAGE(rel_error(got, want) <= tol, "backward_weight");
    }
    {  // bias gradient accumulates
        auto want = gb0;
        hk::reference::conv2d_backward_bias<double>(g, gy.data(), want.data());
        auto got = with_guard<T>(gb0);
        hk::conv2d_backward_bias<T>(g, gyt.data(), got.data());
        CHECK_MESSAGE(rel_error(got, want) <= tol, "backward_bias");
    }
    // transposed convolution: x_t has the conv's output shape, y_t the conv's input shape
    {
        std::vector<double> want(g.x_size());
        hk::reference::conv_transpose2d_forward<double>(g, gy.data(), w.data(), want.data(), nullptr);
        auto got = with_guard<T>(std::vector<double>(g.x_size(), -5.0));
        hk::conv_transpose2d_forward<T>(g, gyt.data(), wt.data(), got.data(), scratch.data());
        CHECK_MESSAGE(rel_error(got, want) <= tol, "conv_transpose2d_forward");
    }
    {
        const auto gyT = random_values(g.x_size(), rng);
        auto want = gy;  // gx of the transposed conv has its input's shape = conv output shape; accumulate
        hk::reference::conv_transpose2d_backward_data<double>(g, gyT.data(), w.data(), want.data(), nullptr);
        auto got = with_guard<T>(gy);
        const auto gyTt = cast<T>(gyT);
        hk::conv_transpose2d_backward_data<T>(g, gyTt.data(), wt.data(), got.data(), scratch.data());
        CHECK_MESSAGE(rel_error(got, want) <= tol, "conv_transpose2d_backward_data");

        auto wantw = gw0;
        hk::reference::conv_transpose2d_backward_weight<double>(g, gy.data(), gyT.data(), wantw.data(), nullptr);
        auto gotw = with_guard<T>(gw0);
        hk::conv_transpose2d_backward_weight<T>(g, gyt.data(), gyTt.data(), gotw.data(), scratch.data());
        CHECK_MESSAGE(rel_error(gotw, wantw) <= tol, "conv_transpose2d_backward_weight");
    }
    for (int i = 0; i < guard; ++i) {  // scratch past its declared size is never touched
        CHECK(std::isnan(double(scratch[scratch.size() - 1 - i])));
    }
}

/// The conv layers of reference_stargan.py at channel base cd (12x24 image, 5 domains).
std::vector<hk::conv_geometry> stargan_shapes(int cd, int b)
{
    return {
        {b, 8, 12, 24, cd, 7, 7, 1, 3},               // G conv7x7 3+5 -> cd
        {b, cd, 12, 24, 2 * cd, 4, 4, 2, 1},          // G down 1 (and convT up 2 = its transpose)
        {b, 2 * cd, 6, 12, 4 * cd, 4, 4, 2, 1},       // G down 2 (and convT up 1)
        {b, 4 * cd, 3, 6, 4 * cd, 3, 3, 1, 1},        // G residual conv
        {b, cd, 12, 24, 3, 7, 7, 1, 3},               // G last conv7x7 -> 3
        {b, 3, 12, 24, cd, 4, 4, 2, 1},               // D conv 1 (bias)
        {b, 4 * cd, 1, 3, 1, 3, 3, 1, 1},             // D src head
        {b, 4 * cd, 1, 3, 5, 1, 3, 1, 0},             // D cls head (full-map kernel)
    };
}

/// Which fast-path route each pass of the SIMD kernels takes for a geometry (the dispatch predicates of
/// detail/conv_simd.hpp), counted over the geometries a test checks, so a test can assert that its random
/// draws really exercised every route it claims to.
struct route_counts {
    int forward_dot = 0, forward_stride1 = 0, forward_packed = 0;
    int backward_data_by_forward = 0, backward_data_gemm = 0;
    int backward_weight_stride1 = 0, backward_weight_packed = 0, backward_weight_ws = 0;

    template <class T>
    void add(const hk::conv_geometry& g)
    {
        namespace d = hk::detail;
        if (d::use_dot_forward<T>(g)) ++forward_dot;
        else if (d::use_stride1_forward<T>(g)) ++forward_stride1;
        else ++forward_packed;
        if (d::backward_data_by_forward(g)) ++backward_data_by_forward;
        else ++backward_data_gemm;
        if (d::use_backward_weight_ws<T>(g)) ++backward_weight_ws;
        else if (d::use_stride1_backward_weight<T>(g)) ++backward_weight_stride1;
        else ++backward_weight_packed;
    }
    int total_forward() const { return forward_dot + forward_stride1 + forward_packed; }
};

void check_every_route(const route_counts& r, int geometries)
{
    INFO("forward dot/stride1/packed ", r.forward_dot, "/", r.forward_stride1, "/", r.forward_packed,
         ", backward_data by-forward/gemm ", r.backward_data_by_forward, "/", r.backward_data_gemm,
         ", backward_weight stride1/packed/ws ", r.backward_weight_stride1, "/", r.backward_weight_packed, "/",
         r.backward_weight_ws);
    CHECK(r.total_forward() == geometries);
    CHECK(r.forward_dot > 0);
    CHECK(r.forward_stride1 > 0);
    CHECK(r.forward_packed > 0);
    CHECK(r.backward_data_by_forward > 0);
    CHECK(r.backward_data_gemm > 0);
    CHECK(r.backward_weight_stride1 > 0);
    CHECK(r.backward_weight_packed > 0);
}

}  // namespace

TEST_CASE("conv kernels match the reference on the StarGAN shapes (embedded cd=32, batch 1 and 3)")
{
    for (int b : {1, 3})
        for (const auto& g : stargan_shapes(32, b)) {
            check_geometry<float>(g, 1e-5, 1u + unsigned(g.in_channels * 7 + g.out_channels));
            check_geometry<double>(g, 1e-12, 2u + unsigned(g.kernel_h));
        }
}

TEST_CASE("conv kernels match the reference on the paper's largest shapes (cd=64, batch 1)")
{
    for (const auto& g : stargan_shapes(64, 1)) check_geometry<float>(g, 1e-5, 11u);
}

TEST_CASE("conv kernels match the reference on random odd geometries")
{
    std::mt19937 rng(20200427u);
    auto pick = [&](int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(rng); };
    int tested = 0;
    route_counts routes_f, routes_d;
    while (tested < 60) {
        hk::conv_geometry g{pick(0, 1) ? 1 : 3, pick(1, 13), pick(1, 11), pick(1, 11), pick(1, 13),
                            pick(1, 7), pick(1, 7), pick(1, 2), pick(0, 3)};
        if (!g.valid()) continue;
        check_geometry<float>(g, 1e-5, unsigned(tested));
        check_geometry<double>(g, 1e-12, unsigned(tested) + 1000u);
        routes_f.add<float>(g);
        routes_d.add<double>(g);
        ++tested;
    }
    // The draws must reach every SIMD route in both precisions, or "odd geometries" tests less than it says.
    check_every_route(routes_f, tested);
    check_every_route(routes_d, tested);
}

TEST_CASE("conv kernels match the reference on random geometries with many channels (every dispatch route)")
{
    std::mt19937 rng(5u);
    auto pick = [&](int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(rng); };
    int tested = 0;
    route_counts routes;
    while (tested < 16) {
        const int k = pick(1, 7);
        hk::conv_geometry g{pick(1, 3), pick(14, 40), pick(1, 9), pick(1, 9), pick(1, 40), k, k, pick(1, 2), pick(0, 3)};
        if (!g.valid()) continue;
        check_geometry<float>(g, 1e-5, unsigned(tested) + 77u);
        routes.add<float>(g);
        ++tested;
    }
    // The random draws alone miss some routes on some instruction sets (with 16 float lanes no draw above
    // takes the stride-1 backward-weight path), so one geometry per route, chosen to take it for 4, 8 and
    // 16 lanes, is checked too.
    const hk::conv_geometry anchors[] = {
        {1, 32, 3, 6, 32, 3, 3, 1, 1},    // forward dot (K = 288, 18 pixels)
        {1, 8, 12, 24, 32, 7, 7, 1, 3},   // forward stride-1, backward-data by forward
        {3, 20, 12, 24, 40, 4, 4, 2, 1},  // forward packed, backward-data GEMM, backward-weight weight-stationary
        {1, 20, 12, 24, 8, 3, 3, 1, 1},   // backward-weight stride 1 (8 outputs, wide grid 310)
        {3, 20, 12, 24, 3, 4, 4, 2, 1},   // backward-weight packed (3 outputs, stride 2)
    };
    for (const auto& g : anchors) {
        check_geometry<float>(g, 1e-5, unsigned(tested) + 77u);
        routes.add<float>(g);
        ++tested;
    }
    check_every_route(routes, tested);  // the title's claim: every dispatch route was taken
    CHECK(routes.backward_weight_ws > 0);
}

TEST_CASE("backward-weight by parts of output channels: every weight the bits of one pass")
{
    // conv2d_backward_weight_parts() cuts a pass into parts of output channels (the autodiff's threads take one
    // each): each part, run on gy's channels of the part, must give the whole pass's weights bit for bit, so that a
    // training's bits do not depend on its thread count. The generator's and discriminator's layers of the
    // embedded, body and paper configurations, at the per-shard and whole batches.
    const std::vector<hk::conv_geometry> layers = {
        {16, 8, 9, 24, 32, 7, 7, 1, 3},    {16, 32, 9, 24, 64, 4, 4, 2, 1},  {16, 64, 5, 12, 128, 4, 4, 2, 1},
        {16, 128, 3, 6, 128, 3, 3, 1, 1},  {8, 128, 3, 6, 128, 3, 3, 1, 1},  {16, 3, 9, 24, 64, 4, 4, 2, 1},
        {16, 128, 3, 6, 256, 4, 4, 2, 1},  {16, 256, 2, 3, 1, 3, 3, 1, 1},   {8, 64, 9, 24, 64, 4, 4, 2, 1},
        {16, 256, 3, 6, 256, 3, 3, 1, 1},  {8, 10, 9, 24, 64, 7, 7, 1, 3},   {16, 64, 9, 24, 3, 7, 7, 1, 3}};
    std::mt19937 rng(5);
    int split = 0;
    for (const auto& g : layers) {
        CAPTURE(describe(g));
        const auto x = cast<float>(random_values(g.x_size(), rng)), gy = cast<float>(random_values(g.y_size(), rng));
        std::vector<float> whole(g.w_size(), 0.5f), s(hk::conv2d_scratch_size<float>(g) + 16);
        hk::conv2d_backward_weight<float>(g, x.data(), gy.data(), whole.data(), s.data());
        for (const int most : {2, 3, 4}) {
            const int parts = hk::conv2d_backward_weight_parts<float>(g, most);
            CAPTURE(most);
            CHECK(parts >= 1);
            CHECK(parts <= most);
            if (parts == 1) continue;
            ++split;
            std::vector<float> cut(g.w_size(), 0.5f);
            const std::size_t pix = std::size_t(g.out_h()) * g.out_w(), wk = std::size_t(g.in_channels) * g.kernel_h * g.kernel_w;
            int covered = 0;
            for (int k = 0; k < parts; ++k) {
                const auto [o0, o1] = hk::conv2d_backward_weight_part<float>(g, parts, k);
                CHECK(o0 == covered);
                covered = o1;
                hk::conv_geometry gp = g;
                gp.out_channels = o1 - o0;
                std::vector<float> gyp(gp.y_size()), sp(hk::conv2d_scratch_size<float>(gp) + 16);
                for (int n = 0; n < g.batch; ++n)
                    std::copy_n(gy.begin() + std::ptrdiff_t((std::size_t(n) * g.out_channels + o0) * pix), std::size_t(gp.out_channels) * pix,
                                gyp.begin() + std::ptrdiff_t(std::size_t(n) * gp.out_channels * pix));
                hk::conv2d_backward_weight<float>(gp, x.data(), gyp.data(), cut.data() + std::size_t(o0) * wk, sp.data());
            }
            CHECK(covered == g.out_channels);
            CHECK(std::equal(cut.begin(), cut.end(), whole.begin()));  // bit for bit (no NaN here)
        }
    }
    CHECK(split >= 10);  // most layers do split
    // a pass whose channels fill no two parts of 16 is not cut
    CHECK(hk::conv2d_backward_weight_parts<float>({16, 64, 9, 24, 3, 7, 7, 1, 3}, 4) == 1);
    CHECK(hk::conv2d_backward_weight_parts<float>({16, 8, 9, 24, 16, 7, 7, 1, 3}, 2) == 1);
}
