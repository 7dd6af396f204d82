// Any NLopt algorithm on the search objective, by its NLopt name. The
// gradient-based ones (LD_*) get the exact gradient from the multipliers
// (envelope theorem); the derivative-free ones (LN_*, GN_*) only values.
//
// NLopt's C++ wrapper reports the negative outcomes as exceptions, some of
// which (roundoff_limited, forced_stop) still leave a usable best point: every
// outcome is mapped to a SearchStatus and the best point seen is kept, since
// after an exception the wrapper's x need not hold it.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <new>
#include <stdexcept>
#include <vector>

#include <nlopt.hpp>

#include "loopfarm/search/local_search.hpp"
#include "progress_watch.hpp"

namespace loopfarm {
namespace {

struct Context {
  CycleObjective* objective = nullptr;
  const LocalSearchOptions* options = nullptr;
  int first_evaluation = 0;
  Eigen::VectorXd best_x;
  ObjectiveValue best;
  bool have_best = false;
  detail::ProgressWatch* progress = nullptr;
  bool too_slow = false;  // the progress stop forced NLopt to stop
};

double objective_function(unsigned k, const double* x, double* grad, void* data) {
  Context& c = *static_cast<Context*>(data);
  // Some NLopt codes (Luksan's LBFGS) call again after a forced stop before
  // they return: no further cycle is evaluated.
  if (c.too_slow) {
    if (grad) std::fill(grad, grad + k, 0.0);
    return std::numeric_limits<double>::infinity();
  }
  const Eigen::Map<const Eigen::VectorXd> point(x, k);
  Eigen::VectorXd gradient;
  const ObjectiveValue v = c.objective->evaluate(point, grad ? &gradient : nullptr);
  if (grad) Eigen::Map<Eigen::VectorXd>(grad, k) = gradient;
  if (v.ok && (!c.have_best || v.value < c.best.value)) {
    c.best = v;
    c.best_x = point;
    c.have_best = true;
  }
  if (c.options->trace) {
    SearchTraceRow row;
    row.iteration = c.objective->evaluations() - c.first_evaluation;
    row.evaluations = row.iteration;
    row.value = v.value;
    row.E_mean = v.E_mean;
    row.gradient_norm = grad ? gradient.cwiseAbs().maxCoeff() : std::numeric_limits<double>::quiet_NaN();
    row.step_norm = std::numeric_limits<double>::quiet_NaN();
    row.damping = std::numeric_limits<double>::quiet_NaN();
    row.accepted = v.ok;
    c.options->trace(row);
  }
  // A geometry that cannot be assembled has no energy: +inf steers every
  // NLopt algorithm away from it (they compare values; none differentiates inf).
  const double value = v.ok ? v.value : std::numeric_limits<double>::infinity();
  if (c.progress->too_slow(c.objective->evaluations() - c.first_evaluation, value)) {
    c.too_slow = true;
    throw nlopt::forced_stop();
  }
  return value;
}

SearchStatus status_of(nlopt::result result) {
  switch (result) {
    case nlopt::SUCCESS:
      return SearchStatus::xtol_reached;
    case nlopt::STOPVAL_REACHED:
      return SearchStatus::stopval_reached;
    case nlopt::FTOL_REACHED:
      return SearchStatus::ftol_reached;
    case nlopt::XTOL_REACHED:
      return SearchStatus::xtol_reached;
    case nlopt::MAXEVAL_REACHED:
      return SearchStatus::maxeval_reached;
    case nlopt::MAXTIME_REACHED:
      return SearchStatus::maxtime_reached;
    case nlopt::ROUNDOFF_LIMITED:
      return SearchStatus::roundoff_limited;
    case nlopt::FORCED_STOP:
      return SearchStatus::forced_stop;
    case nlopt::INVALID_ARGS:
      return SearchStatus::invalid_args;
    case nlopt::OUT_OF_MEMORY:
      return SearchStatus::out_of_memory;
    default:
      return SearchStatus::failure;
  }
}

}  // namespace

LocalSearchSummary minimize_nlopt(CycleObjective& objective, const Eigen::VectorXd& x0,
                                  const LocalSearchOptions& options) {
  const auto start_time = std::chrono::steady_clock::now();
  const OptimizerSection& opt = options.optimizer;
  const ParameterSpace& space = objective.space();
  const Eigen::VectorXd lower = space.lower_bounds();
  const Eigen::VectorXd upper = space.upper_bounds();
  const int k = static_cast<int>(x0.size());

  LocalSearchSummary summary;
  Context context;
  context.objective = &objective;
  context.options = &options;
  context.first_evaluation = objective.evaluations();
  detail::ProgressWatch progress(opt);
  context.progress = &progress;
  std::vector<double> x(x0.data(), x0.data() + k);
  for (int i = 0; i < k; ++i) x[static_cast<size_t>(i)] = std::clamp(x[static_cast<size_t>(i)], lower[i], upper[i]);

  try {
    nlopt::opt optimizer(opt.algorithm.c_str(), static_cast<unsigned>(k));
    optimizer.set_lower_bounds(std::vector<double>(lower.data(), lower.data() + k));
    optimizer.set_upper_bounds(std::vector<double>(upper.data(), upper.data() + k));
    optimizer.set_min_objective(objective_function, &context);
    if (opt.xtol_rel > 0) optimizer.set_xtol_rel(opt.xtol_rel);
    if (opt.ftol_rel > 0) optimizer.set_ftol_rel(opt.ftol_rel);
    if (opt.ftol_abs > 0) optimizer.set_ftol_abs(opt.ftol_abs);
    optimizer.set_stopval(opt.stopval);
    optimizer.set_maxeval(opt.max_evaluations);
    if (opt.time_limit > 0) optimizer.set_maxtime(opt.time_limit);
    // Stochastic algorithms seed from the clock unless told: seed from the
    // start, so a replayed start is identical.
    nlopt::srand(options.random_seed);
    double value = 0.0;
    const nlopt::result result = optimizer.optimize(x, value);
    summary.status = status_of(result);
    summary.message = std::string("NLopt: ") + nlopt_result_to_string(static_cast<nlopt_result>(result));
  } catch (const nlopt::roundoff_limited&) {
    summary.status = SearchStatus::roundoff_limited;
    summary.message = "NLopt: roundoff-limited (the best point so far is kept)";
  } catch (const nlopt::forced_stop&) {
    summary.status = SearchStatus::forced_stop;
    summary.message = "NLopt: forced stop";
  } catch (const std::bad_alloc&) {
    summary.status = SearchStatus::out_of_memory;
    summary.message = "NLopt: out of memory";
  } catch (const std::invalid_argument& e) {
    summary.status = SearchStatus::invalid_args;
    summary.message = std::string("NLopt: invalid arguments: ") + e.what();
  } catch (const std::runtime_error& e) {
    summary.status = SearchStatus::failure;
    summary.message = std::string("NLopt: failure: ") + e.what();
  }

  if (context.too_slow) {
    // Whatever the algorithm made of the forced stop (Luksan's LBFGS reports
    // a failure), the progress stop ended it.
    summary.status = SearchStatus::slow_progress;
    summary.message = progress.message();
  }
  summary.evaluations = objective.evaluations() - context.first_evaluation;
  summary.iterations = summary.evaluations;
  if (!context.have_best) {
    // Not one evaluation succeeded: the start itself cannot be assembled (or
    // NLopt refused before evaluating).
    if (summary.status != SearchStatus::invalid_args) summary.status = SearchStatus::evaluation_failed;
    if (summary.message.empty() || summary.status == SearchStatus::evaluation_failed) {
      summary.message = "the loop cannot be assembled at any evaluated geometry; " + summary.message;
    }
    summary.x = Eigen::Map<const Eigen::VectorXd>(x.data(), k);
    summary.value = std::numeric_limits<double>::infinity();
    summary.E_mean = summary.E_max = std::numeric_limits<double>::quiet_NaN();
  } else {
    summary.x = context.best_x;
    summary.value = context.best.value;
    summary.E_mean = context.best.E_mean;
    summary.E_max = context.best.E_max;
    // Leave the objective at the returned point.
    if (objective.last_x() != summary.x) {
      objective.evaluate(summary.x, nullptr);
      summary.evaluations = objective.evaluations() - context.first_evaluation;
    }
  }
  summary.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_time).count();
  return summary;
}

}  // namespace loopfarm
