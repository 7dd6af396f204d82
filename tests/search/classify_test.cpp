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
#include "loopfarm/search/verify.hpp"
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
      // cubic_321 is decided at a pose (no distance) but has a dimension.
      const bool dimension = (applies && f != Family::trivial) || (f == Family::cubic_321 && n == 6);
      EXPECT_EQ(family_dimension(f, n).has_value(), dimension) << to_string(f) << " n = " << n;
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
  // Every axis parallel: the classifier reads the offsets with the normals
  // centred (0.1 each), and lengths in units of that loop's scale.
  EXPECT_NEAR(c.checks[1].residual, 0.4 / length_scale(centred_parallel_normals(open, 1e-8)), 1e-12);
  EXPECT_NEAR(length_scale(centred_parallel_normals(open, 1e-8)), std::sqrt((1.0 + 9.0 + 6.25 + 12.25 + 4 * 0.01) / 4),
              1e-14);
}

TEST(Classify, ALoopWithALengthWhoseSquareOverflowsIsRefused) {
  // With an infinite length scale every length / L reads 0: such a loop once
  // read spherical with residual 0. It is refused, naming the length.
  LoopGeometry g = random_loop(6, 3);
  g.a[0] = 1e200;
  try {
    classify(g, JointVector::Zero(6), std::vector<double>(6, kTwoPi));
    ADD_FAILURE() << "accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("a1: 1e+200 is too large"), std::string::npos) << e.what();
  }
}

// A condition that cannot be evaluated (NaN) fails its family instead of
// being skipped: the max over a set keeps a NaN, so the set never fits.
TEST(Classify, ANaNConditionFailsItsSet) {
  EXPECT_TRUE(std::isnan(detail::max_abs_step(0.0, std::nan(""))));
  EXPECT_TRUE(std::isnan(detail::max_abs_step(std::nan(""), 5.0)));
  EXPECT_EQ(detail::max_abs_step(2.0, -3.0), 3.0);
  EXPECT_EQ(detail::max_abs_step(2.0, 1.0), 2.0);
  detail::Conditions c;
  c.values = {1e-12, std::nan(""), 1e-13};
  EXPECT_FALSE(c.max_abs() <= 1e-8);
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
    const detail::Best best = detail::best_over_representations<F>(g, by_norm, detail::kNoZeroLength);
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
        expect_same_pick<Family::bennett_triads>(g, where, compared);
        expect_same_pick<Family::coupled_bennett_dyads>(g, where, compared);
        expect_same_pick<Family::sarrus>(g, where, compared);
        expect_same_pick<Family::waldron_hybrid>(g, where, compared);
        expect_same_pick<Family::double_goldberg>(g, where, compared);
        expect_same_pick<Family::hooke>(g, where, compared);
        expect_same_pick<Family::bricard_octahedral_collapsible>(g, where, compared);
        expect_same_pick<Family::angle_symmetric_parallel>(g, where, compared);
        // The Goldberg 6R fit differentiates itself by central differences
        // in every representation written out: one geometry is enough.
        if (seed == 0) expect_same_pick<Family::goldberg_6r>(g, where, compared);
      }
    }
  }
  EXPECT_EQ(compared, 2 * (300 * 3 + 60 * 5 + 24 * 15 + 1));
}

// The least max |condition| over every representation and every set of
// negated twists at the links `free` (one bit per link), each written out as
// the geometry with those twists negated, its score the larger of its
// conditions' and max a_k / L over the negated links: the reference for the
// search over twist signs.
template <Family F>
double least_over_twist_signs_written_out(const LoopGeometry& g, std::uint32_t free) {
  double least = detail::kInf;
  const double L = length_scale(g);
  for (std::uint32_t links = 0; links < (1u << g.joints()); ++links) {
    if ((links & ~free) != 0u) continue;
    double zero = 0.0;
    for (int k = 0; k < g.joints(); ++k) {
      if (links >> k & 1u) zero = std::max(zero, g.a[k] / L);
    }
    const LoopGeometry negated = detail::with_negated_twists(g, links);
    for (const detail::Representation& r : detail::representations(g.joints())) {
      const detail::WrittenOut w(detail::apply(r, negated));
      for (int set = 0; set < detail::condition_sets(F, g.joints()); ++set) {
        detail::Conditions c;
        detail::condition_set<F>(set, w, c);
        least = std::min(least, std::max(c.max_abs(), zero));
      }
    }
  }
  return least;
}

// A loop with some links of zero length (or within the tolerance of it) and
// the twists there of random sign.
LoopGeometry with_zero_length_links(int n, std::uint64_t seed, double tolerance) {
  std::mt19937_64 rng(seed);
  LoopGeometry g = comparison_geometry(n, seed);
  const double L = length_scale(g);
  for (int k = 0; k < n; ++k) {
    if (rng() % 2) g.a[k] = (rng() % 2) ? 0.0 : 0.5 * tolerance * L;
  }
  return g;
}

template <Family F>
void expect_least_over_twist_signs(const LoopGeometry& g, double tolerance, const std::string& where) {
  const detail::Best best = detail::best_over_representations<F>(g, false, tolerance);
  const bool signs = detail::reads_twist_signs(F, g.joints());
  const std::uint32_t free = signs ? detail::zero_length_links(g, tolerance) : 0u;
  const double reference = least_over_twist_signs_written_out<F>(g, free);
  const std::string what = where + " " + to_string(F);
  EXPECT_EQ(best.score, reference) << what;
  // The pick written out scores what the search scored.
  ASSERT_NE(best.representation, nullptr) << what;
  EXPECT_EQ((best.negated_twists & ~free), 0u) << what;
  detail::Conditions c;
  detail::condition_set<F>(best.set, detail::WrittenOut(detail::written_out(best, g)), c);
  double zero = 0.0;
  for (int k = 0; k < g.joints(); ++k) {
    if (best.negated_twists >> k & 1u) zero = std::max(zero, g.a[k] / length_scale(g));
  }
  EXPECT_EQ(std::max(c.max_abs(), zero), best.score) << what;
  // A family that reads no twist sign scores the same whichever signs (to
  // round-off: a negated twist plus pi rounds differently).
  if (!signs) {
    EXPECT_NEAR(least_over_twist_signs_written_out<F>(g, detail::zero_length_links(g, tolerance)), reference, 1e-14)
        << what;
  }
}

// Classification takes the twist sign at every zero-length link as free: its
// search finds the least score over every representation and every set of
// negated twists there, written out one by one. The families it does not
// search over signs (reads_twist_signs) score the same whichever sign.
TEST(FamilyFit, TakesTheLeastOverTheTwistSignsAtZeroLengthLinks) {
  const double tolerance = 1e-8;
  int compared = 0;
  for (std::uint64_t seed = 0; seed < 12; ++seed) {
    const std::string where = "seed=" + std::to_string(seed);
    const LoopGeometry g4 = with_zero_length_links(4, 100 + seed, tolerance);
    expect_least_over_twist_signs<Family::bennett>(g4, tolerance, where);
    expect_least_over_twist_signs<Family::planar>(g4, tolerance, where);
    expect_least_over_twist_signs<Family::trivial>(g4, tolerance, where);
    const LoopGeometry g5 = with_zero_length_links(5, 200 + seed, tolerance);
    expect_least_over_twist_signs<Family::trivial>(g5, tolerance, where);
    expect_least_over_twist_signs<Family::goldberg>(g5, tolerance, where);
    if (seed < 2) {
      const LoopGeometry g6 = with_zero_length_links(6, 300 + seed, tolerance);
      expect_least_over_twist_signs<Family::bricard_line_symmetric>(g6, tolerance, where);
      expect_least_over_twist_signs<Family::bricard_plane_symmetric>(g6, tolerance, where);
      expect_least_over_twist_signs<Family::bricard_trihedral>(g6, tolerance, where);
      expect_least_over_twist_signs<Family::bricard_octahedral_plane>(g6, tolerance, where);
      expect_least_over_twist_signs<Family::bricard_octahedral_collapsible>(g6, tolerance, where);
      expect_least_over_twist_signs<Family::sarrus>(g6, tolerance, where);
    }
    ++compared;
  }
  EXPECT_EQ(compared, 12);
}

// The line-symmetric octahedral Bricard loop (every a_i = 0) and the same
// loop with twists negated: classify's tolerance (1e-8) decides which links
// count as zero-length.
const LoopGeometry kOctahedralLine =
    LoopGeometry::from_degrees(std::vector<double>(6, 0.0), std::vector<double>{50, 70, 110, 50, 70, 110},
                               std::vector<double>{1, 1.3, 0.7, 1, 1.3, 0.7});

// A closed pose of its motion and every joint's travel there (the motion
// as verify traces it).
struct Posed {
  JointVector pose;
  std::vector<double> travel;
};
Posed octahedral_line_motion() {
  const VerificationSummary motion = verify_motion(kOctahedralLine, nullptr);
  EXPECT_TRUE(motion.verified);
  return {motion.pose(), std::vector<double>(motion.joint_travel.data(), motion.joint_travel.data() + 6)};
}

// The joint axes of a loop at angles theta, as lines: each joint's origin
// and direction (forward kinematics, independent of the representations).
std::vector<std::pair<Vector3, Vector3>> joint_axes(const LoopGeometry& g, const JointVector& theta) {
  std::vector<std::pair<Vector3, Vector3>> axes;
  for (int k = 0; k < g.joints(); ++k) {
    const Eigen::Isometry3d frame = forward_transform(g, theta, k);
    axes.push_back({frame.translation(), frame.linear().col(2)});
  }
  return axes;
}

TEST(Classify, ATwistNegatedAtAZeroLengthLinkIsTheSameLoopAndFamily) {
  const LoopGeometry& g = kOctahedralLine;
  const Posed posed = octahedral_line_motion();
  const JointVector& theta = posed.pose;
  ASSERT_LT(closure_residual(g, theta).norm(), 1e-12);
  const std::vector<double>& travel = posed.travel;
  const Classification as_written = classify(g, theta, travel);
  ASSERT_EQ(as_written.family, Family::bricard_line_symmetric) << as_written.detail;
  ASSERT_LE(as_written.residual, 1e-12);
  const auto axes = joint_axes(g, theta);
  std::mt19937_64 rng(17);
  // Each twist negated alone, then random sets of them.
  std::vector<std::uint32_t> sets;
  for (int k = 0; k < 6; ++k) sets.push_back(1u << k);
  for (int i = 0; i < 12; ++i) sets.push_back(static_cast<std::uint32_t>(rng() % 63 + 1));
  for (std::uint32_t links : sets) {
    const std::string where = "negated " + std::to_string(links);
    LoopGeometry negated = g;
    JointVector angles = theta;
    for (int k = 0; k < 6; ++k) {
      if (!(links >> k & 1u)) continue;
      negated.alpha[k] = -g.alpha[k];
      angles[k] += 3.14159265358979323846;
      angles[(k + 1) % 6] -= 3.14159265358979323846;
    }
    // The same loop: it closes at the adjusted angles, with every joint axis
    // the same line in space.
    EXPECT_LT(closure_residual(negated, angles).norm(), 1e-12) << where;
    auto negated_axes = joint_axes(negated, angles);
    if (links >> 5 & 1u) {
      // theta_1 turned by -pi turns the whole loop by -pi about axis 1: undone.
      const Eigen::AngleAxisd undo(3.14159265358979323846, Vector3::UnitZ());
      for (auto& [origin, direction] : negated_axes) {
        origin = undo * origin;
        direction = undo * direction;
      }
    }
    for (int k = 0; k < 6; ++k) {
      EXPECT_LT((negated_axes[k].first - axes[k].first).norm(), 1e-12) << where << " joint " << k;
      EXPECT_LT((negated_axes[k].second - axes[k].second).norm(), 1e-12) << where << " joint " << k;
    }
    // The same family, to round-off as written.
    const Classification c = classify(negated, angles, travel);
    EXPECT_EQ(c.family, Family::bricard_line_symmetric) << where << ": " << c.detail;
    EXPECT_LE(c.residual, 1e-12) << where;
    EXPECT_EQ(c.detail, as_written.detail) << where;
    // The twists as written fit only where the negated set is itself
    // line-symmetric (links i and i + 3 both or neither): elsewhere the sign
    // freedom made the difference.
    if ((links & 7u) == (links >> 3)) {
      EXPECT_LT(family_distance(Family::bricard_line_symmetric, negated), 1e-12) << where;
    } else {
      EXPECT_GT(family_distance(Family::bricard_line_symmetric, negated), 0.1) << where;
    }
  }
}

TEST(Classify, ATwistNegatedAtALinkLongerThanTheToleranceIsAnotherLoop) {
  // Every a_i just above classify's tolerance (1e-8 L): the twists' signs are
  // no longer free, and the loop with alpha1 negated is not line-symmetric.
  LoopGeometry g = kOctahedralLine;
  g.a.setConstant(3e-8 * length_scale(g));
  LoopGeometry negated = g;
  negated.alpha[0] = -negated.alpha[0];
  const Posed posed = octahedral_line_motion();
  const JointVector& theta = posed.pose;
  const std::vector<double>& travel = posed.travel;
  EXPECT_EQ(detail::zero_length_links(negated, 1e-8), 0u);
  const FamilyCheck line = detail::family_check(Family::bricard_line_symmetric, negated, 1e-8);
  EXPECT_GT(line.residual, 0.1);
  EXPECT_NE(classify(negated, theta, travel).family, Family::bricard_line_symmetric);
  // Written as it is, it still fits (to its lengths' size).
  EXPECT_LE(detail::family_check(Family::bricard_line_symmetric, g, 1e-8).residual, 1e-12);
  // Just below the tolerance the sign is free again, at the cost of a_k / L.
  LoopGeometry close = negated;
  close.a.setConstant(0.5e-8 * length_scale(kOctahedralLine));
  const FamilyCheck fits = detail::family_check(Family::bricard_line_symmetric, close, 1e-8);
  EXPECT_LE(fits.residual, 1e-8);
  EXPECT_GE(fits.residual, 0.4e-8);
  EXPECT_NE(fits.conditions.back().name.find("negated"), std::string::npos) << fits.conditions.back().name;
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
