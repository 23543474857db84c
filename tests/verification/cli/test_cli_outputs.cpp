// The `mpmcd` command line as a user runs it, its output folders and files: one folder one run
// (--overwrite), a restart into another folder, a failed write, the snapshots other tools read,
// the grain-scale outputs.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "mpmcd/analysis/time_series.hpp"

#include "cli_helpers.hpp"

using namespace mpmcd::test_support::cli;

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
