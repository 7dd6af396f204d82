#include "representation.hpp"

#include <map>
#include <mutex>

namespace loopfarm::detail {
namespace {

constexpr double kPi = 3.14159265358979323846;

// Builds the maps by applying the same steps as loop.hpp's relabelled,
// reversed and axis_flipped to symbolic parameters (index, sign, offset).
Representation build(int n, int shift, bool reverse, std::uint32_t flips) {
  Representation r;
  r.shift = shift;
  r.reversed = reverse;
  r.flips = flips;
  auto a = [](int k) { return k; };
  auto alpha = [n](int k) { return n + k; };
  auto d = [n](int k) { return 2 * n + k; };
  for (int i = 0; i < 3 * n; ++i) {
    r.index[static_cast<size_t>(i)] = i;
    r.sign[static_cast<size_t>(i)] = 1.0;
    r.offset[static_cast<size_t>(i)] = 0.0;
  }
  for (int k = 0; k < n; ++k) {
    r.angle_index[static_cast<size_t>(k)] = k;
    r.angle_sign[static_cast<size_t>(k)] = 1.0;
  }
  Representation next = r;
  auto copy = [&](int to, int from) {
    next.index[static_cast<size_t>(to)] = r.index[static_cast<size_t>(from)];
    next.sign[static_cast<size_t>(to)] = r.sign[static_cast<size_t>(from)];
    next.offset[static_cast<size_t>(to)] = r.offset[static_cast<size_t>(from)];
  };
  auto copy_angle = [&](int to, int from, double sign) {
    next.angle_index[static_cast<size_t>(to)] = r.angle_index[static_cast<size_t>(from)];
    next.angle_sign[static_cast<size_t>(to)] = sign * r.angle_sign[static_cast<size_t>(from)];
  };
  // relabelled: new joint k is old joint k + shift.
  for (int k = 0; k < n; ++k) {
    const int old = (k + shift) % n;
    copy(a(k), a(old));
    copy(alpha(k), alpha(old));
    copy(d(k), d(old));
    copy_angle(k, old, 1.0);
  }
  r = next;
  if (reverse) {
    // reversed: new joint k is old joint n-1-k (d and theta negated); the
    // link after it is old link n-2-k.
    for (int k = 0; k < n; ++k) {
      const int joint = n - 1 - k;
      const int link = ((n - 2 - k) % n + n) % n;
      copy(a(k), a(link));
      copy(alpha(k), alpha(link));
      copy(d(k), d(joint));
      next.sign[static_cast<size_t>(d(k))] = -r.sign[static_cast<size_t>(d(joint))];
      next.offset[static_cast<size_t>(d(k))] = -r.offset[static_cast<size_t>(d(joint))];
      copy_angle(k, joint, -1.0);
    }
    r = next;
  }
  for (int j = 0; j < n; ++j) {
    if (!(flips >> j & 1u)) continue;
    // axis_flipped: twists on both sides of axis j + pi, d_j and theta_j negated.
    const int before = (j + n - 1) % n;
    r.offset[static_cast<size_t>(alpha(before))] += kPi;
    r.offset[static_cast<size_t>(alpha(j))] += kPi;
    r.sign[static_cast<size_t>(d(j))] = -r.sign[static_cast<size_t>(d(j))];
    r.offset[static_cast<size_t>(d(j))] = -r.offset[static_cast<size_t>(d(j))];
    r.angle_sign[static_cast<size_t>(j)] = -r.angle_sign[static_cast<size_t>(j)];
  }
  return r;
}

}  // namespace

const std::vector<Representation>& representations(int joints) {
  static std::mutex mutex;
  static std::map<int, std::vector<Representation>> cache;
  const std::lock_guard<std::mutex> lock(mutex);
  std::vector<Representation>& list = cache[joints];
  if (list.empty()) {
    for (int reverse = 0; reverse < 2; ++reverse) {
      for (int shift = 0; shift < joints; ++shift) {
        for (std::uint32_t flips = 0; flips < (1u << joints); ++flips) {
          list.push_back(build(joints, shift, reverse != 0, flips));
        }
      }
    }
  }
  return list;
}

LoopGeometry apply(const Representation& r, const LoopGeometry& g) {
  const int n = g.joints();
  GeometryVector p(3 * n);
  p << g.a, g.alpha, g.d;
  LoopGeometry out = g;
  for (int k = 0; k < n; ++k) {
    auto value = [&](int i) {
      return r.sign[static_cast<size_t>(i)] * p[r.index[static_cast<size_t>(i)]] + r.offset[static_cast<size_t>(i)];
    };
    out.a[k] = value(k);
    out.alpha[k] = wrap_angle(value(n + k));
    out.d[k] = value(2 * n + k);
  }
  return out;
}

JointVector apply_angles(const Representation& r, const JointVector& theta) {
  JointVector out(theta.size());
  for (int k = 0; k < theta.size(); ++k) {
    out[k] = r.angle_sign[static_cast<size_t>(k)] * theta[r.angle_index[static_cast<size_t>(k)]];
  }
  return out;
}

GeometryVector pull_back(const Representation& r, const GeometryVector& gradient) {
  GeometryVector out = GeometryVector::Zero(gradient.size());
  for (int i = 0; i < gradient.size(); ++i) {
    out[r.index[static_cast<size_t>(i)]] += r.sign[static_cast<size_t>(i)] * gradient[i];
  }
  return out;
}

std::uint32_t zero_length_links(const LoopGeometry& g, double zero_length) {
  if (!(zero_length >= 0.0)) return 0u;
  const double bound = zero_length * length_scale(g);
  std::uint32_t links = 0;
  for (int k = 0; k < g.joints(); ++k) {
    if (g.a[k] <= bound) links |= 1u << k;
  }
  return links;
}

LoopGeometry with_negated_twists(const LoopGeometry& g, std::uint32_t links) {
  LoopGeometry out = g;
  for (int k = 0; k < g.joints(); ++k) {
    if (links >> k & 1u) out.alpha[k] = wrap_angle(0.0 - g.alpha[k]);  // 0 stays +0
  }
  return out;
}

JointVector negated_twist_angles(const JointVector& theta, std::uint32_t links) {
  const auto n = static_cast<int>(theta.size());
  JointVector out = theta;
  for (int k = 0; k < n; ++k) {
    if (!(links >> k & 1u)) continue;
    out[k] += kPi;
    out[(k + 1) % n] -= kPi;
  }
  return out;
}

}  // namespace loopfarm::detail
