// `handemo info FILE`: describes any file handemo reads. BVH and CSV motion (joint count and names,
// channel layout, frames, fps, duration, per-axis angle ranges: the P_j of Eq. 1), BMP/PNG motion images
// (size, channel count, per-channel pixel min/max: the v of Eq. 3), and JSON (keys with a summary of each
// value, e.g. the codec's range file with p_min/p_max of Eq. 3 and Eq. 6).
#pragma once

#include "../registry.hpp"

#include <handemo/core/io.hpp>
#include <handemo/motion.hpp>
#include <handemo/image.hpp>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cctype>
#include <climits>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <limits>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

namespace handemo::cli::info_cmd {

namespace fs = std::filesystem;

std::string fixed(double v, int decimals = 3)
{
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
    return buf;
}

void describe_clip(const handemo::clip& c, const std::string& format, std::ostream& out)
{
    const auto& sk = c.skel;
    const std::size_t J = sk.size();
    out << "format: " << format << "\n";
    out << "joints: " << J << " (";
    const std::size_t shown = 6;
    for (std::size_t j = 0; j < J; ++j) {
        if (J > shown + 2 && j == shown / 2 + 1) {
            out << ", ... ";
            j = J - shown / 2;
        } else if (j > 0) {
            out << ", ";
        }
        out << sk.joints[j].name;
    }
    std::size_t roots = 0, end_sites = 0, channels = 0;
    for (const auto& jt : sk.joints) {
        roots += jt.parent < 0;
        end_sites += jt.end_site.has_value();
        channels += jt.channels.size();
    }
    out << ")\n";
    out << "roots: " << roots << ", end sites: " << end_sites << "\n";
    // Group joints by channel layout, in order of first appearance.
    std::vector<std::pair<std::string, std::size_t>> layouts;
    for (const auto& jt : sk.joints) {
        std::string l = std::to_string(jt.channels.size()) + " (";
        for (std::size_t k = 0; k < jt.channels.size(); ++k)
            l += (k ? " " : "") + std::string(handemo::channel_name(jt.channels[k]));
        l += ")";
        auto it = std::find_if(layouts.begin(), layouts.end(), [&](auto& p) { return p.first == l; });
        if (it == layouts.end()) layouts.emplace_back(l, 1);
        else ++it->second;
    }
    out << "channels: " << channels << " per frame: ";
    for (std::size_t i = 0; i < layouts.size(); ++i)
        out << (i ? ", " : "") << layouts[i].second << (layouts[i].second == 1 ? " joint x " : " joints x ")
            << layouts[i].first;
    out << "\n";
    out << "frames: " << c.frames << ", fps: " << fixed(c.fps, c.fps == std::round(c.fps) ? 0 : 4)
        << ", duration: " << fixed(c.duration()) << " s\n";
    double lo[3], hi[3];
    for (int a = 0; a < 3; ++a) lo[a] = std::numeric_limits<double>::infinity(), hi[a] = -lo[a];
    for (std::size_t i = 0; i < c.angles.size(); ++i) {
        const std::size_t a = i % 3;
        lo[a] = std::min(lo[a], c.angles[i]);
        hi[a] = std::max(hi[a], c.angles[i]);
    }
    out << "angle range (deg):";
    for (int a = 0; a < 3; ++a) out << " " << "xyz"[a] << " [" << fixed(lo[a]) << ", " << fixed(hi[a]) << "]";
    out << "\n";
}

void describe_image(const fs::path& path, std::ostream& out)
{
    const std::string data = handemo::read_file(path);
    const char* format = data.rfind("BM", 0) == 0 ? "BMP" : data.rfind("\x89PNG", 0) == 0 ? "PNG" : "unknown";
    int w = 0, h = 0, comp = 0;
    const auto* buf = reinterpret_cast<const stbi_uc*>(data.data());
    const int len = static_cast<int>(std::min<std::size_t>(data.size(), static_cast<std::size_t>(INT_MAX)));
    if (stbi_info_from_memory(buf, len, &w, &h, &comp) && (comp != 3 || stbi_is_16_bit_from_memory(buf, len))) {
        // Describe what it is, and why handemo will not use it as a motion image.
        out << "format: " << format << "\nsize: " << w << "x" << h
            << " (width x height)\nchannels: " << comp << ", " << (stbi_is_16_bit_from_memory(buf, len) ? 16 : 8)
            << " bits per channel\nnote: not usable as a motion image (handemo needs 8-bit, 3-channel RGB)\n";
        return;
    }
    const handemo::rgb_image im = handemo::decode_image(data, path.string());
    out << "format: " << format << "\n";
    out << "size: " << im.width << "x" << im.height << " (width x height)\n";
    out << "channels: 3, 8 bits per channel\n";
    const char* names[] = {"R", "G", "B"};
    out << "pixel range:";
    for (std::size_t c = 0; c < 3; ++c) {
        int lo = 255, hi = 0;
        for (std::size_t i = c; i < im.pixels.size(); i += 3) lo = std::min<int>(lo, im.pixels[i]), hi = std::max<int>(hi, im.pixels[i]);
        out << " " << names[c] << " [" << lo << ", " << hi << "]";
    }
    out << "\n";
}

/// One-line summary of a JSON value: numbers and strings as themselves, arrays by length (and the
/// min/max of the numbers they contain), objects by their key count.
std::string json_summary(const nlohmann::json& v)
{
    if (v.is_array()) {
        double lo = std::numeric_limits<double>::infinity(), hi = -lo;
        std::size_t numbers = 0;
        std::vector<const nlohmann::json*> todo{&v};
        while (!todo.empty()) {
            const auto* x = todo.back();
            todo.pop_back();
            if (x->is_number()) {
                const double d = x->get<double>();
                lo = std::min(lo, d), hi = std::max(hi, d), ++numbers;
            } else if (x->is_array()) {
                for (const auto& e : *x) todo.push_back(&e);
            }
        }
        std::string s = "array[" + std::to_string(v.size()) + "]";
        if (numbers) s += " of " + std::to_string(numbers) + " numbers in [" + fixed(lo, 4) + ", " + fixed(hi, 4) + "]";
        return s;
    }
    if (v.is_object()) return "object with " + std::to_string(v.size()) + " keys";
    std::string s = v.dump();
    if (s.size() > 60) s = s.substr(0, 57) + "...";
    return s;
}

void describe_json(const fs::path& path, std::ostream& out)
{
    const std::string text = handemo::read_file(path);
    nlohmann::json j;
    try {
        j = nlohmann::json::parse(text);
    } catch (const nlohmann::json::parse_error& e) {
        throw handemo::format_error("json: " + path.string() + ": " + e.what());
    }
    out << "format: JSON " << (j.is_object() ? "object" : j.type_name()) << "\n";
    if (!j.is_object()) {
        out << "value: " << json_summary(j) << "\n";
        return;
    }
    // Keys and nested keys (two levels), each with a summary of its value.
    for (const auto& [k, v] : j.items()) {
        out << k << ": " << json_summary(v) << "\n";
        if (v.is_object())
            for (const auto& [k2, v2] : v.items()) out << "  " << k2 << ": " << json_summary(v2) << "\n";
    }
    if (j.contains("p_min") && j.contains("p_max") && j["p_min"].is_number() && j["p_max"].is_number())
        out << "codec range: p_min " << j["p_min"].get<double>() << ", p_max " << j["p_max"].get<double>() << " (Eq. 3/6)\n";
}

void describe(const std::string& file, const std::string& skeleton_bvh, std::ostream& out)
{
    const fs::path path(file);
    std::string ext = path.extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    if (ext != ".bvh" && ext != ".csv" && ext != ".bmp" && ext != ".png" && ext != ".json")
        throw handemo::value_error("info: " + file + ": unknown file type '" + ext +
                                   "', expected .bvh, .csv (with --skeleton), .bmp, .png or .json");
    std::ostringstream s;  // print nothing unless the whole file is understood
    s << "file: " << file << "\n";
    if (ext == ".bvh") {
        describe_clip(handemo::read_bvh(path), "BVH", s);
    } else if (ext == ".csv") {
        if (skeleton_bvh.empty())
            throw handemo::value_error("info: " + file + ": a CSV file needs --skeleton REF.bvh (the joints it names)");
        describe_clip(handemo::read_csv(path, handemo::read_bvh(skeleton_bvh).skel), "CSV", s);
    } else if (ext == ".json") {
        describe_json(path, s);
    } else {
        describe_image(path, s);
    }
    out << s.str();
}

}  // namespace handemo::cli::info_cmd

static handemo::cli::add_command reg_info{90, [](CLI::App& app) {
    using namespace handemo::cli::info_cmd;
    auto* sub = app.add_subcommand("info", "Describe a BVH, CSV, BMP/PNG or JSON file");
    auto file = std::make_shared<std::string>();
    auto skel = std::make_shared<std::string>();
    sub->add_option("file", *file, "File to describe (.bvh, .csv, .bmp, .png, .json)")->required();
    sub->add_option("--skeleton", *skel, "Reference BVH giving the skeleton of a CSV file");
    sub->callback([=] { describe(*file, *skel, std::cout); });
}};
