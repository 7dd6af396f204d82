// The discovery farm over MPI (farm.hpp): the transport that carries the
// coordinator's messages between ranks, the remote workers' loop, and the
// entry point.
#include <mpi.h>

#include <algorithm>
#include <csignal>
#include <cstdio>
#include <exception>
#include <optional>
#include <string>
#include <vector>

#include "loopfarm/farm/coordinator.hpp"
#include "loopfarm/farm/farm.hpp"
#include "loopfarm/farm/results_database.hpp"

namespace loopfarm {
namespace {

constexpr int kTagRequest = 1;  // worker -> 0: [stopping byte][encoded records]
constexpr int kTagWork = 2;     // 0 -> worker: start indices (uint64); none means stop

// Verdicts rank 0 broadcasts after opening the database, and codes at the end.
constexpr int kVerdictGo = 0;
constexpr int kVerdictRefused = 1;
constexpr int kVerdictFailed = 2;

void send_bytes(MPI_Comm comm, const std::string& bytes, int destination, int tag) {
  MPI_Send(bytes.data(), static_cast<int>(bytes.size()), MPI_BYTE, destination, tag, comm);
}

std::string receive_bytes(MPI_Comm comm, int source, int tag) {
  MPI_Status status;
  MPI_Probe(source, tag, comm, &status);
  int size = 0;
  MPI_Get_count(&status, MPI_BYTE, &size);
  std::string bytes(static_cast<size_t>(size), '\0');
  MPI_Recv(bytes.data(), size, MPI_BYTE, status.MPI_SOURCE, tag, comm, MPI_STATUS_IGNORE);
  return bytes;
}

std::vector<std::uint64_t> receive_work(MPI_Comm comm) {
  MPI_Status status;
  MPI_Probe(0, kTagWork, comm, &status);
  int count = 0;
  MPI_Get_count(&status, MPI_UINT64_T, &count);
  std::vector<std::uint64_t> chunk(static_cast<size_t>(count));
  MPI_Recv(chunk.data(), count, MPI_UINT64_T, 0, kTagWork, comm, MPI_STATUS_IGNORE);
  return chunk;
}

// Rank 0's side: requests from ranks 1..P-1, chunks back to them.
class MpiTransport : public CoordinatorTransport {
 public:
  MpiTransport(MPI_Comm comm, int ranks) : comm_(comm), ranks_(ranks) {}
  int remote_workers() const override { return ranks_ - 1; }
  std::optional<WorkRequest> poll() override {
    int flag = 0;
    MPI_Status status;
    MPI_Iprobe(MPI_ANY_SOURCE, kTagRequest, comm_, &flag, &status);
    if (!flag) return std::nullopt;
    const std::string message = receive_bytes(comm_, status.MPI_SOURCE, kTagRequest);
    if (message.empty()) throw std::runtime_error("empty message from rank " + std::to_string(status.MPI_SOURCE));
    WorkRequest request;
    request.worker = status.MPI_SOURCE;
    request.stopping = message[0] != '\0';
    request.records = decode_records(std::string_view(message).substr(1));
    return request;
  }
  void send_work(int worker, const std::vector<std::uint64_t>& chunk) override {
    MPI_Send(chunk.data(), static_cast<int>(chunk.size()), MPI_UINT64_T, worker, kTagWork, comm_);
  }

 private:
  MPI_Comm comm_;
  int ranks_;
};

// Ranks 1..P-1: ask, compute, return, until told to stop.
void worker_loop(MPI_Comm comm, const Job& job, const StopFlag& stop) {
  std::vector<StartRecord> done;
  bool stopping = false;
  for (;;) {
    std::string message(1, stopping ? '\1' : '\0');
    std::string encoded;
    encode_records(done, encoded);
    message += encoded;
    send_bytes(comm, message, 0, kTagRequest);
    done.clear();
    const std::vector<std::uint64_t> chunk = receive_work(comm);
    // After a stopping request rank 0 answers with an empty chunk.
    if (chunk.empty()) return;
    for (std::uint64_t index : chunk) {
      if (stop.requested()) break;
      done.push_back(run_start_record(job, index));
    }
    stopping = stop.requested();
  }
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

}  // namespace

MpiSession::MpiSession() {
  MPI_Init_thread(nullptr, nullptr, MPI_THREAD_FUNNELED, &provided_);
  MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
  MPI_Comm_size(MPI_COMM_WORLD, &ranks_);
}

MpiSession::~MpiSession() { MPI_Finalize(); }

FarmSummary run_farm(const Job& job, MPI_Comm comm, StopFlag& stop, const FarmOptions& options) {
  int rank = 0, ranks = 1, thread_level = 0;
  MPI_Comm_rank(comm, &rank);
  MPI_Comm_size(comm, &ranks);
  MPI_Query_thread(&thread_level);
  FarmSummary summary;
  summary.ranks = ranks;

  // Rank 0 opens the database and decides what to run; the verdict goes to
  // every rank, so that a refusal ends them all before any other message.
  int verdict = kVerdictGo;
  std::exception_ptr failure;
  std::optional<ResultsDatabase> db;
  std::optional<ResumePlan> plan;
  if (rank == 0) {
    try {
      if (thread_level < MPI_THREAD_FUNNELED && ranks > 1) {
        throw std::runtime_error(
            "this MPI provides no MPI_THREAD_FUNNELED; rank 0 cannot compute while it coordinates");
      }
      db.emplace(ResultsDatabase::open(job.output.database, DatabaseMode::write));
      plan = plan_run(*db, job, options.new_run, ranks, options.slice);
    } catch (const DatabaseError&) {
      failure = std::current_exception();
      verdict = kVerdictRefused;
    } catch (...) {
      failure = std::current_exception();
      verdict = kVerdictFailed;
    }
  }
  MPI_Bcast(&verdict, 1, MPI_INT, 0, comm);
  if (verdict != kVerdictGo) {
    if (rank == 0) std::rethrow_exception(failure);
    summary.status = verdict == kVerdictRefused ? FarmStatus::refused : FarmStatus::failed;
    return summary;
  }

  if (rank != 0) {
    worker_loop(comm, job, stop);
    const long own_kb = peak_memory_kb();
    MPI_Gather(&own_kb, 1, MPI_LONG, nullptr, 0, MPI_LONG, 0, comm);
    // Every rank ends with rank 0's status (mpirun passes on rank 0's exit code).
    int status = static_cast<int>(FarmStatus::failed);
    MPI_Bcast(&status, 1, MPI_INT, 0, comm);
    summary.status = static_cast<FarmStatus>(status);
    return summary;
  }

  try {
    MpiTransport transport(comm, ranks);
    Progress progress(options.progress);
    summary.run = coordinate(
        *db, *plan, transport, [&job](std::uint64_t index) { return run_start_record(job, index); }, options.chunk,
        stop, progress);
    summary.run_id = plan->run_id;
    summary.stop_signal = stop.signal();
    summary.status = summary.run.complete ? FarmStatus::complete : FarmStatus::stopped;
    // Every rank's peak memory, gathered for the record.
    const long own_kb = peak_memory_kb();
    std::vector<long> peak_kb(static_cast<size_t>(ranks));
    MPI_Gather(&own_kb, 1, MPI_LONG, peak_kb.data(), 1, MPI_LONG, 0, comm);
    summary.peak_mb_rank0 = static_cast<double>(peak_kb[0]) / 1024.0;
    summary.peak_mb_max = static_cast<double>(*std::max_element(peak_kb.begin(), peak_kb.end())) / 1024.0;
    int status = static_cast<int>(summary.status);
    MPI_Bcast(&status, 1, MPI_INT, 0, comm);
    return summary;
  } catch (const std::exception& error) {
    try {
      db->end_session(RunStatus::failed);
    } catch (const std::exception&) {
      // The database is what failed; the caller's message says so.
    }
    if (ranks > 1) {
      // The workers wait for rank 0's answers: end them with the job.
      std::string what = error.what();
      std::replace(what.begin(), what.end(), '\n', ' ');
      std::fprintf(stderr, "loopfarm run: %s; aborting all %d ranks (committed starts are kept)\n", what.c_str(),
                   ranks);
      MPI_Abort(comm, 1);
    }
    throw;
  }
}

}  // namespace loopfarm
