// A fixed group of processes that split a list of independent tasks between them, without a transport: the
// interface the evaluation calls to deal its trainings over processes (eval/schedule.hpp, eval_options::group).
// Each process knows its number and the group's size, waits for the others at a barrier, and gathers a few numbers
// from every process; nothing else crosses. Files are the data: what one process writes (to a file system every
// process sees) another reads after the next barrier. The MPI transport is <handemo/dist/mpi.hpp> (target
// handemo::mpi, dist::mpi_group); this header needs only the standard library.
#pragma once

#include <cstddef>
#include <span>

namespace handemo::dist {

/// @brief Processes 0 .. ranks() - 1 that run one program together. Every collective (barrier(), all_gather()) is
/// called by every process of the group, in the same order.
class process_group {
public:
    virtual ~process_group() = default;
    /// @brief This process's number, 0 .. ranks() - 1.
    virtual std::size_t rank() const noexcept = 0;
    /// @brief Number of processes.
    virtual std::size_t ranks() const noexcept = 0;
    /// @brief Returns once every process has called it: what any process wrote before it is written for all.
    virtual void barrier() = 0;
    /// @brief Every process gives mine.size() values (the same count everywhere); on return all[k * mine.size() + i]
    /// holds process k's value i, copied bit for bit. all.size() must be ranks() * mine.size().
    virtual void all_gather(std::span<const double> mine, std::span<double> all) = 0;
    /// @brief Whether this process writes the shared results (process 0): the others write only their own tasks' files.
    bool writes_files() const noexcept { return rank() == 0; }
};

}  // namespace handemo::dist
