#include "geometry_input.hpp"

#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>
#include <span>
#include <sstream>

#include <toml++/toml.h>

#include "cli_support.hpp"
#include "loopfarm/core/types.hpp"
#include "loopfarm/search/job.hpp"

namespace loopfarm::cli {
namespace {

// "geom.toml:3 key \"a\"": the place a TOML value came from.
std::string toml_place(const std::string& file, const toml::source_region& region, std::string_view key) {
  return file + ":" + std::to_string(region.begin.line) + " key " + quote_text(key);
}

// A TOML value described for a message: its type and, for scalars, the value.
std::string describe_node(const toml::node& node) {
  if (const auto* s = node.as_string()) return "string " + quote_text(s->get());
  if (const auto* b = node.as_boolean()) return std::string("boolean ") + (b->get() ? "true" : "false");
  if (const auto* i = node.as_integer()) return "integer " + std::to_string(i->get());
  if (const auto* f = node.as_floating_point()) return "number " + format_double(f->get());
  if (node.is_table()) return "a table";
  if (node.is_array()) return "an array";
  if (node.is_date()) return "a date";
  if (node.is_time()) return "a time";
  if (node.is_date_time()) return "a date-time";
  return "a value of unknown type";
}

SourcedList read_number_array(const std::string& file, std::string_view key, const toml::node& node) {
  SourcedList list;
  list.source = toml_place(file, node.source(), key);
  const toml::array* array = node.as_array();
  if (array == nullptr) {
    throw UsageError(list.source, "expected an array of numbers such as [2, 4, 2, 4], got " + describe_node(node));
  }
  int index = 1;
  for (const toml::node& element : *array) {
    double value = 0.0;
    if (const auto* i = element.as_integer()) {
      value = static_cast<double>(i->get());
    } else if (const auto* f = element.as_floating_point()) {
      value = f->get();
    } else {
      throw UsageError(list.source,
                       "element " + std::to_string(index) + " is " + describe_node(element) + ", not a number");
    }
    // TOML has nan and inf literals; a geometry has no use for them.
    if (!std::isfinite(value)) {
      throw UsageError(list.source,
                       "element " + std::to_string(index) + " is " + format_double(value) + ": not a finite number");
    }
    list.values.push_back(value);
    ++index;
  }
  return list;
}

// The value of largest magnitude, for the message about lengths too large.
double culprit_max(const std::vector<double>& values) {
  double largest = 0.0;
  for (const double v : values) {
    if (std::abs(v) > std::abs(largest)) largest = v;
  }
  return largest;
}

void check_count(const SourcedList& list, size_t joints, const std::string& reference_source) {
  if (list.values.size() != joints) {
    throw UsageError(list.source, std::to_string(list.values.size()) + " values (" + format_list(list.values) +
                                      ") but " + reference_source + " has " + std::to_string(joints));
  }
}

}  // namespace

std::string format_list(const std::vector<double>& values) {
  std::string out;
  for (size_t i = 0; i < values.size(); ++i) {
    char buffer[40];
    std::snprintf(buffer, sizeof buffer, "%g", values[i] == 0.0 ? 0.0 : values[i]);  // never "-0"
    if (i > 0) out += ", ";
    out += buffer;
  }
  return out;
}

GeometryInput geometry_from_flags(const std::string& a_text, const std::string& alpha_deg_text,
                                  const std::optional<std::string>& d_text) {
  GeometryInput input;
  input.a = {parse_number_list(a_text, "--a"), "--a"};
  input.alpha_deg = {parse_number_list(alpha_deg_text, "--alpha-deg"), "--alpha-deg"};
  if (d_text) input.d = SourcedList{parse_number_list(*d_text, "--d"), "--d"};
  return input;
}

GeometryInput geometry_from_toml(const std::filesystem::path& file) {
  const std::string name = file.string();
  // Read the file ourselves so that "missing" and "unreadable" get the
  // system's reason rather than a parser message.
  std::ifstream stream(file, std::ios::binary);
  if (!stream) throw UsageError("--geometry", "cannot read " + quote_text(name) + ": " + std::strerror(errno));
  std::error_code ec;
  if (std::filesystem::is_directory(file, ec)) {
    throw UsageError("--geometry", "cannot read " + quote_text(name) + ": it is a directory");
  }
  const std::string text{std::istreambuf_iterator<char>(stream), std::istreambuf_iterator<char>()};
  if (stream.bad()) throw UsageError("--geometry", "cannot read " + quote_text(name) + ": read error");
  return geometry_from_toml_text(text, name);
}

GeometryInput geometry_from_toml_text(std::string_view text, const std::string& name) {
  // Text that would send toml++ 3.3 into undefined behaviour (job.hpp).
  if (const std::optional<TomlHazard> hazard = find_toml_hazard(text)) {
    throw UsageError(name + ":" + std::to_string(hazard->line) + ":" + std::to_string(hazard->column),
                     "invalid TOML: " + hazard->message);
  }
  toml::table table;
  try {
    table = toml::parse(text, name);
  } catch (const toml::parse_error& error) {
    const auto& begin = error.source().begin;
    throw UsageError(name + ":" + std::to_string(begin.line) + ":" + std::to_string(begin.column),
                     "invalid TOML: " + one_line(error.description()));
  }

  GeometryInput input;
  bool have_a = false;
  bool have_alpha = false;
  for (const auto& [key, node] : table) {
    const std::string_view k = key.str();
    if (k == "a") {
      input.a = read_number_array(name, k, node);
      have_a = true;
    } else if (k == "alpha_deg") {
      input.alpha_deg = read_number_array(name, k, node);
      have_alpha = true;
    } else if (k == "d") {
      input.d = read_number_array(name, k, node);
    } else {
      throw UsageError(toml_place(name, key.source(), k), "unknown key; a geometry file has only a, alpha_deg and d");
    }
  }
  if (!have_a) throw UsageError(name, "missing key \"a\" (the link lengths, e.g. a = [2, 4, 2, 4])");
  if (!have_alpha) {
    throw UsageError(name, "missing key \"alpha_deg\" (the twists in degrees, e.g. alpha_deg = [30, 90, 30, 90])");
  }
  return input;
}

LoopGeometry make_geometry(const GeometryInput& input) {
  const size_t n = input.a.values.size();
  if (n < static_cast<size_t>(kMinJoints) || n > static_cast<size_t>(kMaxJoints)) {
    throw UsageError(input.a.source, std::to_string(n) + " values (" + format_list(input.a.values) +
                                         "); a loop needs " + std::to_string(kMinJoints) + " to " +
                                         std::to_string(kMaxJoints) + " joints");
  }
  check_count(input.alpha_deg, n, input.a.source);
  if (input.d) check_count(*input.d, n, input.a.source);
  for (size_t i = 0; i < n; ++i) {
    if (input.a.values[i] < 0.0) {
      throw UsageError(input.a.source, "element " + std::to_string(i + 1) + " is " + format_double(input.a.values[i]) +
                                           ": a link length must be >= 0");
    }
  }
  const std::vector<double> zeros(n, 0.0);
  const std::vector<double>& d = input.d ? input.d->values : zeros;
  LoopGeometry geometry = LoopGeometry::from_degrees(input.a.values, input.alpha_deg.values, d);
  // Finite lengths can still be too large to square (1e200): L, and with it
  // every dimensionless energy, would be inf or NaN.
  if (!std::isfinite(length_scale(geometry))) {
    // Name the list that overflows: a, unless a alone is fine (then d).
    const bool a_overflows = !std::isfinite(geometry.a.squaredNorm());
    const SourcedList& culprit = a_overflows || !input.d ? input.a : *input.d;
    throw UsageError(culprit.source, "values such as " + format_list({culprit_max(culprit.values)}) +
                                         " are too large to compute with (the length scale L = sqrt(mean(a^2 + d^2)) "
                                         "overflows); scale the loop down");
  }
  // The library's own check, as a backstop: it throws std::invalid_argument,
  // which the caller reports as bad input too.
  validate_geometry(geometry);
  return geometry;
}

}  // namespace loopfarm::cli
