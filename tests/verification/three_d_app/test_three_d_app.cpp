// 3D through the command line (issue 18): `mpmcd run` of TOML inputs with `dimension = 3`. A
// sphere resting on a wall carries its weight; a sphere squeezed in a box of six walls ([loading])
// has the exact initial Φ and, stopped half way and restarted from its checkpoint, ends with the
// same bytes in every output, and with `[output] grains` writes the coverage and grain-scale
// outputs consistently with its Love-Weber stress and wall forces; 3D inputs with the wrong
// number of components, or 2D-only shapes and keys, are refused with exit 2 and a message naming
// the file, the key and what was expected.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include "../../support/cli_runner.hpp"
#include "../../support/scratch.hpp"

namespace fs = std::filesystem;
using mpmcd::test_support::read_file;
using mpmcd::test_support::run;

namespace {

fs::path scratch(const std::string& name) {
  return mpmcd::test_support::scratch_dir("three_d_app", name);
}

// The paper's gel (method.md §3) on a grid of 10^3 cells of h = 0.5 mm; a sphere of R = 1.5 mm
// (912 lattice points, volumes scaled to 4/3 pi R^3).
const std::string kGelSphere =
    "[grid]\norigin = [0.0, 0.0, 0.0]\nextent = [0.005, 0.005, 0.005]\ncell_size = 0.0005\n"
    "[[materials]]\nname = \"gel\"\nlaw = \"neo_hookean\"\ndensity = 990.0\nlambda = 3e6\n"
    "mu = 1.5e6\n"
    "[[grains]]\nshape = \"sphere\"\nmaterial = \"gel\"\ncenter = [0.0025, 0.0025, 0.0025]\n"
    "radius = 0.0015\n";

fs::path write_input(const fs::path& dir, const std::string& name, const std::string& text) {
  const fs::path p = dir / (name + ".toml");
  std::ofstream(p) << text;
  return p;
}

// The CSV at `path` as columns by header name (every field parsed as a number).
std::map<std::string, std::vector<double>> read_csv(const fs::path& path) {
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);
  std::vector<std::string> names;
  std::stringstream hs(line);
  for (std::string f; std::getline(hs, f, ',');) names.push_back(f);
  std::map<std::string, std::vector<double>> cols;
  while (std::getline(in, line)) {
    std::stringstream ls(line);
    std::size_t k = 0;
    for (std::string f; std::getline(ls, f, ',') && k < names.size(); ++k)
      cols[names[k]].push_back(f.empty() ? std::numeric_limits<double>::quiet_NaN()
                                         : std::stod(f));  // empty: not defined (analyze)
  }
  return cols;
}

// Two spheres (R = 1 mm) stacked along y in a box of six walls, the top one (normal -y) moving
// down at 0.5 m/s for 40 steps of 2e-5 s; `output` is the body of its [output] table.
std::string squeeze_input(const std::string& name, const std::string& output) {
  std::string walls;
  const char* names[6] = {"left", "right", "bottom", "top", "front", "back"};
  const double at[6] = {0.001, 0.003, 0.001, 0.0051, 0.0009, 0.0031};
  for (int k = 0; k < 6; ++k) {
    double n[3] = {0, 0, 0}, x[3] = {0, 0, 0};
    n[k / 2] = k % 2 == 0 ? 1.0 : -1.0;
    x[k / 2] = at[k];
    std::ostringstream w;
    w << "[[walls]]\nname = \"" << names[k] << "\"\npoint = [" << x[0] << ", " << x[1] << ", "
      << x[2] << "]\nnormal = [" << n[0] << ", " << n[1] << ", " << n[2] << "]\n";
    walls += w.str();
  }
  return "[simulation]\nname = \"" + name + "\"\ndimension = 3\n" +
         "[grid]\norigin = [0.0, 0.0, 0.0]\nextent = [0.004, 0.006, 0.004]\ncell_size = 0.0005\n"
         "[[materials]]\nname = \"gel\"\nlaw = \"neo_hookean\"\ndensity = 990.0\nlambda = 3e6\n"
         "mu = 1.5e6\n"
         "[[grains]]\nshape = \"sphere\"\nmaterial = \"gel\"\ncenter = [0.002, 0.002, 0.002]\n"
         "radius = 0.001\n"
         "[[grains]]\nshape = \"sphere\"\nmaterial = \"gel\"\ncenter = [0.002, 0.004, 0.002]\n"
         "radius = 0.001\n" +
         walls +
         "[loading]\n[[loading.stages]]\nname = \"squeeze\"\n[[loading.stages.walls]]\n"
         "name = \"top\"\nvelocity = [0.0, -0.5, 0.0]\n"
         "[time]\ndt = 2e-5\nend_time = 0.0008\n[output]\n" +
         output;
}

}  // namespace

// A sphere set on a frictionless floor (normal +z) under gravity, 389 steps of 2h/c_p (as
// tests/verification/three_d, now from a TOML file): once backward Euler has damped the bouncing,
// the floor's force over the second half of the run is the sphere's weight within 1 %.
TEST(ThreeDApp, SphereRestingOnAWallCarriesItsWeight) {
  const fs::path dir = scratch("rest");
  const fs::path input = write_input(
      dir, "rest",
      "[simulation]\nname = \"rest\"\ndimension = 3\n" + kGelSphere +
          "[[walls]]\nname = \"floor\"\npoint = [0.0, 0.0, 0.001]\nnormal = [0.0, 0.0, 1.0]\n"
          "[loads]\ngravity = [0.0, 0.0, -9.81]\n"
          "[time]\ndt = 1.2845e-5\nend_time = 0.005\n[output]\nvtu = false\n");
  const auto r = run("run -q -t 2 -o " + (dir / "out").string() + " " + input.string());
  ASSERT_EQ(r.code, 0) << r.output;
  auto csv = read_csv(dir / "out" / "rest.csv");
  const auto& t = csv["time"];
  ASSERT_GT(t.size(), 300u);
  const double T = t.back(), mass = csv["mass"].back(), weight = 9.81 * mass;
  // The exact sphere volume times the density (lattice points, volumes rescaled).
  EXPECT_NEAR(mass, 990.0 * 4.0 / 3.0 * std::numbers::pi * std::pow(1.5e-3, 3), 1e-12 * mass);
  double impulse = 0, time = 0;  // the floor's reaction on the sphere over the second half
  for (std::size_t k = 1; k < t.size(); ++k)
    if (t[k] > 0.5 * T) {
      const double dt = t[k] - t[k - 1];
      impulse += -csv["wall_floor_fz"][k] * dt;
      time += dt;
    }
  const double ratio = impulse / time / weight;
  std::printf("  %zu steps to %.4g s: floor force / weight over the second half %.6f\n",
              t.size() - 1, T, ratio);
  EXPECT_NEAR(ratio, 1.0, 0.01);
  EXPECT_EQ(csv["wall_floor_fx"].size(), t.size());  // the 3 components are written
}

// Two spheres (R = 1 mm) stacked along y in a box of six walls, the top one (normal -y) moving
// down at 0.5 m/s ([loading]): Φ0 = 2 (4/3 pi R^3) / V_box exactly; at the end the top and
// bottom walls carry the same load, close to the grains' Love-Weber σ_yy (not equal: the loading
// is not quasi-static), and the two spheres in contact with each other and a wall each give
// Z = 2 N_pairs / N_grains = 1; a run stopped after 20 steps and restarted from its checkpoint
// ends with the same CSV, VTU, PVD and pair files and the same final checkpoint, byte for byte.
TEST(ThreeDApp, SqueezedSpheresRestartBitwise) {
  const fs::path dir = scratch("squeeze");
  const fs::path input =
      write_input(dir, "squeeze", squeeze_input("squeeze", "vtu_interval = 2e-4\n"));
  const fs::path full = dir / "full", split = dir / "split";
  const auto a = run("run -q -t 2 -o " + full.string() + " " + input.string());
  ASSERT_EQ(a.code, 0) << a.output;
  const auto b = run("run -q -t 2 --stop-after 20 -o " + split.string() + " " + input.string());
  ASSERT_EQ(b.code, 4) << b.output;
  const auto c =
      run("run -q -t 2 --restart " + (split / "squeeze_checkpoint_000000020.h5").string());
  ASSERT_EQ(c.code, 0) << c.output;

  auto csv = read_csv(full / "squeeze.csv");
  const double vs0 = 2 * 4.0 / 3.0 * std::numbers::pi * std::pow(1e-3, 3);
  const double v0 = 2e-3 * 4.1e-3 * 2.2e-3;
  EXPECT_NEAR(csv["phi"].front(), vs0 / v0, 1e-12);
  EXPECT_NEAR(csv["box_volume"].front(), v0, 1e-12 * v0);
  const double top = csv["wall_top_stress"].back(), bottom = csv["wall_bottom_stress"].back();
  const double lw = csv["lw_syy"].back();
  std::printf(
      "  Phi %.6f -> %.6f; sigma_top %.4g Pa, sigma_bottom %.4g Pa, Love-Weber %.4g Pa; Z %.3g "
      "(%g pairs, %g grains, %g rattlers)\n",
      csv["phi"].front(), csv["phi"].back(), top, bottom, lw, csv["Z"].back(),
      csv["Z_pairs"].back(), csv["Z_grains"].back(), csv["rattlers"].back());
  EXPECT_GT(csv["phi"].back(), csv["phi"].front());
  EXPECT_LT(top, 0.0);  // compression
  EXPECT_NEAR(bottom / top, 1.0, 0.05);
  EXPECT_NEAR(lw / top, 1.0, 0.1);
  EXPECT_EQ(csv["Z"].back(), 1.0);
  EXPECT_EQ(csv["Z_pairs"].back(), 1.0);
  EXPECT_EQ(csv["rattlers"].back(), 0.0);

  int files = 0;
  for (const auto& e : fs::directory_iterator(full)) {
    const std::string name = e.path().filename().string(), ext = e.path().extension().string();
    if (name.ends_with("_timers.csv") || (ext != ".csv" && ext != ".vtu" && ext != ".pvd"))
      continue;
    ++files;
    EXPECT_TRUE(read_file(e.path()) == read_file(split / name)) << name << " differs";
  }
  EXPECT_GE(files, 10);
  const std::string last = "squeeze_checkpoint_000000040.h5";
  EXPECT_TRUE(read_file(full / last) == read_file(split / last)) << "final checkpoints differ";
}

// Issue 18: the coverage columns and `[output] grains = true` in 3D, on the squeezed spheres.
// At t = 0 no domain overlaps another or leaves the box, `phi_geometric` is the volume of the
// points' cubic domains over the box's (the spheres' lattice, not Φ), and the pores are the one
// void around the spheres. At every snapshot the per-grain volumes sum to V_s, their
// volume-weighted stresses to the row's Love-Weber stress (all six components, as the mean grain
// stress columns do), and the contact-force rows of the bottom wall to its force in the time
// series.
TEST(ThreeDApp, CoverageAndGrainOutputs) {
  const fs::path dir = scratch("grains");
  const fs::path input = write_input(
      dir, "grains", squeeze_input("grains", "vtu = false\nvtu_interval = 4e-4\ngrains = true\n"));
  const auto r = run("run -q -t 2 -o " + (dir / "out").string() + " " + input.string());
  ASSERT_EQ(r.code, 0) << r.output;
  auto csv = read_csv(dir / "out" / "grains.csv");
  for (const char* c : {"phi_geometric", "overlap_over_Vs", "outside_over_Vs", "pore_diameter",
                        "stress_volume", "grain_sxx", "grain_szz", "grain_syz", "contact_syy",
                        "contact_sxz", "fabric_rzz", "fabric_a", "fabric_contacts"})
    EXPECT_EQ(csv[c].size(), csv["time"].size()) << c;
  std::printf(
      "  t = 0: Phi %.6f, phi_geometric %.6f, pore diameter %.4g m; end: Phi %.6f, "
      "phi_geometric %.6f, overlap/Vs %.3g, outside/Vs %.3g\n",
      csv["phi"].front(), csv["phi_geometric"].front(), csv["pore_diameter"].front(),
      csv["phi"].back(), csv["phi_geometric"].back(), csv["overlap_over_Vs"].back(),
      csv["outside_over_Vs"].back());
  EXPECT_EQ(csv["overlap_over_Vs"].front(), 0.0);
  EXPECT_EQ(csv["outside_over_Vs"].front(), 0.0);
  // The points' domains at t = 0 are the lattice's cubes of side h/2 (280 per sphere, 4.4 % more
  // than 4/3 pi R^3): phi_geometric is their volume over the box's, to the voxels' staircase.
  auto grains0 = read_csv(dir / "out" / "grains_grains_000000.csv");
  const double cubes = (grains0["points"][0] + grains0["points"][1]) * std::pow(0.25e-3, 3);
  EXPECT_NEAR(csv["phi_geometric"].front(), cubes / csv["box_volume"].front(), 2e-3);
  // One void around both spheres: (6 V / pi)^(1/3) of the box volume less the spheres'.
  const double pore = csv["box_volume"].front() * (1 - csv["phi_geometric"].front());
  EXPECT_NEAR(csv["pore_diameter"].front(), std::cbrt(6 * pore / std::numbers::pi), 1e-9);
  EXPECT_GT(csv["phi_geometric"].back(), csv["phi_geometric"].front());
  // The contact stress -(1/V) sym Σ F ⊗ ℓ against the grains' (the inertia term apart).
  std::printf("  end: grain_syy %.5g Pa, contact_syy %.5g Pa, fabric_a %.3g (%g contacts)\n",
              csv["grain_syy"].back(), csv["contact_syy"].back(), csv["fabric_a"].back(),
              csv["fabric_contacts"].back());
  EXPECT_NEAR(csv["contact_syy"].back() / csv["grain_syy"].back(), 1.0, 0.02);
  EXPECT_EQ(csv["fabric_a"].back(), 2.5);  // one contact normal, along y: (5/2)(1 - 0)
  for (std::size_t k = 0; k < csv["time"].size(); ++k)
    for (const char* c : {"xx", "yy", "zz", "xy", "xz", "yz"}) {
      const double lw = csv[std::string("lw_s") + c][k];
      EXPECT_NEAR(csv[std::string("grain_s") + c][k], lw, 1e-12 * std::abs(lw) + 1e-9) << c;
    }

  const auto& time = csv["time"];
  for (int n = 0; n < 3; ++n) {  // t = 0, 4e-4, 8e-4 s
    auto grains = read_csv(dir / "out" / fmt::format("grains_grains_{:06d}.csv", n));
    auto forces = read_csv(dir / "out" / fmt::format("grains_forces_{:06d}.csv", n));
    ASSERT_EQ(grains["volume"].size(), 2u);
    const double t = grains["time"].front();
    const auto row = static_cast<std::size_t>(
        std::min_element(time.begin(), time.end(),
                         [&](double a, double b) { return std::abs(a - t) < std::abs(b - t); }) -
        time.begin());
    ASSERT_NEAR(time[row], t, 1e-12);
    EXPECT_NEAR(grains["volume"][0] + grains["volume"][1], csv["Vs"][row], 1e-12 * csv["Vs"][row]);
    for (const char* c : {"xx", "yy", "zz", "xy", "xz", "yz"}) {
      const std::string s = std::string("s") + c;
      const double sum = (grains["volume"][0] * grains[s][0] + grains["volume"][1] * grains[s][1]) /
                         csv["box_volume"][row];
      const double lw = csv[std::string("lw_") + s][row];
      EXPECT_NEAR(sum, lw, 1e-10 * std::abs(lw) + 1e-9) << s << " snapshot " << n;
    }
    // The pressure is -tr(sigma)/3 of the grain's own stress.
    EXPECT_NEAR(grains["pressure"][0],
                -(grains["sxx"][0] + grains["syy"][0] + grains["szz"][0]) / 3,
                1e-9 * std::abs(grains["pressure"][0]) + 1e-9);
    double bottom = 0;  // bottom wall: wall 2, body -1 - 2
    for (std::size_t c = 0; c < forces["a"].size(); ++c)
      if (forces["a"][c] == -3) bottom += forces["fy"][c];
    const double fy = csv["wall_bottom_fy"][row];
    EXPECT_NEAR(bottom, -fy, 1e-9 * std::abs(fy) + 1e-12) << "snapshot " << n;
    if (n == 2) {
      EXPECT_LT(fy, 0.0);  // the grains press on the bottom wall
    }
  }
  // `mpmcd analyze` reads the 3D grain columns: its fabric series has the 3D mean pressures
  // -tr(sigma)/3 of the grains and of the contacts (no fabric angle in 3D).
  const auto a = run("analyze --no-plots " + (dir / "out").string());
  ASSERT_EQ(a.code, 0) << a.output;
  auto fabric = read_csv(dir / "out" / "analysis" / "fabric.csv");
  ASSERT_EQ(fabric["grain_pressure"].size(), csv["time"].size());
  for (std::size_t k = 0; k < csv["time"].size(); ++k)
    for (const char* s : {"grain", "contact"}) {
      const std::string c = std::string(s) + "_s";
      const double p = -(csv[c + "xx"][k] + csv[c + "yy"][k] + csv[c + "zz"][k]) / 3;
      EXPECT_NEAR(fabric[std::string(s) + "_pressure"][k], p, 1e-9 * std::abs(p) + 1e-9)
          << s << " row " << k;
    }
}

// Bad 3D inputs: exit 2, nothing run, and the message names the file, the key and what it
// expected.
TEST(ThreeDApp, BadInputsAreRefusedWithExitTwo) {
  const fs::path dir = scratch("bad");
  const std::string head = "[simulation]\nname = \"bad\"\ndimension = 3\n";
  const std::string tail = "[time]\ndt = 1e-5\nend_time = 1e-4\n";
  const auto with = [&](const std::string& from, const std::string& to) {
    std::string s = kGelSphere;
    const auto at = s.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    return s.replace(at, from.size(), to);
  };
  struct Case {
    std::string name, text, key, says;
  };
  const std::vector<Case> cases = {
      {"center",
       head + with("center = [0.0025, 0.0025, 0.0025]", "center = [0.0025, 0.0025]") + tail,
       "grains[0].center", "expected an array of 3 finite numbers [m], got 2 entries"},
      {"extent", head + with("extent = [0.005, 0.005, 0.005]", "extent = [0.005, 0.005]") + tail,
       "grid.extent", "expected an array of 3"},
      {"normal",
       head + kGelSphere +
           "[[walls]]\nname = \"floor\"\npoint = [0.0, 0.0, 0.0009]\nnormal = [0.0, 1.0]\n" + tail,
       "walls[0].normal", "expected an array of 3 finite numbers, got 2 entries"},
      {"gravity", head + kGelSphere + "[loads]\ngravity = [0.0, -9.81]\n" + tail, "loads.gravity",
       "expected an array of 3"},
      {"disk", head + with("shape = \"sphere\"", "shape = \"disk\"") + tail, "grains[0].shape",
       "shape \"disk\" is 2D only, but [simulation] dimension = 3: use shape = \"sphere\""},
      {"spin", head + kGelSphere + "[grains.initial]\nangular_velocity = 10.0\n" + tail,
       "grains[0].initial.angular_velocity", "2D only"}};
  for (const auto& c : cases) {
    const fs::path input = write_input(dir, c.name, c.text);
    const auto r = run("run -q -o " + (dir / ("out_" + c.name)).string() + " " + input.string());
    EXPECT_EQ(r.code, 2) << c.name << ": " << r.output;
    EXPECT_NE(r.output.find(input.filename().string()), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("'" + c.key + "'"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find(c.says), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(dir / ("out_" + c.name))) << c.name << ": wrote outputs";
  }
}

// A 3D packing read as grains (`shape = "packing"` in a `dimension = 3` run): the spheres of a
// DEM packing (`mpmcd pack`, 20 spheres, Phi0 = 0.40) in a box of six walls, the top one moving
// down. Step 0 has the packing's Phi (sum of 4/3 pi r^3 over the box volume, from the CSV) to
// round-off and the mass rho sum 4/3 pi r^3; giving the packing input (.toml, generated when the
// run starts) instead of its CSV writes the same CSV bytes; the spheres are squeezed (Phi rises,
// the top wall pushes). A 2D packing in a 3D run, polar seeding, and a [[grains]] sphere
// overlapping a packing's sphere are refused with exit 2, naming the file, the key and the sphere.
TEST(ThreeDApp, SpherePackingIsReadAsGrains) {
  const fs::path dir = scratch("packing");
  std::ofstream(dir / "pack.toml")
      << "[packing]\ndimension = 3\ncount = 20\ndiameter_min = 0.8e-3\ndiameter_max = 1.2e-3\n"
         "target_phi = 0.40\naspect_ratio = 1.0\nseed = 4\n[output]\nfolder = \""
      << dir.string() << "\"\nname = \"packing\"\nvtu = false\n";
  const auto packed = run("pack -q --overwrite " + (dir / "pack.toml").string());
  ASSERT_EQ(packed.code, 0) << packed.output;
  // The box and the spheres from the CSV.
  std::ifstream csv_in(dir / "packing.csv");
  std::string line;
  std::vector<double> box;
  double volume = 0;
  int spheres = 0;
  while (std::getline(csv_in, line)) {
    if (line.rfind("# box = ", 0) == 0) {
      std::stringstream ss(line.substr(8));
      for (double v; ss >> v;) box.push_back(v);
    } else if (!line.empty() && line[0] != '#' && line[0] != 'i') {
      std::stringstream ss(line);
      std::vector<double> f;
      for (std::string s; std::getline(ss, s, ',');) f.push_back(std::stod(s));
      ASSERT_EQ(f.size(), 5u) << line;
      volume += 4.0 / 3.0 * std::numbers::pi * std::pow(f[4], 3);
      ++spheres;
    }
  }
  ASSERT_EQ(box.size(), 6u);
  ASSERT_EQ(spheres, 20);
  const double L = box[3] - box[0];
  const double extent = std::ceil((L + 1e-3) / 0.25e-3) * 0.25e-3;  // whole cells, margin >= h
  const auto num = [](double v) { return fmt::format("{:.17g}", v); };
  const auto wall = [&](const std::string& name, double px, double py, double pz,
                        const std::string& normal, const std::string& extra) {
    return "[[walls]]\nname = \"" + name + "\"\npoint = [" + num(px) + ", " + num(py) + ", " +
           num(pz) + "]\nnormal = " + normal + "\n" + extra;
  };
  const auto input = [&](const std::string& name, const std::string& grains) {
    return write_input(
        dir, name,
        "[simulation]\nname = \"" + name +
            "\"\ndimension = 3\n[grid]\norigin = [-0.5e-3, "
            "-0.5e-3, -0.5e-3]\nextent = [" +
            num(extent) + ", " + num(extent) + ", " + num(extent) +
            "]\ncell_size = 0.25e-3\n[[materials]]\nname = \"gel\"\nlaw = "
            "\"neo_hookean\"\ndensity = 990.0\nlambda = 3e6\nmu = 1.5e6\n" +
            grains + wall("left", 0, 0, 0, "[1.0, 0.0, 0.0]", "") +
            wall("right", L, 0, 0, "[-1.0, 0.0, 0.0]", "") +
            wall("bottom", 0, 0, 0, "[0.0, 1.0, 0.0]", "") +
            wall("top", 0, L, 0, "[0.0, -1.0, 0.0]", "velocity = [0.0, -10.0, 0.0]\n") +
            wall("front", 0, 0, 0, "[0.0, 0.0, 1.0]", "") +
            wall("back", 0, 0, L, "[0.0, 0.0, -1.0]", "") +
            "[contact]\nfriction = 0.0\ndelassus = \"grain\"\n"
            "[time]\ndt = 2e-6\nend_time = 4e-5\n[output]\nvtu = false\n");
  };
  const std::string from_csv =
      "[[grains]]\nshape = \"packing\"\nfile = \"packing.csv\"\nmaterial = \"gel\"\n"
      "points_per_cell = 1\n";
  const fs::path a = input("csv", from_csv);
  const auto ra = run("run -q -t 2 -o " + (dir / "out_csv").string() + " " + a.string());
  ASSERT_EQ(ra.code, 0) << ra.output;
  auto cols = read_csv(dir / "out_csv" / "csv.csv");
  ASSERT_GE(cols["phi"].size(), 21u);
  const double phi0 = volume / (L * L * L);
  EXPECT_NEAR(cols["phi"][0], phi0, 1e-12 * phi0);
  EXPECT_NEAR(cols["phi"][0], 0.40, 1e-9);
  EXPECT_NEAR(cols["mass"][0], 990.0 * volume, 1e-12 * 990.0 * volume);
  EXPECT_GT(cols["phi"].back(), cols["phi"][0] * 1.05);  // the top wall moved 0.4 mm of 2.7 mm
  EXPECT_GT(cols["wall_top_fy"].back(), 0.0) << "the top wall pushes the spheres down";
  std::printf(
      "3D packing: 20 spheres, Phi0 %.12f (CSV %.12f), after %zu steps Phi %.6f, top "
      "force %.4g N, Z %.3f\n",
      cols["phi"][0], phi0, cols["phi"].size() - 1, cols["phi"].back(), cols["wall_top_fy"].back(),
      cols["Z"].back());
  // The packing input generated at run start gives the same run.
  std::string from_toml = from_csv;
  from_toml.replace(from_toml.find("packing.csv"), 11, "pack.toml");
  const fs::path b = input("csv", from_toml);
  const auto rb = run("run -q -t 2 -o " + (dir / "out_toml").string() + " " + b.string());
  ASSERT_EQ(rb.code, 0) << rb.output;
  EXPECT_EQ(read_file(dir / "out_csv" / "csv.csv"), read_file(dir / "out_toml" / "csv.csv"));

  // Refused: a 2D packing, polar seeding, a sphere overlapping a packing's sphere.
  std::ofstream(dir / "disks.csv") << "id,x,y,radius\n0,0.001,0.001,0.0004\n";
  std::stringstream first([&] {
    std::ifstream in(dir / "packing.csv");
    std::string l;
    while (std::getline(in, l))
      if (!l.empty() && l[0] != '#' && l[0] != 'i') return l;
    return std::string();
  }());
  std::vector<double> s0;
  for (std::string f; std::getline(first, f, ',');) s0.push_back(std::stod(f));
  struct Case {
    std::string name, grains, key, says;
  };
  const std::vector<Case> cases = {
      {"disks", "[[grains]]\nshape = \"packing\"\nfile = \"disks.csv\"\nmaterial = \"gel\"\n",
       "dimension", "a 3D run (grains[0]"},
      {"polar", from_csv + "seeding = \"polar\"\n", "grains[0].seeding",
       "3D grains are seeded on the lattice"},
      {"overlap",
       from_csv + "[[grains]]\nshape = \"sphere\"\nmaterial = \"gel\"\ncenter = [" + num(s0[1]) +
           ", " + num(s0[2]) + ", " + num(s0[3]) + "]\nradius = 0.2e-3\n",
       "grains[1]", fmt::format("overlaps sphere id {} of", static_cast<int>(s0[0]))}};
  for (const auto& c : cases) {
    const fs::path in = input("bad_" + c.name, c.grains);
    const auto r = run("run -q -o " + (dir / ("out_" + c.name)).string() + " " + in.string());
    EXPECT_EQ(r.code, 2) << c.name << ": " << r.output;
    EXPECT_NE(r.output.find("'" + c.key + "'"), std::string::npos) << c.name << ": " << r.output;
    EXPECT_NE(r.output.find(c.says), std::string::npos) << c.name << ": " << r.output;
    EXPECT_FALSE(fs::exists(dir / ("out_" + c.name))) << c.name << ": wrote outputs";
  }
}
