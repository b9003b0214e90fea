// `handemo synth --out DIR [--takes N] [--seed S] [--fps F] [--motion-set paper|extended]`: writes the synthetic
// hand-motion emotion dataset (handemo/motion/synth.hpp: 7 motion types, or 12 with the extended set, x 5 emotions
// x N takes, each exactly 2 cycles on the 23-joint hand of Eq. 1) as hand_<motion>_<emotion>_<take>.bvh plus a
// matching .csv per take.
#pragma once

#include "../registry.hpp"

#include <handemo/motion.hpp>

#include <cstdint>
#include <filesystem>
#include <iostream>
#include <memory>
#include <string>

namespace handemo::cli::synth_cmd {

struct synth_options {
    std::string out;
    int takes = 1;
    std::uint64_t seed = 1;
    double fps = 60.0;
    std::string motion_set = "paper";
};

void run_synth(const synth_options& o)
{
    namespace fs = std::filesystem;
    if (o.takes < 1 || o.takes > 1000)
        throw handemo::value_error("synth: --takes " + std::to_string(o.takes) + " is not in 1..1000");
    const fs::path dir(o.out);
    std::error_code ec;
    fs::create_directories(dir, ec);
    if (!fs::is_directory(dir)) throw handemo::io_error("synth: cannot create output directory " + dir.string());
    std::size_t files = 0;
    double seconds = 0;
    const auto set = handemo::motion_set_from_string(o.motion_set);
    for (handemo::hand_motion m : handemo::motions_of(set))
        for (handemo::emotion e : handemo::all_emotions)
            for (int k = 0; k < o.takes; ++k) {
                const handemo::clip c = handemo::synthesize(m, e, k, o.seed, o.fps);
                const std::string stem = handemo::file_stem(m, e, k);
                handemo::write_bvh(dir / (stem + ".bvh"), c);
                handemo::write_csv(dir / (stem + ".csv"), c);
                std::cout << "wrote " << (dir / (stem + ".bvh")).string() << " and .csv (" << c.frames << " frames, "
                          << c.duration() << " s)\n";
                files += 2;
                seconds += c.duration();
            }
    std::cout << "synth: " << files << " files (" << files / 2 << " takes, " << seconds << " s of motion at " << o.fps
              << " fps, seed " << o.seed << ") in " << dir.string() << "\n";
}

}  // namespace handemo::cli::synth_cmd

static handemo::cli::add_command reg_synth{10, [](CLI::App& app) {
    using namespace handemo::cli::synth_cmd;
    auto* sub = app.add_subcommand("synth", "Write the synthetic hand-motion emotion dataset (7 or 12 motions x 5 emotions) as BVH + CSV");
    auto o = std::make_shared<synth_options>();
    sub->add_option("--out", o->out, "Output directory (created if missing)")->required();
    sub->add_option("--takes", o->takes, "Takes per motion/emotion pair (default 1)");
    sub->add_option("--seed", o->seed, "Random seed (default 1); the same seed always gives the same files");
    sub->add_option("--fps", o->fps, "Frame rate (default 60)");
    sub->add_option("--motion-set", o->motion_set,
                    "paper: the paper's 7 motion types (default); extended: 12, five more with motion-dependent emotion effects");
    sub->callback([o] { run_synth(*o); });
}};
