#pragma once
/// The dense kernels of the grains factorised as dense matrices (Settings::dense_fill,
/// docs/three_d.md): LAPACK and BLAS from OpenBLAS, whose kernels are chosen at run time for the
/// CPU (AVX2, AVX-512) while mpmcd itself is built for portable SSE2. OpenBLAS runs on one thread
/// here (the grains are already on the OpenMP threads), so the results do not depend on the
/// thread count; they may differ in round-off between CPU types.
#include <Eigen/Core>

namespace mpmcd::dense {

/// OpenBLAS's name of the kernels in use (e.g. "SkylakeX", "Haswell", "Prescott").
const char* kernels();

/// Whether mpmcd chose the kernels again at start-up: OpenBLAS had fallen back to "Prescott" on
/// a CPU with AVX2 or AVX-512 that it does not know, and OPENBLAS_CORETYPE was not set.
bool kernels_reselected();

/// In-place Cholesky factorisation A = L L^T of the symmetric matrix whose lower triangle A holds
/// (LAPACK dpotrf); L in the lower triangle, the strict upper triangle untouched. False when A is
/// not positive definite (A's content is then unspecified).
bool cholesky_in_place(Eigen::MatrixXd& A);

/// B <- L^-1 B for the lower-triangular L of cholesky_in_place (BLAS dtrsm); B is n x m.
void lower_solve(const Eigen::MatrixXd& L, Eigen::Ref<Eigen::MatrixXd> B);

/// x <- L^-T x (BLAS dtrsv).
void lower_transpose_solve(const Eigen::MatrixXd& L, Eigen::VectorXd& x);

/// x <- (L L^T)^-1 x (LAPACK dpotrs).
void cholesky_solve(const Eigen::MatrixXd& L, Eigen::VectorXd& x);

/// In-place Cholesky factorisation A = U^T U of the n x n column-major symmetric matrix whose
/// upper triangle `a` holds (leading dimension n), by blocks of `block` rows on the OpenMP
/// threads (right-looking: LAPACK dpotrf on each diagonal block, BLAS dtrsm on its row, dsyrk
/// and dgemm on the trailing blocks; Golub & Van Loan, Matrix Computations, 4th ed., Alg.
/// 4.2.10). Each block's sequence of kernels is fixed, so the bits do not depend on the thread
/// count. U in the upper triangle, the strict lower triangle untouched. False when A is not
/// positive definite (its content is then unspecified).
bool cholesky_upper_on_threads(double* a, int n, int block = 96);

/// x <- (U^T U)^-1 x for the n x n upper-triangular U of cholesky_upper_on_threads (leading
/// dimension n; BLAS dtrsv twice, on the calling thread).
void upper_cholesky_solve(const double* u, int n, double* x);

/// G = Y^T Y, both triangles (BLAS dsyrk on the lower one, mirrored); Y is n x m, G becomes
/// m x m.
void gram(const Eigen::Ref<const Eigen::MatrixXd>& Y, Eigen::MatrixXd& G);

}  // namespace mpmcd::dense
