// Local dimension of the zero set at a zero of the cycle energy.
//
// At a zero, E_mean = |r|^2 / 2 vanishes with its residual r, and the zero
// set {x : r(x) = 0} near it is, where it is a manifold of constant rank, the
// null space of J = dr/dx: its dimension is the number of free parameters
// minus the numerical rank of J. That is how many parameters the movable
// family has inside the search space (docs/design.md, "From a zero minimum to
// a candidate"), and what makes an unknown family visible.
//
// Numerical rank: singular values above max(relative_tolerance * sigma_max,
// absolute_tolerance). At a zero found to round-off the null-space singular
// values sit at about 1e-12 of the largest and the others above 1e-4 (the
// singular values are reported so that a borderline case can be looked at).
// The absolute floor matters where J vanishes altogether (every direction
// keeps the loop movable, as for spherical loops among their twists); it
// assumes J in dimensionless units: columns of lengths multiplied by the
// length scale L (dimensionless_columns below), columns of angles as they are.
//
// A J with an entry that is not finite (NaN or infinite, as from a cycle
// sample that failed) has no rank to read: the dimension is unknown, rank
// and dimension both -1 and no singular values, never a count that a NaN
// compared with the threshold would make (rank 0, the full dimension).
#pragma once

#include <vector>

#include <Eigen/Core>

namespace loopfarm {

struct LocalDimension {
  static constexpr int unknown = -1;  // rank and dimension when J has an entry that is not finite

  int parameters = 0;               // free parameters (columns of J)
  int rank = 0;                     // numerical rank of J; unknown: J has an entry that is not finite
  int dimension = 0;                // parameters - rank; unknown: J has an entry that is not finite
  double threshold = 0.0;           // absolute singular-value threshold used (0 when unknown)
  Eigen::VectorXd singular_values;  // of J, descending (empty when unknown)

  bool known() const { return dimension != unknown; }
};

LocalDimension local_dimension(const Eigen::MatrixXd& jacobian, double relative_tolerance = 1e-6,
                               double absolute_tolerance = 1e-9);

// J with its length columns multiplied by L: `is_length[c]` says whether
// column c is a derivative with respect to a length (a or d).
Eigen::MatrixXd dimensionless_columns(const Eigen::MatrixXd& jacobian, const std::vector<bool>& is_length,
                                      double length_scale);

}  // namespace loopfarm
