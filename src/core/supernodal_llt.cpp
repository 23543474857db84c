#include "mpmcd/core/supernodal_llt.hpp"

#include <omp.h>
#include <suitesparse/cholmod.h>

#include <vector>

namespace mpmcd {

namespace {
// OpenBLAS built for OpenMP takes its thread count from omp_get_max_threads() at each call made
// outside a parallel region (openblas_set_num_threads(1) does not hold there), and its threaded
// kernels change the bits with the thread count (SupernodalLlt.SameBitsOnOneAndTwoThreads): one
// OpenMP thread while CHOLMOD runs, the caller's count restored after.
class OneOpenMpThread {
 public:
  OneOpenMpThread() : saved_(omp_get_max_threads()) { omp_set_num_threads(1); }
  ~OneOpenMpThread() { omp_set_num_threads(saved_); }
  OneOpenMpThread(const OneOpenMpThread&) = delete;
  OneOpenMpThread& operator=(const OneOpenMpThread&) = delete;

 private:
  int saved_;
};
}  // namespace

struct SupernodalLlt::Impl {
  cholmod_common common{};
  cholmod_factor* factor = nullptr;
  // cholmod_solve2's reusable solution and workspaces.
  mutable cholmod_dense *x = nullptr, *y = nullptr, *e = nullptr;
  bool ok = false;
  double lnz = 0, fl = 0;

  Impl() {
    cholmod_start(&common);
    common.print = 0;  // failures are reported by the return values
    common.supernodal = CHOLMOD_SUPERNODAL;
    common.final_asis = 1;  // keep the supernodal factor as it is made
  }
  ~Impl() {
    release_workspace();
    if (factor != nullptr) cholmod_free_factor(&factor, &common);
    cholmod_finish(&common);
  }
  Impl(const Impl&) = delete;
  Impl& operator=(const Impl&) = delete;

  void release_workspace() const {
    auto* c = const_cast<cholmod_common*>(&common);
    if (x != nullptr) cholmod_free_dense(&x, c);
    if (y != nullptr) cholmod_free_dense(&y, c);
    if (e != nullptr) cholmod_free_dense(&e, c);
  }

  // x := (A + shift I)^-1 b for the n x k column-major b with leading dimension ld, in place.
  void solve(double* b, Eigen::Index n, Eigen::Index k, Eigen::Index ld) const {
    if (!ok || n == 0 || k == 0) return;
    cholmod_dense rhs{};
    rhs.nrow = static_cast<size_t>(n);
    rhs.ncol = static_cast<size_t>(k);
    rhs.nzmax = static_cast<size_t>(ld * k);
    rhs.d = static_cast<size_t>(ld);
    rhs.x = b;
    rhs.xtype = CHOLMOD_REAL;
    rhs.dtype = CHOLMOD_DOUBLE;
    auto* c = const_cast<cholmod_common*>(&common);
    const OneOpenMpThread one;
    if (x != nullptr && x->ncol != rhs.ncol) release_workspace();
    cholmod_solve2(CHOLMOD_A, factor, &rhs, nullptr, &x, nullptr, &y, &e, c);
    const auto* out = static_cast<const double*>(x->x);
    for (Eigen::Index j = 0; j < k; ++j)
      for (Eigen::Index i = 0; i < n; ++i)
        b[j * ld + i] = out[j * static_cast<Eigen::Index>(x->d) + i];
  }
};

SupernodalLlt::SupernodalLlt() : impl_(std::make_unique<Impl>()) {}
SupernodalLlt::~SupernodalLlt() = default;
SupernodalLlt::SupernodalLlt(SupernodalLlt&&) noexcept = default;
SupernodalLlt& SupernodalLlt::operator=(SupernodalLlt&&) noexcept = default;

bool SupernodalLlt::compute(const Eigen::SparseMatrix<double>& A, double shift, const int* order) {
  const OneOpenMpThread one;
  if (!impl_) impl_ = std::make_unique<Impl>();
  Impl& m = *impl_;
  m.ok = false;
  m.release_workspace();
  if (m.factor != nullptr) cholmod_free_factor(&m.factor, &m.common);
  if (!A.isCompressed() || A.rows() != A.cols()) return false;
  // A viewed as CHOLMOD's symmetric matrix whose lower triangle is used (stype -1); CHOLMOD
  // takes non-const pointers but does not write through them here.
  cholmod_sparse a{};
  a.nrow = a.ncol = static_cast<size_t>(A.rows());
  a.nzmax = static_cast<size_t>(A.nonZeros());
  a.p = const_cast<int*>(A.outerIndexPtr());
  a.i = const_cast<int*>(A.innerIndexPtr());
  a.x = const_cast<double*>(A.valuePtr());
  a.stype = -1;
  a.itype = CHOLMOD_INT;
  a.xtype = CHOLMOD_REAL;
  a.dtype = CHOLMOD_DOUBLE;
  a.sorted = 1;
  a.packed = 1;
  std::vector<int> perm;
  if (order != nullptr) {
    perm.assign(order, order + A.rows());
    m.common.nmethods = 1;
    m.common.method[0].ordering = CHOLMOD_GIVEN;
  } else {
    m.common.nmethods = 1;
    m.common.method[0].ordering = CHOLMOD_AMD;
  }
  m.common.postorder = 1;
  m.factor = cholmod_analyze_p(&a, order != nullptr ? perm.data() : nullptr, nullptr, 0, &m.common);
  if (m.factor == nullptr || m.common.status < CHOLMOD_OK) return false;
  m.lnz = m.common.lnz;
  m.fl = m.common.fl;
  double beta[2] = {shift, 0.0};
  const int done = cholmod_factorize_p(&a, beta, nullptr, 0, m.factor, &m.common);
  m.ok = done != 0 && m.common.status == CHOLMOD_OK &&
         m.factor->minor == static_cast<size_t>(A.rows());
  return m.ok;
}

void SupernodalLlt::solve_in_place(Eigen::VectorXd& b) const {
  if (impl_) impl_->solve(b.data(), b.size(), 1, b.size());
}

void SupernodalLlt::solve_in_place(Eigen::Ref<Eigen::MatrixXd> B) const {
  if (impl_) impl_->solve(B.data(), B.rows(), B.cols(), B.outerStride());
}

bool SupernodalLlt::ok() const {
  return impl_ && impl_->ok;
}

double SupernodalLlt::factor_nonzeros() const {
  return impl_ ? impl_->lnz : 0.0;
}

double SupernodalLlt::flops() const {
  return impl_ ? impl_->fl : 0.0;
}

}  // namespace mpmcd
