#pragma once
/// The `mpmcd pack <input>` command (docs/packing.md §9).
#include <string>

namespace mpmcd::packing {

/// Reads the packing input at `input_path`, generates the packing, writes <folder>/<name>.csv
/// and <folder>/<name>.vtu, prints the summary line to stdout and returns 0. `quiet` silences the
/// progress log (not the summary line). Throws InputError on bad input (exit code 2). A packing
/// that did not relax (two disks overlapping by more than kOverlapTolerance of the smaller
/// diameter, which `mpmcd run` refuses) is not written: a message on stderr and 3 [-]. An output
/// folder that already holds <name>.csv or <name>.vtu is refused (InputError) unless `overwrite`,
/// which removes them first.
int pack_command(const std::string& input_path, bool quiet, bool overwrite = false);

}  // namespace mpmcd::packing
