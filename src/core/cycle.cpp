// The cycle energy (cycle.hpp): the elastic equilibrium followed over one
// cycle of the input by continuation, with bisection where a step fails;
// its derivatives are in cycle_derivatives.cpp.
#include "loopfarm/core/cycle.hpp"

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <tuple>

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

// A landing after a fold starts this many max_passive_step along the last
// tangent (see Stepper::land). Over the bench's 8 generic 4R cycles at
// N = 32 (bench/cycle_breakdown), with the tangent start tried first,
// reaches of 0.2, 0.5, 1 and 2 gave 2176, 2088, 1972 and 1901 Newton
// iterations (2305 with no tangent start), the last with every landing
// converged; with the budgeted solve from the last point tried first, as
// land() does, 2021.
constexpr double kLandingReach = 2.0;

// Gauss-Newton steps a solve may take before it is given up (see
// solve_equilibrium): such steps mean the exact Hessian is not positive
// definite on the constraints' null space, which is where a solve that has
// left its branch creeps (10-20 iterations, mostly failing). A continuation
// step's solve gives up after kStepGaussNewtonSteps (the step is then
// bisected or lands), the landing's solve from the last point at its first
// (kLandingGaussNewtonSteps: where it converged on the paper's flat-folded
// loop it took none; the landing along the tangent follows). Over the
// bench's 8 generic 4R cycles at N = 32 (bench/cycle_breakdown): no limits
// 1,947 Newton iterations, the landing's limit alone 1,833, both 1,728 with
// a step limit of 8 (6: 1,746, 7: 1,766, 10: 1,750), every E_mean unchanged;
// step limits of 1-5 moved one loop's cycle to another branch (E_mean 1.01
// to 2.33).
constexpr int kStepGaussNewtonSteps = 8;
constexpr int kLandingGaussNewtonSteps = 0;

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
  //
  // `beyond_failure`: a solve at `target` from an earlier point of this
  // interval failed, and the first half of the interval was then reached in
  // one step, so what made it fail (a fold of the path, as a rule) lies
  // between `from` and `target`. The solve from `from` would fail too (on the
  // bench's generic loops it did at every depth, after its full budget or
  // converged to the far branch, too far to accept): with
  // CycleOptions::skip_failed_retries it is not tried, and the step bisects
  // straight on or, at the finest depth, lands.
  //
  // `stepping_stone`: `target` is a bisection's midpoint, not a sample: its
  // solve may end at CycleOptions::stepping_tolerance.
  Result step(const PathPoint& from, const PathPoint* before, double target, int depth, bool beyond_failure = false,
              bool stepping_stone = false) const {
    Result r;
    if (before != nullptr && before->theta == from.theta) before = nullptr;
    const double h = target - from.theta;
    const bool can_refine = depth < options_.max_refinements;
    const bool known_failure = options_.skip_failed_retries && beyond_failure;
    const bool predicted = options_.predictor && (from.tangent != nullptr || before != nullptr);
    // Step control from the path's own shape: bisect before solving where
    // the tangent says the passive angles would move too far, or where the
    // cubic prediction leaves the tangent line by more than kMaxBend of that
    // (the path bends within the step: the prediction is not to be trusted).
    const bool tangent_too_long =
        from.tangent != nullptr && std::abs(h) * passive_rate(model_, *from.tangent) > options_.max_passive_step;
    bool too_long = can_refine && (known_failure || tangent_too_long);
    EquilibriumState guess;
    if (!too_long && !known_failure) {  // a solve will be tried: its start
      if (predicted) {
        const double bend = predict(from, before, h, guess);
        too_long = can_refine && bend > kMaxBend * options_.max_passive_step;
      } else {
        guess = *from.state;
      }
    }
    bool failed_here = false;  // a solve at `target` from `from` was tried and rejected
    if (!too_long) {
      // A warm-started solve that needs many iterations has lost the branch:
      // bisecting is cheaper than letting it wander.
      if (known_failure) {
        r.solve.status = SolveStatus::max_iterations;  // as the skipped solve would end
      } else {
        SolveLimits limits;
        limits.max_iterations = options_.max_iterations_per_step;
        limits.max_gauss_newton_steps = kStepGaussNewtonSteps;
        if (stepping_stone) limits.stepping_tolerance = options_.stepping_tolerance;
        r.solve = solve_equilibrium(model_, ws_, target, guess, limits);
        r.iterations += r.solve.iterations;
        if (acceptable(r.solve, *from.state)) {
          r.status = SampleStatus::converged;
          return r;
        }
      }
      failed_here = true;
      // A step that fails from its prediction is bisected, not retried from
      // `from`: with the tangent predictor such a retry never succeeded on
      // the bench's generic loops (18 tries, 316 iterations, none accepted).
      if (!can_refine) {
        // The equilibrium branch ends here (a fold of the elastic path) or the
        // solve is hard: a landing (land() below), and whatever it lands on
        // is a jump to another branch. Where the budgeted solve has already converged (to a point
        // too far away: the jump itself) that solve is the landing: solving
        // again from the last point took 10-75 Newton iterations, mostly
        // linearly converging Gauss-Newton steps, and on the bench's generic
        // loops and the paper's figures always landed on the same
        // equilibrium (energies equal to 10 digits), 7 % of a generic cycle's
        // iterations.
        if (r.solve.status != SolveStatus::converged) {
          r.solve = land(from, target);
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
    Result half = step(from, before, mid, depth + 1, false, true);
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
    Result rest = step(midpoint, behind, target, depth + 1,
                       (failed_here || beyond_failure) && half.status == SampleStatus::converged, stepping_stone);
    rest.iterations += r.iterations;
    rest.refinements += r.refinements;
    if (rest.status == SampleStatus::converged) rest.status = SampleStatus::refined;
    if (half.status == SampleStatus::branch_jump && rest.status != SampleStatus::failed) {
      rest.status = SampleStatus::branch_jump;
    }
    return rest;
  }

 private:
  // The solve at `target` after the branch through `from` has ended (a fold
  // of the elastic path, or a hard step at the finest refinement): whatever
  // it converges to is the equilibrium the loop snaps to. First from `from`
  // itself with the step budget, which near a singular pose (the paper's
  // flat-folded loop) stays on the branch, given up at its first
  // Gauss-Newton step (kLandingGaussNewtonSteps). Where that does not converge,
  // `from` is a near-degenerate saddle of the energy on the constraint
  // manifold (the fold): the gradient there is tiny and the exact Hessian
  // indefinite, and the Gauss-Newton steps that replace it creep (they took
  // 39-100 iterations on the bench's generic loops, two of them not
  // converging within 100). Near a fold the path tangent is large along the
  // direction in which the branch leaves, which is where the snap goes: a
  // start moved kLandingReach * max_passive_step along it is past the
  // saddle, and the solve from there converged in 6-12 iterations to the
  // same energies (to 6 digits) where the creeping solve converged. Where
  // the tangent is missing or that solve fails too, the creeping solve with
  // the full iteration limit.
  EquilibriumSummary land(const PathPoint& from, double target) const {
    SolveLimits limits;
    limits.max_iterations = options_.max_iterations_per_step;
    limits.max_gauss_newton_steps = kLandingGaussNewtonSteps;
    EquilibriumSummary summary = solve_equilibrium(model_, ws_, target, *from.state, limits);
    if (summary.status == SolveStatus::converged) return summary;
    int iterations = summary.iterations, evaluations = summary.residual_evaluations;
    auto count = [&](const EquilibriumSummary& s) {
      iterations += s.iterations;
      evaluations += s.residual_evaluations;
    };
    const double rate = from.tangent != nullptr ? passive_rate(model_, *from.tangent) : 0.0;
    if (rate > 0.0 && std::isfinite(rate)) {
      const double s = kLandingReach * options_.max_passive_step / rate;
      EquilibriumState guess = *from.state;
      guess.theta += s * from.tangent->theta;
      guess.deformations += s * from.tangent->deformations;
      summary = solve_equilibrium(model_, ws_, target, guess);
      count(summary);
    }
    if (summary.status != SolveStatus::converged) {
      summary = solve_equilibrium(model_, ws_, target, *from.state);
      count(summary);
    }
    summary.iterations = iterations;
    summary.residual_evaluations = evaluations;
    return summary;
  }

  bool acceptable(const EquilibriumSummary& s, const EquilibriumState& from) const {
    return s.status == SolveStatus::converged && passive_change(model_, s.state, from) <= options_.max_passive_step;
  }

  const LoopModel& model_;
  EquilibriumWorkspace& ws_;
  const CycleOptions& options_;
};

// The running lower bounds of a cycle's energies against a CycleCeiling:
// the samples solved so far, the failed ones left out (their energies, not
// negative either, are unreliable).
class CeilingWatch {
 public:
  CeilingWatch(const CycleCeiling& ceiling, int samples) : ceiling_(ceiling), samples_(samples) {}
  bool bounded() const { return ceiling_.mean < kInfinity || ceiling_.max < kInfinity || ceiling_.failed_sample; }
  // Adds a solved sample; true once the cycle is known to exceed the ceiling.
  bool exceeded_after(const CycleSample& sample) {
    if (sample.status == SampleStatus::failed) return ceiling_.failed_sample;
    sum_ += sample.energy;
    max_ = std::max(max_, sample.energy);
    return sum_ / samples_ > ceiling_.mean || max_ > ceiling_.max;
  }
  void abandon(CycleSummary& summary) const {
    summary.E_mean = sum_ / samples_;
    summary.E_max = max_;
    summary.abandoned = true;
  }

 private:
  static constexpr double kInfinity = std::numeric_limits<double>::infinity();
  const CycleCeiling& ceiling_;
  double samples_;
  double sum_ = 0.0;
  double max_ = 0.0;
};

// The summary's energies and counts from its samples.
void summarize_samples(CycleSummary& summary) {
  const double N = static_cast<double>(summary.samples.size());
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
  if (!(stepping_tolerance >= 0.0) || !std::isfinite(stepping_tolerance)) {
    fail("stepping_tolerance: must be a finite number >= 0, got " + std::to_string(stepping_tolerance));
  }
}

const char* to_string(SampleStatus status) {
  switch (status) {
    case SampleStatus::converged:
      return "converged";
    case SampleStatus::refined:
      return "refined";
    case SampleStatus::branch_jump:
      return "branch_jump";
    case SampleStatus::failed:
      return "failed";
  }
  return "unknown";
}

void cycle_energy(const LoopModel& model, EquilibriumWorkspace& ws, double theta0, const EquilibriumState& start,
                  const CycleOptions& options, CycleSummary& summary, const CycleCeiling& ceiling) {
  options.validate();
  const int N = options.samples;
  summary.samples.resize(static_cast<size_t>(N));
  summary.abandoned = false;
  CeilingWatch watch(ceiling, N);
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
        if (watch.exceeded_after(summary.samples[static_cast<size_t>(j)])) {
          watch.abandon(summary);
          return;
        }
        continue;
      }
      const PathPoint before = point(previous, previous_theta);
      Stepper::Result& r = slots[static_cast<size_t>(next)];
      r = stepper.step(point(from, from_theta), have_previous ? &before : nullptr, target, 0);
      record(j, r);
      if (watch.exceeded_after(summary.samples[static_cast<size_t>(j)])) {
        watch.abandon(summary);
        return;
      }
      if (r.status == SampleStatus::failed) continue;
      std::tie(previous, from, next) = std::make_tuple(from, next, previous);
      previous_theta = from_theta;
      have_previous = r.status != SampleStatus::branch_jump;
      from_theta = target;
    }
  }

  if (!anchor_recorded) summary.total_iterations += anchor.iterations;
  summarize_samples(summary);
}

bool cycle_energy_from_nearby(const LoopModel& model, EquilibriumWorkspace& ws, const CycleSummary& nearby,
                              const CycleOptions& options, CycleSummary& summary, const CycleCeiling& ceiling) {
  const int N = options.samples;
  if (static_cast<int>(nearby.samples.size()) != N || nearby.failed_samples > 0) {
    return false;
  }
  summary.samples.resize(static_cast<size_t>(N));
  summary.total_iterations = 0;
  summary.refinements = 0;
  summary.abandoned = false;
  CeilingWatch watch(ceiling, N);
  // Against a ceiling, nearby's most costly sample first; then the others in
  // order (the samples are independent solves: the order changes nothing else).
  int first = 0;
  if (watch.bounded()) {
    for (int j = 1; j < N; ++j) {
      if (nearby.samples[static_cast<size_t>(j)].energy > nearby.samples[static_cast<size_t>(first)].energy) first = j;
    }
  }
  for (int k = 0; k < N; ++k) {
    const int j = k == 0 ? first : (k <= first ? k - 1 : k);
    const CycleSample& from = nearby.samples[static_cast<size_t>(j)];
    if (from.state.theta.size() != model.joints() || from.state.deformations.size() != model.deformation_count()) {
      return false;  // another model's cycle
    }
    const EquilibriumSummary solve =
        solve_equilibrium(model, ws, from.theta_in, from.state, {.max_iterations = options.max_iterations_per_step});
    summary.total_iterations += solve.iterations;
    // A sample that needs the continuation's help, or that moved far enough
    // to have crossed onto another branch, sends the caller back to the walk.
    // The step rule of the walk, applied to the change of geometry: no
    // passive angle may move by more than max_passive_step. The deformations
    // count too: where they are cheap (a tiny torsion ratio), a solve can
    // keep its angles and slide into another local minimum by a large twist
    // deformation. 400 generic 4R starts at the default settings (before
    // jumped samples were followed too): a limit of a quarter, a half and
    // all of max_passive_step gave 1.10, 1.02 and 0.92 ms median per local
    // minimisation, and 252, 255, 257 verified zeros. Twice it (1 rad) saves
    // 11 % of the default job's instructions, but a sample may then settle on
    // another circuit of the rigid motion: a rocker's window of samples came
    // to reach past the range of the circuit that was verified.
    const double limit = options.max_passive_step;
    if (solve.status != SolveStatus::converged || passive_change(model, from.state, solve.state) > limit ||
        (solve.state.deformations - from.state.deformations).lpNorm<Eigen::Infinity>() > limit) {
      return false;
    }
    CycleSample& s = summary.samples[static_cast<size_t>(j)];
    s.theta_in = from.theta_in;
    s.energy = solve.energy;
    // A sample the walk reached by a jump stays one: its branch is followed
    // continuously in the geometry, but it is still not joined to the
    // sample before it.
    s.status = from.status == SampleStatus::branch_jump ? SampleStatus::branch_jump : SampleStatus::converged;
    s.solve_status = solve.status;
    s.iterations = solve.iterations;
    s.refinements = 0;
    s.closure_residual = solve.closure_residual;
    s.state = solve.state;
    if (watch.exceeded_after(s)) {
      watch.abandon(summary);
      return true;
    }
  }
  summarize_samples(summary);
  return true;
}

}  // namespace loopfarm
