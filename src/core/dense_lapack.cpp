// The dense kernels of include/mpmcd/core/dense_lapack.hpp through the Fortran LAPACK / BLAS
// interface of OpenBLAS (Debian libopenblas-openmp-dev), limited to one OpenBLAS thread.
#include "mpmcd/core/dense_lapack.hpp"

#include <omp.h>

#include <algorithm>
#include <cstddef>
#include <cstdlib>
#include <cstring>
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
void dgemm_(const char* transa, const char* transb, const int* m, const int* n, const int* k,
            const double* alpha, const double* a, const int* lda, const double* b, const int* ldb,
            const double* beta, double* c, const int* ldc);
void openblas_set_num_threads(int num_threads);
char* openblas_get_corename();
// OpenBLAS's (DYNAMIC_ARCH) choice of kernels for the CPU, exported by libopenblas but not in its
// header: weak, so that a build without them only keeps OpenBLAS's own choice.
void gotoblas_dynamic_init() __attribute__((weak));
void gotoblas_dynamic_quit() __attribute__((weak));
}

namespace mpmcd::dense {

namespace {
// Debian 12's OpenBLAS 0.3.21 takes its SSE3 "Prescott" kernels on CPUs newer than its table
// (e.g. family 6, model 207), about half the speed of its AVX-512 ones there (docs/parallel.md,
// "OpenBLAS runs its Prescott kernels on this machine"). Then, unless the user chose a core
// (OPENBLAS_CORETYPE), the choice is made again with the core the CPU's features allow, as
// OpenBLAS does at load time for OPENBLAS_CORETYPE. Run before main (a static initialiser of
// this file, after OpenBLAS's own), single-threaded and before any BLAS call.
bool select_kernels() {
  const char* chosen = std::getenv("OPENBLAS_CORETYPE");
  if ((chosen != nullptr && *chosen != 0) || gotoblas_dynamic_init == nullptr ||
      gotoblas_dynamic_quit == nullptr || std::strcmp(openblas_get_corename(), "Prescott") != 0)
    return false;
  __builtin_cpu_init();
  const char* core = nullptr;
  if (__builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512dq") &&
      __builtin_cpu_supports("avx512bw") && __builtin_cpu_supports("avx512vl")) {
    core = "SkylakeX";
  } else if (__builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma")) {
    core = "Haswell";
  }
  if (core == nullptr) return false;
  setenv("OPENBLAS_CORETYPE", core, 0);
  gotoblas_dynamic_quit();
  gotoblas_dynamic_init();
  unsetenv("OPENBLAS_CORETYPE");
  return true;
}
const bool kernels_selected = select_kernels();

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

const char* kernels() {
  return openblas_get_corename();
}

bool kernels_reselected() {
  return kernels_selected;
}

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

bool cholesky_upper_on_threads(double* a, int n, int block) {
  one_thread();
  const int nblocks = (n + block - 1) / block;
  const auto at = [&](int r, int c) { return a + static_cast<std::ptrdiff_t>(c) * n + r; };
  const auto size = [&](int b) { return std::min(block, n - b * block); };
  const double one = 1.0, minus_one = -1.0;
  bool ok = true;
  const int threads = omp_in_parallel() ? 1 : omp_get_max_threads();
#pragma omp parallel num_threads(threads)
  for (int j = 0; j < nblocks; ++j) {
    const int jb = size(j), j0 = j * block;
    // Diagonal block: U_jj^T U_jj = A_jj (its trailing updates done).
#pragma omp single
    {
      int info = 0;
      dpotrf_("U", &jb, at(j0, j0), &n, &info);
      if (info != 0) ok = false;
    }  // implicit barrier: all threads see ok
    if (!ok) break;
      // Its row: U_jc = U_jj^-T A_jc.
#pragma omp for schedule(dynamic, 1)
    for (int c = j + 1; c < nblocks; ++c) {
      const int cb = size(c);
      dtrsm_("L", "U", "T", "N", &jb, &cb, &one, at(j0, j0), &n, at(j0, c * block), &n);
    }
    // Trailing blocks r <= c: A_rc -= U_jr^T U_jc.
    const int m = nblocks - j - 1;
#pragma omp for schedule(dynamic, 1)
    for (int pair = 0; pair < m * (m + 1) / 2; ++pair) {
      int c = 0;
      while ((c + 1) * (c + 2) / 2 <= pair) ++c;
      const int r = pair - c * (c + 1) / 2 + j + 1;
      c += j + 1;
      const int rb = size(r), cb = size(c), r0 = r * block, c0 = c * block;
      if (r == c) {
        dsyrk_("U", "T", &rb, &jb, &minus_one, at(j0, r0), &n, &one, at(r0, r0), &n);
      } else {
        dgemm_("T", "N", &rb, &cb, &jb, &minus_one, at(j0, r0), &n, at(j0, c0), &n, &one,
               at(r0, c0), &n);
      }
    }
  }
  return ok;
}

void upper_cholesky_solve(const double* u, int n, double* x) {
  one_thread();
  const int inc = 1;
  if (n <= 0) return;
  dtrsv_("U", "T", "N", &n, u, &n, x, &inc);  // U^T y = x
  dtrsv_("U", "N", "N", &n, u, &n, x, &inc);  // U x = y
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
