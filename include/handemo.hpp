// handemo: emotion transfer for 3D hand and body motion (Chan, Irimia, Ho 2020), header-only C++20.
// The umbrella header: includes every module except the optional ones with external runtime
// dependencies (handemo/image.hpp links stb through the handemo::image target).
#pragma once

#include <handemo/core/error.hpp>
#include <handemo/core/io.hpp>
#include <handemo/core/progress.hpp>
#include <handemo/motion.hpp>
#include <handemo/retarget.hpp>
#include <handemo/tensor.hpp>
#include <handemo/kernels.hpp>
#include <handemo/micro.hpp>
#include <handemo/autodiff.hpp>
#include <handemo/nn.hpp>
#include <handemo/dist.hpp>
#include <handemo/metrics.hpp>
#include <handemo/stargan.hpp>
#include <handemo/eval.hpp>
#include <handemo/render.hpp>
