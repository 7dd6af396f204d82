// Dense kernels for the solver's small systems (at most kMaxUnknowns = 31
// rows, 11 for a 4R loop). Eigen's general routines for dynamic sizes block,
// pack and dispatch for large matrices; at these sizes that overhead costs
// more than the arithmetic (a profile of the warm solve put half its
// instructions there), so the few operations the solver needs are written out.
// Private to src/.
#pragma once

#include <cmath>

namespace loopfarm::dense {

// Cholesky factorisation in place: on success the lower triangle of `a`
// (n x n, only its lower triangle read) holds L with a = L Lᵀ. Returns false
// as soon as a pivot is not positive (or not a number): the matrix is then not
// positive definite, which is what the solver uses this test for.
template <class Matrix>
bool cholesky_in_place(Matrix& a, int n) {
  for (int j = 0; j < n; ++j) {
    double pivot = a(j, j);
    for (int k = 0; k < j; ++k) pivot -= a(j, k) * a(j, k);
    if (!(pivot > 0.0)) return false;
    pivot = std::sqrt(pivot);
    a(j, j) = pivot;
    const double inverse = 1.0 / pivot;
    for (int i = j + 1; i < n; ++i) {
      double s = a(i, j);
      for (int k = 0; k < j; ++k) s -= a(i, k) * a(j, k);
      a(i, j) = s * inverse;
    }
  }
  return true;
}

// b <- L^-1 b for every column of b (n rows), L from cholesky_in_place.
template <class Matrix, class Rhs>
void solve_lower(const Matrix& l, int n, Rhs& b) {
  for (int c = 0; c < b.cols(); ++c) {
    for (int i = 0; i < n; ++i) {
      double s = b(i, c);
      for (int k = 0; k < i; ++k) s -= l(i, k) * b(k, c);
      b(i, c) = s / l(i, i);
    }
  }
}

// b <- L^-ᵀ b for every column of b.
template <class Matrix, class Rhs>
void solve_lower_transposed(const Matrix& l, int n, Rhs& b) {
  for (int c = 0; c < b.cols(); ++c) {
    for (int i = n - 1; i >= 0; --i) {
      double s = b(i, c);
      for (int k = i + 1; k < n; ++k) s -= l(k, i) * b(k, c);
      b(i, c) = s / l(i, i);
    }
  }
}

}  // namespace loopfarm::dense
