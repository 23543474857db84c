#pragma once
/// The packing input file (TOML, docs/packing.md §5): a [packing] table (also embeddable in the
/// simulation input) and an [output] table.
#include <string>
#include <string_view>

#include <toml++/toml.h>

#include "mpmcd/packing/packing.hpp"

namespace mpmcd::packing {

/// A whole packing input file.
struct PackingInput {
  std::string source_path;                    ///< the TOML file it came from
  PackingParams params;                       ///< [packing]
  std::string output_folder = "packing_out";  ///< [output] folder, relative to the working dir
  std::string output_name = "packing";        ///< [output] base name of <name>.csv and <name>.vtu
  bool write_vtu = true;                      ///< [output] vtu: write <name>.vtu
};

/// Reads the keys of a [packing] table into PackingParams and validates them. `file` names the
/// source in messages, `prefix` is the dotted path of the table ("packing"). Unknown keys, wrong
/// types, missing or conflicting keys and out-of-range values throw
/// InputError(file, line, "prefix.key", expectation).
PackingParams packing_params_from_toml(const toml::table& table, const std::string& file,
                                       const std::string& prefix = "packing");

/// Loads and validates a packing input file ([packing] required, [output] optional); throws
/// InputError on unreadable files, TOML syntax errors and every schema violation.
PackingInput load_packing_input(const std::string& path);

/// Validates the text of a packing input; `path` names it in messages (throws InputError).
PackingInput parse_packing_input(std::string_view text, const std::string& path);

}  // namespace mpmcd::packing
