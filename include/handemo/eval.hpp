// Evaluation module: numeric comparison of transferred and captured motion (the hand paper's Section 5
// future work): metrics, an independent emotion classifier, baselines, the leave-one-content-out protocol
// and its report.
#pragma once

#include <handemo/eval/metrics.hpp>
#include <handemo/eval/classifier.hpp>
#include <handemo/eval/baselines.hpp>
#include <handemo/eval/report.hpp>
#include <handemo/eval/protocol.hpp>
