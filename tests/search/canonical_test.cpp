#include "loopfarm/search/canonical.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <set>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "loopfarm/core/sample_loops.hpp"
#include "loopfarm/search/verify.hpp"
#include "test_support.hpp"

namespace loopfarm {
namespace {

using testing::rad;

// Another representation of the same loop, built with loop.hpp's own operations
// (independent of the canonical form's internal maps): a relabelling, maybe
// a reversal, some axis flips and a scale, chosen from `seed`.
struct Rewritten {
  LoopGeometry g;
  JointVector theta;
};

Rewritten rewrite(const LoopGeometry& g, const JointVector& theta, std::uint64_t seed) {
  const int n = g.joints();
  std::uint64_t s = seed * 0x9E3779B97F4A7C15ull + 1;
  auto next = [&s] {
    s ^= s << 13;
    s ^= s >> 7;
    s ^= s << 17;
    return s;
  };
  Rewritten r{g, theta};
  const int shift = static_cast<int>(next() % static_cast<std::uint64_t>(n));
  r.g = relabelled(r.g, shift);
  r.theta = relabelled_angles(r.theta, shift);
  if (next() % 2) {
    r.g = reversed(r.g);
    r.theta = reversed_angles(r.theta);
  }
  for (int j = 0; j < n; ++j) {
    if (next() % 2) {
      r.g = axis_flipped(r.g, j);
      r.theta = axis_flipped_angles(r.theta, j);
    }
  }
  const double factor = 0.25 + static_cast<double>(next() % 1000) / 100.0;
  r.g.a *= factor;
  r.g.d *= factor;
  return r;
}

TEST(Canonical, EveryRepresentationOfALoopHasTheSameKey) {
  for (int n = 4; n <= 8; ++n) {
    for (std::uint64_t seed = 1; seed <= 6; ++seed) {
      const LoopGeometry g = random_loop(n, 100 * n + seed);
      const std::string key = canonical_form(g).key;
      for (std::uint64_t k = 0; k < 12; ++k) {
        const Rewritten r = rewrite(g, random_angles(n, seed), 1000 * seed + k);
        EXPECT_EQ(canonical_form(r.g).key, key) << n << " " << seed << " " << k;
      }
    }
  }
}

TEST(Canonical, DifferentLoopsHaveDifferentKeys) {
  std::set<std::string> keys;
  int loops = 0;
  for (int n = 4; n <= 8; ++n) {
    for (std::uint64_t seed = 1; seed <= 20; ++seed) {
      keys.insert(canonical_form(random_loop(n, seed)).key);
      ++loops;
    }
  }
  EXPECT_EQ(static_cast<int>(keys.size()), loops);
  // A small change of one parameter changes the key.
  LoopGeometry g = paper_bennett_loop();
  const std::string key = canonical_form(g).key;
  g.a[0] += 1e-4;
  EXPECT_NE(canonical_form(g).key, key);
}

TEST(Canonical, TheRepresentativeClosesWhereTheInputDid) {
  const LoopGeometry g = paper_bennett_loop();
  const JointVector theta = bennett_angles(g, rad(77));
  for (std::uint64_t k = 0; k < 10; ++k) {
    const Rewritten r = rewrite(g, theta, k);
    ASSERT_LT(closure_residual(r.g, r.theta).norm(), 1e-12);
    const CanonicalForm form = canonical_form(r.g);
    EXPECT_LT(closure_residual(form.geometry, canonical_angles(form, r.theta)).norm(), 1e-12) << k;
    EXPECT_NEAR(length_scale(form.geometry), 1.0, 1e-15);
    EXPECT_NEAR(form.scale, length_scale(r.g), 1e-15);
  }
}

TEST(Canonical, IsIdempotentAndSnapsTheTwistCut) {
  const CanonicalForm form = canonical_form(random_loop(6, 3));
  EXPECT_EQ(canonical_form(form.geometry).key, form.key);
  // Twists of pi and -pi + 1e-12 are the same twist.
  LoopGeometry a = planar_four_bar(1.0, 3.0, 2.5, 3.5);
  a.alpha[1] = 3.14159265358979323846;
  LoopGeometry b = a;
  b.alpha[1] = -3.14159265358979323846 + 1e-12;
  EXPECT_EQ(canonical_form(a).key, canonical_form(b).key);
  // -0 and 0 are the same offset.
  LoopGeometry c = a;
  c.d[2] = -0.0;
  EXPECT_EQ(canonical_form(c).key, canonical_form(a).key);
  EXPECT_EQ(canonical_form(a).key.find("-0,"), std::string::npos);
}

// The form people read: the same key and the same loop (it closes where the
// input did, checked with loop.hpp's closure), with as few negative twists as
// the loop's representations allow, whatever representation it was given in.
TEST(Canonical, TheConventionalFormHasPositiveTwistsWhereTheLoopAllows) {
  const LoopGeometry g = paper_bennett_loop();  // twists 30, 90, 30, 90 deg
  const JointVector theta = bennett_angles(g, rad(77));
  const CanonicalForm canonical = canonical_form(g);
  int negative = 0;
  for (int k = 0; k < 4; ++k) negative += canonical.geometry.alpha[k] < 0 ? 1 : 0;
  EXPECT_GT(negative, 0) << "the key's representative has negative twists";
  for (std::uint64_t k = 0; k < 10; ++k) {
    const Rewritten r = rewrite(g, theta, k);
    const CanonicalForm form = conventional_form(r.g);
    EXPECT_EQ(form.key, canonical.key);
    EXPECT_EQ(canonical_form(form.geometry).key, canonical.key);
    for (int j = 0; j < 4; ++j) {
      EXPECT_GT(form.geometry.alpha[j], 0.0) << j;
      EXPECT_GE(form.geometry.d[j], 0.0) << j;
    }
    // The Bennett loop's own values: a/L and twists 30, 90, 30, 90 in some order.
    std::vector<double> twists(form.geometry.alpha.data(), form.geometry.alpha.data() + 4);
    std::sort(twists.begin(), twists.end());
    EXPECT_NEAR(twists[0], rad(30), 1e-12);
    EXPECT_NEAR(twists[1], rad(30), 1e-12);
    EXPECT_NEAR(twists[2], rad(90), 1e-12);
    EXPECT_NEAR(twists[3], rad(90), 1e-12);
    EXPECT_LT(closure_residual(form.geometry, canonical_angles(form, r.theta)).norm(), 1e-12) << k;
  }
  // A generic loop may need some negative twists in every representation:
  // the conventional form has no more than any other representation has.
  for (int n = 4; n <= 7; ++n) {
    for (std::uint64_t seed = 1; seed <= 4; ++seed) {
      const LoopGeometry loop = random_loop(n, 50 * n + seed);
      const CanonicalForm form = conventional_form(loop);
      EXPECT_EQ(form.key, canonical_form(loop).key);
      auto negatives = [n](const LoopGeometry& x) {
        int count = 0;
        for (int j = 0; j < n; ++j) {
          const double wrapped = std::remainder(x.alpha[j], 2.0 * 3.14159265358979323846);  // [-pi, pi]
          count += wrapped < -1e-6 && wrapped > -3.14159265358979323846 + 1e-6 ? 1 : 0;
        }
        return count;
      };
      for (std::uint64_t k = 0; k < 24; ++k) {
        const Rewritten r = rewrite(loop, random_angles(n, seed), k);
        EXPECT_LE(negatives(form.geometry), negatives(conventional_form(r.g).geometry));
        EXPECT_LE(negatives(form.geometry), negatives(r.g)) << n << " " << seed << " " << k;
      }
    }
  }
}

// The line-symmetric octahedral Bricard loop: every a_i = 0.
LoopGeometry octahedral_line_loop() {
  return LoopGeometry::from_degrees(std::vector<double>(6, 0.0), std::vector<double>{50, 70, 110, 50, 70, 110},
                                    std::vector<double>{1, 1.3, 0.7, 1, 1.3, 0.7});
}

// The loop with the twists of `links` negated and the joint angles on either
// side of each turned by pi (Rz(pi) Rx(-alpha) = Rx(alpha) Rz(pi): the same
// loop where those links have zero length).
Rewritten negate_twists(const LoopGeometry& g, const JointVector& theta, std::uint32_t links) {
  constexpr double kPi = 3.14159265358979323846;
  Rewritten r{g, theta};
  for (int k = 0; k < g.joints(); ++k) {
    if (!(links >> k & 1u)) continue;
    r.g.alpha[k] = -g.alpha[k];
    r.theta[k] += kPi;
    r.theta[(k + 1) % g.joints()] -= kPi;
  }
  return r;
}

// Where a link has zero length its twist's sign is free: the same loop
// written with any of those twists negated (and in any other
// representation) has the same key, and the form's angles close it.
TEST(Canonical, ATwistNegatedAtAZeroLengthLinkKeepsTheKey) {
  const LoopGeometry g = octahedral_line_loop();
  const VerificationSummary motion = verify_motion(g, nullptr);
  ASSERT_TRUE(motion.verified);
  const JointVector theta = motion.pose();
  ASSERT_LT(closure_residual(g, theta).norm(), 1e-12);
  const std::string key = canonical_form(g).key;
  std::uint64_t seed = 1;
  for (std::uint32_t links = 1; links < 64; ++links) {
    const Rewritten negated = negate_twists(g, theta, links);
    // The same loop: every joint axis the same line (forward kinematics). With
    // link 6's twist negated, theta_1 turns by -pi: the whole loop then turns
    // by -pi about axis 1, which is undone here.
    const Eigen::Isometry3d undo((links >> 5 & 1u) ? Eigen::AngleAxisd(3.14159265358979323846, Vector3::UnitZ())
                                                   : Eigen::AngleAxisd(0.0, Vector3::UnitZ()));
    for (int k = 0; k < 6; ++k) {
      const Eigen::Isometry3d x = forward_transform(g, theta, k);
      const Eigen::Isometry3d y = undo * forward_transform(negated.g, negated.theta, k);
      EXPECT_LT((x.translation() - y.translation()).norm(), 1e-12) << links << " " << k;
      EXPECT_LT((x.linear().col(2) - y.linear().col(2)).norm(), 1e-12) << links << " " << k;
    }
    EXPECT_EQ(canonical_form(negated.g).key, key) << links;
    const Rewritten r = rewrite(negated.g, negated.theta, ++seed);
    const CanonicalForm form = canonical_form(r.g);
    EXPECT_EQ(form.key, key) << links;
    // The negated loop closes at the adjusted angles, and the canonical
    // angles close the canonical geometry.
    EXPECT_LT(closure_residual(r.g, r.theta).norm(), 1e-11) << links;
    EXPECT_LT(closure_residual(form.geometry, canonical_angles(form, r.theta)).norm(), 1e-11) << links;
    const CanonicalForm conventional = conventional_form(r.g);
    EXPECT_EQ(conventional.key, key);
    for (int k = 0; k < 6; ++k) EXPECT_GT(conventional.geometry.alpha[k], 0.0) << links << " " << k;
    EXPECT_LT(closure_residual(conventional.geometry, canonical_angles(conventional, r.theta)).norm(), 1e-11) << links;
  }
}

// A line-symmetric 6R with parallel axes (links 1 and 4): the common normal
// between parallel axes may slide along them (d_k + s, d_{k+1} - s cos
// alpha_k) and the loop stays the same, every joint axis the same line. Any
// slide, in any representation, has the loop's key, and the representative
// closes at the canonical angles.
TEST(Canonical, ALoopWithParallelAxesHasOneKeyWhereverItsNormalsLie) {
  // Axis 5 flipped, so that link 4 joins antiparallel axes (twist pi).
  const LoopGeometry g = axis_flipped(LoopGeometry::from_degrees(std::vector<double>{1.0, 1.3, 0.8, 1.0, 1.3, 0.8},
                                                                 std::vector<double>{0, 70, 110, 0, 70, 110},
                                                                 std::vector<double>{0.2, 0.3, -0.1, 0.2, 0.3, -0.1}),
                                      4);
  ASSERT_NEAR(std::abs(g.alpha[3]), 3.14159265358979323846, 1e-15);
  const VerificationSummary motion = verify_motion(g, nullptr);
  ASSERT_TRUE(motion.verified);
  const JointVector theta = motion.pose();
  ASSERT_TRUE(has_parallel_link(g));
  ASSERT_FALSE(has_parallel_link(paper_bennett_loop()));
  const std::string key = canonical_form(g).key;
  std::uint64_t seed = 1;
  for (const auto& [s, t] : {std::pair{0.3, 0.0}, {0.0, -0.45}, {-0.2, 0.7}, {1.5, 1.5}}) {
    LoopGeometry slid = g;
    slid.d[0] += s;
    slid.d[1] -= s;  // cos(alpha_1) = 1
    slid.d[3] += t;
    slid.d[4] += t;  // cos(alpha_4) = -1: antiparallel
    for (int k = 0; k < 6; ++k) {
      const Eigen::Isometry3d x = forward_transform(g, theta, k), y = forward_transform(slid, theta, k);
      EXPECT_LT((x.translation() - y.translation()).cross(x.linear().col(2)).norm(), 1e-12) << s << " " << k;
      EXPECT_LT((x.linear().col(2) - y.linear().col(2)).norm(), 1e-12) << s << " " << k;
    }
    EXPECT_EQ(canonical_form(slid).key, key) << s << " " << t;
    EXPECT_EQ(conventional_form(slid).key, key) << s << " " << t;
    const Rewritten r = rewrite(slid, theta, ++seed);
    const CanonicalForm form = canonical_form(r.g);
    EXPECT_EQ(form.key, key) << s << " " << t;
    EXPECT_LT(closure_residual(form.geometry, canonical_angles(form, r.theta)).norm(), 1e-11) << s;
  }
  // With the twist of link 1 off parallel the same slide is another loop,
  // with another key.
  LoopGeometry skew = g;
  skew.alpha[0] = 1e-3;
  LoopGeometry skew_slid = skew;
  skew_slid.d[0] += 0.3;
  skew_slid.d[1] -= 0.3;
  EXPECT_NE(canonical_form(skew).key, canonical_form(skew_slid).key);
}

// A spherical 4R (every a_i and d_i zero) with any twist negated: the same key.
TEST(Canonical, ASphericalLoopWithATwistNegatedKeepsTheKey) {
  const LoopGeometry g = LoopGeometry::from_degrees(std::vector<double>(4, 0.0), std::vector<double>{35, 80, 65, 100},
                                                    std::vector<double>(4, 0.0));
  const std::string key = canonical_form(g).key;
  for (std::uint32_t links = 1; links < 16; ++links) {
    EXPECT_EQ(canonical_form(negate_twists(g, random_angles(4, 1), links).g).key, key) << links;
  }
}

// A link longer than the key resolves as zero (a / L rounds to a nonzero
// quantum) has a fixed twist sign: negating it gives another loop's key. Just
// below, the sign is free. A loop with no zero-length link gets no negated twist.
TEST(Canonical, ATwistNegatedAtALinkTheKeyResolvesIsAnotherLoop) {
  const double tolerance = 1e-6;
  for (double length : {0.6e-6, 0.4e-6}) {
    LoopGeometry g = octahedral_line_loop();
    g.a.setConstant(length * length_scale(g));
    const std::string key = canonical_form(g, tolerance).key;
    LoopGeometry negated = g;
    negated.alpha[0] = -negated.alpha[0];
    if (length > 0.5e-6) {
      EXPECT_NE(canonical_form(negated, tolerance).key, key);
    } else {
      EXPECT_EQ(canonical_form(negated, tolerance).key, key);
    }
  }
  for (int n = 4; n <= 8; ++n) {
    const LoopGeometry loop = random_loop(n, 900 + n);
    const CanonicalForm form = canonical_form(loop);
    EXPECT_EQ(form.negated_twists, 0u);
    LoopGeometry negated = loop;
    negated.alpha[1] = -negated.alpha[1];
    EXPECT_NE(canonical_form(negated).key, form.key) << n;
  }
}

TEST(Canonical, BadInputThrows) {
  LoopGeometry g = paper_bennett_loop();
  EXPECT_THROW(canonical_form(g, 0.0), std::invalid_argument);
  g.alpha[2] = std::nan("");
  EXPECT_THROW(canonical_form(g), std::invalid_argument);
}

}  // namespace
}  // namespace loopfarm
