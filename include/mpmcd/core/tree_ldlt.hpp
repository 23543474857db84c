#pragma once
/// Eigen's SimplicialLDLT with its numeric factorisation on the threads by subtrees of the
/// elimination tree (docs/parallel.md, "The pivoting's factorisation on the threads").
/// The up-looking factorisation computes row k of L by a sparse triangular solve over the
/// columns of k's descendants in the elimination tree, and writes only into those columns
/// (Davis, Direct Methods for Sparse Linear Systems, 2006, §4.7, §4.8): disjoint subtrees are
/// independent. The tree is split into disjoint subtrees and the rows above them (the top,
/// closed under parents). The subtrees' rows are factorised on the threads, each subtree in
/// ascending order on one thread; then each top row in ascending order, its solve over each
/// subtree's columns on the threads (what they subtract from the top's rows kept per subtree)
/// and its solve over the top's columns either on one thread, the subtrees' parts added in
/// subtree order, or, when the top's part of L is dense enough, as the dense Cholesky
/// factorisation of the top's Schur complement on the threads (top_dense()). The subtrees' rows
/// are the bits of Eigen's factorize_preordered; a top row differs from Eigen's by the order of
/// its sums (round-off); the split and the choice depend on the matrix only.
#include <Eigen/Dense>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>

#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>
#include "mpmcd/core/timer.hpp"

namespace mpmcd {

/// LDL^T of a symmetric sparse matrix (both triangles stored) plus a shift, with AMD ordering;
/// solve(), matrixL(), vectorD(), permutationP() as Eigen's SimplicialLDLT.
class TreeLdlt : public Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> {
 public:
  /// Orders, analyses and factorises A + shift I [A's units], the numeric part on the threads
  /// by subtrees split for `ways` workers when A has at least `min_size` rows [-] and the split
  /// promises a gain; info() tells success. The split depends on A and `ways` only, not on the
  /// thread count, so the factor is the same bits on any number of threads.
  void compute_on_threads(const Eigen::SparseMatrix<double>& A, int ways = 2, int min_size = 1000);

  /// compute_on_threads() in two parts: analyze() orders A and counts L's entries per column
  /// (symbolic_flops(), order()), factorize_analyzed() then factorises A + shift I.
  void analyze(const Eigen::SparseMatrix<double>& A);
  /// The numeric part of compute_on_threads() after analyze(A) [-].
  void factorize_analyzed(int ways = 2, int min_size = 1000);
  /// After analyze(): the sum over L's columns of their entry count (below the diagonal)
  /// squared, the numeric factorisation's multiply-adds to leading order [-].
  double symbolic_flops() const { return symbolic_flops_; }
  /// After analyze(): the fill-reducing order, the k-th pivot is row order()[k] [-].
  const Eigen::VectorXi& order() const { return m_Pinv.indices(); }

  /// b := (A + shift I)^-1 b [b's units over A's], in place. After a split factorisation the
  /// forward substitution runs by the same subtrees on the threads, then the top rows, each
  /// way's part of them added in way order; the backward one the top rows first, then the
  /// subtrees on the threads (Davis 2006, §4.7: column j of L only reaches j's ancestors); a
  /// dense top's part of both is two dense triangular solves with its Cholesky factor. The
  /// same bits on any thread count and inside a parallel region (one thread); to round-off
  /// Eigen's solve() (the top rows' sums in another order). Unsplit: Eigen's solve().
  void solve_in_place(Eigen::VectorXd& b) const;

  /// Timers whose stage kThreadedStage gets the wall time of the threaded regions [s] (null:
  /// none); not owned.
  void set_timers(StageTimers* timers) { timers_ = timers; }

  /// Estimated speedup of the last numeric factorisation's split over one thread: the work
  /// (sum over columns of c (c - 1) / 2, c their entries) divided by the largest way's subtrees'
  /// plus the top's [-]; 1 when it was not split.
  double split_speedup() const { return split_speedup_; }
  /// Rows of the last factorisation's top [-].
  std::int64_t top_rows() const { return static_cast<std::int64_t>(top_.size()); }

  /// How the top rows are factorised: `automatic` chooses by the density of their part of L.
  enum class TopMode {
    automatic,  ///< dense when its flops are not many more than the sparse loop's (split())
    sparse,     ///< the up-looking rows on one thread, as Eigen's loop
    dense,      ///< the dense Schur complement on the threads (top_dense())
  };
  /// Sets how the next factorisations treat the top rows (default: automatic).
  void set_top_mode(TopMode mode) { top_mode_ = mode; }
  /// Whether the last factorisation's top rows were factorised dense.
  bool top_was_dense() const { return top_dense_; }

 private:
  // One way of the split: its subtrees' rows and work arrays, and its parts of the top rows.
  struct Bin {
    std::vector<std::int32_t> rows;  // its subtrees' rows, each subtree ascending [-]
    std::vector<double> y;           // the triangular solve's accumulator, zero between rows
    std::vector<std::int32_t> pattern, tags;  // reach stack and visit marks [-]
    /// |top| x |top|, column-major; column t, rows before t: what its columns subtract from the
    /// top's rows (by top position) in top row t
    std::vector<double> contributions;
    std::vector<double> partial_d;        // per top row: what its columns subtract from D_kk
    std::vector<std::int32_t> start_ptr;  // per top row: its range of `starts` [-]
    std::vector<std::int32_t> starts;     // top rows where the reach leaves the subtrees [-]
  };
  // Chooses the top rows (top_, ascending) and the subtrees below them, dealt to `ways` bins,
  // from the elimination tree m_parent and the column counts; leaves bins_ empty when the split
  // would not pay.
  void split(const Eigen::SparseMatrix<double>& ap, int ways);
  // Row k of L and D (Eigen's factorize_preordered, LDL^T): false if D_kk = 0.
  bool factor_row(const Eigen::SparseMatrix<double>& ap, Eigen::Index k, double* y,
                  std::int32_t* pattern, std::int32_t* tags);
  // The numeric part of row k's solve over its reach pattern[top:] (topological order): L(k, i)
  // appended to column i, returns D_kk from d; add(i, y_i) (a callable, or nullptr for none)
  // adds to y_i as it is used.
  template <class Add>
  double eliminate(std::int32_t k, std::int32_t top, const std::int32_t* pattern, double* y,
                   double d, const Add& add);
  // Top row t's solve over bin b's columns.
  void top_row_part(const Eigen::SparseMatrix<double>& ap, std::size_t t, std::int32_t b, Bin& bin);
  // Top row t's reach over the top's columns, in topological order in pattern[returned:]; tags
  // marks it, and column k = top_[t] of L is emptied.
  std::int32_t top_reach(const Eigen::SparseMatrix<double>& ap, std::size_t t,
                         std::int32_t* pattern, std::int32_t* tags);
  // Top row t's solve over the top's columns and D_kk: false if D_kk = 0.
  bool top_row_rest(const Eigen::SparseMatrix<double>& ap, std::size_t t, double* y,
                    std::int32_t* pattern, std::int32_t* tags);
  // The top rows by the Cholesky factorisation of their Schur complement (A's top block, the
  // shift and the ways' parts) as a dense matrix on the threads, its entries then written into
  // L along the rows' reach (the structural zeros of L come out of it as exact zeros): false if
  // the complement is not positive definite (L's top columns not written).
  bool top_dense(const Eigen::SparseMatrix<double>& ap);

  bool split_ = false;                     ///< the last factorisation was split
  std::vector<Bin> bins_;                  ///< the split's ways (their storage kept between calls)
  std::vector<std::int32_t> top_;          ///< rows above the subtrees, ascending [-]
  std::vector<std::int32_t> top_pos_;      ///< per row: its index in top_, or -1 [-]
  std::vector<std::int32_t> owner_;        ///< per row: its bin, -1 in the top [-]
  std::vector<int> below_;                 ///< per subtree column: its entries in its subtree [-]
  double split_speedup_ = 1.0;             ///< see split_speedup() [-]
  TopMode top_mode_ = TopMode::automatic;  ///< see set_top_mode()
  bool top_dense_ = false;                 ///< the split chose a dense top (see top_was_dense())
  std::vector<double> schur_;      ///< the top's Schur complement, then its U (top_dense()) [A's]
  StageTimers* timers_ = nullptr;  ///< see set_timers()
  CholMatrixType permuted_;        ///< P A P^T's upper triangle (analyze())
  double symbolic_flops_ = 0;      ///< see symbolic_flops() [-]
};

}  // namespace mpmcd
