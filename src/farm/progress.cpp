#include "loopfarm/farm/progress.hpp"

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

}  // namespace

ProgressStyle default_progress_style() {
  if (!isatty(STDERR_FILENO)) return ProgressStyle::log;
  const char* term = std::getenv("TERM");
  if (term != nullptr && std::strcmp(term, "dumb") == 0) return ProgressStyle::log;
  return ProgressStyle::bar;
}

Progress::Progress(ProgressStyle style, double log_interval_s, std::FILE* out)
    : style_(style), interval_(log_interval_s), out_(out), start_(std::chrono::steady_clock::now()), last_(start_) {}

std::string Progress::line(const ProgressCounts& c, double elapsed_s) {
  const double rate = elapsed_s > 0 ? static_cast<double>(c.done_here) / elapsed_s : 0.0;
  const long left = c.total - c.done;
  const double eta = rate > 0 ? static_cast<double>(left) / rate : NAN;
  const double percent = c.total > 0 ? 100.0 * static_cast<double>(c.done) / static_cast<double>(c.total) : 100.0;
  char buffer[256];
  std::snprintf(buffer, sizeof buffer,
                "%ld/%ld starts (%.1f%%), %.3g starts/s, %ld zero minima, %ld candidates, ETA %s", c.done, c.total,
                percent, rate, c.zeros, c.candidates, left <= 0 ? "0s" : duration_text(eta).c_str());
  return buffer;
}

void Progress::update(const ProgressCounts& counts, bool force) {
  if (style_ == ProgressStyle::none) return;
  const auto now = std::chrono::steady_clock::now();
  const double since_last = std::chrono::duration<double>(now - last_).count();
  const double min_gap = style_ == ProgressStyle::bar ? 0.2 : interval_;
  if (!force && since_last < min_gap) return;
  last_ = now;
  const double elapsed = std::chrono::duration<double>(now - start_).count();
  const std::string text = line(counts, elapsed);
  if (style_ == ProgressStyle::bar) {
    constexpr int kWidth = 24;
    const double fraction = counts.total > 0 ? static_cast<double>(counts.done) / static_cast<double>(counts.total) : 1;
    const int filled = static_cast<int>(std::clamp(fraction, 0.0, 1.0) * kWidth);
    std::string bar(static_cast<size_t>(filled), '#');
    bar.resize(kWidth, '.');
    // \r and clear-to-end-of-line: redraw in place.
    std::fprintf(out_, "\r[%s] %s\033[K", bar.c_str(), text.c_str());
    drawn_ = true;
  } else {
    std::fprintf(out_, "loopfarm run: %s\n", text.c_str());
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
  finish();
  std::fprintf(out_, "loopfarm run: %s\n", text.c_str());
  std::fflush(out_);
}

}  // namespace loopfarm
