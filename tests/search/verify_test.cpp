#include "loopfarm/search/verify.hpp"

#include <cmath>
#include <optional>
#include <stdexcept>
#include <vector>

#include <gtest/gtest.h>

#include "loopfarm/core/assembly.hpp"
#include "loopfarm/core/cycle.hpp"
#include "loopfarm/core/sample_loops.hpp"
#include "test_support.hpp"

namespace loopfarm {
namespace {

using testing::deg;
using testing::rad;

constexpr double kPi = 3.14159265358979323846;

// A start pose from the elastic assembly (only a guess: verify_motion solves
// the rigid closure itself).
JointVector assembled_at(const LoopGeometry& g, double theta0) {
  const LoopModel model(g);
  EquilibriumWorkspace ws(model);
  return assemble(model, ws, theta0).state.theta;
}

TEST(Verify, BennettLoopsTurnFullyOnTheirClosedFormPath) {
  struct Case {
    LoopGeometry g;
    JointVector (*angles)(const LoopGeometry&, double);
  };
  const Case cases[] = {{paper_bennett_loop(), bennett_angles},
                        {bennett_loop_line_symmetric(2.0, rad(30), rad(90)), bennett_angles_line_symmetric}};
  for (const Case& c : cases) {
    const VerificationSummary v = verify_motion(c.g, c.angles(c.g, rad(120)));
    EXPECT_TRUE(v.verified);
    EXPECT_TRUE(v.full_turn);
    EXPECT_TRUE(v.limit.empty()) << v.limit;
    EXPECT_LT(v.worst_residual, 1e-12);
    EXPECT_TRUE(v.on_motion);
    EXPECT_GT(v.poses, 360);
    // Independent: the closed-form Bennett angles (eqs. 2a, 4a).
    for (size_t i = 0; i < v.input_angles.size(); i += 37) {
      const JointVector expected = c.angles(c.g, v.input_angles[i]);
      for (int k = 0; k < 4; ++k)
        EXPECT_NEAR(wrap_angle(v.joint_angles[i][k] - expected[k]), 0.0, 1e-9) << i << " " << k;
    }
  }
}

// Planar four-bar with the input at joint 1 between links 4 and 1: the
// diagonal from joint 2 to joint 4 has delta^2 = a1^2 + a4^2 + 2 a1 a4 cos
// theta1 = a2^2 + a3^2 + 2 a2 a3 cos theta3 (law of cosines, exterior angles).
double diagonal_from_input(const LoopGeometry& g, double theta1) {
  return g.a[0] * g.a[0] + g.a[3] * g.a[3] + 2 * g.a[0] * g.a[3] * std::cos(theta1);
}
double diagonal_from_coupler(const LoopGeometry& g, double theta3) {
  return g.a[1] * g.a[1] + g.a[2] * g.a[2] + 2 * g.a[1] * g.a[2] * std::cos(theta3);
}

TEST(Verify, PlanarCrankTurnsFullyOnTheLawOfCosines) {
  const LoopGeometry g = planar_four_bar(1.0, 3.0, 2.5, 3.5);  // Grashof, a1 the crank
  const VerificationSummary v = verify_motion(g, assembled_at(g, 0.0));
  EXPECT_TRUE(v.verified);
  EXPECT_TRUE(v.full_turn);
  for (size_t i = 0; i < v.joint_angles.size(); i += 11) {
    EXPECT_NEAR(diagonal_from_input(g, v.joint_angles[i][0]), diagonal_from_coupler(g, v.joint_angles[i][2]), 1e-9)
        << i;
  }
}

TEST(Verify, PlanarRockerStopsAtItsClosedFormDeadPoints) {
  // a = (3, 1, 2.5, 2): delta^2 = 13 + 12 cos theta1 must lie in
  // [(2.5 - 1)^2, (2.5 + 1)^2], so theta1 in [acos(-0.0625), acos(-0.896)].
  const LoopGeometry g = planar_four_bar(3.0, 1.0, 2.5, 2.0);
  const VerificationSummary v = verify_motion(g, assembled_at(g, rad(120)));
  EXPECT_TRUE(v.verified);
  EXPECT_TRUE(v.on_motion);
  EXPECT_FALSE(v.full_turn);
  EXPECT_FALSE(v.limit.empty());
  const double lo = std::acos((12.25 - 13.0) / 12.0);  // delta = 3.5
  const double hi = std::acos((2.25 - 13.0) / 12.0);   // delta = 1.5
  // The dead points are solved for on the curve: exact to 1e-6 deg.
  EXPECT_NEAR(v.range_lo, lo, rad(1e-6)) << deg(v.range_lo) << " vs " << deg(lo);
  EXPECT_NEAR(v.range_hi, hi, rad(1e-6)) << deg(v.range_hi) << " vs " << deg(hi);
  for (size_t i = 0; i < v.joint_angles.size(); i += 7) {
    EXPECT_NEAR(diagonal_from_input(g, v.joint_angles[i][0]), diagonal_from_coupler(g, v.joint_angles[i][2]), 1e-9)
        << i;
  }
}

TEST(Verify, ARockerIsVerifiedWhateverTheta0ItIsGivenOrNone) {
  const LoopGeometry g = planar_four_bar(3.0, 1.0, 2.5, 2.0);
  const double lo = std::acos((12.25 - 13.0) / 12.0), hi = std::acos((2.25 - 13.0) / 12.0);
  // No pose at all.
  const VerificationSummary none = verify_motion(g, nullptr);
  EXPECT_TRUE(none.verified);
  EXPECT_FALSE(none.full_turn);
  // A pose at theta0 = 0, outside the input's range: the elastic assembly
  // there does not close the rigid loop, and the motion is found elsewhere.
  const VerificationSummary outside = verify_motion(g, assembled_at(g, 0.0));
  EXPECT_TRUE(outside.verified);
  EXPECT_FALSE(outside.assembled);
  EXPECT_FALSE(outside.on_motion);
  EXPECT_NEAR(std::abs(wrap_angle(0.5 * (outside.range_lo + outside.range_hi))), 0.5 * (lo + hi), rad(1e-6));
  // Only the circuit through the pose (the farm's way): not verified there.
  VerificationOptions farm;
  farm.all_circuits = false;
  EXPECT_FALSE(verify_motion(g, assembled_at(g, 0.0), farm).verified);
  EXPECT_THROW(verify_motion(g, nullptr, farm), std::invalid_argument);
  // theta0 picks the circuit whose input reaches it: the mirror image.
  for (const double theta0 : {rad(120), rad(-120)}) {
    VerificationOptions o;
    o.theta0 = theta0;
    const VerificationSummary v = verify_motion(g, nullptr, o);
    ASSERT_TRUE(v.verified);
    const double image = v.range_lo + std::fmod(std::fmod(theta0 - v.range_lo, 2 * kPi) + 2 * kPi, 2 * kPi);
    EXPECT_LE(image, v.range_hi) << deg(theta0);
  }
}

TEST(Verify, MotionWindowIsAFullTurnForACrankAndInsideTheRangeForARocker) {
  const LoopGeometry crank = planar_four_bar(1.0, 3.0, 2.5, 3.5);
  const VerificationSummary c = verify_motion(crank, nullptr);
  const std::optional<MotionWindow> wc = motion_window(crank, c, rad(40));
  ASSERT_TRUE(wc.has_value());
  EXPECT_DOUBLE_EQ(wc->range, 2 * kPi);
  EXPECT_NEAR(wrap_angle(wc->theta0 - rad(40)), 0.0, 1e-12);
  EXPECT_NEAR(wrap_angle(wc->pose[0] - rad(40)), 0.0, 1e-12);
  EXPECT_LT(closure_residual(crank, wc->pose).cwiseAbs().maxCoeff(), 1e-12);

  const LoopGeometry rocker = planar_four_bar(3.0, 1.0, 2.5, 2.0);
  const double lo = std::acos((12.25 - 13.0) / 12.0), hi = std::acos((2.25 - 13.0) / 12.0);
  VerificationOptions o;
  o.theta0 = rad(100);
  const VerificationSummary r = verify_motion(rocker, nullptr, o);
  // theta0 inside the range: centred there, 90 % of the way to the nearer dead point.
  const std::optional<MotionWindow> inside = motion_window(rocker, r, rad(100), o);
  ASSERT_TRUE(inside.has_value());
  EXPECT_NEAR(inside->theta0, rad(100), 1e-12);
  EXPECT_NEAR(inside->range, 1.8 * (rad(100) - lo), 1e-9);
  // theta0 outside: the middle of the range.
  const std::optional<MotionWindow> outside = motion_window(rocker, r, 0.0, o);
  ASSERT_TRUE(outside.has_value());
  EXPECT_NEAR(outside->theta0, 0.5 * (lo + hi), 1e-9);
  EXPECT_NEAR(outside->range, 0.9 * (hi - lo), 1e-9);
  EXPECT_LT(closure_residual(rocker, outside->pose).cwiseAbs().maxCoeff(), 1e-12);
  // Not verified: no window.
  const LoopGeometry rigid = random_loop(4, 1);
  EXPECT_FALSE(motion_window(rigid, verify_motion(rigid, nullptr), 0.0).has_value());
}

// A rocker whose input swings through more than a turn between its dead
// points (a bennett_dyads 6R of the generic 6R job, its input over 416 deg):
// its cycle window is that of a rocker whose dead points are a turn apart,
// 324 deg, not 1.8 times the way to the nearer dead point (which asked the
// cycle for 374 deg and failed). The cycle over the window follows the
// motion: its energy is zero.
TEST(Verify, ARockerSwingingThroughMoreThanATurnGetsTheWindowOfATurnBetweenDeadPoints) {
  const double a[] = {0.531611382243285,  1.173779822696756,  1.315477649410536,
                      0.7218931340907394, 0.5352769675940152, 1.315477649410539};
  const double alpha_deg[] = {-12.28377446671099, -28.01825782690044, -123.2978087118279,
                              -17.43639602091413, -12.83742180167185, -123.297808711828};
  const double d[] = {-0.136483596754084,  -2.145571247316673e-16, -0.1364835967540891,
                      -0.1299244019654296, 1.858529268899931e-16,  -0.1299244019654251};
  const LoopGeometry g = LoopGeometry::from_degrees(a, alpha_deg, d);
  const VerificationSummary v = verify_motion(g, nullptr);
  ASSERT_TRUE(v.verified);
  EXPECT_FALSE(v.full_turn);
  EXPECT_GT(v.range_hi - v.range_lo, 2 * kPi);
  const std::optional<MotionWindow> w = motion_window(g, v, std::nullopt);
  ASSERT_TRUE(w.has_value());
  EXPECT_EQ(w->range, 0.9 * 2 * kPi);
  EXPECT_LT(closure_residual(scaled(g, length_scale(g)), w->pose).cwiseAbs().maxCoeff(), 1e-12);
  const LoopModel model(g);
  EquilibriumWorkspace ws(model);
  const EquilibriumSummary assembled = assemble_from_angles(model, ws, w->pose);
  CycleOptions options;
  options.range = w->range;
  CycleSummary cycle;
  cycle_energy(model, ws, w->theta0, assembled.state, options, cycle);
  EXPECT_EQ(cycle.failed_samples, 0);
  EXPECT_LT(cycle.E_mean, 1e-20);
}

// A full turn whose default start is a singular pose: an L-shaped
// Goldberg-type 6R (Bennett loops fused at psi = pi, to 12 digits) whose
// circuit passes two, at inputs 0 and 180 deg. A cycle of 32 samples from
// 0 deg has a sample on each, leaves the motion there and is no zero
// (E_mean 3.7e-4); the window moved off them is one. A start asked for, or
// no sample count, keeps 0.
TEST(Verify, AFullTurnStartsOffTheSingularPosesOfItsCircuit) {
  const std::vector<double> a = {2.569615506024, 1, 0.6, 1.7, 1.969615506024, 2.7};
  const std::vector<double> alpha = {97.4576031237, 30, 17.4576031237, 58.2116693829, 80, 88.2116693829};
  const std::vector<double> d(6, 0.0);
  const LoopGeometry g = LoopGeometry::from_degrees(a, alpha, d);
  const VerificationSummary v = verify_motion(g, nullptr);
  ASSERT_TRUE(v.verified);
  ASSERT_TRUE(v.full_turn);
  const Circuit& c = v.motion.circuits[static_cast<size_t>(v.circuit)];
  ASSERT_FALSE(c.bifurcations.empty());
  const int N = 32;
  const double h = 2 * kPi / N;
  const std::optional<MotionWindow> moved = motion_window(g, v, std::nullopt, {}, N);
  ASSERT_TRUE(moved.has_value());
  EXPECT_NE(moved->theta0, 0.0);
  EXPECT_LE(std::abs(moved->theta0), h);
  for (const Bifurcation& b : c.bifurcations) {
    EXPECT_GE(std::abs(std::remainder(b.theta[0] - moved->theta0, h)), 0.25 * h - 1e-12) << deg(b.theta[0]);
  }
  EXPECT_LT(closure_residual(g, moved->pose).cwiseAbs().maxCoeff(), 1e-10);
  const std::optional<MotionWindow> at0 = motion_window(g, v, std::nullopt);
  ASSERT_TRUE(at0.has_value());
  EXPECT_EQ(at0->theta0, 0.0);
  const std::optional<MotionWindow> asked = motion_window(g, v, 0.0, {}, N);
  ASSERT_TRUE(asked.has_value());
  EXPECT_EQ(asked->theta0, 0.0);

  // The cycle energy, an independent reading of the motion: zero from the
  // moved start, not from 0.
  auto cycle_energy_from = [&](const MotionWindow& w) {
    const LoopModel model(g);
    EquilibriumWorkspace ws(model);
    const EquilibriumSummary assembled = assemble_from_angles(model, ws, w.pose);
    CycleOptions options;
    options.samples = N;
    CycleSummary cycle;
    cycle_energy(model, ws, w.theta0, assembled.state, options, cycle);
    return cycle.E_mean;
  };
  EXPECT_LT(cycle_energy_from(*moved), 1e-20);
  EXPECT_GT(cycle_energy_from(*at0), 1e-6);
}

TEST(Verify, SphericalCrankTurnsFully) {
  const LoopGeometry g = spherical_four_bar(rad(20), rad(70), rad(60), rad(80));
  const VerificationSummary v = verify_motion(g, assembled_at(g, 0.0));
  EXPECT_TRUE(v.verified);
  EXPECT_TRUE(v.full_turn);
  EXPECT_LT(v.worst_residual, 1e-12);
}

TEST(Verify, RigidLoopsAreNotVerified) {
  for (std::uint64_t seed = 1; seed <= 4; ++seed) {
    const LoopGeometry g = random_loop(4, seed);
    const VerificationSummary v = verify_motion(g, assembled_at(g, 0.0));
    EXPECT_FALSE(v.verified) << seed;
    EXPECT_GT(v.worst_residual, 1e-4) << seed;
  }
  // The paper's loop with a1 = 2.03: close to movable, but not.
  LoopGeometry g = paper_bennett_loop();
  g.a[0] = 2.03;
  const VerificationSummary v = verify_motion(g, bennett_angles(paper_bennett_loop(), rad(120)));
  EXPECT_FALSE(v.verified);
  EXPECT_FALSE(v.assembled);
  EXPECT_GT(v.worst_residual, 1e-4);
}

// Generic 6R loops close at isolated poses (as many as 16) and move
// nowhere: neither the search for every circuit nor the farm's walks
// through each isolated pose (in coarse steps that give up near a singular
// pose, then in 1 deg steps, with no assembly search) may verify one.
TEST(Verify, GenericSixRLoopsThatCloseAtIsolatedPosesAreNotVerified) {
  int poses = 0;
  for (std::uint64_t seed = 1; seed <= 12; ++seed) {
    const LoopGeometry g = random_loop(6, seed);
    const VerificationSummary all = verify_motion(g, nullptr);
    EXPECT_FALSE(all.verified) << seed << ": " << all.limit;
    for (const JointVector& pose : all.motion.isolated_poses) {
      ++poses;
      VerificationOptions farm;
      farm.all_circuits = false;
      farm.steps_per_turn = 64;
      farm.stop_below_singular_ratio = 1e-2;
      EXPECT_FALSE(verify_motion(g, pose, farm).verified) << seed;
      farm.steps_per_turn = 360;
      farm.all_extremes = false;
      farm.stop_below_singular_ratio = 0.0;
      const VerificationSummary fine = verify_motion(g, pose, farm);
      EXPECT_FALSE(fine.verified) << seed;
      EXPECT_TRUE(fine.assembled) << seed;
    }
  }
  EXPECT_GE(poses, 12);  // the loops do close somewhere: the walks ran
}

TEST(Verify, AStructureThatClosesButCannotMoveIsNotVerified) {
  // A planar 4R with a1 + a2 + a3 = a4 closes only stretched flat: a shaky
  // structure, infinitesimally mobile (the residual grows as the square of
  // the input's move), so the walk gets a few bisected micro-steps at most,
  // never a full step.
  const LoopGeometry g = planar_four_bar(1.0, 1.0, 1.0, 3.0);
  JointVector flat(4);
  flat << kPi, 0.0, 0.0, kPi;
  const VerificationSummary v = verify_motion(g, flat);
  EXPECT_TRUE(v.assembled);
  EXPECT_LE(v.worst_residual, 1e-9);  // the micro-steps close to second order
  EXPECT_FALSE(v.verified);
  EXPECT_LT(v.range_hi - v.range_lo, rad(0.5));
}

TEST(Verify, CircuitsThatDoNotReachRoundOffAreNamedInTheLimit) {
  // A 5R that a search stopped at E_mean 1e-19 (jobs/goldberg-5r.toml, start
  // 166): 9e-6 from the bent Goldberg conditions, closing at poses to 5e-15,
  // but its one circuit is followed only to the corrector's 1e-9 and ends
  // lost. An open circuit moves only if every pose closes to round-off
  // (Circuit::moves), so it is not verified; the limit says what was traced
  // and how well, not that the loop closes nowhere.
  const LoopGeometry g = LoopGeometry::from_degrees(
      std::vector<double>{0.5553038463158257, 0.555320646819019, 2.554296094046266, 0.5553038463158257,
                          3.109583139858854},
      std::vector<double>{10.01076902262943, 10.01107501478612, 66.7525498548312, 10.01076902262943, 76.76301288530348},
      std::vector<double>{0, 0, 0, 0, 0});
  const VerificationSummary v = verify_motion(g, nullptr);
  ASSERT_FALSE(v.verified);
  ASSERT_FALSE(v.motion.circuits.empty());
  EXPECT_LT(v.motion.least_residual, 1e-13);
  EXPECT_NE(v.limit.find("circuit"), std::string::npos) << v.limit;
  EXPECT_NE(v.limit.find("traced"), std::string::npos) << v.limit;
  EXPECT_EQ(v.limit.find("closes nowhere"), std::string::npos) << v.limit;
}

TEST(Verify, CoaxialTrivialLoopMovesWithTwoJointsFrozen) {
  // Axes 1 and 3 coincide when theta2 = theta4 = pi (links 2 and 4 folded
  // back over links 1 and 3); the loop then turns about that axis only.
  const LoopGeometry g =
      LoopGeometry::from_degrees(std::vector<double>{1.5, 1.5, 2.5, 2.5}, std::vector<double>{40, 40, 70, 70},
                                 std::vector<double>{0.3, 0.0, -0.3, 0.0});
  JointVector start(4);
  start << rad(30), kPi, rad(-30), kPi;
  const VerificationSummary v = verify_motion(g, start);
  EXPECT_TRUE(v.verified);
  EXPECT_TRUE(v.full_turn);
  EXPECT_NEAR(v.joint_travel[0], 2 * kPi, 1e-9);
  EXPECT_NEAR(v.joint_travel[2], 2 * kPi, 1e-9);
  EXPECT_LT(v.joint_travel[1], 1e-9);
  EXPECT_LT(v.joint_travel[3], 1e-9);
}

TEST(Verify, BadInputThrows) {
  const LoopGeometry g = paper_bennett_loop();
  EXPECT_THROW(verify_motion(g, JointVector::Zero(3)), std::invalid_argument);
  JointVector nan_start = bennett_angles(g, rad(120));
  nan_start[1] = std::nan("");
  EXPECT_THROW(verify_motion(g, nan_start), std::invalid_argument);
  VerificationOptions coarse;
  coarse.steps_per_turn = 63;  // a step over 0.1 rad
  EXPECT_THROW(verify_motion(g, bennett_angles(g, rad(120)), coarse), std::invalid_argument);
  coarse.steps_per_turn = 64;
  EXPECT_TRUE(verify_motion(g, bennett_angles(g, rad(120)), coarse).verified);
  VerificationOptions no_scan;
  no_scan.scan_inputs = -1;
  EXPECT_THROW(verify_motion(g, nullptr, no_scan), std::invalid_argument);
  // Without the scan at fixed inputs the guesses with every joint free find
  // the Bennett loop's circuit, from fewer seeds.
  no_scan.scan_inputs = 0;
  const VerificationSummary free_only = verify_motion(g, nullptr, no_scan);
  const VerificationSummary scanned = verify_motion(g, nullptr);
  EXPECT_TRUE(free_only.verified);
  EXPECT_TRUE(free_only.full_turn);
  EXPECT_LT(free_only.motion.seeds, scanned.motion.seeds);
  EXPECT_EQ(free_only.motion.circuits.size(), scanned.motion.circuits.size());
}

}  // namespace
}  // namespace loopfarm
