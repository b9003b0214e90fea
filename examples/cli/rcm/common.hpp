// Shared parts of the `handemo rcm` subcommands: loading a labelled folder (labels from file names
// `<prefix>_<content>_<emotion>_<take>` or a manifest.csv, as stargan::load_folder reads them), the label
// table, and the fit options every subcommand takes.
#pragma once

#include <handemo/rcm.hpp>
#include <handemo/stargan/dataset.hpp>

#include <CLI/CLI.hpp>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#ifndef HANDEMO_RCM_CIRCUMPLEX
#define HANDEMO_RCM_CIRCUMPLEX "data/rcm/circumplex.json"
#endif

namespace handemo::cli::rcm_cmd {

/// Options shared by fit and eval.
struct fit_cli {
    std::string data, labels = HANDEMO_RCM_CIRCUMPLEX, roles;
    handemo::rcm::fit_options opt;
};

inline void add_fit_options(CLI::App* sub, fit_cli& o)
{
    sub->add_option("--data", o.data, "Folder of <prefix>_<content>_<emotion>_<take>.bvh|csv clips (or with a manifest.csv)")->required();
    sub->add_option("--labels", o.labels, "Circumplex coordinates of the labels (JSON with its citation)")->capture_default_str();
    sub->add_option("--roles", o.roles, "JSON file {\"roles\": {\"left_hand\": \"Hand_L\", ...}} overriding the joint roles found from names");
    sub->add_option("--min-features", o.opt.selection.min_features,
                    "Features kept when fewer pass the effective/consistent tests (filled with the closest to passing)")
        ->capture_default_str();
    sub->add_option("--window", o.opt.lma.window_frames_at_30, "Sliding window in frames at 30 fps (scaled with the frame rate)")
        ->capture_default_str();
    sub->add_option("--pca-variance", o.opt.pca_keep, "Share of the variance the PCA keeps")->capture_default_str();
}

/// The labelled clips of a folder, with contents as performers.
struct loaded_set {
    std::vector<handemo::labelled_clip> items;
    std::vector<handemo::rcm::training_clip> clips;
};

inline loaded_set load_set(const std::string& dir)
{
    loaded_set s;
    s.items = handemo::stargan::load_folder(dir);
    for (const auto& it : s.items) s.clips.push_back({&it.motion, it.emotion, it.content, it.path.filename().string()});
    return s;
}

/// Every label of the set must have circumplex coordinates; checked before any feature is computed.
inline void check_labels(const loaded_set& s, const handemo::rcm::circumplex_table& t, const std::string& table_file)
{
    for (const auto& c : s.clips) (void)t.at(c.emotion, table_file);
}

inline void finish_options(fit_cli& o)
{
    if (!o.roles.empty()) {
        const auto j = nlohmann::json::parse(handemo::read_file(o.roles), nullptr, false);
        if (j.is_discarded() || !j.is_object() || !j.contains("roles"))
            throw handemo::format_error("rcm: " + o.roles + ": not a JSON object with a field 'roles'");
        o.opt.role_overrides = j["roles"];
    }
    o.opt.performer_kind = "content";
    o.opt.show_progress = true;
}

/// The neutral label of a set: `given`, else the label called neutral, else Bandai's normal, else none.
inline std::string neutral_label(const loaded_set& set, const std::string& given)
{
    if (!given.empty()) return given;
    for (const char* n : {"neutral", "normal"})
        if (std::any_of(set.clips.begin(), set.clips.end(), [&](const auto& c) { return c.emotion == n; })) return n;
    return {};
}

/// The candidates of the analysis's choice from --input, --shrink and --neutral (rcm eval, rcm fit): `auto` without a
/// neutral label tries the inputs that need none (said on stdout), unless --input auto was given explicitly.
inline handemo::rcm::loo_options analysis_candidates(const loaded_set& set, const std::string& neutral, const std::string& input,
                                                     bool input_given, const std::string& shrink, const std::string& cmd)
{
    handemo::rcm::loo_options lo;
    lo.neutral = neutral_label(set, neutral);
    lo.inputs = handemo::rcm::parse_analysis_inputs(input, cmd + ": --input");
    lo.shrink = handemo::rcm::parse_shrink(shrink, cmd + ": --shrink");
    if ((input == "relative" || input == "judge" || (input == "auto" && input_given)) && lo.neutral.empty())
        throw handemo::value_error(cmd + ": --input " + input + ": no clip is labelled neutral or normal; name the neutral label with --neutral");
    if (lo.neutral.empty()) {
        lo.inputs = {handemo::rcm::analysis_input::paper, handemo::rcm::analysis_input::clusters};
        std::cout << cmd << ": no clip is labelled neutral or normal: --input auto tries paper and clusters only\n";
    }
    return lo;
}

/// A motion file: .csv as the hand, anything else as BVH; validated, the file named in any error.
inline handemo::clip read_motion(const std::filesystem::path& in)
{
    const auto ext = in.extension().string();
    handemo::clip c = (ext == ".csv" || ext == ".CSV") ? handemo::read_csv(in, handemo::hand_skeleton()) : handemo::read_bvh(in);
    c.validate(in.string());
    return c;
}

/// The analysis `rcm stylise` and `rcm path` print of their input and outputs: the model file's chosen one, read
/// against the --neutral takes when its input needs them; the paper's with --paper, or when the chosen input needs
/// neutral takes and none were given (the line `line` says which, and why).
struct printed_analysis {
    handemo::rcm::chosen_analysis analysis;
    handemo::rcm::neutral_reference reference;
    std::string line;
    handemo::rcm::analysis of(const handemo::clip& c, const std::string& who) const { return analysis.analyse(c, reference, who); }
};

inline printed_analysis printed_analysis_of(const std::string& model_file, const handemo::rcm::rcm_model& m,
                                            const std::vector<std::string>& neutral_files, bool paper, const std::string& cmd)
{
    printed_analysis p{paper ? handemo::rcm::chosen_analysis::paper(m) : handemo::rcm::load_analysis(model_file), {}, {}};
    char b[200];
    std::snprintf(b, sizeof b, "%s: analysis: input %s, shrink %.1f", cmd.c_str(), handemo::rcm::to_string(p.analysis.input()), p.analysis.shrink());
    p.line = b;
    if (paper) p.line += " (--paper)";
    if (p.analysis.needs_neutral() && neutral_files.empty()) {
        p.line = cmd + ": analysis: input paper, shrink 1.0 (the model's analysis, input " + handemo::rcm::to_string(p.analysis.input()) +
                 ", reads a clip against neutral takes of its content: give them with --neutral FILE)";
        p.analysis = handemo::rcm::chosen_analysis::paper(m);
    }
    std::vector<handemo::clip> neutral;
    for (const auto& n : neutral_files) neutral.push_back(read_motion(n));
    std::vector<const handemo::clip*> np;
    for (const auto& n : neutral) np.push_back(&n);
    try {
        p.reference = p.analysis.reference(np, "the --neutral clips");
    } catch (const handemo::error& e) {
        throw handemo::value_error(cmd + ": " + e.what());
    }
    if (!neutral_files.empty() && !p.analysis.needs_neutral()) p.line += " (it reads no neutral takes: --neutral is not used)";
    return p;
}

}  // namespace handemo::cli::rcm_cmd
