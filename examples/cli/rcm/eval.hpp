// `handemo rcm eval --data DIR [--by content|take] [--csv OUT.csv] [--svg OUT.svg]`: leave-one-content-out
// (or leave-one-take-out) accuracy of the analysis: mean circumplex distance between the predicted point and
// the label's coordinates, share of predictions in the label's quadrant, next to a constant predictor (the
// training labels' mean point). `--relative on|auto` reads features against the same content's neutral clips;
// `--input` and `--shrink` choose what is mapped and how far the point is pulled toward the constant predictor,
// fixed or per fold by an inner leave-one-content-out (docs/circumplex.md); both default to that choice (`auto`),
// and `--input paper --shrink none` is the paper's analysis.
#pragma once

#include "common.hpp"

#include <algorithm>
#include <cstdio>
#include <iostream>
#include <map>
#include <memory>

namespace handemo::cli::rcm_cmd {

struct eval_run {
    fit_cli f;
    std::string by = "content", csv, svg, relative, neutral, input = "auto", shrink = "auto";
    bool input_given = false, shrink_given = false;
};

inline void run_eval(eval_run& o)
{
    finish_options(o.f);
    o.f.opt.cluster = false;
    const auto table = handemo::rcm::load_circumplex(o.f.labels);
    const auto set = load_set(o.f.data);
    check_labels(set, table, o.f.labels);
    std::vector<std::string> group;
    for (const auto& it : set.items) {
        if (o.by == "content") group.push_back(it.content);
        else if (o.by == "take") group.push_back(it.take);
        else throw handemo::value_error("rcm eval: --by " + o.by + " is not 'content' or 'take'");
    }
    handemo::rcm::loo_options lo;
    if (!o.relative.empty()) {  // the earlier option: its inputs, and no shrinkage unless --shrink says so
        if (o.input_given) throw handemo::value_error("rcm eval: --relative " + o.relative + " and --input " + o.input + ": give one of them");
        lo.neutral = neutral_label(set, o.neutral);
        lo.relative = handemo::rcm::parse_relative_features(o.relative);
        lo.shrink = handemo::rcm::parse_shrink(o.shrink_given ? o.shrink : "none");
        if (lo.relative != handemo::rcm::relative_features::off && lo.neutral.empty())
            throw handemo::value_error("rcm eval: --relative " + o.relative + ": no clip is labelled neutral or normal; name the neutral label with --neutral");
    } else {
        lo = analysis_candidates(set, o.neutral, o.input, o.input_given, o.shrink, "rcm eval");
    }
    const auto r = handemo::rcm::evaluate_loo(set.clips, group, table, o.f.labels, o.f.opt, lo);
    char buf[512];
    std::snprintf(buf, sizeof buf,
                  "rcm eval: leave-one-%s-out on %s: %zu folds, %zu clips, %zu folds failed\n"
                  "rcm eval: mean distance %.3f, right quadrant %.1f%% (constant mean-label predictor: %.3f, %.1f%%)\n"
                  "rcm eval: mean features kept %.1f, PCA dimensions %.1f\n",
                  o.by.c_str(), o.f.data.c_str(), r.folds.size(), r.samples.size(), r.failed_folds.size(), r.mean_distance,
                  100 * r.quadrant_accuracy, r.baseline_distance, 100 * r.baseline_quadrant_accuracy, r.mean_selected, r.mean_pca_dims);
    std::cout << buf;
    if (!lo.neutral.empty()) {
        std::snprintf(buf, sizeof buf, "rcm eval: non-%s clips: mean distance %.3f (constant mean-label predictor: %.3f); relative features in %zu of %zu folds\n",
                      lo.neutral.c_str(), r.emotional_distance, r.emotional_baseline_distance, r.relative_folds,
                      r.folds.size() - r.failed_folds.size());
        std::cout << buf;
    }
    if (lo.inputs.size() > 1 || lo.relative == handemo::rcm::relative_features::automatic || lo.shrink.size() > 1) {
        std::string line = "rcm eval: inputs per fold:";
        for (const auto& [name, folds] : r.input_folds) line += " " + name + " " + std::to_string(folds);
        std::snprintf(buf, sizeof buf, "; mean shrinkage weight %.2f\n", r.mean_shrink);
        std::cout << line << buf;
    }
    for (const auto& f : r.failed_folds) std::cout << "rcm eval: fold " << f << "\n";
    std::map<std::string, std::pair<double, double>> per;  // label -> (distance sum, quadrant hits)
    std::map<std::string, int> cnt;
    for (const auto& s : r.samples) per[s.emotion].first += s.distance, per[s.emotion].second += s.quadrant_ok, ++cnt[s.emotion];
    for (const auto& [e, v] : per) {
        std::snprintf(buf, sizeof buf, "rcm eval:   %-14s distance %.3f  right quadrant %.0f%%\n", e.c_str(), v.first / cnt[e],
                      100 * v.second / cnt[e]);
        std::cout << buf;
    }
    if (!o.csv.empty()) {
        std::string t = "clip,held_out,emotion,valence,arousal,true_valence,true_arousal,distance,quadrant_ok,input,shrink\n";
        for (const auto& s : r.samples) {
            std::snprintf(buf, sizeof buf, "%s,%s,%s,%.4f,%.4f,%.4f,%.4f,%.4f,%d,%s,%.2f\n", s.name.c_str(), s.held_out.c_str(), s.emotion.c_str(),
                          s.valence, s.arousal, s.true_valence, s.true_arousal, s.distance, s.quadrant_ok ? 1 : 0, s.input.c_str(), s.shrink);
            t += buf;
        }
        handemo::write_file_atomic(o.csv, t);
        std::cout << "rcm eval: wrote " << o.csv << "\n";
    }
    if (!o.svg.empty()) {
        std::vector<handemo::rcm::label_point> labels, preds;
        std::map<std::string, bool> seen;
        for (const auto& s : r.samples) {
            if (!seen[s.emotion]) labels.push_back({s.emotion, s.true_valence, s.true_arousal}), seen[s.emotion] = true;
            preds.push_back({s.emotion, s.valence, s.arousal});
        }
        handemo::rcm::circumplex_svg_options so;
        so.title = "leave-one-" + o.by + "-out predictions (light) and label points";
        handemo::write_file_atomic(o.svg, handemo::rcm::circumplex_svg(labels, std::nullopt, std::nullopt, preds, so));
        std::cout << "rcm eval: wrote " << o.svg << "\n";
    }
}

inline void add_eval(CLI::App& rcm)
{
    auto* sub = rcm.add_subcommand("eval", "Leave-one-content-out accuracy of the circumplex analysis");
    auto o = std::make_shared<eval_run>();
    add_fit_options(sub, o->f);
    sub->add_option("--by", o->by, "Hold out one 'content' or one 'take' per fold")->capture_default_str();
    sub->add_option("--csv", o->csv, "Per-clip predictions (CSV; each row also names its fold's input and shrinkage weight)");
    sub->add_option("--svg", o->svg, "Circumplex with every held-out prediction");
    sub->add_option("--relative", o->relative,
                    "Instead of --input: features as the change from the same content's neutral clips: off (the paper), on, or "
                    "auto (chosen per fold by an inner leave-one-out on its training clips); no shrinkage unless --shrink is given")
        ->check(CLI::IsMember({"off", "on", "auto"}));
    auto* input = sub->add_option("--input", o->input,
                    "What the RBF maps: paper (Table 1 features, global selection), relative (the same against the content's "
                    "neutral clips), clusters (per-pose-cluster selections), judge (the full-rate classifier's features against "
                    "the content's neutral clips), or auto (chosen per fold by an inner leave-one-out; docs/circumplex.md)")
        ->check(CLI::IsMember({"paper", "relative", "clusters", "judge", "auto"}))
        ->capture_default_str();
    auto* shrink = sub->add_option("--shrink", o->shrink,
                    "Pull each point toward the constant predictor: none, a weight in [0, 1] (0: the constant), or auto "
                    "(0, 0.1 .. 1 chosen per fold by the inner leave-one-out, jointly with --input)")
        ->capture_default_str();
    sub->add_option("--neutral", o->neutral, "The neutral label (default: neutral, else normal, when the data has it)");
    sub->callback([o, input, shrink] {
        o->input_given = input->count() > 0;
        o->shrink_given = shrink->count() > 0;
        run_eval(*o);
    });
}

}  // namespace handemo::cli::rcm_cmd
