// `handemo eval ... [--no-rcm] [--rcm-iters N] [--rcm-labels FILE] [--rcm-min-features K] [--rcm-no-synthesis]
// [--rcm-input auto|paper|relative|clusters|judge] [--rcm-shrink auto|none|S]`:
// the circumplex method of Aristidou et al. 2017 (on by default) in the StarGAN evaluation's folds and tables
// (eval/rcm.hpp). Registered from this translation unit (the only one that sees LAPACK) through
// eval_extensions() (registry.hpp); `handemo eval` itself lives in stargan/eval.hpp.
#pragma once

#include "../registry.hpp"
#include "common.hpp"

#include <handemo/eval/rcm.hpp>

#include <memory>
#include <string>

namespace handemo::cli::rcm_cmd {

struct eval_ext_cli {
    bool off = false, explicit_on = false, no_synthesis = false;
    std::string labels = HANDEMO_RCM_CIRCUMPLEX;
    std::string input = "auto", shrink = "auto";
    CLI::Option* labels_opt = nullptr;
    handemo::eval::rcm_eval_options opt;
};

inline eval_ext_cli& eval_ext_state()
{
    static eval_ext_cli s;
    return s;
}

/// On by default: the circumplex rows cost little next to StarGAN's training (a linear-algebra fit and one
/// rules-and-IK stylisation per row).
inline void add_eval_ext_options(CLI::App* sub)
{
    auto& s = eval_ext_state();
    auto* on = sub->add_flag("--rcm", s.explicit_on,
                             "Circumplex method of Aristidou et al. 2017 in each fold (on by default): a model fitted on the fold's "
                             "training clips, its regression numbers, an 'rcm' row (each held-out neutral clip stylised to each "
                             "target label's (valence, arousal)) and the circumplex quadrant every output reaches");
    auto* off = sub->add_flag("--no-rcm", s.off, "Leave the circumplex method out")->excludes(on);
    s.labels_opt = sub->add_option("--rcm-labels", s.labels, "Circumplex coordinates of the labels (JSON with its citation)")
                       ->capture_default_str()
                       ->excludes(off);
    sub->add_option("--rcm-iters", s.opt.stylise.iterations, "BFGS iterations of each rcm stylisation")->capture_default_str()->excludes(off);
    sub->add_option("--rcm-min-features", s.opt.fit.selection.min_features, "Features the circumplex model keeps (rcm fit --min-features)")
        ->capture_default_str()
        ->excludes(off);
    sub->add_flag("--rcm-no-synthesis", s.no_synthesis, "Circumplex regression and quadrant numbers only, no 'rcm' rows")->excludes(off);
    sub->add_option("--rcm-input", s.input,
                    "The circumplex analysis's input, chosen per fold on its training clips as rcm eval --input does (auto: among "
                    "paper, relative, clusters and judge; paper with --rcm-shrink none is the paper's analysis)")
        ->capture_default_str()
        ->excludes(off);
    sub->add_option("--rcm-shrink", s.shrink, "Its pull toward the constant predictor (auto: chosen per fold, as rcm eval --shrink; none; or S in [0, 1])")
        ->capture_default_str()
        ->excludes(off);
}

inline std::shared_ptr<handemo::eval::method_extension> make_eval_ext()
{
    auto& s = eval_ext_state();
    if (s.off) return nullptr;
    auto o = s.opt;
    // parsed first: a mistyped option is an error before anything is loaded
    o.inputs = handemo::rcm::parse_analysis_inputs(s.input, "eval: --rcm-input");
    o.shrink = handemo::rcm::parse_shrink(s.shrink, "eval: --rcm-shrink");
    try {
        o.table = handemo::rcm::load_circumplex(s.labels);
    } catch (const handemo::error& e) {
        // asked for: an error; by default (e.g. an installed handemo whose source tree with the table is gone): said, then left out
        if (s.explicit_on || (s.labels_opt && s.labels_opt->count() > 0)) throw;
        std::cerr << "eval: the circumplex method is left out: " << e.what() << " (give --rcm-labels FILE, or --no-rcm)\n";
        return nullptr;
    }
    o.table_name = s.labels;
    o.synthesis = !s.no_synthesis;
    o.fit.performer_kind = "content";
    return std::make_shared<handemo::eval::rcm_extension>(std::move(o));
}

}  // namespace handemo::cli::rcm_cmd
