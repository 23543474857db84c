#include "mpmcd/app/simulation.hpp"

#include <fmt/format.h>
#include <omp.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <filesystem>
#include <memory>
#include <optional>
#include <utility>

#include "mpmcd/app/compaction_observer.hpp"
#include "mpmcd/app/energy_ledger.hpp"
#include "mpmcd/app/model_builder.hpp"
#include "mpmcd/app/outputs.hpp"
#include "mpmcd/app/progress.hpp"
#include "mpmcd/app/run_folder.hpp"
#include "mpmcd/app/run_state.hpp"
#include "mpmcd/app/speed_check.hpp"
#include "mpmcd/app/step_controller.hpp"
#include "mpmcd/core/errors.hpp"
#include "mpmcd/core/log.hpp"
#include "mpmcd/io/vtu.hpp"
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
// The model of the run, after the thread count is set (a packing input runs its DEM on the
// threads): restored from the checkpoint `restart`, or built from the input.
mpm::Model<2> initial_model(const io::Config& cfg, const RunOptions& opt,
                            const checkpoint::State* restart) {
  const int threads = opt.threads > 0 ? opt.threads : cfg.simulation.threads;
  if (threads > 0) omp_set_num_threads(threads);
  return restart ? restore_model<2>(cfg, *restart, opt.restart) : build_model(cfg);
}

// The solver settings; a new run's walls must enclose its grains.
mpm::Settings<2> checked_settings(const io::Config& cfg, const mpm::Model<2>& model, bool restart) {
  auto settings = build_settings(cfg);
  if (!restart) check_walls_enclose(cfg, model, settings);
  return settings;
}

// Where a new run starts: t = 0 at the nominal step, the energy ledger at the model's energy.
RunState<2> start_state(const io::Config& cfg, const mpm::Model<2>& model) {
  RunState<2> s;
  s.dt = cfg.time.dt;
  s.energy = EnergyLedger<2>::start(cfg.walls.size(), mpm::diagnostics(model));
  return s;
}

// One run: its model and solver, its outputs and its counters. Processes (docs/parallel.md):
// every rank holds the model and computes its grains; rank 0 gathers the state at output and
// checkpoint times and writes every file.
class Run {
 public:
  // Builds or restores everything (may throw InputError: before any output is written), then
  // writes the outputs' headers.
  Run(const io::Config& cfg, const RunOptions& opt, const checkpoint::State* restart);
  // Steps to the end (or a [stop] criterion, a signal, --stop-after); returns the summary.
  RunSummary go();

 private:
  void distribute();
  void gather_state();
  void record(bool force);
  RunState<2> state_now();
  std::string write_checkpoint(const std::string& reason);
  [[noreturn]] void fail(const mpm::StepStats& st);
  void commit(const mpm::StepStats& st, double dt);
  void rebalance();
  std::optional<std::string> stop_criterion(const mpm::StepStats& st);
  bool between_steps(const mpm::StepStats& st, bool at_end);
  std::pair<ProgressSample, std::optional<CompactionObserver::Now>> progress_sample(
      const mpm::StepStats& st, double wall);
  void report_progress(const mpm::StepStats& st, double wall);
  RunSummary finish();

  const io::Config& cfg_;
  const RunOptions& opt_;
  const checkpoint::State* restart_;  // the checkpoint continued (nullptr: a new run)
  mpm::Model<2> model_;
  const mpm::Settings<2> settings_;
  const CompactionObserver observer_;
  RunState<2> start_;  // where this invocation starts (t = 0, or the checkpoint's state)
  const parallel::Comm& comm_;
  const bool root_;
  const parallel::Scheme scheme_;
  const bool any_moving_, stop_active_;
  RunSummary summary_;
  std::optional<SignalGuard> signals_;
  std::unique_ptr<mpm::ImplicitSolver<2>> solver_;
  EnergyLedger<2> ledger_;
  std::unique_ptr<Outputs> out_;  // rank 0 only
  StepController dt_control_;
  ProgressEstimator progress_;
  double t_, next_vtu_, next_csv_;  // simulated time, of the next VTU and CSV output [s]
  const std::int64_t steps0_;       // steps committed before this invocation [-]
  std::int64_t last_checkpoint_step_;
  mpm::StepStats last_;  // the last converged step
  bool fast_points_reported_ = false;
  std::chrono::steady_clock::time_point wall0_, last_progress_, last_checkpoint_wall_;
};

Run::Run(const io::Config& cfg, const RunOptions& opt, const checkpoint::State* restart)
    : cfg_(cfg),
      opt_(opt),
      restart_(restart),
      model_(initial_model(cfg, opt, restart)),
      settings_(checked_settings(cfg, model_, restart != nullptr)),
      observer_(cfg, model_),
      start_(restart ? run_state_of<2>(*restart) : start_state(cfg, model_)),
      comm_(parallel::Comm::world()),
      root_(comm_.rank() == 0),
      scheme_(parallel::scheme_from_string(opt.scheme.empty() ? "partition" : opt.scheme)),
      any_moving_(std::any_of(cfg.boundaries.begin(), cfg.boundaries.end(),
                              [](const auto& b) { return b.moving; })),
      stop_active_(cfg.stop.phi > 0 || cfg.stop.strain > 0 || cfg.stop.stress > 0),
      ledger_(start_.energy),
      dt_control_(cfg.time),
      progress_(cfg.time.end_time, cfg.stop, observer_.initial_phi()),
      t_(start_.time),
      next_vtu_(start_.next_vtu),
      next_csv_(start_.next_csv),
      steps0_(start_.step),
      last_checkpoint_step_(restart ? start_.step : -1) {
  summary_.output_dir = output_folder(cfg, opt, restart != nullptr);
  if (!root_) log().set_level(spdlog::level::off);  // rank 0 reports
  // A restart written elsewhere than its checkpoint: the checkpoint's folder, its history.
  const std::string history_dir =
      prepare_output_folder(cfg, opt, summary_.output_dir, restart != nullptr, comm_);
  signals_.emplace();
  solver_ = std::make_unique<mpm::ImplicitSolver<2>>(model_.grid, settings_, model_.points,
                                                     model_.grains, model_.law_ptrs());
  solver_->set_boundary_conditions(build_boundaries(cfg, model_.grid, 0.0));
  distribute();
  if (root_)  // after every input check: nothing written before
    out_ = std::make_unique<Outputs>(cfg, summary_.output_dir,
                                     observer_.csv_header() + EnergyLedger<2>::csv_header(cfg),
                                     restart, history_dir);
  log().info(
      "mpmcd {} ({}): {} grains, {} material points, grid {}x{} cells of {} m, {} rank(s) x {} "
      "threads",
      kVersion, kGitHash, model_.grains.size(), model_.points.size(), model_.grid.cells()[0],
      model_.grid.cells()[1], model_.grid.cell_size(), comm_.size(), omp_get_max_threads());
  summary_.steps = start_.step;
  summary_.failed_steps = start_.failed_steps;
  summary_.newton_iterations = start_.newton_iterations;
  if (restart) {
    dt_control_.restore(start_.dt, start_.good_since_cut);
    // Every rank gets every impulse; a rank looks up only the contacts it solves.
    solver_->set_warm_start(std::move(start_.warm));
    if (root_) out_->restore_contacts(*solver_);
    log().info("restarted from {} (written by mpmcd {} on {} rank(s)): step {}, t = {:.9g} s",
               opt.restart, restart->mpmcd_version, restart->ranks, summary_.steps, t_);
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
  if (const auto w = fast_wall_warning(cfg, model_)) log().warn("{}", *w);
}

// Deals the grains to the ranks. A restart on the same ranks and scheme keeps the checkpoint's
// distribution and re-balancing counts (bitwise continuation); otherwise the grains are dealt
// again from the restored state.
void Run::distribute() {
  const bool keep =
      restart_ && start_.ranks == comm_.size() && start_.scheme == parallel::to_string(scheme_);
  if (comm_.size() > 1) {
    std::vector<int> owner =
        keep ? start_.grain_owner
             : parallel::deal_grains(model_.points, model_.grains, scheme_, comm_.size());
    solver_->set_distribution(&comm_, owner, scheme_);
  }
  if (keep) {
    std::vector<double> work(start_.grain_work);
    for (std::size_t g = 0; g < start_.grain_owner.size(); ++g)
      if (start_.grain_owner[g] != comm_.rank())
        std::fill_n(work.begin() + static_cast<std::ptrdiff_t>(g * parallel::kWorkPhases),
                    parallel::kWorkPhases, 0.0);
    solver_->set_grain_work(std::move(work));
  }
}

// Rank 0 gathers every grain's points (collective).
void Run::gather_state() {
  ScopedStage ts(&solver_->timers(), "output");
  parallel::gather_points(comm_, model_.points, model_.grains, solver_->owner(), 0);
}

// The CSV row and the VTU snapshot of the committed state, when due or `force`d (collective).
void Run::record(bool force) {
  const double eps = 1e-9 * cfg_.time.dt;
  const bool csv = force || t_ >= next_csv_ - eps, vtu = force || t_ >= next_vtu_ - eps;
  if (!csv && !vtu) return;
  if (comm_.size() > 1) gather_state();
  if (root_ && !fast_points_reported_)
    if (const auto w = fast_point_warning(cfg_, model_, t_)) {
      log().warn("{}", *w);
      fast_points_reported_ = true;
    }
  ScopedStage ts(&solver_->timers(), "output");
  const auto problem = parallel::gather_contacts(comm_, solver_->contact_problem(), 0);
  if (csv) {
    if (root_) {
      const auto d = mpm::diagnostics(model_);
      out_->csv_row(summary_.steps, t_, dt_control_.dt(), last_, d,
                    observer_.csv_fields(model_, last_, problem, t_) + ledger_.csv_fields(d));
    }
    next_csv_ = t_ + cfg_.output.csv_interval;
  }
  if (vtu) {
    if (root_) out_->vtu(model_, *solver_, problem, t_);
    next_vtu_ = t_ + cfg_.output.vtu_interval;
  }
}

// The run's state besides the model, as a checkpoint holds it (on rank 0; the warm start and the
// work counts are gathered by write_checkpoint).
RunState<2> Run::state_now() {
  RunState<2> s;
  s.step = summary_.steps;
  s.time = t_;
  s.dt = dt_control_.dt();
  s.good_since_cut = dt_control_.good_since_cut();
  s.failed_steps = summary_.failed_steps;
  s.newton_iterations = summary_.newton_iterations;
  s.next_vtu = next_vtu_;
  s.next_csv = next_csv_;
  s.csv_rows = out_->csv_rows();
  s.vtu_times = out_->vtu_times();
  for (const auto& w : settings_.contact.walls) s.wall_points.push_back(w.point + t_ * w.velocity);
  s.energy = ledger_.sums();
  s.ranks = comm_.size();
  s.scheme = parallel::to_string(scheme_);
  s.threads = omp_get_max_threads();
  s.grain_owner.assign(model_.grains.size(), 0);
  if (comm_.size() > 1)
    for (std::size_t g = 0; g < model_.grains.size(); ++g) s.grain_owner[g] = solver_->owner()[g];
  return s;
}

// Writes the checkpoint of the committed state (collective: rank 0 gathers every grain and
// every rank's warm-start impulses and writes one file); returns its path on rank 0.
std::string Run::write_checkpoint(const std::string& reason) {
  ScopedStage ts(&solver_->timers(), "checkpoint");
  if (comm_.size() > 1) gather_state();
  // Warm-start impulses of every rank (each contact is solved by one rank).
  auto warm = solver_->gather_warm_start();
  std::vector<double> work = solver_->grain_work();
  work.resize(model_.grains.size() * parallel::kWorkPhases, 0.0);
  comm_.sum(work);
  last_checkpoint_step_ = summary_.steps;
  if (!root_) return std::string();
  RunState<2> run = state_now();
  run.warm = std::move(warm);
  run.grain_work = std::move(work);
  const checkpoint::State s = to_checkpoint(cfg_, model_, run, reason);
  const std::string path =
      (fs::path(out_->dir()) / checkpoint::file_name(cfg_.simulation.name, s.step)).string();
  checkpoint::write(s, path);
  checkpoint::prune(out_->dir(), cfg_.simulation.name, cfg_.checkpoint.keep);
  summary_.checkpoint = path;
  log().info("checkpoint ({}) at step {}, t = {:.9g} s: {}", reason, s.step, t_, path);
  return path;
}

// The step after summary_.steps failed for good (not retryable, or dt at dt_min): writes the last
// good state and its checkpoint, and throws NumericalError.
void Run::fail(const mpm::StepStats& st) {
  const std::int64_t good = summary_.steps;
  if (comm_.size() > 1) gather_state();
  const std::string saved = root_ ? out_->last_good(model_) : std::string();
  // Step good + 1 failed; the state of step good (time t) is the last good one: committed steps
  // always keep every point's support on the grid (the solver checks the positions a step would
  // commit), so its checkpoint can be resumed.
  log().error("step {} failed; last good state (step {}, t = {:.9g} s) written to {}", good + 1,
              good, t_, saved);
  std::string ckpt;
  try {
    ckpt = write_checkpoint("failure");
  } catch (const std::exception& e) {
    log().error("no checkpoint of the last good state: {}", e.what());
  }
  std::string reason = st.retryable
                           ? fmt::format("{}; dt cut down to dt_min = {:.3g} s did not help",
                                         st.failure, dt_control_.dt_min())
                           : st.failure;
  reason += fmt::format(" in step {}, after the last good step {}", good + 1, good);
  if (!ckpt.empty()) reason += fmt::format("; checkpoint of the last good step: {}", ckpt);
  throw NumericalError(reason, good + 1, t_, st.grain, st.point);
}

// Commits the converged step of length dt [s]: points, energy ledger, re-balancing, counters.
void Run::commit(const mpm::StepStats& st, double dt) {
  solver_->commit();
  last_ = st;
  ledger_.add_step(st, settings_.contact.walls, dt);
  if (comm_.size() > 1 && scheme_ == parallel::Scheme::kPartition && opt_.rebalance > 0 &&
      (summary_.steps + 1) % 50 == 0)  // docs/parallel.md: deterministic work weights
    rebalance();
  t_ += dt;
  ++summary_.steps;
  summary_.newton_iterations += st.iterations;
  if (dt_control_.succeeded())
    log().info("dt restored to {:.4g} s at t = {:.9g} s", dt_control_.dt(), t_);
}

// Deals the grains again when the work imbalance exceeds --rebalance (collective).
void Run::rebalance() {
  ScopedStage ts(&solver_->timers(), "rebalance");
  auto owner = solver_->owner();
  bool moved = false;
  const double imbalance = parallel::rebalance(comm_, model_.points, model_.grains, owner,
                                               solver_->take_grain_work(), opt_.rebalance, moved);
  if (moved) {
    solver_->set_distribution(&comm_, owner, scheme_);
    log().info("step {}: work imbalance {:.3f} > {}: grains dealt again", summary_.steps + 1,
               imbalance, opt_.rebalance);
  }
}

// The [stop] criterion reached by the committed step, if any. Phi needs every grain's area: on
// several ranks each one's grains, summed per grain over the ranks (exact: the other ranks add
// zeros), then over the grains in order, as one process does.
std::optional<std::string> Run::stop_criterion(const mpm::StepStats& st) {
  if (!stop_active_) return std::nullopt;
  if (comm_.size() == 1) return observer_.stop_reason(model_, st, t_);
  ScopedStage ts(&solver_->timers(), "output");
  auto areas = CompactionObserver::grain_areas(model_, &solver_->owner(), comm_.rank());
  comm_.sum(areas);
  return observer_.stop_reason(CompactionObserver::total_area(areas), st, t_);
}

// After a committed step that did not end the run (`at_end`: it reached end_time): a signal or
// --stop-after writes a checkpoint and returns false (stop); periodic checkpoints; the progress
// line. Collective.
bool Run::between_steps(const mpm::StepStats& st, bool at_end) {
  const auto now = std::chrono::steady_clock::now();
  const bool stop = opt_.stop_after > 0 && summary_.steps - steps0_ >= opt_.stop_after;
  const bool due_steps =
      cfg_.checkpoint.every_steps > 0 && summary_.steps % cfg_.checkpoint.every_steps == 0;
  const auto since = [&](auto then) { return std::chrono::duration<double>(now - then).count(); };
  // Signals and wall-clock deadlines reach the ranks at different times: they act when any rank
  // has seen them, on every rank in the same step.
  std::vector<double> flags{
      static_cast<double>(g_signal),
      cfg_.checkpoint.every_minutes > 0 &&
              since(last_checkpoint_wall_) >= 60.0 * cfg_.checkpoint.every_minutes
          ? 1.0
          : 0.0,
      !opt_.quiet && since(last_progress_) >= cfg_.output.progress_interval ? 1.0 : 0.0};
  if (comm_.size() > 1) comm_.max(flags);
  const int signal = static_cast<int>(flags[0]);
  const bool due_wall = flags[1] > 0, due_progress = flags[2] > 0;
  if ((signal != 0 || stop) && !at_end) {
    summary_.signal = signal;
    summary_.interrupted = true;
    write_checkpoint(signal != 0 ? "signal" : "stop_after");
    return false;
  }
  if ((due_steps || due_wall) && !(at_end && cfg_.checkpoint.at_end)) {
    write_checkpoint("periodic");
    last_checkpoint_wall_ = now;
  }
  if (due_progress) {  // the same step on every rank: the sample is collective
    last_progress_ = now;
    report_progress(st, since(wall0_));
  }
  return true;
}

// Progress toward the criterion that will end the run (docs/robustness.md, "Progress"): the
// compaction state of the committed step (collective: the grains' area is summed over ranks).
std::pair<ProgressSample, std::optional<CompactionObserver::Now>> Run::progress_sample(
    const mpm::StepStats& st, double wall) {
  ProgressSample s{wall, t_, std::nullopt, std::nullopt, std::nullopt};
  if (!observer_.has_box()) return {s, std::nullopt};
  std::vector<double> areas = CompactionObserver::grain_areas(
      model_, comm_.size() > 1 ? &solver_->owner() : nullptr, comm_.rank());
  if (comm_.size() > 1) comm_.sum(areas);
  const auto now = observer_.now(CompactionObserver::total_area(areas), st, t_);
  s.phi = now->phi;
  s.strain = now->strain;
  if (!st.wall_force.empty()) s.stress = -now->bottom_stress;  // none before the first step
  return {s, now};
}

// The progress line after the committed step `st`, `wall` [s] after this invocation started.
void Run::report_progress(const mpm::StepStats& st, double wall) {
  const auto [sample, state] = progress_sample(st, wall);
  progress_.add(sample);
  std::optional<double> z;
  if (settings_.contact.enabled)
    z = observer_.coordination(parallel::gather_contacts(comm_, solver_->contact_problem(), 0));
  const auto e = progress_.estimate();
  std::string observed;
  if (state)
    observed = fmt::format("  Phi = {:.4f}  sigma_top = {:.4g} Pa", state->phi, state->top_stress);
  if (z) observed += fmt::format("  Z = {:.3f}", *z);
  const double rate = static_cast<double>(summary_.steps - steps0_) / std::max(wall, 1e-30);
  log().info(
      "step {:>7}  t = {:.6e} s ({:5.1f}% of {} = {:.6g}{}){}  newton {}  {:.1f} steps/s  ETA {}",
      summary_.steps, t_, 100 * e.fraction, e.criterion, e.target,
      e.criterion == "end_time"      ? " s"
      : e.criterion == "stop.stress" ? " Pa"
                                     : "",
      observed, st.iterations, rate, format_eta(e.eta));
}

RunSummary Run::go() {
  if (!restart_) record(true);
  comm_.record_syncs();  // the serial fraction, measured at every synchronisation
  wall0_ = last_progress_ = last_checkpoint_wall_ = std::chrono::steady_clock::now();
  if (!opt_.quiet) progress_.add(progress_sample(last_, 0.0).first);
  const double t_end = cfg_.time.end_time, eps = 1e-9 * cfg_.time.dt;
  while (t_ < t_end - eps) {
    const double dt = dt_control_.next(t_end - t_);
    solver_->set_time(t_);
    if (any_moving_) solver_->set_boundary_conditions(build_boundaries(cfg_, model_.grid, t_ + dt));
    const mpm::StepStats st = solver_->solve_step(dt);
    if (!st.converged) {  // the same verdict on every rank (the solver reduces it)
      ++summary_.failed_steps;
      if (!st.retryable || !dt_control_.cut(dt)) fail(st);
      log().warn("step {} at t = {:.9g} s failed ({}), retrying with dt = {:.4g} s",
                 summary_.steps + 1, t_, st.failure, dt_control_.dt());
      continue;
    }
    commit(st, dt);
    const std::optional<std::string> criterion = stop_criterion(st);
    const bool at_end = criterion.has_value() || t_ >= t_end - eps;
    record(at_end);
    if (criterion) {
      log().info("step {}, t = {:.9g} s: {}", summary_.steps, t_, *criterion);
      summary_.stop_reason = *criterion;
      break;
    }
    if (!between_steps(st, at_end)) break;
  }
  return finish();
}

// The end of the run: its checkpoint, the timers (<name>_timers.csv), the energy balance.
RunSummary Run::finish() {
  if (!summary_.interrupted && cfg_.checkpoint.at_end && last_checkpoint_step_ != summary_.steps)
    write_checkpoint("end");
  summary_.time = t_;
  summary_.wall_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0_).count();
  std::string timers;
  for (const auto& [name, secs] : solver_->timers().totals())
    timers += fmt::format(" {} {:.2f} s", name, secs);
  // Per-stage timers over ranks with the serial shares (docs/parallel.md): <name>_timers.csv.
  const std::int64_t steps = summary_.steps - steps0_;
  std::vector<double> bytes{static_cast<double>(comm_.bytes_sent())};
  comm_.sum(bytes);
  const auto solo = comm_.solo_report();
  const auto report = parallel::stage_report(comm_, solver_->timers().totals());
  const std::string csv = parallel::stage_report_csv(
      report, summary_.wall_seconds, comm_.size(), omp_get_max_threads(), steps,
      bytes[0] / comm_.size() / std::max<std::int64_t>(steps, 1), solo);
  if (root_) {
    io::write_file_atomic(
        (fs::path(summary_.output_dir) / (cfg_.simulation.name + "_timers.csv")).string(), csv);
    log().info("{} rank(s), scheme {}: timers in {}_timers.csv", comm_.size(),
               parallel::to_string(scheme_), cfg_.simulation.name);
  }
  if (summary_.interrupted) {
    log().warn("stopped ({}) at step {} (t = {:.9g} s)",
               summary_.signal != 0 ? signal_name(summary_.signal) : "--stop-after", summary_.steps,
               t_);
    return summary_;
  }
  if (ledger_.active()) {                  // the energy balance of the run (docs/accuracy.md)
    if (comm_.size() > 1) gather_state();  // collective
    if (root_) ledger_.report(mpm::diagnostics(model_));
  }
  log().info("done: {} steps ({} retried) to t = {:.6g} s in {:.2f} s wall;{}", summary_.steps,
             summary_.failed_steps, t_, summary_.wall_seconds, timers);
  log().info("outputs in {}", summary_.output_dir);
  return summary_;
}

}  // namespace

RunSummary run_simulation(const io::Config& cfg, const RunOptions& opt,
                          const checkpoint::State* restart) {
  return Run(cfg, opt, restart).go();
}

}  // namespace mpmcd::app
