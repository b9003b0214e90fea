// The handemo CLI is one program with subcommands; each subcommand lives in its own header (motion/,
// render/, stargan/), included by its group's cmd_<group>.cpp, and registers itself here at
// static-initialisation time, so adding one edits only its group's cmd_<group>.cpp.
#pragma once

#include <CLI/CLI.hpp>

#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace handemo::eval {
class method_extension;
}

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

/// Methods another translation unit adds to `handemo eval` (eval/extension.hpp): its options on the eval
/// subcommand, and the extension they ask for (null when not asked for). cmd_rcm.cpp adds `--rcm` this way,
/// so the StarGAN translation unit never includes the circumplex code (LAPACK).
struct eval_extension_entry {
    std::function<void(CLI::App*)> add_options;
    std::function<std::shared_ptr<handemo::eval::method_extension>()> make;
};

inline std::vector<eval_extension_entry>& eval_extensions()
{
    static std::vector<eval_extension_entry> r;
    return r;
}

struct add_eval_extension {
    explicit add_eval_extension(eval_extension_entry e) { eval_extensions().push_back(std::move(e)); }
};

}  // namespace handemo::cli
