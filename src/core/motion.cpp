// Motion of the rigid loop (motion.hpp): assemblies by Levenberg-Marquardt,
// circuits by pseudo-arclength continuation with a Moore-Penrose corrector,
// joint extremes and bifurcation points solved for on the curve.
#include "loopfarm/core/motion.hpp"


#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/QR>
#include <Eigen/SVD>

#include "halton.hpp"

namespace loopfarm {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kTwoPi = 2.0 * kPi;
constexpr int kMaxRows = 6 + kMaxJoints;
// A corrector stops when its step is below this [rad] (round-off reached).
constexpr double kConvergedStep = 1e-13;
constexpr int kMaxCorrectorIterations = 12;
// Probes around a singular point: their distance [rad] and number.
constexpr double kProbeDistance = 1e-3;
constexpr int kProbes = 48;
// A singular value below this fraction of the largest is zero at a located
// singular point (where the corrector's points are only as exact as the
// root-finding that placed them).
constexpr double kSingularTolerance = 1e-5;
// Poses closer than this [rad] in every joint are the same pose; a seed this
// close to a traced circuit (in every joint) lies on it.
constexpr double kSamePose = 1e-6;
constexpr double kOnCircuit = 1e-3;
// A tangent component or singular value below this is round-off.
constexpr double kNoise = 1e-10;
// Circuits traced by analyse_motion at most (bifurcation branches included).
constexpr int kMaxCircuits = 64;

using SystemMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxRows, kMaxJoints>;
using SystemVector = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxRows, 1>;
using Svd = Eigen::JacobiSVD<SystemMatrix>;

// Componentwise wrapped difference a - b, each in (-pi, pi].
JointVector wrapped_difference(const JointVector& a, const JointVector& b) {
  JointVector d = a - b;
  for (int k = 0; k < d.size(); ++k) d[k] = wrap_angle(d[k]);
  return d;
}

// The closure equations with some joints held at fixed values: 6 rows for
// (log R, p), one more per held joint (its angle minus the held value).
class ClosureSystem {
 public:
  ClosureSystem(const LoopGeometry& g, std::vector<int> held, const JointVector& held_at)
      : g_(g), held_(std::move(held)), held_at_(held_at) {}

  int joints() const { return g_.joints(); }
  int rows() const { return 6 + static_cast<int>(held_.size()); }
  const std::vector<int>& held() const { return held_; }

  // Residual F and Jacobian A at x; returns the max-norm of F.
  double evaluate(const JointVector& x, SystemVector& F, SystemMatrix& A) const {
    const int n = joints();
    ChainKinematics chain;
    compute_chain(g_, x, chain);
    F.resize(rows());
    A.setZero(rows(), n);
    F.head<6>() = chain.residual;
    for (int k = 0; k < n; ++k) A.block<6, 1>(0, k) = residual_derivative(chain, chain_index(k, ChainParameter::theta));
    for (size_t h = 0; h < held_.size(); ++h) {
      const int j = held_[h];
      F[6 + static_cast<int>(h)] = x[j] - held_at_[j];
      A(6 + static_cast<int>(h), j) = 1.0;
    }
    return F.cwiseAbs().maxCoeff();
  }

 private:
  const LoopGeometry& g_;
  std::vector<int> held_;
  JointVector held_at_;
};

Svd decompose(const SystemMatrix& A) { return Svd(A, Eigen::ComputeFullU | Eigen::ComputeFullV); }

// Numerical rank: singular values above tolerance * the largest.
int numerical_rank(const Svd& svd, double tolerance) {
  const auto& s = svd.singularValues();
  int r = 0;
  while (r < s.size() && s[r] > tolerance * std::max(s[0], 1e-300)) ++r;
  return r;
}

struct Correction {
  bool converged = false;
  int iterations = 0;
  double residual = 0.0;
};

// Moore-Penrose Newton: minimum-norm steps x -= A^+ F with the pseudo-inverse
// truncated to at most `max_rank` singular values (and to those above the
// rank tolerance), until the step reaches round-off. Each step is orthogonal
// to the null space of A, so on a curve of solutions the iterate moves
// straight back onto the curve from a predicted point. Fails if x moves more
// than `max_move` from where it started or the residual stops falling above
// the tolerance.
Correction correct(const ClosureSystem& system, JointVector& x, int max_rank, double max_move,
                   const MotionOptions& o, const JointVector* tangent = nullptr) {
  using Square = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxJoints, kMaxJoints>;
  const JointVector start = x;
  SystemVector F;
  SystemMatrix A;
  Correction c;
  c.residual = system.evaluate(x, F, A);
  for (; c.iterations < kMaxCorrectorIterations; ++c.iterations) {
    JointVector step;
    bool stepped = false;
    if (tangent) {
      // Along a curve whose tangent t is known, A^T A + t t^T is regular and
      // its solve is the minimum-norm step (orthogonal to t): the bordered
      // system of pseudo-arclength continuation, a small Cholesky instead
      // of an SVD.
      Square M = A.transpose() * A;
      M.noalias() += *tangent * tangent->transpose();
      const Eigen::LLT<Square> llt(M);
      if (llt.info() == Eigen::Success) {
        step = -llt.solve(A.transpose() * F);
        stepped = step.allFinite();
      }
    }
    if (!stepped) {
      const Svd svd = decompose(A);
      const auto& s = svd.singularValues();
      const int rank = std::min(max_rank, numerical_rank(svd, o.rank_tolerance));
      step = JointVector::Zero(x.size());
      for (int i = 0; i < rank; ++i) step -= svd.matrixV().col(i) * (svd.matrixU().col(i).dot(F) / s[i]);
    }
    const JointVector trial = x + step;
    SystemVector Ft;
    SystemMatrix At;
    const double residual = system.evaluate(trial, Ft, At);
    if (!(residual <= c.residual) && residual > 1e-15) break;  // no progress: round-off, or diverging
    x = trial;
    F = Ft;
    A = At;
    c.residual = residual;
    if ((x - start).norm() > max_move) return c;
    if (step.norm() <= kConvergedStep || residual == 0.0) {
      ++c.iterations;
      break;
    }
  }
  c.converged = c.residual <= o.residual_tolerance;
  return c;
}

// Levenberg-Marquardt on the 6 closure equations over the joints marked
// free, from x: the assembly search's solver, robust far from the solution
// (where Newton steps are too long). Returns the final max-norm residual.
double levenberg_marquardt(const LoopGeometry& g, const std::array<bool, kMaxJoints>& free, JointVector& x,
                           int max_iterations) {
  const int n = g.joints();
  using Matrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxJoints, kMaxJoints>;
  using Vector = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxJoints, 1>;
  std::array<int, kMaxJoints> columns{};
  int m = 0;
  for (int k = 0; k < n; ++k) {
    if (free[static_cast<size_t>(k)]) columns[static_cast<size_t>(m++)] = k;
  }
  ChainKinematics chain;
  compute_chain(g, x, chain);
  Vector6 r = chain.residual;
  double norm = r.squaredNorm();
  double mu = 1e-6;
  Eigen::Matrix<double, 6, Eigen::Dynamic, 0, 6, kMaxJoints> A(6, m);
  for (int it = 0; it < max_iterations && r.cwiseAbs().maxCoeff() > 1e-15; ++it) {
    for (int c = 0; c < m; ++c) {
      A.col(c) = residual_derivative(chain, chain_index(columns[static_cast<size_t>(c)], ChainParameter::theta));
    }
    const Matrix normal = A.transpose() * A;
    const Vector gradient = A.transpose() * r;
    bool improved = false;
    while (mu < 1e12) {
      Matrix damped = normal;
      damped.diagonal().array() += mu * (1.0 + normal.diagonal().array());
      const Vector step = Eigen::LDLT<Matrix>(damped).solve(-gradient);
      JointVector trial = x;
      for (int c = 0; c < m; ++c) trial[columns[static_cast<size_t>(c)]] += step[c];
      const Vector6 rt = closure_residual(g, trial);
      if (rt.squaredNorm() < norm) {
        x = trial;
        r = rt;
        norm = rt.squaredNorm();
        mu = std::max(mu / 10.0, 1e-12);
        improved = true;
        break;
      }
      mu *= 10.0;
    }
    if (!improved) break;  // a least-squares minimum: no closure here
    compute_chain(g, x, chain);
  }
  return r.cwiseAbs().maxCoeff();
}

// Halton point `index` over the joints marked free (others keep x's values).
JointVector halton_guess(const JointVector& x, const std::array<bool, kMaxJoints>& free, int index) {
  JointVector guess = x;
  int dimension = 0;
  for (int k = 0; k < x.size(); ++k) {
    if (free[static_cast<size_t>(k)]) {
      guess[k] = -kPi + kTwoPi * radical_inverse(kHaltonBases[static_cast<size_t>(dimension++)], index + 1);
    }
  }
  return guess;
}

bool same_pose(const JointVector& a, const JointVector& b, double tolerance) {
  return wrapped_difference(a, b).cwiseAbs().maxCoeff() <= tolerance;
}

// Closed poses from LM at the Halton guesses, polished by Moore-Penrose
// Newton on `system` and de-duplicated; `least` gets the smallest residual.
std::vector<JointVector> assemblies(const LoopGeometry& g, const ClosureSystem& system, const JointVector& base,
                                    const std::array<bool, kMaxJoints>& free, int guesses, const MotionOptions& o,
                                    double& least) {
  std::vector<JointVector> out;
  for (int i = 0; i < guesses; ++i) {
    JointVector x = halton_guess(base, free, i);
    const double residual = levenberg_marquardt(g, free, x, 200);
    least = std::min(least, residual);
    if (residual > std::sqrt(o.residual_tolerance)) continue;
    if (!correct(system, x, system.joints(), 0.1, o).converged) continue;
    for (int k = 0; k < x.size(); ++k) x[k] = wrap_angle(x[k]);
    if (std::none_of(out.begin(), out.end(), [&](const JointVector& p) { return same_pose(p, x, kSamePose); })) {
      out.push_back(x);
    }
  }
  return out;
}

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

// Brent's method for a root of f on [a, b] with f(a) f(b) <= 0, to an
// interval of `tolerance`.
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

std::vector<Probe> probe_rays(const ClosureSystem& system, const JointVector& xb, const MotionOptions& o,
                              int& nullity, bool& spread) {
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
    const bool known = std::any_of(rays.begin(), rays.end(), [&](const Probe& r) { return r.direction.dot(e) > 0.995; });
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
};

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
  if (!curve_point(system, x0, i0.tangent, x1, i1.tangent, s, o, y)) return;
  if (std::isnan(y[j])) return;
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
  if (!curve_point(system, x0, i0.tangent, x1, i1.tangent, s, o, y)) return;
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
  for (const Probe& r : rays) {
    if (std::abs(r.direction.dot(i0.tangent)) < 0.9) walk.branch_seeds.push_back(r.point);
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

    // Back at the first point (some image of it, 2 pi apart per joint): the
    // segment x -> next passes through it in the direction the walk left it.
    bool closes = false;
    if (closable && walk.points.size() >= 2) {
      const JointVector d = wrapped_difference(x0, x);
      const JointVector segment = next - x;
      const double tau = std::clamp(d.dot(segment) / segment.squaredNorm(), 0.0, 1.0);
      const double gap = (d - tau * segment).norm();
      if (gap <= 0.05 * step + 1e-12 && info.tangent.dot(t0) > 0.5) {
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
      if (((a > 0.0 && b < 0.0) || (a < 0.0 && b > 0.0)) && std::max(std::abs(a), std::abs(b)) > kNoise) {
        locate_extreme(system, x, info, next, next_info, j, s, o, walk);
      }
    }
    if (info.w.dot(next_info.w) < 0.0 &&
        std::max(info.w.norm(), next_info.w.norm()) > kNoise * std::max(info.sigma_max, 1.0)) {
      locate_bifurcation(system, x, info, next, next_info, s, o, walk);
    }

    s += step;
    walk.points.push_back(next);
    walk.arclength.push_back(s);
    if (closes) {
      walk.end = CircuitEnd::closed;
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

// The circuit through the closed pose x (polished), with the seeds of other
// branches met at bifurcations. `g` is scaled to L = 1.
struct TracedCircuit {
  Circuit circuit;
  std::vector<JointVector> branch_seeds;
};

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
  c.end = forward.end == CircuitEnd::closed ? CircuitEnd::closed
          : (forward.end == CircuitEnd::too_long || backward.end == CircuitEnd::too_long) ? CircuitEnd::too_long
                                                                                         : CircuitEnd::lost;
  append_events(backward.extremes, forward.extremes, back_length, c.extremes);
  append_events(backward.bifurcations, forward.bifurcations, back_length, c.bifurcations);
  for (const Walk* w : std::array<const Walk*, 2>{&backward, &forward}) {
    out.branch_seeds.insert(out.branch_seeds.end(), w->branch_seeds.begin(), w->branch_seeds.end());
  }
  c.worst_residual = std::max({polish.residual, forward.worst, backward.worst});
  fill_ranges(c);
  return out;
}

// Distance in max-norm from x (any 2 pi image) to the polyline of a circuit.
double distance_to_circuit(const JointVector& x, const Circuit& c) {
  double best = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i < c.points.size(); ++i) {
    const JointVector d = wrapped_difference(x, c.points[i]);
    if (i + 1 < c.points.size()) {
      const JointVector segment = c.points[i + 1] - c.points[i];
      const double length2 = segment.squaredNorm();
      const double tau = length2 > 0.0 ? std::clamp(d.dot(segment) / length2, 0.0, 1.0) : 0.0;
      best = std::min(best, (d - tau * segment).cwiseAbs().maxCoeff());
    } else {
      best = std::min(best, d.cwiseAbs().maxCoeff());
    }
  }
  return best;
}

// A newly traced circuit repeats a known one if its points a quarter, half
// and three quarters along lie on that one.
bool repeats(const Circuit& c, const std::vector<Circuit>& known) {
  if (c.points.empty()) return true;
  for (const Circuit& k : known) {
    if (k.points.size() < 2) continue;
    bool all = true;
    for (double fraction : {0.25, 0.5, 0.75}) {
      const size_t i = static_cast<size_t>(fraction * static_cast<double>(c.points.size() - 1));
      if (distance_to_circuit(c.points[i], k) > kOnCircuit) {
        all = false;
        break;
      }
    }
    if (all) return true;
  }
  return false;
}

}  // namespace

const char* to_string(CircuitEnd end) {
  switch (end) {
    case CircuitEnd::closed: return "closed";
    case CircuitEnd::lost: return "lost";
    case CircuitEnd::too_long: return "too_long";
    case CircuitEnd::rigid: return "rigid";
  }
  return "lost";
}

void MotionOptions::validate() const {
  auto fail = [](const std::string& what) { throw std::invalid_argument("MotionOptions: " + what); };
  if (input_joint < 0 || input_joint >= kMaxJoints) fail("input_joint out of range");
  if (!(residual_tolerance > 0.0 && residual_tolerance < 1e-3)) fail("residual_tolerance must be in (0, 1e-3)");
  if (!(max_step > 0.0 && max_step <= 0.1)) fail("max_step must be in (0, 0.1] rad");
  if (max_halvings < 1 || max_halvings > 60) fail("max_halvings must be in [1, 60]");
  if (max_points < 16) fail("max_points must be >= 16");
  if (!(rank_tolerance > 0.0 && rank_tolerance < 1e-2)) fail("rank_tolerance must be in (0, 1e-2)");
  if (scan_inputs < 0) fail("scan_inputs must be >= 0");
  if (assembly_guesses < 1) fail("assembly_guesses must be >= 1");
  if (free_guesses < 0) fail("free_guesses must be >= 0");
}

bool Circuit::moves(int input_joint, double min_travel, double residual_tolerance) const {
  if (closed() && freedoms > 0) return true;
  if (ranges.empty() || worst_residual > 1e-3 * residual_tolerance) return false;
  const JointRange& r = input_range(input_joint);
  return r.hi - r.lo >= min_travel;
}

std::vector<JointVector> find_assemblies(const LoopGeometry& geometry, double input_angle, const MotionOptions& o) {
  o.validate();
  validate_geometry(geometry);
  if (o.input_joint >= geometry.joints()) throw std::invalid_argument("find_assemblies: input_joint beyond the loop's joints");
  if (!std::isfinite(input_angle)) throw std::invalid_argument("find_assemblies: the input angle is not finite");
  const LoopGeometry g = scaled(geometry, length_scale(geometry));
  const int n = g.joints();
  JointVector base = JointVector::Zero(n);
  base[o.input_joint] = input_angle;
  std::array<bool, kMaxJoints> free{};
  for (int k = 0; k < n; ++k) free[static_cast<size_t>(k)] = k != o.input_joint;
  const ClosureSystem system(g, {o.input_joint}, base);
  double least = std::numeric_limits<double>::infinity();
  std::vector<JointVector> poses = assemblies(g, system, base, free, o.assembly_guesses, o, least);
  for (JointVector& p : poses) p[o.input_joint] = input_angle;
  return poses;
}

Circuit trace_circuit(const LoopGeometry& geometry, const JointVector& pose, const MotionOptions& o) {
  o.validate();
  validate_geometry(geometry);
  if (pose.size() != geometry.joints()) throw std::invalid_argument("trace_circuit: pose has the wrong number of angles");
  if (!pose.allFinite()) throw std::invalid_argument("trace_circuit: a pose angle is not finite");
  if (o.input_joint >= geometry.joints()) throw std::invalid_argument("trace_circuit: input_joint beyond the loop's joints");
  const LoopGeometry g = scaled(geometry, length_scale(geometry));
  return trace(g, pose, o).circuit;
}

bool pose_at_input(const LoopGeometry& geometry, const Circuit& circuit, double angle, JointVector& pose,
                   const MotionOptions& o) {
  o.validate();
  validate_geometry(geometry);
  if (!std::isfinite(angle)) throw std::invalid_argument("pose_at_input: the angle is not finite");
  const int input = o.input_joint;
  if (input >= geometry.joints()) throw std::invalid_argument("pose_at_input: input_joint beyond the loop's joints");
  const LoopGeometry g = scaled(geometry, length_scale(geometry));
  for (size_t i = 0; i + 1 < circuit.points.size(); ++i) {
    const JointVector& p = circuit.points[i];
    const JointVector& q = circuit.points[i + 1];
    const double lo = std::min(p[input], q[input]), hi = std::max(p[input], q[input]);
    const double target = angle + kTwoPi * std::ceil((lo - angle) / kTwoPi);
    if (target > hi || hi == lo) continue;
    JointVector x = p + (target - p[input]) / (q[input] - p[input]) * (q - p);
    x[input] = target;
    std::vector<int> held = circuit.held_joints;
    held.push_back(input);
    const ClosureSystem system(g, held, x);
    if (!correct(system, x, g.joints(), 0.1, o).converged) continue;
    pose = x;
    return true;
  }
  return false;
}

double cycle_window(const JointRange& r, double theta0) {
  if (r.crank()) return kTwoPi;
  const double middle = 0.5 * (r.lo + r.hi);
  const double image = middle + std::remainder(theta0 - middle, kTwoPi);
  if (!(image > r.lo && image < r.hi)) return 0.0;
  return 1.8 * std::min(image - r.lo, r.hi - image);
}

std::optional<MotionStart> motion_start(const LoopGeometry& geometry, double theta0, const JointVector* near,
                                        double min_travel, const MotionOptions& o) {
  o.validate();
  validate_geometry(geometry);
  const int n = geometry.joints();
  const int input = o.input_joint;
  if (input >= n) throw std::invalid_argument("motion_start: input_joint beyond the loop's joints");
  if (!std::isfinite(theta0)) throw std::invalid_argument("motion_start: theta0 is not finite");
  if (near && near->size() != n) throw std::invalid_argument("motion_start: the pose has the wrong number of angles");
  if (near && !near->allFinite()) throw std::invalid_argument("motion_start: a pose angle is not finite");
  const LoopGeometry g = scaled(geometry, length_scale(geometry));
  JointVector base = JointVector::Zero(n);
  base[input] = theta0;
  const ClosureSystem system(g, {input}, base);

  // The circuit through a closed pose x at theta0, if it moves and leaves a
  // window there.
  auto start_at = [&](const JointVector& x) -> std::optional<MotionStart> {
    Circuit c = trace(g, x, o).circuit;
    if (!c.moves(input, min_travel, o.residual_tolerance)) return std::nullopt;
    const double range = cycle_window(c.input_range(input), theta0);
    if (!(range > 0.0)) return std::nullopt;
    MotionStart s{x, std::move(c), range};
    s.pose[input] = theta0;
    return s;
  };

  JointVector polished;
  if (near) {
    polished = *near;
    polished[input] = theta0;
    if (correct(system, polished, n, 0.1, o).converged) {
      if (std::optional<MotionStart> s = start_at(polished)) return s;
    } else {
      polished.resize(0);
    }
  }
  std::array<bool, kMaxJoints> free{};
  for (int k = 0; k < n; ++k) free[static_cast<size_t>(k)] = k != input;
  double least = std::numeric_limits<double>::infinity();
  std::vector<JointVector> poses = assemblies(g, system, base, free, o.assembly_guesses, o, least);
  if (near) {
    const JointVector& reference = *near;
    std::stable_sort(poses.begin(), poses.end(), [&](const JointVector& p, const JointVector& q) {
      return wrapped_difference(p, reference).norm() < wrapped_difference(q, reference).norm();
    });
  }
  for (const JointVector& x : poses) {
    if (polished.size() == n && same_pose(x, polished, kSamePose)) continue;  // tried above
    if (std::optional<MotionStart> s = start_at(x)) return s;
  }
  return std::nullopt;
}

MotionAnalysis analyse_motion(const LoopGeometry& geometry, const JointVector* pose, const MotionOptions& o) {
  o.validate();
  validate_geometry(geometry);
  const int n = geometry.joints();
  if (o.input_joint >= n) throw std::invalid_argument("analyse_motion: input_joint beyond the loop's joints");
  if (pose && pose->size() != n) throw std::invalid_argument("analyse_motion: pose has the wrong number of angles");
  if (pose && !pose->allFinite()) throw std::invalid_argument("analyse_motion: a pose angle is not finite");
  const LoopGeometry g = scaled(geometry, length_scale(geometry));
  MotionAnalysis out;
  out.input_joint = o.input_joint;
  out.least_residual = std::numeric_limits<double>::infinity();

  // Seeds: closed poses to trace from, in order; `forced` ones (branches at
  // a bifurcation, close to a known circuit by construction) are traced
  // even when near one, and dropped afterwards if they repeat it.
  struct Seed {
    JointVector x;
    bool forced = false;
  };
  std::vector<Seed> seeds;
  auto take = [&](const Seed& seed, bool given) {
    if (static_cast<int>(out.circuits.size()) >= kMaxCircuits) return;
    if (!seed.forced) {
      for (const Circuit& c : out.circuits) {
        if (c.points.size() >= 2 && distance_to_circuit(seed.x, c) <= kOnCircuit) return;
      }
      for (const JointVector& p : out.isolated_poses) {
        if (same_pose(p, seed.x, kSamePose)) return;
      }
    }
    // One motion of a loop with several freedoms is traced (motion.hpp):
    // a later seed with as many is not, whatever surface it lies on.
    if (!given && std::any_of(out.circuits.begin(), out.circuits.end(), [](const Circuit& c) { return c.freedoms > 1; })) {
      const ClosureSystem free_system(g, {}, seed.x);
      SystemVector F;
      SystemMatrix A;
      free_system.evaluate(seed.x, F, A);
      if (n - numerical_rank(decompose(A), o.rank_tolerance) > 1) return;
    }
    TracedCircuit t = trace(g, seed.x, o);
    if (t.circuit.points.empty()) return;
    if (t.circuit.end == CircuitEnd::rigid) {
      out.isolated_poses.push_back(t.circuit.points.front());
      return;
    }
    if (!given && repeats(t.circuit, out.circuits)) return;
    if (given) out.given_circuit = static_cast<int>(out.circuits.size());
    out.circuits.push_back(std::move(t.circuit));
    for (JointVector& b : t.branch_seeds) seeds.push_back({std::move(b), true});
  };

  // The given pose first: its circuit is the one a caller asks about.
  if (pose) {
    JointVector x = *pose;
    const ClosureSystem free_system(g, {}, x);
    const Correction c = correct(free_system, x, n, 0.5, o);
    out.least_residual = c.residual;
    out.given_pose_closes = c.converged;
    out.given_pose = x;
    if (c.converged) take({x, true}, true);
  }

  // Assemblies at input angles over the turn, then with every joint free
  // (which finds motions whose input range falls between the scanned angles).
  std::array<bool, kMaxJoints> free{};
  for (int k = 0; k < n; ++k) free[static_cast<size_t>(k)] = k != o.input_joint;
  for (int i = 0; i < o.scan_inputs; ++i) {
    JointVector base = JointVector::Zero(n);
    base[o.input_joint] = wrap_angle(kTwoPi * i / o.scan_inputs);
    const ClosureSystem system(g, {o.input_joint}, base);
    for (JointVector& x : assemblies(g, system, base, free, o.assembly_guesses, o, out.least_residual)) {
      seeds.push_back({std::move(x), false});
    }
  }
  if (o.free_guesses > 0) {
    std::array<bool, kMaxJoints> all{};
    for (int k = 0; k < n; ++k) all[static_cast<size_t>(k)] = true;
    const JointVector base = JointVector::Zero(n);
    const ClosureSystem system(g, {}, base);
    for (JointVector& x : assemblies(g, system, base, all, o.free_guesses, o, out.least_residual)) {
      seeds.push_back({std::move(x), false});
    }
  }
  out.seeds = static_cast<int>(seeds.size());
  // Seeds grow while circuits are traced (branches at bifurcations).
  for (size_t i = 0; i < seeds.size(); ++i) {
    const Seed seed = seeds[i];  // take() may append to seeds
    take(seed, false);
  }
  return out;
}

}  // namespace loopfarm
