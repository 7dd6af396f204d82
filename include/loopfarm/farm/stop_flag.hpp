// A request to stop a farm run: set from a signal handler (SIGINT, SIGTERM,
// SIGUSR1), by a worker that caught one, or on an error; read by everything
// that hands out or runs starts. Lock-free, so a signal handler may set it.
#pragma once

#include <atomic>

namespace loopfarm {

class StopFlag {
 public:
  // `signal`: the signal's number, or -1 for a stop without one (an error).
  // The first request is the one remembered.
  void request(int signal) noexcept {
    int none = 0;
    signal_.compare_exchange_strong(none, signal == 0 ? -1 : signal, std::memory_order_relaxed);
  }
  bool requested() const noexcept { return signal_.load(std::memory_order_relaxed) != 0; }
  // 0 while running.
  int signal() const noexcept { return signal_.load(std::memory_order_relaxed); }

 private:
  static_assert(std::atomic<int>::is_always_lock_free, "a signal handler sets the flag");
  std::atomic<int> signal_{0};
};

}  // namespace loopfarm
