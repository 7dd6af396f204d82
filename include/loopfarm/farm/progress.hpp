// Progress of a farm run on rank 0's stderr: starts done of total, rate,
// zero minima and candidates so far, ETA. On a terminal a bar redrawn in
// place (at most 5 times a second); otherwise (batch logs) one line every
// `log_interval` seconds. Never on stdout, which carries results.
#pragma once

#include <chrono>
#include <cstdio>
#include <string>

namespace loopfarm {

enum class ProgressStyle { bar, log, none };

// bar when stderr is a terminal and NO_COLOR/TERM=dumb do not say otherwise,
// else log. ECOSYSTEM.md: under mpirun stdout is a pty even when redirected;
// stderr tells the truth.
ProgressStyle default_progress_style();

struct ProgressCounts {
  long done = 0;        // starts committed, this run in total (earlier sessions included)
  long total = 0;       // the run's target
  long done_here = 0;   // done in this session (for the rate)
  long zeros = 0;       // zero minima so far (this run)
  long candidates = 0;  // distinct verified linkages in the database
};

class Progress {
 public:
  Progress(ProgressStyle style, double log_interval_s = 10.0, std::FILE* out = stderr);
  // Draws or logs if it is time to; `force` draws now (the final state).
  void update(const ProgressCounts& counts, bool force = false);
  // Ends the bar's line so that later messages start on a fresh line.
  void finish();
  // One line "loopfarm run: TEXT" on the same stream, the bar's line ended first.
  void message(const std::string& text);

  // The text of one report, without a line end (for tests and logs).
  static std::string line(const ProgressCounts& counts, double elapsed_s);

 private:
  ProgressStyle style_;
  double interval_;
  std::FILE* out_;
  std::chrono::steady_clock::time_point start_;
  std::chrono::steady_clock::time_point last_;
  bool drawn_ = false;
};

}  // namespace loopfarm
