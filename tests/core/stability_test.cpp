// The stability suite (docs/quality/stability.md): where the methods fail.
//
// Every case runs every method that applies to it -- the equilibrium solve
// (the assembly at theta0, and a direct solve where the case is one pose),
// the cycle, the rigid verification, the classification, and a short local
// minimisation with Gauss-Newton and with NLopt's LD_LBFGS -- and asserts
// what must hold everywhere:
//
//   - no NaN or infinity in any result field (the one documented sentinel: a
//     local search that could not evaluate its start reports value = +inf);
//   - a numerical failure is a status, never an exception;
//   - every count is bounded by its options (no hang): Newton iterations per
//     solve and per cycle, poses of the verification walk, evaluations of a
//     local search;
//
// and then the case's own truth: a movable loop reads zero energy and
// verifies, a rigid one reads clearly non-zero, the energy does not change
// with the scale. Where the code gives a wrong or surprising answer today
// (a false zero, a missed zero, an unflagged branch change, a failed status),
// the behaviour is pinned in a StabilityKnownLimit test, so that a fix makes
// it fail and docs/quality/stability.md (the table of all of this, with the commands)
// changes with it.
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <span>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "loopfarm/core/assembly.hpp"
#include "loopfarm/core/cycle.hpp"
#include "loopfarm/core/sample_loops.hpp"
#include "loopfarm/search/classify.hpp"
#include "loopfarm/search/local_search.hpp"
#include "loopfarm/search/objective.hpp"
#include "loopfarm/search/verify.hpp"
#include "test_support.hpp"

namespace loopfarm {
namespace {

using testing::rad;

constexpr double kPi = 3.14159265358979323846;
// Movable loops read energies at round-off, 1e-27 ... 1e-57 here; the
// default job's zero threshold is 1e-20 (jobs/default.toml): a movable loop
// must be below it with room to spare, and a rigid loop far above it.
constexpr double kZero = 1e-20;
// The built-in zero threshold of a job that does not set one (SearchSection).
constexpr double kBuiltInZeroThreshold = 1e-12;

// ---------------------------------------------------------------------------
// What must hold everywhere.

// The most Newton iterations one cycle may spend under its options: per
// sample a bisection tree of depth max_refinements whose inner nodes try one
// budgeted solve each and whose leaves try a budgeted and a full solve
// (src/core/cycle.cpp, Stepper::step), plus the anchor's full solve. More would
// be a loop that does not stop as designed.
long cycle_iteration_bound(const CycleOptions& co, const EquilibriumOptions& eo) {
  const long leaves = 1L << co.max_refinements;
  const long per_sample = (2 * leaves - 1) * co.max_iterations_per_step + leaves * eo.max_iterations;
  return co.samples * per_sample + eo.max_iterations;
}

bool finite_state(const EquilibriumState& s) {
  return s.theta.allFinite() && s.deformations.allFinite() && s.multipliers.allFinite();
}

void expect_sane(const EquilibriumSummary& s, int max_iterations, const std::string& what) {
  EXPECT_NE(s.status, SolveStatus::non_finite) << what;
  EXPECT_TRUE(std::isfinite(s.energy)) << what;
  EXPECT_GE(s.energy, 0.0) << what;
  EXPECT_TRUE(std::isfinite(s.closure_residual)) << what;
  EXPECT_TRUE(std::isfinite(s.stationarity)) << what;
  EXPECT_TRUE(std::isfinite(s.max_regularization)) << what;
  EXPECT_TRUE(finite_state(s.state)) << what;
  EXPECT_GE(s.iterations, 0) << what;
  EXPECT_LE(s.iterations, max_iterations) << what;
}

void expect_sane(const CycleSummary& s, const CycleOptions& co, const EquilibriumOptions& eo, const std::string& what) {
  ASSERT_EQ(s.samples.size(), static_cast<size_t>(co.samples)) << what;
  EXPECT_TRUE(std::isfinite(s.E_mean)) << what;
  EXPECT_TRUE(std::isfinite(s.E_max)) << what;
  EXPECT_GE(s.E_mean, 0.0) << what;
  EXPECT_GE(s.E_max, s.E_mean * (1.0 - 1e-12)) << what;
  EXPECT_TRUE(std::isfinite(s.max_closure_residual)) << what;
  EXPECT_GE(s.total_iterations, 0) << what;
  EXPECT_LE(s.total_iterations, cycle_iteration_bound(co, eo)) << what;
  int failed = 0, jumps = 0;
  for (const CycleSample& sample : s.samples) {
    EXPECT_TRUE(std::isfinite(sample.energy)) << what << " at " << sample.theta_in;
    EXPECT_GE(sample.energy, 0.0) << what;
    EXPECT_TRUE(std::isfinite(sample.closure_residual)) << what;
    EXPECT_TRUE(finite_state(sample.state)) << what << " at " << sample.theta_in;
    EXPECT_NE(sample.solve_status, SolveStatus::non_finite) << what;
    EXPECT_LE(sample.refinements, (2 << co.max_refinements)) << what;
    failed += sample.status == SampleStatus::failed;
    jumps += sample.status == SampleStatus::branch_jump;
  }
  EXPECT_EQ(failed, s.failed_samples) << what;
  EXPECT_EQ(jumps, s.branch_jumps) << what;
}

void expect_sane(const VerificationSummary& v, const VerificationOptions& vo, const std::string& what) {
  EXPECT_TRUE(std::isfinite(v.worst_residual)) << what;
  // A circuit has at most the tracer's point budget.
  EXPECT_LE(v.poses, vo.motion().max_points) << what;
  EXPECT_EQ(v.input_angles.size(), static_cast<size_t>(v.poses)) << what;
  EXPECT_EQ(v.joint_angles.size(), static_cast<size_t>(v.poses)) << what;
  EXPECT_TRUE(std::isfinite(v.range_lo) && std::isfinite(v.range_hi)) << what;
  EXPECT_LE(v.range_lo, v.range_hi) << what;
  EXPECT_TRUE(v.joint_travel.allFinite()) << what;
  for (const JointVector& pose : v.joint_angles) EXPECT_TRUE(pose.allFinite()) << what;
  if (v.on_motion) {
    EXPECT_TRUE(v.assembled) << what;
  }
  if (v.verified) {
    EXPECT_GE(v.circuit, 0) << what;
    EXPECT_LE(v.worst_residual, vo.residual_tolerance) << what;
  }
}

void expect_sane(const Classification& c, const std::string& what) {
  EXPECT_TRUE(std::isfinite(c.residual)) << what;
  ASSERT_EQ(c.checks.size(), 4u) << what;
  for (const FamilyCheck& check : c.checks) {
    // inf is documented for a family that does not apply; NaN never.
    EXPECT_FALSE(std::isnan(check.residual)) << what << " " << to_string(check.family);
    for (const ConditionResidual& condition : check.conditions) {
      EXPECT_FALSE(std::isnan(condition.residual)) << what << " " << condition.name;
    }
  }
}

// ---------------------------------------------------------------------------
// Running the methods.

// One loop as a case: its geometry and start (given joint angles, or an
// automatic assembly at theta0 when `angles` is empty), with the options.
struct Case {
  std::string name;
  LoopGeometry geometry;
  JointVector angles;
  double theta0 = 0.0;
  EquilibriumOptions equilibrium = {};
  CycleOptions cycle = {};
};

struct Methods {
  EquilibriumSummary assembly;
  CycleSummary cycle;
  VerificationSummary verification;
  Classification classification;
};

// Assembly, cycle, rigid verification from the assembled pose and
// classification (with the verified joint travel, as analyse_candidate does),
// each checked for what must hold everywhere.
Methods run_methods(const Case& c) {
  Methods m;
  try {
    const LoopModel model(c.geometry, c.equilibrium);
    EquilibriumWorkspace ws(model);
    const bool given = c.angles.size() > 0;
    m.assembly = given ? assemble_from_angles(model, ws, c.angles) : assemble(model, ws, c.theta0);
    expect_sane(m.assembly, c.equilibrium.max_iterations, c.name + ": assembly");
    const double theta0 = given ? c.angles[0] : c.theta0;
    cycle_energy(model, ws, theta0, m.assembly.state, c.cycle, m.cycle);
    expect_sane(m.cycle, c.cycle, c.equilibrium, c.name + ": cycle");
    const VerificationOptions vo;
    m.verification = verify_motion(c.geometry, m.assembly.state.theta, vo);
    expect_sane(m.verification, vo, c.name + ": verification");
    const JointVector& travel = m.verification.joint_travel;
    const std::span<const double> travel_span =
        m.verification.verified ? std::span<const double>(travel.data(), static_cast<size_t>(travel.size()))
                                : std::span<const double>();
    m.classification = classify(c.geometry, m.assembly.state.theta, travel_span);
    expect_sane(m.classification, c.name + ": classification");
  } catch (const std::exception& e) {
    ADD_FAILURE() << c.name << ": a method threw: " << e.what();
  }
  return m;
}

// A direct equilibrium solve at theta_in from the given joint angles.
EquilibriumSummary solve_at(const LoopGeometry& g, double theta_in, const JointVector& angles,
                            const EquilibriumOptions& eo = {}) {
  const LoopModel model(g, eo);
  EquilibriumWorkspace ws(model);
  const EquilibriumSummary s = solve_equilibrium(model, ws, theta_in, EquilibriumState::at_angles(model, angles));
  expect_sane(s, eo.max_iterations, "direct solve");
  return s;
}

// A search space around a geometry: every a_i free within a relative band
// (fixed when rel_a = 0), every alpha_i free within +-span_alpha (fixed when
// 0), offsets fixed, initial joint angles fixed at `angles`.
ParameterSpace space_around(const LoopGeometry& g, const JointVector& angles, double rel_a, double span_alpha) {
  ParameterSpace s;
  s.joints = g.joints();
  s.specs.resize(static_cast<size_t>(kParameterKinds * g.joints()));
  for (int i = 0; i < g.joints(); ++i) {
    ParameterSpec& a = s.specs[static_cast<size_t>(s.index(ParameterKind::a, i))];
    a.value = g.a[i];
    if (rel_a > 0) {
      a.mode = ParameterSpec::Mode::range;
      a.lo = std::max(0.0, g.a[i] * (1 - rel_a));
      a.hi = g.a[i] * (1 + rel_a);
    }
    ParameterSpec& alpha = s.specs[static_cast<size_t>(s.index(ParameterKind::alpha, i))];
    alpha.value = g.alpha[i];
    if (span_alpha > 0) {
      alpha.mode = ParameterSpec::Mode::range;
      alpha.lo = g.alpha[i] - span_alpha;
      alpha.hi = g.alpha[i] + span_alpha;
    }
    s.specs[static_cast<size_t>(s.index(ParameterKind::d, i))].value = g.d[i];
    s.specs[static_cast<size_t>(s.index(ParameterKind::theta, i))].value = angles[i];
  }
  return s;
}

// Only a1 free in [lo, hi]; everything else fixed.
ParameterSpace a1_free(const LoopGeometry& g, const JointVector& angles, double lo, double hi) {
  ParameterSpace s = space_around(g, angles, 0.0, 0.0);
  ParameterSpec& a1 = s.specs[static_cast<size_t>(s.index(ParameterKind::a, 0))];
  a1.mode = ParameterSpec::Mode::range;
  a1.lo = lo;
  a1.hi = hi;
  return s;
}

constexpr int kMaxEvaluations = 60;  // per local search: short, and the hang bound

// A short local minimisation from the geometry `g0` (its free values) with
// 16 cycle samples, as the paper's Table 1 job; checked for what must hold.
// `final_cycle`, when given, receives the objective's cycle at the returned point.
LocalSearchSummary search(const ParameterSpace& space, const LoopGeometry& g0, const std::string& algorithm,
                          const EquilibriumOptions& eo = {}, CycleSummary* final_cycle = nullptr,
                          bool reuse_nearby_cycle = true) {
  const std::string what = "search " + algorithm;
  LocalSearchSummary s;
  try {
    ObjectiveOptions objective_options;
    objective_options.equilibrium = eo;
    objective_options.cycle.samples = 16;
    objective_options.reuse_nearby_cycle = reuse_nearby_cycle;
    CycleObjective objective(space, objective_options, space.initial_angles(Eigen::VectorXd()));
    LocalSearchOptions options;
    options.optimizer.algorithm = algorithm;
    options.optimizer.max_evaluations = kMaxEvaluations;
    // A guard against a hang only, far above any search's time: the
    // assertion below says the evaluation limit stops first. 20 s was too
    // little for LBFGS from the near-spherical loop in the sanitized build
    // (scripts/test.sh --sanitize) on a loaded machine.
    options.optimizer.time_limit = 300.0;
    s = local_minimize(objective, space.free_values(g0), options);
    if (final_cycle != nullptr) *final_cycle = objective.cycle();
  } catch (const std::exception& e) {
    ADD_FAILURE() << what << " threw: " << e.what();
    return s;
  }
  EXPECT_NE(s.status, SearchStatus::invalid_args) << what << " " << s.message;
  EXPECT_NE(s.status, SearchStatus::out_of_memory) << what;
  EXPECT_NE(s.status, SearchStatus::maxtime_reached) << what << ": the evaluation limit must come first";
  // At most max_evaluations, plus one re-evaluation that leaves the
  // objective at the returned point; NLopt's LBFGS may run one evaluation
  // past its maxeval (as local_search_test notes for its algorithms).
  EXPECT_GE(s.evaluations, 1) << what;
  EXPECT_LE(s.evaluations, kMaxEvaluations + (algorithm == "gauss-newton" ? 1 : 2)) << what;
  EXPECT_TRUE(s.x.allFinite()) << what;
  const Eigen::VectorXd lower = space.lower_bounds(), upper = space.upper_bounds();
  for (int i = 0; i < s.x.size(); ++i) {
    EXPECT_GE(s.x[i], lower[i]) << what;
    EXPECT_LE(s.x[i], upper[i]) << what;
  }
  if (s.status == SearchStatus::evaluation_failed) {
    EXPECT_EQ(s.value, std::numeric_limits<double>::infinity()) << what;  // the documented sentinel
    // No cycle was evaluated: no energy, rather than a 0 that reads as a zero.
    EXPECT_TRUE(std::isnan(s.E_mean)) << what;
    EXPECT_TRUE(std::isnan(s.E_max)) << what;
  } else {
    EXPECT_TRUE(std::isfinite(s.value)) << what;
    EXPECT_TRUE(std::isfinite(s.E_mean)) << what;
    EXPECT_TRUE(std::isfinite(s.E_max)) << what;
    EXPECT_GE(s.E_mean, 0.0) << what;
  }
  return s;
}

const char* const kAlgorithms[] = {"gauss-newton", "LD_LBFGS"};

// The paper's Bennett loop (a = 2, 4, 2, 4; alpha = 30, 90, 30, 90 deg), and
// the rigid loop with a1 lengthened to 2.03 (its Fig. 7 and 12).
LoopGeometry rigid_paper_loop() {
  LoopGeometry g = paper_bennett_loop();
  g.a[0] = 2.03;
  return g;
}
JointVector paper_pose() { return bennett_angles(paper_bennett_loop(), rad(120)); }

// Joint angles equal modulo 2 pi.
double angle_gap(double a, double b) { return std::abs(wrap_angle(a - b)); }

// ---------------------------------------------------------------------------
// Singular configurations on the cycle.

// The rigid paper loop (a1 = 2.03) is flat-folded at theta1 = 0 and 180 deg
// (every axis in one plane, the closure Jacobian loses rank). With N = 24
// from theta0 = 120 deg the cycle samples both folded poses exactly.
TEST(Stability, RigidPaperLoopThroughItsFoldedPosesReadsNonZeroOnOneBranch) {
  Case c{"rigid paper loop through folds", rigid_paper_loop(), paper_pose()};
  c.cycle.samples = 24;
  const Methods m = run_methods(c);
  EXPECT_EQ(m.assembly.status, SolveStatus::converged);
  EXPECT_EQ(m.cycle.failed_samples, 0);
  EXPECT_EQ(m.cycle.branch_jumps, 0);
  // Clearly non-zero: 1.9e-5, seven orders above the built-in zero threshold.
  EXPECT_GT(m.cycle.E_mean, 1e-6);

  // Samples 4 and 16 are the folded poses (120 + 15 j deg).
  const CycleSample& at180 = m.cycle.samples[4];
  const CycleSample& at360 = m.cycle.samples[16];
  ASSERT_NEAR(at180.theta_in, kPi, 1e-12);
  ASSERT_NEAR(at360.theta_in, 2 * kPi, 1e-12);
  for (double fold : {0.0, kPi}) {
    // A cold solve at the fold, from the Bennett loop's folded pose.
    const EquilibriumSummary cold = solve_at(c.geometry, fold, bennett_angles(paper_bennett_loop(), fold));
    ASSERT_EQ(cold.status, SolveStatus::converged) << fold;
    // The continuation lands on the same equilibrium (1e-9: well above the
    // solves' 1e-13 closure tolerance, far below the cusp's depth of 0.8e-5).
    const CycleSample& sample = fold == 0.0 ? at360 : at180;
    EXPECT_NEAR(sample.energy, cold.energy, 1e-9 * cold.energy) << fold;
  }
  // The cusp: the folded pose is lower than its neighbours on the cycle.
  EXPECT_LT(at180.energy, 0.7 * m.cycle.samples[3].energy);
  EXPECT_LT(at180.energy, 0.7 * m.cycle.samples[5].energy);

  // One branch whatever the start: the cycle started at the fold itself
  // (theta0 = 0, the same 24 input angles) reads the same energies.
  Case from_fold = c;
  from_fold.angles = bennett_angles(paper_bennett_loop(), 0.0);
  const Methods f = run_methods(from_fold);
  EXPECT_EQ(f.cycle.failed_samples + f.cycle.branch_jumps, 0);
  for (size_t j = 0; j < 24; ++j) {
    const size_t k = (j + 8) % 24;  // 120 + 15 j = 15 (j + 8) mod 360
    EXPECT_NEAR(m.cycle.samples[j].energy, f.cycle.samples[k].energy, 1e-9 * m.cycle.E_max) << j;
  }

  // Rigid: the rigid closure does not even close at the start pose, and
  // no family fits (the nearest is Bennett, 0.03 / L away in a1).
  EXPECT_FALSE(m.verification.assembled);
  EXPECT_GT(m.verification.worst_residual, 1e-3);
  EXPECT_EQ(m.classification.family, Family::unclassified);
  EXPECT_NEAR(m.classification.residual, 0.00947, 1e-4);
}

// Started at the fold (theta0 = 0, the folded pose as the initial angles),
// the local search still finds the Bennett loop a1 = 2.
TEST(Stability, SearchStartedAtAFoldedPoseReachesTheBennettLoop) {
  const ParameterSpace space = a1_free(rigid_paper_loop(), bennett_angles(paper_bennett_loop(), 0.0), 1.9, 2.1);
  const LocalSearchSummary gn = search(space, rigid_paper_loop(), "gauss-newton");
  EXPECT_EQ(gn.status, SearchStatus::stopval_reached) << gn.message;
  EXPECT_NEAR(gn.x[0], 2.0, 1e-9);  // E ~ (a1 - 2)^2 below 1e-26
  EXPECT_LE(gn.evaluations, 10);    // quadratic convergence: 4 seen
  const LocalSearchSummary lbfgs = search(space, rigid_paper_loop(), "LD_LBFGS");
  // LBFGS stops on xtol short of stopval, but at a zero of the built-in threshold.
  EXPECT_LE(lbfgs.E_mean, kBuiltInZeroThreshold) << to_string(lbfgs.status);
  EXPECT_NEAR(lbfgs.x[0], 2.0, 1e-4);
}

// A Bennett loop exactly at its folded pose: started there, the cycle stays
// on the closure curve (eq. 2a) and the rigid walk from there verifies.
TEST(Stability, BennettLoopAtItsFoldedPoseStaysOnItsClosureCurve) {
  const LoopGeometry p = paper_bennett_loop();
  for (double fold : {0.0, kPi}) {
    const Case c{"Bennett at fold " + std::to_string(fold), p, bennett_angles(p, fold)};
    const Methods m = run_methods(c);
    EXPECT_EQ(m.assembly.status, SolveStatus::converged) << c.name;
    EXPECT_LE(m.assembly.energy, kZero) << c.name;
    EXPECT_EQ(m.cycle.failed_samples + m.cycle.branch_jumps, 0) << c.name;
    EXPECT_LE(m.cycle.E_max, kZero) << c.name;
    for (const CycleSample& s : m.cycle.samples) {
      // theta3 = -theta1, theta4 = -theta2: the asymmetric Bennett motion (1e-8
      // rad: the closure tolerance 1e-13 moves the angles far less).
      EXPECT_LT(angle_gap(s.state.theta[2], -s.state.theta[0]), 1e-8) << c.name << " " << s.theta_in;
      EXPECT_LT(angle_gap(s.state.theta[3], -s.state.theta[1]), 1e-8) << c.name << " " << s.theta_in;
    }
    EXPECT_TRUE(m.verification.verified) << c.name;
    EXPECT_TRUE(m.verification.full_turn) << c.name;
    EXPECT_LE(m.verification.worst_residual, 1e-12) << c.name;
    EXPECT_EQ(m.classification.family, Family::bennett) << c.name;
    EXPECT_EQ(m.classification.setup, BennettSetup::asymmetric) << c.name;
  }
  // Driven through both folds from the paper's pose.
  Case through{"Bennett through folds", p, paper_pose()};
  through.cycle.samples = 24;
  const Methods m = run_methods(through);
  EXPECT_EQ(m.cycle.failed_samples + m.cycle.branch_jumps, 0);
  EXPECT_LE(m.cycle.E_max, kZero);
}

// Planar four-bars whose lengths satisfy Grashof's equality s + l = p + q
// pass through change points, where all links are collinear and two
// branches of the motion cross. Each is movable and must read zero.
TEST(Stability, PlanarFourBarsWithChangePointsReadZeroAndVerify) {
  struct Bar {
    const char* name;
    LoopGeometry geometry;
  };
  const Bar bars[] = {{"parallelogram 1,2,1,2", planar_four_bar(1, 2, 1, 2)},
                      {"kite 1,2,2,1", planar_four_bar(1, 2, 2, 1)},
                      {"Grashof equality 1,2,4,3", planar_four_bar(1, 2, 4, 3)},
                      {"Grashof equality 1,4,2,3", planar_four_bar(1, 4, 2, 3)},
                      {"rhombus 1,1,1,1", planar_four_bar(1, 1, 1, 1)}};
  for (const Bar& bar : bars) {
    for (double theta0 : {0.0, kPi / 2}) {
      Case c{std::string(bar.name) + " at " + std::to_string(theta0), bar.geometry, JointVector(), theta0};
      const Methods m = run_methods(c);
      EXPECT_EQ(m.assembly.status, SolveStatus::converged) << c.name;
      EXPECT_EQ(m.cycle.failed_samples + m.cycle.branch_jumps, 0) << c.name;
      EXPECT_LE(m.cycle.E_max, kZero) << c.name;
      EXPECT_TRUE(m.verification.verified) << c.name;
      EXPECT_TRUE(m.verification.full_turn) << c.name;
      // The rhombus assembles at 90 deg on its coaxial branch (axes 1 and 3
      // coincide, joints 2 and 4 frozen): also a motion, the trivial one.
      const Family expected =
          std::string(bar.name) == "rhombus 1,1,1,1" && theta0 > 0 ? Family::trivial : Family::planar;
      EXPECT_EQ(m.classification.family, expected) << c.name << ": " << m.classification.detail;
    }
  }
}

// At a change point two zero-energy branches cross, and which one the walk
// leaves on is not chosen: it depends on details of the walk (the bisections'
// midpoints solved to full tolerance or not, the round-off of the
// factorisations), and a change of branch is never flagged as a jump. Energy
// and verification are right (both branches move); the joint angles of the
// cycle may not be those of one branch. Pinned here: within each half-turn
// between the change points at 0 and 180 deg the samples keep to one branch,
// and at 180 deg the walk changes branch, unflagged, with at least one of two
// settings (with both since commit 8e8ed93; with exact
// midpoints only before its factorisation changes).
TEST(StabilityKnownLimit, ParallelogramCycleBranchAfterItsChangePointIsNotChosen) {
  Case exact{"parallelogram from 0, exact midpoints", planar_four_bar(1, 2, 1, 2), JointVector(), 0.0};
  exact.cycle.stepping_tolerance = 0.0;
  Case loose = exact;
  loose.name = "parallelogram from 0";
  loose.cycle = CycleOptions{};
  int changes = 0;
  for (const Case& c : {exact, loose}) {
    const Methods m = run_methods(c);
    ASSERT_EQ(m.cycle.samples.size(), 32u) << c.name;
    EXPECT_EQ(m.cycle.branch_jumps, 0) << c.name;
    EXPECT_LE(m.cycle.E_max, kZero) << c.name;
    // Per half-turn: how many samples lie on the parallelogram branch
    // (theta3 = theta1, theta4 = theta2) and on the anti-parallelogram
    // (theta3 = -theta1, theta4 = -theta2).
    std::array<std::array<int, 2>, 2> on{};
    for (const CycleSample& s : m.cycle.samples) {
      const bool first = s.theta_in > 0.01 && s.theta_in < kPi - 0.01;
      const bool second = s.theta_in > kPi + 0.01;
      if (!first && !second) continue;
      const JointVector& t = s.state.theta;
      const bool parallelogram = angle_gap(t[2], t[0]) + angle_gap(t[3], t[1]) < 1e-8;
      const bool anti = angle_gap(t[2], -t[0]) + angle_gap(t[3], -t[1]) < 1e-8;
      EXPECT_TRUE(parallelogram || anti) << c.name << " at " << s.theta_in;
      ++on[second ? 1 : 0][parallelogram ? 0 : 1];
    }
    for (int half : {0, 1}) {
      EXPECT_TRUE(on[half][0] == 0 || on[half][1] == 0) << c.name << ": half-turn " << half << " mixes the branches";
    }
    changes += (on[0][0] > 0) != (on[1][0] > 0);
  }
  EXPECT_GE(changes, 1);
}

// A planar rocker (the kite 2,1,1,2 driven between its two long links) turns
// only over [120, 240] deg. At theta0 = 0 it cannot be assembled: every
// solve stops with max_iterations where the deformations are still about
// zero, and the failed samples' energies make E_mean a false zero.
TEST(StabilityKnownLimit, UnreachableInputAngleGivesFailedSamplesThatReadNearZero) {
  const LoopGeometry kite = planar_four_bar(2, 1, 1, 2);
  const Methods m = run_methods({"kite 2,1,1,2 at 0", kite, JointVector(), 0.0});
  EXPECT_EQ(m.assembly.status, SolveStatus::max_iterations);
  EXPECT_GT(m.assembly.closure_residual, 0.5);
  EXPECT_EQ(m.cycle.failed_samples, 32);
  EXPECT_GT(m.cycle.max_closure_residual, 0.5);
  // The true energy at theta1 = 0 is 0.2 (the cycle from 150 deg reaches it);
  // this reads below every zero threshold.
  EXPECT_LT(m.cycle.E_mean, kZero);
  // The rigid verification is not misled: the pose does not close, and the
  // motion is found elsewhere, over its closed-form range [120, 240] deg.
  EXPECT_FALSE(m.verification.assembled);
  EXPECT_FALSE(m.verification.on_motion);
  EXPECT_TRUE(m.verification.verified);
  EXPECT_NEAR(m.verification.range_hi - m.verification.range_lo, 2 * kPi / 3, 1e-8);
  EXPECT_NEAR(std::cos(0.5 * (m.verification.range_lo + m.verification.range_hi)), -1.0, 1e-12);

  // The search cannot evaluate the start: a status, the summary's E_mean
  // NaN (no energy; it was a 0 that read as a zero until the limit pinned
  // here was fixed), value +inf. (The initial
  // angles 0, 0, 180, 0 deg: all zero would be the collinear stationary
  // point of CollinearInitialAnglesAreAStationaryPointThatIsNotAMinimum.)
  JointVector at0(4);
  at0 << 0.0, 0.0, kPi, 0.0;
  for (const char* algorithm : kAlgorithms) {
    const LocalSearchSummary s = search(space_around(kite, at0, 0.1, 0.2), kite, algorithm);
    EXPECT_EQ(s.status, SearchStatus::evaluation_failed) << algorithm;
    EXPECT_TRUE(std::isnan(s.E_mean)) << algorithm;
    EXPECT_EQ(s.evaluations, 1) << algorithm;
  }

  // Started inside its range, the full turn solves every sample. Just past
  // the dead point at 240 deg the sample at 251.25 deg failed and read
  // 1.7e-18 until the landing after a fold started along the path tangent
  // (Stepper::land in src/core/cycle.cpp); it now reads 0.0081, between its
  // neighbours' 3e-32 (at the dead point) and 0.028.
  const Methods inside = run_methods({"kite at 150, full turn", kite, JointVector(), rad(150)});
  EXPECT_EQ(inside.cycle.failed_samples, 0);
  const std::vector<CycleSample>& samples = inside.cycle.samples;
  ASSERT_EQ(samples.size(), 32u);
  ASSERT_NEAR(samples[9].theta_in, rad(251.25), 1e-12);
  EXPECT_GT(samples[9].energy, 1e-3);
  EXPECT_GT(samples[9].energy, 10.0 * samples[8].energy);
  EXPECT_LT(samples[9].energy, samples[10].energy);
}

// The same rocker assembled at 150 deg: over a full turn it reads clearly
// non-zero (it cannot turn fully: correct); over a range
// inside its motion it reads zero, and the rigid walk finds the dead points.
TEST(Stability, PlanarRockerReadsZeroInsideItsRangeAndNonZeroOverAFullTurn) {
  const LoopGeometry kite = planar_four_bar(2, 1, 1, 2);
  const Methods full = run_methods({"kite at 150, full turn", kite, JointVector(), rad(150)});
  EXPECT_EQ(full.assembly.status, SolveStatus::converged);
  EXPECT_GT(full.cycle.E_mean, 0.01);  // 0.0744; E(0 deg) = 0.2 exactly (docs/quality/stability.md, S4)
  EXPECT_TRUE(full.verification.verified);
  EXPECT_FALSE(full.verification.full_turn);
  EXPECT_NEAR(full.verification.range_lo, rad(120), rad(0.01));
  EXPECT_NEAR(full.verification.range_hi, rad(240), rad(0.01));
  EXPECT_EQ(full.classification.family, Family::planar);

  Case inside{"kite at 150, 40 deg", kite, JointVector(), rad(150)};
  inside.cycle.range = rad(40);
  inside.cycle.samples = 9;
  const Methods m = run_methods(inside);
  EXPECT_EQ(m.cycle.failed_samples + m.cycle.branch_jumps, 0);
  EXPECT_LE(m.cycle.E_max, kZero);
}

// ---------------------------------------------------------------------------
// Near-planar and near-spherical loops.

// A planar crank-rocker whose twists are eps away from 0 or 180 deg is rigid
// and reads c * eps^2 (the deformation needed is of order eps), down to
// eps = 1e-6 with the same c: no round-off floor above 1e-13.
TEST(Stability, NearPlanarLoopsReadTheSquareOfTheirDistanceFromPlanar) {
  const LoopGeometry crank = planar_four_bar(1, 3, 2.5, 3.5);
  struct Variant {
    const char* name;
    int pattern;  // 0: all twists eps; 1: twists 0, pi - eps, pi - eps, 0; 2: twist 1 only
    double c;     // E_mean / eps^2, measured
  };
  const Variant variants[] = {
      {"all twists eps", 0, 1.28681}, {"two twists pi - eps", 1, 0.835471}, {"twist 1 eps", 2, 0.318848}};
  for (const Variant& v : variants) {
    for (double eps : {1e-4, 1e-5, 1e-6}) {
      LoopGeometry g = crank;
      if (v.pattern == 0) g.alpha.setConstant(eps);
      if (v.pattern == 1) g.alpha << 0.0, kPi - eps, kPi - eps, 0.0;
      if (v.pattern == 2) g.alpha[0] = eps;
      const Case c{std::string(v.name) + " " + std::to_string(eps), g, JointVector(), 0.0};
      const Methods m = run_methods(c);
      EXPECT_EQ(m.cycle.failed_samples + m.cycle.branch_jumps, 0) << c.name;
      // 1e-4 relative: the quadratic law holds to the digits printed.
      EXPECT_NEAR(m.cycle.E_mean / (eps * eps), v.c, 1e-4 * v.c) << c.name;
      // The rigid closure misses by about eps: not verified.
      EXPECT_FALSE(m.verification.verified) << c.name;
      EXPECT_GT(m.verification.worst_residual, 0.5 * eps) << c.name;
      EXPECT_EQ(m.classification.family, Family::unclassified) << c.name;
      EXPECT_NEAR(m.classification.residual, eps, 1e-3 * eps) << c.name;  // planar's sin(alpha) = eps
    }
  }
  // At eps = 1e-6 the one-twist variant reads 3.2e-13: below the built-in
  // zero threshold 1e-12 (a "zero" that verification then rejects), above
  // the default job's 1e-20.
  LoopGeometry g = crank;
  g.alpha[0] = 1e-6;
  const Methods m = run_methods({"twist 1 1e-6", g, JointVector(), 0.0});
  EXPECT_LT(m.cycle.E_mean, kBuiltInZeroThreshold);
  EXPECT_GT(m.cycle.E_mean, kZero);
  EXPECT_FALSE(m.verification.verified);
}

// From a near-planar crank (twists 1e-6), both searches reach the planar
// zero nearby in a few evaluations.
TEST(Stability, SearchFromANearPlanarLoopReachesThePlanarZero) {
  LoopGeometry g = planar_four_bar(1, 3, 2.5, 3.5);
  g.alpha.setConstant(1e-6);
  const JointVector pose = run_methods({"near-planar", g, JointVector(), 0.0}).assembly.state.theta;
  const ParameterSpace space = space_around(g, pose, 0.1, 0.2);
  const LocalSearchSummary gn = search(space, g, "gauss-newton");
  EXPECT_EQ(gn.status, SearchStatus::stopval_reached) << gn.message;
  EXPECT_LE(gn.evaluations, 10);
  const LocalSearchSummary lbfgs = search(space, g, "LD_LBFGS");
  EXPECT_LE(lbfgs.E_mean, kBuiltInZeroThreshold) << to_string(lbfgs.status);
}

// Bennett loops with twists within 1e-6 of 0 or 180 deg are exactly movable:
// zero, verified, and classified Bennett, not planar (sin(alpha) = 1e-6 is
// far above the classification tolerance 1e-8).
TEST(Stability, NearPlanarBennettLoopsMoveAndAreClassifiedBennett) {
  struct Twists {
    double alpha1, alpha2;
  };
  const Twists twists[] = {{1e-6, 2e-6}, {kPi - 1e-6, kPi - 2e-6}, {1e-6, kPi - 2e-6}};
  for (const Twists& t : twists) {
    const LoopGeometry b = bennett_loop(1.0, t.alpha1, t.alpha2);
    const Case c{"near-planar Bennett " + std::to_string(t.alpha1) + "," + std::to_string(t.alpha2), b,
                 bennett_angles(b, rad(120))};
    const Methods m = run_methods(c);
    EXPECT_EQ(m.cycle.failed_samples + m.cycle.branch_jumps, 0) << c.name;
    EXPECT_LE(m.cycle.E_max, kZero) << c.name;
    EXPECT_TRUE(m.verification.verified) << c.name;
    EXPECT_TRUE(m.verification.full_turn) << c.name;
    EXPECT_EQ(m.classification.family, Family::bennett) << c.name;
  }
}

// "Near-spherical" has no meaning for a dimensionless energy: a spherical 4R
// whose lengths are all 1e-6 (or 1e-9) is, scaled by L, the same loop as with
// all lengths 1, and reads the same clearly non-zero energy. Only lengths
// exactly zero are spherical (L = 1 by convention): the energy is
// discontinuous there.
TEST(Stability, NearSphericalLoopIsItsOwnUnitScaleCopy) {
  const LoopGeometry sph = spherical_four_bar(rad(20), rad(70), rad(60), rad(80));
  const Methods exact = run_methods({"spherical", sph, JointVector(), 0.0});
  EXPECT_LE(exact.cycle.E_max, kZero);
  EXPECT_TRUE(exact.verification.verified);
  EXPECT_EQ(exact.classification.family, Family::spherical);

  LoopGeometry unit = sph;
  unit.a.setConstant(1.0);
  const Methods reference = run_methods({"spherical twists, lengths 1", unit, JointVector(), 0.0});
  EXPECT_GT(reference.cycle.E_mean, 0.05);  // 0.104: rigid
  for (double eps : {1e-6, 1e-9}) {
    LoopGeometry g = sph;
    g.a.setConstant(eps);
    const Methods m = run_methods({"lengths " + std::to_string(eps), g, JointVector(), 0.0});
    // Scale invariance, to round-off (1e-12 relative).
    EXPECT_NEAR(m.cycle.E_mean, reference.cycle.E_mean, 1e-12 * reference.cycle.E_mean) << eps;
    EXPECT_FALSE(m.verification.verified) << eps;
    EXPECT_NE(m.classification.family, Family::spherical) << eps;
    // One length eps, the others zero: a2 = a3 = a4 = 0, a1 = 2 L.
    g = sph;
    g.a[0] = eps;
    EXPECT_GT(run_methods({"a1 " + std::to_string(eps), g, JointVector(), 0.0}).cycle.E_mean, 0.5) << eps;
  }
}

// Consequently a search from a near-spherical loop, lengths in [0, 2e-6],
// cannot approach the spherical zero at a = 0: it stops at a positive
// minimum. Search spherical loops with the lengths fixed at 0.
TEST(StabilityKnownLimit, SearchFromANearSphericalLoopCannotReachTheSphericalZero) {
  LoopGeometry g = spherical_four_bar(rad(20), rad(70), rad(60), rad(80));
  g.a.setConstant(1e-6);
  const JointVector pose = run_methods({"near-spherical", g, JointVector(), 0.0}).assembly.state.theta;
  for (const char* algorithm : kAlgorithms) {
    const LocalSearchSummary s = search(space_around(g, pose, 1.0, 0.0), g, algorithm);
    EXPECT_GT(s.E_mean, 0.01) << algorithm << " " << to_string(s.status);  // 0.048 seen
    EXPECT_NE(s.status, SearchStatus::stopval_reached) << algorithm;
  }
}

// ---------------------------------------------------------------------------
// Extreme torsion stiffness ratios.

TEST(Stability, ExtremeTorsionRatiosKeepMovableLoopsAtZeroAndRigidLoopsAboveIt) {
  double previous = 0.0;
  for (double rho : {1e-6, 1e-3, 1.0, 1e3, 1e6}) {
    EquilibriumOptions eo;
    eo.torsion_stiffness_ratio = rho;
    const std::string tag = " rho " + std::to_string(rho);
    const Methods bennett = run_methods({"Bennett" + tag, paper_bennett_loop(), paper_pose(), 0.0, eo});
    EXPECT_EQ(bennett.cycle.failed_samples + bennett.cycle.branch_jumps, 0) << tag;
    // Twist deformations at round-off are weighted by rho: 3e-26 at 1e6.
    EXPECT_LE(bennett.cycle.E_max, kZero) << tag;
    EXPECT_TRUE(bennett.verification.verified) << tag;

    const Methods rigid = run_methods({"rigid" + tag, rigid_paper_loop(), paper_pose(), 0.0, eo});
    EXPECT_EQ(rigid.cycle.failed_samples + rigid.cycle.branch_jumps, 0) << tag;
    // Clearly non-zero at every ratio (1.3e-6 at rho = 1e-6: lengths stay stiff).
    EXPECT_GT(rigid.cycle.E_mean, 1e-6) << tag;
    // A stiffer twist can only cost more: E_mean grows with rho (1e-12
    // relative for round-off), towards the lengths-only value 4.04e-5.
    EXPECT_GE(rigid.cycle.E_mean, previous * (1 - 1e-12)) << tag;
    EXPECT_LT(rigid.cycle.E_mean, 4.1e-5) << tag;
    previous = rigid.cycle.E_mean;

    // A generic loop: any answer, but a sane one (checked inside).
    run_methods({"random 4R seed 1" + tag, random_loop(4, 1), JointVector(), 0.0, eo});

    const ParameterSpace space = a1_free(rigid_paper_loop(), paper_pose(), 1.9, 2.1);
    const LocalSearchSummary gn = search(space, rigid_paper_loop(), "gauss-newton", eo);
    EXPECT_EQ(gn.status, SearchStatus::stopval_reached) << tag << " " << gn.message;
    EXPECT_NEAR(gn.x[0], 2.0, 1e-9) << tag;
    const LocalSearchSummary lbfgs = search(space, rigid_paper_loop(), "LD_LBFGS", eo);
    EXPECT_LE(lbfgs.E_mean, kBuiltInZeroThreshold) << tag << " " << to_string(lbfgs.status);
  }
}

// ---------------------------------------------------------------------------
// Scale.

// E_mean is the same at every scale to round-off: the model works in units
// of L. Checked from a thousandth to a thousand (and a millionth to a
// million), for a smooth rigid loop, one with offsets under full compliance,
// a generic loop whose cycle jumps branch twice, and a Bennett loop.
TEST(Stability, EnergyIsScaleInvariantFromAThousandthToAThousand) {
  LoopGeometry offsets = rigid_paper_loop();
  offsets.d << 0.3, -0.2, 0.1, 0.4;
  EquilibriumOptions full;
  full.compliance = Compliance::full;
  const LoopGeometry generic = random_loop(4, 2);
  const JointVector generic_pose = run_methods({"generic", generic, JointVector(), 0.0}).assembly.state.theta;
  const Case cases[] = {{"rigid paper loop", rigid_paper_loop(), paper_pose()},
                        {"offsets, full compliance", offsets, paper_pose(), 0.0, full},
                        {"random 4R seed 2", generic, generic_pose},
                        {"Bennett", paper_bennett_loop(), paper_pose()}};
  for (const Case& base : cases) {
    const Methods unit = run_methods(base);
    for (double k : {1e-6, 1e-3, 1e-2, 1e2, 1e3, 1e6}) {
      Case c = base;
      c.geometry = scaled(base.geometry, 1.0 / k);
      c.name += " x" + std::to_string(k);
      const Methods m = run_methods(c);
      // 1e-12 relative: 3e-14 seen; the iteration paths are the same.
      EXPECT_NEAR(m.cycle.E_mean, unit.cycle.E_mean, 1e-12 * unit.cycle.E_mean + 1e-30) << c.name;
      EXPECT_EQ(m.cycle.branch_jumps, unit.cycle.branch_jumps) << c.name;
      EXPECT_EQ(m.cycle.failed_samples, unit.cycle.failed_samples) << c.name;
      EXPECT_EQ(m.verification.verified, unit.verification.verified) << c.name;
      EXPECT_EQ(m.classification.family, unit.classification.family) << c.name;
      // The verification measures in units of L too. A rigid loop's residual
      // is where the least-squares closure stopped: equal to 2e-9 relative.
      EXPECT_NEAR(m.verification.worst_residual, unit.verification.worst_residual,
                  1e-6 * unit.verification.worst_residual + 1e-14)
          << c.name;
    }
  }
}

// Gauss-Newton (Marquardt's scaling) takes the same steps at every scale;
// LBFGS reaches the zero from 1e-3 to 1e3 (see the known limit beyond).
TEST(Stability, SearchReachesTheBennettLoopFromAThousandthToAThousand) {
  int unit_evaluations = -1;
  for (double k : {1.0, 1e-3, 1e-2, 1e2, 1e3}) {
    const LoopGeometry g = scaled(rigid_paper_loop(), 1.0 / k);
    const ParameterSpace space = a1_free(g, paper_pose(), 1.9 * k, 2.1 * k);
    const LocalSearchSummary gn = search(space, g, "gauss-newton");
    EXPECT_EQ(gn.status, SearchStatus::stopval_reached) << k;
    EXPECT_NEAR(gn.x[0] / k, 2.0, 1e-9) << k;
    if (unit_evaluations < 0) unit_evaluations = gn.evaluations;
    EXPECT_EQ(gn.evaluations, unit_evaluations) << k;
    const LocalSearchSummary lbfgs = search(space, g, "LD_LBFGS");
    EXPECT_LE(lbfgs.E_mean, kBuiltInZeroThreshold) << k << " " << to_string(lbfgs.status);
  }
}

// NLopt sees the geometry in its own units: at a millionfold scale the
// gradient (per unit length) is a millionth and LBFGS's first step falls
// below xtol_rel, so it stops at the start (E_mean 2e-5) saying SUCCESS.
// Gauss-Newton still reaches the zero. Give lengths of order 1.
TEST(StabilityKnownLimit, LbfgsStopsAtTheStartOfAMillionfoldScaledLoop) {
  const double k = 1e6;
  const LoopGeometry g = scaled(rigid_paper_loop(), 1.0 / k);
  const ParameterSpace space = a1_free(g, paper_pose(), 1.9 * k, 2.1 * k);
  const LocalSearchSummary lbfgs = search(space, g, "LD_LBFGS");
  EXPECT_EQ(lbfgs.status, SearchStatus::xtol_reached);
  EXPECT_LE(lbfgs.evaluations, 2);
  EXPECT_NEAR(lbfgs.E_mean, 1.96274e-5, 1e-9);
  const LocalSearchSummary gn = search(space, g, "gauss-newton");
  EXPECT_EQ(gn.status, SearchStatus::stopval_reached);
}

// ---------------------------------------------------------------------------
// Initial angles far from closure.

// From passive angles off by pi, and from random angles, the movable loops
// assemble on their zero and the rigid loop on the same cycle as from the
// paper's pose (E_mean to 1e-9 relative).
TEST(Stability, AnglesFarFromClosureAssembleOnTheZeroBranch) {
  JointVector off_by_pi = paper_pose();
  for (int i = 1; i < 4; ++i) off_by_pi[i] += kPi;
  std::vector<JointVector> starts{off_by_pi};
  for (std::uint64_t seed : {1, 2, 3, 5, 6}) starts.push_back(random_angles(4, seed));
  const double rigid_reference = run_methods({"rigid", rigid_paper_loop(), paper_pose()}).cycle.E_mean;
  for (size_t k = 0; k < starts.size(); ++k) {
    const std::string tag = " start " + std::to_string(k);
    const Methods bennett = run_methods({"Bennett" + tag, paper_bennett_loop(), starts[k]});
    EXPECT_EQ(bennett.cycle.failed_samples + bennett.cycle.branch_jumps, 0) << tag;
    EXPECT_LE(bennett.cycle.E_max, kZero) << tag;
    EXPECT_TRUE(bennett.verification.verified) << tag;
    EXPECT_EQ(bennett.classification.family, Family::bennett) << tag;
    const Methods rigid = run_methods({"rigid" + tag, rigid_paper_loop(), starts[k]});
    EXPECT_EQ(rigid.cycle.failed_samples + rigid.cycle.branch_jumps, 0) << tag;
    EXPECT_NEAR(rigid.cycle.E_mean, rigid_reference, 1e-9 * rigid_reference) << tag;
    EXPECT_FALSE(rigid.verification.assembled) << tag;
    // Spherical 4R from the same angles (seed 2's assembly stops at
    // max_iterations, E 1e-13, and the cycle's anchor solve finishes it).
    const Methods spherical =
        run_methods({"spherical" + tag, spherical_four_bar(rad(20), rad(70), rad(60), rad(80)), starts[k]});
    EXPECT_EQ(spherical.cycle.failed_samples + spherical.cycle.branch_jumps, 0) << tag;
    EXPECT_LE(spherical.cycle.E_max, kZero) << tag;
    EXPECT_TRUE(spherical.verification.verified) << tag;
  }
  // The search from these starts: a1 free from 2.03.
  for (size_t k = 0; k < 4; ++k) {
    const ParameterSpace space = a1_free(rigid_paper_loop(), starts[k], 1.9, 2.1);
    const LocalSearchSummary gn = search(space, rigid_paper_loop(), "gauss-newton");
    EXPECT_EQ(gn.status, SearchStatus::stopval_reached) << k;
    const LocalSearchSummary lbfgs = search(space, rigid_paper_loop(), "LD_LBFGS");
    EXPECT_LE(lbfgs.E_mean, kBuiltInZeroThreshold) << k;
  }
}

// From random_angles(4, 4) the paper's Bennett loop assembles on a spurious
// elastic equilibrium, E = 0.64 with status converged (a KKT point off the
// closure curve); the cycle follows it until it jumps to the zero branch
// (two jumps, flagged): E_mean 0.12 for a movable loop, a missed zero. The
// rigid walk from that pose still closes and verifies. A search whose every
// evaluation assembles afresh from these angles (reuse_nearby_cycle off)
// misses the Bennett loop a1 = 2: its objective jumps between the spurious
// branch and the other, and it ends where its cycle lies on the spurious
// branch throughout, with no jump left to flag it. Reusing the nearby cycle
// (the default) keeps the objective on one branch along the search's path,
// and that path leads to the Bennett loop.
TEST(StabilityKnownLimit, RandomAnglesCanAssembleAMovableLoopOnASpuriousEquilibrium) {
  const JointVector start = random_angles(4, 4);
  const Methods m = run_methods({"Bennett from random angles 4", paper_bennett_loop(), start});
  EXPECT_EQ(m.assembly.status, SolveStatus::converged);
  EXPECT_NEAR(m.assembly.energy, 0.6418, 1e-3);  // a local minimum of the problem at 122.8 deg
  {
    const LoopModel model(paper_bennett_loop());
    EquilibriumWorkspace ws(model);
    EquilibriumState tangent;
    EXPECT_TRUE(equilibrium_tangent(model, ws, m.assembly.state, tangent));  // a minimum, not a saddle
  }
  EXPECT_GT(m.cycle.E_mean, 0.01);     // 0.1199 seen
  EXPECT_GT(m.cycle.branch_jumps, 0);  // 2 seen: the cycle does flag it
  EXPECT_TRUE(m.verification.verified);
  const ParameterSpace space = a1_free(rigid_paper_loop(), start, 1.9, 2.1);
  for (const char* algorithm : kAlgorithms) {
    CycleSummary final_cycle;
    const LocalSearchSummary s = search(space, rigid_paper_loop(), algorithm, {}, &final_cycle, false);
    EXPECT_GT(s.E_mean, 1e-6) << algorithm << " " << to_string(s.status);  // 5.9e-5 (GN), 7.8e-5 (LBFGS)
    EXPECT_GT(std::abs(s.x[0] - 2.0), 0.01) << algorithm;                  // 1.948, 1.940
    EXPECT_EQ(final_cycle.branch_jumps + final_cycle.failed_samples, 0) << algorithm;

    const LocalSearchSummary reused = search(space, rigid_paper_loop(), algorithm, {}, &final_cycle, true);
    EXPECT_LE(reused.E_mean, kBuiltInZeroThreshold) << algorithm << " " << to_string(reused.status);
    EXPECT_NEAR(reused.x[0], 2.0, 1e-6) << algorithm;  // 2 - 2e-16 (GN), 2 - 2e-9 (LBFGS)
  }
}

// From random_angles(4, 1) the planar crank's solve stalls: max_iterations
// with the deformations about zero and the closure residual about 1. The
// cycle continues from that state and every sample fails the same way:
// E_mean reads 1e-26, a false zero (the failed_samples count says it). The
// search is not fooled: its objective falls back to the deterministic
// assembly guesses when the start's angles do not converge.
TEST(StabilityKnownLimit, StalledSolveFromFarAnglesGivesFailedSamplesThatReadNearZero) {
  const LoopGeometry crank = planar_four_bar(1, 3, 2.5, 3.5);
  const JointVector start = random_angles(4, 1);
  const Methods m = run_methods({"crank from random angles 1", crank, start});
  EXPECT_EQ(m.assembly.status, SolveStatus::max_iterations);
  EXPECT_GT(m.assembly.closure_residual, 0.5);
  EXPECT_EQ(m.cycle.failed_samples, 32);
  EXPECT_LT(m.cycle.E_mean, kZero);
  EXPECT_TRUE(m.verification.verified);  // the rigid closure from the same angles is found
  // More iterations do not help: the solve is stuck, not slow.
  const EquilibriumSummary longer = solve_at(crank, start[0], start, [] {
    EquilibriumOptions o;
    o.max_iterations = 1000;
    return o;
  }());
  EXPECT_EQ(longer.status, SolveStatus::max_iterations);
  EXPECT_GT(longer.closure_residual, 0.5);
  for (const char* algorithm : kAlgorithms) {
    const LocalSearchSummary s = search(space_around(crank, start, 0.1, 0.2), crank, algorithm);
    EXPECT_EQ(s.status, SearchStatus::stopval_reached) << algorithm;
    EXPECT_EQ(s.evaluations, 1) << algorithm;
  }
}

// All joint angles zero put a planar loop's links on one line: by symmetry
// a stationary point of the elastic energy and of the rigid least squares,
// but not a minimum. The solve reports converged there (E = 1.75; its
// tangent is refused: the reduced Hessian is not positive definite), the
// rigid walk cannot start, and a search from the movable crank does not see
// its zero (LBFGS wanders off to 0.107; Gauss-Newton stops near the start on
// xtol). The cycle leaves the stationary point at its first step and lands
// on the crank's motion, where every other sample reads zero: E_mean is the
// anchor's 1.75 / 32. (Before the landing after a fold started along the
// path tangent it read 0.81, with 14 failed samples, in 3,640 iterations.)
TEST(StabilityKnownLimit, CollinearInitialAnglesAreAStationaryPointThatIsNotAMinimum) {
  const LoopGeometry crank = planar_four_bar(1, 3, 2.5, 3.5);
  const JointVector collinear = JointVector::Zero(4);
  const Methods m = run_methods({"crank from all-zero angles", crank, collinear});
  EXPECT_EQ(m.assembly.status, SolveStatus::converged);
  EXPECT_NEAR(m.assembly.energy, 1.754386, 1e-5);
  {
    const LoopModel model(crank);
    EquilibriumWorkspace ws(model);
    EquilibriumState tangent;
    EXPECT_FALSE(equilibrium_tangent(model, ws, m.assembly.state, tangent));
  }
  EXPECT_EQ(m.cycle.failed_samples, 0);
  EXPECT_EQ(m.cycle.branch_jumps, 1);
  ASSERT_EQ(m.cycle.samples.size(), 32u);
  EXPECT_NEAR(m.cycle.samples[0].energy, m.assembly.energy, 1e-12);
  for (size_t j = 1; j < m.cycle.samples.size(); ++j) EXPECT_LT(m.cycle.samples[j].energy, kZero) << j;
  EXPECT_NEAR(m.cycle.E_mean, m.assembly.energy / 32.0, 1e-12);
  // The collinear pose does not close the rigid loop; the crank's motion is
  // found from assemblies over the turn all the same.
  EXPECT_FALSE(m.verification.assembled);
  EXPECT_FALSE(m.verification.on_motion);
  EXPECT_TRUE(m.verification.verified);
  EXPECT_TRUE(m.verification.full_turn);
  for (const char* algorithm : kAlgorithms) {
    const ParameterSpace space = space_around(crank, collinear, 0.1, 0.2);
    const LocalSearchSummary s = search(space, crank, algorithm);
    EXPECT_NE(s.status, SearchStatus::stopval_reached) << algorithm;
    EXPECT_GT(s.E_mean, 1e-2) << algorithm << " " << to_string(s.status);
    if (std::string(algorithm) == "LD_LBFGS") {
      EXPECT_GT((s.x - space.free_values(crank)).cwiseAbs().maxCoeff(), 1e-2) << algorithm;
    }
  }
}

// ---------------------------------------------------------------------------
// A start exactly on a zero.

// A movable loop given as the start: both searches report zero at the first
// evaluation and return the start itself, bit for bit.
TEST(Stability, AStartOnAZeroReportsZeroAndDoesNotMove) {
  struct Start {
    std::string name;
    LoopGeometry geometry;
    JointVector angles;
    double rel_a, span_alpha;
    EquilibriumOptions equilibrium = {};
  };
  const LoopGeometry p = paper_bennett_loop();
  const LoopGeometry line_symmetric = bennett_loop_line_symmetric(2.0, rad(30), rad(90));
  const LoopGeometry near_planar = bennett_loop(1.0, 1e-6, 2e-6);
  const LoopGeometry crank = planar_four_bar(1, 3, 2.5, 3.5);
  const LoopGeometry spherical = spherical_four_bar(rad(20), rad(70), rad(60), rad(80));
  JointVector change_point(4);
  change_point << 0.0, kPi, 0.0, kPi;
  EquilibriumOptions soft, stiff;
  soft.torsion_stiffness_ratio = 1e-6;
  stiff.torsion_stiffness_ratio = 1e6;
  const std::vector<Start> starts{
      {"Bennett at 120", p, paper_pose(), 0.1, 0.2},
      {"Bennett at its fold", p, bennett_angles(p, 0.0), 0.1, 0.2},
      {"Bennett from random angles 1", p, random_angles(4, 1), 0.1, 0.2},
      {"Bennett x1e-3", scaled(p, 1e3), paper_pose(), 0.1, 0.2},
      {"Bennett x1e3", scaled(p, 1e-3), paper_pose(), 0.1, 0.2},
      {"Bennett rho 1e-6", p, paper_pose(), 0.1, 0.2, soft},
      {"Bennett rho 1e6", p, paper_pose(), 0.1, 0.2, stiff},
      {"line-symmetric Bennett", line_symmetric, bennett_angles_line_symmetric(line_symmetric, rad(120)), 0.1, 0.2},
      {"near-planar Bennett", near_planar, bennett_angles(near_planar, rad(120)), 0.1, 0.2},
      {"planar crank", crank, run_methods({"crank", crank, JointVector(), 0.0}).assembly.state.theta, 0.1, 0.2},
      {"parallelogram at its change point", planar_four_bar(1, 2, 1, 2), change_point, 0.1, 0.2},
      {"spherical, lengths fixed at 0", spherical,
       run_methods({"sph", spherical, JointVector(), 0.0}).assembly.state.theta, 0.0, 0.2},
  };
  for (const Start& s : starts) {
    const ParameterSpace space = space_around(s.geometry, s.angles, s.rel_a, s.span_alpha);
    const Eigen::VectorXd x0 = space.free_values(s.geometry);
    for (const char* algorithm : kAlgorithms) {
      const LocalSearchSummary r = search(space, s.geometry, algorithm, s.equilibrium);
      EXPECT_EQ(r.status, SearchStatus::stopval_reached) << s.name << " " << algorithm << ": " << r.message;
      EXPECT_EQ(r.evaluations, 1) << s.name << " " << algorithm;
      EXPECT_EQ(r.x, x0) << s.name << " " << algorithm;
      EXPECT_LE(r.E_mean, 1e-26) << s.name << " " << algorithm;  // the default stopval
    }
  }
}

}  // namespace
}  // namespace loopfarm
