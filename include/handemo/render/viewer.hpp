// A motion viewer as one self-contained HTML page: motion is judged by watching it move, and the filmstrips
// of the hand paper's Figures 4-12 are still. handemo does the forward kinematics (motion/skeleton.hpp) and
// embeds every frame's joint and end-site positions, the parent indices and the same per-finger / per-limb
// colours as the PNG renderer (figure.hpp analyse_figure) as JSON; the page only draws them with Canvas 2D
// (no library, no network, nothing fetched). Clips play in a grid of cells, row by row (at most 5 per row
// unless asked otherwise), in sync at their own frame rates or in normalised time (a transferred clip and its
// input, which may differ in tempo, stay aligned); play/pause, scrub, speed, orbit (drag), zoom (wheel) and
// joint names on hover. With a V/A grid (viewer_va_grid: outputs at grid points of the circumplex) the page
// also shows a small circumplex where a click, a drag or the arrow keys pick a point, and plays the output of
// the grid point nearest to it beside the clips before the grid's. For headless checks the page writes,
// into a hidden <pre id="check">, the frame it drew for every clip and the pixel centres of the joints it
// drew (recorded from the drawing calls themselves) at the initial camera, at time 0 or at the time given
// as `view.html?t=SECONDS` (which also starts paused there), and the canvas pixel read back at each centre;
// data-status becomes "ok" once it has drawn with ink at every joint centre and nothing on the console,
// "error: ..." on a script error, console.error/console.warn call or a joint drawn without ink. On a grid page
// `view.html?va=V,A` picks that point first, the check lists the clips drawn, and data-pick holds "index V A" of
// the last pick.
#pragma once

#include <handemo/core/error.hpp>
#include <handemo/motion/circumplex.hpp>
#include <handemo/motion/clip.hpp>
#include <handemo/render/figure.hpp>
#include <handemo/render/viewer_page.hpp>  // generated from viewer_page.html at build time

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace handemo {

/// @brief A grid of outputs over the circumplex for the page's V/A dial: the clips from `first` on are the
/// outputs at `points` (clips[first + k] at points[k], e.g. va_grid()'s points), the clips before `first` (the
/// input, say) are always shown. The page then shows those and one output, the grid point nearest to the point
/// picked on the dial.
struct viewer_va_grid {
    std::size_t first = 0;                         ///< clips shown beside the picked output
    std::size_t n = 0;                             ///< points per side of the grid (an arrow key moves 2 / (n - 1))
    std::vector<std::pair<double, double>> points; ///< (valence, arousal) of each output, in the unit disc
    std::vector<label_point> labels;               ///< drawn on the dial, the first darker (neutral)
};

/// @brief Options of render_viewer_html.
struct viewer_options {
    std::vector<std::string> titles;     ///< one per clip, or empty for "clip 1", "clip 2", ...
    bool normalised_time = false;        ///< start with every clip stretched to the longest one's duration
    std::size_t width = 960;             ///< canvas width in CSS pixels, shared by the clips of one row
    std::size_t height = 540;            ///< height in CSS pixels of one row's cells (below its title band)
    std::size_t columns = 0;             ///< clips per row; 0: ceil(n / rows) with rows = ceil(n / 5)
    std::string page_title = "handemo view";
    figure_options figure;               ///< kind (hand / body) and camera angles, as for filmstrips
    std::optional<viewer_va_grid> va_grid;  ///< a grid of outputs picked on a V/A dial (the cells: `first` + 1)
};

/// @brief Layout constants of the page. The n clips fill a grid of C columns (viewer_columns) and
/// rows = ceil(n / C) rows, row by row: clip i sits in row r = i / C, column k = i % C. Each row is a band of
/// `viewer_title_height` (T) CSS pixels for its cells' titles above cells of width w = W / C and height h
/// (viewer_options::height), so the canvas is W x rows (T + h) and clip i's cell is
///   [k w, (k + 1) w) x [y0, y0 + h),  y0 = (r + 1) T + r h.
/// A point p of clip i with view vectors (right, up), centre c and the shared radius R lands at
///   x = k w + w / 2 + dot(p - c, right) s,  y = y0 + h / 2 - dot(p - c, up) s,
///   s = zoom viewer_fill min(w, h) / (2 R)   (zoom 1 at the start).
inline constexpr double viewer_title_height = 24.0;
inline constexpr double viewer_fill = 0.9;
inline constexpr std::size_t viewer_auto_row = 5;          ///< clips per row at most with automatic columns
inline constexpr std::size_t viewer_max_columns = 10000;  ///< a larger viewer_options::columns is refused
/// @brief The V/A dial of a page with a grid: a square canvas of viewer_dial_size CSS pixels whose unit circle has
/// radius viewer_dial_radius * size about its centre: a click at (x, y) picks valence (x - size / 2) / r and
/// arousal (size / 2 - y) / r (brought onto the circle from outside), r = viewer_dial_radius * size.
inline constexpr double viewer_dial_size = 200.0;
inline constexpr double viewer_dial_radius = 0.42;

/// @brief The index into `points` of the point nearest to (valence, arousal) (Euclidean; the first of equals),
/// as the page picks it. @throws value_error for no points.
inline std::size_t nearest_va_point(const std::vector<std::pair<double, double>>& points, double valence, double arousal)
{
    if (points.empty()) throw value_error("nearest_va_point: no points");
    std::size_t best = 0;
    double bd = 1e300;
    for (std::size_t k = 0; k < points.size(); ++k) {
        const double dv = points[k].first - valence, da = points[k].second - arousal, d = dv * dv + da * da;
        if (d < bd) bd = d, best = k;
    }
    return best;
}

/// @brief The number of columns of the page's grid for n clips: `columns` clamped to n, or for 0 (automatic)
/// ceil(n / rows) with rows = ceil(n / viewer_auto_row), so at most 5 clips share a row and the rows are
/// filled evenly (7 clips: 4 + 3). 0 for n = 0.
/// @throws value_error for columns > viewer_max_columns.
inline std::size_t viewer_columns(std::size_t n, std::size_t columns)
{
    if (columns > viewer_max_columns)
        throw value_error("render_viewer_html: columns " + std::to_string(columns) + " is not in 0.." + std::to_string(viewer_max_columns) +
                          " (0: automatic)");
    if (n == 0) return 0;
    if (columns == 0) {
        const std::size_t rows = (n + viewer_auto_row - 1) / viewer_auto_row;
        return (n + rows - 1) / rows;
    }
    return std::min(columns, n);
}

namespace detail {

inline void json_string(std::string& out, std::string_view s)
{
    out += '"';
    for (char ch : s) {
        const auto u = static_cast<unsigned char>(ch);
        if (ch == '"') out += "\\\"";
        else if (ch == '\\') out += "\\\\";
        else if (ch == '\n') out += "\\n";
        else if (ch == '<') out += "\\u003c";  // no "</script>" inside the embedded data
        else if (ch == '>') out += "\\u003e";
        else if (ch == '&') out += "\\u0026";
        else if (u < 0x20) {
            char b[8];
            std::snprintf(b, sizeof b, "\\u%04x", u);
            out += b;
        } else out += ch;
    }
    out += '"';
}

inline void json_num(std::string& out, double v)
{
    if (!std::isfinite(v)) v = 0;
    char b[32];
    std::snprintf(b, sizeof b, "%.7g", v);
    out += b;
}

inline void json_vec(std::string& out, vec3 v)
{
    out += '[';
    for (int k = 0; k < 3; ++k) {
        if (k) out += ',';
        json_num(out, v[static_cast<std::size_t>(k)]);
    }
    out += ']';
}

inline std::string hex_color(color c)
{
    auto to8 = [](float x) { return static_cast<int>(std::lround(std::clamp(x, 0.0f, 1.0f) * 255.0f)); };
    char b[8];
    std::snprintf(b, sizeof b, "#%02x%02x%02x", to8(c.r), to8(c.g), to8(c.b));
    return b;
}

/// Points of a pose as the viewer stores them: the J joints, then the end site of every joint that has
/// one of nonzero length (parent: that joint).
inline std::vector<vec3> viewer_points(const pose_positions& P, std::span<const std::size_t> ends)
{
    std::vector<vec3> pts(P.joints.begin(), P.joints.end());
    for (auto j : ends) pts.push_back(P.end_sites[j]);
    return pts;
}

}  // namespace detail

/// @brief The data the page draws, as JSON:
/// `{"format":"handemo-view/2","width","height","columns","normalised","view":{"right","up","toward"},"radius",
///   "clips":[{"title","fps","frames","joints","points","names","parents","colors","hidden","stub","center",
///   "positions"}]}`, plus `"grid":{"first","n","points":[[v,a],...],"labels":[[name,v,a],...]}` with a V/A grid
/// (viewer_va_grid; `columns` then lays out its first + 1 cells). `points` = joints + end sites; `positions` is [frames, points, 3] flattened (world units,
/// 7 significant digits) from forward_kinematics; `width` is the canvas width, `height` the height of one row's
/// cells and `columns` the resolved column count (viewer_columns), laid out as viewer_title_height documents;
/// `hidden` points get no ball and no bone to them from
/// their children unless `stub`; a `stub` bone (a hand's forearm) is drawn over 30% of its length from the child.
/// @throws value_error for no clips, a clip with zero frames, a title count other than 0 or the clip count, a
///         width or height outside 64..16384, columns > 10000 or a canvas taller than 16384 (rows (title + height));
///         errors of clip::validate.
inline std::string viewer_json(std::span<const clip> clips, const viewer_options& opt = {})
{
    const std::string fn = "render_viewer_html";
    if (clips.empty()) throw value_error(fn + ": no clips to show (expected at least one)");
    if (!opt.titles.empty() && opt.titles.size() != clips.size())
        throw value_error(fn + ": " + std::to_string(opt.titles.size()) + " titles for " + std::to_string(clips.size()) +
                          " clips (expected one title per clip, or none)");
    if (opt.width < 64 || opt.height < 64 || opt.width > 16384 || opt.height > 16384)
        throw value_error(fn + ": width " + std::to_string(opt.width) + " x cell height " + std::to_string(opt.height) +
                          " is not in 64..16384 per side");
    // with a V/A grid the page shows the clips before the grid's and one output
    const std::size_t cells = opt.va_grid ? opt.va_grid->first + 1 : clips.size();
    if (opt.va_grid) {
        const viewer_va_grid& g = *opt.va_grid;
        if (g.points.empty() || g.first + g.points.size() != clips.size())
            throw value_error(fn + ": a V/A grid of " + std::to_string(g.points.size()) + " points after " + std::to_string(g.first) + " clips for " +
                              std::to_string(clips.size()) + " clips (expected one clip per grid point, at least one)");
        if (g.n < 2) throw value_error(fn + ": V/A grid size " + std::to_string(g.n) + " is not at least 2");
        for (const auto& [v, a] : g.points) circumplex_interpolation::check_point(v, a, fn + ": V/A grid");
        for (const auto& l : g.labels) circumplex_interpolation::check_point(l.valence, l.arousal, fn + ": V/A grid label '" + l.name + "'");
    }
    const std::size_t columns = viewer_columns(cells, opt.columns);
    const std::size_t rows = (cells + columns - 1) / columns;
    const double canvas_height = static_cast<double>(rows) * (viewer_title_height + static_cast<double>(opt.height));
    if (canvas_height > 16384.0)
        throw value_error(fn + ": " + std::to_string(rows) + " rows of height " + std::to_string(opt.height) + " under their titles make a canvas " +
                          std::to_string(static_cast<std::size_t>(canvas_height)) +
                          " pixels tall (expected at most 16384: more columns or a smaller height)");
    std::vector<figure_layout> layouts;
    for (std::size_t i = 0; i < clips.size(); ++i) {
        const std::string what = fn + ": clip " + std::to_string(i + 1);
        if (clips[i].frames == 0) throw value_error(what + " has 0 frames (expected at least 1)");
        if (!(clips[i].fps > 0)) throw value_error(what + ": fps " + std::to_string(clips[i].fps) + " is not > 0");
        clips[i].validate(what);
        layouts.push_back(analyse_figure(clips[i].skel, opt.figure.kind, opt.figure.trunk_color));
    }
    const view_basis view = choose_view(clips, layouts.front(), opt.figure);

    std::string clips_json;
    double radius = 0;
    for (std::size_t ci = 0; ci < clips.size(); ++ci) {
        const clip& c = clips[ci];
        const skeleton& s = c.skel;
        const figure_layout& L = layouts[ci];
        const std::size_t J = s.size();
        const bool hand = L.kind == figure_kind::hand;
        // end sites of nonzero length (from frame 0; an end-site offset does not change over time)
        const pose_positions P0 = clip_pose(c, 0);
        std::vector<std::size_t> ends;
        for (std::size_t j = 0; j < J; ++j)
            if (detail::v_norm(detail::v_sub(P0.end_sites[j], P0.joints[j])) > 1e-9) ends.push_back(j);
        const std::size_t NP = J + ends.size();
        std::vector<int> parents(NP), hidden(NP, 0), stub(NP, 0);
        std::vector<std::string> names(NP), colors(NP);
        for (std::size_t j = 0; j < J; ++j) {
            parents[j] = s.joints[j].parent;
            names[j] = s.joints[j].name;
            colors[j] = detail::hex_color(L.color_of(j));
            hidden[j] = L.hidden[j] || (hand && s.joints[j].parent < 0);  // no ball at a hand's cut forearm
            stub[j] = hand && parents[j] >= 0 && s.joints[static_cast<std::size_t>(parents[j])].parent < 0 &&
                      !L.hidden[static_cast<std::size_t>(parents[j])];
        }
        for (std::size_t e = 0; e < ends.size(); ++e) {
            parents[J + e] = static_cast<int>(ends[e]);
            names[J + e] = s.joints[ends[e]].name + " (end)";
            colors[J + e] = detail::hex_color(L.color_of(ends[e]));
        }

        // positions, and the drawn extent (centre: middle of the bounding box over all frames)
        std::string pos;
        pos.reserve(c.frames * NP * 3 * 10);
        vec3 lo{1e300, 1e300, 1e300}, hi{-1e300, -1e300, -1e300};
        std::vector<std::vector<vec3>> frames_pts;
        frames_pts.reserve(c.frames);
        for (std::size_t f = 0; f < c.frames; ++f) {
            const auto pts = detail::viewer_points(clip_pose(c, f), ends);
            for (std::size_t p = 0; p < NP; ++p) {
                if (f || p) pos += ',';
                detail::json_num(pos, pts[p][0]);
                pos += ',';
                detail::json_num(pos, pts[p][1]);
                pos += ',';
                detail::json_num(pos, pts[p][2]);
                vec3 q = pts[p];
                if (hidden[p]) continue;
                for (std::size_t k = 0; k < 3; ++k) lo[k] = std::min(lo[k], q[k]), hi[k] = std::max(hi[k], q[k]);
                if (stub[p]) {
                    q = detail::v_add(pts[p], detail::v_mul(detail::v_sub(pts[static_cast<std::size_t>(parents[p])], pts[p]), 0.3));
                    for (std::size_t k = 0; k < 3; ++k) lo[k] = std::min(lo[k], q[k]), hi[k] = std::max(hi[k], q[k]);
                }
            }
            frames_pts.push_back(pts);
        }
        vec3 center{};
        if (lo[0] <= hi[0]) center = detail::v_mul(detail::v_add(lo, hi), 0.5);
        for (const auto& pts : frames_pts)
            for (std::size_t p = 0; p < NP; ++p)
                if (!hidden[p]) radius = std::max(radius, detail::v_norm(detail::v_sub(pts[p], center)));

        std::string t = opt.titles.empty() ? "clip " + std::to_string(ci + 1) : opt.titles[ci];
        std::string& o = clips_json;
        o += ci ? ",\n{" : "{";
        o += "\"title\":";
        detail::json_string(o, t);
        o += ",\"fps\":";
        detail::json_num(o, c.fps);
        o += ",\"frames\":" + std::to_string(c.frames) + ",\"joints\":" + std::to_string(J) + ",\"points\":" + std::to_string(NP);
        o += ",\"names\":[";
        for (std::size_t p = 0; p < NP; ++p) {
            if (p) o += ',';
            detail::json_string(o, names[p]);
        }
        o += "],\"parents\":[";
        for (std::size_t p = 0; p < NP; ++p) o += (p ? "," : "") + std::to_string(parents[p]);
        o += "],\"colors\":[";
        for (std::size_t p = 0; p < NP; ++p) o += (p ? ",\"" : "\"") + colors[p] + "\"";
        o += "],\"hidden\":[";
        for (std::size_t p = 0; p < NP; ++p) o += (p ? "," : "") + std::to_string(hidden[p]);
        o += "],\"stub\":[";
        for (std::size_t p = 0; p < NP; ++p) o += (p ? "," : "") + std::to_string(stub[p]);
        o += "],\"center\":";
        detail::json_vec(o, center);
        o += ",\"positions\":[" + pos + "]}";
    }
    if (!(radius > 1e-12)) radius = 1;

    std::string j = "{\"format\":\"handemo-view/2\",\"width\":" + std::to_string(opt.width) + ",\"height\":" + std::to_string(opt.height) +
                    ",\"columns\":" + std::to_string(columns) + ",\"normalised\":" + (opt.normalised_time ? "true" : "false") + ",\"view\":{\"right\":";
    detail::json_vec(j, view.right);
    j += ",\"up\":";
    detail::json_vec(j, view.up);
    j += ",\"toward\":";
    detail::json_vec(j, view.toward);
    j += "},\"radius\":";
    detail::json_num(j, radius);
    if (opt.va_grid) {
        const viewer_va_grid& g = *opt.va_grid;
        j += ",\n\"grid\":{\"first\":" + std::to_string(g.first) + ",\"n\":" + std::to_string(g.n) + ",\"points\":[";
        for (std::size_t k = 0; k < g.points.size(); ++k) {
            j += k ? ",[" : "[";
            detail::json_num(j, g.points[k].first);
            j += ',';
            detail::json_num(j, g.points[k].second);
            j += ']';
        }
        j += "],\"labels\":[";
        for (std::size_t k = 0; k < g.labels.size(); ++k) {
            j += k ? ",[" : "[";
            detail::json_string(j, g.labels[k].name);
            j += ',';
            detail::json_num(j, g.labels[k].valence);
            j += ',';
            detail::json_num(j, g.labels[k].arousal);
            j += ']';
        }
        j += "]}";
    }
    j += ",\n\"clips\":[\n" + clips_json + "]}";
    return j;
}

/// @brief One self-contained HTML page (no network access, nothing fetched) that plays `clips` in a grid
/// (viewer_options::columns; layout as viewer_title_height documents).
/// @param clips any skeletons; the camera comes from the first clip, as for filmstrips.
/// @return the HTML text (write it with write_file_atomic).
/// @throws as viewer_json.
inline std::string render_viewer_html(std::span<const clip> clips, const viewer_options& opt = {})
{
    const std::string data = viewer_json(clips, opt);
    std::string title;
    for (char ch : opt.page_title) {
        if (ch == '<') title += "&lt;";
        else if (ch == '>') title += "&gt;";
        else if (ch == '&') title += "&amp;";
        else title += ch;
    }
    // the page, include/handemo/render/viewer_page.html, is embedded at build time (viewer_page.hpp); its
    // @HANDEMO_...@ markers take the title, the data and the layout constants
    const std::pair<std::string_view, std::string> fields[] = {{"@HANDEMO_TITLE@", title},
                                                               {"@HANDEMO_DATA@", data},
                                                               {"@HANDEMO_TITLE_HEIGHT@", std::to_string(viewer_title_height)},
                                                               {"@HANDEMO_FILL@", std::to_string(viewer_fill)},
                                                               {"@HANDEMO_DIAL_SIZE@", std::to_string(viewer_dial_size)},
                                                               {"@HANDEMO_DIAL_RADIUS@", std::to_string(viewer_dial_radius)}};
    std::string h;
    h.reserve(detail::viewer_page.size() + data.size() + title.size());
    std::size_t pos = 0;
    while (pos < detail::viewer_page.size()) {
        const std::size_t at = detail::viewer_page.find("@HANDEMO_", pos);
        if (at == std::string_view::npos) {
            h += detail::viewer_page.substr(pos);
            break;
        }
        h += detail::viewer_page.substr(pos, at - pos);
        bool replaced = false;
        for (const auto& [marker, value] : fields)
            if (detail::viewer_page.substr(at, marker.size()) == marker) {
                h += value;
                pos = at + marker.size();
                replaced = true;
                break;
            }
        if (!replaced) h += '@', pos = at + 1;  // not a marker: copied as it is
    }
    return h;
}

}  // namespace handemo
