// The fit of the 6R of a cubic motion polynomial, order "321"
// (motion_polynomial.hpp; docs/guide/families.md, "cubic_321") to a loop in
// one of its poses: the family `cubic_321` is decided by it. Internal to the
// search.
//
// The construction: rotation factors h_i = x_i + y_i l_i on the lines of
// joints 1, 2, 3, C = (t - h1)(t - h2)(t - h3) factored again as (t - k1)(t
// - k2)(t - k3) with k1, k2, k3 of the norms of h3, h2, h1, and the loop h1
// h2 h3 k3 k2 k1: opposite joints share a norm factor and turn by equal
// angles. Every joint is at angle 0 at t = infinity; a reparametrisation t
// -> (a t + b) / (c t + d) of the motion moves that pose along it and
// changes no DH parameter, so any pose of the motion can be taken for it,
// and x1 = 0, y1 = 1.
//
// The fit at a closed pose of the loop: t = infinity there, the six axes'
// lines are the loop's, and the factors follow from two linear
// least-squares solves (cubic_motion_fit.cpp): the t^2 coefficients of the
// two factorisations agree for the right y2, y3, and then the t
// coefficients for the right x2, x3, with each of axes 4, 5, 6 taken either
// way round. From these unknowns (theta2, the pose's angle at joint 2, x2,
// y2, x3, y3), polished by Levenberg-Marquardt, the construction is built
// from the loop's links 1 and 2 and offset d2 alone, and its other thirteen
// DH parameters are compared with the loop's: those thirteen differences are
// the fit's residuals, zero on a member (at a pose of its angle-symmetric
// motion) whatever the labels, as the pairing of opposite joints survives a
// relabelling.
#pragma once

#include <array>

#include "loopfarm/core/loop.hpp"

namespace loopfarm::detail {

inline constexpr int kCubicResiduals = 13;

struct CubicMotionFit {
  bool solved = false;  // some set of factors was found and built
  // cos(alpha_k) of the loop minus the construction's for links 3..6, then
  // a'_k / L (a_k signed along u_k x u_{k+1}) for links 3..6, then d_k / L
  // for joints 1, 3, 4, 5, 6.
  std::array<double, kCubicResiduals> residuals{};
  double residual = 1.0;             // max |residual|; 1 when nothing was built
  std::array<double, 5> unknowns{};  // theta2, x2, y2, x3, y3
  std::array<int, 3> flips{};        // +-1: axes 4, 5, 6 as the loop has them against the construction's
};

// The residuals' names, in order.
const char* cubic_residual_name(int i);

// g a 6R (anything else: not solved), pose one of its closed poses.
CubicMotionFit cubic_321_fit(const LoopGeometry& g, const JointVector& pose);

}  // namespace loopfarm::detail
