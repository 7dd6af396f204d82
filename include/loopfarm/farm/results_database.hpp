// The SQLite results database of the farm (docs/database.md documents the
// schema column by column): runs, their sessions (one per invocation), one row
// per start, and one row per distinct verified linkage (candidates).
//
// One writer (rank 0 of `loopfarm run`) and any number of readers (`loopfarm
// report`, sqlite3, pandas) at once: the file is in WAL mode, every write is
// one BEGIN IMMEDIATE ... COMMIT transaction, and a reader sees the last
// committed state. WAL needs every process on one host: keep the database on a
// local (lock-capable) disk, not on a network filesystem.
//
// A file this class refuses (another program's database, a newer schema,
// damage, not SQLite at all) is never written to.
//
// candidate_id numbers candidates in the order they are committed (in index
// order within one commit); the rest of a candidates row does not depend on
// the commit order (the earliest start represents the linkage). One object
// per thread.
#pragma once

#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "loopfarm/farm/results.hpp"

struct sqlite3;

namespace loopfarm {

// One line naming the database path and what is wrong.
class DatabaseError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// PRAGMA application_id of a loopfarm database: "LOOP" in ASCII.
inline constexpr std::int32_t kDatabaseApplicationId = 0x4C4F4F50;
// PRAGMA user_version: the schema version this build writes and reads.
inline constexpr int kDatabaseSchemaVersion = 1;
// busy_timeout: how long a connection waits for another one's lock.
inline constexpr int kDatabaseBusyTimeoutMs = 10000;

enum class DatabaseMode {
  write,  // create the file if missing; the one writer
  read,   // read-only (SQLITE_OPEN_READONLY), also while a writer is running
};

enum class RunStatus { running, stopped, complete, failed };
const char* to_string(RunStatus status);

// What identifies a run: its job (by the hash of the text) and seed. The other
// fields are stored with it; `starts` is the target, which a resume may change.
struct RunIdentity {
  std::string job_path;
  std::string job_text;
  std::uint64_t seed = 0;
  std::uint64_t starts = 0;
  int joints = 0;
  double zero_threshold = 0.0;
  double report_threshold = 0.0;
};

// Half-open range [first, last) of start indices.
struct IndexRange {
  std::uint64_t first = 0;
  std::uint64_t last = 0;
};

struct RunInfo {
  std::int64_t run_id = 0;
  bool created = false;  // a new run; false: an existing run resumed
  // The committed start indices as sorted, disjoint, non-adjacent ranges: a
  // prefix and a few chunks that were in flight when a run stopped, so the
  // memory does not grow with the number of starts.
  std::vector<IndexRange> committed;

  std::uint64_t committed_count() const;
  bool is_committed(std::uint64_t index) const;
  // K such that every index in [0, K) is committed and K is not.
  std::uint64_t committed_prefix() const;
};

struct CommitSummary {
  int starts = 0;          // start rows inserted
  int zeros = 0;           // of them with zero = 1
  int new_candidates = 0;  // candidates rows inserted
  int repeat_hits = 0;     // verified starts that matched an existing candidate
};

// FNV-1a, 64 bit, of the bytes of `text`, as 16 lowercase hex digits: runs.job_hash.
std::string job_hash(std::string_view text);

class ResultsDatabase {
 public:
  // Throws DatabaseError when the file cannot be opened or is refused: not
  // SQLite, another application_id, an unknown schema version, damage (SQLite
  // says so, or PRAGMA quick_check fails: both modes, before anything is
  // written), a missing file (read mode). The message says "damaged" for
  // damage and "not an SQLite database" for a file that is not one.
  static ResultsDatabase open(const std::string& path, DatabaseMode mode);

  ResultsDatabase(const ResultsDatabase&) = delete;
  ResultsDatabase& operator=(const ResultsDatabase&) = delete;
  ResultsDatabase(ResultsDatabase&&) noexcept;
  ResultsDatabase& operator=(ResultsDatabase&&) noexcept;
  ~ResultsDatabase();

  const std::string& path() const;
  DatabaseMode mode() const;
  // The connection, for plain SQL (the report tool); owned by this object.
  sqlite3* handle() const;

  // Decides which run this invocation writes to. No run yet, or new_run: a
  // new run. The latest run with the same job_hash and seed: that run, resumed
  // (its starts target and job_path updated). Anything else throws
  // DatabaseError naming the run and job the database holds and `--new-run`.
  RunInfo open_run(const RunIdentity& identity, bool new_run = false);

  // One session per invocation: marks the run `running` with `ranks`. Returns
  // the session_id. A session left open (a crash) stays `running`.
  std::int64_t begin_session(std::int64_t run_id, int ranks);
  // Ends the open session with `status` (not `running`), copied to the run;
  // a `complete` run gets its ended_at.
  void end_session(RunStatus status);

  // Inserts the starts and de-duplicates the verified ones into candidates,
  // in one transaction: on any error nothing is written and DatabaseError is
  // thrown (a start index already committed for the run is an error).
  // `dedup_tolerance` bounds the difference of every canonical-geometry value
  // (lengths at length scale 1, twists in radians, wrapped) of one linkage.
  CommitSummary commit(std::int64_t run_id, const std::vector<StartRecord>& records, double dedup_tolerance = 1e-5);

 private:
  struct Impl;
  explicit ResultsDatabase(std::unique_ptr<Impl> impl);
  Impl& impl() const;

  std::unique_ptr<Impl> impl_;
};

}  // namespace loopfarm
