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
#include "representation_search.hpp"

namespace loopfarm {

using namespace detail;

namespace {

// The distance over the representations and, when `gradient` is not null, its
// gradient: the best representation written out once and differentiated.
template <Family F>
double distance_over_representations(const LoopGeometry& g, GeometryVector* gradient) {
  const int n = g.joints();
  const RepresentationSearch best = best_representation<F, SquaredNorm>(g);
  assert(best.representation >= 0);  // every norm is finite: the conditions are in units of L
  if (gradient) {
    const detail::Representation& r = detail::representations(n)[static_cast<size_t>(best.representation)];
    const WrittenOut w(detail::apply(r, g));
    FixedConditions c;
    condition_set<F>(best.set, w, c);
    assert(c.norm() == best.score);  // the search's numbers, bit for bit
    *gradient = detail::pull_back(r, c.norm_gradient(3 * n));
  }
  return best.score;
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
    case Family::bennett_triads:
      return distance_over_representations<Family::bennett_triads>(geometry, gradient);
    case Family::coupled_bennett_dyads:
      return distance_over_representations<Family::coupled_bennett_dyads>(geometry, gradient);
    case Family::sarrus:
      return distance_over_representations<Family::sarrus>(geometry, gradient);
    case Family::bricard_octahedral_plane:
      return distance_over_representations<Family::bricard_octahedral_plane>(geometry, gradient);
    case Family::waldron_hybrid:
      return distance_over_representations<Family::waldron_hybrid>(geometry, gradient);
    case Family::goldberg_6r:
      return distance_over_representations<Family::goldberg_6r>(geometry, gradient);
    case Family::double_goldberg:
      return distance_over_representations<Family::double_goldberg>(geometry, gradient);
    case Family::hooke:
      return distance_over_representations<Family::hooke>(geometry, gradient);
    case Family::bricard_octahedral_collapsible:
      return distance_over_representations<Family::bricard_octahedral_collapsible>(geometry, gradient);
    case Family::angle_symmetric_parallel:
      return distance_over_representations<Family::angle_symmetric_parallel>(geometry, gradient);
    case Family::degenerate:
      throw std::invalid_argument("family_distance: degenerate loops have no distance");
    case Family::cubic_321:
      throw std::invalid_argument("family_distance: cubic_321 loops have no distance (decided at a pose)");
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
      best = best_over_representations<Family::bennett>(geometry, true, kNoZeroLength);
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
    case Family::bennett_triads:
    case Family::coupled_bennett_dyads:
    case Family::sarrus:
    case Family::bricard_octahedral_plane:
    case Family::waldron_hybrid:
    case Family::goldberg_6r:
    case Family::double_goldberg:
    case Family::hooke:
    case Family::bricard_octahedral_collapsible:
    case Family::angle_symmetric_parallel:
      best = best_for(family, geometry, true, kNoZeroLength);
      break;
    case Family::degenerate:
      throw std::invalid_argument("family_distance_report: degenerate loops have no distance");
    case Family::cubic_321:
      throw std::invalid_argument("family_distance_report: cubic_321 loops have no distance (decided at a pose)");
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
