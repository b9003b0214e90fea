// The StarGAN golden comparison, written once for both element types (golden_stargan_f32_test.cpp,
// golden_stargan_f64_test.cpp): handemo's generator and discriminator (handemo/stargan/model.hpp) against
// a tiny PyTorch StarGAN with the same layout, computed in float64 (tests/fixtures/stargan_tiny.safetensors
// from scripts/make_golden.py): weights loaded by PyTorch name, forward outputs, the losses, and the
// parameter gradients of L_D (adversarial + classification + WGAN-GP), of the gradient penalty alone
// (double backward; create_graph=True in PyTorch) and of L_G (adversarial + reconstruction + classification).
#pragma once

#include "fixture.hpp"

#include <doctest/doctest.h>
#include <handemo/nn/tensor_file.hpp>
#include <handemo/stargan/model.hpp>

#include <array>
#include <string>
#include <vector>

namespace handemo::test::golden {

using namespace handemo::autodiff;

/// Matches the fixture: H 12 (9 keyframes padded), W 24 (23 joints padded), 5 domains, conv_dim 4,
/// 1 residual block, D with 3 stride-2 layers, batch 2.
struct tiny_config {
    static constexpr std::size_t joints = 23, keyframes = 9, domains = 5, conv_dim = 4, res_blocks = 1,
                                 d_repeat = 3, batch = 2;
};
constexpr std::size_t B = 2;

inline const safetensors_file& fx() { return fixture("stargan_tiny.safetensors"); }

inline std::array<int, B> labels(const std::string& name)
{
    const auto v = fx().get<std::int64_t>(name);
    REQUIRE(v.size() == B);
    return {static_cast<int>(v[0]), static_cast<int>(v[1])};
}

inline double loss(const std::string& name) { return fx().get<double>(name).at(0); }

/// Tolerances: `rtol` relative to max(|want|, floor_frac * max|want|) per element.
struct tolerance {
    double rtol, floor_frac;
};

template <class T>
struct suite {
    using gen_t = stargan::generator<T, tiny_config>;
    using disc_t = stargan::discriminator<T, tiny_config>;
    using image = typename gen_t::image_shape;
    using label = typename gen_t::label_shape;
    using src = typename disc_t::src_shape;
    using cls = typename disc_t::cls_shape;

    template <class S>
    static std::vector<T> get(const std::string& name)
    {
        return fx().get<T>(name, std::vector<std::size_t>(S::dims.begin(), S::dims.end()));
    }
    template <class S>
    static std::vector<double> ref(const std::string& name)
    {
        return fx().get<double>(name, std::vector<std::size_t>(S::dims.begin(), S::dims.end()));
    }
    template <class Got>
    static void close(const std::string& what, const Got& got, const std::vector<double>& want, tolerance tol)
    {
        check_close(what, got, want, tol.rtol, tol.floor_frac);
    }
    static void close_loss(const std::string& what, T got, tolerance tol)
    {
        INFO(what);
        CHECK(static_cast<double>(got) == doctest::Approx(loss(what)).epsilon(tol.rtol));
    }
    template <class M>
    static void check_grads(M& model, const std::string& prefix, tolerance tol)
    {
        model.for_each_parameter([&](std::string_view name, std::span<T>, std::span<T> grad,
                                     std::span<const std::size_t>) {
            check_close(prefix + std::string(name), grad, fx().get<double>(prefix + std::string(name)), tol.rtol,
                        tol.floor_frac);
        });
    }

    struct nets {
        gen_t g;
        disc_t d;
        nets()
        {
            load_parameters(fx(), g, "G.");
            load_parameters(fx(), d, "D.");
        }
    };

    static std::vector<T> interpolate(const std::vector<T>& x, const T* fake)
    {
        const auto alpha = fx().get<T>("input.alpha");
        std::vector<T> xh(x.size());
        const std::size_t per = x.size() / B;
        for (std::size_t i = 0; i < x.size(); ++i)
            xh[i] = alpha[i / per] * x[i] + (T(1) - alpha[i / per]) * fake[i];
        return xh;
    }

    static void forward(tolerance tol)
    {
        nets n;
        tape<T> t;
        const auto xv = get<image>("input.x");
        auto x = t.template input<image>(xv.data());
        const auto cv = get<label>("input.c_trg");
        auto c_trg = t.template input<label>(cv.data());
        auto real = n.d.forward(t, x);
        close("out.d_src_real", real.src.value(), ref<src>("out.d_src_real"), tol);
        close("out.d_cls_real", real.cls.value(), ref<cls>("out.d_cls_real"), tol);
        auto fake = n.g.forward(t, x, c_trg);
        close("out.g_fake", fake.value(), ref<image>("out.g_fake"), tol);
        // the tape-free inference path gives the same image
        typename gen_t::workspace ws;
        std::vector<T> out(image::size);
        n.g.infer(xv.data(), cv.data(), out.data(), ws);
        close("infer", out, ref<image>("out.g_fake"), tol);
        // and so does the frozen generator (weights packed for the weight-stationary kernels)
        const auto frozen = n.g.freeze();
        typename stargan::frozen_generator<T, tiny_config>::workspace fws(frozen);
        std::fill(out.begin(), out.end(), T(9));
        frozen.infer(xv.data(), cv.data(), out.data(), fws);
        close("frozen infer", out, ref<image>("out.g_fake"), tol);
    }

    static void gradient_penalty(tolerance tol)
    {
        nets n;
        tape<T> t;
        const auto xv = get<image>("input.x");
        const auto fake = get<image>("out.g_fake");
        const auto xh = interpolate(xv, fake.data());
        auto xhat = t.template input<image>(xh.data(), true);
        auto o = n.d.forward(t, xhat);
        auto gr = t.grad(sum(o.src), xhat);
        close("out.gp_grad_x", gr.value(), ref<image>("out.gp_grad_x"), tol);
        auto gp = mean(square(l2_norm_per_sample(gr) - T(1)));
        close_loss("loss.d_gp", gp.item(), tol);
        n.d.zero_grad();
        t.backward(gp);
        check_grads(n.d, "grad_gp.", tol);
    }

    static void loss_d(tolerance tol)
    {
        nets n;
        tape<T> t;
        n.g.set_requires_grad(false);  // fake.detach()
        const auto xv = get<image>("input.x");
        auto x = t.template input<image>(xv.data());
        auto c_trg = t.template input<label>(get<label>("input.c_trg").data());
        const auto lab = labels("input.label_org");
        auto real = n.d.forward(t, x);
        auto fake = n.g.forward(t, x, c_trg);
        auto f = n.d.forward(t, fake);
        const auto xh = interpolate(xv, fake.data());
        auto xhat = t.template input<image>(xh.data(), true);
        auto o = n.d.forward(t, xhat);
        auto gp = mean(square(l2_norm_per_sample(t.grad(sum(o.src), xhat)) - T(1)));
        auto d_real = -mean(real.src);
        auto d_fake = mean(f.src);
        auto d_cls = cross_entropy(real.cls, std::span<const int, B>(lab));
        auto ld = d_real + d_fake + T(1) * d_cls + T(10) * gp;
        close_loss("loss.d_real", d_real.item(), tol);
        close_loss("loss.d_fake", d_fake.item(), tol);
        close_loss("loss.d_cls", d_cls.item(), tol);
        close_loss("loss.d_total", ld.item(), tol);
        close("out.d_src_fake", f.src.value(), ref<src>("out.d_src_fake"), tol);
        n.d.zero_grad();
        t.backward(ld);
        check_grads(n.d, "grad_d.", tol);
    }

    static void loss_g(tolerance tol)
    {
        nets n;
        tape<T> t;
        n.d.set_requires_grad(false);
        const auto xv = get<image>("input.x");
        auto x = t.template input<image>(xv.data());
        auto c_trg = t.template input<label>(get<label>("input.c_trg").data());
        auto c_org = t.template input<label>(get<label>("input.c_org").data());
        const auto lab = labels("input.label_trg");
        auto fake = n.g.forward(t, x, c_trg);
        auto s = n.d.forward(t, fake);
        auto rec = n.g.forward(t, fake, c_org);
        auto g_fake = -mean(s.src);
        auto g_rec = l1_loss(x, rec);
        auto g_cls = cross_entropy(s.cls, std::span<const int, B>(lab));
        auto lg = g_fake + T(10) * g_rec + T(1) * g_cls;
        close("out.g_rec", rec.value(), ref<image>("out.g_rec"), tol);
        close("out.d_cls_fake", s.cls.value(), ref<cls>("out.d_cls_fake"), tol);
        close_loss("loss.g_fake", g_fake.item(), tol);
        close_loss("loss.g_rec", g_rec.item(), tol);
        close_loss("loss.g_cls", g_cls.item(), tol);
        close_loss("loss.g_total", lg.item(), tol);
        n.g.zero_grad();
        t.backward(lg);
        check_grads(n.g, "grad_g.", tol);
    }
};

}  // namespace handemo::test::golden
