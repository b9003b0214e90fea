// G's output on this machine against tests/fixtures/infer_x86.safetensors, computed on x86-64 (the xsimd
// architecture it was written with is in its metadata, `arch`): the
// same fixed seeded weights, input image and label must give the same output within 1e-5 on every
// architecture. The x86 build runs it (label default), the aarch64 cross build runs it under qemu-aarch64
// (label cross): hand-embedded through the xsimd kernels (AVX2/AVX-512 there, NEON here) and hand-micro through
// micro::generator (plain loops, the microcontroller path).
// Regenerate on x86 only: HANDEMO_WRITE_FIXTURE=1 build/tests/micro/test_micro -tc='*fixture*'
#include <doctest/doctest.h>

#include "helpers.hpp"

#include <handemo/core/half.hpp>
#include <handemo/micro.hpp>
#include <handemo/nn/safetensors.hpp>
#include <handemo/stargan/configs.hpp>
#include <handemo/stargan/export.hpp>
#include <handemo/stargan/model.hpp>
#include <handemo/stargan/train.hpp>

#include <xsimd/xsimd.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <numeric>
#include <string>
#include <type_traits>
#include <vector>

using namespace handemo;

#ifdef HANDEMO_EXPECT_NEON64
static_assert(std::is_same_v<xsimd::default_arch, xsimd::neon64>, "aarch64 build: xsimd did not choose neon64");
#endif

namespace {

const std::filesystem::path fixture_path = std::filesystem::path(HANDEMO_FIXTURE_DIR) / "infer_x86.safetensors";

double weight_sum(const std::vector<float>& w) { return std::accumulate(w.begin(), w.end(), 0.0); }

float max_abs_diff(const std::vector<float>& a, const std::vector<float>& b)
{
    float m = 0.f;
    for (std::size_t i = 0; i < a.size(); ++i) m = std::max(m, std::abs(a[i] - b[i]));
    return m;
}

}  // namespace

TEST_CASE("G output equals the x86 fixture within 1e-5 (hand-embedded on the SIMD kernels, hand-micro on micro::generator)")
{
    using emb = stargan::with_batch<stargan::hand_embedded, 1>;
    constexpr std::size_t K = 9, J = 23, H = 12, W = 24, C = 5;
    std::printf("xsimd architecture: %s, %d float lanes\n", xsimd::default_arch::name(), int(xsimd::batch<float>::size));

    stargan::generator<float, emb> g;
    test::seed_generator(g, 21);
    const auto wg = test::flat_parameters(g);
    using micro_model = test::runtime_model<stargan::hand_micro, true>;
    stargan::generator<float, stargan::hand_micro> gm;
    test::seed_generator(gm, 22);
    const auto wm = test::flat_parameters(gm);
    micro_model::set_weights(wm);

    // HANDEMO_WRITE_FIXTURE=1 writes the fixture from this machine's outputs first; either way the comparisons
    // below run against the file as it is read back
    const bool write = std::getenv("HANDEMO_WRITE_FIXTURE") != nullptr;
    std::vector<float> x(3 * K * J), label(C);
    if (write) {
        x = stargan::detail::self_test_input(K, J);
        label[3] = 1.f;  // sad
    } else {
        REQUIRE(std::filesystem::exists(fixture_path));
        const safetensors_file f = read_safetensors(fixture_path);
        x = f.get<float>("x", std::vector<std::size_t>{3, K, J});
        label = f.get<float>("label", std::vector<std::size_t>{C});
    }

    std::vector<float> xp(3 * H * W), yp(3 * H * W), y_emb(3 * K * J), y_micro(3 * K * J);
    stargan::pad_image(x.data(), K, J, xp.data(), H, W);
    typename stargan::generator<float, emb>::workspace ws;
    g.infer(xp.data(), label.data(), yp.data(), ws);
    stargan::crop_image(yp.data(), H, W, y_emb.data(), K, J);
    static micro::generator<micro_model>::workspace mws;
    const std::size_t target = std::size_t(std::max_element(label.begin(), label.end()) - label.begin());
    REQUIRE(micro::generator<micro_model>::infer(x.data(), target, y_micro.data(), mws));

    if (write) {
        safetensors_file w;
        w.metadata["what"] = "handemo tests/micro/infer_fixture_test.cpp: seeded G outputs computed on x86-64";
        w.metadata["arch"] = xsimd::default_arch::name();
        w.add<float>("x", x, {3, K, J});
        w.add<float>("label", label, {C});
        w.add<float>("hand_embedded.y", y_emb, {3, K, J});
        w.add<float>("hand_micro.y", y_micro, {3, K, J});
        w.add<double>("hand_embedded.weight_sum", std::vector<double>{weight_sum(wg)}, {1});
        w.add<double>("hand_micro.weight_sum", std::vector<double>{weight_sum(wm)}, {1});
        write_safetensors(fixture_path, w);
        MESSAGE("wrote " << fixture_path.string());
    }
    const safetensors_file f = read_safetensors(fixture_path);
    CHECK(f.get<float>("x", std::vector<std::size_t>{3, K, J}) == x);
    CHECK(f.get<float>("label", std::vector<std::size_t>{C}) == label);
    // the seeded weights are the same here as on x86 (handemo::rng is portable)
    CHECK(weight_sum(wg) == doctest::Approx(f.get<double>("hand_embedded.weight_sum")[0]).epsilon(1e-12));
    CHECK(weight_sum(wm) == doctest::Approx(f.get<double>("hand_micro.weight_sum")[0]).epsilon(1e-12));
    const float de = max_abs_diff(y_emb, f.get<float>("hand_embedded.y", std::vector<std::size_t>{3, K, J}));
    const float dm = max_abs_diff(y_micro, f.get<float>("hand_micro.y", std::vector<std::size_t>{3, K, J}));
    // the frozen generator (weights packed once, the weight-stationary kernels) gives the same image here
    const auto frozen = g.freeze();
    typename stargan::frozen_generator<float, emb>::workspace fws(frozen);
    std::vector<float> y_frozen(3 * K * J);
    frozen.infer(xp.data(), label.data(), yp.data(), fws);
    stargan::crop_image(yp.data(), H, W, y_frozen.data(), K, J);
    const float df = max_abs_diff(y_frozen, f.get<float>("hand_embedded.y", std::vector<std::size_t>{3, K, J}));
    std::printf("max |G - x86 fixture|: hand-embedded %.3g (frozen %.3g), hand-micro %.3g\n", double(de), double(df),
                double(dm));
    CHECK(de <= 1e-5f);
    CHECK(df <= 1e-5f);
    CHECK(dm <= 1e-5f);
}

TEST_CASE("frozen_generator with binary16 weights: G of the rounded weights, bit for bit, in half the bytes")
{
    // with weight_storage::f16 the packed panels hold binary16 where the kernels widen it natively (AVX-512,
    // AVX2 + F16C, NEON: this test also runs under qemu-aarch64); either way the output is exactly that of the
    // float kernels on the weights rounded to binary16 beforehand (the norm parameters stay float)
    using emb = stargan::with_batch<stargan::hand_embedded, 1>;
    constexpr std::size_t H = 12, W = 24, C = 5;
    stargan::generator<float, emb> g, rounded;
    test::seed_generator(g, 21);
    test::seed_generator(rounded, 21);
    rounded.for_each_parameter([](std::string_view, std::span<float> v, std::span<float>, std::span<const std::size_t> shape) {
        if (shape.size() == 4)
            for (auto& x : v) x = half_to_float(float_to_half(x));
    });
    const auto half = g.freeze(kernels::weight_storage::f16), want = rounded.freeze(), plain = g.freeze();
    CHECK(half.storage() == kernels::weight_storage::f16);
    std::vector<float> xp(3 * H * W), label(C), y_half(xp.size()), y_want(xp.size()), y_plain(xp.size());
    handemo::rng r(5);
    for (auto& v : xp) v = float(r.uniform(-1, 1));
    label[1] = 1.f;
    typename stargan::frozen_generator<float, emb>::workspace w1(half), w2(want), w3(plain);
    half.infer(xp.data(), label.data(), y_half.data(), w1);
    want.infer(xp.data(), label.data(), y_want.data(), w2);
    plain.infer(xp.data(), label.data(), y_plain.data(), w3);
    CHECK(std::memcmp(y_half.data(), y_want.data(), y_half.size() * sizeof(float)) == 0);
    const float d = max_abs_diff(y_half, y_plain);
    std::printf("hand-embedded G, binary16 weights: %zu of %zu weight bytes, max |y_f16 - y_f32| %.3g\n", half.weight_bytes(),
                plain.weight_bytes(), double(d));
    CHECK(d > 0.f);     // the rounding is real
    CHECK(d < 2e-2f);   // and small next to the output's range (-1, 1)
    if constexpr (kernels::detail::ws_f16_native<float>) CHECK(half.weight_bytes() < plain.weight_bytes() * 52 / 100);
    else CHECK(half.weight_bytes() == plain.weight_bytes());
    // a weight binary16 cannot hold is refused, naming the parameter
    stargan::generator<float, emb> big;
    test::seed_generator(big, 21);
    big.for_each_parameter([](std::string_view name, std::span<float> v, std::span<float>, auto) {
        if (name == "main.3.weight") v[4] = 1e5f;
    });
    CHECK_THROWS_WITH_AS(big.freeze(kernels::weight_storage::f16), doctest::Contains("parameter main.3.weight: packed_conv: weight 4 is 100000"),
                         value_error);
    // the first layer's label-channel weights too (the frozen G keeps them as maps, not as packed weights)
    stargan::generator<float, emb> big_label;
    test::seed_generator(big_label, 21);
    big_label.for_each_parameter([](std::string_view name, std::span<float> v, std::span<float>, auto) {
        if (name == "main.0.weight") v[3 * 49] = 1e5f;  // output channel 0, input channel 3: the first label channel
    });
    CHECK_THROWS_WITH_AS(big_label.freeze(kernels::weight_storage::f16),
                         doctest::Contains("parameter main.0.weight: packed_conv: weight 147 is 100000"), value_error);
}

TEST_CASE("the fixture's hand-micro weights as an exported header (HANDEMO_WRITE_MICRO_HEADER=path)")
{
    // The header `handemo export --header` would write for these seeded weights, self-test included; the
    // Cortex-M firmware (tests/cross/cortex_m) builds around either. Without the variable: the text only.
    stargan::generator<float, stargan::with_batch<stargan::hand_micro, 1>> g;
    test::seed_generator(g, 22);
    g.set_residual(true);
    stargan::checkpoint_info info;
    info.config = "hand-micro";
    info.domains = stargan::hand_domains();
    info.neutral = "neutral";
    info.range.p_min = -180;
    info.range.p_max = 180;
    info.range.keyframes = 9;
    info.range.joints = 23;
    stargan::header_export_options o;
    o.source = "tests/micro/infer_fixture_test.cpp (seed 22)";
    o.self_test_emotion = "sad";
    const std::string h = stargan::generator_header(g, info, o);
    CHECK(h.find("float weights[80632]") != std::string::npos);
    if (const char* path = std::getenv("HANDEMO_WRITE_MICRO_HEADER")) {
        std::ofstream(path, std::ios::binary) << h;
        std::printf("wrote %s\n", path);
    }
}
