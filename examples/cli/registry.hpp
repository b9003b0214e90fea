// The handemo CLI is one program with subcommands; each subcommand lives in its own header (motion/,
// render/, stargan/), included by its group's cmd_<group>.cpp, and registers itself here at
// static-initialisation time, so adding one edits only its group's cmd_<group>.cpp.
#pragma once

#include <CLI/CLI.hpp>

#include <functional>
#include <string>
#include <vector>

namespace handemo::cli {

using registrar = std::function<void(CLI::App&)>;

inline std::vector<std::pair<int, registrar>>& registry()
{
    static std::vector<std::pair<int, registrar>> r;
    return r;
}

/// Registers a subcommand; `order` sorts them in --help.
struct add_command {
    add_command(int order, registrar r) { registry().emplace_back(order, std::move(r)); }
};

}  // namespace handemo::cli
