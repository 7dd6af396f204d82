// Cost of the elastic-energy core: one warm equilibrium solve and one cycle,
// for the paper's Bennett loop (movable: every sample converges to zero) and
// for generic 4R loops (rigid: every sample carries energy); and the implicit
// differentiation of a solved generic cycle (the Gauss-Newton Jacobian).
//
//   build/release/bench/loopfarm_bench
//
// Counters: Newton iterations per solve or per cycle sample, bisections per
// cycle, samples that jumped branch or failed. Figures are in docs/performance.md.
//
// And the steering's family distances (deflation), which a steered search
// evaluates with every objective value and again with their gradients for
// every Jacobian: planar and trivial (the default job's) over generic 4R
// loops, with and without the gradient.
#include <benchmark/benchmark.h>

#include <cstdint>
#include <vector>

#include "loopfarm/core/assembly.hpp"
#include "loopfarm/core/cycle.hpp"
#include "loopfarm/core/motion.hpp"
#include "loopfarm/core/sample_loops.hpp"
#include "loopfarm/search/classify.hpp"

namespace loopfarm {
namespace {

constexpr double kDeg = 3.14159265358979323846 / 180.0;

struct Fixture {
  LoopGeometry geometry;
  double theta0 = 0.0;
  JointVector start;            // empty: assemble from the deterministic guesses
  bool structured_step = true;  // EquilibriumOptions::structured_step (off: the general step, to compare)
};

EquilibriumOptions solver_options(const Fixture& f) {
  EquilibriumOptions options;
  options.structured_step = f.structured_step;
  return options;
}

// Generic loops: the same fixed seeds everywhere, so runs compare.
constexpr std::uint64_t kGenericSeeds[] = {1, 2, 3, 4, 5, 6, 7, 8};

Fixture bennett() {
  const LoopGeometry g = paper_bennett_loop();
  return {g, 120 * kDeg, bennett_angles(g, 120 * kDeg)};
}

Fixture bennett_general_step() {
  Fixture f = bennett();
  f.structured_step = false;
  return f;
}

Fixture generic(std::uint64_t seed) { return {random_loop(4, seed), 0.0, JointVector()}; }

EquilibriumState assembled(const LoopModel& model, EquilibriumWorkspace& ws, const Fixture& f) {
  return f.start.size() > 0 ? assemble_from_angles(model, ws, f.start).state : assemble(model, ws, f.theta0).state;
}

// One solve at theta0 + 1 degree (N = 360 spacing) from the solution at
// theta0 (`predicted` false), or from the continuation's guess: that solution
// moved 1 degree along its path tangent (what a cycle's first step starts
// from; later steps use the sharper cubic through two samples).
void solve_step(benchmark::State& state, const Fixture& f, bool predicted) {
  const LoopModel model(f.geometry, solver_options(f));
  EquilibriumWorkspace ws(model);
  EquilibriumState guess = assembled(model, ws, f);
  if (predicted) {
    EquilibriumState tangent;
    if (!equilibrium_tangent(model, ws, guess, tangent)) {
      state.SkipWithError("no path tangent at the start");
      return;
    }
    guess.theta += kDeg * tangent.theta;
    guess.deformations += kDeg * tangent.deformations;
    guess.multipliers += kDeg * tangent.multipliers;
  }
  long iterations = 0;
  long solves = 0;
  for (auto _ : state) {
    const EquilibriumSummary s = solve_equilibrium(model, ws, f.theta0 + kDeg, guess);
    benchmark::DoNotOptimize(s.energy);
    iterations += s.iterations;
    ++solves;
  }
  state.counters["iterations"] = static_cast<double>(iterations) / static_cast<double>(solves);
}

// A fixture's model, workspace and assembled start.
struct Prepared {
  LoopModel model;
  EquilibriumWorkspace ws;
  EquilibriumState start;
  double theta0;
};

std::vector<Prepared> prepare(const std::vector<Fixture>& fixtures) {
  std::vector<Prepared> prepared;
  prepared.reserve(fixtures.size());
  for (const Fixture& f : fixtures) {
    LoopModel model(f.geometry, solver_options(f));
    EquilibriumWorkspace ws(model);
    EquilibriumState start = assembled(model, ws, f);
    prepared.push_back({model, ws, start, f.theta0});
  }
  return prepared;
}

void cycle(benchmark::State& state, const std::vector<Fixture>& fixtures) {
  CycleOptions options;
  options.samples = static_cast<int>(state.range(0));
  std::vector<Prepared> prepared = prepare(fixtures);
  CycleSummary summary;
  long cycles = 0, iterations = 0, refinements = 0, jumps = 0, failed = 0;
  size_t next = 0;
  for (auto _ : state) {
    Prepared& p = prepared[next];
    next = (next + 1) % prepared.size();
    cycle_energy(p.model, p.ws, p.theta0, p.start, options, summary);
    benchmark::DoNotOptimize(summary.E_mean);
    ++cycles;
    iterations += summary.total_iterations;
    refinements += summary.refinements;
    jumps += summary.branch_jumps;
    failed += summary.failed_samples;
  }
  const double samples = static_cast<double>(cycles) * options.samples;
  state.counters["it/sample"] = static_cast<double>(iterations) / samples;
  state.counters["bisect/cycle"] = static_cast<double>(refinements) / static_cast<double>(cycles);
  state.counters["jump_frac"] = static_cast<double>(jumps) / samples;
  state.counters["fail_frac"] = static_cast<double>(failed) / samples;
}

// One implicit differentiation of a solved cycle (what a Gauss-Newton step
// costs besides its cycles): d r / d(a, alpha, d) and the angles'
// sensitivities, as the default job's steered objective asks, into matrices
// reused from call to call. The cycles are solved before timing.
void cycle_jacobian(benchmark::State& state, const std::vector<Fixture>& fixtures) {
  CycleOptions options;
  options.samples = static_cast<int>(state.range(0));
  std::vector<Prepared> prepared = prepare(fixtures);
  std::vector<CycleSummary> cycles(prepared.size());
  for (size_t i = 0; i < prepared.size(); ++i) {
    Prepared& p = prepared[i];
    cycle_energy(p.model, p.ws, p.theta0, p.start, options, cycles[i]);
  }
  Eigen::MatrixXd jacobian, angles;
  size_t next = 0;
  for (auto _ : state) {
    Prepared& p = prepared[next];
    cycle_deformation_jacobian(p.model, p.ws, cycles[next], jacobian, &angles);
    benchmark::DoNotOptimize(jacobian.data());
    benchmark::ClobberMemory();
    next = (next + 1) % prepared.size();
  }
  state.counters["samples"] = options.samples;
}

// One family distance of a generic 4R loop, cycling through the fixed seeds.
void BM_FamilyDistance(benchmark::State& state, Family family, bool with_gradient) {
  std::vector<LoopGeometry> geometries;
  for (std::uint64_t seed : kGenericSeeds) geometries.push_back(random_loop(4, seed));
  GeometryVector gradient;
  size_t next = 0;
  for (auto _ : state) {
    const double distance = family_distance(family, geometries[next], with_gradient ? &gradient : nullptr);
    benchmark::DoNotOptimize(distance);
    benchmark::DoNotOptimize(gradient.data());
    next = (next + 1) % geometries.size();
  }
}

void BM_SolveWarm_Bennett(benchmark::State& state) { solve_step(state, bennett(), false); }
void BM_SolveWarm_Generic(benchmark::State& state) { solve_step(state, generic(3), false); }
void BM_SolvePredicted_Bennett(benchmark::State& state) { solve_step(state, bennett(), true); }
void BM_SolvePredicted_Generic(benchmark::State& state) { solve_step(state, generic(3), true); }

void BM_Cycle_Bennett(benchmark::State& state) { cycle(state, {bennett()}); }
// The same with EquilibriumOptions::structured_step off: what the structured step saves.
void BM_SolvePredicted_Bennett_GeneralStep(benchmark::State& state) { solve_step(state, bennett_general_step(), true); }
void BM_Cycle_Bennett_GeneralStep(benchmark::State& state) { cycle(state, {bennett_general_step()}); }
std::vector<Fixture> generic_loops(bool structured_step) {
  std::vector<Fixture> fixtures;
  for (std::uint64_t seed : kGenericSeeds) fixtures.push_back(generic(seed));
  for (Fixture& f : fixtures) f.structured_step = structured_step;
  return fixtures;
}
void BM_Cycle_Generic(benchmark::State& state) { cycle(state, generic_loops(true)); }
void BM_Cycle_Generic_GeneralStep(benchmark::State& state) { cycle(state, generic_loops(false)); }

void BM_CycleJacobian_Generic(benchmark::State& state) { cycle_jacobian(state, generic_loops(true)); }

// The rigid loop's motion: the circuit through a pose (what the farm does
// for a zero), and every circuit from assemblies over the turn (verify).
void BM_TraceCircuit_Bennett(benchmark::State& state) {
  const LoopGeometry g = paper_bennett_loop();
  const JointVector pose = bennett_angles(g, 2.0);
  for (auto _ : state) benchmark::DoNotOptimize(trace_circuit(g, pose).points.size());
}
void BM_AnalyseMotion(benchmark::State& state, LoopGeometry g) {
  for (auto _ : state) benchmark::DoNotOptimize(analyse_motion(g, nullptr).circuits.size());
}

BENCHMARK(BM_TraceCircuit_Bennett)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_AnalyseMotion, bennett, paper_bennett_loop())->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_AnalyseMotion, planar_rocker, planar_four_bar(2.0, 3.0, 2.5, 4.0))->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_AnalyseMotion, trihedral_6r,
                  LoopGeometry::from_degrees(std::vector<double>{1, 1.2, 1.5, 1.3, 1.1, 1.1532562594670797},
                                             std::vector<double>{90, 90, 90, 90, 90, 90}, std::vector<double>(6, 0.0)))
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_SolveWarm_Bennett);
BENCHMARK(BM_SolveWarm_Generic);
BENCHMARK(BM_SolvePredicted_Bennett);
BENCHMARK(BM_SolvePredicted_Generic);
BENCHMARK(BM_Cycle_Bennett)->Arg(16)->Arg(32)->Arg(64)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_SolvePredicted_Bennett_GeneralStep);
BENCHMARK(BM_Cycle_Bennett_GeneralStep)->Arg(32)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_Cycle_Generic)->Arg(16)->Arg(32)->Arg(64)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_Cycle_Generic_GeneralStep)->Arg(32)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_CycleJacobian_Generic)->Arg(32)->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_FamilyDistance, planar, Family::planar, false);
BENCHMARK_CAPTURE(BM_FamilyDistance, planar_gradient, Family::planar, true);
BENCHMARK_CAPTURE(BM_FamilyDistance, trivial, Family::trivial, false);
BENCHMARK_CAPTURE(BM_FamilyDistance, trivial_gradient, Family::trivial, true);

}  // namespace
}  // namespace loopfarm

BENCHMARK_MAIN();
