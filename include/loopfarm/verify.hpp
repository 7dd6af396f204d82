// Verification of a candidate linkage, independent of the elastic model: the
// rigid closure T_1 ... T_n = I solved for the passive angles along the motion,
// in fine steps of the input angle, from an assembled pose both ways.
//
// A movable loop closes to round-off at every step; a rigid one cannot be
// followed at all (or does not even close at the start). A loop that moves
// over part of the turn only (a rocker, many spherical and 6R loops) is still
// movable: the walk stops at its dead points, and the covered input range is
// reported.
//
// For n > 4 a movable loop may have more than one degree of freedom; the walk
// then follows the minimum-norm continuation of the passive angles (the
// Gauss-Newton step is the least-norm one), which is one motion among many.
#pragma once

#include <string>
#include <vector>

#include "loopfarm/loop.hpp"

namespace loopfarm {

struct VerificationOptions {
  int steps_per_turn = 720;           // input step 360 / steps_per_turn degrees (>= 360)
  double residual_tolerance = 1e-9;   // max-norm of the residual (translation / L) for "closes"
  int max_newton_iterations = 30;
  int max_bisections = 12;            // halvings of a step before a motion limit is declared
  int input_joint = 0;

  // Throws std::invalid_argument naming the first invalid option.
  void validate() const;
};

struct VerificationSummary {
  bool assembled = false;     // the rigid closure was solved at the start pose
  bool verified = false;      // assembled, moves by at least one step, and every pose closes
  bool full_turn = false;     // the input turns 360 deg and the loop returns to its start pose
  double range_lo = 0.0;      // input angles covered [rad], unwrapped, range_lo <= theta0 <= range_hi
  double range_hi = 0.0;
  double worst_residual = 0.0;  // largest residual over the solved poses (dimensionless)
  int poses = 0;                // solved poses
  std::vector<double> input_angles;       // the path, in increasing input angle
  std::vector<JointVector> joint_angles;  // all joint angles along it, unwrapped (continuous)
  JointVector joint_travel;     // per joint: max - min of its angle over the path [rad]
  std::string limit;            // why the walk stopped short of a full turn; empty for a full turn
};

// Throws std::invalid_argument for a geometry validate_geometry rejects or a
// start_angles of the wrong size or with non-finite values.
VerificationSummary verify_motion(const LoopGeometry& geometry, const JointVector& start_angles,
                                  const VerificationOptions& options = {});

}  // namespace loopfarm
