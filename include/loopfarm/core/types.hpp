// Fixed-capacity Eigen types shared by the whole library.
//
// Every buffer a solver touches has a compile-time maximum size, so the hot
// loops never allocate: a loop has at most kMaxJoints joints, its kinematic
// chain at most 4 * kMaxJoints elementary motions, and at most 3 * kMaxJoints
// deformable parameters.
#pragma once

#include <Eigen/Core>

namespace loopfarm {

inline constexpr int kMinJoints = 4;
inline constexpr int kMaxJoints = 8;
// Each joint contributes four elementary motions: Rz(theta), Tz(d), Tx(a), Rx(alpha).
inline constexpr int kElementsPerJoint = 4;
inline constexpr int kMaxChain = kElementsPerJoint * kMaxJoints;
inline constexpr int kMaxDeformations = 3 * kMaxJoints;
// Unknowns of one equilibrium solve: passive angles plus deformations.
inline constexpr int kMaxUnknowns = (kMaxJoints - 1) + kMaxDeformations;

using Vector3 = Eigen::Vector3d;
using Matrix3 = Eigen::Matrix3d;
using Vector6 = Eigen::Matrix<double, 6, 1>;
using Matrix6 = Eigen::Matrix<double, 6, 6>;

// One value per joint (angles in radians, lengths in the geometry's unit).
using JointVector = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxJoints, 1>;
// One value per deformable parameter (layout: see LoopModel).
using DeformationVector = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxDeformations, 1>;
// One value per geometric parameter, ordered (a_1..a_n, alpha_1..alpha_n, d_1..d_n).
using GeometryVector = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, 3 * kMaxJoints, 1>;
// A 6 x k block of residual derivatives, one column per joint or parameter.
using Matrix6J = Eigen::Matrix<double, 6, Eigen::Dynamic, 0, 6, kMaxJoints>;

using UnknownVector = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxUnknowns, 1>;
using UnknownMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxUnknowns, kMaxUnknowns>;
using Matrix6U = Eigen::Matrix<double, 6, Eigen::Dynamic, 0, 6, kMaxUnknowns>;
using ChainMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxChain, kMaxChain>;

}  // namespace loopfarm
