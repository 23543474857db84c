// Seeding (points module): lattice disks and the polar (ring) disk seeding used for contact.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "mpmcd/points/seeding.hpp"

using namespace mpmcd;

namespace {
// Support function of a point's domain along the unit vector n: sum_k |n . r_k| [m].
double extent(const Mat<2>& dom, const Vec<2>& n) {
  return (dom.transpose() * n).cwiseAbs().sum();
}
}  // namespace

TEST(PolarSeeding, AreaExactDomainsTileTheDiskAndTouchTheCircle) {
  const Vec<2> c(0.3, -0.1);
  for (double R_over_s : {1.0, 2.5, 5.0, 10.0, 20.0}) {
    const double s = 1e-3, R = R_over_s * s;
    const auto seeds = points::seed_disk_polar(c, R, s);
    ASSERT_EQ(seeds.x.size(), seeds.volume.size());
    ASSERT_EQ(seeds.x.size(), seeds.domain.size());
    double area = 0, outer = 0, inside = 0, spread = 0;
    for (std::size_t i = 0; i < seeds.x.size(); ++i) {
      area += seeds.volume[i];
      // Each domain's parallelogram area 4 |det| equals the point's volume.
      EXPECT_NEAR(4 * std::abs(seeds.domain[i].determinant()), seeds.volume[i],
                  1e-12 * seeds.volume[i]);
      const Vec<2> d = seeds.x[i] - c;
      inside = std::max(inside, d.norm());
      if (d.norm() > 0) {
        const Vec<2> n = d / d.norm();
        outer = std::max(outer, d.norm() + extent(seeds.domain[i], n));
      }
    }
    // Exact area pi R^2; every point strictly inside; the outermost domains reach the circle
    // exactly along their radius.
    EXPECT_NEAR(area, std::numbers::pi * R * R, 1e-12 * R * R) << R_over_s;
    EXPECT_LT(inside, R);
    EXPECT_NEAR(outer, R, 1e-12 * R) << R_over_s;
    // Spacing close to the requested one: points per area within 40 % of 1 / s^2 (a disk of one
    // spacing still gets its centre point and a ring of 6, twice that density).
    spread = static_cast<double>(seeds.x.size()) * s * s / (std::numbers::pi * R * R);
    if (R_over_s > 2) {
      EXPECT_GT(spread, 0.6) << R_over_s;
      EXPECT_LT(spread, 1.4) << R_over_s;
    }
  }
}

TEST(PolarSeeding, BoundaryFollowsTheCircleInEveryDirection) {
  // The support function of the union of domains along any direction is within s^2 / R of R
  // (the polygon of tangent domains), unlike the lattice's staircase (up to s / 2).
  const double s = 1e-3, R = 10 * s;
  const auto seeds = points::seed_disk_polar(Vec<2>::Zero(), R, s);
  double worst = 0;
  for (int k = 0; k < 720; ++k) {
    const double th = 2 * std::numbers::pi * k / 720;
    const Vec<2> n(std::cos(th), std::sin(th));
    double h = -1;
    for (std::size_t i = 0; i < seeds.x.size(); ++i)
      h = std::max(h, seeds.x[i].dot(n) + extent(seeds.domain[i], n));
    worst = std::max(worst, std::abs(h - R));
  }
  std::printf("  polar seeding, R = 10 s: largest |support - R| = %.3e s\n", worst / s);
  EXPECT_LT(worst, s * s / R);
}

TEST(PolarSeeding, DegenerateInputsGiveNoPoints) {
  EXPECT_TRUE(points::seed_disk_polar(Vec<2>::Zero(), 0.0, 1e-3).x.empty());
  EXPECT_TRUE(points::seed_disk_polar(Vec<2>::Zero(), 1e-3, 0.0).x.empty());
  EXPECT_TRUE(points::seed_disk_polar(Vec<2>::Zero(), -1.0, 1e-3).x.empty());
}
