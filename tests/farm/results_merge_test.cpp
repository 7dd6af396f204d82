// Slices and merging in the results database: the slice arithmetic, a slice
// as part of a run's identity, the upgrade of a version 1 database (a file
// written before slices existed, tests/farm/fixtures/schema-v1.sqlite) and of
// a version 2 one (before de-duplication moved into memory, schema-v2.sqlite),
// a version 3 one (before the families whose conditions hold were recorded,
// schema-v3.sqlite) and a version 4 one (before bond fingerprints were stored,
// schema-v4.sqlite: its fingerprints measured here and stored), a version 5
// one (before the keys of loops with a zero-length link took its twist with
// either sign, schema-v5-zero-length.sqlite: re-keyed and its duplicates
// merged), and ResultsDatabase::merge: three slices merged equal one run of the same
// starts (candidates de-duplicated across the slices, row for row), overlaps,
// provenance, and every refusal leaving no file behind. Records are built by
// hand; no search runs.
#include <sqlite3.h>
#include <unistd.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <limits>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "loopfarm/farm/candidate_pose.hpp"
#include "loopfarm/farm/results_database.hpp"
#include "loopfarm/search/bond_relations.hpp"
#include "loopfarm/search/canonical.hpp"
#include "loopfarm/search/verify.hpp"
#include "refusal.hpp"

#ifndef LOOPFARM_SOURCE_DIR
#error "LOOPFARM_SOURCE_DIR is defined by tests/CMakeLists.txt"
#endif

namespace loopfarm {
namespace {

namespace fs = std::filesystem;
using Rows = std::vector<std::vector<std::string>>;

class MergeTest : public ::testing::Test {
 protected:
  void SetUp() override {
    static int counter = 0;
    dir_ = fs::temp_directory_path() /
           ("loopfarm_results_merge_test_" + std::to_string(getpid()) + "_" + std::to_string(counter++));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string file(const std::string& name) const { return (dir_ / name).string(); }
  // The database at `path` has exactly the schema of a new one (an upgrade
  // leaves nothing of the version it came from).
  void expect_schema_of_a_new_database(const std::string& path) const;
  // Every file in the test's directory.
  std::vector<std::string> listing() const {
    std::vector<std::string> names;
    for (const auto& entry : fs::directory_iterator(dir_)) names.push_back(entry.path().filename().string());
    std::sort(names.begin(), names.end());
    return names;
  }

  fs::path dir_;
};

// Every row of a query on the file at `path`, values as text (reals %.17g).
// Read-write with query_only, as loopfarm report reads: the close removes the
// -wal and -shm files the connection made, so that the directory's listing
// shows only what the code under test left.
Rows rows(const std::string& path, const std::string& sql) {
  sqlite3* db = nullptr;
  Rows out;
  if (sqlite3_open_v2(path.c_str(), &db, SQLITE_OPEN_READWRITE, nullptr) != SQLITE_OK ||
      sqlite3_exec(db, "PRAGMA query_only = ON", nullptr, nullptr, nullptr) != SQLITE_OK) {
    ADD_FAILURE() << path;
    sqlite3_close_v2(db);
    return out;
  }
  sqlite3_stmt* s = nullptr;
  if (sqlite3_prepare_v2(db, sql.c_str(), -1, &s, nullptr) != SQLITE_OK) {
    ADD_FAILURE() << sql << ": " << sqlite3_errmsg(db);
  } else {
    while (sqlite3_step(s) == SQLITE_ROW) {
      std::vector<std::string> row;
      for (int c = 0; c < sqlite3_column_count(s); ++c) {
        char buffer[40];
        switch (sqlite3_column_type(s, c)) {
          case SQLITE_NULL:
            row.push_back("NULL");
            break;
          case SQLITE_INTEGER:
            row.push_back(std::to_string(sqlite3_column_int64(s, c)));
            break;
          case SQLITE_FLOAT:
            std::snprintf(buffer, sizeof buffer, "%.17g", sqlite3_column_double(s, c));
            row.push_back(buffer);
            break;
          default:
            row.push_back(reinterpret_cast<const char*>(sqlite3_column_text(s, c)));
        }
      }
      out.push_back(row);
    }
  }
  sqlite3_finalize(s);
  sqlite3_close_v2(db);
  return out;
}

std::string value(const std::string& path, const std::string& sql) {
  const Rows r = rows(path, sql);
  return r.empty() || r[0].empty() ? "no row" : r[0][0];
}

void exec(const std::string& path, const std::string& sql) {
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open_v2(path.c_str(), &db, SQLITE_OPEN_READWRITE, nullptr), SQLITE_OK);
  char* message = nullptr;
  EXPECT_EQ(sqlite3_exec(db, sql.c_str(), nullptr, nullptr, &message), SQLITE_OK) << (message ? message : "");
  sqlite3_free(message);
  sqlite3_close_v2(db);
}

std::string file_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

// What one run of the starts writes, by content: the starts but for their
// wall time and session, and the whole candidates table.
Rows starts_content(const std::string& path) {
  return rows(
      path,
      "SELECT start_index, status, E_mean, E_max, objective, evaluations, zero, verified, candidate_id, a1, a4, "
      "alpha2_deg, d3 FROM starts ORDER BY start_index");
}
void MergeTest::expect_schema_of_a_new_database(const std::string& path) const {
  const std::string fresh = file("fresh.sqlite");
  { ResultsDatabase db = ResultsDatabase::open(fresh, DatabaseMode::write); }
  const std::string schema = "SELECT type, name, sql FROM sqlite_schema ORDER BY type, name";
  EXPECT_EQ(rows(path, schema), rows(fresh, schema));
}

// Every column of every candidate; the columns later schema versions added
// at the end (`families`, version 4; `bond_fingerprint`, version 5) only where
// some row holds a value, so that a database written before them compares with
// its upgraded or merged copy, whose rows hold NULL there (checked apart).
Rows candidates_content(const std::string& path) {
  Rows out = rows(path, "SELECT * FROM candidates ORDER BY candidate_id");
  const Rows names = rows(path, "SELECT name FROM pragma_table_info('candidates')");
  size_t columns = names.size();
  for (const std::string added : {"bond_fingerprint", "families"}) {
    if (columns == 0 || names[columns - 1].at(0) != added) break;
    if (value(path, "SELECT COUNT(*) FROM candidates WHERE " + added + " IS NOT NULL") != "0") break;
    --columns;
  }
  for (auto& row : out) row.resize(columns);
  return out;
}

// The stored canonical geometry of a candidate row read with its table's
// column names `names`.
LoopGeometry row_geometry(const Rows& names, const std::vector<std::string>& row) {
  auto column = [&](const std::string& name) {
    const auto at = std::find(names.begin(), names.end(), std::vector<std::string>{name});
    if (at == names.end()) throw std::logic_error("no column " + name);
    return row.at(static_cast<size_t>(at - names.begin()));
  };
  const int n = std::stoi(column("joints"));
  std::vector<double> a, alpha, d;
  for (int k = 1; k <= n; ++k) {
    a.push_back(std::stod(column("a" + std::to_string(k))));
    alpha.push_back(std::stod(column("alpha" + std::to_string(k) + "_deg")));
    d.push_back(std::stod(column("d" + std::to_string(k))));
  }
  return LoopGeometry::from_degrees(a, alpha, d);
}

// The candidates of a database an upgrade to schema version 7 keyed again,
// against `before`, its rows read before (candidates_content): a row whose
// stored geometry has neither parallel axes nor a zero-length link is kept
// as it was; every row's key is the key of its stored geometry, one that
// `before`'s geometries have now; no two rows share a key; the hits add up as
// before. Returns how many rows were merged away.
size_t expect_keyed_again(const std::string& path, const Rows& before) {
  const Rows after = candidates_content(path);
  const Rows names = rows(path, "SELECT name FROM pragma_table_info('candidates')");
  const size_t key_column = 5,
               hits_column = static_cast<size_t>(
                   std::find(names.begin(), names.end(), std::vector<std::string>{"hits"}) - names.begin());
  EXPECT_EQ(names[key_column][0], "canonical_key");
  std::set<std::string> keys_before;
  long long hits_before = 0, hits_after = 0;
  for (const auto& row : before) {
    const LoopGeometry g = row_geometry(names, row);
    keys_before.insert(canonical_form(g).key);
    hits_before += std::stoll(row.at(hits_column));
    if (has_parallel_link(g) || has_zero_length_link(g)) continue;
    const auto same_id = std::find_if(after.begin(), after.end(), [&](const auto& r) { return r[0] == row[0]; });
    if (same_id == after.end()) {
      ADD_FAILURE() << "candidate " << row[0] << " without parallel axes is gone";
    } else {
      EXPECT_EQ(*same_id, row) << "candidate " << row[0];
    }
  }
  std::set<std::string> keys_after;
  for (const auto& row : after) {
    EXPECT_EQ(row.at(key_column), canonical_form(row_geometry(names, row)).key) << "candidate " << row[0];
    EXPECT_TRUE(keys_after.insert(row.at(key_column)).second) << "candidate " << row[0];
    hits_after += std::stoll(row.at(hits_column));
  }
  // Rows of two keys within the tolerance of each other merge, as a run's do.
  EXPECT_TRUE(std::includes(keys_before.begin(), keys_before.end(), keys_after.begin(), keys_after.end()));
  EXPECT_EQ(hits_after, hits_before);
  EXPECT_EQ(value(path,
                  "SELECT COUNT(*) FROM starts WHERE candidate_id IS NOT NULL AND candidate_id NOT IN "
                  "(SELECT candidate_id FROM candidates)"),
            "0");
  return before.size() - after.size();
}

// --- hand-built starts of one job ---------------------------------------------

LoopGeometry geometry_deg(std::vector<double> a, std::vector<double> alpha_deg, std::vector<double> d) {
  return LoopGeometry::from_degrees(a, alpha_deg, d);
}

constexpr std::uint64_t kStarts = 30;
const char* const kJob = "[search]\nstarts = 30\nseed = 4\n\n[output]\ndatabase = \"a.sqlite\"\n";

RunIdentity identity(const std::string& text = kJob, std::uint64_t seed = 4,
                     std::optional<StartSlice> slice = std::nullopt) {
  RunIdentity id;
  id.job_path = "jobs/test.toml";
  id.job_text = text;
  id.seed = seed;
  id.starts = kStarts;
  id.joints = 4;
  id.zero_threshold = 1e-12;
  id.report_threshold = 1e-6;
  id.slice = slice;
  return id;
}

// Start i: three linkages A, B (every slice) and C (from start 21 on), found
// by verified starts whose canonical geometries differ by less than the
// de-duplication tolerance and whose keys differ (so that the numeric test
// decides), with residuals that say which start represents a candidate;
// between them starts that are no zero, or a zero not verified.
StartRecord start(std::uint64_t i) {
  StartRecord r;
  r.index = i;
  r.status = "ftol_reached";
  r.E_mean = 1e-3 * static_cast<double>(i + 1);
  r.E_max = 2.0 * r.E_mean;
  r.objective = r.E_mean;
  r.evaluations = 10 + static_cast<int>(i);
  r.seconds = 0.25;
  r.final_geometry = geometry_deg({1, 2, 3, 2.5}, {20, 70, 40, 110}, {0.1, -0.3, 0.2, 0});
  r.final_angles = JointVector::Zero(4);
  if (i % 5 == 3) return r;
  r.E_mean = r.E_max = r.objective = 1e-20 * static_cast<double>(i + 1);
  r.zero = true;
  if (i % 5 == 4) return r;
  r.status = "stopval_reached";
  r.verified = true;
  const char linkage = i >= 21 && i % 3 == 0 ? 'C' : (i % 2 == 0 ? 'A' : 'B');
  const double base = linkage == 'A' ? 30.0 : (linkage == 'B' ? 50.0 : 70.0);
  const double jitter = 1e-7 * static_cast<double>(i % 3);  // well inside the 1e-5 tolerance
  r.candidate.canonical_geometry = geometry_deg({0.6 + jitter, 1.2, 0.6, 1.2}, {base, 90, base, 90}, {0, 0, 0, 0});
  r.final_geometry = r.candidate.canonical_geometry;
  r.candidate.canonical_key = std::string("key-") + linkage + "-" + std::to_string(i % 3);
  r.candidate.family = "bennett";
  r.candidate.setup = "asymmetric";
  r.candidate.detail = "start " + std::to_string(i);
  r.candidate.family_residual = 1e-15 * static_cast<double>(i + 1);
  r.candidate.bennett_residual = r.candidate.family_residual;
  r.candidate.planar_residual = 0.5;
  r.candidate.spherical_residual = 0.75;
  r.candidate.trivial_residual = std::numeric_limits<double>::infinity();
  r.candidate.rigid_residual = 1e-13;
  r.candidate.full_turn = true;
  r.candidate.range_hi_deg = 360.0;
  r.candidate.local_dimension = 3;
  r.candidate.free_parameters = 12;
  r.candidate.singular_values = {2.0, 0.5, 1e-13};
  return r;
}

// A database holding one run of `id`: the starts of its slice (or of [first,
// last) when given), committed in index order four at a time by one session.
void write_run(const std::string& path, const RunIdentity& id, std::optional<IndexRange> only = std::nullopt) {
  ResultsDatabase db = ResultsDatabase::open(path, DatabaseMode::write);
  const std::int64_t run = db.open_run(id).run_id;
  db.begin_session(run, 2);
  const IndexRange range = only ? *only : slice_range(id.slice, id.starts);
  std::vector<StartRecord> batch;
  for (std::uint64_t i = range.first; i < range.last; ++i) {
    batch.push_back(start(i));
    if (batch.size() == 4 || i + 1 == range.last) {
      db.commit(run, batch);
      batch.clear();
    }
  }
  db.end_session(RunStatus::complete);
}

StartSlice slice(std::uint64_t index, std::uint64_t count) { return StartSlice{index, count}; }

// --- slices --------------------------------------------------------------------

TEST(SliceRange, TilesTheStartsInNearlyEqualContiguousSlices) {
  for (std::uint64_t starts : {0ull, 1ull, 7ull, 30ull, 100ull, 1001ull}) {
    for (std::uint64_t count : {1ull, 2ull, 3ull, 7ull, 16ull}) {
      std::uint64_t next = 0, smallest = starts, largest = 0;
      for (std::uint64_t i = 0; i < count; ++i) {
        const IndexRange r = slice_range(slice(i, count), starts);
        EXPECT_EQ(r.first, next) << starts << " " << i << "/" << count;
        EXPECT_EQ(r.first, i * starts / count);
        next = r.last;
        smallest = std::min(smallest, r.last - r.first);
        largest = std::max(largest, r.last - r.first);
      }
      EXPECT_EQ(next, starts);
      EXPECT_LE(largest - smallest, 1u);
    }
  }
  const IndexRange whole = slice_range(std::nullopt, 30);
  EXPECT_EQ(whole.first, 0u);
  EXPECT_EQ(whole.last, 30u);
  // index * starts beyond 64 bits.
  const std::uint64_t huge = 1ull << 53;
  EXPECT_EQ(slice_range(slice(999, 1000), huge).last, huge);
  EXPECT_EQ(slice_range(slice(1, 3), huge).first, huge / 3);
  EXPECT_THROW(slice_range(slice(3, 3), 30), std::invalid_argument);
  EXPECT_THROW(slice_range(slice(0, 0), 30), std::invalid_argument);
  EXPECT_EQ(to_string(slice(2, 8)), "2/8");
}

TEST_F(MergeTest, TheSliceIsPartOfTheRunsIdentity) {
  const std::string path = file("slice1.sqlite");
  write_run(path, identity(kJob, 4, slice(1, 3)));
  EXPECT_EQ(rows(path, "SELECT slice_index, slice_count, starts_done FROM runs"), (Rows{{"1", "3", "10"}}));
  const std::string before = file_bytes(path);
  struct Case {
    RunIdentity id;
    std::string why;
  };
  RunIdentity more = identity(kJob, 4, slice(1, 3));
  more.starts = 60;
  for (const Case& c : {Case{identity(kJob, 4, slice(2, 3)), "slice 1/3 of 30 starts"},
                        Case{identity(kJob, 4, slice(1, 4)), "slice 1/4"}, Case{identity(), "every start"},
                        Case{more, "--starts 30"}}) {
    SCOPED_TRACE(c.why);
    ResultsDatabase db = ResultsDatabase::open(path, DatabaseMode::write);
    const std::string text = testing::refusal([&] { db.open_run(c.id); });
    EXPECT_NE(text.find(path), std::string::npos) << text;
    EXPECT_NE(text.find(c.why), std::string::npos) << text;
    EXPECT_NE(text.find("--new-run"), std::string::npos) << text;
  }
  EXPECT_EQ(file_bytes(path), before);
  // The same slice resumes; --new-run adds a run of another slice.
  ResultsDatabase db = ResultsDatabase::open(path, DatabaseMode::write);
  const RunInfo same = db.open_run(identity(kJob, 4, slice(1, 3)));
  EXPECT_FALSE(same.created);
  EXPECT_EQ(same.committed_count(), 10u);
  EXPECT_TRUE(db.open_run(identity(kJob, 4, slice(2, 3)), true).created);
  const std::vector<RunRow> runs = db.runs();
  ASSERT_EQ(runs.size(), 2u);
  ASSERT_TRUE(runs[1].slice.has_value());
  EXPECT_EQ(to_string(*runs[1].slice), "2/3");
}

// --- a database written before slices: schema version 1 -------------------------

const std::string kFixture = std::string(LOOPFARM_SOURCE_DIR) + "/tests/farm/fixtures/schema-v1.sqlite";

// The identity of the run in a fixture (tests/farm/fixtures/README.md), with
// `starts` as its target.
RunIdentity fixture_identity(const std::string& path, std::uint64_t starts) {
  RunIdentity own;
  own.job_path = value(path, "SELECT job_path FROM runs");
  own.job_text = value(path, "SELECT job_text FROM runs");
  own.seed = 7;
  own.starts = starts;
  own.joints = 4;
  own.zero_threshold = 1e-12;
  own.report_threshold = 1e-3;
  return own;
}

TEST_F(MergeTest, AVersion1DatabaseIsReadAsItIsAndUpgradedByItsNextRun) {
  const std::string path = file("v1.sqlite");
  fs::copy_file(kFixture, path);
  ASSERT_EQ(value(path, "PRAGMA user_version"), "1");
  const std::string before = file_bytes(path);
  const Rows starts = rows(path, "SELECT * FROM starts ORDER BY start_index");
  const Rows candidates = candidates_content(path);
  ASSERT_EQ(starts.size(), 12u);
  {
    // Read: as it is, nothing written.
    ResultsDatabase db = ResultsDatabase::open(path, DatabaseMode::read);
    const std::vector<RunRow> runs = db.runs();
    ASSERT_EQ(runs.size(), 1u);
    EXPECT_FALSE(runs[0].slice.has_value());
    EXPECT_EQ(runs[0].starts_done, 12);
  }
  EXPECT_EQ(file_bytes(path), before);
  {
    // Opening for writing and then refusing another job leaves it version 1.
    ResultsDatabase db = ResultsDatabase::open(path, DatabaseMode::write);
    RunIdentity other = identity("[search]\nseed = 99\n", 99);
    EXPECT_NE(testing::refusal([&] { db.open_run(other); }).find("--new-run"), std::string::npos);
  }
  EXPECT_EQ(value(path, "PRAGMA user_version"), "1");
  // Its own job resumes it: upgraded in the same transaction, rows kept.
  {
    ResultsDatabase db = ResultsDatabase::open(path, DatabaseMode::write);
    const RunInfo run = db.open_run(fixture_identity(path, 12));
    EXPECT_FALSE(run.created);
    EXPECT_EQ(run.committed_count(), 12u);
  }
  EXPECT_EQ(value(path, "PRAGMA user_version"), std::to_string(kDatabaseSchemaVersion));
  EXPECT_EQ(rows(path, "SELECT * FROM starts ORDER BY start_index"), starts);
  EXPECT_EQ(rows(path, "SELECT slice_index, slice_count FROM runs"), (Rows{{"NULL", "NULL"}}));
  expect_schema_of_a_new_database(path);
  // Its planar and trivial loops have parallel axes: keyed again (version
  // 7), none merged.
  EXPECT_EQ(expect_keyed_again(path, candidates), 0u);
}

// --- a database written before de-duplication moved into memory: version 2 ----

const std::string kVersion2Fixture = std::string(LOOPFARM_SOURCE_DIR) + "/tests/farm/fixtures/schema-v2.sqlite";

// Start 12 of the fixture's job as a verified start that found stored
// candidate `id` again: its geometry read back from the row, under its own key
// or another one (then only the numeric comparison can find the match).
StartRecord repeat_of_stored_candidate(const std::string& path, int id, const std::string& key) {
  const Rows row = rows(path,
                        "SELECT canonical_key, a1, a2, a3, a4, alpha1_deg, alpha2_deg, alpha3_deg, alpha4_deg, "
                        "d1, d2, d3, d4 FROM candidates WHERE candidate_id = " +
                            std::to_string(id));
  StartRecord r = start(12);
  if (row.size() != 1) {
    ADD_FAILURE() << "no candidate " << id << " in " << path;
    return r;
  }
  std::vector<double> a, alpha, d;
  for (int i = 0; i < 4; ++i) {
    a.push_back(std::stod(row[0][1 + i]));
    alpha.push_back(std::stod(row[0][5 + i]));
    d.push_back(std::stod(row[0][9 + i]));
  }
  r.candidate.canonical_geometry = geometry_deg(a, alpha, d);
  r.candidate.canonical_key = key.empty() ? row[0][0] : key;
  return r;
}

TEST_F(MergeTest, AVersion2DatabaseLosesTheDeduplicationIndexesAndStillFindsItsCandidates) {
  const std::string path = file("v2.sqlite");
  fs::copy_file(kVersion2Fixture, path);
  ASSERT_EQ(value(path, "PRAGMA user_version"), "2");
  const std::string before = file_bytes(path);
  const Rows starts = rows(path, "SELECT * FROM starts ORDER BY start_index");
  const Rows candidates = candidates_content(path);
  ASSERT_EQ(starts.size(), 12u);
  ASSERT_GE(candidates.size(), 2u);
  const std::string indexes =
      "SELECT name FROM sqlite_schema WHERE type = 'index' AND tbl_name = 'candidates' "
      "ORDER BY name";
  EXPECT_EQ(rows(path, indexes),
            (Rows{{"candidates_by_cell"}, {"candidates_by_joints_family"}, {"candidates_by_key"}}));
  {
    // Read: as it is, nothing written.
    ResultsDatabase db = ResultsDatabase::open(path, DatabaseMode::read);
    EXPECT_EQ(db.runs().at(0).starts_done, 12);
  }
  EXPECT_EQ(file_bytes(path), before);

  // Its own job, resumed with more starts: upgraded in the same transaction.
  CommitSummary by_key, by_value;
  {
    ResultsDatabase db = ResultsDatabase::open(path, DatabaseMode::write);
    const RunInfo run = db.open_run(fixture_identity(path, 14));
    EXPECT_EQ(run.committed_count(), 12u);
    // The candidates written before the upgrade are found again, by key and by value.
    by_key = db.commit(run.run_id, {repeat_of_stored_candidate(path, 1, "")});
    StartRecord near = repeat_of_stored_candidate(path, 2, "a key no candidate has");
    near.index = 13;
    by_value = db.commit(run.run_id, {near});
  }
  EXPECT_EQ(by_key.new_candidates, 0);
  EXPECT_EQ(by_key.repeat_hits, 1);
  EXPECT_EQ(by_value.new_candidates, 0);
  EXPECT_EQ(by_value.repeat_hits, 1);
  EXPECT_EQ(value(path, "PRAGMA user_version"), std::to_string(kDatabaseSchemaVersion));
  EXPECT_EQ(rows(path, indexes), (Rows{{"candidates_by_joints_family"}}));
  EXPECT_EQ(rows(path, "SELECT * FROM starts WHERE start_index < 12 ORDER BY start_index"), starts);
  EXPECT_EQ(rows(path, "SELECT candidate_id, hits FROM candidates WHERE candidate_id <= 2 ORDER BY candidate_id"),
            (Rows{{"1", std::to_string(std::stoi(candidates[0].back()) + 1)},
                  {"2", std::to_string(std::stoi(candidates[1].back()) + 1)}}));
  EXPECT_EQ(value(path, "SELECT COUNT(*) FROM candidates"), std::to_string(candidates.size()));
  expect_schema_of_a_new_database(path);
}

// --- a database written before the families whose conditions hold were recorded: version 3 ----

const std::string kVersion3Fixture = std::string(LOOPFARM_SOURCE_DIR) + "/tests/farm/fixtures/schema-v3.sqlite";

TEST_F(MergeTest, AVersion3DatabaseGainsTheFamiliesColumnItsOldRowsLeaveUnrecorded) {
  const std::string path = file("v3.sqlite");
  fs::copy_file(kVersion3Fixture, path);
  ASSERT_EQ(value(path, "PRAGMA user_version"), "3");
  const std::string before = file_bytes(path);
  const Rows starts = rows(path, "SELECT * FROM starts ORDER BY start_index");
  const std::string old_count = value(path, "SELECT COUNT(*) FROM candidates");
  ASSERT_EQ(starts.size(), 12u);
  ASSERT_GE(std::stoi(old_count), 2);
  {
    // Read: as it is, nothing written; the families are not recorded.
    ResultsDatabase db = ResultsDatabase::open(path, DatabaseMode::read);
    const std::vector<CandidateRow> read = db.candidates({});
    ASSERT_EQ(std::to_string(read.size()), old_count);
    for (const CandidateRow& r : read) EXPECT_FALSE(r.families.has_value()) << r.id;
    EXPECT_FALSE(db.candidate(1)->row.families.has_value());
  }
  EXPECT_EQ(file_bytes(path), before);

  // Its own job resumed: upgraded, and a new candidate records its families.
  {
    ResultsDatabase db = ResultsDatabase::open(path, DatabaseMode::write);
    const RunInfo run = db.open_run(fixture_identity(path, 14));
    EXPECT_EQ(run.committed_count(), 12u);
    StartRecord r = start(12);
    ASSERT_TRUE(r.verified);
    r.candidate.families = "bennett,planar";
    const CommitSummary committed = db.commit(run.run_id, {r});
    EXPECT_EQ(committed.new_candidates, 1);
  }
  EXPECT_EQ(value(path, "PRAGMA user_version"), std::to_string(kDatabaseSchemaVersion));
  EXPECT_EQ(rows(path, "SELECT * FROM starts WHERE start_index < 12 ORDER BY start_index"), starts);
  EXPECT_EQ(value(path, "SELECT COUNT(*) FROM candidates WHERE families IS NULL"), old_count);
  EXPECT_EQ(value(path, "SELECT families FROM candidates WHERE first_start = 12"), "bennett,planar");
  {
    ResultsDatabase db = ResultsDatabase::open(path, DatabaseMode::read);
    for (const CandidateRow& r : db.candidates({})) {
      if (r.first_start == 12) {
        EXPECT_EQ(r.families, std::optional<std::string>("bennett,planar"));
      } else {
        EXPECT_FALSE(r.families.has_value()) << r.id;
      }
    }
  }
  expect_schema_of_a_new_database(path);

  // Merged with a database of this version, the old rows stay unrecorded.
  const std::string merged = file("merged-v3.sqlite");
  fs::copy_file(kVersion3Fixture, file("v3-input.sqlite"));
  ResultsDatabase::merge(merged, {file("v3-input.sqlite")});
  EXPECT_EQ(value(merged, "SELECT COUNT(*) FROM candidates WHERE families IS NULL"), old_count);
}

// --- a database written before bond fingerprints were stored: version 4 ----

const std::string kVersion4Fixture = std::string(LOOPFARM_SOURCE_DIR) + "/tests/farm/fixtures/schema-v4.sqlite";

// The bond fingerprint of a stored candidate's geometry, measured here as
// docs/guide/bonds.md says: the motion traced as loopfarm verify traces it,
// the relations measured on the circuit it reports; empty when it does not move.
std::string measured_fingerprint(const CandidateRow& row) {
  const LoopGeometry geometry = candidate_geometry(row);
  const VerificationSummary motion = verify_motion(geometry, nullptr, VerificationOptions{});
  if (!motion.verified || static_cast<int>(motion.joint_angles.size()) < BondOptions{}.minimum_rows()) return "";
  return bond_relations(geometry, motion.joint_angles).fingerprint;
}

TEST_F(MergeTest, AVersion4DatabaseIsUpgradedWhenItsFingerprintsAreStoredAndKeepsEveryRow) {
  const std::string path = file("v4.sqlite");
  fs::copy_file(kVersion4Fixture, path);
  ASSERT_EQ(value(path, "PRAGMA user_version"), "4");
  const std::string before = file_bytes(path);
  const Rows starts = rows(path, "SELECT * FROM starts ORDER BY start_index");
  const Rows candidates = candidates_content(path);
  const Rows runs = rows(path, "SELECT * FROM runs");
  const Rows sessions = rows(path, "SELECT * FROM sessions");
  ASSERT_GE(starts.size(), 24u);
  ASSERT_GE(candidates.size(), 10u);

  // Read: as it is, nothing written, no fingerprint; measured here meanwhile.
  std::vector<BondFingerprint> fingerprints;
  {
    ResultsDatabase db = ResultsDatabase::open(path, DatabaseMode::read);
    const std::vector<FingerprintClass> classes = db.fingerprint_classes({});
    ASSERT_EQ(classes.size(), 1u);
    EXPECT_FALSE(classes[0].fingerprint.has_value());
    EXPECT_EQ(std::to_string(classes[0].candidates), std::to_string(candidates.size()));
    CandidateFilter missing;
    missing.without_fingerprint = true;
    EXPECT_EQ(std::to_string(db.candidate_count(missing)), std::to_string(candidates.size()));
    for (const CandidateRow& r : db.candidates({})) {
      EXPECT_FALSE(r.bond_fingerprint.has_value()) << r.id;
      fingerprints.push_back({r.id, r.first_run, r.first_start, measured_fingerprint(r)});
    }
  }
  EXPECT_EQ(file_bytes(path), before);
  const auto measured = std::count_if(fingerprints.begin(), fingerprints.end(),
                                      [](const BondFingerprint& f) { return !f.fingerprint.empty(); });
  EXPECT_GE(measured, 2);

  // Opened for writing and given nothing to store, it stays version 4, as it was.
  {
    ResultsDatabase db = ResultsDatabase::open(path, DatabaseMode::update);
    const FingerprintStoreSummary nothing = db.store_bond_fingerprints({});
    EXPECT_EQ(nothing.stored, 0);
    EXPECT_FALSE(nothing.upgraded);
  }
  EXPECT_EQ(value(path, "PRAGMA user_version"), "4");
  EXPECT_EQ(file_bytes(path), before);

  // Stored: upgraded in the same transaction, every row of runs, sessions
  // and starts kept. Its candidates with parallel axes (planar and trivial
  // loops) are keyed again (version 7) and two of them named one linkage
  // (the normals between their parallel axes left in other places): merged,
  // the fingerprint measured on the row merged away skipped.
  {
    ResultsDatabase db = ResultsDatabase::open(path, DatabaseMode::update);
    const FingerprintStoreSummary stored = db.store_bond_fingerprints(fingerprints);
    EXPECT_EQ(stored.stored, static_cast<std::int64_t>(fingerprints.size()) - 1);
    EXPECT_EQ(stored.skipped, 1);
    EXPECT_TRUE(stored.upgraded);
  }
  EXPECT_EQ(value(path, "PRAGMA user_version"), std::to_string(kDatabaseSchemaVersion));
  expect_schema_of_a_new_database(path);
  const Rows start_columns = rows(path, "SELECT name FROM pragma_table_info('starts')");
  ASSERT_EQ(start_columns[11][0], "candidate_id");
  Rows kept_starts = rows(path, "SELECT * FROM starts ORDER BY start_index");
  ASSERT_EQ(kept_starts.size(), starts.size());
  for (size_t i = 0; i < starts.size(); ++i) {
    std::vector<std::string> a = kept_starts[i], b = starts[i];
    a.erase(a.begin() + 11);
    b.erase(b.begin() + 11);
    EXPECT_EQ(a, b) << i;
  }
  EXPECT_EQ(rows(path, "SELECT * FROM runs"), runs);
  EXPECT_EQ(rows(path, "SELECT * FROM sessions"), sessions);
  {
    // Read without the fingerprints, to compare with the version 4 rows.
    const std::string copy = file("v5-without-fingerprints.sqlite");
    fs::copy_file(path, copy);
    exec(copy, "UPDATE candidates SET bond_fingerprint = NULL");
    EXPECT_EQ(expect_keyed_again(copy, candidates), 1u);
  }
  const Rows kept = rows(path, "SELECT candidate_id FROM candidates ORDER BY candidate_id");
  {
    ResultsDatabase db = ResultsDatabase::open(path, DatabaseMode::read);
    for (const BondFingerprint& f : fingerprints) {
      if (std::find(kept.begin(), kept.end(), std::vector<std::string>{std::to_string(f.candidate_id)}) == kept.end())
        continue;  // merged away
      EXPECT_EQ(db.candidate(f.candidate_id)->row.bond_fingerprint, std::optional<std::string>(f.fingerprint))
          << f.candidate_id;
    }
    std::int64_t grouped = 0;
    for (const FingerprintClass& c : db.fingerprint_classes({})) {
      EXPECT_TRUE(c.fingerprint.has_value());
      grouped += c.candidates;
    }
    EXPECT_EQ(std::to_string(grouped), std::to_string(kept.size()));
  }

  // Merged, a candidate keeps its fingerprint; merged as version 4, none.
  const std::string merged = file("merged-v5.sqlite");
  ResultsDatabase::merge(merged, {path});
  const std::string by_start = "SELECT first_start, bond_fingerprint FROM candidates ORDER BY first_start";
  EXPECT_EQ(rows(merged, by_start), rows(path, by_start));
  const std::string old_input = file("v4-input.sqlite"), merged_old = file("merged-v4.sqlite");
  fs::copy_file(kVersion4Fixture, old_input);
  ResultsDatabase::merge(merged_old, {old_input});
  EXPECT_EQ(value(merged_old, "SELECT COUNT(*) FROM candidates WHERE bond_fingerprint IS NULL"),
            std::to_string(kept.size()));
  Rows merged_rows = rows(merged, "SELECT * FROM candidates ORDER BY candidate_id");
  for (auto& row : merged_rows) row.pop_back();
  EXPECT_EQ(candidates_content(merged_old), merged_rows);

  // Its own job resumed: the run keeps the fingerprints, and a new candidate has none.
  {
    ResultsDatabase db = ResultsDatabase::open(path, DatabaseMode::write);
    const RunInfo run = db.open_run(fixture_identity(path, 26));
    EXPECT_EQ(run.committed_count(), starts.size());
    StartRecord r = start(25);
    ASSERT_TRUE(r.verified);
    EXPECT_EQ(db.commit(run.run_id, {r}).new_candidates, 1);
  }
  EXPECT_EQ(value(path, "SELECT COUNT(*) FROM candidates WHERE bond_fingerprint IS NULL"), "1");
  EXPECT_EQ(value(path, "SELECT bond_fingerprint IS NULL FROM candidates WHERE first_start = 25"), "1");
}

// --- a database written before the key took a zero-length link's twist with either sign: version 5 ----

// tests/farm/fixtures/README.md: one run of a 6R job (seed 11, 12 starts). Its
// first session, as the build before wrote it, committed starts 4..9 under the
// keys canonical_form gave before it took the twist at a zero-length link with
// either sign: the line-symmetric octahedral Bricard loop O (every a_i = 0) as
// candidate 1 (start 4, hit again by start 8) and, written with the twist of
// link 1 negated, as candidate 3 (start 7), each under another key; a loop G
// without a zero-length link as candidate 2 (start 6). Its second session, as
// the current build writes, committed starts 0..3, 10 and 11: O under the new
// key as candidate 4 (starts 1, 3 and 10), G found again by key (start 2,
// which then represents it).
const std::string kVersion5Fixture =
    std::string(LOOPFARM_SOURCE_DIR) + "/tests/farm/fixtures/schema-v5-zero-length.sqlite";

RunIdentity version5_identity(const std::string& path, std::uint64_t starts) {
  RunIdentity own = fixture_identity(path, starts);
  own.seed = 11;
  own.joints = 6;
  return own;
}

// The line-symmetric octahedral Bricard loop of the fixture, and a verified
// start of it written with the twists of `links` negated (the same loop).
LoopGeometry octahedral_loop(std::uint32_t links = 0) {
  LoopGeometry g = geometry_deg(std::vector<double>(6, 0.0), {50, 70, 110, 50, 70, 110}, {1, 1.3, 0.7, 1, 1.3, 0.7});
  for (int k = 0; k < 6; ++k) {
    if (links >> k & 1u) g.alpha[k] = -g.alpha[k];
  }
  return g;
}
StartRecord verified_start(std::uint64_t index, const LoopGeometry& g) {
  StartRecord r = start(0);
  r.index = index;
  r.final_geometry = g;
  r.final_angles = JointVector::Zero(g.joints());
  const CanonicalForm form = canonical_form(g);
  r.candidate.canonical_key = form.key;
  r.candidate.canonical_geometry = form.geometry;
  r.candidate.detail = "start " + std::to_string(index);
  return r;
}

// A database of an older schema version holding `candidates` rows: a reader
// leaves it byte for byte, and a run of another job is refused and leaves
// its version and candidates as they were (nothing of the upgrade written).
void expect_read_and_a_refused_run_leave_it(const std::string& path, const std::string& version, int candidates) {
  const std::string before = file_bytes(path);
  const Rows rows_before = rows(path, "SELECT * FROM candidates ORDER BY candidate_id");
  {
    ResultsDatabase db = ResultsDatabase::open(path, DatabaseMode::read);
    EXPECT_EQ(db.candidate_count(), candidates);
  }
  EXPECT_EQ(file_bytes(path), before);
  {
    ResultsDatabase db = ResultsDatabase::open(path, DatabaseMode::write);
    EXPECT_NE(testing::refusal([&] { db.open_run(identity("[search]\nseed = 99\n", 99)); }).find("--new-run"),
              std::string::npos);
  }
  EXPECT_EQ(value(path, "PRAGMA user_version"), version);
  EXPECT_EQ(rows(path, "SELECT * FROM candidates ORDER BY candidate_id"), rows_before);
}

// The upgrade of a copy of `fixture` (schema `version`) fails (a trigger
// refuses the removal of a merged row): the file is left as it was, and the
// message names it and the cause.
void expect_a_failing_upgrade_leaves_it(const std::string& fixture, const std::string& path, const std::string& version,
                                        RunIdentity (*identity_of)(const std::string&, std::uint64_t),
                                        std::uint64_t start_count) {
  fs::copy_file(fixture, path);
  const RunIdentity own = identity_of(path, start_count);
  exec(path, "CREATE TRIGGER keep_candidates BEFORE DELETE ON candidates BEGIN SELECT RAISE(ABORT, 'kept'); END");
  const Rows candidates = rows(path, "SELECT * FROM candidates ORDER BY candidate_id");
  const Rows starts = rows(path, "SELECT * FROM starts ORDER BY start_index");
  const Rows runs = rows(path, "SELECT * FROM runs");
  {
    ResultsDatabase db = ResultsDatabase::open(path, DatabaseMode::write);
    const std::string message = testing::refusal([&] { db.open_run(own); });
    EXPECT_NE(message.find(path), std::string::npos) << message;
    EXPECT_NE(message.find("kept"), std::string::npos) << message;
  }
  EXPECT_EQ(value(path, "PRAGMA user_version"), version);
  EXPECT_EQ(rows(path, "SELECT * FROM candidates ORDER BY candidate_id"), candidates);
  EXPECT_EQ(rows(path, "SELECT * FROM starts ORDER BY start_index"), starts);
  EXPECT_EQ(rows(path, "SELECT * FROM runs"), runs);
}

TEST_F(MergeTest, AVersion5DatabaseHasItsZeroLengthLinksKeyedAgainAndTheirDuplicatesMerged) {
  const std::string path = file("v5.sqlite");
  fs::copy_file(kVersion5Fixture, path);
  ASSERT_EQ(value(path, "PRAGMA user_version"), "5");
  const Rows starts = rows(path, "SELECT * FROM starts ORDER BY start_index");
  const Rows candidates = rows(path, "SELECT * FROM candidates ORDER BY candidate_id");
  const std::string run_columns =
      "SELECT run_id, job_path, job_text, job_hash, seed, starts, status, starts_done FROM runs";
  const Rows runs = rows(path, run_columns);
  ASSERT_EQ(starts.size(), 12u);
  ASSERT_EQ(candidates.size(), 4u);
  // Candidates 1, 3 and 4 are one loop under three keys; 4's is the current one.
  const std::string current_key = canonical_form(octahedral_loop()).key;
  EXPECT_EQ(rows(path, "SELECT candidate_id FROM candidates WHERE canonical_key = '" + current_key + "'"),
            (Rows{{"4"}}));
  EXPECT_EQ(value(path, "SELECT COUNT(DISTINCT canonical_key) FROM candidates"), "4");
  expect_read_and_a_refused_run_leave_it(path, "5", 4);
  EXPECT_EQ(rows(path, "SELECT * FROM starts ORDER BY start_index"), starts);

  // Its own job resumes it: upgraded in the same transaction.
  {
    ResultsDatabase db = ResultsDatabase::open(path, DatabaseMode::write);
    const RunInfo run = db.open_run(version5_identity(path, 12));
    EXPECT_FALSE(run.created);
    EXPECT_EQ(run.committed_count(), 12u);
  }
  EXPECT_EQ(value(path, "PRAGMA user_version"), std::to_string(kDatabaseSchemaVersion));
  expect_schema_of_a_new_database(path);
  // One row of O: candidate_id 1 (committed first), represented by its
  // earliest start (1, candidate 4's row), its hits those of the three rows.
  // G, without a zero-length link, exactly as it was.
  const Rows merged = rows(path, "SELECT * FROM candidates ORDER BY candidate_id");
  ASSERT_EQ(merged.size(), 2u);
  Rows expected = {candidates[3], candidates[1]};
  expected[0][0] = "1";
  const Rows names = rows(path, "SELECT name FROM pragma_table_info('candidates')");
  const auto hits_column =
      static_cast<size_t>(std::find(names.begin(), names.end(), std::vector<std::string>{"hits"}) - names.begin());
  ASSERT_LT(hits_column, names.size());
  expected[0][hits_column] = "6";  // 2 + 1 + 3
  EXPECT_EQ(merged, expected);
  EXPECT_EQ(value(path, "SELECT canonical_key FROM candidates WHERE candidate_id = 1"), current_key);
  EXPECT_EQ(value(path, "SELECT canonical_key FROM candidates WHERE candidate_id = 2"), candidates[1][5]);
  // Every start as it was, those of candidates 3 and 4 now naming 1.
  Rows repointed = starts;
  for (auto& row : repointed) {
    if (row[11] == "3" || row[11] == "4") row[11] = "1";
  }
  EXPECT_EQ(rows(path, "SELECT * FROM starts ORDER BY start_index"), repointed);
  EXPECT_EQ(rows(path,
                 "SELECT c.candidate_id, c.hits, COUNT(s.start_index) FROM candidates AS c "
                 "JOIN starts AS s ON s.candidate_id = c.candidate_id GROUP BY c.candidate_id"),
            (Rows{{"1", "6", "6"}, {"2", "2", "2"}}));
  EXPECT_EQ(rows(path, run_columns), runs);

  // The old key of O no longer splits it: O written yet another way, and G, are hits.
  {
    ResultsDatabase db = ResultsDatabase::open(path, DatabaseMode::write);
    const RunInfo run = db.open_run(version5_identity(path, 14));
    // G as the fixture wrote it (README.md), relabelled.
    const LoopGeometry g =
        geometry_deg({1, 1.2, 0.8, 1.1, 0.9, 0.7}, {40, 75, 120, -35, 65, 100}, {0.3, -0.2, 0.5, 0.1, 0.4, -0.3});
    const CommitSummary hits =
        db.commit(run.run_id, {verified_start(12, octahedral_loop(0b100010u)), verified_start(13, relabelled(g, 2))});
    EXPECT_EQ(hits.new_candidates, 0);
    EXPECT_EQ(hits.repeat_hits, 2);
  }
  EXPECT_EQ(rows(path, "SELECT candidate_id, hits FROM candidates ORDER BY candidate_id"),
            (Rows{{"1", "7"}, {"2", "3"}}));
}

// A merge of the version 5 file keys its rows again as the upgrade does: the
// same candidates as the upgraded file.
TEST_F(MergeTest, AVersion5DatabaseMergedHasItsZeroLengthLinksKeyedAgain) {
  const std::string input = file("v5-input.sqlite"), upgraded = file("v5.sqlite");
  fs::copy_file(kVersion5Fixture, input);
  fs::copy_file(kVersion5Fixture, upgraded);
  {
    ResultsDatabase db = ResultsDatabase::open(upgraded, DatabaseMode::write);
    db.open_run(version5_identity(upgraded, 12));
  }
  const std::string merged = file("merged.sqlite");
  const MergeSummary summary = ResultsDatabase::merge(merged, {input});
  EXPECT_EQ(summary.candidates, 2);
  const std::string all = "SELECT * FROM candidates ORDER BY candidate_id";
  EXPECT_EQ(rows(merged, all), rows(upgraded, all));
  EXPECT_EQ(rows(merged, "SELECT start_index, candidate_id FROM starts ORDER BY start_index"),
            rows(upgraded, "SELECT start_index, candidate_id FROM starts ORDER BY start_index"));

  // The first session alone (what the build before wrote, made so with SQL):
  // O's earliest start is under an old key, which the merge stores keyed
  // again, as the upgrade does.
  const std::string old_only = file("v5-old-only.sqlite"), old_upgraded = file("v5-old-upgraded.sqlite");
  fs::copy_file(kVersion5Fixture, old_only);
  exec(old_only,
       "DELETE FROM starts WHERE start_index IN (0, 1, 2, 3, 10, 11); DELETE FROM candidates WHERE candidate_id = 4; "
       "UPDATE candidates SET first_start = 6, hits = 1, detail = 'start 6' WHERE candidate_id = 2");
  fs::copy_file(old_only, old_upgraded);
  {
    ResultsDatabase db = ResultsDatabase::open(old_upgraded, DatabaseMode::write);
    db.open_run(version5_identity(old_upgraded, 12));
  }
  const std::string merged_old = file("merged-old.sqlite");
  EXPECT_EQ(ResultsDatabase::merge(merged_old, {old_only}).candidates, 2);
  EXPECT_EQ(rows(merged_old, all), rows(old_upgraded, all));
  EXPECT_EQ(value(merged_old, "SELECT canonical_key FROM candidates WHERE candidate_id = 1"),
            canonical_form(octahedral_loop()).key);
  EXPECT_EQ(value(merged_old, "SELECT hits FROM candidates WHERE candidate_id = 1"), "3");
}

// An upgrade that fails (here a trigger refuses the removal of a merged row)
// leaves the file as it was, version 5, and says which file.
TEST_F(MergeTest, AVersion5UpgradeThatFailsLeavesTheFileAsItWas) {
  expect_a_failing_upgrade_leaves_it(kVersion5Fixture, file("v5.sqlite"), "5", version5_identity, 12);
}

// Loops of 4 to 8 joints without a zero-length link, and O under the current
// key: a version 5 database of them is upgraded row for row as it was, every
// key byte for byte (and each key is what canonical_form gives its stored
// geometry). Written by this build, then PRAGMA user_version = 5: version 6
// changed no schema.
TEST_F(MergeTest, AVersion5DatabaseWithoutOldKeysOfZeroLengthLinksIsUpgradedRowForRow) {
  for (const bool with_current_zero_length_row : {false, true}) {
    const std::string path = file(with_current_zero_length_row ? "v5-current.sqlite" : "v5-generic.sqlite");
    {
      ResultsDatabase db = ResultsDatabase::open(path, DatabaseMode::write);
      const std::int64_t run = db.open_run(identity()).run_id;
      std::vector<StartRecord> records;
      for (std::uint64_t i = 0; i < 20; ++i) records.push_back(start(i));  // 4R, hand-made keys
      for (int n = 4; n <= 8; ++n) {
        std::vector<double> a, alpha, d;
        for (int k = 0; k < n; ++k) {
          a.push_back(0.4 + 0.13 * k);
          alpha.push_back(-70.0 + 29.0 * k);
          d.push_back(0.2 * (k % 3) - 0.15);
        }
        LoopGeometry g = geometry_deg(a, alpha, d);
        ASSERT_FALSE(has_zero_length_link(g));
        if (n != 4) continue;  // the run is of 4R loops; the others only checked above
        records.push_back(verified_start(20, g));
      }
      db.commit(run, records);
    }
    if (with_current_zero_length_row) {
      // O under its current key: the fixture's candidate 4, copied with SQL
      // (a 6R row in a 4R run; the upgrade reads each row's own joints).
      exec(path, "ATTACH '" + kVersion5Fixture +
                     "' AS f; INSERT INTO candidates SELECT * FROM f.candidates "
                     "WHERE candidate_id = 4; DETACH f");
    }
    exec(path, "PRAGMA user_version = 5");
    const Rows candidates = rows(path, "SELECT * FROM candidates ORDER BY candidate_id");
    const Rows starts = rows(path, "SELECT * FROM starts ORDER BY start_index");
    ASSERT_GE(candidates.size(), 3u);
    {
      ResultsDatabase db = ResultsDatabase::open(path, DatabaseMode::write);
      db.open_run(identity());
    }
    EXPECT_EQ(value(path, "PRAGMA user_version"), std::to_string(kDatabaseSchemaVersion));
    EXPECT_EQ(rows(path, "SELECT * FROM candidates ORDER BY candidate_id"), candidates);
    EXPECT_EQ(rows(path, "SELECT * FROM starts ORDER BY start_index"), starts);
    const Rows keys = rows(path, "SELECT canonical_key FROM candidates ORDER BY candidate_id");
    for (size_t i = 0; i < keys.size(); ++i) EXPECT_EQ(keys[i][0], candidates[i][5]);
  }
  // Every real key of a loop without a zero-length link is the key of its stored geometry.
  for (int n = 4; n <= 8; ++n) {
    std::vector<double> a, alpha, d;
    for (int k = 0; k < n; ++k) {
      a.push_back(0.4 + 0.13 * k);
      alpha.push_back(-70.0 + 29.0 * k);
      d.push_back(0.2 * (k % 3) - 0.15);
    }
    const LoopGeometry g = geometry_deg(a, alpha, d);
    const CanonicalForm form = canonical_form(g);
    LoopGeometry stored = form.geometry;
    for (int k = 0; k < n; ++k)
      stored.alpha[k] = form.geometry.alpha[k] * (180.0 / 3.14159265358979323846) * (3.14159265358979323846 / 180.0);
    EXPECT_EQ(canonical_form(stored).key, form.key) << n;
  }
}

// --- a database written before the key centred the normals between parallel axes: version 6 ---------

// tests/farm/fixtures/README.md: one run of a 6R job (seed 12, 8 starts), one
// session, as the build before wrote it: a line-symmetric Bricard loop P with
// parallel axes (links 1 and 4, twist 0) stored under three keys, its common
// normals between those axes left in three places: slid one way (start 1,
// candidate 1, found again by start 4), another (start 3, candidate 3), and
// as built (start 6, candidate 4); a loop G without parallel axes (start 2,
// candidate 2).
const std::string kVersion6Fixture =
    std::string(LOOPFARM_SOURCE_DIR) + "/tests/farm/fixtures/schema-v6-parallel-axes.sqlite";

RunIdentity version6_identity(const std::string& path, std::uint64_t starts) {
  RunIdentity own = fixture_identity(path, starts);
  own.seed = 12;
  own.joints = 6;
  return own;
}

// P of the fixture with the normal between axes 1 and 2 slid by s and the
// one between axes 4 and 5 by t (the same loop for every s and t).
LoopGeometry parallel_loop(double s = 0.0, double t = 0.0) {
  LoopGeometry g =
      geometry_deg({1.0, 1.3, 0.8, 1.0, 1.3, 0.8}, {0, 70, 110, 0, 70, 110}, {0.2, 0.3, -0.1, 0.2, 0.3, -0.1});
  g.d[0] += s;
  g.d[1] -= s;
  g.d[3] += t;
  g.d[4] -= t;
  return g;
}

TEST_F(MergeTest, AVersion6DatabaseHasItsParallelAxesKeyedAgainAndTheirDuplicatesMerged) {
  const std::string path = file("v6.sqlite");
  fs::copy_file(kVersion6Fixture, path);
  ASSERT_EQ(value(path, "PRAGMA user_version"), "6");
  const Rows starts = rows(path, "SELECT * FROM starts ORDER BY start_index");
  const Rows candidates = rows(path, "SELECT * FROM candidates ORDER BY candidate_id");
  ASSERT_EQ(starts.size(), 8u);
  ASSERT_EQ(candidates.size(), 4u);
  // P under three keys, none of them the current one, which every slide of P shares.
  const std::string current_key = canonical_form(parallel_loop()).key;
  EXPECT_EQ(canonical_form(parallel_loop(0.25, -0.4)).key, current_key);
  EXPECT_EQ(canonical_form(parallel_loop(-0.1, 0.3)).key, current_key);
  EXPECT_EQ(value(path, "SELECT COUNT(*) FROM candidates WHERE canonical_key = '" + current_key + "'"), "0");
  EXPECT_EQ(value(path, "SELECT COUNT(DISTINCT canonical_key) FROM candidates"), "4");
  expect_read_and_a_refused_run_leave_it(path, "6", 4);

  // Its own job resumes it: upgraded in the same transaction. P is one row,
  // candidate 1 (committed first, its representative start 1 the earliest)
  // with the hits of the three; G as it was.
  {
    ResultsDatabase db = ResultsDatabase::open(path, DatabaseMode::write);
    const RunInfo run = db.open_run(version6_identity(path, 8));
    EXPECT_FALSE(run.created);
    EXPECT_EQ(run.committed_count(), 8u);
  }
  EXPECT_EQ(value(path, "PRAGMA user_version"), std::to_string(kDatabaseSchemaVersion));
  expect_schema_of_a_new_database(path);
  EXPECT_EQ(rows(path, "SELECT candidate_id, first_start, hits, canonical_key = '" + current_key +
                           "' FROM candidates ORDER BY candidate_id"),
            (Rows{{"1", "1", "4", "1"}, {"2", "2", "1", "0"}}));
  EXPECT_EQ(rows(path, "SELECT * FROM candidates WHERE candidate_id = 2"), (Rows{candidates[1]}));
  Rows repointed = starts;
  for (auto& row : repointed) {
    if (row[11] == "3" || row[11] == "4") row[11] = "1";
  }
  EXPECT_EQ(rows(path, "SELECT * FROM starts ORDER BY start_index"), repointed);

  // P with its normals slid yet another way is a hit, not a new candidate.
  {
    ResultsDatabase db = ResultsDatabase::open(path, DatabaseMode::write);
    const RunInfo run = db.open_run(version6_identity(path, 9));
    const CommitSummary hits = db.commit(run.run_id, {verified_start(8, parallel_loop(0.6, 0.1))});
    EXPECT_EQ(hits.new_candidates, 0);
    EXPECT_EQ(hits.repeat_hits, 1);
  }
  EXPECT_EQ(rows(path, "SELECT candidate_id, hits FROM candidates ORDER BY candidate_id"),
            (Rows{{"1", "5"}, {"2", "1"}}));
}

// A merge of the version 6 file keys its rows again as the upgrade does.
TEST_F(MergeTest, AVersion6DatabaseMergedHasItsParallelAxesKeyedAgain) {
  const std::string input = file("v6-input.sqlite"), upgraded = file("v6.sqlite");
  fs::copy_file(kVersion6Fixture, input);
  fs::copy_file(kVersion6Fixture, upgraded);
  {
    ResultsDatabase db = ResultsDatabase::open(upgraded, DatabaseMode::write);
    db.open_run(version6_identity(upgraded, 8));
  }
  const std::string merged = file("merged.sqlite");
  EXPECT_EQ(ResultsDatabase::merge(merged, {input}).candidates, 2);
  const std::string all = "SELECT * FROM candidates ORDER BY candidate_id";
  EXPECT_EQ(rows(merged, all), rows(upgraded, all));
  EXPECT_EQ(rows(merged, "SELECT start_index, candidate_id FROM starts ORDER BY start_index"),
            rows(upgraded, "SELECT start_index, candidate_id FROM starts ORDER BY start_index"));
}

// An upgrade of the version 6 file that fails leaves it as it was.
TEST_F(MergeTest, AVersion6UpgradeThatFailsLeavesTheFileAsItWas) {
  expect_a_failing_upgrade_leaves_it(kVersion6Fixture, file("v6.sqlite"), "6", version6_identity, 8);
}

// --- merge ---------------------------------------------------------------------

// Each slice's candidates get a fingerprint naming the slice and the
// representative; the merged candidate carries the one of the row it is made
// of: the input that holds its earliest start.
TEST_F(MergeTest, AMergedCandidateKeepsTheFingerprintOfItsRepresentativesRow) {
  std::vector<std::string> slices;
  for (std::uint64_t i = 0; i < 3; ++i) {
    slices.push_back(file("slice" + std::to_string(i) + ".sqlite"));
    write_run(slices.back(), identity(kJob, 4, slice(i, 3)));
    if (i == 2) continue;  // the last slice measures none
    ResultsDatabase db = ResultsDatabase::open(slices.back(), DatabaseMode::update);
    std::vector<BondFingerprint> fingerprints;
    for (const CandidateRow& r : db.candidates({})) {
      fingerprints.push_back(
          {r.id, r.first_run, r.first_start, "slice " + std::to_string(i) + " start " + std::to_string(r.first_start)});
    }
    EXPECT_EQ(db.store_bond_fingerprints(fingerprints).stored, static_cast<std::int64_t>(fingerprints.size()));
  }
  const std::string merged = file("merged.sqlite");
  ResultsDatabase::merge(merged, slices);
  const Rows result = rows(merged, "SELECT first_start, bond_fingerprint FROM candidates ORDER BY first_start");
  ASSERT_EQ(result.size(), 3u);  // A and B from slice 0, C from slice 2 (starts 21 on)
  EXPECT_EQ(result, (Rows{{"0", "slice 0 start 0"}, {"1", "slice 0 start 1"}, {"21", "NULL"}}));
}

TEST_F(MergeTest, ThreeSlicesMergedEqualOneRunOfTheSameStarts) {
  const std::string whole = file("whole.sqlite");
  write_run(whole, identity());
  std::vector<std::string> slices;
  for (std::uint64_t i = 0; i < 3; ++i) {
    slices.push_back(file("slice" + std::to_string(i) + ".sqlite"));
    // Each slice's job names its own node-local database: [output] is not the job's identity.
    const std::string text =
        "[search]\nstarts = 30\nseed = 4\n\n[output]\ndatabase = \"/tmp/node" + std::to_string(i) + ".sqlite\"\n";
    write_run(slices.back(), identity(text, 4, slice(i, 3)));
  }
  // The candidates straddle the slices: each slice holds A and B.
  for (const std::string& s : slices) {
    EXPECT_GE(std::stoi(value(s, "SELECT COUNT(*) FROM candidates")), 2) << s;
  }
  std::vector<std::string> befores;
  for (const std::string& s : slices) befores.push_back(file_bytes(s));

  const std::string merged = file("merged.sqlite");
  const MergeSummary summary = ResultsDatabase::merge(merged, slices);
  EXPECT_EQ(summary.inputs, 3);
  EXPECT_EQ(summary.starts, kStarts);
  EXPECT_EQ(summary.overlapping_starts, 0u);
  EXPECT_EQ(summary.target, kStarts);
  EXPECT_TRUE(summary.complete);
  EXPECT_EQ(summary.candidates, 3);
  EXPECT_EQ(summary.verified, std::stoll(value(whole, "SELECT SUM(hits) FROM candidates")));

  const Rows candidates = candidates_content(whole);
  ASSERT_EQ(candidates.size(), 3u);
  EXPECT_EQ(candidates_content(merged), candidates);
  EXPECT_EQ(starts_content(merged), starts_content(whole));
  EXPECT_EQ(rows(merged, "SELECT job_text, seed, starts, starts_done, status, slice_index, joints FROM runs"),
            (Rows{{value(slices[0], "SELECT job_text FROM runs"), "4", "30", "30", "complete", "NULL", "4"}}));
  for (size_t i = 0; i < slices.size(); ++i) EXPECT_EQ(file_bytes(slices[i]), befores[i]) << slices[i];
  EXPECT_EQ(listing(), (std::vector<std::string>{"merged.sqlite", "slice0.sqlite", "slice1.sqlite", "slice2.sqlite",
                                                 "whole.sqlite"}));

  // Provenance: each input a row, each start the session and input it came from.
  EXPECT_EQ(rows(merged,
                 "SELECT input_id, path, source_run_id, slice_index, slice_count, starts, starts_done, starts_kept, "
                 "status FROM merge_inputs ORDER BY input_id"),
            (Rows{{"1", slices[0], "1", "0", "3", "30", "10", "10", "complete"},
                  {"2", slices[1], "1", "1", "3", "30", "10", "10", "complete"},
                  {"3", slices[2], "1", "2", "3", "30", "10", "10", "complete"}}));
  EXPECT_EQ(rows(merged,
                 "SELECT i.slice_index, MIN(s.start_index), MAX(s.start_index), COUNT(*) FROM starts AS s "
                 "JOIN sessions AS e ON e.session_id = s.session_id JOIN merge_inputs AS i ON i.input_id = e.input_id "
                 "GROUP BY i.input_id ORDER BY i.input_id"),
            (Rows{{"0", "0", "9", "10"}, {"1", "10", "19", "10"}, {"2", "20", "29", "10"}}));
  EXPECT_EQ(
      rows(merged, "SELECT session_id, input_id, source_session_id, ranks, status FROM sessions"),
      (Rows{{"1", "1", "1", "2", "complete"}, {"2", "2", "1", "2", "complete"}, {"3", "3", "1", "2", "complete"}}));

  // The order of the inputs does not matter; neither does merging in steps.
  const std::string reordered = file("reordered.sqlite");
  ResultsDatabase::merge(reordered, {slices[2], slices[0], slices[1]});
  EXPECT_EQ(candidates_content(reordered), candidates);
  EXPECT_EQ(starts_content(reordered), starts_content(whole));
  const std::string part = file("part.sqlite"), stepwise = file("stepwise.sqlite");
  ResultsDatabase::merge(part, {slices[0], slices[1]});
  EXPECT_EQ(value(part, "SELECT status FROM runs"), "stopped");  // 20 of 30 starts: resumable
  ResultsDatabase::merge(stepwise, {part, slices[2]});
  EXPECT_EQ(candidates_content(stepwise), candidates);
  EXPECT_EQ(starts_content(stepwise), starts_content(whole));
  // The earlier merge's inputs are kept, and the sessions still name them.
  EXPECT_EQ(rows(stepwise, "SELECT input_id, path, slice_index FROM merge_inputs ORDER BY input_id"),
            (Rows{{"1", slices[0], "0"}, {"2", slices[1], "1"}, {"3", part, "NULL"}, {"4", slices[2], "2"}}));
  EXPECT_EQ(rows(stepwise, "SELECT input_id, source_session_id FROM sessions ORDER BY session_id"),
            (Rows{{"1", "1"}, {"2", "1"}, {"4", "1"}}));
}

TEST_F(MergeTest, OverlappingEqualStartsAreKeptOnceAndAResumeFillsTheGaps) {
  const std::string whole = file("whole.sqlite"), first = file("first.sqlite"), middle = file("middle.sqlite");
  write_run(whole, identity());
  write_run(first, identity(), IndexRange{0, 12});  // a run stopped after 12 starts
  write_run(middle, identity(kJob, 4, slice(1, 3)));
  const std::string merged = file("merged.sqlite");
  const MergeSummary summary = ResultsDatabase::merge(merged, {first, middle});
  EXPECT_EQ(summary.starts, 20u);
  EXPECT_EQ(summary.overlapping_starts, 2u);  // starts 10 and 11
  EXPECT_FALSE(summary.complete);
  EXPECT_EQ(rows(merged, "SELECT starts_kept FROM merge_inputs ORDER BY input_id"), (Rows{{"12"}, {"8"}}));
  EXPECT_EQ(value(merged, "SELECT status FROM runs"), "stopped");
  // The merged run is a run of the whole job: the same job resumes it.
  {
    ResultsDatabase db = ResultsDatabase::open(merged, DatabaseMode::write);
    const RunInfo run = db.open_run(identity());
    EXPECT_FALSE(run.created);
    EXPECT_EQ(run.committed_count(), 20u);
    std::vector<StartRecord> rest;
    for (std::uint64_t i = 20; i < kStarts; ++i) rest.push_back(start(i));
    db.commit(run.run_id, rest);
  }
  EXPECT_EQ(candidates_content(merged), candidates_content(whole));
  EXPECT_EQ(starts_content(merged), starts_content(whole));
}

TEST_F(MergeTest, TheSmallestReportThresholdDecidesWhichStartsKeepTheirGeometry) {
  const std::string low = file("low.sqlite"), high = file("high.sqlite");
  RunIdentity strict = identity(kJob, 4, slice(0, 2));
  strict.report_threshold = 1e-12;  // only the zeros keep their geometry
  write_run(low, strict);
  RunIdentity loose = identity(kJob, 4, slice(1, 2));
  loose.report_threshold = 1.0;  // every start keeps its geometry
  write_run(high, loose);
  ASSERT_EQ(value(high, "SELECT COUNT(*) FROM starts WHERE a1 IS NULL"), "0");
  const std::string merged = file("merged.sqlite");
  ResultsDatabase::merge(merged, {high, low});
  EXPECT_EQ(value(merged, "SELECT report_threshold FROM runs"), "9.9999999999999998e-13");
  EXPECT_EQ(value(merged, "SELECT COUNT(*) FROM starts WHERE a1 IS NOT NULL AND E_mean > 1e-12"), "0");
  EXPECT_EQ(value(merged, "SELECT COUNT(*) FROM starts WHERE a1 IS NULL AND zero = 1"), "0");
}

TEST_F(MergeTest, RefusesMismatchedInputsAndWritesNothing) {
  const std::string a = file("a.sqlite"), b = file("b.sqlite");
  write_run(a, identity(kJob, 4, slice(0, 2)));
  write_run(b, identity(kJob, 4, slice(1, 2)));
  const std::string other_job = file("other-job.sqlite"), other_seed = file("other-seed.sqlite");
  write_run(other_job, identity("[search]\nstarts = 30\nseed = 4\nzero_threshold = 1e-10\n", 4, slice(1, 2)));
  write_run(other_seed, identity(kJob, 5, slice(1, 2)));   // the same text, another --seed
  const std::string differing = file("differing.sqlite");  // slice 1 with one start's energy changed
  fs::copy_file(b, differing);
  exec(differing, "UPDATE starts SET E_max = 1 WHERE start_index = 17");
  const std::string two_runs = file("two-runs.sqlite");
  write_run(two_runs, identity(kJob, 4, slice(1, 2)));
  {
    ResultsDatabase db = ResultsDatabase::open(two_runs, DatabaseMode::write);
    db.open_run(identity(kJob, 4, slice(0, 2)), true);
  }
  const std::string empty = file("empty.sqlite");
  { ResultsDatabase db = ResultsDatabase::open(empty, DatabaseMode::write); }
  const std::string existing = file("existing.sqlite");
  fs::copy_file(a, existing);
  const std::string not_sqlite = file("notes.sqlite");
  { std::ofstream(not_sqlite) << "not a database\n"; }

  struct Case {
    std::string output;
    std::vector<std::string> inputs;
    std::string culprit;
    std::vector<std::string> why;
  };
  const std::string out = file("out.sqlite");
  for (const Case& c : {
           Case{out, {a, other_job}, other_job, {"differs from that of " + a, "outside [output]", "zero_threshold"}},
           Case{out, {a, other_seed}, other_seed, {"seeds differ", "seed 5", "seed 4"}},
           Case{out, {b, differing}, differing, {"start 17 differs", "E_max 1 here", b}},
           Case{out, {a, two_runs}, two_runs, {"holds 2 runs"}},
           Case{out, {empty, a}, empty, {"holds no run"}},
           Case{out, {a, a}, a, {"given twice"}},
           Case{out, {a, not_sqlite}, not_sqlite, {"not an SQLite database"}},
           Case{out, {a, file("missing.sqlite")}, file("missing.sqlite"), {"no such file"}},
           Case{existing, {a, b}, existing, {"already exists"}},
           Case{file("no-such-dir/out.sqlite"), {a, b}, file("no-such-dir/out.sqlite"), {"cannot create"}},
       }) {
    SCOPED_TRACE(c.culprit + " " + c.why.front());
    const std::vector<std::string> files = listing();
    std::vector<std::string> bytes;
    for (const std::string& name : files) bytes.push_back(file_bytes(file(name)));
    const std::string text = testing::refusal([&] { ResultsDatabase::merge(c.output, c.inputs); });
    EXPECT_NE(text.find(c.culprit), std::string::npos) << text;
    for (const std::string& why : c.why) EXPECT_NE(text.find(why), std::string::npos) << text;
    EXPECT_EQ(text.find('\n'), std::string::npos) << text;
    // Nothing written: no output, no temporary file, every file as it was.
    EXPECT_EQ(listing(), files);
    for (size_t i = 0; i < files.size(); ++i) EXPECT_EQ(file_bytes(file(files[i])), bytes[i]) << files[i];
  }
  // The same pair with nothing wrong merges.
  EXPECT_EQ(ResultsDatabase::merge(out, {a, b}).starts, kStarts);
}

TEST_F(MergeTest, AVersion1DatabaseMergesAsItIs) {
  const std::string v1 = file("v1.sqlite");
  fs::copy_file(kFixture, v1);
  const std::string before = file_bytes(v1);
  const std::string merged = file("merged.sqlite");
  const MergeSummary summary = ResultsDatabase::merge(merged, {v1});
  EXPECT_EQ(summary.starts, 12u);
  EXPECT_TRUE(summary.complete);
  EXPECT_EQ(file_bytes(v1), before);
  // Its candidates keyed again as the upgrade keys them (parallel axes).
  const std::string upgraded = file("v1-upgraded.sqlite");
  fs::copy_file(kFixture, upgraded);
  {
    ResultsDatabase db = ResultsDatabase::open(upgraded, DatabaseMode::write);
    db.open_run(fixture_identity(upgraded, 12));
  }
  EXPECT_EQ(candidates_content(merged), candidates_content(upgraded));
  EXPECT_EQ(starts_content(merged), starts_content(v1));
  EXPECT_EQ(value(merged, "SELECT COUNT(*) FROM sessions WHERE input_id = 1"),
            value(v1, "SELECT COUNT(*) FROM sessions"));
}

}  // namespace
}  // namespace loopfarm
