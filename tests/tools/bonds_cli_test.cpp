// `loopfarm bonds`, run as a user runs it: one geometry (text and JSON, a
// loop that does not move), and a results database built here with the
// library, whose candidates are traced, measured and grouped into classes of
// equal fingerprint without the file changing; with --store, the fingerprints
// written with their candidates (compared with the fingerprints measured here
// on the stored geometries) and grouped by `loopfarm report --by-fingerprint`,
// also in a database of schema version 4. LOOPFARM_EXECUTABLE is the built
// binary, LOOPFARM_SOURCE_DIR the source tree (for the fixture).
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "command_test_support.hpp"
#include "loopfarm/core/constructions.hpp"
#include "loopfarm/farm/candidate_pose.hpp"
#include "loopfarm/farm/results_database.hpp"
#include "loopfarm/search/bond_relations.hpp"
#include "loopfarm/search/verify.hpp"

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

// --- stored fingerprints ------------------------------------------------------------

// The fingerprint of a stored candidate's geometry, measured here: its motion
// traced as loopfarm verify traces it, the relations on the circuit reported.
std::string measured_fingerprint(const CandidateRow& row) {
  const LoopGeometry geometry = candidate_geometry(row);
  const VerificationSummary motion = verify_motion(geometry, nullptr, VerificationOptions{});
  if (!motion.verified || static_cast<int>(motion.joint_angles.size()) < BondOptions{}.minimum_rows()) return "";
  return bond_relations(geometry, motion.joint_angles).fingerprint;
}

// Every candidate's stored fingerprint, by id ("NULL" when none is stored).
std::map<long long, std::string> stored_fingerprints(const std::string& path) {
  std::map<long long, std::string> out;
  ResultsDatabase db = ResultsDatabase::open(path, DatabaseMode::read);
  for (const CandidateRow& r : db.candidates({})) out[r.id] = r.bond_fingerprint.value_or("NULL");
  return out;
}

TEST_F(BondsCli, StoreWritesEachFingerprintWithItsCandidateAndTheReportGroupsThem) {
  const std::string db = (dir_ / "results.sqlite").string();
  build_database(db);

  testing::CommandResult r = bonds({db, "--store", "--json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  json j = json::parse(r.out);
  EXPECT_EQ(j["stored"]["written"], 3);
  EXPECT_EQ(j["stored"]["skipped"], 0);
  EXPECT_EQ(j["stored"]["upgraded"], false);
  ASSERT_EQ(j["candidates"].size(), 3u);
  for (const json& c : j["candidates"]) EXPECT_TRUE(c["stored_fingerprint"].is_null()) << c.dump();

  // What is stored is the fingerprint of the candidate's stored geometry,
  // measured here; the candidate of another family is left unmeasured.
  std::map<long long, std::string> stored = stored_fingerprints(db);
  {
    ResultsDatabase read = ResultsDatabase::open(db, DatabaseMode::read);
    for (const CandidateRow& row : read.candidates({})) {
      if (row.family == "unclassified") {
        EXPECT_EQ(stored[row.id], measured_fingerprint(row)) << row.id;
        EXPECT_NE(stored[row.id], "") << row.id;
      } else {
        EXPECT_EQ(stored[row.id], "NULL") << row.id;
      }
    }
  }

  // Again: nothing left to measure, the file as it was; --recompute measures again.
  const std::string after_store = testing::read_file(db);
  r = bonds({db, "--store"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("have their bond fingerprints stored already"), std::string::npos) << r.out;
  EXPECT_EQ(testing::read_file(db), after_store);
  r = bonds({db, "--store", "--recompute"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("stored 3 bond fingerprints in " + db), std::string::npos) << r.out;
  EXPECT_EQ(stored_fingerprints(db), stored);
  // Every family: only the one not stored yet is measured.
  r = bonds({db, "--store", "--family", "all", "--json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  j = json::parse(r.out);
  ASSERT_EQ(j["candidates"].size(), 1u);
  EXPECT_EQ(j["candidates"][0]["family"], "bricard_line_symmetric");
  EXPECT_EQ(j["stored"]["written"], 1);

  // Read-only measuring shows what is stored beside what it measures.
  r = bonds({db, "--json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  for (const json& c : json::parse(r.out)["candidates"]) EXPECT_EQ(c["stored_fingerprint"], c["fingerprint"]);

  // The report: the unclassified candidates by stored fingerprint.
  r = run_command(kExecutable, "report", {db, "--by-fingerprint", "--json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  j = json::parse(r.out);
  ASSERT_EQ(j.size(), 2u) << r.out;
  EXPECT_EQ(j[0]["candidates"], 2);
  EXPECT_EQ(j[0]["hits"], 2);
  EXPECT_EQ(j[0]["family"], "unclassified");
  EXPECT_EQ(j[0]["local_dimension"], 9);
  EXPECT_EQ(j[0]["fingerprint"], stored[j[0]["representative"].get<long long>()]);
  EXPECT_EQ(j[1]["candidates"], 1);
  EXPECT_EQ(j[1]["fingerprint"], "6R/4 11 11 11 11 11 11 11 11 11 11 11 11 11 11 11");
  r = run_command(kExecutable, "report", {db, "--by-fingerprint"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("bond fingerprints of the unclassified candidates (3, 3 measured)"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find(j[0]["fingerprint"].get<std::string>()), std::string::npos) << r.out;
  r = run_command(kExecutable, "report", {db, "--by-fingerprint", "--family", "all", "--format", "csv"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(std::count(r.out.begin(), r.out.end(), '\n'), 3) << r.out;  // header, two classes (the Bricard three)
  EXPECT_EQ(r.out.rfind("fingerprint,candidates,hits,representative,family,local_dimension", 0), 0u) << r.out;
}

TEST_F(BondsCli, StoreFillsAVersion4DatabaseAndUpgradesIt) {
  const std::string db = (dir_ / "v4.sqlite").string();
  fs::copy_file(std::string(LOOPFARM_SOURCE_DIR) + "/tests/farm/fixtures/schema-v4.sqlite", db);
  // Not measured yet: the report says so.
  testing::CommandResult r = run_command(kExecutable, "report", {db, "--by-fingerprint", "--family", "all"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("(not measured)"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("--store --family all measures"), std::string::npos) << r.out;

  r = bonds({db, "--store", "--family", "all", "--json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json j = json::parse(r.out);
  EXPECT_EQ(j["stored"]["upgraded"], true);
  // The upgrade keys its candidates with parallel axes again (schema version
  // 7) and merges two planar rows that name one linkage: the fingerprint
  // measured on the row merged away is skipped.
  EXPECT_EQ(j["stored"]["skipped"], 1);
  const std::map<long long, std::string> stored = stored_fingerprints(db);
  EXPECT_EQ(j["stored"]["written"], stored.size());
  ResultsDatabase read = ResultsDatabase::open(db, DatabaseMode::read);
  int with_fingerprint = 0;
  for (const CandidateRow& row : read.candidates({})) {
    EXPECT_EQ(stored.at(row.id), measured_fingerprint(row)) << row.id;
    with_fingerprint += !stored.at(row.id).empty();
  }
  EXPECT_GE(with_fingerprint, 2);
}

TEST_F(BondsCli, StoreIsRefusedWhereItMustNotWrite) {
  const std::string db = (dir_ / "results.sqlite").string();
  build_database(db);
  const std::string before = testing::read_file(db);
  struct Case {
    std::vector<std::string> args;
    std::string expected;
  };
  const std::vector<Case> cases = {
      {{db, "--store", "--tolerance", "1e-8"}, "--tolerance: --store stores fingerprints measured with the default"},
      {{db, "--store", "--steps", "1440"}, "--steps: --store"},
      {{db, "--recompute"}, "--recompute: measures again"},
      {{"--a", "2,4,2,4", "--alpha-deg", "30,90,30,90", "--store"}, "--store: stores the fingerprints"},
      {{"{dir}/missing.sqlite", "--store"}, "missing.sqlite: no such file"},
      {{db, "--store", "--family", "everything"}, "--family: got \"everything\"; expected one of bennett,"},
  };
  for (const Case& c : cases) {
    const testing::CommandResult r = bonds(c.args);
    EXPECT_EQ(r.exit_code, 2) << c.expected << ": " << r.err;
    EXPECT_NE(r.err.find(c.expected), std::string::npos) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_TRUE(r.out.empty()) << r.out;
  }
  EXPECT_FALSE(fs::exists(dir_ / "missing.sqlite"));
  // A read-only file, refused before anything is measured.
  fs::permissions(db, fs::perms::owner_read | fs::perms::group_read | fs::perms::others_read);
  const testing::CommandResult r = bonds({db, "--store"});
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find(db + ": a read-only file"), std::string::npos) << r.err;
  EXPECT_TRUE(r.out.empty()) << r.out;
  EXPECT_EQ(testing::read_file(db), before);
  EXPECT_EQ(files(), (std::vector<std::string>{"results.sqlite"}));
}

}  // namespace
}  // namespace loopfarm
