#include "loopfarm/search/sampler.hpp"

#include <vector>

#include <Random123/philox.h>

namespace loopfarm {

double stream_uniform(std::uint64_t seed, std::uint64_t index, std::uint64_t k) {
  // One Philox call yields four 64-bit words: draws 4m..4m+3 share counter m.
  const r123::Philox4x64 philox;
  const r123::Philox4x64::key_type key = {{seed, index}};
  const r123::Philox4x64::ctr_type counter = {{k / 4, 0, 0, 0}};
  const r123::Philox4x64::ctr_type out = philox(counter, key);
  return static_cast<double>(out.v[k % 4] >> 11) * 0x1.0p-53;
}

StartPoint draw_start(const ParameterSpace& space, std::uint64_t seed, std::uint64_t index) {
  StartPoint start;
  start.index = index;
  std::uint64_t k = 0;
  const Eigen::VectorXd lower = space.lower_bounds();
  const Eigen::VectorXd upper = space.upper_bounds();
  start.x.resize(lower.size());
  for (int i = 0; i < lower.size(); ++i) {
    start.x[i] = lower[i] + (upper[i] - lower[i]) * stream_uniform(seed, index, k++);
  }
  Eigen::VectorXd draws(space.random_angle_count());
  int next = 0;
  for (int j = 0; j < space.joints; ++j) {
    const ParameterSpec& s = space.specs[static_cast<size_t>(space.index(ParameterKind::theta, j))];
    if (s.mode == ParameterSpec::Mode::range) draws[next++] = s.lo + (s.hi - s.lo) * stream_uniform(seed, index, k++);
  }
  start.theta = space.initial_angles(draws);
  return start;
}

}  // namespace loopfarm
