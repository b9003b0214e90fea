// Effective and consistent feature selection of Aristidou et al. 2017, Section 3.2. With f(p, e) the mean
// of a normalised derived feature over the clips of performer p in emotion e:
//   effective for p  when std over emotions of f(p, *) >= 0.21; overall effective when that holds for a
//                    majority of performers (the paper: 7 of 9, so a share of 7/9, rounded up);
//   consistent for e when std over performers of f(*, e) <= 0.2; overall consistent when that holds for a
//                    majority of emotions (the paper: 10 of 12, a share of 10/12, rounded up).
// A feature that is both is selected. Data sets without performers (Bandai's contents, the synthetic hand
// set's motion types) pass their *contents* as performers: a feature is then effective when it separates
// emotions within most motion types, and consistent when an emotion gives it similar values across types.
// Standard deviations are population ones (1/n). If fewer than `min_features` survive, the features closest
// to passing (the larger the smaller of the two fulfilled shares count/majority, then their sum, then the
// mean std across emotions) fill up to `min_features`, and `fallback` says so.
#pragma once

#include <handemo/core/error.hpp>

#include <xtensor/xtensor.hpp>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <map>
#include <numeric>
#include <string>
#include <vector>

namespace handemo::rcm {

/// @brief Thresholds of Section 3.2.
struct selection_options {
    double effective_std = 0.21;         ///< std across emotions for one performer, at least
    double consistent_std = 0.2;         ///< std across performers for one emotion, at most
    double effective_share = 7.0 / 9.0;  ///< share of performers for which a feature must be effective
    double consistent_share = 10.0 / 12.0;  ///< share of emotions for which it must be consistent
    std::size_t min_features = 31;       ///< fill up to this many when fewer survive (the paper kept 31)
};

/// @brief The outcome of select_features().
struct selection_result {
    std::vector<std::size_t> selected;          ///< feature indices, ascending
    std::vector<std::size_t> effective_count;   ///< [D] performers for which each feature is effective
    std::vector<std::size_t> consistent_count;  ///< [D] emotions for which each feature is consistent
    std::vector<double> effectiveness;          ///< [D] mean over performers of the std across emotions
    std::size_t performers = 0, emotions = 0;
    std::size_t need_effective = 0, need_consistent = 0;  ///< the majorities used
    std::size_t survivors = 0;  ///< features that passed both tests (before any fallback)
    bool fallback = false;      ///< true when best-ranked features were added to reach min_features
};

/// @brief Section 3.2's selection on `[N, D]` normalised clip features with an emotion and a performer
/// (or content) label per clip.
/// @throws shape_error when the label counts differ from N; value_error with fewer than 2 emotions or performers.
inline selection_result select_features(const xt::xtensor<double, 2>& x, const std::vector<std::string>& emotion,
                                        const std::vector<std::string>& performer, const selection_options& opt = {})
{
    const std::size_t N = x.shape()[0], D = x.shape()[1];
    if (emotion.size() != N || performer.size() != N)
        throw shape_error("rcm::select_features: " + std::to_string(N) + " clips but " + std::to_string(emotion.size()) +
                          " emotion and " + std::to_string(performer.size()) + " performer labels");
    std::map<std::string, std::size_t> ei, pi;
    for (const auto& e : emotion) ei.emplace(e, 0);
    for (const auto& p : performer) pi.emplace(p, 0);
    std::size_t k = 0;
    for (auto& [n, i] : ei) i = k++;
    k = 0;
    for (auto& [n, i] : pi) i = k++;
    const std::size_t E = ei.size(), P = pi.size();
    if (E < 2 || P < 2)
        throw value_error("rcm::select_features: " + std::to_string(E) + " emotions and " + std::to_string(P) +
                          " performers (or contents); need at least 2 of each");
    selection_result r;
    r.performers = P;
    r.emotions = E;
    r.need_effective = static_cast<std::size_t>(std::ceil(opt.effective_share * static_cast<double>(P) - 1e-9));
    r.need_consistent = static_cast<std::size_t>(std::ceil(opt.consistent_share * static_cast<double>(E) - 1e-9));
    r.effective_count.assign(D, 0);
    r.consistent_count.assign(D, 0);
    r.effectiveness.assign(D, 0.0);
    // cell means f(p, e)
    std::vector<double> sum(P * E * D, 0.0);
    std::vector<std::size_t> cnt(P * E, 0);
    for (std::size_t i = 0; i < N; ++i) {
        const std::size_t p = pi[performer[i]], e = ei[emotion[i]];
        ++cnt[p * E + e];
        for (std::size_t d = 0; d < D; ++d) sum[(p * E + e) * D + d] += x(i, d);
    }
    auto pop_std = [](const std::vector<double>& v) {
        if (v.size() < 2) return std::numeric_limits<double>::quiet_NaN();
        const double m = std::accumulate(v.begin(), v.end(), 0.0) / static_cast<double>(v.size());
        double s = 0;
        for (double a : v) s += (a - m) * (a - m);
        return std::sqrt(s / static_cast<double>(v.size()));
    };
    std::vector<double> vals;
    for (std::size_t d = 0; d < D; ++d) {
        double eff_sum = 0;
        std::size_t eff_n = 0;
        for (std::size_t p = 0; p < P; ++p) {
            vals.clear();
            for (std::size_t e = 0; e < E; ++e)
                if (cnt[p * E + e]) vals.push_back(sum[(p * E + e) * D + d] / static_cast<double>(cnt[p * E + e]));
            const double s = pop_std(vals);
            if (std::isnan(s)) continue;
            eff_sum += s, ++eff_n;
            if (s >= opt.effective_std) ++r.effective_count[d];
        }
        r.effectiveness[d] = eff_n ? eff_sum / static_cast<double>(eff_n) : 0.0;
        for (std::size_t e = 0; e < E; ++e) {
            vals.clear();
            for (std::size_t p = 0; p < P; ++p)
                if (cnt[p * E + e]) vals.push_back(sum[(p * E + e) * D + d] / static_cast<double>(cnt[p * E + e]));
            const double s = pop_std(vals);
            if (!std::isnan(s) && s <= opt.consistent_std) ++r.consistent_count[d];
        }
        if (r.effective_count[d] >= r.need_effective && r.consistent_count[d] >= r.need_consistent) r.selected.push_back(d);
    }
    r.survivors = r.selected.size();
    if (r.selected.size() < opt.min_features) {
        std::vector<std::size_t> order(D);
        std::iota(order.begin(), order.end(), 0);
        // closest to passing both tests first: the smaller of the two fulfilled shares, then their sum,
        // then the mean effectiveness std
        auto share = [&](std::size_t d, bool eff) {
            const double need = static_cast<double>(std::max<std::size_t>(1, eff ? r.need_effective : r.need_consistent));
            return std::min(1.0, static_cast<double>(eff ? r.effective_count[d] : r.consistent_count[d]) / need);
        };
        std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
            const double ma = std::min(share(a, true), share(a, false)), mb = std::min(share(b, true), share(b, false));
            if (ma != mb) return ma > mb;
            const double sa = share(a, true) + share(a, false), sb = share(b, true) + share(b, false);
            if (sa != sb) return sa > sb;
            return r.effectiveness[a] > r.effectiveness[b];
        });
        for (std::size_t d : order) {
            if (r.selected.size() >= std::min(opt.min_features, D)) break;
            if (std::find(r.selected.begin(), r.selected.end(), d) == r.selected.end()) r.selected.push_back(d), r.fallback = true;
        }
        std::sort(r.selected.begin(), r.selected.end());
    }
    return r;
}

}  // namespace handemo::rcm
