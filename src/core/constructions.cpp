#include "loopfarm/core/constructions.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>

#include <Eigen/LU>

#include "loopfarm/core/sample_loops.hpp"

namespace loopfarm {
namespace {

constexpr double kPi = 3.14159265358979323846;
// Round-off allowance of the closed forms: a cosine, a discriminant relative
// to its scale, a Grashof sum relative to the perimeter.
constexpr double kTolerance = 1e-12;

[[noreturn]] void bad(const std::string& what, double value) {
  std::ostringstream message;
  message.precision(17);
  message << what << ": got " << value;
  throw std::invalid_argument(message.str());
}

// ---------------------------------------------------------------------------
// Four-bars

enum class FourBarType { planar, spherical };

// Twist 0 or pi to round-off.
bool is_flat_twist(double alpha) { return std::abs(std::sin(alpha)) <= kTolerance; }

FourBarType four_bar_type(const LoopGeometry& g) {
  validate_geometry(g);
  if (g.joints() != 4) bad("four-bar: joint count", g.joints());
  bool all_flat = true, no_lengths = true;
  for (int k = 0; k < 4; ++k) {
    all_flat = all_flat && is_flat_twist(g.alpha[k]);
    no_lengths = no_lengths && g.a[k] == 0.0 && g.d[k] == 0.0;
  }
  if (no_lengths) {
    for (int k = 0; k < 4; ++k) {
      if (is_flat_twist(g.alpha[k])) {
        bad("spherical four-bar: twist alpha" + std::to_string(k + 1) + " is 0 or pi", g.alpha[k]);
      }
    }
    return FourBarType::spherical;
  }
  if (all_flat) {
    for (int k = 0; k < 4; ++k) {
      if (!(g.a[k] > 0.0)) bad("planar four-bar: length a" + std::to_string(k + 1) + " must be > 0", g.a[k]);
    }
    return FourBarType::planar;
  }
  throw std::invalid_argument(
      "four-bar: neither planar (every twist 0 or pi) nor spherical (every length and offset 0)");
}

void check_joint(int joint, const char* name) {
  if (joint < 0 || joint > 3) bad(std::string("four-bar: ") + name + " joint must be in 0..3", joint);
}

// The planar four-bar written with every twist 0: axes whose direction is
// opposite to axis 0's are flipped (axis_flipped), so their angles change
// sign. `flipped[k]` says which; `closes` is false when the twists cannot be
// made 0 (an odd number of pi) or the offsets do not sum to zero.
struct PlanarRepresentation {
  LoopGeometry geometry;
  std::array<bool, 4> flipped{};
  bool closes = true;
};

PlanarRepresentation planar_representation(const LoopGeometry& g) {
  PlanarRepresentation w;
  w.geometry = g;
  bool opposite = false;  // axis k's direction against axis 0's
  for (int k = 1; k < 4; ++k) {
    opposite = opposite != (std::cos(g.alpha[k - 1]) < 0.0);
    w.flipped[static_cast<size_t>(k)] = opposite;
    if (opposite) w.geometry = axis_flipped(w.geometry, k);
  }
  if (opposite != (std::cos(g.alpha[3]) < 0.0)) w.closes = false;  // back at axis 0 reversed
  for (int k = 0; k < 4; ++k) w.geometry.alpha[k] = 0.0;
  if (std::abs(w.geometry.d.sum()) > kTolerance * std::max(1.0, length_scale(g))) w.closes = false;
  return w;
}

// Planar poses with joint 0 at theta and every twist 0: J1 = a1 (cos, sin),
// J4 = (-a4, 0) in frame 0 (link 4 arrives along x0); J3 at distance a2 from
// J1 and a3 from J4 (circle intersection), each link's direction phi_k, and
// theta_k = phi_k - phi_{k-1}.
std::vector<JointVector> planar_poses_at_zero(const LoopGeometry& g, double theta) {
  std::vector<JointVector> out;
  const Eigen::Vector2d j1(g.a[0] * std::cos(theta), g.a[0] * std::sin(theta)), j3(-g.a[3], 0.0);
  const Eigen::Vector2d v = j3 - j1;
  const double delta = v.norm();
  const double scale = std::max({g.a[1] * g.a[1], g.a[2] * g.a[2], delta * delta});
  if (!(delta > kTolerance * std::sqrt(scale))) return out;  // J1 on J4: no isolated pose
  const double x = (g.a[1] * g.a[1] - g.a[2] * g.a[2] + delta * delta) / (2.0 * delta);
  const double h2 = g.a[1] * g.a[1] - x * x;
  if (h2 < -kTolerance * scale) return out;
  const double h = std::sqrt(std::max(0.0, h2));
  const Eigen::Vector2d along = v / delta, across(-along.y(), along.x());
  for (double sign : {1.0, -1.0}) {
    const Eigen::Vector2d j2 = j1 + x * along + sign * h * across;
    const double phi1 = std::atan2(j2.y() - j1.y(), j2.x() - j1.x());
    const double phi2 = std::atan2(j3.y() - j2.y(), j3.x() - j2.x());
    JointVector t(4);
    t << wrap_angle(theta), wrap_angle(phi1 - theta), wrap_angle(phi2 - phi1), wrap_angle(-phi2);
    out.push_back(t);
    if (h2 <= 0.0) break;  // a dead point: one pose
  }
  return out;
}

// Spherical poses with joint 0 at theta. Axis 2 seen from both sides:
// Rx(alpha4) Rz(theta1) Rx(alpha1) Rz(theta2) Rx(alpha2) e_z = Rz(-theta4) Rx(-alpha3) e_z;
// the z components give m . Rz(theta2) w1 = cos(alpha3) (m the third row of
// M = Rx(alpha4) Rz(theta1) Rx(alpha1), m_z the cosine of the diagonal arc
// between axes 4 and 2), a sine in theta2; x and y then give theta4, and
// theta3 is what the rotation product leaves.
std::vector<JointVector> spherical_poses_at_zero(const LoopGeometry& g, double theta) {
  std::vector<JointVector> out;
  const double s1 = std::sin(g.alpha[1]), c1 = std::cos(g.alpha[1]);
  const double s2 = std::sin(g.alpha[2]), c2 = std::cos(g.alpha[2]);
  const auto rx = [](double a) { return Eigen::AngleAxisd(a, Vector3::UnitX()).toRotationMatrix(); };
  const auto rz = [](double a) { return Eigen::AngleAxisd(a, Vector3::UnitZ()).toRotationMatrix(); };
  const Matrix3 M = rx(g.alpha[3]) * rz(theta) * rx(g.alpha[0]);
  const Vector3 m = M.row(2).transpose();
  const double radius = std::hypot(m.x(), m.y());
  // s1 (m_x sin theta2 - m_y cos theta2) = c2 - c1 m_z, i.e. s1 radius sin(theta2 - psi) = c2 - c1 m_z.
  const double rhs = c2 - c1 * m.z(), amplitude = s1 * radius;
  if (std::abs(amplitude) <= kTolerance) return out;  // axes 4 and 2 coincide: no isolated pose
  const double q = rhs / amplitude;
  if (std::abs(q) > 1.0 + kTolerance) return out;
  const double psi = std::atan2(m.y(), m.x());
  const double root = std::asin(std::clamp(q, -1.0, 1.0));
  const int count = std::abs(q) >= 1.0 ? 1 : 2;
  for (int i = 0; i < count; ++i) {
    const double theta2 = psi + (i == 0 ? root : kPi - root);
    const Vector3 w1(0.0, -s1, c1);
    const Vector3 v = M * rz(theta2) * w1;  // = Rz(-theta4) (0, s2, c2)
    const double theta4 = std::atan2(s2 * v.x(), s2 * v.y());
    // Rz(theta3) = (R1 R2)^T R4^T Rx(-alpha3).
    const Matrix3 r12 = rz(theta) * rx(g.alpha[0]) * rz(theta2) * rx(g.alpha[1]);
    const Matrix3 r4 = rz(theta4) * rx(g.alpha[3]);
    const Matrix3 r3 = r12.transpose() * r4.transpose() * rx(-g.alpha[2]);
    JointVector t(4);
    t << wrap_angle(theta), wrap_angle(theta2), std::atan2(r3(1, 0), r3(0, 0)), wrap_angle(theta4);
    out.push_back(t);
  }
  return out;
}

// The set of cos(theta) of joint 0 over every pose: [lo, hi], from the
// diagonal between joints 4 and 2 (planar: its length, spherical: its arc),
// which links 2 and 3 must be able to span. Empty when lo > hi.
struct CosineRange {
  double lo, hi;
};

CosineRange cosine_range_at_zero(const LoopGeometry& g, FourBarType type) {
  if (type == FourBarType::planar) {
    // |J2 - J4|^2 = a1^2 + a4^2 + 2 a1 a4 cos(theta1) in [(a2 - a3)^2, (a2 + a3)^2].
    const double a0 = g.a[0], a1 = g.a[1], a2 = g.a[2], a3 = g.a[3];
    const double base = a0 * a0 + a3 * a3, twice = 2.0 * a0 * a3;
    return {((a1 - a2) * (a1 - a2) - base) / twice, ((a1 + a2) * (a1 + a2) - base) / twice};
  }
  // m_z = c4 c1 - s4 s1 cos(theta1) must lie in [cos(|alpha2| + |alpha3|), cos(|alpha2| - |alpha3|)].
  const double s = std::sin(g.alpha[3]) * std::sin(g.alpha[0]), c = std::cos(g.alpha[3]) * std::cos(g.alpha[0]);
  const double t1 = std::abs(g.alpha[1]), t2 = std::abs(g.alpha[2]);
  const double m_lo = std::cos(t1 + t2), m_hi = std::cos(t1 - t2);
  const double x = (c - m_hi) / s, y = (c - m_lo) / s;
  return {std::min(x, y), std::max(x, y)};
}

// The angles theta with cos(theta) in the range, as one or two intervals.
std::vector<AngleInterval> angles_of(CosineRange r) {
  if (r.lo > r.hi + kTolerance || r.lo > 1.0 + kTolerance || r.hi < -1.0 - kTolerance) return {};
  const bool zero = r.hi >= 1.0 - kTolerance, half_turn = r.lo <= -1.0 + kTolerance;
  const double from_hi = std::acos(std::clamp(r.hi, -1.0, 1.0)), from_lo = std::acos(std::clamp(r.lo, -1.0, 1.0));
  if (zero && half_turn) return {{-kPi, kPi, true}};
  if (zero) return {{-from_lo, from_lo, false}};
  if (half_turn) return {{from_hi, 2.0 * kPi - from_hi, false}};
  return {{from_hi, from_lo, false}, {-from_lo, -from_hi, false}};
}

// Every joint's angle set over all poses (both circuits together).
std::array<std::vector<AngleInterval>, 4> joint_sets(const LoopGeometry& g, FourBarType type) {
  std::array<std::vector<AngleInterval>, 4> sets;
  LoopGeometry written = g;
  if (type == FourBarType::planar) {
    const PlanarRepresentation w = planar_representation(g);
    if (!w.closes) return sets;
    written = w.geometry;  // flips change angles' signs only, and the sets are symmetric
  }
  for (int j = 0; j < 4; ++j) {
    sets[static_cast<size_t>(j)] = angles_of(cosine_range_at_zero(relabelled(written, j), type));
  }
  for (const auto& s : sets) {
    if (s.empty()) return {};
  }
  return sets;
}

double middle(const AngleInterval& i) { return 0.5 * (i.lo + i.hi); }

}  // namespace

// ---------------------------------------------------------------------------
// Axes and poses

std::vector<Axis> joint_axes(const LoopGeometry& g, const JointVector& theta) {
  validate_geometry(g);
  if (theta.size() != g.joints()) bad("joint_axes: angle count", static_cast<double>(theta.size()));
  std::vector<Axis> out;
  for (int k = 0; k < g.joints(); ++k) {
    const Eigen::Isometry3d f = forward_transform(g, theta, k);
    out.push_back({f.translation(), f.linear().col(2)});
  }
  return out;
}

PosedLoop dh_from_axes(std::span<const Axis> axes) {
  const int n = static_cast<int>(axes.size());
  if (n < kMinJoints || n > kMaxJoints) bad("dh_from_axes: axis count must be in [4, 8]", n);
  for (int k = 0; k < n; ++k) {
    const Axis& axis = axes[static_cast<size_t>(k)];
    if (!axis.point.allFinite() || !axis.direction.allFinite()) {
      bad("dh_from_axes: axis " + std::to_string(k) + " is not finite", k);
    }
    if (std::abs(axis.direction.norm() - 1.0) > 1e-9) {
      bad("dh_from_axes: axis " + std::to_string(k) + " direction must be a unit vector, norm", axis.direction.norm());
    }
  }
  std::vector<Vector3> x(static_cast<size_t>(n)), out_foot(static_cast<size_t>(n)), in_foot(static_cast<size_t>(n));
  PosedLoop r;
  r.geometry.a.resize(n);
  r.geometry.alpha.resize(n);
  r.geometry.d.resize(n);
  r.theta.resize(n);
  for (int k = 0; k < n; ++k) {
    const Axis& u = axes[static_cast<size_t>(k)];
    const Axis& v = axes[static_cast<size_t>((k + 1) % n)];
    // Closest points u.point + s u.direction and v.point + t v.direction.
    double s = 0.0, t = 0.0;
    if (!common_normal_feet(u.point, u.direction, v.point, v.direction, 1e-12, s, t)) {
      // Parallel axes: every normal is common; take the one through the
      // incoming normal's foot on axis k (d_k = 0).
      s = k > 0 ? (in_foot[static_cast<size_t>(k)] - u.point).dot(u.direction) : 0.0;
      t = (u.point + s * u.direction - v.point).dot(v.direction);
    }
    const Vector3 fu = u.point + s * u.direction, fv = v.point + t * v.direction;
    Vector3 dir = fv - fu;
    double a = dir.norm();
    if (a > 1e-12) {
      dir /= a;
    } else {  // intersecting axes: the normal is the cross product
      dir = u.direction.cross(v.direction).normalized();
      a = 0.0;
    }
    x[static_cast<size_t>(k)] = dir;
    out_foot[static_cast<size_t>(k)] = fu;
    in_foot[static_cast<size_t>((k + 1) % n)] = fv;
    r.geometry.a[k] = a;
    r.geometry.alpha[k] = std::atan2(u.direction.cross(v.direction).dot(dir), u.direction.dot(v.direction));
  }
  for (int k = 0; k < n; ++k) {
    const Vector3& prev = x[static_cast<size_t>((k + n - 1) % n)];
    const Vector3& direction = axes[static_cast<size_t>(k)].direction;
    r.geometry.d[k] = (out_foot[static_cast<size_t>(k)] - in_foot[static_cast<size_t>(k)]).dot(direction);
    r.theta[k] = std::atan2(prev.cross(x[static_cast<size_t>(k)]).dot(direction), prev.dot(x[static_cast<size_t>(k)]));
  }
  return r;
}

// ---------------------------------------------------------------------------
// Four-bars

std::vector<JointVector> four_bar_poses(const LoopGeometry& g, int input, double input_angle) {
  const FourBarType type = four_bar_type(g);
  check_joint(input, "input");
  if (!std::isfinite(input_angle)) bad("four_bar_poses: input_angle", input_angle);
  // Solve with the input as joint 0 (relabelled), then map the angles back.
  std::vector<JointVector> poses;
  if (type == FourBarType::planar) {
    const PlanarRepresentation w = planar_representation(relabelled(g, input));
    if (!w.closes) return {};
    for (JointVector t : planar_poses_at_zero(w.geometry, input_angle)) {  // joint 0 is never flipped
      for (int k = 0; k < 4; ++k) {
        if (w.flipped[static_cast<size_t>(k)]) t[k] = -t[k];
      }
      poses.push_back(t);
    }
  } else {
    poses = spherical_poses_at_zero(relabelled(g, input), input_angle);
  }
  for (JointVector& t : poses) {
    t = relabelled_angles(t, -input);
    t[input] = input_angle;  // exactly as asked
  }
  return poses;
}

std::vector<AngleInterval> four_bar_joint_ranges(const LoopGeometry& g, int joint) {
  const FourBarType type = four_bar_type(g);
  check_joint(joint, "range");
  const std::array<std::vector<AngleInterval>, 4> sets = joint_sets(g, type);
  if (sets[0].empty()) return {};
  // A joint that never reaches 0 or pi keeps its sign: two circuits, mirror
  // images of each other.
  int rocker = -1;
  for (int j = 0; j < 4 && rocker < 0; ++j) {
    if (sets[static_cast<size_t>(j)].size() == 2) rocker = j;
  }
  const std::vector<AngleInterval>& own = sets[static_cast<size_t>(joint)];
  if (rocker < 0) return own;
  if (own.size() == 1) return {own[0], own[0]};  // turns fully on each circuit
  // Circuit 0: the rocker's positive interval. The sign of `joint` there,
  // read off one pose of that circuit.
  const AngleInterval& positive = sets[static_cast<size_t>(rocker)][0];
  const std::vector<JointVector> poses = four_bar_poses(g, rocker, middle(positive));
  if (poses.empty()) return {};
  const bool same = poses.front()[joint] > 0.0;
  return same ? std::vector<AngleInterval>{own[0], own[1]} : std::vector<AngleInterval>{own[1], own[0]};
}

const char* to_string(FourBarKind kind) {
  switch (kind) {
    case FourBarKind::crank_rocker:
      return "crank_rocker";
    case FourBarKind::rocker_crank:
      return "rocker_crank";
    case FourBarKind::double_crank:
      return "double_crank";
    case FourBarKind::double_rocker:
      return "double_rocker";
    case FourBarKind::triple_rocker:
      return "triple_rocker";
    case FourBarKind::change_point:
      return "change_point";
  }
  return "unknown";
}

FourBarKind planar_four_bar_kind(const LoopGeometry& g, int input) {
  if (four_bar_type(g) != FourBarType::planar) {
    throw std::invalid_argument("planar_four_bar_kind: the four-bar is not planar");
  }
  check_joint(input, "input");
  std::array<double, 4> sorted{g.a[0], g.a[1], g.a[2], g.a[3]};
  std::sort(sorted.begin(), sorted.end());
  const double excess = sorted[0] + sorted[3] - sorted[1] - sorted[2];
  const double perimeter = g.a.sum();
  if (std::abs(excess) <= kTolerance * perimeter) return FourBarKind::change_point;
  if (excess > 0.0) return FourBarKind::triple_rocker;
  // Grashof: the shortest link (unique when the inequality is strict) turns fully
  // relative to its neighbours.
  int shortest = 0;
  for (int k = 1; k < 4; ++k) {
    if (g.a[k] < g.a[shortest]) shortest = k;
  }
  const int ground = (input + 3) % 4, crank = input, coupler = (input + 1) % 4;
  if (shortest == ground) return FourBarKind::double_crank;
  if (shortest == crank) return FourBarKind::crank_rocker;
  if (shortest == coupler) return FourBarKind::double_rocker;
  return FourBarKind::rocker_crank;
}

FourBarKind four_bar_kind(const LoopGeometry& g, int input) {
  check_joint(input, "input");
  const std::vector<AngleInterval> in = four_bar_joint_ranges(g, input);
  const std::vector<AngleInterval> out = four_bar_joint_ranges(g, (input + 3) % 4);
  if (in.empty()) throw std::invalid_argument("four_bar_kind: the four-bar has no pose");
  if (in.size() == 1) {
    for (int j = 0; j < 4; ++j) {
      const std::vector<AngleInterval> r = four_bar_joint_ranges(g, j);
      if (r[0].full_turn) return FourBarKind::change_point;
    }
    return FourBarKind::triple_rocker;
  }
  if (in[0].full_turn && out[0].full_turn) return FourBarKind::double_crank;
  if (in[0].full_turn) return FourBarKind::crank_rocker;
  if (out[0].full_turn) return FourBarKind::rocker_crank;
  return FourBarKind::double_rocker;
}

LoopGeometry parallelogram_four_bar(double a, double b) {
  if (!(a > 0.0) || !std::isfinite(a)) bad("parallelogram_four_bar: a must be > 0", a);
  if (!(b > 0.0) || !std::isfinite(b)) bad("parallelogram_four_bar: b must be > 0", b);
  return planar_four_bar(a, b, a, b);
}

// ---------------------------------------------------------------------------
// Trihedral Bricard 6R

namespace {

void check_trihedral(const TrihedralBricard& p) {
  for (int k = 0; k < 5; ++k) {
    const double a = p.a[static_cast<size_t>(k)];
    if (!(a > 0.0) || !std::isfinite(a)) bad("trihedral_bricard: a" + std::to_string(k + 1) + " must be > 0", a);
  }
  if (p.sign_pattern > 63u) bad("trihedral_bricard: sign_pattern must be in 0..63", p.sign_pattern);
  if (p.branch > 15u) bad("trihedral_bricard: branch must be in 0..15", p.branch);
}

double a6_squared(const TrihedralBricard& p) {
  const auto& a = p.a;
  return a[0] * a[0] - a[1] * a[1] + a[2] * a[2] - a[3] * a[3] + a[4] * a[4];
}

}  // namespace

double trihedral_bricard_a6(const TrihedralBricard& p) {
  check_trihedral(p);
  const double s = a6_squared(p);
  if (!(s > 0.0)) bad("trihedral_bricard: a1^2 - a2^2 + a3^2 - a4^2 + a5^2 must be > 0", s);
  return std::sqrt(s);
}

std::optional<PosedLoop> trihedral_bricard(const TrihedralBricard& parameters, double p) {
  const double a6 = trihedral_bricard_a6(parameters);
  if (!std::isfinite(p)) bad("trihedral_bricard: p", p);
  const std::array<double, 6> a{parameters.a[0], parameters.a[1], parameters.a[2],
                                parameters.a[3], parameters.a[4], a6};
  // The roots: face f's minus root where its bit is set; the parity of the
  // three bits is the pattern's (see the header).
  const unsigned parity = static_cast<unsigned>(std::popcount(parameters.sign_pattern)) & 1u;
  const unsigned b0 = parameters.branch & 1u, b1 = (parameters.branch >> 1) & 1u;
  const std::array<double, 3> root{b0 ? -1.0 : 1.0, b1 ? -1.0 : 1.0, (parity ^ b0 ^ b1) ? -1.0 : 1.0};
  // p_k = (B - A) . u_k along the edges, from a1^2 - a2^2 = p3^2 - p1^2 and
  // a3^2 - a4^2 = p5^2 - p3^2.
  const double p3_squared = p * p + a[0] * a[0] - a[1] * a[1];
  const double p5_squared = p3_squared + a[2] * a[2] - a[3] * a[3];
  if (p3_squared < 0.0 || p5_squared < 0.0) return std::nullopt;
  const std::array<double, 3> q{p, ((parameters.branch >> 2) & 1u ? -1.0 : 1.0) * std::sqrt(p3_squared),
                                ((parameters.branch >> 3) & 1u ? -1.0 : 1.0) * std::sqrt(p5_squared)};
  // In face (u_i, u_j) B's foot F has F . u_i = p_i, F . u_j = p_j and lies
  // at distance a_{2f+1} from edge u_i and a_{2f+2} from u_j: the face's
  // angle has cos = (p_i p_j +- a a') / |F|^2, |F|^2 = p_i^2 + a^2.
  std::array<double, 3> cosine{};
  for (size_t f = 0; f < 3; ++f) {
    const double pi = q[f], pj = q[(f + 1) % 3], ai = a[2 * f], aj = a[2 * f + 1];
    cosine[f] = std::clamp((pi * pj + root[f] * ai * aj) / (pi * pi + ai * ai), -1.0, 1.0);
  }
  // The trihedron from its three face angles: u1 = x, u3 in the xy plane, u5 above it.
  const double sine = std::sqrt(1.0 - cosine[0] * cosine[0]);
  if (sine < 1e-9) return std::nullopt;  // u1 and u3 collinear: a flat trihedron
  const double y = (cosine[1] - cosine[2] * cosine[0]) / sine;
  const double z_squared = 1.0 - cosine[2] * cosine[2] - y * y;
  if (z_squared < 1e-12) return std::nullopt;  // the three face angles make no (or a flat) trihedron
  const Vector3 u1 = Vector3::UnitX(), u3(cosine[0], sine, 0.0), u5(cosine[2], y, std::sqrt(z_squared));
  Matrix3 edges;
  edges.row(0) = u1.transpose();
  edges.row(1) = u3.transpose();
  edges.row(2) = u5.transpose();
  const Vector3 B = edges.partialPivLu().solve(Vector3(q[0], q[1], q[2]));
  std::array<Axis, 6> axes{Axis{Vector3::Zero(), u1}, Axis{B, u1.cross(u3).normalized()},
                           Axis{Vector3::Zero(), u3}, Axis{B, u3.cross(u5).normalized()},
                           Axis{Vector3::Zero(), u5}, Axis{B, u5.cross(u1).normalized()}};
  // The pattern the construction gives, then axes flipped to the one asked
  // for: flipping axis k changes twists k-1 and k, so flips f with
  // f_{k+1} = f_k xor (change of twist k), f_0 = 0, which closes since the
  // parities agree.
  const PosedLoop raw = dh_from_axes(axes);
  unsigned got = 0;
  for (int k = 0; k < 6; ++k) {
    if (raw.geometry.alpha[k] < 0.0) got |= 1u << k;
  }
  const unsigned change = got ^ parameters.sign_pattern;
  bool flip = false;
  for (int k = 1; k < 6; ++k) {
    flip = flip != (((change >> (k - 1)) & 1u) != 0u);
    if (flip) axes[static_cast<size_t>(k)].direction = -axes[static_cast<size_t>(k)].direction;
  }
  PosedLoop out = dh_from_axes(axes);
  // The loop exactly as the parameters say; the pose is the construction's.
  for (int k = 0; k < 6; ++k) {
    out.geometry.a[k] = a[static_cast<size_t>(k)];
    out.geometry.alpha[k] = ((parameters.sign_pattern >> k) & 1u) ? -kPi / 2 : kPi / 2;
    out.geometry.d[k] = 0.0;
  }
  return out;
}

// ---------------------------------------------------------------------------
// Bennett loops fused in space

namespace {

void check_twist(double twist, const std::string& name) {
  if (!std::isfinite(twist) || std::abs(std::sin(twist)) < 1e-9) bad(name + " must be away from 0 and pi", twist);
}

void check_pair(const BennettPairParameters& p, const char* who) {
  if (!(p.b > 0.0) || !std::isfinite(p.b)) bad(std::string(who) + ": b must be > 0", p.b);
  check_twist(p.beta, std::string(who) + ": beta");
  check_twist(p.alpha, std::string(who) + ": alpha");
  check_twist(p.gamma, std::string(who) + ": gamma");
}

// Bennett loop (a, alpha), (b, beta), (a, alpha), (b, beta), zero offsets.
LoopGeometry bennett(double a, double alpha, double b, double beta) {
  return four_bar(a, b, a, b, alpha, beta, alpha, beta);
}

// A closed pose at joint 0's angle t, by the loop's setup.
JointVector bennett_pose(const LoopGeometry& g, double t) {
  const bool asymmetric = std::sin(g.alpha[0]) * std::sin(g.alpha[1]) > 0.0;
  return asymmetric ? bennett_angles(g, t) : bennett_angles_line_symmetric(g, t);
}

// The Bennett loop (a, alpha), (b, beta), (a, alpha), (b, beta) whose link a
// has Bennett's ratio with the link (b, beta): a = b |sin alpha / sin beta|.
LoopGeometry bennett_with_link(double b, double beta, double alpha) {
  return bennett(b * std::abs(std::sin(alpha) / std::sin(beta)), alpha, b, beta);
}

// Loop 1 (ABCD) and loop 2 (AFED), both with frame 0 on axis A and x0 along
// the shared link DA.
std::pair<LoopGeometry, LoopGeometry> pair_loops(const BennettPairParameters& p) {
  return {bennett_with_link(p.b, p.beta, p.alpha), bennett_with_link(p.b, p.beta, p.gamma)};
}

std::vector<Axis> goldberg_axes(const Goldberg5R& p, double t) {
  const auto [l1, l2] = pair_loops(p.loops);
  const std::vector<Axis> x1 = joint_axes(l1, bennett_pose(l1, t));
  const std::vector<Axis> x2 = joint_axes(l2, bennett_pose(l2, t + p.phi));
  return {x1[1], x1[2], x1[3], x2[2], x2[1]};
}

}  // namespace

PosedLoop goldberg_5r(const Goldberg5R& p, double t) {
  check_pair(p.loops, "goldberg_5r");
  if (!std::isfinite(p.phi)) bad("goldberg_5r: phi", p.phi);
  if (!std::isfinite(t)) bad("goldberg_5r: t", t);
  const std::vector<Axis> axes = goldberg_axes(p, t);
  return dh_from_axes(axes);
}

JointVector goldberg_5r_pose(const Goldberg5R& p, double t) { return goldberg_5r(p, t).theta; }

PosedLoop bennett_pair_6r(const BennettPairParameters& p, double t1, double t2) {
  check_pair(p, "bennett_pair_6r");
  if (!std::isfinite(t1)) bad("bennett_pair_6r: t1", t1);
  if (!std::isfinite(t2)) bad("bennett_pair_6r: t2", t2);
  const auto [l1, l2] = pair_loops(p);
  const std::vector<Axis> x1 = joint_axes(l1, bennett_pose(l1, t1)), x2 = joint_axes(l2, bennett_pose(l2, t2));
  const std::vector<Axis> axes{x1[0], x1[1], x1[2], x1[3], x2[2], x2[1]};
  return dh_from_axes(axes);
}

JointVector bennett_pair_6r_pose(const BennettPairParameters& p, double t1, double t2) {
  return bennett_pair_6r(p, t1, t2).theta;
}

PosedLoop three_bennett_6r(const ThreeBennett6R& p, double t) {
  if (p.link < 0 || p.link > 4) bad("three_bennett_6r: link must be in 0..4", p.link);
  check_twist(p.gamma, "three_bennett_6r: gamma");
  if (!std::isfinite(p.phi)) bad("three_bennett_6r: phi", p.phi);
  const PosedLoop five = goldberg_5r(p.goldberg, t);
  const int P = p.link;
  const double a_pq = five.geometry.a[P], alpha_pq = five.geometry.alpha[P];
  if (!(a_pq > 1e-9)) bad("three_bennett_6r: the 5R link PQ has no length", a_pq);
  check_twist(alpha_pq, "three_bennett_6r: the 5R link PQ's twist");
  // The third loop P Q R S: links PQ (a_pq, alpha_pq), QR (c, gamma), RS, SP.
  const double c = a_pq * std::abs(std::sin(p.gamma) / std::sin(alpha_pq));
  const LoopGeometry third = bennett(a_pq, alpha_pq, c, p.gamma);
  // Its frame 0 on axis P with x along S -> P: the 5R's frame at P moved to
  // the outgoing normal's foot (the third loop has no offsets) and turned by
  // phi; its angle at P is then the 5R's minus phi, and its frame 1 is the
  // 5R's frame at Q.
  const Eigen::Isometry3d at_p = forward_transform(five.geometry, five.theta, P) *
                                 Eigen::Translation3d(0.0, 0.0, five.geometry.d[P]) *
                                 Eigen::AngleAxisd(p.phi, Vector3::UnitZ());
  const std::vector<Axis> local = joint_axes(third, bennett_pose(third, five.theta[P] - p.phi));
  const auto placed = [&](const Axis& axis) { return Axis{at_p * axis.point, at_p.linear() * axis.direction}; };
  const std::vector<Axis> five_axes = joint_axes(five.geometry, five.theta);
  std::vector<Axis> axes;
  for (int k = 0; k < 5; ++k) {
    if (k == P) {
      axes.push_back(placed(local[3]));  // S
      axes.push_back(placed(local[2]));  // R
    } else {
      axes.push_back(five_axes[static_cast<size_t>(k)]);
    }
  }
  return dh_from_axes(axes);
}

JointVector three_bennett_6r_pose(const ThreeBennett6R& p, double t) { return three_bennett_6r(p, t).theta; }

// ---------------------------------------------------------------------------
// Waldron's hybrid 6R

PosedLoop waldron_hybrid_6r(const WaldronHybrid6R& p, double t) {
  if (!(p.b > 0.0) || !std::isfinite(p.b)) bad("waldron_hybrid_6r: b must be > 0", p.b);
  if (!(p.e > 0.0) || !std::isfinite(p.e)) bad("waldron_hybrid_6r: e must be > 0", p.e);
  check_twist(p.beta, "waldron_hybrid_6r: beta");
  check_twist(p.alpha, "waldron_hybrid_6r: alpha");
  check_twist(p.epsilon, "waldron_hybrid_6r: epsilon");
  check_twist(p.gamma, "waldron_hybrid_6r: gamma");
  for (double v : {p.turn, p.slide, p.phase, t}) {
    if (!std::isfinite(v)) bad("waldron_hybrid_6r: turn, slide, phase and t must be finite", v);
  }
  // Each loop with frame 0 on axis A (the z axis through the origin), link
  // 3 (DA, GA) the fixed body and link 0 (AB, AE) turned by the angle at A.
  const LoopGeometry first = bennett_with_link(p.b, p.beta, p.alpha);
  const LoopGeometry second = bennett_with_link(p.e, p.epsilon, p.gamma);
  const std::vector<Axis> x1 = joint_axes(first, bennett_pose(first, t));
  const Eigen::Isometry3d place = Eigen::Translation3d(0.0, 0.0, p.slide) * Eigen::AngleAxisd(p.turn, Vector3::UnitZ());
  std::vector<Axis> x2 = joint_axes(second, bennett_pose(second, t + p.phase));
  for (Axis& axis : x2) axis = {place * axis.point, place.linear() * axis.direction};
  const std::vector<Axis> axes{x1[1], x1[2], x1[3], x2[3], x2[2], x2[1]};  // B C D G F E
  return dh_from_axes(axes);
}

// ---------------------------------------------------------------------------
// The double-Goldberg 6R

PosedLoop double_goldberg_6r(const DoubleGoldberg6R& p, double t) {
  check_pair(p.goldberg.loops, "double_goldberg_6r");
  check_twist(p.epsilon, "double_goldberg_6r: epsilon");
  for (double v : {p.goldberg.phi, p.psi, t}) {
    if (!std::isfinite(v)) bad("double_goldberg_6r: phi, psi and t must be finite", v);
  }
  // Every loop with frame 0 on axis A and x0 along the link arriving at A:
  // the first's and the second's along DA, the third's along YA, which is DA
  // turned by psi.
  const auto [first, second] = pair_loops(p.goldberg.loops);
  const double a = first.a[0], alpha = first.alpha[0];
  const LoopGeometry third = bennett(a, alpha, a * std::abs(std::sin(p.epsilon) / std::sin(alpha)), p.epsilon);
  const std::vector<Axis> x1 = joint_axes(first, bennett_pose(first, t));
  const std::vector<Axis> x2 = joint_axes(second, bennett_pose(second, t + p.goldberg.phi));
  std::vector<Axis> x3 = joint_axes(third, bennett_pose(third, t - p.psi));
  const Eigen::Isometry3d turn(Eigen::AngleAxisd(p.psi, Vector3::UnitZ()));
  for (Axis& axis : x3) axis = {turn * axis.point, turn.linear() * axis.direction};
  const std::vector<Axis> axes{x1[1], x3[2], x3[3], x1[3], x2[2], x2[1]};  // B X Y D E F
  return dh_from_axes(axes);
}

// ---------------------------------------------------------------------------
// Sarrus 6R

namespace {

// The middle joint of a planar chain: where circles of radius r_from about
// `from` and r_to about `to` meet, in the plane spanned by e1 and e2
// (orthonormal), on the side `elbow` picks; nothing where they do not meet.
std::optional<Vector3> elbow_point(const Vector3& from, const Vector3& to, double r_from, double r_to,
                                   const Vector3& e1, const Vector3& e2, bool elbow) {
  const Eigen::Vector2d p(from.dot(e1), from.dot(e2)), q(to.dot(e1), to.dot(e2));
  const Eigen::Vector2d pq = q - p;
  const double dist = pq.norm();
  if (!(dist > 0.0)) return std::nullopt;
  const double along = (dist * dist + r_from * r_from - r_to * r_to) / (2.0 * dist);
  const double h2 = r_from * r_from - along * along;
  if (h2 < 0.0) return std::nullopt;
  const Eigen::Vector2d unit = pq / dist, normal(-unit.y(), unit.x());
  const Eigen::Vector2d m = p + along * unit + (elbow ? 1.0 : -1.0) * std::sqrt(h2) * normal;
  return Vector3(m.x() * e1 + m.y() * e2);
}

}  // namespace

std::optional<PosedLoop> sarrus_6r(const Sarrus6R& p, double s) {
  check_twist(p.gamma, "sarrus_6r: gamma");
  for (double r : {p.r_base_u, p.r_top_u, p.r_base_v, p.r_top_v}) {
    if (!(r > 0.0) || !std::isfinite(r)) bad("sarrus_6r: the chains' link lengths must be > 0", r);
  }
  for (const Vector3* point : {&p.base_u, &p.top_u, &p.base_v, &p.top_v}) {
    if (!point->allFinite()) bad("sarrus_6r: a point is not finite", point->norm());
  }
  if (!std::isfinite(s)) bad("sarrus_6r: s", s);
  const Vector3 w = Vector3::UnitX(), u = Vector3::UnitZ();
  const Vector3 v(0.0, -std::sin(p.gamma), std::cos(p.gamma));
  const Vector3 top_u = p.top_u + s * w, top_v = p.top_v + s * w;
  // The u chain in the plane normal to u (spanned by w and u x w), the v
  // chain in the plane normal to v (w and v x w).
  const std::optional<Vector3> middle_u = elbow_point(p.base_u, top_u, p.r_base_u, p.r_top_u, w, u.cross(w), p.elbow_u);
  const std::optional<Vector3> middle_v = elbow_point(p.base_v, top_v, p.r_base_v, p.r_top_v, w, v.cross(w), p.elbow_v);
  if (!middle_u || !middle_v) return std::nullopt;
  // The base's v axis first: link 1 (v -> u) is not between parallel axes,
  // so the normals of the parallel links run from its foot (dh_from_axes).
  const std::vector<Axis> axes{{p.base_v, v}, {p.base_u, u}, {*middle_u, u}, {top_u, u}, {top_v, v}, {*middle_v, v}};
  return dh_from_axes(axes);
}

// ---------------------------------------------------------------------------
// Hooke's double-spherical 6R

namespace {

// The unit direction at dot products c_from with `from` and c_to with `to`
// (unit, not parallel) on the side of the plane of from and to where
// from . (z x to) has the sign `side`; nothing where no direction has them.
std::optional<Vector3> middle_direction(const Vector3& from, const Vector3& to, double c_from, double c_to,
                                        double side) {
  // z = p from + q to + r (from x to): p + q g = c_from, p g + q = c_to.
  const double g = from.dot(to), sin2 = 1.0 - g * g;
  if (!(sin2 > 1e-12)) return std::nullopt;
  const double p = (c_from - g * c_to) / sin2, q = (c_to - g * c_from) / sin2;
  const double r2 = (1.0 - (p * p + q * q + 2.0 * p * q * g)) / sin2;
  if (r2 < -kTolerance) return std::nullopt;
  // from . (z x to) = z . (to x from) = -r sin2.
  const double r = (side > 0.0 ? -1.0 : 1.0) * std::sqrt(std::max(0.0, r2));
  return Vector3(p * from + q * to + r * from.cross(to)).normalized();
}

}  // namespace

std::optional<PosedLoop> hooke_6r(const Hooke6R& p, double t) {
  if (!p.o1.allFinite() || !p.o2.allFinite()) bad("hooke_6r: a centre is not finite", (p.o2 - p.o1).norm());
  if (!((p.o2 - p.o1).norm() > 1e-9)) bad("hooke_6r: the centres must be apart, distance", (p.o2 - p.o1).norm());
  if (!std::isfinite(t)) bad("hooke_6r: t", t);
  std::array<Vector3, 6> u;
  for (size_t k = 0; k < 6; ++k) {
    if (!p.u[k].allFinite() || !(p.u[k].norm() > 1e-9)) bad("hooke_6r: direction " + std::to_string(k), p.u[k].norm());
    u[k] = p.u[k].normalized();
  }
  const double side1 = u[0].dot(u[1].cross(u[2])), side2 = u[3].dot(u[4].cross(u[5]));
  if (!(std::abs(side1) > 1e-9)) bad("hooke_6r: u0, u1, u2 must not lie in one plane, det", side1);
  if (!(std::abs(side2) > 1e-9)) bad("hooke_6r: u3, u4, u5 must not lie in one plane, det", side2);
  // Link 3 turned by t about the line O1 O2 (both centres stay put).
  const Eigen::Matrix3d turn = Eigen::AngleAxisd(t, (p.o2 - p.o1).normalized()).toRotationMatrix();
  const Vector3 z3 = turn * u[2], z4 = turn * u[3];
  const std::optional<Vector3> z2 = middle_direction(u[0], z3, u[0].dot(u[1]), u[2].dot(u[1]), side1);
  const std::optional<Vector3> z5 = middle_direction(z4, u[5], u[3].dot(u[4]), u[5].dot(u[4]), side2);
  if (!z2 || !z5) return std::nullopt;
  const std::vector<Axis> axes{{p.o1, u[0]}, {p.o1, *z2}, {p.o1, z3}, {p.o2, z4}, {p.o2, *z5}, {p.o2, u[5]}};
  return dh_from_axes(axes);
}

// ---------------------------------------------------------------------------
// Angle-symmetric 6R with three pairs of parallel axes

namespace {

// The turn by `angle` about the line through `point` along the unit `direction`.
Eigen::Isometry3d turn_about(const Vector3& point, const Vector3& direction, double angle) {
  return Eigen::Translation3d(point) * Eigen::AngleAxisd(angle, direction) * Eigen::Translation3d(-point);
}

// x's part normal to the unit n.
Vector3 normal_part(const Vector3& x, const Vector3& n) { return x - x.dot(n) * n; }

// x made unit; refused, the message saying what is degenerate, unless
// |x| > 1e-9 scale: x is built from vectors of length about `scale`, so
// anything shorter is round-off or degenerate input, whatever the unit of
// length. A direction the caller gives has scale 0: any length but zero will
// do (stableNorm, so that neither a tiny nor a huge one under- or overflows).
Vector3 unit_or_throw(const Vector3& x, double scale, const std::string& what) {
  const double norm = x.stableNorm();
  if (!(norm > 1e-9 * scale) || !(norm > 0.0) || !std::isfinite(norm)) {
    bad("angle_symmetric_parallel_6r: " + what, norm);
  }
  return x / norm;
}

}  // namespace

PosedLoop angle_symmetric_parallel_6r(const AngleSymmetricParallel6R& p, double t) {
  const std::array<std::pair<const char*, const Vector3*>, 8> vectors{{{"u", &p.u},
                                                                       {"e1", &p.e1},
                                                                       {"v", &p.v},
                                                                       {"e4", &p.e4},
                                                                       {"h", &p.h},
                                                                       {"p1", &p.p1},
                                                                       {"p3", &p.p3},
                                                                       {"p4", &p.p4}}};
  for (const auto& [name, x] : vectors) {
    if (!x->allFinite())
      bad(std::string("angle_symmetric_parallel_6r: ") + name + " is not finite, |" + name + "|", x->norm());
  }
  for (const auto& [name, x] : {std::pair{"w_turn", p.w_turn}, std::pair{"g_length", p.g_length}, std::pair{"t", t}}) {
    if (!std::isfinite(x)) bad(std::string("angle_symmetric_parallel_6r: ") + name + " is not finite", x);
  }
  const Vector3 u = unit_or_throw(p.u, 0.0, "u has no length, |u|");
  const Vector3 e1 = normal_part(p.e1, u);
  unit_or_throw(e1, p.e1.norm(), "e1 has no part normal to u, its length");
  Vector3 v, e4, w, g;
  if (p.kind == ParallelPairsKind::general) {
    v = unit_or_throw(p.v, 0.0, "v has no length, |v|");
    e4 = normal_part(p.e4, v);
    unit_or_throw(e4, p.e4.norm(), "e4 has no part normal to v, its length");
    // P and Q have the length of the steps e1, e4 at most; their cross
    // product is compared with the square of that scale.
    const Vector3 P = u.cross(e1) + v.cross(e4), Q = e1 + e4;
    const double step = e1.norm() + e4.norm();
    w = unit_or_throw(P.cross(Q), step * step,
                      "u x e1 + v x e4 is parallel to e1 + e4, |(u x e1 + v x e4) x (e1 + e4)|");
    const Vector3 along = w.cross(P);
    const double q = along.dot(Q);
    if (!(std::abs(q) > 1e-9 * along.norm() * Q.norm())) bad("angle_symmetric_parallel_6r: g is undefined", q);
    g = ((e4.squaredNorm() - e1.squaredNorm()) / q) * along;
  } else {
    const Vector3 h = unit_or_throw(p.h, 0.0, "h has no length, |h|");
    const Eigen::Matrix3d half_turn = 2.0 * h * h.transpose() - Eigen::Matrix3d::Identity();
    v = half_turn * u;
    e4 = half_turn * e1;
    unit_or_throw(u.cross(h), 1.0, "u is parallel to h, |u x h|");
    w = Eigen::AngleAxisd(p.w_turn, h) * h.unitOrthogonal();
    g = p.g_length * w.cross(h);
  }
  unit_or_throw(u.cross(w), 1.0, "u is parallel to w, |u x w|");
  unit_or_throw(v.cross(w), 1.0, "v is parallel to w, |v x w|");
  // The lines at t = 0: axis 6 runs along -w, so that joints 3 and 6 turn by
  // one angle.
  const std::array<Axis, 6> lines{Axis{p.p1, u}, Axis{p.p1 + e1, u}, Axis{p.p3, w},
                                  Axis{p.p4, v}, Axis{p.p4 + e4, v}, Axis{p.p3 + g, -w}};
  const Eigen::AngleAxisd ru(t, u), rv(t, v);
  const Vector3 from = g + (rv * e4 - e4), to = g - (ru * e1 - e1);
  const double psi = std::atan2(w.dot(from.cross(to)), normal_part(from, w).dot(normal_part(to, w)));
  // Each axis carried by the motions of the joints before it (products of
  // exponentials about the lines at t = 0).
  const std::array<double, 6> angle{t, -t, psi, t, -t, psi};
  std::vector<Axis> axes;
  Eigen::Isometry3d carried = Eigen::Isometry3d::Identity();
  for (size_t k = 0; k < 6; ++k) {
    axes.push_back({carried * lines[k].point, carried.linear() * lines[k].direction});
    carried = carried * turn_about(lines[k].point, lines[k].direction, angle[k]);
  }
  return dh_from_axes(axes);
}

// ---------------------------------------------------------------------------
// Bricard's plane-symmetric octahedron

PosedLoop bricard_octahedral_plane(const OctahedronPlane& v) {
  for (const Vector3* x : {&v.p, &v.t, &v.q, &v.r}) {
    if (!x->allFinite()) bad("bricard_octahedral_plane: every vertex must be finite", x->norm());
  }
  if (!(std::abs(v.q.z()) > 1e-9) || !(std::abs(v.r.z()) > 1e-9)) {
    bad("bricard_octahedral_plane: Q and R must lie off the mirror plane z = 0, |z|",
        std::min(std::abs(v.q.z()), std::abs(v.r.z())));
  }
  const Vector3 P(v.p.x(), v.p.y(), 0.0), T(v.t.x(), v.t.y(), 0.0);
  const Vector3 mirror(1.0, 1.0, -1.0);
  const Vector3 Q = v.q, R = v.r, U = v.q.cwiseProduct(mirror), S = v.r.cwiseProduct(mirror);
  const std::array<Vector3, 6> vertices{P, S, Q, T, R, U};  // joint i's axis from vertex i to vertex i + 1
  std::vector<Axis> axes;
  for (size_t i = 0; i < vertices.size(); ++i) {
    const Vector3 along = vertices[(i + 1) % vertices.size()] - vertices[i];
    if (!(along.norm() > 1e-9)) bad("bricard_octahedral_plane: a hinge has no length", along.norm());
    axes.push_back({vertices[i], along.normalized()});
  }
  return dh_from_axes(axes);
}

// ---------------------------------------------------------------------------
// Bricard's doubly collapsible octahedron

namespace {

// A line of the plane through `point` with unit direction `along`.
struct PlaneLine {
  Eigen::Vector2d point, along;
};

// The two tangents from `from` (outside) to the circle of radius r about the
// origin, each through `from` towards its point of contact.
std::array<PlaneLine, 2> tangents_to_circle(const Eigen::Vector2d& from, double r) {
  const double distance = from.norm();
  const double phi = std::atan2(from.y(), from.x()), beta = std::acos(r / distance);
  std::array<PlaneLine, 2> out;
  for (int k = 0; k < 2; ++k) {
    const double angle = phi + (k == 0 ? beta : -beta);
    const Eigen::Vector2d contact = r * Eigen::Vector2d(std::cos(angle), std::sin(angle));
    out[static_cast<size_t>(k)] = {from, (contact - from).normalized()};
  }
  return out;
}

Eigen::Vector2d meeting_point(const PlaneLine& l, const PlaneLine& m) {
  const double cross = l.along.x() * m.along.y() - l.along.y() * m.along.x();
  if (!(std::abs(cross) > 1e-9))
    bad("bricard_octahedral_collapsible: two tangents that must meet are parallel, sine", cross);
  const Eigen::Vector2d w = m.point - l.point;
  return l.point + ((w.x() * m.along.y() - w.y() * m.along.x()) / cross) * l.along;
}

}  // namespace

PosedLoop bricard_octahedral_collapsible(const OctahedronCollapsible& f) {
  if (!(f.r1 > 0.0) || !std::isfinite(f.r1))
    bad("bricard_octahedral_collapsible: r1 must be positive and finite", f.r1);
  if (!(f.r2 > 0.0) || !std::isfinite(f.r2))
    bad("bricard_octahedral_collapsible: r2 must be positive and finite", f.r2);
  if (!(std::abs(f.r1 - f.r2) > 1e-9 * std::max(f.r1, f.r2))) {
    bad("bricard_octahedral_collapsible: the two radii must differ, r1 - r2", f.r1 - f.r2);
  }
  const double outer = std::max(f.r1, f.r2);
  for (const Eigen::Vector2d* x : {&f.p, &f.t}) {
    if (!x->allFinite() || !(x->norm() > outer * (1.0 + 1e-9))) {
      bad("bricard_octahedral_collapsible: P and T must lie outside both circles, |x| - max(r1, r2)",
          x->norm() - outer);
    }
  }
  const std::array<PlaneLine, 2> p1 = tangents_to_circle(f.p, f.r1), t1 = tangents_to_circle(f.t, f.r1);
  const std::array<PlaneLine, 2> p2 = tangents_to_circle(f.p, f.r2), t2 = tangents_to_circle(f.t, f.r2);
  const int sr = f.cross_sr ? 1 : 0, qu = f.cross_qu ? 1 : 0;
  const Eigen::Vector2d S = meeting_point(p1[0], t1[static_cast<size_t>(sr)]);
  const Eigen::Vector2d R = meeting_point(p1[1], t1[static_cast<size_t>(1 - sr)]);
  const Eigen::Vector2d Q = meeting_point(p2[0], t2[static_cast<size_t>(qu)]);
  const Eigen::Vector2d U = meeting_point(p2[1], t2[static_cast<size_t>(1 - qu)]);
  const std::array<Eigen::Vector2d, 6> vertices{f.p, S, Q, f.t, R, U};  // joint i's axis from vertex i to i + 1
  std::vector<Axis> axes;
  for (size_t i = 0; i < vertices.size(); ++i) {
    const Eigen::Vector2d along = vertices[(i + 1) % vertices.size()] - vertices[i];
    if (!(along.norm() > 1e-9)) bad("bricard_octahedral_collapsible: a hinge has no length", along.norm());
    axes.push_back({Vector3(vertices[i].x(), vertices[i].y(), 0.0), Vector3(along.x(), along.y(), 0.0).normalized()});
  }
  return dh_from_axes(axes);
}

}  // namespace loopfarm
