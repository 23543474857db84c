// The CI version of examples/compaction_3d (compaction_3d_ci.toml) run through the command line as
// a user runs it: 30 frictionless Neo-Hookean spheres packed by DEM to Phi0 = 0.45 in a box of six
// frictionless walls, the top one moving down at 2 m/s, CPDI + affine, contact on the material
// surface (active set), stopped at Phi = 0.6. Checks: the initial Phi is the packing's, the
// identity ln(Vs/Vs0) = ln(Phi/Phi0) + eps holds at every row, the energy ledger closes, the
// grains store most of the wall work, the packing jams (Z above 4, the wall stress rising), and
// `mpmcd analyze` fits the run with the 3D K_p = lambda + 2 mu / 3.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include "mpmcd/analysis/time_series.hpp"

#include "../../support/cli_runner.hpp"
#include "../../support/scratch.hpp"

namespace fs = std::filesystem;

TEST(Compaction3D, TheCiExampleJamsStoresTheWorkAndKeepsTheVolumeIdentity) {
  const fs::path dir = mpmcd::test_support::scratch_path("compaction_3d");
  fs::remove_all(dir);
  const std::string input =
      std::string(MPMCD_SOURCE_DIR) + "/examples/compaction_3d/compaction_3d_ci.toml";
  const auto r = mpmcd::test_support::run("run -q -t 2 " + input + " -o " + dir.string());
  ASSERT_EQ(r.code, 0) << r.output;
  const auto csv = mpmcd::analysis::read_time_series((dir / "compaction_3d_ci.csv").string());
  const auto& phi = csv.column("phi");
  const auto& eps = csv.column("eps");
  const auto& ln_vs = csv.column("ln_Vs_Vs0");
  const auto& sigma = csv.column("sigma_bottom_over_Mp");
  const auto& z = csv.column("Z");
  const std::size_t n = csv.rows();
  ASSERT_GT(n, 20u);
  EXPECT_NEAR(phi[0], 0.45, 1e-9);  // packing.csv: Phi0 = 0.45 (mpmcd pack)
  EXPECT_GE(phi[n - 1], 0.6);
  double worst_identity = 0;
  for (std::size_t i = 0; i < n; ++i)
    worst_identity =
        std::max(worst_identity, std::abs(ln_vs[i] - (std::log(phi[i] / phi[0]) + eps[i])));
  EXPECT_LT(worst_identity, 1e-12);
  // Energy: the walls' work (only the top wall moves) against the elastic + kinetic change and
  // the ledger's dissipations; what the ledger leaves unaccounted is round-off.
  double work = 0;
  for (const char* w : {"left", "right", "bottom", "top", "front", "back"})
    work += csv.column(std::string("wall_") + w + "_work")[n - 1];
  const double stored = csv.column("energy_change")[n - 1] / work;
  const double unaccounted = csv.column("energy_unaccounted")[n - 1] / work;
  EXPECT_GT(work, 0.0);
  EXPECT_LT(std::abs(unaccounted), 1e-6);
  EXPECT_GT(stored, 0.6);
  // Jammed: Z (rattlers removed) above 4, the bottom wall's stress rising over the last quarter.
  EXPECT_GT(z[n - 1], 4.0);
  EXPECT_LT(sigma[n - 1], sigma[3 * n / 4]);
  EXPECT_LT(sigma[n - 1], -0.01);
  std::printf(
      "compaction 3D (CI): %zu rows, Phi %.4f -> %.4f, eps %.4f, ln(Vs/Vs0) %.5f "
      "(identity within %.2e), sigma/Mp %.5f, Z %.3f, stored %.3f of the wall work "
      "(unaccounted %.2e)\n",
      n, phi[0], phi[n - 1], eps[n - 1], ln_vs[n - 1], worst_identity, sigma[n - 1], z[n - 1],
      stored, unaccounted);
  // The analysis: the 3D wave modulus in the fit (K_p = lambda + 2 mu / 3 = 4 MPa).
  const auto a =
      mpmcd::test_support::run("analyze " + dir.string() + " -o " + (dir / "analysis").string());
  ASSERT_EQ(a.code, 0) << a.output;
  EXPECT_NE(a.output.find("(M_p = 6 MPa, K_p = 4 MPa)"), std::string::npos) << a.output;
  EXPECT_NE(a.output.find("eq. (10) fit: c1 = "), std::string::npos) << a.output;
  std::printf("%s", a.output.c_str());
  fs::remove_all(dir);
}
