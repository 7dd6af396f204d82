// Loops with known motions, built by constructions that share nothing with
// the classifier's family conditions (classify.hpp): ground truth for motion
// tracers and for the classifier itself (docs/quality/ground-truth.md, "Loops built
// from their mechanism").
//
// - four-bars (planar and spherical) in closed form: every pose at an input
//   angle (law of cosines, spherical law of cosines), the range of every
//   joint on each circuit, and the kind of motion (Grashof);
// - the trihedral Bricard 6R built from its geometry: a trihedron, a point,
//   and the perpendiculars from the point to the trihedron's faces;
// - Bennett loops fused in space: the Goldberg 5R, two Bennett loops sharing
//   a link (a 6R with two degrees of freedom) and a 6R of three Bennett loops,
//   their DH parameters read off the joint axes (dh_from_axes);
// - Waldron's hybrid 6R (two Bennett loops sharing a joint axis), the
//   Sarrus 6R (two chains of parallel axes), Hooke's double-spherical 6R
//   (two chains of concurrent axes) and the angle-symmetric 6R with three
//   pairs of parallel axes, also read off their axes;
// - Bricard's plane-symmetric octahedron from its vertices, and his doubly
//   collapsible one from a flat pose: two circles and tangents to them.
//
// Angles in radians; lengths in the geometry's unit. Bad arguments throw
// std::invalid_argument naming the value.
#pragma once

#include <array>
#include <optional>
#include <span>
#include <vector>

#include "loopfarm/core/loop.hpp"

namespace loopfarm {

// ---------------------------------------------------------------------------
// Axes and poses

// A joint axis in space: a point on it and its unit direction.
struct Axis {
  Vector3 point = Vector3::Zero();
  Vector3 direction = Vector3::UnitZ();
};

// A loop with one of its assembled poses.
struct PosedLoop {
  LoopGeometry geometry;
  JointVector theta;
};

// The joint axes of a loop in a pose, in the base frame: axis k is frame k's
// z axis through frame k's origin (forward_transform(g, theta, k)).
std::vector<Axis> joint_axes(const LoopGeometry& geometry, const JointVector& theta);

// The DH parameters and joint angles of the loop whose joint axes are these
// lines, in order (4 to 8 axes, unit directions as given, so a direction
// reversed is an axis flipped): link k is the common normal from axis k to
// axis k+1, a_k >= 0 its length, alpha_k the angle from z_k to z_{k+1} about
// it; d_k and theta_k are measured along and about z_k from the incoming
// normal to the outgoing one. Intersecting axes: the normal is z_k x z_{k+1}
// (a_k = 0, alpha_k in [0, pi]). Parallel axes: the normal through the
// incoming normal's foot on axis k (d_k = 0; for axis 0, through its point).
// The pose closes the geometry by construction; what says the loop moves is
// that the same geometry comes out at every pose of a mechanism.
PosedLoop dh_from_axes(std::span<const Axis> axes);

// ---------------------------------------------------------------------------
// Four-bars in closed form
//
// Planar four-bar: every twist 0 or pi (an even number of pi), every length
// > 0; offsets are allowed when their signed sum along the common axis
// direction is zero (they slide along the axes and do not change the
// angles), otherwise the loop has no pose. Spherical four-bar: every length
// and offset 0, every twist away from 0 and pi. Any other 4R throws.

// An interval of a joint angle [rad]: lo <= hi, lo in [-pi, pi]; hi exceeds
// pi when the interval contains pi (e.g. [2.5, 3.8]). A joint that turns
// fully has full_turn set, lo = -pi and hi = pi.
struct AngleInterval {
  double lo = 0.0;
  double hi = 0.0;
  bool full_turn = false;
};

// Every closed pose of the four-bar with joint `input` (0..3) held at
// `input_angle`, in closed form: the law of cosines on the diagonal between
// the input's neighbours (planar), the spherical law of cosines (spherical).
// 0 poses outside the input's range, 1 at its ends (dead points, where the
// two assembly modes merge) and 2 inside. The two modes come in a fixed order
// (the same root first), so nearby inputs give nearby poses in the same slot
// except across a dead point.
std::vector<JointVector> four_bar_poses(const LoopGeometry& geometry, int input, double input_angle);

// The range of joint `joint` (0..3) on each circuit (connected component of
// the motion), in closed form. Two circuits when some joint can reach
// neither 0 nor pi (its sign never changes, so the motion and its mirror
// image theta -> -theta are apart: a Grashof four-bar); then circuit 0 is the
// one on which the lowest such joint is positive, and the same circuit is
// circuit 0 for every `joint`. One circuit otherwise (non-Grashof, or at a
// change point, where the two modes meet); none when the loop cannot close.
std::vector<AngleInterval> four_bar_joint_ranges(const LoopGeometry& geometry, int joint);

// The motion of a four-bar driven at joint `input`, with the link before the
// input as the ground: the input link is link `input`, the coupler link
// input+1, the output link input+2 and the output joint input+3.
enum class FourBarKind {
  crank_rocker,   // Grashof: the input turns fully, the output rocks
  rocker_crank,   // Grashof: the input rocks, the output turns fully
  double_crank,   // Grashof: both turn fully (the ground is the shortest link)
  double_rocker,  // Grashof: both rock (the coupler is the shortest link), the coupler turns fully
  triple_rocker,  // non-Grashof: no joint turns fully, one circuit
  change_point,   // Grashof equality (e.g. a parallelogram): the circuits meet at a flat pose
};

const char* to_string(FourBarKind kind);

// The kind of a planar four-bar from its lengths (Grashof's rule with s, l
// the shortest and longest and p, q the others: s + l < p + q Grashof, which
// link is the shortest deciding the kind; s + l > p + q triple rocker; equal
// to 1e-12 of the perimeter: change point).
FourBarKind planar_four_bar_kind(const LoopGeometry& geometry, int input);

// The kind of a planar or spherical four-bar from four_bar_joint_ranges:
// two circuits: which of the input and output turn fully; one circuit: a
// change point when some joint turns fully, a triple rocker otherwise.
FourBarKind four_bar_kind(const LoopGeometry& geometry, int input);

// Planar parallelogram: lengths (a, b, a, b), twists 0. At its flat poses it
// is at a change point: the parallelogram and anti-parallelogram modes meet.
LoopGeometry parallelogram_four_bar(double a, double b);

// ---------------------------------------------------------------------------
// Trihedral Bricard 6R from its geometry
//
// Three lines through a point A (the apex) span a trihedron; a point B lies
// off its faces. Joints 1, 3, 5 are the trihedron's edges u1, u3, u5; joints
// 2, 4, 6 are the perpendiculars from B to the faces (u1, u3), (u3, u5),
// (u5, u1). Every two consecutive axes are then perpendicular (an edge lies
// in the faces the perpendiculars cross), the common normals meet each axis
// in one point (the feet of B on the edges and faces), so every offset is
// zero and, with p_k = (B - A) . u_k,
//     a_1^2 - a_2^2 = p_3^2 - p_1^2, a_3^2 - a_4^2 = p_5^2 - p_3^2,
//     a_5^2 - a_6^2 = p_1^2 - p_5^2:
// the trihedral condition a1^2 + a3^2 + a5^2 = a2^2 + a4^2 + a6^2 holds for
// any trihedron and any B. The motion keeps the six lengths: p1 = p is its
// parameter (the signed distance from A to joint 1's foot along axis 1),
// p3^2 and p5^2 follow from the relations above, and in each face the angle
// between the two edges follows from the two lengths (cos = (p_i p_j +- a a')
// / (p_i^2 + a^2)). Which roots are taken is the branch.
//
// Sign patterns: flipping one axis changes the sign of the two twists at it
// (axis_flipped), so the parity of the number of -90 deg twists is all that
// a representation cannot change: the 64 patterns are two loops. In the
// construction the parity is the number of faces, mod 2, in which B's foot
// lies inside the angle between the face's two edges (or its vertical
// angle), i.e. the number of faces where the root with the minus sign is
// taken. Odd parity (e.g. Baker's alternating +90, -90, ...) moved for every
// admissible length set tried; even parity (e.g. all +90) moves for most, but
// some length sets have no real pose at all (docs/quality/ground-truth.md).
struct TrihedralBricard {
  // a1..a5 > 0; a6 = sqrt(a1^2 - a2^2 + a3^2 - a4^2 + a5^2) must be real and > 0.
  std::array<double, 5> a{1.0, 1.0, 1.0, 1.0, 1.0};
  // Bit k set: twist k (alpha_{k+1}) is -90 deg, else +90 deg; 0..63.
  unsigned sign_pattern = 0;
  // Which of the 16 branches of the pattern's parity, 0..15: bits 0 and 1
  // choose the roots in faces (u1, u3) and (u3, u5) (set: minus), the root in
  // face (u5, u1) follows from the parity; bits 2 and 3 the signs of p3, p5.
  unsigned branch = 0;
};

// The trihedral condition's a6.
double trihedral_bricard_a6(const TrihedralBricard& parameters);

// The loop, with exactly the given lengths, twists +-pi/2 of the pattern and
// zero offsets, and its pose at motion parameter p, read off the six axes of
// the construction; nothing where the branch has no real trihedron at p.
std::optional<PosedLoop> trihedral_bricard(const TrihedralBricard& parameters, double p);

// ---------------------------------------------------------------------------
// Bennett loops fused in space
//
// A Bennett loop here is (a, alpha), (b, beta), (a, alpha), (b, beta) with
// zero offsets and |sin alpha| / a = |sin beta| / b; the signs of the twists
// give its setup (sin alpha sin beta > 0: asymmetric, sample_loops.hpp's
// bennett_angles; < 0: line-symmetric). Its poses are those closed forms.

// Two Bennett loops ABCD = (a, alpha), (b, beta), (a, alpha), (b, beta) and
// AFED = (c, gamma), (b, beta), (c, gamma), (b, beta) sharing the link DA
// (axes A and D), with a = b |sin alpha / sin beta| and
// c = b |sin gamma / sin beta| (Goldberg's common ratio).
struct BennettPairParameters {
  double b = 1.0;      // the shared link DA's length, > 0
  double beta = 1.0;   // its twist, away from 0 and pi
  double alpha = 1.0;  // twist of links AB and CD, away from 0 and pi
  double gamma = 2.0;  // twist of links AF and ED, away from 0 and pi
};

// Goldberg 5R: the two loops at A's angles t (loop 1) and t + phi (loop 2),
// links AB and AF fixed to each other at the angle phi about axis A (0:
// collinear, same side; pi: collinear, opposite sides; any other value the
// bent-link variant), the shared link DA removed, so A is no joint: the 5R
// B C D E F. t is the motion parameter (loop 1's angle at A).
struct Goldberg5R {
  BennettPairParameters loops;
  double phi = 3.14159265358979323846;
};
PosedLoop goldberg_5r(const Goldberg5R& parameters, double t);
JointVector goldberg_5r_pose(const Goldberg5R& parameters, double t);

// The two loops sharing DA, the link removed and nothing fused: the 6R
// A B C D E F, each loop at its own angle at A (t1 for ABCD, t2 for AFED).
// Two degrees of freedom (t1, t2).
PosedLoop bennett_pair_6r(const BennettPairParameters& parameters, double t1, double t2);
JointVector bennett_pair_6r_pose(const BennettPairParameters& parameters, double t1, double t2);

// A 6R of three Bennett loops: the Goldberg 5R with a third Bennett loop P Q R
// S fused onto its link P Q (from 5R joint `link` = P to joint link+1 = Q).
// The third loop shares the axes P and Q and the link PQ (its a and alpha);
// its other link has twist gamma and length c = a_PQ |sin gamma / sin
// alpha_PQ| (either setup, from the signs). At P its link S -> P is fixed to
// the 5R's link arriving at P at the angle phi about P, and link PQ is
// removed, so P is no joint: the 6R's joints are the 5R's with P replaced by
// S, R (in loop order). At every t the third loop's angle at P is the 5R's
// angle at P minus phi, so it moves with the 5R: one degree of freedom.
struct ThreeBennett6R {
  Goldberg5R goldberg;
  int link = 0;        // 0..4
  double gamma = 1.0;  // away from 0 and pi
  double phi = 0.0;
};
PosedLoop three_bennett_6r(const ThreeBennett6R& parameters, double t);
JointVector three_bennett_6r_pose(const ThreeBennett6R& parameters, double t);

// ---------------------------------------------------------------------------
// Waldron's hybrid 6R
//
// Two Bennett loops A B C D = (a, alpha), (b, beta), (a, alpha), (b, beta)
// and A E F G = (c, gamma), (e, epsilon), (c, gamma), (e, epsilon), each with
// Bennett's ratio (a = b |sin alpha / sin beta|, c = e |sin gamma / sin
// epsilon|; the two ratios independent), share the joint axis A: the second
// loop is turned about A by `turn` and slid along it by `slide`. Link AB is
// fused to AE and link DA to GA, and joint A is removed, so each loop's angle
// at A is the angle between the same two fused bodies: the second loop's is
// the first's plus `phase`. The 6R is B C D G F E (two Bennett chains joined
// by the two fused bodies), one degree of freedom: t, the first loop's angle
// at A (K. J. Waldron, "Hybrid overconstrained linkages", J. Mechanisms 3
// (1968) 73-78).
struct WaldronHybrid6R {
  double b = 1.0, beta = 1.0, alpha = 2.0;      // loop 1: link BC (b, beta), link AB (a, alpha)
  double e = 1.3, epsilon = -0.8, gamma = 0.6;  // loop 2: link EF (e, epsilon), link AE (c, gamma)
  double turn = 0.7;                            // loop 2 turned about A [rad]
  double slide = 0.3;                           // and slid along A
  double phase = 0.4;                           // loop 2's angle at A minus loop 1's [rad]
};
PosedLoop waldron_hybrid_6r(const WaldronHybrid6R& parameters, double t);

// ---------------------------------------------------------------------------
// The double-Goldberg 6R
//
// Three Bennett loops on one joint axis A (K. Wohlhart, "Merging two general
// Goldberg 5R linkages to obtain a new 6R space mechanism", Mech. Mach.
// Theory 26 (1991) 659-668; cited from the surveys, not read): the Goldberg
// 5R's loops A B C D and A F E D (`goldberg`: sharing the link DA, AF = AB
// turned by phi about A) and a third loop A B X Y = (a, alpha), (epsilon's
// link), (a, alpha), (epsilon's link) sharing the first loop's link AB, its
// length e = a |sin epsilon / sin alpha| (either setup, from the signs). Its
// link Y A is fixed to the first loop's D A at the angle `psi` about A, so
// its angle at A is the first loop's minus psi. The first loop's links BC
// and CD and joint A are removed: the 6R B X Y D E F, links Y -> D (the body
// Y A D) and F -> B (the body F A B) fused. Two Goldberg 5Rs, B C D E F and
// B C D Y X, merged along the dyad B C D. One degree of freedom: t, the
// first loop's angle at A.
struct DoubleGoldberg6R {
  Goldberg5R goldberg;
  double epsilon = -0.7;  // the third loop's other twist, away from 0 and pi
  double psi = 2.0;       // the fusion of Y A to D A about A [rad]
};
PosedLoop double_goldberg_6r(const DoubleGoldberg6R& parameters, double t);

// ---------------------------------------------------------------------------
// Sarrus 6R
//
// Two planar chains of three parallel axes between a base and a top: one
// chain's axes along u, the other's along v, at an angle `gamma` to u. Each
// chain lets the top move in the plane normal to its axes, so the top
// translates along w = u x v / |u x v|, the only motion both allow: one
// degree of freedom, s, the top's travel along w. Base frame: w = x, u = z,
// v = (0, -sin gamma, cos gamma). The loop's joints, in order: 1 the base's
// v axis (through base_v), 2 the base's u axis (base_u), 3 the u chain's
// middle axis, 4 the top's u axis (top_u), 5 the top's v axis (top_v), 6 the
// v chain's middle axis. A middle axis sits where two circles meet in the
// plane normal to its chain's axes, of radius r_base about the chain's base
// axis and r_top about its top axis, on the side `elbow` picks.
struct Sarrus6R {
  double gamma = 1.2;                                     // angle between the chains' axes, away from 0 and pi
  Vector3 base_u{0.0, 0.0, 0.0}, top_u{0.3, 1.5, 0.4};    // points on the u axes at s = 0
  Vector3 base_v{-0.2, -0.4, 0.6}, top_v{0.8, 1.0, 0.9};  // points on the v axes at s = 0
  double r_base_u = 1.0, r_top_u = 1.1;                   // the u chain's links, > 0
  double r_base_v = 1.2, r_top_v = 0.9;                   // the v chain's links, > 0
  bool elbow_u = false, elbow_v = true;
};
// Nothing where a chain cannot reach (its circles do not meet) at s.
std::optional<PosedLoop> sarrus_6r(const Sarrus6R& parameters, double s);

// ---------------------------------------------------------------------------
// Hooke's double-spherical 6R
//
// Axes 1, 2, 3 pass through a centre O1 and axes 4, 5, 6 through another
// centre O2. Link 6 (axis 6 to axis 1) is the ground and carries axis 1
// through O1 and axis 6 through O2; link 3 carries axis 3 through O1 and
// axis 4 through O2. Each spherical chain (joints 1-3, joints 4-6) lets link 3
// turn against link 6 about its centre only, so the loop moves by turning
// link 3 about the line O1 O2: one degree of freedom, t, the angle it is
// turned by from the pose the directions `u` describe (t = 0). The middle
// axes follow: axis 2 through O1 at the angles to axes 1 and 3 that u2 makes
// with u1 and u3 (links 1 and 2 are rigid), on the side of the plane of axes
// 1 and 3 that u2 is on (the chain's branch, kept while the motion does not
// reach the chain's stretched or folded pose); likewise axis 5 with axes 4
// and 6. The DH parameters are read off the six axes (dh_from_axes).
struct Hooke6R {
  Vector3 o1{0.0, 0.0, 0.0}, o2{0.4, 0.3, 1.5};  // the centres, apart
  // The axes' directions at t = 0 (made unit here): 0-2 through o1, 3-5
  // through o2; u0, u1, u2 not in one plane, nor u3, u4, u5.
  std::array<Vector3, 6> u{Vector3(1.0, 0.2, 0.1),  Vector3(0.3, 1.0, -0.4), Vector3(-0.2, 0.5, 1.0),
                           Vector3(0.8, -0.6, 0.3), Vector3(0.1, 0.9, 0.6),  Vector3(-1.0, 0.1, 0.5)};
};
// Nothing where a chain cannot reach at t (the middle axis has no direction
// at its two angles).
std::optional<PosedLoop> hooke_6r(const Hooke6R& parameters, double t);

// ---------------------------------------------------------------------------
// Angle-symmetric 6R with three pairs of parallel axes
//
// Axes 1 and 2 parallel (direction u, axis 2 reached from axis 1 by e1, its
// part normal to u), axes 4 and 5 parallel (v, e4 likewise), axes 3 and 6
// parallel (axis 3 along w, axis 6 along -w, reached from axis 3 by g normal
// to w). Joints 1 and 2 turn by t and -t, so link 2 does not turn against
// link 6 but translates by (R_u(t) - I) e1; joints 4 and 5 likewise by t and
// -t; joints 3 and 6 by one angle psi(t) (axis 6's direction is -w), which
// cancels the turn of links 3-5 against links 2 and 6. The translations
// close for every t, psi(t) the angle that turns g + (R_v(t) - I) e4 into
// g - (R_u(t) - I) e1 about w, when those two vectors have the same part
// along w and the same length at every t: the four conditions
//   w . (e1 + e4) = 0,   w . (u x e1 + v x e4) = 0,
//   g . (u x e1 + v x e4) = 0,   |e1|^2 - |e4|^2 + g . (e1 + e4) = 0
// (docs/guide/families.md). Opposite joints turn by equal angles. Two kinds
// meet them:
// - general: u, e1, v, e4 free; w along (u x e1 + v x e4) x (e1 + e4), g
//   normal to w and to u x e1 + v x e4 with the length the last condition
//   asks;
// - half_turn: axes 4, 5 the half-turn about the direction h of axes 1, 2
//   (v = H u, e4 = H e1, then translated to p4), w normal to h (turned by
//   w_turn about h from h's first normal) and g = g_length w x h, any
//   length: u x e1 + v x e4 and e1 + e4 both lie along h.
// Points p1, p3, p4 on axes 1, 3 and 4 place the pairs; they enter no
// condition.
enum class ParallelPairsKind { general, half_turn };
struct AngleSymmetricParallel6R {
  ParallelPairsKind kind = ParallelPairsKind::general;
  Vector3 u{0.2, -0.3, 1.0}, e1{1.0, 0.4, 0.1};   // axes 1, 2
  Vector3 v{0.9, 0.5, -0.2}, e4{-0.3, 0.8, 0.6};  // axes 4, 5 (general)
  Vector3 h{0.3, 1.0, 0.4};                       // the half-turn's direction (half_turn)
  double w_turn = 0.7, g_length = 0.8;            // w and g (half_turn)
  Vector3 p1{0.0, 0.0, 0.0}, p3{0.6, -0.9, 0.3}, p4{-0.4, 1.1, 0.8};
};
// The loop at t = 0 is the lines as given; at t, every joint moved as above.
// Throws where the kind's lines are degenerate (e1 or e4 along its axis, u
// parallel to h, u or v parallel to w, the general kind's w or g undefined).
PosedLoop angle_symmetric_parallel_6r(const AngleSymmetricParallel6R& parameters, double t);

// ---------------------------------------------------------------------------
// Bricard's plane-symmetric octahedron (his second type) as a 6R loop
//
// The octahedron's vertices P and T (opposite) lie in the mirror plane
// z = 0; Q and R lie off it, U and S are their mirror images, so the mirror
// maps Q onto its opposite vertex U and R onto its opposite S. The loop's
// joints are the hinges PS, SQ, QT, TR, RU, UP, each axis directed from the
// first vertex to the second (the faces PQR and STU are left out): every
// a_i = 0, and the DH parameters and the pose are read off the axes in the
// pose the vertices give.
struct OctahedronPlane {
  Vector3 p{1.0, 0.2, 0.0}, t{-0.9, -0.1, 0.0};  // in the plane: their z is ignored
  Vector3 q{0.1, 1.1, 0.8}, r{0.3, -1.0, 0.6};   // off it
};
PosedLoop bricard_octahedral_plane(const OctahedronPlane& vertices);

// ---------------------------------------------------------------------------
// Bricard's doubly collapsible octahedron (his third type) as a 6R loop, in
// one of its two flat poses
//
// In the plane z = 0, two circles about the origin, of radii r1 and r2, and
// two opposite vertices P and T outside both. From P and from T the two
// tangents to the first circle meet in pairs at the opposite vertices S and
// R, and the tangents to the second circle at the opposite vertices Q and U:
// S where P's first tangent meets one of T's (its first, or its second when
// `cross_sr`), R where the other two meet; Q and U likewise (`cross_qu`).
// The loop's joints are the hinges PS, SQ, QT, TR, RU, UP as for
// bricard_octahedral_plane, every a_i = 0, and the pose is the flat one the
// vertices give (every joint angle 0 or pi). Flat poses are singular
// points of the motion: start a tracer from another pose.
struct OctahedronCollapsible {
  double r1 = 0.6, r2 = 1.1;                  // the circles' radii, positive and different
  Eigen::Vector2d p{2.0, 0.3}, t{-1.7, 1.4};  // outside both circles
  bool cross_sr = false, cross_qu = false;
};
PosedLoop bricard_octahedral_collapsible(const OctahedronCollapsible& flat);

}  // namespace loopfarm
