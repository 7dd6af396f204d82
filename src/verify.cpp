// Rigid verification: the closure solved for the passive angles along the
// motion (verify.hpp). Shares nothing with the elastic model but the loop's
// kinematics (closure_residual, closure_jacobians).
#include "loopfarm/verify.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <Eigen/Cholesky>

namespace loopfarm {
namespace {

constexpr double kTwoPi = 2.0 * 3.14159265358979323846;
// A step whose passive angles move more than this is not taken as continuous
// (the same bound as the cycle's continuation).
constexpr double kMaxPassiveJump = 0.5;

double max_abs(const Vector6& v) { return v.cwiseAbs().maxCoeff(); }

// Levenberg-Marquardt on the 6 closure equations over the passive angles,
// the input held. Converges quadratically where the loop closes (a zero
// residual); elsewhere it stops at the least-squares residual, which is then
// what is reported. Returns the final residual's max-norm.
double solve_closure(const LoopGeometry& g, int input, JointVector& theta, int max_iterations) {
  const int n = g.joints();
  ChainKinematics chain;
  Vector6 r = closure_residual(g, theta);
  double norm = r.squaredNorm();
  double mu = 1e-6;
  for (int it = 0; it < max_iterations && max_abs(r) > 1e-15; ++it) {
    // The passive angles' columns of the closure Jacobian only (what
    // closure_jacobians gives for theta, without its a, alpha, d columns).
    compute_chain(g, theta, chain);
    Eigen::Matrix<double, 6, Eigen::Dynamic, 0, 6, kMaxJoints> A(6, n - 1);
    for (int k = 0, c = 0; k < n; ++k) {
      if (k != input) A.col(c++) = residual_derivative(chain, chain_index(k, ChainParameter::theta));
    }
    // Fixed-capacity types: a verification walks 720 poses and more, and
    // dynamic-size temporaries made this loop allocate several times per
    // iteration.
    using PassiveMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxJoints, kMaxJoints>;
    using PassiveVector = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxJoints, 1>;
    const PassiveMatrix normal = A.transpose() * A;
    const PassiveVector gradient = A.transpose() * r;
    bool improved = false;
    while (mu < 1e12) {
      PassiveMatrix damped = normal;
      damped.diagonal().array() += mu * (1.0 + normal.diagonal().array());
      const PassiveVector step = Eigen::LDLT<PassiveMatrix>(damped).solve(-gradient);
      JointVector trial = theta;
      for (int k = 0, c = 0; k < n; ++k) {
        if (k != input) trial[k] += step[c++];
      }
      const Vector6 rt = closure_residual(g, trial);
      if (rt.squaredNorm() < norm) {
        theta = trial;
        r = rt;
        norm = rt.squaredNorm();
        mu = std::max(mu / 10.0, 1e-12);
        improved = true;
        break;
      }
      mu *= 10.0;
    }
    if (!improved) break;  // a least-squares minimum: the loop does not close here
  }
  return max_abs(r);
}

// One direction of the walk from `start`: steps of `step` (signed) in the
// input until `limit_angle` (a full turn) or until no step closes. Appends
// the poses reached, not the start.
struct Walk {
  std::vector<JointVector> poses;
  double worst = 0.0;
  bool reached_end = false;
  double last_failure_residual = 0.0;
};

Walk walk(const LoopGeometry& g, const JointVector& start, double step, double span, const VerificationOptions& o) {
  const int n = g.joints();
  const int input = o.input_joint;
  Walk w;
  JointVector current = start, previous = start;
  double last_step = 0.0;
  double advanced = 0.0;
  while (span - advanced > 1e-12) {
    bool accepted = false;
    for (int depth = 0; depth <= o.max_bisections && !accepted; ++depth) {
      double s = std::ldexp(std::abs(step), -depth);
      s = std::min(s, span - advanced);
      const double signed_s = step > 0 ? s : -s;
      // Secant prediction from the last two poses, scaled to this step.
      JointVector guess = current;
      if (last_step != 0.0) {
        for (int k = 0; k < n; ++k) guess[k] += (current[k] - previous[k]) * (signed_s / last_step);
      }
      guess[input] = current[input] + signed_s;
      const double residual = solve_closure(g, input, guess, o.max_newton_iterations);
      double jump = 0.0;
      for (int k = 0; k < n; ++k) {
        if (k != input) jump = std::max(jump, std::abs(wrap_angle(guess[k] - current[k])));
      }
      if (residual <= o.residual_tolerance && jump <= kMaxPassiveJump) {
        // Unwrap relative to the last pose, so that angles stay continuous.
        for (int k = 0; k < n; ++k) guess[k] = current[k] + wrap_angle(guess[k] - current[k]);
        guess[input] = current[input] + signed_s;
        previous = current;
        current = guess;
        last_step = signed_s;
        advanced += s;
        w.worst = std::max(w.worst, residual);
        w.poses.push_back(current);
        accepted = true;
      } else {
        w.last_failure_residual = residual;
      }
    }
    if (!accepted) return w;
  }
  w.reached_end = true;
  return w;
}

}  // namespace

void VerificationOptions::validate() const {
  if (steps_per_turn < 360) throw std::invalid_argument("VerificationOptions: steps_per_turn must be >= 360");
  if (!(residual_tolerance > 0.0)) throw std::invalid_argument("VerificationOptions: residual_tolerance must be > 0");
  if (max_newton_iterations < 1) throw std::invalid_argument("VerificationOptions: max_newton_iterations must be >= 1");
  if (max_bisections < 0) throw std::invalid_argument("VerificationOptions: max_bisections must be >= 0");
  if (input_joint < 0 || input_joint >= kMaxJoints) throw std::invalid_argument("VerificationOptions: input_joint out of range");
}

VerificationSummary verify_motion(const LoopGeometry& geometry, const JointVector& start_angles,
                                  const VerificationOptions& options) {
  options.validate();
  validate_geometry(geometry);
  const int n = geometry.joints();
  if (start_angles.size() != n) {
    throw std::invalid_argument("verify_motion: " + std::to_string(start_angles.size()) + " start angles for " +
                                std::to_string(n) + " joints");
  }
  if (!start_angles.allFinite()) throw std::invalid_argument("verify_motion: a start angle is not finite");
  if (options.input_joint >= n) throw std::invalid_argument("verify_motion: input_joint beyond the loop's joints");

  // Dimensionless: lengths in units of L, so the tolerance means the same at any scale.
  const LoopGeometry g = scaled(geometry, length_scale(geometry));
  VerificationSummary out;
  JointVector start = start_angles;
  const double residual = solve_closure(g, options.input_joint, start, 4 * options.max_newton_iterations);
  out.worst_residual = residual;
  if (residual > options.residual_tolerance) {
    out.limit = "the rigid loop does not close at the start pose";
    return out;
  }
  out.assembled = true;
  const double h = kTwoPi / options.steps_per_turn;

  const Walk forward = walk(g, start, h, kTwoPi, options);
  Walk backward;
  if (!forward.reached_end) backward = walk(g, start, -h, kTwoPi, options);
  out.full_turn = forward.reached_end;

  for (auto it = backward.poses.rbegin(); it != backward.poses.rend(); ++it) out.joint_angles.push_back(*it);
  out.joint_angles.push_back(start);
  out.joint_angles.insert(out.joint_angles.end(), forward.poses.begin(), forward.poses.end());
  for (const JointVector& pose : out.joint_angles) out.input_angles.push_back(pose[options.input_joint]);
  out.poses = static_cast<int>(out.joint_angles.size());
  out.worst_residual = std::max({residual, forward.worst, backward.worst});
  out.range_lo = out.input_angles.front();
  out.range_hi = out.input_angles.back();
  out.joint_travel = JointVector::Zero(n);
  for (int k = 0; k < n; ++k) {
    double lo = out.joint_angles.front()[k], hi = lo;
    for (const JointVector& pose : out.joint_angles) {
      lo = std::min(lo, pose[k]);
      hi = std::max(hi, pose[k]);
    }
    out.joint_travel[k] = hi - lo;
  }
  // Moving means covering at least one full step: an infinitesimally mobile
  // (shaky) structure closes to second order over a few tiny bisected steps.
  out.verified = out.range_hi - out.range_lo >= h * (1.0 - 1e-9);

  if (out.full_turn) {
    // The input turned fully; say so if the pose comes back only after more turns.
    double gap = 0.0;
    for (int k = 0; k < n; ++k) gap = std::max(gap, std::abs(wrap_angle(out.joint_angles.back()[k] - start[k])));
    if (gap > 1e-6) out.limit = "the input turns fully but the pose returns only after further turns";
  } else {
    char buffer[160];
    std::snprintf(buffer, sizeof buffer, "closure lost beyond [%.6g, %.6g] deg (residual %.3g there)",
                  out.range_lo * 180.0 / 3.14159265358979323846, out.range_hi * 180.0 / 3.14159265358979323846,
                  std::max(forward.last_failure_residual, backward.last_failure_residual));
    out.limit = buffer;
  }
  return out;
}

}  // namespace loopfarm
