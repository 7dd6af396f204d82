// The fit of the "321" cubic-motion-polynomial 6R (cubic_motion_fit.hpp).
#include "cubic_motion_fit.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "loopfarm/core/constructions.hpp"
#include "loopfarm/core/motion_polynomial.hpp"

namespace loopfarm::detail {

const char* cubic_residual_name(int i) {
  static constexpr const char* kNames[kCubicResiduals] = {
      "cos(alpha3) - the construction's", "cos(alpha4) - the construction's", "cos(alpha5) - the construction's",
      "cos(alpha6) - the construction's", "(a3' - the construction's) / L",   "(a4' - the construction's) / L",
      "(a5' - the construction's) / L",   "(a6' - the construction's) / L",   "(d1 - the construction's) / L",
      "(d3 - the construction's) / L",    "(d4 - the construction's) / L",    "(d5 - the construction's) / L",
      "(d6 - the construction's) / L"};
  return i >= 0 && i < kCubicResiduals ? kNames[i] : "";
}

namespace {

// One loop's parameters as the fit reads them.
struct CubicMotionParameters {
  std::array<double, 6> a{}, sin{}, cos{}, d{};
  double L = 1.0;
};

constexpr std::array<int, 3> kOrder321 = {2, 1, 0};
using Unknowns = std::array<double, 5>;  // theta2, x2, y2, x3, y3

// The loop's joints 1, 2, 3 in the pose at t = infinity: frame 1 on axis 1,
// axis 2 at a1, alpha1 along and about link 1, axis 3 at d2, theta2 along
// and about axis 2 and then a2, alpha2 (T = Rz(theta) Tz(d) Tx(a) Rx(alpha)).
std::array<Axis, 3> chain_axes(const CubicMotionParameters& p, double theta2) {
  const Eigen::Isometry3d t1 =
      Eigen::Translation3d(p.a[0], 0.0, 0.0) * Eigen::AngleAxisd(std::atan2(p.sin[0], p.cos[0]), Vector3::UnitX());
  const Eigen::Isometry3d t2 = t1 * Eigen::AngleAxisd(theta2, Vector3::UnitZ()) *
                               Eigen::Translation3d(0.0, 0.0, p.d[1]) * Eigen::Translation3d(p.a[1], 0.0, 0.0) *
                               Eigen::AngleAxisd(std::atan2(p.sin[1], p.cos[1]), Vector3::UnitX());
  return {Axis{Vector3::Zero(), Vector3::UnitZ()}, Axis{t1.translation(), t1.linear().col(2)},
          Axis{t2.translation(), t2.linear().col(2)}};
}

// The construction's six lines for the unknowns v = (theta2, x2, y2, x3, y3).
struct Hexagon {
  std::array<Axis, 6> axes;
  bool ok = false;
};

Hexagon hexagon(const CubicMotionParameters& p, const Unknowns& v) {
  const std::array<Axis, 3> axes = chain_axes(p, v[0]);
  const std::array<double, 3> x = {0.0, v[1], v[3]}, y = {1.0, v[2], v[4]};
  std::array<DualQuaternion, 3> h;
  for (size_t i = 0; i < 3; ++i) h[i] = rotation_quaternion(RotationFactor{axes[i], x[i], y[i]});
  Hexagon out;
  std::array<DualQuaternion, 3> k;
  try {
    k = refactor_cubic(h, kOrder321);
  } catch (const std::invalid_argument&) {
    return out;  // a real quadratic factor: no second factorisation
  }
  for (size_t i = 0; i < 3; ++i) {
    out.axes[i] = axes[i];
    DualQuaternion line = k[2 - i];  // joints 4, 5, 6: k3, k2, k1
    line.primal[0] = 0.0;
    if (!(line.primal.squaredNorm() > 1e-24) || !line.primal.allFinite() || !line.dual.allFinite()) return out;
    out.axes[3 + i] = axis_of_line(line);
  }
  out.ok = true;
  return out;
}

// The hexagon's DH values (read off its axes by dh_from_axes) in the signed
// form: cos(alpha_k), a'_k = a_k signed along u_k x u_{k+1}, d_k; none where
// two consecutive axes are parallel (|sin alpha_k| <= 1e-7: no common normal
// of their own, and not this construction's generic kind).
struct SignedDh {
  std::array<double, 6> cos{}, a{}, d{};
  bool ok = false;
};

SignedDh signed_dh(const Hexagon& l) {
  SignedDh out;
  if (!l.ok) return out;
  LoopGeometry g;
  try {
    g = dh_from_axes(l.axes).geometry;
  } catch (const std::invalid_argument&) {
    return out;  // an axis not finite
  }
  for (size_t k = 0; k < 6; ++k) {
    const auto j = static_cast<Eigen::Index>(k);
    const double sine = std::sin(g.alpha[j]);
    if (!(std::abs(sine) > 1e-7)) return out;
    out.cos[k] = std::cos(g.alpha[j]);
    out.a[k] = (sine < 0.0 ? -1.0 : 1.0) * g.a[j];
    out.d[k] = g.d[j];
  }
  out.ok = true;
  return out;
}

// The thirteen residuals: cos(alpha_k) for links 3..6, a'_k / L for links
// 3..6, d_k / L for joints 1, 3, 4, 5, 6 (links 1, 2 and d2 are built in),
// with the axis flips of joints 4..6 that fit best (F_j = -1: the loop's axis
// j against the construction's: cos(alpha) and a' of the links on either
// side change sign, and d_j).
constexpr int kResiduals = kCubicResiduals;
using Residuals = Eigen::Matrix<double, kResiduals, 1>;

struct Evaluation {
  Residuals e = Residuals::Constant(1.0);
  std::array<int, 3> flips{1, 1, 1};
  double sum = 1e300;
};

Evaluation evaluate(const CubicMotionParameters& p, const Unknowns& v) {
  Evaluation out;
  const SignedDh c = signed_dh(hexagon(p, v));
  if (!c.ok) return out;
  for (int pattern = 0; pattern < 8; ++pattern) {
    const std::array<double, 6> F = {
        1.0, 1.0, 1.0, pattern & 1 ? -1.0 : 1.0, pattern & 2 ? -1.0 : 1.0, pattern & 4 ? -1.0 : 1.0};
    Residuals e;
    int row = 0;
    for (size_t k = 2; k < 6; ++k) e[row++] = p.cos[k] - F[k] * F[(k + 1) % 6] * c.cos[k];
    for (size_t k = 2; k < 6; ++k) {
      const double loop = (p.sin[k] < 0.0 ? -1.0 : 1.0) * p.a[k];
      e[row++] = (loop - F[k] * F[(k + 1) % 6] * c.a[k]) / p.L;
    }
    for (size_t k : {0, 2, 3, 4, 5}) e[row++] = (p.d[k] - F[k] * c.d[k]) / p.L;
    const double sum = e.squaredNorm();
    if (sum < out.sum) {
      out.sum = sum;
      out.e = e;
      out.flips = {static_cast<int>(F[3]), static_cast<int>(F[4]), static_cast<int>(F[5])};
    }
  }
  return out;
}

// Levenberg-Marquardt on the residuals from v (the linear solution at the
// pose); v is left at the end. The Jacobian has rank 4 of 5: moving t =
// infinity along the motion changes theta2 and the factors together and
// the loop not at all; the damping takes care of that.
Evaluation polish(const CubicMotionParameters& p, Unknowns& v) {
  Evaluation r = evaluate(p, v);
  double lambda = 1e-3;
  for (int iteration = 0; iteration < 30 && r.sum > 1e-30; ++iteration) {
    Eigen::Matrix<double, kResiduals, 5> J;
    for (int j = 0; j < 5; ++j) {
      Unknowns w = v;
      const double h = 1e-7 * std::max(1.0, std::abs(v[static_cast<size_t>(j)]));
      w[static_cast<size_t>(j)] += h;
      J.col(j) = (evaluate(p, w).e - r.e) / h;
    }
    const Eigen::Matrix<double, 5, 5> A = J.transpose() * J;
    const Eigen::Matrix<double, 5, 1> g = J.transpose() * r.e;
    bool improved = false;
    for (int attempt = 0; attempt < 8 && !improved; ++attempt) {
      Eigen::Matrix<double, 5, 5> M = A;
      M.diagonal() += lambda * (A.diagonal().array() + 1e-12).matrix();
      const Eigen::Matrix<double, 5, 1> step = M.ldlt().solve(-g);
      Unknowns w = v;
      for (size_t j = 0; j < 5; ++j) w[j] += step[static_cast<Eigen::Index>(j)];
      // y2 and y3 keep their signs: a factor with y = 0 is no rotation.
      if (w[2] * v[2] <= 0.0 || w[4] * v[4] <= 0.0) {
        lambda *= 10.0;
        continue;
      }
      const Evaluation s = evaluate(p, w);
      if (s.sum < r.sum) {
        v = w;
        r = s;
        lambda = std::max(lambda / 10.0, 1e-12);
        improved = true;
      } else {
        lambda *= 10.0;
      }
    }
    if (!improved) break;
  }
  return r;
}

// h = x + y l.
DualQuaternion factor(double x, double y, const DualQuaternion& line) {
  DualQuaternion h = y * line;
  h.primal[0] += x;
  return h;
}

Eigen::Matrix<double, 8, 1> flat(const DualQuaternion& q) {
  Eigen::Matrix<double, 8, 1> v;
  v << q.primal, q.dual;
  return v;
}

// The factors for the loop's lines at the pose, t = infinity there: with
// x1 = 0, y1 = 1 and the lines of axes 4, 5, 6 taken with the signs s (k3
// = s4 l4, k2 = x2 + y2 s5 l5, k1 = x3 + y3 s6 l6), the coefficient of t^2
// of (t - h1)(t - h2)(t - h3) = (t - k1)(t - k2)(t - k3) is linear in y2, y3
// and, with them, that of t is linear in x2, x3 (the products of x's are the
// same on both sides): two least-squares solves.
Unknowns factors_at_pose(const std::array<DualQuaternion, 6>& l, const std::array<double, 3>& s, double theta2) {
  Eigen::Matrix<double, 8, 2> A;
  A.col(0) = flat(l[1] - s[1] * l[4]);
  A.col(1) = flat(l[2] - s[2] * l[5]);
  const Eigen::Vector2d y = A.colPivHouseholderQr().solve(flat(s[0] * l[3] - l[0]));
  const auto t1 = [&](double x2, double x3) {
    const DualQuaternion h1 = l[0], h2 = factor(x2, y[0], l[1]), h3 = factor(x3, y[1], l[2]);
    const DualQuaternion k3 = s[0] * l[3], k2 = factor(x2, y[0] * s[1], l[4]), k1 = factor(x3, y[1] * s[2], l[5]);
    return flat((h1 * h2 + h1 * h3 + h2 * h3) - (k1 * k2 + k1 * k3 + k2 * k3));
  };
  const Eigen::Matrix<double, 8, 1> f0 = t1(0.0, 0.0);
  Eigen::Matrix<double, 8, 2> B;
  B.col(0) = t1(1.0, 0.0) - f0;
  B.col(1) = t1(0.0, 1.0) - f0;
  const Eigen::Vector2d x = B.colPivHouseholderQr().solve(-f0);
  return {theta2, x[0], y[0], x[1], y[1]};
}

}  // namespace

CubicMotionFit cubic_321_fit(const LoopGeometry& g, const JointVector& pose) {
  CubicMotionFit fit;
  if (g.joints() != 6) return fit;
  CubicMotionParameters p;
  for (int k = 0; k < 6; ++k) {
    const auto i = static_cast<size_t>(k);
    p.a[i] = g.a[k];
    p.sin[i] = std::sin(g.alpha[k]);
    p.cos[i] = std::cos(g.alpha[k]);
    p.d[i] = g.d[k];
  }
  p.L = length_scale(g);
  const std::vector<Axis> axes = joint_axes(g, pose);
  std::array<DualQuaternion, 6> lines;
  for (size_t i = 0; i < 6; ++i) lines[i] = line_of(Axis{axes[i].point / p.L, axes[i].direction});
  // The signs whose linear solution fits best, polished.
  Unknowns best{};
  double least = std::numeric_limits<double>::infinity();
  for (int pattern = 0; pattern < 8; ++pattern) {
    const std::array<double, 3> s = {pattern & 1 ? -1.0 : 1.0, pattern & 2 ? -1.0 : 1.0, pattern & 4 ? -1.0 : 1.0};
    const Unknowns v = factors_at_pose(lines, s, pose[1]);
    if (!std::isfinite(v[2]) || !std::isfinite(v[4]) || v[2] == 0.0 || v[4] == 0.0) continue;
    const double sum = evaluate(p, v).sum;
    if (sum < least) {
      least = sum;
      best = v;
    }
  }
  if (!(least < 1e300)) return fit;
  const Evaluation r = polish(p, best);
  fit.solved = true;
  for (int i = 0; i < kResiduals; ++i) fit.residuals[static_cast<size_t>(i)] = r.e[i];
  fit.residual = r.e.cwiseAbs().maxCoeff();
  fit.unknowns = best;
  fit.flips = r.flips;
  return fit;
}

}  // namespace loopfarm::detail
