// `handemo rcm analyse --model MODEL.json IN.bvh [--svg OUT.svg] [--target V A]`: prints
// `valence V arousal A quadrant Q` and optionally draws the circumplex with the training labels, the
// analysed input and a target point.
#pragma once

#include "common.hpp"

#include <cstdio>
#include <iostream>
#include <memory>
#include <optional>

namespace handemo::cli::rcm_cmd {

struct analyse_run {
    std::string model, input, svg;
    std::vector<double> target;
};

inline void run_analyse(const analyse_run& o)
{
    const auto m = handemo::rcm::load_model(o.model);
    const std::filesystem::path in(o.input);
    const auto ext = in.extension().string();
    handemo::clip c = (ext == ".csv" || ext == ".CSV") ? handemo::read_csv(in, handemo::hand_skeleton()) : handemo::read_bvh(in);
    c.validate(in.string());
    handemo::rcm::analysis a;
    try {
        a = m.analyse(c);
    } catch (const handemo::error& e) {
        throw handemo::value_error("rcm analyse: " + in.string() + ": " + e.what());
    }
    char line[128];
    std::snprintf(line, sizeof line, "valence %.3f arousal %.3f quadrant %d", a.valence, a.arousal, a.quadrant);
    std::cout << line << "\n";
    if (!o.svg.empty()) {
        std::optional<handemo::rcm::label_point> target;
        if (!o.target.empty()) {
            if (o.target.size() != 2 || std::abs(o.target[0]) > 1 || std::abs(o.target[1]) > 1)
                throw handemo::value_error("rcm analyse: --target needs two values (valence arousal) in [-1, 1]");
            target = handemo::rcm::label_point{"target", o.target[0], o.target[1]};
        }
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
    sub->callback([o] { run_analyse(*o); });
}

}  // namespace handemo::cli::rcm_cmd
