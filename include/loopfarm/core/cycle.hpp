// The cycle energy: the input joint driven through a full turn (or a range
// around theta0) in N samples, each sample's stiff-limit equilibrium solved by
// continuation from the previous one.
//
// E_mean, the mean of the sample energies, is the smooth objective of the
// geometry search; E_max is the paper's peak energy. Their derivatives with
// respect to the geometry come from the solved multipliers (envelope theorem,
// cycle_energy_gradient), and the Jacobian of the stacked, stiffness-weighted
// deformations from implicit differentiation of each sample's KKT system
// (cycle_deformation_jacobian), for Gauss-Newton on the outer problem.
#pragma once

#include <limits>
#include <vector>

#include "loopfarm/core/equilibrium.hpp"

namespace loopfarm {

struct CycleOptions {
  int samples = 32;  // N, at least 2
  // Input range covered: a full turn (2 pi, the default) samples
  // theta0 + 2 pi j / N; a smaller range samples [theta0 - range/2,
  // theta0 + range/2] at N evenly spaced points, walked outward from theta0.
  double range = 2.0 * 3.14159265358979323846;
  // A step whose passive angles move by more than this [rad] is refined by
  // bisection, as is a step whose solve fails; where the path tangent
  // foretells such a move, or the prediction bends away from the tangent
  // line, the step is bisected before it is tried.
  double max_passive_step = 0.5;
  int max_refinements = 5;  // bisection depth per step (finest step h / 32)
  // Iteration cap of a continuation solve; a step that needs more is bisected.
  int max_iterations_per_step = 20;
  // Start each solve from a prediction along the path: the cubic through the
  // last two samples and their solved tangents (error O(h^4)), the tangent
  // alone after a jump, the secant where no tangent is known. Off: from the
  // last sample itself (and no bend control), for comparison.
  bool predictor = true;
  // Where a step's solve failed and the first half of its interval was then
  // reached in one step, the failure lies in the second half: the solve at
  // the step's end is not tried again from the midpoint, which bisects
  // straight on, and at the finest depth goes to the landing (whose first
  // solve is from the last point). Off: every depth retries it, for
  // comparison.
  bool skip_failed_retries = true;
  // A bisection's midpoints are no samples, only stepping stones to the next
  // solve: their solves end once closure and stationarity are both at most
  // this (see SolveLimits::stepping_tolerance); samples are always solved to
  // the model's tolerances. 0: midpoints too, for comparison.
  double stepping_tolerance = 1e-6;

  bool full_turn() const;
  // Throws std::invalid_argument naming the first invalid option.
  void validate() const;
};

enum class SampleStatus {
  converged,    // solved from the continuation, no refinement needed
  refined,      // solved after the step was bisected
  branch_jump,  // solved, but the passive angles jumped even at the finest step
  failed,       // the equilibrium solve did not converge (energy unreliable)
};
const char* to_string(SampleStatus status);

struct CycleSample {
  double theta_in = 0.0;  // input angle [rad]
  double energy = 0.0;    // E / (k_a L^2)
  SampleStatus status = SampleStatus::failed;
  SolveStatus solve_status = SolveStatus::max_iterations;
  int iterations = 0;   // Newton iterations, refinement steps included
  int refinements = 0;  // bisections spent reaching this sample
  double closure_residual = 0.0;
  EquilibriumState state;  // angles, deformations, multipliers
};

struct CycleSummary {
  double E_mean = 0.0;
  double E_max = 0.0;
  int failed_samples = 0;
  int branch_jumps = 0;
  int total_iterations = 0;
  int refinements = 0;
  double max_closure_residual = 0.0;
  std::vector<CycleSample> samples;  // in input-angle order
  // The cycle was given up above a CycleCeiling: E_mean and E_max are the
  // lower bounds its solved samples gave, and the other samples were not
  // solved (their entries are stale).
  bool abandoned = false;
};

// Energies above which a cycle need not be finished: once the samples solved
// so far show E_mean > mean (their energies summed over N) or E_max > max
// (one of them above it), the cycle is abandoned. A local search that rejects
// every trial point worse than its current one knows its ceiling before the
// cycle; the samples are never negative, so a partial sum is a lower bound.
struct CycleCeiling {
  double mean = std::numeric_limits<double>::infinity();
  double max = std::numeric_limits<double>::infinity();
  // A failed sample abandons the cycle too, for a caller that rejects every
  // cycle with one: its energy is wherever the solve stopped, no bound on
  // anything, and the walk would go on bisecting towards the samples after it.
  bool failed_sample = false;
};

// Where the stiff-limit equilibrium path folds (a sample with status
// branch_jump) or does not return to its start after a full turn, the cycle
// depends on the direction the input is driven in (reversing the loop's
// labels reverses it), and which branch a jump lands on can change with
// round-off. Such cycles are flagged (branch_jumps, refinements); read their
// energy as one of several possible. Smooth cycles are exact and independent
// of labelling, direction and scale (tests/core/cycle_test.cpp).
//
// Drives the loop from `start` (an assembled state at theta0, e.g. from
// assemble()) through the cycle. `summary` is reused: with the same N it does
// not allocate. The workspace must belong to `model`.
//
// With a finite `ceiling` the walk stops at the first sample after which the
// cycle is known to exceed it (CycleSummary::abandoned).
void cycle_energy(const LoopModel& model, EquilibriumWorkspace& workspace, double theta0, const EquilibriumState& start,
                  const CycleOptions& options, CycleSummary& summary, const CycleCeiling& ceiling = {});

// The cycle of a geometry near the one `nearby` was computed for (same
// theta0, options and model layout), from nearby's samples: each sample is
// solved from nearby's state at its input angle, without walking between
// samples, which for a small change of geometry costs a few Newton
// iterations a sample instead of a walk. Returns false when it cannot vouch
// for the result (nearby had failed samples, a sample did not
// converge within max_iterations_per_step, or a passive angle or a
// deformation moved by more than max_passive_step, the walk's own limit for
// one step, so far that it may have changed branch);
// `summary` is then unspecified and the caller walks with cycle_energy.
// A sample nearby reached by a branch jump keeps that status (and count):
// its branch is followed, but it is still not joined to its predecessor.
// With a finite `ceiling`, the sample of nearby's largest energy is solved
// first (it is the likeliest to tell), and the cycle is abandoned as soon as
// it is known to exceed the ceiling; that returns true, with
// CycleSummary::abandoned, though the samples not solved were not vouched for.
bool cycle_energy_from_nearby(const LoopModel& model, EquilibriumWorkspace& workspace, const CycleSummary& nearby,
                              const CycleOptions& options, CycleSummary& summary, const CycleCeiling& ceiling = {});

// dE_mean / d(a, alpha, d) in GeometryVector order, in the geometry's own units
// (per unit length, per radian), from each sample's multipliers; with
// `sample` >= 0, the derivative of that one sample's energy instead (of E_max
// at its argmax, where the max is differentiable).
GeometryVector cycle_energy_gradient(const LoopModel& model, EquilibriumWorkspace& workspace,
                                     const CycleSummary& summary, int sample = -1);

// The residual vector r of the outer least-squares problem, E_mean = 1/2 |r|^2:
// sample j's deformations weighted by sqrt(stiffness / N), stacked.
Eigen::VectorXd cycle_weighted_deformations(const LoopModel& model, const CycleSummary& summary);
// The same into `r`, resized as needed (no allocation when its size is unchanged).
void cycle_weighted_deformations(const LoopModel& model, const CycleSummary& summary, Eigen::VectorXd& r);

// d r / d(a, alpha, d): (N * deformation_count) x 3n, by implicit
// differentiation of every sample's KKT system. The same differentiation
// gives the joint angles' sensitivities: with `angle_jacobian`, row
// j * n + i holds d theta_i(sample j) / d(a, alpha, d) (zero for the input).
//
// Into `jacobian` (and `*angle_jacobian`), resized as needed: with the same
// N and model size a repeated call reuses their storage and does not allocate
// (every per-sample buffer has a fixed size).
void cycle_deformation_jacobian(const LoopModel& model, EquilibriumWorkspace& workspace, const CycleSummary& summary,
                                Eigen::MatrixXd& jacobian, Eigen::MatrixXd* angle_jacobian = nullptr);
// The same, returning a new matrix.
Eigen::MatrixXd cycle_deformation_jacobian(const LoopModel& model, EquilibriumWorkspace& workspace,
                                           const CycleSummary& summary, Eigen::MatrixXd* angle_jacobian = nullptr);

}  // namespace loopfarm
