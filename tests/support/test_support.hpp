// Helpers shared by the tests: central differences and small comparisons.
#pragma once

#include <algorithm>
#include <cmath>
#include <functional>
#include <random>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/QR>

#include "loopfarm/core/equilibrium.hpp"
#include "loopfarm/core/loop.hpp"

namespace loopfarm::testing {

// Central difference of a vector function of one scalar.
inline Eigen::VectorXd central_difference(const std::function<Eigen::VectorXd(double)>& f, double x, double h) {
  return (f(x + h) - f(x - h)) / (2.0 * h);
}

// |a - b|_inf / max(1, |b|_inf): relative error with an absolute floor.
inline double relative_error(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  return (a - b).cwiseAbs().maxCoeff() / std::max(1.0, b.cwiseAbs().maxCoeff());
}

inline double deg(double radians) { return radians * 180.0 / 3.14159265358979323846; }
inline double rad(double degrees) { return degrees * 3.14159265358979323846 / 180.0; }

// A second, independent equilibrium solver to check solve_equilibrium against.
// It shares nothing with it but closure_residual and the problem statement:
// the method of multipliers (augmented Lagrangian), each subproblem
//     min 1/2 |sqrt(K) delta|^2 + kappa/2 |c + lambda/kappa|^2
// solved as nonlinear least squares by Levenberg-Marquardt with central-
// difference Jacobians and a QR solve, then lambda += kappa c. First-order in
// the multipliers, no Hessian, no analytic derivative: slow, but converges to
// the same exact constrained minimum.
struct ReferenceEquilibrium {
  bool converged = false;
  double energy = 0.0;
  double closure = 0.0;          // max-norm of the final closure residual
  JointVector theta;             // all joint angles
  Eigen::VectorXd deformations;  // in the model's slot order
};

inline ReferenceEquilibrium reference_equilibrium(const LoopModel& model, double theta_in,
                                                  const JointVector& theta_guess) {
  const LoopGeometry& g0 = model.normalized_geometry();
  const int n = g0.joints();
  const int input = model.options().input_joint;
  const int ndef = model.deformation_count();
  const int nx = (n - 1) + ndef;
  std::vector<int> passive;
  for (int i = 0; i < n; ++i) {
    if (i != input) passive.push_back(i);
  }
  // x = (passive angles, deformations); deformation slot k deforms a (k < n),
  // alpha (n <= k < 2n) or d (2n <= k), as documented in equilibrium.hpp.
  auto closure_at = [&](const Eigen::VectorXd& x) {
    LoopGeometry g = g0;
    JointVector theta(n);
    theta[input] = theta_in;
    for (int j = 0; j < n - 1; ++j) theta[passive[j]] = x[j];
    for (int k = 0; k < ndef; ++k) {
      const double v = x[n - 1 + k];
      if (k < n)
        g.a[k] += v;
      else if (k < 2 * n)
        g.alpha[k - n] += v;
      else
        g.d[k - 2 * n] += v;
    }
    return Eigen::VectorXd(closure_residual(g, theta));
  };
  Eigen::VectorXd weight(ndef);
  for (int k = 0; k < ndef; ++k) weight[k] = std::sqrt(model.deformation_stiffness(k));

  const double kappa = 1e3;
  Eigen::VectorXd lambda = Eigen::VectorXd::Zero(6);
  auto residual = [&](const Eigen::VectorXd& x) {
    Eigen::VectorXd r(ndef + 6);
    r.head(ndef) = weight.cwiseProduct(x.tail(ndef));
    r.tail(6) = std::sqrt(kappa) * (closure_at(x) + lambda / kappa);
    return r;
  };

  Eigen::VectorXd x = Eigen::VectorXd::Zero(nx);
  for (int j = 0; j < n - 1; ++j) x[j] = theta_guess[passive[j]];
  ReferenceEquilibrium out;
  for (int outer = 0; outer < 200; ++outer) {
    double damping = 1e-3;
    for (int inner = 0; inner < 200; ++inner) {
      const Eigen::VectorXd r = residual(x);
      Eigen::MatrixXd jac(r.size(), nx);
      const double h = 1e-6;
      for (int u = 0; u < nx; ++u) {
        Eigen::VectorXd xp = x, xm = x;
        xp[u] += h;
        xm[u] -= h;
        jac.col(u) = (residual(xp) - residual(xm)) / (2.0 * h);
      }
      // Levenberg-Marquardt step from the stacked system [J; sqrt(mu) I] dx = [-r; 0].
      bool improved = false;
      Eigen::VectorXd dx;
      for (int tries = 0; tries < 30 && !improved; ++tries) {
        Eigen::MatrixXd stacked(r.size() + nx, nx);
        stacked << jac, std::sqrt(damping) * Eigen::MatrixXd::Identity(nx, nx);
        Eigen::VectorXd rhs = Eigen::VectorXd::Zero(r.size() + nx);
        rhs.head(r.size()) = -r;
        dx = stacked.colPivHouseholderQr().solve(rhs);
        if (residual(x + dx).squaredNorm() <= r.squaredNorm()) {
          improved = true;
          damping = std::max(damping / 10.0, 1e-15);
        } else {
          damping *= 10.0;
        }
      }
      if (!improved) break;
      x += dx;
      if (dx.cwiseAbs().maxCoeff() < 1e-14) break;
    }
    const Eigen::VectorXd c = closure_at(x);
    lambda += kappa * c;
    out.closure = c.cwiseAbs().maxCoeff();
    if (out.closure < 1e-12) {
      out.converged = true;
      break;
    }
  }
  out.theta = JointVector(n);
  out.theta[input] = theta_in;
  for (int j = 0; j < n - 1; ++j) out.theta[passive[j]] = x[j];
  out.deformations = x.tail(ndef);
  out.energy = 0.5 * weight.cwiseProduct(out.deformations).squaredNorm();
  return out;
}

// The rigid closure solved for the passive angles, joint 1 held at theta0, by
// Levenberg-Marquardt from random guesses in [-pi, pi): true with a pose
// closing to 1e-13. A solver of the tests' own, independent of the library's
// assembly and motion tracing (dense, from closure_jacobians).
inline bool assemble_by_levenberg_marquardt(const LoopGeometry& g, double theta0, std::mt19937_64& rng,
                                            JointVector& theta, int guesses) {
  const int n = g.joints();
  std::uniform_real_distribution<double> angle(-3.14159265358979323846, 3.14159265358979323846);
  for (int s = 0; s < guesses; ++s) {
    theta.resize(n);
    theta[0] = theta0;
    for (int k = 1; k < n; ++k) theta[k] = angle(rng);
    double mu = 1e-3;
    Vector6 r = closure_residual(g, theta);
    for (int it = 0; it < 100 && r.cwiseAbs().maxCoeff() > 1e-14; ++it) {
      ClosureJacobians J;
      closure_jacobians(g, theta, J);
      const Eigen::MatrixXd A = J.theta.rightCols(n - 1);
      const Eigen::MatrixXd normal = A.transpose() * A;
      const Eigen::VectorXd gradient = A.transpose() * r;
      bool improved = false;
      for (; mu < 1e10 && !improved; mu *= 10) {
        Eigen::MatrixXd damped = normal;
        damped.diagonal().array() += mu;
        JointVector trial = theta;
        trial.tail(n - 1) += damped.ldlt().solve(-gradient);
        const Vector6 rt = closure_residual(g, trial);
        if (rt.squaredNorm() < r.squaredNorm()) {
          theta = trial;
          r = rt;
          improved = true;
          mu = std::max(1e-12, mu / 100);
        }
      }
      if (!improved) break;
    }
    if (r.cwiseAbs().maxCoeff() < 1e-13) return true;
  }
  return false;
}

}  // namespace loopfarm::testing
