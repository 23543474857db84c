#pragma once
/// The state of a run after a committed step, and its conversion to and from a checkpoint
/// (checkpoint::State, plain arrays; docs/robustness.md): the model's points and grains, the time
/// stepping and output counters, the contact warm start, the walls, the energy ledger and the
/// distribution over ranks. Written once for any dimension; a restart, or a benchmark that starts
/// from a checkpoint file (restore_from_checkpoint), restores a run through it.
#include <cstdint>
#include <string>
#include <vector>

#include "mpmcd/app/energy_ledger.hpp"
#include "mpmcd/checkpoint/checkpoint.hpp"
#include "mpmcd/io/config.hpp"
#include "mpmcd/mpm/model.hpp"
#include "mpmcd/mpm/solver.hpp"

namespace mpmcd::app {

/// Where a run stands after a committed step, besides its points and grains (the model): what a
/// checkpoint holds with the model.
template <int Dim>
struct RunState {
  // Time stepping.
  std::int64_t step = 0;               ///< committed steps [-]
  double time = 0;                     ///< simulated time t^n [s]
  double dt = 0;                       ///< current (possibly cut) time step [s]
  std::int64_t good_since_cut = 0;     ///< good steps since the last dt cut [-]
  std::int64_t failed_steps = 0;       ///< attempts retried with a smaller dt so far [-]
  std::int64_t newton_iterations = 0;  ///< Newton iterations so far [-]
  // Output counters.
  double next_vtu = 0;            ///< simulated time of the next VTU snapshot [s]
  double next_csv = 0;            ///< simulated time of the next CSV row [s]
  std::int64_t csv_rows = 0;      ///< CSV rows written so far (header excluded) [-]
  std::vector<double> vtu_times;  ///< time of each VTU snapshot written so far [s]
  // Contact and walls.
  std::vector<mpm::WarmImpulse<Dim>> warm;  ///< impulses of the last step (warm start) [N s]
  std::vector<Vec<Dim>> wall_points;        ///< current point of each wall plane [m]
  EnergySums energy;                        ///< the energy ledger's sums since t = 0 [J]
  // Distribution (docs/parallel.md).
  int ranks = 1;                     ///< MPI ranks of the run [-]
  std::string scheme = "partition";  ///< parallel scheme of the run [-]
  int threads = 1;                   ///< OpenMP threads per rank [-]
  std::vector<int> grain_owner;      ///< rank owning each grain [-]
  /// Re-balancing work since the last check, grain x parallel::kWorkPhases (grain-major) [-].
  std::vector<double> grain_work;
};

/// The checkpoint of the run of input `config` whose model is `model` and state `run`, written
/// for `reason` ("periodic", "end", "signal", "stop_after", "failure") [-].
template <int Dim>
checkpoint::State to_checkpoint(const io::Config& config, const mpm::Model<Dim>& model,
                                const RunState<Dim>& run, const std::string& reason);

/// The run state held by `state` (points and grains excluded: restore_model).
template <int Dim>
RunState<Dim> run_state_of(const checkpoint::State& state);

/// The model of a restart: grid and materials from `config`, points and grains from `state` (no
/// packing is regenerated). Throws InputError naming `path` if they do not fit together
/// (dimension, materials, history, points outside the grid, warm-start entries, walls).
template <int Dim>
mpm::Model<Dim> restore_model(const io::Config& config, const checkpoint::State& state,
                              const std::string& path);

extern template checkpoint::State to_checkpoint<2>(const io::Config&, const mpm::Model<2>&,
                                                   const RunState<2>&, const std::string&);
extern template RunState<2> run_state_of<2>(const checkpoint::State&);
extern template mpm::Model<2> restore_model<2>(const io::Config&, const checkpoint::State&,
                                               const std::string&);

/// A checkpoint and the input of the run it continues.
struct Restart {
  io::Config config;        ///< the validated input
  checkpoint::State state;  ///< the state to continue from
  std::string path;         ///< the checkpoint file
};

/// Reads checkpoint `path` (refused with InputError if damaged) and the input it continues:
/// `input` if not empty (its text must be the one the checkpoint was written from), else the input
/// text stored in the checkpoint. Throws InputError (exit 2).
Restart load_restart(const std::string& path, const std::string& input);

/// A 2D run restored from a checkpoint file, ready to step on (solver built from `model` and
/// `settings`, boundaries at run.time, warm start run.warm).
struct RestoredRun {
  io::Config config;          ///< the input of the run
  mpm::Model<2> model;        ///< grid, materials, points and grains at the checkpoint
  mpm::Settings<2> settings;  ///< solver settings from the input
  RunState<2> run;            ///< time, dt, counters, warm start, ledger at the checkpoint
  std::string path;           ///< the checkpoint file
};

/// Restores the run of checkpoint `path` with its input (`input`, or the text the checkpoint
/// holds if empty: load_restart). Throws InputError (exit 2).
RestoredRun restore_from_checkpoint(const std::string& path, const std::string& input = "");

}  // namespace mpmcd::app
