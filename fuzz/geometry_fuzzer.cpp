// libFuzzer target: how the commands read a geometry (tools/geometry_input.cpp,
// tools/geometry_options.cpp, tools/cli_support.cpp).
//
// The first byte picks what the rest of the input is:
//   0  the text of a --geometry TOML file (geometry_from_toml_text, make_geometry)
//   1  command-line arguments, one per line, given to the geometry flags of a
//      CLI11 app exactly as energy and verify register them (read_geometry)
//   2  one option value for parse_number, parse_integer and parse_number_list
// Bad input must end in the exceptions the command line turns into exit code 2
// (UsageError, std::invalid_argument from the library's validate_geometry,
// CLI::ParseError from CLI11) with a one-line message; anything else, an
// accepted value that breaks the documented rules, or a sanitizer report is a
// bug, and the fuzzer aborts on it.
#include <cerrno>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include <CLI/CLI.hpp>

#include "cli_support.hpp"
#include "geometry_input.hpp"
#include "geometry_options.hpp"
#include "loopfarm/core/loop.hpp"

namespace {

using namespace loopfarm::cli;

[[noreturn]] void fail(const std::string& what) {
  std::fprintf(stderr, "geometry_fuzzer: contract broken: %s\n", what.c_str());
  std::abort();
}

void check(bool condition, const std::string& what) {
  if (!condition) fail(what);
}

// A message the command prints must stay one line after one_line(), and must
// not be empty after its "where: " prefix.
void check_message(const std::string& message) { check(!one_line(message).empty(), "empty error message"); }

// What an accepted geometry promises (docs/guide/commands.md, "One loop's geometry": 4 <= n <= 8, a >= 0, finite,
// and a finite length scale so that energies are numbers).
void check_geometry(const loopfarm::LoopGeometry& g) {
  const int n = g.joints();
  check(n >= loopfarm::kMinJoints && n <= loopfarm::kMaxJoints,
        "accepted a loop with " + std::to_string(n) + " joints");
  check(g.alpha.size() == n && g.d.size() == n, "accepted lists of different lengths");
  for (int i = 0; i < n; ++i) {
    check(std::isfinite(g.a[i]) && g.a[i] >= 0.0, "accepted a bad link length");
    check(std::isfinite(g.alpha[i]) && std::isfinite(g.d[i]), "accepted a non-finite twist or offset");
  }
  check(std::isfinite(loopfarm::length_scale(g)), "accepted lengths whose length scale overflows");
}

void fuzz_toml(std::string_view text) {
  const GeometryInput input = geometry_from_toml_text(text, "fuzz.toml");
  check_geometry(make_geometry(input));
}

void fuzz_arguments(std::string_view text) {
  // One argument per line, as a shell would hand them over.
  std::vector<std::string> args;
  size_t start = 0;
  while (start <= text.size() && args.size() < 64) {
    const size_t end = text.find('\n', start);
    args.emplace_back(text.substr(start, end == std::string_view::npos ? std::string_view::npos : end - start));
    if (end == std::string_view::npos) break;
    start = end + 1;
  }
  CLI::App app{"fuzz", "loopfarm"};
  GeometryOptions options;
  add_geometry_options(app, options);
  std::vector<std::string> reversed(args.rbegin(), args.rend());  // CLI11 takes them last first
  app.parse(reversed);
  const GeometryRequest request = read_geometry(options);
  check_geometry(request.geometry);
  if (request.theta) {
    check(request.theta->size() == request.geometry.joints(), "--theta-deg of the wrong length accepted");
    for (int i = 0; i < request.theta->size(); ++i) check(std::isfinite((*request.theta)[i]), "non-finite theta");
  }
}

// An accepted number is what strtod reads from the same text (the parser only
// adds strictness, never a different value).
void fuzz_value(std::string_view text) {
  const std::string copy(text);
  try {
    const double value = parse_number(text, "--x");
    check(std::isfinite(value), "parse_number accepted a non-finite value");
    char* end = nullptr;
    errno = 0;
    const double expected = std::strtod(copy.c_str(), &end);
    check(end == copy.c_str() + copy.size(), "parse_number accepted text strtod does not read whole: " + copy);
    check(value == expected, "parse_number differs from strtod on " + quote_text(copy));
  } catch (const UsageError& error) {
    check_message(error.what());
  }
  try {
    const long long value = parse_integer(text, "--n");
    char* end = nullptr;
    const long long expected = std::strtoll(copy.c_str(), &end, 10);
    check(end == copy.c_str() + copy.size() && expected == value,
          "parse_integer differs from strtoll on " + quote_text(copy));
  } catch (const UsageError& error) {
    check_message(error.what());
  }
  try {
    const std::vector<double> values = parse_number_list(text, "--a");
    check(!values.empty(), "parse_number_list accepted an empty list");
    for (const double v : values) check(std::isfinite(v), "parse_number_list accepted a non-finite value");
  } catch (const UsageError& error) {
    check_message(error.what());
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const int mode = data[0] % 3;
  const std::string_view text(reinterpret_cast<const char*>(data) + 1, size - 1);
  try {
    switch (mode) {
      case 0:
        fuzz_toml(text);
        break;
      case 1:
        fuzz_arguments(text);
        break;
      default:
        fuzz_value(text);
        break;
    }
  } catch (const UsageError& error) {
    check_message(error.what());
  } catch (const CLI::ParseError& error) {
    // main() reports these with exit code 2 (or 0 for --help).
    (void)error;
  } catch (const std::invalid_argument& error) {
    check_message(error.what());
  } catch (const std::exception& error) {
    fail(std::string("unexpected exception: ") + error.what());
  } catch (...) {
    fail("exception of unknown type");
  }
  return 0;
}
