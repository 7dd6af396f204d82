#include "candidate_display.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "cli_support.hpp"
#include "loopfarm/core/loop.hpp"
#include "loopfarm/farm/candidate_pose.hpp"
#include "loopfarm/search/canonical.hpp"

namespace loopfarm::cli {
namespace {

constexpr double kDegreesPerRadian = 180.0 / 3.14159265358979323846;

}  // namespace

std::string shown(double v, double threshold, int digits) {
  if (std::isfinite(v) && std::abs(v) < threshold) v = 0.0;
  return format_significant(v == 0.0 ? 0.0 : v, digits);
}

std::string shown_list(const std::vector<double>& values, double threshold, int digits, std::string_view separator) {
  std::string out;
  for (size_t i = 0; i < values.size(); ++i) {
    if (i) out += separator;
    out += shown(values[i], threshold, digits);
  }
  return out;
}

std::string grouped(long long n) {
  std::string digits = std::to_string(n < 0 ? -n : n);
  for (int at = static_cast<int>(digits.size()) - 3; at > 0; at -= 3) digits.insert(static_cast<size_t>(at), ",");
  return (n < 0 ? "-" : "") + digits;
}

std::string count_of(long long count, const std::string& noun) {
  return std::to_string(count) + " " + noun + (count == 1 ? "" : "s");
}

std::string dimension_text(int local_dimension) {
  return local_dimension >= 0 ? std::to_string(local_dimension) : std::string("unknown");
}

std::string dimension_of(int local_dimension, int free_parameters) {
  return (local_dimension >= 0 ? std::to_string(local_dimension) : std::string("?")) + "/" +
         std::to_string(free_parameters);
}

double scale_of(const CandidateRow& r) {
  const double scale = length_scale(candidate_geometry(r));
  return std::isfinite(scale) && scale > 0.0 ? scale : 1.0;
}

int stored_joints(const CandidateRow& r) { return std::clamp(r.joints, 0, static_cast<int>(r.a.size())); }

CandidateRow conventional(const CandidateRow& r) {
  CandidateRow shown = r;
  try {
    const LoopGeometry g = conventional_form(candidate_geometry(r)).geometry;
    const double scale = scale_of(r);
    for (int k = 0; k < g.joints() && k < static_cast<int>(shown.a.size()); ++k) {
      const size_t i = static_cast<size_t>(k);
      shown.a[i] = g.a[k] * scale;
      shown.alpha_deg[i] = g.alpha[k] * kDegreesPerRadian;
      shown.d[i] = g.d[k] * scale;
    }
  } catch (const std::invalid_argument&) {
  }
  return shown;
}

ConventionalJoints conventional_joints(const CandidateRow& r) {
  ConventionalJoints out;
  try {
    const LoopGeometry stored = candidate_geometry(r);
    const CanonicalForm form = conventional_form(stored);
    // The angles map as theta'[k] = +-theta[m] (loop.hpp): a unit angle at
    // stored joint i lands, signed, on the joint it becomes.
    const int n = stored.joints();
    for (int i = 0; i < n; ++i) {
      JointVector probe = JointVector::Zero(n);
      probe[i] = 1.0;
      const JointVector mapped = canonical_angles(form, probe);
      int k = 0;
      for (int j = 1; j < n; ++j) {
        if (std::abs(mapped[j]) > std::abs(mapped[k])) k = j;
      }
      out.joint.push_back(k);
      out.negated.push_back(mapped[k] < 0.0);
    }
  } catch (const std::invalid_argument&) {
    return {};
  }
  return out;
}

void print_columns(const std::vector<TextColumn>& columns, size_t width) {
  std::vector<size_t> widths;
  size_t used = 0;
  for (size_t c = 0; c + 1 < columns.size(); ++c) {
    size_t w = columns[c].header.size();
    for (const std::string& cell : columns[c].cells) w = std::max(w, cell.size());
    widths.push_back(w);
    used += w + 1;
  }
  // The last column gets what is left, at least its header.
  const size_t left = width > used ? width - used : 0;
  const size_t last = width == 0 ? std::string::npos : std::max(columns.back().header.size(), left);
  const size_t rows = columns.front().cells.size();
  for (size_t r = 0; r <= rows; ++r) {
    std::string line;
    for (size_t c = 0; c < columns.size(); ++c) {
      const std::string& cell = r == 0 ? columns[c].header : columns[c].cells[r - 1];
      if (c + 1 < columns.size()) {
        line += cell + std::string(widths[c] - cell.size() + 1, ' ');
      } else {
        line += cell.size() <= last ? cell : cell.substr(0, last - 3) + "...";
      }
    }
    while (!line.empty() && line.back() == ' ') line.pop_back();
    std::printf("%s\n", line.c_str());
  }
}

}  // namespace loopfarm::cli
