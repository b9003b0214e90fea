// Finite-difference gradient checks (double) of every element-wise, reduction, layout and loss op of
// the autodiff tape, and of the graph backward (double derivative) of the ones WGAN-GP uses.
#include "gradcheck.hpp"

#include <array>

using namespace handemo;
using namespace handemo::autodiff;
using handemo::test::gc_param;
using handemo::test::gradcheck;
using handemo::test::leaf;
using handemo::test::random_param;
using autodiff::tape;

namespace {
using S = shape<2, 3, 4>;
std::vector<gc_param> params(std::initializer_list<std::size_t> sizes, unsigned seed = 1)
{
    std::mt19937 rng(seed);
    std::vector<gc_param> ps;
    for (std::size_t n : sizes) ps.push_back(random_param(n, rng));
    return ps;
}
// A fixed random weighting so that sums do not hide wrong per-element gradients.
template <class Sh>
var<double, Sh> weights(tape<double>& t, unsigned seed = 3)
{
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-1, 1);
    std::array<double, Sh::size> w{};
    for (auto& v : w) v = u(rng);
    return t.template input<Sh>(w.data());
}
template <class Sh>
int weighted_sum(const var<double, Sh>& y)
{
    return sum(y * weights<Sh>(*y.t)).id;
}
}  // namespace

TEST_CASE("autodiff: forward values of simple ops")
{
    tape<double> t;
    const double a[4] = {1, -2, 3, -4}, b[4] = {0.5, 0.5, -1, 2};
    auto x = t.input<shape<2, 2>>(a);
    auto y = t.input<shape<2, 2>>(b);
    CHECK(sum(x + y).item() == doctest::Approx(0.0));
    CHECK(sum(x * y).item() == doctest::Approx(0.5 - 1 - 3 - 8));
    CHECK(mean(abs(x)).item() == doctest::Approx(2.5));
    CHECK(sum(relu(x)).item() == doctest::Approx(4.0));
    CHECK(sum(leaky_relu(x, 0.1)).item() == doctest::Approx(4.0 - 0.6));
    auto n = l2_norm_per_sample(x);
    CHECK(n.data()[0] == doctest::Approx(std::sqrt(5.0)));
    CHECK(n.data()[1] == doctest::Approx(5.0));
    const int lab[2] = {0, 1};
    // logits rows (1,-2) and (3,-4): CE = mean(log(1+e^-3), log(e^3+e^-4) + 4)
    auto ce = cross_entropy(x, std::span<const int, 2>(lab));
    CHECK(ce.item() == doctest::Approx((std::log1p(std::exp(-3.0)) + std::log(std::exp(3.0) + std::exp(-4.0)) + 4) / 2));
    const int bad[2] = {0, 7};
    CHECK_THROWS_AS(cross_entropy(x, std::span<const int, 2>(bad)), value_error);
    auto p = pad<3, 4>(t.input<shape<1, 1, 2, 2>>(a));
    CHECK(p.data()[0] == 1);
    CHECK(p.data()[1] == -2);
    CHECK(p.data()[2] == 0);
    CHECK(p.data()[4] == 3);
    CHECK(p.data()[11] == 0);
    auto c = crop<2, 2>(p);
    for (int i = 0; i < 4; ++i) CHECK(c.data()[i] == a[i]);
}

TEST_CASE("autodiff: gradient check, element-wise ops")
{
    auto ps = params({S::size, S::size});
    auto run = [&](auto op) {
        return gradcheck(ps, [&](tape<double>& t) {
            auto a = leaf<S>(t, ps, 0);
            auto b = leaf<S>(t, ps, 1);
            return weighted_sum(op(a, b));
        });
    };
    SUBCASE("add") { run([](auto a, auto b) { return a + b; }); }
    SUBCASE("sub") { run([](auto a, auto b) { return a - b; }); }
    SUBCASE("mul") { run([](auto a, auto b) { return a * b; }); }
    SUBCASE("scalar") { run([](auto a, auto b) { return (2.5 * a + 0.5) - b * b - 1.0 + (-a); }); }
    SUBCASE("relu") { run([](auto a, auto b) { return relu(a) * b; }); }
    SUBCASE("leaky_relu") { run([](auto a, auto b) { return leaky_relu(a, 0.01) * b; }); }
    SUBCASE("tanh") { run([](auto a, auto b) { return tanh(a * b); }); }
    SUBCASE("square") { run([](auto a, auto b) { return square(a) + b; }); }
    SUBCASE("sqrt") { run([](auto a, auto b) { return sqrt(square(a) + 0.1) * b; }); }
    SUBCASE("abs") { run([](auto a, auto b) { return abs(a) * b; }); }
}

TEST_CASE("autodiff: gradient check, reductions and losses")
{
    auto ps = params({S::size});
    auto run = [&](auto op) {
        return gradcheck(ps, [&](tape<double>& t) { return op(leaf<S>(t, ps, 0)).id; });
    };
    SUBCASE("sum") { run([](auto a) { return sum(a * a); }); }
    SUBCASE("mean") { run([](auto a) { return mean(a * a); }); }
    SUBCASE("sum_per_sample") { run([](auto a) { auto s = sum_per_sample(a * a); return sum(s * s); }); }
    SUBCASE("mean_per_sample") { run([](auto a) { auto s = mean_per_sample(a * a); return sum(s * s); }); }
    SUBCASE("l2_norm_per_sample") { run([](auto a) { return mean(square(l2_norm_per_sample(a) - 1.0)); }); }
    SUBCASE("l1_loss") {
        run([](auto a) { return l1_loss(a, weights<S>(*a.t)); });
    }
    SUBCASE("cross_entropy") {
        static const int lab[6] = {0, 3, 1, 2, 3, 0};
        run([](auto a) {
            return cross_entropy(var<double, shape<6, 4>>{a.t, a.id}, std::span<const int, 6>(lab));
        });
    }
    SUBCASE("bce_with_logits") {
        static std::array<double, S::size> tgt{};
        for (std::size_t i = 0; i < tgt.size(); ++i) tgt[i] = (i % 3) / 2.0;
        run([](auto a) { return bce_with_logits(a, std::span<const double, S::size>(tgt)); });
    }
}

TEST_CASE("autodiff: gradient check, layout ops")
{
    auto ps = params({2 * 3 * 2 * 3, 2 * 2, 2 * 3 * 3 * 4});
    gradcheck(ps, [&](tape<double>& t) {
        auto x = leaf<shape<2, 3, 2, 3>>(t, ps, 0);
        auto l = leaf<shape<2, 2>>(t, ps, 1);
        auto y = concat_channels(x, tile<2, 3>(l));
        return weighted_sum(pad<3, 5>(y));
    });
    gradcheck(ps, [&](tape<double>& t) { return weighted_sum(crop<2, 3>(leaf<shape<2, 3, 3, 4>>(t, ps, 2))); });
}

TEST_CASE("autodiff: gradient check, conv2d / conv_transpose2d / instance_norm")
{
    SUBCASE("conv2d 4x4 s2 p1 with bias")
    {
        auto ps = params({2 * 3 * 6 * 8, 4 * 3 * 4 * 4, 4});
        gradcheck(ps, [&](tape<double>& t) {
            return weighted_sum(conv2d<2, 1>(leaf<shape<2, 3, 6, 8>>(t, ps, 0), leaf<shape<4, 3, 4, 4>>(t, ps, 1),
                                             leaf<shape<4>>(t, ps, 2)));
        });
    }
    SUBCASE("conv2d 7x7 p3 and full-map head")
    {
        auto ps = params({2 * 3 * 4 * 5, 2 * 3 * 7 * 7, 3 * 2 * 4 * 5});
        gradcheck(ps, [&](tape<double>& t) {
            auto y = conv2d<1, 3>(leaf<shape<2, 3, 4, 5>>(t, ps, 0), leaf<shape<2, 3, 7, 7>>(t, ps, 1));
            return weighted_sum(conv2d<1, 0>(y, leaf<shape<3, 2, 4, 5>>(t, ps, 2)));
        });
    }
    SUBCASE("conv_transpose2d 4x4 s2 p1")
    {
        auto ps = params({2 * 4 * 3 * 2, 4 * 3 * 4 * 4});
        gradcheck(ps, [&](tape<double>& t) {
            auto y = conv_transpose2d<2, 1>(leaf<shape<2, 4, 3, 2>>(t, ps, 0), leaf<shape<4, 3, 4, 4>>(t, ps, 1));
            static_assert(std::is_same_v<decltype(y)::shape_type, shape<2, 3, 6, 4>>);
            return weighted_sum(y);
        });
    }
    SUBCASE("instance_norm")
    {
        auto ps = params({2 * 3 * 3 * 4, 3, 3});
        gradcheck(ps, [&](tape<double>& t) {
            auto y = instance_norm(leaf<shape<2, 3, 3, 4>>(t, ps, 0), leaf<shape<3>>(t, ps, 1), leaf<shape<3>>(t, ps, 2));
            return weighted_sum(y);
        });
    }
}

TEST_CASE("autodiff: instance_norm matches the definition")
{
    tape<double> t;
    const double x[6] = {1, 2, 3, 4, 10, 20}, g[2] = {2, 1}, b[2] = {0.5, -1};
    auto y = instance_norm(t.input<shape<1, 2, 1, 3>>(x), t.input<shape<2>>(g), t.input<shape<2>>(b));
    const double r0 = 1 / std::sqrt(2.0 / 3 + 1e-5);
    CHECK(y.data()[0] == doctest::Approx(2 * (-1) * r0 + 0.5));
    CHECK(y.data()[1] == doctest::Approx(0.5));
    CHECK(y.data()[2] == doctest::Approx(2 * r0 + 0.5));
}

// Double backward: for each op D uses, check d/d(params) of a loss built from d(sum of output)/d(input).
TEST_CASE("autodiff: gradient check of gradients (double backward)")
{
    SUBCASE("conv2d with bias + leaky_relu")
    {
        auto ps = params({2 * 2 * 6 * 6, 3 * 2 * 4 * 4, 3, 2 * 3 * 3 * 3});
        ps[0].check = false;  // d GP / d x is 0 almost everywhere for a piecewise-linear D (checked below)
        gradcheck(ps, [&](tape<double>& t) {
            auto x = leaf<shape<2, 2, 6, 6>>(t, ps, 0);
            auto h = leaky_relu(conv2d<2, 1>(x, leaf<shape<3, 2, 4, 4>>(t, ps, 1), leaf<shape<3>>(t, ps, 2)), 0.01);
            auto o = sum(h * leaf<shape<2, 3, 3, 3>>(t, ps, 3));
            auto gx = t.grad(o, x);
            return mean(square(l2_norm_per_sample(gx) - 1.0)).id;
        });
    }
    SUBCASE("smooth chain: conv2d -> square -> conv2d head, gradient w.r.t. input and weights")
    {
        auto ps = params({1 * 2 * 4 * 4, 2 * 2 * 3 * 3, 2, 1 * 2 * 4 * 4});
        gradcheck(ps, [&](tape<double>& t) {
            auto x = leaf<shape<1, 2, 4, 4>>(t, ps, 0);
            auto h = square(conv2d<1, 1>(x, leaf<shape<2, 2, 3, 3>>(t, ps, 1), leaf<shape<2>>(t, ps, 2)));
            auto o = sum(conv2d<1, 0>(h, leaf<shape<1, 2, 4, 4>>(t, ps, 3)));
            auto gx = t.grad(o, x);
            return sum(square(gx) * weights<shape<1, 2, 4, 4>>(t)).id;
        });
    }
    SUBCASE("gradient w.r.t. a weight (conv_weight_grad node) and a bias (channel_sum node)")
    {
        auto ps = params({1 * 2 * 5 * 5, 2 * 2 * 3 * 3, 2});
        gradcheck(ps, [&](tape<double>& t) {
            auto x = leaf<shape<1, 2, 5, 5>>(t, ps, 0);
            auto w = leaf<shape<2, 2, 3, 3>>(t, ps, 1);
            auto b = leaf<shape<2>>(t, ps, 2);
            auto o = sum(square(conv2d<2, 1>(x, w, b)));
            auto gw = t.grad(o, w);
            auto gb = t.grad(o, b);
            return (sum(square(gw) * weights<shape<2, 2, 3, 3>>(t)) + sum(gb * gb)).id;
        });
    }
    SUBCASE("conv_transpose2d, mul, sub, affine, mean")
    {
        auto ps = params({1 * 2 * 2 * 3, 2 * 1 * 4 * 4, 1 * 1 * 4 * 6});
        gradcheck(ps, [&](tape<double>& t) {
            auto x = leaf<shape<1, 2, 2, 3>>(t, ps, 0);
            auto y = conv_transpose2d<2, 1>(x, leaf<shape<2, 1, 4, 4>>(t, ps, 1));
            auto z = leaf<shape<1, 1, 4, 6>>(t, ps, 2);
            auto o = mean(square(2.0 * (y * z) - z + 1.0));
            auto gx = t.grad(o, x);
            return sum(square(gx)).id;
        });
    }
}

TEST_CASE("autodiff: grad of a piecewise-linear net is constant in its input; errors are reported")
{
    std::mt19937 rng(5);
    auto xp = random_param(1 * 1 * 4 * 4, rng), wp = random_param(2 * 1 * 4 * 4, rng);
    tape<double> t;
    auto x = t.input<shape<1, 1, 4, 4>>(xp.value.data(), true);
    auto w = t.parameter<shape<2, 1, 4, 4>>(wp.value.data(), wp.grad.data());
    auto o = sum(leaky_relu(conv2d<2, 1>(x, w), 0.2));
    auto gx = t.grad(o, x);
    auto gp = sum(square(gx));
    t.backward(gp);
    CHECK(t.at(x.id).adjoint[0] == 0.0);
    // tanh has no graph backward: grad through it is a clear error, not a wrong number
    auto o2 = sum(tanh(conv2d<2, 1>(x, w)));
    CHECK_THROWS_AS(t.grad(o2, x), value_error);
    CHECK_THROWS_AS(t.backward(gx.id), shape_error);
}

TEST_CASE("autodiff: each op reads back only its own typed parameter record")
{
    tape<double> t;
    const std::array<double, 6> v{1, -2, 3, -4, 5, -6};
    auto x = t.input<shape<2, 3>>(v.data(), true);
    auto y = leaky_relu(x, 0.25);
    auto s = mean_per_sample(y);
    const node<double>& ny = t.at(y.id);
    REQUIRE(ny.holds_params<autodiff::detail::leaky_relu_params<double>>());
    CHECK(ny.params<autodiff::detail::leaky_relu_params<double>>().slope == 0.25);
    const auto r = t.at(s.id).params<autodiff::detail::row_reduce_params<double>>();
    CHECK(r.rows == 2);
    CHECK(r.cols == 3);
    CHECK(r.factor == doctest::Approx(2.0 / 6.0));
    // asking a node for another op's record (or a leaf for any) is a reported bug, not a misread value
    CHECK_FALSE(ny.holds_params<autodiff::detail::row_reduce_params<double>>());
    CHECK_THROWS_AS(ny.params<autodiff::detail::row_reduce_params<double>>(), value_error);
    CHECK_THROWS_AS(t.at(x.id).params<autodiff::detail::leaky_relu_params<double>>(), value_error);
}
