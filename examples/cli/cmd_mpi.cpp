// `handemo train --mpi` and `handemo eval --mpi` (docs/scale-out.md): the one unit of the CLI that includes MPI,
// compiled when CMake finds it (target handemo::mpi). It gives the train and eval commands MPI's start and abort
// (registry.hpp, mpi_hooks); the training and the evaluation are the commands' own code, so 2 processes run the same
// machine code as one process (train: with --shards 2).
#include "registry.hpp"

#include <handemo/dist/mpi.hpp>

#include <memory>

namespace {

struct mpi_state {
    std::unique_ptr<handemo::dist::mpi_runtime> runtime;  // MPI_Finalize at exit, after the exchange and group are gone
    std::unique_ptr<handemo::dist::mpi_exchange> exchange;
    std::unique_ptr<handemo::dist::mpi_group> group;
};

mpi_state& state()
{
    static mpi_state s;
    return s;
}

void start_runtime()
{
    auto& s = state();
    if (!s.runtime) s.runtime = std::make_unique<handemo::dist::mpi_runtime>();
}

const bool registered = [] {
    auto& hooks = handemo::cli::mpi();
    hooks.start = []() -> handemo::dist::shard_exchange* {
        start_runtime();
        auto& s = state();
        if (!s.exchange) s.exchange = std::make_unique<handemo::dist::mpi_exchange>();
        return s.exchange.get();
    };
    hooks.group = []() -> handemo::dist::process_group* {
        start_runtime();
        auto& s = state();
        if (!s.group) s.group = std::make_unique<handemo::dist::mpi_group>();
        return s.group.get();
    };
    hooks.abort = [] {
        const auto& s = state();
        if ((s.exchange && s.exchange->ranks() > 1) || (s.group && s.group->ranks() > 1)) handemo::dist::mpi_runtime::abort_all(1);
    };
    return true;
}();

}  // namespace
