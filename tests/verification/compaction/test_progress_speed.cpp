// Issue 17, items 5 and 8, on the tiny compaction (compaction.toml: 9 disks, top wall down at
// 5 m/s, stop at Phi = 0.8). The progress line follows the criterion that will end the run (the
// [stop] criterion, or end_time when it comes first) and shows Phi, the top wall stress and Z; a
// wall, or a material point, faster than a fraction of the grains' wave speed is reported (the
// issue's case: a top wall at 80 m/s, c = 77.85 m/s), a normal compaction is not; an energy
// ledger that does not close (work from outside it) is reported.
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "mpmcd/app/model_builder.hpp"
#include "mpmcd/app/progress.hpp"
#include "mpmcd/app/speed_check.hpp"
#include "mpmcd/io/load_config.hpp"

#include "../../support/cli_runner.hpp"
#include "../../support/scratch.hpp"

namespace fs = std::filesystem;

namespace {

using mpmcd::test_support::Result;
using mpmcd::test_support::run;

fs::path scratch(const std::string& name) {
  return mpmcd::test_support::scratch_dir("progress", name);
}

std::string tiny_input() {
  std::ifstream in(std::string(MPMCD_TEST_DIR) + "/compaction.toml");
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// `text` with its first `from` replaced by `to` (which must be there).
std::string with(std::string text, const std::string& from, const std::string& to) {
  const auto at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  if (at != std::string::npos) text.replace(at, from.size(), to);
  return text;
}

// Writes `text` (the tiny compaction, changed) with its packing into `dir`; returns the input.
fs::path write_case(const fs::path& dir, const std::string& text) {
  fs::copy_file(fs::path(MPMCD_TEST_DIR) / "packing.csv", dir / "packing.csv",
                fs::copy_options::overwrite_existing);
  std::ofstream(dir / "case.toml") << text;
  return dir / "case.toml";
}

// The progress lines of a run's output ("... ETA ...").
std::vector<std::string> progress_lines(const std::string& output) {
  std::vector<std::string> lines;
  std::istringstream in(output);
  for (std::string line; std::getline(in, line);)
    if (line.find(" ETA ") != std::string::npos) lines.push_back(line);
  return lines;
}

// The percentage of a progress line: "t = 1.84e-04 s ( 98.8% of stop.phi = 0.8)".
double percent(const std::string& line) {
  const auto at = line.find(" s (");
  return at == std::string::npos ? -1 : std::strtod(line.c_str() + at + 4, nullptr);
}

// Every line has a percentage of `criterion`; they do not decrease; the last one is >= `last`.
void expect_progress(const std::vector<std::string>& lines, const std::string& criterion,
                     double last) {
  ASSERT_GT(lines.size(), 20u);
  double before = 0;
  for (std::size_t k = 1; k < lines.size(); ++k) {  // the first has no rate yet
    EXPECT_NE(lines[k].find("% of " + criterion), std::string::npos) << lines[k];
    EXPECT_GE(percent(lines[k]), before - 0.05) << lines[k];
    before = percent(lines[k]);
  }
  EXPECT_GE(percent(lines.back()), last) << lines.back();
  EXPECT_LE(percent(lines.back()), 100.0) << lines.back();
}

}  // namespace

// The case: a compaction stopping at Phi printed "16.9 %" just before it stopped (here
// 46 %: t / end_time). Now the last line before the stop (Phi = 0.7976 of 0.8) says 98.8 %.
TEST(Progress, FollowsTheStopCriterionAndShowsTheCompactionState) {
  const fs::path dir = scratch("phi");
  const std::string text = tiny_input() + "progress_interval = 1e-9\n";  // [output] is last
  const Result r =
      run("run -t 1 " + write_case(dir, text).string() + " -o " + (dir / "out").string());
  ASSERT_EQ(r.code, 0) << r.output;
  ASSERT_NE(r.output.find("stop.phi reached"), std::string::npos) << r.output;
  const auto lines = progress_lines(r.output);
  expect_progress(lines, "stop.phi = 0.8", 95.0);
  // Phi, the top wall's stress (compressive once the grains touch it) and Z.
  const std::string& last = lines.back();
  const auto phi = last.find("Phi = ");
  ASSERT_NE(phi, std::string::npos) << last;
  EXPECT_NEAR(std::strtod(last.c_str() + phi + 6, nullptr), 0.8, 0.005) << last;
  EXPECT_NE(last.find("sigma_top = -"), std::string::npos) << last;
  EXPECT_NE(last.find(" Pa  Z = "), std::string::npos) << last;
  // A normal compaction (wall at 0.064 c) is not reported as too fast, and its ledger closes.
  EXPECT_EQ(r.output.find("wave speed"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("ledger does not close"), std::string::npos) << r.output;
}

// Issue 17, item 8 (energy part): work the ledger cannot see is reported. The tiny compaction
// pushed by a moving grid platen ([[boundary]] box) instead of its top wall: the walls do no work
// while the grains gain energy, so the ledger's remainder is that of the platen.
TEST(Ledger, WorkOfPrescribedGridVelocitiesIsReportedAsNotClosing) {
  const fs::path dir = scratch("platen");
  std::string text = with(tiny_input(), "velocity = [0.0, -5.0]\n", "");
  text = with(text, "point = [0.0, 3.2e-3]", "point = [0.0, 3.45e-3]");
  text = with(text, "end_time = 4e-4", "end_time = 1e-4");
  text = with(text, "[[walls]]\nname = \"bottom\"",
              "[[boundary]]\nnodes = \"box\"\nbox_min = [-0.25e-3, 3.2e-3]\n"
              "box_max = [3.25e-3, 3.5e-3]\nfix = [\"x\", \"y\"]\nvelocity = [0.0, -5.0]\n"
              "moving = true\n\n[[walls]]\nname = \"bottom\"");
  const Result r =
      run("run -t 1 " + write_case(dir, text).string() + " -o " + (dir / "out").string());
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("[W] the energy ledger does not close"), std::string::npos) << r.output;
}

// When end_time comes before the [stop] criterion, the progress follows end_time.
TEST(Progress, FollowsTheTimeLimitWhenItComesFirst) {
  const fs::path dir = scratch("time");
  const std::string text =
      with(tiny_input(), "end_time = 4e-4", "end_time = 1e-4") + "progress_interval = 1e-9\n";
  const Result r =
      run("run -t 1 " + write_case(dir, text).string() + " -o " + (dir / "out").string());
  ASSERT_EQ(r.code, 0) << r.output;
  ASSERT_EQ(r.output.find("stop.phi reached"), std::string::npos) << r.output;
  expect_progress(progress_lines(r.output), "end_time = 0.0001 s", 95.0);
}

// The estimator on synthetic samples: each criterion's fraction from the start of the run, the
// ETA from the recent rate, the criterion expected first.
TEST(Progress, EstimatorPicksTheCriterionExpectedFirst) {
  using mpmcd::app::ProgressEstimator;
  using mpmcd::app::ProgressSample;
  mpmcd::io::StopSection stop;
  stop.phi = 0.9;
  stop.stress = 1e6;
  // Phi from 0.6 at 1e-3 per wall second, t at 1e-6 s per second, stress only after 100 s.
  ProgressEstimator p(1.0, stop, 0.6);
  for (int k = 0; k <= 200; ++k) {
    const double w = k;
    ProgressSample s{w, 1e-6 * w, 0.6 + 1e-3 * w, std::nullopt, std::nullopt};
    if (k > 100) s.stress = 1e3 * (w - 100);
    p.add(s);
  }
  auto e = p.estimate();
  EXPECT_EQ(e.criterion, "stop.phi");
  EXPECT_NEAR(e.fraction, 0.2 / 0.3, 1e-12);
  EXPECT_NEAR(e.eta, 100.0, 1e-6);  // 0.1 left at 1e-3 per second
  EXPECT_LT(p.samples(), 80u);      // only the recent window is kept
  // The rate is the recent one: Phi now grows ten times slower; stress (ETA 900 s) still later.
  for (int k = 201; k <= 400; ++k) {
    const double w = k;
    p.add({w, 1e-6 * w, 0.8 + 1e-4 * (w - 200), std::nullopt, 1e3 * (w - 100)});
  }
  e = p.estimate();
  EXPECT_EQ(e.criterion, "stop.stress");
  EXPECT_NEAR(e.fraction, 0.3, 1e-12);
  EXPECT_NEAR(e.eta, 700.0, 1e-6);  // 7e5 Pa left at 1e3 Pa/s; Phi: 0.08 left at 1e-4/s = 800 s
  // No stop criterion: end_time.
  ProgressEstimator q(2.0, mpmcd::io::StopSection{}, 0.0);
  q.add({0, 0, std::nullopt, std::nullopt, std::nullopt});
  q.add({10, 0.5, std::nullopt, std::nullopt, std::nullopt});
  e = q.estimate();
  EXPECT_EQ(e.criterion, "end_time");
  EXPECT_NEAR(e.fraction, 0.25, 1e-12);
  EXPECT_NEAR(e.eta, 30.0, 1e-9);
  EXPECT_EQ(mpmcd::app::format_eta(e.eta), "30 s");
  EXPECT_EQ(mpmcd::app::format_eta(std::nan("")), "?");
}

// The case: a top wall at 80 m/s, faster than the wave speed c = sqrt((lambda + 2 mu) /
// rho) = 77.85 m/s, reached Phi = 0.97 silently. Both warnings, once each.
TEST(Speed, AWallAndPointsFasterThanTheWaveSpeedAreReported) {
  const fs::path dir = scratch("fast");
  const std::string text =
      with(with(tiny_input(), "velocity = [0.0, -5.0]", "velocity = [0.0, -80.0]"),
           "end_time = 4e-4", "end_time = 6e-6");
  const Result r =
      run("run -t 1 " + write_case(dir, text).string() + " -o " + (dir / "out").string());
  ASSERT_EQ(r.code, 0) << r.output;
  const auto wall = r.output.find("[W] wall 'top' at 80 m/s (1.03 c) moves faster than 0.1 of");
  ASSERT_NE(wall, std::string::npos) << r.output;
  EXPECT_NE(r.output.find("c = sqrt((lambda + 2 mu)/rho) = 77.85 m/s (material 'gel')"),
            std::string::npos)
      << r.output;
  const auto point = r.output.find("[W] at t = ");
  ASSERT_NE(point, std::string::npos) << r.output;
  const std::string line = r.output.substr(point, r.output.find('\n', point) - point);
  EXPECT_NE(line.find("material point "), std::string::npos) << line;
  EXPECT_NE(line.find(" of grain "), std::string::npos) << line;
  EXPECT_NE(line.find("of its material 'gel'"), std::string::npos) << line;
  EXPECT_EQ(r.output.find("[W] wall", wall + 1), std::string::npos) << "reported twice";
  EXPECT_EQ(r.output.find("material point", point + line.size()), std::string::npos)
      << "reported twice";
}

// The thresholds: walls above kFastWallFraction c, points above kFastPointFraction c of their
// grain's material.
TEST(Speed, ThresholdsOfWallsAndPoints) {
  const std::string path = std::string(MPMCD_TEST_DIR) + "/compaction.toml";
  const double c = std::sqrt(6e6 / 990.0);
  EXPECT_NEAR(c, 77.85, 0.01);
  const auto config_with_top = [&](double v) {
    return mpmcd::io::parse_config(with(tiny_input(), "velocity = [0.0, -5.0]",
                                        "velocity = [0.0, -" + std::to_string(v) + "]"),
                                   path);
  };
  {
    const auto cfg = config_with_top(0.99 * mpmcd::app::kFastWallFraction * c);
    const auto model = mpmcd::app::build_model(cfg);
    ASSERT_EQ(mpmcd::app::wave_speeds(model).size(), 1u);
    EXPECT_NEAR(mpmcd::app::wave_speeds(model)[0], c, 1e-9);
    EXPECT_FALSE(mpmcd::app::fast_wall_warning(cfg, model).has_value());
  }
  {
    const auto cfg = config_with_top(1.01 * mpmcd::app::kFastWallFraction * c);
    const auto w = mpmcd::app::fast_wall_warning(cfg, mpmcd::app::build_model(cfg));
    ASSERT_TRUE(w.has_value());
    EXPECT_NE(w->find("wall 'top' at 7.86 m/s (0.101 c)"), std::string::npos) << *w;
  }
  const auto cfg = config_with_top(5.0);
  auto model = mpmcd::app::build_model(cfg);
  EXPECT_FALSE(mpmcd::app::fast_point_warning(cfg, model, 0.0).has_value());
  model.points.v[100] = mpmcd::Vec<2>(0.0, -0.99 * mpmcd::app::kFastPointFraction * c);
  EXPECT_FALSE(mpmcd::app::fast_point_warning(cfg, model, 0.0).has_value());
  model.points.v[200] = mpmcd::Vec<2>(1.01 * mpmcd::app::kFastPointFraction * c, 0.0);
  const auto w = mpmcd::app::fast_point_warning(cfg, model, 1e-5);
  ASSERT_TRUE(w.has_value());
  EXPECT_NE(w->find(fmt::format("at t = 1e-05 s material point 200 of grain {} moves at 39.31 m/s",
                                model.points.grain[200])),
            std::string::npos)
      << *w;
  EXPECT_NE(w->find("(1 point(s) faster than 0.5 c)"), std::string::npos) << *w;
}
