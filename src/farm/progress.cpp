// Progress of a farm run (progress.hpp).
#include "loopfarm/farm/progress.hpp"

#include <sys/ioctl.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>

namespace loopfarm {
namespace {

std::string duration_text(double seconds) {
  if (!std::isfinite(seconds) || seconds < 0) return "?";
  char buffer[32];
  const long s = std::lround(seconds);
  if (s < 60) {
    std::snprintf(buffer, sizeof buffer, "%lds", s);
  } else if (s < 3600) {
    std::snprintf(buffer, sizeof buffer, "%ldm%02lds", s / 60, s % 60);
  } else {
    std::snprintf(buffer, sizeof buffer, "%ldh%02ldm", s / 3600, (s % 3600) / 60);
  }
  return buffer;
}

// The width of the terminal `out` is, else $COLUMNS, else 80.
int terminal_columns(std::FILE* out) {
  winsize size{};
  if (out != nullptr && ::ioctl(fileno(out), TIOCGWINSZ, &size) == 0 && size.ws_col > 0) return size.ws_col;
  if (const char* columns = std::getenv("COLUMNS")) {
    const int n = std::atoi(columns);
    if (n > 0) return n;
  }
  return 80;
}

// 1234567 as "1,234,567".
std::string grouped(long n) {
  std::string digits = std::to_string(n < 0 ? -n : n);
  for (int at = static_cast<int>(digits.size()) - 3; at > 0; at -= 3) digits.insert(static_cast<size_t>(at), ",");
  return n < 0 ? "-" + digits : digits;
}

}  // namespace

ProgressStyle default_progress_style() {
  if (!isatty(STDERR_FILENO)) return ProgressStyle::log;
  const char* term = std::getenv("TERM");
  if (term != nullptr && std::strcmp(term, "dumb") == 0) return ProgressStyle::log;
  return ProgressStyle::bar;
}

Progress::Progress(ProgressStyle style, double log_interval_s, std::FILE* out, int columns)
    : style_(style),
      interval_(log_interval_s),
      out_(out),
      columns_(columns > 0 ? columns : terminal_columns(out)),
      start_(std::chrono::steady_clock::now()) {}

// The fields most wanted first (done, rate, ETA), so that a line cut to a
// narrow terminal loses the counts of zeros and candidates before them.
std::string Progress::line(const ProgressCounts& c, double elapsed_s) {
  const double rate = elapsed_s > 0 ? static_cast<double>(c.done_here) / elapsed_s : 0.0;
  const long left = c.total - c.done;
  const double eta = rate > 0 ? static_cast<double>(left) / rate : NAN;
  const double percent = c.total > 0 ? 100.0 * static_cast<double>(c.done) / static_cast<double>(c.total) : 100.0;
  char rate_text[32];
  if (rate >= 100.0) {
    std::snprintf(rate_text, sizeof rate_text, "%s", grouped(std::lround(rate)).c_str());
  } else {
    std::snprintf(rate_text, sizeof rate_text, "%.3g", rate);
  }
  char buffer[256];
  std::snprintf(buffer, sizeof buffer, "%s/%s starts (%.1f%%), %s starts/s, ETA %s, %s zero minima, %s candidates",
                grouped(c.done).c_str(), grouped(c.total).c_str(), percent, rate_text,
                left <= 0 ? "0s" : duration_text(eta).c_str(), grouped(c.zeros).c_str(), grouped(c.candidates).c_str());
  return buffer;
}

std::string Progress::bar_line(const ProgressCounts& counts, double elapsed_s, int columns) {
  const std::string text = line(counts, elapsed_s);
  const int room = columns - 1;  // the last column left free: writing there wraps on some terminals
  constexpr int kMaxBar = 24, kMinBar = 8;
  const int bar_width = std::min(kMaxBar, room - static_cast<int>(text.size()) - 3);
  std::string out;
  if (bar_width >= kMinBar) {
    const double fraction = counts.total > 0 ? static_cast<double>(counts.done) / static_cast<double>(counts.total) : 1;
    const int filled = static_cast<int>(std::clamp(fraction, 0.0, 1.0) * bar_width);
    std::string bar(static_cast<size_t>(filled), '#');
    bar.resize(static_cast<size_t>(bar_width), '.');
    out = "[" + bar + "] ";
  }
  out += text;
  if (static_cast<int>(out.size()) > room) out.resize(static_cast<size_t>(std::max(room, 0)));
  return out;
}

void Progress::update(const ProgressCounts& counts, bool force) {
  update_at(counts, std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count(), force);
}

void Progress::update_at(const ProgressCounts& counts, double elapsed_s, bool force) {
  if (style_ == ProgressStyle::none || style_ == ProgressStyle::silent) return;
  // A bar shows at once; a log's first line comes within kFirstLog (a run
  // under mpirun shows it is alive), the next ones every interval_.
  const double gap = style_ == ProgressStyle::bar ? (shown_ ? kBarInterval : 0.0)
                                                  : (shown_ ? interval_ : std::min(interval_, kFirstLog));
  if (!force && elapsed_s - last_s_ < gap) return;
  last_s_ = elapsed_s;
  shown_ = true;
  if (style_ == ProgressStyle::bar) {
    // \r and clear-to-end-of-line: redraw in place.
    std::fprintf(out_, "\r%s\033[K", bar_line(counts, elapsed_s, columns_).c_str());
    drawn_ = true;
  } else {
    std::fprintf(out_, "loopfarm run: %s\n", line(counts, elapsed_s).c_str());
  }
  std::fflush(out_);
}

void Progress::finish() {
  if (style_ == ProgressStyle::bar && drawn_) {
    std::fputc('\n', out_);
    std::fflush(out_);
  }
  drawn_ = false;
}

void Progress::message(const std::string& text) {
  if (style_ == ProgressStyle::silent) return;
  finish();
  std::fprintf(out_, "loopfarm run: %s\n", text.c_str());
  std::fflush(out_);
}

}  // namespace loopfarm
