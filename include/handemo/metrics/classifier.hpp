// An emotion classifier independent of the StarGAN discriminator, for the evaluation's "is the transferred
// clip recognised as the target emotion?" (the hand paper judged this by eye, Section 4): hand-made motion
// features of the K keyframes of Eq. 2 (per-joint range of motion, per-channel mean pose, overall range,
// speed and duration) and a nearest-centroid rule in a metric that discounts what varies inside a class.
// Features are standardised; the metric is the inverse of the pooled within-class covariance, shrunk towards
// its diagonal (Ledoit-Wolf style, fixed shrinkage a): S = (1 - a) S_w + a diag(S_w) + eps I, and a sample
// goes to the class c minimising (z - mu_c)^T S^{-1} (z - mu_c) (linear discriminant analysis with equal
// priors). Within-class scatter is mostly content (motion type), so the rule learns to look past content.
#pragma once

#include <handemo/core/error.hpp>
#include <handemo/motion/keyframes.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <string_view>
#include <vector>

namespace handemo::metrics {

/// @brief Motion features of keyframes [K, J, 3] of a clip lasting `duration` seconds: J values
/// log(1 + range of joint j), 3J wrapped mean angles, then log(1 + mean range), log(1 + mean keyframe
/// speed in deg/s), log(duration). 4J + 3 values.
/// @throws value_error for a non-positive duration or fewer than 2 keyframes.
template <std::size_t K>
std::vector<double> motion_features(const keyframes<K>& kf, double duration)
{
    const std::size_t k = kf.count(), J = kf.joints;
    if (k < 2) throw value_error("motion_features: " + std::to_string(k) + " keyframes, expected at least 2");
    if (!(duration > 0) || !std::isfinite(duration))
        throw value_error("motion_features: duration " + std::to_string(duration) + " s is not positive");
    std::vector<double> f(4 * J + 3, 0.0);
    double rom_all = 0, speed = 0;
    for (std::size_t j = 0; j < J; ++j) {
        double rom_j = 0;
        for (std::size_t a = 0; a < 3; ++a) {
            double lo = kf.at(0, j, a), hi = lo, mean = 0;
            for (std::size_t i = 0; i < k; ++i) {
                const double v = kf.at(i, j, a);
                lo = std::min(lo, v), hi = std::max(hi, v), mean += v;
                if (i > 0) speed += std::abs(v - kf.at(i - 1, j, a));
            }
            rom_j += hi - lo;
            mean /= static_cast<double>(k);
            mean = std::fmod(mean, 360.0);
            if (mean > 180) mean -= 360;
            if (mean <= -180) mean += 360;
            f[J + 3 * j + a] = mean;
        }
        rom_all += rom_j;
        f[j] = std::log1p(rom_j / 3);
    }
    const double J3 = static_cast<double>(3 * J);
    f[4 * J] = std::log1p(rom_all / J3);
    f[4 * J + 1] = std::log1p(speed / J3 / (duration / static_cast<double>(k - 1)));
    f[4 * J + 2] = std::log(duration);
    return f;
}

/// @brief Nearest-centroid classifier under a shrunk pooled within-class covariance (see the header comment).
class nearest_centroid_classifier {
public:
    /// @brief Fits on feature vectors `x` (all of one length) with string labels.
    /// @param shrinkage a in [0, 1]: 0 the full within-class covariance, 1 only its diagonal.
    /// @throws value_error for no samples, fewer than 2 classes, or a bad shrinkage; shape_error naming the
    ///         sample whose length differs.
    void fit(const std::vector<std::vector<double>>& x, const std::vector<std::string>& labels, double shrinkage = 0.5)
    {
        if (x.empty() || x.size() != labels.size())
            throw value_error("nearest_centroid_classifier: " + std::to_string(x.size()) + " samples and " +
                              std::to_string(labels.size()) + " labels (need the same non-zero number)");
        if (!(shrinkage >= 0 && shrinkage <= 1))
            throw value_error("nearest_centroid_classifier: shrinkage " + std::to_string(shrinkage) + " is not in [0, 1]");
        d_ = x.front().size();
        for (std::size_t n = 0; n < x.size(); ++n)
            if (x[n].size() != d_)
                throw shape_error("nearest_centroid_classifier: sample " + std::to_string(n) + " has " + std::to_string(x[n].size()) +
                                  " features, sample 0 has " + std::to_string(d_));
        classes_.clear();
        for (const auto& l : labels)
            if (std::find(classes_.begin(), classes_.end(), l) == classes_.end()) classes_.push_back(l);
        std::sort(classes_.begin(), classes_.end());
        if (classes_.size() < 2) throw value_error("nearest_centroid_classifier: one class only ('" + classes_.front() + "')");
        const std::size_t N = x.size(), C = classes_.size();
        // standardisation
        mu_.assign(d_, 0.0), sd_.assign(d_, 0.0);
        for (const auto& v : x)
            for (std::size_t i = 0; i < d_; ++i) mu_[i] += v[i] / static_cast<double>(N);
        for (const auto& v : x)
            for (std::size_t i = 0; i < d_; ++i) sd_[i] += (v[i] - mu_[i]) * (v[i] - mu_[i]) / static_cast<double>(N);
        for (auto& s : sd_) s = s > 1e-18 ? std::sqrt(s) : 1.0;
        std::vector<std::vector<double>> z(N);
        std::vector<std::size_t> y(N);
        for (std::size_t n = 0; n < N; ++n) {
            z[n] = standardise(x[n]);
            y[n] = static_cast<std::size_t>(std::find(classes_.begin(), classes_.end(), labels[n]) - classes_.begin());
        }
        // class centroids
        centroids_.assign(C, std::vector<double>(d_, 0.0));
        std::vector<double> count(C, 0.0);
        for (std::size_t n = 0; n < N; ++n) {
            count[y[n]] += 1;
            for (std::size_t i = 0; i < d_; ++i) centroids_[y[n]][i] += z[n][i];
        }
        for (std::size_t c = 0; c < C; ++c)
            for (auto& v : centroids_[c]) v /= count[c];
        // pooled within-class covariance, shrunk: S = (1 - a) S_w + a diag(S_w) + eps I
        std::vector<double> S(d_ * d_, 0.0);
        const double dof = static_cast<double>(N > C ? N - C : N);
        for (std::size_t n = 0; n < N; ++n)
            for (std::size_t i = 0; i < d_; ++i) {
                const double ri = z[n][i] - centroids_[y[n]][i];
                for (std::size_t j = 0; j <= i; ++j) S[i * d_ + j] += ri * (z[n][j] - centroids_[y[n]][j]) / dof;
            }
        double trace = 0;
        for (std::size_t i = 0; i < d_; ++i) trace += S[i * d_ + i];
        const double eps = 1e-3 * (trace > 0 ? trace / static_cast<double>(d_) : 1.0);
        for (std::size_t i = 0; i < d_; ++i) {
            for (std::size_t j = 0; j < i; ++j) S[i * d_ + j] *= 1 - shrinkage;
            S[i * d_ + i] += eps;
        }
        // Cholesky S = L L^T (lower triangle, in place)
        for (std::size_t j = 0; j < d_; ++j) {
            double s = S[j * d_ + j];
            for (std::size_t k = 0; k < j; ++k) s -= S[j * d_ + k] * S[j * d_ + k];
            if (!(s > 0)) throw value_error("nearest_centroid_classifier: covariance is not positive definite (non-finite features?)");
            const double l = std::sqrt(s);
            S[j * d_ + j] = l;
            for (std::size_t i = j + 1; i < d_; ++i) {
                double t = S[i * d_ + j];
                for (std::size_t k = 0; k < j; ++k) t -= S[i * d_ + k] * S[j * d_ + k];
                S[i * d_ + j] = t / l;
            }
        }
        chol_ = std::move(S);
    }

    /// @brief The class of a feature vector: argmin_c ||L^{-1} (z - mu_c)||^2.
    /// @throws value_error before fit(); shape_error for a wrong feature count.
    const std::string& predict(const std::vector<double>& x) const
    {
        const auto d = distances(x);
        return classes_[static_cast<std::size_t>(std::min_element(d.begin(), d.end()) - d.begin())];
    }

    /// @brief Squared Mahalanobis distance of `x` to every class centroid, in classes() order.
    std::vector<double> distances(const std::vector<double>& x) const
    {
        if (classes_.empty()) throw value_error("nearest_centroid_classifier: predict before fit");
        if (x.size() != d_)
            throw shape_error("nearest_centroid_classifier: " + std::to_string(x.size()) + " features, fitted on " + std::to_string(d_));
        const auto z = standardise(x);
        std::vector<double> out, r(d_);
        for (const auto& c : centroids_) {
            // forward substitution L r = z - mu_c
            double s2 = 0;
            for (std::size_t i = 0; i < d_; ++i) {
                double t = z[i] - c[i];
                for (std::size_t k = 0; k < i; ++k) t -= chol_[i * d_ + k] * r[k];
                r[i] = t / chol_[i * d_ + i];
                s2 += r[i] * r[i];
            }
            out.push_back(s2);
        }
        return out;
    }

    /// @brief The posterior probability of class `label` for `x` when every class is a Gaussian with the shared
    /// (shrunk) covariance and equal priors, the probabilistic reading of predict() (linear discriminant
    /// analysis): exp(-d_label / 2) / sum_c exp(-d_c / 2) with d the distances(). 0 for a label not fitted.
    double posterior(const std::vector<double>& x, std::string_view label) const { return posterior_of(distances(x), index_of(label)); }

    /// @brief posterior() from distances() already computed, for the class at `index` (0 when it is out of range).
    static double posterior_of(const std::vector<double>& d, std::size_t index)
    {
        const double dmin = *std::min_element(d.begin(), d.end());
        double z = 0, p = 0;
        for (std::size_t c = 0; c < d.size(); ++c) {
            const double e = std::exp(-0.5 * (d[c] - dmin));
            z += e;
            if (c == index) p = e;
        }
        return p / z;
    }

    /// @brief The index of `label` in classes() (classes().size() when it was not fitted).
    std::size_t index_of(std::string_view label) const
    {
        return static_cast<std::size_t>(std::find(classes_.begin(), classes_.end(), label) - classes_.begin());
    }

    /// Class labels, sorted.
    const std::vector<std::string>& classes() const noexcept { return classes_; }

private:
    std::vector<double> standardise(const std::vector<double>& x) const
    {
        std::vector<double> z(d_);
        for (std::size_t i = 0; i < d_; ++i) z[i] = (x[i] - mu_[i]) / sd_[i];
        return z;
    }
    std::size_t d_ = 0;
    std::vector<std::string> classes_;
    std::vector<double> mu_, sd_, chol_;
    std::vector<std::vector<double>> centroids_;
};

}  // namespace handemo::metrics
