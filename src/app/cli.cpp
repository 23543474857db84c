#include "mpmcd/app/cli.hpp"

#include <fmt/format.h>
#include <CLI/CLI.hpp>

#include <csignal>
#include <iostream>

#include "mpmcd/app/analyze.hpp"
#include "mpmcd/app/model_builder.hpp"
#include "mpmcd/app/run_state.hpp"
#include "mpmcd/app/simulation.hpp"
#include "mpmcd/contact/law.hpp"
#include "mpmcd/core/errors.hpp"
#include "mpmcd/core/log.hpp"
#include "mpmcd/io/load_config.hpp"
#include "mpmcd/materials/law.hpp"
#include "mpmcd/packing/pack_command.hpp"
#include "mpmcd/parallel/comm.hpp"
#include "mpmcd/version.hpp"

namespace mpmcd::app {

namespace {

void print_laws() {
  for (const auto& law : materials::law_registry()) {
    std::cout << law.name << ": " << law.description << "\n";
    for (const auto& p : law.params)
      std::cout << "    " << p.name << " [" << p.unit << "]: " << p.description << "\n";
  }
  std::cout << "\ncontact laws ([contact] law):\n";
  for (const auto& law : contact::contact_law_registry()) {
    std::cout << law.name << ": " << law.description << "\n";
    for (const auto& p : law.params) std::cout << "    reads the contacts' " << p << "\n";
  }
}

}  // namespace

int run_cli(int argc, char** argv) {
  CLI::App cli{"mpmcd: implicit MPM with Contact Dynamics for soft granular matter"};
  cli.set_version_flag("--version", fmt::format("mpmcd {} ({})", kVersion, kGitHash));
  cli.require_subcommand(1);

  RunOptions run_opt;
  std::string run_input;
  auto* run = cli.add_subcommand("run", "run a simulation from a TOML input");
  run->add_option("input", run_input,
                  "input file (TOML, see docs/input.md); with --restart optional (the checkpoint "
                  "holds the input), and if given it must be the same text");
  run->add_option("--restart", run_opt.restart,
                  "continue from a checkpoint file (<name>_checkpoint_<step>.h5); outputs go on "
                  "in the checkpoint's folder unless -o is given");
  run->add_option("--stop-after", run_opt.stop_after,
                  "stop after this many steps (of this invocation) as if interrupted: write a "
                  "checkpoint and exit 4 (chunks of a long run under a job time limit)")
      ->check(CLI::PositiveNumber);
  run->add_flag("-q,--quiet", run_opt.quiet, "no progress or info lines");
  run->add_flag("--overwrite", run_opt.overwrite,
                "replace an earlier run in the output folder (its files are removed first); "
                "without it such a folder is refused, except a restart's own folder");
  run->add_option("-o,--output", run_opt.output_dir, "output folder (overrides [output] folder)");
  run->add_option("-t,--threads", run_opt.threads, "OpenMP threads (overrides [simulation])")
      ->check(CLI::Range(1, 1024));
  run->add_option("--scheme", run_opt.scheme,
                  "with mpirun: partition (default) or master (docs/parallel.md)")
      ->check(CLI::IsMember({"partition", "master"}));
  run->add_option("--rebalance", run_opt.rebalance,
                  "with mpirun, partition: re-deal the grains when the work imbalance (sum over "
                  "phases of the largest rank's work over the mean) exceeds this, checked every "
                  "50 steps (0: never; default 1.01)")
      ->check(CLI::NonNegativeNumber);

  std::string check_input;
  auto* check = cli.add_subcommand("check", "validate an input file and exit");
  check->add_option("input", check_input, "input file (TOML)")->required();

  std::string list_what;
  auto* list = cli.add_subcommand("list", "print the input reference or the registered laws");
  list->add_option("what", list_what, "input | laws")
      ->required()
      ->check(CLI::IsMember({"input", "laws"}));

  std::string pack_input;
  bool pack_quiet = false;
  auto* pack = cli.add_subcommand("pack", "generate a disk packing by DEM (docs/packing.md)");
  pack->add_option("input", pack_input, "packing input (TOML)")->required();
  pack->add_flag("-q,--quiet", pack_quiet, "only the summary line");
  bool pack_overwrite = false;
  pack->add_flag("--overwrite", pack_overwrite,
                 "replace <name>.csv/.vtu if the output folder holds them (else refused)");

  AnalyzeOptions analyze_opt;
  auto* analyze =
      cli.add_subcommand("analyze",
                         "compaction analysis of run folders: Phi_J, eq. (10) fit, Figures 4-5 "
                         "(docs/observables.md)");
  analyze->add_option("folders", analyze_opt.folders, "run output folders")->required();
  analyze->add_option("-o,--output", analyze_opt.output_dir,
                      "output folder (default <folder>/analysis, or compaction_analysis)");
  analyze
      ->add_option("--jam-stress", analyze_opt.jamming.stress,
                   "jammed: -sigma/M_p of the bottom wall at least this from Phi_J on")
      ->check(CLI::PositiveNumber);
  analyze->add_option("--jam-z", analyze_opt.jamming.min_z, "jammed: also Z at least this")
      ->check(CLI::NonNegativeNumber);
  analyze
      ->add_option("--phi", analyze_opt.distribution_phi,
                   "solid fractions of the force and grain-pressure distributions (runs with "
                   "[output] grains)")
      ->check(CLI::Range(0.0, 1.0));
  bool analyze_no_plots = false;
  analyze->add_flag("--no-plots", analyze_no_plots, "write the CSV files only");
  analyze->add_flag("--overwrite", analyze_opt.overwrite,
                    "replace an earlier analysis in the output folder (else refused)");

  try {
    cli.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int rc = cli.exit(e);
    return rc == 0 ? 0 : static_cast<int>(ExitCode::kInput);
  }

  // `mpmcd run` may be one rank of several (docs/parallel.md); the other commands are serial.
  const parallel::Comm* comm = *run ? &parallel::Comm::world() : nullptr;
  const bool rank0 = !comm || comm->rank() == 0;
  try {
    if (*run) {
      setup_logging(run_opt.quiet ? Verbosity::kQuiet : Verbosity::kNormal);
      if (run_input.empty() && run_opt.restart.empty())
        throw InputError("mpmcd run: an input file is required (or --restart <checkpoint>)");
      RunSummary summary;
      if (!run_opt.restart.empty()) {
        const Restart restart = load_restart(run_opt.restart, run_input);
        summary = run_simulation(restart.config, run_opt, &restart.state);
      } else {
        summary = run_simulation(io::load_config(run_input), run_opt);
      }
      if (summary.interrupted) {
        const std::string by = summary.signal == SIGINT    ? "SIGINT"
                               : summary.signal == SIGTERM ? "SIGTERM"
                               : summary.signal != 0 ? fmt::format("signal {}", summary.signal)
                                                     : std::string("--stop-after");
        if (rank0)
          std::cerr << fmt::format(
              "mpmcd: interrupted ({}) at step {} (t = {:.9g} s); state saved in {}\n"
              "mpmcd: resume with: mpmcd run --restart {}\n",
              by, summary.steps, summary.time, summary.checkpoint, summary.checkpoint);
        return static_cast<int>(ExitCode::kInterrupted);
      }
    } else if (*check) {
      const io::Config cfg = io::load_config(check_input);
      // The settings' checks too (e.g. the active-set solver with friction), as `run` makes them.
      const auto check_model = [&]<int Dim>() {
        const auto model = build_model<Dim>(cfg);
        check_walls_enclose(cfg, model, build_settings(cfg, model));
        std::cout << fmt::format("{}: valid ({} grains, {} material points)\n", check_input,
                                 model.grains.size(), model.points.size());
      };
      if (cfg.simulation.dimension == 3)
        check_model.operator()<3>();
      else
        check_model.operator()<2>();
    } else if (*pack) {
      setup_logging(pack_quiet ? Verbosity::kQuiet : Verbosity::kNormal);
      return packing::pack_command(pack_input, pack_quiet, pack_overwrite);
    } else if (*analyze) {
      analyze_opt.plots = !analyze_no_plots;
      return analyze_command(analyze_opt);
    } else if (*list) {
      if (list_what == "input")
        std::cout << io::input_reference_markdown();
      else
        print_laws();
    }
  } catch (const InputError& e) {
    // Input and numerical errors are met by every rank in the same step (the input is read and
    // the step verdict reduced on all of them): rank 0 reports, every rank returns the code.
    if (rank0) std::cerr << "mpmcd: input error: " << e.what() << "\n";
    return static_cast<int>(ExitCode::kInput);
  } catch (const NumericalError& e) {
    if (rank0) std::cerr << "mpmcd: the simulation cannot go on: " << e.what() << "\n";
    return static_cast<int>(ExitCode::kNumerical);
  } catch (const std::exception& e) {
    // Possibly this rank's alone (a file it cannot write, memory): the others would wait in the
    // next collective, so the whole job ends here.
    const bool many = comm && comm->size() > 1;
    std::cerr << (many ? fmt::format("mpmcd (rank {}): error: ", comm->rank())
                       : std::string("mpmcd: error: "))
              << e.what() << "\n";
    if (many) comm->abort(static_cast<int>(ExitCode::kRuntime));
    return static_cast<int>(ExitCode::kRuntime);
  }
  return 0;
}

}  // namespace mpmcd::app
