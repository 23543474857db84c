// Issue 17, item 5, on the tiny compaction (compaction.toml: 9 disks, top wall down at 5 m/s, stop
// at Phi = 0.8). The progress line follows the criterion that will end the run (the [stop]
// criterion, or end_time when it comes first) and shows Phi, the top wall stress and Z.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "mpmcd/app/progress.hpp"
#include "mpmcd/app/simulation.hpp"
#include "mpmcd/io/load_config.hpp"

#include "../../support/cli_runner.hpp"

namespace fs = std::filesystem;

namespace {

using mpmcd::test_support::Result;
using mpmcd::test_support::run;

fs::path scratch(const std::string& name) {
  // The pid keeps concurrent test runs (other build trees on the machine) apart.
  fs::path p =
      fs::temp_directory_path() / ("mpmcd_progress_" + name + "_" + std::to_string(getpid()));
  fs::remove_all(p);
  fs::create_directories(p);
  return p;
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
