// Spearman's rank correlation (metrics/correlation.hpp) against values worked by hand.
#include <handemo/metrics/correlation.hpp>

#include <doctest/doctest.h>

#include <cmath>
#include <vector>

using namespace handemo;

TEST_CASE("spearman: ranks with ties, known correlations, what is left out")
{
    CHECK(metrics::ranks({10, 30, 20, 20}) == std::vector<double>{1, 4, 2.5, 2.5});
    CHECK(metrics::spearman({1, 2, 3, 4, 5}, {2, 4, 8, 16, 32}) == doctest::Approx(1.0));   // monotone, not linear
    CHECK(metrics::spearman({1, 2, 3, 4, 5}, {5, 4, 3, 2, 1}) == doctest::Approx(-1.0));
    // a tie: ranks of y (1, 2, 3.5, 5, 3.5), rho = 8 / sqrt(10 * 9.5)
    CHECK(metrics::spearman({1, 2, 3, 4, 5}, {5, 6, 7, 8, 7}) == doctest::Approx(8 / std::sqrt(95.0)).epsilon(1e-12));
    // a non-finite pair is left out: the rest is monotone
    CHECK(metrics::spearman({1, 2, 3, 4}, {1, std::nan(""), 3, 4}) == doctest::Approx(1.0));
    CHECK(std::isnan(metrics::spearman({1, 2}, {1, 2})));
    CHECK(std::isnan(metrics::spearman({1, 2, 3}, {7, 7, 7})));
    CHECK_THROWS_AS(metrics::spearman({1, 2, 3}, {1, 2}), value_error);
}
