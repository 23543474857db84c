// Contact Dynamics verification (method.md §4, §7): a disk resting on a wall under gravity, the
// head-on impact of two disks, a block on a tilted-gravity wall (stick / slide / frictionless), and
// the replay of a stored contact problem from a real step.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <memory>
#include <numbers>

#include "../../support/builders.hpp"
#include "../../support/drivers.hpp"
#include "mpmcd/contact/problem.hpp"
#include "mpmcd/walls/wall.hpp"

using namespace mpmcd;
using test_support::add_box;
using test_support::add_disk;
using test_support::kCp;
using test_support::kLambda;
using test_support::kMu;
using test_support::kRho;
using test_support::make_model;

namespace {

mpm::Settings<2> contact_settings(std::vector<walls::Wall<2>> walls, double friction = 0.0) {
  mpm::Settings<2> s;
  s.theta = 1.0;
  s.linear_solver = mpm::LinearSolverKind::kLdlt;
  s.contact.enabled = true;
  s.contact.walls = std::move(walls);
  s.contact.friction = {friction};
  return s;
}

walls::Wall<2> bottom_wall(double y, double friction = 0.0) {
  return {"bottom", Vec<2>(0.0, y), Vec<2>(0.0, 1.0), Vec<2>::Zero(), friction};
}

}  // namespace

TEST(Contact, DiskRestingOnWallCarriesItsWeight) {
  const double h = 0.5e-3, R = 2e-3, y_wall = 4 * h;
  auto model = make_model(h, 20, 20, "neo_hookean", kLambda, kMu, kRho);
  add_disk(model, Vec<2>(0.005, y_wall + R), R, 2);
  auto s = contact_settings({bottom_wall(y_wall)});
  s.gravity = Vec<2>(0.0, -9.81);
  mpm::ImplicitSolver<2> solver(model.grid, s, model.points, model.grains, model.law_ptrs());
  const double dt = 0.5 * h / kCp, T = 0.012;
  const int steps = static_cast<int>(T / dt);
  const double weight = mpm::diagnostics(model).mass * 9.81;
  double impulse_sum = 0, late_impulse = 0, late_time = 0, last_impulse = 0, last_time = 0;
  const Vec<2> p0 = mpm::diagnostics(model).momentum;
  double last_force = 0;
  for (int k = 0; k < steps; ++k) {
    solver.set_time(k * dt);
    auto st = solver.solve_step(dt);
    ASSERT_TRUE(st.converged) << "step " << k << ": " << st.failure;
    solver.commit();
    const double wall_on_grain = -st.wall_force[0][1];  // reaction of the wall on the disk [N/m]
    impulse_sum += wall_on_grain * dt;
    if (k >= steps / 2) {
      late_impulse += wall_on_grain * dt;
      late_time += dt;
    }
    if (k >= steps - steps / 10) {
      last_impulse += wall_on_grain * dt;
      last_time += dt;
    }
    last_force = wall_on_grain;
  }
  const Vec<2> p1 = mpm::diagnostics(model).momentum;
  // Impulse balance: wall impulses - weight * T = change of momentum (exact up to round-off).
  const double balance = impulse_sum - weight * steps * dt - (p1[1] - p0[1]);
  std::printf("  %d steps of %.3e s; momentum balance residual %.2e (weight x T = %.3e N s/m)\n",
              steps, dt, balance, weight * steps * dt);
  std::printf(
      "  wall force / weight averaged over the second half %.5f, over the last tenth "
      "%.5f; last step %.5f\n",
      late_impulse / late_time / weight, last_impulse / last_time / weight, last_force / weight);
  EXPECT_LT(std::abs(balance), 1e-9 * weight * steps * dt);
  EXPECT_NEAR(late_impulse / late_time / weight, 1.0, 0.005);
  EXPECT_NEAR(last_impulse / last_time / weight, 1.0, 0.005);
}

TEST(Contact, HeadOnImpactConservesMomentumAndSeparates) {
  const double h = 0.25e-3, R = 2e-3, v0 = 1.0;
  auto model = make_model(h, 60, 30, "neo_hookean", kLambda, kMu, kRho);
  const double xa = 0.0075 - R - h, xb = 0.0075 + R + h, y = 0.00375;
  add_disk(model, Vec<2>(xa, y), R, 2, [&](const Vec<2>&) { return Vec<2>(v0, 0.0); });
  add_disk(model, Vec<2>(xb, y), R, 2, [&](const Vec<2>&) { return Vec<2>(-v0, 0.0); });
  auto s = contact_settings({});
  mpm::ImplicitSolver<2> solver(model.grid, s, model.points, model.grains, model.law_ptrs());
  const double dt = 0.5 * h / kCp;
  const double p_one = 0.5 * mpm::diagnostics(model).mass * v0;
  const auto r = test_support::head_on_impact(model, solver, dt, 4000, p_one);
  std::printf("  separated after %d steps: v_A = %.4f m/s, v_B = %.4f m/s (restitution %.3f)\n",
              r.steps, r.va, r.vb, (r.vb - r.va) / (2 * v0));
  std::printf(
      "  momentum drift %.2e of one disk's momentum; deepest material overlap %.3e m "
      "(%.3f cells)\n",
      r.worst_p, -r.min_gap, -r.min_gap / h);
  std::printf("  energy: initial %.6e J/m, final kinetic %.6e + elastic %.6e J/m (%.1f %% kept)\n",
              r.d0.kinetic + r.d0.elastic, r.d1.kinetic, r.d1.elastic,
              100 * (r.d1.kinetic + r.d1.elastic) / (r.d0.kinetic + r.d0.elastic));
  test_support::expect_clean_separation(r, h, 4000);
}

// contact.gap_horizon (docs/contact.md): the faces that cannot close within gap_horizon steps
// at twice the step's largest speed are left out of the contact problem. They are inactive at its
// solution, so the head-on impact with face contacts and the active-set solver must follow the
// same path with the cut as with every face within a cell (gap_horizon = 0), while the problems
// hold fewer contacts before and after the touch. (Which of two redundant faces, one per grain,
// carries an interface's impulse is not unique: the active counts may differ, the motion not.)
// Face contacts with the active-set solver, CPDI and affine P2G, as in the paper examples.
TEST(Contact, GapHorizonLeavesOutOnlyFacesThatCannotTouch) {
  const double h = 0.25e-3, R = 2e-3, v0 = 1.0;
  struct Run {
    mpm::Model<2> model;
    std::unique_ptr<mpm::ImplicitSolver<2>> solver;
  };
  const auto make = [&](double horizon) {
    auto run = std::make_unique<Run>();
    run->model = make_model(h, 60, 30, "neo_hookean", kLambda, kMu, kRho);
    const double xa = 0.0075 - R - 0.5 * h, xb = 0.0075 + R + 0.5 * h, y = 0.00375;
    add_disk(run->model, Vec<2>(xa, y), R, 2, [&](const Vec<2>&) { return Vec<2>(v0, 0.0); });
    add_disk(run->model, Vec<2>(xb, y), R, 2, [&](const Vec<2>&) { return Vec<2>(-v0, 0.0); });
    auto s = contact_settings({});
    s.shape = grid::ShapeKind::kCpdi;
    s.affine = true;
    s.contact.grain_faces = true;
    s.contact.active_set = true;
    s.contact.gap_horizon = horizon;
    run->solver = std::make_unique<mpm::ImplicitSolver<2>>(
        run->model.grid, s, run->model.points, run->model.grains, run->model.law_ptrs());
    return run;
  };
  auto cut = make(4.0), all = make(0.0);
  const double dt = 0.5 * h / kCp;
  std::int64_t contacts_cut = 0, contacts_all = 0;
  double worst_dx = 0;
  int touching = 0;
  for (int k = 0; k < 200; ++k) {
    mpm::StepStats st[2];
    for (int r = 0; r < 2; ++r) {
      auto& run = r == 0 ? *cut : *all;
      run.solver->set_time(k * dt);
      st[r] = run.solver->solve_step(dt);
      ASSERT_TRUE(st[r].converged) << "step " << k << ": " << st[r].failure;
      run.solver->commit();
    }
    touching += st[0].active_contacts > 0;
    contacts_cut += st[0].contacts;
    contacts_all += st[1].contacts;
    for (std::size_t i = 0; i < cut->model.points.x.size(); ++i)
      worst_dx = std::max(worst_dx, (cut->model.points.x[i] - all->model.points.x[i]).norm());
  }
  std::printf(
      "  200 steps, %d touching: contacts %lld with the horizon against %lld; largest point "
      "position difference %.2e m (%.2e cells)\n",
      touching, static_cast<long long>(contacts_cut), static_cast<long long>(contacts_all),
      worst_dx, worst_dx / h);
  EXPECT_GT(touching, 20);
  EXPECT_LT(static_cast<double>(contacts_cut), 0.8 * static_cast<double>(contacts_all));
  // Seen: 2.6e-6 cells for gap_horizon = 1, 2 and 4 alike (the solver tolerances' trace); a cut
  // that misses faces (gap_horizon = 0.3) gives 2.5e-3 cells.
  EXPECT_LT(worst_dx, 2e-5 * h);
}

namespace {
// Block (8 x 2 mm) on a wall with gravity tilted by alpha; returns the mean acceleration along the
// wall over [T/2, T] from the momentum, and the largest tangential impulse seen.
struct SlideResult {
  double accel = 0, max_tangential = 0;
};
SlideResult slide(double alpha_deg, double mu, double T) {
  const double h = 0.5e-3, y_wall = 4 * h, g = 9.81, a = alpha_deg * std::numbers::pi / 180;
  auto model = make_model(h, 40, 16, "neo_hookean", kLambda, kMu, kRho);
  add_box(model, Vec<2>(0.004, y_wall), Vec<2>(0.012, y_wall + 0.002), 2);
  auto s = contact_settings({bottom_wall(y_wall, mu)});
  s.gravity = Vec<2>(g * std::sin(a), -g * std::cos(a));
  mpm::ImplicitSolver<2> solver(model.grid, s, model.points, model.grains, model.law_ptrs());
  const double dt = 0.5 * h / kCp;
  const int steps = static_cast<int>(T / dt);
  SlideResult r;
  double p_half = 0, t_half = 0;
  for (int k = 0; k < steps; ++k) {
    solver.set_time(k * dt);
    auto st = solver.solve_step(dt);
    EXPECT_TRUE(st.converged) << st.failure;
    if (!st.converged) return r;
    solver.commit();
    for (const auto& c : solver.contact_problem().contacts)
      r.max_tangential = std::max(r.max_tangential, std::abs(c.impulse[0]));
    if (k == steps / 2) {
      p_half = mpm::diagnostics(model).momentum[0];
      t_half = (k + 1) * dt;
    }
  }
  const auto d = mpm::diagnostics(model);
  r.accel = (d.momentum[0] - p_half) / (d.mass * (steps * dt - t_half));
  return r;
}
}  // namespace

TEST(Contact, BlockSticksBelowFrictionAngleAndSlidesAbove) {
  const double g = 9.81, mu = 0.3;
  const SlideResult stick = slide(10.0, mu, 0.01);
  std::printf("  alpha = 10 deg, mu = 0.3 (tan alpha = %.3f < mu): mean acceleration %.4e m/s^2\n",
              std::tan(10 * std::numbers::pi / 180), stick.accel);
  EXPECT_LT(std::abs(stick.accel), 0.01 * g * std::sin(10 * std::numbers::pi / 180));
  const double a30 = 30 * std::numbers::pi / 180;
  const double expected = g * (std::sin(a30) - mu * std::cos(a30));
  const SlideResult sl = slide(30.0, mu, 0.01);
  std::printf(
      "  alpha = 30 deg, mu = 0.3: acceleration %.5f m/s^2, g (sin a - mu cos a) = %.5f "
      "(error %.2f %%)\n",
      sl.accel, expected, 100 * std::abs(sl.accel - expected) / expected);
  EXPECT_NEAR(sl.accel, expected, 0.02 * expected);
  const SlideResult free = slide(30.0, 0.0, 0.004);
  std::printf(
      "  alpha = 30 deg, mu = 0: acceleration %.5f (g sin a = %.5f), largest tangential "
      "impulse %.1e\n",
      free.accel, g * std::sin(a30), free.max_tangential);
  EXPECT_EQ(free.max_tangential, 0.0);
  EXPECT_NEAR(free.accel, g * std::sin(a30), 0.02 * g * std::sin(a30));
}

TEST(Contact, ReplayedStoredProblemConvergesToTheSameImpulses) {
  const double h = 0.25e-3, R = 2e-3;
  auto model = make_model(h, 60, 30, "neo_hookean", kLambda, kMu, kRho);
  add_disk(model, Vec<2>(0.0075 - R - 0.5 * h, 0.00375), R, 2,
           [](const Vec<2>&) { return Vec<2>(1.0, 0.2); });
  add_disk(model, Vec<2>(0.0075 + R + 0.5 * h, 0.00375), R, 2,
           [](const Vec<2>&) { return Vec<2>(-1.0, 0.0); });
  auto s = contact_settings({}, 0.2);
  s.contact.gs.tolerance = 1e-10;
  mpm::ImplicitSolver<2> solver(model.grid, s, model.points, model.grains, model.law_ptrs());
  const double dt = 0.5 * h / kCp;
  int active = 0;
  for (int k = 0; k < 200 && active < 3; ++k) {
    solver.set_time(k * dt);
    auto st = solver.solve_step(dt);
    ASSERT_TRUE(st.converged) << st.failure;
    solver.commit();
    active = static_cast<int>(st.active_contacts);
  }
  ASSERT_GE(active, 3);
  const auto stored = solver.contact_problem();
  const auto path = (std::filesystem::temp_directory_path() / "mpmcd_replay.txt").string();
  contact::write_problem(stored, path);
  auto replay = contact::read_problem<2>(path);
  for (auto& c : replay.contacts) c.impulse.setZero();  // cold start
  const auto r = contact::solve_gauss_seidel(replay, s.contact.gs);
  ASSERT_TRUE(r.converged);
  double diff = 0, norm = 0;
  for (std::size_t c = 0; c < stored.contacts.size(); ++c) {
    diff += (replay.contacts[c].impulse - stored.contacts[c].impulse).squaredNorm();
    norm += stored.contacts[c].impulse.squaredNorm();
  }
  std::printf("  %zu contacts (%d active), replay: %d sweeps, relative impulse difference %.2e\n",
              stored.contacts.size(), active, r.sweeps, std::sqrt(diff / norm));
  EXPECT_LT(contact::error(stored), 1e-10);
  EXPECT_LT(std::sqrt(diff / norm), 1e-8);
}
