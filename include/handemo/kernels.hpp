// Kernels module: the convolution kernels of the StarGAN (Chan et al. 2020, Sec. 3.3) in a fast xsimd
// version and a plain-loop reference version, and the thread pool that spreads work over cores.
#pragma once

#include <handemo/kernels/conv.hpp>
#include <handemo/kernels/thread_pool.hpp>
