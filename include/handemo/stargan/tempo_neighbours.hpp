// Tempo from the nearest training contents (train_options::tempo_neighbours). The learned tempo factors
// (tempo_fit(), dataset.hpp) are one number per emotion for every input. Where the training contents change their
// durations differently (Bandai's gestures against its walks), that one number fits no content well. With this
// option the factors of an input are the mean log ratio of the K training contents whose neutral clips are most
// like the input:
//   log tempo_d(input) = (1 / K') sum_{c in the K nearest contents with pairs of domain d} r_cd,
// r_cd the mean over content c's (emotion d, neutral) pairs of log(value / neutral value) (durations or cadences, the
// basis tempo_fit() uses), K' <= K those of the K nearest that have such pairs (none: the learned factor). "Like"
// is the Euclidean distance between standardised content descriptors: the 8 clip-level features of
// metrics::full_rate_features() (log duration, log mean speed, log acceleration, log root speed, tremor frequency
// and share, the spread and mean of the joints' lags), a content's descriptor the mean over its neutral clips, each
// feature standardised by its mean and deviation over the training contents (a feature that does not vary is left
// out). K is chosen inside the training clips by the leave-one-content-out check tempo_fit() scores its estimators
// by: each content is left out in turn, its neutral clips stand for the input, the factors come from the other
// contents, and the error is the mean over its pairs of |log(factor / real ratio)|. The candidates are the learned
// factors themselves and K = 3, 2, 1, in that order; the lowest mean error wins and a tie goes to the earlier, so
// neighbours replace the learned factors only where the training set says they predict a left-out content better.
#pragma once

#include <handemo/core/error.hpp>
#include <handemo/metrics/full_rate_judge.hpp>
#include <handemo/stargan/dataset.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <limits>
#include <map>
#include <set>
#include <string>
#include <utility>
#include <vector>

namespace handemo::stargan {

/// @brief The neighbour counts the check tries after the learned factors, in the order a tie is decided.
inline constexpr std::array<std::size_t, 3> tempo_neighbour_grid{3, 2, 1};

/// @brief The number of values of a content descriptor (tempo_descriptor()).
inline constexpr std::size_t tempo_descriptor_size = 8;

/// @brief A clip's content descriptor: the 8 clip-level values of metrics::full_rate_features() (see the header
/// comment). Empty for a clip too short to describe (fewer than 5 frames): such an input keeps the learned factors.
inline std::vector<double> tempo_descriptor(const clip& c)
{
    if (c.frames < 5 || !(c.fps > 0) || !std::isfinite(c.fps)) return {};
    const auto f = metrics::full_rate_features(c);
    return {f.end() - static_cast<std::ptrdiff_t>(tempo_descriptor_size), f.end()};
}

/// @brief What a model needs to give an input its neighbours' tempo: each training content's descriptor and mean log
/// ratio per domain, the standardisation, K, and the check that chose K. k == 0: the learned factors (no table).
struct tempo_neighbours {
    std::size_t k = 0;                             ///< neighbours averaged; 0: the learned factors for every input
    std::vector<std::string> contents;             ///< [N] the training contents, sorted
    std::vector<std::vector<double>> descriptors;  ///< [N][8] each content's descriptor (mean over its neutral clips)
    std::vector<std::vector<double>> log_ratios;   ///< [N][C] mean log ratio per domain; NaN where the content has no pair
    std::vector<double> mean, scale;               ///< [8] the standardisation; scale 0: the feature is left out
    /// the check: the mean left-out error of the learned factors, then of K = 3, 2, 1 (tempo_neighbour_grid); NaN
    /// without a check (fewer than two contents with pairs and described neutral clips)
    std::vector<double> errors;

    bool empty() const noexcept { return k == 0; }

    /// @brief The factors [C] for an input of descriptor `d` (tempo_descriptor()): exp of the mean log ratio of the k
    /// nearest contents that have pairs of each domain; `learned` (the model's factors) for a domain none of them
    /// has, for every domain when the table is empty or `d` is (a clip too short to describe).
    /// @throws shape_error when `d` or `learned` has the wrong length.
    std::vector<double> factors(const std::vector<double>& d, const std::vector<double>& learned) const
    {
        if (empty() || d.empty()) return learned;
        if (d.size() != mean.size())
            throw shape_error("tempo_neighbours: a descriptor of " + std::to_string(d.size()) + " values, expected " + std::to_string(mean.size()));
        const std::size_t C = log_ratios.empty() ? 0 : log_ratios.front().size();
        if (learned.size() != C)
            throw shape_error("tempo_neighbours: " + std::to_string(learned.size()) + " learned factors for " + std::to_string(C) + " domains");
        const auto order = nearest(d);
        std::vector<double> out(learned);
        for (std::size_t c = 0; c < C; ++c) {
            double s = 0;
            std::size_t n = 0;
            for (std::size_t i = 0; i < std::min(k, order.size()); ++i)
                if (const double r = log_ratios[order[i]][c]; std::isfinite(r)) s += r, ++n;
            if (n) out[c] = std::exp(s / static_cast<double>(n));
        }
        return out;
    }

    /// @brief The contents in order of distance from descriptor `d` (ties in the contents' order).
    std::vector<std::size_t> nearest(const std::vector<double>& d) const
    {
        std::vector<std::pair<double, std::size_t>> dist;
        for (std::size_t i = 0; i < descriptors.size(); ++i) {
            double s = 0;
            for (std::size_t f = 0; f < d.size(); ++f)
                if (scale[f] > 0) {
                    const double z = (descriptors[i][f] - d[f]) / scale[f];
                    s += z * z;
                }
            dist.emplace_back(s, i);
        }
        std::stable_sort(dist.begin(), dist.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
        std::vector<std::size_t> out;
        for (const auto& [s, i] : dist) out.push_back(i);
        return out;
    }
};

namespace detail {

/// Each content's descriptor (mean over its described neutral clips) and mean log ratio per domain, of the contents
/// that have both; the clips' pairs as tempo_pairs() makes them.
struct tempo_content_table {
    std::vector<std::string> contents;
    std::vector<std::vector<double>> descriptors, log_ratios;
};

inline tempo_content_table tempo_contents(const std::vector<const labelled_clip*>& all, const std::vector<std::string>& domains,
                                          const std::string& neutral, const tempo_values& values,
                                          const std::map<const labelled_clip*, std::vector<double>>& described)
{
    std::map<std::string, std::pair<std::vector<double>, int>> desc;
    for (const auto* c : all) {
        if (c->emotion != neutral) continue;
        const auto it = described.find(c);
        if (it == described.end() || it->second.empty()) continue;
        auto& [sum, n] = desc[c->content];
        if (sum.empty()) sum.assign(it->second.size(), 0.0);
        for (std::size_t f = 0; f < sum.size(); ++f) sum[f] += it->second[f];
        ++n;
    }
    std::map<std::string, std::vector<std::pair<double, int>>> ratio;
    for (const auto& p : tempo_pairs(all, domains, neutral, values)) {
        auto& r = ratio[p.content];
        if (r.empty()) r.assign(domains.size(), {0.0, 0});
        r[p.domain].first += std::log(p.ratio()), r[p.domain].second += 1;
    }
    tempo_content_table t;
    for (const auto& [content, d] : desc) {  // std::map: sorted by name
        const auto it = ratio.find(content);
        if (it == ratio.end()) continue;
        t.contents.push_back(content);
        std::vector<double> m(d.first);
        for (auto& v : m) v /= d.second;
        t.descriptors.push_back(std::move(m));
        std::vector<double> r(domains.size(), std::nan(""));
        for (std::size_t k = 0; k < domains.size(); ++k)
            if (it->second[k].second) r[k] = it->second[k].first / it->second[k].second;
        t.log_ratios.push_back(std::move(r));
    }
    return t;
}

/// A table of the given contents (all but `skip`; SIZE_MAX: none) with k neighbours and its standardisation.
inline tempo_neighbours tempo_table_without(const tempo_content_table& t, std::size_t skip, std::size_t k)
{
    tempo_neighbours n;
    n.k = k;
    for (std::size_t i = 0; i < t.contents.size(); ++i)
        if (i != skip) n.contents.push_back(t.contents[i]), n.descriptors.push_back(t.descriptors[i]), n.log_ratios.push_back(t.log_ratios[i]);
    const std::size_t F = n.descriptors.empty() ? 0 : n.descriptors.front().size();
    const double N = static_cast<double>(n.descriptors.size());
    n.mean.assign(F, 0.0), n.scale.assign(F, 0.0);
    for (const auto& d : n.descriptors)
        for (std::size_t f = 0; f < F; ++f) n.mean[f] += d[f] / N;
    for (const auto& d : n.descriptors)
        for (std::size_t f = 0; f < F; ++f) n.scale[f] += (d[f] - n.mean[f]) * (d[f] - n.mean[f]) / N;
    for (auto& s : n.scale) s = s > 1e-18 ? std::sqrt(s) : 0.0;
    return n;
}

}  // namespace detail

/// @brief Fits the tempo neighbours on the training clips `d` (see the header comment): the check chooses between
/// the factors tempo_fit() learns (with the same basis; shrinking, when asked, applies to those only) and K = 3, 2, 1
/// neighbours; the table is empty (k == 0) when the learned factors win, or when fewer than two contents have pairs
/// and described neutral clips (no check, errors NaN). Only the given clips are used: pass the training set.
/// @param domains domain names in label order; @param neutral name of the neutral domain
inline tempo_neighbours tempo_neighbours_fit(const std::vector<labelled_clip>& d, const std::vector<std::string>& domains,
                                             const std::string& neutral, bool shrink = false, tempo_basis basis = tempo_basis::duration)
{
    std::vector<const labelled_clip*> all;
    for (const auto& c : d) all.push_back(&c);
    const auto chosen = detail::tempo_fit(all, domains, neutral, shrink, basis).basis.basis;
    const auto values = detail::make_tempo_values(all, chosen);
    std::map<const labelled_clip*, std::vector<double>> described;
    for (const auto* c : all)
        if (c->emotion == neutral) described[c] = tempo_descriptor(c->motion);
    const auto table = detail::tempo_contents(all, domains, neutral, values, described);
    tempo_neighbours out;
    out.errors.assign(1 + tempo_neighbour_grid.size(), std::nan(""));
    if (table.contents.size() < 2) return out;
    const std::set<std::string> scored(table.contents.begin(), table.contents.end());
    out.errors = detail::tempo_loo_scores(all, detail::tempo_pairs(all, domains, neutral, values), scored, out.errors.size(),
                                          [&](const std::vector<const labelled_clip*>& train, const std::string& held) {
                                              const std::size_t h = static_cast<std::size_t>(
                                                  std::find(table.contents.begin(), table.contents.end(), held) - table.contents.begin());
                                              std::vector<std::vector<double>> f{detail::tempo_fit(train, domains, neutral, shrink, chosen).factors};
                                              for (std::size_t k : tempo_neighbour_grid)
                                                  f.push_back(detail::tempo_table_without(table, h, k).factors(table.descriptors[h], f.front()));
                                              return f;
                                          });
    std::size_t best = 0;
    for (std::size_t i = 0; i < out.errors.size(); ++i)
        if (out.errors[i] < out.errors[best] - 1e-12) best = i;
    if (best == 0) return out;
    auto errors = std::move(out.errors);
    out = detail::tempo_table_without(table, std::numeric_limits<std::size_t>::max(), tempo_neighbour_grid[best - 1]);
    out.errors = std::move(errors);
    return out;
}

}  // namespace handemo::stargan
