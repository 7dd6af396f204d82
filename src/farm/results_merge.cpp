// loopfarm merge: one database of the runs of a job's slices
// (ResultsDatabase::merge in results_database.hpp; docs/guide/database.md, "Merging").
//
// The merged database is what one uninterrupted run of every start the inputs
// hold would have written, apart from timing and provenance:
//   - one run, of the whole job (no slice), its target the largest of the
//     inputs' and its report_threshold the smallest (a start keeps its
//     geometry only when its E_mean is at most that, as such a run keeps it);
//   - one starts row per start index, copied from the first input (in the
//     order given) that holds it; a start held by several inputs must have the
//     same row in each, seconds and session apart;
//   - the candidates de-duplicated again over all inputs in start-index order,
//     as the run commits them: each input's representative start (its
//     candidate's first start there) is looked up among the candidates merged
//     so far with the run's own de-duplication (find_candidate) and counted as
//     a hit or added as a new candidate; every other verified start goes
//     where its input's representative went. For a linkage whose verified
//     starts all lie within the tolerance of one another (the case for which
//     one run's candidates do not depend on the order of its commits either)
//     this is exactly what one run does; candidate_id follows the order of
//     first starts, as in an uninterrupted run;
//   - each input a row of merge_inputs, its sessions copied with input_id set,
//     so that every start names the session and database it was computed in.
#include <fcntl.h>
#include <sqlite3.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <queue>
#include <unordered_map>
#include <utility>

#include "candidate_index.hpp"
#include "job_identity.hpp"
#include "loopfarm/core/loop.hpp"
#include "loopfarm/farm/results_database.hpp"
#include "results_database_impl.hpp"
#include "results_rekey.hpp"
#include "results_schema.hpp"
#include "sqlite_support.hpp"

#ifndef LOOPFARM_VERSION
#error "LOOPFARM_VERSION is defined by the loopfarm library target"
#endif

namespace loopfarm {
namespace {

using namespace store;

// ISO 8601 UTC, evaluated by SQLite once per statement.
constexpr const char* kNow = "strftime('%Y-%m-%dT%H:%M:%SZ','now')";

// The columns of a starts row a merge reads, by position.
enum StartColumn {
  kStartIndex = 0,
  kSession,
  kStatus,
  kEMean,
  kEMax,
  kObjective,
  kEvaluations,
  kSeconds,
  kZero,
  kVerified,
  kCandidate,
  kGeometry,  // the 24 geometry columns from here
};
constexpr int kGeometryColumns = 3 * kMaxJoints;

std::string start_columns() {
  return "start_index, session_id, status, E_mean, E_max, objective, evaluations, seconds, zero, verified, "
         "candidate_id, " +
         geometry_columns("", "");
}

// The name of a starts column a merge compares, for messages.
std::string start_column_name(int column) {
  static const char* const names[] = {"start_index", "session_id", "status", "E_mean",   "E_max",       "objective",
                                      "evaluations", "seconds",    "zero",   "verified", "candidate_id"};
  if (column < kGeometry) return names[column];
  const std::string geometry = geometry_columns("", "");
  size_t from = 0;
  for (int i = kGeometry; i < column; ++i) from = geometry.find(", ", from) + 2;
  return geometry.substr(from, geometry.find(',', from) - from);
}

bool same_value(sqlite3_value* x, sqlite3_value* y) {
  const int type = sqlite3_value_type(x);
  if (type != sqlite3_value_type(y)) return false;
  switch (type) {
    case SQLITE_NULL:
      return true;
    case SQLITE_INTEGER:
      return sqlite3_value_int64(x) == sqlite3_value_int64(y);
    case SQLITE_FLOAT:
      return sqlite3_value_double(x) == sqlite3_value_double(y);
    default: {
      const int bytes = sqlite3_value_bytes(x);
      return bytes == sqlite3_value_bytes(y) &&
             std::memcmp(sqlite3_value_blob(x), sqlite3_value_blob(y), static_cast<size_t>(bytes)) == 0;
    }
  }
}

std::string show_value(sqlite3_value* v) {
  switch (sqlite3_value_type(v)) {
    case SQLITE_NULL:
      return "NULL";
    case SQLITE_INTEGER:
      return std::to_string(sqlite3_value_int64(v));
    case SQLITE_FLOAT:
      return format_double(sqlite3_value_double(v));
    default:
      return "'" + std::string(reinterpret_cast<const char*>(sqlite3_value_text(v))) + "'";
  }
}

// One input database, its one run and how its ids map into the output.
struct InputRun {
  std::string path;
  std::optional<ResultsDatabase> db;
  std::optional<ResultsDatabase::Snapshot> snapshot;  // after db: ends first
  sqlite3* connection = nullptr;
  int schema_version = 0;

  std::int64_t run_id = 0;
  std::string job_path, job_text, job_hash, status, loopfarm_version, started_at;
  std::int64_t seed = 0;
  std::uint64_t starts = 0, starts_done = 0;
  std::int64_t joints = 0;
  double zero_threshold = 0.0, report_threshold = 0.0;
  std::optional<StartSlice> slice;
  std::string identity;  // merge_identity of job_text

  std::int64_t input_id = 0;                                  // its merge_inputs row in the output
  std::uint64_t kept = 0;                                     // starts taken from it
  std::unordered_map<std::int64_t, std::int64_t> sessions;    // its session_id -> the output's
  std::unordered_map<std::int64_t, std::int64_t> candidates;  // its candidate_id -> the output's

  Statement cursor;     // its starts in index order
  Statement candidate;  // one of its candidates by id
};

std::string describe(const InputRun& in) {
  return "run " + std::to_string(in.run_id) + " of job " + in.job_path + " (seed " +
         std::to_string(static_cast<std::uint64_t>(in.seed)) +
         (in.slice ? ", slice " + to_string(*in.slice) + " of " + std::to_string(in.starts) + " starts" : "") + ")";
}

// Reads the input's one run; refuses a database of no run or of several.
void read_run(InputRun& in) {
  const std::string slices = in.schema_version >= 2 ? "slice_index, slice_count" : "NULL, NULL";
  Statement runs;
  runs.prepare(in.path, in.connection,
               "SELECT run_id, job_path, job_text, job_hash, seed, starts, joints, zero_threshold, report_threshold, "
               "loopfarm_version, status, starts_done, started_at, " +
                   slices + " FROM runs ORDER BY run_id");
  int count = 0;
  while (runs.step("cannot read the runs")) {
    if (++count > 1) continue;
    in.run_id = runs.integer(0);
    in.job_path = runs.text(1);
    in.job_text = runs.text(2);
    in.job_hash = runs.text(3);
    in.seed = runs.integer(4);
    in.starts = static_cast<std::uint64_t>(std::max<std::int64_t>(0, runs.integer(5)));
    in.joints = runs.integer(6);
    in.zero_threshold = runs.real(7);
    in.report_threshold = runs.real(8);
    in.loopfarm_version = runs.text(9);
    in.status = runs.text(10);
    in.starts_done = static_cast<std::uint64_t>(std::max<std::int64_t>(0, runs.integer(11)));
    in.started_at = runs.text(12);
    if (!runs.is_null(14)) {
      in.slice = StartSlice{static_cast<std::uint64_t>(runs.integer(13)), static_cast<std::uint64_t>(runs.integer(14))};
    }
  }
  if (count == 0) fail(in.path, "holds no run: nothing to merge");
  if (count > 1) {
    fail(in.path, "holds " + std::to_string(count) +
                      " runs; loopfarm merge takes databases of one run each (one per slice, as loopfarm run --slice "
                      "writes them)");
  }
  try {
    in.identity = merge_identity(in.job_text, "the job of run " + std::to_string(in.run_id));
  } catch (const std::invalid_argument& error) {
    fail(in.path, error.what());
  }
}

// Refuses `in` unless it holds the same job (outside [output]) and seed as `first`.
void check_same_job(const InputRun& first, const InputRun& in) {
  const std::string tail = "; loopfarm merge takes databases of one job and seed";
  if (in.identity != first.identity) {
    fail(in.path, "holds " + describe(in) + ", whose job differs from that of " + first.path + " (" + describe(first) +
                      ") outside [output]: " + first_difference(in.identity, first.identity) + tail);
  }
  if (in.seed != first.seed) {
    fail(in.path,
         "holds " + describe(in) + ", and " + first.path + " holds " + describe(first) + ": the seeds differ" + tail);
  }
  if (in.joints != first.joints || in.zero_threshold != first.zero_threshold) {
    fail(in.path, "holds " + describe(in) + " with other joints or zero_threshold than " + first.path + tail);
  }
}

// The new file the merge writes, beside `output`: removed (with any companion
// files) unless renamed to `output`.
class TemporaryDatabase {
 public:
  explicit TemporaryDatabase(const std::string& output)
      : path_(output + ".merging-" + std::to_string(static_cast<long>(::getpid()))) {
    // O_EXCL: never another's file; mode 0666 less the umask, as SQLite creates files.
    const int fd = ::open(path_.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
    if (fd < 0) {
      const std::string reason = std::strerror(errno);
      path_.clear();
      fail(output, "cannot create the merged database beside it (" + output + ".merging-PID): " + reason);
    }
    ::close(fd);
  }
  TemporaryDatabase(const TemporaryDatabase&) = delete;
  TemporaryDatabase& operator=(const TemporaryDatabase&) = delete;
  ~TemporaryDatabase() {
    if (path_.empty()) return;
    for (const char* suffix : {"", "-wal", "-shm", "-journal"}) ::unlink((path_ + suffix).c_str());
  }
  const std::string& path() const { return path_; }
  void rename_to(const std::string& output) {
    std::error_code error;
    if (std::filesystem::exists(std::filesystem::symlink_status(output, error))) {
      fail(output, "appeared while the merge ran; the merged database is not written");
    }
    std::filesystem::rename(path_, output, error);
    if (error)
      throw DatabaseError("results database " + output + ": cannot rename " + path_ + " to it: " + error.message(),
                          DatabaseError::Cause::failed);
    path_.clear();
  }

 private:
  std::string path_;
};

std::string absolute_path(const std::string& path) {
  std::error_code error;
  const std::filesystem::path absolute = std::filesystem::absolute(path, error);
  return error ? path : absolute.lexically_normal().string();
}

}  // namespace

MergeSummary ResultsDatabase::merge(const std::string& output, const std::vector<std::string>& inputs,
                                    double dedup_tolerance) {
  if (inputs.empty()) throw std::invalid_argument("merge: no input databases");
  if (!(dedup_tolerance >= 0.0 && dedup_tolerance < kGridCell)) {
    throw std::invalid_argument("merge: dedup_tolerance must be in [0, 1e-3)");
  }
  std::error_code error;
  if (std::filesystem::exists(std::filesystem::symlink_status(output, error))) {
    fail(output, "already exists; loopfarm merge writes a new database (remove it, or name another)");
  }

  // Every input opened, read and compared before anything is written.
  std::vector<std::unique_ptr<InputRun>> runs;
  for (const std::string& path : inputs) {
    for (const auto& earlier : runs) {
      if (std::filesystem::equivalent(earlier->path, path, error)) {
        fail(path, "is given twice (also as " + earlier->path + ")");
      }
    }
    auto in = std::make_unique<InputRun>();
    in->path = path;
    in->db.emplace(ResultsDatabase::open(path, DatabaseMode::read));
    in->connection = in->db->impl().db();
    in->schema_version = in->db->impl().schema_version;
    in->snapshot.emplace(in->db->snapshot());
    read_run(*in);
    if (!runs.empty()) check_same_job(*runs.front(), *in);
    runs.push_back(std::move(in));
  }
  const InputRun& first = *runs.front();
  std::uint64_t target = 0;
  double report_threshold = std::numeric_limits<double>::infinity();
  std::string started_at = first.started_at;
  for (const auto& in : runs) {
    target = std::max(target, in->starts);
    report_threshold = std::min(report_threshold, in->report_threshold);
    started_at = std::min(started_at, in->started_at);
  }

  MergeSummary summary;
  summary.inputs = static_cast<std::int64_t>(runs.size());
  summary.target = target;
  TemporaryDatabase temporary(output);
  {
    ResultsDatabase merged = ResultsDatabase::open(temporary.path(), DatabaseMode::write);
    Impl& m = merged.impl();
    sqlite3* db = m.db();
    Transaction transaction(m.path, db);

    Statement run;
    run.prepare(m.path, db,
                std::string("INSERT INTO runs (job_path, job_text, job_hash, seed, starts, joints, zero_threshold, "
                            "report_threshold, loopfarm_version, started_at, updated_at, status, starts_done) "
                            "VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10, ") +
                    kNow + ", 'stopped', 0)");
    run.bind(1, first.job_path);
    run.bind(2, first.job_text);
    run.bind(3, job_hash(first.job_text));
    run.bind(4, first.seed);
    run.bind(5, static_cast<std::int64_t>(target));
    run.bind(6, first.joints);
    run.bind(7, first.zero_threshold);
    run.bind(8, report_threshold);
    run.bind(9, LOOPFARM_VERSION);
    run.bind(10, started_at);
    run.run("cannot insert the run");
    const std::int64_t run_id = sqlite3_last_insert_rowid(db);
    const std::string merged_at = query_text(m.path, db, std::string("SELECT ") + kNow);

    // Provenance: each input a merge_inputs row (after the rows of the inputs
    // it was itself merged from, if any), its sessions copied.
    static const char* const kInputColumns =
        "path, source_run_id, job_path, job_hash, seed, slice_index, slice_count, starts, starts_done, starts_kept, "
        "status, report_threshold, loopfarm_version, merged_at";
    Statement add_input;
    add_input.prepare(m.path, db,
                      std::string("INSERT INTO merge_inputs (run_id, ") + kInputColumns +
                          ") VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10, ?11, ?12, ?13, ?14, ?15)");
    Statement add_session;
    add_session.prepare(m.path, db,
                        "INSERT INTO sessions (run_id, ranks, loopfarm_version, started_at, ended_at, status, "
                        "starts_done, input_id, source_session_id) VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9)");
    for (const auto& in : runs) {
      std::unordered_map<std::int64_t, std::int64_t> nested;  // its merge_inputs -> the output's
      if (in->schema_version >= 2) {
        Statement rows;
        rows.prepare(in->path, in->connection,
                     std::string("SELECT input_id, ") + kInputColumns + " FROM merge_inputs ORDER BY input_id");
        while (rows.step("cannot read merge_inputs")) {
          add_input.reset();
          add_input.bind(1, run_id);
          for (int c = 1; c <= 14; ++c) add_input.bind_value(c + 1, rows.value(c));
          add_input.run("cannot insert a merge input");
          nested[rows.integer(0)] = sqlite3_last_insert_rowid(db);
        }
      }
      add_input.reset();
      add_input.bind(1, run_id);
      add_input.bind(2, absolute_path(in->path));
      add_input.bind(3, in->run_id);
      add_input.bind(4, in->job_path);
      add_input.bind(5, in->job_hash);
      add_input.bind(6, in->seed);
      if (in->slice) {
        add_input.bind(7, static_cast<std::int64_t>(in->slice->index));
        add_input.bind(8, static_cast<std::int64_t>(in->slice->count));
      } else {
        add_input.bind_null(7);
        add_input.bind_null(8);
      }
      add_input.bind(9, static_cast<std::int64_t>(in->starts));
      add_input.bind(10, static_cast<std::int64_t>(in->starts_done));
      add_input.bind(11, std::int64_t{0});  // set below
      add_input.bind(12, in->status);
      add_input.bind(13, in->report_threshold);
      add_input.bind(14, in->loopfarm_version);
      add_input.bind(15, merged_at);
      add_input.run("cannot insert a merge input");
      in->input_id = sqlite3_last_insert_rowid(db);

      Statement sessions;
      sessions.prepare(in->path, in->connection,
                       std::string("SELECT session_id, ranks, loopfarm_version, started_at, ended_at, status, "
                                   "starts_done, ") +
                           (in->schema_version >= 2 ? "input_id, source_session_id" : "NULL, NULL") +
                           " FROM sessions WHERE run_id = ?1 ORDER BY session_id");
      sessions.bind(1, in->run_id);
      while (sessions.step("cannot read the sessions")) {
        add_session.reset();
        add_session.bind(1, run_id);
        for (int c = 1; c <= 6; ++c) add_session.bind_value(c + 1, sessions.value(c));
        const auto source = nested.find(sessions.integer(7));
        if (!sessions.is_null(7) && source != nested.end()) {
          add_session.bind(8, source->second);
          add_session.bind_value(9, sessions.value(8));
        } else {
          add_session.bind(8, in->input_id);
          add_session.bind(9, sessions.integer(0));
        }
        add_session.run("cannot insert a session");
        in->sessions[sessions.integer(0)] = sqlite3_last_insert_rowid(db);
      }
    }

    // The starts of every input in index order, merged.
    static const std::vector<std::string> candidate_names = candidate_columns();
    const auto position = [](const char* name) {
      return static_cast<int>(std::find(candidate_names.begin(), candidate_names.end(), name) -
                              candidate_names.begin());
    };
    static const int kFirstRun = position("first_run"), kFirstStart = position("first_start"),
                     kGridCellColumn = position("grid_cell"), kCanonicalKey = position("canonical_key"),
                     kCandidateGeometry = position("a1");
    std::string candidate_list;
    for (const std::string& name : candidate_names) candidate_list += (candidate_list.empty() ? "" : ", ") + name;
    for (const auto& in : runs) {
      in->cursor.prepare(in->path, in->connection,
                         "SELECT " + start_columns() + " FROM starts WHERE run_id = ?1 ORDER BY start_index");
      in->cursor.bind(1, in->run_id);
      // An input older than schema version 4 has not recorded the families
      // whose conditions hold, one older than version 5 no bond fingerprint:
      // NULL, as in an upgraded database. A fingerprint stored with the row a
      // merged candidate is made of comes with it.
      std::string input_list;
      for (const std::string& name : candidate_names) {
        const bool absent =
            (name == "families" && in->schema_version < 4) || (name == "bond_fingerprint" && in->schema_version < 5);
        input_list += (input_list.empty() ? "" : ", ") + (absent ? std::string("NULL") : name);
      }
      in->candidate.prepare(in->path, in->connection,
                            "SELECT " + input_list + " FROM candidates WHERE candidate_id = ?1");
    }
    Statement insert_candidate;
    {
      std::string values;
      for (size_t i = 1; i <= candidate_names.size(); ++i) values += (i > 1 ? ", ?" : "?") + std::to_string(i);
      insert_candidate.prepare(m.path, db,
                               "INSERT INTO candidates (" + candidate_list + ", hits) VALUES (" + values + ", 1)");
    }
    Statement hit;
    hit.prepare(m.path, db, "UPDATE candidates SET hits = hits + 1 WHERE candidate_id = ?1");
    Statement insert_start;
    {
      std::string values;
      for (int i = 1; i <= 12 + kGeometryColumns; ++i) values += (i > 1 ? ", ?" : "?") + std::to_string(i);
      insert_start.prepare(m.path, db,
                           "INSERT INTO starts (run_id, start_index, session_id, status, E_mean, E_max, objective, "
                           "evaluations, seconds, zero, verified, candidate_id, " +
                               geometry_columns("", "") + ") VALUES (" + values + ")");
    }

    // A start keeps its geometry when its E_mean is at most the merged run's report_threshold.
    const auto keeps_geometry = [&](const Statement& row) {
      return !row.is_null(kEMean) && row.real(kEMean) <= report_threshold;
    };
    // The row of start `index` in `other` must equal the one in `kept`.
    const auto check_same_row = [&](const InputRun& kept, const InputRun& other, std::uint64_t index) {
      const bool geometry_kept = keeps_geometry(kept.cursor), geometry_other = keeps_geometry(other.cursor);
      for (int c = kStatus; c < kGeometry + kGeometryColumns; ++c) {
        if (c == kSeconds || c == kCandidate) continue;
        if (c >= kGeometry && !geometry_kept && !geometry_other) break;
        sqlite3_value* x = kept.cursor.value(c);
        sqlite3_value* y = other.cursor.value(c);
        if (c >= kGeometry && geometry_kept != geometry_other) {
          // One side kept its geometry, the other not: E_mean differs, or the thresholds and E_mean do.
          if (!geometry_kept) x = nullptr;
          if (!geometry_other) y = nullptr;
        }
        if (x != nullptr && y != nullptr && same_value(x, y)) continue;
        if (x == nullptr && y == nullptr) continue;
        fail(other.path, "start " + std::to_string(index) + " differs from the same start in " + kept.path + " (" +
                             start_column_name(c) + " " + (y ? show_value(y) : std::string("NULL")) + " here, " +
                             (x ? show_value(x) : std::string("NULL")) +
                             " there): they were not computed alike (another build, machine or job), and loopfarm "
                             "merge keeps a start only when its rows agree");
      }
    };

    using Head = std::pair<std::uint64_t, size_t>;  // (start index, input)
    std::priority_queue<Head, std::vector<Head>, std::greater<>> heads;
    const auto advance = [&](size_t k) {
      if (runs[k]->cursor.step("cannot read the starts")) {
        heads.push({static_cast<std::uint64_t>(runs[k]->cursor.integer(kStartIndex)), k});
      }
    };
    for (size_t k = 0; k < runs.size(); ++k) advance(k);
    std::uint64_t below_target = 0;
    std::vector<size_t> holders;
    while (!heads.empty()) {
      const std::uint64_t index = heads.top().first;
      holders.clear();
      while (!heads.empty() && heads.top().first == index) {
        holders.push_back(heads.top().second);
        heads.pop();
      }
      std::sort(holders.begin(), holders.end());
      InputRun& kept = *runs[holders.front()];
      const Statement& row = kept.cursor;
      for (size_t h = 1; h < holders.size(); ++h) check_same_row(kept, *runs[holders[h]], index);
      if (holders.size() > 1) ++summary.overlapping_starts;

      std::int64_t merged_candidate = 0;
      if (row.integer(kVerified) == 1 && !row.is_null(kCandidate)) {
        const std::int64_t own = row.integer(kCandidate);
        if (const auto found = kept.candidates.find(own); found != kept.candidates.end()) {
          merged_candidate = found->second;
          hit.reset();
          hit.bind(1, merged_candidate);
          hit.run("cannot update a candidate");
        } else {
          // The input's representative of this linkage: de-duplicated as the run would.
          Statement& c = kept.candidate.reset();
          c.bind(1, own);
          if (!c.step("cannot read the candidates")) {
            fail(kept.path,
                 "start " + std::to_string(index) + " names candidate " + std::to_string(own) + ", which is not there");
          }
          if (static_cast<std::uint64_t>(c.integer(kFirstStart)) != index) {
            fail(kept.path, "candidate " + std::to_string(own) + " names start " +
                                std::to_string(c.integer(kFirstStart)) + " as its first, but start " +
                                std::to_string(index) + " is the first that found it: the database is inconsistent");
          }
          CanonicalEntry entry;
          entry.joints = static_cast<int>(c.integer(0));
          if (entry.joints < 1 || entry.joints > kMaxJoints) {
            fail(kept.path, "candidate " + std::to_string(own) + " has " + std::to_string(entry.joints) + " joints");
          }
          const int n = entry.joints;
          entry.key = c.text(kCanonicalKey);
          const bool complete = read_canonical_values(c, kCandidateGeometry, n, entry);
          // An input older than schema version 7 may hold the key written
          // before the twist at a zero-length link was taken with either sign,
          // or before the normal between parallel axes was centred: such a
          // row is keyed again, as the upgrade does (results_rekey.hpp).
          std::optional<RekeyedCandidate> rekeyed;
          if (kept.schema_version < 7) {
            entry.first_run = run_id;
            entry.first_start = static_cast<std::int64_t>(index);
            if (complete) rekeyed = rekey_candidate(entry);
            if (rekeyed) entry = rekeyed->entry;
          }
          if (const std::optional<CanonicalEntry> match = m.find_candidate(entry, dedup_tolerance)) {
            merged_candidate = match->id;
            hit.reset();
            hit.bind(1, merged_candidate);
            hit.run("cannot update a candidate");
          } else {
            insert_candidate.reset();
            const CellOptions own_cell = cell_options(entry, 0.0);
            for (int i = 0; i < static_cast<int>(candidate_names.size()); ++i) {
              if (i == kFirstRun) {
                insert_candidate.bind(i + 1, run_id);
              } else if (i == kFirstStart) {
                insert_candidate.bind(i + 1, static_cast<std::int64_t>(index));
              } else if (i == kGridCellColumn) {
                insert_candidate.bind(i + 1, cell_name(own_cell, CellChoice{}));
              } else if (rekeyed && i == kCanonicalKey) {
                insert_candidate.bind(i + 1, rekeyed->entry.key);
              } else if (rekeyed && i >= kCandidateGeometry && i < kCandidateGeometry + kGeometryColumns) {
                // Twists in degrees, as a run stores them.
                const int list = (i - kCandidateGeometry) / kMaxJoints, k = (i - kCandidateGeometry) % kMaxJoints;
                const LoopGeometry& g = rekeyed->geometry;
                if (k >= g.joints()) {
                  insert_candidate.bind_null(i + 1);
                } else if (list == 1) {
                  insert_candidate.bind(i + 1, stored_twist(g.alpha[k]));
                } else {
                  insert_candidate.bind(i + 1, list == 0 ? g.a[k] : g.d[k]);
                }
              } else {
                insert_candidate.bind_value(i + 1, c.value(i));
              }
            }
            insert_candidate.run("cannot insert a candidate");
            merged_candidate = sqlite3_last_insert_rowid(db);
            // Into the store's in-memory index too, so that the next start
            // of this linkage, from any input, finds it (find_candidate).
            m.index_candidate(merged_candidate, entry, own_cell);
          }
          c.reset();
          kept.candidates[own] = merged_candidate;
        }
        ++summary.verified;
        // The same start in the other inputs: their candidate of it goes where it went.
        for (size_t h = 1; h < holders.size(); ++h) {
          const Statement& same = runs[holders[h]]->cursor;
          if (!same.is_null(kCandidate))
            runs[holders[h]]->candidates.try_emplace(same.integer(kCandidate), merged_candidate);
        }
      }

      Statement& s = insert_start.reset();
      s.bind(1, run_id);
      s.bind(2, static_cast<std::int64_t>(index));
      const auto session = kept.sessions.find(row.integer(kSession));
      if (!row.is_null(kSession) && session != kept.sessions.end()) {
        s.bind(3, session->second);
      } else {
        s.bind_null(3);
      }
      for (int c = kStatus; c <= kVerified; ++c) s.bind_value(c + 2, row.value(c));
      if (merged_candidate != 0) {
        s.bind(12, merged_candidate);
      } else {
        s.bind_null(12);
      }
      const bool geometry = keeps_geometry(row);
      for (int i = 0; i < kGeometryColumns; ++i) {
        if (geometry) {
          s.bind_value(13 + i, row.value(kGeometry + i));
        } else {
          s.bind_null(13 + i);
        }
      }
      s.run("cannot insert a start");
      ++summary.starts;
      ++kept.kept;
      if (index < target) ++below_target;
      for (size_t k : holders) advance(k);
    }

    summary.complete = below_target == target;
    Statement done;
    done.prepare(m.path, db,
                 std::string("UPDATE runs SET starts_done = ?1, status = ?2, updated_at = ") + kNow +
                     ", ended_at = CASE WHEN ?2 = 'complete' THEN " + kNow + " END WHERE run_id = ?3");
    done.bind(1, static_cast<std::int64_t>(summary.starts));
    done.bind(2, summary.complete ? "complete" : "stopped");
    done.bind(3, run_id);
    done.run("cannot update the run");
    Statement kept_rows;
    kept_rows.prepare(m.path, db, "UPDATE merge_inputs SET starts_kept = ?1 WHERE input_id = ?2");
    for (const auto& in : runs) {
      kept_rows.reset();
      kept_rows.bind(1, static_cast<std::int64_t>(in->kept));
      kept_rows.bind(2, in->input_id);
      kept_rows.run("cannot update a merge input");
    }
    summary.candidates = query_integer(m.path, db, "SELECT COUNT(*) FROM candidates");
    transaction.commit();
  }  // closed: every commit in the file, the companion files gone
  temporary.rename_to(output);
  return summary;
}

}  // namespace loopfarm
