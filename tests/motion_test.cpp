// The rigid loop's motion (motion.hpp) against closed forms: Bennett loops
// (their input-output relation), planar and spherical four-bars (the laws of
// cosines), a parallelogram's two branches, coaxial loops, rigid loops.
#include "loopfarm/motion.hpp"

#include <cmath>
#include <stdexcept>
#include <vector>

#include <gtest/gtest.h>

#include "loopfarm/sample_loops.hpp"
#include "test_support.hpp"

namespace loopfarm {
namespace {

using testing::deg;
using testing::rad;

constexpr double kPi = 3.14159265358979323846;
// Ranges must match closed forms to 1e-6 deg.
const double kRangeTolerance = rad(1e-6);

// Planar four-bar with the input at joint 1 between links 4 and 1: the
// diagonal from joint 2 to joint 4 has delta^2 = a1^2 + a4^2 + 2 a1 a4 cos
// theta1 = a2^2 + a3^2 + 2 a2 a3 cos theta3 (law of cosines, exterior angles).
double diagonal_from_input(const LoopGeometry& g, double theta1) {
  return g.a[0] * g.a[0] + g.a[3] * g.a[3] + 2 * g.a[0] * g.a[3] * std::cos(theta1);
}
double diagonal_from_coupler(const LoopGeometry& g, double theta3) {
  return g.a[1] * g.a[1] + g.a[2] * g.a[2] + 2 * g.a[1] * g.a[2] * std::cos(theta3);
}

double max_residual(const LoopGeometry& g, const Circuit& c) {
  const LoopGeometry unit = scaled(g, length_scale(g));
  double worst = 0.0;
  for (const JointVector& p : c.points) worst = std::max(worst, closure_residual(unit, p).cwiseAbs().maxCoeff());
  return worst;
}

TEST(Motion, BennettLoopIsOneClosedCircuitOnItsClosedFormRelation) {
  struct Case {
    LoopGeometry g;
    JointVector (*angles)(const LoopGeometry&, double);
  };
  const Case cases[] = {{paper_bennett_loop(), bennett_angles},
                        {bennett_loop_line_symmetric(2.0, rad(30), rad(90)), bennett_angles_line_symmetric},
                        {bennett_loop(1.3, rad(110), rad(45)), bennett_angles}};
  for (const Case& k : cases) {
    const Circuit c = trace_circuit(k.g, k.angles(k.g, rad(120)));
    ASSERT_TRUE(c.closed()) << to_string(c.end);
    EXPECT_EQ(c.freedoms, 1);
    EXPECT_TRUE(c.held_joints.empty());
    EXPECT_LT(c.worst_residual, 1e-12);
    EXPECT_LT(max_residual(k.g, c), 1e-12);
    EXPECT_TRUE(c.bifurcations.empty());
    // Every joint of a Bennett loop turns fully, once per circuit.
    for (int j = 0; j < 4; ++j) EXPECT_EQ(std::abs(c.ranges[static_cast<size_t>(j)].turns), 1) << j;
    EXPECT_TRUE(c.moves(0, rad(1)));
    // Independent: the closed-form Bennett angles (eqs. 2a, 4a) at every point.
    for (size_t i = 0; i < c.points.size(); ++i) {
      const JointVector expected = k.angles(k.g, c.points[i][0]);
      for (int j = 0; j < 4; ++j) ASSERT_NEAR(wrap_angle(c.points[i][j] - expected[j]), 0.0, 1e-9) << i << " " << j;
    }
    // Points are spaced by at most the largest step.
    for (size_t i = 1; i < c.points.size(); ++i) {
      EXPECT_LE((c.points[i] - c.points[i - 1]).norm(), MotionOptions{}.max_step * (1 + 1e-9));
    }
  }
}

TEST(Motion, BennettLoopHasOneAssemblyAtEveryInput) {
  const LoopGeometry g = paper_bennett_loop();
  for (int i = 0; i < 12; ++i) {
    const double input = rad(-165 + 30 * i);
    const std::vector<JointVector> poses = find_assemblies(g, input);
    ASSERT_EQ(poses.size(), 1u) << deg(input);
    const JointVector expected = bennett_angles(g, input);
    for (int j = 0; j < 4; ++j) EXPECT_NEAR(wrap_angle(poses[0][j] - expected[j]), 0.0, 1e-10);
  }
}

TEST(Motion, PlanarCrankRockerHasTwoMirrorCircuitsWithTheRockerRangeOfTheLawOfCosines) {
  // a = (1, 3, 2.5, 3.5): Grashof with the input link the shortest: the
  // input turns fully, the output (joint 4, between links 3 and 4) rocks.
  const LoopGeometry g = planar_four_bar(1.0, 3.0, 2.5, 3.5);
  for (int i = 0; i < 8; ++i) {
    const double input = rad(-170 + 45 * i);
    const std::vector<JointVector> poses = find_assemblies(g, input);
    ASSERT_EQ(poses.size(), 2u) << deg(input);
    for (const JointVector& p : poses) {
      EXPECT_NEAR(diagonal_from_input(g, p[0]), diagonal_from_coupler(g, p[2]), 1e-10);
    }
  }
  const MotionAnalysis m = analyse_motion(g, nullptr);
  ASSERT_EQ(m.circuits.size(), 2u);
  for (const Circuit& c : m.circuits) {
    EXPECT_TRUE(c.closed());
    EXPECT_EQ(c.freedoms, 1);
    EXPECT_EQ(std::abs(c.ranges[0].turns), 1);
    EXPECT_LT(max_residual(g, c), 1e-12);
    for (size_t i = 0; i < c.points.size(); i += 5) {
      EXPECT_NEAR(diagonal_from_input(g, c.points[i][0]), diagonal_from_coupler(g, c.points[i][2]), 1e-9);
    }
  }
}

TEST(Motion, PlanarTripleRockerRangeIsTheClosedFormToAMicroDegree) {
  // a = (3, 1, 2.5, 2): delta^2 = 13 + 12 cos theta1 must lie in
  // [(2.5 - 1)^2, (2.5 + 1)^2], so theta1 in [acos(-0.0625), acos(-0.896)]
  // on the positive side and its mirror on the negative side: one circuit
  // (the two assembly modes join at the dead points) for each side.
  const LoopGeometry g = planar_four_bar(3.0, 1.0, 2.5, 2.0);
  const double lo = std::acos((12.25 - 13.0) / 12.0);  // delta = 3.5
  const double hi = std::acos((2.25 - 13.0) / 12.0);   // delta = 1.5
  const MotionAnalysis m = analyse_motion(g, nullptr);
  ASSERT_EQ(m.circuits.size(), 2u);
  int positive = 0;
  for (const Circuit& c : m.circuits) {
    ASSERT_TRUE(c.closed()) << to_string(c.end);
    const JointRange& r = c.ranges[0];
    EXPECT_EQ(r.turns, 0);
    const double mid = wrap_angle(0.5 * (r.lo + r.hi));
    const double sign = mid > 0 ? 1.0 : -1.0;
    positive += mid > 0;
    const double expected_lo = sign > 0 ? lo : -hi;
    const double expected_hi = sign > 0 ? hi : -lo;
    EXPECT_NEAR(wrap_angle(r.lo - expected_lo), 0.0, kRangeTolerance) << deg(r.lo) << " vs " << deg(expected_lo);
    EXPECT_NEAR(wrap_angle(r.hi - expected_hi), 0.0, kRangeTolerance) << deg(r.hi) << " vs " << deg(expected_hi);
    // The dead points are the located extremes of the input.
    int input_extremes = 0;
    for (const JointExtreme& e : c.extremes) {
      if (e.joint != 0) continue;
      ++input_extremes;
      EXPECT_NEAR(diagonal_from_input(g, e.theta[0]), e.maximum == (sign > 0) ? 2.25 : 12.25, 1e-9);
    }
    EXPECT_EQ(input_extremes, 2);
  }
  EXPECT_EQ(positive, 1);
  // No assembly outside the range, two inside, one pair merging at the ends.
  EXPECT_TRUE(find_assemblies(g, 0.0).empty());
  EXPECT_TRUE(find_assemblies(g, kPi).empty());
  EXPECT_EQ(find_assemblies(g, 0.5 * (lo + hi)).size(), 2u);
}

TEST(Motion, TracingFromAnyPoseOfTheRockerGivesTheSameCircuit) {
  const LoopGeometry g = planar_four_bar(3.0, 1.0, 2.5, 2.0);
  const std::vector<JointVector> poses = find_assemblies(g, rad(120));
  ASSERT_EQ(poses.size(), 2u);
  const Circuit a = trace_circuit(g, poses[0]);
  const Circuit b = trace_circuit(g, poses[1]);
  ASSERT_TRUE(a.closed() && b.closed());
  EXPECT_NEAR(a.ranges[0].lo, b.ranges[0].lo, kRangeTolerance);
  EXPECT_NEAR(a.ranges[0].hi, b.ranges[0].hi, kRangeTolerance);
  EXPECT_NEAR(a.length, b.length, 1e-6);
}

TEST(Motion, SphericalCrankTurnsFully) {
  const LoopGeometry g = spherical_four_bar(rad(20), rad(70), rad(60), rad(80));
  const MotionAnalysis m = analyse_motion(g, nullptr);
  ASSERT_GE(m.circuits.size(), 1u);
  for (const Circuit& c : m.circuits) {
    EXPECT_TRUE(c.closed());
    EXPECT_EQ(std::abs(c.ranges[0].turns), 1);
    EXPECT_LT(c.worst_residual, 1e-12);
  }
}

TEST(Motion, ParallelogramBranchesCrossAtItsChangePoints) {
  // a = (1, 2, 1, 2): the parallelogram branch (theta1 = theta3, both turn
  // fully) and the antiparallelogram branch cross where the loop folds flat.
  const LoopGeometry g = planar_four_bar(1.0, 2.0, 1.0, 2.0);
  const MotionAnalysis m = analyse_motion(g, nullptr);
  ASSERT_EQ(m.circuits.size(), 2u);
  for (const Circuit& c : m.circuits) {
    EXPECT_TRUE(c.closed()) << to_string(c.end);
    EXPECT_EQ(c.freedoms, 1);
    EXPECT_LT(c.worst_residual, 1e-12);
    ASSERT_EQ(c.bifurcations.size(), 2u);
    for (const Bifurcation& b : c.bifurcations) {
      // Flat: every joint angle 0 or 180 deg.
      for (int j = 0; j < 4; ++j) EXPECT_NEAR(std::sin(b.theta[j]), 0.0, 1e-7) << deg(b.theta[j]);
      EXPECT_EQ(b.branches, 4);
    }
  }
  // One branch keeps theta3 = theta1 (the parallelogram), the other not.
  int parallelogram = 0;
  for (const Circuit& c : m.circuits) {
    bool equal = true;
    for (const JointVector& p : c.points) equal = equal && std::abs(wrap_angle(p[2] - p[0])) < 1e-9;
    parallelogram += equal;
  }
  EXPECT_EQ(parallelogram, 1);
}

TEST(Motion, ParallelogramTracedFromItsChangePointFindsBothBranches) {
  const LoopGeometry g = planar_four_bar(1.0, 2.0, 1.0, 2.0);
  JointVector flat(4);
  flat << 0.0, kPi, 0.0, kPi;
  ASSERT_LT(closure_residual(g, flat).cwiseAbs().maxCoeff(), 1e-14);
  MotionOptions o;
  o.scan_inputs = 0;
  o.free_guesses = 0;
  const MotionAnalysis m = analyse_motion(g, &flat, o);
  EXPECT_TRUE(m.given_pose_closes);
  EXPECT_EQ(m.given_circuit, 0);
  EXPECT_EQ(m.circuits.size(), 2u);
}

TEST(Motion, RigidLoopsHaveNoCircuit) {
  for (std::uint64_t seed = 1; seed <= 4; ++seed) {
    const LoopGeometry g = random_loop(4, seed);
    const MotionAnalysis m = analyse_motion(g, nullptr);
    EXPECT_TRUE(m.circuits.empty()) << seed;
    EXPECT_GT(m.least_residual, 1e-4) << seed;
  }
}

TEST(Motion, AStructureThatClosesButCannotMoveDoesNotMove) {
  // a1 + a2 + a3 = a4: closes only stretched flat, infinitesimally mobile.
  const LoopGeometry g = planar_four_bar(1.0, 1.0, 1.0, 3.0);
  JointVector flat(4);
  flat << kPi, 0.0, 0.0, kPi;
  const Circuit c = trace_circuit(g, flat);
  EXPECT_FALSE(c.closed());
  EXPECT_FALSE(c.moves(0, rad(1)));
}

TEST(Motion, CoaxialTrivialLoopTurnsWithTwoJointsFrozen) {
  const LoopGeometry g = LoopGeometry::from_degrees(std::vector<double>{1.5, 1.5, 2.5, 2.5},
                                                    std::vector<double>{40, 40, 70, 70},
                                                    std::vector<double>{0.3, 0.0, -0.3, 0.0});
  JointVector start(4);
  start << rad(30), kPi, rad(-30), kPi;
  const Circuit c = trace_circuit(g, start);
  ASSERT_TRUE(c.closed());
  EXPECT_EQ(std::abs(c.ranges[0].turns), 1);
  EXPECT_EQ(std::abs(c.ranges[2].turns), 1);
  EXPECT_LT(c.ranges[1].hi - c.ranges[1].lo, 1e-9);
  EXPECT_LT(c.ranges[3].hi - c.ranges[3].lo, 1e-9);
}

TEST(Motion, BadInputThrows) {
  const LoopGeometry g = paper_bennett_loop();
  EXPECT_THROW(trace_circuit(g, JointVector::Zero(3)), std::invalid_argument);
  JointVector nan_start = bennett_angles(g, rad(120));
  nan_start[1] = std::nan("");
  EXPECT_THROW(trace_circuit(g, nan_start), std::invalid_argument);
  EXPECT_THROW(find_assemblies(g, std::nan("")), std::invalid_argument);
  MotionOptions o;
  o.max_step = 0.0;
  EXPECT_THROW(analyse_motion(g, nullptr, o), std::invalid_argument);
  o = {};
  o.input_joint = 4;
  EXPECT_THROW(analyse_motion(g, nullptr, o), std::invalid_argument);
}

}  // namespace
}  // namespace loopfarm
