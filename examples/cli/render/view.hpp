// `handemo view A.bvh [B.bvh ...] --out view.html [--titles a,b,...] [--normalised-time] [--columns N]`: one
// self-contained HTML page (works offline, nothing fetched) that plays the clips in sync in a grid, row by row
// (at most 5 per row unless --columns says otherwise), with play/pause, scrub, speed, orbit, zoom and joint
// names on hover. handemo does the forward kinematics and embeds the joint positions; the page only draws them
// (render/viewer.hpp).
#pragma once

#include "../registry.hpp"

#include <handemo/core/io.hpp>
#include <handemo/motion/bvh.hpp>
#include <handemo/render/viewer.hpp>

#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

static handemo::cli::add_command reg_view{61, [](CLI::App& app) {
    struct args {
        std::vector<std::string> inputs;
        std::string out, kind = "auto", title = "handemo view";
        std::vector<std::string> titles;
        bool normalised = false;
        std::size_t width = 960, height = 540, columns = 0;
    };
    auto a = std::make_shared<args>();
    auto* sub = app.add_subcommand("view", "Write one offline HTML page that plays BVH clips in a grid (orbit, zoom, scrub)");
    sub->add_option("inputs", a->inputs, "BVH files, shown left to right, row by row")->required()->check(CLI::ExistingFile);
    sub->add_option("--out,-o", a->out, "output page (.html)")->required();
    sub->add_option("--titles", a->titles, "clip titles, comma separated (default: file names)")->delimiter(',');
    sub->add_flag("--normalised-time", a->normalised,
                  "start in normalised time: every clip stretched to the longest one's duration (a transfer and its input stay aligned)");
    sub->add_option("--kind", a->kind, "figure kind: auto, hand or body")->check(CLI::IsMember({"auto", "hand", "body"}))->capture_default_str();
    sub->add_option("--columns", a->columns, "clips per row (0: automatic, at most 5 per row; more than the clips: one row)")
        ->capture_default_str();
    sub->add_option("--width", a->width, "canvas width in pixels, shared by a row's clips (64..16384)")->capture_default_str();
    sub->add_option("--height", a->height, "height in pixels of each row's cells, below its titles (64..16384)")->capture_default_str();
    sub->add_option("--title", a->title, "page title")->capture_default_str();
    sub->callback([a] {
        const std::string ext = std::filesystem::path(a->out).extension().string();
        if (ext != ".html" && ext != ".htm")
            throw handemo::value_error("view: --out " + a->out + ": extension '" + ext + "' is not .html or .htm");
        std::vector<handemo::clip> clips;
        for (const auto& f : a->inputs) clips.push_back(handemo::read_bvh(f));
        handemo::viewer_options o;
        o.normalised_time = a->normalised;
        o.width = a->width;
        o.height = a->height;
        o.columns = a->columns;
        o.page_title = a->title;
        o.figure.kind = a->kind == "hand" ? handemo::figure_kind::hand : a->kind == "body" ? handemo::figure_kind::body
                                                                                             : handemo::figure_kind::automatic;
        if (!a->titles.empty()) {
            if (a->titles.size() != clips.size())
                throw handemo::value_error("view: --titles has " + std::to_string(a->titles.size()) + " titles for " +
                                           std::to_string(clips.size()) + " input clips (expected one per clip)");
            o.titles = a->titles;
        } else {
            for (const auto& f : a->inputs) o.titles.push_back(std::filesystem::path(f).stem().string());
        }
        const std::string html = handemo::render_viewer_html(clips, o);
        handemo::write_file_atomic(a->out, html);
        std::cout << "wrote " << a->out << " (" << html.size() / 1024 << " KiB, " << clips.size() << " clips; open it in a browser, works offline)\n";
    });
}};
