// `handemo render IN.bvh [MORE.bvh ...] --out strip.png [--rows N] [--titles a,b,...]`: a filmstrip of one
// or more BVH clips as in the hand paper's Figures 4-12 (one sampled frame per row, one clip per column,
// titles on top), drawn by handemo's own software renderer. PNG or BMP by the output's extension.
#pragma once

#include "../registry.hpp"

#include <handemo/image.hpp>
#include <handemo/motion/bvh.hpp>
#include <handemo/render.hpp>

#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

namespace handemo::cli::render_cmd {

void write_picture(const std::filesystem::path& out, const handemo::rgb_image& im, const std::string& cmd)
{
    const std::string ext = out.extension().string();
    if (ext == ".png" || ext == ".PNG")
        handemo::write_png(out, im);
    else if (ext == ".bmp" || ext == ".BMP")
        handemo::write_bmp(out, im);
    else
        throw handemo::value_error(cmd + ": --out " + out.string() + ": extension '" + ext + "' is not .png or .bmp");
}

}  // namespace handemo::cli::render_cmd

static handemo::cli::add_command reg_render{60, [](CLI::App& app) {
    using namespace handemo::cli::render_cmd;
    struct args {
        std::vector<std::string> inputs;
        std::string out, kind = "auto";
        std::size_t rows = 5, cell = 200;
        std::vector<std::string> titles;
        bool no_labels = false;
    };
    auto a = std::make_shared<args>();
    auto* sub = app.add_subcommand("render", "Draw BVH clips as a filmstrip PNG (one frame per row, one clip per column)");
    sub->add_option("inputs", a->inputs, "BVH files, one column each")->required()->check(CLI::ExistingFile);
    sub->add_option("--out,-o", a->out, "output picture (.png or .bmp)")->required();
    sub->add_option("--rows", a->rows, "frames per clip, sampled uniformly over its duration (1..1000)")->capture_default_str();
    sub->add_option("--titles", a->titles, "column titles, comma separated (default: file names)")->delimiter(',');
    sub->add_option("--cell", a->cell, "cell side in pixels (32..4096)")->capture_default_str();
    sub->add_option("--kind", a->kind, "figure kind: auto, hand or body")->check(CLI::IsMember({"auto", "hand", "body"}))->capture_default_str();
    sub->add_flag("--no-frame-labels", a->no_labels, "do not print frame numbers in the cells");
    sub->callback([a] {
        std::vector<handemo::clip> clips;
        for (const auto& f : a->inputs) clips.push_back(handemo::read_bvh(f));
        handemo::filmstrip_options o;
        o.rows = a->rows;
        o.cell_width = o.cell_height = a->cell;
        o.frame_labels = !a->no_labels;
        o.figure.kind = a->kind == "hand" ? handemo::figure_kind::hand : a->kind == "body" ? handemo::figure_kind::body
                                                                                             : handemo::figure_kind::automatic;
        if (!a->titles.empty()) {
            if (a->titles.size() != clips.size())
                throw handemo::value_error("render: --titles has " + std::to_string(a->titles.size()) + " titles for " +
                                           std::to_string(clips.size()) + " input clips (expected one per clip)");
            o.titles = a->titles;
        } else {
            for (const auto& f : a->inputs) o.titles.push_back(std::filesystem::path(f).stem().string());
        }
        const handemo::rgb_image im = handemo::render_filmstrip(clips, o);
        write_picture(a->out, im, "render");
        std::cout << "wrote " << a->out << " (" << im.width << "x" << im.height << ", " << clips.size() << " clips x " << o.rows
                  << " frames)\n";
    });
}};
