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
  // Links (in the labels as written) whose twist the best representation
  // negates: zero-length links, where the twist's sign is free (representation.hpp).
  std::uint32_t negated_twists = 0;
};

// zero_length for the distances: no link's twist sign is free.
constexpr double kNoZeroLength = -1.0;

// The best representation of g written out: its twists negated where the
// best one negates them, then the representation applied.
inline LoopGeometry written_out(const Best& best, const LoopGeometry& g) {
  return detail::apply(*best.representation, with_negated_twists(g, best.negated_twists));
}

// The condition that makes a negated twist the same loop, a_k = 0, for each
// link k in `links` (as written), in the order of the links: a_k / L, L the
// loop's length scale, named (and differentiated) in the labels of
// representation r, written out as w.
template <class Sink>
void zero_length_conditions(const LoopGeometry& g, std::uint32_t links, const detail::Representation& r,
                            const WrittenOut& w, Sink& c) {
  if (links == 0u) return;
  const double L = length_scale(g);
  for (int j = 0; j < g.joints(); ++j) {
    if (!(links >> j & 1u)) continue;
    int k = 0;  // link j in r's labels
    while (r.index[static_cast<size_t>(k)] != j) ++k;
    c.add([&] { return label("a", k) + " / L (" + label("alpha", k) + " negated: a zero-length link's twist sign)"; },
          [&] { return g.a[j] / L; }, [&] { return w.scale().ratio_gradient(k, w.a(k)); });
  }
}

// The representation is picked by the numeric path's search
// (representation_search.hpp), which evaluates the same formulas on the same
// numbers in the same order as writing every representation out would, and
// keeps the first of equal scores as that would: only the one picked is
// written out, with its conditions named.
//
// Classification (max |condition|, zero_length >= 0) also takes the twist
// sign at every zero-length link, a_k <= zero_length * L, as free: for each
// nonempty set S of such links (in increasing order of its bits, after the
// twists as written) the search runs on the geometry with S's twists negated,
// whose score is the larger of its conditions' and max a_k / L over S (the
// condition that makes it the same loop), and a set replaces the best only
// when strictly better. A loop without a zero-length link (the generic case)
// is searched once, as before; one with z of them up to 2^z times, and only
// for the families whose conditions read twist signs (reads_twist_signs).
// Distances (by_norm) keep the twists as written: the set of
// representations would change where a length crosses the tolerance, and a
// distance steering a search must stay smooth.
template <Family F>
Best best_over_representations(const LoopGeometry& g, bool by_norm, double zero_length) {
  RepresentationSearch search = by_norm ? best_representation<F, SquaredNorm>(g) : best_representation<F, MaxAbs>(g);
  std::uint32_t negated = 0;
  const std::uint32_t free_signs =
      by_norm || !reads_twist_signs(F, g.joints()) ? 0u : zero_length_links(g, zero_length);
  if (free_signs != 0u) {
    const double L = length_scale(g);
    // Every nonempty subset of free_signs, in increasing order.
    for (std::uint32_t links = (0u - free_signs) & free_signs; links != 0u; links = (links - free_signs) & free_signs) {
      double zero = 0.0;  // max a_k / L over the negated links, as zero_length_conditions computes it
      for (int k = 0; k < g.joints(); ++k) {
        if (links >> k & 1u) zero = std::max(zero, g.a[k] / L);
      }
      if (!(zero < search.score)) continue;
      RepresentationSearch negated_search = best_representation<F, MaxAbs>(with_negated_twists(g, links), search.score);
      if (negated_search.representation < 0) continue;
      negated_search.score = std::max(negated_search.score, zero);
      if (negated_search.score < search.score) {
        search = negated_search;
        negated = links;
      }
    }
  }
  Best best;
  if (search.representation < 0) return best;  // no finite score
  const detail::Representation& r = detail::representations(g.joints())[static_cast<size_t>(search.representation)];
  best.representation = &r;
  best.negated_twists = negated;
  const WrittenOut w(written_out(best, g));
  condition_set<F>(search.set, w, best.conditions);
  zero_length_conditions(g, negated, r, w, best.conditions);
  best.score = by_norm ? best.conditions.norm() : best.conditions.max_abs();
  assert(best.score == search.score);  // the search's numbers, bit for bit
  best.setup_sign = F == Family::bennett ? (search.set == 0 ? 1.0 : -1.0) : 0.0;
  best.set = search.set;
  return best;
}

FamilyCheck check_from(Family family, const Best& best);

// best_over_representations for a family named at run time (those with representations).
Best best_for(Family family, const LoopGeometry& g, bool by_norm, double zero_length);

// A family's check on the geometry alone (not trivial, not degenerate), twist
// signs free at links of length at most zero_length * L.
FamilyCheck family_check(Family family, const LoopGeometry& g, double zero_length);

// The n-specific families beyond planar and spherical, in the order they are
// tried (the more special first).
std::vector<Family> special_families(int n);

struct GeometricFit {
  Family family = Family::unclassified;
  double residual = kInf;
  std::string detail;
};

// A loop that fits goldberg, myard or goldberg_bent with one of its two
// Bennett loops equilateral and folding: (a, alpha) twice with Bennett's
// angle relation singular, tan(t1/2) tan(t2/2) = sin((alpha2 + alpha1)/2) /
// sin((alpha2 - alpha1)/2) (asymmetric setup) or cos(..) / cos(..)
// (line-symmetric) with a zero denominator. Such a "Bennett loop" only folds,
// so the 5R has no Goldberg motion (docs/research/discovery-5r-6r.md). It folds in two
// ways. Folded with the joint next to the fused link locked at pi (representation
// joint 5 when the second loop folds, joint 1 when the first does), the two
// axes at its other ends coincide with the removed axis A and the loop turns
// about it freely: the 5R moves as the other Bennett loop with that joint
// locked, a degenerate loop whatever motion a search followed. Folded the
// other way it locks the other loop: two 5R axes coincide and only they turn
// (trivial). Both motions meet where the loop folds both ways, and a walk
// through that pose can switch or stray between them, so no joint's travel
// need look frozen (docs/research/discovery-5r-6r.md, "Goldberg geometries on a
// folding Bennett loop"). Checked in the family's best representation, links 1 and 2
// (first loop) and 1 and 3 (second), to `tolerance` (lengths over L).
struct FoldingGoldberg {
  bool folds = false;
  double residual = kInf;  // the family's residual and the fold's two conditions, the largest
  std::string detail;
  FamilyCheck check;
};

FoldingGoldberg folding_goldberg(Family family, const Best& best, const LoopGeometry& g, double family_residual,
                                 double tolerance);

// The best-fitting movable family of a loop by its geometry alone, for a
// merged or locked loop, with classify's precedence: planar, spherical,
// degenerate (n = 5), then the n-specific ones in their order; the first
// that fits (residual <= tolerance) is taken, so a later one never replaces
// it however small its residual (goldberg_bent, which holds every Goldberg
// loop, fits them to round-off too). A Goldberg-type fit on a folding
// Bennett loop is no Goldberg motion (folding_goldberg): it is degenerate,
// taken only when no later n-specific family fits, as classify takes it.
// When none fits, the least residual.
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
