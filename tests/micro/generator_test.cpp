// micro::generator (the inference-only path for microcontrollers) against stargan::generator::infer, and
// the header that `handemo export --header` writes (stargan/export.hpp).
#include <doctest/doctest.h>

#include "helpers.hpp"

#include <handemo/micro.hpp>
#include <handemo/stargan.hpp>

#include <algorithm>
#include <bit>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include <stdlib.h>

using namespace handemo;

namespace {

/// Largest |micro - host| over G(x, c) for a seeded Cfg, every target domain.
template <class Cfg, bool Residual>
float max_diff_to_host(std::uint64_t seed)
{
    using hcfg = stargan::with_batch<Cfg, 1>;
    stargan::generator<float, hcfg> g;
    test::seed_generator(g, seed);
    g.set_residual(Residual);
    using model = test::runtime_model<Cfg, Residual>;
    model::set_weights(test::flat_parameters(g));
    using mg = micro::generator<model>;
    constexpr std::size_t K = Cfg::keyframes, J = Cfg::joints, C = Cfg::domains, H = mg::H, W = mg::W;
    const auto x = stargan::detail::self_test_input(K, J);
    std::vector<float> xp(3 * H * W), yp(3 * H * W), host(3 * K * J), dev(3 * K * J);
    stargan::pad_image(x.data(), K, J, xp.data(), H, W);
    typename stargan::generator<float, hcfg>::workspace hws;
    static typename mg::workspace ws;  // ~30 KB for hand-micro: static, as on the device
    float worst = 0.f;
    for (std::size_t t = 0; t < C; ++t) {
        std::vector<float> label(C, 0.f);
        label[t] = 1.f;
        g.infer(xp.data(), label.data(), yp.data(), hws);
        stargan::crop_image(yp.data(), H, W, host.data(), K, J);
        CHECK(mg::infer(x.data(), t, dev.data(), ws));
        for (std::size_t i = 0; i < host.size(); ++i) worst = std::max(worst, std::abs(host[i] - dev[i]));
        // the output is not trivially the input or zero
        float change = 0.f;
        for (std::size_t i = 0; i < host.size(); ++i) change = std::max(change, std::abs(host[i] - (Residual ? x[i] : 0.f)));
        CHECK(change > 0.05f);
    }
    // a target that is not a domain: refused (false), the output zeroed, nothing run
    std::fill(dev.begin(), dev.end(), 7.f);
    CHECK_FALSE(mg::infer(x.data(), C, dev.data(), ws));
    CHECK(std::all_of(dev.begin(), dev.end(), [](float v) { return v == 0.f; }));
    return worst;
}

}  // namespace

TEST_CASE("micro::generator equals stargan::generator::infer within 1e-5")
{
    CHECK(max_diff_to_host<stargan::hand_micro, false>(11) <= 1e-5f);
    CHECK(max_diff_to_host<stargan::hand_micro, true>(12) <= 1e-5f);
    CHECK(max_diff_to_host<stargan::hand_tiny, false>(13) <= 1e-5f);
}

namespace {

/// Largest |micro - reference| of micro::detail::conv_forward<G> and conv_transpose<G> (when `transposed`)
/// on seeded data, relative to the largest output.
template <kernels::conv_geometry G, bool transposed>
float micro_conv_error()
{
    rng r(uint64_t(G.in_channels * 131 + G.kernel_h * 7 + G.stride));
    std::vector<float> x(transposed ? G.y_size() : G.x_size()), w(G.w_size());
    for (auto& v : x) v = float(r.uniform(-1, 1));
    for (auto& v : w) v = float(r.uniform(-1, 1));
    const std::size_t ny = transposed ? G.x_size() : G.y_size();
    std::vector<float> ref(ny), got(ny, 1e9f),
        pad(std::max(micro::detail::conv_pad_elements(G), micro::detail::convt_pad_elements(G)), 7.f);
    if constexpr (transposed) {
        kernels::reference::conv_transpose2d_forward(G, x.data(), w.data(), ref.data(), static_cast<float*>(nullptr));
        micro::detail::conv_transpose<G>(x.data(), w.data(), got.data(), pad.data());
    } else {
        kernels::reference::conv2d_forward(G, x.data(), w.data(), static_cast<const float*>(nullptr), ref.data(),
                                           static_cast<float*>(nullptr));
        micro::detail::conv_forward<G>(x.data(), w.data(), got.data(), pad.data());
    }
    float worst = 0.f, scale = 0.f;
    for (std::size_t i = 0; i < ny; ++i) {
        worst = std::max(worst, std::abs(ref[i] - got[i]));
        scale = std::max(scale, std::abs(ref[i]));
    }
    CHECK(scale > 0.1f);
    return worst / scale;
}

}  // namespace

TEST_CASE("micro convolutions (output-stationary, padded copy) equal the reference kernels")
{
    // the generator's seven layers at hand-micro's size, and geometries it does not use: other widths
    // (row tiles of 1, 5 and 7 pixels), stride 2 with kernel 3, pad 0, non-square kernels
    using kernels::conv_geometry;
    CHECK(micro_conv_error<conv_geometry{1, 8, 12, 24, 8, 7, 7, 1, 3}, false>() <= 1e-6f);
    CHECK(micro_conv_error<conv_geometry{1, 8, 12, 24, 16, 4, 4, 2, 1}, false>() <= 1e-6f);
    CHECK(micro_conv_error<conv_geometry{1, 32, 3, 6, 32, 3, 3, 1, 1}, false>() <= 1e-6f);
    CHECK(micro_conv_error<conv_geometry{1, 8, 12, 24, 3, 7, 7, 1, 3}, false>() <= 1e-6f);
    CHECK(micro_conv_error<conv_geometry{1, 3, 5, 11, 4, 3, 3, 1, 1}, false>() <= 1e-6f);
    CHECK(micro_conv_error<conv_geometry{1, 2, 9, 15, 3, 3, 3, 2, 1}, false>() <= 1e-6f);
    CHECK(micro_conv_error<conv_geometry{1, 3, 6, 9, 2, 2, 3, 1, 0}, false>() <= 1e-6f);
    CHECK(micro_conv_error<conv_geometry{1, 2, 7, 14, 5, 5, 1, 1, 2}, false>() <= 1e-6f);
    // transposed: up1 and up2 of hand-micro, and stride 2 / kernel 3, stride 3, pad 0
    CHECK(micro_conv_error<conv_geometry{1, 16, 6, 12, 32, 4, 4, 2, 1}, true>() <= 1e-6f);
    CHECK(micro_conv_error<conv_geometry{1, 8, 12, 24, 16, 4, 4, 2, 1}, true>() <= 1e-6f);
    CHECK(micro_conv_error<conv_geometry{1, 3, 10, 8, 4, 3, 3, 2, 1}, true>() <= 1e-6f);
    CHECK(micro_conv_error<conv_geometry{1, 2, 9, 12, 3, 3, 3, 3, 0}, true>() <= 1e-6f);
    CHECK(micro_conv_error<conv_geometry{1, 4, 8, 16, 2, 4, 2, 2, 0}, true>() <= 1e-6f);
}

TEST_CASE("hand-micro fits a Cortex-M7: <= 512 KB of float weights, <= 128 KB of activations")
{
    using layout = micro::generator_layout<9, 23, 5, 8, 3>;
    stargan::generator<float, stargan::hand_micro> g;
    CHECK(layout::parameter_count == g.parameter_count());
    CHECK(layout::parameter_count * sizeof(float) <= 512u * 1024u);
    CHECK(layout::workspace_bytes <= 128u * 1024u);
    using model = test::runtime_model<stargan::hand_micro, true>;
    CHECK(sizeof(micro::generator<model>::workspace) == layout::workspace_bytes);
    MESSAGE("hand-micro: " << layout::parameter_count << " parameters, " << layout::parameter_count * 4
                           << " bytes of weights, " << layout::workspace_bytes << " bytes of activations, "
                           << layout::macs() << " multiply-adds");
}

TEST_CASE("export: float literals round-trip exactly and always parse as float")
{
    for (float v : {0.f, 1.f, -2.f, 0.1f, -3.0e-7f, 1.17549435e-38f, 3.4028235e38f, 123456.78f, -0.f}) {
        const std::string s = stargan::detail::float_literal(v);
        CHECK(s.back() == 'f');
        CHECK(s.find_first_of(".e") != std::string::npos);
        float back = 1.f;
        const auto r = std::from_chars(s.data(), s.data() + s.size() - 1, back);
        CHECK(r.ec == std::errc{});
        CHECK(r.ptr == s.data() + s.size() - 1);
        // the same bits: == would let -0.f come back as 0.f
        CHECK(std::bit_cast<std::uint32_t>(back) == std::bit_cast<std::uint32_t>(v));
    }
    CHECK(stargan::detail::float_literal(-0.f).front() == '-');
    CHECK_THROWS_AS(stargan::detail::float_literal(std::nanf("")), value_error);
}

TEST_CASE("export: a model path whose status cannot be read is an io_error naming it")
{
    std::string t = (std::filesystem::temp_directory_path() / "handemo_export_XXXXXX").string();
    REQUIRE(::mkdtemp(t.data()) != nullptr);
    const std::filesystem::path loop = std::filesystem::path(t) / "model";
    std::filesystem::create_symlink(loop, loop);  // a link to itself: stat fails with ELOOP
    CHECK_THROWS_WITH_AS(stargan::export_generator_header(loop, {}), doctest::Contains(loop.string().c_str()), io_error);
    CHECK_THROWS_WITH_AS(stargan::export_generator_header(loop / "checkpoint.safetensors", {}), doctest::Contains(loop.string().c_str()),
                         io_error);
    std::filesystem::remove_all(t);
}

TEST_CASE("export: the header holds the configuration, every weight and a host-computed self-test")
{
    stargan::generator<float, stargan::with_batch<stargan::hand_micro, 1>> g;
    test::seed_generator(g, 5);
    g.set_residual(true);
    stargan::checkpoint_info info;
    info.config = "hand-micro";
    info.domains = stargan::hand_domains();
    info.neutral = "neutral";
    info.range.p_min = -90;
    info.range.p_max = 90;
    info.range.keyframes = 9;
    info.range.joints = 23;
    stargan::header_export_options o;
    o.struct_name = "glove_model";
    o.self_test_emotion = "sad";
    const std::string h = stargan::generator_header(g, info, o);
    CHECK(h.find("struct glove_model {") != std::string::npos);
    CHECK(h.find("conv_dim = 8, res_blocks = 3;") != std::string::npos);
    CHECK(h.find("static constexpr bool residual = true;") != std::string::npos);
    CHECK(h.find("float weights[80632]") != std::string::npos);
    CHECK(h.find("self_test_target = 3;") != std::string::npos);  // sad
    CHECK(h.find("main.11.main.4.bias [32]") != std::string::npos);  // the last residual block's IN
    o.self_test_emotion = "bored";
    CHECK_THROWS_WITH_AS(stargan::generator_header(g, info, o), doctest::Contains("unknown emotion 'bored'"), value_error);
}
