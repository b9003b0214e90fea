// The circumplex analysis model of Aristidou et al. 2017, Section 3, end to end: fit (features of every
// training clip -> [0, 1] normalisation -> effective and consistent selection -> PCA to 95% -> Gaussian RBF
// features -> (valence, arousal), Eq. 1-2, and multiquadric RBF (valence, arousal) -> selected features,
// Eq. 3-4 -> pose clusters with their own selections, Section 3.5), analysis of a new clip (its predicted
// circumplex point, clamped to [-1, 1]^2 as the paper clamps to the diagram, and quadrant), the model file
// (JSON with format and version, written atomically, validated on load with errors naming file and field),
// and the leave-one-content-out evaluation of the analysis.
//
// Analysis uses the global selection (all poses); the per-cluster selections are fitted, stored and
// printed for the synthesis. The evaluation also tries what the paper leaves open (analysis_input: the
// per-cluster selections for analysis, features against the content's neutral clips, the full-rate judge's
// feature space; a pull toward the constant predictor), chosen per fold by an inner leave-one-group-out.
#pragma once

#include <handemo/core/error.hpp>
#include <handemo/core/io.hpp>
#include <handemo/core/progress.hpp>
#include <handemo/metrics/full_rate_judge.hpp>
#include <handemo/motion/clip.hpp>
#include <handemo/rcm/circumplex.hpp>
#include <handemo/rcm/cluster.hpp>
#include <handemo/rcm/lma.hpp>
#include <handemo/rcm/maps.hpp>
#include <handemo/rcm/roles.hpp>
#include <handemo/rcm/selection.hpp>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

namespace handemo::rcm {

/// @brief Version of the model file save_model() writes without a chosen analysis (with one it writes 2; both are read).
inline constexpr int model_version = 1;

/// @brief One labelled training clip. `performer` is the performer, or the content (motion type) for
/// data sets without performers (Bandai, the synthetic hand set).
struct training_clip {
    const clip* motion = nullptr;
    std::string emotion;
    std::string performer;
    std::string name;  ///< for messages (usually the file)
};

/// @brief Options of fit_model().
struct fit_options {
    lma_options lma;
    selection_options selection;
    double pca_keep = 0.95;
    bool cluster = true;  ///< fit the pose clusters and their selections (Section 3.5)
    pose_cluster_options clustering;
    nlohmann::json role_overrides = nlohmann::json::object();  ///< `{"left_hand": "Hand_L"}`
    std::string performer_kind = "content";  ///< what plays the performers' role, for the report
    bool show_progress = false;
    bool select = true;  ///< false keeps every feature (a feature space other than Table 1's, as evaluate_loo's judge input)
};

/// @brief The analysed emotion of a clip.
struct analysis {
    double valence = 0, arousal = 0;          ///< clamped to [-1, 1]
    double raw_valence = 0, raw_arousal = 0;  ///< before clamping
    int quadrant = 1;

    /// @brief The analysis of a point Eq. 1 maps to (valence, arousal): clamped to [-1, 1], its quadrant.
    static analysis of_point(double valence, double arousal)
    {
        analysis a;
        a.raw_valence = valence, a.raw_arousal = arousal;
        a.valence = std::clamp(valence, -1.0, 1.0);
        a.arousal = std::clamp(arousal, -1.0, 1.0);
        a.quadrant = handemo::quadrant(a.valence, a.arousal);
        return a;
    }
};

/// @brief A fitted circumplex analysis model.
struct rcm_model {
    feature_set features = feature_set::body;
    lma_options lma;
    nlohmann::json roles = nlohmann::json::object();  ///< role -> joint name on the training skeleton
    feature_normaliser normaliser;
    std::vector<std::size_t> selected;  ///< indices into derived_features()
    selection_result selection;         ///< counts of the global selection
    std::string performer_kind = "content";
    pca_model pca;
    rbf_map to_emotion;   ///< Eq. 1-2: PCA scores -> (valence, arousal)
    rbf_map to_features;  ///< Eq. 3-4: (valence, arousal) -> selected normalised features
    std::vector<label_point> labels;  ///< labels of the training set with their coordinates
    std::string label_source;         ///< citation of the coordinates
    bool has_clusters = false;
    pose_clustering clusters;
    std::vector<std::vector<std::size_t>> cluster_selected;  ///< [C] selected features per pose cluster
    std::vector<std::size_t> cluster_survivors;              ///< [C] how many of those passed both tests
    std::size_t training_clips = 0;

    /// @brief Roles of a skeleton: the model's role names where that skeleton has them, name rules otherwise.
    role_map roles_for(const skeleton& s) const
    {
        role_map m = find_roles(s);
        for (const auto& [k, v] : roles.items()) {
            const std::string name = v.get<std::string>();
            for (std::size_t i = 0; i < m.points.size(); ++i)
                if (m.points[i] == name) m.index[static_cast<std::size_t>(role_from_string(k))] = static_cast<int>(i);
        }
        m.require(features);
        return m;
    }
    /// @brief The selected, normalised features `[S]` of given world positions (the same ones the model was fitted on).
    vector selected_features(const positions_type& p, double fps, const role_map& r) const
    {
        const vector all = normaliser.apply(clip_features(p, fps, r, features, lma));
        vector s = xt::zeros<double>({selected.size()});
        for (std::size_t i = 0; i < selected.size(); ++i) s(i) = all(selected[i]);
        return s;
    }
    /// @brief Eq. 1 on selected normalised features: the circumplex point, clamped to [-1, 1].
    analysis analyse_features(const vector& selected_normalised) const
    {
        const vector e = to_emotion(pca.project(selected_normalised));
        return analysis::of_point(e(0), e(1));
    }
    /// @brief The emotion of a clip (Section 3.3).
    /// @throws value_error when the clip's skeleton lacks a role the features need.
    analysis analyse(const clip& c) const
    {
        const role_map r = roles_for(c.skel);
        return analyse_features(selected_features(world_positions(c), c.fps, r));
    }
    /// @brief Eq. 3: the selected normalised features `[S]` expected at a circumplex point.
    vector desired_features(double valence, double arousal) const
    {
        vector e = {valence, arousal};
        return to_features(e);
    }
    /// @brief Names of the selected features.
    std::vector<std::string> selected_names() const
    {
        std::vector<std::string> n;
        for (std::size_t i : selected) n.push_back(derived_features(features)[i].name);
        return n;
    }
};

/// @brief Raw derived features of one training clip: per window and their mean.
struct clip_feature_data {
    xt::xtensor<double, 2> windows;  ///< [W, D]
    vector mean;                     ///< [D]
    std::size_t window_length = 0;
};

/// @brief Roles of the training skeleton: name rules plus overrides.
inline role_map training_roles(const skeleton& s, const nlohmann::json& overrides, feature_set* fs_out = nullptr)
{
    role_map r = find_roles(s);
    if (!overrides.empty()) apply_role_overrides(r, overrides, "rcm roles");
    const feature_set fs = detect_feature_set(r);
    r.require(fs);
    if (fs_out) *fs_out = fs;
    return r;
}

/// @brief Computes the raw features of every clip (the slow part of a fit; done once for all folds).
inline std::vector<clip_feature_data> compute_features(const std::vector<training_clip>& clips, const role_map& r, feature_set fs,
                                                       const lma_options& lma, bool show_progress)
{
    std::vector<clip_feature_data> out;
    out.reserve(clips.size());
    progress bar("rcm features", static_cast<long>(clips.size()), show_progress ? stderr : nullptr);
    for (std::size_t i = 0; i < clips.size(); ++i) {
        const clip& c = *clips[i].motion;
        clip_feature_data d;
        try {
            d.windows = window_features(world_positions(c), c.fps, r, fs, lma);
        } catch (const error& e) {
            throw value_error("rcm fit: " + clips[i].name + ": " + e.what());
        }
        d.mean = xt::mean(d.windows, {0});
        d.window_length = std::min(c.frames, window_length(c.fps, lma));
        out.push_back(std::move(d));
        bar.update(static_cast<long>(i + 1));
    }
    return out;
}

namespace detail {

inline std::vector<std::string> sorted_unique(const std::vector<std::string>& v)
{
    std::set<std::string> s(v.begin(), v.end());
    return {s.begin(), s.end()};
}

inline matrix rows_of(const std::vector<vector>& rows, std::size_t D)
{
    matrix m = xt::zeros<double>({rows.size(), D});
    for (std::size_t i = 0; i < rows.size(); ++i) xt::view(m, i, xt::all()) = rows[i];
    return m;
}

}  // namespace detail

/// @brief The analysis half of a model on features normalised elsewhere: the selection, the PCA and Eq. 1.
struct emotion_map {
    std::vector<std::size_t> selected;  ///< indices into the normalised features
    selection_result selection;         ///< counts of the selection (empty when every feature is kept)
    pca_model pca;
    rbf_map to_emotion;               ///< Eq. 1-2: PCA scores -> (valence, arousal)
    std::vector<label_point> labels;  ///< the training labels (sorted by name) with their coordinates

    /// @brief The circumplex point of one clip's normalised features `[D]` (all of them; the selected are picked).
    analysis operator()(const vector& normalised) const
    {
        vector s = xt::zeros<double>({selected.size()});
        for (std::size_t k = 0; k < selected.size(); ++k) s(k) = normalised(selected[k]);
        const vector e = to_emotion(pca.project(s));
        return analysis::of_point(e(0), e(1));
    }
};

/// @brief Fits selection (Section 3.2; every feature when `select` is false), PCA and Eq. 1 on normalised features
/// `x` `[N, D]` with an emotion and a performer per row.
/// @throws value_error for a label without coordinates, fewer than 2 emotions or performers, or a singular fit.
inline emotion_map fit_emotion_map(const matrix& x, const std::vector<std::string>& emo, const std::vector<std::string>& perf,
                                   const circumplex_table& table, const std::string& table_name, const selection_options& sel,
                                   double pca_keep, bool select = true)
{
    emotion_map em;
    const std::size_t N = x.shape()[0], D = x.shape()[1];
    if (select) {
        em.selection = select_features(x, emo, perf, sel);
        em.selected = em.selection.selected;
    } else {
        for (std::size_t k = 0; k < D; ++k) em.selected.push_back(k);
    }
    const std::size_t S = em.selected.size();
    matrix xs = xt::zeros<double>({N, S});
    for (std::size_t i = 0; i < N; ++i)
        for (std::size_t k = 0; k < S; ++k) xs(i, k) = x(i, em.selected[k]);
    em.pca = fit_pca(xs, pca_keep, N > 1 ? N - 1 : 1);
    const matrix scores = em.pca.project_rows(xs);
    std::set<std::string> name_set(emo.begin(), emo.end());
    const std::vector<std::string> names(name_set.begin(), name_set.end());
    const std::size_t K = names.size(), d = em.pca.dims();
    for (const auto& n : names) em.labels.push_back(table.at(n, table_name));
    matrix centres = xt::zeros<double>({K, d}), centre_e = xt::zeros<double>({K, std::size_t{2}});
    matrix targets = xt::zeros<double>({N, std::size_t{2}});
    std::vector<double> count(K, 0.0);
    for (std::size_t i = 0; i < N; ++i) {
        const std::size_t k = static_cast<std::size_t>(std::find(names.begin(), names.end(), emo[i]) - names.begin());
        count[k] += 1;
        for (std::size_t j = 0; j < d; ++j) centres(k, j) += scores(i, j);
        targets(i, 0) = em.labels[k].valence;
        targets(i, 1) = em.labels[k].arousal;
    }
    for (std::size_t k = 0; k < K; ++k) {
        for (std::size_t j = 0; j < d; ++j) centres(k, j) /= count[k];
        centre_e(k, 0) = em.labels[k].valence;
        centre_e(k, 1) = em.labels[k].arousal;
    }
    em.to_emotion = fit_rbf_regression(scores, targets, centres, centre_e, rbf_kernel::gaussian, mean_pairwise_distance(scores));
    return em;
}

/// @brief Fits the analysis part (normaliser, selection, PCA, Eq. 1 and Eq. 3 maps) from precomputed features
/// of the clips `use` (indices into clips/features). The features need not be LMA's: their length is read from
/// them, and opt.select = false keeps all of them.
/// @throws value_error for a label without coordinates, fewer than 2 emotions or performers, or a singular fit.
inline rcm_model fit_from_features(const std::vector<training_clip>& clips, const std::vector<clip_feature_data>& feats,
                                   const std::vector<std::size_t>& use, feature_set fs, const circumplex_table& table,
                                   const std::string& table_name, const fit_options& opt)
{
    rcm_model m;
    m.features = fs;
    m.lma = opt.lma;
    m.performer_kind = opt.performer_kind;
    m.label_source = table.source;
    m.training_clips = use.size();
    if (use.empty()) throw value_error("rcm fit: no training clips");
    const std::size_t D = feats[use.front()].mean.size();
    std::vector<vector> raw;
    std::vector<std::string> emo, perf;
    for (std::size_t i : use) raw.push_back(feats[i].mean), emo.push_back(clips[i].emotion), perf.push_back(clips[i].performer);
    m.normaliser = feature_normaliser::fit(detail::rows_of(raw, D));
    const matrix x = m.normaliser.apply_rows(detail::rows_of(raw, D));
    emotion_map em = fit_emotion_map(x, emo, perf, table, table_name, opt.selection, opt.pca_keep, opt.select);
    m.selection = std::move(em.selection);
    m.selected = std::move(em.selected);
    m.pca = std::move(em.pca);
    m.to_emotion = std::move(em.to_emotion);
    m.labels = std::move(em.labels);
    // Eq. 3: each emotion's mean selected features at its circumplex point
    const std::size_t S = m.selected.size(), N = use.size(), K = m.labels.size();
    matrix centre_feat = xt::zeros<double>({K, S}), centre_e = xt::zeros<double>({K, std::size_t{2}});
    const auto names = detail::sorted_unique(emo);  // the order of m.labels
    std::vector<double> count(K, 0.0);
    for (std::size_t i = 0; i < N; ++i) {
        const std::size_t k = static_cast<std::size_t>(std::find(names.begin(), names.end(), emo[i]) - names.begin());
        count[k] += 1;
        for (std::size_t j = 0; j < S; ++j) centre_feat(k, j) += x(i, m.selected[j]);
    }
    for (std::size_t k = 0; k < K; ++k) {
        for (std::size_t j = 0; j < S; ++j) centre_feat(k, j) /= count[k];
        centre_e(k, 0) = m.labels[k].valence;
        centre_e(k, 1) = m.labels[k].arousal;
    }
    m.to_features = fit_rbf_interpolant(centre_e, centre_feat, rbf_kernel::multiquadric, mean_pairwise_distance(centre_e));
    return m;
}

namespace detail {

/// value_error for no clips, shape_error naming the first clip whose skeleton differs from the first one's
inline void check_training_clips(const std::vector<training_clip>& clips, const std::string& what)
{
    if (clips.empty()) throw value_error(what + ": no training clips");
    for (const auto& c : clips)
        if (!c.motion->skel.same_topology(clips.front().motion->skel))
            throw shape_error(what + ": " + c.name + " has a different skeleton from " + clips.front().name);
}

/// fit_model() on the features it computes (those of every clip, with roles r and feature set fs)
inline rcm_model fit_model_from_features(const std::vector<training_clip>& clips, const std::vector<clip_feature_data>& feats,
                                         const role_map& r, feature_set fs, const circumplex_table& table, const std::string& table_name,
                                         const fit_options& opt)
{
    std::vector<std::size_t> all(clips.size());
    for (std::size_t i = 0; i < all.size(); ++i) all[i] = i;
    rcm_model m = fit_from_features(clips, feats, all, fs, table, table_name, opt);
    m.roles = r.to_json();
    if (!opt.cluster) return m;
    // Section 3.5: pose clusters and per-cluster selections
    std::vector<pose> poses;
    std::vector<std::vector<pose>> per_clip;
    for (const auto& c : clips) {
        per_clip.push_back(clip_poses(*c.motion, r, opt.lma.up_axis));
        poses.insert(poses.end(), per_clip.back().begin(), per_clip.back().end());
    }
    pose_cluster_options co = opt.clustering;
    co.clusters = std::min(co.clusters, poses.size());
    m.clusters = cluster_poses(poses, pose_weights(clips.front().motion->skel, r), co);
    m.has_clusters = true;
    const std::size_t C = m.clusters.count(), D = derived_count(fs);
    m.cluster_selected.assign(C, {});
    m.cluster_survivors.assign(C, 0);
    // cluster of each window: the cluster of its centre frame
    std::vector<std::vector<std::size_t>> window_cluster(clips.size());
    for (std::size_t i = 0; i < clips.size(); ++i) {
        const auto starts = window_starts(clips[i].motion->frames, feats[i].window_length);
        for (std::size_t k = 0; k < feats[i].windows.shape()[0]; ++k) {
            const std::size_t centre = std::min(clips[i].motion->frames - 1, starts[k] + feats[i].window_length / 2);
            window_cluster[i].push_back(m.clusters.assign(per_clip[i][centre]));
        }
    }
    for (std::size_t c = 0; c < C; ++c) {
        std::vector<vector> rows;
        std::vector<std::string> emo, perf;
        for (std::size_t i = 0; i < clips.size(); ++i) {
            const auto& w = feats[i].windows;
            vector acc = xt::zeros<double>({D});
            double n = 0;
            for (std::size_t k = 0; k < w.shape()[0]; ++k) {
                if (window_cluster[i][k] != c) continue;
                const vector row = xt::view(w, k, xt::all());
                acc += m.normaliser.apply(row);
                n += 1;
            }
            if (n == 0) continue;
            rows.push_back(acc / n);
            emo.push_back(clips[i].emotion);
            perf.push_back(clips[i].performer);
        }
        try {
            const auto sel = select_features(detail::rows_of(rows, D), emo, perf, opt.selection);
            m.cluster_selected[c] = sel.selected;
            m.cluster_survivors[c] = sel.survivors;
        } catch (const value_error&) {
            m.cluster_selected[c].clear();  // fewer than two emotions or performers reach this cluster
        }
    }
    return m;
}

}  // namespace detail

/// @brief Fits a whole model on labelled clips (one skeleton), with pose clusters when opt.cluster.
/// @throws value_error / shape_error as the steps do, naming the clip where one is at fault.
inline rcm_model fit_model(const std::vector<training_clip>& clips, const circumplex_table& table, const std::string& table_name,
                           const fit_options& opt = {})
{
    detail::check_training_clips(clips, "rcm fit");
    feature_set fs{};
    const role_map r = training_roles(clips.front().motion->skel, opt.role_overrides, &fs);
    return detail::fit_model_from_features(clips, compute_features(clips, r, fs, opt.lma, opt.show_progress), r, fs, table, table_name, opt);
}

// ---- model file ----

namespace detail {

inline nlohmann::json to_json(const matrix& a)
{
    nlohmann::json j = nlohmann::json::array();
    for (std::size_t i = 0; i < a.shape()[0]; ++i) {
        nlohmann::json r = nlohmann::json::array();
        for (std::size_t k = 0; k < a.shape()[1]; ++k) r.push_back(a(i, k));
        j.push_back(r);
    }
    return j;
}
inline nlohmann::json to_json(const vector& a)
{
    nlohmann::json j = nlohmann::json::array();
    for (double v : a) j.push_back(v);
    return j;
}
inline nlohmann::json to_json(const rbf_map& r)
{
    return {{"kernel", std::string(to_string(r.kernel))}, {"sigma", r.sigma}, {"centres", to_json(r.centres)},
            {"lambda", to_json(r.lambda)}, {"linear", to_json(r.linear)}};
}
inline nlohmann::json to_json(const pose& p)
{
    nlohmann::json q = nlohmann::json::array();
    for (const auto& x : p.q) q.push_back({x[0], x[1], x[2], x[3]});
    return {{"height", p.height}, {"q", q}};
}

/// Reader of one model file: every accessor names the file and the field path on error.
struct model_reader {
    std::string file;

    [[noreturn]] void fail(const std::string& field, const std::string& what) const
    {
        throw format_error("rcm model: " + file + ": field '" + field + "' " + what);
    }
    const nlohmann::json& get(const nlohmann::json& o, const std::string& key, const std::string& path) const
    {
        if (!o.is_object() || !o.contains(key)) fail(path + key, "is missing");
        return o.at(key);
    }
    double number(const nlohmann::json& o, const std::string& key, const std::string& path) const
    {
        const auto& v = get(o, key, path);
        if (!v.is_number()) fail(path + key, "is not a number");
        const double x = v.get<double>();
        if (!std::isfinite(x)) fail(path + key, "is not finite");
        return x;
    }
    std::string text(const nlohmann::json& o, const std::string& key, const std::string& path) const
    {
        const auto& v = get(o, key, path);
        if (!v.is_string()) fail(path + key, "is not a string");
        return v.get<std::string>();
    }
    std::vector<double> numbers(const nlohmann::json& v, const std::string& field) const
    {
        if (!v.is_array()) fail(field, "is not an array");
        std::vector<double> out;
        for (std::size_t i = 0; i < v.size(); ++i) {
            if (!v[i].is_number() || !std::isfinite(v[i].get<double>())) fail(field + "[" + std::to_string(i) + "]", "is not a finite number");
            out.push_back(v[i].get<double>());
        }
        return out;
    }
    vector vec(const nlohmann::json& o, const std::string& key, const std::string& path, std::size_t n) const
    {
        const auto x = numbers(get(o, key, path), path + key);
        if (x.size() != n) fail(path + key, "has " + std::to_string(x.size()) + " values, expected " + std::to_string(n));
        vector v = xt::zeros<double>({n});
        for (std::size_t i = 0; i < n; ++i) v(i) = x[i];
        return v;
    }
    matrix mat(const nlohmann::json& o, const std::string& key, const std::string& path, std::size_t rows, std::size_t cols) const
    {
        const auto& v = get(o, key, path);
        if (!v.is_array() || v.size() != rows)
            fail(path + key, "is not an array of " + std::to_string(rows) + " rows");
        matrix m = xt::zeros<double>({rows, cols});
        for (std::size_t i = 0; i < rows; ++i) {
            const auto r = numbers(v[i], path + key + "[" + std::to_string(i) + "]");
            if (r.size() != cols)
                fail(path + key + "[" + std::to_string(i) + "]", "has " + std::to_string(r.size()) + " values, expected " + std::to_string(cols));
            for (std::size_t k = 0; k < cols; ++k) m(i, k) = r[k];
        }
        return m;
    }
    std::vector<std::size_t> indices(const nlohmann::json& v, const std::string& field, std::size_t bound) const
    {
        const auto x = numbers(v, field);
        std::vector<std::size_t> out;
        for (std::size_t i = 0; i < x.size(); ++i) {
            if (x[i] < 0 || x[i] >= static_cast<double>(bound) || x[i] != std::floor(x[i]))
                fail(field + "[" + std::to_string(i) + "]", "is not a feature index below " + std::to_string(bound));
            out.push_back(static_cast<std::size_t>(x[i]));
        }
        return out;
    }
    rbf_map rbf(const nlohmann::json& o, const std::string& key, std::size_t in, std::size_t out) const
    {
        const std::string p = key + ".";
        const auto& j = get(o, key, "");
        rbf_map r;
        const std::string k = text(j, "kernel", p);
        if (k == "gaussian") r.kernel = rbf_kernel::gaussian;
        else if (k == "multiquadric") r.kernel = rbf_kernel::multiquadric;
        else fail(p + "kernel", "is '" + k + "', expected gaussian or multiquadric");
        r.sigma = number(j, "sigma", p);
        if (!(r.sigma > 0)) fail(p + "sigma", "is not positive");
        const auto& c = get(j, "centres", p);
        if (!c.is_array() || c.empty()) fail(p + "centres", "is not a non-empty array");
        const std::size_t K = c.size();
        r.centres = mat(j, "centres", p, K, in);
        r.lambda = mat(j, "lambda", p, K, out);
        r.linear = mat(j, "linear", p, in + 1, out);
        return r;
    }
};

}  // namespace detail

/// @brief The model as JSON (see save_model()).
inline nlohmann::json model_to_json(const rcm_model& m)
{
    using detail::to_json;
    nlohmann::json j;
    j["format"] = "handemo-rcm-model";
    j["version"] = model_version;
    j["paper"] = "Aristidou et al. 2017, Emotion control of unstructured dance movements (Section 3)";
    j["feature_set"] = std::string(to_string(m.features));
    j["lma"] = {{"up_axis", m.lma.up_axis}, {"window_frames_at_30", m.lma.window_frames_at_30}};
    j["roles"] = m.roles;
    j["normaliser"] = {{"lo", m.normaliser.lo}, {"hi", m.normaliser.hi}};
    j["selected"] = m.selected;
    j["selected_names"] = m.selected_names();
    j["selection"] = {{"performer_kind", m.performer_kind}, {"performers", m.selection.performers}, {"emotions", m.selection.emotions},
                      {"need_effective", m.selection.need_effective}, {"need_consistent", m.selection.need_consistent},
                      {"survivors", m.selection.survivors}, {"fallback", m.selection.fallback}};
    j["pca"] = {{"mean", to_json(m.pca.mean)}, {"components", to_json(m.pca.components)}, {"variances", to_json(m.pca.variances)},
                {"total_variance", m.pca.total_variance}};
    j["to_emotion"] = to_json(m.to_emotion);
    j["to_features"] = to_json(m.to_features);
    nlohmann::json labels = nlohmann::json::array();
    for (const auto& l : m.labels) labels.push_back({{"name", l.name}, {"valence", l.valence}, {"arousal", l.arousal}});
    j["labels"] = labels;
    j["label_source"] = m.label_source;
    j["training_clips"] = m.training_clips;
    if (m.has_clusters) {
        nlohmann::json med = nlohmann::json::array();
        for (const auto& p : m.clusters.medoids) med.push_back(to_json(p));
        j["clusters"] = {{"weights", m.clusters.weights}, {"height_weight", m.clusters.height_weight},
                         {"height_scale", m.clusters.height_scale}, {"sizes", m.clusters.sizes}, {"medoids", med},
                         {"selected", m.cluster_selected}, {"survivors", m.cluster_survivors}};
    }
    return j;
}

/// @brief Reads a model from JSON, validating every field.
/// @throws format_error naming `file` and the field.
inline rcm_model model_from_json(const nlohmann::json& j, const std::string& file)
{
    detail::model_reader rd{file};
    if (rd.text(j, "format", "") != "handemo-rcm-model") rd.fail("format", "is not \"handemo-rcm-model\"");
    const double ver = rd.number(j, "version", "");
    if (ver != 1 && ver != 2) rd.fail("version", "is " + std::to_string(static_cast<int>(ver)) + ", this handemo reads 1 and 2");
    if (ver == 2 && !j.contains("analysis")) rd.fail("analysis", "is missing (a version 2 file has one)");
    rcm_model m;
    try {
        m.features = feature_set_from_string(rd.text(j, "feature_set", ""));
    } catch (const value_error&) {
        rd.fail("feature_set", "is not 'body' or 'hand'");
    }
    const std::size_t D = derived_count(m.features);
    const auto& lma = rd.get(j, "lma", "");
    m.lma.up_axis = static_cast<int>(rd.number(lma, "up_axis", "lma."));
    if (m.lma.up_axis < 0 || m.lma.up_axis > 2) rd.fail("lma.up_axis", "is not 0, 1 or 2");
    m.lma.window_frames_at_30 = rd.number(lma, "window_frames_at_30", "lma.");
    if (!(m.lma.window_frames_at_30 >= 2)) rd.fail("lma.window_frames_at_30", "is below 2");
    m.roles = rd.get(j, "roles", "");
    if (!m.roles.is_object()) rd.fail("roles", "is not an object");
    for (const auto& [k, v] : m.roles.items()) {
        try {
            (void)role_from_string(k);
        } catch (const value_error&) {
            rd.fail("roles." + k, "is not a role");
        }
        if (!v.is_string()) rd.fail("roles." + k, "is not a joint name");
    }
    const auto& nm = rd.get(j, "normaliser", "");
    const auto lo = rd.vec(nm, "lo", "normaliser.", D), hi = rd.vec(nm, "hi", "normaliser.", D);
    m.normaliser.lo.assign(lo.begin(), lo.end());
    m.normaliser.hi.assign(hi.begin(), hi.end());
    m.selected = rd.indices(rd.get(j, "selected", ""), "selected", D);
    if (m.selected.empty()) rd.fail("selected", "is empty");
    const std::size_t S = m.selected.size();
    const auto& sel = rd.get(j, "selection", "");
    m.performer_kind = rd.text(sel, "performer_kind", "selection.");
    m.selection.performers = static_cast<std::size_t>(rd.number(sel, "performers", "selection."));
    m.selection.emotions = static_cast<std::size_t>(rd.number(sel, "emotions", "selection."));
    m.selection.need_effective = static_cast<std::size_t>(rd.number(sel, "need_effective", "selection."));
    m.selection.need_consistent = static_cast<std::size_t>(rd.number(sel, "need_consistent", "selection."));
    m.selection.survivors = static_cast<std::size_t>(rd.number(sel, "survivors", "selection."));
    if (!rd.get(sel, "fallback", "selection.").is_boolean()) rd.fail("selection.fallback", "is not true or false");
    m.selection.fallback = sel.at("fallback").get<bool>();
    m.selection.selected = m.selected;
    const auto& pj = rd.get(j, "pca", "");
    const auto& comps = rd.get(pj, "components", "pca.");
    if (!comps.is_array() || comps.empty() || comps.size() > S) rd.fail("pca.components", "is not an array of 1 to " + std::to_string(S) + " rows");
    const std::size_t d = comps.size();
    m.pca.mean = rd.vec(pj, "mean", "pca.", S);
    m.pca.components = rd.mat(pj, "components", "pca.", d, S);
    m.pca.variances = rd.vec(pj, "variances", "pca.", d);
    m.pca.total_variance = rd.number(pj, "total_variance", "pca.");
    m.to_emotion = rd.rbf(j, "to_emotion", d, 2);
    m.to_features = rd.rbf(j, "to_features", 2, S);
    const auto& labels = rd.get(j, "labels", "");
    if (!labels.is_array() || labels.empty()) rd.fail("labels", "is not a non-empty array");
    for (std::size_t i = 0; i < labels.size(); ++i) {
        const std::string p = "labels[" + std::to_string(i) + "].";
        label_point l;
        l.name = rd.text(labels[i], "name", p);
        l.valence = rd.number(labels[i], "valence", p);
        l.arousal = rd.number(labels[i], "arousal", p);
        if (std::abs(l.valence) > 1 || std::abs(l.arousal) > 1) rd.fail(p + "valence", "or arousal is outside [-1, 1]");
        m.labels.push_back(l);
    }
    m.label_source = rd.text(j, "label_source", "");
    m.training_clips = static_cast<std::size_t>(rd.number(j, "training_clips", ""));
    if (j.contains("clusters")) {
        const auto& cj = j.at("clusters");
        m.has_clusters = true;
        m.clusters.weights = rd.numbers(rd.get(cj, "weights", "clusters."), "clusters.weights");
        m.clusters.height_weight = rd.number(cj, "height_weight", "clusters.");
        m.clusters.height_scale = rd.number(cj, "height_scale", "clusters.");
        if (!(m.clusters.height_scale > 0)) rd.fail("clusters.height_scale", "is not positive");
        const auto sizes = rd.numbers(rd.get(cj, "sizes", "clusters."), "clusters.sizes");
        for (double s : sizes) m.clusters.sizes.push_back(static_cast<std::size_t>(s));
        const auto& med = rd.get(cj, "medoids", "clusters.");
        if (!med.is_array() || med.empty()) rd.fail("clusters.medoids", "is not a non-empty array");
        const std::size_t J = m.clusters.weights.size();
        for (std::size_t c = 0; c < med.size(); ++c) {
            const std::string p = "clusters.medoids[" + std::to_string(c) + "].";
            pose ps;
            ps.height = rd.number(med[c], "height", p);
            const matrix q = rd.mat(med[c], "q", p, J, 4);
            for (std::size_t k = 0; k < J; ++k) ps.q.push_back({q(k, 0), q(k, 1), q(k, 2), q(k, 3)});
            m.clusters.medoids.push_back(std::move(ps));
        }
        const auto& cs = rd.get(cj, "selected", "clusters.");
        if (!cs.is_array() || cs.size() != med.size()) rd.fail("clusters.selected", "does not have one list per medoid");
        for (std::size_t c = 0; c < cs.size(); ++c)
            m.cluster_selected.push_back(rd.indices(cs[c], "clusters.selected[" + std::to_string(c) + "]", D));
        for (double s : rd.numbers(rd.get(cj, "survivors", "clusters."), "clusters.survivors")) m.cluster_survivors.push_back(static_cast<std::size_t>(s));
        if (m.cluster_survivors.size() != med.size()) rd.fail("clusters.survivors", "does not have one count per medoid");
    }
    return m;
}

namespace detail {

/// A model file's JSON. @throws io_error when it cannot be read, format_error when it is not JSON.
inline nlohmann::json read_model_json(const std::filesystem::path& path)
{
    const std::string text = read_file(path);
    try {
        return nlohmann::json::parse(text);
    } catch (const nlohmann::json::parse_error& e) {
        throw format_error("rcm model: " + path.string() + ": not JSON: " + e.what());
    }
}

}  // namespace detail

/// @brief Writes a model file atomically (JSON, `"format": "handemo-rcm-model"`, `"version": 1`).
inline void save_model(const rcm_model& m, const std::filesystem::path& path)
{
    write_file_atomic(path, model_to_json(m).dump(1) + "\n");
}

/// @brief Reads and validates a model file.
/// @throws io_error when it cannot be read, format_error naming the file and field when it is malformed.
inline rcm_model load_model(const std::filesystem::path& path)
{
    return model_from_json(detail::read_model_json(path), path.string());
}

// ---- evaluation ----

/// @brief One held-out clip's analysis.
struct eval_sample {
    std::string name, emotion, held_out;
    double valence = 0, arousal = 0;  ///< predicted (clamped)
    double true_valence = 0, true_arousal = 0;
    double distance = 0;  ///< Euclidean distance on the circumplex
    bool quadrant_ok = false;
    double baseline_distance = 0;  ///< distance of the training set's mean label point (a constant predictor)
    bool neutral = false;          ///< a clip of the neutral label (loo_options::neutral)
    bool relative = false;         ///< analysed with features relative to its content's neutral clips
    std::string input = "paper";   ///< the analysis input of its fold (to_string(analysis_input))
    double shrink = 1;             ///< the shrinkage weight of its fold (1: the map's own point)
};

/// @brief The leave-one-group-out evaluation.
struct eval_report {
    std::vector<eval_sample> samples;
    std::vector<std::string> folds;
    std::vector<std::string> failed_folds;  ///< folds whose fit failed, with the reason
    double mean_distance = 0, quadrant_accuracy = 0, baseline_distance = 0, baseline_quadrant_accuracy = 0;
    double mean_selected = 0, mean_pca_dims = 0;
    /// over the non-neutral held-out clips only (the measure of --relative: a neutral clip read against its own
    /// content's neutral mean is no test of the analysis)
    double emotional_distance = 0, emotional_baseline_distance = 0;
    std::size_t relative_folds = 0;  ///< folds analysed with relative features
    std::map<std::string, std::size_t> input_folds;  ///< analysis input -> folds analysed with it
    double mean_shrink = 1;                          ///< mean shrinkage weight over the fitted folds
};

/// @brief How evaluate_loo() reads a clip's features: as they are (the paper), as the change from the mean
/// features of the neutral clips of the same performer or content (`on`), or either, chosen per fold by an inner
/// leave-one-group-out over the fold's training groups (`automatic`: relative when its inner mean distance over the
/// non-neutral clips is lower). docs/circumplex.md gives the rule.
enum class relative_features { off, on, automatic };

/// @brief What evaluate_loo() maps to the circumplex (docs/circumplex.md):
/// - `paper`: the clip's Table 1 features, the global selection (Section 3.3);
/// - `relative`: the same features as the change from the mean of its content's neutral clips;
/// - `clusters`: the per-pose-cluster selections of Section 3.5, one selection, PCA and Eq. 1 map per cluster on
///   the clip's windows in that cluster, the clip's point the mean of the clusters' points weighted by its share of
///   windows in each (the global map for a clip none of whose windows reach a fitted cluster);
/// - `judge`: the full-rate emotion classifier's features (metrics::full_rate_change(): the clip's
///   full_rate_features() against each neutral clip of its content, averaged), all of them, PCA and Eq. 1.
enum class analysis_input { paper, relative, clusters, judge };

/// @brief The name of an analysis input (`paper`, `relative`, `clusters`, `judge`).
inline const char* to_string(analysis_input v) noexcept
{
    switch (v) {
    case analysis_input::paper: return "paper";
    case analysis_input::relative: return "relative";
    case analysis_input::clusters: return "clusters";
    case analysis_input::judge: return "judge";
    }
    return "paper";
}

/// @brief `paper`, `relative`, `clusters` or `judge` as a one-element list, `auto` as all four (in that order, the
/// order of preference on a tie); value_error naming the text and `option` (what gave it) otherwise.
inline std::vector<analysis_input> parse_analysis_inputs(const std::string& s, const std::string& option = "rcm eval: --input")
{
    if (s == "auto") return {analysis_input::paper, analysis_input::relative, analysis_input::clusters, analysis_input::judge};
    for (auto v : {analysis_input::paper, analysis_input::relative, analysis_input::clusters, analysis_input::judge})
        if (s == to_string(v)) return {v};
    throw value_error(option + " " + s + " is not paper, relative, clusters, judge or auto");
}

/// @brief The shrinkage weights `auto` tries: 1, 0.9, .., 0 (in that order, the order of preference on a tie).
inline std::vector<double> shrink_grid()
{
    std::vector<double> g;
    for (int k = 10; k >= 0; --k) g.push_back(k / 10.0);
    return g;
}

/// @brief `none` as {1}, `auto` as shrink_grid(), a number in [0, 1] as itself; value_error naming the text and
/// `option` otherwise.
inline std::vector<double> parse_shrink(const std::string& s, const std::string& option = "rcm eval: --shrink")
{
    if (s == "none") return {1.0};
    if (s == "auto") return shrink_grid();
    std::size_t used = 0;
    double v = -1;
    try {
        v = std::stod(s, &used);
    } catch (const std::exception&) {
        used = 0;
    }
    if (used != s.size() || !(v >= 0 && v <= 1)) throw value_error(option + " " + s + " is not none, auto or a number in [0, 1]");
    return {v};
}

/// @brief Options of evaluate_loo() beyond the fit's.
struct loo_options {
    relative_features relative = relative_features::off;
    std::string neutral;  ///< the neutral label (needed by relative and judge inputs; counted as neutral in the report)
    /// the candidate inputs (empty: from `relative`: off {paper}, on {relative}, automatic {paper, relative})
    std::vector<analysis_input> inputs;
    /// the candidate shrinkage weights s: a point p becomes c + s (p - c), c the fold's constant predictor (empty: {1})
    std::vector<double> shrink;
};

/// @brief `off`, `on` or `auto` as relative_features; value_error naming the text otherwise.
inline relative_features parse_relative_features(const std::string& s)
{
    if (s == "off") return relative_features::off;
    if (s == "on") return relative_features::on;
    if (s == "auto") return relative_features::automatic;
    throw value_error("rcm eval: --relative " + s + " is not off, on or auto");
}

/// @brief A point moved toward the constant predictor `c`: c + s (p - c) for the clamped and the raw point, its
/// quadrant anew. s = 1 keeps the point, s = 0 answers c.
inline analysis shrink_toward(const analysis& p, double cv, double ca, double s) noexcept
{
    analysis a;
    a.valence = cv + s * (p.valence - cv);
    a.arousal = ca + s * (p.arousal - ca);
    a.raw_valence = cv + s * (p.raw_valence - cv);
    a.raw_arousal = ca + s * (p.raw_arousal - ca);
    a.quadrant = quadrant(a.valence, a.arousal);
    return a;
}

/// @brief One candidate of the inner choice: an index into the candidate inputs and a shrinkage weight.
struct variant_choice {
    std::size_t input = 0;
    double shrink = 1;
    double distance = 0;  ///< mean distance of the chosen pair over the inner held-out clips
};

/// @brief The pair (input, weight) with the least mean distance between c_n + s (p_vn - c_n) and the label l_n over
/// the inner held-out clips n: `pred` `[V][N]`, `constant` and `truth` `[N]`. A tie goes to the earlier input, then
/// the earlier weight. With no clips, the first pair.
/// @throws shape_error when the lengths disagree.
inline variant_choice choose_variant(const std::vector<std::vector<analysis>>& pred, const std::vector<label_point>& constant,
                                     const std::vector<label_point>& truth, const std::vector<double>& weights)
{
    const std::size_t N = truth.size();
    if (pred.empty() || weights.empty() || constant.size() != N)
        throw shape_error("rcm eval: choose_variant: no candidates, or constants and labels differ in number");
    for (const auto& p : pred)
        if (p.size() != N) throw shape_error("rcm eval: choose_variant: " + std::to_string(p.size()) + " predictions, expected " + std::to_string(N));
    variant_choice best;
    bool first = true;
    for (std::size_t v = 0; v < pred.size(); ++v)
        for (double s : weights) {
            double d = 0;
            for (std::size_t n = 0; n < N; ++n) {
                const analysis a = shrink_toward(pred[v][n], constant[n].valence, constant[n].arousal, s);
                d += std::hypot(a.valence - truth[n].valence, a.arousal - truth[n].arousal);
            }
            d = N ? d / static_cast<double>(N) : 0.0;
            if (first || d < best.distance) best = {v, s, d}, first = false;
        }
    return best;
}

/// @brief The weighted mean of circumplex points (clamped and raw), the weights normalised to sum to 1; its quadrant anew.
/// @throws value_error when the weights are negative or sum to 0; shape_error when the lengths differ.
inline analysis weighted_point(const std::vector<analysis>& points, const std::vector<double>& weights)
{
    if (points.size() != weights.size() || points.empty()) throw shape_error("rcm eval: weighted_point: points and weights differ in number");
    double total = 0;
    for (double w : weights) {
        if (!(w >= 0)) throw value_error("rcm eval: weighted_point: weight " + std::to_string(w) + " is negative");
        total += w;
    }
    if (!(total > 0)) throw value_error("rcm eval: weighted_point: the weights sum to 0");
    analysis a;
    for (std::size_t k = 0; k < points.size(); ++k) {
        const double w = weights[k] / total;
        a.valence += w * points[k].valence, a.arousal += w * points[k].arousal;
        a.raw_valence += w * points[k].raw_valence, a.raw_arousal += w * points[k].raw_arousal;
    }
    a.quadrant = quadrant(a.valence, a.arousal);
    return a;
}

namespace detail {

/// Every clip's mean features minus the mean of the neutral clips of its performer (content).
/// @throws value_error naming a performer without a neutral clip.
inline std::vector<clip_feature_data> relative_to_neutral(const std::vector<training_clip>& clips,
                                                          const std::vector<clip_feature_data>& feats, const std::string& neutral)
{
    std::map<std::string, std::pair<vector, double>> ref;  // performer -> (sum, count)
    for (std::size_t i = 0; i < clips.size(); ++i) {
        if (clips[i].emotion != neutral) continue;
        auto [it, fresh] = ref.try_emplace(clips[i].performer, xt::zeros<double>({feats[i].mean.size()}), 0.0);
        it->second.first += feats[i].mean;
        it->second.second += 1;
    }
    std::vector<clip_feature_data> out;
    out.reserve(feats.size());
    for (std::size_t i = 0; i < clips.size(); ++i) {
        const auto it = ref.find(clips[i].performer);
        if (it == ref.end())
            throw value_error("rcm eval: relative features: '" + clips[i].performer + "' has no '" + neutral + "' clip to read " +
                              clips[i].name + " against");
        clip_feature_data d;
        d.mean = feats[i].mean - it->second.first / it->second.second;
        d.window_length = feats[i].window_length;
        out.push_back(std::move(d));
    }
    return out;
}

/// Eq. 1 on one clip's raw mean features: normalised, the selected picked, mapped.
inline analysis analyse_mean(const rcm_model& m, const vector& raw_mean)
{
    const vector all = m.normaliser.apply(raw_mean);
    vector s = xt::zeros<double>({m.selected.size()});
    for (std::size_t k = 0; k < m.selected.size(); ++k) s(k) = all(m.selected[k]);
    return m.analyse_features(s);
}

/// Fits on `train` and analyses the clips of `test` (indices into clips and feats).
inline std::vector<analysis> fit_and_analyse(const std::vector<training_clip>& clips, const std::vector<clip_feature_data>& feats,
                                             const std::vector<std::size_t>& train, const std::vector<std::size_t>& test,
                                             feature_set fs, const circumplex_table& table, const std::string& table_name,
                                             const fit_options& opt, rcm_model* fitted = nullptr)
{
    const rcm_model m = fit_from_features(clips, feats, train, fs, table, table_name, opt);
    std::vector<analysis> out;
    for (std::size_t i : test) out.push_back(analyse_mean(m, feats[i].mean));
    if (fitted) *fitted = m;
    return out;
}

/// One clip's features in the full-rate judge's space: the mean over its content's neutral clips' full-rate features
/// `neutrals` of metrics::full_rate_change(features, neutral).
/// @throws value_error with the message `none` when there is no neutral clip.
inline clip_feature_data judge_change(const std::vector<double>& features, const std::vector<const std::vector<double>*>& neutrals,
                                      const std::string& none)
{
    std::vector<double> sum;
    for (const auto* n : neutrals) {
        const auto d = metrics::full_rate_change(features, *n);
        if (sum.empty()) sum.assign(d.size(), 0.0);
        for (std::size_t k = 0; k < d.size(); ++k) sum[k] += d[k];
    }
    if (neutrals.empty()) throw value_error(none);
    clip_feature_data d;
    d.mean = xt::zeros<double>({sum.size()});
    for (std::size_t k = 0; k < sum.size(); ++k) d.mean(k) = sum[k] / static_cast<double>(neutrals.size());
    return d;
}

/// Every clip's features in the full-rate judge's space: the mean over the neutral clips n of its performer
/// (content) of metrics::full_rate_change(f(clip), f(n)), f = metrics::full_rate_features().
/// @throws value_error naming a performer without a neutral clip.
inline std::vector<clip_feature_data> judge_features(const std::vector<training_clip>& clips, const std::string& neutral)
{
    std::vector<std::vector<double>> f;
    f.reserve(clips.size());
    for (const auto& c : clips) {
        try {
            f.push_back(metrics::full_rate_features(*c.motion));
        } catch (const error& e) {
            throw value_error("rcm eval: " + c.name + ": " + e.what());
        }
    }
    std::vector<clip_feature_data> out;
    out.reserve(clips.size());
    for (std::size_t i = 0; i < clips.size(); ++i) {
        std::vector<const std::vector<double>*> ref;
        for (std::size_t j = 0; j < clips.size(); ++j)
            if (clips[j].performer == clips[i].performer && clips[j].emotion == neutral) ref.push_back(&f[j]);
        out.push_back(judge_change(f[i], ref, "rcm eval: judge features: '" + clips[i].performer + "' has no '" + neutral + "' clip to read " + clips[i].name + " against"));
    }
    return out;
}

/// The pose cluster of every window of every clip (the cluster of its centre frame), the clusters found on the
/// poses of the clips `train` only.
struct window_clusters {
    std::size_t count = 0;
    std::vector<std::vector<std::size_t>> of_clip;  ///< [clips][windows]
    pose_clustering clustering;                     ///< to assign the windows of other clips
};

/// The cluster of each window of one clip (of its centre frame's pose).
inline std::vector<std::size_t> assign_windows(const pose_clustering& pc, const clip_feature_data& f, const std::vector<pose>& poses)
{
    std::vector<std::size_t> out;
    const std::size_t frames = poses.size();
    const auto starts = window_starts(frames, f.window_length);
    for (std::size_t k = 0; k < f.windows.shape()[0]; ++k) out.push_back(pc.assign(poses[std::min(frames - 1, starts[k] + f.window_length / 2)]));
    return out;
}

inline window_clusters cluster_windows(const std::vector<clip_feature_data>& feats, const std::vector<std::vector<pose>>& poses,
                                       const std::vector<std::size_t>& train, const std::vector<double>& weights,
                                       pose_cluster_options co)
{
    std::vector<pose> pool;
    for (std::size_t i : train) pool.insert(pool.end(), poses[i].begin(), poses[i].end());
    co.clusters = std::min(co.clusters, pool.size());
    window_clusters wc;
    wc.clustering = cluster_poses(pool, weights, co);
    wc.count = wc.clustering.count();
    wc.of_clip.resize(feats.size());
    for (std::size_t i = 0; i < feats.size(); ++i) wc.of_clip[i] = assign_windows(wc.clustering, feats[i], poses[i]);
    return wc;
}

/// The share of a clip's windows in each of `count` clusters (summing to 1; all 0 for a clip without windows).
inline std::vector<double> window_shares(const std::vector<std::size_t>& window_cluster, std::size_t count)
{
    std::vector<double> s(count, 0.0);
    for (std::size_t c : window_cluster)
        if (c < count) s[c] += 1.0 / static_cast<double>(window_cluster.size());
    return s;
}

/// The `clusters` input's fit: the global model and one selection, PCA and Eq. 1 map per pose cluster (none for a
/// cluster with too few emotions or contents, or whose fit is singular).
struct cluster_fit {
    rcm_model global;
    std::vector<std::optional<emotion_map>> maps;
};

/// The normalised mean of a clip's windows in cluster c, or nothing when none is there.
inline std::optional<vector> cluster_mean(const rcm_model& global, const clip_feature_data& f, const std::vector<std::size_t>& window_cluster,
                                          std::size_t c)
{
    vector acc = xt::zeros<double>({global.normaliser.lo.size()});
    double n = 0;
    for (std::size_t k = 0; k < window_cluster.size(); ++k) {
        if (window_cluster[k] != c) continue;
        const vector row = xt::view(f.windows, k, xt::all());
        acc += global.normaliser.apply(row);
        n += 1;
    }
    if (n == 0) return std::nullopt;
    return vector(acc / n);
}

/// Fits the global model and one selection, PCA and Eq. 1 map per pose cluster on the training clips' normalised
/// windows in it (averaged per clip).
inline cluster_fit fit_clusters(const std::vector<training_clip>& clips, const std::vector<clip_feature_data>& feats, const window_clusters& wc,
                                const std::vector<std::size_t>& train, feature_set fs, const circumplex_table& table,
                                const std::string& table_name, const fit_options& opt)
{
    cluster_fit cf;
    cf.global = fit_from_features(clips, feats, train, fs, table, table_name, opt);
    const std::size_t D = cf.global.normaliser.lo.size();
    cf.maps.resize(wc.count);
    for (std::size_t c = 0; c < wc.count; ++c) {
        std::vector<vector> rows;
        std::vector<std::string> emo, perf;
        for (std::size_t i : train)
            if (auto r = cluster_mean(cf.global, feats[i], wc.of_clip[i], c))
                rows.push_back(std::move(*r)), emo.push_back(clips[i].emotion), perf.push_back(clips[i].performer);
        try {
            cf.maps[c] = fit_emotion_map(rows_of(rows, D), emo, perf, table, table_name, opt.selection, opt.pca_keep);
        } catch (const error&) {
            cf.maps[c].reset();  // too few clips, emotions or contents reach this cluster, or its fit is singular
        }
    }
    return cf;
}

/// A clip's point under the `clusters` input: the mean of the clusters' points weighted by its windows' shares
/// (the global point when no window reaches a cluster whose fit succeeded).
inline analysis analyse_clusters(const cluster_fit& cf, const clip_feature_data& f, const std::vector<std::size_t>& window_cluster)
{
    std::vector<analysis> points;
    std::vector<double> weights;
    const auto shares = window_shares(window_cluster, cf.maps.size());
    for (std::size_t c = 0; c < cf.maps.size(); ++c) {
        if (!cf.maps[c]) continue;
        const auto r = cluster_mean(cf.global, f, window_cluster, c);
        if (!r) continue;
        points.push_back((*cf.maps[c])(*r));
        weights.push_back(shares[c]);
    }
    return points.empty() ? analyse_mean(cf.global, f.mean) : weighted_point(points, weights);
}

/// The analysis input `clusters` on the clips `test`, fitted on `train`.
inline std::vector<analysis> fit_and_analyse_clusters(const std::vector<training_clip>& clips, const std::vector<clip_feature_data>& feats,
                                                      const window_clusters& wc, const std::vector<std::size_t>& train,
                                                      const std::vector<std::size_t>& test, feature_set fs, const circumplex_table& table,
                                                      const std::string& table_name, const fit_options& opt)
{
    const cluster_fit cf = fit_clusters(clips, feats, wc, train, fs, table, table_name, opt);
    std::vector<analysis> out;
    for (std::size_t i : test) out.push_back(analyse_clusters(cf, feats[i], wc.of_clip[i]));
    return out;
}

/// Every clip's features in every candidate input, computed once, and the fits and the inner choice on them.
struct analysis_bank {
    const std::vector<training_clip>* clips = nullptr;
    const circumplex_table* table = nullptr;
    std::string table_name, neutral;
    fit_options opt, judge_opt;
    std::vector<analysis_input> inputs;
    feature_set fs{};
    role_map roles;
    std::vector<clip_feature_data> feats, rel, judge;
    std::vector<std::vector<pose>> poses;
    std::vector<double> pose_w;

    analysis_bank(const std::vector<training_clip>& c, const circumplex_table& t, std::string name, const fit_options& o,
                  std::vector<analysis_input> in, std::string neutral_label)
        : clips(&c), table(&t), table_name(std::move(name)), neutral(std::move(neutral_label)), opt(o), judge_opt(o), inputs(std::move(in))
    {
        judge_opt.select = false;
        roles = training_roles(c.front().motion->skel, opt.role_overrides, &fs);
        feats = compute_features(c, roles, fs, opt.lma, opt.show_progress);
        if (uses(analysis_input::relative)) rel = relative_to_neutral(c, feats, neutral);
        if (uses(analysis_input::judge)) judge = judge_features(c, neutral);
        if (uses(analysis_input::clusters)) {
            for (const auto& x : c) poses.push_back(clip_poses(*x.motion, roles, opt.lma.up_axis));
            pose_w = pose_weights(c.front().motion->skel, roles);
        }
    }
    bool uses(analysis_input v) const { return std::find(inputs.begin(), inputs.end(), v) != inputs.end(); }
    /// the pose clusters of the clips `train` (none without the clusters input)
    window_clusters clusters_of(const std::vector<std::size_t>& train) const
    {
        return uses(analysis_input::clusters) ? cluster_windows(feats, poses, train, pose_w, opt.clustering) : window_clusters{};
    }
    /// input v fitted on `train`, the points of `test`; the fitted model (the global one for clusters) in *m
    std::vector<analysis> predict(analysis_input v, const window_clusters& wc, const std::vector<std::size_t>& train,
                                  const std::vector<std::size_t>& test, rcm_model* m) const
    {
        switch (v) {
        case analysis_input::relative: return fit_and_analyse(*clips, rel, train, test, fs, *table, table_name, opt, m);
        case analysis_input::judge: return fit_and_analyse(*clips, judge, train, test, fs, *table, table_name, judge_opt, m);
        case analysis_input::clusters: {
            if (m) *m = fit_from_features(*clips, feats, train, fs, *table, table_name, opt);
            return fit_and_analyse_clusters(*clips, feats, wc, train, test, fs, *table, table_name, opt);
        }
        case analysis_input::paper: break;
        }
        return fit_and_analyse(*clips, feats, train, test, fs, *table, table_name, opt, m);
    }
    /// the constant predictor of the clips `train`: their labels' mean point
    label_point mean_label(const std::vector<std::size_t>& train) const
    {
        label_point c{"constant", 0, 0};
        for (std::size_t i : train) {
            const auto& l = table->at((*clips)[i].emotion, table_name);
            c.valence += l.valence / static_cast<double>(train.size());
            c.arousal += l.arousal / static_cast<double>(train.size());
        }
        return c;
    }
    /// The inner leave-one-group-out on the clips `train` (their groups in `group`, one per clip of the bank): each
    /// candidate input fitted without one group and its non-neutral clips analysed, then choose_variant() over the
    /// weights. Inner folds one of the candidates cannot fit are left out for all. With one input and one weight,
    /// that pair without fitting anything.
    variant_choice choose(const std::vector<std::string>& group, const std::vector<std::size_t>& train, const std::vector<double>& weights,
                          const window_clusters& wc) const
    {
        if (inputs.size() <= 1 && weights.size() <= 1) return {0, weights.empty() ? 1.0 : weights.front(), 0};
        std::vector<std::string> inner_groups;
        for (std::size_t i : train) inner_groups.push_back(group[i]);
        std::vector<std::vector<analysis>> pred(inputs.size());
        std::vector<label_point> constant, truth;
        for (const auto& g : sorted_unique(inner_groups)) {
            std::vector<std::size_t> in_train, in_test;
            for (std::size_t i : train) {
                if (group[i] != g) in_train.push_back(i);
                else if (neutral.empty() || (*clips)[i].emotion != neutral) in_test.push_back(i);
            }
            if (in_test.empty()) continue;
            std::vector<std::vector<analysis>> p;
            try {
                for (auto v : inputs) p.push_back(predict(v, wc, in_train, in_test, nullptr));
            } catch (const error&) {
                continue;  // an inner fold one of the candidates cannot fit is left out for all
            }
            const label_point c = mean_label(in_train);
            for (std::size_t v = 0; v < inputs.size(); ++v) pred[v].insert(pred[v].end(), p[v].begin(), p[v].end());
            for (std::size_t i : in_test) constant.push_back(c), truth.push_back(table->at((*clips)[i].emotion, table_name));
        }
        return choose_variant(pred, constant, truth, weights);
    }
};

/// The candidate inputs of loo_options (from `relative` when none are listed); value_error for both given, or a
/// missing neutral label with relative or judge inputs.
inline std::vector<analysis_input> candidate_inputs(const loo_options& lo)
{
    if (!lo.inputs.empty() && lo.relative != relative_features::off)
        throw value_error("rcm eval: give the relative option or the candidate inputs, not both");
    std::vector<analysis_input> inputs = lo.inputs;
    if (inputs.empty()) {
        if (lo.relative != relative_features::on) inputs.push_back(analysis_input::paper);
        if (lo.relative != relative_features::off) inputs.push_back(analysis_input::relative);
    }
    auto uses = [&](analysis_input v) { return std::find(inputs.begin(), inputs.end(), v) != inputs.end(); };
    if ((uses(analysis_input::relative) || uses(analysis_input::judge)) && lo.neutral.empty())
        throw value_error(std::string("rcm eval: ") + (uses(analysis_input::judge) && !uses(analysis_input::relative) ? "judge" : "relative") +
                          " features need the neutral label");
    return inputs;
}

}  // namespace detail

/// @brief Leave-one-group-out evaluation of the analysis: for each value of `group` (content or take), fit on
/// the other clips (no pose clusters unless the `clusters` input is a candidate) and analyse the held-out ones.
/// With one candidate input and one shrinkage weight, that is the analysis; with more (lo.inputs, lo.shrink, or
/// relative_features::automatic), each fold chooses the pair (input, weight) by an inner leave-one-group-out over
/// its training groups: the pair with the least mean distance over the inner held-out non-neutral clips, each
/// point shrunk toward the inner fold's constant predictor (choose_variant(); inner folds a candidate cannot fit
/// are left out for all). The outer fold's point is then shrunk toward its own constant predictor, the mean label
/// point of its training clips. docs/circumplex.md gives the rule.
/// @throws value_error for no clips, both lo.relative and lo.inputs, a missing neutral label with relative or
///         judge inputs, or a performer without a neutral clip to read its clips against.
inline eval_report evaluate_loo(const std::vector<training_clip>& clips, const std::vector<std::string>& group,
                                const circumplex_table& table, const std::string& table_name, const fit_options& opt,
                                const loo_options& lo = {})
{
    if (clips.empty()) throw value_error("rcm eval: no clips");
    if (group.size() != clips.size()) throw shape_error("rcm eval: one group per clip needed");
    const std::vector<analysis_input> inputs = detail::candidate_inputs(lo);
    const std::vector<double> weights = lo.shrink.empty() ? std::vector<double>{1.0} : lo.shrink;
    const detail::analysis_bank bank(clips, table, table_name, opt, inputs, lo.neutral);
    eval_report rep;
    rep.folds = detail::sorted_unique(group);
    progress bar("rcm eval folds", static_cast<long>(rep.folds.size()), opt.show_progress ? stderr : nullptr);
    std::size_t fitted = 0, qbase = 0;
    double shrink_sum = 0;
    for (std::size_t f = 0; f < rep.folds.size(); ++f) {
        std::vector<std::size_t> train, test;
        for (std::size_t i = 0; i < clips.size(); ++i) (group[i] == rep.folds[f] ? test : train).push_back(i);
        const label_point base = bank.mean_label(train);
        detail::window_clusters wc;
        variant_choice choice{0, weights.front(), 0};
        try {
            wc = bank.clusters_of(train);
            choice = bank.choose(group, train, weights, wc);
        } catch (const error& e) {
            rep.failed_folds.push_back(rep.folds[f] + ": " + e.what());
            bar.update(static_cast<long>(f + 1));
            continue;
        }
        const analysis_input input = inputs[choice.input];
        rcm_model m;
        std::vector<analysis> an;
        try {
            an = bank.predict(input, wc, train, test, &m);
        } catch (const error& e) {
            rep.failed_folds.push_back(rep.folds[f] + ": " + e.what());
            bar.update(static_cast<long>(f + 1));
            continue;
        }
        ++fitted;
        const bool relative = input == analysis_input::relative;
        rep.relative_folds += relative ? 1 : 0;
        ++rep.input_folds[to_string(input)];
        shrink_sum += choice.shrink;
        rep.mean_selected += static_cast<double>(m.selected.size());
        rep.mean_pca_dims += static_cast<double>(m.pca.dims());
        const double bv = base.valence, ba = base.arousal;
        for (std::size_t k = 0; k < test.size(); ++k) {
            const std::size_t i = test[k];
            const analysis a = choice.shrink == 1.0 ? an[k] : shrink_toward(an[k], bv, ba, choice.shrink);
            const auto& l = table.at(clips[i].emotion, table_name);
            eval_sample es;
            es.name = clips[i].name;
            es.emotion = clips[i].emotion;
            es.held_out = rep.folds[f];
            es.valence = a.valence, es.arousal = a.arousal;
            es.true_valence = l.valence, es.true_arousal = l.arousal;
            es.distance = std::hypot(a.valence - l.valence, a.arousal - l.arousal);
            es.quadrant_ok = a.quadrant == quadrant(l.valence, l.arousal);
            es.baseline_distance = std::hypot(bv - l.valence, ba - l.arousal);
            es.neutral = !lo.neutral.empty() && clips[i].emotion == lo.neutral;
            es.relative = relative;
            es.input = to_string(input);
            es.shrink = choice.shrink;
            qbase += quadrant(bv, ba) == quadrant(l.valence, l.arousal) ? 1 : 0;
            rep.samples.push_back(es);
        }
        bar.update(static_cast<long>(f + 1));
    }
    const double n = static_cast<double>(rep.samples.size());
    double ne = 0;
    for (const auto& s : rep.samples) {
        rep.mean_distance += s.distance / n;
        rep.quadrant_accuracy += (s.quadrant_ok ? 1.0 : 0.0) / n;
        rep.baseline_distance += s.baseline_distance / n;
        if (!s.neutral) rep.emotional_distance += s.distance, rep.emotional_baseline_distance += s.baseline_distance, ne += 1;
    }
    if (ne > 0) rep.emotional_distance /= ne, rep.emotional_baseline_distance /= ne;
    rep.baseline_quadrant_accuracy = n > 0 ? static_cast<double>(qbase) / n : 0;
    if (fitted) {
        rep.mean_selected /= static_cast<double>(fitted), rep.mean_pca_dims /= static_cast<double>(fitted);
        rep.mean_shrink = shrink_sum / static_cast<double>(fitted);
    }
    return rep;
}

/// @brief What a clip is read against under the `relative` and `judge` inputs: the neutral clips of its content.
struct neutral_reference {
    vector mean_features;                         ///< the mean of their raw derived features (relative)
    std::vector<std::vector<double>> full_rate;   ///< each one's metrics::full_rate_features() (judge)
    std::size_t clips = 0;
};

struct model_and_analysis;

/// @brief An analysis whose input and shrinkage weight were chosen on its own training clips, the way each fold of
/// evaluate_loo() chooses them (an inner leave-one-group-out over the training contents, choose_variant()), kept to
/// analyse other clips: the outputs of a transfer, read against the neutral clips of their content. fit_chosen()
/// makes one; on a fold's training clips it gives, for that fold's held-out clips, the points evaluate_loo() does.
class chosen_analysis {
public:
    analysis_input input() const noexcept { return input_; }
    double shrink() const noexcept { return shrink_; }
    /// the mean distance of the chosen pair over the inner held-out non-neutral clips (0 when nothing was chosen)
    double inner_distance() const noexcept { return inner_distance_; }
    /// the constant predictor the points are pulled toward: the training clips' mean label point
    const label_point& constant() const noexcept { return constant_; }
    /// the model of the chosen input's features (for `clusters`, the global one)
    const rcm_model& model() const noexcept { return model_; }

    /// @brief The reference of a content from its neutral clips (any number for the paper and clusters inputs, at
    /// least one for relative and judge); `content` names it in errors.
    /// @throws value_error when relative or judge has no neutral clip, or a clip's features cannot be computed.
    neutral_reference reference(const std::vector<const clip*>& neutrals, const std::string& content) const
    {
        neutral_reference r;
        r.clips = neutrals.size();
        if (input_ != analysis_input::relative && input_ != analysis_input::judge) return r;
        if (neutrals.empty()) throw value_error("rcm analysis: '" + content + "' has no neutral clip to read its clips against");
        for (std::size_t k = 0; k < neutrals.size(); ++k) {
            const std::string who = "the neutral clip " + std::to_string(k + 1) + " of '" + content + "'";
            if (input_ == analysis_input::relative) {
                const vector m = features_of(*neutrals[k], who).mean;
                if (k == 0) r.mean_features = xt::zeros<double>({m.size()});
                r.mean_features += m;
            } else {
                r.full_rate.push_back(full_rate_of(*neutrals[k], who));
            }
        }
        if (input_ == analysis_input::relative) r.mean_features /= static_cast<double>(neutrals.size());
        return r;
    }

    /// @brief The point of the chosen input for a clip of the content `ref` was made from, before the pull toward
    /// the constant (its ranks among a content's clips are those of analyse() whenever shrink() > 0).
    /// @throws shape_error for a skeleton other than the training one; value_error when its features cannot be computed.
    analysis analyse_unshrunk(const clip& c, const neutral_reference& ref, const std::string& who = "clip") const
    {
        if (fitted_ && !c.skel.same_topology(skel_)) throw shape_error("rcm analysis: " + who + " has a skeleton other than the training clips'");
        try {
            return point_of(c, ref, who);
        } catch (const shape_error& e) {  // a feature count other than the fit's (a read model, another skeleton)
            throw shape_error("rcm analysis: " + who + ": " + e.what());
        }
    }

    /// @brief The analysis of a clip of the content `ref` was made from: the chosen input's point pulled toward the
    /// constant by the chosen weight.
    analysis analyse(const clip& c, const neutral_reference& ref, const std::string& who = "clip") const
    {
        const analysis a = analyse_unshrunk(c, ref, who);
        return shrink_ == 1.0 ? a : shrink_toward(a, constant_.valence, constant_.arousal, shrink_);
    }

    /// @brief True when the chosen input reads a clip against its content's neutral clips (relative, judge).
    bool needs_neutral() const noexcept { return input_ == analysis_input::relative || input_ == analysis_input::judge; }
    /// @brief The neutral label the choice read the training clips against (empty when none was given).
    const std::string& neutral_label() const noexcept { return neutral_; }

    /// @brief The paper's analysis of a model: its Table 1 map, no pull toward the constant.
    static chosen_analysis paper(const rcm_model& m)
    {
        chosen_analysis a;
        a.model_ = m;
        return a;
    }

private:
    friend model_and_analysis fit_model_and_chosen(const std::vector<training_clip>&, const circumplex_table&, const std::string&,
                                                   const fit_options&, const loo_options&);
    /// the inner choice over the bank's clips (groups: their performers), then the chosen input fitted on all of them
    static chosen_analysis from_bank(const detail::analysis_bank& bank, const loo_options& lo)
    {
        const auto& clips = *bank.clips;
        const std::vector<double> weights = lo.shrink.empty() ? std::vector<double>{1.0} : lo.shrink;
        std::vector<std::size_t> all(clips.size());
        std::vector<std::string> group;
        for (std::size_t i = 0; i < clips.size(); ++i) all[i] = i, group.push_back(clips[i].performer);
        const detail::window_clusters wc = bank.clusters_of(all);
        const variant_choice choice = bank.choose(group, all, weights, wc);
        chosen_analysis a;
        a.input_ = bank.inputs[choice.input];
        a.shrink_ = choice.shrink;
        a.inner_distance_ = choice.distance;
        a.constant_ = bank.mean_label(all);
        a.neutral_ = lo.neutral;
        a.candidates_ = bank.inputs;
        a.candidate_weights_ = weights;
        a.fitted_ = true;
        a.skel_ = clips.front().motion->skel;
        a.roles_ = bank.roles;
        if (a.input_ == analysis_input::clusters) {
            a.clusters_ = detail::fit_clusters(clips, bank.feats, wc, all, bank.fs, *bank.table, bank.table_name, bank.opt);
            a.clustering_ = wc.clustering;
            a.model_ = a.clusters_.global;
        } else {
            bank.predict(a.input_, wc, all, {}, &a.model_);
        }
        a.model_.roles = bank.roles.to_json();
        a.model_.features = bank.fs;
        a.model_.lma = bank.opt.lma;
        return a;
    }
    friend chosen_analysis fit_chosen(const std::vector<training_clip>&, const circumplex_table&, const std::string&, const fit_options&,
                                      const loo_options&);
    friend nlohmann::json analysis_to_json(const chosen_analysis&);
    friend chosen_analysis analysis_from_json(const nlohmann::json&, const rcm_model&, const std::string&);

    role_map roles_of(const clip& c) const { return fitted_ ? roles_ : model_.roles_for(c.skel); }
    analysis point_of(const clip& c, const neutral_reference& ref, const std::string& who) const
    {
        switch (input_) {
        case analysis_input::judge: {
            std::vector<const std::vector<double>*> n;
            for (const auto& f : ref.full_rate) n.push_back(&f);
            return detail::analyse_mean(model_, detail::judge_change(full_rate_of(c, who), n, "rcm analysis: " + who + " has no neutral clip to be read against").mean);
        }
        case analysis_input::relative: {
            if (ref.mean_features.size() == 0) throw value_error("rcm analysis: " + who + " has no neutral clip to be read against");
            return detail::analyse_mean(model_, vector(features_of(c, who).mean - ref.mean_features));
        }
        case analysis_input::clusters: {
            const auto f = features_of(c, who);
            return detail::analyse_clusters(clusters_, f, detail::assign_windows(clustering_, f, clip_poses(c, roles_of(c), model_.lma.up_axis)));
        }
        case analysis_input::paper: break;
        }
        return detail::analyse_mean(model_, features_of(c, who).mean);
    }
    clip_feature_data features_of(const clip& c, const std::string& who) const
    {
        clip_feature_data d;
        try {
            d.windows = window_features(world_positions(c), c.fps, roles_of(c), model_.features, model_.lma);
        } catch (const error& e) {
            throw value_error("rcm analysis: " + who + ": " + e.what());
        }
        d.mean = xt::mean(d.windows, {0});
        d.window_length = std::min(c.frames, window_length(c.fps, model_.lma));
        return d;
    }
    static std::vector<double> full_rate_of(const clip& c, const std::string& who)
    {
        try {
            return metrics::full_rate_features(c);
        } catch (const error& e) {
            throw value_error("rcm analysis: " + who + ": " + e.what());
        }
    }

    analysis_input input_ = analysis_input::paper;
    double shrink_ = 1, inner_distance_ = 0;
    label_point constant_{"constant", 0, 0};
    std::string neutral_;
    std::vector<analysis_input> candidates_{analysis_input::paper};  ///< what the choice chose among
    std::vector<double> candidate_weights_{1.0};
    rcm_model model_;  ///< the chosen input's map (its features, lma and role names: the training skeleton's)
    detail::cluster_fit clusters_;
    pose_clustering clustering_;
    bool fitted_ = false;  ///< fitted here (the training skeleton and its roles known), not read from a file
    skeleton skel_;
    role_map roles_;
};

/// @brief Fits a chosen_analysis on labelled clips (one skeleton; `performer` is the content): the candidate inputs
/// and weights of `lo` (as evaluate_loo() takes them; `--input auto --shrink auto` is lo.inputs =
/// parse_analysis_inputs("auto"), lo.shrink = shrink_grid()), chosen by the inner leave-one-content-out over these
/// clips, then the chosen input fitted on all of them.
/// @throws value_error / shape_error as evaluate_loo() does, and when the chosen input's fit fails.
inline chosen_analysis fit_chosen(const std::vector<training_clip>& clips, const circumplex_table& table, const std::string& table_name,
                                  const fit_options& opt, const loo_options& lo)
{
    detail::check_training_clips(clips, "rcm analysis");
    const std::vector<analysis_input> inputs = detail::candidate_inputs(lo);
    const detail::analysis_bank bank(clips, table, table_name, opt, inputs, lo.neutral);
    return chosen_analysis::from_bank(bank, lo);
}

/// @brief The paper's model and the chosen analysis of the same clips: fit_model(clips, table, table_name, opt) and
/// fit_chosen(clips, table, table_name, opt, lo), with every clip's features computed once (what `rcm fit` stores).
struct model_and_analysis {
    rcm_model model;
    chosen_analysis analysis;
};

/// @brief fit_model() and fit_chosen() on the same clips and options, sharing the clips' features.
/// @throws as fit_model() and fit_chosen() do.
inline model_and_analysis fit_model_and_chosen(const std::vector<training_clip>& clips, const circumplex_table& table,
                                               const std::string& table_name, const fit_options& opt, const loo_options& lo)
{
    detail::check_training_clips(clips, "rcm fit");
    const std::vector<analysis_input> inputs = detail::candidate_inputs(lo);
    const detail::analysis_bank bank(clips, table, table_name, opt, inputs, lo.neutral);
    model_and_analysis r;
    r.model = detail::fit_model_from_features(clips, bank.feats, bank.roles, bank.fs, table, table_name, opt);
    r.analysis = chosen_analysis::from_bank(bank, lo);
    return r;
}

namespace detail {

/// The analysis half of a map as JSON: selected indices, PCA, Eq. 1 (and the normaliser when given).
inline nlohmann::json map_to_json(const std::vector<std::size_t>& selected, const pca_model& pca, const rbf_map& to_emotion,
                                  const feature_normaliser* norm = nullptr)
{
    nlohmann::json j;
    if (norm) j["normaliser"] = {{"lo", norm->lo}, {"hi", norm->hi}};
    j["selected"] = selected;
    j["pca"] = {{"mean", to_json(pca.mean)}, {"components", to_json(pca.components)}, {"variances", to_json(pca.variances)},
                {"total_variance", pca.total_variance}};
    j["to_emotion"] = to_json(to_emotion);
    return j;
}

/// Reads map_to_json()'s fields at `path` (a prefix ending in '.') on D normalised features (D from the normaliser
/// when `norm` is given).
inline void map_from_json(const model_reader& rd, const nlohmann::json& j, const std::string& path, std::size_t D, std::vector<std::size_t>& selected,
                          pca_model& pca, rbf_map& to_emotion, feature_normaliser* norm = nullptr)
{
    if (norm) {
        const auto& nm = rd.get(j, "normaliser", path);
        const auto lo = rd.numbers(rd.get(nm, "lo", path + "normaliser."), path + "normaliser.lo");
        if (lo.empty()) rd.fail(path + "normaliser.lo", "is empty");
        const auto hi = rd.vec(nm, "hi", path + "normaliser.", lo.size());
        norm->lo = lo;
        norm->hi.assign(hi.begin(), hi.end());
        D = lo.size();
    }
    selected = rd.indices(rd.get(j, "selected", path), path + "selected", D);
    if (selected.empty()) rd.fail(path + "selected", "is empty");
    const std::size_t S = selected.size();
    const auto& pj = rd.get(j, "pca", path);
    const auto& comps = rd.get(pj, "components", path + "pca.");
    if (!comps.is_array() || comps.empty() || comps.size() > S)
        rd.fail(path + "pca.components", "is not an array of 1 to " + std::to_string(S) + " rows");
    const std::size_t d = comps.size();
    pca.mean = rd.vec(pj, "mean", path + "pca.", S);
    pca.components = rd.mat(pj, "components", path + "pca.", d, S);
    pca.variances = rd.vec(pj, "variances", path + "pca.", d);
    pca.total_variance = rd.number(pj, "total_variance", path + "pca.");
    const auto& te = rd.get(j, "to_emotion", path);
    model_reader sub{rd.file};
    try {
        to_emotion = sub.rbf(nlohmann::json{{"to_emotion", te}}, "to_emotion", d, 2);
    } catch (const format_error& e) {  // the field path inside the map
        std::string m = e.what();
        if (const auto at = m.find("field 'to_emotion"); at != std::string::npos) m.replace(at, 7, "field '" + path);
        throw format_error(m);
    }
}

}  // namespace detail

/// @brief A chosen analysis as the "analysis" block of a model file (see save_model()).
inline nlohmann::json analysis_to_json(const chosen_analysis& a)
{
    nlohmann::json j;
    j["input"] = to_string(a.input_);
    j["shrink"] = a.shrink_;
    j["inner_distance"] = a.inner_distance_;
    j["constant"] = {{"valence", a.constant_.valence}, {"arousal", a.constant_.arousal}};
    j["neutral"] = a.neutral_;
    nlohmann::json cand = nlohmann::json::array();
    for (auto v : a.candidates_) cand.push_back(to_string(v));
    j["candidates"] = {{"inputs", cand}, {"shrink", a.candidate_weights_}};
    if (a.input_ == analysis_input::relative || a.input_ == analysis_input::judge)
        j["map"] = detail::map_to_json(a.model_.selected, a.model_.pca, a.model_.to_emotion, &a.model_.normaliser);
    if (a.input_ == analysis_input::clusters) {
        nlohmann::json med = nlohmann::json::array(), maps = nlohmann::json::array();
        for (const auto& p : a.clustering_.medoids) med.push_back(detail::to_json(p));
        for (const auto& m : a.clusters_.maps) maps.push_back(m ? detail::map_to_json(m->selected, m->pca, m->to_emotion) : nlohmann::json());
        j["clusters"] = {{"weights", a.clustering_.weights}, {"height_weight", a.clustering_.height_weight},
                         {"height_scale", a.clustering_.height_scale}, {"medoids", med}, {"maps", maps}};
    }
    return j;
}

/// @brief Reads the "analysis" block of a model file, the model `m` read from the same file (whose map the
/// `paper` and `clusters` inputs use, and whose role names every input uses).
/// @throws format_error naming `file` and the field.
inline chosen_analysis analysis_from_json(const nlohmann::json& j, const rcm_model& m, const std::string& file)
{
    detail::model_reader rd{file};
    const std::string p = "analysis.";
    if (!j.is_object()) rd.fail("analysis", "is not an object");
    chosen_analysis a;
    const std::string input = rd.text(j, "input", p);
    try {
        a.input_ = parse_analysis_inputs(input).at(0);
    } catch (const value_error&) {
        rd.fail(p + "input", "is '" + input + "', expected paper, relative, clusters or judge");
    }
    if (input == "auto") rd.fail(p + "input", "is 'auto', expected the chosen input");
    a.shrink_ = rd.number(j, "shrink", p);
    if (!(a.shrink_ >= 0 && a.shrink_ <= 1)) rd.fail(p + "shrink", "is not in [0, 1]");
    a.inner_distance_ = rd.number(j, "inner_distance", p);
    const auto& c = rd.get(j, "constant", p);
    a.constant_ = {"constant", rd.number(c, "valence", p + "constant."), rd.number(c, "arousal", p + "constant.")};
    if (std::abs(a.constant_.valence) > 1 || std::abs(a.constant_.arousal) > 1) rd.fail(p + "constant", "is outside [-1, 1]");
    a.neutral_ = rd.text(j, "neutral", p);
    const auto& cand = rd.get(j, "candidates", p);
    const auto& ci = rd.get(cand, "inputs", p + "candidates.");
    if (!ci.is_array() || ci.empty()) rd.fail(p + "candidates.inputs", "is not a non-empty array");
    a.candidates_.clear();
    for (std::size_t i = 0; i < ci.size(); ++i) {
        const std::string f = p + "candidates.inputs[" + std::to_string(i) + "]";
        if (!ci[i].is_string()) rd.fail(f, "is not a string");
        try {
            const auto v = parse_analysis_inputs(ci[i].get<std::string>());
            if (v.size() != 1) rd.fail(f, "is not one input");
            a.candidates_.push_back(v.front());
        } catch (const value_error&) {
            rd.fail(f, "is not paper, relative, clusters or judge");
        }
    }
    a.candidate_weights_ = rd.numbers(rd.get(cand, "shrink", p + "candidates."), p + "candidates.shrink");
    if (a.needs_neutral() && a.neutral_.empty()) rd.fail(p + "neutral", "is empty, but input " + input + " reads clips against neutral clips");
    a.model_ = m;
    if (a.needs_neutral()) {
        detail::map_from_json(rd, rd.get(j, "map", p), p + "map.", 0, a.model_.selected, a.model_.pca, a.model_.to_emotion, &a.model_.normaliser);
        if (a.input_ == analysis_input::relative && a.model_.normaliser.lo.size() != derived_count(m.features))
            rd.fail(p + "map.normaliser.lo", "has " + std::to_string(a.model_.normaliser.lo.size()) + " values, expected " +
                                                 std::to_string(derived_count(m.features)));
    }
    if (a.input_ == analysis_input::clusters) {
        const std::string q = p + "clusters.";
        const auto& cj = rd.get(j, "clusters", p);
        a.clustering_.weights = rd.numbers(rd.get(cj, "weights", q), q + "weights");
        a.clustering_.height_weight = rd.number(cj, "height_weight", q);
        a.clustering_.height_scale = rd.number(cj, "height_scale", q);
        if (!(a.clustering_.height_scale > 0)) rd.fail(q + "height_scale", "is not positive");
        const auto& med = rd.get(cj, "medoids", q);
        if (!med.is_array() || med.empty()) rd.fail(q + "medoids", "is not a non-empty array");
        const std::size_t J = a.clustering_.weights.size();
        for (std::size_t k = 0; k < med.size(); ++k) {
            const std::string r = q + "medoids[" + std::to_string(k) + "].";
            pose ps;
            ps.height = rd.number(med[k], "height", r);
            const matrix qm = rd.mat(med[k], "q", r, J, 4);
            for (std::size_t i = 0; i < J; ++i) ps.q.push_back({qm(i, 0), qm(i, 1), qm(i, 2), qm(i, 3)});
            a.clustering_.medoids.push_back(std::move(ps));
        }
        const auto& maps = rd.get(cj, "maps", q);
        if (!maps.is_array() || maps.size() != med.size()) rd.fail(q + "maps", "does not have one entry (a map or null) per medoid");
        a.clusters_.global = m;
        for (std::size_t k = 0; k < maps.size(); ++k) {
            if (maps[k].is_null()) {
                a.clusters_.maps.emplace_back();
                continue;
            }
            emotion_map em;
            detail::map_from_json(rd, maps[k], q + "maps[" + std::to_string(k) + "].", m.normaliser.lo.size(), em.selected, em.pca, em.to_emotion);
            a.clusters_.maps.push_back(std::move(em));
        }
    }
    return a;
}

/// @brief Writes a model file atomically with its chosen analysis: `"version": 2` and an "analysis" block (the
/// chosen input and weight, the constant, and the chosen input's own map where it is not the model's).
inline void save_model(const rcm_model& m, const chosen_analysis& a, const std::filesystem::path& path)
{
    nlohmann::json j = model_to_json(m);
    j["version"] = 2;
    j["analysis"] = analysis_to_json(a);
    write_file_atomic(path, j.dump(1) + "\n");
}

/// @brief The chosen analysis of a model file: its "analysis" block (version 2), or the paper's analysis of its
/// model (version 1, which has none).
/// @throws io_error when it cannot be read, format_error naming the file and field when it is malformed.
inline chosen_analysis load_analysis(const std::filesystem::path& path)
{
    const nlohmann::json j = detail::read_model_json(path);
    const rcm_model m = model_from_json(j, path.string());
    if (!j.contains("analysis")) return chosen_analysis::paper(m);
    return analysis_from_json(j.at("analysis"), m, path.string());
}

}  // namespace handemo::rcm
