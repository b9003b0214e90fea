// Russell's circumplex (valence x arousal, both in [-1, 1]) as used by Aristidou et al. 2017: the
// coordinates of the emotion labels of the data sets (motion/circumplex.hpp reads them from
// data/rcm/circumplex.json: Warriner, Kuperman & Brysbaert 2013 word norms rescaled from 1..9 to
// [-1, 1]), the quadrant of a point, and an SVG picture of the circumplex with the training labels, an
// analysed motion and an optional target.
#pragma once

#include <handemo/core/error.hpp>
#include <handemo/core/io.hpp>
#include <handemo/motion/circumplex.hpp>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace handemo::rcm {

// The label table and its file (motion/circumplex.hpp, below both this module and stargan/, whose continuous
// control reads the same coordinates), under the names this module has always used.
using handemo::circumplex_table;
using handemo::label_point;
using handemo::load_circumplex;
using handemo::parse_circumplex;
using handemo::quadrant;

/// @brief Options of circumplex_svg().
struct circumplex_svg_options {
    std::string title = "Circumplex (valence x arousal)";
    std::size_t size = 480;
};

/// @brief SVG of the circumplex: axes, unit circle, the labels (`class="label"`), optional extra points
/// (`class="train"`, e.g. held-out predictions, coloured as the label of the same name), the analysed point
/// (`class="input"`) and a target (`class="target"`).
inline std::string circumplex_svg(const std::vector<label_point>& labels, const std::optional<label_point>& input,
                                  const std::optional<label_point>& target = std::nullopt,
                                  const std::vector<label_point>& training_points = {}, const circumplex_svg_options& opt = {})
{
    const double S = static_cast<double>(opt.size), m = 50, R = (S - 2 * m) / 2, cx = S / 2, cy = S / 2 + 10;
    auto X = [&](double v) { return cx + std::clamp(v, -1.1, 1.1) * R; };
    auto Y = [&](double a) { return cy - std::clamp(a, -1.1, 1.1) * R; };
    auto num = [](double v) {
        char b[32];
        std::snprintf(b, sizeof b, "%.2f", v);
        return std::string(b);
    };
    auto esc = [](const std::string& s) {
        std::string o;
        for (char c : s) o += c == '<' ? "&lt;" : c == '>' ? "&gt;" : c == '&' ? "&amp;" : c == '"' ? "&quot;" : std::string(1, c);
        return o;
    };
    std::string o = "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" + std::to_string(opt.size) + "\" height=\"" +
                    std::to_string(opt.size + 20) + "\" font-family=\"sans-serif\" font-size=\"12\">\n";
    o += "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n";
    o += "<text x=\"" + num(cx) + "\" y=\"20\" text-anchor=\"middle\" font-size=\"14\">" + esc(opt.title) + "</text>\n";
    o += "<circle cx=\"" + num(cx) + "\" cy=\"" + num(cy) + "\" r=\"" + num(R) + "\" fill=\"none\" stroke=\"#bbb\"/>\n";
    o += "<line x1=\"" + num(X(-1.05)) + "\" y1=\"" + num(cy) + "\" x2=\"" + num(X(1.05)) + "\" y2=\"" + num(cy) + "\" stroke=\"#888\"/>\n";
    o += "<line x1=\"" + num(cx) + "\" y1=\"" + num(Y(-1.05)) + "\" x2=\"" + num(cx) + "\" y2=\"" + num(Y(1.05)) + "\" stroke=\"#888\"/>\n";
    o += "<text x=\"" + num(X(1.05)) + "\" y=\"" + num(cy - 6) + "\" text-anchor=\"end\">valence +</text>\n";
    o += "<text x=\"" + num(X(-1.05)) + "\" y=\"" + num(cy - 6) + "\">valence -</text>\n";
    o += "<text x=\"" + num(cx + 6) + "\" y=\"" + num(Y(1.05) + 4) + "\">arousal +</text>\n";
    o += "<text x=\"" + num(cx + 6) + "\" y=\"" + num(Y(-1.05)) + "\">arousal -</text>\n";
    // one colour per label name, shared by the label point and the training points of that name
    static constexpr const char* palette[] = {"#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd",
                                              "#8c564b", "#e377c2", "#17becf", "#bcbd22", "#7f7f7f"};
    auto colour = [&](const std::string& name) -> std::string {
        for (std::size_t i = 0; i < labels.size(); ++i)
            if (labels[i].name == name) return palette[i % 10];
        return "#9ecae1";
    };
    for (const auto& p : training_points)
        o += "<circle class=\"train\" data-label=\"" + esc(p.name) + "\" cx=\"" + num(X(p.valence)) + "\" cy=\"" + num(Y(p.arousal)) +
             "\" r=\"3\" fill=\"" + colour(p.name) + "\" fill-opacity=\"0.45\"/>\n";
    for (const auto& p : labels) {
        const std::string c = colour(p.name);
        o += "<circle class=\"label\" data-label=\"" + esc(p.name) + "\" cx=\"" + num(X(p.valence)) + "\" cy=\"" + num(Y(p.arousal)) +
             "\" r=\"5\" fill=\"" + c + "\" stroke=\"black\"/>\n";
        o += "<text x=\"" + num(X(p.valence) + 7) + "\" y=\"" + num(Y(p.arousal) - 6) + "\" fill=\"" + c + "\">" + esc(p.name) + "</text>\n";
    }
    if (input) {
        o += "<circle class=\"input\" cx=\"" + num(X(input->valence)) + "\" cy=\"" + num(Y(input->arousal)) +
             "\" r=\"6\" fill=\"#d62728\" data-valence=\"" + num(input->valence) + "\" data-arousal=\"" + num(input->arousal) + "\"/>\n";
        o += "<text x=\"" + num(X(input->valence) + 8) + "\" y=\"" + num(Y(input->arousal) + 14) + "\" fill=\"#d62728\">" +
             esc(input->name.empty() ? "input" : input->name) + "</text>\n";
    }
    if (target) {
        const double tx = X(target->valence), ty = Y(target->arousal);
        o += "<path class=\"target\" d=\"M" + num(tx - 6) + " " + num(ty - 6) + " L" + num(tx + 6) + " " + num(ty + 6) + " M" + num(tx - 6) +
             " " + num(ty + 6) + " L" + num(tx + 6) + " " + num(ty - 6) + "\" stroke=\"#2ca02c\" stroke-width=\"3\" data-valence=\"" +
             num(target->valence) + "\" data-arousal=\"" + num(target->arousal) + "\"/>\n";
        o += "<text x=\"" + num(tx + 8) + "\" y=\"" + num(ty + 14) + "\" fill=\"#2ca02c\">" + esc(target->name.empty() ? "target" : target->name) +
             "</text>\n";
        if (input)
            o += "<line x1=\"" + num(X(input->valence)) + "\" y1=\"" + num(Y(input->arousal)) + "\" x2=\"" + num(tx) + "\" y2=\"" + num(ty) +
                 "\" stroke=\"#2ca02c\" stroke-dasharray=\"4 3\"/>\n";
    }
    o += "</svg>\n";
    return o;
}

}  // namespace handemo::rcm
