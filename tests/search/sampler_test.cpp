#include "loopfarm/search/sampler.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "loopfarm/search/job.hpp"

namespace loopfarm {
namespace {

TEST(Sampler, ReplayIsBitIdenticalAndStreamsDiffer) {
  const Job job = parse_job("[space]\na3 = \"a1\"\nd = 0\ntheta1_deg = 0\n", "s.toml");
  const StartPoint a = draw_start(job.space, 7, 123);
  const StartPoint b = draw_start(job.space, 7, 123);
  EXPECT_EQ(a.x, b.x);  // exact, bit for bit
  EXPECT_EQ(a.theta, b.theta);
  EXPECT_NE(a.x, draw_start(job.space, 7, 124).x);
  EXPECT_NE(a.x, draw_start(job.space, 8, 123).x);
  // Inside the bounds, fixed and tied honoured.
  EXPECT_TRUE((a.x.array() >= job.space.lower_bounds().array()).all());
  EXPECT_TRUE((a.x.array() <= job.space.upper_bounds().array()).all());
  const LoopGeometry g = job.space.geometry(a.x);
  EXPECT_EQ(g.a[2], g.a[0]);
  EXPECT_EQ(a.theta[0], 0.0);
  EXPECT_TRUE((a.theta.tail(3).array().abs() <= 3.14159265358979323846).all());
}

TEST(Sampler, UniformDrawsPassAChiSquareTest) {
  // 20 bins, 20000 draws over many (seed, index, k): chi^2 with 19 degrees of
  // freedom exceeds 43.8 with probability 1e-3. A generator that used the low
  // bits badly, or repeated itself across indices, would fail by far.
  constexpr int kBins = 20;
  std::vector<int> counts(kBins, 0);
  int draws = 0;
  for (std::uint64_t index = 0; index < 2000; ++index) {
    for (std::uint64_t k = 0; k < 10; ++k) {
      const double u = stream_uniform(3, index, k);
      ASSERT_GE(u, 0.0);
      ASSERT_LT(u, 1.0);
      ++counts[static_cast<size_t>(u * kBins)];
      ++draws;
    }
  }
  const double expected = static_cast<double>(draws) / kBins;
  double chi2 = 0.0;
  for (int c : counts) chi2 += (c - expected) * (c - expected) / expected;
  EXPECT_LT(chi2, 43.8);
  // Neighbouring indices are not correlated: the lag-1 correlation over
  // indices of the first draw is small (|r| < 4 / sqrt(n)).
  const int n = 5000;
  double sx = 0, sy = 0, sxy = 0, sxx = 0, syy = 0;
  for (int i = 0; i < n; ++i) {
    const double x = stream_uniform(3, static_cast<std::uint64_t>(i), 0);
    const double y = stream_uniform(3, static_cast<std::uint64_t>(i + 1), 0);
    sx += x, sy += y, sxy += x * y, sxx += x * x, syy += y * y;
  }
  const double r = (sxy - sx * sy / n) / std::sqrt((sxx - sx * sx / n) * (syy - sy * sy / n));
  EXPECT_LT(std::abs(r), 4.0 / std::sqrt(n));
}

TEST(Sampler, DrawsDoNotDependOnHowManyStartsOrWhichOrder) {
  const Job job = parse_job("", "s.toml");
  std::vector<StartPoint> forward, backward;
  for (std::uint64_t i = 0; i < 16; ++i) forward.push_back(draw_start(job.space, 5, i));
  for (std::uint64_t i = 16; i-- > 0;) backward.push_back(draw_start(job.space, 5, i));
  std::reverse(backward.begin(), backward.end());
  for (size_t i = 0; i < forward.size(); ++i) {
    EXPECT_EQ(forward[i].x, backward[i].x);
    EXPECT_EQ(forward[i].theta, backward[i].theta);
  }
}

}  // namespace
}  // namespace loopfarm
