// Kinematics of a closed loop of n revolute joints (4 <= n <= 8).
//
// Convention (Denavit-Hartenberg as in the Bennett literature; docs/design.md,
// "The loop and its closure"): joint i has axis z_i; link i joins axis i to
// axis i+1 (indices mod n) with length a_i along the common normal x_{i+1},
// twist alpha_i about x_{i+1} and offset d_i along z_i. One joint-plus-link
// transform is
//
//     T_i = Rz(theta_i) * Tz(d_i) * Tx(a_i) * Rx(alpha_i)
//
// and the loop is closed when T_1 * T_2 * ... * T_n = I. The closure residual
// is the 6-vector (log of the rotation, translation), in the base frame.
//
// Indices in code are 0-based (joint 0 is the paper's joint 1). Angles are
// radians; lengths are in whatever unit the geometry is given in.
#pragma once

#include <array>
#include <span>
#include <string>

#include <Eigen/Geometry>

#include "loopfarm/core/types.hpp"

namespace loopfarm {

struct LoopGeometry {
  JointVector a;      // link lengths, >= 0
  JointVector alpha;  // link twists [rad]
  JointVector d;      // joint offsets (the paper's R_i)

  int joints() const { return static_cast<int>(a.size()); }

  // Builds a geometry from lengths and twists in degrees (the form people write).
  static LoopGeometry from_degrees(std::span<const double> a, std::span<const double> alpha_deg,
                                   std::span<const double> d);
};

// The largest |a_i| or |d_i| a geometry may have: its square, summed over the
// loop, stays far from overflow (the job reader's bound too).
inline constexpr double kMaxLength = 1e150;

// Throws std::invalid_argument naming the offending parameter when the geometry
// is not a loop loopfarm can handle: n outside [4, 8], sizes that differ,
// non-finite values, a negative length or a length or offset beyond
// kMaxLength.
void validate_geometry(const LoopGeometry& geometry);

// The geometry's length scale L: the root-mean-square of the link lengths and
// offsets, sqrt(mean(a_i^2 + d_i^2)); 1 when every length is zero (a spherical
// loop, whose translations all vanish). Smooth in every length and equivariant
// under scaling, which is what the dimensionless energy E / (k_a L^2) needs.
double length_scale(const LoopGeometry& geometry);

// Derivative of length_scale with respect to (a, alpha, d), in GeometryVector order.
GeometryVector length_scale_gradient(const LoopGeometry& geometry);

// The same loop with all lengths divided by `scale`.
LoopGeometry scaled(const LoopGeometry& geometry, double scale);

// The same physical loop relabelled so that new joint k is old joint k + shift.
// Joint angles map the same way (see relabelled_angles).
LoopGeometry relabelled(const LoopGeometry& geometry, int shift);
JointVector relabelled_angles(const JointVector& theta, int shift);

// The same physical loop traversed in the opposite direction: new joint k is old
// joint n-1-k, with theta' = -theta, d' = -d, and the link after new joint k is
// old link n-2-k (mod n). Joint angles map with reversed_angles.
LoopGeometry reversed(const LoopGeometry& geometry);
JointVector reversed_angles(const JointVector& theta);

// The same physical loop with the direction of joint axis `joint` reversed:
// frame `joint` turned by pi about its x axis, which adds pi to the twists on
// both sides of the axis (alpha_{joint-1}, alpha_joint, wrapped to (-pi, pi])
// and negates the offset d_joint; the joint angle maps with flipped_angles
// (theta_joint' = -theta_joint). The loop product is unchanged (conjugated by
// Rx(pi) when joint is 0). Flipping every axis negates every offset.
LoopGeometry axis_flipped(const LoopGeometry& geometry, int joint);
JointVector axis_flipped_angles(const JointVector& theta, int joint);

// The same physical loop with the common normal between parallel axes placed
// where it splits their offset equally. Between parallel axes (link k with
// |sin alpha_k| <= `tolerance`) the common normal x_{k+1} is free to slide
// along them: d_k and d_{k+1} then change by amounts that cancel along the
// axes' direction, the axes (and the joint angles) do not. Where the search
// leaves that normal is an accident of its path, so offsets there say nothing
// about the loop; here each run of consecutive parallel links k..m (axes k ..
// m+1) gets offsets s_j d_j that are all equal, to the run's length along the
// axes divided by its m - k + 2 offsets (s_j = +-1: axis j along or against
// axis k), and with every link parallel (a planar loop) the n offsets share
// the loop's total. The rule depends on the axes as lines only, so it commutes
// with relabelling, reversal and axis flips, and conditions written on
// offsets (d_i = d_{i+3} of a line-symmetric loop) hold for a loop with
// parallel axes however its normals were left. Other links keep their offsets;
// a loop without parallel axes is returned as it is.
LoopGeometry centred_parallel_normals(const LoopGeometry& geometry, double tolerance);

// The common normal of the lines p + s u and q + t v (unit directions): the
// parameters s and t of its feet. Where the lines are nearly parallel, where
// along them the normal lies is ill-conditioned (a round-off of the
// directions moves it by about eps / sin^2(angle)); what a DH reading needs is
// that the two feet be joined by a segment normal to both lines, which holds
// to round-off here (t is the foot of p + s u on the second line), so that
// the parameters read close. False, with s and t untouched, when
// |u x v|^2 <= min_sin2: parallel within that, every normal common.
bool common_normal_feet(const Vector3& p, const Vector3& u, const Vector3& q, const Vector3& v, double min_sin2,
                        double& s, double& t);

// T_i = Rz(theta) Tz(d) Tx(a) Rx(alpha).
Eigen::Isometry3d joint_transform(double theta, double d, double a, double alpha);

// T_1 * ... * T_count (count defaults to all joints): the pose of frame `count`
// in the base frame.
Eigen::Isometry3d forward_transform(const LoopGeometry& geometry, const JointVector& theta, int count = -1);

// Closure residual (log R, p) of the loop product; zero when the loop closes.
Vector6 closure_residual(const LoopGeometry& geometry, const JointVector& theta);

// Exact derivatives of closure_residual, one column per joint: with respect to
// the joint angles and to each a_i, alpha_i, d_i. Each column is the base-frame
// screw of the elementary motion mapped through the differential of the
// residual, so at a closed pose (residual 0) a column is exactly the screw
// (omega, v) of that motion.
struct ClosureJacobians {
  Matrix6J theta;
  Matrix6J a;
  Matrix6J alpha;
  Matrix6J d;
};
void closure_jacobians(const LoopGeometry& geometry, const JointVector& theta, ClosureJacobians& out);

// ---------------------------------------------------------------------------
// The chain of elementary motions, the machinery under the functions above and
// under the solvers. Element 4*i + k of the chain is the k-th factor of T_i:
// k = 0 Rz(theta_i), 1 Tz(d_i), 2 Tx(a_i), 3 Rx(alpha_i).
enum class ChainParameter { theta = 0, d = 1, a = 2, alpha = 3 };

constexpr int chain_index(int joint, ChainParameter parameter) {
  return kElementsPerJoint * joint + static_cast<int>(parameter);
}

// Everything one evaluation of the loop product yields: the base-frame screw
// (omega_k, v_k) of every elementary motion, the product (R, p), its logarithm
// phi and the residual with its derivative columns.
struct ChainKinematics {
  int elements = 0;
  std::array<Vector3, kMaxChain> omega;  // rotation axis (zero for translations)
  std::array<Vector3, kMaxChain> v;      // linear part of the screw
  Matrix3 rotation;                      // R of the loop product
  Vector3 position;                      // p of the loop product
  Vector3 phi;                           // log(R) as a rotation vector
  Matrix3 log_jacobian;                  // inverse left Jacobian of SO(3) at phi
  Vector6 residual;                      // (phi, p)
};

// Evaluates the chain at the given joint angles.
void compute_chain(const LoopGeometry& geometry, const JointVector& theta, ChainKinematics& out);

// d residual / d s_k for chain element k (exact, not only at closure).
Vector6 residual_derivative(const ChainKinematics& chain, int element);
// residual_derivative of each of `elements` (at most kMaxUnknowns), as the
// columns of `out`, resized to 6 x elements.size(): the closure Jacobian with
// respect to those chain elements in one pass (the same arithmetic, so the
// same bits), as every Newton iteration needs it.
void residual_jacobian(const ChainKinematics& chain, std::span<const int> elements, Matrix6U& out);

// Second derivatives of lambda^T residual with respect to the chain elements
// listed in `elements` (ascending chain order), written to out(i, j) for
// elements[i], elements[j]. This is the constraint curvature that an exact
// Newton step on the closure-constrained problem needs.
void residual_hessian(const ChainKinematics& chain, const Vector6& lambda, std::span<const int> elements,
                      ChainMatrix& out);

// SO(3) logarithm as a rotation vector, valid for every rotation (angle in [0, pi]).
Vector3 so3_log(const Matrix3& rotation);

// Wraps an angle to (-pi, pi].
double wrap_angle(double angle);

}  // namespace loopfarm
