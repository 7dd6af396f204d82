#include "loopfarm/search/classify.hpp"

#include <cmath>
#include <cstdint>
#include <iterator>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "allocation_counter.hpp"
#include "family_fit.hpp"
#include "loopfarm/core/sample_loops.hpp"
#include "test_support.hpp"

namespace loopfarm {
namespace {

using testing::rad;

constexpr double kTwoPi = 2 * 3.14159265358979323846;

// A representation of the same loop by loop.hpp's operations (shift, reversal, flips).
LoopGeometry rewritten(const LoopGeometry& g, int shift, bool reverse, unsigned flips) {
  LoopGeometry out = relabelled(g, shift);
  if (reverse) out = reversed(out);
  for (int j = 0; j < g.joints(); ++j) {
    if (flips >> j & 1u) out = axis_flipped(out, j);
  }
  return out;
}

const std::vector<double> kMoving(4, kTwoPi);  // every joint turns

// kAllFamilies is the enum, entry for entry, and nothing after it; names
// parse back; family_joints and has_family_distance say what family_distance
// itself accepts and refuses.
TEST(Families, TableListsEveryFamilyAndAgreesWithFamilyDistance) {
  const int count = static_cast<int>(std::size(kAllFamilies));
  for (int i = 0; i < count; ++i) EXPECT_EQ(static_cast<int>(kAllFamilies[i]), i);
  EXPECT_STREQ(to_string(static_cast<Family>(count)), "unknown");  // a new family is missing from the table
  for (Family f : kAllFamilies) {
    ASSERT_TRUE(family_from_string(to_string(f)).has_value()) << to_string(f);
    EXPECT_EQ(*family_from_string(to_string(f)), f);
    const int joints = family_joints(f);
    for (int n = 4; n <= 6; ++n) {
      const LoopGeometry g = random_loop(n, 3);
      const bool applies = has_family_distance(f) && (joints == 0 || joints == n);
      if (applies) {
        EXPECT_GE(family_distance(f, g), 0.0) << to_string(f) << " n = " << n;
      } else {
        EXPECT_THROW(family_distance(f, g), std::invalid_argument) << to_string(f) << " n = " << n;
      }
      EXPECT_EQ(family_dimension(f, n).has_value(), applies && f != Family::trivial) << to_string(f) << " n = " << n;
    }
  }
  EXPECT_FALSE(family_from_string("conic").has_value());
  EXPECT_FALSE(family_from_string("").has_value());
  EXPECT_EQ(family_dimension(Family::planar, 5), 9);
  EXPECT_EQ(family_dimension(Family::bennett, 4), 3);
  EXPECT_FALSE(family_dimension(Family::bennett, 5).has_value());
}

TEST(Classify, BennettLoopsInBothSetupsAndAnyRepresentation) {
  for (double a1 : {1.0, 2.0, 3.5}) {
    for (auto [alpha1, alpha2] : {std::pair{30.0, 90.0}, std::pair{50.0, 120.0}, std::pair{100.0, 20.0}}) {
      const LoopGeometry asym = bennett_loop(a1, rad(alpha1), rad(alpha2));
      const LoopGeometry line = bennett_loop_line_symmetric(a1, rad(alpha1), rad(alpha2));
      const Classification ca = classify(asym, bennett_angles(asym, rad(40)), kMoving);
      EXPECT_EQ(ca.family, Family::bennett);
      EXPECT_EQ(ca.setup, BennettSetup::asymmetric);
      EXPECT_LT(ca.residual, 1e-12);
      const Classification cl = classify(line, bennett_angles_line_symmetric(line, rad(40)), kMoving);
      EXPECT_EQ(cl.family, Family::bennett);
      EXPECT_EQ(cl.setup, BennettSetup::line_symmetric);
      EXPECT_LT(cl.residual, 1e-12);
      // Any representation of the loop is still a Bennett loop.
      for (unsigned flips : {0u, 5u, 6u, 13u}) {
        const LoopGeometry w = rewritten(asym, static_cast<int>(flips % 4), flips % 2 == 1, flips);
        EXPECT_EQ(classify(w, JointVector::Zero(4), kMoving).family, Family::bennett) << flips;
      }
    }
  }
}

TEST(Classify, PlanarLoopsNeedParallelAxesAndClosingOffsets) {
  const LoopGeometry crank = planar_four_bar(1.0, 3.0, 2.5, 3.5);
  EXPECT_EQ(classify(crank, JointVector::Zero(4), kMoving).family, Family::planar);
  LoopGeometry offsets = crank;
  offsets.d << 0.3, -0.3, 0.2, -0.2;
  EXPECT_EQ(classify(offsets, JointVector::Zero(4), kMoving).family, Family::planar);
  // With a twist of pi the offset after it counts the other way.
  LoopGeometry flipped = crank;
  flipped.alpha[1] = 3.14159265358979323846;
  flipped.d << 0.3, -0.3, -0.2, 0.2;  // +0.3 - 0.3, then the sign turns: -(-0.2) - 0.2 = 0
  EXPECT_EQ(classify(flipped, JointVector::Zero(4), kMoving).family, Family::planar);
  LoopGeometry open = crank;
  open.d << 0.3, 0.1, 0.0, 0.0;
  const Classification c = classify(open, JointVector::Zero(4), kMoving);
  EXPECT_NE(c.family, Family::planar);
  EXPECT_NEAR(c.checks[1].residual, 0.4 / length_scale(open), 1e-12);
}

TEST(Classify, SphericalLoop) {
  const LoopGeometry g = spherical_four_bar(rad(20), rad(70), rad(60), rad(80));
  const Classification c = classify(g, JointVector::Zero(4), kMoving);
  EXPECT_EQ(c.family, Family::spherical);
  EXPECT_EQ(c.residual, 0.0);
}

LoopGeometry coaxial_13() {
  return LoopGeometry::from_degrees(std::vector<double>{1.5, 1.5, 2.5, 2.5}, std::vector<double>{40, 40, 70, 70},
                                    std::vector<double>{0.3, 0.0, -0.3, 0.0});
}

TEST(Classify, TrivialNeedsCoincidentAxesAndAFrozenJoint) {
  const LoopGeometry g = coaxial_13();
  JointVector pose(4);
  pose << rad(30), rad(180), rad(-30), rad(180);
  const std::vector<double> travel = {kTwoPi, 0.0, kTwoPi, 0.0};
  const Classification c = classify(g, pose, travel);
  EXPECT_EQ(c.family, Family::trivial);
  EXPECT_NE(c.detail.find("axes 1 and 3"), std::string::npos) << c.detail;
  EXPECT_NE(c.detail.find("joints 2, 4 frozen"), std::string::npos) << c.detail;
  // Without a frozen joint, or without the travel, it is not called trivial.
  EXPECT_NE(classify(g, pose, kMoving).family, Family::trivial);
  EXPECT_NE(classify(g, pose, {}).family, Family::trivial);
  // Parallel axes apart from each other do not coincide (a planar loop).
  const LoopGeometry crank = planar_four_bar(1.0, 3.0, 2.5, 3.5);
  EXPECT_EQ(classify(crank, JointVector::Zero(4), travel).family, Family::planar);
  // In a pose where the axes do not coincide, neither.
  JointVector apart = pose;
  apart[1] = rad(120);
  EXPECT_NE(classify(g, apart, travel).family, Family::trivial);
}

TEST(Classify, GenericAndNearlyMovableLoopsAreUnclassified) {
  for (std::uint64_t seed = 1; seed <= 5; ++seed) {
    const Classification c = classify(random_loop(4, seed), random_angles(4, seed), kMoving);
    EXPECT_EQ(c.family, Family::unclassified) << seed;
    for (const FamilyCheck& check : c.checks) EXPECT_GT(check.residual, 1e-3) << seed << to_string(check.family);
  }
  LoopGeometry g = paper_bennett_loop();
  g.a[0] += 1e-3;
  const Classification c = classify(g, bennett_angles(paper_bennett_loop(), rad(40)), kMoving);
  EXPECT_EQ(c.family, Family::unclassified);
  // Two Bennett conditions are off, a1 - a3 and a2 sin(alpha1) - a1 sin(alpha2)
  // (sin(alpha2) = 1), each by 1e-3 in units of L; the residual is the largest
  // condition, 1e-3 / L exactly (to round-off).
  EXPECT_NEAR(c.checks[0].residual, 1e-3 / length_scale(g), 1e-12);
  EXPECT_NE(c.detail.find("bennett"), std::string::npos) << c.detail;
}

TEST(FamilyDistance, ZeroOnTheFamilyPositiveOffItInvariantUnderRepresentation) {
  struct Case {
    Family family;
    LoopGeometry member;
  };
  const Case cases[] = {{Family::bennett, bennett_loop(2.0, rad(40), rad(110))},
                        {Family::planar, planar_four_bar(1.0, 3.0, 2.5, 3.5)},
                        {Family::spherical, spherical_four_bar(rad(20), rad(70), rad(60), rad(80))},
                        {Family::trivial, coaxial_13()}};
  for (const Case& c : cases) {
    EXPECT_LT(family_distance(c.family, c.member), 1e-12) << to_string(c.family);
    const LoopGeometry generic = random_loop(4, 9);
    const double d = family_distance(c.family, generic);
    EXPECT_GT(d, 1e-2) << to_string(c.family);
    for (unsigned flips : {3u, 9u, 14u}) {
      const LoopGeometry w = rewritten(generic, static_cast<int>(flips % 4), flips % 2 == 0, flips);
      EXPECT_NEAR(family_distance(c.family, w), d, 1e-12 * std::max(1.0, d)) << to_string(c.family) << flips;
    }
  }
}

TEST(FamilyDistance, GradientAgreesWithCentralDifferences) {
  for (Family family : {Family::bennett, Family::planar, Family::spherical, Family::trivial}) {
    for (std::uint64_t seed : {11u, 12u}) {
      LoopGeometry g = random_loop(4, seed);
      GeometryVector gradient;
      family_distance(family, g, &gradient);
      GeometryVector fd(12);
      for (int j = 0; j < 12; ++j) {
        auto at = [&](double h) {
          LoopGeometry m = g;
          double& p = j < 4 ? m.a[j] : (j < 8 ? m.alpha[j - 4] : m.d[j - 8]);
          p += h;
          return family_distance(family, m);
        };
        fd[j] = (at(1e-6) - at(-1e-6)) / 2e-6;
      }
      EXPECT_LT((gradient - fd).cwiseAbs().maxCoeff(), 1e-6 * std::max(1.0, fd.cwiseAbs().maxCoeff()))
          << to_string(family) << " " << seed << "\n"
          << gradient.transpose() << "\n"
          << fd.transpose();
    }
  }
}

// Geometries for comparing the numeric and the reporting path of
// family_distance: generic loops, twists far outside (-pi, pi], loops near
// (and on) each family, and exact special values (zero and negative-zero
// lengths and offsets, twists of 0, +-pi/2, +-pi) where many representations tie.
LoopGeometry comparison_geometry(int n, std::uint64_t seed) {
  constexpr double kPi = 3.14159265358979323846;
  std::mt19937_64 rng(seed);
  auto uniform = [&](double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng); };
  auto pick = [&](int count) { return static_cast<int>(rng() % static_cast<std::uint64_t>(count)); };
  LoopGeometry g = random_loop(n, seed);
  switch (seed % 6) {
    case 0:
      break;  // generic
    case 1:   // twists written with extra turns and half turns
      for (int k = 0; k < n; ++k) g.alpha[k] += (pick(7) - 3) * kPi;
      break;
    case 2:  // near planar: twists tiny, 0, pi or -pi
      for (int k = 0; k < n; ++k) {
        const double exact[] = {0.0, kPi, -kPi};
        g.alpha[k] = exact[pick(3)] + (pick(2) ? 0.0 : uniform(-1.0, 1.0) * std::pow(10.0, -uniform(1, 12)));
      }
      break;
    case 3: {  // near trivial: two adjacent axes (nearly) coincide, or (4R) axes 1 and 3
      const int j = pick(n);
      const double noise = pick(2) ? 0.0 : std::pow(10.0, -uniform(2, 12));
      if (n == 4 && pick(2)) {
        g = LoopGeometry::from_degrees(std::vector<double>{1.5, 1.5, 2.5, 2.5}, std::vector<double>{40, 40, 70, 70},
                                       std::vector<double>{0.3, 0.0, -0.3, 0.0});
        g.d[j] += noise;
      } else {
        g.a[j] = noise;
        g.alpha[j] = (pick(2) ? 0.0 : kPi) + noise;
      }
      break;
    }
    case 4:  // near Bennett (4R), else offsets all zero
      if (n == 4) {
        g = pick(2) ? bennett_loop(uniform(0.5, 3), uniform(0.1, 3), uniform(0.1, 3))
                    : bennett_loop_line_symmetric(uniform(0.5, 3), uniform(0.1, 3), uniform(0.1, 3));
        if (pick(2)) g.a[pick(4)] += std::pow(10.0, -uniform(2, 12));
      } else {
        g.d.setZero();
      }
      break;
    case 5:  // exact special values
      for (int k = 0; k < n; ++k) {
        const double twists[] = {0.0, kPi / 2, -kPi / 2, kPi, -kPi};
        const double lengths[] = {0.0, -0.0, 1.0, 2.0};
        const double offsets[] = {0.0, -0.0, 0.5, -0.5};
        g.alpha[k] = twists[pick(5)];
        if (pick(2)) g.a[k] = lengths[pick(4)];
        if (pick(2)) g.d[k] = offsets[pick(4)];
      }
      break;
  }
  return g;
}

// The numeric path (family_distance) gives the distance and gradient of the
// reporting path (family_distance_report, which names the conditions of the
// representation it writes out; that it picks what writing every
// representation out picks is FamilyFit's test). Required to 1e-14 relative;
// by construction (the same formulas on the same numbers, in the same order)
// they agree bit for bit.
TEST(FamilyDistance, NumericPathEqualsTheReportingPath) {
  const int geometries_per_n[] = {0, 0, 0, 0, 600, 120, 60, 30, 18};
  long compared = 0, identical = 0;
  for (int n = kMinJoints; n <= kMaxJoints; ++n) {
    for (std::uint64_t seed = 0; seed < static_cast<std::uint64_t>(geometries_per_n[n]); ++seed) {
      const LoopGeometry g = comparison_geometry(n, 1000 * static_cast<std::uint64_t>(n) + seed);
      for (Family family : {Family::bennett, Family::planar, Family::spherical, Family::trivial}) {
        if (family == Family::bennett && n != 4) continue;
        GeometryVector reference_gradient, gradient;
        const FamilyCheck reference = family_distance_report(family, g, &reference_gradient);
        const double value = family_distance(family, g);
        const double value_with_gradient = family_distance(family, g, &gradient);
        const auto where = [&] {
          return std::string(to_string(family)) + " n=" + std::to_string(n) + " seed=" + std::to_string(seed);
        };
        EXPECT_LE(std::abs(value - reference.residual), 1e-14 * std::abs(reference.residual)) << where();
        EXPECT_EQ(value_with_gradient, value) << where();
        ASSERT_EQ(gradient.size(), 3 * n) << where();
        EXPECT_LE((gradient - reference_gradient).cwiseAbs().maxCoeff(),
                  1e-14 * reference_gradient.cwiseAbs().maxCoeff())
            << where() << "\n"
            << gradient.transpose() << "\n"
            << reference_gradient.transpose();
        ++compared;
        if (value == reference.residual && gradient == reference_gradient) ++identical;
      }
    }
  }
  EXPECT_EQ(identical, compared) << "the paths should agree bit for bit";
}

// The algorithm as it was, as the reference: every representation written
// out, every condition set evaluated with its names, the first of the least
// scores kept.
template <Family F>
detail::Best every_representation_written_out(const LoopGeometry& g, bool by_norm) {
  detail::Best best;
  const int sets = detail::condition_sets(F, g.joints());
  for (const detail::Representation& r : detail::representations(g.joints())) {
    const detail::WrittenOut w(detail::apply(r, g));
    for (int set = 0; set < sets; ++set) {
      detail::Conditions c;
      detail::condition_set<F>(set, w, c);
      const double score = by_norm ? c.norm() : c.max_abs();
      if (score < best.score) {
        best.score = score;
        best.conditions = std::move(c);
        best.representation = &r;
        best.set = set;
      }
    }
  }
  return best;
}

template <Family F>
void expect_same_pick(const LoopGeometry& g, const std::string& where, long& compared) {
  for (bool by_norm : {false, true}) {
    const detail::Best reference = every_representation_written_out<F>(g, by_norm);
    const detail::Best best = detail::best_over_representations<F>(g, by_norm);
    const std::string what = where + " " + to_string(F) + (by_norm ? " by norm" : " by max");
    ASSERT_EQ(best.representation, reference.representation) << what;
    EXPECT_EQ(best.set, reference.set) << what;
    EXPECT_EQ(best.score, reference.score) << what;
    EXPECT_EQ(best.conditions.names, reference.conditions.names) << what;
    EXPECT_EQ(best.conditions.values, reference.conditions.values) << what;
    ++compared;
  }
}

// Classification picks the best representation by the numeric path's search
// (tables, a running score, representations given up early) and writes out
// only that one: it picks what writing every representation out picks, first
// of equals included (the geometries hold exact special values, so ties are
// common), with the same conditions bit for bit.
TEST(FamilyFit, PicksTheRepresentationThatWritingEveryOneOutPicks) {
  const int geometries_per_n[] = {0, 0, 0, 0, 300, 60, 24};
  long compared = 0;
  for (int n = kMinJoints; n <= 6; ++n) {
    for (std::uint64_t seed = 0; seed < static_cast<std::uint64_t>(geometries_per_n[n]); ++seed) {
      const LoopGeometry g = comparison_geometry(n, 7000 + 1000 * static_cast<std::uint64_t>(n) + seed);
      const std::string where = "n=" + std::to_string(n) + " seed=" + std::to_string(seed);
      expect_same_pick<Family::planar>(g, where, compared);
      expect_same_pick<Family::trivial>(g, where, compared);
      if (n == 4) expect_same_pick<Family::bennett>(g, where, compared);
      if (n == 5) {
        expect_same_pick<Family::goldberg>(g, where, compared);
        expect_same_pick<Family::myard>(g, where, compared);
        expect_same_pick<Family::goldberg_bent>(g, where, compared);
      }
      if (n == 6) {
        expect_same_pick<Family::bricard_line_symmetric>(g, where, compared);
        expect_same_pick<Family::bricard_plane_symmetric>(g, where, compared);
        expect_same_pick<Family::bricard_trihedral>(g, where, compared);
        expect_same_pick<Family::bennett_pair>(g, where, compared);
        expect_same_pick<Family::bennett_dyads>(g, where, compared);
        expect_same_pick<Family::sarrus>(g, where, compared);
        expect_same_pick<Family::waldron_hybrid>(g, where, compared);
        expect_same_pick<Family::double_goldberg>(g, where, compared);
        expect_same_pick<Family::hooke>(g, where, compared);
        expect_same_pick<Family::bricard_octahedral_collapsible>(g, where, compared);
        // The Goldberg 6R fit differentiates itself by central differences
        // in every representation written out: one geometry is enough.
        if (seed == 0) expect_same_pick<Family::goldberg_6r>(g, where, compared);
      }
    }
  }
  EXPECT_EQ(compared, 2 * (300 * 3 + 60 * 5 + 24 * 12 + 1));
}

// The reporting path names the best representation's conditions.
TEST(FamilyDistance, ReportListsTheBestRepresentationsConditions) {
  LoopGeometry g = planar_four_bar(1.0, 3.0, 2.5, 3.5);
  g.d << 0.3, 0.1, 0.0, 0.0;
  const FamilyCheck planar = family_distance_report(Family::planar, g);
  ASSERT_EQ(planar.conditions.size(), 5u);
  EXPECT_EQ(planar.conditions[0].name, "sin(alpha1)");
  EXPECT_EQ(planar.conditions[4].name, "signed sum of d / L");
  EXPECT_NEAR(std::abs(planar.conditions[4].residual), 0.4 / length_scale(g), 1e-15);
  EXPECT_EQ(planar.residual, family_distance(Family::planar, g));
  const FamilyCheck bennett = family_distance_report(Family::bennett, bennett_loop_line_symmetric(2.0, 0.5, 1.2));
  EXPECT_EQ(bennett.setup, BennettSetup::line_symmetric);
  EXPECT_LT(bennett.residual, 1e-12);
}

// The steered search calls family_distance on every evaluation: after the
// first call for a joint count (which builds its table of representations), a call
// allocates nothing, with or without the gradient.
TEST(FamilyDistance, RepeatedCallsDoNotAllocate) {
  if (!testing::kCountsAllocations) GTEST_SKIP() << "allocations are not counted under AddressSanitizer";
  for (int n = kMinJoints; n <= kMaxJoints; ++n) {
    const LoopGeometry g = random_loop(n, 21);
    for (Family family : {Family::bennett, Family::planar, Family::spherical, Family::trivial}) {
      if (family == Family::bennett && n != 4) continue;
      GeometryVector gradient;
      const double first = family_distance(family, g, &gradient);
      const GeometryVector first_gradient = gradient;
      const long before = testing::allocations();
      const double again = family_distance(family, g, &gradient);
      const double value = family_distance(family, g);
      EXPECT_EQ(testing::allocations() - before, 0) << to_string(family) << " n=" << n;
      EXPECT_EQ(again, first) << to_string(family) << " n=" << n;
      EXPECT_EQ(value, first) << to_string(family) << " n=" << n;
      EXPECT_TRUE(gradient == first_gradient) << to_string(family) << " n=" << n;
    }
  }
}

TEST(Classify, BadInputThrows) {
  const LoopGeometry g = paper_bennett_loop();
  EXPECT_THROW(classify(g, JointVector::Zero(3), kMoving), std::invalid_argument);
  EXPECT_THROW(classify(g, JointVector::Zero(4), std::vector<double>(3, 0.0)), std::invalid_argument);
  EXPECT_THROW(family_distance(Family::bennett, random_loop(5, 1)), std::invalid_argument);
  EXPECT_THROW(family_distance(Family::unclassified, g), std::invalid_argument);
  EXPECT_THROW(family_distance_report(Family::bennett, random_loop(5, 1)), std::invalid_argument);
  EXPECT_THROW(family_distance_report(Family::unclassified, g), std::invalid_argument);
}

}  // namespace
}  // namespace loopfarm
