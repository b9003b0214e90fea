// `handemo glove send --glove senso|opengloves [--device ID] (--vibrate FINGER,MS,STRENGTH | --force-feedback
// T,I,M,R,P | --haptics HZ,S,AMPLITUDE)`: one command to the glove. Senso vibrates a finger (the glove's
// address is `--to`, else taken from its first position packet of `--hand`); OpenGloves takes force
// feedback per finger (0 free .. 1 locked) or a haptic pulse. The values are checked before the device is
// opened.
#pragma once

#include "common.hpp"

#include <array>
#include <sstream>
#include <string>
#include <vector>

namespace handemo::cli::glove_cmd {

struct send_cli {
    source_options src;
    std::string vibrate, force, haptics, to;
};

/// Splits "a,b,c" into exactly `n` fields. @throws value_error naming the option.
inline std::vector<std::string> split_fields(const std::string& s, std::size_t n, const std::string& option)
{
    std::vector<std::string> out;
    std::stringstream in(s);
    for (std::string f; std::getline(in, f, ',');) out.push_back(f);
    if (out.size() != n) throw value_error("glove send: " + option + " '" + s + "' is not " + std::to_string(n) + " comma-separated values");
    return out;
}

inline double number_field(const std::string& f, const std::string& option)
{
    try {
        std::size_t used = 0;
        const double v = std::stod(f, &used);
        if (used == f.size()) return v;
    } catch (...) {
    }
    throw value_error("glove send: " + option + ": '" + f + "' is not a number");
}

inline void run_send(const send_cli& o)
{
    const auto c = o.src.choice();
    const int given = !o.vibrate.empty() + !o.force.empty() + !o.haptics.empty();
    if (given != 1) throw value_error("glove send: give one of --vibrate (senso), --force-feedback or --haptics (opengloves)");
    std::string line;
    if (c.kind == "senso") {
        if (o.vibrate.empty()) throw value_error("glove send: --glove senso takes --vibrate FINGER,MS,STRENGTH");
        const auto f = split_fields(o.vibrate, 3, "--vibrate");
        const int ms = static_cast<int>(number_field(f[1], "--vibrate")), strength = static_cast<int>(number_field(f[2], "--vibrate"));
        line = senso_vibration(o.to.empty() ? "?" : o.to, f[0], ms, strength);  // checks the values now
        auto t = open_device(o.src, c);
        std::string to = o.to;
        if (to.empty()) {
            senso_decoder d(c.hand);
            glove_sample s;
            const double until = host_seconds() + 2;
            while (to.empty() && host_seconds() < until)
                if (const auto r = t->read(std::chrono::milliseconds(100)); r && d.decode(r->bytes, r->host_time, s).frame) to = d.last_packet().source;
            if (to.empty()) throw device_error("glove send: " + t->name() + ": no position packet of the " + std::string(to_string(c.hand)) + " hand in 2 s to learn the glove's address; give --to");
        }
        line = senso_vibration(to, f[0], ms, strength);
        t->write_text(line);
        std::printf("glove send: %s -> %s\n", line.substr(0, line.size() - 1).c_str(), t->name().c_str());
        return;
    }
    if (c.kind != "opengloves") throw value_error("glove send: --glove " + c.kind + " takes no commands (senso and opengloves do)");
    if (!o.force.empty()) {
        const auto f = split_fields(o.force, 5, "--force-feedback");
        std::array<double, 5> lock{};
        for (std::size_t k = 0; k < 5; ++k) lock[k] = number_field(f[k], "--force-feedback");
        line = opengloves_force_feedback(lock);
    } else if (!o.haptics.empty()) {
        const auto f = split_fields(o.haptics, 3, "--haptics");
        line = opengloves_haptics(number_field(f[0], "--haptics"), number_field(f[1], "--haptics"), number_field(f[2], "--haptics"));
    } else {
        throw value_error("glove send: --glove opengloves takes --force-feedback T,I,M,R,P or --haptics HZ,S,AMPLITUDE");
    }
    auto t = open_device(o.src, c);
    t->write_text(line);
    std::printf("glove send: %s -> %s\n", line.substr(0, line.size() - 1).c_str(), t->name().c_str());
}

inline void add_send(CLI::App* glove)
{
    auto* sub = glove->add_subcommand("send", "Send one command to the glove: Senso vibration, OpenGloves force feedback or a haptic pulse");
    auto o = std::make_shared<send_cli>();
    sub->add_option("--glove", o->src.glove, "Glove: senso or opengloves")->required();
    sub->add_option("--device", o->src.device, "senso: HOST:PORT of its server (default 127.0.0.1:53450); opengloves: a serial port such as /dev/ttyUSB0");
    sub->add_option("--baud", o->src.baud, "opengloves: the serial port's baud rate (8N1)")->capture_default_str();
    add_glove_settings(sub, o->src);
    sub->add_option("--vibrate", o->vibrate, "senso: FINGER,MS,STRENGTH (thumb..pinky, 0..65535 ms, 0..10)");
    sub->add_option("--to", o->to, "senso: the glove's address (default: from its first position packet)");
    sub->add_option("--force-feedback", o->force, "opengloves: T,I,M,R,P per finger, 0 free .. 1 locked");
    sub->add_option("--haptics", o->haptics, "opengloves: HZ,SECONDS,AMPLITUDE (amplitude 0..1)");
    sub->callback([o] { run_send(*o); });
}

}  // namespace handemo::cli::glove_cmd
