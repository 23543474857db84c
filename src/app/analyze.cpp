#include "mpmcd/app/analyze.hpp"

#include <fmt/format.h>
#include <toml++/toml.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <limits>
#include <set>

#include "mpmcd/analysis/grains.hpp"
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
  std::string name;  // run name: <name>.csv and the grain files
  double lambda = 0, mu = 0;
  analysis::GrainModuli moduli;
  analysis::TimeSeries csv;
  std::optional<std::size_t> jam;  // first jammed row
  std::optional<analysis::CompactionFit> fit;
  std::vector<std::size_t> fitted;  // rows fitted
  double identity_error = 0;        // max |ln(Vs/Vs0) - ln(Φ/Φ0) - ε| (paper eq. (9))
  std::vector<double> pressure;     // P = -tr(σ̄)/Dim of the Love-Weber stress per row [Pa]
  std::optional<analysis::PressureLawFit> law;  // Φ(P) beyond jamming
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
  run.moduli = analysis::grain_moduli(
      run.lambda, run.mu, static_cast<int>(root["simulation"]["dimension"].value_or(2)));
}

/// The mean pressure -tr(σ)/Dim [Pa] per row of the stress columns <prefix>xx, <prefix>yy and, in
/// a 3D run's CSV, <prefix>zz.
std::vector<double> mean_pressure(const analysis::TimeSeries& csv, const std::string& prefix) {
  const bool three_d = csv.has(prefix + "zz");
  std::vector<const std::vector<double>*> diagonal{&csv.column(prefix + "xx"),
                                                   &csv.column(prefix + "yy")};
  if (three_d) diagonal.push_back(&csv.column(prefix + "zz"));
  std::vector<double> p(csv.rows());
  for (std::size_t i = 0; i < p.size(); ++i) {
    double trace = 0;
    for (const auto* c : diagonal) trace += (*c)[i];
    p[i] = -trace / static_cast<double>(diagonal.size()) + 0.0;  // + 0: no -0
  }
  return p;
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
  // The pressure law Φ(P) on the same rows, P the mean pressure of the Love-Weber stress.
  if (!run.csv.has("lw_sxx") || !run.csv.has("lw_syy")) return;
  run.pressure = mean_pressure(run.csv, "lw_s");
  std::vector<double> pp;
  for (const std::size_t i : run.fitted) pp.push_back(run.pressure[i]);
  try {
    run.law = analysis::fit_pressure_law(pp, fp, phi_j);
  } catch (const std::invalid_argument& e) {
    std::cout << fmt::format("  pressure-law fit failed: {}\n", e.what());
  }
}

std::string num(double v) {
  return std::isfinite(v) ? fmt::format("{:.12g}", v) : "";
}

// The grain-scale snapshot files of a run, in snapshot order: (grains CSV, forces CSV, time).
struct Snapshot {
  fs::path grains, forces;
  double time = 0;
};

std::vector<Snapshot> grain_snapshots(const Run& run) {
  std::vector<Snapshot> out;
  for (int k = 0;; ++k) {
    Snapshot s;
    s.grains = fs::path(run.folder) / fmt::format("{}_grains_{:06d}.csv", run.name, k);
    s.forces = fs::path(run.folder) / fmt::format("{}_forces_{:06d}.csv", run.name, k);
    if (!fs::is_regular_file(s.grains)) break;
    const auto g = analysis::read_time_series(s.grains.string());
    if (g.rows() == 0) continue;
    s.time = g.column("time").front();
    out.push_back(s);
  }
  return out;
}

// Histogram rows "run,phi_target,phi,time,mean,bin_lo,bin_hi,count,density" of values / mean.
std::string distribution_rows(std::size_t r, double target, double phi, double time,
                              const std::vector<double>& values) {
  double mean = 0;
  for (const double v : values) mean += v / static_cast<double>(values.size());
  std::vector<double> ratio;
  for (const double v : values) ratio.push_back(v / mean);
  // f/<f> and P/<P> on [0, 4] in bins of 0.2 (docs/observables.md)
  const auto h = analysis::histogram(ratio, 20, 0.0, 4.0);
  std::string out;
  for (std::size_t b = 0; b < h.counts.size(); ++b)
    out += fmt::format("{},{:.6g},{:.12g},{:.12g},{:.12g},{:.6g},{:.6g},{},{:.12g}\n", r, target,
                       phi, time, mean, h.edges[b], h.edges[b + 1], h.counts[b], h.density[b]);
  return out;
}

// The fabric time series and the distributions at the solid fractions `targets` of a run with
// grain-scale outputs; appends to the three CSV texts.
void grain_analysis(const Run& run, std::size_t r, const std::vector<double>& targets,
                    std::string& fabric, std::string& forces, std::string& pressures) {
  if (!run.csv.has("fabric_a")) return;
  const auto& phi = run.csv.column("phi");
  const auto& time = run.csv.column("time");
  const auto& z = run.csv.column("Z");
  const auto& a = run.csv.column("fabric_a");
  // A 3D run has no fabric angle (docs/observables.md): its column is left empty.
  const std::vector<double>* angle =
      run.csv.has("fabric_angle") ? &run.csv.column("fabric_angle") : nullptr;
  const auto& nc = run.csv.column("fabric_contacts");
  const std::vector<double> grain_p = mean_pressure(run.csv, "grain_s");
  const std::vector<double> contact_p = mean_pressure(run.csv, "contact_s");
  for (std::size_t i = 0; i < phi.size(); ++i)
    fabric += fmt::format("{},{},{},{},{},{},{},{},{}\n", r, num(time[i]), num(phi[i]), num(z[i]),
                          num(a[i]), angle ? num((*angle)[i]) : std::string(), num(nc[i]),
                          num(grain_p[i]), num(contact_p[i]));
  if (targets.empty()) return;
  const auto snaps = grain_snapshots(run);
  if (snaps.empty()) {
    std::cout << "  no grain snapshots (<name>_grains_<n>.csv): no distributions\n";
    return;
  }
  const auto row_at = [&](double t) {  // the CSV row nearest in time
    std::size_t best = 0;
    for (std::size_t i = 0; i < time.size(); ++i)
      if (std::fabs(time[i] - t) < std::fabs(time[best] - t)) best = i;
    return best;
  };
  for (const double target : targets) {
    std::size_t pick = 0;
    for (std::size_t k = 0; k < snaps.size(); ++k)
      if (std::fabs(phi[row_at(snaps[k].time)] - target) <
          std::fabs(phi[row_at(snaps[pick].time)] - target))
        pick = k;
    const Snapshot& s = snaps[pick];
    const double at = phi[row_at(s.time)];
    std::vector<double> fn, pg;
    if (fs::is_regular_file(s.forces)) {
      const auto f = analysis::read_time_series(s.forces.string());
      for (std::size_t c = 0; c < f.rows(); ++c)
        if (f.column("a")[c] >= 0) fn.push_back(f.column("fn")[c]);  // grain-grain pairs
    }
    const auto g = analysis::read_time_series(s.grains.string());
    for (std::size_t k = 0; k < g.rows(); ++k)
      if (g.column("rattler")[k] == 0) pg.push_back(g.column("pressure")[k]);
    std::cout << fmt::format(
        "  distributions at Phi = {:.4f} (asked {:.4f}, t = {:.6g} s): {} grain contacts, {} "
        "grains without rattlers\n",
        at, target, s.time, fn.size(), pg.size());
    if (!fn.empty()) forces += distribution_rows(r, target, at, s.time, fn);
    if (!pg.empty()) pressures += distribution_rows(r, target, at, s.time, pg);
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

}  // namespace

int analyze_command(const AnalyzeOptions& opt) {
  if (opt.folders.empty()) throw InputError("analyze: give at least one run folder");
  std::vector<Run> runs;
  for (const auto& folder : opt.folders) {
    Run run;
    run.folder = folder;
    read_input_copy(run, run.name);
    run.csv = analysis::read_time_series((fs::path(folder) / (run.name + ".csv")).string());
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
                     for (const char* own :
                          {"compaction_fit.csv", "figure4.csv", "figure5.csv", "figure4.png",
                           "figure5.png", "figure4.pdf", "figure5.pdf", "pressure_law.csv",
                           "phi_pressure.csv", "fabric.csv", "force_distribution.csv",
                           "pressure_distribution.csv", "pressure_law.png", "pressure_law.pdf",
                           "fabric.png", "fabric.pdf", "distributions.png", "distributions.pdf"})
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
  std::string law_csv = "run,phi_J,points,phi_max,phi_max_error,P0,P0_error,rms,determined\n";
  std::string phi_p = "run,time,pressure,phi,model,fitted\n";
  std::string fabric_csv =
      "run,time,phi,Z,fabric_a,fabric_angle,fabric_contacts,grain_pressure,contact_pressure\n";
  const std::string dist_header = "run,phi_target,phi,time,mean,bin_lo,bin_hi,count,density\n";
  std::string force_csv = dist_header, pressure_csv = dist_header;
  bool grains = false;
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
    if (run.law)
      std::cout << fmt::format(
          "  pressure law Phi = Phi_max - (Phi_max - Phi_J) exp(-P/P0): Phi_max = {:.6g} +/- "
          "{:.2g}, P0 = {:.6g} +/- {:.2g} Pa, {} points, RMS residual {:.3g} (of Phi){}\n",
          run.law->phi_max, run.law->phi_max_error, run.law->p0, run.law->p0_error, run.law->points,
          run.law->rms,
          run.law->determined ? ""
                              : "; NOT determined: the data do not approach a maximum in (Phi_J, "
                                "1] (P0 at the end of the scan or Phi_max out of range)");
    if (run.law)
      law_csv +=
          fmt::format("{},{},{},{},{},{},{},{},{}\n", r, num(phi[*run.jam]), run.law->points,
                      num(run.law->phi_max), num(run.law->phi_max_error), num(run.law->p0),
                      num(run.law->p0_error), num(run.law->rms), run.law->determined ? 1 : 0);
    for (std::size_t i = 0; i < run.pressure.size(); ++i) {
      const bool beyond = run.law && run.jam && i >= *run.jam;
      const double m = beyond ? analysis::pressure_law(run.pressure[i], phi[*run.jam],
                                                       run.law->phi_max, run.law->p0)
                              : nan;
      const bool fitted = beyond && phi[i] > phi[*run.jam];
      phi_p += fmt::format("{},{},{},{},{},{}\n", r, num(time[i]), num(run.pressure[i]),
                           num(phi[i]), num(m), fitted ? 1 : 0);
    }
    grains = grains || run.csv.has("fabric_a");
    grain_analysis(run, r, opt.distribution_phi, fabric_csv, force_csv, pressure_csv);
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
  io::write_file_atomic((fs::path(out_dir) / "pressure_law.csv").string(), law_csv);
  io::write_file_atomic((fs::path(out_dir) / "phi_pressure.csv").string(), phi_p);
  std::cout << fmt::format(
      "wrote {}/compaction_fit.csv, figure4.csv, figure5.csv, pressure_law.csv, phi_pressure.csv\n",
      out_dir);
  if (grains) {
    io::write_file_atomic((fs::path(out_dir) / "fabric.csv").string(), fabric_csv);
    std::cout << fmt::format("wrote {}/fabric.csv\n", out_dir);
    if (!opt.distribution_phi.empty()) {
      io::write_file_atomic((fs::path(out_dir) / "force_distribution.csv").string(), force_csv);
      io::write_file_atomic((fs::path(out_dir) / "pressure_distribution.csv").string(),
                            pressure_csv);
      std::cout << fmt::format("wrote {}/force_distribution.csv, pressure_distribution.csv\n",
                               out_dir);
    }
  }

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
    std::cout << fmt::format("wrote {}/figure4.png, figure5.png and .pdf\n", out_dir);
  // tools/plot_grains.py, next to plot_compaction.py: the pressure law, the fabric and the
  // distributions (PNG and PDF).
  const fs::path grains_script = fs::path(script).parent_path() / "plot_grains.py";
  if (!fs::is_regular_file(grains_script)) return 0;
  const std::string gcmd =
      python + " " + shell_quote(grains_script.string()) + " " + shell_quote(out_dir);
  if (std::system(gcmd.c_str()) != 0)
    std::cout << "grain plots not written: " << gcmd << " failed\n";
  else
    std::cout << fmt::format("wrote {}/{}.png and .pdf\n", out_dir,
                             grains ? "pressure_law, fabric, distributions" : "pressure_law");
  return 0;
}

}  // namespace mpmcd::app
