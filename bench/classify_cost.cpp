// What classify costs a loop: the loops read from standard input, one a line,
// each classified once by loopfarm::classify with every joint taken as moving
// (a travel of 1 rad each, so none is frozen) and the pose all zeros, so
// where the pose or the motion decides (trivial, degenerate, cubic_321) the
// family can differ from the one the farm stored. The families found are
// deterministic (counts, not times), so two builds compare exactly; the wall
// time is the steady clock's over the classify calls alone, after every line
// has been read and checked.
//
// A line is one n-joint loop (4 <= n <= 8): its 3n numbers a1..an,
// alpha1..alphan in degrees, d1..dn, separated by whitespace or '|' (what
// sqlite3 prints). The 6R loops of a generic 6R run that are not trivial:
//
//   LOOPFARM=build/release/tools/loopfarm NP=2 jobs/mpirun-local.sh jobs/generic-6r.toml --db g6.sqlite -q
//   sqlite3 g6.sqlite "select a1, a2, a3, a4, a5, a6, alpha1_deg, alpha2_deg, alpha3_deg, alpha4_deg,
//                      alpha5_deg, alpha6_deg, d1, d2, d3, d4, d5, d6
//                      from candidates where family != 'trivial'" > nontrivial.txt
//   build/release/bench/classify_cost < nontrivial.txt
//
// Prints the number of loops, the count of each family returned (in the
// order of kAllFamilies) and the wall time a loop. Instruction counts, on the
// build docs/performance.md measures them with (RelWithDebInfo, build/test):
//
//   valgrind --tool=callgrind --callgrind-out-file=classify.out build/test/bench/classify_cost < nontrivial.txt
//   callgrind_annotate --inclusive=yes classify.out | grep -m1 'loopfarm::classify('
//
// A line that is not a loop (a count of numbers that is not 3n, a word that
// is not a number, a value that is not finite or beyond a double, a geometry
// that classify refuses) is one line on stderr naming its line number, and
// exit 2; nothing is classified then.
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <iostream>
#include <map>
#include <span>
#include <stdexcept>
#include <string>
#include <system_error>
#include <vector>

#include "loopfarm/core/loop.hpp"
#include "loopfarm/search/classify.hpp"

namespace {

using loopfarm::LoopGeometry;

struct InputLoop {
  long line = 0;
  LoopGeometry geometry;
};

[[noreturn]] void refuse(long line, const std::string& message) {
  std::fprintf(stderr, "classify_cost: line %ld: %s\n", line, message.c_str());
  std::exit(2);
}

bool is_separator(char c) { return c == '|' || c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

// The line's numbers, or a refusal naming it.
std::vector<double> numbers_of(const std::string& text, long line) {
  std::vector<double> out;
  size_t i = 0;
  while (i < text.size()) {
    if (is_separator(text[i])) {
      ++i;
      continue;
    }
    size_t end = i;
    while (end < text.size() && !is_separator(text[end])) ++end;
    const std::string word = text.substr(i, end - i);
    // from_chars takes no '+' sign; a number may still carry one.
    const char* first = word.data() + (word.size() > 1 && word[0] == '+' && word[1] != '-' ? 1 : 0);
    const char* last = word.data() + word.size();
    double value = 0.0;
    const auto [stop, error] = std::from_chars(first, last, value);
    if (stop != last || (error != std::errc() && error != std::errc::result_out_of_range)) {
      refuse(line, "\"" + word + "\" (number " + std::to_string(out.size() + 1) + ") is not a number");
    }
    if (error == std::errc::result_out_of_range) {
      refuse(line, "\"" + word + "\" (number " + std::to_string(out.size() + 1) + ") is out of a double's range");
    }
    if (!std::isfinite(value)) {
      refuse(line, "\"" + word + "\" (number " + std::to_string(out.size() + 1) + ") is not finite");
    }
    out.push_back(value);
    i = end;
  }
  return out;
}

LoopGeometry geometry_of(const std::vector<double>& numbers, long line) {
  const size_t count = numbers.size();
  const size_t n = count / 3;
  if (count % 3 != 0 || n < 4 || n > static_cast<size_t>(loopfarm::kMaxJoints)) {
    refuse(line, std::to_string(count) + " numbers; a loop of n joints is 3n (a, alpha in degrees, d), n from 4 to " +
                     std::to_string(loopfarm::kMaxJoints));
  }
  const std::span<const double> all(numbers);
  try {
    LoopGeometry g = LoopGeometry::from_degrees(all.subspan(0, n), all.subspan(n, n), all.subspan(2 * n, n));
    loopfarm::validate_geometry(g);
    return g;
  } catch (const std::invalid_argument& error) {
    refuse(line, std::string("not a loop: ") + error.what());
  }
}

}  // namespace

int main(int argc, char** argv) {
  using namespace loopfarm;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--help") == 0 || std::strcmp(argv[i], "-h") == 0) {
      std::printf("usage: classify_cost < LOOPS (one a line: a1..an alpha1..alphan [deg] d1..dn)\n");
      return 0;
    }
    std::fprintf(stderr, "classify_cost: unknown option %s (the loops come on standard input)\n", argv[i]);
    return 2;
  }

  std::vector<InputLoop> loops;
  std::string text;
  long line = 0;
  while (std::getline(std::cin, text)) {
    ++line;
    loops.push_back({line, geometry_of(numbers_of(text, line), line)});
  }
  if (std::cin.bad()) {
    std::fprintf(stderr, "classify_cost: standard input could not be read after line %ld\n", line);
    return 2;
  }

  std::map<Family, long> count;
  const auto start = std::chrono::steady_clock::now();
  for (const InputLoop& loop : loops) {
    const int n = loop.geometry.joints();
    try {
      ++count[classify(loop.geometry, JointVector::Zero(n), std::vector<double>(static_cast<size_t>(n), 1.0)).family];
    } catch (const std::invalid_argument& error) {
      refuse(loop.line, std::string("classify refuses it: ") + error.what());
    }
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  std::printf("%zu loops\n", loops.size());
  for (const Family family : kAllFamilies) {
    if (const auto found = count.find(family); found != count.end()) {
      std::printf("%-32s %6ld\n", to_string(family), found->second);
    }
  }
  if (loops.empty()) {
    std::printf("wall time %.6f s\n", seconds);
  } else {
    std::printf("wall time %.6f s, %.6f ms a loop\n", seconds, 1e3 * seconds / static_cast<double>(loops.size()));
  }
  return 0;
}
