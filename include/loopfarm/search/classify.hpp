// Classification of a movable loop into the known families (docs/design.md,
// "Known movable 4R loops"; docs/guide/families.md for 5R and 6R), with the residual
// of every condition of every family.
//
// Conditions are evaluated on every equivalent representation of the loop (cyclic
// relabelling, reversal, axis flips: 2n * 2^n of them) and the best one is
// kept, so that the answer does not depend on labels or axis directions.
// Residuals are dimensionless: lengths divided by the length scale L.
//
//   bennett    (n = 4) a1 = a3, a2 = a4, alpha1 = alpha3, alpha2 = alpha4,
//              d_i = 0, and a2 sin(alpha1) = a1 sin(alpha2) (asymmetric setup,
//              paper eq. 1) or = -a1 sin(alpha2) (line-symmetric, eq. 3)
//   planar     every sin(alpha_i) = 0, and the signed sum of the offsets (the
//              sign turning at each alpha_i = pi) is zero
//   spherical  every a_i = 0 and d_i = 0
//   trivial    two joint axes coincide in the given pose and some joint stays
//              frozen over the motion: a rigid rotation about the shared axis
//   goldberg   (n = 5) two Bennett loops sharing a link, the shared link
//              removed and the two collinear links fused
//   myard      (n = 5) the plane-symmetric Goldberg 5R
//   goldberg_bent (n = 5) the same two Bennett loops with the two links
//              fused at any angle (Goldberg's collinear fusion is its
//              special case): offsets d1 = +-d5 appear at the fused link
//   bricard_line_symmetric, bricard_plane_symmetric, bricard_trihedral (n = 6)
//   bennett_pair (n = 6) two Bennett loops sharing a link, the shared link
//              removed and nothing fused: moves with two degrees of freedom
//   bennett_dyads (n = 6) two Bennett dyads with equal (cos alpha + cos
//              beta) / kappa joined by two equal links (docs/guide/families.md)
//   bennett_triads (n = 6) two triads of links, 1-3 and 4-6 of a
//              representation, each of one signed Bennett ratio k = sin
//              alpha / a with no offsets inside (d2 = d3 = d5 = d6 = 0), d4 =
//              -d1, and the same (1 + sum of cos alpha) / k and product of
//              cos(alpha / 2) over k for both (docs/guide/families.md)
//   coupled_bennett_dyads (n = 6) two Bennett dyads (links 2-3 and 5-6 of a
//              representation, d3 = d6 = 0) joined by links 1 and 4, with
//              three relations between their twists and lengths and the
//              offsets on a conic: the dyads' middle joints turn together
//              (docs/guide/families.md)
//   waldron_hybrid (n = 6) Waldron's hybrid: two Bennett dyads (links 1-2
//              and 4-5 of a representation, no offset at joints 2 and 5)
//              whose fourth axes, found in the fused links 3 and 6, are one
//              line, the two Bennett loops' feet on it the same distance
//              apart in both links (a fit of the construction)
//   goldberg_6r (n = 6) Goldberg's 6R of three Bennett loops: a Bennett
//              dyad (links 1-2 of a representation, no offset at joint 2)
//              whose fourth axis, placed in link 6 at the angle that fits
//              best, gives back a Goldberg 5R (goldberg_bent's conditions)
//              with link 1 in the place of the removed link (a fit of the
//              construction)
//   double_goldberg (n = 6) the double-Goldberg 6R (two Goldberg 5Rs merged
//              along a shared Bennett dyad): Waldron's hybrid whose two
//              Bennett loops have one ratio and meet the fourth axis at one
//              point (waldron_hybrid's fit and two conditions more)
//   sarrus     (n = 6) two chains of three parallel axes: sin(alpha) = 0 for
//              two pairs of consecutive links (2, 3 and 5, 6 of a
//              representation) and cos^2(alpha1) = cos^2(alpha4); the link
//              between the chains translates along one line
//   bricard_octahedral_plane (n = 6) every a_i = 0: the axes' meeting
//              points are the vertices of an octahedron with a mirror plane
//              through two opposite vertices that maps each other vertex onto
//              its opposite one (six pairs of equal edges)
//   bricard_octahedral_collapsible (n = 6) every a_i = 0: the axes' meeting
//              points are the vertices of a doubly collapsible octahedron
//              (Bricard's third type, two flat poses): at each vertex the
//              opposite face angles are equal or supplementary, and the four
//              edges of each of the three four-edge cycles through two
//              opposite pairs add up to zero with signs
//   angle_symmetric_parallel (n = 6) three pairs of parallel axes, 1-2 and
//              4-5 of a representation (alpha1 = alpha4 = 0) and 3-6 (|alpha2|
//              + |alpha6| = |alpha3| + |alpha5| = pi), opposite joints turning
//              by equal angles: d3 = d6, a1 |sin alpha2| = a4 |sin alpha3|,
//              a1 (A2 + A6) = a4 (A3 + A5) (A_k = a_k sign(sin alpha_k)),
//              and either (set 0) (d1 + d2) cos alpha2 + (d4 + d5) cos alpha3
//              = 0 and (A3 + A5)^2 cos^2 alpha2 + (d4 + d5)^2 sin^2 alpha3 =
//              a1^2 cos^2 alpha2, with the same read from the other pair of
//              links, or (set 1, axes 4-5 the half-turned 1-2) |alpha2| +
//              |alpha3| = pi and d1 + d2 = d4 + d5
//   cubic_321  (n = 6) the two factorisations (t - h1)(t - h2)(t - h3) =
//              (t - k1)(t - k2)(t - k3) of a cubic motion polynomial, the
//              k's norms those of h3, h2, h1, closed into the loop h1 h2 h3
//              k3 k2 k1 (Hegedus, Schicho, Schroecker 2013): decided at the
//              pose, by fitting the construction to the loop's axes there
//              (cubic_motion_fit.hpp); no distance
//   hooke      (n = 6) Hooke's double-spherical loop: axes 1-3 of a
//              representation through one point (a1 = a2 = d2 = 0), axes 4-6
//              through another (a4 = a5 = d5 = 0), and links 3 and 6 hold the
//              two points equally far apart; link 3 turns against link 6
//              about the line through them
//   degenerate (n = 5, 6) two adjacent axes coincide (a_k = 0, alpha_k = 0
//              or pi) and the (n-1)R loop with them merged is in a movable
//              family (not trivial); or a joint stays locked over the motion
//              (no axes coincide) and the (n-1)R loop left by locking it is
//              in a movable family
//
// docs/guide/classification.md has the details and the tolerances.
#pragma once

#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "loopfarm/core/loop.hpp"

namespace loopfarm {

// Strings (to_string) are stored in results databases: a new family gets a
// new string, an existing one never changes.
enum class Family {
  bennett,
  planar,
  spherical,
  trivial,
  unclassified,
  // 5R (docs/guide/families.md)
  goldberg,
  myard,
  // 6R
  bricard_line_symmetric,
  bricard_plane_symmetric,
  bricard_trihedral,
  // n = 5, 6: two adjacent axes coincide and the loop with them merged is in
  // a movable family (an idle joint)
  degenerate,
  // 5R: Goldberg's construction with the two links fused at an angle
  goldberg_bent,
  // 6R: two Bennett loops sharing a link, the shared link removed (mobility 2)
  bennett_pair,
  // 6R: two Bennett dyads joined by two equal links (found by the generic search)
  bennett_dyads,
  // 6R: two chains of three parallel axes (Sarrus)
  sarrus,
  // 6R: every a_i = 0, the axes' meeting points a Bricard octahedron
  // symmetric in a plane through two opposite vertices (his second type)
  bricard_octahedral_plane,
  // 6R: Waldron's hybrid, two Bennett loops sharing a joint axis, fused
  // links, the shared joint removed
  waldron_hybrid,
  // 6R: Goldberg's 6R, a (bent) Goldberg 5R and a third Bennett loop sharing
  // one of its links, the shared link removed and two links fused
  goldberg_6r,
  // 6R: the double-Goldberg 6R, three Bennett loops fused at one joint axis
  // (two Goldberg 5Rs merged along a shared dyad, which is removed)
  double_goldberg,
  // 6R: Hooke's double-spherical loop, axes 1-3 through one point and axes
  // 4-6 through another; links 3 and 6 turn about the line through both
  hooke,
  // 6R: every a_i = 0, the axes' meeting points a doubly collapsible Bricard
  // octahedron (his third type, with two flat poses)
  bricard_octahedral_collapsible,
  // 6R: the loop of a cubic motion polynomial's two factorisations in the
  // order "321" (opposite joints share a norm factor and turn by equal
  // angles); decided at a pose of the motion
  cubic_321,
  // 6R: three pairs of parallel axes (1-2, 4-5 and 3-6 of a representation)
  // whose opposite joints turn by equal angles
  angle_symmetric_parallel,
  // 6R: two triads of links of one Bennett ratio each (found by the generic search)
  bennett_triads,
  // 6R: two Bennett dyads whose middle joints turn together (found by the generic search)
  coupled_bennett_dyads,
};
const char* to_string(Family family);

// Every family, in the enum's order: the one list for loops over families
// and lists of their names (a --family option and its message). A family
// added to the enum is added here (classify_test fails until it is).
inline constexpr Family kAllFamilies[] = {
    Family::bennett,
    Family::planar,
    Family::spherical,
    Family::trivial,
    Family::unclassified,
    Family::goldberg,
    Family::myard,
    Family::bricard_line_symmetric,
    Family::bricard_plane_symmetric,
    Family::bricard_trihedral,
    Family::degenerate,
    Family::goldberg_bent,
    Family::bennett_pair,
    Family::bennett_dyads,
    Family::sarrus,
    Family::bricard_octahedral_plane,
    Family::waldron_hybrid,
    Family::goldberg_6r,
    Family::double_goldberg,
    Family::hooke,
    Family::bricard_octahedral_collapsible,
    Family::cubic_321,
    Family::angle_symmetric_parallel,
    Family::bennett_triads,
    Family::coupled_bennett_dyads,
};
// The family whose to_string is `name`, or none.
std::optional<Family> family_from_string(std::string_view name);
// The joint count the family's conditions are written for; 0 for any
// (planar, spherical, trivial, unclassified) and for degenerate (n = 5, 6).
int family_joints(Family family);
// Whether family_distance measures it: every family but degenerate,
// cubic_321 (both decided from the motion or a pose of it) and unclassified.
bool has_family_distance(Family family);
// The family's dimension for `joints` joints: its free real parameters,
// the scale included (docs/guide/families.md, docs/guide/classification.md); none for a
// joint count it does not have, for degenerate and for unclassified.
std::optional<int> family_dimension(Family family, int joints);

enum class BennettSetup { none, asymmetric, line_symmetric };
const char* to_string(BennettSetup setup);

struct ConditionResidual {
  std::string name;  // e.g. "a1 - a3", in the best representation's labels
  double residual = 0.0;
};

struct FamilyCheck {
  Family family = Family::unclassified;
  BennettSetup setup = BennettSetup::none;
  double residual = 0.0;  // max |condition| of the best representation (inf where the family does not apply)
  std::vector<ConditionResidual> conditions;
};

struct ClassifyOptions {
  double tolerance = 1e-8;      // a family fits when its residual is at most this
  double frozen_travel = 1e-6;  // [rad] a joint turning less than this over the motion is frozen
  // [rad] 5R only: a joint that rocks by more than frozen_travel but at most
  // this may still be locked for the locked-joint rule (degenerate), where the
  // 4R left must then fit to `tolerance` as for a frozen joint: a loop a
  // distance eps off a locked-joint Bennett loop can close along the walk to
  // order eps^2 with its locked joint rocking by order eps (up to 1e3 eps
  // measured), docs/research/discovery-5r-6r.md, "The rocking joint". Not for trivial.
  double rocking_travel = 1e-3;
};

struct Classification {
  Family family = Family::unclassified;
  BennettSetup setup = BennettSetup::none;
  double residual = 0.0;  // of the family found (of the nearest family when unclassified)
  std::string detail;     // e.g. "axes 1 and 3 coincide; joints 2 and 4 frozen"
  // Every family whose conditions hold (its check's residual within the
  // tolerance; trivial by the pose and the motion): `family` first when it is
  // one of them, then the others in the order they are tried. One geometry
  // can satisfy several families' conditions (a line-symmetric Sarrus loop);
  // `family` is the one the order of precedence picks. Empty when none holds.
  std::vector<Family> fitting;
  // bennett, planar, spherical, trivial, in this order; then for n = 5
  // degenerate, myard, goldberg, goldberg_bent and for n = 6 degenerate, bricard_trihedral,
  // bricard_plane_symmetric, bricard_line_symmetric, bennett_pair, goldberg_6r,
  // double_goldberg, bennett_triads, coupled_bennett_dyads, bennett_dyads, waldron_hybrid, sarrus,
  // angle_symmetric_parallel, bricard_octahedral_plane,
  // bricard_octahedral_collapsible, cubic_321, hooke (the order they are tried).
  std::vector<FamilyCheck> checks;
};

// `pose`: the joint angles of one assembled pose (for the coincidence of
// axes); `joint_travel`: per joint, how far it turns over the verified motion
// [rad], empty when unknown (then no loop is called trivial). Throws
// std::invalid_argument for an invalid geometry or a pose of the wrong size.
Classification classify(const LoopGeometry& geometry, const JointVector& pose, std::span<const double> joint_travel,
                        const ClassifyOptions& options = {});

// Distance of a geometry to a family's conditions, for steering the search
// away from it (deflation): sqrt of the sum of the squared conditions of the
// best representation, lengths divided by L; with its gradient with respect to
// (a, alpha, d) when `gradient` is not null (a min over representations: smooth
// away from the points where the best representation changes).
//   planar, bennett: the conditions above;
//   spherical: sqrt(sum a_i^2 + d_i^2) in the geometry's own units (in units
//     of L it would be constant);
//   trivial: the nearest coincidence of two axes that the geometry alone
//     decides: a_i = 0 and sin(alpha_i) = 0 for adjacent axes, and for n = 4
//     the coaxial 1-3 (or 2-4) conditions a1 = a2, alpha1 = alpha2, a3 = a4,
//     alpha3 = alpha4, d2 = d4 = 0, d1 = -d3.
// The numeric path, called on every evaluation of a steered search: it builds
// no names and, after the first call for a joint count (which builds that
// count's table of representations), allocates nothing. Also goldberg, myard and
// goldberg_bent (n = 5) and the 6R families, their conditions as classify()
// lists them (waldron_hybrid's fit differentiated by central differences).
// Throws std::invalid_argument for an invalid
// geometry, a family for another joint count (Bennett with n != 4, ...),
// Family::degenerate (its conditions depend on which axes are merged),
// Family::cubic_321 (decided at a pose) or Family::unclassified.
double family_distance(Family family, const LoopGeometry& geometry, GeometryVector* gradient = nullptr);

// The same distance (and gradient) by the reporting path: every representation
// written out and the best one's conditions listed by name, as classify()
// lists them (`residual` is the distance; `setup` the best Bennett setup).
// Equal to family_distance bit for bit; slow and allocating, for reports,
// the documentation and tests.
FamilyCheck family_distance_report(Family family, const LoopGeometry& geometry, GeometryVector* gradient = nullptr);

}  // namespace loopfarm
