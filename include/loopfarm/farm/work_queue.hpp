// The farm's work queue: which start indices are still to run, handing them
// out in chunks, and putting finished records back into index order.
//
// Results do not depend on the number of workers, the chunk size or timing:
// every start is a function of (job, seed, index) alone, and the coordinator
// commits records in the order of their start indices (holding back those
// that arrive early), so two uninterrupted runs write the same rows in the
// same order. A stopped run commits whatever finished, gaps included; a resume
// runs exactly the starts that are not committed.
#pragma once

#include <cstdint>
#include <map>
#include <mutex>
#include <vector>

#include "loopfarm/farm/results.hpp"
#include "loopfarm/farm/results_database.hpp"
#include "loopfarm/farm/stop_flag.hpp"

namespace loopfarm {

// The start indices still to run, in increasing order: [0, starts), or the
// range of a slice, less the committed ranges, walked by a cursor (kept as
// ranges: a run may have 1e8 starts).
class PendingCursor {
 public:
  PendingCursor() = default;
  PendingCursor(const std::vector<IndexRange>& committed, std::uint64_t starts)
      : PendingCursor(committed, IndexRange{0, starts}) {}
  PendingCursor(const std::vector<IndexRange>& committed, IndexRange range);
  bool done() const { return range_ >= todo_.size(); }
  std::uint64_t peek() const { return at_; }
  void advance();
  std::uint64_t count() const;

 private:
  std::vector<IndexRange> todo_;
  size_t range_ = 0;
  std::uint64_t at_ = 0;
};

// Hands out the pending start indices in chunks, in increasing order; nothing
// once a stop is requested. Thread-safe. A chunk holds at most `chunk`
// indices, and at most 1 / (2 workers) of those left (at least one), as
// guided scheduling does: large chunks while much is left, for few requests,
// and small ones at the end, so that `workers` workers share the last starts
// (and share a run smaller than workers * chunk at all).
class Dispenser {
 public:
  Dispenser(PendingCursor pending, int chunk, int workers, const StopFlag& stop);
  std::vector<std::uint64_t> take();

 private:
  std::mutex mutex_;
  PendingCursor cursor_;
  std::uint64_t left_;
  int chunk_;
  int workers_;
  const StopFlag& stop_;
};

// Holds records until every pending index before them has arrived, so that
// commits follow start-index order whatever the arrival order.
class OrderedCommits {
 public:
  explicit OrderedCommits(PendingCursor pending) : cursor_(std::move(pending)) {}
  void add(StartRecord record);
  // Moves the records now in order (those with every earlier pending index
  // in) to the end of `out`.
  void move_ready(std::vector<StartRecord>& out);
  // Moves everything held, gaps or not (a stopped run), to the end of `out`.
  void move_all(std::vector<StartRecord>& out);
  // The same as new vectors.
  std::vector<StartRecord> ready();
  std::vector<StartRecord> all();

 private:
  PendingCursor cursor_;
  std::map<std::uint64_t, StartRecord> held_;
};

}  // namespace loopfarm
