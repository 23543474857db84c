// ImplicitSolver: construction, boundary conditions, the step (P2G, Newton iterations staggered
// with contact, the G2P check, the step's statistics) and its commit. The grain field's stages are
// free functions (include/mpmcd/mpm/grain_field.hpp: grain_field.cpp, grain_newton.cpp); the
// contact stages live in contact_detect.cpp and contact_coupling.cpp, the distributed step in
// solver_distributed.cpp (docs/architecture.md, "The mpm module's files").
#include "mpmcd/mpm/solver.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <memory>
#include <stdexcept>
#include <tuple>

#include "mpmcd/core/errors.hpp"
#include "solver_detail.hpp"

namespace mpmcd::mpm {

LinearSolverKind linear_solver_from_string(const std::string& name) {
  if (name == "ldlt") return LinearSolverKind::kLdlt;
  if (name == "lu") return LinearSolverKind::kLu;
  if (name == "cg") return LinearSolverKind::kCg;
  throw InputError("", 0, "solver.linear_solver",
                   "expected \"ldlt\", \"lu\" or \"cg\", got \"" + name + "\"");
}

template <int Dim>
ImplicitSolver<Dim>::ImplicitSolver(const grid::Grid<Dim>& grid, const Settings<Dim>& settings,
                                    points::PointSet<Dim>& points,
                                    const std::vector<points::Grain>& grains,
                                    std::vector<const materials::Law<Dim>*> laws)
    : grid_(grid),
      settings_(settings),
      points_(points),
      grains_(grains),
      laws_(std::move(laws)),
      prescribed_(grid_.node_count()) {}

template <int Dim>
ImplicitSolver<Dim>::~ImplicitSolver() = default;

template <int Dim>
void ImplicitSolver<Dim>::set_walls(std::vector<walls::Wall<Dim>> walls) {
  if (walls.size() != settings_.contact.walls.size())
    throw std::logic_error("ImplicitSolver::set_walls: another number of walls");
  settings_.contact.walls = std::move(walls);
}

template <int Dim>
void ImplicitSolver<Dim>::set_boundary_conditions(const std::vector<VelocityBC<Dim>>& bcs) {
  prescribed_.set(bcs);  // clears only the nodes set before (moving node sets change every step)
}

template <int Dim>
bool ImplicitSolver<Dim>::grain_factor(std::size_t g, double dt) {
  GrainWork& w = *work_[g];
  const points::Grain& gr = grains_[g];
  return prepare_factor(w, trial_, settings_, points_, gr, *laws_[gr.material], w.compliance(), dt);
}

template <int Dim>
StepStats ImplicitSolver<Dim>::solve_step(double dt) {
  StepStats stats;
  const std::size_t ng = grains_.size();
  dt_ = dt;
  step_ready_ = false;
  if (work_.size() != ng) {
    work_.clear();
    for (std::size_t g = 0; g < ng; ++g) work_.push_back(std::make_unique<GrainWork>());
  }
  // The grains this rank computes (all of them on one rank); ghosts are added by exchange_entries.
  if (owner_.size() != ng) owner_.assign(ng, 0);
  owned_.clear();
  role_.assign(ng, 0);
  for (std::size_t g = 0; g < ng; ++g)
    if (owner_[g] == comm_->rank()) {
      owned_.push_back(g);
      role_[g] = 1;
    }
  local_ = owned_;
  const std::size_t no = owned_.size();
  trial_.start(points_);
  // This rank's lowest failing grain into stats; true if there is one.
  auto local_failure = [&]() {
    for (std::size_t g : owned_)
      if (!work_[g]->failure.empty()) {
        stats.failure = work_[g]->failure;
        stats.grain = static_cast<std::int64_t>(g);
        stats.point = work_[g]->fail_point;
        stats.retryable = work_[g]->retryable;
        return true;
      }
    return false;
  };
  auto collect_failure = [&]() {
    local_failure();
    return sync_failure(stats);
  };
  {
    ScopedStage t(&timers_, "p2g");
    const ThreadedRegion threaded(&timers_, no > 1);
#pragma omp parallel for schedule(dynamic, 1) if (no > 1)
    for (std::size_t i = 0; i < no; ++i) {
      const std::size_t g = owned_[i];
      GrainWork& w = *work_[g];
      w.z_factor = -1;
      with_shape(settings_.shape, [&](auto tag) {
        p2g<decltype(tag)>(w, grid_, settings_, points_, grains_[g], prescribed_);
      });
    }
  }
  // Work counts (docs/parallel.md): per grain and phase for re-balancing, where P2G, detection
  // and G2P go with the first Newton iteration; per synchronisation for the counted serial
  // fraction (Comm::count_work).
  grain_work_.resize(ng * parallel::kWorkPhases, 0.0);
  double owned_points = 0;
  for (std::size_t g : owned_) {
    phase_work(g, 0) += parallel::cost::kSetup * static_cast<double>(grains_[g].size());
    owned_points += static_cast<double>(grains_[g].size());
  }
  comm_->count_work(parallel::cost::kP2g * owned_points);
  if (collect_failure()) return stats;
  if (settings_.contact.enabled) {
    exchange_entries();  // the ghost grains' contact nodes (none on one rank)
    ScopedStage t(&timers_, "contact.detect");
    detect_contacts(dt);
    prepare_face_normals();
    comm_->count_work(parallel::cost::kDetectItem * detect_items_);
    exchange_requests();  // the ghost slots' links, and whether any rank has contacts
  } else {
    problem_.contacts.clear();
    problem_.slots.clear();
    face_normals_.clear();
    have_contacts_ = false;
  }
  double impulse_change = 0, ref_scale = 0, vel_scale = 0;
  const double contact_increment_tolerance =
      std::max(settings_.increment_tolerance, settings_.contact.impulse_tolerance);
  // The increment a grain's |dv|_M is judged against, from its own velocity reference `vref`.
  const auto increment_bound = [&](const GrainWork& w, double vref) {
    return w.dv_from_contact ? contact_increment_tolerance * vel_scale
                             : settings_.increment_tolerance * vref;
  };
  // Runs `stage(g, w)` on the threads for each grain of this rank still iterating (neither
  // converged nor failed) and counts the work units it returns, per grain and phase of iteration
  // `it` and for this rank (Comm::count_work).
  const auto on_open_grains = [&](int it, auto&& stage) {
    double units = 0;
    const ThreadedRegion threaded(&timers_, no > 1);
#pragma omp parallel for schedule(dynamic, 1) if (no > 1) reduction(+ : units)
    for (std::size_t i = 0; i < no; ++i) {
      const std::size_t g = owned_[i];
      GrainWork& w = *work_[g];
      if (w.converged || !w.failure.empty()) continue;
      const double u = stage(g, w);
      phase_work(g, it) += u;
      units += u;
    }
    comm_->count_work(units);
  };
  for (int it = 0; it <= settings_.max_iterations; ++it) {
    {
      ScopedStage t(&timers_, "newton.assemble");
      on_open_grains(it, [&](std::size_t g, GrainWork& w) {
        const points::Grain& gr = grains_[g];
        with_shape(settings_.shape, [&](auto tag) {
          evaluate<decltype(tag)>(w, trial_, settings_, points_, gr, *laws_[gr.material], dt);
        });
        if (w.failure.empty()) w.iterations = it;
        return static_cast<double>(gr.size());
      });
    }
    // Face contacts' normals at this iterate's F^{n+1} (face_normals_at_end; none otherwise).
    if (have_contacts_ && !local_failure()) follow_face_normals();
    const bool failed_here = local_failure();
    // Convergence of each evaluated grain: |R| <= tol * reference and |dv|_M <= tol * velocity
    // scale, the references floored at 1e-3 of the largest grain's so that a grain at rest (whose
    // own scales vanish) is judged on the scale of the step, not on round-off. An increment that
    // is the response to a change of the contact impulses is judged like the impulse change it
    // comes from: relative to the whole step (the largest grain's velocity scale) and at
    // max(increment_tolerance, contact.impulse_tolerance). The contact solve ends within its own
    // tolerance of the step's impulses, so each solve may move a lightly loaded grain's impulses
    // by far more than 1e-8 of that grain's own scale, which the staggering cannot resolve
    // (docs/contact.md, "Convergence of the staggering").
    for (std::size_t g : owned_) {
      if (!work_[g]->evaluated) continue;
      ref_scale = std::max(ref_scale, work_[g]->res_ref);
      vel_scale = std::max(vel_scale, work_[g]->vel_ref);
    }
    {
      // One reduction for the scales (max is exact: the same scales as one process) and the
      // failures: the lowest failing grain over the ranks, as the largest of its negatives.
      constexpr double kNoGrain = 1e300;
      std::vector<double> sc{ref_scale, vel_scale,
                             failed_here ? -static_cast<double>(stats.grain) : -kNoGrain};
      over_ranks(sc, &parallel::Comm::max);
      ref_scale = sc[0];
      vel_scale = sc[1];
      if (sc[2] > -kNoGrain && sync_failure(stats, static_cast<std::int64_t>(-sc[2]))) return stats;
    }
    double worst = 0, worst_increment = 0;
    bool all = true;
    int residuals_open = 0, increments_open = 0;
    for (std::size_t g : owned_) {
      GrainWork& w = *work_[g];
      if (w.evaluated) {
        w.evaluated = false;
        const double ref = std::max(w.res_ref, 1e-3 * ref_scale);
        const double vref = std::max(w.vel_ref, 1e-3 * vel_scale);
        const bool res_ok = w.res_norm <= settings_.residual_tolerance * ref;
        const double bound = increment_bound(w, vref);
        const bool inc_ok = !w.solved_once || w.dv_norm <= bound;
        const double inc = inc_ok ? 0.0 : w.dv_norm / bound;  // of the bound, when above it
        w.converged = res_ok && inc_ok;
        residuals_open += res_ok ? 0 : 1;
        increments_open += inc_ok ? 0 : 1;
        worst_increment = std::max(worst_increment, inc);
        const double rel = ref > 0 ? w.res_norm / ref : 0.0;
        w.history.push_back(rel);
        worst = std::max(worst, rel);
      }
      all = all && w.converged;
    }
    {
      std::vector<double> r{worst, all ? 0.0 : 1.0};
      over_ranks(r, &parallel::Comm::max);
      worst = r[0];
      all = r[1] == 0.0;
    }
    stats.residual_history.push_back(worst);
    // Debugging (docs/contact.md): MPMCD_TRACE_NEWTON=1 prints each iteration's convergence state.
    static const bool trace = std::getenv("MPMCD_TRACE_NEWTON") != nullptr;
    if (trace)
      fmt::print(stderr,
                 "[newton] it {} worst relative residual {:.3e}, impulse change {:.3e}, contact "
                 "error {:.3e}; open on this rank: {} residuals, {} increments (worst {:.3e} "
                 "times its bound)\n",
                 it, worst, impulse_change, stats.gs_error, residuals_open, increments_open,
                 worst_increment);
    // Staggered with Newton: the step has converged when the grains have (with the current
    // impulses) and the impulses have stopped changing (method.md §4).
    const bool impulses_ok =
        !have_contacts_ || (it > 0 && impulse_change <= settings_.contact.impulse_tolerance);
    if (all && impulses_ok) {
      stats.converged = true;
      break;
    }
    if (it == settings_.max_iterations) break;
    {
      ScopedStage t(&timers_, "newton.solve");
      on_open_grains(it, [&](std::size_t g, GrainWork& w) {
        const points::Grain& gr = grains_[g];
        newton_solve(w, trial_, settings_, points_, gr, *laws_[gr.material], w.compliance(), dt,
                     reuse_factor(w, settings_));
        return parallel::cost::kCgWork * w.cg_work;
      });
    }
    if (collect_failure()) return stats;
    if (have_contacts_) {
      ScopedStage t(&timers_, "contact.solve");
      impulse_change = update_contacts(stats);
    }
  }
  for (std::size_t g : owned_) {
    stats.iterations = std::max(stats.iterations, work_[g]->iterations);
    stats.linear_solves += work_[g]->solves;
    stats.factorizations += work_[g]->factorizations;
    stats.dense_factorizations += work_[g]->dense_factorizations;
    stats.projected_factorizations += work_[g]->projections;
    stats.shrunk_domains += work_[g]->shrunk_domains;
  }
  if (!stats.converged) {
    for (std::size_t g : owned_)
      if (!work_[g]->converged) {
        stats.grain = static_cast<std::int64_t>(g);
        break;
      }
    std::vector<std::int64_t> gmin{stats.grain < 0 ? std::numeric_limits<std::int64_t>::max()
                                                   : stats.grain};
    over_ranks(gmin, &parallel::Comm::min);
    stats.grain = gmin[0] == std::numeric_limits<std::int64_t>::max() ? -1 : gmin[0];
    stats.failure =
        fmt::format("Newton did not converge in {} iterations (relative residual {:.3e}",
                    settings_.max_iterations,
                    stats.residual_history.empty() ? 0.0 : stats.residual_history.back());
    if (have_contacts_)
      stats.failure += fmt::format(", relative impulse change {:.3e}, Gauss-Seidel error {:.3e}",
                                   impulse_change, stats.gs_error);
    stats.failure += ")";
    return stats;
  }
  // The state this step commits must be one the next step can start from, and its checkpoint one a
  // restart accepts: a point whose new position would put its shape-function support past the
  // grid's edge fails this step (not retryable), so the last good state keeps every point inside.
  {
    ScopedStage t(&timers_, "g2p");
    const ThreadedRegion threaded(&timers_, no > 1);
#pragma omp parallel for schedule(dynamic, 1) if (no > 1)
    for (std::size_t i = 0; i < no; ++i) {
      const std::size_t g = owned_[i];
      with_shape(settings_.shape, [&](auto tag) {
        g2p_check<decltype(tag)>(*work_[g], trial_, grid_, settings_, points_, grains_[g]);
      });
    }
  }
  if (collect_failure()) {
    stats.converged = false;
    return stats;
  }
  // Energy ledger of this rank's grains (docs/accuracy.md). M (v - v^n) = dt f + P times
  // (v^n + v)/2 splits the grid's kinetic energy change into the work of the contact impulses,
  // P . (v^n + v)/2, of the internal and of the body forces; the transfers account for the rest
  // of the points' kinetic energy change.
  // Per grain, summed in grain order over the ranks (the same bits on any rank count).
  const double theta = settings_.theta;
  std::vector<double> ledger(4 * grains_.size(), 0.0);
  for (std::size_t g : owned_) {
    const GrainWork& w = *work_[g];
    double kin_grid = 0, work_c = 0, work_int = 0, work_ext = 0;
    for (std::size_t a = 0; a < w.m.size(); ++a) {
      const Vec<Dim> vm = 0.5 * (w.v_n[a] + w.v[a]);
      kin_grid += 0.5 * w.m[a] * w.v[a].squaredNorm();
      if (have_contacts_) work_c += w.P[a].dot(vm);
      work_int += ((1.0 - theta) * (w.f_n[a] - w.f_ext[a]) + theta * w.f_int[a]).dot(vm);
      work_ext += w.f_ext[a].dot(vm);
    }
    ledger[4 * g] = work_c;
    ledger[4 * g + 1] = (w.kin_points_n - w.kin_grid_n) + (kin_grid - w.kin_points);
    ledger[4 * g + 2] = dt * work_int;
    ledger[4 * g + 3] = dt * work_ext;
  }
  over_ranks(ledger, &parallel::Comm::sum);  // one rank owns each grain: the sum is exact
  if (settings_.shape == grid::ShapeKind::kCpdi)
    for (std::size_t g : owned_)
      for (std::int64_t p = grains_[g].begin; p < grains_[g].end; ++p)
        if (!grid::fits_cpdi_window<Dim>(trial_.F[p] * points_.domain[p], grid_.cell_size()))
          ++stats.oversized_domains;
  for (std::size_t g = 0; g < grains_.size(); ++g) {
    stats.contact_work += ledger[4 * g];
    stats.transfer_loss += ledger[4 * g + 1];
    stats.stress_work += ledger[4 * g + 2];
    stats.body_work += ledger[4 * g + 3];
  }
  // Contact summary: active contacts and the force of the grains on each wall (-P/dt).
  stats.contacts = static_cast<std::int64_t>(problem_.contacts.size());
  // Wall forces per grain and wall, summed in grain order over the ranks (each grain's wall
  // contacts are on its owner's rank, in the serial order): the same bits on any rank count.
  const std::size_t nw = settings_.contact.walls.size();
  std::vector<double> wall_f(grains_.size() * nw * Dim, 0.0);
  previous_.clear();
  for (const auto& c : problem_.contacts) {
    if (c.impulse.dot(c.normal) > 0) ++stats.active_contacts;
    if (c.a < 0) {
      const std::size_t g = static_cast<std::size_t>(problem_.slots[c.b].grain);
      const Vec<Dim> f = contact::impulse_force<Dim>(c.impulse, dt);  // force on the grain
      for (int d = 0; d < Dim; ++d) wall_f[(g * nw + c.wall) * Dim + d] -= f[d];
    }
    const std::int32_t a = c.a < 0 ? -1 - c.wall : problem_.slots[c.a].grain;
    previous_.push_back({slot_key_[c.b], a, problem_.slots[c.b].grain, c.impulse});
  }
  {  // sums over the ranks' contacts, added in rank order
    std::vector<std::int64_t> n{
        stats.contacts,          stats.active_contacts,          stats.linear_solves,
        stats.factorizations,    stats.projected_factorizations, stats.shrunk_domains,
        stats.oversized_domains, stats.dense_factorizations};
    over_ranks(n, &parallel::Comm::sum);
    std::vector<std::int64_t> it{-stats.iterations};
    over_ranks(it, &parallel::Comm::min);
    stats.contacts = n[0];
    stats.active_contacts = n[1];
    stats.linear_solves = n[2];
    stats.factorizations = n[3];
    stats.projected_factorizations = n[4];
    stats.shrunk_domains = n[5];
    stats.oversized_domains = n[6];
    stats.dense_factorizations = n[7];
    stats.iterations = static_cast<int>(-it[0]);
    over_ranks(wall_f, &parallel::Comm::sum);  // one rank holds each grain's wall contacts: exact
  }
  stats.wall_force.assign(nw, {0.0, 0.0, 0.0});
  for (std::size_t g = 0; g < grains_.size(); ++g)
    for (std::size_t k = 0; k < nw; ++k)
      for (int d = 0; d < Dim; ++d) stats.wall_force[k][d] += wall_f[(g * nw + k) * Dim + d];
  std::sort(previous_.begin(), previous_.end(),
            [](const WarmImpulse<Dim>& x, const WarmImpulse<Dim>& y) {
              return std::tie(x.node, x.a, x.b) < std::tie(y.node, y.a, y.b);
            });
  step_ready_ = true;
  return stats;
}

template <int Dim>
void ImplicitSolver<Dim>::commit() {
  if (!step_ready_) throw std::logic_error("ImplicitSolver::commit without a converged step");
  ScopedStage t(&timers_, "g2p");
  const std::size_t no = owned_.size();
  const ThreadedRegion threaded(&timers_, no > 1);
#pragma omp parallel for schedule(dynamic, 1) if (no > 1)
  for (std::size_t i = 0; i < no; ++i) {
    const std::size_t g = owned_[i];
    with_shape(settings_.shape, [&](auto tag) {
      g2p_commit<decltype(tag)>(*work_[g], trial_, settings_, points_, grains_[g]);
    });
  }
  points_.history.swap(trial_.history);
  step_ready_ = false;
}

template <int Dim>
double ImplicitSolver<Dim>::field_mass(std::size_t g) const {
  return mpm::field_mass<Dim>(*work_.at(g));
}

template <int Dim>
Vec<Dim> ImplicitSolver<Dim>::field_momentum(std::size_t g) const {
  return mpm::field_momentum<Dim>(*work_.at(g));
}

template class ImplicitSolver<2>;
template class ImplicitSolver<3>;

}  // namespace mpmcd::mpm
