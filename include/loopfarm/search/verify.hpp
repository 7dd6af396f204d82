// Verification of a candidate linkage, independent of the elastic model: the
// motion of the rigid loop (motion.hpp), traced by arclength.
//
// A loop is verified when a circuit of its rigid closure moves
// (Circuit::moves): it closes on itself with every traced pose closing within
// the residual tolerance, or, open, its input covers at least
// `min_input_travel` with every pose closing to round-off. The
// reported circuit is the one through the given pose when that pose lies on
// a moving circuit; otherwise (and when no pose is given) the one whose input
// range covers theta0, if asked, else the one with the widest input range.
//
// With `all_circuits` (the default: `loopfarm verify`, `loopfarm motion`),
// every circuit is sought from assemblies spread over the whole turn, so a
// movable loop is found whatever pose or theta0 it is given, or none. Without
// it (the farm), only the circuit through the given pose is traced: a zero of
// the cycle energy is on its motion already.
#pragma once

#include <optional>
#include <span>
#include <string>
#include <vector>

#include "loopfarm/core/motion.hpp"

namespace loopfarm {

struct VerificationOptions {
  // Largest step along a circuit: 360 / steps_per_turn degrees of arclength
  // in joint space (>= 64, a step of at most 0.1 rad).
  int steps_per_turn = 720;
  double residual_tolerance = 1e-9;  // max-norm of the residual (translation / L) for "closes"
  int input_joint = 0;
  // [rad] The least input travel of a moving circuit that does not close.
  double min_input_travel = 3.14159265358979323846 / 180.0;
  bool all_circuits = true;
  // With all_circuits: input angles over the turn at which assemblies are
  // sought, besides the guesses with every joint free (MotionOptions::
  // scan_inputs; 0: those guesses only).
  int scan_inputs = 24;
  // Solve for every joint's extremes on the circuit (their ranges exact), or
  // only the input's dead points (the other ranges from the traced points,
  // to within a step).
  bool all_extremes = true;
  // A circuit's walk ends where it nears a singular pose this closely
  // (MotionOptions::stop_below_singular_ratio; 0: never).
  double stop_below_singular_ratio = 0.0;
  // [rad] Prefer the circuit whose input range covers this angle (when no
  // pose on a moving circuit is given).
  std::optional<double> theta0;

  // The tracer's options from these.
  MotionOptions motion() const;
  // Throws std::invalid_argument naming the first invalid option.
  void validate() const;
};

struct VerificationSummary {
  bool assembled = false;  // the given pose closes the rigid loop (after polishing)
  bool on_motion = false;  // the given pose lies on the reported, moving circuit
  bool verified = false;   // a circuit moves (the reported one)
  bool full_turn = false;  // on the reported circuit the input turns fully
  double range_lo = 0.0;   // the reported circuit's input range [rad], unwrapped
  double range_hi = 0.0;
  // Largest residual over the reported circuit's poses (dimensionless); when
  // nothing closes, the least residual any assembly reached.
  double worst_residual = 0.0;
  int poses = 0;                          // points of the reported circuit
  std::vector<double> input_angles;       // its input angle at each point
  std::vector<JointVector> joint_angles;  // its poses, unwrapped (continuous)
  // Per joint: max - min over the reported circuit [rad]; a joint held to
  // trace a loop with several freedoms counts 2 pi (other motions turn it).
  JointVector joint_travel;
  int circuit = -1;       // the reported circuit in motion.circuits; -1 if none
  MotionAnalysis motion;  // every circuit found
  std::string limit;      // what the verdict rests on, in words (empty for a full turn)

  // A closed pose on the reported circuit (its first point); empty if none.
  JointVector pose() const;
};

// Throws std::invalid_argument for a geometry validate_geometry rejects or a
// start pose of the wrong size or with non-finite values. `start_angles` may
// be null (no pose given; needs all_circuits).
VerificationSummary verify_motion(const LoopGeometry& geometry, const JointVector* start_angles,
                                  const VerificationOptions& options = {});
// The same with a pose.
VerificationSummary verify_motion(const LoopGeometry& geometry, const JointVector& start_angles,
                                  const VerificationOptions& options = {});
// The same with further closed poses traced, when the circuit through the
// start pose does not close on itself, before any search of the whole motion
// (analyse_motion's `more_poses`): a circuit through one of them is reported
// when the one through the start pose does not move.
VerificationSummary verify_motion(const LoopGeometry& geometry, const JointVector& start_angles,
                                  std::span<const JointVector> more_poses, const VerificationOptions& options = {});

// Where a cycle of the elastic model driven along the reported motion
// starts and what input range it covers: over a full turn from theta0 when
// the input turns fully; otherwise a window inside the input's range, centred
// on theta0 when theta0 lies inside it (else on the middle of the range),
// reaching 90 % of the way to the nearer dead point on either side. theta0
// defaults to the given pose's input when that pose is on the motion, else 0;
// for a full turn of `samples` samples (> 0) the default is moved off 0, by
// less than one sample spacing, where a sample would lie within a quarter
// spacing (and h/64) of a singular pose the circuit passes: the equilibrium
// solve at a singular pose can leave the motion, and the cycle is then no zero.
struct MotionWindow {
  double theta0 = 0.0;  // [rad] the cycle's start
  double range = 0.0;   // [rad] 2 pi for a full turn; 0: the input does not move
  JointVector pose;     // a closed pose on the motion with the input at theta0
};
// Empty when the loop is not verified (or no pose is found at theta0). The
// range is 0 when the input joint does not move on the reported circuit
// (travel below min_input_travel, the other joints moving): a pose, and no
// cycle of that input.
std::optional<MotionWindow> motion_window(const LoopGeometry& geometry, const VerificationSummary& verification,
                                          std::optional<double> theta0, const VerificationOptions& options = {},
                                          int samples = 0);

}  // namespace loopfarm
