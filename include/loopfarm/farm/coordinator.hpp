// The farm's coordinator, apart from how messages travel: rank 0 of an MPI
// run (farm.hpp) drives it through an MPI transport, the tests through a fake
// one (results out of order, a stop mid-chunk, a resume).
//
// The coordinator is also a worker: a thread of its own runs starts while the
// calling thread answers the remote workers, puts results in start-index
// order (work_queue.hpp) and reports progress; a third thread commits them,
// a batch at a time, while the calling thread fills the next. Work goes out in chunks on
// demand (local minimisations take very different times); a worker's results
// come back with its next request.
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <vector>

#include "loopfarm/farm/progress.hpp"
#include "loopfarm/farm/results.hpp"
#include "loopfarm/farm/results_database.hpp"
#include "loopfarm/farm/stop_flag.hpp"
#include "loopfarm/farm/work_queue.hpp"
#include "loopfarm/search/job.hpp"

namespace loopfarm {

// One worker's request for work, with the records of its previous chunk.
struct WorkRequest {
  int worker = 0;         // the transport's name for it (an MPI rank)
  bool stopping = false;  // it caught a signal: the whole run stops
  std::vector<StartRecord> records;
};

// How requests arrive and chunks go out. A worker sent an empty chunk has
// stopped and sends nothing more.
class CoordinatorTransport {
 public:
  virtual ~CoordinatorTransport() = default;
  // The number of remote workers (the coordinator's own thread not counted).
  virtual int remote_workers() const = 0;
  // The next request if one has arrived; never waits.
  virtual std::optional<WorkRequest> poll() = 0;
  virtual void send_work(int worker, const std::vector<std::uint64_t>& chunk) = 0;
};

// Runs one start; never throws (a failure is a record with status "error").
using StartRunner = std::function<StartRecord(std::uint64_t index)>;

// make_start_record(run_start(job, index)); an exception from the library
// (which would be a defect) becomes a record with status "error" and a line
// on stderr, rather than a dead worker.
StartRecord run_start_record(const Job& job, std::uint64_t index);

// What one invocation runs: the run it writes to, the indices still to do and
// the counts so far (for the progress line of a resumed run).
struct ResumePlan {
  std::int64_t run_id = 0;
  PendingCursor pending;
  long starts = 0;     // the run's target: its slice's starts for a slice
  long committed = 0;  // of them, by earlier sessions
  long zeros = 0;
  long candidates = 0;
};

// Decides the run (ResultsDatabase::open_run: a new run, or the same job, seed
// and slice resumed; another job or slice throws DatabaseError) and opens its
// session with `ranks`. With `slice`, only that slice of the job's starts.
ResumePlan plan_run(ResultsDatabase& db, const Job& job, bool new_run, int ranks,
                    const std::optional<StartSlice>& slice = {});

struct CoordinatorSummary {
  long total = 0;       // the run's target
  long done = 0;        // committed, earlier sessions included
  long done_here = 0;   // committed by this session
  long zeros = 0;       // zero minima of the run
  long candidates = 0;  // candidates in the database
  bool complete = false;
  double wall_s = 0.0;
  // The coordinator's own cost (messages, decoding, commits, progress), apart
  // from its compute thread: what limits how many workers one coordinator serves.
  double coordination_s = 0.0;
  long messages = 0;
};

// Runs the plan's pending starts until all are committed or a stop is
// requested (by `stop` or a worker), commits everything that finished, and
// ends the session (complete or stopped). `chunk` start indices per request.
// Throws DatabaseError when a commit fails (the session is left open: the
// caller ends it as failed).
CoordinatorSummary coordinate(ResultsDatabase& db, const ResumePlan& plan, CoordinatorTransport& transport,
                              const StartRunner& run, int chunk, StopFlag& stop, Progress& progress);

}  // namespace loopfarm
