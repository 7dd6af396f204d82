// Known loops, for tests, benchmarks, examples and ground truth (the fixture
// kit, after Pinocchio's sample-models). Angles in radians.
#pragma once

#include <cstdint>

#include "loopfarm/core/loop.hpp"

namespace loopfarm {

// Bennett loop, asymmetric setup (paper eqs. 1-2): a = (a1, a2, a1, a2),
// alpha = (alpha1, alpha2, alpha1, alpha2), d = 0, with a2 chosen so that
// sin(alpha1)/a1 = sin(alpha2)/a2.
LoopGeometry bennett_loop(double a1, double alpha1, double alpha2);

// Bennett loop, line-symmetric setup (paper eqs. 3-4): as above with
// sin(alpha1)/a1 = -sin(alpha2)/a2 (alpha2 is negated).
LoopGeometry bennett_loop_line_symmetric(double a1, double alpha1, double alpha2);

// The paper's worked example: a = (2, 4, 2, 4), alpha = (30, 90, 30, 90) deg.
LoopGeometry paper_bennett_loop();

// Joint angles of an asymmetric Bennett loop at input theta1 (eq. 2a):
// theta3 = -theta1, theta4 = -theta2, tan(theta1/2) tan(theta2/2) =
// sin((alpha2+alpha1)/2) / sin((alpha2-alpha1)/2).
JointVector bennett_angles(const LoopGeometry& bennett, double theta1);

// Joint angles of a line-symmetric Bennett loop (eq. 4a): theta3 = theta1,
// theta4 = theta2, tan(theta1/2) tan(theta2/2) = cos((alpha2+alpha1)/2) / cos((alpha2-alpha1)/2).
JointVector bennett_angles_line_symmetric(const LoopGeometry& bennett, double theta1);

// A 4R with zero offsets: lengths (a1 .. a4) and twists (alpha1 .. alpha4) as
// given, link i joining axis i to axis i+1.
LoopGeometry four_bar(double a1, double a2, double a3, double a4, double alpha1, double alpha2, double alpha3,
                      double alpha4);

// Planar four-bar, all twists zero, link lengths (a1, a2, a3, a4) going around
// the loop; a1 is the input crank's link.
LoopGeometry planar_four_bar(double a1, double a2, double a3, double a4);

// Spherical 4R: all lengths and offsets zero, twists as given.
LoopGeometry spherical_four_bar(double alpha1, double alpha2, double alpha3, double alpha4);

// A generic loop with n joints: lengths in [0.5, 5], twists in [0, pi], offsets
// in [-1, 1], drawn from a fixed-seed generator (same result everywhere).
LoopGeometry random_loop(int n, std::uint64_t seed);

// Joint angles drawn in [-pi, pi) from the same generator.
JointVector random_angles(int n, std::uint64_t seed);

}  // namespace loopfarm
