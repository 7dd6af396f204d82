// How fast rank 0 ingests: the coordinator (coordinate) fed by a fake
// transport with synthetic start records of the default job's real mix, written
// by the store into a database on disk in WAL mode, without MPI.
//
//   build/release/bench/loopfarm_bench --benchmark_filter='BM_(Ingest|Commit)'
//
// The mix is that of 6,000 starts of jobs/default.toml (loopfarm run
// jobs/default.toml --starts 6000): 40.65 % zero minima, every one verified,
// with a candidate whose fields look like the real ones (a Bennett loop, twelve
// singular values, a canonical key of ~100 characters); 0.2 % of the verified
// starts find a linkage already stored (the job's rate of repeated
// candidates); the geometry columns filled for the zeros (E_mean below the
// report threshold), empty for the rest, as in the real database.
//
// Every chunk of records reaches the coordinator as the bytes a worker sends
// (encode_records, done before the clock starts) and is decoded in poll(), as
// the MPI transport does. The coordinator's own compute thread runs the same
// records at 1 ms a start (a real start takes ~2.5 ms), so that it takes a
// small share as on a cluster.
//
// Counters: starts_per_s (starts committed per second of coordinate(), from
// its first request to the session's end), us_per_start, cpu_us_per_start
// (the process's CPU time over the same span: every thread of rank 0; on a
// busy machine steadier than the wall time), candidates. BM_Commit times the
// store alone on the same records. Figures are in docs/performance.md.
#include <benchmark/benchmark.h>

#include <time.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "loopfarm/farm/coordinator.hpp"
#include "loopfarm/farm/results.hpp"
#include "loopfarm/farm/results_database.hpp"
#include "loopfarm/farm/work_queue.hpp"
#include "loopfarm/search/job.hpp"

namespace loopfarm {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kRadiansPerDegree = kPi / 180.0;

// The default job's mix, from its 6,000 starts.
constexpr double kZeroFraction = 2439.0 / 6000.0;  // zero minima, all verified
constexpr double kRepeatFraction = 5.0 / 2439.0;   // verified starts that hit a stored linkage
constexpr std::uint64_t kRepeatedLinkages = 64;    // the linkages those repeats fall on
constexpr double kZeroStopvalFraction = 2367.0 / 2439.0;
constexpr double kNonzeroFtolFraction = 3318.0 / 3561.0;
constexpr int kChunk = 64;  // loopfarm run's default --chunk

// splitmix64: a record depends on its index alone.
std::uint64_t mix(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

class Draws {
 public:
  explicit Draws(std::uint64_t seed) : state_(seed) {}
  double uniform() {  // [0, 1)
    state_ = mix(state_);
    return static_cast<double>(state_ >> 11) * 0x1.0p-53;
  }
  double between(double lo, double hi) { return lo + (hi - lo) * uniform(); }
  std::uint64_t integer() { return state_ = mix(state_); }

 private:
  std::uint64_t state_;
};

LoopGeometry random_geometry(Draws& draws) {
  LoopGeometry g;
  g.a.resize(4);
  g.alpha.resize(4);
  g.d.resize(4);
  for (int i = 0; i < 4; ++i) {
    g.a[i] = draws.between(0.5, 5.0);
    g.alpha[i] = draws.between(10.0, 170.0) * kRadiansPerDegree;
    g.d[i] = draws.between(-1.0, 1.0);
  }
  return g;
}

// A verified Bennett loop as the search reports it: alternate links equal,
// offsets zero up to rounding, its canonical key from the quantised geometry.
CandidateRecord bennett_candidate(std::uint64_t linkage) {
  Draws draws(linkage ^ 0x5bd1e9955bd1e995ull);
  CandidateRecord c;
  c.family = "bennett";
  c.setup = "asymmetric";
  c.detail = "asymmetric setup";
  const double a0 = draws.between(0.5, 1.5), a1 = draws.between(0.5, 1.5);
  const double t0 = draws.between(-kPi, kPi), t1 = draws.between(-kPi, kPi);
  LoopGeometry& g = c.canonical_geometry;
  g.a.resize(4);
  g.alpha.resize(4);
  g.d.resize(4);
  for (int i = 0; i < 4; ++i) {
    g.a[i] = i % 2 == 0 ? a0 : a1;
    g.alpha[i] = i % 2 == 0 ? t0 : t1;
    g.d[i] = draws.between(-3e-16, 3e-16);
  }
  char key[160];
  std::snprintf(key, sizeof key, "4R a=%.6f,%.6f,%.6f,%.6f alpha=%.6f,%.6f,%.6f,%.6f d=0,0,0,0", a0, a1, a0, a1, t0, t1,
                t0, t1);
  c.canonical_key = key;
  c.family_residual = draws.between(-1e-16, 1e-16);
  c.bennett_residual = c.family_residual;
  c.planar_residual = draws.between(0.2, 1.2);
  c.spherical_residual = draws.between(0.5, 1.5);
  c.trivial_residual = std::numeric_limits<double>::infinity();  // no frozen joint: NULL
  c.rigid_residual = draws.between(1e-16, 2e-15);
  c.full_turn = true;
  c.range_lo_deg = draws.between(-180.0, 180.0);
  c.range_hi_deg = c.range_lo_deg + 360.0;
  c.local_dimension = 3;
  c.free_parameters = 12;
  double s = 0.9;
  for (int i = 0; i < 9; ++i) c.singular_values.push_back(s *= draws.between(0.6, 1.0));
  for (int i = 0; i < 3; ++i) c.singular_values.push_back(std::pow(10.0, draws.between(-17.0, -14.0)));
  return c;
}

StartRecord synthetic_record(std::uint64_t index) {
  Draws draws(index);
  StartRecord r;
  r.index = index;
  r.zero = draws.uniform() < kZeroFraction;
  r.verified = r.zero;
  r.evaluations = 10 + static_cast<int>(draws.integer() % 20);
  r.seconds = draws.between(0.001, 0.003);
  r.final_geometry = random_geometry(draws);
  r.final_angles.resize(4);
  for (int i = 0; i < 4; ++i) r.final_angles[i] = draws.between(-kPi, kPi);
  if (r.zero) {
    r.status = draws.uniform() < kZeroStopvalFraction ? "stopval_reached" : "xtol_reached";
    r.E_mean = std::pow(10.0, draws.between(-33.0, -26.3));
    r.E_max = 2 * r.E_mean;
    r.objective = 10 * r.E_mean;
    // A repeat falls on one of a few linkages (the real ones are loops on a
    // bound of the space); the rest are new linkages of their own.
    const bool repeat = draws.uniform() < kRepeatFraction;
    r.candidate = bennett_candidate(repeat ? (1ull << 63) | (draws.integer() % kRepeatedLinkages) : index);
  } else {
    r.status = draws.uniform() < kNonzeroFtolFraction ? "ftol_reached" : "xtol_reached";
    r.E_mean = std::pow(10.0, draws.between(-5.7, 0.05));
    r.E_max = 1.5 * r.E_mean;
    r.objective = 10 * r.E_mean;
  }
  return r;
}

// CPU time of the process: the coordinating thread, the writer's and the
// coordinator's own compute thread (asleep nearly all the time).
double process_cpu_seconds() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

// The chunks a run of `starts` hands out to `workers` workers, the local one
// included: the dispenser's sizes depend on what is left alone, not on who
// takes them, so they are known before the run.
std::vector<std::vector<std::uint64_t>> chunks_of_a_run(std::uint64_t starts, int workers) {
  StopFlag never;
  Dispenser dispenser(PendingCursor({}, starts), kChunk, workers, never);
  std::vector<std::vector<std::uint64_t>> chunks;
  for (std::vector<std::uint64_t> c = dispenser.take(); !c.empty(); c = dispenser.take()) chunks.push_back(c);
  return chunks;
}

// Workers that each hold one chunk and return its records, already encoded,
// with their next request; round robin, every request at once (a cluster
// whose workers are all waiting on rank 0). `first_chunk` maps a chunk's
// first start index to its number in `encoded_chunks`.
class SyntheticWorkers : public CoordinatorTransport {
 public:
  SyntheticWorkers(int workers, const std::vector<std::string>& encoded_chunks,
                   const std::map<std::uint64_t, long>& first_chunk)
      : chunks_(encoded_chunks), first_chunk_(first_chunk), held_(static_cast<size_t>(workers), kIdle) {}
  int remote_workers() const override { return static_cast<int>(held_.size()); }
  std::optional<WorkRequest> poll() override {
    for (size_t tried = 0; tried < held_.size(); ++tried) {
      const size_t worker = next_;
      next_ = (next_ + 1) % held_.size();
      if (held_[worker] == kStopped) continue;
      WorkRequest request;
      request.worker = static_cast<int>(worker);
      if (held_[worker] != kIdle) request.records = decode_records(chunks_[static_cast<size_t>(held_[worker])]);
      return request;
    }
    return std::nullopt;
  }
  void send_work(int worker, const std::vector<std::uint64_t>& chunk) override {
    auto& held = held_[static_cast<size_t>(worker)];
    if (chunk.empty()) {
      held = kStopped;
      return;
    }
    const auto it = first_chunk_.find(chunk.front());
    if (it == first_chunk_.end()) throw std::logic_error("SyntheticWorkers: a chunk the run does not hand out");
    held = it->second;
  }

 private:
  static constexpr long kIdle = -1;
  static constexpr long kStopped = -2;
  const std::vector<std::string>& chunks_;
  const std::map<std::uint64_t, long>& first_chunk_;
  std::vector<long> held_;  // the chunk number a worker holds, or kIdle / kStopped
  size_t next_ = 0;
};

// Args: starts, remote workers.
void BM_Ingest(benchmark::State& state) {
  const auto starts = static_cast<std::uint64_t>(state.range(0));
  const int workers = static_cast<int>(state.range(1));
  std::vector<std::string> encoded_chunks;
  std::map<std::uint64_t, long> first_chunk;
  for (const std::vector<std::uint64_t>& chunk : chunks_of_a_run(starts, workers + 1)) {
    std::vector<StartRecord> records;
    for (std::uint64_t i : chunk) records.push_back(synthetic_record(i));
    first_chunk[chunk.front()] = static_cast<long>(encoded_chunks.size());
    encode_records(records, encoded_chunks.emplace_back());
  }
  Job job;
  job.path = "synthetic.toml";
  job.text = "synthetic ingest";
  job.loop.joints = 4;
  job.search.seed = 1;
  job.search.starts = static_cast<long>(starts);
  job.search.zero_threshold = 1e-20;
  job.output.report_threshold = 1e-6;
  const std::filesystem::path directory = std::filesystem::temp_directory_path();
  const std::string path = (directory / ("loopfarm_bench_ingest_" + std::to_string(::getpid()) + ".sqlite")).string();
  auto remove_database = [&path] {
    for (const char* suffix : {"", "-wal", "-shm"}) std::filesystem::remove(path + suffix);
  };

  double seconds = 0.0, cpu_seconds = 0.0;
  std::uint64_t committed = 0;
  long candidates = 0;
  for (auto _ : state) {
    remove_database();
    CoordinatorSummary summary;
    {
      ResultsDatabase db = ResultsDatabase::open(path, DatabaseMode::write);
      const ResumePlan plan = plan_run(db, job, false, workers + 1);
      SyntheticWorkers transport(workers, encoded_chunks, first_chunk);
      StopFlag stop;
      Progress progress(ProgressStyle::none);
      const StartRunner local = [](std::uint64_t index) {
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
        return synthetic_record(index);
      };
      const auto begin = std::chrono::steady_clock::now();
      const double cpu_begin = process_cpu_seconds();
      summary = coordinate(db, plan, transport, local, kChunk, stop, progress);
      cpu_seconds += process_cpu_seconds() - cpu_begin;
      const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - begin).count();
      state.SetIterationTime(elapsed);
      seconds += elapsed;
    }
    if (!summary.complete || static_cast<std::uint64_t>(summary.done_here) != starts) {
      state.SkipWithError("the run did not commit every start");
      break;
    }
    committed += static_cast<std::uint64_t>(summary.done_here);
    candidates = summary.candidates;
  }
  remove_database();
  state.counters["starts_per_s"] = static_cast<double>(committed) / seconds;
  state.counters["us_per_start"] = 1e6 * seconds / static_cast<double>(committed);
  state.counters["cpu_us_per_start"] = 1e6 * cpu_seconds / static_cast<double>(committed);
  state.counters["candidates"] = static_cast<double>(candidates);
}

BENCHMARK(BM_Ingest)->Args({200000, 64})->UseManualTime()->Iterations(1)->Unit(benchmark::kMillisecond);

// The store alone: the same records, already decoded and in order, committed
// by ResultsDatabase::commit in transactions of 8,192 starts (the writer
// thread's batches) on the calling thread. What SQLite and the store's
// de-duplication cost a start, without the coordinator: the bound on what one
// writer can ingest. Args: starts.
void BM_Commit(benchmark::State& state) {
  const auto starts = static_cast<std::uint64_t>(state.range(0));
  constexpr size_t kBatch = 8192;
  std::vector<std::vector<StartRecord>> batches;
  for (std::uint64_t i = 0; i < starts; ++i) {
    if (i % kBatch == 0) batches.emplace_back().reserve(kBatch);
    batches.back().push_back(synthetic_record(i));
  }
  RunIdentity identity;
  identity.job_path = "synthetic.toml";
  identity.job_text = "synthetic commit";
  identity.seed = 1;
  identity.starts = starts;
  identity.joints = 4;
  identity.zero_threshold = 1e-20;
  identity.report_threshold = 1e-6;
  const std::string path =
      (std::filesystem::temp_directory_path() / ("loopfarm_bench_commit_" + std::to_string(::getpid()) + ".sqlite"))
          .string();
  auto remove_database = [&path] {
    for (const char* suffix : {"", "-wal", "-shm"}) std::filesystem::remove(path + suffix);
  };

  double seconds = 0.0;
  std::uint64_t committed = 0;
  long candidates = 0;
  for (auto _ : state) {
    remove_database();
    ResultsDatabase db = ResultsDatabase::open(path, DatabaseMode::write);
    const std::int64_t run = db.open_run(identity).run_id;
    db.begin_session(run, 1);
    long new_candidates = 0;
    const auto begin = std::chrono::steady_clock::now();
    for (const std::vector<StartRecord>& batch : batches) {
      const CommitSummary summary = db.commit(run, batch);
      committed += static_cast<std::uint64_t>(summary.starts);
      new_candidates += summary.new_candidates;
    }
    const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - begin).count();
    state.SetIterationTime(elapsed);
    seconds += elapsed;
    db.end_session(RunStatus::complete);
    candidates = new_candidates;
  }
  remove_database();
  state.counters["starts_per_s"] = static_cast<double>(committed) / seconds;
  state.counters["us_per_start"] = 1e6 * seconds / static_cast<double>(committed);
  state.counters["candidates"] = static_cast<double>(candidates);
}

BENCHMARK(BM_Commit)->Arg(200000)->UseManualTime()->Iterations(1)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace loopfarm
