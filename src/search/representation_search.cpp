// The numeric path's representation tables (representation_search.hpp).
#include "representation_search.hpp"

#include <algorithm>
#include <cassert>
#include <stdexcept>
#include <string>

namespace loopfarm::detail {
namespace {

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

}  // namespace

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

}  // namespace loopfarm::detail
