#include "loopfarm/search/classify.hpp"

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <span>
#include <stdexcept>

#include "representation.hpp"

// Two paths share one set of condition formulas (the templates below):
//
// - the reporting path (classify, family_distance_report) writes out every
//   writing of the loop as a LoopGeometry and keeps every condition of the
//   best one with its name: what a report lists;
// - the numeric path (family_distance, called on every evaluation of a
//   steered search) looks each writing's parameters up in small tables filled
//   once per call, keeps only the running sum of squares, gives a writing up
//   as soon as it cannot beat the best so far, and writes out only the best
//   writing, to differentiate it. It builds no string and allocates nothing.
//
// Both evaluate the same formulas on the same numbers in the same order, so
// they pick the same writing and return the same distance bit for bit.
namespace loopfarm {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kPi = 3.14159265358979323846;  // as representation.cpp's twist offsets

std::string label(const char* name, int k) { return name + std::to_string(k + 1); }

// Helpers for conditions built from x / L, L the length scale.
struct Scale {
  double L;
  GeometryVector dL;  // empty on the numeric path's search, which takes no gradients
  int n;
  // d(x_i / L) for parameter index i (a or d); x_i its value.
  GeometryVector ratio_gradient(int i, double x) const {
    assert(dL.size() == 3 * n);
    GeometryVector g = -(x / (L * L)) * dL;
    g[i] += 1.0 / L;
    return g;
  }
};

Scale scale_of(const LoopGeometry& g) { return {length_scale(g), length_scale_gradient(g), g.joints()}; }

// ---------------------------------------------------------------------------
// Writings as the conditions read them: parameters a(k), alpha(k), d(k) in
// the writing's labels, sin and cos of the twists, and the length scale.

// A writing written out (detail::apply, or the geometry as written) with its
// length scale and gradient.
struct WrittenOut {
  LoopGeometry g;
  Scale s;
  explicit WrittenOut(const LoopGeometry& geometry) : g(geometry), s(scale_of(g)) {}
  int joints() const { return g.joints(); }
  double a(int k) const { return g.a[k]; }
  double alpha(int k) const { return g.alpha[k]; }
  double d(int k) const { return g.d[k]; }
  double sin_alpha(int k) const { return std::sin(g.alpha[k]); }
  double cos_alpha(int k) const { return std::cos(g.alpha[k]); }
  const Scale& scale() const { return s; }
};

// ---------------------------------------------------------------------------
// Sinks: where a family's conditions go. Each condition comes as three lazy
// parts, its name, its value and its gradient with respect to the writing's
// (a, alpha, d); a sink evaluates only the parts it keeps.

// The sum of the squared values in the order they come; every norm here is its sqrt.
double sum_of_squares(std::span<const double> values) {
  double s = 0.0;
  for (double v : values) s += v * v;
  return s;
}

// d norm / dp, where the norm is not zero.
template <class Gradients>
GeometryVector norm_gradient_of(std::span<const double> values, const Gradients& gradients, int size) {
  GeometryVector g = GeometryVector::Zero(size);
  const double n = std::sqrt(sum_of_squares(values));
  if (n == 0.0) return g;
  for (size_t i = 0; i < values.size(); ++i) g += (values[i] / n) * gradients[i];
  return g;
}

// Reporting: every part of every condition.
struct Conditions {
  std::vector<std::string> names;
  std::vector<double> values;
  std::vector<GeometryVector> gradients;

  template <class Name, class Value, class Gradient>
  void add(const Name& name, const Value& value, const Gradient& gradient) {
    names.emplace_back(name());
    values.push_back(value());
    gradients.push_back(gradient());
  }
  double max_abs() const {
    double m = 0.0;
    for (double v : values) m = std::max(m, std::abs(v));
    return m;
  }
  double norm() const { return std::sqrt(sum_of_squares(values)); }
  GeometryVector norm_gradient(int size) const { return norm_gradient_of(values, gradients, size); }
};

// The numeric path's best writing: values and gradients, no names, in fixed
// storage (at most 2n conditions, the spherical family's).
struct FixedConditions {
  static constexpr int kCapacity = 2 * kMaxJoints;
  int count = 0;
  std::array<double, kCapacity> values;
  std::array<GeometryVector, kCapacity> gradients;

  template <class Name, class Value, class Gradient>
  void add(const Name&, const Value& value, const Gradient& gradient) {
    assert(count < kCapacity);
    values[static_cast<size_t>(count)] = value();
    gradients[static_cast<size_t>(count)] = gradient();
    ++count;
  }
  std::span<const double> kept() const { return {values.data(), static_cast<size_t>(count)}; }
  double norm() const { return std::sqrt(sum_of_squares(kept())); }
  GeometryVector norm_gradient(int size) const { return norm_gradient_of(kept(), gradients, size); }
};

// The numeric path's search: only the running sum of squares, summed as
// sum_of_squares sums it, and given up once it reaches `bound` (the best
// writing's sum so far). A writing given up cannot be strictly better than
// the best: adding a square never makes a floating-point sum smaller, and
// sqrt is monotone.
struct SquaredNorm {
  double bound = kInf;
  double sum = 0.0;
  bool abandoned = false;

  template <class Name, class Value, class Gradient>
  void add(const Name&, const Value& value, const Gradient&) {
    if (abandoned) return;
    const double v = value();
    sum += v * v;
    abandoned = sum >= bound;
  }
};

// ---------------------------------------------------------------------------
// The conditions of each family on one writing `w`, into sink `c`.

// Bennett conditions (n = 4) that both setups share: opposite links and
// twists equal, no offsets.
template <class Writing, class Sink>
void bennett_common_conditions(const Writing& w, Sink& c) {
  const int n = 4;
  const Scale& s = w.scale();
  auto length_difference = [&](int i, int j) {  // (a_i - a_j) / L
    c.add([&] { return label("a", i) + " - " + label("a", j); }, [&] { return (w.a(i) - w.a(j)) / s.L; },
          [&]() -> GeometryVector { return s.ratio_gradient(i, w.a(i)) - s.ratio_gradient(j, w.a(j)); });
  };
  auto twist_difference = [&](int i, int j) {
    c.add([&] { return label("alpha", i) + " - " + label("alpha", j); },
          [&] { return wrap_angle(w.alpha(i) - w.alpha(j)); },
          [&] {
            GeometryVector grad = GeometryVector::Zero(3 * n);
            grad[n + i] = 1.0;
            grad[n + j] = -1.0;
            return grad;
          });
  };
  length_difference(0, 2);
  length_difference(1, 3);
  twist_difference(0, 2);
  twist_difference(1, 3);
  for (int k = 0; k < n; ++k) {
    c.add([&] { return label("d", k); }, [&] { return w.d(k) / s.L; },
          [&] { return s.ratio_gradient(2 * n + k, w.d(k)); });
  }
}

// The Bennett condition of one setup; setup_sign +1 asymmetric, -1 line-symmetric.
template <class Writing, class Sink>
void bennett_setup_condition(const Writing& w, double setup_sign, Sink& c) {
  const int n = 4;
  const Scale& s = w.scale();
  // (a2 sin alpha1 - +- a1 sin alpha2) / L, paper labels (1-based).
  auto product = [&] { return w.a(1) * w.sin_alpha(0) - setup_sign * w.a(0) * w.sin_alpha(1); };
  c.add([&] { return setup_sign > 0 ? "a2 sin(alpha1) - a1 sin(alpha2)" : "a2 sin(alpha1) + a1 sin(alpha2)"; },
        [&] { return product() / s.L; },
        [&] {
          GeometryVector grad = -(product() / (s.L * s.L)) * s.dL;
          grad[1] += w.sin_alpha(0) / s.L;
          grad[0] += -setup_sign * w.sin_alpha(1) / s.L;
          grad[n + 0] += w.a(1) * w.cos_alpha(0) / s.L;
          grad[n + 1] += -setup_sign * w.a(0) * w.cos_alpha(1) / s.L;
          return grad;
        });
}

template <class Writing, class Sink>
void bennett_conditions(const Writing& w, double setup_sign, Sink& c) {
  bennett_common_conditions(w, c);
  bennett_setup_condition(w, setup_sign, c);
}

template <class Writing, class Sink>
void planar_conditions(const Writing& w, Sink& c) {
  const int n = w.joints();
  const Scale& s = w.scale();
  double sign = 1.0, sum = 0.0;
  std::array<double, kMaxJoints> signs;  // the sign of each offset in the sum
  for (int k = 0; k < n; ++k) {
    c.add([&] { return "sin(" + label("alpha", k) + ")"; }, [&] { return w.sin_alpha(k); },
          [&] {
            GeometryVector grad = GeometryVector::Zero(3 * n);
            grad[n + k] = w.cos_alpha(k);
            return grad;
          });
    // The offset d_k points along z_k, which is +-z_1 for parallel axes.
    sum += sign * w.d(k);
    signs[static_cast<size_t>(k)] = sign;
    if (w.cos_alpha(k) < 0.0) sign = -sign;
  }
  c.add([] { return "signed sum of d / L"; }, [&] { return sum / s.L; },
        [&]() -> GeometryVector {
          GeometryVector dsum = GeometryVector::Zero(3 * n);
          for (int k = 0; k < n; ++k) dsum[2 * n + k] = signs[static_cast<size_t>(k)];
          return dsum / s.L - (sum / (s.L * s.L)) * s.dL;
        });
}

// On the geometry as written (no writings): lengths in units of L when
// `normalised`, else in the geometry's own units.
template <class Sink>
void spherical_conditions(const LoopGeometry& g, bool normalised, Sink& c) {
  const int n = g.joints();
  const double L = normalised ? length_scale(g) : 1.0;
  for (int k = 0; k < n; ++k) {
    c.add([&] { return label("a", k); }, [&] { return g.a[k] / L; },
          [&] {
            GeometryVector grad = GeometryVector::Zero(3 * n);
            grad[k] = 1.0 / L;  // (used unnormalised only, where L = 1)
            return grad;
          });
  }
  for (int k = 0; k < n; ++k) {
    c.add([&] { return label("d", k); }, [&] { return g.d[k] / L; },
          [&] {
            GeometryVector grad = GeometryVector::Zero(3 * n);
            grad[2 * n + k] = 1.0 / L;
            return grad;
          });
  }
}

// Axes 1 and 2 of this writing coincide: a1 = 0 and sin(alpha1) = 0.
template <class Writing, class Sink>
void adjacent_coaxial_conditions(const Writing& w, Sink& c) {
  const int n = w.joints();
  const Scale& s = w.scale();
  c.add([] { return "a1"; }, [&] { return w.a(0) / s.L; }, [&] { return s.ratio_gradient(0, w.a(0)); });
  c.add([] { return "sin(alpha1)"; }, [&] { return w.sin_alpha(0); },
        [&] {
          GeometryVector grad = GeometryVector::Zero(3 * n);
          grad[n] = w.cos_alpha(0);
          return grad;
        });
}

// Axes 1 and 3 of a 4R writing coincide (docs/design.md, "Trivial").
template <class Writing, class Sink>
void coaxial_13_conditions(const Writing& w, Sink& c) {
  const int n = 4;
  const Scale& s = w.scale();
  c.add([] { return "a1 - a2"; }, [&] { return (w.a(0) - w.a(1)) / s.L; },
        [&]() -> GeometryVector { return s.ratio_gradient(0, w.a(0)) - s.ratio_gradient(1, w.a(1)); });
  c.add([] { return "a3 - a4"; }, [&] { return (w.a(2) - w.a(3)) / s.L; },
        [&]() -> GeometryVector { return s.ratio_gradient(2, w.a(2)) - s.ratio_gradient(3, w.a(3)); });
  for (int pair : {0, 2}) {
    c.add([&] { return label("alpha", pair) + " - " + label("alpha", pair + 1); },
          [&] { return wrap_angle(w.alpha(pair) - w.alpha(pair + 1)); },
          [&] {
            GeometryVector grad = GeometryVector::Zero(3 * n);
            grad[n + pair] = 1.0;
            grad[n + pair + 1] = -1.0;
            return grad;
          });
  }
  c.add([] { return "d2"; }, [&] { return w.d(1) / s.L; }, [&] { return s.ratio_gradient(2 * n + 1, w.d(1)); });
  c.add([] { return "d4"; }, [&] { return w.d(3) / s.L; }, [&] { return s.ratio_gradient(2 * n + 3, w.d(3)); });
  c.add([] { return "d1 + d3"; }, [&] { return (w.d(0) + w.d(2)) / s.L; },
        [&]() -> GeometryVector { return s.ratio_gradient(2 * n, w.d(0)) + s.ratio_gradient(2 * n + 2, w.d(2)); });
}


// ---------------------------------------------------------------------------
// 5R and 6R families (docs/families.md). Helpers for the conditions they
// share: a length difference, a twist sum or difference, an offset or a sum
// of offsets, and a Bennett product.

// (a_i + sign a_j) / L, or a_i / L alone when j < 0.
template <class Writing, class Sink>
void add_length(const Writing& w, Sink& c, const char* text, int i, int j, double sign) {
  const Scale& s = w.scale();
  c.add([&] { return std::string(text); },
        [&] { return (w.a(i) + (j >= 0 ? sign * w.a(j) : 0.0)) / s.L; },
        [&]() -> GeometryVector {
          GeometryVector g = s.ratio_gradient(i, w.a(i));
          if (j >= 0) g += sign * s.ratio_gradient(j, w.a(j));
          return g;
        });
}

// (d_i + sign d_j) / L, or d_i / L alone when j < 0.
template <class Writing, class Sink>
void add_offset(const Writing& w, Sink& c, const char* text, int i, int j, double sign) {
  const int n = w.joints();
  const Scale& s = w.scale();
  c.add([&] { return std::string(text); },
        [&] { return (w.d(i) + (j >= 0 ? sign * w.d(j) : 0.0)) / s.L; },
        [&]() -> GeometryVector {
          GeometryVector g = s.ratio_gradient(2 * n + i, w.d(i));
          if (j >= 0) g += sign * s.ratio_gradient(2 * n + j, w.d(j));
          return g;
        });
}

// wrap(alpha_i + sign alpha_j - shift) [rad].
template <class Writing, class Sink>
void add_twist(const Writing& w, Sink& c, const char* text, int i, int j, double sign, double shift = 0.0) {
  const int n = w.joints();
  c.add([&] { return std::string(text); }, [&] { return wrap_angle(w.alpha(i) + sign * w.alpha(j) - shift); },
        [&] {
          GeometryVector g = GeometryVector::Zero(3 * n);
          g[n + i] += 1.0;
          g[n + j] += sign;
          return g;
        });
}

// The Bennett product of links i and j: (a_i sin alpha_j - sign a_j sin alpha_i) / L,
// zero when sin(alpha_i)/a_i = sign sin(alpha_j)/a_j.
template <class Writing, class Sink>
void add_bennett_product(const Writing& w, Sink& c, const char* text, int i, int j, double sign) {
  const int n = w.joints();
  const Scale& s = w.scale();
  auto product = [&] { return w.a(i) * w.sin_alpha(j) - sign * w.a(j) * w.sin_alpha(i); };
  c.add([&] { return std::string(text); }, [&] { return product() / s.L; },
        [&] {
          GeometryVector g = -(product() / (s.L * s.L)) * s.dL;
          g[i] += w.sin_alpha(j) / s.L;
          g[j] += -sign * w.sin_alpha(i) / s.L;
          g[n + j] += w.a(i) * w.cos_alpha(j) / s.L;
          g[n + i] += -sign * w.a(j) * w.cos_alpha(i) / s.L;
          return g;
        });
}

// cos(alpha_i): zero when the twist is a right angle (either sign).
template <class Writing, class Sink>
void add_right_twist(const Writing& w, Sink& c, const char* text, int i) {
  const int n = w.joints();
  c.add([&] { return std::string(text); }, [&] { return w.cos_alpha(i); },
        [&] {
          GeometryVector g = GeometryVector::Zero(3 * n);
          g[n + i] = -w.sin_alpha(i);
          return g;
        });
}

// Goldberg 5R (n = 5): two Bennett loops (b, beta, a, alpha) and
// (b, beta, c, gamma) sharing the link (b, beta), written as links
// 1 (b, beta), 2 (a, alpha), 3 (c, gamma), 4 (b, beta) and 5, the two
// collinear links fused: (a + c, alpha + gamma) when they lie on opposite
// sides of the removed joint, (a - c, alpha - gamma) on the same side. Set
// bits: 0 the first loop's setup (sin alpha/a = -sin beta/b when set), 1 the
// second's, 2 the same-side (subtractive) fusion.
template <class Writing, class Sink>
void goldberg_conditions(int set, const Writing& w, Sink& c) {
  const double s1 = (set & 1) ? -1.0 : 1.0, s2 = (set & 2) ? -1.0 : 1.0;
  const bool subtractive = (set & 4) != 0;
  add_length(w, c, "a1 - a4", 0, 3, -1.0);
  add_twist(w, c, "alpha1 - alpha4", 0, 3, -1.0);
  static constexpr const char* kOffsets[] = {"d1", "d2", "d3", "d4", "d5"};
  for (int k = 0; k < 5; ++k) add_offset(w, c, kOffsets[k], k, -1, 0.0);
  add_bennett_product(w, c, s1 > 0 ? "a1 sin(alpha2) - a2 sin(alpha1)" : "a1 sin(alpha2) + a2 sin(alpha1)", 0, 1, s1);
  add_bennett_product(w, c, s2 > 0 ? "a1 sin(alpha3) - a3 sin(alpha1)" : "a1 sin(alpha3) + a3 sin(alpha1)", 0, 2, s2);
  // a5 - (a2 +- a3), alpha5 - (alpha2 +- alpha3).
  const double f = subtractive ? 1.0 : -1.0;  // sign of a3 in a5 - a2 + f a3
  const Scale& s = w.scale();
  const int n = 5;
  c.add([&] { return subtractive ? "a5 - (a2 - a3)" : "a5 - (a2 + a3)"; },
        [&] { return (w.a(4) - w.a(1) + f * w.a(2)) / s.L; },
        [&]() -> GeometryVector {
          return s.ratio_gradient(4, w.a(4)) - s.ratio_gradient(1, w.a(1)) + f * s.ratio_gradient(2, w.a(2));
        });
  c.add([&] { return subtractive ? "alpha5 - (alpha2 - alpha3)" : "alpha5 - (alpha2 + alpha3)"; },
        [&] { return wrap_angle(w.alpha(4) - w.alpha(1) + f * w.alpha(2)); },
        [&] {
          GeometryVector g = GeometryVector::Zero(3 * n);
          g[n + 4] = 1.0;
          g[n + 1] = -1.0;
          g[n + 2] = f;
          return g;
        });
}

// Myard 5R: the Goldberg 5R whose two Bennett loops are mirror images,
// which makes it plane-symmetric: a2 = a3, alpha3 = -alpha2 (bit 3 clear)
// or pi - alpha2 (bit 3 set), and the shared link's twist a right angle.
// Bits 0-2 as goldberg_conditions.
template <class Writing, class Sink>
void myard_conditions(int set, const Writing& w, Sink& c) {
  goldberg_conditions(set & 7, w, c);
  const double pi_shift = (set & 8) ? kPi : 0.0;
  add_length(w, c, "a2 - a3", 1, 2, -1.0);
  add_twist(w, c, (set & 8) ? "alpha2 + alpha3 - pi" : "alpha2 + alpha3", 1, 2, 1.0, pi_shift);
  add_right_twist(w, c, "cos(alpha1)", 0);
}

// Goldberg's 5R with the two links fused at any angle psi about the removed
// joint's axis (docs/families.md, "Goldberg 5R, bent fused link"). Links 1-4
// as goldberg_conditions; the fused link 5 (a5, alpha5) and the offsets d1,
// d5 it leaves at joints 1 and 5 are those of the screw product
// Rx(-alpha3) Tx(-a3) Rz(psi) Tx(a2) Rx(alpha2). Its dual-angle cosine rule
// with psi eliminated, and the Bennett relations sin(alpha2)/a2 = kappa,
// sin(alpha3)/a3 = sigma kappa (sigma = +1 when both Bennett loops are in the
// same setup, -1 otherwise), give three conditions:
//   d1 - sigma d5 = 0
//   a5 sin(alpha2) sin(alpha5) - a2 (sigma cos(alpha2) + cos(alpha3)) (1 - sigma cos(alpha5)) = 0
//   sin(alpha2)^2 d5^2 (1 + sigma cos(alpha5))^2 - a2^2 G = 0,
// G = 1 - cos^2(alpha2) - cos^2(alpha3) - cos^2(alpha5) + 2 cos(alpha2) cos(alpha3) cos(alpha5)
// (= sin^2(alpha2) sin^2(alpha3) sin^2(psi)); the last is squared so that it
// stays smooth where psi = 0 or pi (Goldberg's own loops, d1 = d5 = 0).
// Bits 0 and 1 of `set` as goldberg_conditions (the fusion side is psi).
template <class Writing, class Sink>
void goldberg_bent_conditions(int set, const Writing& w, Sink& c) {
  const double s1 = (set & 1) ? -1.0 : 1.0, s2 = (set & 2) ? -1.0 : 1.0, sigma = s1 * s2;
  const int n = 5;
  const Scale& s = w.scale();
  add_length(w, c, "a1 - a4", 0, 3, -1.0);
  add_twist(w, c, "alpha1 - alpha4", 0, 3, -1.0);
  add_offset(w, c, "d2", 1, -1, 0.0);
  add_offset(w, c, "d3", 2, -1, 0.0);
  add_offset(w, c, "d4", 3, -1, 0.0);
  add_bennett_product(w, c, s1 > 0 ? "a1 sin(alpha2) - a2 sin(alpha1)" : "a1 sin(alpha2) + a2 sin(alpha1)", 0, 1, s1);
  add_bennett_product(w, c, s2 > 0 ? "a1 sin(alpha3) - a3 sin(alpha1)" : "a1 sin(alpha3) + a3 sin(alpha1)", 0, 2, s2);
  add_offset(w, c, sigma > 0 ? "d1 - d5" : "d1 + d5", 0, 4, -sigma);
  // The fused link's length (the dual part of the cosine rule).
  auto length_term = [&] {
    return w.a(4) * w.sin_alpha(1) * w.sin_alpha(4) -
           w.a(1) * (sigma * w.cos_alpha(1) + w.cos_alpha(2)) * (1.0 - sigma * w.cos_alpha(4));
  };
  c.add([&] {
          return sigma > 0 ? "a5 sin(alpha2) sin(alpha5) - a2 (cos(alpha2) + cos(alpha3)) (1 - cos(alpha5))"
                           : "a5 sin(alpha2) sin(alpha5) - a2 (cos(alpha3) - cos(alpha2)) (1 + cos(alpha5))";
        },
        [&] { return length_term() / s.L; },
        [&] {
          const double P = sigma * w.cos_alpha(1) + w.cos_alpha(2), Q = 1.0 - sigma * w.cos_alpha(4);
          GeometryVector g = -(length_term() / (s.L * s.L)) * s.dL;
          g[4] += w.sin_alpha(1) * w.sin_alpha(4) / s.L;
          g[1] += -P * Q / s.L;
          g[n + 1] += (w.a(4) * w.cos_alpha(1) * w.sin_alpha(4) + w.a(1) * sigma * w.sin_alpha(1) * Q) / s.L;
          g[n + 2] += w.a(1) * w.sin_alpha(2) * Q / s.L;
          g[n + 4] += (w.a(4) * w.sin_alpha(1) * w.cos_alpha(4) - w.a(1) * P * sigma * w.sin_alpha(4)) / s.L;
          return g;
        });
  // The offsets against the fusion angle: sin^2(psi) from the real cosine rule, G.
  auto gram = [&] {
    const double c2 = w.cos_alpha(1), c3 = w.cos_alpha(2), c5 = w.cos_alpha(4);
    return 1.0 - c2 * c2 - c3 * c3 - c5 * c5 + 2.0 * c2 * c3 * c5;
  };
  auto offset_term = [&] {
    const double k = w.sin_alpha(1) * w.d(4) * (1.0 + sigma * w.cos_alpha(4));
    return k * k - w.a(1) * w.a(1) * gram();
  };
  c.add([&] {
          return sigma > 0 ? "(sin(alpha2) d5 (1 + cos(alpha5)))^2 - a2^2 G, over L^2"
                           : "(sin(alpha2) d5 (1 - cos(alpha5)))^2 - a2^2 G, over L^2";
        },
        [&] { return offset_term() / (s.L * s.L); },
        [&] {
          const double c2 = w.cos_alpha(1), c3 = w.cos_alpha(2), c5 = w.cos_alpha(4);
          const double s2v = w.sin_alpha(1), s3v = w.sin_alpha(2), s5v = w.sin_alpha(4);
          const double R = 1.0 + sigma * c5, k = s2v * w.d(4) * R, a2 = w.a(1), G = gram();
          const double L2 = s.L * s.L;
          GeometryVector g = -(2.0 * offset_term() / (L2 * s.L)) * s.dL;
          // dG/dalpha_i = 2 sin(alpha_i) (cos(alpha_i) - product of the other two cosines).
          g[n + 1] += (2.0 * k * c2 * w.d(4) * R - a2 * a2 * 2.0 * s2v * (c2 - c3 * c5)) / L2;
          g[n + 2] += (-a2 * a2 * 2.0 * s3v * (c3 - c2 * c5)) / L2;
          g[n + 4] += (2.0 * k * s2v * w.d(4) * (-sigma * s5v) - a2 * a2 * 2.0 * s5v * (c5 - c2 * c3)) / L2;
          g[2 * n + 4] += 2.0 * k * s2v * R / L2;
          g[1] += -2.0 * a2 * G / L2;
          return g;
        });
}

// Bricard line-symmetric 6R: a_i = a_{i+3}, alpha_i = alpha_{i+3}, d_i = d_{i+3}.
template <class Writing, class Sink>
void bricard_line_conditions(const Writing& w, Sink& c) {
  static constexpr const char* kA[] = {"a1 - a4", "a2 - a5", "a3 - a6"};
  static constexpr const char* kAlpha[] = {"alpha1 - alpha4", "alpha2 - alpha5", "alpha3 - alpha6"};
  static constexpr const char* kD[] = {"d1 - d4", "d2 - d5", "d3 - d6"};
  for (int i = 0; i < 3; ++i) add_length(w, c, kA[i], i, i + 3, -1.0);
  for (int i = 0; i < 3; ++i) add_twist(w, c, kAlpha[i], i, i + 3, -1.0);
  for (int i = 0; i < 3; ++i) add_offset(w, c, kD[i], i, i + 3, -1.0);
}

// Bricard plane-symmetric 6R, the plane through joints 1 and 4: a1 = a6,
// a2 = a5, a3 = a4, alpha1 = -alpha6, alpha2 = -alpha5, alpha3 = -alpha4,
// d1 = d4 = 0, d2 = -d6, d3 = -d5 (in this project's convention; the
// literature's "alpha12 + alpha61 = pi" is the same loop in its own).
template <class Writing, class Sink>
void bricard_plane_conditions(const Writing& w, Sink& c) {
  static constexpr const char* kA[] = {"a1 - a6", "a2 - a5", "a3 - a4"};
  static constexpr const char* kAlpha[] = {"alpha1 + alpha6", "alpha2 + alpha5", "alpha3 + alpha4"};
  for (int i = 0; i < 3; ++i) add_length(w, c, kA[i], i, 5 - i, -1.0);
  for (int i = 0; i < 3; ++i) add_twist(w, c, kAlpha[i], i, 5 - i, 1.0);
  add_offset(w, c, "d1", 0, -1, 0.0);
  add_offset(w, c, "d4", 3, -1, 0.0);
  add_offset(w, c, "d2 + d6", 1, 5, 1.0);
  add_offset(w, c, "d3 + d5", 2, 4, 1.0);
}

// Bricard trihedral 6R: every twist a right angle, every offset zero, and
// a1^2 + a3^2 + a5^2 = a2^2 + a4^2 + a6^2 (in units of L^2).
template <class Writing, class Sink>
void bricard_trihedral_conditions(const Writing& w, Sink& c) {
  const int n = 6;
  const Scale& s = w.scale();
  static constexpr const char* kCos[] = {"cos(alpha1)", "cos(alpha2)", "cos(alpha3)",
                                         "cos(alpha4)", "cos(alpha5)", "cos(alpha6)"};
  static constexpr const char* kD[] = {"d1", "d2", "d3", "d4", "d5", "d6"};
  for (int k = 0; k < n; ++k) add_right_twist(w, c, kCos[k], k);
  for (int k = 0; k < n; ++k) add_offset(w, c, kD[k], k, -1, 0.0);
  auto squares = [&] {
    double q = 0.0;
    for (int k = 0; k < n; ++k) q += (k % 2 == 0 ? 1.0 : -1.0) * w.a(k) * w.a(k);
    return q;
  };
  c.add([] { return "(a1^2 - a2^2 + a3^2 - a4^2 + a5^2 - a6^2) / L^2"; },
        [&] { return squares() / (s.L * s.L); },
        [&] {
          const double q = squares();
          GeometryVector g = -(2.0 * q / (s.L * s.L * s.L)) * s.dL;
          for (int k = 0; k < n; ++k) g[k] += (k % 2 == 0 ? 2.0 : -2.0) * w.a(k) / (s.L * s.L);
          return g;
        });
}

// Two Bennett loops sharing a link, the shared link removed and nothing fused
// (6R): loop 1 (A B C D) = (a, alpha, b, beta) and loop 2 (A F E D) =
// (c, gamma, b, beta) share the link DA = (b, beta) and its axes A and D; the
// 6R A B C D E F keeps every joint, so each loop still turns about the shared
// link on its own: two degrees of freedom (docs/families.md). Written as
// links 1 (a, alpha), 2 (b, beta), 3 (a, alpha), 4 (c, gamma), 5 (b, beta),
// 6 (c, gamma), every offset zero (joints 1 and 4 are A and D). Set bits: 0
// loop 1's setup (sin alpha/a = -sin beta/b when set), 1 loop 2's.
template <class Writing, class Sink>
void bennett_pair_conditions(int set, const Writing& w, Sink& c) {
  const double s1 = (set & 1) ? -1.0 : 1.0, s2 = (set & 2) ? -1.0 : 1.0;
  add_length(w, c, "a1 - a3", 0, 2, -1.0);
  add_twist(w, c, "alpha1 - alpha3", 0, 2, -1.0);
  add_length(w, c, "a4 - a6", 3, 5, -1.0);
  add_twist(w, c, "alpha4 - alpha6", 3, 5, -1.0);
  add_length(w, c, "a2 - a5", 1, 4, -1.0);
  add_twist(w, c, "alpha2 - alpha5", 1, 4, -1.0);
  static constexpr const char* kOffsets[] = {"d1", "d2", "d3", "d4", "d5", "d6"};
  for (int k = 0; k < 6; ++k) add_offset(w, c, kOffsets[k], k, -1, 0.0);
  add_bennett_product(w, c, s1 > 0 ? "a1 sin(alpha2) - a2 sin(alpha1)" : "a1 sin(alpha2) + a2 sin(alpha1)", 0, 1, s1);
  add_bennett_product(w, c, s2 > 0 ? "a4 sin(alpha5) - a5 sin(alpha4)" : "a4 sin(alpha5) + a5 sin(alpha4)", 3, 4, s2);
}

// Two Bennett dyads joined by two equal links (6R, docs/families.md; found
// by the generic 6R search): links 1, 2 with Bennett's ratio kappa1 =
// sin(alpha1)/a1 = sin(alpha2)/a2 and no offset between them (d2 = 0), links
// 4, 5 likewise (kappa2, d5 = 0), the same (cos alpha + cos beta) / kappa for
// both dyads, links 3 and 6 equal, and each dyad's two end joints the same
// offset (d1 = d3, d4 = d6).
template <class Writing, class Sink>
void bennett_dyads_conditions(const Writing& w, Sink& c) {
  const int n = 6;
  const Scale& s = w.scale();
  add_length(w, c, "a3 - a6", 2, 5, -1.0);
  add_twist(w, c, "alpha3 - alpha6", 2, 5, -1.0);
  add_offset(w, c, "d2", 1, -1, 0.0);
  add_offset(w, c, "d5", 4, -1, 0.0);
  add_offset(w, c, "d1 - d3", 0, 2, -1.0);
  add_offset(w, c, "d4 - d6", 3, 5, -1.0);
  add_bennett_product(w, c, "a1 sin(alpha2) - a2 sin(alpha1)", 0, 1, 1.0);
  add_bennett_product(w, c, "a4 sin(alpha5) - a5 sin(alpha4)", 3, 4, 1.0);
  // (cos alpha1 + cos alpha2) / kappa1 = (cos alpha4 + cos alpha5) / kappa2,
  // times sin(alpha1) sin(alpha4), over L.
  auto value = [&] {
    return (w.cos_alpha(0) + w.cos_alpha(1)) * w.a(0) * w.sin_alpha(3) -
           (w.cos_alpha(3) + w.cos_alpha(4)) * w.a(3) * w.sin_alpha(0);
  };
  c.add([] { return "((cos(alpha1) + cos(alpha2)) a1 sin(alpha4) - (cos(alpha4) + cos(alpha5)) a4 sin(alpha1)) / L"; },
        [&] { return value() / s.L; },
        [&] {
          GeometryVector g = -(value() / (s.L * s.L)) * s.dL;
          const double c12 = w.cos_alpha(0) + w.cos_alpha(1), c45 = w.cos_alpha(3) + w.cos_alpha(4);
          g[0] += c12 * w.sin_alpha(3) / s.L;
          g[3] += -c45 * w.sin_alpha(0) / s.L;
          g[n + 0] += (-w.sin_alpha(0) * w.a(0) * w.sin_alpha(3) - c45 * w.a(3) * w.cos_alpha(0)) / s.L;
          g[n + 1] += -w.sin_alpha(1) * w.a(0) * w.sin_alpha(3) / s.L;
          g[n + 3] += (c12 * w.a(0) * w.cos_alpha(3) + w.sin_alpha(3) * w.a(3) * w.sin_alpha(0)) / s.L;
          g[n + 4] += w.sin_alpha(4) * w.a(3) * w.sin_alpha(0) / s.L;
          return g;
        });
}

// The 5R families built from two Bennett loops sharing a link: Goldberg's,
// its symmetric case Myard's and its bent-link variant.
constexpr bool goldberg_type(Family family) {
  return family == Family::goldberg || family == Family::myard || family == Family::goldberg_bent;
}

// The condition sets of a writing that a family's score takes the best of,
// numbered: for Bennett loops set 0 is the asymmetric setup and set 1 the
// line-symmetric one; for trivial loops set 0 is axes 1 and 2 coinciding and
// set 1 (n = 4) axes 1 and 3; planar loops have one set; Goldberg and Myard
// sets as goldberg_conditions and myard_conditions say; Bricard loops one.
int condition_sets(Family family, int joints) {
  switch (family) {
    case Family::bennett: return 2;
    case Family::planar: return 1;
    case Family::trivial: return joints == 4 ? 2 : 1;
    case Family::goldberg: return 8;
    case Family::myard: return 16;
    case Family::goldberg_bent: return 4;
    case Family::bennett_pair: return 4;
    case Family::bennett_dyads:
    case Family::bricard_line_symmetric:
    case Family::bricard_plane_symmetric:
    case Family::bricard_trihedral: return 1;
    case Family::spherical:
    case Family::degenerate:
    case Family::unclassified: break;
  }
  return 0;  // no writings
}

// Whether a family's conditions read cosines of twists (the numeric path
// tabulates them only then).
constexpr bool reads_cosines(Family family) {
  return family == Family::planar || family == Family::myard || family == Family::goldberg_bent ||
         family == Family::bricard_trihedral || family == Family::bennett_dyads;
}

template <Family F, class Writing, class Sink>
void condition_set(int set, const Writing& w, Sink& c) {
  static_assert(F != Family::spherical && F != Family::degenerate && F != Family::unclassified);
  if constexpr (F == Family::bennett) {
    bennett_conditions(w, set == 0 ? 1.0 : -1.0, c);
  } else if constexpr (F == Family::planar) {
    planar_conditions(w, c);
  } else if constexpr (F == Family::goldberg) {
    goldberg_conditions(set, w, c);
  } else if constexpr (F == Family::myard) {
    myard_conditions(set, w, c);
  } else if constexpr (F == Family::goldberg_bent) {
    goldberg_bent_conditions(set, w, c);
  } else if constexpr (F == Family::bricard_line_symmetric) {
    bricard_line_conditions(w, c);
  } else if constexpr (F == Family::bricard_plane_symmetric) {
    bricard_plane_conditions(w, c);
  } else if constexpr (F == Family::bricard_trihedral) {
    bricard_trihedral_conditions(w, c);
  } else if constexpr (F == Family::bennett_pair) {
    bennett_pair_conditions(set, w, c);
  } else if constexpr (F == Family::bennett_dyads) {
    bennett_dyads_conditions(w, c);
  } else if (set == 0) {
    adjacent_coaxial_conditions(w, c);
  } else {
    coaxial_13_conditions(w, c);
  }
}

// ---------------------------------------------------------------------------
// The reporting path: every writing written out, every condition named.

// The best writing's conditions for a family, by max |condition| (for
// classification) or by norm (for distances).
struct Best {
  Conditions conditions;
  const detail::Representation* writing = nullptr;
  double score = kInf;
  double setup_sign = 0.0;  // Bennett: +1 asymmetric, -1 line-symmetric
  int set = 0;              // the best writing's condition set (condition_sets)
};

template <Family F>
Best best_over_writings(const LoopGeometry& g, bool by_norm) {
  Best best;
  const int sets = condition_sets(F, g.joints());
  for (const detail::Representation& r : detail::representations(g.joints())) {
    const WrittenOut w(detail::apply(r, g));
    for (int set = 0; set < sets; ++set) {
      Conditions c;
      condition_set<F>(set, w, c);
      const double score = by_norm ? c.norm() : c.max_abs();
      if (score < best.score) {
        best.score = score;
        best.conditions = std::move(c);
        best.writing = &r;
        best.setup_sign = F == Family::bennett ? (set == 0 ? 1.0 : -1.0) : 0.0;
        best.set = set;
      }
    }
  }
  return best;
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

// ---------------------------------------------------------------------------
// Families decided by the geometry alone, by joint count, for classify() and
// for the merged loop of a degenerate one.

// best_over_writings for a family named at run time (those with writings).
Best best_for(Family family, const LoopGeometry& g, bool by_norm) {
  switch (family) {
    case Family::bennett: return best_over_writings<Family::bennett>(g, by_norm);
    case Family::planar: return best_over_writings<Family::planar>(g, by_norm);
    case Family::trivial: return best_over_writings<Family::trivial>(g, by_norm);
    case Family::goldberg: return best_over_writings<Family::goldberg>(g, by_norm);
    case Family::myard: return best_over_writings<Family::myard>(g, by_norm);
    case Family::goldberg_bent: return best_over_writings<Family::goldberg_bent>(g, by_norm);
    case Family::bricard_line_symmetric: return best_over_writings<Family::bricard_line_symmetric>(g, by_norm);
    case Family::bricard_plane_symmetric: return best_over_writings<Family::bricard_plane_symmetric>(g, by_norm);
    case Family::bricard_trihedral: return best_over_writings<Family::bricard_trihedral>(g, by_norm);
    case Family::bennett_pair: return best_over_writings<Family::bennett_pair>(g, by_norm);
    case Family::bennett_dyads: return best_over_writings<Family::bennett_dyads>(g, by_norm);
    case Family::spherical:
    case Family::degenerate:
    case Family::unclassified: break;
  }
  throw std::logic_error(std::string("best_for: no writings for ") + to_string(family));
}

// A family's check on the geometry alone (not trivial, not degenerate).
FamilyCheck family_check(Family family, const LoopGeometry& g) {
  Best best;
  if (family == Family::spherical) {
    spherical_conditions(g, true, best.conditions);
    best.score = best.conditions.max_abs();
  } else {
    best = best_for(family, g, false);
  }
  FamilyCheck check = check_from(family, best);
  if (family == Family::bennett) {
    check.setup = best.setup_sign > 0 ? BennettSetup::asymmetric : BennettSetup::line_symmetric;
  }
  if (goldberg_type(family)) check.setup = BennettSetup::none;
  return check;
}

// The n-specific families beyond planar and spherical, in the order they are
// tried (the more special first).
std::vector<Family> special_families(int n) {
  switch (n) {
    case 4: return {Family::bennett};
    case 5: return {Family::myard, Family::goldberg, Family::goldberg_bent};
    case 6:
      return {Family::bricard_trihedral, Family::bricard_plane_symmetric, Family::bricard_line_symmetric,
              Family::bennett_pair, Family::bennett_dyads};
    default: return {};
  }
}

// The loop with joints k and k + 1 merged (a_k = 0 and alpha_k snapped to 0
// or pi): joint k keeps offset d_k +- d_{k+1}, the next link's twist gains
// the snapped alpha_k. T_k T_{k+1} = Rz(theta_k +- theta_{k+1})
// Tz(d_k +- d_{k+1}) Tx(a_{k+1}) Rx(alpha_{k+1} + alpha_k) exactly when
// a_k = 0 and alpha_k is 0 (+) or pi (-).
LoopGeometry merged_loop(const LoopGeometry& g, int k) {
  const LoopGeometry w = relabelled(g, k);
  const int n = g.joints();
  const bool flipped = std::cos(w.alpha[0]) < 0.0;
  LoopGeometry r;
  r.a = w.a.tail(n - 1);
  r.alpha = w.alpha.tail(n - 1);
  r.d.resize(n - 1);
  r.d[0] = w.d[0] + (flipped ? -w.d[1] : w.d[1]);
  r.d.tail(n - 2) = w.d.tail(n - 2);
  if (flipped) r.alpha[0] = wrap_angle(r.alpha[0] + kPi);
  return r;
}

struct GeometricFit {
  Family family = Family::unclassified;
  double residual = kInf;
  std::string detail;
};

GeometricFit degenerate_fit(const LoopGeometry& g, double tolerance, FamilyCheck& check);

// The best-fitting movable family of a loop by its geometry alone (planar,
// spherical, degenerate, then the n-specific ones), for a merged loop: once a
// family fits (residual <= tolerance), a later one replaces it only when it
// fits and an earlier, more special one does not (goldberg_bent, which holds
// every Goldberg loop, fits them to round-off too).
GeometricFit geometric_fit(const LoopGeometry& g, double tolerance) {
  const int n = g.joints();
  GeometricFit best;
  std::vector<Family> families = {Family::planar, Family::spherical};
  for (Family f : special_families(n)) families.push_back(f);
  for (Family f : families) {
    const FamilyCheck c = family_check(f, g);
    if (c.residual < best.residual && !(best.residual <= tolerance)) {
      best = {f, c.residual, to_string(f)};
      if (f == Family::bennett) best.detail += std::string(" (") + to_string(c.setup) + " setup)";
    }
  }
  if (n == 5) {
    FamilyCheck degenerate;
    const GeometricFit d = degenerate_fit(g, tolerance, degenerate);
    if (d.residual < best.residual) best = d;
  }
  return best;
}

// Degenerate: over the adjacent pairs of axes, max(a_k / L, |sin alpha_k|,
// the merged loop's best family residual), the least; only pairs that can
// still beat the best so far are merged and classified.
GeometricFit degenerate_fit(const LoopGeometry& g, double tolerance, FamilyCheck& check) {
  const int n = g.joints();
  const double L = length_scale(g);
  std::vector<std::pair<double, int>> pairs;
  for (int k = 0; k < n; ++k) pairs.push_back({std::max(g.a[k] / L, std::abs(std::sin(g.alpha[k]))), k});
  std::stable_sort(pairs.begin(), pairs.end(), [](const auto& x, const auto& y) { return x.first < y.first; });
  check = FamilyCheck{};
  check.family = Family::degenerate;
  check.residual = kInf;
  GeometricFit out;
  out.family = Family::degenerate;
  for (const auto& [pair_residual, k] : pairs) {
    if (!(pair_residual < out.residual)) break;
    const GeometricFit merged = geometric_fit(merged_loop(g, k), tolerance);
    const double residual = std::max(pair_residual, merged.residual);
    if (residual < out.residual) {
      out.residual = residual;
      const int j = (k + 1) % n;
      out.detail = "axes " + std::to_string(k + 1) + " and " + std::to_string(j + 1) + " coincide; merged " +
                   std::to_string(n - 1) + "R: " + merged.detail;
      check.residual = residual;
      check.conditions = {{label("a", k) + " / L", g.a[k] / L},
                          {"sin(" + label("alpha", k) + ")", std::sin(g.alpha[k])},
                          {"merged " + std::to_string(n - 1) + "R loop: " + to_string(merged.family) + " residual",
                           merged.residual}};
    }
  }
  return out;
}

// A fixed transform M between two frames whose z axes are joint axes P and
// Q, written as one DH link between them: M = Tz(u) Rz(p) Tx(a) Rx(alpha)
// Rz(q) Tz(v), a >= 0 the common normal, u and v where it meets P and Q.
// Parallel axes have no unique normal: the one through P's origin (u = 0).
struct LinkBetween {
  double u = 0.0, p = 0.0, a = 0.0, alpha = 0.0, q = 0.0, v = 0.0;
};

LinkBetween link_between(const Eigen::Isometry3d& M) {
  const Vector3 z = Vector3::UnitZ(), zq = M.linear().col(2), o = M.translation();
  // Closest points s z (on P) and o + t zq (on Q).
  const double b = z.dot(zq), du = -o.z(), dv = -zq.dot(o), den = 1.0 - b * b;
  double s = 0.0, t = -zq.dot(o);
  if (den > 1e-14) {
    s = (b * dv - du) / den;
    t = (dv - b * du) / den;
  }
  const Vector3 foot_p = s * z, foot_q = o + t * zq;
  LinkBetween out;
  Vector3 x = foot_q - foot_p;
  out.a = x.norm();
  if (out.a > 1e-12) {
    x /= out.a;
  } else {  // intersecting axes: the normal is their cross product (or any, when they coincide)
    out.a = 0.0;
    const Vector3 n = z.cross(zq);
    x = n.norm() > 1e-12 ? Vector3(n.normalized()) : Vector3::UnitX();
  }
  out.alpha = std::atan2(z.cross(zq).dot(x), b);
  out.u = s;
  out.p = std::atan2(x.y(), x.x());
  out.v = -t;
  const Vector3 xq = M.linear().col(0);
  out.q = std::atan2(x.cross(xq).dot(zq), x.dot(xq));
  return out;
}

// A loop in a pose, with the original index of each of its joints.
struct PosedLoop {
  LoopGeometry g;
  JointVector theta;
  std::vector<int> original;
};

// The (n-1)R loop left when joint k is locked at its angle: links k-1 and k
// and the joint between them become one rigid link from axis k-1 to axis k+1
// (link_between), which moves the feet of the normals on those axes (their
// offsets and angles change). Written with joint k+1 first.
PosedLoop locked_loop(const PosedLoop& loop, int k) {
  const int n = loop.g.joints();
  const LoopGeometry w = relabelled(loop.g, k + 1);  // the locked joint last, its neighbours n - 2 and 0
  const JointVector theta = relabelled_angles(loop.theta, k + 1);
  const Eigen::Isometry3d M = Eigen::Translation3d(w.a[n - 2], 0.0, 0.0) *
                              Eigen::AngleAxisd(w.alpha[n - 2], Vector3::UnitX()) *
                              joint_transform(theta[n - 1], w.d[n - 1], w.a[n - 1], w.alpha[n - 1]);
  const LinkBetween link = link_between(M);
  PosedLoop out;
  out.g.a = w.a.head(n - 1);
  out.g.alpha = w.alpha.head(n - 1);
  out.g.d = w.d.head(n - 1);
  out.g.a[n - 2] = link.a;
  out.g.alpha[n - 2] = link.alpha;
  out.g.d[n - 2] += link.u;
  out.g.d[0] += link.v;
  out.theta = theta.head(n - 1);
  out.theta[n - 2] += link.p;
  out.theta[0] += link.q;
  for (int j = 0; j < n - 1; ++j) out.original.push_back(loop.original[static_cast<size_t>((j + k + 1) % n)]);
  return out;
}

// Locked joints: the best fit (geometric_fit) of the loop left by locking
// one frozen joint, or all of them together (a 6R with two joints locked is
// a 4R), never below 4 joints (a 4R with a joint locked is a 3R, which
// cannot move); for n >= 5.
GeometricFit locked_fit(const LoopGeometry& g, const JointVector& pose, const std::vector<int>& frozen,
                        std::span<const double> travel, double tolerance, double frozen_travel, FamilyCheck& check) {
  const int n = g.joints();
  PosedLoop whole{g, pose, {}};
  for (int j = 0; j < n; ++j) whole.original.push_back(j);
  std::vector<std::vector<int>> choices;
  for (int k : frozen) choices.push_back({k});
  if (frozen.size() > 1 && n - static_cast<int>(frozen.size()) >= 4) choices.push_back(frozen);
  GeometricFit out;
  out.family = Family::degenerate;
  auto lock = [&](const std::vector<int>& locked, const JointVector& angles) {
    PosedLoop loop = whole;
    loop.theta = angles;
    for (int original : locked) {
      const auto at = std::find(loop.original.begin(), loop.original.end(), original);
      loop = locked_loop(loop, static_cast<int>(at - loop.original.begin()));
    }
    return loop;
  };
  for (const std::vector<int>& locked : choices) {
    PosedLoop loop = lock(locked, pose);
    GeometricFit fit = geometric_fit(loop.g, tolerance);
    // A joint that rocks (travel above frozen_travel) has no one angle: over
    // the motion it stays within its travel of the pose's angle, so it is
    // locked at the best angle of that window (golden-section search on the
    // locked loop's residual; the pose may sit where the joint rocks most).
    const int k = locked.front();
    const double window = travel[static_cast<size_t>(k)];
    if (locked.size() == 1 && window > frozen_travel) {
      const double golden = 0.5 * (std::sqrt(5.0) - 1.0);
      double lo = pose[k] - window, hi = pose[k] + window;
      auto residual_at = [&](double angle) {
        JointVector angles = pose;
        angles[k] = angle;
        return geometric_fit(lock(locked, angles).g, tolerance).residual;
      };
      double x1 = hi - golden * (hi - lo), x2 = lo + golden * (hi - lo);
      double f1 = residual_at(x1), f2 = residual_at(x2);
      for (int it = 0; it < 60 && hi - lo > 1e-15; ++it) {
        if (f1 <= f2) {
          hi = x2, x2 = x1, f2 = f1;
          x1 = hi - golden * (hi - lo), f1 = residual_at(x1);
        } else {
          lo = x1, x1 = x2, f1 = f2;
          x2 = lo + golden * (hi - lo), f2 = residual_at(x2);
        }
      }
      JointVector angles = pose;
      angles[k] = f1 <= f2 ? x1 : x2;
      const PosedLoop best = lock(locked, angles);
      const GeometricFit best_fit = geometric_fit(best.g, tolerance);
      if (best_fit.residual < fit.residual) {
        loop = best;
        fit = best_fit;
      }
    }
    if (!(fit.residual < out.residual)) continue;
    out.residual = fit.residual;
    std::string joints, travels;
    double most = 0.0;
    for (int k : locked) {
      joints += (joints.empty() ? "" : ", ") + std::to_string(k + 1);
      most = std::max(most, travel[static_cast<size_t>(k)]);
    }
    const std::string remaining = std::to_string(loop.g.joints()) + "R";
    char buffer[96];
    // A joint that rocks by more than frozen_travel (rocking_travel) is a
    // near-miss's: said so.
    if (most > frozen_travel) {
      std::snprintf(buffer, sizeof buffer, " nearly locked (rocks %.2g rad, above frozen_travel); ", most);
    } else {
      std::snprintf(buffer, sizeof buffer, " locked (travel %.2g rad); ", most);
    }
    out.detail = (locked.size() > 1 ? "joints " : "joint ") + joints + buffer + "locked " + remaining + ": " +
                 fit.detail;
    check.conditions = {{(locked.size() > 1 ? "largest travel of joints " : "joint ") + joints + " [rad]", most},
                        {"locked " + remaining + " loop: " + to_string(fit.family) + " residual", fit.residual}};
  }
  check.residual = out.residual;
  return out;
}

// A loop that fits goldberg, myard or goldberg_bent with one of its two
// Bennett loops equilateral and folding: (a, alpha) twice with Bennett's
// angle relation singular, tan(t1/2) tan(t2/2) = sin((alpha2 + alpha1)/2) /
// sin((alpha2 - alpha1)/2) (asymmetric setup) or cos(..) / cos(..)
// (line-symmetric) with a zero denominator. Such a "Bennett loop" only folds,
// so the 5R has no Goldberg motion (docs/discovery-5r-6r.md). It folds in two
// ways. Folded with the joint next to the fused link locked at pi (writing
// joint 5 when the second loop folds, joint 1 when the first does), the two
// axes at its other ends coincide with the removed axis A and the loop turns
// about it freely: the 5R moves as the other Bennett loop with that joint
// locked, a degenerate loop whatever motion a search followed. Folded the
// other way it locks the other loop: two 5R axes coincide and only they turn
// (trivial). Both motions meet where the loop folds both ways, and a walk
// through that pose can switch or stray between them, so no joint's travel
// need look frozen (docs/discovery-5r-6r.md, "Goldberg geometries on a
// folding Bennett loop"). Checked in the family's best writing, links 1 and 2
// (first loop) and 1 and 3 (second), to `tolerance` (lengths over L).
struct FoldingGoldberg {
  bool folds = false;
  double residual = kInf;  // the family's residual and the fold's two conditions, the largest
  std::string detail;
  FamilyCheck check;
};

FoldingGoldberg folding_goldberg(Family family, const LoopGeometry& g, double family_residual, double tolerance) {
  FoldingGoldberg out;
  if (!goldberg_type(family)) return out;
  const Best best = best_for(family, g, false);
  const LoopGeometry w = detail::apply(*best.writing, g);
  const double L = length_scale(w);
  auto fold = [&](int loop, double& length, double& denominator) {
    const int link = loop + 1;
    const bool line_symmetric = ((best.set >> loop) & 1) != 0;
    const double half = 0.5 * (w.alpha[link] - w.alpha[0]);
    length = (w.a[link] - w.a[0]) / L;
    denominator = line_symmetric ? std::cos(half) : std::sin(half);
    return std::abs(length) <= tolerance && std::abs(denominator) <= tolerance;
  };
  for (int loop = 0; loop < 2; ++loop) {
    double length = 0.0, denominator = 0.0;
    if (!fold(loop, length, denominator)) continue;
    out.folds = true;
    out.residual = std::max({family_residual, std::abs(length), std::abs(denominator)});
    // The links of the folding loop in the 5R (writing links 1, 2 or 3, and 4,
    // which equals 1) and the joint it locks, in the loop's own labels; the
    // other Bennett loop (writing links 1 and 3 or 2, twice) is the 4R left.
    const detail::Representation& r = *best.writing;
    const int folded_link = loop == 0 ? 1 : 2;
    const int other_link = loop == 0 ? 2 : 1;
    std::vector<int> links = {r.index[0], r.index[static_cast<size_t>(folded_link)], r.index[3]};
    std::sort(links.begin(), links.end());
    const int locked_joint = r.angle_index[loop == 1 ? 4 : 0];
    const LoopGeometry moving = LoopGeometry{
        (JointVector(4) << w.a[0], w.a[other_link], w.a[0], w.a[other_link]).finished(),
        (JointVector(4) << w.alpha[0], w.alpha[other_link], w.alpha[0], w.alpha[other_link]).finished(),
        JointVector::Zero(4)};
    const GeometricFit fit = geometric_fit(moving, tolerance);
    double other_length = 0.0, other_denominator = 0.0;
    const bool both = fold(1 - loop, other_length, other_denominator);
    std::string names;
    for (int k : links) names += (names.empty() ? "" : ", ") + std::to_string(k + 1);
    out.detail = std::string(to_string(family)) + "'s conditions on a folding Bennett loop (links " + names +
                 " equal): moves with joint " + std::to_string(locked_joint + 1) + " locked; locked 4R: " +
                 to_string(fit.family) + (both ? " (folding too)" : "");
    out.check.family = Family::degenerate;
    out.check.residual = out.residual;
    out.check.conditions = {{std::string(to_string(family)) + " residual", family_residual},
                            {"folding loop: (link - link 1) / L", length},
                            {"folding loop: denominator of its angle relation", denominator}};
    return out;
  }
  return out;
}

// The detail line of a 5R or 6R family found.
std::string special_detail(Family family, const LoopGeometry& g) {
  if (family == Family::goldberg_bent) {
    // The fusion angle |psi| from the real cosine rule of the best writing:
    // cos(alpha5) = cos(alpha2) cos(alpha3) + sin(alpha2) sin(alpha3) cos(psi).
    const Best best = best_over_writings<Family::goldberg_bent>(g, false);
    const LoopGeometry w = detail::apply(*best.writing, g);
    const double cos_psi = (std::cos(w.alpha[4]) - std::cos(w.alpha[1]) * std::cos(w.alpha[2])) /
                           (std::sin(w.alpha[1]) * std::sin(w.alpha[2]));
    const double psi_deg = std::acos(std::clamp(cos_psi, -1.0, 1.0)) * 180.0 / kPi;
    const bool same = ((best.set & 1) != 0) == ((best.set & 2) != 0);
    char buffer[160];
    std::snprintf(buffer, sizeof buffer,
                  "links fused at %.4g deg (0: same side, 180: opposite sides), d1 = %sd5 = %.4g L, Bennett loops "
                  "in %s setups",
                  psi_deg, same ? "" : "-", w.d[0] / length_scale(w), same ? "the same" : "different");
    return buffer;
  }
  if (family == Family::bennett_pair) {
    const Best best = best_over_writings<Family::bennett_pair>(g, false);
    const LoopGeometry w = detail::apply(*best.writing, g);
    char buffer[200];
    std::snprintf(buffer, sizeof buffer,
                  "two Bennett loops (links 1-3 and 4-6 of the best writing) sharing a removed link (%.4g L, "
                  "%.4g deg) between joints 1 and 4, in %s setups; two degrees of freedom",
                  w.a[1] / length_scale(w), w.alpha[1] * 180.0 / kPi,
                  ((best.set & 1) != 0) == ((best.set & 2) != 0) ? "the same" : "different");
    return buffer;
  }
  if (family == Family::bennett_dyads) {
    const Best best = best_over_writings<Family::bennett_dyads>(g, false);
    const LoopGeometry w = detail::apply(*best.writing, g);
    const double L = length_scale(w);
    char buffer[240];
    std::snprintf(buffer, sizeof buffer,
                  "Bennett dyads (links 1-2 and 4-5 of the best writing, (cos alpha + cos beta) / kappa = %.4g L) "
                  "joined by two equal links (%.4g L, %.4g deg), offsets %.4g L and %.4g L at the dyads' ends",
                  (std::cos(w.alpha[0]) + std::cos(w.alpha[1])) * w.a[0] / std::sin(w.alpha[0]) / L, w.a[2] / L,
                  w.alpha[2] * 180.0 / kPi, w.d[0] / L, w.d[3] / L);
    return buffer;
  }
  if (family != Family::goldberg && family != Family::myard) {
    switch (family) {
      case Family::bricard_line_symmetric: return "line symmetry: link i and joint i as link and joint i + 3";
      case Family::bricard_plane_symmetric: return "plane symmetry through joints 1 and 4 of the best writing";
      case Family::bricard_trihedral: return "right-angle twists, no offsets, a1^2 + a3^2 + a5^2 = a2^2 + a4^2 + a6^2";
      default: return "";
    }
  }
  const Best best = family == Family::goldberg ? best_over_writings<Family::goldberg>(g, false)
                                               : best_over_writings<Family::myard>(g, false);
  std::string d = (best.set & 4) ? "fused links on the same side (a5 = a2 - a3)"
                                 : "fused links on opposite sides (a5 = a2 + a3)";
  d += std::string(", Bennett loops ") + ((best.set & 1) ? "line-symmetric" : "asymmetric") + " and " +
       ((best.set & 2) ? "line-symmetric" : "asymmetric") + " in the best writing";
  return d;
}

// ---------------------------------------------------------------------------
// The numeric path: the writings looked up, not written out.

// The twist offsets detail::representations puts on a twist: none, one axis
// flipped (pi), both axes flipped (pi + pi).
constexpr std::array<double, 3> kTwistOffsets = {0.0, kPi, kPi + kPi};

// One writing as indices into the values of one call (Tables).
struct CompiledWriting {
  std::array<std::uint8_t, kMaxJoints> a{};      // a'_k = Tables::a[a[k]]
  std::array<std::uint8_t, kMaxJoints> twist{};  // alpha'_k = Tables::twist[twist[k]], likewise sin, cos
  std::array<std::uint8_t, kMaxJoints> d{};      // d'_k = Tables::d[d[k]]
};

// The writings of an n-joint loop in detail::representations order: for each
// of the 2n (shift, reversal) orders, its 2^n sets of axis flips, which
// change signs and twist offsets but move no parameter.
struct WritingTable {
  const std::vector<detail::Representation>* representations = nullptr;
  std::vector<CompiledWriting> writings;
};

// Whether two writings take their lengths and offsets from the same joints.
[[maybe_unused]] bool same_places(const CompiledWriting& w, const CompiledWriting& v, int n) {
  for (size_t k = 0; k < static_cast<size_t>(n); ++k) {
    if (w.a[k] != v.a[k] || w.d[k] / 2 != v.d[k] / 2) return false;
  }
  return true;
}

WritingTable build_writing_table(int n) {
  WritingTable table;
  table.representations = &detail::representations(n);
  [[maybe_unused]] const size_t flips = size_t{1} << n;
  table.writings.reserve(table.representations->size());
  for (size_t i = 0; i < table.representations->size(); ++i) {
    const detail::Representation& r = (*table.representations)[i];
    assert(r.flips == i % flips);
    CompiledWriting w;
    for (int k = 0; k < n; ++k) {
      const auto ia = static_cast<size_t>(k), it = static_cast<size_t>(n + k), id = static_cast<size_t>(2 * n + k);
      // a'_k = 1 * a_j + 0.
      assert(r.sign[ia] == 1.0 && r.offset[ia] == 0.0 && !std::signbit(r.offset[ia]));
      w.a[ia] = static_cast<std::uint8_t>(r.index[ia]);
      // alpha'_k = wrap(1 * alpha_j + m pi).
      assert(r.sign[it] == 1.0);
      const auto m = static_cast<int>(std::find(kTwistOffsets.begin(), kTwistOffsets.end(), r.offset[it]) -
                                      kTwistOffsets.begin());
      assert(m < 3);
      w.twist[ia] = static_cast<std::uint8_t>(3 * (r.index[it] - n) + m);
      // d'_k = +-1 * d_j +- 0 (the offset's zero carries the sign).
      const bool negated = r.sign[id] < 0.0;
      assert(std::abs(r.sign[id]) == 1.0 && r.offset[id] == 0.0 && std::signbit(r.offset[id]) == negated);
      w.d[ia] = static_cast<std::uint8_t>(2 * (r.index[id] - 2 * n) + (negated ? 1 : 0));
    }
    // Flips move no parameter, so a writing's lengths, and L, are those of its order's first writing.
    assert(same_places(w, i % flips == 0 ? w : table.writings[i - i % flips], n));
    table.writings.push_back(w);
  }
  return table;
}

// Built on first use, once per joint count (thread-safe static initialisation).
template <int N>
const WritingTable& writing_table_for() {
  static const WritingTable table = build_writing_table(N);
  return table;
}

const WritingTable& writing_table(int n) {
  static_assert(kMinJoints == 4 && kMaxJoints == 8, "one case per joint count");
  switch (n) {
    case 4: return writing_table_for<4>();
    case 5: return writing_table_for<5>();
    case 6: return writing_table_for<6>();
    case 7: return writing_table_for<7>();
    case 8: return writing_table_for<8>();
  }
  throw std::logic_error("writing_table: unvalidated joint count " + std::to_string(n));
}

// The values the writings' parameters take for one geometry: every a_j, every
// +-d_j, every twist alpha_j + m pi (m = 0, 1, 2) wrapped, with its sine and,
// when asked, its cosine. Computed as detail::apply computes them (sign *
// value + offset, twists then wrapped), so a lookup gives the written-out
// writing's number bit for bit.
struct Tables {
  int n = 0;
  std::array<double, kMaxJoints> a;
  std::array<double, 2 * kMaxJoints> d;                // 2j: d_j, 2j + 1: -d_j
  std::array<double, 3 * kMaxJoints> twist, sin, cos;  // 3j + m: alpha_j + m pi
};

Tables tabulate(const LoopGeometry& g, bool cosines) {
  Tables t;
  t.n = g.joints();
  for (int j = 0; j < t.n; ++j) {
    const auto ij = static_cast<size_t>(j);
    t.a[ij] = 1.0 * g.a[j] + 0.0;
    t.d[2 * ij] = 1.0 * g.d[j] + 0.0;
    t.d[2 * ij + 1] = -1.0 * g.d[j] + -0.0;
    for (size_t m = 0; m < 3; ++m) {
      const double alpha = wrap_angle(1.0 * g.alpha[j] + kTwistOffsets[m]);
      t.twist[3 * ij + m] = alpha;
      t.sin[3 * ij + m] = std::sin(alpha);
      if (cosines) t.cos[3 * ij + m] = std::cos(alpha);
    }
  }
  return t;
}

// One writing as the conditions read it, from the tables.
struct TabulatedWriting {
  const Tables& t;
  const CompiledWriting& w;
  const Scale& s;  // L only: the search takes no gradients
  int joints() const { return t.n; }
  double a(int k) const { return t.a[w.a[static_cast<size_t>(k)]]; }
  double alpha(int k) const { return t.twist[w.twist[static_cast<size_t>(k)]]; }
  double d(int k) const { return t.d[w.d[static_cast<size_t>(k)]]; }
  double sin_alpha(int k) const { return t.sin[w.twist[static_cast<size_t>(k)]]; }
  double cos_alpha(int k) const { return t.cos[w.twist[static_cast<size_t>(k)]]; }
  const Scale& scale() const { return s; }
};

// A writing's length scale as scale_of computes it on the written-out
// writing: length_scale on its lengths and offsets, in its order.
double length_scale_of(const Tables& t, const CompiledWriting& w) {
  LoopGeometry lengths;
  lengths.a.resize(t.n);
  lengths.d.resize(t.n);
  for (int k = 0; k < t.n; ++k) {
    lengths.a[k] = t.a[w.a[static_cast<size_t>(k)]];
    lengths.d[k] = t.d[w.d[static_cast<size_t>(k)]];
  }
  return length_scale(lengths);
}

// The best writing so far, kept as best_over_writings keeps it by norm: a
// condition set replaces it only when its norm is strictly smaller, so the
// first of equal ones stays.
struct Search {
  double sum = kInf;  // of squares, of the best writing's conditions
  double norm = kInf;
  int writing = -1;   // index in detail::representations order
  int set = 0;        // which condition set (condition_set)

  void keep(const SquaredNorm& c, int index, int which) {
    // A sum not below the best's cannot have a smaller sqrt.
    if (c.abandoned || !(c.sum < sum)) return;
    const double candidate = std::sqrt(c.sum);
    if (candidate < norm) {
      sum = c.sum;
      norm = candidate;
      writing = index;
      set = which;
    }
  }
};

template <Family F>
Search best_writing(const LoopGeometry& g, const WritingTable& table) {
  const int n = g.joints();
  // Cosines only where a condition's value reads them; elsewhere they enter gradients alone.
  const Tables t = tabulate(g, reads_cosines(F));
  const int sets = condition_sets(F, n);
  const int flips = 1 << n;
  Search best;
  for (int order = 0; order < 2 * n; ++order) {
    const int first = order * flips;
    const Scale s{length_scale_of(t, table.writings[static_cast<size_t>(first)]), GeometryVector(), n};
    for (int i = first; i < first + flips; ++i) {
      const TabulatedWriting w{t, table.writings[static_cast<size_t>(i)], s};
      if constexpr (F == Family::bennett) {
        // The two setups share every condition but the last: sum those once.
        SquaredNorm common{best.sum};
        bennett_common_conditions(w, common);
        for (int set = 0; set < 2; ++set) {
          SquaredNorm c = common;
          bennett_setup_condition(w, set == 0 ? 1.0 : -1.0, c);
          best.keep(c, i, set);
        }
      } else {
        for (int set = 0; set < sets; ++set) {
          SquaredNorm c{best.sum};
          condition_set<F>(set, w, c);
          best.keep(c, i, set);
        }
      }
    }
  }
  return best;
}

// The distance over the writings and, when `gradient` is not null, its
// gradient: the best writing written out once and differentiated.
template <Family F>
double distance_over_writings(const LoopGeometry& g, GeometryVector* gradient) {
  const int n = g.joints();
  const WritingTable& table = writing_table(n);
  const Search best = best_writing<F>(g, table);
  assert(best.writing >= 0);  // every norm is finite: the conditions are in units of L
  if (gradient) {
    const detail::Representation& r = (*table.representations)[static_cast<size_t>(best.writing)];
    const WrittenOut w(detail::apply(r, g));
    FixedConditions c;
    condition_set<F>(best.set, w, c);
    assert(c.norm() == best.norm);  // the search's numbers, bit for bit
    *gradient = detail::pull_back(r, c.norm_gradient(3 * n));
  }
  return best.norm;
}

double spherical_distance(const LoopGeometry& g, GeometryVector* gradient) {
  if (gradient) {
    FixedConditions c;
    spherical_conditions(g, false, c);
    *gradient = c.norm_gradient(3 * g.joints());
    return c.norm();
  }
  SquaredNorm c;
  spherical_conditions(g, false, c);
  return std::sqrt(c.sum);
}

// The 5R and 6R families' distances need their joint count.
void require_joints(const char* where, Family family, const LoopGeometry& g) {
  // Bennett (n = 4) is checked by the callers, with their own messages.
  const int joints = family == Family::bennett ? 0 : family_joints(family);
  if (joints != 0 && g.joints() != joints) {
    throw std::invalid_argument(std::string(where) + ": " + to_string(family) + " loops have " +
                                std::to_string(joints) + " joints, not " + std::to_string(g.joints()));
  }
}

}  // namespace

const char* to_string(Family family) {
  switch (family) {
    case Family::bennett: return "bennett";
    case Family::planar: return "planar";
    case Family::spherical: return "spherical";
    case Family::trivial: return "trivial";
    case Family::unclassified: return "unclassified";
    case Family::goldberg: return "goldberg";
    case Family::myard: return "myard";
    case Family::bricard_line_symmetric: return "bricard_line_symmetric";
    case Family::bricard_plane_symmetric: return "bricard_plane_symmetric";
    case Family::bricard_trihedral: return "bricard_trihedral";
    case Family::degenerate: return "degenerate";
    case Family::goldberg_bent: return "goldberg_bent";
    case Family::bennett_pair: return "bennett_pair";
    case Family::bennett_dyads: return "bennett_dyads";
  }
  return "unknown";
}

std::optional<Family> family_from_string(std::string_view name) {
  for (Family f : kAllFamilies) {
    if (name == to_string(f)) return f;
  }
  return std::nullopt;
}

int family_joints(Family family) {
  switch (family) {
    case Family::bennett: return 4;
    case Family::goldberg:
    case Family::myard:
    case Family::goldberg_bent: return 5;
    case Family::bricard_line_symmetric:
    case Family::bricard_plane_symmetric:
    case Family::bricard_trihedral:
    case Family::bennett_pair:
    case Family::bennett_dyads: return 6;
    case Family::planar:
    case Family::spherical:
    case Family::trivial:
    case Family::degenerate:
    case Family::unclassified: return 0;
  }
  return 0;
}

bool has_family_distance(Family family) { return family != Family::degenerate && family != Family::unclassified; }

std::optional<int> family_dimension(Family family, int joints) {
  const int needs = family_joints(family);
  if (needs != 0 && joints != needs) return std::nullopt;
  switch (family) {
    case Family::bennett: return 3;
    case Family::planar: return 2 * joints - 1;  // n lengths, n - 1 independent offsets
    case Family::spherical: return joints;       // n twists
    case Family::goldberg: return 4;
    case Family::myard: return 2;
    case Family::goldberg_bent: return 5;
    case Family::bricard_line_symmetric: return 9;
    case Family::bricard_plane_symmetric: return 8;
    case Family::bricard_trihedral: return 5;
    case Family::bennett_pair: return 4;
    case Family::bennett_dyads: return 9;
    case Family::trivial:  // a rigid rotation: no dimension of its own
    case Family::degenerate:
    case Family::unclassified: return std::nullopt;
  }
  return std::nullopt;
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
    const Best best = best_over_writings<Family::bennett>(geometry, false);
    bennett = check_from(Family::bennett, best);
    bennett.setup = best.setup_sign > 0 ? BennettSetup::asymmetric : BennettSetup::line_symmetric;
    const WrittenOut as_written(geometry);
    Conditions asym, line;
    bennett_conditions(as_written, 1.0, asym);
    bennett_conditions(as_written, -1.0, line);
    const double as_written_asym = asym.max_abs();
    const double as_written_line = line.max_abs();
    if (std::min(as_written_asym, as_written_line) <= options.tolerance) {
      bennett.setup = as_written_asym <= as_written_line ? BennettSetup::asymmetric : BennettSetup::line_symmetric;
    }
  }
  FamilyCheck planar = check_from(Family::planar, best_over_writings<Family::planar>(geometry, false));
  Best spherical_best;
  spherical_conditions(geometry, true, spherical_best.conditions);
  spherical_best.score = spherical_best.conditions.max_abs();
  FamilyCheck spherical = check_from(Family::spherical, spherical_best);
  // Trivial: coincident axes in the pose, and a frozen joint.
  FamilyCheck trivial;
  trivial.family = Family::trivial;
  const AxisPair pair = nearest_coincident_axes(geometry, pose);
  trivial.conditions.push_back({"axes " + std::to_string(pair.i + 1) + " and " + std::to_string(pair.j + 1) +
                                    " coincide (sin angle, distance / L)",
                                pair.residual});
  std::vector<int> frozen, lockable;
  double least_travel = kInf;
  // 5R: a joint that only rocks (rocking_travel) may be locked too, for the
  // locked-joint rule only (a near-miss of a locked-joint loop, ClassifyOptions).
  const double lockable_travel = n == 5 ? std::max(options.frozen_travel, options.rocking_travel) : options.frozen_travel;
  for (size_t k = 0; k < joint_travel.size(); ++k) {
    least_travel = std::min(least_travel, joint_travel[k]);
    if (joint_travel[k] <= options.frozen_travel) frozen.push_back(static_cast<int>(k));
    if (joint_travel[k] <= lockable_travel) lockable.push_back(static_cast<int>(k));
  }
  trivial.conditions.push_back({"least joint travel [rad]", least_travel});
  // A frozen joint passes when its travel is below frozen_travel; expressed
  // on the tolerance's scale so that one residual decides.
  const bool has_frozen = !frozen.empty();
  trivial.residual = has_frozen ? pair.residual : kInf;

  out.checks = {bennett, planar, spherical, trivial};
  // 5R and 6R: degenerate, then the joint count's own families.
  GeometricFit degenerate, locked;
  if (n == 5 || n == 6) {
    FamilyCheck check;
    degenerate = degenerate_fit(geometry, options.tolerance, check);
    // A joint locked over the motion (no coincident axes: that is trivial):
    // the loop moves as the (n-1)R left by locking it, a degenerate loop too.
    // The degenerate check keeps the better of the two.
    if (!lockable.empty() && !(trivial.residual <= options.tolerance)) {
      FamilyCheck locked_check;
      locked_check.family = Family::degenerate;
      locked = locked_fit(geometry, pose, lockable, joint_travel, options.tolerance, options.frozen_travel,
                          locked_check);
      if (locked.residual < check.residual) check = locked_check;
    }
    out.checks.push_back(check);
    for (Family f : special_families(n)) out.checks.push_back(family_check(f, geometry));
  }
  const double tol = options.tolerance;
  // The first of the 5R/6R families (after degenerate) that fits, in the order
  // tried; not a Goldberg-type loop one of whose Bennett loops only folds:
  // that one is degenerate (folding_goldberg), and its check is degenerate's.
  const FamilyCheck* special = nullptr;
  FoldingGoldberg folding;
  for (Family f : special_families(n)) {
    if (n == 4) break;  // Bennett, handled below as before
    for (const FamilyCheck& c : out.checks) {
      if (c.family != f || !(c.residual <= tol) || special) continue;
      FoldingGoldberg fold = folding_goldberg(f, geometry, c.residual, tol);
      if (!fold.folds) {
        special = &c;
      } else if (!folding.folds) {
        folding = std::move(fold);
      }
    }
  }
  if (folding.folds && !special) {
    for (FamilyCheck& c : out.checks) {
      if (c.family == Family::degenerate && folding.residual < c.residual) c = folding.check;
    }
  }
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
  } else if (degenerate.residual <= tol) {
    out.family = Family::degenerate;
    out.residual = degenerate.residual;
    out.detail = degenerate.detail;
  } else if (special) {
    out.family = special->family;
    out.residual = special->residual;
    out.detail = special_detail(special->family, geometry);
    // A member whose motion found is another one (some members have several).
    if (locked.residual <= tol) out.detail += "; the motion found: " + locked.detail;
  } else if (folding.folds) {
    out.family = Family::degenerate;
    out.residual = folding.residual;
    out.detail = folding.detail;
    if (locked.residual <= tol) out.detail += "; the motion found: " + locked.detail;
  } else if (locked.residual <= tol) {
    out.family = Family::degenerate;
    out.residual = locked.residual;
    out.detail = locked.detail;
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
  require_joints("family_distance", family, geometry);
  switch (family) {
    case Family::bennett:
      if (geometry.joints() != 4) throw std::invalid_argument("family_distance: Bennett loops have 4 joints");
      return distance_over_writings<Family::bennett>(geometry, gradient);
    case Family::planar: return distance_over_writings<Family::planar>(geometry, gradient);
    case Family::spherical: return spherical_distance(geometry, gradient);
    case Family::trivial: return distance_over_writings<Family::trivial>(geometry, gradient);
    case Family::goldberg: return distance_over_writings<Family::goldberg>(geometry, gradient);
    case Family::myard: return distance_over_writings<Family::myard>(geometry, gradient);
    case Family::goldberg_bent: return distance_over_writings<Family::goldberg_bent>(geometry, gradient);
    case Family::bricard_line_symmetric: return distance_over_writings<Family::bricard_line_symmetric>(geometry, gradient);
    case Family::bricard_plane_symmetric: return distance_over_writings<Family::bricard_plane_symmetric>(geometry, gradient);
    case Family::bricard_trihedral: return distance_over_writings<Family::bricard_trihedral>(geometry, gradient);
    case Family::bennett_pair: return distance_over_writings<Family::bennett_pair>(geometry, gradient);
    case Family::bennett_dyads: return distance_over_writings<Family::bennett_dyads>(geometry, gradient);
    case Family::degenerate: throw std::invalid_argument("family_distance: degenerate loops have no distance");
    case Family::unclassified: break;
  }
  throw std::invalid_argument("family_distance: not a family");
}

FamilyCheck family_distance_report(Family family, const LoopGeometry& geometry, GeometryVector* gradient) {
  validate_geometry(geometry);
  require_joints("family_distance_report", family, geometry);
  const int n = geometry.joints();
  Best best;
  switch (family) {
    case Family::bennett:
      if (n != 4) throw std::invalid_argument("family_distance_report: Bennett loops have 4 joints");
      best = best_over_writings<Family::bennett>(geometry, true);
      break;
    case Family::spherical:
      spherical_conditions(geometry, false, best.conditions);
      best.score = best.conditions.norm();
      break;
    case Family::planar:
    case Family::trivial:
    case Family::goldberg:
    case Family::myard:
    case Family::goldberg_bent:
    case Family::bricard_line_symmetric:
    case Family::bricard_plane_symmetric:
    case Family::bricard_trihedral:
    case Family::bennett_pair:
    case Family::bennett_dyads: best = best_for(family, geometry, true); break;
    case Family::degenerate:
      throw std::invalid_argument("family_distance_report: degenerate loops have no distance");
    case Family::unclassified: throw std::invalid_argument("family_distance_report: not a family");
  }
  if (gradient) {
    const GeometryVector g = best.conditions.norm_gradient(3 * n);
    *gradient = best.writing ? detail::pull_back(*best.writing, g) : g;
  }
  FamilyCheck check = check_from(family, best);
  if (family == Family::bennett) {
    check.setup = best.setup_sign > 0 ? BennettSetup::asymmetric : BennettSetup::line_symmetric;
  }
  return check;
}

}  // namespace loopfarm
