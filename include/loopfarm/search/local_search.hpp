// Local minimisation of the search objective over the free geometric
// parameters within their bounds: Gauss-Newton (a bounded Levenberg-Marquardt
// on the stacked deformations, src/search/gauss_newton.cpp) or any NLopt algorithm
// by its NLopt name (src/search/nlopt_search.cpp), both fed exact derivatives.
//
// Options -> local_minimize -> LocalSearchSummary. Every way a run can end,
// NLopt's outcomes and exceptions included, maps to a SearchStatus.
#pragma once

#include <cstdint>
#include <functional>
#include <string>

#include <Eigen/Core>

#include "loopfarm/search/job.hpp"
#include "loopfarm/search/objective.hpp"

namespace loopfarm {

enum class SearchStatus {
  stopval_reached,   // the objective fell below stopval (a zero, for a zero threshold above it)
  ftol_reached,      // the objective stopped changing (ftol_rel / ftol_abs)
  xtol_reached,      // the step became negligible (xtol_rel), or the projected gradient vanished
  maxeval_reached,   // max_evaluations spent
  slow_progress,     // the best objective fell by less than progress_factor over progress_window evaluations
  maxtime_reached,   // time_limit spent
  roundoff_limited,  // NLopt: no further progress possible in floating point (x kept)
  stalled,           // Gauss-Newton: no damped step decreased the objective
  forced_stop,       // NLopt stopped by a forced stop
  failure,           // NLopt reported a generic failure
  invalid_args,      // NLopt rejected the arguments (e.g. an algorithm not built in)
  out_of_memory,
  evaluation_failed,  // the objective could not be evaluated at the start (no assembly)
};
const char* to_string(SearchStatus status);

// One objective evaluation (NLopt) or one accepted or rejected step (Gauss-Newton).
struct SearchTraceRow {
  int iteration = 0;
  int evaluations = 0;
  double value = 0.0;  // the objective (steered E_mean)
  double E_mean = 0.0;
  double gradient_norm = 0.0;  // max-norm of the (projected) gradient; NaN where not computed
  double step_norm = 0.0;      // max-norm of the step taken; NaN where not known
  double damping = 0.0;        // Levenberg-Marquardt parameter; NaN for NLopt
  bool accepted = true;
  bool abandoned = false;  // rejected before its cycle was finished: value and E_mean are lower bounds
};

struct LocalSearchOptions {
  OptimizerSection optimizer;
  std::uint64_t random_seed = 0;                     // for NLopt's stochastic algorithms (nlopt::srand)
  std::function<void(const SearchTraceRow&)> trace;  // called per row when set
};

struct LocalSearchSummary {
  Eigen::VectorXd x;    // best point found (free parameters)
  double value = 0.0;   // objective there
  double E_mean = 0.0;  // unsteered cycle energy there; NaN for evaluation_failed
  double E_max = 0.0;
  SearchStatus status = SearchStatus::failure;
  std::string message;  // what the algorithm said, for people
  int evaluations = 0;  // cycle evaluations
  int iterations = 0;   // Gauss-Newton steps tried; NLopt: evaluations
  double seconds = 0.0;
};

// Dispatches on optimizer.algorithm ("gauss-newton" or an NLopt name).
// `x0` is clamped into [lower, upper]. The objective's last evaluation is left
// at the returned x.
LocalSearchSummary local_minimize(CycleObjective& objective, const Eigen::VectorXd& x0,
                                  const LocalSearchOptions& options);

LocalSearchSummary minimize_gauss_newton(CycleObjective& objective, const Eigen::VectorXd& x0,
                                         const LocalSearchOptions& options);
LocalSearchSummary minimize_nlopt(CycleObjective& objective, const Eigen::VectorXd& x0,
                                  const LocalSearchOptions& options);

}  // namespace loopfarm
