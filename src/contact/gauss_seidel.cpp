// The nonlinear Gauss-Seidel solver of a contact problem (method.md §4;
// include/mpmcd/contact/problem.hpp): the slots' velocities during the sweeps (SlotVelocities,
// respond), the sweep order and its colours (sweep_order), one sweep of the problem's contact
// law's local solutions (contact/law.hpp, resolved once per solve) with the exact nodal blocks
// (solve_node_block, their Delassus matrices kept in a BlockCache), the sweeps until the error is
// met (solve_gauss_seidel, serial or over a distributed problem) and the error measure
// (error_terms, error).
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>

#include "mpmcd/contact/law.hpp"
#include "mpmcd/contact/problem.hpp"

namespace mpmcd::contact {

namespace {

// Diagonal response block W_ss of slot s: I/m (lumped) or its block of the group's G.
template <int Dim>
Mat<Dim> self_block(const Problem<Dim>& p, std::int32_t s) {
  const Slot<Dim>& sl = p.slots[s];
  if (sl.group < 0) return Mat<Dim>::Identity() / sl.mass;
  return p.groups[sl.group].block(static_cast<std::size_t>(sl.local),
                                  static_cast<std::size_t>(sl.local));
}

// The slots' velocities during the sweeps, each group's slots stored contiguously in their local
// order (then the slots without a group), so that a slot's response is one pass over a column
// block of its group's G and a contiguous run of velocities. v[s] is slot s's velocity.
template <int Dim>
struct SlotVelocities {
  std::vector<Vec<Dim>> value;      // by position [m/s]
  std::vector<std::int32_t> pos;    // per slot: its position in value
  std::vector<std::int32_t> first;  // per group: the position of its first slot
  Vec<Dim>& operator[](std::int32_t s) { return value[static_cast<std::size_t>(pos[s])]; }
  const Vec<Dim>& operator[](std::int32_t s) const {
    return value[static_cast<std::size_t>(pos[s])];
  }
};

// Adds the response to an impulse increment dP on slot s to the slot velocities v.
template <int Dim>
void respond(const Problem<Dim>& p, SlotVelocities<Dim>& v, std::int32_t s, const Vec<Dim>& dP) {
  const Slot<Dim>& sl = p.slots[s];
  if (sl.group < 0) {
    v[s] += dP / sl.mass;
    return;
  }
  // v_j += G_{j,s} dP = B_j Gr_js (B_s^T dP) for every slot j of the group (contact::Group), on
  // the slots' directions: one number per direction pair, against the group's contiguous
  // velocities.
  const Group<Dim>& g = p.groups[sl.group];
  const auto s_local = static_cast<std::size_t>(sl.local);
  const int rs = g.rank(s_local);
  std::array<double, Dim> q{};  // B_s^T dP
  for (int m = 0; m < rs; ++m) q[m] = g.basis[s_local].col(m).dot(dP);
  const double* gr = g.Gr.data();
  const auto ld = static_cast<std::size_t>(g.Gr.rows());
  const auto cs = static_cast<std::size_t>(g.col[s_local]);
  Vec<Dim>* out = &v.value[static_cast<std::size_t>(v.first[sl.group])];
  for (std::size_t j = 0; j < g.slots.size(); ++j) {
    const auto cj = static_cast<std::size_t>(g.col[j]);
    for (int n = 0; n < g.rank(j); ++n) {
      double t = 0;  // (Gr_js B_s^T dP)_n
      for (int m = 0; m < rs; ++m) t += gr[(cs + m) * ld + cj + n] * q[m];
      out[j] += t * g.basis[j].col(n);
    }
  }
}

// Contacts above which the per-node work is shared among threads (lumped operator: a contact
// costs a few hundred ns) and above which the work is shared when compliance groups couple the
// nodes (a contact update costs a pass over its groups' slots).
constexpr std::size_t kThreadedContacts = 1024;
constexpr std::size_t kThreadedGroupContacts = 64;

// Whether the sweeps and error sums of problem p run on the threads.
template <int Dim>
bool threaded_problem(const Problem<Dim>& p) {
  return p.contacts.size() > (p.groups.empty() ? kThreadedContacts : kThreadedGroupContacts);
}

// The slots' velocities v_free + response to the current impulses, the groups on the threads if
// `threads` (their wall time to `timers`, stage kThreadedStage; null: none).
template <int Dim>
SlotVelocities<Dim> slot_velocities(const Problem<Dim>& p, bool threads, StageTimers* timers) {
  SlotVelocities<Dim> v;
  const auto nslots = static_cast<std::int32_t>(p.slots.size());
  v.value.resize(p.slots.size());
  v.pos.assign(p.slots.size(), -1);
  v.first.resize(p.groups.size());
  std::int32_t next = 0;
  for (std::size_t g = 0; g < p.groups.size(); ++g) {
    v.first[g] = next;
    for (const std::int32_t s : p.groups[g].slots) v.pos[s] = next++;
  }
  for (std::int32_t s = 0; s < nslots; ++s)
    if (v.pos[s] < 0) v.pos[s] = next++;
  for (std::int32_t s = 0; s < nslots; ++s) v[s] = p.slots[s].v_free;
  const auto net = net_impulses(p);
  // A group's impulses move its own slots only: the groups on the threads, each summing its
  // slots' responses in its slot order (the same bits for any thread count).
  const auto ng = static_cast<std::int64_t>(p.groups.size());
  ThreadedRegion region(timers, threads);
#pragma omp parallel for schedule(dynamic, 4) if (threads)
  for (std::int64_t g = 0; g < ng; ++g)
    for (const std::int32_t s : p.groups[g].slots)
      if (net[s] != Vec<Dim>::Zero()) respond(p, v, s, net[s]);
  region.done();
  for (std::size_t s = 0; s < p.slots.size(); ++s)
    if (p.slots[s].group < 0 && net[s] != Vec<Dim>::Zero())
      respond(p, v, static_cast<std::int32_t>(s), net[s]);
  return v;
}

// Relative free velocity of contact c (its own impulse removed) and its Delassus block W.
template <int Dim>
void free_velocity(const Problem<Dim>& p, const SlotVelocities<Dim>& v, const Contact<Dim>& c,
                   Vec<Dim>& u_free, Mat<Dim>& W) {
  W = self_block(p, c.b);
  const Vec<Dim> vb = v[c.b] - W * c.impulse;
  Vec<Dim> va = c.wall_velocity;
  if (c.a >= 0) {
    const Mat<Dim> Wa = self_block(p, c.a);
    va = v[c.a] + Wa * c.impulse;
    W += Wa;
  }
  u_free = vb - va;
}

}  // namespace

template <int Dim>
SweepOrder sweep_order(const Problem<Dim>& p) {
  SweepOrder runs;
  const auto n = static_cast<std::int32_t>(p.contacts.size());
  runs.order.resize(static_cast<std::size_t>(n));
  for (std::int32_t c = 0; c < n; ++c) runs.order[c] = c;
  const auto node = [&](std::int32_t c) { return p.slots[p.contacts[c].b].node; };
  std::stable_sort(runs.order.begin(), runs.order.end(),
                   [&](std::int32_t x, std::int32_t y) { return node(x) < node(y); });
  std::vector<std::int32_t> start{0};
  for (std::int32_t k = 1; k < n; ++k)
    if (node(runs.order[k]) != node(runs.order[k - 1])) start.push_back(k);
  start.push_back(n);
  if (p.groups.empty()) {
    runs.start = std::move(start);
    runs.phase = {0, static_cast<std::int32_t>(runs.start.size()) - 1};
    return runs;
  }
  // Resources of a slot: its group, or the slot itself when lumped (after the groups).
  const auto resource = [&](std::int32_t s) {
    return p.slots[s].group >= 0 ? p.slots[s].group
                                 : static_cast<std::int32_t>(p.groups.size()) + s;
  };
  const std::size_t nres = p.groups.size() + p.slots.size();
  const auto nruns = static_cast<std::int32_t>(start.size()) - 1;
  std::vector<std::vector<char>> used(nres);  // used[resource][colour]
  std::vector<std::int32_t> colour(static_cast<std::size_t>(nruns));
  std::int32_t ncolours = 0;
  std::vector<std::int32_t> res;
  for (std::int32_t r = 0; r < nruns; ++r) {
    res.clear();
    for (std::int32_t k = start[r]; k < start[r + 1]; ++k) {
      const Contact<Dim>& c = p.contacts[runs.order[k]];
      res.push_back(resource(c.b));
      if (c.a >= 0) res.push_back(resource(c.a));
    }
    std::int32_t col = 0;
    for (;; ++col) {
      bool free = true;
      for (const std::int32_t q : res)
        if (col < static_cast<std::int32_t>(used[q].size()) && used[q][col]) free = false;
      if (free) break;
    }
    for (const std::int32_t q : res) {
      if (static_cast<std::int32_t>(used[q].size()) <= col) used[q].resize(col + 1, 0);
      used[q][col] = 1;
    }
    colour[r] = col;
    ncolours = std::max(ncolours, col + 1);
  }
  // The runs colour by colour (node order within a colour), the contacts in their run's order.
  std::vector<std::int32_t> order;
  order.reserve(runs.order.size());
  runs.start = {0};
  runs.phase = {0};
  for (std::int32_t col = 0; col < ncolours; ++col) {
    for (std::int32_t r = 0; r < nruns; ++r)
      if (colour[r] == col) {
        for (std::int32_t k = start[r]; k < start[r + 1]; ++k) order.push_back(runs.order[k]);
        runs.start.push_back(static_cast<std::int32_t>(order.size()));
      }
    runs.phase.push_back(static_cast<std::int32_t>(runs.start.size()) - 1);
  }
  runs.order = std::move(order);
  return runs;
}

namespace {

// One sweep: each contact solved exactly with the others' current impulses (method.md §4), in
// the serial order within a node; the nodes on the threads (the same impulses for any count).
template <int Dim>
Vec<Dim> project_cone(const Vec<Dim>& P, const Vec<Dim>& n, double mu) {
  // Closest point of the Coulomb cone {p_n >= 0, |p_t| <= mu p_n} to P (in the Euclidean norm).
  const double pn = P.dot(n);
  const Vec<Dim> pt = P - pn * n;
  const double ptn = pt.norm();
  if (ptn <= mu * pn) return P;
  if (mu * ptn <= -pn) return Vec<Dim>::Zero();
  const double qn = (pn + mu * ptn) / (1.0 + mu * mu);
  return qn * n + (ptn > 0 ? (mu * qn / ptn) * pt : Vec<Dim>(Vec<Dim>::Zero()));
}

// Response block of slot s's velocity to an impulse on slot t: I/m or G_st within one group, 0
// between slots of different groups (or walls, t < 0).
template <int Dim>
Mat<Dim> cross_block(const Problem<Dim>& p, std::int32_t s, std::int32_t t) {
  if (s < 0 || t < 0) return Mat<Dim>::Zero();
  if (s == t) return self_block(p, s);
  const Slot<Dim>&ss = p.slots[s], &st = p.slots[t];
  if (ss.group < 0 || ss.group != st.group) return Mat<Dim>::Zero();
  return p.groups[ss.group].block(static_cast<std::size_t>(ss.local),
                                  static_cast<std::size_t>(st.local));
}

// Largest node block solved exactly (2^k active sets).
constexpr int kMaxBlock = 6;

// Exact solution of the k frictionless contacts idx[0..k) of one node together (the nodal block,
// GsSettings::node_blocks): with the other impulses fixed, the linear complementarity problem
// p >= 0, w = u + W (p - p0) >= 0, p . w = 0 over their normal impulses, u_c the current normal
// relative velocity plus g/dt and W_cd = n_c . (response of contact c to a unit impulse of d)
// (method.md §4), solved by trying the active sets in turn with a minimum-norm solve (the node's
// contacts may be redundant: a light field pinched between two grains). Returns false, leaving
// the impulses unchanged, when a contact has friction, k is out of range or no set fits.
// The Delassus matrices W of the nodal blocks of one Gauss-Seidel solve, by the position of the
// block's first contact in the sweep order: they do not change during the solve (the groups' G
// and the normals are fixed), so each is made at the block's first visit, by the thread that
// owns the block's run (GsSettings::node_blocks).
struct BlockCache {
  std::vector<Eigen::Matrix<double, kMaxBlock, kMaxBlock>> W;
  std::vector<char> ready;
};

template <int Dim>
bool solve_node_block(Problem<Dim>& p, SlotVelocities<Dim>& v, const std::int32_t* idx, int k,
                      BlockCache* cache, std::size_t at) {
  if (k < 2 || k > kMaxBlock) return false;
  using MatK = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxBlock, kMaxBlock>;
  using VecK = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxBlock, 1>;
  MatK W(k, k);
  VecK u(k), p0(k);
  const bool cached = cache && cache->ready[at];
  for (int i = 0; i < k; ++i) {
    const Contact<Dim>& c = p.contacts[idx[i]];
    if (c.friction != 0.0) return false;
    const Vec<Dim> va = c.a >= 0 ? v[c.a] : c.wall_velocity;
    u[i] = c.normal.dot(v[c.b] - va) + c.gap / p.dt;
    p0[i] = c.impulse.dot(c.normal);
    if (cached) continue;
    for (int j = 0; j < k; ++j) {
      const Contact<Dim>& d = p.contacts[idx[j]];
      // Velocity of (b_c - a_c) per unit impulse n_d on b_d and -n_d on a_d.
      const Mat<Dim> R = cross_block(p, c.b, d.b) - cross_block(p, c.b, d.a) -
                         cross_block(p, c.a, d.b) + cross_block(p, c.a, d.a);
      W(i, j) = c.normal.dot(R * d.normal);
    }
  }
  if (cached) {
    W = cache->W[at].topLeftCorner(k, k);
  } else if (cache) {
    cache->W[at].topLeftCorner(k, k) = W;
    cache->ready[at] = 1;
  }
  const VecK base = u - W * p0;  // w = base + W p
  // Every active set, the one with the smallest violation of p >= 0, w >= 0 (relative to each
  // contact's scale |base_i| + W_ii |p_i|) is taken; an exact solution has none.
  VecK best;
  double best_violation = std::numeric_limits<double>::infinity();
  // The current active set first (Gauss-Seidel keeps it once converging: one solve), then the
  // others in order.
  int current = 0;
  for (int i = 0; i < k; ++i)
    if (p0[i] > 0) current |= 1 << i;
  for (int trial = -1; trial < (1 << k); ++trial) {
    if (trial == current) continue;
    const int mask = trial < 0 ? current : trial;
    VecK q = VecK::Zero(k);
    int na = 0;
    std::array<int, kMaxBlock> act{};
    for (int i = 0; i < k; ++i)
      if (mask & (1 << i)) act[na++] = i;
    if (na > 0) {
      MatK Wa(na, na);
      VecK ra(na);
      for (int i = 0; i < na; ++i) {
        ra[i] = -base[act[i]];
        for (int j = 0; j < na; ++j) Wa(i, j) = W(act[i], act[j]);
      }
      // LDL^T when W_AA is safely positive definite, else the minimum-norm solution (redundant
      // contacts make it singular).
      VecK qa;
      const auto ldlt = Wa.ldlt();
      if (ldlt.info() == Eigen::Success && ldlt.isPositive() &&
          ldlt.vectorD().minCoeff() > 1e-8 * ldlt.vectorD().maxCoeff())
        qa = ldlt.solve(ra);
      else
        qa = Wa.completeOrthogonalDecomposition().solve(ra);
      if (!qa.allFinite()) continue;
      for (int i = 0; i < na; ++i) q[act[i]] = qa[i];
    }
    const VecK w = base + W * q;
    double violation = 0;
    for (int i = 0; i < k; ++i) {
      const double scale =
          std::abs(base[i]) + W(i, i) * (std::abs(q[i]) + std::abs(p0[i])) + 1e-300;
      const double wi = (mask & (1 << i)) ? std::abs(w[i]) : std::max(-w[i], 0.0);
      violation = std::max(violation, wi / scale);
      if (W(i, i) > 0) violation = std::max(violation, std::max(-q[i], 0.0) * W(i, i) / scale);
    }
    if (violation < best_violation) {
      best_violation = violation;
      best = q;
    }
    if (violation <= 1e-14) break;
  }
  if (!(best_violation <= 1e-10)) return false;
  for (int i = 0; i < k; ++i) {
    Contact<Dim>& c = p.contacts[idx[i]];
    const Vec<Dim> P = std::max(best[i], 0.0) * c.normal;
    const Vec<Dim> dP = P - c.impulse;
    if (dP == Vec<Dim>::Zero()) continue;
    respond(p, v, c.b, dP);
    if (c.a >= 0) respond(p, v, c.a, Vec<Dim>(-dP));
    c.impulse = P;
  }
  return true;
}

// local: the problem's contact law's local solver; omega and node_blocks only for a Signorini law.
template <int Dim>
void sweep(Problem<Dim>& p, SlotVelocities<Dim>& v, const SweepOrder& runs, StageTimers* timers,
           LocalSolver<Dim> local, double omega, bool node_blocks, bool threads,
           BlockCache* cache) {
  const ThreadedRegion threaded(timers, threads);
  for (std::size_t ph = 0; ph + 1 < runs.phase.size(); ++ph)
#pragma omp parallel for schedule(dynamic, 8) if (threads)
    for (std::int64_t r = runs.phase[ph]; r < runs.phase[ph + 1]; ++r)
      for (std::int32_t k = runs.start[r], block_end = k; k < runs.start[r + 1]; ++k) {
        if (node_blocks && k >= block_end) {  // the next node's contacts [k, block_end)
          const std::int64_t node = p.slots[p.contacts[runs.order[k]].b].node;
          block_end = k + 1;
          while (block_end < runs.start[r + 1] &&
                 p.slots[p.contacts[runs.order[block_end]].b].node == node)
            ++block_end;
          if (solve_node_block(p, v, runs.order.data() + k, block_end - k, cache,
                               static_cast<std::size_t>(k))) {
            k = block_end - 1;
            continue;
          }
        }
        Contact<Dim>& c = p.contacts[runs.order[k]];
        Vec<Dim> u;
        Mat<Dim> W;
        free_velocity(p, v, c, u, W);
        Vec<Dim> P = local(u, W, c.normal, c.gap / p.dt, c.friction);
        if (omega != 1.0 && c.friction == 0.0)  // projected SOR on the normal cone p_n >= 0
          P = project_cone<Dim>(c.impulse + omega * (P - c.impulse), c.normal, 0.0);
        const Vec<Dim> dP = P - c.impulse;
        if (dP == Vec<Dim>::Zero()) continue;
        respond(p, v, c.b, dP);
        if (c.a >= 0) respond(p, v, c.a, Vec<Dim>(-dP));
        c.impulse = P;
      }
}

// error_terms, its loops on the threads if `threads`, by the local solver `local`.
template <int Dim>
void error_sums(const Problem<Dim>& p, double& num, double& den, StageTimers* timers, bool threads,
                LocalSolver<Dim> local) {
  const auto v = slot_velocities(p, threads, timers);
  // Each contact's terms on the threads, summed in contact order (the same bits for any count).
  const auto n = static_cast<std::int64_t>(p.contacts.size());
  std::vector<double> tn(static_cast<std::size_t>(n)), td(static_cast<std::size_t>(n));
  {
    const ThreadedRegion threaded(timers, threads);
#pragma omp parallel for schedule(static) if (threads)
    for (std::int64_t i = 0; i < n; ++i) {
      const Contact<Dim>& c = p.contacts[i];
      Vec<Dim> u;
      Mat<Dim> W;
      free_velocity(p, v, c, u, W);
      const Vec<Dim> loc = local(u, W, c.normal, c.gap / p.dt, c.friction);
      tn[i] = (loc - c.impulse).squaredNorm();
      td[i] = c.impulse.squaredNorm();
    }
  }
  num = 0;
  den = 0;
  for (std::int64_t i = 0; i < n; ++i) {
    num += tn[i];
    den += td[i];
  }
}

// sqrt(num) / sqrt(den), 0 without any change.
double error_ratio(double num, double den) {
  return num == 0.0 ? 0.0 : std::sqrt(num) / std::sqrt(std::max(den, 1e-300));
}

// The sweeps until the error is <= tolerance or max_sweeps, the error summed over every part of
// a distributed problem by `reduce` (null: a whole problem). The problem's contact law is looked up
// once. With a tuner each sweep and its error run on the threads or on one thread as the tuner
// chooses (the same bits either way: the colours fix the order), and their time per contact is
// recorded.
template <int Dim>
GsResult gauss_seidel(Problem<Dim>& p, const GsSettings& settings, const ErrorReduce* reduce) {
  const ContactLaw& law = find_contact_law(p.law);
  const LocalSolver<Dim> local = law.template local<Dim>();
  const auto error_now = [&](bool threads) {
    double num = 0, den = 0;
    error_sums(p, num, den, settings.timers, threads, local);
    if (reduce) (*reduce)(num, den);
    return error_ratio(num, den);
  };
  GsResult r;
  const bool can_thread = threaded_problem(p) && omp_get_max_threads() > 1;
  ThreadTuner* const tuner = can_thread ? settings.tuner : nullptr;
  r.error = error_now(can_thread);
  if (r.error <= settings.tolerance) {
    r.converged = true;
    return r;
  }
  auto v = slot_velocities(p, can_thread, settings.timers);
  const SweepOrder own = settings.order ? SweepOrder{} : sweep_order(p);
  const SweepOrder& runs = settings.order ? *settings.order : own;
  const double work = static_cast<double>(p.contacts.size());
  BlockCache cache;
  const bool node_blocks = settings.node_blocks && law.signorini;
  if (node_blocks) {
    cache.W.resize(runs.order.size());
    cache.ready.assign(runs.order.size(), 0);
  }
  while (r.sweeps < settings.max_sweeps) {
    const bool threads = tuner ? tuner->threaded() : can_thread;
    const auto t0 = std::chrono::steady_clock::now();
    const double omega =
        law.signorini && r.sweeps >= settings.relax_after ? settings.relaxation : 1.0;
    sweep(p, v, runs, settings.timers, local, omega, node_blocks, threads, &cache);
    ++r.sweeps;
    r.error = error_now(threads);
    if (tuner)
      tuner->record(
          threads,
          std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() / work);
    if (r.error <= settings.tolerance) {
      r.converged = true;
      break;
    }
  }
  return r;
}

}  // namespace

template <int Dim>
void error_terms(const Problem<Dim>& p, double& num, double& den, StageTimers* timers) {
  error_sums(p, num, den, timers, threaded_problem(p),
             find_contact_law(p.law).template local<Dim>());
}

template <int Dim>
GsResult solve_gauss_seidel(Problem<Dim>& p, const GsSettings& settings,
                            const ErrorReduce& reduce) {
  return gauss_seidel(p, settings, &reduce);
}

template <int Dim>
double error(const Problem<Dim>& p) {
  double num = 0, den = 0;
  error_terms(p, num, den);
  return error_ratio(num, den);
}

template <int Dim>
GsResult solve_gauss_seidel(Problem<Dim>& p, const GsSettings& settings) {
  return gauss_seidel<Dim>(p, settings, nullptr);
}

#define MPMCD_INSTANTIATE(D)                                                       \
  template double error<D>(const Problem<D>&);                                     \
  template SweepOrder sweep_order<D>(const Problem<D>&);                           \
  template GsResult solve_gauss_seidel<D>(Problem<D>&, const GsSettings&);         \
  template void error_terms<D>(const Problem<D>&, double&, double&, StageTimers*); \
  template GsResult solve_gauss_seidel<D>(Problem<D>&, const GsSettings&, const ErrorReduce&);
MPMCD_INSTANTIATE(2)
MPMCD_INSTANTIATE(3)
#undef MPMCD_INSTANTIATE

}  // namespace mpmcd::contact
