// Where a cycle of the elastic model starts on the rigid loop's motion
// (motion.hpp): a pose at a given input angle on a circuit, the input window
// a cycle from there covers, and the assembly to start from.
#include "loopfarm/core/motion.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>

#include "circuit_trace.hpp"
#include "closure_solver.hpp"

namespace loopfarm {

using namespace detail;

bool pose_at_input(const LoopGeometry& geometry, const Circuit& circuit, double angle, JointVector& pose,
                   const MotionOptions& o) {
  o.validate();
  validate_geometry(geometry);
  if (!std::isfinite(angle)) throw std::invalid_argument("pose_at_input: the angle is not finite");
  const int input = o.input_joint;
  if (input >= geometry.joints()) throw std::invalid_argument("pose_at_input: input_joint beyond the loop's joints");
  const LoopGeometry g = scaled(geometry, length_scale(geometry));
  for (size_t i = 0; i + 1 < circuit.points.size(); ++i) {
    const JointVector& p = circuit.points[i];
    const JointVector& q = circuit.points[i + 1];
    const double lo = std::min(p[input], q[input]), hi = std::max(p[input], q[input]);
    const double target = angle + kTwoPi * std::ceil((lo - angle) / kTwoPi);
    if (target > hi || hi == lo) continue;
    JointVector x = p + (target - p[input]) / (q[input] - p[input]) * (q - p);
    x[input] = target;
    std::vector<int> held = circuit.held_joints;
    held.push_back(input);
    const ClosureSystem system(g, held, x);
    if (!correct(system, x, g.joints(), 0.1, o).converged) continue;
    pose = x;
    return true;
  }
  return false;
}

double cycle_window(const JointRange& r, double theta0) {
  if (r.crank()) return kTwoPi;
  const double middle = 0.5 * (r.lo + r.hi);
  const double image = middle + std::remainder(theta0 - middle, kTwoPi);
  if (!(image > r.lo && image < r.hi)) return 0.0;
  // A range of 2 pi would mean a full turn (CycleOptions::range), which a
  // rocker does not make: a rocker whose input swings through more than a
  // turn gets the window of one whose dead points are a turn apart.
  return std::min(0.9 * kTwoPi, 1.8 * std::min(image - r.lo, r.hi - image));
}

std::optional<MotionStart> motion_start(const LoopGeometry& geometry, double theta0, const JointVector* near,
                                        double min_travel, const MotionOptions& o) {
  o.validate();
  validate_geometry(geometry);
  const int n = geometry.joints();
  const int input = o.input_joint;
  if (input >= n) throw std::invalid_argument("motion_start: input_joint beyond the loop's joints");
  if (!std::isfinite(theta0)) throw std::invalid_argument("motion_start: theta0 is not finite");
  if (near && near->size() != n) throw std::invalid_argument("motion_start: the pose has the wrong number of angles");
  if (near && !near->allFinite()) throw std::invalid_argument("motion_start: a pose angle is not finite");
  const LoopGeometry g = scaled(geometry, length_scale(geometry));
  JointVector base = JointVector::Zero(n);
  base[input] = theta0;
  const ClosureSystem system(g, {input}, base);

  // The circuit through a closed pose x at theta0, if it moves and leaves a
  // window there.
  auto start_at = [&](const JointVector& x) -> std::optional<MotionStart> {
    Circuit c = trace(g, x, o).circuit;
    if (!c.moves(input, min_travel, o.residual_tolerance)) return std::nullopt;
    const double range = cycle_window(c.input_range(input), theta0);
    if (!(range > 0.0)) return std::nullopt;
    MotionStart s{x, std::move(c), range};
    s.pose[input] = theta0;
    return s;
  };

  JointVector polished;
  if (near) {
    polished = *near;
    polished[input] = theta0;
    if (correct(system, polished, n, 0.1, o).converged) {
      if (std::optional<MotionStart> s = start_at(polished)) return s;
    } else {
      polished.resize(0);
    }
  }
  std::array<bool, kMaxJoints> free{};
  for (int k = 0; k < n; ++k) free[static_cast<size_t>(k)] = k != input;
  double least = std::numeric_limits<double>::infinity();
  std::vector<JointVector> poses = assemblies(g, system, base, free, o.assembly_guesses, o, least);
  if (near) {
    const JointVector& reference = *near;
    std::stable_sort(poses.begin(), poses.end(), [&](const JointVector& p, const JointVector& q) {
      return wrapped_difference(p, reference).norm() < wrapped_difference(q, reference).norm();
    });
  }
  for (const JointVector& x : poses) {
    if (polished.size() == n && same_pose(x, polished, kSamePose)) continue;  // tried above
    if (std::optional<MotionStart> s = start_at(x)) return s;
  }
  return std::nullopt;
}

}  // namespace loopfarm
