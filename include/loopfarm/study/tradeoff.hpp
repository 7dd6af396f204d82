// Speed against accuracy: one job measured under many configurations, on the
// same starts and the same ground truth (docs/quality/tradeoff.md).
//
// A configuration is the base job with one choice changed (cycle samples N,
// equilibrium tolerance, compliance set, objective (mean or max), local
// algorithm, its relative-decrease stop, zero threshold, the step of a
// zero's analysis):
// one axis at a time, so that each point of the chart says what that one
// choice costs and buys. For each configuration:
//   speed     median and p90 seconds of the local minimisation of the job's
//             starts 0 .. starts-1 (run_start, one core), and the seconds
//             of their zeros' analysis;
//   search    the fraction of those starts reaching zero, the false zeros
//             (zero energy, rigid verification fails) and the worst family
//             residual of the verified zeros;
//   truth     missed zeros: movable ground-truth loops whose cycle energy,
//             evaluated at their pose with the configuration's settings,
//             does not read as zero; rigid ones (perturbed, generic) that
//             read as zero; and the smallest relative perturbation at which
//             every perturbed loop is told apart from zero; and the movable
//             ones a zero's analysis (analyse_zero, from their pose) does
//             not verify or puts in another family: misanalysed.
// The error rate, (false zeros + missed zeros + rigid loops read as zero +
// misanalysed) / (zeros + ground-truth loops), is the accuracy axis of the
// chart; the Pareto front is over (median seconds, error rate).
#pragma once

#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "loopfarm/search/job.hpp"
#include "loopfarm/search/start.hpp"
#include "loopfarm/study/ground_truth.hpp"

namespace loopfarm {

struct TradeoffOptions {
  long starts = 50;  // search starts per configuration: indices 0 .. starts-1
  GroundTruthOptions ground_truth;
  // The values tried on each axis (the base job's own value is always one).
  std::vector<int> samples = {4, 8, 16, 32, 64, 128};
  // The input range a cycle covers [deg] ([loop] range_deg): 360 is a full
  // turn, less a window around theta0 (what a search for rockers needs).
  std::vector<double> ranges_deg = {360.0, 180.0, 90.0};
  std::vector<double> closure_tolerances = {1e-6, 1e-8, 1e-10, 1e-13};  // stationarity 100x looser
  std::vector<std::string> compliances = {"paper", "full"};
  std::vector<std::string> objectives = {"mean", "max"};  // [loop] objective
  std::vector<std::string> algorithms = {"gauss-newton", "LD_LBFGS", "LD_SLSQP", "LD_MMA", "LN_BOBYQA"};
  std::vector<double> zero_thresholds = {1e-8, 1e-12, 1e-16, 1e-20, 1e-24};
  // The local search's relative-decrease stop ([optimizer] ftol_rel; 0: off):
  // ends starts that creep towards a non-zero minimum.
  std::vector<double> ftol_rels = {0.0, 1e-4, 1e-3, 1e-2};
  // The progress stop's window ([optimizer] progress_window; 0: off), with
  // the base job's progress_factor: ends starts that creep over many steps.
  std::vector<int> progress_windows = {0};
  // The checkpoint ([optimizer] checkpoint_evaluations and
  // checkpoint_objective; evaluations 0: off): ends starts still above the
  // objective after that many evaluations.
  std::vector<std::pair<int, double>> checkpoints = {{0, 0.0}};
  // Whether each evaluation's cycle starts from the last one's samples
  // ([optimizer] reuse_nearby_cycle).
  std::vector<bool> reuse_nearby_cycles = {true, false};
  // A zero's analysis: the largest step of its coarse trace, 360 / this
  // degrees (StartOptions::analysis_steps_per_turn, >= 64).
  std::vector<int> analysis_steps = {64, 128, 360};
  // Called after each configuration with its index and the total, for progress.
  std::function<void(int done, int total, const std::string& name)> progress;

  // Throws std::invalid_argument naming the first invalid option.
  void validate() const;
};

// One configuration: the base job with at most one choice changed.
struct TradeoffConfiguration {
  // "base", "samples", "range_deg", "closure_tolerance", "compliance", "objective", "algorithm", "ftol_rel",
  // "progress_window", "checkpoint", "reuse_nearby_cycle", "zero_threshold", "analysis_steps"
  std::string axis;
  std::string value;  // the value on that axis, as text ("16", "1e-08", "LD_LBFGS")
  Job job;
  int analysis_steps_per_turn = StartOptions{}.analysis_steps_per_turn;
  std::string name() const { return axis == "base" ? "base" : axis + "=" + value; }
};

// The base configuration first, then each axis's other values (a value equal
// to the base job's is not repeated).
std::vector<TradeoffConfiguration> tradeoff_configurations(const Job& base, const TradeoffOptions& options);

struct TradeoffRow {
  std::string axis, value;
  // Speed: seconds of local minimisation per start.
  double median_seconds = 0.0;
  double p90_seconds = 0.0;
  double search_seconds = 0.0;    // the sum over the starts: core-seconds of local minimisation
  double analysis_seconds = 0.0;  // the sum over the zeros: core-seconds of their analysis
  // The configuration's whole measurement: its starts, and the ground truth's
  // cycles where they were evaluated for it (run_tradeoff evaluates them once
  // per distinct loop settings).
  double total_seconds = 0.0;
  // Search starts.
  long starts = 0;
  long zeros = 0;
  long verified = 0;
  long false_zeros = 0;                // zero, but the rigid verification fails
  double worst_family_residual = 0.0;  // over the verified zeros; 0 when none
  // Ground truth.
  long movable_cases = 0;
  long missed_zeros = 0;  // movable, not read as zero
  long rigid_cases = 0;
  long rigid_read_as_zero = 0;  // rigid, read as zero
  long misanalysed = 0;         // movable, and its analysis does not verify it or names another family
  // Smallest relative perturbation at which every perturbed case (of that
  // size) reads non-zero, and the sizes above it too; +inf when even the
  // largest is missed.
  double smallest_told_apart = 0.0;
  bool pareto = false;  // on the front of (median_seconds, error_rate)

  double zero_fraction() const { return starts > 0 ? static_cast<double>(zeros) / starts : 0.0; }
  // Core-seconds of search and analysis per verified zero: what a discovery
  // costs (+inf when none).
  double seconds_per_verified_zero() const;
  double error_rate() const;
};

// Each ground-truth loop's cycle energy with these loop settings, assembled
// at its pose (what a start on it reads): NaN where it cannot be assembled
// there, +inf where a sample fails (not an energy).
std::vector<double> ground_truth_energies(const std::vector<GroundTruthCase>& ground_truth, const LoopSection& loop);

// Measures one configuration on the job's first `starts` starts and on the
// ground-truth set, whose energies under the configuration's loop settings
// are given (`energies[i]` for `ground_truth[i]`, from ground_truth_energies)
// or, in the first form, evaluated here.
TradeoffRow measure_configuration(const TradeoffConfiguration& configuration,
                                  const std::vector<GroundTruthCase>& ground_truth, const TradeoffOptions& options);
TradeoffRow measure_configuration(const TradeoffConfiguration& configuration,
                                  const std::vector<GroundTruthCase>& ground_truth, const std::vector<double>& energies,
                                  const TradeoffOptions& options);

// Sets `pareto` on the rows no other row beats in both median seconds and
// error rate (ties in both count as not beaten).
void mark_pareto_front(std::vector<TradeoffRow>& rows);

// Every configuration, measured, with the front marked.
std::vector<TradeoffRow> run_tradeoff(const Job& base, const TradeoffOptions& options);

}  // namespace loopfarm
