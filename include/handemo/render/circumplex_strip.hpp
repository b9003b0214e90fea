// A filmstrip along a path on the circumplex: render_filmstrip()'s columns (one clip per point of the path) under
// a band that draws, above each column, a small circumplex (unit circle, axes, the labels' points) with that
// column's target point on it, so a reader sees where on the dial each column's emotion lies.
#pragma once

#include <handemo/core/error.hpp>
#include <handemo/motion/circumplex.hpp>
#include <handemo/render/canvas.hpp>
#include <handemo/render/filmstrip.hpp>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <span>
#include <utility>
#include <vector>

namespace handemo {

/// @brief The colour of a column's target point on its inset.
inline constexpr color circumplex_target_color = color::rgb8(214, 39, 40);

/// @brief Draws a small circumplex into `c` in the square of side `size` at (x0, y0): the unit circle, the axes
/// (valence to the right, arousal up), each label's point (grey; the first of `labels` darker, e.g. neutral) and
/// the target (valence, arousal) as a red dot.
inline void draw_circumplex_inset(canvas& c, long x0, long y0, long size, const std::vector<label_point>& labels, double valence, double arousal)
{
    const double s = static_cast<double>(size), r = 0.42 * s, cx = static_cast<double>(x0) + s / 2, cy = static_cast<double>(y0) + s / 2;
    const auto at = [&](double v, double a) { return point2{cx + std::clamp(v, -1.0, 1.0) * r, cy - std::clamp(a, -1.0, 1.0) * r}; };
    const color ink = color::rgb8(150, 150, 150);
    c.draw_line({cx - r, cy}, {cx + r, cy}, 1.0, ink);
    c.draw_line({cx, cy - r}, {cx, cy + r}, 1.0, ink);
    constexpr int segments = 72;
    for (int i = 0; i < segments; ++i) {
        const double t0 = 2 * std::numbers::pi * i / segments, t1 = 2 * std::numbers::pi * (i + 1) / segments;
        c.draw_line(at(std::cos(t0), std::sin(t0)), at(std::cos(t1), std::sin(t1)), 1.0, color::rgb8(90, 90, 90));
    }
    const double dot = std::max(1.5, s / 40);
    for (std::size_t i = 0; i < labels.size(); ++i)
        c.fill_disc(at(labels[i].valence, labels[i].arousal), dot, i == 0 ? color::rgb8(60, 60, 60) : color::rgb8(120, 120, 120));
    c.fill_disc(at(valence, arousal), 1.8 * dot, circumplex_target_color);
}

/// @brief A filmstrip of `clips` (render_filmstrip()) under a band of small circumplexes, one above each column
/// with that column's target point (draw_circumplex_inset(); `labels` first the neutral one). A column whose
/// point is absent (the input, say) gets no inset.
/// @param points one per clip: the column's (valence, arousal), or nullopt
/// @throws value_error for a point count other than the clip count; what render_filmstrip() throws.
inline rgb_image render_circumplex_filmstrip(std::span<const clip> clips, const std::vector<std::optional<std::pair<double, double>>>& points,
                                             const std::vector<label_point>& labels, const filmstrip_options& opt = {})
{
    if (points.size() != clips.size())
        throw value_error("circumplex filmstrip: " + std::to_string(points.size()) + " points for " + std::to_string(clips.size()) +
                          " clips (expected one per clip)");
    const rgb_image strip = render_filmstrip(clips, opt);
    const long gap = filmstrip_gap, cw = static_cast<long>(opt.cell_width);
    const long side = std::min<long>(cw, 120), band = side + gap;
    canvas out(strip.width, strip.height + static_cast<std::size_t>(band), opt.figure.background);
    for (std::size_t y = 0; y < strip.height; ++y)
        for (std::size_t x = 0; x < strip.width; ++x) {
            const std::uint8_t* p = strip.pixels.data() + (y * strip.width + x) * 3;
            out.blend(static_cast<long>(x), static_cast<long>(y) + band, color::rgb8(p[0], p[1], p[2]), 1.0f);
        }
    for (std::size_t i = 0; i < clips.size(); ++i)
        if (points[i]) {
            const long x0 = gap + static_cast<long>(i) * (cw + gap) + (cw - side) / 2;
            draw_circumplex_inset(out, x0, gap, side, labels, points[i]->first, points[i]->second);
        }
    return out.to_image();
}

}  // namespace handemo
