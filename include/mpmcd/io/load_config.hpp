#pragma once
/// Loading the simulation input: one TOML file (SI units), validated against the schema registry
/// of io/config.cpp. Every problem is reported as mpmcd::InputError naming file, line, key and
/// what was expected. The loader reads only; it writes nothing.
#include <string>
#include <string_view>

#include "mpmcd/io/config.hpp"

namespace mpmcd::io {

struct Schema;

/// Reads and validates the TOML input at `path` (throws InputError).
Config load_config(const std::string& path);

/// Validates TOML `text`; `source_name` is the file name used in messages and the folder that
/// relative paths (packing files) are resolved against (throws InputError).
Config parse_config(std::string_view text, const std::string& source_name);

/// The schema of the simulation input (tables, keys, types, defaults, ranges, units).
const Schema& config_schema();

/// The full input reference (Markdown) generated from the schema and the law registry; the
/// committed docs/input.md is this text.
std::string input_reference_markdown();

}  // namespace mpmcd::io
