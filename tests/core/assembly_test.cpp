#include "loopfarm/core/assembly.hpp"

#include <stdexcept>
#include <string>

#include <gtest/gtest.h>

#include "loopfarm/core/sample_loops.hpp"
#include "test_support.hpp"

namespace loopfarm {
namespace {

using testing::rad;

TEST(Assembly, MovableLoopsAssembleRigidlyWithoutGivenAngles) {
  const LoopGeometry loops[] = {paper_bennett_loop(), planar_four_bar(1.0, 3.0, 2.5, 3.5),
                                spherical_four_bar(rad(20), rad(70), rad(60), rad(80))};
  for (const LoopGeometry& g : loops) {
    const LoopModel model(g);
    EquilibriumWorkspace ws(model);
    for (double theta0 : {rad(120), rad(-40)}) {
      const EquilibriumSummary s = assemble(model, ws, theta0);
      ASSERT_EQ(s.status, SolveStatus::converged);
      EXPECT_LE(s.energy, 1e-20);
      EXPECT_EQ(s.state.theta[0], theta0);
      // The rigid loop itself closes at the assembled angles.
      EXPECT_LE(closure_residual(model.normalized_geometry(), s.state.theta).cwiseAbs().maxCoeff(), 1e-12);
    }
  }
}

TEST(Assembly, IsDeterministicWhateverTheWorkspaceHeld) {
  LoopGeometry g = paper_bennett_loop();
  g.a[0] = 2.03;
  const LoopModel model(g);
  EquilibriumWorkspace ws(model);
  const EquilibriumSummary first = assemble(model, ws, rad(120));
  solve_equilibrium(model, ws, 2.0, EquilibriumState::at_angles(model, random_angles(4, 9)));
  const EquilibriumSummary second = assemble(model, ws, rad(120));
  EXPECT_EQ(first.energy, second.energy);
  EXPECT_EQ(first.state.theta, second.state.theta);
}

// The kept assembly is the least-energy one: many random starting poses find
// no lower equilibrium.
TEST(Assembly, KeepsTheLeastEnergyEquilibrium) {
  for (std::uint64_t seed = 1; seed <= 4; ++seed) {
    const LoopGeometry g = random_loop(4 + static_cast<int>(seed % 2), seed);
    const LoopModel model(g);
    EquilibriumWorkspace ws(model);
    const EquilibriumSummary best = assemble(model, ws, 0.5);
    ASSERT_EQ(best.status, SolveStatus::converged) << seed;
    int converged = 0;
    for (std::uint64_t k = 0; k < 100; ++k) {
      JointVector theta = random_angles(g.joints(), 1000 * seed + k);
      const EquilibriumSummary s = solve_equilibrium(model, ws, 0.5, EquilibriumState::at_angles(model, theta));
      if (s.status != SolveStatus::converged) continue;
      ++converged;
      EXPECT_GE(s.energy, best.energy - 1e-12 * (1 + best.energy)) << "seed " << seed << " start " << k;
    }
    EXPECT_GT(converged, 50) << seed;
  }
}

TEST(Assembly, FromAnglesSolvesAtTheInputJointsAngle) {
  LoopGeometry g = paper_bennett_loop();
  g.a[0] = 2.03;
  EquilibriumOptions options;
  options.input_joint = 2;
  const LoopModel model(g, options);
  EquilibriumWorkspace ws(model);
  const JointVector theta = bennett_angles(paper_bennett_loop(), rad(120));
  const EquilibriumSummary s = assemble_from_angles(model, ws, theta);
  ASSERT_EQ(s.status, SolveStatus::converged);
  EXPECT_EQ(s.state.theta[2], theta[2]);
  EXPECT_GT(s.energy, 0.0);
  EXPECT_NEAR(wrap_angle(s.state.theta[0] - theta[0]), 0.0, 0.05);  // stayed near the given pose
}

// A non-Grashof planar four-bar cannot reach every input angle rigidly: there
// the least-energy assembly has energy, and where it can, none.
TEST(Assembly, UnreachableInputAngleCostsEnergy) {
  // Links 2 and 3 span a diagonal in [2.5, 4.5]; links 4 and 1 around the
  // input joint span [1.8, 4.2]: input angles where it is below 2.5 are out.
  const LoopGeometry g = planar_four_bar(3.0, 1.0, 3.5, 1.2);
  const LoopModel model(g);
  EquilibriumWorkspace ws(model);
  const EquilibriumSummary reachable = assemble(model, ws, rad(0));
  const EquilibriumSummary unreachable = assemble(model, ws, rad(180));
  ASSERT_EQ(reachable.status, SolveStatus::converged);
  ASSERT_EQ(unreachable.status, SolveStatus::converged);
  EXPECT_LE(reachable.energy, 1e-20);
  EXPECT_GT(unreachable.energy, 1e-3);
}

TEST(Assembly, InvalidGuessCountIsRejectedByName) {
  const LoopModel model(paper_bennett_loop());
  EquilibriumWorkspace ws(model);
  AssemblyOptions o;
  o.guesses = 0;
  try {
    assemble(model, ws, 0.0, o);
    ADD_FAILURE() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("guesses"), std::string::npos);
  }
}

}  // namespace
}  // namespace loopfarm
