// Metrics module: how motions are measured and compared, below both the StarGAN training (its change gate scores
// settings with them) and the evaluation: keyframe RMSE and Table 1's characteristics, the independent emotion
// classifier and a second, full-rate one, and the identity, mean-offset and nearest-neighbour baselines.
#pragma once

#include <handemo/metrics/compare.hpp>
#include <handemo/metrics/classifier.hpp>
#include <handemo/metrics/full_rate_judge.hpp>
#include <handemo/metrics/baselines.hpp>
#include <handemo/metrics/correlation.hpp>
