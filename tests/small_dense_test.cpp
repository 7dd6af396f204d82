// The solver's hand-written dense kernels against Eigen's own factorisation.
#include "../src/small_dense.hpp"

#include <Eigen/Cholesky>
#include <gtest/gtest.h>

#include "loopfarm/types.hpp"

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
