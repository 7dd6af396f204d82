// The closure equations of the rigid loop and their solvers, shared by the
// motion's files: assemblies (motion.cpp), the tracing of a circuit
// (circuit_trace.cpp) and the start of a cycle on a motion (motion_start.cpp).
// Internal to the core.
#pragma once

#include <array>
#include <vector>

#include <Eigen/SVD>

#include "loopfarm/core/loop.hpp"
#include "loopfarm/core/motion.hpp"

namespace loopfarm::detail {

constexpr double kPi = 3.14159265358979323846;
constexpr double kTwoPi = 2.0 * kPi;
constexpr int kMaxRows = 6 + kMaxJoints;
// Poses closer than this [rad] in every joint are the same pose; a seed this
// close to a traced circuit (in every joint) lies on it.
constexpr double kSamePose = 1e-6;
constexpr double kOnCircuit = 1e-3;

using SystemMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxRows, kMaxJoints>;
using SystemVector = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxRows, 1>;
using Svd = Eigen::JacobiSVD<SystemMatrix>;

// Componentwise wrapped difference a - b, each in (-pi, pi].
JointVector wrapped_difference(const JointVector& a, const JointVector& b);

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

Svd decompose(const SystemMatrix& A);

// Numerical rank: singular values above tolerance * the largest.
int numerical_rank(const Svd& svd, double tolerance);

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
Correction correct(const ClosureSystem& system, JointVector& x, int max_rank, double max_move, const MotionOptions& o,
                   const JointVector* tangent = nullptr);

bool same_pose(const JointVector& a, const JointVector& b, double tolerance);

// Closed poses from LM at the Halton guesses, polished by Moore-Penrose
// Newton on `system` and de-duplicated; `least` gets the smallest residual.
std::vector<JointVector> assemblies(const LoopGeometry& g, const ClosureSystem& system, const JointVector& base,
                                    const std::array<bool, kMaxJoints>& free, int guesses, const MotionOptions& o,
                                    double& least);

}  // namespace loopfarm::detail
