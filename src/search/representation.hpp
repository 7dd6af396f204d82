// The equivalent ways of writing down one loop: cyclic relabellings, reversal
// of the loop and flips of joint-axis directions (loop.hpp: relabelled,
// reversed, axis_flipped). Each is an affine map of the DH parameters,
// parameter' = sign * parameter[index] + offset (offsets are multiples of pi
// on twists), so a condition evaluated on any representation can be
// differentiated back to the parameters as written. Internal to the library:
// canonical form, classification and family distances share it.
//
// One more freedom is not an affine map of the parameters: where a link has
// zero length (a_k = 0) the direction of its common normal is free, so its
// twist may be written with either sign, alpha_k or -alpha_k, with theta_k and
// theta_{k+1} turned by pi (Rz(pi) Rx(-alpha) = Rx(alpha) Rz(pi)). Which
// links count as zero-length depends on a tolerance, so the callers apply it
// on top of the representations (with_negated_twists): the canonical form at
// its key's resolution, classification at its tolerance.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "loopfarm/core/loop.hpp"

namespace loopfarm::detail {

struct Representation {
  int shift = 0;            // relabelled(., shift) first,
  bool reversed = false;    // then reversed(.) if set,
  std::uint32_t flips = 0;  // then axis_flipped(., j) for every bit j
  // GeometryVector order (a, alpha, d): parameter i of the representation is
  // sign[i] * p[index[i]] + offset[i] (twists then wrapped to (-pi, pi]).
  std::array<int, 3 * kMaxJoints> index{};
  std::array<double, 3 * kMaxJoints> sign{};
  std::array<double, 3 * kMaxJoints> offset{};
  // Joint angles likewise: theta'[k] = angle_sign[k] * theta[angle_index[k]].
  std::array<int, kMaxJoints> angle_index{};
  std::array<double, kMaxJoints> angle_sign{};
};

// All 2n * 2^n representations of an n-joint loop, the identity first.
const std::vector<Representation>& representations(int joints);

// The geometry as the representation writes it (twists wrapped to (-pi, pi]).
LoopGeometry apply(const Representation& r, const LoopGeometry& g);
JointVector apply_angles(const Representation& r, const JointVector& theta);

// A gradient with respect to the representation's parameters, mapped back to
// the parameters as written.
GeometryVector pull_back(const Representation& r, const GeometryVector& gradient);

// The links whose length is at most zero_length * L (L = length_scale(g)),
// one bit per link: those whose twist sign is free. None when zero_length is
// negative (or NaN).
std::uint32_t zero_length_links(const LoopGeometry& g, double zero_length);

// The geometry with the twists of `links` (one bit per link) negated, then
// wrapped to (-pi, pi]: the same loop where those links have zero length.
LoopGeometry with_negated_twists(const LoopGeometry& g, std::uint32_t links);

// The joint angles that go with it: for each link k in `links`, theta_k + pi
// and theta_{k+1} - pi (not wrapped; a joint between two such links keeps its
// angle).
JointVector negated_twist_angles(const JointVector& theta, std::uint32_t links);

}  // namespace loopfarm::detail
