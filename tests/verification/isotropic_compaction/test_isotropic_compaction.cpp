// The CI version of examples/isotropic_compaction run through the command line as a user runs
// it: 20 soft frictionless disks in a box of four servo walls, contact on the material surface,
// the pressure stepped to P/mu = 0.05, 0.1, 0.2, 0.3, 0.4, 0.5 and held. Over the last third of
// every hold: Phi and phi_geometric rise with P, every wall's stress is within 1 % of its target,
// and the grains do not interpenetrate beyond the grid's trace.
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

TEST(IsotropicCompaction, PhiRisesWithPressureAndTheWallsHoldTheirTargets) {
  const fs::path dir = mpmcd::test_support::scratch_path("isotropic");
  fs::remove_all(dir);
  const std::string input =
      std::string(MPMCD_SOURCE_DIR) + "/examples/isotropic_compaction/isotropic_compaction_ci.toml";
  const auto r = mpmcd::test_support::run("run -t 1 " + input + " -o " + dir.string());
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("loading finished: loading stage 6 ('P/mu = 0.5')"), std::string::npos)
      << r.output;
  const auto csv =
      mpmcd::analysis::read_time_series((dir / "isotropic_compaction_ci.csv").string());
  const auto& t = csv.column("time");
  const auto& stage = csv.column("stage");
  const auto& phi = csv.column("phi");
  const auto& phi_geometric = csv.column("phi_geometric");
  const auto& overlap = csv.column("overlap_over_Vs");
  const char* walls[] = {"bottom", "top", "left", "right"};
  constexpr double kMu = 1.5e6;  // [Pa]
  const double p_over_mu[] = {0.05, 0.1, 0.2, 0.3, 0.4, 0.5};
  double last_phi = 0, last_geometric = 0;
  for (int k = 0; k < 6; ++k) {
    const double target = -p_over_mu[k] * kMu;
    // The hold: the rows of stage k + 1 (the ramp takes its first 20 us); its last third.
    double begin = 1e300, end = -1e300;
    for (std::size_t i = 0; i < csv.rows(); ++i)
      if (stage[i] == k + 1) begin = std::min(begin, t[i]), end = std::max(end, t[i]);
    ASSERT_LT(begin, end) << "stage " << k + 1 << " has no rows";
    double n = 0, mean_phi = 0, mean_geometric = 0, max_overlap = 0;
    double mean_stress[4] = {0, 0, 0, 0};
    for (std::size_t i = 0; i < csv.rows(); ++i) {
      if (stage[i] != k + 1 || t[i] < end - (end - begin) / 3) continue;
      n += 1;
      mean_phi += phi[i];
      mean_geometric += phi_geometric[i];
      max_overlap = std::max(max_overlap, overlap[i]);
      for (int w = 0; w < 4; ++w) {
        const std::string name = std::string("wall_") + walls[w];
        mean_stress[w] += csv.column(name + "_stress")[i];
        EXPECT_EQ(csv.column(name + "_target")[i], target) << name << " at t = " << t[i];
      }
    }
    ASSERT_GE(n, 20) << "stage " << k + 1;
    mean_phi /= n;
    mean_geometric /= n;
    EXPECT_GT(mean_phi, last_phi) << "Phi does not rise with P at P/mu = " << p_over_mu[k];
    EXPECT_GT(mean_geometric, last_geometric) << "P/mu = " << p_over_mu[k];
    last_phi = mean_phi;
    last_geometric = mean_geometric;
    // Interpenetration: with faces the domains of two grains overlap by O(h^2), 0.7 % of V_s at
    // P/mu = 0.05 to 1.9 % at 0.5 on this grid (0.16-0.48 % at half the cell size); the node
    // contact reached 6 % during a long hold at P/mu = 0.2 (examples/isotropic_compaction).
    EXPECT_LT(max_overlap, 0.025) << "P/mu = " << p_over_mu[k];
    std::printf(
        "  P/mu = %.2f: Phi = %.4f, phi_geometric = %.4f, overlap/V_s <= %.4f, wall stress / "
        "target:",
        p_over_mu[k], mean_phi, mean_geometric, max_overlap);
    for (int w = 0; w < 4; ++w) {
      mean_stress[w] /= n;
      std::printf(" %s %.4f", walls[w], mean_stress[w] / target);
      // 1 %: the servo's target once the packing has settled (docs/loading.md); the elastic
      // block holds it too (tests/verification/servo).
      EXPECT_NEAR(mean_stress[w], target, 0.01 * std::fabs(target))
          << walls[w] << " wall at P/mu = " << p_over_mu[k];
    }
    std::printf("\n");
  }
  fs::remove_all(dir);
}

// A loading error on the command line: exit 2, the file, line, key and expectation, no output.
TEST(IsotropicCompaction, ALoadingErrorExits2AndWritesNothing) {
  const fs::path dir = mpmcd::test_support::scratch_dir("isotropic", "bad");
  const std::string example =
      std::string(MPMCD_SOURCE_DIR) + "/examples/isotropic_compaction/isotropic_compaction_ci.toml";
  std::ifstream in(example);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string from = "{ name = \"left\", stress = -7.5e4 }";
  ASSERT_NE(text.find(from), std::string::npos);
  text.replace(text.find(from), from.size(), "{ name = \"lefft\", stress = -7.5e4 }");
  const std::string file = "file = \"packing_ci.csv\"";
  text.replace(text.find(file), file.size(),
               "file = \"" + std::string(MPMCD_SOURCE_DIR) +
                   "/examples/isotropic_compaction/packing_ci.csv\"");
  std::ofstream(dir / "case.toml") << text;
  const auto r = mpmcd::test_support::run("run " + (dir / "case.toml").string() + " -o " +
                                          (dir / "out").string());
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("case.toml:"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("key 'loading.stages[0].walls[2].name': unknown wall \"lefft\", "
                          "expected the name of a [[walls]] entry: bottom, top, left, right "
                          "(did you mean \"left\"?)"),
            std::string::npos)
      << r.output;
  EXPECT_FALSE(fs::exists(dir / "out"));
  fs::remove_all(dir);
}
