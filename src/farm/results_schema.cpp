// The results database's schema and the checks of a file (results_schema.hpp).
#include "results_schema.hpp"

#include <algorithm>
#include <cstdio>
#include <map>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <utility>
#include <vector>

#include "candidate_index.hpp"
#include "loopfarm/core/loop.hpp"
#include "loopfarm/farm/results_database.hpp"
#include "sqlite_support.hpp"

#ifndef LOOPFARM_VERSION
#error "LOOPFARM_VERSION is defined by the loopfarm library target"
#endif

namespace loopfarm::store {
namespace {

std::string hex32(std::int64_t value) {
  char buffer[16];
  std::snprintf(buffer, sizeof buffer, "0x%08x", static_cast<unsigned>(static_cast<std::uint32_t>(value)));
  return buffer;
}

}  // namespace

// a1..a8, alpha1_deg..alpha8_deg, d1..d8, each with `prefix` and `suffix`;
// the three lists separated by `list_separator`.
std::string geometry_columns(const std::string& prefix, const std::string& suffix, const std::string& list_separator) {
  std::string out;
  for (const char* name : {"a", "alpha", "d"}) {
    for (int i = 1; i <= kMaxJoints; ++i) {
      if (!out.empty()) out += i == 1 ? list_separator : ", ";
      out += prefix + name + std::to_string(i) + (std::string(name) == "alpha" ? "_deg" : "") + suffix;
    }
  }
  return out;
}

bool read_canonical_values(const Statement& row, int first, int n, CanonicalEntry& c) {
  bool complete = true;
  for (int list = 0; list < 3; ++list) {
    for (int i = 0; i < n; ++i) {
      const int column = first + list * kMaxJoints + i;
      complete = complete && !row.is_null(column);
      const double v = row.real(column);
      c.values[static_cast<size_t>(list * n + i)] = list == 1 ? twist_from_stored(v) : v;
    }
  }
  return complete;
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
                           "first_start", "grid_cell", "families", "bond_fingerprint"}) {
    out.push_back(name);
  }
  return out;
}

namespace {

// Schema version 1: the runs, their sessions, the starts and candidates, the views.
std::string schema_sql_version_1() {
  const std::string geometry = geometry_columns("", " REAL", ",\n  ");
  const std::string start_geometry = geometry_columns("s.", "", ",\n         ");
  return "CREATE TABLE runs (\n"
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
         "  " +
         geometry +
         ",\n"
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
         "  " +
         geometry +
         ",\n"
         "  PRIMARY KEY (run_id, start_index)\n"
         ") WITHOUT ROWID;\n"
         "CREATE INDEX starts_zero_by_energy ON starts(E_mean) WHERE zero = 1;\n"
         "CREATE INDEX starts_by_candidate ON starts(candidate_id) WHERE candidate_id IS NOT NULL;\n"
         "CREATE VIEW zero_minima AS\n"
         "  SELECT s.run_id, s.start_index, s.E_mean, s.E_max, s.objective, s.status, s.evaluations, s.seconds,\n"
         "         s.verified, s.candidate_id, c.family, c.setup, c.local_dimension, c.family_residual,\n"
         "         c.rigid_residual,\n"
         "         " +
         start_geometry +
         "\n"
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

// Version 1 to 2: slices and merging. A run may be one slice of its job's
// starts (NULL: the whole job); a merged database records each input it was
// made of (merge_inputs) and which input each session, and so each start,
// came from. Only columns and a table are added: every version 1 row stays
// valid as it is (a run of the whole job, sessions run in this database).
const char* const kUpgradeToVersion2 =
    "ALTER TABLE runs ADD COLUMN slice_index INTEGER CHECK (slice_index >= 0);\n"
    "ALTER TABLE runs ADD COLUMN slice_count INTEGER CHECK (slice_count >= 1 AND slice_index < slice_count);\n"
    "CREATE TABLE merge_inputs (\n"
    "  input_id INTEGER PRIMARY KEY,\n"
    "  run_id INTEGER NOT NULL REFERENCES runs(run_id),\n"
    "  path TEXT NOT NULL,\n"
    "  source_run_id INTEGER NOT NULL,\n"
    "  job_path TEXT NOT NULL,\n"
    "  job_hash TEXT NOT NULL,\n"
    "  seed INTEGER NOT NULL,\n"
    "  slice_index INTEGER,\n"
    "  slice_count INTEGER,\n"
    "  starts INTEGER NOT NULL,\n"
    "  starts_done INTEGER NOT NULL,\n"
    "  starts_kept INTEGER NOT NULL,\n"
    "  status TEXT NOT NULL,\n"
    "  report_threshold REAL NOT NULL,\n"
    "  loopfarm_version TEXT NOT NULL,\n"
    "  merged_at TEXT NOT NULL\n"
    ");\n"
    "ALTER TABLE sessions ADD COLUMN input_id INTEGER REFERENCES merge_inputs(input_id);\n"
    "ALTER TABLE sessions ADD COLUMN source_session_id INTEGER;\n";

// Version 2 to 3: de-duplication looks candidates up in rank 0's memory (an
// index of their keys and grid cells, rebuilt from the table when a database
// is opened), so the two SQL indexes that served it are dropped. Each made
// every new candidate, 41 % of the default job's starts, cost a random insert
// into a b-tree of text; without them a single writer stores about twice as
// many starts a second (docs/performance.md). Nothing else changes.
const char* const kUpgradeToVersion3 =
    "DROP INDEX candidates_by_key;\n"
    "DROP INDEX candidates_by_cell;\n";

// Version 3 to 4: every family whose conditions hold is recorded with the
// candidate (`families`, comma-separated, `family` first), since one geometry
// can satisfy several families' conditions. Rows classified before have NULL
// there: not recorded. Nothing else changes.
const char* const kUpgradeToVersion4 = "ALTER TABLE candidates ADD COLUMN families TEXT;\n";

// Version 4 to 5: a candidate's bond fingerprint (the smallest bidegrees of
// the relations between its joint angles, in the labelling that reads least:
// bond_relations.hpp), which `loopfarm bonds --store` measures on the stored
// geometry, so that unnamed loops fall into classes by it. NULL: not
// measured, as in every row written before. Nothing else changes.
const char* const kUpgradeToVersion5 = "ALTER TABLE candidates ADD COLUMN bond_fingerprint TEXT;\n";

// Version 5 to 6: no SQL. The canonical key takes the twist at a zero-length
// link (a_k / L quantised to 0) with either sign, which keys written before
// did not; the upgrade recomputes, in C++, the key, canonical geometry and
// grid cell of every candidate with such a link and merges the rows that
// then name one linkage (ResultsDatabase::Impl::rekey_candidates,
// results_rekey.cpp). The schema itself does not change.
const char* const kUpgradeToVersion6 = "";

// Version 6 to 7: no SQL. The canonical key reads the offsets between
// parallel axes with the common normal centred (canonical.hpp), which keys
// written before did not; the same recomputation as for version 6, over the
// candidates with such a link (rekey_candidates, once for both).
const char* const kUpgradeToVersion7 = "";

}  // namespace

std::string schema_upgrade_sql(int from_version) {
  switch (from_version) {
    case 1:
      return kUpgradeToVersion2;
    case 2:
      return kUpgradeToVersion3;
    case 3:
      return kUpgradeToVersion4;
    case 4:
      return kUpgradeToVersion5;
    case 5:
      return kUpgradeToVersion6;
    case 6:
      return kUpgradeToVersion7;
    default:
      throw std::logic_error("schema_upgrade_sql: no upgrade from version " + std::to_string(from_version));
  }
}

// Version 1 and every upgrade since: a new database has the very schema (the
// same columns in the same order) that an upgraded one has.
std::string schema_sql() {
  std::string sql = schema_sql_version_1();
  for (int version = 1; version < kDatabaseSchemaVersion; ++version) sql += schema_upgrade_sql(version);
  return sql;
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
    fail(path, "schema version " + std::to_string(version) +
                   " is newer than this loopfarm " LOOPFARM_VERSION " knows (" +
                   std::to_string(kDatabaseSchemaVersion) + "): use a newer loopfarm");
  }
  if (version < kOldestDatabaseSchemaVersion) fail(path, "unknown schema version " + std::to_string(version));
  // Its tables, indexes and views, where SQLite can read the schema (damage
  // there is quick_check's to report, with its own words).
  check_schema_objects(path, db, static_cast<int>(version), false);
  return static_cast<int>(version);
}

namespace {

// (type, name) of every table, index and view of a schema, sorted.
using SchemaObjects = std::vector<std::pair<std::string, std::string>>;

// Empty when SQLite cannot read the schema and `strict` is off.
std::optional<SchemaObjects> schema_objects(const std::string& path, sqlite3* db, bool strict) {
  // Read as check_identity reads: damage where SQLite reads the schema is
  // reported as damage ("damaged (...)"), not as a failure.
  SchemaObjects out;
  sqlite3_stmt* list = nullptr;
  int rc = sqlite3_prepare_v2(db,
                              "SELECT type, name FROM sqlite_schema WHERE type IN ('table', 'index', 'view') AND "
                              "name NOT LIKE 'sqlite_%' ORDER BY type, name",
                              -1, &list, nullptr);
  while (rc == SQLITE_OK || rc == SQLITE_ROW) {
    rc = sqlite3_step(list);
    if (rc != SQLITE_ROW) break;
    out.emplace_back(reinterpret_cast<const char*>(sqlite3_column_text(list, 0)),
                     reinterpret_cast<const char*>(sqlite3_column_text(list, 1)));
  }
  const std::string message = sqlite3_errmsg(db);
  sqlite3_finalize(list);
  if (rc != SQLITE_DONE) {
    if (!strict) return std::nullopt;
    fail_read(path, rc, "cannot read the schema", message);
  }
  return out;
}

// The objects of schema version `version`: version 1 and the upgrades to it,
// made in a database in memory (once per version).
const SchemaObjects& expected_objects(int version) {
  static std::mutex mutex;
  static std::map<int, SchemaObjects> made;
  const std::lock_guard<std::mutex> lock(mutex);
  auto at = made.find(version);
  if (at != made.end()) return at->second;
  sqlite3* memory = nullptr;
  if (sqlite3_open(":memory:", &memory) != SQLITE_OK) {
    sqlite3_close(memory);
    throw DatabaseError("cannot open a database in memory", DatabaseError::Cause::failed);
  }
  std::string sql = schema_sql_version_1();
  for (int v = 1; v < version; ++v) sql += schema_upgrade_sql(v);
  char* error = nullptr;
  if (sqlite3_exec(memory, sql.c_str(), nullptr, nullptr, &error) != SQLITE_OK) {
    const std::string message = error ? error : "unknown error";
    sqlite3_free(error);
    sqlite3_close(memory);
    throw std::logic_error("schema version " + std::to_string(version) + " does not build: " + message);
  }
  SchemaObjects objects = *schema_objects(":memory:", memory, true);
  sqlite3_close(memory);
  return made.emplace(version, std::move(objects)).first->second;
}

}  // namespace

void check_schema_objects(const std::string& path, sqlite3* db, int version, bool strict) {
  const std::optional<SchemaObjects> read = schema_objects(path, db, strict);
  if (!read) return;
  const SchemaObjects& held = *read;
  // A missing table first: its indexes went with it.
  for (const bool tables : {true, false}) {
    for (const auto& [type, name] : expected_objects(version)) {
      if ((type == "table") != tables || std::binary_search(held.begin(), held.end(), std::make_pair(type, name))) {
        continue;
      }
      fail(path, "damaged: the " + type + " " + name + " of schema version " + std::to_string(version) + " is missing");
    }
  }
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
  if (shown > 0) {
    for (char& c : problems) {
      if (c == '\n' || c == '\r' || c == '\t') c = ' ';
    }
    if (shown > 3) problems += "; ...";
    fail(path, "damaged (PRAGMA quick_check: " + problems + ")");
  }
  // Sound pages, but every table, index and view of its version there?
  const std::int64_t version = query_integer(path, db, "PRAGMA user_version");
  if (version >= kOldestDatabaseSchemaVersion && version <= kDatabaseSchemaVersion) {
    check_schema_objects(path, db, static_cast<int>(version), true);
  }
}

}  // namespace loopfarm::store
