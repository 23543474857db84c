// Coarse 2D Hertz (method.md §7): the polar-seeded disk of long_hertz/test_hertz.cpp at 10 and 20
// cells per diameter (linear shapes), squeezed to Delta/D = 0.05 between a fixed bottom wall and a
// top wall moving down at 0.3 m/s (0.004 c_p). Checks: the loading is quasi-static (the two
// window-averaged wall forces agree, the kinetic energy is small), no point domain goes deeper than
// 0.1 h into a wall, and the RMS error against Hertz over 0.005 <= Delta/D <= 0.05 at least halves
// from 10 to 20 cells per diameter. Default suite (about 13 s).
#include <gtest/gtest.h>

#include "../../support/contact_builders.hpp"

using namespace mpmcd;
using namespace mpmcd::test_support;

TEST(HertzCoarse, QuasiStaticAndErrorHalvesFrom10To20CellsPerDiameter) {
  std::vector<double> errs;
  for (int cpd : {10, 20}) {
    SqueezeSetup su;
    su.cells_per_diameter = cpd;
    su.polar = true;
    su.wall_speed = 0.3;
    su.courant = 0.25;
    su.final_approach = 0.05 * 2 * su.radius;
    su.samples = 10;
    const auto r = run_squeeze(su);
    ASSERT_TRUE(r.ok) << r.failure;
    print_hertz("linear", su, r, 0.02, 0.05);
    errs.push_back(hertz_rms_error(su, r, 0.005, 0.05));
    double sum = 0, pen = 0;
    int n = 0;
    for (const auto& s : r.curve) {
      pen = std::max(pen, s.penetration / r.h);
      if (s.delta >= 0.02 * r.diameter) {
        sum += std::pow((s.p_top - s.p_bottom) / SqueezeResult::load(s), 2);
        ++n;
      }
    }
    const double balance = std::sqrt(sum / n);
    const auto& last = r.curve.back();
    std::printf(
        "  quasi-static: RMS (P_top - P_bottom) / P = %.3f, final Ekin/Eel = %.2e, deepest point "
        "domain in a wall %.3f h\n",
        balance, last.kinetic / last.elastic, pen);
    EXPECT_LT(balance, 0.05);
    EXPECT_LT(last.kinetic / last.elastic, 0.02);
    EXPECT_LT(pen, 0.1);
  }
  std::printf("  Hertz RMS error 10 -> 20 cells/D: %.3f -> %.3f (ratio %.2f)\n", errs[0], errs[1],
              errs[0] / errs[1]);
  EXPECT_GT(errs[0] / errs[1], 2.0);
}
