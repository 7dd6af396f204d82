// The tracing of one circuit by pseudo-arclength continuation (motion.hpp,
// trace_circuit), shared by the motion's files. Internal to the core.
#pragma once

#include <vector>

#include "loopfarm/core/loop.hpp"
#include "loopfarm/core/motion.hpp"

namespace loopfarm::detail {

// The circuit through the closed pose x (polished), with the seeds of other
// branches met at bifurcations. `g` is scaled to L = 1.
struct TracedCircuit {
  Circuit circuit;
  std::vector<JointVector> branch_seeds;
};

TracedCircuit trace(const LoopGeometry& g, JointVector x, const MotionOptions& o);

}  // namespace loopfarm::detail
