// 3D Hertz (issue 18): the shell-seeded Neo-Hookean sphere of support/sphere_squeeze.hpp (R = 5
// mm, E = 4 MPa, nu = 1/3, E* = E / (1 - nu^2) = 4.5 MPa for a sphere on a rigid flat) pressed by
// a rigid frictionless plate moving down at 0.3 m/s (0.004 c_p), the octant x, y, z > centre with
// symmetry planes (normal node velocities 0), theta = 1, c_p dt / h = 1, sparse LDL^T. Plate on the
// points' faces (CPDI + affine) at 10, 14 and 20 cells per diameter, and at the grid nodes (linear
// shapes) at 20, for 0.02 <= delta/D <= 0.05, against F = (4/3) E* sqrt(R) delta^{3/2} (Johnson eq.
// 4.23) and against the Neo-Hookean finite-element solution of the same sphere
// (tests/reference/sphere_on_plate), which is 10-19 % above that half-space formula at a given
// plate-to-centre approach. Checks: quasi-static; the face walls within 5 % of the finite-element
// reference at 20 cells per diameter (issue 18's tolerance; 3.0 % from the forces of the last run,
// 4.8 % against the linear sphere), their error smaller at 20
// than at 10 cells per diameter, and smaller than the node walls' at 20. Against the formula itself
// the face walls stay 10-14 % high at 20 cells per diameter (docs/three_d.md): issue 18's criterion
// as written, against the half-space formula, is not met, and a correct solution would not meet it.
// Long (12 minutes on a loaded 2-core machine).
#include <gtest/gtest.h>

#include "../../support/sphere_squeeze.hpp"

using namespace mpmcd;
using namespace mpmcd::test_support;

namespace {
// Runs one case and returns its largest error against the finite-element reference.
double run_case(int cpd, bool faces) {
  SphereSqueezeSetup su;
  su.cells_per_diameter = cpd;
  su.octant = true;
  su.face_walls = faces;
  const auto r = run_sphere_squeeze(su);
  EXPECT_TRUE(r.ok) << r.failure;
  print_sphere_hertz(faces ? "faces, CPDI + affine" : "nodes, linear", su, r, 0.02, 0.05);
  EXPECT_LT(sphere_kinetic_ratio(su, r, 0.02), 0.02);
  return sphere_hertz_error(su, r, 0.02, 0.05, /*fe=*/true);
}
}  // namespace

TEST(HertzSphereLong, FaceWallsWithinFivePercentOfTheFiniteElementSphereAt20CellsPerDiameter) {
  const double e10 = run_case(10, true), e14 = run_case(14, true), e20 = run_case(20, true);
  const double n20 = run_case(20, false);
  std::printf(
      "  largest |F/F_FE - 1| for 0.02 <= delta/D <= 0.05: faces 10 / 14 / 20 cells/D: %.3f / "
      "%.3f / %.3f; nodes 20 cells/D: %.3f\n",
      e10, e14, e20, n20);
  EXPECT_LT(e20, 0.05);
  EXPECT_LT(e20, e10);
  EXPECT_LT(e20, n20);
}
