// The `mpmcd` command line as a user runs it, its input checks: valid inputs pass `check`
// (the examples), bad ones exit with 2 and write nothing, and `list` prints the reference.
// Runs and their failures: test_cli_runs.cpp; output folders and files: test_cli_outputs.cpp.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <string>

#include "cli_helpers.hpp"

using namespace mpmcd::test_support::cli;

TEST(Cli, CheckAcceptsTheExample) {
  const Result r = run("check " + example());
  EXPECT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("valid (1 grains"), std::string::npos) << r.output;
}

// Every simulation input under examples/ stays valid (packing inputs, pack*.toml, are `mpmcd pack`
// inputs and are checked by the packing tests).
TEST(Cli, CheckAcceptsEveryExampleInput) {
  int checked = 0;
  for (const auto& e : fs::recursive_directory_iterator(fs::path(MPMCD_SOURCE_DIR) / "examples")) {
    if (!e.is_regular_file() || e.path().extension() != ".toml" ||
        e.path().filename().string().rfind("pack", 0) == 0)
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

TEST(Cli, ListPrintsInputReferenceAndLaws) {
  const Result a = run("list input");
  EXPECT_EQ(a.code, 0);
  EXPECT_EQ(a.output,
            mpmcd::test_support::read_file(fs::path(MPMCD_SOURCE_DIR) / "docs" / "input.md"));
  const Result b = run("list laws");
  EXPECT_EQ(b.code, 0);
  EXPECT_NE(b.output.find("neo_hookean"), std::string::npos);
  EXPECT_NE(b.output.find("coulomb: Signorini + Coulomb"), std::string::npos);
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

// `mpmcd pack` in 3D (issue 18): a [packing] with dimension = 3 writes a sphere packing (CSV with
// a dimension line and a z column); a bad dimension or a 2D box in 3D exits with 2 naming the
// file, the line and the key, and writes nothing.
TEST(Cli, PackInThreeDimensionsAndItsBadKeys) {
  const fs::path dir = scratch("pack3d");
  const std::string head =
      "[packing]\ndimension = 3\ncount = 50\ndiameter_min = 0.8e-3\ndiameter_max = 1.2e-3\n"
      "target_phi = 0.45\nseed = 3\n";
  std::ofstream(dir / "pack.toml")
      << head << "aspect_ratio = 1.0\n[output]\nfolder = \"" << (dir / "out").string() << "\"\n";
  const Result ok = run("pack -q " + (dir / "pack.toml").string());
  EXPECT_EQ(ok.code, 0) << ok.output;
  EXPECT_NE(ok.output.find("packing: 50 grains, phi = 0.450000"), std::string::npos) << ok.output;
  std::ifstream csv(dir / "out" / "packing.csv");
  const std::string text((std::istreambuf_iterator<char>(csv)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("# dimension = 3\n"), std::string::npos) << text.substr(0, 200);
  EXPECT_NE(text.find("\nid,x,y,z,radius\n"), std::string::npos) << text.substr(0, 200);
  // A 2D run given the sphere packing (its CSV, or its input to generate) is refused, naming the
  // dimension.
  for (const std::string file : {"out/packing.csv", "pack.toml"}) {
    const fs::path in = write_input(
        dir, "[[grains]]\nshape = \"packing\"\nfile = \"" + file + "\"\nmaterial = \"gel\"\n",
        "[time]\ndt = 1e-5\nend_time = 2e-5\n");
    const Result r = run("check " + in.string());
    EXPECT_EQ(r.code, 2) << r.output;
    EXPECT_NE(r.output.find("needs a packing of disks"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("dimension"), std::string::npos) << r.output;
  }

  const std::pair<std::string, std::string> bad[] = {
      {"[packing]\ndimension = 1\ncount = 50\n",
       "bad.toml:2: key 'packing.dimension': 2 (disks) or 3 (spheres), got 1"},
      {head + "box = [0.0, 0.0, 0.005, 0.005]\n",
       "bad.toml:8: key 'packing.box': an array of 6 numbers, got 4"}};
  for (const auto& [input, message] : bad) {
    std::ofstream(dir / "bad.toml")
        << input << "[output]\nfolder = \"" << (dir / "bad_out").string() << "\"\n";
    const Result r = run("pack " + (dir / "bad.toml").string());
    EXPECT_EQ(r.code, 2) << r.output;
    EXPECT_NE(r.output.find(message), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(dir / "bad_out"));
  }
}
