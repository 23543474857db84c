#pragma once
/// The `mpmcd` command line (subcommands run, pack, list); returns the process exit code.
namespace mpmcd::app {

/// Parses argv, runs the chosen subcommand and maps exceptions to exit codes (core/errors.hpp).
int run_cli(int argc, char** argv);

}  // namespace mpmcd::app
