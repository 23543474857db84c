#pragma once
// The walled block of tests/verification/wall_block (2D) and wall_block_3d (3D), written once for
// any dimension: a Neo-Hookean block squeezed between frictionless walls, the top one (normal to
// the last axis: y in 2D, z in 3D) moving in at V, from the exact homogeneous velocity field
// (zero acceleration), against the closed form of method.md §7 after every step. The last axis
// is "vertical"; the others are lateral, held by side walls (uniaxial strain, F = diag(1, .., s);
// biaxial when the wall normal to x moves in too) or free (uniaxial stress).
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <string>

#include "builders.hpp"

namespace mpmcd::test_support {

struct BlockResult {
  double worst_J = 0, worst_sigma = 0, force_error = 0, energy_ratio = 0;
  // max |sigma11 - exact| / |sigma11 exact| (biaxial), / |sigma22 exact| otherwise (uniaxial
  // stress: sigma11 = 0) [-]
  double worst_sigma11 = 0;
  // max over points and all components of |sigma - sigma_exact| / max |sigma_exact| [-]
  double worst_sigma_all = 0;
  double side_force_error = 0;  // right wall (biaxial) [-]
  // 3D, triaxial: the back wall's force error and max |sigma_yy - exact| / |sigma_yy exact| [-]
  double back_force_error = 0, worst_sigma_yy = 0;
  // Over every committed step: the largest |J - J_exact|, and the first s where it, or any
  // point's sigma11 or sigma22 error relative to max(|sigma11|, |sigma22|) exact, passed 1e-3
  // (1 if never; in 3D every component of sigma is checked)
  double run_worst_J = 0, lost_at = 1.0;
  double first_retry_at = 1.0;  // s at the start of the first step redone as half steps [-]
  double seconds = 0;           // wall-clock time of the run [s]
  double last_step_work = 0;    // final force x wall travel of one step / wall work [-]
  // (elastic + kinetic change) / the walls' work by the trapezoid rule on the step-end forces,
  // which the exact state matches to O(dt^2) [-]
  double trapezoid_ratio = 0;
  int retries = 0;  // steps redone as two half steps, as the app's step controller does
  std::int64_t factorizations = 0, solves = 0;  // summed over the steps
  std::int64_t projected = 0;       // factorisations redone with the projected tangent (indefinite)
  double contact_dissipation = 0;   // wall work - work of the contact impulses (ledger) / wall work
  double transfer_dissipation = 0;  // kinetic energy the P2G and G2P remove / wall work
  double bulk_dissipation = 0;      // (-stress work on the grid - elastic change) / wall work
  std::int64_t points = 0;          // material points
  bool converged = true;
  std::string failure;
  std::string first_failure;  // why the first step redone as half steps failed
};

// Lateral stretch a of uniaxial stress at vertical stretch s: sigma11 = 0, i.e.
// mu (a^2 - 1) + lambda ln J = 0 with J = a s (2D, plane strain) or a^2 s (3D), by Newton from
// a = 1 (method.md §7 with F = diag(a, s) or diag(a, a, s)).
template <int Dim>
double lateral_stretch(double lambda, double mu, double s) {
  double a = 1.0;
  for (int k = 0; k < 50; ++k) {
    double f, df;
    if constexpr (Dim == 2) {
      f = mu * (a * a - 1) + lambda * std::log(a * s), df = 2 * mu * a + lambda / a;
    } else {
      f = mu * (a * a - 1) + lambda * std::log(a * a * s), df = 2 * mu * a + 2 * lambda / a;
    }
    a -= f / df;
    if (std::abs(f) < 1e-15 * (mu + lambda)) break;
  }
  return a;
}

// How the block is loaded: top wall in at V = 0.4 m/s to s = s_end in `steps` steps (theta = 1).
struct Squeeze {
  double lambda = 0;  // [Pa]
  double s_end = 0.5;
  int steps = 333;
  grid::ShapeKind shape = grid::ShapeKind::kCpdi;
  bool affine = true, wall_points = true, modified_newton = false;
  // false: uniaxial stress (top and bottom walls only, sides free)
  bool side_walls = true;
  // V2 [m/s]: the right wall (normal x) moves left at V2 (biaxial; needs side walls)
  double side_speed = 0;
  // V3 [m/s], 3D only: the back wall (normal y) moves in at V3 too (triaxial; needs side walls)
  double back_speed = 0;
  // [m]: moves the block sideways (a multiple of the point spacing h/2: lattice seeding keeps the
  // sites on that lattice)
  double offset = 0;
  // Newton's relative residual and increment, and the contact impulses' relative change
  double residual_tolerance = 1e-12, impulse_tolerance = 1e-12;
  // true: the block is two grains, [lo, mid] and [mid, hi] along the vertical axis, the lower
  // pushed by the upper through grain-grain contact (contact.grain_contact = "faces" when
  // `grain_faces`)
  bool two_grains = false, grain_faces = true;
  // true: contact problems solved by block principal pivoting (contact.solver = "active_set")
  bool active_set = false;
  // true: the grain-grain face contacts' normals at the iterate's F^{n+1}, with their stiffness
  // (contact.face_normals = "end")
  bool face_normals_at_end = false;
  // The block [lo, hi]^Dim [m] on a grid of cell size h [m] (lo, hi multiples of h), 2 points per
  // cell and axis
  double h = 1e-4, lo = 5e-4, hi = 1.5e-3;
};

// A unit vector along `axis` times `value`, built component by component (no signed zeros).
template <int Dim>
Vec<Dim> along(int axis, double value) {
  Vec<Dim> v = Vec<Dim>::Zero();
  v[axis] = value;
  return v;
}

// Block [lo, hi]^Dim (2D default: [0.5, 1.5] mm^2, h = 0.1 mm, 2 points per cell and axis). With
// side walls (uniaxial strain, or biaxial when the right wall moves left at V2, starting from
// v_x = -V2 (x - lo)/W0) on a grid [0, lo + hi]^Dim; without (uniaxial stress) on a grid twice
// as wide along the lateral axes with the block shifted by 1.5 mm, starting with the lateral
// velocity of the quasi-static path at s = 1, v_i = r V (x_i - x_c)/H0 (the linearised
// sigma11 = 0: r = λ/(λ + 2μ) in plane strain, λ/(2(λ + μ)) in 3D).
// `after_step(s, model)` is called after every committed step with the exact stretch s (probes of
// how the state departs).
template <int Dim, class Observer>
BlockResult squeeze_block(const Squeeze& c, Observer&& after_step) {
  constexpr int up = Dim - 1;  // the vertical axis
  const auto start = std::chrono::steady_clock::now();
  const double lambda = c.lambda, s_end = c.s_end;
  const int steps = c.steps;
  const bool side_walls = c.side_walls;
  constexpr double mu = 1.5e6, rho = 990.0, V = 0.4;
  const double h = c.h, lo = c.lo, hi = c.hi;
  const double V2 = c.side_speed, V3 = c.back_speed;
  // x of the block's left edge minus lo [m]
  const double shift = (side_walls ? 0.0 : 1.5e-3) + c.offset;
  const double ratio = Dim == 2 ? lambda / (lambda + 2 * mu) : lambda / (2 * (lambda + mu));
  const double xc = lo + shift + 0.5 * (hi - lo), rate = ratio * V / (hi - lo);
  const auto n = static_cast<std::int64_t>(std::lround((lo + hi) / h));
  IVec<Dim> cells = IVec<Dim>::Constant(side_walls ? n : 2 * n);
  cells[up] = n;
  auto model = make_model<Dim>(h, cells, "neo_hookean", lambda, mu, rho);
  const auto velocity = [&](const Vec<Dim>& x) {
    Vec<Dim> v;
    for (int i = 0; i < up; ++i)
      v[i] = side_walls ? -(i == 0 ? V2 : V3) * (x[i] - lo) / (hi - lo) : rate * (x[i] - xc);
    v[up] = -V * (x[up] - lo) / (hi - lo);
    return v;
  };
  const double mid = c.two_grains ? 0.5 * (lo + hi) : hi;
  Vec<Dim> corner_lo = Vec<Dim>::Constant(lo + shift), corner_hi = Vec<Dim>::Constant(hi + shift);
  corner_lo[up] = lo;
  corner_hi[up] = mid;
  add_box<Dim>(model, corner_lo, corner_hi, 2, velocity);
  if (c.two_grains) {
    corner_lo[up] = mid;
    corner_hi[up] = hi;
    add_box<Dim>(model, corner_lo, corner_hi, 2, velocity);
  }
  mpm::Settings<Dim> s;
  s.shape = c.shape;
  s.affine = c.affine;
  s.modified_newton = c.modified_newton;
  s.theta = 1.0;
  s.residual_tolerance = s.increment_tolerance = c.residual_tolerance;
  s.contact.enabled = true;
  s.contact.wall_points = c.wall_points;
  s.contact.grain_faces = c.grain_faces;
  s.contact.active_set = c.active_set;
  s.contact.face_normals_at_end = c.face_normals_at_end;
  s.contact.gs.tolerance = 1e-12;
  s.contact.impulse_tolerance = c.impulse_tolerance;
  // bottom, top, left, right (x), then in 3D front, back (y)
  const Vec<Dim> zero = Vec<Dim>::Zero();
  s.contact.walls = {{"bottom", along<Dim>(up, lo), along<Dim>(up, 1), zero, 0.0},
                     {"top", along<Dim>(up, hi), along<Dim>(up, -1), along<Dim>(up, -V), 0.0},
                     {"left", along<Dim>(0, lo), along<Dim>(0, 1), zero, 0.0},
                     {"right", along<Dim>(0, hi), along<Dim>(0, -1), along<Dim>(0, -V2), 0.0}};
  if constexpr (Dim == 3) {
    s.contact.walls.push_back({"front", along<Dim>(1, lo), along<Dim>(1, 1), zero, 0.0});
    s.contact.walls.push_back(
        {"back", along<Dim>(1, hi), along<Dim>(1, -1), along<Dim>(1, -V3), 0.0});
  }
  if (!side_walls) s.contact.walls.resize(2);
  mpm::ImplicitSolver<Dim> solver(model.grid, s, model.points, model.grains, model.law_ptrs());
  const double H0 = hi - lo, dt = (1.0 - s_end) * H0 / V / steps;
  const auto d0 = mpm::diagnostics(model);
  BlockResult r;
  r.points = static_cast<std::int64_t>(model.points.size());
  // The closed form at time t: stretches a (x), b (y in 3D), s (vertical), J and sigma11,
  // sigma_bb (3D), sigma_vertical (method.md §7).
  struct Exact {
    double a, b, s, J, s11, sbb, s22;
  };
  const auto exact = [&](double time) {
    Exact e;
    e.s = 1.0 - V * time / H0;
    e.a = !side_walls ? lateral_stretch<Dim>(lambda, mu, e.s) : 1.0 - V2 * time / H0;
    e.b = !side_walls ? e.a : 1.0 - V3 * time / H0;
    e.J = Dim == 2 ? e.a * e.s : e.a * e.b * e.s;
    e.s11 = (mu * (e.a * e.a - 1) + lambda * std::log(e.J)) / e.J;
    e.sbb = (mu * (e.b * e.b - 1) + lambda * std::log(e.J)) / e.J;
    e.s22 = (mu * (e.s * e.s - 1) + lambda * std::log(e.J)) / e.J;
    return e;
  };
  const auto sigma_exact = [](const Exact& e) {
    Mat<Dim> m = Mat<Dim>::Zero();
    m(0, 0) = e.s11;
    if constexpr (Dim == 3) m(1, 1) = e.sbb;
    m(up, up) = e.s22;
    return m;
  };
  double work = 0, trapezoid = 0, t = 0, force = 0, side_force = 0, contact_work = 0, transfer = 0,
         stress_work = 0, back_force = 0;
  // One step of size `step`; a failed step is redone as two half steps (up to 1/16), as the
  // app's controller cuts dt (docs/accuracy.md lists the failures this still meets).
  std::function<bool(double, int)> advance = [&](double step, int depth) {
    solver.set_time(t);
    const auto st = solver.solve_step(step);
    if (!st.converged) {
      if (depth == 4) {
        r.failure = st.failure + " at t = " + std::to_string(t);
        return false;
      }
      if (r.retries++ == 0) {
        r.first_retry_at = exact(t).s;
        r.first_failure = st.failure;
      }
      return advance(step / 2, depth + 1) && advance(step / 2, depth + 1);
    }
    solver.commit();
    r.factorizations += st.factorizations;
    r.projected += st.projected_factorizations;
    contact_work += st.contact_work;
    transfer += st.transfer_loss;
    stress_work += st.stress_work;
    r.solves += st.linear_solves;
    t += step;
    const double force0 = force, side_force0 = side_force;
    force = st.wall_force[1][up];  // force of the grain on the top wall (+y, +z) [N/m, N]
    work += force * V * step;      // the wall moves down at V against it
    if (side_walls) {
      side_force = st.wall_force[3][0];  // on the right wall (+x) [N/m, N]
      work += side_force * V2 * step;    // which moves left at V2
    }
    trapezoid += 0.5 * ((force0 + force) * V + (side_force0 + side_force) * V2) * step;
    if constexpr (Dim == 3)
      if (side_walls) {
        const double back_force0 = back_force;
        back_force = st.wall_force[5][1];  // on the back wall (+y) [N], which moves in at V3
        work += back_force * V3 * step;
        trapezoid += 0.5 * (back_force0 + back_force) * V3 * step;
      }
    const auto e = exact(t);
    const double scale = std::max(std::abs(e.s11), std::abs(e.s22));
    const Mat<Dim> se = sigma_exact(e);
    double worst = 0;
    for (std::size_t p = 0; p < model.points.size(); ++p) {
      const double dJ = std::abs(model.points.F[p].determinant() - e.J);
      r.run_worst_J = std::max(r.run_worst_J, dJ);
      worst = std::max({worst, dJ, std::abs(model.points.sigma[p](0, 0) - e.s11) / scale,
                        std::abs(model.points.sigma[p](up, up) - e.s22) / scale});
      if constexpr (Dim == 3)
        worst = std::max(worst, (model.points.sigma[p] - se).cwiseAbs().maxCoeff() /
                                    std::max(scale, std::abs(e.sbb)));
    }
    if (worst > 1e-3 && r.lost_at == 1.0) r.lost_at = e.s;
    after_step(e.s, static_cast<const mpm::Model<Dim>&>(model));
    return true;
  };
  for (int k = 0; k < steps; ++k)
    if (!advance(dt, 0)) {
      r.converged = false;
      std::printf(
          "  lambda %.3g MPa: failed at s = %.4f (%s), first half step at s = %.4f, "
          "state lost at s = %.4f\n",
          lambda / 1e6, exact(t).s, r.failure.c_str(), r.first_retry_at, r.lost_at);
      return r;
    }
  const auto e = exact(t);
  const double sf = e.s, a = e.a, J = e.J, s11 = e.s11, s22 = e.s22;
  const double s11_scale = V2 > 0 ? std::abs(s11) : std::abs(s22);
  const Mat<Dim> se = sigma_exact(e);
  const double all_scale = se.cwiseAbs().maxCoeff();
  for (std::size_t p = 0; p < model.points.size(); ++p) {
    r.worst_J = std::max(r.worst_J, std::abs(model.points.F[p].determinant() - J));
    r.worst_sigma =
        std::max(r.worst_sigma, std::abs(model.points.sigma[p](up, up) - s22) / std::abs(s22));
    r.worst_sigma11 =
        std::max(r.worst_sigma11, std::abs(model.points.sigma[p](0, 0) - s11) / s11_scale);
    if constexpr (Dim == 3)
      r.worst_sigma_yy = std::max(r.worst_sigma_yy, std::abs(model.points.sigma[p](1, 1) - e.sbb) /
                                                        std::max(std::abs(e.sbb), std::abs(s22)));
    r.worst_sigma_all =
        std::max(r.worst_sigma_all, (model.points.sigma[p] - se).cwiseAbs().maxCoeff() / all_scale);
  }
  // The loaded faces' areas: a W0 (top) and s H0 (right) in 2D [m], times b W0 in 3D [m^2]
  const double depth = Dim == 2 ? 1.0 : e.b * H0;
  r.force_error = std::abs(force - (-s22 * a * H0 * depth)) / std::abs(s22 * a * H0 * depth);
  if (V2 > 0)
    r.side_force_error =
        std::abs(side_force - (-s11 * sf * H0 * depth)) / std::abs(s11 * sf * H0 * depth);
  if (V3 > 0) {
    const double back_area = a * H0 * sf * H0;
    r.back_force_error = std::abs(back_force - (-e.sbb * back_area)) / std::abs(e.sbb * back_area);
  }
  const auto d = mpm::diagnostics(model);
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  r.last_step_work = (force * V + side_force * V2 + back_force * V3) * dt / work;
  r.energy_ratio = (d.elastic + d.kinetic - d0.elastic - d0.kinetic) / work;
  r.trapezoid_ratio = (d.elastic + d.kinetic - d0.elastic - d0.kinetic) / trapezoid;
  r.contact_dissipation = (work - contact_work) / work;
  r.transfer_dissipation = transfer / work;
  r.bulk_dissipation = (-stress_work - (d.elastic - d0.elastic)) / work;
  std::printf(
      "  lambda %.3g MPa, s = %.3f: max |J - J_exact| = %.2e, max rel. sigma22 error = %.2e, "
      "top force error = %.2e, (elastic + kinetic change) / wall work = %.5f (one step's final "
      "work %.5f), contact "
      "dissipation / wall work = %.2e, transfers %.2e, bulk %.2e, %d steps "
      "redone as half steps (first at s = %.4f), %lld factorisations (%lld projected) for %lld "
      "solves; state lost (1e-3) at s = %.4f; %.1f s\n",
      lambda / 1e6, sf, r.worst_J, r.worst_sigma, r.force_error, r.energy_ratio, r.last_step_work,
      r.contact_dissipation, r.transfer_dissipation, r.bulk_dissipation, r.retries,
      r.first_retry_at, static_cast<long long>(r.factorizations),
      static_cast<long long>(r.projected), static_cast<long long>(r.solves), r.lost_at, r.seconds);
  if (r.retries > 0) std::printf("  first half steps after: %s\n", r.first_failure.c_str());
  if (V2 > 0)
    std::printf(
        "  biaxial a = %.4f: max rel. sigma11 error = %.2e, right force error = %.2e, (elastic + "
        "kinetic change) / trapezoid wall work = %.6f\n",
        a, r.worst_sigma11, r.side_force_error, r.trapezoid_ratio);
  if constexpr (Dim == 3)
    std::printf(
        "  3D, %lld points: max |sigma - sigma_exact| (every component) / max |sigma_exact| = "
        "%.2e, max |J - J_exact| over the run = %.2e, (elastic + kinetic change) / trapezoid wall "
        "work = %.6f\n",
        static_cast<long long>(r.points), r.worst_sigma_all, r.run_worst_J, r.trapezoid_ratio);
  if (V3 > 0)
    std::printf("  triaxial b = %.4f: max rel. sigma_yy error = %.2e, back force error = %.2e\n",
                e.b, r.worst_sigma_yy, r.back_force_error);
  return r;
}

// The same without an observer.
template <int Dim>
BlockResult squeeze_block(const Squeeze& c) {
  return squeeze_block<Dim>(c, [](double, const mpm::Model<Dim>&) {});
}

// Runs `all` by `squeeze` without each of the three parts of docs/accuracy.md's diagnosis (walls
// on the points' faces, CPDI shapes, the affine P2G) and expects the exact state lost: the worst
// relative stress error above 1e-2, 1e-2 and 1e-5.
template <class Squeezer>
void expect_each_ingredient_needed(const Squeeze& all, Squeezer&& squeeze) {
  auto without = all;
  without.wall_points = false;
  const auto nodes = squeeze(without);
  without = all;
  without.shape = grid::ShapeKind::kLinear;
  const auto linear = squeeze(without);
  without = all;
  without.affine = false;
  const auto plain = squeeze(without);
  EXPECT_GT(nodes.worst_sigma, 1e-2);
  EXPECT_GT(linear.worst_sigma, 1e-2);
  EXPECT_GT(plain.worst_sigma, 1e-5);
}

}  // namespace mpmcd::test_support
