// `handemo glove record --glove senso|opengloves|5dt|P.json [--device ID|--replay FILE] --out take.bvh [--seconds N] [--raw raw.bin]`:
// records the glove into a BVH of the 23-joint hand at a steady frame rate, with a live line (duration,
// sample rate, dropped and malformed reports); Ctrl-C ends cleanly and the file is complete.
#pragma once

#include "common.hpp"

#include <iostream>

namespace handemo::cli::glove_cmd {

struct record_cli {
    source_options src;
    std::string out, raw;
    double seconds = 0, fps = 60, flush = 1;
};

inline void run_record(const record_cli& o)
{
    const auto c = o.src.choice();
    const auto& p = c.profile;
    std::optional<glove_calibration> calib;
    if (!o.src.calib.empty()) calib = read_glove_calibration(o.src.calib, p);
    auto t = open_source(o.src, c);
    if (!calib && !p.imus.empty()) std::cerr << "glove: no --calib: hold the hand flat for the first 0.5 s\n";
    record_options ro;
    ro.fps = o.fps, ro.seconds = o.seconds, ro.out = o.out, ro.raw = o.raw, ro.flush_seconds = o.flush;
    ro.reconnect_window = o.src.replay.empty() ? o.src.reconnect : 1;  // a replay reconnects where the recording did
    glove_recorder rec(*t, make_decoder(c), calib, ro);
    warning_printer warn;
    rec.on_warning = [&](const std::string& w) { warn(w); };
    catch_interrupt();
    status_line line;
    while (!interrupted() && rec.step()) line.update(rec.stats());
    line.update(rec.stats(), {}, true);
    line.end();
    rec.flush();
    const auto s = rec.stats();
    if (s.samples == 0 || rec.extent().first == 0)
        throw device_error("glove record: " + t->name() + ": no complete samples in " + std::to_string(s.reports) + " reports (" +
                           std::to_string(s.malformed) + " malformed" + fault_summary(s) + "); nothing written");
    std::printf("glove record: %zu samples (%.2f s, %.1f Hz) -> %s: %zu frames at %g fps; dropped reports %zu, malformed %zu%s, "
                "frames in gaps %zu, timeouts %zu, reconnects %zu, overruns %zu%s\n",
                s.samples, s.duration, s.rate_hz, o.out.c_str(), s.frames, o.fps, s.dropped, s.malformed, fault_summary(s).c_str(), s.gap_frames,
                s.timeouts, s.reconnects, s.overruns, interrupted() ? " (interrupted)" : "");
}

inline void add_record(CLI::App* glove)
{
    auto* sub = glove->add_subcommand("record", "Record the glove into a BVH of the 23-joint hand (Ctrl-C ends cleanly)");
    auto o = std::make_shared<record_cli>();
    add_source_options(sub, o->src);
    sub->add_option("--out", o->out, "Output BVH (rewritten atomically every --flush seconds: always a valid file)")->required();
    sub->add_option("--seconds", o->seconds, "Stop after this many seconds of capture (default: until Ctrl-C or the end of the replay)");
    sub->add_option("--fps", o->fps, "Output frame rate (resampled from the device's timestamps)")->capture_default_str();
    sub->add_option("--raw", o->raw, "Also save every report as a raw stream (replay it with --replay)");
    sub->add_option("--flush", o->flush, "Seconds between rewrites of the BVH")->capture_default_str();
    sub->callback([o] { run_record(*o); });
}

}  // namespace handemo::cli::glove_cmd
