// Where a cycle's Newton iterations go: the bench's 8 generic 4R loops (the
// same fixed seeds as loopfarm_bench's BM_Cycle_Generic), each driven through
// one cycle, with the iterations counted per sample status. Deterministic
// (counts, not times), so two settings compare exactly:
//
//   build/release/bench/cycle_breakdown [--samples N] [--max-refinements D]
//                                       [--max-iterations-per-step B] [--bennett]
//                                       [--general-step] [--retry-failed]
//                                       [--full-newton] [--exact-midpoints]
//
// Prints one line per loop (E_mean, iterations, bisections, jumps, failures)
// and the total iterations by sample status. --bennett drives the paper's
// Bennett loop from 120 deg instead (BM_Cycle_Bennett's cycle), 8 times, so
// that instruction counts (valgrind --tool=callgrind) compare with the
// generic loops'. --general-step turns EquilibriumOptions::structured_step
// off (the same steps through the general factorisation), to compare.
// --retry-failed turns CycleOptions::skip_failed_retries off (every bisection
// depth retries the solve that failed at the depth above), to compare.
// --full-newton turns EquilibriumOptions::simplified_newton off (a full
// Newton step at every iteration), to compare. --exact-midpoints sets
// CycleOptions::stepping_tolerance to 0 (bisection midpoints solved to the
// model's tolerances, as samples are), to compare.
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <string>

#include "loopfarm/core/assembly.hpp"
#include "loopfarm/core/cycle.hpp"
#include "loopfarm/core/sample_loops.hpp"

namespace {

constexpr double kDegree = 3.14159265358979323846 / 180.0;

int integer_argument(int argc, char** argv, int& i) {
  if (i + 1 >= argc) {
    std::fprintf(stderr, "cycle_breakdown: %s needs a value\n", argv[i]);
    std::exit(2);
  }
  char* end = nullptr;
  const long value = std::strtol(argv[++i], &end, 10);
  if (*end != '\0') {
    std::fprintf(stderr, "cycle_breakdown: %s: \"%s\" is not an integer\n", argv[i - 1], argv[i]);
    std::exit(2);
  }
  return static_cast<int>(value);
}

}  // namespace

int main(int argc, char** argv) {
  using namespace loopfarm;
  CycleOptions options;
  bool bennett = false;
  EquilibriumOptions solver;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--samples") == 0) {
      options.samples = integer_argument(argc, argv, i);
    } else if (std::strcmp(argv[i], "--max-refinements") == 0) {
      options.max_refinements = integer_argument(argc, argv, i);
    } else if (std::strcmp(argv[i], "--max-iterations-per-step") == 0) {
      options.max_iterations_per_step = integer_argument(argc, argv, i);
    } else if (std::strcmp(argv[i], "--bennett") == 0) {
      bennett = true;
    } else if (std::strcmp(argv[i], "--general-step") == 0) {
      solver.structured_step = false;
    } else if (std::strcmp(argv[i], "--full-newton") == 0) {
      solver.simplified_newton = false;
    } else if (std::strcmp(argv[i], "--exact-midpoints") == 0) {
      options.stepping_tolerance = 0.0;
    } else if (std::strcmp(argv[i], "--retry-failed") == 0) {
      options.skip_failed_retries = false;
    } else {
      std::fprintf(stderr, "cycle_breakdown: unknown option %s\n", argv[i]);
      return 2;
    }
  }
  try {
    options.validate();
  } catch (const std::exception& error) {
    std::fprintf(stderr, "cycle_breakdown: %s\n", error.what());
    return 2;
  }
  std::map<std::string, std::pair<long, long>> by_status;  // samples, iterations
  long total = 0;
  for (std::uint64_t seed = 1; seed <= 8; ++seed) {
    const double theta0 = bennett ? 120.0 * kDegree : 0.0;
    const LoopModel model(bennett ? paper_bennett_loop() : random_loop(4, seed), solver);
    EquilibriumWorkspace ws(model);
    const EquilibriumState start = bennett
                                       ? EquilibriumState::at_angles(model, bennett_angles(model.geometry(), theta0))
                                       : assemble(model, ws, theta0).state;
    CycleSummary s;
    cycle_energy(model, ws, theta0, start, options, s);
    total += s.total_iterations;
    std::printf("%s(4, %d): E_mean %.10g, %d iterations, %d bisections, %d branch jumps, %d failed\n",
                bennett ? "paper_bennett_loop" : "random_loop", static_cast<int>(seed), s.E_mean, s.total_iterations,
                s.refinements, s.branch_jumps, s.failed_samples);
    for (const CycleSample& sample : s.samples) {
      auto& entry = by_status[to_string(sample.status)];
      ++entry.first;
      entry.second += sample.iterations;
    }
  }
  for (const auto& [status, entry] : by_status) {
    std::printf("%-12s %4ld samples %6ld iterations (%4.1f %%)\n", status.c_str(), entry.first, entry.second,
                100.0 * static_cast<double>(entry.second) / static_cast<double>(total));
  }
  std::printf("total        %4d samples %6ld iterations\n", 8 * options.samples, total);
  return 0;
}
