#include "loopfarm/core/equilibrium.hpp"

#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "allocation_counter.hpp"
#include "loopfarm/core/assembly.hpp"
#include "loopfarm/core/sample_loops.hpp"
#include "test_support.hpp"

namespace loopfarm {
namespace {

using testing::rad;
using testing::reference_equilibrium;

EquilibriumSummary solve_from(const LoopModel& model, double theta_in, const JointVector& theta) {
  EquilibriumWorkspace ws(model);
  return solve_equilibrium(model, ws, theta_in, EquilibriumState::at_angles(model, theta));
}

// The asymmetric Bennett closure equations (2a): theta3 = -theta1,
// theta4 = -theta2, tan(theta1/2) tan(theta2/2) = sin((a2+a1)/2) / sin((a2-a1)/2).
void expect_bennett_closure(const LoopGeometry& g, const JointVector& t, double tol) {
  EXPECT_NEAR(wrap_angle(t[2] + t[0]), 0.0, tol);
  EXPECT_NEAR(wrap_angle(t[3] + t[1]), 0.0, tol);
  const double lhs = std::tan(t[0] / 2) * std::tan(t[1] / 2);
  const double rhs = std::sin((g.alpha[1] + g.alpha[0]) / 2) / std::sin((g.alpha[1] - g.alpha[0]) / 2);
  EXPECT_NEAR(lhs, rhs, tol * std::max(1.0, std::abs(rhs)));
}

// The line-symmetric closure equations (4a): theta3 = theta1, theta4 = theta2,
// tan(theta1/2) tan(theta2/2) = cos((a2+a1)/2) / cos((a2-a1)/2).
void expect_line_symmetric_closure(const LoopGeometry& g, const JointVector& t, double tol) {
  EXPECT_NEAR(wrap_angle(t[2] - t[0]), 0.0, tol);
  EXPECT_NEAR(wrap_angle(t[3] - t[1]), 0.0, tol);
  const double lhs = std::tan(t[0] / 2) * std::tan(t[1] / 2);
  const double rhs = std::cos((g.alpha[1] + g.alpha[0]) / 2) / std::cos((g.alpha[1] - g.alpha[0]) / 2);
  EXPECT_NEAR(lhs, rhs, tol * std::max(1.0, std::abs(rhs)));
}

TEST(Equilibrium, BennettLoopSolvesToZeroEnergyOnItsClosureCurve) {
  const LoopGeometry g = paper_bennett_loop();
  for (Compliance compliance : {Compliance::paper, Compliance::full}) {
    EquilibriumOptions options;
    options.compliance = compliance;
    const LoopModel model(g, options);
    for (double deg : {-150.0, -60.0, 20.0, 75.0, 120.0, 160.0}) {
      // Start away from the answer so that the solver has work to do.
      JointVector guess = bennett_angles(g, rad(deg));
      guess.tail(3).array() += 0.2;
      const EquilibriumSummary s = solve_from(model, rad(deg), guess);
      ASSERT_EQ(s.status, SolveStatus::converged) << deg;
      EXPECT_LE(s.energy, 1e-20) << deg;
      EXPECT_LE(s.closure_residual, 1e-13) << deg;
      EXPECT_EQ(s.state.theta[0], rad(deg));
      expect_bennett_closure(g, s.state.theta, 1e-10);
    }
  }
}

TEST(Equilibrium, LineSymmetricBennettLoopSolvesToZeroEnergyOnItsClosureCurve) {
  const LoopGeometry g = bennett_loop_line_symmetric(2.0, rad(30), rad(90));
  const LoopModel model(g);
  for (double deg : {-120.0, -30.0, 45.0, 120.0}) {
    JointVector guess = bennett_angles_line_symmetric(g, rad(deg));
    guess.tail(3).array() -= 0.15;
    const EquilibriumSummary s = solve_from(model, rad(deg), guess);
    ASSERT_EQ(s.status, SolveStatus::converged) << deg;
    EXPECT_LE(s.energy, 1e-20) << deg;
    expect_line_symmetric_closure(g, s.state.theta, 1e-10);
  }
}

TEST(Equilibrium, PlanarAndSphericalFourBarsHaveZeroEnergy) {
  // Grashof crank-rocker: shortest link 1 is the crank, so every input angle closes.
  const LoopGeometry planar = planar_four_bar(1.0, 3.0, 2.5, 3.5);
  const LoopGeometry spherical = spherical_four_bar(rad(20), rad(70), rad(60), rad(80));
  for (const LoopGeometry* g : {&planar, &spherical}) {
    const LoopModel model(*g);
    EquilibriumWorkspace ws(model);
    EquilibriumState state = EquilibriumState::at_angles(model, random_angles(4, 3));
    // Walk the input around, warm-starting each solve from the last.
    for (int j = 0; j < 24; ++j) {
      const double theta_in = rad(15.0 * j);
      const EquilibriumSummary s = solve_equilibrium(model, ws, theta_in, state);
      ASSERT_EQ(s.status, SolveStatus::converged) << j;
      EXPECT_LE(s.energy, 1e-20) << j;
      state = s.state;
    }
  }
}

// The returned state satisfies the KKT conditions, checked with a central-
// difference Jacobian of closure_residual instead of the solver's own.
TEST(Equilibrium, SolutionSatisfiesKktConditionsCheckedByFiniteDifferences) {
  for (std::uint64_t seed = 1; seed <= 6; ++seed) {
    const LoopGeometry g = random_loop(4 + static_cast<int>(seed % 3), seed);
    for (Compliance compliance : {Compliance::paper, Compliance::full}) {
      EquilibriumOptions options;
      options.compliance = compliance;
      options.torsion_stiffness_ratio = 0.5 + 0.3 * static_cast<double>(seed);
      const LoopModel model(g, options);
      EquilibriumWorkspace ws(model);
      const EquilibriumSummary s =
          solve_equilibrium(model, ws, 0.3, EquilibriumState::at_angles(model, random_angles(g.joints(), seed)));
      if (s.status != SolveStatus::converged) {
        ADD_FAILURE() << "seed " << seed << ": " << to_string(s.status);
        continue;
      }
      LoopGeometry deformed;
      deformed_geometry(model, s.state.deformations, deformed);
      EXPECT_LE(closure_residual(deformed, s.state.theta).cwiseAbs().maxCoeff(), 1e-12);
      // grad_u (1/2 d^T K d) + A^T lambda = 0 for every unknown u.
      for (int u = 0; u < model.unknown_count(); ++u) {
        const double h = 1e-6;
        auto residual_moved = [&](double step) {
          EquilibriumState moved = s.state;
          const int k = model.unknown_deformation(u);
          if (k >= 0)
            moved.deformations[k] += step;
          else
            moved.theta[model.unknown_joint(u)] += step;
          LoopGeometry gm;
          deformed_geometry(model, moved.deformations, gm);
          return closure_residual(gm, moved.theta);
        };
        const Vector6 column = (residual_moved(h) - residual_moved(-h)) / (2 * h);
        const int k = model.unknown_deformation(u);
        const double energy_gradient = k >= 0 ? model.deformation_stiffness(k) * s.state.deformations[k] : 0.0;
        EXPECT_NEAR(energy_gradient + column.dot(s.state.multipliers), 0.0, 1e-8)
            << "seed " << seed << " unknown " << u;
      }
    }
  }
}

// solve_equilibrium against the method of multipliers with finite differences
// (tests/support/test_support.hpp): same energy, same deformations, same pose.
TEST(Equilibrium, AgreesWithAnIndependentAugmentedLagrangianSolver) {
  struct Case {
    LoopGeometry g;
    double theta_in;
    JointVector guess;
  };
  std::vector<Case> cases;
  LoopGeometry long_link = paper_bennett_loop();
  long_link.a[0] = 2.03;
  for (double deg : {120.0, 45.0, -100.0}) {
    cases.push_back({long_link, rad(deg), bennett_angles(paper_bennett_loop(), rad(deg))});
  }
  for (std::uint64_t seed = 11; seed <= 14; ++seed) {
    const LoopGeometry g = random_loop(seed == 14 ? 5 : 4, seed);
    cases.push_back({g, 1.0, random_angles(g.joints(), seed)});
  }
  for (Compliance compliance : {Compliance::paper, Compliance::full}) {
    for (const Case& c : cases) {
      EquilibriumOptions options;
      options.compliance = compliance;
      const LoopModel model(c.g, options);
      const EquilibriumSummary s = solve_from(model, c.theta_in, c.guess);
      ASSERT_EQ(s.status, SolveStatus::converged);
      // Start the reference at the solution's pose: the question is whether
      // both methods call the same point the minimum, not which basin a
      // distant guess falls into.
      JointVector start = s.state.theta;
      start.array() += 0.05;
      const auto ref = reference_equilibrium(model, c.theta_in, start);
      ASSERT_TRUE(ref.converged) << ref.closure;
      EXPECT_NEAR(s.energy, ref.energy, 1e-7 * ref.energy + 1e-14);
      EXPECT_LT((s.state.deformations - ref.deformations).cwiseAbs().maxCoeff(), 1e-6);
      for (int i = 0; i < c.g.joints(); ++i) {
        EXPECT_NEAR(wrap_angle(s.state.theta[i] - ref.theta[i]), 0.0, 1e-6);
      }
    }
  }
}

TEST(Equilibrium, WarmStartFromTheAnswerConvergesAtOnce) {
  LoopGeometry g = paper_bennett_loop();
  g.a[0] = 2.03;
  const LoopModel model(g);
  EquilibriumWorkspace ws(model);
  const EquilibriumSummary cold = solve_equilibrium(
      model, ws, rad(120), EquilibriumState::at_angles(model, bennett_angles(paper_bennett_loop(), rad(120))));
  ASSERT_EQ(cold.status, SolveStatus::converged);
  const EquilibriumSummary again = solve_equilibrium(model, ws, rad(120), cold.state);
  EXPECT_EQ(again.status, SolveStatus::converged);
  EXPECT_LE(again.iterations, 1);
  EXPECT_NEAR(again.energy, cold.energy, 1e-15);
  // A neighbouring input angle from the previous answer: a few Newton steps.
  const EquilibriumSummary next = solve_equilibrium(model, ws, rad(122), cold.state);
  EXPECT_EQ(next.status, SolveStatus::converged);
  EXPECT_LE(next.iterations, 6);
}

// The path tangent d(state)/d theta_in against central differences of two
// solves at theta_in +- h: from equilibrium_tangent (a factorisation at the
// solution) to 1e-6, and from the summary (the last Newton step's
// factorisation, a predictor) to 1e-4. A rigid generic loop exercises the
// multiplier and curvature terms; the Bennett loop, driven at joint 3, the
// input-joint bookkeeping; the full compliance set, the offsets.
TEST(Equilibrium, PathTangentMatchesCentralDifferences) {
  struct Case {
    LoopGeometry geometry;
    Compliance compliance;
    int input_joint;
  };
  const Case cases[] = {{random_loop(4, 6), Compliance::paper, 0},
                        {random_loop(5, 11), Compliance::full, 1},
                        {paper_bennett_loop(), Compliance::paper, 2}};
  for (const Case& c : cases) {
    EquilibriumOptions options;
    options.compliance = c.compliance;
    options.input_joint = c.input_joint;
    const LoopModel model(c.geometry, options);
    EquilibriumWorkspace ws(model);
    const EquilibriumSummary anchor = assemble(model, ws, 0.3);
    ASSERT_EQ(anchor.status, SolveStatus::converged);
    const double theta = anchor.state.theta[c.input_joint];

    EquilibriumState exact_tangent;
    ASSERT_TRUE(equilibrium_tangent(model, ws, anchor.state, exact_tangent));
    // A solve with a few Newton steps, for the summary's tangent.
    EquilibriumState guess = anchor.state;
    guess.theta.array() += 0.02;
    const EquilibriumSummary solved = solve_equilibrium(model, ws, theta, guess);
    ASSERT_EQ(solved.status, SolveStatus::converged);
    ASSERT_TRUE(solved.has_tangent);

    const double h = 1e-5;
    const EquilibriumSummary plus = solve_equilibrium(model, ws, theta + h, anchor.state);
    const EquilibriumSummary minus = solve_equilibrium(model, ws, theta - h, anchor.state);
    ASSERT_EQ(plus.status, SolveStatus::converged);
    ASSERT_EQ(minus.status, SolveStatus::converged);
    auto expect_close = [&](const EquilibriumState& t, double tol, const char* what) {
      for (int i = 0; i < model.joints(); ++i) {
        const double fd = i == c.input_joint ? 1.0 : wrap_angle(plus.state.theta[i] - minus.state.theta[i]) / (2 * h);
        EXPECT_NEAR(t.theta[i], fd, tol * std::max(1.0, std::abs(fd))) << what << " theta" << i + 1;
      }
      for (int k = 0; k < model.deformation_count(); ++k) {
        const double fd = (plus.state.deformations[k] - minus.state.deformations[k]) / (2 * h);
        EXPECT_NEAR(t.deformations[k], fd, tol * std::max(1.0, std::abs(fd)))
            << what << " " << deformation_name(model, k);
      }
      for (int k = 0; k < 6; ++k) {
        const double fd = (plus.state.multipliers[k] - minus.state.multipliers[k]) / (2 * h);
        EXPECT_NEAR(t.multipliers[k], fd, tol * std::max(1.0, std::abs(fd))) << what << " lambda" << k;
      }
    };
    expect_close(exact_tangent, 1e-6, "equilibrium_tangent");
    expect_close(solved.tangent, 1e-4, "summary tangent");
  }
}

// The structured step (negligible multipliers: W = blockdiag(0, K)) against
// the general m x m factorisation it replaces: the same iterates to
// round-off, step by step (solves cut at 1, 2, 3 iterations from a guess
// away from the answer), the same iteration counts to convergence and the
// same path tangent. The paper's Bennett loop (both compliance sets, two
// input joints) and a Goldberg 5R loop, all movable. The structured steps
// are counted, so that the comparison cannot pass by both sides taking the
// general path.
TEST(Equilibrium, StructuredStepIsTheGeneralNewtonStep) {
  struct Case {
    LoopGeometry geometry;
    Compliance compliance;
    int input_joint;
    JointVector start;
  };
  const LoopGeometry bennett = paper_bennett_loop();
  // Goldberg's 5R from two Bennett loops (tests/core/cycle_nr_test.cpp), assembled.
  const double s3 = std::sqrt(3.0);
  const double a[] = {2, 1, s3, 2, 1 + s3}, alpha[] = {90, 30, 60, 90, 90}, d[] = {0, 0, 0, 0, 0};
  const LoopGeometry goldberg = LoopGeometry::from_degrees(a, alpha, d);
  const LoopModel goldberg_model(goldberg);
  EquilibriumWorkspace goldberg_ws(goldberg_model);
  const EquilibriumSummary goldberg_start = assemble(goldberg_model, goldberg_ws, 0.5);
  ASSERT_EQ(goldberg_start.status, SolveStatus::converged);
  ASSERT_LE(goldberg_start.energy, 1e-20);
  const std::vector<Case> cases = {{bennett, Compliance::paper, 0, bennett_angles(bennett, rad(120))},
                                   {bennett, Compliance::full, 2, bennett_angles(bennett, rad(-60))},
                                   {goldberg, Compliance::paper, 0, goldberg_start.state.theta}};
  for (const Case& c : cases) {
    EquilibriumOptions structured_options, general_options;
    structured_options.compliance = general_options.compliance = c.compliance;
    structured_options.input_joint = general_options.input_joint = c.input_joint;
    general_options.structured_step = false;
    const LoopModel structured(c.geometry, structured_options), general(c.geometry, general_options);
    EquilibriumWorkspace ws_structured(structured), ws_general(general);
    EquilibriumState guess = EquilibriumState::at_angles(structured, c.start);
    for (int i = 0; i < structured.joints(); ++i) {
      if (i != c.input_joint) guess.theta[i] += 0.05 * (i + 1);
    }
    const double theta_in = c.start[c.input_joint];
    for (int limit : {1, 2, 3, 0}) {
      const EquilibriumSummary s =
          solve_equilibrium(structured, ws_structured, theta_in, guess, {.max_iterations = limit});
      const EquilibriumSummary g = solve_equilibrium(general, ws_general, theta_in, guess, {.max_iterations = limit});
      // The first step always is one (the guess's multipliers are zero); in
      // between, the multipliers of a guess off the closure curve can grow
      // past the negligible level, and such steps are general on both sides.
      EXPECT_GE(s.structured_steps, 1) << "limit " << limit;
      if (limit == 1) {
        EXPECT_EQ(s.structured_steps, 1);
      }
      EXPECT_EQ(g.structured_steps, 0);
      EXPECT_EQ(s.iterations, g.iterations) << "limit " << limit;
      EXPECT_EQ(s.status, g.status) << "limit " << limit;
      for (int i = 0; i < structured.joints(); ++i) {
        EXPECT_NEAR(wrap_angle(s.state.theta[i] - g.state.theta[i]), 0.0, 1e-12) << "limit " << limit;
      }
      EXPECT_LE((s.state.deformations - g.state.deformations).cwiseAbs().maxCoeff(), 1e-12) << "limit " << limit;
      EXPECT_LE((s.state.multipliers - g.state.multipliers).cwiseAbs().maxCoeff(), 1e-12) << "limit " << limit;
      if (limit == 0) {
        ASSERT_EQ(s.status, SolveStatus::converged);
        EXPECT_GT(s.iterations, 2);
        ASSERT_TRUE(s.has_tangent && g.has_tangent);
        for (int i = 0; i < structured.joints(); ++i) {
          EXPECT_NEAR(s.tangent.theta[i], g.tangent.theta[i], 1e-9 * std::max(1.0, std::abs(g.tangent.theta[i])));
        }
        EXPECT_LE((s.tangent.deformations - g.tangent.deformations).cwiseAbs().maxCoeff(), 1e-9);
      }
    }
  }
}

// The structured Gauss-Newton step (blockdiag(rho I, K + rho I)) against the
// general one: solves of generic 4R loops from far guesses, which start with
// negligible multipliers and fall back to Gauss-Newton steps on the way,
// reach the same equilibrium in the same number of iterations either way.
TEST(Equilibrium, StructuredGaussNewtonStepIsTheGeneralOne) {
  int structured_gauss_newton = 0;
  for (std::uint64_t seed = 1; seed <= 12; ++seed) {
    const LoopGeometry g = random_loop(4, seed);
    EquilibriumOptions general_options;
    general_options.structured_step = false;
    const LoopModel structured(g), general(g, general_options);
    EquilibriumWorkspace ws_structured(structured), ws_general(general);
    const EquilibriumState guess = EquilibriumState::at_angles(structured, random_angles(4, 100 + seed));
    const EquilibriumSummary s = solve_equilibrium(structured, ws_structured, 0.4, guess);
    const EquilibriumSummary r = solve_equilibrium(general, ws_general, 0.4, guess);
    EXPECT_EQ(s.status, r.status) << "seed " << seed;
    EXPECT_EQ(s.iterations, r.iterations) << "seed " << seed;
    EXPECT_EQ(s.gauss_newton_steps, r.gauss_newton_steps) << "seed " << seed;
    // Converged: the same equilibrium to the tolerances. Not converged (seed
    // 10 creeps through 87 Gauss-Newton steps to the iteration limit): the
    // round-off of 100 steps apart (angles 7e-10 and energies 4e-11 apart
    // here; asserted to 1e-5 and 1e-7).
    const double tolerance = s.status == SolveStatus::converged ? 1e-12 : 1e-7;
    EXPECT_NEAR(s.energy, r.energy, tolerance * std::max(1.0, r.energy)) << "seed " << seed;
    for (int i = 0; i < 4; ++i) {
      EXPECT_NEAR(wrap_angle(s.state.theta[i] - r.state.theta[i]), 0.0, 100 * tolerance) << "seed " << seed;
    }
    if (s.gauss_newton_steps > 0 && s.structured_steps > 1) ++structured_gauss_newton;
  }
  // Some of these solves did take structured Gauss-Newton steps.
  EXPECT_GT(structured_gauss_newton, 0);
}

// Simplified Newton steps (the last exact factorisation reused near the
// solution) against full Newton steps throughout: continuation-like solves
// of generic loops, 0.1 rad on from an assembled pose, reach the same
// equilibrium to the tolerances, in at most one more iteration, and give the
// same path tangent to a predictor's accuracy.
TEST(Equilibrium, SimplifiedNewtonStepsReachTheSameEquilibrium) {
  int simplified = 0;
  for (Compliance compliance : {Compliance::paper, Compliance::full}) {
    for (std::uint64_t seed = 1; seed <= 6; ++seed) {
      const LoopGeometry g = random_loop(seed == 6 ? 5 : 4, seed);
      EquilibriumOptions on, off;
      on.compliance = off.compliance = compliance;
      off.simplified_newton = false;
      const LoopModel model_on(g, on), model_off(g, off);
      EquilibriumWorkspace ws_on(model_on), ws_off(model_off);
      const EquilibriumSummary start = assemble(model_off, ws_off, 0.3);
      ASSERT_EQ(start.status, SolveStatus::converged) << "seed " << seed;
      const EquilibriumSummary a = solve_equilibrium(model_on, ws_on, 0.4, start.state);
      const EquilibriumSummary b = solve_equilibrium(model_off, ws_off, 0.4, start.state);
      ASSERT_EQ(a.status, SolveStatus::converged) << "seed " << seed;
      ASSERT_EQ(b.status, SolveStatus::converged) << "seed " << seed;
      EXPECT_EQ(b.simplified_steps, 0);
      EXPECT_LE(a.iterations, b.iterations + 1) << "seed " << seed;
      // Both within the solver's tolerances of the same KKT point.
      EXPECT_LE(a.closure_residual, 1e-13);
      EXPECT_LE(a.stationarity, 1e-11);
      EXPECT_NEAR(a.energy, b.energy, 1e-11 * std::max(1.0, b.energy)) << "seed " << seed;
      for (int i = 0; i < g.joints(); ++i) {
        EXPECT_NEAR(wrap_angle(a.state.theta[i] - b.state.theta[i]), 0.0, 1e-10) << "seed " << seed;
      }
      EXPECT_LE((a.state.deformations - b.state.deformations).cwiseAbs().maxCoeff(), 1e-10) << "seed " << seed;
      ASSERT_TRUE(a.has_tangent && b.has_tangent) << "seed " << seed;
      for (int i = 0; i < g.joints(); ++i) {
        EXPECT_NEAR(a.tangent.theta[i], b.tangent.theta[i], 1e-4 * std::max(1.0, std::abs(b.tangent.theta[i])))
            << "seed " << seed;
      }
      simplified += a.simplified_steps;
    }
  }
  // The comparison is not empty: simplified steps were taken.
  EXPECT_GT(simplified, 0);
}

// SolveLimits::stepping_tolerance ends a solve at its first iterate within
// it, after at least one step, with a tangent; a full solve from there reaches
// the equilibrium the full solve from the start reaches. Warm solves of
// generic loops 0.1 rad from an assembled state, as a continuation's are.
TEST(Equilibrium, SteppingToleranceEndsAtTheFirstIterateWithinIt) {
  constexpr double kStepping = 1e-6;
  int saved = 0;
  for (std::uint64_t seed = 1; seed <= 8; ++seed) {
    const LoopGeometry g = random_loop(4, seed);
    const LoopModel model(g);
    EquilibriumWorkspace ws(model);
    const EquilibriumSummary start = assemble(model, ws, 0.3);
    ASSERT_EQ(start.status, SolveStatus::converged) << "seed " << seed;
    const EquilibriumSummary full = solve_equilibrium(model, ws, 0.4, start.state);
    const EquilibriumSummary loose = solve_equilibrium(model, ws, 0.4, start.state, {.stepping_tolerance = kStepping});
    ASSERT_EQ(full.status, SolveStatus::converged) << "seed " << seed;
    ASSERT_EQ(loose.status, SolveStatus::converged) << "seed " << seed;
    EXPECT_GE(loose.iterations, 1) << "seed " << seed;
    EXPECT_LE(loose.iterations, full.iterations) << "seed " << seed;
    EXPECT_LE(loose.closure_residual, kStepping) << "seed " << seed;
    EXPECT_LE(loose.stationarity, kStepping) << "seed " << seed;
    EXPECT_TRUE(loose.has_tangent) << "seed " << seed;
    // Not a step later than needed: one iteration fewer is not yet within it.
    if (loose.iterations > 1) {
      const EquilibriumSummary before =
          solve_equilibrium(model, ws, 0.4, start.state, {.max_iterations = loose.iterations - 1});
      EXPECT_GT(std::max(before.closure_residual, before.stationarity), kStepping) << "seed " << seed;
    }
    saved += full.iterations - loose.iterations;
    // The stepping stone leads to the same equilibrium.
    const EquilibriumSummary on = solve_equilibrium(model, ws, 0.4, loose.state);
    ASSERT_EQ(on.status, SolveStatus::converged) << "seed " << seed;
    EXPECT_NEAR(on.energy, full.energy, 1e-11 * std::max(1.0, full.energy)) << "seed " << seed;
    for (int i = 0; i < g.joints(); ++i) {
      EXPECT_NEAR(wrap_angle(on.state.theta[i] - full.state.theta[i]), 0.0, 1e-10) << "seed " << seed;
    }
  }
  EXPECT_GT(saved, 0);  // the loose solves did end earlier
}

// A solve given a limit on its Gauss-Newton steps stops (max_iterations)
// instead of taking one more, and is otherwise the unlimited solve: cold
// solves of generic loops from random angles, which fall back to such steps.
TEST(Equilibrium, GaussNewtonLimitStopsBeforeTheNextGaussNewtonStep) {
  int limited = 0;
  for (std::uint64_t seed = 1; seed <= 12; ++seed) {
    const LoopGeometry g = random_loop(4, seed);
    const LoopModel model(g);
    EquilibriumWorkspace ws(model);
    const EquilibriumState guess = EquilibriumState::at_angles(model, random_angles(4, 100 + seed));
    const EquilibriumSummary free = solve_equilibrium(model, ws, 0.4, guess);
    if (free.gauss_newton_steps == 0) continue;
    ++limited;
    for (int limit = 0; limit < std::min(free.gauss_newton_steps, 3); ++limit) {
      const EquilibriumSummary s = solve_equilibrium(model, ws, 0.4, guess, {.max_gauss_newton_steps = limit});
      EXPECT_EQ(s.status, SolveStatus::max_iterations) << "seed " << seed << " limit " << limit;
      EXPECT_EQ(s.gauss_newton_steps, limit) << "seed " << seed;
      EXPECT_LT(s.iterations, free.iterations) << "seed " << seed;
    }
    // A limit the solve does not reach changes nothing.
    const EquilibriumSummary same =
        solve_equilibrium(model, ws, 0.4, guess, {.max_gauss_newton_steps = free.gauss_newton_steps});
    EXPECT_EQ(same.status, free.status) << "seed " << seed;
    EXPECT_EQ(same.iterations, free.iterations) << "seed " << seed;
    EXPECT_EQ(same.energy, free.energy) << "seed " << seed;
  }
  EXPECT_GT(limited, 2);
}

TEST(Equilibrium, SolveDoesNotAllocate) {
  if (!testing::kCountsAllocations) GTEST_SKIP() << "allocations are not counted under AddressSanitizer";
  for (int n : {4, 6, 8}) {
    const LoopGeometry g = random_loop(n, 40 + n);
    EquilibriumOptions options;
    options.compliance = Compliance::full;
    const LoopModel model(g, options);
    EquilibriumWorkspace ws(model);
    const EquilibriumState guess = EquilibriumState::at_angles(model, random_angles(n, 3));
    EquilibriumSummary s = solve_equilibrium(model, ws, 0.7, guess);  // warm-up
    const long before = testing::allocations();
    s = solve_equilibrium(model, ws, 0.7, guess);
    s = solve_equilibrium(model, ws, 0.8, s.state);
    EquilibriumState tangent = s.state;
    equilibrium_tangent(model, ws, s.state, tangent);
    EXPECT_EQ(testing::allocations() - before, 0) << "n = " << n;
    EXPECT_GT(s.iterations, 0);
  }
  {
    // The structured step (a movable loop: negligible multipliers), with the tangent it leaves.
    const LoopModel model(paper_bennett_loop());
    EquilibriumWorkspace ws(model);
    JointVector start = bennett_angles(model.geometry(), 1.0);
    start.tail(3).array() += 0.1;
    const EquilibriumState guess = EquilibriumState::at_angles(model, start);
    EquilibriumSummary s = solve_equilibrium(model, ws, 1.0, guess);  // warm-up
    const long before = testing::allocations();
    s = solve_equilibrium(model, ws, 1.0, guess);
    s = solve_equilibrium(model, ws, 1.1, s.state);
    EXPECT_EQ(testing::allocations() - before, 0) << "structured step";
    EXPECT_GT(s.structured_steps, 0);
    EXPECT_TRUE(s.has_tangent);
  }
  // The counter works: an allocation is seen, from new and from Eigen's
  // dynamic-size matrices (std::malloc) alike.
  const long before = testing::allocations();
  auto* probe = new std::string(100, 'x');
  EXPECT_GT(testing::allocations() - before, 0);
  delete probe;
#if defined(__GLIBC__)
  const long before_eigen = testing::allocations();
  Eigen::MatrixXd dynamic(7, 7);
  dynamic.setZero();
  EXPECT_GT(testing::allocations() - before_eigen, 0) << "an Eigen::MatrixXd allocation went uncounted";
#endif
}

TEST(Equilibrium, NonFiniteGuessIsReportedNotThrown) {
  const LoopModel model(paper_bennett_loop());
  EquilibriumWorkspace ws(model);
  JointVector theta = bennett_angles(paper_bennett_loop(), 1.0);
  theta[2] = std::nan("");
  const EquilibriumSummary s = solve_equilibrium(model, ws, 1.0, EquilibriumState::at_angles(model, theta));
  EXPECT_EQ(s.status, SolveStatus::non_finite);
}

TEST(Equilibrium, InvalidOptionsAreRejectedByName) {
  const LoopGeometry g = paper_bennett_loop();
  auto message = [&](EquilibriumOptions o) -> std::string {
    try {
      LoopModel model(g, o);
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "";
  };
  EquilibriumOptions o;
  o.torsion_stiffness_ratio = 0.0;
  EXPECT_NE(message(o).find("torsion_stiffness_ratio"), std::string::npos);
  o = {};
  o.torsion_stiffness_ratio = std::nan("");
  EXPECT_NE(message(o).find("torsion_stiffness_ratio"), std::string::npos);
  o = {};
  o.input_joint = 4;
  EXPECT_NE(message(o).find("input_joint"), std::string::npos);
  o = {};
  o.closure_tolerance = -1;
  EXPECT_NE(message(o).find("closure_tolerance"), std::string::npos);
  o = {};
  o.max_iterations = 0;
  EXPECT_NE(message(o).find("max_iterations"), std::string::npos);
  EXPECT_EQ(message({}), "");
  EXPECT_THROW(compliance_from_string("stiff"), std::invalid_argument);
  EXPECT_EQ(compliance_from_string("full"), Compliance::full);
}

// The torsion ratio r weights the twist springs: E(r) = min (|da|^2 + r |dalpha|^2) / 2
// rises with r, and the twist deformation |dalpha| falls (the exchange
// argument for a parametric minimum: f + r g has g(x*(r)) non-increasing).
TEST(Equilibrium, TorsionStiffnessRatioWeightsTheTwistDeformations) {
  LoopGeometry g = paper_bennett_loop();
  g.a[0] = 2.03;
  const JointVector guess = bennett_angles(paper_bennett_loop(), rad(120));
  double previous_energy = 0.0;
  double previous_twist = 1e300;
  for (double ratio : {0.1, 1.0, 10.0, 100.0}) {
    EquilibriumOptions o;
    o.torsion_stiffness_ratio = ratio;
    const LoopModel model(g, o);
    const EquilibriumSummary s = solve_from(model, rad(120), guess);
    ASSERT_EQ(s.status, SolveStatus::converged);
    EXPECT_GT(s.energy, previous_energy) << ratio;
    const double twist = s.state.deformations.segment(4, 4).norm();
    EXPECT_LT(twist, previous_twist) << ratio;
    previous_energy = s.energy;
    previous_twist = twist;
  }
}

}  // namespace
}  // namespace loopfarm
