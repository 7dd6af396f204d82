// The rigid motion as the Release build computes it: this program compiles
// the tracer and its solvers itself with GCC's Release flags (-O3 -DNDEBUG,
// both auto-vectorisers on; tests/CMakeLists.txt), where the rest of the
// suite builds them with -O2 and assertions on. The default job's best
// Bennett loop once came out of a Release build as isolated poses only
// (docs/quality/reliability.md, "A compiler sensitivity"); here it, and
// Bennett loops around it, must be one closed circuit with no isolated pose.
#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "loopfarm/core/loop.hpp"
#include "loopfarm/core/motion.hpp"
#include "loopfarm/core/sample_loops.hpp"
#include "test_support.hpp"

namespace loopfarm {
namespace {

using testing::rad;

// One closed circuit of one freedom through every assembly, each joint
// turning once, closing to round-off.
void expect_one_moving_circuit(const LoopGeometry& g, const std::string& name) {
  const MotionAnalysis m = analyse_motion(g, nullptr);
  EXPECT_TRUE(m.isolated_poses.empty()) << name << ": " << m.isolated_poses.size() << " isolated poses";
  ASSERT_EQ(m.circuits.size(), 1u) << name;
  const Circuit& c = m.circuits.front();
  EXPECT_TRUE(c.closed()) << name << ": " << to_string(c.end);
  EXPECT_EQ(c.freedoms, 1) << name;
  EXPECT_GT(c.points.size(), 100u) << name;
  EXPECT_LT(c.worst_residual, 1e-12) << name;
  EXPECT_TRUE(c.moves(0, rad(1), 1e-9)) << name;
  for (int j = 0; j < 4; ++j) EXPECT_EQ(std::abs(c.ranges[static_cast<size_t>(j)].turns), 1) << name << " joint " << j;
}

// A Bennett loop the default job finds (a1 = 0.34, twists -170 and -135.6
// deg), as `loopfarm verify` reads it: at the offsets the results database
// stores (round-off, about 1e-15) and at zero offsets.
TEST(MotionRelease, DefaultJobBennettLoopMoves) {
  const double a[] = {0.3406511249150394, 1.372573062206204, 0.3406511249150396, 1.372573062206204};
  const double alpha_deg[] = {-170.0, -135.5991273336791, -170.0, -135.5991273336791};
  const double stored_d[] = {-9.070144400290041e-16, -9.043756718430537e-16, -9.699571543373534e-16,
                             -9.724825784228196e-16};
  const double zero_d[] = {0.0, 0.0, 0.0, 0.0};
  expect_one_moving_circuit(LoopGeometry::from_degrees(a, alpha_deg, stored_d), "stored offsets");
  expect_one_moving_circuit(LoopGeometry::from_degrees(a, alpha_deg, zero_d), "zero offsets");
}

// Bennett loops over a spread of lengths and twists.
TEST(MotionRelease, BennettLoopsMove) {
  for (int i = 0; i < 8; ++i) {
    const LoopGeometry g = bennett_loop(0.3 + 0.25 * i, rad(10.0 + 20.0 * i), rad(125.0 - 15.0 * i));
    expect_one_moving_circuit(g, "bennett loop " + std::to_string(i));
  }
}

}  // namespace
}  // namespace loopfarm
