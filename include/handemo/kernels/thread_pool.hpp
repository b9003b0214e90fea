// Forwarding header: the thread pool moved to <handemo/core/thread_pool.hpp> (handemo::thread_pool), the
// floor of every module that uses it (the autodiff tape, the StarGAN trainer, the kernels). This header
// keeps the old path and the old name handemo::kernels::thread_pool working; new code includes the core one.
#pragma once

#include <handemo/core/thread_pool.hpp>

namespace handemo::kernels {
using handemo::thread_pool;
}  // namespace handemo::kernels
