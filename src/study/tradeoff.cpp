#include "loopfarm/study/tradeoff.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <stdexcept>

#include "loopfarm/core/assembly.hpp"
#include "loopfarm/core/cycle.hpp"
#include "loopfarm/search/start.hpp"

namespace loopfarm {
namespace {

[[noreturn]] void fail(const std::string& what) { throw std::invalid_argument(what); }

std::string format_number(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.3g", value);
  return buffer;
}

// The q-quantile of `values` (nearest rank; `values` is reordered).
double quantile(std::vector<double>& values, double q) {
  if (values.empty()) return 0.0;
  const double position = std::ceil(q * static_cast<double>(values.size()));  // 1-based
  const size_t rank = std::min(values.size() - 1, position < 1.0 ? 0 : static_cast<size_t>(position) - 1);
  std::nth_element(values.begin(), values.begin() + static_cast<long>(rank), values.end());
  return values[rank];
}

// The ground-truth loop's cycle energy under the configuration's loop
// settings, assembled from its pose: what a start on that loop reads.
// NaN when it cannot be assembled at its pose.
double ground_truth_energy(const GroundTruthCase& c, const LoopSection& loop) {
  EquilibriumOptions equilibrium;
  equilibrium.compliance = loop.compliance;
  equilibrium.torsion_stiffness_ratio = loop.stiffness_ratio;
  equilibrium.closure_tolerance = loop.closure_tolerance;
  equilibrium.stationarity_tolerance = loop.stationarity_tolerance;
  const LoopModel model(c.geometry, equilibrium);
  EquilibriumWorkspace ws(model);
  const EquilibriumSummary start = assemble_from_angles(model, ws, c.pose);
  if (start.status != SolveStatus::converged) return std::numeric_limits<double>::quiet_NaN();
  CycleOptions cycle;
  cycle.samples = loop.samples;
  cycle.range = loop.range;
  CycleSummary summary;
  cycle_energy(model, ws, c.pose[0], start.state, cycle, summary);
  // A failed sample's energy is not to be trusted: the reading is not zero.
  if (summary.failed_samples > 0) return std::numeric_limits<double>::infinity();
  return summary.E_mean;
}

// Whether two loop settings give every ground-truth loop the same cycle
// energy (the search objective E_mean/E_max does not enter the reading).
bool same_reading(const LoopSection& a, const LoopSection& b) {
  return a.joints == b.joints && a.compliance == b.compliance && a.stiffness_ratio == b.stiffness_ratio &&
         a.samples == b.samples && a.range == b.range && a.closure_tolerance == b.closure_tolerance &&
         a.stationarity_tolerance == b.stationarity_tolerance;
}

}  // namespace

std::vector<double> ground_truth_energies(const std::vector<GroundTruthCase>& ground_truth, const LoopSection& loop) {
  std::vector<double> energies;
  energies.reserve(ground_truth.size());
  for (const GroundTruthCase& c : ground_truth) energies.push_back(ground_truth_energy(c, loop));
  return energies;
}

void TradeoffOptions::validate() const {
  if (starts < 1) fail("starts: must be >= 1, got " + std::to_string(starts));
  ground_truth.validate();
  for (int n : samples) {
    if (n < 4 || n > 100000) fail("samples: each must be in [4, 100000], got " + std::to_string(n));
  }
  for (double r : ranges_deg) {
    if (!(r > 0.0 && r <= 360.0)) fail("ranges_deg: each must be in (0, 360], got " + format_number(r));
  }
  for (double t : closure_tolerances) {
    if (!(t > 0.0 && t <= 1e-5)) fail("closure_tolerances: each must be in (0, 1e-5], got " + format_number(t));
  }
  for (const std::string& c : compliances) {
    if (c != "paper" && c != "full") fail("compliances: expected \"paper\" or \"full\", got \"" + c + "\"");
  }
  for (const std::string& o : objectives) {
    if (o != "mean" && o != "max") fail("objectives: expected \"mean\" or \"max\", got \"" + o + "\"");
  }
  for (const std::string& a : algorithms) {
    if (!is_known_algorithm(a)) fail("algorithms: unknown algorithm \"" + a + "\"");
  }
  for (double z : zero_thresholds) {
    if (!(z > 0.0 && z < 1.0)) fail("zero_thresholds: each must be in (0, 1), got " + format_number(z));
  }
  for (double f : ftol_rels) {
    if (!(f >= 0.0 && f < 1.0)) fail("ftol_rels: each must be in [0, 1), got " + format_number(f));
  }
  for (int w : progress_windows) {
    if (w < 0 || w > 100000000) fail("progress_windows: each must be in [0, 1e8], got " + std::to_string(w));
  }
  for (const auto& [evaluations, objective] : checkpoints) {
    if (evaluations < 0 || evaluations > 100000000) {
      fail("checkpoints: each one's evaluations must be in [0, 1e8], got " + std::to_string(evaluations));
    }
    if (evaluations > 0 && !(objective > 0.0)) {
      fail("checkpoints: each one's objective must be > 0, got " + format_number(objective));
    }
  }
  for (int steps : analysis_steps) {
    if (steps < 64 || steps > 100000)
      fail("analysis_steps: each must be in [64, 100000], got " + std::to_string(steps));
  }
}

double TradeoffRow::error_rate() const {
  const double judged = static_cast<double>(zeros + movable_cases + rigid_cases);
  if (judged == 0.0) return 0.0;
  return static_cast<double>(false_zeros + missed_zeros + rigid_read_as_zero + misanalysed) / judged;
}

double TradeoffRow::seconds_per_verified_zero() const {
  return verified > 0 ? (search_seconds + analysis_seconds) / static_cast<double>(verified)
                      : std::numeric_limits<double>::infinity();
}

std::vector<TradeoffConfiguration> tradeoff_configurations(const Job& base, const TradeoffOptions& options) {
  std::vector<TradeoffConfiguration> out;
  out.push_back({"base", "", base});
  auto add = [&](const std::string& axis, const std::string& value, auto change) {
    TradeoffConfiguration c{axis, value, base};
    change(c.job);
    out.push_back(std::move(c));
  };
  for (int n : options.samples) {
    if (n == base.loop.samples) continue;
    add("samples", std::to_string(n), [n](Job& job) { job.loop.samples = n; });
  }
  for (double r : options.ranges_deg) {
    // As the job file converts it (360 gives exactly 2 pi: a full turn).
    const double range = r / 360.0 * (2.0 * 3.14159265358979323846);
    if (range == base.loop.range) continue;
    add("range_deg", format_number(r), [range](Job& job) { job.loop.range = range; });
  }
  for (double t : options.closure_tolerances) {
    if (t == base.loop.closure_tolerance) continue;
    // Stationarity 100 times looser, as in the solver's defaults (1e-13, 1e-11).
    add("closure_tolerance", format_number(t), [t](Job& job) {
      job.loop.closure_tolerance = t;
      job.loop.stationarity_tolerance = std::min(1e-3, 100.0 * t);
    });
  }
  for (const std::string& c : options.compliances) {
    if (compliance_from_string(c) == base.loop.compliance) continue;
    add("compliance", c, [&c](Job& job) { job.loop.compliance = compliance_from_string(c); });
  }
  for (const std::string& o : options.objectives) {
    if (o == base.loop.objective) continue;
    add("objective", o, [&o](Job& job) { job.loop.objective = o; });
  }
  for (const std::string& a : options.algorithms) {
    if (a == base.optimizer.algorithm) continue;
    add("algorithm", a, [&a](Job& job) { job.optimizer.algorithm = a; });
  }
  for (double f : options.ftol_rels) {
    if (f == base.optimizer.ftol_rel) continue;
    add("ftol_rel", format_number(f), [f](Job& job) { job.optimizer.ftol_rel = f; });
  }
  for (int w : options.progress_windows) {
    if (w == base.optimizer.progress_window) continue;
    add("progress_window", std::to_string(w), [w](Job& job) { job.optimizer.progress_window = w; });
  }
  for (const auto& [evaluations, objective] : options.checkpoints) {
    const OptimizerSection& o = base.optimizer;
    if (evaluations == o.checkpoint_evaluations && (evaluations == 0 || objective == o.checkpoint_objective)) continue;
    const std::string value = evaluations == 0 ? "0" : std::to_string(evaluations) + ":" + format_number(objective);
    add("checkpoint", value, [evaluations, objective](Job& job) {
      job.optimizer.checkpoint_evaluations = evaluations;
      job.optimizer.checkpoint_objective = evaluations == 0 ? 0.0 : objective;
    });
  }
  for (bool r : options.reuse_nearby_cycles) {
    if (r == base.optimizer.reuse_nearby_cycle) continue;
    add("reuse_nearby_cycle", r ? "true" : "false", [r](Job& job) { job.optimizer.reuse_nearby_cycle = r; });
  }
  for (double z : options.zero_thresholds) {
    if (z == base.search.zero_threshold) continue;
    add("zero_threshold", format_number(z), [z](Job& job) { job.search.zero_threshold = z; });
  }
  for (int steps : options.analysis_steps) {
    if (steps == out.front().analysis_steps_per_turn) continue;
    TradeoffConfiguration c{"analysis_steps", std::to_string(steps), base};
    c.analysis_steps_per_turn = steps;
    out.push_back(std::move(c));
  }
  return out;
}

TradeoffRow measure_configuration(const TradeoffConfiguration& configuration,
                                  const std::vector<GroundTruthCase>& ground_truth, const TradeoffOptions& options) {
  const auto begin = std::chrono::steady_clock::now();
  const std::vector<double> energies = ground_truth_energies(ground_truth, configuration.job.loop);
  TradeoffRow row = measure_configuration(configuration, ground_truth, energies, options);
  row.total_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - begin).count();
  return row;
}

TradeoffRow measure_configuration(const TradeoffConfiguration& configuration,
                                  const std::vector<GroundTruthCase>& ground_truth, const std::vector<double>& energies,
                                  const TradeoffOptions& options) {
  if (energies.size() != ground_truth.size()) {
    throw std::invalid_argument("measure_configuration: " + std::to_string(energies.size()) + " energies for " +
                                std::to_string(ground_truth.size()) + " ground-truth loops");
  }
  const auto begin = std::chrono::steady_clock::now();
  const Job& job = configuration.job;
  TradeoffRow row;
  row.axis = configuration.axis;
  row.value = configuration.value;

  // The search: the same start indices under every configuration.
  StartOptions start_options;
  start_options.analysis_steps_per_turn = configuration.analysis_steps_per_turn;
  std::vector<double> seconds;
  seconds.reserve(static_cast<size_t>(options.starts));
  for (long i = 0; i < options.starts; ++i) {
    const StartSummary s = run_start(job, static_cast<std::uint64_t>(i), start_options);
    seconds.push_back(s.seconds);
    row.search_seconds += s.seconds;
    row.analysis_seconds += s.analysis_seconds;
    ++row.starts;
    if (!s.zero) continue;
    ++row.zeros;
    if (s.candidate.verification.verified) {
      ++row.verified;
      row.worst_family_residual = std::max(row.worst_family_residual, s.candidate.classification.residual);
    } else {
      ++row.false_zeros;
    }
  }
  row.median_seconds = quantile(seconds, 0.5);
  row.p90_seconds = quantile(seconds, 0.9);

  // The ground truth, read with this configuration's loop settings and zero
  // threshold. Perturbed cases are grouped by size for the smallest
  // perturbation told apart.
  std::map<double, bool> every_told_apart;  // relative size -> all of that size read non-zero
  for (size_t i = 0; i < ground_truth.size(); ++i) {
    const GroundTruthCase& c = ground_truth[i];
    const bool reads_zero = energies[i] <= job.search.zero_threshold;  // false for NaN
    if (c.movable) {
      ++row.movable_cases;
      row.missed_zeros += !reads_zero;
      // Analysed as a zero found there would be (the search's Jacobian
      // serves only the local dimension, which is not judged here).
      const CandidateAnalysis a =
          analyse_zero(c.geometry, c.pose, Eigen::MatrixXd::Zero(1, 1), c.pose[0], start_options);
      row.misanalysed += !a.verification.verified || a.classification.family != expected_classification(c);
    } else {
      ++row.rigid_cases;
      row.rigid_read_as_zero += reads_zero;
      if (c.relative_perturbation > 0.0) {
        auto [it, inserted] = every_told_apart.emplace(c.relative_perturbation, true);
        it->second = it->second && !reads_zero;
      }
    }
  }
  // From the largest size down, while every case of each size is told apart.
  row.smallest_told_apart = std::numeric_limits<double>::infinity();
  for (auto it = every_told_apart.rbegin(); it != every_told_apart.rend() && it->second; ++it) {
    row.smallest_told_apart = it->first;
  }
  row.total_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - begin).count();
  return row;
}

void mark_pareto_front(std::vector<TradeoffRow>& rows) {
  for (TradeoffRow& r : rows) {
    r.pareto = std::none_of(rows.begin(), rows.end(), [&r](const TradeoffRow& o) {
      const bool no_worse = o.median_seconds <= r.median_seconds && o.error_rate() <= r.error_rate();
      const bool better = o.median_seconds < r.median_seconds || o.error_rate() < r.error_rate();
      return no_worse && better;
    });
  }
}

std::vector<TradeoffRow> run_tradeoff(const Job& base, const TradeoffOptions& options) {
  options.validate();
  const std::vector<GroundTruthCase> truth = generate_ground_truth(options.ground_truth);
  const std::vector<TradeoffConfiguration> configurations = tradeoff_configurations(base, options);
  // The ground truth's energies depend on the loop settings alone: the
  // configurations of the other axes (algorithm, ftol_rel, zero threshold,
  // objective) read those of an earlier configuration.
  std::vector<std::pair<LoopSection, std::vector<double>>> readings;
  std::vector<TradeoffRow> rows;
  rows.reserve(configurations.size());
  for (size_t k = 0; k < configurations.size(); ++k) {
    const auto begin = std::chrono::steady_clock::now();
    const LoopSection& loop = configurations[k].job.loop;
    auto known = std::find_if(readings.begin(), readings.end(),
                              [&loop](const auto& reading) { return same_reading(reading.first, loop); });
    if (known == readings.end()) known = readings.insert(readings.end(), {loop, ground_truth_energies(truth, loop)});
    rows.push_back(measure_configuration(configurations[k], truth, known->second, options));
    rows.back().total_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - begin).count();
    if (options.progress) {
      options.progress(static_cast<int>(k + 1), static_cast<int>(configurations.size()), configurations[k].name());
    }
  }
  mark_pareto_front(rows);
  return rows;
}

}  // namespace loopfarm
