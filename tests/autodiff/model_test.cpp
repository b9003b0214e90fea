// StarGAN generator/discriminator on the autodiff tape: parameter names and layouts (official StarGAN),
// output shapes, tape-free inference equal to the tape forward, the frozen generator's batches of any size
// equal to its calls on one image, batch split over a thread pool equal to
// single-threaded, the FLOP counts of inference and of a training step against a hand count, and finite-difference gradient checks (double) of a residual block, a small G, a
// small D and the WGAN-GP penalty through a small D.
#include "gradcheck.hpp"

#include <handemo/stargan/flops.hpp>
#include <handemo/stargan/model.hpp>

#include <map>

using namespace handemo;
using namespace handemo::autodiff;
using namespace handemo::stargan;
using handemo::test::gc_param;
using handemo::test::gradcheck;
using handemo::test::leaf;
using handemo::test::random_param;

namespace {
// Tiny config: 3 keyframes x 5 joints -> 4 x 8 image, 3 domains, conv_dim 2, 1 block, D depth 2.
struct tiny {
    static constexpr std::size_t joints = 5, keyframes = 3, domains = 3, conv_dim = 2, res_blocks = 1,
                                 d_repeat = 2, batch = 2;
};
template <class M>
void randomise(M& m, unsigned seed, double scale = 0.3)
{
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-scale, scale);
    m.for_each_parameter([&](std::string_view name, auto value, auto, std::span<const std::size_t> shape) {
        // InstanceNorm gammas (1-D ".weight") around 1, everything else around 0
        const bool gamma = shape.size() == 1 && name.ends_with(".weight");
        for (auto& v : value) v = gamma ? 1 + u(rng) : u(rng);
    });
}
// Wraps every model parameter as a gc_param that aliases the model's own buffers through copies.
template <class M>
std::vector<gc_param> model_params(M& m)
{
    std::vector<gc_param> ps;
    m.for_each_parameter([&](std::string_view, std::span<double> v, std::span<double>, std::span<const std::size_t>) {
        gc_param p;
        p.value.assign(v.begin(), v.end());
        p.grad.assign(v.size(), 0.0);
        ps.push_back(std::move(p));
    });
    return ps;
}
template <class M>
void load_params(M& m, std::vector<gc_param>& ps)
{
    std::size_t k = 0;
    m.for_each_parameter([&](std::string_view, std::span<double> v, std::span<double> g, std::span<const std::size_t>) {
        std::copy(ps[k].value.begin(), ps[k].value.end(), v.begin());
        std::fill(g.begin(), g.end(), 0.0);
        ++k;
    });
}
template <class M>
void store_grads(M& m, std::vector<gc_param>& ps)
{
    std::size_t k = 0;
    m.for_each_parameter([&](std::string_view, std::span<double>, std::span<double> g, std::span<const std::size_t>) {
        std::copy(g.begin(), g.end(), ps[k].grad.begin());
        ++k;
    });
}
}  // namespace

TEST_CASE("stargan: parameter names and shapes follow official StarGAN")
{
    generator<float, hand_embedded> g;
    discriminator<float, hand_embedded> d;
    std::map<std::string, std::vector<std::size_t>> gp, dp;
    std::vector<std::string> order;
    g.for_each_parameter([&](std::string_view n, std::span<float> v, std::span<float> gr, std::span<const std::size_t> s) {
        CHECK(v.size() == gr.size());
        gp[std::string(n)] = {s.begin(), s.end()};
        order.emplace_back(n);
    });
    d.for_each_parameter([&](std::string_view n, std::span<float>, std::span<float>, std::span<const std::size_t> s) {
        dp[std::string(n)] = {s.begin(), s.end()};
    });
    using V = std::vector<std::size_t>;
    CHECK(order.front() == "main.0.weight");
    CHECK(order.back() == "main.18.weight");
    CHECK(gp["main.0.weight"] == V{32, 8, 7, 7});
    CHECK(gp["main.1.weight"] == V{32});
    CHECK(gp["main.1.bias"] == V{32});
    CHECK(gp["main.3.weight"] == V{64, 32, 4, 4});
    CHECK(gp["main.6.weight"] == V{128, 64, 4, 4});
    CHECK(gp["main.9.main.0.weight"] == V{128, 128, 3, 3});
    CHECK(gp["main.9.main.4.bias"] == V{128});
    CHECK(gp["main.11.main.3.weight"] == V{128, 128, 3, 3});
    CHECK(gp["main.12.weight"] == V{128, 64, 4, 4});  // ConvTranspose2d [in, out, k, k]
    CHECK(gp["main.13.weight"] == V{64});
    CHECK(gp["main.15.weight"] == V{64, 32, 4, 4});
    CHECK(gp["main.16.bias"] == V{32});
    CHECK(gp["main.18.weight"] == V{3, 32, 7, 7});
    CHECK(gp.size() == 3 + 6 + 3 * 6 + 6 + 1);
    CHECK(g.parameter_count() == 1231840);  // = sum(p.numel()) of reference_stargan.py G(32, 3)
    CHECK(dp["main.0.weight"] == V{32, 3, 4, 4});
    CHECK(dp["main.0.bias"] == V{32});
    CHECK(dp["main.4.weight"] == V{128, 64, 4, 4});
    CHECK(dp["conv1.weight"] == V{1, 128, 3, 3});
    CHECK(dp["conv2.weight"] == V{5, 128, 1, 3});
    CHECK(dp.size() == 8);
    generator<float, hand_paper> gpaper;
    CHECK(gpaper.parameter_count() == 8430528);
    static_assert(dims<hand_embedded>::H == 12 && dims<hand_embedded>::W == 24);
    static_assert(dims<body_embedded>::H == 12 && dims<body_embedded>::W == 24);
    static_assert(discriminator<float, with_batch<body_embedded, 4>>::cls_shape::dims[1] == 8);
}

TEST_CASE("stargan: infer equals the tape forward; thread-pool batch split equals one thread")
{
    using cfg = with_batch<hand_embedded, 3>;
    generator<float, cfg> g;
    discriminator<float, cfg> d;
    randomise(g, 1, 0.1);
    randomise(d, 2, 0.1);
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> u(-1, 1);
    std::vector<float> x(3 * 3 * 12 * 24), lab(3 * 5, 0.f), out(x.size());
    for (auto& v : x) v = u(rng);
    lab[1] = lab[5 + 4] = lab[10] = 1;
    tape<float> t1;
    auto y1 = g.forward(t1, t1.input<shape<3, 3, 12, 24>>(x.data()), t1.input<shape<3, 5>>(lab.data()));
    decltype(g)::workspace ws;
    g.infer(x.data(), lab.data(), out.data(), ws);
    for (std::size_t i = 0; i < out.size(); ++i) REQUIRE(out[i] == doctest::Approx(y1.data()[i]).epsilon(1e-4));
    {  // the frozen generator (packed weights) too, and it is a snapshot: later weight changes do not reach it
        const auto f = g.freeze();
        frozen_generator<float, cfg>::workspace fws(f);
        std::vector<float> fo(out.size(), 5.f);
        f.infer(x.data(), lab.data(), fo.data(), fws);
        for (std::size_t i = 0; i < out.size(); ++i) REQUIRE(fo[i] == doctest::Approx(y1.data()[i]).epsilon(1e-4));
        g.set_residual(true);
        g.zero_last_conv();
        std::vector<float> fo2(out.size());
        f.infer(x.data(), lab.data(), fo2.data(), fws);
        CHECK(fo2 == fo);
        g.set_residual(false);
        randomise(g, 1, 0.1);  // restore
    }

    {  // a batch of any size through one frozen generator: each image gets the bits of a call on it alone
        const auto f = g.freeze();
        constexpr std::size_t B = 7, per = 3 * 12 * 24;
        frozen_generator<float, cfg>::workspace big(f, B), one(f);
        CHECK(big.capacity() == B);
        CHECK(one.capacity() == 3);  // never fewer than the configuration's batch
        std::vector<float> xb(B * per), lb(B * 5, 0.f), yb(xb.size()), y1(per);
        for (auto& v : xb) v = u(rng);
        for (std::size_t n = 0; n < B; ++n) lb[n * 5 + (n * 3) % 5] = 1;  // every target, in no order
        f.infer_batch(xb.data(), lb.data(), yb.data(), B, big);
        for (std::size_t n = 0; n < B; ++n) {
            f.infer_batch(xb.data() + n * per, lb.data() + n * 5, y1.data(), 1, one);
            CAPTURE(n);
            CHECK(std::equal(y1.begin(), y1.end(), yb.begin() + std::ptrdiff_t(n * per)));
        }
        std::vector<float> y3(3 * per);  // infer() is the batch of N = 3
        f.infer(xb.data(), lb.data(), y3.data(), one);
        CHECK(std::equal(y3.begin(), y3.end(), yb.begin()));
        CHECK_THROWS_WITH_AS(f.infer_batch(xb.data(), lb.data(), yb.data(), 4, one), doctest::Contains("4 images, the workspace holds 1 to 3"),
                             value_error);
        CHECK_THROWS_AS(f.infer_batch(xb.data(), lb.data(), yb.data(), 0, big), value_error);
    }

    thread_pool pool(2);
    tape<float> t2(1 << 20, &pool);
    auto y2 = g.forward(t2, t2.input<shape<3, 3, 12, 24>>(x.data()), t2.input<shape<3, 5>>(lab.data()));
    for (std::size_t i = 0; i < out.size(); ++i) REQUIRE(y2.data()[i] == doctest::Approx(y1.data()[i]).epsilon(1e-5));
    // D + backward in both tapes: parameter gradients agree
    std::vector<float> g1, g2;
    auto grads = [&](tape<float>& t, decltype(y1) y, std::vector<float>& out_g) {
        d.zero_grad();
        auto o = d.forward(t, y);
        t.backward(sum(o.src) + sum(square(o.cls)));
        d.for_each_parameter([&](std::string_view, std::span<float>, std::span<float> gr, std::span<const std::size_t>) {
            out_g.insert(out_g.end(), gr.begin(), gr.end());
        });
    };
    grads(t1, y1, g1);
    grads(t2, y2, g2);
    REQUIRE(g1.size() == g2.size());
    for (std::size_t i = 0; i < g1.size(); ++i) REQUIRE(g2[i] == doctest::Approx(g1[i]).epsilon(1e-4).scale(1e-3));
}

TEST_CASE("stargan: the frozen generator's label maps are the first layer's label channels, any label")
{
    // frozen_generator convolves the image's 3 channels and adds, per label channel k, the 7x7 convolution of a
    // plane of ones with the weights of input channel 3 + k (zero padding 3). Checked against a direct sum over
    // the taps that land inside the image, and end to end against generator::infer (which convolves the tiled
    // label) with one-hot, blended, all-zero and negative labels.
    using cfg = with_batch<hand_embedded, 1>;
    constexpr std::size_t H = 12, W = 24, C = 5, cd = 32, in = 3 + C;
    generator<float, cfg> g;
    randomise(g, 7, 0.1);
    const auto f = g.freeze();
    const float* w = nullptr;
    g.for_each_parameter([&](std::string_view name, std::span<float> v, std::span<float>, std::span<const std::size_t>) {
        if (name == "main.0.weight") w = v.data();
    });
    REQUIRE(w != nullptr);
    const auto maps = f.label_maps();
    REQUIRE(maps.size() == C * cd * H * W);
    double worst = 0;
    for (std::size_t k = 0; k < C; ++k)
        for (std::size_t o = 0; o < cd; ++o)
            for (std::size_t i = 0; i < H; ++i)
                for (std::size_t j = 0; j < W; ++j) {
                    double want = 0;
                    for (std::size_t u = 0; u < 7; ++u)
                        for (std::size_t v = 0; v < 7; ++v) {
                            const long r = long(i + u) - 3, c = long(j + v) - 3;
                            if (r >= 0 && r < long(H) && c >= 0 && c < long(W)) want += w[((o * in + 3 + k) * 7 + u) * 7 + v];
                        }
                    worst = std::max(worst, std::abs(want - double(maps[((k * cd + o) * H + i) * W + j])));
                }
    CHECK(worst < 1e-5);
    std::mt19937 rng(9);
    std::uniform_real_distribution<float> u(-1, 1);
    std::vector<float> x(3 * H * W), y_infer(x.size()), y_frozen(x.size());
    for (auto& v : x) v = u(rng);
    decltype(g)::workspace ws;
    frozen_generator<float, cfg>::workspace fws(f);
    const std::vector<std::vector<float>> labels{{0, 0, 1, 0, 0}, {0.3f, 0, 0, 0.7f, 0}, {0, 0, 0, 0, 0}, {-0.5f, 1, 0, 0, 0.25f}};
    for (const auto& lab : labels) {
        g.infer(x.data(), lab.data(), y_infer.data(), ws);
        f.infer(x.data(), lab.data(), y_frozen.data(), fws);
        float d = 0;
        for (std::size_t i = 0; i < x.size(); ++i) d = std::max(d, std::abs(y_infer[i] - y_frozen[i]));
        CAPTURE(lab[0]);
        CHECK(d < 2e-5f);  // two float sum orders (the frozen one by kernel row), each within about 1e-5 of the exact G
    }
}

TEST_CASE("stargan: FLOPs of G and of a training step equal a hand count of the tiny net")
{
    // Multiply-adds per image of each convolution, by hand (H x W = 4 x 8, 3 domains, conv_dim 2, 1 block):
    // G: conv7 (3 + 3 -> 2, 32 pixels, 49 taps) 2*32*6*49 = 18816; down1 (2 -> 4, 8 px, 16) 4*8*2*16 = 1024;
    //    down2 (4 -> 8, 2 px) 8*2*4*16 = 1024; two residual conv3 (8 -> 8, 2 px, 9) 8*2*8*9 = 1152 each;
    //    up1 (8 -> 4 at 2 x 4: the adjoint of 4 -> 8 at 1 x 2) 1024; up2 (4 -> 2 at 4 x 8) 1024;
    //    conv7 (2 -> 3, 32 px) 3*32*2*49 = 9408.                                        G = 34624
    // D (2 stride-2 layers): 3 -> 2 at 2 x 4: 2*8*3*16 = 768; 2 -> 4 at 1 x 2: 4*2*2*16 = 256;
    //    src head conv3 4 -> 1 at 1 x 2: 72; cls head 4 -> 3 with a 1 x 2 kernel: 24.    D = 1120
    constexpr double G = 34624, G0 = 18816, D = 1120, D0 = 768, src = 72, cls = 24, images = 2, per_flop = 2;
    CHECK(generator_flops<tiny>() == G * images * per_flop);
    // the frozen G convolves the 3 image channels only (the label's 3 channels come from precomputed maps):
    // conv7 3 -> 2 at 32 pixels 2*32*3*49 = 9408 instead of 18816
    CHECK(frozen_generator_flops<tiny>() == (G - G0 + 9408) * images * per_flop);
    // D step: D(x) forward, weights, inputs but the first layer's;  G(x, c) forward;
    //         D(fake) forward, weights and inputs without the cls head, no input gradient of the first layer;
    //         D(x_hat) forward; its penalty: d sum(src) / d x_hat (no cls head) and the backward of that graph
    // G step: G(x, c_trg) forward, weights, inputs but the first layer's; D(fake) forward and inputs (no weights);
    //         G(fake, c_org) forward, weights, inputs
    const double forward = D + G + D + D + G + D + G;
    const double data = (D - D0) + (D - cls - D0) + (G - G0) + D + G;
    const double weight = D + (D - cls) + G + G;
    const double penalty = (D - cls) + (D - cls) + (D - cls - src);
    CHECK(forward == 108352);
    CHECK(forward + data + weight + penalty == 235264);
    const auto c = train_step_flops<tiny>();
    CHECK(c.forward == forward * images * per_flop);
    CHECK(c.backward_data == data * images * per_flop);
    CHECK(c.backward_weight == weight * images * per_flop);
    CHECK(c.penalty == penalty * images * per_flop);
    CHECK(c.total() == 235264 * images * per_flop);
    // the identity term adds a G with weight gradients and every input gradient but its first layer's
    CHECK(train_step_flops<tiny>(true).total() == (235264 + G + G + (G - G0)) * images * per_flop);
    // a larger batch scales every count
    CHECK(train_step_flops<with_batch<tiny, 8>>().total() == c.total() * 4);
}

TEST_CASE("stargan: gradient check of a residual block (conv3 IN ReLU conv3 IN + skip)")
{
    std::mt19937 rng(11);
    std::vector<gc_param> ps;
    for (std::size_t n : {2 * 3 * 3 * 4, 3 * 3 * 3 * 3, 3, 3, 3 * 3 * 3 * 3, 3, 3}) ps.push_back(random_param(n, rng));
    gradcheck(ps, [&](tape<double>& t) {
        auto x = leaf<shape<2, 3, 3, 4>>(t, ps, 0);
        auto a = relu(instance_norm(conv2d<1, 1>(x, leaf<shape<3, 3, 3, 3>>(t, ps, 1)), leaf<shape<3>>(t, ps, 2),
                                    leaf<shape<3>>(t, ps, 3)));
        auto b = instance_norm(conv2d<1, 1>(a, leaf<shape<3, 3, 3, 3>>(t, ps, 4)), leaf<shape<3>>(t, ps, 5),
                               leaf<shape<3>>(t, ps, 6));
        auto y = x + b;
        return sum(square(y)).id;
    });
}

TEST_CASE("stargan: gradient check of a small generator, discriminator and WGAN-GP penalty")
{
    generator<double, tiny> g;
    discriminator<double, tiny> d;
    randomise(g, 21);
    randomise(d, 22);
    using gen = generator<double, tiny>;
    using dis = discriminator<double, tiny>;
    std::mt19937 rng(23);
    auto xp = random_param(gen::image_shape::size, rng);
    const std::vector<double> lab = {0, 1, 0, 0, 0, 1};
    const int cls_lab[2] = {2, 0};

    SUBCASE("generator (all parameters and the input)")
    {
        auto ps = model_params(g);
        ps.push_back(xp);
        gradcheck(ps, [&](tape<double>& t) {
            load_params(g, ps);
            auto x = leaf<gen::image_shape>(t, ps, ps.size() - 1);
            auto y = g.forward(t, x, t.input<gen::label_shape>(lab.data()));
            return sum(square(y - x)).id;
        }, 1e-6, 1e-9, 12, 1e-5, [&] { store_grads(g, ps); });
    }
    SUBCASE("discriminator (both heads)")
    {
        auto ps = model_params(d);
        ps.push_back(xp);
        gradcheck(ps, [&](tape<double>& t) {
            load_params(d, ps);
            auto o = d.forward(t, leaf<dis::image_shape>(t, ps, ps.size() - 1));
            return (mean(o.src) + cross_entropy(o.cls, std::span<const int, 2>(cls_lab))).id;
        }, 1e-6, 1e-9, 60, 1e-5, [&] { store_grads(d, ps); });
    }
    SUBCASE("gradient penalty through D: mean((||grad_x sum D_src(x)||_2 - 1)^2)")
    {
        auto ps = model_params(d);
        gradcheck(ps, [&](tape<double>& t) {
            load_params(d, ps);
            auto x = t.input<dis::image_shape>(xp.value.data(), true);
            auto o = d.forward(t, x);
            auto gx = t.grad(sum(o.src), x);
            auto cls = cross_entropy(o.cls, std::span<const int, 2>(cls_lab));
            return (10.0 * mean(square(l2_norm_per_sample(gx) - 1.0)) + cls).id;
        }, 1e-6, 1e-9, 60, 1e-5, [&] { store_grads(d, ps); });
    }
}

TEST_CASE("stargan: the frozen generator with Winograd residual convolutions: the direct one's output, a batch's bits")
{
    // conv_algorithm::winograd replaces the residual blocks' 3x3 convolutions (3 x 6 pixels at 4 conv_dim channels)
    // by kernels::winograd_conv3x3: the same G up to the sums' rounding, and infer_batch still gives each image the
    // bits of infer() on it alone. On a target without SIMD (where winograd_conv3x3 takes no geometry) it is direct.
    using cfg = with_batch<hand_embedded, 1>;
    constexpr std::size_t per = 3 * 12 * 24, C = 5, B = 6;
    generator<float, cfg> g;
    randomise(g, 11, 0.1);
    const auto direct = g.freeze(), wino = g.freeze(kernels::weight_storage::native, kernels::conv_algorithm::winograd);
    CHECK(direct.algorithm() == kernels::conv_algorithm::direct);
    CHECK(direct.winograd_convolutions().empty());
    if (!kernels::detail::has_simd) {
        CHECK(wino.algorithm() == kernels::conv_algorithm::direct);
        return;
    }
    REQUIRE(wino.algorithm() == kernels::conv_algorithm::winograd);
    CHECK(wino.winograd_convolutions().size() == 2 * hand_embedded::res_blocks);
    CHECK(wino.convolutions().size() == direct.convolutions().size() - 2 * hand_embedded::res_blocks);
    CHECK(wino.weight_bytes() > direct.weight_bytes());
    std::mt19937 rng(4);
    std::uniform_real_distribution<float> u(-1, 1);
    std::vector<float> x(B * per), lab(B * C, 0.f), yd(x.size()), yw(x.size()), y1(per);
    for (auto& v : x) v = u(rng);
    for (std::size_t n = 0; n < B; ++n) lab[n * C + (n * 2) % C] = 1;
    frozen_generator<float, cfg>::workspace wd(direct, B), ww(wino, B), one(wino);
    direct.infer_batch(x.data(), lab.data(), yd.data(), B, wd);
    wino.infer_batch(x.data(), lab.data(), yw.data(), B, ww);
    // against the same G in double precision: Winograd's error at most twice the direct kernels'
    generator<double, cfg> gd;
    {
        std::vector<std::vector<float>> values;
        g.for_each_parameter([&](std::string_view, std::span<float> v, std::span<float>, std::span<const std::size_t>) {
            values.emplace_back(v.begin(), v.end());
        });
        std::size_t k = 0;
        gd.for_each_parameter([&](std::string_view, std::span<double> v, std::span<double>, std::span<const std::size_t>) {
            std::copy(values[k].begin(), values[k].end(), v.begin());
            ++k;
        });
    }
    std::vector<double> xd(x.begin(), x.end()), ld(lab.begin(), lab.end()), truth(x.size());
    decltype(gd)::workspace gws;
    for (std::size_t n = 0; n < B; ++n) gd.infer(xd.data() + n * per, ld.data() + n * C, truth.data() + n * per, gws);
    double err_direct = 0, err_wino = 0, apart = 0;
    for (std::size_t i = 0; i < x.size(); ++i) {
        err_direct = std::max(err_direct, std::abs(double(yd[i]) - truth[i]));
        err_wino = std::max(err_wino, std::abs(double(yw[i]) - truth[i]));
        apart = std::max(apart, double(std::abs(yd[i] - yw[i])));
    }
    CAPTURE(err_direct);
    CAPTURE(err_wino);
    CHECK(apart > 0);  // another order of the sums
    CHECK(err_wino <= 2 * err_direct);
    CHECK(err_wino < 2e-5);
    for (std::size_t n = 0; n < B; ++n) {
        wino.infer(x.data() + n * per, lab.data() + n * C, y1.data(), one);
        CAPTURE(n);
        CHECK(std::equal(y1.begin(), y1.end(), yw.begin() + std::ptrdiff_t(n * per)));
    }
}
