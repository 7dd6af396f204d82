// The paper's Table 1 search (jobs/paper-table1.toml): L1 = a1 in [1.96,
// 2.05], L2 = a2 in [3.96, 4.05], both twists in [0, 180] deg, opposite links
// tied, R = 0, started at theta1 = 120 deg, theta2 = 90 deg. The zeros it
// finds must be Bennett loops; they form a family, not one point; the
// paper's (2, 4, 30, 90) lies on it; and the paper's pose pins that point.
#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "loopfarm/core/loop.hpp"
#include "loopfarm/search/job.hpp"
#include "loopfarm/search/start.hpp"
#include "test_support.hpp"

namespace loopfarm {
namespace {

using testing::deg;
using testing::rad;

constexpr double kPi = 3.14159265358979323846;

constexpr int kStarts = 16;

const Job& table1_job() {
  static const Job job = read_job_file(std::string(LOOPFARM_SOURCE_DIR) + "/jobs/paper-table1.toml");
  return job;
}

// Closed-form Bennett conditions (paper eqs. 1 and 3), independent of the
// elastic model and of the classifier.
double asymmetric_condition(const LoopGeometry& g) {
  return g.a[1] * std::sin(g.alpha[0]) - g.a[0] * std::sin(g.alpha[1]);
}
double line_symmetric_condition(const LoopGeometry& g) {
  return g.a[1] * std::sin(g.alpha[0]) + g.a[0] * std::sin(g.alpha[1]);
}

TEST(PaperTable1, JobEncodesThePapersScopes) {
  const Job& job = table1_job();
  const ParameterSpace& s = job.space;
  EXPECT_EQ(job.loop.joints, 4);
  EXPECT_EQ(s.free_count(), 4);  // a1, a2, alpha1, alpha2
  EXPECT_DOUBLE_EQ(s.lower_bounds()[0], 1.96);
  EXPECT_DOUBLE_EQ(s.upper_bounds()[0], 2.05);
  EXPECT_DOUBLE_EQ(s.lower_bounds()[1], 3.96);
  EXPECT_DOUBLE_EQ(s.upper_bounds()[1], 4.05);
  EXPECT_NEAR(s.upper_bounds()[2], rad(180), 1e-15);
  const JointVector theta = s.initial_angles(Eigen::VectorXd());
  EXPECT_NEAR(theta[0], rad(120), 1e-15);
  EXPECT_NEAR(theta[1], rad(90), 1e-15);
}

TEST(PaperTable1, EveryZeroIsABennettLoopAndTheZerosFormAFamily) {
  const Job& job = table1_job();
  std::vector<StartSummary> zeros;
  for (int index = 0; index < kStarts; ++index) {
    const StartSummary s = run_start(job, static_cast<std::uint64_t>(index));
    if (!s.zero) continue;
    const LoopGeometry& g = s.final_geometry;
    // Ties and R = 0 hold by construction; the condition that is found:
    const double condition = std::min(std::abs(asymmetric_condition(g)), std::abs(line_symmetric_condition(g)));
    EXPECT_LT(condition, 1e-9) << "start " << index;
    // A Bennett loop, or its degenerate planar member (a parallelogram, both
    // twists 0 or 180 deg), which satisfies the same conditions.
    const Family family = s.candidate.classification.family;
    EXPECT_TRUE(family == Family::bennett || family == Family::planar) << "start " << index << " " << to_string(family);
    if (family == Family::planar) {
      EXPECT_LT(std::abs(std::sin(g.alpha[0])) + std::abs(std::sin(g.alpha[1])), 1e-8) << "start " << index;
    }
    EXPECT_TRUE(s.candidate.verification.verified) << "start " << index;
    EXPECT_TRUE(s.candidate.verification.full_turn) << "start " << index;
    // The Bennett family inside these 4 free parameters has dimension 3.
    // Its planar member, the parallelogram, is where the Bennett family meets
    // the planar one and the zero set is no manifold: there the count is that
    // of the branches the final cycle's samples lie on, 3 where they all lie
    // on the one the Bennett motions continue and 2 where the cycle changes
    // branch at a change point (docs/guide/local-dimension.md, Limits; start 1,
    // whose cycle the search followed from nearby geometries, since the
    // continuation's midpoints are solved to CycleOptions::stepping_tolerance).
    if (family == Family::planar) {
      EXPECT_GE(s.candidate.local_dimension.dimension, 2) << "start " << index;
      EXPECT_LE(s.candidate.local_dimension.dimension, 3) << "start " << index;
    } else {
      EXPECT_EQ(s.candidate.local_dimension.dimension, 3) << "start " << index;
    }
    zeros.push_back(s);
    if (family == Family::planar) continue;  // eqs. (2a), (4a) divide by sin((alpha2 -+ alpha1)/2)
    // The assembled pose obeys the closed-form pose equation (2a) or (4a).
    const double t = std::tan(s.final_angles[0] / 2) * std::tan(s.final_angles[1] / 2);
    const double a1 = g.alpha[0], a2 = g.alpha[1];
    const double asym = std::sin((a2 + a1) / 2) / std::sin((a2 - a1) / 2);
    const double line = std::cos((a2 + a1) / 2) / std::cos((a2 - a1) / 2);
    EXPECT_LT(std::min(std::abs(t - asym), std::abs(t - line)), 1e-7 * std::max(1.0, std::abs(t))) << "start " << index;
  }
  // Gauss-Newton from the paper's scopes reaches zero from most starts.
  EXPECT_GE(static_cast<int>(zeros.size()), kStarts / 2);
  // A family, not one point: the twists found spread over many degrees.
  double lo = 1e9, hi = -1e9;
  for (const StartSummary& s : zeros) {
    lo = std::min(lo, deg(s.final_geometry.alpha[0]));
    hi = std::max(hi, deg(s.final_geometry.alpha[0]));
  }
  EXPECT_GT(hi - lo, 10.0);
}

TEST(PaperTable1, ThePapersPointIsOnTheFamilyAndThePosePinsIt) {
  // (2, 4, 30, 90) is a zero of the same objective.
  const Job& job = table1_job();
  CycleObjective objective(job.space, ObjectiveOptions::from_loop(job.loop),
                           job.space.initial_angles(Eigen::VectorXd()));
  Eigen::VectorXd paper(4);
  paper << 2.0, 4.0, rad(30), rad(90);
  const ObjectiveValue v = objective.evaluate(paper, nullptr);
  ASSERT_TRUE(v.ok);
  EXPECT_LT(v.E_max, 1e-20);
  // With the lengths at their nominal 2 and 4 the family is the curve
  // sin(alpha2) = 2 sin(alpha1) (alpha1 <= 30 deg, two branches of alpha2);
  // the paper's pose (theta1, theta2) = (120, 90) deg with the Bennett angles
  // (-120, -90) for joints 3 and 4 closes the loop at one point of it only,
  // (30, 90) deg. The library's closure residual, along both branches:
  JointVector pose(4);
  pose << rad(120), rad(90), rad(-120), rad(-90);
  for (double alpha1_deg : {10.0, 20.0, 25.0, 28.0, 29.5, 30.0}) {
    const double alpha1 = rad(alpha1_deg);
    // At 30 deg exactly 90 (2 sin(alpha1) rounds just below 1, whose arcsine
    // is 1e-6 deg off).
    const double principal = alpha1_deg == 30.0 ? kPi / 2 : std::asin(2.0 * std::sin(alpha1));
    for (double alpha2 : {principal, kPi - principal}) {
      const LoopGeometry g = LoopGeometry::from_degrees(
          std::vector<double>{2, 4, 2, 4}, std::vector<double>{alpha1_deg, deg(alpha2), alpha1_deg, deg(alpha2)},
          std::vector<double>{0, 0, 0, 0});
      const double residual = closure_residual(g, pose).cwiseAbs().maxCoeff();
      if (alpha1_deg == 30.0) {
        EXPECT_LT(residual, 1e-12) << deg(alpha2);
      } else {
        EXPECT_GT(residual, 1e-3) << alpha1_deg << " " << deg(alpha2);
      }
    }
  }
}

}  // namespace
}  // namespace loopfarm
