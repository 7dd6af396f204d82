#include "loopfarm/core/sample_loops.hpp"

#include <cmath>

namespace loopfarm {
namespace {

constexpr double kPi = 3.14159265358979323846;

// SplitMix64: a tiny, fully specified generator, so fixtures are the same on
// every platform and standard library.
struct SplitMix64 {
  std::uint64_t state;
  std::uint64_t next() {
    std::uint64_t z = (state += 0x9E3779B97F4A7C15ULL);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    return z ^ (z >> 31);
  }
  double uniform(double lo, double hi) { return lo + (hi - lo) * static_cast<double>(next() >> 11) * 0x1p-53; }
};

}  // namespace

LoopGeometry four_bar(double a1, double a2, double a3, double a4, double alpha1, double alpha2, double alpha3,
                      double alpha4) {
  LoopGeometry g;
  g.a.resize(4);
  g.alpha.resize(4);
  g.d.setZero(4);
  g.a << a1, a2, a3, a4;
  g.alpha << alpha1, alpha2, alpha3, alpha4;
  return g;
}

LoopGeometry bennett_loop(double a1, double alpha1, double alpha2) {
  const double a2 = a1 * std::sin(alpha2) / std::sin(alpha1);
  return four_bar(a1, a2, a1, a2, alpha1, alpha2, alpha1, alpha2);
}

LoopGeometry bennett_loop_line_symmetric(double a1, double alpha1, double alpha2) {
  const double a2 = a1 * std::sin(alpha2) / std::sin(alpha1);
  return four_bar(a1, a2, a1, a2, alpha1, -alpha2, alpha1, -alpha2);
}

LoopGeometry paper_bennett_loop() { return four_bar(2.0, 4.0, 2.0, 4.0, kPi / 6.0, kPi / 2.0, kPi / 6.0, kPi / 2.0); }

JointVector bennett_angles(const LoopGeometry& g, double theta1) {
  const double ratio = std::sin(0.5 * (g.alpha[1] + g.alpha[0])) / std::sin(0.5 * (g.alpha[1] - g.alpha[0]));
  const double theta2 = 2.0 * std::atan2(ratio, std::tan(0.5 * theta1));
  JointVector theta(4);
  theta << theta1, theta2, -theta1, -theta2;
  return theta;
}

JointVector bennett_angles_line_symmetric(const LoopGeometry& g, double theta1) {
  const double ratio = std::cos(0.5 * (g.alpha[1] + g.alpha[0])) / std::cos(0.5 * (g.alpha[1] - g.alpha[0]));
  const double theta2 = 2.0 * std::atan2(ratio, std::tan(0.5 * theta1));
  JointVector theta(4);
  theta << theta1, theta2, theta1, theta2;
  return theta;
}

LoopGeometry planar_four_bar(double a1, double a2, double a3, double a4) {
  return four_bar(a1, a2, a3, a4, 0.0, 0.0, 0.0, 0.0);
}

LoopGeometry spherical_four_bar(double alpha1, double alpha2, double alpha3, double alpha4) {
  return four_bar(0.0, 0.0, 0.0, 0.0, alpha1, alpha2, alpha3, alpha4);
}

LoopGeometry random_loop(int n, std::uint64_t seed) {
  SplitMix64 rng{seed};
  LoopGeometry g;
  g.a = JointVector(n);
  g.alpha = JointVector(n);
  g.d = JointVector(n);
  for (int i = 0; i < n; ++i) {
    g.a[i] = rng.uniform(0.5, 5.0);
    g.alpha[i] = rng.uniform(0.0, kPi);
    g.d[i] = rng.uniform(-1.0, 1.0);
  }
  return g;
}

JointVector random_angles(int n, std::uint64_t seed) {
  SplitMix64 rng{seed ^ 0xA5A5A5A5DEADBEEFULL};
  JointVector theta(n);
  for (int i = 0; i < n; ++i) theta[i] = rng.uniform(-kPi, kPi);
  return theta;
}

}  // namespace loopfarm
