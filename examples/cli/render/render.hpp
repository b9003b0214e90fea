// `handemo render IN.bvh [MORE.bvh ...] --out strip.png [--rows N] [--titles a,b,...]`: a filmstrip of one
// or more BVH clips as in the hand paper's Figures 4-12 (one sampled frame per row, one clip per column,
// titles on top), drawn by handemo's own software renderer. PNG or BMP by the output's extension.
// `--animate out.gif [--gif-fps F] [--normalised-time]`: the clips side by side playing in sync as an
// animated GIF (render/animation.hpp, gif/writer.hpp; needs giflib at build time).
#pragma once

#include "../registry.hpp"

#include <handemo/image.hpp>
#include <handemo/motion/bvh.hpp>
#include <handemo/render.hpp>
#ifdef HANDEMO_HAVE_GIF
#include <handemo/gif.hpp>
#endif

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
        std::string out, animate, kind = "auto";
        std::size_t rows = 5, cell = 200;
        std::vector<std::string> titles;
        bool no_labels = false, normalised = false;
        double gif_fps = 0;
    };
    auto a = std::make_shared<args>();
    auto* sub = app.add_subcommand("render", "Draw BVH clips as a filmstrip PNG (one frame per row, one clip per column) "
                                             "or an animated GIF of them playing side by side (--animate)");
    sub->add_option("inputs", a->inputs, "BVH files, one column each")->required()->check(CLI::ExistingFile);
    sub->add_option("--out,-o", a->out, "output filmstrip picture (.png or .bmp)");
    sub->add_option("--animate", a->animate,
                                     "write an animated GIF: the clips side by side in one row, playing in sync, looping");
    sub->add_option("--gif-fps", a->gif_fps,
                    "GIF frames per second, (0, 50]; default the first clip's rate capped at 30 (delays are whole "
                    "centiseconds, rounded so the loop keeps its true length)");
    sub->add_flag("--normalised-time", a->normalised, "GIF: stretch every clip to the longest one's duration");
    sub->add_option("--rows", a->rows, "frames per clip, sampled uniformly over its duration (1..1000)")->capture_default_str();
    sub->add_option("--titles", a->titles, "column titles, comma separated (default: file names)")->delimiter(',');
    sub->add_option("--cell", a->cell, "cell side in pixels (32..4096)")->capture_default_str();
    sub->add_option("--kind", a->kind, "figure kind: auto, hand or body")->check(CLI::IsMember({"auto", "hand", "body"}))->capture_default_str();
    sub->add_flag("--no-frame-labels", a->no_labels, "do not print frame numbers in the cells");
    sub->callback([a] {
        if (a->out.empty() && a->animate.empty())
            throw handemo::value_error("render: nothing to write: give --out strip.png and/or --animate out.gif");
        std::vector<handemo::clip> clips;
        for (const auto& f : a->inputs) {
            clips.push_back(handemo::read_bvh(f));
            if (clips.back().frames == 0) throw handemo::value_error("render: " + f + " has 0 frames (expected at least 1)");
        }
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
        if (!a->animate.empty()) {
#ifdef HANDEMO_HAVE_GIF
            handemo::animation_options ao;
            ao.fps = a->gif_fps;
            ao.normalised_time = a->normalised;
            ao.strip = o;
            if (a->gif_fps < 0 || a->gif_fps > 50)
                throw handemo::value_error("render: --gif-fps " + std::to_string(a->gif_fps) + " is not in (0, 50] (" + a->animate + ")");
            const handemo::filmstrip_animation anim(clips, ao);
            const std::size_t bytes = handemo::write_gif(a->animate, anim);
            const handemo::rgb_image f0 = anim.frame(0);
            std::cout << "wrote " << a->animate << " (" << f0.width << "x" << f0.height << ", " << anim.frame_count() << " frames at "
                      << anim.fps() << " fps, " << bytes / 1024 << " KB)\n";
#else
            throw handemo::value_error("render: --animate " + a->animate + ": this handemo was built without giflib (libgif-dev)");
#endif
        }
        if (!a->out.empty()) {
            const handemo::rgb_image im = handemo::render_filmstrip(clips, o);
            write_picture(a->out, im, "render");
            std::cout << "wrote " << a->out << " (" << im.width << "x" << im.height << ", " << clips.size() << " clips x " << o.rows
                      << " frames)\n";
        }
    });
}};
