// The squeezed disk against the FE reference (tests/support/squeezed_disk.hpp) with the walls on
// the points' faces (contact.wall_contact = "points", CPDI + affine P2G) at R/h = 10, for
// lambda / mu = 0, 2 and 66.7: the force within 2 % of the FE force over Delta/D = 0.05-0.39 and
// at least 98 % of the walls' work stored (docs/accuracy.md, "The squeezed disk"), and the contact
// half-width (the span of the top wall's active contacts in the contacts VTU, 8 outputs) within
// one cell of the FE half-width from Delta/D = 0.05 on. The refinement study is in long_squeeze_fe.
#include "../../support/squeezed_disk.hpp"

using namespace mpmcd::test_support::squeeze;

TEST(SqueezeFe, FaceWallsForceWithinTwoPercentOfTheFiniteElementSolutionAtTenCellsPerRadius) {
  for (double lambda : {0.0, 3e6, 1e8}) {
    const DiskRun r = run_disk(10, lambda, 5e-6, kSpeed, "points");
    print(fmt::format("lambda {:g} MPa, R/h = 10, face walls", lambda / 1e6), r);
    EXPECT_LT(worst(r), 0.02) << "lambda " << lambda;
    EXPECT_GT(r.stored, 0.98) << "lambda " << lambda;
    EXPECT_LE(r.stored, 1.0) << "lambda " << lambda;
    EXPECT_GE(r.half_width.size(), 7u) << "lambda " << lambda;
    EXPECT_LT(worst_half_width(r), kRadius / 10) << "lambda " << lambda;
  }
}
