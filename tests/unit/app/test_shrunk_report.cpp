// CPDI domains wider than a cell (docs/accuracy.md, "Point splitting"): a free block stretched
// along x by its initial velocity gradient until its point domains (half a cell wide at 2 points
// per cell) span more than a cell. By default its points are split (RunSummary::split_points) and
// the free flight stays exact; with `split_points = false` the run counts the shrunk domains
// (RunSummary::shrunk_steps, shrunk_domains_max); the same block at rest reports neither.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "../../support/scratch.hpp"
#include "mpmcd/app/simulation.hpp"
#include "mpmcd/checkpoint/checkpoint.hpp"
#include "mpmcd/core/log.hpp"
#include "mpmcd/io/load_config.hpp"

namespace fs = std::filesystem;

namespace {

// A 1 mm block of a very soft gel (mu = 1 Pa: it flies apart nearly freely) on a 0.1 mm grid,
// 2 x 2 points per cell, with v_x = rate (x - c) [1/s], for 200 steps of 10 us.
// A gel of mu [Pa] (lambda = 0); `affine` sets [solver] affine.
mpmcd::app::RunSummary stretch(double rate, const std::string& name, bool split, double mu = 1.0,
                               bool affine = false) {
  mpmcd::setup_logging(mpmcd::Verbosity::kQuiet);
  const fs::path dir = mpmcd::test_support::scratch_dir("shrunk", name);
  std::ostringstream in;
  in << "[simulation]\nname = \"stretch\"\n"
        "[grid]\norigin = [-4e-3, -1e-3]\nextent = [8e-3, 2e-3]\ncell_size = 1e-4\n"
        "shape_function = \"cpdi\"\nsplit_points = "
     << (split ? "true" : "false")
     << "\n"
        "[[materials]]\nname = \"gel\"\nlaw = \"neo_hookean\"\ndensity = 990.0\nlambda = 0.0\n"
        "mu = "
     << mu
     << "\n"
        "[[grains]]\nshape = \"rectangle\"\nmaterial = \"gel\"\n"
        "min_corner = [-0.5e-3, -0.5e-3]\nmax_corner = [0.5e-3, 0.5e-3]\npoints_per_cell = 2\n"
        "[grains.initial]\ngradient = ["
     << rate
     << ", 0.0, 0.0, 0.0]\n"
        "[time]\ndt = 1e-5\nend_time = 2e-3\n"
        "[solver]\naffine = "
     << (affine ? "true" : "false") << "\n[output]\nvtu = false\n";
  const fs::path input = dir / "stretch.toml";
  std::ofstream(input) << in.str();
  mpmcd::app::RunOptions opt;
  opt.threads = 1;
  opt.quiet = true;
  opt.output_dir = (dir / "out").string();
  return mpmcd::app::run_simulation(mpmcd::io::load_config(input.string()), opt);
}

}  // namespace

TEST(ShrunkDomains, AStretchedBlockReportsThemABlockAtRestDoesNot) {
  // The points fly freely: F_xx = 1 + rate t, so the domains (0.5 h wide) are wider than a cell
  // from t = 0.5 ms (step 50) on, and then span three cells or two depending on where they lie;
  // wider than two cells from t = 1.5 ms (step 150) on, they all span three.
  const auto stretched = stretch(2000.0, "stretched", false);
  EXPECT_EQ(stretched.steps, 200);
  EXPECT_GT(stretched.shrunk_steps, 100);
  EXPECT_LE(stretched.shrunk_steps, 150);
  EXPECT_EQ(stretched.shrunk_domains_max, 400);  // every point of the 10 x 10 cell block
  EXPECT_EQ(stretched.split_points, 0);
  for (bool split : {false, true}) {
    const auto rest = stretch(0.0, split ? "rest_split" : "rest", split);
    EXPECT_EQ(rest.steps, 200);
    EXPECT_EQ(rest.shrunk_steps, 0);
    EXPECT_EQ(rest.shrunk_domains_max, 0);
    EXPECT_EQ(rest.split_points, 0);
  }
}

TEST(SplitPoints, AStretchedBlockSplitsItsPointsAndKeepsItsFreeFlightExact) {
  // F_xx = 1 + rate t reaches 2 at step 50 (the 400 points, whose domains are then a cell wide,
  // become 800) and 4 at step 150 (800 more): 1,200 splits, 1,600 points at F_xx = 5.
  const double rate = 2000.0;
  // mu = 1e-9 Pa: the tension that slows the free edges (3 m/s^2 over a cell at mu = 1 Pa, a 1 %
  // error in F by F_xx = 2) is negligible; the affine P2G carries the linear field exactly.
  const auto run = stretch(rate, "split", true, 1e-9, true);
  EXPECT_EQ(run.steps, 200);
  EXPECT_EQ(run.shrunk_steps, 0);
  EXPECT_EQ(run.split_points, 1200);
  ASSERT_FALSE(run.checkpoint.empty());
  const auto s = mpmcd::checkpoint::read(run.checkpoint);
  ASSERT_EQ(s.x.size(), 2u * 1600u);
  // Free flight: each point keeps its velocity, so v_x = rate (x - 0) / (1 + rate t) and
  // F_xx = 1 + rate t at every point, children included; the mass and area are the block's.
  const double fxx = 1.0 + rate * s.time;
  EXPECT_NEAR(fxx, 5.0, 1e-9);
  double worst_v = 0, worst_f = 0, mass = 0, area = 0;
  for (std::size_t p = 0; p < 1600; ++p) {
    worst_v = std::max(worst_v, std::abs(s.v[2 * p] - rate * s.x[2 * p] / fxx) / (0.5e-3 * rate));
    worst_v = std::max(worst_v, std::abs(s.v[2 * p + 1]) / (0.5e-3 * rate));
    worst_f = std::max(worst_f, std::abs(s.F[4 * p] - fxx));
    mass += s.mass[p];
    area += s.volume[p];
  }
  std::printf(
      "  free flight after 1,200 splits: worst |v - exact| / v_edge = %.2e, |F_xx - exact| "
      "= %.2e\n",
      worst_v, worst_f);
  EXPECT_LT(worst_v, 1e-9);
  EXPECT_LT(worst_f, 1e-9);
  EXPECT_NEAR(mass, 990.0 * 1e-6, 1e-15);
  EXPECT_NEAR(area, fxx * 1e-6, 1e-15);
}
