// `loopfarm run`: the discovery farm (run_command.cpp).
#pragma once

#include "subcommand.hpp"

namespace loopfarm::cli {

Subcommand add_run_command(CLI::App& parent);

// With LOOPFARM_EXIT_FILE set, rank 0 (as the MPI launcher numbers the
// processes; a process not launched by one is rank 0) writes `code` there.
// Once interrupted, mpirun exits 1 whatever its ranks said, so a script that
// launches it maps its status from this file (jobs/mpirun-local.sh).
// `loopfarm run` writes it before MPI_Finalize, which an interrupted mpirun
// may not let a rank return from; main writes it again for every command.
void record_exit_code(int code);

}  // namespace loopfarm::cli
