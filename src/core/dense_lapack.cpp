// The dense kernels of include/mpmcd/core/dense_lapack.hpp through the Fortran LAPACK / BLAS
// interface of OpenBLAS (Debian libopenblas-openmp-dev), limited to one OpenBLAS thread.
#include "mpmcd/core/dense_lapack.hpp"

#include <omp.h>

#include <algorithm>
#include <mutex>

extern "C" {
void dpotrf_(const char* uplo, const int* n, double* a, const int* lda, int* info);
void dpotrs_(const char* uplo, const int* n, const int* nrhs, const double* a, const int* lda,
             double* b, const int* ldb, int* info);
void dtrsm_(const char* side, const char* uplo, const char* transa, const char* diag, const int* m,
            const int* n, const double* alpha, const double* a, const int* lda, double* b,
            const int* ldb);
void dtrsv_(const char* uplo, const char* trans, const char* diag, const int* n, const double* a,
            const int* lda, double* x, const int* incx);
void dsyrk_(const char* uplo, const char* trans, const int* n, const int* k, const double* alpha,
            const double* a, const int* lda, const double* beta, double* c, const int* ldc);
void openblas_set_num_threads(int num_threads);
}

namespace mpmcd::dense {

namespace {
// One OpenBLAS thread, set before the first call: the callers are on the OpenMP threads already,
// and a threaded BLAS would make the sums depend on the thread count. OpenBLAS built for OpenMP
// also sets the OpenMP default thread count of the calling thread to 1 (omp_set_num_threads):
// restored, or every later parallel region of mpmcd would run on one thread.
void one_thread() {
  static std::once_flag once;
  std::call_once(once, [] {
    const int threads = omp_get_max_threads();
    openblas_set_num_threads(1);
    omp_set_num_threads(threads);
  });
}
int as_int(Eigen::Index n) {
  return static_cast<int>(n);
}
}  // namespace

bool cholesky_in_place(Eigen::MatrixXd& A) {
  one_thread();
  const int n = as_int(A.rows()), lda = std::max(1, n);
  int info = 0;
  if (n > 0) dpotrf_("L", &n, A.data(), &lda, &info);
  return info == 0;
}

void lower_solve(const Eigen::MatrixXd& L, Eigen::Ref<Eigen::MatrixXd> B) {
  one_thread();
  const int n = as_int(L.rows()), m = as_int(B.cols()), lda = std::max(1, n),
            ldb = std::max(1, as_int(B.outerStride()));
  const double one = 1.0;
  if (n > 0 && m > 0) dtrsm_("L", "L", "N", "N", &n, &m, &one, L.data(), &lda, B.data(), &ldb);
}

void lower_transpose_solve(const Eigen::MatrixXd& L, Eigen::VectorXd& x) {
  one_thread();
  const int n = as_int(L.rows()), lda = std::max(1, n), inc = 1;
  if (n > 0) dtrsv_("L", "T", "N", &n, L.data(), &lda, x.data(), &inc);
}

void cholesky_solve(const Eigen::MatrixXd& L, Eigen::VectorXd& x) {
  one_thread();
  const int n = as_int(L.rows()), lda = std::max(1, n), nrhs = 1;
  int info = 0;
  if (n > 0) dpotrs_("L", &n, &nrhs, L.data(), &lda, x.data(), &lda, &info);
}

void gram(const Eigen::Ref<const Eigen::MatrixXd>& Y, Eigen::MatrixXd& G) {
  one_thread();
  const int n = as_int(Y.rows()), m = as_int(Y.cols()), lda = std::max(1, as_int(Y.outerStride())),
            ldc = std::max(1, m);
  const double one = 1.0, zero = 0.0;
  G.resize(m, m);
  if (m == 0) return;
  if (n == 0) {
    G.setZero();
    return;
  }
  dsyrk_("L", "T", &m, &n, &one, Y.data(), &lda, &zero, G.data(), &ldc);
  G.triangularView<Eigen::StrictlyUpper>() = G.transpose();
}

}  // namespace mpmcd::dense
