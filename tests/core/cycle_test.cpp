#include "loopfarm/core/cycle.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include <gtest/gtest.h>

#include "allocation_counter.hpp"
#include "loopfarm/core/assembly.hpp"
#include "loopfarm/core/sample_loops.hpp"
#include "test_support.hpp"

namespace loopfarm {
namespace {

using testing::rad;
using testing::relative_error;

constexpr double kPi = 3.14159265358979323846;

// The paper's loop with link 1 lengthened to 2.03: not movable, smooth cycle.
LoopGeometry long_link_loop() {
  LoopGeometry g = paper_bennett_loop();
  g.a[0] = 2.03;
  return g;
}

JointVector paper_start() { return bennett_angles(paper_bennett_loop(), rad(120)); }

CycleSummary run_cycle(const LoopGeometry& g, const JointVector& start, const EquilibriumOptions& eo = {},
                       const CycleOptions& co = {}) {
  const LoopModel model(g, eo);
  EquilibriumWorkspace ws(model);
  const EquilibriumSummary assembled = assemble_from_angles(model, ws, start);
  CycleSummary summary;
  cycle_energy(model, ws, start[eo.input_joint], assembled.state, co, summary);
  return summary;
}

// A parameter of the geometry in GeometryVector order (a, alpha, d).
double& parameter(LoopGeometry& g, int j) {
  const int n = g.joints();
  if (j < n) return g.a[j];
  if (j < 2 * n) return g.alpha[j - n];
  return g.d[j - 2 * n];
}

struct GradientCase {
  const char* name;
  LoopGeometry g;
  JointVector start;
  Compliance compliance;
};

std::vector<GradientCase> gradient_cases() {
  std::vector<GradientCase> cases;
  cases.push_back({"paper loop a1=2.03", long_link_loop(), paper_start(), Compliance::paper});
  LoopGeometry offset = long_link_loop();
  offset.d << 0.1, -0.05, 0.2, 0.0;
  cases.push_back({"with offsets, full compliance", offset, paper_start(), Compliance::full});
  LoopGeometry five = random_loop(5, 21);
  cases.push_back({"random 5R", five, random_angles(5, 21), Compliance::paper});
  return cases;
}

// A gradient case's cycle, solved with N samples.
struct SolvedCycle {
  SolvedCycle(const GradientCase& c, int samples)
      : eo(options_for(c)), co(cycle_options(samples)), model(c.g, eo), ws(model) {
    cycle_energy(model, ws, c.start[0], assemble_from_angles(model, ws, c.start).state, co, summary);
  }
  static EquilibriumOptions options_for(const GradientCase& c) {
    EquilibriumOptions o;
    o.compliance = c.compliance;
    return o;
  }
  static CycleOptions cycle_options(int samples) {
    CycleOptions o;
    o.samples = samples;
    return o;
  }
  EquilibriumOptions eo;
  CycleOptions co;
  LoopModel model;
  EquilibriumWorkspace ws;
  CycleSummary summary;
};

// dE_mean/dp from the multipliers against central differences of whole cycles.
TEST(Cycle, EnergyGradientAgreesWithCentralDifferences) {
  for (const GradientCase& c : gradient_cases()) {
    SolvedCycle s(c, 16);
    ASSERT_EQ(s.summary.failed_samples + s.summary.branch_jumps, 0) << c.name;
    ASSERT_GT(s.summary.E_mean, 1e-8) << c.name;
    const GeometryVector gradient = cycle_energy_gradient(s.model, s.ws, s.summary);

    const int np = 3 * c.g.joints();
    Eigen::VectorXd fd(np);
    for (int j = 0; j < np; ++j) {
      const double h = 1e-5;
      auto e_mean = [&](double step) {
        LoopGeometry g = c.g;
        parameter(g, j) += step;
        // Started from the base cycle's solved pose: the same branch.
        return run_cycle(g, s.summary.samples[0].state.theta, s.eo, s.co).E_mean;
      };
      fd[j] = (e_mean(h) - e_mean(-h)) / (2 * h);
    }
    EXPECT_LT((gradient - fd).cwiseAbs().maxCoeff(), 1e-6 * fd.cwiseAbs().maxCoeff())
        << c.name << "\nanalytic " << gradient.transpose() << "\nfd       " << fd.transpose();
  }
}

// d r/dp by implicit differentiation against central differences of the
// stacked weighted deformations; and E_mean = |r|^2 / 2 ties it to the gradient.
TEST(Cycle, DeformationJacobianAgreesWithCentralDifferences) {
  for (const GradientCase& c : gradient_cases()) {
    SolvedCycle s(c, 8);
    ASSERT_EQ(s.summary.failed_samples + s.summary.branch_jumps, 0) << c.name;
    const Eigen::VectorXd r = cycle_weighted_deformations(s.model, s.summary);
    EXPECT_NEAR(0.5 * r.squaredNorm(), s.summary.E_mean, 1e-14 + 1e-12 * s.summary.E_mean);
    const Eigen::MatrixXd jacobian = cycle_deformation_jacobian(s.model, s.ws, s.summary);
    ASSERT_EQ(jacobian.rows(), r.size());
    ASSERT_EQ(jacobian.cols(), 3 * c.g.joints());

    Eigen::MatrixXd fd(jacobian.rows(), jacobian.cols());
    for (int j = 0; j < jacobian.cols(); ++j) {
      const double h = 1e-5;
      auto weighted = [&](double step) {
        LoopGeometry g = c.g;
        parameter(g, j) += step;
        const LoopModel moved(g, s.eo);
        return cycle_weighted_deformations(moved, run_cycle(g, s.summary.samples[0].state.theta, s.eo, s.co));
      };
      fd.col(j) = (weighted(h) - weighted(-h)) / (2 * h);
    }
    EXPECT_LT(relative_error(jacobian, fd), 1e-6) << c.name;
    // Gauss-Newton identity: grad E_mean = J^T r.
    const GeometryVector gradient = cycle_energy_gradient(s.model, s.ws, s.summary);
    EXPECT_LT(relative_error(jacobian.transpose() * r, gradient), 1e-9) << c.name;
  }
}

// The joint angles' sensitivities from the same implicit differentiation.
TEST(Cycle, AngleJacobianAgreesWithCentralDifferences) {
  for (const GradientCase& c : gradient_cases()) {
    SolvedCycle s(c, 8);
    ASSERT_EQ(s.summary.failed_samples + s.summary.branch_jumps, 0) << c.name;
    const int n = c.g.joints();
    Eigen::MatrixXd angles;
    cycle_deformation_jacobian(s.model, s.ws, s.summary, &angles);
    ASSERT_EQ(angles.rows(), 8 * n);
    ASSERT_EQ(angles.cols(), 3 * n);
    Eigen::MatrixXd fd(angles.rows(), angles.cols());
    for (int j = 0; j < angles.cols(); ++j) {
      const double h = 1e-5;
      auto stacked = [&](double step) {
        LoopGeometry g = c.g;
        parameter(g, j) += step;
        const CycleSummary moved = run_cycle(g, s.summary.samples[0].state.theta, s.eo, s.co);
        Eigen::VectorXd theta(8 * n);
        for (int k = 0; k < 8; ++k) theta.segment(k * n, n) = moved.samples[static_cast<size_t>(k)].state.theta;
        return theta;
      };
      const Eigen::VectorXd plus = stacked(h), minus = stacked(-h);
      for (int row = 0; row < fd.rows(); ++row) fd(row, j) = wrap_angle(plus[row] - minus[row]) / (2 * h);
    }
    EXPECT_LT(relative_error(angles, fd), 1e-6) << c.name;
    EXPECT_GT(fd.cwiseAbs().maxCoeff(), 1e-3) << c.name;  // the angles do move with the geometry
  }
}

TEST(Cycle, BennettLoopHasZeroCycleEnergy) {
  const CycleSummary s = run_cycle(paper_bennett_loop(), paper_start());
  ASSERT_EQ(s.samples.size(), 32u);
  EXPECT_EQ(s.failed_samples, 0);
  EXPECT_EQ(s.branch_jumps, 0);
  EXPECT_LE(s.E_max, 1e-20);
  EXPECT_LE(s.max_closure_residual, 1e-13);
  // Full turn: theta0 + 2 pi j / N.
  for (size_t j = 0; j < s.samples.size(); ++j) {
    EXPECT_NEAR(s.samples[j].theta_in, rad(120) + 2 * kPi * static_cast<double>(j) / 32, 1e-14);
  }
}

TEST(Cycle, GenericLoopsHaveEnergyWellAboveZero) {
  for (std::uint64_t seed = 1; seed <= 5; ++seed) {
    const LoopGeometry g = random_loop(4, seed);
    const LoopModel model(g);
    EquilibriumWorkspace ws(model);
    const EquilibriumSummary start = assemble(model, ws, 0.0);
    ASSERT_EQ(start.status, SolveStatus::converged) << seed;
    CycleSummary s;
    cycle_energy(model, ws, 0.0, start.state, {}, s);
    EXPECT_GT(s.E_mean, 1e-3) << seed;
    EXPECT_GE(s.E_max, s.E_mean) << seed;
  }
}

// The energy belongs to the physical loop, not to how it is written down.
TEST(Cycle, EnergyIsInvariantUnderRelabellingReversalAndScaling) {
  struct Case {
    LoopGeometry g;
    JointVector start;
  };
  std::vector<Case> cases;
  cases.push_back({long_link_loop(), paper_start()});
  LoopGeometry offset = long_link_loop();
  offset.d << 0.3, -0.2, 0.1, 0.4;
  cases.push_back({offset, paper_start()});
  cases.push_back({random_loop(5, 2), random_angles(5, 2)});
  cases.push_back({random_loop(5, 10), random_angles(5, 10)});
  for (const Case& c : cases) {
    const int n = c.g.joints();
    EquilibriumOptions eo;
    eo.compliance = Compliance::full;
    const CycleSummary base = run_cycle(c.g, c.start, eo);
    // The premise: a smooth elastic path that closes after one turn (steps may
    // be refined where it bends). Where the path jumps branch, the cycle
    // depends on the driving direction (which reversal flips) and on
    // round-off (see cycle.hpp).
    ASSERT_EQ(base.failed_samples + base.branch_jumps, 0);
    const JointVector solved = base.samples[0].state.theta;
    ASSERT_GT(base.E_mean, 1e-6);
    const double tol = 1e-10 * base.E_mean;

    for (int shift = 1; shift < n; ++shift) {
      EquilibriumOptions shifted = eo;
      shifted.input_joint = (n - shift) % n;  // old joint 0 is new joint n - shift
      const CycleSummary s = run_cycle(relabelled(c.g, shift), relabelled_angles(solved, shift), shifted);
      EXPECT_NEAR(s.E_mean, base.E_mean, tol) << "shift " << shift;
      EXPECT_NEAR(s.E_max, base.E_max, tol) << "shift " << shift;
    }
    {
      EquilibriumOptions rev = eo;
      rev.input_joint = n - 1;  // old joint 0 is new joint n - 1, theta' = -theta
      const CycleSummary s = run_cycle(reversed(c.g), reversed_angles(solved), rev);
      EXPECT_NEAR(s.E_mean, base.E_mean, tol) << "reversed";
      EXPECT_NEAR(s.E_max, base.E_max, tol) << "reversed";
    }
    for (double factor : {0.01, 3.0, 1000.0}) {
      LoopGeometry g = c.g;
      g.a *= factor;
      g.d *= factor;
      const CycleSummary s = run_cycle(g, solved, eo);
      EXPECT_NEAR(s.E_mean, base.E_mean, tol) << "scale " << factor;
      EXPECT_NEAR(s.E_max, base.E_max, tol) << "scale " << factor;
    }
  }
}

// A partial range is sampled evenly around theta0, and every sample's energy
// is the exact equilibrium (checked with the independent reference solver).
TEST(Cycle, PartialRangeSamplesAroundTheta0AndAgreesWithReferenceSolver) {
  const LoopGeometry g = long_link_loop();
  CycleOptions co;
  co.samples = 7;
  co.range = rad(60);
  const CycleSummary s = run_cycle(g, paper_start(), {}, co);
  ASSERT_EQ(s.samples.size(), 7u);
  EXPECT_EQ(s.failed_samples, 0);
  const LoopModel model(g);
  for (int j = 0; j < 7; ++j) {
    const CycleSample& sample = s.samples[static_cast<size_t>(j)];
    EXPECT_NEAR(sample.theta_in, rad(90 + 10 * j), 1e-14);
    const auto ref = testing::reference_equilibrium(model, sample.theta_in, sample.state.theta);
    ASSERT_TRUE(ref.converged);
    EXPECT_NEAR(sample.energy, ref.energy, 1e-7 * ref.energy) << j;
  }
  double mean = 0.0, max = 0.0;
  for (const CycleSample& sample : s.samples) {
    mean += sample.energy / 7;
    max = std::max(max, sample.energy);
  }
  EXPECT_DOUBLE_EQ(s.E_mean, mean);
  EXPECT_DOUBLE_EQ(s.E_max, max);
}

// The input angles a coarse and a fine cycle share get the same energies:
// the continuation stays on one branch and does not drift with the step.
TEST(Cycle, ResultDoesNotDependOnTheSampleCountAtSharedAngles) {
  CycleOptions coarse, fine;
  coarse.samples = 16;
  fine.samples = 64;
  const CycleSummary a = run_cycle(long_link_loop(), paper_start(), {}, coarse);
  const CycleSummary b = run_cycle(long_link_loop(), paper_start(), {}, fine);
  for (int j = 0; j < 16; ++j) {
    EXPECT_NEAR(a.samples[static_cast<size_t>(j)].energy, b.samples[static_cast<size_t>(4 * j)].energy, 1e-9 * b.E_max)
        << j;
  }
}

// The predictor (tangent, cubic Hermite) and its bend control only
// change where each solve starts: on smooth cycles every sample must land on
// the same solution as without them.
TEST(Cycle, PredictorChangesOnlyTheStartingPoints) {
  struct Case {
    LoopGeometry geometry;
    JointVector start;
  };
  const LoopGeometry generic = random_loop(4, 6);
  const LoopModel generic_model(generic);
  EquilibriumWorkspace generic_ws(generic_model);
  const Case cases[] = {{paper_bennett_loop(), paper_start()},
                        {long_link_loop(), paper_start()},
                        {generic, assemble(generic_model, generic_ws, 0.0).state.theta}};
  for (const Case& c : cases) {
    CycleOptions with, without;
    without.predictor = false;
    const CycleSummary a = run_cycle(c.geometry, c.start, {}, with);
    const CycleSummary b = run_cycle(c.geometry, c.start, {}, without);
    ASSERT_EQ(a.branch_jumps + a.failed_samples, 0);
    ASSERT_EQ(b.branch_jumps + b.failed_samples, 0);
    for (size_t j = 0; j < a.samples.size(); ++j) {
      EXPECT_NEAR(a.samples[j].energy, b.samples[j].energy, 1e-12 * std::max(1.0, b.samples[j].energy)) << j;
      for (int i = 0; i < 4; ++i) {
        EXPECT_NEAR(wrap_angle(a.samples[j].state.theta[i] - b.samples[j].state.theta[i]), 0.0, 1e-9) << j;
      }
    }
  }
}

// A cycle abandoned above a ceiling: against the whole cycle of the same
// geometry, walked without one, its energies are lower bounds that already
// exceed the ceiling; a ceiling above the cycle changes nothing. From a
// nearby cycle, nearby's most costly sample is solved first, so a ceiling on
// E_max below it gives up after that one sample, with its energy.
TEST(Cycle, ACycleAboveItsCeilingIsAbandonedWithLowerBounds) {
  CycleOptions options;
  options.samples = 8;
  const LoopGeometry g = long_link_loop();
  const CycleSummary whole = run_cycle(g, paper_start(), {}, options);
  ASSERT_EQ(whole.failed_samples + whole.branch_jumps, 0);
  ASSERT_FALSE(whole.abandoned);
  const LoopModel model(g);
  EquilibriumWorkspace ws(model);
  const EquilibriumSummary assembled = assemble_from_angles(model, ws, paper_start());
  ASSERT_EQ(assembled.status, SolveStatus::converged);
  const double theta0 = paper_start()[0];

  CycleSummary walked;
  cycle_energy(model, ws, theta0, assembled.state, options, walked, {.mean = 1.01 * whole.E_mean});
  EXPECT_FALSE(walked.abandoned);
  EXPECT_EQ(walked.E_mean, whole.E_mean);
  EXPECT_EQ(walked.E_max, whole.E_max);
  for (const double fraction : {0.1, 0.5, 0.9}) {
    const CycleCeiling ceiling{.mean = fraction * whole.E_mean};
    cycle_energy(model, ws, theta0, assembled.state, options, walked, ceiling);
    EXPECT_TRUE(walked.abandoned) << fraction;
    EXPECT_GT(walked.E_mean, ceiling.mean) << fraction;
    EXPECT_LE(walked.E_mean, whole.E_mean * (1 + 1e-12)) << fraction;
    EXPECT_LE(walked.E_max, whole.E_max * (1 + 1e-12)) << fraction;
    // Given up before its last sample, unless that one tells.
    EXPECT_LE(walked.total_iterations, whole.total_iterations) << fraction;
    if (fraction <= 0.5) EXPECT_LT(walked.total_iterations, whole.total_iterations) << fraction;
  }
  cycle_energy(model, ws, theta0, assembled.state, options, walked, {.max = 0.5 * whole.E_max});
  EXPECT_TRUE(walked.abandoned);
  EXPECT_GT(walked.E_max, 0.5 * whole.E_max);

  // From the whole cycle itself as the nearby one: each sample converges
  // where it is, so the bounds are the samples' own energies.
  const auto costliest =
      std::max_element(whole.samples.begin(), whole.samples.end(),
                       [](const CycleSample& a, const CycleSample& b) { return a.energy < b.energy; });
  CycleSummary reused;
  ASSERT_TRUE(cycle_energy_from_nearby(model, ws, whole, options, reused, {.max = 0.99 * costliest->energy}));
  EXPECT_TRUE(reused.abandoned);
  EXPECT_NEAR(reused.E_max, costliest->energy, 1e-9 * costliest->energy);
  EXPECT_NEAR(reused.E_mean, costliest->energy / options.samples, 1e-9 * costliest->energy);
  ASSERT_TRUE(cycle_energy_from_nearby(model, ws, whole, options, reused, {.mean = 0.5 * whole.E_mean}));
  EXPECT_TRUE(reused.abandoned);
  EXPECT_GT(reused.E_mean, 0.5 * whole.E_mean);
  EXPECT_LE(reused.E_mean, whole.E_mean * (1 + 1e-9));
  // Above the cycle: all of it, in input order, as without a ceiling.
  CycleSummary unbounded;
  ASSERT_TRUE(cycle_energy_from_nearby(model, ws, whole, options, unbounded));
  ASSERT_TRUE(cycle_energy_from_nearby(model, ws, whole, options, reused, {.mean = 2 * whole.E_mean}));
  EXPECT_FALSE(reused.abandoned);
  EXPECT_EQ(reused.E_mean, unbounded.E_mean);
  for (size_t j = 0; j < whole.samples.size(); ++j) {
    EXPECT_EQ(reused.samples[j].theta_in, unbounded.samples[j].theta_in) << j;
    EXPECT_EQ(reused.samples[j].energy, unbounded.samples[j].energy) << j;
  }
  // A summary abandoned before is whole again when walked without a ceiling.
  ASSERT_TRUE(walked.abandoned);
  cycle_energy(model, ws, theta0, assembled.state, options, walked);
  EXPECT_FALSE(walked.abandoned);
  EXPECT_EQ(walked.E_mean, whole.E_mean);
}

// A failed sample abandons a cycle whose ceiling asks for it, at that
// sample: the kite 2,1,1,2 rocks over [120, 240] deg only, and from its
// stretched pose at 0 deg every sample of the turn fails (each after the
// walk's bisections) and reads near zero (docs/quality/stability.md, S4).
// Walked with the flag, the cycle stops at the first one, for a fraction of
// the iterations; a cycle without failed samples is not touched by it.
TEST(Cycle, AFailedSampleAbandonsACycleWhoseCeilingRejectsThem) {
  const LoopGeometry kite = planar_four_bar(2, 1, 1, 2);
  const LoopModel model(kite);
  EquilibriumWorkspace ws(model);
  CycleOptions options;
  options.samples = 8;
  JointVector stretched(4);
  stretched << 0.0, 0.0, kPi, 0.0;
  const EquilibriumState from = EquilibriumState::at_angles(model, stretched);
  CycleSummary whole, given_up;
  cycle_energy(model, ws, 0.0, from, options, whole);
  ASSERT_EQ(whole.failed_samples, 8);
  ASSERT_FALSE(whole.abandoned);
  cycle_energy(model, ws, 0.0, from, options, given_up, {.failed_sample = true});
  EXPECT_TRUE(given_up.abandoned);
  EXPECT_LT(3 * given_up.total_iterations, whole.total_iterations);

  // A window of 60 deg around 180 deg, inside the range, fails nowhere: the
  // flag changes nothing there.
  options.range = rad(60);
  const EquilibriumSummary inside = assemble(model, ws, kPi);
  ASSERT_EQ(inside.status, SolveStatus::converged);
  CycleSummary free_walk, flagged;
  cycle_energy(model, ws, kPi, inside.state, options, free_walk);
  ASSERT_EQ(free_walk.failed_samples, 0);
  cycle_energy(model, ws, kPi, inside.state, options, flagged, {.failed_sample = true});
  EXPECT_FALSE(flagged.abandoned);
  EXPECT_EQ(flagged.E_mean, free_walk.E_mean);
}

// cycle_energy_from_nearby against the walk: the long-link loop's cycle
// re-solved at a1 a little further gives every sample's energy and angles of
// the walk at that geometry (to the solve's tolerance); a nearby cycle with a
// branch jump, or a step that moves the angles too far, is refused. With few
// samples it costs a fraction of the walk's iterations; with many, where
// the walk's cubic predictor needs about two a sample, it costs about as
// much (96 against 69 at N = 32).
TEST(Cycle, CycleFromANearbyGeometryAgreesWithTheWalk) {
  for (int N : {4, 32}) {
    CycleOptions options;
    options.samples = N;
    const CycleSummary nearby = run_cycle(long_link_loop(), paper_start(), {}, options);
    ASSERT_EQ(nearby.branch_jumps + nearby.failed_samples, 0);
    LoopGeometry g = long_link_loop();
    g.a[0] += 0.01;
    g.alpha[1] -= rad(0.5);
    const CycleSummary walked = run_cycle(g, paper_start(), {}, options);
    ASSERT_EQ(walked.branch_jumps + walked.failed_samples, 0);
    const LoopModel model(g);
    EquilibriumWorkspace ws(model);
    CycleSummary reused;
    ASSERT_TRUE(cycle_energy_from_nearby(model, ws, nearby, options, reused)) << N;
    ASSERT_EQ(reused.samples.size(), walked.samples.size());
    for (size_t j = 0; j < walked.samples.size(); ++j) {
      EXPECT_EQ(reused.samples[j].theta_in, walked.samples[j].theta_in);
      EXPECT_NEAR(reused.samples[j].energy, walked.samples[j].energy, 1e-9 * walked.samples[j].energy) << j;
      for (int i = 0; i < 4; ++i) {
        EXPECT_NEAR(wrap_angle(reused.samples[j].state.theta[i] - walked.samples[j].state.theta[i]), 0.0, 1e-9) << j;
      }
    }
    EXPECT_NEAR(reused.E_mean, walked.E_mean, 1e-9 * walked.E_mean);
    EXPECT_EQ(
        reused.E_max,
        std::max_element(reused.samples.begin(), reused.samples.end(), [](const CycleSample& a, const CycleSample& b) {
          return a.energy < b.energy;
        })->energy);
    EXPECT_LE(reused.total_iterations, 4 * N);
    if (N == 4) {
      EXPECT_LT(reused.total_iterations, walked.total_iterations / 3)
          << reused.total_iterations << " vs " << walked.total_iterations;
    }

    // Far away (a1 from 2.03 to 3.5, alpha2 from 90 to 40 deg): refused,
    // whatever it would converge to.
    LoopGeometry far = long_link_loop();
    far.a[0] = 3.5;
    far.alpha[1] = rad(40);
    const LoopModel far_model(far);
    EquilibriumWorkspace far_ws(far_model);
    EXPECT_FALSE(cycle_energy_from_nearby(far_model, far_ws, nearby, options, reused)) << N;
    // A sample the nearby walk reached by a jump stays flagged; one whose
    // solve failed is no guide.
    CycleSummary jumped = nearby;
    jumped.samples[1].status = SampleStatus::branch_jump;
    jumped.branch_jumps = 1;
    ASSERT_TRUE(cycle_energy_from_nearby(model, ws, jumped, options, reused));
    EXPECT_EQ(reused.samples[1].status, SampleStatus::branch_jump);
    EXPECT_EQ(reused.branch_jumps, 1);
    CycleSummary failed = nearby;
    failed.samples[1].status = SampleStatus::failed;
    failed.failed_samples = 1;
    EXPECT_FALSE(cycle_energy_from_nearby(model, ws, failed, options, reused));
    // Nor one of another model layout (the offsets springy too).
    EquilibriumOptions full;
    full.compliance = Compliance::full;
    const LoopModel full_model(g, full);
    EquilibriumWorkspace full_ws(full_model);
    EXPECT_FALSE(cycle_energy_from_nearby(full_model, full_ws, nearby, options, reused));
    // Nor one of another sample count.
    CycleOptions other = options;
    other.samples = N + 1;
    EXPECT_FALSE(cycle_energy_from_nearby(model, ws, nearby, other, reused));
  }
}

TEST(Cycle, RepeatedCycleWithTheSameSampleCountDoesNotAllocate) {
  if (!testing::kCountsAllocations) GTEST_SKIP() << "allocations are not counted under AddressSanitizer";
  const LoopGeometry g = long_link_loop();
  const LoopModel model(g);
  EquilibriumWorkspace ws(model);
  const EquilibriumState start = assemble_from_angles(model, ws, paper_start()).state;
  CycleSummary s;
  cycle_energy(model, ws, rad(120), start, {}, s);
  const long before = testing::allocations();
  cycle_energy(model, ws, rad(120), start, {}, s);
  EXPECT_EQ(testing::allocations() - before, 0);
  EXPECT_EQ(s.failed_samples, 0);
}

// The Gauss-Newton hot path: every accepted step differentiates its cycle.
TEST(Cycle, RepeatedDeformationJacobianIntoTheSameOutputDoesNotAllocate) {
  if (!testing::kCountsAllocations) GTEST_SKIP() << "allocations are not counted under AddressSanitizer";
  for (const GradientCase& c : gradient_cases()) {
    SolvedCycle s(c, 32);
    Eigen::MatrixXd jacobian, angles;
    cycle_deformation_jacobian(s.model, s.ws, s.summary, jacobian, &angles);
    const Eigen::MatrixXd first = jacobian, first_angles = angles;
    const long before = testing::allocations();
    cycle_deformation_jacobian(s.model, s.ws, s.summary, jacobian, &angles);
    cycle_deformation_jacobian(s.model, s.ws, s.summary, jacobian);
    EXPECT_EQ(testing::allocations() - before, 0) << c.name;
    // The same answer, bit for bit, as the first call and the allocating form.
    EXPECT_TRUE(jacobian == first) << c.name;
    EXPECT_TRUE(angles == first_angles) << c.name;
    EXPECT_TRUE(cycle_deformation_jacobian(s.model, s.ws, s.summary) == first) << c.name;
  }
}

TEST(Cycle, InvalidOptionsAreRejectedByName) {
  auto message = [](const CycleOptions& o) -> std::string {
    try {
      o.validate();
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "";
  };
  CycleOptions o;
  EXPECT_EQ(message(o), "");
  o.samples = 1;
  EXPECT_NE(message(o).find("samples"), std::string::npos);
  o = {};
  o.range = 0.0;
  EXPECT_NE(message(o).find("range"), std::string::npos);
  o.range = 7.0;
  EXPECT_NE(message(o).find("range"), std::string::npos);
  o = {};
  o.max_passive_step = std::nan("");
  EXPECT_NE(message(o).find("max_passive_step"), std::string::npos);
  o = {};
  o.max_refinements = -1;
  EXPECT_NE(message(o).find("max_refinements"), std::string::npos);
  o = {};
  o.max_iterations_per_step = 0;
  EXPECT_NE(message(o).find("max_iterations_per_step"), std::string::npos);
  o = {};
  o.stepping_tolerance = -1e-6;
  EXPECT_NE(message(o).find("stepping_tolerance"), std::string::npos);
  o.stepping_tolerance = std::numeric_limits<double>::infinity();
  EXPECT_NE(message(o).find("stepping_tolerance"), std::string::npos);
}

// Where the elastic path folds, the walk lands on another branch. The bench's
// 8 generic loops at N = 32 have 9 such landings; before the landing started
// along the path tangent (Stepper::land) two of them failed after 100
// Newton iterations each and the whole set took 2,305 iterations. Now every
// sample converges; a landed sample is checked by a second method: a strict
// local minimum (equilibrium_tangent factors its reduced Hessian) that a
// cold solve from its own state confirms without a step.
TEST(Cycle, LandingsAfterFoldsConvergeToStrictLocalMinima) {
  int jumps = 0, iterations = 0;
  for (std::uint64_t seed = 1; seed <= 8; ++seed) {
    const LoopModel model(random_loop(4, seed));
    EquilibriumWorkspace ws(model);
    const EquilibriumState start = assemble(model, ws, 0.0).state;
    CycleSummary s;
    cycle_energy(model, ws, 0.0, start, CycleOptions{}, s);
    EXPECT_EQ(s.failed_samples, 0) << seed;
    iterations += s.total_iterations;
    for (const CycleSample& sample : s.samples) {
      if (sample.status != SampleStatus::branch_jump) continue;
      ++jumps;
      EXPECT_EQ(sample.solve_status, SolveStatus::converged) << seed;
      EquilibriumState tangent;
      EXPECT_TRUE(equilibrium_tangent(model, ws, sample.state, tangent)) << seed << " at " << sample.theta_in;
      const EquilibriumSummary again = solve_equilibrium(model, ws, sample.theta_in, sample.state);
      EXPECT_EQ(again.status, SolveStatus::converged) << seed;
      EXPECT_LE(again.iterations, 1) << seed;
      EXPECT_NEAR(again.energy, sample.energy, 1e-12 * std::max(1.0, sample.energy)) << seed;
    }
  }
  EXPECT_GE(jumps, 5);
  // A deterministic count, not a timing: 1,498 Newton iterations in all,
  // measured at commit 3903a98; the bound, 3 % above it, catches a change
  // that costs the walk iterations.
  EXPECT_LE(iterations, 1545) << "iterations " << iterations;
}

// Two cycles of the same 4R loop agree sample by sample: the same statuses,
// energies to 1e-10 and angles to 1e-8 (the solve's tolerance).
void expect_same_samples(const CycleSummary& a, const CycleSummary& b, std::uint64_t seed) {
  ASSERT_EQ(a.samples.size(), b.samples.size());
  for (size_t j = 0; j < a.samples.size(); ++j) {
    EXPECT_EQ(a.samples[j].status, b.samples[j].status) << seed << " sample " << j;
    EXPECT_NEAR(a.samples[j].energy, b.samples[j].energy, 1e-10 * std::max(1.0, b.samples[j].energy)) << seed;
    for (int i = 0; i < 4; ++i) {
      EXPECT_NEAR(wrap_angle(a.samples[j].state.theta[i] - b.samples[j].state.theta[i]), 0.0, 1e-8) << seed;
    }
  }
}

// The bench's 8 generic loops, each walked from the same assembly with
// options `a` and `b`; `check(model, cycle_a, cycle_b, seed)` sees each pair.
struct PairTotals {
  int iterations_a = 0, iterations_b = 0, jumps_b = 0, refinements_b = 0;
};
template <class Check>
PairTotals compare_generic_cycles(const CycleOptions& a, const CycleOptions& b, Check check) {
  PairTotals totals;
  for (std::uint64_t seed = 1; seed <= 8; ++seed) {
    const LoopModel model(random_loop(4, seed));
    EquilibriumWorkspace ws(model);
    const EquilibriumState start = assemble(model, ws, 0.0).state;
    CycleSummary ca, cb;
    cycle_energy(model, ws, 0.0, start, a, ca);
    cycle_energy(model, ws, 0.0, start, b, cb);
    totals.iterations_a += ca.total_iterations;
    totals.iterations_b += cb.total_iterations;
    totals.jumps_b += cb.branch_jumps;
    totals.refinements_b += cb.refinements;
    check(model, ca, cb, seed);
  }
  return totals;
}

// CycleOptions::skip_failed_retries against retrying: on the bench's 8
// generic loops, whose cycles pass 9 folds at N = 32, skipping the solves
// already known to fail changes no sample (the same statuses, energies and
// angles to the solve's tolerance) and saves iterations (1,498 against 1,596
// in all, measured at commit 3903a98). Not on every loop: a skipped retry
// can be one that would have been accepted, and the step bisects instead.
TEST(Cycle, SkippingKnownFailedRetriesChangesNoSample) {
  CycleOptions skip, retry;
  retry.skip_failed_retries = false;
  const PairTotals totals = compare_generic_cycles(
      skip, retry, [](const LoopModel&, const CycleSummary& a, const CycleSummary& b, std::uint64_t seed) {
        expect_same_samples(a, b, seed);
      });
  EXPECT_GE(totals.jumps_b, 5);  // the comparison passes folds
  EXPECT_LT(totals.iterations_a, totals.iterations_b);
}

// CycleOptions::stepping_tolerance against solving the bisections' midpoints
// to full tolerance: on the bench's 8 generic loops (23 bisections a cycle at
// N = 32, 9 folds) no sample changes (the same statuses, energies and angles
// to the solve's tolerance, every sample at the model's tolerances) and the
// walk needs fewer iterations (cycle_breakdown: 1,498 against 1,728).
TEST(Cycle, LooseMidpointsChangeNoSample) {
  CycleOptions loose, exact;
  exact.stepping_tolerance = 0.0;
  const PairTotals totals = compare_generic_cycles(
      loose, exact, [](const LoopModel& model, const CycleSummary& a, const CycleSummary& b, std::uint64_t seed) {
        expect_same_samples(a, b, seed);
        for (const CycleSample& sample : a.samples) {
          EXPECT_EQ(sample.solve_status, SolveStatus::converged) << seed << " at " << sample.theta_in;
          EXPECT_LE(sample.closure_residual, model.options().closure_tolerance) << seed << " at " << sample.theta_in;
        }
      });
  EXPECT_GE(totals.jumps_b, 5);          // the comparison passes folds
  EXPECT_GE(totals.refinements_b, 100);  // and has midpoints to loosen
  EXPECT_LT(totals.iterations_a, totals.iterations_b);
}

// A known limit, pinned so that docs/quality/stability.md's statement stays true until
// it is fixed (then this test fails and docs/quality/stability.md, "Known limits of the
// cycle near folds of the elastic path", must change with it):
// near a fold of the elastic path the continuation can pass to another branch
// without flagging a jump, so the cycle energy of this generic loop depends on
// the per-step iteration budget.
TEST(CycleKnownLimit, GenericLoopPathDependsOnTheStepBudgetNearAFold) {
  const LoopModel model(random_loop(4, 3));
  EquilibriumWorkspace ws(model);
  const EquilibriumState start = assemble(model, ws, 0.0).state;
  CycleOptions generous, tight;
  generous.max_iterations_per_step = 20;
  tight.max_iterations_per_step = 10;
  CycleSummary a, b;
  cycle_energy(model, ws, 0.0, start, generous, a);
  cycle_energy(model, ws, 0.0, start, tight, b);
  EXPECT_EQ(a.branch_jumps + a.failed_samples, 0);
  EXPECT_EQ(b.branch_jumps + b.failed_samples, 0);
  EXPECT_NEAR(a.E_mean, 1.011, 0.001);
  EXPECT_NEAR(b.E_mean, 2.331, 0.001);
}

}  // namespace
}  // namespace loopfarm
