// `handemo image IN.bmp --out view.png [--joints hand|none] [--scale N]`: the hand paper's Figure 3 view of
// a motion image (Eq. 3: K keyframes x J joints, RGB = x/y/z angles), enlarged with nearest-neighbour
// sampling, keyframe indices along the rows and joint names along the columns.
#pragma once

#include "../registry.hpp"

#include <handemo/image.hpp>
#include <handemo/motion/hand.hpp>
#include <handemo/render.hpp>

#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

static handemo::cli::add_command reg_image{61, [](CLI::App& app) {
    struct args {
        std::string in, out, joints = "auto";
        std::size_t scale = 24;
    };
    auto a = std::make_shared<args>();
    auto* sub = app.add_subcommand("image", "Draw a motion image (BMP/PNG, keyframes x joints) enlarged with labels");
    sub->add_option("input", a->in, "motion image (.bmp or .png)")->required()->check(CLI::ExistingFile);
    sub->add_option("--out,-o", a->out, "output picture (.png or .bmp)")->required();
    sub->add_option("--joints", a->joints, "column labels: hand (the 23 joint names), none (numbers), auto (hand when 23 wide)")
        ->check(CLI::IsMember({"auto", "hand", "none"}))
        ->capture_default_str();
    sub->add_option("--scale", a->scale, "pixels per cell (1..256)")->capture_default_str();
    sub->callback([a] {
        const handemo::rgb_image src = handemo::read_image(a->in);
        std::vector<std::string> names;
        if (a->joints == "hand" || (a->joints == "auto" && src.width == handemo::hand_joint_count)) {
            if (src.width != handemo::hand_joint_count)
                throw handemo::shape_error("image: " + a->in + ": --joints hand needs " + std::to_string(handemo::hand_joint_count) +
                                           " columns, the image has " + std::to_string(src.width));
            for (const auto& j : handemo::hand_skeleton().joints) names.push_back(j.name);
        }
        const handemo::rgb_image view = handemo::render_motion_image(src, names, a->scale);
        const std::string ext = std::filesystem::path(a->out).extension().string();
        if (ext == ".png" || ext == ".PNG")
            handemo::write_png(a->out, view);
        else if (ext == ".bmp" || ext == ".BMP")
            handemo::write_bmp(a->out, view);
        else
            throw handemo::value_error("image: --out " + a->out + ": extension '" + ext + "' is not .png or .bmp");
        std::cout << "wrote " << a->out << " (" << view.width << "x" << view.height << " from a " << src.height << "x" << src.width
                  << " motion image)\n";
    });
}};
