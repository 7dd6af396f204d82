// Motion of the rigid loop: its assemblies, and the circuits of its
// configuration curve traced by pseudo-arclength continuation.
//
// The closure T_1 ... T_n = I is 6 equations in the n joint angles. Where a
// loop moves, its closed poses form curves in joint space (surfaces for a
// loop with two freedoms); a connected piece of such a curve is a circuit.
// Everything here is kinematics of the rigid loop: the elastic model is not
// used, so verification built on it is independent of the search.
//
//   find_assemblies  every closed pose at one input angle (each assembly
//                    mode there), by Levenberg-Marquardt from deterministic
//                    guesses spread over the passive angles;
//   trace_circuit    the circuit through a closed pose, followed by
//                    arclength in joint space: a predictor along the null
//                    space of the closure Jacobian and a Moore-Penrose
//                    (Gauss-Newton, minimum-norm) corrector back onto the
//                    curve, through turning points of the input, until the
//                    circuit closes on itself or cannot be followed. Joint
//                    extremes (the input's are its dead points) are solved
//                    for on the curve, singular poses (the closure
//                    Jacobian loses rank, as where branches cross) are
//                    located and reported;
//   analyse_motion   every circuit: seeds from a given pose, from assemblies
//                    at input angles spread over the turn and from
//                    assemblies with every joint free, each traced unless it
//                    lies on a circuit already found, and the other branches
//                    at every bifurcation point traced as circuits of their own.
//
// Lengths are divided by the length scale L (length_scale) before anything
// is solved, so tolerances mean the same at every scale. Angles are radians,
// unwrapped along a circuit (continuous, not reduced to a turn).
//
// A loop with f > 1 freedoms (two Bennett loops sharing a removed link) has
// an f-dimensional set of poses; trace_circuit then holds f - 1 passive
// joints at their values in the start pose (picked so that the most joints
// keep moving) and traces the curve left, which is one motion of many:
// Circuit::held_joints names them. docs/guide/motion.md has the method, its
// tolerances and its limits.
#pragma once

#include <optional>
#include <span>
#include <string>
#include <vector>

#include "loopfarm/core/loop.hpp"

namespace loopfarm {

struct MotionOptions {
  int input_joint = 0;
  // Max-norm of the closure residual (rotation, translation / L) for a pose
  // to count as closed.
  double residual_tolerance = 1e-9;
  // [rad] Largest step along a circuit, as arclength in joint space (the
  // Euclidean norm of the change of all joint angles).
  double max_step = 3.14159265358979323846 / 360.0;
  // Halvings of a step allowed before the circuit is declared not followable.
  int max_halvings = 30;
  // Points per circuit at most (a circuit longer than this ends, said so).
  int max_points = 50000;
  // A walk whose last stall_points steps advanced, together, less than one
  // max_step ends `stalled` (0: never). On a curve of closed poses the step
  // regrows by half each easy step after a hard stretch, so a genuine walk
  // advances many max_steps in this many points; a walk that creeps is
  // following the thin tube where a near miss closes only to about the
  // tolerance, and would spend max_points on a fraction of a degree.
  int stall_points = 1000;
  // A walk that reaches a point whose singular ratio (Circuit::
  // least_singular_ratio) is below this ends there, `singular` (0: never):
  // for a coarse trace that is redone finely near singular poses anyway.
  double stop_below_singular_ratio = 0.0;
  // A singular value of the closure Jacobian below this fraction of the
  // largest counts as zero (its numerical rank, hence the freedoms).
  double rank_tolerance = 1e-7;
  // analyse_motion: input angles over the turn at which assemblies are
  // sought, deterministic guesses per solve, and guesses with every joint free.
  int scan_inputs = 24;
  int assembly_guesses = 48;
  int free_guesses = 96;
  // Locate the extremes of every joint (true) or of the input joint only.
  bool all_extremes = true;

  // Throws std::invalid_argument naming the first invalid option.
  void validate() const;
};

// A pose where the angle of `joint` is extreme along its circuit (its
// derivative along the curve vanishes): for the input joint, a dead point.
struct JointExtreme {
  int joint = 0;
  bool maximum = false;
  double arclength = 0.0;  // along the circuit from its first point
  JointVector theta;       // the pose, unwrapped as the circuit is
};

// A singular pose: the closure Jacobian loses rank on the circuit. Other
// branches may cross there (a parallelogram's change point: 4 branch
// directions) or none (0: the circuit only passes a fold of the closure).
struct Bifurcation {
  double arclength = 0.0;
  JointVector theta;
  int branches = 0;                      // branch directions found leaving the point (2 per branch through it)
  double smallest_singular_value = 0.0;  // of the closure Jacobian at the located point
};

// The range of one joint along a circuit [rad], unwrapped. A crank turns
// fully (`turns` != 0 on a closed circuit: the net number of turns per
// circuit); a rocker's range is [lo, hi] with hi - lo < 2 pi.
struct JointRange {
  double lo = 0.0;
  double hi = 0.0;
  int turns = 0;
  bool crank() const { return turns != 0; }
};

enum class CircuitEnd {
  closed,    // returned to its first point: a whole circuit
  lost,      // the closure could not be followed further (steps halved to nothing)
  too_long,  // MotionOptions::max_points reached
  stalled,   // its last MotionOptions::stall_points steps advanced less than one max_step
  singular,  // a point nearer a singular pose than MotionOptions::stop_below_singular_ratio allows
  rigid,     // the pose closes but the closure Jacobian has full rank: an isolated pose
};
const char* to_string(CircuitEnd end);

struct Circuit {
  std::vector<JointVector> points;  // unwrapped poses along the circuit, in order
  std::vector<double> arclength;    // from the first point, one per point
  CircuitEnd end = CircuitEnd::lost;
  int freedoms = 0;                    // null-space dimension of the closure Jacobian at regular points
  std::vector<int> held_joints;        // joints held at their start values (freedoms > 1)
  std::vector<JointRange> ranges;      // one per joint
  std::vector<JointExtreme> extremes;  // in order of arclength
  std::vector<Bifurcation> bifurcations;
  double worst_residual = 0.0;  // over every point (and located extreme)
  double length = 0.0;          // total arclength
  // How near the circuit passes a singular pose: the least ratio, over its
  // points, of the closure Jacobian's smallest retained singular value to its
  // largest (1 for a well-conditioned curve, 0 at a singular pose).
  double least_singular_ratio = 1.0;

  bool closed() const { return end == CircuitEnd::closed; }
  // The input's range [rad] and whether it turns fully.
  const JointRange& input_range(int input_joint) const { return ranges[static_cast<size_t>(input_joint)]; }
  // Moves: the circuit closes on itself, or its input covers at least
  // `min_travel` with every point closing to round-off (a residual of at
  // most 1e-3 of `residual_tolerance`). An open circuit whose residual
  // climbs to the tolerance is a near miss closing approximately over a
  // short stretch (often near a folded pose), not a motion.
  bool moves(int input_joint, double min_travel, double residual_tolerance) const;
};

// Every closed pose (residual within options.residual_tolerance, polished to
// round-off) with the input joint at `input_angle`, one per assembly mode
// (poses closer than 1e-6 rad in every joint are one), in a deterministic order.
// Throws std::invalid_argument for a geometry validate_geometry rejects.
std::vector<JointVector> find_assemblies(const LoopGeometry& geometry, double input_angle,
                                         const MotionOptions& options = {});

// The circuit through `pose`, which must close within the tolerance (a pose
// that does not is polished first by a Moore-Penrose Newton solve; if it
// still does not close the circuit is empty and ends `lost`).
Circuit trace_circuit(const LoopGeometry& geometry, const JointVector& pose, const MotionOptions& options = {});

// A closed pose of the circuit with the input joint at `angle` (any 2 pi
// image), interpolated between its points and corrected with the input
// held: the first such pose along the circuit. False if the circuit's input
// never takes that angle.
bool pose_at_input(const LoopGeometry& geometry, const Circuit& circuit, double angle, JointVector& pose,
                   const MotionOptions& options = {});

// The input range [rad] a cycle of the elastic model started at `theta0` on
// a circuit covers while staying on it: a full turn (2 pi) when the input
// turns fully; otherwise a window centred on theta0 reaching 90 % of the way
// to the nearer dead point on either side (the margin keeps the cycle's
// samples off the fold, where the elastic equilibrium path turns back), and
// at most 324 deg, the window of a rocker whose dead points are a turn apart
// (the input of some rockers swings through more than a turn; a range of
// 2 pi would be a full turn, CycleOptions::range). 0
// when no 2 pi image of theta0 lies strictly inside the input's range.
double cycle_window(const JointRange& input_range, double theta0);

// Where a cycle of the elastic model can start on a motion: a closed pose
// with the input at theta0 whose circuit moves (Circuit::moves with
// `min_travel`), and the window a cycle from it covers (cycle_window).
struct MotionStart {
  JointVector pose;    // closed, with pose[input_joint] = theta0
  Circuit circuit;     // the circuit through it
  double range = 0.0;  // cycle_window(circuit's input range, theta0) > 0
};

// The assembly at theta0 that lies on a motion: `near` (may be null) when,
// with its input set to theta0 and polished, it closes and its circuit
// moves; otherwise the assemblies find_assemblies finds there, nearest to
// `near` first, the first whose circuit moves. Empty when no assembly at
// theta0 lies on a motion (a loop that moves nowhere, or a theta0 outside
// its input's range or at a dead point). Throws as trace_circuit does.
std::optional<MotionStart> motion_start(const LoopGeometry& geometry, double theta0, const JointVector* near,
                                        double min_travel, const MotionOptions& options = {});

struct MotionAnalysis {
  int input_joint = 0;                      // as in the options
  std::vector<Circuit> circuits;            // the circuit through the given pose first, then in order found
  int given_circuit = -1;                   // index of the circuit through the given pose; -1 if none
  bool given_pose_closes = false;           // the given pose closes (after polishing)
  JointVector given_pose;                   // the given pose, polished; empty if none was given
  std::vector<JointVector> isolated_poses;  // closed poses that do not move (rigid assemblies)
  double least_residual = 0.0;              // the smallest residual any assembly reached (when none closes)
  int seeds = 0;                            // closed poses found by the assembly search
  int branch_seeds = 0;                     // points on other branches met at singular poses, each traced
};

// Every circuit found from `pose` (may be null), from assemblies at
// options.scan_inputs input angles and from assemblies with every joint free.
MotionAnalysis analyse_motion(const LoopGeometry& geometry, const JointVector* pose, const MotionOptions& options = {});
// The same with `more_poses` traced, when the circuit through `pose` does
// not close on itself, after it and before any assembly search: in order,
// each that closes (after polishing) and lies on no circuit traced and at no
// isolated pose found before it. They are other poses known to close, such
// as the samples of a cycle with no energy, whose motion may not pass
// through `pose` (a cycle can close at a few isolated poses and follow a
// motion at its other samples).
MotionAnalysis analyse_motion(const LoopGeometry& geometry, const JointVector* pose,
                              std::span<const JointVector> more_poses, const MotionOptions& options = {});

}  // namespace loopfarm
