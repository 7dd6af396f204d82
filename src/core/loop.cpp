#include "loopfarm/core/loop.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace loopfarm {
namespace {

constexpr double kPi = 3.14159265358979323846;

[[noreturn]] void fail(const std::string& what) { throw std::invalid_argument(what); }

JointVector from_span(std::span<const double> values, double factor) {
  JointVector out(static_cast<Eigen::Index>(values.size()));
  for (size_t i = 0; i < values.size(); ++i) out[static_cast<Eigen::Index>(i)] = values[i] * factor;
  return out;
}

// beta(t) = 1/t^2 - (1 + cos t) / (2 t sin t), the coefficient of phi^2 in the
// inverse left Jacobian of SO(3), and beta'(t)/t. Series near 0, where the
// closed forms cancel catastrophically.
void log_jacobian_coefficients(double t, double& beta, double& dbeta_over_t) {
  if (t < 0.1) {
    const double t2 = t * t;
    beta = 1.0 / 12.0 + t2 * (1.0 / 720.0 + t2 * (1.0 / 30240.0 + t2 * (1.0 / 1209600.0)));
    dbeta_over_t = 1.0 / 360.0 + t2 * (1.0 / 7560.0 + t2 * (1.0 / 201600.0 + t2 * (1.0 / 5987520.0)));
    return;
  }
  const double half = 0.5 * t;
  const double cot_half = std::cos(half) / std::sin(half);
  const double csc2_half = 1.0 / (std::sin(half) * std::sin(half));
  beta = 1.0 / (t * t) - cot_half / (2.0 * t);
  dbeta_over_t = -2.0 / (t * t * t * t) + csc2_half / (4.0 * t * t) + cot_half / (2.0 * t * t * t);
}

}  // namespace

LoopGeometry LoopGeometry::from_degrees(std::span<const double> a, std::span<const double> alpha_deg,
                                        std::span<const double> d) {
  LoopGeometry g;
  if (a.size() > static_cast<size_t>(kMaxJoints) || alpha_deg.size() > static_cast<size_t>(kMaxJoints) ||
      d.size() > static_cast<size_t>(kMaxJoints)) {
    fail("a loop has at most " + std::to_string(kMaxJoints) + " joints");
  }
  g.a = from_span(a, 1.0);
  g.alpha = from_span(alpha_deg, kPi / 180.0);
  g.d = from_span(d, 1.0);
  return g;
}

void validate_geometry(const LoopGeometry& g) {
  const int n = g.joints();
  if (n < kMinJoints || n > kMaxJoints) {
    fail("a: a loop needs " + std::to_string(kMinJoints) + " to " + std::to_string(kMaxJoints) + " joints, got " +
         std::to_string(n));
  }
  if (g.alpha.size() != n)
    fail("alpha: expected " + std::to_string(n) + " values, got " + std::to_string(g.alpha.size()));
  if (g.d.size() != n) fail("d: expected " + std::to_string(n) + " values, got " + std::to_string(g.d.size()));
  for (int i = 0; i < n; ++i) {
    const std::string k = std::to_string(i + 1);
    if (!std::isfinite(g.a[i])) fail("a" + k + ": not a finite number");
    if (g.a[i] < 0.0) fail("a" + k + ": a link length must be >= 0, got " + std::to_string(g.a[i]));
    if (!std::isfinite(g.alpha[i])) fail("alpha" + k + ": not a finite number");
    if (!std::isfinite(g.d[i])) fail("d" + k + ": not a finite number");
    // Squares of lengths (the length scale, the energy) must not overflow.
    for (const auto& [name, value] : {std::pair{"a", g.a[i]}, std::pair{"d", g.d[i]}}) {
      if (std::abs(value) > kMaxLength) {
        char text[32];
        std::snprintf(text, sizeof text, "%g", value);
        fail(name + k + ": " + text + " is too large to compute with (its square overflows; |value| must be <= 1e150)" +
             ": scale the loop down");
      }
    }
  }
}

double length_scale(const LoopGeometry& g) {
  const double mean_square = (g.a.squaredNorm() + g.d.squaredNorm()) / g.joints();
  return mean_square > 0.0 ? std::sqrt(mean_square) : 1.0;
}

GeometryVector length_scale_gradient(const LoopGeometry& g) {
  const int n = g.joints();
  GeometryVector grad = GeometryVector::Zero(3 * n);
  const double mean_square = (g.a.squaredNorm() + g.d.squaredNorm()) / n;
  if (mean_square <= 0.0) return grad;  // L is the constant 1 there
  const double L = std::sqrt(mean_square);
  // dL/da_i = a_i / (n L), likewise for d_i.
  grad.segment(0, n) = g.a / (n * L);
  grad.segment(2 * n, n) = g.d / (n * L);
  return grad;
}

LoopGeometry scaled(const LoopGeometry& g, double scale) {
  LoopGeometry out = g;
  out.a /= scale;
  out.d /= scale;
  return out;
}

LoopGeometry relabelled(const LoopGeometry& g, int shift) {
  const int n = g.joints();
  LoopGeometry out = g;
  for (int k = 0; k < n; ++k) {
    const int old = ((k + shift) % n + n) % n;
    out.a[k] = g.a[old];
    out.alpha[k] = g.alpha[old];
    out.d[k] = g.d[old];
  }
  return out;
}

JointVector relabelled_angles(const JointVector& theta, int shift) {
  const int n = static_cast<int>(theta.size());
  JointVector out(n);
  for (int k = 0; k < n; ++k) out[k] = theta[((k + shift) % n + n) % n];
  return out;
}

LoopGeometry reversed(const LoopGeometry& g) {
  // Inverting T_1...T_n = I and conjugating by Rz(pi) turns every factor
  // Rx(-alpha) Tx(-a) Tz(-d) Rz(-theta) into Rx(alpha) Tx(a) Tz(-d) Rz(-theta);
  // regrouping the product cyclically gives a DH chain over the joints in
  // reverse order, where the link after old joint i is old link i - 1.
  const int n = g.joints();
  LoopGeometry out = g;
  for (int k = 0; k < n; ++k) {
    const int joint = n - 1 - k;
    const int link = ((n - 2 - k) % n + n) % n;
    out.d[k] = -g.d[joint];
    out.a[k] = g.a[link];
    out.alpha[k] = g.alpha[link];
  }
  return out;
}

JointVector reversed_angles(const JointVector& theta) {
  const int n = static_cast<int>(theta.size());
  JointVector out(n);
  for (int k = 0; k < n; ++k) out[k] = -theta[n - 1 - k];
  return out;
}

LoopGeometry axis_flipped(const LoopGeometry& g, int joint) {
  // T_{j-1} Rx(pi) = Rz Tz Tx Rx(alpha_{j-1} + pi), and Rx(-pi) T_j =
  // Rz(-theta_j) Tz(-d_j) Tx(a_j) Rx(alpha_j - pi): Rx(pi) commutes with the
  // x motions and reverses the z ones.
  const int n = g.joints();
  const int before = (joint + n - 1) % n;
  constexpr double kPi = 3.14159265358979323846;
  LoopGeometry out = g;
  out.alpha[before] = wrap_angle(g.alpha[before] + kPi);
  out.alpha[joint] = wrap_angle(out.alpha[joint] + kPi);  // reads `out`: n >= 4, so before != joint
  out.d[joint] = -g.d[joint];
  return out;
}

JointVector axis_flipped_angles(const JointVector& theta, int joint) {
  JointVector out = theta;
  out[joint] = -theta[joint];
  return out;
}

LoopGeometry centred_parallel_normals(const LoopGeometry& g, double tolerance) {
  const int n = g.joints();
  auto parallel = [&](int k) { return std::abs(std::sin(g.alpha[k])) <= tolerance; };
  // Offsets first .. first + count - 1 (mod n), each signed along axis
  // `first`, share their sum equally.
  LoopGeometry out = g;
  auto share = [&](int first, int count) {
    double sign = 1.0, total = 0.0;
    for (int j = 0; j < count; ++j) {
      const int k = (first + j) % n;
      total += sign * g.d[k];
      if (std::cos(g.alpha[k]) < 0.0) sign = -sign;
    }
    sign = 1.0;
    for (int j = 0; j < count; ++j) {
      const int k = (first + j) % n;
      out.d[k] = sign * total / count;
      if (std::cos(g.alpha[k]) < 0.0) sign = -sign;
    }
  };
  int start = -1;  // a link that is not parallel: runs end there
  for (int k = 0; k < n && start < 0; ++k) {
    if (!parallel(k)) start = k;
  }
  if (start < 0) {
    share(0, n);
    return out;
  }
  for (int j = 1; j <= n;) {
    const int first = (start + j) % n;
    if (!parallel(first)) {
      ++j;
      continue;
    }
    int links = 0;
    while (j + links <= n && parallel((first + links) % n)) ++links;
    share(first, links + 1);
    j += links;
  }
  return out;
}

bool common_normal_feet(const Vector3& p, const Vector3& u, const Vector3& q, const Vector3& v, double min_sin2,
                        double& s, double& t) {
  const Vector3 n = u.cross(v);
  const double nn = n.squaredNorm();
  if (!(nn > min_sin2)) return false;
  // (p + s u) - (q + t v) is along n: s is the coordinate of q - p along u in
  // the basis (u, v, n). t is then the foot of p + s u on the second line,
  // so that the segment between the feet is normal to both lines to
  // round-off even where s itself is uncertain.
  s = (q - p).cross(v).dot(n) / nn;
  t = (p + s * u - q).dot(v);
  return true;
}

Eigen::Isometry3d joint_transform(double theta, double d, double a, double alpha) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.rotate(Eigen::AngleAxisd(theta, Vector3::UnitZ()));
  t.translate(Vector3(a, 0.0, d));  // Tz(d) Tx(a) commute
  t.rotate(Eigen::AngleAxisd(alpha, Vector3::UnitX()));
  return t;
}

Eigen::Isometry3d forward_transform(const LoopGeometry& g, const JointVector& theta, int count) {
  if (count < 0) count = g.joints();
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  for (int i = 0; i < count; ++i) t = t * joint_transform(theta[i], g.d[i], g.a[i], g.alpha[i]);
  return t;
}

Vector3 so3_log(const Matrix3& R) {
  const double cos_angle = std::clamp(0.5 * (R.trace() - 1.0), -1.0, 1.0);
  const Vector3 axis_sin(R(2, 1) - R(1, 2), R(0, 2) - R(2, 0), R(1, 0) - R(0, 1));  // 2 sin(t) u
  const double sin_angle = 0.5 * axis_sin.norm();
  const double angle = std::atan2(sin_angle, cos_angle);
  if (angle < 1e-6) {
    // t / (2 sin t) = 1/2 + t^2/12 + ...
    return (0.5 + angle * angle / 12.0) * axis_sin;
  }
  if (angle < kPi - 1e-4) return (angle / (2.0 * sin_angle)) * axis_sin;
  // Near pi the antisymmetric part vanishes: take the axis from the symmetric
  // part, R + R^T = 2 cos t I + 2 (1 - cos t) u u^T, then its sign from axis_sin.
  const Matrix3 B = 0.5 * (R + R.transpose()) - cos_angle * Matrix3::Identity();
  int k = 0;
  B.diagonal().maxCoeff(&k);
  Vector3 u = B.col(k) / std::sqrt(std::max(B(k, k), 1e-300));
  u.normalize();
  if (u.dot(axis_sin) < 0.0) u = -u;
  return angle * u;
}

double wrap_angle(double angle) {
  // Most angles the solvers wrap are already in range: skip the division.
  if (angle > -kPi && angle <= kPi) return angle;
  double w = std::remainder(angle, 2.0 * kPi);  // in [-pi, pi]
  if (w <= -kPi) w += 2.0 * kPi;
  return w;
}

void compute_chain(const LoopGeometry& g, const JointVector& theta, ChainKinematics& out) {
  const int n = g.joints();
  out.elements = kElementsPerJoint * n;
  Matrix3 R = Matrix3::Identity();
  Vector3 p = Vector3::Zero();
  for (int i = 0; i < n; ++i) {
    const int e = kElementsPerJoint * i;
    // Rz(theta_i): rotation about the current z axis through the current origin.
    out.omega[e] = R.col(2);
    out.v[e] = p.cross(out.omega[e]);
    const double ct = std::cos(theta[i]), st = std::sin(theta[i]);
    const Vector3 x = ct * R.col(0) + st * R.col(1);
    const Vector3 y = -st * R.col(0) + ct * R.col(1);
    R.col(0) = x;
    R.col(1) = y;
    // Tz(d_i) then Tx(a_i): translations along the current z and x axes.
    out.omega[e + 1].setZero();
    out.v[e + 1] = R.col(2);
    p += g.d[i] * R.col(2);
    out.omega[e + 2].setZero();
    out.v[e + 2] = R.col(0);
    p += g.a[i] * R.col(0);
    // Rx(alpha_i): rotation about the current x axis through the current origin.
    out.omega[e + 3] = R.col(0);
    out.v[e + 3] = p.cross(out.omega[e + 3]);
    const double ca = std::cos(g.alpha[i]), sa = std::sin(g.alpha[i]);
    const Vector3 y2 = ca * R.col(1) + sa * R.col(2);
    const Vector3 z2 = -sa * R.col(1) + ca * R.col(2);
    R.col(1) = y2;
    R.col(2) = z2;
  }
  out.rotation = R;
  out.position = p;
  out.phi = so3_log(R);
  // Inverse left Jacobian: J^-1(phi) = I - phi^/2 + beta(|phi|) phi^2, with
  // phi^2 = phi phiᵀ - |phi|^2 I written out (Eigen's 3 x 3 product of the
  // skew matrices was a call of its own, 3 % of a generic cycle's
  // instructions).
  const double t = out.phi.norm();
  double beta = 0.0, dbeta_over_t = 0.0;
  log_jacobian_coefficients(t, beta, dbeta_over_t);
  const Vector3 half = 0.5 * out.phi;
  Matrix3& J = out.log_jacobian;
  J.noalias() = (beta * out.phi) * out.phi.transpose();
  J.diagonal().array() += 1.0 - beta * t * t;
  J(0, 1) += half.z();
  J(0, 2) -= half.y();
  J(1, 0) -= half.z();
  J(1, 2) += half.x();
  J(2, 0) += half.y();
  J(2, 1) -= half.x();
  out.residual.head<3>() = out.phi;
  out.residual.tail<3>() = p;
}

Vector6 residual_derivative(const ChainKinematics& c, int k) {
  // A change ds of element k moves the product by exp(ds * xi_k^) on the left:
  // dR = omega^ R, dp = omega x p + v; d log R = J_l^-1(phi) omega.
  Vector6 col;
  col.head<3>().noalias() = c.log_jacobian * c.omega[k];
  col.tail<3>() = c.omega[k].cross(c.position) + c.v[k];
  return col;
}

void residual_jacobian(const ChainKinematics& c, std::span<const int> elements, Matrix6U& out) {
  const int m = static_cast<int>(elements.size());
  out.resize(6, m);
  for (int u = 0; u < m; ++u) {
    const int k = elements[static_cast<size_t>(u)];
    const Vector3& w = c.omega[k];
    const Vector3& p = c.position;
    const Vector3& v = c.v[k];
    auto col = out.col(u);
    col.head<3>().noalias() = c.log_jacobian * w;
    // w x p + v component by component, in Eigen's order (so the same bits):
    // Eigen's cross product went through a temporary stored as scalars and
    // reloaded as a pair, a store-forwarding stall that perf annotate put at
    // three quarters of this function's time.
    col[3] = (w.y() * p.z() - w.z() * p.y()) + v.x();
    col[4] = (w.z() * p.x() - w.x() * p.z()) + v.y();
    col[5] = (w.x() * p.y() - w.y() * p.x()) + v.z();
  }
}

void residual_hessian(const ChainKinematics& c, const Vector6& lambda, std::span<const int> elements,
                      ChainMatrix& out) {
  // For chain elements k <= l (the screw of l depends on s_k through the
  // bracket d xi_l / d s_k = [xi_k, xi_l]):
  //   d2 phi / ds_k ds_l = M_{omega_l} u_k + J^-1 (omega_k x omega_l),  u_k = J^-1 omega_k,
  //   d2 p   / ds_k ds_l = omega_k x (omega_l x p + v_l),
  // where M_w = d(J^-1(phi) w)/d phi = w^/2 + (beta'/t) g_w phi^T + beta (phi w^T + (phi.w) I - 2 w phi^T)
  // and g_w = phi x (phi x w). Contracted with lambda = (l_w, l_v) every term
  // is a handful of dot products of per-element vectors precomputed below.
  const int m = static_cast<int>(elements.size());
  out.resize(m, m);
  const Vector3 lw = lambda.head<3>();
  const Vector3 lv = lambda.tail<3>();
  const Vector3& phi = c.phi;
  const double t = phi.norm();
  double beta = 0.0, dbeta_over_t = 0.0;
  log_jacobian_coefficients(t, beta, dbeta_over_t);
  const Vector3 mu = c.log_jacobian.transpose() * lw;
  const double lw_phi = lw.dot(phi);

  // Per-element precomputation. Grouping the terms by what they share with
  // element k, the entry for k <= l is
  //   h = w_k . t_l + u_k . q_l + (phi . u_k) s_l + (l_w . u_k) r_l,
  //   q_l = 1/2 l_w x w_l + beta (l_w . phi) w_l,
  //   s_l = (beta'/t) (l_w . g_l) - 2 beta (l_w . w_l),   r_l = beta (phi . w_l),
  //   t_l = w_l x mu + (w_l x p + v_l) x l_v.
  // A translation has w = 0 and u = 0, so its row of the upper triangle is
  // zero, and as column l (q_l = 0, s_l = r_l = 0) it keeps only w_k . t_l.
  // So every entry is one dot product of 8-vectors, [w_k; u_k; phi . u_k;
  // l_w . u_k] with [t_l; q_l; s_l; r_l]: whole SIMD rows instead of four
  // 3-vector products and two branches an entry.
  Eigen::Matrix<double, 8, kMaxChain> left, right;
  for (int i = 0; i < m; ++i) {
    const int e = elements[static_cast<size_t>(i)];
    const auto kind = static_cast<ChainParameter>(e % kElementsPerJoint);
    const Vector3& w = c.omega[e];
    auto l = left.col(i);
    auto r = right.col(i);
    r.head<3>() = (w.cross(c.position) + c.v[e]).cross(lv);
    if (kind != ChainParameter::theta && kind != ChainParameter::alpha) {
      l.setZero();
      r.tail<5>().setZero();
      continue;
    }
    const Vector3 u = c.log_jacobian * w;
    const double phi_w = phi.dot(w);
    const double lw_w = lw.dot(w);
    const double lw_g = lw_phi * phi_w - t * t * lw_w;
    l.head<3>() = w;
    l.segment<3>(3) = u;
    l[6] = phi.dot(u);
    l[7] = lw.dot(u);
    r.head<3>() += w.cross(mu);
    r.segment<3>(3) = 0.5 * lw.cross(w) + beta * lw_phi * w;
    r[6] = dbeta_over_t * lw_g - 2.0 * beta * lw_w;
    r[7] = beta * phi_w;
  }
  for (int j = 0; j < m; ++j) {
    for (int i = 0; i <= j; ++i) {
      const double h = left.col(i).dot(right.col(j));
      out(i, j) = h;
      out(j, i) = h;
    }
  }
}

void closure_jacobians(const LoopGeometry& g, const JointVector& theta, ClosureJacobians& out) {
  ChainKinematics chain;
  compute_chain(g, theta, chain);
  const int n = g.joints();
  out.theta.resize(6, n);
  out.a.resize(6, n);
  out.alpha.resize(6, n);
  out.d.resize(6, n);
  for (int i = 0; i < n; ++i) {
    out.theta.col(i) = residual_derivative(chain, chain_index(i, ChainParameter::theta));
    out.d.col(i) = residual_derivative(chain, chain_index(i, ChainParameter::d));
    out.a.col(i) = residual_derivative(chain, chain_index(i, ChainParameter::a));
    out.alpha.col(i) = residual_derivative(chain, chain_index(i, ChainParameter::alpha));
  }
}

Vector6 closure_residual(const LoopGeometry& g, const JointVector& theta) {
  const Eigen::Isometry3d t = forward_transform(g, theta);
  Vector6 r;
  r.head<3>() = so3_log(t.rotation());
  r.tail<3>() = t.translation();
  return r;
}

}  // namespace loopfarm
