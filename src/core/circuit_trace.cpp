// The tracing of a circuit (motion.hpp, trace_circuit): pseudo-arclength
// continuation with a Moore-Penrose corrector, joint extremes and
// bifurcation points solved for on the curve.
#include "circuit_trace.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <Eigen/Eigenvalues>
#include <Eigen/QR>

#include "closure_solver.hpp"
#include "halton.hpp"

namespace loopfarm {
namespace detail {
namespace {

// Probes around a singular point: their distance [rad] and number.
constexpr double kProbeDistance = 1e-3;
constexpr int kProbes = 48;
// A singular value below this fraction of the largest is zero at a located
// singular point (where the corrector's points are only as exact as the
// root-finding that placed them).
constexpr double kSingularTolerance = 1e-5;
// A tangent component or singular value below this is round-off.
constexpr double kNoise = 1e-10;
// Two probe rays, or the tangents of two branches, closer than this cosine
// are one direction: the resolution at which branches crossing at a singular
// point are told apart (about 5.7 degrees).
constexpr double kSameDirection = 0.995;
// Extremes located per joint and walk, at most: a joint the motion barely
// turns (by 1e-6 deg, say) can have a tangent component just above round-off
// whose sign flips at nearly every step, and each flip would cost a root
// search of its own (708 per joint, 40 s and more, for one zero of the
// generic 6R job). Past the cap the joint's range is read off the walk's
// points.
constexpr int kMaxExtremesPerJoint = 16;

// What the continuation needs at a closed point: the unit tangent (null
// vector of the system's Jacobian, rank n - 1), the smallest retained
// singular value and its right singular vector, and w = A v (whose sign
// change along the curve marks a bifurcation).
struct PointInfo {
  JointVector tangent;
  JointVector v;  // right singular vector of the smallest retained singular value
  SystemVector w;
  double sigma = 0.0;
  double sigma_max = 0.0;
};

PointInfo point_info(const ClosureSystem& system, const JointVector& x) {
  using Square = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxJoints, kMaxJoints>;
  SystemVector F;
  SystemMatrix A;
  system.evaluate(x, F, A);
  // The right singular vectors and values from the eigen-decomposition of
  // A^T A (ascending): cheaper than an SVD, and the squared singular values
  // resolve what is needed here (the tangent, and a smallest retained
  // singular value down to about 1e-8 of the largest).
  const Square gram = A.transpose() * A;
  const Eigen::SelfAdjointEigenSolver<Square> eigen(gram);
  PointInfo p;
  p.tangent = eigen.eigenvectors().col(0);
  p.v = eigen.eigenvectors().col(1);
  const auto& lambda = eigen.eigenvalues();
  p.sigma = std::sqrt(std::max(lambda[1], 0.0));
  p.sigma_max = std::sqrt(std::max(lambda[lambda.size() - 1], 0.0));
  p.w = A * p.v;
  return p;
}

// Orients `info` like the reference tangent and singular vector (continuity).
void orient(PointInfo& info, const JointVector& tangent, const JointVector& v) {
  if (info.tangent.dot(tangent) < 0.0) info.tangent = -info.tangent;
  if (info.v.dot(v) < 0.0) {
    info.v = -info.v;
    info.w = -info.w;
  }
}

// The angle between two unit vectors.
double angle_between(const JointVector& a, const JointVector& b) { return std::acos(std::clamp(a.dot(b), -1.0, 1.0)); }

// Brent's method for a root of f on [a, b] with f(a) f(b) <= 0, to an
// interval of `tolerance`. NaN if f is NaN anywhere it is evaluated (the
// corrector failed there): no root is then claimed.
template <class F>
double brent_root(F&& f, double a, double b, double fa, double fb, double tolerance) {
  if (fa == 0.0) return a;
  if (fb == 0.0) return b;
  double c = a, fc = fa, d = b - a, e = d;
  for (int it = 0; it < 100; ++it) {
    if ((fb > 0.0) == (fc > 0.0)) {
      c = a;
      fc = fa;
      d = e = b - a;
    }
    if (std::abs(fc) < std::abs(fb)) {
      a = b;
      b = c;
      c = a;
      fa = fb;
      fb = fc;
      fc = fa;
    }
    const double tol = 2.0 * std::numeric_limits<double>::epsilon() * std::abs(b) + 0.5 * tolerance;
    const double m = 0.5 * (c - b);
    if (std::abs(m) <= tol || fb == 0.0) return b;
    if (std::abs(e) >= tol && std::abs(fa) > std::abs(fb)) {
      // Inverse quadratic interpolation, or the secant where only two points differ.
      const double s = fb / fa;
      double p, q;
      if (a == c) {
        p = 2.0 * m * s;
        q = 1.0 - s;
      } else {
        const double qa = fa / fc, r = fb / fc;
        p = s * (2.0 * m * qa * (qa - r) - (b - a) * (r - 1.0));
        q = (qa - 1.0) * (r - 1.0) * (s - 1.0);
      }
      if (p > 0.0) q = -q;
      p = std::abs(p);
      if (2.0 * p < std::min(3.0 * m * q - std::abs(tol * q), std::abs(e * q))) {
        e = d;
        d = p / q;
      } else {
        d = m;
        e = d;
      }
    } else {
      d = m;
      e = d;
    }
    a = b;
    fa = fb;
    b += std::abs(d) > tol ? d : (m > 0.0 ? tol : -tol);
    fb = f(b);
    if (std::isnan(fb)) return std::numeric_limits<double>::quiet_NaN();
  }
  return b;
}

// A point of the curve between two accepted points (x0, t0) and (x1, t1),
// at chord parameter s in [0, |x1 - x0|]: predicted along the nearer end's
// tangent and corrected. False if the corrector fails there.
bool curve_point(const ClosureSystem& system, const JointVector& x0, const JointVector& t0, const JointVector& x1,
                 const JointVector& t1, double s, const MotionOptions& o, JointVector& y) {
  const double length = (x1 - x0).norm();
  y = s <= 0.5 * length ? JointVector(x0 + s * t0) : JointVector(x1 - (length - s) * t1);
  return correct(system, y, system.joints() - 1, 0.5 * length + 1e-9, o).converged;
}

// The singular point's branch directions: probes at kProbeDistance along
// directions spread over the null space at `xb` (singular values below
// kSingularTolerance of the largest), each corrected onto the solution set;
// the corrected probes' directions from xb, clustered. `spread` is set when
// most corrected probes have two freedoms or more themselves (a surface of
// poses: more than one freedom, not branches crossing at a singular point).
struct Probe {
  JointVector direction;
  JointVector point;
};

std::vector<Probe> probe_rays(const ClosureSystem& system, const JointVector& xb, const MotionOptions& o, int& nullity,
                              bool& spread) {
  const int n = system.joints();
  SystemVector F;
  SystemMatrix A;
  system.evaluate(xb, F, A);
  const Svd svd = decompose(A);
  nullity = n - numerical_rank(svd, kSingularTolerance);
  spread = false;
  std::vector<Probe> rays;
  if (nullity < 2) return rays;
  const auto N = svd.matrixV().rightCols(nullity);
  int surface = 0, converged = 0;
  for (int i = 0; i < kProbes; ++i) {
    // Directions: a circle in the first two null vectors, tilted by Halton
    // coordinates into the others (if any).
    Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxJoints, 1> c(nullity);
    const double phi = kTwoPi * (i + 0.5) / kProbes;
    c[0] = std::cos(phi);
    c[1] = std::sin(phi);
    for (int k = 2; k < nullity; ++k) c[k] = 2.0 * radical_inverse(kHaltonBases[static_cast<size_t>(k)], i + 1) - 1.0;
    c.normalize();
    const JointVector d = N * c;
    JointVector y = xb + kProbeDistance * d;
    if (!correct(system, y, n, 0.5 * kProbeDistance, o).converged) continue;
    const double distance = (y - xb).norm();
    if (distance < 0.25 * kProbeDistance) continue;
    const JointVector e = (y - xb) / distance;
    // On a surface of poses the probe is a regular point with as many
    // freedoms; on a branch through a singular point it has one.
    ++converged;
    SystemVector Fy;
    SystemMatrix Ay;
    system.evaluate(y, Fy, Ay);
    if (n - numerical_rank(decompose(Ay), o.rank_tolerance) >= 2) ++surface;
    const bool known =
        std::any_of(rays.begin(), rays.end(), [&](const Probe& r) { return r.direction.dot(e) > kSameDirection; });
    if (!known) rays.push_back({e, y});
  }
  spread = converged > 0 && 2 * surface > converged;
  return rays;
}

// Joints to hold so that a pose with f > 1 freedoms leaves a curve: f - 1
// passive joints, picked one at a time. Holding joint h leaves the motions
// of the null space with no h component; the pick keeps the most joints
// moving in what is left (a joint moves if the space has a component of it
// above round-off), then the input moving the most. So an idle joint pair is
// held at one of its joints rather than freezing the loop's own motion.
std::vector<int> joints_to_hold(const SystemMatrix& null_space, int input) {
  const int n = static_cast<int>(null_space.rows());
  using Basis = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxJoints, kMaxJoints>;
  Basis basis = null_space;
  std::vector<int> held;
  // The basis of the motions left when joint h is held too.
  auto without = [](const Basis& b, int h) {
    const Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxJoints, 1> r = b.row(h).transpose().normalized();
    const Eigen::HouseholderQR<Basis> qr{Basis(r)};
    const Basis q = qr.householderQ();
    return Basis(b * q.rightCols(b.cols() - 1));
  };
  while (basis.cols() > 1) {
    int best = -1, best_moving = -1;
    double best_input = -1.0;
    Basis best_basis;
    for (int h = 0; h < n; ++h) {
      if (h == input || std::find(held.begin(), held.end(), h) != held.end()) continue;
      if (basis.row(h).norm() <= kNoise) continue;  // the joint does not move: holding it removes nothing
      const Basis left = without(basis, h);
      int moving = 0;
      for (int j = 0; j < n; ++j) moving += left.row(j).norm() > 1e-6;
      const double input_motion = left.row(input).norm();
      if (moving > best_moving || (moving == best_moving && input_motion > best_input + 1e-12)) {
        best = h;
        best_moving = moving;
        best_input = input_motion;
        best_basis = left;
      }
    }
    if (best < 0) break;
    held.push_back(best);
    basis = best_basis;
  }
  std::sort(held.begin(), held.end());
  return held;
}

// One direction of a circuit from its first point.
struct Walk {
  std::vector<JointVector> points;  // after the first point
  std::vector<double> arclength;
  std::vector<JointExtreme> extremes;
  std::vector<Bifurcation> bifurcations;
  std::vector<JointVector> branch_seeds;  // points on other branches at bifurcations
  CircuitEnd end = CircuitEnd::lost;
  double worst = 0.0;
  double least_singular_ratio = 1.0;  // over the accepted points
};

// sigma / sigma_max at a point (0 where the Jacobian vanishes).
double singular_ratio(const PointInfo& p) { return p.sigma_max > 0.0 ? p.sigma / p.sigma_max : 0.0; }

// Locates the extreme of joint j between two accepted points (t_j changes sign).
void locate_extreme(const ClosureSystem& system, const JointVector& x0, const PointInfo& i0, const JointVector& x1,
                    const PointInfo& i1, int j, double arclength0, const MotionOptions& o, Walk& walk) {
  const double length = (x1 - x0).norm();
  JointVector y;
  auto f = [&](double s) {
    if (!curve_point(system, x0, i0.tangent, x1, i1.tangent, s, o, y)) return std::numeric_limits<double>::quiet_NaN();
    PointInfo p = point_info(system, y);
    orient(p, i0.tangent, i0.v);
    return p.tangent[j];
  };
  const double s = brent_root(f, 0.0, length, i0.tangent[j], i1.tangent[j], 1e-15);
  if (std::isnan(s) || !curve_point(system, x0, i0.tangent, x1, i1.tangent, s, o, y)) return;
  SystemVector F;
  SystemMatrix A;
  walk.worst = std::max(walk.worst, system.evaluate(y, F, A));
  walk.extremes.push_back({j, i0.tangent[j] > 0.0, arclength0 + s, y});
}

// Locates the bifurcation between two accepted points (w changes sign) and
// probes its branches; points on branches other than this one become seeds.
void locate_bifurcation(const ClosureSystem& system, const JointVector& x0, const PointInfo& i0, const JointVector& x1,
                        const PointInfo& i1, double arclength0, const MotionOptions& o, Walk& walk) {
  const double length = (x1 - x0).norm();
  const SystemVector e = i0.w.normalized();
  JointVector y;
  auto f = [&](double s) {
    if (!curve_point(system, x0, i0.tangent, x1, i1.tangent, s, o, y)) return std::numeric_limits<double>::quiet_NaN();
    PointInfo p = point_info(system, y);
    orient(p, i0.tangent, i0.v);
    return p.w.dot(e);
  };
  const double s = brent_root(f, 0.0, length, i0.w.dot(e), i1.w.dot(e), 1e-15);
  if (std::isnan(s) || !curve_point(system, x0, i0.tangent, x1, i1.tangent, s, o, y)) return;
  const PointInfo at = point_info(system, y);
  if (!(at.sigma <= kSingularTolerance * at.sigma_max)) return;  // singular vectors swapped: no bifurcation
  int nullity = 0;
  bool spread = false;
  const std::vector<Probe> rays = probe_rays(system, y, o, nullity, spread);
  Bifurcation b;
  b.arclength = arclength0 + s;
  b.theta = y;
  b.branches = static_cast<int>(rays.size());
  b.smallest_singular_value = at.sigma;
  walk.bifurcations.push_back(b);
  // This branch leaves y both ways along the chord x0 -> x1 (which passes
  // through y): the ray best aligned with each way is this branch, if it is
  // within 26 degrees of it; every other ray, however close to this branch,
  // is another branch and becomes a seed.
  const JointVector chord = (x1 - x0) / length;
  size_t ahead = rays.size(), behind = rays.size();
  double best_ahead = 0.9, best_behind = 0.9;
  for (size_t r = 0; r < rays.size(); ++r) {
    const double c = rays[r].direction.dot(chord);
    if (c > best_ahead) {
      best_ahead = c;
      ahead = r;
    }
    if (-c > best_behind) {
      best_behind = -c;
      behind = r;
    }
  }
  for (size_t r = 0; r < rays.size(); ++r) {
    if (r != ahead && r != behind) walk.branch_seeds.push_back(rays[r].point);
  }
}

// Follows the curve of `system` from x0 along +-t0 until it returns to x0
// (closed), cannot be followed, or has too many points.
Walk walk_curve(const ClosureSystem& system, const JointVector& x0, const PointInfo& start, double direction,
                bool closable, const MotionOptions& o, int max_points) {
  const int n = system.joints();
  Walk walk;
  JointVector x = x0;
  PointInfo info = start;
  info.tangent *= direction;
  const JointVector t0 = info.tangent;
  double s = 0.0;
  double h = o.max_step;
  int halvings = 0;
  std::array<int, kMaxJoints> located{};  // extremes located per joint
  JointVector first_tangent;              // at the walk's first point after x0
  double first_turn = 0.0;                // of the tangent over the walk's second step
  while (true) {
    if (static_cast<int>(walk.points.size()) + 1 >= max_points) {
      walk.end = CircuitEnd::too_long;
      return walk;
    }
    // Predictor along the tangent, corrector back onto the curve.
    JointVector next = x + h * info.tangent;
    const Correction c = correct(system, next, n - 1, 0.5 * h, o, &info.tangent);
    PointInfo next_info;
    bool accepted = c.converged;
    double step = 0.0;
    if (accepted) {
      next_info = point_info(system, next);
      orient(next_info, info.tangent, info.v);
      step = (next - x).norm();
      // A step that turned the tangent sharply, or moved much less or more
      // than asked, may have jumped to another branch or across a fold.
      accepted = next_info.tangent.dot(info.tangent) >= 0.9 && step >= 0.5 * h && step <= 1.5 * h;
    }
    if (!accepted) {
      h *= 0.5;
      if (++halvings > o.max_halvings) {
        walk.end = CircuitEnd::lost;
        return walk;
      }
      continue;
    }
    halvings = 0;
    walk.worst = std::max(walk.worst, c.residual);
    walk.least_singular_ratio = std::min(walk.least_singular_ratio, singular_ratio(next_info));
    if (walk.least_singular_ratio < o.stop_below_singular_ratio) {
      walk.end = CircuitEnd::singular;
      return walk;
    }

    // Back at the first point (some image of it, 2 pi apart per joint): the
    // segment x -> next passes through it in the direction the walk left it.
    // That direction is the tangent at the walk's first point after x0,
    // which must be no further from the tangent at x than this step and the
    // walk's first steps turn (its second step's turn standing for its
    // first's), give or take the branches' resolution: so a walk that comes
    // back through a first point next to a singular pose along another
    // branch crossing there does not close, but goes on along that branch.
    // (x0's own tangent is ill-determined next to a singular pose, where the
    // closure Jacobian has two small singular values.)
    bool closes = false;
    if (closable && walk.points.size() >= 2) {
      const JointVector d = wrapped_difference(x0, x);
      const JointVector segment = next - x;
      const double tau = std::clamp(d.dot(segment) / segment.squaredNorm(), 0.0, 1.0);
      const double gap = (d - tau * segment).norm();
      // The angles are computed only where the gap closes (&& stops first), not at every step.
      if (gap <= 0.05 * step + 1e-12 &&
          angle_between(info.tangent, first_tangent) <=
              angle_between(info.tangent, next_info.tangent) + first_turn + std::acos(kSameDirection)) {
        closes = true;
        next = x + d;  // exactly the first point's image
        next_info = start;
        next_info.tangent = t0;
        orient(next_info, info.tangent, info.v);
        step = d.norm();
      }
    }

    // Extremes of the joints and bifurcations between x and next.
    const int first = o.all_extremes ? 0 : o.input_joint;
    const int last = o.all_extremes ? n - 1 : o.input_joint;
    // A joint the motion does not turn has a tangent component of round-off
    // size whose sign means nothing; so has w where the Jacobian's rank is
    // below n - 1 all along.
    for (int j = first; j <= last; ++j) {
      const double a = info.tangent[j], b = next_info.tangent[j];
      if (((a > 0.0 && b < 0.0) || (a < 0.0 && b > 0.0)) && std::max(std::abs(a), std::abs(b)) > kNoise &&
          located[static_cast<size_t>(j)] < kMaxExtremesPerJoint) {
        ++located[static_cast<size_t>(j)];
        locate_extreme(system, x, info, next, next_info, j, s, o, walk);
      }
    }
    if (info.w.dot(next_info.w) < 0.0 &&
        std::max(info.w.norm(), next_info.w.norm()) > kNoise * std::max(info.sigma_max, 1.0)) {
      locate_bifurcation(system, x, info, next, next_info, s, o, walk);
    }

    s += step;
    if (walk.points.empty()) first_tangent = next_info.tangent;
    if (walk.points.size() == 1) first_turn = angle_between(first_tangent, next_info.tangent);
    walk.points.push_back(next);
    walk.arclength.push_back(s);
    if (closes) {
      walk.end = CircuitEnd::closed;
      return walk;
    }
    const size_t count = walk.arclength.size();
    const auto window = static_cast<size_t>(o.stall_points);
    if (window > 0 && count > window && s - walk.arclength[count - 1 - window] < o.max_step) {
      walk.end = CircuitEnd::stalled;
      return walk;
    }
    if (c.iterations <= 3 && next_info.tangent.dot(info.tangent) >= 0.995) h = std::min(1.5 * h, o.max_step);
    x = next;
    info = next_info;
  }
}

// Events (extremes, singular poses) of the backward and the forward walk in
// the order of the joined circuit, their arclength measured from its first
// point (the backward walk's last).
template <class Event>
void append_events(const std::vector<Event>& backward, const std::vector<Event>& forward, double back_length,
                   std::vector<Event>& out) {
  for (auto it = backward.rbegin(); it != backward.rend(); ++it) {
    out.push_back(*it);
    out.back().arclength = back_length - it->arclength;
  }
  for (const Event& e : forward) {
    out.push_back(e);
    out.back().arclength += back_length;
  }
}

// The ranges of every joint along a circuit, extremes included.
void fill_ranges(Circuit& c) {
  const int n = static_cast<int>(c.points.front().size());
  c.ranges.assign(static_cast<size_t>(n), {});
  for (int j = 0; j < n; ++j) {
    JointRange& r = c.ranges[static_cast<size_t>(j)];
    r.lo = r.hi = c.points.front()[j];
    for (const JointVector& p : c.points) {
      r.lo = std::min(r.lo, p[j]);
      r.hi = std::max(r.hi, p[j]);
    }
    for (const JointExtreme& e : c.extremes) {
      r.lo = std::min(r.lo, e.theta[j]);
      r.hi = std::max(r.hi, e.theta[j]);
    }
    if (c.closed()) r.turns = static_cast<int>(std::lround((c.points.back()[j] - c.points.front()[j]) / kTwoPi));
  }
}

}  // namespace

TracedCircuit trace(const LoopGeometry& g, JointVector x, const MotionOptions& o) {
  const int n = g.joints();
  TracedCircuit out;
  Circuit& c = out.circuit;
  const ClosureSystem free_system(g, {}, x);
  const Correction polish = correct(free_system, x, n, 0.5, o);
  if (!polish.converged) {
    c.end = CircuitEnd::lost;
    c.worst_residual = polish.residual;
    return out;
  }

  // Freedoms at x: the null space of the closure Jacobian. More than one
  // direction is either a loop with several freedoms (solutions fill the
  // null space) or a singular point where branches cross (they do not).
  SystemVector F;
  SystemMatrix A;
  free_system.evaluate(x, F, A);
  const Svd svd = decompose(A);
  const int nullity = n - numerical_rank(svd, o.rank_tolerance);
  std::vector<int> held;
  c.freedoms = nullity;
  if (nullity == 0) {
    c.end = CircuitEnd::rigid;
    c.points = {x};
    c.arclength = {0.0};
    c.worst_residual = polish.residual;
    fill_ranges(c);
    return out;
  }
  if (nullity >= 2) {
    int probe_nullity = 0;
    bool spread = false;
    const std::vector<Probe> rays = probe_rays(free_system, x, o, probe_nullity, spread);
    if (spread) {
      held = joints_to_hold(svd.matrixV().rightCols(nullity), o.input_joint);
    } else {
      // A singular point: trace from a point on its first branch (the walk
      // comes back through x), and seed the others; with no branch found,
      // from x along its last null vector.
      c.freedoms = 1;
      for (size_t r = 1; r < rays.size(); ++r) out.branch_seeds.push_back(rays[r].point);
      if (!rays.empty()) x = rays.front().point;
    }
  }
  const ClosureSystem system(g, held, x);
  c.held_joints = held;

  PointInfo start = point_info(system, x);
  // Deterministic orientation: the input angle increasing, else the first
  // joint that moves.
  double sign = 1.0;
  for (int k = 0; k < n; ++k) {
    const int j = (o.input_joint + k) % n;
    if (std::abs(start.tangent[j]) > 1e-9) {
      sign = start.tangent[j] > 0.0 ? 1.0 : -1.0;
      break;
    }
  }
  start.tangent *= sign;

  const Walk forward = walk_curve(system, x, start, 1.0, true, o, o.max_points);
  Walk backward;
  if (forward.end != CircuitEnd::closed) {
    backward = walk_curve(system, x, start, -1.0, false, o, o.max_points - static_cast<int>(forward.points.size()));
  }
  // Joined: the backward walk reversed, the start, the forward walk.
  const double back_length = backward.arclength.empty() ? 0.0 : backward.arclength.back();
  for (size_t i = backward.points.size(); i-- > 0;) {
    c.points.push_back(backward.points[i]);
    c.arclength.push_back(back_length - backward.arclength[i]);
  }
  c.points.push_back(x);
  c.arclength.push_back(back_length);
  for (size_t i = 0; i < forward.points.size(); ++i) {
    c.points.push_back(forward.points[i]);
    c.arclength.push_back(back_length + forward.arclength[i]);
  }
  c.length = c.arclength.back();
  const auto either = [&](CircuitEnd end) { return forward.end == end || backward.end == end; };
  c.end = forward.end == CircuitEnd::closed ? CircuitEnd::closed
          : either(CircuitEnd::singular)    ? CircuitEnd::singular
          : either(CircuitEnd::too_long)    ? CircuitEnd::too_long
          : either(CircuitEnd::stalled)     ? CircuitEnd::stalled
                                            : CircuitEnd::lost;
  append_events(backward.extremes, forward.extremes, back_length, c.extremes);
  append_events(backward.bifurcations, forward.bifurcations, back_length, c.bifurcations);
  for (const Walk* w : std::array<const Walk*, 2>{&backward, &forward}) {
    out.branch_seeds.insert(out.branch_seeds.end(), w->branch_seeds.begin(), w->branch_seeds.end());
  }
  c.worst_residual = std::max({polish.residual, forward.worst, backward.worst});
  c.least_singular_ratio =
      std::min({singular_ratio(start), forward.least_singular_ratio, backward.least_singular_ratio});
  fill_ranges(c);
  return out;
}

}  // namespace detail

Circuit trace_circuit(const LoopGeometry& geometry, const JointVector& pose, const MotionOptions& o) {
  o.validate();
  validate_geometry(geometry);
  if (pose.size() != geometry.joints())
    throw std::invalid_argument("trace_circuit: pose has the wrong number of angles");
  if (!pose.allFinite()) throw std::invalid_argument("trace_circuit: a pose angle is not finite");
  if (o.input_joint >= geometry.joints())
    throw std::invalid_argument("trace_circuit: input_joint beyond the loop's joints");
  const LoopGeometry g = scaled(geometry, length_scale(geometry));
  return detail::trace(g, pose, o).circuit;
}

}  // namespace loopfarm
