// Coarse 2D Hertz (method.md §7), default suite: the disk of tests/verification/long_hertz at 10
// and 20 cells per diameter (linear shapes, 2x2 points per cell), squeezed to Delta/D = 0.05
// between a fixed bottom wall and a top wall moving down at 0.3 m/s (0.004 c_p). Checks: the
// loading is quasi-static (the two wall forces agree, the kinetic energy is small) and the error
// against Hertz shrinks at least by half from 10 to 20 cells per diameter. The 10 % acceptance at
// >= 20 cells per diameter is checked by the long test. About 30 s.
#include <gtest/gtest.h>

#include "../../support/contact_builders.hpp"

using namespace mpmcd;
using namespace mpmcd::test_support;

TEST(HertzCoarse, QuasiStaticAndErrorHalvesFrom10To20CellsPerDiameter) {
  std::vector<double> errs;
  for (int cpd : {10, 20}) {
    SqueezeSetup su;
    su.cells_per_diameter = cpd;
    su.wall_speed = 0.3;
    su.courant = 0.25;
    su.final_approach = 0.05 * 2 * su.radius;
    su.samples = 10;
    const auto r = run_squeeze(su);
    ASSERT_TRUE(r.ok) << r.failure;
    errs.push_back(print_hertz("linear", su, r, 0.02, 0.05));
    // Balance of the two wall forces (RMS over Delta/D >= 0.02; single samples jump by a few %
    // when the top wall passes a node row).
    double sum = 0;
    int n = 0;
    for (const auto& s : r.curve)
      if (s.delta >= 0.02 * r.diameter) {
        sum += std::pow((s.p_top - s.p_bottom) / SqueezeResult::load(s), 2);
        ++n;
      }
    const double balance = std::sqrt(sum / n);
    const auto& last = r.curve.back();
    std::printf("  quasi-static: RMS (P_top - P_bottom) / P = %.3f, final Ekin/Eel = %.2e\n",
                balance, last.kinetic / last.elastic);
    EXPECT_LT(balance, 0.05);
    EXPECT_LT(last.kinetic / last.elastic, 0.02);
  }
  std::printf("  Hertz error 10 -> 20 cells/D: %.3f -> %.3f (ratio %.2f)\n", errs[0], errs[1],
              errs[0] / errs[1]);
  EXPECT_GT(errs[0] / errs[1], 2.0);
}
