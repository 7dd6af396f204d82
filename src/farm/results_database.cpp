// The SQLite results database (results_database.hpp, docs/database.md).
//
// Every write is one BEGIN IMMEDIATE ... COMMIT transaction held by a
// Transaction guard that rolls back on any exception, so that an error leaves
// the file as it was. Statements are prepared once per connection and reset
// after use.
#include "loopfarm/farm/results_database.hpp"

#include <sqlite3.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <optional>

#include "loopfarm/core/loop.hpp"

#ifndef LOOPFARM_VERSION
#error "LOOPFARM_VERSION is defined by the loopfarm library target"
#endif

namespace loopfarm {
namespace {

constexpr double kDegreesPerRadian = 180.0 / 3.14159265358979323846;
constexpr double kRadiansPerDegree = 3.14159265358979323846 / 180.0;
// ISO 8601 UTC, evaluated by SQLite once per statement.
constexpr const char* kNow = "strftime('%Y-%m-%dT%H:%M:%SZ','now')";

[[noreturn]] void fail(const std::string& path, const std::string& what) {
  throw DatabaseError("results database " + path + ": " + what);
}

[[noreturn]] void fail_sqlite(const std::string& path, sqlite3* db, const std::string& what) {
  fail(path, what + ": " + (db ? sqlite3_errmsg(db) : "out of memory"));
}

std::string hex32(std::int64_t value) {
  char buffer[16];
  std::snprintf(buffer, sizeof buffer, "0x%08x", static_cast<unsigned>(static_cast<std::uint32_t>(value)));
  return buffer;
}

std::string format_double(double value) {
  char buffer[40];
  std::snprintf(buffer, sizeof buffer, "%.17g", value);
  return buffer;
}

// a1..a8, alpha1_deg..alpha8_deg, d1..d8, each with `prefix` and `suffix`;
// the three lists separated by `list_separator`.
std::string geometry_columns(const std::string& prefix, const std::string& suffix,
                             const std::string& list_separator = ", ") {
  std::string out;
  for (const char* name : {"a", "alpha", "d"}) {
    for (int i = 1; i <= kMaxJoints; ++i) {
      if (!out.empty()) out += i == 1 ? list_separator : ", ";
      out += prefix + name + std::to_string(i) + (std::string(name) == "alpha" ? "_deg" : "") + suffix;
    }
  }
  return out;
}

// The candidate columns that describe the representative start, in bind order
// (the geometry expands to its 24 columns); everything but candidate_id and hits.
std::vector<std::string> candidate_columns() {
  std::vector<std::string> out = {"joints", "family", "setup", "detail", "canonical_key"};
  for (const char* name : {"a", "alpha", "d"}) {
    for (int i = 1; i <= kMaxJoints; ++i) {
      out.push_back(name + std::to_string(i) + (std::string(name) == "alpha" ? "_deg" : ""));
    }
  }
  for (const char* name : {"family_residual", "bennett_residual", "planar_residual", "spherical_residual",
                           "trivial_residual", "rigid_residual", "full_turn", "range_lo_deg", "range_hi_deg",
                           "local_dimension", "free_parameters", "singular_values", "E_mean", "E_max", "first_run",
                           "first_start", "grid_cell"}) {
    out.push_back(name);
  }
  return out;
}

std::string schema_sql() {
  const std::string geometry = geometry_columns("", " REAL", ",\n  ");
  const std::string start_geometry = geometry_columns("s.", "", ",\n         ");
  return
      "CREATE TABLE runs (\n"
      "  run_id INTEGER PRIMARY KEY,\n"
      "  job_path TEXT NOT NULL,\n"
      "  job_text TEXT NOT NULL,\n"
      "  job_hash TEXT NOT NULL,\n"
      "  seed INTEGER NOT NULL,\n"
      "  starts INTEGER NOT NULL,\n"
      "  joints INTEGER NOT NULL,\n"
      "  zero_threshold REAL NOT NULL,\n"
      "  report_threshold REAL NOT NULL,\n"
      "  loopfarm_version TEXT NOT NULL,\n"
      "  ranks INTEGER,\n"
      "  started_at TEXT NOT NULL,\n"
      "  updated_at TEXT NOT NULL,\n"
      "  ended_at TEXT,\n"
      "  status TEXT NOT NULL CHECK (status IN ('running', 'stopped', 'complete', 'failed')),\n"
      "  starts_done INTEGER NOT NULL DEFAULT 0\n"
      ");\n"
      "CREATE TABLE sessions (\n"
      "  session_id INTEGER PRIMARY KEY,\n"
      "  run_id INTEGER NOT NULL REFERENCES runs(run_id),\n"
      "  ranks INTEGER NOT NULL,\n"
      "  loopfarm_version TEXT NOT NULL,\n"
      "  started_at TEXT NOT NULL,\n"
      "  ended_at TEXT,\n"
      "  status TEXT NOT NULL CHECK (status IN ('running', 'stopped', 'complete', 'failed')),\n"
      "  starts_done INTEGER NOT NULL DEFAULT 0\n"
      ");\n"
      "CREATE INDEX sessions_by_run ON sessions(run_id);\n"
      "CREATE TABLE candidates (\n"
      "  candidate_id INTEGER PRIMARY KEY,\n"
      "  joints INTEGER NOT NULL,\n"
      "  family TEXT NOT NULL,\n"
      "  setup TEXT NOT NULL,\n"
      "  detail TEXT NOT NULL,\n"
      "  canonical_key TEXT NOT NULL,\n"
      "  " + geometry + ",\n"
      "  family_residual REAL,\n"
      "  bennett_residual REAL,\n"
      "  planar_residual REAL,\n"
      "  spherical_residual REAL,\n"
      "  trivial_residual REAL,\n"
      "  rigid_residual REAL,\n"
      "  full_turn INTEGER NOT NULL CHECK (full_turn IN (0, 1)),\n"
      "  range_lo_deg REAL,\n"
      "  range_hi_deg REAL,\n"
      "  local_dimension INTEGER NOT NULL,\n"
      "  free_parameters INTEGER NOT NULL,\n"
      "  singular_values TEXT NOT NULL,\n"
      "  E_mean REAL,\n"
      "  E_max REAL,\n"
      "  first_run INTEGER NOT NULL REFERENCES runs(run_id),\n"
      "  first_start INTEGER NOT NULL,\n"
      "  grid_cell TEXT NOT NULL,\n"
      "  hits INTEGER NOT NULL DEFAULT 1\n"
      ");\n"
      "CREATE INDEX candidates_by_joints_family ON candidates(joints, family);\n"
      "CREATE INDEX candidates_by_key ON candidates(joints, canonical_key);\n"
      "CREATE INDEX candidates_by_cell ON candidates(joints, grid_cell);\n"
      // WITHOUT ROWID: the primary key is the table's own b-tree, so a start
      // costs one row and no separate index (the database is sized per start).
      "CREATE TABLE starts (\n"
      "  run_id INTEGER NOT NULL REFERENCES runs(run_id),\n"
      "  start_index INTEGER NOT NULL,\n"
      "  session_id INTEGER REFERENCES sessions(session_id),\n"
      "  status TEXT NOT NULL,\n"
      "  E_mean REAL,\n"
      "  E_max REAL,\n"
      "  objective REAL,\n"
      "  evaluations INTEGER NOT NULL,\n"
      "  seconds REAL,\n"
      "  zero INTEGER NOT NULL CHECK (zero IN (0, 1)),\n"
      "  verified INTEGER NOT NULL CHECK (verified IN (0, 1)),\n"
      "  candidate_id INTEGER REFERENCES candidates(candidate_id),\n"
      "  " + geometry + ",\n"
      "  PRIMARY KEY (run_id, start_index)\n"
      ") WITHOUT ROWID;\n"
      "CREATE INDEX starts_zero_by_energy ON starts(E_mean) WHERE zero = 1;\n"
      "CREATE INDEX starts_by_candidate ON starts(candidate_id) WHERE candidate_id IS NOT NULL;\n"
      "CREATE VIEW zero_minima AS\n"
      "  SELECT s.run_id, s.start_index, s.E_mean, s.E_max, s.objective, s.status, s.evaluations, s.seconds,\n"
      "         s.verified, s.candidate_id, c.family, c.setup, c.local_dimension, c.family_residual,\n"
      "         c.rigid_residual,\n"
      "         " + start_geometry + "\n"
      "  FROM starts AS s LEFT JOIN candidates AS c ON c.candidate_id = s.candidate_id\n"
      "  WHERE s.zero = 1\n"
      "  ORDER BY s.E_mean, s.run_id, s.start_index;\n"
      "CREATE VIEW family_counts AS\n"
      "  SELECT family, COUNT(*) AS candidates, SUM(hits) AS hits\n"
      "  FROM candidates GROUP BY family ORDER BY hits DESC, family;\n"
      "CREATE VIEW status_counts AS\n"
      "  SELECT run_id, status, COUNT(*) AS starts, SUM(zero) AS zeros, SUM(verified) AS verified\n"
      "  FROM starts GROUP BY run_id, status ORDER BY run_id, starts DESC, status;\n"
      "CREATE VIEW energy_histogram AS\n"
      "  SELECT run_id, CASE WHEN E_mean > 0 THEN CAST(floor(log10(E_mean)) AS INTEGER) END AS log10_E_mean,\n"
      "         COUNT(*) AS starts\n"
      "  FROM starts WHERE E_mean IS NOT NULL\n"
      "  GROUP BY run_id, log10_E_mean ORDER BY run_id, log10_E_mean;\n"
      "CREATE VIEW run_summary AS\n"
      "  SELECT r.run_id, r.job_path, r.seed, r.status, r.starts, r.starts_done,\n"
      "         (SELECT COUNT(*) FROM starts AS s WHERE s.run_id = r.run_id AND s.zero = 1) AS zeros,\n"
      "         (SELECT COUNT(*) FROM starts AS s WHERE s.run_id = r.run_id AND s.verified = 1) AS verified,\n"
      "         (SELECT COUNT(*) FROM candidates AS c WHERE c.first_run = r.run_id) AS new_candidates,\n"
      "         (SELECT MIN(s.E_mean) FROM starts AS s WHERE s.run_id = r.run_id) AS best_E_mean,\n"
      "         (SELECT SUM(s.seconds) FROM starts AS s WHERE s.run_id = r.run_id) AS start_seconds,\n"
      "         r.started_at, r.updated_at, r.ended_at\n"
      "  FROM runs AS r ORDER BY r.run_id;\n";
}

// An open sqlite3 connection; closed (with sqlite3_close_v2, so that order
// against statements does not matter) when it goes.
struct Connection {
  sqlite3* db = nullptr;

  Connection() = default;
  Connection(const Connection&) = delete;
  Connection& operator=(const Connection&) = delete;
  ~Connection() { sqlite3_close_v2(db); }
};

// Opens `path` (or the URI `filename` for it); errors name `path`.
void open_connection(Connection& c, const std::string& path, int flags, const std::string& filename = {}) {
  const int rc = sqlite3_open_v2((filename.empty() ? path : filename).c_str(), &c.db, flags, nullptr);
  if (rc != SQLITE_OK) fail_sqlite(path, c.db, "cannot open");
  sqlite3_extended_result_codes(c.db, 1);
  sqlite3_busy_timeout(c.db, kDatabaseBusyTimeoutMs);
  // The last connection to close a WAL database checkpoints and deletes the
  // WAL under an EXCLUSIVE lock on the file, and a reader that opens the file
  // in that moment without a busy timeout (the sqlite3 shell) fails with
  // "database is locked": 30 of 4696 and 49 of 3768 plain sqlite3 reads
  // across 40 short runs did (docs/reliability-faults.md). A read-only connection cannot
  // checkpoint anyway, so it does not try; the writer checkpoints before it
  // closes (~Impl), without that lock, and keeps it for a few microseconds
  // only (deleting the empty WAL).
  if ((flags & SQLITE_OPEN_READONLY) != 0) sqlite3_db_config(c.db, SQLITE_DBCONFIG_NO_CKPT_ON_CLOSE, 1, nullptr);
}

// An SQLite URI that opens `path` read-only as immutable: no locks, no WAL,
// no companion files. '%', '?' and '#' are escaped; an absolute path gets an
// empty authority ("file:///...").
std::string immutable_uri(const std::string& path) {
  std::string uri = path.rfind('/', 0) == 0 ? "file://" : "file:";
  for (const char c : path) {
    if (c == '%' || c == '?' || c == '#') {
      char escaped[4];
      std::snprintf(escaped, sizeof escaped, "%%%02X", static_cast<unsigned char>(c));
      uri += escaped;
    } else {
      uri += c;
    }
  }
  return uri + "?immutable=1";
}

// NAME-wal exists and is not empty: commits may be there and not yet in the file.
bool has_commits_in_wal(const std::string& path) {
  std::error_code error;
  const std::uintmax_t size = std::filesystem::file_size(path + "-wal", error);
  return !error && size > 0;
}

void exec(const std::string& path, sqlite3* db, const std::string& sql, const char* what) {
  char* message = nullptr;
  if (sqlite3_exec(db, sql.c_str(), nullptr, nullptr, &message) != SQLITE_OK) {
    const std::string text = message ? message : sqlite3_errmsg(db);
    sqlite3_free(message);
    fail(path, std::string(what) + ": " + text);
  }
}

// A prepared statement, reset (bindings cleared) before every use.
class Statement {
 public:
  Statement() = default;
  Statement(const Statement&) = delete;
  Statement& operator=(const Statement&) = delete;
  ~Statement() { sqlite3_finalize(stmt_); }

  bool prepared() const { return stmt_ != nullptr; }

  void prepare(const std::string& path, sqlite3* db, const std::string& sql) {
    path_ = &path;
    db_ = db;
    if (sqlite3_prepare_v3(db, sql.c_str(), -1, SQLITE_PREPARE_PERSISTENT, &stmt_, nullptr) != SQLITE_OK) {
      fail_sqlite(path, db, "cannot prepare \"" + sql.substr(0, 60) + "...\"");
    }
  }

  Statement& reset() {
    sqlite3_reset(stmt_);
    sqlite3_clear_bindings(stmt_);
    return *this;
  }

  void bind_null(int i) { check(sqlite3_bind_null(stmt_, i)); }
  void bind(int i, std::int64_t value) { check(sqlite3_bind_int64(stmt_, i, value)); }
  void bind(int i, int value) { check(sqlite3_bind_int64(stmt_, i, value)); }
  void bind(int i, bool value) { check(sqlite3_bind_int64(stmt_, i, value ? 1 : 0)); }
  // NaN and infinities are NULL: SQL has no NaN, and a residual that does not
  // apply (+inf) reads best as "no value".
  void bind(int i, double value) {
    check(std::isfinite(value) ? sqlite3_bind_double(stmt_, i, value) : sqlite3_bind_null(stmt_, i));
  }
  void bind(int i, const std::string& value) {
    check(sqlite3_bind_text(stmt_, i, value.data(), static_cast<int>(value.size()), SQLITE_TRANSIENT));
  }
  void bind(int i, const char* value) { check(sqlite3_bind_text(stmt_, i, value, -1, SQLITE_TRANSIENT)); }

  // True for a row, false when done; throws on an error (the statement is
  // reset, so that it holds no lock).
  bool step(const char* what) {
    const int rc = sqlite3_step(stmt_);
    if (rc == SQLITE_ROW) return true;
    if (rc == SQLITE_DONE) return false;
    const std::string message = sqlite3_errmsg(db_);
    sqlite3_reset(stmt_);
    fail(*path_, std::string(what) + ": " + message);
  }
  void run(const char* what) {
    step(what);
    sqlite3_reset(stmt_);
  }
  // The result code of one step (extended), the statement reset: for callers
  // that explain particular errors themselves.
  int step_code(std::string& message) {
    const int rc = sqlite3_step(stmt_);
    if (rc != SQLITE_ROW && rc != SQLITE_DONE) message = sqlite3_errmsg(db_);
    sqlite3_reset(stmt_);
    return rc;
  }

  std::int64_t integer(int column) const { return sqlite3_column_int64(stmt_, column); }
  bool is_null(int column) const { return sqlite3_column_type(stmt_, column) == SQLITE_NULL; }
  double real(int column) const { return sqlite3_column_double(stmt_, column); }
  std::string text(int column) const {
    const auto* bytes = reinterpret_cast<const char*>(sqlite3_column_text(stmt_, column));
    return bytes ? std::string(bytes, static_cast<size_t>(sqlite3_column_bytes(stmt_, column))) : std::string();
  }

 private:
  void check(int rc) const {
    if (rc != SQLITE_OK) fail_sqlite(*path_, db_, "cannot bind a parameter");
  }

  const std::string* path_ = nullptr;
  sqlite3* db_ = nullptr;
  sqlite3_stmt* stmt_ = nullptr;
};

std::int64_t query_integer(const std::string& path, sqlite3* db, const std::string& sql) {
  Statement s;
  s.prepare(path, db, sql);
  if (!s.step(sql.c_str())) fail(path, sql + " returned no row");
  return s.integer(0);
}

std::string query_text(const std::string& path, sqlite3* db, const std::string& sql) {
  Statement s;
  s.prepare(path, db, sql);
  if (!s.step(sql.c_str())) fail(path, sql + " returned no row");
  return s.text(0);
}

// SQLite's own words for a damaged file ("database disk image is
// malformed") do not say which file or that it is the file's fault: say both.
[[noreturn]] void fail_read(const std::string& path, int rc, const std::string& what, const std::string& message) {
  if ((rc & 0xff) == SQLITE_NOTADB) fail(path, "not an SQLite database");
  if ((rc & 0xff) == SQLITE_CORRUPT) fail(path, "damaged (" + what + ": " + message + ")");
  fail(path, what + ": " + message);
}

// The schema version of a loopfarm database, or 0 for an empty database (no
// schema objects, no application_id: a file this program may initialise when
// `allow_empty`). Refuses everything else. Reads only.
int check_identity(const std::string& path, sqlite3* db, bool allow_empty) {
  // The first read of the file: say plainly when it is not SQLite at all, or
  // damaged where SQLite reads first (the header, page 1, a file cut short).
  sqlite3_stmt* first = nullptr;
  int rc = sqlite3_prepare_v2(db, "PRAGMA application_id", -1, &first, nullptr);
  if (rc == SQLITE_OK) rc = sqlite3_step(first);
  const std::int64_t application_id = rc == SQLITE_ROW ? sqlite3_column_int64(first, 0) : 0;
  const std::string message = sqlite3_errmsg(db);
  sqlite3_finalize(first);
  if (rc != SQLITE_ROW) fail_read(path, rc, "cannot read PRAGMA application_id", message);
  const std::int64_t version = query_integer(path, db, "PRAGMA user_version");
  if (application_id == 0 && version == 0 && query_integer(path, db, "SELECT COUNT(*) FROM sqlite_schema") == 0) {
    if (allow_empty) return 0;
    fail(path, "an empty database, not a loopfarm results database");
  }
  if (application_id != kDatabaseApplicationId) {
    fail(path, "not a loopfarm results database (PRAGMA application_id is " + hex32(application_id) + ", expected " +
                   hex32(kDatabaseApplicationId) + ")");
  }
  if (version > kDatabaseSchemaVersion) {
    fail(path, "schema version " + std::to_string(version) + " is newer than this loopfarm " LOOPFARM_VERSION
               " knows (" + std::to_string(kDatabaseSchemaVersion) + "): use a newer loopfarm");
  }
  if (version != kDatabaseSchemaVersion) fail(path, "unknown schema version " + std::to_string(version));
  return static_cast<int>(version);
}

// PRAGMA quick_check: every page of the file read and its b-tree structure
// checked (not index against table contents, which integrity_check adds at
// several times the cost). Damage it finds is reported as a few of its
// problems on one line.
void check_integrity(const std::string& path, sqlite3* db) {
  sqlite3_stmt* check = nullptr;
  int rc = sqlite3_prepare_v2(db, "PRAGMA quick_check", -1, &check, nullptr);
  std::string problems;
  int shown = 0;
  while (rc == SQLITE_OK || rc == SQLITE_ROW) {
    rc = sqlite3_step(check);
    if (rc != SQLITE_ROW) break;
    const auto* text = reinterpret_cast<const char*>(sqlite3_column_text(check, 0));
    const std::string row = text ? text : "";
    if (row == "ok" || row.rfind("*** in database", 0) == 0) continue;  // the heading of a list of problems
    if (shown++ < 3) problems += (problems.empty() ? "" : "; ") + row;
  }
  const std::string message = sqlite3_errmsg(db);
  sqlite3_finalize(check);
  if (rc != SQLITE_DONE) fail_read(path, rc, "PRAGMA quick_check", message);
  if (shown == 0) return;
  for (char& c : problems) {
    if (c == '\n' || c == '\r' || c == '\t') c = ' ';
  }
  if (shown > 3) problems += "; ...";
  fail(path, "damaged (PRAGMA quick_check: " + problems + ")");
}

// BEGIN IMMEDIATE on construction; ROLLBACK when it goes without commit().
class Transaction {
 public:
  Transaction(const std::string& path, sqlite3* db) : path_(path), db_(db) {
    exec(path, db, "BEGIN IMMEDIATE", "cannot begin a transaction");
  }
  Transaction(const Transaction&) = delete;
  Transaction& operator=(const Transaction&) = delete;
  ~Transaction() {
    if (open_) sqlite3_exec(db_, "ROLLBACK", nullptr, nullptr, nullptr);
  }
  void commit() {
    exec(path_, db_, "COMMIT", "cannot commit");
    open_ = false;
  }

 private:
  const std::string& path_;
  sqlite3* db_;
  bool open_ = true;
};

std::string json_array(const std::vector<double>& values) {
  std::string out = "[";
  for (size_t i = 0; i < values.size(); ++i) {
    if (i) out += ',';
    out += std::isfinite(values[i]) ? format_double(values[i]) : "null";
  }
  return out + "]";
}

// What de-duplication compares of one candidate: its canonical geometry as the
// database holds it (twists through their stored degrees, so that a record
// compares with a stored row exactly as the row would) and its first start.
struct CanonicalEntry {
  std::int64_t id = 0;
  std::string key;
  int joints = 0;
  std::array<double, 3 * kMaxJoints> values{};  // a, alpha [rad], d
  std::int64_t first_run = 0;
  std::int64_t first_start = 0;
};

// The largest difference between two canonical geometries of n joints
// (twists wrapped), stopping early once it exceeds `tolerance`.
double canonical_distance(const CanonicalEntry& x, const CanonicalEntry& y, double tolerance) {
  const int n = x.joints;
  double distance = 0.0;
  for (int i = 0; i < 3 * n && distance <= tolerance; ++i) {
    const double difference = x.values[i] - y.values[i];
    distance = std::max(distance, std::abs(i >= n && i < 2 * n ? wrap_angle(difference) : difference));
  }
  return distance;
}

// De-duplication looks a record up by the grid cell of its canonical
// geometry: every value (a and d at L = 1, twists in radians) cut into cells
// of width kGridCell, twists on a circle of whole cells so that -pi and pi
// meet. Two geometries within the tolerance (< kGridCell) of each other lie
// in the same cell or, for each value near a cell edge, the neighbouring one:
// the lookup tries every such combination (usually one or two cells), so its
// cost does not grow with the number of candidates, not even when thousands
// share a value (searches that end on a bound).
constexpr double kGridCell = 1e-3;
constexpr long kTwistCells = 6283;  // round(2 pi / kGridCell): twists wrap on whole cells
constexpr size_t kMaxCellCombinations = 4096;

// Per value, the cells a geometry within `tolerance` may occupy (the first is
// the value's own).
std::vector<std::vector<long>> cell_options(const CanonicalEntry& c, double tolerance) {
  const int n = c.joints;
  constexpr double kTwoPi = 2.0 * 3.14159265358979323846;
  std::vector<std::vector<long>> options(static_cast<size_t>(3 * n));
  for (int i = 0; i < 3 * n; ++i) {
    const bool twist = i >= n && i < 2 * n;
    const double width = twist ? kTwoPi / kTwistCells : kGridCell;
    const double u = twist ? (c.values[i] + kTwoPi / 2) / width : c.values[i] / width;
    const double cell = std::floor(u);
    const double offset = (u - cell) * width;  // distance above the cell's lower edge
    auto wrap = [twist](long k) { return twist ? ((k % kTwistCells) + kTwistCells) % kTwistCells : k; };
    const long k = static_cast<long>(cell);
    std::vector<long>& o = options[static_cast<size_t>(i)];
    o.push_back(wrap(k));
    if (offset <= tolerance) o.push_back(wrap(k - 1));
    if (width - offset <= tolerance) o.push_back(wrap(k + 1));
  }
  return options;
}

std::string cell_name(const std::vector<std::vector<long>>& options, const std::vector<size_t>& choice) {
  std::string out;
  for (size_t i = 0; i < options.size(); ++i) {
    if (i > 0) out += ',';
    out += std::to_string(options[i][choice[i]]);
  }
  return out;
}

// The grid cell a candidate is stored under.
std::string grid_cell(const CanonicalEntry& c) {
  const auto options = cell_options(c, 0.0);
  return cell_name(options, std::vector<size_t>(options.size(), 0));
}

double stored_twist(double radians) { return radians * kDegreesPerRadian; }
double twist_from_stored(double degrees) { return degrees * kRadiansPerDegree; }

CanonicalEntry canonical_entry(const StartRecord& r, std::int64_t run_id) {
  const LoopGeometry& g = r.candidate.canonical_geometry;
  const int n = g.joints();
  CanonicalEntry c;
  c.key = r.candidate.canonical_key;
  c.joints = n;
  for (int i = 0; i < n; ++i) {
    c.values[i] = g.a[i];
    c.values[n + i] = twist_from_stored(stored_twist(g.alpha[i]));
    c.values[2 * n + i] = g.d[i];
  }
  c.first_run = run_id;
  c.first_start = static_cast<std::int64_t>(r.index);
  return c;
}

void check_geometry(const std::string& path, const LoopGeometry& g, const char* what, std::uint64_t index) {
  if (g.alpha.size() != g.a.size() || g.d.size() != g.a.size()) {
    fail(path, std::string(what) + " of start " + std::to_string(index) + " has lists of different lengths");
  }
}

}  // namespace

const char* to_string(RunStatus status) {
  switch (status) {
    case RunStatus::running: return "running";
    case RunStatus::stopped: return "stopped";
    case RunStatus::complete: return "complete";
    case RunStatus::failed: return "failed";
  }
  return "failed";
}

std::string job_hash(std::string_view text) {
  std::uint64_t hash = 0xcbf29ce484222325ull;  // FNV-1a 64 offset basis
  for (const char c : text) {
    hash ^= static_cast<unsigned char>(c);
    hash *= 0x100000001b3ull;  // FNV-1a 64 prime
  }
  char buffer[20];
  std::snprintf(buffer, sizeof buffer, "%016llx", static_cast<unsigned long long>(hash));
  return buffer;
}

std::uint64_t RunInfo::committed_count() const {
  std::uint64_t count = 0;
  for (const IndexRange& r : committed) count += r.last - r.first;
  return count;
}

bool RunInfo::is_committed(std::uint64_t index) const {
  // The first range that ends after index; it holds index if it starts at or before it.
  const auto it = std::upper_bound(committed.begin(), committed.end(), index,
                                   [](std::uint64_t i, const IndexRange& r) { return i < r.last; });
  return it != committed.end() && it->first <= index;
}

std::uint64_t RunInfo::committed_prefix() const {
  return !committed.empty() && committed.front().first == 0 ? committed.front().last : 0;
}

struct ResultsDatabase::Impl {
  std::string path;
  DatabaseMode mode = DatabaseMode::read;
  Connection connection;  // first, so that it is closed after the statements

  Statement insert_start;
  Statement insert_candidate;
  Statement replace_candidate;
  Statement hit_candidate;
  Statement select_by_key;
  Statement select_by_cell;
  Statement select_all;

  std::int64_t session_id = 0;  // 0: no open session
  std::int64_t session_run = 0;
  bool checkpoint_on_close = false;  // a writer whose open succeeded

  Impl() = default;
  Impl(const Impl&) = delete;
  Impl& operator=(const Impl&) = delete;
  // Copies every committed page from the WAL into the file and empties the
  // WAL, so that the file alone holds everything (a copy of it is whole) and
  // the checkpoint that closing does under an EXCLUSIVE lock finds nothing
  // left to copy (open_connection). A reader still on an old snapshot delays
  // it up to 1 s, then it is left to the close or the next writer: the WAL
  // keeps the commits either way.
  ~Impl() {
    if (!checkpoint_on_close || connection.db == nullptr) return;
    sqlite3_busy_timeout(connection.db, 1000);
    sqlite3_exec(connection.db, "PRAGMA wal_checkpoint(TRUNCATE)", nullptr, nullptr, nullptr);
  }

  sqlite3* db() const { return connection.db; }

  void require_write(const char* what) const {
    if (mode != DatabaseMode::write) fail(path, std::string(what) + ": the database is open read-only");
  }

  Statement& prepared(Statement& s, const std::string& sql) {
    if (!s.prepared()) s.prepare(path, db(), sql);
    return s.reset();
  }

  std::optional<CanonicalEntry> find_candidate(const CanonicalEntry& incoming, double tolerance);
  std::int64_t place_candidate(std::int64_t run_id, const StartRecord& r, double tolerance, CommitSummary& summary);
  void bind_candidate(Statement& s, std::int64_t run_id, const StartRecord& r);
};

// The stored candidate of the same linkage as `incoming`: the one with its
// canonical key, else the nearest whose values are all within `tolerance`
// (largest difference smallest, then lowest id). Looked up through the
// indexes on (joints, canonical_key) and (joints, grid_cell), so that rank
// 0's memory does not grow with the number of candidates and a lookup costs
// the same whatever their number.
std::optional<CanonicalEntry> ResultsDatabase::Impl::find_candidate(const CanonicalEntry& incoming,
                                                                     double tolerance) {
  const int n = incoming.joints;
  auto read = [n](Statement& s) {
    CanonicalEntry c;
    c.id = s.integer(0);
    c.key = s.text(1);
    c.first_run = s.integer(2);
    c.first_start = s.integer(3);
    c.joints = n;
    for (int i = 0; i < n; ++i) {
      c.values[i] = s.real(4 + i);
      c.values[n + i] = twist_from_stored(s.real(4 + kMaxJoints + i));
      c.values[2 * n + i] = s.real(4 + 2 * kMaxJoints + i);
    }
    return c;
  };
  static const std::string columns =
      "SELECT candidate_id, canonical_key, first_run, first_start, " + geometry_columns("", "") + " FROM candidates ";
  Statement& by_key = prepared(select_by_key, columns + "WHERE joints = ?1 AND canonical_key = ?2 "
                                                        "ORDER BY candidate_id LIMIT 1");
  by_key.bind(1, n);
  by_key.bind(2, incoming.key);
  if (by_key.step("cannot read the candidates")) return read(by_key);

  std::optional<CanonicalEntry> best;
  double best_distance = 0.0;
  auto consider = [&](Statement& s) {
    while (s.step("cannot read the candidates")) {
      CanonicalEntry other = read(s);
      const double distance = canonical_distance(incoming, other, tolerance);
      if (distance > tolerance) continue;
      if (!best || distance < best_distance || (distance == best_distance && other.id < best->id)) {
        best = std::move(other);
        best_distance = distance;
      }
    }
  };
  const auto options = cell_options(incoming, tolerance);
  size_t combinations = 1;
  for (const auto& o : options) combinations = std::min(combinations * o.size(), kMaxCellCombinations + 1);
  if (combinations > kMaxCellCombinations) {
    // Only with a tolerance near the cell width: compare with every candidate.
    Statement& all = prepared(select_all, columns + "WHERE joints = ?1");
    all.bind(1, n);
    consider(all);
    return best;
  }
  // Every combination of each value's possible cells, odometer order.
  std::vector<size_t> choice(options.size(), 0);
  for (;;) {
    Statement& cell = prepared(select_by_cell, columns + "WHERE joints = ?1 AND grid_cell = ?2");
    cell.bind(1, n);
    cell.bind(2, cell_name(options, choice));
    consider(cell);
    size_t i = 0;
    while (i < choice.size() && ++choice[i] == options[i].size()) choice[i++] = 0;
    if (i == choice.size()) break;
  }
  return best;
}

void ResultsDatabase::Impl::bind_candidate(Statement& s, std::int64_t run_id, const StartRecord& r) {
  const CandidateRecord& c = r.candidate;
  const LoopGeometry& g = c.canonical_geometry;
  const int n = g.joints();
  int p = 1;
  s.bind(p++, n);
  s.bind(p++, c.family);
  s.bind(p++, c.setup);
  s.bind(p++, c.detail);
  s.bind(p++, c.canonical_key);
  for (const JointVector* list : {&g.a, &g.alpha, &g.d}) {
    const double factor = list == &g.alpha ? kDegreesPerRadian : 1.0;
    for (int i = 0; i < kMaxJoints; ++i, ++p) {
      if (i < n) {
        s.bind(p, (*list)[i] * factor);
      } else {
        s.bind_null(p);
      }
    }
  }
  for (double value : {c.family_residual, c.bennett_residual, c.planar_residual, c.spherical_residual,
                       c.trivial_residual, c.rigid_residual}) {
    s.bind(p++, value);
  }
  s.bind(p++, c.full_turn);
  s.bind(p++, c.range_lo_deg);
  s.bind(p++, c.range_hi_deg);
  s.bind(p++, c.local_dimension);
  s.bind(p++, c.free_parameters);
  s.bind(p++, json_array(c.singular_values));
  s.bind(p++, r.E_mean);
  s.bind(p++, r.E_max);
  s.bind(p++, run_id);
  s.bind(p++, static_cast<std::int64_t>(r.index));
  s.bind(p++, grid_cell(canonical_entry(r, run_id)));
}

// The candidate_id for a verified record: an existing candidate of the same
// linkage (its hits counted, and its representative columns taken from this
// record when this start came first), or a new row.
std::int64_t ResultsDatabase::Impl::place_candidate(std::int64_t run_id, const StartRecord& r, double tolerance,
                                                    CommitSummary& summary) {
  static const std::vector<std::string> columns = candidate_columns();
  CanonicalEntry incoming = canonical_entry(r, run_id);
  const std::optional<CanonicalEntry> match = find_candidate(incoming, tolerance);
  if (!match) {
    static const std::string sql = [] {
      std::string names, values;
      for (size_t i = 0; i < columns.size(); ++i) {
        names += (i ? ", " : "") + columns[i];
        values += (i ? ", ?" : "?") + std::to_string(i + 1);
      }
      return "INSERT INTO candidates (" + names + ", hits) VALUES (" + values + ", 1)";
    }();
    Statement& s = prepared(insert_candidate, sql);
    bind_candidate(s, run_id, r);
    s.run("cannot insert a candidate");
    ++summary.new_candidates;
    return sqlite3_last_insert_rowid(db());
  }

  const CanonicalEntry& existing = *match;
  const std::int64_t id = existing.id;
  ++summary.repeat_hits;
  // The earliest (run, start) represents the linkage, whatever the order of
  // the commits that brought them.
  if (std::pair(run_id, incoming.first_start) < std::pair(existing.first_run, existing.first_start)) {
    static const std::string sql = [] {
      std::string assignments;
      for (size_t i = 0; i < columns.size(); ++i) {
        assignments += (i ? ", " : "") + columns[i] + " = ?" + std::to_string(i + 1);
      }
      return "UPDATE candidates SET " + assignments + ", hits = hits + 1 WHERE candidate_id = ?" +
             std::to_string(columns.size() + 1);
    }();
    Statement& s = prepared(replace_candidate, sql);
    bind_candidate(s, run_id, r);
    s.bind(static_cast<int>(columns.size() + 1), id);
    s.run("cannot update a candidate");
  } else {
    Statement& s = prepared(hit_candidate, "UPDATE candidates SET hits = hits + 1 WHERE candidate_id = ?1");
    s.bind(1, id);
    s.run("cannot update a candidate");
  }
  return id;
}

ResultsDatabase::ResultsDatabase(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
ResultsDatabase::ResultsDatabase(ResultsDatabase&&) noexcept = default;
ResultsDatabase& ResultsDatabase::operator=(ResultsDatabase&&) noexcept = default;
ResultsDatabase::~ResultsDatabase() = default;

ResultsDatabase::Impl& ResultsDatabase::impl() const {
  if (!impl_) throw std::logic_error("ResultsDatabase: used after being moved from");
  return *impl_;
}

const std::string& ResultsDatabase::path() const { return impl().path; }
DatabaseMode ResultsDatabase::mode() const { return impl().mode; }
sqlite3* ResultsDatabase::handle() const { return impl().db(); }

ResultsDatabase ResultsDatabase::open(const std::string& path, DatabaseMode mode) {
  auto impl = std::make_unique<Impl>();
  impl->path = path;
  impl->mode = mode;
  std::error_code error;
  const bool exists = std::filesystem::exists(path, error);
  if (exists && std::filesystem::is_directory(path, error)) fail(path, "a directory, not a database file");

  // A file without a WAL holding commits is whole in itself: judge what it
  // is (page 1: SQLite or not, application_id, version, cut short) with
  // SQLite's locks and WAL off, because even a read-only connection to a
  // file whose header says WAL creates NAME-wal and NAME-shm, and a file
  // refused here must be left as it was, companions included. A writer that
  // starts meanwhile changes none of what this reads.
  if (exists && !has_commits_in_wal(path)) {
    Connection peek;
    open_connection(peek, path, SQLITE_OPEN_READONLY | SQLITE_OPEN_URI, immutable_uri(path));
    check_identity(path, peek.db, mode == DatabaseMode::write);
  }

  if (mode == DatabaseMode::read) {
    if (!exists) fail(path, "no such file");
    open_connection(impl->connection, path, SQLITE_OPEN_READONLY);
    exec(path, impl->db(), "PRAGMA query_only = ON", "cannot set query_only");
    check_identity(path, impl->db(), false);
    // A reader checks the whole file too, so that a report never lists what
    // a damaged file happens to yield: about 2 s per million starts.
    check_integrity(path, impl->db());
    return ResultsDatabase(std::move(impl));
  }

  // Judge an existing file on a read-only connection first: nothing that
  // could write to it (journal mode, recovery, a checkpoint on close) happens
  // before it is known to be ours and sound.
  if (exists) {
    Connection probe;
    open_connection(probe, path, SQLITE_OPEN_READONLY);
    if (check_identity(path, probe.db, true) != 0) check_integrity(path, probe.db);
  }
  open_connection(impl->connection, path, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE);
  sqlite3* db = impl->db();
  const std::string journal = query_text(path, db, "PRAGMA journal_mode = WAL");
  if (journal != "wal") {
    fail(path, "cannot use WAL journal mode (got \"" + journal + "\"): put the database on a local disk");
  }
  exec(path, db, "PRAGMA synchronous = NORMAL; PRAGMA foreign_keys = ON", "cannot set pragmas");
  Transaction transaction(path, db);
  // Again under the write lock: another process may have created it meanwhile.
  if (check_identity(path, db, true) == 0) {
    exec(path, db, schema_sql(), "cannot create the schema");
    exec(path, db,
         "PRAGMA application_id = " + std::to_string(kDatabaseApplicationId) +
             "; PRAGMA user_version = " + std::to_string(kDatabaseSchemaVersion),
         "cannot set the schema version");
  }
  transaction.commit();
  impl->checkpoint_on_close = true;
  return ResultsDatabase(std::move(impl));
}

RunInfo ResultsDatabase::open_run(const RunIdentity& identity, bool new_run) {
  Impl& m = impl();
  m.require_write("open_run");
  sqlite3* db = m.db();
  const std::string hash = job_hash(identity.job_text);
  const auto seed = static_cast<std::int64_t>(identity.seed);  // seeds >= 2^63 read as negative, same bits
  Transaction transaction(m.path, db);
  RunInfo info;

  Statement latest;
  latest.prepare(m.path, db,
                 "SELECT run_id, job_path, job_hash, seed, joints, zero_threshold, report_threshold "
                 "FROM runs ORDER BY run_id DESC LIMIT 1");
  if (!new_run && latest.step("cannot read the runs")) {
    const std::int64_t run_id = latest.integer(0);
    const std::string path = latest.text(1), held_hash = latest.text(2);
    const std::int64_t held_seed = latest.integer(3);
    if (held_hash != hash || held_seed != seed) {
      const std::string what = held_hash != hash ? (held_seed != seed ? "job text and seed" : "job text") : "seed";
      fail(m.path, "holds run " + std::to_string(run_id) + " of job " + path + " (job_hash " + held_hash + ", seed " +
                       std::to_string(static_cast<std::uint64_t>(held_seed)) + "), and this job " +
                       identity.job_path + " (job_hash " + hash + ", seed " + std::to_string(identity.seed) +
                       ") differs in its " + what + ": pass --new-run to add a new run to this database");
    }
    if (latest.integer(4) != identity.joints || latest.real(5) != identity.zero_threshold ||
        latest.real(6) != identity.report_threshold) {
      fail(m.path, "run " + std::to_string(run_id) + " has the same job and seed but other joints or thresholds (" +
                       std::to_string(latest.integer(4)) + ", " + format_double(latest.real(5)) + ", " +
                       format_double(latest.real(6)) + "): pass --new-run to add a new run to this database");
    }
    latest.reset();
    Statement update;
    update.prepare(m.path, db,
                   std::string("UPDATE runs SET starts = ?1, job_path = ?2, updated_at = ") + kNow +
                       " WHERE run_id = ?3");
    update.bind(1, static_cast<std::int64_t>(identity.starts));
    update.bind(2, identity.job_path);
    update.bind(3, run_id);
    update.run("cannot update the run");

    Statement committed;
    committed.prepare(m.path, db, "SELECT start_index FROM starts WHERE run_id = ?1 ORDER BY start_index");
    committed.bind(1, run_id);
    while (committed.step("cannot read the committed starts")) {
      const auto index = static_cast<std::uint64_t>(committed.integer(0));
      if (!info.committed.empty() && info.committed.back().last == index) {
        ++info.committed.back().last;
      } else {
        info.committed.push_back({index, index + 1});
      }
    }
    info.run_id = run_id;
    transaction.commit();
    return info;
  }
  latest.reset();

  Statement insert;
  insert.prepare(m.path, db,
                 std::string("INSERT INTO runs (job_path, job_text, job_hash, seed, starts, joints, zero_threshold, "
                             "report_threshold, loopfarm_version, started_at, updated_at, status, starts_done) "
                             "VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ") +
                     kNow + ", " + kNow + ", 'stopped', 0)");
  insert.bind(1, identity.job_path);
  insert.bind(2, identity.job_text);
  insert.bind(3, hash);
  insert.bind(4, seed);
  insert.bind(5, static_cast<std::int64_t>(identity.starts));
  insert.bind(6, identity.joints);
  insert.bind(7, identity.zero_threshold);
  insert.bind(8, identity.report_threshold);
  insert.bind(9, LOOPFARM_VERSION);
  insert.run("cannot insert the run");
  info.run_id = sqlite3_last_insert_rowid(db);
  info.created = true;
  transaction.commit();
  return info;
}

std::int64_t ResultsDatabase::begin_session(std::int64_t run_id, int ranks) {
  Impl& m = impl();
  m.require_write("begin_session");
  if (m.session_id != 0) fail(m.path, "session " + std::to_string(m.session_id) + " is still open");
  sqlite3* db = m.db();
  Transaction transaction(m.path, db);
  Statement run;
  run.prepare(m.path, db,
              std::string("UPDATE runs SET ranks = ?1, status = 'running', ended_at = NULL, updated_at = ") + kNow +
                  " WHERE run_id = ?2");
  run.bind(1, ranks);
  run.bind(2, run_id);
  run.run("cannot update the run");
  if (sqlite3_changes(db) == 0) fail(m.path, "no run " + std::to_string(run_id));
  Statement session;
  session.prepare(m.path, db,
                  std::string("INSERT INTO sessions (run_id, ranks, loopfarm_version, started_at, status, "
                              "starts_done) VALUES (?1, ?2, ?3, ") +
                      kNow + ", 'running', 0)");
  session.bind(1, run_id);
  session.bind(2, ranks);
  session.bind(3, LOOPFARM_VERSION);
  session.run("cannot insert the session");
  const std::int64_t id = sqlite3_last_insert_rowid(db);
  transaction.commit();
  m.session_id = id;
  m.session_run = run_id;
  return id;
}

void ResultsDatabase::end_session(RunStatus status) {
  Impl& m = impl();
  m.require_write("end_session");
  if (status == RunStatus::running) throw std::invalid_argument("end_session: a session cannot end 'running'");
  if (m.session_id == 0) fail(m.path, "end_session: no session is open");
  sqlite3* db = m.db();
  Transaction transaction(m.path, db);
  Statement session;
  session.prepare(m.path, db,
                  std::string("UPDATE sessions SET status = ?1, ended_at = ") + kNow + " WHERE session_id = ?2");
  session.bind(1, to_string(status));
  session.bind(2, m.session_id);
  session.run("cannot update the session");
  Statement run;
  run.prepare(m.path, db,
              std::string("UPDATE runs SET status = ?1, updated_at = ") + kNow +
                  ", ended_at = CASE WHEN ?1 = 'complete' THEN " + kNow + " END WHERE run_id = ?2");
  run.bind(1, to_string(status));
  run.bind(2, m.session_run);
  run.run("cannot update the run");
  transaction.commit();
  m.session_id = 0;
  m.session_run = 0;
}

CommitSummary ResultsDatabase::commit(std::int64_t run_id, const std::vector<StartRecord>& records,
                                      double dedup_tolerance) {
  Impl& m = impl();
  m.require_write("commit");
  // The grid lookup looks one cell either way (find_candidate).
  if (!(dedup_tolerance >= 0.0 && dedup_tolerance < kGridCell)) {
    throw std::invalid_argument("commit: dedup_tolerance must be in [0, 1e-3)");
  }
  CommitSummary summary;
  if (records.empty()) return summary;
  sqlite3* db = m.db();

  // In index order, so that candidates are numbered and represented the same
  // however the records of one commit arrived.
  std::vector<const StartRecord*> order;
  for (const StartRecord& r : records) order.push_back(&r);
  std::sort(order.begin(), order.end(), [](const StartRecord* x, const StartRecord* y) { return x->index < y->index; });
  for (size_t i = 0; i < order.size(); ++i) {
    const std::uint64_t index = order[i]->index;
    if (i > 0 && order[i - 1]->index == index) {
      fail(m.path, "start " + std::to_string(index) + " appears twice in one commit to run " + std::to_string(run_id));
    }
    if (index > static_cast<std::uint64_t>(std::numeric_limits<std::int64_t>::max())) {
      fail(m.path, "start index " + std::to_string(index) + " does not fit an SQLite integer");
    }
  }

  Transaction transaction(m.path, db);
  Statement run;
  run.prepare(m.path, db, "SELECT joints, report_threshold FROM runs WHERE run_id = ?1");
  run.bind(1, run_id);
  if (!run.step("cannot read the run")) fail(m.path, "commit: no run " + std::to_string(run_id));
  const int joints = static_cast<int>(run.integer(0));
  const double report_threshold = run.real(1);
  run.reset();

  static const std::string insert_sql = [] {
    std::string values;
    for (int i = 1; i <= 12 + 3 * kMaxJoints; ++i) values += (i > 1 ? ", ?" : "?") + std::to_string(i);
    return "INSERT INTO starts (run_id, start_index, session_id, status, E_mean, E_max, objective, evaluations, "
           "seconds, zero, verified, candidate_id, " +
           geometry_columns("", "") + ") VALUES (" + values + ")";
  }();
  const std::int64_t session = m.session_run == run_id ? m.session_id : 0;
  for (const StartRecord* record : order) {
    const StartRecord& r = *record;
    const LoopGeometry& g = r.final_geometry;
    check_geometry(m.path, g, "the final geometry", r.index);
    if (g.joints() != 0 && g.joints() != joints) {
      fail(m.path, "start " + std::to_string(r.index) + " has " + std::to_string(g.joints()) + " joints, run " +
                       std::to_string(run_id) + " " + std::to_string(joints));
    }
    std::int64_t candidate_id = 0;
    if (r.verified) {
      check_geometry(m.path, r.candidate.canonical_geometry, "the canonical geometry", r.index);
      if (r.candidate.canonical_geometry.joints() != joints) {
        fail(m.path, "the canonical geometry of start " + std::to_string(r.index) + " has " +
                         std::to_string(r.candidate.canonical_geometry.joints()) + " joints, run " +
                         std::to_string(run_id) + " " + std::to_string(joints));
      }
      candidate_id = m.place_candidate(run_id, r, dedup_tolerance, summary);
    }

    Statement& s = m.prepared(m.insert_start, insert_sql);
    int p = 1;
    s.bind(p++, run_id);
    s.bind(p++, static_cast<std::int64_t>(r.index));
    if (session != 0) {
      s.bind(p++, session);
    } else {
      s.bind_null(p++);
    }
    s.bind(p++, r.status);
    s.bind(p++, r.E_mean);
    s.bind(p++, r.E_max);
    s.bind(p++, r.objective);
    s.bind(p++, r.evaluations);
    s.bind(p++, r.seconds);
    s.bind(p++, r.zero);
    s.bind(p++, r.verified);
    if (candidate_id != 0) {
      s.bind(p++, candidate_id);
    } else {
      s.bind_null(p++);
    }
    // The geometry of the minima worth looking at; NaN compares false.
    const bool keep_geometry = r.E_mean <= report_threshold;
    const int n = g.joints();
    for (const JointVector* list : {&g.a, &g.alpha, &g.d}) {
      const double factor = list == &g.alpha ? kDegreesPerRadian : 1.0;
      for (int i = 0; i < kMaxJoints; ++i, ++p) {
        if (keep_geometry && i < n) {
          s.bind(p, (*list)[i] * factor);
        } else {
          s.bind_null(p);
        }
      }
    }
    std::string message;
    const int rc = s.step_code(message);
    if (rc == SQLITE_CONSTRAINT_PRIMARYKEY) {
      fail(m.path, "start " + std::to_string(r.index) + " of run " + std::to_string(run_id) +
                       " is already committed (nothing of this commit was written)");
    }
    if (rc != SQLITE_DONE) fail(m.path, "cannot insert start " + std::to_string(r.index) + ": " + message);
    ++summary.starts;
    if (r.zero) ++summary.zeros;
  }

  Statement progress;
  progress.prepare(m.path, db,
                   std::string("UPDATE runs SET starts_done = starts_done + ?1, updated_at = ") + kNow +
                       " WHERE run_id = ?2");
  progress.bind(1, summary.starts);
  progress.bind(2, run_id);
  progress.run("cannot update the run");
  if (session != 0) {
    Statement done;
    done.prepare(m.path, db, "UPDATE sessions SET starts_done = starts_done + ?1 WHERE session_id = ?2");
    done.bind(1, summary.starts);
    done.bind(2, session);
    done.run("cannot update the session");
  }
  transaction.commit();
  return summary;
}

}  // namespace loopfarm
