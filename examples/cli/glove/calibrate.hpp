// `handemo glove calibrate --glove senso|opengloves|5dt|P.json [--device ID|--replay FILE] --out calib.json [--hold S] [--settle S]`:
// the flat-hand pose (every glove) and a fist (flex gloves), each held for --hold seconds after --settle
// seconds to get there; from a replay, the first --hold seconds are the flat hand and the next the fist.
#pragma once

#include "common.hpp"

#include <iostream>
#include <thread>

namespace handemo::cli::glove_cmd {

struct calibrate_cli {
    source_options src;
    std::string out;
    double hold = 1, settle = 2;
};

/// Collects the complete samples of `seconds` (sample time) after skipping `settle` seconds (host time, live
/// only). The sample that ends a window is carried into the next one (a replay's poses follow each other).
inline std::vector<glove_sample> collect(glove_transport& t, glove_decoder& d, double seconds, double settle, std::size_t& malformed,
                                         std::optional<glove_sample>& carry)
{
    const double skip_until = host_seconds() + settle;
    std::vector<glove_sample> out;
    if (carry && settle <= 0) out.push_back(*carry);
    carry.reset();
    glove_sample s;
    while (!interrupted() && !t.finished()) {
        const auto r = t.read(std::chrono::milliseconds(100));
        if (!r) continue;
        const auto res = d.decode(r->bytes, r->host_time, s);
        if (res.fault != report_fault::none) {
            if (++malformed <= 20) std::cerr << "glove: warning: report skipped: " << res.message << "\n";
            continue;
        }
        if (!res.frame || host_seconds() < skip_until) continue;
        if (!out.empty() && s.time() - out.front().time() >= seconds - 1e-9) {
            carry = s;
            break;
        }
        out.push_back(s);
    }
    return out;
}

inline void run_calibrate(const calibrate_cli& o)
{
    const auto choice = o.src.choice();
    const auto& p = choice.profile;
    auto t = open_source(o.src, choice);
    const bool live = o.src.replay.empty();
    const double settle = live ? o.settle : 0;
    const auto decoder = make_decoder(choice);
    auto& d = *decoder;
    std::size_t malformed = 0;
    std::optional<glove_sample> carry;
    catch_interrupt();
    std::cerr << "glove calibrate: hold the hand flat (fingers straight and together, palm down)"
              << (live ? ", starting in " + std::to_string(static_cast<int>(settle)) + " s" : "") << "\n";
    const auto flat = collect(*t, d, o.hold, settle, malformed, carry);
    std::vector<glove_sample> fist;
    bool fist_needed = false;
    for (const auto* f : p.flexes) fist_needed = fist_needed || f->fist_calibrated;
    if (fist_needed) {
        std::cerr << "glove calibrate: make a fist" << (live ? ", starting in " + std::to_string(static_cast<int>(settle)) + " s" : "") << "\n";
        fist = collect(*t, d, o.hold, settle, malformed, carry);
        if (fist.empty()) throw device_error("glove calibrate: " + t->name() + ": no samples of the fist");
    }
    if (flat.empty()) throw device_error("glove calibrate: " + t->name() + ": no samples of the flat hand");
    const auto c = calibrate_glove(p, flat, fist);
    write_glove_calibration(o.out, c, p);
    std::printf("glove calibrate: %zu flat%s samples (%zu malformed reports skipped) -> %s\n", flat.size(),
                fist.empty() ? "" : (" and " + std::to_string(fist.size()) + " fist").c_str(), malformed, o.out.c_str());
}

inline void add_calibrate(CLI::App* glove)
{
    auto* sub = glove->add_subcommand("calibrate", "Calibrate from a flat hand (and a fist, for flex gloves)");
    auto o = std::make_shared<calibrate_cli>();
    add_source_options(sub, o->src, false);
    sub->add_option("--out", o->out, "Calibration file (JSON) for --calib")->required();
    sub->add_option("--hold", o->hold, "Seconds each pose is held")->capture_default_str();
    sub->add_option("--settle", o->settle, "Seconds to get into each pose before it is measured (live devices)")->capture_default_str();
    sub->callback([o] { run_calibrate(*o); });
}

}  // namespace handemo::cli::glove_cmd
