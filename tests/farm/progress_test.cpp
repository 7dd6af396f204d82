// A farm run's progress: the bar fits the terminal it is drawn on and redraws
// at most 4 times a second; a log's first line comes within 2 s and the next
// every interval; the coordinator counts starts as their records arrive,
// before the batch holding them is committed. The clock is driven by the
// tests (Progress::update_at), the output captured in memory.
#include "loopfarm/farm/progress.hpp"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <regex>
#include <string>
#include <vector>

#include <gtest/gtest.h>

namespace loopfarm {
namespace {

// What a Progress writes, captured through open_memstream.
class Capture {
 public:
  Capture() : file_(open_memstream(&buffer_, &size_)) {}
  ~Capture() {
    if (file_ != nullptr) std::fclose(file_);
    std::free(buffer_);
  }
  std::FILE* file() { return file_; }
  std::string text() {
    std::fflush(file_);
    return std::string(buffer_, size_);
  }

 private:
  char* buffer_ = nullptr;
  size_t size_ = 0;
  std::FILE* file_;
};

ProgressCounts large_counts() {
  ProgressCounts c;
  c.done = 1'234'567;
  c.total = 10'000'000;
  c.done_here = 1'234'567;
  c.zeros = 501'234;
  c.candidates = 499'876;
  return c;
}

TEST(Progress, TheBarFitsTheTerminalAndKeepsTheEtaOnEightyColumns) {
  for (int columns : {200, 120, 100, 80, 60, 40, 10}) {
    const std::string line = Progress::bar_line(large_counts(), 250.0, columns);
    EXPECT_LE(static_cast<int>(line.size()), columns - 1) << columns << ": " << line;
  }
  const std::string wide = Progress::bar_line(large_counts(), 250.0, 200);
  EXPECT_EQ(wide.rfind("[##", 0), 0u) << wide;  // 12 % of a 24-character bar
  EXPECT_NE(wide.find("499,876 candidates"), std::string::npos) << wide;
  const std::string eighty = Progress::bar_line(large_counts(), 250.0, 80);
  EXPECT_NE(eighty.find("1,234,567/10,000,000 starts (12.3%), 4,938 starts/s, ETA 29m35s"), std::string::npos)
      << eighty;
}

TEST(Progress, TheLineGroupsDigitsAndPutsTheRateAndEtaFirst) {
  ProgressCounts c;
  c.done = 1200;
  c.total = 4000;
  c.done_here = 1200;
  c.zeros = 402;
  c.candidates = 398;
  EXPECT_EQ(Progress::line(c, 60.0),
            "1,200/4,000 starts (30.0%), 20 starts/s, ETA 2m20s, 402 zero minima, 398 candidates");
  c.done = c.total;  // the ETA of a finished run
  EXPECT_EQ(Progress::line(c, 60.0),
            "4,000/4,000 starts (100.0%), 20 starts/s, ETA 0s, 402 zero minima, 398 candidates");
  c.done_here = 123'456;  // a rate of 100 and more, to the start
  EXPECT_EQ(Progress::line(c, 1.0).find("123,456 starts/s"), std::string("4,000/4,000 starts (100.0%), ").size());
}

// Every redraw starts with \r.
int redraws(const std::string& text) { return static_cast<int>(std::count(text.begin(), text.end(), '\r')); }

TEST(Progress, TheBarShowsAtOnceAndRedrawsAtMostFourTimesASecond) {
  Capture out;
  Progress progress(ProgressStyle::bar, 10.0, out.file(), 80);
  ProgressCounts c = large_counts();
  for (int tick = 0; tick <= 100; ++tick) progress.update_at(c, 0.01 * tick, false);  // one second, 101 updates
  EXPECT_EQ(redraws(out.text()), 5);                                                  // at 0, 0.25, 0.5, 0.75 and 1.0 s
  progress.update_at(c, 1.01, true);                                                  // forced: the final state
  EXPECT_EQ(redraws(out.text()), 6);
  progress.finish();
  // Each redraw fits: \r, at most 79 characters, clear to the end of the line.
  const std::string text = out.text();
  size_t at = 0;
  while ((at = text.find('\r', at)) != std::string::npos) {
    const size_t end = text.find("\033[K", at);
    ASSERT_NE(end, std::string::npos);
    EXPECT_LE(end - at - 1, 79u);
    at = end;
  }
  EXPECT_EQ(text.back(), '\n');
}

TEST(Progress, ALogShowsItsFirstLineWithinTwoSecondsThenEveryInterval) {
  Capture out;
  Progress progress(ProgressStyle::log, 10.0, out.file());
  ProgressCounts c = large_counts();
  std::vector<double> times;
  for (int tick = 0; tick <= 250; ++tick) {
    const size_t before = out.text().size();
    progress.update_at(c, 0.1 * tick, false);
    if (out.text().size() != before) times.push_back(0.1 * tick);
  }
  ASSERT_EQ(times.size(), 3u) << out.text();
  EXPECT_NEAR(times[0], 2.0, 1e-9);
  EXPECT_NEAR(times[1], 12.0, 1e-9);
  EXPECT_NEAR(times[2], 22.0, 1e-9);
  EXPECT_EQ(out.text().rfind("loopfarm run: 1,234,567/10,000,000 starts (12.3%)", 0), 0u) << out.text();
}

TEST(Progress, NoneWritesNoProgressButItsNotes) {
  Capture out;
  Progress progress(ProgressStyle::none, 0.0, out.file());
  progress.update_at(large_counts(), 5.0, true);
  progress.finish();
  progress.message("resuming run 1");
  EXPECT_EQ(out.text(), "loopfarm run: resuming run 1\n");
}

TEST(Progress, SilentWritesNothing) {
  Capture out;
  Progress progress(ProgressStyle::silent, 0.0, out.file());
  progress.update_at(large_counts(), 5.0, true);
  progress.message("resuming run 1");
  progress.finish();
  EXPECT_EQ(out.text(), "");
}

}  // namespace
}  // namespace loopfarm
