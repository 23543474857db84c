#pragma once
/// The `mpmcd pack <input>` command (docs/packing.md §9).
#include <string>

namespace mpmcd::packing {

/// Reads the packing input at `input_path`, generates the packing, writes <folder>/<name>.csv
/// and <folder>/<name>.vtu, prints the summary line to stdout and returns 0. `quiet` silences the
/// progress log (not the summary line). Throws InputError on bad input (exit code 2).
int pack_command(const std::string& input_path, bool quiet);

}  // namespace mpmcd::packing
