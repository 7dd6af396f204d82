// Polishing a geometry onto its motion (geometry_polish.hpp): Gauss-Newton
// on the closure of many poses, the poses eliminated through the left null
// spaces of their closure Jacobians.
#include "loopfarm/core/geometry_polish.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <string>

#include <Eigen/QR>
#include <Eigen/SVD>

#include "closure_solver.hpp"

namespace loopfarm {

using namespace detail;

namespace {

// Fixed-capacity types for the per-pose work (no heap allocation per pose).
using PoseSvd = Eigen::JacobiSVD<Matrix6J>;
using ParameterColumns = Eigen::Matrix<double, 6, Eigen::Dynamic, 0, 6, 3 * kMaxJoints>;

std::string format(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.1e", value);
  return text;
}

// The change of the geometry's parameters, in GeometryVector order, for a
// step dx along the directions.
void add_step(LoopGeometry& g, const Eigen::VectorXd& change) {
  const int n = g.joints();
  for (int k = 0; k < n; ++k) {
    g.a[k] += change[k];
    g.alpha[k] += change[n + k];
    g.d[k] += change[2 * n + k];
  }
}

// Minimum-norm least-squares solution of A dx = b over the columns not
// held, with held columns fixed at the values already in dx.
Eigen::VectorXd solve_free(const Eigen::MatrixXd& A, const Eigen::VectorXd& b, const std::vector<bool>& held,
                           Eigen::VectorXd dx, double rank_tolerance) {
  std::vector<int> free;
  Eigen::VectorXd rhs = b;
  for (int c = 0; c < A.cols(); ++c) {
    if (held[static_cast<size_t>(c)]) {
      rhs -= A.col(c) * dx[c];
    } else {
      free.push_back(c);
    }
  }
  if (free.empty()) return dx;
  Eigen::MatrixXd Af(A.rows(), static_cast<int>(free.size()));
  for (size_t j = 0; j < free.size(); ++j) Af.col(static_cast<int>(j)) = A.col(free[j]);
  Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd> cod(Af.rows(), Af.cols());
  cod.setThreshold(rank_tolerance);
  cod.compute(Af);
  const Eigen::VectorXd x = cod.solve(rhs);
  for (size_t j = 0; j < free.size(); ++j) dx[free[j]] = x[static_cast<int>(j)];
  return dx;
}

}  // namespace

void GeometryPolishOptions::validate() const {
  auto fail = [](const std::string& what) { throw std::invalid_argument("GeometryPolishOptions: " + what); };
  if (!(target_residual > 0.0 && target_residual < 1e-6)) fail("target_residual must be in (0, 1e-6)");
  if (max_iterations < 1) fail("max_iterations must be >= 1");
  if (stall_iterations < 1) fail("stall_iterations must be >= 1");
  if (!(max_displacement > 0.0)) fail("max_displacement must be > 0");
  if (!(rank_tolerance > 0.0 && rank_tolerance < 1e-2)) fail("rank_tolerance must be in (0, 1e-2)");
  if (!(min_singular_ratio >= 0.0 && min_singular_ratio < 1.0)) fail("min_singular_ratio must be in [0, 1)");
}

PolishDirections PolishDirections::every_parameter(const LoopGeometry& geometry) {
  const int n = geometry.joints();
  PolishDirections out;
  out.directions = Eigen::MatrixXd::Identity(3 * n, 3 * n);
  out.lower = Eigen::VectorXd::Constant(3 * n, -std::numeric_limits<double>::infinity());
  out.upper = Eigen::VectorXd::Constant(3 * n, std::numeric_limits<double>::infinity());
  for (int k = 0; k < n; ++k) out.lower[k] = -geometry.a[k];
  return out;
}

GeometryPolishSummary polish_geometry(const LoopGeometry& geometry, std::span<const JointVector> poses, int freedoms,
                                      const PolishDirections& directions, const GeometryPolishOptions& options) {
  options.validate();
  validate_geometry(geometry);
  const int n = geometry.joints();
  const Eigen::Index k = directions.directions.cols();
  if (directions.directions.rows() != 3 * n || directions.lower.size() != k || directions.upper.size() != k) {
    throw std::invalid_argument("polish_geometry: the directions need " + std::to_string(3 * n) +
                                " rows and a lower and upper bound per column");
  }
  if (freedoms < 1 || freedoms >= n) throw std::invalid_argument("polish_geometry: freedoms must be in [1, n - 1]");
  for (const JointVector& p : poses) {
    if (p.size() != n || !p.allFinite())
      throw std::invalid_argument("polish_geometry: a pose has the wrong size or is not finite");
  }

  GeometryPolishSummary out;
  out.geometry = geometry;
  out.step = Eigen::VectorXd::Zero(k);
  const double L = length_scale(geometry);
  LoopGeometry g = scaled(geometry, L);
  // The directions in the scaled parameters (lengths / L).
  Eigen::MatrixXd D = directions.directions;
  D.topRows(n) /= L;
  D.bottomRows(n) /= L;

  const int rank = n - freedoms;
  const int left = 6 - rank;
  MotionOptions corrector;
  ClosureJacobians J;

  const auto worst_residual = [&](const LoopGeometry& at, const std::vector<JointVector>& of) {
    double worst = 0.0;
    for (const JointVector& p : of) worst = std::max(worst, closure_residual(at, p).cwiseAbs().maxCoeff());
    return worst;
  };
  // A geometry that closes to round-off already, at poses enough, is left
  // as it is.
  out.poses.assign(poses.begin(), poses.end());
  out.initial_residual = worst_residual(g, out.poses);
  out.final_residual = out.initial_residual;
  if (out.initial_residual <= options.target_residual && static_cast<Eigen::Index>(poses.size()) * left >= k) {
    out.poses_used = static_cast<int>(out.poses.size());
    out.converged = true;
    return out;
  }
  // The poses used: those where the closure Jacobian has its motion's rank
  // clearly (near a singular pose its left null space is not the motion's).
  out.poses.clear();
  for (const JointVector& p : poses) {
    closure_jacobians(g, p, J);
    const PoseSvd svd(J.theta);
    const auto& s = svd.singularValues();
    if (s[rank - 1] >= options.min_singular_ratio * s[0]) out.poses.push_back(p);
  }
  out.poses_used = static_cast<int>(out.poses.size());
  out.initial_residual = worst_residual(g, out.poses);
  out.final_residual = out.initial_residual;
  if (out.poses_used * left < k) {
    out.message = std::to_string(out.poses_used) + " regular poses of " + std::to_string(poses.size()) +
                  " are too few to fix " + std::to_string(k) + " parameters";
    return out;
  }

  Eigen::MatrixXd A(out.poses_used * left, k);
  Eigen::VectorXd b(out.poses_used * left);
  // Each pose's linearisation, kept for its part of the step.
  struct Linearisation {
    Vector6 F;
    ParameterColumns BD;  // d F / d dx
    PoseSvd svd;          // of d F / d theta
  };
  std::vector<Linearisation> at(static_cast<size_t>(out.poses_used));
  Eigen::VectorXd total = Eigen::VectorXd::Zero(k);
  double best = out.initial_residual;
  int since_halved = 0;
  double halved_from = out.initial_residual;
  while (out.iterations < options.max_iterations) {
    ++out.iterations;
    // The step system: each pose's residual in its left null space.
    for (int i = 0; i < out.poses_used; ++i) {
      Linearisation& l = at[static_cast<size_t>(i)];
      const JointVector& p = out.poses[static_cast<size_t>(i)];
      closure_jacobians(g, p, J);
      l.F = closure_residual(g, p);
      ParameterColumns B(6, 3 * n);
      B << J.a, J.alpha, J.d;
      l.BD.resize(6, k);
      l.BD.noalias() = B * D;
      l.svd.compute(J.theta, Eigen::ComputeFullU | Eigen::ComputeThinV);
      const auto U2 = l.svd.matrixU().rightCols(left);
      A.middleRows(i * left, left).noalias() = U2.transpose() * l.BD;
      b.segment(i * left, left).noalias() = -U2.transpose() * l.F;
    }
    // A component that would cross its bound is held at the bound and the
    // others solved again.
    std::vector<bool> held(static_cast<size_t>(k), false);
    Eigen::VectorXd dx = Eigen::VectorXd::Zero(k);
    for (Eigen::Index round = 0; round <= k; ++round) {
      dx = solve_free(A, b, held, dx, options.rank_tolerance);
      bool crossed = false;
      for (Eigen::Index c = 0; c < k; ++c) {
        if (held[static_cast<size_t>(c)]) continue;
        const double lo = directions.lower[c] - total[c];
        const double hi = directions.upper[c] - total[c];
        if (dx[c] < lo || dx[c] > hi) {
          dx[c] = std::clamp(dx[c], lo, hi);
          held[static_cast<size_t>(c)] = true;
          crossed = true;
        }
      }
      if (!crossed) break;
    }
    const Eigen::VectorXd change = D * dx;
    // The poses' part of the Gauss-Newton step: each pose moves to undo what
    // is left of its residual, within its closure Jacobian's range.
    for (int i = 0; i < out.poses_used; ++i) {
      const Linearisation& l = at[static_cast<size_t>(i)];
      const Vector6 predicted = l.F + l.BD * dx;
      const auto& s = l.svd.singularValues();
      JointVector& p = out.poses[static_cast<size_t>(i)];
      for (int r = 0; r < rank; ++r) p -= l.svd.matrixV().col(r) * (l.svd.matrixU().col(r).dot(predicted) / s[r]);
    }
    add_step(g, change);
    total += dx;
    out.displacement = (D * total).cwiseAbs().maxCoeff();
    if (out.displacement > options.max_displacement) {
      out.message = "the polish moves the geometry " + format(out.displacement) + " (more than " +
                    format(options.max_displacement) + "): no movable loop is this near";
      return out;
    }
    // Every pose back onto the closure of the new geometry.
    for (JointVector& p : out.poses) {
      const ClosureSystem system(g, {}, p);
      const Correction c = correct(system, p, rank, 0.5, corrector);
      if (!c.converged) {
        out.message = "a pose no longer closes after a step (residual " + format(c.residual) + ")";
        return out;
      }
    }
    out.final_residual = worst_residual(g, out.poses);
    if (out.final_residual <= options.target_residual) {
      out.converged = true;
      break;
    }
    best = std::min(best, out.final_residual);
    if (best <= 0.5 * halved_from) {
      halved_from = best;
      since_halved = 0;
    } else if (++since_halved >= options.stall_iterations) {
      break;
    }
  }
  if (!out.converged) {
    if (out.message.empty()) {
      out.message = "the closure stays at " + format(best) + " over " + std::to_string(out.poses_used) +
                    " poses after " + std::to_string(out.iterations) + " iterations (a near miss)";
    }
    return out;
  }
  out.step = total;
  // The polished geometry in the given units: the given one plus the step
  // along the directions (a tied parameter moves with its source exactly).
  out.geometry = geometry;
  add_step(out.geometry, directions.directions * total);
  for (int i = 0; i < n; ++i) out.geometry.a[i] = std::max(out.geometry.a[i], 0.0);
  return out;
}

}  // namespace loopfarm
