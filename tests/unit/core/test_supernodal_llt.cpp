// SupernodalLlt (CHOLMOD's supernodal Cholesky): the solutions of Eigen's SimplicialLDLT to
// round-off with a shift, on a grid-like and a dense-block (3D packing-like) matrix, with
// CHOLMOD's AMD and with a given order; a multi-column solve; the same bits on 1 and 2 threads;
// a matrix that is not positive definite reported.
#include <gtest/gtest.h>
#include <omp.h>

#include <Eigen/SparseCholesky>
#include <cmath>

#include "../../support/sparse_matrices.hpp"
#include "mpmcd/core/supernodal_llt.hpp"
#include "mpmcd/core/tree_ldlt.hpp"

namespace {

using mpmcd::SupernodalLlt;
using mpmcd::test_support::grain_blocks_matrix;
using mpmcd::test_support::grid_matrix;

// (A + shift I)^-1 b by Eigen's SimplicialLDLT.
Eigen::VectorXd reference_solve(const Eigen::SparseMatrix<double>& A, double shift,
                                const Eigen::VectorXd& b) {
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt;
  ldlt.setShift(shift);
  ldlt.compute(A);
  EXPECT_EQ(ldlt.info(), Eigen::Success);
  return ldlt.solve(b);
}

void expect_solves_like_eigen(const Eigen::SparseMatrix<double>& A, double shift,
                              const int* order) {
  SupernodalLlt llt;
  ASSERT_TRUE(llt.compute(A, shift, order));
  EXPECT_TRUE(llt.ok());
  EXPECT_GT(llt.factor_nonzeros(), static_cast<double>(A.rows()));
  EXPECT_GT(llt.flops(), llt.factor_nonzeros());
  const Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(A.rows(), -1.0, 2.0);
  Eigen::VectorXd x = b;
  llt.solve_in_place(x);
  const Eigen::VectorXd ref = reference_solve(A, shift, b);
  EXPECT_LT((x - ref).norm(), 1e-10 * ref.norm());
}

TEST(SupernodalLlt, SolvesAsSimplicialLdltOnAGridMatrix) {
  const Eigen::SparseMatrix<double> A = grid_matrix(30, 40, 1e-3, 7);
  expect_solves_like_eigen(A, 1e-6, nullptr);
}

TEST(SupernodalLlt, SolvesAsSimplicialLdltOnDenseGrainBlocksWithAGivenOrder) {
  // 40 grains of 60 + 20 contacts, rank 3 couplings: W is singular but for the diagonal, as
  // nearly redundant contacts make it; the shift keeps it definite.
  const Eigen::SparseMatrix<double> A = grain_blocks_matrix(40, 60, 20, 3, 1e-4, 3);
  mpmcd::TreeLdlt tree;
  tree.analyze(A);
  expect_solves_like_eigen(A, 1e-8, tree.order().data());
  expect_solves_like_eigen(A, 1e-8, nullptr);
  // Its factor's columns are long: the supernodal case (flops per entry well above 40).
  EXPECT_GT(tree.symbolic_flops(),
            40.0 * static_cast<double>(tree.matrixL().nestedExpression().nonZeros()));
}

TEST(SupernodalLlt, MultiColumnSolveMatchesSingleSolves) {
  const Eigen::SparseMatrix<double> A = grain_blocks_matrix(20, 50, 10, 3, 1e-3, 5);
  SupernodalLlt llt;
  ASSERT_TRUE(llt.compute(A, 0.0));
  Eigen::MatrixXd B = Eigen::MatrixXd::Random(A.rows(), 5);
  const Eigen::MatrixXd B0 = B;
  llt.solve_in_place(B);
  for (Eigen::Index j = 0; j < B.cols(); ++j) {
    Eigen::VectorXd x = B0.col(j);
    llt.solve_in_place(x);
    EXPECT_LT((B.col(j) - x).norm(), 1e-12 * x.norm()) << j;
  }
  // A block of columns of a larger matrix (its leading dimension is not its row count).
  Eigen::MatrixXd wide = Eigen::MatrixXd::Random(A.rows(), 8);
  const Eigen::MatrixXd wide0 = wide;
  llt.solve_in_place(wide.middleCols(2, 3));
  EXPECT_EQ(wide.col(0), wide0.col(0));
  EXPECT_EQ(wide.col(7), wide0.col(7));
  Eigen::VectorXd x = wide0.col(3);
  llt.solve_in_place(x);
  EXPECT_LT((wide.col(3) - x).norm(), 1e-12 * x.norm());
}

TEST(SupernodalLlt, SameBitsOnOneAndTwoThreads) {
  const Eigen::SparseMatrix<double> A = grain_blocks_matrix(30, 80, 20, 3, 1e-4, 11);
  const Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(A.rows(), 1.0, 3.0);
  Eigen::VectorXd x[2];
  const int saved = omp_get_max_threads();
  for (int t = 1; t <= 2; ++t) {
    omp_set_num_threads(t);
    SupernodalLlt llt;
    ASSERT_TRUE(llt.compute(A, 1e-8));
    x[t - 1] = b;
    llt.solve_in_place(x[t - 1]);
  }
  omp_set_num_threads(saved);
  for (Eigen::Index i = 0; i < b.size(); ++i) ASSERT_EQ(x[0][i], x[1][i]) << i;
}

TEST(SupernodalLlt, ReportsAMatrixThatIsNotPositiveDefinite) {
  Eigen::SparseMatrix<double> A = grid_matrix(10, 10, 1e-3, 1);
  A.coeffRef(37, 37) = -1.0;
  SupernodalLlt llt;
  EXPECT_FALSE(llt.compute(A, 0.0));
  EXPECT_FALSE(llt.ok());
  // Usable again afterwards.
  EXPECT_TRUE(llt.compute(grid_matrix(10, 10, 1e-3, 1), 0.0));
}

}  // namespace
