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

#include <array>
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

/// Every parameter gradient of G, then of D, concatenated.
std::vector<float> all_grads(generator<float, cfg>& g, discriminator<float, cfg>& d)
{
    std::vector<float> out;
    auto collect = [&](std::string_view, std::span<float>, std::span<float> gr, std::span<const std::size_t>) {
        out.insert(out.end(), gr.begin(), gr.end());
    };
    g.for_each_parameter(collect);
    d.for_each_parameter(collect);
    return out;
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
    std::vector<float> out = all_grads(g, d);
    out.push_back(gp.item());
    return out;
}

/// d_step's loss with the batch cut in two shards of 3, each on its own tape with its own gradient shard,
/// the shards' terms scaled by 1/2 (their share of the batch), run on `pool` (or one after the other);
/// then the gradient shards reduced. The same layout of results as d_step.
std::vector<float> d_step_sharded(thread_pool* pool, generator<float, cfg>& g, discriminator<float, cfg>& d)
{
    using gen = generator<float, cfg>;
    using img = shape<3, 3, gen::H, gen::W>;
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(-1, 1);
    std::vector<float> x(gen::image_shape::size), xh(x.size()), lab(gen::label_shape::size, 0.f);
    for (auto& v : x) v = u(rng);
    for (std::size_t n = 0; n < 6; ++n) lab[n * 5 + n % 5] = 1;
    g.set_grad_shards(2);
    d.set_grad_shards(2);
    g.zero_grad();
    d.zero_grad();
    std::array<float, 2> gps{};
    tape<float> tapes[2] = {tape<float>(1 << 20), tape<float>(1 << 20)};
    auto shard = [&](int s) {
        tape<float>& t = tapes[s];
        const std::size_t o = std::size_t(s) * 3;
        auto xv = t.input<img>(x.data() + o * img::size / 3);
        auto fake = g.forward(t, xv, t.input<shape<3, 5>>(lab.data() + o * 5), std::size_t(s));
        for (std::size_t i = 0; i < img::size; ++i) xh[o * img::size / 3 + i] = 0.3f * x[o * img::size / 3 + i] + 0.7f * fake.data()[i];
        auto xhv = t.input<img>(xh.data() + o * img::size / 3, true);
        auto oh = d.forward(t, xhv, std::size_t(s));
        auto gp = 0.5f * mean(square(l2_norm_per_sample(t.grad(sum(oh.src), xhv)) - 1.0f));
        auto loss = 0.5f * mean(d.forward(t, fake, std::size_t(s)).src) - 0.5f * mean(d.forward(t, xv, std::size_t(s)).src) + 10.0f * gp;
        gps[std::size_t(s)] = gp.item();
        t.backward(loss);
    };
    if (pool) pool->parallel_for(0, 2, shard);
    else shard(0), shard(1);
    g.reduce_grad_shards(pool);
    d.reduce_grad_shards(pool);
    std::vector<float> out = all_grads(g, d);
    out.push_back(gps[0] + gps[1]);
    g.set_grad_shards(1);
    d.set_grad_shards(1);
    return out;
}

/// The largest |a[i]| and the largest |a[i] - b[i]| (a tolerance check: diff <= tol * scale).
std::pair<double, double> scale_and_diff(const std::vector<float>& a, const std::vector<float>& b)
{
    double scale = 0, diff = 0;
    for (std::size_t i = 0; i < a.size(); ++i) {
        scale = std::max(scale, double(std::abs(a[i])));
        diff = std::max(diff, double(std::abs(a[i] - b[i])));
    }
    return {scale, diff};
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
    const auto [scale, diff] = scale_and_diff(single, first);
    CHECK(diff <= 1e-4 * scale);
    CHECK(bitwise_equal(d_step(t1, g, d), single));
}

TEST_CASE("data-parallel shards: two half batches on two tapes add up to the whole batch's gradients")
{
    generator<float, cfg> g;
    discriminator<float, cfg> d;
    randomise(g, 1);
    randomise(d, 2);
    tape<float> t1(1 << 22);
    const auto whole = d_step(t1, g, d);
    const auto seq = d_step_sharded(nullptr, g, d);
    REQUIRE(seq.size() == whole.size());
    const auto [scale, diff] = scale_and_diff(whole, seq);
    CHECK(scale > 0);
    CHECK(diff <= 1e-4 * scale);  // the same sums in another order
    // on two threads: the same bits as one after the other (each shard has its own tape and gradients;
    // the reduction is element-wise in shard order)
    thread_pool pool2(2);
    CHECK(bitwise_equal(d_step_sharded(&pool2, g, d), seq));
    // a shard that was not allocated is refused, naming set_grad_shards
    tape<float> t(1 << 20);
    std::vector<float> x(generator<float, cfg>::image_shape::size);
    CHECK_THROWS_WITH_AS(d.forward(t, t.input<generator<float, cfg>::image_shape>(x.data()), 1), doctest::Contains("set_grad_shards"),
                         value_error);
    CHECK_THROWS_AS(g.set_grad_shards(0), value_error);
}
