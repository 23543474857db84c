// Runs that survive: a run stopped half way (--stop-after, SIGTERM to the real binary, SIGKILL)
// and resumed from its checkpoint ends bitwise identical to an uninterrupted run: point arrays,
// contact warm start, CSV rows, every VTU. Damaged checkpoints and foreign inputs are refused with
// exit 2; a numerical failure leaves a loadable checkpoint of the last good step.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "../../support/scratch.hpp"
#include "mpmcd/app/run_state.hpp"
#include "mpmcd/app/simulation.hpp"
#include "mpmcd/checkpoint/checkpoint.hpp"
#include "mpmcd/core/errors.hpp"
#include "mpmcd/core/log.hpp"
#include "mpmcd/io/load_config.hpp"

namespace fs = std::filesystem;
namespace ck = mpmcd::checkpoint;

namespace {

fs::path scratch(const std::string& name) {
  return mpmcd::test_support::scratch_dir("restart", name);
}

// Two gel disks thrown at each other in a box of three walls under gravity: they collide at
// about step 12, bounce off each other and the side walls (contacts all along, so warm-start
// impulses matter). About 3 ms per step.
// `contact`, `time`: more lines of the [contact] and [time] tables.
fs::path write_case(const fs::path& dir, int steps, const std::string& checkpoint,
                    const std::string& contact = "", const std::string& time = "") {
  const fs::path p = dir / "pair.toml";
  std::ofstream(p) << "[simulation]\nname = \"pair\"\n"
                      "[grid]\norigin = [0.0, 0.0]\nextent = [0.02, 0.012]\ncell_size = 0.001\n"
                      "[[materials]]\nname = \"gel\"\nlaw = \"neo_hookean\"\ndensity = 990.0\n"
                      "lambda = 3e6\nmu = 1.5e6\n"
                      "[[grains]]\nshape = \"disk\"\nmaterial = \"gel\"\n"
                      "center = [0.006, 0.005]\nradius = 0.0035\n"
                      "[grains.initial]\nvelocity = [1.0, 0.0]\n"
                      "[[grains]]\nshape = \"disk\"\nmaterial = \"gel\"\n"
                      "center = [0.0135, 0.0055]\nradius = 0.0035\n"
                      "[grains.initial]\nvelocity = [-1.0, 0.0]\n"
                      "[[walls]]\nname = \"floor\"\npoint = [0.0, 0.0012]\nnormal = [0.0, 1.0]\n"
                      "[[walls]]\nname = \"left\"\npoint = [0.0015, 0.0]\nnormal = [1.0, 0.0]\n"
                      "[[walls]]\nname = \"right\"\npoint = [0.0185, 0.0]\nnormal = [-1.0, 0.0]\n"
                      "[loads]\ngravity = [0.0, -9.81]\n"
                      "[time]\ndt = 2e-5\nend_time = "
                   << steps * 2e-5 << "\n"
                   << time << "[contact]\nfriction = 0.3\n"
                   << contact
                   << "[output]\nfolder = \"out\"\nvtu_interval = 1e-4\n"
                      "[checkpoint]\n"
                   << checkpoint;
  return p;
}

bool same_bits(const std::vector<double>& a, const std::vector<double>& b) {
  return a.size() == b.size() &&
         (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0);
}

// The final states and every output file of two runs are identical, bit for bit.
void expect_identical_runs(const fs::path& a, const fs::path& b, std::int64_t steps) {
  const ck::State sa = ck::read((a / ck::file_name("pair", steps)).string());
  const ck::State sb = ck::read((b / ck::file_name("pair", steps)).string());
  EXPECT_EQ(sa.step, sb.step);
  EXPECT_EQ(std::memcmp(&sa.time, &sb.time, sizeof(double)), 0);
  EXPECT_TRUE(same_bits(sa.x, sb.x)) << "positions differ";
  EXPECT_TRUE(same_bits(sa.v, sb.v)) << "velocities differ";
  EXPECT_TRUE(same_bits(sa.F, sb.F)) << "deformation gradients differ";
  EXPECT_TRUE(same_bits(sa.sigma, sb.sigma)) << "stresses differ";
  EXPECT_TRUE(same_bits(sa.sigma_zz, sb.sigma_zz));
  EXPECT_TRUE(same_bits(sa.volume, sb.volume));
  EXPECT_TRUE(same_bits(sa.history, sb.history));
  EXPECT_EQ(sa.warm_node, sb.warm_node);
  EXPECT_TRUE(same_bits(sa.warm_impulse, sb.warm_impulse)) << "warm-start impulses differ";
  EXPECT_FALSE(sa.warm_node.empty()) << "the case should end with contacts";
  EXPECT_EQ(ck::payload_checksum(sa), ck::payload_checksum(sb));
  // No timestamps in the file: the same state gives the same bytes.
  EXPECT_TRUE(mpmcd::test_support::read_file(a / ck::file_name("pair", steps)) ==
              mpmcd::test_support::read_file(b / ck::file_name("pair", steps)))
      << "final checkpoint files differ";
  int files = 0;
  for (const auto& e : fs::directory_iterator(a)) {
    const std::string ext = e.path().extension().string();
    if (ext != ".csv" && ext != ".vtu" && ext != ".pvd") continue;
    if (e.path().filename().string().ends_with("_timers.csv")) continue;  // wall-clock times
    ++files;
    const fs::path other = b / e.path().filename();
    ASSERT_TRUE(fs::exists(other)) << other;
    EXPECT_TRUE(mpmcd::test_support::read_file(e.path()) == mpmcd::test_support::read_file(other))
        << e.path().filename() << " differs";
  }
  for (const auto& e : fs::directory_iterator(b))
    EXPECT_TRUE(fs::exists(a / e.path().filename()) || e.path().extension() == ".h5" ||
                e.path().extension() == ".log")
        << "extra file " << e.path();
  EXPECT_GT(files, 20);
}

// Runs the binary in the background with stdout+stderr to `log`; returns its pid.
pid_t spawn(const std::vector<std::string>& args, const fs::path& log) {
  const pid_t pid = fork();
  if (pid == 0) {
    FILE* f = std::freopen(log.c_str(), "w", stdout);
    if (f == nullptr || dup2(fileno(stdout), 2) < 0) _exit(120);
    std::vector<char*> argv;
    static std::string bin = MPMCD_BINARY;
    argv.push_back(bin.data());
    for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    execv(bin.c_str(), argv.data());
    _exit(121);
  }
  return pid;
}

int wait_exit(pid_t pid) {
  int status = 0;
  waitpid(pid, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

int run_binary(const std::vector<std::string>& args, const fs::path& log) {
  return wait_exit(spawn(args, log));
}

std::int64_t csv_rows(const fs::path& csv) {
  std::ifstream in(csv);
  std::string line;
  std::int64_t n = -1;
  while (std::getline(in, line)) ++n;
  return n;
}

// Waits (up to 60 s) until `done()` holds; false on timeout.
template <class F>
bool wait_for(F done) {
  const auto t0 = std::chrono::steady_clock::now();
  while (!done()) {
    if (std::chrono::steady_clock::now() - t0 > std::chrono::seconds(60)) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return true;
}

// An uninterrupted reference run of the binary in <dir>/ref.
fs::path reference(const fs::path& dir, int steps, const std::string& checkpoint) {
  const fs::path in = write_case(dir, steps, checkpoint);
  const fs::path out = dir / "ref";
  EXPECT_EQ(run_binary({"run", "-q", "-t", "1", in.string(), "-o", out.string()}, dir / "ref.log"),
            0)
      << mpmcd::test_support::read_file(dir / "ref.log");
  return in;
}

}  // namespace

namespace {
// In process, deterministic split: N steps against N/2 (--stop-after) + restart to N, with
// `contact` and `time` added to the [contact] and [time] tables (without `time`: N = 60 steps of
// 2e-5 s). Returns N.
std::int64_t stop_half_way_and_resume(const std::string& name, const std::string& contact,
                                      const std::string& time = "") {
  mpmcd::setup_logging(mpmcd::Verbosity::kQuiet);
  const fs::path dir = scratch(name);
  const fs::path in = write_case(dir, 60, "keep = 5\n", contact, time);
  const auto cfg = mpmcd::io::load_config(in.string());
  mpmcd::app::RunOptions opt;
  opt.threads = 1;
  opt.output_dir = (dir / "full").string();
  const auto full = mpmcd::app::run_simulation(cfg, opt);
  EXPECT_FALSE(full.interrupted);
  if (time.empty()) {
    EXPECT_EQ(full.steps, 60);
  }
  const std::int64_t n = full.steps;

  opt.output_dir = (dir / "split").string();
  opt.stop_after = n / 2;
  const auto first = mpmcd::app::run_simulation(cfg, opt);
  EXPECT_TRUE(first.interrupted);
  EXPECT_EQ(first.steps, n / 2);
  EXPECT_EQ(first.checkpoint, (dir / "split" / ck::file_name("pair", n / 2)).string());
  if (first.checkpoint.empty()) return n;
  EXPECT_EQ(ck::read(first.checkpoint).reason, "stop_after");

  // Resume with no input (the checkpoint holds it) into the checkpoint's folder.
  const auto restart = mpmcd::app::load_restart(first.checkpoint, "");
  mpmcd::app::RunOptions ropt;
  ropt.threads = 1;
  ropt.restart = first.checkpoint;
  const auto second = mpmcd::app::run_simulation(restart.config, ropt, &restart.state);
  EXPECT_FALSE(second.interrupted);
  EXPECT_EQ(second.steps, n);
  EXPECT_EQ(second.output_dir, (dir / "split").string());
  expect_identical_runs(dir / "full", dir / "split", n);
  return n;
}
}  // namespace

TEST(Restart, StopHalfWayAndResumeIsBitwise) {
  stop_half_way_and_resume("half", "");
}

// Contacts on the points' faces (walls and grains): their warm-start keys are face numbers, which
// the checkpoint check refused before 2026-11-25 ("names a node that does not exist").
TEST(Restart, StopHalfWayAndResumeWithFaceContactsIsBitwise) {
  stop_half_way_and_resume("half_faces", "wall_contact = \"points\"\ngrain_contact = \"faces\"\n");
}

// Δt from the Newton count (docs/robustness.md): the step changes along the run (the checkpoint
// holds Δt and the good steps since the last cut), and a run stopped half-way and resumed ends
// on the same bits in the same number of steps.
TEST(Restart, NewtonStepControlResumesBitwise) {
  const std::int64_t n = stop_half_way_and_resume(
      "newton", "",
      "control = \"newton\"\ndt_max = 8e-5\ntarget_iterations = 4\nrecover_steps = 2\n");
  // Not 60 steps of 2e-5 s: the step grew in flight and shrank in the collision.
  EXPECT_LT(n, 50);
  EXPECT_GT(n, 15);
}

// The real binary: SIGTERM after some progress -> exit 4 and the resume line; resuming it gives
// the uninterrupted result bitwise.
TEST(Restart, SigtermThenResumeIsBitwise) {
  const fs::path dir = scratch("sigterm");
  const int n = 400;
  const fs::path in = reference(dir, n, "");
  const fs::path out = dir / "run";
  const pid_t pid =
      spawn({"run", "-t", "1", in.string(), "-o", out.string()}, dir / "interrupted.log");
  ASSERT_TRUE(wait_for([&] { return csv_rows(out / "pair.csv") >= n / 4; }));
  kill(pid, SIGTERM);
  const int code = wait_exit(pid);
  const std::string log = mpmcd::test_support::read_file(dir / "interrupted.log");
  ASSERT_EQ(code, 4) << log;
  EXPECT_NE(log.find("interrupted (SIGTERM) at step "), std::string::npos) << log;
  const auto ckpts = ck::list(out.string(), "pair");
  ASSERT_EQ(ckpts.size(), 1u) << log;
  EXPECT_NE(log.find("resume with: mpmcd run --restart " + ckpts.back()), std::string::npos) << log;
  const ck::State s = ck::read(ckpts.back());
  EXPECT_EQ(s.reason, "signal");
  EXPECT_GT(s.step, 0);
  EXPECT_LT(s.step, n);
  EXPECT_EQ(csv_rows(out / "pair.csv"), s.step + 1);  // every row up to the interrupted step
  // Resume, naming the input too (it must be the same text).
  const int rc = run_binary({"run", "-q", "-t", "1", in.string(), "--restart", ckpts.back()},
                            dir / "resume.log");
  ASSERT_EQ(rc, 0) << mpmcd::test_support::read_file(dir / "resume.log");
  expect_identical_runs(dir / "ref", out, n);
}

// SIGKILL at any moment leaves the last complete checkpoint readable; resuming from it (rows and
// snapshots written after it are dropped or rewritten) still reproduces the reference bitwise.
TEST(Restart, SigkillLeavesALoadableCheckpoint) {
  const fs::path dir = scratch("sigkill");
  const int n = 400;
  const std::string every = "every_steps = 3\nkeep = 3\n";
  const fs::path in = reference(dir, n, every);
  const fs::path out = dir / "run";
  const pid_t pid =
      spawn({"run", "-q", "-t", "1", in.string(), "-o", out.string()}, dir / "killed.log");
  ASSERT_TRUE(wait_for([&] { return csv_rows(out / "pair.csv") >= 50; }));
  kill(pid, SIGKILL);
  EXPECT_EQ(wait_exit(pid), 128 + SIGKILL);
  const auto ckpts = ck::list(out.string(), "pair");
  ASSERT_FALSE(ckpts.empty());
  // keep = 3, plus the newest when the kill falls between its rename and the pruning of the
  // oldest (a checkpoint is pruned only once its successor is safe on disk).
  EXPECT_LE(ckpts.size(), 4u);
  const ck::State s = ck::read(ckpts.back());  // throws if damaged
  EXPECT_EQ(s.step % 3, 0);
  const int rc =
      run_binary({"run", "-q", "-t", "1", "--restart", ckpts.back()}, dir / "resume.log");
  ASSERT_EQ(rc, 0) << mpmcd::test_support::read_file(dir / "resume.log");
  expect_identical_runs(dir / "ref", out, n);
}

// Damaged checkpoints are refused by the command line with exit 2 and a clear message; an input
// other than the checkpoint's is refused too.
TEST(Restart, DamagedCheckpointOrForeignInputExits2) {
  const fs::path dir = scratch("damaged");
  const fs::path in = write_case(dir, 10, "");
  ASSERT_EQ(run_binary({"run", "-q", in.string()}, dir / "run.log"), 0)
      << mpmcd::test_support::read_file(dir / "run.log");
  const fs::path good = dir / "out" / ck::file_name("pair", 10);
  const std::string bytes = mpmcd::test_support::read_file(good);
  ASSERT_GT(bytes.size(), 1000u);
  std::ofstream(dir / "truncated.h5", std::ios::binary) << bytes.substr(0, bytes.size() - 100);
  std::string flipped = bytes;
  flipped[bytes.size() / 2] = static_cast<char>(flipped[bytes.size() / 2] ^ 1);
  std::ofstream(dir / "flipped.h5", std::ios::binary) << flipped;
  std::ofstream(dir / "empty.h5", std::ios::binary) << "";
  // Issue 17: a bit flipped in the header's NUL padding (outside the checksum before format 6).
  std::string padding = bytes;
  ASSERT_EQ(padding[300], '\0');
  padding[300] = 1;
  std::ofstream(dir / "padding.h5", std::ios::binary) << padding;
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"truncated.h5", "truncated"},
      {"flipped.h5", "checksum mismatch"},
      {"padding.h5", "checksum mismatch"},
      {"empty.h5", "shorter than its 512-byte header"},
      {"absent.h5", "no such file"}};
  for (const auto& [file, fragment] : cases) {
    const int rc = run_binary({"run", "--restart", (dir / file).string()}, dir / "bad.log");
    const std::string log = mpmcd::test_support::read_file(dir / "bad.log");
    EXPECT_EQ(rc, 2) << file << ": " << log;
    EXPECT_NE(log.find("checkpoint refused: "), std::string::npos) << log;
    EXPECT_NE(log.find(fragment), std::string::npos) << log;
  }
  // Another input: refused, the checkpoint is not loaded.
  const fs::path other = dir / "other.toml";
  std::ofstream(other) << mpmcd::test_support::read_file(in) << "# edited\n";
  EXPECT_EQ(run_binary({"run", other.string(), "--restart", good.string()}, dir / "bad.log"), 2);
  EXPECT_NE(mpmcd::test_support::read_file(dir / "bad.log").find("is not the one checkpoint"),
            std::string::npos)
      << mpmcd::test_support::read_file(dir / "bad.log");
  // Nothing to run.
  EXPECT_EQ(run_binary({"run"}, dir / "bad.log"), 2);
}

// Issue 17: bitwise equality is promised for the same thread count only; a restart with another
// one says so (the checkpoint stores the writer's thread count), one with the same does not.
TEST(Restart, AnotherThreadCountPrintsANote) {
  const fs::path dir = scratch("threads");
  const fs::path in = write_case(dir, 8, "");
  ASSERT_EQ(run_binary({"run", "-q", "-t", "2", in.string(), "--stop-after", "4"}, dir / "a.log"),
            4)
      << mpmcd::test_support::read_file(dir / "a.log");
  const fs::path ckpt = dir / "out" / ck::file_name("pair", 4);
  EXPECT_EQ(ck::read(ckpt.string()).threads, 2);
  ASSERT_EQ(run_binary({"run", "-q", "-t", "1", "--restart", ckpt.string()}, dir / "b.log"), 0)
      << mpmcd::test_support::read_file(dir / "b.log");
  EXPECT_NE(mpmcd::test_support::read_file(dir / "b.log")
                .find("note: the checkpoint was written with 2 thread(s) per rank, "
                      "this run has 1: the run goes on, but bitwise equality with "
                      "an uninterrupted run is promised only with the same thread "
                      "count (-t 2)"),
            std::string::npos)
      << mpmcd::test_support::read_file(dir / "b.log");
  EXPECT_EQ(ck::read((dir / "out" / ck::file_name("pair", 8)).string()).threads, 1);
  ASSERT_EQ(run_binary({"run", "-q", "-t", "2", "--restart", ckpt.string()}, dir / "c.log"), 0)
      << mpmcd::test_support::read_file(dir / "c.log");
  EXPECT_EQ(mpmcd::test_support::read_file(dir / "c.log").find("note:"), std::string::npos)
      << mpmcd::test_support::read_file(dir / "c.log");
}

// Checkpoint format 7 added the wall loading; a format 6 file (written by the mpmcd before it,
// format6/: a disk over a rising floor, stopped after step 1 of 3) is still read and continues
// the run to the same CSV bytes as that mpmcd's uninterrupted run (format6/tiny_full.csv).
TEST(Restart, AFormat6CheckpointStillContinuesBitwise) {
  const fs::path src = fs::path(MPMCD_TEST_DIR) / "format6";
  const fs::path dir = scratch("format6");
  const fs::path ckpt = dir / "tiny_checkpoint_000000001.h5";
  fs::copy_file(src / "tiny_checkpoint_000000001.h5", ckpt);
  fs::copy_file(src / "tiny_step1.csv", dir / "tiny.csv");
  ASSERT_EQ(mpmcd::test_support::read_file(ckpt).rfind("MPMCD-CHECKPOINT 6\n", 0), 0u);
  const ck::State s = ck::read(ckpt.string());
  EXPECT_EQ(s.step, 1);
  EXPECT_TRUE(s.loading_stage.empty() && s.loading_control.empty() && s.loading_wall.empty());
  const int rc = run_binary({"run", "-q", "-t", "1", "--restart", ckpt.string()}, dir / "run.log");
  ASSERT_EQ(rc, 0) << mpmcd::test_support::read_file(dir / "run.log");
  EXPECT_TRUE(mpmcd::test_support::read_file(dir / "tiny.csv") ==
              mpmcd::test_support::read_file(src / "tiny_full.csv"))
      << mpmcd::test_support::read_file(dir / "tiny.csv") << "\nexpected\n"
      << mpmcd::test_support::read_file(src / "tiny_full.csv");
}

// The CSV rows of a run continued from an old checkpoint against the rows of the uninterrupted run
// of the mpmcd that wrote it: the same header and rows, the rows up to the restart byte for byte,
// the later ones with each field within `rel` of its column's largest magnitude (a solver change
// since, such as a convergence test, moves them at the tolerance's level; a misread state moves
// them far more). The solver's counters (iterations, solves, sweeps) are not compared.
void expect_same_run(const fs::path& got, const fs::path& expected, int restart_step, double rel) {
  const auto rows = [](const fs::path& f) {
    std::vector<std::vector<std::string>> out;
    std::istringstream in(mpmcd::test_support::read_file(f));
    for (std::string line; std::getline(in, line);) {
      out.emplace_back();
      std::istringstream fields(line);
      for (std::string v; std::getline(fields, v, ',');) out.back().push_back(v);
    }
    return out;
  };
  const auto a = rows(got), b = rows(expected);
  ASSERT_EQ(a.size(), b.size());
  ASSERT_FALSE(b.empty());
  ASSERT_EQ(a[0], b[0]) << "header";
  const std::vector<std::string>& header = b[0];
  for (std::size_t k = 0; k < header.size(); ++k) {
    if (header[k] == "newton_iterations" || header[k] == "linear_solves" ||
        header[k] == "gs_sweeps")
      continue;
    // Quantities that vanish by symmetry or by the energy balance are judged on the scale of the
    // ones they come from.
    static const std::map<std::string, std::vector<std::string>> siblings{
        {"momentum_x", {"momentum_y"}},
        {"lw_sxy", {"lw_sxx", "lw_syy"}},
        {"energy_unaccounted", {"energy_change"}}};
    std::vector<std::size_t> columns{k};
    if (const auto it = siblings.find(header[k]); it != siblings.end())
      for (const std::string& name : it->second)
        columns.push_back(static_cast<std::size_t>(std::find(header.begin(), header.end(), name) -
                                                   header.begin()));
    double scale = 0;
    for (std::size_t c : columns) {
      ASSERT_LT(c, header.size()) << "no sibling column of " << header[k];
      for (std::size_t r = 1; r < b.size(); ++r)
        scale = std::max(scale, std::abs(std::stod(b[r][c])));
    }
    for (std::size_t r = 1; r < b.size(); ++r) {
      if (static_cast<int>(r) - 1 <= restart_step) {
        EXPECT_EQ(a[r][k], b[r][k]) << header[k] << ", row " << r;
        continue;
      }
      const double x = std::stod(a[r][k]), y = std::stod(b[r][k]);
      if (std::isnan(y)) {
        EXPECT_TRUE(std::isnan(x)) << header[k] << ", row " << r;
        continue;
      }
      EXPECT_LE(std::abs(x - y), rel * scale)
          << header[k] << ", row " << r << ": " << x << " vs " << y;
    }
  }
}

// Checkpoint format 8 added the servo's integral (a 13th value per wall in /loading/wall); a
// format 7 file with [loading] (written by the mpmcd before it, format7/: a block whose top wall
// is a servo, stopped after step 10 of 30 in the middle of its ramp) is read with the integral 0
// and continues the run as that mpmcd's uninterrupted run did. Until 2026-11-26 to the same CSV
// bytes; the convergence test of contact increments changed since (docs/contact.md, "Convergence
// of the staggering"), which moves the later rows by up to 1e-9 of their columns' scale, so the
// rows after the restart are compared to 1e-7 of it (expect_same_run).
TEST(Restart, AFormat7CheckpointWithLoadingStillContinuesItsRun) {
  const fs::path src = fs::path(MPMCD_TEST_DIR) / "format7";
  const fs::path dir = scratch("format7");
  const fs::path ckpt = dir / "tiny_loading_checkpoint_000000010.h5";
  fs::copy_file(src / "tiny_loading_checkpoint_000000010.h5", ckpt);
  fs::copy_file(src / "tiny_loading_step10.csv", dir / "tiny_loading.csv");
  ASSERT_EQ(mpmcd::test_support::read_file(ckpt).rfind("MPMCD-CHECKPOINT 7\n", 0), 0u);
  const ck::State s = ck::read(ckpt.string());
  EXPECT_EQ(s.step, 10);
  ASSERT_EQ(s.loading_control.size(), 4u);
  EXPECT_EQ(s.loading_control[1], 1) << "the top wall is not stress-controlled";
  EXPECT_EQ(s.loading_wall.size(), 4u * 12u);
  const int rc = run_binary({"run", "-q", "-t", "1", "--restart", ckpt.string()}, dir / "run.log");
  ASSERT_EQ(rc, 0) << mpmcd::test_support::read_file(dir / "run.log");
  expect_same_run(dir / "tiny_loading.csv", src / "tiny_loading_full.csv", 10, 1e-7);
}
