// G inference, batch 1, between two marker system calls, for counting the instructions one inference takes
// on a target that has no hardware counters here (aarch64 under qemu-aarch64: bench/aarch64_icount.sh runs it
// with one instruction per translation block and counts the executed blocks between the markers).
// Usage: icount_infer CONFIG STORAGE   CONFIG: paper | embedded | micro (hand-micro through the SIMD kernels)
//        | micro-plain (hand-micro through handemo::micro, the microcontroller path); STORAGE: native | f16.
// The weights are a cheap deterministic pattern (the instruction count of G does not depend on their values,
// and PyTorch's init under one-instruction-per-block emulation would take minutes for the paper's 8.4 M).
#include <handemo/micro.hpp>
#include <handemo/stargan/model.hpp>

#include "../../tests/micro/helpers.hpp"  // runtime_model, flat_parameters

#include <sys/syscall.h>
#include <unistd.h>

#include <cstdio>
#include <cstring>
#include <span>
#include <string_view>
#include <vector>

using namespace handemo;
using namespace handemo::stargan;

namespace {

/// The marker the counting script looks for in qemu's system-call log (getppid has no side effect).
void marker() { syscall(SYS_getppid); }

template <class G>
void fill_pattern(G& g)
{
    std::uint32_t s = 12345;
    g.for_each_parameter([&](std::string_view, std::span<float> v, std::span<float>, auto) {
        for (auto& x : v) {
            s = s * 1664525u + 1013904223u;
            x = (float(s >> 8) / float(1u << 24) - 0.5f) * 0.1f;
        }
    });
}

std::vector<float> input(std::size_t n)
{
    std::vector<float> x(n);
    for (std::size_t i = 0; i < n; ++i) x[i] = float((i * 37) % 101) / 50.f - 1.f;
    return x;
}

template <class Config>
int run_frozen(kernels::weight_storage storage)
{
    generator<float, Config> g;
    fill_pattern(g);
    const auto f = g.freeze(storage);
    typename frozen_generator<float, Config>::workspace ws(f);
    constexpr std::size_t H = dims<Config>::H, W = dims<Config>::W, C = Config::domains;
    const std::vector<float> x = input(3 * H * W);
    std::vector<float> lab(C, 0.f), out(x.size());
    lab[2] = 1;
    f.infer(x.data(), lab.data(), out.data(), ws);  // warm: first-touch of the workspace stays outside
    marker();
    f.infer(x.data(), lab.data(), out.data(), ws);
    marker();
    double sum = 0;
    for (float v : out) sum += v;
    std::printf("icount_infer: %zu weight bytes, output sum %.6f\n", f.weight_bytes(), sum);
    return 0;
}

int run_micro_plain()
{
    using model = test::runtime_model<hand_micro, true>;
    generator<float, with_batch<hand_micro, 1>> g;
    fill_pattern(g);
    model::set_weights(test::flat_parameters(g));
    using mg = micro::generator<model>;
    static mg::workspace ws;
    const std::vector<float> x = input(3 * hand_micro::keyframes * hand_micro::joints);
    std::vector<float> out(x.size());
    mg::infer(x.data(), 2, out.data(), ws);
    marker();
    mg::infer(x.data(), 2, out.data(), ws);
    marker();
    double sum = 0;
    for (float v : out) sum += v;
    std::printf("icount_infer: %zu weight bytes, output sum %.6f\n", sizeof(model::weights), sum);
    return 0;
}

}  // namespace

int main(int argc, char** argv)
{
    if (argc != 3) {
        std::fprintf(stderr, "usage: icount_infer paper|embedded|micro|micro-plain native|f16\n");
        return 2;
    }
    const std::string_view cfg = argv[1], st = argv[2];
    if (st != "native" && st != "f16") {
        std::fprintf(stderr, "icount_infer: storage '%s' is not native or f16\n", argv[2]);
        return 2;
    }
    const auto storage = st == "f16" ? kernels::weight_storage::f16 : kernels::weight_storage::native;
    if (cfg == "paper") return run_frozen<hand_paper>(storage);
    if (cfg == "embedded") return run_frozen<hand_embedded>(storage);
    if (cfg == "micro") return run_frozen<hand_micro>(storage);
    if (cfg == "micro-plain") return run_micro_plain();
    std::fprintf(stderr, "icount_infer: config '%s' is not paper, embedded, micro or micro-plain\n", argv[1]);
    return 2;
}
