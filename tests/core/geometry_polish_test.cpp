// Polishing a geometry onto its motion (geometry_polish.hpp), checked with
// other methods: a Bennett loop moved off its family is polished back onto
// Bennett's closed-form conditions; a 6R of three Bennett loops moved off is
// polished onto a geometry whose circuit the tracer follows to round-off
// through every polished pose; a near miss with no movable loop along the
// directions allowed is refused; bounds hold.
#include "loopfarm/core/geometry_polish.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "loopfarm/core/constructions.hpp"
#include "loopfarm/core/motion.hpp"
#include "loopfarm/core/sample_loops.hpp"

namespace loopfarm {
namespace {

constexpr double kPi = 3.14159265358979323846;

// A deterministic pattern in [-1, 1] for parameter k (no generator needed).
double pattern(int k) { return std::sin(1.0 + 2.7 * k); }

// Every parameter moved by `size` (lengths relative to L) in a fixed pattern.
LoopGeometry moved_off(const LoopGeometry& g, double size) {
  const double L = length_scale(g);
  LoopGeometry out = g;
  const int n = g.joints();
  for (int k = 0; k < n; ++k) {
    out.a[k] += size * L * std::abs(pattern(k));  // lengths stay >= 0
    out.alpha[k] += size * pattern(n + k);
    out.d[k] += size * L * pattern(2 * n + k);
  }
  return out;
}

std::vector<JointVector> bennett_poses(const LoopGeometry& g, int count) {
  std::vector<JointVector> poses;
  for (int i = 0; i < count; ++i) poses.push_back(bennett_angles(g, -kPi + (i + 0.5) * 2.0 * kPi / count));
  return poses;
}

// Bennett's conditions (sample_loops.hpp): opposite links equal, zero
// offsets, sin(alpha1) / a1 = sin(alpha2) / a2; the largest violation, lengths / L.
double bennett_violation(const LoopGeometry& g) {
  const double L = length_scale(g);
  double worst = std::abs(g.a[0] - g.a[2]) / L;
  worst = std::max(worst, std::abs(g.a[1] - g.a[3]) / L);
  worst = std::max(worst, std::abs(g.alpha[0] - g.alpha[2]));
  worst = std::max(worst, std::abs(g.alpha[1] - g.alpha[3]));
  for (int k = 0; k < 4; ++k) worst = std::max(worst, std::abs(g.d[k]) / L);
  worst = std::max(worst, std::abs(std::sin(g.alpha[0]) * g.a[1] - std::sin(g.alpha[1]) * g.a[0]) / L);
  return worst;
}

TEST(GeometryPolish, ABennettLoopMovedOffItsFamilyIsPolishedBackOntoBennettsConditions) {
  const LoopGeometry bennett = bennett_loop(1.3, 0.7, 2.1);
  const LoopGeometry off = moved_off(bennett, 1e-7);
  ASSERT_GT(bennett_violation(off), 1e-8);
  const std::vector<JointVector> poses = bennett_poses(bennett, 32);
  const GeometryPolishSummary p = polish_geometry(off, poses, 1, PolishDirections::every_parameter(off));
  ASSERT_TRUE(p.converged) << p.message;
  EXPECT_EQ(p.poses_used, 32);
  EXPECT_GT(p.initial_residual, 1e-9);
  EXPECT_LE(p.final_residual, 1e-13);
  EXPECT_GT(p.iterations, 0);
  // It moves by about the perturbation, not more.
  EXPECT_GT(p.displacement, 1e-9);
  EXPECT_LT(p.displacement, 1e-6);
  EXPECT_LT(bennett_violation(p.geometry), 1e-12);
  const LoopGeometry unit = scaled(p.geometry, length_scale(p.geometry));
  for (const JointVector& pose : p.poses) EXPECT_LT(closure_residual(unit, pose).cwiseAbs().maxCoeff(), 1e-13);
}

TEST(GeometryPolish, ASixBarMovedOffIsPolishedOntoAMotionTheTracerFollowsThroughEveryPolishedPose) {
  ThreeBennett6R parameters;
  parameters.goldberg.loops = {1.0, 1.2, 0.7, -2.1};
  parameters.gamma = 2.3;
  const LoopGeometry six = three_bennett_6r(parameters, 0.9).geometry;
  std::vector<JointVector> poses;
  for (int i = 0; i < 128; ++i) poses.push_back(three_bennett_6r_pose(parameters, -kPi + (i + 0.5) * 2.0 * kPi / 128));
  const LoopGeometry off = moved_off(six, 1e-8);
  // The tracer cannot follow the loop moved off: it closes nowhere near
  // round-off, and a rigid 6R has isolated poses only.
  const Circuit lost = trace_circuit(off, poses.front());
  EXPECT_FALSE(lost.closed() && lost.worst_residual < 1e-9) << to_string(lost.end);
  const GeometryPolishSummary p = polish_geometry(off, poses, 1, PolishDirections::every_parameter(off));
  ASSERT_TRUE(p.converged) << p.message;
  EXPECT_LE(p.final_residual, 1e-13);
  EXPECT_LT(p.displacement, 1e-6);
  ASSERT_GE(p.poses_used, 100);
  // The tracer, from one polished pose: the whole circuit, every point
  // closing to 1e-11 (a hundredth of the tolerance; the directions of the
  // geometry the poses hardly see leave more near the motion's singular
  // poses the fewer the poses: 7e-10 at 24, 7e-12 at 64, 5e-13 at 128),
  // and every other polished pose on it.
  const Circuit c = trace_circuit(p.geometry, p.poses.front());
  ASSERT_TRUE(c.closed()) << to_string(c.end);
  EXPECT_LT(c.worst_residual, 1e-11);
  for (const JointVector& pose : p.poses) {
    double nearest = std::numeric_limits<double>::infinity();
    for (const JointVector& q : c.points) {
      nearest = std::min(nearest, (pose - q).unaryExpr([](double x) { return std::abs(wrap_angle(x)); }).maxCoeff());
    }
    EXPECT_LT(nearest, 2e-2);  // within a trace step (0.5 deg of arclength)
  }
}

// A Bennett loop with a1 moved by 1e-10 of L closes within the tracer's
// tolerance along its whole circuit: the tracer follows it around. Only the
// offsets may move, and no 4R with unequal opposite links moves whatever its
// offsets (Bennett's theorem): the polish is refused and the geometry kept.
// With every parameter free it finds the Bennett loop 1e-10 away.
TEST(GeometryPolish, ANearMissWithNoMovableLoopAlongItsDirectionsIsRefused) {
  const LoopGeometry bennett = bennett_loop(1.3, 0.7, 2.1);
  LoopGeometry off = bennett;
  off.a[0] += 1e-10 * length_scale(bennett);
  const std::vector<JointVector> poses = bennett_poses(bennett, 32);
  const Circuit traced = trace_circuit(off, poses.front());
  EXPECT_TRUE(traced.closed()) << to_string(traced.end);
  EXPECT_GT(traced.worst_residual, 1e-12);

  PolishDirections offsets;
  offsets.directions = Eigen::MatrixXd::Zero(12, 4);
  for (int k = 0; k < 4; ++k) offsets.directions(8 + k, k) = 1.0;
  offsets.lower = Eigen::VectorXd::Constant(4, -std::numeric_limits<double>::infinity());
  offsets.upper = Eigen::VectorXd::Constant(4, std::numeric_limits<double>::infinity());
  const GeometryPolishSummary refused = polish_geometry(off, poses, 1, offsets);
  EXPECT_FALSE(refused.converged);
  EXPECT_FALSE(refused.message.empty());
  EXPECT_GT(refused.final_residual, 1e-12);
  EXPECT_EQ(refused.geometry.a, off.a);
  EXPECT_EQ(refused.geometry.d, off.d);

  const GeometryPolishSummary found = polish_geometry(off, poses, 1, PolishDirections::every_parameter(off));
  ASSERT_TRUE(found.converged) << found.message;
  EXPECT_LT(bennett_violation(found.geometry), 1e-13);
  EXPECT_LT(found.displacement, 1e-9);
}

TEST(GeometryPolish, AParameterAtItsBoundIsHeldThere) {
  const LoopGeometry bennett = bennett_loop(1.3, 0.7, 2.1);
  const LoopGeometry off = moved_off(bennett, 1e-7);
  const std::vector<JointVector> poses = bennett_poses(bennett, 32);
  // Free, the polish moves a1 too.
  const GeometryPolishSummary free = polish_geometry(off, poses, 1, PolishDirections::every_parameter(off));
  ASSERT_TRUE(free.converged);
  ASSERT_GT(free.step[0], 1e-8 * length_scale(off));
  // a1 may not move: a3 follows it instead.
  PolishDirections held = PolishDirections::every_parameter(off);
  held.lower[0] = 0.0;
  held.upper[0] = 0.0;
  const GeometryPolishSummary p = polish_geometry(off, poses, 1, held);
  ASSERT_TRUE(p.converged) << p.message;
  EXPECT_EQ(p.geometry.a[0], off.a[0]);
  EXPECT_EQ(p.step[0], 0.0);
  EXPECT_LT(bennett_violation(p.geometry), 1e-12);

  // A one-sided bound the free step crosses: a1 grows only to it and is
  // held there.
  PolishDirections one_sided = PolishDirections::every_parameter(off);
  one_sided.upper[0] = 0.5 * free.step[0];
  const GeometryPolishSummary q = polish_geometry(off, poses, 1, one_sided);
  ASSERT_TRUE(q.converged) << q.message;
  EXPECT_EQ(q.step[0], one_sided.upper[0]);
  EXPECT_LT(bennett_violation(q.geometry), 1e-12);
  // every_parameter keeps lengths >= 0.
  const PolishDirections every = PolishDirections::every_parameter(off);
  for (int k = 0; k < 4; ++k) EXPECT_EQ(every.lower[k], -off.a[k]);
}

TEST(GeometryPolish, TooFewPosesForTheDirectionsAreSaid) {
  const LoopGeometry bennett = bennett_loop(1.3, 0.7, 2.1);
  const LoopGeometry off = moved_off(bennett, 1e-7);
  // 3 poses fix 9 conditions (3 each, a 4R's left null space), not 12 parameters.
  const GeometryPolishSummary p =
      polish_geometry(off, bennett_poses(bennett, 3), 1, PolishDirections::every_parameter(off));
  EXPECT_FALSE(p.converged);
  EXPECT_NE(p.message.find("too few"), std::string::npos) << p.message;
}

TEST(GeometryPolish, BadInputThrows) {
  const LoopGeometry g = bennett_loop(1.3, 0.7, 2.1);
  const std::vector<JointVector> poses = bennett_poses(g, 8);
  const PolishDirections every = PolishDirections::every_parameter(g);
  EXPECT_THROW(polish_geometry(g, poses, 0, every), std::invalid_argument);
  EXPECT_THROW(polish_geometry(g, poses, 4, every), std::invalid_argument);
  PolishDirections short_rows = every;
  short_rows.directions = Eigen::MatrixXd::Identity(11, 12);
  EXPECT_THROW(polish_geometry(g, poses, 1, short_rows), std::invalid_argument);
  PolishDirections short_bounds = every;
  short_bounds.lower.resize(3);
  EXPECT_THROW(polish_geometry(g, poses, 1, short_bounds), std::invalid_argument);
  std::vector<JointVector> bad = poses;
  bad[2] = JointVector::Zero(5);
  EXPECT_THROW(polish_geometry(g, bad, 1, every), std::invalid_argument);
  bad[2] = JointVector::Constant(4, std::numeric_limits<double>::quiet_NaN());
  EXPECT_THROW(polish_geometry(g, bad, 1, every), std::invalid_argument);
  GeometryPolishOptions o;
  o.max_displacement = 0.0;
  EXPECT_THROW(polish_geometry(g, poses, 1, every, o), std::invalid_argument);
  o = {};
  o.target_residual = -1.0;
  EXPECT_THROW(o.validate(), std::invalid_argument);
}

}  // namespace
}  // namespace loopfarm
