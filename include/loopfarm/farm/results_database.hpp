// The SQLite results database of the farm (docs/guide/database.md documents the
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
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "loopfarm/farm/results.hpp"

namespace loopfarm {

// One line naming the database path and what is wrong. `refused`: the file's
// fault (not a loopfarm database, damaged, a newer schema, another job: bad
// input); `failed`: the system's (I/O, out of memory, a lock never released).
class DatabaseError : public std::runtime_error {
 public:
  enum class Cause { refused, failed };
  explicit DatabaseError(const std::string& what, Cause cause = Cause::refused)
      : std::runtime_error(what), cause_(cause) {}
  Cause cause() const { return cause_; }

 private:
  Cause cause_;
};

// PRAGMA application_id of a loopfarm database: "LOOP" in ASCII.
inline constexpr std::int32_t kDatabaseApplicationId = 0x4C4F4F50;
// PRAGMA user_version: the schema version this build writes. It reads every
// version from kOldestDatabaseSchemaVersion on, and upgrades an older file to
// this one when it opens it for writing (results_schema.cpp says what changed).
inline constexpr int kDatabaseSchemaVersion = 7;
inline constexpr int kOldestDatabaseSchemaVersion = 1;
// The de-duplication's numeric tolerance unless a caller gives another
// (commit, merge); the upgrades to schema versions 6 and 7 merge with it.
inline constexpr double kDefaultDedupTolerance = 1e-5;
// busy_timeout: how long a connection waits for another one's lock.
inline constexpr int kDatabaseBusyTimeoutMs = 10000;

enum class DatabaseMode {
  write,   // create the file if missing; the one writer
  read,    // read-only (SQLITE_OPEN_READONLY), also while a writer is running
  update,  // write to an existing database: never created; a read-only file is refused
};

enum class RunStatus { running, stopped, complete, failed };
const char* to_string(RunStatus status);

// Half-open range [first, last) of start indices.
struct IndexRange {
  std::uint64_t first = 0;
  std::uint64_t last = 0;
};

// Slice `index` of `count` (0 <= index < count) of a job's start indices: the
// count contiguous ranges of [0, starts) whose sizes differ by at most one,
// slice I being [floor(I * starts / count), floor((I + 1) * starts / count)).
struct StartSlice {
  std::uint64_t index = 0;
  std::uint64_t count = 1;
};
// The start indices of `slice` of [0, starts); of the whole job without one.
IndexRange slice_range(const std::optional<StartSlice>& slice, std::uint64_t starts);
// "I/K", as `loopfarm run --slice` takes it.
std::string to_string(const StartSlice& slice);

// What identifies a run: its job (by the hash of the text), seed and slice.
// The other fields are stored with it; `starts` is the target, which a resume
// may change, except for a slice (the slices of a job tile its starts only
// when each is taken of the same target).
struct RunIdentity {
  std::string job_path;
  std::string job_text;
  std::uint64_t seed = 0;
  std::uint64_t starts = 0;
  int joints = 0;
  double zero_threshold = 0.0;
  double report_threshold = 0.0;
  std::optional<StartSlice> slice;  // none: every start of the job
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

// --- what readers ask of the database -----------------------------------------

// One row of `runs`.
struct RunRow {
  std::int64_t run_id = 0;
  std::string job_path;
  std::uint64_t seed = 0;
  std::int64_t starts = 0;       // the target
  std::int64_t starts_done = 0;  // committed
  std::string status;            // running, stopped, complete, failed
  std::int64_t ranks = 0;        // of the last session
  int joints = 0;
  std::string started_at, updated_at;  // ISO 8601 UTC
  std::optional<StartSlice> slice;     // none: every start of the job
  std::int64_t merged_inputs = 0;      // databases `loopfarm merge` made it of (0: run here)
  // Its job's [search] zero_threshold: a start whose E_mean is at most this is a zero.
  double zero_threshold = std::numeric_limits<double>::quiet_NaN();
};

// Counts over the starts of one run, or of every run.
struct StartCounts {
  std::int64_t starts = 0;
  std::int64_t zeros = 0;
  std::int64_t verified = 0;
  double mean_seconds = std::numeric_limits<double>::quiet_NaN();   // per start; NaN without starts
  double total_seconds = std::numeric_limits<double>::quiet_NaN();  // core-seconds
};

struct StatusCount {
  std::string status;  // a start's status (an optimiser's end, "evaluation_failed", ...)
  std::int64_t starts = 0;
};

struct FamilyCount {
  std::string family;
  std::int64_t candidates = 0;  // distinct linkages
  std::int64_t hits = 0;        // starts that found them
};

// log10 of every start's E_mean by decade; exact zeros and NULL apart.
struct EnergyHistogram {
  std::map<int, std::int64_t> decades;  // floor(log10 E_mean) -> starts
  std::int64_t zeros = 0;               // E_mean exactly 0
  std::int64_t missing = 0;             // NULL: the start could not be evaluated
};

// One row of `candidates` as a reader needs it: the canonical geometry (L = 1,
// twists in degrees) as lists of `joints` values.
struct CandidateRow {
  static constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  long long id = 0;
  std::string family, setup, detail;
  // Every family whose conditions hold, comma-separated, `family` first;
  // none for a row written before schema version 4 (not recorded).
  std::optional<std::string> families;
  // The bond fingerprint of the stored geometry (bond_relations.hpp), as
  // `loopfarm bonds --store` measured it; empty when it measured none (the
  // stored geometry does not move); none when not measured (NULL, or a
  // database older than schema version 5).
  std::optional<std::string> bond_fingerprint;
  double E_mean = kNaN, E_max = kNaN;
  long long hits = 0, first_run = 0, first_start = 0;
  int local_dimension = 0, free_parameters = 0;  // local_dimension -1: unknown (LocalDimension::unknown)
  double rigid_residual = kNaN, family_residual = kNaN;
  double bennett_residual = kNaN, planar_residual = kNaN, spherical_residual = kNaN, trivial_residual = kNaN;
  bool full_turn = false;
  double range_lo_deg = kNaN, range_hi_deg = kNaN;
  int joints = 0;
  std::vector<double> a, alpha_deg, d;
};

// One row of `candidates` whole: the reader's row and the columns only the
// store itself needs (the key and grid cell it de-duplicates by, and the
// local-dimension analysis's singular values as the stored JSON array text).
struct CandidateDetails {
  CandidateRow row;
  std::string canonical_key;
  std::string singular_values;
  std::string grid_cell;
};

// The smallest and largest candidate_id of a database.
struct CandidateIdRange {
  std::int64_t first = 0;
  std::int64_t last = 0;
};

// Which candidates, in the report's order: unclassified first (a possible new
// family, or a defect for 4R), then by E_mean from zero upwards, then by id.
struct CandidateFilter {
  std::string family;                     // empty: every family
  std::optional<double> max_energy;       // E_mean at most this
  std::optional<std::int64_t> first_run;  // found first by this run
  std::int64_t limit = -1;                // at most this many; negative: no limit
  std::int64_t offset = 0;                // skip this many (paging)
  bool without_fingerprint = false;       // only those whose bond fingerprint is not stored
};

// Candidates of one bond fingerprint (or of none stored), as
// ResultsDatabase::fingerprint_classes groups them.
struct FingerprintClass {
  // The fingerprint; empty: measured, none (the stored geometry does not
  // move); none: not measured.
  std::optional<std::string> fingerprint;
  std::int64_t candidates = 0;  // distinct linkages
  std::int64_t hits = 0;        // starts that found them
  // The first of them in the report's order (by E_mean, then id).
  std::int64_t representative = 0;
  std::string family;                            // the representative's
  int local_dimension = 0, free_parameters = 0;  // local_dimension -1: unknown
  double E_mean = std::numeric_limits<double>::quiet_NaN();
};

// A bond fingerprint to store with a candidate: `first_run` and `first_start`
// name the representative whose geometry was measured, so that a candidate
// whose representative a run has replaced meanwhile is left alone.
struct BondFingerprint {
  std::int64_t candidate_id = 0;
  std::int64_t first_run = 0;
  std::int64_t first_start = 0;
  std::string fingerprint;  // empty: measured, none (the stored geometry does not move)
};

// What ResultsDatabase::store_bond_fingerprints did.
struct FingerprintStoreSummary {
  std::int64_t stored = 0;   // rows written
  std::int64_t skipped = 0;  // candidates gone or represented by another start now
  bool upgraded = false;     // the file was of an older schema version, upgraded in the same transaction
};

// The connection's PRAGMA values (what SQLite reports, not options), for the record and for tests.
struct ConnectionPragmas {
  std::string journal_mode;  // "wal" while open for writing
  bool foreign_keys = false;
  int synchronous = 0;  // 1: NORMAL
  int busy_timeout_ms = 0;
  bool query_only = false;
};

// FNV-1a, 64 bit, of the bytes of `text`, as 16 lowercase hex digits: runs.job_hash.
std::string job_hash(std::string_view text);

// What ResultsDatabase::merge did.
struct MergeSummary {
  std::int64_t inputs = 0;               // databases read
  std::uint64_t starts = 0;              // start rows written (each start index once)
  std::uint64_t overlapping_starts = 0;  // rows present in more than one input (equal; the first kept)
  std::uint64_t target = 0;              // the merged run's starts target: the largest of the inputs'
  std::int64_t candidates = 0;           // distinct linkages after de-duplication
  std::int64_t verified = 0;             // verified starts: the candidates' hits together
  bool complete = false;                 // every index of [0, target) is there
};

class ResultsDatabase {
 public:
  // Throws DatabaseError when the file cannot be opened or is refused: not
  // SQLite, another application_id, an unknown schema version, damage (SQLite
  // says so, or PRAGMA quick_check fails: every mode, before anything is
  // written), a missing file (read and update modes), an empty one or a
  // read-only one (update mode: a file without write permission, or whose
  // mode has no write bit at all, which even root does not write to; a
  // directory where the journal cannot be created). The message says
  // "damaged" for damage and "not an SQLite database" for a file that is not one.
  static ResultsDatabase open(const std::string& path, DatabaseMode mode);

  ResultsDatabase(const ResultsDatabase&) = delete;
  ResultsDatabase& operator=(const ResultsDatabase&) = delete;
  ResultsDatabase(ResultsDatabase&&) noexcept;
  ResultsDatabase& operator=(ResultsDatabase&&) noexcept;
  ~ResultsDatabase();

  const std::string& path() const;
  DatabaseMode mode() const;
  ConnectionPragmas connection_settings() const;

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
  CommitSummary commit(std::int64_t run_id, const std::vector<StartRecord>& records,
                       double dedup_tolerance = kDefaultDedupTolerance);

  // --- reading (either mode). A query's failure throws DatabaseError: refused
  // when SQLite finds the file damaged, failed otherwise. `run_id` empty: every run.
  std::vector<RunRow> runs() const;
  StartCounts start_counts(std::optional<std::int64_t> run_id = {}) const;
  // Most starts first.
  std::vector<StatusCount> status_counts(std::optional<std::int64_t> run_id = {}) const;
  // Families in name order, of the candidates `first_run` found first (every candidate if empty).
  std::vector<FamilyCount> family_counts(std::optional<std::int64_t> first_run = {}) const;
  EnergyHistogram energy_histogram(std::optional<std::int64_t> run_id = {}) const;
  std::int64_t candidate_count() const;
  // How many candidates `filter` selects, its limit and offset aside.
  std::int64_t candidate_count(const CandidateFilter& filter) const;
  // Empty when the database holds no candidate.
  std::optional<CandidateIdRange> candidate_id_range() const;
  std::vector<CandidateRow> candidates(const CandidateFilter& filter) const;
  // The candidate with this id; empty when there is none.
  std::optional<CandidateDetails> candidate(std::int64_t candidate_id) const;
  // The candidates `filter` selects (its limit and offset aside) grouped by
  // their stored bond fingerprint: the most candidates first, then the most
  // hits, then by fingerprint; the measured loops without one ("") and the
  // candidates not measured (none) last.
  std::vector<FingerprintClass> fingerprint_classes(const CandidateFilter& filter) const;

  // --- writing bond fingerprints (write or update mode) -------------------------
  // Stores each fingerprint with its candidate, in one transaction (an older
  // schema is upgraded to this version within it): on any error nothing is
  // written and DatabaseError is thrown. A candidate that is gone, or whose
  // representative is no longer the start named, is skipped. Nothing to store:
  // nothing written, the schema left as it is.
  FingerprintStoreSummary store_bond_fingerprints(const std::vector<BondFingerprint>& fingerprints);

  // Merges the databases `inputs`, each holding one run of the same job (its
  // text apart from the [output] table) and seed, into a new database `output`
  // holding one run of every start they hold (the whole job: no slice), as if
  // one uninterrupted run had computed them: every start index once (rows of
  // the same index in several inputs must be equal, seconds and sessions
  // apart), the verified starts de-duplicated again in start-index order, and
  // where each row came from in merge_inputs and sessions (docs/guide/database.md,
  // "Merging"). The output is written to a temporary file beside it and
  // renamed at the end: a refusal (DatabaseError, refused: an input not a
  // loopfarm database, of another job or seed, rows that differ, `output`
  // already there) or a failure leaves no file behind and the inputs as they were.
  static MergeSummary merge(const std::string& output, const std::vector<std::string>& inputs,
                            double dedup_tolerance = kDefaultDedupTolerance);

  // One read transaction: every query while it lives sees the same committed
  // state, even while a writer commits. Ends when it goes.
  class Snapshot {
   public:
    Snapshot(Snapshot&&) noexcept;
    Snapshot& operator=(Snapshot&&) = delete;
    ~Snapshot();

   private:
    friend class ResultsDatabase;
    explicit Snapshot(const ResultsDatabase* db) : db_(db) {}
    const ResultsDatabase* db_;
  };
  Snapshot snapshot() const;

 private:
  struct Impl;
  explicit ResultsDatabase(std::unique_ptr<Impl> impl);
  Impl& impl() const;

  std::unique_ptr<Impl> impl_;
};

}  // namespace loopfarm
