// `loopfarm bonds`, run as a user runs it: one geometry (text and JSON, a
// loop that does not move), and a results database built here with the
// library, whose candidates are traced, measured and grouped into classes of
// equal fingerprint without the file changing. LOOPFARM_EXECUTABLE is the
// built binary.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "command_test_support.hpp"
#include "loopfarm/core/constructions.hpp"
#include "loopfarm/farm/results_database.hpp"

namespace loopfarm {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

const std::string kExecutable = LOOPFARM_EXECUTABLE;
constexpr double kPi = 3.14159265358979323846;

class BondsCli : public testing::CommandTest {
 protected:
  BondsCli() : CommandTest("loopfarm-bonds-test") {}
  testing::CommandResult bonds(const std::vector<std::string>& args) { return run_command(kExecutable, "bonds", args); }
};

// |<u, v>| / (|u| |v|).
double alignment(const std::vector<double>& u, const std::vector<double>& v) {
  double uv = 0.0, uu = 0.0, vv = 0.0;
  for (size_t k = 0; k < u.size() && k < v.size(); ++k) {
    uv += u[k] * v[k];
    uu += u[k] * u[k];
    vv += v[k] * v[k];
  }
  return std::abs(uv) / std::sqrt(uu * vv);
}

// The paper's Bennett loop (30, 90 deg twists, asymmetric setup): every pair
// (1, 1), joints 1 and 2 with tan(theta1 / 2) tan(theta2 / 2) = K =
// sin(60 deg) / sin(30 deg) (bond_relations_test.cpp checks the form by closing the loop).
TEST_F(BondsCli, ABennettLoopHasEveryPairMoebiusRelated) {
  testing::CommandResult r = bonds({"--a", "2,4,2,4", "--alpha-deg", "30,90,30,90"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(r.err.empty()) << r.err;
  EXPECT_NE(r.out.find("fingerprint             4R/4 11 11 11 11 11 11\n"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("1-2   related    (1, 1)"), std::string::npos) << r.out;

  r = bonds({"--a", "2,4,2,4", "--alpha-deg", "30,90,30,90", "--json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json j = json::parse(r.out);
  EXPECT_EQ(j["fingerprint"], "4R/4 11 11 11 11 11 11");
  EXPECT_EQ(j["verified"], true);
  EXPECT_EQ(j["rows"], 125);
  ASSERT_EQ(j["pairs"].size(), 6u);
  for (const json& p : j["pairs"]) {
    EXPECT_EQ(p["status"], "related");
    EXPECT_EQ(p["p"], 1);
    EXPECT_EQ(p["q"], 1);
    EXPECT_LT(p["ratio"].get<double>(), 1e-11);
  }
  EXPECT_EQ(j["pairs"][0]["joints"], json::array({1, 2}));
  const double K = std::sin(kPi / 3) / std::sin(kPi / 6);
  EXPECT_NEAR(alignment(j["pairs"][0]["coefficients"].get<std::vector<double>>(), {-K, 0, 0, 1}), 1.0, 1e-10);
  EXPECT_EQ(j["joints"].size(), 4u);
  EXPECT_EQ(j["joints"][0]["frozen"], false);
}

// A planar crank-rocker's input and output: Freudenstein's (2, 2); with
// degrees up to 1 only, none.
TEST_F(BondsCli, APlanarFourBarsInputAndOutputHaveBidegreeTwoTwo) {
  testing::CommandResult r = bonds({"--a", "1,3,2.5,3.2", "--alpha-deg", "0,0,0,0", "--json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  json j = json::parse(r.out);
  EXPECT_EQ(j["pairs"][2]["joints"], json::array({1, 4}));
  EXPECT_EQ(j["pairs"][2]["status"], "related");
  EXPECT_EQ(j["pairs"][2]["p"], 2);
  EXPECT_EQ(j["pairs"][2]["q"], 2);
  r = bonds({"--a", "1,3,2.5,3.2", "--alpha-deg", "0,0,0,0", "--json", "--max-degree", "1"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  j = json::parse(r.out);
  EXPECT_EQ(j["pairs"][2]["status"], "none");
  EXPECT_TRUE(j["pairs"][2]["p"].is_null());
  EXPECT_EQ(j["rows"], 20);
}

TEST_F(BondsCli, ALoopThatDoesNotMoveHasNoRelationsAndExitsWithFour) {
  testing::CommandResult r = bonds({"--a", "1,2,3,2.5", "--alpha-deg", "20,70,40,110", "--d=0.1,-0.3,0.2,0"});
  EXPECT_EQ(r.exit_code, 4) << r.err;
  EXPECT_NE(r.out.find("not verified"), std::string::npos) << r.out;
  r = bonds({"--a", "1,2,3,2.5", "--alpha-deg", "20,70,40,110", "--d=0.1,-0.3,0.2,0", "--json"});
  EXPECT_EQ(r.exit_code, 4) << r.err;
  EXPECT_EQ(json::parse(r.out)["verified"], false);
}

TEST_F(BondsCli, BadInputIsRefusedNamingTheFlag) {
  struct Case {
    std::vector<std::string> args;
    std::string expected;
  };
  const std::vector<Case> cases = {
      {{"--a", "2,4,2,4", "--alpha-deg", "30,90,30,90", "--max-degree", "9"}, "--max-degree: got 9"},
      {{"--a", "2,4,2,4", "--alpha-deg", "30,90,30,90", "--tolerance", "1"}, "--tolerance: got 1"},
      {{"--a", "2,4,2,4", "--alpha-deg", "30,90,30,90", "--rows", "74"}, "--rows: got 74"},
      {{"--a", "2,4,2,4", "--alpha-deg", "30,90,30,90", "--frozen-travel-deg", "-1"}, "--frozen-travel-deg"},
      {{"--a", "2,4,2,4", "--alpha-deg", "30,90,30,90", "--family", "bennett"}, "--family: selects candidates"},
      {{"{dir}/x.sqlite", "--a", "2,4,2,4", "--alpha-deg", "30,90,30,90"}, "DB: give either"},
      {{"{dir}/missing.sqlite"}, "missing.sqlite"},
      {{}, "--a: missing"},
  };
  for (const Case& c : cases) {
    const testing::CommandResult r = bonds(c.args);
    EXPECT_EQ(r.exit_code, 2) << c.expected << ": " << r.err;
    EXPECT_NE(r.err.find(c.expected), std::string::npos) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_TRUE(r.out.empty()) << r.out;
  }
  EXPECT_FALSE(fs::exists(dir_ / "missing.sqlite"));
}

// --- a database -------------------------------------------------------------------

StartRecord verified(std::uint64_t index, const LoopGeometry& geometry, const std::string& family) {
  StartRecord r;
  r.index = index;
  r.status = "stopval_reached";
  r.E_mean = 1e-28;
  r.E_max = 3e-28;
  r.objective = 1e-28;
  r.evaluations = 40;
  r.seconds = 0.25;
  r.zero = true;
  r.verified = true;
  r.final_geometry = geometry;
  r.final_angles = JointVector::Zero(geometry.joints());
  CandidateRecord& c = r.candidate;
  c.family = family;
  c.setup = "none";
  c.detail = family + " loop";
  c.family_residual = 1e-14;
  c.bennett_residual = 1.0;
  c.planar_residual = 0.5;
  c.spherical_residual = 0.75;
  c.trivial_residual = std::numeric_limits<double>::infinity();
  c.rigid_residual = 1e-15;
  c.full_turn = true;
  c.range_lo_deg = -180.0;
  c.range_hi_deg = 180.0;
  c.local_dimension = 9;
  c.free_parameters = 18;
  c.singular_values = {2.0, 0.5, 1e-13};
  c.canonical_key = family + "-" + std::to_string(index);
  c.canonical_geometry = geometry;
  return r;
}

LoopGeometry line_symmetric_bricard(double d1) {
  return LoopGeometry::from_degrees(std::vector<double>{1, 1.7, 0.8, 1, 1.7, 0.8},
                                    std::vector<double>{51.566, 120.321, -34.377, 51.566, 120.321, -34.377},
                                    std::vector<double>{d1, 0.3, -0.5, d1, 0.3, -0.5});
}

// Two line-symmetric Bricard loops and Waldron's hybrid stored as
// unclassified (a family is only a label here), a third Bricard loop as
// bricard_line_symmetric.
void build_database(const std::string& path) {
  ResultsDatabase db = ResultsDatabase::open(path, DatabaseMode::write);
  RunIdentity id;
  id.job_path = "jobs/bonds-test.toml";
  id.job_text = "[search]\nstarts = 10\n";
  id.seed = 1;
  id.starts = 10;
  id.joints = 6;
  id.zero_threshold = 1e-20;
  id.report_threshold = 1e-6;
  const std::int64_t run = db.open_run(id).run_id;
  db.commit(run, {verified(0, line_symmetric_bricard(0.4), "unclassified"),
                  verified(1, waldron_hybrid_6r(WaldronHybrid6R{}, 1.0).geometry, "unclassified"),
                  verified(2, line_symmetric_bricard(0.45), "unclassified"),
                  verified(3, line_symmetric_bricard(0.35), "bricard_line_symmetric")});
}

TEST_F(BondsCli, ADatabasesCandidatesFallIntoClassesByFingerprint) {
  const std::string db = (dir_ / "results.sqlite").string();
  build_database(db);
  const std::string before = testing::read_file(db);
  const std::vector<std::string> files = this->files();

  testing::CommandResult r = bonds({db, "--json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json j = json::parse(r.out);
  EXPECT_EQ(j["family"], "unclassified");
  ASSERT_EQ(j["candidates"].size(), 3u);
  for (const json& c : j["candidates"]) {
    ASSERT_TRUE(c["fingerprint"].is_string()) << c.dump();
    EXPECT_EQ(c["verified"], true);
    EXPECT_EQ(c["family"], "unclassified");
  }
  // Waldron's hybrid: every pair (1, 1) by its construction.
  const std::string all_moebius = "6R/4 11 11 11 11 11 11 11 11 11 11 11 11 11 11 11";
  int moebius = 0;
  for (const json& c : j["candidates"]) moebius += c["fingerprint"] == all_moebius;
  EXPECT_EQ(moebius, 1);
  ASSERT_EQ(j["classes"].size(), 2u) << r.out;
  EXPECT_EQ(j["classes"][0]["count"], 2);
  EXPECT_EQ(j["classes"][1]["count"], 1);
  EXPECT_EQ(j["classes"][1]["fingerprint"], all_moebius);
  // The Bricard class: opposite joints equal, (1, 1) at pairs 1-4, 2-5, 3-6.
  const std::string fingerprint = j["classes"][0]["fingerprint"];
  EXPECT_NE(fingerprint, all_moebius);

  // Text: a line per candidate, then the classes.
  r = bonds({db});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("classes by fingerprint (3 of 3 candidates measured)"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find(fingerprint), std::string::npos);

  // Another family, and a limit.
  r = bonds({db, "--family", "bricard_line_symmetric", "--json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json other = json::parse(r.out);
  ASSERT_EQ(other["candidates"].size(), 1u);
  EXPECT_EQ(other["candidates"][0]["fingerprint"], fingerprint);
  r = bonds({db, "--limit", "1", "--json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(json::parse(r.out)["candidates"].size(), 1u);

  // Refused: a family the database does not hold, a negative limit.
  r = bonds({db, "--family", "myard"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--family: no myard candidate"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("unclassified (3)"), std::string::npos) << r.err;
  r = bonds({db, "--limit", "-1"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--limit: got -1"), std::string::npos) << r.err;

  // Read-only: the file as it was, nothing added beside it.
  EXPECT_EQ(testing::read_file(db), before);
  EXPECT_EQ(this->files(), files);
}

}  // namespace
}  // namespace loopfarm
