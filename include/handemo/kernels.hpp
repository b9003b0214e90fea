// Kernels module: the convolution kernels of the StarGAN (Chan et al. 2020, Sec. 3.3) in a fast xsimd
// version and a plain-loop reference version. The thread pool that spreads work over cores is in core/
// (<handemo/core/thread_pool.hpp>).
#pragma once

#include <handemo/core/thread_pool.hpp>
#include <handemo/kernels/activation.hpp>
#include <handemo/kernels/conv.hpp>
