// The mirror test (docs/accuracy.md): two identical frictionless disks stacked between walls are,
// by symmetry, each one disk squeezed against a frictionless wall. `mpmcd run` on the one-disk box
// and on the two-disk stack (mirror.toml): at time 2t the stack's top wall must carry the force
// of the one-disk run at time t and have done twice its work. This checks grain-grain contact
// against wall contact through the paths users run (walls, contact, points crossing cells), and
// the energy ledger of both (stored fraction of the wall work).
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "mpmcd/analysis/time_series.hpp"

#include "../../support/cli_runner.hpp"
#include "../../support/scratch.hpp"

namespace fs = std::filesystem;

namespace {

// `text` with every `from` replaced by `to`.
std::string replace_all(std::string text, const std::string& from, const std::string& to) {
  for (auto at = text.find(from); at != std::string::npos; at = text.find(from, at + to.size()))
    text.replace(at, from.size(), to);
  return text;
}

// Runs `disks` stacked disks at cell size h [m] with `contact` added to the [contact] table (TOML
// lines); returns their CSV time series.
mpmcd::analysis::TimeSeries run_stack(int disks, double h, const std::string& contact) {
  std::ifstream in(std::string(MPMCD_TEST_DIR) + "/mirror.toml");
  std::stringstream ss;
  ss << in.rdbuf();
  std::string grains;
  for (int k = 0; k < disks; ++k)
    grains += "[[grains]]\nshape = \"disk\"\ncenter = [0.5e-4, " +
              fmt::format("{:.17g}", (k + 0.5) * 1e-4) +
              "]\nradius = 4.8e-5\nmaterial = \"gel\"\n\n";
  const double top = disks * 1e-4;
  std::string text = replace_all(ss.str(), "@GRAINS@", grains);
  text = replace_all(text, "@TOP_PLUS@", fmt::format("{:.17g}", top + 0.25e-3));
  text = replace_all(text, "@TOP@", fmt::format("{:.17g}", top));
  text = replace_all(text, "@CELL@", fmt::format("{:.17g}", h));
  text = replace_all(text, "[contact]\n", "[contact]\n" + contact);
  const fs::path dir = mpmcd::test_support::scratch_dir(
      "mirror",
      std::to_string(disks) + "_" + fmt::format("{:.17g}", h) + (contact.empty() ? "" : "_faces"));
  std::ofstream(dir / "mirror.toml") << text;
  const auto r = mpmcd::test_support::run("run -q -t 1 " + (dir / "mirror.toml").string() + " -o " +
                                          (dir / "out").string());
  EXPECT_EQ(r.code, 0) << r.output;
  return mpmcd::analysis::read_time_series((dir / "out" / "mirror.csv").string());
}

double at(const mpmcd::analysis::TimeSeries& s, const std::string& col, double t) {
  const auto &time = s.column("time"), &y = s.column(col);
  for (std::size_t i = 1; i < time.size(); ++i)
    if (time[i] >= t)
      return y[i - 1] + (y[i] - y[i - 1]) * (t - time[i - 1]) / (time[i] - time[i - 1]);
  return y.back();
}

struct Mirror {
  double work_ratio[3], force_ratio[3], stored1, stored2;
};

Mirror mirror(double h, const std::string& contact = "") {
  const auto one = run_stack(1, h, contact), two = run_stack(2, h, contact);
  Mirror m{};
  const double t_end = one.column("time").back();
  const double fracs[3] = {0.5, 0.7, 0.9};
  for (int k = 0; k < 3; ++k) {
    const double t = fracs[k] * t_end;
    m.work_ratio[k] = at(two, "wall_top_work", 2 * t) / (2 * at(one, "wall_top_work", t));
    m.force_ratio[k] = at(two, "wall_top_fy", 2 * t) / at(one, "wall_top_fy", t);
  }
  const auto stored = [](const mpmcd::analysis::TimeSeries& s) {
    double w = 0;
    for (const char* wall : {"bottom", "top", "left", "right"})
      w += s.column(std::string("wall_") + wall + "_work").back();
    return s.column("energy_change").back() / w;
  };
  m.stored1 = stored(one);
  m.stored2 = stored(two);
  std::printf(
      "  h = %.4g um%s: two-disk / one-disk work at 50/70/90 %% of the run %.3f %.3f %.3f, force "
      "%.3f %.3f %.3f; stored / wall work: one disk %.3f, two disks %.3f\n",
      h * 1e6, contact.empty() ? "" : " (faces)", m.work_ratio[0], m.work_ratio[1], m.work_ratio[2],
      m.force_ratio[0], m.force_ratio[1], m.force_ratio[2], m.stored1, m.stored2);
  return m;
}

}  // namespace

TEST(Mirror, TwoStackedDisksMatchOneDiskOnAWallAtEightCellsPerDiameter) {
  // d/4 (h = 25 um) is reported, not asserted: the grain-grain contact is about 15 % too soft
  // there (docs/accuracy.md, the open item); from d/8 on it agrees with the wall.
  mirror(25e-6);
  const Mirror m = mirror(12.5e-6);
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(m.work_ratio[k], 1.0, 0.06) << "at " << 50 + 20 * k << " % of the run";
    EXPECT_NEAR(m.force_ratio[k], 1.0, 0.1) << "at " << 50 + 20 * k << " % of the run";
  }
  EXPECT_GT(m.stored1, 0.97);
  EXPECT_GT(m.stored2, 0.94);
}

// Contact on the material surface (contact.grain_contact = "faces", with face walls): the
// grain-grain contact is as stiff as the wall already at d/4, where the node contact is 15 %
// too soft (seen: work ratio 0.996 / 0.942 / 0.943 at d/4, 0.979 / 0.963 / 0.971 and force
// ratio 0.966 / 1.008 / 0.959 at d/8; stored 0.945 / 0.899 at d/4, 0.971 / 0.951 at d/8).
TEST(Mirror, FaceContactsMatchTheWallFromFourCellsPerDiameter) {
  const std::string faces = "wall_contact = \"points\"\ngrain_contact = \"faces\"\n";
  const Mirror coarse = mirror(25e-6, faces);
  for (int k = 0; k < 3; ++k)
    EXPECT_NEAR(coarse.work_ratio[k], 1.0, 0.08) << "d/4, at " << 50 + 20 * k << " % of the run";
  EXPECT_GT(coarse.stored2, 0.93 * coarse.stored1);
  const Mirror fine = mirror(12.5e-6, faces);
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(fine.work_ratio[k], 1.0, 0.05) << "d/8, at " << 50 + 20 * k << " % of the run";
    EXPECT_NEAR(fine.force_ratio[k], 1.0, 0.06) << "d/8, at " << 50 + 20 * k << " % of the run";
  }
  EXPECT_GT(fine.stored2, 0.96 * fine.stored1);
}
