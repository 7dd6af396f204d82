#include "loopfarm/core/cycle_start.hpp"

#include <cmath>
#include <utility>

#include "loopfarm/core/assembly.hpp"

namespace loopfarm {

CycleStart choose_cycle_start(const LoopModel& model, EquilibriumWorkspace& workspace, double theta0,
                              const JointVector* given, const CycleStartOptions& options) {
  CycleStart out;
  MotionOptions motion;
  motion.input_joint = model.options().input_joint;
  motion.all_extremes = false;
  if (given) {
    out.assembly = assemble_from_angles(model, workspace, *given);
    out.motion = motion_start(model.geometry(), theta0, &out.assembly.state.theta, options.min_travel, motion);
    // On a motion only if it is the given pose's own.
    for (int k = 0; out.motion && k < model.joints(); ++k) {
      if (std::abs(wrap_angle(out.motion->pose[k] - out.assembly.state.theta[k])) > 1e-6) out.motion.reset();
    }
  } else {
    out.assembly = assemble(model, workspace, theta0);
    out.motion = motion_start(model.geometry(), theta0, &out.assembly.state.theta, options.min_travel, motion);
    if (out.motion) {
      EquilibriumSummary on_motion = assemble_from_angles(model, workspace, out.motion->pose);
      if (on_motion.status == SolveStatus::converged) {
        out.assembly = std::move(on_motion);
      } else {
        out.motion.reset();
      }
    }
  }
  out.range = options.range ? *options.range : out.motion ? out.motion->range : 2.0 * 3.14159265358979323846;
  return out;
}

}  // namespace loopfarm
