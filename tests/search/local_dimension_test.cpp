#include "loopfarm/search/local_dimension.hpp"

#include <cmath>
#include <limits>
#include <utility>
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

// dr/d(a, alpha, d) of a movable loop's cycle, every parameter free.
Eigen::MatrixXd cycle_jacobian(const LoopGeometry& g, const JointVector* start, int samples = 24) {
  const LoopModel model(g);
  EquilibriumWorkspace ws(model);
  const EquilibriumSummary assembled = start ? assemble_from_angles(model, ws, *start) : assemble(model, ws, 0.0);
  EXPECT_EQ(assembled.status, SolveStatus::converged);
  CycleOptions options;
  options.samples = samples;
  CycleSummary cycle;
  cycle_energy(model, ws, assembled.state.theta[0], assembled.state, options, cycle);
  EXPECT_LT(cycle.E_max, 1e-20);  // a zero: the Jacobian's null space is the zero set's tangent
  return cycle_deformation_jacobian(model, ws, cycle);
}

// Dimensionless for the rank: length columns (a, d) times L.
Eigen::MatrixXd dimensionless(const Eigen::MatrixXd& J, const LoopGeometry& g) {
  std::vector<bool> is_length(12, true);
  for (int i = 4; i < 8; ++i) is_length[static_cast<size_t>(i)] = false;
  return dimensionless_columns(J, is_length, length_scale(g));
}

// Null space of a condition Jacobian C (rows: conditions, columns: 3n parameters).
Eigen::MatrixXd null_space(const Eigen::MatrixXd& conditions) {
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(conditions, Eigen::ComputeFullV);
  int rank = 0;
  for (int i = 0; i < svd.singularValues().size(); ++i) rank += svd.singularValues()[i] > 1e-10;
  return svd.matrixV().rightCols(conditions.cols() - rank);
}

// The second, independent method: the closed-form family's conditions. Their
// null space is the family's tangent space; the cycle Jacobian must vanish on
// it, and its rank must equal the number of independent conditions.
void expect_matches_family(const Eigen::MatrixXd& J, const LoopGeometry& g, const Eigen::MatrixXd& conditions,
                           int known_dimension) {
  const LocalDimension dim = local_dimension(dimensionless(J, g));
  EXPECT_EQ(dim.dimension, known_dimension) << dim.singular_values.transpose();
  const Eigen::MatrixXd tangent = null_space(conditions);
  ASSERT_EQ(tangent.cols(), known_dimension);
  EXPECT_LT((J * tangent).cwiseAbs().maxCoeff(), 1e-8 * J.cwiseAbs().maxCoeff());
  // A clear gap between the null-space and the other singular values.
  EXPECT_LT(dim.singular_values[dim.rank], 1e-10 * dim.singular_values[0]);
  EXPECT_GT(dim.singular_values[dim.rank - 1], 1e-4 * dim.singular_values[0]);
}

TEST(LocalDimension, BennettFamilyHasThreeParameters) {
  // a1 = a3, a2 = a4, alpha1 = alpha3, alpha2 = alpha4, d = 0 and
  // a2 sin(alpha1) = a1 sin(alpha2): 9 conditions on 12 parameters.
  const LoopGeometry g = paper_bennett_loop();
  const JointVector start = bennett_angles(g, rad(120));
  const int n = 4;
  Eigen::MatrixXd C = Eigen::MatrixXd::Zero(9, 3 * n);
  C(0, 0) = 1, C(0, 2) = -1;
  C(1, 1) = 1, C(1, 3) = -1;
  C(2, n + 0) = 1, C(2, n + 2) = -1;
  C(3, n + 1) = 1, C(3, n + 3) = -1;
  for (int i = 0; i < 4; ++i) C(4 + i, 2 * n + i) = 1;
  C(8, 0) = -std::sin(g.alpha[1]);
  C(8, 1) = std::sin(g.alpha[0]);
  C(8, n + 0) = g.a[1] * std::cos(g.alpha[0]);
  C(8, n + 1) = -g.a[0] * std::cos(g.alpha[1]);
  expect_matches_family(cycle_jacobian(g, &start), g, C, 3);
}

TEST(LocalDimension, PlanarCrankFamilyHasSevenParameters) {
  // Every sin(alpha_i) = 0 and the offsets close along the axes (their sum,
  // all twists being 0): 5 conditions; the four lengths and three offsets free.
  const LoopGeometry g = planar_four_bar(1.0, 3.0, 2.5, 3.5);
  const int n = 4;
  Eigen::MatrixXd C = Eigen::MatrixXd::Zero(5, 3 * n);
  for (int i = 0; i < 4; ++i) C(i, n + i) = 1;
  for (int i = 0; i < 4; ++i) C(4, 2 * n + i) = 1;
  expect_matches_family(cycle_jacobian(g, nullptr), g, C, 7);
}

TEST(LocalDimension, CoaxialTrivialFamilyHasFiveParameters) {
  // Axes 1 and 3 coincide: a1 = a2, alpha1 = alpha2, a3 = a4, alpha3 =
  // alpha4, d2 = d4 = 0, d1 = -d3 (7 conditions). With theta2 = theta4 = pi
  // links 2 and 4 fold back over links 1 and 3, and the loop turns about the
  // shared axis with theta3 = -theta1.
  const int n = 4;
  LoopGeometry g =
      LoopGeometry::from_degrees(std::vector<double>{1.5, 1.5, 2.5, 2.5}, std::vector<double>{40, 40, 70, 70},
                                 std::vector<double>{0.3, 0.0, -0.3, 0.0});
  JointVector start(4);
  start << rad(30), rad(180), rad(-30), rad(180);
  Eigen::MatrixXd C = Eigen::MatrixXd::Zero(7, 3 * n);
  C(0, 0) = 1, C(0, 1) = -1;
  C(1, 2) = 1, C(1, 3) = -1;
  C(2, n + 0) = 1, C(2, n + 1) = -1;
  C(3, n + 2) = 1, C(3, n + 3) = -1;
  C(4, 2 * n + 1) = 1;
  C(5, 2 * n + 3) = 1;
  C(6, 2 * n + 0) = 1, C(6, 2 * n + 2) = 1;
  expect_matches_family(cycle_jacobian(g, &start), g, C, 5);
}

TEST(LocalDimension, SphericalLoopsFillTheSpaceOfTwists) {
  // In a spherical search space (a = d = 0 fixed, twists free) every Grashof
  // crank moves: the zero set is open, dimension 4 of 4. (In the full space
  // the length scale of an all-zero-length loop is not differentiable, so the
  // spherical family is measured in its own space; docs/guide/local-dimension.md.)
  const LoopGeometry g = spherical_four_bar(rad(20), rad(70), rad(60), rad(80));
  const Eigen::MatrixXd J = dimensionless(cycle_jacobian(g, nullptr), g).middleCols(4, 4);
  const LocalDimension dim = local_dimension(J);
  EXPECT_EQ(dim.dimension, 4);
  EXPECT_EQ(dim.rank, 0);
}

TEST(LocalDimension, RigidLoopKeepsOnlyTheScaleDirection) {
  // Not a zero, but the rank count itself: the energy is dimensionless, so
  // scaling every length (direction (a, 0, d)) never changes r; a generic
  // loop's cycle Jacobian has no other null direction.
  const LoopGeometry g = random_loop(4, 3);
  const LoopModel model(g);
  EquilibriumWorkspace ws(model);
  CycleSummary cycle;
  CycleOptions options;
  options.samples = 24;
  cycle_energy(model, ws, 0.0, assemble(model, ws, 0.0).state, options, cycle);
  const LocalDimension dim = local_dimension(dimensionless(cycle_deformation_jacobian(model, ws, cycle), g));
  EXPECT_EQ(dim.parameters, 12);
  EXPECT_EQ(dim.dimension, 1) << dim.singular_values.transpose();
  Eigen::VectorXd scale = Eigen::VectorXd::Zero(12);
  scale << g.a, Eigen::VectorXd::Zero(4), g.d;
  const Eigen::MatrixXd J = cycle_deformation_jacobian(model, ws, cycle);
  EXPECT_LT((J * scale).cwiseAbs().maxCoeff(), 1e-9 * J.cwiseAbs().maxCoeff());
}

// A Jacobian with a NaN or an infinite entry (a cycle sample that failed)
// has no rank to read: the dimension is unknown (-1), not the full one a NaN
// compared with the threshold would give, wherever the entry lies. A finite
// Jacobian of the same shape keeps its count.
TEST(LocalDimension, AJacobianWithAnEntryThatIsNotFiniteHasAnUnknownDimension) {
  const LoopGeometry g = paper_bennett_loop();
  const JointVector start = bennett_angles(g, rad(120));
  const Eigen::MatrixXd J = dimensionless(cycle_jacobian(g, &start), g);
  ASSERT_EQ(local_dimension(J).dimension, 3);
  for (double bad : {std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity(),
                     -std::numeric_limits<double>::infinity()}) {
    for (const auto& [row, col] : {std::pair{0, 0}, std::pair{5, 7}, std::pair{-1, 11}}) {
      Eigen::MatrixXd broken = J;
      broken(row < 0 ? broken.rows() - 1 : row, col) = bad;
      const LocalDimension dim = local_dimension(broken);
      EXPECT_EQ(dim.parameters, 12);
      EXPECT_EQ(dim.rank, -1) << bad << " at " << row << ", " << col;
      EXPECT_EQ(dim.dimension, -1) << bad << " at " << row << ", " << col;
      EXPECT_FALSE(dim.known());
      EXPECT_EQ(dim.singular_values.size(), 0);
    }
  }
  EXPECT_TRUE(local_dimension(J).known());
}

}  // namespace
}  // namespace loopfarm
