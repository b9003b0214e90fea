// The handemo CLI is one program with subcommands; each subcommand lives in its own cmd_*.cpp and
// registers itself here at static-initialisation time, so adding one never edits a shared file.
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
