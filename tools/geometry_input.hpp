// Reading a loop's geometry as people write it: link lengths a, twists alpha
// in degrees and offsets d, from command-line lists or from a TOML file.
// Every value keeps the name of where it came from (a flag, or file, line and
// key) so that an error message points at the exact place to fix.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "loopfarm/core/loop.hpp"

namespace loopfarm::cli {

// A list of numbers and where it came from: "--a" or "geom.toml:2 key \"a\"".
struct SourcedList {
  std::vector<double> values;
  std::string source;
};

struct GeometryInput {
  SourcedList a;
  SourcedList alpha_deg;
  std::optional<SourcedList> d;  // absent: all offsets zero
};

// From the flags' texts (comma-separated numbers); `d_text` may be absent.
GeometryInput geometry_from_flags(const std::string& a_text, const std::string& alpha_deg_text,
                                  const std::optional<std::string>& d_text);

// From a TOML file holding the arrays a, alpha_deg and (optionally) d and
// nothing else. Throws UsageError naming the file, line and key for an
// unreadable file, a syntax error, an unknown key, a missing key or a value of
// the wrong type.
GeometryInput geometry_from_toml(const std::filesystem::path& file);

// The same from the file's text; `name` stands for the file in messages.
// Separate so that the parser can be tested and fuzzed without a file.
GeometryInput geometry_from_toml_text(std::string_view text, const std::string& name);

// Checks what the library's validate_geometry checks, but names the input's
// sources: 4 to 8 joints, the same count in every list, lengths >= 0. Values
// are already known to be finite. Also rejects lengths so large that the
// length scale L overflows (every energy would be NaN).
LoopGeometry make_geometry(const GeometryInput& input);

// "2, 4, 2, 4": a list for messages and summaries (%g).
std::string format_list(const std::vector<double>& values);

}  // namespace loopfarm::cli
