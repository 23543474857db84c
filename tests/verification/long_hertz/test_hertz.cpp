// 2D Hertz (method.md §7): a Neo-Hookean disk (R = 5 mm, mu = 1.5 MPa, lambda = 3 MPa,
// rho = 990 kg/m^3) seeded on rings (polar seeding, so that its outline is a circle and not the
// lattice's staircase) squeezed quasi-statically between two rigid frictionless walls (bottom
// fixed, top moving down at 0.3 m/s = 0.004 c_p), no gravity, theta = 1, 2 points per cell and
// axis, c_p dt / h = 0.25. The walls start on the extreme point domains (zero gaps), so the loss
// of diameter is the top wall's travel. The load is the mean of the two wall forces, each
// averaged over the sampling window. Acceptance: within 10 % of Hertz for
// 0.02 <= Delta/D <= 0.05 at 20 and 40 cells per diameter (linear shapes) and at 20 (uGIMP); the
// RMS error over the whole curve 0.005 <= Delta/D <= 0.05 shrinks from 20 to 40 cells per
// diameter. Long (about 6 minutes on an idle machine).
#include <gtest/gtest.h>

#include "../../support/contact_builders.hpp"

using namespace mpmcd;
using namespace mpmcd::test_support;

namespace {
SqueezeSetup hertz_setup(int cpd, grid::ShapeKind shape) {
  SqueezeSetup su;
  su.cells_per_diameter = cpd;
  su.shape = shape;
  su.polar = true;
  su.wall_speed = 0.3;
  su.courant = 0.25;
  su.final_approach = 0.05 * 2 * su.radius;
  su.samples = 10;
  return su;
}
}  // namespace

TEST(HertzLong, LinearShapesWithinTenPercentAt20And40CellsPerDiameter) {
  std::vector<double> worst, rms;
  for (int cpd : {20, 40}) {
    const auto su = hertz_setup(cpd, grid::ShapeKind::kLinear);
    const auto r = run_squeeze(su);
    ASSERT_TRUE(r.ok) << r.failure;
    worst.push_back(print_hertz("linear", su, r, 0.02, 0.05));
    rms.push_back(hertz_rms_error(su, r, 0.005, 0.05));
  }
  std::printf(
      "  Hertz error, max over 0.02 <= Delta/D <= 0.05: 20 cells/D %.3f, 40 cells/D %.3f; RMS "
      "over 0.005 <= Delta/D <= 0.05: %.3f -> %.3f\n",
      worst[0], worst[1], rms[0], rms[1]);
  EXPECT_LT(worst[0], 0.10);
  EXPECT_LT(worst[1], 0.10);
  EXPECT_LT(rms[1], rms[0]);
}

TEST(HertzLong, UGimpShapesWithinTenPercentAt20CellsPerDiameter) {
  const auto su = hertz_setup(20, grid::ShapeKind::kUGimp);
  const auto r = run_squeeze(su);
  ASSERT_TRUE(r.ok) << r.failure;
  EXPECT_LT(print_hertz("ugimp", su, r, 0.02, 0.05), 0.10);
}
