// A second emotion classifier, independent of the keyframe judge (classifier.hpp) in both its inputs and its
// model: it reads the clip at full rate, not its 9 keyframes, and it is discriminative, not a nearest centroid.
// Features (full_rate_features()): per joint the log range of motion, the circular mean of each angle (posture),
// the log mean speed and the log tremor energy (the motion left after a 0.2 s quadratic Savitzky-Golay smoothing); per clip
// the log duration, the log mean speed, acceleration and root speed, the tremor's frequency (zero crossings of
// that residual) and its share of the motion, and the spread and mean of the joints' lags behind the clip's
// widest channel (asynchrony, the hand's finger lag). The judge reads them as a change against a neutral clip of
// the same content (full_rate_change(): per-joint ranges, speeds and tremor, the mean posture per axis and the
// clip features, each minus the neutral clip's), so that what the content sets cancels. The classifier
// (full_rate_classifier) standardises them and fits a multinomial logistic regression with an L2 penalty on the weights (not the biases),
//   L(W) = -(1/N) sum_n log softmax(W x_n)_{y_n} + (lambda / 2) sum_{c, i > 0} W_ci^2,
// minimised by L-BFGS; lambda is chosen from a fixed grid by leave-one-group-out cross-validation on the
// training samples (the groups are contents, so the weight that recognises emotions on unseen contents wins).
// The judge (full_rate_judge) reads the change in one of three input sets (full_rate_inputs): the posture pooled
// per axis over the joints, the posture of every joint besides, or that and the clip's own features (not read
// against the neutral clip) besides; it keeps the candidate whose leave-one-content-out accuracy on its training
// clips is highest (a tie keeps the smaller set).
#pragma once

#include <handemo/core/error.hpp>
#include <handemo/motion/cadence.hpp>
#include <handemo/motion/clip.hpp>
#include <handemo/motion/codec.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <limits>
#include <numbers>
#include <string>
#include <string_view>
#include <vector>

namespace handemo::metrics {

/// @brief Options of full_rate_features().
struct full_rate_feature_options {
    double smooth_seconds = 0.2;     ///< width of the quadratic smoothing whose residual is the tremor
    double max_lag_fraction = 0.15;  ///< largest lag searched, as a fraction of the clip's frames
    double lag_min_range = 0.2;      ///< channels whose range is below this share of the widest channel's have no lag
};

/// @brief The number of features full_rate_features() gives for J joints: 6J + 8.
constexpr std::size_t full_rate_feature_count(std::size_t joints) noexcept { return 6 * joints + 8; }

namespace detail {
using ::handemo::detail::quadratic_smooth;  // motion/cadence.hpp
}  // namespace detail

/// @brief Full-rate motion features of a clip (see the header comment), 6J + 8 values in this order: J log(1 +
/// range / 3 axes) of the unwrapped angles, 3J circular mean angles (degrees, (-180, 180]), J log(1 + mean
/// speed in deg/s) (central differences), J log(1 + RMS tremor residual in degrees), then log(duration),
/// log(1 + mean speed), log(1 + mean |acceleration| / 100), log(1 + mean root speed) (position channels of joints
/// that have them, in the file's units per second; 0 without), log(1 + tremor frequency in Hz), the tremor's share
/// of the motion (RMS residual / (RMS residual + mean range / 4)), and the standard deviation and mean absolute
/// value of the lags (fractions of the duration) that best align each wide channel with the widest one.
/// @throws value_error for fewer than 5 frames or a non-positive frame rate.
inline std::vector<double> full_rate_features(const clip& c, const full_rate_feature_options& o = {})
{
    const std::size_t n = c.frames, J = c.skel.size(), J3 = 3 * J;
    if (n < 5) throw value_error("full_rate_features: " + std::to_string(n) + " frames, expected at least 5");
    if (!(c.fps > 0) || !std::isfinite(c.fps)) throw value_error("full_rate_features: fps " + std::to_string(c.fps) + " is not positive");
    const double fps = c.fps;
    const std::size_t h = std::clamp<std::size_t>(static_cast<std::size_t>(std::lround(0.5 * o.smooth_seconds * fps)), 2, (n - 1) / 2);
    std::vector<double> f(full_rate_feature_count(J), 0.0);
    std::vector<std::vector<double>> centred(J3);  // unwrapped, mean removed (for the lags)
    std::vector<double> range(J3, 0.0);
    double speed_all = 0, acc_all = 0, resid_ss = 0, range_all = 0, cross_w = 0, cross_sum = 0;
    std::vector<double> u(n);
    for (std::size_t ch = 0; ch < J3; ++ch) {
        // unwrap: consecutive differences taken in (-180, 180]
        u[0] = c.angles[ch];
        double s = std::sin(u[0] * std::numbers::pi / 180), co = std::cos(u[0] * std::numbers::pi / 180);
        for (std::size_t i = 1; i < n; ++i) {
            const double a = c.angles[i * J3 + ch];
            u[i] = u[i - 1] + wrap_angle_deg(a - c.angles[(i - 1) * J3 + ch]);
            s += std::sin(a * std::numbers::pi / 180), co += std::cos(a * std::numbers::pi / 180);
        }
        const auto [lo, hi] = std::minmax_element(u.begin(), u.end());
        range[ch] = *hi - *lo;
        f[J + ch] = std::hypot(s, co) > 1e-9 * static_cast<double>(n) ? std::atan2(s, co) * 180 / std::numbers::pi : 0.0;
        // speed (central differences, one-sided at the ends) and acceleration
        double sp = 0, ac = 0;
        for (std::size_t i = 0; i < n; ++i) {
            const double d = i == 0 ? u[1] - u[0] : i == n - 1 ? u[n - 1] - u[n - 2] : 0.5 * (u[i + 1] - u[i - 1]);
            sp += std::abs(d) * fps;
            if (i > 0 && i + 1 < n) ac += std::abs(u[i + 1] - 2 * u[i] + u[i - 1]) * fps * fps;
        }
        sp /= static_cast<double>(n), ac /= static_cast<double>(n - 2);
        // tremor: the residual after a quadratic smoothing, its RMS and its zero crossings
        const auto sm = detail::quadratic_smooth(u, h);
        double rss = 0;
        std::size_t crossings = 0;
        double prev = u[0] - sm[0];
        for (std::size_t i = 0; i < n; ++i) {
            const double r = u[i] - sm[i];
            rss += r * r;
            if (i > 0 && ((r > 0 && prev <= 0) || (r < 0 && prev >= 0))) ++crossings;
            if (r != 0) prev = r;
        }
        const std::size_t j = ch / 3;
        f[j] += range[ch] / 3;
        f[4 * J + j] += sp / 3;
        f[5 * J + j] += rss / static_cast<double>(n) / 3;
        speed_all += sp / static_cast<double>(J3), acc_all += ac / static_cast<double>(J3);
        resid_ss += rss / static_cast<double>(n) / static_cast<double>(J3);
        range_all += range[ch] / static_cast<double>(J3);
        cross_w += rss, cross_sum += rss * static_cast<double>(crossings) / 2 / c.duration();
        // centred copy for the lags
        double mean = 0;
        for (double v : u) mean += v / static_cast<double>(n);
        centred[ch].resize(n);
        for (std::size_t i = 0; i < n; ++i) centred[ch][i] = u[i] - mean;
    }
    for (std::size_t j = 0; j < J; ++j) {
        f[j] = std::log1p(f[j]);
        f[4 * J + j] = std::log1p(f[4 * J + j]);
        f[5 * J + j] = std::log1p(std::sqrt(f[5 * J + j]));
    }
    // root speed: position channels of joints that have them
    double root = 0;
    std::size_t roots = 0;
    for (std::size_t j = 0; j < J; ++j) {
        if (!c.skel.joints[j].has_position()) continue;
        double s = 0;
        for (std::size_t i = 1; i < n; ++i) {
            double d2 = 0;
            for (std::size_t a = 0; a < 3; ++a) {
                const double d = c.positions[(i * J + j) * 3 + a] - c.positions[((i - 1) * J + j) * 3 + a];
                d2 += d * d;
            }
            s += std::sqrt(d2) * fps;
        }
        root += s / static_cast<double>(n - 1), ++roots;
    }
    // lags: each wide channel against the widest, by the normalised cross-correlation over the overlap
    const std::size_t ref = static_cast<std::size_t>(std::max_element(range.begin(), range.end()) - range.begin());
    const long max_lag = std::max<long>(1, std::lround(o.max_lag_fraction * static_cast<double>(n)));
    std::vector<double> lags;
    for (std::size_t ch = 0; ch < J3; ++ch) {
        if (ch == ref || !(range[ch] > 0) || range[ch] < o.lag_min_range * range[ref]) continue;
        double best = -std::numeric_limits<double>::infinity();
        long best_lag = 0;
        for (long lag = -max_lag; lag <= max_lag; ++lag) {
            double sxy = 0, sxx = 0, syy = 0;
            for (long i = std::max<long>(0, -lag); i < static_cast<long>(n) - std::max<long>(0, lag); ++i) {
                const double x = centred[ref][static_cast<std::size_t>(i)], y = centred[ch][static_cast<std::size_t>(i + lag)];
                sxy += x * y, sxx += x * x, syy += y * y;
            }
            const double r = sxx > 0 && syy > 0 ? std::abs(sxy) / std::sqrt(sxx * syy) : 0.0;
            // the smaller |lag| on a tie, so the answer does not depend on the search order
            if (r > best + 1e-12 || (std::abs(r - best) <= 1e-12 && std::abs(lag) < std::abs(best_lag))) best = r, best_lag = lag;
        }
        lags.push_back(static_cast<double>(best_lag) / static_cast<double>(n));
    }
    double lag_mean = 0, lag_abs = 0, lag_sd = 0;
    for (double l : lags) lag_mean += l / static_cast<double>(lags.size()), lag_abs += std::abs(l) / static_cast<double>(lags.size());
    for (double l : lags) lag_sd += (l - lag_mean) * (l - lag_mean) / static_cast<double>(lags.size());
    const double resid_rms = std::sqrt(resid_ss);
    double* g = f.data() + 6 * J;
    g[0] = std::log(c.duration());
    g[1] = std::log1p(speed_all);
    g[2] = std::log1p(acc_all / 100);
    g[3] = roots ? std::log1p(root / static_cast<double>(roots)) : 0.0;
    g[4] = std::log1p(cross_w > 0 ? cross_sum / cross_w : 0.0);
    g[5] = resid_rms + range_all / 4 > 0 ? resid_rms / (resid_rms + range_all / 4) : 0.0;
    g[6] = lags.empty() ? 0.0 : std::sqrt(lag_sd);
    g[7] = lag_abs;
    return f;
}

/// @brief The input sets the full-rate judge can read a change in (full_rate_change()).
enum class full_rate_inputs {
    pooled,    ///< per joint range, speed and tremor; the posture pooled per axis over the joints; the clip features (3J + 11)
    joints,    ///< the pooled set and every joint's posture change besides (6J + 11): a head bowed, a chest lifted
    absolute,  ///< the joints set and the clip's own features besides, not read against the neutral clip (12J + 19)
};

/// @brief Every input set, in the order the judge prefers them on a tie (the smaller first): what it chooses from by default.
inline const std::vector<full_rate_inputs>& all_full_rate_inputs()
{
    static const std::vector<full_rate_inputs> all{full_rate_inputs::pooled, full_rate_inputs::joints, full_rate_inputs::absolute};
    return all;
}

/// @brief "pooled", "joints" or "absolute".
inline const char* to_string(full_rate_inputs i) noexcept
{
    return i == full_rate_inputs::joints ? "joints" : i == full_rate_inputs::absolute ? "absolute" : "pooled";
}

/// @brief Parses "pooled", "joints" or "absolute".
/// @throws value_error naming the value otherwise.
inline full_rate_inputs parse_full_rate_inputs(std::string_view v)
{
    if (v == "pooled") return full_rate_inputs::pooled;
    if (v == "joints") return full_rate_inputs::joints;
    if (v == "absolute") return full_rate_inputs::absolute;
    throw value_error("full-rate judge inputs '" + std::string(v) + "': expected pooled, joints or absolute");
}

/// @brief The number of values full_rate_change() gives for J joints: 3J + 11 (pooled), 6J + 11 (joints), 12J + 19
/// (absolute).
constexpr std::size_t full_rate_change_count(std::size_t joints, full_rate_inputs inputs = full_rate_inputs::pooled) noexcept
{
    switch (inputs) {
    case full_rate_inputs::joints: return 6 * joints + 11;
    case full_rate_inputs::absolute: return 12 * joints + 19;
    default: return 3 * joints + 11;
    }
}

/// @brief What the full-rate judge reads: a clip's features (full_rate_features()) against those of a neutral clip
/// of the same content (the same take where there is one), so that what the content sets (its joints' ranges,
/// speeds and posture) cancels and what the emotion changes stays. 3J + 11 values: per joint the differences of
/// log range, log speed and log tremor energy; per axis the mean over joints of the posture difference (wrapped
/// into (-180, 180]); the differences of the 8 clip features. With full_rate_inputs::joints, 3J values follow:
/// each joint's posture difference per axis (wrapped, degrees), joint by joint; with full_rate_inputs::absolute,
/// those 3J and then the clip's own 6J + 8 features as they are.
/// @throws shape_error when the two vectors differ in length or are not 6J + 8 long.
inline std::vector<double> full_rate_change(const std::vector<double>& clip_features, const std::vector<double>& neutral_features,
                                            full_rate_inputs inputs = full_rate_inputs::pooled)
{
    const std::size_t d = clip_features.size();
    if (d != neutral_features.size() || d < 8 || (d - 8) % 6 != 0)
        throw shape_error("full_rate_change: " + std::to_string(d) + " and " + std::to_string(neutral_features.size()) +
                          " features, expected two vectors of 6J + 8");
    const std::size_t J = (d - 8) / 6;
    std::vector<double> out(full_rate_change_count(J, inputs), 0.0);
    for (std::size_t j = 0; j < J; ++j) {
        out[j] = clip_features[j] - neutral_features[j];                          // log range
        out[J + j] = clip_features[4 * J + j] - neutral_features[4 * J + j];      // log speed
        out[2 * J + j] = clip_features[5 * J + j] - neutral_features[5 * J + j];  // log tremor energy
        for (std::size_t a = 0; a < 3; ++a) {
            const double d = wrap_angle_deg(clip_features[J + 3 * j + a] - neutral_features[J + 3 * j + a]);
            out[3 * J + a] += d / static_cast<double>(J);
            if (inputs != full_rate_inputs::pooled) out[3 * J + 11 + 3 * j + a] = d;
        }
    }
    for (std::size_t i = 0; i < 8; ++i) out[3 * J + 3 + i] = clip_features[6 * J + i] - neutral_features[6 * J + i];
    if (inputs == full_rate_inputs::absolute) std::copy(clip_features.begin(), clip_features.end(), out.begin() + static_cast<std::ptrdiff_t>(6 * J + 11));
    return out;
}

/// @brief Multinomial logistic regression on standardised features, its L2 weight chosen by leave-one-group-out
/// cross-validation (see the header comment).
class full_rate_classifier {
public:
    /// The L2 weights tried by fit(), in order.
    static constexpr std::array<double, 5> lambda_grid{0.001, 0.01, 0.1, 1.0, 10.0};

    /// @brief Fits on feature vectors `x` with string labels; `groups` (one per sample, e.g. the content) are the
    /// cross-validation's folds: each group is left out in turn and the weight of lambda_grid with the most
    /// left-out samples recognised wins (ties to the larger weight). With fewer than 2 groups (or `groups` empty),
    /// 5 interleaved folds are used instead.
    /// @throws value_error for no samples, fewer than 2 classes, or label/group counts that differ; shape_error
    ///         naming the sample whose length differs.
    void fit(const std::vector<std::vector<double>>& x, const std::vector<std::string>& labels, const std::vector<std::string>& groups = {})
    {
        check_input(x, labels, "fit");
        if (!groups.empty() && groups.size() != x.size())
            throw value_error("full_rate_classifier: " + std::to_string(groups.size()) + " groups for " + std::to_string(x.size()) + " samples");
        // folds: one per distinct group, else interleaved
        std::vector<std::string> names;
        for (const auto& g : groups)
            if (std::find(names.begin(), names.end(), g) == names.end()) names.push_back(g);
        std::vector<std::size_t> fold(x.size());
        std::size_t folds = 0;
        if (names.size() >= 2) {
            folds = names.size();
            for (std::size_t n = 0; n < x.size(); ++n) fold[n] = static_cast<std::size_t>(std::find(names.begin(), names.end(), groups[n]) - names.begin());
        } else {
            folds = std::min<std::size_t>(5, x.size());
            for (std::size_t n = 0; n < x.size(); ++n) fold[n] = n % folds;
        }
        cv_accuracy_.assign(lambda_grid.size(), 0.0);
        for (std::size_t k = 0; k < folds; ++k) {
            std::vector<std::vector<double>> xt, xv;
            std::vector<std::string> yt, yv;
            for (std::size_t n = 0; n < x.size(); ++n) (fold[n] == k ? xv : xt).push_back(x[n]), (fold[n] == k ? yv : yt).push_back(labels[n]);
            if (xv.empty() || distinct(yt) < 2) continue;
            for (std::size_t l = 0; l < lambda_grid.size(); ++l) {
                full_rate_classifier inner;
                inner.fit_fixed(xt, yt, lambda_grid[l]);
                for (std::size_t i = 0; i < xv.size(); ++i) cv_accuracy_[l] += inner.predict(xv[i]) == yv[i] ? 1.0 : 0.0;
            }
        }
        std::size_t best = lambda_grid.size() - 1;
        for (std::size_t l = lambda_grid.size(); l-- > 0;)
            if (cv_accuracy_[l] > cv_accuracy_[best]) best = l;
        for (auto& a : cv_accuracy_) a /= static_cast<double>(x.size());
        auto cv = std::move(cv_accuracy_);
        fit_fixed(x, labels, lambda_grid[best]);
        cv_accuracy_ = std::move(cv);
        cv_accuracy_chosen_ = cv_accuracy_[best];
    }

    /// @brief Fits with a given L2 weight, no cross-validation.
    /// @throws as fit(), and value_error for a negative or non-finite lambda.
    void fit_fixed(const std::vector<std::vector<double>>& x, const std::vector<std::string>& labels, double lambda)
    {
        check_input(x, labels, "fit_fixed");
        if (!(lambda >= 0) || !std::isfinite(lambda))
            throw value_error("full_rate_classifier: lambda " + std::to_string(lambda) + " is not a non-negative number");
        lambda_ = lambda;
        cv_accuracy_.clear(), cv_accuracy_chosen_ = std::nan("");
        d_ = x.front().size();
        classes_.clear();
        for (const auto& l : labels)
            if (std::find(classes_.begin(), classes_.end(), l) == classes_.end()) classes_.push_back(l);
        std::sort(classes_.begin(), classes_.end());
        const std::size_t N = x.size();
        mu_.assign(d_, 0.0), sd_.assign(d_, 0.0);
        for (const auto& v : x)
            for (std::size_t i = 0; i < d_; ++i) mu_[i] += v[i] / static_cast<double>(N);
        for (const auto& v : x)
            for (std::size_t i = 0; i < d_; ++i) sd_[i] += (v[i] - mu_[i]) * (v[i] - mu_[i]) / static_cast<double>(N);
        for (std::size_t i = 0; i < d_; ++i) {
            if (!std::isfinite(sd_[i])) throw value_error("full_rate_classifier: feature " + std::to_string(i) + " is not finite");
            sd_[i] = sd_[i] > 1e-18 ? std::sqrt(sd_[i]) : 1.0;
        }
        std::vector<double> z(N * (d_ + 1));
        std::vector<std::size_t> y(N);
        for (std::size_t n = 0; n < N; ++n) {
            z[n * (d_ + 1)] = 1.0;
            for (std::size_t i = 0; i < d_; ++i) z[n * (d_ + 1) + 1 + i] = (x[n][i] - mu_[i]) / sd_[i];
            y[n] = index_of(labels[n]);
        }
        w_.assign(classes_.size() * (d_ + 1), 0.0);
        minimise(z, y);
    }

    /// @brief The loss L(W) of the header comment and its gradient, for standardised samples `z` [N, d + 1] (a
    /// leading 1 for the bias) with class indices `y`, C classes and the weights `w` [C, d + 1].
    /// dL/dW_c = (1/N) sum_n (p_nc - [y_n = c]) z_n + lambda W_c (the bias column unpenalised), p_n = softmax(W z_n).
    static double loss_and_gradient(const std::vector<double>& w, const std::vector<double>& z, const std::vector<std::size_t>& y,
                                    std::size_t C, double lambda, std::vector<double>& grad)
    {
        const std::size_t N = y.size(), D = z.size() / N;
        grad.assign(w.size(), 0.0);
        double loss = 0;
        std::vector<double> s(C);
        for (std::size_t n = 0; n < N; ++n) {
            const double* zn = z.data() + n * D;
            double mx = -std::numeric_limits<double>::infinity();
            for (std::size_t c = 0; c < C; ++c) {
                double v = 0;
                for (std::size_t i = 0; i < D; ++i) v += w[c * D + i] * zn[i];
                s[c] = v, mx = std::max(mx, v);
            }
            double sum = 0;
            for (std::size_t c = 0; c < C; ++c) sum += std::exp(s[c] - mx);
            loss += (mx + std::log(sum) - s[y[n]]) / static_cast<double>(N);
            for (std::size_t c = 0; c < C; ++c) {
                const double g = (std::exp(s[c] - mx) / sum - (c == y[n] ? 1.0 : 0.0)) / static_cast<double>(N);
                for (std::size_t i = 0; i < D; ++i) grad[c * D + i] += g * zn[i];
            }
        }
        for (std::size_t c = 0; c < C; ++c)
            for (std::size_t i = 1; i < D; ++i) loss += 0.5 * lambda * w[c * D + i] * w[c * D + i], grad[c * D + i] += lambda * w[c * D + i];
        return loss;
    }

    /// @brief Class probabilities of a feature vector, in classes() order.
    /// @throws value_error before fit(); shape_error for a wrong feature count.
    std::vector<double> probabilities(const std::vector<double>& x) const
    {
        if (classes_.empty()) throw value_error("full_rate_classifier: predict before fit");
        if (x.size() != d_)
            throw shape_error("full_rate_classifier: " + std::to_string(x.size()) + " features, fitted on " + std::to_string(d_));
        const std::size_t D = d_ + 1;
        std::vector<double> s(classes_.size());
        double mx = -std::numeric_limits<double>::infinity();
        for (std::size_t c = 0; c < classes_.size(); ++c) {
            double v = w_[c * D];
            for (std::size_t i = 0; i < d_; ++i) v += w_[c * D + 1 + i] * (x[i] - mu_[i]) / sd_[i];
            s[c] = v, mx = std::max(mx, v);
        }
        double sum = 0;
        for (auto& v : s) sum += v = std::exp(v - mx);
        for (auto& v : s) v /= sum;
        return s;
    }

    /// @brief The most probable class of a feature vector.
    const std::string& predict(const std::vector<double>& x) const
    {
        const auto p = probabilities(x);
        return classes_[static_cast<std::size_t>(std::max_element(p.begin(), p.end()) - p.begin())];
    }

    /// Class labels, sorted.
    const std::vector<std::string>& classes() const noexcept { return classes_; }
    /// @brief The index of `label` in classes(); classes().size() when the classifier never saw it.
    std::size_t index_of(std::string_view label) const
    {
        return static_cast<std::size_t>(std::find(classes_.begin(), classes_.end(), label) - classes_.begin());
    }
    /// The L2 weight of the fitted model.
    double lambda() const noexcept { return lambda_; }
    /// Cross-validated accuracy per weight of lambda_grid (fit() only; empty after fit_fixed()).
    const std::vector<double>& cv_accuracy() const noexcept { return cv_accuracy_; }
    /// Cross-validated accuracy of the chosen weight (NaN after fit_fixed()).
    double cv_accuracy_chosen() const noexcept { return cv_accuracy_chosen_; }

private:
    static std::size_t distinct(const std::vector<std::string>& v)
    {
        std::vector<std::string> s(v);
        std::sort(s.begin(), s.end());
        return static_cast<std::size_t>(std::unique(s.begin(), s.end()) - s.begin());
    }

    static void check_input(const std::vector<std::vector<double>>& x, const std::vector<std::string>& labels, const char* who)
    {
        if (x.empty() || x.size() != labels.size())
            throw value_error(std::string("full_rate_classifier::") + who + ": " + std::to_string(x.size()) + " samples and " +
                              std::to_string(labels.size()) + " labels (need the same non-zero number)");
        for (std::size_t n = 0; n < x.size(); ++n)
            if (x[n].size() != x.front().size())
                throw shape_error(std::string("full_rate_classifier::") + who + ": sample " + std::to_string(n) + " has " +
                                  std::to_string(x[n].size()) + " features, sample 0 has " + std::to_string(x.front().size()));
        if (distinct(labels) < 2) throw value_error(std::string("full_rate_classifier::") + who + ": one class only ('" + labels.front() + "')");
    }


    /// L-BFGS (10 pairs) with a backtracking Armijo line search, from w_ = 0, until the gradient's largest
    /// component is below 1e-6 or 500 iterations.
    void minimise(const std::vector<double>& z, const std::vector<std::size_t>& y)
    {
        const std::size_t C = classes_.size(), P = w_.size(), M = 10;
        std::vector<double> g, gn, wn(P), dir(P);
        double f = loss_and_gradient(w_, z, y, C, lambda_, g);
        std::vector<std::vector<double>> S, Y;
        std::vector<double> rho;
        const auto dot = [](const std::vector<double>& a, const std::vector<double>& b) {
            double s = 0;
            for (std::size_t i = 0; i < a.size(); ++i) s += a[i] * b[i];
            return s;
        };
        for (int it = 0; it < 500; ++it) {
            double gmax = 0;
            for (double v : g) gmax = std::max(gmax, std::abs(v));
            if (gmax < 1e-6) break;
            // two-loop recursion: dir = -H g
            dir = g;
            std::vector<double> alpha(S.size());
            for (std::size_t k = S.size(); k-- > 0;) {
                alpha[k] = rho[k] * dot(S[k], dir);
                for (std::size_t i = 0; i < P; ++i) dir[i] -= alpha[k] * Y[k][i];
            }
            const double gamma = S.empty() ? 1.0 / std::max(1.0, std::sqrt(dot(g, g))) : dot(S.back(), Y.back()) / dot(Y.back(), Y.back());
            for (auto& v : dir) v *= gamma;
            for (std::size_t k = 0; k < S.size(); ++k) {
                const double beta = rho[k] * dot(Y[k], dir);
                for (std::size_t i = 0; i < P; ++i) dir[i] += (alpha[k] - beta) * S[k][i];
            }
            for (auto& v : dir) v = -v;
            double slope = dot(g, dir);
            if (!(slope < 0)) {  // not a descent direction: restart from steepest descent
                S.clear(), Y.clear(), rho.clear();
                for (std::size_t i = 0; i < P; ++i) dir[i] = -g[i] / std::max(1.0, std::sqrt(dot(g, g)));
                slope = dot(g, dir);
            }
            double step = 1.0, fn = 0;
            bool moved = false;
            for (int ls = 0; ls < 40; ++ls, step *= 0.5) {
                for (std::size_t i = 0; i < P; ++i) wn[i] = w_[i] + step * dir[i];
                fn = loss_and_gradient(wn, z, y, C, lambda_, gn);
                if (fn <= f + 1e-4 * step * slope) {
                    moved = true;
                    break;
                }
            }
            if (!moved) break;
            std::vector<double> s(P), yv(P);
            for (std::size_t i = 0; i < P; ++i) s[i] = wn[i] - w_[i], yv[i] = gn[i] - g[i];
            const double sy = dot(s, yv);
            if (sy > 1e-12) {
                if (S.size() == M) S.erase(S.begin()), Y.erase(Y.begin()), rho.erase(rho.begin());
                S.push_back(std::move(s)), Y.push_back(std::move(yv)), rho.push_back(1.0 / sy);
            }
            w_.swap(wn), g.swap(gn), f = fn;
        }
    }

    std::size_t d_ = 0;
    double lambda_ = 0;
    std::vector<std::string> classes_;
    std::vector<double> mu_, sd_, w_;
    std::vector<double> cv_accuracy_;
    double cv_accuracy_chosen_ = std::nan("");
};

/// @brief The full-rate judge: a full_rate_classifier on the change full_rate_change() reads in one of its input
/// sets, the set chosen by leave-one-group-out accuracy on the training samples.
class full_rate_judge {
public:
    /// @brief Fits on clips' full_rate_features() `clip_features`, each against its neutral reference's
    /// `reference_features` (same order), with labels and groups as full_rate_classifier::fit(). For each set of
    /// `candidates` (in order) the classifier is fitted with its own L2 weight chosen by the groups'
    /// cross-validation; the set with the highest cross-validated accuracy at its chosen weight is kept, the earlier
    /// set on a tie (so {pooled, joints} keeps the smaller set unless the larger recognises more).
    /// @throws value_error for no candidate or counts that differ; as full_rate_classifier::fit() otherwise.
    void fit(const std::vector<std::vector<double>>& clip_features, const std::vector<std::vector<double>>& reference_features,
             const std::vector<std::string>& labels, const std::vector<std::string>& groups = {},
             const std::vector<full_rate_inputs>& candidates = all_full_rate_inputs())
    {
        if (candidates.empty()) throw value_error("full_rate_judge::fit: no input set to choose from");
        if (clip_features.size() != reference_features.size())
            throw value_error("full_rate_judge::fit: " + std::to_string(clip_features.size()) + " clips and " +
                              std::to_string(reference_features.size()) + " references");
        candidates_ = candidates;
        cv_.clear();
        bool have = false;
        for (const auto inputs : candidates) {
            std::vector<std::vector<double>> x;
            x.reserve(clip_features.size());
            for (std::size_t n = 0; n < clip_features.size(); ++n) x.push_back(full_rate_change(clip_features[n], reference_features[n], inputs));
            full_rate_classifier c;
            c.fit(x, labels, groups);
            cv_.push_back(c.cv_accuracy_chosen());
            if (!have || c.cv_accuracy_chosen() > clf_.cv_accuracy_chosen()) clf_ = std::move(c), inputs_ = inputs, have = true;
        }
    }

    /// @brief The emotion a clip's features say, read against its neutral reference's.
    /// @throws value_error before fit(); shape_error for features of another skeleton size.
    const std::string& predict(const std::vector<double>& clip_features, const std::vector<double>& reference_features) const
    {
        return clf_.predict(full_rate_change(clip_features, reference_features, inputs_));
    }

    /// @brief Class probabilities, in classifier().classes() order.
    std::vector<double> probabilities(const std::vector<double>& clip_features, const std::vector<double>& reference_features) const
    {
        return clf_.probabilities(full_rate_change(clip_features, reference_features, inputs_));
    }

    /// The input set kept.
    full_rate_inputs inputs() const noexcept { return inputs_; }
    /// The classifier fitted on the kept set.
    const full_rate_classifier& classifier() const noexcept { return clf_; }
    /// The sets tried, in order, and each one's cross-validated accuracy at its chosen weight.
    const std::vector<full_rate_inputs>& candidates() const noexcept { return candidates_; }
    const std::vector<double>& candidate_cv_accuracy() const noexcept { return cv_; }

private:
    full_rate_classifier clf_;
    full_rate_inputs inputs_ = full_rate_inputs::pooled;
    std::vector<full_rate_inputs> candidates_;
    std::vector<double> cv_;
};

}  // namespace handemo::metrics
