// Prints, as one JSON object on stdout, the raw generator output of a hand-embedded checkpoint on a fixed input,
// for the golden test against the PyTorch reference (tests/golden/generator_test.py): the input image x
// [1, 3, H, W] (the K x J motion image zero-padded to H x W), G(x, c) for every one-hot target c through
// generator::infer and through frozen_generator (the path transfers take), and the parameter names and
// shapes of handemo's G and D, which the reference's state_dict must equal.
// Usage: golden_generator_output <checkpoint.safetensors>
#include <handemo/stargan/configs.hpp>
#include <handemo/stargan/train.hpp>

#include <cmath>
#include <cstdio>
#include <exception>
#include <string>
#include <vector>

using namespace handemo;
using namespace handemo::stargan;

namespace {

using config = with_batch<hand_embedded, 1>;
using gen_type = generator<float, config>;
constexpr std::size_t H = gen_type::H, W = gen_type::W, C = gen_type::C;

void print_floats(const char* key, const std::vector<float>& v)
{
    std::printf("\"%s\":[", key);
    for (std::size_t i = 0; i < v.size(); ++i) std::printf("%s%.9g", i ? "," : "", double(v[i]));
    std::printf("]");
}

template <class M>
void print_parameters(const char* key, M& model)
{
    std::printf("\"%s\":[", key);
    bool first = true;
    for (const auto& p : list_parameters(model)) {
        std::printf("%s[\"%s\",[", first ? "" : ",", p.name.c_str());
        for (std::size_t i = 0; i < p.shape.size(); ++i) std::printf("%s%zu", i ? "," : "", p.shape[i]);
        std::printf("]]");
        first = false;
    }
    std::printf("]");
}

}  // namespace

int main(int argc, char** argv)
{
    if (argc != 2) {
        std::fprintf(stderr, "usage: golden_generator_output <checkpoint.safetensors>\n");
        return 2;
    }
    try {
        const auto ck = read_checkpoint(argv[1]);
        const safetensors_file& f = ck.first;
        const checkpoint_info& info = ck.second;
        if (info.config != "hand-embedded") {
            std::fprintf(stderr, "golden_generator_output: %s: configuration %s, expected hand-embedded\n", argv[1],
                         info.config.c_str());
            return 1;
        }
        gen_type g;
        load_parameters(f, g, f.find("G_ema.main.0.weight") ? "G_ema." : "G.");
        const bool residual = info.options.is_object() && info.options.value("residual", false);
        g.set_residual(residual);
        g.set_requires_grad(false);
        const auto frozen = g.freeze();

        // a smooth input of every sign inside the K x J motion image, zero in the padding (as pad_image leaves it)
        std::vector<float> x(3 * H * W, 0.f);
        for (std::size_t c = 0; c < 3; ++c)
            for (std::size_t h = 0; h < hand_embedded::keyframes; ++h)
                for (std::size_t w = 0; w < hand_embedded::joints; ++w)
                    x[(c * H + h) * W + w] = float(0.9 * std::sin(1.3 * double(c) + 0.37 * double(h) + 0.11 * double((c + 1) * w)));

        std::printf("{\"config\":\"%s\",\"residual\":%s,\"H\":%zu,\"W\":%zu,\"C\":%zu,", info.config.c_str(),
                    residual ? "true" : "false", H, W, C);
        print_floats("x", x);
        gen_type::workspace ws;
        frozen_generator<float, config>::workspace fws(frozen);
        std::vector<float> label(C), out(x.size());
        for (const char* path : {"infer", "frozen"}) {
            std::printf(",\"%s\":[", path);
            for (std::size_t t = 0; t < C; ++t) {
                std::fill(label.begin(), label.end(), 0.f);
                label[t] = 1.f;
                if (path[0] == 'i') g.infer(x.data(), label.data(), out.data(), ws);
                else frozen.infer(x.data(), label.data(), out.data(), fws);
                std::printf("%s{", t ? "," : "");
                print_floats("y", out);
                std::printf("}");
            }
            std::printf("]");
        }
        std::printf(",");
        print_parameters("g_params", g);
        discriminator<float, config> d;
        std::printf(",");
        print_parameters("d_params", d);
        std::printf("}\n");
    } catch (const std::exception& e) {
        std::fprintf(stderr, "golden_generator_output: %s\n", e.what());
        return 1;
    }
    return 0;
}
