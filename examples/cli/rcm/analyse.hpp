// `handemo rcm analyse --model MODEL.json IN.bvh [--neutral N.bvh ...] [--paper] [--svg OUT.svg] [--target V A]`:
// prints `valence V arousal A quadrant Q` with the model's chosen analysis (its input and pull toward the constant;
// the relative and judge inputs read the clip against neutral takes of the same content, --neutral) or the paper's
// (--paper, or a model file without a chosen analysis), and optionally draws the circumplex with the training
// labels, the analysed input and a target point.
#pragma once

#include "common.hpp"

#include <cstdio>
#include <iostream>
#include <memory>
#include <optional>

namespace handemo::cli::rcm_cmd {

struct analyse_run {
    std::string model, input, svg;
    std::vector<std::string> neutral;
    std::vector<double> target;
    bool paper = false;
};

inline void run_analyse(const analyse_run& o)
{
    if (!o.target.empty() && (o.target.size() != 2 || std::abs(o.target[0]) > 1 || std::abs(o.target[1]) > 1))
        throw handemo::value_error("rcm analyse: --target needs two values (valence arousal) in [-1, 1]");
    const auto m = handemo::rcm::load_model(o.model);
    const auto chosen = o.paper ? handemo::rcm::chosen_analysis::paper(m) : handemo::rcm::load_analysis(o.model);
    if (chosen.needs_neutral() && o.neutral.empty())
        throw handemo::value_error(std::string("rcm analyse: the analysis of ") + o.model + " (input " + handemo::rcm::to_string(chosen.input()) +
                                   ") reads a clip against neutral takes of its content: give them with --neutral FILE (or --paper for "
                                   "the paper's analysis)");
    const std::filesystem::path in(o.input);
    const handemo::clip c = read_motion(in);
    std::vector<handemo::clip> neutral;
    for (const auto& n : o.neutral) neutral.push_back(read_motion(n));
    std::vector<const handemo::clip*> np;
    for (const auto& n : neutral) np.push_back(&n);
    handemo::rcm::analysis a;
    try {
        a = chosen.analyse(c, chosen.reference(np, "the --neutral clips"), in.string());
    } catch (const handemo::error& e) {
        throw handemo::value_error(std::string("rcm analyse: ") + e.what());
    }
    char line[160];
    std::snprintf(line, sizeof line, "valence %.3f arousal %.3f quadrant %d", a.valence, a.arousal, a.quadrant);
    std::cout << line << "\n";
    std::snprintf(line, sizeof line, "rcm analyse: input %s, shrink %.1f%s", handemo::rcm::to_string(chosen.input()), chosen.shrink(),
                  o.paper ? " (--paper)" : "");
    std::cerr << line << "\n";
    if (!o.svg.empty()) {
        std::optional<handemo::rcm::label_point> target;
        if (!o.target.empty()) target = handemo::rcm::label_point{"target", o.target[0], o.target[1]};
        handemo::rcm::circumplex_svg_options so;
        so.title = in.filename().string() + " on the circumplex";
        const auto svg = handemo::rcm::circumplex_svg(m.labels, handemo::rcm::label_point{in.stem().string(), a.valence, a.arousal}, target, {}, so);
        handemo::write_file_atomic(o.svg, svg);
        std::cerr << "rcm analyse: wrote " << o.svg << "\n";
    }
}

inline void add_analyse(CLI::App& rcm)
{
    auto* sub = rcm.add_subcommand("analyse", "Print the circumplex point (valence, arousal, quadrant) of a motion");
    auto o = std::make_shared<analyse_run>();
    sub->add_option("--model", o->model, "Model file written by `handemo rcm fit`")->required();
    sub->add_option("input", o->input, "Motion to analyse (.bvh; .csv for the hand)")->required();
    sub->add_option("--svg", o->svg, "Also draw the circumplex with the labels, the input and the target");
    sub->add_option("--target", o->target, "A target point VALENCE AROUSAL to draw")->expected(2);
    sub->add_option("--neutral", o->neutral,
                    "Neutral takes of the input's content (.bvh, .csv), which the relative and judge analyses read the input against");
    sub->add_flag("--paper", o->paper, "The paper's analysis (Table 1 features, no pull toward the constant), whatever the model chose");
    sub->callback([o] { run_analyse(*o); });
}

}  // namespace handemo::cli::rcm_cmd
