#pragma once
/// `mpmcd analyze`: the compaction analysis of one or more run folders (docs/observables.md,
/// "Analysis"): Φ_J detection, fit of paper eq. (10), data and plots of the paper's Figures 4-5.
#include <string>
#include <vector>

#include "mpmcd/analysis/compaction_fit.hpp"

namespace mpmcd::app {

/// Command-line options of `mpmcd analyze`.
struct AnalyzeOptions {
  std::vector<std::string> folders;    ///< run output folders (each with input.toml and <name>.csv)
  std::string output_dir;              ///< where to write; "" = <folder>/analysis for one run,
                                       ///< ./compaction_analysis for several
  analysis::JammingCriterion jamming;  ///< Φ_J detection
  bool plots = true;                   ///< run tools/plot_compaction.py for the PNGs
  bool overwrite = false;  ///< replace an earlier analysis in output_dir (else refused) [-]
  /// Solid fractions at which the force and grain-pressure distributions are taken (runs with
  /// `[output] grains`: the snapshot whose CSV row has the nearest Φ) [-].
  std::vector<double> distribution_phi;
};

/// Analyses the runs, prints the fits and writes compaction_fit.csv, figure4.csv, figure5.csv
/// (and figure4.png, figure5.png when python3 with matplotlib is found), pressure_law.csv and
/// phi_pressure.csv (the pressure law Φ(P) fitted beyond Φ_J), and for runs with grain-scale
/// outputs fabric.csv and, at `distribution_phi`, force_distribution.csv and
/// pressure_distribution.csv (docs/observables.md). Throws InputError for a
/// folder that is not a compaction run (exit 2), and for an output folder that already holds
/// these files unless `overwrite` (then removed first). Returns the exit code (0).
int analyze_command(const AnalyzeOptions& options);

}  // namespace mpmcd::app
