// The dense kernels of the dense grain factorisations (core/dense_lapack.hpp) against Eigen's,
// and the OpenMP thread count left as it was (OpenBLAS built for OpenMP would set it to 1).
#include <gtest/gtest.h>
#include <omp.h>

#include <Eigen/Dense>

#include "mpmcd/core/dense_lapack.hpp"

using namespace mpmcd;

TEST(DenseLapack, CholeskySolvesAndGramMatchEigenAndKeepTheThreadCount) {
  const int saved = omp_get_max_threads();
  omp_set_num_threads(2);
  const Eigen::Index n = 150, m = 40;
  const Eigen::MatrixXd R = Eigen::MatrixXd::Random(n, n);
  const Eigen::MatrixXd A =
      R * R.transpose() + static_cast<double>(n) * Eigen::MatrixXd::Identity(n, n);
  Eigen::MatrixXd L = A;
  ASSERT_TRUE(dense::cholesky_in_place(L));
  EXPECT_EQ(omp_get_max_threads(), 2);
  const Eigen::MatrixXd Le = A.llt().matrixL();
  const Eigen::MatrixXd Ll = L.triangularView<Eigen::Lower>();
  EXPECT_LE((Ll - Le).norm(), 1e-13 * Le.norm());
  // L^-1 B, then Y^T Y against Eigen.
  const Eigen::MatrixXd B = Eigen::MatrixXd::Random(n, m);
  Eigen::MatrixXd Y = B;
  dense::lower_solve(L, Y);
  const Eigen::MatrixXd Ye = Le.triangularView<Eigen::Lower>().solve(B);
  EXPECT_LE((Y - Ye).norm(), 1e-12 * Ye.norm());
  Eigen::MatrixXd G;
  dense::gram(Y, G);
  EXPECT_LE((G - Ye.transpose() * Ye).norm(), 1e-12 * G.norm());
  EXPECT_EQ((G - G.transpose()).norm(), 0.0);
  // Solves with one right-hand side.
  const Eigen::VectorXd b = Eigen::VectorXd::Random(n);
  Eigen::VectorXd x = b;
  dense::cholesky_solve(L, x);
  EXPECT_LE((A * x - b).norm(), 1e-12 * b.norm());
  Eigen::VectorXd z = b;
  dense::lower_transpose_solve(L, z);
  EXPECT_LE((Le.transpose() * z - b).norm(), 1e-12 * b.norm());
  // Not positive definite: refused.
  Eigen::MatrixXd I = -Eigen::MatrixXd::Identity(3, 3);
  EXPECT_FALSE(dense::cholesky_in_place(I));
  EXPECT_EQ(omp_get_max_threads(), 2);
#pragma omp parallel
  {
#pragma omp single
    EXPECT_EQ(omp_get_num_threads(), 2);
  }
  omp_set_num_threads(saved);
}
