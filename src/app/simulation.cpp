#include "mpmcd/app/simulation.hpp"

#include <fmt/format.h>
#include <omp.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstring>
#include <filesystem>

#include "mpmcd/app/compaction_observer.hpp"
#include "mpmcd/app/model_builder.hpp"
#include "mpmcd/app/outputs.hpp"
#include "mpmcd/app/progress.hpp"
#include "mpmcd/app/run_folder.hpp"
#include "mpmcd/app/speed_check.hpp"
#include "mpmcd/app/step_controller.hpp"
#include "mpmcd/core/errors.hpp"
#include "mpmcd/core/log.hpp"
#include "mpmcd/io/load_config.hpp"
#include "mpmcd/parallel/distribute.hpp"
#include "mpmcd/version.hpp"

namespace mpmcd::app {

namespace fs = std::filesystem;

namespace {

// SIGINT / SIGTERM: the handler only records the signal; the loop finishes its step, writes a
// checkpoint and returns. SA_RESETHAND: a second signal gets the default action (stops at once).
volatile std::sig_atomic_t g_signal = 0;

extern "C" void on_stop_signal(int sig) {
  g_signal = sig;
}

class SignalGuard {
 public:
  SignalGuard() {
    g_signal = 0;
    struct sigaction sa = {};
    sa.sa_handler = on_stop_signal;
    sigemptyset(&sa.sa_mask);
    sa.sa_flags = SA_RESETHAND;
    sigaction(SIGINT, &sa, &old_int_);
    sigaction(SIGTERM, &sa, &old_term_);
  }
  ~SignalGuard() {
    sigaction(SIGINT, &old_int_, nullptr);
    sigaction(SIGTERM, &old_term_, nullptr);
  }
  SignalGuard(const SignalGuard&) = delete;
  SignalGuard& operator=(const SignalGuard&) = delete;

 private:
  struct sigaction old_int_ = {}, old_term_ = {};
};

const char* signal_name(int sig) {
  return sig == SIGINT ? "SIGINT" : sig == SIGTERM ? "SIGTERM" : "a signal";
}

// The model of a restart: grid and materials from the input, points and grains from the
// checkpoint (no packing is regenerated). Throws InputError if they do not fit together.
mpm::Model<2> restore_model(const io::Config& cfg, const checkpoint::State& s,
                            const std::string& path) {
  const auto refuse = [&](const std::string& what) {
    return InputError(path, 0, "", "checkpoint does not fit its input: " + what);
  };
  if (s.dim != 2) throw refuse(fmt::format("dimension {}", s.dim));
  mpm::Model<2> model = model_frame<2>(cfg);
  const std::size_t n = s.points();
  auto& p = model.points;
  p.x.resize(n);
  p.v.resize(n);
  p.L.resize(n);
  p.F.resize(n);
  p.sigma.resize(n);
  p.domain.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    p.x[i] = Vec<2>(s.x[2 * i], s.x[2 * i + 1]);
    p.v[i] = Vec<2>(s.v[2 * i], s.v[2 * i + 1]);
    p.L[i] << s.L[4 * i], s.L[4 * i + 1], s.L[4 * i + 2], s.L[4 * i + 3];
    p.F[i] << s.F[4 * i], s.F[4 * i + 1], s.F[4 * i + 2], s.F[4 * i + 3];
    p.sigma[i] << s.sigma[4 * i], s.sigma[4 * i + 1], s.sigma[4 * i + 2], s.sigma[4 * i + 3];
    p.domain[i] << s.domain[4 * i], s.domain[4 * i + 1], s.domain[4 * i + 2], s.domain[4 * i + 3];
  }
  p.sigma_zz = s.sigma_zz;
  p.mass = s.mass;
  p.volume0 = s.volume0;
  p.volume = s.volume;
  p.grain = s.grain;
  p.history = s.history;
  for (std::size_t g = 0; g < s.grain_begin.size(); ++g) {
    points::Grain gr;
    gr.begin = s.grain_begin[g];
    gr.end = s.grain_end[g];
    gr.material = s.grain_material[g];
    gr.half_width = s.grain_half_width[g];
    gr.history_offset = s.grain_history_offset[g];
    if (gr.material >= static_cast<int>(model.laws.size()))
      throw refuse(fmt::format("grain {} has material {}, the input has {} materials", g,
                               gr.material, model.laws.size()));
    const std::int64_t hs = model.laws[gr.material]->history_size();
    if (gr.history_offset + hs * gr.size() > static_cast<std::int64_t>(p.history.size()))
      throw refuse(fmt::format("grain {}: history shorter than its law needs", g));
    model.grains.push_back(gr);
  }
  for (std::size_t i = 0; i < n; ++i)
    if (!model.grid.inside(p.x[i], 0.0))
      throw refuse(fmt::format("point {} lies outside the grid", i));
  const auto ng = static_cast<std::int32_t>(model.grains.size());
  const auto nwall = static_cast<std::int32_t>(cfg.walls.size());
  for (std::size_t k = 0; k < s.warm_node.size(); ++k)
    if (s.warm_node[k] < -model.grid.node_count() || s.warm_node[k] >= model.grid.node_count() ||
        s.warm_b[k] < 0 || s.warm_b[k] >= ng || s.warm_a[k] >= ng || s.warm_a[k] < -nwall)
      throw refuse(
          fmt::format("contact warm-start entry {} names a node or body that does not "
                      "exist",
                      k));
  if (s.wall_point.size() != 2 * cfg.walls.size())
    throw refuse(fmt::format("{} walls in the checkpoint, {} in the input", s.wall_point.size() / 2,
                             cfg.walls.size()));
  return model;
}

}  // namespace

Restart load_restart(const std::string& path, const std::string& input) {
  Restart r;
  r.path = path;
  r.state = checkpoint::read(path);
  if (input.empty()) {
    r.config = io::parse_config(r.state.input_text, r.state.input_path);
  } else {
    r.config = io::load_config(input);
    if (checkpoint::fnv1a(r.config.source_text) != r.state.input_hash)
      throw InputError(input, 0, "",
                       fmt::format("this input is not the one checkpoint '{}' was written from "
                                   "({}); a restart continues the same run: give that input or "
                                   "none (the checkpoint holds it)",
                                   path, r.state.input_path));
  }
  return r;
}

RunSummary run_simulation(const io::Config& cfg, const RunOptions& opt,
                          const checkpoint::State* restart) {
  RunSummary summary;
  const int threads = opt.threads > 0 ? opt.threads : cfg.simulation.threads;
  if (threads > 0) omp_set_num_threads(threads);
  // May throw InputError: before any output.
  mpm::Model<2> model = restart ? restore_model(cfg, *restart, opt.restart) : build_model(cfg);
  auto settings = build_settings(cfg);
  if (!restart) check_walls_enclose(cfg, model, settings);
  bool any_moving = false;
  for (const auto& b : cfg.boundaries) any_moving = any_moving || b.moving;

  summary.output_dir = output_folder(cfg, opt, restart != nullptr);
  const CompactionObserver observer(cfg, model);
  // Processes (docs/parallel.md): every rank holds the model and computes its grains; rank 0
  // gathers the state at output and checkpoint times and writes every file.
  const auto& comm = parallel::Comm::world();
  const bool root = comm.rank() == 0;
  if (!root) log().set_level(spdlog::level::off);  // rank 0 reports
  // A restart written elsewhere than its checkpoint: the checkpoint's folder, its history.
  const std::string history_dir =
      prepare_output_folder(cfg, opt, summary.output_dir, restart != nullptr, comm);
  SignalGuard signals;
  mpm::ImplicitSolver<2> solver(model.grid, settings, model.points, model.grains, model.law_ptrs());
  solver.set_boundary_conditions(build_boundaries(cfg, model.grid, 0.0));
  const parallel::Scheme scheme =
      parallel::scheme_from_string(opt.scheme.empty() ? "partition" : opt.scheme);
  // A restart on the same ranks and scheme keeps the checkpoint's distribution and re-balancing
  // counts (bitwise continuation); otherwise the grains are dealt again from the restored state.
  const bool keep =
      restart && restart->ranks == comm.size() && restart->scheme == parallel::to_string(scheme);
  if (comm.size() > 1) {
    std::vector<int> owner =
        keep ? std::vector<int>(restart->grain_owner.begin(), restart->grain_owner.end())
             : parallel::deal_grains(model.points, model.grains, scheme, comm.size());
    solver.set_distribution(&comm, owner, scheme);
  }
  if (keep) {
    std::vector<double> work(restart->grain_work);
    for (std::size_t g = 0; g < restart->grain_owner.size(); ++g)
      if (restart->grain_owner[g] != comm.rank())
        std::fill_n(work.begin() + static_cast<std::ptrdiff_t>(g * parallel::kWorkPhases),
                    parallel::kWorkPhases, 0.0);
    solver.set_grain_work(std::move(work));
  }
  // Energy ledger (docs/accuracy.md): the work done by each wall on the grains, W_k += -F_k . v_k
  // dt with F_k the grains' force on wall k over the step, and by the body forces, against the
  // change of elastic plus kinetic energy since t = 0. What is lost on the way: contact
  // dissipates D_c += sum_k W_k(step) - W_c(step), W_c the work of all contact impulses on the
  // grains (StepStats::contact_work); the transfers D_t (StepStats::transfer_loss); the stress
  // work on the grid not stored as elastic energy, D_i = -sum W_int - (Psi - Psi_0) (plastic
  // dissipation; for elastic laws, time integration and quadrature). The remainder is the
  // Newton tolerance's (and prescribed grid velocities' work).
  std::vector<double> wall_work(cfg.walls.size(), 0.0);
  double energy0 = 0, kinetic0 = 0, contact_dissipation = 0, transfer_dissipation = 0;
  double stress_work = 0, body_work = 0;
  if (restart) {
    wall_work = restart->wall_work;
    energy0 = restart->energy0;
    kinetic0 = restart->kinetic0;
    contact_dissipation = restart->contact_dissipation;
    transfer_dissipation = restart->transfer_dissipation;
    stress_work = restart->stress_work;
    body_work = restart->body_work;
  } else {
    const auto d0 = mpm::diagnostics(model);  // every rank holds the initial points
    energy0 = d0.elastic + d0.kinetic;
    kinetic0 = d0.kinetic;
  }
  std::string ledger_header;
  for (const auto& w : cfg.walls) ledger_header += ",wall_" + w.name + "_work";
  if (!cfg.walls.empty())
    ledger_header +=
        ",body_work,energy_change,contact_dissipation,transfer_dissipation,internal_dissipation,"
        "energy_unaccounted";
  // The ledger's terms from the diagnostics d of the current points: {sum of the walls' work,
  // E - E0, internal dissipation D_i, remainder}.
  struct Ledger {
    double walls, change, internal, rest;
  };
  const auto ledger = [&](const mpm::Diagnostics<2>& d) {
    Ledger l{0, d.elastic + d.kinetic - energy0, 0, 0};
    for (const double w : wall_work) l.walls += w;
    l.internal = -stress_work - (d.elastic - (energy0 - kinetic0));
    l.rest =
        l.walls + body_work - contact_dissipation - transfer_dissipation - l.internal - l.change;
    return l;
  };
  std::unique_ptr<Outputs> out_ptr;  // after every input check: nothing written before
  if (root)
    out_ptr = std::make_unique<Outputs>(
        cfg, summary.output_dir, observer.csv_header() + ledger_header, restart, history_dir);
  // The ledger's CSV fields: work of each wall and of the body forces, E - E0, the contact,
  // transfer and internal dissipations, and the remainder.
  const auto ledger_fields = [&](const mpm::Diagnostics<2>& d) {
    std::string f;
    if (wall_work.empty()) return f;  // the ledger is written by runs with walls
    for (const double w : wall_work) f += fmt::format(",{:.12e}", w);
    const Ledger l = ledger(d);
    return f + fmt::format(",{:.12e},{:.12e},{:.12e},{:.12e},{:.12e},{:.12e}", body_work, l.change,
                           contact_dissipation, transfer_dissipation, l.internal, l.rest);
  };
  const bool stop_active = cfg.stop.phi > 0 || cfg.stop.strain > 0 || cfg.stop.stress > 0;
  const auto gather_state = [&](int to) {
    ScopedStage ts(&solver.timers(), "output");
    parallel::gather_points(comm, model.points, model.grains, solver.owner(), to);
  };

  log().info(
      "mpmcd {} ({}): {} grains, {} material points, grid {}x{} cells of {} m, {} rank(s) x {} "
      "threads",
      kVersion, kGitHash, model.grains.size(), model.points.size(), model.grid.cells()[0],
      model.grid.cells()[1], model.grid.cell_size(), comm.size(), omp_get_max_threads());
  const double dt_nominal = cfg.time.dt, t_end = cfg.time.end_time;
  double t = 0;
  StepController dt_control(cfg.time);  // the step: cut on failure, restored after good steps
  double next_vtu = 0, next_csv = 0;
  if (restart) {
    t = restart->time;
    dt_control.restore(restart->dt, restart->good_since_cut);
    next_vtu = restart->next_vtu;
    next_csv = restart->next_csv;
    summary.steps = restart->step;
    summary.failed_steps = restart->failed_steps;
    summary.newton_iterations = restart->newton_iterations;
    // Every rank gets every impulse; a rank looks up only the contacts it solves.
    std::vector<mpm::WarmImpulse<2>> warm(restart->warm_node.size());
    for (std::size_t k = 0; k < warm.size(); ++k)
      warm[k] = {restart->warm_node[k], restart->warm_a[k], restart->warm_b[k],
                 Vec<2>(restart->warm_impulse[2 * k], restart->warm_impulse[2 * k + 1])};
    solver.set_warm_start(std::move(warm));
    if (root) out_ptr->restore_contacts(solver);
    log().info("restarted from {} (written by mpmcd {} on {} rank(s)): step {}, t = {:.9g} s",
               opt.restart, restart->mpmcd_version, restart->ranks, summary.steps, t);
    // The order of the threads' floating-point sums changes with their count (docs/robustness.md).
    if (restart->threads != omp_get_max_threads())
      log().warn(
          "note: the checkpoint was written with {} thread(s) per rank, this run has {}: the run "
          "goes on, but bitwise equality with an uninterrupted run is promised only with the same "
          "thread count (-t {})",
          restart->threads, omp_get_max_threads(), restart->threads);
  }
  // Runs driven faster than the grains can follow (docs/robustness.md): walls at the start,
  // material points at output times (rank 0 then holds every point), each reported once.
  if (const auto w = fast_wall_warning(cfg, model)) log().warn("{}", *w);
  bool fast_points_reported = false;
  mpm::StepStats last;
  auto record = [&](bool force) {
    const double eps = 1e-9 * dt_nominal;
    const bool csv = force || t >= next_csv - eps, vtu = force || t >= next_vtu - eps;
    if (!csv && !vtu) return;
    if (comm.size() > 1) gather_state(0);
    if (root && !fast_points_reported)
      if (const auto w = fast_point_warning(cfg, model, t)) {
        log().warn("{}", *w);
        fast_points_reported = true;
      }
    ScopedStage ts(&solver.timers(), "output");
    const auto problem = parallel::gather_contacts(comm, solver.contact_problem(), 0);
    if (csv) {
      if (root) {
        const auto d = mpm::diagnostics(model);
        out_ptr->csv_row(summary.steps, t, dt_control.dt(), last, d,
                         observer.csv_fields(model, last, problem, t) + ledger_fields(d));
      }
      next_csv = t + cfg.output.csv_interval;
    }
    if (vtu) {
      if (root) out_ptr->vtu(model, solver, problem, t);
      next_vtu = t + cfg.output.vtu_interval;
    }
  };
  // Writes the checkpoint of the committed state (collective: rank 0 gathers every grain and
  // every rank's warm-start impulses and writes one file); returns its path on rank 0.
  std::int64_t last_checkpoint_step = restart ? restart->step : -1;
  auto write_checkpoint = [&](const std::string& reason) {
    ScopedStage ts(&solver.timers(), "checkpoint");
    if (comm.size() > 1) gather_state(0);
    // Warm-start impulses of every rank (each contact is solved by one rank).
    const auto warm = solver.gather_warm_start();
    std::vector<double> work = solver.grain_work();
    work.resize(model.grains.size() * parallel::kWorkPhases, 0.0);
    comm.sum(work);
    last_checkpoint_step = summary.steps;
    if (!root) return std::string();
    Outputs& out = *out_ptr;
    checkpoint::State s;
    s.dim = 2;
    s.input_text = cfg.source_text;
    s.input_path = cfg.source_path;
    s.reason = reason;
    s.step = summary.steps;
    s.time = t;
    s.dt = dt_control.dt();
    s.good_since_cut = dt_control.good_since_cut();
    s.failed_steps = summary.failed_steps;
    s.newton_iterations = summary.newton_iterations;
    s.next_vtu = next_vtu;
    s.next_csv = next_csv;
    s.csv_rows = out.csv_rows();
    s.vtu_times = out.vtu_times();
    const auto& p = model.points;
    const std::size_t n = p.size();
    s.x.resize(2 * n);
    s.v.resize(2 * n);
    s.L.resize(4 * n);
    s.F.resize(4 * n);
    s.sigma.resize(4 * n);
    s.domain.resize(4 * n);
    for (std::size_t i = 0; i < n; ++i)
      for (int a = 0; a < 2; ++a) {
        s.x[2 * i + a] = p.x[i][a];
        s.v[2 * i + a] = p.v[i][a];
        for (int b = 0; b < 2; ++b) {
          s.L[4 * i + 2 * a + b] = p.L[i](a, b);
          s.F[4 * i + 2 * a + b] = p.F[i](a, b);
          s.sigma[4 * i + 2 * a + b] = p.sigma[i](a, b);
          s.domain[4 * i + 2 * a + b] = p.domain[i](a, b);
        }
      }
    s.sigma_zz = p.sigma_zz;
    s.mass = p.mass;
    s.volume0 = p.volume0;
    s.volume = p.volume;
    s.grain = p.grain;
    s.history = p.history;
    for (const auto& g : model.grains) {
      s.grain_begin.push_back(g.begin);
      s.grain_end.push_back(g.end);
      s.grain_material.push_back(g.material);
      s.grain_half_width.push_back(g.half_width);
      s.grain_history_offset.push_back(g.history_offset);
    }
    for (const auto& w : warm) {
      s.warm_node.push_back(w.node);
      s.warm_a.push_back(w.a);
      s.warm_b.push_back(w.b);
      s.warm_impulse.push_back(w.impulse[0]);
      s.warm_impulse.push_back(w.impulse[1]);
    }
    for (const auto& w : settings.contact.walls) {
      const Vec<2> x = w.point + t * w.velocity;
      s.wall_point.push_back(x[0]);
      s.wall_point.push_back(x[1]);
    }
    s.ranks = comm.size();
    s.scheme = parallel::to_string(scheme);
    s.threads = omp_get_max_threads();
    s.grain_owner.assign(model.grains.size(), 0);
    if (comm.size() > 1)
      for (std::size_t g = 0; g < model.grains.size(); ++g) s.grain_owner[g] = solver.owner()[g];
    s.grain_work = work;
    s.wall_work = wall_work;
    s.energy0 = energy0;
    s.contact_dissipation = contact_dissipation;
    s.kinetic0 = kinetic0;
    s.transfer_dissipation = transfer_dissipation;
    s.stress_work = stress_work;
    s.body_work = body_work;
    const std::string path =
        (fs::path(out.dir()) / checkpoint::file_name(cfg.simulation.name, s.step)).string();
    checkpoint::write(s, path);
    checkpoint::prune(out.dir(), cfg.simulation.name, cfg.checkpoint.keep);
    summary.checkpoint = path;
    log().info("checkpoint ({}) at step {}, t = {:.9g} s: {}", reason, s.step, t, path);
    return path;
  };
  if (!restart) record(true);
  comm.record_syncs();  // the serial fraction, measured at every synchronisation
  const auto wall0 = std::chrono::steady_clock::now();
  auto last_progress = wall0, last_checkpoint_wall = wall0;
  const std::int64_t steps0 = summary.steps;
  // Progress toward the criterion that will end the run (docs/robustness.md, "Progress"): the
  // compaction state of the committed step (collective: the grains' area is summed over ranks).
  ProgressEstimator progress(t_end, cfg.stop, observer.initial_phi());
  const auto progress_sample = [&](const mpm::StepStats& st, double wall) {
    ProgressSample s{wall, t, std::nullopt, std::nullopt, std::nullopt};
    if (!observer.has_box()) return std::make_pair(s, std::optional<CompactionObserver::Now>());
    std::vector<double> areas = CompactionObserver::grain_areas(
        model, comm.size() > 1 ? &solver.owner() : nullptr, comm.rank());
    if (comm.size() > 1) comm.sum(areas);
    const auto now = observer.now(CompactionObserver::total_area(areas), st, t);
    s.phi = now->phi;
    s.strain = now->strain;
    if (!st.wall_force.empty()) s.stress = -now->bottom_stress;  // none before the first step
    return std::make_pair(s, now);
  };
  if (!opt.quiet) progress.add(progress_sample(last, 0.0).first);
  while (t < t_end - 1e-9 * dt_nominal) {
    const double dt_try = dt_control.next(t_end - t);
    solver.set_time(t);
    if (any_moving) solver.set_boundary_conditions(build_boundaries(cfg, model.grid, t + dt_try));
    mpm::StepStats st = solver.solve_step(dt_try);
    if (!st.converged) {  // the same verdict on every rank (the solver reduces it)
      ++summary.failed_steps;
      if (!st.retryable || !dt_control.cut(dt_try)) {
        if (comm.size() > 1) gather_state(0);
        const std::string saved = root ? out_ptr->last_good(model) : std::string();
        // Step summary.steps + 1 failed; the state of step summary.steps (time t) is the last
        // good one: committed steps always keep every point's support on the grid (the solver
        // checks the positions a step would commit), so its checkpoint can be resumed.
        log().error("step {} failed; last good state (step {}, t = {:.9g} s) written to {}",
                    summary.steps + 1, summary.steps, t, saved);
        std::string ckpt;
        try {
          ckpt = write_checkpoint("failure");
        } catch (const std::exception& e) {
          log().error("no checkpoint of the last good state: {}", e.what());
        }
        std::string reason = st.retryable ? fmt::format(
                                                "{}; dt cut down to dt_min = {:.3g} s "
                                                "did not help",
                                                st.failure, cfg.time.dt_min)
                                          : st.failure;
        reason += fmt::format(" in step {}, after the last good step {}", summary.steps + 1,
                              summary.steps);
        if (!ckpt.empty()) reason += fmt::format("; checkpoint of the last good step: {}", ckpt);
        throw NumericalError(reason, summary.steps + 1, t, st.grain, st.point);
      }
      log().warn("step {} at t = {:.9g} s failed ({}), retrying with dt = {:.4g} s",
                 summary.steps + 1, t, st.failure, dt_control.dt());
      continue;
    }
    solver.commit();
    last = st;
    double step_work = 0;
    for (std::size_t k = 0; k < wall_work.size() && k < st.wall_force.size(); ++k) {
      const double wk = -(st.wall_force[k][0] * settings.contact.walls[k].velocity[0] +
                          st.wall_force[k][1] * settings.contact.walls[k].velocity[1]) *
                        dt_try;
      wall_work[k] += wk;
      step_work += wk;
    }
    contact_dissipation += step_work - st.contact_work;
    transfer_dissipation += st.transfer_loss;
    stress_work += st.stress_work;
    body_work += st.body_work;
    if (comm.size() > 1 && scheme == parallel::Scheme::kPartition && opt.rebalance > 0 &&
        (summary.steps + 1) % 50 == 0) {  // docs/parallel.md: deterministic work weights
      ScopedStage ts(&solver.timers(), "rebalance");
      auto owner = solver.owner();
      bool moved = false;
      const double imbalance = parallel::rebalance(comm, model.points, model.grains, owner,
                                                   solver.take_grain_work(), opt.rebalance, moved);
      if (moved) {
        solver.set_distribution(&comm, owner, scheme);
        log().info("step {}: work imbalance {:.3f} > {}: grains dealt again", summary.steps + 1,
                   imbalance, opt.rebalance);
      }
    }
    t += dt_try;
    ++summary.steps;
    summary.newton_iterations += st.iterations;
    if (dt_control.succeeded())
      log().info("dt restored to {:.4g} s at t = {:.9g} s", dt_control.dt(), t);
    // [stop] criteria. Phi needs every grain's area: on several ranks each one's grains, summed
    // per grain over the ranks (exact: the other ranks add zeros), then over the grains in
    // order, as one process does.
    std::optional<std::string> criterion;
    if (stop_active && comm.size() > 1) {
      ScopedStage ts(&solver.timers(), "output");
      auto areas = CompactionObserver::grain_areas(model, &solver.owner(), comm.rank());
      comm.sum(areas);
      criterion = observer.stop_reason(CompactionObserver::total_area(areas), st, t);
    } else if (stop_active) {
      criterion = observer.stop_reason(model, st, t);
    }
    const bool at_end = criterion.has_value() || t >= t_end - 1e-9 * dt_nominal;
    record(at_end);
    if (criterion) {
      log().info("step {}, t = {:.9g} s: {}", summary.steps, t, *criterion);
      summary.stop_reason = *criterion;
      break;
    }
    const auto now = std::chrono::steady_clock::now();
    const bool stop = opt.stop_after > 0 && summary.steps - steps0 >= opt.stop_after;
    const bool due_steps =
        cfg.checkpoint.every_steps > 0 && summary.steps % cfg.checkpoint.every_steps == 0;
    // Signals and wall-clock deadlines reach the ranks at different times: they act when any
    // rank has seen them, on every rank in the same step.
    std::vector<double> flags{
        static_cast<double>(g_signal),
        cfg.checkpoint.every_minutes > 0 &&
                std::chrono::duration<double>(now - last_checkpoint_wall).count() >=
                    60.0 * cfg.checkpoint.every_minutes
            ? 1.0
            : 0.0,
        !opt.quiet && std::chrono::duration<double>(now - last_progress).count() >=
                          cfg.output.progress_interval
            ? 1.0
            : 0.0};
    if (comm.size() > 1) comm.max(flags);
    const int signal = static_cast<int>(flags[0]);
    const bool due_wall = flags[1] > 0, due_progress = flags[2] > 0;
    if ((signal != 0 || stop) && !at_end) {
      summary.signal = signal;
      summary.interrupted = true;
      write_checkpoint(signal != 0 ? "signal" : "stop_after");
      break;
    }
    if ((due_steps || due_wall) && !(at_end && cfg.checkpoint.at_end)) {
      write_checkpoint("periodic");
      last_checkpoint_wall = now;
    }
    if (due_progress) {  // the same step on every rank: the sample is collective
      last_progress = now;
      const double wall = std::chrono::duration<double>(now - wall0).count();
      const auto [sample, state] = progress_sample(st, wall);
      progress.add(sample);
      std::optional<double> z;
      if (settings.contact.enabled)
        z = observer.coordination(parallel::gather_contacts(comm, solver.contact_problem(), 0));
      const auto e = progress.estimate();
      std::string observed;
      if (state)
        observed =
            fmt::format("  Phi = {:.4f}  sigma_top = {:.4g} Pa", state->phi, state->top_stress);
      if (z) observed += fmt::format("  Z = {:.3f}", *z);
      const double rate = static_cast<double>(summary.steps - steps0) / std::max(wall, 1e-30);
      log().info(
          "step {:>7}  t = {:.6e} s ({:5.1f}% of {} = {:.6g}{}){}  newton {}  {:.1f} steps/s  "
          "ETA {}",
          summary.steps, t, 100 * e.fraction, e.criterion, e.target,
          e.criterion == "end_time"      ? " s"
          : e.criterion == "stop.stress" ? " Pa"
                                         : "",
          observed, st.iterations, rate, format_eta(e.eta));
    }
  }
  if (!summary.interrupted && cfg.checkpoint.at_end && last_checkpoint_step != summary.steps)
    write_checkpoint("end");
  summary.time = t;
  summary.wall_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  std::string timers;
  for (const auto& [name, secs] : solver.timers().totals())
    timers += fmt::format(" {} {:.2f} s", name, secs);
  // Per-stage timers over ranks with the serial shares (docs/parallel.md): <name>_timers.csv.
  std::vector<double> bytes{static_cast<double>(comm.bytes_sent())};
  comm.sum(bytes);
  const auto solo = comm.solo_report();
  const auto report = parallel::stage_report(comm, solver.timers().totals());
  const std::string csv = parallel::stage_report_csv(
      report, summary.wall_seconds, comm.size(), omp_get_max_threads(), summary.steps - steps0,
      bytes[0] / comm.size() / std::max<std::int64_t>(summary.steps - steps0, 1), solo);
  if (root) {
    io::write_file_atomic(
        (fs::path(summary.output_dir) / (cfg.simulation.name + "_timers.csv")).string(), csv);
    log().info("{} rank(s), scheme {}: timers in {}_timers.csv", comm.size(),
               parallel::to_string(scheme), cfg.simulation.name);
  }
  if (summary.interrupted) {
    log().warn("stopped ({}) at step {} (t = {:.9g} s)",
               summary.signal != 0 ? signal_name(summary.signal) : "--stop-after", summary.steps,
               t);
    return summary;
  }
  if (!wall_work.empty() && comm.size() > 1) gather_state(0);  // collective
  if (!wall_work.empty() && root) {  // the energy balance of the run (docs/accuracy.md)
    const Ledger l = ledger(mpm::diagnostics(model));
    const double in = l.walls + body_work;
    const auto pct = [&](double x) { return in != 0 ? 100 * x / std::abs(in) : 0.0; };
    log().info(
        "energy: walls and body forces did {:.6g} J/m of work, elastic + kinetic changed by "
        "{:.6g} J/m; dissipated by contact {:.3g} %, by the transfers {:.3g} %, in the bulk "
        "(stress work not stored) {:.3g} %; unaccounted {:.3g} % of the work",
        in, l.change, pct(contact_dissipation), pct(transfer_dissipation), pct(l.internal),
        pct(l.rest));
    // The ledger closes to the solver tolerances (about 1e-8 of the work): a remainder above
    // kLedgerTolerance of the energy scale is work from outside it (docs/accuracy.md).
    constexpr double kLedgerTolerance = 1e-3;
    const double scale = std::max({std::abs(in), std::abs(l.change), 1e-300});
    if (std::abs(l.rest) > kLedgerTolerance * scale)
      log().warn(
          "the energy ledger does not close: {:.6g} J/m ({:.3g} % of the work) is unaccounted; "
          "prescribed grid velocities ([[boundary]]) do work the ledger does not count, and loose "
          "Newton or Gauss-Seidel tolerances leave a remainder (docs/accuracy.md)",
          l.rest, 100 * std::abs(l.rest) / scale);
  }
  log().info("done: {} steps ({} retried) to t = {:.6g} s in {:.2f} s wall;{}", summary.steps,
             summary.failed_steps, t, summary.wall_seconds, timers);
  log().info("outputs in {}", summary.output_dir);
  return summary;
}

}  // namespace mpmcd::app
