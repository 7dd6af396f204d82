#include "loopfarm/core/assembly.hpp"

#include <array>
#include <stdexcept>

#include "halton.hpp"

namespace loopfarm {
namespace {

constexpr double kPi = 3.14159265358979323846;

bool better(const EquilibriumSummary& candidate, const EquilibriumSummary& best) {
  const bool c_ok = candidate.status == SolveStatus::converged;
  const bool b_ok = best.status == SolveStatus::converged;
  if (c_ok != b_ok) return c_ok;
  if (c_ok) return candidate.energy < best.energy;
  return candidate.closure_residual < best.closure_residual;
}

}  // namespace

void AssemblyOptions::validate() const {
  if (guesses < 1) throw std::invalid_argument("guesses: must be >= 1, got " + std::to_string(guesses));
}

EquilibriumSummary assemble(const LoopModel& model, EquilibriumWorkspace& ws, double theta0,
                            const AssemblyOptions& options) {
  options.validate();
  const int n = model.joints();
  EquilibriumSummary best;
  bool have_best = false;
  for (int g = 0; g < options.guesses; ++g) {
    JointVector theta(n);
    int passive = 0;
    for (int i = 0; i < n; ++i) {
      if (i == model.options().input_joint) {
        theta[i] = theta0;
      } else {
        // Halton point g + 1: point 0 is zero in every base, a corner.
        theta[i] = -kPi + 2.0 * kPi * radical_inverse(kHaltonBases[static_cast<size_t>(passive++)], g + 1);
      }
    }
    const EquilibriumSummary s = solve_equilibrium(model, ws, theta0, EquilibriumState::at_angles(model, theta));
    if (!have_best || better(s, best)) {
      best = s;
      have_best = true;
    }
  }
  return best;
}

EquilibriumSummary assemble_from_angles(const LoopModel& model, EquilibriumWorkspace& ws, const JointVector& theta) {
  const EquilibriumState guess = EquilibriumState::at_angles(model, theta);
  return solve_equilibrium(model, ws, theta[model.options().input_joint], guess);
}

}  // namespace loopfarm
