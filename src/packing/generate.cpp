// The packing protocols of docs/packing.md §3-§4: random start, growth or wall compression with
// damped dynamics, relaxation (FIRE or damped dynamics), jamming search by bisection.
#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numbers>
#include <random>

#include "dem.hpp"
#include "mpmcd/core/errors.hpp"
#include "mpmcd/core/log.hpp"
#include "mpmcd/packing/packing.hpp"
#include "params_check.hpp"

namespace mpmcd::packing {

namespace detail {

std::optional<ParamProblem> check_params(const PackingParams& p) {
  const auto bad = [](std::string key, std::string what) {
    return std::optional<ParamProblem>(ParamProblem{std::move(key), std::move(what)});
  };
  const auto finite_pos = [](double v) { return std::isfinite(v) && v > 0.0; };
  if (!p.diameters.empty()) {
    if (static_cast<std::int64_t>(p.diameters.size()) > kMaxDisks)
      return bad("diameters",
                 fmt::format("at most {} diameters, got {}", kMaxDisks, p.diameters.size()));
    for (std::size_t i = 0; i < p.diameters.size(); ++i)
      if (!finite_pos(p.diameters[i]))
        return bad("diameters",
                   fmt::format("finite diameters > 0 [m], entry {} is {}", i + 1, p.diameters[i]));
    const auto [lo, hi] = std::minmax_element(p.diameters.begin(), p.diameters.end());
    if (*hi > 10.0 * *lo)
      return bad("diameters",
                 fmt::format("largest / smallest diameter <= 10, got {} / {}", *hi, *lo));
  } else {
    if (p.count < 1 || p.count > kMaxDisks)
      return bad("count", fmt::format("an integer in [1, {}], got {}", kMaxDisks, p.count));
    if (!finite_pos(p.diameter_min))
      return bad("diameter_min", fmt::format("a finite number > 0 [m], got {}", p.diameter_min));
    if (!std::isfinite(p.diameter_max) || p.diameter_max < p.diameter_min)
      return bad("diameter_max", fmt::format("a finite number >= diameter_min = {} [m], got {}",
                                             p.diameter_min, p.diameter_max));
    if (p.diameter_max > 10.0 * p.diameter_min)
      return bad("diameter_max", fmt::format("diameter_max / diameter_min <= 10, got {}",
                                             p.diameter_max / p.diameter_min));
  }
  if (p.box) {
    const auto& b = *p.box;
    for (double v : b)
      if (!std::isfinite(v)) return bad("box", "four finite numbers [m]");
    if (!(b[2] > b[0]) || !(b[3] > b[1]))
      return bad("box", fmt::format("[xmin, ymin, xmax, ymax] with xmax > xmin and ymax > ymin, "
                                    "got [{}, {}, {}, {}]",
                                    b[0], b[1], b[2], b[3]));
  } else {
    if (!std::isfinite(p.aspect_ratio) || p.aspect_ratio < 1e-3 || p.aspect_ratio > 1e3)
      return bad("aspect_ratio", fmt::format("a number in [0.001, 1000], got {}", p.aspect_ratio));
    if (!std::isfinite(p.origin[0]) || !std::isfinite(p.origin[1]))
      return bad("origin", "two finite numbers [m]");
  }
  if (p.method != PackingMethod::kJam &&
      (!std::isfinite(p.target_phi) || p.target_phi <= 0.0 || p.target_phi > 0.9))
    return bad("target_phi", fmt::format("a number in (0, 0.9], got {}", p.target_phi));
  if (!std::isfinite(p.friction) || p.friction < 0.0 || p.friction > 10.0)
    return bad("friction", fmt::format("a number in [0, 10], got {}", p.friction));
  if (p.periodic && p.method == PackingMethod::kWalls)
    return bad("boundary", "\"walls\" for method \"walls\" (a periodic cell has no walls)");
  if (p.method == PackingMethod::kJam && p.friction != 0.0)
    return bad("friction", "0 for method \"jam\" (the jamming search is frictionless)");
  const double ref_phi = p.method == PackingMethod::kJam ? p.jam_start_phi : p.target_phi;
  if (!std::isfinite(p.initial_phi) || p.initial_phi <= 0.0 || p.initial_phi >= ref_phi)
    return bad("initial_phi",
               fmt::format("a number in (0, {}) (below the {}), got {}", ref_phi,
                           p.method == PackingMethod::kJam ? "jam_start_phi" : "target_phi",
                           p.initial_phi));
  if (p.growth_steps < 0 || p.growth_steps > kMaxSteps)
    return bad("growth_steps",
               fmt::format("an integer in [0, {}], got {}", kMaxSteps, p.growth_steps));
  if (p.max_relax_steps < 1 || p.max_relax_steps > kMaxSteps)
    return bad("max_relax_steps",
               fmt::format("an integer in [1, {}], got {}", kMaxSteps, p.max_relax_steps));
  if (!std::isfinite(p.overlap_tolerance) || p.overlap_tolerance <= 0.0 ||
      p.overlap_tolerance > 0.1)
    return bad("overlap_tolerance",
               fmt::format("a number in (0, 0.1], got {}", p.overlap_tolerance));
  if (!std::isfinite(p.damping_ratio) || p.damping_ratio < 0.0 || p.damping_ratio > 10.0)
    return bad("damping_ratio", fmt::format("a number in [0, 10], got {}", p.damping_ratio));
  if (!std::isfinite(p.global_damping) || p.global_damping < 0.0 || p.global_damping > 10.0)
    return bad("global_damping", fmt::format("a number in [0, 10], got {}", p.global_damping));
  if (!std::isfinite(p.jam_start_phi) || p.jam_start_phi < 0.1 || p.jam_start_phi > 0.9)
    return bad("jam_start_phi", fmt::format("a number in [0.1, 0.9], got {}", p.jam_start_phi));
  if (!std::isfinite(p.jam_phi_tolerance) || p.jam_phi_tolerance < 1e-6 ||
      p.jam_phi_tolerance > 0.05)
    return bad("jam_phi_tolerance",
               fmt::format("a number in [1e-6, 0.05], got {}", p.jam_phi_tolerance));
  return std::nullopt;
}

}  // namespace detail

namespace {

using detail::Dem;

// Uniform double in [0, 1) (docs/packing.md eq. 0) from the 53 high bits of one mt19937_64 draw
// (portable, unlike std::uniform_real_distribution).
double uniform01(std::mt19937_64& rng) {
  return static_cast<double>(rng() >> 11) * 0x1.0p-53;
}

// Energy per disk below which a minimised state counts as unjammed [k_n d^2]. O'Hern et al.
// (Phys. Rev. E 68 (2003) 011306, §II) use 1e-16; since E/N ~ 0.2 (phi - phi_J)^2 above jamming
// (measured, docs/packing.md §3), 1e-14 shifts phi_J by < 1e-6, far below jam_phi_tolerance, and is
// reached much sooner by states just below jamming.
constexpr double kUnjammedEnergy = 1e-14;
// A minimum is found when the largest net force < this * sqrt(2 E/N), the typical contact force.
constexpr double kForceStop = 1e-6;

// Frictional relaxation with damped dynamics: until overlaps < tol and kinetic energy per disk
// < 1e-14 (§4). Returns true when both held.
bool relax_damped(Dem& dem, std::int64_t max_steps, double tol) {
  const double dt = dem.time_step();
  const double nd = static_cast<double>(dem.size());
  for (std::int64_t k = 0; k < max_steps; ++k) {
    dem.md_step(dt);
    if (dem.max_overlap() < tol && dem.kinetic_energy() / nd < 1e-14) return true;
  }
  return false;
}

}  // namespace

Packing generate_packing(const PackingParams& params) {
  PackingReport report;
  return generate_packing(params, report);
}

Packing generate_packing(const PackingParams& p, PackingReport& report) {
  if (auto problem = detail::check_params(p))
    throw InputError("", 0, "packing." + problem->key, problem->expectation);
  const auto t_start = std::chrono::steady_clock::now();
  std::mt19937_64 rng(p.seed);
  report = PackingReport{};

  // Requested diameters [m]: explicit list or uniform in [d_min, d_max] (§1).
  std::vector<double> d = p.diameters;
  if (d.empty()) {
    d.resize(static_cast<std::size_t>(p.count));
    for (double& di : d) di = p.diameter_min + (p.diameter_max - p.diameter_min) * uniform01(rng);
  }
  const std::size_t n = d.size();
  double disk_area = 0.0;
  for (double di : d) disk_area += std::numbers::pi * 0.25 * di * di;

  // Reference state (scale 1): the packing fraction phi_ref in the final box (§3, eq. 8).
  const bool jam = p.method == PackingMethod::kJam;
  const double phi_ref = jam ? p.jam_start_phi : p.target_phi;
  double width = 0.0, height = 0.0, x0 = 0.0, y0 = 0.0, c = 1.0;
  if (p.box) {
    x0 = (*p.box)[0];
    y0 = (*p.box)[1];
    width = (*p.box)[2] - x0;
    height = (*p.box)[3] - y0;
    c = std::sqrt(phi_ref * width * height / disk_area);
    for (double& di : d) di *= c;
  } else {
    const double area = disk_area / phi_ref;
    width = std::sqrt(area * p.aspect_ratio);
    height = std::sqrt(area / p.aspect_ratio);
    x0 = p.origin[0];
    y0 = p.origin[1];
  }
  double dbar = 0.0;
  for (double di : d) dbar += di;
  dbar /= static_cast<double>(n);
  const double dmax = *std::max_element(d.begin(), d.end());
  // A wall box must hold the largest disk; a periodic cell must be 3 of them wide so that each
  // pair interacts through one image only.
  const double fit = p.periodic ? 3.0 : 1.0;
  if (fit * dmax >= std::min(width, height))
    throw InputError("", 0, p.box ? "packing.box" : "packing.count",
                     fmt::format("a box wider than {} largest disk{}: diameter {:.6g} m, box "
                                 "{:.6g} x {:.6g} m",
                                 p.periodic ? "3 times the" : "the", p.periodic ? "s" : "", dmax,
                                 width, height));

  // Reduced units (§2): length d_mean.
  const double wr = width / dbar, hr = height / dbar;
  std::vector<double> r0(n), x(n), y(n);
  for (std::size_t i = 0; i < n; ++i) r0[i] = 0.5 * d[i] / dbar;
  const double phi0 = p.initial_phi;
  const double s0 = std::sqrt(phi0 / phi_ref);  // radius scale at the start (grow, jam)
  const double g0 = std::sqrt(phi_ref / phi0);  // box scale at the start (walls)
  const bool walls = p.method == PackingMethod::kWalls;
  const double bw = walls ? g0 * wr : wr, bh = walls ? g0 * hr : hr;
  const double bx = 0.5 * (wr - bw), by = 0.5 * (hr - bh);
  const double rs = walls ? 1.0 : s0;
  for (std::size_t i = 0; i < n; ++i) {
    // Random centers keeping each (start-size) disk inside the walls.
    const double ri = p.periodic ? 0.0 : std::min(rs * r0[i], 0.5 * std::min(bw, bh));
    x[i] = bx + ri + (bw - 2.0 * ri) * uniform01(rng);
    y[i] = by + ri + (bh - 2.0 * ri) * uniform01(rng);
  }
  detail::DemSettings settings;
  settings.law = p.contact_law;
  settings.friction = p.friction;
  settings.damping_ratio = p.damping_ratio;
  settings.global_damping = p.global_damping;
  settings.periodic = p.periodic;
  Dem dem(std::move(x), std::move(y), std::move(r0), {bx, by, bx + bw, by + bh}, settings);
  dem.set_scale(rs);

  // Growth or wall compression with damped dynamics: phi rises linearly from phi0 to phi_ref
  // in growth_steps steps (eq. 9 and 10).
  const double dt = dem.time_step();
  const auto g_steps = p.growth_steps;
  std::array<double, 4> box_prev = dem.box();
  for (std::int64_t k = 1; k <= g_steps; ++k) {
    const double phi =
        phi0 + (phi_ref - phi0) * static_cast<double>(k) / static_cast<double>(g_steps);
    if (walls) {
      const double g = std::sqrt(phi_ref / phi);
      const std::array<double, 4> b{0.5 * wr * (1.0 - g), 0.5 * hr * (1.0 - g),
                                    0.5 * wr * (1.0 + g), 0.5 * hr * (1.0 + g)};
      dem.set_box(b);
      dem.set_wall_velocity({(b[0] - box_prev[0]) / dt, (b[1] - box_prev[1]) / dt,
                             (b[2] - box_prev[2]) / dt, (b[3] - box_prev[3]) / dt});
      box_prev = b;
    } else {
      dem.set_scale(std::sqrt(phi / phi_ref));
    }
    dem.md_step(dt);
  }
  dem.set_wall_velocity({0.0, 0.0, 0.0, 0.0});
  dem.set_box({0.0, 0.0, wr, hr});
  dem.set_scale(1.0);
  log().info("packing: {} disks, {} to phi = {:.4f} in {} steps", n,
             walls ? "wall compression" : "growth", phi_ref, g_steps);

  // Relaxation at the reference state (§4).
  const double tol = p.overlap_tolerance;
  double scale = 1.0;
  if (p.friction > 0.0) {
    report.relaxed = relax_damped(dem, p.max_relax_steps, tol);
  } else {
    const auto res = jam ? dem.minimize(p.max_relax_steps, 0.0, kUnjammedEnergy, kForceStop)
                         : dem.minimize(p.max_relax_steps, tol, 0.0, 0.0);
    report.relaxed = dem.max_overlap() < tol;
    log().debug("packing: FIRE relaxation {} steps, max overlap {:.3g} d", res.steps,
                dem.max_overlap());
  }

  if (jam) {
    // Quasi-static jamming search (§4, O'Hern et al. 2003): affine compression steps of the
    // radii, each followed by a FIRE minimisation; a state is jammed when its minimised energy
    // per disk exceeds kUnjammedEnergy. Bisection between the densest unjammed and the loosest
    // jammed state until their gap < jam_phi_tolerance.
    std::vector<double> lo_x, lo_y, hi_x, hi_y;
    double phi_lo = -1.0, phi_hi = -1.0, phi = phi_ref, step = 0.005;
    bool jammed = dem.energy() / static_cast<double>(n) > kUnjammedEnergy;
    bool from_lo = false;     // the last trial started from the densest unjammed state
    bool hi_from_lo = false;  // the loosest jammed state was compressed from that state
    for (int iter = 0; iter < 400; ++iter) {
      if (jammed) {
        phi_hi = phi;
        dem.get_positions(hi_x, hi_y);
        hi_from_lo = from_lo;
      } else {
        phi_lo = phi;
        dem.get_positions(lo_x, lo_y);
        hi_from_lo = false;
      }
      if (phi_lo > 0.0 && phi_hi > 0.0 && phi_hi - phi_lo < p.jam_phi_tolerance) {
        if (hi_from_lo) break;
        // Otherwise the jammed state came from an older, coarser path: compress the densest
        // unjammed state to phi_hi (below); if that is unjammed, go on from it in half-tolerance
        // steps.
      }
      if (phi_hi < 0.0)
        phi = std::min(phi_lo > 0.0 ? phi_lo + step : phi + step, 0.91);
      else if (phi_lo < 0.0)
        phi = std::max(phi - step, 0.05);
      else if (phi_hi - phi_lo >= p.jam_phi_tolerance)
        phi = 0.5 * (phi_lo + phi_hi);
      else
        phi = phi_hi;
      from_lo = phi_lo > 0.0;
      if (from_lo)
        dem.set_positions(lo_x, lo_y);
      else
        dem.set_positions(hi_x, hi_y);
      dem.set_scale(std::sqrt(phi / phi_ref));
      const auto res = dem.minimize(p.max_relax_steps, 0.0, kUnjammedEnergy, kForceStop);
      jammed = res.energy_per_disk > kUnjammedEnergy;
      if (!jammed && phi >= phi_hi && phi_hi > 0.0) {
        // phi_hi was jammed along another path but not from here: search above again.
        phi_hi = -1.0;
        step = 0.5 * p.jam_phi_tolerance;
      }
      log().debug("packing: jam search phi = {:.6f}: {} (E/N = {:.3g}, |F| = {:.3g}, {} steps)",
                  phi, jammed ? "jammed" : "unjammed", res.energy_per_disk, res.max_force,
                  res.steps);
      if (phi >= 0.91 || phi <= 0.05) break;
    }
    report.relaxed = phi_lo > 0.0 && phi_hi > 0.0 && hi_from_lo;
    if (phi_hi > 0.0) {
      dem.set_positions(hi_x, hi_y);
      dem.set_scale(std::sqrt(phi_hi / phi_ref));
      dem.update_forces(false);
      report.jamming_phi = report.relaxed ? 0.5 * (phi_lo + phi_hi) : phi_hi;
    }
    scale = dem.scale();
  }

  // Back to metres (§3): with a given box the box stays and the radii carry the scale; without,
  // the diameters stay as requested and the box follows.
  const double len = p.box ? dbar : dbar / scale;
  dem.wrap();
  Packing out;
  out.seed = p.seed;
  out.periodic = p.periodic;
  out.xmin = x0;
  out.ymin = y0;
  out.xmax = p.box ? (*p.box)[2] : x0 + wr * len;
  out.ymax = p.box ? (*p.box)[3] : y0 + hr * len;
  out.disks.resize(n);
  for (std::size_t i = 0; i < n; ++i)
    out.disks[i] = Disk{static_cast<std::int64_t>(i), x0 + dem.x()[i] * len, y0 + dem.y()[i] * len,
                        dem.r()[i] * len};
  report.phi = packing_fraction(out);
  report.mean_diameter = mean_diameter(out);
  report.max_overlap = max_overlap(out) / report.mean_diameter;
  report.diameter_scale = p.box ? c * scale : 1.0;
  report.steps = dem.steps();
  report.wall_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
  if (!report.relaxed && !jam)
    log().warn(
        "packing: not relaxed after {} steps: largest overlap {:.3g} d_mean > tolerance {:.3g} "
        "(phi = {:.4f} may be above jamming)",
        p.max_relax_steps, report.max_overlap, tol, report.phi);
  return out;
}

double packing_fraction(const Packing& packing) {
  double area = 0.0;
  for (const auto& disk : packing.disks) area += std::numbers::pi * disk.radius * disk.radius;
  const double box = (packing.xmax - packing.xmin) * (packing.ymax - packing.ymin);
  return box > 0.0 ? area / box : 0.0;
}

double mean_diameter(const Packing& packing) {
  if (packing.disks.empty()) return 0.0;
  double sum = 0.0;
  for (const auto& disk : packing.disks) sum += 2.0 * disk.radius;
  return sum / static_cast<double>(packing.disks.size());
}

double max_overlap(const Packing& packing) {
  const double dbar = mean_diameter(packing);
  if (!(dbar > 0.0)) return 0.0;
  const std::size_t n = packing.disks.size();
  std::vector<double> x(n), y(n), r(n);
  for (std::size_t i = 0; i < n; ++i) {
    x[i] = (packing.disks[i].x - packing.xmin) / dbar;
    y[i] = (packing.disks[i].y - packing.ymin) / dbar;
    r[i] = packing.disks[i].radius / dbar;
  }
  detail::DemSettings settings;
  settings.periodic = packing.periodic;
  Dem dem(std::move(x), std::move(y), std::move(r),
          {0.0, 0.0, (packing.xmax - packing.xmin) / dbar, (packing.ymax - packing.ymin) / dbar},
          settings);
  dem.update_forces(false);
  return dem.max_overlap() * dbar;
}

std::string summary_line(const Packing& packing) {
  const double dbar = mean_diameter(packing);
  return fmt::format(
      "packing: {} grains, phi = {:.6f}, max overlap = {:.3e} d_mean (d_mean = {:.6g} m, {} = "
      "[{:.6g}, {:.6g}] x [{:.6g}, {:.6g}] m)",
      packing.disks.size(), packing_fraction(packing),
      dbar > 0.0 ? max_overlap(packing) / dbar : 0.0, dbar,
      packing.periodic ? "periodic cell" : "box", packing.xmin, packing.xmax, packing.ymin,
      packing.ymax);
}

}  // namespace mpmcd::packing
