// Polishing a geometry onto its motion: the nearby loop that closes exactly
// at many poses along a traced circuit.
//
// A zero of the sampled cycle energy closes its sample poses, but where the
// search stops is only as accurate as the energy can tell: near some zeros the
// closure gap grows with the square of the distance to the movable loop, and
// a geometry 1e-8 of L away closes to 1e-11 along its whole circuit, within
// the tracer's tolerance. The tracer then follows it around the circuit
// through its pose, while a finer or wider trace elsewhere on its motion loses
// the thin tube of near-closed poses. polish_geometry moves such a geometry
// onto the movable loop it approximates, or reports that none is near.
//
// The unknowns are the geometry's parameters along given directions (a job's
// free parameters, ties included) and the joint angles of every pose; the
// equations are the closure of every pose. Gauss-Newton with the poses
// eliminated: at a pose on a motion with f freedoms, the closure Jacobian J_i
// with respect to the joint angles has rank n - f, and the part U2_i^T F_i of
// the residual in its left null space cannot be removed by moving the pose,
// only by moving the geometry. Stacked over the poses,
//
//     U2_i^T (F_i + B_i D dx) = 0,   B_i = d F_i / d(a, alpha, d),
//
// is solved for the step dx in least squares (minimum norm: directions the
// closures do not see, such as the overall scale, do not move), and every
// pose is then corrected onto the new geometry by Moore-Penrose Newton.
//
// Why this certifies a motion: a loop that does not move closes at finitely
// many poses (a 6R at most 16 assemblies in all), so a geometry that closes to
// round-off at many poses spread along a circuit moves. A near miss, closing
// within the tolerance along a tube but not exactly, keeps its floor: the
// polish does not converge, or runs away from the geometry it was given.
//
// Lengths are divided by the length scale L of the given geometry, so the
// residuals and the displacement are dimensionless (lengths / L, angles in
// radians), as everywhere in the motion's code.
#pragma once

#include <span>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "loopfarm/core/loop.hpp"

namespace loopfarm {

struct GeometryPolishOptions {
  // Max-norm of the closure residual at every pose for the polish to have
  // converged: round-off, where a loop with a motion ends and a near miss
  // does not get to.
  double target_residual = 1e-13;
  int max_iterations = 30;
  // The polish stops, not converged, when the worst residual has not fallen
  // to half its best over this many iterations (a near miss's floor). Near a
  // singular set of movable loops Gauss-Newton converges linearly and not
  // monotonically: start 1191 of the generic 6R job goes 1.1e-11, 3.2e-12,
  // 5.2e-12, 2.1e-11, 4.1e-12, 2.9e-12, ..., 4.4e-13 (the 8th), 6.9e-14.
  int stall_iterations = 8;
  // Largest change of any parameter (dimensionless) the polish may make: a
  // geometry farther than this from a movable loop is not one of its zeros.
  double max_displacement = 1e-4;
  // A singular value of the stacked step system below this fraction of its
  // largest counts as zero (its direction is not moved).
  double rank_tolerance = 1e-9;
  // A pose whose closure Jacobian has its (n - f)-th singular value below
  // this fraction of its largest is near a singular pose of the motion and
  // is not used (its left null space is not the motion's).
  double min_singular_ratio = 1e-6;
  // Throws std::invalid_argument naming the first invalid option.
  void validate() const;
};

// The parameters a polish may move: the geometry changes by directions * dx,
// each direction a column in GeometryVector order (a_1..a_n, alpha_1..alpha_n,
// d_1..d_n; the geometry's units), with lower <= dx <= upper (componentwise;
// infinite bounds allowed). A component that reaches its bound is held there.
struct PolishDirections {
  Eigen::MatrixXd directions;
  Eigen::VectorXd lower;
  Eigen::VectorXd upper;

  // Every parameter, each its own direction, with lengths kept >= 0.
  static PolishDirections every_parameter(const LoopGeometry& geometry);
};

struct GeometryPolishSummary {
  bool converged = false;
  LoopGeometry geometry;           // polished; the given geometry when not converged
  Eigen::VectorXd step;            // dx: the change along each direction
  std::vector<JointVector> poses;  // the poses used, closed on `geometry` when converged
  int poses_used = 0;              // given poses regular enough to be used
  int iterations = 0;
  double initial_residual = 0.0;  // max-norm over the poses used, before and after
  double final_residual = 0.0;
  double displacement = 0.0;  // max-norm of the change of (a / L, alpha, d / L)
  std::string message;        // why it did not converge (empty when it did)
};

// Polishes `geometry` so that every pose of `poses` (closed poses along one
// circuit of a motion with `freedoms` freedoms, spread along it, at least as
// many as the free directions) closes to options.target_residual. Throws
// std::invalid_argument for an invalid geometry, directions of the wrong
// shape, a pose of the wrong size or freedoms outside [1, n - 1].
GeometryPolishSummary polish_geometry(const LoopGeometry& geometry, std::span<const JointVector> poses, int freedoms,
                                      const PolishDirections& directions, const GeometryPolishOptions& options = {});

}  // namespace loopfarm
