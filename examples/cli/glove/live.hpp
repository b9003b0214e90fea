// `handemo glove live --model MODEL --emotion E --glove senso|opengloves|5dt|P.json [--device ID|--replay FILE] [--window S]
// [--every S] (--out rolling.bvh | --print)`: the last --window seconds of the glove are transferred to
// emotion E every --every seconds (stargan load_model(...)->transfer(clip, E)) and written as a rolling
// BVH (atomically replaced) or printed as joint angles, with the latency from the newest report's arrival
// to the output. A device is read on the reader thread, which keeps reading (and stamping arrivals) while a
// window is transferred here.
#pragma once

#include "common.hpp"

#include <handemo/stargan/transfer.hpp>

#include <filesystem>
#include <iostream>
#include <memory>

namespace handemo::cli {
/// Defined in cmd_stargan.cpp, which already compiles every generator configuration.
std::unique_ptr<stargan::emotion_model> load_emotion_model(const std::filesystem::path& path);
}  // namespace handemo::cli

namespace handemo::cli::glove_cmd {

struct live_cli {
    source_options src;
    std::string model, emotion, out;
    bool print = false;
    double window = 2, every = 0.5, seconds = 0, fps = 60;
};

inline void run_live(const live_cli& o)
{
    if (o.out.empty() && !o.print) throw value_error("glove live: give --out rolling.bvh or --print");
    if (!(o.window > 0.2)) throw value_error("glove live: --window " + std::to_string(o.window) + " s is too short (at least 0.2 s)");
    const auto model = load_emotion_model(o.model);
    (void)model->domain(o.emotion);  // an unknown emotion fails now, not after the first window
    const auto c = o.src.choice();
    const auto& p = c.profile;
    std::optional<glove_calibration> calib;
    if (!o.src.calib.empty()) calib = read_glove_calibration(o.src.calib, p);
    auto t = open_source(o.src, c);
    record_options ro;
    ro.fps = o.fps, ro.seconds = o.seconds, ro.keep_seconds = o.window;
    ro.reconnect_window = o.src.replay.empty() ? o.src.reconnect : 1;
    glove_recorder rec(*t, make_decoder(c), calib, ro);
    warning_printer warn;
    rec.on_warning = [&](const std::string& w) { warn(w); };
    catch_interrupt();
    status_line line;
    double last_out = -1e9, newest_arrival = 0, worst = 0, sum = 0;
    std::size_t outputs = 0, seen = 0;
    while (!interrupted() && rec.step()) {
        const auto s = rec.stats();
        // the newest report's arrival: stamped by the reader thread, else (a replay) when it was seen here
        if (s.samples != seen) seen = s.samples, newest_arrival = s.last_arrival > 0 ? s.last_arrival : host_seconds();
        const auto [poses, span] = rec.extent();
        if (poses < 2 || s.duration - last_out < o.every || span < o.window * 0.5) {
            line.update(s);
            continue;
        }
        last_out = s.duration;
        const clip window = rec.take(o.window);
        const auto r = model->transfer(window, o.emotion);
        if (!o.out.empty()) write_bvh(o.out, r.motion);
        const double latency = host_seconds() - newest_arrival;
        worst = std::max(worst, latency), sum += latency, ++outputs;
        if (o.print) {
            const double* a = r.motion.frame_angles(r.motion.frames - 1);
            std::printf("t=%.2f latency=%.1fms", s.duration, latency * 1000);
            for (std::size_t j = 0; j < r.motion.joint_count(); ++j)
                std::printf(" %s=%.1f,%.1f,%.1f", r.motion.skel.joints[j].name.c_str(), a[j * 3], a[j * 3 + 1], a[j * 3 + 2]);
            std::printf("\n");
            std::fflush(stdout);
        }
        char extra[96];
        std::snprintf(extra, sizeof extra, "  -> %s  latency %.1f ms", o.emotion.c_str(), latency * 1000);
        line.update(s, extra, true);
    }
    line.end();
    const auto s = rec.stats();
    std::printf("glove live: %zu windows of %.1f s transferred to %s%s%s; latency from report to output mean %.1f ms, worst %.1f ms; "
                "%zu samples, dropped %zu, malformed %zu%s, overruns %zu\n",
                outputs, o.window, o.emotion.c_str(), o.out.empty() ? "" : " -> ", o.out.c_str(), outputs ? sum / static_cast<double>(outputs) * 1000 : 0.0,
                worst * 1000, s.samples, s.dropped, s.malformed, fault_summary(s).c_str(), s.overruns);
    if (outputs == 0) throw device_error("glove live: " + t->name() + ": not enough samples for one window of " + std::to_string(o.window) + " s");
}

inline void add_live(CLI::App* glove)
{
    auto* sub = glove->add_subcommand("live", "Transfer a sliding window of the glove to an emotion as it is captured (rolling BVH or joint angles)");
    auto o = std::make_shared<live_cli>();
    add_source_options(sub, o->src);
    sub->add_option("--model", o->model, "Model folder or checkpoint written by 'handemo train'")->required();
    sub->add_option("--emotion", o->emotion, "Target emotion")->required();
    sub->add_option("--out", o->out, "Rolling BVH, replaced atomically after every transfer");
    sub->add_flag("--print", o->print, "Print the newest output frame's joint angles (degrees) instead of / besides --out");
    sub->add_option("--window", o->window, "Seconds of the sliding window")->capture_default_str();
    sub->add_option("--every", o->every, "Seconds between transfers")->capture_default_str();
    sub->add_option("--seconds", o->seconds, "Stop after this many seconds of capture")->capture_default_str();
    sub->add_option("--fps", o->fps, "Frame rate of the window clip")->capture_default_str();
    sub->callback([o] { run_live(*o); });
}

}  // namespace handemo::cli::glove_cmd
