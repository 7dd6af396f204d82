// `loopfarm groundtruth`, run as a user runs it: its CSV and JSON against the
// library's generate_ground_truth, --out written whole or not at all, and
// bad options refused with exit code 2 and one line naming the flag.
// LOOPFARM_EXECUTABLE is the path of the built binary.
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "command_test_support.hpp"
#include "loopfarm/study/ground_truth.hpp"

namespace loopfarm {
namespace {

namespace fs = std::filesystem;
using testing::read_file;
using testing::split;

const std::string kExecutable = LOOPFARM_EXECUTABLE;
constexpr double kPi = 3.14159265358979323846;

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

// The whole text as a double, or NaN if it is not exactly one number.
double to_number(const std::string& text) {
  if (text.empty()) return std::nan("");
  char* end = nullptr;
  const double value = std::strtod(text.c_str(), &end);
  return end == text.c_str() + text.size() ? value : std::nan("");
}

size_t count_of(const std::string& text, const std::string& needle) {
  size_t count = 0;
  for (size_t at = text.find(needle); at != std::string::npos; at = text.find(needle, at + 1)) ++count;
  return count;
}

using Result = testing::CommandResult;

class GroundTruthCli : public testing::CommandTest {
 protected:
  GroundTruthCli() : CommandTest("loopfarm-groundtruth-test") {}
  // Runs `loopfarm groundtruth` with `args` ("{dir}" replaced by the test's directory).
  Result run(const std::vector<std::string>& args) { return run_command(kExecutable, "groundtruth", args); }
};

GroundTruthOptions options_of_the_runs() {
  GroundTruthOptions options;
  options.seed = 5;
  options.cases_per_family = 2;
  options.generic_loops = 3;
  options.relative_perturbations = {1e-3, 1e-6};
  return options;
}
const std::vector<std::string> kRunArguments = {"--seed",    "5", "--per-family",    "2",
                                                "--generic", "3", "--perturbations", "1e-3,1e-6"};

std::vector<std::string> with(std::vector<std::string> args, const std::vector<std::string>& more) {
  args.insert(args.end(), more.begin(), more.end());
  return args;
}

TEST_F(GroundTruthCli, CsvHasOneRowPerCaseWithTheLibrarysValues) {
  const Result result = run(with(kRunArguments, {"--format", "csv"}));
  ASSERT_EQ(result.exit_code, 0) << result.err;
  EXPECT_EQ(result.err, "");
  const std::vector<std::string> lines = lines_of(result.out);
  const std::vector<GroundTruthCase> cases = generate_ground_truth(options_of_the_runs());
  ASSERT_EQ(lines.size(), cases.size() + 1);
  EXPECT_EQ(lines[0],
            "id,family,setup,movable,full_turn,parent,perturbed_parameter,relative_perturbation,pose_residual,"
            "a1,a2,a3,a4,alpha1_deg,alpha2_deg,alpha3_deg,alpha4_deg,d1,d2,d3,d4,"
            "theta1_deg,theta2_deg,theta3_deg,theta4_deg");
  for (size_t i = 0; i < cases.size(); ++i) {
    const GroundTruthCase& c = cases[i];
    SCOPED_TRACE(c.id);
    const std::vector<std::string> f = split(lines[i + 1], ',');
    ASSERT_EQ(f.size(), 25u);
    EXPECT_EQ(f[0], c.id);
    EXPECT_EQ(f[1], to_string(c.family));
    EXPECT_EQ(f[2], to_string(c.setup));
    EXPECT_EQ(f[3], c.movable ? "1" : "0");
    EXPECT_EQ(f[4], c.full_turn ? "1" : "0");
    EXPECT_EQ(f[5], c.parent);
    EXPECT_EQ(f[6], c.perturbed_parameter);
    if (c.parent.empty()) {
      EXPECT_EQ(f[7], "");
    } else {
      EXPECT_EQ(to_number(f[7]), c.relative_perturbation);
    }
    EXPECT_EQ(to_number(f[8]), c.pose_residual);
    for (int j = 0; j < 4; ++j) {
      // %.17g: lengths read back exactly, angles to the last bit of the conversion.
      EXPECT_EQ(to_number(f[9 + j]), c.geometry.a[j]);
      EXPECT_NEAR(to_number(f[13 + j]) * kPi / 180.0, c.geometry.alpha[j], 1e-15);
      EXPECT_EQ(to_number(f[17 + j]), c.geometry.d[j]);
      EXPECT_NEAR(to_number(f[21 + j]) * kPi / 180.0, c.pose[j], 1e-15);
    }
  }
}

TEST_F(GroundTruthCli, CsvFileGetsTheSameBytesAsStandardOutputAndRunsAreIdentical) {
  const Result to_stdout = run(with(kRunArguments, {"--format", "csv"}));
  ASSERT_EQ(to_stdout.exit_code, 0) << to_stdout.err;
  // --csv - is standard output, in place of the summary.
  const Result dash = run(with(kRunArguments, {"--csv", "-"}));
  ASSERT_EQ(dash.exit_code, 0) << dash.err;
  EXPECT_EQ(dash.out, to_stdout.out);
  std::vector<std::string> args = with(kRunArguments, {"--csv", "{dir}/set.csv"});
  const Result first = run(args);
  ASSERT_EQ(first.exit_code, 0) << first.err;
  EXPECT_EQ(first.out, "");
  const size_t count = generate_ground_truth(options_of_the_runs()).size();
  EXPECT_NE(first.err.find("wrote " + std::to_string(count) + " cases"), std::string::npos) << first.err;
  const std::string written = read_file(dir_ / "set.csv");
  EXPECT_EQ(written, to_stdout.out);
  // A second run replaces the file with the same bytes; no temporary file stays.
  ASSERT_EQ(run(args).exit_code, 0);
  EXPECT_EQ(read_file(dir_ / "set.csv"), written);
  EXPECT_EQ(files(), std::vector<std::string>{"set.csv"});
}

TEST_F(GroundTruthCli, JsonHasOneObjectPerCase) {
  std::vector<std::string> args = kRunArguments;
  args.insert(args.end(), {"--format", "json"});
  const Result result = run(args);
  ASSERT_EQ(result.exit_code, 0) << result.err;
  const std::vector<GroundTruthCase> cases = generate_ground_truth(options_of_the_runs());
  const std::vector<std::string> lines = lines_of(result.out);
  ASSERT_EQ(lines.size(), cases.size() + 2);
  EXPECT_EQ(lines.front(), "[");
  EXPECT_EQ(lines.back(), "]");
  EXPECT_EQ(count_of(result.out, "{\"id\":"), cases.size());
  for (size_t i = 0; i < cases.size(); ++i) {
    const GroundTruthCase& c = cases[i];
    const std::string& line = lines[i + 1];
    SCOPED_TRACE(line);
    EXPECT_EQ(line.rfind("{\"id\":\"" + c.id + "\",\"family\":\"" + to_string(c.family) + "\"", 0), 0u);
    EXPECT_NE(line.find(c.movable ? "\"movable\":true" : "\"movable\":false"), std::string::npos);
    EXPECT_NE(line.find(c.parent.empty() ? "\"parent\":null" : "\"parent\":\"" + c.parent + "\""), std::string::npos);
    for (const char* key : {"\"geometry\":{\"a\":[", "\"alpha_deg\":[", "\"d\":[", "\"theta_deg\":["}) {
      EXPECT_NE(line.find(key), std::string::npos) << key;
    }
    EXPECT_EQ(line.back(), i + 1 < cases.size() ? ',' : '}');
  }
}

TEST_F(GroundTruthCli, TextCountsTheCasesAndMarkdownListsThem) {
  const std::vector<GroundTruthCase> cases = generate_ground_truth(options_of_the_runs());
  size_t movable = 0;
  for (const GroundTruthCase& c : cases) movable += c.movable ? 1 : 0;
  const Result text = run(kRunArguments);
  ASSERT_EQ(text.exit_code, 0) << text.err;
  EXPECT_NE(text.out.find("ground truth: " + std::to_string(cases.size()) + " cases, " + std::to_string(movable) +
                          " movable, " + std::to_string(cases.size() - movable) + " rigid"),
            std::string::npos)
      << text.out;
  const Result markdown = run(with(kRunArguments, {"--format", "markdown"}));
  ASSERT_EQ(markdown.exit_code, 0) << markdown.err;
  const std::vector<std::string> lines = lines_of(markdown.out);
  ASSERT_EQ(lines.size(), cases.size() + 2);
  EXPECT_EQ(lines[0].rfind("| id | family | setup | movable |", 0), 0u) << lines[0];
  for (size_t i = 0; i < cases.size(); ++i) {
    EXPECT_EQ(lines[i + 2].rfind("| " + cases[i].id + " | ", 0), 0u) << lines[i + 2];
    EXPECT_NE(lines[i + 2].find(cases[i].movable ? " | yes | " : " | no | "), std::string::npos) << lines[i + 2];
  }
}

TEST_F(GroundTruthCli, PerturbationsNoneGivesTheMovableCasesOnly) {
  const Result result = run({"--per-family", "1", "--generic", "0", "--perturbations", "none", "--format", "csv"});
  ASSERT_EQ(result.exit_code, 0) << result.err;
  const std::vector<std::string> lines = lines_of(result.out);
  ASSERT_EQ(lines.size(), 1u + 5u);  // Bennett in both setups, planar, spherical, trivial
  for (size_t i = 1; i < lines.size(); ++i) EXPECT_EQ(split(lines[i], ',')[3], "1") << lines[i];
}

struct BadOption {
  std::string name;
  std::vector<std::string> args;
  std::string flag;  // must appear in the message
};

std::ostream& operator<<(std::ostream& out, const BadOption& bad) { return out << bad.name; }

class GroundTruthCliBadOption : public GroundTruthCli, public ::testing::WithParamInterface<BadOption> {};

TEST_P(GroundTruthCliBadOption, ExitsWithCode2AndOneLineNamingTheFlag) {
  const BadOption& bad = GetParam();
  // A previous file at the --csv target must survive the failed run.
  const std::string sentinel = "id,family\nkept,bennett\n";
  std::ofstream(dir_ / "keep.csv") << sentinel;
  std::vector<std::string> args = bad.args;
  if (bad.flag != "--csv") args.insert(args.end(), {"--csv", "{dir}/keep.csv"});

  const Result result = run(args);

  EXPECT_EQ(result.exit_code, 2) << result.err;
  EXPECT_EQ(result.out, "");
  const std::vector<std::string> lines = lines_of(result.err);
  ASSERT_EQ(lines.size(), 1u) << result.err;
  EXPECT_EQ(lines[0].rfind("loopfarm groundtruth: ", 0), 0u) << lines[0];
  EXPECT_NE(lines[0].find(bad.flag), std::string::npos) << lines[0];
  EXPECT_EQ(read_file(dir_ / "keep.csv"), sentinel);
  EXPECT_EQ(files(), std::vector<std::string>{"keep.csv"});
}

INSTANTIATE_TEST_SUITE_P(
    BadOptions, GroundTruthCliBadOption,
    ::testing::Values(BadOption{"NegativeCount", {"--per-family", "-1"}, "--per-family"},
                      BadOption{"CountNotANumber", {"--per-family", "many"}, "--per-family"},
                      BadOption{"TooManyGeneric", {"--generic", "1000001"}, "--generic"},
                      BadOption{"NegativeSeed", {"--seed", "-3"}, "--seed"},
                      BadOption{"SeedNotAnInteger", {"--seed", "1.5"}, "--seed"},
                      BadOption{"PerturbationZero", {"--perturbations", "1e-3,0"}, "--perturbations"},
                      BadOption{"PerturbationOne", {"--perturbations", "1"}, "--perturbations"},
                      BadOption{"PerturbationTwice", {"--perturbations", "1e-3,1e-3"}, "--perturbations"},
                      BadOption{"PerturbationsAlike", {"--perturbations", "1e-3,1.0000000001e-3"}, "--perturbations"},
                      BadOption{"PerturbationNotANumber", {"--perturbations", "1e-3,x"}, "--perturbations"},
                      BadOption{"UnknownFormat", {"--format", "xml"}, "--format"},
                      BadOption{"CsvIsADirectory", {"--csv", "{dir}"}, "--csv"},
                      BadOption{"CsvInAMissingDirectory", {"--csv", "{dir}/missing/set.csv"}, "--csv"},
                      BadOption{"CsvIsADevice", {"--csv", "/dev/null"}, "--csv"},
                      BadOption{"CsvDashWithFormat", {"--csv", "-", "--format", "json"}, "--csv"},
                      BadOption{"OutWasReplaced", {"--out", "{dir}/set.csv"}, "--out"},
                      BadOption{"UnknownFlag", {"--samples", "3"}, "--samples"}),
    [](const ::testing::TestParamInfo<BadOption>& info) { return info.param.name; });

}  // namespace
}  // namespace loopfarm
