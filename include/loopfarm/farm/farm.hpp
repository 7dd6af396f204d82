// The discovery farm over MPI: one entry point that takes the job, its store
// and a communicator and returns what happened. MPI lives here, at the edge
// of the library; the coordinator (coordinator.hpp) and everything below it
// know nothing of it.
//
// Rank 0 of the communicator opens the job's results database, decides the
// run (a new one, or the same job and seed resumed), coordinates and computes;
// every other rank computes. P ranks give P workers. Every rank reads the same
// job; the job's [output] database is the store.
//
// Stop: a StopFlag set (by the caller's signal handlers) on any rank. No more
// work is handed out, the starts in hand finish, everything is committed, and
// the run ends `stopped`. Under mpirun only SIGUSR1 leaves time (mpirun
// follows SIGTERM with SIGKILL after about 1 s); Slurm's --signal=USR1@T sends
// it ahead of the time limit.
#pragma once

#include <mpi.h>

#include <cstdint>
#include <optional>

#include "loopfarm/farm/coordinator.hpp"
#include "loopfarm/farm/progress.hpp"
#include "loopfarm/farm/stop_flag.hpp"
#include "loopfarm/search/job.hpp"

namespace loopfarm {

// MPI for the life of the object: initialised with MPI_THREAD_FUNNELED (rank
// 0 computes on a thread of its own while its main thread talks), finalised
// when it goes.
class MpiSession {
 public:
  MpiSession();
  ~MpiSession();
  MpiSession(const MpiSession&) = delete;
  MpiSession& operator=(const MpiSession&) = delete;
  MPI_Comm world() const { return MPI_COMM_WORLD; }
  int rank() const { return rank_; }
  int ranks() const { return ranks_; }
  bool funneled() const { return provided_ >= MPI_THREAD_FUNNELED; }

 private:
  int provided_ = 0;
  int rank_ = 0;
  int ranks_ = 1;
};

struct FarmOptions {
  int chunk = 64;  // start indices per request
  ProgressStyle progress = ProgressStyle::log;
  bool new_run = false;             // add a new run to a database that holds another job
  std::optional<StartSlice> slice;  // run only this slice of the job's starts (a run of its own)
};

enum class FarmStatus {
  complete,  // every start of the run is committed
  stopped,   // stopped by a StopFlag; resumable
  refused,   // rank 0 refused the database or the job (on rank 0 this throws instead)
  failed,    // rank 0 failed (on rank 0 this throws instead)
};

// What a call did: the status on every rank; the rest on rank 0 only.
struct FarmSummary {
  FarmStatus status = FarmStatus::failed;
  int ranks = 1;
  std::int64_t run_id = 0;
  CoordinatorSummary run;      // counts and timings of this call (coordinator.hpp)
  double peak_mb_rank0 = 0.0;  // peak resident memory (VmHWM)
  double peak_mb_max = 0.0;    // of every rank
  int stop_signal = 0;         // what stopped it (-1: an error), 0 if nothing
};

// Collective over `comm`. On rank 0: throws DatabaseError when the database
// is refused (not loopfarm's, damaged, another job: nothing is written) and
// std::exception on any other failure (the session is marked failed; with more
// than one rank, MPI_Abort ends them all after the message is printed). On
// the other ranks: returns refused or failed in those cases.
FarmSummary run_farm(const Job& job, MPI_Comm comm, StopFlag& stop, const FarmOptions& options);

}  // namespace loopfarm
