// Seeding packed grains with material points (docs/packing.md §8).
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <set>
#include <utility>

#include "mpmcd/core/errors.hpp"
#include "mpmcd/packing/packing.hpp"
#include "mpmcd/packing/seeding.hpp"

using namespace mpmcd;
using namespace mpmcd::packing;

namespace {

void expect_valid_seeding(const Packing& pk, const SeededPacking<2>& s) {
  ASSERT_EQ(s.offset.size(), pk.disks.size() + 1);
  ASSERT_EQ(s.x.size(), s.volume.size());
  ASSERT_EQ(s.x.size(), s.grain.size());
  EXPECT_EQ(s.offset.back(), s.x.size());
  double total_points = 0.0, total_disks = 0.0;
  for (std::size_t g = 0; g < pk.disks.size(); ++g) {
    const double disk = std::numbers::pi * pk.disks[g].radius * pk.disks[g].radius;
    double points = 0.0;
    ASSERT_LT(s.offset[g], s.offset[g + 1]) << "grain " << g << " has no point";
    for (std::size_t k = s.offset[g]; k < s.offset[g + 1]; ++k) {
      EXPECT_EQ(s.grain[k], static_cast<std::int64_t>(g));
      points += s.volume[k];
    }
    EXPECT_NEAR(points, disk, 0.01 * disk) << "grain " << g;
    total_points += points;
    total_disks += disk;
  }
  EXPECT_NEAR(total_points, total_disks, 0.01 * total_disks);
  // No two points share a position (exact comparison: all sites come from one lattice).
  std::set<std::pair<double, double>> seen;
  for (const auto& x : s.x) EXPECT_TRUE(seen.insert({x[0], x[1]}).second) << x.transpose();
}

}  // namespace

TEST(Seeding, PackedGrainsShareNoPointAndKeepTheirArea) {
  PackingParams p;
  p.count = 300;
  p.diameter_min = 0.8e-3;
  p.diameter_max = 1.2e-3;
  p.target_phi = 0.78;
  p.overlap_tolerance = 0.05;  // a loosely relaxed packing: overlaps up to 5 % of d
  p.max_relax_steps = 50;
  const Packing pk = generate_packing(p);
  const double h = 1e-3 / 8.0;
  const auto s = seed_packing(pk, Vec<2>(pk.xmin, pk.ymin), h, 2);
  std::printf("seeded %zu points in %zu grains, max overlap %.3e d\n", s.x.size(), pk.disks.size(),
              max_overlap(pk) / mean_diameter(pk));
  expect_valid_seeding(pk, s);
}

TEST(Seeding, SharedSiteGoesToTheGrainWhoseCenterIsNearerRelativeToItsRadius) {
  // Two disks overlapping by a fifth of the small one: sites in the lens are claimed twice.
  Packing pk;
  pk.xmax = pk.ymax = 10.0;
  pk.disks = {{0, 4.0, 5.0, 1.0}, {1, 5.6, 5.0, 0.8}};
  const double h = 0.1;
  const Vec<2> origin(0.0, 0.0);
  const auto s = seed_packing(pk, origin, h, 1);
  expect_valid_seeding(pk, s);
  int in_lens = 0;
  for (std::size_t k = 0; k < s.x.size(); ++k) {
    const double r0 = (s.x[k] - Vec<2>(4.0, 5.0)).norm() / 1.0;
    const double r1 = (s.x[k] - Vec<2>(5.6, 5.0)).norm() / 0.8;
    if (r0 < 1.0 && r1 < 1.0) {
      ++in_lens;
      EXPECT_EQ(s.grain[k], r0 <= r1 ? 0 : 1) << s.x[k].transpose();
    }
  }
  EXPECT_GT(in_lens, 10);
}

TEST(Seeding, RejectsBadLatticeSettings) {
  Packing pk;
  pk.xmax = pk.ymax = 1.0;
  pk.disks = {{0, 0.5, 0.5, 0.01}};
  EXPECT_THROW(seed_packing(pk, Vec<2>(0, 0), 0.0, 2), InputError);
  EXPECT_THROW(seed_packing(pk, Vec<2>(0, 0), 0.1, 0), InputError);
  // Spacing 0.5: no site inside a disk of radius 0.01 centred between sites.
  pk.disks[0] = {0, 0.5, 0.5, 0.01};
  EXPECT_THROW(seed_packing(pk, Vec<2>(0, 0), 0.5, 1), InputError);
  // A billion points is refused instead of allocated.
  EXPECT_THROW(seed_packing(pk, Vec<2>(0, 0), 1e-7, 64), InputError);
}
