#include "loopfarm/cycle.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>
#include <tuple>

#include <Eigen/Cholesky>
#include <Eigen/LU>

namespace loopfarm {
namespace {

constexpr double kTwoPi = 6.28318530717958647692;

[[noreturn]] void fail(const std::string& what) { throw std::invalid_argument(what); }

// Largest change of a passive angle between two states, modulo 2 pi.
double passive_change(const LoopModel& model, const EquilibriumState& a, const EquilibriumState& b) {
  double change = 0.0;
  for (int i = 0; i < model.joints(); ++i) {
    if (i == model.options().input_joint) continue;
    change = std::max(change, std::abs(wrap_angle(a.theta[i] - b.theta[i])));
  }
  return change;
}

// Step control: the largest departure of the cubic prediction from the
// tangent line accepted without bisecting, as a fraction of
// CycleOptions::max_passive_step. Newton iterations over the bench's 8
// generic 4R cycles at N = 32: 2782 at 0.04, 2793 at 0.1, 3222 at 0.4, 3456
// without this control; the energies are the same in all four.
constexpr double kMaxBend = 0.1;

// Largest rate of change of a passive angle along a path tangent.
double passive_rate(const LoopModel& model, const EquilibriumState& tangent) {
  double rate = 0.0;
  for (int i = 0; i < model.joints(); ++i) {
    if (i != model.options().input_joint) rate = std::max(rate, std::abs(tangent.theta[i]));
  }
  return rate;
}

// A solved point of the equilibrium path, with its tangent when the solve
// provided one.
struct PathPoint {
  const EquilibriumState* state = nullptr;
  const EquilibriumState* tangent = nullptr;  // d state / d theta_in, or null
  double theta = 0.0;
};

// The guess for the solve at from.theta + h. With tangents at `from` and
// `before`: the cubic Hermite polynomial through both points and tangents,
// error O(h^4); with a tangent at `from` only, a Taylor step along it
// (O(h^2)); without a tangent, the secant through `before` and `from`
// (O(h^2)). Angles are differenced modulo 2 pi.
double predict(const PathPoint& from, const PathPoint* before, double h, EquilibriumState& out) {
  const EquilibriumState& x = *from.state;
  out.theta = x.theta;
  out.deformations = x.deformations;
  out.multipliers = x.multipliers;
  if (from.tangent != nullptr) {
    const EquilibriumState& t = *from.tangent;
    if (before == nullptr || before->tangent == nullptr) {
      out.theta += h * t.theta;
      out.deformations += h * t.deformations;
      out.multipliers += h * t.multipliers;
      return 0.0;
    }
    // P(s) = x + t s + a s^2 + b s^3 with P(-p) = x_b, P'(-p) = t_b:
    // b = (2 (x_b - x) + (t + t_b) p) / p^3, a = (t - t_b) / (2 p) + 3/2 b p.
    const EquilibriumState& xb = *before->state;
    const EquilibriumState& tb = *before->tangent;
    const double p = from.theta - before->theta;
    auto extrapolate = [&](double x1, double x0, double t1, double t0) {
      const double cubic = (2.0 * (x0 - x1) + (t1 + t0) * p) / (p * p * p);
      const double quadratic = (t1 - t0) / (2.0 * p) + 1.5 * cubic * p;
      return h * (t1 + h * (quadratic + h * cubic));
    };
    double bend = 0.0;
    for (int i = 0; i < x.theta.size(); ++i) {
      // x_b - x modulo 2 pi: differences only, so the branch of each angle does not matter.
      const double move = extrapolate(0.0, wrap_angle(xb.theta[i] - x.theta[i]), t.theta[i], tb.theta[i]);
      out.theta[i] += move;
      bend = std::max(bend, std::abs(move - h * t.theta[i]));
    }
    for (int k = 0; k < x.deformations.size(); ++k) {
      out.deformations[k] += extrapolate(x.deformations[k], xb.deformations[k], t.deformations[k], tb.deformations[k]);
    }
    for (int k = 0; k < 6; ++k) {
      out.multipliers[k] += extrapolate(x.multipliers[k], xb.multipliers[k], t.multipliers[k], tb.multipliers[k]);
    }
    return bend;
  }
  if (before == nullptr) return 0.0;
  const EquilibriumState& b = *before->state;
  const double ratio = h / (from.theta - before->theta);
  for (int i = 0; i < x.theta.size(); ++i) out.theta[i] += ratio * wrap_angle(x.theta[i] - b.theta[i]);
  out.deformations += ratio * (x.deformations - b.deformations);
  out.multipliers += ratio * (x.multipliers - b.multipliers);
  return 0.0;
}

// Continuation from one solved input angle to the next, with bisection where a
// solve fails or the passive angles move too far for one step.
class Stepper {
 public:
  Stepper(const LoopModel& model, EquilibriumWorkspace& ws, const CycleOptions& options)
      : model_(model), ws_(ws), options_(options) {}

  struct Result {
    EquilibriumSummary solve;
    SampleStatus status = SampleStatus::failed;
    int iterations = 0;
    int refinements = 0;
  };

  // Steps from `from` to the input angle `target` (`before`, if given, is
  // the point before `from`, for the predictor).
  Result step(const PathPoint& from, const PathPoint* before, double target, int depth) const {
    Result r;
    if (before != nullptr && before->theta == from.theta) before = nullptr;
    const double h = target - from.theta;
    const bool can_refine = depth < options_.max_refinements;
    const bool predicted = options_.predictor && (from.tangent != nullptr || before != nullptr);
    // Step control from the path's own shape: bisect before solving where
    // the tangent says the passive angles would move too far, or where the
    // cubic prediction leaves the tangent line by more than kMaxBend of that
    // (the path bends within the step: the prediction is not to be trusted).
    bool too_long = can_refine && from.tangent != nullptr &&
                    std::abs(h) * passive_rate(model_, *from.tangent) > options_.max_passive_step;
    EquilibriumState guess;
    if (!too_long && predicted) {
      const double bend = predict(from, before, h, guess);
      too_long = can_refine && bend > kMaxBend * options_.max_passive_step;
    } else if (!too_long) {
      guess = *from.state;
    }
    if (!too_long) {
      // A warm-started solve that needs many iterations has lost the branch:
      // bisecting is cheaper than letting it wander.
      const int budget = options_.max_iterations_per_step;
      r.solve = solve_equilibrium(model_, ws_, target, guess, budget);
      r.iterations += r.solve.iterations;
      if (acceptable(r.solve, *from.state)) {
        r.status = SampleStatus::converged;
        return r;
      }
      // A step that fails from its prediction is bisected, not retried from
      // `from`: with the tangent predictor such a retry never succeeded on
      // the bench's generic loops (18 tries, 316 iterations, none accepted).
      if (!can_refine) {
        // The equilibrium branch ends here (a fold of the elastic path) or the
        // solve is hard: one solve from the last point of the branch with the
        // full iteration budget, and whatever it lands on is a jump to another
        // branch. Where the budgeted solve has already converged (to a point
        // too far away: the jump itself) that solve is the landing: solving
        // again from the last point took 10-75 Newton iterations, mostly
        // linearly converging Gauss-Newton steps, and on the bench's generic
        // loops and the paper's figures always landed on the same
        // equilibrium (energies equal to 10 digits), 7 % of a generic cycle's
        // iterations.
        if (r.solve.status != SolveStatus::converged) {
          r.solve = solve_equilibrium(model_, ws_, target, *from.state);
          r.iterations += r.solve.iterations;
        }
        if (acceptable(r.solve, *from.state)) {
          r.status = SampleStatus::converged;
        } else {
          r.status = r.solve.status == SolveStatus::converged ? SampleStatus::branch_jump : SampleStatus::failed;
        }
        return r;
      }
    }
    // Bisect: reach the midpoint, then the target from there.
    const double mid = 0.5 * (from.theta + target);
    Result half = step(from, before, mid, depth + 1);
    r.iterations += half.iterations;
    r.refinements += 1 + half.refinements;
    if (half.status == SampleStatus::failed) {
      half.iterations = r.iterations;
      half.refinements = r.refinements;
      return half;
    }
    const PathPoint midpoint{&half.solve.state, half.solve.has_tangent ? &half.solve.tangent : nullptr, mid};
    // Across a jump the point before lies on another branch: predict from
    // the landing point's own tangent only.
    const PathPoint* behind = half.status == SampleStatus::branch_jump ? nullptr : &from;
    Result rest = step(midpoint, behind, target, depth + 1);
    rest.iterations += r.iterations;
    rest.refinements += r.refinements;
    if (rest.status == SampleStatus::converged) rest.status = SampleStatus::refined;
    if (half.status == SampleStatus::branch_jump && rest.status != SampleStatus::failed) {
      rest.status = SampleStatus::branch_jump;
    }
    return rest;
  }

 private:
  bool acceptable(const EquilibriumSummary& s, const EquilibriumState& from) const {
    return s.status == SolveStatus::converged && passive_change(model_, s.state, from) <= options_.max_passive_step;
  }

  const LoopModel& model_;
  EquilibriumWorkspace& ws_;
  const CycleOptions& options_;};

// d normalised parameter / d parameter: p~ = p / L(p) for lengths, alpha unchanged.
Eigen::MatrixXd normalization_jacobian(const LoopModel& model) {
  const LoopGeometry& g = model.geometry();
  const int n = g.joints();
  const double L = model.length_scale();
  const GeometryVector dL = length_scale_gradient(g);
  Eigen::MatrixXd D = Eigen::MatrixXd::Identity(3 * n, 3 * n);
  for (int i = 0; i < n; ++i) {
    D(i, i) = 1.0 / L;
    D(2 * n + i, 2 * n + i) = 1.0 / L;
  }
  for (int j = 0; j < 3 * n; ++j) {
    for (int i = 0; i < n; ++i) {
      D(i, j) -= g.a[i] / (L * L) * dL[j];
      D(2 * n + i, j) -= g.d[i] / (L * L) * dL[j];
    }
  }
  return D;
}

// Chain element of geometric parameter j in GeometryVector order.
int parameter_element(int n, int j) {
  const int joint = j % n;
  switch (j / n) {
    case 0: return chain_index(joint, ChainParameter::a);
    case 1: return chain_index(joint, ChainParameter::alpha);
    default: return chain_index(joint, ChainParameter::d);
  }
}

}  // namespace

bool CycleOptions::full_turn() const { return range >= kTwoPi; }

void CycleOptions::validate() const {
  if (samples < 2) fail("samples: must be >= 2, got " + std::to_string(samples));
  if (!(range > 0.0) || !(range <= kTwoPi + 1e-12)) {
    fail("range: must be in (0, 360] degrees, got " + std::to_string(range * 360.0 / kTwoPi) + " degrees");
  }
  if (!(max_passive_step > 0.0) || !std::isfinite(max_passive_step)) {
    fail("max_passive_step: must be a finite number > 0, got " + std::to_string(max_passive_step));
  }
  if (max_refinements < 0 || max_refinements > 30) {
    fail("max_refinements: must be in [0, 30], got " + std::to_string(max_refinements));
  }
  if (max_iterations_per_step < 1) {
    fail("max_iterations_per_step: must be >= 1, got " + std::to_string(max_iterations_per_step));
  }
}

const char* to_string(SampleStatus status) {
  switch (status) {
    case SampleStatus::converged: return "converged";
    case SampleStatus::refined: return "refined";
    case SampleStatus::branch_jump: return "branch_jump";
    case SampleStatus::failed: return "failed";
  }
  return "unknown";
}

void cycle_energy(const LoopModel& model, EquilibriumWorkspace& ws, double theta0, const EquilibriumState& start,
                  const CycleOptions& options, CycleSummary& summary) {
  options.validate();
  const int N = options.samples;
  summary.samples.resize(static_cast<size_t>(N));
  const bool full = options.full_turn();
  for (int j = 0; j < N; ++j) {
    summary.samples[static_cast<size_t>(j)].theta_in =
        full ? theta0 + kTwoPi * j / N : theta0 + options.range * (static_cast<double>(j) / (N - 1) - 0.5);
  }

  const Stepper stepper(model, ws, options);
  // The anchor: the equilibrium at theta0 itself, from the given start.
  EquilibriumSummary anchor = solve_equilibrium(model, ws, theta0, start);
  if (options.predictor && anchor.status == SolveStatus::converged && !anchor.has_tangent) {
    // Started on the solution (no Newton step, so no tangent from one): the
    // first steps predict much better with it.
    anchor.has_tangent = equilibrium_tangent(model, ws, anchor.state, anchor.tangent);
  }
  summary.total_iterations = 0;
  summary.refinements = 0;

  auto record = [&](int j, const Stepper::Result& r) {
    CycleSample& s = summary.samples[static_cast<size_t>(j)];
    s.energy = r.solve.energy;
    s.status = r.status;
    s.solve_status = r.solve.status;
    s.iterations = r.iterations;
    s.refinements = r.refinements;
    s.closure_residual = r.solve.closure_residual;
    s.state = r.solve.state;
    summary.total_iterations += r.iterations;
    summary.refinements += r.refinements;
  };

  bool anchor_recorded = false;
  std::array<Stepper::Result, 3> slots;
  // Walk outward from the anchor: forward over the samples at or after theta0,
  // then backward over those before it (a partial range only). A failed
  // sample is skipped over: the walk goes on from the last solved one.
  for (int direction : {+1, -1}) {
    // The last solved point and the one before it, with their tangents, and
    // the slot the next step's result goes to: three slots in rotation, so
    // that no summary is copied to move along.
    slots[0].solve = anchor;
    int from = 0, previous = 1, next = 2;
    double from_theta = theta0;
    double previous_theta = theta0;
    bool have_previous = false;
    auto point = [&](int slot, double theta) {
      const EquilibriumSummary& s = slots[static_cast<size_t>(slot)].solve;
      return PathPoint{&s.state, s.has_tangent ? &s.tangent : nullptr, theta};
    };
    const int first = direction > 0 ? 0 : N - 1;
    for (int j = first; j >= 0 && j < N; j += direction) {
      const double target = summary.samples[static_cast<size_t>(j)].theta_in;
      if ((direction > 0) != (target >= theta0)) continue;
      if (target == theta0) {
        Stepper::Result at_anchor;
        at_anchor.solve = anchor;
        at_anchor.status = anchor.status == SolveStatus::converged ? SampleStatus::converged : SampleStatus::failed;
        at_anchor.iterations = anchor.iterations;
        anchor_recorded = true;
        record(j, at_anchor);
        continue;
      }
      const PathPoint before = point(previous, previous_theta);
      Stepper::Result& r = slots[static_cast<size_t>(next)];
      r = stepper.step(point(from, from_theta), have_previous ? &before : nullptr, target, 0);
      record(j, r);
      if (r.status == SampleStatus::failed) continue;
      std::tie(previous, from, next) = std::make_tuple(from, next, previous);
      previous_theta = from_theta;
      have_previous = r.status != SampleStatus::branch_jump;
      from_theta = target;
    }
  }

  if (!anchor_recorded) summary.total_iterations += anchor.iterations;

  summary.E_mean = 0.0;
  summary.E_max = 0.0;
  summary.failed_samples = 0;
  summary.branch_jumps = 0;
  summary.max_closure_residual = 0.0;
  for (const CycleSample& s : summary.samples) {
    summary.E_mean += s.energy / N;
    summary.E_max = std::max(summary.E_max, s.energy);
    summary.failed_samples += s.status == SampleStatus::failed;
    summary.branch_jumps += s.status == SampleStatus::branch_jump;
    summary.max_closure_residual = std::max(summary.max_closure_residual, s.closure_residual);
  }
}

GeometryVector cycle_energy_gradient(const LoopModel& model, EquilibriumWorkspace& ws, const CycleSummary& summary) {
  const int n = model.joints();
  const int N = static_cast<int>(summary.samples.size());
  Eigen::VectorXd normalized_gradient = Eigen::VectorXd::Zero(3 * n);
  for (const CycleSample& s : summary.samples) {
    // Envelope theorem: dE/dp~ = lambda^T dc/dp~ at the solution (the energy
    // itself does not depend on the geometry in normalised units).
    deformed_geometry(model, s.state.deformations, ws.deformed);
    compute_chain(ws.deformed, s.state.theta, ws.chain);
    for (int j = 0; j < 3 * n; ++j) {
      normalized_gradient[j] += s.state.multipliers.dot(residual_derivative(ws.chain, parameter_element(n, j))) / N;
    }
  }
  const Eigen::VectorXd gradient = normalization_jacobian(model).transpose() * normalized_gradient;
  return GeometryVector(gradient);
}

Eigen::VectorXd cycle_weighted_deformations(const LoopModel& model, const CycleSummary& summary) {
  const int m = model.deformation_count();
  const int N = static_cast<int>(summary.samples.size());
  Eigen::VectorXd r(N * m);
  for (int j = 0; j < N; ++j) {
    for (int k = 0; k < m; ++k) {
      r[j * m + k] = std::sqrt(model.deformation_stiffness(k) / N) * summary.samples[static_cast<size_t>(j)].state.deformations[k];
    }
  }
  return r;
}

Eigen::MatrixXd cycle_deformation_jacobian(const LoopModel& model, EquilibriumWorkspace& ws,
                                           const CycleSummary& summary, Eigen::MatrixXd* angle_jacobian) {
  const int n = model.joints();
  const int m = model.deformation_count();
  const int nu = model.unknown_count();
  const int np = 3 * n;
  const int N = static_cast<int>(summary.samples.size());
  Eigen::MatrixXd jacobian(N * m, np);
  if (angle_jacobian) angle_jacobian->setZero(N * n, np);  // the input angle's rows stay zero

  // Every chain element: unknowns and parameters share elements, so one
  // Hessian over the whole chain gives both W and the mixed block.
  std::array<int, kMaxChain> all{};
  for (int e = 0; e < kElementsPerJoint * n; ++e) all[static_cast<size_t>(e)] = e;
  const std::span<const int> elements(all.data(), static_cast<size_t>(kElementsPerJoint * n));

  Eigen::MatrixXd W(nu, nu), Lxp(nu, np), A(6, nu), Ap(6, np);
  for (int j = 0; j < N; ++j) {
    const CycleSample& s = summary.samples[static_cast<size_t>(j)];
    deformed_geometry(model, s.state.deformations, ws.deformed);
    compute_chain(ws.deformed, s.state.theta, ws.chain);
    residual_hessian(ws.chain, s.state.multipliers, elements, ws.chain_hessian);
    for (int u = 0; u < nu; ++u) {
      const int eu = model.unknown_element(u);
      A.col(u) = residual_derivative(ws.chain, eu);
      for (int v = 0; v < nu; ++v) W(u, v) = ws.chain_hessian(eu, model.unknown_element(v));
      const int k = model.unknown_deformation(u);
      if (k >= 0) W(u, u) += model.deformation_stiffness(k);
      for (int p = 0; p < np; ++p) Lxp(u, p) = ws.chain_hessian(eu, parameter_element(n, p));
    }
    for (int p = 0; p < np; ++p) Ap.col(p) = residual_derivative(ws.chain, parameter_element(n, p));

    // Differentiate the KKT conditions: [W Aᵀ; A 0] [dx; dl] = -[Lxp; Ap].
    // Solved through H = W + sigma AᵀA (positive definite at a regular
    // minimum), the right-hand side shifted by sigma Aᵀ Ap to match.
    double sigma = 1.0;
    Eigen::LLT<Eigen::MatrixXd> llt;
    for (int attempt = 0; attempt < 12; ++attempt, sigma *= 10.0) {
      llt.compute(W + sigma * A.transpose() * A);
      if (llt.info() == Eigen::Success) break;
    }
    const Eigen::MatrixXd Y = llt.solve(A.transpose());
    const Eigen::MatrixXd Z = llt.solve(-Lxp - sigma * A.transpose() * Ap);
    // The Schur complement is singular only where the closure Jacobian loses
    // rank; there the sensitivity is not defined and a pseudo-inverse is used.
    const Eigen::MatrixXd S = A * Y;
    const Eigen::MatrixXd rhs = A * Z + Ap;
    Eigen::MatrixXd dual;
    Eigen::LLT<Eigen::MatrixXd> schur(S);
    if (schur.info() == Eigen::Success) {
      dual = schur.solve(rhs);
    } else {
      dual = S.completeOrthogonalDecomposition().solve(rhs);
    }
    const Eigen::MatrixXd dx = Z - Y * dual;
    for (int u = 0; u < nu; ++u) {
      const int k = model.unknown_deformation(u);
      if (k >= 0) jacobian.row(j * m + k) = std::sqrt(model.deformation_stiffness(k) / N) * dx.row(u);
      const int joint = model.unknown_joint(u);
      if (angle_jacobian && joint >= 0) angle_jacobian->row(j * n + joint) = dx.row(u);
    }
  }
  const Eigen::MatrixXd normalization = normalization_jacobian(model);
  // Angles are dimensionless: they depend on the geometry only through the
  // normalised parameters, as the deformations do.
  if (angle_jacobian) *angle_jacobian = *angle_jacobian * normalization;
  return jacobian * normalization;
}

}  // namespace loopfarm
