// `handemo rcm path --model MODEL IN.bvh --path sad,neutral,happy [--steps N] --out strip.png`: one motion
// stylised to a sequence of points along a path on the circumplex (rcm::parse_path(), sample_path(),
// stylise_to_point() of rcm/control.hpp), drawn as a filmstrip (one column per point, the input first, as
// `handemo render` draws them). Waypoints are labels (the model's, then the --labels table's) or explicit
// points `V:A` / `(V,A)`. Prints, per column, the target point and `rcm analyse` of the output (the model's chosen
// analysis; --neutral takes for one that reads them, --paper for the paper's).
#pragma once

#include "common.hpp"

#include <handemo/image.hpp>
#include <handemo/motion/bvh.hpp>
#include <handemo/render.hpp>

#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>

namespace handemo::cli::rcm_cmd {

struct path_run {
    std::string model, input, path, out, labels = HANDEMO_RCM_CIRCUMPLEX, bvh_dir;
    std::size_t steps = 2, rows = 5, cell = 160;
    bool no_input = false, paper = false;
    std::vector<std::string> neutral;
    handemo::rcm::point_options po;
};

inline void run_path(const path_run& o)
{
    namespace rc = handemo::rcm;
    const std::filesystem::path out(o.out);
    const std::string ext = out.extension().string();
    if (ext != ".png" && ext != ".PNG" && ext != ".bmp" && ext != ".BMP")
        throw handemo::value_error("rcm path: --out " + o.out + ": extension '" + ext + "' is not .png or .bmp");
    const auto m = rc::load_model(o.model);
    // the model's labels first, then the table's others
    std::vector<rc::label_point> labels = m.labels;
    for (const auto& l : rc::load_circumplex(o.labels).labels)
        if (std::none_of(labels.begin(), labels.end(), [&](const rc::label_point& x) { return x.name == l.name; })) labels.push_back(l);
    const auto points = rc::sample_path(rc::parse_path(o.path, labels), o.steps);
    const std::filesystem::path in(o.input);
    const handemo::clip c = read_motion(in);
    const auto pa = printed_analysis_of(o.model, m, o.neutral, o.paper, "rcm path");
    std::cout << pa.line << "\n";
    std::vector<handemo::clip> clips;
    handemo::filmstrip_options fo;
    fo.rows = o.rows;
    fo.cell_width = fo.cell_height = o.cell;
    char line[256];
    rc::analysis a0;
    try {
        a0 = pa.of(c, in.string());
    } catch (const handemo::error& e) {
        throw handemo::value_error("rcm path: " + in.string() + ": " + e.what());
    }
    std::snprintf(line, sizeof line, "rcm path: input valence %.3f arousal %.3f quadrant %d, %zu frames\n", a0.valence, a0.arousal,
                  a0.quadrant, c.frames);
    std::cout << line;
    if (!o.no_input) {
        clips.push_back(c);
        fo.titles.push_back("input");
    }
    if (!o.bvh_dir.empty()) std::filesystem::create_directories(o.bvh_dir);
    for (std::size_t k = 0; k < points.size(); ++k) {
        const auto& p = points[k];
        rc::point_result r;
        try {
            r = rc::stylise_to_point(m, c, p.valence, p.arousal, o.po);
        } catch (const handemo::value_error& e) {
            throw handemo::value_error(std::string(e.what()) + " (" + in.string() + ")");
        }
        rc::analysis a;
        try {
            a = pa.of(r.synth.motion, "column " + std::to_string(k));
        } catch (const handemo::error& e) {
            throw handemo::value_error("rcm path: " + std::string(e.what()));
        }
        std::snprintf(line, sizeof line,
                      "step %zu: target %s valence %.3f arousal %.3f quadrant %d -> valence %.3f arousal %.3f quadrant %d, %zu frames\n", k,
                      rc::path_title(p).c_str(), p.valence, p.arousal, rc::quadrant(p.valence, p.arousal), a.valence, a.arousal, a.quadrant,
                      r.synth.motion.frames);
        std::cout << line;
        if (!o.bvh_dir.empty()) {
            std::snprintf(line, sizeof line, "step%02zu.bvh", k);
            handemo::write_bvh(std::filesystem::path(o.bvh_dir) / line, r.synth.motion);
        }
        clips.push_back(std::move(r.synth.motion));
        fo.titles.push_back(rc::path_title(p));
    }
    const handemo::rgb_image im = handemo::render_filmstrip(clips, fo);
    if (ext == ".png" || ext == ".PNG") handemo::write_png(out, im);
    else handemo::write_bmp(out, im);
    std::cout << "rcm path: wrote " << o.out << " (" << im.width << "x" << im.height << ", " << clips.size() << " clips x " << fo.rows
              << " frames)\n";
}

inline void add_path(CLI::App& rcm)
{
    auto* sub = rcm.add_subcommand("path", "Stylise one motion along a path on the circumplex and draw it as a filmstrip");
    auto o = std::make_shared<path_run>();
    sub->add_option("--model", o->model, "Model file written by `handemo rcm fit`")->required();
    sub->add_option("input", o->input, "Motion to stylise (.bvh; .csv for the hand)")->required();
    sub->add_option("--path", o->path,
                    "Waypoints, comma separated: labels (sad,neutral,happy) or points V:A or (V,A); write --path=-0.5:0.2,... when "
                    "the first starts with '-'")
        ->required();
    sub->add_option("--steps", o->steps, "Columns per path segment (each waypoint is a column; N - 1 points between two)")->capture_default_str();
    sub->add_option("--out", o->out, "Filmstrip picture (.png or .bmp): the input, then one column per path point")->required();
    sub->add_option("--labels", o->labels, "Circumplex coordinates of labels the model was not trained on")->capture_default_str();
    sub->add_option("--rows", o->rows, "Frames per clip (rows of the filmstrip)")->capture_default_str();
    sub->add_option("--cell", o->cell, "Cell side in pixels")->capture_default_str();
    sub->add_flag("--no-input", o->no_input, "Leave the input's column out");
    sub->add_option("--bvh-dir", o->bvh_dir, "Also write each column's motion as DIR/stepNN.bvh");
    sub->add_option("--neutral", o->neutral,
                    "Neutral takes of the input's content (.bvh, .csv): the model's analysis of each column reads them when its "
                    "input is relative or judge (without them, the paper's analysis is printed)");
    sub->add_flag("--paper", o->paper, "Print the paper's analysis of each column, whatever the model chose");
    sub->add_option("--iters", o->po.iterations, "BFGS iterations of each stylisation")->capture_default_str();
    sub->add_option("--bound", o->po.bound, "Largest |coefficient| (as rcm stylise)")->capture_default_str();
    sub->callback([o] { run_path(*o); });
}

}  // namespace handemo::cli::rcm_cmd
