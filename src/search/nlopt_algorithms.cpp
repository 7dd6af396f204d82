// The names of the local algorithms a job may ask for (job.hpp): Gauss-Newton
// and the NLopt algorithms of Debian's build that run on their own. With
// nlopt_search.cpp, the only place that knows NLopt.
#include <string>

#include <nlopt.h>

#include "loopfarm/search/job.hpp"

namespace loopfarm {

bool is_known_algorithm(const std::string& name) {
  if (name == "gauss-newton") return true;
  // Not in Debian's build of NLopt (they fail with invalid_args).
  if (name == "GD_STOGO" || name == "GD_STOGO_RAND" || name == "GN_AGS" || name == "LD_LBFGS_NOCEDAL") return false;
  // AUGLAG and MLSL drive a subsidiary local optimiser that a job cannot
  // name; without one NLopt rejects them or crashes (MLSL, LD_AUGLAG).
  if (name.find("AUGLAG") != std::string::npos || name.find("MLSL") != std::string::npos) return false;
  return static_cast<int>(nlopt_algorithm_from_string(name.c_str())) >= 0;
}

}  // namespace loopfarm
