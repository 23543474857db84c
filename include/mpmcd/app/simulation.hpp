#pragma once
/// The simulation driver: builds the model from the validated input, runs the implicit steps with
/// time-step cuts on failure, and writes the outputs (VTU/PVD series, CSV time series, input copy).
#include <cstdint>
#include <string>
#include <vector>

#include "mpmcd/checkpoint/checkpoint.hpp"
#include "mpmcd/io/config.hpp"
#include "mpmcd/mpm/model.hpp"
#include "mpmcd/mpm/solver.hpp"

namespace mpmcd::app {

/// Command-line options of `mpmcd run`.
struct RunOptions {
  bool quiet = false;           ///< no progress lines or info messages
  std::string output_dir;       ///< overrides [output] folder if not empty
  int threads = 0;              ///< overrides [simulation] threads if > 0
  std::string restart;          ///< checkpoint to continue from ("" = start at t = 0)
  std::int64_t stop_after = 0;  ///< if > 0: stop after this many steps of this invocation, as if
                                ///< interrupted (checkpoint written; for job time limits, tests)
  std::string scheme;  ///< parallel scheme "partition" (default) or "master" (docs/parallel.md)
  double rebalance = 1.01;  ///< partition: re-deal above this work imbalance (partition.hpp) [-]
  /// Replace an earlier run in the output folder (its files are removed first); without it a
  /// folder holding a run is refused (InputError), except a restart's own folder [-].
  bool overwrite = false;
};

/// Summary of a finished run.
struct RunSummary {
  std::int64_t steps = 0;              ///< committed steps
  std::int64_t failed_steps = 0;       ///< attempts retried with a smaller dt
  std::int64_t newton_iterations = 0;  ///< sum over steps
  double time = 0;                     ///< final simulated time [s]
  double wall_seconds = 0;             ///< wall time of the stepping loop [s]
  std::string output_dir;              ///< where the outputs are
  std::string stop_reason;             ///< the [stop] criterion reached, "" if end_time
  std::string checkpoint;              ///< last checkpoint written ("" if none)
  bool interrupted = false;            ///< stopped before end_time by a signal or stop_after
  int signal = 0;                      ///< signal that interrupted the run (0: none)
  /// Committed steps of this invocation in which some CPDI domains spanned more than two cells
  /// and were shrunk to their window for the shape functions (docs/accuracy.md) [-].
  std::int64_t shrunk_steps = 0;
  /// The most such points in one of those steps, over all grains and ranks [-].
  std::int64_t shrunk_domains_max = 0;
  /// Points split in two in this invocation because their CPDI domain outgrew its window
  /// ([grid] split_points; docs/accuracy.md, "Point splitting") [-].
  std::int64_t split_points = 0;
};

/// Runs the whole simulation, from t = 0 or from `restart` (options.restart names its file);
/// throws InputError (exit 2) or NumericalError (exit 3, after writing the last good state and
/// its checkpoint). SIGINT/SIGTERM finish the current step, write a checkpoint and return with
/// RunSummary::signal set (exit 4 in the command line).
RunSummary run_simulation(const io::Config& config, const RunOptions& options,
                          const checkpoint::State* restart = nullptr);

}  // namespace mpmcd::app
