#include "mpmcd/app/analyze.hpp"

#include <fmt/format.h>
#include <toml++/toml.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <limits>
#include <set>

#include "mpmcd/analysis/time_series.hpp"
#include "mpmcd/core/errors.hpp"
#include "mpmcd/io/output_folder.hpp"
#include "mpmcd/io/vtu.hpp"

#ifndef MPMCD_TOOLS_DIR
#define MPMCD_TOOLS_DIR ""
#endif

namespace mpmcd::app {

namespace fs = std::filesystem;

namespace {

/// One run folder: its name, moduli, time series and analysis.
struct Run {
  std::string folder;
  double lambda = 0, mu = 0;
  analysis::GrainModuli moduli;
  analysis::TimeSeries csv;
  std::optional<std::size_t> jam;  // first jammed row
  std::optional<analysis::CompactionFit> fit;
  std::vector<std::size_t> fitted;  // rows fitted
  double identity_error = 0;        // max |ln(Vs/Vs0) - ln(Φ/Φ0) - ε| (paper eq. (9))
};

/// The run's name and the (λ, μ) of its grains from the input copy `input.toml`.
void read_input_copy(Run& run, std::string& name) {
  const fs::path input = fs::path(run.folder) / "input.toml";
  std::error_code ec;
  if (!fs::is_directory(run.folder, ec))
    throw InputError(run.folder, 0, "", "not a folder (expected the output folder of a run)");
  if (!fs::is_regular_file(input, ec))
    throw InputError(input.string(), 0, "",
                     "no input copy: expected the output folder of `mpmcd run`");
  toml::table root;
  try {
    root = toml::parse_file(input.string());
  } catch (const toml::parse_error& e) {
    throw InputError(input.string(), static_cast<std::int64_t>(e.source().begin.line), "",
                     fmt::format("TOML syntax error: {}", e.description()));
  }
  name = root["simulation"]["name"].value_or(std::string("mpmcd"));
  std::set<std::pair<double, double>> used;
  const toml::array* grains = root["grains"].as_array();
  const toml::array* materials = root["materials"].as_array();
  if (grains && materials)
    for (const auto& g : *grains) {
      const auto material = g.as_table() ? (*g.as_table())["material"].value<std::string>()
                                         : std::optional<std::string>();
      for (const auto& m : *materials) {
        const toml::table* t = m.as_table();
        if (!t || !material || (*t)["name"].value<std::string>() != material) continue;
        const auto l = (*t)["lambda"].value<double>(), u = (*t)["mu"].value<double>();
        if (!l || !u)
          throw InputError(input.string(), 0, "materials.lambda",
                           "the grains' material has no lambda and mu: M_p = lambda + 2 mu is "
                           "needed for eq. (10)");
        used.insert({*l, *u});
      }
    }
  if (used.size() != 1)
    throw InputError(input.string(), 0, "materials",
                     used.empty() ? "no grain material with lambda and mu found"
                                  : "the grains have several (lambda, mu): M_p is ambiguous");
  run.lambda = used.begin()->first;
  run.mu = used.begin()->second;
  run.moduli = analysis::grain_moduli(run.lambda, run.mu);
}

void analyse(Run& run, const analysis::JammingCriterion& criterion) {
  const auto& phi = run.csv.column("phi");
  const auto& eps = run.csv.column("eps");
  const auto& lnvs = run.csv.column("ln_Vs_Vs0");
  const auto& y = run.csv.column("sigma_bottom_over_Mp");
  const auto& z = run.csv.column("Z");
  if (run.csv.rows() == 0) throw InputError(run.csv.path, 0, "", "no data rows");
  for (std::size_t i = 0; i < phi.size(); ++i)
    run.identity_error = std::max(
        run.identity_error, std::fabs(lnvs[i] - std::log(phi[i] / phi[0]) - eps[i]));  // eq. (9)
  run.jam = analysis::detect_jamming(phi, y, z, criterion);
  if (!run.jam) return;
  const double phi_j = phi[*run.jam];
  std::vector<double> fp, fz, fy;
  for (std::size_t i = *run.jam; i < phi.size(); ++i)
    if (phi[i] > phi_j) {  // only Φ > Φ_J
      run.fitted.push_back(i);
      fp.push_back(phi[i]);
      fz.push_back(z[i]);
      fy.push_back(y[i]);
    }
  if (fp.size() < 3) return;
  try {
    run.fit = analysis::fit_compaction_law(fp, fz, fy, run.moduli);
  } catch (const std::invalid_argument& e) {
    std::cout << fmt::format("  fit failed: {}\n", e.what());
  }
}

std::string shell_quote(const std::string& s) {
  std::string out = "'";
  for (char c : s) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

/// tools/plot_compaction.py: $MPMCD_TOOLS_DIR, next to the binary (tools/ or ../../tools for
/// build/<preset>/mpmcd), then the source tree the binary was built from.
std::string find_plot_script() {
  std::vector<fs::path> dirs;
  if (const char* env = std::getenv("MPMCD_TOOLS_DIR")) dirs.emplace_back(env);
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (!ec) {
    dirs.push_back(exe.parent_path() / "tools");
    dirs.push_back(exe.parent_path() / ".." / ".." / "tools");
    dirs.push_back(exe.parent_path() / ".." / "share" / "mpmcd" / "tools");
  }
  dirs.emplace_back(MPMCD_TOOLS_DIR);
  for (const auto& d : dirs) {
    const fs::path p = d / "plot_compaction.py";
    if (!d.empty() && fs::is_regular_file(p, ec)) return p.lexically_normal().string();
  }
  return "";
}

std::string num(double v) {
  return std::isfinite(v) ? fmt::format("{:.12g}", v) : "";
}

}  // namespace

int analyze_command(const AnalyzeOptions& opt) {
  if (opt.folders.empty()) throw InputError("analyze: give at least one run folder");
  std::vector<Run> runs;
  for (const auto& folder : opt.folders) {
    Run run;
    run.folder = folder;
    std::string name;
    read_input_copy(run, name);
    run.csv = analysis::read_time_series((fs::path(folder) / (name + ".csv")).string());
    analyse(run, opt.jamming);
    runs.push_back(std::move(run));
  }

  std::string out_dir = opt.output_dir;
  if (out_dir.empty())
    out_dir = runs.size() == 1 ? (fs::path(runs[0].folder) / "analysis").string()
                               : std::string("compaction_analysis");
  // One folder, one analysis (docs/robustness.md, "Output folders"): an earlier one is refused
  // unless --overwrite, which removes its files (with the PNGs a --no-plots run would not replace).
  io::claim_output_folder(
      out_dir,
      io::files_in(out_dir,
                   [](const std::string& f) {
                     for (const char* own : {"compaction_fit.csv", "figure4.csv", "figure5.csv",
                                             "figure4.png", "figure5.png"})
                       if (f == own || f == std::string(own) + ".tmp") return true;
                     return false;
                   }),
      opt.overwrite, "analysis", opt.folders.front(),
      opt.output_dir.empty() ? "analysis folder" : "-o");
  fs::create_directories(out_dir);

  std::string fit_csv =
      "run,folder,lambda,mu,Mp,Kp,rows,phi0,phi_J,jam_row,points,c1,c1_error,c2,c2_error,"
      "correlation,rms,converged,identity_error\n";
  std::string fig4 = "run,lambda,time,phi,eps,ln_Vs_Vs0\n";
  std::string fig5 = "run,lambda,phi,Z,sigma_over_Mp,model,fitted\n";
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (std::size_t r = 0; r < runs.size(); ++r) {
    const Run& run = runs[r];
    const auto& phi = run.csv.column("phi");
    const auto& time = run.csv.column("time");
    const auto& eps = run.csv.column("eps");
    const auto& lnvs = run.csv.column("ln_Vs_Vs0");
    const auto& y = run.csv.column("sigma_bottom_over_Mp");
    const auto& z = run.csv.column("Z");
    std::cout << fmt::format(
        "{}: lambda = {:g} MPa, mu = {:g} MPa (M_p = {:g} MPa, K_p = {:g} MPa), {} rows, Phi "
        "{:.4f} -> {:.4f}, eq. (9) identity error {:.2e}\n",
        run.folder, run.lambda / 1e6, run.mu / 1e6, run.moduli.mp / 1e6, run.moduli.kp / 1e6,
        phi.size(), phi.front(), phi.back(), run.identity_error);
    if (!run.jam)
      std::cout << fmt::format(
          "  not jammed: -sigma/M_p >= {:g}{} does not hold up to the last row; no fit\n",
          opt.jamming.stress,
          opt.jamming.min_z > 0 ? fmt::format(" with Z >= {:g}", opt.jamming.min_z) : "");
    else
      std::cout << fmt::format(
          "  jamming: Phi_J = {:.5f} (row {}, Z = {:.3f}); {} rows with "
          "Phi > Phi_J\n",
          phi[*run.jam], *run.jam, z[*run.jam], run.fitted.size());
    if (run.fit)
      std::cout << fmt::format(
          "  eq. (10) fit: c1 = {:.6g} +/- {:.2g}, c2 = {:.6g} +/- {:.2g} (correlation {:.3f}), "
          "{} points, RMS residual {:.3g} (of sigma/M_p){}\n",
          run.fit->c1, run.fit->c1_error, run.fit->c2, run.fit->c2_error, run.fit->correlation,
          run.fit->points, run.fit->rms, run.fit->converged ? "" : ", NOT converged");
    else if (run.jam)
      std::cout << "  too few points beyond jamming for a fit (3 needed)\n";
    const auto f =
        run.fit.value_or(analysis::CompactionFit{nan, nan, nan, nan, nan, nan, 0, 0, false});
    fit_csv += fmt::format("{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}\n", r,
                           fs::path(run.folder).lexically_normal().string(), num(run.lambda),
                           num(run.mu), num(run.moduli.mp), num(run.moduli.kp), phi.size(),
                           num(phi.front()), run.jam ? num(phi[*run.jam]) : "",
                           run.jam ? fmt::format("{}", *run.jam) : "", run.fitted.size(), num(f.c1),
                           num(f.c1_error), num(f.c2), num(f.c2_error), num(f.correlation),
                           num(f.rms), run.fit && f.converged ? 1 : 0, num(run.identity_error));
    for (std::size_t i = 0; i < phi.size(); ++i) {
      fig4 += fmt::format("{},{},{},{},{},{}\n", r, num(run.lambda), num(time[i]), num(phi[i]),
                          num(eps[i]), num(lnvs[i]));
      const bool beyond = run.jam && i >= *run.jam;
      const double model =
          run.fit && beyond ? analysis::compaction_law(phi[i], z[i], f.c1, f.c2, run.moduli) : nan;
      const bool fitted = run.fit && beyond && phi[i] > phi[*run.jam];
      fig5 += fmt::format("{},{},{},{},{},{},{}\n", r, num(run.lambda), num(phi[i]), num(z[i]),
                          num(y[i]), num(model), fitted ? 1 : 0);
    }
  }
  io::write_file_atomic((fs::path(out_dir) / "compaction_fit.csv").string(), fit_csv);
  io::write_file_atomic((fs::path(out_dir) / "figure4.csv").string(), fig4);
  io::write_file_atomic((fs::path(out_dir) / "figure5.csv").string(), fig5);
  std::cout << fmt::format("wrote {}/compaction_fit.csv, figure4.csv, figure5.csv\n", out_dir);

  if (!opt.plots) return 0;
  const std::string script = find_plot_script();
  if (script.empty()) {
    std::cout << "PNGs not written: tools/plot_compaction.py not found (set MPMCD_TOOLS_DIR)\n";
    return 0;
  }
  // The project's Python tools use /usr/bin/python3 (Debian's numpy and matplotlib); else PATH.
  std::string python;
  for (const char* p : {"/usr/bin/python3", "python3"})
    if (std::system((std::string(p) + " -c 'import numpy, matplotlib' >/dev/null 2>&1").c_str()) ==
        0) {
      python = p;
      break;
    }
  if (python.empty()) {
    std::cout << "PNGs not written: python3 with numpy and matplotlib not found (the CSV files "
                 "are written; plot them with "
              << script << ")\n";
    return 0;
  }
  const std::string cmd = python + " " + shell_quote(script) + " " + shell_quote(out_dir);
  if (std::system(cmd.c_str()) != 0)
    std::cout << "PNGs not written: " << cmd << " failed\n";
  else
    std::cout << fmt::format("wrote {}/figure4.png, figure5.png\n", out_dir);
  return 0;
}

}  // namespace mpmcd::app
