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
namespace handemo::dist {
class shard_exchange;
class process_group;
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

/// `handemo train --mpi` and `handemo eval --mpi`: set by cmd_mpi.cpp, the one unit that includes MPI, when the CLI is
/// built with MPI (target handemo::mpi); empty otherwise. `start` initialises MPI once and returns the processes'
/// exchange (train), `group` the same processes as a group (eval); `abort` ends every process after an error in one
/// of them (the others may wait for it in a collective).
struct mpi_hooks {
    std::function<handemo::dist::shard_exchange*()> start;
    std::function<handemo::dist::process_group*()> group;
    std::function<void()> abort;
};

inline mpi_hooks& mpi()
{
    static mpi_hooks h;
    return h;
}

}  // namespace handemo::cli
