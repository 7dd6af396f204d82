// The ground-truth set (ground_truth.hpp, docs/quality/ground-truth.md): movable 4R
// loops built from their families' conditions with closed-form closed poses,
// and rigid ones made from them by one perturbation each, plus random loops.
#include "loopfarm/study/ground_truth.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdio>
#include <set>
#include <stdexcept>

#include "loopfarm/core/sample_loops.hpp"
#include "loopfarm/search/sampler.hpp"

namespace loopfarm {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDegree = kPi / 180.0;
// A movable case's closed-form pose must close to this (max-norm of
// (log R, p / L)); the closed forms reach a few 1e-16.
constexpr double kRoundOff = 1e-12;
// Rejection sampling of a family's shape: the acceptance rate is at least a
// few per cent for every valid option, so this is never reached.
constexpr int kMaxAttempts = 100000;
// Planar four-bars: the Grashof inequalities hold by at least this, in units
// of the input link (the shortest), and the other links are at least this
// much longer than it. Keeps the loops away from change points, where the
// input's full turn passes a flat, singular pose.
constexpr double kGrashofMargin = 0.1;
// The trivial loop's two link lengths differ by at least this ratio, so that
// no representation of it is a Bennett loop (which needs a1 = a3).
constexpr double kTrivialLengthMargin = 0.1;
constexpr std::uint64_t kMaxCount = 1000000;

// One Philox stream per case, keyed by (seed, family << 32 | index), so a
// case does not depend on how many others are generated.
enum class StreamFamily : std::uint64_t {
  bennett_asymmetric = 1,
  bennett_line_symmetric = 2,
  planar = 3,
  spherical = 4,
  trivial = 5,
  generic = 6,
};

class Draws {
 public:
  Draws(std::uint64_t seed, StreamFamily family, int index)
      : seed_(seed), stream_((static_cast<std::uint64_t>(family) << 32) | static_cast<std::uint64_t>(index)) {}

  double uniform(double lo, double hi) { return lo + (hi - lo) * stream_uniform(seed_, stream_, next_++); }
  double log_uniform(double lo, double hi) { return std::exp(uniform(std::log(lo), std::log(hi))); }
  bool coin() { return stream_uniform(seed_, stream_, next_++) < 0.5; }
  // An input angle away from the folded poses at 0 and pi, either sign.
  double input_angle(double margin) {
    const double magnitude = uniform(margin, kPi - margin);
    return coin() ? magnitude : -magnitude;
  }
  // A 64-bit key for the fixtures that take one (random_loop).
  std::uint64_t key() {
    const auto high = static_cast<std::uint64_t>(stream_uniform(seed_, stream_, next_++) * 0x1p32);
    const auto low = static_cast<std::uint64_t>(stream_uniform(seed_, stream_, next_++) * 0x1p32);
    return (high << 32) | low;
  }

 private:
  std::uint64_t seed_;
  std::uint64_t stream_;
  std::uint64_t next_ = 0;
};

// Runs `draw` until `accept` holds; rejection sampling of a family's shape.
template <class Draw, class Accept>
void draw_until(Draw draw, Accept accept, const char* what) {
  for (int attempt = 0; attempt < kMaxAttempts; ++attempt) {
    draw();
    if (accept()) return;
  }
  throw std::logic_error(std::string("generate_ground_truth: no acceptable ") + what + " drawn");
}

// Max-norm of the closure residual with the translation in units of L.
double pose_residual(const LoopGeometry& g, const JointVector& theta) {
  return closure_residual(scaled(g, length_scale(g)), theta).cwiseAbs().maxCoeff();
}

std::string index_text(int index) {
  char buffer[16];
  std::snprintf(buffer, sizeof buffer, "%03d", index);
  return buffer;
}

// "1e-03", "2.5e-04": the shortest mantissa of %.6e, for ids.
std::string size_text(double size) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.6e", size);
  std::string text = buffer;
  const size_t e = text.find('e');
  std::string mantissa = text.substr(0, e);
  while (mantissa.back() == '0') mantissa.pop_back();
  if (mantissa.back() == '.') mantissa.pop_back();
  return mantissa + text.substr(e);
}

GroundTruthCase movable_case(GroundTruthFamily family, BennettSetup setup, std::string id, LoopGeometry g,
                             JointVector pose) {
  GroundTruthCase c;
  c.id = std::move(id);
  c.family = family;
  c.setup = setup;
  c.movable = true;
  c.full_turn = true;
  c.geometry = std::move(g);
  c.pose = std::move(pose);
  c.pose_residual = pose_residual(c.geometry, c.pose);
  if (!(c.pose_residual <= kRoundOff)) {
    char buffer[64];
    std::snprintf(buffer, sizeof buffer, "%.3g", c.pose_residual);
    throw std::logic_error("generate_ground_truth: the closed-form pose of " + c.id + " does not close (residual " +
                           buffer + ")");
  }
  return c;
}

// Axis flips (loop.hpp's axis_flipped) of a random non-empty set of joints:
// the same physical loop written with other axis directions, so that twists
// of 180 deg and negated offsets appear.
void flip_some_axes(Draws& draws, LoopGeometry& g, JointVector& pose) {
  int mask = 0;
  for (int j = 0; j < 4; ++j) mask |= draws.coin() ? 1 << j : 0;
  if (mask == 0) mask = 1 << 1;
  for (int j = 0; j < 4; ++j) {
    if (mask & (1 << j)) {
      g = axis_flipped(g, j);
      pose = axis_flipped_angles(pose, j);
    }
  }
}

// ---------------------------------------------------------------------------
// Bennett loops: twists anywhere in [m, pi - m] except near the pair where
// the loop turns into the coaxial trivial loop (a1 = a2 and equal twists as
// written or after flipping axes 1 and 2): there the closed form's ratio
// blows up and theta2 sticks at 180 deg.
GroundTruthCase bennett_case(const GroundTruthOptions& o, BennettSetup setup, int index) {
  const bool asymmetric = setup == BennettSetup::asymmetric;
  Draws draws(o.seed, asymmetric ? StreamFamily::bennett_asymmetric : StreamFamily::bennett_line_symmetric, index);
  const double m = o.twist_margin;
  double alpha1 = 0.0, alpha2 = 0.0;
  draw_until(
      [&] {
        alpha1 = draws.uniform(m, kPi - m);
        alpha2 = draws.uniform(m, kPi - m);
      },
      [&] { return asymmetric ? std::abs(alpha1 - alpha2) >= m : std::abs(alpha1 + alpha2 - kPi) >= m; },
      "Bennett twists");
  const double scale = draws.log_uniform(o.min_length_scale, o.max_length_scale);
  auto make = asymmetric ? bennett_loop : bennett_loop_line_symmetric;
  // a2 follows from a1 and the twists; a1 is set so that L is the drawn scale.
  const LoopGeometry g = make(scale / length_scale(make(1.0, alpha1, alpha2)), alpha1, alpha2);
  const double theta0 = draws.input_angle(o.pose_margin);
  JointVector pose = asymmetric ? bennett_angles(g, theta0) : bennett_angles_line_symmetric(g, theta0);
  return movable_case(GroundTruthFamily::bennett, setup,
                      std::string("bennett-") + to_string(setup) + "-" + index_text(index), g, std::move(pose));
}

// ---------------------------------------------------------------------------
// Planar four-bar poses. With every twist 0 the loop product is a planar
// motion and closure says a1 e^{i phi1} + a2 e^{i phi2} + a3 e^{i phi3} + a4 = 0,
// phi_k = theta_1 + ... + theta_k (phi4 = 0): the input link and the fixed
// link a4 end at distance D = |a4 + a1 e^{i theta1}| from each other, and
// links 2 and 3 close the triangle over that diagonal (law of cosines);
// `elbow` (+1 or -1) picks one of its two assembly modes. Offsets whose sum
// is zero slide along the common axis and do not change the angles.
JointVector planar_pose(const LoopGeometry& g, double theta1, double elbow) {
  using Complex = std::complex<double>;
  const double a1 = g.a[0], a2 = g.a[1], a3 = g.a[2], a4 = g.a[3];
  const Complex diagonal = a4 + a1 * std::polar(1.0, theta1);
  const double D = std::abs(diagonal);
  const double cos_beta = (a2 * a2 + D * D - a3 * a3) / (2.0 * a2 * D);
  const double phi2 = std::arg(-diagonal) + elbow * std::acos(std::clamp(cos_beta, -1.0, 1.0));
  const double phi3 = std::arg(-diagonal - a2 * std::polar(1.0, phi2));
  JointVector theta(4);
  theta << theta1, wrap_angle(phi2 - theta1), wrap_angle(phi3 - phi2), wrap_angle(-phi3);
  return theta;
}

// The input link a1 is the shortest and the Grashof inequality is strict:
// the diagonal D, which runs over [a4 - a1, a4 + a1] as the input turns,
// stays strictly inside [|a2 - a3|, a2 + a3], where links 2 and 3 can span it.
GroundTruthCase planar_case(const GroundTruthOptions& o, int index) {
  Draws draws(o.seed, StreamFamily::planar, index);
  double a2 = 0.0, a3 = 0.0, a4 = 0.0;
  draw_until(
      [&] {
        a2 = draws.uniform(1.0 + kGrashofMargin, 5.0);
        a3 = draws.uniform(1.0 + kGrashofMargin, 5.0);
        a4 = draws.uniform(1.0 + kGrashofMargin, 5.0);
      },
      [&] { return a4 - 1.0 - std::abs(a2 - a3) >= kGrashofMargin && a2 + a3 - a4 - 1.0 >= kGrashofMargin; },
      "planar four-bar");
  LoopGeometry g = planar_four_bar(1.0, a2, a3, a4);
  // Variants: plain; with offsets along the common axis summing to zero; and
  // those with some axes flipped (twists of 180 deg, the offsets' signs turning).
  const int variant = index % 3;
  if (variant >= 1) {
    for (int j = 0; j < 3; ++j) g.d[j] = draws.uniform(-1.0, 1.0);
    g.d[3] = -(g.d[0] + g.d[1] + g.d[2]);
  }
  g = scaled(g, length_scale(g) / draws.log_uniform(o.min_length_scale, o.max_length_scale));
  const double theta0 = draws.input_angle(o.pose_margin);
  JointVector pose = planar_pose(g, theta0, draws.coin() ? 1.0 : -1.0);
  if (variant == 2) flip_some_axes(draws, g, pose);
  return movable_case(GroundTruthFamily::planar, BennettSetup::none, "planar-" + index_text(index), g, std::move(pose));
}

// ---------------------------------------------------------------------------
// Spherical loops. All axes pass through one point; z_k is joint k's axis.
// In the base frame z1 = e_z, z2 = Rz(theta1) Rx(alpha1) e_z and, from
// closure, z4 = T4^-1 e_z = Rx(-alpha4) e_z, so the diagonal arc delta
// between axes 2 and 4 has
//     cos delta = cos alpha1 cos alpha4 - sin alpha1 sin alpha4 cos theta1
// and, seen through joint 3, the same with alpha2, alpha3 and theta3.
Eigen::Matrix3d rz(double angle) { return Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitZ()).toRotationMatrix(); }
Eigen::Matrix3d rx(double angle) { return Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitX()).toRotationMatrix(); }

// theta3 from the diagonal (two assembly modes, `elbow`), theta2 by turning
// joint 3's image of z4 onto z4 about z2, theta4 from what the rotation
// product leaves.
JointVector spherical_pose(const LoopGeometry& g, double theta1, double elbow) {
  const double alpha1 = g.alpha[0], alpha2 = g.alpha[1], alpha3 = g.alpha[2], alpha4 = g.alpha[3];
  const Eigen::Matrix3d R1 = rz(theta1) * rx(alpha1);
  const Eigen::Vector3d z4 = rx(-alpha4) * Eigen::Vector3d::UnitZ();
  const Eigen::Vector3d w = R1.transpose() * z4;  // z4 in frame 2
  const double cos_theta3 = (std::cos(alpha2) * std::cos(alpha3) - w.z()) / (std::sin(alpha2) * std::sin(alpha3));
  const double theta3 = elbow * std::acos(std::clamp(cos_theta3, -1.0, 1.0));
  const Eigen::Vector3d u = rx(alpha2) * rz(theta3) * rx(alpha3) * Eigen::Vector3d::UnitZ();
  const double theta2 = std::atan2(w.y(), w.x()) - std::atan2(u.y(), u.x());
  // Rz(theta4) = (R1 R2 R3)^T Rx(-alpha4).
  const Eigen::Matrix3d R4z = (R1 * rz(theta2) * rx(alpha2) * rz(theta3) * rx(alpha3)).transpose() * rx(-alpha4);
  JointVector theta(4);
  theta << theta1, wrap_angle(theta2), theta3, std::atan2(R4z(1, 0), R4z(0, 0));
  return theta;
}

// The largest arc the two links at a joint can span, the other end of the
// range being |alpha_i - alpha_j|.
double widest_arc(double alpha_i, double alpha_j) { return std::min(alpha_i + alpha_j, 2.0 * kPi - alpha_i - alpha_j); }

// The input turns fully when the diagonal's range from the input side,
// [|alpha1 - alpha4|, widest_arc(alpha1, alpha4)], lies strictly inside the
// range links 2 and 3 can span (the spherical Grashof condition).
GroundTruthCase spherical_case(const GroundTruthOptions& o, int index) {
  Draws draws(o.seed, StreamFamily::spherical, index);
  const double m = o.twist_margin;
  double alpha[4] = {};
  draw_until(
      [&] {
        for (double& t : alpha) t = draws.uniform(m, kPi - m);
      },
      [&] {
        return std::abs(alpha[0] - alpha[3]) - std::abs(alpha[1] - alpha[2]) >= m &&
               widest_arc(alpha[1], alpha[2]) - widest_arc(alpha[0], alpha[3]) >= m;
      },
      "spherical crank");
  const LoopGeometry g = spherical_four_bar(alpha[0], alpha[1], alpha[2], alpha[3]);
  const double theta0 = draws.input_angle(o.pose_margin);
  JointVector pose = spherical_pose(g, theta0, draws.coin() ? 1.0 : -1.0);
  return movable_case(GroundTruthFamily::spherical, BennettSetup::none, "spherical-" + index_text(index), g,
                      std::move(pose));
}

// ---------------------------------------------------------------------------
// The coaxial 1-3 loop: a = (p, p, q, q), alpha = (beta, beta, gamma, gamma),
// d = (e, 0, -e, 0). With theta2 = 180 deg, Tx(p) Rx(beta) Rz(pi) Tx(p)
// Rx(beta) = Rz(pi), so T1 T2 = Rz(theta1 + pi) Tz(e) and likewise T3 T4 =
// Rz(theta3 + pi) Tz(-e): the loop closes for every theta1 with theta3 =
// -theta1, joints 2 and 4 frozen. Odd cases have some axes flipped.
GroundTruthCase trivial_case(const GroundTruthOptions& o, int index) {
  Draws draws(o.seed, StreamFamily::trivial, index);
  const double m = o.twist_margin;
  double q = 0.0, beta = 0.0, gamma = 0.0;
  draw_until([&] { q = draws.uniform(0.3, 3.0); }, [&] { return std::abs(q - 1.0) >= kTrivialLengthMargin; },
             "trivial loop lengths");
  draw_until(
      [&] {
        beta = draws.uniform(m, kPi - m);
        gamma = draws.uniform(m, kPi - m);
      },
      [&] { return std::abs(beta - gamma) >= m; }, "trivial loop twists");
  const double e = draws.uniform(-1.0, 1.0);
  LoopGeometry g;
  g.a.resize(4);
  g.alpha.resize(4);
  g.d.resize(4);
  g.a << 1.0, 1.0, q, q;
  g.alpha << beta, beta, gamma, gamma;
  g.d << e, 0.0, -e, 0.0;
  g = scaled(g, length_scale(g) / draws.log_uniform(o.min_length_scale, o.max_length_scale));
  const double theta0 = draws.input_angle(o.pose_margin);
  JointVector pose(4);
  pose << theta0, kPi, -theta0, kPi;
  if (index % 2 == 1) flip_some_axes(draws, g, pose);
  return movable_case(GroundTruthFamily::trivial, BennettSetup::none, "trivial-" + index_text(index), g,
                      std::move(pose));
}

// ---------------------------------------------------------------------------
// Perturbations that leave every movable family (Delassus: for 4R there are
// no others). Not every parameter does: a planar loop with a length changed
// is another planar loop, a spherical loop with a twist changed another
// spherical loop, so those families get a twist or an offset, and a length
// or an offset, respectively. Case k of a family uses entry k mod size.
enum class ParameterKind { a, alpha, d };
struct Parameter {
  ParameterKind kind;
  int joint;  // 0-based
};

std::vector<Parameter> destroying_parameters(GroundTruthFamily family) {
  using K = ParameterKind;
  switch (family) {
    // Off a1 = a3, alpha2 = alpha4, or d = 0: no Bennett representation, and the
    // twists are away from planar, the lengths from spherical.
    case GroundTruthFamily::bennett:
      return {{K::a, 0}, {K::alpha, 1}, {K::d, 2}};
    // A twist off 0/180 deg: the axes are no longer parallel; an offset:
    // their signed sum is no longer zero, the loop cannot close at all.
    case GroundTruthFamily::planar:
      return {{K::alpha, 0}, {K::d, 1}, {K::alpha, 2}, {K::d, 3}};
    // Any length or offset: the axes no longer meet in one point, and the
    // loop cannot close at all.
    case GroundTruthFamily::spherical:
      return {{K::a, 0}, {K::d, 1}, {K::a, 2}, {K::d, 3}};
    // Off a1 = a2, alpha3 = alpha4, d2 = 0 or d1 + d3 = 0: axes 1 and 3 no
    // longer coincide, and the loop is none of the other families.
    case GroundTruthFamily::trivial:
      return {{K::a, 0}, {K::alpha, 2}, {K::d, 1}, {K::d, 0}};
    case GroundTruthFamily::generic:
      break;
  }
  return {};
}

std::string parameter_name(const Parameter& p) {
  const char* kind = p.kind == ParameterKind::a ? "a" : p.kind == ParameterKind::alpha ? "alpha" : "d";
  return kind + std::to_string(p.joint + 1);
}

GroundTruthCase perturbed_case(const GroundTruthCase& parent, const Parameter& parameter, double size) {
  GroundTruthCase c;
  c.family = parent.family;
  c.setup = parent.setup;
  c.movable = false;
  c.full_turn = false;
  c.parent = parent.id;
  c.perturbed_parameter = parameter_name(parameter);
  c.relative_perturbation = size;
  c.id = parent.id + "-" + c.perturbed_parameter + "-" + size_text(size);
  c.geometry = parent.geometry;
  const double L = length_scale(parent.geometry);
  switch (parameter.kind) {
    case ParameterKind::a:
      c.geometry.a[parameter.joint] += size * L;
      break;
    case ParameterKind::alpha:
      c.geometry.alpha[parameter.joint] += size;
      break;
    case ParameterKind::d:
      c.geometry.d[parameter.joint] += size * L;
      break;
  }
  c.pose = parent.pose;
  c.pose_residual = pose_residual(c.geometry, c.pose);
  return c;
}

GroundTruthCase generic_case(const GroundTruthOptions& o, int index) {
  Draws draws(o.seed, StreamFamily::generic, index);
  const std::uint64_t key = draws.key();
  GroundTruthCase c;
  c.id = "generic-" + index_text(index);
  c.family = GroundTruthFamily::generic;
  c.geometry = random_loop(4, key);
  c.pose = random_angles(4, key);
  c.pose_residual = pose_residual(c.geometry, c.pose);
  return c;
}

}  // namespace

void GroundTruthOptions::validate() const {
  auto fail = [](const std::string& what, double value) {
    char buffer[48];
    std::snprintf(buffer, sizeof buffer, "%.17g", value);
    throw std::invalid_argument("GroundTruthOptions: " + what + ", got " + buffer);
  };
  if (cases_per_family < 0 || static_cast<std::uint64_t>(cases_per_family) > kMaxCount) {
    fail("cases_per_family must be in [0, 1000000]", cases_per_family);
  }
  if (generic_loops < 0 || static_cast<std::uint64_t>(generic_loops) > kMaxCount) {
    fail("generic_loops must be in [0, 1000000]", generic_loops);
  }
  std::set<std::string> sizes;
  for (double size : relative_perturbations) {
    if (!(size > 0.0 && size < 1.0)) fail("every relative perturbation must be in (0, 1)", size);
    // Ids carry the size with 7 significant digits; two sizes must not share one.
    if (!sizes.insert(size_text(size)).second) {
      fail("relative perturbations must differ in their first 7 significant digits (the ids carry 7)", size);
    }
  }
  if (!(min_length_scale > 0.0 && std::isfinite(min_length_scale))) {
    fail("min_length_scale must be finite and > 0", min_length_scale);
  }
  if (!(max_length_scale >= min_length_scale && std::isfinite(max_length_scale))) {
    fail("max_length_scale must be finite and >= min_length_scale", max_length_scale);
  }
  if (!(twist_margin > 0.0 && twist_margin <= 10.0 * kDegree))
    fail("twist_margin must be in (0, 10 deg]", twist_margin);
  if (!(pose_margin > 0.0 && pose_margin <= 45.0 * kDegree)) fail("pose_margin must be in (0, 45 deg]", pose_margin);
}

const char* to_string(GroundTruthFamily family) {
  switch (family) {
    case GroundTruthFamily::bennett:
      return "bennett";
    case GroundTruthFamily::planar:
      return "planar";
    case GroundTruthFamily::spherical:
      return "spherical";
    case GroundTruthFamily::trivial:
      return "trivial";
    case GroundTruthFamily::generic:
      return "generic";
  }
  return "unknown";
}

Family expected_classification(const GroundTruthCase& c) {
  if (!c.movable) return Family::unclassified;
  switch (c.family) {
    case GroundTruthFamily::bennett:
      return Family::bennett;
    case GroundTruthFamily::planar:
      return Family::planar;
    case GroundTruthFamily::spherical:
      return Family::spherical;
    case GroundTruthFamily::trivial:
      return Family::trivial;
    case GroundTruthFamily::generic:
      break;
  }
  return Family::unclassified;
}

std::vector<GroundTruthCase> generate_ground_truth(const GroundTruthOptions& options) {
  options.validate();
  std::vector<GroundTruthCase> cases;
  auto add_with_perturbations = [&](GroundTruthCase movable, int index) {
    const std::vector<Parameter> parameters = destroying_parameters(movable.family);
    const Parameter& parameter = parameters[static_cast<size_t>(index) % parameters.size()];
    cases.push_back(std::move(movable));
    const GroundTruthCase& parent = cases.back();
    std::vector<GroundTruthCase> perturbed;
    for (double size : options.relative_perturbations) perturbed.push_back(perturbed_case(parent, parameter, size));
    for (GroundTruthCase& c : perturbed) cases.push_back(std::move(c));
  };
  const int n = options.cases_per_family;
  for (BennettSetup setup : {BennettSetup::asymmetric, BennettSetup::line_symmetric}) {
    for (int i = 0; i < n; ++i) add_with_perturbations(bennett_case(options, setup, i), i);
  }
  for (int i = 0; i < n; ++i) add_with_perturbations(planar_case(options, i), i);
  for (int i = 0; i < n; ++i) add_with_perturbations(spherical_case(options, i), i);
  for (int i = 0; i < n; ++i) add_with_perturbations(trivial_case(options, i), i);
  for (int i = 0; i < options.generic_loops; ++i) cases.push_back(generic_case(options, i));
  return cases;
}

}  // namespace loopfarm
