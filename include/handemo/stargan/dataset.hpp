// Labelled motion datasets for StarGAN training (Section 3.3 of the hand paper): a folder of BVH or CSV
// clips whose content (motion type) and emotion come from file names `<prefix>_<content>_<emotion>_<take>`
// (the synthetic hand set: `hand_crawling_angry_0.bvh`; Bandai: `dataset-1_walk_happy_001.bvh`) or from a
// `manifest.csv` (`path,content,emotion`). Also the tempo factors of the transfer step: Table 1's "fast" and
// "slow" cannot live in K time-normalised keyframes, so each target emotion gets the median ratio of its
// clips' durations to the neutral take of the same content.
#pragma once

#include <handemo/core/error.hpp>
#include <handemo/core/io.hpp>
#include <handemo/motion/bvh.hpp>
#include <handemo/motion/clip.hpp>
#include <handemo/motion/csv.hpp>
#include <handemo/motion/hand.hpp>

#include <algorithm>
#include <cmath>
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

/// @brief One labelled clip.
struct labelled_clip {
    std::filesystem::path path;
    std::string content;
    std::string emotion;
    std::string take;
    clip motion;
};

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

/// @brief Reads `dir/manifest.csv` (`path,content,emotion[,take]`, header line first).
/// @throws format_error naming the file and line.
inline std::vector<labelled_clip> read_manifest(const std::filesystem::path& dir)
{
    const auto mpath = dir / "manifest.csv";
    const std::string text = read_file(mpath);
    std::vector<labelled_clip> out;
    std::size_t line_no = 0, pos = 0;
    bool header = true;
    while (pos <= text.size()) {
        const std::size_t nl = text.find('\n', pos);
        const std::string_view line(text.data() + pos, (nl == std::string::npos ? text.size() : nl) - pos);
        pos = nl == std::string::npos ? text.size() + 1 : nl + 1;
        ++line_no;
        if (line.find_first_not_of(" \t\r") == std::string_view::npos) continue;
        const auto f = detail::split_csv_line(line);
        if (header) {
            header = false;
            if (f.size() < 3 || f[0] != "path" || f[1] != "content" || f[2] != "emotion")
                throw format_error("manifest: " + mpath.string() + ":" + std::to_string(line_no) +
                                   ": header is not 'path,content,emotion[,take]'");
            continue;
        }
        if (f.size() < 3 || f.size() > 4 || f[0].empty() || f[1].empty() || f[2].empty())
            throw format_error("manifest: " + mpath.string() + ":" + std::to_string(line_no) + ": expected 3 or 4 non-empty fields, found " +
                               std::to_string(f.size()));
        labelled_clip c;
        c.path = dir / f[0];
        c.content = f[1];
        c.emotion = f[2];
        c.take = f.size() == 4 ? f[3] : std::to_string(out.size());
        out.push_back(std::move(c));
    }
    if (out.empty()) throw format_error("manifest: " + mpath.string() + ": no clips listed");
    return out;
}

/// @brief Loads every labelled clip of a folder (BVH preferred over a CSV of the same stem), sorted by
/// path so the order (and so training) is deterministic.
/// @throws io_error for a missing folder, value_error for a bad name, format_error for a bad file,
///         shape_error when the clips do not share one skeleton (naming the first file that differs).
inline std::vector<labelled_clip> load_folder(const std::filesystem::path& dir, const load_options& opt = {})
{
    namespace fs = std::filesystem;
    if (!fs::is_directory(dir)) throw io_error("dataset: " + dir.string() + " is not a folder");
    std::vector<labelled_clip> items;
    if (fs::exists(dir / "manifest.csv")) {
        items = read_manifest(dir);
    } else {
        std::vector<fs::path> files;
        for (const auto& e : fs::directory_iterator(dir))
            if (e.is_regular_file() && (detail::is_bvh(e.path()) || detail::is_csv(e.path()))) files.push_back(e.path());
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

/// @brief Tempo factor per domain: the median over clips of that emotion of duration / duration of the
/// neutral clip of the same content (the same take when there is one, otherwise the mean over the
/// content's neutral takes). Domains without data, and the neutral domain itself, get 1.
/// @param domains domain names in label order; @param neutral name of the neutral domain
inline std::vector<double> tempo_factors(const std::vector<labelled_clip>& d, const std::vector<std::string>& domains,
                                         const std::string& neutral)
{
    std::map<std::pair<std::string, std::string>, double> neutral_by_take;
    std::map<std::string, std::pair<double, int>> neutral_mean;
    for (const auto& c : d)
        if (c.emotion == neutral) {
            neutral_by_take[{c.content, c.take}] = c.motion.duration();
            auto& m = neutral_mean[c.content];
            m.first += c.motion.duration();
            m.second += 1;
        }
    std::vector<double> out(domains.size(), 1.0);
    for (std::size_t k = 0; k < domains.size(); ++k) {
        if (domains[k] == neutral) continue;
        std::vector<double> ratios;
        for (const auto& c : d) {
            if (c.emotion != domains[k]) continue;
            double base = 0;
            if (auto it = neutral_by_take.find({c.content, c.take}); it != neutral_by_take.end())
                base = it->second;
            else if (auto m = neutral_mean.find(c.content); m != neutral_mean.end())
                base = m->second.first / m->second.second;
            if (base > 0 && c.motion.duration() > 0) ratios.push_back(c.motion.duration() / base);
        }
        if (ratios.empty()) continue;
        std::sort(ratios.begin(), ratios.end());
        const std::size_t n = ratios.size();
        out[k] = n % 2 ? ratios[n / 2] : 0.5 * (ratios[n / 2 - 1] + ratios[n / 2]);
    }
    return out;
}

}  // namespace handemo::stargan
