// Job texts shared by the search tests.
#pragma once

namespace loopfarm::testing {

// The paper's Table 1 scopes with its pose (theta1 = 120, theta2 = 90 and the
// asymmetric Bennett angles for joints 3 and 4 as the assembly's guess): a
// Bennett family, sin(alpha1)/a1 = sin(alpha2)/a2, lies inside.
inline constexpr const char* kBennettSpaceJob = R"(
[loop]
samples = 16
[space]
a1 = [1.96, 2.05]
a2 = [3.96, 4.05]
a3 = "a1"
a4 = "a2"
alpha1_deg = [0, 180]
alpha2_deg = [0, 180]
alpha3_deg = "alpha1_deg"
alpha4_deg = "alpha2_deg"
d = 0
theta1_deg = 120
theta2_deg = 90
theta3_deg = -120
theta4_deg = -90
)";

}  // namespace loopfarm::testing
