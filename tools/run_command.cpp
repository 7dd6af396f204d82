// loopfarm run JOB.toml: the discovery farm. Under `mpirun -np P` or alone
// (one rank). MPI lives here, at the edge; the library knows nothing of it.
//
// Rank 0 is the coordinator and a worker: a compute thread runs starts while
// the main thread answers the other ranks, commits results and reports
// progress, so P ranks give P workers. Work goes out in chunks of start
// indices on demand (local minimisations take very different times); results
// come back with the next request.
//
// Results do not depend on P, the chunk size or timing: every start is a
// function of (job, seed, index) alone, and rank 0 commits records in the
// order of their start indices (holding back those that arrive early), so two
// uninterrupted runs write the same rows in the same order. A stopped run
// commits whatever finished, gaps included; a resume runs exactly the starts
// that are not committed.
//
// Stop: SIGINT, SIGTERM and SIGUSR1 only set a flag. No more work is handed
// out, the starts in hand finish, everything is committed, and the command
// exits with kExitStopped and a line saying how to resume. Under mpirun only
// SIGUSR1 leaves time (mpirun follows SIGTERM with SIGKILL after about 1 s);
// Slurm's --signal=USR1@T sends it ahead of the time limit.
#include "run_command.hpp"

#include <mpi.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <limits>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "cli_support.hpp"
#include "loopfarm/search/job.hpp"
#include "loopfarm/farm/results.hpp"
#include "loopfarm/farm/results_database.hpp"
#include "loopfarm/search/start.hpp"
#include "progress.hpp"

// Under AddressSanitizer (tools/test.sh --sanitize): the allocations Open MPI
// keeps until exit are suppressed by library name (tools/sanitizers/lsan.supp),
// which needs whole allocation stacks; the default fast unwinder stops in
// Open MPI's components, which are built without frame pointers. Full
// unwinding costs every allocation a slow walk, so only the program that
// starts MPI asks for it, here, and the test programs keep the fast one
// (ASAN_OPTIONS in the environment still overrides this default).
#if defined(__SANITIZE_ADDRESS__)
#define LOOPFARM_ADDRESS_SANITIZER 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define LOOPFARM_ADDRESS_SANITIZER 1
#endif
#endif
#ifdef LOOPFARM_ADDRESS_SANITIZER
extern "C" const char* __asan_default_options() { return "fast_unwind_on_malloc=0"; }
#endif

namespace loopfarm::cli {
namespace {

// A signal number, set by the handler; 0 while running.
std::atomic<int> g_stop_signal{0};
static_assert(std::atomic<int>::is_always_lock_free, "the signal handler needs a lock-free flag");

extern "C" void on_stop_signal(int signal) { g_stop_signal.store(signal, std::memory_order_relaxed); }

void install_stop_handlers() {
  struct sigaction action {};
  action.sa_handler = on_stop_signal;
  sigemptyset(&action.sa_mask);
  for (int signal : {SIGINT, SIGTERM, SIGUSR1}) sigaction(signal, &action, nullptr);
}

bool stop_requested() { return g_stop_signal.load(std::memory_order_relaxed) != 0; }

constexpr int kTagRequest = 1;  // worker -> 0: [stopping byte][encoded records]
constexpr int kTagWork = 2;     // 0 -> worker: start indices (uint64); none means stop

struct RunArguments {
  std::string job;
  std::string starts;
  std::string seed;
  std::string db;
  // 16 starts per request: a worker waits for its next chunk up to one
  // 2 ms polling period of rank 0, which at 4 starts of the default job
  // (about 6 ms each) cost 5 % of its time (parallel efficiency 0.947 from
  // 1 to 2 ranks; 0.983 at 16).
  std::string chunk = "16";
  std::string progress = "auto";
  bool new_run = false;
};

// Thrown on rank 0 after the other ranks have been told to go home, so that
// main prints it once.
struct RunSettings {
  Job job;
  int chunk = 16;
  ProgressStyle progress = ProgressStyle::log;
  bool new_run = false;
};

RunSettings read_settings(const RunArguments& args) {
  RunSettings s;
  try {
    s.job = read_job_file(args.job);
  } catch (const JobError& error) {
    throw UsageError("job file", error.what());
  }
  if (!args.starts.empty()) {
    const long long starts = parse_integer(args.starts, "--starts");
    if (starts < 1 || starts > (1LL << 53)) throw UsageError("--starts", "got " + args.starts + "; must be >= 1");
    s.job.search.starts = static_cast<long>(starts);
  }
  if (!args.seed.empty()) {
    const long long seed = parse_integer(args.seed, "--seed");
    if (seed < 0) throw UsageError("--seed", "got " + args.seed + "; must be >= 0");
    s.job.search.seed = static_cast<std::uint64_t>(seed);
  }
  if (!args.db.empty()) s.job.output.database = args.db;
  const long long chunk = parse_integer(args.chunk, "--chunk");
  if (chunk < 1 || chunk > 100000) throw UsageError("--chunk", "got " + args.chunk + "; must be in [1, 100000]");
  s.chunk = static_cast<int>(chunk);
  if (args.progress == "auto") {
    s.progress = default_progress_style();
  } else if (args.progress == "bar") {
    s.progress = ProgressStyle::bar;
  } else if (args.progress == "log") {
    s.progress = ProgressStyle::log;
  } else if (args.progress == "none") {
    s.progress = ProgressStyle::none;
  } else {
    throw UsageError("--progress", "got " + quote_text(args.progress) + "; expected auto, bar, log or none");
  }
  s.new_run = args.new_run;
  return s;
}

// One start, as a record. An exception from the library (which would be a
// defect) becomes a record with status "error" rather than a dead rank.
StartRecord run_one(const Job& job, std::uint64_t index) {
  try {
    return make_start_record(run_start(job, index));
  } catch (const std::exception& error) {
    StartRecord r;
    r.index = index;
    r.status = "error";
    r.E_mean = r.E_max = r.objective = std::numeric_limits<double>::quiet_NaN();
    std::fprintf(stderr, "loopfarm run: start %llu failed: %s\n", static_cast<unsigned long long>(index),
                 one_line(error.what()).c_str());
    return r;
  }
}

// The start indices still to run, in increasing order: [0, starts) less the
// committed ranges, walked by a cursor (kept as ranges: a run may have 1e8
// starts).
class PendingCursor {
 public:
  PendingCursor() = default;
  PendingCursor(const std::vector<IndexRange>& committed, std::uint64_t starts) {
    std::uint64_t from = 0;
    for (const IndexRange& c : committed) {
      if (c.first >= starts) break;
      if (c.first > from) todo_.push_back({from, c.first});
      from = std::max(from, c.last);
    }
    if (from < starts) todo_.push_back({from, starts});
    if (!todo_.empty()) at_ = todo_.front().first;
  }
  bool done() const { return range_ >= todo_.size(); }
  std::uint64_t peek() const { return at_; }
  void advance() {
    if (++at_ >= todo_[range_].last && ++range_ < todo_.size()) at_ = todo_[range_].first;
  }
  std::uint64_t count() const {
    std::uint64_t n = 0;
    for (const IndexRange& r : todo_) n += r.last - r.first;
    return n;
  }

 private:
  std::vector<IndexRange> todo_;
  size_t range_ = 0;
  std::uint64_t at_ = 0;
};

// Hands out the pending start indices in chunks, in increasing order; nothing
// once a stop is requested.
class Dispenser {
 public:
  Dispenser(PendingCursor pending, int chunk) : cursor_(std::move(pending)), chunk_(chunk) {}
  std::vector<std::uint64_t> take() {
    std::lock_guard lock(mutex_);
    std::vector<std::uint64_t> out;
    if (stop_requested()) return out;
    while (static_cast<int>(out.size()) < chunk_ && !cursor_.done()) {
      out.push_back(cursor_.peek());
      cursor_.advance();
    }
    return out;
  }

 private:
  std::mutex mutex_;
  PendingCursor cursor_;
  int chunk_;
};

// Rank 0's own worker: a thread that takes chunks like any rank and leaves
// its records for the main thread (no MPI calls: MPI_THREAD_FUNNELED).
class LocalWorker {
 public:
  LocalWorker(const Job& job, Dispenser& dispenser)
      : thread_([this, &job, &dispenser] {
          for (;;) {
            const std::vector<std::uint64_t> chunk = dispenser.take();
            if (chunk.empty()) break;
            for (std::uint64_t index : chunk) {
              if (stop_requested()) break;
              StartRecord record = run_one(job, index);
              std::lock_guard lock(mutex_);
              done_.push_back(std::move(record));
            }
          }
          finished_.store(true);
        }) {}
  ~LocalWorker() { thread_.join(); }
  std::vector<StartRecord> collect() {
    std::lock_guard lock(mutex_);
    std::vector<StartRecord> out;
    out.swap(done_);
    return out;
  }
  bool finished() const { return finished_.load(); }

 private:
  std::mutex mutex_;
  std::vector<StartRecord> done_;
  std::atomic<bool> finished_{false};
  std::thread thread_;  // last: started once the members above exist
};

// Holds records until every pending index before them has arrived, so that
// commits follow start-index order whatever the arrival order.
class OrderedCommits {
 public:
  explicit OrderedCommits(PendingCursor pending) : cursor_(std::move(pending)) {}
  void add(StartRecord record) {
    const std::uint64_t index = record.index;
    held_.emplace(index, std::move(record));
  }
  // Records now ready, in index order.
  std::vector<StartRecord> ready() {
    std::vector<StartRecord> out;
    while (!cursor_.done()) {
      auto it = held_.find(cursor_.peek());
      if (it == held_.end()) break;
      out.push_back(std::move(it->second));
      held_.erase(it);
      cursor_.advance();
    }
    return out;
  }
  // Everything held, gaps or not (a stopped run).
  std::vector<StartRecord> all() {
    std::vector<StartRecord> out = ready();
    for (auto& [index, record] : held_) out.push_back(std::move(record));
    held_.clear();
    return out;
  }

 private:
  PendingCursor cursor_;
  std::map<std::uint64_t, StartRecord> held_;
};

void send_bytes(const std::string& bytes, int destination, int tag) {
  MPI_Send(bytes.data(), static_cast<int>(bytes.size()), MPI_BYTE, destination, tag, MPI_COMM_WORLD);
}

std::string receive_bytes(int source, int tag, int* from) {
  MPI_Status status;
  MPI_Probe(source, tag, MPI_COMM_WORLD, &status);
  int size = 0;
  MPI_Get_count(&status, MPI_BYTE, &size);
  std::string bytes(static_cast<size_t>(size), '\0');
  MPI_Recv(bytes.data(), size, MPI_BYTE, status.MPI_SOURCE, tag, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
  if (from) *from = status.MPI_SOURCE;
  return bytes;
}

void send_work(const std::vector<std::uint64_t>& chunk, int destination) {
  MPI_Send(chunk.data(), static_cast<int>(chunk.size()), MPI_UINT64_T, destination, kTagWork, MPI_COMM_WORLD);
}

// Ranks 1..P-1: ask, compute, return, until told to stop.
void worker_loop(const Job& job) {
  std::vector<StartRecord> done;
  bool stopping = false;
  for (;;) {
    std::string message(1, stopping ? '\1' : '\0');
    std::string encoded;
    encode_records(done, encoded);
    message += encoded;
    send_bytes(message, 0, kTagRequest);
    done.clear();
    if (stopping) break;  // rank 0 answers with an empty chunk; take it
    MPI_Status status;
    MPI_Probe(0, kTagWork, MPI_COMM_WORLD, &status);
    int count = 0;
    MPI_Get_count(&status, MPI_UINT64_T, &count);
    std::vector<std::uint64_t> chunk(static_cast<size_t>(count));
    MPI_Recv(chunk.data(), count, MPI_UINT64_T, 0, kTagWork, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
    if (chunk.empty()) return;
    for (std::uint64_t index : chunk) {
      if (stop_requested()) break;
      done.push_back(run_one(job, index));
    }
    stopping = stop_requested();
  }
  // The stop reply to the last request.
  std::vector<std::uint64_t> none(1);
  MPI_Status status;
  MPI_Probe(0, kTagWork, MPI_COMM_WORLD, &status);
  int count = 0;
  MPI_Get_count(&status, MPI_UINT64_T, &count);
  none.resize(static_cast<size_t>(count));
  MPI_Recv(none.data(), count, MPI_UINT64_T, 0, kTagWork, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
}

// This process's peak resident memory [kB] (VmHWM), 0 where /proc is missing.
long peak_memory_kb() {
  std::FILE* status = std::fopen("/proc/self/status", "r");
  if (status == nullptr) return 0;
  char line[256];
  long kb = 0;
  while (std::fgets(line, sizeof line, status)) {
    if (std::sscanf(line, "VmHWM: %ld kB", &kb) == 1) break;
  }
  std::fclose(status);
  return kb;
}

std::string signal_name(int signal) {
  switch (signal) {
    case SIGINT: return "SIGINT";
    case SIGTERM: return "SIGTERM";
    case SIGUSR1: return "SIGUSR1";
    default: return "signal " + std::to_string(signal);
  }
}

std::string resume_command(const RunArguments& args, const RunSettings& s) {
  std::string command = "loopfarm run " + args.job;
  if (!args.starts.empty()) command += " --starts " + args.starts;
  if (!args.seed.empty()) command += " --seed " + args.seed;
  command += " --db " + s.job.output.database;
  return command;
}

// What this invocation runs: the run it writes to, the indices still to do
// and the counts so far (for the progress line of a resumed run).
struct ResumePlan {
  std::int64_t run_id = 0;
  PendingCursor pending;
  long committed = 0;
  long zeros = 0;
  long candidates = 0;
};

ResumePlan plan_run(ResultsDatabase& db, const Job& job, bool new_run, int ranks) {
  RunIdentity identity;
  identity.job_path = job.path;
  identity.job_text = job.text;
  identity.seed = job.search.seed;
  identity.starts = static_cast<std::uint64_t>(job.search.starts);
  identity.joints = job.loop.joints;
  identity.zero_threshold = job.search.zero_threshold;
  identity.report_threshold = job.output.report_threshold;
  const RunInfo run = db.open_run(identity, new_run);
  ResumePlan plan;
  plan.run_id = run.run_id;
  plan.pending = PendingCursor(run.committed, identity.starts);
  plan.committed = static_cast<long>(identity.starts - plan.pending.count());
  plan.zeros = static_cast<long>(db.start_counts(run.run_id).zeros);
  plan.candidates = static_cast<long>(db.candidate_count());
  db.begin_session(run.run_id, ranks);
  return plan;
}

// Rank 0. Returns the exit code.
int coordinate(const RunArguments& args, const RunSettings& s, ResultsDatabase& db, const ResumePlan& plan, int ranks) {
  const Job& job = s.job;
  Dispenser dispenser(plan.pending, s.chunk);
  OrderedCommits commits(plan.pending);
  Progress progress(s.progress);
  ProgressCounts counts;
  counts.total = job.search.starts;
  counts.done = plan.committed;
  counts.zeros = plan.zeros;
  counts.candidates = plan.candidates;
  if (plan.committed > 0) {
    std::fprintf(stderr, "loopfarm run: resuming run %lld of %s: %ld of %ld starts already committed\n",
                 static_cast<long long>(plan.run_id), job.output.database.c_str(), plan.committed, counts.total);
  }

  // Rank 0's own cost (messages, decoding, commits, progress), apart from
  // its compute thread: what limits how many ranks one coordinator serves.
  using Clock = std::chrono::steady_clock;
  const auto session_start = Clock::now();
  double coordination_s = 0.0;
  long messages = 0;

  std::vector<StartRecord> batch;
  auto last_commit = std::chrono::steady_clock::now();
  auto commit = [&](std::vector<StartRecord> records) {
    for (StartRecord& r : records) batch.push_back(std::move(r));
  };
  auto flush = [&](bool force) {
    const auto now = std::chrono::steady_clock::now();
    if (batch.empty()) return;
    if (!force && batch.size() < 256 && now - last_commit < std::chrono::seconds(2)) return;
    const CommitSummary c = db.commit(plan.run_id, batch);
    counts.done += c.starts;
    counts.done_here += c.starts;
    counts.zeros += c.zeros;
    counts.candidates += c.new_candidates;
    batch.clear();
    last_commit = now;
  };

  int active_workers = ranks - 1;
  {
    LocalWorker local(job, dispenser);
    // Destroyed before `local` joins its thread: on an exception (a failed
    // commit) the thread stops after its current start instead of running on.
    struct StopOnUnwind {
      ~StopOnUnwind() {
        if (std::uncaught_exceptions() > 0) g_stop_signal.store(-1);
      }
    } stop_on_unwind;
    while (active_workers > 0 || !local.finished()) {
      bool busy = false;
      int flag = 0;
      MPI_Status status;
      const auto work_start = Clock::now();
      MPI_Iprobe(MPI_ANY_SOURCE, kTagRequest, MPI_COMM_WORLD, &flag, &status);
      if (flag) {
        ++messages;
        busy = true;
        int from = 0;
        const std::string message = receive_bytes(status.MPI_SOURCE, kTagRequest, &from);
        if (message.empty()) throw std::runtime_error("empty message from rank " + std::to_string(from));
        // A worker that caught a signal stops the whole run.
        if (message[0] != '\0' && !stop_requested()) g_stop_signal.store(SIGUSR1);
        for (StartRecord& r : decode_records(std::string_view(message).substr(1))) commits.add(std::move(r));
        const std::vector<std::uint64_t> chunk = dispenser.take();
        send_work(chunk, from);
        if (chunk.empty()) --active_workers;
      }
      for (StartRecord& r : local.collect()) commits.add(std::move(r));
      commit(commits.ready());
      flush(false);
      progress.update(counts);
      coordination_s += std::chrono::duration<double>(Clock::now() - work_start).count();
      if (!busy) std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
    // What the thread finished between the last collect and its end.
    for (StartRecord& r : local.collect()) commits.add(std::move(r));
  }
  commit(commits.all());
  flush(true);
  progress.update(counts, true);
  progress.finish();

  const int signal = g_stop_signal.load();
  const bool complete = counts.done >= counts.total;
  db.end_session(complete ? RunStatus::complete : RunStatus::stopped);
  const double wall_s = std::chrono::duration<double>(Clock::now() - session_start).count();
  std::fprintf(stderr, "loopfarm run: %ld of %ld starts committed to %s, %ld zero minima, %ld candidates\n", counts.done,
               counts.total, job.output.database.c_str(), counts.zeros, counts.candidates);
  // Every rank's peak memory, gathered for the record (and the issue's
  // "flat in the number of starts" check).
  const long own_kb = peak_memory_kb();
  std::vector<long> peak_kb(static_cast<size_t>(ranks));
  MPI_Gather(&own_kb, 1, MPI_LONG, peak_kb.data(), 1, MPI_LONG, 0, MPI_COMM_WORLD);
  std::fprintf(stderr,
               "loopfarm run: this session %ld starts in %.1f s on %d ranks (%.3g starts/s); rank 0 coordination "
               "%.3f s (%.2f%% of the wall time, %ld messages); peak memory per rank %.1f MB (rank 0) .. %.1f MB\n",
               counts.done_here, wall_s, ranks, wall_s > 0 ? static_cast<double>(counts.done_here) / wall_s : 0.0,
               coordination_s, wall_s > 0 ? 100.0 * coordination_s / wall_s : 0.0, messages, peak_kb[0] / 1024.0,
               *std::max_element(peak_kb.begin(), peak_kb.end()) / 1024.0);
  if (!complete) {
    std::fprintf(stderr, "loopfarm run: stopped by %s; resume with: %s\n", signal_name(signal).c_str(),
                 resume_command(args, s).c_str());
    return kExitStopped;
  }
  return kExitSuccess;
}

int run_run_command(const RunArguments& args) {
  install_stop_handlers();
  int provided = 0;
  MPI_Init_thread(nullptr, nullptr, MPI_THREAD_FUNNELED, &provided);
  int rank = 0, ranks = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &ranks);
  struct Finalize {
    ~Finalize() { MPI_Finalize(); }
  } finalize;

  // Every rank reads the job (the same file gives the same verdict), so a
  // bad job ends every rank before any collective call.
  std::optional<RunSettings> settings;
  std::exception_ptr failure;
  try {
    settings = read_settings(args);
  } catch (...) {
    failure = std::current_exception();
  }
  if (failure) {
    if (rank == 0) std::rethrow_exception(failure);
    return kExitUsage;
  }
  const RunSettings& s = *settings;
  if (provided < MPI_THREAD_FUNNELED && ranks > 1 && rank == 0) {
    throw EnvironmentError("this MPI provides no MPI_THREAD_FUNNELED; rank 0 cannot compute while it coordinates");
  }

  // Rank 0 opens the database and decides what to run; the verdict goes to
  // every rank (0: go, else the exit code).
  int verdict = 0;
  std::optional<ResultsDatabase> db;
  std::optional<ResumePlan> plan;
  if (rank == 0) {
    try {
      db.emplace(ResultsDatabase::open(s.job.output.database, DatabaseMode::write));
      plan = plan_run(*db, s.job, s.new_run, ranks);
    } catch (const DatabaseError& error) {
      // A database that is not loopfarm's, or holds another job: bad input.
      failure = std::make_exception_ptr(UsageError("database", error.what()));
      verdict = kExitUsage;
    } catch (...) {
      failure = std::current_exception();
      verdict = kExitFailure;
    }
  }
  MPI_Bcast(&verdict, 1, MPI_INT, 0, MPI_COMM_WORLD);
  if (verdict != 0) {
    if (rank == 0) std::rethrow_exception(failure);
    return verdict;
  }
  if (rank != 0) {
    worker_loop(s.job);
    const long own_kb = peak_memory_kb();
    MPI_Gather(&own_kb, 1, MPI_LONG, nullptr, 0, MPI_LONG, 0, MPI_COMM_WORLD);
    // Every rank exits with rank 0's code, so that mpirun passes it on (3
    // for a stopped run) and kills no rank that is still finalising.
    int code = kExitFailure;
    MPI_Bcast(&code, 1, MPI_INT, 0, MPI_COMM_WORLD);
    return code;
  }
  try {
    int code = coordinate(args, s, *db, *plan, ranks);
    MPI_Bcast(&code, 1, MPI_INT, 0, MPI_COMM_WORLD);
    return code;
  } catch (const std::exception& error) {
    try {
      db->end_session(RunStatus::failed);
    } catch (const std::exception&) {
      // The database is what failed; the message below says so.
    }
    if (ranks > 1) {
      // The workers wait for rank 0's answers: end them with the job.
      std::fprintf(stderr, "loopfarm run: %s; aborting all %d ranks (committed starts are kept)\n",
                   one_line(error.what()).c_str(), ranks);
      MPI_Abort(MPI_COMM_WORLD, kExitFailure);
    }
    throw;
  }
}

}  // namespace

Subcommand add_run_command(CLI::App& parent) {
  auto args = std::make_shared<RunArguments>();
  CLI::App* app = parent.add_subcommand(
      "run", "Run a job's starts (alone or under mpirun) into the results database; resumes where it stopped.");
  app->footer(
      "Examples:\n"
      "  loopfarm run jobs/default.toml\n"
      "  mpirun -np 8 loopfarm run jobs/default.toml --db /scratch/default.sqlite\n"
      "Stop with SIGINT, SIGTERM or SIGUSR1 (under mpirun: SIGUSR1): the starts in hand finish and are committed;\n"
      "running the same command again resumes.\n"
      "Exit codes: 0 all starts committed, 1 failure, 2 bad input (job file, options, a database holding another\n"
      "job, not a loopfarm database or damaged: left untouched), 3 stopped by a signal (resumable).\n");
  app->add_option("JOB", args->job, "job file (TOML, see docs/job-file.md)")->required()->type_name("JOB.toml");
  app->add_option("--starts", args->starts, "override [search] starts")->type_name("N");
  app->add_option("--seed", args->seed, "override [search] seed")->type_name("S");
  app->add_option("--db", args->db, "override [output] database")->type_name("PATH");
  app->add_flag("--new-run", args->new_run, "add a new run to a database that holds another job");
  app->add_option("--chunk", args->chunk, "start indices handed out per request")->type_name("K")->capture_default_str();
  app->add_option("--progress", args->progress, "auto (bar on a terminal, else a line every 10 s), bar, log or none")
      ->type_name("STYLE")
      ->capture_default_str();
  return {app, [args] { return run_run_command(*args); }};
}

}  // namespace loopfarm::cli
