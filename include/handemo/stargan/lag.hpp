// The joint lag: per target emotion and joint, a time shift of that joint's keyframes (Table 1's finger lag: a
// fearful hand's fingers trail its wrist by a part of a cycle). In the keyframes of a motion that lags, a
// joint's curve is its neutral curve moved later, which changes every keyframe value by an amount that depends
// on the movement: no offset or scale per channel (the posture prior, the amplitude stage) can express it, but a
// shift per joint, the same for every movement, can.
//
// The shift is read off the keyframe spline: keyframe k of a joint lagging by d takes the value of its curve at
// k - d (in keyframe intervals, linear between keyframes), clamped to the clip's first and last keyframe (the
// joint holds its start pose until its lagged curve begins, so the shift needs no assumption that the motion
// repeats). The lags are fitted on the training pairs (an emotional take and the neutral take of the same content
// and take) by a grid search per emotion and joint on the keyframes' excursions about their mean (so the posture
// prior, which moves the mean, plays no part), scaled by the amplitude stage's factor; an emotion keeps its lags
// only when leave-one-content-out inside the training clips finds them closer to the left-out contents' real takes
// than no lag (joint_lags_checked()), so a data set without a lag style gets none.
#pragma once

#include <handemo/core/error.hpp>
#include <handemo/motion/codec.hpp>
#include <handemo/motion/keyframes.hpp>
#include <handemo/motion/labelled.hpp>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <span>
#include <string>
#include <utility>
#include <vector>

namespace handemo::stargan {

/// @brief The lags (keyframe intervals) the fit chooses from: -2 to 2 in steps of 1/8.
inline std::vector<double> joint_lag_grid()
{
    std::vector<double> g;
    for (int i = -16; i <= 16; ++i) g.push_back(i / 8.0);
    return g;
}

namespace detail {

/// A channel's keyframe curve at keyframe position s: v[k * stride] for k < n, linear between keyframes, held at the
/// first and last (exactly their values there).
inline double curve_at(const double* v, std::size_t stride, std::size_t n, double s) noexcept
{
    if (s <= 0.0) return v[0];
    if (s >= static_cast<double>(n - 1)) return v[(n - 1) * stride];
    const auto i = static_cast<std::size_t>(s);
    const double f = s - static_cast<double>(i);
    return (1.0 - f) * v[i * stride] + f * v[(i + 1) * stride];
}

}  // namespace detail

/// @brief Shifts each joint's keyframes by its lag (in place, no allocation): keyframe k takes the value of the
/// joint's keyframe curve at k - lag[j] (linear between keyframes, clamped to the first and last keyframe).
/// A positive lag delays the joint, a negative one advances it; 0 leaves it as it is.
/// @throws value_error when `lag` does not hold one value per joint or a lag is not finite.
template <std::size_t K>
void shift_joints(keyframes<K>& kf, std::span<const double> lag)
{
    if (lag.size() != kf.joints)
        throw value_error("joint lag: " + std::to_string(lag.size()) + " lags for " + std::to_string(kf.joints) + " joints");
    const std::size_t C = kf.joints * 3, n = kf.count();
    for (std::size_t j = 0; j < kf.joints; ++j) {
        const double d = lag[j];
        if (!std::isfinite(d)) throw value_error("joint lag: the lag of joint " + std::to_string(j) + " is not finite");
        if (d == 0.0) continue;
        for (std::size_t c = 0; c < 3; ++c) {
            double* v = kf.angles.data() + j * 3 + c;
            // in place: a delay reads only keyframes at or before k, so k runs down; an advance runs up
            const auto value_at = [&](std::size_t k) { return detail::curve_at(v, C, n, static_cast<double>(k) - d); };
            if (d > 0)
                for (std::size_t k = n; k-- > 0;) v[k * C] = value_at(k);
            else
                for (std::size_t k = 0; k < n; ++k) v[k * C] = value_at(k);
        }
    }
}

/// @brief What joint_lags_checked() fitted: the lags and the leave-one-content-out check of each emotion.
struct joint_lag_fit {
    /// [C][J] lag per domain and joint in keyframe intervals (the neutral domain's, and an emotion's whose check
    /// failed, all 0)
    std::vector<std::vector<double>> lag;
    /// [C] mean keyframe RMSE of the excursions (deg) over the left-out contents' pairs, without / with the lags
    /// fitted on the other contents; NaN for the neutral domain and where there are fewer than two contents
    std::vector<std::pair<double, double>> check;
    /// [C] whether the emotion keeps its lags (its check's RMSE with the lags below the one without)
    std::vector<bool> kept;
};

namespace detail {

/// An emotional take and the neutral take it is compared with (same content and take, else the content's first
/// neutral take), as amplitude_factors() pairs them.
struct lag_pair {
    std::size_t emotional, neutral;
};

inline std::vector<lag_pair> lag_pairs(const std::vector<labelled_clip>& clips, const std::string& emotion, const std::string& neutral,
                                const std::vector<bool>& use)
{
    std::vector<lag_pair> r;
    for (std::size_t m = 0; m < clips.size(); ++m) {
        if (!use[m] || clips[m].emotion != emotion) continue;
        std::size_t best = clips.size();
        for (std::size_t q = 0; q < clips.size(); ++q) {
            if (!use[q] || clips[q].emotion != neutral || clips[q].content != clips[m].content) continue;
            if (clips[q].take == clips[m].take) {
                best = q;
                break;
            }
            if (best == clips.size()) best = q;
        }
        if (best < clips.size()) r.push_back({m, best});
    }
    return r;
}

/// Sum of squared (wrapped) differences between a x (the neutral channel shifted by d, about its mean) and the
/// emotional channel about its mean, over the joint's 3 channels.
template <std::size_t K>
double lag_error(const keyframes<K>& neutral, const keyframes<K>& emotional, std::size_t j, double d, double a)
{
    const std::size_t C = neutral.joints * 3, n = neutral.count();
    double s = 0;
    for (std::size_t c = 0; c < 3; ++c) {
        const std::size_t ch = j * 3 + c;
        double x[64], mx = 0, my = 0;
        for (std::size_t k = 0; k < n; ++k) {
            x[k] = curve_at(neutral.angles.data() + ch, C, n, static_cast<double>(k) - d);
            mx += x[k];
            my += emotional.angles[k * C + ch];
        }
        mx /= static_cast<double>(n), my /= static_cast<double>(n);
        for (std::size_t k = 0; k < n; ++k) {
            const double e = wrap_angle_deg(a * (x[k] - mx) - (emotional.angles[k * C + ch] - my));
            s += e * e;
        }
    }
    return s;
}

/// The lags of one emotion fitted on `pairs`: per joint the grid value with the least lag_error() summed over
/// the pairs (ties to the smaller |lag|, then the earlier one).
template <std::size_t K>
std::vector<double> fit_emotion_lags(const std::vector<keyframes<K>>& kfs, const std::vector<lag_pair>& pairs, std::size_t joints, double a)
{
    std::vector<double> lag(joints, 0.0);
    if (pairs.empty()) return lag;
    const auto grid = joint_lag_grid();
    for (std::size_t j = 0; j < joints; ++j) {
        double best = std::numeric_limits<double>::infinity();
        for (double d : grid) {
            double s = 0;
            for (const auto& p : pairs) s += lag_error(kfs[p.neutral], kfs[p.emotional], j, d, a);
            if (s < best || (s == best && std::abs(d) < std::abs(lag[j]))) best = s, lag[j] = d;
        }
    }
    return lag;
}

/// Keyframe RMSE (deg) of a pair's excursions: the neutral take shifted by `lag` and scaled by a, against the
/// emotional take, each about its per-channel mean.
template <std::size_t K>
double lag_pair_rmse(const keyframes<K>& neutral, const keyframes<K>& emotional, const std::vector<double>& lag, double a)
{
    double s = 0;
    for (std::size_t j = 0; j < neutral.joints; ++j) s += lag_error(neutral, emotional, j, lag[j], a);
    return std::sqrt(s / static_cast<double>(neutral.angles.size()));
}

}  // namespace detail

/// @brief The joint lags of every domain relative to `neutral`, each emotion's kept only when leave-one-content-out
/// on the training clips says they carry over (see the file comment).
/// @param kfs the clips' keyframes (at most 64 keyframes), in the order of `clips`
/// @param amplitude [C] the amplitude stage's factor per domain (all 1 without the stage), which scales the
///        neutral take's excursions before they are compared
/// @throws value_error when the sizes disagree or a clip has more than 64 keyframes.
template <std::size_t K>
joint_lag_fit joint_lags_checked(const std::vector<labelled_clip>& clips, const std::vector<keyframes<K>>& kfs,
                                 const std::vector<std::string>& domains, const std::string& neutral, const std::vector<double>& amplitude)
{
    if (kfs.size() != clips.size() || amplitude.size() != domains.size())
        throw value_error("joint lag: " + std::to_string(kfs.size()) + " keyframe sets for " + std::to_string(clips.size()) + " clips, " +
                          std::to_string(amplitude.size()) + " amplitude factors for " + std::to_string(domains.size()) + " domains");
    if (kfs.empty()) return {};
    const std::size_t J = kfs.front().joints;
    for (const auto& k : kfs)
        if (k.count() > 64 || k.count() < 2 || k.joints != J)
            throw value_error("joint lag: keyframes of " + std::to_string(k.count()) + " x " + std::to_string(k.joints) +
                              " joints (2 to 64 keyframes of one skeleton)");
    std::vector<std::string> contents;
    for (const auto& c : clips)
        if (std::find(contents.begin(), contents.end(), c.content) == contents.end()) contents.push_back(c.content);
    joint_lag_fit r;
    r.lag.assign(domains.size(), std::vector<double>(J, 0.0));
    r.check.assign(domains.size(), {std::nan(""), std::nan("")});
    r.kept.assign(domains.size(), false);
    const std::vector<bool> all(clips.size(), true);
    const auto nit = std::find(domains.begin(), domains.end(), neutral);
    if (nit == domains.end()) throw value_error("joint lag: the neutral domain '" + neutral + "' is not among the domains");
    const double a_neutral = amplitude[static_cast<std::size_t>(nit - domains.begin())];
    for (std::size_t d = 0; d < domains.size(); ++d) {
        if (domains[d] == neutral) continue;
        const double a = amplitude[d] / a_neutral;
        if (contents.size() >= 2) {
            double s0 = 0, s1 = 0;
            std::size_t n = 0;
            for (const auto& held : contents) {
                std::vector<bool> train(clips.size()), test(clips.size());
                for (std::size_t m = 0; m < clips.size(); ++m) train[m] = clips[m].content != held, test[m] = !train[m];
                const auto tp = detail::lag_pairs(clips, domains[d], neutral, test);
                if (tp.empty()) continue;
                const auto lag = detail::fit_emotion_lags<K>(kfs, detail::lag_pairs(clips, domains[d], neutral, train), J, a);
                const std::vector<double> none(J, 0.0);
                for (const auto& p : tp) {
                    s0 += detail::lag_pair_rmse(kfs[p.neutral], kfs[p.emotional], none, a);
                    s1 += detail::lag_pair_rmse(kfs[p.neutral], kfs[p.emotional], lag, a);
                    ++n;
                }
            }
            if (n) r.check[d] = {s0 / static_cast<double>(n), s1 / static_cast<double>(n)};
        }
        r.kept[d] = r.check[d].second < r.check[d].first;
        if (r.kept[d]) r.lag[d] = detail::fit_emotion_lags<K>(kfs, detail::lag_pairs(clips, domains[d], neutral, all), J, a);
    }
    return r;
}

}  // namespace handemo::stargan
