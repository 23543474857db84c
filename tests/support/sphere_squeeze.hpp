#pragma once
// 3D Hertz (issue 18): a Neo-Hookean sphere squeezed quasi-statically between two rigid
// frictionless plates (bottom fixed, top moving down), two identical Hertz contacts by symmetry,
// against F = (4/3) E* sqrt(R) delta^{3/2} (Johnson, Contact Mechanics, eq. 4.23) with delta the
// approach of one contact (half the loss of diameter) and 1/E* = (1 - nu^2)/E for an elastic sphere
// on a rigid flat. The sphere is seeded on concentric shells so that its outline is a sphere and
// not the lattice's staircase (whose flat top layer is as wide as the contact at delta/D = 0.05
// with 20 cells per diameter).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <string>
#include <vector>

#include "mpmcd/materials/law.hpp"
#include "mpmcd/mpm/model.hpp"
#include "mpmcd/mpm/solver.hpp"
#include "mpmcd/points/seeding.hpp"
#include "stepping.hpp"

namespace mpmcd::test_support {

// Young's modulus of the Neo-Hookean law at small strain, E = mu (3 lambda + 2 mu)/(lambda + mu)
// [Pa], and Poisson's ratio nu = lambda / (2 (lambda + mu)) [-].
inline double young_modulus(double lambda, double mu) {
  return mu * (3 * lambda + 2 * mu) / (lambda + mu);
}
inline double poisson_ratio(double lambda, double mu) {
  return lambda / (2 * (lambda + mu));
}

// Contact modulus of an elastic sphere on a rigid flat: E* = E / (1 - nu^2) [Pa].
inline double sphere_flat_modulus(double lambda, double mu) {
  const double nu = poisson_ratio(lambda, mu);
  return young_modulus(lambda, mu) / (1 - nu * nu);
}

// Hertz force of a sphere of radius R [m] on a rigid flat at approach delta [m]:
// F = (4/3) E* sqrt(R) delta^{3/2} [N] (Johnson, Contact Mechanics, eq. 4.23).
inline double hertz_sphere_force(double delta, double R, double e_star) {
  return delta > 0 ? 4.0 / 3.0 * e_star * std::sqrt(R) * std::pow(delta, 1.5) : 0.0;
}

// The finite-element reference of tests/reference/sphere_on_plate (an axisymmetric linear-elastic
// sphere, E = 4 MPa, nu = 1/3, on a rigid flat; R/800 elements at the pole): F_FE / F_Hertz at
// delta/D = 0.0025, 0.005, ..., 0.05 (reference.txt). A sphere is stiffer than Hertz's half-space
// formula at a given plate-to-centre approach, by about 0.9 sqrt(delta/D).
inline constexpr double kFeOverHertz[20] = {1.0387, 1.0580, 1.0713, 1.0844, 1.0953, 1.1055, 1.1144,
                                            1.1229, 1.1318, 1.1398, 1.1474, 1.1541, 1.1619, 1.1694,
                                            1.1758, 1.1818, 1.1891, 1.1944, 1.2013, 1.2069};

// The finite-strain reference of tests/reference/sphere_on_plate: the same sphere and mesh with
// the simulated compressible Neo-Hookean law (lambda = 3 MPa, mu = 1.5 MPa), F_NH / F_Hertz at
// the same delta/D (reference_neo_hookean.txt); 1.6-1.9 % below the linear sphere for
// 0.02 <= delta/D <= 0.05.
inline constexpr double kNhOverHertz[20] = {1.0314, 1.0477, 1.0590, 1.0697, 1.0790, 1.0882, 1.0953,
                                            1.1041, 1.1120, 1.1194, 1.1267, 1.1335, 1.1396, 1.1470,
                                            1.1544, 1.1605, 1.1670, 1.1743, 1.1794, 1.1874};

// Linear interpolation at delta/D = x in [0.0025, 0.05] of a table at 0.0025, 0.005, ..., 0.05.
inline double interpolate_reference(const double (&table)[20], double x) {
  const double k = std::clamp(x / 0.0025 - 1.0, 0.0, 19.0);
  const int i = std::min(static_cast<int>(k), 18);
  return table[i] + (k - i) * (table[i + 1] - table[i]);
}

// F_FE / F_Hertz of the linear-elastic sphere at delta/D = x in [0.0025, 0.05] [-].
inline double fe_over_hertz(double x) {
  return interpolate_reference(kFeOverHertz, x);
}

// F_NH / F_Hertz of the Neo-Hookean sphere at delta/D = x in [0.0025, 0.05] [-].
inline double nh_over_hertz(double x) {
  return interpolate_reference(kNhOverHertz, x);
}

// A ball of radius R about c seeded on n concentric shells of thickness s = R/n: shell k at
// radius (k + 1/2) s holds N_k = max(1, round(4 pi (k + 1/2)^2)) points on a Fibonacci lattice
// (golden-angle spiral), each with the shell's volume / N_k, so that the volumes sum to
// 4/3 pi R^3 exactly and the outer points lie s/2 inside the sphere (their half-width).
inline points::Seeds<3> seed_ball_shells(const Vec<3>& c, double R, int n) {
  points::Seeds<3> out;
  const double s = R / n, golden = std::numbers::pi * (3 - std::sqrt(5.0));
  for (int k = 0; k < n; ++k) {
    const double r = (k + 0.5) * s;
    const int count =
        std::max(1, static_cast<int>(std::lround(4 * std::numbers::pi * (k + 0.5) * (k + 0.5))));
    const double shell =
        4.0 / 3.0 * std::numbers::pi * (std::pow((k + 1) * s, 3) - std::pow(k * s, 3)) / count;
    for (int i = 0; i < count; ++i) {
      const double z = 1 - (2 * i + 1.0) / count, rho = std::sqrt(1 - z * z);
      const double phi = golden * i;
      out.x.push_back(c + r * Vec<3>(rho * std::cos(phi), rho * std::sin(phi), z));
      out.volume.push_back(shell);
    }
  }
  return out;
}

// The part of seed_ball_shells(c, R, n) in the octant x, y, z > c, each shell's volumes rescaled to
// an eighth of the shell (a shell with no point there gets one on the diagonal).
inline points::Seeds<3> seed_octant_shells(const Vec<3>& c, double R, int n) {
  const auto all = seed_ball_shells(c, R, n);
  points::Seeds<3> out;
  const double s = R / n;
  std::size_t i = 0;
  for (int k = 0; k < n; ++k) {
    const int count =
        std::max(1, static_cast<int>(std::lround(4 * std::numbers::pi * (k + 0.5) * (k + 0.5))));
    const std::size_t first = out.x.size();
    for (int j = 0; j < count; ++j, ++i)
      if ((all.x[i] - c).minCoeff() > 0) out.x.push_back(all.x[i]);
    if (out.x.size() == first) out.x.push_back(c + (k + 0.5) * s * Vec<3>::Ones() / std::sqrt(3.0));
    const double eighth = std::numbers::pi / 6.0 * (std::pow((k + 1) * s, 3) - std::pow(k * s, 3));
    out.volume.resize(out.x.size(), eighth / static_cast<double>(out.x.size() - first));
  }
  return out;
}

// Grid nodes whose index along `axis` is `index`.
inline std::vector<std::int64_t> plane_nodes_3d(const grid::Grid<3>& g, int axis,
                                                std::int64_t index) {
  std::vector<std::int64_t> out;
  for (std::int64_t i = 0; i < g.node_count(); ++i)
    if (g.node_coords(i)[axis] == index) out.push_back(i);
  return out;
}

// The squeeze of a sphere between two plates.
struct SphereSqueezeSetup {
  double radius = 5e-3;         // sphere radius R [m]
  int cells_per_diameter = 10;  // D / h (even: the centre is a node)
  int shells_per_cell = 2;      // shells per cell along the radius (s = h / shells_per_cell)
  double lambda = 3e6, mu = 1.5e6, rho = 990;                   // Neo-Hookean law [Pa, Pa, kg/m^3]
  grid::ShapeKind shape = grid::ShapeKind::kLinear;             // shape functions
  mpm::LinearSolverKind solver = mpm::LinearSolverKind::kLdlt;  // per-grain linear solver
  bool face_walls = false;    // walls on the points' faces (CPDI + affine) instead of nodes
  double courant = 1.0;       // c_p dt / h [-]
  double wall_speed = 0.3;    // top wall speed [m/s]
  double final_delta = 0.05;  // final approach of one contact / D (top travel = 2 delta) [-]
  int samples = 10;           // windows over the run
  int max_cuts = 4;           // a step that fails is retried with dt halved up to this often
  // Model the octant x, y, z > centre only, with symmetry planes through the centre (the normal
  // velocity of the grid nodes on them prescribed to 0) instead of the bottom plate: one
  // contact, a quarter of it in the model (load = 4 x the top plate force), top travel = delta.
  bool octant = false;
};

// One window of the squeeze curve: forces are the wall impulses over the window / its duration.
struct SphereSqueezeSample {
  double delta = 0;     // mean approach of one contact over the window (top travel / 2) [m]
  double f_top = 0;     // mean force of the sphere on the top plate, upward [N]
  double f_bottom = 0;  // mean force of the sphere on the bottom plate, downward [N]
  double kinetic = 0, elastic = 0;  // energies at the end of the window [J]
  // Mean of the two plate forces [N] (removes the sphere's inertia to first order).
  double load() const { return 0.5 * (f_top + f_bottom); }
};

struct SphereSqueezeResult {
  double h = 0, dt = 0, diameter = 0;  // cell size, step [s], material extent along z [m]
  std::int64_t points = 0, steps = 0, iterations = 0, cuts = 0;
  double seconds = 0;
  bool ok = true;
  std::string failure;
  std::vector<SphereSqueezeSample> curve;
};

inline SphereSqueezeResult run_sphere_squeeze(const SphereSqueezeSetup& su) {
  const auto t0 = std::chrono::steady_clock::now();
  SphereSqueezeResult res;
  const int half_d = su.cells_per_diameter / 2;
  const double h = su.radius / half_d;
  const int half = half_d + 3;
  mpm::Model<3> model;
  model.grid = grid::Grid<3>(Vec<3>::Zero(), h, IVec<3>(2 * half, 2 * half, 2 * half));
  model.add_material(materials::make_law<3>("neo_hookean", {{"lambda", su.lambda}, {"mu", su.mu}}),
                     su.rho);
  const Vec<3> c(half * h, half * h, half * h);
  const int shells = half_d * su.shells_per_cell;
  const double lp = 0.5 * su.radius / shells;  // point half-width: half a shell
  const auto seeds =
      su.octant ? seed_octant_shells(c, su.radius, shells) : seed_ball_shells(c, su.radius, shells);
  double zmin = std::numeric_limits<double>::infinity(), zmax = -zmin;
  for (const auto& x : seeds.x) {
    zmin = std::min(zmin, x[2] - lp);
    zmax = std::max(zmax, x[2] + lp);
  }
  if (su.octant) zmin = c[2];  // the bottom of the model is the symmetry plane
  res.diameter = su.octant ? 2 * (zmax - zmin) : zmax - zmin;
  const double v = su.wall_speed;
  // Quasi-static start: v_z = -v (z - z_bottom) / D, the bottom at rest, the top at -v.
  model.add_grain(seeds, 0, lp, [&](const Vec<3>& x) {
    return Vec<3>(0, 0, -v * (x[2] - zmin) / (zmax - zmin));
  });
  res.points = static_cast<std::int64_t>(model.points.size());
  mpm::Settings<3> s;
  s.shape = su.shape;
  s.theta = 1.0;
  s.linear_solver = su.solver;
  s.contact.enabled = true;
  s.contact.friction = {0.0};
  if (su.face_walls) {
    s.shape = grid::ShapeKind::kCpdi;
    s.affine = true;
    s.contact.wall_points = true;
  }
  // The plates touch the extreme point domains: the gaps start at 0. Octant: the top plate only
  // (wall 0), the symmetry planes as node velocity conditions.
  if (!su.octant)
    s.contact.walls.push_back({"bottom", Vec<3>(0, 0, zmin), Vec<3>(0, 0, 1), Vec<3>::Zero(), 0.0});
  s.contact.walls.push_back({"top", Vec<3>(0, 0, zmax), Vec<3>(0, 0, -1), Vec<3>(0, 0, -v), 0.0});
  mpm::ImplicitSolver<3> solver(model.grid, s, model.points, model.grains, model.law_ptrs());
  if (su.octant) {
    std::vector<mpm::VelocityBC<3>> bcs(3);
    for (int a = 0; a < 3; ++a) {
      bcs[a].nodes = plane_nodes_3d(model.grid, a, half);
      bcs[a].mask = static_cast<std::uint8_t>(1u << a);
    }
    solver.set_boundary_conditions(bcs);
  }
  const int top = su.octant ? 0 : 1;
  const double share = su.octant ? 4.0 : 1.0;  // the model's share of the contact: 1/4
  const double cp = std::sqrt((su.lambda + 2 * su.mu) / su.rho);
  res.h = h;
  res.dt = su.courant * h / cp;
  const double t_end = (su.octant ? 1 : 2) * su.final_delta * 2 * su.radius / v;
  const double window = t_end / su.samples;
  double t = 0, next = window, wt = 0, wdelta = 0, imp_top = 0, imp_bottom = 0;
  while (t < t_end * (1 - 1e-12)) {
    double dt = std::min(res.dt, t_end - t);
    const mpm::StepStats st = step_with_cuts(solver, t, dt, su.max_cuts, res.cuts);
    if (!st.converged) {
      res.ok = false;
      res.failure = st.failure;
      break;
    }
    solver.commit();
    // One contact's approach: half the top travel (octant: all of it).
    wdelta += (su.octant ? 1.0 : 0.5) * v * (t + 0.5 * dt) * dt;
    imp_top += share * st.wall_force[top][2] * dt;
    // Octant: no bottom plate; its force is taken as the top one's.
    imp_bottom -= su.octant ? -share * st.wall_force[top][2] * dt : st.wall_force[0][2] * dt;
    wt += dt;
    t += dt;
    ++res.steps;
    res.iterations += st.iterations;
    if (t >= next * (1 - 1e-9) || t >= t_end * (1 - 1e-12)) {
      next += window;
      const auto d = mpm::diagnostics(model);
      res.curve.push_back({wdelta / wt, imp_top / wt, imp_bottom / wt, d.kinetic, d.elastic});
      wt = wdelta = imp_top = imp_bottom = 0;
    }
  }
  res.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return res;
}

// Largest |F / F_ref - 1| over the windows with lo <= delta/D <= hi, F_ref = Hertz's formula or
// (fe = true) the Neo-Hookean finite-element reference nh_over_hertz x Hertz.
inline double sphere_hertz_error(const SphereSqueezeSetup& su, const SphereSqueezeResult& r,
                                 double lo, double hi, bool fe = false) {
  const double es = sphere_flat_modulus(su.lambda, su.mu);
  double worst = 0;
  for (const auto& s : r.curve) {
    const double x = s.delta / (2 * su.radius);
    const double ref = hertz_sphere_force(s.delta, su.radius, es) * (fe ? nh_over_hertz(x) : 1.0);
    if (x >= lo * (1 - 1e-9) && x <= hi * (1 + 1e-9))
      worst = std::max(worst, std::abs(s.load() / ref - 1));
  }
  return worst;
}

// Largest kinetic / elastic energy over the windows with delta/D >= lo (quasi-static check).
inline double sphere_kinetic_ratio(const SphereSqueezeSetup& su, const SphereSqueezeResult& r,
                                   double lo) {
  double worst = 0;
  for (const auto& s : r.curve)
    if (s.delta / (2 * su.radius) >= lo * (1 - 1e-9))
      worst = std::max(worst, s.kinetic / std::max(s.elastic, 1e-300));
  return worst;
}

// Prints F / F_Hertz against delta / D and returns the largest |F / F_Hertz - 1| over the
// windows with lo <= delta/D <= hi.
inline double print_sphere_hertz(const char* label, const SphereSqueezeSetup& su,
                                 const SphereSqueezeResult& r, double lo, double hi) {
  const double es = sphere_flat_modulus(su.lambda, su.mu);
  std::printf(
      "  %s: D/h = %d, h = %.3e m, dt = %.3e s, %lld points%s, %lld steps (%lld cut), %.1f Newton "
      "it/step, %.1f s\n",
      label, su.cells_per_diameter, r.h, r.dt, static_cast<long long>(r.points),
      su.octant ? " (octant)" : "", static_cast<long long>(r.steps), static_cast<long long>(r.cuts),
      static_cast<double>(r.iterations) / static_cast<double>(std::max<std::int64_t>(r.steps, 1)),
      r.seconds);
  std::printf("  %10s %8s %10s %10s %10s %10s %8s %8s %8s %9s\n", "delta [m]", "delta/D",
              "F_top [N]", "F_bottom", "F_sim", "F_Hertz", "/Hertz-1", "/FE_lin-1", "/FE_NH-1",
              "Ekin/Eel");
  double worst = 0;
  for (const auto& s : r.curve) {
    const double fh = hertz_sphere_force(s.delta, su.radius, es), f = s.load();
    const double x = s.delta / (2 * su.radius), err = f / fh - 1;
    std::printf("  %10.4e %8.4f %10.4f %10.4f %10.4f %10.4f %+8.3f %+8.3f %+8.3f %9.2e\n", s.delta,
                x, s.f_top, s.f_bottom, f, fh, err, f / (fh * fe_over_hertz(x)) - 1,
                f / (fh * nh_over_hertz(x)) - 1, s.kinetic / std::max(s.elastic, 1e-300));
    if (x >= lo * (1 - 1e-9) && x <= hi * (1 + 1e-9)) worst = std::max(worst, std::abs(err));
  }
  std::printf(
      "  %s: largest |F/F_Hertz - 1| for %.3f <= delta/D <= %.3f: %.3f; largest |F/F_FE_NH - 1|: "
      "%.3f\n",
      label, lo, hi, worst, sphere_hertz_error(su, r, lo, hi, true));
  return worst;
}

}  // namespace mpmcd::test_support
