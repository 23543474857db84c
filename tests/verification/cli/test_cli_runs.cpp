// The `mpmcd` command line as a user runs it, its runs: a run's CSV series and stamped input
// copy, numerical failures (exit 3, the last good state and its checkpoint), `pack` then `run`,
// a packing that did not relax, the OpenMP spin count of the run's first log line.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "mpmcd/analysis/time_series.hpp"
#include "mpmcd/checkpoint/checkpoint.hpp"
#include "mpmcd/core/openmp_env.hpp"

#include "cli_helpers.hpp"

using namespace mpmcd::test_support::cli;

TEST(Cli, RunWritesSeriesCsvAndStampedInputCopy) {
  const fs::path dir = scratch("run");
  const Result r = run("run -q " + example() + " -o " + dir.string());
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_TRUE(r.output.empty()) << "--quiet printed: " << r.output;
  const std::string copy = mpmcd::test_support::read_file(dir / "input.toml");
  EXPECT_EQ(copy.rfind("# run by mpmcd ", 0), 0u);
  EXPECT_NE(copy.find(mpmcd::test_support::read_file(example())), std::string::npos);
  const std::string pvd = mpmcd::test_support::read_file(dir / "squeezed_disk.pvd");
  int frames = 0, contact_frames = 0;  // point snapshots and contact snapshots (walls)
  for (auto& e : fs::directory_iterator(dir)) {
    if (e.path().extension() != ".vtu") continue;
    const bool contacts = e.path().filename().string().find("_contacts_") != std::string::npos;
    (contacts ? contact_frames : frames) += 1;
  }
  EXPECT_EQ(frames, 25);  // t = 0 and every 2.5e-4 s up to 6e-3 s
  EXPECT_EQ(contact_frames, 25);
  EXPECT_NE(pvd.find("squeezed_disk_000024.vtu"), std::string::npos);
  // CSV: header + one row per 5e-5 s; mass identical on every row.
  const auto series = mpmcd::analysis::read_time_series((dir / "squeezed_disk.csv").string());
  EXPECT_EQ(series.names.at(0), "step");
  const auto& mass = series.column("mass");
  ASSERT_EQ(mass.size(), 121u);
  for (double m : mass) EXPECT_EQ(m, mass.front());
}

TEST(Cli, InvertedPointStopsWithExit3AndLastGoodState) {
  const fs::path dir = scratch("diverge");
  // A disk crushed along x at 1500 /s with dt = 1 ms: dF11 = -0.5 -> J < 0; no dt cut allowed.
  const fs::path in = write_input(dir,
                                  "[[grains]]\nshape = \"disk\"\nmaterial = \"gel\"\n"
                                  "center = [0.01, 0.01]\nradius = 0.004\n"
                                  "[grains.initial]\ngradient = [-1500.0, 0.0, 0.0, 0.0]\n",
                                  "[time]\ndt = 1e-3\ndt_min = 1e-3\nend_time = 1e-2\n");
  const Result r = run("run " + in.string());
  EXPECT_EQ(r.code, 3) << r.output;
  EXPECT_NE(r.output.find("J = "), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("step 1"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("grain 0"), std::string::npos) << r.output;
  EXPECT_TRUE(fs::exists(dir / "out" / "mpmcd_last_good.vtu")) << r.output;
  // A loadable checkpoint of the last good step (step 0), named in the diagnostic.
  const fs::path ckpt = dir / "out" / "mpmcd_checkpoint_000000000.h5";
  EXPECT_NE(r.output.find("checkpoint of the last good step: " + ckpt.string()), std::string::npos)
      << r.output;
  const auto state = mpmcd::checkpoint::read(ckpt.string());
  EXPECT_EQ(state.step, 0);
  EXPECT_EQ(state.reason, "failure");
  EXPECT_EQ(state.points(), 227u);  // the disk on rings (polar seeding, the default for disks)
  // Resuming it meets the same failure: exit 3 again, not a crash.
  const Result again = run("run --restart " + ckpt.string());
  EXPECT_EQ(again.code, 3) << again.output;
  EXPECT_NE(again.output.find("J = "), std::string::npos) << again.output;
}

TEST(Cli, PointLeavingTheGridStopsWithExit3) {
  const fs::path dir = scratch("leave");
  const fs::path in = write_input(dir,
                                  "[[grains]]\nshape = \"disk\"\nmaterial = \"gel\"\n"
                                  "center = [0.01, 0.01]\nradius = 0.004\n"
                                  "[grains.initial]\nvelocity = [10.0, 0.0]\n",
                                  "[time]\ndt = 1e-4\nend_time = 1e-2\n");
  const Result r = run("run " + in.string());
  EXPECT_EQ(r.code, 3) << r.output;
  EXPECT_NE(r.output.find("left the grid"), std::string::npos) << r.output;
  // Issue 17: the failure checkpoint is the last state that is actually good. The step that would
  // move a point off the grid fails; the one before it is saved, names one step in every line and
  // is accepted by --restart, which meets the same failure again (exit 3, not a refusal).
  std::string ckpt;
  for (const auto& e : fs::directory_iterator(dir / "out"))
    if (e.path().extension() == ".h5") ckpt = e.path().string();
  ASSERT_FALSE(ckpt.empty()) << r.output;
  const auto state = mpmcd::checkpoint::read(ckpt);
  EXPECT_EQ(state.reason, "failure");
  EXPECT_GT(state.step, 0);
  const std::string failed = "step " + std::to_string(state.step + 1);
  EXPECT_NE(
      r.output.find(failed + " failed; last good state (step " + std::to_string(state.step) + ","),
      std::string::npos)
      << r.output;
  EXPECT_NE(
      r.output.find("in " + failed + ", after the last good step " + std::to_string(state.step) +
                    "; checkpoint of the last good step: " + ckpt),
      std::string::npos)
      << r.output;
  int outside = 0;  // the grid is [0, 0.02]^2 m
  for (const double x : state.x) outside += x < 0.0 || x > 0.02;
  EXPECT_EQ(outside, 0) << "coordinates off the grid in the last good state";
  const Result again = run("run --restart " + ckpt);
  EXPECT_EQ(again.code, 3) << again.output;
  EXPECT_NE(again.output.find("left the grid"), std::string::npos) << again.output;
  EXPECT_NE(again.output.find("in " + failed + ","), std::string::npos) << again.output;
}

TEST(Cli, PackThenRunGrainsFromThePackingFile) {
  const fs::path dir = scratch("pack");
  std::ofstream(dir / "pack.toml")
      << "[packing]\ncount = 12\ndiameter_min = 0.8e-3\ndiameter_max = 1.2e-3\n"
         "aspect_ratio = 1.0\norigin = [0.0, 0.0]\ntarget_phi = 0.7\nmethod = \"grow\"\n"
         "seed = 7\n[output]\nfolder = \""
      << dir.string() << "\"\nname = \"packing\"\n";
  const Result p = run("pack -q " + (dir / "pack.toml").string());
  ASSERT_EQ(p.code, 0) << p.output;
  EXPECT_NE(p.output.find("packing: 12 grains, phi = 0.700000"), std::string::npos) << p.output;
  std::ofstream(dir / "run.toml")
      << "[grid]\norigin = [-0.001, -0.001]\nextent = [0.006, 0.006]\ncell_size = 0.000125\n"
         "[[materials]]\nname = \"gel\"\nlaw = \"neo_hookean\"\ndensity = 990.0\n"
         "lambda = 3e6\nmu = 1.5e6\n[[grains]]\nshape = \"packing\"\nfile = \"packing.csv\"\n"
         "material = \"gel\"\n[time]\ndt = 1e-7\nend_time = 5e-7\n[output]\nfolder = \"out\"\n";
  const Result c = run("check " + (dir / "run.toml").string());
  EXPECT_EQ(c.code, 0) << c.output;
  EXPECT_NE(c.output.find("valid (12 grains"), std::string::npos) << c.output;
  const Result r = run("run -q " + (dir / "run.toml").string());
  EXPECT_EQ(r.code, 0) << r.output;
  EXPECT_TRUE(fs::exists(dir / "out" / "mpmcd.csv"));
  // The same packing generated inline from its packing input when the run starts.
  std::string text;
  {
    std::ifstream in(dir / "run.toml");
    std::stringstream ss;
    ss << in.rdbuf();
    text = ss.str();
  }
  text.replace(text.find("packing.csv"), 11, "pack.toml");
  std::ofstream(dir / "inline.toml") << text;
  const Result g = run("check " + (dir / "inline.toml").string());
  EXPECT_EQ(g.code, 0) << g.output;
  EXPECT_NE(g.output.find("valid (12 grains"), std::string::npos) << g.output;
  // A packing whose disk leaves the grid is refused with the disk named.
  std::ofstream(dir / "small.toml")
      << "[grid]\norigin = [0.0, 0.0]\nextent = [0.002, 0.002]\ncell_size = 0.000125\n"
         "[[materials]]\nname = \"gel\"\nlaw = \"neo_hookean\"\ndensity = 990.0\n"
         "lambda = 3e6\nmu = 1.5e6\n[[grains]]\nshape = \"packing\"\nfile = \"packing.csv\"\n"
         "material = \"gel\"\n[time]\ndt = 1e-7\nend_time = 5e-7\n";
  const Result s = run("run " + (dir / "small.toml").string());
  EXPECT_EQ(s.code, 2) << s.output;
  EXPECT_NE(s.output.find("packing.csv: key 'disk "), std::string::npos) << s.output;
}

// Issue 17: `mpmcd pack` does not write a packing that did not relax (one `run` would refuse):
// exit 3, a message saying so and what to change, nothing written.
TEST(Cli, PackRefusesToWriteAPackingThatDidNotRelax) {
  const fs::path dir = scratch("unrelaxed");
  std::ofstream(dir / "pack.toml")
      << "[packing]\ncount = 40\ndiameter_min = 0.8e-3\ndiameter_max = 1.2e-3\n"
         "aspect_ratio = 1.0\ntarget_phi = 0.78\nfriction = 0.3\nseed = 7\n"
         "max_relax_steps = 2000\n[output]\nfolder = \""
      << (dir / "out").string() << "\"\nname = \"packing\"\n";
  const Result p = run("pack -q " + (dir / "pack.toml").string());
  EXPECT_EQ(p.code, 3) << p.output;
  EXPECT_NE(p.output.find("pack.toml: the packing did not relax: disks "), std::string::npos)
      << p.output;
  EXPECT_NE(p.output.find("Nothing written"), std::string::npos) << p.output;
  EXPECT_FALSE(fs::exists(dir / "out" / "packing.csv"));
}

// The spin count mpmcd sets for libgomp unless the user chose a wait policy (core/openmp_env.hpp),
// as the run's log line of ranks and threads reports it.
TEST(Cli, SetsTheOpenMpSpinCountUnlessTheUserChoseAWaitPolicy) {
  const auto first_line = [](const std::string& env) {
    const fs::path dir = scratch("spin");
    const std::string cmd = "env -u OMP_WAIT_POLICY -u GOMP_SPINCOUNT -u MPMCD_OPENMP_ENV_SET " +
                            env + " " + std::string(MPMCD_BINARY) + " run " + example() +
                            " -t 2 --stop-after 1 --overwrite -o " + dir.string() + " 2>&1";
    FILE* pipe = popen(cmd.c_str(), "r");
    std::array<char, 4096> buf{};
    std::string out;
    while (pipe && fgets(buf.data(), buf.size(), pipe)) out += buf.data();
    if (pipe) pclose(pipe);
    const auto at = out.find("rank(s) x");  // the run's first line (threads, wait policy)
    return at == std::string::npos ? out : out.substr(at, out.find('\n', at) - at);
  };
  EXPECT_NE(first_line("").find(fmt::format("(GOMP_SPINCOUNT={})", mpmcd::kGompSpinCount)),
            std::string::npos)
      << first_line("");
  EXPECT_NE(first_line("OMP_WAIT_POLICY=passive").find("(OMP_WAIT_POLICY=passive)"),
            std::string::npos);
  EXPECT_NE(first_line("GOMP_SPINCOUNT=77").find("(GOMP_SPINCOUNT=77)"), std::string::npos);
}
