#include "loopfarm/study/tradeoff.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include <gtest/gtest.h>

namespace loopfarm {
namespace {

// A small generic 4R job: cheap starts, every family reachable.
constexpr const char* kJob = R"(
[loop]
joints = 4
samples = 16

[optimizer]
algorithm = "gauss-newton"
max_evaluations = 40

[search]
starts = 10
seed = 3
zero_threshold = 1e-12
)";

// A ground-truth set small enough for a test: one loop per family, each
// perturbed once by 1e-2 (of L, or of a radian), and one generic loop.
TradeoffOptions small_options() {
  TradeoffOptions o;
  o.starts = 3;
  o.ground_truth.cases_per_family = 1;
  o.ground_truth.generic_loops = 1;
  o.ground_truth.relative_perturbations = {1e-2};
  return o;
}

TEST(Tradeoff, ConfigurationsChangeOneChoiceEachAndSkipTheBaseValue) {
  const Job base = parse_job(kJob, "job.toml");
  TradeoffOptions o;
  o.samples = {8, 16, 32};  // 16 is the base's
  o.closure_tolerances = {1e-8};
  o.compliances = {"paper", "full"};  // paper is the base's
  o.objectives = {"mean"};            // the base's: no configuration
  o.algorithms = {"gauss-newton", "LD_LBFGS"};
  o.zero_thresholds = {1e-12, 1e-20};
  o.ftol_rels = {0.0, 1e-3};               // 0 is the base's
  o.progress_windows = {0, 40};            // 0 is the base's
  o.checkpoints = {{0, 0.0}, {20, 1e-6}};  // 0 (off) is the base's
  o.reuse_nearby_cycles = {true, false};   // true is the base's
  o.ranges_deg = {360, 90};                // 360 is the base's
  o.analysis_steps = {64, 360};            // 64 is the default's
  const auto configurations = tradeoff_configurations(base, o);
  // base, samples 8 and 32, range 90, tolerance, full, LBFGS, ftol 1e-3, window 40, checkpoint 20:1e-6,
  // no reuse, 1e-20, analysis steps 360
  ASSERT_EQ(configurations.size(), 13u);
  EXPECT_EQ(configurations[0].name(), "base");
  int changed_samples = 0;
  for (const TradeoffConfiguration& c : configurations) {
    const bool samples_axis = c.axis == "samples";
    EXPECT_EQ(c.job.loop.samples != base.loop.samples, samples_axis) << c.name();
    EXPECT_EQ(c.job.optimizer.algorithm != base.optimizer.algorithm, c.axis == "algorithm") << c.name();
    EXPECT_EQ(c.job.loop.compliance != base.loop.compliance, c.axis == "compliance") << c.name();
    EXPECT_EQ(c.job.loop.range != base.loop.range, c.axis == "range_deg") << c.name();
    EXPECT_EQ(c.job.search.zero_threshold != base.search.zero_threshold, c.axis == "zero_threshold") << c.name();
    EXPECT_EQ(c.job.optimizer.ftol_rel != base.optimizer.ftol_rel, c.axis == "ftol_rel") << c.name();
    EXPECT_EQ(c.job.optimizer.progress_window != base.optimizer.progress_window, c.axis == "progress_window")
        << c.name();
    EXPECT_EQ(c.job.optimizer.reuse_nearby_cycle != base.optimizer.reuse_nearby_cycle, c.axis == "reuse_nearby_cycle")
        << c.name();
    EXPECT_EQ(c.job.optimizer.checkpoint_evaluations != base.optimizer.checkpoint_evaluations, c.axis == "checkpoint")
        << c.name();
    if (c.axis == "checkpoint") {
      EXPECT_EQ(c.value, "20:1e-06");
      EXPECT_EQ(c.job.optimizer.checkpoint_objective, 1e-6);
    }
    EXPECT_EQ(c.job.loop.objective, "mean") << c.name();
    EXPECT_EQ(c.job.loop.closure_tolerance != base.loop.closure_tolerance, c.axis == "closure_tolerance") << c.name();
    EXPECT_EQ(c.analysis_steps_per_turn != StartOptions{}.analysis_steps_per_turn, c.axis == "analysis_steps")
        << c.name();
    if (samples_axis) {
      ++changed_samples;
      EXPECT_EQ(std::to_string(c.job.loop.samples), c.value);
    }
  }
  EXPECT_EQ(changed_samples, 2);
  ASSERT_EQ(configurations[3].axis, "range_deg");
  EXPECT_EQ(configurations[3].job.loop.range, 90.0 / 360.0 * (2.0 * 3.14159265358979323846));
  ASSERT_EQ(configurations[4].axis, "closure_tolerance");
  EXPECT_EQ(configurations[4].job.loop.stationarity_tolerance, 1e-6);  // 100x the closure tolerance
}

TEST(Tradeoff, ParetoFrontKeepsTheRowsNoOtherBeatsInBothSpeedAndErrors) {
  auto row = [](double seconds, long errors) {
    TradeoffRow r;
    r.median_seconds = seconds;
    r.movable_cases = 100;
    r.missed_zeros = errors;
    return r;
  };
  // Error rates 0.10, 0.05, 0.05, 0.00, 0.20.
  std::vector<TradeoffRow> rows = {row(1.0, 10), row(2.0, 5), row(3.0, 5), row(4.0, 0), row(0.5, 20)};
  mark_pareto_front(rows);
  EXPECT_TRUE(rows[0].pareto);
  EXPECT_TRUE(rows[1].pareto);
  EXPECT_FALSE(rows[2].pareto);  // as accurate as rows[1], slower
  EXPECT_TRUE(rows[3].pareto);   // the most accurate
  EXPECT_TRUE(rows[4].pareto);   // the fastest
  EXPECT_DOUBLE_EQ(rows[1].error_rate(), 0.05);
}

TEST(Tradeoff, TheBaseReadsEveryMovableLoopAsZeroAndTellsThePerturbedOnesApart) {
  const Job base = parse_job(kJob, "job.toml");
  const TradeoffOptions o = small_options();
  const auto truth = generate_ground_truth(o.ground_truth);
  const TradeoffRow row = measure_configuration(tradeoff_configurations(base, o)[0], truth, o);
  EXPECT_EQ(row.starts, 3);
  EXPECT_GT(row.median_seconds, 0.0);
  EXPECT_GE(row.p90_seconds, row.median_seconds);
  EXPECT_LE(row.verified + row.false_zeros, row.zeros);
  EXPECT_EQ(row.movable_cases, 5);  // Bennett in both setups, planar, spherical, trivial
  EXPECT_EQ(row.missed_zeros, 0);
  EXPECT_EQ(row.rigid_cases, 6);  // the five perturbed and one generic
  EXPECT_EQ(row.rigid_read_as_zero, 0);
  EXPECT_EQ(row.smallest_told_apart, 1e-2);
  EXPECT_EQ(row.misanalysed, 0);  // every movable loop verified, in its family
  EXPECT_GT(row.analysis_seconds, 0.0);
}

// The analysis of the movable ground-truth loops is judged against the
// family they were built in: a Bennett loop labelled planar is misanalysed,
// at every step of the analysis.
TEST(Tradeoff, AMovableLoopAnalysedIntoAnotherFamilyIsMisanalysed) {
  const Job base = parse_job(kJob, "job.toml");
  TradeoffOptions o = small_options();
  o.starts = 1;
  std::vector<GroundTruthCase> truth = generate_ground_truth(o.ground_truth);
  ASSERT_EQ(truth.front().family, GroundTruthFamily::bennett);
  ASSERT_TRUE(truth.front().movable);
  truth.front().family = GroundTruthFamily::planar;
  for (int steps : {64, 360}) {
    TradeoffConfiguration c{"analysis_steps", std::to_string(steps), base};
    c.analysis_steps_per_turn = steps;
    const TradeoffRow row = measure_configuration(c, truth, o);
    EXPECT_EQ(row.misanalysed, 1) << steps;
    EXPECT_GT(row.error_rate(), 0.0) << steps;
  }
}

TEST(Tradeoff, ALooseZeroThresholdReadsPerturbedLoopsAsZero) {
  // A 1e-2 perturbation costs an energy of order 1e-5 (it grows as the square
  // of the error, paper Fig. 7): a threshold of 1e-2 cannot tell it apart, and
  // the row says so.
  const Job base = parse_job(kJob, "job.toml");
  TradeoffOptions o = small_options();
  o.starts = 1;
  TradeoffConfiguration loose{"zero_threshold", "1e-2", base};
  loose.job.search.zero_threshold = 1e-2;
  const auto truth = generate_ground_truth(o.ground_truth);
  const TradeoffRow row = measure_configuration(loose, truth, o);
  EXPECT_EQ(row.missed_zeros, 0);
  EXPECT_GT(row.rigid_read_as_zero, 0);
  EXPECT_EQ(row.smallest_told_apart, std::numeric_limits<double>::infinity());
  EXPECT_GT(row.error_rate(), 0.0);
}

// A window sees part of the motion: every movable loop still reads zero,
// and each perturbed one reads less than over the full turn, but not zero
// (the energy over the window is the mean over its samples, which lie on
// the part of the full turn's curve around theta0).
TEST(Tradeoff, AWindowReadsMovableLoopsAsZeroAndPerturbedOnesLower) {
  const Job base = parse_job(kJob, "job.toml");
  const auto truth = generate_ground_truth(small_options().ground_truth);
  LoopSection window = base.loop;
  window.range = 90.0 / 360.0 * (2.0 * 3.14159265358979323846);
  const std::vector<double> full = ground_truth_energies(truth, base.loop);
  const std::vector<double> part = ground_truth_energies(truth, window);
  int lower = 0, rigid = 0;
  for (size_t i = 0; i < truth.size(); ++i) {
    if (truth[i].movable) {
      EXPECT_LE(part[i], base.search.zero_threshold) << truth[i].id;
      continue;
    }
    ++rigid;
    EXPECT_GT(part[i], base.search.zero_threshold) << truth[i].id;
    lower += part[i] < full[i];
  }
  EXPECT_EQ(rigid, 6);
  EXPECT_GE(lower, rigid / 2);
}

TEST(Tradeoff, GroundTruthEnergiesOfTheSameLoopSectionServeEveryAxisThatKeepsIt) {
  // What run_tradeoff does for the algorithm, ftol_rel, objective and
  // zero-threshold axes: the base's energies, read with another threshold,
  // give what evaluating them afresh gives.
  const Job base = parse_job(kJob, "job.toml");
  TradeoffOptions o = small_options();
  o.starts = 1;
  const auto truth = generate_ground_truth(o.ground_truth);
  const std::vector<double> energies = ground_truth_energies(truth, base.loop);
  ASSERT_EQ(energies.size(), truth.size());
  TradeoffConfiguration loose{"zero_threshold", "1e-2", base};
  loose.job.search.zero_threshold = 1e-2;
  const TradeoffRow fresh = measure_configuration(loose, truth, o);
  const TradeoffRow reused = measure_configuration(loose, truth, energies, o);
  EXPECT_EQ(reused.missed_zeros, fresh.missed_zeros);
  EXPECT_EQ(reused.rigid_read_as_zero, fresh.rigid_read_as_zero);
  EXPECT_GT(reused.rigid_read_as_zero, 0);
  EXPECT_EQ(reused.smallest_told_apart, fresh.smallest_told_apart);
  EXPECT_THROW(measure_configuration(loose, truth, std::vector<double>(1), o), std::invalid_argument);
}

TEST(Tradeoff, InvalidOptionsAreRejectedByName) {
  auto message = [](const TradeoffOptions& o) -> std::string {
    try {
      o.validate();
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "";
  };
  // A fresh set of options per case, one field made invalid.
  auto with = [&message](auto change) {
    TradeoffOptions o;
    change(o);
    return message(o);
  };
  EXPECT_EQ(with([](TradeoffOptions&) {}), "");
  EXPECT_NE(with([](TradeoffOptions& o) { o.samples = {2}; }).find("samples"), std::string::npos);
  EXPECT_NE(with([](TradeoffOptions& o) { o.algorithms = {"LD_FAST"}; }).find("LD_FAST"), std::string::npos);
  EXPECT_NE(with([](TradeoffOptions& o) { o.zero_thresholds = {std::nan("")}; }).find("zero_thresholds"),
            std::string::npos);
  EXPECT_NE(with([](TradeoffOptions& o) { o.starts = 0; }).find("starts"), std::string::npos);
  EXPECT_NE(with([](TradeoffOptions& o) { o.ftol_rels = {-1.0}; }).find("ftol_rels"), std::string::npos);
  EXPECT_NE(with([](TradeoffOptions& o) { o.progress_windows = {-1}; }).find("progress_windows"), std::string::npos);
  EXPECT_NE(with([](TradeoffOptions& o) { o.ranges_deg = {400.0}; }).find("ranges_deg"), std::string::npos);
  EXPECT_NE(with([](TradeoffOptions& o) { o.objectives = {"median"}; }).find("median"), std::string::npos);
  EXPECT_NE(with([](TradeoffOptions& o) { o.ground_truth.cases_per_family = -1; }), "");
}

}  // namespace
}  // namespace loopfarm
