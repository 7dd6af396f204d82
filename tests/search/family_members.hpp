// What the 5R and 6R family tests share (families_test.cpp, families_6r_test.cpp):
// loops posed by each family's construction, random representations,
// closed poses found by the rigid closure, and the checks that a member moves
// and is classified and that its near-misses are rigid.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Geometry>
#include <Eigen/SVD>

#include "allocation_counter.hpp"
#include "loopfarm/core/constructions.hpp"
#include "loopfarm/core/loop.hpp"
#include "loopfarm/core/motion_polynomial.hpp"
#include "loopfarm/core/sample_loops.hpp"
#include "loopfarm/search/classify.hpp"
#include "loopfarm/search/verify.hpp"
#include "test_support.hpp"

namespace loopfarm::family_tests {

inline constexpr double kPi = 3.14159265358979323846;

// ---------------------------------------------------------------------------
// Fixtures

// Posed loops, axes and dh_from_axes are constructions.hpp's.
using Posed = PosedLoop;

inline LoopGeometry make_loop(std::vector<double> a, std::vector<double> alpha, std::vector<double> d) {
  LoopGeometry g;
  const int n = static_cast<int>(a.size());
  g.a = Eigen::Map<JointVector>(a.data(), n);
  g.alpha = Eigen::Map<JointVector>(alpha.data(), n);
  g.d = Eigen::Map<JointVector>(d.data(), n);
  return g;
}

// Bennett loop (a, alpha), (b, beta), (a, alpha), (b, beta), d = 0; the
// caller makes sin(alpha)/a = +-sin(beta)/b.
inline LoopGeometry bennett(double a, double alpha, double b, double beta) {
  return make_loop({a, b, a, b}, {alpha, beta, alpha, beta}, {0, 0, 0, 0});
}

// A closed pose of a Bennett loop at input t, by its setup.
inline JointVector bennett_pose(const LoopGeometry& g, double t) {
  const bool asymmetric = std::sin(g.alpha[0]) * g.a[1] * std::sin(g.alpha[1]) * g.a[0] > 0.0;
  return asymmetric ? bennett_angles(g, t) : bennett_angles_line_symmetric(g, t);
}

// A representation of the same loop by loop.hpp's operations (shift, reversal,
// flips), with its angles.
inline Posed rewritten(const Posed& p, int shift, bool reverse, unsigned flips) {
  Posed out{relabelled(p.geometry, shift), relabelled_angles(p.theta, shift)};
  if (reverse) out = {reversed(out.geometry), reversed_angles(out.theta)};
  for (int j = 0; j < p.geometry.joints(); ++j) {
    if (flips >> j & 1u) out = {axis_flipped(out.geometry, j), axis_flipped_angles(out.theta, j)};
  }
  return out;
}

// A random representation, one in which no joint of `locked` (which the motion does
// not turn) is joint 1, the input that verify_motion drives.
inline Posed random_representation(const Posed& p, std::mt19937_64& rng, const std::vector<int>& locked = {}) {
  const int n = p.geometry.joints();
  std::uniform_int_distribution<int> shift(0, n - 1), flips(0, (1 << n) - 1), coin(0, 1);
  for (;;) {
    const int s = shift(rng);
    const bool reverse = coin(rng) == 1;
    const unsigned f = static_cast<unsigned>(flips(rng));
    // Relabelled, new joint j is old joint j + s; reversed, new joint j is old n - 1 - j.
    const int input = reverse ? (n - 1 + s) % n : s;
    if (std::find(locked.begin(), locked.end(), input) != locked.end()) continue;
    return rewritten(p, s, reverse, f);
  }
}

inline double uniform(std::mt19937_64& rng, double lo, double hi) {
  return std::uniform_real_distribution<double>(lo, hi)(rng);
}

// A twist away from 0 and pi (and its sign random).
inline double twist(std::mt19937_64& rng) {
  const double t = uniform(rng, 0.3, kPi - 0.3);
  return uniform(rng, 0.0, 1.0) < 0.5 ? t : -t;
}

// Goldberg 5R from two random Bennett loops sharing the link (b, beta):
// loop 1 is (A B C D) = (a, alpha, b, beta), loop 2 (A F E D) = (c, gamma,
// b, beta), each in a random setup; they share axes A and D. At A the links
// A->B and A->F are fused collinear (phi = 0: same side, pi: opposite
// sides), link DA removed: the 5R B C D E F (constructions.hpp's
// goldberg_5r, built in space). `phi` other than 0 and pi fuses them at an
// angle: the bent-link variant (docs/guide/families.md).
inline Posed goldberg_member(std::mt19937_64& rng, double phi) {
  for (;;) {
    const double alpha = twist(rng), beta = twist(rng), gamma = twist(rng);
    const double a = uniform(rng, 0.5, 2.0);
    // |sin alpha| / a = |sin beta| / b = |sin gamma| / c, the setups from the signs.
    const double b = a * std::abs(std::sin(beta) / std::sin(alpha));
    const double c = a * std::abs(std::sin(gamma) / std::sin(alpha));
    if (b < 0.3 || b > 4.0 || c < 0.3 || c > 4.0 || std::abs(a - c) < 0.2) continue;
    return goldberg_5r({{b, beta, alpha, gamma}, phi}, uniform(rng, 0.3, kPi - 0.3));
  }
}

// Two Bennett loops sharing a link, the shared link removed and nothing
// fused: loop 1 (A B C D) = (a, alpha, b, beta) and loop 2 (A F E D) =
// (c, gamma, b, beta) in random setups, sharing the link DA (both with frame
// 0 on axis A), each at its own input (t1, t2): the 6R A B C D E F, read off
// its six axes. Each loop turns about DA on its own, so the 6R has two
// degrees of freedom (docs/guide/families.md, "Two Bennett loops sharing a link").
inline Posed bennett_pair_member(std::mt19937_64& rng) {
  for (;;) {
    const double alpha = twist(rng), beta = twist(rng), gamma = twist(rng);
    const double b = uniform(rng, 0.5, 2.0);
    // |sin alpha| / a = |sin beta| / b = |sin gamma| / c, the setups from the signs.
    const double a = b * std::abs(std::sin(alpha) / std::sin(beta));
    const double c = b * std::abs(std::sin(gamma) / std::sin(beta));
    if (a < 0.3 || a > 4.0 || c < 0.3 || c > 4.0) continue;
    const double t1 = uniform(rng, 0.3, kPi - 0.3), t2 = uniform(rng, 0.3, kPi - 0.3);
    return bennett_pair_6r({b, beta, alpha, gamma}, t1, -t2);
  }
}

// Waldron's hybrid 6R (constructions.hpp's waldron_hybrid_6r, built in
// space from its mechanism, not from the classifier's fit): two random
// Bennett loops, each in a random setup (the signs of its twists), sharing
// the joint axis A, the second turned about A and slid along it by random
// amounts, the fused links at a random phase.
inline WaldronHybrid6R random_waldron(std::mt19937_64& rng) {
  for (;;) {
    WaldronHybrid6R p;
    p.b = uniform(rng, 0.5, 2.0);
    p.beta = twist(rng);
    p.alpha = twist(rng);
    p.e = uniform(rng, 0.5, 2.0);
    p.epsilon = twist(rng);
    p.gamma = twist(rng);
    // The Bennett loops' other links: a = b |sin alpha / sin beta|, c = e |sin gamma / sin epsilon|.
    const double a = p.b * std::abs(std::sin(p.alpha) / std::sin(p.beta));
    const double c = p.e * std::abs(std::sin(p.gamma) / std::sin(p.epsilon));
    if (a < 0.3 || a > 4.0 || c < 0.3 || c > 4.0) continue;
    p.turn = uniform(rng, -kPi, kPi);
    p.slide = uniform(rng, -0.8, 0.8);
    p.phase = uniform(rng, -kPi, kPi);
    return p;
  }
}

inline Posed waldron_member(std::mt19937_64& rng) {
  const WaldronHybrid6R p = random_waldron(rng);
  return waldron_hybrid_6r(p, uniform(rng, -kPi, kPi));
}

// Hooke's double-spherical 6R (constructions.hpp's hooke_6r, built in space
// from two centres and three axis directions through each, not from the
// conditions): the centres 0.6 to 1.6 apart, random directions with every
// two axes of a triad and every two consecutive axes at least 0.3 rad from
// parallel, neither triad near a plane, and the line of centres at least
// 0.25 (in cosine) from perpendicular to axes 1, 3, 4 and 6 (so that moving
// an offset of links 3 or 6 changes the distance it holds to first order).
// `t` is a turn of link 3 at which it can still turn 0.2 rad either way.
struct HookeMember {
  Hooke6R parameters;
  double t = 0.0;
};

inline HookeMember random_hooke(std::mt19937_64& rng) {
  const auto direction = [&] {
    for (;;) {
      const Vector3 v(uniform(rng, -1, 1), uniform(rng, -1, 1), uniform(rng, -1, 1));
      if (v.norm() > 0.2 && v.norm() < 1.0) return Vector3(v.normalized());
    }
  };
  const auto apart = [](const Vector3& u, const Vector3& v) { return u.cross(v).norm() > std::sin(0.3); };
  for (;;) {
    HookeMember m;
    Hooke6R& p = m.parameters;
    p.o1 = Vector3(uniform(rng, -1, 1), uniform(rng, -1, 1), uniform(rng, -1, 1));
    const Vector3 line = direction();
    p.o2 = p.o1 + uniform(rng, 0.6, 1.6) * line;
    for (Vector3& u : p.u) u = direction();
    const auto& u = p.u;
    bool ok = apart(u[0], u[2]) && apart(u[3], u[5]);
    for (size_t k = 0; k < 6; ++k) ok = ok && apart(u[k], u[(k + 1) % 6]);
    ok = ok && std::abs(u[0].dot(u[1].cross(u[2]))) > 0.3 && std::abs(u[3].dot(u[4].cross(u[5]))) > 0.3;
    for (int k : {0, 2, 3, 5}) ok = ok && std::abs(line.dot(u[static_cast<size_t>(k)])) > 0.25;
    if (!ok) continue;
    m.t = uniform(rng, -1.0, 1.0);
    if (hooke_6r(p, m.t - 0.2) && hooke_6r(p, m.t) && hooke_6r(p, m.t + 0.2)) return m;
  }
}

inline Posed hooke_member(std::mt19937_64& rng) {
  const HookeMember m = random_hooke(rng);
  return *hooke_6r(m.parameters, m.t);
}

// Myard 5R: Goldberg from two mirror-image Bennett loops, the shared link a
// right-angle twist: (a, alpha, b, pi/2) and (a, -alpha, b, pi/2).
// Goldberg's 6R of three Bennett loops (constructions.hpp's three_bennett_6r,
// built in space from its mechanism, not from the classifier's fit): a
// Goldberg 5R from two random Bennett loops in random setups, fused at A
// collinear (either side) or at a random angle, and a third Bennett loop of
// random twist on its link `link` (random when negative), fused at P
// collinear or at a random angle. Lengths kept within [0.3, 4] of each other.
// A fusion angle of two Bennett loops' links: collinear on opposite sides
// (pi) or the same side (0), or bent at a random angle of random sign.
inline double random_fusion(std::mt19937_64& rng) {
  const double u = uniform(rng, 0.0, 1.0);
  if (u < 0.25) return kPi;
  if (u < 0.4) return 0.0;
  const double angle = uniform(rng, 0.3, kPi - 0.3);
  return uniform(rng, 0.0, 1.0) < 0.5 ? angle : -angle;
}

inline ThreeBennett6R random_goldberg_6r(std::mt19937_64& rng, int link = -1) {
  const auto fusion = [&] { return random_fusion(rng); };
  for (;;) {
    const double alpha = twist(rng), beta = twist(rng), gamma = twist(rng);
    const double a = uniform(rng, 0.5, 2.0);
    const double b = a * std::abs(std::sin(beta) / std::sin(alpha));
    const double c = a * std::abs(std::sin(gamma) / std::sin(alpha));
    if (b < 0.3 || b > 4.0 || c < 0.3 || c > 4.0 || std::abs(a - c) < 0.2) continue;
    ThreeBennett6R p;
    p.goldberg = {{b, beta, alpha, gamma}, fusion()};
    p.link = link >= 0 ? link : static_cast<int>(uniform(rng, 0.0, 5.0 - 1e-9));
    p.gamma = twist(rng);
    p.phi = fusion();
    // The link the third loop shares, and the third loop's other length.
    const LoopGeometry five = goldberg_5r(p.goldberg, 1.0).geometry;
    const double a_pq = five.a[p.link], sin_pq = std::abs(std::sin(five.alpha[p.link]));
    if (a_pq < 0.3 || a_pq > 4.0 || sin_pq < 0.2) continue;
    const double c3 = a_pq * std::abs(std::sin(p.gamma)) / sin_pq;
    if (c3 < 0.3 || c3 > 4.0) continue;
    return p;
  }
}

inline Posed goldberg_6r_member(std::mt19937_64& rng, int link = -1) {
  return three_bennett_6r(random_goldberg_6r(rng, link), uniform(rng, 0.3, kPi - 0.3));
}

// The double-Goldberg 6R (constructions.hpp's double_goldberg_6r, built in
// space from three Bennett loops, not from the classifier's conditions): a
// Goldberg 5R from two random Bennett loops in random setups and a third
// loop of random twist on the first loop's link AB, each fused at A
// collinear (either side) or at a random angle. Lengths within [0.3, 4].
inline DoubleGoldberg6R random_double_goldberg(std::mt19937_64& rng) {
  for (;;) {
    const double alpha = twist(rng), beta = twist(rng), gamma = twist(rng), epsilon = twist(rng);
    const double a = uniform(rng, 0.5, 2.0);
    // |sin alpha| / a = |sin beta| / b = |sin gamma| / c = |sin epsilon| / e.
    const double b = a * std::abs(std::sin(beta) / std::sin(alpha));
    const double c = a * std::abs(std::sin(gamma) / std::sin(alpha));
    const double e = a * std::abs(std::sin(epsilon) / std::sin(alpha));
    if (std::min({b, c, e}) < 0.3 || std::max({b, c, e}) > 4.0) continue;
    // Fused on one side, the fused links F -> B and Y -> D are a - c and
    // e - b long: kept away from coincident axes.
    if (std::abs(a - c) < 0.2 || std::abs(e - b) < 0.2) continue;
    DoubleGoldberg6R p;
    p.goldberg = {{b, beta, alpha, gamma}, random_fusion(rng)};
    p.epsilon = epsilon;
    p.psi = random_fusion(rng);
    return p;
  }
}

inline Posed double_goldberg_member(std::mt19937_64& rng) {
  return double_goldberg_6r(random_double_goldberg(rng), uniform(rng, 0.3, kPi - 0.3));
}

inline Posed myard_member(std::mt19937_64& rng, double phi) {
  const double alpha = twist(rng), a = uniform(rng, 0.5, 2.0);
  const double b = a / std::abs(std::sin(alpha));
  return goldberg_5r({{b, kPi / 2, alpha, -alpha}, phi}, uniform(rng, 0.3, kPi - 0.3));
}

// A closed pose of a 6R: inputs tried over the turn until one assembles.
inline bool closed_pose(const LoopGeometry& g, std::mt19937_64& rng, JointVector& theta) {
  for (int i = 0; i < 12; ++i) {
    if (testing::assemble_by_levenberg_marquardt(g, -kPi + (i + 0.5) * kPi / 6, rng, theta, 30)) return true;
  }
  return false;
}

// Bricard's doubly collapsible octahedron (bricard_octahedral_collapsible's
// flat pose): the two radii apart, P and T outside both circles and at least
// 0.7 rad from each other and from the opposite direction (where tangents
// from them are parallel), and the two ways each pair of tangents meets.
// Drawn again while tangents meet far out (an offset above 6) or two
// consecutive hinges are within 10 degrees of one line: nearly degenerate
// octahedra, whose conditions read round-off times their large lengths.
// `way` 0-3 fixes the pairings (bit 0: cross_sr, bit 1: cross_qu).
inline OctahedronCollapsible random_collapsible(std::mt19937_64& rng, int way = -1) {
  while (true) {
    OctahedronCollapsible o;
    o.r1 = uniform(rng, 0.4, 0.8);
    o.r2 = uniform(rng, 1.0, 1.4);
    const double phi = uniform(rng, -kPi, kPi);
    const double psi = phi + (rng() % 2 ? 1.0 : -1.0) * uniform(rng, 0.7, kPi - 0.7);
    o.p = uniform(rng, 1.8, 2.6) * Eigen::Vector2d(std::cos(phi), std::sin(phi));
    o.t = uniform(rng, 1.8, 2.6) * Eigen::Vector2d(std::cos(psi), std::sin(psi));
    o.cross_sr = way < 0 ? rng() % 2 != 0 : (way & 1) != 0;
    o.cross_qu = way < 0 ? rng() % 2 != 0 : (way & 2) != 0;
    const LoopGeometry g = bricard_octahedral_collapsible(o).geometry;
    if (g.d.cwiseAbs().maxCoeff() < 6.0 && g.alpha.array().sin().abs().minCoeff() > std::sin(10.0 * kPi / 180.0)) {
      return o;
    }
  }
}

// The pose of a traced motion farthest from its flat poses, which are
// singular points of a doubly collapsible octahedron's motion: the one on
// the reported circuit whose joint angle nearest 0 or pi is farthest from it.
inline JointVector off_flat_pose(const VerificationSummary& whole) {
  EXPECT_TRUE(whole.verified) << whole.limit;
  JointVector best = JointVector::Zero(6);
  double farthest = -1.0;
  for (const JointVector& theta : whole.joint_angles) {
    const double nearest = theta.array().sin().abs().minCoeff();
    if (nearest > farthest) {
      farthest = nearest;
      best = theta;
    }
  }
  return best;
}

// A doubly collapsible octahedron in a pose off its flat ones.
inline Posed collapsible_member(std::mt19937_64& rng) {
  const LoopGeometry g = bricard_octahedral_collapsible(random_collapsible(rng)).geometry;
  return {g, off_flat_pose(verify_motion(g, nullptr))};
}

// The 6R of a cubic motion polynomial in the order "321"
// (motion_polynomial.hpp's cubic_motion_6r, built from three rotation
// factors, not from the fit): axes through points in [-1, 1]^3 with random
// directions, x in [-1, 1], |y| in [0.4, 1.6] of either sign, the three
// norm factors' roots x + i |y| at least 0.3 apart. Drawn again while the
// loop has a link within 10 degrees of parallel axes, a length or offset
// above 6 L or below 0.05 L (nearly degenerate loops: their residuals read
// round-off times large numbers), or t (in [-3, 3]) leaves no closed pose.
inline CubicMotion6R random_cubic(std::mt19937_64& rng) {
  while (true) {
    CubicMotion6R p;
    for (RotationFactor& f : p.factors) {
      f.axis.point = Vector3(uniform(rng, -1, 1), uniform(rng, -1, 1), uniform(rng, -1, 1));
      f.axis.direction = Vector3(uniform(rng, -1, 1), uniform(rng, -1, 1), uniform(rng, -1, 1));
      if (!(f.axis.direction.norm() > 0.3)) f.axis.direction = Vector3::UnitZ();
      f.x = uniform(rng, -1, 1);
      f.y = uniform(rng, 0.4, 1.6) * (rng() % 2 ? 1.0 : -1.0);
    }
    bool apart = true;
    for (size_t i = 0; i < 3; ++i) {
      for (size_t j = i + 1; j < 3; ++j) {
        apart = apart &&
                std::hypot(p.factors[i].x - p.factors[j].x, std::abs(p.factors[i].y) - std::abs(p.factors[j].y)) > 0.3;
      }
    }
    if (!apart) continue;
    const LoopGeometry g = cubic_motion_6r(p, 0.0).geometry;
    const double L = length_scale(g);
    const double largest = std::max(g.a.cwiseAbs().maxCoeff(), g.d.cwiseAbs().maxCoeff()) / L;
    if (largest < 6.0 && g.a.minCoeff() > 0.05 * L &&
        g.alpha.array().sin().abs().minCoeff() > std::sin(10.0 * kPi / 180.0)) {
      return p;
    }
  }
}

inline Posed cubic_member(std::mt19937_64& rng) {
  const CubicMotion6R p = random_cubic(rng);
  const PosedLoop m = cubic_motion_6r(p, uniform(rng, -3, 3));
  return {m.geometry, m.theta};
}

// The angle-symmetric 6R with three pairs of parallel axes
// (angle_symmetric_parallel_6r) of the given kind: random directions, steps
// between the parallel axes of length 0.5 to 1.5, points in the unit cube
// about the origin. Drawn again while a twist between the pairs is within 10
// degrees of 0 or pi, a length or offset exceeds 4 (the general kind's g
// grows without bound where its last condition nearly divides by zero) or
// axes 3 and 6 are less than 0.2 apart.
inline Vector3 random_vector(std::mt19937_64& rng, double lo, double hi) {
  Vector3 x;
  do {
    x = {uniform(rng, -1.0, 1.0), uniform(rng, -1.0, 1.0), uniform(rng, -1.0, 1.0)};
  } while (x.norm() < 0.2 || x.norm() > 1.0);
  return uniform(rng, lo, hi) * x.normalized();
}

inline AngleSymmetricParallel6R random_angle_symmetric_parallel(std::mt19937_64& rng, ParallelPairsKind kind) {
  for (;;) {
    AngleSymmetricParallel6R p;
    p.kind = kind;
    p.u = random_vector(rng, 1.0, 1.0);
    p.v = random_vector(rng, 1.0, 1.0);
    p.h = random_vector(rng, 1.0, 1.0);
    p.e1 = random_vector(rng, 0.5, 1.5);
    p.e4 = random_vector(rng, 0.5, 1.5);
    p.e1 -= p.e1.dot(p.u) * p.u;
    p.e4 -= p.e4.dot(p.v) * p.v;
    if (p.e1.norm() < 0.5 || p.e4.norm() < 0.5) continue;
    p.w_turn = uniform(rng, -kPi, kPi);
    p.g_length = (rng() % 2 ? 1.0 : -1.0) * uniform(rng, 0.3, 1.5);
    p.p1 = random_vector(rng, 0.0, 1.0);
    p.p3 = random_vector(rng, 0.0, 1.0);
    p.p4 = random_vector(rng, 0.0, 1.0);
    if (std::abs(p.u.cross(p.h).norm()) < 0.3) continue;
    try {
      const LoopGeometry g = angle_symmetric_parallel_6r(p, 0.0).geometry;
      bool far = g.a.cwiseAbs().maxCoeff() < 4.0 && g.d.cwiseAbs().maxCoeff() < 4.0 && g.a[2] + g.a[5] > 0.0;
      for (int k : {1, 2, 4, 5}) far = far && std::abs(std::sin(g.alpha[k])) > std::sin(10.0 * kPi / 180.0);
      const std::vector<Axis> axes = joint_axes(g, angle_symmetric_parallel_6r(p, 0.0).theta);
      const Vector3 between = axes[5].point - axes[2].point;
      far = far && (between - between.dot(axes[2].direction) * axes[2].direction).norm() > 0.2;
      if (far) return p;
    } catch (const std::invalid_argument&) {
    }
  }
}

constexpr std::array<ParallelPairsKind, 2> kParallelPairsKinds = {ParallelPairsKind::general,
                                                                  ParallelPairsKind::half_turn};

// A member at a random t of its motion.
inline Posed angle_symmetric_parallel_member(std::mt19937_64& rng, ParallelPairsKind kind) {
  const AngleSymmetricParallel6R p = random_angle_symmetric_parallel(rng, kind);
  return angle_symmetric_parallel_6r(p, uniform(rng, -kPi, kPi));
}

// Bricard line-symmetric 6R: a_i = a_{i+3}, alpha_i = alpha_{i+3}, d_i = d_{i+3}.
inline LoopGeometry bricard_line_geometry(std::mt19937_64& rng) {
  std::array<double, 3> a, t, d;
  for (int i = 0; i < 3; ++i) {
    a[i] = uniform(rng, 0.5, 2.0);
    t[i] = twist(rng);
    d[i] = uniform(rng, -0.5, 0.5);
  }
  return make_loop({a[0], a[1], a[2], a[0], a[1], a[2]}, {t[0], t[1], t[2], t[0], t[1], t[2]},
                   {d[0], d[1], d[2], d[0], d[1], d[2]});
}

// Bricard plane-symmetric 6R (plane through joints 1 and 4).
inline LoopGeometry bricard_plane_geometry(std::mt19937_64& rng) {
  std::array<double, 3> a, t;
  for (int i = 0; i < 3; ++i) {
    a[i] = uniform(rng, 0.5, 2.0);
    t[i] = twist(rng);
  }
  const double d2 = uniform(rng, -0.5, 0.5), d3 = uniform(rng, -0.5, 0.5);
  return make_loop({a[0], a[1], a[2], a[2], a[1], a[0]}, {t[0], t[1], t[2], -t[2], -t[1], -t[0]},
                   {0, d2, d3, 0, -d3, -d2});
}

// Bricard trihedral 6R: right-angle twists of random signs, no offsets,
// a6 from a1^2 + a3^2 + a5^2 = a2^2 + a4^2 + a6^2.
inline LoopGeometry bricard_trihedral_geometry(std::mt19937_64& rng) {
  for (;;) {
    std::vector<double> a(6), alpha(6);
    for (int i = 0; i < 5; ++i) a[i] = uniform(rng, 0.5, 2.0);
    const double a6_squared = a[0] * a[0] + a[2] * a[2] + a[4] * a[4] - a[1] * a[1] - a[3] * a[3];
    if (a6_squared < 0.25) continue;
    a[5] = std::sqrt(a6_squared);
    for (int i = 0; i < 6; ++i) alpha[i] = uniform(rng, 0.0, 1.0) < 0.5 ? kPi / 2 : -kPi / 2;
    return make_loop(a, alpha, std::vector<double>(6, 0.0));
  }
}

// Two Bennett dyads joined by two equal links: links 1, 2 with Bennett's
// ratio kappa1 and d2 = 0, links 4, 5 with kappa2 and d5 = 0, the same
// (cos alpha + cos beta) / kappa (alpha5 solved from it), links 3 and 6
// equal and free, d1 = d3 and d4 = d6 free. Twists negative (the searches'
// canonical representation; other representations are the test's random ones).
inline LoopGeometry bennett_dyads_geometry(std::mt19937_64& rng) {
  for (;;) {
    const double k1 = -uniform(rng, 0.4, 1.5), k2 = -uniform(rng, 0.4, 1.5);
    const double t1 = -uniform(rng, 0.3, kPi - 0.3), t2 = -uniform(rng, 0.3, kPi - 0.3);
    const double t4 = -uniform(rng, 0.3, kPi - 0.3);
    const double cos5 = (std::cos(t1) + std::cos(t2)) / k1 * k2 - std::cos(t4);
    if (std::abs(cos5) > 0.95) continue;
    const double t5 = -std::acos(cos5);
    const double c = uniform(rng, 0.5, 1.5), gamma = -uniform(rng, 0.3, kPi - 0.3);
    const std::vector<double> a = {std::sin(t1) / k1, std::sin(t2) / k1, c, std::sin(t4) / k2, std::sin(t5) / k2, c};
    if (*std::min_element(a.begin(), a.end()) < 0.2 || *std::max_element(a.begin(), a.end()) > 3.0) continue;
    const double e = uniform(rng, -0.3, 0.3), f = uniform(rng, -0.3, 0.3);
    return make_loop(a, {t1, t2, gamma, t4, t5, gamma}, {e, 0.0, e, f, 0.0, f});
  }
}

// Two Bennett-ratio triads (bennett_triads) from their conditions: links 1-3
// of ratio k1 = |sin alpha| / a, links 4-6 of k2, alpha1..alpha5 given (in
// (-pi, 0)), alpha6 and k2 solved from the two quantities the triads share
// (a quadratic in cos(alpha6/2), or in sin(alpha6/2) when `plus`; `root`
// picks one), d1 given and d4 = -d1, or d4 = d1 when `plus` (that form is the
// first with axes 1, 3 and 5 flipped); no other offset. None where the
// quadratic has no root in range or k2 lies beyond 20 times k1 either way.
inline std::optional<LoopGeometry> bennett_triads_loop(bool plus, double k1, const std::array<double, 5>& alpha,
                                                       double d1, int root) {
  const double sign = plus ? -1.0 : 1.0;
  const auto half = [&](double x) { return plus ? std::sin(0.5 * x) : std::cos(0.5 * x); };
  const double lambda = (1.0 + sign * (std::cos(alpha[0]) + std::cos(alpha[1]) + std::cos(alpha[2]))) / k1;
  const double mu = half(alpha[0]) * half(alpha[1]) * half(alpha[2]) / k1;
  const double c45 = std::cos(alpha[3]) + std::cos(alpha[4]), h45 = half(alpha[3]) * half(alpha[4]);
  // With x = half(alpha6), 1 +- the sum of cosines of links 4-6 is sign c45 +
  // 2 x^2, so k2 = (sign c45 + 2 x^2) / lambda, and mu k2 = h45 x:
  // 2 mu x^2 - lambda h45 x + sign mu c45 = 0.
  const double qa = 2.0 * mu, qb = -lambda * h45, qc = sign * mu * c45;
  const double discriminant = qb * qb - 4.0 * qa * qc;
  if (!(discriminant >= 0.0) || qa == 0.0) return std::nullopt;
  const double x = (-qb + (root == 0 ? 1.0 : -1.0) * std::sqrt(discriminant)) / (2.0 * qa);
  // alpha6 in (-pi, 0): cos(alpha6/2) in (0, 1), sin(alpha6/2) in (-1, 0).
  if (plus ? !(x > -1.0 && x < 0.0) : !(x > 0.0 && x < 1.0)) return std::nullopt;
  const double alpha6 = plus ? 2.0 * std::asin(x) : -2.0 * std::acos(x);
  const double k2 = (sign * c45 + 2.0 * x * x) / lambda;
  if (!(k2 > 0.0) || !(k2 < 20.0 * k1) || !(k2 > k1 / 20.0)) return std::nullopt;
  LoopGeometry g;
  g.alpha = JointVector(6);
  g.alpha << alpha[0], alpha[1], alpha[2], alpha[3], alpha[4], alpha6;
  g.a = JointVector(6);
  for (int i = 0; i < 6; ++i) g.a[i] = std::abs(std::sin(g.alpha[i])) / (i < 3 ? k1 : k2);
  g.d = JointVector::Zero(6);
  g.d[0] = d1;
  g.d[3] = plus ? d1 : -d1;
  return g;
}

// A random bennett_triads loop (d4 = -d1, twists in (-0.95 pi, -0.05 pi)),
// its lengths within [0.2, 3]. Most assemble (docs/guide/families.md).
inline LoopGeometry bennett_triads_geometry(std::mt19937_64& rng) {
  for (;;) {
    const double k1 = uniform(rng, 0.4, 1.5), d1 = uniform(rng, -0.2, 0.2);
    std::array<double, 5> alpha;
    for (double& t : alpha) t = -uniform(rng, 0.05 * kPi, 0.95 * kPi);
    for (int root : {0, 1}) {
      const std::optional<LoopGeometry> g = bennett_triads_loop(false, k1, alpha, d1, root);
      if (g && g->a.minCoeff() >= 0.2 && g->a.maxCoeff() <= 3.0) return *g;
    }
  }
}

// One in a closed pose, found by the rigid closure from random guesses.
inline Posed bennett_triads_member(std::mt19937_64& rng) {
  for (;;) {
    const LoopGeometry g = bennett_triads_geometry(rng);
    JointVector theta;
    if (closed_pose(g, rng, theta)) return {g, theta};
  }
}

// Two Bennett dyads with coupled middle joints (coupled_bennett_dyads) from
// their conditions, the only construction known: the dyads' signed ratio k2
// = sin alpha / a and twists alpha2, alpha3, alpha5 given, alpha6 from
// tan(alpha2/2) tan(alpha3/2) = tan(alpha5/2) tan(alpha6/2) and k5 from
// (cos alpha2 + cos alpha3) / k2 = (cos alpha5 + cos alpha6) / k5; the
// joining links' a1, alpha1, alpha4 given and a4 from tan(alpha1/2) / a1 =
// tan(alpha4/2) / a4; with m = a / sin alpha of links 1 and 4, the offsets
// (d1, d2, d4, d5) = s (1/k5, 1/k2, 1/k2, 1/k5) + t (m1, m1, m4, m4), d3 = d6
// = 0, t given and s = +-sqrt(k2 k5 m1 m4 (1 + t^2) - 1) (`s_sign`). Eight
// free parameters.
struct CoupledBennettDyadsParameters {
  double k2, alpha2, alpha3, alpha5, a1, alpha1, alpha4, t;
  double s_sign = 1.0;
};
struct CoupledBennettDyads {
  LoopGeometry geometry;
  double k2, k5, m1, m4, s, t;
};

// The offsets of the conic's parametric form at (s, t).
inline JointVector coupled_bennett_dyads_offsets(const CoupledBennettDyads& c, double s, double t) {
  JointVector d = JointVector::Zero(6);
  d[0] = s / c.k5 + t * c.m1;
  d[1] = s / c.k2 + t * c.m1;
  d[3] = s / c.k2 + t * c.m4;
  d[4] = s / c.k5 + t * c.m4;
  return d;
}

// None where a length comes out negative or s imaginary.
inline std::optional<CoupledBennettDyads> coupled_bennett_dyads_loop(const CoupledBennettDyadsParameters& p) {
  const auto half_tan = [](double x) { return std::tan(0.5 * x); };
  const double alpha6 = 2.0 * std::atan(half_tan(p.alpha2) * half_tan(p.alpha3) / half_tan(p.alpha5));
  CoupledBennettDyads c;
  c.k2 = p.k2;
  c.k5 = p.k2 * (std::cos(p.alpha5) + std::cos(alpha6)) / (std::cos(p.alpha2) + std::cos(p.alpha3));
  const double a4 = p.a1 * half_tan(p.alpha4) / half_tan(p.alpha1);
  const std::vector<double> a = {p.a1, std::sin(p.alpha2) / c.k2, std::sin(p.alpha3) / c.k2,
                                 a4,   std::sin(p.alpha5) / c.k5, std::sin(alpha6) / c.k5};
  if (!(*std::min_element(a.begin(), a.end()) > 0.0)) return std::nullopt;
  c.m1 = p.a1 / std::sin(p.alpha1);
  c.m4 = a4 / std::sin(p.alpha4);
  c.t = p.t;
  const double s2 = c.k2 * c.k5 * c.m1 * c.m4 * (1.0 + c.t * c.t) - 1.0;
  if (!(s2 > 0.0)) return std::nullopt;
  c.s = std::copysign(std::sqrt(s2), p.s_sign);
  c.geometry = make_loop(a, {p.alpha1, p.alpha2, p.alpha3, p.alpha4, p.alpha5, alpha6}, std::vector<double>(6, 0.0));
  c.geometry.d = coupled_bennett_dyads_offsets(c, c.s, c.t);
  return c;
}

// A random one: the two dyads' twists of one sign and the two joining
// links' of one sign, each sign drawn (a dyad's twists take its ratio's
// sign, the lengths being positive; dyads of opposite signs make s
// imaginary, joining links of opposite signs a4 negative), |k2| in [0.4,
// 2], the twists 0.15 rad or more from 0 and pi, a1 in [0.3, 2], t in
// [-1.5, 1.5]; redrawn unless alpha6 is 0.1 rad or more from 0 and pi, |k5|
// lies in [0.2, 5] and a4 in [0.1, 5].
inline CoupledBennettDyads coupled_bennett_dyads_draw(std::mt19937_64& rng) {
  const auto sign = [&] { return uniform(rng, -1.0, 1.0) < 0.0 ? -1.0 : 1.0; };
  for (;;) {
    const double dyads = sign(), joining = sign();
    const auto twist = [&](double s) { return s * uniform(rng, 0.15, kPi - 0.15); };
    CoupledBennettDyadsParameters p;
    p.k2 = dyads * uniform(rng, 0.4, 2.0);
    p.alpha2 = twist(dyads);
    p.alpha3 = twist(dyads);
    p.alpha5 = twist(dyads);
    p.a1 = uniform(rng, 0.3, 2.0);
    p.alpha1 = twist(joining);
    p.alpha4 = twist(joining);
    p.t = uniform(rng, -1.5, 1.5);
    p.s_sign = sign();
    const std::optional<CoupledBennettDyads> c = coupled_bennett_dyads_loop(p);
    if (!c) continue;
    const double alpha6 = std::abs(c->geometry.alpha[5]), k5 = std::abs(c->k5), a4 = c->geometry.a[3];
    if (alpha6 > 0.1 && alpha6 < kPi - 0.1 && k5 >= 0.2 && k5 <= 5.0 && a4 > 0.1 && a4 < 5.0) return *c;
  }
}

// The builder's parameters of a loop it built.
inline CoupledBennettDyadsParameters coupled_bennett_dyads_parameters(const CoupledBennettDyads& c) {
  const LoopGeometry& g = c.geometry;
  CoupledBennettDyadsParameters p;
  p.k2 = c.k2;
  p.alpha2 = g.alpha[1];
  p.alpha3 = g.alpha[2];
  p.alpha5 = g.alpha[4];
  p.a1 = g.a[0];
  p.alpha1 = g.alpha[0];
  p.alpha4 = g.alpha[3];
  p.t = c.t;
  p.s_sign = c.s;
  return p;
}

inline LoopGeometry coupled_bennett_dyads_geometry(std::mt19937_64& rng) {
  return coupled_bennett_dyads_draw(rng).geometry;
}

// One in a closed pose, found by the rigid closure from random guesses.
inline Posed coupled_bennett_dyads_member(std::mt19937_64& rng) {
  for (;;) {
    const LoopGeometry g = coupled_bennett_dyads_geometry(rng);
    JointVector theta;
    if (closed_pose(g, rng, theta)) return {g, theta};
  }
}

// A Sarrus loop from its mechanism (constructions.hpp: two chains of parallel
// axes between a base and a top), not from its conditions: random axis
// directions, points and links, read off the axes at the top's travel 0.
inline LoopGeometry sarrus_geometry(std::mt19937_64& rng) {
  auto point = [&] { return Vector3(uniform(rng, -1, 1), uniform(rng, -1, 1), uniform(rng, -1, 1)); };
  for (;;) {
    Sarrus6R p;
    p.gamma = uniform(rng, 0.3, kPi - 0.3);
    p.base_u = point();
    p.top_u = point();
    p.base_v = point();
    p.top_v = point();
    p.r_base_u = uniform(rng, 0.5, 1.5);
    p.r_top_u = uniform(rng, 0.5, 1.5);
    p.r_base_v = uniform(rng, 0.5, 1.5);
    p.r_top_v = uniform(rng, 0.5, 1.5);
    p.elbow_u = uniform(rng, 0, 1) < 0.5;
    p.elbow_v = uniform(rng, 0, 1) < 0.5;
    const std::optional<PosedLoop> built = sarrus_6r(p, 0.0);
    if (!built) continue;
    const LoopGeometry& g = built->geometry;
    if (g.a.minCoeff() < 0.1 * length_scale(g)) continue;  // no nearly coincident axes
    // The top must travel: both chains still reach a little either way.
    if (!sarrus_6r(p, -0.05) || !sarrus_6r(p, 0.05)) continue;
    return g;
  }
}

// A loop plus an idle joint: joint 1 of `p` split into two coaxial joints
// (a link of length 0 and twist 0 or pi between them, the offset shared
// between them), the angle split too.
inline Posed with_idle_joint(const Posed& p, std::mt19937_64& rng) {
  const int n = p.geometry.joints();
  const bool flipped = uniform(rng, 0.0, 1.0) < 0.5;
  const double sigma = flipped ? kPi : 0.0, c = flipped ? -1.0 : 1.0;
  const double t = uniform(rng, -0.5, 0.5), spin = uniform(rng, -kPi, kPi);
  Posed out;
  out.geometry.a.resize(n + 1);
  out.geometry.alpha.resize(n + 1);
  out.geometry.d.resize(n + 1);
  out.theta.resize(n + 1);
  out.geometry.a << 0.0, p.geometry.a;
  out.geometry.alpha << sigma, p.geometry.alpha;
  out.geometry.alpha[1] = wrap_angle(p.geometry.alpha[0] - sigma);
  out.geometry.d << t, p.geometry.d;
  out.geometry.d[1] = c * (p.geometry.d[0] - t);  // d_1 + c d_2 = the merged offset
  out.theta << spin, p.theta;
  out.theta[1] = c * (p.theta[0] - spin);
  return out;
}

inline double closure_error(const Posed& p) { return closure_residual(p.geometry, p.theta).cwiseAbs().maxCoeff(); }

// The rigid verification from the given pose only, as the farm verifies a
// zero: whether the loop moves there. Finding motions from anywhere else is
// motion_test's.
inline VerificationSummary verify_from(const LoopGeometry& g, const JointVector& pose) {
  VerificationOptions o;
  o.all_circuits = false;
  return verify_motion(g, pose, o);
}

inline Classification classified(const Posed& p, const VerificationSummary& v) {
  const std::span<const double> travel(v.joint_travel.data(), static_cast<size_t>(v.joint_travel.size()));
  return classify(p.geometry, p.theta, v.verified ? travel : std::span<const double>());
}

// The member is movable (rigid closure followed along at least 10 degrees of
// input, closing to round-off) and, in a random representation, classified as its
// family with a residual at round-off.
inline void expect_movable_member(const Posed& member, Family family, std::mt19937_64& rng, const std::string& tag,
                                  const std::vector<int>& locked = {}) {
  ASSERT_LT(closure_error(member), 1e-12) << tag;
  const Posed w = random_representation(member, rng, locked);
  ASSERT_LT(closure_error(w), 1e-12) << tag;
  const VerificationSummary v = verify_from(w.geometry, w.theta);
  EXPECT_TRUE(v.verified) << tag << ": " << v.limit;
  EXPECT_GT(v.range_hi - v.range_lo, 10.0 * kPi / 180.0) << tag;
  const Classification c = classified(w, v);
  EXPECT_EQ(c.family, family) << tag << ": " << to_string(c.family) << ", " << c.detail;
  ASSERT_FALSE(c.fitting.empty()) << tag;
  EXPECT_EQ(c.fitting.front(), family) << tag;
  EXPECT_LT(c.residual, 1e-10) << tag;
  // The family's own check says so too, whatever family won; the residual
  // reported is that of the reported family's check.
  for (const FamilyCheck& check : c.checks) {
    if (check.family == family) {
      EXPECT_LT(check.residual, 1e-10) << tag;
    }
    if (check.family == c.family) {
      EXPECT_EQ(check.residual, c.residual) << tag << ": " << to_string(c.family) << ", " << c.detail;
    }
  }
}

// Parameter p (GeometryVector order: a, alpha, d) moved by eps (times L for
// lengths and offsets, radians for twists).
inline LoopGeometry perturbed(const LoopGeometry& g, int p, double eps) {
  const int n = g.joints();
  LoopGeometry out = g;
  const double L = length_scale(g);
  if (p < n)
    out.a[p] += eps * L;
  else if (p < 2 * n)
    out.alpha[p - n] += eps;
  else
    out.d[p - 2 * n] += eps * L;
  return out;
}

// Parameter p moved by h in its own units (for central differences).
inline LoopGeometry perturbed_raw(const LoopGeometry& g, int p, double h) {
  const int n = g.joints();
  LoopGeometry out = g;
  if (p < n)
    out.a[p] += h;
  else if (p < 2 * n)
    out.alpha[p - n] += h;
  else
    out.d[p - 2 * n] += h;
  return out;
}

inline const std::array<double, 4> kNearMisses = {1e-3, 1e-4, 1e-5, 1e-6};

// The member with parameter p moved by each near-miss size: the rigid
// closure cannot follow it from the member's pose (not verified), and it is
// not classified as the family, its residual there at least eps / 10.
inline void expect_near_misses_rigid(const Posed& member, Family family, int p, const std::string& tag) {
  for (double eps : kNearMisses) {
    const LoopGeometry g = perturbed(member.geometry, p, eps);
    const VerificationSummary v = verify_from(g, member.theta);
    EXPECT_FALSE(v.verified) << tag << " parameter " << p << " + " << eps << ": worst residual " << v.worst_residual;
    const Classification c = classified({g, member.theta}, v);
    EXPECT_NE(c.family, family) << tag << " parameter " << p << " + " << eps;
    for (const FamilyCheck& check : c.checks) {
      if (check.family == family) {
        EXPECT_GT(check.residual, eps / 10) << tag << " " << eps;
      }
    }
  }
}

// A random Bennett loop (either setup, from the twists' signs) in a pose.
inline Posed random_bennett_member(std::mt19937_64& rng) {
  const double a = uniform(rng, 0.5, 2.0), alpha = twist(rng), beta = twist(rng);
  const double b = a * std::abs(std::sin(beta) / std::sin(alpha));
  const LoopGeometry g = bennett(a, alpha, b, beta);
  return {g, bennett_pose(g, uniform(rng, 0.3, kPi - 0.3))};
}

// A loop in a pose with one more joint axis put on link k (between axes k
// and k+1): a random line fixed to that link. Locked, the new joint leaves
// the loop as it was; free, it adds a joint that the motion need not turn.
inline Posed with_locked_joint(const Posed& p, int k, std::mt19937_64& rng) {
  std::vector<Axis> axes = joint_axes(p.geometry, p.theta);
  const double L = length_scale(p.geometry);
  const Vector3 point =
      axes[static_cast<size_t>(k)].point + L * Vector3(uniform(rng, -1, 1), uniform(rng, -1, 1), uniform(rng, -1, 1));
  const Vector3 direction = Vector3(uniform(rng, -1, 1), uniform(rng, -1, 1), uniform(rng, -1, 1)).normalized();
  axes.insert(axes.begin() + k + 1, Axis{point, direction});
  return dh_from_axes(axes);
}

}  // namespace loopfarm::family_tests
