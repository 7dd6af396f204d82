// Four-bars of every kind (planar by Grashof's rule, spherical by their
// closed-form ranges), shared by the tests of the closed forms
// (constructions_test) and of the motion tracer against them (motion_test).
#pragma once

#include <string>
#include <vector>

#include "loopfarm/core/constructions.hpp"
#include "loopfarm/core/sample_loops.hpp"

namespace loopfarm::testing {

struct FourBarCase {
  std::string name;
  LoopGeometry g;
  bool planar;
  FourBarKind kind_at_input_0;
};

// A planar loop written with some axes flipped (twists pi) and offsets that
// sum to zero along the axes: the same mechanism as `g`.
inline LoopGeometry flipped_with_offsets(LoopGeometry g) {
  g.d << 0.3, -0.5, 0.1, 0.1;
  g = axis_flipped(g, 1);
  return axis_flipped(g, 2);
}

inline std::vector<FourBarCase> four_bar_cases() {
  return {
      {"planar crank-rocker", planar_four_bar(1.0, 3.0, 2.5, 3.2), true, FourBarKind::crank_rocker},
      {"planar rocker-crank", planar_four_bar(3.0, 2.5, 1.0, 3.2), true, FourBarKind::rocker_crank},
      {"planar double crank", planar_four_bar(3.0, 2.5, 3.2, 1.0), true, FourBarKind::double_crank},
      {"planar Grashof double rocker", planar_four_bar(3.0, 1.0, 2.5, 3.2), true, FourBarKind::double_rocker},
      {"planar triple rocker", planar_four_bar(2.0, 3.0, 2.2, 4.0), true, FourBarKind::triple_rocker},
      {"planar triple rocker through pi", planar_four_bar(3.0, 1.6, 2.0, 1.9), true, FourBarKind::triple_rocker},
      {"parallelogram", parallelogram_four_bar(1.5, 2.5), true, FourBarKind::change_point},
      {"planar kite", planar_four_bar(1.0, 1.0, 2.0, 2.0), true, FourBarKind::change_point},
      {"planar crank-rocker with flipped axes and offsets", flipped_with_offsets(planar_four_bar(1.0, 3.0, 2.5, 3.2)),
       true, FourBarKind::crank_rocker},
      {"spherical crank-rocker", spherical_four_bar(0.3, 0.9, 0.75, 0.95), false, FourBarKind::crank_rocker},
      {"spherical crank-rocker with large and negative twists", spherical_four_bar(0.5, -2.0, 1.4, 1.9), false,
       FourBarKind::crank_rocker},
      {"spherical double rocker", spherical_four_bar(0.9, 0.3, 0.75, 0.95), false, FourBarKind::double_rocker},
      {"spherical triple rocker", spherical_four_bar(0.8, 1.1, 0.7, 1.5), false, FourBarKind::triple_rocker},
  };
}

}  // namespace loopfarm::testing
