// The results database: schema and pragmas, runs and resume, sessions,
// commits (atomic, no duplicate starts), de-duplication of candidates
// independent of commit order, refusal of foreign or damaged files without
// touching them, and reading while a writer is busy. Records are built by
// hand; no search runs.
#include "loopfarm/farm/results_database.hpp"

#include <sqlite3.h>
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include <gtest/gtest.h>

namespace loopfarm {
namespace {

namespace fs = std::filesystem;

constexpr double kPi = 3.14159265358979323846;

// A fresh directory per test, removed afterwards.
class ResultsDatabaseTest : public ::testing::Test {
 protected:
  void SetUp() override {
    static int counter = 0;
    dir_ = fs::temp_directory_path() /
           ("loopfarm_results_database_test_" + std::to_string(getpid()) + "_" + std::to_string(counter++));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::string file(const std::string& name) const { return (dir_ / name).string(); }

  fs::path dir_;
};

// --- plain SQLite access, independent of the class under test ---------------

struct RawConnection {
  sqlite3* db = nullptr;
  explicit RawConnection(const std::string& path, int flags = SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE) {
    EXPECT_EQ(sqlite3_open_v2(path.c_str(), &db, flags, nullptr), SQLITE_OK) << path;
  }
  ~RawConnection() { sqlite3_close_v2(db); }
  RawConnection(const RawConnection&) = delete;
  RawConnection& operator=(const RawConnection&) = delete;
};

void exec(sqlite3* db, const std::string& sql) {
  char* message = nullptr;
  const int rc = sqlite3_exec(db, sql.c_str(), nullptr, nullptr, &message);
  EXPECT_EQ(rc, SQLITE_OK) << sql << ": " << (message ? message : "");
  sqlite3_free(message);
}

// Every row of a query, each value as text: NULL as "NULL", reals with %.17g
// (so that rows compare exactly).
std::vector<std::vector<std::string>> rows(sqlite3* db, const std::string& sql) {
  sqlite3_stmt* s = nullptr;
  std::vector<std::vector<std::string>> out;
  if (sqlite3_prepare_v2(db, sql.c_str(), -1, &s, nullptr) != SQLITE_OK) {
    ADD_FAILURE() << sql << ": " << sqlite3_errmsg(db);
    return out;
  }
  while (sqlite3_step(s) == SQLITE_ROW) {
    std::vector<std::string> row;
    for (int c = 0; c < sqlite3_column_count(s); ++c) {
      switch (sqlite3_column_type(s, c)) {
        case SQLITE_NULL:
          row.push_back("NULL");
          break;
        case SQLITE_INTEGER:
          row.push_back(std::to_string(sqlite3_column_int64(s, c)));
          break;
        case SQLITE_FLOAT: {
          char buffer[40];
          std::snprintf(buffer, sizeof buffer, "%.17g", sqlite3_column_double(s, c));
          row.push_back(buffer);
          break;
        }
        default:
          row.push_back(reinterpret_cast<const char*>(sqlite3_column_text(s, c)));
      }
    }
    out.push_back(row);
  }
  sqlite3_finalize(s);
  return out;
}

std::string value(sqlite3* db, const std::string& sql) {
  const auto r = rows(db, sql);
  return r.empty() || r[0].empty() ? "no row" : r[0][0];
}

std::int64_t count(sqlite3* db, const std::string& table) {
  return std::stoll(value(db, "SELECT COUNT(*) FROM " + table));
}

std::string fmt(double x) {
  char buffer[40];
  std::snprintf(buffer, sizeof buffer, "%.17g", x);
  return buffer;
}

double real(sqlite3* db, const std::string& sql) {
  const std::string text = value(db, sql);
  return text == "NULL" || text == "no row" ? std::nan("") : std::stod(text);
}

// The same through a read-only connection of the test's own to the file of
// `db`, opened for the one query: what any reader of the file sees.
std::vector<std::vector<std::string>> rows(const ResultsDatabase& db, const std::string& sql) {
  RawConnection reader(db.path(), SQLITE_OPEN_READONLY);
  return rows(reader.db, sql);
}

std::string value(const ResultsDatabase& db, const std::string& sql) {
  RawConnection reader(db.path(), SQLITE_OPEN_READONLY);
  return value(reader.db, sql);
}

std::int64_t count(const ResultsDatabase& db, const std::string& table) {
  RawConnection reader(db.path(), SQLITE_OPEN_READONLY);
  return count(reader.db, table);
}

double real(const ResultsDatabase& db, const std::string& sql) {
  RawConnection reader(db.path(), SQLITE_OPEN_READONLY);
  return real(reader.db, sql);
}

std::string file_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

// --- hand-built records -------------------------------------------------------

RunIdentity identity(const std::string& text = "[search]\nstarts = 100\n", std::uint64_t seed = 1) {
  RunIdentity id;
  id.job_path = "jobs/test.toml";
  id.job_text = text;
  id.seed = seed;
  id.starts = 100;
  id.joints = 4;
  id.zero_threshold = 1e-12;
  id.report_threshold = 1e-6;
  return id;
}

LoopGeometry geometry_deg(std::vector<double> a, std::vector<double> alpha_deg, std::vector<double> d) {
  return LoopGeometry::from_degrees(a, alpha_deg, d);
}

StartRecord plain_start(std::uint64_t index, double E_mean) {
  StartRecord r;
  r.index = index;
  r.status = "ftol_reached";
  r.E_mean = E_mean;
  r.E_max = 2.0 * E_mean;
  r.objective = E_mean;
  r.evaluations = 10 + static_cast<int>(index);
  r.seconds = 0.5;
  r.zero = E_mean <= 1e-12;
  r.final_geometry = geometry_deg({1, 2, 3, 2.5}, {20, 70, 40, 110}, {0.1, -0.3, 0.2, 0});
  r.final_angles = JointVector::Zero(4);
  return r;
}

// A verified zero whose canonical geometry is `canonical` (length scale 1 not
// enforced: the database stores what it is given).
StartRecord verified_start(std::uint64_t index, const LoopGeometry& canonical, const std::string& key,
                           double E_mean = 1e-20) {
  StartRecord r = plain_start(index, E_mean);
  r.status = "stopval_reached";
  r.zero = true;
  r.verified = true;
  r.final_geometry = canonical;
  CandidateRecord& c = r.candidate;
  c.family = "bennett";
  c.setup = "asymmetric";
  c.detail = "asymmetric setup";
  c.family_residual = 1e-15 * static_cast<double>(index + 1);  // differs per start: shows which one represents
  c.bennett_residual = c.family_residual;
  c.planar_residual = 0.5;
  c.spherical_residual = 0.75;
  c.trivial_residual = std::numeric_limits<double>::infinity();
  c.rigid_residual = 1e-13;
  c.full_turn = true;
  c.range_lo_deg = 0.0;
  c.range_hi_deg = 360.0;
  c.local_dimension = 3;
  c.free_parameters = 12;
  c.singular_values = {2.0, 0.5, 1e-13};
  c.canonical_key = key;
  c.canonical_geometry = canonical;
  return r;
}

LoopGeometry bennett_canonical() {
  return geometry_deg({0.632456, 1.264911, 0.632456, 1.264911}, {30, 90, 30, 90}, {0, 0, 0, 0});
}

LoopGeometry shifted(LoopGeometry g, double delta) {
  g.a.array() += delta;
  g.alpha.array() += delta;
  g.d.array() += delta;
  return g;
}

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const DatabaseError& e) {
    return e.what();
  }
  return "no DatabaseError";
}

// --- tests --------------------------------------------------------------------

TEST(JobHash, IsFnv1a64InHex) {
  EXPECT_EQ(job_hash(""), "cbf29ce484222325");
  EXPECT_EQ(job_hash("a"), "af63dc4c8601ec8c");
  EXPECT_EQ(job_hash("foobar"), "85944171f73967e8");
}

TEST_F(ResultsDatabaseTest, CreatesTheSchemaWithItsPragmas) {
  const std::string path = file("r.sqlite");
  {
    ResultsDatabase db = ResultsDatabase::open(path, DatabaseMode::write);
    EXPECT_EQ(db.path(), path);
    EXPECT_EQ(db.mode(), DatabaseMode::write);
    const ConnectionPragmas settings = db.connection_settings();
    EXPECT_TRUE(settings.foreign_keys);
    EXPECT_EQ(settings.synchronous, 1);  // NORMAL
    EXPECT_EQ(settings.busy_timeout_ms, kDatabaseBusyTimeoutMs);
    EXPECT_EQ(settings.journal_mode, "wal");
    EXPECT_FALSE(settings.query_only);
    RawConnection raw(path, SQLITE_OPEN_READONLY);
    EXPECT_EQ(value(raw.db, "PRAGMA journal_mode"), "wal");
  }
  RawConnection raw(path, SQLITE_OPEN_READONLY);
  EXPECT_EQ(value(raw.db, "PRAGMA user_version"), std::to_string(kDatabaseSchemaVersion));
  EXPECT_EQ(value(raw.db, "PRAGMA application_id"), std::to_string(kDatabaseApplicationId));
  EXPECT_EQ(value(raw.db, "PRAGMA journal_mode"), "wal");
  const std::string schema = "SELECT type, name FROM sqlite_schema WHERE name NOT LIKE 'sqlite_%' ORDER BY 1, 2";
  const auto objects = rows(raw.db, schema);
  std::vector<std::string> names;
  for (const auto& row : objects) names.push_back(row[0] + " " + row[1]);
  EXPECT_EQ(names, (std::vector<std::string>{"index candidates_by_joints_family", "index sessions_by_run",
                                             "index starts_by_candidate", "index starts_zero_by_energy",
                                             "table candidates", "table merge_inputs", "table runs", "table sessions",
                                             "table starts", "view energy_histogram", "view family_counts",
                                             "view run_summary", "view status_counts", "view zero_minima"}));
  // Reopening an existing database neither fails nor changes the schema.
  { ResultsDatabase again = ResultsDatabase::open(path, DatabaseMode::write); }
  EXPECT_EQ(rows(raw.db, schema), objects);
}

TEST_F(ResultsDatabaseTest, ResumeFindsTheRunAndItsCommittedStarts) {
  const std::string path = file("r.sqlite");
  {
    ResultsDatabase db = ResultsDatabase::open(path, DatabaseMode::write);
    const RunInfo run = db.open_run(identity());
    EXPECT_EQ(run.run_id, 1);
    EXPECT_TRUE(run.created);
    EXPECT_EQ(run.committed_count(), 0u);
    EXPECT_EQ(run.committed_prefix(), 0u);
    EXPECT_FALSE(run.is_committed(0));
    db.commit(run.run_id, {plain_start(0, 1.0), plain_start(2, 1.0), plain_start(1, 1.0)});
    db.commit(run.run_id, {plain_start(7, 1.0), plain_start(5, 1.0)});
  }
  ResultsDatabase db = ResultsDatabase::open(path, DatabaseMode::write);
  RunIdentity more = identity();
  more.starts = 500;
  more.job_path = "elsewhere/test.toml";
  const RunInfo run = db.open_run(more);
  EXPECT_EQ(run.run_id, 1);
  EXPECT_FALSE(run.created);
  ASSERT_EQ(run.committed.size(), 3u);
  EXPECT_EQ(run.committed[0].first, 0u);
  EXPECT_EQ(run.committed[0].last, 3u);
  EXPECT_EQ(run.committed[1].first, 5u);
  EXPECT_EQ(run.committed[1].last, 6u);
  EXPECT_EQ(run.committed[2].first, 7u);
  EXPECT_EQ(run.committed[2].last, 8u);
  EXPECT_EQ(run.committed_count(), 5u);
  EXPECT_EQ(run.committed_prefix(), 3u);
  const std::vector<bool> expected = {true, true, true, false, false, true, false, true, false};
  for (std::uint64_t i = 0; i < expected.size(); ++i) EXPECT_EQ(run.is_committed(i), expected[i]) << i;
  EXPECT_FALSE(run.is_committed(~0ull));
  EXPECT_EQ(rows(db, "SELECT starts, job_path, starts_done FROM runs"),
            (std::vector<std::vector<std::string>>{{"500", "elsewhere/test.toml", "5"}}));
}

TEST_F(ResultsDatabaseTest, AResumeThatWouldDropCommittedStartsIsRefusedAndTheFileUntouched) {
  const std::string path = file("r.sqlite");
  {
    ResultsDatabase db = ResultsDatabase::open(path, DatabaseMode::write);
    db.commit(db.open_run(identity()).run_id, {plain_start(0, 1.0), plain_start(7, 1.0)});
  }
  const std::string before = file_bytes(path);
  RunIdentity fewer = identity();
  fewer.starts = 7;  // start 7 is committed
  {
    ResultsDatabase db = ResultsDatabase::open(path, DatabaseMode::write);
    const std::string text = error_of([&] { db.open_run(fewer); });
    EXPECT_NE(text.find(path), std::string::npos) << text;
    EXPECT_NE(text.find("committed starts up to index 7"), std::string::npos) << text;
    EXPECT_NE(text.find("--starts 8 or more"), std::string::npos) << text;
  }
  EXPECT_EQ(file_bytes(path), before);
  fewer.starts = 8;  // the least that keeps them
  ResultsDatabase db = ResultsDatabase::open(path, DatabaseMode::write);
  EXPECT_EQ(db.open_run(fewer).committed_count(), 2u);
  EXPECT_EQ(rows(db, "SELECT starts, starts_done FROM runs"), (std::vector<std::vector<std::string>>{{"8", "2"}}));
}

TEST_F(ResultsDatabaseTest, AnotherJobIsRefusedAndTheFileUntouched) {
  const std::string path = file("r.sqlite");
  {
    ResultsDatabase db = ResultsDatabase::open(path, DatabaseMode::write);
    db.commit(db.open_run(identity()).run_id, {plain_start(0, 1.0)});
  }
  const std::string before = file_bytes(path);
  ASSERT_FALSE(before.empty());
  {
    ResultsDatabase db = ResultsDatabase::open(path, DatabaseMode::write);
    const std::string text = error_of([&] { db.open_run(identity("[search]\nstarts = 200\n")); });
    EXPECT_NE(text.find(path), std::string::npos) << text;
    EXPECT_NE(text.find("holds run 1 of job jobs/test.toml"), std::string::npos) << text;
    EXPECT_NE(text.find("job text"), std::string::npos) << text;
    EXPECT_NE(text.find("--new-run"), std::string::npos) << text;
    EXPECT_EQ(text.find('\n'), std::string::npos) << text;
    const std::string seed = error_of([&] { db.open_run(identity("[search]\nstarts = 100\n", 2)); });
    EXPECT_NE(seed.find("differs in its seed"), std::string::npos) << seed;
  }
  EXPECT_EQ(file_bytes(path), before);
  // The file alone holds everything: no commit is left in the WAL.
  EXPECT_FALSE(fs::exists(path + "-wal") && fs::file_size(path + "-wal") > 0);
}

TEST_F(ResultsDatabaseTest, NewRunAddsARunAndBecomesTheOneResumed) {
  const std::string path = file("r.sqlite");
  ResultsDatabase db = ResultsDatabase::open(path, DatabaseMode::write);
  EXPECT_EQ(db.open_run(identity()).run_id, 1);
  db.commit(1, {plain_start(0, 1.0)});
  const RunInfo second = db.open_run(identity("other job"), true);
  EXPECT_EQ(second.run_id, 2);
  EXPECT_TRUE(second.created);
  EXPECT_EQ(second.committed_count(), 0u);
  // The same job again with --new-run: a third run, not a resume.
  EXPECT_EQ(db.open_run(identity("other job"), true).run_id, 3);
  const RunInfo resumed = db.open_run(identity("other job"));
  EXPECT_EQ(resumed.run_id, 3);
  EXPECT_FALSE(resumed.created);
  // Only the latest run resumes: the first job is now "another job".
  EXPECT_NE(error_of([&] { db.open_run(identity()); }).find("holds run 3"), std::string::npos);
  EXPECT_EQ(value(db, "SELECT group_concat(job_hash, ' ') FROM runs"),
            job_hash(identity().job_text) + " " + job_hash("other job") + " " + job_hash("other job"));
}

TEST_F(ResultsDatabaseTest, DuplicateStartIndexThrowsAndWritesNothing) {
  const std::string path = file("r.sqlite");
  ResultsDatabase db = ResultsDatabase::open(path, DatabaseMode::write);
  const std::int64_t run = db.open_run(identity()).run_id;
  db.begin_session(run, 2);
  db.commit(run, {plain_start(0, 1.0), verified_start(1, bennett_canonical(), "k1"), plain_start(5, 1.0)});
  const ResultsDatabase& h = db;
  auto snapshot = [&] {
    return std::vector<std::int64_t>{
        count(h, "starts"), count(h, "candidates"), std::stoll(value(h, "SELECT starts_done FROM runs")),
        std::stoll(value(h, "SELECT hits FROM candidates")), std::stoll(value(h, "SELECT starts_done FROM sessions"))};
  };
  const auto before = snapshot();
  EXPECT_EQ(before, (std::vector<std::int64_t>{3, 1, 3, 1, 3}));

  // Starts 2 (a second hit of the candidate) and 3 are written before the
  // duplicate 5 fails the commit: all of it is rolled back.
  const std::string text = error_of([&] {
    db.commit(run, {plain_start(5, 1.0), plain_start(3, 1.0), verified_start(2, bennett_canonical(), "k1")});
  });
  EXPECT_NE(text.find("start 5 of run 1 is already committed"), std::string::npos) << text;
  EXPECT_EQ(snapshot(), before);
  EXPECT_NE(error_of([&] {
              db.commit(run, {plain_start(4, 1.0), plain_start(4, 1.0)});
            }).find("appears twice"),
            std::string::npos);
  EXPECT_EQ(snapshot(), before);
  EXPECT_NE(error_of([&] { db.commit(9, {plain_start(4, 1.0)}); }).find("no run 9"), std::string::npos);
  EXPECT_EQ(snapshot(), before);

  // The connection is still usable and its candidate cache consistent.
  db.commit(run, {verified_start(2, bennett_canonical(), "k1")});
  EXPECT_EQ(count(h, "candidates"), 1);
  EXPECT_EQ(value(h, "SELECT hits FROM candidates"), "2");
}

TEST_F(ResultsDatabaseTest, DeduplicationIsIndependentOfCommitOrder) {
  // One linkage written twice: canonical geometries 1e-7 apart, keys that
  // differ (a quantisation boundary), and a different linkage.
  const LoopGeometry g = bennett_canonical();
  const StartRecord early = verified_start(3, g, "key-a", 1e-22);
  const StartRecord late = verified_start(8, shifted(g, 1e-7), "key-b", 1e-21);
  const StartRecord other = verified_start(5, shifted(g, 1e-3), "key-c");

  auto build = [&](const std::string& name, const std::vector<std::vector<StartRecord>>& commits) {
    const std::string path = file(name);
    ResultsDatabase db = ResultsDatabase::open(path, DatabaseMode::write);
    const std::int64_t run = db.open_run(identity()).run_id;
    for (const auto& records : commits) db.commit(run, records);
    return rows(db, "SELECT * FROM candidates ORDER BY candidate_id");
  };
  const auto forward = build("forward.sqlite", {{early}, {late}, {other}});
  const auto backward = build("backward.sqlite", {{late}, {early}, {other}});
  const auto one_commit = build("one.sqlite", {{other, late, early}});

  ASSERT_EQ(forward.size(), 2u);
  EXPECT_EQ(backward, forward);
  EXPECT_EQ(one_commit, forward);  // within a commit records go in index order

  const std::string path = file("forward.sqlite");
  ResultsDatabase db = ResultsDatabase::open(path, DatabaseMode::read);
  EXPECT_EQ(rows(db,
                 "SELECT candidate_id, canonical_key, first_run, first_start, hits, E_mean, "
                 "family_residual FROM candidates ORDER BY candidate_id"),
            (std::vector<std::vector<std::string>>{{"1", "key-a", "1", "3", "2", fmt(1e-22), fmt(1e-15 * 4.0)},
                                                   {"2", "key-c", "1", "5", "1", fmt(1e-20), fmt(1e-15 * 6.0)}}));
  EXPECT_EQ(rows(db, "SELECT start_index, candidate_id FROM starts ORDER BY start_index"),
            (std::vector<std::vector<std::string>>{{"3", "1"}, {"5", "2"}, {"8", "1"}}));
}

TEST_F(ResultsDatabaseTest, DeduplicationRules) {
  ResultsDatabase db = ResultsDatabase::open(file("r.sqlite"), DatabaseMode::write);
  const std::int64_t run = db.open_run(identity()).run_id;
  // Twists across the wrap at +-180 deg are one linkage.
  LoopGeometry near_pi = bennett_canonical();
  near_pi.alpha[1] = kPi - 1e-8;
  LoopGeometry near_minus_pi = near_pi;
  near_minus_pi.alpha[1] = -kPi + 1e-8;
  // Equal keys are one linkage whatever the numbers (the key is the primary test).
  const LoopGeometry far = shifted(bennett_canonical(), 0.01);
  const CommitSummary summary =
      db.commit(run, {verified_start(0, near_pi, "wrap-1"), verified_start(1, near_minus_pi, "wrap-2"),
                      verified_start(2, bennett_canonical(), "same"), verified_start(3, far, "same"),
                      // Beyond the tolerance and another key: another candidate.
                      verified_start(4, shifted(bennett_canonical(), 2e-5), "near")});
  EXPECT_EQ(summary.starts, 5);
  EXPECT_EQ(summary.zeros, 5);
  EXPECT_EQ(summary.new_candidates, 3);
  EXPECT_EQ(summary.repeat_hits, 2);
  EXPECT_EQ(rows(db, "SELECT first_start, hits FROM candidates ORDER BY candidate_id"),
            (std::vector<std::vector<std::string>>{{"0", "2"}, {"2", "2"}, {"4", "1"}}));
  // A looser tolerance merges what a tight one keeps apart, with the nearest
  // candidate: 3e-5 from the second, 5e-5 from the third.
  db.commit(run, {verified_start(5, shifted(bennett_canonical(), -3e-5), "near-2")}, 1e-4);
  EXPECT_EQ(rows(db, "SELECT first_start, hits FROM candidates ORDER BY candidate_id"),
            (std::vector<std::vector<std::string>>{{"0", "2"}, {"2", "3"}, {"4", "1"}}));
}

TEST_F(ResultsDatabaseTest, DeduplicationAcrossGridCellEdgesAndAmongManyEqualValues) {
  // The lookup goes by grid cell (width 1e-3): two representations of one linkage
  // on either side of a cell edge, in every value at once, are still one;
  // and a thousand candidates that share a1 (as searches ending on a bound
  // give) neither hide a match nor merge with each other. Checked against a
  // brute-force comparison of every pair.
  ResultsDatabase db = ResultsDatabase::open(file("r.sqlite"), DatabaseMode::write);
  const std::int64_t run = db.open_run(identity()).run_id;
  LoopGeometry edge = bennett_canonical();
  edge.a << 0.632, 1.265, 0.632, 1.265;  // lengths on cell edges (multiples of 1e-3)
  const double twist_cell = 2 * kPi / 6283;
  edge.alpha << -kPi + 100 * twist_cell, -kPi + 2000 * twist_cell, -kPi + 100 * twist_cell,
      kPi;  // twist edges; pi wraps
  std::vector<StartRecord> records;
  records.push_back(verified_start(0, shifted(edge, -4e-6), "edge-below"));
  records.push_back(verified_start(1, shifted(edge, 4e-6), "edge-above"));
  // 1000 candidates with the same a1, 1e-4 apart in alpha2: all distinct.
  for (int k = 0; k < 1000; ++k) {
    LoopGeometry g = bennett_canonical();
    g.alpha[1] = 1.0 + 1e-4 * k;
    records.push_back(verified_start(static_cast<std::uint64_t>(10 + k), g, "many-" + std::to_string(k)));
  }
  // And one more representation of the 500th, 3e-6 away: a hit, not a candidate.
  LoopGeometry again = bennett_canonical();
  again.alpha[1] = 1.0 + 1e-4 * 500 + 3e-6;
  records.push_back(verified_start(2000, again, "many-500-again"));
  const CommitSummary summary = db.commit(run, records);
  EXPECT_EQ(summary.new_candidates, 1 + 1000);
  EXPECT_EQ(summary.repeat_hits, 2);
  EXPECT_EQ(rows(db, "SELECT hits FROM candidates WHERE first_start = 0"),
            (std::vector<std::vector<std::string>>{{"2"}}));
  EXPECT_EQ(rows(db, "SELECT hits FROM candidates WHERE first_start = 510"),
            (std::vector<std::vector<std::string>>{{"2"}}));
  EXPECT_THROW(db.commit(run, {plain_start(3000, 1.0)}, 1e-3), std::invalid_argument);
}

TEST_F(ResultsDatabaseTest, ForeignAndDamagedFilesAreRefusedUntouched) {
  const std::string foreign = file("foreign.sqlite");
  {
    RawConnection raw(foreign);
    exec(raw.db, "CREATE TABLE t (x); INSERT INTO t VALUES (1)");
  }
  const std::string garbage = file("garbage.sqlite");
  {
    std::ofstream out(garbage, std::ios::binary);
    for (int i = 0; i < 5000; ++i) out.put(static_cast<char>((i * 7919) % 251));
  }
  const std::string newer = file("newer.sqlite");
  {
    { ResultsDatabase db = ResultsDatabase::open(newer, DatabaseMode::write); }
    RawConnection raw(newer);
    exec(raw.db, "PRAGMA user_version = " + std::to_string(kDatabaseSchemaVersion + 1));
  }
  const std::string damaged = file("damaged.sqlite");
  {
    ResultsDatabase db = ResultsDatabase::open(damaged, DatabaseMode::write);
    const std::int64_t run = db.open_run(identity()).run_id;
    std::vector<StartRecord> records;
    for (std::uint64_t i = 0; i < 300; ++i) records.push_back(plain_start(i, 1e-9));
    db.commit(run, records);
  }
  const std::uintmax_t size = fs::file_size(damaged);
  ASSERT_GE(size, 8u * 4096u);
  // Copies of the sound file, each damaged one way.
  const std::string truncated = file("truncated.sqlite");  // cut short (a full disk, a partial copy)
  fs::copy_file(damaged, truncated);
  fs::resize_file(truncated, size / 2);
  const std::string header = file("header.sqlite");  // the 100-byte header overwritten
  fs::copy_file(damaged, header);
  {
    std::fstream out(header, std::ios::binary | std::ios::in | std::ios::out);
    for (int i = 0; i < 100; ++i) out.put('x');
  }
  // A table dropped (by hand, or a tool that went wrong); a row that breaks
  // a CHECK constraint (written with the constraints off), which only a
  // read-write connection's quick_check reports.
  const std::string no_table = file("no-table.sqlite"), broken_check = file("broken-check.sqlite");
  fs::copy_file(damaged, no_table);
  fs::copy_file(damaged, broken_check);
  {
    RawConnection raw(no_table);
    exec(raw.db, "DROP TABLE sessions");
  }
  {
    RawConnection raw(broken_check);
    exec(raw.db, "PRAGMA ignore_check_constraints = 1; UPDATE starts SET zero = 5 WHERE start_index = 3");
  }
  {
    // Scribble over the middle of the file: the header (page 1) stays intact.
    std::fstream out(damaged, std::ios::binary | std::ios::in | std::ios::out);
    out.seekp(static_cast<std::streamoff>(size / 2));
    for (int i = 0; i < 4096; ++i) out.put(static_cast<char>(0xA5));
  }

  struct Case {
    std::string path;
    std::string why;
  };
  for (const Case& c : {Case{foreign, "not a loopfarm results database (PRAGMA application_id is 0x00000000"},
                        Case{garbage, "not an SQLite database"},
                        Case{newer, "schema version " + std::to_string(kDatabaseSchemaVersion + 1) + " is newer"},
                        Case{damaged, "damaged (PRAGMA quick_check: "}, Case{truncated, "damaged ("},
                        Case{header, "not an SQLite database"},
                        Case{no_table, "damaged: the table sessions of schema version " +
                                           std::to_string(kDatabaseSchemaVersion) + " is missing"},
                        Case{broken_check, "damaged (PRAGMA quick_check: CHECK constraint failed in starts"}}) {
    SCOPED_TRACE(c.path);
    const std::string before = file_bytes(c.path);
    // Both modes: a reader must not list what a damaged file happens to hold.
    for (const DatabaseMode mode : {DatabaseMode::write, DatabaseMode::read}) {
      const std::string text = error_of([&] { ResultsDatabase::open(c.path, mode); });
      EXPECT_NE(text.find(c.path), std::string::npos) << text;
      EXPECT_NE(text.find(c.why), std::string::npos) << text;
      EXPECT_EQ(text.find('\n'), std::string::npos) << text;
      EXPECT_EQ(file_bytes(c.path), before);
      // SQLite may leave an empty WAL companion; nothing is written to it.
      EXPECT_FALSE(fs::exists(c.path + "-wal") && fs::file_size(c.path + "-wal") > 0);
      // A file refused for what its first page says gets no companions at
      // all (only the checks of the whole file need SQLite's WAL).
      if (c.path != damaged && c.path != broken_check && c.path != no_table) {
        EXPECT_FALSE(fs::exists(c.path + "-wal") || fs::exists(c.path + "-shm"));
      }
    }
  }
  EXPECT_NE(error_of([&] { ResultsDatabase::open(file("missing.sqlite"), DatabaseMode::read); }).find("no such file"),
            std::string::npos);
  EXPECT_FALSE(fs::exists(file("missing.sqlite")));
  EXPECT_NE(error_of([&] {
              ResultsDatabase::open(file("no/such/dir/r.sqlite"), DatabaseMode::write);
            }).find("its directory " + file("no/such/dir") + " does not exist"),
            std::string::npos);
  fs::create_directories(file("dir.sqlite"));
  for (const DatabaseMode mode : {DatabaseMode::write, DatabaseMode::read}) {
    const std::string text = error_of([&] { ResultsDatabase::open(file("dir.sqlite"), mode); });
    EXPECT_NE(text.find(file("dir.sqlite") + ": a directory"), std::string::npos) << text;
  }
  // A path with the characters an SQLite URI escapes is opened as itself.
  const std::string odd = file("odd %41?#.sqlite");
  { ResultsDatabase db = ResultsDatabase::open(odd, DatabaseMode::write); }
  EXPECT_TRUE(fs::exists(odd));
  EXPECT_NO_THROW(ResultsDatabase::open(odd, DatabaseMode::read));
  EXPECT_FALSE(fs::exists(file("odd A")));
}

TEST_F(ResultsDatabaseTest, EmptyFileIsInitialised) {
  const std::string path = file("empty.sqlite");
  { std::ofstream touch(path); }
  ASSERT_TRUE(fs::exists(path));
  EXPECT_NE(error_of([&] { ResultsDatabase::open(path, DatabaseMode::read); }).find("empty"), std::string::npos);
  ResultsDatabase db = ResultsDatabase::open(path, DatabaseMode::write);
  EXPECT_EQ(value(db, "PRAGMA user_version"), std::to_string(kDatabaseSchemaVersion));
}

// The writer checkpoints before it closes, so that the file alone holds every
// commit (a copy of just the file is whole) and the checkpoint on close, which
// holds an EXCLUSIVE lock that makes readers without a busy timeout fail,
// finds nothing left to copy; it also survives a reader on an old snapshot.
TEST_F(ResultsDatabaseTest, TheWriterLeavesEverythingInTheFile) {
  const std::string path = file("r.sqlite");
  const std::string copy = file("copy.sqlite");
  {
    ResultsDatabase db = ResultsDatabase::open(path, DatabaseMode::write);
    const std::int64_t run = db.open_run(identity()).run_id;
    std::vector<StartRecord> records;
    for (std::uint64_t i = 0; i < 200; ++i) records.push_back(plain_start(i, 1e-9));
    db.commit(run, records);
    ASSERT_GT(fs::file_size(path + "-wal"), 0u);  // the commits are in the WAL while it is open
    // Another connection stays open: the close cannot checkpoint, ~Impl does.
    RawConnection other(path, SQLITE_OPEN_READONLY);
    EXPECT_EQ(count(other.db, "starts"), 200);
    { ResultsDatabase moved = std::move(db); }
    fs::copy_file(path, copy);
  }
  RawConnection raw(copy, SQLITE_OPEN_READONLY);
  EXPECT_EQ(count(raw.db, "starts"), 200);
  EXPECT_EQ(value(raw.db, "PRAGMA integrity_check"), "ok");
}

TEST_F(ResultsDatabaseTest, ReadModeWorksWhileAWriterHoldsATransaction) {
  const std::string path = file("r.sqlite");
  ResultsDatabase writer = ResultsDatabase::open(path, DatabaseMode::write);
  const std::int64_t run = writer.open_run(identity()).run_id;
  writer.commit(run, {plain_start(0, 1.0), plain_start(1, 1.0)});

  RawConnection busy(path);
  exec(busy.db, "BEGIN IMMEDIATE");
  exec(busy.db,
       "INSERT INTO starts (run_id, start_index, status, evaluations, zero, verified) "
       "VALUES (1, 99, 'failure', 0, 0, 0)");
  {
    ResultsDatabase reader = ResultsDatabase::open(path, DatabaseMode::read);
    EXPECT_EQ(count(reader, "starts"), 2);  // the committed state only
    EXPECT_EQ(value(reader, "SELECT COUNT(*) FROM zero_minima"), "0");
    // A reader never writes.
    EXPECT_NE(error_of([&] { reader.commit(run, {plain_start(2, 1.0)}); }).find("read-only"), std::string::npos);
    EXPECT_NE(error_of([&] { reader.open_run(identity()); }).find("read-only"), std::string::npos);
    EXPECT_TRUE(reader.connection_settings().query_only);
  }
  exec(busy.db, "COMMIT");
  ResultsDatabase reader = ResultsDatabase::open(path, DatabaseMode::read);
  EXPECT_EQ(count(reader, "starts"), 3);
}

TEST_F(ResultsDatabaseTest, GeometryColumnsAreNullBeyondNAndAboveTheReportThreshold) {
  ResultsDatabase db = ResultsDatabase::open(file("r.sqlite"), DatabaseMode::write);
  const std::int64_t run = db.open_run(identity()).run_id;  // report_threshold 1e-6
  StartRecord nan = plain_start(2, std::numeric_limits<double>::quiet_NaN());
  nan.status = "evaluation_failed";
  db.commit(run, {plain_start(0, 1e-7), plain_start(1, 1e-3), nan, verified_start(3, bennett_canonical(), "k")});
  const ResultsDatabase& h = db;
  // Which columns hold a value: the first 4 of each list, for starts 0 and 3 only.
  std::string presence = "SELECT start_index";
  for (const char* name : {"a", "alpha", "d"}) {
    for (int i = 1; i <= 8; ++i) {
      presence +=
          std::string(", ") + name + std::to_string(i) + (std::string(name) == "alpha" ? "_deg" : "") + " IS NOT NULL";
    }
  }
  const std::string four = "1,1,1,1,0,0,0,0";
  auto joined = [](const std::vector<std::string>& row) {
    std::string out;
    for (size_t i = 1; i < row.size(); ++i) out += (i > 1 ? "," : "") + row[i];
    return out;
  };
  const auto present = rows(h, presence + " FROM starts ORDER BY start_index");
  ASSERT_EQ(present.size(), 4u);
  EXPECT_EQ(joined(present[0]), four + "," + four + "," + four);
  EXPECT_EQ(joined(present[1]), "0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0");
  EXPECT_EQ(joined(present[2]), joined(present[1]));
  EXPECT_EQ(joined(present[3]), joined(present[0]));
  // Lengths as given, twists in degrees.
  EXPECT_EQ(real(h, "SELECT a4 FROM starts WHERE start_index = 0"), 2.5);
  EXPECT_EQ(real(h, "SELECT d2 FROM starts WHERE start_index = 0"), -0.3);
  EXPECT_NEAR(real(h, "SELECT alpha2_deg FROM starts WHERE start_index = 0"), 70.0, 1e-12);
  EXPECT_NEAR(real(h, "SELECT alpha4_deg FROM candidates"), 90.0, 1e-12);
  EXPECT_EQ(real(h, "SELECT a2 FROM candidates"), 1.264911);
  EXPECT_EQ(rows(h, "SELECT E_mean, E_max, objective, zero, verified, candidate_id FROM starts WHERE start_index = 2"),
            (std::vector<std::vector<std::string>>{{"NULL", "NULL", "NULL", "0", "0", "NULL"}}));
  EXPECT_EQ(rows(h,
                 "SELECT joints, family, setup, d4, a5, alpha5_deg, d8, trivial_residual, planar_residual, "
                 "full_turn, singular_values, local_dimension, free_parameters FROM candidates"),
            (std::vector<std::vector<std::string>>{{"4", "bennett", "asymmetric", "0", "NULL", "NULL", "NULL", "NULL",
                                                    "0.5", "1", "[2,0.5," + fmt(1e-13) + "]", "3", "12"}}));
}

TEST_F(ResultsDatabaseTest, SessionsTrackInvocations) {
  const std::string path = file("r.sqlite");
  ResultsDatabase db = ResultsDatabase::open(path, DatabaseMode::write);
  const std::int64_t run = db.open_run(identity()).run_id;
  EXPECT_EQ(value(db, "SELECT status FROM runs"), "stopped");
  EXPECT_EQ(db.begin_session(run, 4), 1);
  EXPECT_NE(error_of([&] { db.begin_session(run, 4); }).find("still open"), std::string::npos);
  EXPECT_EQ(rows(db, "SELECT status, ranks, ended_at FROM runs"),
            (std::vector<std::vector<std::string>>{{"running", "4", "NULL"}}));
  db.commit(run, {plain_start(0, 1.0), plain_start(1, 1e-13)});
  db.end_session(RunStatus::stopped);
  EXPECT_NE(error_of([&] { db.end_session(RunStatus::stopped); }).find("no session"), std::string::npos);
  EXPECT_THROW(db.end_session(RunStatus::running), std::invalid_argument);
  EXPECT_EQ(rows(db, "SELECT status, ended_at IS NULL, starts_done FROM runs"),
            (std::vector<std::vector<std::string>>{{"stopped", "1", "2"}}));

  EXPECT_EQ(db.begin_session(run, 2), 2);
  db.commit(run, {plain_start(2, 1.0)});
  db.commit(run, {plain_start(3, 1.0)});
  db.end_session(RunStatus::complete);
  EXPECT_EQ(rows(db,
                 "SELECT session_id, run_id, ranks, status, starts_done, ended_at IS NOT NULL, "
                 "loopfarm_version FROM sessions ORDER BY 1"),
            (std::vector<std::vector<std::string>>{{"1", "1", "4", "stopped", "2", "1", LOOPFARM_VERSION},
                                                   {"2", "1", "2", "complete", "2", "1", LOOPFARM_VERSION}}));
  EXPECT_EQ(rows(db, "SELECT status, ranks, starts_done, ended_at IS NOT NULL, loopfarm_version FROM runs"),
            (std::vector<std::vector<std::string>>{{"complete", "2", "4", "1", LOOPFARM_VERSION}}));
  EXPECT_EQ(rows(db, "SELECT start_index, session_id FROM starts ORDER BY 1"),
            (std::vector<std::vector<std::string>>{{"0", "1"}, {"1", "1"}, {"2", "2"}, {"3", "2"}}));
  // ISO 8601 UTC.
  const std::string started = value(db, "SELECT started_at FROM runs");
  EXPECT_EQ(started.size(), 20u) << started;
  EXPECT_EQ(started[10], 'T');
  EXPECT_EQ(started.back(), 'Z');
}

TEST_F(ResultsDatabaseTest, ViewsAnswerTheCommonQuestions) {
  ResultsDatabase db = ResultsDatabase::open(file("r.sqlite"), DatabaseMode::write);
  const std::int64_t run = db.open_run(identity()).run_id;
  StartRecord unverified = plain_start(4, 3e-14);
  unverified.zero = true;
  db.commit(run, {plain_start(0, 0.5), verified_start(1, bennett_canonical(), "k", 3e-20),
                  verified_start(2, bennett_canonical(), "k", 3e-25), plain_start(3, 0.005), unverified,
                  plain_start(5, 0.0)});
  const ResultsDatabase& h = db;
  EXPECT_EQ(rows(h, "SELECT start_index, verified, family FROM zero_minima"),
            (std::vector<std::vector<std::string>>{
                {"5", "0", "NULL"}, {"2", "1", "bennett"}, {"1", "1", "bennett"}, {"4", "0", "NULL"}}));
  EXPECT_EQ(rows(h, "SELECT * FROM family_counts"), (std::vector<std::vector<std::string>>{{"bennett", "1", "2"}}));
  EXPECT_EQ(rows(h, "SELECT * FROM status_counts"),
            (std::vector<std::vector<std::string>>{{"1", "ftol_reached", "4", "2", "0"},
                                                   {"1", "stopval_reached", "2", "2", "2"}}));
  EXPECT_EQ(rows(h, "SELECT log10_E_mean, starts FROM energy_histogram"),
            (std::vector<std::vector<std::string>>{
                {"NULL", "1"}, {"-25", "1"}, {"-20", "1"}, {"-14", "1"}, {"-3", "1"}, {"-1", "1"}}));
  EXPECT_EQ(rows(h, "SELECT run_id, starts_done, zeros, verified, new_candidates, best_E_mean FROM run_summary"),
            (std::vector<std::vector<std::string>>{{"1", "6", "4", "2", "1", "0"}}));
}

TEST_F(ResultsDatabaseTest, MovesKeepTheConnection) {
  ResultsDatabase a = ResultsDatabase::open(file("r.sqlite"), DatabaseMode::write);
  const std::int64_t run = a.open_run(identity()).run_id;
  a.begin_session(run, 1);  // the session belongs to the connection
  ResultsDatabase b = std::move(a);
  EXPECT_EQ(b.path(), file("r.sqlite"));
  ResultsDatabase c = ResultsDatabase::open(file("s.sqlite"), DatabaseMode::write);
  c = std::move(b);
  EXPECT_EQ(c.path(), file("r.sqlite"));
  EXPECT_EQ(c.mode(), DatabaseMode::write);
  c.commit(run, {plain_start(0, 1.0)});
  c.end_session(RunStatus::complete);
  EXPECT_EQ(rows(c, "SELECT starts_done, session_id FROM runs JOIN starts USING (run_id)"),
            (std::vector<std::vector<std::string>>{{"1", "1"}}));
  EXPECT_THROW(a.path(), std::logic_error);
}

// The typed queries a reader has, each against SQL of the test's own on a
// connection of its own: the two must agree row for row.
TEST_F(ResultsDatabaseTest, TypedQueriesAgreeWithPlainSql) {
  const std::string path = file("r.sqlite");
  ResultsDatabase db = ResultsDatabase::open(path, DatabaseMode::write);
  const std::int64_t first = db.open_run(identity()).run_id;
  db.begin_session(first, 3);
  StartRecord failed = plain_start(6, std::numeric_limits<double>::quiet_NaN());
  failed.status = "evaluation_failed";
  db.commit(first,
            {plain_start(0, 0.5), verified_start(1, bennett_canonical(), "k", 3e-20),
             verified_start(2, bennett_canonical(), "k", 3e-25), plain_start(3, 0.005), plain_start(5, 0.0), failed});
  db.end_session(RunStatus::stopped);
  RunIdentity other = identity("other job", 7);
  other.starts = 5;
  const std::int64_t second = db.open_run(other, true).run_id;
  StartRecord planar = verified_start(0, geometry_deg({1, 2, 1, 2}, {0, 0, 0, 0}, {0, 0, 0, 0}), "p", 2e-30);
  planar.candidate.family = "planar";
  StartRecord odd = verified_start(1, geometry_deg({1, 3, 1, 3}, {10, 20, 30, 40}, {0, 0, 0, 0}), "u", 1e-21);
  odd.candidate.family = "unclassified";
  db.commit(second, {planar, odd, plain_start(2, 2e-4)});

  const std::vector<RunRow> runs = db.runs();
  ASSERT_EQ(runs.size(), 2u);
  EXPECT_EQ(rows(db, "SELECT run_id, job_path, seed, starts, starts_done, status, ranks, joints FROM runs"),
            (std::vector<std::vector<std::string>>{
                {std::to_string(runs[0].run_id), runs[0].job_path, std::to_string(runs[0].seed),
                 std::to_string(runs[0].starts), std::to_string(runs[0].starts_done), runs[0].status,
                 std::to_string(runs[0].ranks), std::to_string(runs[0].joints)},
                {std::to_string(runs[1].run_id), runs[1].job_path, std::to_string(runs[1].seed),
                 std::to_string(runs[1].starts), std::to_string(runs[1].starts_done), runs[1].status, "NULL",
                 std::to_string(runs[1].joints)}}));
  EXPECT_EQ(runs[0].status, "stopped");
  EXPECT_EQ(runs[1].seed, 7u);
  EXPECT_EQ(runs[0].started_at, value(db, "SELECT started_at FROM runs WHERE run_id = 1"));

  for (const std::optional<std::int64_t> run :
       {std::optional<std::int64_t>{}, std::optional<std::int64_t>{first}, std::optional<std::int64_t>{second}}) {
    const std::string where = run ? " WHERE run_id = " + std::to_string(*run) : "";
    const StartCounts c = db.start_counts(run);
    EXPECT_EQ(c.starts, count(db, "starts" + where));
    EXPECT_EQ(c.zeros,
              std::stoll(value(db, "SELECT COUNT(*) FROM starts" + where + (run ? " AND" : " WHERE") + " zero = 1")));
    EXPECT_EQ(c.verified, std::stoll(value(db, "SELECT COUNT(*) FROM starts" + where + (run ? " AND" : " WHERE") +
                                                   " verified = 1")));
    EXPECT_EQ(c.total_seconds, real(db, "SELECT SUM(seconds) FROM starts" + where));
    EXPECT_DOUBLE_EQ(c.mean_seconds, c.total_seconds / static_cast<double>(c.starts));

    std::vector<std::vector<std::string>> statuses;
    for (const StatusCount& s : db.status_counts(run)) statuses.push_back({s.status, std::to_string(s.starts)});
    EXPECT_EQ(statuses, rows(db, "SELECT status, COUNT(*) AS n FROM starts" + where +
                                     " GROUP BY status ORDER BY n "
                                     "DESC, status"));

    const std::string found_first = run ? " WHERE first_run = " + std::to_string(*run) : "";
    std::vector<std::vector<std::string>> families;
    for (const FamilyCount& f : db.family_counts(run)) {
      families.push_back({f.family, std::to_string(f.candidates), std::to_string(f.hits)});
    }
    EXPECT_EQ(families, rows(db, "SELECT family, COUNT(*), SUM(hits) FROM candidates" + found_first +
                                     " GROUP BY family ORDER BY family"));

    // The histogram against the schema's own view (SQLite's log10).
    const EnergyHistogram h = db.energy_histogram(run);
    std::vector<std::vector<std::string>> bins;
    if (h.zeros) bins.push_back({"NULL", std::to_string(h.zeros)});
    for (const auto& [decade, n] : h.decades) bins.push_back({std::to_string(decade), std::to_string(n)});
    EXPECT_EQ(bins, rows(db, "SELECT log10_E_mean, SUM(starts) FROM energy_histogram" + where +
                                 " GROUP BY log10_E_mean ORDER BY log10_E_mean IS NOT NULL, log10_E_mean"));
    EXPECT_EQ(h.missing, std::stoll(value(db, "SELECT COUNT(*) FROM starts" + where + (run ? " AND" : " WHERE") +
                                                  " E_mean IS NULL")));
  }
  EXPECT_EQ(db.energy_histogram(first).missing, 1);
  EXPECT_EQ(db.candidate_count(), count(db, "candidates"));

  // Candidates: unclassified first, then by energy; filters and paging.
  auto ids = [](const std::vector<CandidateRow>& list) {
    std::vector<std::vector<std::string>> out;
    for (const CandidateRow& r : list) out.push_back({std::to_string(r.id)});
    return out;
  };
  const std::string order = " ORDER BY family <> 'unclassified', E_mean, candidate_id";
  EXPECT_EQ(ids(db.candidates({})), rows(db, "SELECT candidate_id FROM candidates" + order));
  EXPECT_EQ(db.candidates({}).front().family, "unclassified");
  CandidateFilter bennett;
  bennett.family = "bennett";
  EXPECT_EQ(ids(db.candidates(bennett)), rows(db, "SELECT candidate_id FROM candidates WHERE family = 'bennett'"));
  CandidateFilter low;
  low.max_energy = 1e-22;
  EXPECT_EQ(ids(db.candidates(low)), rows(db, "SELECT candidate_id FROM candidates WHERE E_mean <= 1e-22" + order));
  CandidateFilter by_run;
  by_run.first_run = second;
  EXPECT_EQ(ids(db.candidates(by_run)),
            rows(db, "SELECT candidate_id FROM candidates WHERE first_run = " + std::to_string(second) + order));
  CandidateFilter page;
  page.limit = 1;
  page.offset = 1;
  EXPECT_EQ(ids(db.candidates(page)), rows(db, "SELECT candidate_id FROM candidates" + order + " LIMIT 1 OFFSET 1"));
  page.offset = 10;
  EXPECT_TRUE(db.candidates(page).empty());

  // One row's every field against its columns.
  const CandidateRow row = db.candidates(bennett).at(0);
  EXPECT_EQ(rows(db,
                 "SELECT family, setup, detail, hits, first_run, first_start, local_dimension, free_parameters, "
                 "full_turn, joints FROM candidates WHERE candidate_id = " +
                     std::to_string(row.id)),
            (std::vector<std::vector<std::string>>{
                {row.family, row.setup, row.detail, std::to_string(row.hits), std::to_string(row.first_run),
                 std::to_string(row.first_start), std::to_string(row.local_dimension),
                 std::to_string(row.free_parameters), row.full_turn ? "1" : "0", std::to_string(row.joints)}}));
  const std::string id = " FROM candidates WHERE candidate_id = " + std::to_string(row.id);
  EXPECT_EQ(row.E_mean, real(db, "SELECT E_mean" + id));
  EXPECT_EQ(row.family_residual, real(db, "SELECT family_residual" + id));
  EXPECT_TRUE(std::isnan(row.trivial_residual));  // +inf is stored as NULL
  ASSERT_EQ(row.a.size(), 4u);
  ASSERT_EQ(row.alpha_deg.size(), 4u);
  ASSERT_EQ(row.d.size(), 4u);
  for (int i = 0; i < 4; ++i) {
    const std::string k = std::to_string(i + 1);
    EXPECT_EQ(row.a[static_cast<size_t>(i)], real(db, "SELECT a" + k + id));
    EXPECT_EQ(row.alpha_deg[static_cast<size_t>(i)], real(db, "SELECT alpha" + k + "_deg" + id));
    EXPECT_EQ(row.d[static_cast<size_t>(i)], real(db, "SELECT d" + k + id));
  }
}

// A selection's count, the id range and one candidate whole, against plain SQL.
TEST_F(ResultsDatabaseTest, OneCandidateWholeAndTheCountOfASelection) {
  const std::string path = file("r.sqlite");
  ResultsDatabase db = ResultsDatabase::open(path, DatabaseMode::write);
  EXPECT_FALSE(db.candidate_id_range().has_value());
  EXPECT_FALSE(db.candidate(1).has_value());
  const std::int64_t first = db.open_run(identity()).run_id;
  StartRecord planar = verified_start(0, geometry_deg({1, 2, 1, 2}, {0, 0, 0, 0}, {0, 0, 0, 0}), "p", 2e-30);
  planar.candidate.family = "planar";
  db.commit(first, {verified_start(1, bennett_canonical(), "k", 3e-20), planar,
                    verified_start(2, shifted(bennett_canonical(), 1e-3), "k2", 5e-21), plain_start(3, 0.5)});
  const std::int64_t second = db.open_run(identity("other job", 7), true).run_id;
  db.commit(second, {verified_start(0, shifted(bennett_canonical(), 2e-3), "k3", 1e-22)});

  const std::optional<CandidateIdRange> ids = db.candidate_id_range();
  ASSERT_TRUE(ids.has_value());
  EXPECT_EQ(std::to_string(ids->first), value(db, "SELECT MIN(candidate_id) FROM candidates"));
  EXPECT_EQ(std::to_string(ids->last), value(db, "SELECT MAX(candidate_id) FROM candidates"));

  // The count ignores limit and offset and applies every condition.
  CandidateFilter filter;
  filter.limit = 1;
  filter.offset = 2;
  EXPECT_EQ(db.candidate_count(filter), count(db, "candidates"));
  filter.family = "bennett";
  EXPECT_EQ(db.candidate_count(filter), 3);
  filter.max_energy = 1e-20;
  EXPECT_EQ(db.candidate_count(filter), 2);
  filter.first_run = second;
  EXPECT_EQ(db.candidate_count(filter), 1);
  filter.family = "spherical";
  EXPECT_EQ(db.candidate_count(filter), 0);

  // One candidate: the row the list reads, and the store's own columns.
  for (std::int64_t id = ids->first; id <= ids->last; ++id) {
    const std::optional<CandidateDetails> c = db.candidate(id);
    ASSERT_TRUE(c.has_value()) << id;
    const std::string where = " FROM candidates WHERE candidate_id = " + std::to_string(id);
    EXPECT_EQ(c->row.id, id);
    EXPECT_EQ(c->row.family, value(db, "SELECT family" + where));
    EXPECT_EQ(c->row.E_mean, real(db, "SELECT E_mean" + where));
    EXPECT_EQ(c->row.first_run, std::stoll(value(db, "SELECT first_run" + where)));
    EXPECT_EQ(c->canonical_key, value(db, "SELECT canonical_key" + where));
    EXPECT_EQ(c->singular_values, value(db, "SELECT singular_values" + where));
    EXPECT_EQ(c->grid_cell, value(db, "SELECT grid_cell" + where));
    ASSERT_EQ(c->row.a.size(), 4u);
    EXPECT_EQ(c->row.alpha_deg[1], real(db, "SELECT alpha2_deg" + where));
    EXPECT_EQ(c->row.d[3], real(db, "SELECT d4" + where));
  }
  EXPECT_FALSE(db.candidate(ids->last + 1).has_value());
  EXPECT_FALSE(db.candidate(0).has_value());
  EXPECT_FALSE(db.candidate(-5).has_value());
}

// --- bond fingerprints ----------------------------------------------------------

// Candidates 1 (E 3e-20), 2 (5e-21), 3 (1e-22) and a planar one, 4 (2e-30),
// found by starts 1, 2, 4 and 0 of run 1.
void write_four_candidates(ResultsDatabase& db) {
  const std::int64_t run = db.open_run(identity()).run_id;
  db.commit(run, {verified_start(1, bennett_canonical(), "k1", 3e-20),
                  verified_start(2, shifted(bennett_canonical(), 1e-3), "k2", 5e-21),
                  verified_start(4, shifted(bennett_canonical(), 2e-3), "k3", 1e-22)});
  StartRecord planar = verified_start(0, geometry_deg({1, 2, 1, 2}, {0, 0, 0, 0}, {0, 0, 0, 0}), "p", 2e-30);
  planar.candidate.family = "planar";
  db.commit(run, {planar});
}

TEST_F(ResultsDatabaseTest, StoredFingerprintsAreReadBackAndGroupedIntoClasses) {
  const std::string path = file("r.sqlite");
  {
    ResultsDatabase db = ResultsDatabase::open(path, DatabaseMode::write);
    write_four_candidates(db);
    EXPECT_EQ(value(db, "SELECT COUNT(*) FROM candidates WHERE bond_fingerprint IS NULL"), "4");
  }
  {
    ResultsDatabase db = ResultsDatabase::open(path, DatabaseMode::update);
    EXPECT_EQ(db.mode(), DatabaseMode::update);
    // Nothing measured yet: one class of candidates not measured.
    std::vector<FingerprintClass> classes = db.fingerprint_classes({});
    ASSERT_EQ(classes.size(), 1u);
    EXPECT_FALSE(classes[0].fingerprint.has_value());
    EXPECT_EQ(classes[0].candidates, 4);
    EXPECT_EQ(classes[0].representative, 4);  // the least E_mean
    CandidateFilter missing;
    missing.without_fingerprint = true;
    EXPECT_EQ(db.candidate_count(missing), 4);

    const FingerprintStoreSummary stored =
        db.store_bond_fingerprints({{1, 1, 1, "4R/4 11 11 11 11 11 11"},
                                    {2, 1, 2, "4R/4 11 11 11 11 11 11"},
                                    {3, 1, 4, ""},
                                    // Not the representative of candidate 4 (start 0): left alone.
                                    {4, 1, 3, "4R/4 22 22 22 22 22 22"},
                                    // No such candidate.
                                    {9, 1, 9, "4R/4 22 22 22 22 22 22"}});
    EXPECT_EQ(stored.stored, 3);
    EXPECT_EQ(stored.skipped, 2);
    EXPECT_FALSE(stored.upgraded);
    EXPECT_EQ(db.candidate_count(missing), 1);
    missing.family = "bennett";
    EXPECT_EQ(db.candidate_count(missing), 0);

    EXPECT_EQ(db.candidate(1)->row.bond_fingerprint, std::optional<std::string>("4R/4 11 11 11 11 11 11"));
    EXPECT_EQ(db.candidate(3)->row.bond_fingerprint, std::optional<std::string>(""));
    EXPECT_FALSE(db.candidate(4)->row.bond_fingerprint.has_value());
    for (const CandidateRow& r : db.candidates({})) {
      EXPECT_EQ(r.bond_fingerprint.has_value(), r.id != 4) << r.id;
    }

    // Classes: the fingerprints, then the measured loops without one, then those not measured.
    classes = db.fingerprint_classes({});
    ASSERT_EQ(classes.size(), 3u);
    EXPECT_EQ(classes[0].fingerprint, std::optional<std::string>("4R/4 11 11 11 11 11 11"));
    EXPECT_EQ(classes[0].candidates, 2);
    EXPECT_EQ(classes[0].hits, 2);
    EXPECT_EQ(classes[0].representative, 2);  // 5e-21 < 3e-20
    EXPECT_EQ(classes[0].family, "bennett");
    EXPECT_EQ(classes[0].local_dimension, 3);
    EXPECT_EQ(classes[0].free_parameters, 12);
    EXPECT_EQ(classes[0].E_mean, 5e-21);
    EXPECT_EQ(classes[1].fingerprint, std::optional<std::string>(""));
    EXPECT_EQ(classes[1].representative, 3);
    EXPECT_FALSE(classes[2].fingerprint.has_value());
    EXPECT_EQ(classes[2].representative, 4);
    // A selection: the classes among its candidates only.
    CandidateFilter bennett;
    bennett.family = "bennett";
    bennett.max_energy = 1e-20;
    classes = db.fingerprint_classes(bennett);
    ASSERT_EQ(classes.size(), 2u);
    EXPECT_EQ(classes[0].candidates, 1);
    EXPECT_EQ(classes[0].representative, 2);
    EXPECT_EQ(classes[1].representative, 3);
    // Nothing to store: nothing written.
    EXPECT_EQ(db.store_bond_fingerprints({}).stored, 0);
  }
  // A start earlier than a candidate's representative replaces it: the
  // fingerprint measured on the old geometry goes with it.
  {
    ResultsDatabase db = ResultsDatabase::open(path, DatabaseMode::write);
    const std::int64_t run = db.open_run(identity()).run_id;
    const CommitSummary summary = db.commit(run, {verified_start(3, shifted(bennett_canonical(), 2e-3 + 1e-7), "k3")});
    EXPECT_EQ(summary.repeat_hits, 1);
    EXPECT_EQ(summary.new_candidates, 0);
    EXPECT_EQ(value(db, "SELECT first_start FROM candidates WHERE candidate_id = 3"), "3");
    EXPECT_EQ(value(db, "SELECT bond_fingerprint FROM candidates WHERE candidate_id = 3"), "NULL");
    // A later start of a candidate (a hit) keeps it.
    db.commit(run, {verified_start(5, shifted(bennett_canonical(), 1e-7), "k1")});
    EXPECT_EQ(value(db, "SELECT hits || ' ' || bond_fingerprint FROM candidates WHERE candidate_id = 1"),
              "2 4R/4 11 11 11 11 11 11");
  }
  // A reader cannot store.
  ResultsDatabase reader = ResultsDatabase::open(path, DatabaseMode::read);
  EXPECT_NE(error_of([&] { reader.store_bond_fingerprints({{1, 1, 1, "x"}}); }).find("read-only"), std::string::npos);
}

TEST_F(ResultsDatabaseTest, UpdateModeRefusesWhatItMustNotWriteUntouched) {
  // A missing file is not created, an empty one not initialised.
  const std::string missing = file("missing.sqlite");
  EXPECT_NE(error_of([&] { ResultsDatabase::open(missing, DatabaseMode::update); }).find("no such file"),
            std::string::npos);
  EXPECT_FALSE(fs::exists(missing));
  const std::string empty = file("empty.sqlite");
  { std::ofstream touch(empty); }
  EXPECT_NE(error_of([&] { ResultsDatabase::open(empty, DatabaseMode::update); }).find("not a loopfarm"),
            std::string::npos);
  EXPECT_EQ(fs::file_size(empty), 0u);

  // A file whose mode has no write bit, whoever opens it (root too).
  const std::string path = file("r.sqlite");
  {
    ResultsDatabase db = ResultsDatabase::open(path, DatabaseMode::write);
    write_four_candidates(db);
  }
  const std::string before = file_bytes(path);
  fs::permissions(path, fs::perms::owner_read | fs::perms::group_read | fs::perms::others_read);
  const std::string text = error_of([&] { ResultsDatabase::open(path, DatabaseMode::update); });
  EXPECT_NE(text.find(path), std::string::npos) << text;
  EXPECT_NE(text.find("read-only file (mode 0444)"), std::string::npos) << text;
  EXPECT_EQ(file_bytes(path), before);
  EXPECT_FALSE(fs::exists(path + "-wal"));
  EXPECT_FALSE(fs::exists(path + "-shm"));
  // Read mode still reads it.
  EXPECT_EQ(ResultsDatabase::open(path, DatabaseMode::read).candidate_count(), 4);
  fs::permissions(path, fs::perms::owner_write, fs::perm_options::add);
  EXPECT_EQ(ResultsDatabase::open(path, DatabaseMode::update).candidate_count(), 4);
}

// Candidates of equal energy come in id order, the same at every read.
TEST_F(ResultsDatabaseTest, EqualEnergiesAreOrderedById) {
  const std::string path = file("r.sqlite");
  ResultsDatabase db = ResultsDatabase::open(path, DatabaseMode::write);
  const std::int64_t run = db.open_run(identity()).run_id;
  std::vector<StartRecord> records;
  for (int i = 0; i < 6; ++i) {
    records.push_back(verified_start(static_cast<std::uint64_t>(i), shifted(bennett_canonical(), 1e-3 * i),
                                     "tie" + std::to_string(i), i % 2 ? 1e-20 : 1e-21));
  }
  db.commit(run, records);
  std::vector<long long> ids;
  for (const CandidateRow& r : db.candidates({})) ids.push_back(r.id);
  const std::vector<std::vector<std::string>> expected =
      rows(db, "SELECT candidate_id FROM candidates ORDER BY E_mean, candidate_id");
  ASSERT_EQ(ids.size(), expected.size());
  for (size_t i = 0; i < ids.size(); ++i) EXPECT_EQ(std::to_string(ids[i]), expected[i][0]);
  // Three at each energy: within each, ascending ids.
  const std::vector<CandidateRow> listed = db.candidates({});
  for (size_t i = 1; i < listed.size(); ++i) {
    if (listed[i - 1].E_mean == listed[i].E_mean) {
      EXPECT_LT(listed[i - 1].id, listed[i].id);
    }
  }
  EXPECT_EQ(listed.front().E_mean, 1e-21);
}

// A snapshot sees one committed state while a writer goes on committing.
TEST_F(ResultsDatabaseTest, ASnapshotSeesOneState) {
  const std::string path = file("r.sqlite");
  ResultsDatabase writer = ResultsDatabase::open(path, DatabaseMode::write);
  const std::int64_t run = writer.open_run(identity()).run_id;
  writer.commit(run, {plain_start(0, 1.0)});
  const ResultsDatabase reader = ResultsDatabase::open(path, DatabaseMode::read);
  {
    const ResultsDatabase::Snapshot snapshot = reader.snapshot();
    EXPECT_EQ(reader.start_counts().starts, 1);
    writer.commit(run, {plain_start(1, 1.0)});
    EXPECT_EQ(reader.start_counts().starts, 1);
  }
  EXPECT_EQ(reader.start_counts().starts, 2);
}

// A reader of a file it may not write (chmod a-w: root included) reads it as
// immutable and creates no companions, not even while it is open: a
// read-only connection would create NAME-wal and NAME-shm and could not
// remove them, and a read-write one is not for a file made read-only.
TEST_F(ResultsDatabaseTest, AReaderOfAReadOnlyFileCreatesNoCompanions) {
  const std::string path = file("r.sqlite");
  {
    ResultsDatabase db = ResultsDatabase::open(path, DatabaseMode::write);
    write_four_candidates(db);
  }
  ASSERT_FALSE(fs::exists(path + "-wal") || fs::exists(path + "-shm"));
  const std::string before = file_bytes(path);
  fs::permissions(path, fs::perms::owner_read | fs::perms::group_read | fs::perms::others_read);
  {
    const ResultsDatabase reader = ResultsDatabase::open(path, DatabaseMode::read);
    EXPECT_EQ(reader.candidate_count(), 4);
    EXPECT_TRUE(reader.connection_settings().query_only);
    EXPECT_FALSE(fs::exists(path + "-wal"));
    EXPECT_FALSE(fs::exists(path + "-shm"));
  }
  EXPECT_FALSE(fs::exists(path + "-wal"));
  EXPECT_FALSE(fs::exists(path + "-shm"));
  EXPECT_EQ(file_bytes(path), before);
  EXPECT_EQ(fs::status(path).permissions(), fs::perms::owner_read | fs::perms::group_read | fs::perms::others_read);
}

// A file made read-only (chmod a-w) is written by neither writer, whoever
// runs it (root included, whom permissions do not stop): the refusal names
// the mode, and the file is left as it was.
TEST_F(ResultsDatabaseTest, NoWriterWritesAReadOnlyFile) {
  const std::string path = file("r.sqlite");
  {
    ResultsDatabase db = ResultsDatabase::open(path, DatabaseMode::write);
    write_four_candidates(db);
  }
  const std::string before = file_bytes(path);
  fs::permissions(path, fs::perms::owner_read | fs::perms::group_read | fs::perms::others_read);
  for (const DatabaseMode mode : {DatabaseMode::write, DatabaseMode::update}) {
    try {
      ResultsDatabase::open(path, mode);
      ADD_FAILURE() << "a read-only file was opened for writing";
    } catch (const std::exception& e) {
      EXPECT_NE(std::string(e.what()).find("a read-only file (mode 0444)"), std::string::npos) << e.what();
    }
  }
  EXPECT_EQ(file_bytes(path), before);
  EXPECT_FALSE(fs::exists(path + "-wal") || fs::exists(path + "-shm"));
}

// A finished database is one file, and reading it keeps it one file.
TEST_F(ResultsDatabaseTest, AClosedDatabaseAndItsReadersLeaveOneFile) {
  const std::string path = file("r.sqlite");
  auto companions = [&] {
    std::vector<std::string> out;
    for (const char* suffix : {"-wal", "-shm", "-journal"}) {
      if (fs::exists(path + suffix)) out.push_back(suffix);
    }
    return out;
  };
  const std::vector<std::string> none;
  {
    ResultsDatabase db = ResultsDatabase::open(path, DatabaseMode::write);
    const std::int64_t run = db.open_run(identity()).run_id;
    db.commit(run, {plain_start(0, 1.0), verified_start(1, bennett_canonical(), "k")});
    EXPECT_EQ(companions(), (std::vector<std::string>{"-wal", "-shm"}));  // WAL while it writes
    // A reader during the run works, and leaves the writer's files alone.
    {
      const ResultsDatabase reader = ResultsDatabase::open(path, DatabaseMode::read);
      EXPECT_EQ(reader.start_counts().starts, 2);
      EXPECT_TRUE(reader.connection_settings().query_only);
    }
    EXPECT_EQ(companions(), (std::vector<std::string>{"-wal", "-shm"}));
  }
  EXPECT_EQ(companions(), none);
  const std::string bytes = file_bytes(path);
  for (int i = 0; i < 2; ++i) {
    {
      const ResultsDatabase reader = ResultsDatabase::open(path, DatabaseMode::read);
      EXPECT_EQ(reader.candidates({}).size(), 1u);
      EXPECT_TRUE(reader.connection_settings().query_only);
      EXPECT_NE(
          error_of([&] { const_cast<ResultsDatabase&>(reader).commit(1, {plain_start(5, 1.0)}); }).find("read-only"),
          std::string::npos);
    }
    EXPECT_EQ(companions(), none);
    EXPECT_EQ(file_bytes(path), bytes);  // read, not written
  }
  // A plain read-only connection, by contrast, leaves both behind; a reader
  // then neither removes them nor fails.
  {
    RawConnection raw(path, SQLITE_OPEN_READONLY);
    EXPECT_EQ(count(raw.db, "starts"), 2);
  }
  const std::vector<std::string> left = companions();
  EXPECT_EQ(left, (std::vector<std::string>{"-wal", "-shm"}));
  {
    const ResultsDatabase reader = ResultsDatabase::open(path, DatabaseMode::read);
    EXPECT_EQ(reader.start_counts().starts, 2);
  }
  EXPECT_EQ(companions(), left);
  EXPECT_EQ(file_bytes(path), bytes);
}

}  // namespace
}  // namespace loopfarm
