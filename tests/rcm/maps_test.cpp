// PCA against a known decomposition, RBF maps (Eq. 1-4): exact at the centres, linear precision,
// singular systems as clear errors.
#include <handemo/rcm.hpp>

#include <doctest/doctest.h>

#include <cmath>
#include <limits>
#include <stdexcept>

using namespace handemo;
using doctest::Approx;

TEST_CASE("pca: recovers a known orthonormal basis and variances, keeps 95%")
{
    // an orthonormal basis (rotation by 30 degrees about z, then 45 about x)
    const double c = std::cos(M_PI / 6), s = std::sin(M_PI / 6), c2 = std::cos(M_PI / 4), s2 = std::sin(M_PI / 4);
    const double v[3][3] = {{c, s * c2, s * s2}, {-s, c * c2, c * s2}, {0, -s2, c2}};
    // the 8 sign combinations of scores (+-3, +-2, +-0.1): covariance diag(9, 4, 0.01) in that basis
    rcm::matrix x = xt::zeros<double>({std::size_t{8}, std::size_t{3}});
    const double sd[3] = {3, 2, 0.1};
    for (std::size_t i = 0; i < 8; ++i)
        for (std::size_t k = 0; k < 3; ++k) {
            const double score = ((i >> k) & 1 ? 1.0 : -1.0) * sd[k];
            for (std::size_t d = 0; d < 3; ++d) x(i, d) += score * v[k][d] + (d == 0 && k == 0 ? 5.0 : 0.0);
        }
    const auto p = rcm::fit_pca(x, 0.95);
    REQUIRE(p.dims() == 2);  // 13 / 13.01 of the variance
    CHECK(p.variances(0) == Approx(9.0));
    CHECK(p.variances(1) == Approx(4.0));
    CHECK(p.total_variance == Approx(13.01));
    CHECK(p.mean(0) == Approx(5.0));
    for (std::size_t k = 0; k < 2; ++k) {
        double dot = 0;
        for (std::size_t d = 0; d < 3; ++d) dot += p.components(k, d) * v[k][d];
        CHECK(std::abs(dot) == Approx(1.0));
    }
    const rcm::vector y = p.project(xt::view(x, 0, xt::all()));
    CHECK(std::abs(y(0)) == Approx(3.0));
    CHECK(std::abs(y(1)) == Approx(2.0));
    CHECK(rcm::fit_pca(x, 1.0).dims() == 3);
    CHECK(rcm::fit_pca(x, 0.5).dims() == 1);
    CHECK_THROWS_WITH_AS(rcm::fit_pca(xt::ones<double>({std::size_t{4}, std::size_t{3}})), doctest::Contains("no variance"), value_error);
    // values LAPACK cannot take are refused before it runs (its failure would escape as std::runtime_error),
    // naming the row and column
    rcm::matrix bad = x;
    bad(5, 2) = std::numeric_limits<double>::quiet_NaN();
    CHECK_THROWS_WITH_AS(rcm::fit_pca(bad), doctest::Contains("rcm::fit_pca: row 5 column 2 is nan"), value_error);
    bad(5, 2) = -std::numeric_limits<double>::infinity();
    CHECK_THROWS_WITH_AS(rcm::fit_pca(bad), doctest::Contains("row 5 column 2 is -inf"), value_error);
    bad(5, 2) = 1e300;  // finite, but its square is not
    CHECK_THROWS_WITH_AS(rcm::fit_pca(bad), doctest::Contains("covariance overflows"), value_error);
    // and a LAPACK failure that still happens comes back as value_error naming the function
    CHECK_THROWS_WITH_AS(rcm::detail::lapack("rcm::f", []() -> int { throw std::runtime_error("did not converge"); }),
                         doctest::Contains("rcm::f: LAPACK failed: did not converge"), value_error);
    CHECK_THROWS_WITH_AS(rcm::detail::lapack("rcm::f", []() -> int { throw shape_error("kept"); }), doctest::Contains("kept"), shape_error);
}

TEST_CASE("rbf: interpolation is exact at the centres for both kernels")
{
    rcm::matrix c = {{-0.6, 0.3}, {0.87, 0.26}, {-0.72, -0.38}, {0.12, -0.39}, {0.5, 0.14}, {-0.18, -0.33}};
    rcm::matrix y = {{0.1, 2}, {0.9, -1}, {0.3, 0.5}, {0.4, 4}, {0.8, 0}, {0.2, 1}};
    for (auto k : {rcm::rbf_kernel::gaussian, rcm::rbf_kernel::multiquadric}) {
        const auto m = rcm::fit_rbf_interpolant(c, y, k, rcm::mean_pairwise_distance(c));
        for (std::size_t i = 0; i < c.shape()[0]; ++i) {
            const rcm::vector out = m(xt::view(c, i, xt::all()));
            CHECK(out(0) == Approx(y(i, 0)));
            CHECK(out(1) == Approx(y(i, 1)));
        }
        // the side conditions: sum lambda = 0
        double sum = 0;
        for (std::size_t i = 0; i < c.shape()[0]; ++i) sum += m.lambda(i, 0);
        CHECK(sum == Approx(0.0).epsilon(1e-9));
    }
}

TEST_CASE("rbf: a linear function is reproduced everywhere (the linear term of Eq. 1 and 3)")
{
    rcm::matrix c = {{0, 0}, {1, 0}, {0, 1}, {1, 1}, {0.5, 0.2}};
    rcm::matrix y = xt::zeros<double>({std::size_t{5}, std::size_t{1}});
    for (std::size_t i = 0; i < 5; ++i) y(i, 0) = 2 + 3 * c(i, 0) - c(i, 1);
    const auto m = rcm::fit_rbf_interpolant(c, y, rcm::rbf_kernel::multiquadric, 0.7);
    CHECK(m(rcm::vector{0.3, -2.0})(0) == Approx(2 + 0.9 + 2.0));
    CHECK(m.linear(1, 0) == Approx(3.0));
}

TEST_CASE("rbf: Eq. 1 regression fits the linear term on all samples and passes through the centres")
{
    rcm::matrix samples = {{0, 0}, {1, 0}, {0, 1}, {1, 1}, {2, 1}, {1, 2}, {0.5, 0.5}, {2, 2}};
    rcm::matrix targets = xt::zeros<double>({std::size_t{8}, std::size_t{2}});
    for (std::size_t i = 0; i < 8; ++i) targets(i, 0) = samples(i, 0) - samples(i, 1), targets(i, 1) = 0.5 * samples(i, 0) + 0.1;
    rcm::matrix centres = {{0.2, 0.1}, {1.5, 1.5}, {0.1, 1.2}};
    rcm::matrix cv = {{0.9, -0.9}, {0.5, 0.5}, {-0.9, 0.3}};
    const auto m = rcm::fit_rbf_regression(samples, targets, centres, cv, rcm::rbf_kernel::gaussian, rcm::mean_pairwise_distance(samples));
    CHECK(m.linear(1, 0) == Approx(1.0));  // the samples are exactly linear
    CHECK(m.linear(2, 0) == Approx(-1.0));
    for (std::size_t k = 0; k < 3; ++k) {
        const rcm::vector out = m(xt::view(centres, k, xt::all()));
        CHECK(out(0) == Approx(cv(k, 0)));
        CHECK(out(1) == Approx(cv(k, 1)));
    }
}

TEST_CASE("rbf: singular systems are errors, never NaN")
{
    rcm::matrix dup = {{0, 0}, {0, 0}, {1, 1}, {1, 0}};
    rcm::matrix y = {{1}, {2}, {3}, {4}};
    CHECK_THROWS_WITH_AS(rcm::fit_rbf_interpolant(dup, y, rcm::rbf_kernel::gaussian, 1.0), doctest::Contains("singular"), value_error);
    rcm::matrix collinear = {{0, 0}, {1, 1}, {2, 2}, {3, 3}};
    CHECK_THROWS_WITH_AS(rcm::fit_rbf_interpolant(collinear, y, rcm::rbf_kernel::multiquadric, 1.0), doctest::Contains("singular"), value_error);
    rcm::matrix few = {{0, 0}, {1, 0}};
    CHECK_THROWS_WITH_AS(rcm::fit_rbf_interpolant(few, rcm::matrix{{1}, {2}}, rcm::rbf_kernel::gaussian, 1.0),
                         doctest::Contains("singular"), value_error);
    CHECK_THROWS_AS(rcm::fit_rbf_interpolant(rcm::matrix{{0, 0}, {1, 0}, {0, 1}}, rcm::matrix{{1}, {2}, {3}}, rcm::rbf_kernel::gaussian, 0.0),
                    value_error);
    // regression: duplicate samples cannot fix the linear term; duplicate centres cannot be interpolated
    rcm::matrix same = {{1, 1}, {1, 1}, {1, 1}, {1, 1}};
    rcm::matrix t = xt::zeros<double>({std::size_t{4}, std::size_t{2}});
    rcm::matrix cs = {{0, 0}, {1, 0}};
    rcm::matrix cvs = {{0, 0}, {1, 1}};
    CHECK_THROWS_WITH_AS(rcm::fit_rbf_regression(same, t, cs, cvs, rcm::rbf_kernel::gaussian, 1.0), doctest::Contains("singular"), value_error);
    rcm::matrix ok = {{0, 0}, {1, 0}, {0, 1}, {1, 1}};
    rcm::matrix cdup = {{0.5, 0.5}, {0.5, 0.5}};
    CHECK_THROWS_WITH_AS(rcm::fit_rbf_regression(ok, t, cdup, cvs, rcm::rbf_kernel::gaussian, 1.0), doctest::Contains("coincide"), value_error);
    CHECK_THROWS_AS(rcm::mean_pairwise_distance(rcm::matrix{{1, 1}}), value_error);
}
