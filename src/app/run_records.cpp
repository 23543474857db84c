// What a run records while it steps (class Run, run.hpp): the CSV rows and VTU snapshots when
// due, checkpoints, the last good state of a failed run, and the progress line.
#include <fmt/format.h>
#include <omp.h>

#include <algorithm>
#include <filesystem>

#include "mpmcd/app/speed_check.hpp"
#include "mpmcd/core/errors.hpp"
#include "mpmcd/core/log.hpp"
#include "mpmcd/parallel/distribute.hpp"
#include "run.hpp"

namespace mpmcd::app::detail {

namespace fs = std::filesystem;

// Rank 0 gathers every grain's points (collective).
template <int Dim>
void Run<Dim>::gather_state() {
  ScopedStage ts(&solver_->timers(), "output");
  parallel::gather_points(comm_, model_.points, model_.grains, solver_->owner(), 0);
}

// The CSV row and the VTU snapshot of the committed state, when due or `force`d (collective).
template <int Dim>
void Run<Dim>::record(bool force) {
  const double eps = 1e-9 * cfg_.time.dt;
  const bool csv = force || t_ >= next_csv_ - eps, vtu = force || t_ >= next_vtu_ - eps;
  if (!csv && !vtu) return;
  if (comm_.size() > 1) gather_state();
  if (root_ && !fast_points_reported_)
    if (const auto w = fast_point_warning(cfg_, model_, t_)) {
      log().warn("{}", *w);
      fast_points_reported_ = true;
    }
  if (root_ && !shrunk_reported_ && last_.shrunk_domains > 0) {
    log().warn(
        "{} material point domains span more than two cells along an axis at t = {:.6g} s: CPDI "
        "evaluates their shape functions on the domain shrunk to fit its window, which no longer "
        "tiles the grain there (docs/accuracy.md; more points per cell avoid it)",
        last_.shrunk_domains, t_);
    shrunk_reported_ = true;
  }
  ScopedStage ts(&solver_->timers(), "output");
  const auto problem = parallel::gather_contacts(comm_, solver_->contact_problem(), 0);
  if (csv) {
    if (root_) {
      const auto d = mpm::diagnostics(model_);
      out_->csv_row(summary_.steps, t_, dt_control_.dt(), last_, d,
                    observer_.csv_fields(model_, last_, problem, t_) + loading_.csv_fields(t_) +
                        ledger_.csv_fields(d));
    }
    next_csv_ = t_ + cfg_.output.csv_interval;
  }
  if (vtu) {
    if (root_) out_->vtu(model_, *solver_, problem, t_);
    next_vtu_ = t_ + cfg_.output.vtu_interval;
  }
}

// The run's counters, as its checkpoint written for `reason` holds them (on rank 0; the model,
// the warm start and the work counts are added by write_checkpoint).
template <int Dim>
checkpoint::State Run<Dim>::state_now(const std::string& reason) {
  checkpoint::State s;
  s.reason = reason;
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
  store_energy(ledger_.sums(), s);
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
template <int Dim>
std::string Run<Dim>::write_checkpoint(const std::string& reason) {
  ScopedStage ts(&solver_->timers(), "checkpoint");
  if (comm_.size() > 1) gather_state();
  // Warm-start impulses of every rank (each contact is solved by one rank).
  const auto warm = solver_->gather_warm_start();
  std::vector<double> work = solver_->grain_work();
  work.resize(model_.grains.size() * parallel::kWorkPhases, 0.0);
  comm_.sum(work);
  last_checkpoint_step_ = summary_.steps;
  if (!root_) return std::string();
  checkpoint::State s = state_now(reason);
  s.grain_work = std::move(work);
  store_run(cfg_, model_, warm, loading_.active() ? loading_.walls(t_) : settings_.contact.walls,
            s);
  if (loading_.active()) store_loading(loading_.state(), s);
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
template <int Dim>
void Run<Dim>::fail(const mpm::StepStats& st) {
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

// Progress toward the criterion that will end the run (docs/robustness.md, "Progress"): the
// compaction state of the committed step (collective: the grains' area is summed over ranks).
template <int Dim>
std::pair<ProgressSample, std::optional<typename CompactionObserver<Dim>::Now>>
Run<Dim>::progress_sample(const mpm::StepStats& st, double wall) {
  ProgressSample s{wall, t_, std::nullopt, std::nullopt, std::nullopt};
  if (!observer_.has_box()) return {s, std::nullopt};
  std::vector<double> areas = CompactionObserver<Dim>::grain_areas(
      model_, comm_.size() > 1 ? &solver_->owner() : nullptr, comm_.rank());
  if (comm_.size() > 1) comm_.sum(areas);
  const auto now = observer_.now(CompactionObserver<Dim>::total_area(areas), st, t_);
  s.phi = now->phi;
  s.strain = now->strain;
  if (!st.wall_force.empty()) s.stress = -now->bottom_stress;  // none before the first step
  return {s, now};
}

// The progress line after the committed step `st`, `wall` [s] after this invocation started.
template <int Dim>
void Run<Dim>::report_progress(const mpm::StepStats& st, double wall) {
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
// The members defined in this file, for both dimensions (simulation.cpp instantiates the rest).
#define MPMCD_RUN_RECORDS(Dim)                                                             \
  template void Run<Dim>::gather_state();                                                  \
  template void Run<Dim>::record(bool);                                                    \
  template checkpoint::State Run<Dim>::state_now(const std::string&);                      \
  template std::string Run<Dim>::write_checkpoint(const std::string&);                     \
  template void Run<Dim>::fail(const mpm::StepStats&);                                     \
  template std::pair<ProgressSample, std::optional<typename CompactionObserver<Dim>::Now>> \
  Run<Dim>::progress_sample(const mpm::StepStats&, double);                                \
  template void Run<Dim>::report_progress(const mpm::StepStats&, double);
MPMCD_RUN_RECORDS(2)
MPMCD_RUN_RECORDS(3)
#undef MPMCD_RUN_RECORDS

}  // namespace mpmcd::app::detail
