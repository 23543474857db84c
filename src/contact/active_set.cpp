#include "mpmcd/contact/active_set.hpp"

#include "mpmcd/contact/law.hpp"
#include "mpmcd/core/timer.hpp"

#include <Eigen/Dense>
#include <Eigen/SparseCholesky>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <vector>

namespace mpmcd::contact {

namespace {
// Proximal steps of one solve before it is left to Gauss-Seidel.
constexpr int kMaxProximalSteps = 30;
// Gauss-Seidel sweeps before the pivoting: one, which finishes the problems whose warm start is
// right (the later Newton iterations of a step) without the pivoting. More sweeps give the
// pivoting a better first active set but cost more than the pivots they save where W and the
// factorisation are kept (ActiveSetCache): dense 300-disk state at d/8, 1.30-1.41 s per step with
// 1 sweep against 1.83-1.86 s with 10 (3: 1.55 s); on 51 problems of the 40-disk case at d/16
// that Gauss-Seidel needed 380 to 2,900 sweeps for: 1,650 pivots and 1.07 s with 1 sweep against
// 502 and 0.87 s with 10, all solved without a sweep after (docs/contact.md).
constexpr int kPreSweeps = 1;
}  // namespace

namespace {

// The normal system's parts (normal_system): b, p, and W's columns from the resources the
// contacts share. A contact's relative normal velocity n_c . (v_B - v_A) responds to impulses
// through the slots it shares with other contacts: those of one compliance group (G blocks) or
// one lumped slot (I / m). Each such resource lists its (contact, slot, sign) entries; every pair
// of entries adds sign_e sign_f n_e . R(slot_e, slot_f) n_f to W (method.md §4). In a group,
// n_e . G_ef n_f = nu_e . Gr_ef nu_f with nu = B^T n the normal on the slot's directions
// (contact::Group), kept in the entry with its rows of Gr.
template <int Dim>
class NormalColumns {
 public:
  struct Entry {
    std::int32_t contact, slot;
    double sign;
    int rank = 0;                  // directions of the slot (group resource), 0 if lumped
    Eigen::Index col = 0;          // the slot's first row of Gr
    std::array<double, Dim> nu{};  // B^T n of the contact's normal [-]
  };

  // b and p of `sys` (sized here); with `with_matrix` also the resources' entry lists.
  NormalColumns(const Problem<Dim>& p, bool with_matrix, NormalSystem& sys)
      : p_(p), ng_(p.groups.size()) {
    const auto m = static_cast<Eigen::Index>(p.contacts.size());
    sys.b.resize(m);
    sys.p.resize(m);
    if (with_matrix) by_resource_.resize(ng_ + p.slots.size());
    for (Eigen::Index c = 0; c < m; ++c) {
      const Contact<Dim>& k = p.contacts[static_cast<std::size_t>(c)];
      const Vec<Dim> va = k.a >= 0 ? p.slots[k.a].v_free : k.wall_velocity;
      sys.b[c] = k.normal.dot(p.slots[k.b].v_free - va) + k.gap / p.dt;
      sys.p[c] = k.impulse.dot(k.normal);
      if (!with_matrix) continue;
      const auto ci = static_cast<std::int32_t>(c);
      by_resource_[resource(k.b)].push_back(entry(ci, k.b, 1.0));
      if (k.a >= 0) by_resource_[resource(k.a)].push_back(entry(ci, k.a, -1.0));
    }
  }

  // The group of slot s's resource, or -1 for a lumped slot [-].
  std::int64_t group_of(std::int32_t s) const { return p_.slots[s].group; }

  // Column c's row count (the merge of its one or two resources' lists) [-].
  std::size_t count(Eigen::Index c) const {
    const auto [l1, l2] = lists(p_.contacts[static_cast<std::size_t>(c)]);
    std::size_t i = 0, j = 0, n = 0;
    while (i < l1->size() || j < l2->size()) {
      const std::int32_t r1 = i < l1->size() ? (*l1)[i].contact : std::numeric_limits<int>::max();
      const std::int32_t r2 = j < l2->size() ? (*l2)[j].contact : std::numeric_limits<int>::max();
      i += r1 <= r2;
      j += r2 <= r1;
      ++n;
    }
    return n;
  }

  // Writes column c's rows and values from `out` on: the entries of its resources' lists, which
  // are in ascending contact order, merged (a contact sharing both resources with c gets both
  // terms, added).
  void fill(Eigen::Index c, int* rows, double* vals) const {
    const Contact<Dim>& k = p_.contacts[static_cast<std::size_t>(c)];
    const auto [l1, l2] = lists(k);
    const std::size_t r1 = resource(k.b), r2 = k.a >= 0 ? resource(k.a) : 0;
    const auto ci = static_cast<std::int32_t>(c);
    const Entry f1 = entry(ci, k.b, 1.0), f2 = k.a >= 0 ? entry(ci, k.a, -1.0) : Entry{};
    std::size_t i = 0, j = 0, out = 0;
    while (i < l1->size() || j < l2->size()) {
      const std::int32_t c1 = i < l1->size() ? (*l1)[i].contact : std::numeric_limits<int>::max();
      const std::int32_t c2 = j < l2->size() ? (*l2)[j].contact : std::numeric_limits<int>::max();
      double v = 0;
      if (c1 <= c2) v += value(r1, (*l1)[i++], f1);
      if (c2 <= c1) v += value(r2, (*l2)[j++], f2);
      rows[out] = std::min(c1, c2);
      vals[out++] = v;
    }
  }

 private:
  std::size_t resource(std::int32_t s) const {
    return p_.slots[s].group >= 0 ? static_cast<std::size_t>(p_.slots[s].group)
                                  : ng_ + static_cast<std::size_t>(s);
  }
  Entry entry(std::int32_t c, std::int32_t s, double sign) const {
    Entry e{c, s, sign};
    const Slot<Dim>& sl = p_.slots[s];
    if (sl.group < 0) return e;
    const Group<Dim>& g = p_.groups[sl.group];
    const auto j = static_cast<std::size_t>(sl.local);
    e.rank = g.rank(j);
    e.col = g.col[j];
    for (int m = 0; m < e.rank; ++m)
      e.nu[m] = g.basis[j].col(m).dot(p_.contacts[static_cast<std::size_t>(c)].normal);
    return e;
  }
  // f is column c's own entry in resource r.
  double value(std::size_t r, const Entry& e, const Entry& f) const {
    if (r >= ng_) {  // lumped: R = I / m
      const Vec<Dim>& ne = p_.contacts[static_cast<std::size_t>(e.contact)].normal;
      const Vec<Dim>& nf = p_.contacts[static_cast<std::size_t>(f.contact)].normal;
      return e.sign * f.sign * ne.dot(nf) / p_.slots[f.slot].mass;
    }
    const Eigen::MatrixXd& Gr = p_.groups[r].Gr;
    double acc = 0;
    for (int n = 0; n < f.rank; ++n) {
      const double* col = Gr.data() + (f.col + n) * Gr.rows() + e.col;
      double row = 0;
      for (int m = 0; m < e.rank; ++m) row += e.nu[m] * col[m];
      acc += row * f.nu[n];
    }
    return e.sign * f.sign * acc;
  }
  std::pair<const std::vector<Entry>*, const std::vector<Entry>*> lists(
      const Contact<Dim>& k) const {
    return {&by_resource_[resource(k.b)], k.a >= 0 ? &by_resource_[resource(k.a)] : &none_};
  }
  const Problem<Dim>& p_;
  std::size_t ng_;
  std::vector<std::vector<Entry>> by_resource_;
  std::vector<Entry> none_;
};

}  // namespace

template <int Dim>
NormalSystem normal_system(const Problem<Dim>& p, bool with_matrix, StageTimers* timers) {
  if (!with_matrix) {
    NormalSystem sys;
    const NormalColumns<Dim> cols(p, false, sys);
    return sys;
  }
  Eigen::SparseMatrix<double> W;
  NormalSystem sys = normal_system_into(p, W, timers);
  sys.W = std::move(W);
  return sys;
}

template <int Dim>
NormalSystem normal_system_into(const Problem<Dim>& p, Eigen::SparseMatrix<double>& W,
                                StageTimers* timers) {
  const auto m = static_cast<Eigen::Index>(p.contacts.size());
  NormalSystem sys;
  const NormalColumns<Dim> cols(p, true, sys);
  // W column by column on the threads, straight into compressed storage; a first pass counts
  // each column's rows.
  std::vector<Eigen::Index> count(static_cast<std::size_t>(m) + 1, 0);
  const bool threads = p.groups.size() > 1;
  ThreadedRegion counting(timers, threads);
#pragma omp parallel for schedule(dynamic, 64) if (threads)
  for (Eigen::Index c = 0; c < m; ++c)
    count[static_cast<std::size_t>(c) + 1] = static_cast<Eigen::Index>(cols.count(c));
  counting.done();
  for (std::size_t c = 0; c < static_cast<std::size_t>(m); ++c) count[c + 1] += count[c];
  // resize() keeps W's storage (Eigen empties it without freeing), so an assembly of no more
  // entries than the last writes into pages already mapped; a larger one reserves 10 % more.
  W.resize(m, m);
  const Eigen::Index nnz = count.back();
  if (W.data().allocatedSize() < nnz) W.reserve(nnz + nnz / 10);
  W.resizeNonZeros(nnz);
  for (Eigen::Index c = 0; c <= m; ++c)
    W.outerIndexPtr()[c] = static_cast<int>(count[static_cast<std::size_t>(c)]);
  int* const rows = W.innerIndexPtr();
  double* const vals = W.valuePtr();
  ThreadedRegion filling(timers, threads);
#pragma omp parallel for schedule(dynamic, 64) if (threads)
  for (Eigen::Index c = 0; c < m; ++c)
    cols.fill(c, rows + count[static_cast<std::size_t>(c)],
              vals + count[static_cast<std::size_t>(c)]);
  return sys;
}

template <int Dim>
NormalSystem refresh_normal_system(const Problem<Dim>& p, const std::vector<char>& stale,
                                   Eigen::SparseMatrix<double>& W, StageTimers* timers) {
  const auto m = static_cast<Eigen::Index>(p.contacts.size());
  NormalSystem sys;
  const NormalColumns<Dim> cols(p, true, sys);
  const auto is_stale = [&](std::int32_t s) {
    const std::int64_t g = s >= 0 ? cols.group_of(s) : -1;
    return g >= 0 && stale[static_cast<std::size_t>(g)] != 0;
  };
  const bool threads = p.groups.size() > 1;
  ThreadedRegion filling(timers, threads);
#pragma omp parallel for schedule(dynamic, 64) if (threads)
  for (Eigen::Index c = 0; c < m; ++c) {
    const Contact<Dim>& k = p.contacts[static_cast<std::size_t>(c)];
    if (!is_stale(k.b) && !is_stale(k.a)) continue;
    const int at = W.outerIndexPtr()[c];
    cols.fill(c, W.innerIndexPtr() + at, W.valuePtr() + at);
  }
  return sys;
}

namespace {

// Contacts that enter or leave the base set before the solver factorises the active set anew
// (the bordered solve's Schur complement is dense, of this order at most).
constexpr int kMaxBordered = 96;
// Ways of the split of W_AA's numeric factorisation (TreeLdlt: subtrees of the elimination tree
// on the threads). Fixed, so that the impulses are the same bits on any thread count: the d/8
// paper state at Phi = 0.95, 2 threads, 5 steps alternated 3 times: 371-379 ms per step against
// 391-399 ms unsplit (pivoting 168-181 against 184-193 ms); 1 thread: 507-508 against 490-493 ms
// (docs/parallel.md).
constexpr int kFactorWays = 2;
// Iterative refinement steps of a bordered solve.
constexpr int kMaxRefinements = 4;
// W_AA goes to the supernodal factorisation (SupernodalLlt) when L's columns have at least this
// many entries on average (its multiply-adds over its entries) and the factorisation at least
// kSupernodalFlops multiply-adds, and to TreeLdlt otherwise. Measured (docs/contact.md, "The
// supernodal factorisation"): the 300-sphere 3D state (mean column about 1,350, 3e10
// multiply-adds) factorises about 10 times faster supernodal; the 2D paper state at d/8 (mean
// column about 130, 6e7) 1.5 times slower on 2 threads, where TreeLdlt splits its tree.
constexpr double kSupernodalColumns = 400;
constexpr double kSupernodalFlops = 1e8;

// Whether a factor with `flops` multiply-adds and `nonzeros` entries is made supernodal.
bool use_supernodal(double flops, double nonzeros) {
  if (const char* force = std::getenv("MPMCD_SUPERNODAL")) return force[0] == '1';
  return flops >= kSupernodalFlops && flops >= kSupernodalColumns * nonzeros;
}
// Projected Gauss-Seidel sweeps on W before the first active set of a new W (sweep_on_w).
constexpr int kWSweeps = 20;
// Contacts from which the passes over W's columns run on the threads [-].
constexpr std::ptrdiff_t kThreadedRows = 2000;

// out = q + (W + delta I) x for the symmetric W: out_c from column c (row c), on the threads
// (their wall time to `timers`, stage kThreadedStage). In a large problem (from kThreadedRows
// contacts) whose x is zero on more than half of them (the pivots' impulses, nonzero on the
// active set only), W x is summed from the columns where x is nonzero instead: each of two fixed
// halves of the columns into its own vector, the two added in order, so the same bits on any
// thread count. The dense 3D state (7,500 contacts, a third active): the step -14 % on one
// thread (docs/three_d.md).
void shifted_product(const Eigen::SparseMatrix<double>& W, const Eigen::VectorXd& x,
                     const Eigen::VectorXd& q, double delta, Eigen::VectorXd& out,
                     StageTimers* timers) {
  const Eigen::Index m = W.cols();
  out.resize(m);
  if (m > kThreadedRows && 2 * (x.array() != 0.0).count() < m) {
    const Eigen::Index half = m / 2;
    Eigen::MatrixXd parts = Eigen::MatrixXd::Zero(m, 2);
    ThreadedRegion region(timers, true);
#pragma omp parallel for schedule(static, 1)
    for (int part = 0; part < 2; ++part) {
      double* const acc = parts.col(part).data();
      for (Eigen::Index r = part == 0 ? 0 : half; r < (part == 0 ? half : m); ++r) {
        const double xr = x[r];
        if (xr == 0.0) continue;
        for (Eigen::SparseMatrix<double>::InnerIterator it(W, r); it; ++it)
          acc[it.row()] += it.value() * xr;
      }
    }
    region.done();
    for (Eigen::Index c = 0; c < m; ++c) out[c] = q[c] + (parts(c, 0) + parts(c, 1)) + delta * x[c];
    return;
  }
  ThreadedRegion region(timers, m > kThreadedRows);
#pragma omp parallel for schedule(static) if (m > kThreadedRows)
  for (Eigen::Index c = 0; c < m; ++c) {
    double acc = 0;
    for (Eigen::SparseMatrix<double>::InnerIterator it(W, c); it; ++it)
      acc += it.value() * x[it.row()];
    out[c] = q[c] + acc + delta * x[c];
  }
}

// Projected Gauss-Seidel sweeps on W for the shifted problem min 1/2 x.(W + delta I) x + q.x,
// x >= 0 (each contact's local solution x_c = max(0, x_c - w_c / (W_cc + delta)), w = q +
// (W + delta I) x, method.md §4), from x: at most `sweeps`, and none after one that changes
// whether x_c > 0 for at most 1 in 1,000 contacts (the active set it suggests has settled; on the
// dense d/8 state the changes fall 160, 70, 27, 13, 19, 19, 11, 12, 10, then 3-10 per sweep). The
// contacts are swept in two fixed halves at once, each in order with the other half's values of
// the previous sweep (block Jacobi between the halves), so the answer is the same bits on any
// thread count. On the threads from kThreadedRows contacts.
void sweep_on_w(const Eigen::SparseMatrix<double>& W, const Eigen::VectorXd& q,
                const Eigen::VectorXd& d, double delta, Eigen::VectorXd& x, int sweeps,
                StageTimers* timers) {
  const Eigen::Index m = W.cols(), half = m / 2;
  Eigen::VectorXd before(m);
  for (int k = 0; k < sweeps; ++k) {
    before = x;
    std::array<std::int64_t, 2> flips{0, 0};  // per half: contacts whose x_c > 0 changed
    ThreadedRegion region(timers, m > kThreadedRows);
#pragma omp parallel for schedule(static, 1) if (m > kThreadedRows)
    for (int part = 0; part < 2; ++part) {
      const Eigen::Index lo = part == 0 ? 0 : half, hi = part == 0 ? half : m;
      std::int64_t n = 0;
      for (Eigen::Index c = lo; c < hi; ++c) {
        double acc = q[c] + delta * x[c];
        for (Eigen::SparseMatrix<double>::InnerIterator it(W, c); it; ++it) {
          const Eigen::Index r = it.row();
          acc += it.value() * (r >= lo && r < hi ? x[r] : before[r]);
        }
        const double next = std::max(0.0, x[c] - acc / (d[c] + delta));
        n += (next > 0.0) != (x[c] > 0.0);
        x[c] = next;
      }
      flips[static_cast<std::size_t>(part)] = n;
    }
    region.done();
    if (flips[0] + flips[1] <= m / 1000) return;
  }
}

// Solves with W_AA + delta I (sparse LDL^T) kept in a ShiftedFactor: the proximal steps of one
// solve, the pivots and (with a cache) the next solve of the same W reuse the factorisation of a
// base set B while the active set A differs from it by at most kMaxBordered contacts.
class ShiftedSolver {
 public:
  // `timers` (may be null) gets the wall time of the threaded regions.
  ShiftedSolver(const Eigen::SparseMatrix<double>& W, ShiftedFactor& f, double delta,
                StageTimers* timers)
      : W_(W), f_(f), timers_(timers) {
    f_.ldlt.set_timers(timers);
    set_shift(delta);
  }

  // The timers given at construction.
  StageTimers* timers() const { return timers_; }

  // A new shift delta [s/kg]; the next solve factorises unless it is the factorised one.
  void set_shift(double delta) {
    if (delta != f_.delta) f_.active.clear();
    f_.delta = delta;
  }

  // p_A = (W_AA + delta I)^-1 r_A with r = -q on the contacts `active` (ascending), 0
  // elsewhere; false when a factorisation fails.
  bool solve(const std::vector<std::int32_t>& active, const Eigen::VectorXd& q, Eigen::VectorXd& p,
             bool refined = true) {
    p.setZero();
    active_ = active;
    if (active.empty()) return true;
    if (f_.active.empty() || !border(active) || !cheaper_bordered()) {
      if (!factorise(active)) return false;
      border(active);
    }
    if (!prepare()) {
      if (!factorise(active) || !border(active) || !prepare()) return false;
    }
    r_ = Eigen::VectorXd::Zero(q.size());
    for (const std::int32_t c : active) r_[c] = -q[c];
    p = apply(r_);
    return refined ? refine(p) : p.allFinite();
  }

  // Iterative refinement of the last solve's answer p against W_AA + delta I: one step after a
  // fresh factorisation, up to kMaxRefinements while the residual halves after a bordered solve,
  // whose Schur complement loses digits on the nearly redundant contacts (with one step the
  // two-grain block test stalled at impulse changes of 4e-12 between Newton iterations). What
  // solve(..., refined = false) leaves out; false if p is not finite.
  bool refine(Eigen::VectorXd& p) {
    if (active_.empty()) return true;
    // Stop at round-off: a residual within a few ulps of r's largest entry cannot fall further.
    const double floor = 8 * std::numeric_limits<double>::epsilon() * r_.cwiseAbs().maxCoeff();
    double last = std::numeric_limits<double>::infinity();
    for (int k = 0; k < (bordered_.empty() ? 1 : kMaxRefinements); ++k) {
      // r - (W + delta I) x on A (x = 0 off A), 0 elsewhere; row c of W is its column c (W is
      // symmetric), so each contact's entry is one pass over its column, on the threads.
      Eigen::VectorXd res = Eigen::VectorXd::Zero(r_.size());
      const auto na = static_cast<std::ptrdiff_t>(active_.size());
      ThreadedRegion region(timers_, na > kThreadedRows);
#pragma omp parallel for schedule(static) if (na > kThreadedRows)
      for (std::ptrdiff_t a = 0; a < na; ++a) {
        const std::int32_t c = active_[static_cast<std::size_t>(a)];
        double acc = 0;
        for (Eigen::SparseMatrix<double>::InnerIterator it(W_, c); it; ++it)
          if (in_active_[static_cast<std::size_t>(it.row())]) acc += it.value() * p[it.row()];
        res[c] = r_[c] - f_.delta * p[c] - acc;
      }
      region.done();
      const double norm = res.cwiseAbs().maxCoeff();
      if (!(norm < 0.5 * last) || norm <= floor) break;
      last = norm;
      p += apply(res);
    }
    return p.allFinite();
  }

 private:
  // Makes `active` the base set: W_BB + delta I factorised, no bordered columns.
  bool factorise(const std::vector<std::int32_t>& active) {
    ScopedStage stage(timers_, "contact.as.factor");
    const auto na = static_cast<Eigen::Index>(active.size());
    const auto m = static_cast<std::size_t>(W_.rows());
    f_.active.clear();
    f_.local.assign(m, -1);
    f_.column.assign(m, -1);
    f_.owners.clear();
    for (Eigen::Index i = 0; i < na; ++i) f_.local[static_cast<std::size_t>(active[i])] = i;
    // W_BB column by column straight into compressed storage, on the threads: the rows of W's
    // column active[i] that are in B, in W's (ascending) order, which the local indices keep.
    std::vector<int> start(static_cast<std::size_t>(na) + 1, 0);
    ThreadedRegion counting(timers_, na > kThreadedRows);
#pragma omp parallel for schedule(static) if (na > kThreadedRows)
    for (Eigen::Index i = 0; i < na; ++i) {
      int n = 0;
      for (Eigen::SparseMatrix<double>::InnerIterator it(W_, active[i]); it; ++it)
        n += f_.local[static_cast<std::size_t>(it.row())] >= 0;
      start[static_cast<std::size_t>(i) + 1] = n;
    }
    counting.done();
    for (std::size_t i = 0; i < static_cast<std::size_t>(na); ++i) start[i + 1] += start[i];
    f_.Waa.resize(na, na);
    f_.Waa.resizeNonZeros(start.back());
    std::copy(start.begin(), start.end(), f_.Waa.outerIndexPtr());
    int* const rows = f_.Waa.innerIndexPtr();
    double* const vals = f_.Waa.valuePtr();
    ThreadedRegion gathering(timers_, na > kThreadedRows);
#pragma omp parallel for schedule(static) if (na > kThreadedRows)
    for (Eigen::Index i = 0; i < na; ++i) {
      int out = start[static_cast<std::size_t>(i)];
      for (Eigen::SparseMatrix<double>::InnerIterator it(W_, active[i]); it; ++it) {
        const std::int32_t j = f_.local[static_cast<std::size_t>(it.row())];
        if (j < 0) continue;
        rows[out] = j;
        vals[out++] = it.value();
      }
    }
    gathering.done();
    // The ordering and L's column counts first; long columns (dense 3D packings) go to the
    // supernodal factorisation with the same ordering, the others to TreeLdlt's loop.
    f_.ldlt.setShift(f_.delta);
    f_.ldlt.analyze(f_.Waa);
    f_.factor_flops = f_.ldlt.symbolic_flops();
    f_.factor_nonzeros = static_cast<double>(f_.ldlt.matrixL().nestedExpression().nonZeros());
    f_.supernodal = use_supernodal(f_.factor_flops, f_.factor_nonzeros);
    if (f_.supernodal) {
      if (!f_.llt.compute(f_.Waa, f_.delta, f_.ldlt.order().data())) return false;
    } else {
      f_.ldlt.factorize_analyzed(kFactorWays);
      if (f_.ldlt.info() != Eigen::Success) return false;
    }
    // MPMCD_TRACE_FACTOR=1: one line per factorisation on stderr (docs/contact.md, "The
    // supernodal factorisation"), to tune kSupernodalColumns and kSupernodalFlops.
    if (std::getenv("MPMCD_TRACE_FACTOR") != nullptr)
      std::fprintf(
          stderr,
          "factor contacts=%ld active=%ld nnz_Waa=%ld nnz_L=%.0f flops=%.3g supernodal=%d\n",
          static_cast<long>(W_.rows()), static_cast<long>(na), static_cast<long>(f_.Waa.nonZeros()),
          f_.factor_nonzeros, f_.factor_flops, f_.supernodal ? 1 : 0);
    f_.active = active;
    f_.solved.resize(na, 2 * kMaxBordered);
    return true;
  }

  // The contacts N of `active` not in B and R of B not in `active` (bordered_, N first); false
  // when they are more than kMaxBordered.
  bool border(const std::vector<std::int32_t>& active) {
    bordered_.clear();
    n_entered_ = 0;
    in_active_.assign(static_cast<std::size_t>(W_.rows()), 0);
    for (const std::int32_t c : active) in_active_[static_cast<std::size_t>(c)] = 1;
    for (const std::int32_t c : active)
      if (f_.local[static_cast<std::size_t>(c)] < 0) bordered_.push_back(c);
    n_entered_ = bordered_.size();
    for (const std::int32_t c : f_.active)
      if (!in_active_[static_cast<std::size_t>(c)]) bordered_.push_back(c);
    return bordered_.size() <= static_cast<std::size_t>(kMaxBordered);
  }

  // Whether the bordered solve costs less than factorising the active set: its new columns
  // (a forward and a back substitution each) and its Schur complement, against the flops of the
  // base's factorisation.
  bool cheaper_bordered() const {
    double fresh = 0;
    for (const std::int32_t b : bordered_) fresh += f_.column[static_cast<std::size_t>(b)] < 0;
    const auto k = static_cast<double>(bordered_.size());
    const double per_column = static_cast<double>(W_.nonZeros()) / static_cast<double>(W_.cols());
    return 4.0 * f_.factor_nonzeros * fresh + k * k * per_column < f_.factor_flops;
  }

  // The bordered columns (W_BB + delta I)^-1 c (made once per contact and base) and the LU of
  // the Schur complement S = D - C^T (W_BB + delta I)^-1 C, with C = [W_BN, E_R] and D the
  // block diag(W_NN + delta I, 0); false if S is singular.
  bool prepare() {
    ScopedStage stage(timers_, "contact.as.border");
    const auto k = static_cast<Eigen::Index>(bordered_.size());
    if (k == 0) return true;
    const auto nb = static_cast<Eigen::Index>(f_.active.size());
    // The new columns' right-hand sides c in their slots of f_.solved, then their solves, on
    // the threads by column when there are several (each solve whole: the same bits).
    const std::size_t first = f_.owners.size();
    for (const std::int32_t b : bordered_) {
      if (f_.column[static_cast<std::size_t>(b)] >= 0) continue;
      if (static_cast<Eigen::Index>(f_.owners.size()) == f_.solved.cols())
        f_.solved.conservativeResize(nb, 2 * f_.solved.cols());
      auto c = f_.solved.col(static_cast<Eigen::Index>(f_.owners.size()));
      c.setZero();
      if (f_.local[static_cast<std::size_t>(b)] >= 0) {
        c[f_.local[static_cast<std::size_t>(b)]] = 1.0;
      } else {
        for (Eigen::SparseMatrix<double>::InnerIterator it(W_, b); it; ++it) {
          const std::int32_t j = f_.local[static_cast<std::size_t>(it.row())];
          if (j >= 0) c[j] = it.value();
        }
      }
      f_.column[static_cast<std::size_t>(b)] = static_cast<std::int32_t>(f_.owners.size());
      f_.owners.push_back(b);
    }
    const auto fresh = static_cast<std::ptrdiff_t>(f_.owners.size() - first);
    if (f_.supernodal) {  // one multi-column solve
      if (fresh > 0)
        f_.llt.solve_in_place(f_.solved.middleCols(static_cast<Eigen::Index>(first), fresh));
    } else {
      ThreadedRegion columns(timers_, fresh > 1);
#pragma omp parallel for schedule(dynamic) if (fresh > 1)
      for (std::ptrdiff_t i = 0; i < fresh; ++i) {
        auto col = f_.solved.col(static_cast<Eigen::Index>(first) + i);
        Eigen::VectorXd c = col;
        f_.ldlt.solve_in_place(c);
        col = c;
      }
      columns.done();
    }
    Eigen::MatrixXd S(k, k);
    for (Eigen::Index j = 0; j < k; ++j) {
      const auto z = f_.solved.col(f_.column[static_cast<std::size_t>(bordered_[j])]);
      for (Eigen::Index i = 0; i < k; ++i) S(i, j) = -dot_c(i, z);
    }
    for (std::size_t i = 0; i < n_entered_; ++i)
      for (std::size_t j = 0; j < n_entered_; ++j)
        S(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) +=
            W_.coeff(bordered_[i], bordered_[j]) + (i == j ? f_.delta : 0.0);
    schur_.compute(S);
    return std::abs(schur_.determinant()) > 0.0 && std::isfinite(schur_.determinant());
  }

  // c_i . z for the bordered contact i (C's column i: W_Bn or e_r) and a vector z on B.
  double dot_c(Eigen::Index i, const Eigen::Ref<const Eigen::VectorXd>& z) const {
    const std::int32_t b = bordered_[static_cast<std::size_t>(i)];
    if (static_cast<std::size_t>(i) >= n_entered_) return z[f_.local[static_cast<std::size_t>(b)]];
    double acc = 0;
    for (Eigen::SparseMatrix<double>::InnerIterator it(W_, b); it; ++it) {
      const std::int32_t j = f_.local[static_cast<std::size_t>(it.row())];
      if (j >= 0) acc += it.value() * z[j];
    }
    return acc;
  }

  // x = (W_AA + delta I)^-1 r on the active set (r and x over all contacts, x = 0 off A): the
  // base solve u = (W_BB + delta I)^-1 r_B, the border y = S^-1 ([r_N; 0] - C^T u), then
  // x_B = u - (W_BB + delta I)^-1 C y and x_N = y (x_R = 0: y's R part is their multiplier).
  Eigen::VectorXd apply(const Eigen::VectorXd& r) const {
    ScopedStage stage(timers_, "contact.as.apply");
    const auto nb = static_cast<Eigen::Index>(f_.active.size());
    Eigen::VectorXd u(nb);
    for (Eigen::Index i = 0; i < nb; ++i)
      u[i] = in_active_[static_cast<std::size_t>(f_.active[i])] ? r[f_.active[i]] : 0.0;
    if (f_.supernodal)
      f_.llt.solve_in_place(u);
    else
      f_.ldlt.solve_in_place(u);
    Eigen::VectorXd x = Eigen::VectorXd::Zero(r.size());
    const auto k = static_cast<Eigen::Index>(bordered_.size());
    if (k > 0) {
      Eigen::VectorXd rhs(k);
      for (Eigen::Index i = 0; i < k; ++i)
        rhs[i] = (static_cast<std::size_t>(i) < n_entered_ ? r[bordered_[i]] : 0.0) - dot_c(i, u);
      const Eigen::VectorXd y = schur_.solve(rhs);
      // u minus the solved columns times y, by blocks of rows on the threads (each entry's
      // sum over the columns in their order: the same bits on any thread count).
      const int blocks = nb > kThreadedRows ? 2 : 1;
      ThreadedRegion region(timers_, blocks > 1);
#pragma omp parallel for schedule(static) if (blocks > 1)
      for (int part = 0; part < blocks; ++part) {
        const Eigen::Index lo = nb * part / blocks, len = nb * (part + 1) / blocks - lo;
        for (Eigen::Index j = 0; j < k; ++j)
          u.segment(lo, len) -=
              y[j] *
              f_.solved.col(f_.column[static_cast<std::size_t>(bordered_[j])]).segment(lo, len);
      }
      region.done();
      for (std::size_t j = 0; j < n_entered_; ++j)
        x[bordered_[j]] = y[static_cast<Eigen::Index>(j)];
    }
    for (Eigen::Index i = 0; i < nb; ++i)
      if (in_active_[static_cast<std::size_t>(f_.active[i])]) x[f_.active[i]] = u[i];
    return x;
  }

  const Eigen::SparseMatrix<double>& W_;
  ShiftedFactor& f_;
  StageTimers* timers_;                 // see the constructor
  std::vector<std::int32_t> bordered_;  // N (entered), then R (left)
  std::size_t n_entered_ = 0;
  std::vector<char> in_active_;       // per contact: in the active set of this solve
  std::vector<std::int32_t> active_;  // the active set of the last solve (ascending)
  Eigen::VectorXd r_;                 // its right-hand side: -q on the active set, 0 elsewhere
  Eigen::PartialPivLU<Eigen::MatrixXd> schur_;
};

// The largest violation of p >= 0, w = b + W p >= 0, p w = 0 over the contacts, as an impulse
// (w_c / W_cc), and the scale it is measured against (the largest impulse or |b_c| / W_cc).
std::pair<double, double> violation(const NormalSystem& sys, const Eigen::VectorXd& w,
                                    const Eigen::VectorXd& d, const Eigen::VectorXd& p) {
  double worst = 0, scale = 0;
  for (Eigen::Index c = 0; c < p.size(); ++c) {
    const double wc = w[c] / d[c];
    worst = std::max({worst, -p[c], -wc, std::min(std::max(p[c], 0.0), std::max(wc, 0.0))});
    scale = std::max({scale, std::abs(p[c]), std::abs(sys.b[c]) / d[c]});
  }
  return {worst, scale};
}

// Primal active-set method for the shifted problem (Lawson & Hanson 1974, ch. 23, on the
// strictly convex quadratic program min 1/2 x.(W + delta I) x + q.x, x >= 0, whose optimality
// conditions are the complementarity problem of one proximal step): from a feasible x, solve on
// the free set F; if a free impulse would turn negative, move toward the solution until the first
// one reaches 0 and fix it; else free the contact whose velocity w_c / W_cc is the most negative.
// The objective falls at every step, so it does not cycle where the block pivoting does (nearly
// redundant face contacts of split points, docs/contact.md). Its solves are refined only when
// they are the answer (no impulse would turn negative): the step length needs no more digits.
// Counts its solves in `pivots`; false after `max_steps` solves, on a failed solve or when the
// contact just freed is fixed again at once (round-off).
bool primal_active_set(ShiftedSolver& solver, const Eigen::SparseMatrix<double>& W,
                       const Eigen::VectorXd& q, const Eigen::VectorXd& d, double delta,
                       Eigen::VectorXd& x, int max_steps, int& pivots) {
  const Eigen::Index m = q.size();
  std::vector<char> free(static_cast<std::size_t>(m));
  for (Eigen::Index c = 0; c < m; ++c) free[c] = x[c] > 0.0;
  Eigen::VectorXd z(m), w(m);
  std::vector<std::int32_t> idx;
  std::int32_t freed = -1;
  double q_scale = 0;  // the largest |q_c| / W_cc [N s]
  for (Eigen::Index c = 0; c < m; ++c) q_scale = std::max(q_scale, std::abs(q[c]) / d[c]);
  for (int k = 0; k < max_steps; ++k) {
    idx.clear();
    for (Eigen::Index c = 0; c < m; ++c)
      if (free[c]) idx.push_back(static_cast<std::int32_t>(c));
    ++pivots;
    if (!solver.solve(idx, q, z, false)) return false;
    double alpha = 1.0;
    std::int32_t hit = -1;
    for (const std::int32_t c : idx)
      if (z[c] < 0.0 && x[c] / (x[c] - z[c]) < alpha) {
        alpha = x[c] / (x[c] - z[c]);
        hit = c;
      }
    if (hit >= 0) {
      if (hit == freed && alpha == 0.0) return false;
      x += alpha * (z - x);
      for (const std::int32_t c : idx)
        if (c == hit || x[c] <= 0.0) {
          x[c] = 0.0;
          free[c] = 0;
        }
      freed = -1;
      continue;
    }
    x = z;
    if (!solver.refine(x)) return false;
    shifted_product(W, x, q, delta, w, solver.timers());
    const double scale = std::max(x.cwiseAbs().maxCoeff(), q_scale);
    double most = -1e-12 * scale;  // the block pivoting's feasibility tolerance
    freed = -1;
    for (Eigen::Index c = 0; c < m; ++c)
      if (!free[c] && w[c] / (d[c] + delta) < most) {
        most = w[c] / (d[c] + delta);
        freed = static_cast<std::int32_t>(c);
      }
    if (freed < 0) return true;
    free[freed] = 1;
  }
  return false;
}

// The W_cc that the proximal shift is scaled by [s/kg]: the largest, but at most 1,000 times the
// median. A shift delta slows the proximal steps of a contact with W_cc ~ d by delta / d per
// step, and the pivoting stops once the violation no longer halves from one to the next. In
// dense 3D packings a few face contacts on nearly empty nodes' slots had W_cc up to 1e7 times the
// median: a shift of 1e-12 of theirs left the other contacts' violation at 1e-8 of the
// impulses, above the tolerance, and Gauss-Seidel then swept 1,000 times without converging
// (docs/contact.md, "The proximal shift and nearly massless slots"). In the 2D paper case at
// d/4, 51 of the first 1,712 solves had a largest W_cc above 1,000 times the median (up to
// 6,600 times).
double proximal_reference(const Eigen::VectorXd& d) {
  const double largest = d.maxCoeff();
  std::vector<double> sorted(d.data(), d.data() + d.size());
  const auto mid = sorted.begin() + static_cast<std::ptrdiff_t>(sorted.size() / 2);
  std::nth_element(sorted.begin(), mid, sorted.end());
  return std::min(largest, 1000.0 * *mid);
}

// Gauss-Seidel's error of frictionless contacts with impulses p: the relative distance
// |loc - p| / |p| to their local solutions loc_c = max(0, p_c - w_c / W_cc), w = b + W p (the
// local problem of contact c with the others' impulses fixed, method.md §4).
double local_error(const Eigen::VectorXd& w, const Eigen::VectorXd& d, const Eigen::VectorXd& p) {
  double num = 0, den = 0;
  for (Eigen::Index c = 0; c < p.size(); ++c) {
    const double loc = std::max(0.0, p[c] - w[c] / d[c]);
    num += (loc - p[c]) * (loc - p[c]);
    den += p[c] * p[c];
  }
  return num == 0.0 ? 0.0 : std::sqrt(num) / std::sqrt(std::max(den, 1e-300));
}

}  // namespace

template <int Dim>
GsResult solve_active_set(Problem<Dim>& problem, const GsSettings& settings,
                          ActiveSetCache* cache) {
  GsResult result;
  // The pivoting solves the frictionless Signorini law: other laws and friction go to the sweeps.
  const bool frictionless = find_contact_law(problem.law).active_set &&
                            std::all_of(problem.contacts.begin(), problem.contacts.end(),
                                        [](const Contact<Dim>& c) { return c.friction == 0.0; });
  if (frictionless && !problem.contacts.empty()) {
    // The sweeps' answer is kept only if it meets 1e-3 of the tolerance (a warm start that was
    // right): an answer just within the tolerance would leave the staggering impulse changes of
    // the tolerance's order that the pivoting's exact answer does not.
    // With W and its factorisation kept from the last solve (the later Newton iterations of a
    // step), one pivot from the warm start costs less than a sweep: no sweep first.
    const bool reuse = cache && cache->valid;
    if (!reuse) {
      GsSettings pre = settings;
      pre.max_sweeps = std::min(kPreSweeps, settings.max_sweeps);
      pre.tolerance = 1e-3 * settings.tolerance;
      const GsResult first = solve_gauss_seidel(problem, pre);
      result.sweeps = first.sweeps;
      if (first.converged) {
        result.error = first.error;
        result.converged = true;
        return result;
      }
    }
    ScopedStage assemble(settings.timers, "contact.as.assemble");
    // W made again only in the columns of the groups whose G changed, when nothing else did (the
    // Newton iterations of a step in which some grains factorise anew): the same W, bit for bit.
    std::vector<double> normals;
    if (cache && !reuse) {
      normals.reserve(problem.contacts.size() * Dim);
      for (const Contact<Dim>& c : problem.contacts)
        normals.insert(normals.end(), c.normal.data(), c.normal.data() + Dim);
    }
    const bool refresh = cache && !reuse && cache->pattern && cache->refreshable &&
                         cache->stale.size() == problem.groups.size() &&
                         cache->W.cols() == static_cast<Eigen::Index>(problem.contacts.size()) &&
                         cache->normals == normals;
    // A new W is written into the storage of the last one (in a dense 3D packing W is about a
    // gigabyte, and fresh storage faults its pages in at every assembly).
    ActiveSetCache local;
    ActiveSetCache& kept = cache ? *cache : local;
    NormalSystem sys = refresh
                           ? refresh_normal_system(problem, cache->stale, cache->W, settings.timers)
                       : reuse ? normal_system(problem, false, settings.timers)
                               : normal_system_into(problem, kept.W, settings.timers);
    if (!reuse) {
      kept.factor.active.clear();
      kept.valid = true;
      kept.pattern = true;
      kept.refreshable = false;
      kept.stale.assign(problem.groups.size(), 0);
      kept.normals = std::move(normals);
    }
    const Eigen::SparseMatrix<double>& W = kept.W;
    assemble.done();
    ScopedStage pivoting(settings.timers, "contact.as.pivot");
    const auto m = sys.b.size();
    const Eigen::VectorXd d = W.diagonal();
    // Proximal point (Rockafellar 1976): p_{k+1} solves the complementarity problem of
    // min 1/2 p.W p + b.p + delta/2 |p - p_k|^2, i.e. the matrix W + delta I and the vector
    // b - delta p_k, whose condition number is at most max W_cc / delta however redundant the
    // contacts (a nearly massless slot's row, whose W_cc may be far above delta's reference, is
    // dominated by its diagonal); its solutions converge to one of the original problem. From a
    // warm start near the answer (the Newton iterations and steps of a quasi-static run) one step
    // suffices. delta starts at 1e-12 of the reference W_cc (proximal_reference), so that the
    // proximal steps converge fast, and grows 100-fold (to 1e-6 of it) whenever the pivoting cycles
    // on an ill-conditioned W_AA.
    const double w_ref = proximal_reference(d);
    double delta = 1e-12 * w_ref;
    ShiftedSolver solver(W, kept.factor, delta, settings.timers);
    Eigen::VectorXd p = sys.p.cwiseMax(0.0), q, w, next(m);
    Eigen::VectorXd w_p;  // b + W p at the last accepted impulses p [m/s]
    std::vector<char> active(static_cast<std::size_t>(m));
    std::vector<std::int32_t> idx, infeasible;
    bool solved = false;
    double last = std::numeric_limits<double>::infinity();
    for (int outer = 0; outer < kMaxProximalSteps && !solved; ++outer) {
      q = sys.b - delta * p;
      // The starting active set: the contacts whose local solution (the others' impulses fixed)
      // has a positive impulse, p_c - w_c / M_cc > 0 (the semismooth-Newton rule).
      // With a new W (the first solve of a step) in a large problem the rule is applied after
      // up to kWSweeps projected Gauss-Seidel sweeps on W from p (sweep_on_w), which cost a few
      // products with W and bring the first active set closer: in the dense d/8 state the first
      // pivot flips about 210 contacts instead of 410 (docs/contact.md).
      // Not in small problems, which need few pivots anyway: there the guess after the sweeps,
      // with many contacts near p_c = w_c = 0, made the 3D head-on impact's path depend on
      // round-off (ThreeD.DenseAndSparseGrainFactorisationsTakeTheSameSteps).
      Eigen::VectorXd guess = p;
      if (!reuse && outer == 0 && m > kThreadedRows)
        sweep_on_w(W, q, d, delta, guess, kWSweeps, settings.timers);
      shifted_product(W, guess, q, delta, w, settings.timers);
      for (Eigen::Index c = 0; c < m; ++c) active[c] = guess[c] - w[c] / (d[c] + delta) > 0.0;
      // Block principal pivoting (Judice & Pires 1994): flip every infeasible contact while
      // their number falls (three more tries when it does not). When it stops falling, the
      // infeasible contacts left are a few nearly redundant ones that block flips trade back and
      // forth (and Murty's one-at-a-time rule took tens of pivots for, docs/contact.md): the
      // primal active-set method finishes from the last iterate, clipped to p >= 0.
      std::size_t best = std::numeric_limits<std::size_t>::max();
      int tries = 3;
      bool pivoted = false, stalled = false;
      for (int k = 0; k < settings.block_pivots; ++k) {
        idx.clear();
        for (Eigen::Index c = 0; c < m; ++c)
          if (active[c]) idx.push_back(static_cast<std::int32_t>(c));
        ++result.pivots;
        // In a large problem (from kThreadedRows contacts) a pivot's solve is refined only once
        // its active set looks right: the flips need the signs, not the last digits (the dense
        // d/8 state: refining every pivot's solve took a third of the pivoting). A small one
        // refines every pivot: the walled blocks' staggering at a tolerance of 1e-12 needs that
        // path (with unrefined pivots, impulse changes stalled at 2-3.5e-12, docs/contact.md).
        const bool refine_each = m <= kThreadedRows;
        if (!solver.solve(idx, q, next, refine_each)) break;
        bool refined = refine_each;
        for (;;) {
          shifted_product(W, next, q, delta, w, settings.timers);
          double scale = next.cwiseAbs().maxCoeff();
          for (Eigen::Index c = 0; c < m; ++c) scale = std::max(scale, std::abs(q[c]) / d[c]);
          const double tol = 1e-12 * scale;
          infeasible.clear();
          for (Eigen::Index c = 0; c < m; ++c)
            if (active[c] ? next[c] < -tol : w[c] / (d[c] + delta) < -tol)
              infeasible.push_back(static_cast<std::int32_t>(c));
          if (!infeasible.empty() || refined) break;
          if (!solver.refine(next)) break;
          refined = true;
        }
        if (infeasible.empty()) {
          pivoted = refined;
          break;
        }
        if (infeasible.size() < best) {
          best = infeasible.size();
          tries = 3;
        } else if (tries > 0) {
          --tries;
        } else {
          stalled = true;
          break;
        }
        for (const std::int32_t c : infeasible) active[c] = !active[c];
      }
      if (!pivoted) {  // stalled or cycling: the primal method from a feasible point
        next = stalled ? next.cwiseMax(0.0) : p;
        pivoted = primal_active_set(solver, W, q, d, delta, next, 3 * static_cast<int>(m) + 100,
                                    result.pivots);
      }
      if (!pivoted) {
        if (delta >= 1e-6 * w_ref) break;
        delta *= 100;
        solver.set_shift(delta);
        last = std::numeric_limits<double>::infinity();
        continue;
      }
      p = next.cwiseMax(0.0);
      // Done when the violation meets the tolerance or stops falling (round-off, about 1e-14 of
      // the impulses): Gauss-Seidel's error then decides, and sweeps if it must.
      shifted_product(W, p, sys.b, 0.0, w_p, settings.timers);
      const auto [worst, scale] = violation(sys, w_p, d, p);
      solved = worst <= 1e-3 * settings.tolerance * scale || worst > 0.5 * last;
      last = worst;
    }
    pivoting.done();
    if (solved) {
      for (Eigen::Index c = 0; c < m; ++c) {
        Contact<Dim>& k = problem.contacts[static_cast<std::size_t>(c)];
        k.impulse = p[c] * k.normal;
      }
      // Gauss-Seidel's error (error(problem)) from W, without the slot velocities: each
      // frictionless contact's local solution max(0, p_c - w_c / W_cc) (the others' impulses
      // fixed) against its impulse, |loc - p| / |p|. Met: no sweep.
      result.error = local_error(w_p, d, p);
      if (result.error <= settings.tolerance) {
        result.converged = true;
        return result;
      }
    }
  }
  ScopedStage polish(settings.timers, "contact.as.check");
  const GsResult gs = solve_gauss_seidel(problem, settings);
  polish.done();
  result.sweeps += gs.sweeps;
  result.error = gs.error;
  result.converged = gs.converged;
  return result;
}

#define MPMCD_INSTANTIATE(D)                                                                   \
  template NormalSystem normal_system<D>(const Problem<D>&, bool, StageTimers*);               \
  template NormalSystem normal_system_into<D>(const Problem<D>&, Eigen::SparseMatrix<double>&, \
                                              StageTimers*);                                   \
  template NormalSystem refresh_normal_system<D>(const Problem<D>&, const std::vector<char>&,  \
                                                 Eigen::SparseMatrix<double>&, StageTimers*);  \
  template GsResult solve_active_set<D>(Problem<D>&, const GsSettings&, ActiveSetCache*);
MPMCD_INSTANTIATE(2)
MPMCD_INSTANTIATE(3)
#undef MPMCD_INSTANTIATE

}  // namespace mpmcd::contact
