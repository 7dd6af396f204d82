// The progress stops of a local search ([optimizer] progress_window and
// progress_factor; checkpoint_evaluations and checkpoint_objective): a start
// whose best objective has fallen by less than a factor over its last
// evaluations is creeping towards a minimum it would not reach within its
// budget; one whose best objective is still above checkpoint_objective after
// checkpoint_evaluations evaluations seldom reaches a zero. Gauss-Newton and
// the NLopt driver share them.
#pragma once

#include <algorithm>
#include <limits>
#include <vector>

#include "loopfarm/search/job.hpp"

namespace loopfarm::detail {

class ProgressWatch {
 public:
  // Sized once for the start's whole budget; each stop off when its
  // evaluations are 0.
  explicit ProgressWatch(const OptimizerSection& optimizer)
      : window_(optimizer.progress_window),
        factor_(optimizer.progress_factor),
        checkpoint_(optimizer.checkpoint_evaluations),
        checkpoint_objective_(optimizer.checkpoint_objective) {
    if (window_ > 0) best_.reserve(static_cast<size_t>(optimizer.max_evaluations) + 1);
  }

  // Records `value` (finite or not) seen after `evaluations` evaluations;
  // true once the best value so far is above the best of `window`
  // evaluations ago divided by the factor, or above the checkpoint's
  // objective at or after its evaluations.
  bool too_slow(int evaluations, double value) {
    if (evaluations < 0) return false;
    least_ = std::min(least_, value);
    if (checkpoint_ > 0 && evaluations >= checkpoint_ && !(least_ <= checkpoint_objective_)) {
      message_ = "objective above checkpoint_objective after checkpoint_evaluations evaluations";
      return true;
    }
    if (window_ <= 0) return false;
    const double best_before = best_.empty() ? kInfinity : best_.back();
    const double best = std::min(best_before, value);
    // best_[e]: the best value after e evaluations (+inf before the first).
    best_.resize(std::max(best_.size(), static_cast<size_t>(evaluations) + 1), best_before);
    best_[static_cast<size_t>(evaluations)] = best;
    if (evaluations < window_) return false;
    if (best > best_[static_cast<size_t>(evaluations - window_)] / factor_) {
      message_ = "objective fell by less than progress_factor over progress_window evaluations";
      return true;
    }
    return false;
  }

  // What a search stopped by too_slow says (LocalSearchSummary::message).
  const char* message() const { return message_; }

 private:
  static constexpr double kInfinity = std::numeric_limits<double>::infinity();
  int window_;
  double factor_;
  int checkpoint_;
  double checkpoint_objective_;
  double least_ = kInfinity;
  std::vector<double> best_;
  const char* message_ = "";
};

}  // namespace loopfarm::detail
