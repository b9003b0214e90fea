// Shared parts of the `handemo glove` subcommands: choosing the glove (--glove), opening its transport (TCP,
// serial, HID device, replay file) behind the reader thread, Ctrl-C, the live status line and the warning
// printer.
#pragma once

#include <handemo/glove.hpp>
#ifdef HANDEMO_HAVE_HIDAPI
#include <handemo/glove/hid.hpp>
#endif

#include <CLI/CLI.hpp>

#include <atomic>
#include <csignal>
#include <cstdio>
#include <memory>
#include <optional>
#include <string>
#include <unistd.h>

namespace handemo::cli::glove_cmd {

/// Options every reading subcommand has.
struct source_options {
    std::string glove, device, replay, calib, hand = "right";
    bool realtime = false;
    double reconnect = 5;
    int sensors = 14, baud = 115200, analog_max = 4095;
    glove_choice choice() const { return choose_glove(glove, hand_side_from_string(hand), sensors, analog_max); }
};

inline const char* glove_help()
{
    return "Glove: senso (Senso server, JSON lines over TCP), opengloves (OpenGloves/LucidGloves alpha encoding over serial), "
           "5dt (5DT Data Glove Ultra, USB HID) or a HID profile (JSON, e.g. examples/glove/imu7_example.json)";
}

/// --hand, --sensors, --baud, --analog-max: the settings of the glove families.
inline void add_glove_settings(CLI::App* sub, source_options& o)
{
    sub->add_option("--hand", o.hand, "Which hand the glove is on (senso: which hand's packets; 5dt: which product id)")
        ->check(CLI::IsMember({"right", "left"}))
        ->capture_default_str();
    sub->add_option("--sensors", o.sensors, "5dt: the model, 5 or 14 sensors")->check(CLI::IsMember({5, 14}))->capture_default_str();
    sub->add_option("--analog-max", o.analog_max, "opengloves: the firmware's largest analog value, 1023 or 4095")
        ->check(CLI::IsMember({1023, 4095}))
        ->capture_default_str();
}

inline void add_source_options(CLI::App* sub, source_options& o, bool calib = true)
{
    sub->add_option("--glove", o.glove, glove_help())->required();
    auto* dev = sub->add_option("--device", o.device,
                                "senso: HOST:PORT of its server (default 127.0.0.1:53450); opengloves: a serial port such as /dev/ttyUSB0 or "
                                "/dev/rfcomm0; HID gloves: VVVV:PPPP (hex) or a path such as /dev/hidraw3 (default: the profile's ids)");
    sub->add_option("--replay", o.replay, "Read a raw report stream (written by --raw or 'glove simulate') instead of a device")->excludes(dev);
    sub->add_flag("--realtime", o.realtime, "Replay at the recorded pace instead of as fast as possible");
    sub->add_option("--reconnect", o.reconnect, "Seconds to keep trying to reopen a disconnected device (0: stop)")->capture_default_str();
    sub->add_option("--baud", o.baud, "opengloves: the serial port's baud rate (8N1)")->capture_default_str();
    add_glove_settings(sub, o);
    if (calib) sub->add_option("--calib", o.calib, "Calibration written by 'handemo glove calibrate' (default: IMU gloves take the first 0.5 s as the flat hand, flex gloves the nominal values)");
}

/// Opens the device itself (no reader thread).
inline std::unique_ptr<glove_transport> open_device(const source_options& o, const glove_choice& c)
{
    std::string spec = o.device.empty() ? c.default_device : o.device;
    switch (c.link) {
    case glove_link::tcp: return std::make_unique<tcp_transport>(spec);
    case glove_link::serial:
        if (spec.empty()) throw value_error("glove: --glove " + c.kind + " reads a serial port: give --device /dev/ttyUSB0 (see 'handemo glove list'), or --replay FILE");
        return std::make_unique<serial_transport>(spec, o.baud);
    default: break;
    }
    const auto& p = c.profile;
    if (spec.empty()) {
        if (!p.vendor_id || !p.product_id || (*p.vendor_id == 0 && *p.product_id == 0))
            throw value_error("glove: profile '" + p.name + "' has no vendor/product id: give --device VVVV:PPPP or a path (see 'handemo glove list'), or --replay FILE");
        char b[16];
        std::snprintf(b, sizeof b, "%04x:%04x", *p.vendor_id, *p.product_id);
        spec = b;
    }
#ifdef HANDEMO_HAVE_HIDAPI
    std::size_t max_report = 64;
    for (const auto& r : p.reports) max_report = std::max(max_report, r.size);
    return std::make_unique<hid_transport>(spec, p.init_features, max_report + 1);
#else
    throw device_error("glove: HID device " + spec + ": this handemo was built without hidapi (libhidapi-dev); --replay FILE still works");
#endif
}

/// A device, or a replay at the recorded pace (--realtime), behind the reader thread; a replay as fast as it
/// is read without one (a queue would only overflow).
inline std::unique_ptr<glove_transport> open_source(const source_options& o, const glove_choice& c)
{
    std::unique_ptr<glove_transport> t;
    if (!o.replay.empty()) {
        auto r = std::make_unique<replay_transport>(o.replay, o.realtime);
        if (r->truncated() >= 0)
            std::fprintf(stderr, "glove: warning: %s: the last record (at byte %ld) is truncated and ignored\n", o.replay.c_str(), r->truncated());
        if (!o.realtime) return r;
        t = std::move(r);
    } else {
        t = open_device(o, c);
    }
    reader_options ro;
    ro.reconnect_window = o.replay.empty() ? o.reconnect : 1;
    return std::make_unique<glove_reader>(std::move(t), ro);
}

inline std::atomic<bool>& interrupted()
{
    static std::atomic<bool> flag{false};
    return flag;
}

/// Ctrl-C (and SIGTERM) ends a recording cleanly: the loop stops and the file is written.
inline void catch_interrupt()
{
    interrupted() = false;
    auto h = [](int) { interrupted() = true; };
    std::signal(SIGINT, h);
    std::signal(SIGTERM, h);
}

/// Prints warnings, the first 20 in full, then one line per 100.
struct warning_printer {
    std::size_t n = 0;
    void operator()(const std::string& w)
    {
        ++n;
        if (n <= 20) std::fprintf(stderr, "glove: warning: %s\n", w.c_str());
        else if (n % 100 == 0) std::fprintf(stderr, "glove: warning: %zu warnings so far (latest: %s)\n", n, w.c_str());
    }
};

/// The live line: redrawn on a terminal, a line a second otherwise.
class status_line {
public:
    status_line() : tty_(::isatty(::fileno(stderr)) != 0) {}
    void update(const record_stats& s, const std::string& extra = {}, bool force = false)
    {
        const double now = host_seconds();
        if (!force && now - last_ < (tty_ ? 0.2 : 1.0)) return;
        last_ = now;
        std::fprintf(stderr, "%sglove: %6.1f s  %6.1f Hz  %zu samples  dropped %zu  malformed %zu  overruns %zu%s%s", tty_ ? "\r\033[K" : "",
                     s.duration, s.rate_hz, s.samples, s.dropped, s.malformed, s.overruns, extra.c_str(), tty_ ? "" : "\n");
        std::fflush(stderr);
        drawn_ = true;
    }
    void end()
    {
        if (tty_ && drawn_) std::fputc('\n', stderr);
    }

private:
    bool tty_;
    bool drawn_ = false;
    double last_ = -1e9;
};

inline std::string fault_summary(const record_stats& s)
{
    std::string r;
    for (std::size_t f = 1; f < report_fault_count; ++f)
        if (s.faults[f]) r += (r.empty() ? "" : ", ") + std::string(to_string(static_cast<report_fault>(f))) + " " + std::to_string(s.faults[f]);
    return r.empty() ? "" : " (" + r + ")";
}

}  // namespace handemo::cli::glove_cmd
