// Locked joints (family_fit.hpp, locked_fit): the loop left by locking joints
// that stay frozen over the motion, and its fit to the known families.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <span>
#include <string>
#include <vector>

#include "family_fit.hpp"

namespace loopfarm::detail {
namespace {

// A fixed transform M between two frames whose z axes are joint axes P and
// Q, written as one DH link between them: M = Tz(u) Rz(p) Tx(a) Rx(alpha)
// Rz(q) Tz(v), a >= 0 the common normal, u and v where it meets P and Q.
// Parallel axes have no unique normal: the one through P's origin (u = 0).
struct LinkBetween {
  double u = 0.0, p = 0.0, a = 0.0, alpha = 0.0, q = 0.0, v = 0.0;
};

LinkBetween link_between(const Eigen::Isometry3d& M) {
  const Vector3 z = Vector3::UnitZ(), zq = M.linear().col(2), o = M.translation();
  // Closest points s z (on P) and o + t zq (on Q).
  const double b = z.dot(zq);
  double s = 0.0, t = -zq.dot(o);
  common_normal_feet(Vector3::Zero(), z, o, zq, 1e-14, s, t);
  const Vector3 foot_p = s * z, foot_q = o + t * zq;
  LinkBetween out;
  Vector3 x = foot_q - foot_p;
  out.a = x.norm();
  if (out.a > 1e-12) {
    x /= out.a;
  } else {  // intersecting axes: the normal is their cross product (or any, when they coincide)
    out.a = 0.0;
    const Vector3 n = z.cross(zq);
    x = n.norm() > 1e-12 ? Vector3(n.normalized()) : Vector3::UnitX();
  }
  out.alpha = std::atan2(z.cross(zq).dot(x), b);
  out.u = s;
  out.p = std::atan2(x.y(), x.x());
  out.v = -t;
  const Vector3 xq = M.linear().col(0);
  out.q = std::atan2(x.cross(xq).dot(zq), x.dot(xq));
  return out;
}

// A loop in a pose, with the original index of each of its joints.
struct PosedLoop {
  LoopGeometry g;
  JointVector theta;
  std::vector<int> original;
};

// The (n-1)R loop left when joint k is locked at its angle: links k-1 and k
// and the joint between them become one rigid link from axis k-1 to axis k+1
// (link_between), which moves the feet of the normals on those axes (their
// offsets and angles change). Written with joint k+1 first.
PosedLoop locked_loop(const PosedLoop& loop, int k) {
  const int n = loop.g.joints();
  const LoopGeometry w = relabelled(loop.g, k + 1);  // the locked joint last, its neighbours n - 2 and 0
  const JointVector theta = relabelled_angles(loop.theta, k + 1);
  const Eigen::Isometry3d M = Eigen::Translation3d(w.a[n - 2], 0.0, 0.0) *
                              Eigen::AngleAxisd(w.alpha[n - 2], Vector3::UnitX()) *
                              joint_transform(theta[n - 1], w.d[n - 1], w.a[n - 1], w.alpha[n - 1]);
  const LinkBetween link = link_between(M);
  PosedLoop out;
  out.g.a = w.a.head(n - 1);
  out.g.alpha = w.alpha.head(n - 1);
  out.g.d = w.d.head(n - 1);
  out.g.a[n - 2] = link.a;
  out.g.alpha[n - 2] = link.alpha;
  out.g.d[n - 2] += link.u;
  out.g.d[0] += link.v;
  out.theta = theta.head(n - 1);
  out.theta[n - 2] += link.p;
  out.theta[0] += link.q;
  for (int j = 0; j < n - 1; ++j) out.original.push_back(loop.original[static_cast<size_t>((j + k + 1) % n)]);
  return out;
}

}  // namespace

GeometricFit locked_fit(const LoopGeometry& g, const JointVector& pose, const std::vector<int>& frozen,
                        std::span<const double> travel, double tolerance, double frozen_travel, FamilyCheck& check) {
  const int n = g.joints();
  PosedLoop whole{g, pose, {}};
  for (int j = 0; j < n; ++j) whole.original.push_back(j);
  std::vector<std::vector<int>> choices;
  for (int k : frozen) choices.push_back({k});
  if (frozen.size() > 1 && n - static_cast<int>(frozen.size()) >= 4) choices.push_back(frozen);
  GeometricFit out;
  out.family = Family::degenerate;
  auto lock = [&](const std::vector<int>& locked, const JointVector& angles) {
    PosedLoop loop = whole;
    loop.theta = angles;
    for (int original : locked) {
      const auto at = std::find(loop.original.begin(), loop.original.end(), original);
      loop = locked_loop(loop, static_cast<int>(at - loop.original.begin()));
    }
    return loop;
  };
  for (const std::vector<int>& locked : choices) {
    PosedLoop loop = lock(locked, pose);
    GeometricFit fit = geometric_fit(loop.g, tolerance);
    // A joint that rocks (travel above frozen_travel) has no one angle: over
    // the motion it stays within its travel of the pose's angle, so it is
    // locked at the best angle of that window (golden-section search on the
    // locked loop's residual; the pose may sit where the joint rocks most).
    const int k = locked.front();
    const double window = travel[static_cast<size_t>(k)];
    if (locked.size() == 1 && window > frozen_travel) {
      const double golden = 0.5 * (std::sqrt(5.0) - 1.0);
      double lo = pose[k] - window, hi = pose[k] + window;
      auto residual_at = [&](double angle) {
        JointVector angles = pose;
        angles[k] = angle;
        return geometric_fit(lock(locked, angles).g, tolerance).residual;
      };
      double x1 = hi - golden * (hi - lo), x2 = lo + golden * (hi - lo);
      double f1 = residual_at(x1), f2 = residual_at(x2);
      for (int it = 0; it < 60 && hi - lo > 1e-15; ++it) {
        if (f1 <= f2) {
          hi = x2, x2 = x1, f2 = f1;
          x1 = hi - golden * (hi - lo), f1 = residual_at(x1);
        } else {
          lo = x1, x1 = x2, f1 = f2;
          x2 = lo + golden * (hi - lo), f2 = residual_at(x2);
        }
      }
      JointVector angles = pose;
      angles[k] = f1 <= f2 ? x1 : x2;
      const PosedLoop best = lock(locked, angles);
      const GeometricFit best_fit = geometric_fit(best.g, tolerance);
      if (best_fit.residual < fit.residual) {
        loop = best;
        fit = best_fit;
      }
    }
    if (!(fit.residual < out.residual)) continue;
    out.residual = fit.residual;
    std::string joints, travels;
    double most = 0.0;
    for (int k : locked) {
      joints += (joints.empty() ? "" : ", ") + std::to_string(k + 1);
      most = std::max(most, travel[static_cast<size_t>(k)]);
    }
    const std::string remaining = std::to_string(loop.g.joints()) + "R";
    char buffer[96];
    // A joint that rocks by more than frozen_travel (rocking_travel) is a
    // near-miss's: said so.
    if (most > frozen_travel) {
      std::snprintf(buffer, sizeof buffer, " nearly locked (rocks %.2g rad, above frozen_travel); ", most);
    } else {
      std::snprintf(buffer, sizeof buffer, " locked (travel %.2g rad); ", most);
    }
    out.detail =
        (locked.size() > 1 ? "joints " : "joint ") + joints + buffer + "locked " + remaining + ": " + fit.detail;
    check.conditions = {{(locked.size() > 1 ? "largest travel of joints " : "joint ") + joints + " [rad]", most},
                        {"locked " + remaining + " loop: " + to_string(fit.family) + " residual", fit.residual}};
  }
  check.residual = out.residual;
  return out;
}

}  // namespace loopfarm::detail
