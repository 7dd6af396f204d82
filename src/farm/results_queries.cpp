// What readers ask of the results database (results_database.hpp, "reading"):
// the report's runs, counts, histogram and candidates, and the counts a
// resumed run starts its progress from. Every query is a prepared statement
// with bound parameters; a failed step says whether the file is damaged.
#include <sqlite3.h>

#include <cmath>
#include <cstdio>
#include <string>

#include "loopfarm/farm/results_database.hpp"
#include "results_database_impl.hpp"
#include "sqlite_support.hpp"

namespace loopfarm {
namespace {

using store::Statement;

// A statement of the reader's: its step fails with the cause of the error
// (a damaged file is refused, anything else a failure).
class Query {
 public:
  Query(const std::string& path, sqlite3* db, const std::string& sql) : path_(path), db_(db) {
    if (sqlite3_prepare_v2(db, sql.c_str(), -1, &statement_, nullptr) != SQLITE_OK) fail("cannot read");
  }
  ~Query() { sqlite3_finalize(statement_); }
  Query(const Query&) = delete;
  Query& operator=(const Query&) = delete;

  void bind(int i, std::int64_t v) { check(sqlite3_bind_int64(statement_, i, v)); }
  void bind(int i, double v) { check(sqlite3_bind_double(statement_, i, v)); }
  void bind(int i, const std::string& v) {
    check(sqlite3_bind_text(statement_, i, v.data(), static_cast<int>(v.size()), SQLITE_TRANSIENT));
  }
  bool step() {
    const int rc = sqlite3_step(statement_);
    if (rc == SQLITE_ROW) return true;
    if (rc == SQLITE_DONE) return false;
    fail("cannot read");
  }
  bool null(int c) const { return sqlite3_column_type(statement_, c) == SQLITE_NULL; }
  double real(int c) const { return null(c) ? std::nan("") : sqlite3_column_double(statement_, c); }
  std::int64_t integer(int c) const { return sqlite3_column_int64(statement_, c); }
  std::string text(int c) const {
    const auto* t = reinterpret_cast<const char*>(sqlite3_column_text(statement_, c));
    return t ? std::string(t, static_cast<size_t>(sqlite3_column_bytes(statement_, c))) : std::string();
  }

 private:
  [[noreturn]] void fail(const char* what) const {
    store::fail_read(path_, sqlite3_extended_errcode(db_), what, sqlite3_errmsg(db_));
  }
  void check(int rc) const {
    if (rc != SQLITE_OK) fail("cannot bind a parameter");
  }

  const std::string& path_;
  sqlite3* db_;
  sqlite3_stmt* statement_ = nullptr;
};

// " WHERE column = ?1" when a run is given, else nothing.
std::string where_run(const char* column, const std::optional<std::int64_t>& run_id) {
  return run_id ? std::string(" WHERE ") + column + " = ?1" : std::string();
}

void bind_run(Query& q, const std::optional<std::int64_t>& run_id) {
  if (run_id) q.bind(1, *run_id);
}

}  // namespace

ConnectionPragmas ResultsDatabase::connection_settings() const {
  const Impl& m = impl();
  ConnectionPragmas s;
  s.journal_mode = store::query_text(m.path, m.db(), "PRAGMA journal_mode");
  s.foreign_keys = store::query_integer(m.path, m.db(), "PRAGMA foreign_keys") != 0;
  s.synchronous = static_cast<int>(store::query_integer(m.path, m.db(), "PRAGMA synchronous"));
  s.busy_timeout_ms = static_cast<int>(store::query_integer(m.path, m.db(), "PRAGMA busy_timeout"));
  s.query_only = store::query_integer(m.path, m.db(), "PRAGMA query_only") != 0;
  return s;
}

std::vector<RunRow> ResultsDatabase::runs() const {
  const Impl& m = impl();
  // A version 1 file (read as it is) has neither slices nor merges.
  const std::string slices =
      m.schema_version >= 2
          ? "slice_index, slice_count, (SELECT COUNT(*) FROM merge_inputs AS i WHERE i.run_id = runs.run_id) "
          : "NULL, NULL, 0 ";
  Query q(m.path, m.db(),
          "SELECT run_id, job_path, seed, starts, starts_done, status, ranks, joints, started_at, updated_at, " +
              slices + ", zero_threshold FROM runs ORDER BY run_id");
  std::vector<RunRow> rows;
  while (q.step()) {
    RunRow r;
    r.run_id = q.integer(0);
    r.job_path = q.text(1);
    r.seed = static_cast<std::uint64_t>(q.integer(2));  // stored as the same 64 bits
    r.starts = q.integer(3);
    r.starts_done = q.integer(4);
    r.status = q.text(5);
    r.ranks = q.integer(6);
    r.joints = static_cast<int>(q.integer(7));
    r.started_at = q.text(8);
    r.updated_at = q.text(9);
    if (!q.null(10)) {
      r.slice = StartSlice{static_cast<std::uint64_t>(q.integer(10)), static_cast<std::uint64_t>(q.integer(11))};
    }
    r.merged_inputs = q.integer(12);
    r.zero_threshold = q.real(13);
    rows.push_back(std::move(r));
  }
  return rows;
}

StartCounts ResultsDatabase::start_counts(std::optional<std::int64_t> run_id) const {
  const Impl& m = impl();
  Query q(m.path, m.db(),
          "SELECT COUNT(*), TOTAL(zero), TOTAL(verified), AVG(seconds), SUM(seconds) FROM starts" +
              where_run("run_id", run_id));
  bind_run(q, run_id);
  StartCounts c;
  if (q.step()) {
    c.starts = q.integer(0);
    c.zeros = q.integer(1);
    c.verified = q.integer(2);
    c.mean_seconds = q.real(3);
    c.total_seconds = q.real(4);
  }
  return c;
}

std::vector<StatusCount> ResultsDatabase::status_counts(std::optional<std::int64_t> run_id) const {
  const Impl& m = impl();
  Query q(m.path, m.db(),
          "SELECT status, COUNT(*) FROM starts" + where_run("run_id", run_id) +
              " GROUP BY status ORDER BY COUNT(*) DESC, status");
  bind_run(q, run_id);
  std::vector<StatusCount> rows;
  while (q.step()) rows.push_back({q.text(0), q.integer(1)});
  return rows;
}

std::vector<FamilyCount> ResultsDatabase::family_counts(std::optional<std::int64_t> first_run) const {
  const Impl& m = impl();
  Query q(m.path, m.db(),
          "SELECT family, COUNT(*), SUM(hits) FROM candidates" + where_run("first_run", first_run) +
              " GROUP BY family ORDER BY family");
  bind_run(q, first_run);
  std::vector<FamilyCount> rows;
  while (q.step()) rows.push_back({q.text(0), q.integer(1), q.integer(2)});
  return rows;
}

// Binned here rather than in SQL: log10 in SQL needs SQLite's optional math
// functions, and floor(log10(E)) of a double is then computed exactly as a
// reader in C++ or Python would.
EnergyHistogram ResultsDatabase::energy_histogram(std::optional<std::int64_t> run_id) const {
  const Impl& m = impl();
  Query q(m.path, m.db(), "SELECT E_mean FROM starts" + where_run("run_id", run_id));
  bind_run(q, run_id);
  EnergyHistogram h;
  while (q.step()) {
    const double e = q.real(0);
    if (std::isnan(e)) {
      ++h.missing;
    } else if (e <= 0) {
      ++h.zeros;
    } else {
      ++h.decades[static_cast<int>(std::floor(std::log10(e)))];
    }
  }
  return h;
}

std::int64_t ResultsDatabase::candidate_count() const {
  const Impl& m = impl();
  Query q(m.path, m.db(), "SELECT COUNT(*) FROM candidates");
  return q.step() ? q.integer(0) : 0;
}

namespace {

// The column of the stored bond fingerprints; NULL (none measured) in a
// database of schema version 4 or older, which has no such column.
std::string fingerprint_column(int schema_version) { return schema_version >= 5 ? "bond_fingerprint" : "NULL"; }

// The columns a CandidateRow is read from, in read_candidate_row's order;
// `families` is NULL in a database of schema version 3 or older (the column
// came with version 4, and a reader does not upgrade), `bond_fingerprint` in
// one of version 4 or older.
std::string candidate_row_columns(int schema_version) {
  std::string sql =
      std::string("candidate_id, family, ") + (schema_version >= 4 ? "families" : "NULL") + ", " +
      fingerprint_column(schema_version) +
      ", setup, detail, E_mean, E_max, hits, first_run, first_start, local_dimension, "
      "free_parameters, rigid_residual, family_residual, bennett_residual, planar_residual, spherical_residual, "
      "trivial_residual, full_turn, range_lo_deg, range_hi_deg, joints";
  for (const char* kind : {"a%d", "alpha%d_deg", "d%d"}) {
    for (int i = 1; i <= kMaxJoints; ++i) {
      char column[16];
      std::snprintf(column, sizeof column, kind, i);
      sql += std::string(", ") + column;
    }
  }
  return sql;
}

// Reads candidate_row_columns() from column `c` on; returns the next column.
int read_candidate_row(const Query& q, int c, CandidateRow& r) {
  r.id = q.integer(c++);
  r.family = q.text(c++);
  if (!q.null(c)) r.families = q.text(c);
  ++c;
  if (!q.null(c)) r.bond_fingerprint = q.text(c);
  ++c;
  r.setup = q.text(c++);
  r.detail = q.text(c++);
  r.E_mean = q.real(c++);
  r.E_max = q.real(c++);
  r.hits = q.integer(c++);
  r.first_run = q.integer(c++);
  r.first_start = q.integer(c++);
  r.local_dimension = static_cast<int>(q.integer(c++));
  r.free_parameters = static_cast<int>(q.integer(c++));
  r.rigid_residual = q.real(c++);
  r.family_residual = q.real(c++);
  r.bennett_residual = q.real(c++);
  r.planar_residual = q.real(c++);
  r.spherical_residual = q.real(c++);
  r.trivial_residual = q.real(c++);
  r.full_turn = q.integer(c++) != 0;
  r.range_lo_deg = q.real(c++);
  r.range_hi_deg = q.real(c++);
  r.joints = static_cast<int>(q.integer(c++));
  for (std::vector<double>* v : {&r.a, &r.alpha_deg, &r.d}) {
    for (int i = 0; i < kMaxJoints; ++i, ++c) {
      if (i < r.joints) v->push_back(q.real(c));
    }
  }
  return c;
}

// " WHERE ..." of a filter's conditions; its parameters are ?1 (family), ?2
// (max_energy) and ?3 (first_run), bound by bind_candidate_filter.
std::string candidate_filter_sql(const CandidateFilter& filter, int schema_version) {
  std::string sql = " WHERE 1";
  if (!filter.family.empty()) sql += " AND family = ?1";
  if (filter.max_energy) sql += " AND E_mean <= ?2";
  if (filter.first_run) sql += " AND first_run = ?3";
  if (filter.without_fingerprint) sql += " AND " + fingerprint_column(schema_version) + " IS NULL";
  return sql;
}

void bind_candidate_filter(Query& q, const CandidateFilter& filter) {
  if (!filter.family.empty()) q.bind(1, filter.family);
  if (filter.max_energy) q.bind(2, *filter.max_energy);
  if (filter.first_run) q.bind(3, *filter.first_run);
}

}  // namespace

std::int64_t ResultsDatabase::candidate_count(const CandidateFilter& filter) const {
  const Impl& m = impl();
  Query q(m.path, m.db(), "SELECT COUNT(*) FROM candidates" + candidate_filter_sql(filter, m.schema_version));
  bind_candidate_filter(q, filter);
  return q.step() ? q.integer(0) : 0;
}

std::optional<CandidateIdRange> ResultsDatabase::candidate_id_range() const {
  const Impl& m = impl();
  Query q(m.path, m.db(), "SELECT MIN(candidate_id), MAX(candidate_id) FROM candidates");
  if (!q.step() || q.null(0)) return std::nullopt;
  return CandidateIdRange{q.integer(0), q.integer(1)};
}

std::vector<CandidateRow> ResultsDatabase::candidates(const CandidateFilter& filter) const {
  const Impl& m = impl();
  // candidate_id last: equal energies come in one order, the same every time.
  Query q(m.path, m.db(),
          "SELECT " + candidate_row_columns(m.schema_version) + " FROM candidates" +
              candidate_filter_sql(filter, m.schema_version) +
              " ORDER BY family <> 'unclassified', E_mean, candidate_id LIMIT ?4 OFFSET ?5");
  bind_candidate_filter(q, filter);
  q.bind(4, filter.limit < 0 ? std::int64_t{-1} : filter.limit);
  q.bind(5, filter.offset < 0 ? std::int64_t{0} : filter.offset);
  std::vector<CandidateRow> rows;
  while (q.step()) {
    CandidateRow r;
    read_candidate_row(q, 0, r);
    rows.push_back(std::move(r));
  }
  return rows;
}

std::optional<CandidateDetails> ResultsDatabase::candidate(std::int64_t candidate_id) const {
  const Impl& m = impl();
  Query q(m.path, m.db(),
          "SELECT " + candidate_row_columns(m.schema_version) +
              ", canonical_key, singular_values, grid_cell FROM candidates WHERE candidate_id = ?1");
  q.bind(1, candidate_id);
  if (!q.step()) return std::nullopt;
  CandidateDetails out;
  int c = read_candidate_row(q, 0, out.row);
  out.canonical_key = q.text(c++);
  out.singular_values = q.text(c++);
  out.grid_cell = q.text(c++);
  return out;
}

std::vector<FingerprintClass> ResultsDatabase::fingerprint_classes(const CandidateFilter& filter) const {
  const Impl& m = impl();
  // Each class's representative is its first candidate in the report's order
  // (by E_mean, then id), as the list of candidates orders them.
  Query q(m.path, m.db(),
          "SELECT fingerprint, n, total_hits, candidate_id, family, local_dimension, free_parameters, E_mean FROM ("
          "SELECT " +
              fingerprint_column(m.schema_version) +
              " AS fingerprint, candidate_id, family, local_dimension, free_parameters, E_mean, "
              "COUNT(*) OVER same AS n, SUM(hits) OVER same AS total_hits, "
              "ROW_NUMBER() OVER (same ORDER BY E_mean, candidate_id) AS place FROM candidates" +
              candidate_filter_sql(filter, m.schema_version) + " WINDOW same AS (PARTITION BY " +
              fingerprint_column(m.schema_version) +
              ")) WHERE place = 1 "
              "ORDER BY fingerprint IS NULL, fingerprint = '', n DESC, total_hits DESC, fingerprint");
  bind_candidate_filter(q, filter);
  std::vector<FingerprintClass> classes;
  while (q.step()) {
    FingerprintClass c;
    if (!q.null(0)) c.fingerprint = q.text(0);
    c.candidates = q.integer(1);
    c.hits = q.integer(2);
    c.representative = q.integer(3);
    c.family = q.text(4);
    c.local_dimension = static_cast<int>(q.integer(5));
    c.free_parameters = static_cast<int>(q.integer(6));
    c.E_mean = q.real(7);
    classes.push_back(std::move(c));
  }
  return classes;
}

ResultsDatabase::Snapshot ResultsDatabase::snapshot() const {
  const Impl& m = impl();
  store::exec(m.path, m.db(), "BEGIN", "cannot begin a read transaction");
  return Snapshot(this);
}

ResultsDatabase::Snapshot::Snapshot(Snapshot&& other) noexcept : db_(other.db_) { other.db_ = nullptr; }

// COMMIT of a read transaction releases the read lock; it cannot fail in a
// way that loses anything, so a destructor may swallow its result.
ResultsDatabase::Snapshot::~Snapshot() {
  if (db_ != nullptr && db_->impl_) sqlite3_exec(db_->impl_->db(), "COMMIT", nullptr, nullptr, nullptr);
}

}  // namespace loopfarm
