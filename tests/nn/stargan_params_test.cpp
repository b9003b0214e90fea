// The nn utilities on the real StarGAN models (handemo/stargan/model.hpp): PyTorch default init by
// name and shape, Adam over for_each_parameter, save/load by PyTorch name.
#include <doctest/doctest.h>
#include <handemo/nn.hpp>
#include <handemo/stargan/model.hpp>

#include <cmath>
#include <filesystem>

namespace {
struct tiny_config {
    static constexpr std::size_t joints = 23, keyframes = 9, domains = 5, conv_dim = 4, res_blocks = 1,
                                 d_repeat = 3, batch = 2;
};
using gen_t = handemo::stargan::generator<float, tiny_config>;
using disc_t = handemo::stargan::discriminator<float, tiny_config>;
}  // namespace

TEST_CASE("nn utilities on the real StarGAN models: init, Adam, save and load")
{
    gen_t g;
    disc_t d;
    handemo::init_pytorch_default(g, 11);
    handemo::init_pytorch_default(d, 12);
    double mx_t = 0, mx_b = 0;
    g.for_each_parameter([&](std::string_view name, std::span<float> v, std::span<float>, std::span<const std::size_t>) {
        if (name == "main.10.weight")  // ConvTranspose2d(16, 8, 4): [16, 8, 4, 4], fan_in 8*16 = 128
            for (float x : v) mx_t = std::max(mx_t, double(std::abs(x)));
        if (name == "main.1.weight")
            for (float x : v) CHECK(x == 1.0f);
    });
    d.for_each_parameter([&](std::string_view name, std::span<float> v, std::span<float>, std::span<const std::size_t>) {
        if (name == "main.0.bias")  // Conv2d(3, 4, 4) bias: U(+-1/sqrt(48))
            for (float x : v) mx_b = std::max(mx_b, double(std::abs(x)));
    });
    CHECK(mx_t <= 1.0 / std::sqrt(128.0));
    CHECK(mx_t > 0.9 / std::sqrt(128.0));
    CHECK(mx_b <= 1.0 / std::sqrt(48.0));

    // save / load round trip through the PyTorch names, and the fixture's names are the same set
    const auto p = std::filesystem::temp_directory_path() / "handemo_nn_g.safetensors";
    handemo::save_parameters(p, g, {{"config", "tiny"}});
    gen_t g2;
    CHECK(handemo::load_parameters(p, g2).at("config") == "tiny");
    std::vector<float> a, b;
    g.for_each_parameter([&](auto, std::span<float> v, auto, auto) { a.insert(a.end(), v.begin(), v.end()); });
    g2.for_each_parameter([&](auto, std::span<float> v, auto, auto) { b.insert(b.end(), v.begin(), v.end()); });
    CHECK(a == b);
    std::filesystem::remove(p);

    // Adam over the generator: one step moves each weight with a nonzero gradient by ~lr
    handemo::adam<float> opt(g);
    g.zero_grad();
    g.for_each_parameter([&](auto, std::span<float>, std::span<float> gr, auto) {
        for (std::size_t i = 0; i < gr.size(); ++i) gr[i] = (i % 3 == 0) ? 0.5f : -0.25f;
    });
    opt.step(g, 1e-3);
    std::size_t k = 0;
    bool all = true;
    g.for_each_parameter([&](auto, std::span<float> v, auto, auto) {
        for (std::size_t i = 0; i < v.size(); ++i, ++k) {
            const float want = a[k] + ((i % 3 == 0) ? -1e-3f : 1e-3f);
            all = all && std::abs(v[i] - want) < 1e-6f;
        }
    });
    CHECK(all);
}
