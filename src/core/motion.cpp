// Motion of the rigid loop (motion.hpp): assemblies at an input angle and
// every circuit of the loop (analyse_motion); the tracing of one circuit is
// in circuit_trace.cpp, the start of a cycle on a motion in motion_start.cpp.
#include "loopfarm/core/motion.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "circuit_trace.hpp"
#include "closure_solver.hpp"

namespace loopfarm {

using namespace detail;

namespace {

// Circuits traced by analyse_motion at most (bifurcation branches included).
constexpr int kMaxCircuits = 64;

// Distance in max-norm from x (any 2 pi image) to the polyline of a circuit.
double distance_to_circuit(const JointVector& x, const Circuit& c) {
  double best = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i < c.points.size(); ++i) {
    const JointVector d = wrapped_difference(x, c.points[i]);
    if (i + 1 < c.points.size()) {
      const JointVector segment = c.points[i + 1] - c.points[i];
      const double length2 = segment.squaredNorm();
      const double tau = length2 > 0.0 ? std::clamp(d.dot(segment) / length2, 0.0, 1.0) : 0.0;
      best = std::min(best, (d - tau * segment).cwiseAbs().maxCoeff());
    } else {
      best = std::min(best, d.cwiseAbs().maxCoeff());
    }
  }
  return best;
}

// A newly traced circuit repeats a known one if its points a quarter, half
// and three quarters along lie on that one.
bool repeats(const Circuit& c, const std::vector<Circuit>& known) {
  if (c.points.empty()) return true;
  for (const Circuit& k : known) {
    if (k.points.size() < 2) continue;
    bool all = true;
    for (double fraction : {0.25, 0.5, 0.75}) {
      const size_t i = static_cast<size_t>(fraction * static_cast<double>(c.points.size() - 1));
      if (distance_to_circuit(c.points[i], k) > kOnCircuit) {
        all = false;
        break;
      }
    }
    if (all) return true;
  }
  return false;
}

}  // namespace

const char* to_string(CircuitEnd end) {
  switch (end) {
    case CircuitEnd::closed:
      return "closed";
    case CircuitEnd::lost:
      return "lost";
    case CircuitEnd::too_long:
      return "too_long";
    case CircuitEnd::stalled:
      return "stalled";
    case CircuitEnd::singular:
      return "singular";
    case CircuitEnd::rigid:
      return "rigid";
  }
  return "lost";
}

void MotionOptions::validate() const {
  auto fail = [](const std::string& what) { throw std::invalid_argument("MotionOptions: " + what); };
  if (input_joint < 0 || input_joint >= kMaxJoints) fail("input_joint out of range");
  if (!(residual_tolerance > 0.0 && residual_tolerance < 1e-3)) fail("residual_tolerance must be in (0, 1e-3)");
  if (!(max_step > 0.0 && max_step <= 0.1)) fail("max_step must be in (0, 0.1] rad");
  if (max_halvings < 1 || max_halvings > 60) fail("max_halvings must be in [1, 60]");
  if (max_points < 16) fail("max_points must be >= 16");
  if (stall_points < 0) fail("stall_points must be >= 0");
  if (!(rank_tolerance > 0.0 && rank_tolerance < 1e-2)) fail("rank_tolerance must be in (0, 1e-2)");
  if (!(stop_below_singular_ratio >= 0.0 && stop_below_singular_ratio < 1.0)) {
    fail("stop_below_singular_ratio must be in [0, 1)");
  }
  if (scan_inputs < 0) fail("scan_inputs must be >= 0");
  if (assembly_guesses < 1) fail("assembly_guesses must be >= 1");
  if (free_guesses < 0) fail("free_guesses must be >= 0");
}

bool Circuit::moves(int input_joint, double min_travel, double residual_tolerance) const {
  if (closed() && freedoms > 0) return true;
  if (ranges.empty() || worst_residual > 1e-3 * residual_tolerance) return false;
  const JointRange& r = input_range(input_joint);
  return r.hi - r.lo >= min_travel;
}

std::vector<JointVector> find_assemblies(const LoopGeometry& geometry, double input_angle, const MotionOptions& o) {
  o.validate();
  validate_geometry(geometry);
  if (o.input_joint >= geometry.joints())
    throw std::invalid_argument("find_assemblies: input_joint beyond the loop's joints");
  if (!std::isfinite(input_angle)) throw std::invalid_argument("find_assemblies: the input angle is not finite");
  const LoopGeometry g = scaled(geometry, length_scale(geometry));
  const int n = g.joints();
  JointVector base = JointVector::Zero(n);
  base[o.input_joint] = input_angle;
  std::array<bool, kMaxJoints> free{};
  for (int k = 0; k < n; ++k) free[static_cast<size_t>(k)] = k != o.input_joint;
  const ClosureSystem system(g, {o.input_joint}, base);
  double least = std::numeric_limits<double>::infinity();
  std::vector<JointVector> poses = assemblies(g, system, base, free, o.assembly_guesses, o, least);
  for (JointVector& p : poses) p[o.input_joint] = input_angle;
  return poses;
}

MotionAnalysis analyse_motion(const LoopGeometry& geometry, const JointVector* pose, const MotionOptions& o) {
  return analyse_motion(geometry, pose, {}, o);
}

MotionAnalysis analyse_motion(const LoopGeometry& geometry, const JointVector* pose,
                              std::span<const JointVector> more_poses, const MotionOptions& o) {
  o.validate();
  validate_geometry(geometry);
  const int n = geometry.joints();
  if (o.input_joint >= n) throw std::invalid_argument("analyse_motion: input_joint beyond the loop's joints");
  if (pose && pose->size() != n) throw std::invalid_argument("analyse_motion: pose has the wrong number of angles");
  if (pose && !pose->allFinite()) throw std::invalid_argument("analyse_motion: a pose angle is not finite");
  for (const JointVector& p : more_poses) {
    if (p.size() != n) throw std::invalid_argument("analyse_motion: a further pose has the wrong number of angles");
    if (!p.allFinite()) throw std::invalid_argument("analyse_motion: a further pose's angle is not finite");
  }
  const LoopGeometry g = scaled(geometry, length_scale(geometry));
  MotionAnalysis out;
  out.input_joint = o.input_joint;
  out.least_residual = std::numeric_limits<double>::infinity();

  // Seeds: closed poses to trace from, in order; `forced` ones (branches at
  // a bifurcation, close to a known circuit by construction) are traced
  // even when near one, and dropped afterwards if they repeat it.
  struct Seed {
    JointVector x;
    bool forced = false;
  };
  std::vector<Seed> seeds;
  // Traces dropped because they repeat a known circuit: the curve they
  // followed is traced already, so a later seed on them is not traced again,
  // as a seed on a known circuit is not. On a near miss (a loop that closes
  // to about the tolerance along a curve, not to round-off) the walk creeps
  // and ends too long, covering only part of its curve; every scan seed
  // beyond its ends was traced 50,000 points again and dropped.
  std::vector<Circuit> repeated;
  const auto on_traced_curve = [&](const JointVector& x) {
    const auto near = [&](const Circuit& c) { return c.points.size() >= 2 && distance_to_circuit(x, c) <= kOnCircuit; };
    return std::any_of(out.circuits.begin(), out.circuits.end(), near) ||
           std::any_of(repeated.begin(), repeated.end(), near);
  };
  auto take = [&](const Seed& seed, bool given) {
    if (static_cast<int>(out.circuits.size()) >= kMaxCircuits) return;
    if (!seed.forced) {
      if (on_traced_curve(seed.x)) return;
      for (const JointVector& p : out.isolated_poses) {
        if (same_pose(p, seed.x, kSamePose)) return;
      }
    }
    // One motion of a loop with several freedoms is traced (motion.hpp):
    // a later seed with as many is not, whatever surface it lies on.
    if (!given &&
        std::any_of(out.circuits.begin(), out.circuits.end(), [](const Circuit& c) { return c.freedoms > 1; })) {
      const ClosureSystem free_system(g, {}, seed.x);
      SystemVector F;
      SystemMatrix A;
      free_system.evaluate(seed.x, F, A);
      if (n - numerical_rank(decompose(A), o.rank_tolerance) > 1) return;
    }
    TracedCircuit t = trace(g, seed.x, o);
    if (t.circuit.points.empty()) return;
    if (t.circuit.end == CircuitEnd::rigid) {
      out.isolated_poses.push_back(t.circuit.points.front());
      return;
    }
    if (!given && repeats(t.circuit, out.circuits)) {
      repeated.push_back(std::move(t.circuit));
      return;
    }
    if (given) out.given_circuit = static_cast<int>(out.circuits.size());
    out.circuits.push_back(std::move(t.circuit));
    out.branch_seeds += static_cast<int>(t.branch_seeds.size());
    for (JointVector& b : t.branch_seeds) seeds.push_back({std::move(b), true});
  };

  // The given pose first: its circuit is the one a caller asks about.
  if (pose) {
    JointVector x = *pose;
    const ClosureSystem free_system(g, {}, x);
    const Correction c = correct(free_system, x, n, 0.5, o);
    out.least_residual = c.residual;
    out.given_pose_closes = c.converged;
    out.given_pose = x;
    if (c.converged) take({x, true}, true);
  }
  // Further closed poses when the given pose's circuit is not whole, each
  // traced unless it lies on a circuit traced or at an isolated pose found
  // (take()).
  const bool given_whole = out.given_circuit >= 0 && out.circuits[static_cast<size_t>(out.given_circuit)].closed();
  for (const JointVector& p : given_whole ? std::span<const JointVector>() : more_poses) {
    JointVector x = p;
    const ClosureSystem free_system(g, {}, x);
    const Correction c = correct(free_system, x, n, 0.5, o);
    out.least_residual = std::min(out.least_residual, c.residual);
    if (c.converged) take({x, false}, false);
  }

  // Assemblies at input angles over the turn, then with every joint free
  // (which finds motions whose input range falls between the scanned angles).
  std::array<bool, kMaxJoints> free{};
  for (int k = 0; k < n; ++k) free[static_cast<size_t>(k)] = k != o.input_joint;
  for (int i = 0; i < o.scan_inputs; ++i) {
    JointVector base = JointVector::Zero(n);
    base[o.input_joint] = wrap_angle(kTwoPi * i / o.scan_inputs);
    const ClosureSystem system(g, {o.input_joint}, base);
    for (JointVector& x : assemblies(g, system, base, free, o.assembly_guesses, o, out.least_residual)) {
      seeds.push_back({std::move(x), false});
    }
  }
  if (o.free_guesses > 0) {
    std::array<bool, kMaxJoints> all{};
    for (int k = 0; k < n; ++k) all[static_cast<size_t>(k)] = true;
    const JointVector base = JointVector::Zero(n);
    const ClosureSystem system(g, {}, base);
    for (JointVector& x : assemblies(g, system, base, all, o.free_guesses, o, out.least_residual)) {
      seeds.push_back({std::move(x), false});
    }
  }
  out.seeds = static_cast<int>(seeds.size());
  // Seeds grow while circuits are traced (branches at bifurcations).
  for (size_t i = 0; i < seeds.size(); ++i) {
    const Seed seed = seeds[i];  // take() may append to seeds
    take(seed, false);
  }
  return out;
}

}  // namespace loopfarm
