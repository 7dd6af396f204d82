// A stored linkage as lines in space, for CAD and scripts: the axis of every
// joint (a point on it and its unit direction) in the base frame, at a closed
// pose of the rigid loop on its motion (core's joint_axes at that pose).
//
// Frames are those of the closure (loop.hpp): frame k is T_1 ... T_k, whose z
// axis is joint k's axis (0-based); frame 0 is the base frame, so joint 1's
// axis is the z axis through the origin. The point on axis k is frame k's
// origin, where link k-1 ends: the foot on axis k of the common normal of
// axes k-1 and k. Consecutive axes k and k+1 are therefore a_k apart along
// their common normal and at the twist alpha_k to each other.
#pragma once

#include <optional>
#include <vector>

#include "loopfarm/core/constructions.hpp"
#include "loopfarm/core/loop.hpp"
#include "loopfarm/farm/results_database.hpp"

namespace loopfarm {

// The canonical geometry a candidates row stores (length scale 1, twists in
// degrees converted to radians).
LoopGeometry candidate_geometry(const CandidateRow& row);

// A closed pose on a candidate's motion, and its axes there.
struct CandidatePose {
  double input_deg = 0.0;         // joint 1's angle at the pose, in (-180, 180]
  JointVector theta;              // every joint's angle [rad], each in (-pi, pi]
  double closure_residual = 0.0;  // max-norm of closure_residual at theta
  bool full_turn = false;         // on that motion joint 1 turns fully
  double range_lo_deg = 0.0;      // joint 1's range on that motion, unwrapped
  double range_hi_deg = 0.0;
  std::vector<Axis> axes;  // core's joint_axes at theta
};

// The pose loopfarm verify and loopfarm motion start from: on the motion
// verify_motion reports (every circuit sought, joint 1 the input, the one
// whose input range covers input_deg preferred), with joint 1 at input_deg;
// when joint 1 rocks and does not reach input_deg, at the middle of its
// range. Empty when the rigid loop does not move (nothing stored as a
// candidate should be such a loop, but a stored row is only data). Throws
// std::invalid_argument for a geometry validate_geometry rejects.
std::optional<CandidatePose> candidate_pose(const LoopGeometry& geometry, double input_deg = 0.0);

}  // namespace loopfarm
