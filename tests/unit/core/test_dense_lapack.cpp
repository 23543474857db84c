// The dense kernels of the dense grain factorisations (core/dense_lapack.hpp) against Eigen's,
// and the OpenMP thread count left as it was (OpenBLAS built for OpenMP would set it to 1).
#include <gtest/gtest.h>
#include <omp.h>

#include <Eigen/Dense>
#include <cstdlib>

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

TEST(DenseLapack, BlockedUpperCholeskyOnTheThreadsMatchesEigenWithTheSameBits) {
  // U^T U = A by blocks on the threads (n not a multiple of the block, so a ragged last block):
  // Eigen's factor to round-off, the strict lower triangle untouched, the same bits on 1 and 2
  // threads and inside a parallel region; a matrix that is not positive definite refused.
  const int saved = omp_get_max_threads();
  const int n = 203, block = 48;
  const Eigen::MatrixXd R = Eigen::MatrixXd::Random(n, n);
  const Eigen::MatrixXd A = R * R.transpose() + n * Eigen::MatrixXd::Identity(n, n);
  const auto factor = [&](int threads, bool nested) {
    Eigen::MatrixXd U = A;
    U.triangularView<Eigen::StrictlyLower>().setConstant(7.0);
    omp_set_num_threads(threads);
    bool ok = false;
    if (nested) {
#pragma omp parallel num_threads(2)
      {
#pragma omp single
        ok = dense::cholesky_upper_on_threads(U.data(), n, block);
      }
    } else {
      ok = dense::cholesky_upper_on_threads(U.data(), n, block);
    }
    omp_set_num_threads(saved);
    EXPECT_TRUE(ok);
    return U;
  };
  const Eigen::MatrixXd two = factor(2, false), one = factor(1, false), nested = factor(2, true);
  EXPECT_EQ(two, one);
  EXPECT_EQ(two, nested);
  EXPECT_EQ((two.triangularView<Eigen::StrictlyLower>().toDenseMatrix().array() == 7.0).count(),
            n * (n - 1) / 2);
  const Eigen::MatrixXd Ue = A.llt().matrixU();
  const Eigen::MatrixXd U = two.triangularView<Eigen::Upper>();
  EXPECT_LE((U - Ue).norm(), 1e-13 * Ue.norm());
  Eigen::MatrixXd N = -A;
  EXPECT_FALSE(dense::cholesky_upper_on_threads(N.data(), n, block));
}

TEST(DenseLapack, KernelsAreNotTheSse3FallbackOnACpuWithAvx2) {
  // OpenBLAS 0.3.21 falls back to "Prescott" on CPUs it does not know; mpmcd then chooses the
  // kernels the CPU's features allow (unless the user set OPENBLAS_CORETYPE).
  __builtin_cpu_init();
  if (std::getenv("OPENBLAS_CORETYPE") != nullptr || !__builtin_cpu_supports("avx2") ||
      !__builtin_cpu_supports("fma"))
    GTEST_SKIP() << "OPENBLAS_CORETYPE set, or no AVX2";
  EXPECT_STRNE(dense::kernels(), "Prescott") << "reselected: " << dense::kernels_reselected();
  // And they compute: a Cholesky factor against Eigen's.
  const Eigen::MatrixXd R = Eigen::MatrixXd::Random(300, 300);
  Eigen::MatrixXd A = R * R.transpose() + 300.0 * Eigen::MatrixXd::Identity(300, 300);
  const Eigen::MatrixXd Le = A.llt().matrixL();
  ASSERT_TRUE(dense::cholesky_in_place(A));
  const Eigen::MatrixXd L = A.triangularView<Eigen::Lower>();
  EXPECT_LE((L - Le).norm(), 1e-13 * Le.norm());
}
