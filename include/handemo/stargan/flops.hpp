// Floating-point operations of the StarGAN generator's inference and of one training step (the hand paper's
// Sec. 3.3 networks, StarGAN's losses with the WGAN-GP penalty), counted from the layer shapes: the roofline
// that bench/compare.sh sets against the machine's FMA peak. A convolution of m multiply-adds costs 2m
// FLOPs per pass; a pass is its forward, its backward-data (the gradient of its input, only where something
// before it needs one), its backward-weight (the gradient of its weights, only where they train), and, for
// the penalty's double backward, the two derivatives of a backward-data node (its incoming gradient: a
// forward convolution; its weights: a backward-weight). InstanceNorm, the activations, the label tiling, the
// losses and Adam are element-wise (a few operations per activation or parameter, against a convolution's
// channels x taps per output) and are not counted, as a roofline of FMAs does not count them.
#pragma once

#include <handemo/stargan/model.hpp>

#include <cstddef>

namespace handemo::stargan {

/// @brief Multiply-adds of one forward pass of each convolution of G and D (batch Config::batch).
template <stargan_config Config>
struct layer_macs {
    using g_type = generator<float, Config>;
    using dims_type = dims<Config>;
    /// G's first (conv7 on image + tiled label) and all of its convolutions
    static double g_first() noexcept { return g_type::geometries()[0].macs(); }
    static double g_all() noexcept { return g_type::forward_macs(); }
    /// D's first stride-2 convolution (on the image), its src head (conv3 -> 1 channel), its cls head
    /// (a kernel as large as the last map -> C logits), and all of them
    static double d_first() noexcept { return d_layer(0); }
    static double d_src() noexcept
    {
        return double(dims_type::N) * dims_type::Hd * dims_type::Wd * dims_type::Cd * 9;
    }
    static double d_cls() noexcept
    {
        return double(dims_type::N) * dims_type::C * dims_type::Cd * dims_type::Hd * dims_type::Wd;
    }
    static double d_all() noexcept
    {
        double m = d_src() + d_cls();
        for (std::size_t i = 0; i < dims_type::rep; ++i) m += d_layer(i);
        return m;
    }
    /// D's stride-2 4x4 convolution i (0: on the image)
    static double d_layer(std::size_t i) noexcept
    {
        return double(dims_type::N) * dims_type::d_ch(i + 1) * dims_type::d_h(i + 1) * dims_type::d_w(i + 1) *
               dims_type::d_ch(i) * 16;
    }
};

/// @brief FLOPs of G(x, c) on a batch of Config::batch images: 2 x its convolutions' multiply-adds.
template <stargan_config Config>
double generator_flops() noexcept
{
    return 2 * layer_macs<Config>::g_all();
}

/// @brief FLOPs frozen_generator performs for G(x, c) on a batch of Config::batch images: generator_flops()
/// without the first convolution's multiply-adds on the C tiled label channels, which it adds as maps
/// computed once (frozen_generator::label_maps(); the add is element-wise and not counted).
template <stargan_config Config>
double frozen_generator_flops() noexcept
{
    constexpr double C = double(Config::domains);
    return 2 * (layer_macs<Config>::g_all() - layer_macs<Config>::g_first() * C / (3 + C));
}

/// @brief FLOPs of one trainer::train_step() of batch Config::batch (n_critic 1), by kind of pass.
struct train_step_flops_count {
    double forward = 0;          ///< 3 G and 4 D forward passes
    double backward_data = 0;    ///< input gradients of the D and G steps
    double backward_weight = 0;  ///< weight gradients of the D and G steps
    double penalty = 0;          ///< WGAN-GP: the gradient of D's src head at x_hat and the backward through it
    double total() const noexcept { return forward + backward_data + backward_weight + penalty; }
};

/// @brief FLOPs of one training step, counted pass by pass from the layer shapes (see the file's comment).
/// D step: D(x) (src and cls heads in the loss: every weight gradient, the input gradient of every layer
/// but the first), G(x, c_trg) forward only (G does not train in it), D(fake) (src head only: no gradient
/// through the cls head, none into the first layer's input), D(x_hat) forward, then the penalty: the
/// gradient of sum(src) with respect to x_hat (backward-data of the src head and of every stride-2 layer,
/// the first included) recorded as a graph, and its backward (the weight gradient of each of those nodes,
/// and the gradient of their incoming gradient except at the src head, whose incoming gradient is the
/// constant 1). G step: f = G(x, c_trg) (weight gradients, input gradients but the first layer's), D(f)
/// (input gradients through both heads, no weight gradients: D does not train in it), G(f, c_org) (weight
/// and input gradients of every layer). identity: the optional identity term G(x, c_org)
/// (train_options::lambda_id), one more G like the first of the G step.
template <stargan_config Config>
train_step_flops_count train_step_flops(bool identity = false) noexcept
{
    using L = layer_macs<Config>;
    const double G = L::g_all(), G0 = L::g_first(), D = L::d_all(), D0 = L::d_first(), src = L::d_src(),
                 cls = L::d_cls();
    train_step_flops_count c;
    c.forward = 3 * G + 4 * D;
    c.backward_data = (D - D0) + (D - cls - D0) + D + (G - G0) + G;
    c.backward_weight = D + (D - cls) + 2 * G;
    c.penalty = (D - cls) + (D - cls) + (D - cls - src);
    if (identity) {
        c.forward += G;
        c.backward_data += G - G0;
        c.backward_weight += G;
    }
    c.forward *= 2, c.backward_data *= 2, c.backward_weight *= 2, c.penalty *= 2;
    return c;
}

}  // namespace handemo::stargan
