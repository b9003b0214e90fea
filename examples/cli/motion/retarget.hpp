// `handemo retarget --in A.bvh --to hand|body|SKELETON.bvh|MODEL --out B.bvh [--hand left|right] [--map MAP.json]`:
// the retargeting alone (retarget/), to check a mapping in a viewer or to move motion between rigs. `--print-map`
// writes the slots found in the input as a map file, a start for a rig of one's own.
#pragma once

#include "../registry.hpp"
#include "../retarget_common.hpp"

#include <handemo/core/io.hpp>
#include <handemo/motion/body.hpp>
#include <handemo/motion/bvh.hpp>
#include <handemo/motion/hand.hpp>
#include <handemo/nn/safetensors.hpp>
#include <handemo/retarget.hpp>

#include <filesystem>
#include <iostream>
#include <memory>
#include <string>

namespace handemo::cli::retarget_cmd {

struct retarget_cli {
    std::string in, to, out, hand, map, to_map;
    bool print_map = false;
};

/// The target skeleton of --to: handemo's hand or body, a BVH file's skeleton, or the skeleton a model stores.
inline skeleton target_skeleton(const std::string& to)
{
    namespace fs = std::filesystem;
    if (to == "hand") return hand_skeleton();
    if (to == "body") return body_skeleton();
    if (fs::path(to).extension() == ".bvh") {
        skeleton s = read_bvh(to).skel;
        s.name = fs::path(to).filename().string();
        return s;
    }
    const fs::path ck = fs::is_directory(to) ? fs::path(to) / "checkpoint.safetensors" : fs::path(to);
    if (!fs::exists(ck)) throw io_error("retarget: --to " + to + ": not hand, body, a .bvh file or a model (no " + ck.string() + ")");
    const auto f = read_safetensors(ck);
    const auto it = f.metadata.find("skeleton");
    if (it == f.metadata.end()) throw format_error("retarget: --to " + to + ": the model stores no skeleton (trained before skeletons were stored)");
    skeleton s = parse_bvh(it->second, ck.string() + " (metadata 'skeleton')").skel;
    s.name = ck.string();
    return s;
}

inline void run(const retarget_cli& o)
{
    const clip in = read_bvh(o.in);
    retarget::map_options mo;
    mo.hand = hand_side(o.hand);
    if (!o.map.empty()) mo.source_slots = retarget::read_map(o.map, in.skel);
    if (o.print_map) {
        const auto b = mo.source_slots ? *mo.source_slots : retarget::detect(in.skel, mo.hand ? mo.hand : 'r');
        std::cout << retarget::map_to_json(b, in.skel);
        if (o.to.empty()) return;
    }
    if (o.to.empty() || o.out.empty()) throw value_error("retarget: --to and --out are needed (or --print-map alone)");
    const skeleton target = target_skeleton(o.to);
    if (!o.to_map.empty()) mo.target_slots = retarget::read_map(o.to_map, target);
    const auto m = retarget::make_map(in.skel, target, mo);
    print_map_summary("retarget", o.in, m);
    write_bvh(o.out, retarget::retarget_clip(in, m));
    std::cout << "retarget: wrote " << o.out << " (" << in.frames << " frames)\n";
}

}  // namespace handemo::cli::retarget_cmd

static handemo::cli::add_command reg_retarget{36, [](CLI::App& app) {
    auto* sub = app.add_subcommand("retarget", "Move a motion onto another skeleton (handemo's hand or body, a BVH's or a model's skeleton)");
    auto o = std::make_shared<handemo::cli::retarget_cmd::retarget_cli>();
    sub->add_option("--in", o->in, "Input motion (.bvh), any skeleton a built-in convention or --map describes")->required();
    sub->add_option("--to", o->to, "Target: hand, body, a .bvh file (its skeleton) or a model folder (the skeleton it was trained on)");
    sub->add_option("--out", o->out, "Output .bvh on the target skeleton");
    sub->add_option("--hand", o->hand, "Which hand of the input, for a hand target: left or right (needed when it has two)")
        ->check(CLI::IsMember({"left", "right"}));
    sub->add_option("--map", o->map, "JSON map file naming the input's joints by slot (docs/retargeting.md)");
    sub->add_option("--to-map", o->to_map, "JSON map file naming the target's joints by slot");
    sub->add_flag("--print-map", o->print_map, "Print the slots found in the input as a map file (JSON) and stop unless --to is given");
    sub->callback([o] { handemo::cli::retarget_cmd::run(*o); });
}};
