// The farm's coordinator (coordinator.hpp).
#include "loopfarm/farm/coordinator.hpp"

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <csignal>
#include <cstdio>
#include <exception>
#include <limits>
#include <mutex>
#include <string>
#include <thread>

#include "loopfarm/search/start.hpp"

namespace loopfarm {
namespace {

// A commit when this many records are in order, or 2 s after the last one:
// large transactions write each page they touch once (the random inserts
// into the candidates' indexes touch a page per row in small ones), and a
// crash loses at most 2 s of work, which a resume runs again.
constexpr size_t kCommitBatch = 8192;
constexpr auto kCommitInterval = std::chrono::seconds(2);

// `text` on one line: line ends and tabs become spaces, trailing ones go.
std::string one_line(std::string text) {
  for (char& c : text) {
    if (c == '\n' || c == '\r' || c == '\t') c = ' ';
  }
  while (!text.empty() && text.back() == ' ') text.pop_back();
  return text;
}

// The coordinator's own worker: a thread that takes chunks like any worker
// and leaves its records for the coordinating thread (which alone talks to
// the transport: MPI_THREAD_FUNNELED).
class LocalWorker {
 public:
  LocalWorker(const StartRunner& run, Dispenser& dispenser, const StopFlag& stop)
      : thread_([this, &run, &dispenser, &stop] {
          for (;;) {
            const std::vector<std::uint64_t> chunk = dispenser.take();
            if (chunk.empty()) break;
            for (std::uint64_t index : chunk) {
              if (stop.requested()) break;
              StartRecord record = run(index);
              std::lock_guard lock(mutex_);
              done_.push_back(std::move(record));
            }
          }
          finished_.store(true);
        }) {}
  ~LocalWorker() { thread_.join(); }
  LocalWorker(const LocalWorker&) = delete;
  LocalWorker& operator=(const LocalWorker&) = delete;
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

// Commits batches on a thread of its own, so that the coordinating thread
// goes on answering workers, decoding and ordering records while SQLite
// writes: the two halves of rank 0's work overlap. It holds one batch at a
// time; handing over the next waits until the last is committed, so ingest
// runs at the writer's pace and at most two batches are in memory. The
// database is used by this thread alone from construction to destruction. A
// failed commit ends the thread and is rethrown on the coordinating thread by
// the next call.
class BatchWriter {
 public:
  BatchWriter(ResultsDatabase& db, std::int64_t run_id) : db_(db), run_id_(run_id), thread_([this] { write(); }) {}
  // Commits the batch in hand, if any, then joins.
  ~BatchWriter() {
    {
      std::lock_guard lock(mutex_);
      closing_ = true;
    }
    changed_.notify_all();
    thread_.join();
  }
  BatchWriter(const BatchWriter&) = delete;
  BatchWriter& operator=(const BatchWriter&) = delete;

  // Hands `batch` over; it comes back empty (with the capacity of the last one).
  void submit(std::vector<StartRecord>& batch) {
    std::unique_lock lock(mutex_);
    wait_until_idle(lock);
    in_hand_.swap(batch);
    busy_ = true;
    changed_.notify_all();
  }
  // Returns once everything handed over is committed.
  void drain() {
    std::unique_lock lock(mutex_);
    wait_until_idle(lock);
  }
  // The commits finished since the last call, summed.
  CommitSummary take_committed() {
    std::lock_guard lock(mutex_);
    if (failure_) std::rethrow_exception(failure_);
    const CommitSummary out = committed_;
    committed_ = CommitSummary();
    return out;
  }
  // Seconds spent committing, and waiting for it on the coordinating thread.
  double writing_s() {
    std::lock_guard lock(mutex_);
    return writing_s_;
  }
  double waiting_s() const { return waiting_s_; }

 private:
  void wait_until_idle(std::unique_lock<std::mutex>& lock) {
    const auto begin = std::chrono::steady_clock::now();
    changed_.wait(lock, [this] { return !busy_ || failure_; });
    waiting_s_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - begin).count();
    if (failure_) std::rethrow_exception(failure_);
  }

  void write() {
    std::unique_lock lock(mutex_);
    for (;;) {
      changed_.wait(lock, [this] { return busy_ || closing_; });
      if (!busy_) return;
      lock.unlock();
      const auto begin = std::chrono::steady_clock::now();
      CommitSummary c;
      std::exception_ptr error;
      try {
        c = db_.commit(run_id_, in_hand_);
      } catch (...) {
        error = std::current_exception();
      }
      in_hand_.clear();
      lock.lock();
      writing_s_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - begin).count();
      committed_.starts += c.starts;
      committed_.zeros += c.zeros;
      committed_.new_candidates += c.new_candidates;
      committed_.repeat_hits += c.repeat_hits;
      failure_ = error;
      busy_ = false;
      changed_.notify_all();
      if (failure_) return;
    }
  }

  ResultsDatabase& db_;
  const std::int64_t run_id_;
  std::mutex mutex_;
  std::condition_variable changed_;
  std::vector<StartRecord> in_hand_;
  bool busy_ = false;  // in_hand_ is being (or about to be) committed
  bool closing_ = false;
  std::exception_ptr failure_;
  CommitSummary committed_;
  double writing_s_ = 0.0;
  double waiting_s_ = 0.0;  // the coordinating thread's alone
  std::thread thread_;      // last: started once the members above exist
};

}  // namespace

StartRecord run_start_record(const Job& job, std::uint64_t index) {
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

ResumePlan plan_run(ResultsDatabase& db, const Job& job, bool new_run, int ranks,
                    const std::optional<StartSlice>& slice) {
  RunIdentity identity;
  identity.job_path = job.path;
  identity.job_text = job.text;
  identity.seed = job.search.seed;
  identity.starts = static_cast<std::uint64_t>(job.search.starts);
  identity.joints = job.loop.joints;
  identity.zero_threshold = job.search.zero_threshold;
  identity.report_threshold = job.output.report_threshold;
  identity.slice = slice;
  const RunInfo run = db.open_run(identity, new_run);
  const IndexRange range = slice_range(slice, identity.starts);
  ResumePlan plan;
  plan.run_id = run.run_id;
  plan.pending = PendingCursor(run.committed, range);
  plan.starts = static_cast<long>(range.last - range.first);
  plan.committed = static_cast<long>(range.last - range.first - plan.pending.count());
  plan.zeros = static_cast<long>(db.start_counts(run.run_id).zeros);
  plan.candidates = static_cast<long>(db.candidate_count());
  db.begin_session(run.run_id, ranks);
  return plan;
}

CoordinatorSummary coordinate(ResultsDatabase& db, const ResumePlan& plan, CoordinatorTransport& transport,
                              const StartRunner& run, int chunk, StopFlag& stop, Progress& progress) {
  using Clock = std::chrono::steady_clock;
  Dispenser dispenser(plan.pending, chunk, transport.remote_workers() + 1, stop);
  OrderedCommits commits(plan.pending);
  ProgressCounts counts;
  counts.total = plan.starts;
  counts.done = plan.committed;
  counts.zeros = plan.zeros;
  counts.candidates = plan.candidates;
  if (plan.committed > 0) {
    progress.message("resuming run " + std::to_string(plan.run_id) + " of " + db.path() + ": " +
                     std::to_string(plan.committed) + " of " + std::to_string(counts.total) +
                     " starts already committed");
  }

  CoordinatorSummary summary;
  const auto session_start = Clock::now();
  std::vector<StartRecord> batch;
  batch.reserve(kCommitBatch);
  auto last_commit = Clock::now();
  std::optional<BatchWriter> writer(std::in_place, db, plan.run_id);
  auto flush = [&](bool force) {
    const auto now = Clock::now();
    if (batch.empty()) return;
    if (!force && batch.size() < kCommitBatch && now - last_commit < kCommitInterval) return;
    writer->submit(batch);
    last_commit = now;
  };
  auto count_commits = [&] {
    const CommitSummary c = writer->take_committed();
    counts.done += c.starts;
    counts.done_here += c.starts;
    counts.zeros += c.zeros;
    counts.candidates += c.new_candidates;
  };
  // Progress counts a start when its record arrives, not when its batch is
  // committed (every 8,192 starts or 2 s); candidates are known only once
  // committed (de-duplication).
  long arrived = 0, arrived_zeros = 0;
  auto arrive = [&](StartRecord& r) {
    ++arrived;
    arrived_zeros += r.zero ? 1 : 0;
    commits.add(std::move(r));
  };
  auto show_progress = [&] {
    ProgressCounts shown = counts;
    shown.done = plan.committed + arrived;
    shown.done_here = arrived;
    shown.zeros = plan.zeros + arrived_zeros;
    progress.update(shown);
  };

  int active_workers = transport.remote_workers();
  {
    LocalWorker local(run, dispenser, stop);
    // Destroyed before `local` joins its thread: on an exception (a failed
    // commit) the thread stops after its current start instead of running on.
    struct StopOnUnwind {
      StopFlag& stop;
      ~StopOnUnwind() {
        if (std::uncaught_exceptions() > 0) stop.request(-1);
      }
    } stop_on_unwind{stop};
    while (active_workers > 0 || !local.finished()) {
      const auto work_start = Clock::now();
      std::optional<WorkRequest> request = transport.poll();
      if (request) {
        ++summary.messages;
        // A worker that caught a signal stops the whole run.
        if (request->stopping) stop.request(SIGUSR1);
        for (StartRecord& r : request->records) arrive(r);
        const std::vector<std::uint64_t> work = dispenser.take();
        transport.send_work(request->worker, work);
        if (work.empty()) --active_workers;
      }
      for (StartRecord& r : local.collect()) arrive(r);
      commits.move_ready(batch);
      flush(false);
      count_commits();
      show_progress();
      summary.coordination_s += std::chrono::duration<double>(Clock::now() - work_start).count();
      if (!request) std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
    // What the thread finished between the last collect and its end.
    for (StartRecord& r : local.collect()) commits.add(std::move(r));
  }
  commits.move_all(batch);
  flush(true);
  writer->drain();
  count_commits();
  // The coordination's cost: this thread's work, less its waits for the
  // writer, and the writer's.
  summary.coordination_s += writer->writing_s() - writer->waiting_s();
  writer.reset();  // the database is this thread's again
  progress.update(counts, true);
  progress.finish();

  summary.total = counts.total;
  summary.done = counts.done;
  summary.done_here = counts.done_here;
  summary.zeros = counts.zeros;
  summary.candidates = counts.candidates;
  summary.complete = counts.done >= counts.total;
  db.end_session(summary.complete ? RunStatus::complete : RunStatus::stopped);
  summary.wall_s = std::chrono::duration<double>(Clock::now() - session_start).count();
  return summary;
}

}  // namespace loopfarm
