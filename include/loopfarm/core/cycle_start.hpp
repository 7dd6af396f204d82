// Where a cycle of the elastic model starts and what input range it covers,
// chosen from the rigid loop's motion (motion.hpp): a movable loop reads zero
// cycle energy only when it is driven along its motion, from an assembly on
// a moving circuit, over input angles that circuit reaches.
#pragma once

#include <optional>

#include "loopfarm/core/equilibrium.hpp"
#include "loopfarm/core/motion.hpp"

namespace loopfarm {

struct CycleStartOptions {
  // [rad] The range to cover as asked (2 pi: a full turn); empty: the
  // motion's window (cycle_window), or a full turn off a motion.
  std::optional<double> range;
  // [rad] The least input travel of a circuit that moves without closing.
  double min_travel = 3.14159265358979323846 / 180.0;
};

struct CycleStart {
  EquilibriumSummary assembly;        // the cycle's start state at theta0
  std::optional<MotionStart> motion;  // the motion the assembly lies on, if any
  double range = 0.0;                 // [rad] the input range the cycle covers
};

// The assembly: from `given` angles (may be null) when given, and on a
// motion only if it is that pose's own circuit; otherwise an assembly at
// theta0 on a motion (motion_start, nearest the least-energy assembly
// first), else the least-energy assembly of assemble(). The range: as asked;
// otherwise the motion's window when the assembly lies on one, else a full
// turn. The workspace must belong to `model`.
CycleStart choose_cycle_start(const LoopModel& model, EquilibriumWorkspace& workspace, double theta0,
                              const JointVector* given, const CycleStartOptions& options = {});

}  // namespace loopfarm
