// A tape packs a parameter's convolution weights into panels once and gives the panels to every convolution
// that reads the parameter until reset() (tape::packed, autodiff/conv.hpp's weight_panels): the same panels and
// kernels as packing at each call, so the same bits, and a reset forgets them, so new weights are packed again.
#include "gradcheck.hpp"

#include <handemo/kernels/conv.hpp>

#include <cstring>
#include <random>
#include <vector>

using namespace handemo;
using namespace handemo::autodiff;
using handemo::test::gc_param;
using handemo::test::gradcheck;
using handemo::test::leaf;
using handemo::test::random_param;

namespace panels_case {

// Shapes that take the weight-stationary kernel both ways (checked below): 32 and 16 channels, 9 x 23 images.
constexpr std::size_t N = 2, Ci = 16, Co = 32, H = 9, W = 23;
using x_shape = shape<N, Ci, H, W>;
using w1_shape = shape<Co, Ci, 3, 3>;
using w2_shape = shape<Ci, Co, 3, 3>;

std::vector<float> random_values(std::size_t n, unsigned seed, float a)
{
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(-a, a);
    std::vector<float> v(n);
    for (auto& e : v) e = u(rng);
    return v;
}

struct run_result {
    std::vector<float> loss, gx, gw1, gw2;
    std::size_t packed = 0;
};

/// A loss that reads w1 in three forward passes, both weights in backward-data passes, and the gradient of a
/// gradient (the penalty's shape): h = lrelu(conv(x, w1)), y = conv(h, w2) + conv(conv(x2, w1), w2),
/// loss = sum(y r) + mean((|d sum(y r) / dx| - 1)^2). With `as_parameters` the weights are parameters (caller
/// memory, packed once per tape); else copies on the tape, which the kernels pack at every call.
run_result run(tape<float>& t, const std::vector<float>& x, const std::vector<float>& x2, std::vector<float>& w1,
               std::vector<float>& w2, const std::vector<float>& r, bool as_parameters, bool keep_w1 = false)
{
    if (keep_w1)
        t.reset_keeping_packed(w1.data(), w1.data() + w1.size());
    else
        t.reset();
    run_result out;
    std::vector<float> g1(w1.size(), 0.f), g2(w2.size(), 0.f);
    var<float, w1_shape> v1;
    var<float, w2_shape> v2;
    if (as_parameters) {
        v1 = t.parameter<w1_shape>(w1.data(), g1.data());
        v2 = t.parameter<w2_shape>(w2.data(), g2.data());
    } else {
        v1 = t.input<w1_shape>(w1.data(), true);
        v2 = t.input<w2_shape>(w2.data(), true);
    }
    auto xv = t.input<x_shape>(x.data(), true);
    auto x2v = t.input<x_shape>(x2.data());
    auto h = leaky_relu(conv2d<1, 1>(xv, v1), 0.2f);
    auto y = conv2d<1, 1>(h, v2) + conv2d<1, 1>(conv2d<1, 1>(x2v, v1), v2);
    auto head = sum(y * t.input<x_shape>(r.data()));
    auto gx = t.grad(head, xv);
    auto loss = head + mean(square(l2_norm_per_sample(gx) - 1.0f));
    t.backward(loss);
    out.loss.assign(loss.data(), loss.data() + 1);
    out.gx.assign(xv.adjoint(), xv.adjoint() + x_shape::size);
    if (as_parameters) {
        out.gw1 = g1;
        out.gw2 = g2;
    } else {
        out.gw1.assign(v1.adjoint(), v1.adjoint() + w1.size());
        out.gw2.assign(v2.adjoint(), v2.adjoint() + w2.size());
    }
    out.packed = t.packed_count();
    return out;
}

bool same_bits(const std::vector<float>& a, const std::vector<float>& b)
{
    return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
}

/// The loss, the input gradient and both weight gradients of two runs, bit for bit.
bool same_run(const run_result& a, const run_result& b)
{
    return same_bits(a.loss, b.loss) && same_bits(a.gx, b.gx) && same_bits(a.gw1, b.gw1) && same_bits(a.gw2, b.gw2);
}

}  // namespace panels_case

TEST_CASE("autodiff: a parameter's convolution panels are packed once per tape, the same bits as at every call")
{
    using namespace panels_case;
    const kernels::conv_geometry g1{int(N), int(Ci), int(H), int(W), int(Co), 3, 3, 1, 1};
    const kernels::conv_geometry g2{int(N), int(Co), int(H), int(W), int(Ci), 3, 3, 1, 1};
    // the shapes exercise what they are for: both weights packed for the forward and the backward-data passes
    REQUIRE(kernels::conv2d_panel_elements<float>(g1, kernels::conv_panels::forward) > 0);
    REQUIRE(kernels::conv2d_panel_elements<float>(g1, kernels::conv_panels::backward_data) > 0);
    REQUIRE(kernels::conv2d_panel_elements<float>(g2, kernels::conv_panels::forward) > 0);
    REQUIRE(kernels::conv2d_panel_elements<float>(g2, kernels::conv_panels::backward_data) > 0);

    const auto x = random_values(x_shape::size, 1, 1.f), x2 = random_values(x_shape::size, 2, 1.f);
    const auto r = random_values(x_shape::size, 3, 1.f);
    auto w1 = random_values(w1_shape::size, 4, 0.2f), w2 = random_values(w2_shape::size, 5, 0.2f);
    tape<float> t, ref;
    const run_result a = run(t, x, x2, w1, w2, r, true);
    const run_result b = run(ref, x, x2, w1, w2, r, false);
    CHECK(a.packed == 4);  // (w1, w2) x (forward, backward-data), each once for all of its passes
    CHECK(b.packed == 0);
    CHECK(same_run(a, b));

    // an optimiser's update between two resets: the tape packs the new weights, not the old panels
    for (auto& v : w1) v *= -1.5f;
    const run_result c = run(t, x, x2, w1, w2, r, true);
    const run_result d = run(ref, x, x2, w1, w2, r, false);
    CHECK(!same_bits(c.gx, a.gx));
    CHECK(same_run(c, d));

    // a reset that keeps w1's panels (the trainer's G phase keeps G's from the D phase): w2 changed and is packed
    // again, w1 is not, and the result is the same bits as packing everything at every call
    for (auto& v : w2) v *= 0.75f;
    const run_result e = run(t, x, x2, w1, w2, r, true, true);
    const run_result f = run(ref, x, x2, w1, w2, r, false);
    CHECK(e.packed == 4);
    CHECK(same_run(e, f));
    // the kept panels are really the old ones: had w1 changed, keeping them would be wrong (the caller's promise)
    for (auto& v : w1) v *= 0.5f;
    const run_result stale = run(t, x, x2, w1, w2, r, true, true);
    const run_result fresh = run(ref, x, x2, w1, w2, r, false);
    CHECK(!same_bits(stale.gx, fresh.gx));
}

TEST_CASE("autodiff: gradient check through panels packed once per tape (double, a weight read four times)")
{
    // 9 channels fill a vector of doubles (at most 8 lanes) and make K = 81 no multiple of the lanes, which keeps
    // the few pixels of 5 x 6 images off the dot path: the weight-stationary kernel both ways
    const kernels::conv_geometry g{1, 9, 5, 6, 9, 3, 3, 1, 1};
    REQUIRE(kernels::conv2d_panel_elements<double>(g, kernels::conv_panels::forward) > 0);
    REQUIRE(kernels::conv2d_panel_elements<double>(g, kernels::conv_panels::backward_data) > 0);
    std::mt19937 rng(11);
    std::vector<gc_param> ps{random_param(9 * 5 * 6, rng), random_param(9 * 9 * 3 * 3, rng, 0.3),
                             random_param(9 * 5 * 6, rng)};
    gradcheck(ps, [&](tape<double>& t) {
        auto x = leaf<shape<1, 9, 5, 6>>(t, ps, 0);
        auto w = leaf<shape<9, 9, 3, 3>>(t, ps, 1);
        auto y = conv2d<1, 1>(square(conv2d<1, 1>(x, w)), w);
        auto head = sum(y * leaf<shape<1, 9, 5, 6>>(t, ps, 2));
        auto gx = t.grad(head, x);
        REQUIRE(t.packed_count() == 2);  // w's forward and backward-data panels, packed once each so far
        return (head + sum(square(gx))).id;
    });
}
