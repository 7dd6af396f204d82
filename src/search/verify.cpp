// Rigid verification on the rigid loop's motion (verify.hpp). Shares nothing
// with the elastic model: the circuits come from motion.hpp.
#include "loopfarm/search/verify.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>

namespace loopfarm {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDegreesPerRadian = 180.0 / kPi;

double travel(const Circuit& c, int input) {
  const JointRange& r = c.input_range(input);
  return r.hi - r.lo;
}

// Does the circuit's input range cover `angle` (mod 2 pi)?
bool covers(const Circuit& c, int input, double angle) {
  const JointRange& r = c.input_range(input);
  if (r.crank()) return true;
  const double shifted = r.lo + std::fmod(std::fmod(angle - r.lo, 2.0 * kPi) + 2.0 * kPi, 2.0 * kPi);
  return shifted <= r.hi;
}

// The circuit to report: through the given pose if it moves; else one
// covering theta0 if asked; else the widest moving one; else the given one.
int reported_circuit(const MotionAnalysis& m, const VerificationOptions& o) {
  auto moves = [&](const Circuit& c) { return c.moves(o.input_joint, o.min_input_travel, o.residual_tolerance); };
  if (m.given_circuit >= 0 && moves(m.circuits[static_cast<size_t>(m.given_circuit)])) return m.given_circuit;
  int best = -1;
  for (int i = 0; i < static_cast<int>(m.circuits.size()); ++i) {
    const Circuit& c = m.circuits[static_cast<size_t>(i)];
    if (!moves(c)) continue;
    if (best < 0) {
      best = i;
      continue;
    }
    const Circuit& b = m.circuits[static_cast<size_t>(best)];
    const bool c_covers = o.theta0 && covers(c, o.input_joint, *o.theta0);
    const bool b_covers = o.theta0 && covers(b, o.input_joint, *o.theta0);
    if (c_covers != b_covers) {
      if (c_covers) best = i;
      continue;
    }
    if (travel(c, o.input_joint) > travel(b, o.input_joint) + 1e-9) best = i;
  }
  return best >= 0 ? best : m.given_circuit;
}

std::string scientific(double v) {
  char buffer[40];
  std::snprintf(buffer, sizeof buffer, "%.3g", v);
  return buffer;
}

std::string degrees(double radians) {
  char buffer[40];
  std::snprintf(buffer, sizeof buffer, "%.9g", radians * kDegreesPerRadian);
  return buffer;
}

// The start of a full turn of `samples` samples nearest 0 that keeps every
// sample more than a quarter of their spacing h away from the circuit's
// singular poses, else the one of the offsets 0, +-h/16, ..., +-15 h/16 that
// keeps them furthest. "More than" by h/64: a start exactly h/4 from a
// singular pose puts the cycle's halved steps onto it, where the equilibrium
// solve can cross to another branch (the 6R of
// Verify.AFullTurnStartsOffTheSingularPosesOfItsCircuit, whose singular poses
// lie at 0 and 180 deg to within 3e-12 rad), and a singular pose located at
// -1.6e-12 or at +2.6e-12 rad would decide between h/4 and 5h/16.
double full_turn_start(const Circuit& c, int input, int samples) {
  if (samples <= 0 || c.bifurcations.empty()) return 0.0;
  const double h = 2.0 * kPi / samples;
  auto clearance = [&](double theta0) {
    double least = kPi;
    for (const Bifurcation& b : c.bifurcations) {
      // The distance from b's input to the nearest sample theta0 + k h.
      const double offset = std::remainder(b.theta[input] - theta0, h);
      least = std::min(least, std::abs(offset));
    }
    return least;
  };
  const double enough = 0.25 * h + h / 64;
  double best = 0.0, best_clearance = clearance(0.0);
  for (int step = 1; step < 16 && best_clearance < enough; ++step) {
    for (const double theta0 : {step * h / 16, -step * h / 16}) {
      const double here = clearance(theta0);
      if (here > best_clearance) {
        best = theta0;
        best_clearance = here;
      }
    }
  }
  return best;
}

}  // namespace

MotionOptions VerificationOptions::motion() const {
  MotionOptions m;
  m.input_joint = input_joint;
  m.residual_tolerance = residual_tolerance;
  m.max_step = 2.0 * kPi / steps_per_turn;
  m.all_extremes = all_extremes;
  m.stop_below_singular_ratio = stop_below_singular_ratio;
  m.scan_inputs = scan_inputs;
  return m;
}

void VerificationOptions::validate() const {
  if (steps_per_turn < 64) throw std::invalid_argument("VerificationOptions: steps_per_turn must be >= 64");
  if (!(residual_tolerance > 0.0 && residual_tolerance < 1e-3)) {
    throw std::invalid_argument("VerificationOptions: residual_tolerance must be in (0, 1e-3)");
  }
  if (input_joint < 0 || input_joint >= kMaxJoints)
    throw std::invalid_argument("VerificationOptions: input_joint out of range");
  if (!(min_input_travel > 0.0 && min_input_travel < 2.0 * kPi)) {
    throw std::invalid_argument("VerificationOptions: min_input_travel must be in (0, 2 pi)");
  }
  if (scan_inputs < 0) throw std::invalid_argument("VerificationOptions: scan_inputs must be >= 0");
  if (theta0 && !std::isfinite(*theta0)) throw std::invalid_argument("VerificationOptions: theta0 is not finite");
  motion().validate();
}

JointVector VerificationSummary::pose() const { return joint_angles.empty() ? JointVector() : joint_angles.front(); }

namespace {

VerificationSummary verify(const LoopGeometry& geometry, const JointVector* start_angles,
                           std::span<const JointVector> more_poses, const VerificationOptions& options) {
  options.validate();
  validate_geometry(geometry);
  const int n = geometry.joints();
  if (start_angles) {
    if (start_angles->size() != n) {
      throw std::invalid_argument("verify_motion: " + std::to_string(start_angles->size()) + " start angles for " +
                                  std::to_string(n) + " joints");
    }
    if (!start_angles->allFinite()) throw std::invalid_argument("verify_motion: a start angle is not finite");
  } else if (!options.all_circuits) {
    throw std::invalid_argument("verify_motion: without a start pose every circuit must be sought (all_circuits)");
  }
  if (options.input_joint >= n) throw std::invalid_argument("verify_motion: input_joint beyond the loop's joints");

  VerificationSummary out;
  MotionOptions motion = options.motion();
  if (!options.all_circuits) {
    // The farm: the circuit through the search's pose only.
    motion.scan_inputs = 0;
    motion.free_guesses = 0;
  }
  out.motion = analyse_motion(geometry, start_angles, more_poses, motion);
  const MotionAnalysis& m = out.motion;
  out.assembled = m.given_pose_closes;
  out.circuit = reported_circuit(m, options);
  if (out.circuit < 0) {
    out.worst_residual = m.least_residual;
    if (!m.isolated_poses.empty()) {
      out.limit = "the rigid loop closes at isolated poses only and does not move";
    } else if (start_angles && !options.all_circuits) {
      out.limit = "the rigid loop does not close at the start pose";
    } else if (!m.circuits.empty()) {
      // Circuits were traced, but none moved the input by min_input_travel
      // with every pose closing to round-off (an open circuit: its residual
      // at most 1e-3 of the tolerance; Circuit::moves).
      double best = std::numeric_limits<double>::infinity();
      for (const Circuit& c : m.circuits) best = std::min(best, c.worst_residual);
      out.limit = std::to_string(m.circuits.size()) + (m.circuits.size() == 1 ? " circuit" : " circuits") +
                  " traced (least residual " + scientific(m.least_residual) + "), none moving the input " +
                  degrees(options.min_input_travel) +
                  " deg with every pose closing to round-off (the best circuit's worst residual " + scientific(best) +
                  ")";
    } else {
      out.limit = "the rigid loop closes nowhere (least residual " + scientific(m.least_residual) + ")";
    }
    return out;
  }
  const Circuit& c = m.circuits[static_cast<size_t>(out.circuit)];
  const int input = options.input_joint;
  out.verified = c.moves(input, options.min_input_travel, options.residual_tolerance);
  out.on_motion = out.verified && out.circuit == m.given_circuit;
  const JointRange& r = c.input_range(input);
  out.full_turn = r.crank();
  out.range_lo = r.lo;
  out.range_hi = r.hi;
  out.worst_residual = c.worst_residual;
  out.joint_angles = c.points;
  out.poses = static_cast<int>(c.points.size());
  for (const JointVector& p : c.points) out.input_angles.push_back(p[input]);
  out.joint_travel = JointVector::Zero(n);
  for (int k = 0; k < n; ++k) {
    const JointRange& k_range = c.ranges[static_cast<size_t>(k)];
    out.joint_travel[k] = k_range.hi - k_range.lo;
  }
  // A joint held to trace a loop with several freedoms is turned by the
  // loop's other motions: it is not frozen.
  for (int k : c.held_joints) out.joint_travel[k] = 2.0 * kPi;

  if (out.full_turn) {
    if (std::abs(r.turns) > 1) {
      out.limit = "the input turns " + std::to_string(std::abs(r.turns)) + " times before the pose returns";
    }
  } else if (!(r.hi - r.lo >= options.min_input_travel)) {
    out.limit = "the input joint does not move on this circuit (travel " + degrees(r.hi - r.lo) +
                " deg), the others do: no cycle of it (relabel the loop so that joint 1 moves)";
  } else if (c.closed()) {
    out.limit = "the input rocks between dead points at " + degrees(r.lo) + " and " + degrees(r.hi) + " deg";
  } else {
    out.limit = std::string("the circuit ends (") + to_string(c.end) + ") at input " + degrees(r.lo) + " and " +
                degrees(r.hi) + " deg";
  }
  if (!out.verified) {
    out.limit = "the rigid loop closes but does not move (input travel " + degrees(r.hi - r.lo) + " deg)";
  } else if (start_angles && !out.on_motion) {
    out.limit += std::string(out.limit.empty() ? "" : "; ") + "the given pose " +
                 (m.given_pose_closes ? "is not on this motion" : "does not close the rigid loop");
  }
  if (c.freedoms > 1) {
    out.limit +=
        std::string(out.limit.empty() ? "" : "; ") + std::to_string(c.freedoms) + " freedoms: traced with joints held";
  }
  return out;
}

}  // namespace

VerificationSummary verify_motion(const LoopGeometry& geometry, const JointVector* start_angles,
                                  const VerificationOptions& options) {
  return verify(geometry, start_angles, {}, options);
}

VerificationSummary verify_motion(const LoopGeometry& geometry, const JointVector& start_angles,
                                  const VerificationOptions& options) {
  return verify(geometry, &start_angles, {}, options);
}

VerificationSummary verify_motion(const LoopGeometry& geometry, const JointVector& start_angles,
                                  std::span<const JointVector> more_poses, const VerificationOptions& options) {
  return verify(geometry, &start_angles, more_poses, options);
}

std::optional<MotionWindow> motion_window(const LoopGeometry& geometry, const VerificationSummary& v,
                                          std::optional<double> theta0, const VerificationOptions& options,
                                          int samples) {
  if (!v.verified || v.circuit < 0) return std::nullopt;
  const Circuit& c = v.motion.circuits[static_cast<size_t>(v.circuit)];
  const int input = options.input_joint;
  if (!theta0 && v.on_motion) theta0 = v.motion.given_pose[input];
  MotionWindow w;
  const JointRange& r = c.input_range(input);
  if (r.crank()) {
    w.theta0 = theta0 ? *theta0 : full_turn_start(c, input, samples);
    w.range = 2.0 * kPi;
  } else {
    double centre = 0.5 * (r.lo + r.hi);
    if (theta0) {
      // theta0's image nearest the range's middle.
      const double image = centre + std::remainder(*theta0 - centre, 2.0 * kPi);
      if (image > r.lo && image < r.hi) centre = image;
    }
    w.theta0 = centre;
    // A closed circuit moves when any joint does: its input may stay where
    // it is (a frozen joint as input), and then there is no cycle of it.
    w.range = r.hi - r.lo >= options.min_input_travel ? cycle_window(r, centre) : 0.0;
  }
  // The cycle's angles as people read them: theta0 and the pose in (-180, 180] deg.
  w.theta0 = wrap_angle(w.theta0);
  MotionOptions m = options.motion();
  if (!pose_at_input(geometry, c, w.theta0, w.pose, m)) return std::nullopt;
  for (int k = 0; k < w.pose.size(); ++k) w.pose[k] = wrap_angle(w.pose[k]);
  w.pose[input] = w.theta0;
  return w;
}

}  // namespace loopfarm
