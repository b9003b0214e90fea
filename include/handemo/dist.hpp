// Distributed module: work spread across processes. The interface the trainer shares its parts through
// (dist/exchange.hpp) and the process group the evaluation deals its trainings over (dist/group.hpp), both core
// only; their MPI transport is <handemo/dist/mpi.hpp>, target handemo::mpi, the only part that needs MPI (like
// <handemo/glove/hid.hpp> and hidapi).
#pragma once

#include <handemo/dist/exchange.hpp>
#include <handemo/dist/group.hpp>
