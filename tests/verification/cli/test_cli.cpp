// The `mpmcd` command line as a user runs it: exit codes (0 ok, 2 bad input, 3 numerical failure),
// nothing written for a bad input, the outputs of a run, the last good state after a failure.
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "mpmcd/analysis/time_series.hpp"
#include "mpmcd/checkpoint/checkpoint.hpp"
#include "mpmcd/core/openmp_env.hpp"

#include "../../support/cli_runner.hpp"
#include "../../support/scratch.hpp"

namespace fs = std::filesystem;

namespace {

using mpmcd::test_support::Result;
using mpmcd::test_support::run;

std::string example() {
  return std::string(MPMCD_SOURCE_DIR) + "/examples/squeezed_disk/squeezed_disk.toml";
}

fs::path scratch(const std::string& name) {
  return mpmcd::test_support::scratch_dir("cli", name);
}

// Writes an input whose only grain is given by `grain` and time section by `time`.
fs::path write_input(const fs::path& dir, const std::string& grain, const std::string& time) {
  const fs::path p = dir / "case.toml";
  std::ofstream(p) << "[grid]\norigin = [0.0, 0.0]\nextent = [0.02, 0.02]\ncell_size = 0.001\n"
                      "[[materials]]\nname = \"gel\"\nlaw = \"neo_hookean\"\ndensity = 990.0\n"
                      "lambda = 3e6\nmu = 1.5e6\n"
                   << grain << time << "[output]\nfolder = \"out\"\n";
  return p;
}

}  // namespace

TEST(Cli, CheckAcceptsTheExample) {
  const Result r = run("check " + example());
  EXPECT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("valid (1 grains"), std::string::npos) << r.output;
}

// Every simulation input under examples/ stays valid (packing inputs, pack.toml, are `mpmcd pack`
// inputs and are checked by the packing tests).
TEST(Cli, CheckAcceptsEveryExampleInput) {
  int checked = 0;
  for (const auto& e : fs::recursive_directory_iterator(fs::path(MPMCD_SOURCE_DIR) / "examples")) {
    if (!e.is_regular_file() || e.path().extension() != ".toml" ||
        e.path().filename() == "pack.toml")
      continue;
    if (e.path().string().find("/output") != std::string::npos) continue;  // run outputs
    const Result r = run("check " + e.path().string());
    EXPECT_EQ(r.code, 0) << e.path() << ": " << r.output;
    ++checked;
  }
  EXPECT_GE(checked, 8);
}

TEST(Cli, BadInputExitsWith2AndWritesNothing) {
  const fs::path dir = scratch("bad");
  const fs::path in = write_input(dir,
                                  "[[grains]]\nshape = \"disk\"\nmaterial = \"gel\"\n"
                                  "center = [0.01, 0.01]\nradius = -0.004\n",
                                  "[time]\ndt = 1e-5\nend_time = 1e-4\n");
  const Result r = run("run " + in.string());
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("case.toml:"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("radius"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir / "out")) << "output written for a rejected input";
  EXPECT_EQ(run("run " + (dir / "missing.toml").string()).code, 2);
  EXPECT_EQ(run("run").code, 2);  // missing argument
  EXPECT_EQ(run("frobnicate").code, 2);
}

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

TEST(Cli, ListPrintsInputReferenceAndLaws) {
  const Result a = run("list input");
  EXPECT_EQ(a.code, 0);
  EXPECT_EQ(a.output,
            mpmcd::test_support::read_file(fs::path(MPMCD_SOURCE_DIR) / "docs" / "input.md"));
  const Result b = run("list laws");
  EXPECT_EQ(b.code, 0);
  EXPECT_NE(b.output.find("neo_hookean"), std::string::npos);
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

// Issue 17: overlapping grains are refused at input (exit 2, both grains and the overlap named,
// nothing written); touching ones pass. Before, they ran and their common area counted twice.
TEST(Cli, OverlappingGrainsAreRefusedTouchingOnesPass) {
  const fs::path dir = scratch("overlap");
  const auto disks = [](double dx) {
    return fmt::format(
        "[[grains]]\nshape = \"disk\"\nmaterial = \"gel\"\ncenter = [0.01, 0.01]\n"
        "radius = 0.001\n[[grains]]\nshape = \"disk\"\nmaterial = \"gel\"\n"
        "center = [{:.17g}, 0.01]\nradius = 0.001\n",
        0.01 + dx);
  };
  const std::string time = "[time]\ndt = 1e-5\nend_time = 2e-5\n";
  const fs::path in = write_input(dir, disks(0.0005), time);
  for (const std::string cmd : {"check ", "run "}) {
    const Result r = run(cmd + in.string());
    EXPECT_EQ(r.code, 2) << r.output;
    EXPECT_NE(r.output.find("case.toml:16: key 'grains[1]': grains that touch but do not "
                            "overlap (up to 0.001 of the smaller one's diameter or side): "
                            "grains[1] (line 16) overlaps grains[0] (line 11) by 0.0015 m = 0.75 "
                            "of the smaller size"),
              std::string::npos)
        << r.output;
  }
  EXPECT_FALSE(fs::exists(dir / "out"));
  const Result touching = run("check " + write_input(dir, disks(0.002), time).string());
  EXPECT_EQ(touching.code, 0) << touching.output;
  // A packing file with a disk given twice (under another id): refused naming both lines.
  std::ofstream(dir / "packing.csv") << "# box = 0.002 0.002 0.018 0.018\nid,x,y,radius\n"
                                        "0,0.005,0.005,0.001\n1,0.01,0.01,0.001\n"
                                        "2,0.015,0.015,0.001\n3,0.01,0.01,0.001\n";
  const fs::path pk = write_input(
      dir, "[[grains]]\nshape = \"packing\"\nfile = \"packing.csv\"\nmaterial = \"gel\"\n", time);
  const Result dup = run("run " + pk.string());
  EXPECT_EQ(dup.code, 2) << dup.output;
  EXPECT_NE(dup.output.find("packing.csv:6: disk id 3 to overlap no other disk"), std::string::npos)
      << dup.output;
  EXPECT_NE(dup.output.find("overlaps disk id 1 of line 4 by 0.002 m"), std::string::npos)
      << dup.output;
  EXPECT_FALSE(fs::exists(dir / "out"));
  // A packing disk over an explicit disk: both named.
  const fs::path mixed =
      write_input(dir,
                  "[[grains]]\nshape = \"packing\"\nfile = \"packing.csv\"\nmaterial = \"gel\"\n"
                  "[[grains]]\nshape = \"disk\"\nmaterial = \"gel\"\ncenter = [0.0155, 0.015]\n"
                  "radius = 0.001\n",
                  time);
  std::ofstream(dir / "packing.csv") << "# box = 0.002 0.002 0.018 0.018\nid,x,y,radius\n"
                                        "0,0.005,0.005,0.001\n1,0.01,0.01,0.001\n"
                                        "2,0.015,0.015,0.001\n";
  const Result mix = run("check " + mixed.string());
  EXPECT_EQ(mix.code, 2) << mix.output;
  EXPECT_NE(mix.output.find("grains[1] (line 15) overlaps disk id 2 of "), std::string::npos)
      << mix.output;
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

namespace {

std::vector<std::string> names_in(const fs::path& dir) {
  std::vector<std::string> out;
  for (const auto& e : fs::directory_iterator(dir)) out.push_back(e.path().filename().string());
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace

// Issue 17: a reused output folder never mixes two runs. A folder holding a run (input.toml or
// files named after the run) is refused with exit 2 and left as it is; --overwrite removes that
// run's files (and those of the run named in the old input.toml) first. The same for pack.
TEST(Cli, ReusedOutputFolderIsRefusedUnlessOverwrite) {
  const fs::path dir = scratch("reuse");
  const std::string disk =
      "[[grains]]\nshape = \"disk\"\nmaterial = \"gel\"\ncenter = [0.01, 0.01]\nradius = 0.004\n";
  const fs::path five = write_input(dir, disk, "[time]\ndt = 1e-5\nend_time = 5e-5\n");
  fs::rename(five, dir / "five.toml");
  ASSERT_EQ(run("run -q " + (dir / "five.toml").string()).code, 0);
  const auto first = names_in(dir / "out");
  EXPECT_TRUE(fs::exists(dir / "out" / "mpmcd_000005.vtu"));
  const std::string csv = mpmcd::test_support::read_file(dir / "out" / "mpmcd.csv");
  const fs::path three = write_input(dir, disk, "[time]\ndt = 1e-5\nend_time = 3e-5\n");
  const Result again = run("run -q " + three.string());
  EXPECT_EQ(again.code, 2) << again.output;
  EXPECT_NE(again.output.find("case.toml: key 'output.folder': a folder without the files of an "
                              "earlier run named 'mpmcd', but '"),
            std::string::npos)
      << again.output;
  EXPECT_NE(again.output.find("give --overwrite to remove them first"), std::string::npos)
      << again.output;
  EXPECT_EQ(names_in(dir / "out"), first);
  EXPECT_EQ(mpmcd::test_support::read_file(dir / "out" / "mpmcd.csv"), csv);
  // --overwrite: only the new run's files, none of the longer first run's snapshots.
  const Result over = run("run -q --overwrite " + three.string());
  EXPECT_EQ(over.code, 0) << over.output;
  EXPECT_FALSE(fs::exists(dir / "out" / "mpmcd_000004.vtu"));
  EXPECT_FALSE(fs::exists(dir / "out" / "mpmcd_000005.vtu"));
  EXPECT_FALSE(fs::exists(dir / "out" / "mpmcd_checkpoint_000000005.h5"));
  EXPECT_TRUE(fs::exists(dir / "out" / "mpmcd_000003.vtu"));
  EXPECT_EQ(mpmcd::test_support::read_file(dir / "out" / "mpmcd.pvd").find("mpmcd_000004.vtu"),
            std::string::npos);
  // A run of another name: refused (the folder holds a run), then it replaces the old one.
  const fs::path other = write_input(dir, "[simulation]\nname = \"other\"\n" + disk,
                                     "[time]\ndt = 1e-5\nend_time = 2e-5\n");
  const Result named = run("run -q " + other.string() + " -o " + (dir / "out").string());
  EXPECT_EQ(named.code, 2) << named.output;
  EXPECT_NE(named.output.find("key '-o': a folder without the files of an earlier run (named "
                              "'mpmcd', this one 'other')"),
            std::string::npos)
      << named.output;
  ASSERT_EQ(run("run -q --overwrite " + other.string() + " -o " + (dir / "out").string()).code, 0);
  for (const auto& f : names_in(dir / "out"))
    EXPECT_TRUE(f == "input.toml" || f.rfind("other", 0) == 0) << f << " left in the folder";
  // mpmcd pack: the same rule for <name>.csv / <name>.vtu.
  std::ofstream(dir / "pack.toml")
      << "[packing]\ncount = 12\ndiameter_min = 0.8e-3\ndiameter_max = 1.2e-3\n"
         "aspect_ratio = 1.0\ntarget_phi = 0.7\nseed = 7\n[output]\nfolder = \""
      << (dir / "pk").string() << "\"\nname = \"packing\"\n";
  ASSERT_EQ(run("pack -q " + (dir / "pack.toml").string()).code, 0);
  const Result pack_again = run("pack -q " + (dir / "pack.toml").string());
  EXPECT_EQ(pack_again.code, 2) << pack_again.output;
  EXPECT_NE(pack_again.output.find("pack.toml: key 'output.folder': a folder without the files "
                                   "of an earlier packing named 'packing'"),
            std::string::npos)
      << pack_again.output;
  EXPECT_EQ(run("pack -q --overwrite " + (dir / "pack.toml").string()).code, 0);
}

// Issue 17: `--restart ck.h5 -o elsewhere` makes `elsewhere` hold the whole run: the CSV rows and
// snapshots written before the checkpoint are copied from its folder, so every file the .pvd
// series list is there, and the folder equals that of an uninterrupted run (same thread count).
TEST(Cli, RestartIntoAnotherFolderHoldsTheWholeRun) {
  const fs::path dir = scratch("moved");
  const fs::path in = write_input(dir,
                                  "[[grains]]\nshape = \"disk\"\nmaterial = \"gel\"\n"
                                  "center = [0.006, 0.01]\nradius = 0.003\n"
                                  "[[grains]]\nshape = \"disk\"\nmaterial = \"gel\"\n"
                                  "center = [0.014, 0.01]\nradius = 0.003\n",
                                  "[time]\ndt = 1e-5\nend_time = 1e-4\n");
  const std::string base = "run -q -t 1 " + in.string() + " -o ";
  ASSERT_EQ(run(base + (dir / "full").string()).code, 0);
  ASSERT_EQ(run(base + (dir / "part").string() + " --stop-after 4").code, 4);
  const fs::path ckpt = dir / "part" / "mpmcd_checkpoint_000000004.h5";
  ASSERT_TRUE(fs::exists(ckpt));
  const Result r =
      run("run -q -t 1 --restart " + ckpt.string() + " -o " + (dir / "moved").string());
  ASSERT_EQ(r.code, 0) << r.output;
  const auto listed = [](const fs::path& pvd) {
    std::vector<std::string> files;
    const std::string text = mpmcd::test_support::read_file(pvd);
    for (std::size_t at = text.find("file=\""); at != std::string::npos;
         at = text.find("file=\"", at + 1))
      files.push_back(text.substr(at + 6, text.find('"', at + 6) - at - 6));
    return files;
  };
  for (const char* series : {"mpmcd.pvd", "mpmcd_contacts.pvd"}) {
    const auto files = listed(dir / "moved" / series);
    EXPECT_EQ(files.size(), 11u) << series;
    for (const auto& f : files) EXPECT_TRUE(fs::exists(dir / "moved" / f)) << f << " listed";
    EXPECT_EQ(mpmcd::test_support::read_file(dir / "moved" / series),
              mpmcd::test_support::read_file(dir / "full" / series))
        << series;
  }
  auto outputs = [](const fs::path& d) {
    std::vector<std::string> out;
    for (const auto& f : names_in(d))
      if (f.find("timers") == std::string::npos && f != "input.toml") out.push_back(f);
    return out;
  };
  EXPECT_EQ(outputs(dir / "moved"), outputs(dir / "full"));
  for (const auto& f : outputs(dir / "full"))
    EXPECT_EQ(mpmcd::test_support::read_file(dir / "moved" / f),
              mpmcd::test_support::read_file(dir / "full" / f))
        << f;
  // A restart into a folder holding another run is refused like a new run.
  const Result taken =
      run("run -q -t 1 --restart " + ckpt.string() + " -o " + (dir / "full").string());
  EXPECT_EQ(taken.code, 2) << taken.output;
}

// Issue 17, messages. A full disk: the reason is named and no .tmp file is left behind (a
// file-size limit stands in for the full disk: write(2) fails with EFBIG, SIGXFSZ ignored; `pack`,
// which does not start MPI, whose start-up needs a few MB of files).
TEST(Cli, AFailedWriteNamesTheReasonAndLeavesNoTmp) {
  const fs::path dir = scratch("full");
  std::ofstream(dir / "pack.toml")
      << "[packing]\ncount = 40\ndiameter_min = 0.8e-3\ndiameter_max = 1.2e-3\n"
         "aspect_ratio = 1.0\ntarget_phi = 0.7\nseed = 7\n[output]\nfolder = \""
      << (dir / "out").string() << "\"\nname = \"packing\"\n";
  const std::string cmd = "trap '' XFSZ; ulimit -f 2; " + std::string(MPMCD_BINARY) + " pack -q " +
                          (dir / "pack.toml").string() + " 2>&1";
  FILE* pipe = popen(cmd.c_str(), "r");
  ASSERT_NE(pipe, nullptr);
  std::string out;
  std::array<char, 4096> buf{};
  while (fgets(buf.data(), buf.size(), pipe)) out += buf.data();
  const int status = pclose(pipe);
  EXPECT_EQ(WIFEXITED(status) ? WEXITSTATUS(status) : -1, 1) << out;
  EXPECT_NE(out.find("mpmcd: error: cannot write '" + (dir / "out" / "packing.csv.tmp").string() +
                     "': " + std::strerror(EFBIG)),
            std::string::npos)
      << out;
  for (const auto& f : names_in(dir / "out"))
    EXPECT_NE(fs::path(f).extension(), ".tmp") << f << " left behind";
}

// `mpmcd pack` given a simulation input names the missing [packing] table; a packing path that
// is a directory is called a directory.
TEST(Cli, PackOfASimulationInputAndAPackingThatIsADirectory) {
  const Result p = run("pack " + example());
  EXPECT_EQ(p.code, 2) << p.output;
  EXPECT_NE(p.output.find("squeezed_disk.toml: key 'packing': a [packing] table (docs/packing.md "
                          "§5): this looks like a simulation input, which `mpmcd run` takes"),
            std::string::npos)
      << p.output;
  const fs::path dir = scratch("dirpacking");
  fs::create_directories(dir / "pk");
  const fs::path in =
      write_input(dir, "[[grains]]\nshape = \"packing\"\nfile = \"pk\"\nmaterial = \"gel\"\n",
                  "[time]\ndt = 1e-5\nend_time = 5e-5\n");
  const Result c = run("check " + in.string());
  EXPECT_EQ(c.code, 2) << c.output;
  EXPECT_NE(c.output.find("is a directory"), std::string::npos) << c.output;
  EXPECT_EQ(c.output.find("not found"), std::string::npos) << c.output;
  const Result d = run("pack " + dir.string());
  EXPECT_EQ(d.code, 2) << d.output;
  EXPECT_NE(d.output.find("it is a directory"), std::string::npos) << d.output;
}

TEST(Cli, CheckRefusesAPackingBoxLargerThanTheGridBeforeTheDem) {
  // 20,000 disks of 0.8-1.2 mm at Phi = 0.78 need a box of at least 0.14 m; the grid is 6 mm. The
  // refusal must come from the box (known before the DEM), not after running it (18 s before).
  const fs::path dir = scratch("packbox");
  std::ofstream(dir / "pack.toml")
      << "[packing]\ncount = 20000\ndiameter_min = 0.8e-3\ndiameter_max = 1.2e-3\n"
         "aspect_ratio = 1.0\norigin = [0.0, 0.0]\ntarget_phi = 0.78\nmethod = \"grow\"\n"
         "seed = 7\n[output]\nfolder = \"out\"\nname = \"packing\"\n";
  std::ofstream(dir / "run.toml")
      << "[grid]\norigin = [-0.001, -0.001]\nextent = [0.006, 0.006]\ncell_size = 0.000125\n"
         "[[materials]]\nname = \"gel\"\nlaw = \"neo_hookean\"\ndensity = 990.0\n"
         "lambda = 3e6\nmu = 1.5e6\n[[grains]]\nshape = \"packing\"\nfile = \"pack.toml\"\n"
         "material = \"gel\"\n[time]\ndt = 1e-7\nend_time = 5e-7\n[output]\nfolder = \"out\"\n";
  const auto t0 = std::chrono::steady_clock::now();
  const Result c = run("check " + (dir / "run.toml").string());
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_EQ(c.code, 2) << c.output;
  EXPECT_NE(c.output.find("packing box"), std::string::npos) << c.output;
  EXPECT_NE(c.output.find("checked before the DEM runs"), std::string::npos) << c.output;
  EXPECT_LT(secs, 5.0) << "the DEM ran before the box was checked";
}

// Issue 17: the snapshots are read by other tools. Debian's python3-meshio (5.0) reads every
// point snapshot and every contacts snapshot with contacts; a snapshot without contacts (step 0
// always) is a valid empty piece, which VTK reads (checked when python3-vtk9 is there) but which
// no meshio release reads (it refuses every mesh without cells, its own too: meshio issue 1412),
// docs/robustness.md. Skipped without meshio.
TEST(Cli, SnapshotsAreReadByMeshioAndTheEmptyContactsPieceByVtk) {
  if (std::system("/usr/bin/python3 -c 'import meshio' >/dev/null 2>&1") != 0)
    GTEST_SKIP() << "/usr/bin/python3 with meshio not found (Debian: python3-meshio)";
  const fs::path dir = scratch("meshio");
  // Two touching disks pushed together: no contact at step 0, contacts from step 1.
  const fs::path in = write_input(dir,
                                  "[[grains]]\nshape = \"disk\"\nmaterial = \"gel\"\n"
                                  "center = [0.0065, 0.01]\nradius = 0.0035\n"
                                  "[grains.initial]\nvelocity = [0.5, 0.0]\n"
                                  "[[grains]]\nshape = \"disk\"\nmaterial = \"gel\"\n"
                                  "center = [0.0135, 0.01]\nradius = 0.0035\n"
                                  "[grains.initial]\nvelocity = [-0.5, 0.0]\n",
                                  "[time]\ndt = 1e-5\nend_time = 5e-5\n");
  const Result r = run("run -q -t 1 " + in.string() + " -o " + (dir / "out").string());
  ASSERT_EQ(r.code, 0) << r.output;
  std::ofstream(dir / "read.py") << R"py(import glob, re, sys
import meshio
counts = {"points": 0, "contacts": 0, "empty": []}
for f in sorted(glob.glob(sys.argv[1] + "/*.vtu")):
    n = int(re.search(rb'NumberOfPoints="(\d+)"', open(f, "rb").read(4096)).group(1))
    if n == 0:
        counts["empty"].append(f)
        continue
    m = meshio.read(f)
    assert m.points.shape == (n, 3), (f, m.points.shape)
    assert sum(len(c.data) for c in m.cells) == n, f
    kind = "contacts" if "_contacts_" in f else "points"
    want = "normal_impulse" if kind == "contacts" else "stress"
    assert want in m.point_data and len(m.point_data[want]) == n, (f, list(m.point_data))
    counts[kind] += 1
print("meshio read", counts["points"], "point and", counts["contacts"], "contact snapshots")
try:
    import vtk
except ImportError:
    print("vtk absent")
    sys.exit(0)
for f in counts["empty"]:
    errors = []
    reader = vtk.vtkXMLUnstructuredGridReader()
    reader.AddObserver("ErrorEvent", lambda o, e: errors.append(e))
    reader.SetFileName(f)
    reader.Update()
    out = reader.GetOutput()
    assert not errors and out.GetNumberOfPoints() == 0 and out.GetNumberOfCells() == 0, f
    assert out.GetPointData().GetArray("normal_impulse") is not None, f
    print("vtk read empty", f.rsplit("/", 1)[-1])
)py";
  FILE* pipe = popen(
      ("/usr/bin/python3 " + (dir / "read.py").string() + " " + (dir / "out").string() + " 2>&1")
          .c_str(),
      "r");
  ASSERT_NE(pipe, nullptr);
  std::string out;
  std::array<char, 4096> buf{};
  while (fgets(buf.data(), buf.size(), pipe)) out += buf.data();
  ASSERT_EQ(pclose(pipe), 0) << out;
  EXPECT_NE(out.find("meshio read 6 point and 5 contact snapshots"), std::string::npos) << out;
  if (out.find("vtk absent") == std::string::npos) {
    EXPECT_NE(out.find("vtk read empty mpmcd_contacts_000000.vtu"), std::string::npos) << out;
  }
  std::printf("%s", out.c_str());
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

// Issue 19: `[output] grains = true` writes, at every snapshot time, the per-grain CSV and the
// contact-force CSV (docs/observables.md, "Grain-scale outputs"), consistent with the CSV time
// series of the same instant; a bad value of the key is refused with exit 2.
TEST(Cli, GrainOutputsAtSnapshotTimes) {
  const fs::path dir = scratch("grains");
  const fs::path src = fs::path(MPMCD_SOURCE_DIR) / "tests" / "verification" / "compaction";
  fs::copy_file(src / "packing.csv", dir / "packing.csv");
  std::string text = mpmcd::test_support::read_file(src / "compaction.toml");
  text.replace(text.find("end_time = 4e-4"), 15, "end_time = 2e-4");
  text.replace(text.find("vtu_interval = 2e-5"), 19, "vtu_interval = 1e-4\ngrains = true");
  std::ofstream(dir / "grains.toml") << text;
  const Result r = run("run -q -t 1 " + (dir / "grains.toml").string());
  ASSERT_EQ(r.code, 0) << r.output;
  const auto series = mpmcd::analysis::read_time_series((dir / "out" / "compaction.csv").string());
  for (const char* c : {"stress_volume", "grain_syy", "contact_syy", "fabric_a", "fabric_contacts"})
    EXPECT_TRUE(series.has(c)) << c;
  const auto& time = series.column("time");
  for (int k = 0; k < 3; ++k) {  // t = 0, 1e-4, 2e-4 s
    const auto grains = mpmcd::analysis::read_time_series(
        (dir / "out" / fmt::format("compaction_grains_{:06d}.csv", k)).string());
    const auto forces = mpmcd::analysis::read_time_series(
        (dir / "out" / fmt::format("compaction_forces_{:06d}.csv", k)).string());
    ASSERT_EQ(grains.rows(), 9u);
    const double t = grains.column("time").front();
    const auto row = static_cast<std::size_t>(
        std::min_element(time.begin(), time.end(),
                         [&](double a, double b) { return std::abs(a - t) < std::abs(b - t); }) -
        time.begin());
    ASSERT_NEAR(time[row], t, 1e-12);
    // The grains' areas sum to Vs, their stresses to the Love-Weber stress of the row.
    double vs = 0, syy = 0;
    for (std::size_t g = 0; g < 9; ++g) {
      vs += grains.column("area")[g];
      syy += grains.column("area")[g] * grains.column("syy")[g];
      EXPECT_NEAR(grains.column("circularity")[g], 1.0, 0.05);
    }
    EXPECT_NEAR(vs / series.column("Vs")[row], 1.0, 1e-11);
    syy /= series.column("box_area")[row];
    EXPECT_NEAR(syy, series.column("lw_syy")[row], 1e-10 * std::abs(series.column("lw_syy")[row]));
    // The rows of the bottom wall (body -1) carry the force of the series' wall column.
    double bottom = 0;
    for (std::size_t c = 0; c < forces.rows(); ++c)
      if (forces.column("a")[c] == -1) bottom += forces.column("fy")[c];
    const double fy = series.column("wall_bottom_fy")[row];
    EXPECT_NEAR(bottom, -fy, 1e-9 * std::abs(fy) + 1e-12) << "snapshot " << k;
    if (k == 2) {
      EXPECT_GT(forces.rows(), 5u);
    }
  }
  // `mpmcd analyze` on it: the fabric series and, at Φ = 0.7, the distributions of the snapshot
  // nearest that Φ, whose counts are the grain-grain rows and the non-rattler grains it holds.
  const Result a = run("analyze " + (dir / "out").string() + " --phi 0.7 --no-plots");
  ASSERT_EQ(a.code, 0) << a.output;
  const fs::path an = dir / "out" / "analysis";
  const auto fabric = mpmcd::analysis::read_time_series((an / "fabric.csv").string());
  EXPECT_EQ(fabric.rows(), series.rows());
  EXPECT_NEAR(fabric.column("fabric_a").back(), series.column("fabric_a").back(), 1e-11);
  const auto fdist = mpmcd::analysis::read_time_series((an / "force_distribution.csv").string());
  const auto pdist = mpmcd::analysis::read_time_series((an / "pressure_distribution.csv").string());
  ASSERT_GT(fdist.rows(), 0u);
  const double t = fdist.column("time").front();
  int snapshot = -1;
  for (int k = 0; k < 3; ++k)
    if (mpmcd::analysis::read_time_series(
            (dir / "out" / fmt::format("compaction_grains_{:06d}.csv", k)).string())
            .column("time")
            .front() == t)
      snapshot = k;
  ASSERT_GE(snapshot, 0);
  const auto forces = mpmcd::analysis::read_time_series(
      (dir / "out" / fmt::format("compaction_forces_{:06d}.csv", snapshot)).string());
  const auto grains = mpmcd::analysis::read_time_series(
      (dir / "out" / fmt::format("compaction_grains_{:06d}.csv", snapshot)).string());
  double pairs = 0, kept = 0, counted = 0, density = 0, mean = 0;
  for (std::size_t c = 0; c < forces.rows(); ++c)
    if (forces.column("a")[c] >= 0) {
      ++pairs;
      mean += forces.column("fn")[c];
    }
  for (std::size_t g = 0; g < grains.rows(); ++g) kept += grains.column("rattler")[g] == 0;
  for (std::size_t b = 0; b < fdist.rows(); ++b) {
    counted += fdist.column("count")[b];
    density += fdist.column("density")[b] * (fdist.column("bin_hi")[b] - fdist.column("bin_lo")[b]);
  }
  EXPECT_EQ(counted, pairs);
  EXPECT_NEAR(density, 1.0, 1e-12);  // every f/<f> within [0, 4] here
  EXPECT_NEAR(fdist.column("mean").front(), mean / pairs, 1e-9 * mean / pairs);
  double pcount = 0;
  for (std::size_t b = 0; b < pdist.rows(); ++b) pcount += pdist.column("count")[b];
  EXPECT_EQ(pcount, kept);
  // Bad value: exit 2 naming the file and the key, nothing written.
  text.replace(text.find("grains = true"), 13, "grains = \"yes\"");
  text.replace(text.find("folder = \"out\""), 14, "folder = \"bad\"");
  std::ofstream(dir / "bad.toml") << text;
  const Result b = run("run -q " + (dir / "bad.toml").string());
  EXPECT_EQ(b.code, 2) << b.output;
  EXPECT_NE(b.output.find("bad.toml:"), std::string::npos) << b.output;
  EXPECT_NE(b.output.find("grains"), std::string::npos) << b.output;
  EXPECT_FALSE(fs::exists(dir / "bad"));
}

// The active-set contact solver solves frictionless contacts only: friction anywhere (the
// default grain pair, a material pair, a wall) is refused at input with exit 2, naming the key,
// not dropped. Without friction the same input runs.
TEST(Cli, ActiveSetSolverRefusesFriction) {
  const fs::path dir = scratch("active_set");
  const std::string grains =
      "[[grains]]\nshape = \"disk\"\nmaterial = \"gel\"\ncenter = [0.01, 0.006]\n"
      "radius = 0.003\n[[grains]]\nshape = \"disk\"\nmaterial = \"gel\"\n"
      "center = [0.01, 0.0125]\nradius = 0.003\n"
      "[[walls]]\nname = \"floor\"\npoint = [0.0, 0.002]\nnormal = [0.0, 1.0]\n";
  const std::string time = "[time]\ndt = 1e-5\nend_time = 2e-5\n";
  const auto input = [&](const std::string& contact, const std::string& wall) {
    return write_input(dir, grains + wall + "[contact]\nsolver = \"active_set\"\n" + contact, time);
  };
  for (const auto& [contact, wall] :
       {std::pair<std::string, std::string>{"friction = 0.3\n", ""},
        std::pair<std::string, std::string>{"", "friction = 0.5\n"}}) {
    for (const std::string cmd : {"check ", "run "}) {
      const Result r = run(cmd + input(contact, wall).string());
      EXPECT_EQ(r.code, 2) << cmd << r.output;
      EXPECT_NE(r.output.find("key 'contact.solver'"), std::string::npos) << r.output;
      EXPECT_NE(r.output.find("frictionless contacts only"), std::string::npos) << r.output;
      EXPECT_FALSE(fs::exists(dir / "out"));
    }
  }
  const Result ok = run("run " + input("", "").string());
  EXPECT_EQ(ok.code, 0) << ok.output;
}
