#include "mpmcd/app/simulation.hpp"
#include "mpmcd/core/openmp_env.hpp"

#include <fmt/format.h>
#include <omp.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <cstring>
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
#include "mpmcd/points/split.hpp"
#include "mpmcd/version.hpp"
#include "run.hpp"

namespace mpmcd::app {

namespace fs = std::filesystem;

namespace {

// The last SIGINT or SIGTERM caught while a SignalGuard is alive (0: none); Run::between_steps
// acts on it after the step.
volatile std::sig_atomic_t g_signal = 0;

extern "C" void on_stop_signal(int sig) {
  g_signal = sig;
}

const char* signal_name(int sig) {
  return sig == SIGINT ? "SIGINT" : sig == SIGTERM ? "SIGTERM" : "a signal";
}

// The model of the run, after the thread count is set (a packing input runs its DEM on the
// threads): restored from the checkpoint `restart`, or built from the input.
template <int Dim>
mpm::Model<Dim> initial_model(const io::Config& cfg, const RunOptions& opt,
                              const checkpoint::State* restart) {
  const int threads = opt.threads > 0 ? opt.threads : cfg.simulation.threads;
  if (threads > 0) omp_set_num_threads(threads);
  return restart ? restore_model<Dim>(cfg, *restart, opt.restart) : build_model<Dim>(cfg);
}

// The solver settings; a new run's walls must enclose its grains.
template <int Dim>
mpm::Settings<Dim> checked_settings(const io::Config& cfg, const mpm::Model<Dim>& model,
                                    bool restart) {
  auto settings = build_settings(cfg, model);
  if (!restart) check_walls_enclose(cfg, model, settings);
  return settings;
}

// The energy ledger's sums where the run starts: the checkpoint's, or zero sums from the model's
// energy at t = 0 (every rank holds the initial points).
template <int Dim>
EnergySums start_energy(const io::Config& cfg, const mpm::Model<Dim>& model,
                        const checkpoint::State* restart) {
  return restart ? energy_sums_of(*restart)
                 : EnergyLedger<Dim>::start(cfg.walls.size(), mpm::diagnostics(model));
}

}  // namespace

namespace detail {

SignalGuard::SignalGuard() {
  g_signal = 0;
  struct sigaction sa = {};
  sa.sa_handler = on_stop_signal;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = SA_RESETHAND;
  sigaction(SIGINT, &sa, &old_int_);
  sigaction(SIGTERM, &sa, &old_term_);
}

SignalGuard::~SignalGuard() {
  sigaction(SIGINT, &old_int_, nullptr);
  sigaction(SIGTERM, &old_term_, nullptr);
}

template <int Dim>
Run<Dim>::Run(const io::Config& cfg, const RunOptions& opt, const checkpoint::State* restart)
    : cfg_(cfg),
      opt_(opt),
      restart_(restart),
      model_(initial_model<Dim>(cfg, opt, restart)),
      settings_(checked_settings(cfg, model_, restart != nullptr)),
      observer_(cfg, model_),
      comm_(parallel::Comm::world()),
      root_(comm_.rank() == 0),
      scheme_(parallel::scheme_from_string(opt.scheme.empty() ? "partition" : opt.scheme)),
      any_moving_(std::any_of(cfg.boundaries.begin(), cfg.boundaries.end(),
                              [](const auto& b) { return b.moving; })),
      stop_active_(cfg.stop.phi > 0 || cfg.stop.strain > 0 || cfg.stop.stress > 0),
      ledger_(start_energy(cfg, model_, restart)),
      loading_(cfg, settings_.contact.walls, model_),
      dt_control_(cfg.time),
      progress_(cfg.time.end_time, cfg.stop, observer_.initial_phi()),
      t_(restart ? restart->time : 0.0),
      next_vtu_(restart ? restart->next_vtu : 0.0),
      next_csv_(restart ? restart->next_csv : 0.0),
      steps0_(restart ? restart->step : 0),
      last_checkpoint_step_(restart ? restart->step : -1) {
  summary_.output_dir = output_folder(cfg, opt, restart != nullptr);
  if (!root_) log().set_level(spdlog::level::off);  // rank 0 reports
  // A restart written elsewhere than its checkpoint: the checkpoint's folder, its history.
  const std::string history_dir =
      prepare_output_folder(cfg, opt, summary_.output_dir, restart != nullptr, comm_);
  signals_.emplace();
  solver_ = std::make_unique<mpm::ImplicitSolver<Dim>>(model_.grid, settings_, model_.points,
                                                       model_.grains, model_.law_ptrs());
  solver_->set_boundary_conditions(build_boundaries(cfg, model_.grid, 0.0));
  distribute();
  if (root_)  // after every input check: nothing written before
    out_ = std::make_unique<Outputs>(
        cfg, summary_.output_dir,
        observer_.csv_header() + loading_.csv_header() + EnergyLedger<Dim>::csv_header(cfg),
        restart, history_dir);
  std::string cells = fmt::format("{}", model_.grid.cells()[0]);
  for (int a = 1; a < Dim; ++a) cells += fmt::format("x{}", model_.grid.cells()[a]);
  log().info(
      "mpmcd {} ({}): {}{} grains, {} material points, grid {} cells of {} m, {} rank(s) x {} "
      "threads ({})",
      kVersion, kGitHash, Dim == 3 ? "3D, " : "", model_.grains.size(), model_.points.size(), cells,
      model_.grid.cell_size(), comm_.size(), omp_get_max_threads(), openmp_wait_policy());
  if (loading_.active()) {
    if (restart) {
      try {
        loading_.restore(loading_state_of<Dim>(*restart));
      } catch (const std::invalid_argument& e) {
        throw InputError(opt.restart, 0, "",
                         fmt::format("checkpoint does not fit its input: {}", e.what()));
      }
      observer_.move_walls(loading_.walls(t_));
    } else {
      loading_.start(
          CompactionObserver<Dim>::total_area(CompactionObserver<Dim>::grain_areas(model_)));
    }
    log().info("{}", loading_.describe());
  }
  if (restart) {
    dt_control_.restore(restart->dt, restart->good_since_cut);
    summary_.steps = restart->step;
    summary_.failed_steps = restart->failed_steps;
    summary_.newton_iterations = restart->newton_iterations;
    // Every rank gets every impulse; a rank looks up only the contacts it solves.
    solver_->set_warm_start(warm_start_of<Dim>(*restart));
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
template <int Dim>
void Run<Dim>::distribute() {
  const bool keep = restart_ && restart_->ranks == comm_.size() &&
                    restart_->scheme == parallel::to_string(scheme_);
  if (comm_.size() > 1) {
    std::vector<int> owner =
        keep ? std::vector<int>(restart_->grain_owner.begin(), restart_->grain_owner.end())
             : parallel::deal_grains(model_.points, model_.grains, scheme_, comm_.size());
    solver_->set_distribution(&comm_, owner, scheme_);
  }
  if (keep) {
    std::vector<double> work(restart_->grain_work);
    for (std::size_t g = 0; g < restart_->grain_owner.size(); ++g)
      if (restart_->grain_owner[g] != comm_.rank())
        std::fill_n(work.begin() + static_cast<std::ptrdiff_t>(g * parallel::kWorkPhases),
                    parallel::kWorkPhases, 0.0);
    solver_->set_grain_work(std::move(work));
  }
}

// Commits the converged step of length dt [s]: points, energy ledger, re-balancing, counters.
template <int Dim>
void Run<Dim>::commit(const mpm::StepStats& st, double dt) {
  solver_->commit();
  if (st.oversized_domains > 0) split_points();
  last_ = st;
  if (st.shrunk_domains > 0) {
    ++summary_.shrunk_steps;
    summary_.shrunk_domains_max = std::max(summary_.shrunk_domains_max, st.shrunk_domains);
  }
  ledger_.add_step(st, solver_->settings().contact.walls, dt);  // the walls of this step
  if (comm_.size() > 1 && scheme_ == parallel::Scheme::kPartition && opt_.rebalance > 0 &&
      (summary_.steps + 1) % 50 == 0)  // docs/parallel.md: deterministic work weights
    rebalance();
  t_ += dt;
  ++summary_.steps;
  summary_.newton_iterations += st.iterations;
  if (dt_control_.succeeded(st.iterations, dt) && !dt_control_.adaptive())
    log().info("dt restored to {:.4g} s at t = {:.9g} s", dt_control_.dt(), t_);
}

// Splits the points whose CPDI domain outgrew its window ([grid] split_points), after a step
// that found some (StepStats::oversized_domains, the same count on every rank): the owners list
// them, every rank applies the same list to its copy of the points (collective on several
// ranks), and the warm-start keys follow the new point numbers. Children of a stretched split
// can still be too wide: up to 8 rounds.
template <int Dim>
void Run<Dim>::split_points() {
  if (settings_.shape != grid::ShapeKind::kCpdi || !cfg_.grid.split_points) return;
  std::vector<std::size_t> mine;
  for (std::size_t g = 0; g < model_.grains.size(); ++g)
    if (solver_->owner()[g] == comm_.rank()) mine.push_back(g);
  for (int round = 0; round < 8; ++round) {
    auto splits = points::find_splits(model_.points, model_.grains, mine, model_.grid.cell_size());
    if (comm_.size() > 1) {
      std::vector<char> bytes(splits.size() * sizeof(points::Split));
      std::memcpy(bytes.data(), splits.data(), bytes.size());
      splits.clear();
      for (const auto& b : comm_.allgather(bytes)) {
        const std::size_t k = splits.size();
        splits.resize(k + b.size() / sizeof(points::Split));
        std::memcpy(splits.data() + k, b.data(), b.size());
      }
      points::sort_splits(splits);
    }
    if (splits.empty()) return;
    solver_->renumber_points(points::apply_splits(model_.points, model_.grains, splits));
    if (root_ && summary_.split_points == 0)
      log().info("t = {:.9g} s: first {} point(s) split in two (CPDI domains wider than a cell)",
                 t_, splits.size());
    summary_.split_points += static_cast<std::int64_t>(splits.size());
  }
}

// Deals the grains again when the work imbalance exceeds --rebalance (collective).
template <int Dim>
void Run<Dim>::rebalance() {
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
template <int Dim>
std::optional<std::string> Run<Dim>::stop_criterion(const mpm::StepStats& st) {
  if (!stop_active_) return std::nullopt;
  if (comm_.size() == 1) return observer_.stop_reason(model_, st, t_);
  ScopedStage ts(&solver_->timers(), "output");
  auto areas = CompactionObserver<Dim>::grain_areas(model_, &solver_->owner(), comm_.rank());
  comm_.sum(areas);
  return observer_.stop_reason(CompactionObserver<Dim>::total_area(areas), st, t_);
}

// V_s, the grains' current area [m^2] (collective on several ranks: summed per grain over the
// ranks, then over the grains in order, as stop_criterion does).
template <int Dim>
double Run<Dim>::grain_area() {
  if (comm_.size() == 1)
    return CompactionObserver<Dim>::total_area(CompactionObserver<Dim>::grain_areas(model_));
  auto areas = CompactionObserver<Dim>::grain_areas(model_, &solver_->owner(), comm_.rank());
  comm_.sum(areas);
  return CompactionObserver<Dim>::total_area(areas);
}

// The loading after the committed step of length dt [s] (every rank: the wall forces are
// reduced over the ranks, Phi when a stage needs it is collective): walls moved, stage ended.
// Returns the reason to end the run once the last stage has ended.
template <int Dim>
std::optional<std::string> Run<Dim>::loading_step(const mpm::StepStats& st, double dt) {
  if (!loading_.active()) return std::nullopt;
  loading_.committed(st, dt);
  observer_.move_walls(loading_.walls(t_));
  const double area = loading_.needs_area() ? grain_area() : 0.0;
  if (const auto ended = loading_.advance(t_, area)) {
    if (loading_.finished()) return "loading finished: " + *ended;  // logged as the run's end
    log().info("step {}: {}; stage {} ('{}') starts", summary_.steps, *ended,
               loading_.state().stage + 1, loading_.stage_name());
  }
  return std::nullopt;
}

// After a committed step that did not end the run (`at_end`: it reached end_time): a signal or
// --stop-after writes a checkpoint and returns false (stop); periodic checkpoints; the progress
// line. Collective.
template <int Dim>
bool Run<Dim>::between_steps(const mpm::StepStats& st, bool at_end) {
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

template <int Dim>
RunSummary Run<Dim>::go() {
  if (!restart_) record(true);
  comm_.record_syncs();  // the serial fraction, measured at every synchronisation
  wall0_ = last_progress_ = last_checkpoint_wall_ = std::chrono::steady_clock::now();
  if (!opt_.quiet) progress_.add(progress_sample(last_, 0.0).first);
  const double t_end = cfg_.time.end_time, eps = 1e-9 * cfg_.time.dt;
  // A restart from the checkpoint of a loading that has ended has nothing left to do.
  while (t_ < t_end - eps && !loading_.finished()) {
    double remaining = t_end - t_;
    // A stage of given duration ends on a step boundary.
    if (const auto te = loading_.stage_end_time(); te && *te - t_ > eps)
      remaining = std::min(remaining, *te - t_);
    const double dt = dt_control_.next(remaining);
    solver_->set_time(t_);
    if (loading_.active()) solver_->set_walls(loading_.step_walls(t_, dt));
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
    std::optional<std::string> criterion = loading_step(st, dt);
    if (!criterion) criterion = stop_criterion(st);
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
template <int Dim>
RunSummary Run<Dim>::finish() {
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
  if (summary_.split_points > 0 && root_)
    log().info("{} point(s) were split in two during this run ([grid] split_points), {} now",
               summary_.split_points, model_.points.size());
  if (summary_.shrunk_steps > 0)
    log().warn(
        "CPDI domains were shrunk to their window in {} of the {} steps of this run, at most {} "
        "points in one step (docs/accuracy.md; more points per cell avoid it)",
        summary_.shrunk_steps, summary_.steps - steps0_, summary_.shrunk_domains_max);
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

template class Run<2>;
template class Run<3>;

}  // namespace detail

RunSummary run_simulation(const io::Config& cfg, const RunOptions& opt,
                          const checkpoint::State* restart) {
  if (cfg.simulation.dimension == 3) return detail::Run<3>(cfg, opt, restart).go();
  return detail::Run<2>(cfg, opt, restart).go();
}

}  // namespace mpmcd::app
