#pragma once
// Builders shared by the contact verification tests: a Neo-Hookean disk squeezed between two rigid
// frictionless walls (bottom fixed, top moving down), the 2D Hertz closed form (method.md §7), and
// two disks approaching head-on.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <string>
#include <vector>

#include "builders.hpp"
#include "stepping.hpp"

namespace mpmcd::test_support {

// Plane-strain modulus of the Neo-Hookean law at small strain, E* = 4 mu (lambda + mu) /
// (lambda + 2 mu) [Pa] (method.md §7).
inline double plane_strain_modulus(double lambda, double mu) {
  return 4 * mu * (lambda + mu) / (lambda + 2 * mu);
}

// 2D Hertz, disk of radius R [m] between two rigid frictionless plates under the load P [N/m]:
// loss of diameter Delta = (2P / (pi E*)) [2 ln(4R/a) - 1], a = 2 sqrt(P R / (pi E*)) [m].
inline double hertz_approach(double P, double R, double e_star) {
  const double a = 2 * std::sqrt(P * R / (std::numbers::pi * e_star));
  return 2 * P / (std::numbers::pi * e_star) * (2 * std::log(4 * R / a) - 1);
}

// Inverse of hertz_approach: the load P [N/m] giving the loss of diameter delta [m] (bisection in
// log P; Delta(P) is increasing while a < 4R/e, far beyond the range of validity).
inline double hertz_load(double delta, double R, double e_star) {
  if (delta <= 0) return 0;
  double lo = 1e-12 * e_star * R, hi = 0.5 * e_star * R;
  for (int i = 0; i < 200; ++i) {
    const double mid = std::sqrt(lo * hi);
    (hertz_approach(mid, R, e_star) < delta ? lo : hi) = mid;
  }
  return std::sqrt(lo * hi);
}

// A disk squeezed between a fixed bottom wall and a top wall moving down at constant speed.
struct SqueezeSetup {
  double radius = 5e-3;         // disk radius R [m]
  int cells_per_diameter = 20;  // D / h (even: the disk centre is a node, R = (D/h)/2 h)
  int ppc = 2;                  // points per cell and axis
  double lambda = 3e6, mu = 1.5e6, rho = 990;        // Neo-Hookean law [Pa, Pa, kg/m^3]
  grid::ShapeKind shape = grid::ShapeKind::kLinear;  // shape functions
  double courant = 0.4;                              // c_p dt / h [-]
  double wall_speed = 0.1;                           // top wall speed [m/s]
  double final_approach = 1e-3;                      // top wall travel [m]
  double theta = 1.0;                                // theta-method parameter [-]
  bool preload = true;  // start the disk with the quasi-static velocity v_y = -v (y - y_b) / D
  int samples = 50;     // samples recorded over the run
  double lateral_margin = 0.6;  // grid half-width beyond R, in diameters
  double offset = 0.0;          // disk centre above a node row, in cells (a multiple of 1/(2 ppc))
  double wall_range = 1.0;      // mpm::ContactSettings::wall_range [cells]
  bool polar = false;           // seed the disk on rings (points::seed_disk_polar), else a lattice
};

// One sample of the squeeze curve. Contact Dynamics gives impulses per step, which chatter from
// step to step where a node row meets a wall; the forces are therefore the impulses summed over
// the steps since the previous sample divided by that time, at the window's mean approach.
struct SqueezeSample {
  double delta = 0;                 // mean top wall travel over the window (loss of diameter) [m]
  double p_top = 0;                 // mean force of the disk on the top wall, upward [N/m]
  double p_bottom = 0;              // mean force of the disk on the bottom wall, downward [N/m]
  double kinetic = 0, elastic = 0;  // energies [J/m]
  double volume = 0;                // total point volume sum J V0 [m^2]
  std::int64_t active = 0;          // active contacts
  double penetration = 0;           // deepest point domain beyond either wall [m]
  double mean_ln_j = 0;   // sum V0 ln J / sum V0, averaged over the window like the forces [-]
  double mean_shear = 0;  // sum V0 (b_xx + b_yy - 2) / sum V0, b = F F^T, window average [-]
};

struct SqueezeResult {
  double h = 0, dt = 0;         // cell size [m], nominal step [s]
  double diameter = 0;          // material extent along y at t = 0 (point domains) [m]
  double volume0 = 0;           // initial total point volume [m^2]
  double first_force = -1;      // wall travel at the first step with a force on the top wall [m]
  std::int64_t steps = 0;       // committed steps
  std::int64_t cuts = 0;        // steps retried with a smaller dt
  std::int64_t points = 0;      // material points
  std::int64_t iterations = 0;  // Newton iterations, summed over committed steps
  std::int64_t gs_sweeps = 0;   // Gauss-Seidel sweeps, summed over committed steps
  std::string timers;           // stage timers of the run
  double seconds = 0;           // wall-clock time [s]
  bool ok = true;               // every step converged (after cuts)
  std::string failure;          // first unrecoverable failure
  std::vector<SqueezeSample> curve;
  // Mean of the two wall forces [N/m] (removes the disk's inertia to first order).
  static double load(const SqueezeSample& s) { return 0.5 * (s.p_top + s.p_bottom); }
};

inline SqueezeResult run_squeeze(const SqueezeSetup& su) {
  const auto t0 = std::chrono::steady_clock::now();
  SqueezeResult res;
  const int half_d = su.cells_per_diameter / 2;
  const double h = su.radius / half_d;
  const int half_x = half_d + static_cast<int>(std::ceil(su.lateral_margin * 2 * half_d)) + 3;
  const int half_y = half_d + 4;
  auto model = make_model(h, 2 * half_x, 2 * half_y, "neo_hookean", su.lambda, su.mu, su.rho);
  const Vec<2> c(half_x * h, (half_y + su.offset) * h);
  // The walls touch the extreme point domains (half-width lp = h / (2 ppc)): the gaps start at 0.
  const double lp = 0.5 * h / su.ppc;
  auto seeds = su.polar ? points::seed_disk_polar(c, su.radius, h / su.ppc)
                        : points::seed_ball<2>(model.grid.origin(), h, su.ppc, c, su.radius);
  double ymin = std::numeric_limits<double>::infinity(), ymax = -ymin;
  for (std::size_t i = 0; i < seeds.x.size(); ++i) {
    // Extent of the point's domain along y: sum of |e_y . r_k| over its half-edges.
    const double ey = seeds.domain.empty() ? lp : seeds.domain[i].row(1).cwiseAbs().sum();
    ymin = std::min(ymin, seeds.x[i][1] - ey);
    ymax = std::max(ymax, seeds.x[i][1] + ey);
  }
  res.diameter = ymax - ymin;
  const double v = su.wall_speed;
  model.add_grain(seeds, 0, lp, [&](const Vec<2>& x) {
    return Vec<2>(0.0, su.preload ? -v * (x[1] - ymin) / (ymax - ymin) : 0.0);
  });
  res.points = static_cast<std::int64_t>(model.points.size());
  mpm::Settings<2> s;
  s.shape = su.shape;
  s.theta = su.theta;
  s.contact.enabled = true;
  s.contact.wall_range = su.wall_range;
  s.contact.walls.push_back({"bottom", Vec<2>(0, ymin), Vec<2>(0, 1), Vec<2>::Zero(), 0.0});
  s.contact.walls.push_back({"top", Vec<2>(0, ymax), Vec<2>(0, -1), Vec<2>(0, -v), 0.0});
  mpm::ImplicitSolver<2> solver(model.grid, s, model.points, model.grains, model.law_ptrs());
  const double cp = std::sqrt((su.lambda + 2 * su.mu) / su.rho);
  res.h = h;
  res.dt = su.courant * h / cp;
  res.volume0 = mpm::diagnostics(model).volume;
  const double t_end = su.final_approach / v;
  const double sample_every = t_end / su.samples;
  double t = 0, next_sample = sample_every;
  double window_t = 0, window_delta = 0, impulse_top = 0, impulse_bottom = 0;
  double window_ln_j = 0, window_shear = 0;
  double v0 = 0;
  for (std::size_t p = 0; p < model.points.size(); ++p) v0 += model.points.volume0[p];
  while (t < t_end * (1 - 1e-12)) {
    double dt = std::min(res.dt, t_end - t);
    const mpm::StepStats st = step_with_cuts(solver, t, dt, 6, res.cuts);
    if (!st.converged) {
      res.ok = false;
      res.failure = st.failure;
      break;
    }
    solver.commit();
    window_delta += v * (t + 0.5 * dt) * dt;
    impulse_top += st.wall_force[1][1] * dt;
    impulse_bottom -= st.wall_force[0][1] * dt;
    window_t += dt;
    for (std::size_t p = 0; p < model.points.size(); ++p) {
      const Mat<2>& F = model.points.F[p];
      window_ln_j += dt * model.points.volume0[p] * std::log(F.determinant()) / v0;
      window_shear += dt * model.points.volume0[p] * ((F * F.transpose()).trace() - 2) / v0;
    }
    t += dt;
    ++res.steps;
    res.iterations += st.iterations;
    res.gs_sweeps += st.gs_sweeps;
    if (res.first_force < 0 && st.wall_force[1][1] > 0) res.first_force = v * t;
    if (t >= next_sample * (1 - 1e-9) || t >= t_end * (1 - 1e-12)) {
      next_sample += sample_every;
      const auto d = mpm::diagnostics(model);
      double pen = 0;
      const double y_top = ymax - v * t;
      for (std::size_t p = 0; p < model.points.size(); ++p) {
        const Vec<2> ey =
            model.points.domain[p].transpose() * (model.points.F[p].transpose() * Vec<2>(0, 1));
        const double e = ey.cwiseAbs().sum();
        pen = std::max({pen, model.points.x[p][1] + e - y_top, ymin - (model.points.x[p][1] - e)});
      }
      res.curve.push_back({window_delta / window_t, impulse_top / window_t,
                           impulse_bottom / window_t, d.kinetic, d.elastic, d.volume,
                           st.active_contacts, pen, window_ln_j / window_t,
                           window_shear / window_t});
      window_t = window_delta = impulse_top = impulse_bottom = window_ln_j = window_shear = 0;
    }
  }
  res.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  for (const auto& [name, sec] : solver.timers().totals())
    res.timers += name + " " + std::to_string(sec) + " s; ";
  return res;
}

// Linear interpolation of the mean load of a curve at loss of diameter `delta` [m] (-1 outside).
inline double load_at(const SqueezeResult& r, double delta) {
  const auto& c = r.curve;
  for (std::size_t i = 1; i < c.size(); ++i)
    if (c[i - 1].delta <= delta && delta <= c[i].delta) {
      const double w = (delta - c[i - 1].delta) / (c[i].delta - c[i - 1].delta);
      return (1 - w) * SqueezeResult::load(c[i - 1]) + w * SqueezeResult::load(c[i]);
    }
  return -1;
}

// Root mean square of P_sim / P_Hertz - 1 over the samples with lo <= Delta/D <= hi.
inline double hertz_rms_error(const SqueezeSetup& su, const SqueezeResult& r, double lo,
                              double hi) {
  const double es = plane_strain_modulus(su.lambda, su.mu);
  double sum = 0;
  int n = 0;
  for (const auto& s : r.curve) {
    const double x = s.delta / r.diameter;
    if (x < lo * (1 - 1e-9) || x > hi * (1 + 1e-9)) continue;
    sum += std::pow(SqueezeResult::load(s) / hertz_load(s.delta, su.radius, es) - 1, 2);
    ++n;
  }
  return n > 0 ? std::sqrt(sum / n) : std::numeric_limits<double>::infinity();
}

// Prints a squeeze curve against 2D Hertz (method.md §7) and returns the largest relative error
// of the mean wall load over the samples with lo <= Delta/D <= hi.
inline double print_hertz(const char* label, const SqueezeSetup& su, const SqueezeResult& r,
                          double lo, double hi) {
  const double es = plane_strain_modulus(su.lambda, su.mu);
  std::printf(
      "  %s: D/h = %d, h = %.3e m, dt = %.3e s, %lld points, %lld steps (%lld cut), "
      "%.1f Newton it/step, %.1f s\n",
      label, su.cells_per_diameter, r.h, r.dt, static_cast<long long>(r.points),
      static_cast<long long>(r.steps), static_cast<long long>(r.cuts),
      static_cast<double>(r.iterations) / static_cast<double>(std::max<std::int64_t>(r.steps, 1)),
      r.seconds);
  std::printf("  %10s %8s %10s %10s %10s %10s %8s %9s %9s\n", "Delta [m]", "Delta/D", "P_top",
              "P_bottom", "P_sim", "P_Hertz", "error", "Ekin/Eel", "pen/h");
  double worst = 0;
  for (const auto& s : r.curve) {
    const double ph = hertz_load(s.delta, su.radius, es), p = SqueezeResult::load(s);
    const double x = s.delta / r.diameter, err = p / ph - 1;
    std::printf("  %10.4e %8.4f %10.2f %10.2f %10.2f %10.2f %+8.3f %9.2e %9.2e\n", s.delta, x,
                s.p_top, s.p_bottom, p, ph, err, s.kinetic / std::max(s.elastic, 1e-300),
                s.penetration / r.h);
    if (x >= lo * (1 - 1e-9) && x <= hi * (1 + 1e-9)) worst = std::max(worst, std::abs(err));
  }
  std::printf("  %s: largest |P_sim/P_Hertz - 1| for %.3f <= Delta/D <= %.3f: %.3f\n", label, lo,
              hi, worst);
  return worst;
}

}  // namespace mpmcd::test_support
