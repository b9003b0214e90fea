// The reference kernels themselves: a hand-computed cross-correlation (not a flipped convolution) and
// the adjoint identities that make backward-data / backward-weight / bias the exact gradients of the
// forward pass, in double precision; and the transposed convolution's output size rule.
#include <doctest/doctest.h>

#include <handemo/kernels/reference.hpp>

#include <cmath>
#include <random>
#include <vector>

namespace hk = handemo::kernels;
namespace ref = handemo::kernels::reference;

namespace {
double dot(const std::vector<double>& a, const std::vector<double>& b)
{
    double s = 0;
    for (std::size_t i = 0; i < a.size(); ++i) s += a[i] * b[i];
    return s;
}
std::vector<double> rnd(std::size_t n, std::mt19937& rng)
{
    std::normal_distribution<double> d;
    std::vector<double> v(n);
    for (auto& e : v) e = d(rng);
    return v;
}
}  // namespace

TEST_CASE("reference conv2d_forward is PyTorch's cross-correlation with zero padding")
{
    // x = [[1,2,3],[4,5,6],[7,8,9]], w = [[1,0],[0,-1]] (not flipped), pad 1, stride 2 -> 2x2
    const hk::conv_geometry g{1, 1, 3, 3, 1, 2, 2, 2, 1};
    REQUIRE(g.out_h() == 2);
    REQUIRE(g.out_w() == 2);
    const double x[9] = {1, 2, 3, 4, 5, 6, 7, 8, 9}, w[4] = {1, 0, 0, -1}, b[1] = {0.5};
    double y[4];
    ref::conv2d_forward<double>(g, x, w, b, y, nullptr);
    // out(i,j) = x(2i-1, 2j-1) - x(2i, 2j) + 0.5
    CHECK(y[0] == doctest::Approx(0 - 1 + 0.5));
    CHECK(y[1] == doctest::Approx(0 - 3 + 0.5));
    CHECK(y[2] == doctest::Approx(0 - 7 + 0.5));
    CHECK(y[3] == doctest::Approx(5 - 9 + 0.5));
}

TEST_CASE("reference backward passes are the adjoints of the forward pass (double)")
{
    std::mt19937 rng(7);
    const hk::conv_geometry gs[] = {{2, 3, 5, 7, 4, 3, 3, 1, 1}, {3, 2, 6, 5, 3, 4, 4, 2, 1},
                                    {1, 4, 4, 4, 2, 1, 1, 1, 0}, {2, 2, 5, 5, 3, 5, 3, 2, 3},
                                    {1, 5, 3, 6, 2, 3, 6, 1, 0}};
    for (const auto& g : gs) {
        const auto x = rnd(g.x_size(), rng), w = rnd(g.w_size(), rng), gy = rnd(g.y_size(), rng),
                   b = rnd(std::size_t(g.out_channels), rng);
        std::vector<double> y(g.y_size()), y0(g.y_size()), gx(g.x_size(), 0.0), gw(g.w_size(), 0.0),
            gb(std::size_t(g.out_channels), 0.0);
        ref::conv2d_forward<double>(g, x.data(), w.data(), nullptr, y.data(), nullptr);
        ref::conv2d_backward_data<double>(g, gy.data(), w.data(), gx.data(), nullptr);
        ref::conv2d_backward_weight<double>(g, x.data(), gy.data(), gw.data(), nullptr);
        const double lhs = dot(y, gy);
        // <conv(x, w), gy> = <x, bwd_data(gy, w)> = <w, bwd_weight(x, gy)>
        CHECK(dot(x, gx) == doctest::Approx(lhs).epsilon(1e-12));
        CHECK(dot(w, gw) == doctest::Approx(lhs).epsilon(1e-12));
        // <conv(x,w,b) - conv(x,w,0), gy> = <b, bwd_bias(gy)>
        ref::conv2d_forward<double>(g, x.data(), w.data(), b.data(), y0.data(), nullptr);
        for (std::size_t i = 0; i < y0.size(); ++i) y0[i] -= y[i];
        ref::conv2d_backward_bias<double>(g, gy.data(), gb.data());
        CHECK(dot(b, gb) == doctest::Approx(dot(y0, gy)).epsilon(1e-12));
        // finite difference of L = <conv(x,w), gy> in one x and one w entry (L is linear: exact up to rounding)
        const std::size_t ix = g.x_size() / 2, iw = g.w_size() / 3;
        auto xp = x;
        xp[ix] += 1e-3;
        auto wp = w;
        wp[iw] += 1e-3;
        std::vector<double> yp(g.y_size());
        ref::conv2d_forward<double>(g, xp.data(), w.data(), nullptr, yp.data(), nullptr);
        CHECK((dot(yp, gy) - lhs) / 1e-3 == doctest::Approx(gx[ix]).epsilon(1e-6));
        ref::conv2d_forward<double>(g, x.data(), wp.data(), nullptr, yp.data(), nullptr);
        CHECK((dot(yp, gy) - lhs) / 1e-3 == doctest::Approx(gw[iw]).epsilon(1e-6));

        // transposed conv: forward = bwd_data, its gradients are the adjoints again
        const auto xt = rnd(g.y_size(), rng), gyt = rnd(g.x_size(), rng);
        std::vector<double> yt(g.x_size()), gxt(g.y_size(), 0.0), gwt(g.w_size(), 0.0);
        ref::conv_transpose2d_forward<double>(g, xt.data(), w.data(), yt.data(), nullptr);
        ref::conv_transpose2d_backward_data<double>(g, gyt.data(), w.data(), gxt.data(), nullptr);
        ref::conv_transpose2d_backward_weight<double>(g, xt.data(), gyt.data(), gwt.data(), nullptr);
        const double lt = dot(yt, gyt);
        CHECK(dot(xt, gxt) == doctest::Approx(lt).epsilon(1e-12));
        CHECK(dot(w, gwt) == doctest::Approx(lt).epsilon(1e-12));
    }
}

TEST_CASE("ConvTranspose2d geometry: (H-1)s - 2p + k round-trips through out_h/out_w")
{
    // StarGAN up-sampling: ConvTranspose2d(4cd -> 2cd, 4, 2, 1) on 3x6 gives 6x12
    const int H = 3, W = 6, k = 4, s = 2, p = 1;
    const hk::conv_geometry g{1, 64, (H - 1) * s - 2 * p + k, (W - 1) * s - 2 * p + k, 128, k, k, s, p};
    CHECK(g.in_h == 6);
    CHECK(g.in_w == 12);
    CHECK(g.out_h() == H);
    CHECK(g.out_w() == W);
    CHECK(g.valid());
    CHECK_FALSE(hk::conv_geometry{1, 1, 2, 2, 1, 5, 5, 1, 1}.valid());
}
