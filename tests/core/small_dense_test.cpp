// The solver's hand-written dense kernels against Eigen's own factorisation.
#include "../../src/core/small_dense.hpp"

#include <gtest/gtest.h>
#include <Eigen/Cholesky>

#include "loopfarm/core/types.hpp"

namespace loopfarm {
namespace {

using Rows8 = Eigen::Matrix<double, Eigen::Dynamic, 8, Eigen::RowMajor, kMaxUnknowns, 8>;

TEST(SmallDense, CholeskyAndSolvesAgreeWithEigen) {
  for (int n : {1, 2, 11, 17, kMaxUnknowns}) {
    // Fixed-capacity storage, as in the solver: the leading dimension is n.
    const Eigen::MatrixXd g = Eigen::MatrixXd::Random(n, n);
    const Eigen::MatrixXd spd = g * g.transpose() + n * Eigen::MatrixXd::Identity(n, n);
    UnknownMatrix a = spd;
    ASSERT_TRUE(dense::cholesky_in_place(a, n)) << n;
    const Eigen::LLT<Eigen::MatrixXd> reference(spd);
    const Eigen::MatrixXd l_ref = reference.matrixL();
    // The strictly lower triangle is L, the diagonal 1 / L(i, i).
    Eigen::MatrixXd l = a.triangularView<Eigen::StrictlyLower>();
    l.diagonal() = a.diagonal().head(n).cwiseInverse();
    EXPECT_LT((l - l_ref).cwiseAbs().maxCoeff(), 1e-12 * l_ref.cwiseAbs().maxCoeff()) << n;

    Rows8 b = Rows8::Random(n, 8);
    const Eigen::MatrixXd b0 = b;
    dense::solve_lower_rows(a, n, b);
    EXPECT_LT((l_ref * Eigen::MatrixXd(b) - b0).cwiseAbs().maxCoeff(), 1e-12) << n;

    UnknownVector x = UnknownVector::Random(n);
    const Eigen::VectorXd x0 = x;
    dense::solve_lower_transposed(a, n, x);
    EXPECT_LT((l_ref.transpose() * Eigen::VectorXd(x) - x0).cwiseAbs().maxCoeff(), 1e-12) << n;
  }
}

// The kernels compiled for a fixed size (the solver's sizes, leading
// dimension equal to the size) against the same kernels at run-time size
// (reached through a leading dimension of 32, which no size has): identical
// to the bit.
TEST(SmallDense, FixedSizeKernelsGiveTheRunTimeSizeResultsExactly) {
  for (int n : {6, 11, 14, 15, 17, 19, 20, 23, 27, 31}) {
    const Eigen::MatrixXd g = Eigen::MatrixXd::Random(n, n);
    const Eigen::MatrixXd spd = g * g.transpose() + n * Eigen::MatrixXd::Identity(n, n);
    UnknownMatrix fixed = spd;  // leading dimension n: the fixed-size kernels
    using Padded = Eigen::Matrix<double, 32, 32>;
    Padded general = Padded::Zero();
    general.topLeftCorner(n, n) = spd;  // leading dimension 32: the run-time kernels
    ASSERT_TRUE(dense::cholesky_in_place(fixed, n));
    ASSERT_TRUE(dense::cholesky_in_place(general, n));
    for (int j = 0; j < n; ++j) {
      for (int i = j; i < n; ++i) ASSERT_EQ(fixed(i, j), general(i, j)) << n;
    }
    Rows8 b_fixed = Rows8::Random(n, 8);
    Rows8 b_general = b_fixed;
    dense::solve_lower_rows(fixed, n, b_fixed);
    dense::solve_lower_rows(general, n, b_general);
    EXPECT_TRUE((b_fixed.array() == b_general.array()).all()) << n;
    UnknownVector x_fixed = UnknownVector::Random(n);
    UnknownVector x_general = x_fixed;
    dense::solve_lower_transposed(fixed, n, x_fixed);
    dense::solve_lower_transposed(general, n, x_general);
    EXPECT_TRUE((x_fixed.array() == x_general.array()).all()) << n;
  }
}

TEST(SmallDense, CholeskyRefusesMatricesThatAreNotPositiveDefinite) {
  UnknownMatrix a(3, 3);
  a << 1, 0, 0, 0, -1, 0, 0, 0, 1;  // indefinite
  EXPECT_FALSE(dense::cholesky_in_place(a, 3));
  a << 1, 1, 0, 1, 1, 0, 0, 0, 1;  // singular
  EXPECT_FALSE(dense::cholesky_in_place(a, 3));
  a << 1, 0, 0, 0, std::nan(""), 0, 0, 0, 1;
  EXPECT_FALSE(dense::cholesky_in_place(a, 3));
}

}  // namespace
}  // namespace loopfarm
