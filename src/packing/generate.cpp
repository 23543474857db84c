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
  if (p.dimension != 2 && p.dimension != 3)
    return bad("dimension", fmt::format("2 (disks) or 3 (spheres), got {}", p.dimension));
  const bool three = p.dimension == 3;
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
    const auto& z = p.box_z;
    for (double v : b)
      if (!std::isfinite(v))
        return bad("box", three ? "six finite numbers [m]" : "four finite numbers [m]");
    if (three && !(std::isfinite(z[0]) && std::isfinite(z[1])))
      return bad("box", "six finite numbers [m]");
    if (!three && (!(b[2] > b[0]) || !(b[3] > b[1])))
      return bad("box", fmt::format("[xmin, ymin, xmax, ymax] with xmax > xmin and ymax > ymin, "
                                    "got [{}, {}, {}, {}]",
                                    b[0], b[1], b[2], b[3]));
    if (three && (!(b[2] > b[0]) || !(b[3] > b[1]) || !(z[1] > z[0])))
      return bad("box", fmt::format("[xmin, ymin, zmin, xmax, ymax, zmax] with each max > min, "
                                    "got [{}, {}, {}, {}, {}, {}]",
                                    b[0], b[1], z[0], b[2], b[3], z[1]));
  } else {
    if (!std::isfinite(p.aspect_ratio) || p.aspect_ratio < 1e-3 || p.aspect_ratio > 1e3)
      return bad("aspect_ratio", fmt::format("a number in [0.001, 1000], got {}", p.aspect_ratio));
    if (!std::isfinite(p.origin[0]) || !std::isfinite(p.origin[1]) ||
        (three && !std::isfinite(p.origin_z)))
      return bad("origin", three ? "three finite numbers [m]" : "two finite numbers [m]");
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
template <int Dim>
bool relax_damped(detail::Dem<Dim>& dem, std::int64_t max_steps, double tol) {
  const double dt = dem.time_step();
  const double nd = static_cast<double>(dem.size());
  for (std::int64_t k = 0; k < max_steps; ++k) {
    dem.md_step(dt);
    if (dem.max_overlap() < tol && dem.kinetic_energy() / nd < 1e-14) return true;
  }
  return false;
}

// Grain measure of diameter d: disk area pi d^2 / 4 (2D), sphere volume pi d^3 / 6 (3D) [m^Dim].
template <int Dim>
double grain_measure(double d) {
  if constexpr (Dim == 2)
    return std::numbers::pi * 0.25 * d * d;
  else
    return std::numbers::pi / 6.0 * d * d * d;
}

// The protocols of §3 in Dim dimensions (the 2D path is the original disk generator).
template <int Dim>
Packing generate_impl(const PackingParams& p, PackingReport& report) {
  using Dem = detail::Dem<Dim>;
  const auto root = [](double v) { return detail::dim_root<Dim>(v); };
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
  double grain_volume = 0.0;
  for (double di : d) grain_volume += grain_measure<Dim>(di);

  // Reference state (scale 1): the packing fraction phi_ref in the final box (§3, eq. 8).
  const bool jam = p.method == PackingMethod::kJam;
  const double phi_ref = jam ? p.jam_start_phi : p.target_phi;
  std::array<double, Dim> ext{}, lo{};  // box extents and lower corner [m]
  double c = 1.0;
  if (p.box) {
    lo[0] = (*p.box)[0];
    lo[1] = (*p.box)[1];
    ext[0] = (*p.box)[2] - lo[0];
    ext[1] = (*p.box)[3] - lo[1];
    if constexpr (Dim == 3) {
      lo[2] = p.box_z[0];
      ext[2] = p.box_z[1] - lo[2];
    }
    double target = phi_ref;  // phi_ref x box volume [m^Dim]
    for (int a = 0; a < Dim; ++a) target *= ext[a];
    c = root(target / grain_volume);
    for (double& di : d) di *= c;
  } else {
    const double volume = grain_volume / phi_ref;
    if constexpr (Dim == 2) {
      ext[0] = std::sqrt(volume * p.aspect_ratio);
      ext[1] = std::sqrt(volume / p.aspect_ratio);
    } else {
      // W x W x H with W / H = aspect_ratio: H = (V / a^2)^(1/3).
      ext[2] = std::cbrt(volume / (p.aspect_ratio * p.aspect_ratio));
      ext[0] = ext[1] = p.aspect_ratio * ext[2];
      lo[2] = p.origin_z;
    }
    lo[0] = p.origin[0];
    lo[1] = p.origin[1];
  }
  double dbar = 0.0;
  for (double di : d) dbar += di;
  dbar /= static_cast<double>(n);
  const double dmax = *std::max_element(d.begin(), d.end());
  // A wall box must hold the largest grain; a periodic cell must be 3 of them wide so that each
  // pair interacts through one image only.
  const double fit = p.periodic ? 3.0 : 1.0;
  const double ext_min = *std::min_element(ext.begin(), ext.end());
  if (fit * dmax >= ext_min) {
    std::string dims = fmt::format("{:.6g} x {:.6g}", ext[0], ext[1]);
    if constexpr (Dim == 3) dims += fmt::format(" x {:.6g}", ext[2]);
    const char* grain = Dim == 2 ? "disk" : "sphere";
    throw InputError(
        "", 0, p.box ? "packing.box" : "packing.count",
        fmt::format("a box wider than {} largest {}{}: diameter {:.6g} m, box "
                    "{} m",
                    p.periodic ? "3 times the" : "the", grain, p.periodic ? "s" : "", dmax, dims));
  }

  // Reduced units (§2): length d_mean.
  std::array<double, Dim> er;  // box extents [d_mean]
  for (int a = 0; a < Dim; ++a) er[a] = ext[a] / dbar;
  std::vector<double> r0(n);
  typename Dem::Coords x;
  for (auto& xa : x) xa.assign(n, 0.0);
  for (std::size_t i = 0; i < n; ++i) r0[i] = 0.5 * d[i] / dbar;
  const double phi0 = p.initial_phi;
  const double s0 = root(phi0 / phi_ref);  // radius scale at the start (grow, jam)
  const double g0 = root(phi_ref / phi0);  // box scale at the start (walls)
  const bool walls = p.method == PackingMethod::kWalls;
  std::array<double, Dim> bw, bl;  // start box extents and lower corner [d_mean]
  for (int a = 0; a < Dim; ++a) {
    bw[a] = walls ? g0 * er[a] : er[a];
    bl[a] = 0.5 * (er[a] - bw[a]);
  }
  const double bw_min = *std::min_element(bw.begin(), bw.end());
  const double rs = walls ? 1.0 : s0;
  for (std::size_t i = 0; i < n; ++i) {
    // Random centers keeping each (start-size) grain inside the walls.
    const double ri = p.periodic ? 0.0 : std::min(rs * r0[i], 0.5 * bw_min);
    for (int a = 0; a < Dim; ++a) x[a][i] = bl[a] + ri + (bw[a] - 2.0 * ri) * uniform01(rng);
  }
  detail::DemSettings settings;
  settings.law = p.contact_law;
  settings.friction = p.friction;
  settings.damping_ratio = p.damping_ratio;
  settings.global_damping = p.global_damping;
  settings.periodic = p.periodic;
  typename Dem::Box box0;
  for (int a = 0; a < Dim; ++a) {
    box0[a] = bl[a];
    box0[Dim + a] = bl[a] + bw[a];
  }
  Dem dem(std::move(x), std::move(r0), box0, settings);
  dem.set_scale(rs);

  // Growth or wall compression with damped dynamics: phi rises linearly from phi0 to phi_ref
  // in growth_steps steps (eq. 9 and 10).
  const double dt = dem.time_step();
  const auto g_steps = p.growth_steps;
  typename Dem::Box box_prev = dem.box();
  for (std::int64_t k = 1; k <= g_steps; ++k) {
    const double phi =
        phi0 + (phi_ref - phi0) * static_cast<double>(k) / static_cast<double>(g_steps);
    if (walls) {
      const double g = root(phi_ref / phi);
      typename Dem::Box b, v;
      for (int a = 0; a < Dim; ++a) {
        b[a] = 0.5 * er[a] * (1.0 - g);
        b[Dim + a] = 0.5 * er[a] * (1.0 + g);
      }
      for (int w = 0; w < 2 * Dim; ++w) v[w] = (b[w] - box_prev[w]) / dt;
      dem.set_box(b);
      dem.set_wall_velocity(v);
      box_prev = b;
    } else {
      dem.set_scale(root(phi / phi_ref));
    }
    dem.md_step(dt);
  }
  dem.set_wall_velocity({});
  typename Dem::Box box_ref{};
  for (int a = 0; a < Dim; ++a) box_ref[Dim + a] = er[a];
  dem.set_box(box_ref);
  dem.set_scale(1.0);
  log().info("packing: {} {}, {} to phi = {:.4f} in {} steps", n, Dim == 2 ? "disks" : "spheres",
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
    // per grain exceeds kUnjammedEnergy. Bisection between the densest unjammed and the loosest
    // jammed state until their gap < jam_phi_tolerance.
    typename Dem::Coords lo_x, hi_x;
    double phi_lo = -1.0, phi_hi = -1.0, phi = phi_ref, step = 0.005;
    bool jammed = dem.energy() / static_cast<double>(n) > kUnjammedEnergy;
    bool from_lo = false;     // the last trial started from the densest unjammed state
    bool hi_from_lo = false;  // the loosest jammed state was compressed from that state
    for (int iter = 0; iter < 400; ++iter) {
      if (jammed) {
        phi_hi = phi;
        dem.get_positions(hi_x);
        hi_from_lo = from_lo;
      } else {
        phi_lo = phi;
        dem.get_positions(lo_x);
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
      dem.set_positions(from_lo ? lo_x : hi_x);
      dem.set_scale(root(phi / phi_ref));
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
      dem.set_positions(hi_x);
      dem.set_scale(root(phi_hi / phi_ref));
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
  out.dimension = Dim;
  out.seed = p.seed;
  out.periodic = p.periodic;
  out.xmin = lo[0];
  out.ymin = lo[1];
  out.xmax = p.box ? (*p.box)[2] : lo[0] + er[0] * len;
  out.ymax = p.box ? (*p.box)[3] : lo[1] + er[1] * len;
  if constexpr (Dim == 3) {
    out.zmin = lo[2];
    out.zmax = p.box ? p.box_z[1] : lo[2] + er[2] * len;
  }
  out.disks.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    out.disks[i] = Disk{static_cast<std::int64_t>(i), lo[0] + dem.x(0)[i] * len,
                        lo[1] + dem.x(1)[i] * len, dem.r()[i] * len};
    if constexpr (Dim == 3) out.disks[i].z = lo[2] + dem.x(2)[i] * len;
  }
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

// Largest overlap of a packing in Dim dimensions [m], by the DEM's cell lists.
template <int Dim>
double max_overlap_impl(const Packing& packing) {
  const double dbar = mean_diameter(packing);
  if (!(dbar > 0.0)) return 0.0;
  const std::size_t n = packing.disks.size();
  typename detail::Dem<Dim>::Coords x;
  for (auto& xa : x) xa.resize(n);
  std::vector<double> r(n);
  for (std::size_t i = 0; i < n; ++i) {
    x[0][i] = (packing.disks[i].x - packing.xmin) / dbar;
    x[1][i] = (packing.disks[i].y - packing.ymin) / dbar;
    if constexpr (Dim == 3) x[2][i] = (packing.disks[i].z - packing.zmin) / dbar;
    r[i] = packing.disks[i].radius / dbar;
  }
  detail::DemSettings settings;
  settings.periodic = packing.periodic;
  typename detail::Dem<Dim>::Box box{};
  box[Dim] = (packing.xmax - packing.xmin) / dbar;
  box[Dim + 1] = (packing.ymax - packing.ymin) / dbar;
  if constexpr (Dim == 3) box[5] = (packing.zmax - packing.zmin) / dbar;
  detail::Dem<Dim> dem(std::move(x), std::move(r), box, settings);
  dem.update_forces(false);
  return dem.max_overlap() * dbar;
}

}  // namespace

Packing generate_packing(const PackingParams& params) {
  PackingReport report;
  return generate_packing(params, report);
}

Packing generate_packing(const PackingParams& p, PackingReport& report) {
  if (auto problem = detail::check_params(p))
    throw InputError("", 0, "packing." + problem->key, problem->expectation);
  return p.dimension == 3 ? generate_impl<3>(p, report) : generate_impl<2>(p, report);
}

double packing_fraction(const Packing& packing) {
  const bool three = packing.dimension == 3;
  double volume = 0.0;
  for (const auto& disk : packing.disks)
    volume += three ? 4.0 / 3.0 * std::numbers::pi * disk.radius * disk.radius * disk.radius
                    : std::numbers::pi * disk.radius * disk.radius;
  double box = (packing.xmax - packing.xmin) * (packing.ymax - packing.ymin);
  if (three) box *= packing.zmax - packing.zmin;
  return box > 0.0 ? volume / box : 0.0;
}

double mean_diameter(const Packing& packing) {
  if (packing.disks.empty()) return 0.0;
  double sum = 0.0;
  for (const auto& disk : packing.disks) sum += 2.0 * disk.radius;
  return sum / static_cast<double>(packing.disks.size());
}

double max_overlap(const Packing& packing) {
  return packing.dimension == 3 ? max_overlap_impl<3>(packing) : max_overlap_impl<2>(packing);
}

std::string summary_line(const Packing& packing) {
  const double dbar = mean_diameter(packing);
  return fmt::format(
      "packing: {} grains, phi = {:.6f}, max overlap = {:.3e} d_mean (d_mean = {:.6g} m, {} = "
      "[{:.6g}, {:.6g}] x [{:.6g}, {:.6g}]{} m)",
      packing.disks.size(), packing_fraction(packing),
      dbar > 0.0 ? max_overlap(packing) / dbar : 0.0, dbar,
      packing.periodic ? "periodic cell" : "box", packing.xmin, packing.xmax, packing.ymin,
      packing.ymax,
      packing.dimension == 3 ? fmt::format(" x [{:.6g}, {:.6g}]", packing.zmin, packing.zmax)
                             : std::string());
}

}  // namespace mpmcd::packing
