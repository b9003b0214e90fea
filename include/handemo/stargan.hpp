// StarGAN emotion transfer (Sections 3.3-3.4 of the hand paper): the model, named configurations, the
// labelled dataset, training with checkpoints, and transfer of new motions.
#pragma once

#include <handemo/stargan/configs.hpp>
#include <handemo/stargan/dataset.hpp>
#include <handemo/stargan/export.hpp>
#include <handemo/stargan/flops.hpp>
#include <handemo/stargan/gate.hpp>
#include <handemo/stargan/model.hpp>
#include <handemo/stargan/train.hpp>
#include <handemo/stargan/transfer.hpp>
#include <handemo/stargan/capture.hpp>
#include <handemo/stargan/continuous.hpp>
