// nn module: the neural-network utilities around the StarGAN of Sec. 3.3 of the hand paper — a
// portable seeded RNG, PyTorch's default initialisation, Adam with a learning-rate schedule, and
// safetensors I/O for weights, optimiser state and golden fixtures.
#pragma once

#include <handemo/nn/parameters.hpp>
#include <handemo/nn/rng.hpp>
#include <handemo/nn/init.hpp>
#include <handemo/nn/adam.hpp>
#include <handemo/nn/tensor_file.hpp>
#include <handemo/nn/safetensors.hpp>
