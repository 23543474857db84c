// The squeezed disk against the FE reference (tests/support/squeezed_disk.hpp) under refinement,
// R/h = 10, 20, 40, with node walls, and its dependence on dt and the wall speed. Long: 19 min
// (convergence) and 3 min (halving) with 1 thread on the 2-core machine under load, 6 min for the
// face walls' halving at three lambdas (ctest --preset long).
#include <map>

#include "../../support/squeezed_disk.hpp"

using namespace mpmcd::test_support::squeeze;

TEST(SqueezeFeLong, CpdiAffineForceConvergesToTheFiniteElementSolution) {
  for (double lambda : {0.0, 3e6}) {
    std::map<int, DiskRun> runs;
    for (int rh : {10, 20, 40}) {
      runs[rh] = run_disk(rh, lambda, 5e-6, kSpeed);
      print(fmt::format("lambda {:g} MPa, R/h = {}", lambda / 1e6, rh), runs[rh]);
    }
    const double e10 = worst(runs[10]), e20 = worst(runs[20]), e40 = worst(runs[40]);
    std::printf("  lambda %g MPa: worst |force/FE - 1| = %.4f, %.4f, %.4f (observed order %.2f)\n",
                lambda / 1e6, e10, e20, e40, std::log2((e10 - e20) / std::max(e20 - e40, 1e-12)));
    // Issue 14: within 3 % of the FE force at R/h = 40 for Delta/D in [0.05, 0.4]; the elastic
    // energy at least 98 % of the walls' work (at 0.01 c_s here; the issue asks 0.005 c_s).
    EXPECT_LT(e40, 0.03);
    EXPECT_LE(e40, e10);
    EXPECT_GT(runs[20].stored, 0.98);
    EXPECT_GT(runs[40].stored, 0.98);
  }
}

TEST(SqueezeFeLong, HalvingTheStepOrTheWallSpeedChangesTheForceByLessThanOnePercent) {
  const DiskRun base = run_disk(20, 0.0, 5e-6, kSpeed), fine = run_disk(20, 0.0, 2.5e-6, kSpeed),
                slow = run_disk(20, 0.0, 5e-6, 0.5 * kSpeed);
  print("R/h = 20, dt = 5 us", base);
  print("R/h = 20, dt = 2.5 us", fine);
  print("R/h = 20, half speed", slow);
  for (std::size_t k = 0; k < kStations.size(); ++k) {
    EXPECT_NEAR(fine.ratio[k] / base.ratio[k], 1.0, 0.01) << "Delta/D = " << kStations[k];
    EXPECT_NEAR(slow.ratio[k] / base.ratio[k], 1.0, 0.01) << "Delta/D = " << kStations[k];
  }
}

// The same refinement with the walls on the points' faces (contact.wall_contact = "points"):
// issue 14 asks the force within 3 % of the FE solution at R/h = 40 and at least 98 % of the wall
// work stored; the observed order of the error at each station is printed.
namespace {
void face_wall_refinement(double lambda, int points_per_cell = 2,
                          const std::string& contact_solver = "gauss_seidel") {
  std::map<int, DiskRun> runs;
  for (int rh : {10, 20, 40}) {
    runs[rh] = run_disk(rh, lambda, 5e-6, kSpeed, "points", points_per_cell, contact_solver);
    print(fmt::format("lambda {:g} MPa, R/h = {}, face walls, {} points per cell, {}", lambda / 1e6,
                      rh, points_per_cell, contact_solver),
          runs[rh]);
  }
  std::string orders;
  for (std::size_t k = 0; k < kStations.size(); ++k) {
    const double e10 = runs[10].ratio[k] - 1, e20 = runs[20].ratio[k] - 1,
                 e40 = runs[40].ratio[k] - 1;
    orders += fmt::format("  {:.2f}: {:.2f}", kStations[k],
                          std::log2(std::abs(e10 - e20) / std::max(std::abs(e20 - e40), 1e-12)));
  }
  std::printf("  lambda %g MPa: worst |force/FE - 1| = %.4f, %.4f, %.4f; observed order%s\n",
              lambda / 1e6, worst(runs[10]), worst(runs[20]), worst(runs[40]), orders.c_str());
  EXPECT_LT(worst(runs[40]), 0.03);
  for (int rh : {10, 20, 40}) EXPECT_GT(runs[rh].stored, 0.98) << "R/h = " << rh;
  // Issue 14: the contact half-width within one cell of the FE one, on the refined grids (at
  // R/h = 10 the lambda = 100 MPa disk at 3 points per cell misses it by 0.12 h at one output,
  // Delta/D = 0.354; the default suite checks R/h = 10 at 2 points per cell).
  for (int rh : {20, 40}) {
    EXPECT_GE(runs[rh].half_width.size(), 7u) << "R/h = " << rh;
    EXPECT_LT(worst_half_width(runs[rh]), kRadius / rh) << "R/h = " << rh;
  }
}
}  // namespace

// lambda / mu = 0 and 2 (seen: worst error 1.2 / 0.3 / 0.2 % and 0.9 / 0.5 / 0.7 % at R/h = 10,
// 20, 40; stored 99.0-99.5 %).
TEST(SqueezeFeLong, FaceWallsForceConvergesToTheFiniteElementSolution) {
  for (double lambda : {0.0, 3e6}) face_wall_refinement(lambda);
}

// lambda / mu = 66.7 (docs/accuracy.md, "Point splitting"): with 2 points per cell the force
// at Delta/D = 0.39 falls below the FE force as the grid is refined (0.993 / 0.986 / 0.970 of it
// at R/h = 10 / 20 / 40 with point splitting and the active-set solver; 0.962 at R/h = 40 when
// stretched domains were shrunk), an error of the number of points per cell (splitting more
// points, or all, removes it). With 3 points per cell (seen 2026-11-27): 1.0014 / 0.9977 / 0.9920
// at 0.39, worst error over the stations 5.2 / 1.05 / 0.80 %, stored 99.1 / 99.0 / 98.6 %, no
// failed step, 290 s on one thread; contact half-width within 1.12 / 0.60 / 0.79 h of the FE one.
TEST(SqueezeFeLong, FaceWallsForceConvergesForANearlyIncompressibleDiskAtThreePointsPerCell) {
  face_wall_refinement(1e8, 3, "active_set");
}

// Issue 14: for lambda / mu = 0, 2 and 66.7, the face-wall disk at R/h = 20 (2 points per cell,
// as in the default suite's R/h = 10 test) run three times to Delta/D = 0.4: at 0.01 c_s with
// dt = 5 us, at half the wall speed (0.005 c_s) and with half the step. At 0.005 c_s the grains
// store at least 98 % of the walls' work; halving the speed or the step moves the force by less
// than 1 % at every station. Seen (2026-11-27, 339 s on one thread): stored 99.56 / 99.57 /
// 99.16 % at 0.005 c_s (99.26 / 99.21 / 98.55 % at 0.01 c_s); the largest change of the force,
// 0.14 % (lambda = 100 MPa, Delta/D = 0.39, half speed).
TEST(SqueezeFeLong, FaceWallsAtHalfTheSpeedStoreTheWorkAndHalvingTheSpeedOrStepKeepsTheForce) {
  for (double lambda : {0.0, 3e6, 1e8}) {
    const std::string label = fmt::format("lambda {:g} MPa, R/h = 20, face walls", lambda / 1e6);
    const DiskRun base = run_disk(20, lambda, 5e-6, kSpeed, "points"),
                  slow = run_disk(20, lambda, 5e-6, 0.5 * kSpeed, "points"),
                  fine = run_disk(20, lambda, 2.5e-6, kSpeed, "points");
    print(label + ", 0.01 c_s, dt = 5 us", base);
    print(label + ", 0.005 c_s, dt = 5 us", slow);
    print(label + ", 0.01 c_s, dt = 2.5 us", fine);
    EXPECT_GE(slow.stored, 0.98) << "lambda " << lambda;
    EXPECT_LE(slow.stored, 1.0) << "lambda " << lambda;
    for (std::size_t k = 0; k < kStations.size(); ++k) {
      EXPECT_NEAR(slow.ratio[k] / base.ratio[k], 1.0, 0.01)
          << "lambda " << lambda << ", half speed, Delta/D = " << kStations[k];
      EXPECT_NEAR(fine.ratio[k] / base.ratio[k], 1.0, 0.01)
          << "lambda " << lambda << ", half step, Delta/D = " << kStations[k];
    }
  }
}
