// The SQLite results database (results_database.hpp, docs/guide/database.md).
//
// Every write is one BEGIN IMMEDIATE ... COMMIT transaction held by a
// Transaction guard that rolls back on any exception, so that an error leaves
// the file as it was. Statements are prepared once per connection and reset
// after use.
#include "loopfarm/farm/results_database.hpp"

#include <sqlite3.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <optional>

#include "candidate_index.hpp"
#include "loopfarm/core/loop.hpp"
#include "results_database_impl.hpp"
#include "results_schema.hpp"
#include "sqlite_support.hpp"

#ifndef LOOPFARM_VERSION
#error "LOOPFARM_VERSION is defined by the loopfarm library target"
#endif

namespace loopfarm {
namespace {

using namespace store;

constexpr double kDegreesPerRadian = 180.0 / 3.14159265358979323846;
// ISO 8601 UTC, evaluated by SQLite once per statement.
constexpr const char* kNow = "strftime('%Y-%m-%dT%H:%M:%SZ','now')";

std::string json_array(const std::vector<double>& values) {
  std::string out = "[";
  for (size_t i = 0; i < values.size(); ++i) {
    if (i) out += ',';
    out += std::isfinite(values[i]) ? format_double(values[i]) : "null";
  }
  return out + "]";
}

void check_geometry(const std::string& path, const LoopGeometry& g, const char* what, std::uint64_t index) {
  if (g.alpha.size() != g.a.size() || g.d.size() != g.a.size()) {
    fail(path, std::string(what) + " of start " + std::to_string(index) + " has lists of different lengths");
  }
}

}  // namespace

const char* to_string(RunStatus status) {
  switch (status) {
    case RunStatus::running:
      return "running";
    case RunStatus::stopped:
      return "stopped";
    case RunStatus::complete:
      return "complete";
    case RunStatus::failed:
      return "failed";
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

IndexRange slice_range(const std::optional<StartSlice>& slice, std::uint64_t starts) {
  if (!slice) return {0, starts};
  if (slice->count == 0 || slice->index >= slice->count) {
    throw std::invalid_argument("slice_range: slice " + to_string(*slice) + " is not 0 <= I < K");
  }
  // 128 bits: index * starts may exceed 64 (GCC's and Clang's extension).
  __extension__ using Wide = unsigned __int128;
  const auto bound = [&](std::uint64_t i) { return static_cast<std::uint64_t>(Wide{i} * starts / slice->count); };
  return {bound(slice->index), bound(slice->index + 1)};
}

std::string to_string(const StartSlice& slice) {
  return std::to_string(slice.index) + "/" + std::to_string(slice.count);
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

// Brings the in-memory index of candidates up to the table: loads it on first
// use, and again when another connection has committed since (PRAGMA
// data_version) or the table holds an id it has not seen (rows written on
// this connection other than through place_candidate). Twice a commit, not
// per start.
void ResultsDatabase::Impl::refresh_candidate_index() {
  const std::int64_t version = prepared(data_version, "PRAGMA data_version").step("cannot read PRAGMA data_version")
                                   ? data_version.integer(0)
                                   : 0;
  data_version.reset();
  Statement& highest = prepared(highest_candidate, "SELECT MAX(candidate_id) FROM candidates");
  const std::int64_t highest_id = highest.step("cannot read the candidates") ? highest.integer(0) : 0;
  highest.reset();
  if (candidate_index.loaded() && candidate_index.data_version() == version &&
      highest_id <= candidate_index.highest_id()) {
    return;
  }
  candidate_index.clear();
  Statement all;
  all.prepare(path, db(), "SELECT candidate_id, joints, canonical_key, grid_cell FROM candidates");
  while (all.step("cannot read the candidates")) {
    const std::int64_t id = all.integer(0);
    const int joints = static_cast<int>(all.integer(1));
    candidate_index.add(key_hash(joints, all.text(2)), id);
    std::uint64_t cell = 0;
    // A grid_cell that is not a list of 3 n integers is no cell a lookup names.
    if (cell_hash_of_name(joints, all.text(3), cell)) candidate_index.add(cell, id);
  }
  candidate_index.set_loaded(version);
}

// Row `id` of candidates with its grid cell, if there is one.
std::optional<ResultsDatabase::Impl::StoredCandidate> ResultsDatabase::Impl::read_candidate(std::int64_t id) {
  static const std::string sql = "SELECT candidate_id, canonical_key, first_run, first_start, " +
                                 geometry_columns("", "") +
                                 ", joints, grid_cell FROM candidates WHERE candidate_id = ?1";
  Statement& s = prepared(select_by_id, sql);
  s.bind(1, id);
  if (!s.step("cannot read the candidates")) return std::nullopt;
  StoredCandidate out;
  CanonicalEntry& c = out.entry;
  c.id = s.integer(0);
  c.key = s.text(1);
  c.first_run = s.integer(2);
  c.first_start = s.integer(3);
  c.joints = static_cast<int>(s.integer(4 + 3 * kMaxJoints));
  read_canonical_values(s, 4, std::clamp(c.joints, 0, kMaxJoints), c);
  out.grid_cell = s.text(5 + 3 * kMaxJoints);
  s.reset();
  return out;
}

void ResultsDatabase::Impl::index_candidate(std::int64_t id, const CanonicalEntry& c, const CellOptions& own_cell) {
  candidate_index.add(key_hash(c.joints, c.key), id);
  candidate_index.add(cell_hash(c.joints, own_cell, CellChoice{}), id);
}

// The stored candidate of the same linkage as `incoming`: the one with its
// canonical key (the lowest id if several), else the nearest whose values are
// all within `tolerance` (largest difference smallest, then lowest id) among
// those stored in a grid cell `incoming` may share. The in-memory index names
// the candidates that may have the key or lie in those cells; each is read
// back by id and counts only if its key, or its grid_cell, is that one. A new
// linkage (nearly every verified start) costs no SQL at all, and a lookup the
// same whatever the number of candidates.
std::optional<CanonicalEntry> ResultsDatabase::Impl::find_candidate(const CanonicalEntry& incoming, double tolerance,
                                                                    std::int64_t exclude) {
  if (!candidate_index.loaded()) refresh_candidate_index();
  const int n = incoming.joints;
  std::optional<CanonicalEntry> by_key;
  candidate_index.for_each(key_hash(n, incoming.key), [&](std::int64_t id) {
    if (id == exclude || (by_key && by_key->id <= id)) return;
    std::optional<StoredCandidate> stored = read_candidate(id);
    if (stored && stored->entry.joints == n && stored->entry.key == incoming.key) by_key = std::move(stored->entry);
  });
  if (by_key) return by_key;

  std::optional<CanonicalEntry> best;
  double best_distance = 0.0;
  auto consider = [&](CanonicalEntry other) {
    if (other.id == exclude) return;
    const double distance = canonical_distance(incoming, other, tolerance);
    if (distance > tolerance) return;
    if (!best || distance < best_distance || (distance == best_distance && other.id < best->id)) {
      best = std::move(other);
      best_distance = distance;
    }
  };
  const CellOptions options = cell_options(incoming, tolerance);
  if (options.combinations() > kMaxCellCombinations) {
    // Only with a tolerance near the cell width: compare with every candidate.
    static const std::string sql = "SELECT candidate_id, canonical_key, first_run, first_start, " +
                                   geometry_columns("", "") + " FROM candidates WHERE joints = ?1";
    Statement& all = prepared(select_all, sql);
    all.bind(1, n);
    while (all.step("cannot read the candidates")) {
      CanonicalEntry c;
      c.id = all.integer(0);
      c.key = all.text(1);
      c.first_run = all.integer(2);
      c.first_start = all.integer(3);
      c.joints = n;
      read_canonical_values(all, 4, n, c);
      consider(std::move(c));
    }
    return best;
  }
  // Every combination of each value's possible cells.
  CellChoice choice{};
  do {
    std::string name;  // the cell's text, made only if a candidate may be there
    candidate_index.for_each(cell_hash(n, options, choice), [&](std::int64_t id) {
      std::optional<StoredCandidate> stored = read_candidate(id);
      if (!stored || stored->entry.joints != n) return;
      if (name.empty()) name = cell_name(options, choice);
      if (stored->grid_cell == name) consider(std::move(stored->entry));
    });
  } while (next_choice(options, choice));
  return best;
}

void ResultsDatabase::Impl::bind_candidate(Statement& s, std::int64_t run_id, const StartRecord& r,
                                           const std::string& grid_cell) {
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
  s.bind(p++, grid_cell);
  s.bind(p++, c.families);
  // A run measures no bond fingerprint, and one measured on a representative
  // this record replaces was of another geometry.
  s.bind_null(p++);
}

// The candidate_id for a verified record: an existing candidate of the same
// linkage (its hits counted, and its representative columns taken from this
// record when this start came first), or a new row.
std::int64_t ResultsDatabase::Impl::place_candidate(std::int64_t run_id, const StartRecord& r, double tolerance,
                                                    CommitSummary& summary) {
  static const std::vector<std::string> columns = candidate_columns();
  CanonicalEntry incoming = canonical_entry(r, run_id);
  const std::optional<CanonicalEntry> match = find_candidate(incoming, tolerance);
  const CellOptions own_cell = cell_options(incoming, 0.0);
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
    bind_candidate(s, run_id, r, cell_name(own_cell, CellChoice{}));
    s.run("cannot insert a candidate");
    ++summary.new_candidates;
    const std::int64_t id = sqlite3_last_insert_rowid(db());
    index_candidate(id, incoming, own_cell);
    return id;
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
    bind_candidate(s, run_id, r, cell_name(own_cell, CellChoice{}));
    s.bind(static_cast<int>(columns.size() + 1), id);
    s.run("cannot update a candidate");
    index_candidate(id, incoming, own_cell);
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
  if (mode == DatabaseMode::update && !exists) fail(path, "no such file");
  if (exists && !has_commits_in_wal(path)) {
    Connection peek;
    open_connection(peek, path, SQLITE_OPEN_READONLY | SQLITE_OPEN_URI, immutable_uri(path));
    check_identity(path, peek.db, mode == DatabaseMode::write);
  }
  const FileAccess access = file_access(path);
  // A writer that could not write is refused before anything is created:
  // an existing read-only file (a mode without a write bit too, so that
  // `run` as root does not write a file made read-only on purpose), its
  // directory, companions it may not write.
  if (mode != DatabaseMode::read) check_writer_access(path, access, true);

  if (mode == DatabaseMode::read) {
    if (!exists) fail(path, "no such file");
    // A reader of a database that is one file (no connection has it open:
    // the last to close removed NAME-wal and NAME-shm) keeps it one file. A
    // read-only connection to a WAL file creates both and cannot remove them
    // (that takes a write lock), so such a reader opens the file read-write
    // with query_only on: its close, the last, removes what it created, and
    // copies nothing into the file (the WAL is empty). When it may not write
    // the file or its directory, it reads it as immutable, which creates
    // neither (nor could it in a directory it cannot write). With companions
    // there (a run writing, or one that crashed) it reads read-only and
    // leaves them.
    switch (reader_connection(access)) {
      case ReaderConnection::read_write:
        open_connection(impl->connection, path, SQLITE_OPEN_READWRITE);
        break;
      case ReaderConnection::read_only:
        open_connection(impl->connection, path, SQLITE_OPEN_READONLY);
        break;
      case ReaderConnection::immutable:
        open_connection(impl->connection, path, SQLITE_OPEN_READONLY | SQLITE_OPEN_URI, immutable_uri(path));
        break;
    }
    exec(path, impl->db(), "PRAGMA query_only = ON", "cannot set query_only");
    impl->schema_version = check_identity(path, impl->db(), false);
    // A reader checks the whole file too, so that a report never lists what
    // a damaged file happens to yield: about 2 s per million starts.
    check_integrity(path, impl->db());
    return ResultsDatabase(std::move(impl));
  }

  // Judge an existing file on a read-only connection first: nothing that
  // could write to it (journal mode, recovery, a checkpoint on close) happens
  // before it is known to be ours and sound.
  const bool update = mode == DatabaseMode::update;
  if (exists) {
    Connection probe;
    open_connection(probe, path, SQLITE_OPEN_READONLY);
    if (check_identity(path, probe.db, !update) != 0) check_integrity(path, probe.db);
  }
  open_connection(impl->connection, path, update ? SQLITE_OPEN_READWRITE : SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE);
  sqlite3* db = impl->db();
  const std::string journal = query_text(path, db, "PRAGMA journal_mode = WAL");
  if (journal != "wal") {
    fail(path, "cannot use WAL journal mode (got \"" + journal + "\"): put the database on a local disk");
  }
  // A 64 MiB page cache (SQLite's default is 2 MiB): the indexes of candidates
  // take random inserts, which read a page from the file each when the cache
  // cannot hold them.
  exec(path, db, "PRAGMA synchronous = NORMAL; PRAGMA foreign_keys = ON; PRAGMA cache_size = -65536",
       "cannot set pragmas");
  Transaction transaction(path, db);
  // Again under the write lock: another process may have created it meanwhile.
  // An older schema is upgraded by the first write that needs it (open_run),
  // so that a database refused after this (another job) is left as it was.
  impl->schema_version = check_identity(path, db, !update);
  // Again on this connection: a read-only one (the probe's) does not test the
  // CHECK constraints, so a row that breaks one passes there.
  if (impl->schema_version != 0) check_integrity(path, db);
  if (impl->schema_version == 0) {
    exec(path, db, schema_sql(), "cannot create the schema");
    exec(path, db,
         "PRAGMA application_id = " + std::to_string(kDatabaseApplicationId) +
             "; PRAGMA user_version = " + std::to_string(kDatabaseSchemaVersion),
         "cannot set the schema version");
    impl->schema_version = kDatabaseSchemaVersion;
  }
  transaction.commit();
  impl->checkpoint_on_close = true;
  return ResultsDatabase(std::move(impl));
}

void ResultsDatabase::Impl::upgrade_schema() {
  for (int version = schema_version; version < kDatabaseSchemaVersion; ++version) {
    const std::string sql = schema_upgrade_sql(version);
    if (!sql.empty()) exec(path, db(), sql, "cannot upgrade the schema");
  }
  // 5 to 6 and 6 to 7 change rows, not the schema: the keys of candidates
  // with a zero-length link or parallel axes, computed again once.
  if (schema_version < 7) rekey_candidates();
  exec(path, db(), "PRAGMA user_version = " + std::to_string(kDatabaseSchemaVersion), "cannot set the schema version");
}

namespace {

// "slice 1/3 of 300 starts" or "every start".
std::string describe_slice(const std::optional<StartSlice>& slice, std::uint64_t starts) {
  if (!slice) return "every start";
  return "slice " + to_string(*slice) + " of " + std::to_string(starts) + " starts";
}

}  // namespace

RunInfo ResultsDatabase::open_run(const RunIdentity& identity, bool new_run) {
  Impl& m = impl();
  m.require_write("open_run");
  sqlite3* db = m.db();
  const std::string hash = job_hash(identity.job_text);
  const auto seed = static_cast<std::int64_t>(identity.seed);        // seeds >= 2^63 read as negative, same bits
  if (identity.slice) slice_range(identity.slice, identity.starts);  // throws on a slice not 0 <= I < K
  Transaction transaction(m.path, db);
  if (m.schema_version < kDatabaseSchemaVersion) m.upgrade_schema();
  RunInfo info;

  Statement latest;
  latest.prepare(m.path, db,
                 "SELECT run_id, job_path, job_hash, seed, joints, zero_threshold, report_threshold, starts, "
                 "slice_index, slice_count FROM runs ORDER BY run_id DESC LIMIT 1");
  if (!new_run && latest.step("cannot read the runs")) {
    const std::int64_t run_id = latest.integer(0);
    const std::string path = latest.text(1), held_hash = latest.text(2);
    const std::int64_t held_seed = latest.integer(3);
    if (held_hash != hash || held_seed != seed) {
      const std::string what = held_hash != hash ? (held_seed != seed ? "job text and seed" : "job text") : "seed";
      fail(m.path, "holds run " + std::to_string(run_id) + " of job " + path + " (job_hash " + held_hash + ", seed " +
                       std::to_string(static_cast<std::uint64_t>(held_seed)) + "), and this job " + identity.job_path +
                       " (job_hash " + hash + ", seed " + std::to_string(identity.seed) + ") differs in its " + what +
                       ": pass --new-run to add a new run to this database");
    }
    if (latest.integer(4) != identity.joints || latest.real(5) != identity.zero_threshold ||
        latest.real(6) != identity.report_threshold) {
      fail(m.path, "run " + std::to_string(run_id) + " has the same job and seed but other joints or thresholds (" +
                       std::to_string(latest.integer(4)) + ", " + format_double(latest.real(5)) + ", " +
                       format_double(latest.real(6)) + "): pass --new-run to add a new run to this database");
    }
    // A slice is its own run: resuming another slice (or the whole job) into
    // it would mix two ranges of starts under one run.
    std::optional<StartSlice> held_slice;
    if (!latest.is_null(9)) {
      held_slice =
          StartSlice{static_cast<std::uint64_t>(latest.integer(8)), static_cast<std::uint64_t>(latest.integer(9))};
    }
    const auto held_starts = static_cast<std::uint64_t>(latest.integer(7));
    const bool same_slice =
        held_slice.has_value() == identity.slice.has_value() &&
        (!held_slice || (held_slice->index == identity.slice->index && held_slice->count == identity.slice->count));
    if (!same_slice) {
      fail(m.path, "holds run " + std::to_string(run_id) + " of job " + path + ", " +
                       describe_slice(held_slice, held_starts) + ", and this invocation asks for " +
                       describe_slice(identity.slice, identity.starts) +
                       ": give each slice a database of its own (--db), or pass --new-run");
    }
    // The slices of a job tile its starts only when all are taken of one target.
    if (held_slice && held_starts != identity.starts) {
      fail(m.path, "holds run " + std::to_string(run_id) + ", " + describe_slice(held_slice, held_starts) +
                       ", and this invocation asks for " + std::to_string(identity.starts) +
                       " starts: a slice keeps the starts it was begun with (run it with --starts " +
                       std::to_string(held_starts) + ", or pass --new-run)");
    }
    latest.reset();
    // A run's target may grow (more starts of the same job), never drop
    // starts it has committed.
    Statement highest;
    highest.prepare(m.path, db, "SELECT MAX(start_index) FROM starts WHERE run_id = ?1");
    highest.bind(1, run_id);
    if (highest.step("cannot read the committed starts") && !highest.is_null(0) &&
        static_cast<std::uint64_t>(highest.integer(0)) >= identity.starts) {
      const auto needed = static_cast<std::uint64_t>(highest.integer(0)) + 1;
      fail(m.path, "run " + std::to_string(run_id) + " has committed starts up to index " + std::to_string(needed - 1) +
                       ", and this invocation asks for " + std::to_string(identity.starts) + " starts: give --starts " +
                       std::to_string(needed) + " or more, or pass --new-run");
    }
    highest.reset();
    Statement update;
    update.prepare(
        m.path, db,
        std::string("UPDATE runs SET starts = ?1, job_path = ?2, updated_at = ") + kNow + " WHERE run_id = ?3");
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
    m.upgraded_schema();
    return info;
  }
  latest.reset();

  Statement insert;
  insert.prepare(m.path, db,
                 std::string("INSERT INTO runs (job_path, job_text, job_hash, seed, starts, joints, zero_threshold, "
                             "report_threshold, loopfarm_version, slice_index, slice_count, started_at, updated_at, "
                             "status, starts_done) VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10, ?11, ") +
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
  if (identity.slice) {
    insert.bind(10, static_cast<std::int64_t>(identity.slice->index));
    insert.bind(11, static_cast<std::int64_t>(identity.slice->count));
  } else {
    insert.bind_null(10);
    insert.bind_null(11);
  }
  insert.run("cannot insert the run");
  info.run_id = sqlite3_last_insert_rowid(db);
  info.created = true;
  transaction.commit();
  m.upgraded_schema();
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
  m.refresh_candidate_index();

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
    if (rc != SQLITE_DONE) {
      throw DatabaseError(
          "results database " + m.path + ": cannot insert start " + std::to_string(r.index) + ": " + message,
          cause_of(rc));
    }
    ++summary.starts;
    if (r.zero) ++summary.zeros;
  }

  Statement progress;
  progress.prepare(
      m.path, db,
      std::string("UPDATE runs SET starts_done = starts_done + ?1, updated_at = ") + kNow + " WHERE run_id = ?2");
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

FingerprintStoreSummary ResultsDatabase::store_bond_fingerprints(const std::vector<BondFingerprint>& fingerprints) {
  Impl& m = impl();
  m.require_write("store_bond_fingerprints");
  FingerprintStoreSummary summary;
  if (fingerprints.empty()) return summary;
  sqlite3* db = m.db();
  Transaction transaction(m.path, db);
  if (m.schema_version < kDatabaseSchemaVersion) {
    m.upgrade_schema();
    summary.upgraded = true;
  }
  // Only where the measured representative still represents the candidate.
  Statement update;
  update.prepare(m.path, db,
                 "UPDATE candidates SET bond_fingerprint = ?1 "
                 "WHERE candidate_id = ?2 AND first_run = ?3 AND first_start = ?4");
  for (const BondFingerprint& f : fingerprints) {
    update.bind(1, f.fingerprint);
    update.bind(2, f.candidate_id);
    update.bind(3, f.first_run);
    update.bind(4, f.first_start);
    update.run("cannot store a bond fingerprint");
    if (sqlite3_changes(db) > 0) {
      ++summary.stored;
    } else {
      ++summary.skipped;
    }
  }
  transaction.commit();
  if (summary.upgraded) m.upgraded_schema();
  return summary;
}

}  // namespace loopfarm
