#include "mpmcd/app/cli.hpp"

#include <fmt/format.h>
#include <CLI/CLI.hpp>

#include "mpmcd/core/errors.hpp"
#include "mpmcd/version.hpp"

namespace mpmcd::app {

int run_cli(int argc, char** argv) {
  CLI::App cli{"mpmcd: implicit MPM with Contact Dynamics for soft granular matter"};
  cli.set_version_flag("--version", fmt::format("mpmcd {} ({})", kVersion, kGitHash));
  try {
    cli.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int rc = cli.exit(e);
    return rc == 0 ? 0 : static_cast<int>(ExitCode::kInput);
  }
  return 0;
}

}  // namespace mpmcd::app
