// Tests of the constructions with known motions (constructions.hpp) against
// independent computations: closure residuals of loop.hpp's product, brute
// force scans of the closed forms, Grashof's rule from the lengths, loop.hpp's
// representations, the rank of the closure Jacobian, and a Levenberg-Marquardt
// assembly of the rigid closure from random guesses (a generic 6R with its
// input held cannot be assembled at all).
#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/SVD>

#include "four_bar_cases.hpp"
#include "loopfarm/core/constructions.hpp"
#include "loopfarm/core/loop.hpp"
#include "loopfarm/core/motion_polynomial.hpp"
#include "loopfarm/core/sample_loops.hpp"
#include "test_support.hpp"

namespace loopfarm {
namespace {

using testing::four_bar_cases;
using testing::FourBarCase;

constexpr double kPi = 3.14159265358979323846;

double residual(const LoopGeometry& g, const JointVector& theta) {
  const Vector6 r = closure_residual(g, theta);
  return std::max(r.head<3>().cwiseAbs().maxCoeff(), r.tail<3>().cwiseAbs().maxCoeff() / length_scale(g));
}

double angle_distance(double x, double y) { return std::abs(wrap_angle(x - y)); }

double pose_distance(const JointVector& x, const JointVector& y) {
  double out = 0.0;
  for (int k = 0; k < x.size(); ++k) out = std::max(out, angle_distance(x[k], y[k]));
  return out;
}

// Whether angle x lies in the interval, widened by `margin`.
bool inside(const AngleInterval& i, double x, double margin) {
  if (i.full_turn) return true;
  const double shifted = i.lo + std::fmod(std::fmod(x - i.lo + margin, 2 * kPi) + 2 * kPi, 2 * kPi) - margin;
  return shifted >= i.lo - margin && shifted <= i.hi + margin;
}

bool inside_any(const std::vector<AngleInterval>& set, double x, double margin) {
  return std::any_of(set.begin(), set.end(), [&](const AngleInterval& i) { return inside(i, x, margin); });
}

// ---------------------------------------------------------------------------
// dh_from_axes

TEST(Constructions, DhFromAxesReadsAKnownLoopAndItsPoseOffItsAxes) {
  // The coaxial "trivial" loop of ground-truth.md, which has offsets: a = (p,
  // p, q, q), alpha = (b, b, c, c), d = (e, 0, -e, 0), closed at (t, pi, -t, pi).
  LoopGeometry g;
  g.a.resize(4);
  g.alpha.resize(4);
  g.d.resize(4);
  g.a << 1.3, 1.3, 0.7, 0.7;
  g.alpha << 0.9, 0.9, -2.1, -2.1;
  g.d << 0.4, 0.0, -0.4, 0.0;
  JointVector theta(4);
  theta << 0.8, kPi, -0.8, kPi;
  ASSERT_LT(residual(g, theta), 1e-14);
  const LoopGeometry bennett = paper_bennett_loop();
  for (const auto& [geometry, pose] : {std::pair{g, theta}, std::pair{bennett, bennett_angles(bennett, 1.1)}}) {
    const PosedLoop read = dh_from_axes(joint_axes(geometry, pose));
    for (int k = 0; k < 4; ++k) {
      EXPECT_NEAR(read.geometry.a[k], geometry.a[k], 1e-12) << k;
      EXPECT_NEAR(angle_distance(read.geometry.alpha[k], geometry.alpha[k]), 0.0, 1e-12) << k;
      EXPECT_NEAR(read.geometry.d[k], geometry.d[k], 1e-12) << k;
      EXPECT_NEAR(angle_distance(read.theta[k], pose[k]), 0.0, 1e-12) << k;
    }
  }
  // An axis reversed is the loop with that axis flipped (loop.hpp's representations).
  for (int j = 1; j < 4; ++j) {
    std::vector<Axis> axes = joint_axes(g, theta);
    axes[static_cast<size_t>(j)].direction = -axes[static_cast<size_t>(j)].direction;
    const PosedLoop read = dh_from_axes(axes);
    const LoopGeometry flipped = axis_flipped(g, j);
    const JointVector flipped_theta = axis_flipped_angles(theta, j);
    for (int k = 0; k < 4; ++k) {
      EXPECT_NEAR(angle_distance(read.geometry.alpha[k], flipped.alpha[k]), 0.0, 1e-12) << j << " " << k;
      EXPECT_NEAR(read.geometry.d[k], flipped.d[k], 1e-12) << j << " " << k;
      EXPECT_NEAR(angle_distance(read.theta[k], flipped_theta[k]), 0.0, 1e-12) << j << " " << k;
    }
  }
}

TEST(Constructions, CommonNormalFeetAreJoinedByANormalAsLinesTurnParallel) {
  // Two lines built from their common normal: feet F and F + a x, directions
  // u and u turned by `angle` about x; each line given by a point slid along
  // it by a known amount. Well apart, the feet come back to round-off; nearly
  // parallel, where along the lines they lie is ill-conditioned, but the
  // segment between them is normal to both lines to round-off and as long as
  // the lines are apart (to about eps / angle, the distance's conditioning).
  std::mt19937_64 rng(41);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  for (const double angle : {0.5, 1e-2, 1e-4, 1e-5, 3e-6, 1.5e-6}) {
    for (int trial = 0; trial < 20; ++trial) {
      const Vector3 u = Vector3(unit(rng), unit(rng), unit(rng)).normalized();
      const Vector3 x = u.cross(Vector3(unit(rng), unit(rng), unit(rng))).normalized();
      const Vector3 v = Eigen::AngleAxisd(angle, x) * u;
      const Vector3 foot = 2.0 * Vector3(unit(rng), unit(rng), unit(rng));
      const double slide_p = 2.0 * unit(rng), slide_q = 2.0 * unit(rng);
      const Vector3 p = foot + slide_p * u, q = foot + 0.7 * x + slide_q * v;
      double s = 0.0, t = 0.0;
      ASSERT_TRUE(common_normal_feet(p, u, q, v, 1e-12, s, t)) << angle;
      if (angle >= 1e-2) {
        EXPECT_NEAR(s, -slide_p, 1e-12) << angle << " " << trial;
        EXPECT_NEAR(t, -slide_q, 1e-12) << angle << " " << trial;
      }
      const Vector3 normal = (q + t * v) - (p + s * u);
      EXPECT_LT(std::abs(normal.dot(u)), 1e-14) << angle << " " << trial;
      EXPECT_LT(std::abs(normal.dot(v)), 1e-14) << angle << " " << trial;
      EXPECT_NEAR(normal.norm(), 0.7, 1e-14 / angle) << angle << " " << trial;
    }
  }
  // Parallel within the bound: nothing computed.
  double s = 5.0, t = 6.0;
  EXPECT_FALSE(common_normal_feet(Vector3::Zero(), Vector3::UnitZ(), Vector3(1, 0, 0),
                                  Eigen::AngleAxisd(1e-7, Vector3::UnitX()) * Vector3::UnitZ(), 1e-12, s, t));
  EXPECT_EQ(s, 5.0);
  EXPECT_EQ(t, 6.0);
}

TEST(Constructions, DhFromAxesClosesWithNearlyParallelAxes) {
  // Any lines are a loop's axes at a pose of it: the DH parameters read off
  // them close at the angles read with them, also where two axes are within
  // a few microradians of parallel.
  for (const double twist : {1e-3, 1e-4, 1e-5, 3e-6, 1.01e-6}) {
    const LoopGeometry g = random_loop(6, 17);
    const JointVector theta = random_angles(6, 17);
    std::vector<Axis> axes = joint_axes(g, theta);
    // Axis 4 turned towards axis 3 until `twist` apart.
    const Vector3 normal = axes[2].direction.cross(axes[3].direction).normalized();
    axes[3].direction = Eigen::AngleAxisd(twist, normal) * axes[2].direction;
    const PosedLoop read = dh_from_axes(axes);
    EXPECT_NEAR(std::abs(std::sin(read.geometry.alpha[2])), std::sin(twist), 1e-12) << twist;
    EXPECT_LT(closure_residual(read.geometry, read.theta).norm(), 1e-11) << twist;
  }
}

TEST(Constructions, DhFromAxesRefusesBadAxes) {
  const std::vector<Axis> three(3);
  EXPECT_THROW(dh_from_axes(three), std::invalid_argument);
  std::vector<Axis> four = joint_axes(paper_bennett_loop(), bennett_angles(paper_bennett_loop(), 1.0));
  four[2].direction *= 2.0;
  EXPECT_THROW(dh_from_axes(four), std::invalid_argument);
}

// ---------------------------------------------------------------------------
// Four-bars

TEST(Constructions, FourBarKindsFromRangesAgreeWithGrashofsRule) {
  for (const FourBarCase& c : four_bar_cases()) {
    EXPECT_EQ(four_bar_kind(c.g, 0), c.kind_at_input_0) << c.name << ": " << to_string(four_bar_kind(c.g, 0));
    if (!c.planar) continue;
    for (int input = 0; input < 4; ++input) {
      EXPECT_EQ(four_bar_kind(c.g, input), planar_four_bar_kind(c.g, input)) << c.name << " input " << input;
    }
  }
  // Either end: driven at the output joint, a crank-rocker is a rocker-crank
  // read backwards (input and output exchanged).
  const LoopGeometry crank_rocker = planar_four_bar(1.0, 3.0, 2.5, 3.2);
  EXPECT_EQ(planar_four_bar_kind(reversed(crank_rocker), 0), FourBarKind::rocker_crank);
}

TEST(Constructions, FourBarPosesCloseAndNumberTwoInsideTheRangeAndNoneOutside) {
  for (const FourBarCase& c : four_bar_cases()) {
    const bool change_point = c.kind_at_input_0 == FourBarKind::change_point;
    for (int input = 0; input < 4; ++input) {
      std::vector<AngleInterval> all;
      for (const AngleInterval& i : four_bar_joint_ranges(c.g, input)) all.push_back(i);
      ASSERT_FALSE(all.empty()) << c.name;
      for (int s = 0; s < 720; ++s) {
        const double x = -kPi + (s + 0.37) * kPi / 360;
        const std::vector<JointVector> poses = four_bar_poses(c.g, input, x);
        const std::string tag = c.name + " input " + std::to_string(input) + " at " + std::to_string(x);
        for (const JointVector& t : poses) {
          EXPECT_LT(residual(c.g, t), 1e-12) << tag;
          EXPECT_EQ(t[input], x) << tag;
        }
        if (inside_any(all, x, -1e-6)) {
          // At a change point the modes cross at the flat poses (one pose).
          const bool flat = change_point && std::min(angle_distance(x, 0.0), angle_distance(x, kPi)) < 1e-6;
          EXPECT_EQ(poses.size(), flat ? 1u : 2u) << tag;
        } else if (!inside_any(all, x, 1e-6)) {
          EXPECT_EQ(poses.size(), 0u) << tag;
        }
      }
      // At the ends of a rocker's range the two modes merge into one pose.
      for (const AngleInterval& i : all) {
        if (i.full_turn) continue;
        for (double end : {i.lo, i.hi}) {
          const std::vector<JointVector> at = four_bar_poses(c.g, input, wrap_angle(end));
          ASSERT_FALSE(at.empty()) << c.name << " end " << end;
          for (const JointVector& t : at) EXPECT_LT(residual(c.g, t), 1e-12) << c.name;
          if (at.size() == 2) {
            EXPECT_LT(pose_distance(at[0], at[1]), 1e-5) << c.name << " end " << end;
          }
          const double in = end == i.lo ? end + 1e-8 : end - 1e-8;
          const std::vector<JointVector> near = four_bar_poses(c.g, input, wrap_angle(in));
          ASSERT_EQ(near.size(), 2u) << c.name << " near end " << end;
          EXPECT_LT(pose_distance(near[0], near[1]), 1e-2) << c.name;
          EXPECT_GT(pose_distance(near[0], near[1]), 1e-7) << c.name;
        }
      }
    }
  }
}

TEST(Constructions, ParallelogramPosesCloseAtTheChangePoint) {
  const LoopGeometry g = parallelogram_four_bar(1.5, 2.5);
  for (double x : {0.0, kPi, 1e-9, -1e-9, kPi - 1e-9}) {
    const std::vector<JointVector> poses = four_bar_poses(g, 0, x);
    ASSERT_FALSE(poses.empty()) << x;
    for (const JointVector& t : poses) EXPECT_LT(residual(g, t), 1e-12) << x;
  }
  // Off the flat poses: the parallelogram mode, (t, pi - t, t, pi - t) as the
  // opposite links stay parallel, and the anti-parallelogram mode.
  const std::vector<JointVector> poses = four_bar_poses(g, 0, 0.7);
  ASSERT_EQ(poses.size(), 2u);
  JointVector parallelogram(4);
  parallelogram << 0.7, kPi - 0.7, 0.7, kPi - 0.7;
  EXPECT_LT(std::min(pose_distance(poses[0], parallelogram), pose_distance(poses[1], parallelogram)), 1e-12);
  EXPECT_GT(std::max(pose_distance(poses[0], parallelogram), pose_distance(poses[1], parallelogram)), 0.1);
}

// The circuits of a four-bar by brute force: joint 0 scanned on a grid, the
// poses at neighbouring grid points joined by nearest neighbour, and two
// branches merged where they meet (a dead point, where the count drops, or a
// crossing). Each circuit's range of every joint is the smallest arc
// covering its samples.
struct ScannedCircuits {
  std::vector<std::array<std::vector<double>, 4>> samples;  // per circuit, per joint
};

ScannedCircuits scan_circuits(const LoopGeometry& g, int steps) {
  struct Slot {
    JointVector pose;
    int label;
  };
  std::vector<int> parent;
  const auto find = [&](int x) {
    while (parent[static_cast<size_t>(x)] != x) {
      parent[static_cast<size_t>(x)] = parent[static_cast<size_t>(parent[static_cast<size_t>(x)])];  // halving
      x = parent[static_cast<size_t>(x)];
    }
    return x;
  };
  const auto unite = [&](int x, int y) { parent[static_cast<size_t>(find(x))] = find(y); };
  std::vector<std::vector<Slot>> grid(static_cast<size_t>(steps));
  for (int s = 0; s < steps; ++s) {
    for (const JointVector& t : four_bar_poses(g, 0, -kPi + s * 2 * kPi / steps)) {
      parent.push_back(static_cast<int>(parent.size()));
      grid[static_cast<size_t>(s)].push_back({t, static_cast<int>(parent.size()) - 1});
    }
  }
  for (int s = 0; s < steps; ++s) {
    auto& here = grid[static_cast<size_t>(s)];
    const auto& next = grid[static_cast<size_t>((s + 1) % steps)];
    if (here.size() == 2 && (next.size() != 2 || pose_distance(here[0].pose, here[1].pose) < 1e-3)) {
      unite(here[0].label, here[1].label);
    }
    if (next.size() == 2 && here.size() != 2) unite(next[0].label, next[1].label);
    for (const Slot& slot : here) {
      double best = 1e9;
      int label = -1;
      for (const Slot& other : next) {
        const double dist = pose_distance(slot.pose, other.pose);
        if (dist < best) {
          best = dist;
          label = other.label;
        }
      }
      if (label >= 0 && best < 0.2) unite(slot.label, label);
    }
  }
  std::vector<int> roots;
  ScannedCircuits out;
  for (const auto& slots : grid) {
    for (const Slot& slot : slots) {
      const int root = find(slot.label);
      auto at = std::find(roots.begin(), roots.end(), root);
      if (at == roots.end()) {
        roots.push_back(root);
        out.samples.emplace_back();
        at = roots.end() - 1;
      }
      auto& circuit = out.samples[static_cast<size_t>(at - roots.begin())];
      for (int k = 0; k < 4; ++k) circuit[static_cast<size_t>(k)].push_back(slot.pose[k]);
    }
  }
  return out;
}

// The smallest arc covering the angles: the complement of the largest gap.
AngleInterval covering_arc(std::vector<double> x, double full_gap) {
  std::sort(x.begin(), x.end());
  double gap = x.front() + 2 * kPi - x.back();
  double lo = x.front(), hi = x.back();
  for (size_t i = 1; i < x.size(); ++i) {
    if (x[i] - x[i - 1] > gap) {
      gap = x[i] - x[i - 1];
      lo = x[i];
      hi = x[i - 1] + 2 * kPi;
    }
  }
  if (gap < full_gap) return {-kPi, kPi, true};
  return {lo, hi, false};
}

TEST(Constructions, FourBarJointRangesAgreeWithABruteForceScanOfThePoses) {
  for (const FourBarCase& c : four_bar_cases()) {
    // Every joint as the input, on a 1e-4 rad grid: poses exist exactly on the
    // union of its ranges over the circuits.
    for (int joint = 0; joint < 4; ++joint) {
      const std::vector<AngleInterval> ranges = four_bar_joint_ranges(c.g, joint);
      int mismatches = 0;
      // (Off -pi itself: a kite folded there has a continuum of poses.)
      for (double x = -kPi + 0.5e-4; x < kPi; x += 1e-4) {
        const bool has = !four_bar_poses(c.g, joint, x).empty();
        if (has && !inside_any(ranges, x, 1e-4)) ++mismatches;
        if (!has && inside_any(ranges, x, -1e-4)) ++mismatches;
      }
      EXPECT_EQ(mismatches, 0) << c.name << " joint " << joint;
    }
    // The circuits: their number, and every joint's range on each, against
    // the scan along joint 0 (grid 1e-4 rad; the other joints' extremes to
    // 1e-3; near joint 0's dead points the others move fast, so a gap of up
    // to 0.2 rad still counts as a full turn).
    const ScannedCircuits scanned = scan_circuits(c.g, 62832);
    const std::vector<AngleInterval> first = four_bar_joint_ranges(c.g, 0);
    ASSERT_EQ(scanned.samples.size(), first.size()) << c.name;
    // Match the scanned circuits to the closed form's by the sign of a joint
    // that keeps its sign (two circuits), else trivially.
    std::vector<size_t> order(scanned.samples.size());
    for (size_t i = 0; i < order.size(); ++i) order[i] = i;
    if (order.size() == 2) {
      int rocker = -1;
      for (int j = 0; j < 4 && rocker < 0; ++j) {
        if (!four_bar_joint_ranges(c.g, j)[0].full_turn) rocker = j;
      }
      ASSERT_GE(rocker, 0) << c.name;
      const AngleInterval closed = four_bar_joint_ranges(c.g, rocker)[0];
      const double closed_mid = 0.5 * (closed.lo + closed.hi);
      const double scanned_value = scanned.samples[0][static_cast<size_t>(rocker)][0];
      if ((closed_mid > 0) != (std::sin(scanned_value) > 0)) std::swap(order[0], order[1]);
    }
    for (int joint = 0; joint < 4; ++joint) {
      const std::vector<AngleInterval> ranges = four_bar_joint_ranges(c.g, joint);
      for (size_t k = 0; k < ranges.size(); ++k) {
        const AngleInterval arc = covering_arc(scanned.samples[order[k]][static_cast<size_t>(joint)], 0.2);
        const std::string tag = c.name + " joint " + std::to_string(joint) + " circuit " + std::to_string(k);
        EXPECT_EQ(arc.full_turn, ranges[k].full_turn) << tag << ": scanned " << arc.lo << " " << arc.hi;
        if (arc.full_turn || ranges[k].full_turn) continue;
        EXPECT_LT(angle_distance(arc.lo, ranges[k].lo), 1e-3) << tag << ": " << arc.lo << " vs " << ranges[k].lo;
        EXPECT_LT(angle_distance(arc.hi, ranges[k].hi), 1e-3) << tag << ": " << arc.hi << " vs " << ranges[k].hi;
      }
    }
  }
}

TEST(Constructions, FourBarFunctionsRefuseBadArguments) {
  const LoopGeometry crank_rocker = planar_four_bar(1.0, 3.0, 2.5, 3.2);
  EXPECT_THROW(four_bar_poses(crank_rocker, 4, 0.0), std::invalid_argument);
  EXPECT_THROW(four_bar_poses(crank_rocker, 0, std::nan("")), std::invalid_argument);
  EXPECT_THROW(four_bar_joint_ranges(crank_rocker, -1), std::invalid_argument);
  EXPECT_THROW(four_bar_poses(paper_bennett_loop(), 0, 0.0), std::invalid_argument);  // neither kind
  EXPECT_THROW(planar_four_bar_kind(spherical_four_bar(0.3, 0.9, 0.75, 0.95), 0), std::invalid_argument);
  EXPECT_THROW(parallelogram_four_bar(-1.0, 1.0), std::invalid_argument);
  // An odd number of twists pi, or offsets that do not cancel: no pose at all.
  LoopGeometry odd = crank_rocker;
  odd.alpha[1] = kPi;
  EXPECT_TRUE(four_bar_poses(odd, 0, 0.5).empty());
  EXPECT_TRUE(four_bar_joint_ranges(odd, 0).empty());
  LoopGeometry offset = crank_rocker;
  offset.d[2] = 0.1;
  EXPECT_TRUE(four_bar_poses(offset, 0, 0.5).empty());
}

// ---------------------------------------------------------------------------
// Trihedral Bricard

// Parameters spread over an interval where the branch exists (scanned on a
// grid), or none.
std::vector<double> trihedral_parameters(const TrihedralBricard& t, int count) {
  double lo = 0.0, hi = -1.0, run_lo = 0.0;
  bool in_run = false;
  for (double p = -6.0; p <= 6.0 + 1e-9; p += 0.01) {
    const bool exists = trihedral_bricard(t, p).has_value();
    if (exists && !in_run) run_lo = p;
    if (!exists && in_run && p - 0.01 - run_lo > hi - lo) {
      lo = run_lo;
      hi = p - 0.01;
    }
    in_run = exists;
  }
  if (in_run && 6.0 - run_lo > hi - lo) {
    lo = run_lo;
    hi = 6.0;
  }
  std::vector<double> out;
  if (hi - lo < 0.2) return out;
  for (int i = 0; i < count; ++i) out.push_back(lo + 0.05 + (hi - lo - 0.1) * i / (count - 1));
  return out;
}

// The first branch (in order) of the pattern that moves over an interval of
// p, with `count` parameters spread over it.
std::vector<double> moving_branch(TrihedralBricard& t, int count) {
  std::vector<double> ps;
  for (t.branch = 0; t.branch < 16; ++t.branch) {
    ps = trihedral_parameters(t, count);
    if (!ps.empty()) return ps;
  }
  return ps;
}

TEST(Constructions, TrihedralBricardClosesAlongItsMotionInEverySignPattern) {
  // Every one of the 64 patterns, on two length sets, from the first branch
  // that moves over an interval of p: the exact DH loop (lengths as given,
  // twists +-90 deg of the pattern, no offsets) is closed by the poses read
  // off the construction at five parameters, and its joints move.
  for (const std::array<double, 5>& lengths :
       {std::array<double, 5>{1.5, 1.0, 1.2, 0.8, 1.0}, std::array<double, 5>{0.7, 1.3, 1.6, 0.9, 1.1}}) {
    for (unsigned pattern = 0; pattern < 64; ++pattern) {
      TrihedralBricard t{lengths, pattern, 0};
      const std::vector<double> ps = moving_branch(t, 5);
      const std::string tag = "pattern " + std::to_string(pattern) + " branch " + std::to_string(t.branch);
      ASSERT_EQ(ps.size(), 5u) << tag;
      const PosedLoop first = *trihedral_bricard(t, ps[0]);
      for (int k = 0; k < 6; ++k) {
        EXPECT_EQ(first.geometry.alpha[k] < 0, ((pattern >> k) & 1u) != 0) << tag;
        EXPECT_EQ(first.geometry.d[k], 0.0) << tag;
      }
      EXPECT_NEAR(first.geometry.a[5], trihedral_bricard_a6(t), 0.0) << tag;
      double moved = 0.0;
      for (double p : ps) {
        const std::optional<PosedLoop> at = trihedral_bricard(t, p);
        ASSERT_TRUE(at.has_value()) << tag << " p " << p;
        EXPECT_EQ(at->geometry.a, first.geometry.a) << tag;
        EXPECT_LT(residual(first.geometry, at->theta), 1e-10) << tag << " p " << p;
        moved = std::max(moved, pose_distance(at->theta, first.theta));
      }
      EXPECT_GT(moved, 0.1) << tag;
    }
  }
}

TEST(Constructions, TrihedralBricardMovesWithOneDegreeOfFreedom) {
  // The closure Jacobian at the construction's poses has rank 5 (a 6R whose
  // input is held is rigid unless it is special), and the assembly by
  // Levenberg-Marquardt from random guesses, which knows nothing of the
  // construction, finds poses at the construction's input angles, with the
  // construction's two points of concurrent axes.
  std::mt19937_64 rng(41);
  for (unsigned pattern : {0u, 42u, 1u}) {
    TrihedralBricard t{{1.5, 1.0, 1.2, 0.8, 1.0}, pattern, 0};
    const std::vector<double> ps = moving_branch(t, 3);
    ASSERT_EQ(ps.size(), 3u) << pattern;
    for (double p : ps) {
      const PosedLoop at = *trihedral_bricard(t, p);
      ClosureJacobians J;
      closure_jacobians(at.geometry, at.theta, J);
      const Eigen::JacobiSVD<Eigen::MatrixXd> svd(J.theta);
      EXPECT_GT(svd.singularValues()[4], 1e-4 * svd.singularValues()[0]) << pattern;
      EXPECT_LT(svd.singularValues()[5], 1e-10 * svd.singularValues()[0]) << pattern;
      JointVector theta;
      ASSERT_TRUE(testing::assemble_by_levenberg_marquardt(at.geometry, at.theta[0], rng, theta, 40))
          << pattern << " p " << p;
      // In the pose found, axes 1, 3, 5 meet in one point and so do 2, 4, 6:
      // the geometry the construction starts from.
      const std::vector<Axis> axes = joint_axes(at.geometry, theta);
      for (int k = 0; k < 6; ++k) {
        const Axis& u = axes[static_cast<size_t>(k)];
        const Axis& v = axes[static_cast<size_t>((k + 2) % 6)];
        const Vector3 normal = u.direction.cross(v.direction);
        ASSERT_GT(normal.norm(), 1e-6) << pattern;
        EXPECT_LT(std::abs((v.point - u.point).dot(normal)) / normal.norm(), 1e-9) << pattern << " axes " << k;
      }
    }
  }
}

TEST(Constructions, TrihedralBricardParityDecidesWhetherSomeLengthsMove) {
  // The 64 patterns are two loops: flips change two twists at a time, so the
  // parity of the number of -90 deg twists is kept by every representation. For
  // these lengths no branch of even parity exists, and the assembly from
  // random guesses finds no pose at any of 24 inputs in two even patterns
  // (all +90 deg, and two -90 deg), while odd patterns (one -90 deg, Baker's
  // alternating one) assemble and move.
  const std::array<double, 5> lengths{2.636, 1.143, 0.558, 1.408, 2.969};
  std::mt19937_64 rng(43);
  for (unsigned pattern : {0u, 3u, 1u, 42u}) {
    const bool odd = std::popcount(pattern) % 2 == 1;
    bool any_branch = false;
    for (unsigned branch = 0; branch < 16; ++branch) {
      const TrihedralBricard t{lengths, pattern, branch};
      for (double p = -30.0; p <= 30.0 && !any_branch; p += 0.01) any_branch = trihedral_bricard(t, p).has_value();
    }
    EXPECT_EQ(any_branch, odd) << pattern;
    const TrihedralBricard t{lengths, pattern, 0};
    LoopGeometry g;
    g.a.resize(6);
    g.alpha.resize(6);
    g.d.setZero(6);
    for (int k = 0; k < 5; ++k) g.a[k] = lengths[static_cast<size_t>(k)];
    g.a[5] = trihedral_bricard_a6(t);
    for (int k = 0; k < 6; ++k) g.alpha[k] = ((pattern >> k) & 1u) ? -kPi / 2 : kPi / 2;
    int assembled = 0;
    for (int i = 0; i < 24; ++i) {
      JointVector theta;
      if (testing::assemble_by_levenberg_marquardt(g, -kPi + (i + 0.5) * kPi / 12, rng, theta, odd ? 10 : 40))
        ++assembled;
    }
    if (odd) {
      EXPECT_GE(assembled, 12) << pattern;
    } else {
      EXPECT_EQ(assembled, 0) << pattern;
    }
  }
}

TEST(Constructions, TrihedralBricardRefusesBadParameters) {
  EXPECT_THROW(trihedral_bricard({{1, -1, 1, 1, 1}, 0, 0}, 0.0), std::invalid_argument);
  EXPECT_THROW(trihedral_bricard({{1, 1, 1, 1, 1}, 64, 0}, 0.0), std::invalid_argument);
  EXPECT_THROW(trihedral_bricard({{1, 1, 1, 1, 1}, 0, 16}, 0.0), std::invalid_argument);
  EXPECT_THROW(trihedral_bricard({{0.5, 2, 0.5, 2, 0.5}, 0, 0}, 0.0), std::invalid_argument);  // a6^2 < 0
  EXPECT_THROW(trihedral_bricard({{1, 1, 1, 1, 1}, 0, 0}, std::nan("")), std::invalid_argument);
}

// ---------------------------------------------------------------------------
// Bennett loops fused in space

// The loop built at t0 is closed by the poses at the other parameters, the
// same geometry is read off at each, and the joints move.
template <typename Build>
void expect_closes_along(Build build, const std::vector<double>& ts, const std::string& tag) {
  const PosedLoop first = build(ts.front());
  double moved = 0.0;
  for (double t : ts) {
    const PosedLoop at = build(t);
    EXPECT_LT(residual(first.geometry, at.theta), 1e-10) << tag << " t " << t;
    const int n = first.geometry.joints();
    for (int k = 0; k < n; ++k) {
      EXPECT_NEAR(at.geometry.a[k], first.geometry.a[k], 1e-10) << tag << " t " << t;
      EXPECT_NEAR(angle_distance(at.geometry.alpha[k], first.geometry.alpha[k]), 0.0, 1e-10) << tag << " t " << t;
      EXPECT_NEAR(at.geometry.d[k], first.geometry.d[k], 1e-10) << tag << " t " << t;
    }
    moved = std::max(moved, pose_distance(at.theta, first.theta));
  }
  EXPECT_GT(moved, 0.1) << tag;
}

// Both setups: sin(alpha) sin(beta) > 0 is asymmetric, < 0 line-symmetric.
const std::vector<BennettPairParameters> kPairs = {
    {1.0, 1.2, 0.7, 2.1},   // both loops asymmetric
    {1.3, -0.9, 2.4, 0.5},  // both line-symmetric
    {0.8, 1.9, -1.1, 0.6},  // one of each
};

const std::vector<double> kMotion = {0.4, 0.9, 1.5, 2.2, 2.8};

// The closure Jacobian at a built pose has rank `rank`: its singular value
// `rank` - 1 above `least` of the largest, the next one round-off (n - rank
// degrees of freedom).
void expect_closure_rank(const PosedLoop& at, int rank, double least, const std::string& tag) {
  ClosureJacobians J;
  closure_jacobians(at.geometry, at.theta, J);
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(J.theta);
  EXPECT_GT(svd.singularValues()[rank - 1], least * svd.singularValues()[0]) << tag;
  EXPECT_LT(svd.singularValues()[rank], 1e-10 * svd.singularValues()[0]) << tag;
}

// One degree of freedom of a 6R.
void expect_one_freedom(const PosedLoop& at, const std::string& tag) { expect_closure_rank(at, 5, 1e-5, tag); }

TEST(Constructions, Goldberg5RClosesAlongItsMotionInEveryFusion) {
  for (const BennettPairParameters& pair : kPairs) {
    for (double phi : {0.0, kPi, 1.1, -2.3}) {
      const Goldberg5R g{pair, phi};
      const std::string tag = "goldberg b " + std::to_string(pair.b) + " phi " + std::to_string(phi);
      expect_closes_along([&](double t) { return goldberg_5r(g, t); }, kMotion, tag);
      const PosedLoop at = goldberg_5r(g, 1.0);
      ASSERT_EQ(at.geometry.joints(), 5);
      EXPECT_EQ(goldberg_5r_pose(g, 1.0), at.theta);
      expect_closure_rank(at, 4, 1e-4, tag);  // one degree of freedom
    }
  }
}

TEST(Constructions, BennettPair6RClosesOverBothOfItsFreedoms) {
  for (const BennettPairParameters& pair : kPairs) {
    const std::string tag = "pair b " + std::to_string(pair.b);
    expect_closes_along([&](double t) { return bennett_pair_6r(pair, t, 0.8); }, kMotion, tag + " t1");
    expect_closes_along([&](double t) { return bennett_pair_6r(pair, 0.8, t); }, kMotion, tag + " t2");
    const PosedLoop at = bennett_pair_6r(pair, 1.1, -0.6);
    EXPECT_EQ(bennett_pair_6r_pose(pair, 1.1, -0.6), at.theta);
    expect_closure_rank(at, 4, 1e-4, tag);  // two degrees of freedom
  }
}

TEST(Constructions, ThreeBennett6RClosesAlongItsMotionOnEveryLinkAndFusion) {
  for (const BennettPairParameters& pair : kPairs) {
    for (int link = 0; link < 5; ++link) {
      for (double phi : {0.0, kPi, 0.7}) {
        for (double gamma : {0.9, -2.0}) {  // both setups of the third loop
          const ThreeBennett6R s{{pair, link % 2 == 0 ? kPi : 0.0}, link, gamma, phi};
          const std::string tag = "three bennett b " + std::to_string(pair.b) + " link " + std::to_string(link) +
                                  " phi " + std::to_string(phi) + " gamma " + std::to_string(gamma);
          expect_closes_along([&](double t) { return three_bennett_6r(s, t); }, kMotion, tag);
          const PosedLoop at = three_bennett_6r(s, 1.0);
          ASSERT_EQ(at.geometry.joints(), 6);
          EXPECT_EQ(three_bennett_6r_pose(s, 1.0), at.theta);
          // The 5R's links away from P are the 6R's; P's place holds the
          // third loop's links S -> R (the 5R link PQ's a, alpha, read
          // backwards) and R -> Q (c, gamma).
          const PosedLoop five = goldberg_5r(s.goldberg, 1.0);
          const auto six_index = [&](int k) { return k < link ? k : k + 1; };
          for (int k = 0; k < 5; ++k) {
            if (k == link || (k + 1) % 5 == link) continue;
            EXPECT_NEAR(at.geometry.a[six_index(k)], five.geometry.a[k], 1e-10) << tag << " link " << k;
            EXPECT_NEAR(angle_distance(at.geometry.alpha[six_index(k)], five.geometry.alpha[k]), 0.0, 1e-10) << tag;
          }
          const double a_pq = five.geometry.a[link], alpha_pq = five.geometry.alpha[link];
          EXPECT_NEAR(at.geometry.a[link], a_pq, 1e-10) << tag;
          EXPECT_NEAR(angle_distance(at.geometry.alpha[link], alpha_pq), 0.0, 1e-10) << tag;
          EXPECT_NEAR(at.geometry.a[link + 1], a_pq * std::abs(std::sin(gamma) / std::sin(alpha_pq)), 1e-10) << tag;
          EXPECT_NEAR(angle_distance(at.geometry.alpha[link + 1], gamma), 0.0, 1e-10) << tag;
          expect_one_freedom(at, tag);
        }
      }
    }
  }
}

TEST(Constructions, WaldronHybridClosesAlongItsMotion) {
  // Both loops' setups, several placements of the second loop on axis A.
  const std::vector<WaldronHybrid6R> hybrids = {
      {},
      {1.0, 1.2, 0.7, 0.8, 2.1, -1.4, 0.0, 0.0, 0.0},
      {0.7, -0.9, 2.4, 1.5, 0.5, 1.9, -2.2, -0.6, 1.3},
  };
  for (size_t i = 0; i < hybrids.size(); ++i) {
    const WaldronHybrid6R& h = hybrids[i];
    const std::string tag = "waldron " + std::to_string(i);
    expect_closes_along([&](double t) { return waldron_hybrid_6r(h, t); }, kMotion, tag);
    const PosedLoop at = waldron_hybrid_6r(h, 1.0);
    ASSERT_EQ(at.geometry.joints(), 6);
    expect_one_freedom(at, tag);
    // Its two Bennett chains keep their links: B -> C and C -> D are loop
    // 1's (b, beta) and (a, alpha), G -> F and F -> E loop 2's (c, gamma)
    // and (e, epsilon) read backwards, with no offset at C and F.
    EXPECT_NEAR(at.geometry.a[0], h.b, 1e-10) << tag;
    EXPECT_NEAR(at.geometry.a[1], h.b * std::abs(std::sin(h.alpha) / std::sin(h.beta)), 1e-10) << tag;
    EXPECT_NEAR(at.geometry.a[3], h.e * std::abs(std::sin(h.gamma) / std::sin(h.epsilon)), 1e-10) << tag;
    EXPECT_NEAR(at.geometry.a[4], h.e, 1e-10) << tag;
    EXPECT_NEAR(at.geometry.d[1], 0.0, 1e-10) << tag;
    EXPECT_NEAR(at.geometry.d[4], 0.0, 1e-10) << tag;
  }
}

// Dual quaternions against Eigen's rotations: a rotation factor t - h, h = x
// + y l, moves a line as the rotation about l by the angle phi with
// cot(phi / 2) = (t - x) / y, in the sense opposite to y l's direction
// (t - h is proportional to cos(phi/2) - sin(phi/2) l); its norm is (t -
// x)^2 + y^2; and a product of factors moves lines as the product of their
// rotations, composed in the order written (the rightmost acts first).
TEST(Constructions, RotationFactorsMoveLinesAsRotationsAboutTheirAxes) {
  std::mt19937_64 rng(17);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const auto random_axis = [&] {
    return Axis{Vector3(u(rng), u(rng), u(rng)), Vector3(u(rng), u(rng), u(rng)).normalized()};
  };
  const auto rotation = [](const RotationFactor& f, double t) {
    const double phi = 2.0 * std::atan2(f.y, t - f.x);  // cot(phi/2) = (t - x) / y
    return Eigen::Isometry3d(Eigen::Translation3d(f.axis.point) *
                             Eigen::AngleAxisd(-phi, f.axis.direction.normalized()) *
                             Eigen::Translation3d(-f.axis.point));
  };
  for (int trial = 0; trial < 20; ++trial) {
    const RotationFactor f1{random_axis(), u(rng), 0.3 + std::abs(u(rng))};
    const RotationFactor f2{random_axis(), u(rng), -0.3 - std::abs(u(rng))};
    const Axis line = random_axis();
    const double t = 3.0 * u(rng);
    DualQuaternion one;
    one.primal[0] = 1.0;
    const DualQuaternion p1 = t * one - rotation_quaternion(f1), p2 = t * one - rotation_quaternion(f2);
    // Its norm: p p* = (t - x)^2 + y^2, real, with no dual part.
    const DualQuaternion norm = p1 * conjugate(p1);
    EXPECT_NEAR(norm.primal[0], (t - f1.x) * (t - f1.x) + f1.y * f1.y, 1e-12);
    EXPECT_LT(norm.primal.tail<3>().norm() + norm.dual.norm(), 1e-12);
    const Eigen::Isometry3d r = rotation(f1, t) * rotation(f2, t);
    const Axis moved = axis_of_line(moved_line(p1 * p2, line_of(line)));
    const Vector3 direction = r.linear() * line.direction.normalized();
    EXPECT_LT((moved.direction - direction).norm(), 1e-12) << trial;
    // The same line: the moved point lies on it.
    const Vector3 gap = r * line.point - moved.point;
    EXPECT_LT((gap - gap.dot(direction) * direction).norm(), 1e-12) << trial;
    // inverse(x) x = 1.
    const DualQuaternion identity = inverse(p1) * p1;
    EXPECT_LT((identity.primal - one.primal).norm() + identity.dual.norm(), 1e-12) << trial;
  }
}

// refactor_cubic: the k's multiply back to the same cubic, their norms are
// h3's, h2's and h1's (321) or h2's, h3's and h1's (231), and a cubic with a
// real quadratic factor is refused.
TEST(Constructions, CubicMotionPolynomialsFactorAgainInEitherOrder) {
  std::mt19937_64 rng(18);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int trial = 0; trial < 20; ++trial) {
    std::array<DualQuaternion, 3> h;
    for (DualQuaternion& x : h) {
      x = rotation_quaternion(RotationFactor{Axis{Vector3(u(rng), u(rng), u(rng)), Vector3(u(rng), u(rng), u(rng))},
                                             u(rng), 0.4 + std::abs(u(rng))});
    }
    const std::array<DualQuaternion, 4> cubic = cubic_product(h[0], h[1], h[2]);
    for (const std::array<int, 3>& order : {std::array<int, 3>{2, 1, 0}, std::array<int, 3>{1, 2, 0}}) {
      const std::array<DualQuaternion, 3> k = refactor_cubic(h, order);
      const std::array<DualQuaternion, 4> again = cubic_product(k[0], k[1], k[2]);
      for (size_t i = 0; i < 4; ++i) {
        EXPECT_LT((again[i].primal - cubic[i].primal).norm() + (again[i].dual - cubic[i].dual).norm(), 1e-11) << trial;
      }
      for (size_t j = 0; j < 3; ++j) {
        const DualQuaternion& norm_of = h[static_cast<size_t>(order[j])];
        EXPECT_NEAR(k[j].primal[0], norm_of.primal[0], 1e-11) << trial;
        EXPECT_NEAR(k[j].primal.squaredNorm(), norm_of.primal.squaredNorm(), 1e-11) << trial;
        EXPECT_LT(std::abs(k[j].primal.tail<3>().dot(k[j].dual.tail<3>())) + std::abs(k[j].dual[0]), 1e-11)
            << trial << ": not a rotation factor (the Pluecker condition)";
      }
    }
  }
  // h2 turning back about h1's line: (t - h1)(t - h2) is h1's norm, a real
  // factor of the cubic, which leaves no remainder to split off a factor of
  // that norm with.
  const Axis line{Vector3(0.3, -0.2, 0.1), Vector3(0.2, 1.0, -0.4)};
  const std::array<DualQuaternion, 3> back = {
      rotation_quaternion(RotationFactor{line, 0.5, 1.0}), rotation_quaternion(RotationFactor{line, 0.5, -1.0}),
      rotation_quaternion(RotationFactor{Axis{Vector3(1.0, 0.0, 0.0), Vector3::UnitY()}, -0.4, 0.7})};
  EXPECT_THROW(refactor_cubic(back, {2, 1, 0}), std::invalid_argument);
}

// cubic_motion_6r keeps one geometry along its motion, in both orders, with
// one degree of freedom; bad arguments throw naming the value.
TEST(Constructions, CubicMotion6RClosesAlongItsMotion) {
  CubicMotion6R p;
  p.factors = {RotationFactor{Axis{Vector3(0.0, 0.0, 0.0), Vector3(0.2, 0.1, 1.0)}, 0.1, 0.8},
               RotationFactor{Axis{Vector3(1.0, 0.2, -0.3), Vector3(-0.5, 1.0, 0.3)}, -0.6, -1.1},
               RotationFactor{Axis{Vector3(0.4, 1.1, 0.5), Vector3(0.9, -0.2, 0.6)}, 0.7, 0.5}};
  for (const std::array<int, 3>& order : {std::array<int, 3>{2, 1, 0}, std::array<int, 3>{1, 2, 0}}) {
    p.order = order;
    const std::string tag =
        "order " + std::to_string(order[0] + 1) + std::to_string(order[1] + 1) + std::to_string(order[2] + 1);
    expect_closes_along([&](double t) { return cubic_motion_6r(p, t); }, {-4.0, -1.0, 0.0, 0.5, 2.0, 30.0}, tag);
    expect_one_freedom(cubic_motion_6r(p, 0.3), tag);
  }
  CubicMotion6R bad = p;
  bad.factors[1].y = 0.0;
  EXPECT_THROW(cubic_motion_6r(bad, 0.0), std::invalid_argument);
  bad = p;
  bad.order = {0, 2, 1};
  EXPECT_THROW(cubic_motion_6r(bad, 0.0), std::invalid_argument);
  bad.order = {2, 2, 0};
  EXPECT_THROW(cubic_motion_6r(bad, 0.0), std::invalid_argument);
  EXPECT_THROW(cubic_motion_6r(p, std::nan("")), std::invalid_argument);
}

TEST(Constructions, DoubleGoldberg6RClosesAlongItsMotionInEverySetupAndFusion) {
  for (const BennettPairParameters& pair : kPairs) {
    for (double phi : {0.0, kPi, 1.1}) {
      for (double psi : {kPi, 0.0, -0.8}) {
        for (double epsilon : {0.6, -2.2}) {  // both setups of the third loop
          const DoubleGoldberg6R g{{pair, phi}, epsilon, psi};
          const std::string tag = "double goldberg b " + std::to_string(pair.b) + " phi " + std::to_string(phi) +
                                  " psi " + std::to_string(psi) + " epsilon " + std::to_string(epsilon);
          expect_closes_along([&](double t) { return double_goldberg_6r(g, t); }, kMotion, tag);
          const PosedLoop at = double_goldberg_6r(g, 1.0);
          ASSERT_EQ(at.geometry.joints(), 6);
          expect_one_freedom(at, tag);
          // B -> X and X -> Y are the third loop's (e, epsilon) and (a,
          // alpha), D -> E and E -> F the second's (c, gamma) and (b, beta),
          // with no offset at X and E; the 5R's joints D, E, F keep their
          // links (goldberg_5r: its links 3 and 4).
          const double a = pair.b * std::abs(std::sin(pair.alpha) / std::sin(pair.beta));
          EXPECT_NEAR(at.geometry.a[0], a * std::abs(std::sin(epsilon) / std::sin(pair.alpha)), 1e-10) << tag;
          EXPECT_NEAR(angle_distance(at.geometry.alpha[0], epsilon), 0.0, 1e-10) << tag;
          EXPECT_NEAR(at.geometry.a[1], a, 1e-10) << tag;
          EXPECT_NEAR(angle_distance(at.geometry.alpha[1], pair.alpha), 0.0, 1e-10) << tag;
          const PosedLoop five = goldberg_5r(g.goldberg, 1.0);
          for (int k : {3, 4}) {
            EXPECT_NEAR(at.geometry.a[k], five.geometry.a[k - 1], 1e-10) << tag << " link " << k;
            EXPECT_NEAR(angle_distance(at.geometry.alpha[k], five.geometry.alpha[k - 1]), 0.0, 1e-10) << tag;
          }
          EXPECT_NEAR(at.geometry.d[1], 0.0, 1e-10) << tag;
          EXPECT_NEAR(at.geometry.d[4], 0.0, 1e-10) << tag;
        }
      }
    }
  }
}

// A construction that may not reach (it returns std::optional): it reaches
// every value of `ts`, is closed along them (expect_closes_along) and has
// one degree of freedom at `at`, the pose it returns.
template <class Build>
PosedLoop expect_reaches_and_moves_along(Build build, const std::vector<double>& ts, double at,
                                         const std::string& tag) {
  bool reaches = true;
  for (double t : ts) {
    EXPECT_TRUE(build(t).has_value()) << tag << " t " << t;
    reaches = reaches && build(t).has_value();
  }
  if (!reaches || !build(at).has_value()) return {};
  expect_closes_along([&](double t) { return *build(t); }, ts, tag);
  const PosedLoop pose = *build(at);
  expect_one_freedom(pose, tag);
  return pose;
}

TEST(Constructions, SarrusClosesAlongItsMotionAndItsTopOnlyTranslates) {
  std::vector<Sarrus6R> linkages(3);
  linkages[1].gamma = 2.3;
  linkages[1].elbow_u = true;
  linkages[2].gamma = 0.6;
  linkages[2].elbow_v = false;
  linkages[2].r_top_v = 1.4;
  const std::vector<double> travel = {-0.3, -0.15, 0.0, 0.1, 0.25};
  for (size_t i = 0; i < linkages.size(); ++i) {
    const Sarrus6R& p = linkages[i];
    const std::string tag = "sarrus " + std::to_string(i);
    const PosedLoop at = expect_reaches_and_moves_along([&](double s) { return sarrus_6r(p, s); }, travel, 0.1, tag);
    ASSERT_EQ(at.geometry.joints(), 6) << tag;
    // Two chains of parallel axes: twists 0 or pi within each chain, and
    // gamma (up to the axes' orientation) where the chains meet.
    for (int k : {1, 2, 4, 5}) EXPECT_NEAR(std::sin(at.geometry.alpha[k]), 0.0, 1e-12) << tag << " link " << k;
    for (int k : {0, 3}) EXPECT_NEAR(std::abs(std::cos(at.geometry.alpha[k])), std::abs(std::cos(p.gamma)), 1e-12);
    // The top only translates against the base: at every pose its axes
    // (joints 4 and 5) point as the base's (joints 2 and 1) do.
    for (double s : travel) {
      const PosedLoop pose = *sarrus_6r(p, s);
      const std::vector<Axis> axes = joint_axes(pose.geometry, pose.theta);
      EXPECT_NEAR(axes[3].direction.dot(axes[1].direction), 1.0, 1e-10) << tag << " s " << s;
      EXPECT_NEAR(axes[4].direction.dot(axes[0].direction), 1.0, 1e-10) << tag << " s " << s;
    }
  }
  // Out of reach: the u chain cannot stretch that far.
  EXPECT_FALSE(sarrus_6r(Sarrus6R{}, 5.0).has_value());
}

// Hooke's double-spherical 6R: the loop built at one turn is closed by the
// poses at the others and reads the same geometry; one degree of freedom;
// axes 1-3 meet in one point (a1 = a2 = d2 = 0) and axes 4-6 in another; the
// centres' distance is what links 3 and 6 hold (from the DH parameters:
// O2 - O1 = d3 z3 + a3 x4 + d4 z4 in link 3, likewise in link 6).
TEST(Constructions, HookeClosesAlongItsMotionAboutTheLineOfCentres) {
  std::vector<Hooke6R> linkages(3);
  linkages[1].o2 = {-0.7, 0.9, 0.2};
  linkages[1].u[1] = {0.9, -0.3, 0.8};
  linkages[2].o1 = {0.2, -0.1, 0.3};
  linkages[2].u[4] = {-0.5, 0.4, 0.9};
  const std::vector<double> turns = {-0.3, -0.15, 0.0, 0.1, 0.25};
  for (size_t i = 0; i < linkages.size(); ++i) {
    const Hooke6R& p = linkages[i];
    const std::string tag = "hooke " + std::to_string(i);
    const PosedLoop at = expect_reaches_and_moves_along([&](double t) { return hooke_6r(p, t); }, turns, 0.1, tag);
    ASSERT_EQ(at.geometry.joints(), 6) << tag;
    const LoopGeometry& g = at.geometry;
    for (double zero : {g.a[0], g.a[1], g.d[1], g.a[3], g.a[4], g.d[4]}) EXPECT_NEAR(zero, 0.0, 1e-12) << tag;
    const double centres = (p.o2 - p.o1).norm();
    for (int k : {2, 5}) {
      const int j = (k + 1) % 6;
      EXPECT_NEAR(g.d[k] * g.d[k] + g.a[k] * g.a[k] + g.d[j] * g.d[j] + 2 * g.d[k] * g.d[j] * std::cos(g.alpha[k]),
                  centres * centres, 1e-12)
          << tag << " link " << k + 1;
    }
  }
  // Out of reach: the default linkage is a rocker, which cannot turn link 3
  // through -2.4 rad (its reach ends near -1.92 and -2.90).
  EXPECT_FALSE(hooke_6r(Hooke6R{}, -2.4).has_value());
  Hooke6R bad;
  bad.o2 = bad.o1;
  EXPECT_THROW(hooke_6r(bad, 0.0), std::invalid_argument);
  bad = {};
  bad.u[2] = bad.u[0] + bad.u[1];  // axes 1-3 in one plane
  EXPECT_THROW(hooke_6r(bad, 0.0), std::invalid_argument);
  bad = {};
  bad.u[4] = Vector3::Zero();
  EXPECT_THROW(hooke_6r(bad, 0.0), std::invalid_argument);
  EXPECT_THROW(hooke_6r(Hooke6R{}, NAN), std::invalid_argument);
}

// The angle-symmetric 6R with three pairs of parallel axes, both kinds: the
// loop built at one t is closed by the poses at the others and reads the
// same geometry; one degree of freedom; at every t axes 1, 2 and 4, 5 are
// parallel and axes 3, 6 antiparallel, joints 1 and 4 have turned by t,
// joints 2 and 5 by -t and joints 3 and 6 by one angle. Degenerate lines and
// values that are not finite are refused.
TEST(Constructions, AngleSymmetricParallelClosesAlongItsMotionWithEqualOppositeAngles) {
  std::vector<AngleSymmetricParallel6R> linkages(4);
  linkages[1].e4 = {0.5, -0.6, 1.1};
  linkages[1].p3 = {-0.8, 0.2, 0.5};
  linkages[2].kind = ParallelPairsKind::half_turn;
  linkages[3].kind = ParallelPairsKind::half_turn;
  linkages[3].h = {-0.7, 0.2, 0.9};
  linkages[3].w_turn = -2.1;
  linkages[3].g_length = -1.3;
  const std::vector<double> ts = {-2.5, -0.8, 0.0, 0.3, 1.4, 3.0};
  for (size_t i = 0; i < linkages.size(); ++i) {
    const AngleSymmetricParallel6R& p = linkages[i];
    const std::string tag = "angle_symmetric_parallel " + std::to_string(i);
    const auto build = [&](double t) { return angle_symmetric_parallel_6r(p, t); };
    expect_closes_along(build, ts, tag);
    expect_one_freedom(build(0.7), tag);
    const PosedLoop rest = build(0.0);
    for (double t : ts) {
      const PosedLoop at = build(t);
      const std::vector<Axis> axes = joint_axes(at.geometry, at.theta);
      EXPECT_NEAR(axes[0].direction.dot(axes[1].direction), 1.0, 1e-12) << tag << " t " << t;
      EXPECT_NEAR(axes[3].direction.dot(axes[4].direction), 1.0, 1e-12) << tag << " t " << t;
      EXPECT_NEAR(axes[2].direction.dot(axes[5].direction), -1.0, 1e-12) << tag << " t " << t;
      const JointVector turned = at.theta - rest.theta;
      EXPECT_NEAR(angle_distance(turned[0], t), 0.0, 1e-10) << tag << " t " << t;
      EXPECT_NEAR(angle_distance(turned[1], -t), 0.0, 1e-10) << tag << " t " << t;
      for (int k = 0; k < 3; ++k) {
        EXPECT_NEAR(angle_distance(turned[k + 3], turned[k]), 0.0, 1e-10) << tag << " t " << t << " joint " << k + 1;
      }
    }
  }
  AngleSymmetricParallel6R bad;
  bad.e1 = bad.u;  // no step between axes 1 and 2
  EXPECT_THROW(angle_symmetric_parallel_6r(bad, 0.0), std::invalid_argument);
  bad = {};
  bad.kind = ParallelPairsKind::half_turn;
  bad.h = bad.u;  // axes 4, 5 on axes 1, 2's direction
  EXPECT_THROW(angle_symmetric_parallel_6r(bad, 0.0), std::invalid_argument);
  bad = {};
  bad.v = bad.u;
  bad.e4 = -bad.e1;  // e1 + e4 = 0: no w
  EXPECT_THROW(angle_symmetric_parallel_6r(bad, 0.0), std::invalid_argument);
  EXPECT_THROW(angle_symmetric_parallel_6r(AngleSymmetricParallel6R{}, NAN), std::invalid_argument);
}

// The construction has no unit of length: every length of a member (e1, e4,
// g_length, p1, p3, p4) and every direction multiplied by 1e-6 or 1e6 gives
// the same loop, its lengths and offsets multiplied too, its twists and
// angles the same, closed to round-off. Near degeneracy is judged against the
// member's own lengths: at length 1e6, a step e1 whose part normal to u is
// 1e-10 of it is refused, and one of 1e-6 of it is not.
TEST(Constructions, AngleSymmetricParallelIsTheSameLoopAtEveryScale) {
  std::vector<AngleSymmetricParallel6R> linkages(2);
  linkages[1].kind = ParallelPairsKind::half_turn;
  const auto scaled = [](AngleSymmetricParallel6R p, double s) {
    for (Vector3* x : {&p.u, &p.e1, &p.v, &p.e4, &p.h, &p.p1, &p.p3, &p.p4}) *x *= s;
    p.g_length *= s;
    return p;
  };
  for (size_t i = 0; i < linkages.size(); ++i) {
    for (double t : {-2.2, 0.0, 0.9}) {
      const PosedLoop one = angle_symmetric_parallel_6r(linkages[i], t);
      for (double s : {1e-6, 1e6}) {
        const std::string tag =
            "angle_symmetric_parallel " + std::to_string(i) + " t " + std::to_string(t) + " scale " + std::to_string(s);
        PosedLoop m;
        ASSERT_NO_THROW(m = angle_symmetric_parallel_6r(scaled(linkages[i], s), t)) << tag;
        EXPECT_LT(residual(m.geometry, m.theta), 1e-12) << tag;
        for (int k = 0; k < 6; ++k) {
          EXPECT_NEAR(m.geometry.a[k], s * one.geometry.a[k], 1e-9 * s) << tag << " a" << k + 1;
          EXPECT_NEAR(m.geometry.d[k], s * one.geometry.d[k], 1e-9 * s) << tag << " d" << k + 1;
          EXPECT_NEAR(angle_distance(m.geometry.alpha[k], one.geometry.alpha[k]), 0.0, 1e-9)
              << tag << " alpha" << k + 1;
          EXPECT_NEAR(angle_distance(m.theta[k], one.theta[k]), 0.0, 1e-9) << tag << " theta" << k + 1;
        }
      }
    }
  }
  AngleSymmetricParallel6R large = scaled(AngleSymmetricParallel6R{}, 1e6);
  const Vector3 normal = large.u.unitOrthogonal();
  large.e1 = large.u + 1e-10 * large.u.norm() * normal;
  EXPECT_THROW(angle_symmetric_parallel_6r(large, 0.0), std::invalid_argument);
  large.e1 = large.u + 1e-6 * large.u.norm() * normal;
  EXPECT_NO_THROW(angle_symmetric_parallel_6r(large, 0.0));
}

// A field that is not finite is refused with its name.
TEST(Constructions, AngleSymmetricParallelNamesAFieldThatIsNotFinite) {
  const auto message = [](const AngleSymmetricParallel6R& p, double t) {
    try {
      angle_symmetric_parallel_6r(p, t);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  const std::vector<std::pair<std::string, Vector3 AngleSymmetricParallel6R::*>> vectors{
      {"u", &AngleSymmetricParallel6R::u},   {"e1", &AngleSymmetricParallel6R::e1},
      {"v", &AngleSymmetricParallel6R::v},   {"e4", &AngleSymmetricParallel6R::e4},
      {"h", &AngleSymmetricParallel6R::h},   {"p1", &AngleSymmetricParallel6R::p1},
      {"p3", &AngleSymmetricParallel6R::p3}, {"p4", &AngleSymmetricParallel6R::p4}};
  for (const auto& [name, field] : vectors) {
    for (double bad : {NAN, INFINITY}) {
      AngleSymmetricParallel6R p;
      (p.*field)[1] = bad;
      EXPECT_NE(message(p, 0.3).find(": " + name + " is not finite"), std::string::npos) << name << " " << bad;
    }
  }
  for (const std::string name : {"w_turn", "g_length", "t"}) {
    AngleSymmetricParallel6R p;
    p.kind = ParallelPairsKind::half_turn;
    double t = 0.3;
    (name == "w_turn" ? p.w_turn : name == "g_length" ? p.g_length : t) = -INFINITY;
    EXPECT_NE(message(p, t).find(": " + name + " is not finite"), std::string::npos) << name;
  }
}

// Bricard's doubly collapsible octahedron, built flat: in each of the four
// ways the tangents meet, the loop closes in the pose it is built in, every
// a_i = 0 and every joint angle 0 or pi; its vertices (the frames' origins,
// where consecutive axes meet) lie in one plane, and the hinges P S, S T,
// T R, R P lie on lines that touch the circle of radius r1 about the centre
// and P Q, Q T, T U, U P on lines that touch the one of radius r2, the
// centre found from the loop alone (the point on the bisectors at P and T of
// the lines to S and R). Bad radii and vertices are refused.
TEST(Constructions, CollapsibleOctahedronIsBuiltFlatOnTangents) {
  for (int way = 0; way < 4; ++way) {
    OctahedronCollapsible o;
    o.cross_sr = (way & 1) != 0;
    o.cross_qu = (way & 2) != 0;
    const PosedLoop m = bricard_octahedral_collapsible(o);
    const std::string tag = "way " + std::to_string(way);
    EXPECT_LT(closure_residual(m.geometry, m.theta).cwiseAbs().maxCoeff(), 1e-12) << tag;
    for (int k = 0; k < 6; ++k) {
      EXPECT_LT(m.geometry.a[k], 1e-12) << tag;
      EXPECT_LT(std::abs(std::sin(m.theta[k])), 1e-12) << tag;
    }
    // V[k] is where axes k - 1 and k meet (the frame after k joints): P, S,
    // Q, T, R, U.
    std::array<Vector3, 6> V;
    for (int k = 0; k < 6; ++k) V[static_cast<size_t>(k)] = forward_transform(m.geometry, m.theta, k).translation();
    const Vector3 normal = (V[1] - V[0]).cross(V[3] - V[0]).normalized();
    for (const Vector3& x : V) EXPECT_LT(std::abs(normal.dot(x - V[0])), 1e-12) << tag;
    const auto distance_to_line = [&](const Vector3& c, const Vector3& x, const Vector3& y) {
      return (c - x).cross((y - x).normalized()).norm();
    };
    // The centre: on the line through P that halves the angle between its
    // lines to S and R, and on T's likewise (either bisector: the one that
    // puts the centre at r1 from all four lines).
    const auto bisectors = [&](size_t at, size_t u, size_t v) {
      const Vector3 a = (V[u] - V[at]).normalized(), b = (V[v] - V[at]).normalized();
      return std::array<Vector3, 2>{(a + b).normalized(), (a - b).normalized()};
    };
    bool found = false;
    for (const Vector3& bp : bisectors(0, 1, 4)) {
      for (const Vector3& bt : bisectors(3, 1, 4)) {
        // The point of P + s bp nearest to the line T + u bt (both in the plane).
        const Vector3 w = V[0] - V[3];
        const double b = bp.dot(bt), denominator = 1.0 - b * b;
        if (denominator < 1e-12) continue;
        const double s = (b * bt.dot(w) - bp.dot(w)) / denominator;
        const Vector3 c = V[0] + s * bp;
        const std::array<double, 4> first = {distance_to_line(c, V[0], V[1]), distance_to_line(c, V[1], V[3]),
                                             distance_to_line(c, V[3], V[4]), distance_to_line(c, V[4], V[0])};
        if (std::abs(first[0] - o.r1) > 1e-9) continue;
        found = true;
        for (double r : first) EXPECT_NEAR(r, o.r1, 1e-12) << tag;
        for (double r : {distance_to_line(c, V[0], V[2]), distance_to_line(c, V[2], V[3]),
                         distance_to_line(c, V[3], V[5]), distance_to_line(c, V[5], V[0])}) {
          EXPECT_NEAR(r, o.r2, 1e-12) << tag;
        }
      }
    }
    EXPECT_TRUE(found) << tag;
  }
  OctahedronCollapsible bad;
  bad.r2 = bad.r1;
  EXPECT_THROW(bricard_octahedral_collapsible(bad), std::invalid_argument);
  bad = {};
  bad.r1 = -0.5;
  EXPECT_THROW(bricard_octahedral_collapsible(bad), std::invalid_argument);
  bad = {};
  bad.p = {0.5, 0.5};  // inside the circle of radius 1.1
  EXPECT_THROW(bricard_octahedral_collapsible(bad), std::invalid_argument);
  bad = {};
  bad.t = -bad.p;  // tangents from opposite points are parallel in pairs
  EXPECT_THROW(bricard_octahedral_collapsible(bad), std::invalid_argument);
  bad = {};
  bad.t = {NAN, 1.0};
  EXPECT_THROW(bricard_octahedral_collapsible(bad), std::invalid_argument);
}

TEST(Constructions, FusedConstructionsRefuseBadParameters) {
  EXPECT_THROW(goldberg_5r({{-1.0, 1.0, 1.0, 2.0}, kPi}, 0.5), std::invalid_argument);
  EXPECT_THROW(goldberg_5r({{1.0, 0.0, 1.0, 2.0}, kPi}, 0.5), std::invalid_argument);
  EXPECT_THROW(bennett_pair_6r({1.0, 1.0, kPi, 2.0}, 0.5, 0.5), std::invalid_argument);
  EXPECT_THROW(three_bennett_6r({{{1.0, 1.0, 1.0, 2.0}, kPi}, 5, 1.0, 0.0}, 0.5), std::invalid_argument);
  EXPECT_THROW(three_bennett_6r({{{1.0, 1.0, 1.0, 2.0}, kPi}, 0, 0.0, 0.0}, 0.5), std::invalid_argument);
  WaldronHybrid6R waldron;
  waldron.epsilon = kPi;
  EXPECT_THROW(waldron_hybrid_6r(waldron, 0.5), std::invalid_argument);
  EXPECT_THROW(waldron_hybrid_6r(WaldronHybrid6R{}, NAN), std::invalid_argument);
  EXPECT_THROW(double_goldberg_6r({{{1.0, 1.0, 1.0, 2.0}, kPi}, 0.0, kPi}, 0.5), std::invalid_argument);
  EXPECT_THROW(double_goldberg_6r({{{1.0, 1.0, 1.0, 2.0}, kPi}, 1.0, NAN}, 0.5), std::invalid_argument);
  Sarrus6R sarrus;
  sarrus.gamma = 0.0;
  EXPECT_THROW(sarrus_6r(sarrus, 0.0), std::invalid_argument);
  sarrus = {};
  sarrus.r_top_v = -1.0;
  EXPECT_THROW(sarrus_6r(sarrus, 0.0), std::invalid_argument);
}

}  // namespace
}  // namespace loopfarm
