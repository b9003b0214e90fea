// Autodiff module: the reverse-mode tape (arena reused across iterations, flat node records, reverse
// loop, graph backward for double derivatives) and the ops the StarGAN of the hand paper (Sec. 3.3)
// trains with: convolutions, instance norm, activations, reductions and losses, including the WGAN-GP
// gradient penalty that needs the gradient of a gradient.
#pragma once

#include <handemo/tensor/shape.hpp>
#include <handemo/autodiff/tape.hpp>
#include <handemo/autodiff/ops.hpp>
#include <handemo/autodiff/conv.hpp>
#include <handemo/autodiff/norm.hpp>
