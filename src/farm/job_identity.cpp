// A job's identity for merging (job_identity.hpp).
#include "job_identity.hpp"

#include <algorithm>
#include <sstream>
#include <stdexcept>
#include <vector>

#include <toml++/toml.h>

#include "loopfarm/search/job.hpp"

namespace loopfarm::store {
namespace {

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream stream(text);
  for (std::string line; std::getline(stream, line);) lines.push_back(line);
  return lines;
}

}  // namespace

std::string merge_identity(std::string_view job_text, const std::string& source_name) {
  // The same guard as the job reader's: text that would drive toml++ into
  // undefined behaviour is refused before it is parsed.
  if (const std::optional<TomlHazard> hazard = find_toml_hazard(job_text)) {
    throw std::invalid_argument(source_name + ": the job text is not valid TOML (line " + std::to_string(hazard->line) +
                                ": " + hazard->message + ")");
  }
  toml::table root;
  try {
    root = toml::parse(job_text, source_name);
  } catch (const toml::parse_error& error) {
    std::string description(error.description());
    std::replace(description.begin(), description.end(), '\n', ' ');
    throw std::invalid_argument(source_name + ": the job text is not valid TOML (line " +
                                std::to_string(error.source().begin.line) + ": " + description + ")");
  }
  root.erase("output");
  std::ostringstream out;
  out << toml::toml_formatter(root);
  return out.str();
}

std::string first_difference(const std::string& x, const std::string& y) {
  const std::vector<std::string> a = lines_of(x), b = lines_of(y);
  std::string table;
  for (size_t i = 0; i < std::max(a.size(), b.size()); ++i) {
    const std::string* left = i < a.size() ? &a[i] : nullptr;
    const std::string* right = i < b.size() ? &b[i] : nullptr;
    if (left && right && *left == *right) {
      if (!left->empty() && left->front() == '[') table = *left;
      continue;
    }
    auto show = [](const std::string* line) { return line ? "`" + *line + "`" : std::string("(nothing)"); };
    return (table.empty() ? "" : "in " + table + ", ") + show(left) + " against " + show(right);
  }
  return "nothing";
}

}  // namespace loopfarm::store
