// The paper's figures (Xu & Li 2017, README.md "Citing"; docs/quality/paper-figures.md) as asserted tests.
// The charts of the same runs are in docs/quality/figures/ (docs/quality/make_figures.sh).
#include <cmath>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/SVD>

#include "loopfarm/core/assembly.hpp"
#include "loopfarm/core/cycle.hpp"
#include "loopfarm/core/sample_loops.hpp"
#include "test_support.hpp"

namespace loopfarm {
namespace {

using testing::rad;

// The paper's start: theta1 = 120 deg, theta2 = 90 deg (and, on the Bennett
// closure curve, theta3 = -120, theta4 = -90 in the asymmetric setup).
JointVector paper_start() {
  JointVector theta(4);
  theta << rad(120), rad(90), rad(-120), rad(-90);
  return theta;
}

CycleSummary paper_cycle(const LoopGeometry& g, const JointVector& start, int samples = 32) {
  const LoopModel model(g);
  EquilibriumWorkspace ws(model);
  const EquilibriumSummary assembled = assemble_from_angles(model, ws, start);
  CycleOptions options;
  options.samples = samples;
  CycleSummary summary;
  cycle_energy(model, ws, start[0], assembled.state, options, summary);
  return summary;
}

LoopGeometry paper_loop_with(double a1, double a2) {
  LoopGeometry g = paper_bennett_loop();
  g.a[0] = a1;
  g.a[2] = a1;
  g.a[1] = a2;
  g.a[3] = a2;
  return g;
}

// Fig. 6: the quasi-perfect Bennett loop has zero energy over the whole cycle,
// on the closure curve of eqs. (2a).
TEST(PaperFigure6, BennettLoopHasZeroEnergyOverTheCycleOnItsClosureCurve) {
  const LoopGeometry g = paper_bennett_loop();
  const CycleSummary s = paper_cycle(g, paper_start(), 64);
  EXPECT_EQ(s.failed_samples, 0);
  EXPECT_EQ(s.branch_jumps, 0);
  const double ratio = std::sin((g.alpha[1] + g.alpha[0]) / 2) / std::sin((g.alpha[1] - g.alpha[0]) / 2);
  EXPECT_NEAR(ratio, std::sqrt(3.0), 1e-15);  // the start satisfies it: tan 60 tan 45
  for (const CycleSample& sample : s.samples) {
    EXPECT_LE(sample.energy, 1e-20) << sample.theta_in;
    const JointVector& t = sample.state.theta;
    EXPECT_NEAR(wrap_angle(t[2] + t[0]), 0.0, 1e-10);
    EXPECT_NEAR(wrap_angle(t[3] + t[1]), 0.0, 1e-10);
    // tan(theta1/2) tan(theta2/2) = ratio, written without the poles of tan:
    // sin(t1/2) sin(t2/2) - ratio cos(t1/2) cos(t2/2) = 0.
    EXPECT_NEAR(std::sin(t[0] / 2) * std::sin(t[1] / 2) - ratio * std::cos(t[0] / 2) * std::cos(t[1] / 2), 0.0, 1e-10);
  }
}

// Fig. 6, line-symmetric setup (eqs. 3-4): joints 3 and 4 reversed, so
// alpha2 = alpha4 = -90 deg, theta3 = theta1, theta4 = theta2.
TEST(PaperFigure6, LineSymmetricSetupHasZeroEnergyOnItsClosureCurve) {
  const LoopGeometry g = bennett_loop_line_symmetric(2.0, rad(30), rad(90));
  EXPECT_NEAR(g.a[1], 4.0, 1e-15);
  const CycleSummary s = paper_cycle(g, bennett_angles_line_symmetric(g, rad(120)), 64);
  EXPECT_EQ(s.failed_samples, 0);
  const double ratio = std::cos((g.alpha[1] + g.alpha[0]) / 2) / std::cos((g.alpha[1] - g.alpha[0]) / 2);
  for (const CycleSample& sample : s.samples) {
    EXPECT_LE(sample.energy, 1e-20) << sample.theta_in;
    const JointVector& t = sample.state.theta;
    EXPECT_NEAR(wrap_angle(t[2] - t[0]), 0.0, 1e-10);
    EXPECT_NEAR(wrap_angle(t[3] - t[1]), 0.0, 1e-10);
    EXPECT_NEAR(std::sin(t[0] / 2) * std::sin(t[1] / 2) - ratio * std::cos(t[0] / 2) * std::cos(t[1] / 2), 0.0, 1e-10);
  }
}

// Fig. 7: lengthening link 1 raises the peak energy from zero, as the square
// of the error (the deformations are linear in it, the energy quadratic).
TEST(PaperFigure7, PeakEnergyGrowsAsTheSquareOfTheLengthError) {
  std::vector<double> error, peak;
  for (int k = 0; k <= 5; ++k) {
    LoopGeometry g = paper_bennett_loop();
    g.a[0] = 2.0 + 0.02 * k;
    const CycleSummary s = paper_cycle(g, paper_start());
    ASSERT_EQ(s.failed_samples, 0) << g.a[0];
    if (k == 0) {
      EXPECT_LE(s.E_max, 1e-20);
      continue;
    }
    error.push_back(0.02 * k);
    peak.push_back(s.E_max);
  }
  for (size_t i = 1; i < peak.size(); ++i) {
    EXPECT_GT(peak[i], peak[i - 1]);
    const double slope = std::log(peak[i] / peak[i - 1]) / std::log(error[i] / error[i - 1]);
    EXPECT_NEAR(slope, 2.0, 0.1) << "between a1 = " << 2 + error[i - 1] << " and " << 2 + error[i];
  }
  // The coefficient itself, E_max ~ c (da)^2, is the same at both ends of the range to 10 %.
  const double c_small = peak.front() / (error.front() * error.front());
  const double c_large = peak.back() / (error.back() * error.back());
  EXPECT_NEAR(c_large / c_small, 1.0, 0.1);
}

// Fig. 12: the two link-length combinations of the paper's optimisation. Both
// miss the Bennett ratio a2 = 2 a1 (1.97 -> 3.94 vs 4.03; 2.03 -> 4.06 vs
// 4.01), the first by more, and its peak energy E1_max is the larger (Fig. 13).
TEST(PaperFigure12, FirstCombinationHasTheLargerPeakEnergy) {
  const CycleSummary first = paper_cycle(paper_loop_with(1.97, 4.03), paper_start());
  const CycleSummary second = paper_cycle(paper_loop_with(2.03, 4.01), paper_start());
  ASSERT_EQ(first.failed_samples + second.failed_samples, 0);
  EXPECT_GT(second.E_max, 1e-8);
  EXPECT_GT(first.E_max, second.E_max);
  EXPECT_GT(first.E_mean, second.E_mean);
  // A scaled Bennett loop is still a Bennett loop: (2.03, 4.06) moves.
  EXPECT_LE(paper_cycle(paper_loop_with(2.03, 4.06), paper_start()).E_max, 1e-20);
}

// The flat-folded poses of the paper's loop with a1 = 2.03: theta1 = 0 and 180
// deg, where every axis lies in one plane and the closure Jacobian loses rank.
// The solve converges there, the energy curve has a cusp (the folded pose is
// lower than its neighbours on both sides), and the independent augmented-
// Lagrangian solver agrees.
TEST(PaperFoldedPoses, SolveConvergesAtTheCuspAndAgreesWithASecondMethod) {
  LoopGeometry g = paper_bennett_loop();
  g.a[0] = 2.03;
  const LoopModel model(g);
  EquilibriumWorkspace ws(model);
  for (double folded_deg : {0.0, 180.0}) {
    // Approach along the cycle: the paper's start, continued to the folded pose.
    CycleOptions options;
    options.samples = 121;
    const double from = rad(120);
    const double to = rad(folded_deg);
    options.range = 2 * std::abs(to - from);
    CycleSummary s;
    cycle_energy(model, ws, from, assemble_from_angles(model, ws, paper_start()).state, options, s);
    // Sample 0 or 120 is theta0 -/+ range/2, the folded pose itself.
    const size_t at = to < from ? 0 : 120;
    const CycleSample& folded = s.samples[at];
    ASSERT_NEAR(folded.theta_in, to, 1e-12);
    ASSERT_EQ(folded.solve_status, SolveStatus::converged) << folded_deg;

    // The closure Jacobian with respect to the unknowns (3 passive angles, 4
    // lengths, 4 twists) loses rank at the fold: all axes lie in one plane.
    ClosureJacobians jac;
    closure_jacobians(model.normalized_geometry(), bennett_angles(paper_bennett_loop(), to), jac);
    Eigen::MatrixXd a(6, 11);
    a << jac.theta.rightCols(3), jac.a, jac.alpha;
    Eigen::JacobiSVD<Eigen::MatrixXd> svd(a);
    EXPECT_LT(svd.singularValues()[5], 1e-14 * svd.singularValues()[0]) << folded_deg;

    // Cusp: lower than the neighbours on either side, at 1 and 3 degrees.
    for (double offset_deg : {1.0, 3.0}) {
      for (double side : {-1.0, 1.0}) {
        const EquilibriumSummary near = solve_equilibrium(model, ws, to + side * rad(offset_deg), folded.state);
        ASSERT_EQ(near.status, SolveStatus::converged);
        EXPECT_GT(near.energy, folded.energy) << folded_deg << " " << side * offset_deg;
      }
    }
    // Second method, started a little off the folded pose.
    JointVector start = folded.state.theta;
    start.array() += 0.05;
    const auto ref = testing::reference_equilibrium(model, to, start);
    ASSERT_TRUE(ref.converged) << folded_deg;
    EXPECT_NEAR(folded.energy, ref.energy, 1e-6 * ref.energy) << folded_deg;
  }
}

// The other movable 4R families over a whole cycle, assembled automatically:
// a planar four-bar whose input link is a crank (Grashof, shortest link
// driven) and a spherical 4R whose input turns fully.
TEST(MovableFamilies, PlanarCrankAndSphericalLoopHaveZeroCycleEnergy) {
  const LoopGeometry planar = planar_four_bar(1.0, 3.0, 2.5, 3.5);
  const LoopGeometry spherical = spherical_four_bar(rad(20), rad(70), rad(60), rad(80));
  for (const LoopGeometry* g : {&planar, &spherical}) {
    const LoopModel model(*g);
    EquilibriumWorkspace ws(model);
    const EquilibriumSummary start = assemble(model, ws, 0.0);
    ASSERT_EQ(start.status, SolveStatus::converged);
    CycleOptions options;
    options.samples = 64;
    CycleSummary s;
    cycle_energy(model, ws, 0.0, start.state, options, s);
    EXPECT_EQ(s.failed_samples + s.branch_jumps, 0);
    EXPECT_LE(s.E_max, 1e-20);
  }
}

}  // namespace
}  // namespace loopfarm
