// 3D packings (issue 18): spheres from the same DEM generator as the disks (docs/packing.md),
// packing fraction and overlaps, walls and periodic cell, the jamming fraction of random close
// packing, the CSV file with a z column read back exactly, and the 3D pack input.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <set>
#include <string>

#include <unistd.h>

#include "../../support/scratch.hpp"
#include "mpmcd/core/errors.hpp"
#include "mpmcd/packing/input.hpp"
#include "mpmcd/packing/overlap.hpp"
#include "mpmcd/packing/pack_command.hpp"
#include "mpmcd/packing/packing.hpp"
#include "mpmcd/packing/seeding.hpp"

using namespace mpmcd::packing;
namespace fs = std::filesystem;

namespace {

constexpr double kD = 1e-3;  // nominal diameter [m]

// 150 spheres with diameters uniform in [0.8, 1.2] mm, grown in a cube.
PackingParams sphere_params(double phi, bool periodic, std::uint64_t seed = 42) {
  PackingParams p;
  p.dimension = 3;
  p.count = 150;
  p.diameter_min = 0.8 * kD;
  p.diameter_max = 1.2 * kD;
  p.aspect_ratio = 1.0;
  p.target_phi = phi;
  p.periodic = periodic;
  p.seed = seed;
  return p;
}

// Largest overlap between two spheres, by brute force over all pairs (independent of the DEM's
// cell lists and of find_sphere_overlap), relative to the smaller diameter [-]; minimum image
// in a periodic cell.
double brute_force_overlap(const Packing& pk) {
  const double L[3] = {pk.xmax - pk.xmin, pk.ymax - pk.ymin, pk.zmax - pk.zmin};
  const auto image = [&](double d, int a) {
    if (!pk.periodic) return d;
    return d - L[a] * std::round(d / L[a]);
  };
  double worst = 0.0;
  for (std::size_t i = 0; i < pk.disks.size(); ++i)
    for (std::size_t j = i + 1; j < pk.disks.size(); ++j) {
      const auto &a = pk.disks[i], &b = pk.disks[j];
      const double dx = image(a.x - b.x, 0), dy = image(a.y - b.y, 1), dz = image(a.z - b.z, 2);
      const double depth = a.radius + b.radius - std::sqrt(dx * dx + dy * dy + dz * dz);
      worst = std::max(worst, depth / (2.0 * std::min(a.radius, b.radius)));
    }
  return worst;
}

// Largest penetration of a sphere into a wall, relative to the mean diameter [-].
double wall_overlap(const Packing& pk) {
  double worst = 0.0;
  for (const auto& s : pk.disks)
    worst = std::max({worst, pk.xmin - (s.x - s.radius), (s.x + s.radius) - pk.xmax,
                      pk.ymin - (s.y - s.radius), (s.y + s.radius) - pk.ymax,
                      pk.zmin - (s.z - s.radius), (s.z + s.radius) - pk.zmax});
  return worst / mean_diameter(pk);
}

// The issue-18 criterion: phi within 0.003 of the target, every overlap below 1e-3 d_mean.
void expect_packed(const Packing& pk, const PackingReport& report, double target) {
  ASSERT_EQ(pk.dimension, 3);
  ASSERT_EQ(pk.disks.size(), 150u);
  const double phi = packing_fraction(pk);
  const double pair = brute_force_overlap(pk), wall = pk.periodic ? 0.0 : wall_overlap(pk);
  std::printf(
      "  %s, 150 spheres, target %.3f: phi = %.6f (error %.1e), largest overlap sphere-sphere "
      "%.2e of the smaller d, sphere-wall %.2e d_mean; %lld DEM steps, %.2f s\n",
      pk.periodic ? "periodic" : "walls", target, phi, phi - target, pair, wall,
      static_cast<long long>(report.steps), report.wall_seconds);
  EXPECT_NEAR(phi, target, 0.003);
  EXPECT_NEAR(report.phi, phi, 1e-12);
  EXPECT_TRUE(report.relaxed);
  EXPECT_LT(pair, 1e-3);
  EXPECT_LT(wall, 1e-3);
  EXPECT_LT(max_overlap(pk) / mean_diameter(pk), 1e-3);
  EXPECT_FALSE(find_sphere_overlap(pk, kOverlapTolerance));
  // Diameters kept (no box given), the box a cube.
  for (const auto& s : pk.disks) {
    EXPECT_GE(2.0 * s.radius, 0.8 * kD * (1 - 1e-12));
    EXPECT_LE(2.0 * s.radius, 1.2 * kD * (1 + 1e-12));
    EXPECT_GE(s.z, pk.zmin);
    EXPECT_LE(s.z, pk.zmax);
  }
  EXPECT_NEAR((pk.zmax - pk.zmin) / (pk.xmax - pk.xmin), 1.0, 1e-12);
}

fs::path scratch(const std::string& name) {
  const auto dir = mpmcd::test_support::scratch_path("test_pack3d");
  fs::create_directories(dir);
  return dir / name;
}

}  // namespace

// Walls: 150 spheres in a cube of about 5.4 d jam near phi = 0.54 (JammingFractions below), so
// the walled target is 0.50.
TEST(ThreeDPacking, GrowBetweenWallsReachesPhiWithoutOverlap) {
  PackingReport report;
  const Packing pk = generate_packing(sphere_params(0.50, false), report);
  expect_packed(pk, report, 0.50);
}

TEST(ThreeDPacking, GrowInAPeriodicCellReachesPhiWithoutOverlap) {
  PackingReport report;
  const Packing pk = generate_packing(sphere_params(0.60, true), report);
  expect_packed(pk, report, 0.60);
  EXPECT_TRUE(pk.periodic);
}

// Moving walls and the Hertz law in a given box: the box is kept, the diameters scaled by one
// factor.
TEST(ThreeDPacking, WallCompressionWithHertzInAGivenBox) {
  PackingParams p = sphere_params(0.45, false, 3);
  p.method = PackingMethod::kWalls;
  p.contact_law = ContactLaw::kHertz;
  p.box = std::array<double, 4>{0.001, 0.002, 0.007, 0.008};
  p.box_z = {-0.001, 0.003};  // 6 x 6 x 4 mm
  PackingReport report;
  const Packing pk = generate_packing(p, report);
  std::printf("  walls + Hertz, box 6 x 6 x 4 mm: phi = %.6f, overlap %.2e, %.2f s\n",
              packing_fraction(pk), brute_force_overlap(pk), report.wall_seconds);
  EXPECT_EQ(pk.xmin, 0.001);
  EXPECT_EQ(pk.ymax, 0.008);
  EXPECT_EQ(pk.zmin, -0.001);
  EXPECT_EQ(pk.zmax, 0.003);
  EXPECT_NEAR(packing_fraction(pk), 0.45, 0.003);
  EXPECT_LT(brute_force_overlap(pk), 1e-3);
  EXPECT_LT(wall_overlap(pk), 1e-3);
  double lo = 1e9, hi = 0.0;
  for (const auto& s : pk.disks) lo = std::min(lo, s.radius), hi = std::max(hi, s.radius);
  EXPECT_LE(hi / lo, 1.5 + 1e-12);
}

TEST(ThreeDPacking, SameSeedSameSpheresOtherSeedOthers) {
  const Packing a = generate_packing(sphere_params(0.4, true, 7));
  const Packing b = generate_packing(sphere_params(0.4, true, 7));
  const Packing c = generate_packing(sphere_params(0.4, true, 8));
  bool ab = true, ac = true;
  for (std::size_t i = 0; i < a.disks.size(); ++i) {
    ab = ab && a.disks[i].x == b.disks[i].x && a.disks[i].z == b.disks[i].z;
    ac = ac && a.disks[i].x == c.disks[i].x && a.disks[i].z == c.disks[i].z;
  }
  EXPECT_TRUE(ab);
  EXPECT_FALSE(ac);
}

// Frictionless spheres in a periodic cell jam at random close packing, phi_J = 0.64 (O'Hern et
// al., Phys. Rev. E 68 (2003) 011306: 0.639 for monodisperse spheres); walls lower it.
TEST(ThreeDPacking, JammingFractions) {
  PackingParams p = sphere_params(0.0, true);
  p.method = PackingMethod::kJam;
  p.jam_start_phi = kJamStartPhi3D;
  PackingReport per;
  const Packing pk = generate_packing(p, per);
  p.periodic = false;
  PackingReport walls;
  generate_packing(p, walls);
  std::printf("  jam, 150 spheres: periodic phi_J = %.5f (%.2f s), walls phi_J = %.5f (%.2f s)\n",
              per.jamming_phi, per.wall_seconds, walls.jamming_phi, walls.wall_seconds);
  EXPECT_TRUE(per.relaxed);
  EXPECT_GE(per.jamming_phi, 0.62);
  EXPECT_LE(per.jamming_phi, 0.66);
  EXPECT_LT(brute_force_overlap(pk), 1e-3);
  EXPECT_TRUE(walls.relaxed);
  EXPECT_GE(walls.jamming_phi, 0.50);
  EXPECT_LT(walls.jamming_phi, per.jamming_phi);
}

// The CSV file of a 3D packing: '# dimension = 3', a six-number box, a z column; read back to the
// same spheres bit for bit (walls and periodic), and its VTU written.
TEST(ThreeDPacking, CsvRoundTripIsExact) {
  for (const bool periodic : {false, true}) {
    const Packing pk = generate_packing(sphere_params(0.4, periodic, 5));
    const auto path = scratch(periodic ? "p.csv" : "w.csv");
    write_packing_csv(pk, path.string());
    std::ifstream in(path);
    std::string l1, l2, l3;
    std::getline(in, l1);
    std::getline(in, l2);
    std::getline(in, l3);
    EXPECT_EQ(l2, "# dimension = 3");
    EXPECT_EQ(l3.rfind("# box = 0 0 0 ", 0), 0u) << l3;
    const Packing back = read_packing_csv(path.string());
    EXPECT_EQ(back.dimension, 3);
    EXPECT_EQ(back.periodic, periodic);
    EXPECT_EQ(back.seed, 5u);
    EXPECT_EQ(back.zmin, pk.zmin);
    EXPECT_EQ(back.zmax, pk.zmax);
    EXPECT_EQ(back.xmax, pk.xmax);
    ASSERT_EQ(back.disks.size(), pk.disks.size());
    for (std::size_t i = 0; i < pk.disks.size(); ++i) {
      EXPECT_EQ(back.disks[i].id, pk.disks[i].id);
      EXPECT_EQ(back.disks[i].x, pk.disks[i].x);
      EXPECT_EQ(back.disks[i].y, pk.disks[i].y);
      EXPECT_EQ(back.disks[i].z, pk.disks[i].z);
      EXPECT_EQ(back.disks[i].radius, pk.disks[i].radius);
    }
    EXPECT_EQ(packing_fraction(back), packing_fraction(pk));
    write_packing_vtu(pk, scratch("p.vtu").string());
    EXPECT_TRUE(fs::file_size(scratch("p.vtu")) > 0);
  }
  fs::remove_all(scratch("").parent_path());
}

// Files from elsewhere: a z column without a dimension line is 3D (box = bounding box); a 2D
// file stays 2D; a 3D file with a four-number box, or without z, or two spheres overlapping (a
// pair that is apart in x-y only), is refused naming the line.
TEST(ThreeDPacking, ForeignAndMalformedFiles) {
  const Packing a = parse_packing_csv("id,x,y,z,radius\n0,0,0,0,1\n1,2,0,0,1\n", "a.csv");
  EXPECT_EQ(a.dimension, 3);
  EXPECT_EQ(a.zmin, -1.0);
  EXPECT_EQ(a.zmax, 1.0);
  EXPECT_NEAR(packing_fraction(a), 2 * 4.0 / 3.0 * M_PI / (4 * 2 * 2), 1e-15);
  const Packing b = parse_packing_csv("id,x,y,radius\n0,0,0,1\n", "b.csv");
  EXPECT_EQ(b.dimension, 2);
  const auto refused = [](const std::string& text, std::int64_t line, const std::string& what) {
    try {
      parse_packing_csv(text, "bad.csv");
      ADD_FAILURE() << "accepted: " << text;
    } catch (const mpmcd::InputError& e) {
      const std::string msg = e.what();
      EXPECT_EQ(e.line(), line) << msg;
      EXPECT_NE(msg.find(what), std::string::npos) << msg;
      EXPECT_NE(msg.find("bad.csv"), std::string::npos) << msg;
    }
  };
  refused("# dimension = 3\n# box = 0 0 4 4\nid,x,y,z,radius\n0,2,2,2,1\n", 2, "six numbers");
  refused("# dimension = 3\nid,x,y,radius\n0,2,2,1\n", 2, "'id,x,y,z,radius'");
  refused("# dimension = 4\nid,x,y,radius\n0,2,2,1\n", 1, "key 'dimension': 2 or 3");
  // Same x and y, z apart by 1.5 radii: overlapping spheres (as disks they would coincide).
  refused("id,x,y,z,radius\n0,0,0,0,1\n1,0,0,1.5,1\n", 3, "sphere id 1 to overlap no other");
  refused("# box = 0 0 0 4 4 4\nid,x,y,z,radius\n0,2,2,3.5,1\n", 3, "it is outside");
  // Touching is fine.
  EXPECT_EQ(parse_packing_csv("id,x,y,z,radius\n0,0,0,0,1\n1,0,0,2,1\n", "t.csv").disks.size(), 2u);
}

// The pack input: dimension = 3 with a six-number box / three-number origin, friction; a bad
// dimension, a 2D box in 3D and friction with method "jam" are refused naming the file and the key.
TEST(ThreeDPacking, PackInputAcceptsDimension3AndNamesBadKeys) {
  const std::string head =
      "[packing]\ndimension = 3\ncount = 40\ndiameter_min = 0.8e-3\ndiameter_max = 1.2e-3\n"
      "target_phi = 0.4\n";
  const auto in = parse_packing_input(head + "box = [0, 0, 0, 0.004, 0.004, 0.003]\n", "a.toml");
  EXPECT_EQ(in.params.dimension, 3);
  EXPECT_EQ(in.params.box_z[1], 0.003);
  EXPECT_EQ((*in.params.box)[2], 0.004);
  const auto in2 = parse_packing_input(head + "aspect_ratio = 2.0\norigin = [1, 2, 3]\n", "b.toml");
  EXPECT_EQ(in2.params.origin_z, 3.0);
  EXPECT_EQ(in2.params.jam_start_phi, kJamStartPhi3D);
  const Packing pk = generate_packing(in2.params);
  EXPECT_EQ(pk.zmin, 3.0);
  EXPECT_NEAR((pk.xmax - pk.xmin) / (pk.zmax - pk.zmin), 2.0, 1e-12);
  EXPECT_NEAR((pk.ymax - pk.ymin) / (pk.zmax - pk.zmin), 2.0, 1e-12);
  const auto refused = [](const std::string& text, const std::string& what) {
    try {
      parse_packing_input(text, "bad.toml");
      ADD_FAILURE() << "accepted: " << text;
    } catch (const mpmcd::InputError& e) {
      const std::string msg = e.what();
      EXPECT_NE(msg.find(what), std::string::npos) << msg;
      EXPECT_NE(msg.find("bad.toml"), std::string::npos) << msg;
    }
  };
  refused("[packing]\ndimension = 4\ncount = 4\n", "key 'packing.dimension': 2 (disks) or 3");
  refused("[packing]\ndimension = \"3\"\ncount = 4\n", "key 'packing.dimension': an integer");
  refused(head + "box = [0, 0, 0.004, 0.004]\n", "key 'packing.box': an array of 6 numbers");
  refused(head + "aspect_ratio = 1.0\norigin = [0, 0]\n", "key 'packing.origin': an array of 3");
  // Friction is accepted in 3D (eq. 4'), not with the (frictionless) jamming search.
  const auto in3 = parse_packing_input(head + "aspect_ratio = 1.0\nfriction = 0.2\n", "c.toml");
  EXPECT_EQ(in3.params.friction, 0.2);
  refused(
      "[packing]\ndimension = 3\ncount = 40\ndiameter_min = 0.8e-3\ndiameter_max = 1.2e-3\n"
      "aspect_ratio = 1.0\nmethod = \"jam\"\nfriction = 0.2\n",
      "key 'packing.friction': 0 for method \"jam\"");
}

// `mpmcd pack` of a 3D input writes the CSV and the VTU and prints the 3D box; seed_packing of
// 2D grains refuses a 3D packing, and 3D grains get each its sphere's exact volume.
TEST(ThreeDPacking, PackCommandWrites3DFiles) {
  const auto input = scratch("pack3d.toml");
  const auto folder = scratch("out3d");
  std::ofstream(input) << "[packing]\ndimension = 3\ncount = 60\ndiameter_min = 0.8e-3\n"
                          "diameter_max = 1.2e-3\nbox = [0, 0, 0, 0.004, 0.004, 0.005]\n"
                          "target_phi = 0.45\nseed = 5\n[output]\nfolder = \""
                       << folder.string() << "\"\nname = \"p\"\n";
  testing::internal::CaptureStdout();
  const int rc = pack_command(input.string(), true);
  const std::string out = testing::internal::GetCapturedStdout();
  EXPECT_EQ(rc, 0);
  EXPECT_NE(out.find("packing: 60 grains, phi = 0.45"), std::string::npos) << out;
  EXPECT_NE(out.find("x [0, 0.005] m"), std::string::npos) << out;
  ASSERT_TRUE(fs::exists(folder / "p.vtu"));
  const Packing pk = read_packing_csv((folder / "p.csv").string());
  EXPECT_EQ(pk.dimension, 3);
  EXPECT_EQ(pk.disks.size(), 60u);
  EXPECT_EQ(pk.zmax, 0.005);
  EXPECT_NEAR(packing_fraction(pk), 0.45, 1e-9);
  EXPECT_THROW(seed_packing<2>(pk, mpmcd::Vec<2>::Zero(), 1e-4, 2), mpmcd::InputError);
  // 3D seeding at h = 0.25 mm (about d/4), 2 points per cell axis: each sphere's points lie inside
  // it, no lattice site is seeded twice, and the volumes sum to 4/3 pi r^3 per sphere.
  const double h = 0.25e-3, s = h / 2;
  const auto seeded = seed_packing<3>(pk, mpmcd::Vec<3>(-h, -h, -h), h, 2);
  ASSERT_EQ(seeded.offset.size(), pk.disks.size() + 1);
  ASSERT_EQ(seeded.offset.back(), seeded.x.size());
  std::set<std::array<long long, 3>> sites;
  double total = 0, exact = 0;
  for (std::size_t g = 0; g < pk.disks.size(); ++g) {
    const auto& d = pk.disks[g];
    const mpmcd::Vec<3> c(d.x, d.y, d.z);
    double volume = 0;
    ASSERT_LT(seeded.offset[g], seeded.offset[g + 1]) << "sphere " << d.id << " has no point";
    for (std::size_t k = seeded.offset[g]; k < seeded.offset[g + 1]; ++k) {
      EXPECT_LT((seeded.x[k] - c).norm(), d.radius);
      volume += seeded.volume[k];
      std::array<long long, 3> site{};
      for (int a = 0; a < 3; ++a) site[a] = std::llround((seeded.x[k][a] + h) / s - 0.5);
      EXPECT_TRUE(sites.insert(site).second) << "site seeded twice";
    }
    const double v = 4.0 / 3.0 * std::numbers::pi * std::pow(d.radius, 3);
    EXPECT_NEAR(volume, v, 1e-12 * v);
    total += volume;
    exact += v;
  }
  // the lattice count is the volume over s^3 within a few percent (points per sphere ~ 270)
  EXPECT_NEAR(static_cast<double>(seeded.x.size()) * s * s * s / exact, 1.0, 0.03);
  EXPECT_NEAR(total, exact, 1e-12 * exact);
  fs::remove_all(scratch("").parent_path());
}
