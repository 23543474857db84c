#pragma once
/// Supernodal sparse Cholesky factorisation through SuiteSparse's CHOLMOD (Debian
/// libsuitesparse-dev): L L^T = P (A + shift I) P^T, the columns of L with the same pattern
/// grouped into supernodes whose dense blocks are factorised and updated by BLAS / LAPACK
/// (Ng & Peyton 1993; Chen, Davis, Hager & Rajamanickam, ACM TOMS 35(3), 2008). Where L's
/// columns are long (the active set's W_AA in a dense 3D packing: every pair of contacts on one
/// sphere couples, a mean of ~1,000 entries per column of L) the dense kernels run at several
/// times the speed of a simplicial up-looking loop (TreeLdlt); docs/contact.md, "The supernodal
/// factorisation". OpenBLAS runs on one thread here (the OpenMP default set to 1 around each
/// CHOLMOD call), so the bits do not depend on the thread count.
#include <Eigen/Core>
#include <Eigen/SparseCore>

#include <memory>

namespace mpmcd {

/// Cholesky factor of a sparse symmetric positive definite matrix plus a shift, by CHOLMOD's
/// supernodal method; one object is not to be used by two threads at once.
class SupernodalLlt {
 public:
  SupernodalLlt();
  ~SupernodalLlt();
  SupernodalLlt(SupernodalLlt&&) noexcept;
  SupernodalLlt& operator=(SupernodalLlt&&) noexcept;
  SupernodalLlt(const SupernodalLlt&) = delete;
  SupernodalLlt& operator=(const SupernodalLlt&) = delete;

  /// Analyses and factorises A + shift I [A's units] with the fill-reducing order `order` (the
  /// k-th pivot is row order[k]; null: CHOLMOD's AMD). A is compressed, square and symmetric; its
  /// lower triangle is read. False when A + shift I is not positive definite or CHOLMOD fails
  /// (e.g. an index overflow); the factor is then unusable.
  bool compute(const Eigen::SparseMatrix<double>& A, double shift, const int* order = nullptr);

  /// b := (A + shift I)^-1 b [b's units over A's], in place.
  void solve_in_place(Eigen::VectorXd& b) const;
  /// Each column of B := (A + shift I)^-1 B, in place (one multi-column solve; B's column j
  /// may differ in round-off from solving it alone).
  void solve_in_place(Eigen::Ref<Eigen::MatrixXd> B) const;

  /// Whether a factor is held (the last compute() succeeded).
  bool ok() const;
  /// Entries of L (below and on the diagonal) the analysis counted [-].
  double factor_nonzeros() const;
  /// Floating-point operations of the numeric factorisation the analysis counted [-].
  double flops() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace mpmcd
