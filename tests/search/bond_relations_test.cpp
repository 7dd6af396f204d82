// bond_relations against relations known independently: Bennett's closed
// form, Freudenstein's equation of the planar four-bar, the equal opposite
// angles of the line-symmetric Bricard loop, the Moebius joints of loops
// built from Bennett loops (Goldberg's 5R, Waldron's hybrid 6R, on the
// constructions' own motions), a fingerprint that does not depend on the
// labels, and bad input.
#include "loopfarm/search/bond_relations.hpp"

#include <cmath>
#include <limits>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "loopfarm/core/constructions.hpp"
#include "loopfarm/core/sample_loops.hpp"
#include "loopfarm/search/verify.hpp"
#include "test_support.hpp"

namespace loopfarm {
namespace {

using testing::rad;

constexpr double kPi = 3.14159265358979323846;

// The circuit loopfarm verify reports, traced by the rigid closure.
std::vector<JointVector> traced(const LoopGeometry& g) {
  const VerificationSummary v = verify_motion(g, nullptr);
  EXPECT_TRUE(v.verified);
  return v.joint_angles;
}

// Poses of a construction over its motion parameter, t in [lo, hi).
template <class Pose>
std::vector<JointVector> along(Pose pose, double lo, double hi, int count) {
  std::vector<JointVector> poses;
  for (int k = 0; k < count; ++k) poses.push_back(pose(lo + (hi - lo) * k / count));
  return poses;
}

// |<u, v>| / (|u| |v|): 1 when the two are the same relation up to scale.
double alignment(const std::vector<double>& u, const std::vector<double>& v) {
  if (u.size() != v.size()) return 0.0;
  double uv = 0.0, uu = 0.0, vv = 0.0;
  for (size_t k = 0; k < u.size(); ++k) {
    uv += u[k] * v[k];
    uu += u[k] * u[k];
    vv += v[k] * v[k];
  }
  return std::abs(uv) / std::sqrt(uu * vv);
}

void expect_related(const BondSummary& s, int i, int j, int p, int q, const std::string& tag) {
  const BondPair& pair = s.pair(i, j);
  EXPECT_EQ(to_string(pair.status), std::string("related")) << tag << " pair " << i + 1 << "-" << j + 1;
  EXPECT_EQ(pair.p, p) << tag << " pair " << i + 1 << "-" << j + 1;
  EXPECT_EQ(pair.q, q) << tag << " pair " << i + 1 << "-" << j + 1;
  EXPECT_LT(pair.ratio, 1e-11) << tag << " pair " << i + 1 << "-" << j + 1;
  EXPECT_GT(pair.gap, 1e-6) << tag << " pair " << i + 1 << "-" << j + 1;
}

// The coefficients of a product of two homogeneous forms in (s_i, c_i) and
// (s_j, c_j), each given by its coefficients by power of s (u[a] multiplies
// s^a c^(p-a)): the layout of BondPair::coefficients.
std::vector<double> outer(const std::vector<double>& u, const std::vector<double>& v) {
  std::vector<double> out;
  for (const double x : u) {
    for (const double y : v) out.push_back(x * y);
  }
  return out;
}

std::vector<double> plus(std::vector<double> u, const std::vector<double>& v, double scale = 1.0) {
  for (size_t k = 0; k < u.size(); ++k) u[k] += scale * v[k];
  return u;
}

// Bennett loop (a1, alpha1), (a2, alpha2), (a1, alpha1), (a2, alpha2) in the
// asymmetric setup (sin alpha1 / a1 = sin alpha2 / a2). Its joints turn as the
// spherical isogram of the same twists, theta3 = -theta1, theta4 = -theta2, with
// tan(theta1 / 2) tan(theta2 / 2) = K = sin((alpha2 + alpha1) / 2) / sin((alpha2 - alpha1) / 2);
// the signs in this DH convention are checked first by closing the loop at
// poses built from the relation alone. In homogeneous form s1 s2 - K c1 c2 = 0:
// bidegree (1, 1), coefficients (c1 c2, c1 s2, s1 c2, s1 s2) = (-K, 0, 0, 1).
TEST(BondRelations, BennettJointsFollowBennettsClosedForm) {
  const double alpha1 = 0.6, alpha2 = 1.9;
  const LoopGeometry g = bennett_loop(1.3, alpha1, alpha2);
  const double K = std::sin(0.5 * (alpha2 + alpha1)) / std::sin(0.5 * (alpha2 - alpha1));
  for (const double t : {-2.5, -1.0, 0.3, 1.7, 2.9}) {
    const double theta2 = 2.0 * std::atan(K / std::tan(0.5 * t));
    JointVector theta(4);
    theta << t, theta2, -t, -theta2;
    ASSERT_LT(closure_residual(g, theta).lpNorm<Eigen::Infinity>(), 1e-12) << t;
  }

  const std::vector<JointVector> poses = traced(g);
  const BondSummary s = bond_relations(g, poses);
  EXPECT_EQ(s.rows, 125);
  EXPECT_LT(s.worst_closure, 1e-12);
  for (int i = 0; i < 4; ++i) {
    for (int j = i + 1; j < 4; ++j) expect_related(s, i, j, 1, 1, "bennett");
  }
  EXPECT_NEAR(alignment(s.pair(0, 1).coefficients, {-K, 0.0, 0.0, 1.0}), 1.0, 1e-10);
  // theta3 = -theta1: sin((theta1 + theta3) / 2) = s1 c3 + c1 s3 = 0.
  EXPECT_NEAR(alignment(s.pair(0, 2).coefficients, {0.0, 1.0, 1.0, 0.0}), 1.0, 1e-10);
  // theta2 and theta3 = -theta1: -tan(theta3 / 2) tan(theta2 / 2) = K, K c2 c3 + s2 s3 = 0.
  EXPECT_NEAR(alignment(s.pair(1, 2).coefficients, {K, 0.0, 0.0, 1.0}), 1.0, 1e-10);
  EXPECT_EQ(s.fingerprint, "4R/4 11 11 11 11 11 11");

  // The line-symmetric setup: theta3 = theta1, theta4 = theta2 and
  // K = cos((alpha2 + alpha1) / 2) / cos((alpha2 - alpha1) / 2), with the
  // twists as bennett_loop_line_symmetric writes them (alpha2 negated).
  const LoopGeometry h = bennett_loop_line_symmetric(1.3, alpha1, alpha2);
  const double L = std::cos(0.5 * (h.alpha[1] + h.alpha[0])) / std::cos(0.5 * (h.alpha[1] - h.alpha[0]));
  for (const double t : {-2.5, 0.3, 2.9}) {
    const double theta2 = 2.0 * std::atan(L / std::tan(0.5 * t));
    JointVector theta(4);
    theta << t, theta2, t, theta2;
    ASSERT_LT(closure_residual(h, theta).lpNorm<Eigen::Infinity>(), 1e-12) << t;
  }
  const BondSummary l = bond_relations(h, traced(h));
  EXPECT_NEAR(alignment(l.pair(0, 1).coefficients, {-L, 0.0, 0.0, 1.0}), 1.0, 1e-10);
  // theta3 = theta1: sin((theta3 - theta1) / 2) = c1 s3 - s1 c3 = 0.
  EXPECT_NEAR(alignment(l.pair(0, 2).coefficients, {0.0, 1.0, -1.0, 0.0}), 1.0, 1e-10);
  EXPECT_EQ(l.fingerprint, s.fingerprint);
}

// Planar four-bar, links a1 (input, joint 1 to 2), a2 (coupler), a3 (output,
// joint 3 to 4), a4 (ground, joint 4 to 1), twists 0. With phi_k = theta_1 +
// ... + theta_k the direction of link k and phi_4 = 0 (closed), the loop is
// a1 e^(i phi1) + a2 e^(i phi2) + a3 e^(i phi3) + a4 = 0; eliminating the
// coupler (|a2 e^(i phi2)|^2) with phi1 = theta1, phi3 = -theta4 gives
// Freudenstein's equation
//   F = a1^2 + a3^2 + a4^2 - a2^2 + 2 a1 a3 cos(theta1 + theta4)
//       + 2 a1 a4 cos(theta1) + 2 a3 a4 cos(theta4) = 0,
// of bidegree (2, 2) in the half angles (cos = c^2 - s^2, sin = 2 s c, 1 = s^2 + c^2).
// A Grashof crank-rocker's curve has genus 1: no (1, 1), (1, 2) or (2, 1)
// relation (those curves are rational).
TEST(BondRelations, PlanarFourBarInputAndOutputFollowFreudenstein) {
  const double a1 = 1.0, a2 = 3.0, a3 = 2.5, a4 = 3.2;
  const LoopGeometry g = planar_four_bar(a1, a2, a3, a4);
  ASSERT_EQ(planar_four_bar_kind(g, 0), FourBarKind::crank_rocker);
  // One assembly mode over the input's full turn, in closed form.
  const std::vector<JointVector> poses = along([&](double t) { return four_bar_poses(g, 0, t).at(0); }, -kPi, kPi, 400);
  const double k0 = a1 * a1 + a3 * a3 + a4 * a4 - a2 * a2;
  for (const JointVector& theta : poses) {
    const double F = k0 + 2 * a1 * a3 * std::cos(theta[0] + theta[3]) + 2 * a1 * a4 * std::cos(theta[0]) +
                     2 * a3 * a4 * std::cos(theta[3]);
    ASSERT_NEAR(F, 0.0, 1e-12);
  }
  // F's coefficients: forms in (s, c) by power of s.
  const std::vector<double> one{1, 0, 1}, cosine{1, 0, -1}, sine{0, 2, 0};
  std::vector<double> expected = outer(one, one);
  for (double& x : expected) x *= k0;
  expected = plus(expected, outer(cosine, cosine), 2 * a1 * a3);
  expected = plus(expected, outer(sine, sine), -2 * a1 * a3);
  expected = plus(expected, outer(cosine, one), 2 * a1 * a4);
  expected = plus(expected, outer(one, cosine), 2 * a3 * a4);

  const BondSummary s = bond_relations(g, poses);
  expect_related(s, 0, 3, 2, 2, "closed form");
  EXPECT_NEAR(alignment(s.pair(0, 3).coefficients, expected), 1.0, 1e-9);
  // (1, 1), (1, 2) and (2, 1), tried before, are far from holding.
  EXPECT_GT(s.pair(0, 3).closest_rejected, 1e-5);

  // The same from the traced circuit.
  const BondSummary t = bond_relations(g, traced(g));
  expect_related(t, 0, 3, 2, 2, "traced");
  EXPECT_NEAR(alignment(t.pair(0, 3).coefficients, expected), 1.0, 1e-9);
  EXPECT_EQ(t.fingerprint, s.fingerprint);

  // With degrees up to 1 only, no relation.
  BondOptions linear;
  linear.max_degree = 1;
  const BondSummary none = bond_relations(g, poses, linear);
  EXPECT_EQ(none.pair(0, 3).status, BondStatus::none);
  EXPECT_GT(none.pair(0, 3).ratio, 1e-5);
  EXPECT_EQ(none.rows, 20);
}

// Line-symmetric Bricard (docs/guide/families.md's example): a half-turn maps
// joint i onto joint i + 3, so opposite angles are equal, sin((theta_j -
// theta_i) / 2) = c_i s_j - s_i c_j = 0: (1, 1), coefficients (0, 1, -1, 0);
// no other pair is Moebius-related (families.md, "6R from a cubic motion polynomial").
TEST(BondRelations, LineSymmetricBricardHasEqualOppositeAngles) {
  const LoopGeometry g =
      LoopGeometry::from_degrees(std::vector<double>{1, 1.7, 0.8, 1, 1.7, 0.8},
                                 std::vector<double>{51.566, 120.321, -34.377, 51.566, 120.321, -34.377},
                                 std::vector<double>{0.4, 0.3, -0.5, 0.4, 0.3, -0.5});
  const BondSummary s = bond_relations(g, traced(g));
  for (int i = 0; i < 3; ++i) {
    expect_related(s, i, i + 3, 1, 1, "bricard");
    EXPECT_NEAR(alignment(s.pair(i, i + 3).coefficients, {0.0, 1.0, -1.0, 0.0}), 1.0, 1e-10) << i;
  }
  for (const BondPair& p : s.pairs) {
    if (p.j == p.i + 3) continue;
    EXPECT_FALSE(p.status == BondStatus::related && p.p == 1 && p.q == 1) << p.i + 1 << "-" << p.j + 1;
  }
}

// Plane-symmetric Bricard (families.md's example): the mirror maps joint 2
// onto 6 and 3 onto 5, whose angles are opposite; families.md: those two
// pairs are Moebius-related, and no other.
TEST(BondRelations, PlaneSymmetricBricardHasItsMirroredPairsRelated) {
  const LoopGeometry g =
      LoopGeometry::from_degrees(std::vector<double>{1, 1.7, 0.8, 0.8, 1.7, 1},
                                 std::vector<double>{51.566, 120.321, -34.377, 34.377, -120.321, -51.566},
                                 std::vector<double>{0, 0.3, -0.5, 0, 0.5, -0.3});
  const BondSummary s = bond_relations(g, traced(g));
  expect_related(s, 1, 5, 1, 1, "plane-symmetric");
  expect_related(s, 2, 4, 1, 1, "plane-symmetric");
  for (const BondPair& p : s.pairs) {
    if ((p.i == 1 && p.j == 5) || (p.i == 2 && p.j == 4)) continue;
    EXPECT_FALSE(p.status == BondStatus::related && p.p == 1 && p.q == 1) << p.i + 1 << "-" << p.j + 1;
  }
}

// Goldberg's 5R B C D E F from two Bennett loops ABCD and AFED (the
// construction's motion, loop 1's angle t at A): the angles at B, C turn
// with loop 1 and those at E, F with loop 2, each a Moebius function of
// u = tan(t / 2), so those pairs are (1, 1); the angle at D is the
// difference of the two loops' angles there, tan(theta_D / 2) a rational
// function of degree 2 in u. Against a joint whose tangent is Moebius in u
// (so u is rational in it) the relation has degree 1 in D and 2 in the
// other: (2, 1) for B-D and C-D, (1, 2) for D-E and D-F. families.md: joint
// 3 is Moebius-related to no other joint, 6 of 10 pairs are.
TEST(BondRelations, GoldbergJointThreeHasDegreeTwoAgainstTheOthers) {
  const Goldberg5R goldberg{{2.0, kPi / 2, kPi / 6, kPi / 3}, kPi};
  const LoopGeometry g = goldberg_5r(goldberg, 1.0).geometry;
  const std::vector<JointVector> built = along([&](double t) { return goldberg_5r_pose(goldberg, t); }, -kPi, kPi, 360);
  const std::vector<std::pair<std::vector<JointVector>, std::string>> motions{{built, "construction"},
                                                                              {traced(g), "traced"}};
  for (const auto& [poses, tag] : motions) {
    const BondSummary s = bond_relations(g, poses);
    EXPECT_LT(s.worst_closure, 1e-11) << tag;
    const std::vector<std::pair<int, int>> moebius{{0, 1}, {0, 3}, {0, 4}, {1, 3}, {1, 4}, {3, 4}};
    for (const auto& [i, j] : moebius) expect_related(s, i, j, 1, 1, tag);
    expect_related(s, 0, 2, 2, 1, tag);
    expect_related(s, 1, 2, 2, 1, tag);
    expect_related(s, 2, 3, 1, 2, tag);
    expect_related(s, 2, 4, 1, 2, tag);
    // The joint D (3) relabelled last: its pairs read (2, 1) and come last.
    EXPECT_EQ(s.fingerprint, "5R/4 11 11 11 21 11 11 21 11 21 21") << tag;
  }
}

// Waldron's hybrid 6R: every joint turns with one of two Bennett loops whose
// angles at the shared axis differ by a constant, each joint's half-angle
// tangent Moebius in tan(t / 2): all 15 pairs (1, 1) (families.md: 15 of 15).
TEST(BondRelations, WaldronHybridHasEveryPairMoebiusRelated) {
  const WaldronHybrid6R hybrid;
  const LoopGeometry g = waldron_hybrid_6r(hybrid, 1.0).geometry;
  const std::vector<JointVector> poses =
      along([&](double t) { return waldron_hybrid_6r(hybrid, t).theta; }, -kPi, kPi, 360);
  const BondSummary s = bond_relations(g, poses);
  EXPECT_LT(s.worst_closure, 1e-10);
  for (const BondPair& p : s.pairs) expect_related(s, p.i, p.j, 1, 1, "waldron");
  EXPECT_EQ(s.fingerprint, "6R/4 11 11 11 11 11 11 11 11 11 11 11 11 11 11 11");
}

// The table in new labels: new joint k is old joint (shift + k) mod n, or
// (shift - k) mod n reversed; a pair whose joints change order reads (q, p).
TEST(BondRelations, TheFingerprintIsTheSameInEveryLabelling) {
  const Goldberg5R goldberg{{1.5, 1.2, 0.7, -2.3}, kPi};
  const LoopGeometry g = goldberg_5r(goldberg, 1.0).geometry;
  const BondSummary original = bond_relations(g, traced(g));
  const int n = 5;
  std::set<std::string> fingerprints;
  for (int reverse = 0; reverse < 2; ++reverse) {
    for (int shift = 0; shift < n; ++shift) {
      LoopGeometry h = relabelled(g, shift);
      if (reverse) h = reversed(h);
      const BondSummary s = bond_relations(h, traced(h));
      fingerprints.insert(s.fingerprint);
      auto old_joint = [&](int k) { return reverse ? (shift + n - 1 - k) % n : (shift + k) % n; };
      for (const BondPair& p : s.pairs) {
        const int oi = old_joint(p.i), oj = old_joint(p.j);
        const BondPair& o = original.pair(oi, oj);
        const std::string tag = "shift " + std::to_string(shift) + (reverse ? " reversed" : "") + " pair " +
                                std::to_string(p.i + 1) + "-" + std::to_string(p.j + 1);
        EXPECT_EQ(p.status, o.status) << tag;
        EXPECT_EQ(p.p, oi < oj ? o.p : o.q) << tag;
        EXPECT_EQ(p.q, oi < oj ? o.q : o.p) << tag;
      }
    }
  }
  EXPECT_EQ(fingerprints, std::set<std::string>{original.fingerprint});
  EXPECT_NE(original.fingerprint.find("21"), std::string::npos) << original.fingerprint;
}

// A table written by hand: one adjacent pair (1, 2), the rest (1, 1). Its
// least reading puts the pair last, as (2, 3) in the orientation (1, 2).
TEST(BondRelations, TheFingerprintIsTheLeastReading) {
  std::vector<BondPair> pairs;
  for (int i = 0; i < 4; ++i) {
    for (int j = i + 1; j < 4; ++j) {
      BondPair p;
      p.i = i;
      p.j = j;
      p.status = BondStatus::related;
      p.p = 1;
      p.q = (i == 0 && j == 1) ? 2 : 1;
      pairs.push_back(p);
    }
  }
  EXPECT_EQ(bond_fingerprint(4, 4, pairs), "4R/4 11 11 11 11 11 12");
  pairs[0].p = 2;
  pairs[0].q = 1;
  EXPECT_EQ(bond_fingerprint(4, 4, pairs), "4R/4 11 11 11 11 11 12");
  EXPECT_THROW(bond_fingerprint(4, 4, std::span<const BondPair>(pairs).first(5)), std::invalid_argument);
}

// Two families, two fingerprints: the line-symmetric Bricard loop, Waldron's
// hybrid and a bennett_dyads loop (families.md's example, of which no pair is
// Moebius-related).
TEST(BondRelations, DifferentFamiliesHaveDifferentFingerprints) {
  const LoopGeometry bricard =
      LoopGeometry::from_degrees(std::vector<double>{1, 1.7, 0.8, 1, 1.7, 0.8},
                                 std::vector<double>{51.566, 120.321, -34.377, 51.566, 120.321, -34.377},
                                 std::vector<double>{0.4, 0.3, -0.5, 0.4, 0.3, -0.5});
  const LoopGeometry dyads =
      LoopGeometry::from_degrees(std::vector<double>{0.29105928100629913, 0.3266234112565141, 1.1155627045785708,
                                                     2.0724378472248963, 2.112627142478364, 1.1155627045785708},
                                 std::vector<double>{-160.21822699133264, -157.67920498998612, -40.123422809296045,
                                                     -112.41458911002134, -109.54549378379366, -40.123422809296045},
                                 std::vector<double>{-0.29099955783023707, 0, -0.29099955783023707,
                                                     0.017028759702287233, 0, 0.017028759702287233});
  const LoopGeometry waldron = waldron_hybrid_6r(WaldronHybrid6R{}, 1.0).geometry;
  const BondSummary b = bond_relations(bricard, traced(bricard));
  const BondSummary d = bond_relations(dyads, traced(dyads));
  const BondSummary w = bond_relations(waldron, traced(waldron));
  EXPECT_NE(b.fingerprint, d.fingerprint);
  EXPECT_NE(b.fingerprint, w.fingerprint);
  EXPECT_NE(d.fingerprint, w.fingerprint);
  for (const BondPair& p : d.pairs) {
    EXPECT_FALSE(p.status == BondStatus::related && p.p == 1 && p.q == 1) << p.i + 1 << "-" << p.j + 1;
  }
}

// A joint that barely moves (travel 6e-6 rad, above frozen_travel): its own
// half-angle forms of degree 2 nearly vanish on its poses (by about the
// square of its travel), so at bidegree (1, 2) against it the matrix has two
// near-null vectors (joint 1's two linear forms times that one): ambiguous,
// never related. A joint that does not move (1e-8 rad) is frozen.
TEST(BondRelations, ANearlyStillJointIsAmbiguousAndAStillOneFrozen) {
  const LoopGeometry g = random_loop(4, 3);
  std::vector<JointVector> poses;
  for (int k = 0; k < 200; ++k) {
    const double t = 2.0 * kPi * k / 200;
    JointVector theta(4);
    theta << t, 0.3 + 3e-6 * std::sin(t), 0.7 + 1e-8 * std::cos(t), t + 1.0;
    poses.push_back(theta);
  }
  const BondSummary s = bond_relations(g, poses);
  EXPECT_FALSE(s.frozen[1]);
  EXPECT_TRUE(s.frozen[2]);
  EXPECT_NEAR(s.travel[1], 6e-6, 1e-8);
  EXPECT_EQ(s.pair(0, 1).status, BondStatus::ambiguous);
  EXPECT_EQ(s.pair(0, 1).p, 1);
  EXPECT_EQ(s.pair(0, 1).q, 2);
  EXPECT_LE(s.pair(0, 1).gap, s.tolerance);
  EXPECT_EQ(s.pair(0, 2).status, BondStatus::frozen);
  EXPECT_EQ(s.pair(2, 3).status, BondStatus::frozen);
  EXPECT_TRUE(std::isnan(s.pair(2, 3).ratio));
  // Joint 4 turns with joint 1 at a constant difference: (1, 1).
  EXPECT_EQ(s.pair(0, 3).status, BondStatus::related);
  EXPECT_EQ(s.pair(0, 3).p + s.pair(0, 3).q, 2);
  EXPECT_NE(s.fingerprint.find('f'), std::string::npos);
  EXPECT_NE(s.fingerprint.find('?'), std::string::npos);
  EXPECT_GT(s.worst_closure, 1e-3);  // made-up poses do not close, and the summary says so
}

TEST(BondRelations, PosesAreUsedAsGivenWhenFewerThanTheRowsWanted) {
  const LoopGeometry g = bennett_loop(1.3, 0.6, 1.9);
  const std::vector<JointVector> poses = along([&](double t) { return bennett_angles(g, t); }, -kPi, kPi, 90);
  const BondSummary s = bond_relations(g, poses);
  EXPECT_EQ(s.poses, 90);
  EXPECT_EQ(s.rows, 90);
  BondOptions few;
  few.rows = 75;
  EXPECT_EQ(bond_relations(g, poses, few).rows, 75);
}

TEST(BondRelations, BadInputThrowsNamingWhatIsWrong) {
  const LoopGeometry g = bennett_loop(1.3, 0.6, 1.9);
  const std::vector<JointVector> poses = along([&](double t) { return bennett_angles(g, t); }, -kPi, kPi, 200);
  auto message = [&](const std::vector<JointVector>& p, const BondOptions& o, const LoopGeometry& geometry) {
    try {
      (void)bond_relations(geometry, p, o);
    } catch (const std::invalid_argument& error) {
      return std::string(error.what());
    }
    return std::string("(no exception)");
  };
  BondOptions o;
  o.max_degree = 0;
  EXPECT_NE(message(poses, o, g).find("max_degree is 0"), std::string::npos);
  o.max_degree = 9;
  EXPECT_NE(message(poses, o, g).find("max_degree is 9"), std::string::npos);
  o = {};
  for (const double tolerance : {0.0, 1.0, -1e-9, std::numeric_limits<double>::quiet_NaN()}) {
    o.tolerance = tolerance;
    EXPECT_NE(message(poses, o, g).find("tolerance"), std::string::npos) << tolerance;
  }
  o = {};
  o.frozen_travel = -1.0;
  EXPECT_NE(message(poses, o, g).find("frozen_travel"), std::string::npos);
  o = {};
  o.rows = 74;
  EXPECT_NE(message(poses, o, g).find("rows is 74"), std::string::npos);
  o = {};
  EXPECT_NE(message(std::vector<JointVector>(poses.begin(), poses.begin() + 74), o, g).find("74 poses"),
            std::string::npos);
  std::vector<JointVector> bad = poses;
  bad[3] = JointVector::Zero(5);
  EXPECT_NE(message(bad, o, g).find("pose 3 has 5 angles for 4 joints"), std::string::npos);
  bad = poses;
  bad[7][2] = std::numeric_limits<double>::infinity();
  EXPECT_NE(message(bad, o, g).find("pose 7"), std::string::npos);
  LoopGeometry three = g;
  three.a.conservativeResize(3);
  EXPECT_THROW(bond_relations(three, poses), std::invalid_argument);
  EXPECT_THROW((void)bond_relations(g, poses).pair(0, 7), std::out_of_range);
}

}  // namespace
}  // namespace loopfarm
