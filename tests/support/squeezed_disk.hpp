#pragma once
// The squeezed disk of issue 14 through `mpmcd run`, against the project's independent
// finite-element solution (tests/reference/squeezed_disk, FEniCS, mesh-converged to 0.014 %):
// a Neo-Hookean disk (R = 1 mm, mu = 1.5 MPa, rho = 990 kg/m^3, polar seeding, 2 points per cell)
// between two frictionless walls closing at 0.01 c_s each (0.389 m/s, c_s = sqrt(mu/rho)),
// CPDI + affine P2G (docs/accuracy.md, "The squeezed disk"). The plate force, averaged over
// Delta/D +- 0.01 (the impulses chatter as node rows meet the walls), is compared with the FE
// force at Delta/D = 0.05 ... 0.39, and the stored energy with the walls' work. Shared by
// tests/verification/squeeze_fe (default suite) and long_squeeze_fe (ctest --preset long).
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "cli_runner.hpp"
#include "mpmcd/analysis/time_series.hpp"
#include "scratch.hpp"
#include "vtu_reader.hpp"

namespace mpmcd::test_support::squeeze {

namespace fs = std::filesystem;

inline constexpr double kRadius = 1e-3, kMu = 1.5e6, kRho = 990.0;
inline const double kSpeed = 0.01 * std::sqrt(kMu / kRho);                       // each wall [m/s]
inline const std::vector<double> kStations = {0.05, 0.1, 0.15, 0.2, 0.3, 0.39};  // Delta/D [-]

// FE force P(Delta/D) [N/m] and contact half-width a(Delta/D) [m] for `lambda` [Pa], from
// tests/reference/squeezed_disk.
struct FeCurve {
  std::vector<double> x, force, half_width;
  // Linear interpolation of `y` (force or half_width) at Delta/D = d.
  double interp(const std::vector<double>& y, double d) const {
    const auto it = std::lower_bound(x.begin(), x.end(), d);
    const auto i = static_cast<std::size_t>(
        std::clamp<std::ptrdiff_t>(it - x.begin(), 1, static_cast<std::ptrdiff_t>(x.size()) - 1));
    return y[i - 1] + (y[i] - y[i - 1]) * (d - x[i - 1]) / (x[i] - x[i - 1]);
  }
  double at(double d) const { return interp(force, d); }
};

inline FeCurve fe_curve(double lambda) {
  std::ifstream in(std::string(MPMCD_SOURCE_DIR) +
                   "/tests/reference/squeezed_disk/squeezed_disk_fe.csv");
  FeCurve c;
  std::string line;
  bool header = true;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    if (header) {  // lambda_Pa,mu_Pa,R_m,delta_over_D,force_N_per_m,...
      header = false;
      continue;
    }
    std::stringstream ss(line);
    std::string f;
    std::vector<double> v;
    while (std::getline(ss, f, ',')) v.push_back(std::stod(f));
    if (v.size() >= 5 && v[0] == lambda) {
      c.x.push_back(v[3]);
      c.force.push_back(v[4]);
      c.half_width.push_back(v[5]);
    }
  }
  return c;
}

struct DiskRun {
  std::vector<double> ratio;  // MPM force / FE force at kStations [-]
  double stored = 0;          // elastic + kinetic change / work of both walls at the end [-]
  // Per VTU output with contacts on the top wall: Delta/D, the MPM contact half-width (half the
  // span of its active contacts, which sit on node columns, plus half a cell) and the FE
  // half-width [m].
  std::vector<std::array<double, 3>> half_width;
};

// Runs the disk at R/h = `rh` with step `dt` [s] and wall speed `speed` [m/s] to Delta/D = 0.4,
// the walls acting on the grid nodes (`wall_contact` "nodes") or on the points' faces ("points"),
// seeded with `points_per_cell`, contacts solved by `contact_solver` ([contact] solver).
inline DiskRun run_disk(int rh, double lambda, double dt, double speed,
                        const std::string& wall_contact = "nodes", int points_per_cell = 2,
                        const std::string& contact_solver = "gauss_seidel") {
  const double h = kRadius / rh, t_end = 0.4 * kRadius / speed;
  const std::string tag = fmt::format("{}_{:g}_{:g}_{:g}_{}_{}_{}", rh, lambda, dt, speed,
                                      wall_contact, points_per_cell, contact_solver);
  const fs::path dir = mpmcd::test_support::scratch_dir("squeeze_fe", tag);
  std::ofstream(dir / "disk.toml") << fmt::format(
      "[simulation]\nname = \"disk\"\n"
      "[grid]\norigin = [-2e-3, -1.5e-3]\nextent = [4e-3, 3e-3]\ncell_size = {:.17g}\n"
      "shape_function = \"cpdi\"\n"
      "[[materials]]\nname = \"gel\"\nlaw = \"neo_hookean\"\ndensity = {}\nlambda = {:.17g}\n"
      "mu = {}\n"
      "[[grains]]\nshape = \"disk\"\nmaterial = \"gel\"\ncenter = [0.0, 0.0]\nradius = {}\n"
      "points_per_cell = {}\n"
      "[time]\ndt = {:.17g}\nend_time = {:.17g}\n"
      "[solver]\naffine = true\n"
      "[contact]\nfriction = 0.0\nwall_contact = \"{}\"\nsolver = \"{}\"\n"
      "[[walls]]\nname = \"bottom\"\npoint = [0.0, {}]\nnormal = [0.0, 1.0]\n"
      "velocity = [0.0, {:.17g}]\n"
      "[[walls]]\nname = \"top\"\npoint = [0.0, {}]\nnormal = [0.0, -1.0]\n"
      "velocity = [0.0, {:.17g}]\n"
      "[output]\ncsv_interval = {:.17g}\nvtu_interval = {:.17g}\n",
      h, kRho, lambda, kMu, kRadius, points_per_cell, dt, t_end, wall_contact, contact_solver,
      -kRadius, speed, kRadius, -speed, t_end / 400, t_end / 8);
  const auto r = mpmcd::test_support::run("run -q -t 1 " + (dir / "disk.toml").string() + " -o " +
                                          (dir / "out").string());
  EXPECT_EQ(r.code, 0) << r.output;
  const auto s = mpmcd::analysis::read_time_series((dir / "out" / "disk.csv").string());
  const auto &t = s.column("time"), &top = s.column("wall_top_fy"),
             &bottom = s.column("wall_bottom_fy");
  const FeCurve fe = fe_curve(lambda);
  DiskRun out;
  for (double x : kStations) {
    double f = 0, p = 0;  // sums over the window Delta/D in (x - 0.01, x + 0.01)
    for (std::size_t i = 0; i < t.size(); ++i) {
      const double d = 2 * speed * t[i] / (2 * kRadius);  // Delta/D
      if (std::abs(d - x) >= 0.01) continue;
      f += 0.5 * (top[i] - bottom[i]);  // the grains push the top wall up, the bottom one down
      p += fe.at(d);
    }
    out.ratio.push_back(p > 0 ? f / p : 0.0);
  }
  // Contact half-width from the contacts VTU series (disk_contacts.pvd: one file per output).
  std::ifstream pvd(dir / "out" / "disk_contacts.pvd");
  const std::string series((std::istreambuf_iterator<char>(pvd)), std::istreambuf_iterator<char>());
  const std::regex entry(R"(timestep=\"([^\"]+)\"[^>]*file=\"([^\"]+)\")");
  for (auto it = std::sregex_iterator(series.begin(), series.end(), entry);
       it != std::sregex_iterator(); ++it) {
    const double d = 2 * speed * std::stod((*it)[1]) / (2 * kRadius);
    const VtuData c = read_vtu((dir / "out" / std::string((*it)[2])).string());
    double lo = 1e300, hi = -1e300;
    const auto& p = c.arrays.at("normal_impulse");
    const auto& a = c.arrays.at("body_a");
    for (std::size_t k = 0; k < p.size(); ++k)
      if (p[k] > 0 && a[k] < 0 && c.points[3 * k + 1] > 0) {  // the top wall's active contacts
        lo = std::min(lo, c.points[3 * k]);
        hi = std::max(hi, c.points[3 * k]);
      }
    // The contacts sit on node columns (spacing h): each stands for the column of width h about
    // it, so the contact zone reaches half a cell beyond the outermost active one.
    if (hi >= lo)
      out.half_width.push_back({d, 0.5 * (hi - lo) + 0.5 * h, fe.interp(fe.half_width, d)});
  }
  const double work = s.column("wall_top_work").back() + s.column("wall_bottom_work").back();
  out.stored = s.column("energy_change").back() / work;
  return out;
}

inline void print(const std::string& label, const DiskRun& r) {
  std::string line = "  " + label + ": force / FE";
  for (std::size_t k = 0; k < kStations.size(); ++k)
    line += fmt::format("  {:.2f}: {:.4f}", kStations[k], r.ratio[k]);
  line += "; contact half-width (MPM - FE) / R at Delta/D";
  for (const auto& [d, mpm, fe] : r.half_width)
    line += fmt::format("  {:.3f}: {:+.4f}", d, (mpm - fe) / kRadius);
  std::printf("%s; stored / wall work %.4f\n", line.c_str(), r.stored);
}

// The largest |MPM - FE| contact half-width over the outputs at Delta/D >= 0.05 [m].
inline double worst_half_width(const DiskRun& r) {
  double e = 0;
  for (const auto& [d, mpm, fe] : r.half_width)
    if (d >= 0.05) e = std::max(e, std::abs(mpm - fe));
  return e;
}

inline double worst(const DiskRun& r) {
  double e = 0;
  for (double q : r.ratio) e = std::max(e, std::abs(q - 1));
  return e;
}

}  // namespace mpmcd::test_support::squeeze
