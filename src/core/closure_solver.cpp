// The closure solvers (closure_solver.hpp): Moore-Penrose Newton for a
// closed pose near a given one, Levenberg-Marquardt from deterministic
// guesses for the assemblies.
#include "closure_solver.hpp"

#include <algorithm>
#include <array>
#include <cmath>

#include <Eigen/Cholesky>

#include "halton.hpp"

namespace loopfarm::detail {
namespace {

// A corrector stops when its step is below this [rad] (round-off reached).
constexpr double kConvergedStep = 1e-13;
constexpr int kMaxCorrectorIterations = 12;

// Levenberg-Marquardt stops at a least-squares minimum when this many
// accepted steps in a row each lower the residual's norm by less than
// kStagnantDecrease of it. Measured on the assembly searches of 6R near
// misses and of Goldberg 5R loops (16,224 solves): a solve that goes on to
// close never creeps so slowly for three steps before it does, while one
// that does not close spends about a third of its iterations there.
constexpr int kStagnantSteps = 3;
constexpr double kStagnantDecrease = 1e-6;

// Levenberg-Marquardt on the 6 closure equations over the joints marked
// free, from x: the assembly search's solver, robust far from the solution
// (where Newton steps are too long). It hands over to the corrector once the
// max-norm residual is at most `handover` (Newton's method converges from
// there, where the damping slows a near miss's approach to its least
// residual), or stops at a least-squares minimum (above). Returns the final
// max-norm residual.
double levenberg_marquardt(const LoopGeometry& g, const std::array<bool, kMaxJoints>& free, JointVector& x,
                           int max_iterations, double handover) {
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
  int stagnant = 0;
  for (int it = 0; it < max_iterations && r.cwiseAbs().maxCoeff() > handover && stagnant < kStagnantSteps; ++it) {
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
        const double decrease = 1.0 - std::sqrt(rt.squaredNorm() / norm);
        stagnant = decrease < kStagnantDecrease ? stagnant + 1 : 0;
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

}  // namespace

JointVector wrapped_difference(const JointVector& a, const JointVector& b) {
  JointVector d = a - b;
  for (int k = 0; k < d.size(); ++k) d[k] = wrap_angle(d[k]);
  return d;
}

Svd decompose(const SystemMatrix& A) { return Svd(A, Eigen::ComputeFullU | Eigen::ComputeFullV); }

// Numerical rank: singular values above tolerance * the largest.
int numerical_rank(const Svd& svd, double tolerance) {
  const auto& s = svd.singularValues();
  int r = 0;
  while (r < s.size() && s[r] > tolerance * std::max(s[0], 1e-300)) ++r;
  return r;
}

Correction correct(const ClosureSystem& system, JointVector& x, int max_rank, double max_move, const MotionOptions& o,
                   const JointVector* tangent) {
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

bool same_pose(const JointVector& a, const JointVector& b, double tolerance) {
  return wrapped_difference(a, b).cwiseAbs().maxCoeff() <= tolerance;
}

std::vector<JointVector> assemblies(const LoopGeometry& g, const ClosureSystem& system, const JointVector& base,
                                    const std::array<bool, kMaxJoints>& free, int guesses, const MotionOptions& o,
                                    double& least) {
  std::vector<JointVector> out;
  for (int i = 0; i < guesses; ++i) {
    JointVector x = halton_guess(base, free, i);
    const double residual = levenberg_marquardt(g, free, x, 200, 1e-2 * std::sqrt(o.residual_tolerance));
    least = std::min(least, residual);
    if (residual > std::sqrt(o.residual_tolerance)) continue;
    const Correction c = correct(system, x, system.joints(), 0.1, o);
    least = std::min(least, c.residual);
    if (!c.converged) continue;
    for (int k = 0; k < x.size(); ++k) x[k] = wrap_angle(x[k]);
    if (std::none_of(out.begin(), out.end(), [&](const JointVector& p) { return same_pose(p, x, kSamePose); })) {
      out.push_back(x);
    }
  }
  return out;
}

}  // namespace loopfarm::detail
