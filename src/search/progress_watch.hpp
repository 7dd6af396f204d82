// The progress stop of a local search ([optimizer] progress_window and
// progress_factor): a start whose best objective has fallen by less than a
// factor over its last evaluations is creeping towards a minimum it would not
// reach within its budget. Gauss-Newton and the NLopt driver share it.
#pragma once

#include <algorithm>
#include <limits>
#include <vector>

#include "loopfarm/search/job.hpp"

namespace loopfarm::detail {

class ProgressWatch {
 public:
  // What a search stopped by it says (LocalSearchSummary::message).
  static constexpr const char* kMessage =
      "objective fell by less than progress_factor over progress_window evaluations";

  // Sized once for the start's whole budget; off when window is 0.
  explicit ProgressWatch(const OptimizerSection& optimizer)
      : window_(optimizer.progress_window), factor_(optimizer.progress_factor) {
    if (window_ > 0) best_.reserve(static_cast<size_t>(optimizer.max_evaluations) + 1);
  }

  // Records `value` (finite or not) seen after `evaluations` evaluations;
  // true once the best value so far is above the best of `window`
  // evaluations ago divided by the factor.
  bool too_slow(int evaluations, double value) {
    if (window_ <= 0 || evaluations < 0) return false;
    const double best_before = best_.empty() ? kInfinity : best_.back();
    const double best = std::min(best_before, value);
    // best_[e]: the best value after e evaluations (+inf before the first).
    best_.resize(std::max(best_.size(), static_cast<size_t>(evaluations) + 1), best_before);
    best_[static_cast<size_t>(evaluations)] = best;
    if (evaluations < window_) return false;
    return best > best_[static_cast<size_t>(evaluations - window_)] / factor_;
  }

 private:
  static constexpr double kInfinity = std::numeric_limits<double>::infinity();
  int window_;
  double factor_;
  std::vector<double> best_;
};

}  // namespace loopfarm::detail
