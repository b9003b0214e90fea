// Whole-StarGAN benchmarks (hand paper Sec. 3.3) side by side with reference_stargan.py and ONNX Runtime
// (onnxruntime_bench.js): batch-1 generator inference, single thread, tape-free (frozen_generator and
// generator::infer), and batch-32 inference (frozen_generator::infer_batch, clips/s); the whole transfer of 32
// clips with the shipped model, clip by clip and in batches (emotion_model::transfer_batch, clips/s); one training step of the
// library's trainer (D step with WGAN-GP + G step, batch 16, Adam on both), data-parallel on 2 threads and on 1
// (threads:N), and two independent half-batch steps at once on two threads (stargan_train_pair: the bound of the
// 2-thread step with the memory system's contention). Every benchmark but the pair has a FLOP counter (the FLOPs of one
// call, stargan/flops.hpp: inference 2 x the multiply-adds G performs per image (frozen_generator's without the first
// layer's label channels, which it adds as precomputed maps); the training step pass by pass, the
// gradient penalty's double backward included) and GFLOP/s = FLOP / time. The rows stargan_infer_winograd/ run the
// frozen generator with the residual convolutions by Winograd's F(3x2, 3x3) (kernels::conv_algorithm::winograd):
// their FLOP and GFLOP/s count the same direct-convolution FLOPs as the other rows (what G computes, however it is
// computed), and performed_FLOP what the multiplications of their GEMMs and of the other layers are. Every frozen
// row's performed_FLOP leaves out the multiply-adds the packed kernels skip (kernel rows over the zero padding).
// HANDEMO_BENCH_QUICK=1 in the environment runs every benchmark for 0.01 s instead of its minimum time: a check
// that the program runs end to end, not a measurement.
#include <handemo/motion/synth.hpp>
#include <handemo/nn/adam.hpp>
#include <handemo/nn/init.hpp>
#include <handemo/stargan/flops.hpp>
#include <handemo/stargan/model.hpp>
#include <handemo/stargan/train.hpp>
#include <handemo/stargan/transfer.hpp>

#include <benchmark/benchmark.h>

#include "../tests/micro/helpers.hpp"  // runtime_model, seed_generator, flat_parameters

#include <cstdlib>
#include <memory>
#include <random>
#include <thread>

using namespace handemo;
using namespace handemo::stargan;
using autodiff::tape;

namespace {

/// A benchmark's minimum time: `seconds`, or 0.01 s with HANDEMO_BENCH_QUICK set (a run-through, not a measurement).
double min_time(double seconds)
{
    const char* q = std::getenv("HANDEMO_BENCH_QUICK");
    return q && *q && *q != '0' ? 0.01 : seconds;
}

/// The FLOP counter (one call's FLOPs) and GFLOP/s of a benchmark.
void flop_counters(benchmark::State& st, double flop)
{
    st.counters["FLOP"] = flop;
    st.counters["GFLOP/s"] = benchmark::Counter(flop, benchmark::Counter::kIsIterationInvariantRate, benchmark::Counter::kIs1000);
}

/// The counter performed_FLOP of a frozen generator's call on `images` images: frozen_generator_flops() with each
/// convolution's multiply-adds replaced by those it performs: without the kernel rows that read only the zero
/// padding (kernels::packed_conv::macs() of the call: on a batch the last layer's groups of images skip them too),
/// and the residual convolutions' by those of their Winograd GEMMs (when it has them).
template <class Config, class Frozen>
void performed_counter(benchmark::State& st, const Frozen& f, std::size_t images)
{
    const double n = double(images);
    double flop = frozen_generator_flops<Config>() * n;
    for (const auto& c : f.convolutions()) flop += 2 * (c.macs(images) - c.geometry().macs() / c.geometry().batch * n);
    for (const auto& w : f.winograd_convolutions()) flop += 2 * (w.macs_per_image() - w.geometry().macs() / w.geometry().batch) * n;
    st.counters["performed_FLOP"] = flop;
}

/// frozen: frozen_generator (weights packed once, the path of transfer and the CLI); else generator::infer.
/// storage: the frozen generator's weight storage (kernels::weight_storage::f16: binary16 panels). algorithm: its
/// residual convolutions' (kernels::conv_algorithm::winograd: Winograd's).
template <class Config, bool frozen, kernels::weight_storage storage = kernels::weight_storage::native,
          kernels::conv_algorithm algorithm = kernels::conv_algorithm::direct>
void bm_infer(benchmark::State& st)
{
    generator<float, Config> g;
    rng gen(1);
    init_pytorch_default(g, gen);
    const auto f = g.freeze(storage, algorithm);
    st.counters["weight_MB"] = double(f.weight_bytes()) / 1e6;
    performed_counter<Config>(st, f, 1);
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
    flop_counters(st, frozen ? frozen_generator_flops<Config>() : generator_flops<Config>());
}

/// G inference of a batch of B clips through one packed batch-1 generator (frozen_generator::infer_batch: each
/// layer over the whole batch), one thread: the batched path of a folder transfer; clips/s as items per second.
/// storage, algorithm: as bm_infer's.
template <class Config, std::size_t B, kernels::weight_storage storage = kernels::weight_storage::native,
          kernels::conv_algorithm algorithm = kernels::conv_algorithm::direct>
void bm_infer_batch(benchmark::State& st)
{
    static_assert(Config::batch == 1, "bm_infer_batch: a batch-1 configuration (the generator a transfer loads)");
    using cfg = Config;
    generator<float, cfg> g;
    rng gen(1);
    init_pytorch_default(g, gen);
    const auto f = g.freeze(storage, algorithm);
    st.counters["weight_MB"] = double(f.weight_bytes()) / 1e6;
    performed_counter<cfg>(st, f, B);
    typename frozen_generator<float, cfg>::workspace ws(f, B);
    constexpr std::size_t H = dims<cfg>::H, W = dims<cfg>::W, C = Config::domains;
    std::vector<float> x(B * 3 * H * W), lab(B * C, 0.f), out(x.size());
    std::mt19937 r(2);
    std::uniform_real_distribution<float> u(-1, 1);
    for (auto& v : x) v = u(r);
    for (std::size_t n = 0; n < B; ++n) lab[n * C + n % C] = 1;
    for (auto _ : st) {
        f.infer_batch(x.data(), lab.data(), out.data(), B, ws);
        benchmark::DoNotOptimize(out.data());
    }
    st.SetItemsProcessed(std::int64_t(st.iterations()) * std::int64_t(B));
    st.counters["batch"] = double(B);
    flop_counters(st, double(B) * frozen_generator_flops<cfg>());
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
    flop_counters(st, 2.0 * micro_model::layout::macs());
}

/// The shipped hand-embedded model transferring 32 synthesized clips (pointing and gripping at 30 fps) to
/// "sad", one thread: clip by clip (transfer() with a workspace, as each thread of `handemo transfer --in DIR` does)
/// or, with batch > 0, through transfer_batch() in batches of `batch` clips; algorithm: how G computes its residual
/// convolutions (the CLI's --conv). clips/s as items per second.
void bm_transfer(benchmark::State& st, std::size_t batch, kernels::conv_algorithm algorithm, bool shipped_gates)
{
    const auto ck = read_checkpoint(std::filesystem::path(HANDEMO_SOURCE_DIR) / "data" / "models" / "hand-embedded" / "checkpoint.safetensors");
    stargan::detail::emotion_model_impl<hand_embedded> model(ck.first, ck.second, kernels::weight_storage::native, algorithm);
    // the shipped gates weigh G's change 0 for sad, so its transfer skips G; the other rows time G, with a gate
    // that keeps G's whole change (the same work but for the gate's few additions)
    const std::size_t D = ck.second.domains.size();
    if (!shipped_gates) model.set_gate(std::vector<double>(D, 1.0), std::vector<double>(D, 1.0), std::vector<double>(D, 1.0));
    std::vector<clip> clips;
    for (int i = 0; i < 32; ++i)
        clips.push_back(synthesize(i % 2 ? hand_motion::gripping : hand_motion::pointing, emotion::neutral, i / 2, 7, 30.0));
    std::vector<transfer_result> out(clips.size());
    auto ws = model.make_workspace();
    auto bws = model.make_batch_workspace(std::max<std::size_t>(batch, 1));
    for (auto _ : st) {
        if (batch) model.transfer_batch(clips, "sad", {}, bws, out);
        else
            for (std::size_t i = 0; i < clips.size(); ++i) model.transfer(clips[i], "sad", {}, ws, out[i]);
        benchmark::DoNotOptimize(out.data());
    }
    st.SetItemsProcessed(std::int64_t(st.iterations()) * std::int64_t(clips.size()));
    st.counters["batch"] = double(batch);
    if (!shipped_gates) flop_counters(st, double(clips.size()) * frozen_generator_flops<hand_embedded>());
}

/// A trainer of batch N (the library's own, data-parallel over `threads`) on 64 random images with random
/// labels, with the paper's options (lambda_cls 1, lambda_rec 10, lambda_gp 10, Adam 0.5, 0.999, n_critic 1),
/// as reference_stargan.py's step, after two warm-up steps (the first ones touch the tapes' arenas and the
/// pool's threads for the first time: page faults that no later step repeats).
template <class Base, std::size_t N>
std::unique_ptr<trainer<Base, N>> warm_trainer(unsigned threads, bool handemo_preset = false)
{
    using tr_t = trainer<Base, N>;
    constexpr std::size_t C = Base::domains, H = tr_t::H, W = tr_t::W, count = 64;
    prepared_data data;
    data.H = H, data.W = W, data.K = Base::keyframes, data.J = Base::joints, data.domains = C;
    std::mt19937 r(3);
    std::uniform_real_distribution<float> u(-1, 1);
    data.images.resize(count * 3 * H * W);
    for (auto& v : data.images) v = u(r);
    for (std::size_t m = 0; m < count; ++m) {
        data.labels.push_back(int(m % C));
        data.contents.push_back("c" + std::to_string(m / C));
        data.sources.push_back("random" + std::to_string(m));
    }
    data.tempo.assign(C, 1.0);
    data.amplitude.assign(C, 1.0);
    // the paper's options, or the handemo preset's (residual G, identity and change-size terms, EMA, augmentation);
    // the random images have no paired takes, so the preset's paired term is left out (it is element-wise)
    train_options opt = handemo_preset ? handemo_options() : train_options{};
    opt.lambda_pair = 0;
    opt.n_critic = 1;
    opt.iters = 1 << 30;  // the learning rate stays constant
    opt.progress_out = nullptr;
    opt.threads = threads;
    std::vector<std::string> names;
    for (std::size_t c = 0; c < C; ++c) names.push_back("e" + std::to_string(c));
    auto tr = std::make_unique<tr_t>(make_info<Base>("bench", names, "e0"), std::move(data), opt);
    tr->train_step();
    tr->train_step();
    return tr;
}

/// The counter performed_FLOP of a training step: 2 x the multiply-adds its convolutions perform in one more step
/// (kernels::performed_macs_count: the weight-stationary kernels skip the products with the zero padding above and
/// below the image, which the FLOP counter, counted from the layer shapes, includes).
template <class Trainer>
void performed_step_counter(benchmark::State& st, Trainer& tr)
{
    const kernels::performed_macs_count count;
    tr.train_step();
    st.counters["performed_FLOP"] = 2.0 * double(count.macs());
}

/// One trainer::train_step() (D step with WGAN-GP and a G step, batch 16, Adam on both), data-parallel over
/// the benchmark's argument of threads (1 and 2: the 2-thread / 1-thread ratio; 0 = all cores).
template <class Base>
void bm_train(benchmark::State& st)
{
    const unsigned threads = st.range(0) > 0 ? unsigned(st.range(0)) : std::max(1u, std::thread::hardware_concurrency());
    auto tr = warm_trainer<Base, 16>(threads);
    performed_step_counter(st, *tr);
    for (auto _ : st) tr->train_step();
    benchmark::DoNotOptimize(tr->log());
    flop_counters(st, train_step_flops<with_batch<Base, 16>>().total());
    st.counters["threads"] = double(threads);
}

/// One iteration of the `handemo` preset (what `handemo train` and `handemo eval` run), batch 16: the step above
/// plus the identity term's fourth pass of G (forward and backward), the change-size term, the EMA update and the
/// augmentation of the batch (not the paired term, which needs paired takes: element-wise, a small share). Its time, not bm_train's, is what an evaluation's training time is made of. No FLOP
/// counter (stargan/flops.hpp counts bm_train's step); performed_FLOP counts what its convolutions perform, the fourth pass included.
template <class Base>
void bm_train_preset(benchmark::State& st)
{
    auto tr = warm_trainer<Base, 16>(unsigned(st.range(0)), true);
    performed_step_counter(st, *tr);
    for (auto _ : st) tr->train_step();
    benchmark::DoNotOptimize(tr->log());
    st.counters["threads"] = double(st.range(0));
}

/// The machine's bound for the 2-thread step, memory system included: two independent trainers of batch 8,
/// one thread each, stepping at the same time on the benchmark's two threads (no gradient reduction, no
/// shared Adam, no synchronisation but the benchmark's own per-iteration start). A data-parallel 2-thread
/// step of batch 16 does the same work plus its reduction, so it cannot be faster than this on the machine.
template <class Base>
void bm_train_pair(benchmark::State& st)
{
    auto tr = warm_trainer<Base, 8>(1);
    for (auto _ : st) tr->train_step();
    benchmark::DoNotOptimize(tr->log());
}

}  // namespace

BENCHMARK(bm_infer<hand_paper, true>)->Name("stargan_infer/paper(64,6)/b1")->Unit(benchmark::kMicrosecond)->MinTime(min_time(1.0));
BENCHMARK(bm_infer<hand_embedded, true>)->Name("stargan_infer/embedded(32,3)/b1")->Unit(benchmark::kMicrosecond)->MinTime(min_time(1.0));
BENCHMARK(bm_infer_batch<hand_paper, 32>)->Name("stargan_infer/paper(64,6)/b32")->Unit(benchmark::kMicrosecond)->MinTime(min_time(2.0));
BENCHMARK(bm_infer_batch<hand_embedded, 32>)->Name("stargan_infer/embedded(32,3)/b32")->Unit(benchmark::kMicrosecond)->MinTime(min_time(2.0));
BENCHMARK_CAPTURE(bm_transfer, one_at_a_time, 0, kernels::conv_algorithm::direct, false)->Name("stargan_transfer/embedded(32,3)/32clips/one_at_a_time")
    ->Unit(benchmark::kMillisecond)->MinTime(min_time(2.0));
BENCHMARK_CAPTURE(bm_transfer, batch32, 32, kernels::conv_algorithm::direct, false)->Name("stargan_transfer/embedded(32,3)/32clips/batch32")
    ->Unit(benchmark::kMillisecond)->MinTime(min_time(2.0));
BENCHMARK_CAPTURE(bm_transfer, batch32_winograd, 32, kernels::conv_algorithm::winograd, false)
    ->Name("stargan_transfer/embedded(32,3)/32clips/batch32_winograd")->Unit(benchmark::kMillisecond)->MinTime(min_time(2.0));
BENCHMARK_CAPTURE(bm_transfer, shipped_gates, 32, kernels::conv_algorithm::direct, true)
    ->Name("stargan_transfer/embedded(32,3)/32clips/shipped_gates")->Unit(benchmark::kMillisecond)->MinTime(min_time(2.0));
BENCHMARK(bm_infer<hand_micro, true>)->Name("stargan_infer/hand-micro(8,3)/b1")->Unit(benchmark::kMicrosecond)->MinTime(min_time(1.0));
BENCHMARK(bm_infer<hand_paper, true, kernels::weight_storage::f16>)->Name("stargan_infer_f16/paper(64,6)/b1")->Unit(benchmark::kMicrosecond)->MinTime(min_time(1.0));
BENCHMARK(bm_infer<hand_embedded, true, kernels::weight_storage::f16>)->Name("stargan_infer_f16/embedded(32,3)/b1")->Unit(benchmark::kMicrosecond)->MinTime(min_time(1.0));
BENCHMARK(bm_infer_batch<hand_paper, 32, kernels::weight_storage::f16>)->Name("stargan_infer_f16/paper(64,6)/b32")->Unit(benchmark::kMicrosecond)->MinTime(min_time(2.0));
BENCHMARK(bm_infer_batch<hand_embedded, 32, kernels::weight_storage::f16>)->Name("stargan_infer_f16/embedded(32,3)/b32")->Unit(benchmark::kMicrosecond)->MinTime(min_time(2.0));
BENCHMARK(bm_infer<hand_paper, true, kernels::weight_storage::native, kernels::conv_algorithm::winograd>)->Name("stargan_infer_winograd/paper(64,6)/b1")->Unit(benchmark::kMicrosecond)->MinTime(min_time(1.0));
BENCHMARK(bm_infer<hand_embedded, true, kernels::weight_storage::native, kernels::conv_algorithm::winograd>)->Name("stargan_infer_winograd/embedded(32,3)/b1")->Unit(benchmark::kMicrosecond)->MinTime(min_time(1.0));
BENCHMARK(bm_infer_batch<hand_paper, 32, kernels::weight_storage::native, kernels::conv_algorithm::winograd>)->Name("stargan_infer_winograd/paper(64,6)/b32")->Unit(benchmark::kMicrosecond)->MinTime(min_time(2.0));
BENCHMARK(bm_infer_batch<hand_embedded, 32, kernels::weight_storage::native, kernels::conv_algorithm::winograd>)->Name("stargan_infer_winograd/embedded(32,3)/b32")->Unit(benchmark::kMicrosecond)->MinTime(min_time(2.0));
BENCHMARK(bm_infer<hand_paper, false>)->Name("stargan_infer_unpacked/paper(64,6)/b1")->Unit(benchmark::kMicrosecond)->MinTime(min_time(1.0));
BENCHMARK(bm_infer<hand_embedded, false>)->Name("stargan_infer_unpacked/embedded(32,3)/b1")->Unit(benchmark::kMicrosecond)->MinTime(min_time(1.0));
BENCHMARK(bm_infer_micro)->Name("micro_infer/hand-micro(8,3)/b1")->Unit(benchmark::kMicrosecond)->MinTime(min_time(1.0));
BENCHMARK(bm_train<hand_paper>)->Name("stargan_train/paper(64,6)/b16")->ArgName("threads")->Arg(2)->Arg(1)
    ->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(min_time(3.0));
BENCHMARK(bm_train<hand_embedded>)->Name("stargan_train/embedded(32,3)/b16")->ArgName("threads")->Arg(2)->Arg(1)
    ->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(min_time(2.0));
BENCHMARK(bm_train_preset<hand_embedded>)->Name("stargan_train_preset/embedded(32,3)/b16")->ArgName("threads")->Arg(1)
    ->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(min_time(2.0));
BENCHMARK(bm_train_preset<body_embedded>)->Name("stargan_train_preset/body-embedded(32,3)/b16")->ArgName("threads")->Arg(1)
    ->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(min_time(2.0));
BENCHMARK(bm_train_pair<hand_paper>)->Name("stargan_train_pair/paper(64,6)/2xb8")->Threads(2)
    ->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(min_time(3.0));
BENCHMARK(bm_train_pair<hand_embedded>)->Name("stargan_train_pair/embedded(32,3)/2xb8")->Threads(2)
    ->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(min_time(2.0));

BENCHMARK_MAIN();
