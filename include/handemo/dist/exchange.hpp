// Data parallelism across processes, without a transport: the interface the trainer calls to share each
// process's part of a step (stargan/train.hpp, train_options::exchange). A process owns one part of the batch
// (the part its rank numbers), computes it alone, and the exchange makes every process's copy of every part
// equal to its owner's. Nothing is added here: the trainer then adds the parts up in part order, as it does
// for the parts of one process, so P processes train bit for bit what one process with P parts trains.
// The MPI transport is <handemo/dist/mpi.hpp> (target handemo::mpi); this header needs only the core.
#pragma once

#include <cstddef>
#include <span>

namespace handemo::dist {

/// @brief Processes that each own one part of a data-parallel step and share them.
class shard_exchange {
public:
    virtual ~shard_exchange() = default;
    /// @brief This process's number, 0 .. ranks() - 1: the part it owns.
    virtual std::size_t rank() const noexcept = 0;
    /// @brief Number of processes (parts).
    virtual std::size_t ranks() const noexcept = 0;
    /// @brief On entry parts[rank()] holds this process's `count` values; on return every parts[k] (k <
    /// ranks()) holds process k's, copied bit for bit (no arithmetic). Collective: every process calls it with
    /// the same count, in the same order.
    virtual void share(std::span<float* const> parts, std::size_t count) = 0;
    /// @brief Whether this process writes files (rank 0): the others hold the same state and write nothing.
    bool writes_files() const noexcept { return rank() == 0; }
};

}  // namespace handemo::dist
