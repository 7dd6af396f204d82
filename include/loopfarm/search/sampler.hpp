// Reproducible random starts: start `index` of a job draws its free geometric
// values (uniform in their bounds, in ParameterSpace::free_indices() order)
// and its random initial angles (uniform in their ranges, in joint order)
// from a Philox4x64 stream keyed by (seed, index) with the draw number as the
// counter. Any start can be replayed alone and gives bit-identical values,
// whatever the number of starts or ranks and the order they run in.
#pragma once

#include <cstdint>

#include <Eigen/Core>

#include "loopfarm/search/job.hpp"

namespace loopfarm {

struct StartPoint {
  std::uint64_t index = 0;
  Eigen::VectorXd x;  // free geometric values
  JointVector theta;  // initial joint angles (fixed and tied filled in)
};

StartPoint draw_start(const ParameterSpace& space, std::uint64_t seed, std::uint64_t index);

// The k-th uniform double in [0, 1) of stream (seed, index): the top 53 bits
// of one Philox4x64 output word, 2^-53 apart. Exposed for tests.
double stream_uniform(std::uint64_t seed, std::uint64_t index, std::uint64_t k);

}  // namespace loopfarm
