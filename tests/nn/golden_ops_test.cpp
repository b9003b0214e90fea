// Each autodiff op against PyTorch 1.13 (tests/fixtures/ops.safetensors from scripts/make_golden.py):
// forward value and the input gradients for a random upstream gradient gy, in float, within ops_rtol
// relative (floored at 1% of each tensor's largest magnitude): the README's bound. Measured worst:
// 1.5e-5 (conv2d 7x7 input gradient, on an AVX-512 machine); 1.1e-5 was measured on another.
#include "fixture.hpp"

#include <doctest/doctest.h>
#include <handemo/autodiff.hpp>

using namespace handemo::autodiff;
using handemo::shape;
using handemo::test::check_close;

namespace {

constexpr double ops_rtol = 2e-5;  // README: "ops within 2e-5 relative"

const handemo::safetensors_file& ops()
{
    return handemo::test::fixture("ops.safetensors");
}

template <class S>
std::vector<float> get(const std::string& name)
{
    const auto& t = ops().at(name);
    std::vector<std::size_t> want(S::dims.begin(), S::dims.end());
    INFO(name);
    REQUIRE(t.shape == want);
    return t.to_vector<float>();
}

template <class S>
var<float, S> input(tape<float>& t, const std::string& name, bool grad = true)
{
    const auto v = get<S>(name);
    return t.template input<S>(v.data(), grad);
}

// Seeds the upstream gradient gy by differentiating L = sum(y * gy).
template <class S>
void backward_with(tape<float>& t, const var<float, S>& y, const std::string& prefix)
{
    auto gy = input<S>(t, prefix + ".gy", false);
    t.backward(sum(y * gy));
}

template <class S>
void check_value(const var<float, S>& v, const std::string& name)
{
    check_close(name, v.value(), get<S>(name), ops_rtol);
}

template <class S>
void check_grad(const var<float, S>& v, const std::string& name)
{
    const std::span<const float> g(v.adjoint(), S::size);
    check_close(name, g, get<S>(name), ops_rtol);
}

}  // namespace

TEST_CASE("conv2d 4x4 stride 2 pad 1 with bias matches PyTorch")
{
    tape<float> t;
    auto x = input<shape<2, 3, 8, 8>>(t, "conv2d_s2.x");
    auto w = input<shape<4, 3, 4, 4>>(t, "conv2d_s2.w");
    auto b = input<shape<4>>(t, "conv2d_s2.b");
    auto y = conv2d<2, 1>(x, w, b);
    check_value(y, "conv2d_s2.y");
    backward_with(t, y, "conv2d_s2");
    check_grad(x, "conv2d_s2.gx");
    check_grad(w, "conv2d_s2.gw");
    check_grad(b, "conv2d_s2.gb");
}

TEST_CASE("conv2d 7x7 pad 3 with bias matches PyTorch")
{
    tape<float> t;
    auto x = input<shape<2, 3, 6, 7>>(t, "conv2d_k7.x");
    auto w = input<shape<4, 3, 7, 7>>(t, "conv2d_k7.w");
    auto b = input<shape<4>>(t, "conv2d_k7.b");
    auto y = conv2d<1, 3>(x, w, b);
    check_value(y, "conv2d_k7.y");
    backward_with(t, y, "conv2d_k7");
    check_grad(x, "conv2d_k7.gx");
    check_grad(w, "conv2d_k7.gw");
    check_grad(b, "conv2d_k7.gb");
}

TEST_CASE("conv_transpose2d 4x4 stride 2 pad 1 matches PyTorch")
{
    tape<float> t;
    auto x = input<shape<2, 4, 3, 5>>(t, "conv_transpose2d.x");
    auto w = input<shape<4, 3, 4, 4>>(t, "conv_transpose2d.w");
    auto y = conv_transpose2d<2, 1>(x, w);
    check_value(y, "conv_transpose2d.y");
    backward_with(t, y, "conv_transpose2d");
    check_grad(x, "conv_transpose2d.gx");
    check_grad(w, "conv_transpose2d.gw");
}

TEST_CASE("instance_norm (affine, eps 1e-5) matches PyTorch")
{
    tape<float> t;
    auto x = input<shape<2, 3, 4, 5>>(t, "instance_norm.x");
    auto g = input<shape<3>>(t, "instance_norm.weight");
    auto b = input<shape<3>>(t, "instance_norm.bias");
    auto y = instance_norm(x, g, b);
    check_value(y, "instance_norm.y");
    backward_with(t, y, "instance_norm");
    check_grad(x, "instance_norm.gx");
    check_grad(g, "instance_norm.gweight");
    check_grad(b, "instance_norm.gbias");
}

TEST_CASE("relu, leaky_relu(0.01) and tanh match PyTorch")
{
    using S = shape<2, 3, 4, 5>;
    {
        tape<float> t;
        auto x = input<S>(t, "relu.x");
        auto y = relu(x);
        check_value(y, "relu.y");
        backward_with(t, y, "relu");
        check_grad(x, "relu.gx");
    }
    {
        tape<float> t;
        auto x = input<S>(t, "leaky_relu.x");
        auto y = leaky_relu(x, 0.01f);
        check_value(y, "leaky_relu.y");
        backward_with(t, y, "leaky_relu");
        check_grad(x, "leaky_relu.gx");
    }
    {
        tape<float> t;
        auto x = input<S>(t, "tanh.x");
        auto y = handemo::autodiff::tanh(x);
        check_value(y, "tanh.y");
        backward_with(t, y, "tanh");
        check_grad(x, "tanh.gx");
    }
}

TEST_CASE("softmax cross-entropy and BCE with logits (mean) match PyTorch")
{
    {
        tape<float> t;
        auto x = input<shape<4, 5>>(t, "cross_entropy.logits");
        const auto l64 = ops().get<std::int64_t>("cross_entropy.labels");
        std::array<int, 4> labels{};
        for (std::size_t i = 0; i < 4; ++i) labels[i] = static_cast<int>(l64[i]);
        auto y = cross_entropy(x, std::span<const int, 4>(labels));
        check_value(y, "cross_entropy.y");
        backward_with(t, y, "cross_entropy");
        check_grad(x, "cross_entropy.glogits");
    }
    {
        tape<float> t;
        auto x = input<shape<4, 5>>(t, "bce_with_logits.logits");
        const auto tg = get<shape<4, 5>>("bce_with_logits.targets");
        auto y = bce_with_logits(x, std::span<const float, 20>(tg.data(), 20));
        check_value(y, "bce_with_logits.y");
        backward_with(t, y, "bce_with_logits");
        check_grad(x, "bce_with_logits.glogits");
    }
}

TEST_CASE("L1 mean and per-sample L2 norm match PyTorch")
{
    {
        tape<float> t;
        auto a = input<shape<2, 3, 4, 5>>(t, "l1_mean.a");
        auto b = input<shape<2, 3, 4, 5>>(t, "l1_mean.b");
        auto y = l1_loss(a, b);
        check_value(y, "l1_mean.y");
        backward_with(t, y, "l1_mean");
        check_grad(a, "l1_mean.ga");
        check_grad(b, "l1_mean.gb");
    }
    {
        tape<float> t;
        auto x = input<shape<4, 3, 4, 5>>(t, "l2_norm.x");
        auto y = l2_norm_per_sample(x);
        check_value(y, "l2_norm.y");
        backward_with(t, y, "l2_norm");
        check_grad(x, "l2_norm.gx");
    }
}
