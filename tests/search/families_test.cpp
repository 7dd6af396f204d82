// Property tests of the 5R and 6R families (docs/guide/families.md): members built
// from random parameters by each family's construction, each one checked
// movable by the rigid closure along a motion (verify_motion, which shares
// nothing with the classifier) and classified as its family in any representation;
// near-misses (one parameter moved by 1e-3 ... 1e-6) checked rigid and not
// classified as the family.
//
// The constructions are geometric where the family is defined by one: a
// Goldberg 5R is assembled from two Bennett loops placed in space (their
// closed-form poses, sample_loops.hpp), its DH parameters read off the joint
// axes (constructions.hpp's goldberg_5r and dh_from_axes), so the
// classifier's closed-form conditions are checked against the construction,
// not against themselves. Bricard loops are built
// from their DH conditions and closed by a Levenberg-Marquardt solve of the
// rigid closure from random guesses (a generic 6R with its input held cannot
// be assembled at all, so a closed pose already says the loop is special).
#include "family_members.hpp"

namespace loopfarm::family_tests {
namespace {

// ---------------------------------------------------------------------------
// 5R

TEST(Families, GoldbergFromTwoBennettLoopsMovesAndIsGoldbergInBothFusions) {
  std::mt19937_64 rng(11);
  for (int i = 0; i < 8; ++i) {
    // Both fusions: the collinear links on opposite sides (phi = pi) and on
    // the same side (phi = 0); the loops' setups are random.
    const double phi = i % 2 == 0 ? kPi : 0.0;
    const Posed m = goldberg_member(rng, phi);
    const std::string tag = "goldberg " + std::to_string(i);
    // Offsets zero, links 1 and 4 equal, as the construction promises.
    EXPECT_LT(m.geometry.d.cwiseAbs().maxCoeff(), 1e-12) << tag;
    expect_movable_member(m, Family::goldberg, rng, tag);
    // Goldberg's collinear fusion is the bent family at phi = 0 or pi.
    for (const FamilyCheck& check : classify(m.geometry, m.theta, std::vector<double>(5, 2 * kPi)).checks) {
      if (check.family == Family::goldberg_bent) {
        EXPECT_LT(check.residual, 1e-10) << tag;
      }
    }
    // a1, alpha2, d3, a5, alpha5 in turn.
    const std::array<int, 5> parameters = {0, 5 + 1, 10 + 2, 4, 5 + 4};
    expect_near_misses_rigid(m, Family::goldberg, parameters[static_cast<size_t>(i) % parameters.size()], tag);
  }
}

TEST(Families, GoldbergReportsWhichSideTheFusedLinksAreOn) {
  std::mt19937_64 rng(12);
  const Posed opposite = goldberg_member(rng, kPi), same = goldberg_member(rng, 0.0);
  const std::vector<double> moving(5, 2 * kPi);
  EXPECT_NE(classify(opposite.geometry, opposite.theta, moving).detail.find("opposite sides"), std::string::npos);
  EXPECT_NE(classify(same.geometry, same.theta, moving).detail.find("same side"), std::string::npos);
}

// A fusion angle away from 0 and pi (either sign).
double bent_angle(std::mt19937_64& rng) {
  const double phi = uniform(rng, 0.2, kPi - 0.2);
  return uniform(rng, 0.0, 1.0) < 0.5 ? phi : -phi;
}

TEST(Families, BentGoldbergMovesAndIsGoldbergBentAtAnyFusionAngle) {
  // Fused at an angle phi other than 0 or pi the construction still moves
  // (two Bennett loops turning about the common link DA), with offsets d1 =
  // +-d5 != 0 at the fused link: + when the two Bennett loops are in the
  // same setup, - otherwise. The conditions of goldberg_bent (the dual-angle
  // cosine rule of the fused link with phi eliminated) are checked against
  // that construction, which reads the DH parameters off the axes.
  std::mt19937_64 rng(13);
  int same = 0, different = 0;
  for (int i = 0; i < 10; ++i) {
    const double phi = bent_angle(rng);
    const Posed m = goldberg_member(rng, phi);
    const std::string tag = "goldberg_bent " + std::to_string(i) + " phi " + std::to_string(phi);
    EXPECT_GT(std::abs(m.geometry.d[0]), 1e-3) << tag;
    EXPECT_LT(m.geometry.d.segment(1, 3).cwiseAbs().maxCoeff(), 1e-12) << tag;
    // Links 2 and 3 are (a, alpha) and (c, gamma): their Bennett loops'
    // setups are the signs of sin(alpha)/a and sin(gamma)/c against sin(beta)/b.
    const bool same_setup = std::sin(m.geometry.alpha[1]) * std::sin(m.geometry.alpha[2]) > 0.0;
    (same_setup ? same : different) += 1;
    EXPECT_NEAR(m.geometry.d[0], same_setup ? m.geometry.d[4] : -m.geometry.d[4], 1e-12) << tag;
    expect_movable_member(m, Family::goldberg_bent, rng, tag);
    // The detail names the fusion angle: |phi| in degrees, to its 4 digits.
    const Classification c = classify(m.geometry, m.theta, std::vector<double>(5, 2 * kPi));
    const size_t at = c.detail.find("fused at ");
    ASSERT_NE(at, std::string::npos) << c.detail;
    EXPECT_NEAR(std::stod(c.detail.substr(at + 9)), std::abs(phi) * 180.0 / kPi, 0.05) << c.detail;
    // a1, alpha2, d3, a5, alpha5, d5, d1, a2 in turn: every one leaves the family.
    const std::array<int, 8> parameters = {0, 5 + 1, 10 + 2, 4, 5 + 4, 10 + 4, 10 + 0, 1};
    expect_near_misses_rigid(m, Family::goldberg_bent, parameters[static_cast<size_t>(i) % parameters.size()], tag);
  }
  EXPECT_GT(same, 0);
  EXPECT_GT(different, 0);
}

TEST(Families, BentGoldbergNearTheStraightFusionIsStillMovableAndClassified) {
  // Small fusion angles: offsets of order phi, the conditions still at
  // round-off (the squared offset condition is smooth at phi = 0).
  std::mt19937_64 rng(16);
  for (double phi : {1e-3, -2e-2, kPi - 1e-2}) {
    const Posed m = goldberg_member(rng, phi);
    const std::string tag = "phi " + std::to_string(phi);
    expect_movable_member(m, Family::goldberg_bent, rng, tag);
  }
}

TEST(Families, RigidFiveBarsWithBentGoldbergOffsetsAreNotClassified) {
  // A member's offsets swapped in sign (d1 = -d5 where the setups want
  // d1 = d5) or doubled: rigid, and not goldberg_bent.
  std::mt19937_64 rng(17);
  for (int i = 0; i < 4; ++i) {
    const Posed m = goldberg_member(rng, bent_angle(rng));
    for (int variant = 0; variant < 2; ++variant) {
      LoopGeometry g = m.geometry;
      if (variant == 0) {
        g.d[4] = -g.d[4];
      } else {
        g.d[0] *= 2.0;
        g.d[4] *= 2.0;
      }
      const VerificationSummary v = verify_from(g, m.theta);
      EXPECT_FALSE(v.verified) << i << " " << variant;
      const Classification c = classified({g, m.theta}, v);
      EXPECT_NE(c.family, Family::goldberg_bent) << i << " " << variant;
      for (const FamilyCheck& check : c.checks) {
        if (check.family == Family::goldberg_bent) {
          EXPECT_GT(check.residual, 1e-3) << i << " " << variant;
        }
      }
    }
  }
}

TEST(Families, MyardIsThePlaneSymmetricGoldberg) {
  std::mt19937_64 rng(14);
  for (int i = 0; i < 6; ++i) {
    const double phi = i % 2 == 0 ? kPi : 0.0;
    const Posed m = myard_member(rng, phi);
    const std::string tag = "myard " + std::to_string(i);
    expect_movable_member(m, Family::myard, rng, tag);
    // It is a Goldberg loop too (the more special family is reported).
    const std::vector<double> moving(5, 2 * kPi);
    const Classification c = classify(m.geometry, m.theta, moving);
    for (const FamilyCheck& check : c.checks) {
      if (check.family == Family::goldberg) {
        EXPECT_LT(check.residual, 1e-10) << tag;
      }
    }
    // Off the symmetry but on Goldberg: a general Goldberg loop is not Myard.
    const std::array<int, 3> parameters = {1, 5 + 0, 5 + 1};  // a2, alpha1, alpha2
    expect_near_misses_rigid(m, Family::myard, parameters[static_cast<size_t>(i) % parameters.size()], tag);
  }
}

TEST(Families, BennettWithAnIdleJointIsDegenerate) {
  std::mt19937_64 rng(15);
  for (int i = 0; i < 6; ++i) {
    const Posed m = with_idle_joint(random_bennett_member(rng), rng);
    const std::string tag = "degenerate 5R " + std::to_string(i);
    expect_movable_member(m, Family::degenerate, rng, tag);
    const Classification c = classify(m.geometry, m.theta, std::vector<double>(5, 2 * kPi));
    EXPECT_NE(c.detail.find("merged 4R: bennett"), std::string::npos) << c.detail;
    // Off Bennett, the merged 4R is rigid: what is left is the idle spin of
    // the coaxial pair alone, the other joints frozen (trivial), or nothing.
    for (double eps : kNearMisses) {
      const LoopGeometry off = perturbed(m.geometry, 2, eps);  // a3, a Bennett link
      const VerificationSummary v = verify_from(off, m.theta);
      const Classification k = classified({off, m.theta}, v);
      EXPECT_NE(k.family, Family::degenerate) << tag << " " << eps;
      if (v.verified) {
        EXPECT_EQ(k.family, Family::trivial) << tag << " " << eps << " " << k.detail;
      }
    }
  }
}

// Both degenerate rules fit a Bennett loop with an idle joint whose pair of
// axes is 1e-10 rad from coaxial (within the tolerance), posed with the idle
// joint at 0, where it closes exactly: the coaxial pair, tried first,
// decides, at a residual of 1e-10. Told that joint 2 rocks, the locked-joint
// rule reads the exact Bennett loop, to round-off. The degenerate check shown
// is the rule that decided, with the residual reported.
TEST(Families, TheDegenerateCheckShownIsTheRuleThatDecided) {
  std::mt19937_64 rng(43);
  const double tilt = 1e-10;
  for (int i = 0; i < 4; ++i) {
    const Posed q = random_bennett_member(rng);
    const LoopGeometry& b = q.geometry;
    Posed m;
    m.geometry = make_loop({0.0, b.a[0], b.a[1], b.a[2], b.a[3]},
                           {tilt, b.alpha[0] - tilt, b.alpha[1], b.alpha[2], b.alpha[3]}, {0, 0, 0, 0, 0});
    m.theta = (JointVector(5) << q.theta[0], 0.0, q.theta[1], q.theta[2], q.theta[3]).finished();
    const std::string tag = "tilted idle joint " + std::to_string(i);
    ASSERT_LT(closure_error(m), 1e-12) << tag;
    const std::vector<double> travel = {2 * kPi, 1e-4, 2 * kPi, 2 * kPi, 2 * kPi};  // joint 2 rocks
    const Classification c = classify(m.geometry, m.theta, travel);
    EXPECT_EQ(c.family, Family::degenerate) << tag << ": " << c.detail;
    EXPECT_NE(c.detail.find("axes 1 and 2 coincide; merged 4R: bennett"), std::string::npos) << tag << ": " << c.detail;
    EXPECT_GT(c.residual, 0.5 * tilt) << tag;
    EXPECT_LE(c.residual, ClassifyOptions{}.tolerance) << tag;
    int shown = 0;
    for (const FamilyCheck& check : c.checks) {
      if (check.family != Family::degenerate) continue;
      ++shown;
      EXPECT_EQ(check.residual, c.residual) << tag;
      ASSERT_FALSE(check.conditions.empty()) << tag;
      EXPECT_EQ(check.conditions.front().name, "a1 / L") << tag;
    }
    EXPECT_EQ(shown, 1) << tag;
  }
}

TEST(Families, ALockedJointOnABennettLoopIsADegenerate5R) {
  // The 5R moves as the Bennett loop with the extra joint locked: verified
  // (rigid closure, every joint free), that joint frozen, and classified
  // degenerate with the locked 4R a Bennett loop; off Bennett it is rigid.
  std::mt19937_64 rng(18);
  for (int i = 0; i < 6; ++i) {
    const int k = i % 4;
    const Posed m = with_locked_joint(random_bennett_member(rng), k, rng);
    const std::string tag = "locked " + std::to_string(i);
    const VerificationSummary v = verify_from(m.geometry, m.theta);
    ASSERT_TRUE(v.verified) << tag << ": " << v.limit;
    EXPECT_LT(v.joint_travel[k + 1], 1e-9) << tag;
    expect_movable_member(m, Family::degenerate, rng, tag, {k + 1});
    const Classification c = classified(m, v);
    EXPECT_NE(c.detail.find("joint " + std::to_string(k + 2) + " locked"), std::string::npos) << c.detail;
    EXPECT_NE(c.detail.find("locked 4R: bennett"), std::string::npos) << c.detail;
    // A Bennett link off by eps: the locked 4R is no Bennett loop, the 5R is rigid.
    const int bennett_link = k == 0 ? 2 : 0;  // a link the extra joint did not split
    expect_near_misses_rigid(m, Family::degenerate, bennett_link, tag);
  }
}

TEST(Families, AJointThatRocksNearALockedBennettLoopIsLockedOnlyWithinTolerance) {
  // The searches' near-misses of a locked-joint Bennett loop close along the
  // walk with the locked joint rocking by 1e-6 ... 1e-4 rad, above
  // frozen_travel (docs/research/discovery-5r-6r.md, "The rocking joint"). Up to
  // rocking_travel such a joint is locked for the rule, and the 4R left still
  // decides: exact members pass, a Bennett link off by eps does not, and a
  // joint that turns more than rocking_travel is never locked.
  std::mt19937_64 rng(29);
  const ClassifyOptions defaults;
  for (int i = 0; i < 6; ++i) {
    const int k = i % 4;
    const Posed bennett4 = random_bennett_member(rng);
    const Posed m = with_locked_joint(bennett4, k, rng);
    const std::string tag = "rocking " + std::to_string(i);
    // The rigid walk (independent of classify): the extra joint is frozen.
    const VerificationSummary v = verify_from(m.geometry, m.theta);
    ASSERT_TRUE(v.verified) << tag << ": " << v.limit;
    ASSERT_LT(v.joint_travel[k + 1], 1e-9) << tag;
    std::vector<double> travel(v.joint_travel.data(), v.joint_travel.data() + 5);
    for (double rock : {3e-6, 1e-4, 0.9 * defaults.rocking_travel}) {
      travel[static_cast<size_t>(k + 1)] = rock;
      const Classification c = classify(m.geometry, m.theta, travel);
      EXPECT_EQ(c.family, Family::degenerate) << tag << " " << rock << ": " << c.detail;
      EXPECT_NE(c.detail.find("joint " + std::to_string(k + 2) + " nearly locked"), std::string::npos) << c.detail;
      EXPECT_NE(c.detail.find("locked 4R: bennett"), std::string::npos) << c.detail;
      EXPECT_LT(c.residual, 1e-10) << tag;
      // Without the allowance (rocking_travel at frozen_travel) it is not locked.
      ClassifyOptions strict;
      strict.rocking_travel = strict.frozen_travel;
      EXPECT_EQ(classify(m.geometry, m.theta, travel, strict).family, Family::unclassified) << tag << " " << rock;
      // The pose taken where the joint has rocked away by half its travel: the
      // 4R locked at the pose's angle has offsets of that order, but the joint's
      // angle over the motion lies within its travel of the pose's, and locked
      // at the best angle of that window it is the Bennett loop again. Two
      // travels away the window misses the locked angle: not degenerate.
      JointVector off = m.theta;
      off[k + 1] += 0.5 * rock;
      const Classification shifted = classify(m.geometry, off, travel);
      EXPECT_EQ(shifted.family, Family::degenerate) << tag << " " << rock << ": " << shifted.detail;
      EXPECT_LT(shifted.residual, 1e-10) << tag << " " << rock;
      off[k + 1] = m.theta[k + 1] + 2.0 * rock;
      EXPECT_NE(classify(m.geometry, off, travel).family, Family::degenerate) << tag << " " << rock;
    }
    // A joint that turns more than rocking_travel moves: not locked.
    travel[static_cast<size_t>(k + 1)] = 2.0 * defaults.rocking_travel;
    EXPECT_EQ(classify(m.geometry, m.theta, travel).family, Family::unclassified) << tag;
    // Near-misses: a Bennett link of the 4R off by eps L, the joint rocking by
    // 1e-4 rad. Not degenerate at the tolerance. With the joint frozen (no
    // window), the locked 4R's residual that classify reads off the 5R's axes
    // (link_between) equals the Bennett residual of the test's own 4R
    // perturbed alike, a second method; rocking, the window's best angle can
    // only lower it.
    const int link5 = k == 0 ? 2 : 0;  // a 5R link the extra joint did not split
    const int link4 = k == 0 ? 1 : 0;  // the same link in the 4R
    auto locked_residual = [](const Classification& c) {
      for (const FamilyCheck& check : c.checks) {
        if (check.family == Family::degenerate && check.conditions.size() == 2) return check.conditions[1].residual;
      }
      return -1.0;
    };
    for (double eps : {1e-7, 1e-6, 1e-5}) {
      Posed near = m;
      near.geometry.a[link5] += eps * length_scale(m.geometry);
      Posed near4 = bennett4;
      near4.geometry.a[link4] += eps * length_scale(m.geometry);
      const double own = classify(near4.geometry, near4.theta, std::span<const double>()).checks.front().residual;
      EXPECT_GT(own, 0.1 * eps) << tag;
      travel[static_cast<size_t>(k + 1)] = 0.5 * defaults.frozen_travel;
      const Classification frozen = classify(near.geometry, near.theta, travel);
      EXPECT_NE(frozen.family, Family::degenerate) << tag << " " << eps << ": " << frozen.detail;
      EXPECT_NEAR(locked_residual(frozen), own, 1e-6 * own) << tag << " " << eps;
      travel[static_cast<size_t>(k + 1)] = 1e-4;
      const Classification c = classify(near.geometry, near.theta, travel);
      EXPECT_NE(c.family, Family::degenerate) << tag << " " << eps << ": " << c.detail;
      EXPECT_LE(locked_residual(c), own * (1.0 + 1e-6)) << tag << " " << eps;
      EXPECT_GT(locked_residual(c), defaults.tolerance) << tag << " " << eps;
      // On a loose pass whose tolerance covers it (analyse_candidate's second
      // pass), it is labelled with that nearest description.
      ClassifyOptions loose;
      loose.tolerance = 2.0 * own;  // at least the rocking residual
      EXPECT_EQ(classify(near.geometry, near.theta, travel, loose).family, Family::degenerate) << tag << " " << eps;
    }
  }
}

TEST(Families, GoldbergOnAnEquilateralBennettLoopMovesWithALockedJoint) {
  // docs/research/discovery-5r-6r.md: Goldberg's conditions with the second Bennett
  // loop equilateral, (c, gamma) = (b, beta): links (b, beta), (a, alpha),
  // (b, beta), (b, beta), (a + b, alpha + beta). Bennett's condition holds for
  // the equilateral loop whatever b and beta, but such a loop only folds; the
  // 5R moves with joint 5 locked (the search's loops, in its labels joint 3).
  // It is classified degenerate (the locked 4R a Bennett loop), although its
  // geometry is Goldberg's.
  std::mt19937_64 rng(19);
  int moving = 0;
  for (int i = 0; i < 6; ++i) {
    const double a = uniform(rng, 0.5, 2.0), alpha = twist(rng), beta = twist(rng);
    const double b = a * std::abs(std::sin(beta) / std::sin(alpha));
    const LoopGeometry g =
        make_loop({b, a, b, b, a + b}, {beta, alpha, beta, beta, wrap_angle(alpha + beta)}, {0, 0, 0, 0, 0});
    const std::vector<double> turning(5, 2 * kPi);
    for (const FamilyCheck& check : classify(g, JointVector::Zero(5), turning).checks) {
      if (check.family == Family::goldberg) {
        EXPECT_LT(check.residual, 1e-12);
      }
    }
    // Of its assemblies, those where every joint but 5 turns.
    for (int attempt = 0; attempt < 40; ++attempt) {
      JointVector theta;
      if (!testing::assemble_by_levenberg_marquardt(g, uniform(rng, -kPi, kPi), rng, theta, 1)) continue;
      const VerificationSummary v = verify_from(g, theta);
      if (!v.verified) continue;
      const Classification k = classified({g, theta}, v);
      if (!(v.joint_travel[4] < 1e-9 && v.joint_travel.head(4).minCoeff() > 1.0)) continue;
      ++moving;
      EXPECT_EQ(k.family, Family::degenerate) << i << ": " << k.detail;
      EXPECT_NE(k.detail.find("joint 5 locked"), std::string::npos) << k.detail;
      EXPECT_NE(k.detail.find("locked 4R: bennett"), std::string::npos) << k.detail;
      break;
    }
  }
  EXPECT_GE(moving, 3);
}

// A Goldberg-type 5R on a folding Bennett loop (docs/research/discovery-5r-6r.md):
// Bennett loop 1 (a, alpha, b, beta) at input t and loop 2 equilateral
// (b, beta) folded at its joints F and D, (t + phi, pi, -(t + phi), pi),
// fused at A at phi; the 5R B C D E F read off the axes. `folded_residual`
// is loop 2's closure at the folded pose (0 up to round-off).
struct FoldingGoldberg5R {
  LoopGeometry bennett_loop, folding_loop;  // loops 1 and 2
  Posed loop;
  double folded_residual = 0.0;
};

FoldingGoldberg5R goldberg_on_a_folding_bennett_loop(std::mt19937_64& rng, double phi) {
  double a, alpha, b, beta;
  do {
    alpha = twist(rng);
    beta = twist(rng);
    a = uniform(rng, 0.5, 2.0);
    b = a * std::abs(std::sin(beta) / std::sin(alpha));
  } while (b < 0.3 || b > 4.0 || std::abs(a - b) < 0.2);
  const LoopGeometry l1 = bennett(a, alpha, b, beta), l2 = bennett(b, beta, b, beta);
  const double t = uniform(rng, 0.3, kPi - 0.3);
  JointVector folded(4);
  folded << t + phi, kPi, -(t + phi), kPi;
  const std::vector<Axis> x1 = joint_axes(l1, bennett_pose(l1, t)), x2 = joint_axes(l2, folded);
  return {l1, l2, dh_from_axes(std::vector<Axis>{x1[1], x1[2], x1[3], x2[2], x2[1]}),
          closure_residual(l2, folded).cwiseAbs().maxCoeff()};
}

TEST(Families, GoldbergOnAFoldingBennettLoopIsDegenerateWhateverTheWalk) {
  // docs/research/discovery-5r-6r.md, "Goldberg geometries on a folding Bennett loop":
  // built from the mechanism, independently of the conditions. Bennett loop 1
  // (a, alpha, b, beta) in its motion and loop 2 equilateral (b, beta) four
  // times, folded with its joints F and D at pi (axes E and A then coincide
  // and it turns freely about them), fused at A at phi; the 5R B C D E F
  // read off the axes. It moves with joint F (5) locked as loop 1. Folded
  // the other way (joints A and E at pi) it locks loop 1: axes D and F
  // coincide and only joints D and F turn (trivial). The two motions meet
  // where loop 2 folds both ways, and a walk through that pose may switch or
  // stray between them: the joint travels the classifier is given then show
  // no frozen joint. Degenerate whatever the travels, except a clean trivial
  // motion, which stays trivial (tried first).
  std::mt19937_64 rng(29);
  int locked_walks = 0, trivial_walks = 0;
  for (int i = 0; i < 8; ++i) {
    const double phi = i == 6 ? 1.1 : (i % 2 == 0 ? kPi : 0.0);  // opposite sides, same side, bent
    const FoldingGoldberg5R built = goldberg_on_a_folding_bennett_loop(rng, phi);
    const LoopGeometry &l1 = built.bennett_loop, &l2 = built.folding_loop;
    const std::string tag = "folding " + std::to_string(i);
    ASSERT_LT(built.folded_residual, 1e-12) << tag;
    const Posed& p = built.loop;
    ASSERT_LT(closure_error(p), 1e-12) << tag;
    const Family family = i == 6 ? Family::goldberg_bent : Family::goldberg;
    for (const FamilyCheck& check : classify(p.geometry, p.theta, {}).checks) {
      if (check.family == family) {
        EXPECT_LT(check.residual, 1e-10) << tag;
      }
    }
    // A random representation; where joint F (4) went.
    const int shift = static_cast<int>(rng() % 5);
    const bool reverse = rng() % 2 == 1;
    const Posed w = rewritten(p, shift, reverse, static_cast<unsigned>(rng() % 32));
    int f = (4 - shift + 5) % 5;
    if (reverse) f = 4 - f;
    const std::string locked = "moves with joint " + std::to_string(f + 1) + " locked; locked 4R: bennett";
    // The classifier told that every joint turns, as after a walk that switched.
    const std::vector<double> turning(5, 2 * kPi);
    const Classification all = classify(w.geometry, w.theta, turning);
    EXPECT_EQ(all.family, Family::degenerate) << tag << ": " << all.detail;
    EXPECT_NE(all.detail.find(locked), std::string::npos) << tag << ": " << all.detail;
    EXPECT_LT(all.residual, 1e-10) << tag;
    // The walk from this pose, whatever it followed.
    if (f != 0) {
      const VerificationSummary v = verify_from(w.geometry, w.theta);
      ASSERT_TRUE(v.verified) << tag << ": " << v.limit;
      const Classification k = classified(w, v);
      EXPECT_EQ(k.family, Family::degenerate) << tag << ": " << k.detail;
      EXPECT_NE(k.detail.find(locked), std::string::npos) << tag << ": " << k.detail;
      if (v.joint_travel[f] < 1e-9) ++locked_walks;
    }
    // Folded the other way, loop 1 locked at t = pi - phi: axes D and F (2, 4)
    // coincide; a walk that stays on that motion is trivial.
    JointVector other(4);
    const double s = uniform(rng, 0.5, 2.5);
    other << kPi, s, kPi, -s;
    const std::vector<Axis> x1 = joint_axes(l1, bennett_pose(l1, kPi - phi)), x2 = joint_axes(l2, other);
    const Posed q =
        rewritten(dh_from_axes(std::vector<Axis>{x1[1], x1[2], x1[3], x2[2], x2[1]}), 2, false, 0);  // joint D first
    ASSERT_LT(closure_error(q), 1e-12) << tag;
    const VerificationSummary vq = verify_from(q.geometry, q.theta);
    ASSERT_TRUE(vq.verified) << tag << ": " << vq.limit;
    const Classification kq = classified(q, vq);
    const bool stayed = vq.joint_travel[1] < 1e-9 && vq.joint_travel[3] < 1e-9 && vq.joint_travel[4] < 1e-9;
    if (stayed) {
      ++trivial_walks;
      EXPECT_EQ(kq.family, Family::trivial) << tag << ": " << kq.detail;
      EXPECT_NE(kq.detail.find("axes 1 and 3 coincide"), std::string::npos) << tag << ": " << kq.detail;
    } else {
      EXPECT_EQ(kq.family, Family::degenerate) << tag << ": " << kq.detail;
    }
  }
  EXPECT_GE(locked_walks, 3);
  EXPECT_GE(trivial_walks, 3);
  // Loop 1 nearly folding too (alpha = beta + delta, as the search's loops):
  // its motion passes close to the meeting pose. A walk by input steps used
  // to stray there (joint F turning more than frozen_travel, 1e-6 rad);
  // traced by arclength the circuit keeps to its branch. Degenerate, with
  // joint 5 locked, whatever the walk.
  int verified = 0;
  for (int i = 0; i < 16; ++i) {
    const double beta = twist(rng), b = uniform(rng, 0.5, 2.0);
    const double alpha = beta + std::pow(10.0, uniform(rng, -3.7, -2.9));
    const double a = b * std::abs(std::sin(alpha) / std::sin(beta)), phi = i % 2 ? kPi : 0.0,
                 t = uniform(rng, 0.3, 2.8);
    const LoopGeometry l1 = bennett(a, alpha, b, beta), l2 = bennett(b, beta, b, beta);
    JointVector folded(4);
    folded << t + phi, kPi, -(t + phi), kPi;
    const std::vector<Axis> x1 = joint_axes(l1, bennett_pose(l1, t)), x2 = joint_axes(l2, folded);
    const Posed p = dh_from_axes(std::vector<Axis>{x1[1], x1[2], x1[3], x2[2], x2[1]});
    const VerificationSummary v = verify_from(p.geometry, p.theta);
    if (!v.verified) continue;
    ++verified;
    const Classification k = classified(p, v);
    EXPECT_EQ(k.family, Family::degenerate) << i << ": " << k.detail;
    EXPECT_NE(k.detail.find("moves with joint 5 locked; locked 4R: bennett"), std::string::npos) << k.detail;
  }
  EXPECT_GE(verified, 12);
}

// The merged 5R of a 6R is read as classify reads a 5R: a Goldberg-type
// loop on a folding Bennett loop (built as in
// GoldbergOnAFoldingBennettLoopIsDegenerateWhateverTheWalk) is degenerate,
// and with an idle joint added the 6R is degenerate with that merged 5R
// described so, not as a Goldberg loop.
TEST(Families, AnIdleJointOnAGoldbergOnAFoldingBennettLoopMergesToNoGoldberg5R) {
  std::mt19937_64 rng(31);
  for (int i = 0; i < 6; ++i) {
    const double phi = i == 4 ? 1.1 : (i % 2 == 0 ? kPi : 0.0);  // opposite sides, same side, bent
    const FoldingGoldberg5R built = goldberg_on_a_folding_bennett_loop(rng, phi);
    const Posed& p = built.loop;
    const std::string family = i == 4 ? "goldberg_bent" : "goldberg";
    const std::string tag = "folding " + family + " " + std::to_string(i);
    ASSERT_LT(built.folded_residual, 1e-12) << tag;
    ASSERT_LT(closure_error(p), 1e-12) << tag;
    const Classification five = classify(p.geometry, p.theta, std::vector<double>(5, 2 * kPi));
    ASSERT_EQ(five.family, Family::degenerate) << tag << ": " << five.detail;
    const Posed m = with_idle_joint(p, rng);
    ASSERT_LT(closure_error(m), 1e-12) << tag;
    const Classification c = classify(m.geometry, m.theta, std::vector<double>(6, 2 * kPi));
    EXPECT_EQ(c.family, Family::degenerate) << tag << ": " << c.detail;
    EXPECT_LT(c.residual, 1e-10) << tag;
    EXPECT_NE(c.detail.find("axes 1 and 2 coincide; merged 5R: " + family + "'s conditions on a folding Bennett loop"),
              std::string::npos)
        << tag << ": " << c.detail;
    EXPECT_NE(c.detail.find("locked 4R: bennett"), std::string::npos) << tag << ": " << c.detail;
    for (const FamilyCheck& check : c.checks) {
      if (check.family == Family::degenerate) {
        ASSERT_EQ(check.conditions.size(), 3u) << tag;
        EXPECT_EQ(check.conditions[2].name, "merged 5R loop: degenerate residual") << tag;
      }
    }
  }
}

}  // namespace
}  // namespace loopfarm::family_tests
