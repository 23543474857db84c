// Dynamic verification of the implicit step: free vibration of a bar in uniaxial strain against
// T1 = 4 L / c_p (method.md §7), energy behaviour of theta = 1/2 and theta = 1, convergence of the
// period under grid refinement, quadratic Newton convergence, mass and momentum conservation.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "../../support/builders.hpp"

using namespace mpmcd;
using test_support::add_box;
using test_support::add_disk;
using test_support::kCp;
using test_support::kLambda;
using test_support::kMu;
using test_support::kRho;
using test_support::make_model;

namespace {

struct BarResult {
  double period = 0;  // measured first period [s]
  double energy0 = 0, energy_end = 0;
  double max_rise = 0;   // largest step-to-step relative energy increase
  double max_drift = 0;  // largest |E - E0| / E0 over the run
};

// Bar of length L in uniaxial strain (v_y = 0 everywhere), fixed at x0, free at x0 + L, started in
// its first mode v = v0 sin(pi (x - x0) / (2L)). Period measured from zero crossings of the
// momentum.
BarResult run_bar(int cells, double steps_per_period, double periods, double theta,
                  grid::ShapeKind shape = grid::ShapeKind::kLinear) {
  const double L = 0.1, h = L / cells;
  const double T = 4 * L / kCp;
  auto model = make_model(h, cells + 4, 6, "neo_hookean", kLambda, kMu, kRho);
  const double x0 = 2 * h;
  const double v0 = 1e-4 * kCp;  // strain amplitude 1e-4
  add_box(model, Vec<2>(x0, 2 * h), Vec<2>(x0 + L, 4 * h), 2, [&](const Vec<2>& x) {
    return Vec<2>(v0 * std::sin(std::numbers::pi * (x[0] - x0) / (2 * L)), 0.0);
  });
  mpm::Settings<2> s;
  s.theta = theta;
  s.shape = shape;
  mpm::ImplicitSolver<2> solver(model.grid, s, model.points, model.grains, model.law_ptrs());
  mpm::VelocityBC<2> lateral, end;
  lateral.nodes = test_support::all_nodes(model.grid);
  lateral.mask = 0b10;
  // The fixed end: the node plane at x0 and, for uGIMP whose support reaches one node further,
  // the plane behind it (a wall is everything at or beyond x0).
  end.nodes = test_support::plane_nodes(model.grid, 0, 2);
  for (auto n : test_support::plane_nodes(model.grid, 0, 1)) end.nodes.push_back(n);
  end.mask = 0b01;
  solver.set_boundary_conditions({lateral, end});
  const double dt = T / steps_per_period;
  const int nsteps = static_cast<int>(std::round(periods * steps_per_period));
  BarResult r;
  auto d = mpm::diagnostics(model);
  r.energy0 = d.kinetic + d.elastic;
  double e_prev = r.energy0, p_prev = d.momentum[0];
  std::vector<double> crossings;
  for (int k = 1; k <= nsteps; ++k) {
    auto st = solver.solve_step(dt);
    EXPECT_TRUE(st.converged) << st.failure;
    if (!st.converged) return r;
    solver.commit();
    d = mpm::diagnostics(model);
    const double e = d.kinetic + d.elastic, p = d.momentum[0];
    r.max_rise = std::max(r.max_rise, (e - e_prev) / r.energy0);
    r.max_drift = std::max(r.max_drift, std::abs(e - r.energy0) / r.energy0);
    if ((p_prev > 0) != (p > 0)) crossings.push_back(dt * (k - 1 + p_prev / (p_prev - p)));
    e_prev = e;
    p_prev = p;
  }
  r.energy_end = e_prev;
  if (crossings.size() >= 3) {
    // consecutive crossings are half a period apart
    r.period = 2 * (crossings.back() - crossings.front()) / (crossings.size() - 1);
  }
  return r;
}

}  // namespace

TEST(Dynamics, BarPeriodMatchesAnalyticalWithin2Percent) {
  const double T = 4 * 0.1 / kCp;
  for (auto shape : {grid::ShapeKind::kLinear, grid::ShapeKind::kUGimp}) {
    BarResult r = run_bar(20, 100, 3, 0.5, shape);
    const double err = std::abs(r.period - T) / T;
    std::printf("  bar, 20 cells, %s: T = %.6e s, analytical 4L/c_p = %.6e s, error %.3f %%\n",
                shape == grid::ShapeKind::kLinear ? "linear" : "ugimp", r.period, T, 100 * err);
    EXPECT_LT(err, 0.02);
  }
}

TEST(Dynamics, TrapezoidalEnergyDriftBelowOnePercentOver10Periods) {
  BarResult r = run_bar(20, 60, 10, 0.5);
  std::printf("  theta = 1/2: E0 = %.6e J, E_end = %.6e J, max |E - E0|/E0 = %.3e\n", r.energy0,
              r.energy_end, r.max_drift);
  EXPECT_LT(r.max_drift, 0.01);
}

TEST(Dynamics, BackwardEulerEnergyDecaysMonotonically) {
  BarResult r = run_bar(20, 60, 3, 1.0);
  std::printf(
      "  theta = 1: E_end / E0 = %.4f, largest step increase %.2e E0 (expected decay "
      "exp(-pi w dt) per period)\n",
      r.energy_end / r.energy0, r.max_rise);
  EXPECT_LE(r.max_rise, 1e-12);
  EXPECT_LT(r.energy_end, 0.9 * r.energy0);
}

TEST(Dynamics, PeriodErrorConvergesUnderGridRefinement) {
  const double T = 4 * 0.1 / kCp;
  std::vector<double> errs;
  std::vector<int> cells = {5, 10, 20, 40};
  for (int c : cells) {
    // dt proportional to h (steps per period = 5 * cells): time and space errors both O(h^2)
    BarResult r = run_bar(c, 5.0 * c, 2, 0.5);
    errs.push_back(std::abs(r.period - T) / T);
  }
  for (std::size_t i = 0; i < cells.size(); ++i) {
    std::printf("  cells = %2d  h = %.4e m  period error = %.4e", cells[i], 0.1 / cells[i],
                errs[i]);
    if (i > 0) std::printf("  rate = %.2f", std::log(errs[i - 1] / errs[i]) / std::log(2.0));
    std::printf("\n");
  }
  const double rate = std::log(errs[1] / errs.back()) / std::log(4.0);
  std::printf("  observed convergence rate (10 -> 40 cells): %.2f\n", rate);
  EXPECT_GT(rate, 1.7);
  EXPECT_LT(errs.back(), errs.front());
}

TEST(Dynamics, NewtonConvergesQuadratically) {
  // A disk hit by a strong compressive velocity field with a large step: a nonlinear step.
  auto model = make_model(0.01, 30, 30, "neo_hookean", kLambda, kMu, kRho);
  const Vec<2> c(0.15, 0.15);
  add_disk(model, c, 0.08, 2, [&](const Vec<2>& x) { return Vec<2>(-20.0 * (x - c)); });
  mpm::Settings<2> s;
  s.theta = 1.0;
  s.residual_tolerance = 1e-12;
  s.increment_tolerance = 1e-12;
  s.modified_newton = false;  // full Newton: a new tangent every iteration
  mpm::ImplicitSolver<2> solver(model.grid, s, model.points, model.grains, model.law_ptrs());
  auto st = solver.solve_step(4e-3);
  ASSERT_TRUE(st.converged) << st.failure;
  std::printf("  Newton residual history (|R| / reference):");
  for (double r : st.residual_history) std::printf(" %.3e", r);
  std::printf("\n");
  const auto& h = st.residual_history;
  ASSERT_GE(h.size(), 4u);
  // Quadratic: once in the asymptotic range (r < 1e-3), r_{k+1} <= C r_k^2 with a moderate C.
  int checked = 0;
  for (std::size_t k = 0; k + 1 < h.size(); ++k) {
    if (h[k] < 1e-3 && h[k] > 1e-11 && h[k + 1] > 1e-15) {
      const double order = std::log(h[k + 1]) / std::log(h[k]);
      std::printf("  k = %zu: order log r_{k+1} / log r_k = %.2f\n", k, order);
      EXPECT_GT(order, 1.7);
      ++checked;
    }
  }
  EXPECT_GE(checked, 1);
}

TEST(Dynamics, ModifiedNewtonReachesTheSameStateAsFullNewton) {
  // The same nonlinear step with the default modified Newton (Settings::modified_newton): more,
  // cheaper iterations (the stall rule refactorises when the residual falls by less than half),
  // the same converged velocities and deformation gradients.
  std::vector<mpm::Model<2>> models;
  std::vector<mpm::StepStats> stats;
  for (const bool modified : {false, true}) {
    auto model = make_model(0.01, 30, 30, "neo_hookean", kLambda, kMu, kRho);
    const Vec<2> c(0.15, 0.15);
    add_disk(model, c, 0.08, 2, [&](const Vec<2>& x) { return Vec<2>(-20.0 * (x - c)); });
    mpm::Settings<2> s;
    s.residual_tolerance = s.increment_tolerance = 1e-12;
    s.modified_newton = modified;
    mpm::ImplicitSolver<2> solver(model.grid, s, model.points, model.grains, model.law_ptrs());
    stats.push_back(solver.solve_step(4e-3));
    ASSERT_TRUE(stats.back().converged) << stats.back().failure;
    solver.commit();
    models.push_back(std::move(model));
  }
  std::printf("  full: %d iterations, %lld factorisations; modified: %d iterations, %lld\n",
              stats[0].iterations, static_cast<long long>(stats[0].factorizations),
              stats[1].iterations, static_cast<long long>(stats[1].factorizations));
  EXPECT_LT(stats[1].factorizations, stats[0].factorizations);
  double dv = 0, vmax = 0, dF = 0;
  for (std::size_t p = 0; p < models[0].points.size(); ++p) {
    dv = std::max(dv, (models[0].points.v[p] - models[1].points.v[p]).norm());
    vmax = std::max(vmax, models[0].points.v[p].norm());
    dF = std::max(dF, (models[0].points.F[p] - models[1].points.F[p]).norm());
  }
  EXPECT_LT(dv, 1e-9 * vmax);
  EXPECT_LT(dF, 1e-10);
}

TEST(Dynamics, MassExactAndMomentumConservedWithoutBoundaryConditions) {
  for (auto shape : {grid::ShapeKind::kLinear, grid::ShapeKind::kUGimp}) {
    auto model = make_model(0.01, 30, 30, "neo_hookean", kLambda, kMu, kRho);
    const Vec<2> c(0.15, 0.15);
    add_disk(model, c, 0.06, 2, [&](const Vec<2>& x) {
      const Vec<2> r = x - c;
      return Vec<2>(3.0 + 40.0 * r[1] + 5.0 * std::sin(60 * x[0]), -2.0 - 40.0 * r[0]);
    });
    add_disk(model, Vec<2>(0.07, 0.07), 0.03, 3,
             [&](const Vec<2>& x) { return Vec<2>(std::cos(80 * x[1]), 1.0); });
    mpm::Settings<2> s;
    s.shape = shape;
    s.theta = 0.5;
    mpm::ImplicitSolver<2> solver(model.grid, s, model.points, model.grains, model.law_ptrs());
    const auto d0 = mpm::diagnostics(model);
    const auto masses = model.points.mass;
    double worst_p = 0, worst_field_mass = 0;
    for (int k = 0; k < 40; ++k) {
      auto st = solver.solve_step(2e-4);
      ASSERT_TRUE(st.converged) << st.failure;
      double field_mass = 0;
      for (std::size_t g = 0; g < model.grains.size(); ++g) field_mass += solver.field_mass(g);
      worst_field_mass = std::max(worst_field_mass, std::abs(field_mass - d0.mass) / d0.mass);
      solver.commit();
      const auto d = mpm::diagnostics(model);
      worst_p = std::max(worst_p, (d.momentum - d0.momentum).norm() / d0.momentum.norm());
    }
    EXPECT_EQ(masses, model.points.mass);  // point masses never change: bitwise
    std::printf("  %s: max relative nodal-mass error %.2e, momentum drift %.2e over 40 steps\n",
                shape == grid::ShapeKind::kLinear ? "linear" : "ugimp", worst_field_mass, worst_p);
    EXPECT_LT(worst_field_mass, 1e-13);
    EXPECT_LT(worst_p, 1e-11);
  }
}

TEST(Dynamics, GravityChangesMomentumByWeightTimesTime) {
  auto model = make_model(0.01, 30, 30, "neo_hookean", kLambda, kMu, kRho);
  add_disk(model, Vec<2>(0.15, 0.15), 0.05, 2);
  mpm::Settings<2> s;
  s.gravity = Vec<2>(0.0, -9.81);
  mpm::ImplicitSolver<2> solver(model.grid, s, model.points, model.grains, model.law_ptrs());
  const auto d0 = mpm::diagnostics(model);
  const double dt = 1e-4;
  for (int k = 0; k < 20; ++k) {
    ASSERT_TRUE(solver.solve_step(dt).converged);
    solver.commit();
  }
  const auto d = mpm::diagnostics(model);
  const double expected = -9.81 * d0.mass * 20 * dt;
  EXPECT_NEAR(d.momentum[1], expected, 1e-10 * std::abs(expected));
  EXPECT_NEAR(d.momentum[0], 0.0, 1e-12 * std::abs(expected));
}

TEST(Dynamics, TranslatedBlockStaysUnstrainedAcrossTenCells) {
  // A free block moving at a uniform velocity across 10 cells (points crossing grid lines every
  // few steps, boundary nodes with little mass): J = 1 and sigma = 0 to 1e-8 with every shape
  // family, with and without the affine P2G (issue 14).
  constexpr double h = 1e-4, V = 0.5;
  for (const auto shape :
       {grid::ShapeKind::kLinear, grid::ShapeKind::kUGimp, grid::ShapeKind::kCpdi})
    for (const bool affine : {false, true}) {
      auto model = make_model(h, 20, 20, "neo_hookean", kLambda, kMu, kRho);
      add_box(model, Vec<2>(3.3 * h, 4.1 * h), Vec<2>(7.3 * h, 8.1 * h), 2,
              [&](const Vec<2>&) { return Vec<2>(V, V / 3); });
      mpm::Settings<2> s;
      s.shape = shape;
      s.affine = affine;
      s.residual_tolerance = s.increment_tolerance = 1e-12;
      mpm::ImplicitSolver<2> solver(model.grid, s, model.points, model.grains, model.law_ptrs());
      const double dt = 0.37 * h / V;  // 27 steps over 10 cells
      for (int k = 0; k < 27; ++k) {
        solver.set_time(k * dt);
        const auto st = solver.solve_step(dt);
        ASSERT_TRUE(st.converged) << st.failure;
        solver.commit();
      }
      double dJ = 0, sig = 0, dv = 0;
      for (std::size_t p = 0; p < model.points.size(); ++p) {
        dJ = std::max(dJ, std::abs(model.points.F[p].determinant() - 1.0));
        sig = std::max(sig, model.points.sigma[p].norm() / kMu);
        dv = std::max(dv, (model.points.v[p] - Vec<2>(V, V / 3)).norm() / V);
      }
      std::printf(
          "  shape %d, affine %d: max |J - 1| = %.2e, max |sigma| / mu = %.2e, max |dv| / V "
          "= %.2e\n",
          static_cast<int>(shape), affine ? 1 : 0, dJ, sig, dv);
      EXPECT_LT(dJ, 1e-8);
      EXPECT_LT(sig, 1e-8);
      EXPECT_LT(dv, 1e-8);
    }
}
