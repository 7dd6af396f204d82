// The families' names, joint counts and dimensions (classify.hpp).
#include <optional>
#include <string_view>

#include "loopfarm/search/classify.hpp"

namespace loopfarm {

const char* to_string(Family family) {
  switch (family) {
    case Family::bennett:
      return "bennett";
    case Family::planar:
      return "planar";
    case Family::spherical:
      return "spherical";
    case Family::trivial:
      return "trivial";
    case Family::unclassified:
      return "unclassified";
    case Family::goldberg:
      return "goldberg";
    case Family::myard:
      return "myard";
    case Family::bricard_line_symmetric:
      return "bricard_line_symmetric";
    case Family::bricard_plane_symmetric:
      return "bricard_plane_symmetric";
    case Family::bricard_trihedral:
      return "bricard_trihedral";
    case Family::degenerate:
      return "degenerate";
    case Family::goldberg_bent:
      return "goldberg_bent";
    case Family::bennett_pair:
      return "bennett_pair";
    case Family::bennett_dyads:
      return "bennett_dyads";
    case Family::sarrus:
      return "sarrus";
    case Family::bricard_octahedral_plane:
      return "bricard_octahedral_plane";
    case Family::waldron_hybrid:
      return "waldron_hybrid";
    case Family::goldberg_6r:
      return "goldberg_6r";
    case Family::double_goldberg:
      return "double_goldberg";
    case Family::hooke:
      return "hooke";
    case Family::bricard_octahedral_collapsible:
      return "bricard_octahedral_collapsible";
    case Family::cubic_321:
      return "cubic_321";
    case Family::angle_symmetric_parallel:
      return "angle_symmetric_parallel";
    case Family::bennett_triads:
      return "bennett_triads";
    case Family::coupled_bennett_dyads:
      return "coupled_bennett_dyads";
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
    case Family::bennett:
      return 4;
    case Family::goldberg:
    case Family::myard:
    case Family::goldberg_bent:
      return 5;
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
    case Family::cubic_321:
    case Family::angle_symmetric_parallel:
      return 6;
    case Family::planar:
    case Family::spherical:
    case Family::trivial:
    case Family::degenerate:
    case Family::unclassified:
      return 0;
  }
  return 0;
}

// degenerate and cubic_321 are decided from the motion or a pose of it, not
// by conditions on the geometry.
bool has_family_distance(Family family) {
  return family != Family::degenerate && family != Family::unclassified && family != Family::cubic_321;
}

std::optional<int> family_dimension(Family family, int joints) {
  const int needs = family_joints(family);
  if (needs != 0 && joints != needs) return std::nullopt;
  switch (family) {
    case Family::bennett:
      return 3;
    case Family::planar:
      return 2 * joints - 1;  // n lengths, n - 1 independent offsets
    case Family::spherical:
      return joints;  // n twists
    case Family::goldberg:
      return 4;
    case Family::myard:
      return 2;
    case Family::goldberg_bent:
      return 5;
    case Family::bricard_line_symmetric:
      return 9;
    case Family::bricard_plane_symmetric:
      return 8;
    case Family::bricard_trihedral:
      return 5;
    case Family::bennett_pair:
      return 4;
    case Family::bennett_dyads:
      return 9;
    case Family::bennett_triads:
      // 18 parameters, 11 conditions; local_dimension reads 7 on the
      // search's members (docs/guide/families.md).
      return 7;
    case Family::coupled_bennett_dyads:
      // 18 parameters, ten independent conditions (Q' repeats Q's conic);
      // the wrenches reciprocal to the joint screws along the motion count
      // ten on the search's members (docs/guide/families.md).
      return 8;
    case Family::sarrus:
      // 18 parameters less five conditions; the first-order count
      // (local_dimension) reads 14 on members (docs/guide/families.md).
      return 13;
    case Family::bricard_octahedral_plane:
      // The octahedron's two vertices in the plane and two off it, less the
      // plane's motions and the flex (docs/guide/families.md).
      return 6;
    case Family::waldron_hybrid:
      // Two Bennett loops (three parameters each, the scale included) and
      // the second's turn and slide along the shared axis and its phase:
      // 18 parameters, 9 conditions; local_dimension reads 9 on members
      // (docs/guide/families.md).
      return 9;
    case Family::goldberg_6r:
      // A bent Goldberg 5R (5, the scale included) and the third Bennett
      // loop's twist and fusion angle: 18 parameters, 11 conditions; the
      // construction's Jacobian has rank 7 (docs/guide/families.md).
      return 7;
    case Family::double_goldberg:
      // Three Bennett loops on one joint axis (a Goldberg 5R's five and the
      // third loop's twist and fusion angle): 18 parameters, 11 conditions;
      // the construction's Jacobian has rank 7. local_dimension reads 9 on
      // members: it sees waldron_hybrid, which holds them (docs/guide/families.md).
      return 7;
    case Family::hooke:
      // Two centres and three axis directions through each (18 numbers)
      // less the rigid motions (6) and the motion itself (1): 18 parameters,
      // 7 conditions; the construction's Jacobian has rank 11, and
      // local_dimension reads 11 on members (docs/guide/families.md).
      return 11;
    case Family::bricard_octahedral_collapsible:
      // Two radii and two vertices in the plane of a flat pose, less the
      // turn about the circles' centre: the construction's Jacobian has rank
      // 5, and the 21 conditions' gradients rank 13 of 18 (docs/guide/families.md).
      return 5;
    case Family::cubic_321:
      // Three rotation factors (6 numbers each) less the rigid motions (6)
      // and the reparametrisations of the motion (3): 9; local_dimension
      // reads 9 on members (docs/guide/families.md).
      return 9;
    case Family::angle_symmetric_parallel:
      // Either kind of its construction (constructions.hpp): three pairs of
      // parallel lines (18 numbers) less the rigid motions (6), the four
      // conditions and the motion itself: 7; the construction's Jacobian has
      // rank 7 (docs/guide/families.md).
      return 7;
    case Family::trivial:  // a rigid rotation: no dimension of its own
    case Family::degenerate:
    case Family::unclassified:
      return std::nullopt;
  }
  return std::nullopt;
}

const char* to_string(BennettSetup setup) {
  switch (setup) {
    case BennettSetup::none:
      return "none";
    case BennettSetup::asymmetric:
      return "asymmetric";
    case BennettSetup::line_symmetric:
      return "line_symmetric";
  }
  return "unknown";
}

}  // namespace loopfarm
