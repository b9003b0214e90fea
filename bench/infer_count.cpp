// One G inference at batch 1 for a named configuration, for deterministic instruction counts under callgrind
// (README, "Embedded targets"; no timing: the machine it runs on is shared). Prints the weight and activation
// bytes. `micro` runs hand-micro through handemo::micro::generator (the microcontroller path) instead.
//   valgrind --tool=callgrind --toggle-collect='*::infer*' build/bench/infer_count hand-micro [micro]
#include <handemo/micro.hpp>
#include <handemo/nn.hpp>
#include <handemo/stargan.hpp>

#include <cstdio>
#include <string>
#include <vector>

using namespace handemo;

namespace {

struct micro_model {
    static constexpr std::size_t joints = 23, keyframes = 9, domains = 5, conv_dim = 8, res_blocks = 3;
    static constexpr bool residual = true;
    using layout = micro::generator_layout<keyframes, joints, domains, conv_dim, res_blocks>;
    static inline float weights[layout::parameter_count];
};

}  // namespace

int main(int argc, char** argv)
{
    if (argc < 2) {
        std::fprintf(stderr, "usage: infer_count CONFIG [micro]\n");
        return 2;
    }
    const std::string name = argv[1];
    const bool use_micro = argc > 2 && std::string(argv[2]) == "micro";
    return stargan::with_config(name, [&]<stargan::stargan_config Config>(const stargan::config_info&) {
        using cfg = stargan::with_batch<Config, 1>;
        stargan::generator<float, cfg> g;
        init_pytorch_default(g, 1);
        g.set_residual(true);
        constexpr std::size_t H = stargan::dims<cfg>::H, W = stargan::dims<cfg>::W, C = Config::domains;
        std::vector<float> x(3 * H * W, 0.25f), y(3 * H * W), label(C, 0.f);
        label[0] = 1.f;
        if (use_micro) {
            if constexpr (std::is_same_v<Config, stargan::hand_micro>) {
                std::size_t i = 0;
                g.for_each_parameter([&](std::string_view, std::span<float> v, std::span<float>, auto) {
                    for (float w : v) micro_model::weights[i++] = w;
                });
                static micro::generator<micro_model>::workspace ws;
                micro::generator<micro_model>::infer_padded(x.data(), label.data(), y.data(), ws);
                std::printf("%s micro: %zu weight bytes, %zu activation bytes, y[0] = %g\n", name.c_str(),
                            g.parameter_count() * sizeof(float), sizeof ws, double(y[0]));
                return 0;
            } else {
                std::fprintf(stderr, "infer_count: 'micro' needs hand-micro\n");
                return 2;
            }
        }
        typename stargan::generator<float, cfg>::workspace ws;
        g.infer(x.data(), label.data(), y.data(), ws);
        std::printf("%s (%s): %zu weight bytes, %zu activation bytes, %.0f multiply-adds, y[0] = %g\n", name.c_str(),
                    xsimd::default_arch::name(), g.parameter_count() * sizeof(float), ws.bytes(), g.forward_macs(),
                    double(y[0]));
        return 0;
    });
}
