// 3D Hertz (issue 18): the shell-seeded Neo-Hookean sphere of support/sphere_squeeze.hpp (R = 5
// mm, E = 4 MPa, nu = 1/3, E* = E / (1 - nu^2) = 4.5 MPa for a sphere on a rigid flat) pressed by
// a rigid frictionless plate moving down at 0.3 m/s (0.004 c_p), the octant x, y, z > centre with
// symmetry planes (normal node velocities 0), theta = 1, c_p dt / h = 1, sparse LDL^T, against
// F = (4/3) E* sqrt(R) delta^{3/2} (Johnson eq. 4.23) for 0.02 <= delta/D <= 0.05.
// Plate on the points' faces (CPDI + affine) at 10, 14 and 20 cells per diameter, and at the grid
// nodes (linear shapes) at 20. Checks: quasi-static; the error of the face walls falls from 10 to
// 20 cells per diameter; the face walls are closer to Hertz than the node walls at 20 cells.
// Issue 18 asks 5 % at >= 20 cells per diameter: NOT met yet (seen 14 % at 20, face walls; the
// error falls slowly, 37 % -> 16 % -> 14 %), so the bound asserted here is the one seen, 15 %, as a
// guard against regressions, not the criterion (docs/three_d.md, "Hertz for a sphere").
// Long (about 10 minutes on a loaded 2-core machine).
#include <gtest/gtest.h>

#include "../../support/sphere_squeeze.hpp"

using namespace mpmcd;
using namespace mpmcd::test_support;

namespace {
SphereSqueezeResult run_case(int cpd, bool faces, double& err) {
  SphereSqueezeSetup su;
  su.cells_per_diameter = cpd;
  su.octant = true;
  su.face_walls = faces;
  const auto r = run_sphere_squeeze(su);
  EXPECT_TRUE(r.ok) << r.failure;
  print_sphere_hertz(faces ? "faces, CPDI + affine" : "nodes, linear", su, r, 0.02, 0.05);
  err = sphere_hertz_error(su, r, 0.02, 0.05);
  EXPECT_LT(sphere_kinetic_ratio(su, r, 0.02), 0.02);
  return r;
}
}  // namespace

TEST(HertzSphereLong, FaceWallsConvergeTowardHertzAndBeatNodeWalls) {
  double e10 = 0, e14 = 0, e20 = 0, n20 = 0;
  run_case(10, true, e10);
  run_case(14, true, e14);
  run_case(20, true, e20);
  run_case(20, false, n20);
  std::printf(
      "  largest |F/F_Hertz - 1| for 0.02 <= delta/D <= 0.05: faces 10 / 14 / 20 cells/D: %.3f / "
      "%.3f / %.3f; nodes 20 cells/D: %.3f\n",
      e10, e14, e20, n20);
  EXPECT_LT(e20, e10);
  EXPECT_LT(e20, 0.15);  // seen 0.144; issue 18 asks 0.05 (not met)
  EXPECT_LT(e20, n20);
}
