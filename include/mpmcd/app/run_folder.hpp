#pragma once
/// The output folder of a run (docs/robustness.md, "Output folders"): which folder a run writes
/// to, and one folder, one run: a new run refuses a folder holding files of an earlier run unless
/// --overwrite removes them first; a restart continues in its checkpoint's folder.
#include <string>

#include "mpmcd/app/simulation.hpp"
#include "mpmcd/io/config.hpp"
#include "mpmcd/parallel/comm.hpp"

namespace mpmcd::app {

/// The folder a run writes to: `options.output_dir` if given; else, for a restart (`restart`),
/// the folder of its checkpoint `options.restart`; else [output] folder, a relative one taken
/// from the input file's folder [-].
std::string output_folder(const io::Config& config, const RunOptions& options, bool restart);

/// Makes `dir` this run's folder: a restart writing to its checkpoint's folder continues there;
/// any other run claims it (a folder holding input.toml or files of a run of this name is refused
/// with InputError unless `options.overwrite`, which removes them, and those of the run named in
/// the old input.toml, first). Returns the checkpoint's folder when a restart writes elsewhere
/// (its earlier outputs are copied from there, Outputs), else "". Collective: rank 0 looks and
/// tells the others.
std::string prepare_output_folder(const io::Config& config, const RunOptions& options,
                                  const std::string& dir, bool restart, const parallel::Comm& comm);

}  // namespace mpmcd::app
