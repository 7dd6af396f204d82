// Motion polynomials and the 6R of a cubic one (motion_polynomial.hpp).
#include "loopfarm/core/motion_polynomial.hpp"

#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>

namespace loopfarm {
namespace {

[[noreturn]] void bad(const std::string& what, double value) {
  std::ostringstream message;
  message.precision(17);
  message << what << ": got " << value;
  throw std::invalid_argument(message.str());
}

Quaternion4 conjugate(const Quaternion4& p) { return {p[0], -p[1], -p[2], -p[3]}; }

// The polynomial's value at t (coefficients of t^0 .. t^m).
DualQuaternion evaluate(std::span<const DualQuaternion> polynomial, double t) {
  DualQuaternion value;
  for (size_t i = polynomial.size(); i-- > 0;) value = t * value + polynomial[i];
  return value;
}

// The monic linear polynomial t - h.
std::array<DualQuaternion, 2> linear(const DualQuaternion& h) {
  DualQuaternion one;
  one.primal[0] = 1.0;
  return {DualQuaternion{} - h, one};
}

}  // namespace

Quaternion4 quaternion_product(const Quaternion4& a, const Quaternion4& b) {
  return {a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3], a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2],
          a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1], a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0]};
}

DualQuaternion operator*(const DualQuaternion& x, const DualQuaternion& y) {
  return {quaternion_product(x.primal, y.primal),
          quaternion_product(x.primal, y.dual) + quaternion_product(x.dual, y.primal)};
}
DualQuaternion operator+(const DualQuaternion& x, const DualQuaternion& y) {
  return {x.primal + y.primal, x.dual + y.dual};
}
DualQuaternion operator-(const DualQuaternion& x, const DualQuaternion& y) {
  return {x.primal - y.primal, x.dual - y.dual};
}
DualQuaternion operator*(double s, const DualQuaternion& x) { return {s * x.primal, s * x.dual}; }

DualQuaternion conjugate(const DualQuaternion& x) { return {conjugate(x.primal), conjugate(x.dual)}; }

DualQuaternion inverse(const DualQuaternion& x) {
  // (p + eps d)^-1 = p^-1 - eps p^-1 d p^-1.
  const double n = x.primal.squaredNorm();
  const Quaternion4 p = conjugate(x.primal) / n;
  return {p, -quaternion_product(quaternion_product(p, x.dual), p)};
}

DualQuaternion line_of(const Axis& axis) {
  const Vector3 u = axis.direction.normalized();
  const Vector3 m = axis.point.cross(u);
  return {Quaternion4(0.0, u[0], u[1], u[2]), Quaternion4(0.0, m[0], m[1], m[2])};
}

Axis axis_of_line(const DualQuaternion& line) {
  const Vector3 v = line.primal.tail<3>(), m = line.dual.tail<3>();
  // m = q x v for every point q of the line; the foot is v x m / |v|^2.
  return {v.cross(m) / v.squaredNorm(), v.normalized()};
}

DualQuaternion moved_line(const DualQuaternion& sigma, const DualQuaternion& line) {
  return (1.0 / sigma.primal.squaredNorm()) * (sigma * line * conjugate(sigma));
}

DualQuaternion rotation_quaternion(const RotationFactor& f) {
  DualQuaternion h = f.y * line_of(f.axis);
  h.primal[0] = f.x;
  return h;
}

DualQuaternion right_factor(std::span<const DualQuaternion> polynomial, double b, double c,
                            std::span<DualQuaternion> quotient) {
  const size_t m = polynomial.size() - 1;
  // The remainder modulo t^2 + b t + c, from the top down.
  std::array<DualQuaternion, 4> r{};
  for (size_t i = 0; i <= m; ++i) r[i] = polynomial[i];
  for (size_t i = m; i >= 2; --i) {
    const DualQuaternion lead = r[i];
    r[i] = DualQuaternion{};
    r[i - 1] = r[i - 1] - b * lead;
    r[i - 2] = r[i - 2] - c * lead;
  }
  if (!(r[1].primal.squaredNorm() > 1e-24)) {
    bad("right_factor: the remainder's leading coefficient is zero (a real quadratic factor); its norm",
        r[1].primal.norm());
  }
  const DualQuaternion k = DualQuaternion{} - inverse(r[1]) * r[0];
  // polynomial = quotient (t - k): quotient[i - 1] = polynomial[i] + quotient[i] k.
  quotient[m - 1] = polynomial[m];
  for (size_t i = m - 1; i >= 1; --i) quotient[i - 1] = polynomial[i] + quotient[i] * k;
  return k;
}

std::array<DualQuaternion, 4> cubic_product(const DualQuaternion& h1, const DualQuaternion& h2,
                                            const DualQuaternion& h3) {
  const std::array<DualQuaternion, 2> f1 = linear(h1), f2 = linear(h2), f3 = linear(h3);
  std::array<DualQuaternion, 3> q{};
  for (size_t i = 0; i < 2; ++i) {
    for (size_t j = 0; j < 2; ++j) q[i + j] = q[i + j] + f1[i] * f2[j];
  }
  std::array<DualQuaternion, 4> out{};
  for (size_t i = 0; i < 3; ++i) {
    for (size_t j = 0; j < 2; ++j) out[i + j] = out[i + j] + q[i] * f3[j];
  }
  return out;
}

std::array<DualQuaternion, 3> refactor_cubic(const std::array<DualQuaternion, 3>& h, const std::array<int, 3>& order) {
  std::array<DualQuaternion, 4> cubic = cubic_product(h[0], h[1], h[2]);
  // The norm of t - h is t^2 - 2 h_w t + |primal h|^2 (h's primal vector part
  // squared plus h_w^2).
  const auto norm_of = [&h](int i) {
    const DualQuaternion& x = h[static_cast<size_t>(i)];
    return std::array<double, 2>{-2.0 * x.primal[0], x.primal.squaredNorm()};
  };
  std::array<DualQuaternion, 3> k{};
  std::array<DualQuaternion, 3> quadratic{};
  const std::array<double, 2> n3 = norm_of(order[2]), n2 = norm_of(order[1]);
  k[2] = right_factor(cubic, n3[0], n3[1], quadratic);
  std::array<DualQuaternion, 2> last{};
  k[1] = right_factor(quadratic, n2[0], n2[1], last);
  k[0] = DualQuaternion{} - last[0];
  return k;
}

PosedLoop cubic_motion_6r(const CubicMotion6R& p, double t) {
  for (size_t i = 0; i < 3; ++i) {
    const RotationFactor& f = p.factors[i];
    if (!(f.y != 0.0) || !std::isfinite(f.y) || !std::isfinite(f.x)) {
      bad("cubic_motion_6r: each factor's y must be finite and nonzero, and x finite", f.y);
    }
    if (!f.axis.point.allFinite() || !(f.axis.direction.norm() > 1e-12) || !f.axis.direction.allFinite()) {
      bad("cubic_motion_6r: each factor's axis needs a finite point and a nonzero direction; its direction's norm",
          f.axis.direction.norm());
    }
  }
  std::array<bool, 3> seen{};
  for (int i : p.order) {
    if (i < 0 || i > 2 || seen[static_cast<size_t>(i)]) bad("cubic_motion_6r: order must permute 0, 1, 2", i);
    seen[static_cast<size_t>(i)] = true;
  }
  // k1 = h1 or k3 = h3 would make two of the six axes one joint.
  if (p.order[0] == 0) bad("cubic_motion_6r: order[0] must not be 0 (k1 would be h1)", p.order[0]);
  if (p.order[2] == 2) bad("cubic_motion_6r: order[2] must not be 2 (k3 would be h3)", p.order[2]);
  if (!std::isfinite(t)) bad("cubic_motion_6r: t must be finite", t);
  const std::array<DualQuaternion, 3> h = {rotation_quaternion(p.factors[0]), rotation_quaternion(p.factors[1]),
                                           rotation_quaternion(p.factors[2])};
  const std::array<DualQuaternion, 3> k = refactor_cubic(h, p.order);
  // Each chain's axes at t: axis j moved by the factors before it.
  const auto chain = [t](const std::array<DualQuaternion, 3>& factors) {
    std::array<Axis, 3> axes;
    DualQuaternion sigma;
    sigma.primal[0] = 1.0;
    for (size_t j = 0; j < 3; ++j) {
      DualQuaternion line = factors[j];
      line.primal[0] = 0.0;  // the line's multiple: h - h_w
      axes[j] = axis_of_line(moved_line(sigma, line));
      const std::array<DualQuaternion, 2> f = linear(factors[j]);
      sigma = sigma * evaluate(f, t);
    }
    return axes;
  };
  const std::array<Axis, 3> first = chain(h), second = chain(k);
  const std::array<Axis, 6> axes = {first[0], first[1], first[2], second[2], second[1], second[0]};
  return dh_from_axes(axes);
}

}  // namespace loopfarm
