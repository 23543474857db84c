// DEM packings (docs/packing.md §3-§4): packing fraction, overlaps, reproducibility, jamming.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "mpmcd/core/errors.hpp"
#include "mpmcd/packing/packing.hpp"

using namespace mpmcd::packing;

namespace {

constexpr double kD = 1e-3;  // nominal diameter d [m]

PackingParams paper_params(std::uint64_t seed) {
  PackingParams p;
  p.count = 300;
  p.diameter_min = 0.8 * kD;
  p.diameter_max = 1.2 * kD;
  p.aspect_ratio = 1.0;
  p.target_phi = 0.78;
  p.seed = seed;
  return p;
}

void expect_inside(const Packing& pk, double tol) {
  for (const auto& d : pk.disks) {
    EXPECT_GE(d.x - d.radius, pk.xmin - tol) << "disk " << d.id;
    EXPECT_LE(d.x + d.radius, pk.xmax + tol) << "disk " << d.id;
    EXPECT_GE(d.y - d.radius, pk.ymin - tol) << "disk " << d.id;
    EXPECT_LE(d.y + d.radius, pk.ymax + tol) << "disk " << d.id;
  }
}

bool same(const Packing& a, const Packing& b) {
  if (a.disks.size() != b.disks.size() || a.xmax != b.xmax || a.ymax != b.ymax) return false;
  for (std::size_t i = 0; i < a.disks.size(); ++i)
    if (a.disks[i].x != b.disks[i].x || a.disks[i].y != b.disks[i].y ||
        a.disks[i].radius != b.disks[i].radius)
      return false;
  return true;
}

}  // namespace

TEST(Generate, Grow300DisksReachesPhiWithNegligibleOverlap) {
  PackingReport report;
  const Packing pk = generate_packing(paper_params(42), report);
  std::printf("grow: phi = %.6f, max overlap = %.3e d, %lld steps, %.2f s\n", report.phi,
              report.max_overlap, static_cast<long long>(report.steps), report.wall_seconds);
  ASSERT_EQ(pk.disks.size(), 300u);
  EXPECT_NEAR(packing_fraction(pk), 0.78, 0.003);
  EXPECT_NEAR(report.phi, packing_fraction(pk), 1e-12);
  // Largest overlap, measured independently of the generator, relative to d.
  EXPECT_LT(max_overlap(pk) / kD, 1e-3);
  EXPECT_TRUE(report.relaxed);
  expect_inside(pk, 1e-3 * kD);
  // Without a box the requested diameters are kept.
  for (const auto& d : pk.disks) {
    EXPECT_GE(2.0 * d.radius, 0.8 * kD * (1 - 1e-12));
    EXPECT_LE(2.0 * d.radius, 1.2 * kD * (1 + 1e-12));
  }
  EXPECT_NEAR((pk.xmax - pk.xmin) / (pk.ymax - pk.ymin), 1.0, 1e-12);
  EXPECT_EQ(pk.seed, 42u);
}

TEST(Generate, SameSeedSameOutputOtherSeedOtherOutput) {
  const Packing a = generate_packing(paper_params(7));
  const Packing b = generate_packing(paper_params(7));
  const Packing c = generate_packing(paper_params(8));
  EXPECT_TRUE(same(a, b));
  EXPECT_FALSE(same(a, c));
  EXPECT_NEAR(packing_fraction(c), 0.78, 0.003);
}

TEST(Generate, WallCompressionWithHertzLawInAGivenBox) {
  PackingParams p = paper_params(3);
  p.method = PackingMethod::kWalls;
  p.contact_law = ContactLaw::kHertz;
  p.box = std::array<double, 4>{0.01, 0.02, 0.03, 0.035};  // 20 mm x 15 mm
  PackingReport report;
  const Packing pk = generate_packing(p, report);
  EXPECT_EQ(pk.xmin, 0.01);
  EXPECT_EQ(pk.ymax, 0.035);
  EXPECT_NEAR(packing_fraction(pk), 0.78, 0.003);
  EXPECT_LT(max_overlap(pk) / mean_diameter(pk), 1e-3);
  expect_inside(pk, 1e-3 * kD);
  // The diameters were scaled by one factor: their ratio stays within [0.8, 1.2] / [0.8, 1.2].
  double lo = 1e9, hi = 0.0;
  for (const auto& d : pk.disks) lo = std::min(lo, d.radius), hi = std::max(hi, d.radius);
  EXPECT_LE(hi / lo, 1.5 + 1e-12);
  EXPECT_GT(report.diameter_scale, 0.0);
}

TEST(Generate, ExplicitDiametersWithFrictionAreKept) {
  PackingParams p;
  for (int i = 0; i < 100; ++i) p.diameters.push_back(i % 2 ? 1.4e-3 : 1.0e-3);  // bidisperse
  p.target_phi = 0.70;
  p.friction = 0.3;
  p.aspect_ratio = 2.0;
  PackingReport report;
  const Packing pk = generate_packing(p, report);
  ASSERT_EQ(pk.disks.size(), 100u);
  for (std::size_t i = 0; i < pk.disks.size(); ++i)
    EXPECT_DOUBLE_EQ(2.0 * pk.disks[i].radius, p.diameters[i]);
  EXPECT_NEAR(packing_fraction(pk), 0.70, 1e-9);
  EXPECT_TRUE(report.relaxed);
  EXPECT_LT(report.max_overlap, 1e-3);
  EXPECT_NEAR((pk.xmax - pk.xmin) / (pk.ymax - pk.ymin), 2.0, 1e-12);
}

TEST(Generate, FrictionlessJammingPeriodicIsRandomClosePacking) {
  PackingParams p = paper_params(42);
  p.method = PackingMethod::kJam;
  p.periodic = true;
  PackingReport report;
  const Packing pk = generate_packing(p, report);
  std::printf(
      "jam (periodic, 300 disks): phi_J = %.5f, output phi = %.5f, max overlap = %.3e d, "
      "%.2f s\n",
      report.jamming_phi, report.phi, report.max_overlap, report.wall_seconds);
  EXPECT_TRUE(report.relaxed);
  EXPECT_GE(report.jamming_phi, 0.82);
  EXPECT_LE(report.jamming_phi, 0.87);
  // The output is the loosest jammed state found: just above phi_J, with small overlaps.
  EXPECT_GE(report.phi, report.jamming_phi);
  EXPECT_LT(report.phi - report.jamming_phi, p.jam_phi_tolerance);
  EXPECT_LT(report.max_overlap, 1e-3);
  EXPECT_TRUE(pk.periodic);
}

TEST(Generate, FrictionlessJammingBetweenWallsIsLooserThanBulk) {
  // Walls lower the jamming fraction of 300 disks by a boundary layer about 0.1 d thick over a
  // perimeter of about 68 d (docs/packing.md §7): expect 0.79 - 0.83.
  PackingParams p = paper_params(42);
  p.method = PackingMethod::kJam;
  PackingReport report;
  const Packing pk = generate_packing(p, report);
  std::printf("jam (walls, 300 disks): phi_J = %.5f, max overlap = %.3e d, %.2f s\n",
              report.jamming_phi, report.max_overlap, report.wall_seconds);
  EXPECT_TRUE(report.relaxed);
  EXPECT_GE(report.jamming_phi, 0.79);
  EXPECT_LE(report.jamming_phi, 0.83);
  EXPECT_LT(report.max_overlap, 1e-3);
  // Diameters kept (no box given): the box shrank to the jammed state.
  for (const auto& d : pk.disks) EXPECT_LE(2.0 * d.radius, 1.2 * kD * (1 + 1e-12));
}

TEST(Generate, RejectsInconsistentParameters) {
  PackingParams p = paper_params(1);
  p.target_phi = 0.95;
  EXPECT_THROW(generate_packing(p), mpmcd::InputError);
  p = paper_params(1);
  p.count = kMaxDisks + 1;
  EXPECT_THROW(generate_packing(p), mpmcd::InputError);
  p = paper_params(1);
  p.count = 1;
  p.target_phi = 0.9;  // one disk of 0.9 of a square box area does not fit in it
  p.box = std::array<double, 4>{0.0, 0.0, 1e-3, 1e-3};
  try {
    generate_packing(p);
    FAIL() << "expected InputError";
  } catch (const mpmcd::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("wider than the largest disk"), std::string::npos)
        << e.what();
  }
  p = paper_params(1);
  p.method = PackingMethod::kWalls;
  p.periodic = true;
  EXPECT_THROW(generate_packing(p), mpmcd::InputError);
}
