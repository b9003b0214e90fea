// handemo: emotion transfer for 3D hand and body motion (Chan, Irimia, Ho 2020), header-only C++20.
// The umbrella header: includes every module except the optional ones with external runtime
// dependencies (handemo/image.hpp links stb, handemo/glove.hpp links hidapi).
#pragma once

#include <handemo/core/error.hpp>
#include <handemo/core/io.hpp>
#include <handemo/core/progress.hpp>
#include <handemo/motion.hpp>
