#pragma once
// Private to the app module: one run of run_simulation (class Run), shared by its two source files
// (docs/architecture.md, "The app module's files"): simulation.cpp builds the run and steps it
// (the loop, signals, checkpoints when due, the end of the run); run_records.cpp writes what the
// run records (CSV rows and snapshots, checkpoints, the last good state of a failure, the progress
// line).
#include <chrono>
#include <csignal>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <utility>

#include "mpmcd/app/compaction_observer.hpp"
#include "mpmcd/app/energy_ledger.hpp"
#include "mpmcd/app/outputs.hpp"
#include "mpmcd/app/progress.hpp"
#include "mpmcd/app/run_state.hpp"
#include "mpmcd/app/simulation.hpp"
#include "mpmcd/app/step_controller.hpp"
#include "mpmcd/app/wall_loading.hpp"
#include "mpmcd/parallel/comm.hpp"
#include "mpmcd/parallel/partition.hpp"

namespace mpmcd::app::detail {

/// Catches SIGINT and SIGTERM while alive (simulation.cpp): the handler only records the signal;
/// the loop finishes its step, writes a checkpoint and returns. SA_RESETHAND: a second signal gets
/// the default action (stops at once). The previous handlers come back on destruction.
class SignalGuard {
 public:
  SignalGuard();
  ~SignalGuard();
  SignalGuard(const SignalGuard&) = delete;
  SignalGuard& operator=(const SignalGuard&) = delete;

 private:
  struct sigaction old_int_ = {}, old_term_ = {};
};

/// One run in Dim = 2 or 3 dimensions: its model and solver, its outputs and its counters.
/// Processes (docs/parallel.md): every rank holds the model and computes its grains; rank 0
/// gathers the state at output and checkpoint times and writes every file.
template <int Dim>
class Run {
 public:
  /// Builds or restores everything (may throw InputError: before any output is written), then
  /// writes the outputs' headers.
  Run(const io::Config& cfg, const RunOptions& opt, const checkpoint::State* restart);
  /// Steps to the end (or a [stop] criterion, a signal, --stop-after); returns the summary.
  RunSummary go();

 private:
  // simulation.cpp: setting up, stepping, ending.
  void distribute();
  void commit(const mpm::StepStats& st, double dt);
  void rebalance();
  void split_points();
  std::optional<std::string> stop_criterion(const mpm::StepStats& st);
  double grain_area();
  std::optional<std::string> loading_step(const mpm::StepStats& st, double dt);
  bool between_steps(const mpm::StepStats& st, bool at_end);
  RunSummary finish();
  // run_records.cpp: what the run writes.
  void gather_state();
  void record(bool force);
  checkpoint::State state_now(const std::string& reason);
  std::string write_checkpoint(const std::string& reason);
  [[noreturn]] void fail(const mpm::StepStats& st);
  std::pair<ProgressSample, std::optional<typename CompactionObserver<Dim>::Now>> progress_sample(
      const mpm::StepStats& st, double wall);
  void report_progress(const mpm::StepStats& st, double wall);

  const io::Config& cfg_;
  const RunOptions& opt_;
  const checkpoint::State* restart_;  // the checkpoint continued (nullptr: a new run)
  mpm::Model<Dim> model_;
  const mpm::Settings<Dim> settings_;
  CompactionObserver<Dim> observer_;  // follows the walls moved by loading_
  const parallel::Comm& comm_;
  const bool root_;
  const parallel::Scheme scheme_;
  const bool any_moving_, stop_active_;
  RunSummary summary_;
  std::optional<SignalGuard> signals_;
  std::unique_ptr<mpm::ImplicitSolver<Dim>> solver_;
  EnergyLedger<Dim> ledger_;
  WallLoading<Dim> loading_;      // [loading]: the walls' motion in stages (inactive without it)
  std::unique_ptr<Outputs> out_;  // rank 0 only
  StepController dt_control_;
  ProgressEstimator progress_;
  double t_, next_vtu_, next_csv_;  // simulated time, of the next VTU and CSV output [s]
  const std::int64_t steps0_;       // steps committed before this invocation [-]
  std::int64_t last_checkpoint_step_;
  mpm::StepStats last_;  // the last converged step
  bool fast_points_reported_ = false;
  bool shrunk_reported_ = false;  // the shrunk-CPDI-domain warning was given
  std::chrono::steady_clock::time_point wall0_, last_progress_, last_checkpoint_wall_;
};

}  // namespace mpmcd::app::detail
