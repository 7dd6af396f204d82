// The loopfarm command line, run as a user runs it: exit codes, the one-line
// messages for bad input, stdout formats and the files it writes (or must not
// write). LOOPFARM_EXECUTABLE is the path of the built binary.
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "loopfarm/core/cycle.hpp"
#include "loopfarm/core/cycle_start.hpp"
#include "loopfarm/core/loop.hpp"

namespace {

namespace fs = std::filesystem;

const std::string kExecutable = LOOPFARM_EXECUTABLE;
const std::vector<std::string> kBennett = {"energy", "--a", "2,4,2,4", "--alpha-deg", "30,90,30,90"};

// Single quotes for /bin/sh: only the quote itself needs care.
std::string shell_quote(const std::string& text) {
  std::string out = "'";
  for (const char c : text) {
    if (c == '\'') {
      out += "'\\''";
    } else {
      out += c;
    }
  }
  return out + "'";
}

std::string read_file(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

void write_file(const fs::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
}

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

std::vector<std::string> split(const std::string& text, char separator) {
  std::vector<std::string> parts;
  size_t start = 0;
  while (true) {
    const size_t end = text.find(separator, start);
    parts.push_back(text.substr(start, end == std::string::npos ? std::string::npos : end - start));
    if (end == std::string::npos) return parts;
    start = end + 1;
  }
}

// The whole text as a double, or NaN if it is not exactly one number.
double to_number(const std::string& text) {
  if (text.empty()) return std::nan("");
  char* end = nullptr;
  const double value = std::strtod(text.c_str(), &end);
  return end == text.c_str() + text.size() ? value : std::nan("");
}

// The raw text of a top-level value in a one-line JSON object: the key's
// value up to the next ',' or '}' outside brackets. Empty if the key is absent.
std::string json_raw(const std::string& json, const std::string& key) {
  const std::string needle = "\"" + key + "\":";
  const size_t at = json.find(needle);
  if (at == std::string::npos) return "";
  size_t i = at + needle.size();
  const size_t start = i;
  int depth = 0;
  bool in_string = false;
  for (; i < json.size(); ++i) {
    const char c = json[i];
    if (in_string) {
      if (c == '\\') {
        ++i;
      } else if (c == '"') {
        in_string = false;
      }
    } else if (c == '"') {
      in_string = true;
    } else if (c == '[' || c == '{') {
      ++depth;
    } else if (c == ']' || c == '}') {
      if (depth == 0) break;
      --depth;
    } else if (c == ',' && depth == 0) {
      break;
    }
  }
  return json.substr(start, i - start);
}

double json_number(const std::string& json, const std::string& key) { return to_number(json_raw(json, key)); }

// `base` followed by `more`.
std::vector<std::string> with(std::vector<std::string> base, const std::vector<std::string>& more) {
  base.insert(base.end(), more.begin(), more.end());
  return base;
}

bool have_gnuplot() { return std::system("command -v gnuplot >/dev/null 2>&1") == 0; }

struct Result {
  int exit_code = -1;
  std::string out;
  std::string err;
};

class CliTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    std::string name = std::string(info->test_suite_name()) + "-" + info->name();
    for (char& c : name) {
      if (c == '/') c = '-';
    }
    dir_ = fs::temp_directory_path() / ("loopfarm-cli-test-" + std::to_string(::getpid()) + "-" + name);
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override {
    std::error_code ignored;
    fs::remove_all(dir_, ignored);
  }

  // Runs the binary with `args` ("{dir}" replaced by the test's directory),
  // optionally prefixed by environment assignments for /bin/sh.
  Result run(const std::vector<std::string>& args, const std::string& environment = "") {
    std::string command = environment + (environment.empty() ? "" : " ") + shell_quote(kExecutable);
    for (std::string arg : args) {
      for (size_t at; (at = arg.find("{dir}")) != std::string::npos;) arg.replace(at, 5, dir_.string());
      command += ' ';
      command += shell_quote(arg);
    }
    const fs::path out = dir_ / ".stdout";
    const fs::path err = dir_ / ".stderr";
    command += " >";
    command += shell_quote(out.string());
    command += " 2>";
    command += shell_quote(err.string());
    const int status = std::system(command.c_str());
    Result result;
    result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    result.out = read_file(out);
    result.err = read_file(err);
    fs::remove(out);
    fs::remove(err);
    return result;
  }

  // Names of the files in the test directory.
  std::vector<std::string> files() const {
    std::vector<std::string> names;
    for (const auto& entry : fs::directory_iterator(dir_)) names.push_back(entry.path().filename().string());
    std::sort(names.begin(), names.end());
    return names;
  }

  fs::path dir_;
};

// ---------------------------------------------------------------------------
// Bad input: exit code 2, one line on stderr naming the flag or file position,
// nothing on stdout, and no file written or changed.

struct BadInput {
  std::string name;
  std::vector<std::string> args;
  std::vector<std::string> message_parts;  // each must appear in the message
  std::string toml = "";                   // written to {dir}/geom.toml when not empty
};

std::ostream& operator<<(std::ostream& out, const BadInput& input) { return out << input.name; }

class BadInputTest : public CliTest, public ::testing::WithParamInterface<BadInput> {};

TEST_P(BadInputTest, ExitsWithCode2AndOneLineNamingTheFlag) {
  const BadInput& input = GetParam();
  if (!input.toml.empty()) write_file(dir_ / "geom.toml", input.toml);
  // A previous result at the --csv target must survive the failed run.
  std::vector<std::string> args = input.args;
  const std::string sentinel = "theta_in_deg,energy\n0,1\n";
  bool guarded = false;
  if (args.front() == "energy" && std::find(args.begin(), args.end(), "--csv") == args.end()) {
    write_file(dir_ / "keep.csv", sentinel);
    args.insert(args.end(), {"--csv", "{dir}/keep.csv"});
    guarded = true;
  }
  const auto before = files();

  const Result result = run(args);

  EXPECT_EQ(result.exit_code, 2) << result.err;
  EXPECT_EQ(result.out, "");
  const auto lines = lines_of(result.err);
  ASSERT_EQ(lines.size(), 1u) << result.err;
  EXPECT_EQ(result.err.back(), '\n');
  EXPECT_EQ(lines[0].rfind("loopfarm", 0), 0u) << lines[0];
  for (const std::string& part : input.message_parts) {
    EXPECT_NE(lines[0].find(part), std::string::npos) << "expected " << part << " in: " << lines[0];
  }
  if (guarded) {
    EXPECT_EQ(read_file(dir_ / "keep.csv"), sentinel);
  }
  EXPECT_EQ(files(), before) << "a failed run left files behind";
}

INSTANTIATE_TEST_SUITE_P(
    Energy, BadInputTest,
    ::testing::Values(
        BadInput{"three_joints",
                 {"energy", "--a", "1,2,3", "--alpha-deg", "10,20,30"},
                 {"loopfarm energy: --a:", "3 values"}},
        BadInput{"nine_joints",
                 {"energy", "--a", "1,1,1,1,1,1,1,1,1", "--alpha-deg", "10,10,10,10,10,10,10,10,10"},
                 {"loopfarm energy: --a:", "9 values"}},
        BadInput{"alpha_count_differs",
                 {"energy", "--a", "2,4,2,4", "--alpha-deg", "30,90,30"},
                 {"--alpha-deg:", "3 values"}},
        BadInput{"d_count_differs", with(kBennett, {"--d", "0,0,0"}), {"--d:", "3 values"}},
        BadInput{"theta_count_differs", with(kBennett, {"--theta-deg", "120,90,-120"}), {"--theta-deg:", "3 values"}},
        BadInput{"nan_length", {"energy", "--a", "2,nan,2,4", "--alpha-deg", "30,90,30,90"}, {"--a:", "\"nan\""}},
        BadInput{"inf_twist", {"energy", "--a", "2,4,2,4", "--alpha-deg", "30,inf,30,90"}, {"--alpha-deg:", "\"inf\""}},
        BadInput{"infinity_offset", with(kBennett, {"--d", "0,Infinity,0,0"}), {"--d:", "\"Infinity\""}},
        BadInput{"negative_length", {"energy", "--a=-2,4,2,4", "--alpha-deg", "30,90,30,90"}, {"--a:", "-2", ">= 0"}},
        BadInput{"empty_list", {"energy", "--a", "", "--alpha-deg", "30,90,30,90"}, {"--a:", "empty"}},
        BadInput{
            "empty_element", {"energy", "--a", "2,,2,4", "--alpha-deg", "30,90,30,90"}, {"--a:", "element 2", "empty"}},
        BadInput{"trailing_comma", {"energy", "--a", "2,4,2,4,", "--alpha-deg", "30,90,30,90"}, {"--a:", "element 5"}},
        BadInput{"junk_in_number", {"energy", "--a", "2,4x,2,4", "--alpha-deg", "30,90,30,90"}, {"--a:", "\"4x\""}},
        BadInput{"letters", {"energy", "--a", "2,x,2,4", "--alpha-deg", "30,90,30,90"}, {"--a:", "\"x\""}},
        BadInput{"samples_too_few", with(kBennett, {"--samples", "1"}), {"--samples:", "1"}},
        BadInput{"samples_not_a_number", with(kBennett, {"--samples", "abc"}), {"--samples:", "\"abc\""}},
        BadInput{"samples_fraction", with(kBennett, {"--samples", "2.5"}), {"--samples:", "\"2.5\""}},
        BadInput{"unknown_compliance", with(kBennett, {"--compliance", "rigid"}), {"--compliance:", "rigid", "paper"}},
        BadInput{"zero_torsion_ratio", with(kBennett, {"--torsion-ratio", "0"}), {"--torsion-ratio:", "0"}},
        BadInput{"negative_torsion_ratio", with(kBennett, {"--torsion-ratio=-1"}), {"--torsion-ratio:", "-1"}},
        BadInput{"range_too_large", with(kBennett, {"--range-deg", "400"}), {"--range-deg:", "400"}},
        BadInput{"range_zero", with(kBennett, {"--range-deg", "0"}), {"--range-deg:", "0"}},
        BadInput{"nan_theta0", with(kBennett, {"--theta0-deg", "nan"}), {"--theta0-deg:", "\"nan\""}},
        BadInput{"missing_twists", {"energy", "--a", "2,4,2,4"}, {"--alpha-deg:", "missing"}},
        BadInput{"missing_geometry", {"energy"}, {"--a:", "missing"}},
        BadInput{"toml_unknown_key",
                 {"energy", "--geometry", "{dir}/geom.toml"},
                 {"geom.toml:3 key \"b\"", "unknown key"},
                 "a = [2, 4, 2, 4]\nalpha_deg = [30, 90, 30, 90]\nb = 1\n"},
        BadInput{"toml_wrong_type",
                 {"energy", "--geometry", "{dir}/geom.toml"},
                 {"geom.toml:1 key \"a\"", "string \"2,4,2,4\""},
                 "a = \"2,4,2,4\"\nalpha_deg = [30, 90, 30, 90]\n"},
        BadInput{"toml_wrong_element_type",
                 {"energy", "--geometry", "{dir}/geom.toml"},
                 {"geom.toml:2 key \"alpha_deg\"", "element 2", "boolean true"},
                 "a = [2, 4, 2, 4]\nalpha_deg = [30, true, 30, 90]\n"},
        BadInput{"toml_nan",
                 {"energy", "--geometry", "{dir}/geom.toml"},
                 {"geom.toml:2 key \"d\"", "nan"},
                 "a = [2, 4, 2, 4]\nd = [0, nan, 0, 0]\nalpha_deg = [30, 90, 30, 90]\n"},
        BadInput{"toml_count_differs",
                 {"energy", "--geometry", "{dir}/geom.toml"},
                 {"geom.toml:2 key \"alpha_deg\"", "3 values"},
                 "a = [2, 4, 2, 4]\nalpha_deg = [30, 90, 30]\n"},
        BadInput{"toml_missing_key",
                 {"energy", "--geometry", "{dir}/geom.toml"},
                 {"geom.toml", "alpha_deg"},
                 "a = [2, 4, 2, 4]\n"},
        BadInput{"toml_syntax_error",
                 {"energy", "--geometry", "{dir}/geom.toml"},
                 {"geom.toml:", "invalid TOML"},
                 "a = [2, 4, 2, 4\nalpha_deg = [30, 90, 30, 90]\n"},
        BadInput{"toml_missing_file", {"energy", "--geometry", "{dir}/absent.toml"}, {"--geometry:", "absent.toml"}},
        BadInput{"geometry_and_flags", with(kBennett, {"--geometry", "{dir}/absent.toml"}), {"--geometry"}},
        BadInput{
            "csv_directory_missing", with(kBennett, {"--csv", "{dir}/no/such/dir/out.csv"}), {"--csv:", "out.csv"}},
        BadInput{"csv_is_a_directory", with(kBennett, {"--csv", "{dir}"}), {"--csv:", "directory"}},
        BadInput{"log_without_plot", with(kBennett, {"--log"}), {"--log"}},
        BadInput{"unknown_option", with(kBennett, {"--frobnicate"}), {"--frobnicate"}}),
    [](const ::testing::TestParamInfo<BadInput>& info) { return info.param.name; });

const std::string kTable1 = std::string(LOOPFARM_SOURCE_DIR) + "/jobs/paper-table1.toml";

INSTANTIATE_TEST_SUITE_P(
    StartAndVerify, BadInputTest,
    ::testing::Values(
        BadInput{"start_missing_job",
                 {"start", "{dir}/absent.toml"},
                 {"loopfarm start: job file:", "absent.toml:0:", "cannot read"}},
        BadInput{"start_bad_job_key",
                 {"start", "{dir}/geom.toml"},
                 {"loopfarm start: job file:", "geom.toml:2: loop.joint:", "unknown key"},
                 "[loop]\njoint = 4\n"},
        BadInput{"start_bad_job_range",
                 {"start", "{dir}/geom.toml"},
                 {"geom.toml:3: space.alpha1_deg:", "lo > hi"},
                 "[space]\n\nalpha1_deg = [90, 30]\n"},
        BadInput{"start_index_beyond", {"start", kTable1, "--index", "200"}, {"loopfarm start: --index:", "0 to 199"}},
        BadInput{"start_index_text", {"start", kTable1, "--index", "two"}, {"loopfarm start: --index:", "\"two\""}},
        BadInput{"start_count_zero", {"start", kTable1, "--count", "0", "--json"}, {"--count:", "got 0"}},
        BadInput{"start_unknown_format", {"start", kTable1, "--format", "xml"}, {"--format:", "xml"}},
        BadInput{"start_format_and_json", {"start", kTable1, "--format", "csv", "--json"}, {"--json", "--format"}},
        BadInput{
            "start_count_beyond", {"start", kTable1, "--index", "198", "--count", "5", "--json"}, {"--count:", "202"}},
        BadInput{"start_algorithm", {"start", kTable1, "--algorithm", "LD_NOPE"}, {"--algorithm:", "LD_NOPE"}},
        BadInput{"start_no_job", {"start"}, {"JOB"}},
        BadInput{"verify_three_joints",
                 {"verify", "--a", "1,2,3", "--alpha-deg", "10,20,30"},
                 {"loopfarm verify: --a:", "3 values"}},
        BadInput{"verify_steps",
                 {"verify", "--a", "2,4,2,4", "--alpha-deg", "30,90,30,90", "--steps", "63"},
                 {"--steps:", "63"}},
        BadInput{"verify_samples",
                 {"verify", "--a", "2,4,2,4", "--alpha-deg", "30,90,30,90", "--samples", "2"},
                 {"--samples:", "2"}},
        BadInput{"verify_theta_count",
                 {"verify", "--a", "2,4,2,4", "--alpha-deg", "30,90,30,90", "--theta-deg", "1,2"},
                 {"--theta-deg:", "2 values"}}),
    [](const ::testing::TestParamInfo<BadInput>& info) { return info.param.name; });

// ---------------------------------------------------------------------------
// Results.

TEST_F(CliTest, JsonForThePaperBennettLoopHasZeroEnergy) {
  const Result result = run(with(kBennett, {"--theta-deg", "120,90,-120,-90", "--samples", "24", "--json"}));
  ASSERT_EQ(result.exit_code, 0) << result.err;
  EXPECT_EQ(result.err, "");
  const auto lines = lines_of(result.out);
  ASSERT_EQ(lines.size(), 1u) << result.out;
  const std::string& json = lines[0];
  EXPECT_EQ(json.front(), '{');
  EXPECT_EQ(json.back(), '}');

  // Keys present, in the documented order.
  const std::vector<std::string> keys = {"E_mean",       "E_max",           "samples",      "failed_samples",
                                         "branch_jumps", "refinements",     "iterations",   "max_closure_residual",
                                         "theta0_deg",   "theta_deg",       "range_deg",    "on_motion",
                                         "full_turn",    "input_range_deg", "length_scale", "compliance",
                                         "seconds"};
  size_t previous = 0;
  for (const std::string& key : keys) {
    const size_t at = json.find("\"" + key + "\":");
    ASSERT_NE(at, std::string::npos) << key;
    EXPECT_GE(at, previous) << key << " out of order";
    previous = at;
  }
  EXPECT_EQ(json.find("nan"), std::string::npos);
  EXPECT_EQ(json.find("inf"), std::string::npos);

  const double e_max = json_number(json, "E_max");
  ASSERT_FALSE(std::isnan(e_max)) << json_raw(json, "E_max");
  EXPECT_LE(e_max, 1e-20);
  EXPECT_LE(json_number(json, "E_mean"), e_max);
  EXPECT_EQ(json_raw(json, "samples"), "24");
  EXPECT_EQ(json_raw(json, "failed_samples"), "0");
  EXPECT_EQ(json_raw(json, "compliance"), "\"paper\"");
  EXPECT_DOUBLE_EQ(json_number(json, "theta0_deg"), 120.0);
  EXPECT_NEAR(json_number(json, "length_scale"), std::sqrt(10.0), 1e-12);
  // The given pose is on the Bennett motion, whose input turns fully.
  EXPECT_EQ(json_raw(json, "on_motion"), "true");
  EXPECT_EQ(json_raw(json, "full_turn"), "true");
  EXPECT_EQ(json_raw(json, "input_range_deg"), "null");
  EXPECT_EQ(json_number(json, "range_deg"), 360.0);

  std::string theta = json_raw(json, "theta_deg");
  ASSERT_GE(theta.size(), 2u);
  ASSERT_EQ(theta.front(), '[');
  ASSERT_EQ(theta.back(), ']');
  const auto angles = split(theta.substr(1, theta.size() - 2), ',');
  ASSERT_EQ(angles.size(), 4u) << theta;
  const double expected[] = {120.0, 90.0, -120.0, -90.0};
  for (size_t i = 0; i < 4; ++i) EXPECT_NEAR(to_number(angles[i]), expected[i], 1e-6) << theta;
  EXPECT_GE(json_number(json, "seconds"), 0.0);
}

TEST_F(CliTest, NegativeListsWorkAsSeparateArguments) {
  // The other assembly of the same Bennett loop; CLI11 must take "-120,..."
  // as the value, not as an option.
  const Result result = run(with(kBennett, {"--theta-deg", "-120,-90,120,90", "--samples", "8", "--json"}));
  ASSERT_EQ(result.exit_code, 0) << result.err;
  EXPECT_LE(json_number(result.out, "E_max"), 1e-20) << result.out;
  EXPECT_DOUBLE_EQ(json_number(result.out, "theta0_deg"), -120.0);
}

TEST_F(CliTest, GenericLoopHasPositiveEnergy) {
  const Result result = run(
      {"energy", "--a", "1,2,3,2.5", "--alpha-deg", "20,70,40,110", "--d=0.1,-0.3,0.2,0", "--samples", "16", "--json"});
  ASSERT_EQ(result.exit_code, 0) << result.err;
  const double e_mean = json_number(result.out, "E_mean");
  EXPECT_GT(e_mean, 1e-6) << result.out;
  EXPECT_GE(json_number(result.out, "E_max"), e_mean);
  EXPECT_EQ(json_raw(result.out, "samples"), "16");
}

// A non-Grashof four-bar driven at a rocker (range from the law of cosines,
// as in VerifyFindsARockerWhateverTheta0): the automatic range is a window
// centred on theta0 inside the input's range, where the energy is zero; a
// full turn when theta0 is outside it (no assembly on a motion there) or
// when asked for.
TEST_F(CliTest, EnergyCyclesARockerOverAWindowInsideItsRange) {
  const double lo = std::acos(10.25 / 16.0) * 180.0 / 3.14159265358979323846;
  const std::vector<std::string> rocker = {"energy", "--a", "2,3,2.5,4", "--alpha-deg", "0,0,0,0"};
  const Result inside = run(with(rocker, {"--theta0-deg", "200", "--json"}));
  ASSERT_EQ(inside.exit_code, 0) << inside.err;
  EXPECT_EQ(json_raw(inside.out, "on_motion"), "true");
  EXPECT_EQ(json_raw(inside.out, "full_turn"), "false");
  const std::string range = json_raw(inside.out, "input_range_deg");
  EXPECT_NEAR(std::stod(range.substr(1)), lo, 1e-6) << range;
  EXPECT_NEAR(std::stod(range.substr(range.find(',') + 1)), 360.0 - lo, 1e-6) << range;
  EXPECT_NEAR(json_number(inside.out, "range_deg"), 1.8 * (360.0 - lo - 200.0), 1e-6);
  EXPECT_LE(json_number(inside.out, "E_mean"), 1e-20);
  EXPECT_EQ(json_raw(inside.out, "failed_samples"), "0");

  const Result text = run(with(rocker, {"--theta0-deg", "200"}));
  ASSERT_EQ(text.exit_code, 0) << text.err;
  EXPECT_NE(text.out.find("(on a motion of the rigid loop)"), std::string::npos) << text.out;
  EXPECT_NE(text.out.find("a window inside the input's range"), std::string::npos) << text.out;

  const Result outside = run(with(rocker, {"--theta0-deg", "0", "--json"}));
  ASSERT_EQ(outside.exit_code, 0) << outside.err;
  EXPECT_EQ(json_raw(outside.out, "on_motion"), "false");
  EXPECT_EQ(json_raw(outside.out, "full_turn"), "null");
  EXPECT_EQ(json_number(outside.out, "range_deg"), 360.0);
  EXPECT_GT(json_number(outside.out, "E_mean"), 1e-6);

  const Result asked = run(with(rocker, {"--theta0-deg", "200", "--range-deg", "360", "--json"}));
  ASSERT_EQ(asked.exit_code, 0) << asked.err;
  EXPECT_EQ(json_number(asked.out, "range_deg"), 360.0);
  EXPECT_GT(json_number(asked.out, "E_mean"), 1e-6);
}

// What `energy` prints is what the library computes: the same start
// (choose_cycle_start) and cycle (cycle_energy), to the last bit, for a rigid
// loop over a full turn and for a rocker over its automatic window.
TEST_F(CliTest, EnergyPrintsWhatTheLibraryComputes) {
  using loopfarm::CycleOptions, loopfarm::CycleStart, loopfarm::CycleSummary, loopfarm::EquilibriumWorkspace,
      loopfarm::LoopGeometry, loopfarm::LoopModel;
  struct Case {
    std::vector<std::string> flags;
    LoopGeometry geometry;
    double theta0_deg;
  };
  const std::vector<Case> cases = {
      {{"--a", "1,2,3,2.5", "--alpha-deg", "20,70,40,110", "--d=0.1,-0.3,0.2,0", "--theta0-deg", "30"},
       LoopGeometry::from_degrees(std::vector<double>{1, 2, 3, 2.5}, std::vector<double>{20, 70, 40, 110},
                                  std::vector<double>{0.1, -0.3, 0.2, 0}),
       30.0},
      {{"--a", "2,3,2.5,4", "--alpha-deg", "0,0,0,0", "--theta0-deg", "200"},
       LoopGeometry::from_degrees(std::vector<double>{2, 3, 2.5, 4}, std::vector<double>{0, 0, 0, 0},
                                  std::vector<double>{0, 0, 0, 0}),
       200.0},
  };
  for (const Case& c : cases) {
    std::vector<std::string> args = {"energy", "--samples", "16", "--json"};
    args.insert(args.end(), c.flags.begin(), c.flags.end());
    const Result r = run(args);
    ASSERT_EQ(r.exit_code, 0) << r.err;

    const LoopModel model(c.geometry);
    EquilibriumWorkspace ws(model);
    const double theta0 = c.theta0_deg * 3.14159265358979323846 / 180.0;
    const CycleStart start = loopfarm::choose_cycle_start(model, ws, theta0, nullptr);
    CycleOptions options;
    options.samples = 16;
    options.range = start.range;
    CycleSummary cycle;
    loopfarm::cycle_energy(model, ws, theta0, start.assembly.state, options, cycle);
    EXPECT_EQ(json_number(r.out, "E_mean"), cycle.E_mean) << r.out;
    EXPECT_EQ(json_number(r.out, "E_max"), cycle.E_max) << r.out;
    EXPECT_EQ(json_number(r.out, "iterations"), cycle.total_iterations) << r.out;
    EXPECT_EQ(json_raw(r.out, "on_motion"), start.motion ? "true" : "false") << r.out;
    EXPECT_NEAR(json_number(r.out, "range_deg"), start.range * 180.0 / 3.14159265358979323846, 1e-12) << r.out;
  }
}

TEST_F(CliTest, TomlGeometryGivesTheSameResultAsFlags) {
  write_file(dir_ / "loop.toml",
             "# a generic loop\na = [1, 2, 3, 2.5]\nalpha_deg = [20, 70, 40, 110]\nd = [0.1, -0.3, 0.2, 0]\n");
  const Result from_flags = run(
      {"energy", "--a", "1,2,3,2.5", "--alpha-deg", "20,70,40,110", "--d=0.1,-0.3,0.2,0", "--samples", "8", "--json"});
  const Result from_file = run({"energy", "--geometry", "{dir}/loop.toml", "--samples", "8", "--json"});
  ASSERT_EQ(from_flags.exit_code, 0) << from_flags.err;
  ASSERT_EQ(from_file.exit_code, 0) << from_file.err;
  EXPECT_EQ(json_raw(from_flags.out, "E_mean"), json_raw(from_file.out, "E_mean"));
  EXPECT_EQ(json_raw(from_flags.out, "theta_deg"), json_raw(from_file.out, "theta_deg"));
}

TEST_F(CliTest, SummaryNamesEveryQuantity) {
  const Result result = run(with(kBennett, {"--theta-deg", "120,90,-120,-90", "--samples", "8"}));
  ASSERT_EQ(result.exit_code, 0) << result.err;
  for (const char* part : {"E_mean", "E_max", "failed samples", "branch jumps", "refinements", "Newton iterations",
                           "max closure residual", "theta_deg", "wall time", "length scale"}) {
    EXPECT_NE(result.out.find(part), std::string::npos) << part << " missing from\n" << result.out;
  }
}

TEST_F(CliTest, CsvHasAHeaderAndOneRowPerSample) {
  write_file(dir_ / "curve.csv", "old contents\n");
  const Result result =
      run(with(kBennett, {"--theta-deg", "120,90,-120,-90", "--samples", "12", "--csv", "{dir}/curve.csv"}));
  ASSERT_EQ(result.exit_code, 0) << result.err;
  EXPECT_NE(result.out.find("E_mean"), std::string::npos);
  const auto lines = lines_of(read_file(dir_ / "curve.csv"));
  ASSERT_EQ(lines.size(), 13u);
  EXPECT_EQ(lines[0],
            "theta_in_deg,energy,status,iterations,closure_residual,theta1_deg,theta2_deg,theta3_deg,theta4_deg,"
            "da1,da2,da3,da4,dalpha1_deg,dalpha2_deg,dalpha3_deg,dalpha4_deg");
  for (size_t row = 1; row < lines.size(); ++row) {
    const auto fields = split(lines[row], ',');
    ASSERT_EQ(fields.size(), 17u) << lines[row];
    EXPECT_NEAR(to_number(fields[0]), 120.0 + 30.0 * static_cast<double>(row - 1), 1e-9) << lines[row];
    EXPECT_LE(to_number(fields[1]), 1e-20) << lines[row];
    EXPECT_TRUE(fields[2] == "converged" || fields[2] == "refined") << lines[row];
    for (size_t f = 3; f < fields.size(); ++f) {
      EXPECT_FALSE(std::isnan(to_number(fields[f]))) << "field " << f << " of " << lines[row];
    }
  }
  EXPECT_EQ(files(), std::vector<std::string>{"curve.csv"}) << "temporary files left behind";
}

TEST_F(CliTest, CsvWithFullComplianceHasOffsetColumns) {
  const Result result =
      run({"energy", "--a", "1,2,3,2.5", "--alpha-deg", "20,70,40,110", "--samples", "4", "--compliance", "full",
           "--range-deg", "90", "--theta0-deg", "10", "--csv", "{dir}/curve.csv", "--json"});
  ASSERT_EQ(result.exit_code, 0) << result.err;
  EXPECT_EQ(json_raw(result.out, "compliance"), "\"full\"");
  const auto lines = lines_of(read_file(dir_ / "curve.csv"));
  ASSERT_EQ(lines.size(), 5u);
  EXPECT_NE(lines[0].find(",dd1,dd2,dd3,dd4"), std::string::npos) << lines[0];
  EXPECT_EQ(split(lines[0], ',').size(), 21u);
  // A partial range is [theta0 - R/2, theta0 + R/2].
  EXPECT_NEAR(to_number(split(lines[1], ',')[0]), -35.0, 1e-9);
  EXPECT_NEAR(to_number(split(lines[4], ',')[0]), 55.0, 1e-9);
}

TEST_F(CliTest, PlotWritesAPng) {
  if (!have_gnuplot()) GTEST_SKIP() << "gnuplot is not installed";
  for (const bool log : {false, true}) {
    const fs::path png = dir_ / (log ? "log.png" : "linear.png");
    std::vector<std::string> args = {"energy",    "--a", "1,2,3,2.5", "--alpha-deg", "20,70,40,110",
                                     "--samples", "16",  "--plot",    png.string()};
    if (log) args.push_back("--log");
    const Result result = run(args);
    ASSERT_EQ(result.exit_code, 0) << result.err;
    const std::string image = read_file(png);
    ASSERT_GT(image.size(), 100u);
    EXPECT_EQ(image.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8));
  }
  // A zero-energy loop on a log axis (zeros cannot be drawn there) still plots.
  const Result bennett =
      run(with(kBennett, {"--theta-deg", "120,90,-120,-90", "--samples", "8", "--plot", "{dir}/zero.png", "--log"}));
  ASSERT_EQ(bennett.exit_code, 0) << bennett.err;
  EXPECT_GT(fs::file_size(dir_ / "zero.png"), 100u);
  EXPECT_EQ(files(), (std::vector<std::string>{"linear.png", "log.png", "zero.png"}));
}

TEST_F(CliTest, PlotExtensionPicksTheFormat) {
  // Any extension but .png, .svg and .pdf is refused before any work, even
  // without gnuplot, and leaves nothing behind.
  for (const char* command : {"energy", "motion"}) {
    const Result refused = run({command, "--a", "2,4,2,4", "--alpha-deg", "30,90,30,90", "--plot", "{dir}/curve.txt"},
                               "PATH=" + (dir_ / "empty-path").string());
    EXPECT_EQ(refused.exit_code, 2) << command << ": " << refused.err;
    EXPECT_EQ(refused.out, "");
    EXPECT_NE(refused.err.find("--plot: "), std::string::npos) << refused.err;
    EXPECT_NE(refused.err.find("expected .png, .svg or .pdf"), std::string::npos) << refused.err;
  }
  EXPECT_TRUE(files().empty());
  if (!have_gnuplot()) GTEST_SKIP() << "gnuplot is not installed";
  const Result svg = run(with(kBennett, {"--theta-deg", "120,90,-120,-90", "--samples", "8", "--plot", "{dir}/e.svg"}));
  ASSERT_EQ(svg.exit_code, 0) << svg.err;
  const std::string svg_bytes = read_file(dir_ / "e.svg");
  EXPECT_EQ(svg_bytes.substr(0, 5), "<?xml");
  EXPECT_NE(svg_bytes.find("<svg"), std::string::npos);
  if (std::system("gnuplot -e 'set terminal' 2>&1 | grep -q pdfcairo") == 0) {
    const Result pdf = run({"motion", "--a", "1,2,1,2", "--alpha-deg", "0,0,0,0", "--plot", "{dir}/m.pdf"});
    ASSERT_EQ(pdf.exit_code, 0) << pdf.err;
    EXPECT_EQ(read_file(dir_ / "m.pdf").substr(0, 5), "%PDF-");
  }
}

TEST_F(CliTest, PlotWithoutGnuplotFailsBeforeWritingAnything) {
  write_file(dir_ / "keep.csv", "sentinel\n");
  const Result result = run(with(kBennett, {"--csv", "{dir}/keep.csv", "--plot", "{dir}/out.png"}),
                            "PATH=" + (dir_ / "empty-path").string());
  EXPECT_EQ(result.exit_code, 1);
  EXPECT_EQ(result.out, "");
  ASSERT_EQ(lines_of(result.err).size(), 1u) << result.err;
  EXPECT_NE(result.err.find("--plot: gnuplot not found"), std::string::npos) << result.err;
  EXPECT_EQ(read_file(dir_ / "keep.csv"), "sentinel\n");
  EXPECT_EQ(files(), std::vector<std::string>{"keep.csv"});
}

TEST_F(CliTest, VersionHelpAndMissingSubcommand) {
  const Result version = run({"--version"});
  EXPECT_EQ(version.exit_code, 0);
  EXPECT_NE(version.out.find(LOOPFARM_VERSION), std::string::npos) << version.out;

  const Result help = run({"energy", "--help"});
  EXPECT_EQ(help.exit_code, 0);
  EXPECT_NE(help.out.find("--alpha-deg"), std::string::npos) << help.out;

  const Result none = run({});
  EXPECT_EQ(none.exit_code, 2);
  EXPECT_EQ(lines_of(none.err).size(), 1u) << none.err;
}

}  // namespace

// ---------------------------------------------------------------------------
// loopfarm start and loopfarm verify.

namespace {

const char* const kCandidateKeys[] = {"family",           "setup",           "verified", "rigid_residual",
                                      "family_residuals", "local_dimension", "E_mean",   "status"};

TEST_F(CliTest, StartReachesABennettLoopAndSaysEverythingInJson) {
  const Result result = run({"start", kTable1, "--index", "2", "--json"});
  ASSERT_EQ(result.exit_code, 0) << result.err;
  const auto lines = lines_of(result.out);
  ASSERT_EQ(lines.size(), 1u) << result.out;
  const std::string& json = lines[0];
  for (const char* key : kCandidateKeys) EXPECT_NE(json_raw(json, key), "") << key << " in " << json;
  EXPECT_EQ(json_raw(json, "zero"), "true");
  EXPECT_EQ(json_raw(json, "family"), "\"bennett\"");
  EXPECT_EQ(json_raw(json, "verified"), "true");
  EXPECT_EQ(json_number(json, "local_dimension"), 3);
  EXPECT_LT(json_number(json, "E_mean"), 1e-20);
  EXPECT_LT(json_number(json, "rigid_residual"), 1e-12);
  EXPECT_EQ(json_raw(json, "status"), "\"stopval_reached\"");
  EXPECT_NE(json_raw(json, "family_residuals").find("\"planar\":"), std::string::npos);
  EXPECT_GT(json_number(json, "analysis_seconds"), 0.0);
}

TEST_F(CliTest, StartReplaysBitIdenticallyAndRunsRanges) {
  const auto without_time = [](std::string json) {
    for (const std::string key : {"seconds", "analysis_seconds"}) {
      const std::string field = "\"" + key + "\":" + json_raw(json, key);
      json.replace(json.find(field), field.size(), "");
    }
    return json;
  };
  const Result one = run({"start", kTable1, "--index", "5", "--json"});
  const Result range = run({"start", kTable1, "--index", "4", "--count", "3", "--json"});
  ASSERT_EQ(one.exit_code, 0) << one.err;
  ASSERT_EQ(range.exit_code, 0) << range.err;
  const auto lines = lines_of(range.out);
  ASSERT_EQ(lines.size(), 3u);
  for (int i = 0; i < 3; ++i) EXPECT_EQ(json_number(lines[static_cast<size_t>(i)], "index"), 4 + i);
  // Start 5 alone and within a range: the same numbers to the last digit.
  EXPECT_EQ(without_time(lines_of(one.out)[0]), without_time(lines[1]));
}

TEST_F(CliTest, StartStoryAndTrace) {
  const Result result = run({"start", kTable1, "--index", "0", "--trace"});
  ASSERT_EQ(result.exit_code, 0) << result.err;
  const auto lines = lines_of(result.out);
  ASSERT_GT(lines.size(), 10u);
  EXPECT_NE(lines[0].find("iter"), std::string::npos) << lines[0];  // the trace's header
  for (const char* part : {"drawn geometry", "local minimisation (gauss-newton)", "final geometry", "zero",
                           "rigid verification", "classification", "canonical key", "local dimension"}) {
    EXPECT_NE(result.out.find(part), std::string::npos) << part;
  }
  // --trace with --json: the trace goes to stderr, stdout stays one JSON line.
  const Result json = run({"start", kTable1, "--index", "0", "--trace", "--json"});
  EXPECT_EQ(lines_of(json.out).size(), 1u);
  EXPECT_NE(json.err.find("iter"), std::string::npos);
}

// Every format of a command carries the same values: JSON parsed with
// nlohmann against CSV split by hand and Markdown's field-value rows.
TEST_F(CliTest, EveryFormatCarriesTheSameValues) {
  const std::vector<std::string> bennett = {
      "energy", "--a", "2,4,2,4", "--alpha-deg", "30,90,30,90", "--theta-deg", "120,90,-120,-90", "--samples", "8"};
  const Result json = run(with(bennett, {"--format", "json"}));
  const Result alias = run(with(bennett, {"--json"}));
  const Result csv = run(with(bennett, {"--format", "csv"}));
  const Result markdown = run(with(bennett, {"--format", "markdown"}));
  for (const Result* r : {&json, &alias, &csv, &markdown}) ASSERT_EQ(r->exit_code, 0) << r->err;
  const nlohmann::json object = nlohmann::json::parse(json.out);
  EXPECT_EQ(nlohmann::json::parse(alias.out).size(), object.size());
  const auto csv_lines = lines_of(csv.out);
  ASSERT_EQ(csv_lines.size(), 2u) << csv.out;
  const auto names = split(csv_lines[0], ',');
  const auto values = split(csv_lines[1], ',');
  ASSERT_EQ(names.size(), values.size());
  EXPECT_EQ(names.size(), object.size());
  const auto markdown_lines = lines_of(markdown.out);
  ASSERT_EQ(markdown_lines.size(), object.size() + 2) << markdown.out;
  EXPECT_EQ(markdown_lines[0], "| field | value |");
  for (size_t i = 0; i < names.size(); ++i) {
    SCOPED_TRACE(names[i]);
    ASSERT_TRUE(object.contains(names[i]));
    const nlohmann::json& value = object[names[i]];
    if (names[i] == "seconds") continue;  // the wall time of each run
    if (value.is_number()) {
      EXPECT_EQ(to_number(values[i]), value.get<double>());
    } else if (value.is_string()) {
      EXPECT_EQ(values[i], value.get<std::string>());
    } else if (value.is_boolean()) {
      EXPECT_EQ(values[i], value.get<bool>() ? "1" : "0");
    } else if (value.is_null()) {
      EXPECT_EQ(values[i], "");
    }
    EXPECT_EQ(markdown_lines[i + 2].rfind("| " + names[i] + " | ", 0), 0u);
  }
  EXPECT_EQ(object["samples"], 8);
  EXPECT_LT(object["E_max"].get<double>(), 1e-20);

  // --count N with csv: one header, a row per start, the index first.
  const Result starts = run({"start", kTable1, "--index", "4", "--count", "3", "--format", "csv"});
  ASSERT_EQ(starts.exit_code, 0) << starts.err;
  const auto rows = lines_of(starts.out);
  ASSERT_EQ(rows.size(), 4u) << starts.out;
  EXPECT_EQ(rows[0].rfind("index,algorithm,status,", 0), 0u) << rows[0];
  for (int i = 0; i < 3; ++i) EXPECT_EQ(rows[static_cast<size_t>(i + 1)].rfind(std::to_string(4 + i) + ",", 0), 0u);
  // Many stories, one after the other.
  const Result stories = run({"start", kTable1, "--index", "4", "--count", "2"});
  ASSERT_EQ(stories.exit_code, 0) << stories.err;
  EXPECT_NE(stories.out.find("start 4 of"), std::string::npos);
  EXPECT_NE(stories.out.find("start 5 of"), std::string::npos);

  const Result verified = run({"verify", "--a", "2,4,2,4", "--alpha-deg", "30,90,30,90", "--format", "markdown"});
  ASSERT_EQ(verified.exit_code, 0) << verified.err;
  EXPECT_NE(verified.out.find("\n| verified | yes |\n"), std::string::npos) << verified.out;
  EXPECT_NE(verified.out.find("\n| family | bennett |\n"), std::string::npos) << verified.out;
}

// '-' is standard output, with the same bytes the file gets; never with a
// format that would share it, and never two outputs at once.
TEST_F(CliTest, DashSendsAFileToStandardOutput) {
  const std::vector<std::string> loop = {"energy", "--a", "2,4,2,4", "--alpha-deg", "30,90,30,90", "--samples", "6"};
  std::vector<std::string> to_file = loop, to_stdout = loop, both = loop, with_json = loop;
  to_file.insert(to_file.end(), {"--csv", "{dir}/curve.csv"});
  to_stdout.insert(to_stdout.end(), {"--csv", "-"});
  const Result file = run(to_file);
  const Result dash = run(to_stdout);
  ASSERT_EQ(file.exit_code, 0) << file.err;
  ASSERT_EQ(dash.exit_code, 0) << dash.err;
  const std::string written = read_file(dir_ / "curve.csv");
  EXPECT_EQ(lines_of(written).size(), 7u);
  // The same curve (the wall time is not in it), and nothing else on stdout.
  EXPECT_EQ(dash.out, written);
  EXPECT_EQ(files(), std::vector<std::string>{"curve.csv"});
  with_json.insert(with_json.end(), {"--csv", "-", "--json"});
  const Result refused = run(with_json);
  EXPECT_EQ(refused.exit_code, 2);
  EXPECT_EQ(refused.out, "");
  EXPECT_NE(refused.err.find("--csv:"), std::string::npos) << refused.err;
  both.insert(both.end(), {"--csv", "-", "--plot", "-"});
  const Result twice = run(both);
  EXPECT_EQ(twice.exit_code, 2);
  EXPECT_NE(twice.err.find("already taken by --csv"), std::string::npos) << twice.err;
  // A device is never written over, nor the file the shell sent standard
  // output to through /dev/stdout (this test's runner sends it to a file).
  for (const char* device : {"/dev/null", "/dev/stdout"}) {
    const Result refused_device = run(with(loop, {"--csv", device}));
    EXPECT_EQ(refused_device.exit_code, 2) << device;
    EXPECT_EQ(refused_device.out, "") << device;
    EXPECT_NE(refused_device.err.find("not a regular file"), std::string::npos) << refused_device.err;
  }
  EXPECT_TRUE(fs::exists("/dev/null") && !fs::is_regular_file("/dev/null"));
}

TEST_F(CliTest, VerifyClassifiesMovableAndRigidLoops) {
  const Result bennett =
      run({"verify", "--a", "2,4,2,4", "--alpha-deg", "30,90,30,90", "--theta-deg", "120,90,-120,-90", "--json"});
  ASSERT_EQ(bennett.exit_code, 0) << bennett.err;
  const std::string& b = bennett.out;
  for (const char* key : kCandidateKeys) EXPECT_NE(json_raw(b, key), "") << key;
  EXPECT_EQ(json_raw(b, "family"), "\"bennett\"");
  EXPECT_EQ(json_raw(b, "setup"), "\"asymmetric\"");
  EXPECT_EQ(json_raw(b, "verified"), "true");
  EXPECT_EQ(json_number(b, "local_dimension"), 3);  // of 12 parameters
  const Result planar = run({"verify", "--a", "1,3,2.5,3.5", "--alpha-deg", "0,0,0,0", "--json"});
  EXPECT_EQ(json_raw(planar.out, "family"), "\"planar\"");
  EXPECT_EQ(json_number(planar.out, "local_dimension"), 7);
  // Rigid: exit code 4, and nothing that means something only at a zero.
  const Result rigid =
      run({"verify", "--a", "1,2,3,2.5", "--alpha-deg", "20,70,40,110", "--d=0.1,-0.3,0.2,0", "--json"});
  ASSERT_EQ(rigid.exit_code, 4) << rigid.err;
  EXPECT_EQ(json_raw(rigid.out, "verified"), "false");
  EXPECT_EQ(json_raw(rigid.out, "family"), "\"unclassified\"");
  EXPECT_EQ(json_raw(rigid.out, "E_mean"), "null");
  EXPECT_EQ(json_raw(rigid.out, "local_dimension"), "null");
  EXPECT_EQ(json_raw(rigid.out, "singular_values"), "null");
  EXPECT_EQ(json_raw(rigid.out, "circuits"), "[]");
  const Result text = run({"verify", "--a", "1,2,3,2.5", "--alpha-deg", "20,70,40,110", "--d=0.1,-0.3,0.2,0"});
  EXPECT_EQ(text.exit_code, 4);
  EXPECT_EQ(text.out.find("E_mean"), std::string::npos) << text.out;
  EXPECT_EQ(text.out.find("local dimension"), std::string::npos) << text.out;
}

// A coaxial trivial loop written so that joint 1 is one of its frozen joints:
// verified (the other joints turn), trivial, and no cycle of an input that
// does not move (it once ended with "range: must be in (0, 360]", exit 2).
TEST_F(CliTest, VerifyOfALoopWhoseInputIsFrozenGivesNoCycle) {
  const Result r =
      run({"verify", "--a", "1.5,2.5,2.5,1.5", "--alpha-deg", "40,70,70,40", "--d=0,-0.3,0,0.3", "--json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(json_raw(r.out, "verified"), "true");
  EXPECT_EQ(json_raw(r.out, "family"), "\"trivial\"");
  EXPECT_EQ(json_raw(r.out, "E_mean"), "null");
  EXPECT_EQ(json_raw(r.out, "local_dimension"), "null");
  const Result text = run({"verify", "--a", "1.5,2.5,2.5,1.5", "--alpha-deg", "40,70,70,40", "--d=0,-0.3,0,0.3"});
  EXPECT_EQ(text.exit_code, 0) << text.err;
  EXPECT_NE(text.out.find("the input joint does not move on this circuit"), std::string::npos) << text.out;
  EXPECT_EQ(text.out.find("E_mean"), std::string::npos) << text.out;
}

// A non-Grashof four-bar whose input cannot reach theta0 = 0: verified from
// no pose, from theta0 = 0 and from a pose inside its range, with the range
// of the law of cosines (delta^2 = 20 + 16 cos theta1 <= 30.25).
TEST_F(CliTest, VerifyFindsARockerWhateverTheta0) {
  const double lo = std::acos(10.25 / 16.0) * 180.0 / 3.14159265358979323846;
  for (const std::vector<std::string>& extra :
       {std::vector<std::string>{}, std::vector<std::string>{"--theta0-deg", "0"},
        std::vector<std::string>{"--theta0-deg", "200"}}) {
    std::vector<std::string> args = {"verify", "--a", "2,3,2.5,4", "--alpha-deg", "0,0,0,0", "--json"};
    args.insert(args.end(), extra.begin(), extra.end());
    const Result r = run(args);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_EQ(json_raw(r.out, "verified"), "true");
    EXPECT_EQ(json_raw(r.out, "family"), "\"planar\"");
    EXPECT_EQ(json_raw(r.out, "full_turn"), "false");
    const std::string range = json_raw(r.out, "input_range_deg");
    const double range_lo = std::stod(range.substr(1));
    const double range_hi = std::stod(range.substr(range.find(',') + 1));
    EXPECT_NEAR(range_lo, lo, 1e-6) << range;
    EXPECT_NEAR(range_hi, 360.0 - lo, 1e-6) << range;
    // The cycle energy along the motion, over a window inside the range.
    EXPECT_LT(json_number(r.out, "E_mean"), 1e-20);
    EXPECT_LT(json_number(r.out, "cycle_range_deg"), 360.0 - 2 * lo);
  }
}

// A Bennett loop with a1 moved by 3e-9 is rigid, yet its circuit closes
// within the tracer's tolerance (1e-9) all the way round: verify judges the
// geometry as given at round-off, refuses it (exit 4, no family, no cycle)
// and gives the movable loop its polish finds next to it, a Bennett loop by
// the closed-form conditions. One moved by 1e-6 does not close within the
// tolerance: refused, nothing polished. `motion` agrees. The exact loop
// verifies as given, with no polish.
TEST_F(CliTest, VerifyRefusesANearMissThatClosesOnlyWithinTheTolerance) {
  for (const char* a : {"2.000000003,4,2,4", "2.000001,4,2,4"}) {
    SCOPED_TRACE(a);
    const Result r = run({"verify", "--a", a, "--alpha-deg", "30,90,30,90", "--json"});
    ASSERT_EQ(r.exit_code, 4) << r.err;
    const nlohmann::json j = nlohmann::json::parse(r.out);
    EXPECT_EQ(j["verified"], false);
    EXPECT_NE(j["family"], "bennett");
    EXPECT_TRUE(j["E_mean"].is_null());
    EXPECT_GT(j["rigid_residual"].get<double>(), 1e-10);
    const Result m = run({"motion", "--a", a, "--alpha-deg", "30,90,30,90", "--json"});
    EXPECT_EQ(m.exit_code, 4) << m.out;
  }
  const Result near = run({"verify", "--a", "2.000000003,4,2,4", "--alpha-deg", "30,90,30,90", "--json"});
  const nlohmann::json j = nlohmann::json::parse(near.out);
  EXPECT_EQ(j["family_conditions_hold"], "bennett");
  const nlohmann::json& polish = j["polish"];
  ASSERT_EQ(polish["converged"], true) << near.out;
  EXPECT_EQ(polish["verified"], true);
  EXPECT_EQ(polish["family"], "bennett");
  EXPECT_LT(polish["rigid_residual"].get<double>(), 1e-13);
  const double moved = polish["displacement"].get<double>();
  EXPECT_GT(moved, 1e-10);
  EXPECT_LT(moved, 3e-9);
  // Independent of the tracer: Bennett's conditions on the polished
  // geometry (opposite links equal, sin(alpha1) / a1 = sin(alpha2) / a2).
  const nlohmann::json& g = j["polished_geometry"];
  const auto a = g["a"].get<std::vector<double>>();
  const auto alpha = g["alpha_deg"].get<std::vector<double>>();
  const double to_rad = 3.14159265358979323846 / 180.0;
  EXPECT_GT(a[0], 2.0);
  EXPECT_LT(a[0], 2.000000003);
  EXPECT_NEAR(a[0], a[2], 1e-14);
  EXPECT_NEAR(a[1], a[3], 1e-14);
  EXPECT_NEAR(alpha[0], alpha[2], 1e-12);
  EXPECT_NEAR(alpha[1], alpha[3], 1e-12);
  EXPECT_NEAR(a[0] * std::sin(alpha[1] * to_rad), a[1] * std::sin(alpha[0] * to_rad), 1e-14);
  for (const double d : g["d"].get<std::vector<double>>()) EXPECT_NEAR(d, 0.0, 1e-14);
  const Result text = run({"verify", "--a", "2.000000003,4,2,4", "--alpha-deg", "30,90,30,90"});
  EXPECT_NE(text.out.find("the geometry as given does not move"), std::string::npos) << text.out;
  EXPECT_NE(text.out.find("polished geometry"), std::string::npos) << text.out;
  const Result m = run({"motion", "--a", "2.000000003,4,2,4", "--alpha-deg", "30,90,30,90"});
  EXPECT_NE(m.out.find("the geometry as given does not move"), std::string::npos) << m.out;
  const Result far = run({"verify", "--a", "2.000001,4,2,4", "--alpha-deg", "30,90,30,90", "--json"});
  EXPECT_TRUE(nlohmann::json::parse(far.out)["polish"]["converged"].is_null()) << far.out;

  const Result exact = run({"verify", "--a", "2,4,2,4", "--alpha-deg", "30,90,30,90", "--json"});
  ASSERT_EQ(exact.exit_code, 0) << exact.err;
  const nlohmann::json e = nlohmann::json::parse(exact.out);
  EXPECT_EQ(e["family"], "bennett");
  EXPECT_TRUE(e["polish"]["converged"].is_null());
  EXPECT_TRUE(e["polished_geometry"]["a"].is_null());
}

// A trihedral Bricard 6R with every twist +90 deg and lengths for which that
// loop cannot be assembled: the family's conditions hold, no motion exists,
// and no family is claimed.
TEST_F(CliTest, VerifyNamesNoFamilyWithoutAMotion) {
  const std::vector<std::string> geometry = {"--a", "2.636,1.143,0.558,1.408,2.969,3.575738804778671", "--alpha-deg",
                                             "90,90,90,90,90,90"};
  std::vector<std::string> args = {"verify", "--json"};
  args.insert(args.end(), geometry.begin(), geometry.end());
  const Result r = run(args);
  ASSERT_EQ(r.exit_code, 4) << r.err;
  EXPECT_EQ(json_raw(r.out, "family"), "null");
  EXPECT_EQ(json_raw(r.out, "family_conditions_hold"), "\"bricard_trihedral\"");
  args.erase(args.begin() + 1);
  const Result text = run(args);
  EXPECT_NE(text.out.find("none: the bricard_trihedral conditions hold, but no motion was found"), std::string::npos)
      << text.out;
  // The alternating signs move, with the same lengths.
  const Result alternating = run({"verify", "--json", "--a", "2.636,1.143,0.558,1.408,2.969,3.575738804778671",
                                  "--alpha-deg", "90,-90,90,-90,90,-90"});
  ASSERT_EQ(alternating.exit_code, 0) << alternating.err;
  EXPECT_EQ(json_raw(alternating.out, "family"), "\"bricard_trihedral\"");
}

TEST_F(CliTest, MotionPrintsCircuitsWritesCsvAndPlot) {
  // The parallelogram: two circuits crossing at two change points.
  const Result r = run({"motion", "--a", "1,2,1,2", "--alpha-deg", "0,0,0,0", "--csv", "{dir}/curves.csv", "--plot",
                        "{dir}/curves.png"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("circuits                2 found"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("singular pose       the closure Jacobian loses rank; 4 branch directions leave it"),
            std::string::npos)
      << r.out;
  const std::vector<std::string> rows = lines_of(read_file(dir_ / "curves.csv"));
  ASSERT_GT(rows.size(), 100u);
  EXPECT_EQ(rows[0], "circuit,point,arclength_rad,theta1_deg,theta2_deg,theta3_deg,theta4_deg");
  EXPECT_EQ(rows[1].substr(0, 4), "1,0,");
  EXPECT_EQ(rows.back().substr(0, 2), "2,");
  const std::string image = read_file(dir_ / "curves.png");
  ASSERT_GT(image.size(), 100u);
  EXPECT_EQ(image.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8));
  // CSV to standard output, and JSON.
  const Result csv = run({"motion", "--a", "2,4,2,4", "--alpha-deg", "30,90,30,90", "--csv", "-"});
  ASSERT_EQ(csv.exit_code, 0) << csv.err;
  EXPECT_EQ(lines_of(csv.out)[0], "circuit,point,arclength_rad,theta1_deg,theta2_deg,theta3_deg,theta4_deg");
  const Result json = run({"motion", "--a", "2,4,2,4", "--alpha-deg", "30,90,30,90", "--json"});
  ASSERT_EQ(json.exit_code, 0) << json.err;
  EXPECT_EQ(json_raw(json.out, "verified"), "true");
  EXPECT_NE(json.out.find("\"full_turn\":true"), std::string::npos);
  // Rigid: exit code 4, no circuit.
  const Result rigid = run({"motion", "--a", "1,2,3,2.5", "--alpha-deg", "20,70,40,110", "--json"});
  EXPECT_EQ(rigid.exit_code, 4) << rigid.err;
  EXPECT_EQ(json_raw(rigid.out, "circuits"), "[]");
}

// motion refuses what verify refuses, with the same message.
TEST_F(CliTest, MotionAndVerifyRefuseTheSameBadGeometry) {
  const std::vector<std::vector<std::string>> bad = {
      {"--a", "1,2,3", "--alpha-deg", "10,20,30"},
      {"--a", "1,2,3,4", "--alpha-deg", "10,20,30"},
      {"--a", "1,-2,3,4", "--alpha-deg", "10,20,30,40"},
      {"--a", "1,2,3,4", "--alpha-deg", "10,20,nan,40"},
      {"--a", "1,2,3,4", "--alpha-deg", "10,20,30,40", "--theta-deg", "1,2"}};
  for (const std::vector<std::string>& geometry : bad) {
    std::vector<std::string> verify = {"verify"}, motion = {"motion"};
    verify.insert(verify.end(), geometry.begin(), geometry.end());
    motion.insert(motion.end(), geometry.begin(), geometry.end());
    const Result v = run(verify), m = run(motion);
    EXPECT_EQ(v.exit_code, 2) << v.err;
    EXPECT_EQ(m.exit_code, 2) << m.err;
    // The same message after the command's name.
    ASSERT_EQ(v.err.rfind("loopfarm verify: ", 0), 0u) << v.err;
    ASSERT_EQ(m.err.rfind("loopfarm motion: ", 0), 0u) << m.err;
    EXPECT_EQ(v.err.substr(17), m.err.substr(17));
    EXPECT_EQ(m.out, "");
  }
  const Result steps = run({"motion", "--a", "2,4,2,4", "--alpha-deg", "30,90,30,90", "--steps", "63"});
  EXPECT_EQ(steps.exit_code, 2);
  EXPECT_NE(steps.err.find("--steps"), std::string::npos) << steps.err;
  const Result both = run({"motion", "--a", "2,4,2,4", "--alpha-deg", "30,90,30,90", "--csv", "-", "--json"});
  EXPECT_EQ(both.exit_code, 2);
}

}  // namespace
