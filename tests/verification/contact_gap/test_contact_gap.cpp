// When does a grain-grain contact switch on? Two identical Neo-Hookean disks approach head-on
// slowly (no gravity); for each gap criterion (method.md §4: kGap, the gap from the points'
// domains; kOverlap, pure support overlap) we record the centre distance at the first step with a
// positive normal impulse, relative to the diameter D and in cells. The whole force-distance
// curves are written to a CSV file (docs/figures/contact_gap.png is drawn from it by
// tools/plot_contact_gap.py).
//
// HeadOnNormalPointsFromAToB guards the normal direction (it once pointed from B to A).
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "../../support/builders.hpp"

using namespace mpmcd;
using test_support::make_model;

namespace {

constexpr double kLambda = 3e6, kMu = 1.5e6, kRho = 990.0;

struct Sample {
  double distance;  // centre distance (centroids of the points) [m]
  double gap;       // material gap along the line of centres (point domains) [m]
  double force;     // normal contact force on disk B, sum_c p_n / dt [N/m]
  std::int64_t active;
};

struct Approach {
  double h = 0, diameter = 0;
  double first_distance = -1;  // centre distance at the end of the first step with a force [m]
  double first_gap = 0;        // material gap then [m]
  double step_closing = 0;     // relative approach per step [m]
  std::vector<Sample> curve;
};

const char* name_of(mpm::GapCriterion c) {
  return c == mpm::GapCriterion::kGap ? "gap" : "overlap";
}
const char* name_of(grid::ShapeKind s) {
  return s == grid::ShapeKind::kLinear ? "linear" : "ugimp";
}

// Disks of radius R = (cpd/2) h centred on nodes, 3 cells apart (surface to surface), each moving
// towards the other at v/2 with v dt = closing * h; 2x2 points per cell. Runs until the disks
// separate again (or max_steps).
Approach approach(mpm::GapCriterion criterion, grid::ShapeKind shape, int cpd = 10,
                  double closing = 0.01, int max_steps = 1000) {
  const double R = 5e-3, h = 2 * R / cpd;
  const int ppc = 2;
  const int nx = 2 * cpd + 3 + 8, ny = cpd + 8;
  auto model = make_model(h, nx, ny, "neo_hookean", kLambda, kMu, kRho);
  const double cp = std::sqrt((kLambda + 2 * kMu) / kRho);
  const double dt = 0.4 * h / cp, v = closing * h / dt;
  const Vec<2> ca((4 + cpd / 2) * h, (ny / 2) * h), cb = ca + Vec<2>((cpd + 3) * h, 0);
  const double lp = 0.5 * h / ppc;
  model.add_grain(points::seed_ball<2>(model.grid.origin(), h, ppc, ca, R), 0, lp,
                  [&](const Vec<2>&) { return Vec<2>(0.5 * v, 0); });
  model.add_grain(points::seed_ball<2>(model.grid.origin(), h, ppc, cb, R), 0, lp,
                  [&](const Vec<2>&) { return Vec<2>(-0.5 * v, 0); });
  mpm::Settings<2> s;
  s.shape = shape;
  s.theta = 1.0;
  s.contact.enabled = true;
  s.contact.criterion = criterion;
  mpm::ImplicitSolver<2> solver(model.grid, s, model.points, model.grains, model.law_ptrs());
  Approach out;
  out.h = h;
  out.step_closing = v * dt;
  const auto& pts = model.points;
  const auto measure = [&](double force, std::int64_t active) {
    Vec<2> xa = Vec<2>::Zero(), xb = Vec<2>::Zero();
    double ma = 0, mb = 0, right_a = -1e300, left_b = 1e300;
    for (std::size_t p = 0; p < pts.size(); ++p) {
      if (pts.grain[p] == 0) {
        xa += pts.mass[p] * pts.x[p];
        ma += pts.mass[p];
        right_a = std::max(right_a, pts.x[p][0] + lp * std::abs(pts.F[p](0, 0)));
      } else {
        xb += pts.mass[p] * pts.x[p];
        mb += pts.mass[p];
        left_b = std::min(left_b, pts.x[p][0] - lp * std::abs(pts.F[p](0, 0)));
      }
    }
    return Sample{(xb / mb - xa / ma)[0], left_b - right_a, force, active};
  };
  const Sample s0 = measure(0, 0);
  out.diameter = s0.distance - s0.gap;  // material extent along the line of centres: exactly 2R
  out.curve.push_back(s0);
  bool touched = false;
  for (int k = 0; k < max_steps; ++k) {
    solver.set_time(k * dt);
    const auto st = solver.solve_step(dt);
    EXPECT_TRUE(st.converged) << st.failure;
    if (!st.converged) break;
    solver.commit();
    double force = 0;
    for (const auto& c : solver.contact_problem().contacts) force += c.impulse.dot(c.normal) / dt;
    const Sample sm = measure(force, st.active_contacts);
    out.curve.push_back(sm);
    if (st.active_contacts > 0 && out.first_distance < 0) {
      out.first_distance = sm.distance;
      out.first_gap = sm.gap;
    }
    touched = touched || st.active_contacts > 0;
    if (touched && st.active_contacts == 0 && sm.gap > 0.5 * h) break;  // separated again
    if (sm.gap < -1.5 * h) break;  // interpenetrating: no contact force (a failure below)
  }
  return out;
}

}  // namespace

TEST(ContactGap, FirstForceDistancePerCriterion) {
  const std::string csv =
      (std::filesystem::temp_directory_path() / "mpmcd_contact_gap.csv").string();
  std::ofstream f(csv);
  f << "criterion,shape,cells_per_diameter,h,diameter,distance,gap,force,active\n";
  std::printf("  disks R = 5 mm, 2x2 points per cell, closing %.3f h per step\n", 0.01);
  std::printf("  %-8s %-7s %4s %14s %16s %14s\n", "criterion", "shape", "D/h", "first (d-D)/h",
              "first d/D", "gap/h then");
  for (int cpd : {10, 20}) {
    for (auto shape : {grid::ShapeKind::kLinear, grid::ShapeKind::kUGimp}) {
      for (auto crit : {mpm::GapCriterion::kGap, mpm::GapCriterion::kOverlap}) {
        const Approach a = approach(crit, shape, cpd);
        for (const auto& sm : a.curve)
          f << name_of(crit) << ',' << name_of(shape) << ',' << cpd << ',' << a.h << ','
            << a.diameter << ',' << sm.distance << ',' << sm.gap << ',' << sm.force << ','
            << sm.active << '\n';
        ASSERT_GT(a.first_distance, 0) << "no contact force";
        const double early = (a.first_distance - a.diameter) / a.h;
        // kGap: the force must appear when the point domains meet (measured: within 0.002 h at
        // 10 and 20 cells per diameter, one step closing 0.01 h). kOverlap: the supports share a
        // node before the materials meet (measured: 0.48 h early with linear shape functions,
        // 0.90 h with uGIMP, whose support is wider).
        if (crit == mpm::GapCriterion::kGap) {
          EXPECT_LT(std::abs(early), 0.05) << name_of(shape) << " D/h = " << cpd;
        } else {
          EXPECT_GT(early, 0.4) << name_of(shape) << " D/h = " << cpd;
        }
        std::printf("  %-8s %-7s %4d %14.3f %16.5f %14.3f\n", name_of(crit), name_of(shape), cpd,
                    early, a.first_distance / a.diameter, a.first_gap / a.h);
      }
    }
  }
  std::printf("  curves written to %s\n", csv.c_str());
}

// Minimal reproduction of the normal-direction bug: disk A (left) and B (right) half a cell apart,
// closing at 2 m/s, support-overlap criterion: the shared nodes' normals should point from A to B
// (+x) and the approaching disks get a positive impulse.
TEST(ContactGap, HeadOnNormalPointsFromAToB) {
  auto model = make_model(1e-3, 30, 16, "neo_hookean", kLambda, kMu, kRho);
  test_support::add_disk(model, Vec<2>(0.009, 0.008), 5e-3, 2,
                         [](const Vec<2>&) { return Vec<2>(1.0, 0); });
  test_support::add_disk(model, Vec<2>(0.0195, 0.008), 5e-3, 2,
                         [](const Vec<2>&) { return Vec<2>(-1.0, 0); });
  mpm::Settings<2> s;
  s.contact.enabled = true;
  s.contact.criterion = mpm::GapCriterion::kOverlap;
  mpm::ImplicitSolver<2> solver(model.grid, s, model.points, model.grains, model.law_ptrs());
  solver.set_time(0);
  const auto st = solver.solve_step(1e-6);
  ASSERT_TRUE(st.converged) << st.failure;
  const auto& pb = solver.contact_problem();
  for (const auto& c : pb.contacts)
    std::printf("  node %lld: n = (%+.3f, %+.3f), u_free.n = %+.3f m/s, p_n = %.3e N s\n",
                static_cast<long long>(pb.slots[c.b].node), c.normal[0], c.normal[1],
                (pb.slots[c.b].v_free - pb.slots[c.a].v_free).dot(c.normal),
                c.impulse.dot(c.normal));
  ASSERT_GT(st.contacts, 0);
  for (const auto& c : pb.contacts) EXPECT_GT(c.normal[0], 0.9);
  EXPECT_GT(st.active_contacts, 0);
}
