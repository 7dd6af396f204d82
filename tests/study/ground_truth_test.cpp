// The ground-truth set, each label checked by a method independent of how the
// case was built: movable cases by the rigid verification (verify.hpp), the
// classifier (classify.hpp) and the cycle energy (cycle.hpp); rigid ones by
// the same tools failing to find a motion.
#include "loopfarm/study/ground_truth.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "loopfarm/core/assembly.hpp"
#include "loopfarm/core/cycle.hpp"
#include "loopfarm/search/classify.hpp"
#include "loopfarm/search/verify.hpp"
#include "test_support.hpp"

namespace loopfarm {
namespace {

using testing::rad;

constexpr double kPi = 3.14159265358979323846;

// The set the expensive checks run on: 12 cases per family cover every
// planar variant and trivial representation 4 times and every perturbed parameter
// at least 3 times, in well under a second.
constexpr int kCasesPerFamily = 12;
constexpr int kGenericLoops = 12;
GroundTruthOptions small_set() {
  GroundTruthOptions options;
  options.seed = 1;
  options.cases_per_family = kCasesPerFamily;
  options.generic_loops = kGenericLoops;
  return options;
}

// Max-norm of the closure residual, translation in units of L (computed
// here, not taken from the case).
double closure_error(const LoopGeometry& g, const JointVector& theta) {
  const Vector6 r = closure_residual(g, theta);
  const double L = length_scale(g);
  return std::max(r.head<3>().cwiseAbs().maxCoeff(), r.tail<3>().cwiseAbs().maxCoeff() / L);
}

struct CycleResult {
  EquilibriumSummary assembly;
  CycleSummary cycle;
};

// The cycle energy over a full turn from the elastic assembly at `pose`.
CycleResult cycle_from(const LoopGeometry& g, const JointVector& pose) {
  const LoopModel model(g);
  EquilibriumWorkspace workspace(model);
  CycleResult out;
  out.assembly = assemble_from_angles(model, workspace, pose);
  cycle_energy(model, workspace, pose[0], out.assembly.state, CycleOptions{}, out.cycle);
  return out;
}

bool same_bits(const JointVector& x, const JointVector& y) {
  return x.size() == y.size() && std::memcmp(x.data(), y.data(), sizeof(double) * static_cast<size_t>(x.size())) == 0;
}

bool same_bits(double x, double y) { return std::memcmp(&x, &y, sizeof x) == 0; }

bool same_case(const GroundTruthCase& x, const GroundTruthCase& y) {
  return x.id == y.id && x.family == y.family && x.setup == y.setup && x.movable == y.movable &&
         x.full_turn == y.full_turn && x.parent == y.parent && x.perturbed_parameter == y.perturbed_parameter &&
         same_bits(x.relative_perturbation, y.relative_perturbation) && same_bits(x.geometry.a, y.geometry.a) &&
         same_bits(x.geometry.alpha, y.geometry.alpha) && same_bits(x.geometry.d, y.geometry.d) &&
         same_bits(x.pose, y.pose) && same_bits(x.pose_residual, y.pose_residual);
}

std::vector<double> travel_of(const VerificationSummary& v) {
  return std::vector<double>(v.joint_travel.data(), v.joint_travel.data() + v.joint_travel.size());
}

// ---------------------------------------------------------------------------

TEST(GroundTruth, EveryMovableCaseClosesMovesOverAFullTurnAndIsClassifiedInItsFamily) {
  GroundTruthOptions options = small_set();
  options.relative_perturbations.clear();
  int movable = 0;
  std::map<GroundTruthFamily, int> per_family;
  for (const GroundTruthCase& c : generate_ground_truth(options)) {
    if (!c.movable) continue;
    SCOPED_TRACE(c.id);
    ++movable;
    ++per_family[c.family];
    EXPECT_LE(closure_error(c.geometry, c.pose), 1e-12);
    EXPECT_LE(c.pose_residual, 1e-12);

    const VerificationSummary v = verify_motion(c.geometry, c.pose);
    EXPECT_TRUE(v.assembled);
    EXPECT_TRUE(v.verified) << v.limit;
    EXPECT_EQ(v.full_turn, c.full_turn) << v.limit;
    EXPECT_LT(v.worst_residual, 1e-12);
    // The verification's own solve at the start left the pose where it was:
    // it was closed already (a full turn walks forward only, so the path
    // starts there).
    if (v.full_turn) {
      for (int k = 0; k < 4; ++k) EXPECT_NEAR(wrap_angle(v.joint_angles.front()[k] - c.pose[k]), 0.0, 1e-12);
    }

    const Classification k = classify(c.geometry, c.pose, travel_of(v));
    EXPECT_EQ(k.family, expected_classification(c)) << k.detail;
    EXPECT_EQ(k.setup, c.setup) << k.detail;
    if (c.family == GroundTruthFamily::trivial) {
      // The coaxial 1-3 motion in every representation: joints 2 and 4 frozen.
      EXPECT_EQ(k.detail, "axes 1 and 3 coincide; joints 2, 4 frozen");
    }
  }
  EXPECT_EQ(movable, 5 * options.cases_per_family);
  EXPECT_EQ(per_family[GroundTruthFamily::bennett], 2 * options.cases_per_family);
  EXPECT_EQ(per_family[GroundTruthFamily::planar], options.cases_per_family);
  EXPECT_EQ(per_family[GroundTruthFamily::spherical], options.cases_per_family);
  EXPECT_EQ(per_family[GroundTruthFamily::trivial], options.cases_per_family);
}

TEST(GroundTruth, EveryMovableCaseNeedsNoEnergyOverAFullTurnFromItsPose) {
  GroundTruthOptions options = small_set();
  options.relative_perturbations.clear();
  for (const GroundTruthCase& c : generate_ground_truth(options)) {
    if (!c.movable) continue;
    SCOPED_TRACE(c.id);
    const CycleResult r = cycle_from(c.geometry, c.pose);
    EXPECT_EQ(r.assembly.status, SolveStatus::converged);
    // A closed pose is its own equilibrium.
    for (int k = 0; k < 4; ++k) EXPECT_NEAR(wrap_angle(r.assembly.state.theta[k] - c.pose[k]), 0.0, 1e-9);
    EXPECT_LT(r.cycle.E_max, 1e-20);
    EXPECT_EQ(r.cycle.failed_samples, 0);
    EXPECT_EQ(r.cycle.branch_jumps, 0);
  }
}

TEST(GroundTruth, PerturbationsOfAtLeast1e3DoNotMoveAndCostEnergy) {
  const std::vector<GroundTruthCase> cases = generate_ground_truth(small_set());
  std::map<std::string, const GroundTruthCase*> by_id;
  for (const GroundTruthCase& c : cases) by_id[c.id] = &c;
  int checked = 0;
  for (const GroundTruthCase& c : cases) {
    if (c.parent.empty() || c.relative_perturbation < 1e-3) continue;
    SCOPED_TRACE(c.id);
    ++checked;
    EXPECT_FALSE(c.movable);
    const VerificationSummary v = verify_motion(c.geometry, c.pose);
    EXPECT_FALSE(v.verified) << "range " << v.range_lo << " .. " << v.range_hi;
    // Not even one closed pose near the parent's.
    EXPECT_FALSE(v.assembled) << v.worst_residual;
    const CycleResult r = cycle_from(c.geometry, c.pose);
    // The energy grows as the square of the perturbation: E_mean / eps^2
    // is 0.09 ... 6 over these families (docs/quality/ground-truth.md), far above
    // the zero threshold (1e-20) at eps = 1e-3. Spherical loops are further
    // still: their one length is the whole length scale.
    const double eps = c.relative_perturbation;
    EXPECT_GT(r.cycle.E_mean, 1e-2 * eps * eps) << "E_max " << r.cycle.E_max;
    if (by_id.at(c.parent)->family == GroundTruthFamily::spherical) {
      EXPECT_GT(r.cycle.E_mean, 1e-3);
    }
  }
  EXPECT_EQ(checked, 5 * kCasesPerFamily * 2);  // 1e-2 and 1e-3 of every movable case
}

// The law docs/quality/ground-truth.md states: below 1e-3 the energy of a perturbed
// loop grows as c eps^2, at every size it lists down to 1e-8. Each case's
// E_mean / eps^2 at 1e-4, 1e-5, 1e-7 and 1e-8 is within a factor 2 of its
// value at 1e-6 (the page's criterion), and every energy is far above the
// zero threshold 1e-20. Spherical loops have no eps^2 law (their one length
// is the length scale; the test above).
TEST(GroundTruth, PerturbedEnergiesFollowTheSquareLawDownTo1e8) {
  GroundTruthOptions options = small_set();
  options.generic_loops = 0;
  options.relative_perturbations = {1e-4, 1e-5, 1e-6, 1e-7, 1e-8};
  const std::vector<GroundTruthCase> cases = generate_ground_truth(options);
  std::map<std::string, const GroundTruthCase*> by_id;
  for (const GroundTruthCase& c : cases) by_id[c.id] = &c;
  // E_mean / eps^2 per (parent, parameter) and size.
  std::map<std::string, std::map<double, double>> ratio;
  for (const GroundTruthCase& c : cases) {
    if (c.parent.empty() || by_id.at(c.parent)->family == GroundTruthFamily::spherical) continue;
    const CycleResult r = cycle_from(c.geometry, c.pose);
    ASSERT_EQ(r.cycle.failed_samples, 0) << c.id;
    const double eps = c.relative_perturbation;
    EXPECT_GT(r.cycle.E_mean, 1e3 * 1e-20) << c.id;
    ratio[c.parent + " " + c.perturbed_parameter][eps] = r.cycle.E_mean / (eps * eps);
  }
  // One perturbed parameter per movable case: Bennett (both setups), planar, trivial.
  EXPECT_EQ(ratio.size(), 4u * kCasesPerFamily);
  for (const auto& [name, by_size] : ratio) {
    ASSERT_EQ(by_size.size(), 5u) << name;
    const double reference = by_size.at(1e-6);
    for (const auto& [eps, c] : by_size) {
      EXPECT_LT(c, 2.0 * reference) << name << " eps " << eps;
      EXPECT_GT(c, 0.5 * reference) << name << " eps " << eps;
    }
  }
}

TEST(GroundTruth, APerturbedSphericalLoopCostsTheSameEnergyWhateverTheSize) {
  // Its one non-zero length sets L, so in units of L every size is the same
  // loop: the relative size says nothing for this family.
  GroundTruthOptions options = small_set();
  options.cases_per_family = 2;
  options.generic_loops = 0;
  std::map<std::string, std::vector<double>> energies;
  for (const GroundTruthCase& c : generate_ground_truth(options)) {
    if (c.family == GroundTruthFamily::spherical && !c.movable) {
      energies[c.parent].push_back(cycle_from(c.geometry, c.pose).cycle.E_mean);
    }
  }
  ASSERT_EQ(energies.size(), 2u);
  for (const auto& [parent, e] : energies) {
    SCOPED_TRACE(parent);
    ASSERT_EQ(e.size(), options.relative_perturbations.size());
    for (double value : e) EXPECT_NEAR(value, e.front(), 1e-6 * e.front());
  }
}

TEST(GroundTruth, PerturbedCasesDifferFromTheirParentInTheNamedParameterOnly) {
  const std::vector<GroundTruthCase> cases = generate_ground_truth(small_set());
  std::map<std::string, const GroundTruthCase*> by_id;
  for (const GroundTruthCase& c : cases) by_id[c.id] = &c;
  int perturbed = 0;
  for (const GroundTruthCase& c : cases) {
    if (c.parent.empty()) continue;
    SCOPED_TRACE(c.id);
    ++perturbed;
    ASSERT_TRUE(by_id.count(c.parent));
    const GroundTruthCase& p = *by_id.at(c.parent);
    EXPECT_TRUE(p.movable);
    EXPECT_EQ(c.family, p.family);
    EXPECT_EQ(c.setup, p.setup);
    EXPECT_EQ(c.id.rfind(p.id + "-" + c.perturbed_parameter + "-", 0), 0u);
    EXPECT_TRUE(same_bits(c.pose, p.pose));
    // Exactly one of the 12 parameters changed, by size * L or size rad.
    const double L = length_scale(p.geometry);
    int changed = 0;
    for (int j = 0; j < 4; ++j) {
      const std::string joint = std::to_string(j + 1);
      const struct {
        std::string name;
        double before, after, unit;
      } parameters[] = {{"a" + joint, p.geometry.a[j], c.geometry.a[j], L},
                        {"alpha" + joint, p.geometry.alpha[j], c.geometry.alpha[j], 1.0},
                        {"d" + joint, p.geometry.d[j], c.geometry.d[j], L}};
      for (const auto& q : parameters) {
        if (q.before == q.after) continue;
        ++changed;
        EXPECT_EQ(q.name, c.perturbed_parameter);
        EXPECT_NEAR(q.after - q.before, c.relative_perturbation * q.unit, 1e-12 * q.unit);
      }
    }
    EXPECT_EQ(changed, 1);
  }
  EXPECT_EQ(perturbed, 5 * kCasesPerFamily * 7);
}

TEST(GroundTruth, ThePerturbationsItAvoidsKeepTheLoopMovable) {
  // Why a planar loop gets a twist or an offset and a spherical loop a
  // length: a planar loop with a longer link, or a spherical loop with a
  // wider twist, is another member of its family and still moves.
  GroundTruthOptions options = small_set();
  options.cases_per_family = 1;
  options.relative_perturbations.clear();
  int checked = 0;
  for (const GroundTruthCase& c : generate_ground_truth(options)) {
    if (c.family != GroundTruthFamily::planar && c.family != GroundTruthFamily::spherical) continue;
    SCOPED_TRACE(c.id);
    ++checked;
    LoopGeometry g = c.geometry;
    if (c.family == GroundTruthFamily::planar) {
      g.a[1] += 1e-3 * length_scale(g);
    } else {
      g.alpha[1] += 1e-3;
    }
    const VerificationSummary v = verify_motion(g, c.pose);
    EXPECT_TRUE(v.verified);
    EXPECT_TRUE(v.full_turn);
    EXPECT_EQ(classify(g, v.joint_angles.front(), travel_of(v)).family, expected_classification(c));
    EXPECT_LT(cycle_from(g, v.joint_angles.front()).cycle.E_max, 1e-20);
  }
  EXPECT_EQ(checked, 2);
}

TEST(GroundTruth, GenericLoopsAreRigid) {
  int checked = 0;
  for (const GroundTruthCase& c : generate_ground_truth(small_set())) {
    if (c.family != GroundTruthFamily::generic) continue;
    SCOPED_TRACE(c.id);
    ++checked;
    EXPECT_FALSE(c.movable);
    EXPECT_EQ(expected_classification(c), Family::unclassified);
    EXPECT_FALSE(verify_motion(c.geometry, c.pose).verified);
    // From the least-energy assembly (the random pose is far from closing).
    const LoopModel model(c.geometry);
    EquilibriumWorkspace workspace(model);
    const EquilibriumSummary assembly = assemble(model, workspace, c.pose[0]);
    CycleSummary cycle;
    cycle_energy(model, workspace, c.pose[0], assembly.state, CycleOptions{}, cycle);
    EXPECT_GT(cycle.E_mean, 1e-4);
  }
  EXPECT_EQ(checked, kGenericLoops);
}

TEST(GroundTruth, SameOptionsGiveTheSameSetBitForBit) {
  const std::vector<GroundTruthCase> first = generate_ground_truth(small_set());
  const std::vector<GroundTruthCase> second = generate_ground_truth(small_set());
  ASSERT_EQ(first.size(), second.size());
  for (size_t i = 0; i < first.size(); ++i) EXPECT_TRUE(same_case(first[i], second[i])) << first[i].id;

  // Case k of a family does not depend on how many are asked for...
  GroundTruthOptions fewer = small_set();
  fewer.cases_per_family = 3;
  fewer.generic_loops = 2;
  std::map<std::string, const GroundTruthCase*> by_id;
  for (const GroundTruthCase& c : first) by_id[c.id] = &c;
  const std::vector<GroundTruthCase> subset = generate_ground_truth(fewer);
  for (const GroundTruthCase& c : subset) {
    ASSERT_TRUE(by_id.count(c.id)) << c.id;
    EXPECT_TRUE(same_case(c, *by_id.at(c.id))) << c.id;
  }
  // ... but does depend on the seed.
  GroundTruthOptions other_seed = small_set();
  other_seed.seed = 2;
  const std::vector<GroundTruthCase> other = generate_ground_truth(other_seed);
  ASSERT_EQ(other.size(), first.size());
  int differing = 0;
  for (size_t i = 0; i < first.size(); ++i) {
    EXPECT_EQ(other[i].id, first[i].id);
    differing += same_bits(other[i].geometry.alpha, first[i].geometry.alpha) &&
                         same_bits(other[i].geometry.a, first[i].geometry.a)
                     ? 0
                     : 1;
  }
  EXPECT_EQ(differing, static_cast<int>(first.size()));
}

TEST(GroundTruth, IdsAreUnique) {
  const std::vector<GroundTruthCase> cases = generate_ground_truth(small_set());
  std::set<std::string> ids;
  for (const GroundTruthCase& c : cases) EXPECT_TRUE(ids.insert(c.id).second) << c.id;
  EXPECT_EQ(cases.size(), static_cast<size_t>(5 * kCasesPerFamily * (1 + 7) + kGenericLoops));
  EXPECT_TRUE(ids.count("bennett-asymmetric-000"));
  EXPECT_TRUE(ids.count("bennett-line_symmetric-005"));
  EXPECT_TRUE(ids.count("planar-002-alpha3-1e-08"));
  EXPECT_TRUE(ids.count("generic-005"));
}

TEST(GroundTruth, CoversTheRangesItPromises) {
  GroundTruthOptions options;
  options.cases_per_family = 64;
  options.relative_perturbations.clear();
  options.generic_loops = 0;
  const double m = options.twist_margin;
  double least_twist = kPi, greatest_twist = 0.0;
  double least_scale = 1e300, greatest_scale = 0.0;
  int planar_with_offsets = 0, planar_with_flipped_axes = 0, negative_inputs = 0;
  std::map<BennettSetup, int> setups;
  for (const GroundTruthCase& c : generate_ground_truth(options)) {
    SCOPED_TRACE(c.id);
    const LoopGeometry& g = c.geometry;
    const double theta0 = std::abs(c.pose[0]);
    EXPECT_GE(theta0, options.pose_margin);
    EXPECT_LE(theta0, kPi - options.pose_margin);
    negative_inputs += c.pose[0] < 0 ? 1 : 0;
    if (c.family != GroundTruthFamily::spherical) {
      const double L = length_scale(g);
      EXPECT_GE(L, options.min_length_scale * (1 - 1e-12));
      EXPECT_LE(L, options.max_length_scale * (1 + 1e-12));
      least_scale = std::min(least_scale, L);
      greatest_scale = std::max(greatest_scale, L);
    }
    switch (c.family) {
      case GroundTruthFamily::bennett:
        ++setups[c.setup];
        for (int j = 0; j < 2; ++j) {
          // Twists as drawn (the line-symmetric setup writes -alpha2).
          const double alpha = std::abs(g.alpha[j]);
          EXPECT_GE(alpha, m);
          EXPECT_LE(alpha, kPi - m);
          least_twist = std::min(least_twist, alpha);
          greatest_twist = std::max(greatest_twist, alpha);
        }
        if (c.setup == BennettSetup::asymmetric) {
          EXPECT_GE(std::abs(g.alpha[0] - g.alpha[1]), m);
        } else {
          EXPECT_GE(std::abs(g.alpha[0] - g.alpha[1] - kPi), m);
        }
        break;
      case GroundTruthFamily::planar: {
        // The input link is the shortest and the Grashof inequality strict.
        const double shortest = g.a[0];
        const double longest = g.a.maxCoeff();
        EXPECT_LT(shortest, g.a.tail<3>().minCoeff());
        EXPECT_LT(shortest + longest, g.a.sum() - shortest - longest);
        planar_with_offsets += g.d.cwiseAbs().maxCoeff() > 0 ? 1 : 0;
        planar_with_flipped_axes += g.alpha.cwiseAbs().maxCoeff() > 1.0 ? 1 : 0;
        break;
      }
      case GroundTruthFamily::spherical:
        EXPECT_EQ(g.a.cwiseAbs().maxCoeff(), 0.0);
        EXPECT_EQ(g.d.cwiseAbs().maxCoeff(), 0.0);
        for (int j = 0; j < 4; ++j) EXPECT_GE(std::abs(std::sin(g.alpha[j])), std::sin(m) * (1 - 1e-12));
        break;
      case GroundTruthFamily::trivial:
      case GroundTruthFamily::generic:
        break;
    }
  }
  EXPECT_EQ(setups[BennettSetup::asymmetric], 64);
  EXPECT_EQ(setups[BennettSetup::line_symmetric], 64);
  // Twists over nearly all of (0, 180) deg, scales over 0.1 ... 10.
  EXPECT_LT(least_twist, rad(15));
  EXPECT_GT(greatest_twist, rad(165));
  EXPECT_LT(least_scale, 0.2);
  EXPECT_GT(greatest_scale, 5.0);
  EXPECT_GT(planar_with_offsets, 30);
  EXPECT_GT(planar_with_flipped_axes, 10);
  EXPECT_GT(negative_inputs, 64);
  EXPECT_LT(negative_inputs, 4 * 64);
}

TEST(GroundTruthOptions, InvalidOptionsThrowNamingTheOption) {
  struct Bad {
    const char* name;
    void (*change)(GroundTruthOptions&);
  };
  const Bad cases[] = {
      {"cases_per_family", [](GroundTruthOptions& o) { o.cases_per_family = -1; }},
      {"generic_loops", [](GroundTruthOptions& o) { o.generic_loops = 2000000; }},
      {"relative perturbation",
       [](GroundTruthOptions& o) {
         o.relative_perturbations = {1e-3, 0.0};
       }},
      {"relative perturbation", [](GroundTruthOptions& o) { o.relative_perturbations = {1.0}; }},
      {"relative perturbation", [](GroundTruthOptions& o) { o.relative_perturbations = {NAN}; }},
      {"relative perturbations",
       [](GroundTruthOptions& o) {
         o.relative_perturbations = {1e-3, 1e-3 * (1 + 1e-12)};
       }},
      {"min_length_scale", [](GroundTruthOptions& o) { o.min_length_scale = 0.0; }},
      {"max_length_scale", [](GroundTruthOptions& o) { o.max_length_scale = 0.05; }},
      {"max_length_scale", [](GroundTruthOptions& o) { o.max_length_scale = INFINITY; }},
      {"twist_margin", [](GroundTruthOptions& o) { o.twist_margin = 0.0; }},
      {"twist_margin", [](GroundTruthOptions& o) { o.twist_margin = rad(11); }},
      {"pose_margin", [](GroundTruthOptions& o) { o.pose_margin = rad(46); }},
  };
  for (const Bad& bad : cases) {
    GroundTruthOptions options;
    bad.change(options);
    try {
      generate_ground_truth(options);
      ADD_FAILURE() << bad.name << ": no exception";
    } catch (const std::invalid_argument& error) {
      EXPECT_NE(std::string(error.what()).find(bad.name), std::string::npos) << error.what();
    }
  }
  EXPECT_NO_THROW(GroundTruthOptions{}.validate());
}

TEST(GroundTruth, EmptyCountsGiveAnEmptySet) {
  GroundTruthOptions options;
  options.cases_per_family = 0;
  options.generic_loops = 0;
  EXPECT_TRUE(generate_ground_truth(options).empty());
  options.generic_loops = 3;
  EXPECT_EQ(generate_ground_truth(options).size(), 3u);
}

}  // namespace
}  // namespace loopfarm
