// Grain-scale observables on hand-made data (analysis/grains.hpp, docs/observables.md): a grain's
// stress average and invariants, its shape from seeded points (disk, rectangle, ellipse), the
// contact forces per pair, the fabric tensor, the force histogram and the contact stress of a
// packing whose contacts are known.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <vector>

#include "mpmcd/analysis/grains.hpp"
#include "mpmcd/points/seeding.hpp"

using namespace mpmcd;
using namespace mpmcd::analysis;

namespace {

constexpr double kPi = std::numbers::pi;

// Adds the seeds as grain g of `points`, mapped by x -> c + F (x - c) (volumes J V0, domains F D:
// the state of a grain deformed homogeneously by F about c). Domains of lattice seeds are squares
// of half-width spacing/2.
void add_seeds(points::PointSet<2>& points, const points::Seeds<2>& seeds, double spacing, int g,
               const Mat<2>& F = Mat<2>::Identity(), const Vec<2>& c = Vec<2>::Zero()) {
  for (std::size_t i = 0; i < seeds.x.size(); ++i) {
    const Mat<2> dom =
        seeds.domain.empty() ? Mat<2>(0.5 * spacing * Mat<2>::Identity()) : seeds.domain[i];
    points.add(c + F * (seeds.x[i] - c), Vec<2>::Zero(), 1.0, seeds.volume[i], dom, g);
    points.F.back() = F;
    points.volume.back() = F.determinant() * seeds.volume[i];
  }
}

std::vector<points::Grain> one_grain(const points::PointSet<2>& p) {
  points::Grain g;
  g.end = static_cast<std::int64_t>(p.size());
  return {g};
}

// A contact at one grid node: impulse `impulse` of a on b over the step, normal n from a to b.
ContactImpulse node(int a, int b, const Vec<2>& impulse, const Vec<2>& n, const Vec<2>& x) {
  ContactImpulse c;
  c.a = a;
  c.b = b;
  c.impulse = impulse;
  c.normal = n;
  c.normal_impulse = impulse.dot(n);
  c.position = x;
  return c;
}

GrainState at(double x, double y) {
  GrainState g;
  g.centroid = Vec<2>(x, y);
  g.area = 1.0;
  return g;
}

}  // namespace

TEST(GrainStress, VolumeAverageAndInvariants) {
  points::PointSet<2> p;
  const Mat<2> dom = 0.5e-3 * Mat<2>::Identity();
  p.add(Vec<2>(0, 0), Vec<2>::Zero(), 1, 1e-6, dom, 0);
  p.add(Vec<2>(1e-3, 0), Vec<2>::Zero(), 1, 3e-6, dom, 0);
  p.sigma[0] << -4, 2, 2, 0;
  p.sigma[1] << 0, -2, -2, -4;
  p.sigma_zz[0] = 1;
  p.sigma_zz[1] = -3;
  const GrainState g = grain_state(p, 0, 2, nullptr);
  EXPECT_DOUBLE_EQ(g.area, 4e-6);
  EXPECT_DOUBLE_EQ(g.centroid[0], 0.75e-3);  // (0 * 1 + 1e-3 * 3) / 4
  // σ̄ = (1 σ_0 + 3 σ_1) / 4 = [[-1, -1], [-1, -3]], σzz = (1 - 9) / 4 = -2
  EXPECT_DOUBLE_EQ(g.stress(0, 0), -1);
  EXPECT_DOUBLE_EQ(g.stress(0, 1), -1);
  EXPECT_DOUBLE_EQ(g.stress(1, 1), -3);
  EXPECT_DOUBLE_EQ(g.stress_zz, -2);
  EXPECT_DOUBLE_EQ(mean_stress(g.stress), -2);
  // s = [[1, -1], [-1, -1]]: |s| = 2; 3D deviator diag(1, -1, 0) with s_xy = -1: sqrt(1.5 * 4)
  EXPECT_DOUBLE_EQ(deviator_norm(g.stress), 2);
  EXPECT_DOUBLE_EQ(von_mises(g.stress, g.stress_zz), std::sqrt(6.0));
  // Uniaxial stress -1 along x (σyy = σzz = 0): von Mises 1.
  Mat<2> u;
  u << -1, 0, 0, 0;
  EXPECT_NEAR(von_mises(u, 0.0), 1.0, 1e-15);
  // Second moment: two squares of side 1 mm at distance 0.75 and 0.25 mm from the centroid.
  const double side = 1e-3, own = side * side * side * side / 12;  // each square's own moment
  EXPECT_NEAR(g.moment(0, 0), 1e-6 * 0.75e-3 * 0.75e-3 + 3e-6 * 0.25e-3 * 0.25e-3 + 4 * own, 1e-25);
  EXPECT_NEAR(g.moment(1, 1), 4 * own, 1e-25);
}

TEST(GrainShape, SeededDisks) {
  const double r = 1e-3, h = 1e-4;
  for (const int ppc : {2, 4}) {
    const double spacing = h / ppc;
    struct Case {
      const char* name;
      points::Seeds<2> seeds;
    };
    const Case cases[] = {
        {"lattice", points::seed_ball<2>(Vec<2>::Zero(), h, ppc, Vec<2>(2e-3, 2e-3), r)},
        {"polar", points::seed_disk_polar(Vec<2>(2e-3, 2e-3), r, spacing)}};
    for (const auto& c : cases) {
      points::PointSet<2> p;
      add_seeds(p, c.seeds, spacing, 0);
      const auto g = grain_states(p, one_grain(p)).front();
      const double circ = circularity(g.hull_area, g.hull_perimeter);
      std::printf(
          "  %s disk, R/spacing = %.0f: area / pi R^2 - 1 = %.2e, hull area / pi R^2 - 1 = %.2e, "
          "perimeter / 2 pi R - 1 = %.2e, circularity %.5f, aspect ratio %.6f, centroid error "
          "%.1e m\n",
          c.name, r / spacing, g.area / (kPi * r * r) - 1, g.hull_area / (kPi * r * r) - 1,
          g.hull_perimeter / (2 * kPi * r) - 1, circ, aspect_ratio(g.moment),
          (g.centroid - Vec<2>(2e-3, 2e-3)).norm());
      EXPECT_NEAR(g.area / (kPi * r * r), 1.0, 0.01) << c.name;
      EXPECT_LT((g.centroid - Vec<2>(2e-3, 2e-3)).norm(), 1e-9) << c.name;
      // I = π R⁴ / 4 about any axis through the centre.
      EXPECT_NEAR(g.moment(0, 0) / (kPi * r * r * r * r / 4), 1.0, 0.01) << c.name;
      EXPECT_NEAR(aspect_ratio(g.moment), 1.0, 1e-3) << c.name;
      // The hull of the domains' corners circumscribes the disk within a spacing: its perimeter
      // is 2π R (1 + O(spacing/R)). Its circularity is that of a convex polygon, 1 - π²/(3n²)
      // for a regular n-gon: polar seeding's outer domains are tangent to the circle (n = the
      // outer ring's 2 N points: 1 - 2e-4 at R/spacing = 20); a lattice disk's hull has only
      // ~3.45 (R/spacing)^(2/3) vertices (Balog and Bárány 1991), n ≈ 25 at R/spacing = 20,
      // 1 - π²/(3n²) ≈ 0.995: asserted above 0.99 (lattice) and 0.9995 (polar).
      EXPECT_NEAR(g.hull_perimeter / (2 * kPi * r), 1.0, spacing / r) << c.name;
      EXPECT_GT(circ, c.name[0] == 'l' ? 0.99 : 0.9995) << c.name;
      EXPECT_LE(circ, 1.0) << c.name;
    }
  }
}

TEST(GrainShape, RectangleAndEllipse) {
  const double h = 1e-4, spacing = h / 2;
  // A 2 mm x 0.5 mm rectangle on the lattice: I = A diag(L², W²)/12 exactly, aspect L/W = 4,
  // hull = the rectangle (circularity 4π A / (2(L + W))² = π/6.25).
  {
    points::PointSet<2> p;
    add_seeds(p, points::seed_box<2>(Vec<2>::Zero(), h, 2, Vec<2>(0, 0), Vec<2>(2e-3, 0.5e-3)),
              spacing, 0);
    const auto g = grain_states(p, one_grain(p)).front();
    EXPECT_NEAR(g.area, 1e-6, 1e-18);
    EXPECT_NEAR(aspect_ratio(g.moment), 4.0, 1e-9);
    EXPECT_NEAR(principal(g.moment).angle, 0.0, 1e-9);
    EXPECT_NEAR(g.hull_area, 1e-6, 1e-18);
    EXPECT_NEAR(g.hull_perimeter, 5e-3, 1e-15);
    EXPECT_NEAR(circularity(g.hull_area, g.hull_perimeter), kPi / 6.25, 1e-9);
  }
  // A disk of radius 1 mm stretched by F = R(30°) diag(2, 0.5): an ellipse of semi-axes 2 and
  // 0.5 mm at 30°, aspect ratio 4, area π a b.
  {
    const double r = 1e-3, th = kPi / 6;
    Mat<2> rot, F;
    rot << std::cos(th), -std::sin(th), std::sin(th), std::cos(th);
    F = rot * Vec<2>(2.0, 0.5).asDiagonal() * rot.transpose();
    const Vec<2> c(2e-3, 2e-3);
    points::PointSet<2> p;
    add_seeds(p, points::seed_disk_polar(c, r, spacing), spacing, 0, F, c);
    const auto g = grain_states(p, one_grain(p)).front();
    const double a = 2e-3, b = 0.5e-3;
    std::printf(
        "  ellipse 4:1 at 30 deg: aspect ratio %.6f, orientation %.6f deg, area / pi a b - 1 = "
        "%.2e, circularity %.5f\n",
        aspect_ratio(g.moment), principal(g.moment).angle, g.area / (kPi * a * b) - 1,
        circularity(g.hull_area, g.hull_perimeter));
    EXPECT_NEAR(g.area / (kPi * a * b), 1.0, 1e-12);
    EXPECT_NEAR(aspect_ratio(g.moment), 4.0, 4.0 * 0.01);
    EXPECT_NEAR(principal(g.moment).angle, 30.0, 0.1);
  }
}

TEST(Principal, AnglesAndEigenvalues) {
  Mat<2> m;
  m << 1, 0, 0, 3;  // major along y
  auto p = principal(m);
  EXPECT_DOUBLE_EQ(p.major, 3);
  EXPECT_DOUBLE_EQ(p.minor, 1);
  EXPECT_DOUBLE_EQ(p.angle, 90);
  m << 2, 1, 1, 2;  // eigenvalues 3 (along (1, 1)) and 1
  p = principal(m);
  EXPECT_DOUBLE_EQ(p.major, 3);
  EXPECT_DOUBLE_EQ(p.minor, 1);
  EXPECT_DOUBLE_EQ(p.angle, 45);
  m << 2, -1, -1, 2;
  EXPECT_DOUBLE_EQ(principal(m).angle, -45);
}

// Four grains of unit area: 0 at (0, 0), 1 at (0, 2), 2 at (0, 4), 3 at (2, 0), and grain 4 at
// (10, 10) touching nothing. Contacts (dt = 0.5 s, impulses P = f dt):
//   0-1: vertical, f_n = 2, over two nodes (1 + 1), one of them listed as (1, 0);
//   1-2: vertical, f_n = 4, with a tangential force 1;
//   0-3: horizontal, f_n = 6;
//   wall 0 (bottom, normal +y) - grain 0 at y = -1: f_n = 12 over three nodes (4 each);
//   wall 1 (top, normal -y) - grain 2 at y = 5: f_n = 8;
//   2-3: a round-off impulse 1e-9 of the largest: not in contact.
class KnownPacking : public ::testing::Test {
 protected:
  void SetUp() override {
    grains = {at(0, 0), at(0, 2), at(0, 4), at(2, 0), at(10, 10)};
    const double dt2 = dt;
    const Vec<2> up(0, 1), right(1, 0);
    contacts = {
        node(0, 1, 1 * dt2 * up, up, Vec<2>(-0.5, 1)),
        node(1, 0, -1 * dt2 * up, -up, Vec<2>(0.5, 1)),  // the same pair named (1, 0)
        node(1, 2, dt2 * Vec<2>(-1, 4), up, Vec<2>(0, 3)),
        node(0, 3, 6 * dt2 * right, right, Vec<2>(1, 0)),
        node(-1, 0, 4 * dt2 * up, up, Vec<2>(-0.5, -1)),
        node(-1, 0, 4 * dt2 * up, up, Vec<2>(0, -1)),
        node(-1, 0, 4 * dt2 * up, up, Vec<2>(0.5, -1)),
        node(-2, 2, -8 * dt2 * up, -up, Vec<2>(0, 5)),
        node(2, 3, 1.2e-8 * dt2 * Vec<2>(1, -2).normalized(), Vec<2>(1, -2).normalized(),
             Vec<2>(1, 2)),
    };
    pairs = pair_forces(contacts, dt, grains);
  }
  const double dt = 0.5;
  std::vector<GrainState> grains;
  std::vector<ContactImpulse> contacts;
  std::vector<PairForce> pairs;
};

TEST_F(KnownPacking, PairForcesNormalsAndBranches) {
  ASSERT_EQ(pairs.size(), 6u);  // sorted: (-2, 2), (-1, 0), (0, 1), (0, 3), (1, 2), (2, 3)
  const auto& top = pairs[0];
  EXPECT_EQ(top.a, -2);
  EXPECT_EQ(top.b, 2);
  EXPECT_DOUBLE_EQ(top.normal_force, 8);
  EXPECT_DOUBLE_EQ(top.force[1], -8);
  EXPECT_DOUBLE_EQ(top.branch[1], -1);  // from the contact point (0, 5) to (0, 4)
  const auto& bottom = pairs[1];
  EXPECT_EQ(bottom.nodes, 3);
  EXPECT_DOUBLE_EQ(bottom.normal_force, 12);
  EXPECT_DOUBLE_EQ(bottom.point[0], 0.0);
  EXPECT_DOUBLE_EQ(bottom.point[1], -1.0);
  EXPECT_DOUBLE_EQ(bottom.branch[1], 1.0);
  const auto& p01 = pairs[2];
  EXPECT_EQ(p01.a, 0);
  EXPECT_EQ(p01.b, 1);
  EXPECT_EQ(p01.nodes, 2);
  EXPECT_DOUBLE_EQ(p01.normal_force, 2);  // both nodes push 1 from 0 to 1
  EXPECT_DOUBLE_EQ(p01.normal[1], 1);
  EXPECT_DOUBLE_EQ(p01.branch[1], 2);
  const auto& p12 = pairs[4];
  EXPECT_DOUBLE_EQ(p12.normal_force, 4);
  EXPECT_DOUBLE_EQ(p12.tangential_force, 1);  // t = e_z × (0, 1) = (-1, 0)
  EXPECT_TRUE(p12.in_contact);
  EXPECT_FALSE(pairs[5].in_contact);  // 1e-9 of the largest
  // The same pairs as Z: 0-1, 1-2, 0-3 (grain 3 has one contact: a rattler; grain 4 none).
  const auto z = coordination(contacts, 5);
  EXPECT_EQ(z.all_pairs, 3);
  EXPECT_EQ(z.pairs, 2);
  EXPECT_EQ(z.rattlers, 2);
  ASSERT_EQ(z.kept.size(), 5u);
  EXPECT_EQ(z.kept[3], 0);
  EXPECT_EQ(z.kept[4], 0);
}

TEST_F(KnownPacking, FabricTensor) {
  // Every grain pair in contact: two vertical, one horizontal: R = diag(1/3, 2/3), a = 2/3.
  const Fabric all = fabric(pairs);
  EXPECT_EQ(all.contacts, 3);
  EXPECT_DOUBLE_EQ(all.tensor(0, 0), 1.0 / 3);
  EXPECT_DOUBLE_EQ(all.tensor(1, 1), 2.0 / 3);
  EXPECT_DOUBLE_EQ(all.tensor(0, 1), 0.0);
  EXPECT_DOUBLE_EQ(all.anisotropy, 2.0 / 3);
  EXPECT_DOUBLE_EQ(all.angle, 90.0);
  // The network of Z (rattler 3 removed): two vertical contacts, R = diag(0, 1), a = 2.
  const auto z = coordination(contacts, 5);
  const Fabric net = fabric(pairs, z.kept);
  EXPECT_EQ(net.contacts, 2);
  EXPECT_DOUBLE_EQ(net.tensor(1, 1), 1.0);
  EXPECT_DOUBLE_EQ(net.anisotropy, 2.0);
  // An isotropic triangle: normals at 0, 60 and 120 degrees give R = I/2, a = 0.
  std::vector<PairForce> tri(3);
  for (int k = 0; k < 3; ++k) {
    tri[k].a = k;
    tri[k].b = k + 1;
    tri[k].in_contact = true;
    tri[k].normal = Vec<2>(std::cos(k * kPi / 3), std::sin(k * kPi / 3));
  }
  const Fabric iso = fabric(tri);
  EXPECT_NEAR(iso.tensor(0, 0), 0.5, 1e-15);
  EXPECT_NEAR(iso.tensor(0, 1), 0.0, 1e-15);
  EXPECT_NEAR(iso.anisotropy, 0.0, 1e-15);
}

TEST_F(KnownPacking, ForceDistribution) {
  // Normal forces of the grain pairs in contact: 2, 4, 6; <f> = 4; f/<f> = 0.5, 1, 1.5.
  std::vector<double> f;
  for (const auto& p : pairs)
    if (p.in_contact && p.a >= 0) f.push_back(p.normal_force);
  ASSERT_EQ(f.size(), 3u);
  double mean = 0;
  for (double v : f) mean += v / 3;
  for (double& v : f) v /= mean;
  const Histogram h = histogram(f, 4, 0.0, 2.0);  // bins of 0.5: [0, .5) [.5, 1) [1, 1.5) [1.5, 2]
  ASSERT_EQ(h.counts.size(), 4u);
  EXPECT_EQ(h.counts[0], 0);
  EXPECT_EQ(h.counts[1], 1);
  EXPECT_EQ(h.counts[2], 1);
  EXPECT_EQ(h.counts[3], 1);  // 1.5 falls in the last bin
  EXPECT_DOUBLE_EQ(h.density[1], 1.0 / (3 * 0.5));
  EXPECT_DOUBLE_EQ(h.edges[4], 2.0);
  EXPECT_EQ(histogram(f, 2, 0.0, 1.0).outside, 1);  // 1.5 outside [0, 1]
}

TEST_F(KnownPacking, ContactStress) {
  // σ_c = -(1/V) Σ F ⊗ ℓ (symmetric part) with V = 10:
  //   0-1: F = (0, 2), ℓ = (0, 2): yy 4;  1-2: F = (-1, 4), ℓ = (0, 2): xy -2 (sym -1), yy 8;
  //   0-3: F = (6, 0), ℓ = (2, 0): xx 12;  bottom: F = (0, 12), ℓ = (0, 1): yy 12;
  //   top: F = (0, -8), ℓ = (0, -1): yy 8.
  const Mat<2> s = contact_stress(pairs, 10.0);
  EXPECT_DOUBLE_EQ(s(0, 0), -1.2);
  EXPECT_DOUBLE_EQ(s(1, 1), -3.2);
  EXPECT_DOUBLE_EQ(s(0, 1), 0.1);
  EXPECT_DOUBLE_EQ(s(1, 0), 0.1);
  // Mean grain stress: Σ σ̄_g A_g / V.
  std::vector<GrainState> g(2);
  g[0].area = 1;
  g[0].stress << -2, 0, 0, -4;
  g[1].area = 3;
  g[1].stress << -6, 1, 1, 0;
  const Mat<2> m = mean_grain_stress(g, 10.0);
  EXPECT_DOUBLE_EQ(m(0, 0), -2.0);
  EXPECT_DOUBLE_EQ(m(1, 1), -0.4);
  EXPECT_DOUBLE_EQ(m(0, 1), 0.3);
}

// 3D (issue 18): a box grain of 4 x 2 x 1 lattice cubes (side d) under two stresses: its volume,
// centroid and volume-averaged stress, the second moment of a box of half-extents a, b, c
// (V/3 diag(a², b², c²), the lattice terms plus each cube's own moment: exact) and its aspect
// ratio a/c; the 3D invariants.
TEST(GrainState3D, BoxGrainMomentStressAndInvariants) {
  const double d = 1e-3;
  points::PointSet<3> p;
  for (int k = 0; k < 1; ++k)
    for (int j = 0; j < 2; ++j)
      for (int i = 0; i < 4; ++i)
        p.add(Vec<3>((i + 0.5) * d, (j + 0.5) * d, (k + 0.5) * d), Vec<3>::Zero(), 1.0, d * d * d,
              Mat<3>::Identity() * (0.5 * d), 0);
  for (std::size_t q = 0; q < p.size(); ++q)
    p.sigma[q] =
        q < 4 ? Mat<3>(Vec<3>(-1, -2, -3).asDiagonal()) : Mat<3>(Vec<3>(-3, -2, -1).asDiagonal());
  p.sigma[0](0, 2) = p.sigma[0](2, 0) = 4;  // σxz of one point: 4/8 on average
  const std::vector<points::Grain> grains = {points::Grain{0, 8}};
  const auto states = grain_states(p, grains);
  ASSERT_EQ(states.size(), 1u);
  const GrainStateOf<3>& g = states[0];
  EXPECT_DOUBLE_EQ(g.area, 8 * d * d * d);
  EXPECT_NEAR(g.centroid[0], 2 * d, 1e-18);
  EXPECT_NEAR(g.centroid[1], d, 1e-18);
  EXPECT_NEAR(g.centroid[2], 0.5 * d, 1e-18);
  EXPECT_DOUBLE_EQ(g.stress(0, 0), -2);
  EXPECT_DOUBLE_EQ(g.stress(2, 2), -2);
  EXPECT_DOUBLE_EQ(g.stress(0, 2), 0.5);
  const double V = 8 * d * d * d, a = 2 * d, b = d, c = 0.5 * d;
  EXPECT_NEAR(g.moment(0, 0), V / 3 * a * a, 1e-12 * V * a * a);
  EXPECT_NEAR(g.moment(1, 1), V / 3 * b * b, 1e-12 * V * a * a);
  EXPECT_NEAR(g.moment(2, 2), V / 3 * c * c, 1e-12 * V * a * a);
  EXPECT_NEAR(g.moment(0, 1), 0.0, 1e-12 * V * a * a);
  EXPECT_NEAR(aspect_ratio(g.moment), a / c, 1e-9);
  // σ = diag(-2, -2, -2) + 0.5 (e_x⊗e_z + e_z⊗e_x): σ_m = -2, |s| = sqrt(2 · 0.25).
  EXPECT_DOUBLE_EQ(mean_stress(g.stress), -2.0);
  EXPECT_NEAR(deviator_norm(g.stress), std::sqrt(0.5), 1e-15);
}

// 3D pairs: the force of a contact named (b, a) reversed, the tangential force |F - f_n n|; the
// fabric of normals along ±x, ±y, ±z equally (R = I/3, a = 0) and of normals along y only
// (R_1 = 1: a = (5/2)(1 - 0)); the contact stress σ_c = -(1/V) Σ F ⊗ ℓ and the mean grain
// stress in 3D.
TEST(PairForces3D, TangentialForceFabricAndStresses) {
  std::vector<GrainStateOf<3>> g(3);
  g[0].centroid = Vec<3>(0, 0, 0);
  g[1].centroid = Vec<3>(0, 2, 0);
  g[2].centroid = Vec<3>(0, 0, 2);
  for (auto& s : g) s.area = 1;
  std::vector<ContactImpulseOf<3>> c(3);
  const auto set = [&](ContactImpulseOf<3>& ci, int a, int b, const Vec<3>& P, const Vec<3>& n) {
    ci.a = a;
    ci.b = b;
    ci.impulse = P;
    ci.normal = n;
    ci.normal_impulse = P.dot(n);
  };
  set(c[0], 0, 1, Vec<3>(0.3, 2, 0.4), Vec<3>(0, 1, 0));  // 0 on 1
  set(c[1], 2, 0, Vec<3>(0, 0, -3), Vec<3>(0, 0, -1));    // 2 on 0: stored as 0 on 2
  set(c[2], -1, 0, Vec<3>(0, 5, 0), Vec<3>(0, 1, 0));     // wall 0 on grain 0
  c[2].position = Vec<3>(0, -1, 0);
  const auto pairs = pair_forces(c, 0.5, g);  // F = P / 0.5
  ASSERT_EQ(pairs.size(), 3u);
  EXPECT_EQ(pairs[1].a, 0);
  EXPECT_EQ(pairs[1].b, 1);
  EXPECT_DOUBLE_EQ(pairs[1].normal_force, 4.0);
  EXPECT_DOUBLE_EQ(pairs[1].tangential_force, 1.0);  // |(0.6, 0, 0.8)|
  EXPECT_EQ(pairs[2].b, 2);
  EXPECT_DOUBLE_EQ(pairs[2].force[2], 6.0);  // reversed: 0 on 2 along +z
  EXPECT_DOUBLE_EQ(pairs[2].normal[2], 1.0);
  EXPECT_DOUBLE_EQ(pairs[2].tangential_force, 0.0);
  // σ_c = -(1/V) sym Σ F ⊗ ℓ: (0.6, 4, 0.8)⊗(0, 2, 0), (0, 0, 6)⊗(0, 0, 2), wall (0, 10, 0)⊗
  // (0, 1, 0); V = 4.
  const Mat<3> s = contact_stress(pairs, 4.0);
  EXPECT_DOUBLE_EQ(s(1, 1), -(8 + 10) / 4.0);
  EXPECT_DOUBLE_EQ(s(2, 2), -12 / 4.0);
  EXPECT_DOUBLE_EQ(s(0, 1), -0.6 / 4.0);
  EXPECT_DOUBLE_EQ(s(1, 2), -0.8 / 4.0);
  g[0].stress = Mat<3>::Identity();
  g[1].stress = 3 * Mat<3>::Identity();
  EXPECT_DOUBLE_EQ(mean_grain_stress(g, 4.0)(2, 2), 1.0);

  std::vector<PairForceOf<3>> iso(3);
  for (int k = 0; k < 3; ++k) {
    iso[k].a = 0;
    iso[k].b = k + 1;
    iso[k].in_contact = true;
    iso[k].normal = Vec<3>::Unit(k);
  }
  const FabricOf<3> f = fabric(iso);
  EXPECT_EQ(f.contacts, 3);
  EXPECT_NEAR(f.tensor(1, 1), 1.0 / 3, 1e-15);
  EXPECT_NEAR(f.anisotropy, 0.0, 1e-15);
  for (auto& p : iso) p.normal = Vec<3>::UnitY();
  EXPECT_NEAR(fabric(iso).anisotropy, 2.5, 1e-15);
  const std::vector<std::uint8_t> kept = {1, 1, 0, 0};  // only pair 0-1 between kept grains
  EXPECT_EQ(fabric(iso, kept).contacts, 1);
}
