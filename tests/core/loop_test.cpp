#include "loopfarm/core/loop.hpp"

#include <array>
#include <cmath>
#include <stdexcept>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "loopfarm/core/sample_loops.hpp"
#include "test_support.hpp"

namespace loopfarm {
namespace {

using testing::rad;
using testing::relative_error;

// Perturbs chain element `e` (theta, d, a or alpha of one joint) by h.
void perturb(LoopGeometry& g, JointVector& theta, int e, double h) {
  const int joint = e / kElementsPerJoint;
  switch (static_cast<ChainParameter>(e % kElementsPerJoint)) {
    case ChainParameter::theta:
      theta[joint] += h;
      break;
    case ChainParameter::d:
      g.d[joint] += h;
      break;
    case ChainParameter::a:
      g.a[joint] += h;
      break;
    case ChainParameter::alpha:
      g.alpha[joint] += h;
      break;
  }
}

Vector6 residual_at(LoopGeometry g, JointVector theta, int e, double h) {
  perturb(g, theta, e, h);
  return closure_residual(g, theta);
}

// Random poses whose residual rotation stays away from pi, where the logarithm
// (and so the residual) is discontinuous.
JointVector pose_away_from_log_cut(const LoopGeometry& g, std::uint64_t seed) {
  for (std::uint64_t k = 0;; ++k) {
    JointVector theta = random_angles(g.joints(), seed * 1000 + k);
    if (closure_residual(g, theta).head<3>().norm() < 2.8) return theta;
  }
}

TEST(Loop, JointTransformIsTheDenavitHartenbergProduct) {
  const double theta = 0.3, d = -0.7, a = 1.9, alpha = 2.1;
  Eigen::Isometry3d expected = Eigen::Isometry3d::Identity();
  expected.rotate(Eigen::AngleAxisd(theta, Vector3::UnitZ()));
  expected.translate(Vector3(0, 0, d));
  expected.translate(Vector3(a, 0, 0));
  expected.rotate(Eigen::AngleAxisd(alpha, Vector3::UnitX()));
  EXPECT_LT((joint_transform(theta, d, a, alpha).matrix() - expected.matrix()).cwiseAbs().maxCoeff(), 1e-15);
}

TEST(Loop, ChainProductAgreesWithForwardTransform) {
  for (int n = kMinJoints; n <= kMaxJoints; ++n) {
    const LoopGeometry g = random_loop(n, 7 + n);
    const JointVector theta = random_angles(n, 11 + n);
    ChainKinematics chain;
    compute_chain(g, theta, chain);
    const Eigen::Isometry3d t = forward_transform(g, theta);
    EXPECT_LT((chain.rotation - t.rotation()).cwiseAbs().maxCoeff(), 1e-14) << n;
    EXPECT_LT((chain.position - t.translation()).cwiseAbs().maxCoeff(), 1e-13) << n;
    EXPECT_LT((chain.residual - closure_residual(g, theta)).cwiseAbs().maxCoeff(), 1e-13) << n;
  }
}

TEST(Loop, BennettLoopClosesInBothSetups) {
  const LoopGeometry asym = paper_bennett_loop();
  const LoopGeometry sym = bennett_loop_line_symmetric(2.0, rad(30), rad(90));
  for (double t1 = -170.0; t1 <= 170.0; t1 += 17.0) {
    EXPECT_LT(closure_residual(asym, bennett_angles(asym, rad(t1))).norm(), 1e-13) << t1;
    EXPECT_LT(closure_residual(sym, bennett_angles_line_symmetric(sym, rad(t1))).norm(), 1e-13) << t1;
  }
  // The paper's start: theta1 = 120 deg gives theta2 = 90 deg in both setups.
  EXPECT_NEAR(bennett_angles(asym, rad(120))[1], rad(90), 1e-14);
  EXPECT_NEAR(bennett_angles_line_symmetric(sym, rad(120))[1], rad(90), 1e-14);
}

TEST(Loop, NonBennettLoopDoesNotCloseAtBennettAngles) {
  LoopGeometry g = paper_bennett_loop();
  g.a[0] = 2.1;
  EXPECT_GT(closure_residual(g, bennett_angles(paper_bennett_loop(), rad(120))).norm(), 1e-2);
}

TEST(Loop, ClosureJacobiansMatchCentralDifferences) {
  const double h = 1e-6;
  for (int n = kMinJoints; n <= kMaxJoints; ++n) {
    for (std::uint64_t seed = 1; seed <= 3; ++seed) {
      const LoopGeometry g = random_loop(n, 100 * n + seed);
      const JointVector theta = pose_away_from_log_cut(g, 100 * n + seed);
      ClosureJacobians jac;
      closure_jacobians(g, theta, jac);
      for (int i = 0; i < n; ++i) {
        const auto diff = [&](ChainParameter p) {
          const int e = chain_index(i, p);
          return Vector6((residual_at(g, theta, e, h) - residual_at(g, theta, e, -h)) / (2 * h));
        };
        EXPECT_LT(relative_error(jac.theta.col(i), diff(ChainParameter::theta)), 1e-7) << n << " theta" << i;
        EXPECT_LT(relative_error(jac.d.col(i), diff(ChainParameter::d)), 1e-7) << n << " d" << i;
        EXPECT_LT(relative_error(jac.a.col(i), diff(ChainParameter::a)), 1e-7) << n << " a" << i;
        EXPECT_LT(relative_error(jac.alpha.col(i), diff(ChainParameter::alpha)), 1e-7) << n << " alpha" << i;
      }
    }
  }
}

TEST(Loop, JacobianColumnsAreBaseFrameScrewsAtClosure) {
  // At a closed pose the residual's differential is the identity: a joint's
  // column is (axis direction, point-on-axis x direction) in the base frame.
  const LoopGeometry g = paper_bennett_loop();
  const JointVector theta = bennett_angles(g, rad(120));
  ClosureJacobians jac;
  closure_jacobians(g, theta, jac);
  for (int i = 0; i < 4; ++i) {
    const Eigen::Isometry3d frame = forward_transform(g, theta, i);
    const Vector3 axis = frame.rotation().col(2);
    const Vector3 point = frame.translation();
    EXPECT_LT((jac.theta.col(i).head<3>() - axis).norm(), 1e-12);
    EXPECT_LT((jac.theta.col(i).tail<3>() - point.cross(axis)).norm(), 1e-12);
    EXPECT_LT((jac.d.col(i).tail<3>() - axis).norm(), 1e-12);
    EXPECT_LT(jac.d.col(i).head<3>().norm(), 1e-15);
  }
}

// residual_jacobian is residual_derivative column by column, to the bit
// (residual_derivative itself is checked against differences above), for a
// sparse list of elements in chain order as a solve's unknowns are.
TEST(Loop, ResidualJacobianIsResidualDerivativeColumnByColumn) {
  for (int n : {4, 6, 8}) {
    const LoopGeometry g = random_loop(n, 400 + n);
    ChainKinematics chain;
    compute_chain(g, pose_away_from_log_cut(g, 400 + n), chain);
    std::array<int, kMaxUnknowns> list{};
    int count = 0;
    for (int e = 1; e < kElementsPerJoint * n && count < kMaxUnknowns; e += (e % 3 == 0 ? 2 : 1)) {
      list[static_cast<size_t>(count++)] = e;
    }
    Matrix6U jacobian;
    residual_jacobian(chain, std::span<const int>(list.data(), static_cast<size_t>(count)), jacobian);
    ASSERT_EQ(jacobian.cols(), count);
    for (int u = 0; u < count; ++u) {
      const Vector6 expected = residual_derivative(chain, list[static_cast<size_t>(u)]);
      for (int r = 0; r < 6; ++r) EXPECT_EQ(jacobian(r, u), expected[r]) << "n=" << n << " column " << u;
    }
  }
}

TEST(Loop, ResidualHessianMatchesDifferencesOfTheJacobian) {
  const double h = 1e-6;
  for (int n : {4, 6, 8}) {
    const LoopGeometry g = random_loop(n, 300 + n);
    const JointVector theta = pose_away_from_log_cut(g, 300 + n);
    Vector6 lambda;
    lambda << 0.3, -1.2, 0.7, 2.0, -0.4, 1.1;
    std::array<int, kMaxChain> all{};
    for (int e = 0; e < kElementsPerJoint * n; ++e) all[static_cast<size_t>(e)] = e;
    const std::span<const int> elements(all.data(), static_cast<size_t>(kElementsPerJoint * n));
    ChainKinematics chain;
    compute_chain(g, theta, chain);
    ChainMatrix H;
    residual_hessian(chain, lambda, elements, H);
    for (int k = 0; k < kElementsPerJoint * n; ++k) {
      // Column k of the Hessian: d/ds_k of lambda^T (d residual / d s_l) for all l.
      Eigen::VectorXd plus(kElementsPerJoint * n), minus(kElementsPerJoint * n);
      for (double sign : {+1.0, -1.0}) {
        LoopGeometry gp = g;
        JointVector tp = theta;
        perturb(gp, tp, k, sign * h);
        ChainKinematics cp;
        compute_chain(gp, tp, cp);
        for (int l = 0; l < kElementsPerJoint * n; ++l) {
          (sign > 0 ? plus : minus)[l] = lambda.dot(residual_derivative(cp, l));
        }
      }
      const Eigen::VectorXd fd = (plus - minus) / (2 * h);
      EXPECT_LT(relative_error(H.col(k).head(kElementsPerJoint * n), fd), 1e-7) << "n=" << n << " element " << k;
    }
  }
}

TEST(Loop, ResidualHessianIsExactAtSmallRotations) {
  // Near closure the log uses its series; the Hessian must stay exact there.
  const LoopGeometry g = paper_bennett_loop();
  JointVector theta = bennett_angles(g, rad(120));
  theta[1] += 1e-3;  // a residual rotation of about 1e-3 rad
  const double h = 1e-6;
  Vector6 lambda;
  lambda << 1.0, 2.0, -1.0, 0.5, 0.25, -0.75;
  const std::array<int, 4> elements{1, 3, 4, 6};
  ChainKinematics chain;
  compute_chain(g, theta, chain);
  ChainMatrix H;
  residual_hessian(chain, lambda, elements, H);
  for (size_t i = 0; i < elements.size(); ++i) {
    for (size_t j = 0; j < elements.size(); ++j) {
      double fd = 0.0;
      for (double sign : {+1.0, -1.0}) {
        LoopGeometry gp = g;
        JointVector tp = theta;
        perturb(gp, tp, elements[i], sign * h);
        ChainKinematics cp;
        compute_chain(gp, tp, cp);
        fd += sign * lambda.dot(residual_derivative(cp, elements[j])) / (2 * h);
      }
      EXPECT_NEAR(H(static_cast<int>(i), static_cast<int>(j)), fd, 1e-7 * std::max(1.0, std::abs(fd)));
    }
  }
}

TEST(Loop, RelabelledAndReversedLoopsCloseAtMappedAngles) {
  const LoopGeometry g = paper_bennett_loop();
  const JointVector theta = bennett_angles(g, rad(77));
  for (int shift = 0; shift < 4; ++shift) {
    EXPECT_LT(closure_residual(relabelled(g, shift), relabelled_angles(theta, shift)).norm(), 1e-13) << shift;
  }
  EXPECT_LT(closure_residual(reversed(g), reversed_angles(theta)).norm(), 1e-13);
  // Reversal with offsets, at a pose that does not close (a random 6R loop):
  // the loop product is inverted and conjugated by a rigid transform, which
  // keeps its rotation angle (the displacement changes with the conjugating
  // frame, so only the angle is compared).
  const LoopGeometry r = random_loop(6, 42);
  const JointVector rt = random_angles(6, 42);
  const Vector6 fwd = closure_residual(r, rt);
  const Vector6 back = closure_residual(reversed(r), reversed_angles(rt));
  EXPECT_GT(fwd.head<3>().norm(), 1e-2);
  EXPECT_NEAR(fwd.head<3>().norm(), back.head<3>().norm(), 1e-12);
}

TEST(Loop, AxisFlipLeavesTheLoopProductUnchanged) {
  // At any pose, not only a closed one: flipping axis j > 0 inserts Rx(pi)
  // Rx(-pi) between T_{j-1} and T_j, so the product is the same matrix;
  // flipping axis 0 conjugates it by Rx(pi).
  for (int n : {4, 6, 8}) {
    const LoopGeometry g = random_loop(n, 7 + n);
    const JointVector theta = random_angles(n, 7 + n);
    const Eigen::Matrix4d product = forward_transform(g, theta).matrix();
    for (int j = 0; j < n; ++j) {
      const LoopGeometry f = axis_flipped(g, j);
      const Eigen::Matrix4d flipped = forward_transform(f, axis_flipped_angles(theta, j)).matrix();
      Eigen::Isometry3d rx = Eigen::Isometry3d::Identity();
      rx.rotate(Eigen::AngleAxisd(3.14159265358979323846, Vector3::UnitX()));
      const Eigen::Matrix4d expected =
          j == 0 ? Eigen::Matrix4d(rx.matrix().transpose() * product * rx.matrix()) : product;
      EXPECT_LT((flipped - expected).cwiseAbs().maxCoeff(), 1e-12) << n << " " << j;
      EXPECT_DOUBLE_EQ(f.d[j], -g.d[j]);
      // Flipping twice is the identity (up to the wrap of the twists).
      const LoopGeometry back = axis_flipped(f, j);
      for (int k = 0; k < n; ++k)
        EXPECT_NEAR(std::remainder(back.alpha[k] - g.alpha[k], 2 * 3.14159265358979323846), 0.0, 1e-14);
    }
  }
  // A closed pose stays closed: the Bennett loop with axis 2 flipped.
  const LoopGeometry b = paper_bennett_loop();
  const JointVector theta = bennett_angles(b, rad(50));
  EXPECT_LT(closure_residual(axis_flipped(b, 2), axis_flipped_angles(theta, 2)).norm(), 1e-13);
}

constexpr double kPi = 3.14159265358979323846;

// The lines of the joint axes at a pose: axis k + 1 is the z axis of frame k.
std::vector<std::pair<Vector3, Vector3>> axis_lines(const LoopGeometry& g, const JointVector& theta) {
  std::vector<std::pair<Vector3, Vector3>> out;
  for (int k = 0; k < g.joints(); ++k) {
    const Eigen::Isometry3d frame = forward_transform(g, theta, k);
    out.emplace_back(frame.translation(), frame.linear().col(2));
  }
  return out;
}

// Distance and angle of every pair of axes: what two placements of one
// chain of lines share when the base frame itself moved.
std::vector<double> pair_invariants(const LoopGeometry& g, const JointVector& theta) {
  const auto lines = axis_lines(g, theta);
  std::vector<double> out;
  for (size_t i = 0; i < lines.size(); ++i) {
    for (size_t j = i + 1; j < lines.size(); ++j) {
      const Vector3 u = lines[i].second, v = lines[j].second, w = lines[j].first - lines[i].first;
      const Vector3 n = u.cross(v);
      out.push_back(std::atan2(n.norm(), u.dot(v)));
      out.push_back(n.norm() > 1e-9 ? std::abs(w.dot(n)) / n.norm() : w.cross(u).norm());
    }
  }
  return out;
}

double max_difference(const LoopGeometry& x, const LoopGeometry& y) {
  double m = 0.0;
  for (int k = 0; k < x.joints(); ++k) {
    m = std::max({m, std::abs(x.a[k] - y.a[k]), std::abs(std::remainder(x.alpha[k] - y.alpha[k], 2 * kPi)),
                  std::abs(x.d[k] - y.d[k])});
  }
  return m;
}

TEST(Loop, CentredParallelNormalsSplitEachRunsOffsetAndMoveNoAxis) {
  // Links 0 (parallel) and 3 (antiparallel) of a 6R; the last link is not
  // parallel, so the base frame stays and every axis line must stay.
  LoopGeometry g = random_loop(6, 3);
  g.alpha[0] = 0.0;
  g.alpha[3] = kPi;
  const JointVector theta = random_angles(6, 3);
  LoopGeometry c = centred_parallel_normals(g, 1e-9);
  EXPECT_NEAR(c.d[0], c.d[1], 1e-15);
  EXPECT_NEAR(c.d[3], -c.d[4], 1e-15);
  EXPECT_NEAR(c.d[0] + c.d[1], g.d[0] + g.d[1], 1e-15);
  EXPECT_NEAR(c.d[3] - c.d[4], g.d[3] - g.d[4], 1e-15);
  for (int k : {2, 5}) EXPECT_EQ(c.d[k], g.d[k]) << k;
  EXPECT_TRUE(c.a == g.a && c.alpha == g.alpha);
  EXPECT_GT(std::abs(g.d[0] - g.d[1]), 1e-2);  // the test moves something
  auto before = axis_lines(g, theta), after = axis_lines(c, theta);
  for (size_t k = 0; k < before.size(); ++k) {
    EXPECT_LT((before[k].second - after[k].second).norm(), 1e-14) << k;
    EXPECT_LT((after[k].first - before[k].first).cross(before[k].second).norm(), 1e-14) << k;
  }
  EXPECT_LT((forward_transform(g, theta).matrix() - forward_transform(c, theta).matrix()).cwiseAbs().maxCoeff(), 1e-14);

  // A run of two links (axes 1, 2, 3; the second link antiparallel) in a 7R:
  // three offsets, signed along axis 1, share their sum.
  g = random_loop(7, 4);
  g.alpha[1] = 0.0;
  g.alpha[2] = -kPi;
  c = centred_parallel_normals(g, 1e-9);
  EXPECT_NEAR(c.d[1], c.d[2], 1e-15);
  EXPECT_NEAR(c.d[2], -c.d[3], 1e-15);
  EXPECT_NEAR(c.d[1] + c.d[2] - c.d[3], g.d[1] + g.d[2] - g.d[3], 1e-15);
  before = axis_lines(g, random_angles(7, 4));
  after = axis_lines(c, random_angles(7, 4));
  for (size_t k = 0; k < before.size(); ++k) {
    EXPECT_LT((after[k].first - before[k].first).cross(before[k].second).norm(), 1e-14) << k;
  }

  // A run through the base frame (links 4 and 0 of a 5R): the base frame's
  // normal moves too, so the chain is compared by its pairs of axes.
  g = random_loop(5, 5);
  g.alpha[4] = 0.0;
  g.alpha[0] = 0.0;
  c = centred_parallel_normals(g, 1e-9);
  EXPECT_NEAR(c.d[4], c.d[0], 1e-15);
  EXPECT_NEAR(c.d[0], c.d[1], 1e-15);
  const std::vector<double> pairs_before = pair_invariants(g, random_angles(5, 5));
  const std::vector<double> pairs_after = pair_invariants(c, random_angles(5, 5));
  for (size_t k = 0; k < pairs_before.size(); ++k) EXPECT_NEAR(pairs_before[k], pairs_after[k], 1e-13) << k;

  // Every link parallel (a planar 4R): the signed offsets share their total.
  g = random_loop(4, 6);
  g.alpha = JointVector::Constant(4, 0.0);
  g.alpha[2] = kPi;
  c = centred_parallel_normals(g, 1e-9);
  const double total = g.d[0] + g.d[1] + g.d[2] - g.d[3];
  for (int k = 0; k < 4; ++k) EXPECT_NEAR(c.d[k], (k == 3 ? -1.0 : 1.0) * total / 4, 1e-15) << k;

  // Without parallel axes nothing changes.
  g = random_loop(6, 7);
  c = centred_parallel_normals(g, 1e-9);
  EXPECT_TRUE(c.a == g.a && c.alpha == g.alpha && c.d == g.d);
}

TEST(Loop, CentredParallelNormalsCommuteWithRepresentationsAndRepeat) {
  LoopGeometry g = random_loop(6, 8);
  g.alpha[0] = 0.0;
  g.alpha[5] = kPi;  // a run through the base frame
  g.alpha[3] = 0.0;
  const LoopGeometry c = centred_parallel_normals(g, 1e-9);
  EXPECT_LT(max_difference(centred_parallel_normals(c, 1e-9), c), 1e-15);
  for (int j = 0; j < 6; ++j) {
    EXPECT_LT(max_difference(centred_parallel_normals(axis_flipped(g, j), 1e-9), axis_flipped(c, j)), 1e-14) << j;
    EXPECT_LT(max_difference(centred_parallel_normals(relabelled(g, j), 1e-9), relabelled(c, j)), 1e-14) << j;
  }
  EXPECT_LT(max_difference(centred_parallel_normals(reversed(g), 1e-9), reversed(c)), 1e-14);
  // Within the tolerance a link counts as parallel; beyond it, not.
  LoopGeometry near = g;
  near.alpha[3] = 1e-10;
  EXPECT_NEAR(centred_parallel_normals(near, 1e-9).d[3], centred_parallel_normals(near, 1e-9).d[4], 1e-15);
  EXPECT_EQ(centred_parallel_normals(near, 1e-11).d[3], near.d[3]);
}

TEST(Loop, SoThreeLogInvertsTheExponentialEverywhere) {
  for (double angle : {0.0, 1e-9, 1e-5, 0.3, 1.5, 3.0, 3.14159, 3.141592653589793}) {
    const Vector3 axis = Vector3(0.3, -0.5, 0.8).normalized();
    const Matrix3 R = Eigen::AngleAxisd(angle, axis).toRotationMatrix();
    const Vector3 phi = so3_log(R);
    EXPECT_LT((Eigen::AngleAxisd(phi.norm(), phi.norm() > 0 ? Vector3(phi.normalized()) : axis).toRotationMatrix() - R)
                  .cwiseAbs()
                  .maxCoeff(),
              1e-12)
        << angle;
    EXPECT_NEAR(phi.norm(), angle, 1e-12) << angle;
  }
}

TEST(Loop, LengthScaleIsTheRootMeanSquareLengthAndScales) {
  const LoopGeometry g = paper_bennett_loop();
  EXPECT_DOUBLE_EQ(length_scale(g), std::sqrt(10.0));
  EXPECT_DOUBLE_EQ(length_scale(scaled(g, 0.5)), 2.0 * std::sqrt(10.0));
  EXPECT_DOUBLE_EQ(length_scale(spherical_four_bar(0.3, 0.4, 0.5, 0.6)), 1.0);
  // Its gradient against central differences.
  const LoopGeometry r = random_loop(5, 3);
  const GeometryVector grad = length_scale_gradient(r);
  const double h = 1e-6;
  for (int i = 0; i < 5; ++i) {
    LoopGeometry p = r, m = r;
    p.a[i] += h;
    m.a[i] -= h;
    EXPECT_NEAR(grad[i], (length_scale(p) - length_scale(m)) / (2 * h), 1e-9);
    p = r;
    m = r;
    p.d[i] += h;
    m.d[i] -= h;
    EXPECT_NEAR(grad[10 + i], (length_scale(p) - length_scale(m)) / (2 * h), 1e-9);
    EXPECT_EQ(grad[5 + i], 0.0);
  }
}

TEST(Loop, InvalidGeometriesAreRefusedWithTheParameterNamed) {
  auto message = [](const LoopGeometry& g) {
    try {
      validate_geometry(g);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  LoopGeometry g = paper_bennett_loop();
  g.a[2] = -1.0;
  EXPECT_NE(message(g).find("a3"), std::string::npos);
  g = paper_bennett_loop();
  g.alpha[1] = std::nan("");
  EXPECT_NE(message(g).find("alpha2"), std::string::npos);
  g = paper_bennett_loop();
  g.d[3] = INFINITY;
  EXPECT_NE(message(g).find("d4"), std::string::npos);
  g = paper_bennett_loop();
  g.d = JointVector::Zero(3);
  EXPECT_NE(message(g).find("d:"), std::string::npos);
  const std::array<double, 3> three{1, 1, 1};
  EXPECT_NE(message(LoopGeometry::from_degrees(three, three, three)).find("joints"), std::string::npos);
  const std::array<double, 9> nine{1, 1, 1, 1, 1, 1, 1, 1, 1};
  EXPECT_THROW(LoopGeometry::from_degrees(nine, nine, nine), std::invalid_argument);
  EXPECT_EQ(message(random_loop(8, 1)), "accepted");
  // Lengths whose squares overflow: the length scale would be infinite.
  g = paper_bennett_loop();
  g.a[0] = 1e200;
  EXPECT_NE(message(g).find("a1: 1e+200 is too large to compute with"), std::string::npos) << message(g);
  g = paper_bennett_loop();
  g.d[1] = -2e150;
  EXPECT_NE(message(g).find("d2: -2e+150"), std::string::npos) << message(g);
  g.d[1] = -1e150;
  EXPECT_EQ(message(g), "accepted");
  EXPECT_TRUE(std::isfinite(length_scale(g)));
}

TEST(Loop, WrapAngleMapsIntoTheHalfOpenInterval) {
  EXPECT_DOUBLE_EQ(wrap_angle(3 * M_PI), M_PI);
  EXPECT_DOUBLE_EQ(wrap_angle(-M_PI), M_PI);
  EXPECT_NEAR(wrap_angle(2 * M_PI + 0.25), 0.25, 1e-15);
  EXPECT_NEAR(wrap_angle(-0.25), -0.25, 1e-15);
}

}  // namespace
}  // namespace loopfarm
