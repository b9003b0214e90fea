// This machine's single-core FP32 FMA peak for each instruction set the kernels may be compiled for: AVX-512
// (16 float lanes) and AVX2 with FMA (8 lanes). Each is timed on 12 independent accumulator chains kept in
// registers (more chains than FMA latency x FMA ports on the CPUs handemo runs on, so the FMA units never wait
// for a result), 100 M FMAs a repetition, best of 5 repetitions in thread CPU time (robust when other
// processes share the core). It is the roofline for handemo's kernels; bench/compare.sh reads its lines.
// No handemo code in it. Each measuring function sets its own instruction set (a target attribute), so the
// program builds with any -march and reports an instruction set the CPU lacks as n/a.
// Output, one line per instruction set:
//   AVX512 FMA: <GFLOP/s> GFLOP/s (thread CPU time; wall clock <GFLOP/s>)
//   AVX2 FMA: <GFLOP/s> GFLOP/s (thread CPU time; wall clock <GFLOP/s>)
// or `<ISA> FMA: n/a (...)`. Exits 1 when the CPU has neither.
// Build: cmake --build build-bench --target peak_fma, or g++ -O2 bench/peak_fma.cpp -o peak_fma
#include <immintrin.h>

#include <chrono>
#include <cstdio>
#include <ctime>

namespace {

constexpr int chains = 12;
constexpr long iterations = 100000000 / chains;  // 100 M FMAs a repetition

double thread_cpu_seconds()
{
    timespec ts{};
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
}

/// One repetition's rates: over thread CPU time and over wall-clock time, and the accumulators' sum (printed,
/// so that the chains cannot be optimised away).
struct rate {
    double cpu_gflops = 0, wall_gflops = 0;
    float sum = 0;
};

/// Rates of `fmas` FMAs of `lanes` floats each (2 FLOP per lane) timed from t0/c0 to now.
rate finish(std::chrono::steady_clock::time_point t0, double c0, double fmas, int lanes, const float* acc, int n)
{
    const double cpu = thread_cpu_seconds() - c0;
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    rate r;
    r.cpu_gflops = fmas * lanes * 2 / cpu / 1e9;
    r.wall_gflops = fmas * lanes * 2 / wall / 1e9;
    for (int i = 0; i < n; ++i) r.sum += acc[i];
    return r;
}

// d[i] = d[i] * b + c on every chain: the multiplier just below 1 and the small addend keep the values finite.
__attribute__((target("avx512f"), noinline)) rate run_avx512(long n)
{
    __m512 d[chains];
    for (int i = 0; i < chains; ++i) d[i] = _mm512_set1_ps(1.0f + float(i) * 1e-3f);
    const __m512 b = _mm512_set1_ps(0.9999f), c = _mm512_set1_ps(1e-6f);
    const auto t0 = std::chrono::steady_clock::now();
    const double c0 = thread_cpu_seconds();
    for (long k = 0; k < n; ++k) {
#pragma GCC unroll 12
        for (int i = 0; i < chains; ++i) d[i] = _mm512_fmadd_ps(d[i], b, c);
    }
    float acc[chains * 16];
    for (int i = 0; i < chains; ++i) _mm512_storeu_ps(acc + 16 * i, d[i]);
    return finish(t0, c0, double(n) * chains, 16, acc, chains * 16);
}

__attribute__((target("avx2,fma"), noinline)) rate run_avx2(long n)
{
    __m256 d[chains];
    for (int i = 0; i < chains; ++i) d[i] = _mm256_set1_ps(1.0f + float(i) * 1e-3f);
    const __m256 b = _mm256_set1_ps(0.9999f), c = _mm256_set1_ps(1e-6f);
    const auto t0 = std::chrono::steady_clock::now();
    const double c0 = thread_cpu_seconds();
    for (long k = 0; k < n; ++k) {
#pragma GCC unroll 12
        for (int i = 0; i < chains; ++i) d[i] = _mm256_fmadd_ps(d[i], b, c);
    }
    float acc[chains * 8];
    for (int i = 0; i < chains; ++i) _mm256_storeu_ps(acc + 8 * i, d[i]);
    return finish(t0, c0, double(n) * chains, 8, acc, chains * 8);
}

/// Best of 5 repetitions (other processes share the machine), printed as `<name> FMA: ...`.
void report(const char* name, rate (*run)(long))
{
    rate best;
    float sum = 0;
    for (int rep = 0; rep < 5; ++rep) {
        const rate r = run(iterations);
        best.cpu_gflops = r.cpu_gflops > best.cpu_gflops ? r.cpu_gflops : best.cpu_gflops;
        best.wall_gflops = r.wall_gflops > best.wall_gflops ? r.wall_gflops : best.wall_gflops;
        sum += r.sum;
    }
    std::printf("%s FMA: %.1f GFLOP/s (thread CPU time; wall clock %.1f) (sum %g)\n", name, best.cpu_gflops,
                best.wall_gflops, double(sum));
    std::fflush(stdout);
}

}  // namespace

int main()
{
    __builtin_cpu_init();
    const bool avx512 = __builtin_cpu_supports("avx512f");
    const bool avx2 = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
    if (avx512) report("AVX512", run_avx512);
    else std::printf("AVX512 FMA: n/a (the CPU has no AVX-512F)\n");
    if (avx2) report("AVX2", run_avx2);
    else std::printf("AVX2 FMA: n/a (the CPU has no AVX2 and FMA)\n");
    return avx512 || avx2 ? 0 : 1;
}
