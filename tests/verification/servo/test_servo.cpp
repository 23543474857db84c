// Stress-controlled walls and loading stages ([loading], docs/loading.md) through the app, as a
// user runs them: a Neo-Hookean block between four frictionless walls whose top wall is a servo
// holds the target stress within 1 % after its settling time (wall stresses, every point's
// sigma22 and the closed form of uniaxial strain, method.md §7); stages end on their `until`
// conditions (stress, time, strain) and ramps follow their line; a restart in the middle of a
// stage continues bitwise; a biaxial test (side walls servos with integral action, top wall at a
// velocity) keeps the lateral stress and the closed form of F = diag(a, s).
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <utility>

#include "../../support/scratch.hpp"
#include "mpmcd/analysis/time_series.hpp"
#include "mpmcd/app/run_state.hpp"
#include "mpmcd/app/simulation.hpp"
#include "mpmcd/checkpoint/checkpoint.hpp"
#include "mpmcd/core/log.hpp"
#include "mpmcd/io/load_config.hpp"

namespace fs = std::filesystem;
namespace ck = mpmcd::checkpoint;

namespace {

constexpr double kLambda = 3e6, kMu = 1.5e6;  // the block's Neo-Hookean material [Pa]
constexpr double kH0 = 1e-3;                  // the block's initial height and width [m]

fs::path scratch(const std::string& name) {
  return mpmcd::test_support::scratch_dir("servo", name);
}

// The block [0.5, 1.5] mm^2 between four walls touching it (uniaxial strain), cell size h [m],
// 2 x 2 points per cell, CPDI + affine + face walls (the configuration that keeps a walled block
// homogeneous, docs/accuracy.md), time step dt [s]; `loading` is the [loading] part.
std::string block_input(double h, double dt, double end_time, const std::string& loading) {
  std::ostringstream in;
  in.precision(17);
  in << "[simulation]\nname = \"block\"\n"
        "[grid]\norigin = [0.0, 0.0]\nextent = [2e-3, 2e-3]\ncell_size = "
     << h
     << "\nshape_function = \"cpdi\"\n"
        "[[materials]]\nname = \"gel\"\nlaw = \"neo_hookean\"\ndensity = 990.0\nlambda = "
     << kLambda << "\nmu = " << kMu
     << "\n[[grains]]\nshape = \"rectangle\"\nmaterial = \"gel\"\n"
        "min_corner = [0.5e-3, 0.5e-3]\nmax_corner = [1.5e-3, 1.5e-3]\npoints_per_cell = 2\n"
        "[time]\ndt = "
     << dt << "\nend_time = " << end_time
     << "\n[solver]\naffine = true\nresidual_tolerance = 1e-10\nincrement_tolerance = 1e-10\n"
        "[contact]\nwall_contact = \"points\"\ntolerance = 1e-10\nimpulse_tolerance = 1e-10\n"
        "[[walls]]\nname = \"bottom\"\npoint = [0.0, 0.5e-3]\nnormal = [0.0, 1.0]\n"
        "[[walls]]\nname = \"top\"\npoint = [0.0, 1.5e-3]\nnormal = [0.0, -1.0]\n"
        "[[walls]]\nname = \"left\"\npoint = [0.5e-3, 0.0]\nnormal = [1.0, 0.0]\n"
        "[[walls]]\nname = \"right\"\npoint = [1.5e-3, 0.0]\nnormal = [-1.0, 0.0]\n"
     << loading << "[output]\nfolder = \"out\"\nvtu = false\n";
  return in.str();
}

mpmcd::app::RunSummary run(const std::string& text, const fs::path& dir,
                           std::int64_t stop_after = 0) {
  mpmcd::setup_logging(mpmcd::Verbosity::kQuiet);
  const fs::path in = dir / "block.toml";
  std::ofstream(in) << text;
  const auto cfg = mpmcd::io::load_config(in.string());
  mpmcd::app::RunOptions opt;
  opt.threads = 1;
  opt.quiet = true;
  opt.output_dir = (dir / "out").string();
  opt.stop_after = stop_after;
  return mpmcd::app::run_simulation(cfg, opt);
}

// sigma22 of the homogeneous uniaxial strain F = diag(1, s) (method.md §7) [Pa].
double sigma22(double s) {
  return (kMu * (s * s - 1) + kLambda * std::log(s)) / s;
}

// sigma11 of the same state [Pa].
double sigma11(double s) {
  return kLambda * std::log(s) / s;
}

// The servo's hold in a run's CSV: the top target follows its ramp to `target` [Pa] over `ramp`
// [s] and holds; from `settled` [s] on, the top and bottom walls and the Love-Weber sigma_yy are
// within 1 % of the target, the top stress within 1e-3 of the closed form sigma22 of the stretch
// reached (h / H0), and each of the `sides` walls within 1 % of sigma11. Returns the rows checked
// and the worst |sigma_top - target| / |target|.
std::pair<int, double> check_hold(const mpmcd::analysis::TimeSeries& csv, double target,
                                  double ramp, double settled,
                                  std::initializer_list<const char*> sides) {
  const auto& t = csv.column("time");
  const auto& top = csv.column("wall_top_stress");
  const auto& h_box = csv.column("h");
  int checked = 0;
  double worst = 0;
  for (std::size_t i = 0; i < csv.rows(); ++i) {
    EXPECT_NEAR(csv.column("wall_top_target")[i], target * std::min(t[i] / ramp, 1.0),
                1e-9 * std::fabs(target))
        << t[i];
    if (t[i] < settled) continue;
    ++checked;
    const double s = h_box[i] / kH0;  // the stretch reached
    worst = std::max(worst, std::fabs(top[i] - target) / std::fabs(target));
    EXPECT_NEAR(top[i], target, 0.01 * std::fabs(target)) << "top wall at t = " << t[i];
    EXPECT_NEAR(csv.column("wall_bottom_stress")[i], target, 0.01 * std::fabs(target))
        << "bottom wall at t = " << t[i];
    EXPECT_NEAR(csv.column("lw_syy")[i], target, 0.01 * std::fabs(target))
        << "Love-Weber at t = " << t[i];
    EXPECT_NEAR(sigma22(s), target, 0.01 * std::fabs(target)) << "closed form at s = " << s;
    EXPECT_NEAR(top[i], sigma22(s), 1e-3 * std::fabs(target)) << t[i];
    for (const char* side : sides)
      EXPECT_NEAR(csv.column(side)[i], sigma11(s), 0.01 * std::fabs(sigma11(s)))
          << side << " at t = " << t[i];
  }
  return {checked, worst};
}

}  // namespace

// The top wall is a servo with the automatic gain; its target -0.3 MPa is ramped over 0.1 ms and
// held. Settling time (docs/loading.md): tau = H / (M_p g) = 67 us for g = 0.25 min(dt/(rho h),
// h/(M_p dt)) at c_p dt / h = 0.78, and the ramp leaves a lag of about rate x tau; the check
// starts 3 ms later, at 0.4 ms (about 5 tau after the ramp).
TEST(Servo, HoldsTargetStressOnElasticBlockWithinOnePercent) {
  const fs::path dir = scratch("hold");
  const double target = -3e5, ramp = 1e-4, settled = 4e-4, h = 1e-4, dt = 1e-6;
  const auto summary = run(block_input(h, dt, 1e-3,
                                       "[loading]\n[[loading.stages]]\nname = \"press\"\n"
                                       "ramp = 1e-4\nuntil = { time = 5e-4 }\n"
                                       "[[loading.stages.walls]]\nname = \"top\"\nstress = -3e5\n"),
                           dir);
  // The last stage's end ends the run.
  EXPECT_NE(summary.stop_reason.find("loading finished"), std::string::npos) << summary.stop_reason;
  EXPECT_NEAR(summary.time, 5e-4, 1e-12);
  const auto csv = mpmcd::analysis::read_time_series((dir / "out" / "block.csv").string());
  const auto& h_box = csv.column("h");
  ASSERT_GT(csv.rows(), 400u);
  const auto [checked, worst] = check_hold(csv, target, ramp, settled, {"wall_left_stress"});
  EXPECT_GT(checked, 90);
  std::printf("  servo block: worst |sigma_top - target| / |target| after %.2g s: %.3e\n", settled,
              worst);
  // Every point's sigma22 at the end (the final checkpoint holds them).
  const ck::State s = ck::read(summary.checkpoint);
  const double s_end = h_box.back() / kH0;
  double worst_point = 0;
  for (std::size_t p = 0; p < s.points(); ++p)
    worst_point = std::max(worst_point, std::fabs(s.sigma[4 * p + 3] - target) / std::fabs(target));
  EXPECT_LT(worst_point, 0.01);
  std::printf("  final s = %.6f: sigma22(s) = %.6g Pa, worst point sigma22 error %.3e\n", s_end,
              sigma22(s_end), worst_point);
}

namespace {

// The coarse block (h = 0.2 mm, 100 points) driven through four stages that end on a stress, a
// time, and two strains; the servo of the hold stage has an integral term (its integral is state
// that a restart must carry).
std::string staged_input(const std::string& checkpoint = "") {
  return block_input(
      2e-4, 2e-6, 2e-3,
      "[loading]\nintegral_time = 1e-4\n"
      "[[loading.stages]]\nname = \"approach\"\nuntil = { stress = -2e5, wall = \"top\" }\n"
      "[[loading.stages.walls]]\nname = \"top\"\nvelocity = [0.0, -0.5]\n"
      "[[loading.stages]]\nname = \"hold\"\nuntil = { time = 1e-4 }\n"
      "[[loading.stages.walls]]\nname = \"top\"\nstress = -2e5\n"
      "[[loading.stages]]\nname = \"unload\"\nuntil = { strain = -0.01 }\n"
      "[[loading.stages.walls]]\nname = \"top\"\nvelocity = [0.0, 0.5]\n"
      "[[loading.stages]]\nname = \"reload\"\nramp = 2e-5\nuntil = { strain = -0.02 }\n"
      "[[loading.stages.walls]]\nname = \"top\"\nvelocity = [0.0, -0.25]\n" +
          checkpoint);
}

}  // namespace

TEST(Loading, StagesEndOnTheirConditionsAndRampsFollowTheirLine) {
  const fs::path dir = scratch("stages");
  const auto summary = run(staged_input(), dir);
  EXPECT_NE(summary.stop_reason.find("loading finished: loading stage 4 ('reload')"),
            std::string::npos)
      << summary.stop_reason;
  EXPECT_NE(summary.stop_reason.find("until.strain"), std::string::npos) << summary.stop_reason;
  const auto csv = mpmcd::analysis::read_time_series((dir / "out" / "block.csv").string());
  const auto& t = csv.column("time");
  const auto& stage = csv.column("stage");
  const auto& top = csv.column("wall_top_stress");
  const auto& eps = csv.column("eps");
  const auto& vy = csv.column("wall_top_vy");
  const auto& goal = csv.column("wall_top_target");
  // Each row's stage is the one that steps after it: the row where a stage ends shows the next.
  std::vector<std::size_t> first(6, 0);  // first row of stages 1..5 (5: none)
  for (std::size_t i = 1; i < csv.rows(); ++i) {
    ASSERT_GE(stage[i], stage[i - 1]);
    if (stage[i] != stage[i - 1]) first[static_cast<std::size_t>(stage[i])] = i;
  }
  ASSERT_GT(first[2], 0u);
  ASSERT_GT(first[3], first[2]);
  ASSERT_GT(first[4], first[3]);
  // 1: the top wall at -0.5 m/s until its stress crosses -2e5 Pa (not before).
  for (std::size_t i = 1; i < first[2]; ++i) {
    EXPECT_EQ(vy[i], -0.5);
    EXPECT_GT(top[i], -2e5) << t[i];
    EXPECT_TRUE(std::isnan(goal[i]));  // velocity control: no target stress
  }
  EXPECT_LE(top[first[2]], -2e5);
  // 2: stress control for exactly 1e-4 s (its steps end on the stage's end), target -2e5 Pa.
  EXPECT_NEAR(t[first[3]] - t[first[2]], 1e-4, 1e-12);
  for (std::size_t i = first[2]; i < first[3]; ++i) EXPECT_EQ(goal[i], -2e5);
  // 3: unloading at +0.5 m/s until eps crosses -0.01 upward.
  for (std::size_t i = first[3] + 1; i <= first[4]; ++i) EXPECT_EQ(vy[i], 0.5);
  for (std::size_t i = first[3]; i < first[4]; ++i) EXPECT_LT(eps[i], -0.01) << t[i];
  EXPECT_GE(eps[first[4]], -0.01);
  // 4: the velocity ramps from +0.5 to -0.25 m/s over 2e-5 s (the step's velocity is the ramp's
  // value at the step's end), then holds until eps crosses -0.02 downward: the last row.
  const double t4 = t[first[4]];
  for (std::size_t i = first[4] + 1; i < csv.rows(); ++i) {
    const double share = std::min((t[i] - t4) / 2e-5, 1.0);
    EXPECT_NEAR(vy[i], 0.5 + share * (-0.75), 1e-9) << t[i];
  }
  for (std::size_t i = first[4]; i + 1 < csv.rows(); ++i) EXPECT_GT(eps[i], -0.02) << t[i];
  EXPECT_LE(eps.back(), -0.02);
  EXPECT_EQ(stage.back(), 4);
}

// A run stopped in the middle of the hold stage (stress control) and restarted from its checkpoint
// writes the same CSV rows, byte for byte, and ends in the same state as the uninterrupted run.
TEST(Loading, RestartMidStageIsBitwise) {
  const fs::path dir = scratch("restart");
  fs::create_directories(dir / "full");
  fs::create_directories(dir / "split");
  const auto full = run(staged_input(), dir / "full");
  ASSERT_FALSE(full.interrupted);
  // The hold stage starts after about 27 steps of approach and lasts 50 steps.
  const auto first = run(staged_input(), dir / "split", 50);
  ASSERT_TRUE(first.interrupted);
  const ck::State mid = ck::read(first.checkpoint);
  ASSERT_EQ(mid.loading_stage.size(), 5u);
  EXPECT_EQ(mid.loading_stage[0], 1.0) << "not in the hold stage";
  EXPECT_EQ(mid.loading_control.at(1), 1) << "the top wall is not stress-controlled";
  ASSERT_EQ(mid.loading_wall.size(), 4u * 13u);
  EXPECT_NE(mid.loading_wall[13 + 12], 0.0) << "the top wall's servo integral is not stored";
  const auto restart = mpmcd::app::load_restart(first.checkpoint, "");
  mpmcd::app::RunOptions ropt;
  ropt.threads = 1;
  ropt.quiet = true;
  ropt.restart = first.checkpoint;
  const auto second = mpmcd::app::run_simulation(restart.config, ropt, &restart.state);
  EXPECT_EQ(second.steps, full.steps);
  EXPECT_EQ(second.stop_reason, full.stop_reason);
  EXPECT_TRUE(mpmcd::test_support::read_file(dir / "full" / "out" / "block.csv") ==
              mpmcd::test_support::read_file(dir / "split" / "out" / "block.csv"))
      << "CSV rows differ";
  const ck::State a = ck::read(full.checkpoint), b = ck::read(second.checkpoint);
  EXPECT_EQ(ck::payload_checksum(a), ck::payload_checksum(b));
  EXPECT_EQ(a.loading_wall, b.loading_wall);
  EXPECT_EQ(a.wall_point, b.wall_point);
}

namespace {

// Cauchy stress sigma_kk of the homogeneous state F = diag(a, s) (method.md §7):
// [mu (stretch^2 - 1) + lambda ln J] / J, J = a s, stretch a for sigma11 and s for sigma22 [Pa].
double sigma_biaxial(double stretch, double a, double s) {
  const double j = a * s;
  return (kMu * (stretch * stretch - 1) + kLambda * std::log(j)) / j;
}

}  // namespace

// The biaxial test of docs/loading.md on the block: stage 1 brings the four walls to the
// confining stress -p0 (equibiaxial state); stage 2 keeps the side walls at -p0 (servos) while
// the top wall moves down at a constant speed (bottom at rest) until eps = -0.1. During the
// compression the side walls move out by themselves; after a settling time the side walls hold
// -p0 within 1 %, and the top wall stress, the Love-Weber stress and every point's stress are
// those of F = diag(a, s) with a and s read from the walls' positions.
TEST(Loading, BiaxialHoldsTheLateralStressWhileTheTopWallMoves) {
  const fs::path dir = scratch("biaxial");
  const double p0 = 1e5, v = 0.1;  // confining stress [Pa], top wall speed [m/s]
  std::ostringstream loading;
  loading << "[loading]\nintegral_time = 1e-4\n"
             "[[loading.stages]]\nname = \"confine\"\nramp = 1e-4\nuntil = { time = 5e-4 }\n"
             "walls = [{ name = \"bottom\", stress = "
          << -p0 << " }, { name = \"top\", stress = " << -p0
          << " },\n         { name = \"left\", stress = " << -p0
          << " }, { name = \"right\", stress = " << -p0
          << " }]\n"
             "[[loading.stages]]\nname = \"compress\"\nramp = 5e-5\nuntil = { strain = -0.1 }\n"
             "walls = [{ name = \"bottom\", velocity = [0.0, 0.0] }, { name = \"top\", velocity "
             "= [0.0, "
          << -v << "] }]\n";
  const auto summary = run(block_input(1e-4, 1e-6, 3e-3, loading.str()), dir);
  EXPECT_NE(summary.stop_reason.find("loading finished: loading stage 2 ('compress')"),
            std::string::npos)
      << summary.stop_reason;
  const auto csv = mpmcd::analysis::read_time_series((dir / "out" / "block.csv").string());
  const auto& t = csv.column("time");
  const auto& stage = csv.column("stage");
  const auto& top = csv.column("wall_top_stress");
  const auto& left = csv.column("wall_left_stress");
  const auto& right = csv.column("wall_right_stress");
  const auto& lw_xx = csv.column("lw_sxx");
  const auto& lw_yy = csv.column("lw_syy");
  const auto& h_box = csv.column("h");
  const auto& width = csv.column("width");
  const auto& vx = csv.column("wall_right_vx");
  // The end of stage 1 (settled): the equibiaxial state within 1 %.
  std::size_t start2 = 0;
  for (std::size_t i = 1; i < csv.rows() && !start2; ++i)
    if (stage[i] == 2) start2 = i;
  ASSERT_GT(start2, 0u);
  for (const auto* col : {&top, &left, &right})
    EXPECT_NEAR((*col)[start2 - 1], -p0, 0.01 * p0) << "end of the confinement";
  // Stage 2 after 0.3 ms of compression (about 4 settling times of the side servos).
  const double t_check = t[start2] + 3e-4;
  int checked = 0;
  double worst_side = 0, worst_top = 0;
  for (std::size_t i = start2; i < csv.rows(); ++i) {
    if (t[i] < t_check) continue;
    ++checked;
    const double a = width[i] / kH0, s = h_box[i] / kH0;
    const double s11 = sigma_biaxial(a, a, s), s22 = sigma_biaxial(s, a, s);
    worst_side = std::max(worst_side, std::fabs(left[i] + p0) / p0);
    worst_top = std::max(worst_top, std::fabs(top[i] - s22) / std::fabs(s22));
    EXPECT_NEAR(left[i], -p0, 0.01 * p0) << "left wall at t = " << t[i];
    EXPECT_NEAR(right[i], -p0, 0.01 * p0) << "right wall at t = " << t[i];
    EXPECT_NEAR(top[i], s22, 1e-3 * std::fabs(s22)) << "top wall at t = " << t[i];
    EXPECT_NEAR(left[i], s11, 1e-3 * std::fabs(s11)) << "left wall at t = " << t[i];
    EXPECT_NEAR(lw_yy[i], s22, 1e-3 * std::fabs(s22)) << "Love-Weber at t = " << t[i];
    EXPECT_NEAR(lw_xx[i], s11, 1e-3 * std::fabs(s11)) << "Love-Weber at t = " << t[i];
    EXPECT_GT(vx[i], 0.0) << "the right wall does not move out at t = " << t[i];
  }
  EXPECT_GT(checked, 50);
  // Every point's stress at the end (the final checkpoint holds them).
  const ck::State st = ck::read(summary.checkpoint);
  const double a = width.back() / kH0, s = h_box.back() / kH0;
  double worst_point = 0;
  for (std::size_t p = 0; p < st.points(); ++p) {
    worst_point = std::max(worst_point, std::fabs(st.sigma[4 * p] - sigma_biaxial(a, a, s)) /
                                            std::fabs(sigma_biaxial(a, a, s)));
    worst_point = std::max(worst_point, std::fabs(st.sigma[4 * p + 3] - sigma_biaxial(s, a, s)) /
                                            std::fabs(sigma_biaxial(s, a, s)));
  }
  EXPECT_LT(worst_point, 1e-3);
  std::printf(
      "  biaxial block: end a = %.5f, s = %.5f; worst side wall / -p0 - 1: %.2e, worst top wall "
      "against the closed form: %.2e, worst point: %.2e\n",
      a, s, worst_side, worst_top, worst_point);
}

// The same in 3D (docs/three_d.md): a cube [0.5, 1.5] mm^3 between six frictionless face walls
// (uniaxial strain along y, F = diag(1, s, 1)), h = 0.25 mm (2^3 points per cell, 512 points, as
// tests/verification/wall_block_3d), the top wall a servo with the automatic gain, its target
// -0.3 MPa ramped over 0.1 ms and held; c_p dt / h = 0.78 as in 2D. After 0.4 ms the top and
// bottom walls, the Love-Weber sigma_yy and the closed form of the reached stretch are within 1 %
// of the target, and the side walls carry sigma11 = lambda ln(s) / s.
TEST(Servo, HoldsTargetStressOnElasticCubeInThreeDimensionsWithinOnePercent) {
  const fs::path dir = scratch("hold3d");
  const double target = -3e5, ramp = 1e-4, settled = 4e-4, h = 2.5e-4, dt = 2.5e-6;
  std::ostringstream in;
  in.precision(17);
  in << "[simulation]\nname = \"block\"\ndimension = 3\n"
        "[grid]\norigin = [0.0, 0.0, 0.0]\nextent = [2e-3, 2e-3, 2e-3]\ncell_size = "
     << h
     << "\nshape_function = \"cpdi\"\n"
        "[[materials]]\nname = \"gel\"\nlaw = \"neo_hookean\"\ndensity = 990.0\nlambda = "
     << kLambda << "\nmu = " << kMu
     << "\n[[grains]]\nshape = \"box\"\nmaterial = \"gel\"\n"
        "min_corner = [0.5e-3, 0.5e-3, 0.5e-3]\nmax_corner = [1.5e-3, 1.5e-3, 1.5e-3]\n"
        "points_per_cell = 2\n[time]\ndt = "
     << dt
     << "\nend_time = 1e-3\n"
        "[solver]\naffine = true\nresidual_tolerance = 1e-10\nincrement_tolerance = 1e-10\n"
        "[contact]\nwall_contact = \"points\"\nsolver = \"active_set\"\ntolerance = 1e-10\n"
        "impulse_tolerance = 1e-10\n";
  const char* walls[][3] = {{"bottom", "[0.0, 0.5e-3, 0.0]", "[0.0, 1.0, 0.0]"},
                            {"top", "[0.0, 1.5e-3, 0.0]", "[0.0, -1.0, 0.0]"},
                            {"left", "[0.5e-3, 0.0, 0.0]", "[1.0, 0.0, 0.0]"},
                            {"right", "[1.5e-3, 0.0, 0.0]", "[-1.0, 0.0, 0.0]"},
                            {"front", "[0.0, 0.0, 0.5e-3]", "[0.0, 0.0, 1.0]"},
                            {"back", "[0.0, 0.0, 1.5e-3]", "[0.0, 0.0, -1.0]"}};
  for (const auto& w : walls)
    in << "[[walls]]\nname = \"" << w[0] << "\"\npoint = " << w[1] << "\nnormal = " << w[2] << "\n";
  in << "[loading]\n[[loading.stages]]\nname = \"press\"\nramp = 1e-4\nuntil = { time = 5e-4 }\n"
        "[[loading.stages.walls]]\nname = \"top\"\nstress = -3e5\n"
        "[output]\nfolder = \"out\"\nvtu = false\n";
  const auto summary = run(in.str(), dir);
  EXPECT_NE(summary.stop_reason.find("loading finished"), std::string::npos) << summary.stop_reason;
  const auto csv = mpmcd::analysis::read_time_series((dir / "out" / "block.csv").string());
  const auto& h_box = csv.column("h");
  ASSERT_GT(csv.rows(), 150u);
  const auto [checked, worst] =
      check_hold(csv, target, ramp, settled, {"wall_left_stress", "wall_front_stress"});
  EXPECT_GT(checked, 30);
  std::printf(
      "  servo cube (3D): worst |sigma_top - target| / |target| after %.2g s: %.3e, final "
      "s = %.6f, sigma22(s) = %.6g Pa\n",
      settled, worst, h_box.back() / kH0, sigma22(h_box.back() / kH0));
}
