// De-duplication of candidates, two ways: the store's (an in-memory index of
// keys and grid cells, rows read back to confirm) against a brute-force search
// written here from the rules alone (docs/guide/database.md): the stored
// candidate with the same key (the lowest id), else the nearest one with every
// canonical value within the tolerance (twists wrapped; ties to the lowest
// id), else a new candidate; the earliest (run, start) represents it. The
// records are built to land on grid-cell edges, near the +-180 degree wrap,
// within and just beyond the tolerance, and to repeat keys; the commits come
// out of index order, across a reopened file, a failed commit and a row
// written by another connection.
//
// And the index's parts on their own: cell names and their hashes, the
// open-addressing table through growth and collisions, and the exact text
// of the numbers the store writes.
#include "candidate_index.hpp"

#include <sqlite3.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <limits>
#include <map>
#include <random>
#include <set>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "loopfarm/core/loop.hpp"
#include "loopfarm/farm/results_database.hpp"
#include "sqlite_support.hpp"

namespace loopfarm {
namespace {

namespace fs = std::filesystem;

constexpr double kPi = 3.14159265358979323846;
constexpr double kTolerance = 1e-5;  // ResultsDatabase::commit's default

// --- the brute-force reference -------------------------------------------------

struct ReferenceCandidate {
  std::int64_t id = 0;
  std::string key;
  std::vector<double> values;  // a, alpha [rad, through degrees as stored], d
  std::int64_t first_run = 0, first_start = 0;
  std::int64_t hits = 0;
};

std::vector<double> stored_values(const LoopGeometry& g) {
  std::vector<double> v;
  for (int i = 0; i < g.joints(); ++i) v.push_back(g.a[i]);
  for (int i = 0; i < g.joints(); ++i) v.push_back((g.alpha[i] * (180.0 / kPi)) * (kPi / 180.0));
  for (int i = 0; i < g.joints(); ++i) v.push_back(g.d[i]);
  return v;
}

double largest_difference(const std::vector<double>& x, const std::vector<double>& y) {
  const size_t n = x.size() / 3;
  double largest = 0.0;
  for (size_t i = 0; i < x.size(); ++i) {
    const double difference = x[i] - y[i];
    largest = std::max(largest, std::abs(i >= n && i < 2 * n ? wrap_angle(difference) : difference));
  }
  return largest;
}

class ReferenceStore {
 public:
  // The candidate_id each record gets, the records taken in index order.
  std::map<std::uint64_t, std::int64_t> commit(std::int64_t run, std::vector<StartRecord> records) {
    std::sort(records.begin(), records.end(), [](const auto& x, const auto& y) { return x.index < y.index; });
    std::map<std::uint64_t, std::int64_t> placed;
    for (const StartRecord& r : records) {
      if (!r.verified) continue;
      const std::vector<double> values = stored_values(r.candidate.canonical_geometry);
      ReferenceCandidate* match = nullptr;
      for (ReferenceCandidate& c : candidates_) {
        if (c.key == r.candidate.canonical_key && (!match || c.id < match->id)) match = &c;
      }
      if (match) ++key_hits;
      if (!match) {
        double best = 0.0;
        for (ReferenceCandidate& c : candidates_) {
          const double distance = largest_difference(values, c.values);
          if (distance > kTolerance) continue;
          if (!match || distance < best || (distance == best && c.id < match->id)) {
            match = &c;
            best = distance;
          }
        }
        if (match) ++near_hits;
      }
      const auto start = static_cast<std::int64_t>(r.index);
      if (!match) {
        const std::int64_t id = candidates_.empty() ? 1 : candidates_.back().id + 1;
        candidates_.push_back({id, r.candidate.canonical_key, values, run, start, 1});
        placed[r.index] = id;
        continue;
      }
      ++match->hits;
      if (std::pair(run, start) < std::pair(match->first_run, match->first_start)) {
        match->key = r.candidate.canonical_key;
        match->values = values;
        match->first_run = run;
        match->first_start = start;
        ++replacements;
      }
      placed[r.index] = match->id;
    }
    return placed;
  }
  void add(ReferenceCandidate c) { candidates_.push_back(std::move(c)); }

  int key_hits = 0;      // found by the key
  int near_hits = 0;     // found by the values
  int replacements = 0;  // an earlier start came to represent a stored candidate

  // "id key first_run first_start hits" per candidate, by id.
  std::vector<std::string> rows() const {
    std::vector<std::string> out;
    for (const ReferenceCandidate& c : candidates_) {
      out.push_back(std::to_string(c.id) + " " + c.key + " " + std::to_string(c.first_run) + " " +
                    std::to_string(c.first_start) + " " + std::to_string(c.hits));
    }
    return out;
  }

 private:
  std::vector<ReferenceCandidate> candidates_;
};

// --- plain SQLite, to read what the store wrote ------------------------------------

std::vector<std::string> query(const std::string& path, const std::string& sql) {
  sqlite3* db = nullptr;
  EXPECT_EQ(sqlite3_open_v2(path.c_str(), &db, SQLITE_OPEN_READONLY, nullptr), SQLITE_OK);
  sqlite3_stmt* s = nullptr;
  EXPECT_EQ(sqlite3_prepare_v2(db, sql.c_str(), -1, &s, nullptr), SQLITE_OK) << sqlite3_errmsg(db);
  std::vector<std::string> out;
  while (sqlite3_step(s) == SQLITE_ROW) {
    std::string row;
    for (int c = 0; c < sqlite3_column_count(s); ++c) {
      const auto* text = reinterpret_cast<const char*>(sqlite3_column_text(s, c));
      row += (c ? " " : "") + std::string(text ? text : "NULL");
    }
    out.push_back(row);
  }
  sqlite3_finalize(s);
  sqlite3_close_v2(db);
  return out;
}

// --- records that test the lookup -------------------------------------------------

// Linkages whose values sit on or near grid-cell edges (multiples of 1e-3 for
// lengths, of 2 pi / 6283 for twists, the wrap at +-pi among them), and their
// repeats: the same key, or another key within, at or beyond the tolerance.
class LinkageMaker {
 public:
  explicit LinkageMaker(unsigned seed) : random_(seed) {}

  LoopGeometry base() {
    LoopGeometry g;
    g.a.resize(4);
    g.alpha.resize(4);
    g.d.resize(4);
    const double twist_cell = 2 * kPi / 6283;
    for (int i = 0; i < 4; ++i) {
      // Few distinct cells, so that linkages share cells and values.
      g.a[i] = 0.5 + 1e-3 * static_cast<double>(pick(6)) + edge_offset();
      g.alpha[i] = -kPi + twist_cell * static_cast<double>(pick(2) == 0 ? 0 : 3000 + pick(4)) + edge_offset();
      g.d[i] = 1e-3 * static_cast<double>(pick(3)) - 1e-3 + edge_offset();
    }
    return g;
  }

  // A near copy: every value moved by up to `spread` either way.
  LoopGeometry near(const LoopGeometry& g, double spread) {
    LoopGeometry out = g;
    std::uniform_real_distribution<double> move(-spread, spread);
    for (int i = 0; i < 4; ++i) {
      out.a[i] += move(random_);
      out.alpha[i] += move(random_);
      out.d[i] += move(random_);
    }
    return out;
  }

  int pick(int n) { return std::uniform_int_distribution<int>(0, n - 1)(random_); }
  double uniform() { return std::uniform_real_distribution<double>(0.0, 1.0)(random_); }

 private:
  // On an edge, just below or above it, or well inside the cell.
  double edge_offset() {
    switch (pick(4)) {
      case 0:
        return 0.0;
      case 1:
        return -4e-6;
      case 2:
        return 4e-6;
      default:
        return 4e-4;
    }
  }
  std::mt19937_64 random_;
};

StartRecord verified(std::uint64_t index, const LoopGeometry& canonical, const std::string& key) {
  StartRecord r;
  r.index = index;
  r.status = "stopval_reached";
  r.E_mean = 1e-25;
  r.E_max = 2e-25;
  r.objective = 1e-24;
  r.evaluations = 12;
  r.seconds = 0.002;
  r.zero = true;
  r.verified = true;
  r.final_geometry = canonical;
  r.final_angles = JointVector::Zero(4);
  CandidateRecord& c = r.candidate;
  c.family = "bennett";
  c.setup = "asymmetric";
  c.detail = "asymmetric setup";
  c.singular_values = {1.0, 0.5, 1e-15};
  c.trivial_residual = std::numeric_limits<double>::infinity();
  c.full_turn = true;
  c.local_dimension = 3;
  c.free_parameters = 12;
  c.canonical_key = key;
  c.canonical_geometry = canonical;
  return r;
}

StartRecord plain(std::uint64_t index) {
  StartRecord r = verified(index, LoopGeometry(), "");
  r.status = "ftol_reached";
  r.E_mean = r.E_max = r.objective = 0.5;
  r.zero = r.verified = false;
  r.final_geometry = LoopGeometry::from_degrees(std::vector<double>{1, 2, 1, 2}, std::vector<double>{30, 60, 30, 60},
                                                std::vector<double>{0, 0, 0, 0});
  r.candidate = CandidateRecord();
  return r;
}

// Commits of `per_commit` records each, over indices [0, count): verified
// starts of linkages made as they go, repeats of earlier ones by key or by
// geometry, plain starts between; shuffled within windows so that a later
// commit often holds an earlier start of a linkage (its representative moves).
std::vector<std::vector<StartRecord>> make_commits(LinkageMaker& make, std::uint64_t count, size_t per_commit) {
  std::vector<std::pair<LoopGeometry, std::string>> linkages;
  std::vector<StartRecord> records;
  for (std::uint64_t index = 0; index < count; ++index) {
    const double u = make.uniform();
    if (u < 0.3 || linkages.empty()) {
      linkages.emplace_back(make.base(), "key-" + std::to_string(index));
      records.push_back(verified(index, linkages.back().first, linkages.back().second));
    } else if (u < 0.45) {  // the same key, values anywhere near
      const auto& [g, key] = linkages[static_cast<size_t>(make.pick(static_cast<int>(linkages.size())))];
      records.push_back(verified(index, make.near(g, 1e-4), key));
    } else if (u < 0.75) {  // another key, values within or just beyond the tolerance
      const auto& [g, key] = linkages[static_cast<size_t>(make.pick(static_cast<int>(linkages.size())))];
      const double spread = make.pick(2) == 0 ? 0.6 * kTolerance : 1.6 * kTolerance;
      records.push_back(verified(index, make.near(g, spread), key + "-near-" + std::to_string(index)));
    } else {
      records.push_back(plain(index));
    }
  }
  // Out of order: each window of 3 commits shuffled.
  std::mt19937_64 shuffle(7);
  for (size_t first = 0; first < records.size(); first += 3 * per_commit) {
    const size_t last = std::min(records.size(), first + 3 * per_commit);
    std::shuffle(records.begin() + static_cast<long>(first), records.begin() + static_cast<long>(last), shuffle);
  }
  std::vector<std::vector<StartRecord>> commits;
  for (size_t first = 0; first < records.size(); first += per_commit) {
    commits.emplace_back(records.begin() + static_cast<long>(first),
                         records.begin() + static_cast<long>(std::min(records.size(), first + per_commit)));
  }
  return commits;
}

RunIdentity identity() {
  RunIdentity id;
  id.job_path = "jobs/test.toml";
  id.job_text = "[search]\nstarts = 100\n";
  id.seed = 1;
  id.starts = 1000000;
  id.joints = 4;
  id.zero_threshold = 1e-12;
  id.report_threshold = 1e-6;
  return id;
}

class CandidateIndexTest : public ::testing::Test {
 protected:
  void SetUp() override {
    static int counter = 0;
    dir_ = fs::temp_directory_path() /
           ("loopfarm_candidate_index_test_" + std::to_string(getpid()) + "_" + std::to_string(counter++));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string file(const std::string& name) const { return (dir_ / name).string(); }

  fs::path dir_;
};

// The store's candidates and each start's candidate_id equal the brute-force
// reference's, commit after commit.
TEST_F(CandidateIndexTest, StoreAgreesWithBruteForceDeduplication) {
  const std::string path = file("r.sqlite");
  LinkageMaker make(11);
  const auto commits = make_commits(make, 3000, 100);
  ReferenceStore reference;
  std::map<std::uint64_t, std::int64_t> expected_placement;
  std::int64_t run = 0;
  auto check = [&](const std::string& when) {
    EXPECT_EQ(query(path,
                    "SELECT candidate_id || ' ' || canonical_key || ' ' || first_run || ' ' || first_start || ' ' || "
                    "hits FROM candidates ORDER BY candidate_id"),
              reference.rows())
        << when;
    std::vector<std::string> expected;
    for (const auto& [index, id] : expected_placement)
      expected.push_back(std::to_string(index) + " " + std::to_string(id));
    EXPECT_EQ(query(path,
                    "SELECT start_index || ' ' || candidate_id FROM starts WHERE candidate_id IS NOT NULL "
                    "ORDER BY start_index"),
              expected)
        << when;
  };

  size_t next = 0;
  auto commit_some = [&](ResultsDatabase& db, size_t how_many) {
    for (size_t end = std::min(commits.size(), next + how_many); next < end; ++next) {
      db.commit(run, commits[next]);
      for (const auto& [index, id] : reference.commit(run, commits[next])) expected_placement[index] = id;
    }
  };
  {
    ResultsDatabase db = ResultsDatabase::open(path, DatabaseMode::write);
    run = db.open_run(identity()).run_id;
    commit_some(db, 10);
    check("after 10 commits");
    // A failed commit (a start already committed) writes nothing, and what it
    // would have added is not found later.
    std::vector<StartRecord> failing = commits[next];
    failing.push_back(commits[0].front());
    EXPECT_THROW(db.commit(run, failing), DatabaseError);
    commit_some(db, 5);
    check("after a failed commit");
  }
  {
    // Reopened: the lookup starts from what the file holds.
    ResultsDatabase db = ResultsDatabase::open(path, DatabaseMode::write);
    ASSERT_EQ(db.open_run(identity()).run_id, run);
    commit_some(db, 5);
    check("after reopening");

    // Another connection adds a candidate between two commits; a later start
    // with its key finds it, and being earlier than its first start, comes to
    // represent it.
    const LoopGeometry g = LoopGeometry::from_degrees(
        std::vector<double>{9, 9, 9, 9}, std::vector<double>{10, 10, 10, 10}, std::vector<double>{0, 0, 0, 0});
    const StartRecord late = verified(999998, make.near(g, 1e-3), "foreign");
    const std::string cell = store::grid_cell(store::canonical_entry(verified(0, g, "foreign"), run));
    sqlite3* other = nullptr;
    ASSERT_EQ(sqlite3_open_v2(path.c_str(), &other, SQLITE_OPEN_READWRITE, nullptr), SQLITE_OK);
    sqlite3_busy_timeout(other, 10000);
    char* message = nullptr;
    const std::string insert =
        "INSERT INTO candidates (joints, family, setup, detail, canonical_key, a1, a2, a3, a4, alpha1_deg, "
        "alpha2_deg, alpha3_deg, alpha4_deg, d1, d2, d3, d4, full_turn, local_dimension, free_parameters, "
        "singular_values, first_run, first_start, grid_cell, hits) VALUES (4, 'bennett', 'x', 'x', 'foreign', "
        "9, 9, 9, 9, 10, 10, 10, 10, 0, 0, 0, 0, 1, 3, 12, '[]', " +
        std::to_string(run) + ", 999999, '" + cell + "', 1)";
    ASSERT_EQ(sqlite3_exec(other, insert.c_str(), nullptr, nullptr, &message), SQLITE_OK) << message;
    sqlite3_close_v2(other);
    const std::int64_t foreign_id = std::stoll(query(path, "SELECT MAX(candidate_id) FROM candidates").at(0));
    reference.add({foreign_id, "foreign", stored_values(g), run, 999999, 1});
    db.commit(run, {late});
    for (const auto& [index, id] : reference.commit(run, {late})) expected_placement[index] = id;
    EXPECT_EQ(expected_placement[late.index], foreign_id);
    check("after another connection's write");
    commit_some(db, commits.size());
  }
  check("at the end");
  const std::vector<std::string> expected = reference.rows();
  // The test exercised every way: many linkages, hits by key and by value, moved representatives.
  EXPECT_GT(expected.size(), 200u);
  EXPECT_GT(reference.key_hits, 100);
  EXPECT_GT(reference.near_hits, 100);
  EXPECT_GT(reference.replacements, 20);
}

// --- the parts ---------------------------------------------------------------------

TEST(CandidateIndexParts, CellNamesAndTheirHashesAgree) {
  LinkageMaker make(3);
  for (int trial = 0; trial < 500; ++trial) {
    StartRecord r = verified(static_cast<std::uint64_t>(trial), make.near(make.base(), 1e-5), "k");
    const store::CanonicalEntry entry = store::canonical_entry(r, 1);
    const store::CellOptions options = store::cell_options(entry, kTolerance);
    ASSERT_EQ(options.values, 12);
    ASSERT_LE(options.combinations(), store::kMaxCellCombinations);
    // Every combination once: distinct names, hashes that the name gives back.
    std::set<std::string> names;
    store::CellChoice choice{};
    do {
      const std::string name = store::cell_name(options, choice);
      std::uint64_t from_name = 0;
      ASSERT_TRUE(store::cell_hash_of_name(4, name, from_name)) << name;
      EXPECT_EQ(from_name, store::cell_hash(4, options, choice)) << name;
      EXPECT_TRUE(names.insert(name).second) << name;
    } while (store::next_choice(options, choice));
    EXPECT_EQ(names.size(), options.combinations());
    // The candidate's own cell is the first combination.
    EXPECT_EQ(store::grid_cell(entry), *names.find(store::cell_name(options, store::CellChoice{})));
  }
  std::uint64_t hash = 0;
  EXPECT_FALSE(store::cell_hash_of_name(4, "1,2,3", hash));
  EXPECT_FALSE(store::cell_hash_of_name(1, "1,2,x", hash));
  EXPECT_TRUE(store::cell_hash_of_name(1, "-1,2,3", hash));
  EXPECT_NE(store::key_hash(4, "a"), store::key_hash(5, "a"));
}

TEST(CandidateIndexParts, TableReturnsEveryIdUnderItsHash) {
  store::CandidateIndex index;
  std::map<std::uint64_t, std::multiset<std::int64_t>> expected;
  // Many ids on few hashes (0 among them), through several growths.
  for (std::int64_t id = 1; id <= 20000; ++id) {
    const std::uint64_t hash = static_cast<std::uint64_t>(id % 997) * 0x9e3779b97f4a7c15ull;
    index.add(hash, id);
    expected[hash].insert(id);
  }
  EXPECT_EQ(index.entries(), 20000u);
  EXPECT_EQ(index.highest_id(), 20000);
  for (const auto& [hash, ids] : expected) {
    std::multiset<std::int64_t> found;
    index.for_each(hash, [&](std::int64_t id) { found.insert(id); });
    ASSERT_EQ(found, ids) << hash;
  }
  int none = 0;
  index.for_each(12345, [&](std::int64_t) { ++none; });
  EXPECT_EQ(none, 0);
  index.clear();
  index.for_each(0, [&](std::int64_t) { ++none; });
  EXPECT_EQ(none, 0);
  EXPECT_FALSE(index.loaded());
}

// The store writes reals into text (singular_values) as printf's %.17g does.
TEST(CandidateIndexParts, FormatDoubleIsPrintfG17) {
  std::vector<double> values = {0.0,
                                -0.0,
                                1.0,
                                -1.0,
                                0.1,
                                1.0 / 3.0,
                                2.2782478928674097e-14,
                                8.1622785218992015e-17,
                                1e16,
                                1e17,
                                123456789012345678.0,
                                1e-5,
                                1e-4,
                                0.0001234,
                                std::numeric_limits<double>::min(),
                                std::numeric_limits<double>::denorm_min(),
                                std::numeric_limits<double>::max(),
                                std::numeric_limits<double>::lowest(),
                                std::numeric_limits<double>::epsilon()};
  std::mt19937_64 random(5);
  for (int i = 0; i < 200000; ++i) {
    std::uint64_t bits = random();
    double x = 0.0;
    std::memcpy(&x, &bits, sizeof x);
    if (std::isfinite(x)) values.push_back(x);
    values.push_back(std::uniform_real_distribution<double>(-1.0, 1.0)(random));
  }
  for (double x : values) {
    char expected[40];
    std::snprintf(expected, sizeof expected, "%.17g", x);
    ASSERT_EQ(store::format_double(x), expected);
  }
}

}  // namespace
}  // namespace loopfarm
