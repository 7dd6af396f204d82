// The farm over MPI, run by CTest under `mpirun -np 2`: a test program with
// its own main, every test collective over MPI_COMM_WORLD. Two ranks write
// what one process writes; a run stopped by a request on a worker rank ends
// `stopped` on every rank and its resume completes it; a larger target
// resumes a finished run. The reference is the store fed every start's record
// in one commit, on rank 0.
#include <mpi.h>
#include <unistd.h>

#include <algorithm>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "loopfarm/farm/coordinator.hpp"
#include "loopfarm/farm/farm.hpp"
#include "loopfarm/farm/results_database.hpp"
#include "loopfarm/search/job.hpp"

namespace loopfarm {
namespace {

namespace fs = std::filesystem;

int rank() {
  int r = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &r);
  return r;
}

// The small generic 4R job of tests/tools/farm_test.sh; no wall-clock limit per
// start, so that a loaded machine cannot change a result.
constexpr const char* kJob = R"([loop]
joints = 4
samples = 16

[optimizer]
algorithm = "gauss-newton"
max_evaluations = 100
time_limit_s = 0

[search]
starts = 24
seed = 7

[output]
report_threshold = 1e-3
)";

// A directory of rank 0's (its name broadcast), removed at the end.
class FarmMpiTest : public ::testing::Test {
 protected:
  void SetUp() override {
    static int counter = 0;
    std::string name = "loopfarm_farm_mpi_test_" + std::to_string(getpid()) + "_" + std::to_string(counter++);
    int size = static_cast<int>(name.size());
    MPI_Bcast(&size, 1, MPI_INT, 0, MPI_COMM_WORLD);
    name.resize(static_cast<size_t>(size));
    MPI_Bcast(name.data(), size, MPI_CHAR, 0, MPI_COMM_WORLD);
    dir_ = fs::temp_directory_path() / name;
    if (rank() == 0) fs::create_directories(dir_);
    job_ = parse_job(kJob, "farm_mpi_test.toml");
  }
  void TearDown() override {
    MPI_Barrier(MPI_COMM_WORLD);
    if (rank() == 0) fs::remove_all(dir_);
  }

  Job job_at(const std::string& database, long starts) const {
    Job job = job_;
    job.output.database = (dir_ / database).string();
    job.search.starts = starts;
    return job;
  }

  // What a database holds: candidates in id order and the start counts.
  static std::vector<std::string> contents(const std::string& path) {
    const ResultsDatabase db = ResultsDatabase::open(path, DatabaseMode::read);
    std::vector<std::string> out;
    for (const CandidateRow& c : db.candidates({})) {
      char energy[40];
      std::snprintf(energy, sizeof energy, "%.17g", c.E_mean);
      out.push_back(std::to_string(c.id) + " " + c.family + " " + std::to_string(c.first_start) + " " +
                    std::to_string(c.hits) + " " + energy);
    }
    const StartCounts counts = db.start_counts();
    out.push_back(std::to_string(counts.starts) + " starts, " + std::to_string(counts.zeros) + " zeros, " +
                  std::to_string(counts.verified) + " verified");
    return out;
  }

  // Rank 0: every start of `job` run here and committed at once.
  std::vector<std::string> reference(const Job& job) const {
    const std::string path = (dir_ / "reference.sqlite").string();
    if (!fs::exists(path)) {
      ResultsDatabase db = ResultsDatabase::open(path, DatabaseMode::write);
      const ResumePlan plan = plan_run(db, job, false, 1);
      std::vector<StartRecord> records;
      for (long i = 0; i < job.search.starts; ++i)
        records.push_back(run_start_record(job, static_cast<std::uint64_t>(i)));
      db.commit(plan.run_id, records);
      db.end_session(RunStatus::complete);
    }
    return contents(path);
  }

  fs::path dir_;
  Job job_;
};

TEST_F(FarmMpiTest, TwoRanksWriteWhatOneProcessWrites) {
  const Job job = job_at("farm.sqlite", 24);
  StopFlag stop;
  const FarmSummary s = run_farm(job, MPI_COMM_WORLD, stop, {});
  EXPECT_EQ(s.status, FarmStatus::complete);
  EXPECT_EQ(s.ranks, 2);
  if (rank() != 0) return;
  EXPECT_EQ(s.run.done, 24);
  EXPECT_EQ(s.run.done_here, 24);
  EXPECT_EQ(s.run.total, 24);
  EXPECT_GT(s.run.messages, 0);  // rank 1 asked for work
  EXPECT_GT(s.peak_mb_max, 0.0);
  EXPECT_EQ(contents(job.output.database), reference(job));
}

TEST_F(FarmMpiTest, AStopOnAWorkerRankStopsEveryRankAndAResumeCompletes) {
  const Job job = job_at("farm.sqlite", 24);
  StopFlag stop;
  if (rank() == 1) stop.request(SIGUSR1);  // as if SIGUSR1 reached rank 1 only
  const FarmSummary first = run_farm(job, MPI_COMM_WORLD, stop, {});
  EXPECT_EQ(first.status, FarmStatus::stopped);
  if (rank() == 0) {
    EXPECT_EQ(first.stop_signal, SIGUSR1);
    EXPECT_LT(first.run.done, 24);
    EXPECT_EQ(ResultsDatabase::open(job.output.database, DatabaseMode::read).runs().at(0).status, "stopped");
  }
  StopFlag go;
  const FarmSummary second = run_farm(job, MPI_COMM_WORLD, go, {});
  EXPECT_EQ(second.status, FarmStatus::complete);
  if (rank() != 0) return;
  EXPECT_EQ(second.run.done, 24);
  EXPECT_EQ(second.run.done_here, 24 - first.run.done);
  // The same starts, zeros and verified; the same linkages (ids follow the
  // commit order, which the stop changed).
  std::vector<std::string> got = contents(job.output.database), want = reference(job);
  EXPECT_EQ(got.back(), want.back());
  for (std::vector<std::string>* rows : {&got, &want}) {
    for (std::string& r : *rows) r = r.substr(r.find(' ') + 1);
    std::sort(rows->begin(), rows->end());
  }
  EXPECT_EQ(got, want);
}

TEST_F(FarmMpiTest, ALargerTargetResumesAFinishedRun) {
  StopFlag stop;
  EXPECT_EQ(run_farm(job_at("farm.sqlite", 12), MPI_COMM_WORLD, stop, {}).status, FarmStatus::complete);
  const Job job = job_at("farm.sqlite", 24);
  const FarmSummary s = run_farm(job, MPI_COMM_WORLD, stop, {});
  EXPECT_EQ(s.status, FarmStatus::complete);
  if (rank() != 0) return;
  EXPECT_EQ(s.run.done_here, 12);
  EXPECT_EQ(contents(job.output.database), reference(job));
}

TEST_F(FarmMpiTest, AnotherJobsDatabaseIsRefusedOnEveryRank) {
  StopFlag stop;
  EXPECT_EQ(run_farm(job_at("farm.sqlite", 4), MPI_COMM_WORLD, stop, {}).status, FarmStatus::complete);
  Job other = job_at("farm.sqlite", 4);
  other.search.seed = 8;
  if (rank() == 0) {
    EXPECT_THROW(run_farm(other, MPI_COMM_WORLD, stop, {}), DatabaseError);
  } else {
    EXPECT_EQ(run_farm(other, MPI_COMM_WORLD, stop, {}).status, FarmStatus::refused);
  }
}

}  // namespace
}  // namespace loopfarm

// MPI for the whole program; every rank runs every test (they are
// collective), rank 0 prints, and the program fails if a test failed on any rank.
int main(int argc, char** argv) {
  const loopfarm::MpiSession mpi;
  ::testing::InitGoogleTest(&argc, argv);
  if (mpi.rank() != 0) {
    ::testing::TestEventListeners& listeners = ::testing::UnitTest::GetInstance()->listeners();
    delete listeners.Release(listeners.default_result_printer());
  }
  if (mpi.ranks() != 2) {
    if (mpi.rank() == 0) std::fprintf(stderr, "farm_mpi_test: run under mpirun -np 2 (got %d ranks)\n", mpi.ranks());
    return 1;
  }
  int failed = RUN_ALL_TESTS() != 0 ? 1 : 0;
  int any = 0;
  MPI_Allreduce(&failed, &any, 1, MPI_INT, MPI_MAX, mpi.world());
  return any;
}
