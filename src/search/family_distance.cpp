// Distances to the families (classify.hpp): family_distance, the numeric path
// (family_conditions.hpp), and family_distance_report, the reporting path.
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
#include <string>
#include <vector>

#include "family_conditions.hpp"
#include "family_fit.hpp"
#include "representation.hpp"

namespace loopfarm {

using namespace detail;

namespace {

// ---------------------------------------------------------------------------
// The numeric path: the representations looked up, not written out.

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

// Whether two representations take their lengths and offsets from the same joints.
[[maybe_unused]] bool same_places(const CompiledRepresentation& w, const CompiledRepresentation& v, int n) {
  for (size_t k = 0; k < static_cast<size_t>(n); ++k) {
    if (w.a[k] != v.a[k] || w.d[k] / 2 != v.d[k] / 2) return false;
  }
  return true;
}

RepresentationTable build_representation_table(int n) {
  RepresentationTable table;
  table.representations = &detail::representations(n);
  [[maybe_unused]] const size_t flips = size_t{1} << n;
  table.compiled.reserve(table.representations->size());
  for (size_t i = 0; i < table.representations->size(); ++i) {
    const detail::Representation& r = (*table.representations)[i];
    assert(r.flips == i % flips);
    CompiledRepresentation w;
    for (int k = 0; k < n; ++k) {
      const auto ia = static_cast<size_t>(k), it = static_cast<size_t>(n + k), id = static_cast<size_t>(2 * n + k);
      // a'_k = 1 * a_j + 0.
      assert(r.sign[ia] == 1.0 && r.offset[ia] == 0.0 && !std::signbit(r.offset[ia]));
      w.a[ia] = static_cast<std::uint8_t>(r.index[ia]);
      // alpha'_k = wrap(1 * alpha_j + m pi).
      assert(r.sign[it] == 1.0);
      const auto m =
          static_cast<int>(std::find(kTwistOffsets.begin(), kTwistOffsets.end(), r.offset[it]) - kTwistOffsets.begin());
      assert(m < 3);
      w.twist[ia] = static_cast<std::uint8_t>(3 * (r.index[it] - n) + m);
      // d'_k = +-1 * d_j +- 0 (the offset's zero carries the sign).
      const bool negated = r.sign[id] < 0.0;
      assert(std::abs(r.sign[id]) == 1.0 && r.offset[id] == 0.0 && std::signbit(r.offset[id]) == negated);
      w.d[ia] = static_cast<std::uint8_t>(2 * (r.index[id] - 2 * n) + (negated ? 1 : 0));
    }
    // Flips move no parameter, so a representation's lengths, and L, are those of its order's first representation.
    assert(same_places(w, i % flips == 0 ? w : table.compiled[i - i % flips], n));
    table.compiled.push_back(w);
  }
  return table;
}

// Built on first use, once per joint count (thread-safe static initialisation).
template <int N>
const RepresentationTable& representation_table_for() {
  static const RepresentationTable table = build_representation_table(N);
  return table;
}

const RepresentationTable& representation_table(int n) {
  static_assert(kMinJoints == 4 && kMaxJoints == 8, "one case per joint count");
  switch (n) {
    case 4:
      return representation_table_for<4>();
    case 5:
      return representation_table_for<5>();
    case 6:
      return representation_table_for<6>();
    case 7:
      return representation_table_for<7>();
    case 8:
      return representation_table_for<8>();
  }
  throw std::logic_error("representation_table: unvalidated joint count " + std::to_string(n));
}

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
double length_scale_of(const Tables& t, const CompiledRepresentation& w) {
  LoopGeometry lengths;
  lengths.a.resize(t.n);
  lengths.d.resize(t.n);
  for (int k = 0; k < t.n; ++k) {
    lengths.a[k] = t.a[w.a[static_cast<size_t>(k)]];
    lengths.d[k] = t.d[w.d[static_cast<size_t>(k)]];
  }
  return length_scale(lengths);
}

// The best representation so far, kept as best_over_representations keeps it by norm: a
// condition set replaces it only when its norm is strictly smaller, so the
// first of equal ones stays.
struct Search {
  double sum = kInf;  // of squares, of the best representation's conditions
  double norm = kInf;
  int representation = -1;  // index in detail::representations order
  int set = 0;              // which condition set (condition_set)

  void keep(const SquaredNorm& c, int index, int which) {
    // A sum not below the best's cannot have a smaller sqrt.
    if (c.abandoned || !(c.sum < sum)) return;
    const double candidate = std::sqrt(c.sum);
    if (candidate < norm) {
      sum = c.sum;
      norm = candidate;
      representation = index;
      set = which;
    }
  }
};

template <Family F>
Search best_representation(const LoopGeometry& g, const RepresentationTable& table) {
  const int n = g.joints();
  // Cosines only where a condition's value reads them; elsewhere they enter gradients alone.
  const Tables t = tabulate(g, reads_cosines(F));
  const int sets = condition_sets(F, n);
  const int flips = 1 << n;
  Search best;
  for (int order = 0; order < 2 * n; ++order) {
    const int first = order * flips;
    const Scale s{length_scale_of(t, table.compiled[static_cast<size_t>(first)]), GeometryVector(), n};
    for (int i = first; i < first + flips; ++i) {
      const TabulatedRepresentation w{t, table.compiled[static_cast<size_t>(i)], s};
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

// The distance over the representations and, when `gradient` is not null, its
// gradient: the best representation written out once and differentiated.
template <Family F>
double distance_over_representations(const LoopGeometry& g, GeometryVector* gradient) {
  const int n = g.joints();
  const RepresentationTable& table = representation_table(n);
  const Search best = best_representation<F>(g, table);
  assert(best.representation >= 0);  // every norm is finite: the conditions are in units of L
  if (gradient) {
    const detail::Representation& r = (*table.representations)[static_cast<size_t>(best.representation)];
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

double family_distance(Family family, const LoopGeometry& geometry, GeometryVector* gradient) {
  validate_geometry(geometry);
  require_joints("family_distance", family, geometry);
  switch (family) {
    case Family::bennett:
      if (geometry.joints() != 4) throw std::invalid_argument("family_distance: Bennett loops have 4 joints");
      return distance_over_representations<Family::bennett>(geometry, gradient);
    case Family::planar:
      return distance_over_representations<Family::planar>(geometry, gradient);
    case Family::spherical:
      return spherical_distance(geometry, gradient);
    case Family::trivial:
      return distance_over_representations<Family::trivial>(geometry, gradient);
    case Family::goldberg:
      return distance_over_representations<Family::goldberg>(geometry, gradient);
    case Family::myard:
      return distance_over_representations<Family::myard>(geometry, gradient);
    case Family::goldberg_bent:
      return distance_over_representations<Family::goldberg_bent>(geometry, gradient);
    case Family::bricard_line_symmetric:
      return distance_over_representations<Family::bricard_line_symmetric>(geometry, gradient);
    case Family::bricard_plane_symmetric:
      return distance_over_representations<Family::bricard_plane_symmetric>(geometry, gradient);
    case Family::bricard_trihedral:
      return distance_over_representations<Family::bricard_trihedral>(geometry, gradient);
    case Family::bennett_pair:
      return distance_over_representations<Family::bennett_pair>(geometry, gradient);
    case Family::bennett_dyads:
      return distance_over_representations<Family::bennett_dyads>(geometry, gradient);
    case Family::sarrus:
      return distance_over_representations<Family::sarrus>(geometry, gradient);
    case Family::degenerate:
      throw std::invalid_argument("family_distance: degenerate loops have no distance");
    case Family::unclassified:
      break;
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
      best = best_over_representations<Family::bennett>(geometry, true);
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
    case Family::bennett_dyads:
    case Family::sarrus:
      best = best_for(family, geometry, true);
      break;
    case Family::degenerate:
      throw std::invalid_argument("family_distance_report: degenerate loops have no distance");
    case Family::unclassified:
      throw std::invalid_argument("family_distance_report: not a family");
  }
  if (gradient) {
    const GeometryVector g = best.conditions.norm_gradient(3 * n);
    *gradient = best.representation ? detail::pull_back(*best.representation, g) : g;
  }
  FamilyCheck check = check_from(family, best);
  if (family == Family::bennett) {
    check.setup = best.setup_sign > 0 ? BennettSetup::asymmetric : BennettSetup::line_symmetric;
  }
  return check;
}

}  // namespace loopfarm
