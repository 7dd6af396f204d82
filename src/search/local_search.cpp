#include "loopfarm/search/local_search.hpp"

#include <limits>
#include <string>

namespace loopfarm {

const char* to_string(SearchStatus status) {
  switch (status) {
    case SearchStatus::stopval_reached:
      return "stopval_reached";
    case SearchStatus::ftol_reached:
      return "ftol_reached";
    case SearchStatus::xtol_reached:
      return "xtol_reached";
    case SearchStatus::maxeval_reached:
      return "maxeval_reached";
    case SearchStatus::slow_progress:
      return "slow_progress";
    case SearchStatus::maxtime_reached:
      return "maxtime_reached";
    case SearchStatus::roundoff_limited:
      return "roundoff_limited";
    case SearchStatus::stalled:
      return "stalled";
    case SearchStatus::forced_stop:
      return "forced_stop";
    case SearchStatus::failure:
      return "failure";
    case SearchStatus::invalid_args:
      return "invalid_args";
    case SearchStatus::out_of_memory:
      return "out_of_memory";
    case SearchStatus::evaluation_failed:
      return "evaluation_failed";
  }
  return "unknown";
}

LocalSearchSummary local_minimize(CycleObjective& objective, const Eigen::VectorXd& x0,
                                  const LocalSearchOptions& options) {
  if (!x0.allFinite() || x0.size() != objective.space().free_count()) {
    LocalSearchSummary summary;
    summary.x = x0;
    summary.value = std::numeric_limits<double>::quiet_NaN();
    summary.E_mean = summary.E_max = std::numeric_limits<double>::quiet_NaN();
    summary.status = SearchStatus::evaluation_failed;
    summary.message = x0.size() != objective.space().free_count()
                          ? "the start has " + std::to_string(x0.size()) + " values for " +
                                std::to_string(objective.space().free_count()) + " free parameters"
                          : "the start has a non-finite value";
    return summary;
  }
  if (options.optimizer.algorithm == "gauss-newton") return minimize_gauss_newton(objective, x0, options);
  return minimize_nlopt(objective, x0, options);
}

}  // namespace loopfarm
