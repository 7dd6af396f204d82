// Assembly: the loop's initial pose at the input angle theta0.
//
// From given joint angles, the equilibrium solve starts there. Without them a
// loop may assemble in several ways, so a fixed set of deterministic guesses
// (a Halton sequence over the passive angles) is solved and the least-energy
// converged assembly kept: the same geometry always assembles the same way.
#pragma once

#include "loopfarm/core/equilibrium.hpp"

namespace loopfarm {

struct AssemblyOptions {
  int guesses = 24;  // deterministic starting guesses tried (>= 1)
  void validate() const;
};

// Least-energy equilibrium at theta0 over the deterministic guesses. The
// summary's status is `converged` if any guess converged.
EquilibriumSummary assemble(const LoopModel& model, EquilibriumWorkspace& workspace, double theta0,
                            const AssemblyOptions& options = {});

// Equilibrium at theta[input_joint] started from the given joint angles.
EquilibriumSummary assemble_from_angles(const LoopModel& model, EquilibriumWorkspace& workspace,
                                        const JointVector& theta);

}  // namespace loopfarm
