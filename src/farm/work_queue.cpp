// The farm's work queue (work_queue.hpp).
#include "loopfarm/farm/work_queue.hpp"

#include <algorithm>
#include <stdexcept>

namespace loopfarm {

PendingCursor::PendingCursor(const std::vector<IndexRange>& committed, IndexRange range) {
  std::uint64_t from = range.first;
  for (const IndexRange& c : committed) {
    if (c.first >= range.last) break;
    if (c.first > from) todo_.push_back({from, c.first});
    from = std::max(from, c.last);
  }
  if (from < range.last) todo_.push_back({from, range.last});
  if (!todo_.empty()) at_ = todo_.front().first;
}

void PendingCursor::advance() {
  if (++at_ >= todo_[range_].last && ++range_ < todo_.size()) at_ = todo_[range_].first;
}

std::uint64_t PendingCursor::count() const {
  std::uint64_t n = 0;
  for (const IndexRange& r : todo_) n += r.last - r.first;
  return n;
}

Dispenser::Dispenser(PendingCursor pending, int chunk, int workers, const StopFlag& stop)
    : cursor_(std::move(pending)), left_(cursor_.count()), chunk_(chunk), workers_(workers), stop_(stop) {
  if (chunk_ < 1 || workers_ < 1) throw std::invalid_argument("Dispenser: chunk and workers must be >= 1");
}

std::vector<std::uint64_t> Dispenser::take() {
  std::lock_guard lock(mutex_);
  std::vector<std::uint64_t> out;
  if (stop_.requested()) return out;
  const std::uint64_t guided = std::max<std::uint64_t>(1, left_ / (2 * static_cast<std::uint64_t>(workers_)));
  const std::uint64_t size = std::min(static_cast<std::uint64_t>(chunk_), guided);
  while (out.size() < size && !cursor_.done()) {
    out.push_back(cursor_.peek());
    cursor_.advance();
  }
  left_ -= out.size();
  return out;
}

void OrderedCommits::add(StartRecord record) {
  const std::uint64_t index = record.index;
  held_.emplace(index, std::move(record));
}

void OrderedCommits::move_ready(std::vector<StartRecord>& out) {
  while (!cursor_.done()) {
    auto it = held_.find(cursor_.peek());
    if (it == held_.end()) break;
    out.push_back(std::move(it->second));
    held_.erase(it);
    cursor_.advance();
  }
}

void OrderedCommits::move_all(std::vector<StartRecord>& out) {
  move_ready(out);
  for (auto& [index, record] : held_) out.push_back(std::move(record));
  held_.clear();
}

std::vector<StartRecord> OrderedCommits::ready() {
  std::vector<StartRecord> out;
  move_ready(out);
  return out;
}

std::vector<StartRecord> OrderedCommits::all() {
  std::vector<StartRecord> out;
  move_all(out);
  return out;
}

}  // namespace loopfarm
