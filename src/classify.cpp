#include "loopfarm/classify.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "representation.hpp"

namespace loopfarm {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// A family's conditions on one writing of the loop: values and their
// derivatives with respect to that writing's parameters (a, alpha, d).
struct Conditions {
  std::vector<std::string> names;
  std::vector<double> values;
  std::vector<GeometryVector> gradients;

  void add(std::string name, double value, GeometryVector gradient) {
    names.push_back(std::move(name));
    values.push_back(value);
    gradients.push_back(std::move(gradient));
  }
  double max_abs() const {
    double m = 0.0;
    for (double v : values) m = std::max(m, std::abs(v));
    return m;
  }
  double norm() const {
    double s = 0.0;
    for (double v : values) s += v * v;
    return std::sqrt(s);
  }
  // d norm / dp, where the norm is not zero.
  GeometryVector norm_gradient(int size) const {
    GeometryVector g = GeometryVector::Zero(size);
    const double n = norm();
    if (n == 0.0) return g;
    for (size_t i = 0; i < values.size(); ++i) g += (values[i] / n) * gradients[i];
    return g;
  }
};

std::string label(const char* name, int k) { return name + std::to_string(k + 1); }

// Helpers for conditions built from x / L, L the length scale.
struct Scale {
  double L;
  GeometryVector dL;
  int n;
  // d(x_i / L) for parameter index i (a or d); x_i its value.
  GeometryVector ratio_gradient(int i, double x) const {
    GeometryVector g = -(x / (L * L)) * dL;
    g[i] += 1.0 / L;
    return g;
  }
};

Scale scale_of(const LoopGeometry& g) { return {length_scale(g), length_scale_gradient(g), g.joints()}; }

// Bennett conditions (n = 4) on writing `g`; setup_sign +1 asymmetric, -1 line-symmetric.
Conditions bennett_conditions(const LoopGeometry& g, double setup_sign) {
  const int n = 4;
  const Scale s = scale_of(g);
  Conditions c;
  auto length_difference = [&](int i, int j) {  // (a_i - a_j) / L
    c.add(label("a", i) + " - " + label("a", j), (g.a[i] - g.a[j]) / s.L,
          s.ratio_gradient(i, g.a[i]) - s.ratio_gradient(j, g.a[j]));
  };
  auto twist_difference = [&](int i, int j) {
    GeometryVector grad = GeometryVector::Zero(3 * n);
    grad[n + i] = 1.0;
    grad[n + j] = -1.0;
    c.add(label("alpha", i) + " - " + label("alpha", j), wrap_angle(g.alpha[i] - g.alpha[j]), grad);
  };
  length_difference(0, 2);
  length_difference(1, 3);
  twist_difference(0, 2);
  twist_difference(1, 3);
  for (int k = 0; k < n; ++k) c.add(label("d", k), g.d[k] / s.L, s.ratio_gradient(2 * n + k, g.d[k]));
  // (a2 sin alpha1 - +- a1 sin alpha2) / L, paper labels (1-based).
  const double product = g.a[1] * std::sin(g.alpha[0]) - setup_sign * g.a[0] * std::sin(g.alpha[1]);
  GeometryVector grad = -(product / (s.L * s.L)) * s.dL;
  grad[1] += std::sin(g.alpha[0]) / s.L;
  grad[0] += -setup_sign * std::sin(g.alpha[1]) / s.L;
  grad[n + 0] += g.a[1] * std::cos(g.alpha[0]) / s.L;
  grad[n + 1] += -setup_sign * g.a[0] * std::cos(g.alpha[1]) / s.L;
  c.add(setup_sign > 0 ? "a2 sin(alpha1) - a1 sin(alpha2)" : "a2 sin(alpha1) + a1 sin(alpha2)", product / s.L, grad);
  return c;
}

Conditions planar_conditions(const LoopGeometry& g) {
  const int n = g.joints();
  const Scale s = scale_of(g);
  Conditions c;
  double sign = 1.0, sum = 0.0;
  GeometryVector dsum = GeometryVector::Zero(3 * n);
  for (int k = 0; k < n; ++k) {
    GeometryVector grad = GeometryVector::Zero(3 * n);
    grad[n + k] = std::cos(g.alpha[k]);
    c.add("sin(" + label("alpha", k) + ")", std::sin(g.alpha[k]), grad);
    // The offset d_k points along z_k, which is +-z_1 for parallel axes.
    sum += sign * g.d[k];
    dsum[2 * n + k] = sign;
    if (std::cos(g.alpha[k]) < 0.0) sign = -sign;
  }
  GeometryVector grad = dsum / s.L - (sum / (s.L * s.L)) * s.dL;
  c.add("signed sum of d / L", sum / s.L, grad);
  return c;
}

Conditions spherical_conditions(const LoopGeometry& g, bool normalised) {
  const int n = g.joints();
  const double L = normalised ? length_scale(g) : 1.0;
  Conditions c;
  for (int k = 0; k < n; ++k) {
    GeometryVector grad = GeometryVector::Zero(3 * n);
    grad[k] = 1.0 / L;  // (used unnormalised only, where L = 1)
    c.add(label("a", k), g.a[k] / L, grad);
  }
  for (int k = 0; k < n; ++k) {
    GeometryVector grad = GeometryVector::Zero(3 * n);
    grad[2 * n + k] = 1.0 / L;
    c.add(label("d", k), g.d[k] / L, grad);
  }
  return c;
}

// Axes 1 and 2 of this writing coincide: a1 = 0 and sin(alpha1) = 0.
Conditions adjacent_coaxial_conditions(const LoopGeometry& g) {
  const int n = g.joints();
  const Scale s = scale_of(g);
  Conditions c;
  c.add("a1", g.a[0] / s.L, s.ratio_gradient(0, g.a[0]));
  GeometryVector grad = GeometryVector::Zero(3 * n);
  grad[n] = std::cos(g.alpha[0]);
  c.add("sin(alpha1)", std::sin(g.alpha[0]), grad);
  return c;
}

// Axes 1 and 3 of a 4R writing coincide (DESIGN.md).
Conditions coaxial_13_conditions(const LoopGeometry& g) {
  const int n = 4;
  const Scale s = scale_of(g);
  Conditions c;
  c.add("a1 - a2", (g.a[0] - g.a[1]) / s.L, s.ratio_gradient(0, g.a[0]) - s.ratio_gradient(1, g.a[1]));
  c.add("a3 - a4", (g.a[2] - g.a[3]) / s.L, s.ratio_gradient(2, g.a[2]) - s.ratio_gradient(3, g.a[3]));
  for (int pair : {0, 2}) {
    GeometryVector grad = GeometryVector::Zero(3 * n);
    grad[n + pair] = 1.0;
    grad[n + pair + 1] = -1.0;
    c.add(label("alpha", pair) + " - " + label("alpha", pair + 1), wrap_angle(g.alpha[pair] - g.alpha[pair + 1]), grad);
  }
  c.add("d2", g.d[1] / s.L, s.ratio_gradient(2 * n + 1, g.d[1]));
  c.add("d4", g.d[3] / s.L, s.ratio_gradient(2 * n + 3, g.d[3]));
  c.add("d1 + d3", (g.d[0] + g.d[2]) / s.L, s.ratio_gradient(2 * n, g.d[0]) + s.ratio_gradient(2 * n + 2, g.d[2]));
  return c;
}

// The best writing's conditions for a family, by max |condition| (for
// classification) or by norm (for distances).
struct Best {
  Conditions conditions;
  const detail::Representation* writing = nullptr;
  double score = kInf;
  double setup_sign = 0.0;
};

template <class Make>
Best best_over_writings(const LoopGeometry& g, bool by_norm, Make make) {
  Best best;
  for (const detail::Representation& r : detail::representations(g.joints())) {
    const LoopGeometry w = detail::apply(r, g);
    make(w, [&](Conditions c, double setup_sign) {
      const double score = by_norm ? c.norm() : c.max_abs();
      if (score < best.score) {
        best.score = score;
        best.conditions = std::move(c);
        best.writing = &r;
        best.setup_sign = setup_sign;
      }
    });
  }
  return best;
}

Best best_bennett(const LoopGeometry& g, bool by_norm) {
  return best_over_writings(g, by_norm, [](const LoopGeometry& w, auto keep) {
    keep(bennett_conditions(w, 1.0), 1.0);
    keep(bennett_conditions(w, -1.0), -1.0);
  });
}

Best best_trivial_geometric(const LoopGeometry& g, bool by_norm) {
  const int n = g.joints();
  return best_over_writings(g, by_norm, [n](const LoopGeometry& w, auto keep) {
    keep(adjacent_coaxial_conditions(w), 0.0);
    if (n == 4) keep(coaxial_13_conditions(w), 0.0);
  });
}

Best best_planar(const LoopGeometry& g, bool by_norm) {
  // The offsets' signed sum depends on the axes' directions off the family;
  // the best writing makes the distance independent of how it is written.
  return best_over_writings(g, by_norm, [](const LoopGeometry& w, auto keep) { keep(planar_conditions(w), 0.0); });
}

FamilyCheck check_from(Family family, const Best& best) {
  FamilyCheck check;
  check.family = family;
  check.residual = best.score;
  for (size_t i = 0; i < best.conditions.values.size(); ++i) {
    check.conditions.push_back({best.conditions.names[i], best.conditions.values[i]});
  }
  return check;
}

struct AxisPair {
  int i = -1, j = -1;
  double residual = kInf;  // max(sin of the angle between them, distance / L)
};

AxisPair nearest_coincident_axes(const LoopGeometry& g, const JointVector& pose) {
  const int n = g.joints();
  const double L = length_scale(g);
  std::vector<Vector3> origin, axis;
  for (int k = 0; k < n; ++k) {
    const Eigen::Isometry3d frame = forward_transform(g, pose, k);
    origin.push_back(frame.translation());
    axis.push_back(frame.linear().col(2));
  }
  AxisPair best;
  for (int i = 0; i < n; ++i) {
    for (int j = i + 1; j < n; ++j) {
      const double angle = axis[i].cross(axis[j]).norm();
      const double distance = (origin[j] - origin[i]).cross(axis[i]).norm() / L;
      const double residual = std::max(angle, distance);
      if (residual < best.residual) best = {i, j, residual};
    }
  }
  return best;
}

}  // namespace

const char* to_string(Family family) {
  switch (family) {
    case Family::bennett: return "bennett";
    case Family::planar: return "planar";
    case Family::spherical: return "spherical";
    case Family::trivial: return "trivial";
    case Family::unclassified: return "unclassified";
  }
  return "unknown";
}

const char* to_string(BennettSetup setup) {
  switch (setup) {
    case BennettSetup::none: return "none";
    case BennettSetup::asymmetric: return "asymmetric";
    case BennettSetup::line_symmetric: return "line_symmetric";
  }
  return "unknown";
}

Classification classify(const LoopGeometry& geometry, const JointVector& pose, std::span<const double> joint_travel,
                        const ClassifyOptions& options) {
  validate_geometry(geometry);
  const int n = geometry.joints();
  if (pose.size() != n || !pose.allFinite()) {
    throw std::invalid_argument("classify: the pose needs " + std::to_string(n) + " finite joint angles");
  }
  if (!joint_travel.empty() && static_cast<int>(joint_travel.size()) != n) {
    throw std::invalid_argument("classify: joint_travel needs one value per joint");
  }
  Classification out;

  // Bennett: the best writing; the setup as written when it fits as written.
  FamilyCheck bennett;
  bennett.family = Family::bennett;
  bennett.residual = kInf;
  if (n == 4) {
    const Best best = best_bennett(geometry, false);
    bennett = check_from(Family::bennett, best);
    bennett.setup = best.setup_sign > 0 ? BennettSetup::asymmetric : BennettSetup::line_symmetric;
    const double as_written_asym = bennett_conditions(geometry, 1.0).max_abs();
    const double as_written_line = bennett_conditions(geometry, -1.0).max_abs();
    if (std::min(as_written_asym, as_written_line) <= options.tolerance) {
      bennett.setup = as_written_asym <= as_written_line ? BennettSetup::asymmetric : BennettSetup::line_symmetric;
    }
  }
  FamilyCheck planar = check_from(Family::planar, best_planar(geometry, false));
  Conditions spherical_c = spherical_conditions(geometry, true);
  FamilyCheck spherical = check_from(Family::spherical, Best{spherical_c, nullptr, spherical_c.max_abs(), 0.0});

  // Trivial: coincident axes in the pose, and a frozen joint.
  FamilyCheck trivial;
  trivial.family = Family::trivial;
  const AxisPair pair = nearest_coincident_axes(geometry, pose);
  trivial.conditions.push_back({"axes " + std::to_string(pair.i + 1) + " and " + std::to_string(pair.j + 1) +
                                    " coincide (sin angle, distance / L)",
                                pair.residual});
  std::vector<int> frozen;
  double least_travel = kInf;
  for (size_t k = 0; k < joint_travel.size(); ++k) {
    least_travel = std::min(least_travel, joint_travel[k]);
    if (joint_travel[k] <= options.frozen_travel) frozen.push_back(static_cast<int>(k));
  }
  trivial.conditions.push_back({"least joint travel [rad]", least_travel});
  // A frozen joint passes when its travel is below frozen_travel; expressed
  // on the tolerance's scale so that one residual decides.
  const bool has_frozen = !frozen.empty();
  trivial.residual = has_frozen ? pair.residual : kInf;

  out.checks = {bennett, planar, spherical, trivial};
  const double tol = options.tolerance;
  if (trivial.residual <= tol) {
    out.family = Family::trivial;
    out.residual = trivial.residual;
    out.detail = "axes " + std::to_string(pair.i + 1) + " and " + std::to_string(pair.j + 1) + " coincide; joint";
    out.detail += frozen.size() > 1 ? "s" : "";
    for (size_t k = 0; k < frozen.size(); ++k) out.detail += (k ? ", " : " ") + std::to_string(frozen[k] + 1);
    out.detail += " frozen";
  } else if (planar.residual <= tol) {
    out.family = Family::planar;
    out.residual = planar.residual;
    out.detail = "all joint axes parallel";
  } else if (spherical.residual <= tol) {
    out.family = Family::spherical;
    out.residual = spherical.residual;
    out.detail = "all joint axes through one point";
  } else if (bennett.residual <= tol) {
    out.family = Family::bennett;
    out.setup = bennett.setup;
    out.residual = bennett.residual;
    out.detail = std::string(to_string(bennett.setup)) + " setup";
  } else {
    const FamilyCheck* nearest = &out.checks.front();
    for (const FamilyCheck& c : out.checks) {
      if (c.residual < nearest->residual) nearest = &c;
    }
    out.residual = nearest->residual;
    char buffer[96];
    std::snprintf(buffer, sizeof buffer, "nearest family: %s (residual %.3g)", to_string(nearest->family),
                  nearest->residual);
    out.detail = buffer;
  }
  return out;
}

double family_distance(Family family, const LoopGeometry& geometry, GeometryVector* gradient) {
  validate_geometry(geometry);
  const int n = geometry.joints();
  Conditions c;
  const detail::Representation* writing = nullptr;
  switch (family) {
    case Family::bennett: {
      if (n != 4) throw std::invalid_argument("family_distance: Bennett loops have 4 joints");
      Best best = best_bennett(geometry, true);
      c = std::move(best.conditions);
      writing = best.writing;
      break;
    }
    case Family::planar: {
      Best best = best_planar(geometry, true);
      c = std::move(best.conditions);
      writing = best.writing;
      break;
    }
    case Family::spherical: c = spherical_conditions(geometry, false); break;
    case Family::trivial: {
      Best best = best_trivial_geometric(geometry, true);
      c = std::move(best.conditions);
      writing = best.writing;
      break;
    }
    case Family::unclassified: throw std::invalid_argument("family_distance: not a family");
  }
  if (gradient) {
    const GeometryVector g = c.norm_gradient(3 * n);
    *gradient = writing ? detail::pull_back(*writing, g) : g;
  }
  return c.norm();
}

}  // namespace loopfarm
