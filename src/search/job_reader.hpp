// What the job file's parsers share (job.cpp, job_space.cpp): the reader of
// one job file, which names the file, the line and the key in every error.
// Internal to the search.
#pragma once

#include <cmath>
#include <cstdio>
#include <string>

#include <toml++/toml.h>

#include "loopfarm/search/job.hpp"

namespace loopfarm::detail {

constexpr double kPi = 3.14159265358979323846;
constexpr double kRadiansPerDegree = kPi / 180.0;
// The largest magnitude of a length (a, d). Energies are divided by L^2, L the
// RMS of the lengths; beyond about 1e154 the squares overflow, L is inf and
// every energy NaN, and a range's width hi - lo can overflow too. 1e150 keeps
// the sum of 16 squares finite with room to spare.
constexpr double kMaxLength = 1e150;

inline std::string format(double value) {
  char buffer[40];
  std::snprintf(buffer, sizeof buffer, "%.10g", value);
  return buffer;
}

// The reader of one job file: where it is and how to complain.
struct Reader {
  std::string file;

  [[noreturn]] void fail(const toml::source_region& where, const std::string& key, const std::string& message) const {
    throw JobError(file, static_cast<int>(where.begin.line), key, message);
  }

  static std::string describe(const toml::node& node) {
    if (const auto* s = node.as_string()) return "the string \"" + s->get() + "\"";
    if (const auto* b = node.as_boolean()) return std::string("the boolean ") + (b->get() ? "true" : "false");
    if (const auto* i = node.as_integer()) return "the integer " + std::to_string(i->get());
    if (const auto* f = node.as_floating_point()) return "the number " + format(f->get());
    if (node.is_table()) return "a table";
    if (node.is_array()) return "an array";
    return "a date or time";
  }

  double number(const toml::node& node, const std::string& key) const {
    double value = 0.0;
    if (const auto* i = node.as_integer()) {
      value = static_cast<double>(i->get());
    } else if (const auto* f = node.as_floating_point()) {
      value = f->get();
    } else {
      fail(node.source(), key, "expected a number, got " + describe(node));
    }
    // TOML has nan and inf literals; no job setting has a use for them.
    if (!std::isfinite(value)) fail(node.source(), key, "got " + format(value) + "; must be a finite number");
    return value;
  }

  long long integer(const toml::node& node, const std::string& key) const {
    const auto* i = node.as_integer();
    if (i == nullptr) fail(node.source(), key, "expected an integer, got " + describe(node));
    return i->get();
  }

  // An integer in [lo, hi]; `allowed` says so in the message ("in [1, 1e8]").
  int integer_in(const toml::node& node, const std::string& key, long long lo, long long hi,
                 const std::string& allowed) const {
    const long long n = integer(node, key);
    if (n < lo || n > hi) fail(node.source(), key, "got " + std::to_string(n) + "; must be " + allowed);
    return static_cast<int>(n);
  }

  bool boolean(const toml::node& node, const std::string& key) const {
    const auto* b = node.as_boolean();
    if (b == nullptr) fail(node.source(), key, "expected true or false, got " + describe(node));
    return b->get();
  }

  std::string string(const toml::node& node, const std::string& key) const {
    const auto* s = node.as_string();
    if (s == nullptr) fail(node.source(), key, "expected a string, got " + describe(node));
    return s->get();
  }

  const toml::table& table(const toml::node& node, const std::string& key) const {
    const toml::table* t = node.as_table();
    if (t == nullptr) fail(node.source(), key, "expected a table [" + key + "], got " + describe(node));
    return *t;
  }

  // number > 0 (strict) or >= 0.
  double positive(const toml::node& node, const std::string& key, bool strict) const {
    const double value = number(node, key);
    if (strict ? !(value > 0.0) : !(value >= 0.0)) {
      fail(node.source(), key, "got " + format(value) + "; must be " + (strict ? "> 0" : ">= 0"));
    }
    return value;
  }
};

// The [space] table (job_space.cpp) of a loop of `joints` joints; `table`
// may be null (every parameter takes its default).
ParameterSpace read_space(const Reader& r, const toml::table* table, int joints);

}  // namespace loopfarm::detail
