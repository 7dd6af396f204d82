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
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Geometry>
#include <Eigen/SVD>

#include "allocation_counter.hpp"
#include "loopfarm/core/constructions.hpp"
#include "loopfarm/core/loop.hpp"
#include "loopfarm/core/sample_loops.hpp"
#include "loopfarm/search/classify.hpp"
#include "loopfarm/search/verify.hpp"
#include "test_support.hpp"

namespace loopfarm {
namespace {

constexpr double kPi = 3.14159265358979323846;

// ---------------------------------------------------------------------------
// Fixtures

// Posed loops, axes and dh_from_axes are constructions.hpp's.
using Posed = PosedLoop;

LoopGeometry make_loop(std::vector<double> a, std::vector<double> alpha, std::vector<double> d) {
  LoopGeometry g;
  const int n = static_cast<int>(a.size());
  g.a = Eigen::Map<JointVector>(a.data(), n);
  g.alpha = Eigen::Map<JointVector>(alpha.data(), n);
  g.d = Eigen::Map<JointVector>(d.data(), n);
  return g;
}

// Bennett loop (a, alpha), (b, beta), (a, alpha), (b, beta), d = 0; the
// caller makes sin(alpha)/a = +-sin(beta)/b.
LoopGeometry bennett(double a, double alpha, double b, double beta) {
  return make_loop({a, b, a, b}, {alpha, beta, alpha, beta}, {0, 0, 0, 0});
}

// A closed pose of a Bennett loop at input t, by its setup.
JointVector bennett_pose(const LoopGeometry& g, double t) {
  const bool asymmetric = std::sin(g.alpha[0]) * g.a[1] * std::sin(g.alpha[1]) * g.a[0] > 0.0;
  return asymmetric ? bennett_angles(g, t) : bennett_angles_line_symmetric(g, t);
}

// A representation of the same loop by loop.hpp's operations (shift, reversal,
// flips), with its angles.
Posed rewritten(const Posed& p, int shift, bool reverse, unsigned flips) {
  Posed out{relabelled(p.geometry, shift), relabelled_angles(p.theta, shift)};
  if (reverse) out = {reversed(out.geometry), reversed_angles(out.theta)};
  for (int j = 0; j < p.geometry.joints(); ++j) {
    if (flips >> j & 1u) out = {axis_flipped(out.geometry, j), axis_flipped_angles(out.theta, j)};
  }
  return out;
}

// A random representation, one in which no joint of `locked` (which the motion does
// not turn) is joint 1, the input that verify_motion drives.
Posed random_representation(const Posed& p, std::mt19937_64& rng, const std::vector<int>& locked = {}) {
  const int n = p.geometry.joints();
  std::uniform_int_distribution<int> shift(0, n - 1), flips(0, (1 << n) - 1), coin(0, 1);
  for (;;) {
    const int s = shift(rng);
    const bool reverse = coin(rng) == 1;
    const unsigned f = static_cast<unsigned>(flips(rng));
    // Relabelled, new joint j is old joint j + s; reversed, new joint j is old n - 1 - j.
    const int input = reverse ? (n - 1 + s) % n : s;
    if (std::find(locked.begin(), locked.end(), input) != locked.end()) continue;
    return rewritten(p, s, reverse, f);
  }
}

double uniform(std::mt19937_64& rng, double lo, double hi) {
  return std::uniform_real_distribution<double>(lo, hi)(rng);
}

// A twist away from 0 and pi (and its sign random).
double twist(std::mt19937_64& rng) {
  const double t = uniform(rng, 0.3, kPi - 0.3);
  return uniform(rng, 0.0, 1.0) < 0.5 ? t : -t;
}

// Goldberg 5R from two random Bennett loops sharing the link (b, beta):
// loop 1 is (A B C D) = (a, alpha, b, beta), loop 2 (A F E D) = (c, gamma,
// b, beta), each in a random setup; they share axes A and D. At A the links
// A->B and A->F are fused collinear (phi = 0: same side, pi: opposite
// sides), link DA removed: the 5R B C D E F (constructions.hpp's
// goldberg_5r, built in space). `phi` other than 0 and pi fuses them at an
// angle: the bent-link variant (docs/guide/families.md).
Posed goldberg_member(std::mt19937_64& rng, double phi) {
  for (;;) {
    const double alpha = twist(rng), beta = twist(rng), gamma = twist(rng);
    const double a = uniform(rng, 0.5, 2.0);
    // |sin alpha| / a = |sin beta| / b = |sin gamma| / c, the setups from the signs.
    const double b = a * std::abs(std::sin(beta) / std::sin(alpha));
    const double c = a * std::abs(std::sin(gamma) / std::sin(alpha));
    if (b < 0.3 || b > 4.0 || c < 0.3 || c > 4.0 || std::abs(a - c) < 0.2) continue;
    return goldberg_5r({{b, beta, alpha, gamma}, phi}, uniform(rng, 0.3, kPi - 0.3));
  }
}

// Two Bennett loops sharing a link, the shared link removed and nothing
// fused: loop 1 (A B C D) = (a, alpha, b, beta) and loop 2 (A F E D) =
// (c, gamma, b, beta) in random setups, sharing the link DA (both with frame
// 0 on axis A), each at its own input (t1, t2): the 6R A B C D E F, read off
// its six axes. Each loop turns about DA on its own, so the 6R has two
// degrees of freedom (docs/guide/families.md, "Two Bennett loops sharing a link").
Posed bennett_pair_member(std::mt19937_64& rng) {
  for (;;) {
    const double alpha = twist(rng), beta = twist(rng), gamma = twist(rng);
    const double b = uniform(rng, 0.5, 2.0);
    // |sin alpha| / a = |sin beta| / b = |sin gamma| / c, the setups from the signs.
    const double a = b * std::abs(std::sin(alpha) / std::sin(beta));
    const double c = b * std::abs(std::sin(gamma) / std::sin(beta));
    if (a < 0.3 || a > 4.0 || c < 0.3 || c > 4.0) continue;
    const double t1 = uniform(rng, 0.3, kPi - 0.3), t2 = uniform(rng, 0.3, kPi - 0.3);
    return bennett_pair_6r({b, beta, alpha, gamma}, t1, -t2);
  }
}

// Myard 5R: Goldberg from two mirror-image Bennett loops, the shared link a
// right-angle twist: (a, alpha, b, pi/2) and (a, -alpha, b, pi/2).
Posed myard_member(std::mt19937_64& rng, double phi) {
  const double alpha = twist(rng), a = uniform(rng, 0.5, 2.0);
  const double b = a / std::abs(std::sin(alpha));
  return goldberg_5r({{b, kPi / 2, alpha, -alpha}, phi}, uniform(rng, 0.3, kPi - 0.3));
}

// A closed pose of a 6R: inputs tried over the turn until one assembles.
bool closed_pose(const LoopGeometry& g, std::mt19937_64& rng, JointVector& theta) {
  for (int i = 0; i < 12; ++i) {
    if (testing::assemble_by_levenberg_marquardt(g, -kPi + (i + 0.5) * kPi / 6, rng, theta, 30)) return true;
  }
  return false;
}

// Bricard line-symmetric 6R: a_i = a_{i+3}, alpha_i = alpha_{i+3}, d_i = d_{i+3}.
LoopGeometry bricard_line_geometry(std::mt19937_64& rng) {
  std::array<double, 3> a, t, d;
  for (int i = 0; i < 3; ++i) {
    a[i] = uniform(rng, 0.5, 2.0);
    t[i] = twist(rng);
    d[i] = uniform(rng, -0.5, 0.5);
  }
  return make_loop({a[0], a[1], a[2], a[0], a[1], a[2]}, {t[0], t[1], t[2], t[0], t[1], t[2]},
                   {d[0], d[1], d[2], d[0], d[1], d[2]});
}

// Bricard plane-symmetric 6R (plane through joints 1 and 4).
LoopGeometry bricard_plane_geometry(std::mt19937_64& rng) {
  std::array<double, 3> a, t;
  for (int i = 0; i < 3; ++i) {
    a[i] = uniform(rng, 0.5, 2.0);
    t[i] = twist(rng);
  }
  const double d2 = uniform(rng, -0.5, 0.5), d3 = uniform(rng, -0.5, 0.5);
  return make_loop({a[0], a[1], a[2], a[2], a[1], a[0]}, {t[0], t[1], t[2], -t[2], -t[1], -t[0]},
                   {0, d2, d3, 0, -d3, -d2});
}

// Bricard trihedral 6R: right-angle twists of random signs, no offsets,
// a6 from a1^2 + a3^2 + a5^2 = a2^2 + a4^2 + a6^2.
LoopGeometry bricard_trihedral_geometry(std::mt19937_64& rng) {
  for (;;) {
    std::vector<double> a(6), alpha(6);
    for (int i = 0; i < 5; ++i) a[i] = uniform(rng, 0.5, 2.0);
    const double a6_squared = a[0] * a[0] + a[2] * a[2] + a[4] * a[4] - a[1] * a[1] - a[3] * a[3];
    if (a6_squared < 0.25) continue;
    a[5] = std::sqrt(a6_squared);
    for (int i = 0; i < 6; ++i) alpha[i] = uniform(rng, 0.0, 1.0) < 0.5 ? kPi / 2 : -kPi / 2;
    return make_loop(a, alpha, std::vector<double>(6, 0.0));
  }
}

// Two Bennett dyads joined by two equal links: links 1, 2 with Bennett's
// ratio kappa1 and d2 = 0, links 4, 5 with kappa2 and d5 = 0, the same
// (cos alpha + cos beta) / kappa (alpha5 solved from it), links 3 and 6
// equal and free, d1 = d3 and d4 = d6 free. Twists negative (the searches'
// canonical representation; other representations are the test's random ones).
LoopGeometry bennett_dyads_geometry(std::mt19937_64& rng) {
  for (;;) {
    const double k1 = -uniform(rng, 0.4, 1.5), k2 = -uniform(rng, 0.4, 1.5);
    const double t1 = -uniform(rng, 0.3, kPi - 0.3), t2 = -uniform(rng, 0.3, kPi - 0.3);
    const double t4 = -uniform(rng, 0.3, kPi - 0.3);
    const double cos5 = (std::cos(t1) + std::cos(t2)) / k1 * k2 - std::cos(t4);
    if (std::abs(cos5) > 0.95) continue;
    const double t5 = -std::acos(cos5);
    const double c = uniform(rng, 0.5, 1.5), gamma = -uniform(rng, 0.3, kPi - 0.3);
    const std::vector<double> a = {std::sin(t1) / k1, std::sin(t2) / k1, c, std::sin(t4) / k2, std::sin(t5) / k2, c};
    if (*std::min_element(a.begin(), a.end()) < 0.2 || *std::max_element(a.begin(), a.end()) > 3.0) continue;
    const double e = uniform(rng, -0.3, 0.3), f = uniform(rng, -0.3, 0.3);
    return make_loop(a, {t1, t2, gamma, t4, t5, gamma}, {e, 0.0, e, f, 0.0, f});
  }
}

// A loop plus an idle joint: joint 1 of `p` split into two coaxial joints
// (a link of length 0 and twist 0 or pi between them, the offset shared
// between them), the angle split too.
Posed with_idle_joint(const Posed& p, std::mt19937_64& rng) {
  const int n = p.geometry.joints();
  const bool flipped = uniform(rng, 0.0, 1.0) < 0.5;
  const double sigma = flipped ? kPi : 0.0, c = flipped ? -1.0 : 1.0;
  const double t = uniform(rng, -0.5, 0.5), spin = uniform(rng, -kPi, kPi);
  Posed out;
  out.geometry.a.resize(n + 1);
  out.geometry.alpha.resize(n + 1);
  out.geometry.d.resize(n + 1);
  out.theta.resize(n + 1);
  out.geometry.a << 0.0, p.geometry.a;
  out.geometry.alpha << sigma, p.geometry.alpha;
  out.geometry.alpha[1] = wrap_angle(p.geometry.alpha[0] - sigma);
  out.geometry.d << t, p.geometry.d;
  out.geometry.d[1] = c * (p.geometry.d[0] - t);  // d_1 + c d_2 = the merged offset
  out.theta << spin, p.theta;
  out.theta[1] = c * (p.theta[0] - spin);
  return out;
}

double closure_error(const Posed& p) { return closure_residual(p.geometry, p.theta).cwiseAbs().maxCoeff(); }

// The rigid verification from the given pose only, as the farm verifies a
// zero: whether the loop moves there. Finding motions from anywhere else is
// motion_test's.
VerificationSummary verify_from(const LoopGeometry& g, const JointVector& pose) {
  VerificationOptions o;
  o.all_circuits = false;
  return verify_motion(g, pose, o);
}

Classification classified(const Posed& p, const VerificationSummary& v) {
  const std::span<const double> travel(v.joint_travel.data(), static_cast<size_t>(v.joint_travel.size()));
  return classify(p.geometry, p.theta, v.verified ? travel : std::span<const double>());
}

// The member is movable (rigid closure followed along at least 10 degrees of
// input, closing to round-off) and, in a random representation, classified as its
// family with a residual at round-off.
void expect_movable_member(const Posed& member, Family family, std::mt19937_64& rng, const std::string& tag,
                           const std::vector<int>& locked = {}) {
  ASSERT_LT(closure_error(member), 1e-12) << tag;
  const Posed w = random_representation(member, rng, locked);
  ASSERT_LT(closure_error(w), 1e-12) << tag;
  const VerificationSummary v = verify_from(w.geometry, w.theta);
  EXPECT_TRUE(v.verified) << tag << ": " << v.limit;
  EXPECT_GT(v.range_hi - v.range_lo, 10.0 * kPi / 180.0) << tag;
  const Classification c = classified(w, v);
  EXPECT_EQ(c.family, family) << tag << ": " << to_string(c.family) << ", " << c.detail;
  EXPECT_LT(c.residual, 1e-10) << tag;
  // The family's own check says so too, whatever family won.
  for (const FamilyCheck& check : c.checks) {
    if (check.family == family) {
      EXPECT_LT(check.residual, 1e-10) << tag;
    }
  }
}

// Parameter p (GeometryVector order: a, alpha, d) moved by eps (times L for
// lengths and offsets, radians for twists).
LoopGeometry perturbed(const LoopGeometry& g, int p, double eps) {
  const int n = g.joints();
  LoopGeometry out = g;
  const double L = length_scale(g);
  if (p < n)
    out.a[p] += eps * L;
  else if (p < 2 * n)
    out.alpha[p - n] += eps;
  else
    out.d[p - 2 * n] += eps * L;
  return out;
}

// Parameter p moved by h in its own units (for central differences).
LoopGeometry perturbed_raw(const LoopGeometry& g, int p, double h) {
  const int n = g.joints();
  LoopGeometry out = g;
  if (p < n)
    out.a[p] += h;
  else if (p < 2 * n)
    out.alpha[p - n] += h;
  else
    out.d[p - 2 * n] += h;
  return out;
}

const std::array<double, 4> kNearMisses = {1e-3, 1e-4, 1e-5, 1e-6};

// The member with parameter p moved by each near-miss size: the rigid
// closure cannot follow it from the member's pose (not verified), and it is
// not classified as the family, its residual there at least eps / 10.
void expect_near_misses_rigid(const Posed& member, Family family, int p, const std::string& tag) {
  for (double eps : kNearMisses) {
    const LoopGeometry g = perturbed(member.geometry, p, eps);
    const VerificationSummary v = verify_from(g, member.theta);
    EXPECT_FALSE(v.verified) << tag << " parameter " << p << " + " << eps << ": worst residual " << v.worst_residual;
    const Classification c = classified({g, member.theta}, v);
    EXPECT_NE(c.family, family) << tag << " parameter " << p << " + " << eps;
    for (const FamilyCheck& check : c.checks) {
      if (check.family == family) {
        EXPECT_GT(check.residual, eps / 10) << tag << " " << eps;
      }
    }
  }
}

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

// A random Bennett loop (either setup, from the twists' signs) in a pose.
Posed random_bennett_member(std::mt19937_64& rng) {
  const double a = uniform(rng, 0.5, 2.0), alpha = twist(rng), beta = twist(rng);
  const double b = a * std::abs(std::sin(beta) / std::sin(alpha));
  const LoopGeometry g = bennett(a, alpha, b, beta);
  return {g, bennett_pose(g, uniform(rng, 0.3, kPi - 0.3))};
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

// A loop in a pose with one more joint axis put on link k (between axes k
// and k+1): a random line fixed to that link. Locked, the new joint leaves
// the loop as it was; free, it adds a joint that the motion need not turn.
Posed with_locked_joint(const Posed& p, int k, std::mt19937_64& rng) {
  std::vector<Axis> axes = joint_axes(p.geometry, p.theta);
  const double L = length_scale(p.geometry);
  const Vector3 point =
      axes[static_cast<size_t>(k)].point + L * Vector3(uniform(rng, -1, 1), uniform(rng, -1, 1), uniform(rng, -1, 1));
  const Vector3 direction = Vector3(uniform(rng, -1, 1), uniform(rng, -1, 1), uniform(rng, -1, 1)).normalized();
  axes.insert(axes.begin() + k + 1, Axis{point, direction});
  return dh_from_axes(axes);
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
    double a, alpha, b, beta;
    do {
      alpha = twist(rng);
      beta = twist(rng);
      a = uniform(rng, 0.5, 2.0);
      b = a * std::abs(std::sin(beta) / std::sin(alpha));
    } while (b < 0.3 || b > 4.0 || std::abs(a - b) < 0.2);
    const LoopGeometry l1 = bennett(a, alpha, b, beta), l2 = bennett(b, beta, b, beta);
    const double t = uniform(rng, 0.3, kPi - 0.3);
    const std::string tag = "folding " + std::to_string(i);
    // Loop 2 folded at F and D: (t + phi, pi, -(t + phi), pi) closes exactly.
    JointVector folded(4);
    folded << t + phi, kPi, -(t + phi), kPi;
    ASSERT_LT(closure_residual(l2, folded).cwiseAbs().maxCoeff(), 1e-12) << tag;
    std::vector<Axis> x1 = joint_axes(l1, bennett_pose(l1, t)), x2 = joint_axes(l2, folded);
    const Posed p = dh_from_axes(std::vector<Axis>{x1[1], x1[2], x1[3], x2[2], x2[1]});
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
    x1 = joint_axes(l1, bennett_pose(l1, kPi - phi));
    x2 = joint_axes(l2, other);
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

// ---------------------------------------------------------------------------
// 6R

// Members of a 6R family from `make` (parameters), closed by the rigid
// closure from random guesses; near-misses moving `parameters` in turn. Of
// `tries` geometries at least `at_least` must assemble.
void expect_6r_family(LoopGeometry (*make)(std::mt19937_64&), Family family, std::array<int, 3> parameters,
                      std::uint64_t seed, int tries = 6, int at_least = 5) {
  std::mt19937_64 rng(seed);
  int built = 0;
  for (int i = 0; i < tries; ++i) {
    const LoopGeometry g = make(rng);
    JointVector theta;
    if (!closed_pose(g, rng, theta)) continue;
    ++built;
    const std::string tag = std::string(to_string(family)) + " " + std::to_string(i);
    expect_movable_member({g, theta}, family, rng, tag);
    expect_near_misses_rigid({g, theta}, family, parameters[static_cast<size_t>(i) % 3], tag);
  }
  EXPECT_GE(built, at_least) << to_string(family);
}

TEST(Families, BricardLineSymmetricMovesAndIsClassified) {
  expect_6r_family(bricard_line_geometry, Family::bricard_line_symmetric, {0, 6 + 1, 12 + 2}, 21);  // a1, alpha2, d3
}

TEST(Families, BricardPlaneSymmetricMovesAndIsClassified) {
  expect_6r_family(bricard_plane_geometry, Family::bricard_plane_symmetric, {1, 6 + 2, 12 + 0}, 22);  // a2, alpha3, d1
}

TEST(Families, BricardPlaneSymmetricNeedsTheTwistsOpposite) {
  // The literature's alpha12 + alpha61 = pi written in this project's
  // convention is alpha1 + alpha6 = 0; with the sums pi instead (an even
  // number of the three sums changed by pi is only another representation) the loop
  // does not even assemble.
  std::mt19937_64 rng(23);
  LoopGeometry g = bricard_plane_geometry(rng);
  for (int i = 3; i < 6; ++i) g.alpha[i] = wrap_angle(g.alpha[i] + kPi);
  JointVector theta;
  EXPECT_FALSE(closed_pose(g, rng, theta));
}

TEST(Families, BricardTrihedralMovesAndIsClassified) {
  expect_6r_family(bricard_trihedral_geometry, Family::bricard_trihedral, {5, 6 + 1, 12 + 3}, 24);  // a6, alpha2, d4
}

// Two Bennett loops sharing a link (removed, nothing fused): built in space,
// movable, every offset zero, classified bennett_pair in any representation with
// residual at round-off; two degrees of freedom (the closure's Jacobian has
// a two-dimensional null space); near-misses rigid. Its geometry is
// unclassified without the family; the generic 6R search's start 398 lies
// 4e-6 from one (docs/research/discovery-5r-6r.md).
TEST(Families, TwoBennettLoopsSharingALinkMoveAndAreABennettPair) {
  std::mt19937_64 rng(27);
  for (int i = 0; i < 8; ++i) {
    const Posed m = bennett_pair_member(rng);
    const std::string tag = "bennett_pair " + std::to_string(i);
    EXPECT_LT(m.geometry.d.cwiseAbs().maxCoeff(), 1e-12) << tag;
    expect_movable_member(m, Family::bennett_pair, rng, tag);
    ClosureJacobians J;
    closure_jacobians(m.geometry, m.theta, J);
    const Eigen::JacobiSVD<Eigen::MatrixXd> svd(J.theta);
    const Eigen::VectorXd sv = svd.singularValues();  // descending
    EXPECT_GT(sv[3], 1e-3 * sv[0]) << tag;
    EXPECT_LT(sv[4], 1e-10 * sv[0]) << tag;
    EXPECT_NE(classify(m.geometry, m.theta, std::vector<double>(6, 2 * kPi)).detail.find("two Bennett loops"),
              std::string::npos)
        << tag;
    // a1, alpha2, d3, a4, alpha5, d1, a2, alpha6 in turn.
    const std::array<int, 8> parameters = {0, 6 + 1, 12 + 2, 3, 6 + 4, 12 + 0, 1, 6 + 5};
    expect_near_misses_rigid(m, Family::bennett_pair, parameters[static_cast<size_t>(i)], tag);
  }
}

// The 9-parameter class the generic 6R search finds most (docs/research/discovery-5r-6r.md):
// members built from the conditions, closed by the rigid closure from
// random guesses (a generic 6R cannot be assembled with its input held),
// verified movable, classified in random representations; near-misses a1, alpha2,
// d3 rigid. Unclassified before the family.
// Many members are rockers over a few tens of degrees, or have no real
// assembly at all (docs/guide/families.md), so more are built than for Bricard's.
TEST(Families, TwoBennettDyadsJoinedByEqualLinksMoveAndAreClassified) {
  // Near-misses in a1, alpha2, d3; 12 built, at least 7 assembled.
  expect_6r_family(bennett_dyads_geometry, Family::bennett_dyads, {0, 6 + 1, 12 + 2}, 28, 12, 7);
}

// The condition that only the search's loops showed, (cos alpha1 + cos alpha2) / kappa1 =
// (cos alpha4 + cos alpha5) / kappa2: with alpha5 moved off it by 0.05 rad (a5 kept on kappa2)
// the loops are rigid.
TEST(Families, BennettDyadsNeedTheSameCosineSumOverKappa) {
  std::mt19937_64 rng(29);
  int tried = 0;
  for (int i = 0; i < 6; ++i) {
    const LoopGeometry member = bennett_dyads_geometry(rng);
    JointVector theta;
    if (!closed_pose(member, rng, theta)) continue;
    LoopGeometry off = member;
    off.alpha[4] += 0.05;
    off.a[4] = off.a[3] * std::sin(off.alpha[4]) / std::sin(off.alpha[3]);
    JointVector pose;
    ++tried;
    // Assembled at all, it does not move: verify_motion loses the closure at once.
    if (closed_pose(off, rng, pose)) {
      const VerificationSummary v = verify_from(off, pose);
      EXPECT_FALSE(v.verified && v.range_hi - v.range_lo > 1e-3) << i << ": " << v.range_lo << " " << v.range_hi;
    }
    EXPECT_NE(classify(off, JointVector::Zero(6), std::vector<double>(6, 1.0)).family, Family::bennett_dyads) << i;
  }
  EXPECT_GE(tried, 4);
}

TEST(Families, GoldbergWithAnIdleJointIsADegenerate6R) {
  std::mt19937_64 rng(25);
  for (int i = 0; i < 4; ++i) {
    // Straight fusions, then a bent one.
    const double phi = i == 3 ? 1.3 : (i % 2 == 0 ? kPi : 0.0);
    const Posed m = with_idle_joint(goldberg_member(rng, phi), rng);
    const std::string tag = "degenerate 6R " + std::to_string(i);
    expect_movable_member(m, Family::degenerate, rng, tag);
    const Classification c = classify(m.geometry, m.theta, std::vector<double>(6, 2 * kPi));
    const std::string merged = i == 3 ? "merged 5R: goldberg_bent" : "merged 5R: goldberg";
    EXPECT_NE(c.detail.find(merged), std::string::npos) << c.detail;
    if (i != 3) {
      EXPECT_EQ(c.detail.find("goldberg_bent"), std::string::npos) << c.detail;
    }
  }
}

TEST(Families, AGoldbergLoopWithALockedJointIsADegenerate6R) {
  std::mt19937_64 rng(27);
  for (int i = 0; i < 3; ++i) {
    const Posed m = with_locked_joint(goldberg_member(rng, i == 2 ? 1.1 : kPi), i, rng);
    const std::string tag = "locked 6R " + std::to_string(i);
    expect_movable_member(m, Family::degenerate, rng, tag, {i + 1});
    const Classification c = classified(m, verify_from(m.geometry, m.theta));
    EXPECT_NE(c.detail.find(i == 2 ? "locked 5R: goldberg_bent" : "locked 5R: goldberg"), std::string::npos)
        << c.detail;
  }
}

TEST(Families, ABennettLoopWithTwoLockedJointsIsADegenerate6R) {
  // Two extra axes fixed on two links of a Bennett loop: locking one leaves a
  // 5R that still has a locked joint, locking both the Bennett loop.
  std::mt19937_64 rng(28);
  for (int i = 0; i < 3; ++i) {
    const Posed five = with_locked_joint(random_bennett_member(rng), i, rng);  // joint i + 1 locked
    const Posed six = with_locked_joint(five, i + 2, rng);                     // and joint i + 3
    const std::string tag = "two locked " + std::to_string(i);
    expect_movable_member(six, Family::degenerate, rng, tag, {i + 1, i + 3});
    const Classification c = classified(six, verify_from(six.geometry, six.theta));
    EXPECT_NE(c.detail.find("joints " + std::to_string(i + 2) + ", " + std::to_string(i + 4) + " locked"),
              std::string::npos)
        << c.detail;
    EXPECT_NE(c.detail.find("locked 4R: bennett"), std::string::npos) << c.detail;
  }
}

TEST(Families, ALineSymmetricBricardLoopFoundMovingWithTwoLockedJointsStaysBricard) {
  // A Bennett loop has a half-turn symmetry taking joint i to joint i + 2
  // (computed here from the pose, Kabsch on the four joint origins). An
  // extra axis on link 1 and its image on link 3 make a line-symmetric 6R,
  // a Bricard loop, which also moves as the Bennett loop with the two extra
  // joints locked: its geometry is Bricard's, so it is classified so, and
  // the detail names the motion found (the bricard-6r searches meet these).
  std::mt19937_64 rng(29);
  int checked = 0;
  for (int i = 0; i < 4; ++i) {
    const Posed b = random_bennett_member(rng);
    const std::vector<Axis> axes = joint_axes(b.geometry, b.theta);
    Eigen::Matrix<double, 3, 4> from, to;
    for (int j = 0; j < 4; ++j) {
      from.col(j) = axes[static_cast<size_t>(j)].point;
      to.col(j) = axes[static_cast<size_t>((j + 2) % 4)].point;
    }
    const Eigen::Matrix4d T = Eigen::umeyama(from, to, false);
    const Eigen::Matrix3d R = T.topLeftCorner<3, 3>();
    const Vector3 t = T.topRightCorner<3, 1>();
    ASSERT_LT((R * from + t.replicate(1, 4) - to).cwiseAbs().maxCoeff(), 1e-9) << i;
    const double L = length_scale(b.geometry);
    const Vector3 point = axes[0].point + L * Vector3(uniform(rng, -1, 1), uniform(rng, -1, 1), uniform(rng, -1, 1));
    const Vector3 direction = Vector3(uniform(rng, -1, 1), uniform(rng, -1, 1), uniform(rng, -1, 1)).normalized();
    const Posed six = dh_from_axes(
        std::vector<Axis>{axes[0], {point, direction}, axes[1], axes[2], {R * point + t, R * direction}, axes[3]});
    const std::string tag = "symmetric locked " + std::to_string(i);
    const VerificationSummary v = verify_from(six.geometry, six.theta);
    ASSERT_TRUE(v.verified) << tag << ": " << v.limit;
    EXPECT_LT(std::max(v.joint_travel[1], v.joint_travel[4]), 1e-9) << tag;
    const Classification c = classified(six, v);
    EXPECT_EQ(c.family, Family::bricard_line_symmetric) << tag << ": " << c.detail;
    EXPECT_NE(c.detail.find("the motion found: joints 2, 5 locked"), std::string::npos) << c.detail;
    EXPECT_NE(c.detail.find("locked 4R: bennett"), std::string::npos) << c.detail;
    ++checked;
  }
  EXPECT_EQ(checked, 4);
}

TEST(Families, PlanarAndSpherical5RAnd6RKeepTheirFamilies) {
  // Planar and spherical loops of any n were classified before; a planar 6R
  // with a closed pose, a spherical 5R.
  std::mt19937_64 rng(26);
  const LoopGeometry planar =
      make_loop({1.0, 2.2, 1.7, 2.0, 1.5, 1.9}, std::vector<double>(6, 0.0), std::vector<double>(6, 0.0));
  JointVector theta;
  ASSERT_TRUE(closed_pose(planar, rng, theta));
  const VerificationSummary v = verify_from(planar, theta);
  EXPECT_TRUE(v.verified);
  EXPECT_EQ(classified({planar, theta}, v).family, Family::planar);
  const LoopGeometry spherical =
      make_loop(std::vector<double>(5, 0.0), {0.9, 1.2, 0.7, 1.4, 1.1}, std::vector<double>(5, 0.0));
  EXPECT_EQ(classify(spherical, JointVector::Zero(5), std::vector<double>(5, 1.0)).family, Family::spherical);
}

TEST(Families, Generic5RAnd6RAreUnclassifiedWithEveryResidualLarge) {
  for (int n : {5, 6}) {
    for (std::uint64_t seed = 1; seed <= 5; ++seed) {
      const LoopGeometry g = random_loop(n, seed);
      const Classification c = classify(g, random_angles(n, seed), std::vector<double>(n, 1.0));
      EXPECT_EQ(c.family, Family::unclassified) << n << " " << seed;
      EXPECT_EQ(c.checks.size(), n == 5 ? 8u : 10u);
      for (const FamilyCheck& check : c.checks) EXPECT_GT(check.residual, 1e-3) << to_string(check.family);
    }
  }
}

// ---------------------------------------------------------------------------
// Distances (deflation) of the new families

TEST(Families, DistanceIsZeroOnMembersAndTheNumericPathEqualsTheReport) {
  std::mt19937_64 rng(31);
  struct Case {
    Family family;
    LoopGeometry member;
  };
  std::vector<Case> cases = {{Family::goldberg, goldberg_member(rng, kPi).geometry},
                             {Family::goldberg, goldberg_member(rng, 0.0).geometry},
                             {Family::myard, myard_member(rng, kPi).geometry},
                             {Family::goldberg_bent, goldberg_member(rng, 1.1).geometry},
                             {Family::goldberg_bent, goldberg_member(rng, -2.3).geometry},
                             {Family::bricard_line_symmetric, bricard_line_geometry(rng)},
                             {Family::bricard_plane_symmetric, bricard_plane_geometry(rng)},
                             {Family::bricard_trihedral, bricard_trihedral_geometry(rng)},
                             {Family::bennett_pair, bennett_pair_member(rng).geometry},
                             {Family::bennett_dyads, bennett_dyads_geometry(rng)}};
  for (const Case& c : cases) {
    const int n = c.member.joints();
    EXPECT_LT(family_distance(c.family, c.member), 1e-12) << to_string(c.family);
    for (std::uint64_t seed = 1; seed <= 3; ++seed) {
      // Near the member every parameter moved a little (one alone can keep a
      // symmetry of the family, and two representations tie: a kink of the minimum).
      LoopGeometry near = c.member;
      for (int p = 0; p < 3 * n; ++p) near = perturbed(near, p, uniform(rng, -1e-3, 1e-3));
      for (const LoopGeometry& g : {random_loop(n, seed), near}) {
        GeometryVector numeric_gradient, report_gradient;
        const double numeric = family_distance(c.family, g, &numeric_gradient);
        const FamilyCheck report = family_distance_report(c.family, g, &report_gradient);
        EXPECT_EQ(numeric, report.residual) << to_string(c.family);  // bit for bit
        EXPECT_EQ(numeric_gradient, report_gradient) << to_string(c.family);
        EXPECT_EQ(numeric, family_distance(c.family, g)) << to_string(c.family);
        // Against central differences.
        const double h = 1e-6;
        for (int p = 0; p < 3 * n; ++p) {
          const double fd =
              (family_distance(c.family, perturbed_raw(g, p, h)) - family_distance(c.family, perturbed_raw(g, p, -h))) /
              (2 * h);
          EXPECT_NEAR(numeric_gradient[p], fd, 1e-5 * std::max(1.0, std::abs(fd))) << to_string(c.family) << " " << p;
        }
      }
    }
  }
}

TEST(Families, DistanceNeedsTheRightJointCountAndIsAllocationFree) {
  EXPECT_THROW(family_distance(Family::goldberg, random_loop(6, 1)), std::invalid_argument);
  EXPECT_THROW(family_distance(Family::goldberg_bent, random_loop(4, 1)), std::invalid_argument);
  EXPECT_THROW(family_distance(Family::bricard_line_symmetric, random_loop(5, 1)), std::invalid_argument);
  EXPECT_THROW(family_distance(Family::degenerate, random_loop(5, 1)), std::invalid_argument);
  EXPECT_THROW(family_distance_report(Family::myard, random_loop(4, 1)), std::invalid_argument);
  if (!testing::kCountsAllocations) GTEST_SKIP() << "allocations are not counted under AddressSanitizer";
  const LoopGeometry g5 = random_loop(5, 2), g6 = random_loop(6, 2);
  GeometryVector gradient;
  // Warm: the representation tables are built on the first call per joint count.
  family_distance(Family::goldberg, g5, &gradient);
  family_distance(Family::bricard_trihedral, g6, &gradient);
  const long before = testing::allocations();
  double sum = 0.0;
  for (Family f : {Family::goldberg, Family::myard, Family::goldberg_bent}) sum += family_distance(f, g5, &gradient);
  for (Family f : {Family::bricard_line_symmetric, Family::bricard_plane_symmetric, Family::bricard_trihedral,
                   Family::bennett_pair, Family::bennett_dyads}) {
    sum += family_distance(f, g6, &gradient);
  }
  EXPECT_EQ(testing::allocations() - before, 0);
  EXPECT_GT(sum, 0.0);
}

}  // namespace
}  // namespace loopfarm
