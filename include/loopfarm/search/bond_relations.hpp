// Polynomial relations between the joint angles of a movable loop along one
// circuit of its motion: for every pair of joints (i < j), the smallest
// bidegree (p, q) of a nonzero polynomial P with
//
//     P(tan(theta_i / 2), tan(theta_j / 2)) = 0     at every pose of the circuit,
//
// p the degree in joint i's half-angle tangent, q in joint j's. Two joints
// whose half-angle tangents are related by a Moebius map have bidegree (1, 1)
// (every pair of a Bennett loop; opposite joints of a line-symmetric Bricard
// loop); the input and output of a generic planar four-bar have (2, 2)
// (Freudenstein's equation). In the theory of bonds (Hegedues, Schicho,
// Schroecker 2013) such degrees are what tells linkages apart; here they are
// measured on a traced motion, as a fingerprint of a loop that fits no known
// family (docs/guide/bonds.md).
//
// Numerically, in homogeneous form so that tan = infinity needs no care:
// with s = sin(theta / 2), c = cos(theta / 2) the relation is
//
//     sum_{a, b} P_ab  s_i^a c_i^(p - a)  s_j^b c_j^(q - b) = 0,
//
// one row per pose (poses spread evenly along the circuit's arclength), one
// column per monomial, column a (q + 1) + b; a relation exists when the
// matrix's smallest singular value over its largest is at most the
// tolerance, and its right singular vector is P. A relation of bidegree
// (p, q) gives one of every larger bidegree (times s^2 + c^2 = 1), so the
// candidates are tried from the smallest: by p + q, then by max(p, q), then
// by p, every p, q in [1, max_degree]. The closed poses of a circuit map onto
// an irreducible curve of the torus of the two angles, so the relations of the
// smallest bidegree are one polynomial up to scale: the next singular value
// (the gap) is well above the tolerance for a clean relation, and a second
// near-zero one says that the pair's relation cannot be told (a joint that
// barely moves, too few or badly spread poses).
//
// The fingerprint is the table of bidegrees written in the labels for which
// it reads least, over the 2n relabellings of the loop (cyclic shifts and the
// reversal: the dihedral group of the n-gon); axis flips change no degree. So
// loops of one family share it whatever their labels.
#pragma once

#include <span>
#include <string>
#include <vector>

#include "loopfarm/core/loop.hpp"

namespace loopfarm {

struct BondOptions {
  // The largest degree tried in either joint: candidates (p, q) with
  // 1 <= p, q <= max_degree. At most 8.
  int max_degree = 4;
  // A relation: smallest singular value / largest <= tolerance. Relations on
  // the traced motions of exact geometries read 1e-16 ... 3e-12, on stored
  // (17-digit) ones up to about 1e-9; smaller bidegrees that do not hold read
  // 2e-6 and more where every joint travels 90 deg or more, less where
  // joints only rock (docs/guide/bonds.md).
  double tolerance = 1e-9;
  // [rad] A joint whose travel over the poses (max - min of its unwrapped
  // angle) is below this is frozen: its pairs are not fitted.
  double frozen_travel = 1e-6;
  // Poses used as rows, spread by arclength; 0: 5 (max_degree + 1)^2 (125
  // for degree 4). At least 3 (max_degree + 1)^2, three times the columns of
  // the largest candidate. When fewer poses are given, all of them are used.
  int rows = 0;

  // The rows asked for (`rows`, or its default for max_degree).
  int wanted_rows() const;
  // The fewest poses a call accepts: 3 (max_degree + 1)^2.
  int minimum_rows() const;
  // Throws std::invalid_argument naming the first invalid option and its value.
  void validate() const;
};

enum class BondStatus {
  related,    // a relation of bidegree (p, q), and no second one there
  ambiguous,  // more than one independent relation at the smallest bidegree: not told (docs/guide/bonds.md)
  none,       // no relation up to max_degree in either joint
  frozen,     // joint i or j does not move: not fitted
};
const char* to_string(BondStatus status);

struct BondPair {
  int i = 0;  // joints, 0-based, i < j
  int j = 0;
  BondStatus status = BondStatus::none;
  int p = 0;  // the bidegree (related, ambiguous): degree in joint i's half-angle tangent
  int q = 0;  // and in joint j's; 0 for none and frozen
  // Smallest singular value / largest at (p, q); for `none` at (max_degree,
  // max_degree), the largest candidate. NaN for frozen.
  double ratio = 0.0;
  // The next singular value / largest there: how clearly the relation is one.
  double gap = 0.0;
  // The least ratio among the candidates tried before (p, q), or among all
  // for `none`: how near a smaller bidegree came. NaN when none was tried.
  double closest_rejected = 0.0;
  // P's coefficients (related, ambiguous): unit norm, largest component
  // positive; coefficient a (q + 1) + b multiplies s_i^a c_i^(p-a) s_j^b c_j^(q-b).
  std::vector<double> coefficients;
};

struct BondSummary {
  int joints = 0;
  int max_degree = 0;
  double tolerance = 0.0;
  int poses = 0;  // poses given
  int rows = 0;   // poses used, spread by arclength
  // Largest closure residual over the rows used (max-norm, lengths over L):
  // round-off for poses on a motion.
  double worst_closure = 0.0;
  std::vector<double> travel;   // per joint [rad]: max - min over the poses
  std::vector<bool> frozen;     // per joint: travel < frozen_travel
  std::vector<BondPair> pairs;  // (0, 1), (0, 2), ..., (0, n-1), (1, 2), ..., (n-2, n-1)
  // The table of bidegrees in the relabelling that reads least (header).
  std::string fingerprint;
  double seconds = 0.0;  // wall time of the call

  // The pair (i, j) in either order; throws std::out_of_range for no such pair.
  const BondPair& pair(int i, int j) const;
};

// The relations along `poses`, closed poses of `geometry` in order along one
// circuit (VerificationSummary::joint_angles, Circuit::points), angles
// unwrapped or not. Throws std::invalid_argument for a geometry
// validate_geometry rejects, invalid options, a pose of the wrong size or
// with a non-finite angle, or fewer poses than options.minimum_rows().
BondSummary bond_relations(const LoopGeometry& geometry, std::span<const JointVector> poses,
                           const BondOptions& options = {});

// The fingerprint of a table (BondSummary::fingerprint): "<n>R/<max_degree>"
// then one entry per pair in the order of BondSummary::pairs, for the
// relabelling of the joints (cyclic shifts, reversal) whose string is least.
// An entry is "pq" for a relation of bidegree (p, q) ("11", "21"), "pq?" for
// an ambiguous one, "-" for none up to max_degree, "f" for a frozen joint.
// Under a relabelling a pair whose joints change order reads (q, p).
std::string bond_fingerprint(int joints, int max_degree, std::span<const BondPair> pairs);

}  // namespace loopfarm
