// `loopfarm report`, run as a user runs it on a database built here with the
// library (hand-made records, no search): files and scripts get every row,
// the table 50 and says so; --summary in every format it has; a run, family
// or candidate the database does not hold refused naming what it holds; the
// table's width and round-off; and one candidate whole with its joint axes,
// checked against the common normals of consecutive axes. JSON is read back
// with SQLite's JSON functions. LOOPFARM_EXECUTABLE is the built binary.
#include <sqlite3.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "command_test_support.hpp"
#include "loopfarm/farm/results_database.hpp"
#include "loopfarm/search/canonical.hpp"
#include "loopfarm/search/verify.hpp"

namespace loopfarm {
namespace {

namespace fs = std::filesystem;
using testing::split;

const std::string kExecutable = LOOPFARM_EXECUTABLE;
constexpr double kPi = 3.14159265358979323846;
constexpr double kBennettOffsetNoise = -4.39262e-16;

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

// One CSV line's fields, quotes ("a,b" and "" inside) undone.
std::vector<std::string> csv_fields(const std::string& line) {
  std::vector<std::string> fields(1);
  bool quoted = false;
  for (size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (quoted && c == '"' && i + 1 < line.size() && line[i + 1] == '"') {
      fields.back() += '"';
      ++i;
    } else if (c == '"') {
      quoted = !quoted;
    } else if (c == ',' && !quoted) {
      fields.emplace_back();
    } else {
      fields.back() += c;
    }
  }
  return fields;
}

double to_number(const std::string& text) {
  if (text.empty()) return std::nan("");
  char* end = nullptr;
  const double value = std::strtod(text.c_str(), &end);
  return end == text.c_str() + text.size() ? value : std::nan("");
}

// SQLite's JSON functions on a document: json_valid, and json_extract or
// json_array_length at a path, as text ("" for SQL NULL).
std::string json_query(const std::string& function, const std::string& document, const std::string& path = "") {
  sqlite3* db = nullptr;
  sqlite3_open(":memory:", &db);
  const std::string sql = "SELECT " + function + (path.empty() ? "(?1)" : "(?1, ?2)");
  sqlite3_stmt* statement = nullptr;
  std::string out = "(SQL error)";
  if (sqlite3_prepare_v2(db, sql.c_str(), -1, &statement, nullptr) == SQLITE_OK) {
    sqlite3_bind_text(statement, 1, document.c_str(), static_cast<int>(document.size()), SQLITE_TRANSIENT);
    if (!path.empty()) sqlite3_bind_text(statement, 2, path.c_str(), -1, SQLITE_TRANSIENT);
    if (sqlite3_step(statement) == SQLITE_ROW) {
      if (sqlite3_column_type(statement, 0) == SQLITE_FLOAT) {
        char buffer[40];
        std::snprintf(buffer, sizeof buffer, "%.17g", sqlite3_column_double(statement, 0));
        out = buffer;
      } else {
        const auto* text = reinterpret_cast<const char*>(sqlite3_column_text(statement, 0));
        out = text ? text : "";
      }
    }
  }
  sqlite3_finalize(statement);
  sqlite3_close(db);
  return out;
}
bool json_valid(const std::string& document) { return json_query("json_valid", document) == "1"; }
std::string json_text(const std::string& document, const std::string& path) {
  return json_query("json_extract", document, path);
}
double json_real(const std::string& document, const std::string& path) { return to_number(json_text(document, path)); }
long long json_length(const std::string& document, const std::string& path = "$") {
  return std::stoll(json_query("json_array_length", document, path));
}

// --- the database ---------------------------------------------------------------

// A verified start; its canonical key (which the store de-duplicates by) is
// FAMILY-KEY, KEY the start's index unless given.
StartRecord verified(std::uint64_t index, const LoopGeometry& canonical, const std::string& family, double E_mean,
                     std::uint64_t key = ~std::uint64_t{0}) {
  StartRecord r;
  r.index = index;
  r.status = "stopval_reached";
  r.E_mean = E_mean;
  r.E_max = 3.0 * E_mean;
  r.objective = E_mean;
  r.evaluations = 40;
  r.seconds = 0.25;
  r.zero = true;
  r.verified = true;
  r.final_geometry = canonical;
  r.final_angles = JointVector::Zero(canonical.joints());
  CandidateRecord& c = r.candidate;
  c.family = family;
  c.setup = family == "bennett" ? "asymmetric" : "none";
  c.detail = family + " loop";
  c.family_residual = 1e-14;
  c.bennett_residual = 1e-14;
  c.planar_residual = 0.5;
  c.spherical_residual = 0.75;
  c.trivial_residual = std::numeric_limits<double>::infinity();
  c.rigid_residual = 1e-13;
  c.full_turn = true;
  c.range_lo_deg = -180.0;
  c.range_hi_deg = 180.0;
  c.local_dimension = 3;
  c.free_parameters = 12;
  c.singular_values = {2.0, 0.5, 1e-13};
  c.canonical_key = family + "-" + std::to_string(key == ~std::uint64_t{0} ? index : key);
  c.canonical_geometry = canonical;
  return r;
}

LoopGeometry degrees(std::vector<double> a, std::vector<double> alpha_deg, std::vector<double> d) {
  return LoopGeometry::from_degrees(a, alpha_deg, d);
}

constexpr int kFiller = 1200;      // bennett-like rows of run 1 beyond the real loops
constexpr int kCandidates = 1206;  // 4 real loops, the filler, 2 of run 2
constexpr int kBennett = 1203;     // the Bennett loop, the filler, run 2's

// A 4R test job (or of `joints` joints) of `starts` starts, seed 1, zero
// threshold 1e-12, report threshold 1e-6.
RunIdentity test_job(const std::string& job_path, std::uint64_t starts, int joints = 4) {
  RunIdentity id;
  id.job_path = job_path;
  id.job_text = "[search]\nstarts = " + std::to_string(starts) + "\n";
  id.seed = 1;
  id.starts = starts;
  id.joints = joints;
  id.zero_threshold = 1e-12;
  id.report_threshold = 1e-6;
  return id;
}

// Candidate 1: a Bennett loop (canonical, its offset d1 stored as round-off);
// 2: a planar crank-rocker whose joint 1 turns fully; 3: a generic loop that
// does not move (unclassified); 4: a planar crank-rocker whose joint 1 rocks;
// then bennett-like rows at three energies (ties), and two rows of run 2.
void build_database(const std::string& path) {
  ResultsDatabase db = ResultsDatabase::open(path, DatabaseMode::write);
  RunIdentity id = test_job("jobs/report-test.toml", 2000);
  const std::int64_t run1 = db.open_run(id).run_id;
  const double s = std::sqrt(10.0);
  LoopGeometry bennett = degrees({2 / s, 4 / s, 2 / s, 4 / s}, {30, 90, 30, 90}, {0, 0, 0, 0});
  bennett.d[0] = kBennettOffsetNoise;
  std::vector<StartRecord> records = {
      verified(0, bennett, "bennett", 1e-25),
      verified(1, degrees({1, 3, 2.5, 3.2}, {0, 0, 0, 0}, {0, 0, 0, 0}), "planar", 1e-28),
      verified(2, degrees({1, 2, 3, 2.5}, {20, 70, 40, 110}, {0.1, -0.3, 0.2, 0}), "unclassified", 1e-18),
      verified(3, degrees({3, 1, 3.2, 2.5}, {0, 0, 0, 0}, {0, 0, 0, 0}), "planar", 1e-27)};
  const double energies[] = {1e-20, 1e-22, 1e-21};
  for (int i = 0; i < kFiller; ++i) {
    const double x = 0.001 * i;
    records.push_back(
        verified(static_cast<std::uint64_t>(4 + i),
                 degrees({0.5 + x, 1.2 - 0.5 * x, 0.5 + x, 1.2 - 0.5 * x}, {35, 90, 35, 90}, {0, 0, 0, 0}), "bennett",
                 energies[i % 3]));
  }
  db.commit(run1, records);
  id.job_text = "[search]\nstarts = 10\n";
  id.seed = 9;
  const std::int64_t run2 = db.open_run(id, true).run_id;
  db.commit(run2,
            {verified(0, degrees({0.3, 0.9, 0.3, 0.9}, {20, 60, 20, 60}, {0, 0, 0, 0}), "bennett", 1e-23, 5000),
             verified(1, degrees({0.35, 0.9, 0.35, 0.9}, {20, 60, 20, 60}, {0, 0, 0, 0}), "bennett", 1e-24, 5001)});
}

class ReportCli : public testing::CommandTest {
 protected:
  ReportCli() : CommandTest("loopfarm-report-test") {}

  static void SetUpTestSuite() {
    database_ = (fs::temp_directory_path() / ("loopfarm-report-test-" + std::to_string(::getpid()) + ".sqlite"));
    fs::remove(database_);
    build_database(database_.string());
  }
  static void TearDownTestSuite() { fs::remove(database_); }

  // `loopfarm report DB args...`
  testing::CommandResult report(std::vector<std::string> args) {
    args.insert(args.begin(), database_.string());
    return run_command(kExecutable, "report", args);
  }
  // Exit code 2, one line on stderr containing every one of `texts`, nothing on stdout.
  void expect_refused(const std::vector<std::string>& args, const std::vector<std::string>& texts) {
    const testing::CommandResult r = report(args);
    std::string joined;
    for (const std::string& a : args) joined += " " + a;
    EXPECT_EQ(r.exit_code, 2) << joined << ": " << r.err;
    EXPECT_EQ(lines_of(r.err).size(), 1u) << joined << ": " << r.err;
    EXPECT_TRUE(r.out.empty()) << joined << ": " << r.out.substr(0, 300);
    for (const std::string& text : texts) EXPECT_NE(r.err.find(text), std::string::npos) << joined << ": " << r.err;
  }

  static fs::path database_;
};

fs::path ReportCli::database_;

TEST_F(ReportCli, FilesGetEveryRowAndTheTableFiftyWithACount) {
  testing::CommandResult r = report({"--format", "csv"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(lines_of(r.out).size(), static_cast<size_t>(kCandidates + 1));
  r = report({"--family", "bennett", "--format", "csv"});
  EXPECT_EQ(lines_of(r.out).size(), static_cast<size_t>(kBennett + 1));
  r = report({"--format", "json"});
  ASSERT_TRUE(json_valid(r.out));
  EXPECT_EQ(json_length(r.out), kCandidates);
  r = report({"--format", "markdown"});
  EXPECT_EQ(lines_of(r.out).size(), static_cast<size_t>(kCandidates + 2));

  // An explicit --limit applies to every format; 0 is every row.
  EXPECT_EQ(lines_of(report({"--format", "csv", "--limit", "7"}).out).size(), 8u);
  EXPECT_EQ(json_length(report({"--format", "json", "--limit", "3"}).out), 3);
  EXPECT_EQ(lines_of(report({"--format", "csv", "--limit", "0"}).out).size(), static_cast<size_t>(kCandidates + 1));

  r = report({});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::vector<std::string> lines = lines_of(r.out);
  ASSERT_EQ(lines.size(), 52u);  // header, 50 rows, the count
  EXPECT_EQ(lines.back(), "showing 50 of 1,206 (use --limit 0 for all)");
  lines = lines_of(report({"--limit", "10"}).out);
  ASSERT_EQ(lines.size(), 12u);
  EXPECT_EQ(lines.back(), "showing 10 of 1,206 (use --limit 0 for all)");
  r = report({"--limit", "0"});
  EXPECT_EQ(lines_of(r.out).size(), static_cast<size_t>(kCandidates + 1));
  EXPECT_EQ(r.out.find("showing"), std::string::npos);
  // Nothing left out, nothing said.
  r = report({"--family", "planar"});
  EXPECT_EQ(lines_of(r.out).size(), 3u);
  EXPECT_EQ(r.out.find("showing"), std::string::npos);
  r = report({"--max-energy", "1e-40"});
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_EQ(r.out, "(no candidates match)\n");
  expect_refused({"--limit", "-1"}, {"--limit", "-1"});
  expect_refused({"--limit", "ten"}, {"--limit", "ten"});
}

// A candidate's chart quotes the stored E_mean exactly as the table prints it
// (the chart's own curve is recomputed and has its own mean, named apart).
TEST_F(ReportCli, ACandidateChartQuotesTheTablesEnergy) {
  if (std::system("command -v gnuplot >/dev/null 2>&1") != 0) GTEST_SKIP() << "gnuplot is not installed";
  const testing::CommandResult r = report({"--family", "planar", "--limit", "1", "--plot", "{dir}/charts"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::vector<std::string> lines = lines_of(r.out);
  ASSERT_GE(lines.size(), 2u) << r.out;
  std::istringstream row(lines[1]);
  std::string id, family, energy;
  row >> id >> family >> energy;
  EXPECT_NE(r.err.find("candidate_" + id + "_cycle.png (E_mean " + energy + " stored, "), std::string::npos)
      << lines[1] << "\n"
      << r.err;
  for (const std::string& name : {"candidate_" + id + "_cycle.png", std::string("minima_histogram.png")}) {
    std::ifstream in(dir_ / "charts" / name, std::ios::binary);
    std::string magic(8, '\0');
    in.read(magic.data(), 8);
    EXPECT_EQ(magic, std::string("\x89PNG\r\n\x1a\n", 8)) << name;
  }
}

TEST_F(ReportCli, SummaryFollowsTheFormat) {
  testing::CommandResult r = report({"--summary", "--format", "json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  ASSERT_TRUE(json_valid(r.out)) << r.out;
  EXPECT_EQ(json_length(r.out, "$.runs"), 2);
  EXPECT_EQ(json_text(r.out, "$.runs[1].run_id"), "2");
  EXPECT_EQ(json_text(r.out, "$.runs[0].job_path"), "jobs/report-test.toml");
  EXPECT_EQ(json_text(r.out, "$.run"), "");
  EXPECT_EQ(json_text(r.out, "$.starts.starts"), std::to_string(kCandidates));
  EXPECT_EQ(json_text(r.out, "$.starts.verified"), std::to_string(kCandidates));
  EXPECT_EQ(json_length(r.out, "$.families"), 3);
  EXPECT_EQ(json_text(r.out, "$.families[0].family"), "bennett");
  EXPECT_EQ(json_text(r.out, "$.families[0].candidates"), std::to_string(kBennett));
  EXPECT_EQ(json_text(r.out, "$.by_status[0].status"), "stopval_reached");
  EXPECT_GT(json_length(r.out, "$.histogram.decades"), 0);

  r = report({"--summary", "--format", "json", "--run", "2"});
  ASSERT_TRUE(json_valid(r.out)) << r.out;
  EXPECT_EQ(json_text(r.out, "$.run"), "2");
  EXPECT_EQ(json_text(r.out, "$.starts.starts"), "2");

  r = report({"--summary", "--format", "markdown"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("| family | candidates | hits |"), std::string::npos);
  EXPECT_NE(r.out.find("| bennett | 1203 | 1203 |"), std::string::npos) << r.out;
  r = report({"--summary"});
  EXPECT_NE(r.out.find("histogram of log10(E_mean)"), std::string::npos);
  expect_refused({"--summary", "--format", "csv"}, {"--format", "csv", "--summary"});
}

TEST_F(ReportCli, WhatTheDatabaseDoesNotHoldIsRefusedNamingWhatItHolds) {
  expect_refused({"--run", "5"}, {"--run", "no run 5", "its runs: 1, 2"});
  expect_refused({"--summary", "--run", "5"}, {"--run", "its runs: 1, 2"});
  expect_refused({"--run", "five"}, {"--run", "five"});
  expect_refused({"--family", "myard"},
                 {"--family", "no myard candidate", "families present: bennett (1,203), planar (2), unclassified (1)"});
  expect_refused({"--family", "conic"}, {"--family", "conic", "expected one of"});
  expect_refused({"--candidate", "99999"}, {"--candidate", "no candidate 99999", "candidate ids 1 to 1206"});
  expect_refused({"--candidate", "0", "--format", "json"}, {"--candidate", "candidate ids 1 to 1206"});
  expect_refused({"--candidate", "x1"}, {"--candidate", "x1"});
  // A run the database holds that found none of them is an empty list, not an error.
  const testing::CommandResult r = report({"--run", "2", "--family", "planar"});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.out, "(no candidates match)\n");
}

TEST_F(ReportCli, TheTableFits120ColumnsShowsRoundOffAsZeroAndIsDeterministic) {
  testing::CommandResult r = report({"--limit", "0"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::vector<std::string> lines = lines_of(r.out);
  for (const std::string& line : lines) EXPECT_LE(line.size(), 120u) << line;
  EXPECT_EQ(lines[0].find("rigid_res"), std::string::npos);
  // The Bennett loop (candidate 1): its offset d1 = -4.4e-16 is shown as 0.
  std::string bennett;
  for (const std::string& line : lines) {
    if (line.rfind("1 ", 0) == 0) bennett = line;
  }
  ASSERT_FALSE(bennett.empty()) << r.out.substr(0, 500);
  EXPECT_NE(bennett.find("d=0,0,0,0"), std::string::npos) << bennett;
  EXPECT_EQ(r.out.find("e-16"), std::string::npos);

  r = report({"--wide", "--limit", "0"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::vector<std::string> wide = lines_of(r.out);
  for (const char* column : {"setup", "first", "rigid_res", "family_res", "input range"}) {
    EXPECT_NE(wide[0].find(column), std::string::npos) << column;
  }
  EXPECT_TRUE(std::any_of(wide.begin(), wide.end(), [](const std::string& l) { return l.size() > 120; }));
  EXPECT_EQ(r.out.find("e-16"), std::string::npos);
  expect_refused({"--wide", "--format", "csv"}, {"--wide"});

  // csv keeps the stored value to the bit.
  r = report({"--format", "csv"});
  const std::vector<std::string> csv = lines_of(r.out);
  const std::vector<std::string> header = split(csv[0], ',');
  const size_t d1 = static_cast<size_t>(std::find(header.begin(), header.end(), "d1") - header.begin());
  ASSERT_LT(d1, header.size());
  bool seen = false;
  std::vector<std::pair<double, long long>> order;
  for (size_t i = 1; i < csv.size(); ++i) {
    const std::vector<std::string> f = split(csv[i], ',');
    if (f[0] == "1") {
      EXPECT_EQ(to_number(f[d1]), kBennettOffsetNoise);
      seen = true;
    }
    if (f[1] != "unclassified") order.push_back({to_number(f[4]), std::stoll(f[0])});
  }
  EXPECT_TRUE(seen);
  // From zero upwards; equal energies (a third of the filler each) by id.
  EXPECT_TRUE(std::is_sorted(order.begin(), order.end()));
  EXPECT_EQ(report({"--format", "csv"}).out, r.out);
}

// The distance of two lines p + s u along their common normal, and the angle
// of their directions [rad].
std::pair<double, double> distance_and_angle(const double p1[3], const double u1[3], const double p2[3],
                                             const double u2[3]) {
  const double c[3] = {u1[1] * u2[2] - u1[2] * u2[1], u1[2] * u2[0] - u1[0] * u2[2], u1[0] * u2[1] - u1[1] * u2[0]};
  const double w[3] = {p2[0] - p1[0], p2[1] - p1[1], p2[2] - p1[2]};
  const double cross = std::sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
  const double dot = u1[0] * u2[0] + u1[1] * u2[1] + u1[2] * u2[2];
  double distance = 0.0;
  if (cross < 1e-9) {
    // Parallel: the part of w across the lines.
    const double along = w[0] * u1[0] + w[1] * u1[1] + w[2] * u1[2];
    distance = std::sqrt(std::max(0.0, w[0] * w[0] + w[1] * w[1] + w[2] * w[2] - along * along));
  } else {
    distance = std::abs(w[0] * c[0] + w[1] * c[1] + w[2] * c[2]) / cross;
  }
  return {distance, std::atan2(cross, dot)};
}

// The axes in a --candidate JSON document: consecutive lines a_i apart at alpha_i.
void expect_axes_match_the_geometry(const std::string& json) {
  const long long n = json_length(json, "$.axes");
  ASSERT_EQ(n, std::stoll(json_text(json, "$.joints")));
  for (long long k = 0; k < n; ++k) {
    const long long next = (k + 1) % n;
    double p1[3], u1[3], p2[3], u2[3];
    for (int i = 0; i < 3; ++i) {
      const std::string at = "[" + std::to_string(i) + "]";
      p1[i] = json_real(json, "$.axes[" + std::to_string(k) + "].point" + at);
      u1[i] = json_real(json, "$.axes[" + std::to_string(k) + "].direction" + at);
      p2[i] = json_real(json, "$.axes[" + std::to_string(next) + "].point" + at);
      u2[i] = json_real(json, "$.axes[" + std::to_string(next) + "].direction" + at);
    }
    const auto [distance, angle] = distance_and_angle(p1, u1, p2, u2);
    const std::string index = std::to_string(k + 1);
    EXPECT_NEAR(distance, json_real(json, "$.a" + index), 1e-8) << "axes " << k + 1 << ", " << next + 1;
    EXPECT_NEAR(angle * 180.0 / kPi, std::abs(json_real(json, "$.alpha" + index + "_deg")), 1e-7)
        << "axes " << k + 1 << ", " << next + 1;
  }
}

TEST_F(ReportCli, OneCandidateWholeWithItsJointAxes) {
  // The planar crank-rocker: axes parallel to z through the polygon of the links.
  testing::CommandResult r = report({"--candidate", "2", "--format", "json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  ASSERT_TRUE(json_valid(r.out)) << r.out;
  EXPECT_EQ(json_text(r.out, "$.candidate_id"), "2");
  EXPECT_EQ(json_text(r.out, "$.family"), "planar");
  EXPECT_EQ(json_text(r.out, "$.canonical_key"), "planar-1");
  EXPECT_EQ(json_length(r.out, "$.singular_values"), 3);
  EXPECT_FALSE(json_text(r.out, "$.grid_cell").empty());
  EXPECT_NEAR(json_real(r.out, "$.pose.input_deg"), 90.0, 1e-12);  // the default
  EXPECT_LT(json_real(r.out, "$.pose.closure_residual"), 1e-9);
  for (int k = 0; k < 4; ++k) {
    const std::string axis = "$.axes[" + std::to_string(k) + "]";
    EXPECT_EQ(json_text(r.out, axis + ".joint"), std::to_string(k + 1));
    EXPECT_NEAR(std::abs(json_real(r.out, axis + ".direction[2]")), 1.0, 1e-12);
    EXPECT_NEAR(json_real(r.out, axis + ".point[2]"), 0.0, 1e-12);
  }
  EXPECT_NEAR(json_real(r.out, "$.axes[0].theta_deg"), 90.0, 1e-12);
  // Joint 1 at 90 deg: link 1 leaves the origin along y.
  EXPECT_NEAR(json_real(r.out, "$.axes[1].point[0]"), 0.0, 1e-12);
  EXPECT_NEAR(json_real(r.out, "$.axes[1].point[1]"), json_real(r.out, "$.a1"), 1e-12);
  expect_axes_match_the_geometry(r.out);
  const std::string planar_json = r.out;

  // The Bennett loop: skew axes at the twists, a_i apart.
  r = report({"--candidate", "1", "--format", "json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  ASSERT_TRUE(json_valid(r.out)) << r.out;
  EXPECT_EQ(json_real(r.out, "$.d1"), kBennettOffsetNoise);
  expect_axes_match_the_geometry(r.out);

  // Another input angle.
  r = report({"--candidate", "2", "--format", "json", "--input-deg", "30"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NEAR(json_real(r.out, "$.pose.input_deg"), 30.0, 1e-9);
  EXPECT_NEAR(json_real(r.out, "$.axes[0].theta_deg"), 30.0, 1e-9);
  expect_axes_match_the_geometry(r.out);

  // csv: one row per joint, every column, the same values as the JSON.
  r = report({"--candidate", "2", "--format", "csv"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::vector<std::string> csv = lines_of(r.out);
  ASSERT_EQ(csv.size(), 5u);
  const std::vector<std::string> header = csv_fields(csv[0]);
  auto column = [&](const std::string& name) {
    return static_cast<size_t>(std::find(header.begin(), header.end(), name) - header.begin());
  };
  for (const char* name :
       {"candidate_id", "family", "E_mean", "a4", "canonical_key", "singular_values", "grid_cell", "input_deg", "joint",
        "theta_deg", "point_x", "point_y", "point_z", "direction_x", "direction_y", "direction_z"}) {
    EXPECT_LT(column(name), header.size()) << name;
  }
  for (int k = 0; k < 4; ++k) {
    const std::vector<std::string> f = csv_fields(csv[static_cast<size_t>(k + 1)]);
    ASSERT_EQ(f.size(), header.size()) << csv[static_cast<size_t>(k + 1)];
    EXPECT_EQ(f[column("joint")], std::to_string(k + 1));
    EXPECT_EQ(f[column("candidate_id")], "2");
    EXPECT_EQ(f[column("singular_values")], "[2,0.5,1e-13]");
    const std::string axis = "$.axes[" + std::to_string(k) + "]";
    EXPECT_EQ(to_number(f[column("point_x")]), json_real(planar_json, axis + ".point[0]"));
    EXPECT_EQ(to_number(f[column("direction_z")]), json_real(planar_json, axis + ".direction[2]"));
  }

  // Text and markdown: the same, for people; round-off as 0.
  r = report({"--candidate", "1"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("candidate 1\n"), std::string::npos);
  EXPECT_NE(r.out.find("canonical_key"), std::string::npos);
  EXPECT_NE(r.out.find("point (x, y, z)"), std::string::npos);
  // Joint 1's row of the joint table: d1 (stored -4.4e-16) shown as 0.
  const std::vector<std::string> text = lines_of(r.out);
  const auto joint1 =
      std::find_if(text.begin(), text.end(), [](const std::string& l) { return l.rfind("1 ", 0) == 0; });
  ASSERT_NE(joint1, text.end()) << r.out;
  EXPECT_EQ(joint1->find("e-"), std::string::npos) << *joint1;
  std::istringstream cells(*joint1);
  std::string joint, a, alpha, d;
  cells >> joint >> a >> alpha >> d;
  EXPECT_EQ(d, "0") << *joint1;
  r = report({"--candidate", "1", "--format", "markdown"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("| joint | theta [deg] | point x |"), std::string::npos);
  EXPECT_NE(r.out.find("| canonical_key | bennett-0 |"), std::string::npos);
}

TEST_F(ReportCli, APoseOutsideARockersRangeOrOfALoopThatDoesNotMove) {
  // Candidate 4's joint 1 rocks: its default pose lies in its range.
  testing::CommandResult r = report({"--candidate", "4", "--format", "json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  ASSERT_TRUE(json_valid(r.out)) << r.out;
  EXPECT_EQ(json_text(r.out, "$.pose.input_full_turn"), "0");
  const double lo = json_real(r.out, "$.pose.input_range_lo_deg");
  const double hi = json_real(r.out, "$.pose.input_range_hi_deg");
  const double at = json_real(r.out, "$.pose.input_deg");
  ASSERT_LT(lo, hi);
  const double image = at + 360.0 * std::round((0.5 * (lo + hi) - at) / 360.0);
  EXPECT_GE(image, lo);
  EXPECT_LE(image, hi);
  expect_axes_match_the_geometry(r.out);
  char beyond[32];
  std::snprintf(beyond, sizeof beyond, "%.0f", std::remainder(hi + 0.5 * (360.0 - (hi - lo)), 360.0));
  expect_refused({"--candidate", "4", "--input-deg", beyond}, {"--input-deg", "rocks in", beyond});

  // Candidate 3 does not move: shown whole, the pose and axes null, and said on stderr.
  r = report({"--candidate", "3", "--format", "json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  ASSERT_TRUE(json_valid(r.out)) << r.out;
  EXPECT_EQ(json_text(r.out, "$.family"), "unclassified");
  EXPECT_EQ(json_text(r.out, "$.pose.input_deg"), "");
  EXPECT_EQ(json_length(r.out, "$.axes"), 4);
  EXPECT_EQ(json_text(r.out, "$.axes[0].point"), "");
  EXPECT_EQ(json_text(r.out, "$.axes[0].joint"), "1");
  EXPECT_NE(r.err.find("does not move"), std::string::npos) << r.err;

  expect_refused({"--input-deg", "30"}, {"--input-deg"});
  expect_refused({"--candidate", "2", "--input-deg", "nan"}, {"--input-deg", "nan"});
  expect_refused({"--candidate", "2", "--limit", "3"}, {"--candidate"});
  expect_refused({"--candidate", "2", "--summary"}, {"--candidate"});
}

// Rows a damaged or hand-edited file may hold (a joint count beyond what is
// stored, a NULL length) are shown as they are, never crashed on.
TEST_F(ReportCli, ARowThatIsNoLoopIsShownNotCrashedOn) {
  const fs::path copy = dir_ / "edited.sqlite";
  fs::copy_file(database_, copy);
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open(copy.c_str(), &db), SQLITE_OK);
  ASSERT_EQ(sqlite3_exec(db,
                         "PRAGMA journal_mode = DELETE; UPDATE candidates SET joints = 99 WHERE candidate_id = 2; "
                         "UPDATE candidates SET a2 = NULL WHERE candidate_id = 1; "
                         "UPDATE candidates SET joints = -3 WHERE candidate_id = 4;",
                         nullptr, nullptr, nullptr),
            SQLITE_OK);
  sqlite3_close(db);
  for (const std::string format : {"table", "csv", "json", "markdown"}) {
    const testing::CommandResult list = run_command(kExecutable, "report", {copy.string(), "--format", format});
    EXPECT_EQ(list.exit_code, 0) << format << ": " << list.err;
    for (const char* id : {"1", "2", "4"}) {
      const testing::CommandResult r =
          run_command(kExecutable, "report", {copy.string(), "--candidate", id, "--format", format});
      EXPECT_EQ(r.exit_code, 0) << format << " " << id << ": " << r.err;
      EXPECT_NE(r.err.find("no pose"), std::string::npos) << format << " " << id << ": " << r.err;
      if (format == "json") {
        EXPECT_TRUE(json_valid(r.out)) << r.out;
      }
    }
  }
  const testing::CommandResult r = run_command(kExecutable, "report", {copy.string(), "--format", "json"});
  ASSERT_TRUE(json_valid(r.out));
  EXPECT_EQ(json_length(r.out), kCandidates);
}

// A candidate whose local dimension is unknown (its deformation Jacobian had
// an entry that is not finite) is stored with -1 and shown as unknown: "?/12"
// in the table and Markdown, empty in CSV, null in JSON, also by fingerprint.
TEST_F(ReportCli, ALocalDimensionStoredAsUnknownIsShownSo) {
  const fs::path path = dir_ / "unknown.sqlite";
  {
    ResultsDatabase db = ResultsDatabase::open(path.string(), DatabaseMode::write);
    const std::int64_t run = db.open_run(test_job("jobs/unknown-test.toml", 2)).run_id;
    const double s = std::sqrt(10.0);
    StartRecord unknown =
        verified(0, degrees({2 / s, 4 / s, 2 / s, 4 / s}, {30, 90, 30, 90}, {0, 0, 0, 0}), "bennett", 1e-25);
    unknown.candidate.local_dimension = -1;
    unknown.candidate.singular_values.clear();
    db.commit(run, {unknown});
  }
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open(path.c_str(), &db), SQLITE_OK);
  sqlite3_stmt* statement = nullptr;
  ASSERT_EQ(sqlite3_prepare_v2(db, "SELECT local_dimension FROM candidates", -1, &statement, nullptr), SQLITE_OK);
  ASSERT_EQ(sqlite3_step(statement), SQLITE_ROW);
  EXPECT_EQ(sqlite3_column_int(statement, 0), -1);
  sqlite3_finalize(statement);
  sqlite3_close(db);

  const auto report_of = [&](std::vector<std::string> args) {
    args.insert(args.begin(), path.string());
    const testing::CommandResult r = run_command(kExecutable, "report", args);
    EXPECT_EQ(r.exit_code, 0) << r.err;
    return r.out;
  };
  const std::vector<std::string> table = lines_of(report_of({}));
  ASSERT_GE(table.size(), 2u);
  EXPECT_NE(table[1].find(" ?/12 "), std::string::npos) << table[1];
  const std::vector<std::string> markdown = lines_of(report_of({"--format", "markdown"}));
  ASSERT_EQ(markdown.size(), 3u);
  EXPECT_NE(markdown[2].find("| ?/12 |"), std::string::npos) << markdown[2];
  const std::vector<std::string> csv = lines_of(report_of({"--format", "csv"}));
  ASSERT_EQ(csv.size(), 2u);
  const std::vector<std::string> names = csv_fields(csv[0]), values = csv_fields(csv[1]);
  const auto column = std::find(names.begin(), names.end(), "local_dimension");
  ASSERT_NE(column, names.end());
  ASSERT_EQ(values.size(), names.size());
  EXPECT_EQ(values[static_cast<size_t>(column - names.begin())], "");
  EXPECT_EQ(json_query("json_type", report_of({"--format", "json"}), "$[0].local_dimension"), "null");
  EXPECT_EQ(json_query("json_type", report_of({"--by-fingerprint", "--family", "bennett", "--format", "json"}),
                       "$[0].local_dimension"),
            "null");
}

// The cells of a Markdown table row ("| a | b |": "a", "b"), trimmed.
std::vector<std::string> markdown_cells(const std::string& line) {
  std::vector<std::string> cells = split(line, '|');
  std::vector<std::string> out;
  for (size_t i = 1; i + 1 < cells.size(); ++i) {
    std::string cell = cells[i];
    cell.erase(0, cell.find_first_not_of(' '));
    cell.erase(cell.find_last_not_of(' ') + 1);
    out.push_back(cell);
  }
  return out;
}

// People read the atlases: a Bennett loop stored in its canonical form (every
// twist negative) shows its twists positive, in the conventional form as the
// table does, in the parameter spread and the representative's parameters of
// both the Markdown atlas and the HTML page; the canonical values stay shown
// for the charts, which are drawn from them.
TEST_F(ReportCli, TheAtlasesShowABennettLoopWithPositiveTwists) {
  const fs::path path = dir_ / "bennett.sqlite";
  std::vector<LoopGeometry> stored;
  for (const double alpha : {30.0, 45.0}) {
    // a1 / sin(alpha1) = a2 / sin(alpha2): a Bennett loop.
    const double a1 = std::sin(alpha * kPi / 180.0);
    stored.push_back(canonical_form(degrees({a1, 1, a1, 1}, {alpha, 90, alpha, 90}, {0, 0, 0, 0})).geometry);
    for (int k = 0; k < 4; ++k) ASSERT_LT(stored.back().alpha[k], 0.0) << "the canonical twists are not negative";
  }
  {
    ResultsDatabase db = ResultsDatabase::open(path.string(), DatabaseMode::write);
    const std::int64_t run = db.open_run(test_job("jobs/bennett-test.toml", 2)).run_id;
    db.commit(run, {verified(0, stored[0], "bennett", 1e-25), verified(1, stored[1], "bennett", 1e-24)});
  }

  // The HTML page: the representative's first parameter table is the conventional form.
  const fs::path page = dir_ / "atlas.html";
  testing::CommandResult r = run_command(kExecutable, "report", {path.string(), "--html", page.string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string html = testing::read_file(page);
  const size_t table = html.find("<table class=\"data params");
  ASSERT_NE(table, std::string::npos);
  const std::string params = html.substr(table, html.find("</table>", table) - table);
  EXPECT_NE(html.rfind("conventional form, L = 1, twists in degrees", table), std::string::npos);
  int twists = 0;
  for (size_t at = params.find("<tr><td>"); at != std::string::npos; at = params.find("<tr><td>", at + 1)) {
    // <tr><td>joint</td><td>a</td><td>alpha</td><td>d</td></tr>: the third cell.
    size_t cell = at;
    for (int k = 0; k < 3; ++k) cell = params.find("<td>", cell) + 4;
    EXPECT_GT(to_number(params.substr(cell, params.find("</td>", cell) - cell)), 0.0) << params;
    ++twists;
  }
  EXPECT_EQ(twists, 4) << params;

  // The Markdown atlas: every twist of the spread and of the representative positive.
  if (std::system("command -v gnuplot >/dev/null 2>&1") != 0) GTEST_SKIP() << "no gnuplot for --atlas";
  const fs::path atlas = dir_ / "atlas";
  r = run_command(kExecutable, "report", {path.string(), "--atlas", atlas.string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string md = testing::read_file(atlas / "atlas.md");
  EXPECT_NE(md.find("Parameters (conventional form, L = 1, twists in degrees)"), std::string::npos) << md;
  int spread = 0;
  bool representative = false;
  for (const std::string& line : lines_of(md)) {
    if (line.rfind("| alpha", 0) == 0) {
      const std::vector<std::string> cells = markdown_cells(line);
      ASSERT_EQ(cells.size(), 4u) << line;
      for (size_t i = 1; i < 4; ++i) EXPECT_GT(to_number(cells[i]), 0.0) << line;
      ++spread;
    }
    // The representative's conventional parameters come first, then the canonical ones.
    if (line.rfind("alpha = ", 0) == 0 && !representative) {
      representative = true;
      for (const std::string& value : split(line.substr(8, line.find(" deg") - 8), ',')) {
        EXPECT_GT(to_number(value.substr(value.find_first_not_of(' '))), 0.0) << line;
      }
    }
  }
  EXPECT_EQ(spread, 4) << md;
  EXPECT_TRUE(representative) << md;
  // The canonical form, which the charts are drawn from, stays shown and says how its joints map.
  EXPECT_NE(md.find("canonical form"), std::string::npos) << md;
  EXPECT_NE(md.find("of the conventional form"), std::string::npos) << md;
}

// The number after `label` in `text` ("E_mean " in "..., E_mean 2.5e-30, ...", up to a
// comma, space or quote), NaN if none.
double number_after(const std::string& text, const std::string& label) {
  const size_t at = text.find(label);
  if (at == std::string::npos) return std::nan("");
  const size_t start = at + label.size();
  const size_t end = text.find_first_of(", \"", start);
  return to_number(text.substr(start, end == std::string::npos ? std::string::npos : end - start));
}

// The Markdown atlas `md` recomputes a zero cycle energy for its
// representative and says which joint drove it (`driven`).
void expect_atlas_drives_a_zero(const std::string& md, const std::string& driven) {
  const size_t recomputed = md.find("Cycle energy recomputed here: ");
  ASSERT_NE(recomputed, std::string::npos) << md;
  EXPECT_LT(number_after(md.substr(recomputed), "E_mean "), 1e-20) << md.substr(recomputed, 100);
  EXPECT_NE(md.find(driven), std::string::npos) << md;
}

// The stored full_turn and input range belong to the labelling the search
// verified a loop in; the canonical form's joint 1 may rock where another
// joint turns fully. Both atlases then drive a joint that turns fully (the
// first in the canonical numbering), over a full turn, and read a zero: a
// Bennett-triads 6R of the generic 6R search as stored in canonical form
// (joint 1 rocks on both circuits, joints 2 to 5 turn fully), and a planar
// crank-rocker stored with its rocking joint first (joints 2 and 3 turn fully),
// which the conventional form numbers otherwise. Each says which joint it
// drives, in both forms.
TEST_F(ReportCli, TheAtlasesDriveAJointThatTurnsFullyWhereJointOneRocks) {
  struct Case {
    std::string name, family;
    LoopGeometry stored;
  };
  const std::vector<Case> cases = {{"triads", "bennett_triads",
                                    degrees({0.5358164540989007, 0.8249169227425416, 0.7966869784893877,
                                             0.9128809676663918, 1.455081393381001, 1.150730041840033},
                                            {-27.47893022437578, -134.7338773702884, -33.19625118602273,
                                             -141.1443361773064, -90.38069489801955, -82.2900369250908},
                                            {9.580387347121904e-15, -5.299541570880196e-14, -0.247900690510372,
                                             5.712772204102417e-15, -4.808719565969614e-15, 0.247900690510327})},
                                   {"crank-rocker", "planar", degrees({3, 1, 3.2, 2.5}, {0, 0, 0, 0}, {0, 0, 0, 0})}};
  const bool gnuplot = std::system("command -v gnuplot >/dev/null 2>&1") == 0;
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    const int n = c.stored.joints();
    // The loop as the tracer sees it: joint 1 turns fully on no circuit, and
    // the first joint that turns fully on one is the one the atlases must drive.
    const VerificationSummary v = verify_motion(c.stored, nullptr);
    ASSERT_TRUE(v.verified);
    int first_crank = -1;
    for (int j = 0; j < n && first_crank < 0; ++j) {
      for (const Circuit& circuit : v.motion.circuits) {
        if (circuit.ranges[static_cast<size_t>(j)].crank()) first_crank = j;
      }
    }
    ASSERT_GT(first_crank, 0) << "joint 1 turns fully, or no joint does";
    const std::string joint = std::to_string(first_crank + 1), angle = "theta" + joint;
    // Which joint of the conventional form that is, and whether its angle runs the other way.
    JointVector probe = JointVector::Zero(n);
    probe[first_crank] = 1.0;
    const JointVector mapped = canonical_angles(conventional_form(c.stored), probe);
    int conventional = 0;
    for (int k = 1; k < n; ++k) {
      if (std::abs(mapped[k]) > std::abs(mapped[conventional])) conventional = k;
    }
    const std::string there = angle + " is the angle of joint " + std::to_string(conventional + 1) + " there" +
                              (mapped[conventional] < 0.0 ? " measured the other way" : ".");

    // Stored as the search stores it: a full turn (of its own input).
    const fs::path path = dir_ / (c.name + ".sqlite");
    {
      ResultsDatabase db = ResultsDatabase::open(path.string(), DatabaseMode::write);
      const std::int64_t run = db.open_run(test_job("jobs/" + c.name + "-test.toml", 2, n)).run_id;
      db.commit(run, {verified(0, c.stored, c.family, 1e-29)});
    }
    const std::string driven = "driven by its joint " + joint + " (" + angle +
                               "), the first of its joints that turns "
                               "fully on a circuit of the rigid loop (joint 1 does not)";

    const fs::path page = dir_ / (c.name + ".html");
    testing::CommandResult r = run_command(kExecutable, "report", {path.string(), "--html", page.string()});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const std::string html = testing::read_file(page);
    EXPECT_LT(number_after(html, "recomputed (360 samples, log axis), E_mean "), 1e-20);
    EXPECT_NE(html.find(driven), std::string::npos) << html.substr(html.find("drawn from the canonical form"), 600);
    EXPECT_NE(html.find(there), std::string::npos) << there;
    EXPECT_NE(html.find("input angle " + angle + " [deg]"), std::string::npos);
    EXPECT_NE(html.find("\"input\":\"" + angle + "\""), std::string::npos);

    if (!gnuplot) continue;
    const fs::path atlas = dir_ / (c.name + "-atlas");
    r = run_command(kExecutable, "report", {path.string(), "--atlas", atlas.string()});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const std::string md = testing::read_file(atlas / "atlas.md");
    expect_atlas_drives_a_zero(md, driven);
    EXPECT_NE(md.find(there), std::string::npos) << there << "\n" << md;
    const std::string svg = testing::read_file(atlas / (std::to_string(n) + "r_" + c.family + "_motion.svg"));
    EXPECT_NE(svg.find(">" + angle + " = 0 deg<"), std::string::npos) << svg.substr(0, 300);
  }
}

// Where no joint turns fully, joint 1 is driven over a window of its range
// on a circuit as the tracer finds it on the stored geometry, not over the
// stored input range, which belongs to the search's labelling: a planar
// triple rocker (joint 1 swings through [73.9, 286.1] deg) stored with the
// range of another of its joints, [-140.3, 140.3] deg.
TEST_F(ReportCli, TheAtlasesDriveJointOneOverItsTracedRangeWhereNoJointTurnsFully) {
  const fs::path path = dir_ / "rocker.sqlite";
  {
    ResultsDatabase db = ResultsDatabase::open(path.string(), DatabaseMode::write);
    const std::int64_t run = db.open_run(test_job("jobs/rocker-test.toml", 2)).run_id;
    StartRecord rocker = verified(0, degrees({2, 2.5, 3, 4.6}, {0, 0, 0, 0}, {0, 0, 0, 0}), "planar", 1e-29);
    rocker.candidate.full_turn = false;
    rocker.candidate.range_lo_deg = -140.264174;
    rocker.candidate.range_hi_deg = 140.264174;
    db.commit(run, {rocker});
  }
  const std::string driven =
      "driven by its joint 1 (theta1) over a window of its range on a circuit of the rigid loop (no joint turns fully)";
  const fs::path page = dir_ / "rocker.html";
  testing::CommandResult r = run_command(kExecutable, "report", {path.string(), "--html", page.string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string html = testing::read_file(page);
  EXPECT_LT(number_after(html, "recomputed (360 samples, log axis), E_mean "), 1e-20);
  EXPECT_NE(html.find(driven), std::string::npos);
  // The chart spans a window inside joint 1's range (an image of it whole
  // turns away), not the stored one.
  const size_t chart = html.find("<svg class=\"chart energy\"");
  ASSERT_NE(chart, std::string::npos);
  const double lo = number_after(html.substr(chart), "data-lo=\""), hi = number_after(html.substr(chart), "data-hi=\"");
  const double turns = 360.0 * std::round((180.0 - 0.5 * (lo + hi)) / 360.0);
  EXPECT_GT(hi - lo, 90.0) << lo << " " << hi;
  EXPECT_GT(lo + turns, 73.9) << lo;
  EXPECT_LT(hi + turns, 286.1) << hi;

  if (std::system("command -v gnuplot >/dev/null 2>&1") != 0) GTEST_SKIP() << "no gnuplot for --atlas";
  const fs::path atlas = dir_ / "rocker-atlas";
  r = run_command(kExecutable, "report", {path.string(), "--atlas", atlas.string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  expect_atlas_drives_a_zero(testing::read_file(atlas / "atlas.md"), driven);
}

}  // namespace
}  // namespace loopfarm
