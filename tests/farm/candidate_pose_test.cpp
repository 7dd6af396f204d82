// Joint axes of a stored linkage at a closed pose, against constructions that
// do not use the frames they come from: the distance and angle of
// consecutive axis lines from their common normal (a_i and alpha_i), the
// offsets d_i between the feet of the normals, the planar loop's points as a
// polygon with the link lengths as sides, and the pose's input angle.
#include "loopfarm/farm/candidate_pose.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

#include <gtest/gtest.h>

namespace loopfarm {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = kPi / 180.0;

LoopGeometry geometry_deg(std::vector<double> a, std::vector<double> alpha_deg, std::vector<double> d) {
  return LoopGeometry::from_degrees(a, alpha_deg, d);
}

// The common normal of two lines p + s u: its feet on each line and its length.
struct CommonNormal {
  Vector3 foot1, foot2;
  double length = 0.0;
};

CommonNormal common_normal(const Axis& l1, const Axis& l2) {
  const Vector3 w = l1.point - l2.point;
  const double b = l1.direction.dot(l2.direction);
  const double d1 = l1.direction.dot(w);
  const double d2 = l2.direction.dot(w);
  const double denominator = 1.0 - b * b;
  CommonNormal n;
  if (denominator < 1e-12) {
    // Parallel lines: any normal; the one through l2's point.
    n.foot2 = l2.point;
    n.foot1 = l1.point + l1.direction * l1.direction.dot(l2.point - l1.point);
  } else {
    const double s = (b * d2 - d1) / denominator;
    const double t = (d2 - b * d1) / denominator;
    n.foot1 = l1.point + s * l1.direction;
    n.foot2 = l2.point + t * l2.direction;
  }
  n.length = (n.foot2 - n.foot1).norm();
  return n;
}

// Every axis a unit vector; consecutive lines (the last to the first too) a_k
// apart at the twist alpha_k (in [0, pi]), with the normal's foot on line k+1
// at that line's point and d_k between the feet on line k.
void expect_lines_of(const LoopGeometry& g, const std::vector<Axis>& axes, double tolerance) {
  const int n = g.joints();
  ASSERT_EQ(static_cast<int>(axes.size()), n);
  for (int k = 0; k < n; ++k) {
    const Axis& here = axes[static_cast<size_t>(k)];
    const Axis& next = axes[static_cast<size_t>((k + 1) % n)];
    EXPECT_NEAR(here.direction.norm(), 1.0, 1e-12) << "axis " << k + 1;
    const double angle = std::acos(std::clamp(here.direction.dot(next.direction), -1.0, 1.0));
    EXPECT_NEAR(angle, std::abs(g.alpha[k]), tolerance) << "twist between axes " << k + 1 << " and " << k + 2;
    const CommonNormal normal = common_normal(here, next);
    EXPECT_NEAR(normal.length, g.a[k], tolerance) << "distance between axes " << k + 1 << " and " << k + 2;
    if (std::sin(g.alpha[k]) > 0.1) {
      EXPECT_NEAR((normal.foot2 - next.point).norm(), 0.0, tolerance) << "foot on axis " << k + 2;
      EXPECT_NEAR((normal.foot1 - here.point).dot(here.direction), g.d[k], tolerance) << "offset d" << k + 1;
    }
  }
}

TEST(CandidatePose, AtZeroAnglesTheFirstLinkIsAlongXAndTwistedAboutIt) {
  const LoopGeometry g = geometry_deg({2, 3, 4, 5}, {30, 0, 0, 0}, {0.5, 0, 0, 0});
  const std::vector<Axis> axes = joint_axes(g, JointVector::Zero(4));
  EXPECT_TRUE(axes[0].point.isZero(0.0));
  EXPECT_TRUE(axes[0].direction.isApprox(Vector3(0, 0, 1)));
  EXPECT_TRUE(axes[1].point.isApprox(Vector3(2, 0, 0.5)));
  EXPECT_TRUE(axes[1].direction.isApprox(Vector3(0, -std::sin(30 * kDeg), std::cos(30 * kDeg))));
}

TEST(CandidatePose, PlanarFourBarAxesAreParallelToZThroughAPolygonOfTheLinkLengths) {
  // Grashof, shortest link next to joint 1: joint 1 turns fully.
  const LoopGeometry g = geometry_deg({1, 3, 2.5, 3.2}, {0, 0, 0, 0}, {0, 0, 0, 0});
  const std::optional<CandidatePose> pose = candidate_pose(g);
  ASSERT_TRUE(pose.has_value());
  EXPECT_TRUE(pose->full_turn);
  EXPECT_NEAR(pose->input_deg, 0.0, 1e-12);
  EXPECT_NEAR(pose->theta[0], 0.0, 1e-12);
  EXPECT_LT(pose->closure_residual, 1e-9);
  for (int k = 0; k < 4; ++k) {
    const Axis& axis = pose->axes[static_cast<size_t>(k)];
    EXPECT_NEAR(axis.direction.z(), 1.0, 1e-12) << "axis " << k + 1;
    EXPECT_NEAR(axis.point.z(), 0.0, 1e-12) << "axis " << k + 1;
    const Axis& next = pose->axes[static_cast<size_t>((k + 1) % 4)];
    EXPECT_NEAR((next.point - axis.point).norm(), g.a[k], 1e-9) << "side " << k + 1;
  }
  // Joint 1 at 0: link 1 leaves the origin along x.
  EXPECT_NEAR(pose->axes[1].point.x(), 1.0, 1e-12);
  EXPECT_NEAR(pose->axes[1].point.y(), 0.0, 1e-12);
  expect_lines_of(g, pose->axes, 1e-9);

  // Another input angle: joint 1 there, link 1 turned with it.
  const std::optional<CandidatePose> turned = candidate_pose(g, 30.0);
  ASSERT_TRUE(turned.has_value());
  EXPECT_NEAR(turned->input_deg, 30.0, 1e-9);
  EXPECT_NEAR(turned->axes[1].point.x(), std::cos(30 * kDeg), 1e-9);
  EXPECT_NEAR(turned->axes[1].point.y(), std::sin(30 * kDeg), 1e-9);
  expect_lines_of(g, turned->axes, 1e-9);
}

TEST(CandidatePose, BennettAxesAreATwistApartAndALinkLengthApartAlongTheirCommonNormal) {
  const double s = std::sqrt(10.0);  // the length scale of a = 2, 4, 2, 4: stored canonically
  const LoopGeometry g = geometry_deg({2 / s, 4 / s, 2 / s, 4 / s}, {30, 90, 30, 90}, {0, 0, 0, 0});
  for (const double input : {0.0, 75.0, -140.0}) {
    const std::optional<CandidatePose> pose = candidate_pose(g, input);
    ASSERT_TRUE(pose.has_value()) << input;
    EXPECT_NEAR(pose->input_deg, input, 1e-9);
    EXPECT_LT(pose->closure_residual, 1e-9);
    expect_lines_of(g, pose->axes, 1e-8);
    // Not planar: the axes are not all parallel.
    EXPECT_LT(std::abs(pose->axes[0].direction.dot(pose->axes[1].direction)), 0.9);
  }
}

TEST(CandidatePose, OffsetsLieAlongTheAxesBetweenTheFeetOfTheNormals) {
  // An open chain at arbitrary angles: offsets and lengths hold link by link.
  const LoopGeometry g = geometry_deg({1, 2, 1.5, 0.7}, {40, 70, 20, 100}, {0.3, -0.5, 0.2, 0.9});
  JointVector theta(4);
  theta << 0.3, -1.1, 2.0, 0.4;
  const std::vector<Axis> axes = joint_axes(g, theta);
  // Links 1 to 3: the fourth returns to the base only where the loop closes.
  for (int k = 0; k < 3; ++k) {
    const CommonNormal normal = common_normal(axes[static_cast<size_t>(k)], axes[static_cast<size_t>(k + 1)]);
    EXPECT_NEAR(normal.length, g.a[k], 1e-12);
    EXPECT_NEAR((normal.foot2 - axes[static_cast<size_t>(k + 1)].point).norm(), 0.0, 1e-12);
    EXPECT_NEAR((normal.foot1 - axes[static_cast<size_t>(k)].point).dot(axes[static_cast<size_t>(k)].direction), g.d[k],
                1e-12);
  }
}

TEST(CandidatePose, ARigidLoopHasNoPoseAndAGeometryThatIsNoLoopIsRefused) {
  EXPECT_FALSE(candidate_pose(geometry_deg({1, 2, 3, 2.5}, {20, 70, 40, 110}, {0.1, -0.3, 0.2, 0})).has_value());
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(candidate_pose(geometry_deg({1, nan, 1, 2}, {0, 0, 0, 0}, {0, 0, 0, 0})), std::invalid_argument);
  EXPECT_THROW(candidate_pose(geometry_deg({1, 2, 1}, {0, 0, 0}, {0, 0, 0})), std::invalid_argument);
}

TEST(CandidatePose, CandidateGeometryConvertsTwistsToRadians) {
  CandidateRow row;
  row.joints = 4;
  row.a = {0.5, 1, 0.5, 1};
  row.alpha_deg = {30, 90, 30, 90};
  row.d = {0, 0.25, 0, 0};
  const LoopGeometry g = candidate_geometry(row);
  ASSERT_EQ(g.joints(), 4);
  EXPECT_DOUBLE_EQ(g.alpha[1], kPi / 2);
  EXPECT_DOUBLE_EQ(g.d[1], 0.25);
  EXPECT_DOUBLE_EQ(g.a[3], 1.0);
}

}  // namespace
}  // namespace loopfarm
