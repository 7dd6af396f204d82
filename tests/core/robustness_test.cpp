// Numerical robustness: many random geometries, drawn far wider than a job's
// bounds (every joint count from 4 to 8, lengths from 1e-6 to 1e6 in one loop,
// twists and offsets exactly zero or exactly pi, near-coincident axes, known
// families with small noise), through the equilibrium solve, assembly, the
// cycle and its gradient. Whatever the geometry, every result must be finite,
// every failure must be a status, and the iteration counts must stay within
// the caps the options set.
//
// The count defaults to 100,000 geometries (docs/quality/reliability.md);
// LOOPFARM_ROBUSTNESS_GEOMETRIES overrides it (the sanitizer build runs fewer).
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <map>
#include <string>
#include <tuple>

#include <gtest/gtest.h>

#include "loopfarm/core/assembly.hpp"
#include "loopfarm/core/cycle.hpp"
#include "loopfarm/core/equilibrium.hpp"
#include "loopfarm/core/loop.hpp"
#include "loopfarm/core/sample_loops.hpp"
#include "loopfarm/search/sampler.hpp"

namespace loopfarm {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr std::uint64_t kSeed = 20261123;

// Draws from one Philox stream per geometry, so that a failure names the
// geometry's index and it can be replayed alone.
class Draws {
 public:
  explicit Draws(std::uint64_t index) : index_(index) {}
  double uniform(double lo, double hi) { return lo + (hi - lo) * stream_uniform(kSeed, index_, k_++); }
  int integer(int lo, int hi) {  // inclusive
    return lo + std::min(hi - lo, static_cast<int>(stream_uniform(kSeed, index_, k_++) * (hi - lo + 1)));
  }
  bool chance(double p) { return stream_uniform(kSeed, index_, k_++) < p; }
  // 10^u for u uniform in [lo, hi].
  double log_uniform(double lo, double hi) { return std::pow(10.0, uniform(lo, hi)); }

 private:
  std::uint64_t index_;
  std::uint64_t k_ = 0;
};

enum class Kind { generic, special_values, extreme_scales, near_family, count };
const char* name(Kind kind) {
  switch (kind) {
    case Kind::generic:
      return "generic";
    case Kind::special_values:
      return "special values";
    case Kind::extreme_scales:
      return "extreme scales";
    case Kind::near_family:
      return "near a family";
    case Kind::count:
      break;
  }
  return "?";
}

LoopGeometry sized(int n) {
  LoopGeometry g;
  g.a.resize(n);
  g.alpha.resize(n);
  g.d.resize(n);
  return g;
}

// A value that is often one of the values where formulas divide by zero or
// branch: 0, pi, -pi, pi/2.
double special_angle(Draws& draws) {
  static constexpr std::array<double, 5> values{0.0, kPi, -kPi, kPi / 2, -kPi / 2};
  return draws.chance(0.6) ? values[draws.integer(0, 4)] : draws.uniform(-kPi, kPi);
}

LoopGeometry draw_geometry(Kind kind, Draws& draws) {
  const int n = draws.integer(kMinJoints, kMaxJoints);
  LoopGeometry g = sized(n);
  switch (kind) {
    case Kind::generic:
      for (int i = 0; i < n; ++i) {
        g.a[i] = draws.uniform(0.0, 5.0);
        g.alpha[i] = draws.uniform(-kPi, kPi);
        g.d[i] = draws.uniform(-2.0, 2.0);
      }
      break;
    case Kind::special_values:
      // Zero lengths, parallel and anti-parallel axes, zero offsets: the
      // planar, spherical and coincident-axis degeneracies.
      for (int i = 0; i < n; ++i) {
        g.a[i] = draws.chance(0.4) ? 0.0 : draws.uniform(0.0, 3.0);
        g.alpha[i] = special_angle(draws);
        g.d[i] = draws.chance(0.5) ? 0.0 : draws.uniform(-1.0, 1.0);
      }
      if (draws.chance(0.1)) g.a.setZero();  // every length zero: L from the offsets, or none at all
      if (draws.chance(0.05)) g.d.setZero();
      break;
    case Kind::extreme_scales:
      // Twelve decades within one loop: the normalisation by L must keep the
      // solve well scaled, and tiny links must not produce NaN.
      for (int i = 0; i < n; ++i) {
        g.a[i] = draws.log_uniform(-6.0, 6.0);
        g.alpha[i] = draws.chance(0.2) ? draws.uniform(-1e-9, 1e-9) : draws.uniform(-kPi, kPi);
        g.d[i] = (draws.chance(0.5) ? -1.0 : 1.0) * draws.log_uniform(-6.0, 6.0);
      }
      break;
    case Kind::near_family: {
      // Movable loops and their near misses: the paths fold and change branch.
      const int family = draws.integer(0, 2);
      if (family == 0) {
        g = bennett_loop(draws.uniform(0.1, 5.0), draws.uniform(0.05, kPi - 0.05), draws.uniform(0.05, kPi - 0.05));
      } else if (family == 1) {
        g = planar_four_bar(draws.uniform(0.1, 5.0), draws.uniform(0.1, 5.0), draws.uniform(0.1, 5.0),
                            draws.uniform(0.1, 5.0));
      } else {
        g = spherical_four_bar(draws.uniform(-kPi, kPi), draws.uniform(-kPi, kPi), draws.uniform(-kPi, kPi),
                               draws.uniform(-kPi, kPi));
      }
      const double noise = draws.log_uniform(-12.0, -2.0);
      for (int i = 0; i < g.joints(); ++i) {
        g.a[i] = std::abs(g.a[i] + noise * draws.uniform(-1.0, 1.0));
        g.alpha[i] += noise * draws.uniform(-1.0, 1.0);
        g.d[i] += noise * draws.uniform(-1.0, 1.0);
      }
      break;
    }
    case Kind::count:
      break;
  }
  return g;
}

bool finite(const EquilibriumState& state) {
  return state.theta.allFinite() && state.deformations.allFinite() && state.multipliers.allFinite();
}

std::uint64_t geometry_count() {
  if (const char* text = std::getenv("LOOPFARM_ROBUSTNESS_GEOMETRIES")) {
    const long long count = std::atoll(text);
    if (count > 0) return static_cast<std::uint64_t>(count);
  }
  return 100000;
}

// One test per kind of geometry and shard, an eighth of the count each, so
// that CTest runs them in parallel and each stays well inside its timeout.
constexpr int kShards = 2;
class Robustness : public ::testing::TestWithParam<std::tuple<Kind, int>> {};

TEST_P(Robustness, RandomGeometriesGiveFiniteResultsStatusesAndBoundedIterations) {
  const auto [kind, shard] = GetParam();
  const std::uint64_t count = geometry_count() / (static_cast<int>(Kind::count) * kShards);
  CycleOptions cycle_options;
  cycle_options.samples = 8;
  AssemblyOptions assembly_options;
  assembly_options.guesses = 4;
  // The most Newton iterations one cycle may spend: every sample refined to
  // the finest step, each sub-step at its cap.
  const long long cycle_iteration_cap = static_cast<long long>(cycle_options.samples) *
                                        (1LL << cycle_options.max_refinements) * cycle_options.max_iterations_per_step;

  std::map<std::string, int> statuses;
  int invalid = 0, cycles = 0, failed_cycles = 0, non_finite = 0;
  long long total_cycle_iterations = 0;
  int max_cycle_iterations = 0;
  std::array<int, kMaxJoints + 1> joints{};
  for (std::uint64_t i = 0; i < count; ++i) {
    // Kinds and shards draw from disjoint streams: geometry `index` is the
    // same whatever the count.
    const std::uint64_t index = (i * kShards + shard) * static_cast<int>(Kind::count) + static_cast<int>(kind);
    Draws draws(index);
    const LoopGeometry geometry = draw_geometry(kind, draws);
    ++joints[geometry.joints()];
    const std::string where = std::string("geometry ") + std::to_string(index) + " (" + name(kind) + ", n " +
                              std::to_string(geometry.joints()) + ")";
    EquilibriumOptions options;
    options.compliance = draws.chance(0.5) ? Compliance::full : Compliance::paper;
    options.torsion_stiffness_ratio = draws.log_uniform(-2.0, 2.0);
    options.input_joint = draws.integer(0, geometry.joints() - 1);
    // A geometry the library refuses must be refused by the model's check
    // too, with the exception its callers turn into a message.
    try {
      validate_geometry(geometry);
    } catch (const std::invalid_argument&) {
      ++invalid;
      EXPECT_THROW(LoopModel(geometry, options), std::invalid_argument) << where;
      continue;
    }
    const LoopModel model(geometry, options);
    ASSERT_TRUE(std::isfinite(model.length_scale()) && model.length_scale() > 0.0) << where;
    EquilibriumWorkspace workspace(model);

    // One solve from random angles: far from closure, often near a fold.
    JointVector theta(geometry.joints());
    for (int i = 0; i < geometry.joints(); ++i) theta[i] = draws.uniform(-kPi, kPi);
    const EquilibriumSummary far = assemble_from_angles(model, workspace, theta);
    ++statuses[to_string(far.status)];
    ASSERT_LE(far.iterations, options.max_iterations) << where;
    if (far.status != SolveStatus::non_finite) {
      EXPECT_TRUE(std::isfinite(far.energy) && std::isfinite(far.closure_residual) && std::isfinite(far.stationarity) &&
                  finite(far.state))
          << where << ": non-finite result with status " << to_string(far.status);
    } else {
      ++non_finite;
    }
    if (far.status == SolveStatus::converged) {
      EXPECT_LE(far.closure_residual, 1e3 * options.closure_tolerance) << where;
      EXPECT_GE(far.energy, 0.0) << where;
    }

    // Assembly, then a short cycle and its gradient from it.
    const double theta0 = draws.uniform(-kPi, kPi);
    const EquilibriumSummary start = assemble(model, workspace, theta0, assembly_options);
    ++statuses[std::string("assembly ") + to_string(start.status)];
    if (start.status != SolveStatus::converged) continue;
    ASSERT_TRUE(finite(start.state) && std::isfinite(start.energy)) << where;
    CycleSummary cycle;
    cycle_energy(model, workspace, theta0, start.state, cycle_options, cycle);
    ++cycles;
    if (cycle.failed_samples > 0) ++failed_cycles;
    ASSERT_TRUE(std::isfinite(cycle.E_mean) && std::isfinite(cycle.E_max)) << where;
    ASSERT_GE(cycle.E_mean, 0.0) << where;
    ASSERT_LE(cycle.E_mean, cycle.E_max * (1 + 1e-12) + 1e-300) << where;
    ASSERT_TRUE(std::isfinite(cycle.max_closure_residual)) << where;
    ASSERT_LE(cycle.total_iterations, cycle_iteration_cap) << where;
    ASSERT_EQ(static_cast<int>(cycle.samples.size()), cycle_options.samples) << where;
    for (const CycleSample& sample : cycle.samples) {
      ASSERT_TRUE(std::isfinite(sample.energy) && finite(sample.state)) << where;
      // A sample that is not `failed` rests on a converged solve.
      if (sample.status != SampleStatus::failed) {
        ASSERT_EQ(sample.solve_status, SolveStatus::converged) << where;
      }
    }
    total_cycle_iterations += cycle.total_iterations;
    max_cycle_iterations = std::max(max_cycle_iterations, cycle.total_iterations);
    if (cycle.failed_samples == 0) {
      const GeometryVector gradient = cycle_energy_gradient(model, workspace, cycle);
      ASSERT_TRUE(gradient.allFinite()) << where;
    }
  }

  // The figures docs/quality/reliability.md quotes.
  std::printf("robustness, %s, shard %d: %llu geometries (n = 4..8:", name(kind), shard,
              static_cast<unsigned long long>(count));
  for (int n = kMinJoints; n <= kMaxJoints; ++n) std::printf(" %d", joints[n]);
  std::printf(
      "), %d refused by validate_geometry, %d cycles (%d with failed samples), "
      "cycle iterations mean %.1f max %d (cap %lld), non-finite solves %d\n",
      invalid, cycles, failed_cycles, cycles ? double(total_cycle_iterations) / cycles : 0.0, max_cycle_iterations,
      cycle_iteration_cap, non_finite);
  for (const auto& [status, n] : statuses) std::printf("  %-30s %d\n", status.c_str(), n);

  // Non-finite inputs are the only source of non_finite; none are drawn here.
  EXPECT_EQ(non_finite, 0);
  // The draw must exercise the cycle, not only refusals.
  EXPECT_GT(cycles, static_cast<int>(count / 2));
}

INSTANTIATE_TEST_SUITE_P(Kinds, Robustness,
                         ::testing::Combine(::testing::Values(Kind::generic, Kind::special_values, Kind::extreme_scales,
                                                              Kind::near_family),
                                            ::testing::Range(0, kShards)),
                         [](const ::testing::TestParamInfo<std::tuple<Kind, int>>& info) {
                           std::string text = name(std::get<0>(info.param));
                           for (char& c : text) c = c == ' ' ? '_' : c;
                           return text + "_" + std::to_string(std::get<1>(info.param));
                         });

}  // namespace
}  // namespace loopfarm
