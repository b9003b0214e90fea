// Google Benchmark of handemo's convolution kernels on every conv shape of the StarGAN of Chan et al.
// 2020 (reference_stargan.py: 12x24 image, 5 domains, cd = 64 "paper" and cd = 32 "embedded"), forward at
// batch 1 (inference) and forward / backward-data / backward-weight at batch 16 (training), each with a
// GFLOP/s counter (2 x multiply-adds / s), plus the generator's whole conv stack at batch 1.
#include <benchmark/benchmark.h>

#include <chrono>
#include <thread>
#include <vector>

#include <xsimd/xsimd.hpp>

#include <handemo/kernels/conv.hpp>
#include <handemo/kernels/packed.hpp>

#include <cstdio>
#include <random>
#include <string>
#include <vector>

namespace hk = handemo::kernels;

namespace {

struct layer {
    std::string name;
    hk::conv_geometry g;  // batch filled in per benchmark
    bool transposed;      // ConvTranspose2d whose forward is g's backward-data
};

std::vector<layer> stargan_layers(int cd)
{
    return {
        {"G.conv7_in", {1, 8, 12, 24, cd, 7, 7, 1, 3}, false},
        {"G.down1", {1, cd, 12, 24, 2 * cd, 4, 4, 2, 1}, false},
        {"G.down2", {1, 2 * cd, 6, 12, 4 * cd, 4, 4, 2, 1}, false},
        {"G.res3x3", {1, 4 * cd, 3, 6, 4 * cd, 3, 3, 1, 1}, false},
        {"G.up1(convT)", {1, 2 * cd, 6, 12, 4 * cd, 4, 4, 2, 1}, true},
        {"G.up2(convT)", {1, cd, 12, 24, 2 * cd, 4, 4, 2, 1}, true},
        {"G.conv7_out", {1, cd, 12, 24, 3, 7, 7, 1, 3}, false},
        {"D.conv1", {1, 3, 12, 24, cd, 4, 4, 2, 1}, false},
        {"D.conv2", {1, cd, 6, 12, 2 * cd, 4, 4, 2, 1}, false},
        {"D.conv3", {1, 2 * cd, 3, 6, 4 * cd, 4, 4, 2, 1}, false},
        {"D.src3x3", {1, 4 * cd, 1, 3, 1, 3, 3, 1, 1}, false},
        {"D.cls", {1, 4 * cd, 1, 3, 5, 1, 3, 1, 0}, false},
    };
}

struct buffers {
    std::vector<float> x, w, b, y, scratch;
    explicit buffers(const hk::conv_geometry& g)
        : x(g.x_size()), w(g.w_size()), b(std::size_t(g.out_channels)), y(g.y_size()),
          scratch(hk::conv2d_scratch_size<float>(g))
    {
        std::mt19937 rng(1);
        std::uniform_real_distribution<float> d(-1.f, 1.f);
        for (auto* v : {&x, &w, &b, &y}) for (auto& e : *v) e = d(rng);
    }
};

enum class pass { forward, backward_data, backward_weight };

void run_layer(benchmark::State& state, hk::conv_geometry g, bool transposed, pass ps)
{
    buffers buf(g);
    std::vector<float> gw(g.w_size(), 0.f);
    for (auto _ : state) {
        // for a transposed layer, "forward" is g's backward-data (into x), "backward_data" is g's forward
        if (!transposed) {
            switch (ps) {
            case pass::forward: hk::conv2d_forward(g, buf.x.data(), buf.w.data(), buf.b.data(), buf.y.data(), buf.scratch.data()); break;
            case pass::backward_data: hk::conv2d_backward_data(g, buf.y.data(), buf.w.data(), buf.x.data(), buf.scratch.data()); break;
            case pass::backward_weight: hk::conv2d_backward_weight(g, buf.x.data(), buf.y.data(), gw.data(), buf.scratch.data()); break;
            }
        } else {
            switch (ps) {
            case pass::forward: hk::conv_transpose2d_forward(g, buf.y.data(), buf.w.data(), buf.x.data(), buf.scratch.data()); break;
            case pass::backward_data: hk::conv_transpose2d_backward_data(g, buf.x.data(), buf.w.data(), buf.y.data(), buf.scratch.data()); break;
            case pass::backward_weight: hk::conv_transpose2d_backward_weight(g, buf.y.data(), buf.x.data(), gw.data(), buf.scratch.data()); break;
            }
        }
        benchmark::ClobberMemory();
    }
    state.counters["GFLOPS"] = benchmark::Counter(2 * g.macs() * 1e-9, benchmark::Counter::kIsIterationInvariantRate);
}

/// The generator's conv stack at batch 1 (rep residual blocks of two 3x3 convs), in network order.
std::vector<layer> generator_sequence(int cd, int rep)
{
    const auto all = stargan_layers(cd);
    std::vector<layer> seq = {all[0], all[1], all[2]};
    for (int r = 0; r < 2 * rep; ++r) seq.push_back(all[3]);
    seq.insert(seq.end(), {all[4], all[5], all[6]});
    return seq;
}

void run_generator(benchmark::State& state, int cd, int rep)
{
    const std::vector<layer> seq = generator_sequence(cd, rep);
    std::vector<buffers> bufs;
    double macs = 0;
    for (const auto& l : seq) {
        bufs.emplace_back(l.g);
        macs += l.g.macs();
    }
    for (auto _ : state) {
        for (std::size_t i = 0; i < seq.size(); ++i) {
            auto& b = bufs[i];
            if (seq[i].transposed)
                hk::conv_transpose2d_forward(seq[i].g, b.y.data(), b.w.data(), b.x.data(), b.scratch.data());
            else
                hk::conv2d_forward<float>(seq[i].g, b.x.data(), b.w.data(), nullptr, b.y.data(), b.scratch.data());
        }
        benchmark::ClobberMemory();
    }
    state.counters["GFLOPS"] = benchmark::Counter(2 * macs * 1e-9, benchmark::Counter::kIsIterationInvariantRate);
    state.counters["MMAC"] = macs * 1e-6;
}

hk::packed_conv<float> pack(const hk::conv_geometry& g, const float* w, bool transposed)
{
    return transposed ? hk::packed_conv<float>::conv_transpose2d(g, w) : hk::packed_conv<float>::conv2d(g, w);
}

/// One packed forward pass on a layer's buffers: a transposed layer reads y and writes x (g's sides).
void packed_forward(const hk::packed_conv<float>& p, bool transposed, buffers& b, float* scratch)
{
    if (transposed) p.forward(b.y.data(), nullptr, b.x.data(), scratch);
    else p.forward(b.x.data(), nullptr, b.y.data(), scratch);
}

/// The same layer with its weights packed once (kernels/packed.hpp, the path of stargan::frozen_generator).
void run_packed_layer(benchmark::State& state, hk::conv_geometry g, bool transposed)
{
    buffers buf(g);
    const auto p = pack(g, buf.w.data(), transposed);
    std::vector<float> scratch(p.scratch_size());
    for (auto _ : state) {
        packed_forward(p, transposed, buf, scratch.data());
        benchmark::ClobberMemory();
    }
    // the multiply-adds it performs: without the kernel rows over the zero padding (packed_conv::macs_per_image())
    state.counters["GFLOPS"] = benchmark::Counter(2 * p.macs_per_image() * g.batch * 1e-9, benchmark::Counter::kIsIterationInvariantRate);
    state.counters["MMAC_counted"] = g.macs() * 1e-6;
    state.SetLabel(p.weight_stationary() ? "weight-stationary" : "fallback");
}

/// Prototype measurement: pack the weights on every call (as a training step would) and run the batch.
void run_repacked_layer(benchmark::State& state, hk::conv_geometry g, bool transposed)
{
    buffers buf(g);
    std::vector<float> scratch;
    for (auto _ : state) {
        const auto p = pack(g, buf.w.data(), transposed);
        if (scratch.size() < p.scratch_size()) scratch.resize(p.scratch_size());
        packed_forward(p, transposed, buf, scratch.data());
        benchmark::ClobberMemory();
    }
    state.counters["GFLOPS"] = benchmark::Counter(2 * g.macs() * 1e-9, benchmark::Counter::kIsIterationInvariantRate);
}

/// The generator's conv stack at batch 1 with packed weights (each layer its own weights, as in the model).
void run_packed_generator(benchmark::State& state, int cd, int rep)
{
    const std::vector<layer> seq = generator_sequence(cd, rep);
    std::vector<buffers> bufs;
    std::vector<hk::packed_conv<float>> packed;
    std::size_t ns = 0;
    double macs = 0, counted = 0;
    for (const auto& l : seq) {
        bufs.emplace_back(l.g);
        packed.push_back(pack(l.g, bufs.back().w.data(), l.transposed));
        ns = std::max(ns, packed.back().scratch_size());
        macs += packed.back().macs_per_image() * l.g.batch;  // performed: the kernel rows over the padding skipped
        counted += l.g.macs();
    }
    std::vector<float> scratch(ns);
    for (auto _ : state) {
        for (std::size_t i = 0; i < seq.size(); ++i) packed_forward(packed[i], seq[i].transposed, bufs[i], scratch.data());
        benchmark::ClobberMemory();
    }
    state.counters["GFLOPS"] = benchmark::Counter(2 * macs * 1e-9, benchmark::Counter::kIsIterationInvariantRate);
    state.counters["MMAC"] = macs * 1e-6;
    state.counters["MMAC_counted"] = counted * 1e-6;
}

/// One run of the peak loop: 12 x n FMAs on B::size lanes; returns the sum so nothing is optimised away.
float peak_loop(long n)
{
    using B = xsimd::batch<float>;
    using R = typename B::register_type;
    // named locals, not an array: an array whose address escapes is stored every iteration (measured:
    // 71 instead of 226 GFLOP/s with AVX-512 on Zen 5)
    R a0 = B(1.000f), a1 = B(1.001f), a2 = B(1.002f), a3 = B(1.003f), a4 = B(1.004f), a5 = B(1.005f);
    R a6 = B(1.006f), a7 = B(1.007f), a8 = B(1.008f), a9 = B(1.009f), a10 = B(1.010f), a11 = B(1.011f);
    const B b(0.9999f), c(1e-6f);
    for (long k = 0; k < n; k++) {
        for (R* r : {&a0, &a1, &a2, &a3, &a4, &a5, &a6, &a7, &a8, &a9, &a10, &a11})
            *r = static_cast<R>(xsimd::fma(B(*r), b, c));
#if defined(__x86_64__)
        __asm__ volatile("" : "+v"(a0), "+v"(a1), "+v"(a2), "+v"(a3), "+v"(a4), "+v"(a5), "+v"(a6), "+v"(a7),
                         "+v"(a8), "+v"(a9), "+v"(a10), "+v"(a11));
#endif
    }
    B sum = B(a0) + B(a1) + B(a2) + B(a3) + B(a4) + B(a5) + B(a6) + B(a7) + B(a8) + B(a9) + B(a10) + B(a11);
    return xsimd::hadd(sum);
}

/// The FP32 FMA peak of the instruction set the kernels were compiled for (xsimd::default_arch: avx512bw
/// with -march=native on an AVX-512 machine, avx2 on an AVX2 one), measured inside this program with the
/// loop of bench/peak_fma.cpp (12 independent FMA chains kept in registers), so that fraction of
/// peak compares numbers taken under the same machine load and for the same vector width.
void peak_fma(benchmark::State& state)
{
    const long n = 1000000;
    for (auto _ : state) benchmark::DoNotOptimize(peak_loop(n));
    state.counters["GFLOPS"] =
        benchmark::Counter(double(n) * 12 * xsimd::batch<float>::size * 2 * 1e-9, benchmark::Counter::kIsIterationInvariantRate);
}

/// The same loop on `state.range(0)` threads at once (each its own copy), wall time: the FMA throughput the
/// machine gives that many threads together. On a VM whose vCPUs are SMT siblings of one physical core it is
/// about the 1-thread peak, not twice it, which bounds what any compute-bound 2-thread speed-up can be.
void peak_fma_threads(benchmark::State& state)
{
    const int T = int(state.range(0));
    const long n = 1000000;
    for (auto _ : state) {
        const auto t0 = std::chrono::steady_clock::now();
        std::vector<std::thread> th;
        std::vector<float> out(std::size_t(T), 0.f);
        for (int t = 1; t < T; ++t) th.emplace_back([&, t] { out[std::size_t(t)] = peak_loop(n); });
        out[0] = peak_loop(n);
        for (auto& x : th) x.join();
        benchmark::DoNotOptimize(out.data());
        state.SetIterationTime(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    }
    state.counters["GFLOPS"] = benchmark::Counter(double(n) * 12 * xsimd::batch<float>::size * 2 * T * 1e-9,
                                                  benchmark::Counter::kIsIterationInvariantRate);
}

}  // namespace

int main(int argc, char** argv)
{
    // `bench_conv --simd_arch`: the instruction set the kernels were compiled for and its float lanes
    // (compare.sh picks the matching FMA peak with it)
    if (argc == 2 && std::string(argv[1]) == "--simd_arch") {
        std::printf("%s %d\n", xsimd::default_arch::name(), int(xsimd::batch<float>::size));
        return 0;
    }
    // the ISA the kernels run on, in the JSON context (compare.sh prints it and picks the matching peak)
    benchmark::AddCustomContext("simd_arch", xsimd::default_arch::name());
    benchmark::AddCustomContext("simd_float_lanes", std::to_string(xsimd::batch<float>::size));
    benchmark::RegisterBenchmark((std::string("peak_fma/") + xsimd::default_arch::name()).c_str(), peak_fma)->Unit(benchmark::kMillisecond)->Repetitions(3)
        ->ReportAggregatesOnly(false);
    benchmark::RegisterBenchmark((std::string("peak_fma_threads/") + xsimd::default_arch::name()).c_str(), peak_fma_threads)
        ->Arg(2)->ArgName("threads")->UseManualTime()->Unit(benchmark::kMillisecond)->Repetitions(3)->ReportAggregatesOnly(false);
    benchmark::RegisterBenchmark("generator_convs/paper(64,6)/b1", run_generator, 64, 6)->Unit(benchmark::kMicrosecond);
    benchmark::RegisterBenchmark("generator_convs/embedded(32,3)/b1", run_generator, 32, 3)->Unit(benchmark::kMicrosecond);
    benchmark::RegisterBenchmark("packed_generator_convs/paper(64,6)/b1", run_packed_generator, 64, 6)->Unit(benchmark::kMicrosecond);
    benchmark::RegisterBenchmark("packed_generator_convs/embedded(32,3)/b1", run_packed_generator, 32, 3)->Unit(benchmark::kMicrosecond);
    for (int cd : {64, 32})
        for (const auto& l : stargan_layers(cd))
            if (l.name[0] == 'G')
                benchmark::RegisterBenchmark(("packed/cd" + std::to_string(cd) + "/" + l.name + "/fwd/b1").c_str(), run_packed_layer,
                                             l.g, l.transposed)->Unit(benchmark::kMicrosecond);
    for (int cd : {64, 32})
        for (const auto& l : stargan_layers(cd)) {
            hk::conv_geometry g8 = l.g;
            g8.batch = 8;
            benchmark::RegisterBenchmark(("repacked/cd" + std::to_string(cd) + "/" + l.name + "/fwd/b8").c_str(), run_repacked_layer,
                                         g8, l.transposed)->Unit(benchmark::kMicrosecond);
            benchmark::RegisterBenchmark(("repacked/cd" + std::to_string(cd) + "/" + l.name + "/bwd_data/b8").c_str(), run_repacked_layer,
                                         g8, !l.transposed)->Unit(benchmark::kMicrosecond);
        }
    for (int cd : {64, 32})
        for (const auto& l : stargan_layers(cd)) {
            const std::string base = "cd" + std::to_string(cd) + "/" + l.name;
            hk::conv_geometry g = l.g;
            benchmark::RegisterBenchmark((base + "/fwd/b1").c_str(), run_layer, g, l.transposed, pass::forward)
                ->Unit(benchmark::kMicrosecond);
            g.batch = 16;
            benchmark::RegisterBenchmark((base + "/fwd/b16").c_str(), run_layer, g, l.transposed, pass::forward)
                ->Unit(benchmark::kMicrosecond);
            benchmark::RegisterBenchmark((base + "/bwd_data/b16").c_str(), run_layer, g, l.transposed, pass::backward_data)
                ->Unit(benchmark::kMicrosecond);
            benchmark::RegisterBenchmark((base + "/bwd_weight/b16").c_str(), run_layer, g, l.transposed, pass::backward_weight)
                ->Unit(benchmark::kMicrosecond);
        }
    benchmark::Initialize(&argc, argv);
    if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
}
