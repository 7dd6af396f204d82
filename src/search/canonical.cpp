#include "loopfarm/search/canonical.hpp"

#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <vector>

#include "representation.hpp"

namespace loopfarm {
namespace {

constexpr double kPi = 3.14159265358979323846;

// A twist's quantum: (-pi, pi], with -pi + eps snapped to pi so both sides
// of the cut agree.
long long twist_quantum(double alpha, double tolerance) {
  if (alpha < -kPi + tolerance) alpha += 2 * kPi;
  return std::llround(alpha / tolerance);
}

// A link the key writes as zero length: its length (at length scale 1) quantised to 0.
bool zero_length(double a, double tolerance) { return std::llround(a / tolerance) == 0; }

// The loop with the common normals between parallel axes centred
// (centred_parallel_normals): a link counts as parallel where the key would
// write its twist as 0 or pi, |sin(alpha)| below half a quantum. Where the
// search left such a normal is no property of the loop, and the key (and the
// length scale, which the offsets enter) must not depend on it.
LoopGeometry centred(const LoopGeometry& geometry, double tolerance) {
  return centred_parallel_normals(geometry, 0.5 * tolerance);
}

// Quantised values of a scaled representation, (a, alpha, d).
std::vector<long long> quantised(const LoopGeometry& g, double tolerance) {
  const int n = g.joints();
  std::vector<long long> q;
  q.reserve(static_cast<size_t>(3 * n));
  auto quantum = [tolerance](double v) { return std::llround(v / tolerance); };
  for (int k = 0; k < n; ++k) q.push_back(quantum(g.a[k]));
  for (int k = 0; k < n; ++k) q.push_back(twist_quantum(g.alpha[k], tolerance));
  for (int k = 0; k < n; ++k) q.push_back(quantum(g.d[k]));
  return q;
}

std::string decimal(long long quantum, int decimals, double tolerance) {
  if (quantum == 0) return "0";
  char buffer[48];
  std::snprintf(buffer, sizeof buffer, "%.*f", decimals, static_cast<double>(quantum) * tolerance);
  return buffer;
}

// The representation of `unit` (length scale 1) whose rank(.) is smallest,
// written into form's geometry and transformation; returns that rank. At a
// link the key writes as zero length (its length quantised to 0) the twist's
// sign is free (representation.hpp): each such twist is negated when
// prefer_negated(twist, negated twist) says so. Both ranks used here order
// the twists of one representation independently of one another (a
// lexicographic order of their quanta, after a count of negative ones), so
// choosing each sign on its own gives the smallest rank over all 2^z sign
// choices. A loop without such a link does no more than before.
template <typename Rank, typename PreferNegated>
std::vector<long long> smallest_representation(const LoopGeometry& unit, double tolerance, Rank rank,
                                               PreferNegated prefer_negated, CanonicalForm& form) {
  const int n = unit.joints();
  bool any_zero_length = false;
  for (int k = 0; k < n; ++k) any_zero_length = any_zero_length || zero_length(unit.a[k], tolerance);
  std::vector<long long> best;
  for (const detail::Representation& r : detail::representations(n)) {
    LoopGeometry candidate = detail::apply(r, unit);
    std::uint32_t negated = 0;
    if (any_zero_length) {
      for (int k = 0; k < n; ++k) {
        if (!zero_length(candidate.a[k], tolerance)) continue;
        const double flipped = detail::with_negated_twists(candidate, 1u << k).alpha[k];
        if (prefer_negated(candidate.alpha[k], flipped)) {
          candidate.alpha[k] = flipped;
          negated |= 1u << k;
        }
      }
    }
    std::vector<long long> order = rank(candidate);
    if (best.empty() || order < best) {
      best = std::move(order);
      form.geometry = candidate;
      form.shift = r.shift;
      form.reversed = r.reversed;
      form.flips = r.flips;
      form.negated_twists = negated;
    }
  }
  return best;
}

}  // namespace

CanonicalForm canonical_form(const LoopGeometry& geometry, double tolerance) {
  validate_geometry(geometry);
  if (!(tolerance > 0.0 && tolerance < 1.0)) throw std::invalid_argument("canonical_form: tolerance must be in (0, 1)");
  const int n = geometry.joints();
  CanonicalForm best;
  const LoopGeometry loop = centred(geometry, tolerance);
  best.scale = length_scale(loop);
  const std::vector<long long> best_key = smallest_representation(
      scaled(loop, best.scale), tolerance, [tolerance](const LoopGeometry& g) { return quantised(g, tolerance); },
      [tolerance](double twist, double negated) {
        return twist_quantum(negated, tolerance) < twist_quantum(twist, tolerance);
      },
      best);
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

bool has_zero_length_link(const LoopGeometry& geometry, double tolerance) {
  validate_geometry(geometry);
  if (!(tolerance > 0.0 && tolerance < 1.0)) {
    throw std::invalid_argument("has_zero_length_link: tolerance must be in (0, 1)");
  }
  // As canonical_form reads the lengths: scaled to length scale 1.
  const LoopGeometry loop = centred(geometry, tolerance);
  const LoopGeometry unit = scaled(loop, length_scale(loop));
  for (int k = 0; k < unit.joints(); ++k) {
    if (zero_length(unit.a[k], tolerance)) return true;
  }
  return false;
}

bool has_parallel_link(const LoopGeometry& geometry, double tolerance) {
  validate_geometry(geometry);
  if (!(tolerance > 0.0 && tolerance < 1.0)) {
    throw std::invalid_argument("has_parallel_link: tolerance must be in (0, 1)");
  }
  for (int k = 0; k < geometry.joints(); ++k) {
    if (std::abs(std::sin(geometry.alpha[k])) <= 0.5 * tolerance) return true;
  }
  return false;
}

CanonicalForm conventional_form(const LoopGeometry& geometry, double tolerance) {
  CanonicalForm best = canonical_form(geometry, tolerance);
  const int n = geometry.joints();
  // (negative twists, negative offsets, quantised values): smallest wins. A
  // twist a hair above -pi is pi, as the key reads it.
  auto is_negative_twist = [tolerance](double alpha) { return alpha < -tolerance && alpha >= -kPi + tolerance; };
  smallest_representation(
      scaled(centred(geometry, tolerance), best.scale), tolerance,
      [&](const LoopGeometry& g) {
        long long negative_twists = 0, negative_offsets = 0;
        for (int k = 0; k < n; ++k) {
          negative_twists += is_negative_twist(g.alpha[k]) ? 1 : 0;
          negative_offsets += g.d[k] < -tolerance ? 1 : 0;
        }
        std::vector<long long> order{negative_twists, negative_offsets};
        const std::vector<long long> values = quantised(g, tolerance);
        order.insert(order.end(), values.begin(), values.end());
        return order;
      },
      [&](double twist, double negated) {
        const bool negative = is_negative_twist(twist), negated_negative = is_negative_twist(negated);
        if (negative != negated_negative) return negated_negative < negative;
        return twist_quantum(negated, tolerance) < twist_quantum(twist, tolerance);
      },
      best);
  for (int k = 0; k < n; ++k) {
    if (best.geometry.alpha[k] < -kPi + tolerance) best.geometry.alpha[k] += 2 * kPi;
  }
  return best;
}

JointVector canonical_angles(const CanonicalForm& form, const JointVector& theta) {
  for (const detail::Representation& r : detail::representations(static_cast<int>(theta.size()))) {
    if (r.shift == form.shift && r.reversed == form.reversed && r.flips == form.flips)
      return detail::negated_twist_angles(detail::apply_angles(r, theta), form.negated_twists);
  }
  throw std::invalid_argument("canonical_angles: the form does not belong to a loop of this size");
}

}  // namespace loopfarm
