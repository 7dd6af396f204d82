// The fit of a loop to the known families by its geometry alone, on the
// reporting path (family_conditions.hpp): the best representation written
// out, every condition named. Shared by classification (classify.cpp, locked_joints.cpp)
// and family_distance_report (family_distance.cpp). Internal to the search.
#pragma once

#include <cassert>
#include <span>
#include <string>
#include <vector>

#include "family_conditions.hpp"
#include "representation.hpp"
#include "representation_search.hpp"

namespace loopfarm::detail {

// The best representation's conditions for a family, by max |condition| (for
// classification) or by norm (for distances).
struct Best {
  Conditions conditions;
  const detail::Representation* representation = nullptr;
  double score = kInf;
  double setup_sign = 0.0;  // Bennett: +1 asymmetric, -1 line-symmetric
  int set = 0;              // the best representation's condition set (condition_sets)
};

// The representation is picked by the numeric path's search
// (representation_search.hpp), which evaluates the same formulas on the same
// numbers in the same order as writing every representation out would, and
// keeps the first of equal scores as that would: only the one picked is
// written out, with its conditions named.
template <Family F>
Best best_over_representations(const LoopGeometry& g, bool by_norm) {
  const RepresentationSearch search =
      by_norm ? best_representation<F, SquaredNorm>(g) : best_representation<F, MaxAbs>(g);
  Best best;
  if (search.representation < 0) return best;  // no finite score
  const detail::Representation& r = detail::representations(g.joints())[static_cast<size_t>(search.representation)];
  const WrittenOut w(detail::apply(r, g));
  condition_set<F>(search.set, w, best.conditions);
  best.score = by_norm ? best.conditions.norm() : best.conditions.max_abs();
  assert(best.score == search.score);  // the search's numbers, bit for bit
  best.representation = &r;
  best.setup_sign = F == Family::bennett ? (search.set == 0 ? 1.0 : -1.0) : 0.0;
  best.set = search.set;
  return best;
}

FamilyCheck check_from(Family family, const Best& best);

// best_over_representations for a family named at run time (those with representations).
Best best_for(Family family, const LoopGeometry& g, bool by_norm);

// A family's check on the geometry alone (not trivial, not degenerate).
FamilyCheck family_check(Family family, const LoopGeometry& g);

// The n-specific families beyond planar and spherical, in the order they are
// tried (the more special first).
std::vector<Family> special_families(int n);

struct GeometricFit {
  Family family = Family::unclassified;
  double residual = kInf;
  std::string detail;
};

// The best-fitting movable family of a loop by its geometry alone (planar,
// spherical, degenerate, then the n-specific ones), for a merged loop: once a
// family fits (residual <= tolerance), a later one replaces it only when it
// fits and an earlier, more special one does not (goldberg_bent, which holds
// every Goldberg loop, fits them to round-off too).
GeometricFit geometric_fit(const LoopGeometry& g, double tolerance);

// Degenerate: over the adjacent pairs of axes, max(a_k / L, |sin alpha_k|,
// the merged loop's best family residual), the least; only pairs that can
// still beat the best so far are merged and classified.
GeometricFit degenerate_fit(const LoopGeometry& g, double tolerance, FamilyCheck& check);

// Locked joints: the best fit (geometric_fit) of the loop left by locking
// one frozen joint, or all of them together (a 6R with two joints locked is
// a 4R), never below 4 joints (a 4R with a joint locked is a 3R, which
// cannot move); for n >= 5.
GeometricFit locked_fit(const LoopGeometry& g, const JointVector& pose, const std::vector<int>& frozen,
                        std::span<const double> travel, double tolerance, double frozen_travel, FamilyCheck& check);

}  // namespace loopfarm::detail
