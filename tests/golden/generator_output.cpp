// Prints, as one JSON object on stdout, the raw generator output of a hand-embedded checkpoint on a fixed input,
// for the golden test against the PyTorch reference (tests/golden/generator_test.py): the input image x
// [1, 3, H, W] (the K x J motion image zero-padded to H x W), G(x, c) for every one-hot target c through
// generator::infer and through frozen_generator (the path transfers take), and the parameter names and
// shapes of handemo's G and D, which the reference's state_dict must equal.
// Usage: golden_generator_output <checkpoint.safetensors>
//
// A second mode feeds the agreement test with ONNX Runtime (tests/golden/onnx_test.py):
//   golden_generator_output --batch CONFIG G.safetensors X.f32 C.f32 BATCH Y_BATCH.f32 Y_ONE.f32 [f16|winograd]
// loads the G parameters (PyTorch names, no prefix) of hand-embedded or hand-paper, reads BATCH images x
// [BATCH, 3, H, W] and one-hot labels [BATCH, C] (little-endian float32), and writes G(x, c) computed by
// frozen_generator::infer_batch on the whole batch (Y_BATCH) and by infer() one image at a time (Y_ONE).
// With `f16` the frozen generator stores its convolution weights as binary16 (kernels::weight_storage::f16),
// rounding the float weights it loaded itself; with `winograd` it computes the residual convolutions by Winograd's
// F(3x2, 3x3) (kernels::conv_algorithm::winograd; an error where the target has no such path).
#include <handemo/stargan/configs.hpp>
#include <handemo/stargan/train.hpp>

#include <cmath>
#include <cstdio>
#include <fstream>
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

std::vector<float> read_floats(const char* path, std::size_t count)
{
    std::vector<float> v(count);
    std::ifstream in(path, std::ios::binary);
    if (!in.read(reinterpret_cast<char*>(v.data()), std::streamsize(count * sizeof(float))) || in.peek() != EOF)
        throw io_error(std::string("golden_generator_output: ") + path + ": expected exactly " + std::to_string(count) + " float32 values");
    return v;
}

void write_floats(const char* path, const std::vector<float>& v)
{
    write_file_atomic(path, std::string_view(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(float)));
}

/// The --batch mode for one configuration.
template <stargan_config Base>
void run_batch(char** arg, kernels::weight_storage storage, kernels::conv_algorithm algorithm)
{
    using cfg = with_batch<Base, 1>;
    generator<float, cfg> g;
    load_parameters(std::filesystem::path(arg[0]), g);
    const std::size_t batch = std::stoul(arg[3]), per = 3 * dims<cfg>::H * dims<cfg>::W, C = Base::domains;
    if (batch == 0) throw value_error("golden_generator_output: batch 0");
    const auto x = read_floats(arg[1], batch * per), c = read_floats(arg[2], batch * C);
    const auto f = g.freeze(storage, algorithm);
    if (f.algorithm() != algorithm)
        throw value_error(std::string("golden_generator_output: this target has no ") + kernels::conv_algorithm_name(algorithm) + " path");
    typename frozen_generator<float, cfg>::workspace ws(f, batch), one(f);
    std::vector<float> y(batch * per), y1(batch * per);
    f.infer_batch(x.data(), c.data(), y.data(), batch, ws);
    for (std::size_t n = 0; n < batch; ++n) f.infer(x.data() + n * per, c.data() + n * C, y1.data() + n * per, one);
    write_floats(arg[4], y);
    write_floats(arg[5], y1);
}

}  // namespace

int main(int argc, char** argv)
{
    if ((argc == 9 || (argc == 10 && (std::string(argv[9]) == "f16" || std::string(argv[9]) == "winograd"))) &&
        std::string(argv[1]) == "--batch") {
        try {
            const std::string config = argv[2], mode = argc == 10 ? argv[9] : "";
            const auto storage = mode == "f16" ? kernels::weight_storage::f16 : kernels::weight_storage::native;
            const auto algorithm = mode == "winograd" ? kernels::conv_algorithm::winograd : kernels::conv_algorithm::direct;
            if (config == "hand-embedded") run_batch<hand_embedded>(argv + 3, storage, algorithm);
            else if (config == "hand-paper") run_batch<hand_paper>(argv + 3, storage, algorithm);
            else throw value_error("golden_generator_output: configuration " + config + ", expected hand-embedded or hand-paper");
        } catch (const std::exception& e) {
            std::fprintf(stderr, "golden_generator_output: %s\n", e.what());
            return 1;
        }
        return 0;
    }
    if (argc != 2) {
        std::fprintf(stderr, "usage: golden_generator_output <checkpoint.safetensors>\n"
                             "       golden_generator_output --batch CONFIG G.safetensors X.f32 C.f32 BATCH Y_BATCH.f32 Y_ONE.f32 [f16|winograd]\n");
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
