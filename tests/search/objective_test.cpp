#include "loopfarm/search/objective.hpp"

#include <cmath>

#include <gtest/gtest.h>

#include "loopfarm/search/job.hpp"
#include "search_fixtures.hpp"
#include "test_support.hpp"

namespace loopfarm {
namespace {

using testing::rad;
using testing::relative_error;

// A rigid 4R with offsets, ties (a3 = a1, d3 = -d1) and a fixed twist: the
// chain rule through the ties is part of what is checked.
constexpr const char* kTiedJob = R"(
[loop]
joints = 4
samples = 12
[space]
a1 = [0.5, 5]
a2 = [0.5, 5]
a3 = "a1"
a4 = [0.5, 5]
alpha1_deg = [0, 180]
alpha2_deg = 40
alpha3_deg = [0, 180]
alpha4_deg = [0, 180]
d1 = [-1, 1]
d2 = 0
d3 = "-d1"
d4 = [-1, 1]
theta1_deg = 120
theta2_deg = 90
theta3_deg = -120
theta4_deg = -90
)";

struct TiedFixture {
  Job job = parse_job(kTiedJob, "tied.toml");
  JointVector theta = job.space.initial_angles(Eigen::VectorXd());
  Eigen::VectorXd x0() const {
    Eigen::VectorXd x(job.space.free_count());
    // a1, a2, a4, alpha1, alpha3, alpha4, d1, d4 (free order: a, alpha, d)
    x << 2.1, 3.7, 3.2, rad(20), rad(25), rad(45), 0.15, -0.1;
    return x;
  }
  // A direction of small steps away from x0 along which the cycle stays smooth.
  Eigen::VectorXd path_direction() const {
    Eigen::VectorXd direction(job.space.free_count());
    direction << 0.3, -0.2, 0.1, rad(2), rad(-1), rad(1.5), 0.05, 0.02;
    return direction;
  }
  // The job's loop settings, each evaluation walking its cycle from the assembly.
  ObjectiveOptions fresh_options() const {
    ObjectiveOptions options = ObjectiveOptions::from_loop(job.loop);
    options.reuse_nearby_cycle = false;
    return options;
  }
};

Eigen::VectorXd central_gradient(CycleObjective& objective, const Eigen::VectorXd& x, double h) {
  Eigen::VectorXd g(x.size());
  for (int i = 0; i < x.size(); ++i) {
    Eigen::VectorXd p = x, m = x;
    p[i] += h;
    m[i] -= h;
    g[i] = (objective.evaluate(p, nullptr).value - objective.evaluate(m, nullptr).value) / (2 * h);
  }
  return g;
}

TEST(Objective, GradientThroughTiesAgreesWithCentralDifferences) {
  TiedFixture f;
  ASSERT_EQ(f.job.space.free_count(), 8);
  CycleObjective objective(f.job.space, ObjectiveOptions::from_loop(f.job.loop), f.theta);
  Eigen::VectorXd gradient;
  const ObjectiveValue v = objective.evaluate(f.x0(), &gradient);
  ASSERT_TRUE(v.ok);
  ASSERT_EQ(v.failed_samples + v.branch_jumps, 0);
  EXPECT_GT(v.E_mean, 1e-4);  // rigid: the test means something
  EXPECT_EQ(v.value, v.E_mean);
  const Eigen::VectorXd fd = central_gradient(objective, f.x0(), 1e-6);
  EXPECT_LT(relative_error(gradient, fd), 1e-6) << gradient.transpose() << "\n" << fd.transpose();
}

TEST(Objective, ResidualsAndJacobianAgreeWithValueAndCentralDifferences) {
  TiedFixture f;
  CycleObjective objective(f.job.space, ObjectiveOptions::from_loop(f.job.loop), f.theta);
  Eigen::VectorXd r, gradient;
  Eigen::MatrixXd J;
  const ObjectiveValue v = objective.evaluate_residuals(f.x0(), r, &J);
  ASSERT_TRUE(v.ok);
  EXPECT_NEAR(0.5 * r.squaredNorm(), v.E_mean, 1e-13 * v.E_mean);
  objective.evaluate(f.x0(), &gradient);
  EXPECT_LT(relative_error(J.transpose() * r, gradient), 1e-9);
  Eigen::MatrixXd fd(J.rows(), J.cols());
  for (int i = 0; i < f.x0().size(); ++i) {
    Eigen::VectorXd p = f.x0(), m = f.x0(), rp, rm;
    p[i] += 1e-6;
    m[i] -= 1e-6;
    objective.evaluate_residuals(p, rp, nullptr);
    objective.evaluate_residuals(m, rm, nullptr);
    fd.col(i) = (rp - rm) / 2e-6;
  }
  EXPECT_LT(relative_error(J, fd), 1e-6);
}

// A smooth stand-in for a family distance (its gradient is exact), so that
// the steering's own derivatives are what is checked.
double twist_gap(const LoopGeometry& g, GeometryVector* gradient) {
  const int n = g.joints();
  const double gap = std::sqrt(std::pow(g.alpha[0] - g.alpha[2], 2) + std::pow(g.a[1] - 3.0, 2));
  if (gradient) {
    gradient->setZero(3 * n);
    (*gradient)[n + 0] = (g.alpha[0] - g.alpha[2]) / gap;
    (*gradient)[n + 2] = -(g.alpha[0] - g.alpha[2]) / gap;
    (*gradient)[1] = (g.a[1] - 3.0) / gap;
  }
  return gap;
}

// Steered by both means, each far from a factor of 1: a deflation by the
// twist gap and a travel term with a large t0.
ObjectiveOptions strongly_steered(const TiedFixture& f) {
  ObjectiveOptions options = ObjectiveOptions::from_loop(f.job.loop);
  options.deflation.push_back({"twist gap", twist_gap});
  options.deflation_power = 2.0;
  options.deflation_shift = 0.5;
  options.nontrivial = true;
  options.min_travel = rad(60);  // large, so that the travel term is far from 1
  return options;
}

TEST(Objective, SteeredGradientAndJacobianAgreeWithCentralDifferences) {
  TiedFixture f;
  ObjectiveOptions options = strongly_steered(f);
  // Every evaluation from the assembly, so that the value and the residuals
  // at x0 come from the same cycle to the last bit (a cycle reused from the
  // differences' neighbours agrees to the solve's tolerance only).
  options.reuse_nearby_cycle = false;
  CycleObjective objective(f.job.space, options, f.theta);
  Eigen::VectorXd gradient, r;
  Eigen::MatrixXd J;
  const ObjectiveValue v = objective.evaluate(f.x0(), &gradient);
  ASSERT_TRUE(v.ok);
  EXPECT_GT(v.steering_factor, 1.5);
  EXPECT_NEAR(v.value, v.steering_factor * v.E_mean, 1e-15 * v.value);
  const Eigen::VectorXd fd = central_gradient(objective, f.x0(), 1e-6);
  EXPECT_LT(relative_error(gradient, fd), 1e-6) << gradient.transpose() << "\n" << fd.transpose();
  objective.evaluate_residuals(f.x0(), r, &J);
  EXPECT_NEAR(0.5 * r.squaredNorm(), v.value, 1e-13 * v.value);
  EXPECT_LT(relative_error(J.transpose() * r, gradient), 1e-9);
}

// The steering factor against the formula docs/guide/steering.md and
// objective.hpp define, computed here on its own from the cycle's samples:
// M = prod_f (dist_f^-p + shift) * prod_{j != input} (1 + (t0 / travel_j)^2),
// travel_j the max - min of joint j's angle unwrapped along the samples.
TEST(Objective, SteeringFactorIsTheDocumentedFormula) {
  TiedFixture f;
  for (const double power : {1.0, 2.0, 3.0}) {
    ObjectiveOptions options = ObjectiveOptions::from_loop(f.job.loop);
    options.deflation.push_back({"twist gap", twist_gap});
    options.deflation_power = power;
    options.deflation_shift = 0.5;
    options.nontrivial = true;
    options.min_travel = rad(60);
    CycleObjective objective(f.job.space, options, f.theta);
    const ObjectiveValue v = objective.evaluate(f.x0(), nullptr);
    ASSERT_TRUE(v.ok);

    const LoopGeometry& g = objective.geometry();
    const double gap = std::sqrt(std::pow(g.alpha[0] - g.alpha[2], 2) + std::pow(g.a[1] - 3.0, 2));
    double expected = std::pow(gap, -power) + 0.5;
    const std::vector<CycleSample>& samples = objective.cycle().samples;
    for (int j = 1; j < 4; ++j) {
      double angle = samples[0].state.theta[j], lo = angle, hi = angle;
      for (size_t k = 1; k < samples.size(); ++k) {
        double step = std::fmod(samples[k].state.theta[j] - samples[k - 1].state.theta[j], 2 * 3.14159265358979323846);
        if (step > 3.14159265358979323846) step -= 2 * 3.14159265358979323846;
        if (step < -3.14159265358979323846) step += 2 * 3.14159265358979323846;
        angle += step;
        lo = std::min(lo, angle);
        hi = std::max(hi, angle);
      }
      expected *= 1.0 + std::pow(rad(60) / (hi - lo), 2);
    }
    EXPECT_NEAR(v.steering_factor, expected, 1e-12 * expected) << power;
    EXPECT_GT(v.steering_factor, 2.0) << power;
    EXPECT_NEAR(v.value, expected * v.E_mean, 1e-12 * v.value) << power;
  }
}

TEST(Objective, MaxMeasureHasTheWorstSamplesGradientAndResiduals) {
  // E_max is differentiable where its worst sample does not change: checked
  // against central differences there, with and without steering, and the
  // residuals carry E_max exactly.
  TiedFixture f;
  for (bool steered : {false, true}) {
    ObjectiveOptions options = ObjectiveOptions::from_loop(f.job.loop);
    options.measure = CycleMeasure::max;
    options.reuse_nearby_cycle = false;  // bit-identical cycles at x0, as above
    if (steered) {
      options.deflation.push_back({"twist gap", twist_gap});
      options.nontrivial = true;
      options.min_travel = rad(60);
    }
    CycleObjective objective(f.job.space, options, f.theta);
    Eigen::VectorXd gradient, r;
    Eigen::MatrixXd J;
    const ObjectiveValue v = objective.evaluate(f.x0(), &gradient);
    ASSERT_TRUE(v.ok);
    EXPECT_GT(v.E_max, 1.2 * v.E_mean);  // the max is not the mean here
    EXPECT_NEAR(v.value, v.steering_factor * v.E_max, 1e-15 * v.value);
    const Eigen::VectorXd fd = central_gradient(objective, f.x0(), 1e-6);
    EXPECT_LT(relative_error(gradient, fd), 1e-6) << "steered " << steered << "\n"
                                                  << gradient.transpose() << "\n"
                                                  << fd.transpose();
    objective.evaluate_residuals(f.x0(), r, &J);
    EXPECT_NEAR(0.5 * r.squaredNorm(), v.value, 1e-13 * v.value);
    EXPECT_LT(relative_error(J.transpose() * r, gradient), 1e-9);
  }
}

// The nearby cycle's reuse is a cheaper way to the same number: along a path
// of small steps its values agree with evaluations from the assembly to the
// solve's tolerance, at a fraction of the Newton iterations.
TEST(Objective, ReusedNearbyCyclesAgreeWithFreshOnesAndCostFewerIterations) {
  TiedFixture f;
  CycleObjective fresh(f.job.space, f.fresh_options(), f.theta);
  CycleObjective reused(f.job.space, ObjectiveOptions::from_loop(f.job.loop), f.theta);
  const Eigen::VectorXd direction = f.path_direction();
  long long fresh_iterations = 0, reused_iterations = 0;
  for (int k = 0; k <= 10; ++k) {
    const Eigen::VectorXd x = f.x0() + (0.005 * k) * direction;
    const ObjectiveValue a = fresh.evaluate(x, nullptr);
    const ObjectiveValue b = reused.evaluate(x, nullptr);
    ASSERT_TRUE(a.ok && b.ok) << k;
    ASSERT_EQ(a.failed_samples + a.branch_jumps, 0) << k;
    EXPECT_NEAR(b.E_mean, a.E_mean, 1e-10 * a.E_mean) << k;
    EXPECT_NEAR(b.E_max, a.E_max, 1e-10 * a.E_max) << k;
    EXPECT_LT((reused.start_state().theta - fresh.start_state().theta).cwiseAbs().maxCoeff(), 1e-8) << k;
    fresh_iterations += fresh.cycle().total_iterations;
    if (k > 0) reused_iterations += reused.cycle().total_iterations;
  }
  // 10 steps: the reused cycles cost a few iterations a sample.
  EXPECT_LT(reused_iterations, fresh_iterations / 3) << reused_iterations << " vs " << fresh_iterations;
}

// Where the nearby cycle's Jacobian was computed (as Gauss-Newton does at
// each point it accepts), the next evaluation starts each sample from a
// first-order prediction along it: the same values as evaluations from the
// assembly, in fewer Newton iterations than from the nearby samples as they
// were.
TEST(Objective, PredictedNearbySamplesGiveTheSameValuesInFewerIterations) {
  TiedFixture f;
  CycleObjective fresh(f.job.space, f.fresh_options(), f.theta);
  CycleObjective predicted(f.job.space, ObjectiveOptions::from_loop(f.job.loop), f.theta);
  CycleObjective unpredicted(f.job.space, ObjectiveOptions::from_loop(f.job.loop), f.theta);
  const Eigen::VectorXd direction = f.path_direction();
  long long predicted_iterations = 0, unpredicted_iterations = 0;
  Eigen::VectorXd r;
  Eigen::MatrixXd J;
  for (int k = 0; k <= 8; ++k) {
    const Eigen::VectorXd x = f.x0() + (0.006 * k) * direction;
    const ObjectiveValue a = fresh.evaluate(x, nullptr);
    const ObjectiveValue b = predicted.evaluate_residuals(x, r, &J);
    const ObjectiveValue c = unpredicted.evaluate_residuals(x, r, nullptr);
    ASSERT_TRUE(a.ok && b.ok && c.ok) << k;
    ASSERT_EQ(a.failed_samples + a.branch_jumps, 0) << k;
    EXPECT_NEAR(b.E_mean, a.E_mean, 1e-10 * a.E_mean) << k;
    EXPECT_NEAR(c.E_mean, a.E_mean, 1e-10 * a.E_mean) << k;
    if (k > 0) {
      predicted_iterations += predicted.cycle().total_iterations;
      unpredicted_iterations += unpredicted.cycle().total_iterations;
    }
  }
  // 192 against 248 when this was written.
  EXPECT_LT(predicted_iterations, unpredicted_iterations * 9 / 10)
      << predicted_iterations << " vs " << unpredicted_iterations;
}

// A step too large to vouch for falls back to the walk from the assembly,
// and gives the fresh value exactly.
TEST(Objective, AFarStepFallsBackToTheFreshCycle) {
  TiedFixture f;
  CycleObjective fresh(f.job.space, f.fresh_options(), f.theta);
  CycleObjective reused(f.job.space, ObjectiveOptions::from_loop(f.job.loop), f.theta);
  Eigen::VectorXd far = f.x0();
  far[0] = 4.5;       // a1 from 2.1
  far[4] = rad(120);  // alpha3 from 25 deg
  ASSERT_TRUE(reused.evaluate(f.x0(), nullptr).ok);
  const ObjectiveValue b = reused.evaluate(far, nullptr);
  const ObjectiveValue a = fresh.evaluate(far, nullptr);
  ASSERT_TRUE(a.ok && b.ok);
  EXPECT_EQ(b.E_mean, a.E_mean);
  EXPECT_EQ(reused.cycle().total_iterations, fresh.cycle().total_iterations);
}

// A ceiling on the steered objective: below a point's value the evaluation
// is given up with a lower bound of it that exceeds the ceiling (against the
// same point evaluated whole by a second objective), above it the evaluation
// is the whole one. An abandoned evaluation is not the next one's nearby
// cycle: the point evaluated again gives its value as before. Both measures.
TEST(Objective, AnEvaluationAboveItsCeilingIsAbandonedWithALowerBound) {
  TiedFixture f;
  for (const CycleMeasure measure : {CycleMeasure::mean, CycleMeasure::max}) {
    ObjectiveOptions options = ObjectiveOptions::from_loop(f.job.loop);
    options.measure = measure;
    options.deflation.push_back({"twist gap", twist_gap});
    options.nontrivial = true;
    options.min_travel = rad(60);  // a travel factor well above 1
    CycleObjective whole(f.job.space, options, f.theta);
    CycleObjective bounded(f.job.space, options, f.theta);
    const Eigen::VectorXd direction = f.path_direction();
    const Eigen::VectorXd x1 = f.x0() + 0.01 * direction;
    Eigen::VectorXd r;
    const ObjectiveValue at_x0 = whole.evaluate_residuals(f.x0(), r, nullptr);
    const ObjectiveValue at_x1 = whole.evaluate_residuals(x1, r, nullptr);
    const Eigen::Index rows = r.size();
    ASSERT_TRUE(at_x0.ok && at_x1.ok);
    ASSERT_GT(rows, 0);
    ASSERT_GT(at_x1.steering_factor, 1.5);
    ASSERT_TRUE(bounded.evaluate_residuals(f.x0(), r, nullptr).ok);

    const ObjectiveValue above = bounded.evaluate_residuals(x1, r, nullptr, 2.0 * at_x1.value);
    ASSERT_TRUE(above.ok);
    EXPECT_FALSE(above.abandoned);
    EXPECT_NEAR(above.value, at_x1.value, 1e-10 * at_x1.value);
    EXPECT_EQ(r.size(), rows);  // the residuals of a whole evaluation

    for (const double fraction : {0.05, 0.3}) {
      const double ceiling = fraction * at_x1.value;
      const ObjectiveValue given_up = bounded.evaluate_residuals(x1, r, nullptr, ceiling);
      EXPECT_FALSE(given_up.ok) << fraction;
      EXPECT_TRUE(given_up.abandoned) << fraction;
      EXPECT_GT(given_up.value, ceiling) << fraction;
      EXPECT_LE(given_up.value, at_x1.value * (1 + 1e-9)) << fraction;
      EXPECT_EQ(r.size(), 0) << fraction;
      EXPECT_FALSE(bounded.last_ok()) << fraction;
    }
    // The next evaluation starts from the whole cycle at x1 evaluated above,
    // not from an abandoned one.
    const ObjectiveValue again = bounded.evaluate_residuals(x1, r, nullptr);
    ASSERT_TRUE(again.ok);
    EXPECT_NEAR(again.value, at_x1.value, 1e-10 * at_x1.value);
  }
}

// A trial evaluated under a ceiling keeps the deflation's gradient it
// computed for the bound: the Jacobian the search then asks for at that
// point is the one a whole evaluation there gives, to the last bit (both
// cycles walked afresh from the assembly), and agrees with central
// differences of the residuals.
TEST(Objective, AJacobianAfterACeilingIsTheWholeEvaluationsJacobian) {
  TiedFixture f;
  ObjectiveOptions options = strongly_steered(f);
  options.reuse_nearby_cycle = false;
  CycleObjective whole(f.job.space, options, f.theta);
  CycleObjective bounded(f.job.space, options, f.theta);
  const Eigen::VectorXd x1 = f.x0() + 0.01 * f.path_direction();
  Eigen::VectorXd r_whole, r_bounded;
  Eigen::MatrixXd J_whole, J_bounded;
  const ObjectiveValue a = whole.evaluate_residuals(x1, r_whole, &J_whole);
  const ObjectiveValue b = bounded.evaluate_residuals(x1, r_bounded, &J_bounded, 10.0 * a.value);
  ASSERT_TRUE(a.ok && b.ok);
  ASSERT_GT(a.steering_factor, 1.5);
  EXPECT_EQ(a.value, b.value);
  EXPECT_EQ(r_whole, r_bounded);
  EXPECT_EQ(J_whole, J_bounded);
  // And in the search's order of calls: values under a ceiling at another
  // point and then at x1, then the Jacobian on its own.
  ASSERT_TRUE(bounded.evaluate_residuals(f.x0(), r_bounded, nullptr, 10.0 * a.value).ok);
  ASSERT_TRUE(bounded.evaluate_residuals(x1, r_bounded, nullptr, 10.0 * a.value).ok);
  bounded.residual_jacobian(J_bounded);
  EXPECT_EQ(J_whole, J_bounded);
  EXPECT_GT(J_whole.cwiseAbs().maxCoeff(), 0.0);
}

TEST(Objective, DeflationLiftsTheZerosOfTheDeflatedFamilyOnly) {
  // The paper's Bennett loop is a zero; deflating a distance that vanishes
  // there makes it a non-zero, deflating one that does not leaves it a zero.
  const Job job = parse_job(testing::kBennettSpaceJob, "bennett.toml");
  Eigen::VectorXd x(4);
  x << 2.0, 4.0, rad(30), rad(90);
  const JointVector theta = job.space.initial_angles(Eigen::VectorXd());
  const FamilyDistance on_family = [](const LoopGeometry& g, GeometryVector*) {
    return std::abs(g.a[1] * std::sin(g.alpha[0]) - g.a[0] * std::sin(g.alpha[1]));
  };
  const FamilyDistance elsewhere = [](const LoopGeometry&, GeometryVector*) { return 0.7; };
  ObjectiveOptions plain = ObjectiveOptions::from_loop(job.loop);
  CycleObjective zero(job.space, plain, theta);
  EXPECT_LT(zero.evaluate(x, nullptr).value, 1e-20);
  ObjectiveOptions deflated = plain;
  deflated.deflation.push_back({"on", on_family});
  CycleObjective lifted(job.space, deflated, theta);
  // E ~ dist^2 near the family and the factor ~ dist^-2: a point 1e-4 off
  // the family keeps a value of order one, where plain E is ~1e-9.
  Eigen::VectorXd off = x;
  off[0] += 1e-4;
  const ObjectiveValue near = lifted.evaluate(off, nullptr);
  EXPECT_LT(near.E_mean, 1e-7);
  EXPECT_GT(near.value, 1e-3);
  ObjectiveOptions other = plain;
  other.deflation.push_back({"elsewhere", elsewhere});
  CycleObjective kept(job.space, other, theta);
  EXPECT_LT(kept.evaluate(x, nullptr).value, 1e-20);
}

TEST(Objective, JointTravelUnwrapsAcrossTheCut) {
  CycleSummary cycle;
  const double angles[] = {3.0, 3.1, -3.1, -3.0, 3.1};  // crosses +-pi twice
  for (double a : angles) {
    CycleSample s;
    s.state.theta = JointVector::Constant(4, a);
    cycle.samples.push_back(s);
  }
  const std::vector<JointTravel> travel = joint_travel(cycle, 4);
  // Unwrapped: 3.0, 3.1, 3.1832, 3.2832, 3.1 -> max - min = 0.2832.
  EXPECT_NEAR(travel[1].travel, 2 * 3.14159265358979323846 - 6.0, 1e-12);
  EXPECT_EQ(travel[1].argmax, 3);
  EXPECT_EQ(travel[1].argmin, 0);
}

}  // namespace
}  // namespace loopfarm
