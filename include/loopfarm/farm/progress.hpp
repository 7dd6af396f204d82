// Progress of a farm run on rank 0's stderr: starts finished of total, rate,
// zero minima, candidates, ETA. On a terminal a bar redrawn in place, at most
// 4 times a second, that fits the terminal's width; otherwise (batch logs,
// mpirun) a first line within 2 s and then one line every `log_interval`
// seconds. Never on stdout, which carries results.
#pragma once

#include <chrono>
#include <cstdio>
#include <string>

namespace loopfarm {

// none: no progress, but notes such as "resuming run 1" still show;
// silent: nothing at all (loopfarm run --quiet).
enum class ProgressStyle { bar, log, none, silent };

// bar when stderr is a terminal and NO_COLOR/TERM=dumb do not say otherwise,
// else log. ECOSYSTEM.md: under mpirun stdout is a pty even when redirected;
// stderr tells the truth.
ProgressStyle default_progress_style();

struct ProgressCounts {
  long done = 0;        // starts finished, this run in total (earlier sessions included)
  long total = 0;       // the run's target
  long done_here = 0;   // finished in this session (for the rate)
  long zeros = 0;       // zero minima so far (this run)
  long candidates = 0;  // distinct verified linkages in the database (known once committed)
};

class Progress {
 public:
  // `columns`: the width a bar must fit; 0 asks the terminal `out` is (or
  // $COLUMNS, else 80).
  Progress(ProgressStyle style, double log_interval_s = 10.0, std::FILE* out = stderr, int columns = 0);
  // Draws or logs if it is time to; `force` draws now (the final state).
  void update(const ProgressCounts& counts, bool force = false);
  // The same at `elapsed_s` seconds after construction (tests drive the clock).
  void update_at(const ProgressCounts& counts, double elapsed_s, bool force);
  // Ends the bar's line so that later messages start on a fresh line.
  void finish();
  // One line "loopfarm run: TEXT" on the same stream, the bar's line ended first.
  void message(const std::string& text);

  // The text of one report, without a line end (for tests and logs).
  static std::string line(const ProgressCounts& counts, double elapsed_s);
  // The bar's line for a terminal `columns` wide: "[###...] " and line(), the
  // bar shortened or left out, and the text cut, so that it is at most
  // columns - 1 characters (the cursor never wraps).
  static std::string bar_line(const ProgressCounts& counts, double elapsed_s, int columns);

  // The gaps between redraws of the bar, and before a log's first line.
  static constexpr double kBarInterval = 0.25;
  static constexpr double kFirstLog = 2.0;

 private:
  ProgressStyle style_;
  double interval_;
  std::FILE* out_;
  int columns_;
  std::chrono::steady_clock::time_point start_;
  double last_s_ = 0.0;  // when the last line was drawn or logged, from start_
  bool shown_ = false;   // a line has been drawn or logged
  bool drawn_ = false;   // the bar's line is open
};

}  // namespace loopfarm
