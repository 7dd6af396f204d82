// The fit of a loop to the known families by its geometry alone, on the
// reporting path (family_conditions.hpp): every representation written out,
// every condition named. Shared by classification (classify.cpp, locked_joints.cpp)
// and family_distance_report (family_distance.cpp). Internal to the search.
#pragma once

#include <span>
#include <string>
#include <vector>

#include "family_conditions.hpp"
#include "representation.hpp"

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

template <Family F>
Best best_over_representations(const LoopGeometry& g, bool by_norm) {
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
        best.representation = &r;
        best.setup_sign = F == Family::bennett ? (set == 0 ? 1.0 : -1.0) : 0.0;
        best.set = set;
      }
    }
  }
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
