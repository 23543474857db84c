// Friction in the 3D DEM (issue 18, docs/packing.md eq. 4'): vector tangential springs with a
// Coulomb cap and sphere spins. Two spheres in sliding contact (the tangential force never exceeds
// mu f_n and equals it while sliding), an oblique collision (linear and angular momentum, orbital
// plus spin, conserved to round-off), and frictional packings of 150 spheres.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <vector>

#include "../../../src/packing/dem.hpp"
#include "mpmcd/packing/overlap.hpp"
#include "mpmcd/packing/packing.hpp"

using namespace mpmcd::packing;
using Dem3 = detail::Dem<3>;
using V3 = std::array<double, 3>;

namespace {

V3 cross(const V3& a, const V3& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
double dot(const V3& a, const V3& b) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}
double norm(const V3& a) {
  return std::sqrt(dot(a, a));
}
V3 unit(const V3& a) {
  const double l = norm(a);
  return {a[0] / l, a[1] / l, a[2] / l};
}

V3 pos(const Dem3& dem, std::size_t i) {
  return {dem.x(0)[i], dem.x(1)[i], dem.x(2)[i]};
}
V3 vel(const Dem3& dem, std::size_t i) {
  return {dem.v(0)[i], dem.v(1)[i], dem.v(2)[i]};
}
V3 spin(const Dem3& dem, std::size_t i) {
  return {dem.spin(0)[i], dem.spin(1)[i], dem.spin(2)[i]};
}
V3 force(const Dem3& dem, std::size_t i) {
  return {dem.f(0)[i], dem.f(1)[i], dem.f(2)[i]};
}

// Two spheres with centers xa, xb, reduced radii ra, rb, velocities va, vb and spins wa, wb in a
// box of walls far away; no viscous damping and no drag, friction mu.
Dem3 two_spheres(const V3& xa, const V3& xb, double ra, double rb, const V3& va, const V3& vb,
                 const V3& wa, const V3& wb, double mu, double skin = 0.3) {
  detail::DemSettings s;
  s.friction = mu;
  s.skin = skin;
  s.damping_ratio = 0.0;
  s.global_damping = 0.0;
  Dem3::Coords x, v;
  Dem3::Spins w;
  for (int a = 0; a < 3; ++a) {
    x[a] = {xa[a], xb[a]};
    v[a] = {va[a], vb[a]};
    w[a] = {wa[a], wb[a]};
  }
  Dem3 dem(x, {ra, rb}, {-20, -20, -20, 20, 20, 20}, s);
  dem.set_velocities(v);
  dem.set_spins(w);
  return dem;
}

struct SlidingStats {
  int contact_steps = 0;    // steps that ended with the spheres overlapping
  int at_cap = 0;           // ... with |f_t| = mu f_n (to 1e-12)
  double worst_ratio = 0;   // largest |f_t| / (mu f_n)
  double worst_normal = 0;  // largest |f . n + f_n| / f_n (the normal force is f_n = delta)
  double worst_cos = -1;    // largest cosine between f_t and the slip velocity, while at the cap
  std::vector<V3> ft;       // tangential force on sphere 0 at each contact step
};

// Runs a collision of two unit spheres approaching along n at relative speed 2 vn, their contact
// points slipping at about 2 vt (spins); measures |f_t| against mu f_n at every step (linear law,
// f_n = k_n delta = delta) from the positions and the net force on sphere 0, which is the contact
// force (no walls are touched, no damping).
SlidingStats collide(double vn, double vt, double mu, double skin = 0.3) {
  const V3 n = unit({1.0, 0.3, -0.2});
  const V3 t = unit(cross(n, {0.0, 0.0, 1.0}));
  const V3 b = cross(n, t);
  const V3 xb = {n[0] * 1.001, n[1] * 1.001, n[2] * 1.001};  // just apart (d = 1)
  // The slip comes from the spins: (w_a + w_b) / 2 x n = vt (2 t - 0.05 b) for these spins (a
  // spin about n, the twist, makes no slip); the translation adds a small tangential drift.
  V3 va, vb, wa, wb;
  for (int a = 0; a < 3; ++a) {
    va[a] = vn * n[a] + 0.01 * vt * t[a];
    vb[a] = -va[a];
    wa[a] = vt * (b[a] + 0.2 * t[a] + 0.3 * n[a]);
    wb[a] = vt * (3.0 * b[a] - 0.1 * t[a] - 0.2 * n[a]);
  }
  Dem3 dem = two_spheres({0, 0, 0}, xb, 0.5, 0.5, va, vb, wa, wb, mu, skin);
  const double dt = 0.1 * dem.time_step();
  SlidingStats st;
  for (int k = 0; k < 2000; ++k) {
    dem.md_step(dt);
    const V3 x0 = pos(dem, 0), x1 = pos(dem, 1);
    const V3 dx = {x1[0] - x0[0], x1[1] - x0[1], x1[2] - x0[2]};
    const double d = norm(dx), delta = 1.0 - d;
    if (delta <= 0.0) {
      if (st.contact_steps > 0) break;  // the collision is over
      continue;
    }
    ++st.contact_steps;
    const V3 nn = unit(dx);
    const V3 f = force(dem, 0);
    const double fdn = dot(f, nn);
    const V3 ft = {f[0] - fdn * nn[0], f[1] - fdn * nn[1], f[2] - fdn * nn[2]};
    st.ft.push_back(ft);
    const double fn = delta, ratio = norm(ft) / (mu * fn);
    st.worst_ratio = std::max(st.worst_ratio, ratio);
    st.worst_normal = std::max(st.worst_normal, std::abs(fdn + fn) / fn);
    if (ratio > 1.0 - 1e-12) {
      ++st.at_cap;
      // Slip velocity of the contact point (lever arms r - delta/2, eq. 4'): f_t opposes it.
      const double arm = 0.5 - 0.5 * delta;
      V3 w;
      const V3 w0 = spin(dem, 0), w1 = spin(dem, 1), v0 = vel(dem, 0), v1 = vel(dem, 1);
      for (int a = 0; a < 3; ++a) w[a] = arm * (w0[a] + w1[a]);
      const V3 wxn = cross(w, nn);
      V3 vc;
      for (int a = 0; a < 3; ++a) vc[a] = v0[a] - v1[a] + wxn[a];
      const double vcn = dot(vc, nn);
      for (int a = 0; a < 3; ++a) vc[a] -= vcn * nn[a];
      st.worst_cos = std::max(st.worst_cos, dot(ft, vc) / (norm(ft) * norm(vc)));
    }
  }
  return st;
}

// Total linear momentum sum m v and angular momentum about the origin sum m x x v + I w.
void momenta(const Dem3& dem, V3& p, V3& l) {
  p = {0, 0, 0};
  l = {0, 0, 0};
  for (std::size_t i = 0; i < dem.size(); ++i) {
    const double m = dem.mass(i), inertia = dem.inertia(i);
    const V3 x = pos(dem, i), v = vel(dem, i), w = spin(dem, i);
    const V3 xv = cross(x, v);
    for (int a = 0; a < 3; ++a) {
      p[a] += m * v[a];
      l[a] += m * xv[a] + inertia * w[a];
    }
  }
}

PackingParams frictional_spheres(double phi, double mu, bool periodic) {
  PackingParams p;
  p.dimension = 3;
  p.count = 150;
  p.diameter_min = 0.8e-3;
  p.diameter_max = 1.2e-3;
  p.aspect_ratio = 1.0;
  p.target_phi = phi;
  p.friction = mu;
  p.periodic = periodic;
  p.seed = 42;
  return p;
}

}  // namespace

// Gross sliding: relative tangential speed 50 times the normal one. The tangential force never
// exceeds mu f_n and sits on it while the spheres slide, against the slip; slow slip sticks (the
// spring stays below the cap for most of the contact).
TEST(DemFriction3D, SlidingContactTangentialForceIsCappedAtMuFn) {
  const double mu = 0.5;
  const SlidingStats slide = collide(0.02, 1.0, mu);
  std::printf(
      "  sliding: %d contact steps, %d at |f_t| = mu f_n, max |f_t| / (mu f_n) - 1 = %.2e, "
      "normal force error %.1e, max cos(f_t, v_slip) = %.4f\n",
      slide.contact_steps, slide.at_cap, slide.worst_ratio - 1.0, slide.worst_normal,
      slide.worst_cos);
  ASSERT_GT(slide.contact_steps, 100);
  EXPECT_LE(slide.worst_ratio, 1.0 + 1e-12);
  EXPECT_EQ(slide.at_cap, slide.contact_steps);
  EXPECT_LT(slide.worst_normal, 1e-9);
  EXPECT_LT(slide.worst_cos, -0.99);
  const SlidingStats stick = collide(0.02, 0.001, mu);
  std::printf("  slow slip: %d contact steps, %d at the cap, max |f_t| / (mu f_n) = %.4f\n",
              stick.contact_steps, stick.at_cap, stick.worst_ratio);
  EXPECT_LE(stick.worst_ratio, 1.0 + 1e-12);
  EXPECT_LT(stick.at_cap, stick.contact_steps / 2);
  // With a skin of 1e-4 d the neighbour list is rebuilt every few steps during the contact: the
  // spring is carried over, so the forces are the same to the bit.
  const SlidingStats rebuilt = collide(0.02, 0.001, mu, 1e-4);
  ASSERT_EQ(rebuilt.ft.size(), stick.ft.size());
  for (std::size_t k = 0; k < stick.ft.size(); ++k)
    for (int a = 0; a < 3; ++a) ASSERT_EQ(rebuilt.ft[k][a], stick.ft[k][a]) << "step " << k;
}

// An oblique collision of two spinning spheres of different sizes, away from the origin, without
// damping or drag: velocity Verlet conserves sum m v and sum (m x x v + I w) to round-off because
// the pair forces are opposite and the contact point's lever arms r - delta/2 add up to the
// center distance (eq. 4'). Friction must have acted: the spins change.
TEST(DemFriction3D, ObliqueCollisionConservesMomentumAndAngularMomentum) {
  const V3 xa = {1.3, -0.7, 2.1};
  const V3 n = unit({0.8, 0.5, -0.3});
  const double ra = 0.6, rb = 0.45, d0 = 1.06;  // apart by 0.01
  const V3 xb = {xa[0] + d0 * n[0], xa[1] + d0 * n[1], xa[2] + d0 * n[2]};
  Dem3 dem = two_spheres(xa, xb, ra, rb, {0.05, 0.12, -0.04}, {-0.07, -0.09, 0.03},
                         {0.4, -0.3, 0.2}, {-0.2, 0.5, 0.6}, 0.5);
  V3 p0, l0;
  momenta(dem, p0, l0);
  const V3 w0 = spin(dem, 0);
  double scale_p = 0.0, scale_l = 0.0;  // sums of magnitudes, for relative errors
  for (std::size_t i = 0; i < 2; ++i) {
    scale_p += dem.mass(i) * norm(vel(dem, i));
    scale_l +=
        dem.mass(i) * norm(pos(dem, i)) * norm(vel(dem, i)) + dem.inertia(i) * norm(spin(dem, i));
  }
  const double e0 = dem.kinetic_energy();
  double err_p = 0.0, err_l = 0.0, max_overlap = 0.0;
  int contact_steps = 0;
  for (int k = 0; k < 3000 && !(contact_steps > 0 && dem.max_overlap() == 0.0); ++k) {
    dem.md_step(0.2 * dem.time_step());
    V3 p, l;
    momenta(dem, p, l);
    err_p = std::max(err_p, norm({p[0] - p0[0], p[1] - p0[1], p[2] - p0[2]}) / scale_p);
    err_l = std::max(err_l, norm({l[0] - l0[0], l[1] - l0[1], l[2] - l0[2]}) / scale_l);
    max_overlap = std::max(max_overlap, dem.max_overlap());
    contact_steps += dem.max_overlap() > 0.0;
  }
  const V3 w1 = spin(dem, 0);
  const double dw = norm({w1[0] - w0[0], w1[1] - w0[1], w1[2] - w0[2]}) / norm(w0);
  const double e1 = dem.kinetic_energy();
  std::printf(
      "  oblique collision: %d contact steps, max overlap %.3g d, spin change of sphere 0 %.3f, "
      "kinetic energy %.6f -> %.6f; relative drift: momentum %.1e, angular momentum %.1e\n",
      contact_steps, max_overlap, dw, e0, e1, err_p, err_l);
  ASSERT_GT(contact_steps, 50);
  ASSERT_EQ(dem.max_overlap(), 0.0);  // the spheres have separated
  EXPECT_GT(dw, 0.05);
  EXPECT_LT(e1, e0);  // sliding dissipates
  EXPECT_LT(err_p, 1e-14);
  EXPECT_LT(err_l, 1e-14);
}

// A frictional packing (mu = 0.5, 150 spheres grown between walls to 0.48, just below where they
// jam, relaxed by damped dynamics): the target phi, overlaps below 1e-3 d. Under the same protocol
// in a periodic cell at phi = 0.60 the frictionless spheres relax (they jam near 0.636,
// test_three_d.cpp) while the frictional ones stay jammed with overlaps of a few percent of d:
// friction jams the spheres looser.
TEST(DemFriction3D, FrictionalPackingReachesPhiAndJamsLooserThanFrictionless) {
  PackingReport report;
  const Packing pk = generate_packing(frictional_spheres(0.48, 0.5, false), report);
  std::printf(
      "  mu = 0.5, walls, target 0.48: phi = %.6f, largest overlap %.2e d_mean, %lld DEM "
      "steps, %.2f s\n",
      report.phi, report.max_overlap, static_cast<long long>(report.steps), report.wall_seconds);
  EXPECT_EQ(pk.dimension, 3);
  EXPECT_NEAR(packing_fraction(pk), 0.48, 0.003);
  EXPECT_TRUE(report.relaxed);
  EXPECT_LT(report.max_overlap, 1e-3);
  EXPECT_FALSE(find_sphere_overlap(pk, kOverlapTolerance));

  PackingParams p0 = frictional_spheres(0.60, 0.0, true), p1 = frictional_spheres(0.60, 0.5, true);
  p1.max_relax_steps = 20000;
  PackingReport r0, r1;
  generate_packing(p0, r0);
  generate_packing(p1, r1);
  std::printf(
      "  periodic, phi = 0.60: mu = 0 relaxed %d, overlap %.2e d_mean; mu = 0.5 relaxed %d, "
      "overlap %.2e d_mean after %lld steps\n",
      r0.relaxed, r0.max_overlap, r1.relaxed, r1.max_overlap, static_cast<long long>(r1.steps));
  EXPECT_TRUE(r0.relaxed);
  EXPECT_LT(r0.max_overlap, 1e-4);
  EXPECT_FALSE(r1.relaxed);
  EXPECT_GT(r1.max_overlap, 1e-2);
}
