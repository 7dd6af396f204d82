// Gauss-Newton for the outer problem: minimise E_mean = |r(x)|^2 / 2 over the
// box [lower, upper], r the stacked, stiffness-weighted deformations of the
// cycle and J = dr/dx from implicit differentiation (cycle.hpp).
//
// Where a movable geometry exists the residual vanishes at the minimum, and
// Gauss-Newton converges quadratically to it (docs/design.md, "Objective and
// local minimisation"); elsewhere it is a Levenberg-Marquardt method with
// Marquardt's diagonal scaling (lengths and twists have different units) and
// the damping rule of Nielsen (1999). Bounds are handled by projection:
// variables at a bound whose gradient points out of the box are held there
// for the step, the others solve the damped normal equations, and the trial
// point is clamped into the box.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

#include <Eigen/Cholesky>

#include "loopfarm/search/local_search.hpp"
#include "progress_watch.hpp"

namespace loopfarm {
namespace {

constexpr double kInitialDampingScale = 1e-3;  // mu0 = this * max diag(JᵀJ)
constexpr double kMaxDamping = 1e20;           // relative to the scaling: give up beyond

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

LocalSearchSummary minimize_gauss_newton(CycleObjective& objective, const Eigen::VectorXd& x0,
                                         const LocalSearchOptions& options) {
  const auto start_time = std::chrono::steady_clock::now();
  const OptimizerSection& opt = options.optimizer;
  const ParameterSpace& space = objective.space();
  const Eigen::VectorXd lower = space.lower_bounds();
  const Eigen::VectorXd upper = space.upper_bounds();
  const int k = static_cast<int>(x0.size());
  const int first_evaluation = objective.evaluations();
  auto evaluations = [&] { return objective.evaluations() - first_evaluation; };

  LocalSearchSummary summary;
  Eigen::VectorXd x = x0.cwiseMax(lower).cwiseMin(upper);
  Eigen::VectorXd r, trial_r;
  Eigen::MatrixXd J;
  ObjectiveValue current = objective.evaluate_residuals(x, r, &J);
  summary.x = x;
  if (!current.ok) {
    summary.status = SearchStatus::evaluation_failed;
    summary.message = "the loop cannot be assembled at the start geometry";
    summary.value = current.value;
    // No cycle was evaluated: no energy to report (not 0, which reads as a zero).
    summary.E_mean = summary.E_max = std::numeric_limits<double>::quiet_NaN();
    summary.evaluations = evaluations();
    summary.seconds = seconds_since(start_time);
    return summary;
  }

  auto finish = [&](SearchStatus status, const std::string& message) {
    summary.x = x;
    summary.value = current.value;
    summary.E_mean = current.E_mean;
    summary.E_max = current.E_max;
    summary.status = status;
    summary.message = message;
    summary.evaluations = evaluations();
    summary.seconds = seconds_since(start_time);
    // Leave the objective at the returned point (a rejected trial may have
    // been its last evaluation).
    if (objective.last_x() != x) {
      Eigen::VectorXd unused;
      objective.evaluate_residuals(x, unused, nullptr);
      summary.evaluations = evaluations();
    }
    return summary;
  };

  detail::ProgressWatch progress(opt);
  double mu = -1.0;  // set from the first JᵀJ
  double nu = 2.0;
  Eigen::VectorXd step = Eigen::VectorXd::Zero(k);
  for (int iteration = 1;; ++iteration) {
    if (current.value <= opt.stopval) return finish(SearchStatus::stopval_reached, "objective below stopval");
    if (evaluations() >= opt.max_evaluations) return finish(SearchStatus::maxeval_reached, "max_evaluations reached");
    if (progress.too_slow(evaluations(), current.value)) return finish(SearchStatus::slow_progress, progress.message());
    if (opt.time_limit > 0 && seconds_since(start_time) >= opt.time_limit) {
      return finish(SearchStatus::maxtime_reached, "time limit reached");
    }

    const Eigen::VectorXd gradient = J.transpose() * r;
    // Free set: variables not held at a bound by a gradient pointing out.
    std::vector<int> free;
    double projected_gradient = 0.0;
    for (int i = 0; i < k; ++i) {
      const bool held = (x[i] <= lower[i] && gradient[i] > 0.0) || (x[i] >= upper[i] && gradient[i] < 0.0);
      if (!held) {
        free.push_back(i);
        projected_gradient = std::max(projected_gradient, std::abs(gradient[i]));
      }
    }
    if (free.empty() || projected_gradient == 0.0) {
      return finish(SearchStatus::xtol_reached, "projected gradient vanished");
    }
    const int f = static_cast<int>(free.size());
    Eigen::MatrixXd Jf(J.rows(), f);
    Eigen::VectorXd gf(f);
    for (int c = 0; c < f; ++c) {
      Jf.col(c) = J.col(free[static_cast<size_t>(c)]);
      gf[c] = gradient[free[static_cast<size_t>(c)]];
    }
    const Eigen::MatrixXd normal = Jf.transpose() * Jf;
    // Marquardt's scaling, floored so that a parameter the residual does not
    // see (a zero column) still gets a bounded step.
    Eigen::VectorXd scaling = normal.diagonal().cwiseMax(1e-12 * std::max(1.0, normal.diagonal().maxCoeff()));
    if (mu < 0.0) mu = kInitialDampingScale;

    bool accepted = false;
    while (!accepted) {
      if (mu > kMaxDamping) return finish(SearchStatus::stalled, "no damped step decreased the objective");
      Eigen::MatrixXd damped = normal;
      damped.diagonal() += mu * scaling;
      const Eigen::LDLT<Eigen::MatrixXd> ldlt(damped);
      const Eigen::VectorXd df = ldlt.solve(-gf);
      step.setZero();
      for (int c = 0; c < f; ++c) step[free[static_cast<size_t>(c)]] = df[c];
      const Eigen::VectorXd trial = (x + step).cwiseMax(lower).cwiseMin(upper);
      const Eigen::VectorXd taken = trial - x;
      // Decrease the Gauss-Newton model predicts for the step actually taken.
      const double predicted = -(gradient.dot(taken) + 0.5 * (J * taken).squaredNorm());
      // The step is accepted only below this (ratio > 1e-4 below), so the
      // trial's cycle is given up as soon as its samples show it above:
      // about a third of the trials are rejected.
      const double ceiling = predicted > 0.0 ? current.value - 1e-4 * predicted : -1.0;
      const ObjectiveValue tried = objective.evaluate_residuals(trial, trial_r, nullptr, ceiling);
      const double actual = current.value - tried.value;
      const double ratio = predicted > 0.0 ? actual / predicted : -1.0;
      accepted = tried.ok && actual > 0.0 && ratio > 1e-4;
      if (options.trace) {
        SearchTraceRow row;
        row.iteration = iteration;
        row.evaluations = evaluations();
        row.value = tried.value;
        row.E_mean = tried.E_mean;
        row.gradient_norm = projected_gradient;
        row.step_norm = taken.cwiseAbs().maxCoeff();
        row.damping = mu;
        row.accepted = accepted;
        row.abandoned = tried.abandoned;
        options.trace(row);
      }
      ++summary.iterations;
      if (accepted) {
        const double previous = current.value;
        const double x_norm = x.norm();
        x = trial;
        current = tried;
        r = trial_r;
        // The cycle of the accepted point is the objective's last one: its
        // Jacobian costs one implicit differentiation, no new cycle.
        objective.residual_jacobian(J);
        mu *= std::max(1.0 / 3.0, 1.0 - std::pow(2.0 * ratio - 1.0, 3));
        nu = 2.0;
        if (current.value <= opt.stopval) return finish(SearchStatus::stopval_reached, "objective below stopval");
        if (taken.norm() <= opt.xtol_rel * (x_norm + opt.xtol_rel)) {
          return finish(SearchStatus::xtol_reached, "step below xtol_rel");
        }
        const double change = previous - current.value;
        if ((opt.ftol_rel > 0 && change <= opt.ftol_rel * std::abs(previous)) ||
            (opt.ftol_abs > 0 && change <= opt.ftol_abs)) {
          return finish(SearchStatus::ftol_reached, "objective change below ftol");
        }
      } else {
        mu *= nu;
        nu *= 2.0;
        if (taken.cwiseAbs().maxCoeff() == 0.0)
          return finish(SearchStatus::xtol_reached, "step vanished at the bounds");
        if (evaluations() >= opt.max_evaluations)
          return finish(SearchStatus::maxeval_reached, "max_evaluations reached");
        if (progress.too_slow(evaluations(), current.value))
          return finish(SearchStatus::slow_progress, progress.message());
        if (opt.time_limit > 0 && seconds_since(start_time) >= opt.time_limit) {
          return finish(SearchStatus::maxtime_reached, "time limit reached");
        }
      }
    }
  }
}

}  // namespace loopfarm
