#pragma once
/// The state of a run after a committed step to and from a checkpoint (checkpoint::State, plain
/// arrays; docs/robustness.md): the model's points and grains, the contact warm start, the walls
/// and the energy ledger's sums (the counters are the State's own fields). Written once for any
/// dimension; a restart, or a benchmark that starts from a checkpoint file
/// (restore_from_checkpoint), restores a run through it.
#include <cstdint>
#include <string>
#include <vector>

#include "mpmcd/app/energy_ledger.hpp"
#include "mpmcd/app/wall_loading.hpp"
#include "mpmcd/checkpoint/checkpoint.hpp"
#include "mpmcd/io/config.hpp"
#include "mpmcd/mpm/model.hpp"
#include "mpmcd/mpm/solver.hpp"
#include "mpmcd/walls/wall.hpp"

namespace mpmcd::app {

/// Fills `state` with the input `config` of the run, the points and grains of `model`, the
/// contact warm start `warm` and the points of `walls` at state.time. The run's counters (time
/// stepping, outputs, energy ledger: store_energy, distribution) are checkpoint::State's own
/// fields, set by the caller.
template <int Dim>
void store_run(const io::Config& config, const mpm::Model<Dim>& model,
               const std::vector<mpm::WarmImpulse<Dim>>& warm,
               const std::vector<walls::Wall<Dim>>& walls, checkpoint::State& state);

/// The model of a restart: grid and materials from `config`, points and grains from `state` (no
/// packing is regenerated). Throws InputError naming `path` if they do not fit together
/// (dimension, materials, history, points outside the grid, warm-start entries, walls).
template <int Dim>
mpm::Model<Dim> restore_model(const io::Config& config, const checkpoint::State& state,
                              const std::string& path);

/// The contact warm start held by `state` (impulses of the last converged step).
template <int Dim>
std::vector<mpm::WarmImpulse<Dim>> warm_start_of(const checkpoint::State& state);

/// Stores the wall loading's state in `state` (docs/loading.md): per wall 4 Dim + 5 values
/// (checkpoint::State::loading_wall).
template <int Dim>
void store_loading(const LoadingState<Dim>& loading, checkpoint::State& state);
/// The wall loading's state held by `state` (walls at state.wall_point). Throws
/// std::invalid_argument when the checkpoint has none or a malformed one.
template <int Dim>
LoadingState<Dim> loading_state_of(const checkpoint::State& state);

/// Stores the energy ledger's sums in `state`.
void store_energy(const EnergySums& sums, checkpoint::State& state);
/// The energy ledger's sums held by `state`.
EnergySums energy_sums_of(const checkpoint::State& state);

extern template void store_run<2>(const io::Config&, const mpm::Model<2>&,
                                  const std::vector<mpm::WarmImpulse<2>>&,
                                  const std::vector<walls::Wall<2>>&, checkpoint::State&);
extern template mpm::Model<2> restore_model<2>(const io::Config&, const checkpoint::State&,
                                               const std::string&);
extern template std::vector<mpm::WarmImpulse<2>> warm_start_of<2>(const checkpoint::State&);
extern template void store_run<3>(const io::Config&, const mpm::Model<3>&,
                                  const std::vector<mpm::WarmImpulse<3>>&,
                                  const std::vector<walls::Wall<3>>&, checkpoint::State&);
extern template mpm::Model<3> restore_model<3>(const io::Config&, const checkpoint::State&,
                                               const std::string&);
extern template std::vector<mpm::WarmImpulse<3>> warm_start_of<3>(const checkpoint::State&);
extern template void store_loading<2>(const LoadingState<2>&, checkpoint::State&);
extern template void store_loading<3>(const LoadingState<3>&, checkpoint::State&);
extern template LoadingState<2> loading_state_of<2>(const checkpoint::State&);
extern template LoadingState<3> loading_state_of<3>(const checkpoint::State&);

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

/// A run of dimension Dim restored from a checkpoint file, ready to step on (a solver built from
/// `model` and `settings`, boundaries at state.time, warm start `warm`).
template <int Dim = 2>
struct RestoredRun {
  io::Config config;            ///< the input of the run
  checkpoint::State state;      ///< the checkpoint: time, dt, counters, ledger, distribution
  mpm::Model<Dim> model;        ///< grid, materials, points and grains at the checkpoint
  mpm::Settings<Dim> settings;  ///< solver settings from the input
  std::vector<mpm::WarmImpulse<Dim>> warm;  ///< contact impulses of the last step (warm start)
  std::string path;                         ///< the checkpoint file
};

/// Restores the run of checkpoint `path` with its input (`input`, or the text the checkpoint
/// holds if empty: load_restart); its `[simulation] dimension` must be Dim. Throws InputError
/// (exit 2).
template <int Dim = 2>
RestoredRun<Dim> restore_from_checkpoint(const std::string& path, const std::string& input = "");
extern template RestoredRun<2> restore_from_checkpoint<2>(const std::string&, const std::string&);
extern template RestoredRun<3> restore_from_checkpoint<3>(const std::string&, const std::string&);

}  // namespace mpmcd::app
