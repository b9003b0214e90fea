// Evaluation module: numeric comparison of transferred and captured motion (the hand paper's Section 5
// future work): the leave-one-content-out protocol and its report, on the metrics, classifier and baselines of
// handemo/metrics.hpp.
#pragma once

#include <handemo/metrics.hpp>
#include <handemo/eval/report.hpp>
#include <handemo/eval/protocol.hpp>
