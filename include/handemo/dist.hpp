// Distributed module: data parallelism across processes. The interface the trainer shares its parts
// through (dist/exchange.hpp, core only); its MPI transport is <handemo/dist/mpi.hpp>, target handemo::mpi,
// the only part that needs MPI (like <handemo/glove/hid.hpp> and hidapi).
#pragma once

#include <handemo/dist/exchange.hpp>
