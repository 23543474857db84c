// The distributed step (docs/parallel.md): distribution of the grains over the ranks, work
// counts for re-balancing, failures agreed over the ranks, the exchange of the ghost grains'
// contact nodes and of the slots' requests, and the contact update on several ranks.
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <stdexcept>
#include <vector>

#include "mpmcd/core/errors.hpp"
#include "solver_detail.hpp"

namespace mpmcd::mpm {

// ---------------------------------------------------------------------------------------------
// Distributed step (docs/parallel.md).

namespace {
template <class T>
T take(parallel::Buffer& b) {
  return b.get<T>();
}
}  // namespace

template <int Dim>
void ImplicitSolver<Dim>::set_distribution(const parallel::Comm* comm, std::vector<int> owner,
                                           parallel::Scheme scheme) {
  if (owner.size() != grains_.size())
    throw std::invalid_argument("ImplicitSolver::set_distribution: one owner per grain");
  comm_ = comm != nullptr ? comm : &parallel::Comm::alone();
  owner_ = std::move(owner);
  scheme_ = scheme;
  if (distributed() && settings_.contact.enabled && settings_.contact.wall_points)
    throw InputError("", 0, "contact.wall_contact",
                     "wall contact at the points' faces (\"points\") runs on one rank for now: "
                     "use wall_contact = \"nodes\" on several ranks");
  if (distributed() && settings_.contact.enabled && settings_.contact.grain_faces)
    throw InputError("", 0, "contact.grain_contact",
                     "grain-grain contact at the points' faces (\"faces\") runs on one rank for "
                     "now: use grain_contact = \"nodes\" on several ranks");
  if (distributed() && settings_.contact.enabled && settings_.contact.active_set)
    throw InputError("", 0, "contact.solver",
                     "the active-set contact solver runs on one rank for now: use solver = "
                     "\"gauss_seidel\" on several ranks");
  if (distributed() && settings_.contact.enabled && settings_.contact.grain_compliance &&
      settings_.linear_solver != LinearSolverKind::kCg)
    throw InputError("", 0, "contact.delassus",
                     "the grain compliance operator couples all contacts of a grain and is not "
                     "available on more than one rank yet: use delassus = \"lumped\" (or run on "
                     "one rank)");
  // Every rank's warm-start impulses to every rank: the contacts of a node move with its lowest
  // grain, and the new owner must find their impulses (as after a restart, which reads them all).
  if (distributed()) set_warm_start(gather_warm_start());
}

template <int Dim>
std::vector<double> ImplicitSolver<Dim>::take_grain_work() {
  std::vector<double> w(grains_.size() * parallel::kWorkPhases, 0.0);
  grain_work_.resize(w.size(), 0.0);
  w.swap(grain_work_);
  return w;
}

template <int Dim>
double& ImplicitSolver<Dim>::phase_work(std::size_t g, int iteration) {
  return grain_work_[g * parallel::kWorkPhases +
                     static_cast<std::size_t>(std::min(iteration, parallel::kWorkPhases - 1))];
}

template <int Dim>
bool ImplicitSolver<Dim>::sync_failure(StepStats& stats, std::int64_t lowest) {
  // The lowest failing grain over all ranks (reduced here unless given), its message from its
  // owner; on one rank, this rank's failure as it is.
  if (!distributed()) return !stats.failure.empty();
  ScopedStage tc(&timers_, "newton.check.comm");
  constexpr std::int64_t kNone = std::numeric_limits<std::int64_t>::max();
  std::vector<std::int64_t> g{lowest};
  if (lowest < 0) {
    g[0] = stats.failure.empty() ? kNone : stats.grain;
    comm_->min(g);
  }
  if (g[0] == kNone) return false;
  const int root = owner_[static_cast<std::size_t>(g[0])];
  parallel::Buffer b;
  if (comm_->rank() == root) {
    b.put(stats.point);
    b.put(static_cast<std::int32_t>(stats.retryable));
    b.bytes().insert(b.bytes().end(), stats.failure.begin(), stats.failure.end());
  }
  comm_->broadcast(b.bytes(), root);
  stats.grain = g[0];
  stats.point = take<std::int64_t>(b);
  stats.retryable = take<std::int32_t>(b) != 0;
  const std::size_t head = sizeof(std::int64_t) + sizeof(std::int32_t);
  stats.failure.assign(b.bytes().begin() + static_cast<std::ptrdiff_t>(head), b.bytes().end());
  return true;
}

template <int Dim>
void ImplicitSolver<Dim>::exchange_entries() {
  if (!distributed()) return;
  ScopedStage t(&timers_, "comm.entries");
  // 1. Node boxes of every grain (each rank sends its own: a few integers per grain).
  const int me = comm_->rank(), np = comm_->size();
  const std::size_t ng = grains_.size();
  const ContactSettings<Dim>& cs = settings_.contact;
  const double h = grid_.cell_size();
  parallel::Buffer mine;
  for (std::size_t g : owned_) {
    const GrainWork& w = *work_[g];
    mine.put(static_cast<std::int32_t>(g));
    std::array<std::int64_t, 2 * Dim> box;
    for (int d = 0; d < Dim; ++d) {
      box[d] = grains_[g].size() > 0 ? w.box_lo[d] : 0;
      box[Dim + d] = grains_[g].size() > 0 ? w.box_lo[d] + w.box_n[d] - 1 : -1;
    }
    mine.put(box);
  }
  const auto all = comm_->allgather(mine.bytes());
  boxes_.assign(ng, {});
  for (int r = 0; r < np; ++r) {
    parallel::Buffer b;
    b.bytes() = all[r];
    while (!b.done()) {
      const auto g = take<std::int32_t>(b);
      boxes_[g] = take<std::array<std::int64_t, 2 * Dim>>(b);
    }
  }
  const auto overlap = [&](std::size_t g1, std::size_t g2) {
    for (int d = 0; d < Dim; ++d)
      if (boxes_[g1][d] > boxes_[g2][Dim + d] || boxes_[g2][d] > boxes_[g1][Dim + d]) return false;
    return true;
  };
  const auto inside = [&](std::size_t g, const IVec<Dim>& c) {
    for (int d = 0; d < Dim; ++d)
      if (c[d] < boxes_[g][d] || c[d] > boxes_[g][Dim + d]) return false;
    return true;
  };
  // 2. Neighbours (symmetric): ranks owning a grain whose box meets one of mine (partition); the
  // master and every other rank (master).
  const bool master = scheme_ == parallel::Scheme::kMaster;
  std::vector<std::vector<std::size_t>> near(ng);  // owned grain -> grains whose boxes meet it
  std::vector<char> is_nb(static_cast<std::size_t>(np), 0);
  for (std::size_t g : owned_)
    for (std::size_t g2 = 0; g2 < ng; ++g2) {
      if (g2 == g || !overlap(g, g2)) continue;
      if (master || owner_[g2] != me) near[g].push_back(g2);
      if (!master && owner_[g2] != me) is_nb[owner_[g2]] = 1;
    }
  if (master)
    for (int r = 0; r < np; ++r) is_nb[r] = me == 0 ? r != 0 : r == 0;
  neighbours_.clear();
  for (int r = 0; r < np; ++r)
    if (is_nb[r]) neighbours_.push_back(r);
  // 3. Each owned grain's contact-capable nodes (mass above the threshold) that another rank may
  // need: inside the box of a grain owned there (partition); inside any other grain's box or
  // within wall range (master, to rank 0). Sent with the points touching them (x, F).
  std::map<int, parallel::Buffer> out;
  for (int r : neighbours_) out[r];
  std::vector<std::int32_t> sel, pts;
  std::vector<char> dest(static_cast<std::size_t>(np));
  // Counted work (Comm::count_work): grain pairs tested above; node-in-box and wall tests, values
  // packed.
  comm_->count_work(parallel::cost::kPairTest * static_cast<double>(owned_.size() * ng));
  double tests = 0, items = 0;
  for (std::size_t g : owned_) {
    const GrainWork& w = *work_[g];
    if (master && me == 0) break;
    for (int r : neighbours_) {
      sel.clear();
      for (std::size_t a = 0; a < w.m.size(); ++a) {
        if (w.m[a] < w.contact_mass) continue;
        const IVec<Dim> c = w.node_box[a] + w.box_lo;
        bool send = false;
        for (std::size_t g2 : near[g]) {
          tests += 1;
          if ((master || owner_[g2] == r) && inside(g2, c)) {
            send = true;
            break;
          }
        }
        if (!send && master) {
          const Vec<Dim> xn = grid_.node_position(c);
          tests += static_cast<double>(cs.walls.size());
          for (const auto& wall : cs.walls)
            if (wall.distance(xn, time_) <= cs.wall_range * h) send = true;
        }
        if (send) sel.push_back(static_cast<std::int32_t>(a));
      }
      if (sel.empty()) continue;
      parallel::Buffer& b = out[r];
      b.put(static_cast<std::int32_t>(g));
      b.put(w.contact_mass);
      b.put(static_cast<std::int32_t>(sel.size()));
      pts.clear();
      for (std::int32_t a : sel) {
        b.put(w.node_global[a]);
        b.put(w.m[a]);
        b.put(w.grad_m[a]);
        b.put(static_cast<std::int32_t>(w.node_pts_start[a + 1] - w.node_pts_start[a]));
        for (std::int32_t k = w.node_pts_start[a]; k < w.node_pts_start[a + 1]; ++k) {
          b.put(w.node_pts[k]);
          pts.push_back(w.node_pts[k]);
        }
      }
      std::sort(pts.begin(), pts.end());
      pts.erase(std::unique(pts.begin(), pts.end()), pts.end());
      b.put(static_cast<std::int32_t>(pts.size()));
      for (std::int32_t i : pts) {
        const std::int64_t p = grains_[g].begin + i;
        b.put(i);
        b.put(points_.x[p]);
        b.put(points_.F[p]);
      }
      items += static_cast<double>(sel.size() + 2 * pts.size());
    }
  }
  comm_->count_work(parallel::cost::kBoxTest * tests + parallel::cost::kExchangeItem * items);
  auto in = comm_->exchange(out, neighbours_);
  // 4. Ghost grains: their sent nodes as a field of this rank (mass, mass gradient, points).
  for (auto& [r, b] : in) {
    while (!b.done()) {
      const auto g = static_cast<std::size_t>(take<std::int32_t>(b));
      GrainWork& w = *work_[g];
      role_[g] = 2;
      w.contact_mass = take<double>(b);
      const auto k = static_cast<std::size_t>(take<std::int32_t>(b));
      w.m.resize(k);
      w.grad_m.resize(k);
      w.node_global.resize(k);
      w.node_pts_start.assign(k + 1, 0);
      w.node_pts.clear();
      for (std::size_t a = 0; a < k; ++a) {
        w.node_global[a] = take<std::int64_t>(b);
        w.m[a] = take<double>(b);
        w.grad_m[a] = take<Vec<Dim>>(b);
        const auto npts = take<std::int32_t>(b);
        for (std::int32_t j = 0; j < npts; ++j) w.node_pts.push_back(take<std::int32_t>(b));
        w.node_pts_start[a + 1] = static_cast<std::int32_t>(w.node_pts.size());
      }
      const auto npts = take<std::int32_t>(b);
      for (std::int32_t j = 0; j < npts; ++j) {
        const std::int64_t p = grains_[g].begin + take<std::int32_t>(b);
        points_.x[p] = take<Vec<Dim>>(b);
        points_.F[p] = take<Mat<Dim>>(b);
      }
      w.v.assign(k, Vec<Dim>::Zero());
      w.P.assign(k, Vec<Dim>::Zero());
      w.mask.assign(k, 0);
      comm_->count_work(parallel::cost::kExchangeItem *
                        static_cast<double>(k + w.node_pts.size() + npts));
    }
  }
  local_.clear();
  for (std::size_t g = 0; g < ng; ++g)
    if (role_[g]) local_.push_back(g);
}

template <int Dim>
void ImplicitSolver<Dim>::exchange_requests() {
  // The slots of ghost grains in this rank's contacts: ask their owners for their velocities
  // every iteration, and hand them the warm-start impulse (owners then serve those slots).
  if (!distributed()) {
    have_contacts_ = !problem_.contacts.empty();
    return;
  }
  ScopedStage tc(&timers_, "contact.detect.comm");
  std::vector<std::int64_t> count{static_cast<std::int64_t>(problem_.contacts.size())};
  comm_->sum(count);
  have_contacts_ = count[0] > 0;
  links_.clear();
  std::map<int, parallel::Buffer> out;
  for (int r : neighbours_) {
    links_[r];
    out[r];
  }
  comm_->count_work(parallel::cost::kExchangeItem * static_cast<double>(slot_ref_.size()));
  for (std::size_t s = 0; s < slot_ref_.size(); ++s) {
    const auto [g, a] = slot_ref_[s];
    if (role_[g] != 2) continue;
    const int r = owner_[g];
    links_.at(r).ask.push_back(static_cast<std::int32_t>(s));
    parallel::Buffer& b = out.at(r);
    b.put(g);
    b.put(work_[g]->node_global[a]);
    b.put(work_[g]->P[a]);
  }
  auto in = comm_->exchange(out, neighbours_);
  for (auto& [r, b] : in) {
    Link& link = links_.at(r);
    while (!b.done()) {
      const auto g = take<std::int32_t>(b);
      const auto node = take<std::int64_t>(b);
      const Vec<Dim> P = take<Vec<Dim>>(b);
      GrainWork& w = *work_[g];
      const IVec<Dim> c = grid_.node_coords(node) - w.box_lo;
      std::int64_t idx = 0, stride = 1;
      for (int d = 0; d < Dim; ++d) {
        idx += c[d] * stride;
        stride *= w.box_n[d];
      }
      const std::int32_t a = w.box_to_active[static_cast<std::size_t>(idx)];
      w.P[a] = P;
      link.serve.emplace_back(g, a);
    }
  }
  comm_->count_work(parallel::cost::kExchangeItem * static_cast<double>(link_sizes().first));
}

template <int Dim>
std::pair<std::size_t, std::size_t> ImplicitSolver<Dim>::link_sizes() const {
  std::size_t serve = 0, ask = 0;
  for (const auto& [r, link] : links_) {
    serve += link.serve.size();
    ask += link.ask.size();
  }
  return {serve, ask};
}

template <int Dim>
double ImplicitSolver<Dim>::update_contacts_distributed(StepStats& stats) {
  // Counted work (Comm::count_work) of the bookkeeping around the solve: slots served to and
  // asked from other ranks, this rank's slots, one pass over its contacts after the solve.
  const auto [n_serve, n_ask] = link_sizes();
  const auto n_slots = static_cast<double>(problem_.slots.size());
  // 1. Velocities of the ghost slots from their owners (boundary data, neighbours only).
  {
    ScopedStage tc(&timers_, "contact.solve.comm");
    std::map<int, parallel::Buffer> out;
    for (const auto& [r, link] : links_) {
      parallel::Buffer& b = out[r];
      for (const auto& [g, a] : link.serve) b.put(work_[g]->v[a]);
    }
    comm_->count_work(parallel::cost::kExchangeItem * static_cast<double>(n_serve));
    auto in = comm_->exchange(out, neighbours_);
    for (const auto& [r, link] : links_) {
      parallel::Buffer& b = in.at(r);
      for (std::int32_t s : link.ask) {
        const auto [g, a] = slot_ref_[s];
        work_[g]->v[a] = take<Vec<Dim>>(b);
      }
    }
  }
  // 2. Free velocities (lumped operator) of this rank's slots, as in update_contacts.
  for (std::size_t s = 0; s < slot_ref_.size(); ++s) {
    const GrainWork& w = *work_[slot_ref_[s].first];
    const std::int32_t a = slot_ref_[s].second;
    auto& slot = problem_.slots[s];
    slot.mass = w.m[a];
    slot.v_free = w.v[a] - w.P[a] / w.m[a];
  }
  std::vector<Vec<Dim>> old(problem_.contacts.size());
  for (std::size_t c = 0; c < old.size(); ++c) old[c] = problem_.contacts[c].impulse;
  comm_->count_work(parallel::cost::kExchangeItem * (static_cast<double>(n_ask) + n_slots));
  // 3. Gauss-Seidel: each rank on its nodes' contacts (no slot is shared between ranks), the
  // error summed over ranks before every test (partition); all contacts on rank 0 (master).
  contact::GsResult r;
  if (scheme_ == parallel::Scheme::kPartition) {
    // Counted work before each error test: one pass over this rank's contacts for the first
    // test, two (the sweep and its error) for the others.
    double passes = 1;
    const contact::ErrorReduce reduce = [&](double& num, double& den) {
      comm_->count_work(parallel::cost::kContactPass * passes *
                        static_cast<double>(problem_.contacts.size()));
      passes = 2;
      ScopedStage tc(&timers_, "contact.solve.comm");
      std::vector<double> v{num, den};
      comm_->sum(v);
      num = v[0];
      den = v[1];
    };
    ScopedStage t(&timers_, "contact.gs");
    r = contact::solve_gauss_seidel(problem_, gs_settings(), reduce);
  } else {
    r.converged = true;  // ranks other than 0 hold no contact
    if (comm_->rank() == 0) {
      ScopedStage t(&timers_, "contact.gs");
      r = contact::solve_gauss_seidel(problem_, gs_settings());
      comm_->count_work(parallel::cost::kContactPass * (1.0 + 2.0 * r.sweeps) *
                        static_cast<double>(problem_.contacts.size()));
    }
    ScopedStage tc(&timers_, "contact.solve.comm");
    std::vector<double> v{static_cast<double>(r.sweeps), r.error, r.converged ? 0.0 : 1.0};
    comm_->max(v);
    r.sweeps = static_cast<int>(v[0]);
    r.error = v[1];
    r.converged = v[2] == 0.0;
  }
  gs_converged_ = r.converged;
  auto [num, den] = detail::impulse_change(problem_, old, r, stats);
  const std::vector<Vec<Dim>> slot_p = contact::net_impulses(problem_);
  // 4. New impulses into the grains: own slots here, ghost slots sent back to their owners.
  std::vector<double> dv2(work_.size(), -1.0);
  const auto apply = [&](std::int32_t g, std::int32_t a, const Vec<Dim>& P) {
    apply_lumped_impulse(g, a, P, dv2);
  };
  for (std::size_t s = 0; s < slot_ref_.size(); ++s)
    if (role_[slot_ref_[s].first] == 1) apply(slot_ref_[s].first, slot_ref_[s].second, slot_p[s]);
  {
    ScopedStage tc(&timers_, "contact.solve.comm");
    std::map<int, parallel::Buffer> out;
    for (const auto& [rk, link] : links_) {
      parallel::Buffer& b = out[rk];
      for (std::int32_t s : link.ask) {
        b.put(slot_p[s]);
        work_[slot_ref_[s].first]->P[slot_ref_[s].second] = slot_p[s];
      }
    }
    comm_->count_work(parallel::cost::kExchangeItem *
                      (static_cast<double>(old.size() + n_ask) + n_slots));
    auto in = comm_->exchange(out, neighbours_);
    for (const auto& [rk, link] : links_) {
      parallel::Buffer& b = in.at(rk);
      for (const auto& [g, a] : link.serve) apply(g, a, take<Vec<Dim>>(b));
    }
    comm_->count_work(parallel::cost::kExchangeItem * static_cast<double>(n_serve));
    std::vector<double> v{num, den};
    comm_->sum(v);
    num = v[0];
    den = v[1];
  }
  for (std::size_t g : owned_)
    if (dv2[g] >= 0.0) work_[g]->impulses_changed(dv2[g]);
  return detail::relative_change(num, den, gs_converged_);
}

// The members defined here (the class is instantiated in solver.cpp).
#define MPMCD_INSTANTIATE(D)                                                                 \
  template void ImplicitSolver<D>::set_distribution(const parallel::Comm*, std::vector<int>, \
                                                    parallel::Scheme);                       \
  template std::vector<double> ImplicitSolver<D>::take_grain_work();                         \
  template double& ImplicitSolver<D>::phase_work(std::size_t, int);                          \
  template bool ImplicitSolver<D>::sync_failure(StepStats&, std::int64_t);                   \
  template void ImplicitSolver<D>::exchange_entries();                                       \
  template void ImplicitSolver<D>::exchange_requests();                                      \
  template std::pair<std::size_t, std::size_t> ImplicitSolver<D>::link_sizes() const;        \
  template double ImplicitSolver<D>::update_contacts_distributed(StepStats&);
MPMCD_INSTANTIATE(2)
MPMCD_INSTANTIATE(3)
#undef MPMCD_INSTANTIATE

}  // namespace mpmcd::mpm
