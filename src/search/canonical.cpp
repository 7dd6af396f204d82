#include "loopfarm/search/canonical.hpp"

#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <vector>

#include "representation.hpp"

namespace loopfarm {
namespace {

constexpr double kPi = 3.14159265358979323846;

// Quantised values of a scaled representation, (a, alpha, d).
std::vector<long long> quantised(const LoopGeometry& g, double tolerance) {
  const int n = g.joints();
  std::vector<long long> q;
  q.reserve(static_cast<size_t>(3 * n));
  auto quantum = [tolerance](double v) { return std::llround(v / tolerance); };
  for (int k = 0; k < n; ++k) q.push_back(quantum(g.a[k]));
  for (int k = 0; k < n; ++k) {
    // (-pi, pi], with -pi + eps snapped to pi so both sides of the cut agree.
    double alpha = g.alpha[k];
    if (alpha < -kPi + tolerance) alpha += 2 * kPi;
    q.push_back(quantum(alpha));
  }
  for (int k = 0; k < n; ++k) q.push_back(quantum(g.d[k]));
  return q;
}

std::string decimal(long long quantum, int decimals, double tolerance) {
  if (quantum == 0) return "0";
  char buffer[48];
  std::snprintf(buffer, sizeof buffer, "%.*f", decimals, static_cast<double>(quantum) * tolerance);
  return buffer;
}

}  // namespace

CanonicalForm canonical_form(const LoopGeometry& geometry, double tolerance) {
  validate_geometry(geometry);
  if (!(tolerance > 0.0 && tolerance < 1.0)) throw std::invalid_argument("canonical_form: tolerance must be in (0, 1)");
  const int n = geometry.joints();
  CanonicalForm best;
  best.scale = length_scale(geometry);
  const LoopGeometry unit = scaled(geometry, best.scale);
  std::vector<long long> best_key;
  for (const detail::Representation& r : detail::representations(n)) {
    const LoopGeometry candidate = detail::apply(r, unit);
    std::vector<long long> key = quantised(candidate, tolerance);
    if (best_key.empty() || key < best_key) {
      best_key = std::move(key);
      best.geometry = candidate;
      best.shift = r.shift;
      best.reversed = r.reversed;
      best.flips = r.flips;
    }
  }
  const int decimals = std::max(0, static_cast<int>(std::ceil(-std::log10(tolerance) - 1e-9)));
  std::string key = std::to_string(n) + "R";
  const char* names[] = {" a=", " alpha=", " d="};
  for (int kind = 0; kind < 3; ++kind) {
    key += names[kind];
    for (int k = 0; k < n; ++k) {
      if (k) key += ",";
      key += decimal(best_key[static_cast<size_t>(kind * n + k)], decimals, tolerance);
    }
  }
  best.key = key;
  return best;
}

JointVector canonical_angles(const CanonicalForm& form, const JointVector& theta) {
  for (const detail::Representation& r : detail::representations(static_cast<int>(theta.size()))) {
    if (r.shift == form.shift && r.reversed == form.reversed && r.flips == form.flips)
      return detail::apply_angles(r, theta);
  }
  throw std::invalid_argument("canonical_angles: the form does not belong to a loop of this size");
}

}  // namespace loopfarm
