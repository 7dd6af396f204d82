#include "loopfarm/search/local_dimension.hpp"

#include <algorithm>

#include <Eigen/SVD>

namespace loopfarm {

Eigen::MatrixXd dimensionless_columns(const Eigen::MatrixXd& jacobian, const std::vector<bool>& is_length,
                                      double length_scale) {
  Eigen::MatrixXd out = jacobian;
  for (int c = 0; c < out.cols() && c < static_cast<int>(is_length.size()); ++c) {
    if (is_length[static_cast<size_t>(c)]) out.col(c) *= length_scale;
  }
  return out;
}

LocalDimension local_dimension(const Eigen::MatrixXd& jacobian, double relative_tolerance, double absolute_tolerance) {
  LocalDimension out;
  out.parameters = static_cast<int>(jacobian.cols());
  if (jacobian.size() == 0) {
    out.dimension = out.parameters;
    return out;
  }
  // A NaN singular value would count as below the threshold: no rank.
  if (!jacobian.allFinite()) {
    out.rank = LocalDimension::unknown;
    out.dimension = LocalDimension::unknown;
    return out;
  }
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(jacobian);  // values only; J is at most a few thousand x 24
  out.singular_values = svd.singularValues();
  // A tall J has cols() singular values; a wide one fewer: the rest are zero.
  const double largest = out.singular_values.size() > 0 ? out.singular_values[0] : 0.0;
  out.threshold = std::max(relative_tolerance * largest, absolute_tolerance);
  for (int i = 0; i < out.singular_values.size(); ++i) {
    if (out.singular_values[i] > out.threshold) ++out.rank;
  }
  out.dimension = out.parameters - out.rank;
  return out;
}

}  // namespace loopfarm
