// The cycle test on 5R and 6R loops: the mean elastic
// energy over a cycle, from the automatic assembly at theta1 = 0, tells the
// movable loops of docs/guide/families.md (Goldberg, Myard, Bricard) from generic
// ones, which are rigid (a generic 5R is over-constrained by one, a generic
// 6R has finitely many assemblies and none with its input held elsewhere) and
// from near-misses of the movable ones. The path `loopfarm verify` and
// `loopfarm report --plot` take (assemble, then cycle_energy).
#include <cmath>
#include <span>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "loopfarm/core/assembly.hpp"
#include "loopfarm/core/cycle.hpp"
#include "loopfarm/core/sample_loops.hpp"

namespace loopfarm {
namespace {

struct Named {
  std::string name;
  LoopGeometry geometry;
};

LoopGeometry from_degrees(std::vector<double> a, std::vector<double> alpha_deg, std::vector<double> d) {
  return LoopGeometry::from_degrees(std::span<const double>(a), std::span<const double>(alpha_deg),
                                    std::span<const double>(d));
}

// The examples of docs/guide/families.md ("Examples"), which move through a full turn.
std::vector<Named> movable_examples() {
  const double s3 = std::sqrt(3.0);
  return {
      {"goldberg", from_degrees({2, 1, s3, 2, 1 + s3}, {90, 30, 60, 90, 90}, {0, 0, 0, 0, 0})},
      {"myard (opposite sides)", from_degrees({2, 1, 1, 2, 2}, {90, 30, -30, 90, 0}, {0, 0, 0, 0, 0})},
      {"myard (same side)", from_degrees({2, 1, 1, 2, 0}, {90, 30, -30, 90, 60}, {0, 0, 0, 0, 0})},
      {"bricard_line_symmetric",
       from_degrees({1, 1.7, 0.8, 1, 1.7, 0.8}, {51.566, 120.321, -34.377, 51.566, 120.321, -34.377},
                    {0.4, 0.3, -0.5, 0.4, 0.3, -0.5})},
      {"bricard_plane_symmetric",
       from_degrees({1, 1.7, 0.8, 0.8, 1.7, 1}, {51.566, 120.321, -34.377, 34.377, -120.321, -51.566},
                    {0, 0.3, -0.5, 0, 0.5, -0.3})},
  };
}

// Assembled at theta0, driven over `range` in N samples.
CycleSummary cycle_of(const LoopGeometry& g, double theta0 = 0.0, double range = 2.0 * M_PI, int samples = 32) {
  const LoopModel model(g);
  EquilibriumWorkspace workspace(model);
  const EquilibriumSummary assembly = assemble(model, workspace, theta0);
  CycleOptions options;
  options.samples = samples;
  options.range = range;
  CycleSummary cycle;
  cycle_energy(model, workspace, theta0, assembly.state, options, cycle);
  return cycle;
}

// A zero as the search counts one (docs/guide/job-file.md, zero_threshold): E_mean
// at most 1e-12 and no failed sample. The examples are far below it.
TEST(CycleNR, KnownMovable5RAnd6RLoopsNeedNoEnergyOverAFullTurn) {
  for (const Named& loop : movable_examples()) {
    const CycleSummary cycle = cycle_of(loop.geometry);
    EXPECT_LT(cycle.E_mean, 1e-20) << loop.name;
    EXPECT_EQ(cycle.failed_samples, 0) << loop.name;
  }
}

// Generic loops (random lengths, twists and offsets) are rigid: every one of
// 12 5R and 12 6R loops needs energy, E_mean far above the zero threshold.
TEST(CycleNR, Generic5RAnd6RLoopsAreRigid) {
  for (int n : {5, 6}) {
    for (std::uint64_t seed = 1; seed <= 12; ++seed) {
      const CycleSummary cycle = cycle_of(random_loop(n, seed));
      EXPECT_GT(cycle.E_mean, 1e-6) << n << "R, seed " << seed;
    }
  }
}

// Near-misses: one parameter of a movable example moved by 1e-3 (x L for a
// length, rad for a twist) makes it rigid: the energy grows as the square of
// the distance, and 1e-3 puts it well above the zero threshold.
TEST(CycleNR, NearMissesOfMovable5RAnd6RLoopsNeedEnergy) {
  for (const Named& loop : movable_examples()) {
    for (int parameter : {0, 1}) {  // a1, then the twist alpha2
      LoopGeometry g = loop.geometry;
      if (parameter == 0) {
        g.a[0] += 1e-3 * length_scale(g);
      } else {
        g.alpha[1] += 1e-3;
      }
      const CycleSummary cycle = cycle_of(g);
      EXPECT_GT(cycle.E_mean, 1e-10) << loop.name << ", parameter " << parameter;
    }
  }
}

// The trihedral Bricard example of docs/guide/families.md turns its input through
// about +-135 deg only: over a full turn it needs energy, over 180 deg
// around theta1 = 0 (within its motion) none. A trihedral search needs
// range_deg < 360.
TEST(CycleNR, TrihedralBricardIsMovableOverARangeOnly) {
  const LoopGeometry g =
      from_degrees({1.5, 1, 1.2, 0.8, 1, 1.746424919657298}, {90, -90, 90, -90, 90, -90}, {0, 0, 0, 0, 0, 0});
  EXPECT_GT(cycle_of(g).E_mean, 1e-4);
  const CycleSummary part = cycle_of(g, 0.0, M_PI);
  EXPECT_LT(part.E_mean, 1e-20);
  EXPECT_EQ(part.failed_samples, 0);
}

}  // namespace
}  // namespace loopfarm
