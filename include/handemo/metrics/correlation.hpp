// Rank correlation: Spearman's rho of two samples, the Pearson correlation of their ranks (ties take the mean of
// the ranks they span), for "does the output move with the target" where only the order is meaningful (the
// continuous control's analysed valence and arousal against the targets, eval/continuous.hpp).
#pragma once

#include <handemo/core/error.hpp>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <string>
#include <vector>

namespace handemo::metrics {

/// @brief The ranks of `x` (1 = smallest), ties given the mean of the ranks they span.
inline std::vector<double> ranks(const std::vector<double>& x)
{
    std::vector<std::size_t> order(x.size());
    std::iota(order.begin(), order.end(), std::size_t{0});
    std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return x[a] < x[b]; });
    std::vector<double> r(x.size());
    for (std::size_t i = 0; i < order.size();) {
        std::size_t j = i;
        while (j + 1 < order.size() && x[order[j + 1]] == x[order[i]]) ++j;
        const double mean_rank = 0.5 * static_cast<double>(i + j) + 1.0;
        for (std::size_t k = i; k <= j; ++k) r[order[k]] = mean_rank;
        i = j + 1;
    }
    return r;
}

/// @brief Spearman's rank correlation of `x` and `y` (pairs with a non-finite value left out): NaN when fewer
/// than 3 pairs remain or one side is constant.
/// @throws value_error when the samples differ in length.
inline double spearman(const std::vector<double>& x, const std::vector<double>& y)
{
    if (x.size() != y.size())
        throw value_error("spearman: " + std::to_string(x.size()) + " and " + std::to_string(y.size()) + " values (expected pairs)");
    std::vector<double> a, b;
    for (std::size_t i = 0; i < x.size(); ++i)
        if (std::isfinite(x[i]) && std::isfinite(y[i])) a.push_back(x[i]), b.push_back(y[i]);
    if (a.size() < 3) return std::nan("");
    const auto ra = ranks(a), rb = ranks(b);
    const double n = static_cast<double>(ra.size()), mean = (n + 1) / 2;
    double sab = 0, saa = 0, sbb = 0;
    for (std::size_t i = 0; i < ra.size(); ++i) {
        sab += (ra[i] - mean) * (rb[i] - mean);
        saa += (ra[i] - mean) * (ra[i] - mean);
        sbb += (rb[i] - mean) * (rb[i] - mean);
    }
    if (saa == 0 || sbb == 0) return std::nan("");
    return sab / std::sqrt(saa * sbb);
}

}  // namespace handemo::metrics
