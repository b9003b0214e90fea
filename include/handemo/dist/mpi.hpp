// The MPI transport of work across processes (target handemo::mpi, any MPI 3 library; Debian's Open MPI is
// the one tested): the process's MPI lifetime, a dist::shard_exchange (data-parallel training) and a
// dist::process_group (the evaluation's trainings dealt over processes) over a communicator. Each part is
// broadcast from its owner, parts in rank order, so every process receives every part bit for bit and the
// trainer adds them in part order itself (MPI_Allreduce would add them in an order of its own choosing,
// which changes with the number of processes and the library). Only this header includes <mpi.h>.
#pragma once

#include <handemo/core/error.hpp>
#include <handemo/dist/exchange.hpp>
#include <handemo/dist/group.hpp>

#include <mpi.h>

#include <algorithm>
#include <climits>
#include <cstdlib>
#include <cstddef>
#include <span>
#include <string>

namespace handemo::dist {

namespace detail {

/// Throws io_error naming the MPI call and the library's message when `rc` is not MPI_SUCCESS.
inline void check_mpi(int rc, const char* call)
{
    if (rc == MPI_SUCCESS) return;
    char msg[MPI_MAX_ERROR_STRING] = {};
    int len = 0;
    MPI_Error_string(rc, msg, &len);
    throw io_error(std::string("mpi: ") + call + " failed: " + std::string(msg, std::size_t(std::max(len, 0))));
}

/// The rank of this process in `comm` and the number of processes there.
struct comm_place {
    std::size_t rank = 0, ranks = 1;
};
inline comm_place place_in(MPI_Comm comm)
{
    int r = 0, n = 0;
    check_mpi(MPI_Comm_rank(comm, &r), "MPI_Comm_rank");
    check_mpi(MPI_Comm_size(comm, &n), "MPI_Comm_size");
    return {std::size_t(r), std::size_t(n)};
}

}  // namespace detail

/// @brief The process's MPI lifetime: MPI_Init_thread (funneled: only the thread that made it calls MPI) on
/// construction, MPI_Finalize on destruction. Errors of MPI_COMM_WORLD are returned, not fatal, and thrown
/// as io_error naming the call.
class mpi_runtime {
public:
    /// @brief With main's arguments (MPI may take its own from them).
    mpi_runtime(int& argc, char**& argv) { init(&argc, &argv); }
    /// @brief Without them (MPI_Init_thread(NULL, NULL, ...)), e.g. when MPI is started after the command line was parsed.
    mpi_runtime() { init(nullptr, nullptr); }
    mpi_runtime(const mpi_runtime&) = delete;
    mpi_runtime& operator=(const mpi_runtime&) = delete;
    ~mpi_runtime() { MPI_Finalize(); }
    /// @brief Ends every process of MPI_COMM_WORLD with `code`: what a process that failed alone calls, so
    /// that the others do not wait for it in a collective forever.
    [[noreturn]] static void abort_all(int code) noexcept
    {
        MPI_Abort(MPI_COMM_WORLD, code);
        std::abort();
    }

private:
    static void init(int* argc, char*** argv)
    {
        int provided = 0;
        detail::check_mpi(MPI_Init_thread(argc, argv, MPI_THREAD_FUNNELED, &provided), "MPI_Init_thread");
        MPI_Comm_set_errhandler(MPI_COMM_WORLD, MPI_ERRORS_RETURN);
    }
};

/// @brief A shard_exchange over an MPI communicator (MPI_COMM_WORLD unless given): rank and size are the
/// communicator's; share() broadcasts each part from its owner (ranks 0, 1, ... in turn), in chunks of at
/// most INT_MAX values.
class mpi_exchange final : public shard_exchange {
public:
    explicit mpi_exchange(MPI_Comm comm = MPI_COMM_WORLD) : comm_(comm)
    {
        const auto p = detail::place_in(comm_);
        rank_ = p.rank, ranks_ = p.ranks;
    }
    std::size_t rank() const noexcept override { return rank_; }
    std::size_t ranks() const noexcept override { return ranks_; }
    void share(std::span<float* const> parts, std::size_t count) override
    {
        if (parts.size() < ranks_)
            throw value_error("mpi: share: " + std::to_string(parts.size()) + " parts for " + std::to_string(ranks_) + " processes");
        for (std::size_t owner = 0; owner < ranks_; ++owner)
            for (std::size_t at = 0; at < count;) {
                const std::size_t n = std::min<std::size_t>(count - at, INT_MAX);
                detail::check_mpi(MPI_Bcast(parts[owner] + at, int(n), MPI_FLOAT, int(owner), comm_), "MPI_Bcast");
                at += n;
            }
    }
    /// @brief Waits for every process of the communicator (e.g. before reading what rank 0 wrote).
    void barrier() { detail::check_mpi(MPI_Barrier(comm_), "MPI_Barrier"); }

private:
    MPI_Comm comm_;
    std::size_t rank_ = 0, ranks_ = 1;
};

/// @brief A process_group over an MPI communicator (MPI_COMM_WORLD unless given): rank and size are the
/// communicator's; barrier() is MPI_Barrier, all_gather() MPI_Allgather of doubles (a copy, no arithmetic).
class mpi_group final : public process_group {
public:
    explicit mpi_group(MPI_Comm comm = MPI_COMM_WORLD) : comm_(comm)
    {
        const auto p = detail::place_in(comm_);
        rank_ = p.rank, ranks_ = p.ranks;
    }
    std::size_t rank() const noexcept override { return rank_; }
    std::size_t ranks() const noexcept override { return ranks_; }
    void barrier() override { detail::check_mpi(MPI_Barrier(comm_), "MPI_Barrier"); }
    void all_gather(std::span<const double> mine, std::span<double> all) override
    {
        if (all.size() != mine.size() * ranks_ || mine.size() > std::size_t(INT_MAX))
            throw value_error("mpi: all_gather: " + std::to_string(mine.size()) + " values per process and room for " +
                              std::to_string(all.size()) + ", not " + std::to_string(ranks_) + " times as many");
        detail::check_mpi(MPI_Allgather(mine.data(), int(mine.size()), MPI_DOUBLE, all.data(), int(mine.size()), MPI_DOUBLE, comm_),
                          "MPI_Allgather");
    }

private:
    MPI_Comm comm_;
    std::size_t rank_ = 0, ranks_ = 1;
};

}  // namespace handemo::dist
