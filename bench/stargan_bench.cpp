// Whole-StarGAN benchmarks (hand paper Sec. 3.3) side by side with reference_stargan.py: batch-1 generator
// inference, single thread, tape-free (generator::infer); one training step (D step with WGAN-GP + G step,
// batch 16, Adam on both) on the autodiff tape with the batch split over 2 threads and over 1 (threads:N). GFLOP/s counters are
// multiply-adds x 2 / time (for training, an estimate: 7 G-forward + 14 D-forward equivalents per step).
#include <handemo/nn/adam.hpp>
#include <handemo/nn/init.hpp>
#include <handemo/stargan/model.hpp>

#include <benchmark/benchmark.h>

#include "../tests/micro/helpers.hpp"  // runtime_model, seed_generator, flat_parameters

#include <random>
#include <thread>

using namespace handemo;
using namespace handemo::stargan;
using autodiff::tape;

namespace {

/// frozen: frozen_generator (weights packed once, the path of transfer and the CLI); else generator::infer.
template <class Config, bool frozen>
void bm_infer(benchmark::State& st)
{
    generator<float, Config> g;
    rng gen(1);
    init_pytorch_default(g, gen);
    const auto f = g.freeze();
    typename generator<float, Config>::workspace ws;
    typename frozen_generator<float, Config>::workspace fws(f);
    constexpr std::size_t H = dims<Config>::H, W = dims<Config>::W, C = Config::domains;
    std::vector<float> x(3 * H * W), lab(C, 0.f), out(x.size());
    std::mt19937 r(2);
    std::uniform_real_distribution<float> u(-1, 1);
    for (auto& v : x) v = u(r);
    lab[2] = 1;
    for (auto _ : st) {
        if constexpr (frozen) f.infer(x.data(), lab.data(), out.data(), fws);
        else g.infer(x.data(), lab.data(), out.data(), ws);
        benchmark::DoNotOptimize(out.data());
    }
    st.counters["GFLOP/s"] =
        benchmark::Counter(2.0 * generator<float, Config>::forward_macs(), benchmark::Counter::kIsIterationInvariantRate,
                           benchmark::Counter::kIs1000);
}

/// G inference of hand-micro on the microcontroller path (micro::generator: plain loops, no heap), batch 1,
/// one thread, on this machine: the x86 time of the Embedded targets table.
void bm_infer_micro(benchmark::State& st)
{
    // hand-micro's weights filled at run time (what `handemo export --header` makes constexpr), as the micro tests do
    using micro_model = test::runtime_model<hand_micro, true>;
    generator<float, with_batch<hand_micro, 1>> g;
    test::seed_generator(g, 1);
    micro_model::set_weights(test::flat_parameters(g));
    using mg = micro::generator<micro_model>;
    static mg::workspace ws;
    std::vector<float> x(3 * hand_micro::keyframes * hand_micro::joints), out(x.size());
    std::mt19937 r(2);
    std::uniform_real_distribution<float> u(-1, 1);
    for (auto& v : x) v = u(r);
    for (auto _ : st) {
        mg::infer(x.data(), 2, out.data(), ws);
        benchmark::DoNotOptimize(out.data());
    }
    st.counters["GFLOP/s"] = benchmark::Counter(2.0 * micro_model::layout::macs(), benchmark::Counter::kIsIterationInvariantRate,
                                                benchmark::Counter::kIs1000);
}

template <class Base>
void bm_train(benchmark::State& st)
{
    using cfg = with_batch<Base, 16>;
    constexpr std::size_t N = 16, C = Base::domains, H = dims<cfg>::H, W = dims<cfg>::W;
    using img = shape<N, 3, H, W>;
    generator<float, cfg> g;
    discriminator<float, cfg> d;
    rng gen(1);
    init_pytorch_default(g, gen);
    init_pytorch_default(d, gen);
    adam_options opt;
    opt.beta1 = 0.5;
    opt.beta2 = 0.999;
    adam<float> og(g, opt), od(d, opt);
    // threads = the benchmark's argument (1 and 2: the parallel efficiency of issue 13), 0 = all cores
    const unsigned threads = st.range(0) > 0 ? unsigned(st.range(0)) : std::max(1u, std::thread::hardware_concurrency());
    thread_pool pool(threads);
    tape<float> t(std::size_t{1} << 22, &pool);
    std::mt19937 r(3);
    std::uniform_real_distribution<float> u(-1, 1), a01(0, 1);
    std::vector<float> x(img::size), xh(img::size), org(N * C, 0.f), trg(N * C, 0.f);
    std::array<int, N> lab{}, tl{};
    for (auto& v : x) v = u(r);
    for (std::size_t n = 0; n < N; ++n) {
        lab[n] = int(r() % C);
        tl[n] = int(r() % C);
        org[n * C + lab[n]] = 1;
        trg[n * C + tl[n]] = 1;
    }
    auto step = [&]() {
        // D step: real, fake (G without grads), gradient penalty at x_hat = a x + (1 - a) fake
        t.reset();
        d.zero_grad();
        g.set_requires_grad(false);
        d.set_requires_grad(true);
        auto xv = t.input<img>(x.data());
        auto real = d.forward(t, xv);
        auto fake = g.forward(t, xv, t.input<shape<N, C>>(trg.data()));
        auto fk = d.forward(t, fake);
        const std::size_t per = img::size / N;
        for (std::size_t n = 0; n < N; ++n) {
            const float a = a01(r);
            for (std::size_t i = 0; i < per; ++i) xh[n * per + i] = a * x[n * per + i] + (1 - a) * fake.data()[n * per + i];
        }
        auto xhv = t.input<img>(xh.data(), true);
        auto oh = d.forward(t, xhv);
        auto gp = mean(square(l2_norm_per_sample(t.grad(sum(oh.src), xhv)) - 1.0f));
        auto ld = -mean(real.src) + mean(fk.src) + cross_entropy(real.cls, std::span<const int, N>(lab)) + 10.0f * gp;
        t.backward(ld);
        od.step(d, 1e-4);
        // G step: adversarial + classification + 10 x L1 reconstruction
        t.reset();
        g.zero_grad();
        g.set_requires_grad(true);
        d.set_requires_grad(false);
        auto x2 = t.input<img>(x.data());
        auto f2 = g.forward(t, x2, t.input<shape<N, C>>(trg.data()));
        auto o2 = d.forward(t, f2);
        auto rec = g.forward(t, f2, t.input<shape<N, C>>(org.data()));
        auto lg = -mean(o2.src) + 10.0f * autodiff::l1_loss(x2, rec) + cross_entropy(o2.cls, std::span<const int, N>(tl));
        t.backward(lg);
        og.step(g, 1e-4);
        return lg.item();
    };
    // two steps before timing, as reference_stargan.py does: the first ones touch the tape's arena and the
    // pool's threads for the first time (page faults), which no later step repeats
    step();
    step();
    for (auto _ : st) benchmark::DoNotOptimize(step());
    const double macs = 7 * generator<float, cfg>::forward_macs() + 14 * discriminator<float, cfg>::forward_macs();
    st.counters["GFLOP/s"] = benchmark::Counter(2.0 * macs, benchmark::Counter::kIsIterationInvariantRate,
                                                benchmark::Counter::kIs1000);
    st.counters["threads"] = double(pool.size());
}

}  // namespace

BENCHMARK(bm_infer<hand_paper, true>)->Name("stargan_infer/paper(64,6)/b1")->Unit(benchmark::kMicrosecond)->MinTime(1.0);
BENCHMARK(bm_infer<hand_embedded, true>)->Name("stargan_infer/embedded(32,3)/b1")->Unit(benchmark::kMicrosecond)->MinTime(1.0);
BENCHMARK(bm_infer<hand_micro, true>)->Name("stargan_infer/hand-micro(8,3)/b1")->Unit(benchmark::kMicrosecond)->MinTime(1.0);
BENCHMARK(bm_infer<hand_paper, false>)->Name("stargan_infer_unpacked/paper(64,6)/b1")->Unit(benchmark::kMicrosecond)->MinTime(1.0);
BENCHMARK(bm_infer<hand_embedded, false>)->Name("stargan_infer_unpacked/embedded(32,3)/b1")->Unit(benchmark::kMicrosecond)->MinTime(1.0);
BENCHMARK(bm_infer_micro)->Name("micro_infer/hand-micro(8,3)/b1")->Unit(benchmark::kMicrosecond)->MinTime(1.0);
BENCHMARK(bm_train<hand_paper>)->Name("stargan_train/paper(64,6)/b16")->ArgName("threads")->Arg(2)->Arg(1)
    ->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(3.0);
BENCHMARK(bm_train<hand_embedded>)->Name("stargan_train/embedded(32,3)/b16")->ArgName("threads")->Arg(2)->Arg(1)
    ->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(2.0);

BENCHMARK_MAIN();
