// A motion viewer as one self-contained HTML page: motion is judged by watching it move, and the filmstrips
// of the hand paper's Figures 4-12 are still. handemo does the forward kinematics (motion/skeleton.hpp) and
// embeds every frame's joint and end-site positions, the parent indices and the same per-finger / per-limb
// colours as the PNG renderer (figure.hpp analyse_figure) as JSON; the page only draws them with Canvas 2D
// (no library, no network, nothing fetched). Clips play in a grid of cells, row by row (at most 5 per row
// unless asked otherwise), in sync at their own frame rates or in normalised time (a transferred clip and its
// input, which may differ in tempo, stay aligned); play/pause, scrub, speed, orbit (drag), zoom (wheel) and
// joint names on hover. For headless checks the page writes,
// into a hidden <pre id="check">, the frame it drew for every clip and the pixel centres of the joints it
// drew (recorded from the drawing calls themselves) at the initial camera, at time 0 or at the time given
// as `view.html?t=SECONDS` (which also starts paused there), and the canvas pixel read back at each centre;
// data-status becomes "ok" once it has drawn with ink at every joint centre and nothing on the console,
// "error: ..." on a script error, console.error/console.warn call or a joint drawn without ink.
#pragma once

#include <handemo/core/error.hpp>
#include <handemo/motion/clip.hpp>
#include <handemo/render/figure.hpp>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace handemo {

/// @brief Options of render_viewer_html.
struct viewer_options {
    std::vector<std::string> titles;     ///< one per clip, or empty for "clip 1", "clip 2", ...
    bool normalised_time = false;        ///< start with every clip stretched to the longest one's duration
    std::size_t width = 960;             ///< canvas width in CSS pixels, shared by the clips of one row
    std::size_t height = 540;            ///< height in CSS pixels of one row's cells (below its title band)
    std::size_t columns = 0;             ///< clips per row; 0: ceil(n / rows) with rows = ceil(n / 5)
    std::string page_title = "handemo view";
    figure_options figure;               ///< kind (hand / body) and camera angles, as for filmstrips
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
///   "positions"}]}`. `points` = joints + end sites; `positions` is [frames, points, 3] flattened (world units,
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
    const std::size_t columns = viewer_columns(clips.size(), opt.columns);
    const std::size_t rows = (clips.size() + columns - 1) / columns;
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
    std::string h;
    h.reserve(data.size() + 12000);
    h += R"js(<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>)js" + title + R"js(</title>
<style>
body{font:14px sans-serif;margin:12px;color:#222;background:#fafafa}
canvas{background:#fff;border:1px solid #ccc;cursor:grab;display:block}
#bar{margin:8px 0;display:flex;gap:12px;align-items:center;flex-wrap:wrap}
#scrub{width:360px}
#check{display:none}
</style></head><body>
<div id="heading"></div>
<canvas id="view"></canvas>
<div id="bar"><button id="play">pause</button>
<input id="scrub" type="range" min="0" max="1000" value="0">
<span id="time"></span>
<label>speed <select id="speed"><option>0.25</option><option>0.5</option><option selected>1</option><option>2</option></select></label>
<label><input id="norm" type="checkbox"> normalised time</label>
<button id="reset">reset view</button>
<span style="color:#777">drag: orbit, wheel: zoom, space: play/pause, hover: joint names</span></div>
<pre id="check" data-status="not run"></pre>
<script type="application/json" id="data">
)js";
    h += data;
    h += R"js(
</script>
<script>
"use strict";
(function () {
const check = document.getElementById("check");
const problems = [];  // script errors and console errors/warnings, reported by the check
function fail(msg) { problems.push(String(msg)); check.textContent = "error: " + problems.join("; "); check.setAttribute("data-status", "error: " + msg); }
window.onerror = function (msg) { fail(msg); };
if (window.addEventListener) window.addEventListener("unhandledrejection", e => fail("unhandled rejection: " + e.reason));
for (const level of ["error", "warn"]) {
  const orig = console[level];
  console[level] = function () { fail("console." + level + ": " + Array.prototype.join.call(arguments, " ")); return orig.apply(console, arguments); };
}
const D = JSON.parse(document.getElementById("data").textContent);
const W = D.width, TITLE = )js" + std::to_string(viewer_title_height) + R"js(, FILL = )js" + std::to_string(viewer_fill) + R"js(;
const n = D.clips.length, cols = D.columns, rows = Math.ceil(n / cols);
const cw = W / cols, ch = D.height, H = rows * (TITLE + ch);  // cell size; canvas height
function cell(i) {  // clip i's cell: row i / cols, column i % cols, below its row's title band
  const r = Math.floor(i / cols), k = i % cols;
  return {x: k * cw, y: (r + 1) * TITLE + r * ch, r: r, k: k};
}
const cv = document.getElementById("view"), ctx = cv.getContext("2d");
const dpr = window.devicePixelRatio || 1;
cv.width = Math.round(W * dpr); cv.height = Math.round(H * dpr);
cv.style.width = W + "px"; cv.style.height = H + "px";
const dur = D.clips.map(c => c.frames / c.fps), T = Math.max.apply(null, dur);
let t = 0, playing = true, speed = 1, yaw = 0, pitch = 0, zoom = 1, mouse = null, drag = null, last = null;
const norm = document.getElementById("norm"); norm.checked = D.normalised;
document.getElementById("heading").textContent = n + " clip" + (n > 1 ? "s" : "") + ": " +
  D.clips.map(c => c.title + " (" + c.frames + " frames, " + c.fps + " fps)").join(", ");
function rot(v, k, a) {  // Rodrigues: v turned by a radians about the unit axis k
  const c = Math.cos(a), s = Math.sin(a), d = k[0]*v[0] + k[1]*v[1] + k[2]*v[2];
  const x = [k[1]*v[2] - k[2]*v[1], k[2]*v[0] - k[0]*v[2], k[0]*v[1] - k[1]*v[0]];
  return [0, 1, 2].map(i => v[i]*c + x[i]*s + k[i]*d*(1 - c));
}
function camera() {  // the initial view turned by yaw about its up and pitch about the new right
  const up0 = D.view.up;
  const r = rot(D.view.right, up0, yaw), tw = rot(D.view.toward, up0, yaw);
  return {right: r, up: rot(up0, r, pitch), toward: rot(tw, r, pitch)};
}
function frameOf(i) {
  const c = D.clips[i];
  if (norm.checked) return Math.min(c.frames - 1, Math.round(t / T * (c.frames - 1)));
  return Math.min(c.frames - 1, Math.floor(t * c.fps + 1e-9));
}
function project(i, f, cam) {  // pixel positions of every point of clip i at frame f
  const c = D.clips[i], P = c.positions, o = f * c.points * 3, s = zoom * FILL * Math.min(cw, ch) / (2 * D.radius);
  const b = cell(i), out = [];
  for (let p = 0; p < c.points; ++p) {
    const q = [P[o + 3*p] - c.center[0], P[o + 3*p + 1] - c.center[1], P[o + 3*p + 2] - c.center[2]];
    const dot = v => q[0]*v[0] + q[1]*v[1] + q[2]*v[2];
    out.push({x: b.x + cw/2 + dot(cam.right)*s, y: b.y + ch/2 - dot(cam.up)*s, z: dot(cam.toward)});
  }
  return out;
}
let hover = null, trace = null;  // trace: when an array, draw() records [clip, frame, point, x, y] of every joint it draws
function draw() {
  const cam = camera();
  ctx.setTransform(dpr, 0, 0, dpr, 0, 0);
  ctx.clearRect(0, 0, W, H);
  ctx.font = "14px sans-serif"; ctx.textAlign = "center"; ctx.fillStyle = "#222";
  const base = Math.max(1.5, 0.02 * Math.min(cw, ch) * zoom);
  let best = null;
  for (let i = 0; i < n; ++i) {
    const c = D.clips[i], f = frameOf(i), px = project(i, f, cam), b = cell(i);
    ctx.fillStyle = "#222"; ctx.fillText(c.title, b.x + cw/2, b.y - TITLE + 17, cw - 4);
    ctx.strokeStyle = "#ddd"; ctx.lineWidth = 1; ctx.beginPath();
    if (b.k) { ctx.moveTo(b.x, b.y - TITLE); ctx.lineTo(b.x, b.y + ch); }  // between the columns of a row
    if (b.r) { ctx.moveTo(b.x, b.y - TITLE); ctx.lineTo(b.x + cw, b.y - TITLE); }  // between rows
    ctx.stroke();
    ctx.save(); ctx.beginPath(); ctx.rect(b.x, b.y, cw, ch); ctx.clip();
    const items = [];
    for (let p = 0; p < c.points; ++p) {
      const q = c.parents[p];
      if (q >= 0 && (!c.hidden[q] || c.stub[p])) {
        let a = px[q];
        if (c.stub[p]) a = {x: px[p].x + 0.3*(a.x - px[p].x), y: px[p].y + 0.3*(a.y - px[p].y), z: px[p].z + 0.3*(a.z - px[p].z)};
        items.push({z: (a.z + px[p].z)/2, bone: true, a: a, b: px[p], col: c.colors[p]});
      }
      if (!c.hidden[p]) items.push({z: px[p].z + 1e-6, bone: false, b: px[p], col: c.colors[p]});
    }
    items.sort((u, v) => u.z - v.z);  // painter: far first
    ctx.lineCap = "round";
    if (trace) for (let p = 0; p < c.points; ++p) if (!c.hidden[p]) trace.push([i, f, p, px[p].x, px[p].y]);
    for (const it of items) {
      if (it.bone) { ctx.strokeStyle = it.col; ctx.lineWidth = 2*base; ctx.beginPath(); ctx.moveTo(it.a.x, it.a.y); ctx.lineTo(it.b.x, it.b.y); ctx.stroke(); }
      else { ctx.fillStyle = it.col; ctx.strokeStyle = "rgba(0,0,0,0.35)"; ctx.lineWidth = 1; ctx.beginPath(); ctx.arc(it.b.x, it.b.y, 1.15*base, 0, 2*Math.PI); ctx.fill(); ctx.stroke(); }
    }
    ctx.restore();
    ctx.fillStyle = "#888"; ctx.font = "11px sans-serif"; ctx.textAlign = "left";
    ctx.fillText("frame " + f + " / " + (c.frames - 1), b.x + 6, b.y + ch - 6);
    ctx.font = "14px sans-serif"; ctx.textAlign = "center";
    const inside = mouse && mouse.x >= b.x && mouse.x < b.x + cw && mouse.y >= b.y && mouse.y < b.y + ch;
    if (inside) for (let p = 0; p < c.points; ++p) {  // hover: the joints of the cell under the mouse (drawing is clipped to it)
      if (c.hidden[p]) continue;
      const d = Math.hypot(px[p].x - mouse.x, px[p].y - mouse.y);
      if (d < 10 && (!best || d < best.d)) best = {d: d, x: px[p].x, y: px[p].y, text: c.title + ": " + c.names[p]};
    }
  }
  hover = best;
  if (best) {
    ctx.font = "12px sans-serif"; ctx.textAlign = "left";
    const w = ctx.measureText(best.text).width + 10, x = Math.min(best.x + 10, W - w - 2), y = Math.max(best.y - 26, 2);
    ctx.fillStyle = "rgba(255,255,224,0.95)"; ctx.fillRect(x, y, w, 20);
    ctx.strokeStyle = "#999"; ctx.strokeRect(x, y, w, 20);
    ctx.fillStyle = "#222"; ctx.fillText(best.text, x + 5, y + 14);
  }
  document.getElementById("scrub").value = Math.round(t / T * 1000);
  document.getElementById("time").textContent = t.toFixed(2) + " / " + T.toFixed(2) + " s";
}
function tick(now) {
  if (last !== null && playing) { t += (now - last) / 1000 * speed; if (t >= T) t = t % T; }
  last = now; draw(); requestAnimationFrame(tick);
}
const playBtn = document.getElementById("play");
function toggle() { playing = !playing; playBtn.textContent = playing ? "pause" : "play"; }
playBtn.onclick = toggle;
document.addEventListener("keydown", e => { if (e.code === "Space") { e.preventDefault(); toggle(); } });
document.getElementById("scrub").oninput = e => { t = e.target.value / 1000 * T; if (t >= T) t = Math.max(0, T - 1e-6); draw(); };
document.getElementById("speed").onchange = e => { speed = parseFloat(e.target.value); };
norm.onchange = draw;
document.getElementById("reset").onclick = () => { yaw = 0; pitch = 0; zoom = 1; draw(); };
function pos(e) { const r = cv.getBoundingClientRect(); return {x: e.clientX - r.left, y: e.clientY - r.top}; }
cv.addEventListener("mousedown", e => { drag = pos(e); cv.style.cursor = "grabbing"; });
window.addEventListener("mouseup", () => { drag = null; cv.style.cursor = "grab"; });
cv.addEventListener("mousemove", e => {
  const p = pos(e); mouse = p;
  if (drag) { yaw -= (p.x - drag.x) * 0.01; pitch = Math.max(-1.55, Math.min(1.55, pitch + (p.y - drag.y) * 0.01)); drag = p; }
  if (!playing) draw();
});
cv.addEventListener("mouseleave", () => { mouse = null; if (!playing) draw(); });
cv.addEventListener("wheel", e => { e.preventDefault(); zoom = Math.max(0.1, Math.min(20, zoom * Math.exp(-e.deltaY * 0.001))); if (!playing) draw(); }, {passive: false});
// Headless check: draw once at time ?t= (default 0) at the initial camera, recording the joints drawn, then
// read the canvas back at each joint centre. Lines "clip i frame f: p:x,y p:x,y ..." (CSS pixels), then
// "ink k/m" (joint centres whose canvas pixel is opaque).
const query = typeof location !== "undefined" ? new URLSearchParams(location.search) : null;
if (query && query.has("t")) { t = Math.max(0, Math.min(parseFloat(query.get("t")) || 0, T)); playing = false; playBtn.textContent = "play"; }
trace = [];
draw();
const lines = [];
let inked = 0;
for (let i = 0; i < n; ++i) {
  const mine = trace.filter(r => r[0] === i);
  lines.push("clip " + i + " frame " + (mine.length ? mine[0][1] : frameOf(i)) + ": " + mine.map(r => r[2] + ":" + r[3].toFixed(2) + "," + r[4].toFixed(2)).join(" "));
}
const img = ctx.getImageData(0, 0, cv.width, cv.height);  // one readback (several would warn on the console)
for (const r of trace) {
  const x = Math.floor(r[3] * dpr), y = Math.floor(r[4] * dpr);
  if (img && img.data && x >= 0 && y >= 0 && x < cv.width && y < cv.height && img.data[4 * (y * cv.width + x) + 3] === 255) ++inked;
}
lines.push("ink " + inked + "/" + trace.length);
const drawn = trace.length;
trace = null;
if (!problems.length) {
  check.textContent = lines.join("\n");
  check.setAttribute("data-status", inked === drawn ? "ok" : "error: " + (drawn - inked) + " of " + drawn + " joints drawn without ink");
}
requestAnimationFrame(tick);
})();
</script>
</body></html>
)js";
    return h;
}

}  // namespace handemo
