// One name per glove family, as `--glove` takes it: "senso" (JSON lines over TCP), "opengloves" (alpha
// encoding over serial), "5dt" (5DT Data Glove Ultra over USB HID) or the path of a JSON profile (any other
// HID glove). glove_choice says which decoder reads it and how it is reached by default.
#pragma once

#include <handemo/core/error.hpp>
#include <handemo/glove/fivedt.hpp>
#include <handemo/glove/opengloves.hpp>
#include <handemo/glove/profile.hpp>
#include <handemo/glove/senso.hpp>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace handemo {

/// How a glove family is reached.
enum class glove_link : std::uint8_t { hid, serial, tcp };

/// @brief A glove family and its settings.
struct glove_choice {
    std::string kind;             ///< "senso", "opengloves", "5dt" or "profile"
    glove_profile profile;        ///< its sensors (the decoder's profile)
    glove_link link = glove_link::hid;
    hand_side hand = hand_side::right;
    int analog_max = 4095;        ///< OpenGloves firmware's largest analog value
    std::string default_device;   ///< where it is found without --device ("" for none)
};

/// @brief Resolves `--glove`.
/// @param sensors the 5DT model (5 or 14). @throws value_error, io_error, format_error (a bad profile file).
inline glove_choice choose_glove(const std::string& glove, hand_side hand = hand_side::right, int sensors = 14, int analog_max = 4095)
{
    glove_choice c;
    c.hand = hand, c.analog_max = analog_max;
    if (glove == "senso") {
        c.kind = glove, c.profile = senso_profile(), c.link = glove_link::tcp, c.default_device = "127.0.0.1:53450";
    } else if (glove == "opengloves") {
        c.kind = glove, c.profile = opengloves_profile(), c.link = glove_link::serial;
        if (analog_max != 1023 && analog_max != 4095) throw value_error("glove: --analog-max " + std::to_string(analog_max) + " is not 1023 or 4095");
    } else if (glove == "5dt") {
        c.kind = glove, c.profile = fivedt_profile(sensors, hand), c.link = glove_link::hid;
    } else {
        c.kind = "profile", c.profile = read_glove_profile(glove), c.link = glove_link::hid;
    }
    return c;
}

/// @brief A fresh decoder for a glove choice.
inline std::unique_ptr<glove_decoder> make_decoder(const glove_choice& c)
{
    if (c.kind == "senso") return std::make_unique<senso_decoder>(c.hand);
    if (c.kind == "opengloves") return std::make_unique<opengloves_decoder>(c.analog_max);
    return std::make_unique<report_decoder>(c.profile);
}

/// @brief The messages a glove of choice `c` sends for sample `s` (of c.profile's sensors): one JSON
/// line (senso), one alpha-encoded line with per-joint values (opengloves) or the profile's reports, for
/// simulation, tests and benchmarks. `tick` is the report counter, `time` the device clock in seconds.
inline std::vector<std::vector<std::uint8_t>> encode_messages(const glove_choice& c, const glove_sample& s, std::uint64_t tick, double time)
{
    auto bytes = [](const std::string& l) { return std::vector<std::uint8_t>(l.begin(), l.end()); };
    if (c.kind == "senso") return {bytes(senso_position_line(s, c.hand))};
    if (c.kind == "opengloves") return {bytes(opengloves_line(s, c.analog_max))};
    return encode_reports(c.profile, s, tick, time);
}

}  // namespace handemo
