// Micro module: inference of a trained StarGAN generator (Chan et al. 2020, Sec. 3.3) on targets without
// exceptions, heap or RTTI (a glove's Cortex-M7). Needs only kernels/reference.hpp; the model's weights come
// from a header written by `handemo export --header` (stargan/export.hpp).
#pragma once

#include <handemo/micro/generator.hpp>
