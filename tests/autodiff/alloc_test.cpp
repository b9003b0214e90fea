// Allocation count of a StarGAN training step on the autodiff tape and of generator::infer: this program
// replaces the global operator new/delete with counting versions. After the first step the arena and
// the node vector are big enough, so the second step (D step with WGAN-GP + G step) allocates nothing.
#include <handemo/stargan/model.hpp>

#include <doctest/doctest.h>

#include <atomic>
#include <cstdlib>
#include <new>
#include <random>

#include "../alloc_hook.hpp"

using namespace handemo;
using namespace handemo::autodiff;
using namespace handemo::stargan;

namespace {
using cfg = with_batch<hand_embedded, 4>;
constexpr std::size_t N = 4, C = 5;

struct step_data {
    std::vector<float> x, x_hat, org, trg;
    std::array<int, N> lab{}, trg_lab{};
};

// One StarGAN step as reference_stargan.py: D step (real, fake, GP at x_hat) then G step (adversarial,
// classification, reconstruction). Returns the two losses.
std::pair<float, float> train_step(tape<float>& t, generator<float, cfg>& g, discriminator<float, cfg>& d,
                                   const step_data& s)
{
    using img = shape<N, 3, 12, 24>;
    t.reset();
    d.zero_grad();
    g.set_requires_grad(false);
    d.set_requires_grad(true);
    auto x = t.input<img>(s.x.data());
    auto trg = t.input<shape<N, C>>(s.trg.data());
    auto real = d.forward(t, x);
    auto fake = g.forward(t, x, trg);
    auto fk = d.forward(t, fake);
    auto xh = t.input<img>(s.x_hat.data(), true);
    auto oh = d.forward(t, xh);
    auto gx = t.grad(sum(oh.src), xh);
    auto gp = mean(square(l2_norm_per_sample(gx) - 1.0f));
    auto ld = -mean(real.src) + mean(fk.src) + cross_entropy(real.cls, std::span<const int, N>(s.lab)) + 10.0f * gp;
    t.backward(ld);
    const float ld_v = ld.item();

    t.reset();
    g.zero_grad();
    g.set_requires_grad(true);
    d.set_requires_grad(false);
    auto x2 = t.input<img>(s.x.data());
    auto fake2 = g.forward(t, x2, t.input<shape<N, C>>(s.trg.data()));
    auto o2 = d.forward(t, fake2);
    auto rec = g.forward(t, fake2, t.input<shape<N, C>>(s.org.data()));
    auto lg = -mean(o2.src) + 10.0f * l1_loss(x2, rec) + cross_entropy(o2.cls, std::span<const int, N>(s.trg_lab));
    t.backward(lg);
    return {ld_v, lg.item()};
}
}  // namespace

TEST_CASE("autodiff: the second training step makes no heap allocation")
{
    generator<float, cfg> g;
    discriminator<float, cfg> d;
    std::mt19937 rng(1);
    std::uniform_real_distribution<float> u(-0.1f, 0.1f), img(-1.f, 1.f);
    g.for_each_parameter([&](std::string_view, std::span<float> v, std::span<float>, std::span<const std::size_t> sh) {
        for (auto& e : v) e = sh.size() == 1 ? 1.f + u(rng) : u(rng);
    });
    d.for_each_parameter([&](std::string_view, std::span<float> v, std::span<float>, std::span<const std::size_t>) {
        for (auto& e : v) e = u(rng);
    });
    step_data s;
    s.x.resize(N * 3 * 12 * 24);
    s.x_hat.resize(s.x.size());
    for (auto& e : s.x) e = img(rng);
    for (auto& e : s.x_hat) e = img(rng);
    s.org.assign(N * C, 0.f);
    s.trg.assign(N * C, 0.f);
    for (std::size_t n = 0; n < N; ++n) {
        s.lab[n] = int(n % C);
        s.trg_lab[n] = int((n + 2) % C);
        s.org[n * C + s.lab[n]] = 1;
        s.trg[n * C + s.trg_lab[n]] = 1;
    }
    tape<float> t(1 << 16);  // small blocks: the first step must grow the arena
    const long before_first = handemo_test::alloc_count.load();
    auto l1 = train_step(t, g, d, s);
    const long first = handemo_test::alloc_count.load() - before_first;
    const long before_second = handemo_test::alloc_count.load();
    auto l2 = train_step(t, g, d, s);
    const long second = handemo_test::alloc_count.load() - before_second;
    MESSAGE("allocations: first step " << first << ", second step " << second << ", arena "
                                       << t.arena_bytes() / 1024 << " KiB, nodes " << t.node_count());
    CHECK(first > 0);
    CHECK(second == 0);
    CHECK(l1.first == l2.first);  // same inputs and parameters (no optimiser step): same losses
    CHECK(l1.second == l2.second);
    CHECK(std::isfinite(l1.first));
    CHECK(std::isfinite(l1.second));

    generator<float, hand_embedded>::workspace ws;  // allocates here, once
    generator<float, hand_embedded> g1;
    std::vector<float> out(3 * 12 * 24), lab1 = {0, 0, 1, 0, 0};
    const long before_infer = handemo_test::alloc_count.load();
    g1.infer(s.x.data(), lab1.data(), out.data(), ws);
    g1.infer(s.x.data(), lab1.data(), out.data(), ws);
    CHECK(handemo_test::alloc_count.load() - before_infer == 0);
    // the frozen generator allocates when it packs and when its workspace is made, never in infer()
    const auto frozen = g1.freeze();
    frozen_generator<float, hand_embedded>::workspace fws(frozen);
    const long before_frozen = handemo_test::alloc_count.load();
    frozen.infer(s.x.data(), lab1.data(), out.data(), fws);
    frozen.infer(s.x.data(), lab1.data(), out.data(), fws);
    CHECK(handemo_test::alloc_count.load() - before_frozen == 0);
}
