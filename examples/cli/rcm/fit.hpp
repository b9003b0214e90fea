// `handemo rcm fit --data DIR --out MODEL.json [--input auto|...] [--shrink auto|none|S] [--neutral LABEL]`: fits
// the circumplex analysis model (features, selection, PCA, RBF maps both ways, pose clusters) on a labelled folder,
// prints which features survive, and chooses the analysis the way each fold of `rcm eval` does (input and pull
// toward the constant by a leave-one-content-out over the folder), stored in the same file.
#pragma once

#include "common.hpp"

#include <cstdio>
#include <iostream>
#include <memory>

namespace handemo::cli::rcm_cmd {

struct fit_run {
    fit_cli f;
    std::string out;
    std::size_t clusters = 5;
    bool no_clusters = false;
    std::string input = "auto", shrink = "auto", neutral;
    bool input_given = false;
};

inline void print_selection(const handemo::rcm::rcm_model& m, std::ostream& os)
{
    const auto& s = m.selection;
    os << "rcm fit: effective = std across emotions >= 0.21 for " << s.need_effective << " of " << s.performers << " "
       << m.performer_kind << "s (the paper's performers); consistent = std across " << m.performer_kind << "s <= 0.2 for "
       << s.need_consistent << " of " << s.emotions << " emotions\n";
    os << "rcm fit: " << s.survivors << " of " << handemo::rcm::derived_count(m.features) << " features pass both tests";
    if (s.fallback) os << "; filled up to " << m.selected.size() << " with the features closest to passing";
    os << "\n";
    const auto& defs = handemo::rcm::derived_features(m.features);
    for (std::size_t i : m.selected) {
        os << "  " << defs[i].name << "  (effective for " << s.effective_count[i] << ", consistent for " << s.consistent_count[i]
           << (s.effective_count[i] >= s.need_effective && s.consistent_count[i] >= s.need_consistent ? ", survives)" : ")") << "\n";
    }
    os << "rcm fit: PCA keeps " << m.pca.dims() << " of " << m.selected.size() << " dimensions\n";
    if (m.has_clusters)
        for (std::size_t c = 0; c < m.clusters.count(); ++c)
            os << "rcm fit: pose cluster " << c << ": " << m.clusters.sizes[c] << " poses, "
               << (m.cluster_selected[c].empty() ? std::string("no selection (fewer than two emotions or ") + m.performer_kind +
                                                       "s have windows centred in it)"
                                                 : std::to_string(m.cluster_survivors[c]) + " features pass both tests, " +
                                                       std::to_string(m.cluster_selected[c].size()) + " selected")
               << "\n";
}

inline void run_fit(fit_run& o)
{
    finish_options(o.f);
    o.f.opt.cluster = !o.no_clusters;
    o.f.opt.clustering.clusters = o.clusters;
    const auto table = handemo::rcm::load_circumplex(o.f.labels);
    const auto set = load_set(o.f.data);
    check_labels(set, table, o.f.labels);
    std::cout << "rcm fit: " << set.clips.size() << " clips from " << o.f.data << "; contents play the performers' role\n";
    const auto lo = analysis_candidates(set, o.neutral, o.input, o.input_given, o.shrink, "rcm fit");
    const auto fitted = handemo::rcm::fit_model_and_chosen(set.clips, table, o.f.labels, o.f.opt, lo);
    const auto& m = fitted.model;
    const auto& a = fitted.analysis;
    // the selection counts are not stored per feature in the file; print them now
    print_selection(m, std::cout);
    char line[256];
    std::snprintf(line, sizeof line, "rcm fit: analysis: input %s, shrink %.1f toward (%.3f, %.3f)", handemo::rcm::to_string(a.input()), a.shrink(),
                  a.constant().valence, a.constant().arousal);
    std::cout << line;
    if (lo.inputs.size() > 1 || lo.shrink.size() > 1) {
        std::snprintf(line, sizeof line, ", chosen by leave-one-content-out (inner mean distance %.3f)", a.inner_distance());
        std::cout << line;
    }
    if (a.needs_neutral()) std::cout << "; clips are read against their content's '" << lo.neutral << "' clips (rcm analyse --neutral)";
    std::cout << "\n";
    handemo::rcm::save_model(m, a, o.out);
    std::cout << "rcm fit: wrote " << o.out << " (" << handemo::rcm::to_string(m.features) << " features, labels:";
    for (const auto& l : m.labels) std::cout << " " << l.name;
    std::cout << ")\n";
}

inline void add_fit(CLI::App& rcm)
{
    auto* sub = rcm.add_subcommand("fit", "Fit the circumplex analysis model on a labelled folder, with the analysis chosen on it");
    auto o = std::make_shared<fit_run>();
    add_fit_options(sub, o->f);
    sub->add_option("--out", o->out, "Model file to write (JSON)")->required();
    sub->add_option("--clusters", o->clusters, "Pose clusters (Section 3.5)")->capture_default_str();
    sub->add_flag("--no-clusters", o->no_clusters, "Skip the pose clustering");
    auto* input = sub->add_option("--input", o->input,
                                  "The analysis's input: paper, relative, clusters, judge, or auto (chosen by leave-one-content-out "
                                  "on the folder, as each fold of rcm eval chooses it)")
                      ->check(CLI::IsMember({"paper", "relative", "clusters", "judge", "auto"}))
                      ->capture_default_str();
    sub->add_option("--shrink", o->shrink, "The pull toward the constant predictor: none, a weight in [0, 1], or auto (chosen with --input)")
        ->capture_default_str();
    sub->add_option("--neutral", o->neutral, "The neutral label (default: neutral, else normal, when the data has it)");
    sub->callback([o, input] {
        o->input_given = input->count() > 0;
        run_fit(*o);
    });
}

}  // namespace handemo::cli::rcm_cmd
