// Filmstrips as in the hand paper's Figures 4-12 ("Screenshots (one frame per row) ... Columns from left to
// right: angry, happy, input (neutral), sad, fearful"): one column per clip, one row per sampled frame
// (sampled uniformly over each clip's own duration, frame round(r (n - 1) / (rows - 1)) in row r), column
// titles on top. One camera and one scale serve the whole strip: the view comes from the first clip and
// the scale from the bounding box of every frame of every clip, so sizes and motions compare across cells.
#pragma once

#include <handemo/core/error.hpp>
#include <handemo/image/rgb_image.hpp>
#include <handemo/motion/clip.hpp>
#include <handemo/render/canvas.hpp>
#include <handemo/render/figure.hpp>
#include <handemo/render/font.hpp>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <span>
#include <string>
#include <vector>

namespace handemo {

/// Pixels of grid colour between and around the cells of a filmstrip. Cell (row r, column c) has its
/// top-left corner at (gap + c (cell_width + gap), title_height + gap + r (cell_height + gap)).
inline constexpr long filmstrip_gap = 3;

/// @brief Layout of a filmstrip.
struct filmstrip_options {
    std::size_t rows = 5;                ///< sampled frames per clip (one row each), 1..1000
    std::size_t cell_width = 200;        ///< pixels per cell, 32..4096
    std::size_t cell_height = 200;
    std::vector<std::string> titles;     ///< one per clip (column titles), or empty for none
    bool frame_labels = true;            ///< write the frame index in each cell's corner
    int title_scale = 2;                 ///< font scale of the titles (reduced when a title does not fit)
    color grid_color = color::rgb8(215, 215, 215);
    figure_options figure;               ///< camera, colours, kind (hand / body)
};

namespace detail {

/// Row r of `rows` shows frame round(r (n - 1) / (rows - 1)) of an n-frame clip.
inline std::size_t filmstrip_frame(std::size_t r, std::size_t rows, std::size_t n) noexcept
{
    if (rows <= 1 || n <= 1) return 0;
    return static_cast<std::size_t>(std::llround(static_cast<double>(r) * static_cast<double>(n - 1) /
                                                 static_cast<double>(rows - 1)));
}

/// Horizontal centroid (component orthogonal to `up`) of the drawn joints of a pose.
inline vec3 horizontal_centroid(const figure_layout& L, const pose_positions& P, vec3 up) noexcept
{
    vec3 m{};
    double n = 0;
    for (std::size_t j = 0; j < P.joints.size(); ++j) {
        if (L.hidden[j]) continue;
        m = v_add(m, P.joints[j]);
        n += 1;
    }
    return n > 0 ? v_reject(v_mul(m, 1.0 / n), v_unit(up, {0, 1, 0})) : vec3{};
}

/// Shortens `s` with a trailing ".." until it fits `max_px` at `scale`.
inline std::string fit_text(std::string s, long max_px, int scale)
{
    if (text_width(s, scale) <= max_px) return s;
    while (!s.empty() && text_width(s + "..", scale) > max_px) s.pop_back();
    return s.empty() ? s : s + "..";
}

}  // namespace detail

/// @brief Everything a filmstrip's cells share: per-clip layouts, the camera, scale and tracking.
struct filmstrip_plan {
    std::vector<figure_layout> layouts;  ///< [clips]
    figure_projection projection;        ///< view, view-space centre, pixels per unit, depth range
    bool track = false;                  ///< whether each frame is centred on its horizontal centroid
    point2 origin;                       ///< where the view-space centre lands in a cell, in cell pixels

    /// @brief The tracking offset of a pose of clip `ci` (zero when not tracking).
    vec3 track_offset(std::size_t ci, const pose_positions& P, const figure_options& o) const
    {
        return track ? detail::horizontal_centroid(layouts[ci], P, o.up) : vec3{};
    }
    /// @brief Pixel position inside a cell of a world point of a pose whose tracking offset is `offset`.
    point2 project(vec3 p, vec3 offset = {}) const noexcept
    {
        const vec3 q = detail::v_sub(p, offset);
        const view_basis& v = projection.view;
        return {origin.x + (detail::v_dot(q, v.right) - projection.cx) * projection.scale,
                origin.y - (detail::v_dot(q, v.up) - projection.cy) * projection.scale};
    }
};

/// @brief Checks the inputs of a filmstrip and fits one camera and scale to every frame of every clip.
/// @throws value_error for no clips, a clip with zero frames, a title count that is neither 0 nor the
///         clip count, rows or cell sizes out of range; shape_error / value_error from clip::validate.
inline filmstrip_plan plan_filmstrip(std::span<const clip> clips, const filmstrip_options& opt)
{
    const std::string fn = "render_filmstrip";
    if (clips.empty()) throw value_error(fn + ": no clips to draw (expected at least one)");
    if (opt.rows < 1 || opt.rows > 1000)
        throw value_error(fn + ": rows " + std::to_string(opt.rows) + " is not in 1..1000");
    if (opt.cell_width < 32 || opt.cell_height < 32 || opt.cell_width > 4096 || opt.cell_height > 4096)
        throw value_error(fn + ": cell size " + std::to_string(opt.cell_width) + "x" + std::to_string(opt.cell_height) +
                          " is not in 32..4096 per side");
    if (!opt.titles.empty() && opt.titles.size() != clips.size())
        throw value_error(fn + ": " + std::to_string(opt.titles.size()) + " titles for " + std::to_string(clips.size()) +
                          " clips (expected one title per clip, or none)");
    filmstrip_plan plan;
    std::vector<figure_layout>& layouts = plan.layouts;
    for (std::size_t i = 0; i < clips.size(); ++i) {
        const std::string what = fn + ": clip " + std::to_string(i) + (opt.titles.empty() ? "" : " ('" + opt.titles[i] + "')");
        if (clips[i].frames == 0) throw value_error(what + " has 0 frames (expected at least 1)");
        clips[i].validate(what);
        layouts.push_back(analyse_figure(clips[i].skel, opt.figure.kind, opt.figure.trunk_color));
    }
    const figure_layout& L0 = layouts.front();
    const bool hand = L0.kind == figure_kind::hand;
    const bool track = opt.figure.track < 0 ? !hand : opt.figure.track > 0;
    plan.track = track;
    figure_projection& pr = plan.projection;
    pr.view = choose_view(clips, L0, opt.figure);

    // Pass 1: view-space bounding box and depth range over every frame of every clip.
    double x0 = 1e300, x1 = -1e300, y0 = 1e300, y1 = -1e300, d0 = 1e300, d1 = -1e300;
    auto track_of = [&](std::size_t ci, const pose_positions& P) {
        return plan.track_offset(ci, P, opt.figure);
    };
    for (std::size_t ci = 0; ci < clips.size(); ++ci) {
        for (std::size_t f = 0; f < clips[ci].frames; ++f) {
            const pose_positions P = clip_pose(clips[ci], f);
            for (const auto& q : figure_primitives(clips[ci].skel, layouts[ci], P, track_of(ci, P))) {
                auto take = [&](vec3 p) {
                    const double x = detail::v_dot(p, pr.view.right), y = detail::v_dot(p, pr.view.up),
                                 d = detail::v_dot(p, pr.view.toward);
                    x0 = std::min(x0, x), x1 = std::max(x1, x), y0 = std::min(y0, y), y1 = std::max(y1, y);
                    d0 = std::min(d0, d), d1 = std::max(d1, d);
                };
                if (q.kind == figure_primitive::shape::palm) {
                    for (auto& p : q.polygon) take(p);
                } else {
                    take(q.a);
                    take(q.b);
                }
            }
        }
    }
    if (!(x1 >= x0)) x0 = x1 = y0 = y1 = d0 = d1 = 0;  // nothing drawable (every joint hidden)

    const auto cw = static_cast<double>(opt.cell_width), ch = static_cast<double>(opt.cell_height);
    const double side = std::min(cw, ch);
    const double bone_width = opt.figure.bone_width > 0 ? opt.figure.bone_width : (hand ? 0.024 : 0.014);
    pr.radius_px = std::max(1.0, bone_width * side);
    const double label_h = opt.frame_labels ? 10.0 : 0.0;
    const double pad = 2.0 * pr.radius_px + 4.0;
    const double sx = (cw - 2 * pad) / std::max(x1 - x0, 1e-9), sy = (ch - 2 * pad - label_h) / std::max(y1 - y0, 1e-9);
    pr.scale = std::max(1e-9, std::min(sx, sy));
    if (x1 - x0 < 1e-9 && y1 - y0 < 1e-9) pr.scale = 1.0;
    pr.cx = 0.5 * (x0 + x1);
    pr.cy = 0.5 * (y0 + y1);
    pr.depth_min = d0;
    pr.depth_max = d1;

    plan.origin = {cw / 2, (ch - label_h) / 2};
    return plan;
}

namespace detail {

/// Draws a filmstrip of `rows` rows whose cell (row r, column c) shows frame `frame_of(r, c)` of clip c.
/// render_filmstrip and filmstrip_animation both draw through this, so an animation frame is pixel for
/// pixel a one-row filmstrip of the same frames.
template <class FrameOf>
rgb_image draw_filmstrip(std::span<const clip> clips, const filmstrip_options& opt, const filmstrip_plan& plan,
                         std::size_t rows_n, FrameOf&& frame_of)
{
    const figure_projection& pr = plan.projection;
    const long gap = filmstrip_gap;
    int ts = std::max(1, opt.title_scale);  // one scale for every title: the largest at which all fit
    for (const auto& t : opt.titles)
        while (ts > 1 && text_width(t, ts) > static_cast<long>(opt.cell_width) - 4) --ts;
    const long title_h = opt.titles.empty() ? 0 : text_height(ts) + 12;
    const auto cols = static_cast<long>(clips.size()), rows = static_cast<long>(rows_n);
    const long W = cols * static_cast<long>(opt.cell_width) + (cols + 1) * gap;
    const long H = title_h + rows * static_cast<long>(opt.cell_height) + (rows + 1) * gap;
    canvas out(static_cast<std::size_t>(W), static_cast<std::size_t>(H), opt.grid_color);
    if (title_h > 0) out.fill_rect(0, 0, W, title_h, opt.figure.background);
    for (long c = 0; c < cols; ++c) {
        const long cx0 = gap + c * (static_cast<long>(opt.cell_width) + gap);
        if (title_h > 0) {
            const int s = ts;
            const std::string t = detail::fit_text(opt.titles[static_cast<std::size_t>(c)], static_cast<long>(opt.cell_width) - 4, s);
            draw_text(out, cx0 + (static_cast<long>(opt.cell_width) - text_width(t, s)) / 2, (title_h - text_height(s)) / 2, t,
                      color::rgb8(30, 30, 30), s);
        }
        const clip& cl = clips[static_cast<std::size_t>(c)];
        for (long r = 0; r < rows; ++r) {
            const std::size_t f = frame_of(static_cast<std::size_t>(r), static_cast<std::size_t>(c));
            canvas cell(opt.cell_width, opt.cell_height, opt.figure.background);
            const pose_positions P = clip_pose(cl, f);
            const auto prims = figure_primitives(cl.skel, plan.layouts[static_cast<std::size_t>(c)], P,
                                                 plan.track_offset(static_cast<std::size_t>(c), P, opt.figure));
            draw_figure(cell, prims, pr, plan.origin, opt.figure.background);
            if (opt.frame_labels)
                draw_text(cell, 3, static_cast<long>(opt.cell_height) - 9, "f" + std::to_string(f), color::rgb8(140, 140, 140), 1);
            out.blit(cell, cx0, title_h + gap + r * (static_cast<long>(opt.cell_height) + gap));
        }
    }
    return out.to_image();
}

}  // namespace detail

/// @brief Renders clips side by side, one sampled frame per row (the paper's Figures 4-12).
/// @param clips one column each; any skeletons (the camera comes from the first clip).
/// @param opt rows, cell size, column titles, figure options.
/// @return an RGB image of cols x rows cells plus a title band.
/// @throws value_error for no clips, a clip with zero frames, a title count that is neither 0 nor the
///         clip count, rows or cell sizes out of range; shape_error / value_error from clip::validate.
inline rgb_image render_filmstrip(std::span<const clip> clips, const filmstrip_options& opt = {})
{
    const filmstrip_plan plan = plan_filmstrip(clips, opt);
    return detail::draw_filmstrip(clips, opt, plan, opt.rows, [&](std::size_t r, std::size_t c) {
        return detail::filmstrip_frame(r, opt.rows, clips[c].frames);
    });
}

}  // namespace handemo
