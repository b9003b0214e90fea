// `handemo train --mpi` (docs/scale-out.md): the one unit of the CLI that includes MPI, compiled when CMake finds it
// (target handemo::mpi). It gives the train command MPI's start and abort (registry.hpp, mpi_hooks); the training
// itself is the train command's own code, so 2 processes run the same machine code as one process with --shards 2.
#include "registry.hpp"

#include <handemo/dist/mpi.hpp>

#include <memory>

namespace {

struct mpi_state {
    std::unique_ptr<handemo::dist::mpi_runtime> runtime;  // MPI_Finalize at exit, after the exchange is gone
    std::unique_ptr<handemo::dist::mpi_exchange> exchange;
};

mpi_state& state()
{
    static mpi_state s;
    return s;
}

const bool registered = [] {
    auto& hooks = handemo::cli::mpi();
    hooks.start = []() -> handemo::dist::shard_exchange* {
        auto& s = state();
        if (!s.exchange) {
            s.runtime = std::make_unique<handemo::dist::mpi_runtime>();
            s.exchange = std::make_unique<handemo::dist::mpi_exchange>();
        }
        return s.exchange.get();
    };
    hooks.abort = [] {
        const auto& s = state();
        if (s.exchange && s.exchange->ranks() > 1) handemo::dist::mpi_runtime::abort_all(1);
    };
    return true;
}();

}  // namespace
