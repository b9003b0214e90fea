// Labelled motion datasets for StarGAN training (Section 3.3 of the hand paper): a folder of BVH or CSV
// clips whose content (motion type) and emotion come from file names `<prefix>_<content>_<emotion>_<take>`
// (the synthetic hand set: `hand_crawling_angry_0.bvh`; Bandai: `dataset-1_walk_happy_001.bvh`) or from a
// `manifest.csv` (`path,content,emotion`). Also the tempo factors of the transfer step: Table 1's "fast" and
// "slow" cannot live in K time-normalised keyframes, so each target emotion gets a factor on the input's
// duration, estimated from its clips' durations relative to the neutral take of the same content. The
// estimator (median ratio, duration-weighted ratio, geometric mean, a robust two-way fit, or no change) is
// chosen per data set by leave-one-content-out cross-validation on the training clips (tempo_fit()): on
// Bandai, truncated neutral captures (20-31 frames) make per-take ratios of 3-13x. Optionally
// (train_options::tempo_shrink) the chosen factors are shrunk toward 1 in log space by a weight chosen by the
// same leave-one-content-out check (tempo_shrink_fit()): factors that do not carry over to a left-out content are
// pulled toward keeping the duration. The ratios are of the clips' durations (tempo_basis::duration), or of their
// cadences (tempo_basis::cadence, motion/cadence.hpp: how fast a clip moves through its own range, whatever the
// number of cycles it holds), or of whichever tempo_basis_check() finds in the training pairs (tempo_basis::automatic:
// the cadence when the durations and the cadences of the pairs disagree, as they do when takes hold different
// numbers of cycles).
#pragma once

#include <handemo/core/error.hpp>
#include <handemo/core/io.hpp>
#include <handemo/motion/bvh.hpp>
#include <handemo/motion/cadence.hpp>
#include <handemo/motion/clip.hpp>
#include <handemo/motion/csv.hpp>
#include <handemo/motion/hand.hpp>
#include <handemo/motion/labelled.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <vector>

namespace handemo::stargan {

/// @brief The parts of a clip name `<prefix>_<content>_<emotion>_<take>`.
struct clip_name {
    std::string prefix, content, emotion, take;
};

/// @brief Splits a file stem into prefix, content, emotion and take (the last three `_` fields; the
/// prefix is everything before them and may itself hold `_`).
/// @throws value_error naming the stem when it has fewer than four `_`-separated fields.
inline clip_name parse_clip_name(std::string_view stem)
{
    std::vector<std::string_view> parts;
    std::size_t start = 0;
    for (;;) {
        const std::size_t u = stem.find('_', start);
        parts.push_back(stem.substr(start, u == std::string_view::npos ? std::string_view::npos : u - start));
        if (u == std::string_view::npos) break;
        start = u + 1;
    }
    if (parts.size() < 4)
        throw value_error("dataset: file name '" + std::string(stem) +
                          "' is not <prefix>_<content>_<emotion>_<take> (and there is no manifest.csv)");
    for (auto p : parts)
        if (p.empty()) throw value_error("dataset: file name '" + std::string(stem) + "' has an empty field");
    const std::size_t n = parts.size();
    clip_name r;
    r.prefix = std::string(stem.substr(0, static_cast<std::size_t>(parts[n - 3].data() - stem.data()) - 1));
    r.content = std::string(parts[n - 3]);
    r.emotion = std::string(parts[n - 2]);
    r.take = std::string(parts[n - 1]);
    return r;
}

/// @brief Options of load_folder().
struct load_options {
    std::vector<std::string> exclude_contents;  ///< contents (motion types) left out
    std::optional<skeleton> csv_skeleton;       ///< skeleton of CSV clips (default: first BVH, else the hand)
};

namespace detail {

inline bool is_bvh(const std::filesystem::path& p)
{
    const auto e = p.extension().string();
    return e == ".bvh" || e == ".BVH";
}
inline bool is_csv(const std::filesystem::path& p)
{
    const auto e = p.extension().string();
    return e == ".csv" || e == ".CSV";
}

inline std::vector<std::string> split_csv_line(std::string_view line)
{
    std::vector<std::string> out;
    std::string cur;
    for (char ch : line) {
        if (ch == ',') {
            out.push_back(cur);
            cur.clear();
        } else if (ch != '\r') {
            cur += ch;
        }
    }
    out.push_back(cur);
    for (auto& s : out) {
        const auto b = s.find_first_not_of(" \t"), e = s.find_last_not_of(" \t");
        s = b == std::string::npos ? std::string() : s.substr(b, e - b + 1);
    }
    return out;
}

}  // namespace detail

/// @brief Parses the text of a `manifest.csv` (`path,content,emotion[,take]`, header line first) whose
/// paths are relative to `dir`.
/// @param source the file name used in error messages.
/// @throws format_error naming the file and line for a bad header or row, a path that is absolute or
///         climbs out of `dir` (`..`), or a path listed twice (naming both lines).
inline std::vector<labelled_clip> parse_manifest(std::string_view text, const std::filesystem::path& dir, const std::string& source)
{
    std::vector<labelled_clip> out;
    std::map<std::string, std::size_t> first_line;  // normalised path -> line that listed it
    std::size_t line_no = 0, pos = 0;
    bool header = true;
    auto fail = [&](const std::string& msg) -> format_error {
        return format_error("manifest: " + source + ":" + std::to_string(line_no) + ": " + msg);
    };
    while (pos <= text.size()) {
        const std::size_t nl = text.find('\n', pos);
        const std::string_view line = text.substr(pos, (nl == std::string_view::npos ? text.size() : nl) - pos);
        pos = nl == std::string_view::npos ? text.size() + 1 : nl + 1;
        ++line_no;
        if (line.find_first_not_of(" \t\r") == std::string_view::npos) continue;
        const auto f = detail::split_csv_line(line);
        if (header) {
            header = false;
            if (f.size() < 3 || f[0] != "path" || f[1] != "content" || f[2] != "emotion")
                throw fail("header is not 'path,content,emotion[,take]'");
            continue;
        }
        if (f.size() < 3 || f.size() > 4 || f[0].empty() || f[1].empty() || f[2].empty())
            throw fail("expected 3 or 4 non-empty fields, found " + std::to_string(f.size()));
        const std::filesystem::path rel(f[0]);
        if (rel.is_absolute() || rel.has_root_name() || rel.has_root_directory())
            throw fail("path '" + f[0] + "' is absolute, expected a path inside " + dir.string());
        for (const auto& part : rel)
            if (part == "..") throw fail("path '" + f[0] + "' leaves the data folder (..)");
        const std::string key = rel.lexically_normal().generic_string();
        if (const auto [it, fresh] = first_line.emplace(key, line_no); !fresh)
            throw fail("path '" + f[0] + "' is listed twice (first on line " + std::to_string(it->second) + ")");
        labelled_clip c;
        c.path = dir / rel;
        c.content = f[1];
        c.emotion = f[2];
        c.take = f.size() == 4 ? f[3] : std::to_string(out.size());
        out.push_back(std::move(c));
    }
    if (out.empty()) throw format_error("manifest: " + source + ": no clips listed");
    return out;
}

/// @brief Reads `dir/manifest.csv` (`path,content,emotion[,take]`, header line first).
/// @throws io_error when unreadable; format_error naming the file and line (see parse_manifest).
inline std::vector<labelled_clip> read_manifest(const std::filesystem::path& dir)
{
    const auto mpath = dir / "manifest.csv";
    return parse_manifest(read_file(mpath), dir, mpath.string());
}

/// @brief Loads every labelled clip of a folder (BVH preferred over a CSV of the same stem), sorted by
/// path so the order (and so training) is deterministic.
/// @throws io_error for a missing folder, value_error for a bad name, format_error for a bad file,
///         shape_error when the clips do not share one skeleton (naming the first file that differs).
inline std::vector<labelled_clip> load_folder(const std::filesystem::path& dir, const load_options& opt = {})
{
    namespace fs = std::filesystem;
    if (!is_folder(dir)) throw io_error("dataset: " + dir.string() + " is not a folder");
    std::vector<labelled_clip> items;
    if (path_exists(dir / "manifest.csv")) {
        items = read_manifest(dir);
    } else {
        std::vector<fs::path> files;
        for (const auto& f : regular_files_in(dir))
            if (detail::is_bvh(f) || detail::is_csv(f)) files.push_back(f);
        std::sort(files.begin(), files.end());
        std::set<std::string> bvh_stems;
        for (const auto& f : files)
            if (detail::is_bvh(f)) bvh_stems.insert(f.stem().string());
        for (const auto& f : files) {
            if (detail::is_csv(f) && bvh_stems.count(f.stem().string())) continue;
            const clip_name n = parse_clip_name(f.stem().string());
            labelled_clip c;
            c.path = f;
            c.content = n.content;
            c.emotion = n.emotion;
            c.take = n.take;
            items.push_back(std::move(c));
        }
    }
    std::sort(items.begin(), items.end(), [](const auto& a, const auto& b) { return a.path < b.path; });
    std::vector<labelled_clip> kept;
    for (auto& c : items)
        if (std::find(opt.exclude_contents.begin(), opt.exclude_contents.end(), c.content) == opt.exclude_contents.end())
            kept.push_back(std::move(c));
    if (kept.empty()) throw value_error("dataset: no motion clips in " + dir.string() + " (after exclusions)");

    std::optional<skeleton> csv_skel = opt.csv_skeleton;
    for (auto& c : kept) {
        if (detail::is_bvh(c.path)) {
            c.motion = read_bvh(c.path);
            if (!csv_skel) csv_skel = c.motion.skel;
        }
    }
    for (auto& c : kept)
        if (detail::is_csv(c.path)) c.motion = read_csv(c.path, csv_skel ? *csv_skel : hand_skeleton());
    for (const auto& c : kept)
        if (!c.motion.skel.same_topology(kept.front().motion.skel))
            throw shape_error("dataset: " + c.path.string() + " has a skeleton of " + std::to_string(c.motion.skel.size()) +
                              " joints that differs from " + kept.front().path.string() + " (" +
                              std::to_string(kept.front().motion.skel.size()) + " joints)");
    return kept;
}

/// @brief Distinct contents of a dataset, sorted.
inline std::vector<std::string> contents_of(const std::vector<labelled_clip>& d)
{
    std::set<std::string> s;
    for (const auto& c : d) s.insert(c.content);
    return {s.begin(), s.end()};
}

/// @brief The tempo estimators tempo_fit() chooses from, simplest first (the order breaks ties).
enum class tempo_estimator : std::uint8_t {
    keep,      ///< 1: keep the input's duration
    median,    ///< median over pairs of duration / paired neutral duration
    weighted,  ///< sum of durations / sum of the paired neutral durations (duration-weighted ratio)
    log_mean,  ///< exp of the mean log ratio: the least-squares fit of log duration = take effect + style effect
    two_way,   ///< Tukey's median polish of log duration = take effect + style effect (robust two-way fit)
};
inline constexpr std::size_t tempo_estimator_count = 5;

/// @brief Name of an estimator: keep, median, weighted, log-mean, two-way.
constexpr std::string_view to_string(tempo_estimator e) noexcept
{
    constexpr std::string_view n[] = {"keep", "median", "weighted", "log-mean", "two-way"};
    return n[static_cast<int>(e)];
}

/// @brief What the tempo factors are ratios of (train_options::tempo_basis).
enum class tempo_basis : std::uint8_t {
    duration,   ///< the clips' durations: the transfer's output lasts the input's duration times the factor
    cadence,    ///< the clips' cadence_time() (motion/cadence.hpp): the factor is how much slower the emotion moves
    automatic,  ///< the cadence when tempo_basis_check() finds that the training pairs' durations and cadences disagree
};

/// @brief Name of a basis: duration, cadence, auto.
constexpr std::string_view to_string(tempo_basis b) noexcept
{
    constexpr std::string_view n[] = {"duration", "cadence", "auto"};
    return n[static_cast<int>(b)];
}

/// @brief The basis named `name` (duration, cadence, auto).
/// @throws value_error naming `what` (the option) and the accepted names.
inline tempo_basis parse_tempo_basis(std::string_view name, const std::string& what = "tempo_basis")
{
    for (auto b : {tempo_basis::duration, tempo_basis::cadence, tempo_basis::automatic})
        if (name == to_string(b)) return b;
    throw value_error(what + " '" + std::string(name) + "' is not duration, cadence or auto");
}

/// @brief The median disagreement above which tempo_basis_check() chooses the cadence: log(1.25), the durations
/// and the cadences of half the pairs differing by more than a quarter.
inline const double tempo_basis_threshold = std::log(1.25);

/// @brief What tempo_basis::automatic found in the training pairs.
struct tempo_basis_choice {
    tempo_basis basis = tempo_basis::duration;  ///< duration or cadence
    /// median over the (emotion clip, neutral clip) pairs of |log(duration ratio) - log(cadence ratio)|: 0 when every
    /// take of a content holds the same number of cycles; NaN without pairs
    double disagreement = std::nan("");
    std::size_t pairs = 0;  ///< the pairs it was measured on
};

/// @brief One candidate of tempo_fit(): its factors on the whole set and its cross-validation error.
struct tempo_candidate {
    tempo_estimator estimator;
    std::vector<double> factors;  ///< [C] fitted on every given clip
    double cv_error;              ///< mean over contents of the mean |log(predicted / real ratio)|; NaN without CV
};

/// @brief The tempo factors tempo_fit() chose, the estimator that made them and every candidate's score.
struct tempo_fit_result {
    std::vector<double> factors;            ///< [C] the chosen estimator's factors
    tempo_estimator estimator;              ///< the chosen estimator
    std::vector<tempo_candidate> candidates;  ///< every estimator, in tempo_estimator order
    std::size_t cv_contents = 0;            ///< contents scored by leave-one-content-out (0: no CV, fallback)
    std::size_t pairs = 0;                  ///< (emotion clip, neutral) pairs in the given clips
    /// with shrinking (tempo_fit(..., true)): the weight applied (shrink_tempo()) and the check's error of every
    /// weight of tempo_shrink_grid; without: 0 and empty
    double shrink_weight = 0;
    std::vector<double> shrink_errors;
    /// the basis the factors are ratios of (duration or cadence) and, for tempo_basis::automatic, what decided it
    tempo_basis_choice basis;
};

/// @brief The weights tempo_shrink_fit() chooses from: 0 keeps the fitted factors, 1 keeps the input's duration.
inline constexpr std::array<double, 5> tempo_shrink_grid{0.0, 0.25, 0.5, 0.75, 1.0};

/// @brief Tempo factors shrunk toward 1 in log space: exp((1 - w) log f) for each factor (w = 0: unchanged, w = 1:
/// all 1).
inline std::vector<double> shrink_tempo(std::vector<double> factors, double w)
{
    for (auto& f : factors) f = w == 0.0 ? f : std::exp((1.0 - w) * std::log(f));
    return factors;
}

/// @brief The leave-one-content-out check of the shrink weight: its error per weight and the weight chosen.
struct tempo_shrink_check {
    std::vector<double> errors;  ///< [tempo_shrink_grid] mean over contents of the mean |log(predicted / real ratio)|; NaN without CV
    double weight = 0;           ///< the lowest error's weight (ties to less shrinkage); 0 without CV
    std::size_t contents = 0;    ///< contents scored (0: fewer than two contents hold pairs, no check)
};

namespace detail {

/// The per-clip quantity the tempo factors are ratios of: the duration, or the cadence (computed once per clip).
struct tempo_values {
    tempo_basis basis = tempo_basis::duration;  ///< duration or cadence
    std::map<const labelled_clip*, double> cadence;
    /// the clip's value; 0 when it has none (a cadence of a clip that does not move)
    double operator()(const labelled_clip* c) const
    {
        if (basis == tempo_basis::duration) return c->motion.duration();
        const auto it = cadence.find(c);
        return it == cadence.end() ? 0.0 : it->second;
    }
};

/// The values of basis `b` (duration or cadence) for every clip of `d`.
inline tempo_values make_tempo_values(const std::vector<const labelled_clip*>& d, tempo_basis b)
{
    tempo_values v;
    v.basis = b == tempo_basis::cadence ? tempo_basis::cadence : tempo_basis::duration;
    if (v.basis == tempo_basis::cadence)
        for (const auto* c : d) v.cadence[c] = ::handemo::detail::cadence_time_of(c->motion, cadence_smooth_seconds);
    return v;
}

/// One emotion clip and the neutral value it is compared with (same content and take, otherwise the mean over the
/// content's neutral takes); the values are durations or cadences (tempo_values).
struct tempo_pair {
    std::size_t domain;
    std::string content;
    double value, neutral_value;
    double ratio() const noexcept { return value / neutral_value; }
};

inline std::vector<tempo_pair> tempo_pairs(const std::vector<const labelled_clip*>& d, const std::vector<std::string>& domains,
                                           const std::string& neutral, const tempo_values& v)
{
    std::map<std::pair<std::string, std::string>, double> neutral_by_take;
    std::map<std::string, std::pair<double, int>> neutral_mean;
    for (const auto* c : d)
        if (c->emotion == neutral && v(c) > 0) {
            neutral_by_take[{c->content, c->take}] = v(c);
            auto& m = neutral_mean[c->content];
            m.first += v(c);
            m.second += 1;
        }
    std::vector<tempo_pair> out;
    for (const auto* c : d) {
        if (c->emotion == neutral) continue;
        const auto k = std::find(domains.begin(), domains.end(), c->emotion);
        if (k == domains.end()) continue;
        double base = 0;
        if (auto it = neutral_by_take.find({c->content, c->take}); it != neutral_by_take.end())
            base = it->second;
        else if (auto m = neutral_mean.find(c->content); m != neutral_mean.end())
            base = m->second.first / m->second.second;
        if (base > 0 && v(c) > 0) out.push_back({static_cast<std::size_t>(k - domains.begin()), c->content, v(c), base});
    }
    return out;
}

inline double median_of(std::vector<double> v)
{
    std::sort(v.begin(), v.end());
    const std::size_t n = v.size();
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

/// Tukey's median polish of the log value (duration or cadence) over rows (content, take) and columns (domains): alternately
/// subtract row and column medians of the residuals. Returns exp(column effect - neutral column effect).
inline std::vector<double> tempo_two_way(const std::vector<const labelled_clip*>& d, const std::vector<std::string>& domains,
                                         const std::string& neutral, const tempo_values& v)
{
    std::vector<double> out(domains.size(), 1.0);
    const auto nk = std::find(domains.begin(), domains.end(), neutral);
    if (nk == domains.end()) return out;
    // cells: row index, column index, residual (the mean log duration of the clips in the cell)
    std::map<std::pair<std::string, std::string>, std::size_t> row_of;
    std::map<std::pair<std::size_t, std::size_t>, std::pair<double, int>> sums;
    for (const auto* c : d) {
        const auto k = std::find(domains.begin(), domains.end(), c->emotion);
        if (k == domains.end() || !(v(c) > 0)) continue;
        const auto row = row_of.try_emplace({c->content, c->take}, row_of.size()).first->second;
        auto& s = sums[{row, static_cast<std::size_t>(k - domains.begin())}];
        s.first += std::log(v(c));
        s.second += 1;
    }
    struct cell {
        std::size_t row, col;
        double res;
    };
    std::vector<cell> cells;
    for (const auto& [rc, s] : sums) cells.push_back({rc.first, rc.second, s.first / s.second});
    std::vector<double> col_effect(domains.size(), 0.0);
    std::vector<bool> has_col(domains.size(), false);
    for (const auto& c : cells) has_col[c.col] = true;
    const std::size_t neutral_col = static_cast<std::size_t>(nk - domains.begin());
    if (!has_col[neutral_col]) return out;
    auto sweep = [&](bool rows, std::size_t count) {
        double moved = 0;
        for (std::size_t i = 0; i < count; ++i) {
            std::vector<double> v;
            for (const auto& c : cells)
                if ((rows ? c.row : c.col) == i) v.push_back(c.res);
            if (v.empty()) continue;
            const double m = median_of(std::move(v));
            if (!rows) col_effect[i] += m;
            for (auto& c : cells)
                if ((rows ? c.row : c.col) == i) c.res -= m;
            moved = std::max(moved, std::abs(m));
        }
        return moved;
    };
    for (int it = 0; it < 100; ++it) {
        const double moved = std::max(sweep(true, row_of.size()), sweep(false, domains.size()));
        if (moved < 1e-12) break;
    }
    for (std::size_t k = 0; k < domains.size(); ++k)
        if (has_col[k] && k != neutral_col) out[k] = std::exp(col_effect[k] - col_effect[neutral_col]);
    return out;
}

inline std::vector<double> tempo_estimate(tempo_estimator e, const std::vector<const labelled_clip*>& d,
                                          const std::vector<std::string>& domains, const std::string& neutral, const tempo_values& v)
{
    std::vector<double> out(domains.size(), 1.0);
    if (e == tempo_estimator::keep) return out;
    if (e == tempo_estimator::two_way) return tempo_two_way(d, domains, neutral, v);
    const auto pairs = tempo_pairs(d, domains, neutral, v);
    for (std::size_t k = 0; k < domains.size(); ++k) {
        std::vector<double> ratios;
        double num = 0, den = 0, logs = 0;
        for (const auto& p : pairs)
            if (p.domain == k) ratios.push_back(p.ratio()), num += p.value, den += p.neutral_value, logs += std::log(p.ratio());
        if (ratios.empty()) continue;
        switch (e) {
        case tempo_estimator::median: out[k] = median_of(std::move(ratios)); break;
        case tempo_estimator::weighted: out[k] = num / den; break;
        default: out[k] = std::exp(logs / static_cast<double>(ratios.size())); break;  // log_mean
        }
    }
    return out;
}

}  // namespace detail

/// @brief The tempo factors of one estimator (see tempo_estimator): per domain, the duration (or with
/// tempo_basis::cadence the cadence_time()) of its clips relative to the neutral clip of the same content (the same
/// take when there is one, otherwise the mean over the content's neutral takes). Domains without data, and the
/// neutral domain itself, get 1.
/// @param domains domain names in label order; @param neutral name of the neutral domain
/// @param basis duration or cadence (tempo_basis::automatic is tempo_fit()'s: it reads as duration here)
/// @return [C] factors
inline std::vector<double> tempo_estimate(tempo_estimator e, const std::vector<labelled_clip>& d,
                                          const std::vector<std::string>& domains, const std::string& neutral,
                                          tempo_basis basis = tempo_basis::duration)
{
    std::vector<const labelled_clip*> p;
    for (const auto& c : d) p.push_back(&c);
    return detail::tempo_estimate(e, p, domains, neutral, detail::make_tempo_values(p, basis));
}

namespace detail {

inline tempo_basis_choice tempo_basis_check(const std::vector<const labelled_clip*>& all, const std::vector<std::string>& domains,
                                            const std::string& neutral, const tempo_values& cadence)
{
    // the clips that have a cadence (a clip that does not move has none), so that both lists hold the same pairs
    std::vector<const labelled_clip*> moving;
    for (const auto* c : all)
        if (cadence(c) > 0) moving.push_back(c);
    const auto by_duration = tempo_pairs(moving, domains, neutral, make_tempo_values(moving, tempo_basis::duration));
    const auto by_cadence = tempo_pairs(moving, domains, neutral, cadence);
    tempo_basis_choice r;
    std::vector<double> gaps;
    for (std::size_t i = 0; i < std::min(by_duration.size(), by_cadence.size()); ++i)
        gaps.push_back(std::abs(std::log(by_duration[i].ratio()) - std::log(by_cadence[i].ratio())));
    r.pairs = gaps.size();
    if (gaps.empty()) return r;
    r.disagreement = median_of(gaps);
    r.basis = r.disagreement > tempo_basis_threshold ? tempo_basis::cadence : tempo_basis::duration;
    return r;
}

/// The leave-one-content-out check tempo_fit(), tempo_shrink_fit() and tempo_neighbours_fit() score their candidates
/// by: for each content of `scored` (in order), `fit(train, held)` on the clips of the other contents gives one factor
/// vector per candidate for the left-out content `held`; a candidate's score is the mean over the contents of the mean
/// |log(factor / real ratio)| over that content's pairs.
template <class Fit>
std::vector<double> tempo_loo_scores(const std::vector<const labelled_clip*>& all, const std::vector<tempo_pair>& pairs,
                                     const std::set<std::string>& scored, std::size_t candidates, Fit&& fit)
{
    std::vector<double> total(candidates, 0.0);
    for (const auto& held : scored) {
        std::vector<const labelled_clip*> train;
        for (const auto* c : all)
            if (c->content != held) train.push_back(c);
        const std::vector<std::vector<double>> factors = fit(train, held);
        for (std::size_t i = 0; i < candidates; ++i) {
            const auto& f = factors[i];
            double err = 0;
            std::size_t n = 0;
            for (const auto& p : pairs)
                if (p.content == held) err += std::abs(std::log(f[p.domain] / p.ratio())), ++n;
            total[i] += err / static_cast<double>(n);
        }
    }
    for (auto& t : total) t /= static_cast<double>(scored.size());
    return total;
}

inline tempo_shrink_check tempo_shrink_fit(const std::vector<const labelled_clip*>& all, const std::vector<std::string>& domains,
                                           const std::string& neutral, tempo_estimator e, const tempo_values& values)
{
    const auto pairs = tempo_pairs(all, domains, neutral, values);
    std::set<std::string> scored;
    for (const auto& p : pairs) scored.insert(p.content);
    tempo_shrink_check r;
    r.errors.assign(tempo_shrink_grid.size(), std::nan(""));
    if (scored.size() < 2) return r;
    r.contents = scored.size();
    r.errors = tempo_loo_scores(all, pairs, scored, tempo_shrink_grid.size(), [&](const std::vector<const labelled_clip*>& train, const std::string&) {
        const auto fitted = tempo_estimate(e, train, domains, neutral, values);
        std::vector<std::vector<double>> f;
        for (double w : tempo_shrink_grid) f.push_back(shrink_tempo(fitted, w));
        return f;
    });
    std::size_t best = 0;
    for (std::size_t w = 0; w < tempo_shrink_grid.size(); ++w)
        if (r.errors[w] < r.errors[best] - 1e-12) best = w;
    r.weight = tempo_shrink_grid[best];
    return r;
}

}  // namespace detail

/// @brief tempo_basis::automatic's choice on `d` (pass the training set): the median over the (emotion clip, neutral
/// clip) pairs of |log(duration ratio) - log(cadence ratio)|. A take's duration is its cadence times the number of
/// cycles it holds (motion/cadence.hpp), so the two ratios agree when the takes of a content hold the same number
/// of cycles (the synthetic hand set: two cycles each) and disagree when they do not (captures cut to fragments,
/// walks of different lengths). Above tempo_basis_threshold the durations are mostly counting cycles, which the
/// transfer keeps from its input, and the cadence is chosen; at or below it the duration (the simpler, and the
/// basis when the two agree). Without pairs: duration.
/// @param domains domain names in label order; @param neutral name of the neutral domain
inline tempo_basis_choice tempo_basis_check(const std::vector<labelled_clip>& d, const std::vector<std::string>& domains,
                                            const std::string& neutral)
{
    std::vector<const labelled_clip*> all;
    for (const auto& c : d) all.push_back(&c);
    return detail::tempo_basis_check(all, domains, neutral, detail::make_tempo_values(all, tempo_basis::cadence));
}

namespace detail {

/// tempo_fit() of the clips `all` points to.
inline tempo_fit_result tempo_fit(const std::vector<const labelled_clip*>& all, const std::vector<std::string>& domains,
                                  const std::string& neutral, bool shrink, tempo_basis basis)
{
    tempo_fit_result r;
    auto values = detail::make_tempo_values(all, basis == tempo_basis::duration ? tempo_basis::duration : tempo_basis::cadence);
    if (basis == tempo_basis::automatic) {
        r.basis = detail::tempo_basis_check(all, domains, neutral, values);
        if (r.basis.basis == tempo_basis::duration) values = detail::make_tempo_values(all, tempo_basis::duration);
    } else {
        r.basis.basis = basis;
    }
    const auto pairs = detail::tempo_pairs(all, domains, neutral, values);
    std::set<std::string> scored;
    for (const auto& p : pairs) scored.insert(p.content);

    r.pairs = pairs.size();
    r.cv_contents = scored.size() >= 2 ? scored.size() : 0;
    for (std::size_t i = 0; i < tempo_estimator_count; ++i) {
        const auto e = static_cast<tempo_estimator>(i);
        r.candidates.push_back({e, detail::tempo_estimate(e, all, domains, neutral, values), std::nan("")});
    }
    if (r.cv_contents == 0) {
        r.estimator = tempo_estimator::weighted;
        r.factors = r.candidates[static_cast<std::size_t>(r.estimator)].factors;
        return r;
    }
    const auto scores = detail::tempo_loo_scores(all, pairs, scored, tempo_estimator_count, [&](const std::vector<const labelled_clip*>& train, const std::string&) {
        std::vector<std::vector<double>> f;
        for (std::size_t i = 0; i < tempo_estimator_count; ++i)
            f.push_back(detail::tempo_estimate(static_cast<tempo_estimator>(i), train, domains, neutral, values));
        return f;
    });
    std::size_t best = 0;
    for (std::size_t i = 0; i < tempo_estimator_count; ++i) {
        r.candidates[i].cv_error = scores[i];
        if (r.candidates[i].cv_error < r.candidates[best].cv_error - 1e-12) best = i;
    }
    r.estimator = static_cast<tempo_estimator>(best);
    r.factors = r.candidates[best].factors;
    if (shrink) {
        const auto check = detail::tempo_shrink_fit(all, domains, neutral, r.estimator, values);
        r.shrink_weight = check.weight;
        r.shrink_errors = check.errors;
        r.factors = shrink_tempo(std::move(r.factors), check.weight);
    }
    return r;
}

}  // namespace detail

/// @brief Fits the tempo factors of the transfer step: every tempo_estimator is scored by leave-one-content-out
/// cross-validation inside `d` (for each content holding (emotion, neutral) pairs: fit on the other contents,
/// error = mean over that content's pairs of |log(predicted factor / real ratio)|; the score is the mean of these
/// errors over the contents) and the estimator with the lowest score wins, ties going to the simpler (earlier in
/// tempo_estimator). The ratios are of durations or cadences (`basis`; tempo_basis::automatic decides by
/// tempo_basis_check() on `d`). Only the given clips are used: pass the training set, never held-out data. With
/// fewer than two contents holding pairs there is no cross-validation: `weighted` is used and every cv_error is NaN.
/// With `shrink` the chosen factors are then shrunk toward 1 by the weight tempo_shrink_fit() chooses for the
/// chosen estimator (train_options::tempo_shrink).
/// @param domains domain names in label order; @param neutral name of the neutral domain
/// @return the chosen factors ([C], 1 for the neutral domain and domains without data), the estimator, every
///         candidate's factors and score, and the basis.
inline tempo_fit_result tempo_fit(const std::vector<labelled_clip>& d, const std::vector<std::string>& domains,
                                  const std::string& neutral, bool shrink = false, tempo_basis basis = tempo_basis::duration)
{
    std::vector<const labelled_clip*> all;
    for (const auto& c : d) all.push_back(&c);
    return detail::tempo_fit(all, domains, neutral, shrink, basis);
}

/// @brief The shrink weight of one estimator's factors, chosen inside `d` by leave-one-content-out: for each weight
/// w of tempo_shrink_grid and each content holding (emotion, neutral) pairs, the estimator is fitted on the other
/// contents, its factors shrunk by w (shrink_tempo()), and the error is the mean over that content's pairs of
/// |log(predicted factor / real ratio)|; a weight's score is the mean of these errors over the contents
/// (tempo_fit()'s score for the estimator at w = 0). The lowest score wins, ties (within 1e-12) going to less
/// shrinkage. Factors that hold on every content keep weight 0; factors that no left-out content follows are
/// shrunk. Only the given clips are used: pass the training set.
/// @param domains domain names in label order; @param neutral name of the neutral domain
/// @param basis duration or cadence, the ratios' basis (tempo_basis::automatic reads as duration here)
inline tempo_shrink_check tempo_shrink_fit(const std::vector<labelled_clip>& d, const std::vector<std::string>& domains,
                                           const std::string& neutral, tempo_estimator e, tempo_basis basis = tempo_basis::duration)
{
    std::vector<const labelled_clip*> all;
    for (const auto& c : d) all.push_back(&c);
    return detail::tempo_shrink_fit(all, domains, neutral, e, detail::make_tempo_values(all, basis));
}

/// @brief Tempo factor per domain: tempo_fit()'s choice (used by prepare_data() and stored in checkpoints), shrunk
/// by the checked weight when `shrink` (train_options::tempo_shrink), of durations or cadences (`basis`,
/// train_options::tempo_basis).
/// @param domains domain names in label order; @param neutral name of the neutral domain
inline std::vector<double> tempo_factors(const std::vector<labelled_clip>& d, const std::vector<std::string>& domains,
                                         const std::string& neutral, bool shrink = false, tempo_basis basis = tempo_basis::duration)
{
    return tempo_fit(d, domains, neutral, shrink, basis).factors;
}

}  // namespace handemo::stargan
