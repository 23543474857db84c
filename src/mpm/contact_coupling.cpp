// The coupling of the grains by Contact Dynamics, staggered with Newton (method.md §4,
// docs/contact.md): warm-start impulses, slot velocities and impulses, the grains' compliance at
// their slots (Delassus operator) and the Gauss-Seidel update of the impulses on one rank.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <tuple>
#include <vector>

#include "mpmcd/contact/active_set.hpp"
#include "mpmcd/core/dense_lapack.hpp"
#include "solver_detail.hpp"

namespace mpmcd::mpm {

template <int Dim>
void ImplicitSolver<Dim>::set_warm_start(std::vector<WarmImpulse<Dim>> impulses) {
  previous_ = std::move(impulses);
  sort_unique(previous_);
}

template <int Dim>
void ImplicitSolver<Dim>::renumber_points(std::span<const std::int64_t> index) {
  constexpr std::int64_t faces = 2 * Dim;  // face number = point * 2 Dim + 2 axis + side
  for (auto& w : previous_)
    if (w.node < 0 && w.a >= 0) {
      const std::int64_t f = -1 - w.node;
      w.node = -1 - (index[static_cast<std::size_t>(f / faces)] * faces + f % faces);
    }
  sort_unique(previous_);
}

template <int Dim>
void ImplicitSolver<Dim>::sort_unique(std::vector<WarmImpulse<Dim>>& impulses) {
  const auto key = [](const WarmImpulse<Dim>& x) { return std::tie(x.node, x.a, x.b); };
  std::stable_sort(
      impulses.begin(), impulses.end(),
      [&](const WarmImpulse<Dim>& x, const WarmImpulse<Dim>& y) { return key(x) < key(y); });
  // One impulse per contact (the union of several ranks' copies holds each once per rank).
  impulses.erase(std::unique(impulses.begin(), impulses.end(),
                             [&](const WarmImpulse<Dim>& x, const WarmImpulse<Dim>& y) {
                               return key(x) == key(y);
                             }),
                 impulses.end());
}

template <int Dim>
std::vector<WarmImpulse<Dim>> ImplicitSolver<Dim>::gather_warm_start() const {
  if (!distributed()) return previous_;
  parallel::Buffer mine;
  for (const auto& w : previous_) {
    mine.put(w.node);
    mine.put(w.a);
    mine.put(w.b);
    for (int d = 0; d < Dim; ++d) mine.put(w.impulse[d]);
  }
  std::vector<WarmImpulse<Dim>> all;
  for (const auto& bytes : comm_->allgather(mine.bytes())) {
    parallel::Buffer b;
    b.bytes() = bytes;
    while (!b.done()) {
      WarmImpulse<Dim> w;
      w.node = b.get<std::int64_t>();
      w.a = b.get<std::int32_t>();
      w.b = b.get<std::int32_t>();
      for (int d = 0; d < Dim; ++d) w.impulse[d] = b.get<double>();
      all.push_back(w);
    }
  }
  sort_unique(all);
  return all;
}

template <int Dim>
Vec<Dim> ImplicitSolver<Dim>::slot_velocity(std::size_t s) const {
  const GrainWork& w = *work_[slot_ref_[s].first];
  Vec<Dim> v = Vec<Dim>::Zero();
  for (std::int32_t k = slot_start_[s]; k < slot_start_[s + 1]; ++k)
    v += slot_weight_[k] * w.v[slot_node_[k]];
  return v;
}

template <int Dim>
void ImplicitSolver<Dim>::spread_slot_impulses() {
  // Node slots assign (0 + P = P exactly, so runs without face slots keep their bits), face slots
  // add their weighted impulses. A slot writes only its grain's P, so the grains go on the threads,
  // each with its slots in ascending order: every node sees the operations of one pass over all
  // slots in the same order (the same bits on any thread count).
  const auto ns = static_cast<std::int64_t>(slot_ref_.size());
  const std::size_t ng = work_.size();
  if (grain_slots_for_ != ns) {  // counting sort of the slots by grain (stable)
    grain_slot_start_.assign(ng + 1, 0);
    for (const auto& ref : slot_ref_) ++grain_slot_start_[static_cast<std::size_t>(ref.first) + 1];
    for (std::size_t g = 0; g < ng; ++g) grain_slot_start_[g + 1] += grain_slot_start_[g];
    grain_slots_.resize(static_cast<std::size_t>(ns));
    std::vector<std::int32_t> fill(grain_slot_start_.begin(), grain_slot_start_.end() - 1);
    for (std::int64_t s = 0; s < ns; ++s)
      grain_slots_[static_cast<std::size_t>(
          fill[static_cast<std::size_t>(slot_ref_[static_cast<std::size_t>(s)].first)]++)] =
          static_cast<std::int32_t>(s);
    grain_slots_for_ = ns;
  }
  const auto ngi = static_cast<std::int64_t>(ng);
  const bool threads = ns > 512 && ngi > 1;
  const ThreadedRegion threaded(&timers_, threads);
#pragma omp parallel for schedule(dynamic, 4) if (threads)
  for (std::int64_t gi = 0; gi < ngi; ++gi) {
    const auto g = static_cast<std::size_t>(gi);
    const std::int32_t b = grain_slot_start_[g], e = grain_slot_start_[g + 1];
    if (b == e) continue;
    std::vector<Vec<Dim>>& P = work_[g]->P;
    for (std::int32_t i = b; i < e; ++i) {
      const auto s = static_cast<std::size_t>(grain_slots_[static_cast<std::size_t>(i)]);
      for (std::int32_t k = slot_start_[s]; k < slot_start_[s + 1]; ++k) P[slot_node_[k]].setZero();
    }
    for (std::int32_t i = b; i < e; ++i) {
      const auto s = static_cast<std::size_t>(grain_slots_[static_cast<std::size_t>(i)]);
      if (!slot_is_face_[s]) P[slot_ref_[s].second] = slot_P_[s];
    }
    for (std::int32_t i = b; i < e; ++i) {
      const auto s = static_cast<std::size_t>(grain_slots_[static_cast<std::size_t>(i)]);
      if (slot_is_face_[s])
        for (std::int32_t k = slot_start_[s]; k < slot_start_[s + 1]; ++k)
          P[slot_node_[k]] += slot_weight_[k] * slot_P_[s];
    }
  }
}

namespace {

// Y = L^-1 Y in place (LDL^T of the grain's Newton matrix, P A P^T = L D L^T; Y, row-major
// n x ncol, holds P E B on entry): the column-by-column sparse solve of Eigen (x_r -= x_i L_ri for
// each column x with x_i != 0, i in order) done on all columns at once, row by row, so that each
// L_ri updates a contiguous run of Y's row r: the same operations on every nonzero, vectorised.
// Each row keeps the range [lo, hi) of columns where it may be nonzero (lo = hi: none; a column
// outside is exactly 0 there and skipped, as Eigen skips it); inside, an entry with x_i = 0 is
// updated by 0 (a zero's sign aside, the same value). 3x cheaper than the per-column solve on
// the CPDI grains of the paper compaction.
template <class Factor>
void forward_substitute(const Factor& ldlt, double* Y, Eigen::Index ncol,
                        std::vector<Eigen::Index>& lo, std::vector<Eigen::Index>& hi) {
  const auto& L = ldlt.matrixL().nestedExpression();
  for (Eigen::Index i = 0; i < L.outerSize(); ++i) {
    const Eigen::Index a = lo[static_cast<std::size_t>(i)], b = hi[static_cast<std::size_t>(i)];
    if (a >= b) continue;
    const double* yi = Y + i * ncol;
    for (typename std::decay_t<decltype(L)>::InnerIterator it(L, i); it; ++it) {
      const Eigen::Index r = it.index();
      if (r <= i) continue;  // the unit diagonal (and nothing above it) is not applied
      const double l = it.value();
      double* yr = Y + r * ncol;
      for (Eigen::Index c = a; c < b; ++c) yr[c] -= yi[c] * l;
      lo[static_cast<std::size_t>(r)] = std::min(lo[static_cast<std::size_t>(r)], a);
      hi[static_cast<std::size_t>(r)] = std::max(hi[static_cast<std::size_t>(r)], b);
    }
  }
}

}  // namespace

template <int Dim>
void ImplicitSolver<Dim>::build_slot_bases() {
  // The impulse a slot receives is a sum of its contacts' impulses: along their normals when they
  // are frictionless, anywhere in R^Dim otherwise. Its basis: Gram-Schmidt on those normals, in
  // contact order (a normal within 1e-6 of the span of the earlier ones adds nothing), the
  // identity once Dim directions are needed.
  const std::size_t ns = problem_.slots.size();
  slot_basis_.assign(ns, Mat<Dim>::Zero());
  slot_rank_.assign(ns, 0);
  const auto add = [&](std::int32_t s, const Vec<Dim>& n, bool frictional) {
    if (s < 0) return;
    Mat<Dim>& B = slot_basis_[static_cast<std::size_t>(s)];
    int& r = slot_rank_[static_cast<std::size_t>(s)];
    if (r == Dim) return;
    if (frictional) {
      B.setIdentity();
      r = Dim;
      return;
    }
    Vec<Dim> v = n;
    for (int m = 0; m < r; ++m) v -= B.col(m).dot(v) * B.col(m);
    if (!(v.norm() > 1e-6 * n.norm())) return;
    B.col(r++) = v.normalized();
    if (r == Dim) B.setIdentity();
  };
  for (const auto& c : problem_.contacts) {
    const bool frictional = c.friction != 0.0;
    add(c.a, c.normal, frictional);
    add(c.b, c.normal, frictional);
  }
  slot_bases_valid_ = true;
}

template <int Dim>
bool ImplicitSolver<Dim>::grain_compliance(std::size_t g) {
  // Z = A^-1 E B (response of the grain's velocities to unit impulses at its slots along their
  // basis directions B; A^-1 -> M^-1 for a lumped group) and its slot rows G = B (B^T E^T Z) B^T,
  // from the factorisation of the current Newton matrix. Column (j, d) of E is
  // sum_k w_jk e_{a_jk, d} (one node of weight 1 for a node slot). The impulses on slot j lie in
  // the span of B_j (its frictionless contacts' normals, or all directions), so G P and Z B^T P
  // are exact, and the contact solvers read G only along those directions (a frictionless
  // contact's normal velocity and n^T W n): with one normal per face slot, 1/Dim of the columns of
  // the full E (docs/contact.md, "Compliance on the contact directions").
  GrainWork& w = *work_[g];
  if (!w.lumped_group) {
    if (!reuse_factor(w, settings_) && !grain_factor(g, dt_)) return true;
    // Z and G depend only on the factorisation, the slots and their contacts (fixed in a step).
    if (w.z_factor == w.factor_count) return false;
    w.z_factor = w.factor_count;
  }
  const auto k = static_cast<Eigen::Index>(w.slots.size());
  const auto ndof = static_cast<Eigen::Index>(w.m.size() * Dim);
  contact::Group<Dim>& group = problem_.groups[problem_.slots[w.slots[0]].group];
  w.z_col.assign(static_cast<std::size_t>(k) + 1, 0);
  for (Eigen::Index j = 0; j < k; ++j)
    w.z_col[static_cast<std::size_t>(j) + 1] =
        w.z_col[static_cast<std::size_t>(j)] + slot_rank_[static_cast<std::size_t>(w.slots[j])];
  const Eigen::Index ncol = w.z_col.back();
  // With an LDL^T factorisation P A P^T = L D L^T, B^T E^T A^-1 E B = Y^T D^-1 Y with
  // Y = L^-1 P E B: forward substitutions only, and Y stays sparse because E's columns touch a
  // few nodes (the triangular solve skips zero entries). 4x cheaper than Z = A^-1 E for a CPDI
  // disk (docs/accuracy.md, cost); the velocity response then takes one back substitution.
  w.z_forward = !w.lumped_group && settings_.linear_solver == LinearSolverKind::kLdlt;
  // Column (j, m) of E B, without the prescribed components (which do not respond): into Z, or
  // for the forward-only response into row P_r of Y (kept from call to call, so that its memory
  // is reused), with each row's range of nonzero columns.
  const auto fill = [&](auto&& entry) {
    for (Eigen::Index j = 0; j < k; ++j) {
      const std::size_t s = static_cast<std::size_t>(w.slots[j]);
      const Mat<Dim>& B = slot_basis_[s];
      for (Eigen::Index m = 0; m < slot_rank_[s]; ++m)
        for (std::int32_t q = slot_start_[s]; q < slot_start_[s + 1]; ++q) {
          const std::int32_t a = slot_node_[q];
          const double f = slot_weight_[q] / (w.lumped_group ? w.m[a] : 1.0);
          for (int d = 0; d < Dim; ++d)
            if (!(w.mask[a] & (1u << d)) && B(d, m) != 0.0)
              entry(a * Dim + d, w.z_col[static_cast<std::size_t>(j)] + m, f * B(d, m));
        }
    }
  };
  Eigen::MatrixXd& Gr = group.Gr;  // B^T G B: the compliance on the slots' directions [s/kg]
  if (w.z_forward && w.factor_dense) {
    // Dense factor A = L L^T: Y = L^-1 E B by a blocked triangular solve, Gr = Y^T Y.
    w.resize_z(ndof, ncol, true);
    auto Z = w.Z();
    fill([&](Eigen::Index row, Eigen::Index col, double v) { Z(row, col) = v; });
    dense::lower_solve(w.chol, Z);
    dense::gram(Z, Gr);
  } else if (w.z_forward) {
    // E B goes straight into row P_r of a row-major Y (in buffers of the thread, their capacity
    // kept), with each row's range of nonzero columns; Y = L^-1 P E B then becomes Z.
    thread_local std::vector<double> y_store;
    thread_local std::vector<Eigen::Index> lo, hi;
    y_store.assign(static_cast<std::size_t>(ndof * ncol), 0.0);
    lo.assign(static_cast<std::size_t>(ndof), ncol);
    hi.assign(static_cast<std::size_t>(ndof), 0);
    const auto& perm = w.ldlt.permutationP().indices();
    fill([&](Eigen::Index row, Eigen::Index col, double v) {
      const auto r = static_cast<std::size_t>(perm[row]);
      y_store[r * static_cast<std::size_t>(ncol) + static_cast<std::size_t>(col)] = v;
      lo[r] = std::min(lo[r], col);
      hi[r] = std::max(hi[r], col + 1);
    });
    forward_substitute(w.ldlt, y_store.data(), ncol, lo, hi);
    w.resize_z(ndof, ncol, false);
    auto Z = w.Z();
    Z = Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
        y_store.data(), ndof, ncol);
    const Eigen::VectorXd& d = w.ldlt.vectorD();
    if (!(d.array() > 0.0).all()) {
      Gr.noalias() = Z.transpose() * d.cwiseInverse().asDiagonal() * Z;
    } else {
      // D > 0 (the projected tangent keeps the grains' Newton matrices positive definite when
      // they serve a compliance): S^T S with S = D^-1/2 Y, one triangle by a symmetric rank
      // update (half the flops of the general product), mirrored. S in a buffer of the thread.
      thread_local std::vector<double> s_store;
      s_store.resize(static_cast<std::size_t>(ndof * ncol));
      Eigen::Map<Eigen::MatrixXd> S(s_store.data(), ndof, ncol);
      S.noalias() = d.cwiseInverse().cwiseSqrt().asDiagonal() * Z;
      Gr.setZero(ncol, ncol);
      Gr.selfadjointView<Eigen::Lower>().rankUpdate(S.transpose());
      Gr.triangularView<Eigen::StrictlyUpper>() = Gr.transpose();
    }
  } else {
    w.resize_z(ndof, ncol, true);
    auto Z = w.Z();
    fill([&](Eigen::Index row, Eigen::Index col, double v) { Z(row, col) = v; });
    if (!w.lumped_group)
      for (Eigen::Index c = 0; c < ncol; ++c)
        if (Z.col(c).squaredNorm() > 0) Z.col(c) = linear_solve(w, settings_, Z.col(c));
    Gr.setZero(ncol, ncol);
    for (Eigen::Index i = 0; i < k; ++i) {
      const std::size_t s = static_cast<std::size_t>(w.slots[i]);
      Eigen::MatrixXd rows = Eigen::MatrixXd::Zero(Dim, ncol);  // E_i^T Z
      for (std::int32_t q = slot_start_[s]; q < slot_start_[s + 1]; ++q)
        rows += slot_weight_[q] * Z.middleRows(slot_node_[q] * Dim, Dim);
      Gr.middleRows(w.z_col[static_cast<std::size_t>(i)], slot_rank_[s]) =
          slot_basis_[s].leftCols(slot_rank_[s]).transpose() * rows;
    }
  }
  // The group keeps Gr with the slots' directions (G_ij = B_i Gr_ij B_j^T: contact::Group).
  group.col = w.z_col;
  group.basis.resize(static_cast<std::size_t>(k));
  for (Eigen::Index j = 0; j < k; ++j)
    group.basis[static_cast<std::size_t>(j)] = slot_basis_[static_cast<std::size_t>(w.slots[j])];
  return true;
}

template <int Dim>
void ImplicitSolver<Dim>::apply_lumped_impulse(std::int32_t g, std::int32_t a, const Vec<Dim>& P,
                                               std::vector<double>& dv2) {
  GrainWork& w = *work_[g];
  if (P == w.P[a]) return;
  const Vec<Dim> v_free = w.v[a] - w.P[a] / w.m[a];
  w.P[a] = P;
  const Vec<Dim> v_new = v_free + P / w.m[a];
  double& acc = dv2[static_cast<std::size_t>(g)];
  acc = std::max(acc, 0.0) + w.m[a] * (v_new - w.v[a]).squaredNorm();
  w.v[a] = v_new;
}

template <int Dim>
double ImplicitSolver<Dim>::update_contacts(StepStats& stats) {
  if (distributed()) return update_contacts_distributed(stats);  // lumped, Gauss-Seidel
  // Response of each grain: its compliance group (exact, linearised) or the lumped 1/m_I.
  const auto ngroups = static_cast<std::int64_t>(problem_.groups.size());
  if (!slot_bases_valid_) build_slot_bases();
  bool new_compliance = false;
  std::vector<char> changed(static_cast<std::size_t>(ngroups), 0);  // per group: a new G
  ThreadedRegion threaded(&timers_, ngroups > 1);
#pragma omp parallel for schedule(dynamic, 1) if (ngroups > 1) reduction(|| : new_compliance)
  for (std::int64_t gi = 0; gi < ngroups; ++gi) {
    const bool fresh =
        grain_compliance(static_cast<std::size_t>(slot_ref_[problem_.groups[gi].slots[0]].first));
    changed[static_cast<std::size_t>(gi)] = fresh ? 1 : 0;
    new_compliance = fresh || new_compliance;
  }
  threaded.done();
  if (new_compliance) as_cache_.compliance_changed(changed);
  for (const auto& w : work_)
    if (!w->failure.empty()) return 1.0;
  // Free velocities: the grains' current iterates without their contact impulses (method.md §4).
  // A slot alone at its node: v - P/m. A group's slots: v - sum_j G_{s,j} P_j, the terms
  // subtracted in the order of j; per group, column block j of G against all its rows at once
  // (contiguous, the bits of G.block(Dim s, Dim j) * P_j), the groups on the threads.
  const auto nslots = static_cast<std::int64_t>(slot_ref_.size());
  for (std::int64_t si = 0; si < nslots; ++si) {
    const auto s = static_cast<std::size_t>(si);
    const GrainWork& w = *work_[slot_ref_[s].first];
    const std::int32_t a = slot_ref_[s].second;
    auto& slot = problem_.slots[s];
    if (!slot_is_face_[s]) slot.mass = w.m[a];
    if (slot.group < 0)  // a node slot alone at its node (face slots are always grouped)
      slot.v_free = w.v[a] - slot_P_[s] / w.m[a];
  }
  {
    ThreadedRegion threaded_free(&timers_, ngroups > 1);
#pragma omp parallel for schedule(dynamic, 1) if (ngroups > 1)
    for (std::int64_t gi = 0; gi < ngroups; ++gi) {
      const contact::Group<Dim>& group = problem_.groups[static_cast<std::size_t>(gi)];
      const auto k = group.slots.size();
      std::vector<double> vf(Dim * k);
      for (std::size_t j = 0; j < k; ++j) {
        const auto s = static_cast<std::size_t>(group.slots[j]);
        const Vec<Dim> v0 =
            slot_is_face_[s] ? slot_velocity(s) : work_[slot_ref_[s].first]->v[slot_ref_[s].second];
        for (int d = 0; d < Dim; ++d) vf[Dim * j + static_cast<std::size_t>(d)] = v0[d];
      }
      // v_free = v - B Gr B^T P (contact::Group): the impulses on the directions, Gr times them,
      // back to the slots' components.
      Eigen::VectorXd pr(group.Gr.rows());
      for (std::size_t j = 0; j < k; ++j) {
        const Vec<Dim>& P = slot_P_[static_cast<std::size_t>(group.slots[j])];
        for (int m = 0; m < group.rank(j); ++m) pr[group.col[j] + m] = group.basis[j].col(m).dot(P);
      }
      const Eigen::VectorXd ur = group.Gr * pr;
      for (std::size_t j = 0; j < k; ++j)
        for (int m = 0; m < group.rank(j); ++m)
          for (int d = 0; d < Dim; ++d)
            vf[Dim * j + static_cast<std::size_t>(d)] -=
                group.basis[j](d, m) * ur[group.col[j] + m];
      for (std::size_t j = 0; j < k; ++j)
        for (int d = 0; d < Dim; ++d)
          problem_.slots[static_cast<std::size_t>(group.slots[j])].v_free[d] =
              vf[Dim * j + static_cast<std::size_t>(d)];
    }
  }
  std::vector<Vec<Dim>> old(problem_.contacts.size());
  for (std::size_t c = 0; c < old.size(); ++c) old[c] = problem_.contacts[c].impulse;
  // With the active-set solver the staggering's impulse change is measured on the grains' nodal
  // impulses, which the contact problem determines uniquely, not on the contacts' impulses,
  // which redundant contacts (two grains' faces on one interface) share in a way that may drift
  // from one Newton iteration to the next (docs/contact.md).
  const bool nodal_change = settings_.contact.active_set;
  std::vector<std::vector<Vec<Dim>>> old_nodal;
  if (nodal_change)
    for (const auto& w : work_) old_nodal.push_back(w->P);
  contact::GsResult r;
  // Debugging (docs/contact.md): MPMCD_WRITE_STALLED_PROBLEM=<folder> writes each problem whose
  // solve does not converge or takes more than 100 Gauss-Seidel sweeps, as given (warm start),
  // for contact::read_problem.
  static const char* const stalled_dir = std::getenv("MPMCD_WRITE_STALLED_PROBLEM");
  contact::Problem<Dim> given;
  if (stalled_dir) given = problem_;
  {
    ScopedStage t(&timers_, "contact.gs");
    if (!sweep_order_ready_) {
      sweep_order_ = contact::sweep_order(problem_);
      sweep_order_ready_ = true;
    }
    contact::GsSettings gs = gs_settings();
    gs.order = &sweep_order_;
    r = settings_.contact.active_set ? contact::solve_active_set(problem_, gs, &as_cache_)
                                     : contact::solve_gauss_seidel(problem_, gs);
  }
  if (stalled_dir && (!r.converged || r.sweeps > 100)) {
    static int written = 0;
    contact::write_problem(given, fmt::format("{}/stalled_{:04d}.txt", stalled_dir, written++));
  }
  gs_converged_ = r.converged;
  const auto [num, den] = detail::impulse_change(problem_, old, r, stats);
  const std::vector<Vec<Dim>> slot_p = contact::net_impulses(problem_);
  // The new impulses enter the grains' residuals; their velocities take the linearised response
  // (v += Z dP, or the lumped v = v_free + P/m), and a grain whose impulses changed iterates again.
  std::vector<double> dv2(work_.size(), -1.0);
  for (std::size_t s = 0; s < slot_ref_.size(); ++s) {
    if (problem_.slots[s].group >= 0) continue;
    slot_P_[s] = slot_p[s];
    apply_lumped_impulse(slot_ref_[s].first, slot_ref_[s].second, slot_p[s], dv2);
  }
  // Each group's response on the threads: a group is one grain's, and writes only that grain's
  // velocities and its own slots' impulses.
  ThreadedRegion threaded_response(&timers_, ngroups > 1);
#pragma omp parallel for schedule(dynamic, 1) if (ngroups > 1)
  for (std::int64_t gi = 0; gi < ngroups; ++gi) {
    const contact::Group<Dim>& group = problem_.groups[static_cast<std::size_t>(gi)];
    const std::int32_t g = slot_ref_[group.slots[0]].first;
    GrainWork& w = *work_[g];
    Eigen::VectorXd dP(w.z_col.back());  // B^T (P - P_old), slot after slot
    bool changed = false;
    for (std::size_t j = 0; j < group.slots.size(); ++j) {
      const std::int32_t s = group.slots[j];
      const Vec<Dim> d = slot_p[s] - slot_P_[s];
      changed = changed || d != Vec<Dim>::Zero();
      const int r = slot_rank_[static_cast<std::size_t>(s)];
      dP.segment(w.z_col[j], r) =
          slot_basis_[static_cast<std::size_t>(s)].leftCols(r).transpose() * d;
      slot_P_[s] = slot_p[s];
    }
    if (!changed) continue;
    // dv = A^-1 E B B^T dP = Z B^T dP (dP lies in the span of B), or P^T L^-T D^-1 Y B^T dP with
    // the forward-only response.
    Eigen::VectorXd dv = w.Z() * dP;
    if (w.z_forward && w.factor_dense) {
      dense::lower_transpose_solve(w.chol, dv);
    } else if (w.z_forward) {
      dv = w.ldlt.vectorD().cwiseInverse().asDiagonal() * dv;
      w.ldlt.matrixU().solveInPlace(dv);
      dv = w.ldlt.permutationPinv() * dv;
    }
    double acc = 0;
    for (std::size_t a = 0; a < w.m.size(); ++a) {
      const Vec<Dim> d = dv.template segment<Dim>(static_cast<Eigen::Index>(a * Dim));
      w.v[a] += d;
      acc += w.m[a] * d.squaredNorm();
    }
    dv2[g] = acc;
  }
  threaded_response.done();
  if (!problem_.groups.empty()) spread_slot_impulses();
  for (std::size_t g = 0; g < work_.size(); ++g)
    if (dv2[g] >= 0.0) work_[g]->impulses_changed(dv2[g]);
  if (nodal_change) {
    double nodal_num = 0, nodal_den = 0;
    for (std::size_t g = 0; g < work_.size(); ++g)
      for (std::size_t a = 0; a < work_[g]->P.size(); ++a) {
        const Vec<Dim>& P = work_[g]->P[a];
        const Vec<Dim> P_old = a < old_nodal[g].size() ? old_nodal[g][a] : Vec<Dim>::Zero();
        nodal_num += (P - P_old).squaredNorm();
        nodal_den += P.squaredNorm();
      }
    return detail::relative_change(nodal_num, nodal_den, gs_converged_);
  }
  return detail::relative_change(num, den, gs_converged_);
}

// The members defined here (the class is instantiated in solver.cpp).
#define MPMCD_INSTANTIATE(D)                                                                       \
  template void ImplicitSolver<D>::set_warm_start(std::vector<WarmImpulse<D>>);                    \
  template void ImplicitSolver<D>::renumber_points(std::span<const std::int64_t>);                 \
  template void ImplicitSolver<D>::sort_unique(std::vector<WarmImpulse<D>>&);                      \
  template std::vector<WarmImpulse<D>> ImplicitSolver<D>::gather_warm_start() const;               \
  template Vec<D> ImplicitSolver<D>::slot_velocity(std::size_t) const;                             \
  template void ImplicitSolver<D>::spread_slot_impulses();                                         \
  template bool ImplicitSolver<D>::grain_compliance(std::size_t);                                  \
  template void ImplicitSolver<D>::build_slot_bases();                                             \
  template double ImplicitSolver<D>::update_contacts(StepStats&);                                  \
  template void ImplicitSolver<D>::apply_lumped_impulse(std::int32_t, std::int32_t, const Vec<D>&, \
                                                        std::vector<double>&);
MPMCD_INSTANTIATE(2)
MPMCD_INSTANTIATE(3)
#undef MPMCD_INSTANTIATE

}  // namespace mpmcd::mpm
