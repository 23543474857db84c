// A tiny compaction run by the `mpmcd` binary (compaction.toml: 9 disks, top wall down at 5 m/s,
// stop at Phi = 0.8; ~3 s) and the observables of docs/observables.md on every CSV row: the
// identity ln(Vs/Vs0) = ln(Phi/Phi0) + eps of paper eq. (9) to 1e-10, the energy ledger, Phi
// increasing, wall stress zero before the first contact, the stop criterion, Z and the Love-Weber
// cross-check. Then `mpmcd analyze` on that run, on three synthetic eq. (10) runs overlaid, and on
// garbage (exit 2); each [stop] criterion at its threshold.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "mpmcd/analysis/compaction_fit.hpp"
#include "mpmcd/analysis/time_series.hpp"
#include "mpmcd/app/compaction_observer.hpp"
#include "mpmcd/app/model_builder.hpp"
#include "mpmcd/io/load_config.hpp"

#include "../../support/cli_runner.hpp"
#include "../../support/scratch.hpp"

namespace fs = std::filesystem;
using mpmcd::analysis::TimeSeries;

namespace {

using mpmcd::test_support::Result;
using mpmcd::test_support::run;

fs::path scratch(const std::string& name) {
  return mpmcd::test_support::scratch_dir("compaction", name);
}

constexpr double kPhiStop = 0.8;  // [stop] phi of compaction.toml
constexpr double kMp = 6e6;       // lambda + 2 mu of compaction.toml [Pa]

// The tiny compaction run and its CSV time series. One test runs it and checks everything on it
// (ctest runs every test in its own process: one run instead of one per check).
struct TinyRun {
  fs::path dir;
  Result result;
  TimeSeries csv;
  const std::vector<double>& col(const std::string& name) const { return csv.column(name); }
};

void Eq9IdentityHoldsOnEveryRow(const TinyRun& r) {
  const auto &phi = r.col("phi"), &eps = r.col("eps"), &lnvs = r.col("ln_Vs_Vs0"), &h = r.col("h");
  const auto &vs = r.col("Vs"), &area = r.col("box_area"), &width = r.col("width");
  double worst = 0;
  for (std::size_t i = 0; i < phi.size(); ++i) {
    worst = std::max(worst, std::fabs(lnvs[i] - (std::log(phi[i] / phi[0]) + eps[i])));
    EXPECT_NEAR(lnvs[i], std::log(phi[i] / phi[0]) + eps[i], 1e-10) << "row " << i;
    EXPECT_NEAR(eps[i], std::log(h[i] / h[0]), 1e-14) << "row " << i;
    EXPECT_NEAR(phi[i], vs[i] / area[i], 1e-14) << "row " << i;
    EXPECT_NEAR(lnvs[i], std::log(vs[i] / vs[0]), 1e-14) << "row " << i;
    EXPECT_EQ(width[i], width[0]);
  }
  std::printf(
      "eq. (9) identity: largest error %.2e over %zu rows; Phi %.4f -> %.4f, eps %.4f, "
      "ln(Vs/Vs0) %.4f\n",
      worst, phi.size(), phi.front(), phi.back(), eps.back(), lnvs.back());
  EXPECT_LT(lnvs.back(), 0.0);  // compressible grains lose area (lambda = 3 MPa)
}

// The energy ledger (docs/accuracy.md) closes on every row: the work of the walls equals the
// change of elastic plus kinetic energy plus what contact, the transfers and the bulk dissipate,
// to the Newton tolerance; contact dissipates (frictionless, Moreau-Jean e = 0: never creates).
void EnergyLedgerClosesOnEveryRow(const TinyRun& r) {
  const auto &change = r.col("energy_change"), &dc = r.col("contact_dissipation");
  const auto &dt = r.col("transfer_dissipation"), &di = r.col("internal_dissipation");
  const auto &rest = r.col("energy_unaccounted"), &body = r.col("body_work");
  double work = 0, worst = 0;
  for (std::size_t i = 0; i < change.size(); ++i) {
    double w = body[i];
    for (const char* wall : {"bottom", "top", "left", "right"})
      w += r.col(std::string("wall_") + wall + "_work")[i];
    work = std::max(work, std::fabs(w));
    EXPECT_NEAR(rest[i], w - change[i] - dc[i] - dt[i] - di[i], 1e-12 * (1 + std::fabs(w)));
    EXPECT_GE(dc[i], -1e-9 * std::fabs(w)) << "row " << i;
    worst = std::max(worst, std::fabs(rest[i]));
  }
  ASSERT_GT(work, 0.0);
  EXPECT_LT(worst, 1e-6 * work);
  std::printf(
      "energy ledger: wall work %.4e J/m, stored %.1f %%, contact %.2f %%, transfers %.2f %%, "
      "bulk %.2f %%, largest remainder %.1e of the work\n",
      work, 100 * change.back() / work, 100 * dc.back() / work, 100 * dt.back() / work,
      100 * di.back() / work, worst / work);
}

void PhiIncreasesAndTheBoxShrinks(const TinyRun& r) {
  const auto &phi = r.col("phi"), &h = r.col("h");
  for (std::size_t i = 1; i < phi.size(); ++i) {
    EXPECT_GT(phi[i], phi[i - 1]) << "row " << i;
    EXPECT_LT(h[i], h[i - 1]) << "row " << i;
  }
  EXPECT_NEAR(h.front(), 3.2e-3, 1e-15);
  EXPECT_NEAR(phi.front(), 0.592377139682, 1e-9);  // 9 disks of packing.csv in 3 x 3.2 mm^2
}

void WallStressZeroBeforeFirstContactAndCompressiveAfter(const TinyRun& r) {
  const auto& active = r.col("active_contacts");
  std::size_t first = 0;
  while (first < active.size() && active[first] == 0) ++first;
  ASSERT_GT(first, 5u) << "the top wall starts 0.22 mm above the grains";
  ASSERT_LT(first, active.size());
  struct Wall {
    const char *stress, *fx, *fy;
    double nx, ny;  // normal into the box
  };
  const Wall walls[4] = {{"wall_bottom_stress", "wall_bottom_fx", "wall_bottom_fy", 0, 1},
                         {"wall_top_stress", "wall_top_fx", "wall_top_fy", 0, -1},
                         {"wall_left_stress", "wall_left_fx", "wall_left_fy", 1, 0},
                         {"wall_right_stress", "wall_right_fx", "wall_right_fy", -1, 0}};
  for (const auto& w : walls) {
    const auto &s = r.col(w.stress), &fx = r.col(w.fx), &fy = r.col(w.fy);
    for (std::size_t i = 0; i < first; ++i) EXPECT_EQ(s[i], 0.0) << w.stress << " row " << i;
    for (std::size_t i = 0; i < s.size(); ++i) {
      EXPECT_LE(s[i], 1e-6) << w.stress << " row " << i;  // never tensile (mechanics sign: < 0)
      // sigma = F . n / L (L the box side it closes).
      const double n[2] = {w.nx, w.ny};
      const double len = n[0] != 0 ? r.col("h")[i] : r.col("width")[i];
      EXPECT_NEAR(s[i], (fx[i] * n[0] + fy[i] * n[1]) / len, 1e-9 * (std::fabs(s[i]) + 1))
          << w.stress << " row " << i;
    }
  }
  const auto& bottom = r.col("wall_bottom_stress");
  const auto& over = r.col("sigma_bottom_over_Mp");
  EXPECT_LT(bottom.back(), -1e4);  // the bottom wall carries the load at the end
  for (std::size_t i = 0; i < bottom.size(); ++i)
    EXPECT_NEAR(over[i], bottom[i] / kMp, 1e-12) << "row " << i;
}

void StopCriterionHonoured(const TinyRun& r) {
  const auto &phi = r.col("phi"), &time = r.col("time");
  // csv_interval = 0: a row per step, so the row before the last is below the target.
  EXPECT_GE(phi.back(), kPhiStop);
  EXPECT_LT(phi[phi.size() - 2], kPhiStop);
  EXPECT_LT(time.back(), 4e-4 - 1e-9);  // before end_time
  EXPECT_NE(r.result.output.find("stop.phi reached: Phi = "), std::string::npos) << r.result.output;
}

void CoordinationAndLoveWeberStress(const TinyRun& r) {
  const auto &z = r.col("Z"), &pairs = r.col("Z_pairs"), &grains = r.col("Z_grains");
  const auto& rattlers = r.col("rattlers");
  for (std::size_t i = 0; i < z.size(); ++i) {
    EXPECT_EQ(grains[i] + rattlers[i], 9.0) << "row " << i;
    EXPECT_DOUBLE_EQ(z[i], grains[i] > 0 ? 2 * pairs[i] / grains[i] : 0.0) << "row " << i;
  }
  EXPECT_EQ(z.front(), 0.0);
  EXPECT_GT(z.back(), 1.0);
  // Love-Weber sigma_yy against the mean of the top and bottom wall stresses over the last tenth
  // (a dynamic compaction: within 20 %).
  const auto &lw = r.col("lw_syy"), &top = r.col("wall_top_stress"),
             &bottom = r.col("wall_bottom_stress");
  double a = 0, b = 0;
  for (std::size_t i = lw.size() - lw.size() / 10; i < lw.size(); ++i) {
    a += lw[i];
    b += 0.5 * (top[i] + bottom[i]);
  }
  std::printf("Love-Weber sigma_yy %.4g Pa, mean wall stress %.4g Pa (last tenth); final Z %.3f\n",
              a / (lw.size() / 10), b / (lw.size() / 10), z.back());
  EXPECT_NEAR(a / b, 1.0, 0.2);
}

void AnalyzeWritesFitAndFigures(const TinyRun& r) {
  const fs::path out = r.dir / "analysis";
  const Result a = run("analyze --no-plots " + (r.dir / "out").string() + " -o " + out.string());
  ASSERT_EQ(a.code, 0) << a.output;
  EXPECT_NE(a.output.find("jamming: Phi_J = "), std::string::npos) << a.output;
  EXPECT_NE(a.output.find("eq. (10) fit: c1 = "), std::string::npos) << a.output;
  for (const char* f : {"compaction_fit.csv", "figure4.csv", "figure5.csv"})
    EXPECT_TRUE(fs::exists(out / f)) << f;
  const TimeSeries fig4 = mpmcd::analysis::read_time_series((out / "figure4.csv").string());
  EXPECT_EQ(fig4.rows(), r.csv.rows());
}

// A synthetic run folder: input copy with lambda, mu and a CSV whose sigma/M_p follows eq. (10)
// beyond Phi_J = 0.8 (zero before), Z rising from 3.5 to 5.
void synthetic_run(const fs::path& dir, double lambda, double c1, double c2) {
  fs::create_directories(dir);
  std::ofstream(dir / "input.toml")
      << "# run by mpmcd (synthetic)\n[simulation]\nname = \"syn\"\n[[materials]]\nname = "
         "\"gel\"\nlaw = \"neo_hookean\"\ndensity = 990.0\nlambda = "
      << lambda << "\nmu = 1.5e6\n[[grains]]\nshape = \"packing\"\nfile = \"p.csv\"\nmaterial = "
      << "\"gel\"\n";
  const auto m = mpmcd::analysis::grain_moduli(lambda, 1.5e6);
  std::ofstream csv(dir / "syn.csv");
  csv.precision(17);
  csv << "step,time,eps,phi,ln_Vs_Vs0,sigma_bottom_over_Mp,Z\n";
  const double phi0 = 0.78;
  for (int i = 0; i <= 200; ++i) {
    const double phi = phi0 + (0.97 - phi0) * i / 200.0;
    const double z = phi < 0.8 - 1e-12 ? 2.0 : 3.5 + 1.5 * (phi - 0.8) / 0.17;
    const double y = phi < 0.8 - 1e-12 ? 0.0 : mpmcd::analysis::compaction_law(phi, z, c1, c2, m);
    const double lnvs = -0.1 * (phi - phi0), eps = lnvs - std::log(phi / phi0);
    csv << i << "," << 1e-6 * i << "," << eps << "," << phi << "," << lnvs << "," << y << "," << z
        << "\n";
  }
}

// Field `name` of data row `row` of a CSV file with a header (text fields allowed).
double csv_value(const fs::path& file, const std::string& name, std::size_t row) {
  std::ifstream in(file);
  std::vector<std::vector<std::string>> rows;
  for (std::string line; std::getline(in, line);) {
    std::vector<std::string> fields;
    std::stringstream ss(line);
    for (std::string f; std::getline(ss, f, ',');) fields.push_back(f);
    rows.push_back(fields);
  }
  for (std::size_t k = 0; k < rows.at(0).size(); ++k)
    if (rows[0][k] == name) return std::stod(rows.at(row + 1).at(k));
  ADD_FAILURE() << "no column " << name << " in " << file;
  return 0;
}

}  // namespace

TEST(Analyze, ThreeSyntheticRunsOverlaidRecoverC1C2) {
  // The paper's three materials with their c1 and c2 = 0.27 (eq. (10) exactly beyond Phi = 0.8).
  const fs::path dir = scratch("synthetic");
  const double lambdas[3] = {100e6, 3e6, 0.0}, c1s[3] = {0.01, 0.23, 1.3};
  std::string args = "analyze -o ";
  args += (dir / "analysis").string();
  for (int k = 0; k < 3; ++k) {
    const fs::path folder = dir / fs::path("run").concat(std::to_string(k));
    synthetic_run(folder, lambdas[k], c1s[k], 0.27);
    args += " ";
    args += folder.string();
  }
  const Result r = run(args);
  ASSERT_EQ(r.code, 0) << r.output;
  std::printf("%s", r.output.c_str());
  if (r.output.find("PNGs not written") == std::string::npos) {
    EXPECT_TRUE(fs::exists(dir / "analysis" / "figure4.png")) << r.output;
    EXPECT_TRUE(fs::exists(dir / "analysis" / "figure5.png")) << r.output;
    EXPECT_TRUE(fs::exists(dir / "analysis" / "figure5.pdf")) << r.output;
  }
  const fs::path fit = dir / "analysis" / "compaction_fit.csv";
  for (std::size_t k = 0; k < 3; ++k) {
    EXPECT_EQ(csv_value(fit, "lambda", k), lambdas[k]);
    EXPECT_NEAR(csv_value(fit, "c1", k), c1s[k], 0.01 * c1s[k]) << "lambda " << lambdas[k];
    EXPECT_NEAR(csv_value(fit, "c2", k), 0.27, 0.01 * 0.27) << "lambda " << lambdas[k];
    // The first row at Phi >= 0.8 (Phi on a grid of 200 steps from 0.78 to 0.97).
    EXPECT_NEAR(csv_value(fit, "phi_J", k), 0.78 + 0.19 * 22 / 200, 1e-12) << lambdas[k];
    EXPECT_LT(csv_value(fit, "identity_error", k), 1e-12);
  }
  std::ifstream fig5(dir / "analysis" / "figure5.csv");
  std::size_t lines = 0;
  for (std::string line; std::getline(fig5, line);) ++lines;
  EXPECT_EQ(lines, 1 + 3u * 201u);  // the three runs overlaid
  // Issue 17: the analysis folder is not reused silently; --overwrite replaces the analysis and
  // removes its files first (the PNGs a --no-plots analysis would leave stale).
  const Result again = run(args);
  EXPECT_EQ(again.code, 2) << again.output;
  EXPECT_NE(again.output.find("key '-o': a folder without the files of an earlier analysis"),
            std::string::npos)
      << again.output;
  const Result over = run(args + " --no-plots --overwrite");
  EXPECT_EQ(over.code, 0) << over.output;
  EXPECT_FALSE(fs::exists(dir / "analysis" / "figure4.png"));
  EXPECT_TRUE(fs::exists(dir / "analysis" / "figure4.csv"));
}

TEST(Analyze, GarbageExitsWith2) {
  const fs::path dir = scratch("garbage");
  // Not a folder.
  Result r = run("analyze " + (dir / "nothing").string());
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("not a folder"), std::string::npos) << r.output;
  // A folder without the input copy.
  r = run("analyze " + dir.string());
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("no input copy"), std::string::npos) << r.output;
  // A run without walls: the CSV lacks phi.
  synthetic_run(dir / "nowalls", 3e6, 0.23, 0.27);
  std::ofstream(dir / "nowalls" / "syn.csv") << "step,time,Vs\n0,0,1e-6\n";
  r = run("analyze " + (dir / "nowalls").string());
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("key 'phi': missing column"), std::string::npos) << r.output;
  // A CSV that is not numbers.
  std::ofstream(dir / "nowalls" / "syn.csv") << "phi,eps\nabc,1\n";
  r = run("analyze " + (dir / "nowalls").string());
  EXPECT_EQ(r.code, 2) << r.output;
  // A bad TOML input copy.
  std::ofstream(dir / "nowalls" / "input.toml") << "[[[";
  r = run("analyze " + (dir / "nowalls").string());
  EXPECT_EQ(r.code, 2) << r.output;
  // No folder at all.
  EXPECT_EQ(run("analyze").code, 2);
}

namespace {

// The observer of compaction.toml with its [stop] table replaced by `stop`.
struct StopCase {
  mpmcd::io::Config config;
  mpmcd::mpm::Model<2> model;
  explicit StopCase(const std::string& stop) {
    const std::string path = std::string(MPMCD_TEST_DIR) + "/compaction.toml";
    std::ifstream in(path);
    std::stringstream ss;
    ss << in.rdbuf();
    std::string text = ss.str();
    const auto at = text.find("[stop]\nphi = 0.8\n");
    text.replace(at, 17, stop);
    config = mpmcd::io::parse_config(text, path);
    model = mpmcd::app::build_model(config);
  }
};

}  // namespace

TEST(StopCriteria, EachCriterionAtItsThreshold) {
  mpmcd::mpm::StepStats st;
  st.wall_force.assign(4, {0.0, 0.0, 0.0});
  {
    // |eps| = |ln(h/h0)| >= 0.1 with h = 3.2 mm - 5 m/s t: t >= 3.2e-3 (1 - e^-0.1) / 5.
    const StopCase c("[stop]\nstrain = 0.1\n");
    const mpmcd::app::CompactionObserver obs(c.config, c.model);
    const double t = 3.2e-3 * (1 - std::exp(-0.1)) / 5;
    EXPECT_FALSE(obs.stop_reason(c.model, st, 0.999 * t).has_value());
    const auto r = obs.stop_reason(c.model, st, 1.001 * t);
    ASSERT_TRUE(r.has_value());
    EXPECT_NE(r->find("stop.strain reached"), std::string::npos) << *r;
  }
  {
    // Bottom wall (width 3 mm): -sigma >= 2e5 Pa when the grains push it with 600 N/m.
    const StopCase c("[stop]\nstress = 2e5\n");
    const mpmcd::app::CompactionObserver obs(c.config, c.model);
    st.wall_force[0] = {0.0, -599.0, 0.0};
    EXPECT_FALSE(obs.stop_reason(c.model, st, 1e-5).has_value());
    st.wall_force[1] = {0.0, 700.0, 0.0};  // the top wall does not count
    EXPECT_FALSE(obs.stop_reason(c.model, st, 1e-5).has_value());
    st.wall_force[0] = {0.0, -601.0, 0.0};
    const auto r = obs.stop_reason(c.model, st, 1e-5);
    ASSERT_TRUE(r.has_value());
    EXPECT_NE(r->find("stop.stress reached"), std::string::npos) << *r;
  }
  {
    // Phi = Vs0 / (3 mm h) >= 0.7 with the grains' initial area (the model is not stepped).
    const StopCase c("[stop]\nphi = 0.7\n");
    const mpmcd::app::CompactionObserver obs(c.config, c.model);
    double vs = 0;
    for (double v : c.model.points.volume) vs += v;
    const double t = (3.2e-3 - vs / (0.7 * 3e-3)) / 5;
    EXPECT_FALSE(obs.stop_reason(c.model, st, 0.999 * t).has_value());
    const auto r = obs.stop_reason(c.model, st, 1.001 * t);
    ASSERT_TRUE(r.has_value());
    EXPECT_NE(r->find("stop.phi reached"), std::string::npos) << *r;
  }
  {
    // No [stop] table: never.
    const StopCase c("");
    const mpmcd::app::CompactionObserver obs(c.config, c.model);
    EXPECT_FALSE(obs.stop_reason(c.model, st, 5e-4).has_value());
  }
}

void SnapshotPicturesAtChosenPhi(const TinyRun& r) {
  if (std::system("/usr/bin/python3 -c 'import numpy, matplotlib' >/dev/null 2>&1") != 0) {
    std::printf("snapshots not checked: /usr/bin/python3 with numpy and matplotlib not found\n");
    return;
  }
  const fs::path out = r.dir / "snapshots";
  std::string cmd = "/usr/bin/python3 ";
  cmd += std::string(MPMCD_SOURCE_DIR) + "/tools/plot_snapshots.py ";
  cmd += (r.dir / "out").string() + " --phi 0.6 0.8 --field pressure -o " + out.string();
  FILE* pipe = popen((cmd + " 2>&1").c_str(), "r");
  std::string text;
  std::array<char, 4096> buf{};
  while (pipe && fgets(buf.data(), buf.size(), pipe)) text += buf.data();
  ASSERT_EQ(pipe ? pclose(pipe) : -1, 0) << text;
  EXPECT_TRUE(fs::exists(out / "snapshot_phi0.600_pressure.png")) << text;
  EXPECT_TRUE(fs::exists(out / "snapshot_phi0.800_pressure.png")) << text;
  // Phi = 0.6 is nearest to the first snapshot (Phi0 = 0.592).
  EXPECT_NE(text.find("compaction_000000.vtu"), std::string::npos) << text;
}

TEST(Compaction, TinyRunObservablesAnalysisAndSnapshots) {
  TinyRun r;
  r.dir = scratch("run");
  r.result = run("run -t 1 " + std::string(MPMCD_TEST_DIR) + "/compaction.toml -o " +
                 (r.dir / "out").string());
  ASSERT_EQ(r.result.code, 0) << r.result.output;
  r.csv = mpmcd::analysis::read_time_series((r.dir / "out" / "compaction.csv").string());
  ASSERT_GT(r.csv.rows(), 20u);
  {
    SCOPED_TRACE("Eq9IdentityHoldsOnEveryRow");
    Eq9IdentityHoldsOnEveryRow(r);
  }
  {
    SCOPED_TRACE("EnergyLedgerClosesOnEveryRow");
    EnergyLedgerClosesOnEveryRow(r);
  }
  {
    SCOPED_TRACE("PhiIncreasesAndTheBoxShrinks");
    PhiIncreasesAndTheBoxShrinks(r);
  }
  {
    SCOPED_TRACE("WallStressZeroBeforeFirstContactAndCompressiveAfter");
    WallStressZeroBeforeFirstContactAndCompressiveAfter(r);
  }
  {
    SCOPED_TRACE("StopCriterionHonoured");
    StopCriterionHonoured(r);
  }
  {
    SCOPED_TRACE("CoordinationAndLoveWeberStress");
    CoordinationAndLoveWeberStress(r);
  }
  {
    SCOPED_TRACE("AnalyzeWritesFitAndFigures");
    AnalyzeWritesFitAndFigures(r);
  }
  {
    SCOPED_TRACE("SnapshotPicturesAtChosenPhi");
    SnapshotPicturesAtChosenPhi(r);
  }
}
