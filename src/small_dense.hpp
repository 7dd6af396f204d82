// Dense kernels for the solver's small systems (at most kMaxUnknowns = 31
// rows, 11 for a 4R loop). Eigen's general routines for dynamic sizes block,
// pack and dispatch for large matrices; at these sizes that overhead costs
// more than the arithmetic (a profile of the warm solve put half its
// instructions there), so the few operations the solver needs are written out,
// column-oriented so that every inner loop runs down one contiguous column.
// Matrices are column-major (Eigen's default). Private to src/.
#pragma once

#include <cmath>
#include <type_traits>

namespace loopfarm::dense {

// Each kernel comes twice: with the size a compile-time constant
// (std::integral_constant) and with it a plain int. The solver's sizes are
// few (3n - 1 or 4n - 1 unknowns, the 6 x 6 Schur complement), and with the
// size known the compiler writes the triangular loops out as straight-line
// code; with a runtime size the short inner loops spend most of their
// instructions on trip counts and vector remainders (callgrind over the
// bench's 8 generic 4R cycles: the 11 x 11 Cholesky took 3,461 instructions
// a call, 1,427 written out). The public entry points dispatch the sizes
// the solver meets (dispatch_size).
namespace detail {

// Calls f(std::integral_constant<int, i>) for i = Begin, ..., End - 1: the
// loop written out at compile time, for the fixed-size kernels below (GCC 12
// unrolls a loop completely only where its trip count is a constant, which
// in a triangular loop nest it is only once the outer indices are).
template <int Begin, int End, class F>
inline void static_for(F&& f) {
  if constexpr (Begin < End) {
    f(std::integral_constant<int, Begin>{});
    static_for<Begin + 1, End>(f);
  }
}

// The fixed-size Cholesky: the loops of the general one below with every
// index a constant, so that the whole factorisation is straight-line code.
template <int N>
[[gnu::flatten]] bool cholesky_in_place(double* __restrict a, long lda, std::integral_constant<int, N>) {
  bool positive = true;
  static_for<0, N>([&](auto j) {
    double* __restrict column = a + j * lda;
    const double pivot = column[j];
    // No early return from the unrolled loop: a failed pivot poisons the
    // rest with NaN, and the result says "not positive definite" all the same.
    positive = positive && pivot > 0.0;
    const double inverse = 1.0 / std::sqrt(pivot);
    column[j] = inverse;
    static_for<j + 1, N>([&](auto i) { column[i] *= inverse; });
    static_for<j + 1, N>([&](auto k) {
      double* __restrict target = a + k * lda;
      const double factor = column[k];
      static_for<k, N>([&](auto i) { target[i] -= column[i] * factor; });
    });
  });
  return positive;
}

inline bool cholesky_in_place(double* __restrict a, long lda, int n) {
  for (int j = 0; j < n; ++j) {
    double* __restrict column = a + j * lda;
    const double pivot = column[j];
    if (!(pivot > 0.0)) return false;
    const double root = std::sqrt(pivot);
    const double inverse = 1.0 / root;
    column[j] = inverse;
    for (int i = j + 1; i < n; ++i) column[i] *= inverse;
    // Rank-one update of the trailing lower triangle.
    for (int k = j + 1; k < n; ++k) {
      double* __restrict target = a + k * lda;
      const double factor = column[k];
      for (int i = k; i < n; ++i) target[i] -= column[i] * factor;
    }
  }
  return true;
}

// The fixed-size forward substitution, written out like the Cholesky above.
template <int width, int N>
[[gnu::flatten]] void solve_lower_rows(const double* __restrict l, long ldl, std::integral_constant<int, N>,
                                       double* __restrict rows) {
  static_for<0, N>([&](auto j) {
    const double* __restrict column = l + j * ldl;
    double* __restrict pivot_row = rows + j * width;
    const double inverse = column[j];
    for (int c = 0; c < width; ++c) pivot_row[c] *= inverse;
    static_for<j + 1, N>([&](auto i) {
      double* __restrict row = rows + i * width;
      const double factor = column[i];
      for (int c = 0; c < width; ++c) row[c] -= factor * pivot_row[c];
    });
  });
}

template <int width>
void solve_lower_rows(const double* __restrict l, long ldl, int n, double* __restrict rows) {
  for (int j = 0; j < n; ++j) {
    const double* __restrict column = l + j * ldl;
    double* __restrict pivot_row = rows + j * width;
    const double inverse = column[j];
    for (int c = 0; c < width; ++c) pivot_row[c] *= inverse;
    for (int i = j + 1; i < n; ++i) {
      double* __restrict row = rows + i * width;
      const double factor = column[i];
      for (int c = 0; c < width; ++c) row[c] -= factor * pivot_row[c];
    }
  }
}

// One body for both: its loops are not triangular, so a constant size is enough.
template <class Size>
void solve_lower_transposed(const double* __restrict l, long ldl, Size n, double* __restrict b) {
  for (int i = n - 1; i >= 0; --i) {
    const double* __restrict column = l + i * ldl;
    // Two partial sums halve the dependency chain of the dot product.
    double s0 = b[i], s1 = 0.0;
    int k = i + 1;
    for (; k + 1 < n; k += 2) {
      s0 -= column[k] * b[k];
      s1 -= column[k + 1] * b[k + 1];
    }
    if (k < n) s0 -= column[k] * b[k];
    b[i] = (s0 + s1) * column[i];
  }
}

template <int N>
using Size = std::integral_constant<int, N>;

// Calls kernel(size) with size a compile-time constant for the sizes the
// solver meets most (6: the Schur complement; 3 to 7: the passive angles of
// the structured step; 11, 14, 17: the unknowns of 4R, 5R and 6R loops with
// the paper's compliance; 15, 19: 4R and 5R with the full one), a plain int
// otherwise (larger loops, where the arithmetic outweighs the loop overhead
// and written-out code would only grow).
template <class Kernel>
decltype(auto) dispatch_size(int n, Kernel&& kernel) {
  switch (n) {
    case 3: return kernel(Size<3>{});
    case 4: return kernel(Size<4>{});
    case 5: return kernel(Size<5>{});
    case 6: return kernel(Size<6>{});
    case 7: return kernel(Size<7>{});
    case 11: return kernel(Size<11>{});
    case 14: return kernel(Size<14>{});
    case 15: return kernel(Size<15>{});
    case 17: return kernel(Size<17>{});
    case 19: return kernel(Size<19>{});
    default: return kernel(n);
  }
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
bool cholesky_in_place(Matrix& matrix, int n) {
  double* a = matrix.data();
  const long lda = matrix.outerStride();
  return detail::dispatch_size(n, [&](auto size) { return detail::cholesky_in_place(a, lda, size); });
}

// B <- L^-1 B for a row-major B of n rows and a fixed number of columns,
// L from cholesky_in_place (inverted diagonal): row i of B is updated by
// whole rows, which the compiler unrolls and vectorises.
template <class Matrix, class Rows>
void solve_lower_rows(const Matrix& lower, int n, Rows& b) {
  static_assert(Rows::IsRowMajor && Rows::ColsAtCompileTime > 0, "row-major, fixed width");
  constexpr int width = Rows::ColsAtCompileTime;
  const double* l = lower.data();
  const long ldl = lower.outerStride();
  double* rows = b.data();
  detail::dispatch_size(n, [&](auto size) { detail::solve_lower_rows<width>(l, ldl, size, rows); });
}

// b <- L^-ᵀ b for every column of b, L from cholesky_in_place (inverted diagonal).
template <class Matrix, class Rhs>
void solve_lower_transposed(const Matrix& lower, int n, Rhs& rhs) {
  const double* l = lower.data();
  const long ldl = lower.outerStride();
  for (long c = 0; c < rhs.cols(); ++c) {
    double* b = rhs.data() + c * rhs.outerStride();
    detail::dispatch_size(n, [&](auto size) { detail::solve_lower_transposed(l, ldl, size, b); });
  }
}

}  // namespace loopfarm::dense
