// `loopfarm tradeoff`, run as a user runs it: a small sweep whose CSV has one
// row per configuration with the library's measures, a chart that appears
// only when the whole run succeeded, and bad options refused with exit code 2
// and one line naming the flag, leaving existing files untouched.
// LOOPFARM_EXECUTABLE is the path of the built binary.
#include <stdlib.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "command_test_support.hpp"

namespace loopfarm {
namespace {

namespace fs = std::filesystem;
using testing::read_file;
using testing::split;

const std::string kExecutable = LOOPFARM_EXECUTABLE;

class TradeoffCli : public testing::CommandTest {
 protected:
  TradeoffCli() : CommandTest("loopfarm-tradeoff-test") {}
  void SetUp() override {
    CommandTest::SetUp();
    // A small generic job: cheap starts.
    std::ofstream(dir_ / "job.toml") << "[loop]\nsamples = 8\n[optimizer]\nmax_evaluations = 20\n"
                                        "[search]\nstarts = 5\nzero_threshold = 1e-20\n";
  }
  testing::CommandResult run(const std::vector<std::string>& args) {
    return run_command(kExecutable, "tradeoff", args);
  }
};

// The smallest sweep that has every axis: two starts, one loop per family.
const std::vector<std::string> kSmallSweep = {"{dir}/job.toml",
                                              "--starts",
                                              "2",
                                              "--per-family",
                                              "1",
                                              "--generic",
                                              "1",
                                              "--perturbations",
                                              "1e-2",
                                              "--samples",
                                              "8,16",
                                              "--ranges-deg",
                                              "360,90",
                                              "--closure-tolerances",
                                              "1e-8",
                                              "--compliances",
                                              "paper",
                                              "--objectives",
                                              "mean,max",
                                              "--algorithms",
                                              "gauss-newton,LD_LBFGS",
                                              "--zero-thresholds",
                                              "1e-20",
                                              "--ftol-rels",
                                              "0,1e-3",
                                              "--reuse-nearby-cycles",
                                              "true,false",
                                              "--analysis-steps",
                                              "64,360"};

TEST_F(TradeoffCli, WritesOneCsvRowPerConfigurationAndAChart) {
  std::vector<std::string> args = kSmallSweep;
  for (const char* extra : {"--csv", "{dir}/t.csv", "--plot", "{dir}/t.png"}) args.emplace_back(extra);
  const testing::CommandResult r = run(args);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::vector<std::string> rows = split(read_file(dir_ / "t.csv"), '\n');
  // Header, base, samples=16, range_deg=90, closure_tolerance=1e-08, objective=max, algorithm=LD_LBFGS,
  // ftol_rel=0.001, reuse_nearby_cycle=false, analysis_steps=360, then "" after the last newline.
  ASSERT_EQ(rows.size(), 11u) << read_file(dir_ / "t.csv");
  const std::vector<std::string> header = split(rows[0], ',');
  EXPECT_EQ(header.front(), "axis");
  EXPECT_EQ(header.back(), "pareto");
  const size_t movable_column =
      static_cast<size_t>(std::find(header.begin(), header.end(), "movable_cases") - header.begin());
  ASSERT_LT(movable_column, header.size());
  int on_front = 0;
  for (size_t i = 1; i + 1 < rows.size(); ++i) {
    const std::vector<std::string> cells = split(rows[i], ',');
    ASSERT_EQ(cells.size(), header.size()) << rows[i];
    on_front += cells.back() == "1";
    // Bennett in both setups, planar, spherical, trivial: one each.
    EXPECT_EQ(cells[movable_column], "5") << rows[i];
  }
  EXPECT_EQ(split(rows[1], ',')[0], "base");
  EXPECT_GE(on_front, 1);  // the fastest configuration is always on the front
  // The table on stdout names every configuration; the PNG exists.
  for (const char* name : {"base", "samples=16", "closure_tolerance=1e-08", "objective=max", "algorithm=LD_LBFGS",
                           "ftol_rel=0.001", "analysis_steps=360"}) {
    EXPECT_NE(r.out.find(name), std::string::npos) << name;
  }
  EXPECT_GT(fs::file_size(dir_ / "t.png"), 1000u);
  EXPECT_EQ(read_file(dir_ / "t.png").substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8));
  // A progress line on stderr per configuration, none with --quiet; the same table either way.
  EXPECT_NE(r.err.find("loopfarm tradeoff: 1/9 configurations measured (base)\n"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("loopfarm tradeoff: 9/9 configurations measured"), std::string::npos) << r.err;
  std::vector<std::string> quiet_args = kSmallSweep;
  quiet_args.emplace_back("--quiet");
  const testing::CommandResult quiet = run(quiet_args);
  ASSERT_EQ(quiet.exit_code, 0) << quiet.err;
  EXPECT_EQ(quiet.err, "");
  EXPECT_EQ(quiet.out.substr(0, quiet.out.find('\n')), r.out.substr(0, r.out.find('\n')));
}

TEST_F(TradeoffCli, BadOptionsExitWithCode2NamingTheFlagAndLeaveFilesAlone) {
  std::ofstream(dir_ / "keep.csv") << "precious\n";
  const std::vector<std::pair<std::vector<std::string>, std::string>> cases = {
      {{"{dir}/job.toml", "--starts", "0"}, "--starts"},
      {{"{dir}/job.toml", "--samples", "2,8"}, "--samples"},
      {{"{dir}/job.toml", "--samples", "8.5"}, "--samples"},
      {{"{dir}/job.toml", "--ranges-deg", "0"}, "--ranges-deg"},
      {{"{dir}/job.toml", "--ranges-deg", "361"}, "--ranges-deg"},
      {{"{dir}/job.toml", "--algorithms", "gauss-newton,LD_FAST"}, "--algorithms"},
      {{"{dir}/job.toml", "--compliances", "rigid"}, "--compliances"},
      {{"{dir}/job.toml", "--objectives", "mean,median"}, "--objectives"},
      {{"{dir}/job.toml", "--zero-thresholds", "nan"}, "--zero-thresholds"},
      {{"{dir}/job.toml", "--ftol-rels", "0,0"}, "--ftol-rels"},
      {{"{dir}/job.toml", "--progress-windows", "40.5"}, "--progress-windows"},
      {{"{dir}/job.toml", "--checkpoints", "20"}, "--checkpoints"},
      {{"{dir}/job.toml", "--checkpoints", "20:0"}, "--checkpoints"},
      {{"{dir}/job.toml", "--checkpoints", "0:1e-6"}, "--checkpoints"},
      {{"{dir}/job.toml", "--checkpoints", "20:x"}, "--checkpoints"},
      {{"{dir}/job.toml", "--reuse-nearby-cycles", "true,yes"}, "--reuse-nearby-cycles"},
      {{"{dir}/job.toml", "--reuse-nearby-cycles", "false,false"}, "--reuse-nearby-cycles"},
      {{"{dir}/job.toml", "--closure-tolerances", "0.1"}, "--closure-tolerances"},
      {{"{dir}/job.toml", "--perturbations", "2"}, "--perturbations"},
      {{"{dir}/job.toml", "--analysis-steps", "63"}, "--analysis-steps"},
      {{"{dir}/missing.toml"}, "missing.toml"},
      {{"{dir}/job.toml", "--csv", "{dir}/no/such/dir/t.csv"}, "--csv"},
      {{"{dir}/job.toml", "--plot", "{dir}/t.jpg"}, "--plot"},
  };
  for (const auto& [args, flag] : cases) {
    std::vector<std::string> with_output = args;
    with_output.insert(with_output.end(), {"--csv", "{dir}/keep.csv"});
    if (flag == "--csv") with_output = args;
    const testing::CommandResult r = run(with_output);
    EXPECT_EQ(r.exit_code, 2) << flag << ": " << r.err;
    EXPECT_EQ(split(r.err, '\n').size(), 2u) << "not one line: " << r.err;
    EXPECT_NE(r.err.find(flag), std::string::npos) << r.err;
    EXPECT_EQ(read_file(dir_ / "keep.csv"), "precious\n") << flag;
  }
}

// One start under the base configuration and the few rows that one value
// per axis leaves: the smallest sweep, without ground truth.
const std::vector<std::string> kOneStart = {"{dir}/job.toml",
                                            "--starts",
                                            "1",
                                            "--per-family",
                                            "0",
                                            "--generic",
                                            "0",
                                            "--perturbations",
                                            "none",
                                            "--samples",
                                            "8",
                                            "--ranges-deg",
                                            "360",
                                            "--closure-tolerances",
                                            "1e-10",
                                            "--compliances",
                                            "full",
                                            "--objectives",
                                            "mean",
                                            "--algorithms",
                                            "gauss-newton",
                                            "--zero-thresholds",
                                            "1e-20",
                                            "--ftol-rels",
                                            "0",
                                            "--reuse-nearby-cycles",
                                            "true",
                                            "--analysis-steps",
                                            "64"};

// No configuration finds a verified zero, so that none has a cost per zero:
// the chart is drawn all the same, that panel empty and saying why, rather
// than failing after the work (a logarithmic axis with nothing on it).
TEST_F(TradeoffCli, AChartWithoutAVerifiedZeroIsDrawnWithThatPanelSayingSo) {
  std::vector<std::string> args = kOneStart;
  for (const char* extra : {"--quiet", "--csv", "{dir}/t.csv", "--plot", "{dir}/t.svg"}) args.emplace_back(extra);
  const testing::CommandResult r = run(args);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err, "");
  // What the test is about: not one configuration with a verified zero.
  const std::vector<std::string> rows = split(read_file(dir_ / "t.csv"), '\n');
  ASSERT_GE(rows.size(), 3u);
  const std::vector<std::string> header = split(rows[0], ',');
  const size_t verified_column =
      static_cast<size_t>(std::find(header.begin(), header.end(), "verified") - header.begin());
  ASSERT_LT(verified_column, header.size());
  for (size_t i = 1; i + 1 < rows.size(); ++i) ASSERT_EQ(split(rows[i], ',')[verified_column], "0") << rows[i];
  const std::string chart = read_file(dir_ / "t.svg");
  EXPECT_NE(chart.find("<svg"), std::string::npos);
  EXPECT_NE(chart.find("no configuration found a verified zero"), std::string::npos);
  // The other panels are drawn as ever: their axis labels are there.
  EXPECT_NE(chart.find("median time of local minimisation per start [ms]"), std::string::npos);
  EXPECT_NE(chart.find("worst family residual of the verified zeros"), std::string::npos);
}

// A PDF that this gnuplot cannot write (no pdfcairo terminal: a gnuplot on
// PATH that lists none) is refused before the work, not after it.
TEST_F(TradeoffCli, APdfThisGnuplotCannotWriteIsRefusedBeforeTheWork) {
  fs::create_directories(dir_ / "bin");
  const fs::path fake = dir_ / "bin" / "gnuplot";
  std::ofstream(fake) << "#!/bin/sh\necho 'dumb png svg'\n";
  fs::permissions(fake, fs::perms::owner_all);
  const char* old_path = std::getenv("PATH");
  const std::string saved = old_path ? old_path : "";
  ::setenv("PATH", ((dir_ / "bin").string() + ":" + saved).c_str(), 1);
  std::vector<std::string> args = kOneStart;
  for (const char* extra : {"--plot", "{dir}/t.pdf"}) args.emplace_back(extra);
  const testing::CommandResult r = run(args);
  ::setenv("PATH", saved.c_str(), 1);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_EQ(split(r.err, '\n').size(), 2u) << "not one line: " << r.err;
  EXPECT_NE(r.err.find("--plot: "), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("no pdfcairo terminal"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("configurations measured"), std::string::npos) << r.err;  // nothing measured
  EXPECT_EQ(r.out, "");
  EXPECT_FALSE(fs::exists(dir_ / "t.pdf"));
}

}  // namespace
}  // namespace loopfarm
