// MPI, optional at build time (CMake finds Debian's libopenmpi-dev; docs/CLUSTER.md): the one
// file that includes <mpi.h> is Mpi.cpp; the rest of the code sees core/Communicator.h.
#pragma once

#include <memory>
#include <string>

#include "core/Communicator.h"

namespace sl {

/// True when this build has MPI.
bool mpiBuilt();

/// "Open MPI v4.1.4 ..." (the library's own version string), or "" without MPI.
std::string mpiLibraryVersion();

/// The processes this one runs with: MPI's world when the build has MPI and a launcher
/// (mpirun, mpiexec, srun) started this process, else this process alone. MPI is initialised
/// here and finalised when the returned object is destroyed; call it once, from the main
/// thread (MPI is called only from there: MPI_THREAD_FUNNELED).
std::unique_ptr<Communicator> worldCommunicator();

}  // namespace sl
