// Ground truth: a generated, labelled set of 4R loops whose answer is known
// by construction, to measure the search's methods against (missed zeros,
// false zeros, the smallest perturbation still told apart from zero).
//
// Known movable (docs/design.md, "Known movable 4R loops"), each with a pose that
// closes the rigid loop to round-off, computed in closed form:
//   bennett    both setups (bennett_loop, bennett_loop_line_symmetric), twists
//              over [margin, 180 deg - margin] away from the twist pairs where
//              the loop degenerates, length scales from min to max, pose from
//              the closed forms bennett_angles / bennett_angles_line_symmetric;
//   planar     four-bars with the input link the shortest and the Grashof
//              inequality strict by a margin (a crank: the input turns
//              fully); some with offsets whose signed sum is zero, some with
//              axes flipped (twists of 180 deg); pose from the law of cosines;
//   spherical  all lengths zero, twists chosen so that the input turns fully
//              (the spherical Grashof condition on the diagonal arc); pose
//              from the spherical law of cosines;
//   trivial    the coaxial 1-3 loop (docs/design.md, "Trivial"): axes 1 and 3
//              coincide, joints 2 and 4 frozen at 180 deg, theta3 = -theta1;
//              some with axes flipped.
// Known rigid: every movable case perturbed in one parameter that takes it
// out of every movable family (a length for spherical loops, a twist or an
// offset for planar ones, any of a, alpha, d for Bennett and trivial ones),
// by each relative size (of L for lengths and offsets, of one radian for
// twists); and generic random loops (random_loop).
//
// Every draw comes from the Philox stream keyed by (seed, family and case
// index) (stream_uniform), so case k of a family is the same whatever the
// number of cases asked for, and the same options give the same set bit for
// bit. docs/quality/ground-truth.md describes the set.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "loopfarm/core/loop.hpp"
#include "loopfarm/search/classify.hpp"

namespace loopfarm {

struct GroundTruthOptions {
  std::uint64_t seed = 1;
  // Movable cases per family: Bennett loops (this many in each setup), planar
  // four-bars, spherical 4R loops and trivial coaxial loops.
  int cases_per_family = 8;
  // Generic random loops (rigid, unperturbed).
  int generic_loops = 8;
  // Each movable case is perturbed once by each of these relative sizes
  // (distinct, each in (0, 1)); empty: no perturbed cases.
  std::vector<double> relative_perturbations = {1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8};
  // Length scales L (length_scale) drawn log-uniformly in [min, max];
  // spherical loops have no lengths (L = 1 by convention).
  double min_length_scale = 0.1;
  double max_length_scale = 10.0;
  // [rad] Drawn twists stay this far from 0 and 180 deg, Bennett twist pairs
  // this far from the pairs where the loop turns coaxial (alpha1 = alpha2 in
  // the asymmetric setup, alpha1 + alpha2 = 180 deg in the line-symmetric
  // one), and the spherical diagonal arc this far inside its range (the
  // spherical Grashof condition), at most 10 deg.
  double twist_margin = 5.0 * 3.14159265358979323846 / 180.0;
  // [rad] The input angle of a pose stays this far from 0 and 180 deg, where
  // Bennett loops fold flat; at most 45 deg.
  double pose_margin = 15.0 * 3.14159265358979323846 / 180.0;

  // Throws std::invalid_argument naming the first invalid option.
  void validate() const;
};

// The family a case was generated in; for a perturbed case, its parent's.
enum class GroundTruthFamily { bennett, planar, spherical, trivial, generic };
const char* to_string(GroundTruthFamily family);

struct GroundTruthCase {
  // Stable name: "<family>-<index>" (Bennett: "bennett-<setup>-<index>"),
  // "generic-<index>"; a perturbed case "<parent>-<parameter>-<size>", e.g.
  // "planar-002-alpha1-1e-03".
  std::string id;
  GroundTruthFamily family = GroundTruthFamily::generic;
  BennettSetup setup = BennettSetup::none;  // Bennett cases (and their perturbations)
  bool movable = false;
  // Movable cases: the input (joint 1) turns a full turn (every movable case
  // generated so far does). False for rigid cases.
  bool full_turn = false;
  std::string parent;               // id of the movable case perturbed; empty otherwise
  std::string perturbed_parameter;  // "a1", "alpha2", "d3" (1-based); empty when not perturbed
  // The added amount / L of the parent (lengths, offsets) or / 1 rad (twists);
  // 0 when not perturbed. A spherical parent has no lengths (L = 1), and the
  // one length or offset added becomes the perturbed loop's whole length
  // scale: in units of L every size gives the same loop.
  double relative_perturbation = 0.0;
  LoopGeometry geometry;
  // Joint angles [rad] with the input angle theta0 first. Movable cases: a
  // closed pose (pose_residual at round-off). Perturbed cases: the parent's
  // pose; generic cases: random_angles; neither closes (a start guess).
  JointVector pose;
  // Max-norm of the closure residual at the pose, (log R [rad], p / L).
  double pose_residual = 0.0;
};

// The classification a correct method gives the case: its family for a
// movable case (generic never is), unclassified for a rigid one.
Family expected_classification(const GroundTruthCase& c);

// The whole set: for each family in the order Bennett asymmetric, Bennett
// line-symmetric, planar, spherical, trivial, each movable case followed by
// its perturbations (in the order of relative_perturbations); then the
// generic loops. Throws
// std::invalid_argument for invalid options.
std::vector<GroundTruthCase> generate_ground_truth(const GroundTruthOptions& options = {});

}  // namespace loopfarm
