// Motion polynomials: polynomials in a real parameter t with dual-quaternion
// coefficients whose norm is real, the rational motions that revolute chains
// move along (G. Hegedus, J. Schicho, H.-P. Schroecker, "Factorization of
// rational curves in the Study quadric and revolute linkages", Mech. Mach.
// Theory 69 (2013) 142-152; docs/guide/families.md, "6R from a cubic motion
// polynomial").
//
// A dual quaternion is p + eps d (eps^2 = 0), p and d quaternions stored as
// (w, x, y, z) with Hamilton's product. The line through the point q with unit
// direction u is the pure dual quaternion u + eps (q x u); a rotation by phi
// about it is cos(phi/2) + sin(phi/2) (u + eps (q x u)), and a dual quaternion
// sigma with real norm sigma sigma* moves a line l to sigma l sigma* / |p|^2
// (sigma* conjugates both parts).
//
// A rotation factor t - h, h = x + y l with l a line, turns its joint by the
// angle phi with cot(phi/2) = (t - x) / y; its norm is (t - x)^2 + y^2. The
// product of three of them, C(t) = (t - h1)(t - h2)(t - h3), is the motion of
// the last link of the 3R chain h1 h2 h3, every joint at angle 0 at t =
// infinity. For three distinct norm factors C factors again in every order of
// them: the first and last factors of two factorisations differing there are
// two 3R chains with the same motion, a movable 6R (motion_6r).
#pragma once

#include <array>
#include <span>

#include "loopfarm/core/constructions.hpp"
#include "loopfarm/core/loop.hpp"

namespace loopfarm {

using Quaternion4 = Eigen::Vector4d;  // (w, x, y, z)

struct DualQuaternion {
  Quaternion4 primal = Quaternion4::Zero();
  Quaternion4 dual = Quaternion4::Zero();
};

Quaternion4 quaternion_product(const Quaternion4& p, const Quaternion4& q);
DualQuaternion operator*(const DualQuaternion& x, const DualQuaternion& y);
DualQuaternion operator+(const DualQuaternion& x, const DualQuaternion& y);
DualQuaternion operator-(const DualQuaternion& x, const DualQuaternion& y);
DualQuaternion operator*(double s, const DualQuaternion& x);
// Both parts conjugated.
DualQuaternion conjugate(const DualQuaternion& x);
// The inverse, for a primal part away from zero.
DualQuaternion inverse(const DualQuaternion& x);

// The line of an axis as a dual quaternion, and back (the direction made
// unit, the point the line's foot from the origin).
DualQuaternion line_of(const Axis& axis);
Axis axis_of_line(const DualQuaternion& line);

// The line l moved by sigma: sigma l sigma* / |primal(sigma)|^2.
DualQuaternion moved_line(const DualQuaternion& sigma, const DualQuaternion& line);

// A rotation factor t - h: h = x + y line(axis), y != 0.
struct RotationFactor {
  Axis axis;
  double x = 0.0;
  double y = 1.0;
};
DualQuaternion rotation_quaternion(const RotationFactor& factor);

// The right factor t - k of the monic motion polynomial `polynomial`
// (coefficients of t^0 .. t^m, m = polynomial.size() - 1 >= 1) whose norm
// is t^2 + b t + c, one of the polynomial's norm factors: k, and the
// quotient, monic of degree m - 1, in `quotient` (size m). The remainder of
// the polynomial modulo the norm is r1 t + r0 = r1 (t - k).
DualQuaternion right_factor(std::span<const DualQuaternion> polynomial, double b, double c,
                            std::span<DualQuaternion> quotient);

// The monic cubic (t - h1)(t - h2)(t - h3), coefficients of t^0 .. t^3.
std::array<DualQuaternion, 4> cubic_product(const DualQuaternion& h1, const DualQuaternion& h2,
                                            const DualQuaternion& h3);

// The other factorisation C = (t - k1)(t - k2)(t - k3) of C = (t - h1)(t -
// h2)(t - h3), the factors' norms taken in the order `order` of h's norms
// (order[j] is the index, 0..2, of the h whose norm is k_{j+1}'s): {2, 1, 0}
// is the "321" order, {1, 2, 0} the "231" one. Factors are split off from
// the right: k3 first. Throws std::invalid_argument where a remainder's
// leading coefficient cannot be inverted (the cubic has a real quadratic
// factor, as when h2 turns back about h1's line). With two equal norm
// factors the factorisation is not unique; this gives one of them.
std::array<DualQuaternion, 3> refactor_cubic(const std::array<DualQuaternion, 3>& h, const std::array<int, 3>& order);

// The 6R of a cubic motion polynomial: the chains h1 h2 h3 and k1 k2 k3
// (refactor_cubic) closed into the loop h1 h2 h3 k3 k2 k1, in the pose at
// parameter t (every joint at angle 0 in the limit t -> infinity): each axis
// moved by the factors before it in its chain, evaluated at t, and the DH
// parameters read off the six axes (dh_from_axes). The geometry is the same at
// every t: that is what makes the loop move.
struct CubicMotion6R {
  std::array<RotationFactor, 3> factors;
  std::array<int, 3> order{2, 1, 0};  // "321"; {1, 2, 0}: "231"
};
PosedLoop cubic_motion_6r(const CubicMotion6R& parameters, double t);

}  // namespace loopfarm
