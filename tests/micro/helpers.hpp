// Deterministic generator weights for the micro and cross-architecture tests: PyTorch's default init from
// a seed (handemo::rng, portable: the same weights on x86 and aarch64) with the instance-norm affine
// parameters moved off 1/0, so every part of G shows in its output; and a micro::generator model whose
// weights are filled at run time from such a generator.
#pragma once

#include <handemo/micro.hpp>
#include <handemo/nn.hpp>
#include <handemo/stargan/model.hpp>

#include <cstdint>
#include <span>
#include <string_view>
#include <vector>

namespace handemo::test {

/// init_pytorch_default(g, seed), then rank-1 parameters (instance-norm gamma, beta) = 1 + U(-0.2, 0.2), U(-0.1, 0.1).
template <class G>
void seed_generator(G& g, std::uint64_t seed)
{
    init_pytorch_default(g, seed);
    rng r(seed + 1000);
    g.for_each_parameter([&](std::string_view name, std::span<float> v, std::span<float>, std::span<const std::size_t> shape) {
        if (shape.size() != 1) return;
        const bool gamma = name.ends_with(".weight");
        for (auto& x : v) x = float(gamma ? 1.0 + r.uniform(-0.2, 0.2) : r.uniform(-0.1, 0.1));
    });
}

/// G's parameters in state_dict order, densely packed (the layout of `handemo export --header`).
template <class G>
std::vector<float> flat_parameters(G& g)
{
    std::vector<float> flat;
    g.for_each_parameter([&](std::string_view, std::span<float> v, std::span<float>, auto) { flat.insert(flat.end(), v.begin(), v.end()); });
    return flat;
}

/// A micro::generator model of configuration Cfg whose weights are set at run time (set_weights).
template <class Cfg, bool Residual>
struct runtime_model {
    static constexpr std::size_t joints = Cfg::joints, keyframes = Cfg::keyframes, domains = Cfg::domains,
                                 conv_dim = Cfg::conv_dim, res_blocks = Cfg::res_blocks;
    static constexpr bool residual = Residual;
    using layout = micro::generator_layout<keyframes, joints, domains, conv_dim, res_blocks>;
    static inline float weights[layout::parameter_count];
    static void set_weights(const std::vector<float>& w)
    {
        for (std::size_t i = 0; i < layout::parameter_count; ++i) weights[i] = w.at(i);
    }
};

}  // namespace handemo::test
