// Helpers shared by the tests: central differences and small comparisons.
#pragma once

#include <cmath>
#include <functional>

#include <Eigen/Core>

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

}  // namespace loopfarm::testing
