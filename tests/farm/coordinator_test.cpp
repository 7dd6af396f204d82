// The farm's coordinator without MPI, through a fake transport: results that
// arrive out of order are committed in start-index order, a stop request in
// the middle of a chunk ends the run with what finished, and a resume runs
// exactly the starts that are missing. The reference is the store fed the same
// records in one commit, in index order. Records are made by hand (no search
// runs), so the runs take milliseconds.
#include "loopfarm/farm/coordinator.hpp"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <deque>
#include <filesystem>
#include <map>
#include <mutex>
#include <regex>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "loopfarm/farm/results_database.hpp"

namespace loopfarm {
namespace {

namespace fs = std::filesystem;

// A record that depends on its index only: every fifth a zero, every seventh
// a verified linkage of one of three canonical geometries (so that
// de-duplication and candidate numbering depend on the commit order).
StartRecord fake_record(std::uint64_t index) {
  StartRecord r;
  r.index = index;
  r.status = "ftol_reached";
  r.E_mean = index % 5 == 0 ? 1e-20 : 1e-3 * static_cast<double>(index + 1);
  r.E_max = 2 * r.E_mean;
  r.objective = r.E_mean;
  r.evaluations = static_cast<int>(index);
  r.seconds = 0.001;
  r.zero = index % 5 == 0;
  r.final_geometry = LoopGeometry::from_degrees(std::vector<double>{1, 2, 1, 2}, std::vector<double>{30, 60, 30, 60},
                                                std::vector<double>{0, 0, 0, 0});
  r.final_angles = JointVector::Zero(4);
  if (index % 7 == 0) {
    r.zero = true;
    r.verified = true;
    const double a = 1.0 + 0.25 * static_cast<double>(index % 3);
    r.candidate.canonical_geometry = LoopGeometry::from_degrees(
        std::vector<double>{a, 1.5, a, 1.5}, std::vector<double>{40, 70, 40, 70}, std::vector<double>{0, 0, 0, 0});
    r.candidate.canonical_key = "k" + std::to_string(index % 3);
    r.candidate.family = "bennett";
    r.candidate.setup = "asymmetric";
    r.candidate.detail = "fake";
    r.candidate.singular_values = {1.0};
  }
  return r;
}

// The runner the coordinator's own thread uses; it remembers what it ran.
// `delay` per start keeps that thread from running every start before the
// fake remote workers have had theirs (a fake record takes a microsecond;
// a loaded machine may not schedule the coordinating thread for longer).
struct RecordingRunner {
  std::mutex mutex;
  std::multiset<std::uint64_t> ran;
  std::chrono::microseconds delay{0};
  StartRunner runner() {
    return [this](std::uint64_t index) {
      if (delay.count() > 0) std::this_thread::sleep_for(delay);
      {
        std::lock_guard lock(mutex);
        ran.insert(index);
      }
      return fake_record(index);
    };
  }
};

// Remote workers that answer in an order of the test's choosing. Each worker
// holds its current chunk; poll() lets the next worker in `order` (cycling)
// that holds work report it: its records, the last one first (out of order
// within a chunk too), or, for the worker told to stop after `stop_after`
// records, those and a stopping request.
class FakeTransport : public CoordinatorTransport {
 public:
  FakeTransport(int workers, RecordingRunner& runner) : chunks_(static_cast<size_t>(workers)), runner_(runner) {
    for (int w = 0; w < workers; ++w) fresh_.push_back(w);
  }
  int remote_workers() const override { return static_cast<int>(chunks_.size()); }

  std::optional<WorkRequest> poll() override {
    // First every worker's opening request, which carries nothing.
    if (!fresh_.empty()) {
      WorkRequest request;
      request.worker = fresh_.back();  // the last worker asks first
      fresh_.pop_back();
      return request;
    }
    // Then, of the workers holding a chunk, the one that got it last.
    if (handed_.empty()) return std::nullopt;
    const int w = handed_.back();
    handed_.pop_back();
    WorkRequest request;
    request.worker = w;
    std::vector<std::uint64_t>& chunk = chunks_[static_cast<size_t>(w)];
    size_t take = chunk.size();
    if (w == stop_worker_ && stop_after_ >= 0) {
      take = std::min(take, static_cast<size_t>(stop_after_));
      request.stopping = true;
      stop_after_ = -1;
    }
    for (size_t i = take; i-- > 0;) {
      {
        std::lock_guard lock(runner_.mutex);
        runner_.ran.insert(chunk[i]);
      }
      request.records.push_back(fake_record(chunk[i]));
    }
    chunk.clear();
    return request;
  }

  void send_work(int worker, const std::vector<std::uint64_t>& chunk) override {
    ++answers_;
    if (chunk.empty()) {
      ++stopped_;
      return;
    }
    chunks_[static_cast<size_t>(worker)] = chunk;
    handed_.push_back(worker);
  }

  // Worker `worker` reports only `records` of its next chunk, with a stop request.
  void stop_mid_chunk(int worker, int records) {
    stop_worker_ = worker;
    stop_after_ = records;
  }
  int stopped() const { return stopped_; }

 private:
  std::vector<std::vector<std::uint64_t>> chunks_;
  std::vector<int> fresh_;
  std::vector<int> handed_;
  RecordingRunner& runner_;
  int stop_worker_ = -1;
  int stop_after_ = -1;
  int answers_ = 0;
  int stopped_ = 0;
};

class CoordinatorTest : public ::testing::Test {
 protected:
  void SetUp() override {
    static int counter = 0;
    dir_ = fs::temp_directory_path() /
           ("loopfarm_coordinator_test_" + std::to_string(getpid()) + "_" + std::to_string(counter++));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    job_.path = "jobs/fake.toml";
    job_.text = "[search]\nstarts = 200\n";
    job_.loop.joints = 4;
    job_.search.starts = kStarts;
    job_.search.seed = 3;
    job_.search.zero_threshold = 1e-12;
    job_.output.report_threshold = 1e-6;
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string file(const std::string& name) const { return (dir_ / name).string(); }

  // What the store holds: the candidates in id order and the counts.
  static std::vector<std::string> contents(const ResultsDatabase& db) {
    std::vector<std::string> out;
    for (const CandidateRow& c : db.candidates({})) {
      out.push_back(std::to_string(c.id) + " " + c.family + " first " + std::to_string(c.first_start) + " hits " +
                    std::to_string(c.hits) + " a1 " + std::to_string(c.a.at(0)));
    }
    const StartCounts counts = db.start_counts();
    out.push_back("starts " + std::to_string(counts.starts) + " zeros " + std::to_string(counts.zeros) + " verified " +
                  std::to_string(counts.verified));
    return out;
  }

  // The reference: every record committed at once, in index order.
  std::vector<std::string> reference() {
    if (!reference_.empty()) return reference_;
    ResultsDatabase db = ResultsDatabase::open(file("reference.sqlite"), DatabaseMode::write);
    const ResumePlan plan = plan_run(db, job_, false, 1);
    std::vector<StartRecord> records;
    for (std::uint64_t i = 0; i < static_cast<std::uint64_t>(kStarts); ++i) records.push_back(fake_record(i));
    db.commit(plan.run_id, records);
    reference_ = contents(db);
    return reference_;
  }

  static constexpr long kStarts = 200;
  std::vector<std::string> reference_;
  fs::path dir_;
  Job job_;
  Progress quiet_{ProgressStyle::none};
};

TEST_F(CoordinatorTest, ResultsOutOfOrderAreCommittedInIndexOrder) {
  ResultsDatabase db = ResultsDatabase::open(file("farm.sqlite"), DatabaseMode::write);
  const ResumePlan plan = plan_run(db, job_, false, 4);
  RecordingRunner runner;
  FakeTransport transport(3, runner);
  StopFlag stop;
  const CoordinatorSummary s = coordinate(db, plan, transport, runner.runner(), 5, stop, quiet_);
  EXPECT_TRUE(s.complete);
  EXPECT_EQ(s.done, kStarts);
  EXPECT_EQ(s.done_here, kStarts);
  EXPECT_EQ(s.total, kStarts);
  EXPECT_FALSE(stop.requested());
  EXPECT_EQ(transport.stopped(), 3);  // every worker was sent home
  // Every start ran once, between the coordinator's thread and the workers.
  EXPECT_EQ(runner.ran.size(), static_cast<size_t>(kStarts));
  EXPECT_EQ(std::set<std::uint64_t>(runner.ran.begin(), runner.ran.end()).size(), static_cast<size_t>(kStarts));
  EXPECT_EQ(contents(db), reference());
  EXPECT_EQ(s.zeros, db.start_counts().zeros);
  EXPECT_EQ(s.candidates, db.candidate_count());
  EXPECT_EQ(db.runs().at(0).status, "complete");
}

// Progress counts a start when its record reaches the coordinator: with
// every update logged, the lines before the last show starts done while the
// run's records still wait for their batch (committed every 8,192 starts or
// 2 s: once, at the end, in a run of milliseconds).
TEST_F(CoordinatorTest, ProgressCountsStartsAsTheirRecordsArrive) {
  ResultsDatabase db = ResultsDatabase::open(file("farm.sqlite"), DatabaseMode::write);
  const ResumePlan plan = plan_run(db, job_, false, 4);
  RecordingRunner runner;
  FakeTransport transport(3, runner);
  StopFlag stop;
  char* buffer = nullptr;
  size_t size = 0;
  std::FILE* out = open_memstream(&buffer, &size);
  ASSERT_NE(out, nullptr);
  CoordinatorSummary s;
  {
    Progress every_update(ProgressStyle::log, 0.0, out);
    s = coordinate(db, plan, transport, runner.runner(), 5, stop, every_update);
  }
  std::fclose(out);
  const std::string log(buffer, size);
  std::free(buffer);
  ASSERT_TRUE(s.complete);
  std::vector<long> done, zeros;
  const std::regex pattern(R"(loopfarm run: ([0-9,]+)/200 starts .* ([0-9,]+) zero minima)");
  for (auto it = std::sregex_iterator(log.begin(), log.end(), pattern); it != std::sregex_iterator(); ++it) {
    auto number = [](std::string text) {
      text.erase(std::remove(text.begin(), text.end(), ','), text.end());
      return std::stol(text);
    };
    done.push_back(number((*it)[1].str()));
    zeros.push_back(number((*it)[2].str()));
  }
  ASSERT_GE(done.size(), 3u) << log;
  EXPECT_TRUE(std::is_sorted(done.begin(), done.end())) << log;
  EXPECT_EQ(done.back(), kStarts);
  EXPECT_EQ(zeros.back(), s.zeros);
  // Before the last (forced) line: starts and zeros counted, not yet committed.
  EXPECT_GT(*std::max_element(done.begin(), done.end() - 1), 0) << log;
  EXPECT_GT(*std::max_element(zeros.begin(), zeros.end() - 1), 0) << log;
}

TEST_F(CoordinatorTest, AStopMidChunkKeepsWhatFinishedAndAResumeRunsExactlyTheRest) {
  const std::string path = file("farm.sqlite");
  std::set<std::uint64_t> first_session;
  {
    ResultsDatabase db = ResultsDatabase::open(path, DatabaseMode::write);
    const ResumePlan plan = plan_run(db, job_, false, 3);
    RecordingRunner runner;
    runner.delay = std::chrono::milliseconds(1);  // the stop must find starts still to run
    FakeTransport transport(2, runner);
    transport.stop_mid_chunk(0, 2);  // worker 0 reports 2 of its first 8 and asks to stop
    StopFlag stop;
    const CoordinatorSummary s = coordinate(db, plan, transport, runner.runner(), 8, stop, quiet_);
    EXPECT_FALSE(s.complete);
    EXPECT_TRUE(stop.requested());
    EXPECT_LT(s.done, kStarts);
    EXPECT_GE(s.done, 2);
    EXPECT_EQ(transport.stopped(), 2);
    EXPECT_EQ(db.runs().at(0).status, "stopped");
    EXPECT_EQ(db.start_counts().starts, s.done);
    first_session.insert(runner.ran.begin(), runner.ran.end());
    // Worker 0's chunk was 8 indices; 6 of them were never reported.
    EXPECT_EQ(static_cast<long>(first_session.size()), s.done);
  }
  ResultsDatabase db = ResultsDatabase::open(path, DatabaseMode::write);
  const ResumePlan plan = plan_run(db, job_, false, 3);
  EXPECT_EQ(plan.committed, static_cast<long>(first_session.size()));
  RecordingRunner runner;
  FakeTransport transport(2, runner);
  StopFlag stop;
  const CoordinatorSummary s = coordinate(db, plan, transport, runner.runner(), 8, stop, quiet_);
  EXPECT_TRUE(s.complete);
  EXPECT_EQ(s.done, kStarts);
  EXPECT_EQ(s.done_here, kStarts - static_cast<long>(first_session.size()));
  // Exactly the missing starts ran, each once.
  std::set<std::uint64_t> missing;
  for (std::uint64_t i = 0; i < static_cast<std::uint64_t>(kStarts); ++i) {
    if (!first_session.count(i)) missing.insert(i);
  }
  EXPECT_EQ(runner.ran.size(), missing.size());
  EXPECT_EQ(std::set<std::uint64_t>(runner.ran.begin(), runner.ran.end()), missing);
  EXPECT_EQ(contents(db).back(), reference().back());  // the same starts, zeros and verified
  // Candidates: the same linkages with the same representatives and hits
  // (their ids follow the commit order, which the stop changed).
  auto without_ids = [](std::vector<std::string> rows) {
    for (std::string& r : rows) r = r.substr(r.find(' ') + 1);
    std::sort(rows.begin(), rows.end());
    return rows;
  };
  EXPECT_EQ(without_ids(contents(db)), without_ids(reference()));
  EXPECT_EQ(db.runs().at(0).status, "complete");
}

TEST_F(CoordinatorTest, AStopBeforeAnythingRunsCommitsNothingAndEndsStopped) {
  ResultsDatabase db = ResultsDatabase::open(file("farm.sqlite"), DatabaseMode::write);
  const ResumePlan plan = plan_run(db, job_, false, 2);
  RecordingRunner runner;
  FakeTransport transport(1, runner);
  StopFlag stop;
  stop.request(SIGUSR1);
  const CoordinatorSummary s = coordinate(db, plan, transport, runner.runner(), 4, stop, quiet_);
  EXPECT_FALSE(s.complete);
  EXPECT_EQ(s.done, 0);
  EXPECT_TRUE(runner.ran.empty());
  EXPECT_EQ(transport.stopped(), 1);
  EXPECT_EQ(stop.signal(), SIGUSR1);
  EXPECT_EQ(db.runs().at(0).status, "stopped");
}

TEST(WorkQueue, PendingCursorWalksTheGapsBetweenCommittedRanges) {
  PendingCursor cursor({{0, 3}, {5, 6}, {8, 20}}, 12);
  std::vector<std::uint64_t> seen;
  for (; !cursor.done(); cursor.advance()) seen.push_back(cursor.peek());
  EXPECT_EQ(seen, (std::vector<std::uint64_t>{3, 4, 6, 7}));
  EXPECT_EQ(PendingCursor({{0, 3}, {5, 6}, {8, 20}}, 12).count(), 4u);
  EXPECT_TRUE(PendingCursor({{0, 10}}, 10).done());
  EXPECT_EQ(PendingCursor({}, 3).count(), 3u);
}

TEST(WorkQueue, PendingCursorOfASliceWalksOnlyItsRange) {
  // Slice [10, 20) of a run whose starts 12, 13 and 25 are committed.
  PendingCursor cursor({{12, 14}, {25, 26}}, IndexRange{10, 20});
  std::vector<std::uint64_t> seen;
  for (; !cursor.done(); cursor.advance()) seen.push_back(cursor.peek());
  EXPECT_EQ(seen, (std::vector<std::uint64_t>{10, 11, 14, 15, 16, 17, 18, 19}));
  EXPECT_TRUE(PendingCursor({{0, 40}}, IndexRange{10, 20}).done());
  EXPECT_TRUE(PendingCursor({}, IndexRange{7, 7}).done());  // an empty slice
}

TEST(WorkQueue, OrderedCommitsHoldBackWhatArrivesEarly) {
  OrderedCommits commits(PendingCursor({{2, 3}}, 6));  // pending 0, 1, 3, 4, 5
  commits.add(fake_record(3));
  commits.add(fake_record(1));
  EXPECT_TRUE(commits.ready().empty());  // 0 is missing
  commits.add(fake_record(0));
  std::vector<std::uint64_t> ready;
  for (const StartRecord& r : commits.ready()) ready.push_back(r.index);
  EXPECT_EQ(ready, (std::vector<std::uint64_t>{0, 1, 3}));
  commits.add(fake_record(5));
  EXPECT_TRUE(commits.ready().empty());  // 4 is missing
  std::vector<std::uint64_t> rest;
  for (const StartRecord& r : commits.all()) rest.push_back(r.index);
  EXPECT_EQ(rest, (std::vector<std::uint64_t>{5}));
}

TEST(WorkQueue, ADispenserHandsOutChunksInOrderAndNothingAfterAStop) {
  StopFlag stop;
  Dispenser dispenser(PendingCursor({{1, 2}}, 7), 3, 1, stop);
  EXPECT_EQ(dispenser.take(), (std::vector<std::uint64_t>{0, 2, 3}));  // 6 left: at most 3
  EXPECT_EQ(dispenser.take(), (std::vector<std::uint64_t>{4}));        // 3 left: 1
  EXPECT_EQ(dispenser.take(), (std::vector<std::uint64_t>{5}));
  EXPECT_EQ(dispenser.take(), (std::vector<std::uint64_t>{6}));
  EXPECT_TRUE(dispenser.take().empty());
  Dispenser stopped(PendingCursor({}, 7), 3, 1, stop);
  stop.request(SIGINT);
  EXPECT_TRUE(stopped.take().empty());
  stop.request(SIGTERM);
  EXPECT_EQ(stop.signal(), SIGINT);  // the first request is remembered
}

// Chunks of at most `chunk`, and of at most 1 / (2 workers) of what is left:
// every index once, in order, large chunks first, single indices at the end.
TEST(WorkQueue, ADispenserShrinksItsChunksAsTheRunEnds) {
  StopFlag stop;
  Dispenser dispenser(PendingCursor({}, 1000), 64, 2, stop);
  std::vector<size_t> sizes;
  std::uint64_t next = 0;
  for (std::vector<std::uint64_t> chunk = dispenser.take(); !chunk.empty(); chunk = dispenser.take()) {
    for (std::uint64_t index : chunk) EXPECT_EQ(index, next++);
    sizes.push_back(chunk.size());
  }
  EXPECT_EQ(next, 1000u);
  ASSERT_GE(sizes.size(), 4u);
  EXPECT_EQ(sizes.front(), 64u);                              // 1000 / 4 = 250 left per share: the cap
  EXPECT_TRUE(std::is_sorted(sizes.rbegin(), sizes.rend()));  // never growing
  EXPECT_EQ(sizes.back(), 1u);
  // A run smaller than the workers' chunks is shared: 24 starts, 2 workers.
  Dispenser small(PendingCursor({}, 24), 64, 2, stop);
  EXPECT_EQ(small.take().size(), 6u);
  EXPECT_EQ(small.take().size(), 4u);
  EXPECT_THROW(Dispenser(PendingCursor({}, 24), 0, 2, stop), std::invalid_argument);
}

}  // namespace
}  // namespace loopfarm
