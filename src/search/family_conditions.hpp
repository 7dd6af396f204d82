// The conditions of the known families on one representation of a loop
// (classify.hpp), written once as templates over where the parameters come
// from and where the conditions go. Internal to the search.
//
// Two paths share one set of condition formulas (the templates below):
//
// - the numeric path (representation_search.hpp) looks each representation's
//   parameters up in small tables filled once per call, keeps only a running
//   score (the sum of squares for family_distance, called on every evaluation
//   of a steered search; the max |value| for classification), gives a
//   representation up as soon as it cannot beat the best so far, and builds no
//   string and allocates nothing;
// - the reporting path (classify, family_distance_report) writes out the
//   representation the numeric path picked as a LoopGeometry and keeps every
//   condition with its name: what a report lists; family_distance writes it
//   out too, to differentiate it.
//
// Both evaluate the same formulas on the same numbers in the same order, so
// the written-out representation scores what the search scored, bit for bit.
#pragma once

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <initializer_list>
#include <limits>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "loopfarm/core/loop.hpp"
#include "loopfarm/search/classify.hpp"

namespace loopfarm::detail {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kPi = 3.14159265358979323846;  // as representation.cpp's twist offsets

inline std::string label(const char* name, int k) { return name + std::to_string(k + 1); }

// max(m, |v|) with NaN kept: a condition that cannot be evaluated (an
// overflow, a square root of a negative) fails its set instead of being
// skipped, as std::max would skip it.
inline double max_abs_step(double m, double v) {
  const double a = std::abs(v);
  return std::isnan(m) || a <= m ? m : a;
}

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

inline Scale scale_of(const LoopGeometry& g) { return {length_scale(g), length_scale_gradient(g), g.joints()}; }

// ---------------------------------------------------------------------------
// Representations as the conditions read them: parameters a(k), alpha(k), d(k) in
// the representation's labels, sin and cos of the twists, and the length scale.

// A representation written out (detail::apply, or the geometry as written) with its
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
// parts, its name, its value and its gradient with respect to the representation's
// (a, alpha, d); a sink evaluates only the parts it keeps.

// The sum of the squared values in the order they come; every norm here is its sqrt.
inline double sum_of_squares(std::span<const double> values) {
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
    for (double v : values) m = max_abs_step(m, v);
    return m;
  }
  double norm() const { return std::sqrt(sum_of_squares(values)); }
  GeometryVector norm_gradient(int size) const { return norm_gradient_of(values, gradients, size); }
};

// The numeric path's best representation: values and gradients, no names, in fixed
// storage (at most 21 conditions, bricard_octahedral_collapsible's).
struct FixedConditions {
  static constexpr int kCapacity = 3 * kMaxJoints;
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
// representation's sum so far). A representation given up cannot be strictly better than
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
// The conditions of each family on one representation `w`, into sink `c`.

// Bennett conditions (n = 4) that both setups share: opposite links and
// twists equal, no offsets.
template <class RepresentationView, class Sink>
void bennett_common_conditions(const RepresentationView& w, Sink& c) {
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
template <class RepresentationView, class Sink>
void bennett_setup_condition(const RepresentationView& w, double setup_sign, Sink& c) {
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

template <class RepresentationView, class Sink>
void bennett_conditions(const RepresentationView& w, double setup_sign, Sink& c) {
  bennett_common_conditions(w, c);
  bennett_setup_condition(w, setup_sign, c);
}

template <class RepresentationView, class Sink>
void planar_conditions(const RepresentationView& w, Sink& c) {
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

// On the geometry as written (no representations): lengths in units of L when
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

// Axes 1 and 2 of this representation coincide: a1 = 0 and sin(alpha1) = 0.
template <class RepresentationView, class Sink>
void adjacent_coaxial_conditions(const RepresentationView& w, Sink& c) {
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

// Axes 1 and 3 of a 4R representation coincide (docs/design.md, "Trivial").
template <class RepresentationView, class Sink>
void coaxial_13_conditions(const RepresentationView& w, Sink& c) {
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
// 5R and 6R families (docs/guide/families.md). Helpers for the conditions they
// share: a length difference, a twist sum or difference, an offset or a sum
// of offsets, and a Bennett product.

// (a_i + sign a_j) / L, or a_i / L alone when j < 0.
template <class RepresentationView, class Sink>
void add_length(const RepresentationView& w, Sink& c, const char* text, int i, int j, double sign) {
  const Scale& s = w.scale();
  c.add([&] { return std::string(text); }, [&] { return (w.a(i) + (j >= 0 ? sign * w.a(j) : 0.0)) / s.L; },
        [&]() -> GeometryVector {
          GeometryVector g = s.ratio_gradient(i, w.a(i));
          if (j >= 0) g += sign * s.ratio_gradient(j, w.a(j));
          return g;
        });
}

// (d_i + sign d_j) / L, or d_i / L alone when j < 0.
template <class RepresentationView, class Sink>
void add_offset(const RepresentationView& w, Sink& c, const char* text, int i, int j, double sign) {
  const int n = w.joints();
  const Scale& s = w.scale();
  c.add([&] { return std::string(text); }, [&] { return (w.d(i) + (j >= 0 ? sign * w.d(j) : 0.0)) / s.L; },
        [&]() -> GeometryVector {
          GeometryVector g = s.ratio_gradient(2 * n + i, w.d(i));
          if (j >= 0) g += sign * s.ratio_gradient(2 * n + j, w.d(j));
          return g;
        });
}

// wrap(alpha_i + sign alpha_j - shift) [rad].
template <class RepresentationView, class Sink>
void add_twist(const RepresentationView& w, Sink& c, const char* text, int i, int j, double sign, double shift = 0.0) {
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
template <class RepresentationView, class Sink>
void add_bennett_product(const RepresentationView& w, Sink& c, const char* text, int i, int j, double sign) {
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
template <class RepresentationView, class Sink>
void add_right_twist(const RepresentationView& w, Sink& c, const char* text, int i) {
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
template <class RepresentationView, class Sink>
void goldberg_conditions(int set, const RepresentationView& w, Sink& c) {
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
template <class RepresentationView, class Sink>
void myard_conditions(int set, const RepresentationView& w, Sink& c) {
  goldberg_conditions(set & 7, w, c);
  const double pi_shift = (set & 8) ? kPi : 0.0;
  add_length(w, c, "a2 - a3", 1, 2, -1.0);
  add_twist(w, c, (set & 8) ? "alpha2 + alpha3 - pi" : "alpha2 + alpha3", 1, 2, 1.0, pi_shift);
  add_right_twist(w, c, "cos(alpha1)", 0);
}

// Goldberg's 5R with the two links fused at any angle psi about the removed
// joint's axis (docs/guide/families.md, "Goldberg 5R, bent fused link"). Links 1-4
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
template <class RepresentationView, class Sink>
void goldberg_bent_conditions(int set, const RepresentationView& w, Sink& c) {
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
  c.add(
      [&] {
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
  c.add(
      [&] {
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
template <class RepresentationView, class Sink>
void bricard_line_conditions(const RepresentationView& w, Sink& c) {
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
template <class RepresentationView, class Sink>
void bricard_plane_conditions(const RepresentationView& w, Sink& c) {
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
template <class RepresentationView, class Sink>
void bricard_trihedral_conditions(const RepresentationView& w, Sink& c) {
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
  c.add([] { return "(a1^2 - a2^2 + a3^2 - a4^2 + a5^2 - a6^2) / L^2"; }, [&] { return squares() / (s.L * s.L); },
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
// link on its own: two degrees of freedom (docs/guide/families.md). Written as
// links 1 (a, alpha), 2 (b, beta), 3 (a, alpha), 4 (c, gamma), 5 (b, beta),
// 6 (c, gamma), every offset zero (joints 1 and 4 are A and D). Set bits: 0
// loop 1's setup (sin alpha/a = -sin beta/b when set), 1 loop 2's.
template <class RepresentationView, class Sink>
void bennett_pair_conditions(int set, const RepresentationView& w, Sink& c) {
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

// Two Bennett dyads, links i, j and k, l, with the same (cos alpha_i + cos
// alpha_j) / kappa, kappa = sin(alpha_i) / a_i, as (cos alpha_k + cos
// alpha_l) / kappa', kappa' = sin(alpha_k) / a_k: ((cos alpha_i + cos
// alpha_j) a_i sin(alpha_k) - (cos alpha_k + cos alpha_l) a_k sin(alpha_i)) / L.
template <class RepresentationView, class Sink>
void add_dyad_invariant(const RepresentationView& w, Sink& c, const char* text, int i, int j, int k, int l) {
  const int n = w.joints();
  const Scale& s = w.scale();
  const auto value = [&] {
    return (w.cos_alpha(i) + w.cos_alpha(j)) * w.a(i) * w.sin_alpha(k) -
           (w.cos_alpha(k) + w.cos_alpha(l)) * w.a(k) * w.sin_alpha(i);
  };
  c.add([&] { return std::string(text); }, [&] { return value() / s.L; },
        [&] {
          GeometryVector g = -(value() / (s.L * s.L)) * s.dL;
          const double first = w.cos_alpha(i) + w.cos_alpha(j), second = w.cos_alpha(k) + w.cos_alpha(l);
          g[i] += first * w.sin_alpha(k) / s.L;
          g[k] += -second * w.sin_alpha(i) / s.L;
          g[n + i] += (-w.sin_alpha(i) * w.a(i) * w.sin_alpha(k) - second * w.a(k) * w.cos_alpha(i)) / s.L;
          g[n + j] += -w.sin_alpha(j) * w.a(i) * w.sin_alpha(k) / s.L;
          g[n + k] += (first * w.a(i) * w.cos_alpha(k) + w.sin_alpha(k) * w.a(k) * w.sin_alpha(i)) / s.L;
          g[n + l] += w.sin_alpha(l) * w.a(k) * w.sin_alpha(i) / s.L;
          return g;
        });
}

// Two Bennett dyads joined by two equal links (6R, docs/guide/families.md; found
// by the generic 6R search): links 1, 2 with Bennett's ratio kappa1 =
// sin(alpha1)/a1 = sin(alpha2)/a2 and no offset between them (d2 = 0), links
// 4, 5 likewise (kappa2, d5 = 0), the same (cos alpha + cos beta) / kappa for
// both dyads, links 3 and 6 equal, and each dyad's two end joints the same
// offset (d1 = d3, d4 = d6).
template <class RepresentationView, class Sink>
void bennett_dyads_conditions(const RepresentationView& w, Sink& c) {
  add_length(w, c, "a3 - a6", 2, 5, -1.0);
  add_twist(w, c, "alpha3 - alpha6", 2, 5, -1.0);
  add_offset(w, c, "d2", 1, -1, 0.0);
  add_offset(w, c, "d5", 4, -1, 0.0);
  add_offset(w, c, "d1 - d3", 0, 2, -1.0);
  add_offset(w, c, "d4 - d6", 3, 5, -1.0);
  add_bennett_product(w, c, "a1 sin(alpha2) - a2 sin(alpha1)", 0, 1, 1.0);
  add_bennett_product(w, c, "a4 sin(alpha5) - a5 sin(alpha4)", 3, 4, 1.0);
  add_dyad_invariant(w, c,
                     "((cos(alpha1) + cos(alpha2)) a1 sin(alpha4) - (cos(alpha4) + cos(alpha5)) a4 sin(alpha1)) / L", 0,
                     1, 3, 4);
}

// Two Bennett-ratio triads (6R, docs/guide/families.md; found by the generic
// 6R search): links 1-3 with one Bennett ratio k1 = sin(alpha) / a and no
// offset between them (d2 = d3 = 0), links 4-6 likewise (k2, d5 = d6 = 0),
// opposite offsets where the triads meet (d4 = -d1), and two quantities the
// same for both triads: (1 + the sum of their cosines of twists) / k and the
// product of their cos(alpha / 2) over k. The ratios are signed, so all six
// twists have one sign. The loops with d4 = +d1 (1 - the sum of cosines and
// sin(alpha / 2) in the two quantities) are these written with axes 1, 3 and
// 5 flipped, which adds pi to every twist and negates d1.
template <class RepresentationView, class Sink>
void bennett_triads_conditions(const RepresentationView& w, Sink& c) {
  const int n = 6;
  const Scale& s = w.scale();
  add_bennett_product(w, c, "a1 sin(alpha2) - a2 sin(alpha1)", 0, 1, 1.0);
  add_bennett_product(w, c, "a1 sin(alpha3) - a3 sin(alpha1)", 0, 2, 1.0);
  add_bennett_product(w, c, "a4 sin(alpha5) - a5 sin(alpha4)", 3, 4, 1.0);
  add_bennett_product(w, c, "a4 sin(alpha6) - a6 sin(alpha4)", 3, 5, 1.0);
  add_offset(w, c, "d2", 1, -1, 0.0);
  add_offset(w, c, "d3", 2, -1, 0.0);
  add_offset(w, c, "d5", 4, -1, 0.0);
  add_offset(w, c, "d6", 5, -1, 0.0);
  add_offset(w, c, "d1 + d4", 0, 3, 1.0);
  // q(triad 1) / k1 = q(triad 2) / k2, times sin(alpha1) sin(alpha4), over L:
  // (q1 a1 sin(alpha4) - q2 a4 sin(alpha1)) / L. `dq(i)` is dq / dalpha_i.
  const auto add_equal = [&](const char* text, const auto& q, const auto& dq) {
    const auto value = [&] { return q(0) * w.a(0) * w.sin_alpha(3) - q(3) * w.a(3) * w.sin_alpha(0); };
    c.add([&] { return std::string(text); }, [&] { return value() / s.L; },
          [&] {
            GeometryVector g = -(value() / (s.L * s.L)) * s.dL;
            const double one = w.a(0) * w.sin_alpha(3), two = w.a(3) * w.sin_alpha(0);
            g[0] += q(0) * w.sin_alpha(3) / s.L;
            g[3] += -q(3) * w.sin_alpha(0) / s.L;
            for (int i = 0; i < 3; ++i) {
              g[n + i] += dq(i) * one / s.L;
              g[n + 3 + i] += -dq(3 + i) * two / s.L;
            }
            g[n + 3] += q(0) * w.a(0) * w.cos_alpha(3) / s.L;
            g[n + 0] += -q(3) * w.a(3) * w.cos_alpha(0) / s.L;
            return g;
          });
  };
  const auto sum = [&](int first) {
    return 1.0 + w.cos_alpha(first) + w.cos_alpha(first + 1) + w.cos_alpha(first + 2);
  };
  add_equal(
      "((1 + cos(alpha1) + cos(alpha2) + cos(alpha3)) a1 sin(alpha4) - (1 + cos(alpha4) + cos(alpha5) + cos(alpha6)) "
      "a4 sin(alpha1)) / L",
      sum, [&](int i) { return -w.sin_alpha(i); });
  // cos(alpha / 2) = sqrt((1 + cos(alpha)) / 2): the twists lie in (-pi, pi].
  const auto half = [&](int i) { return std::sqrt(0.5 * (1.0 + w.cos_alpha(i))); };
  const auto product = [&](int first) { return half(first) * half(first + 1) * half(first + 2); };
  add_equal(
      "(cos(alpha1/2) cos(alpha2/2) cos(alpha3/2) a1 sin(alpha4) - cos(alpha4/2) cos(alpha5/2) cos(alpha6/2) a4 "
      "sin(alpha1)) / L",
      product, [&](int i) {
        const int first = i < 3 ? 0 : 3;
        double others = 1.0;
        for (int j = first; j < first + 3; ++j) {
          if (j != i) others *= half(j);
        }
        return -0.5 * std::sin(0.5 * w.alpha(i)) * others;
      });
}

// sin(alpha / 2) and cos(alpha / 2) of a twist in (-pi, pi], from its sine and
// cosine: the larger of the two from sqrt((1 +- cos alpha) / 2), the other
// from sin(alpha) = 2 sin(alpha / 2) cos(alpha / 2), so neither loses digits
// near 0 or pi.
struct HalfAngle {
  double sin, cos;
};
inline HalfAngle half_angle(double alpha, double sin_alpha, double cos_alpha) {
  if (cos_alpha >= 0.0) {
    const double c = std::sqrt(0.5 * (1.0 + cos_alpha));
    return {0.5 * sin_alpha / c, c};
  }
  const double s = std::copysign(std::sqrt(0.5 * (1.0 - cos_alpha)), alpha);
  return {s, 0.5 * sin_alpha / s};
}

// A number and its gradient with respect to the lengths a, the sines of the
// twists and the offsets of one representation (entries k, n + k and 2n + k):
// the polynomial conditions below are written once over double (their values)
// and over this (their gradients).
struct WithGradient {
  double value;
  GeometryVector gradient;
};
inline WithGradient operator+(const WithGradient& x, const WithGradient& y) {
  return {x.value + y.value, x.gradient + y.gradient};
}
inline WithGradient operator-(const WithGradient& x, const WithGradient& y) {
  return {x.value - y.value, x.gradient - y.gradient};
}
inline WithGradient operator*(const WithGradient& x, const WithGradient& y) {
  return {x.value * y.value, y.value * x.gradient + x.value * y.gradient};
}

// Two Bennett dyads with coupled middle joints (6R, docs/guide/families.md;
// found by the generic 6R search): links 2, 3 a Bennett dyad (k2 = sin
// alpha2 / a2 = sin alpha3 / a3, signed, d3 = 0) and links 5, 6 another (k5,
// d6 = 0), joined by links 1 and 4 (m = a / sin alpha), with
//   d1 + d4 = d2 + d5,
//   C1 tan(alpha2/2) tan(alpha3/2) = tan(alpha5/2) tan(alpha6/2),
//   C2 (cos alpha2 + cos alpha3) / k2 = (cos alpha5 + cos alpha6) / k5,
//   C3 tan(alpha1/2) / a1 = tan(alpha4/2) / a4,
//   L  m1 (k5 d5 - k2 d4) = m4 (k5 d1 - k2 d2),
//   Q  k2 d2 d4 - k5 d1 d5 = (k5 - k2) (m1 m4 - 1 / (k2 k5)),
//   Q' m1 d4 d5 - m4 d1 d2 = (m1 - m4) (m1 m4 - 1 / (k2 k5)):
// ten conditions and Q' (Q's conic again, kept for k2 = k5, where Q holds
// on all of L's plane). The dyads' middle joints 3 and 6 turn together (theta3 + theta6
// stays constant). Every condition is unchanged by the mirror image (alpha
// and d negated), so loops written with axes 2, 4 and 6 flipped and
// mirrored, as the search also finds them, are members in the
// representation with those axes flipped: one condition set. The dyads'
// ratios, C1 and C3 are relative misses of two products (below); the others
// are cleared of their denominators, L, Q and Q' then cubic in lengths,
// over L^3.
template <class RepresentationView, class Sink>
void coupled_bennett_dyads_conditions(const RepresentationView& w, Sink& c) {
  const int n = 6;
  const Scale& s = w.scale();
  add_offset(w, c, "d3", 2, -1, 0.0);
  add_offset(w, c, "d6", 5, -1, 0.0);
  // The dyads' ratios, C1 and C3 as equal products x = y, written (x - y) /
  // (|x| + |y|) (0 where both vanish, as for zero twists): a relative miss.
  // A length moved by eps L changes it by eps L / (2 a) at least, a twist in
  // C1 or C3 by eps / 2 (d log tan(alpha/2) / d alpha = 1 / sin alpha),
  // whatever the twists' sizes, where the products themselves (as
  // add_bennett_product writes a ratio) shrink with a small twist.
  // `derivatives(i)`: dx and dy by parameter i, for i in `parameters`.
  const auto add_equal_products = [&](const char* text, const auto& products, const auto& derivatives,
                                      std::initializer_list<int> parameters) {
    const auto value = [&] {
      const auto [x, y] = products();
      const double sum = std::abs(x) + std::abs(y);
      return sum == 0.0 ? 0.0 : (x - y) / sum;
    };
    c.add([&] { return std::string(text); }, value,
          [&] {
            const auto [x, y] = products();
            const double sum = std::abs(x) + std::abs(y), v = value();
            GeometryVector g = GeometryVector::Zero(3 * n);
            if (sum == 0.0) return g;
            const double sx = x < 0.0 ? -1.0 : 1.0, sy = y < 0.0 ? -1.0 : 1.0;
            for (int i : parameters) {
              const auto [dx, dy] = derivatives(i);
              g[i] = (dx - dy - v * (sx * dx + sy * dy)) / sum;
            }
            return g;
          });
  };
  const auto add_ratio = [&](const char* text, int i, int j) {
    add_equal_products(
        text,
        [&] {
          return std::pair{w.a(i) * w.sin_alpha(j), w.a(j) * w.sin_alpha(i)};
        },
        [&](int p) {
          if (p == i) return std::pair{w.sin_alpha(j), 0.0};
          if (p == j) return std::pair{0.0, w.sin_alpha(i)};
          if (p == n + j) return std::pair{w.a(i) * w.cos_alpha(j), 0.0};
          return std::pair{0.0, w.a(j) * w.cos_alpha(i)};  // n + i
        },
        {i, j, n + i, n + j});
  };
  add_ratio("(a2 sin(alpha3) - a3 sin(alpha2)) / (|a2 sin(alpha3)| + |a3 sin(alpha2)|)", 1, 2);
  add_ratio("(a5 sin(alpha6) - a6 sin(alpha5)) / (|a5 sin(alpha6)| + |a6 sin(alpha5)|)", 4, 5);
  c.add([] { return "d1 + d4 - d2 - d5"; }, [&] { return (w.d(0) + w.d(3) - w.d(1) - w.d(4)) / s.L; },
        [&]() -> GeometryVector {
          return s.ratio_gradient(2 * n, w.d(0)) + s.ratio_gradient(2 * n + 3, w.d(3)) -
                 s.ratio_gradient(2 * n + 1, w.d(1)) - s.ratio_gradient(2 * n + 4, w.d(4));
        });
  // C2, bennett_dyads' invariant.
  add_dyad_invariant(
      w, c, "C2: ((cos(alpha2) + cos(alpha3)) a2 sin(alpha5) - (cos(alpha5) + cos(alpha6)) a5 sin(alpha2)) / L", 1, 2,
      4, 5);
  const auto half = [&](int k) { return half_angle(w.alpha(k), w.sin_alpha(k), w.cos_alpha(k)); };
  // C3: a4 sin(alpha1/2) cos(alpha4/2) = a1 cos(alpha1/2) sin(alpha4/2).
  add_equal_products(
      "C3: (a4 sin(alpha1/2) cos(alpha4/2) - a1 cos(alpha1/2) sin(alpha4/2)) / (|a4 sin(alpha1/2) cos(alpha4/2)| + "
      "|a1 cos(alpha1/2) sin(alpha4/2)|)",
      [&] {
        const HalfAngle h1 = half(0), h4 = half(3);
        return std::pair{w.a(3) * h1.sin * h4.cos, w.a(0) * h1.cos * h4.sin};
      },
      [&](int i) {
        const HalfAngle h1 = half(0), h4 = half(3);
        switch (i) {
          case 0:
            return std::pair{0.0, h1.cos * h4.sin};
          case 3:
            return std::pair{h1.sin * h4.cos, 0.0};
          case n + 0:
            return std::pair{0.5 * w.a(3) * h1.cos * h4.cos, -0.5 * w.a(0) * h1.sin * h4.sin};
          default:  // n + 3
            return std::pair{-0.5 * w.a(3) * h1.sin * h4.sin, 0.5 * w.a(0) * h1.cos * h4.cos};
        }
      },
      {0, 3, n + 0, n + 3});
  // C1: sin(alpha2/2) sin(alpha3/2) cos(alpha5/2) cos(alpha6/2) =
  // cos(alpha2/2) cos(alpha3/2) sin(alpha5/2) sin(alpha6/2). Each twist's
  // half angle enters one side as its sine and the other as its cosine.
  add_equal_products(
      "C1: (sin(alpha2/2) sin(alpha3/2) cos(alpha5/2) cos(alpha6/2) - cos(alpha2/2) cos(alpha3/2) sin(alpha5/2) "
      "sin(alpha6/2)) / (sum of their |.|)",
      [&] {
        const HalfAngle h2 = half(1), h3 = half(2), h5 = half(4), h6 = half(5);
        return std::pair{h2.sin * h3.sin * h5.cos * h6.cos, h2.cos * h3.cos * h5.sin * h6.sin};
      },
      [&](int i) {
        std::array<HalfAngle, 4> h = {half(1), half(2), half(4), half(5)};
        const int moved = i == n + 1 ? 0 : i == n + 2 ? 1 : i == n + 4 ? 2 : 3;
        // x's factors: sin, sin, cos, cos; y's: cos, cos, sin, sin.
        double x = 0.5, y = 0.5;
        for (int k = 0; k < 4; ++k) {
          const bool x_sine = k < 2;
          if (k == moved) {
            x *= x_sine ? h[k].cos : -h[k].sin;
            y *= x_sine ? -h[k].sin : h[k].cos;
          } else {
            x *= x_sine ? h[k].sin : h[k].cos;
            y *= x_sine ? h[k].cos : h[k].sin;
          }
        }
        return std::pair{x, y};
      },
      {n + 1, n + 2, n + 4, n + 5});
  // L, Q and Q', written once over the kind of number (`a`, `sin`, `d` give
  // one of the representation's parameters as one), multiplied out so that
  // no ratio is left: L by a2 a5 sin(alpha1) sin(alpha4), Q by a2 a5
  // sin(alpha1) sin(alpha2) sin(alpha4) sin(alpha5), Q' by (sin(alpha1)
  // sin(alpha4))^2 sin(alpha2) sin(alpha5).
  const auto offset_line = [](const auto& a, const auto& sin, const auto& d) {
    return a(0) * sin(3) * (a(1) * sin(4) * d(4) - a(4) * sin(1) * d(3)) -
           a(3) * sin(0) * (a(1) * sin(4) * d(0) - a(4) * sin(1) * d(1));
  };
  const auto offset_conic = [](const auto& a, const auto& sin, const auto& d) {
    const auto product = sin(0) * sin(1) * sin(3) * sin(4);
    const auto shared = a(0) * a(3) * sin(1) * sin(4) - a(1) * a(4) * sin(0) * sin(3);
    return product * (a(4) * sin(1) * d(1) * d(3) - a(1) * sin(4) * d(0) * d(4)) -
           (a(1) * sin(4) - a(4) * sin(1)) * shared;
  };
  const auto offset_conic_partner = [](const auto& a, const auto& sin, const auto& d) {
    const auto product = sin(0) * sin(1) * sin(3) * sin(4);
    const auto shared = a(0) * a(3) * sin(1) * sin(4) - a(1) * a(4) * sin(0) * sin(3);
    return product * (a(0) * sin(3) * d(3) * d(4) - a(3) * sin(0) * d(0) * d(1)) -
           (a(0) * sin(3) - a(3) * sin(0)) * shared;
  };
  const double L3 = s.L * s.L * s.L;
  const auto add_cubic = [&](const char* text, const auto& expression) {
    const auto value = [&] {
      return expression([&](int k) { return w.a(k); }, [&](int k) { return w.sin_alpha(k); },
                        [&](int k) { return w.d(k); });
    };
    c.add([&] { return std::string(text); }, [&] { return value() / L3; },
          [&] {
            const auto variable = [&](int index, double x) {
              WithGradient v{x, GeometryVector::Zero(3 * n)};
              v.gradient[index] = 1.0;
              return v;
            };
            const WithGradient e = expression([&](int k) { return variable(k, w.a(k)); },
                                              [&](int k) { return variable(n + k, w.sin_alpha(k)); },
                                              [&](int k) { return variable(2 * n + k, w.d(k)); });
            GeometryVector g = e.gradient;  // d sin(alpha) = cos(alpha) d alpha
            for (int k = 0; k < n; ++k) g[n + k] *= w.cos_alpha(k);
            return GeometryVector(g / L3 - (3.0 * e.value / (L3 * s.L)) * s.dL);
          });
  };
  add_cubic(
      "(a1 sin(alpha4) (a2 sin(alpha5) d5 - a5 sin(alpha2) d4) - a4 sin(alpha1) (a2 sin(alpha5) d1 - a5 "
      "sin(alpha2) d2)) / L^3",
      offset_line);
  add_cubic("Q: k2 d2 d4 - k5 d1 d5 - (k5 - k2) (m1 m4 - 1 / (k2 k5)), cleared, / L^3", offset_conic);
  add_cubic("Q': m1 d4 d5 - m4 d1 d2 - (m1 - m4) (m1 m4 - 1 / (k2 k5)), cleared, / L^3", offset_conic_partner);
}

// Waldron's hybrid 6R (docs/guide/families.md): two Bennett loops B C D A
// and G F E A sharing the joint axis A, links AB and AE fused into one body
// and DA and GA into another, joint A removed: the 6R B C D G F E. In one
// representation: links 1, 2 (joints 1-3) are a Bennett dyad, links 4, 5
// (joints 4-6) another, and links 3 (D -> G) and 6 (E -> B) are the fused
// bodies. Each dyad closes into a Bennett loop (b, beta), (a, alpha),
// (b, beta), (a, alpha) through one fourth axis A, which the fused bodies
// both carry; the fit finds it in each of them, from the geometry alone.

// The fourth axis in one fused link. The link carries axes U and V (unit
// directions u, v, in the link's frame); A leaves U at U's foot pu along a
// normal of length l and twist lambda (the link U -> A of a Bennett loop,
// no offset at U) and reaches V at V's foot pv along a normal of length m,
// twist mu (the link A -> V, no offset at V). Its direction z makes the
// angle lambda with u and mu with v: the common lines of two cones, up to
// two (candidates 0 and 1). Where the cones touch, the two meet in the
// plane of u and v, and the cones' equations give the direction only to
// the square root of the round-off; so a third candidate is always tried:
// the direction in that plane whose angles to u and v miss lambda and mu
// least (in the sum of squares), its miss in radians added in quadrature.
// Where the cones do not meet, it is the only one. For each, the line A
// placed from U and the one placed from V are parallel: `apart` is their
// distance over L, `slide` the signed distance along z from the first's
// foot to the second's, in the geometry's units.
struct FusedLinkFit {
  static constexpr size_t kCandidates = 3;
  std::array<double, kCandidates> apart{};
  std::array<double, kCandidates> slide{};
};

inline FusedLinkFit fourth_axis_in_link(const Vector3& pu, const Vector3& u, double l, double sin_l, double cos_l,
                                        const Vector3& pv, const Vector3& v, double m, double sin_m, double cos_m,
                                        double L) {
  FusedLinkFit out;
  const Vector3 uxv = u.cross(v);
  const double s2 = uxv.squaredNorm(), c = u.dot(v);
  // Parallel axes U and V, or a link A would share an axis with: no fourth
  // axis this fit can place (a Waldron loop needs neither); a residual of 1
  // (one L apart), whatever the scale.
  if (!(s2 > 1e-24) || !(std::abs(sin_l) > 1e-12) || !(std::abs(sin_m) > 1e-12)) {
    out.apart.fill(1.0);
    return out;
  }
  // A placed along z from both axes: its distance and slide, `miss` added.
  const auto place = [&](const Vector3& z, bool normalise, double miss, size_t k) {
    // Link U -> A: z = cos_l u - sin_l (u x x_UA), and x_UA = (u x x_UA) x u.
    Vector3 x_ua = ((cos_l * u - z) / sin_l).cross(u);
    // Link A -> V: v = cos_m z - sin_m (z x x_AV), and x_AV = (z x x_AV) x z.
    Vector3 x_av = ((cos_m * z - v) / sin_m).cross(z);
    if (normalise) {  // unit only where z makes both angles exactly
      x_ua.normalize();
      x_av.normalize();
    }
    const Vector3 gap = (pv - m * x_av) - (pu + l * x_ua);
    const double along = gap.dot(z);
    out.apart[k] = std::hypot((gap - along * z).norm() / L, miss);
    out.slide[k] = along;
  };
  // z = x u + y v + w (u x v) / |u x v| with z . u = cos_l, z . v = cos_m, |z| = 1.
  const double x = (cos_l - c * cos_m) / s2, y = (cos_m - c * cos_l) / s2;
  const double w2 = 1.0 - (x * cos_l + y * cos_m);
  const Vector3 normal = uxv / std::sqrt(s2);
  if (w2 > 0.0) {
    const double w = std::sqrt(w2);
    for (size_t k = 0; k < 2; ++k) place((x * u + y * v + (k == 0 ? w : -w) * normal).normalized(), false, 0.0, k);
  } else {
    out.apart[0] = out.apart[1] = kInf;
  }
  // In the plane of u and v: e1 = u, e2 toward v, v at the angle phi.
  const Vector3 e2 = (v - c * u).normalized();
  const double phi = std::atan2(std::sqrt(s2), c), lambda = std::atan2(std::abs(sin_l), cos_l),
               mu = std::atan2(std::abs(sin_m), cos_m);
  double least = kInf, best = 0.0;
  // The in-plane direction nearest to both angles, on each side of u and of v
  // (a least-squares compromise: the two choosing one exactly tie where the
  // cones touch, and switching between them would not be smooth).
  for (double theta :
       {0.5 * (lambda + phi - mu), 0.5 * (lambda + phi + mu), 0.5 * (-lambda + phi - mu), 0.5 * (-lambda + phi + mu)}) {
    // The angles to u and v of the direction at theta from u.
    const double to_u = std::abs(wrap_angle(theta)), to_v = std::abs(wrap_angle(theta - phi));
    const double miss = std::hypot(to_u - lambda, to_v - mu);
    if (miss < least) {
      least = miss;
      best = theta;
    }
  }
  place(std::cos(best) * u + std::sin(best) * e2, true, least, 2);
  return out;
}

// One representation's parameters as the fit reads them.
struct WaldronParameters {
  std::array<double, 6> a{}, sin{}, cos{}, d{};
  double L = 1.0;
};

// The fit of one representation, lengths over L: in link 3 (joints D = 3,
// G = 4) the fourth axis closing dyad 1 (D -> A as link 1, from link 2's
// foot on axis 3) against the one closing dyad 2 (A -> G as link 5, to
// link 4's foot on axis 4); in link 6 (joints E = 6, B = 1) the one closing
// dyad 2 (E -> A as link 4, from link 5's foot on axis 6) against dyad 1's
// (A -> B as link 2, to link 1's foot on axis 1); and the two loops' feet on
// A: from dyad 1's to dyad 2's along A in link 3, back in link 6, the same
// distance once A is one joint axis of both bodies. The direction of A is
// dyad 1's in both links (an axis flip of a dyad-2 joint makes it so in
// another representation). Of the candidate directions in each link, the pair
// with the least sum of squares.
struct WaldronFit {
  double link3 = 0.0;  // the two fourth axes in link 3 apart / L
  double link6 = 0.0;  // likewise in link 6
  double slide = 0.0;  // (slide in link 3 + slide in link 6) / L: zero on a member
  double feet = 0.0;   // dyad 2's foot on A minus dyad 1's, along A / L (link 3's)
};

inline WaldronFit waldron_fit(const WaldronParameters& p) {
  const Vector3 z = Vector3::UnitZ();
  // Link 3: axis 3 along z through the link's foot, axis 4 through (a3, 0, 0).
  const Vector3 v3(0.0, -p.sin[2], p.cos[2]);
  const FusedLinkFit in3 =
      fourth_axis_in_link(-p.d[2] * z, z, p.a[0], p.sin[0], p.cos[0], Vector3(p.a[2], 0.0, 0.0) + p.d[3] * v3, v3,
                          p.a[4], p.sin[4], p.cos[4], p.L);
  // Link 6: axis 6 along z, axis 1 through (a6, 0, 0).
  const Vector3 v6(0.0, -p.sin[5], p.cos[5]);
  const FusedLinkFit in6 =
      fourth_axis_in_link(-p.d[5] * z, z, p.a[3], p.sin[3], p.cos[3], Vector3(p.a[5], 0.0, 0.0) + p.d[0] * v6, v6,
                          p.a[1], p.sin[1], p.cos[1], p.L);
  WaldronFit best;
  double least = kInf;
  for (size_t i = 0; i < FusedLinkFit::kCandidates; ++i) {
    for (size_t j = 0; j < FusedLinkFit::kCandidates; ++j) {
      // In link 6 the slide runs from dyad 2's foot to dyad 1's.
      const WaldronFit f{in3.apart[i], in6.apart[j], (in3.slide[i] + in6.slide[j]) / p.L, in3.slide[i] / p.L};
      const double sum = f.link3 * f.link3 + f.link6 * f.link6 + f.slide * f.slide;
      if (sum < least) {
        least = sum;
        best = f;
      }
    }
  }
  return best;
}

template <class RepresentationView>
WaldronParameters waldron_parameters(const RepresentationView& w) {
  WaldronParameters p;
  for (int k = 0; k < 6; ++k) {
    const auto i = static_cast<size_t>(k);
    p.a[i] = w.a(k);
    p.sin[i] = w.sin_alpha(k);
    p.cos[i] = w.cos_alpha(k);
    p.d[i] = w.d(k);
  }
  p.L = w.scale().L;
  return p;
}

// The gradient of one of the fit's values (which: 0 link3, 1 link6, 2
// slide, 3 feet) with respect to the representation's (a, alpha, d), by central
// differences (the fit has no closed form to differentiate): steps of 1e-6
// L on lengths and offsets, 1e-6 rad on twists, each side evaluated with
// its own L.
inline GeometryVector waldron_fit_gradient(const WaldronParameters& p, const std::array<double, 6>& alpha, int which) {
  const int n = 6;
  GeometryVector g = GeometryVector::Zero(3 * n);
  const auto value = [which](const WaldronFit& f) {
    return which == 0 ? f.link3 : which == 1 ? f.link6 : which == 2 ? f.slide : f.feet;
  };
  for (int q = 0; q < 3 * n; ++q) {
    const auto k = static_cast<size_t>(q % n);
    const double h = q < n || q >= 2 * n ? 1e-6 * p.L : 1e-6;
    std::array<double, 2> side{};
    for (size_t s = 0; s < 2; ++s) {
      WaldronParameters r = p;
      const double step = s == 0 ? h : -h;
      if (q < n) {
        r.a[k] += step;
      } else if (q < 2 * n) {
        r.sin[k] = std::sin(alpha[k] + step);
        r.cos[k] = std::cos(alpha[k] + step);
      } else {
        r.d[k] += step;
      }
      double mean_square = 0.0;
      for (size_t i = 0; i < 6; ++i) mean_square += r.a[i] * r.a[i] + r.d[i] * r.d[i];
      mean_square /= n;
      r.L = mean_square > 0.0 ? std::sqrt(mean_square) : 1.0;
      side[s] = value(waldron_fit(r));
    }
    g[q] = (side[0] - side[1]) / (2.0 * h);
  }
  return g;
}

// |sin(alpha_i)| / a_i = |sin(alpha_j)| / a_j, as (a_i |sin alpha_j| - a_j
// |sin alpha_i|) / L: a Bennett dyad in either setup (the setups differ by an
// axis flip, and the fourth axis is a line either way).
template <class RepresentationView, class Sink>
void add_bennett_ratio(const RepresentationView& w, Sink& c, const char* text, int i, int j) {
  const int n = w.joints();
  const Scale& s = w.scale();
  auto product = [&] { return w.a(i) * std::abs(w.sin_alpha(j)) - w.a(j) * std::abs(w.sin_alpha(i)); };
  c.add([&] { return std::string(text); }, [&] { return product() / s.L; },
        [&] {
          const double sign_i = w.sin_alpha(i) < 0.0 ? -1.0 : 1.0, sign_j = w.sin_alpha(j) < 0.0 ? -1.0 : 1.0;
          GeometryVector g = -(product() / (s.L * s.L)) * s.dL;
          g[i] += std::abs(w.sin_alpha(j)) / s.L;
          g[j] += -std::abs(w.sin_alpha(i)) / s.L;
          g[n + j] += w.a(i) * sign_j * w.cos_alpha(j) / s.L;
          g[n + i] += -w.a(j) * sign_i * w.cos_alpha(i) / s.L;
          return g;
        });
}

// The conditions: the two dyads (no offset at their middle joints 2 and 5,
// Bennett's ratio on links 1, 2 and on 4, 5) and the fit of their fourth
// axes (waldron_fit), evaluated once, when the first of its values is read.
// With `double_goldberg`, the double-Goldberg 6R's two more: one Bennett
// ratio for both dyads, and the two loops' feet on the fourth axis at one
// point (a third Bennett loop then joins the fused links at A: below).
template <class RepresentationView, class Sink>
void waldron_conditions(const RepresentationView& w, Sink& c, bool double_goldberg) {
  add_offset(w, c, "d2", 1, -1, 0.0);
  add_offset(w, c, "d5", 4, -1, 0.0);
  add_bennett_ratio(w, c, "a1 |sin(alpha2)| - a2 |sin(alpha1)|", 0, 1);
  add_bennett_ratio(w, c, "a4 |sin(alpha5)| - a5 |sin(alpha4)|", 3, 4);
  if (double_goldberg) add_bennett_ratio(w, c, "a1 |sin(alpha4)| - a4 |sin(alpha1)|", 0, 3);
  bool fitted = false;
  WaldronParameters p;
  WaldronFit fit;
  const auto get = [&]() -> const WaldronFit& {
    if (!fitted) {
      p = waldron_parameters(w);
      fit = waldron_fit(p);
      fitted = true;
    }
    return fit;
  };
  const auto gradient = [&](int which) {
    get();
    std::array<double, 6> alpha;
    for (int k = 0; k < 6; ++k) alpha[static_cast<size_t>(k)] = w.alpha(k);
    return waldron_fit_gradient(p, alpha, which);
  };
  c.add([] { return "link 3: fourth axes of dyads 1-2 and 4-5 apart / L"; }, [&] { return get().link3; },
        [&] { return gradient(0); });
  c.add([] { return "link 6: fourth axes of dyads 1-2 and 4-5 apart / L"; }, [&] { return get().link6; },
        [&] { return gradient(1); });
  c.add([] { return "feet of the two Bennett loops on the fourth axis: link 3 against link 6 / L"; },
        [&] { return get().slide; }, [&] { return gradient(2); });
  if (double_goldberg) {
    c.add([] { return "feet of the two Bennett loops on the fourth axis apart / L"; }, [&] { return get().feet; },
          [&] { return gradient(3); });
  }
}

// Waldron's hybrid 6R: the construction's nine conditions.
template <class RepresentationView, class Sink>
void waldron_hybrid_conditions(const RepresentationView& w, Sink& c) {
  waldron_conditions(w, c, false);
}

// The double-Goldberg 6R (docs/guide/families.md): Waldron's hybrid whose
// two Bennett loops (A B C D and A E F G, the 6R B C D G F E) have one ratio
// and meet the fourth axis A at one point. Links AB (in link 6) and GA (in
// link 3) are then a Bennett dyad about A, which closes into a third Bennett
// loop A B C' G: two Goldberg 5Rs, B C D G C' (loops one and three) and
// G F E B C' (two and three), merged along the dyad B C' G, which is
// removed. Eleven conditions.
template <class RepresentationView, class Sink>
void double_goldberg_conditions(const RepresentationView& w, Sink& c) {
  waldron_conditions(w, c, true);
}

// Goldberg's 6R of three Bennett loops (docs/guide/families.md): a Goldberg
// 5R B C D E F (goldberg_bent: the fusion at its removed joint A at any
// angle, Goldberg's collinear ones included) and a third Bennett loop
// P Q R S sharing the 5R's link P Q (its length and twist, and the axes P
// and Q); the third loop's link S -> P is fixed to the 5R's link arriving at
// P at any angle about P, and the link P Q is removed with joint P: the 6R
// has the 5R's joints with P replaced by S and R. In one representation:
// joint 1 is S, 2 is R, 3 is Q, links 1 (S -> R) and 2 (R -> Q) are the
// third loop's Bennett dyad (no offset at R), link 6 (joint 6 -> S) is the
// fused link, links 3-5 are the 5R's own. The fit puts P back: it leaves S
// at link 1's foot along a normal of length a2 at twist alpha2 (the third
// loop's S -> P, equal to its opposite R -> Q), at an angle psi about S that
// is fixed in link 6. The 5R is then P, Q and joints 4-6, with link P -> Q
// equal to link 1 (the third loop's opposite links), links 2-4 equal to
// links 3-5, the offsets at Q and joints 4-5 the 6R's, and link 6 -> P with
// the offsets at joint 6 and at P read off the two axes carried by link 6.
// psi is the one unknown: the angle at which that 5R fits goldberg_bent best,
// with P as the Goldberg 5R's joint B, C, D, E or F (`k` = 0 ... 4) and its
// two Bennett loops in either setup (goldberg_bent's sets).

// One representation's parameters as the fit reads them.
struct Goldberg6RParameters {
  std::array<double, 6> a{}, alpha{}, sin{}, cos{}, d{};
  double L = 1.0;
};

template <class RepresentationView>
Goldberg6RParameters goldberg_6r_parameters(const RepresentationView& w) {
  Goldberg6RParameters p;
  for (int k = 0; k < 6; ++k) {
    const auto i = static_cast<size_t>(k);
    p.a[i] = w.a(k);
    p.alpha[i] = w.alpha(k);
    p.sin[i] = w.sin_alpha(k);
    p.cos[i] = w.cos_alpha(k);
    p.d[i] = w.d(k);
  }
  p.L = w.scale().L;
  return p;
}

// The 5R the fit builds, in its own labels: joint 0 is P, joint 1 Q (the
// 6R's joint 3), joints 2-4 the 6R's joints 4-6. `fusion` is the angle about
// P from link 4's normal (6 -> P) to the third loop's link S -> P.
struct Goldberg6RFive {
  std::array<double, 5> a{}, alpha{}, sin{}, cos{}, d{};
  double fusion = 0.0;
};

// `fusion` computed only when asked (the fit's evaluations do not read it).
inline Goldberg6RFive goldberg_6r_five(const Goldberg6RParameters& p, double psi, bool fusion = false) {
  Goldberg6RFive f;
  // In the frame of joint 1 (S, at the foot of link 6): axis 6 through
  // (-a6, 0, 0) along (0, sin alpha6, cos alpha6); P through (a2 cos psi,
  // a2 sin psi, d1) along Rx'(alpha2) z, x' = (cos psi, sin psi, 0).
  const Vector3 p6(-p.a[5], 0.0, 0.0), u6(0.0, p.sin[5], p.cos[5]);
  const double cp = std::cos(psi), sp = std::sin(psi);
  const Vector3 u(cp, sp, 0.0);
  const Vector3 pp = Vector3(0.0, 0.0, p.d[0]) + p.a[1] * u, up(sp * p.sin[1], -cp * p.sin[1], p.cos[1]);
  // The common normal of axis 6 and axis P: feet p6 + s u6 and pp + t up.
  const Vector3 w0 = p6 - pp;
  const double b = u6.dot(up);
  double s = 0.0, t = up.dot(w0);  // parallel axes: the foot on axis 6 at link 6's
  common_normal_feet(p6, u6, pp, up, 1e-24, s, t);
  const Vector3 gap = (pp + t * up) - (p6 + s * u6), cross = u6.cross(up);
  const double length = gap.norm();
  Vector3 x = length > 1e-12 * p.L ? Vector3(gap / length) : Vector3(cross);
  if (!(x.squaredNorm() > 1e-30)) x = Vector3(1.0, 0.0, 0.0).cross(u6);
  x.normalize();
  const double twist = std::atan2(cross.dot(x), b);
  const int from[4] = {0, 2, 3, 4};  // 5R links 0-3: the 6R's links 1, 3, 4, 5
  for (size_t m = 0; m < 4; ++m) {
    const auto i = static_cast<size_t>(from[m]);
    f.a[m] = p.a[i];
    f.alpha[m] = p.alpha[i];
    f.sin[m] = p.sin[i];
    f.cos[m] = p.cos[i];
  }
  f.a[4] = length;
  f.alpha[4] = twist;
  f.sin[4] = std::sin(twist);
  f.cos[4] = std::cos(twist);
  f.d[0] = -t;  // from link 4's foot on P to the third loop's, the point pp
  f.d[1] = p.d[2];
  f.d[2] = p.d[3];
  f.d[3] = p.d[4];
  f.d[4] = p.d[5] + s;
  if (fusion) f.fusion = std::atan2(x.cross(u).dot(up), x.dot(u));
  return f;
}

// The 5R as goldberg_bent's conditions read it, P as the Goldberg 5R's joint k.
struct Goldberg6RFiveView {
  const Goldberg6RFive& f;
  int k;
  Scale s;
  size_t at(int g) const { return static_cast<size_t>((g - k + 5) % 5); }
  int joints() const { return 5; }
  double a(int g) const { return f.a[at(g)]; }
  double alpha(int g) const { return f.alpha[at(g)]; }
  double d(int g) const { return f.d[at(g)]; }
  double sin_alpha(int g) const { return f.sin[at(g)]; }
  double cos_alpha(int g) const { return f.cos[at(g)]; }
  const Scale& scale() const { return s; }
};

// Values only, in the order they come; those not in `mask` (bit q for the
// q-th) left at zero, not evaluated.
struct Goldberg6RValues {
  std::array<double, 10> values{};
  unsigned mask = 0x3ffu;
  int count = 0;
  template <class Name, class Value, class Gradient>
  void add(const Name&, const Value& value, const Gradient&) {
    if ((mask >> count & 1u) != 0) values[static_cast<size_t>(count)] = value();
    ++count;
  }
};

// Names only (the reporting path).
struct Goldberg6RNames {
  std::array<std::string, 10> names;
  int count = 0;
  template <class Name, class Value, class Gradient>
  void add(const Name& name, const Value&, const Gradient&) {
    names[static_cast<size_t>(count++)] = name();
  }
};

// goldberg_bent's ten conditions on the 5R, over the 6R's L (those in `mask`).
inline std::array<double, 10> goldberg_6r_values(const Goldberg6RFive& f, int k, int setup, double L,
                                                 unsigned mask = 0x3ffu) {
  const Goldberg6RFiveView view{f, k, Scale{L, GeometryVector(), 5}};
  Goldberg6RValues v;
  v.mask = mask;
  goldberg_bent_conditions(setup, view, v);
  return v.values;
}

// Per k, the goldberg_bent conditions (bit q for the q-th, in their order)
// that read the 5R's link 4 (6 -> P) or its offsets at P or joint 6, i.e.
// depend on psi, when P is the Goldberg 5R's joint k; made at compile time
// (the fit asks for every value of every evaluation). The conditions read:
// a1 - a4 and alpha1 - alpha4 links 1, 4; d2, d3, d4 their joints; the two
// Bennett products links 1, 2 and 1, 3; d1 -+ d5 joints 1, 5; the length
// term links 2, 3, 5; the offset term links 2, 3, 5 and joint 5 (1-based
// Goldberg labels).
inline constexpr std::array<unsigned, 5> kGoldberg6RPsiMasks = [] {
  constexpr unsigned kLinks[10] = {0b01001, 0b01001, 0, 0, 0, 0b00011, 0b00101, 0, 0b10110, 0b10110};
  constexpr unsigned kJoints[10] = {0, 0, 0b00010, 0b00100, 0b01000, 0, 0, 0b10001, 0, 0b10000};
  std::array<unsigned, 5> masks{};
  for (int k = 0; k < 5; ++k) {
    const unsigned link = 1u << ((4 + k) % 5), joints = (1u << k) | (1u << ((4 + k) % 5));
    for (size_t q = 0; q < 10; ++q) {
      if ((kLinks[q] & link) != 0 || (kJoints[q] & joints) != 0) masks[static_cast<size_t>(k)] |= 1u << q;
    }
  }
  return masks;
}();

// Whether goldberg_bent's condition q depends on psi when P is joint k.
constexpr bool goldberg_6r_depends_on_psi(int q, int k) {
  return (kGoldberg6RPsiMasks[static_cast<size_t>(k)] >> q & 1u) != 0;
}

struct Goldberg6RFit {
  std::array<double, 10> values{};  // goldberg_bent's, at psi
  double psi = 0.0;
  double fusion = 0.0;  // the angle about P (Goldberg6RFive::fusion)
};

// The sum of squares of the psi-dependent values at psi.
inline double goldberg_6r_dependent_sum(const Goldberg6RParameters& p, int k, int setup, double psi,
                                        std::array<double, 10>& values) {
  values = goldberg_6r_values(goldberg_6r_five(p, psi), k, setup, p.L, kGoldberg6RPsiMasks[static_cast<size_t>(k)]);
  double sum = 0.0;
  for (int q = 0; q < 10; ++q) {
    if (goldberg_6r_depends_on_psi(q, k)) sum += values[static_cast<size_t>(q)] * values[static_cast<size_t>(q)];
  }
  return sum;
}

// Gauss-Newton on psi from `psi`, the derivative by central differences;
// a step that does not lower the sum is halved, up to three times; at most
// eight steps (from the grid's best angle a member's psi is reached in four
// or five, to round-off).
inline double goldberg_6r_refine(const Goldberg6RParameters& p, int k, int setup, double psi) {
  std::array<double, 10> values{}, plus{}, minus{}, trial{};
  double sum = goldberg_6r_dependent_sum(p, k, setup, psi, values);
  for (int iteration = 0; iteration < 8 && sum > 0.0; ++iteration) {
    const double h = 1e-6;
    goldberg_6r_dependent_sum(p, k, setup, psi + h, plus);
    goldberg_6r_dependent_sum(p, k, setup, psi - h, minus);
    double jj = 0.0, jr = 0.0;
    for (int q = 0; q < 10; ++q) {
      if (!goldberg_6r_depends_on_psi(q, k)) continue;
      const auto i = static_cast<size_t>(q);
      const double j = (plus[i] - minus[i]) / (2.0 * h);
      jj += j * j;
      jr += j * values[i];
    }
    if (!(jj > 0.0)) break;
    double step = std::clamp(-jr / jj, -0.5, 0.5);
    if (std::abs(step) < 1e-14) break;
    bool moved = false;
    for (int halving = 0; halving < 4 && !moved; ++halving, step *= 0.5) {
      const double candidate = goldberg_6r_dependent_sum(p, k, setup, psi + step, trial);
      if (candidate < sum) {
        psi += step;
        sum = candidate;
        values = trial;
        moved = true;
      }
    }
    if (!moved) break;
  }
  return psi;
}

inline Goldberg6RFit goldberg_6r_fit_at(const Goldberg6RParameters& p, int k, int setup, double psi) {
  const Goldberg6RFive f = goldberg_6r_five(p, psi, true);
  return {goldberg_6r_values(f, k, setup, p.L), psi, f.fusion};
}

// The fit: Gauss-Newton from the best of a few starting angles. Where the
// 5R's link 6 -> P must have a known twist (P as C: it is the Goldberg 5R's
// B C, equal to E F, the 6R's link 4; P as F: it is E F, equal to B C, the
// 6R's link 3), its cosine, cos(alpha6) cos(alpha2) - sin(alpha6) sin(alpha2)
// cos(psi), gives psi up to its sign: the two are the starts. Otherwise a grid
// of 16 angles.
inline Goldberg6RFit goldberg_6r_fit(const Goldberg6RParameters& p, int k, int setup) {
  constexpr int kGrid = 16;
  std::array<double, 10> values{};
  double start = 0.0, least = kInf;
  const auto consider = [&](double psi) {
    const double sum = goldberg_6r_dependent_sum(p, k, setup, psi, values);
    if (sum < least) {
      least = sum;
      start = psi;
    }
  };
  const double sines = p.sin[5] * p.sin[1];
  if ((k == 1 || k == 4) && std::abs(sines) > 1e-12) {
    const double target = p.cos[k == 1 ? 3 : 2];
    const double psi = std::acos(std::clamp((p.cos[5] * p.cos[1] - target) / sines, -1.0, 1.0));
    consider(psi);
    consider(-psi);
  } else {
    for (int i = 0; i < kGrid; ++i) consider(2.0 * kPi * i / kGrid);
  }
  return goldberg_6r_fit_at(p, k, setup, goldberg_6r_refine(p, k, setup, start));
}

// The gradient of every value of the fit with respect to the representation's
// (a, alpha, d), by central differences (steps 1e-6 L and 1e-6 rad), each
// side refined from the fit's psi and evaluated with its own L.
inline std::array<GeometryVector, 10> goldberg_6r_fit_gradients(const Goldberg6RParameters& p, int k, int setup,
                                                                double psi) {
  const int n = 6;
  std::array<GeometryVector, 10> g;
  for (auto& v : g) v = GeometryVector::Zero(3 * n);
  for (int q = 0; q < 3 * n; ++q) {
    const auto i = static_cast<size_t>(q % n);
    const double h = q < n || q >= 2 * n ? 1e-6 * p.L : 1e-6;
    std::array<std::array<double, 10>, 2> side{};
    for (size_t s = 0; s < 2; ++s) {
      Goldberg6RParameters r = p;
      const double step = s == 0 ? h : -h;
      if (q < n) {
        r.a[i] += step;
      } else if (q < 2 * n) {
        r.alpha[i] = p.alpha[i] + step;
        r.sin[i] = std::sin(r.alpha[i]);
        r.cos[i] = std::cos(r.alpha[i]);
      } else {
        r.d[i] += step;
      }
      double mean_square = 0.0;
      for (size_t j = 0; j < 6; ++j) mean_square += r.a[j] * r.a[j] + r.d[j] * r.d[j];
      mean_square /= n;
      r.L = mean_square > 0.0 ? std::sqrt(mean_square) : 1.0;
      side[s] = goldberg_6r_fit_at(r, k, setup, goldberg_6r_refine(r, k, setup, psi)).values;
    }
    for (size_t v = 0; v < 10; ++v) g[v][q] = (side[0][v] - side[1][v]) / (2.0 * h);
  }
  return g;
}

// The number of condition sets: P as each of the Goldberg 5R's five joints,
// times goldberg_bent's four.
constexpr int kGoldberg6RSets = 20;

// The conditions of set `set` (P as the Goldberg 5R's joint set / 4, its
// Bennett loops in goldberg_bent's setups set % 4): the third loop's dyad
// (d2, the Bennett ratio of links 1 and 2), then goldberg_bent's conditions
// on the 5R, those that do not depend on psi first (read at psi = 0, where
// they are what they are at any psi), then the fitted ones.
template <class RepresentationView, class Sink>
void goldberg_6r_conditions(int set, const RepresentationView& w, Sink& c) {
  const int k = set / 4, setup = set % 4;
  add_offset(w, c, "d2", 1, -1, 0.0);
  add_bennett_ratio(w, c, "a1 |sin(alpha2)| - a2 |sin(alpha1)|", 0, 1);
  bool have_parameters = false, have_fixed = false, fitted = false, have_gradients = false;
  Goldberg6RParameters p;
  std::array<double, 10> fixed{};
  Goldberg6RFit fit;
  std::array<GeometryVector, 10> gradients;
  const auto parameters = [&]() -> const Goldberg6RParameters& {
    if (!have_parameters) {
      p = goldberg_6r_parameters(w);
      have_parameters = true;
    }
    return p;
  };
  const auto value = [&](int q) {
    if (!goldberg_6r_depends_on_psi(q, k)) {
      if (!have_fixed) {
        fixed = goldberg_6r_values(goldberg_6r_five(parameters(), 0.0), k, setup, parameters().L,
                                   ~kGoldberg6RPsiMasks[static_cast<size_t>(k)] & 0x3ffu);
        have_fixed = true;
      }
      return fixed[static_cast<size_t>(q)];
    }
    if (!fitted) {
      fit = goldberg_6r_fit(parameters(), k, setup);
      fitted = true;
    }
    return fit.values[static_cast<size_t>(q)];
  };
  const auto gradient = [&](int q) {
    if (!have_gradients) {
      if (!fitted) {
        fit = goldberg_6r_fit(parameters(), k, setup);
        fitted = true;
      }
      gradients = goldberg_6r_fit_gradients(parameters(), k, setup, fit.psi);
      have_gradients = true;
    }
    return gradients[static_cast<size_t>(q)];
  };
  static constexpr const char* kJoint[5] = {"B", "C", "D", "E", "F"};
  const auto name = [&](int q) {
    const Goldberg6RFive f;
    const Goldberg6RFiveView view{f, 0, Scale{1.0, GeometryVector(), 5}};
    Goldberg6RNames names;
    goldberg_bent_conditions(setup, view, names);
    return std::string("5R with P as ") + kJoint[k] + ": " + names.names[static_cast<size_t>(q)];
  };
  for (int pass = 0; pass < 2; ++pass) {
    for (int q = 0; q < 10; ++q) {
      if (goldberg_6r_depends_on_psi(q, k) != (pass == 1)) continue;
      c.add([&] { return name(q); }, [&] { return value(q); }, [&] { return gradient(q); });
    }
  }
}

// Sarrus 6R: two chains of three parallel axes, joints 2, 3, 4 and 5, 6, 1
// of the representation: sin(alpha2) = sin(alpha3) = 0, sin(alpha5) =
// sin(alpha6) = 0, and cos(alpha1)^2 = cos(alpha4)^2. Each chain lets the link between the chains (links 1 and
// 4) move in the plane normal to its axes, so it translates along the line
// normal to both directions: every such loop that closes moves (planar when
// the two directions are parallel, which planar is tried for first).
template <class RepresentationView, class Sink>
void sarrus_conditions(const RepresentationView& w, Sink& c) {
  const int n = 6;
  static constexpr const char* kSin[] = {"sin(alpha2)", "sin(alpha3)", "sin(alpha5)", "sin(alpha6)"};
  static constexpr int kLinks[] = {1, 2, 4, 5};
  for (int i = 0; i < 4; ++i) {
    const int k = kLinks[i];
    c.add([&] { return std::string(kSin[i]); }, [&] { return w.sin_alpha(k); },
          [&] {
            GeometryVector g = GeometryVector::Zero(3 * n);
            g[n + k] = w.cos_alpha(k);
            return g;
          });
  }
  // The angle between the two directions seen from either link between the
  // chains: without it the loop does not close.
  c.add([] { return "cos(alpha1)^2 - cos(alpha4)^2"; },
        [&] { return w.cos_alpha(0) * w.cos_alpha(0) - w.cos_alpha(3) * w.cos_alpha(3); },
        [&] {
          GeometryVector g = GeometryVector::Zero(3 * n);
          g[n + 0] = -2.0 * w.cos_alpha(0) * w.sin_alpha(0);
          g[n + 3] = 2.0 * w.cos_alpha(3) * w.sin_alpha(3);
          return g;
        });
}

// The angle-symmetric 6R with three pairs of parallel axes
// (constructions.hpp, angle_symmetric_parallel_6r; docs/guide/families.md):
// axes 1, 2 parallel (alpha1 = 0), axes 4, 5 parallel (alpha4 = 0), axes 3
// and 6 kept parallel by the twists (|alpha2| + |alpha6| = |alpha3| +
// |alpha5| = pi); joints 1, 4 and 2, 5 and 3, 6 turn by equal angles. With
// A_k = a_k sign(sin alpha_k) (the length signed along z_k x z_{k+1}), D1 =
// d1 + d2 and D4 = d4 + d5 (only the sums are defined between parallel
// axes): d3 = d6, a1 |sin alpha2| = a4 |sin alpha3|, a1 (A2 + A6) = a4 (A3 +
// A5), and, set 0 (the general kind), D1 cos alpha2 + D4 cos alpha3 = 0,
// (A3 + A5)^2 cos^2 alpha2 + D4^2 sin^2 alpha3 = a1^2 cos^2 alpha2 and the
// same read from the other pair of links, (A2 + A6)^2 cos^2 alpha3 + D1^2
// sin^2 alpha2 = a4^2 cos^2 alpha3; or, set 1 (axes 4, 5 the half-turned
// axes 1, 2), |alpha2| + |alpha3| = pi and D1 = D4. These are the
// construction's four conditions on the lines written in DH parameters;
// lengths in units of L, squared ones of L^2.
template <class RepresentationView, class Sink>
void angle_symmetric_parallel_conditions(int set, const RepresentationView& w, Sink& c) {
  const int n = 6;
  const Scale& s = w.scale();
  const auto twist = [&](int k) { return wrap_angle(w.alpha(k)); };
  const auto sign_of = [](double x) { return x < 0.0 ? -1.0 : 1.0; };
  const auto sigma = [&](int k) { return sign_of(w.sin_alpha(k)); };
  const auto signed_length = [&](int k) { return w.a(k) * sigma(k); };
  // A twist that is zero.
  const auto zero_twist = [&](const char* text, int k) {
    c.add([&] { return std::string(text); }, [&] { return twist(k); },
          [&] {
            GeometryVector g = GeometryVector::Zero(3 * n);
            g[n + k] = 1.0;
            return g;
          });
  };
  // |alpha_i| + |alpha_j| - pi.
  const auto supplementary = [&](const char* text, int i, int j) {
    c.add([&] { return std::string(text); }, [&] { return std::abs(twist(i)) + std::abs(twist(j)) - kPi; },
          [&] {
            GeometryVector g = GeometryVector::Zero(3 * n);
            g[n + i] += sign_of(twist(i));
            g[n + j] += sign_of(twist(j));
            return g;
          });
  };
  zero_twist("alpha1", 0);
  zero_twist("alpha4", 3);
  supplementary("|alpha2| + |alpha6| - pi", 1, 5);
  supplementary("|alpha3| + |alpha5| - pi", 2, 4);
  add_offset(w, c, "d3 - d6", 2, 5, -1.0);
  // (a1 |sin alpha2| - a4 |sin alpha3|) / L.
  const auto sines = [&] { return w.a(0) * std::abs(w.sin_alpha(1)) - w.a(3) * std::abs(w.sin_alpha(2)); };
  c.add([] { return "a1 |sin(alpha2)| - a4 |sin(alpha3)|"; }, [&] { return sines() / s.L; },
        [&] {
          GeometryVector g = -(sines() / (s.L * s.L)) * s.dL;
          g[0] += std::abs(w.sin_alpha(1)) / s.L;
          g[3] -= std::abs(w.sin_alpha(2)) / s.L;
          g[n + 1] += w.a(0) * sigma(1) * w.cos_alpha(1) / s.L;
          g[n + 2] -= w.a(3) * sigma(2) * w.cos_alpha(2) / s.L;
          return g;
        });
  // (a1 (A2 + A6) - a4 (A3 + A5)) / L^2.
  const auto sums = [&] {
    return w.a(0) * (signed_length(1) + signed_length(5)) - w.a(3) * (signed_length(2) + signed_length(4));
  };
  c.add([] { return "a1 (A2 + A6) - a4 (A3 + A5)"; }, [&] { return sums() / (s.L * s.L); },
        [&] {
          const double L2 = s.L * s.L;
          GeometryVector g = -(2.0 * sums() / (L2 * s.L)) * s.dL;
          g[0] += (signed_length(1) + signed_length(5)) / L2;
          g[1] += w.a(0) * sigma(1) / L2;
          g[5] += w.a(0) * sigma(5) / L2;
          g[3] -= (signed_length(2) + signed_length(4)) / L2;
          g[2] -= w.a(3) * sigma(2) / L2;
          g[4] -= w.a(3) * sigma(4) / L2;
          return g;
        });
  const auto D1 = [&] { return w.d(0) + w.d(1); };
  const auto D4 = [&] { return w.d(3) + w.d(4); };
  if (set == 1) {
    supplementary("|alpha2| + |alpha3| - pi", 1, 2);
    // (D1 - D4) / L: the general kind's offsets condition, cos(alpha2) (D1
    // - D4) here, written without the factor, which vanishes at alpha2 =
    // +-pi/2 where rigid loops with unequal sums would pass it.
    c.add([] { return "(d1 + d2) - (d4 + d5)"; }, [&] { return (D1() - D4()) / s.L; },
          [&] {
            GeometryVector g = -((D1() - D4()) / (s.L * s.L)) * s.dL;
            g[2 * n + 0] += 1.0 / s.L;
            g[2 * n + 1] += 1.0 / s.L;
            g[2 * n + 3] -= 1.0 / s.L;
            g[2 * n + 4] -= 1.0 / s.L;
            return g;
          });
    return;
  }
  // ((d1 + d2) cos alpha2 + (d4 + d5) cos alpha3) / L.
  const auto offsets = [&] { return D1() * w.cos_alpha(1) + D4() * w.cos_alpha(2); };
  c.add([] { return "(d1 + d2) cos(alpha2) + (d4 + d5) cos(alpha3)"; }, [&] { return offsets() / s.L; },
        [&] {
          GeometryVector g = -(offsets() / (s.L * s.L)) * s.dL;
          g[2 * n + 0] += w.cos_alpha(1) / s.L;
          g[2 * n + 1] += w.cos_alpha(1) / s.L;
          g[2 * n + 3] += w.cos_alpha(2) / s.L;
          g[2 * n + 4] += w.cos_alpha(2) / s.L;
          g[n + 1] -= D1() * w.sin_alpha(1) / s.L;
          g[n + 2] -= D4() * w.sin_alpha(2) / s.L;
          return g;
        });
  // ((A_i + A_j)^2 - a_k^2) cos^2 alpha_p + (d_m + d_{m+1})^2 sin^2 alpha_q,
  // over L^2, read from either pair of links. Each implies the other where
  // neither cosine is zero; at alpha2 = +-pi/2 the first leaves d1 + d2 free
  // and only the second fixes it (and at alpha3 = +-pi/2 the reverse).
  const auto circle_terms = [&](int i, int j, int k, int p, int m, int q) {
    const double S = signed_length(i) + signed_length(j), cp = w.cos_alpha(p), sq = w.sin_alpha(q);
    const double D = w.d(m) + w.d(m + 1);
    return (S * S - w.a(k) * w.a(k)) * cp * cp + D * D * sq * sq;
  };
  const auto circle = [&](const char* text, int i, int j, int k, int p, int m, int q) {
    c.add([&] { return std::string(text); }, [&] { return circle_terms(i, j, k, p, m, q) / (s.L * s.L); },
          [&] {
            const double L2 = s.L * s.L;
            const double S = signed_length(i) + signed_length(j), cp = w.cos_alpha(p), sp = w.sin_alpha(p);
            const double cq = w.cos_alpha(q), sq = w.sin_alpha(q), D = w.d(m) + w.d(m + 1);
            GeometryVector g = -(2.0 * circle_terms(i, j, k, p, m, q) / (L2 * s.L)) * s.dL;
            g[i] += 2.0 * S * sigma(i) * cp * cp / L2;
            g[j] += 2.0 * S * sigma(j) * cp * cp / L2;
            g[k] -= 2.0 * w.a(k) * cp * cp / L2;
            g[2 * n + m] += 2.0 * D * sq * sq / L2;
            g[2 * n + m + 1] += 2.0 * D * sq * sq / L2;
            g[n + p] -= 2.0 * (S * S - w.a(k) * w.a(k)) * cp * sp / L2;
            g[n + q] += 2.0 * D * D * sq * cq / L2;
            return g;
          });
  };
  circle("(A3 + A5)^2 cos^2(alpha2) + (d4 + d5)^2 sin^2(alpha3) - a1^2 cos^2(alpha2)", 2, 4, 0, 1, 3, 2);
  circle("(A2 + A6)^2 cos^2(alpha3) + (d1 + d2)^2 sin^2(alpha2) - a4^2 cos^2(alpha3)", 1, 5, 3, 2, 0, 1);
}

// Bricard's plane-symmetric octahedral 6R (his second type,
// docs/guide/families.md). Every a_i = 0, so axes u and u + 1 meet, at V_u:
// the six meeting points are an octahedron's vertices, V_u and V_{u+3}
// opposite. Its twelve edges are the hinges, |V_{u-1} V_u| = |d_u| along axis
// u, and the face diagonals, |V_{u-1} V_{u+1}|^2 = d_u^2 + d_{u+1}^2 +
// 2 d_u d_{u+1} cos(alpha_u) across link u. Set k (0, 1, 2): the mirror plane
// holds V_k and V_{k+3} and maps every other vertex onto its opposite one, so
// each edge is as long as its mirror image: six equalities.
template <class RepresentationView, class Sink>
void bricard_octahedral_plane_conditions(int set, const RepresentationView& w, Sink& c) {
  const int n = 6;
  const Scale& s = w.scale();
  static constexpr const char* kLengths[] = {"a1", "a2", "a3", "a4", "a5", "a6"};
  for (int i = 0; i < n; ++i) add_length(w, c, kLengths[i], i, -1, 0.0);
  // The edge between V_u and V_v (not opposite), and when `gradient` is not
  // null its gradient with respect to the representation's (a, alpha, d).
  auto edge = [&](int u, int v, GeometryVector* gradient) {
    if ((v - u + n) % n > 3) std::swap(u, v);  // v is 1 or 2 vertices on from u
    if (gradient) *gradient = GeometryVector::Zero(3 * n);
    if ((v - u + n) % n == 1) {  // the hinge along axis v
      const double d = w.d(v);
      if (gradient) (*gradient)[2 * n + v] = d > 0.0 ? 1.0 : (d < 0.0 ? -1.0 : 0.0);
      return std::abs(d);
    }
    const int m = (u + 1) % n, m1 = (m + 1) % n;  // the diagonal across link m
    const double dm = w.d(m), dm1 = w.d(m1), cm = w.cos_alpha(m);
    const double e = std::sqrt(std::max(0.0, dm * dm + dm1 * dm1 + 2.0 * dm * dm1 * cm));
    if (gradient && e > 0.0) {
      (*gradient)[2 * n + m] = (dm + dm1 * cm) / e;
      (*gradient)[2 * n + m1] = (dm1 + dm * cm) / e;
      (*gradient)[n + m] = -dm * dm1 * w.sin_alpha(m) / e;
    }
    return e;
  };
  const int k = set;
  // Each edge against its mirror image: (u, v) against (u', v').
  const int pairs[6][4] = {{k, k + 1, k, k + 4},         {k, k + 2, k, k + 5},         {k + 3, k + 1, k + 3, k + 4},
                           {k + 3, k + 2, k + 3, k + 5}, {k + 1, k + 2, k + 4, k + 5}, {k + 1, k + 5, k + 2, k + 4}};
  for (const auto& q : pairs) {
    const int u = q[0] % n, v = q[1] % n, u2 = q[2] % n, v2 = q[3] % n;
    auto difference = [&] { return (edge(u, v, nullptr) - edge(u2, v2, nullptr)) / s.L; };
    c.add(
        [&] {
          return "(|V" + std::to_string(u + 1) + "V" + std::to_string(v + 1) + "| - |V" + std::to_string(u2 + 1) + "V" +
                 std::to_string(v2 + 1) + "|) / L";
        },
        difference,
        [&] {
          GeometryVector g1, g2;
          edge(u, v, &g1);
          edge(u2, v2, &g2);
          return GeometryVector((g1 - g2) / s.L - (difference() / s.L) * s.dL);
        });
  }
}

// Hooke's double-spherical 6R (docs/guide/families.md): axes 1, 2, 3 of the
// representation through one point O1 (a1 = a2 = 0, and d2 = 0: links 1 and 2
// meet axis 2 at the same point), axes 4, 5, 6 through another, O2 (a4 = a5 =
// d5 = 0). Links 3 and 6 each carry both centres; each spherical chain lets
// link 3 turn against link 6 about its centre, so together about the line
// O1 O2, once the two links hold the centres equally far apart. In link 3,
// O1 is link 2's foot on axis 3 and O2 link 4's foot on axis 4, so O2 - O1 =
// d3 z3 + a3 x4 + d4 z4; in link 6, O1 - O2 = d6 z6 + a6 x1 + d1 z1. With
// z3 . z4 = cos(alpha3), z6 . z1 = cos(alpha6) and the normals perpendicular
// to both axes, the squared distances are
//   d3^2 + a3^2 + d4^2 + 2 d3 d4 cos(alpha3) and d6^2 + a6^2 + d1^2 + 2 d6 d1 cos(alpha6);
// their difference over L^2 is the last condition (squared, so polynomial in
// the parameters and smooth where the two centres meet: a spherical loop).
template <class RepresentationView, class Sink>
void hooke_conditions(const RepresentationView& w, Sink& c) {
  const int n = 6;
  const Scale& s = w.scale();
  add_length(w, c, "a1", 0, -1, 0.0);
  add_length(w, c, "a2", 1, -1, 0.0);
  add_offset(w, c, "d2", 1, -1, 0.0);
  add_length(w, c, "a4", 3, -1, 0.0);
  add_length(w, c, "a5", 4, -1, 0.0);
  add_offset(w, c, "d5", 4, -1, 0.0);
  // |O1 O2|^2 in link k (joints k and k + 1; 0-based k = 2 or 5).
  auto squared = [&](int k) {
    const int j = (k + 1) % n;
    return w.d(k) * w.d(k) + w.a(k) * w.a(k) + w.d(j) * w.d(j) + 2.0 * w.d(k) * w.d(j) * w.cos_alpha(k);
  };
  auto difference = [&] { return (squared(2) - squared(5)) / (s.L * s.L); };
  c.add([] { return "(|O1O2|^2 in link 3 - |O1O2|^2 in link 6) / L^2"; }, difference,
        [&] {
          GeometryVector g = -(2.0 * difference() / s.L) * s.dL;
          for (int k : {2, 5}) {
            const int j = (k + 1) % n;
            const double sign = k == 2 ? 1.0 : -1.0, scale = sign / (s.L * s.L);
            g[k] += scale * 2.0 * w.a(k);
            g[2 * n + k] += scale * 2.0 * (w.d(k) + w.d(j) * w.cos_alpha(k));
            g[2 * n + j] += scale * 2.0 * (w.d(j) + w.d(k) * w.cos_alpha(k));
            g[n + k] += -scale * 2.0 * w.d(k) * w.d(j) * w.sin_alpha(k);
          }
          return g;
        });
}

// Bricard's doubly collapsible octahedral 6R (his third type,
// docs/guide/families.md). Every a_i = 0, and the meeting points V_u of axes
// u and u + 1 are an octahedron's vertices, V_u and V_{u+3} opposite, as for
// bricard_octahedral_plane: hinge h_u = |V_{u-1} V_u| = |d_u| and diagonal
// D_u = |V_{u-1} V_{u+1}| across link u. In a flat pose of such an octahedron
// the four edges at a vertex lie on the two tangents from it to one circle
// and the two to another about the same centre, so the four face angles at
// every vertex are, in their order round it, f1, f2, f3, f4 with f1 = f3 and
// f2 = f4, or f1 = pi - f3 and f2 = pi - f4: two conditions on their cosines
// per vertex, with the sign s = +-1 of the closer fit. And the four edges of
// each cycle V_{k-1} V_k V_{k+2} V_{k+3} (through two opposite pairs) touch
// one circle in that pose, so they add up to zero with signs: h_k +- D_{k+1}
// +- h_{k+3} +- D_{k+4} = 0, the signs those of the closest fit. The lengths
// and angles are the octahedron's own, so the conditions hold in every pose
// and every representation. A vertex with an edge of zero length at it (no
// octahedron) fails its angle conditions by 1.
template <class RepresentationView, class Sink>
void bricard_octahedral_collapsible_conditions(const RepresentationView& w, Sink& c) {
  const int n = 6;
  const Scale& s = w.scale();
  static constexpr const char* kLengths[] = {"a1", "a2", "a3", "a4", "a5", "a6"};
  for (int i = 0; i < n; ++i) add_length(w, c, kLengths[i], i, -1, 0.0);
  auto at = [](int u) { return static_cast<size_t>((u % 6 + 6) % 6); };
  // The twelve edges, computed when a condition first needs them.
  std::array<double, 6> hinge{}, diagonal{};
  bool edges = false;
  auto need_edges = [&] {
    if (edges) return;
    for (int u = 0; u < n; ++u) {
      const double d = w.d(u), d1 = w.d(static_cast<int>(at(u + 1)));
      hinge[at(u)] = std::abs(d);
      diagonal[at(u)] = std::sqrt(std::max(0.0, d * d + d1 * d1 + 2.0 * d * d1 * w.cos_alpha(u)));
    }
    edges = true;
  };
  // The gradients of hinge u and diagonal u with respect to (a, alpha, d).
  auto hinge_gradient = [&](int u) {
    GeometryVector g = GeometryVector::Zero(3 * n);
    const double d = w.d(u);
    g[2 * n + u] = d > 0.0 ? 1.0 : (d < 0.0 ? -1.0 : 0.0);
    return g;
  };
  auto diagonal_gradient = [&](int u) {
    GeometryVector g = GeometryVector::Zero(3 * n);
    const int u1 = static_cast<int>(at(u + 1));
    const double e = diagonal[at(u)], d = w.d(u), d1 = w.d(u1), cu = w.cos_alpha(u);
    if (e > 0.0) {
      g[2 * n + u] = (d + d1 * cu) / e;
      g[2 * n + u1] = (d1 + d * cu) / e;
      g[n + u] = -d * d1 * w.sin_alpha(u) / e;
    }
    return g;
  };
  // An edge of the octahedron: a hinge or a diagonal, by its index.
  struct Edge {
    bool is_hinge;
    int index;
  };
  auto length = [&](Edge e) { return e.is_hinge ? hinge[at(e.index)] : diagonal[at(e.index)]; };
  auto length_gradient = [&](Edge e) {
    return e.is_hinge ? hinge_gradient(static_cast<int>(at(e.index)))
                      : diagonal_gradient(static_cast<int>(at(e.index)));
  };
  // The cosine of a face angle from its two sides p, q and the side r
  // opposite it (law of cosines), or none where a side has no length. Three
  // lengths that make no triangle (round-off where a side nearly vanishes)
  // read the cosine held to [-1, 1], with no gradient.
  struct Angle {
    Edge p, q, r;
  };
  auto law_of_cosines = [&](const Angle& a) {
    const double p = length(a.p), q = length(a.q), r = length(a.r);
    return (p * p + q * q - r * r) / (2.0 * p * q);
  };
  auto cosine = [&](const Angle& a, double& value) {
    if (!(length(a.p) > 0.0 && length(a.q) > 0.0)) return false;
    value = std::clamp(law_of_cosines(a), -1.0, 1.0);
    return true;
  };
  auto cosine_gradient = [&](const Angle& a) {
    const double p = length(a.p), q = length(a.q), r = length(a.r);
    if (std::abs(law_of_cosines(a)) > 1.0) return GeometryVector(GeometryVector::Zero(3 * n));
    return GeometryVector((p * p - q * q + r * r) / (2.0 * p * p * q) * length_gradient(a.p) +
                          (q * q - p * p + r * r) / (2.0 * p * q * q) * length_gradient(a.q) -
                          r / (p * q) * length_gradient(a.r));
  };
  for (int i = 0; i < n; ++i) {
    // Round V_i: V_{i-1} (hinge i), V_{i+1} (hinge i + 1), V_{i+2} (diagonal
    // i + 1), V_{i-2} (diagonal i - 1); the faces between them are links i,
    // i + 1, the face V_{i-2} V_i V_{i+2} and link i - 1.
    const std::array<Angle, 4> face = {
        Angle{{true, i}, {true, i + 1}, {false, i}}, Angle{{true, i + 1}, {false, i + 1}, {true, i + 2}},
        Angle{{false, i + 1}, {false, i - 1}, {false, i + 3}}, Angle{{false, i - 1}, {true, i}, {true, i - 1}}};
    struct {
      bool computed = false, octahedron = false;
      double sign = 1.0;
      std::array<double, 4> cosines{};
    } fit;
    auto vertex = [&] {
      if (fit.computed) return;
      fit.computed = true;
      need_edges();
      fit.octahedron = true;
      for (size_t k = 0; k < 4; ++k) fit.octahedron = cosine(face[k], fit.cosines[k]) && fit.octahedron;
      if (!fit.octahedron) return;
      const std::array<double, 4>& f = fit.cosines;
      const double same = (f[0] - f[2]) * (f[0] - f[2]) + (f[1] - f[3]) * (f[1] - f[3]);
      const double supplementary = (f[0] + f[2]) * (f[0] + f[2]) + (f[1] + f[3]) * (f[1] + f[3]);
      fit.sign = supplementary < same ? -1.0 : 1.0;
    };
    for (size_t k = 0; k < 2; ++k) {
      c.add(
          [&] {
            return "cos(f" + std::to_string(k + 1) + ") -+ cos(f" + std::to_string(k + 3) + ") at V" +
                   std::to_string(i + 1);
          },
          [&] {
            vertex();
            return fit.octahedron ? fit.cosines[k] - fit.sign * fit.cosines[k + 2] : 1.0;
          },
          [&] {
            vertex();
            if (!fit.octahedron) return GeometryVector(GeometryVector::Zero(3 * n));
            return GeometryVector(cosine_gradient(face[k]) - fit.sign * cosine_gradient(face[k + 2]));
          });
    }
  }
  for (int k = 0; k < 3; ++k) {
    // The cycle V_{k-1} V_k V_{k+2} V_{k+3}: hinge k, diagonal k + 1, hinge
    // k + 3, diagonal k + 4; signs + and the three of the best fit.
    const std::array<Edge, 4> cycle = {Edge{true, k}, Edge{false, k + 1}, Edge{true, k + 3}, Edge{false, k + 4}};
    std::array<double, 4> sign = {1.0, 1.0, 1.0, 1.0};
    double sum = 0.0;
    bool computed = false;
    auto fit = [&] {
      if (computed) return;
      computed = true;
      need_edges();
      double best = kInf;
      for (int pattern = 0; pattern < 8; ++pattern) {
        const std::array<double, 4> trial = {1.0, pattern & 1 ? -1.0 : 1.0, pattern & 2 ? -1.0 : 1.0,
                                             pattern & 4 ? -1.0 : 1.0};
        double t = 0.0;
        for (size_t e = 0; e < 4; ++e) t += trial[e] * length(cycle[e]);
        if (std::abs(t) < best) {
          best = std::abs(t);
          sum = t;
          sign = trial;
        }
      }
    };
    c.add(
        [&] {
          fit();
          std::string text = "(h" + std::to_string(k + 1);
          const char* names[] = {"h", "D", "h", "D"};
          for (size_t e = 1; e < 4; ++e) {
            text += (sign[e] > 0 ? " + " : " - ") + std::string(names[e]) + std::to_string(at(cycle[e].index) + 1);
          }
          return text + ") / L";
        },
        [&] {
          fit();
          return sum / s.L;
        },
        [&] {
          fit();
          GeometryVector g = -(sum / (s.L * s.L)) * s.dL;
          for (size_t e = 0; e < 4; ++e) g += (sign[e] / s.L) * length_gradient(cycle[e]);
          return g;
        });
  }
}

// The 5R families built from two Bennett loops sharing a link: Goldberg's,
// its symmetric case Myard's and its bent-link variant.
constexpr bool goldberg_type(Family family) {
  return family == Family::goldberg || family == Family::myard || family == Family::goldberg_bent;
}

// The condition sets of a representation that a family's score takes the best of,
// numbered: for Bennett loops set 0 is the asymmetric setup and set 1 the
// line-symmetric one; for trivial loops set 0 is axes 1 and 2 coinciding and
// set 1 (n = 4) axes 1 and 3; planar loops have one set; Goldberg and Myard
// sets as goldberg_conditions and myard_conditions say; Bricard loops one;
// angle_symmetric_parallel two (its general kind, set 0, and its half-turn
// kind, set 1).
inline int condition_sets(Family family, int joints) {
  switch (family) {
    case Family::bennett:
      return 2;
    case Family::planar:
      return 1;
    case Family::trivial:
      return joints == 4 ? 2 : 1;
    case Family::goldberg:
      return 8;
    case Family::myard:
      return 16;
    case Family::goldberg_bent:
      return 4;
    case Family::bennett_pair:
      return 4;
    case Family::bricard_octahedral_plane:
      return 3;
    case Family::goldberg_6r:
      return kGoldberg6RSets;
    case Family::angle_symmetric_parallel:
      return 2;
    case Family::hooke:
    case Family::bricard_octahedral_collapsible:
    case Family::bennett_dyads:
    case Family::bennett_triads:
    case Family::coupled_bennett_dyads:
    case Family::waldron_hybrid:
    case Family::double_goldberg:
    case Family::sarrus:
    case Family::bricard_line_symmetric:
    case Family::bricard_plane_symmetric:
    case Family::bricard_trihedral:
      return 1;
    case Family::spherical:
    case Family::degenerate:
    case Family::cubic_321:
    case Family::unclassified:
      break;
  }
  return 0;  // no representations
}

// Whether a family's conditions read cosines of twists (the numeric path
// tabulates them only then).
constexpr bool reads_cosines(Family family) {
  return family == Family::planar || family == Family::myard || family == Family::goldberg_bent ||
         family == Family::bricard_trihedral || family == Family::bennett_dyads || family == Family::bennett_triads ||
         family == Family::coupled_bennett_dyads || family == Family::sarrus ||
         family == Family::bricard_octahedral_plane || family == Family::waldron_hybrid ||
         family == Family::goldberg_6r || family == Family::double_goldberg || family == Family::hooke ||
         family == Family::bricard_octahedral_collapsible || family == Family::angle_symmetric_parallel;
}

// Whether a family's score can depend on the sign of a twist (the freedom at
// a zero-length link, representation.hpp): not where every condition reads
// twists only through cos(alpha) or |sin(alpha)|, as planar's, trivial's on
// five or more joints (adjacent axes coaxial), the trihedral Bricard loop's
// and the two octahedral ones' (edge lengths and face angles) do.
// Classification tries the twist signs only for the others (family_fit.hpp).
constexpr bool reads_twist_signs(Family family, int joints) {
  switch (family) {
    case Family::planar:
    case Family::bricard_trihedral:
    case Family::bricard_octahedral_plane:
    case Family::bricard_octahedral_collapsible:
      return false;
    case Family::trivial:
      return joints == 4;  // axes 1 and 3 coaxial: twist differences
    default:
      return true;
  }
}

template <Family F, class RepresentationView, class Sink>
void condition_set(int set, const RepresentationView& w, Sink& c) {
  static_assert(F != Family::spherical && F != Family::degenerate && F != Family::unclassified &&
                F != Family::cubic_321);
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
  } else if constexpr (F == Family::bennett_triads) {
    bennett_triads_conditions(w, c);
  } else if constexpr (F == Family::coupled_bennett_dyads) {
    coupled_bennett_dyads_conditions(w, c);
  } else if constexpr (F == Family::waldron_hybrid) {
    waldron_hybrid_conditions(w, c);
  } else if constexpr (F == Family::goldberg_6r) {
    goldberg_6r_conditions(set, w, c);
  } else if constexpr (F == Family::double_goldberg) {
    double_goldberg_conditions(w, c);
  } else if constexpr (F == Family::sarrus) {
    sarrus_conditions(w, c);
  } else if constexpr (F == Family::bricard_octahedral_plane) {
    bricard_octahedral_plane_conditions(set, w, c);
  } else if constexpr (F == Family::hooke) {
    hooke_conditions(w, c);
  } else if constexpr (F == Family::bricard_octahedral_collapsible) {
    bricard_octahedral_collapsible_conditions(w, c);
  } else if constexpr (F == Family::angle_symmetric_parallel) {
    angle_symmetric_parallel_conditions(set, w, c);
  } else if (set == 0) {
    adjacent_coaxial_conditions(w, c);
  } else {
    coaxial_13_conditions(w, c);
  }
}

}  // namespace loopfarm::detail
