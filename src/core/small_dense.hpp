// Dense kernels for the solver's small systems (at most kMaxUnknowns = 31
// rows, 11 for a 4R loop). Eigen's general routines for dynamic sizes block,
// pack and dispatch for large matrices; at these sizes that overhead costs
// more than the arithmetic (a profile of the warm solve put half its
// instructions there), so the few operations the solver needs are written out,
// column-oriented so that every inner loop runs down one contiguous column.
// Matrices are column-major (Eigen's default). Private to src/.
//
// Each kernel is compiled once for every size the solver uses (the unknown
// counts of every loop size and compliance, and the 6 x 6 Schur complement)
// with the size and the leading dimension as constants, and once for any
// size: with constant loop bounds the compiler specialises the short inner
// loops (the 11 x 11 Cholesky: 3,470 -> 2,550 instructions a call over the
// bench's generic cycles, valgrind --tool=callgrind bench/cycle_breakdown). The
// arithmetic, and its order, is the same in all versions, so their results
// are identical to the bit (tests/core/small_dense_test.cpp).
#pragma once

#include <cmath>
#include <type_traits>
#include <utility>

#include <Eigen/Core>

namespace loopfarm::dense {
namespace detail {

// The sizes with their own compiled kernels: 3n - 1 (paper compliance) and
// 4n - 1 (full) unknowns for n = 4..8 joints, and 6 (the Schur complement).
using SpecializedSizes = std::integer_sequence<int, 6, 11, 14, 15, 17, 19, 20, 23, 27, 31>;

// Calls kernel(std::integral_constant<int, N>) where n and the leading
// dimension are both one of the specialised sizes N, else
// kernel(std::integral_constant<int, 0>) (size and stride at run time).
template <class Kernel, int... Sizes>
decltype(auto) with_size(int n, long stride, std::integer_sequence<int, Sizes...>, Kernel&& kernel) {
  using Result = decltype(kernel(std::integral_constant<int, 0>{}));
  if constexpr (std::is_void_v<Result>) {
    const bool done =
        ((n == Sizes && stride == Sizes ? (kernel(std::integral_constant<int, Sizes>{}), true) : false) || ...);
    if (!done) kernel(std::integral_constant<int, 0>{});
  } else {
    Result result{};
    const bool done =
        ((n == Sizes && stride == Sizes ? (result = kernel(std::integral_constant<int, Sizes>{}), true) : false) ||
         ...);
    if (!done) result = kernel(std::integral_constant<int, 0>{});
    return result;
  }
}

template <class Kernel>
decltype(auto) with_size(int n, long stride, Kernel&& kernel) {
  return with_size(n, stride, SpecializedSizes{}, static_cast<Kernel&&>(kernel));
}

}  // namespace detail

// Cholesky factorisation in place (right-looking): on success the strictly
// lower triangle of `a` (n x n, only its lower triangle read) holds L with
// a = L Lᵀ, and the diagonal holds 1 / L(i, i), so that the triangular solves
// below multiply instead of divide (a division on the back-substitution's
// critical path costs as much as the rest of the row). Returns false as soon
// as a pivot is not positive (or not a number): the matrix is then not
// positive definite, which is what the solver uses this test for.
template <class Matrix>
bool cholesky_in_place(Matrix& matrix, int size) {
  return detail::with_size(size, matrix.outerStride(), [&](auto fixed) {
    constexpr int N = decltype(fixed)::value;  // 0: size and stride at run time
    const int n = N > 0 ? N : size;
    const long lda = N > 0 ? N : matrix.outerStride();
    double* __restrict a = matrix.data();
    // First as L D Lᵀ, the columns left unscaled (c_j = L(:, j) d_j): from
    // one pivot to the next the critical path is then a division, a
    // multiplication and an update, where the square root and the division
    // after it doubled it (perf annotate put a third of this kernel's time
    // on those two). The square roots come after, independent of each other.
    for (int j = 0; j < n; ++j) {
      double* __restrict column = a + j * lda;
      const double pivot = column[j];
      if (!(pivot > 0.0)) return false;
      const double inverse = 1.0 / pivot;
      // Rank-one update of the trailing lower triangle: c_i c_k / d_j.
      for (int k = j + 1; k < n; ++k) {
        double* __restrict target = a + k * lda;
        const double factor = column[k] * inverse;
        for (int i = k; i < n; ++i) target[i] -= column[i] * factor;
      }
    }
    // L(:, j) = c_j / sqrt(d_j), and the diagonal 1 / sqrt(d_j).
    for (int j = 0; j < n; ++j) {
      double* __restrict column = a + j * lda;
      const double inverse = 1.0 / std::sqrt(column[j]);
      column[j] = inverse;
      for (int i = j + 1; i < n; ++i) column[i] *= inverse;
    }
    return true;
  });
}

// B <- L^-1 B for a row-major B of n rows and a fixed number of columns,
// L from cholesky_in_place (inverted diagonal): row i of B is updated by
// whole rows, in SIMD packets (below).
template <class Matrix, class Rows>
void solve_lower_rows(const Matrix& lower, int size, Rows& b) {
  static_assert(Rows::IsRowMajor && Rows::ColsAtCompileTime > 0, "row-major, fixed width");
  constexpr int width = Rows::ColsAtCompileTime;
  detail::with_size(size, lower.outerStride(), [&](auto fixed) {
    constexpr int N = decltype(fixed)::value;
    const int n = N > 0 ? N : size;
    const long ldl = N > 0 ? N : lower.outerStride();
    const double* __restrict l = lower.data();
    double* __restrict rows = b.data();
    // The rows as Eigen maps of fixed width: Eigen's explicit SIMD packets,
    // where GCC 12 left the plain loop over two rows of one buffer scalar
    // (perf annotate of solve_columns); the same operations element by
    // element, so the same bits.
    using Row = Eigen::Map<Eigen::Matrix<double, 1, width>>;
    for (int j = 0; j < n; ++j) {
      const double* __restrict column = l + j * ldl;
      Row pivot_row(rows + j * width);
      pivot_row *= column[j];
      for (int i = j + 1; i < n; ++i) Row(rows + i * width) -= column[i] * pivot_row;
    }
  });
}

// b <- L^-ᵀ b for every column of b, L from cholesky_in_place (inverted diagonal).
template <class Matrix, class Rhs>
void solve_lower_transposed(const Matrix& lower, int size, Rhs& rhs) {
  detail::with_size(size, lower.outerStride(), [&](auto fixed) {
    constexpr int N = decltype(fixed)::value;
    const int n = N > 0 ? N : size;
    const long ldl = N > 0 ? N : lower.outerStride();
    const double* __restrict l = lower.data();
    for (long c = 0; c < rhs.cols(); ++c) {
      double* __restrict b = rhs.data() + c * rhs.outerStride();
      for (int i = n - 1; i >= 0; --i) {
        const double* __restrict column = l + i * ldl;
        // The dot product from the far end, so that b[i + 1], the value
        // computed last, enters last: the older terms are summed while it is
        // still being computed, and only a few operations separate one row
        // from the next. Two partial sums halve the rest of the chain.
        double s0 = 0.0, s1 = 0.0;
        int k = n - 1;
        for (; k > i + 1; k -= 2) {
          s0 += column[k] * b[k];
          s1 += column[k - 1] * b[k - 1];
        }
        if (k == i + 1) s0 += column[k] * b[k];
        b[i] = (b[i] - (s0 + s1)) * column[i];
      }
    }
  });
}

}  // namespace loopfarm::dense
