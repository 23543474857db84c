// The run's count of shrunk CPDI domains (RunSummary::shrunk_steps, shrunk_domains_max;
// docs/accuracy.md): a free block stretched along x by its initial velocity gradient until its
// point domains (half a cell wide at 2 points per cell) span more than a cell reports them; the
// same block at rest reports none.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "../../support/scratch.hpp"
#include "mpmcd/app/simulation.hpp"
#include "mpmcd/core/log.hpp"
#include "mpmcd/io/load_config.hpp"

namespace fs = std::filesystem;

namespace {

// A 1 mm block of a very soft gel (mu = 1 Pa: it flies apart freely) on a 0.1 mm grid,
// 2 x 2 points per cell, with v_x = rate (x - c) [1/s], for 200 steps of 10 us.
mpmcd::app::RunSummary stretch(double rate, const std::string& name) {
  mpmcd::setup_logging(mpmcd::Verbosity::kQuiet);
  const fs::path dir = mpmcd::test_support::scratch_dir("shrunk", name);
  std::ostringstream in;
  in << "[simulation]\nname = \"stretch\"\n"
        "[grid]\norigin = [-4e-3, -1e-3]\nextent = [8e-3, 2e-3]\ncell_size = 1e-4\n"
        "shape_function = \"cpdi\"\n"
        "[[materials]]\nname = \"gel\"\nlaw = \"neo_hookean\"\ndensity = 990.0\nlambda = 0.0\n"
        "mu = 1.0\n"
        "[[grains]]\nshape = \"rectangle\"\nmaterial = \"gel\"\n"
        "min_corner = [-0.5e-3, -0.5e-3]\nmax_corner = [0.5e-3, 0.5e-3]\npoints_per_cell = 2\n"
        "[grains.initial]\ngradient = ["
     << rate
     << ", 0.0, 0.0, 0.0]\n"
        "[time]\ndt = 1e-5\nend_time = 2e-3\n"
        "[output]\nvtu = false\n";
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
  const auto stretched = stretch(2000.0, "stretched");
  EXPECT_EQ(stretched.steps, 200);
  EXPECT_GT(stretched.shrunk_steps, 100);
  EXPECT_LE(stretched.shrunk_steps, 150);
  EXPECT_EQ(stretched.shrunk_domains_max, 400);  // every point of the 10 x 10 cell block
  const auto rest = stretch(0.0, "rest");
  EXPECT_EQ(rest.steps, 200);
  EXPECT_EQ(rest.shrunk_steps, 0);
  EXPECT_EQ(rest.shrunk_domains_max, 0);
}
