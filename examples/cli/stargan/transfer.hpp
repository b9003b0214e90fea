// `handemo transfer --model MODEL --in IN.bvh|IN.bmp|DIR --emotion E --out OUT.bvh|OUT.bmp|DIR`: turns a motion
// into the target emotion with a trained model (Section 3.4 of the hand paper: keyframes -> Eq. 3 image -> G ->
// Eq. 6 -> interpolation, with the learned tempo factor). A folder in: every .bvh in it, on --threads threads
// sharing the one loaded model (with an emotion target each thread runs G on batches of files), into the --out
// folder under the same names, with a progress bar; a file that fails is named and skipped, and the command fails at the end when any did. Instead of --emotion, a point of the
// circumplex (--valence V --arousal A), or a target that moves over the clip (--path "neutral,sad,angry" with
// --duration, or --curve FILE of time,valence,arousal rows): the continuous control of stargan/continuous.hpp.
// --grid N --out view.html: the transfers at the points of an N x N grid over the unit disc (G once per label,
// then a blend per point), in one offline viewer page whose V/A dial picks the output played.
#pragma once

#include "../registry.hpp"
#include "options.hpp"

#include <handemo/image.hpp>
#include <handemo/image/keyframe_image.hpp>
#include <handemo/render/circumplex_strip.hpp>
#include <handemo/render/viewer.hpp>
#include <handemo/retarget.hpp>
#include <handemo/stargan.hpp>
#include "../retarget_common.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

// Where the shipped model is looked for (the build sets both: this source tree's copy and the installed one).
#ifndef HANDEMO_SHIPPED_MODEL
#define HANDEMO_SHIPPED_MODEL ""
#endif
#ifndef HANDEMO_INSTALLED_MODEL
#define HANDEMO_INSTALLED_MODEL ""
#endif
#ifndef HANDEMO_SHIPPED_CIRCUMPLEX
#define HANDEMO_SHIPPED_CIRCUMPLEX ""
#endif
#ifndef HANDEMO_INSTALLED_CIRCUMPLEX
#define HANDEMO_INSTALLED_CIRCUMPLEX ""
#endif

namespace handemo::cli::transfer_cmd {

/// The shipped hand model: $HANDEMO_MODEL, else this source tree's data/models/hand-embedded, else the installed copy.
inline std::filesystem::path default_model()
{
    if (const char* e = std::getenv("HANDEMO_MODEL"); e && *e) return e;
    for (const char* p : {HANDEMO_SHIPPED_MODEL, HANDEMO_INSTALLED_MODEL})
        if (std::filesystem::exists(std::filesystem::path(p) / "checkpoint.safetensors")) return p;
    throw io_error(std::string("transfer: no --model given and no shipped model at ") + HANDEMO_SHIPPED_MODEL + " or " + HANDEMO_INSTALLED_MODEL +
                   " (set HANDEMO_MODEL or pass --model)");
}

/// The labels' circumplex coordinates: this source tree's data/rcm/circumplex.json, else the installed copy.
inline std::filesystem::path default_circumplex()
{
    for (const char* p : {HANDEMO_SHIPPED_CIRCUMPLEX, HANDEMO_INSTALLED_CIRCUMPLEX})
        if (*p && std::filesystem::exists(p)) return p;
    throw io_error(std::string("transfer: no circumplex coordinates at ") + HANDEMO_SHIPPED_CIRCUMPLEX + " or " + HANDEMO_INSTALLED_CIRCUMPLEX +
                   " (pass --circumplex)");
}

struct transfer_cli {
    std::string model, in, emotion, out, from, like, hand, map;
    std::size_t frames = 0, threads = 0;
    bool detail = false;
    kernels::weight_storage weights = kernels::weight_storage::native;
    kernels::conv_algorithm conv = kernels::conv_algorithm::direct;
    // the continuous target: a point, a path over a duration, or a curve file
    std::optional<double> valence, arousal, duration;
    std::string path, curve, circumplex;
    std::string rate_blend;  ///< how the labels' tempo and amplitude factors are blended (stargan::rate_blend); empty: the default
    // a filmstrip along the --path: one column per point (--steps per segment), a small circumplex above each
    std::string filmstrip;
    std::size_t steps = 4, rows = 5;
    // a grid of points over the unit disc, written into one viewer page (--out view.html)
    std::size_t grid = 0;
};

/// What a transfer goes to: an emotion, or the continuous control with a point or a curve.
struct transfer_target {
    std::optional<stargan::continuous_control> control;
    std::optional<std::pair<double, double>> point;
    std::optional<va_curve> curve;
    std::string title;  ///< for the report: the emotion, the point or the path
};

/// The target of the options: exactly one of --emotion, --valence/--arousal, --path, --curve. A --path without
/// --duration spans `clip_seconds` (the input's duration; 0 when the input is a folder: then --duration is needed).
inline transfer_target target_of(const transfer_cli& o, const stargan::emotion_model& model)
{
    const int kinds = (o.emotion.empty() ? 0 : 1) + (o.valence || o.arousal ? 1 : 0) + (o.path.empty() ? 0 : 1) + (o.curve.empty() ? 0 : 1) +
                      (o.grid ? 1 : 0);
    if (kinds == 0) throw value_error("transfer: no target: give --emotion, or --valence and --arousal, or --path, or --curve, or --grid");
    if (kinds > 1) throw value_error("transfer: give one target: --emotion, --valence/--arousal, --path, --curve or --grid");
    if (o.grid) va_grid(o.grid);  // a grid size out of range stops here
    if (o.duration && o.path.empty()) throw value_error("transfer: --duration is the time of a --path");
    transfer_target t;
    const stargan::rate_blend rates = o.rate_blend.empty() ? stargan::default_rate_blend : stargan::parse_rate_blend(o.rate_blend, "transfer: --rate-blend");
    if (!o.emotion.empty()) {
        if (!o.rate_blend.empty())
            throw value_error("transfer: --rate-blend blends the labels' rates between their points: it needs a continuous target, not --emotion");
        model.domain(o.emotion);  // an unknown emotion stops here, before any file is read
        t.title = o.emotion;
        return t;
    }
    if (o.detail) throw value_error("transfer: --detail is per emotion: it is not available with a continuous target");
    const std::filesystem::path table_path = o.circumplex.empty() ? default_circumplex() : std::filesystem::path(o.circumplex);
    const circumplex_table table = load_circumplex(table_path);
    t.control.emplace(model, table, rates, table_path.string());
    char b[96];
    if (o.valence || o.arousal) {
        if (!o.valence || !o.arousal) throw value_error("transfer: --valence and --arousal go together (a point of the circumplex)");
        circumplex_interpolation::check_point(*o.valence, *o.arousal, "transfer: --valence/--arousal");
        t.point.emplace(*o.valence, *o.arousal);
        std::snprintf(b, sizeof b, "valence %g arousal %g", *o.valence, *o.arousal);
        t.title = b;
    } else if (!o.path.empty()) {
        const auto waypoints = parse_path(o.path, table.labels, "transfer: --path");
        if (o.duration && !(*o.duration > 0)) throw value_error("transfer: --duration " + std::to_string(*o.duration) + " s is not positive");
        // without --duration, the path spans the input (set per clip by curve_for())
        t.curve = path_curve(waypoints, o.duration ? *o.duration : 1.0, "transfer: --path");
        t.title = "path " + o.path;
    } else if (!o.curve.empty()) {
        t.curve = read_va_curve(o.curve);
        t.title = "curve " + o.curve;
    } else {
        t.title = "V/A grid " + std::to_string(o.grid) + " x " + std::to_string(o.grid);
    }
    return t;
}

/// The curve of `t` for a clip: a --path without --duration stretched from the clip's first frame to its last.
inline va_curve curve_for(const transfer_cli& o, const transfer_target& t, const clip& in)
{
    va_curve c = *t.curve;
    if (!o.path.empty() && !o.duration && c.size() > 1) {
        const double d = in.frames > 1 ? static_cast<double>(in.frames - 1) / in.fps : 1.0;  // first frame to last
        const double scale = d / c.time.back();
        for (auto& x : c.time) x *= scale;
    }
    return c;
}

/// --filmstrip: the input, then one column per point of the --path (waypoints and --steps - 1 points between each
/// two), each the transfer at that constant point, with the point drawn on a small circumplex above its column.
inline void write_path_filmstrip(const transfer_cli& o, const transfer_target& t, const clip& in, const stargan::capture_options& co)
{
    const std::string ext = std::filesystem::path(o.filmstrip).extension().string();
    if (ext != ".png" && ext != ".bmp") throw value_error("transfer: --filmstrip " + o.filmstrip + ": expected a .png or .bmp file");
    const circumplex_table table = load_circumplex(o.circumplex.empty() ? default_circumplex() : std::filesystem::path(o.circumplex));
    const auto points = sample_path(parse_path(o.path, table.labels, "transfer: --path"), o.steps, "transfer: --steps");
    const auto source = o.from.empty() ? std::optional<std::string_view>() : std::optional<std::string_view>(o.from);
    std::vector<clip> clips{in};
    std::vector<std::optional<std::pair<double, double>>> where{std::nullopt};
    filmstrip_options fo;
    fo.rows = o.rows;
    fo.cell_width = fo.cell_height = 140;
    fo.titles.push_back("input");
    for (const auto& p : points) {
        clips.push_back(stargan::transfer_capture(*t.control, in, std::pair{p.valence, p.arousal}, source, co).motion);
        where.emplace_back(std::pair{p.valence, p.arousal});
        fo.titles.push_back(path_title(p));
    }
    // the labels' points on each inset: the model's, neutral first
    const auto& labels = t.control->interpolation().labels();
    std::vector<label_point> drawn{labels[t.control->interpolation().neutral()]};
    for (std::size_t i = 0; i < labels.size(); ++i)
        if (i != t.control->interpolation().neutral()) drawn.push_back(labels[i]);
    const rgb_image im = render_circumplex_filmstrip(clips, where, drawn, fo);
    (ext == ".png" ? write_png : write_bmp)(o.filmstrip, im);
    std::cout << "transfer: wrote " << o.filmstrip << " (" << im.width << "x" << im.height << ", the input and " << points.size()
              << " points of the path)\n";
}

/// One capture through the target: transfer_capture() of the emotion, the point or the curve.
inline stargan::capture_result transfer_one(const transfer_cli& o, const stargan::emotion_model& model, const transfer_target& t, const clip& in,
                                            const stargan::capture_options& co)
{
    const auto source = o.from.empty() ? std::optional<std::string_view>() : std::optional<std::string_view>(o.from);
    if (t.point) return stargan::transfer_capture(*t.control, in, *t.point, source, co);
    if (t.curve) return stargan::transfer_capture(*t.control, in, curve_for(o, t, in), source, co);
    return stargan::transfer_capture(model, in, o.emotion, source, co);
}

inline bool has_ext(const std::string& p, const char* a, const char* b = nullptr)
{
    const auto e = std::filesystem::path(p).extension().string();
    return e == a || (b && e == b);
}

/// The capture options of a BVH transfer (hand, map, detail) for the clip `in`.
inline stargan::capture_options capture_options_of(const transfer_cli& o, const clip& in)
{
    stargan::capture_options co;
    co.hand = hand_side(o.hand);
    co.detail = o.detail;
    if (!o.map.empty()) co.slots = retarget::read_map(o.map, in.skel);
    return co;
}

/// --grid N: the input, then the transfer at every point of va_grid(N) (G run once per label on the clip the model
/// sees, prepare(); then one blend per point), in one viewer page with the V/A dial (viewer_va_grid).
inline void write_grid_view(const transfer_cli& o, const transfer_target& t, const clip& in, const stargan::capture_options& co)
{
    if (!has_ext(o.out, ".html")) throw value_error("transfer: --grid writes a viewer page: --out " + o.out + " must be a .html file");
    const auto points = va_grid(o.grid);
    const auto source = o.from.empty() ? std::optional<std::string_view>() : std::optional<std::string_view>(o.from);
    const stargan::continuous_control& control = *t.control;
    std::vector<clip> clips{in};
    for (auto& c : stargan::transfer_capture_points(control, in, points, source, co)) clips.push_back(std::move(c));
    viewer_options vo;
    vo.titles.push_back("input");
    for (const auto& [v, a] : points) {
        char b[64];
        std::snprintf(b, sizeof b, "valence %.2f arousal %.2f", v, a);
        vo.titles.push_back(b);
    }
    viewer_va_grid g;
    g.first = 1;
    g.n = o.grid;
    g.points = points;
    const auto& labels = control.interpolation().labels();  // the model's, neutral first
    g.labels.push_back(labels[control.interpolation().neutral()]);
    for (std::size_t i = 0; i < labels.size(); ++i)
        if (i != control.interpolation().neutral()) g.labels.push_back(labels[i]);
    vo.va_grid = std::move(g);
    vo.page_title = "handemo transfer: " + std::filesystem::path(o.in).filename().string() + " over the circumplex";
    write_file_atomic(o.out, render_viewer_html(clips, vo));
    std::cout << "transfer: " << o.in << " (" << in.frames << " frames) -> " << t.title << " (" << points.size()
              << " points in the unit disc) -> " << o.out << "\n";
}

/// --in DIR: every .bvh of the folder (not its subfolders), sorted by name, to --out DIR under the same name.
/// With an emotion target the threads take the files in batches of up to 32 and run G once per batch.
/// Threads take files in turn; each output is written atomically; a failure is printed with the file's name and
/// the rest go on; at the end, the files per second, and an error when any failed.
inline void run_folder(const transfer_cli& o, const stargan::emotion_model& model, const transfer_target& target)
{
    namespace fs = std::filesystem;
    if (has_ext(o.out, ".bvh", ".bmp") || has_ext(o.out, ".png"))
        throw value_error("transfer: --in " + o.in + " is a folder: --out must be a folder too, not " + o.out);
    if (!o.like.empty() || o.frames) throw value_error("transfer: --like and --frames are for a motion image input, not a folder");
    if (!o.filmstrip.empty()) throw value_error("transfer: --filmstrip draws one input: --in " + o.in + " is a folder");
    if (o.detail && !model.has_detail())
        throw value_error("transfer: --detail: model " + model.info().source + " has no detail layer (trained before it existed): train it again");
    if (!o.from.empty()) model.domain(o.from);
    std::vector<fs::path> files;
    for (const auto& e : regular_files_in(o.in))
        if (e.extension() == ".bvh") files.push_back(e);
    std::sort(files.begin(), files.end());
    if (files.empty()) throw value_error("transfer: --in " + o.in + " holds no .bvh file");
    if (path_exists(o.out) && !is_folder(o.out)) throw value_error("transfer: --out " + o.out + " exists and is not a folder");
    make_directories(o.out);
    const std::size_t threads = std::clamp<std::size_t>(o.threads ? o.threads : std::thread::hardware_concurrency(), 1, files.size());
    // an emotion target: each thread takes the files in batches and runs G once per batch (transfer_capture_batch,
    // the same bytes as file by file); a continuous target (a point, a path, a curve) goes file by file
    const bool batched = !target.control;
    const std::size_t batch = batched ? std::clamp<std::size_t>((files.size() + threads - 1) / threads, 1, 32) : 1;
    const auto source = o.from.empty() ? std::optional<std::string_view>() : std::optional<std::string_view>(o.from);
    std::atomic<std::size_t> next{0};
    std::mutex m;  // guards the progress bar, the failure list and std::cout
    std::vector<std::string> failed;
    std::size_t done = 0;
    // the run's report (progress, skipped files) goes to stdout: stderr keeps the one error line of a failure
    progress bar("transfer " + std::to_string(files.size()) + " files", static_cast<long>(files.size()), stdout);
    const auto start = std::chrono::steady_clock::now();
    const auto work = [&] {
        std::optional<stargan::emotion_model::batch_workspace> ws;  // this thread's
        if (batched) ws = model.make_batch_workspace(batch);
        std::vector<clip> clips;
        std::vector<stargan::capture_options> options;
        std::vector<std::size_t> which;
        std::vector<stargan::capture_result> results;
        for (std::size_t first = next.fetch_add(batch); first < files.size(); first = next.fetch_add(batch)) {
            const std::size_t end = std::min(files.size(), first + batch);
            std::vector<std::string> error(end - first);
            const auto write = [&](std::size_t i, const stargan::capture_result& cr) {
                try {
                    write_bvh(fs::path(o.out) / files[i].filename(), cr.motion, cr.retargeted ? -1 : 6);
                } catch (const std::exception& e) {
                    error[i - first] = e.what();
                }
            };
            if (batched) {
                clips.clear(), options.clear(), which.clear();
                for (std::size_t i = first; i < end; ++i) {
                    try {
                        clip in = read_bvh(files[i]);
                        options.push_back(capture_options_of(o, in));
                        clips.push_back(std::move(in));
                        which.push_back(i);
                    } catch (const std::exception& e) {
                        error[i - first] = e.what();
                    }
                }
                results.assign(clips.size(), {});
                const auto errors = stargan::transfer_capture_batch(model, clips, o.emotion, source, options, *ws, results);
                for (std::size_t k = 0; k < clips.size(); ++k) {
                    if (errors[k].empty()) write(which[k], results[k]);
                    else error[which[k] - first] = errors[k];
                }
            } else {
                for (std::size_t i = first; i < end; ++i) {
                    try {
                        const clip in = read_bvh(files[i]);
                        write(i, transfer_one(o, model, target, in, capture_options_of(o, in)));
                    } catch (const std::exception& e) {
                        error[i - first] = e.what();
                    }
                }
            }
            const std::lock_guard lock(m);
            for (std::size_t i = first; i < end; ++i) {
                if (!error[i - first].empty()) {
                    failed.push_back(files[i].filename().string());
                    std::cout << "transfer: " << files[i].string() << ": " << error[i - first] << " (skipped)" << std::endl;
                }
                bar.update(static_cast<long>(++done));
            }
        }
    };
    std::vector<std::thread> pool;
    for (std::size_t k = 1; k < threads; ++k) pool.emplace_back(work);
    work();
    for (auto& th : pool) th.join();
    bar.finish();
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::cout << "transfer: " << files.size() - failed.size() << " of " << files.size() << " files of " << o.in << " -> " << target.title << " -> "
              << o.out << " (" << threads << " threads, "
              << (batched && !model.uses_generator(o.emotion)
                      ? "G not run: the gate of " + o.emotion + " keeps none of its change, "
                  : batched ? "G on batches of " + std::to_string(batch) + " files" +
                                  (model.conv_algorithm() == kernels::conv_algorithm::winograd ? " (residual convolutions by Winograd), " : ", ")
                            : std::string())
              << static_cast<double>(files.size()) / std::max(seconds, 1e-9) << " files/s)\n";
    if (!failed.empty()) {
        std::string names;
        for (std::size_t i = 0; i < failed.size() && i < 5; ++i) names += (i ? ", " : "") + failed[i];
        throw value_error("transfer: " + std::to_string(failed.size()) + " of " + std::to_string(files.size()) + " files failed (" + names +
                          (failed.size() > 5 ? ", ..." : "") + "); the others were written to " + o.out);
    }
}

inline void run_transfer(const transfer_cli& o)
{
    using namespace handemo;
    using namespace handemo::stargan;
    namespace fs = std::filesystem;
    const std::string model_path = o.model.empty() ? default_model().string() : o.model;
    if (o.model.empty())
        std::cout << "transfer: no --model given: using the shipped hand model " << model_path
                  << " (trained on handemo's synthetic hand emotions, not on real captures)\n";
    const auto model = load_model(model_path, o.weights, o.conv);
    const auto& info = model->info();
    const transfer_target target = target_of(o, *model);
    if (is_folder(o.in)) {
        if (o.grid) throw value_error("transfer: --grid shows one input: --in " + o.in + " is a folder");
        run_folder(o, *model, target);
        return;
    }
    if (o.threads) throw value_error("transfer: --threads is for a folder --in (" + o.in + " is a file)");
    if (o.grid) {
        if (!has_ext(o.in, ".bvh")) throw value_error("transfer: --grid: --in " + o.in + ": expected a .bvh file");
        if (!o.filmstrip.empty()) throw value_error("transfer: --filmstrip draws the points of a --path, not a --grid");
        const clip in = read_bvh(o.in);
        write_grid_view(o, target, in, capture_options_of(o, in));
        return;
    }
    const bool in_image = has_ext(o.in, ".bmp", ".png"), out_image = has_ext(o.out, ".bmp", ".png");
    if (!in_image && !has_ext(o.in, ".bvh"))
        throw value_error("transfer: --in " + o.in + ": expected a .bvh, .bmp or .png file");
    if (!out_image && !has_ext(o.out, ".bvh")) throw value_error("transfer: --out " + o.out + ": expected a .bvh, .bmp or .png file");
    if (target.control && (in_image || out_image))
        throw value_error("transfer: a continuous target blends full-rate motions: --in and --out must be .bvh files (" +
                          (in_image ? o.in : o.out) + " is a motion image)");
    if (in_image) {
        // the image's keyframes (Eq. 6) through every step a BVH input's keyframes take (transfer_keyframes())
        const auto px = from_image<dynamic_keyframes>(read_image(o.in), model->joints(), model->keyframes(), o.in);
        const std::optional<std::string_view> from = o.from.empty() ? std::nullopt : std::optional<std::string_view>(o.from);
        if (!out_image && o.like.empty())
            throw value_error("transfer: a BVH output from an image input needs --like REF.bvh (skeleton, fps, frames)");
        const auto kf = model->transfer_keyframes(decode(px, info.range), o.emotion, from);
        if (out_image) {
            (has_ext(o.out, ".png") ? write_png : write_bmp)(o.out, to_image(encode(kf, info.range)));
        } else {
            const clip ref = read_bvh(o.like);
            model->check_skeleton(ref.skel);
            const double tempo = model->tempo(o.emotion, from);
            const std::size_t n = o.frames ? o.frames : model->output_frames(ref.frames, tempo);
            write_bvh(o.out, reconstruct(kf, ref.skel, n, ref.fps));
        }
        std::cout << "transfer: " << o.in << " -> " << o.emotion << " -> " << o.out << "\n";
        return;
    }
    const clip in = read_bvh(o.in);
    if (o.detail && out_image) throw value_error("transfer: --detail adds full-rate motion; a motion image output (" + o.out + ") has none");
    if (o.detail && !model->has_detail())
        throw value_error("transfer: --detail: model " + model_path + " has no detail layer (trained before it existed): train it again");
    const auto co = capture_options_of(o, in);
    if (!o.filmstrip.empty() && o.path.empty()) throw value_error("transfer: --filmstrip draws the points of a --path");
    const auto cr = transfer_one(o, *model, target, in, co);
    if (cr.map) print_map_summary("transfer", o.in, *cr.map);
    const auto& r = cr.on_model;
    if (out_image)
        (has_ext(o.out, ".png") ? write_png : write_bmp)(o.out, to_image(r.image));
    else
        write_bvh(o.out, cr.motion, cr.retargeted ? -1 : 6);
    if (r.clamped_values)
        std::cerr << "transfer: warning: " << r.clamped_values << " keyframe angles of " << o.in
                  << " lie outside the model's range ("
                  << (info.range.per_channel() ? std::string("the training data's, per channel")
                                               : "[" + std::to_string(info.range.p_min) + ", " + std::to_string(info.range.p_max) + "]")
                  << ") and reached G clamped by Eq. 3"
                  << (model->residual() ? " (the output adds G's change to the unclamped angles)" : " (the output is G's image)") << "\n";
    if (r.limited_values)
        std::cerr << "transfer: note: " << r.limited_values << " output keyframe angles were held at the joint limits of the model's skeleton\n";
    std::string weights;
    if (target.point) {  // the labels the point blends, in the model's domain order
        const auto w = target.control->weights(target.point->first, target.point->second);
        char b[64];
        for (std::size_t d = 0; d < w.size(); ++d)
            if (w[d] != 0) {
                std::snprintf(b, sizeof b, "%s%s %.3f", weights.empty() ? ", weights " : " ", info.domains[d].c_str(), w[d]);
                weights += b;
            }
    }
    std::string lag;
    if (!target.point && !target.curve && !o.emotion.empty()) {  // a discrete target: the joint lag it applies, if any
        std::vector<double> l;
        model->lag_of(model->domain(o.emotion), o.from.empty() ? std::optional<std::string_view>() : std::optional<std::string_view>(o.from), l);
        double most = 0;
        for (double v : l) most = std::max(most, std::abs(v));
        if (most > 0) {
            char b[80];
            std::snprintf(b, sizeof b, ", joint lag up to %.3g keyframes", most);
            lag = b;
        }
    }
    const bool no_g = !target.point && !target.curve && !o.emotion.empty() && !model->uses_generator(o.emotion);
    std::cout << "transfer: " << o.in << " (" << in.frames << " frames) -> " << target.title << " (tempo x" << r.tempo << ", "
              << cr.motion.frames << " frames" << (o.detail ? ", with detail" : "") << lag << weights
              << (no_g ? ", G not run: the gate keeps none of its change" : "") << ") -> " << o.out << "\n";
    if (!o.filmstrip.empty()) write_path_filmstrip(o, target, in, co);
}

}  // namespace handemo::cli::transfer_cmd

static handemo::cli::add_command reg_transfer{50, [](CLI::App& app) {
    auto* sub = app.add_subcommand("transfer", "Turn a motion (BVH, or a motion image BMP/PNG) into another emotion with a trained model");
    auto o = std::make_shared<handemo::cli::transfer_cmd::transfer_cli>();
    sub->add_option("--model", o->model,
                    "Model folder or checkpoint.safetensors written by 'handemo train' (default: the shipped hand model, trained on "
                    "handemo's synthetic hand emotions)");
    sub->add_option("--in", o->in, "Input motion: .bvh, a K x J motion image .bmp/.png (its keyframes, Eq. 6, take the same steps as a BVH's), or a folder "
                                      "(its .bvh files)")->required();
    sub->add_option("--emotion", o->emotion, "Target emotion (a domain of the model, e.g. angry); or one of the continuous targets below");
    sub->add_option("--valence", o->valence, "Continuous target: valence of a point of the circumplex (with --arousal; V^2 + A^2 <= 1)");
    sub->add_option("--arousal", o->arousal, "Continuous target: arousal of the point (with --valence)");
    sub->add_option("--path", o->path,
                    "Continuous target moving over the clip: waypoints, comma separated, labels (neutral,sad,angry) or points V:A; "
                    "write --path=-0.5:0.2,... when the first starts with '-'");
    sub->add_option("--duration", o->duration, "Seconds the --path takes from the clip's first frame (default: to its last); held after");
    sub->add_option("--curve", o->curve, "Continuous target moving over the clip: a file of time,valence,arousal rows (seconds; linear between rows)");
    sub->add_option("--filmstrip", o->filmstrip,
                    "With --path: also draw a filmstrip (.png/.bmp), the input then one column per point of the path, each with its "
                    "point on a small circumplex");
    sub->add_option("--grid", o->grid,
                    "Continuous targets over the whole circumplex: the transfers at the points of an N x N grid in the unit disc "
                    "(3..101), written into one viewer page (--out view.html) whose V/A dial picks the output played");
    sub->add_option("--steps", o->steps, "Columns of the --filmstrip per path segment (each waypoint is a column)")->capture_default_str();
    sub->add_option("--rows", o->rows, "Frames per column of the --filmstrip")->capture_default_str();
    sub->add_option("--circumplex", o->circumplex, "The labels' circumplex coordinates (default: the shipped data/rcm/circumplex.json)");
    sub->add_option("--rate-blend", o->rate_blend,
                    "With a continuous target: how the labels' tempo and amplitude factors are blended between their points, linear "
                    "or geometric (in log space: halfway to a label twice as slow is sqrt(2) times as slow); default linear");
    sub->add_option("--out", o->out,
                    "Output: .bvh (full-rate motion), .bmp/.png (the output's motion image: the keyframes the .bvh would pass through), "
                    "a folder for a folder --in, or .html for --grid")->required();
    sub->add_option("--threads", o->threads, "Threads for a folder --in, sharing the one loaded model (default: the machine's cores)");
    sub->add_option("--hand", o->hand, "Which hand of the capture to transfer with a hand model: left or right (needed when it has two)")
        ->check(CLI::IsMember({"left", "right"}));
    sub->add_option("--map", o->map, "JSON map file naming the capture's joints by slot, for a rig no built-in convention knows (docs/retargeting.md)");
    sub->add_option("--from", o->from, "Emotion of the input (default: the model's neutral domain); sets the tempo ratio");
    sub->add_option("--like", o->like, "Reference BVH for an image input and BVH output (skeleton, fps, frames)");
    sub->add_flag("--detail", o->detail,
                  "Add the detail layer: the input's own full-rate detail (what 9 keyframes miss), at the target emotion's "
                  "amplitude and frequency learned from the training clips; the keyframes stay as they are");
    sub->add_option("--frames", o->frames, "Output frame count for an image input (default: the reference's times the tempo)");
    handemo::cli::add_inference_weights_option(sub, o->weights,
                                               "G's convolution weights as trained, or rounded to IEEE binary16 (half the "
                                               "bytes per inference; README, Performance)");
    handemo::cli::add_conv_algorithm_option(sub, o->conv,
                                            "how G computes its residual 3x3 convolutions: directly, or by Winograd's F(3x2, 3x3) "
                                            "(faster on a folder's batches; the motion differs from direct's in the last bits; "
                                            "docs/engine.md)");
    sub->callback([o] { handemo::cli::transfer_cmd::run_transfer(*o); });
}};
