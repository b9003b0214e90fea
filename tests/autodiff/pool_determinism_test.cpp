// The README's determinism claim for training ("the same seed and thread count give bitwise the same
// weights") rests on the autodiff convolutions splitting the batch over the tape's thread pool with
// static chunks and reducing the per-chunk weight gradients in chunk order. This runs the library's own
// code through the pool, a StarGAN D step with the WGAN-GP penalty (first and double backward through
// every conv op), and checks that repeated runs, and runs on a new pool of the same size, give bitwise
// equal gradients; a different thread count is only equal up to rounding (another summation order).
#include <doctest/doctest.h>

#include <handemo/autodiff.hpp>
#include <handemo/core/thread_pool.hpp>
#include <handemo/stargan/model.hpp>

#include <cstring>
#include <random>
#include <span>
#include <vector>

using namespace handemo;
using namespace handemo::autodiff;
using namespace handemo::stargan;

namespace {

using cfg = with_batch<hand_embedded, 6>;  // 6 samples: 3 chunks of 2 on a 3-thread pool

template <class M>
void randomise(M& m, unsigned seed)
{
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(-0.1f, 0.1f);
    m.for_each_parameter([&](std::string_view name, std::span<float> v, std::span<float>, std::span<const std::size_t> s) {
        const bool gamma = s.size() == 1 && name.ends_with(".weight");
        for (auto& e : v) e = gamma ? 1 + u(rng) : u(rng);
    });
}

/// One D step of the training loss on tape t (G forward, D on real/fake/x_hat, the penalty's double
/// backward): returns every parameter gradient of G and D, then the penalty value, concatenated.
std::vector<float> d_step(tape<float>& t, generator<float, cfg>& g, discriminator<float, cfg>& d)
{
    using gen = generator<float, cfg>;
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(-1, 1);
    std::vector<float> x(gen::image_shape::size), xh(x.size()), lab(gen::label_shape::size, 0.f);
    for (auto& v : x) v = u(rng);
    for (std::size_t n = 0; n < 6; ++n) lab[n * 5 + n % 5] = 1;
    t.reset();
    g.zero_grad();
    d.zero_grad();
    auto xv = t.input<gen::image_shape>(x.data());
    auto fake = g.forward(t, xv, t.input<gen::label_shape>(lab.data()));
    for (std::size_t i = 0; i < x.size(); ++i) xh[i] = 0.3f * x[i] + 0.7f * fake.data()[i];
    auto xhv = t.input<gen::image_shape>(xh.data(), true);
    auto oh = d.forward(t, xhv);
    auto gp = mean(square(l2_norm_per_sample(t.grad(sum(oh.src), xhv)) - 1.0f));
    auto loss = mean(d.forward(t, fake).src) - mean(d.forward(t, xv).src) + 10.0f * gp;
    t.backward(loss);
    std::vector<float> out;
    auto collect = [&](std::string_view, std::span<float>, std::span<float> gr, std::span<const std::size_t>) {
        out.insert(out.end(), gr.begin(), gr.end());
    };
    g.for_each_parameter(collect);
    d.for_each_parameter(collect);
    out.push_back(gp.item());
    return out;
}

bool bitwise_equal(const std::vector<float>& a, const std::vector<float>& b)
{
    return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
}

}  // namespace

TEST_CASE("autodiff through a thread pool: a D step with the penalty is bitwise repeatable for a thread count")
{
    generator<float, cfg> g;
    discriminator<float, cfg> d;
    randomise(g, 1);
    randomise(d, 2);

    thread_pool pool3(3);
    tape<float> t3(1 << 22, &pool3);
    const auto first = d_step(t3, g, d);
    REQUIRE(first.size() > 1000);
    for (int rep = 0; rep < 4; ++rep) CHECK(bitwise_equal(d_step(t3, g, d), first));

    {  // a new pool and tape of the same size: the same bits (nothing depends on thread timing)
        thread_pool again(3);
        tape<float> ta(1 << 22, &again);
        CHECK(bitwise_equal(d_step(ta, g, d), first));
    }

    // One thread reduces the weight gradients in another order: equal only up to float rounding.
    tape<float> t1(1 << 22);
    const auto single = d_step(t1, g, d);
    REQUIRE(single.size() == first.size());
    double scale = 0, diff = 0;
    for (std::size_t i = 0; i < first.size(); ++i) {
        scale = std::max(scale, double(std::abs(single[i])));
        diff = std::max(diff, double(std::abs(first[i] - single[i])));
    }
    CHECK(diff <= 1e-4 * scale);
    CHECK(bitwise_equal(d_step(t1, g, d), single));
}
