// Evaluation module: numeric comparison of transferred and captured motion (the hand paper's Section 5
// future work): metrics, baselines and the leave-one-content-out protocol.
#pragma once

#include <handemo/eval/metrics.hpp>
