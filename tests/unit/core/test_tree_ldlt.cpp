// TreeLdlt: unsplit, Eigen's SimplicialLDLT loop on SuiteSparse AMD's order; split into subtrees
// on the threads, the same factor to round-off and the same bits on 1 and 2 threads; its
// substitutions on the threads; a zero pivot reported.
#include <gtest/gtest.h>
#include <omp.h>

#include <Eigen/SparseCholesky>
#include <algorithm>
#include <cmath>

#include "../../support/sparse_matrices.hpp"
#include "mpmcd/core/tree_ldlt.hpp"

namespace {

using mpmcd::test_support::grid_matrix;

// Factorises `A` + shift I by `tree` on `threads` threads, split for 2.
void tree_factor(mpmcd::TreeLdlt& tree, const Eigen::SparseMatrix<double>& A, double shift,
                 int threads) {
  const int saved = omp_get_max_threads();
  omp_set_num_threads(threads);
  tree.setShift(shift);
  tree.compute_on_threads(A, 2, 100);
  omp_set_num_threads(saved);
}

void expect_same_bits(const mpmcd::TreeLdlt& a, const mpmcd::TreeLdlt& b) {
  const auto& La = a.matrixL().nestedExpression();
  const auto& Lb = b.matrixL().nestedExpression();
  ASSERT_EQ(La.nonZeros(), Lb.nonZeros());
  for (Eigen::Index k = 0; k < La.nonZeros(); ++k) {
    ASSERT_EQ(La.innerIndexPtr()[k], Lb.innerIndexPtr()[k]) << k;
    ASSERT_EQ(La.valuePtr()[k], Lb.valuePtr()[k]) << k;
  }
  ASSERT_EQ(a.vectorD(), b.vectorD());
}

// The largest difference between the values of two factors of the same pattern (checked).
double worst_difference(const mpmcd::TreeLdlt& a, const mpmcd::TreeLdlt& b) {
  const auto& La = a.matrixL().nestedExpression();
  const auto& Lb = b.matrixL().nestedExpression();
  EXPECT_EQ(La.nonZeros(), Lb.nonZeros());
  double worst = 0;
  for (Eigen::Index k = 0; k < std::min(La.nonZeros(), Lb.nonZeros()); ++k) {
    EXPECT_EQ(La.innerIndexPtr()[k], Lb.innerIndexPtr()[k]) << k;
    worst = std::max(worst, std::abs(La.valuePtr()[k] - Lb.valuePtr()[k]));
  }
  return worst;
}

// |(A + shift I) x - b| / |b|.
double relative_residual(const Eigen::SparseMatrix<double>& A, double shift,
                         const Eigen::VectorXd& x, const Eigen::VectorXd& b) {
  Eigen::SparseMatrix<double> I(A.rows(), A.cols());
  I.setIdentity();
  const Eigen::SparseMatrix<double> shifted = A + shift * I;
  return (shifted * x - b).norm() / b.norm();
}

TEST(TreeLdlt, OneWayIsEigensLoopOnItsOrdering) {
  // Without a split, the numeric factorisation is Eigen's on the matrix permuted by AMD's
  // order: Eigen's SimplicialLDLT without ordering on P A P^T gives the same bits.
  const Eigen::SparseMatrix<double> A = grid_matrix(30, 30, 1e-2, 3);
  mpmcd::TreeLdlt tree;
  tree.compute_on_threads(A, 1, 100);
  ASSERT_EQ(tree.info(), Eigen::Success);
  EXPECT_EQ(tree.split_speedup(), 1.0);
  EXPECT_EQ(tree.top_rows(), 0);
  Eigen::SparseMatrix<double> permuted(A.rows(), A.cols());
  permuted.selfadjointView<Eigen::Upper>() =
      A.selfadjointView<Eigen::Lower>().twistedBy(tree.permutationP());
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>, Eigen::Upper, Eigen::NaturalOrdering<int>>
      eigen(permuted);
  ASSERT_EQ(eigen.info(), Eigen::Success);
  EXPECT_EQ(eigen.vectorD(), tree.vectorD());
  const auto& L1 = eigen.matrixL().nestedExpression();
  const auto& L2 = tree.matrixL().nestedExpression();
  ASSERT_EQ(L1.nonZeros(), L2.nonZeros());
  for (Eigen::Index k = 0; k < L1.nonZeros(); ++k) ASSERT_EQ(L1.valuePtr()[k], L2.valuePtr()[k]);
}

TEST(TreeLdlt, SplitAgreesToRoundOffAndGivesTheSameBitsOnOneAndTwoThreads) {
  const Eigen::SparseMatrix<double> A = grid_matrix(60, 50, 1e-3, 7);
  const double shift = 1e-9;
  mpmcd::TreeLdlt serial;
  serial.setShift(shift);
  serial.compute_on_threads(A, 1, 100);
  ASSERT_EQ(serial.info(), Eigen::Success);
  mpmcd::TreeLdlt two, one;
  tree_factor(two, A, shift, 2);
  tree_factor(one, A, shift, 1);
  ASSERT_EQ(two.info(), Eigen::Success);
  // The split was used: subtrees on the threads under a top of a few hundred rows.
  EXPECT_GT(two.split_speedup(), 1.5);
  EXPECT_GT(two.top_rows(), 0);
  EXPECT_LT(two.top_rows(), 400);
  expect_same_bits(two, one);
  // The unsplit factor: the same pattern, values to round-off.
  const double worst = worst_difference(serial, two);
  EXPECT_GT(worst, 0.0);  // the top rows sum in another order
  EXPECT_LT(worst, 1e-10);
  EXPECT_LT((serial.vectorD() - two.vectorD()).cwiseAbs().maxCoeff(),
            1e-12 * serial.vectorD().cwiseAbs().maxCoeff());
  const Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(A.rows(), -1.0, 2.0);
  EXPECT_LT(relative_residual(A, shift, two.solve(b), b), 1e-9);
}

TEST(TreeLdlt, SubstitutionsOnTheThreadsAgreeWithEigensSolveAndGiveTheSameBits) {
  // solve_in_place after a split factorisation: the subtrees' substitutions on the threads, the
  // top's on one; against Eigen's solve() with the same factor to round-off, the same bits on
  // 1 and 2 threads and inside a parallel region, and the residual of A + shift I.
  const Eigen::SparseMatrix<double> A = grid_matrix(60, 50, 1e-3, 7);
  const double shift = 1e-9;
  mpmcd::TreeLdlt tree;
  tree_factor(tree, A, shift, 2);
  ASSERT_GT(tree.top_rows(), 0);
  Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(A.rows(), -1.0, 2.0);
  b[7] = 0.0;  // a zero entry: the forward substitution skips its column
  const Eigen::VectorXd eigen = tree.solve(b);
  const int saved = omp_get_max_threads();
  Eigen::VectorXd two = b, one = b, nested = b;
  omp_set_num_threads(2);
  tree.solve_in_place(two);
#pragma omp parallel num_threads(2)
  {
#pragma omp single
    tree.solve_in_place(nested);
  }
  omp_set_num_threads(1);
  tree.solve_in_place(one);
  omp_set_num_threads(saved);
  EXPECT_EQ(two, one);
  EXPECT_EQ(two, nested);
  const double scale = eigen.cwiseAbs().maxCoeff();
  EXPECT_GT((two - eigen).cwiseAbs().maxCoeff(), 0.0);  // the top rows sum in another order
  EXPECT_LT((two - eigen).cwiseAbs().maxCoeff(), 1e-11 * scale);
  EXPECT_LT(relative_residual(A, shift, two, b), 1e-9);
  // Unsplit, it is Eigen's solve().
  mpmcd::TreeLdlt whole;
  whole.setShift(shift);
  whole.compute_on_threads(A, 1, 100);
  Eigen::VectorXd w = b;
  whole.solve_in_place(w);
  EXPECT_EQ(w, whole.solve(b));
}

// Factorises `A` + shift I by `tree` split for 2 on `threads` threads, its top rows `mode`.
void tree_factor(mpmcd::TreeLdlt& tree, const Eigen::SparseMatrix<double>& A, double shift,
                 int threads, mpmcd::TreeLdlt::TopMode mode) {
  tree.set_top_mode(mode);
  tree_factor(tree, A, shift, threads);
}

TEST(TreeLdlt, DenseTopAgreesWithTheSparseTopToRoundOffAndGivesTheSameBits) {
  // The top rows by the dense Cholesky factorisation of their Schur complement on the threads:
  // the same pattern of L as the up-looking rows (its structural zeros exact zeros), the values
  // to round-off, the same bits on 1 and 2 threads; the solve with the dense top.
  using Mode = mpmcd::TreeLdlt::TopMode;
  const Eigen::SparseMatrix<double> A = grid_matrix(60, 50, 1e-3, 7);
  const double shift = 1e-9;
  mpmcd::TreeLdlt sparse, two, one;
  tree_factor(sparse, A, shift, 2, Mode::sparse);
  tree_factor(two, A, shift, 2, Mode::dense);
  tree_factor(one, A, shift, 1, Mode::dense);
  ASSERT_EQ(sparse.info(), Eigen::Success);
  ASSERT_EQ(two.info(), Eigen::Success);
  EXPECT_FALSE(sparse.top_was_dense());
  EXPECT_TRUE(two.top_was_dense());
  ASSERT_GT(two.top_rows(), 0);
  expect_same_bits(two, one);
  const double worst = worst_difference(sparse, two);
  EXPECT_GT(worst, 0.0);
  EXPECT_LT(worst, 1e-10);
  EXPECT_LT((sparse.vectorD() - two.vectorD()).cwiseAbs().maxCoeff(),
            1e-12 * sparse.vectorD().cwiseAbs().maxCoeff());
  // The solve: the top's part by the dense factor, against the sparse top's to round-off, the
  // same bits on 1 and 2 threads.
  const Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(A.rows(), -1.0, 2.0);
  Eigen::VectorXd x = b, x1 = b, xs = b;
  const int saved = omp_get_max_threads();
  omp_set_num_threads(2);
  two.solve_in_place(x);
  sparse.solve_in_place(xs);
  omp_set_num_threads(1);
  two.solve_in_place(x1);
  omp_set_num_threads(saved);
  EXPECT_EQ(x, x1);
  EXPECT_LT((x - xs).cwiseAbs().maxCoeff(), 1e-11 * xs.cwiseAbs().maxCoeff());
  EXPECT_LT(relative_residual(A, shift, x, b), 1e-9);
}

TEST(TreeLdlt, DenseTopFallsBackToTheSparseRowsWhenNotPositiveDefinite) {
  // -A: LDL^T exists (all pivots negative), Cholesky does not; the top rows then come from the
  // up-looking loop, the same bits as asked for it.
  using Mode = mpmcd::TreeLdlt::TopMode;
  const Eigen::SparseMatrix<double> A = -grid_matrix(60, 50, 1e-3, 7);
  mpmcd::TreeLdlt sparse, dense;
  tree_factor(sparse, A, 0.0, 2, Mode::sparse);
  tree_factor(dense, A, 0.0, 2, Mode::dense);
  ASSERT_EQ(dense.info(), Eigen::Success);
  EXPECT_FALSE(dense.top_was_dense());
  expect_same_bits(sparse, dense);
  EXPECT_LT(dense.vectorD().maxCoeff(), 0.0);
}

TEST(TreeLdlt, ZeroPivotIsReported) {
  // A singular matrix (the grid's couplings without a diagonal term have the constant-like
  // null vector of a signed graph Laplacian only if balanced; a zero block is singular for sure).
  Eigen::SparseMatrix<double> A = grid_matrix(40, 40, 1e-3, 5);
  A.coeffRef(0, 0) = 0.0;
  for (Eigen::SparseMatrix<double>::InnerIterator it(A, 0); it; ++it) it.valueRef() = 0.0;
  for (Eigen::Index j = 0; j < A.cols(); ++j)
    for (Eigen::SparseMatrix<double>::InnerIterator it(A, j); it; ++it)
      if (it.row() == 0) it.valueRef() = 0.0;
  mpmcd::TreeLdlt tree;
  tree_factor(tree, A, 0.0, 2);
  EXPECT_EQ(tree.info(), Eigen::NumericalIssue);
}

}  // namespace
