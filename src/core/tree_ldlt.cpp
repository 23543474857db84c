#include "mpmcd/core/tree_ldlt.hpp"

#include "mpmcd/core/dense_lapack.hpp"

#include <omp.h>
#include <suitesparse/amd.h>

#include <algorithm>
#include <functional>
#include <numeric>
#include <queue>
#include <type_traits>
#include <utility>

namespace mpmcd {

namespace {
// Subtrees the split may make, at most, per way [-].
constexpr std::size_t kSubtreesPerWay = 32;
// The split is used only when it promises at least this speedup over one thread [-].
constexpr double kMinSpeedup = 1.15;
// Rows of the top, at most (each way keeps a dense |top| x |top| block of contributions) [-].
constexpr std::size_t kMaxTopRows = 1500;
// Top rows from which a dense top may be chosen [-].
constexpr std::size_t kMinDenseTop = 64;
// Multiply-adds per second of the dense top (its kernels, the complement's assembly and the
// entries' write-back) over the sparse rows' loop, on one thread [-]: the d/8 paper state at
// Phi = 0.95 (20 factorisations of W_AA, 318-672 top rows), 3.1e9 against 0.87e9
// (docs/parallel.md).
constexpr double kDenseRate = 3.5;
}  // namespace

template <class Add>
double TreeLdlt::eliminate(std::int32_t k, std::int32_t top, const std::int32_t* pattern, double* y,
                           double d, const Add& add) {
  // factor_row's loop: for i in pattern[top:] (the reach, in topological order), L(k, i) =
  // y_i / D_ii appended to column i, y minus column i times y_i, D_kk minus L(k, i) y_i.
  const auto size = static_cast<std::int32_t>(m_matrix.rows());
  const int* Lp = m_matrix.outerIndexPtr();
  int* Li = m_matrix.innerIndexPtr();
  double* Lx = m_matrix.valuePtr();
  int* count = m_nonZerosPerCol.data();
  for (; top < size; ++top) {
    const std::int32_t i = pattern[top];
    double yi = y[i];
    if constexpr (!std::is_same_v<Add, std::nullptr_t>) add(i, yi);
    y[i] = 0.0;
    const double l_ki = yi / m_diag[i];
    const int p2 = Lp[i] + count[i];
    int p = Lp[i];
    for (; p < p2; ++p) y[Li[p]] -= Lx[p] * yi;
    d -= l_ki * yi;
    Li[p] = k;
    Lx[p] = l_ki;
    ++count[i];
  }
  return d;
}

void TreeLdlt::compute_on_threads(const Eigen::SparseMatrix<double>& A, int ways, int min_size) {
  analyze(A);
  factorize_analyzed(ways, min_size);
}

void TreeLdlt::analyze(const Eigen::SparseMatrix<double>& A) {
  // As SimplicialCholeskyBase::compute<true> with SuiteSparse's AMD for the ordering (the
  // same fill as Eigen's AMD, 3-15 times faster on the active set's W_AA): P, P A P^T's upper
  // triangle, the elimination tree and column counts; the numeric factorisation follows in
  // factorize_analyzed().
  const Eigen::Index n = A.cols();
  CholMatrixType& tmp = permuted_;
  tmp.resize(n, n);
  ConstCholMatrixPtr pmat = &tmp;
  Eigen::VectorXi order(n);
  double control[AMD_CONTROL], info[AMD_INFO];
  amd_defaults(control);
  if (!A.isCompressed() || amd_order(static_cast<int>(n), A.outerIndexPtr(), A.innerIndexPtr(),
                                     order.data(), control, info) < AMD_OK) {
    ordering(A, pmat, tmp);  // Eigen's AMD
  } else {
    m_Pinv.indices() = order;  // AMD's order: the k-th pivot is row order[k]
    m_P = m_Pinv.inverse();
    tmp.selfadjointView<Eigen::Upper>() = A.selfadjointView<Eigen::Lower>().twistedBy(m_P);
  }
  if (pmat != &tmp) tmp = *pmat;
  analyzePattern_preordered(tmp, true);
  symbolic_flops_ = 0;
  const int* Lp = m_matrix.outerIndexPtr();
  for (Eigen::Index j = 0; j < n; ++j) {
    const auto c = static_cast<double>(Lp[j + 1] - Lp[j]);
    symbolic_flops_ += c * c;
  }
}

void TreeLdlt::factorize_analyzed(int ways, int min_size) {
  const CholMatrixType& ap = permuted_;
  const Eigen::Index n = ap.cols();
  split_ = false;
  top_dense_ = false;
  top_.clear();
  split_speedup_ = 1.0;
  if (ways > 1 && n >= min_size) split(ap, ways);
  if (!split_) {  // no split: Eigen's own loop
    factorize_preordered<true>(ap);
    return;
  }
  const auto nu = static_cast<std::size_t>(n), nt = top_.size();
  m_diag.resize(n);
  below_.assign(nu, 0);
  bool ok = true;
  const int threads =
      omp_in_parallel() ? 1 : std::min(omp_get_max_threads(), static_cast<int>(bins_.size()));
  // Each way (bin) on one thread: its subtrees' rows, then its parts of the top rows.
  ThreadedRegion region(timers_, threads > 1);
#pragma omp parallel for schedule(static, 1) num_threads(threads)
  for (std::size_t b = 0; b < bins_.size(); ++b) {
    Bin& bin = bins_[b];
    bin.y.assign(nu, 0.0);
    bin.pattern.resize(nu);
    bin.tags.assign(nu, -1);
    // Column t holds the top rows before t: only that part is zeroed (and read).
    bin.contributions.resize(nt * nt);
    for (std::size_t t = 0; t < nt; ++t)
      std::fill_n(bin.contributions.begin() + static_cast<std::ptrdiff_t>(t * nt), t, 0.0);
    bin.partial_d.assign(nt, 0.0);
    bin.start_ptr.assign(nt + 1, 0);
    bin.starts.clear();
    bool fine = true;
    for (const std::int32_t k : bin.rows)
      if (!factor_row(ap, k, bin.y.data(), bin.pattern.data(), bin.tags.data())) {
        fine = false;
        break;
      }
    if (!fine) {
#pragma omp atomic write
      ok = false;
      continue;
    }
    for (const std::int32_t k : bin.rows)  // the entries of column k within its subtree
      below_[static_cast<std::size_t>(k)] = m_nonZerosPerCol[k];
    for (std::size_t t = 0; t < nt; ++t) top_row_part(ap, t, static_cast<std::int32_t>(b), bin);
  }
  region.done();
  // The top rows: dense on the threads, or (not positive definite, or chosen) on one thread.
  if (ok && top_dense_ && !top_dense(ap)) top_dense_ = false;
  if (ok && !top_dense_) {
    std::vector<double> y(nu, 0.0);
    std::vector<std::int32_t> pattern(nu), tags(nu, -1);
    for (std::size_t t = 0; t < nt && ok; ++t)
      ok = top_row_rest(ap, t, y.data(), pattern.data(), tags.data());
  }
  m_info = ok ? Eigen::Success : Eigen::NumericalIssue;
  m_factorizationIsOk = true;
}

void TreeLdlt::solve_in_place(Eigen::VectorXd& b) const {
  if (!split_) {
    b = solve(b);
    return;
  }
  // Eigen's SimplicialCholeskyBase::_solve_impl: x = P b, L x = x (unit lower), x = D^-1 x,
  // L^T x = x, b = P^-1 x; the two substitutions by subtrees (see the declaration).
  Eigen::VectorXd x = m_P.size() > 0 ? Eigen::VectorXd(m_P * b) : b;
  const int* Lp = m_matrix.outerIndexPtr();
  const int* Li = m_matrix.innerIndexPtr();
  const double* Lx = m_matrix.valuePtr();
  const int* count = m_nonZerosPerCol.data();
  const std::size_t nt = top_.size(), nb = bins_.size();
  const int threads = omp_in_parallel() ? 1 : std::min(omp_get_max_threads(), static_cast<int>(nb));
  // Forward, each way's columns: its rows' entries (the first below_ of a column) in x, the
  // top's in its own accumulator (by top position).
  std::vector<double> acc(nb * nt, 0.0);
  ThreadedRegion forward(timers_, threads > 1);
#pragma omp parallel for schedule(static, 1) num_threads(threads)
  for (std::size_t w = 0; w < nb; ++w) {
    double* a = acc.data() + w * nt;
    for (const std::int32_t k : bins_[w].rows) {
      const double xk = x[k];
      if (xk == 0.0) continue;
      const int p1 = Lp[k] + below_[static_cast<std::size_t>(k)], p2 = Lp[k] + count[k];
      int p = Lp[k];
      for (; p < p1; ++p) x[Li[p]] -= Lx[p] * xk;
      for (; p < p2; ++p) a[top_pos_[static_cast<std::size_t>(Li[p])]] -= Lx[p] * xk;
    }
  }
  forward.done();
  const double* d = m_diag.data();
  const auto back = [&](std::int32_t k) {
    double xk = x[k] * (1.0 / d[k]);
    for (int p = Lp[k]; p < Lp[k] + count[k]; ++p) xk -= Lx[p] * x[Li[p]];
    x[k] = xk;
  };
  if (top_dense_) {
    // The top's columns and rows reach top rows only: their part of the two substitutions with
    // the diagonal is x_T := S^-1 x_T, S = U^T U the top's Schur complement (top_dense()), after
    // the ways' parts.
    std::vector<double> xt(nt);
    for (std::size_t t = 0; t < nt; ++t) {
      double xk = x[top_[t]];
      for (std::size_t w = 0; w < nb; ++w) xk += acc[w * nt + t];
      xt[t] = xk;
    }
    dense::upper_cholesky_solve(schur_.data(), static_cast<int>(nt), xt.data());
    for (std::size_t t = 0; t < nt; ++t) x[top_[t]] = xt[t];
  } else {
    // The top's columns (they reach top rows only), each row with the ways' parts first.
    for (std::size_t t = 0; t < nt; ++t) {
      const std::int32_t k = top_[t];
      double xk = x[k];
      for (std::size_t w = 0; w < nb; ++w) xk += acc[w * nt + t];
      x[k] = xk;
      if (xk == 0.0) continue;
      for (int p = Lp[k]; p < Lp[k] + count[k]; ++p) x[Li[p]] -= Lx[p] * xk;
    }
    // Backward with the diagonal: row k of L^T x = D^-1 x reads its ancestors' entries, so the
    // top (descending) first, then each way's subtrees (descending) on the threads.
    for (std::size_t t = nt; t-- > 0;) back(top_[t]);
  }
  {
    ThreadedRegion backward(timers_, threads > 1);
#pragma omp parallel for schedule(static, 1) num_threads(threads)
    for (std::size_t w = 0; w < nb; ++w)
      for (auto it = bins_[w].rows.rbegin(); it != bins_[w].rows.rend(); ++it) back(*it);
  }
  if (m_Pinv.size() > 0) {
    b = m_Pinv * x;
  } else {
    b = x;
  }
}

void TreeLdlt::top_row_part(const Eigen::SparseMatrix<double>& ap, std::size_t t, std::int32_t b,
                            Bin& bin) {
  // Top row k's triangular solve restricted to bin b's subtrees (its reach there, in
  // topological order, as factor_row): L(k, i) for their columns i, what these columns
  // subtract from the top's rows (column t of bin.contributions) and from D_kk
  // (bin.partial_d[t]), and the top rows where the reach leaves the subtrees (bin.starts).
  const std::int32_t k = top_[t];
  const auto size = static_cast<std::int32_t>(ap.rows());
  const int* Lp = m_matrix.outerIndexPtr();
  int* Li = m_matrix.innerIndexPtr();
  double* Lx = m_matrix.valuePtr();
  const int* parent = m_parent.data();
  int* count = m_nonZerosPerCol.data();
  double* y = bin.y.data();
  std::int32_t* pattern = bin.pattern.data();
  std::int32_t* tags = bin.tags.data();
  std::int32_t top = size;
  for (Eigen::SparseMatrix<double>::InnerIterator it(ap, k); it; ++it) {
    auto i = static_cast<std::int32_t>(it.index());
    if (owner_[static_cast<std::size_t>(i)] != b) continue;
    y[i] += it.value();
    std::int32_t len = 0;
    for (; i >= 0 && owner_[static_cast<std::size_t>(i)] == b && tags[i] != k; i = parent[i]) {
      pattern[len++] = i;
      tags[i] = k;
    }
    if (i >= 0 && owner_[static_cast<std::size_t>(i)] < 0) bin.starts.push_back(i);
    while (len > 0) pattern[--top] = pattern[--len];
  }
  double* c = bin.contributions.data() + t * top_.size();
  double d = 0;
  for (; top < size; ++top) {
    const std::int32_t i = pattern[top];
    const double yi = y[i];
    y[i] = 0.0;
    const double l_ki = yi / m_diag[i];
    const int p1 = Lp[i] + below_[static_cast<std::size_t>(i)], p2 = Lp[i] + count[i];
    int p = Lp[i];
    for (; p < p1; ++p) y[Li[p]] -= Lx[p] * yi;
    for (; p < p2; ++p) c[top_pos_[static_cast<std::size_t>(Li[p])]] -= Lx[p] * yi;
    d -= l_ki * yi;
    Li[p] = k;
    Lx[p] = l_ki;
    ++count[i];
  }
  bin.partial_d[t] = d;
  bin.start_ptr[t + 1] = static_cast<std::int32_t>(bin.starts.size());
}

std::int32_t TreeLdlt::top_reach(const Eigen::SparseMatrix<double>& ap, std::size_t t,
                                 std::int32_t* pattern, std::int32_t* tags) {
  // The reach of top row k over the top's columns, from A's entries on the top's rows and from
  // where the ways' parts left their subtrees (the top is closed under parents), in topological
  // order; column k emptied for the rows after it.
  const std::int32_t k = top_[t];
  const int* parent = m_parent.data();
  auto top = static_cast<std::int32_t>(ap.rows());
  tags[k] = k;
  m_nonZerosPerCol[k] = 0;
  const auto reach = [&](std::int32_t i) {
    std::int32_t len = 0;
    for (; tags[i] != k; i = parent[i]) {
      pattern[len++] = i;
      tags[i] = k;
    }
    while (len > 0) pattern[--top] = pattern[--len];
  };
  for (Eigen::SparseMatrix<double>::InnerIterator it(ap, k); it; ++it)
    if (owner_[static_cast<std::size_t>(it.index())] < 0)
      reach(static_cast<std::int32_t>(it.index()));
  for (const Bin& bin : bins_)
    for (std::int32_t s = bin.start_ptr[t]; s < bin.start_ptr[t + 1]; ++s)
      reach(bin.starts[static_cast<std::size_t>(s)]);
  return top;
}

bool TreeLdlt::top_row_rest(const Eigen::SparseMatrix<double>& ap, std::size_t t, double* y,
                            std::int32_t* pattern, std::int32_t* tags) {
  // Top row k's solve over the top's columns: A's entries on the top's rows, over their reach
  // (top_reach), then factor_row's loop, each way's contribution added, in way order, to y_i as
  // it is used (the same sums for any thread count).
  const std::int32_t k = top_[t];
  for (Eigen::SparseMatrix<double>::InnerIterator it(ap, k); it; ++it)
    if (owner_[static_cast<std::size_t>(it.index())] < 0) y[it.index()] += it.value();
  const std::int32_t top = top_reach(ap, t, pattern, tags);
  double d = y[k] * m_shiftScale + m_shiftOffset;
  y[k] = 0.0;
  for (const Bin& bin : bins_) d += bin.partial_d[t];
  m_diag[k] = eliminate(k, top, pattern, y, d, [&](std::int32_t i, double& yi) {
    for (const Bin& bin : bins_)
      yi += bin.contributions[t * top_.size() +
                              static_cast<std::size_t>(top_pos_[static_cast<std::size_t>(i)])];
  });
  return m_diag[k] != 0.0;
}

bool TreeLdlt::top_dense(const Eigen::SparseMatrix<double>& ap) {
  // S = A_TT + shift + sum over the ways of their parts (by top position; column t of its upper
  // triangle is top row t, as in Bin::contributions), S = U^T U, and then the rows of L: with
  // U = D^(1/2) L_TT^T, L(k_t, k_s) = U_st / U_ss and D_t = U_tt^2.
  const std::size_t nt = top_.size();
  schur_.resize(nt * nt);
  const int threads = omp_in_parallel() ? 1 : omp_get_max_threads();
  {
    ThreadedRegion region(timers_, threads > 1);
#pragma omp parallel for schedule(dynamic, 16) num_threads(threads)
    for (std::size_t t = 0; t < nt; ++t) {
      double* s = schur_.data() + t * nt;
      std::fill_n(s, t + 1, 0.0);
      const std::int32_t k = top_[t];
      for (Eigen::SparseMatrix<double>::InnerIterator it(ap, k); it; ++it) {
        const auto i = static_cast<std::size_t>(it.index());
        if (owner_[i] < 0) s[top_pos_[i]] += it.value();
      }
      s[t] = s[t] * m_shiftScale + m_shiftOffset;
      for (const Bin& bin : bins_) {
        const double* c = bin.contributions.data() + t * nt;
        for (std::size_t r = 0; r < t; ++r) s[r] += c[r];
        s[t] += bin.partial_d[t];
      }
    }
    region.done();
    ThreadedRegion factoring(timers_, threads > 1);
    if (!dense::cholesky_upper_on_threads(schur_.data(), static_cast<int>(nt))) return false;
  }
  // Each top row's reach over the top's columns (top_reach), its entries from U.
  const auto size = static_cast<std::int32_t>(ap.rows());
  const int* Lp = m_matrix.outerIndexPtr();
  int* Li = m_matrix.innerIndexPtr();
  double* Lx = m_matrix.valuePtr();
  int* count = m_nonZerosPerCol.data();
  std::vector<std::int32_t> pattern(static_cast<std::size_t>(size)), tags(pattern.size(), -1);
  for (std::size_t t = 0; t < nt; ++t) {
    const std::int32_t k = top_[t];
    std::int32_t top = top_reach(ap, t, pattern.data(), tags.data());
    const double* u = schur_.data() + t * nt;
    for (; top < size; ++top) {
      const std::int32_t i = pattern[top];
      const auto s = static_cast<std::size_t>(top_pos_[static_cast<std::size_t>(i)]);
      const int p = Lp[i] + count[i]++;
      Li[p] = k;
      Lx[p] = u[s] / schur_[s * nt + s];
    }
    m_diag[k] = u[t] * u[t];
  }
  return true;
}

bool TreeLdlt::factor_row(const Eigen::SparseMatrix<double>& ap, Eigen::Index k, double* y,
                          std::int32_t* pattern, std::int32_t* tags) {
  // Eigen's SimplicialCholeskyBase::factorize_preordered<true>, the body of its loop over k
  // (Davis 2006, §4.8: row k of L by a sparse triangular solve over the elimination tree).
  const auto size = static_cast<std::int32_t>(ap.rows());
  const int* parent = m_parent.data();
  int* count = m_nonZerosPerCol.data();
  const auto kk = static_cast<std::int32_t>(k);
  y[k] = 0.0;
  std::int32_t top = size;
  tags[k] = kk;
  count[k] = 0;
  for (Eigen::SparseMatrix<double>::InnerIterator it(ap, k); it; ++it) {
    auto i = static_cast<std::int32_t>(it.index());
    if (i <= kk) {
      y[i] += it.value();
      std::int32_t len = 0;
      for (; tags[i] != kk; i = parent[i]) {
        pattern[len++] = i;
        tags[i] = kk;
      }
      while (len > 0) pattern[--top] = pattern[--len];
    }
  }
  const double d = y[k] * m_shiftScale + m_shiftOffset;
  y[k] = 0.0;
  m_diag[k] = eliminate(kk, top, pattern, y, d, nullptr);
  return m_diag[k] != 0.0;
}

void TreeLdlt::split(const Eigen::SparseMatrix<double>& ap, int ways) {
  const auto n = static_cast<std::size_t>(ap.rows());
  const int* parent = m_parent.data();
  // The work of column i: the updates it makes to the later rows' triangular solves, sum over
  // its entries of those above them, c (c - 1) / 2 for c entries (left-looking count).
  std::vector<double> work(n, 1.0);
  for (std::size_t i = 0; i < n; ++i) {
    const double c = m_nonZerosPerCol[static_cast<Eigen::Index>(i)];
    work[i] += 0.5 * c * (c - 1);
  }
  // Subtree sums (a parent comes after its children) and child lists.
  std::vector<double> sub = work;
  std::vector<std::int32_t> head(n, -1), next(n, -1), roots;
  for (std::size_t k = n; k-- > 0;) {  // descending, so that the lists come out ascending
    if (parent[k] >= 0) {
      next[k] = head[static_cast<std::size_t>(parent[k])];
      head[static_cast<std::size_t>(parent[k])] = static_cast<std::int32_t>(k);
    } else {
      roots.push_back(static_cast<std::int32_t>(k));
    }
  }
  for (std::size_t k = 0; k < n; ++k)
    if (parent[k] >= 0) sub[static_cast<std::size_t>(parent[k])] += sub[k];
  const double total = std::accumulate(work.begin(), work.end(), 0.0);
  // Greedy descent: the largest subtree's root moves to the top and its children become
  // subtrees, while the estimate top + max(largest subtree, subtrees' sum / ways) falls.
  using Item = std::pair<double, std::int32_t>;
  std::priority_queue<Item> frontier;
  double frontier_sum = 0;
  for (const std::int32_t r : roots) {
    frontier.emplace(sub[static_cast<std::size_t>(r)], r);
    frontier_sum += sub[static_cast<std::size_t>(r)];
  }
  const std::size_t max_subtrees = kSubtreesPerWay * static_cast<std::size_t>(ways);
  double top_work = 0, best = total;
  std::vector<std::int32_t> expanded;
  std::size_t best_expanded = 0;
  while (!frontier.empty() && frontier.size() <= max_subtrees) {
    const double estimate =
        top_work + std::max(frontier.top().first, frontier_sum / static_cast<double>(ways));
    if (estimate < best) {
      best = estimate;
      best_expanded = expanded.size();
    }
    const auto [s, r] = frontier.top();
    if (head[static_cast<std::size_t>(r)] < 0) break;  // the largest is one row
    frontier.pop();
    frontier_sum -= s;
    top_work += work[static_cast<std::size_t>(r)];
    expanded.push_back(r);
    for (std::int32_t c = head[static_cast<std::size_t>(r)]; c >= 0;
         c = next[static_cast<std::size_t>(c)]) {
      frontier.emplace(sub[static_cast<std::size_t>(c)], c);
      frontier_sum += sub[static_cast<std::size_t>(c)];
    }
  }
  if (total / best < kMinSpeedup || best_expanded > kMaxTopRows) return;
  // Replay the best number of expansions: the top rows, and the subtree roots left.
  std::vector<char> in_top(n, 0);
  for (std::size_t e = 0; e < best_expanded; ++e) in_top[static_cast<std::size_t>(expanded[e])] = 1;
  std::vector<Item> chosen;
  const auto add_root = [&](std::int32_t r) {
    chosen.emplace_back(sub[static_cast<std::size_t>(r)], r);
  };
  for (const std::int32_t r : roots)
    if (!in_top[static_cast<std::size_t>(r)]) add_root(r);
  for (std::size_t e = 0; e < best_expanded; ++e)
    for (std::int32_t c = head[static_cast<std::size_t>(expanded[e])]; c >= 0;
         c = next[static_cast<std::size_t>(c)])
      if (!in_top[static_cast<std::size_t>(c)]) add_root(c);
  // The subtrees dealt to the ways, largest first to the least loaded (LPT), each subtree's
  // rows ascending (its rows' order in the serial loop).
  std::sort(chosen.begin(), chosen.end(), std::greater<>());
  bins_.resize(static_cast<std::size_t>(ways));  // kept between calls: their arrays' storage
  for (Bin& bin : bins_) bin.rows.clear();
  std::vector<double> load(static_cast<std::size_t>(ways), 0.0);
  owner_.assign(n, -1);
  std::vector<std::int32_t> stack, rows;
  for (const auto& [s, r] : chosen) {
    const auto b =
        static_cast<std::size_t>(std::min_element(load.begin(), load.end()) - load.begin());
    load[b] += s;
    rows.clear();
    stack.assign(1, r);
    while (!stack.empty()) {
      const std::int32_t v = stack.back();
      stack.pop_back();
      rows.push_back(v);
      owner_[static_cast<std::size_t>(v)] = static_cast<std::int32_t>(b);
      for (std::int32_t c = head[static_cast<std::size_t>(v)]; c >= 0;
           c = next[static_cast<std::size_t>(c)])
        stack.push_back(c);
    }
    std::sort(rows.begin(), rows.end());
    bins_[b].rows.insert(bins_[b].rows.end(), rows.begin(), rows.end());
  }
  top_pos_.assign(n, -1);
  for (std::size_t k = 0; k < n; ++k)
    if (in_top[k]) {
      top_pos_[k] = static_cast<std::int32_t>(top_.size());
      top_.push_back(static_cast<std::int32_t>(k));
    }
  double top_rows_work = 0;
  for (const std::int32_t k : top_) top_rows_work += work[static_cast<std::size_t>(k)];
  // The dense top's work: n^3 / 6 multiply-adds for n rows, at about kDenseRate times the
  // sparse loop's rate.
  const auto top_size = static_cast<double>(top_.size());
  const double dense_work = top_size * top_size * top_size / 6.0 / kDenseRate;
  top_dense_ =
      top_mode_ == TopMode::dense || (top_mode_ == TopMode::automatic &&
                                      top_.size() >= kMinDenseTop && dense_work < top_rows_work);
  if (top_dense_) top_rows_work = dense_work / ways;
  split_speedup_ = total / (top_rows_work + *std::max_element(load.begin(), load.end()));
  split_ = true;
}

}  // namespace mpmcd
