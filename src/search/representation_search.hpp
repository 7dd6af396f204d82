// The numeric path's search over the representations of a loop
// (family_conditions.hpp): each representation's parameters looked up in
// small tables filled once per call, not written out, and a representation
// given up as soon as it cannot beat the best so far. It builds no string
// and allocates nothing. family_distance uses it by norm; classification
// (best_over_representations, family_fit.hpp) by max |condition|, then writes
// out the one representation it picked. Internal to the search.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <type_traits>
#include <vector>

#include "family_conditions.hpp"
#include "representation.hpp"

namespace loopfarm::detail {

// The twist offsets detail::representations puts on a twist: none, one axis
// flipped (pi), both axes flipped (pi + pi).
constexpr std::array<double, 3> kTwistOffsets = {0.0, kPi, kPi + kPi};

// One representation as indices into the values of one call (Tables).
struct CompiledRepresentation {
  std::array<std::uint8_t, kMaxJoints> a{};      // a'_k = Tables::a[a[k]]
  std::array<std::uint8_t, kMaxJoints> twist{};  // alpha'_k = Tables::twist[twist[k]], likewise sin, cos
  std::array<std::uint8_t, kMaxJoints> d{};      // d'_k = Tables::d[d[k]]
};

// The representations of an n-joint loop in detail::representations order: for each
// of the 2n (shift, reversal) orders, its 2^n sets of axis flips, which
// change signs and twist offsets but move no parameter.
struct RepresentationTable {
  const std::vector<detail::Representation>* representations = nullptr;
  std::vector<CompiledRepresentation> compiled;
};

// Built on first use, once per joint count (thread-safe static initialisation).
const RepresentationTable& representation_table(int n);

// The values the representations' parameters take for one geometry: every a_j, every
// +-d_j, every twist alpha_j + m pi (m = 0, 1, 2) wrapped, with its sine and,
// when asked, its cosine. Computed as detail::apply computes them (sign *
// value + offset, twists then wrapped), so a lookup gives the written-out
// representation's number bit for bit.
struct Tables {
  int n = 0;
  std::array<double, kMaxJoints> a;
  std::array<double, 2 * kMaxJoints> d;                // 2j: d_j, 2j + 1: -d_j
  std::array<double, 3 * kMaxJoints> twist, sin, cos;  // 3j + m: alpha_j + m pi
};

Tables tabulate(const LoopGeometry& g, bool cosines);

// One representation as the conditions read it, from the tables.
struct TabulatedRepresentation {
  const Tables& t;
  const CompiledRepresentation& w;
  const Scale& s;  // L only: the search takes no gradients
  int joints() const { return t.n; }
  double a(int k) const { return t.a[w.a[static_cast<size_t>(k)]]; }
  double alpha(int k) const { return t.twist[w.twist[static_cast<size_t>(k)]]; }
  double d(int k) const { return t.d[w.d[static_cast<size_t>(k)]]; }
  double sin_alpha(int k) const { return t.sin[w.twist[static_cast<size_t>(k)]]; }
  double cos_alpha(int k) const { return t.cos[w.twist[static_cast<size_t>(k)]]; }
  const Scale& scale() const { return s; }
};

// A representation's length scale as scale_of computes it on the written-out
// representation: length_scale on its lengths and offsets, in its order.
double length_scale_of(const Tables& t, const CompiledRepresentation& w);

// The classification's search: the running max |value|, given up once it
// reaches `bound` (the best representation's so far): a representation given
// up cannot have a strictly smaller max. Conditions::max_abs's max, in the
// same order (a NaN value makes both NaN: a set that cannot be evaluated
// never fits, and is given up at once).
struct MaxAbs {
  double bound = kInf;
  double max = 0.0;
  bool abandoned = false;

  template <class Name, class Value, class Gradient>
  void add(const Name&, const Value& value, const Gradient&) {
    if (abandoned) return;
    max = max_abs_step(max, value());
    abandoned = max >= bound || std::isnan(max);
  }
};

// The best representation so far, kept as the reporting path keeps it (by
// norm or by max |condition|): a condition set replaces it only when its
// score is strictly smaller, so the first of equal ones stays.
struct RepresentationSearch {
  double sum = kInf;  // by norm: of squares, of the best representation's conditions
  double score = kInf;
  int representation = -1;  // index in detail::representations order
  int set = 0;              // which condition set (condition_set)

  void keep(const SquaredNorm& c, int index, int which) {
    // A sum not below the best's cannot have a smaller sqrt.
    if (c.abandoned || !(c.sum < sum)) return;
    const double candidate = std::sqrt(c.sum);
    if (candidate < score) {
      sum = c.sum;
      score = candidate;
      representation = index;
      set = which;
    }
  }
  void keep(const MaxAbs& c, int index, int which) {
    if (c.abandoned || !(c.max < score)) return;
    score = c.max;
    representation = index;
    set = which;
  }
};

// The representation and condition set of family F that fit g best: by the
// norm of the conditions (Sink = SquaredNorm) or by their max |value|
// (Sink = MaxAbs). With Sink = MaxAbs and a finite `bound`, only a
// representation whose score is below it counts (representation -1 if none):
// the search over twist signs (best_over_representations) passes the best
// score so far.
template <Family F, class Sink>
RepresentationSearch best_representation(const LoopGeometry& g, double bound_score = kInf) {
  const int n = g.joints();
  const RepresentationTable& table = representation_table(n);
  // Cosines only where a condition's value reads them; elsewhere they enter gradients alone.
  const Tables t = tabulate(g, reads_cosines(F));
  const int sets = condition_sets(F, n);
  const int flips = 1 << n;
  RepresentationSearch best;
  if constexpr (std::is_same_v<Sink, MaxAbs>) best.score = bound_score;
  auto bound = [&best] {
    if constexpr (std::is_same_v<Sink, SquaredNorm>) {
      return best.sum;
    } else {
      return best.score;
    }
  };
  for (int order = 0; order < 2 * n; ++order) {
    const int first = order * flips;
    const Scale s{length_scale_of(t, table.compiled[static_cast<size_t>(first)]), GeometryVector(), n};
    for (int i = first; i < first + flips; ++i) {
      const TabulatedRepresentation w{t, table.compiled[static_cast<size_t>(i)], s};
      if constexpr (F == Family::bennett) {
        // The two setups share every condition but the last: evaluate those once.
        Sink common{bound()};
        bennett_common_conditions(w, common);
        for (int set = 0; set < 2; ++set) {
          Sink c = common;
          bennett_setup_condition(w, set == 0 ? 1.0 : -1.0, c);
          best.keep(c, i, set);
        }
      } else {
        for (int set = 0; set < sets; ++set) {
          Sink c{bound()};
          condition_set<F>(set, w, c);
          best.keep(c, i, set);
        }
      }
    }
  }
  return best;
}

}  // namespace loopfarm::detail
