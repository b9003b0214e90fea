// The linear algebra of the circumplex analysis (Aristidou et al. 2017, Sections 3.3-3.4): PCA of the
// selected features to the components that keep 95% of the variance, and radial basis function maps with
// a linear term, Gaussian features -> (valence, arousal) (Eq. 1, 2) and multiquadric (valence, arousal) ->
// features (Eq. 3, 4). Eigen-decompositions, SVDs and solves are LAPACK's through xtensor-blas; a singular
// or ill-conditioned system is a value_error that says why, never a NaN.
//
// Fitting. fit_rbf_interpolant() solves the classic augmented system
//   [Phi  P] [lambda]   [values]        Phi_kl = phi(|c_k - c_l|), P_k = [1, c_k],
//   [P^T  0] [w     ] = [0     ]
// so the map reproduces the values at the K centres exactly (it needs K >= d + 1 centres that are not
// affinely dependent). fit_rbf_regression() serves Eq. 1, whose paper version has more unknowns (1 + d + K)
// than centres (K emotions): it fits the linear term w_0 + w^T f by least squares on every training clip
// and then interpolates the residuals at the K emotion centres with the RBF part, so the map still passes
// exactly through each emotion's coordinates at that emotion's mean features.
#pragma once

#include <handemo/core/error.hpp>

#include <xtensor-blas/xlinalg.hpp>
#include <xtensor/xtensor.hpp>
#include <xtensor/xview.hpp>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace handemo::rcm {

using matrix = xt::xtensor<double, 2>;
using vector = xt::xtensor<double, 1>;

namespace detail {

/// Runs an xtensor-blas call, whose LAPACK failures (no convergence, a singular factor) come back as
/// std::runtime_error, and rethrows those as value_error naming `who`.
template <class F>
auto lapack(const std::string& who, F&& f) -> decltype(f())
{
    try {
        return f();
    } catch (const error&) {
        throw;
    } catch (const std::runtime_error& e) {
        throw value_error(who + ": LAPACK failed: " + e.what());
    }
}

/// Throws value_error when a matrix is singular or too ill-conditioned to solve (SVD, LAPACK gesdd).
inline void check_conditioning(const matrix& a, const std::string& who, const std::string& why)
{
    for (double v : a)
        if (!std::isfinite(v)) throw value_error(who + ": the system has a non-finite entry");
    const auto s = std::get<1>(lapack(who, [&] { return xt::linalg::svd(a, false, true); }));
    const double smax = s.size() ? s(0) : 0.0, smin = s.size() ? s(s.size() - 1) : 0.0;
    if (!(smax > 0) || smin <= 1e-11 * smax)
        throw value_error(who + ": the linear system is singular (smallest/largest singular value " + std::to_string(smin) +
                          "/" + std::to_string(smax) + "): " + why);
}

}  // namespace detail

/// @brief Mean Euclidean distance between all pairs of distinct rows of `[N, d]` (the sigma of Eq. 2, 4).
/// @throws value_error with fewer than two rows or when all rows coincide.
inline double mean_pairwise_distance(const matrix& x)
{
    const std::size_t n = x.shape()[0];
    if (n < 2) throw value_error("rcm::mean_pairwise_distance: " + std::to_string(n) + " rows, need at least 2");
    double s = 0;
    std::size_t c = 0;
    for (std::size_t i = 0; i < n; ++i)
        for (std::size_t j = i + 1; j < n; ++j, ++c) {
            double d2 = 0;
            for (std::size_t k = 0; k < x.shape()[1]; ++k) d2 += (x(i, k) - x(j, k)) * (x(i, k) - x(j, k));
            s += std::sqrt(d2);
        }
    const double m = s / static_cast<double>(c);
    if (!(m > 0)) throw value_error("rcm::mean_pairwise_distance: all rows coincide");
    return m;
}

/// @brief Principal component analysis keeping the leading components that explain a share of the variance.
struct pca_model {
    vector mean;           ///< [D]
    matrix components;     ///< [k, D] orthonormal rows, largest variance first
    vector variances;      ///< [k] variance along each component
    double total_variance = 0;

    std::size_t dims() const noexcept { return components.shape()[0]; }
    /// @brief Scores of one feature vector: components (x - mean), `[k]`.
    vector project(const vector& x) const
    {
        if (x.size() != mean.size())
            throw shape_error("rcm::pca_model::project: " + std::to_string(x.size()) + " features, expected " + std::to_string(mean.size()));
        vector y = xt::zeros<double>({dims()});
        for (std::size_t c = 0; c < dims(); ++c)
            for (std::size_t d = 0; d < mean.size(); ++d) y(c) += components(c, d) * (x(d) - mean(d));
        return y;
    }
    /// @brief project() of every row of `[N, D]`.
    matrix project_rows(const matrix& x) const
    {
        matrix y = xt::zeros<double>({x.shape()[0], dims()});
        for (std::size_t i = 0; i < x.shape()[0]; ++i) {
            const vector r = xt::view(x, i, xt::all());
            xt::view(y, i, xt::all()) = project(r);
        }
        return y;
    }
};

/// @brief Fits PCA on the rows of `[N, D]` (covariance with 1/N, LAPACK syevd via xt::linalg::eigh) and keeps
/// the fewest leading components whose variances reach `keep` of the total, at most `max_dims`.
/// Each component's sign is fixed so that its largest-magnitude entry is positive.
/// @throws value_error when there are no rows, a value is not finite, the covariance overflows or the data has no
/// variance.
inline pca_model fit_pca(const matrix& x, double keep = 0.95, std::size_t max_dims = std::numeric_limits<std::size_t>::max())
{
    const std::size_t n = x.shape()[0], D = x.shape()[1];
    if (n == 0 || D == 0) throw value_error("rcm::fit_pca: empty data (" + std::to_string(n) + " x " + std::to_string(D) + ")");
    if (!(keep > 0 && keep <= 1)) throw value_error("rcm::fit_pca: variance share " + std::to_string(keep) + " is not in (0, 1]");
    for (std::size_t i = 0; i < n; ++i)
        for (std::size_t j = 0; j < D; ++j)
            if (!std::isfinite(x(i, j)))
                throw value_error("rcm::fit_pca: row " + std::to_string(i) + " column " + std::to_string(j) + " is " + std::to_string(x(i, j)) +
                                  ", not a finite number");
    pca_model m;
    m.mean = xt::mean(x, {0});
    matrix c = x;
    for (std::size_t i = 0; i < n; ++i) xt::view(c, i, xt::all()) -= m.mean;
    const matrix cov = xt::linalg::dot(xt::transpose(c), c) / static_cast<double>(n);
    for (double v : cov)
        if (!std::isfinite(v)) throw value_error("rcm::fit_pca: the covariance overflows (values too large to square)");
    const auto [evals, evecs] = detail::lapack("rcm::fit_pca", [&] { return xt::linalg::eigh(cov); });  // ascending
    double total = 0;
    for (double v : evals) total += std::max(0.0, v);
    if (!(total > 0)) throw value_error("rcm::fit_pca: the data has no variance");
    m.total_variance = total;
    std::size_t k = 0;
    double acc = 0;
    while (k < D && k < max_dims && acc < keep * total * (1 - 1e-12)) {
        acc += std::max(0.0, evals(D - 1 - k));
        ++k;
    }
    k = std::max<std::size_t>(1, k);
    m.components = xt::zeros<double>({k, D});
    m.variances = xt::zeros<double>({k});
    for (std::size_t c2 = 0; c2 < k; ++c2) {
        const std::size_t col = D - 1 - c2;
        m.variances(c2) = std::max(0.0, evals(col));
        std::size_t arg = 0;
        for (std::size_t d = 0; d < D; ++d)
            if (std::abs(evecs(d, col)) > std::abs(evecs(arg, col))) arg = d;
        const double sign = evecs(arg, col) < 0 ? -1.0 : 1.0;
        for (std::size_t d = 0; d < D; ++d) m.components(c2, d) = sign * evecs(d, col);
    }
    return m;
}

/// @brief The radial basis of Eq. 2 (Gaussian) or Eq. 4 (multiquadric).
enum class rbf_kernel : std::uint8_t { gaussian, multiquadric };
constexpr std::string_view to_string(rbf_kernel k) noexcept { return k == rbf_kernel::gaussian ? "gaussian" : "multiquadric"; }

/// @brief phi(r): exp(-r^2 / (2 sigma^2)) (Eq. 2) or sqrt(1 + r^2 / sigma^2) (Eq. 4).
inline double rbf_phi(rbf_kernel k, double r, double sigma) noexcept
{
    const double q = r * r / (sigma * sigma);
    return k == rbf_kernel::gaussian ? std::exp(-0.5 * q) : std::sqrt(1.0 + q);
}

namespace detail {

/// The [K, K] kernel matrix phi(|c_k - c_l|) of the centres, as both fits solve with it.
inline matrix rbf_gram(const matrix& centres, rbf_kernel kernel, double sigma)
{
    const std::size_t K = centres.shape()[0], d = centres.shape()[1];
    matrix phi = xt::zeros<double>({K, K});
    for (std::size_t k = 0; k < K; ++k)
        for (std::size_t l = 0; l < K; ++l) {
            double r2 = 0;
            for (std::size_t i = 0; i < d; ++i) r2 += (centres(k, i) - centres(l, i)) * (centres(k, i) - centres(l, i));
            phi(k, l) = rbf_phi(kernel, std::sqrt(r2), sigma);
        }
    return phi;
}

/// Refuses a solve whose result is not finite (a singular system that LAPACK did not report).
inline void require_finite_solution(const matrix& sol, const std::string& who)
{
    for (double v : sol)
        if (!std::isfinite(v)) throw value_error(who + ": the solution is not finite (singular system)");
}

}  // namespace detail

/// @brief y(x) = w_0 + W^T x + sum_k lambda_k phi(|x - c_k|) for m outputs at once (Eq. 1 and 3).
struct rbf_map {
    rbf_kernel kernel = rbf_kernel::gaussian;
    double sigma = 1;
    matrix centres;  ///< [K, d]
    matrix lambda;   ///< [K, m]
    matrix linear;   ///< [d + 1, m]; row 0 is w_0

    std::size_t inputs() const noexcept { return centres.shape()[1]; }
    std::size_t outputs() const noexcept { return lambda.shape()[1]; }
    /// @brief Evaluates the map at one input `[d]`, giving `[m]`.
    vector operator()(const vector& x) const
    {
        const std::size_t d = inputs(), m = outputs(), K = centres.shape()[0];
        if (x.size() != d) throw shape_error("rcm::rbf_map: input has " + std::to_string(x.size()) + " values, expected " + std::to_string(d));
        vector y = xt::zeros<double>({m});
        for (std::size_t o = 0; o < m; ++o) {
            double v = linear(0, o);
            for (std::size_t i = 0; i < d; ++i) v += linear(i + 1, o) * x(i);
            y(o) = v;
        }
        for (std::size_t k = 0; k < K; ++k) {
            double r2 = 0;
            for (std::size_t i = 0; i < d; ++i) r2 += (x(i) - centres(k, i)) * (x(i) - centres(k, i));
            const double phi = rbf_phi(kernel, std::sqrt(r2), sigma);
            for (std::size_t o = 0; o < m; ++o) y(o) += lambda(k, o) * phi;
        }
        return y;
    }
};

/// @brief RBF interpolation with a linear term through `[K, m]` values at `[K, d]` centres (exact at the
/// centres), by the augmented system above.
/// @throws value_error when sigma is not positive, the shapes disagree, or the system is singular
/// (coincident centres, fewer than d + 1 centres, affinely dependent centres).
inline rbf_map fit_rbf_interpolant(const matrix& centres, const matrix& values, rbf_kernel kernel, double sigma)
{
    const std::size_t K = centres.shape()[0], d = centres.shape()[1], m = values.shape()[1];
    const std::string who = "rcm::fit_rbf_interpolant";
    if (!(sigma > 0) || !std::isfinite(sigma)) throw value_error(who + ": sigma " + std::to_string(sigma) + " is not positive");
    if (values.shape()[0] != K)
        throw shape_error(who + ": " + std::to_string(values.shape()[0]) + " value rows for " + std::to_string(K) + " centres");
    if (K < d + 1)
        throw value_error(who + ": " + std::to_string(K) + " centres cannot fix a linear term in " + std::to_string(d) +
                          " dimensions (need at least " + std::to_string(d + 1) + "): the system is singular");
    const std::size_t n = K + d + 1;
    matrix a = xt::zeros<double>({n, n});
    matrix b = xt::zeros<double>({n, m});
    xt::view(a, xt::range(0, K), xt::range(0, K)) = detail::rbf_gram(centres, kernel, sigma);
    for (std::size_t k = 0; k < K; ++k) {
        a(k, K) = a(K, k) = 1.0;
        for (std::size_t i = 0; i < d; ++i) a(k, K + 1 + i) = a(K + 1 + i, k) = centres(k, i);
        for (std::size_t o = 0; o < m; ++o) b(k, o) = values(k, o);
    }
    detail::check_conditioning(a, who, "centres coincide or are affinely dependent");
    const matrix sol = detail::lapack(who, [&] { return matrix(xt::linalg::solve(a, b)); });
    detail::require_finite_solution(sol, who);
    rbf_map r;
    r.kernel = kernel;
    r.sigma = sigma;
    r.centres = centres;
    r.lambda = xt::view(sol, xt::range(0, K), xt::all());
    r.linear = xt::view(sol, xt::range(K, n), xt::all());
    return r;
}

/// @brief Eq. 1 fitted as described at the top: linear term by least squares on the `[N, d]` samples and
/// `[N, m]` targets, then RBF interpolation of the residuals at `[K, d]` centres with `[K, m]` values.
/// @throws value_error for a rank-deficient sample design (fewer than d + 1 samples in general position)
/// or a singular RBF matrix (coincident centres).
inline rbf_map fit_rbf_regression(const matrix& samples, const matrix& targets, const matrix& centres,
                                  const matrix& centre_values, rbf_kernel kernel, double sigma)
{
    const std::size_t N = samples.shape()[0], d = samples.shape()[1], K = centres.shape()[0], m = targets.shape()[1];
    const std::string who = "rcm::fit_rbf_regression";
    if (!(sigma > 0) || !std::isfinite(sigma)) throw value_error(who + ": sigma " + std::to_string(sigma) + " is not positive");
    if (targets.shape()[0] != N || centres.shape()[1] != d || centre_values.shape()[0] != K || centre_values.shape()[1] != m)
        throw shape_error(who + ": samples, targets, centres and centre values disagree in shape");
    if (N < d + 1)
        throw value_error(who + ": " + std::to_string(N) + " samples cannot fix a linear term in " + std::to_string(d) +
                          " dimensions: the system is singular");
    matrix design = xt::ones<double>({N, d + 1});
    xt::view(design, xt::all(), xt::range(1, d + 1)) = samples;
    detail::check_conditioning(design, who, "the samples do not span their dimensions (duplicate or collinear feature vectors)");
    const matrix w = std::get<0>(detail::lapack(who, [&] { return xt::linalg::lstsq(design, targets); }));
    const matrix phi = detail::rbf_gram(centres, kernel, sigma);
    matrix resid = xt::zeros<double>({K, m});
    for (std::size_t k = 0; k < K; ++k) {
        for (std::size_t o = 0; o < m; ++o) {
            double lin = w(0, o);
            for (std::size_t i = 0; i < d; ++i) lin += w(i + 1, o) * centres(k, i);
            resid(k, o) = centre_values(k, o) - lin;
        }
    }
    detail::check_conditioning(phi, who, "two centres coincide");
    const matrix lambda = detail::lapack(who, [&] { return matrix(xt::linalg::solve(phi, resid)); });
    detail::require_finite_solution(lambda, who);
    rbf_map r;
    r.kernel = kernel;
    r.sigma = sigma;
    r.centres = centres;
    r.lambda = lambda;
    r.linear = w;
    return r;
}

}  // namespace handemo::rcm
