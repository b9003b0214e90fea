// `handemo encode IN.bvh|DIR --out OUT [--keyframes K] [--range RANGE.json] [--png]`: turns motion clips
// into the paper's motion images (Section 3.3.1, Eq. 3): K keyframes uniform in time (Section 3.2), one
// row per keyframe, one column per joint, R/G/B = x/y/z angles rescaled by the dataset's p_min/p_max.
// Without --range the range is computed over the inputs and written to OUT/range.json. Writes
// OUT/<stem>.bmp (lossless, as the paper), optionally .png, and OUT/index.json with the labels parsed from
// hand_<motion>_<emotion>_<take> names. Prints the codec's round-trip error (Eq. 3 then Eq. 6) against
// its bound (p_max - p_min) / 510.
#pragma once

#include "../registry.hpp"

#include <handemo/image.hpp>
#include <handemo/motion.hpp>
#include <handemo/image/keyframe_image.hpp>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

namespace handemo::cli::encode_cmd {

namespace fs = std::filesystem;
using dyn_keyframes = handemo::keyframes<handemo::dynamic_keyframes>;

struct encode_options {
    std::string in, out, range;
    std::size_t keyframes = 9;
    bool png = false;
};

std::vector<fs::path> bvh_inputs(const fs::path& in)
{
    std::error_code ec;
    if (!fs::exists(in, ec)) throw handemo::io_error("encode: input " + in.string() + " does not exist");
    std::vector<fs::path> files;
    if (fs::is_directory(in, ec)) {
        for (const auto& e : fs::directory_iterator(in))
            if (e.is_regular_file() && e.path().extension() == ".bvh") files.push_back(e.path());
        std::sort(files.begin(), files.end());
        if (files.empty()) throw handemo::io_error("encode: no .bvh files in directory " + in.string());
    } else {
        files.push_back(in);
    }
    return files;
}

void run_encode(const encode_options& o)
{
    if (o.keyframes < 2 || o.keyframes > 4096)
        throw handemo::value_error("encode: --keyframes " + std::to_string(o.keyframes) + " is not in 2..4096");
    const std::vector<fs::path> files = bvh_inputs(o.in);
    // Read and label everything before writing anything.
    std::vector<dyn_keyframes> kfs;
    nlohmann::json index = nlohmann::json::array();
    for (const auto& f : files) {
        const std::string stem = f.stem().string();
        nlohmann::json entry{{"image", stem + ".bmp"}, {"source", f.string()}};
        if (stem.rfind("hand_", 0) == 0) {
            const handemo::stem_labels l = handemo::parse_file_stem(stem);
            entry["motion"] = std::string(handemo::to_string(l.motion));
            entry["emotion"] = std::string(handemo::to_string(l.emo));
            entry["take"] = l.take;
        }
        const handemo::clip c = handemo::read_bvh(f);
        auto k = handemo::extract_keyframes<handemo::dynamic_keyframes>(c, o.keyframes);
        if (!kfs.empty() && k.joints != kfs.front().joints)
            throw handemo::shape_error("encode: " + f.string() + " has " + std::to_string(k.joints) + " joints, " +
                                       files.front().string() + " has " + std::to_string(kfs.front().joints));
        kfs.push_back(std::move(k));
        index.push_back(std::move(entry));
    }
    const fs::path out(o.out);
    std::error_code ec;
    fs::create_directories(out, ec);
    if (!fs::is_directory(out)) throw handemo::io_error("encode: cannot create output directory " + out.string());
    handemo::angle_range r;
    if (!o.range.empty()) {
        r = handemo::load_range(o.range);
        if ((r.keyframes && r.keyframes != o.keyframes) || (r.joints && r.joints != kfs.front().joints))
            throw handemo::shape_error("encode: " + o.range + " is for " + std::to_string(r.joints) + "x" +
                                       std::to_string(r.keyframes) + " images (joints x keyframes), the inputs give " +
                                       std::to_string(kfs.front().joints) + "x" + std::to_string(o.keyframes));
    } else {
        r = handemo::compute_range(kfs);
        handemo::save_range(out / "range.json", r);
        std::cout << "wrote " << (out / "range.json").string() << " (p_min " << r.p_min << ", p_max " << r.p_max << ")\n";
    }
    double worst = 0;
    std::size_t clamped = 0;
    for (std::size_t i = 0; i < kfs.size(); ++i) {
        const auto px = handemo::encode(kfs[i], r);
        const auto back = handemo::decode(px, r);
        for (std::size_t a = 0; a < back.angles.size(); ++a) {
            const double p = kfs[i].angles[a];
            if (p < r.p_min || p > r.p_max) ++clamped;
            else worst = std::max(worst, std::abs(back.angles[a] - p));
        }
        const handemo::rgb_image im = handemo::to_image(px);
        const std::string stem = files[i].stem().string();
        handemo::write_bmp(out / (stem + ".bmp"), im);
        std::cout << "wrote " << (out / (stem + ".bmp")).string();
        if (o.png) {
            handemo::write_png(out / (stem + ".png"), im);
            std::cout << " and .png";
        }
        std::cout << " (" << im.width << "x" << im.height << ")\n";
    }
    handemo::write_file_atomic(out / "index.json", index.dump(1) + "\n");
    std::cout << "encode: " << kfs.size() << " clips, " << o.keyframes << " keyframes x " << kfs.front().joints
              << " joints; round-trip max angle error " << worst << " deg (bound (p_max-p_min)/510 = "
              << r.max_roundtrip_error() << " deg)";
    if (clamped) std::cout << "; " << clamped << " angles outside the range were clamped";
    std::cout << "\n";
}

}  // namespace handemo::cli::encode_cmd

static handemo::cli::add_command reg_encode{20, [](CLI::App& app) {
    using namespace handemo::cli::encode_cmd;
    auto* sub = app.add_subcommand("encode", "Encode BVH clips as motion images (keyframes, Eq. 3) plus range.json");
    auto o = std::make_shared<encode_options>();
    sub->add_option("input", o->in, "A .bvh file or a directory of .bvh files")->required();
    sub->add_option("--out", o->out, "Output directory for the images, range.json and index.json")->required();
    sub->add_option("--keyframes", o->keyframes, "Keyframes per clip = image rows (default 9, as the paper)");
    sub->add_option("--range", o->range, "Use this range.json instead of computing one over the inputs");
    sub->add_flag("--png", o->png, "Also write a PNG beside each BMP");
    sub->callback([o] { run_encode(*o); });
}};
