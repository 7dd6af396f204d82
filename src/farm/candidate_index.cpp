// De-duplication's lookup (candidate_index.hpp).
#include "candidate_index.hpp"

#include <algorithm>
#include <cmath>

#include "loopfarm/core/loop.hpp"

namespace loopfarm::store {
namespace {

constexpr double kDegreesPerRadian = 180.0 / 3.14159265358979323846;
constexpr double kRadiansPerDegree = 3.14159265358979323846 / 180.0;

}  // namespace

double canonical_distance(const CanonicalEntry& x, const CanonicalEntry& y, double tolerance) {
  const int n = x.joints;
  double distance = 0.0;
  for (int i = 0; i < 3 * n && distance <= tolerance; ++i) {
    const double difference = x.values[i] - y.values[i];
    distance = std::max(distance, std::abs(i >= n && i < 2 * n ? wrap_angle(difference) : difference));
  }
  return distance;
}

std::vector<std::vector<long>> cell_options(const CanonicalEntry& c, double tolerance) {
  const int n = c.joints;
  constexpr double kTwoPi = 2.0 * 3.14159265358979323846;
  std::vector<std::vector<long>> options(static_cast<size_t>(3 * n));
  for (int i = 0; i < 3 * n; ++i) {
    const bool twist = i >= n && i < 2 * n;
    const double width = twist ? kTwoPi / kTwistCells : kGridCell;
    const double u = twist ? (c.values[i] + kTwoPi / 2) / width : c.values[i] / width;
    const double cell = std::floor(u);
    const double offset = (u - cell) * width;  // distance above the cell's lower edge
    auto wrap = [twist](long k) { return twist ? ((k % kTwistCells) + kTwistCells) % kTwistCells : k; };
    const long k = static_cast<long>(cell);
    std::vector<long>& o = options[static_cast<size_t>(i)];
    o.push_back(wrap(k));
    if (offset <= tolerance) o.push_back(wrap(k - 1));
    if (width - offset <= tolerance) o.push_back(wrap(k + 1));
  }
  return options;
}

std::string cell_name(const std::vector<std::vector<long>>& options, const std::vector<size_t>& choice) {
  std::string out;
  for (size_t i = 0; i < options.size(); ++i) {
    if (i > 0) out += ',';
    out += std::to_string(options[i][choice[i]]);
  }
  return out;
}

// The grid cell a candidate is stored under.
std::string grid_cell(const CanonicalEntry& c) {
  const auto options = cell_options(c, 0.0);
  return cell_name(options, std::vector<size_t>(options.size(), 0));
}

double stored_twist(double radians) { return radians * kDegreesPerRadian; }
double twist_from_stored(double degrees) { return degrees * kRadiansPerDegree; }

CanonicalEntry canonical_entry(const StartRecord& r, std::int64_t run_id) {
  const LoopGeometry& g = r.candidate.canonical_geometry;
  const int n = g.joints();
  CanonicalEntry c;
  c.key = r.candidate.canonical_key;
  c.joints = n;
  for (int i = 0; i < n; ++i) {
    c.values[i] = g.a[i];
    c.values[n + i] = twist_from_stored(stored_twist(g.alpha[i]));
    c.values[2 * n + i] = g.d[i];
  }
  c.first_run = run_id;
  c.first_start = static_cast<std::int64_t>(r.index);
  return c;
}

}  // namespace loopfarm::store
