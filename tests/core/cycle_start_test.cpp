#include "loopfarm/core/cycle_start.hpp"

#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "loopfarm/core/assembly.hpp"
#include "loopfarm/core/constructions.hpp"
#include "loopfarm/core/cycle.hpp"
#include "loopfarm/core/sample_loops.hpp"
#include "test_support.hpp"

namespace loopfarm {
namespace {

using testing::rad;

constexpr double kPi = 3.14159265358979323846;

// The non-Grashof four-bar a = 2, 3, 2.5, 4: its input rocks between
// lo = acos(10.25 / 16) and 2 pi - lo (law of cosines on the diagonal).
const LoopGeometry kRocker = planar_four_bar(2.0, 3.0, 2.5, 4.0);
const double kLo = std::acos(10.25 / 16.0);

double cycle_energy_from(const LoopModel& model, EquilibriumWorkspace& ws, double theta0, const CycleStart& start) {
  CycleOptions o;
  o.range = start.range;
  CycleSummary cycle;
  cycle_energy(model, ws, theta0, start.assembly.state, o, cycle);
  return cycle.failed_samples == 0 ? cycle.E_mean : std::numeric_limits<double>::infinity();
}

TEST(CycleStart, InsideARockersRangeTheWindowIsTheClosedFormAndTheEnergyZero) {
  const LoopModel model(kRocker);
  EquilibriumWorkspace ws(model);
  for (double theta0_deg : {60.0, 120.0, 200.0, 300.0}) {
    const double theta0 = rad(theta0_deg);
    const CycleStart start = choose_cycle_start(model, ws, theta0, nullptr);
    ASSERT_TRUE(start.motion.has_value()) << theta0_deg;
    EXPECT_NEAR(start.range, 1.8 * std::min(theta0 - kLo, 2 * kPi - kLo - theta0), 1e-9) << theta0_deg;
    EXPECT_LT(closure_residual(kRocker, start.assembly.state.theta).cwiseAbs().maxCoeff(), 1e-12) << theta0_deg;
    EXPECT_LE(cycle_energy_from(model, ws, theta0, start), 1e-20) << theta0_deg;
  }
}

TEST(CycleStart, OutsideTheRangeTheLeastEnergyAssemblyAndAFullTurn) {
  const LoopModel model(kRocker);
  EquilibriumWorkspace ws(model);
  const CycleStart start = choose_cycle_start(model, ws, 0.0, nullptr);
  EXPECT_FALSE(start.motion.has_value());
  EXPECT_EQ(start.range, 2 * kPi);
  const EquilibriumSummary least = assemble(model, ws, 0.0);
  EXPECT_EQ(start.assembly.state.theta, least.state.theta);
  EXPECT_GT(start.assembly.energy, 1e-6);  // the loop cannot close at 0
}

TEST(CycleStart, AGivenPoseIsKeptAndItsMotionsWindowTaken) {
  const LoopModel model(kRocker);
  EquilibriumWorkspace ws(model);
  const double theta0 = rad(200);
  for (const JointVector& mode : four_bar_poses(kRocker, 0, theta0)) {
    const CycleStart start = choose_cycle_start(model, ws, theta0, &mode);
    ASSERT_TRUE(start.motion.has_value());
    EXPECT_LT((start.assembly.state.theta - mode).cwiseAbs().maxCoeff(), 1e-9);
    EXPECT_NEAR(start.range, 1.8 * (2 * kPi - kLo - theta0), 1e-9);
  }
  // Asked for, the range is as asked.
  const CycleStart asked = choose_cycle_start(model, ws, theta0, nullptr, {.range = 2 * kPi});
  EXPECT_EQ(asked.range, 2 * kPi);
  EXPECT_TRUE(asked.motion.has_value());
}

TEST(CycleStart, ABennettLoopsInputTurnsFully) {
  const LoopGeometry g = paper_bennett_loop();
  const LoopModel model(g);
  EquilibriumWorkspace ws(model);
  for (double theta0_deg : {0.0, 120.0, -75.0}) {
    const CycleStart start = choose_cycle_start(model, ws, rad(theta0_deg), nullptr);
    ASSERT_TRUE(start.motion.has_value()) << theta0_deg;
    EXPECT_EQ(start.range, 2 * kPi) << theta0_deg;
    EXPECT_LE(cycle_energy_from(model, ws, rad(theta0_deg), start), 1e-20) << theta0_deg;
  }
}

TEST(CycleStart, ARigidLoopHasNoMotion) {
  const LoopGeometry g = LoopGeometry::from_degrees(
      std::vector<double>{1, 2, 3, 2.5}, std::vector<double>{20, 70, 40, 110}, std::vector<double>{0.1, -0.3, 0.2, 0});
  const LoopModel model(g);
  EquilibriumWorkspace ws(model);
  const CycleStart start = choose_cycle_start(model, ws, 0.0, nullptr);
  EXPECT_FALSE(start.motion.has_value());
  EXPECT_EQ(start.range, 2 * kPi);
}

}  // namespace
}  // namespace loopfarm
