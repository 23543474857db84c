// Compaction observables on hand-made data: the box from four walls, Φ, ε and the identity of
// paper eq. (9), wall stress, Love-Weber stress of a uniform state, coordination number Z.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <numbers>
#include <vector>

#include "../../support/scratch.hpp"
#include "mpmcd/analysis/observables.hpp"
#include "mpmcd/analysis/time_series.hpp"
#include "mpmcd/core/errors.hpp"
#include "mpmcd/walls/wall.hpp"

using namespace mpmcd;
using namespace mpmcd::analysis;

namespace {

// A 3 mm x 2 mm box at the origin, top wall moving down at 2 m/s, listed in a shuffled order.
std::vector<walls::Wall<2>> box_walls() {
  return {{"top", Vec<2>(0, 2e-3), Vec<2>(0, -1), Vec<2>(0, -2)},
          {"left", Vec<2>(0, 0), Vec<2>(1, 0), Vec<2>::Zero()},
          {"right", Vec<2>(3e-3, 0), Vec<2>(-1, 0), Vec<2>::Zero()},
          {"bottom", Vec<2>(0, 0), Vec<2>(0, 1), Vec<2>::Zero()}};
}

ContactImpulse pair(int a, int b, double p) {
  return {a, b, p};
}

}  // namespace

TEST(Box, FoundFromFourAxisWallsInAnyOrder) {
  const auto walls = box_walls();
  const auto b = find_box(walls);
  ASSERT_TRUE(b.has_value());
  EXPECT_EQ(b->top, 0u);
  EXPECT_EQ(b->left, 1u);
  EXPECT_EQ(b->right, 2u);
  EXPECT_EQ(b->bottom, 3u);
  const Box box = box_at(walls, *b, 1e-4);  // top at 2 mm - 0.2 mm
  EXPECT_DOUBLE_EQ(box.height(), 1.8e-3);
  EXPECT_DOUBLE_EQ(box.width(), 3e-3);
  EXPECT_DOUBLE_EQ(box.area(), 5.4e-6);
  EXPECT_DOUBLE_EQ(wall_length(box, *b, 0), 3e-3);
  EXPECT_DOUBLE_EQ(wall_length(box, *b, 1), 1.8e-3);
}

TEST(Box, NotABox) {
  auto walls = box_walls();
  walls.pop_back();  // three walls
  EXPECT_FALSE(find_box(walls).has_value());
  walls = box_walls();
  walls[1].normal = Vec<2>(1, 1).normalized();  // tilted wall
  EXPECT_FALSE(find_box(walls).has_value());
  walls = box_walls();
  walls[2].normal = Vec<2>(1, 0);  // two left walls
  EXPECT_FALSE(find_box(walls).has_value());
}

TEST(Compaction, PhiStrainAndIdentityOfEq9) {
  const auto walls = box_walls();
  const auto b = *find_box(walls);
  const Box box0 = box_at(walls, b, 0.0);
  const double vs0 = 4.2e-6;
  const auto s0 = compaction_state(box0, box0, vs0, vs0);
  EXPECT_DOUBLE_EQ(s0.phi, 0.7);
  EXPECT_EQ(s0.strain, 0.0);
  EXPECT_EQ(s0.ln_vs_vs0, 0.0);
  for (double t : {1e-5, 2e-4, 5e-4, 9e-4}) {
    const double vs = vs0 * (1 - 30 * t);  // grains lose area as they are squeezed
    const auto s = compaction_state(box_at(walls, b, t), box0, vs, vs0);
    EXPECT_DOUBLE_EQ(s.height, 2e-3 - 2 * t);
    EXPECT_DOUBLE_EQ(s.strain, std::log((2e-3 - 2 * t) / 2e-3));
    EXPECT_DOUBLE_EQ(s.phi, vs / (3e-3 * (2e-3 - 2 * t)));
    EXPECT_NEAR(s.ln_vs_vs0, std::log(s.phi / s0.phi) + s.strain, 1e-14);  // eq. (9)
  }
}

TEST(Compaction, WallStressIsNegativeInCompression) {
  // Grains push the bottom wall (normal +y) down with 30 N/m over 3 mm: -10 kPa.
  EXPECT_DOUBLE_EQ(wall_normal_stress(Vec<2>(0.5, -30), Vec<2>(0, 1), 3e-3), -1e4);
  // ... and the top wall (normal -y) up.
  EXPECT_DOUBLE_EQ(wall_normal_stress(Vec<2>(0, 30), Vec<2>(0, -1), 3e-3), -1e4);
  // Pulling (adhesion, never in CD) would be positive.
  EXPECT_DOUBLE_EQ(wall_normal_stress(Vec<2>(-30, 0), Vec<2>(-1, 0), 3e-3), 1e4);
}

// A 3D box of six walls (the order of the walls is free), the top one moving down: the box, its
// volume, the face areas the stresses divide by, Φ; a tilted or missing wall is no box.
TEST(Compaction, ThreeDimensionalBoxOfSixWalls) {
  std::vector<walls::Wall<3>> w = {
      {"back", Vec<3>(0, 0, 4e-3), Vec<3>(0, 0, -1), Vec<3>::Zero(), 0.0},
      {"left", Vec<3>(0, 0, 0), Vec<3>(1, 0, 0), Vec<3>::Zero(), 0.0},
      {"right", Vec<3>(3e-3, 0, 0), Vec<3>(-1, 0, 0), Vec<3>::Zero(), 0.0},
      {"bottom", Vec<3>(0, 0, 0), Vec<3>(0, 1, 0), Vec<3>::Zero(), 0.0},
      {"top", Vec<3>(0, 2e-3, 0), Vec<3>(0, -1, 0), Vec<3>(0, -2, 0), 0.0},
      {"front", Vec<3>(0, 0, 1e-3), Vec<3>(0, 0, 1), Vec<3>::Zero(), 0.0}};
  const auto b = find_box(w);
  ASSERT_TRUE(b.has_value());
  EXPECT_EQ(b->front, 5u);
  EXPECT_EQ(b->back, 0u);
  EXPECT_EQ(b->top, 4u);
  const Box box0 = box_at(w, *b, 0.0), box = box_at(w, *b, 1e-4);
  EXPECT_EQ(box0.dim, 3);
  EXPECT_DOUBLE_EQ(box0.area(), 3e-3 * 2e-3 * 3e-3);  // width x height x depth [m^3]
  EXPECT_DOUBLE_EQ(box.height(), 2e-3 - 2e-4);
  EXPECT_DOUBLE_EQ(wall_length(box, *b, b->top), 3e-3 * 3e-3);             // width x depth
  EXPECT_DOUBLE_EQ(wall_length(box, *b, b->left), (2e-3 - 2e-4) * 3e-3);   // height x depth
  EXPECT_DOUBLE_EQ(wall_length(box, *b, b->front), 3e-3 * (2e-3 - 2e-4));  // width x height
  const auto s = compaction_state(box, box0, 9e-9, 9e-9);
  EXPECT_DOUBLE_EQ(s.phi, 9e-9 / box.area());
  EXPECT_NEAR(s.strain, std::log(0.9), 1e-14);
  // 1 N on the top face of 9e-6 m^2, pushed up by the grains: -1/9e-6 Pa.
  EXPECT_DOUBLE_EQ(wall_normal_stress(Vec<3>(0, 1, 0), w[4].normal, wall_length(box, *b, 4)),
                   -1.0 / 9e-6);
  auto tilted = w;
  tilted[5].normal = Vec<3>(0, 0.6, 0.8);
  EXPECT_FALSE(find_box(tilted).has_value());
  tilted = w;
  tilted.pop_back();
  EXPECT_FALSE(find_box(tilted).has_value());
}

TEST(LoveWeber, UniformStressOverTheSolidFraction) {
  points::PointSet<2> pts;
  Mat<2> s;
  s << -2e5, 3e4, 3e4, -5e5;
  for (int i = 0; i < 10; ++i) {
    pts.add(Vec<2>(i, 0), Vec<2>::Zero(), 1.0, 1e-8, Mat<2>::Identity() * 5e-5, 0);
    pts.volume.back() = 1e-8 * (1 + 0.1 * i);  // current volumes differ
    pts.sigma.back() = s;
  }
  const double vs = 1e-7 * (1 + 0.45);
  // Over the grains' own area: the uniform stress itself; over a box twice as large: half.
  EXPECT_LT((love_weber_stress(pts, vs) - s).norm(), 1e-9 * s.norm());
  EXPECT_LT((love_weber_stress(pts, 2 * vs) - 0.5 * s).norm(), 1e-9 * s.norm());
}

TEST(Coordination, PairsWithSeveralNodesCountOnce) {
  // Triangle 0-1-2 with each pair touching at several nodes; a wall contact on grain 0.
  const std::vector<ContactImpulse> c = {pair(0, 1, 1.0), pair(0, 1, 0.5), pair(1, 2, 2.0),
                                         pair(2, 1, 0.1), pair(0, 2, 0.3), pair(0, 2, 0.3),
                                         pair(-1, 0, 5.0)};
  const auto z = coordination(c, 3);
  EXPECT_EQ(z.all_pairs, 3);
  EXPECT_EQ(z.pairs, 3);
  EXPECT_EQ(z.grains, 3);
  EXPECT_EQ(z.rattlers, 0);
  EXPECT_EQ(z.wall_contacts, 1);
  EXPECT_DOUBLE_EQ(z.z, 2.0);  // 2 * 3 / 3
}

TEST(Coordination, RattlersRemovedRepeatedly) {
  // Square 0-1-2-3 with diagonal 0-2 (5 pairs), a chain 3-4-5 hanging off it, grain 6 free,
  // grain 7 touching only a wall. Removing 5 leaves 4 with one contact: it goes too.
  const std::vector<ContactImpulse> c = {pair(0, 1, 1), pair(1, 2, 1),  pair(2, 3, 1),
                                         pair(3, 0, 1), pair(0, 2, 1),  pair(3, 4, 1),
                                         pair(4, 5, 1), pair(-1, 7, 1), pair(-1, 0, 1)};
  const auto z = coordination(c, 8);
  EXPECT_EQ(z.all_pairs, 7);
  EXPECT_EQ(z.wall_contacts, 2);
  EXPECT_EQ(z.grains, 4);
  EXPECT_EQ(z.rattlers, 4);  // 4, 5, 6, 7
  EXPECT_EQ(z.pairs, 5);
  EXPECT_DOUBLE_EQ(z.z, 2.0 * 5 / 4);
}

TEST(Coordination, WallsHoldGrainsButAreNotPairs) {
  // A column 0-1-2 between the bottom wall (-1) and the top wall (-2); grain 3 in the corner of
  // the bottom and left (-3) walls; grain 4 on the bottom wall only.
  const std::vector<ContactImpulse> c = {pair(-1, 0, 2), pair(0, 1, 2),   pair(1, 2, 2),
                                         pair(-2, 2, 2), pair(-1, 3, 1),  pair(-3, 3, 1),
                                         pair(-1, 4, 1), pair(-1, 4, 0.5)};
  const auto z = coordination(c, 5);
  EXPECT_EQ(z.wall_contacts, 5);
  EXPECT_EQ(z.grains, 4);  // 0, 1, 2 and the corner grain 3 (two walls, no pair)
  EXPECT_EQ(z.rattlers, 1);
  EXPECT_EQ(z.pairs, 2);
  EXPECT_DOUBLE_EQ(z.z, 1.0);
  // Without the walls every grain of the column is a rattler in turn.
  const auto bare = coordination(c, 5, {1e-6, false});
  EXPECT_EQ(bare.grains, 0);
  EXPECT_EQ(bare.z, 0.0);
}

TEST(Coordination, ThresholdAndSignsOfImpulses) {
  // Pair 0-1 carries a large impulse; 1-2 only round-off (1e-9 relative); 0-2 sums to a negative
  // (opening) impulse; 2-3 nodes cancel. Only 0-1 is a contact, so everyone is a rattler.
  const std::vector<ContactImpulse> c = {pair(0, 1, 1.0), pair(1, 2, 1e-9), pair(0, 2, -0.2),
                                         pair(2, 3, 0.5), pair(2, 3, -0.5)};
  const auto z = coordination(c, 4);
  EXPECT_EQ(z.all_pairs, 1);
  EXPECT_EQ(z.grains, 0);
  EXPECT_EQ(z.z, 0.0);
  // A looser relative threshold keeps 1-2 (then 0-1-2 is a chain, still all rattlers).
  EXPECT_EQ(coordination(c, 4, {1e-12}).all_pairs, 2);
  EXPECT_EQ(coordination({}, 5).z, 0.0);
}

TEST(Coordination, FromAContactProblem) {
  contact::Problem<2> pb;
  pb.slots.resize(4);
  pb.slots[0].grain = 0;
  pb.slots[1].grain = 1;
  pb.slots[2].grain = 1;
  pb.slots[3].grain = 2;
  contact::Contact<2> c;
  c.a = 0;
  c.b = 1;
  c.normal = Vec<2>(1, 0);
  c.impulse = Vec<2>(2.0, 0.5);
  pb.contacts.push_back(c);
  c.a = -1;
  c.wall = 2;
  c.b = 3;
  c.normal = Vec<2>(0, 1);
  c.impulse = Vec<2>(0.0, -1.0);
  pb.contacts.push_back(c);
  const auto ci = contact_impulses(pb);
  ASSERT_EQ(ci.size(), 2u);
  EXPECT_EQ(ci[0].a, 0);
  EXPECT_EQ(ci[0].b, 1);
  EXPECT_DOUBLE_EQ(ci[0].normal_impulse, 2.0);
  EXPECT_EQ(ci[1].a, -3);
  EXPECT_EQ(ci[1].b, 2);
  EXPECT_DOUBLE_EQ(ci[1].normal_impulse, -1.0);
}

TEST(TimeSeries, ReadsColumnsAndRefusesGarbage) {
  const auto dir = mpmcd::test_support::scratch_path("unit_analysis");
  std::filesystem::create_directories(dir);
  const auto good = (dir / "good.csv").string();
  std::ofstream(good) << "time,phi\n0,0.7\n1e-3,7.5e-1\n";
  const auto ts = read_time_series(good);
  EXPECT_EQ(ts.rows(), 2u);
  EXPECT_EQ(ts.column("phi")[1], 0.75);
  EXPECT_TRUE(ts.has("time"));
  EXPECT_THROW((void)ts.column("Z"), InputError);
  const auto bad = (dir / "bad.csv").string();
  std::ofstream(bad) << "time,phi\n0,abc\n";
  EXPECT_THROW(read_time_series(bad), InputError);
  std::ofstream(bad) << "time,phi\n0\n";
  EXPECT_THROW(read_time_series(bad), InputError);
  EXPECT_THROW(read_time_series((dir / "none.csv").string()), InputError);
}

namespace {

// The pore diameter of pores of measures m_i: Σ m_i d_i / Σ m_i with the equivalent diameters
// d_i = sqrt(4 m_i / π) (2D) or (6 m_i / π)^(1/3) (3D) [m].
double weighted_diameter(std::initializer_list<double> measures, int dim) {
  double weighted = 0, total = 0;
  for (const double m : measures) {
    weighted +=
        m * (dim == 3 ? std::cbrt(6 * m / std::numbers::pi) : std::sqrt(4 * m / std::numbers::pi));
    total += m;
  }
  return weighted / total;
}

// A grain: an nx x ny lattice of square point domains of side d with lower-left corner `origin`,
// every point with the deformation gradient F about the grain's centre.
void add_block(points::PointSet<2>& pts, std::int32_t g, const Vec<2>& origin, int nx, int ny,
               double d, const Mat<2>& F = Mat<2>::Identity()) {
  const Vec<2> centre = origin + 0.5 * d * Vec<2>(nx, ny);
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const Vec<2> x0 = origin + d * Vec<2>(i + 0.5, j + 0.5);
      pts.add(centre + F * (x0 - centre), Vec<2>::Zero(), 1.0, d * d,
              Mat<2>::Identity() * (0.5 * d), g);
      pts.F.back() = F;
    }
}

}  // namespace

TEST(Coverage, OneGrainCoversItsAreaAndTwoOverlappingGrainsTheirStrip) {
  const Box box{0, 4e-3, 0, 2e-3};
  const double d = 1e-4;
  points::PointSet<2> pts;
  add_block(pts, 0, Vec<2>(0.5e-3, 0.5e-3), 10, 10, d);  // 1 mm x 1 mm
  const double pixel = d / 16;
  const auto one = domain_coverage(pts, box, pixel);
  EXPECT_DOUBLE_EQ(one.pixel, pixel);
  EXPECT_NEAR(one.covered, 1e-6, 1e-6 * 4 * pixel / 1e-3);  // one pixel row per edge at most
  EXPECT_EQ(one.overlap, 0.0);
  EXPECT_EQ(one.outside, 0.0);

  // A second grain overlapping the first over a 0.23 mm strip and crossing the right wall.
  add_block(pts, 1, Vec<2>(1.27e-3, 0.5e-3), 30, 10, d);  // x from 1.27 to 4.27 mm
  const auto two = domain_coverage(pts, box, pixel);
  EXPECT_NEAR(two.overlap, 0.23e-3 * 1e-3, 2 * pixel * 1e-3);
  EXPECT_NEAR(two.outside, 0.27e-3 * 1e-3, 2 * pixel * 1e-3);
  EXPECT_NEAR(two.covered, (4e-3 - 0.5e-3) * 1e-3,  // the union inside the box
              4 * pixel * 1e-3);
}

TEST(Coverage, DomainsFollowTheDeformationGradient) {
  const Box box{0, 4e-3, 0, 4e-3};
  Mat<2> F;
  F << 1.3, 0.4, -0.1, 0.6;  // J = 0.82
  points::PointSet<2> pts;
  add_block(pts, 0, Vec<2>(1.5e-3, 1.5e-3), 10, 10, 1e-4, F);
  const auto c = domain_coverage(pts, box, 1e-4 / 16);
  EXPECT_NEAR(c.covered / 1e-6, F.determinant(), 0.01);  // tiles without gaps or overlaps
  EXPECT_EQ(c.overlap, 0.0);                             // overlaps within a grain are not counted
  // A raster limited to 1e4 pixels coarsens them and still measures the area.
  const auto coarse = domain_coverage(pts, box, 1e-4 / 16, 10000);
  EXPECT_GT(coarse.pixel, 4e-3 / 100);  // 100 x 100 pixels cover at most the 4 mm box
  EXPECT_NEAR(coarse.covered / 1e-6, F.determinant(), 0.05);
}

TEST(Coverage, PoresBorderTwoGrainsOrAWallAndGapsOneGrain) {
  // A 1 mm x 1 mm box filled by two grains (x < 0.5 mm and x > 0.5 mm) except a 0.2 mm square
  // hole across both, a 0.1 mm hole on the right wall (pores) and a 0.1 mm hole inside grain 0
  // (a gap). Pore diameter: (A1 d1 + A2 d2) / (A1 + A2) with d_i = sqrt(4 A_i / π).
  const Box box{0, 1e-3, 0, 1e-3};
  const double d = 1e-4;
  points::PointSet<2> pts;
  for (int g = 0; g < 2; ++g)
    for (int j = 0; j < 10; ++j)
      for (int i = 5 * g; i < 5 * g + 5; ++i) {
        if ((i == 4 || i == 5) && (j == 2 || j == 3)) continue;  // 0.2 mm pore
        if (i == 9 && j == 7) continue;                          // 0.1 mm pore on the wall
        if (i == 1 && j == 7) continue;                          // 0.1 mm gap in grain 0
        pts.add(Vec<2>((i + 0.5) * d, (j + 0.5) * d), Vec<2>::Zero(), 1.0, d * d,
                Mat<2>::Identity() * (0.5 * d), g);
      }
  const auto c = domain_coverage(pts, box, d / 16);
  const double a1 = 4e-8, a2 = 1e-8;
  const double expected = weighted_diameter({a1, a2}, 2);
  EXPECT_NEAR(c.pore_diameter, expected, 1e-3 * expected);
  EXPECT_NEAR(c.pores, a1 + a2, 1e-12);
  EXPECT_NEAR(c.gaps, 1e-8, 1e-12);
  EXPECT_NEAR(c.covered, 1e-6 - a1 - 2 * a2, 1e-12);
}

namespace {

// A 3D grain: an n[0] x n[1] x n[2] lattice of cubic point domains of side d with lowest corner
// `origin`, every point with the deformation gradient F about the grain's centre; the points
// listed in `skip` (lattice indices i, j, k) left out.
void add_block_3d(points::PointSet<3>& pts, std::int32_t g, const Vec<3>& origin,
                  const std::array<int, 3>& n, double d, const Mat<3>& F = Mat<3>::Identity(),
                  const std::vector<std::array<int, 3>>& skip = {}) {
  const Vec<3> centre = origin + 0.5 * d * Vec<3>(n[0], n[1], n[2]);
  for (int k = 0; k < n[2]; ++k)
    for (int j = 0; j < n[1]; ++j)
      for (int i = 0; i < n[0]; ++i) {
        if (std::find(skip.begin(), skip.end(), std::array<int, 3>{i, j, k}) != skip.end())
          continue;
        const Vec<3> x0 = origin + d * Vec<3>(i + 0.5, j + 0.5, k + 0.5);
        pts.add(centre + F * (x0 - centre), Vec<3>::Zero(), 1.0, d * d * d,
                Mat<3>::Identity() * (0.5 * d), g);
        pts.F.back() = F;
      }
}

}  // namespace

// One box-shaped domain whose faces lie on voxel faces: its volume to round-off, nothing outside
// or overlapping; a second grain overlapping it over a slab and crossing the right wall: the
// slab's volume as overlap, the part past the wall as outside (within one voxel layer).
TEST(Coverage3D, OneBoxAndTwoOverlappingGrains) {
  const Box box{0, 4e-3, 0, 2e-3, 0, 2e-3, 3};
  points::PointSet<3> pts;
  pts.add(Vec<3>(1e-3, 1e-3, 1e-3), Vec<3>::Zero(), 1.0, 0.5e-9,
          Vec<3>(0.5e-3, 0.25e-3, 0.5e-3).asDiagonal().toDenseMatrix(), 0);  // 1 x 0.5 x 1 mm
  const double voxel = 1e-3 / 32;
  const auto one = domain_coverage(pts, box, voxel);
  EXPECT_DOUBLE_EQ(one.pixel, voxel);
  EXPECT_NEAR(one.covered, 0.5e-9, 1e-12 * 0.5e-9);
  EXPECT_EQ(one.overlap, 0.0);
  EXPECT_EQ(one.outside, 0.0);
  // Pores: the box less the domain, one void reaching the walls.
  EXPECT_NEAR(one.pores, 16e-9 - 0.5e-9, 1e-12 * 16e-9);
  EXPECT_NEAR(one.pore_diameter, std::cbrt(6 * 15.5e-9 / std::numbers::pi), 1e-12);

  // Grain 1: x from 1.3 to 4.3 mm (over grain 0's x <= 1.5 mm: a 0.2 mm slab), y and z as
  // grain 0's domain.
  add_block_3d(pts, 1, Vec<3>(1.3e-3, 0.75e-3, 0.5e-3), {30, 5, 10}, 1e-4);
  const auto two = domain_coverage(pts, box, voxel);
  const double face = 0.5e-3 * 1e-3;  // the y-z section of both grains
  std::printf("  overlap %.6g (exact 1e-10), outside %.6g (1.5e-10), covered %.6g (1.75e-9) m^3\n",
              two.overlap, two.outside, two.covered);
  EXPECT_NEAR(two.overlap, 0.2e-3 * face, voxel * face);
  EXPECT_NEAR(two.outside, 0.3e-3 * face, voxel * face);
  EXPECT_NEAR(two.covered, (4e-3 - 0.5e-3) * face, 2 * voxel * face);
}

// Parallelepipeds: a sheared and stretched lattice (F, J = det F) tiles without gaps or overlaps,
// so its covered volume is J times the undeformed one; a raster limited to 1e5 voxels coarsens
// them and still measures it.
TEST(Coverage3D, ParallelepipedsFollowTheDeformationGradient) {
  const Box box{0, 3e-3, 0, 3e-3, 0, 3e-3, 3};
  Mat<3> F;
  F << 1.2, 0.3, -0.1, 0.05, 0.8, 0.2, -0.2, 0.1, 1.1;
  points::PointSet<3> pts;
  add_block_3d(pts, 0, Vec<3>(1e-3, 1e-3, 1e-3), {10, 10, 10}, 1e-4, F);
  const auto c = domain_coverage(pts, box, 1e-4 / 4);
  std::printf("  J = %.6f, covered / V0 = %.6f\n", F.determinant(), c.covered / 1e-9);
  EXPECT_NEAR(c.covered / 1e-9, F.determinant(), 0.01);
  EXPECT_EQ(c.overlap, 0.0);  // overlaps within a grain are not counted
  EXPECT_EQ(c.outside, 0.0);
  const auto coarse = domain_coverage(pts, box, 1e-4 / 4, 100000);
  EXPECT_GT(coarse.pixel, 3e-3 / 47);  // 47^3 > 1e5 voxels over the box alone
  EXPECT_NEAR(coarse.covered / 1e-9, F.determinant(), 0.05);
  std::printf("  coarse: voxel %.4g m, covered / V0 = %.6f\n", coarse.pixel, coarse.covered / 1e-9);
}

// A 1 mm cube filled by two grains (x < 0.5 mm and x > 0.5 mm) less a 0.2 mm cubic hole across
// both (enclosed between the grains: a pore), a 0.1 mm hole in grain 1 on the right wall (a
// pore) and a 0.1 mm hole enclosed in grain 0 (a gap). The voids are 6-connected; the pore
// diameter is (V1 d1 + V2 d2) / (V1 + V2), d_i = (6 V_i / π)^(1/3).
TEST(Coverage3D, PoresBorderTwoGrainsOrAWallAndGapsOneGrain) {
  const Box box{0, 1e-3, 0, 1e-3, 0, 1e-3, 3};
  const double d = 1e-4;
  std::vector<std::array<int, 3>> holes = {{9, 7, 5}, {1, 7, 5}};
  for (int i = 4; i < 6; ++i)
    for (int j = 2; j < 4; ++j)
      for (int k = 2; k < 4; ++k) holes.push_back({i, j, k});
  points::PointSet<3> pts;
  for (int g = 0; g < 2; ++g) {
    std::vector<std::array<int, 3>> skip;  // the holes in this grain's own lattice indices
    for (const auto& h : holes)
      if (h[0] >= 5 * g && h[0] < 5 * g + 5) skip.push_back({h[0] - 5 * g, h[1], h[2]});
    add_block_3d(pts, g, Vec<3>(5 * g * d, 0, 0), {5, 10, 10}, d, Mat<3>::Identity(), skip);
  }
  const auto c = domain_coverage(pts, box, d / 8);
  const double v1 = 8e-12, v2 = 1e-12;
  const double expected = weighted_diameter({v1, v2}, 3);
  EXPECT_NEAR(c.pore_diameter, expected, 1e-9 * expected);
  EXPECT_NEAR(c.pores, v1 + v2, 1e-9 * (v1 + v2));
  EXPECT_NEAR(c.gaps, 1e-12, 1e-9 * 1e-12);
  EXPECT_NEAR(c.covered, 1e-9 - v1 - 2 * v2, 1e-9 * 1e-9);
  EXPECT_EQ(c.overlap, 0.0);
  EXPECT_EQ(c.outside, 0.0);
}
