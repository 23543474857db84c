// The grain field's transfers on one grain (p2g, g2p_point: include/mpmcd/mpm/grain_field.hpp),
// for every shape family, with and without the affine P2G, in 2D and 3D, on a jittered, deformed,
// stressed and moving Neo-Hookean disk / ball (deformed_grain.hpp):
// - p2g: partition of unity (sum_I m_I = sum_p m_p), first moment (sum_I m_I x_I = sum_p m_p x_p,
//   which a node put at the wrong place breaks), momentum (sum_I m_I v_I = sum_p m_p v_p) and the
//   internal forces at t^n summing to zero (sum_I f_I^n = sum_p m_p g) over the node box; the
//   grain's field keeps all of it but the round-off masses of the nodes it leaves out; a uniform
//   (linear with the affine P2G) velocity field is transferred exactly;
// - g2p_point: a linear nodal field gives the points its value and gradient (PIC), a uniform
//   change of the nodal velocities is added to theirs (FLIP), a linear nodal increment moves them
//   by its value.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "deformed_grain.hpp"

using namespace mpmcd;
using namespace mpmcd::test_support;

namespace {

template <int Dim, class S1>
void check_p2g(bool affine) {
  SCOPED_TRACE(std::string("Dim ") + std::to_string(Dim) + ", shape " +
               std::to_string(static_cast<int>(kind_of<S1>())) + (affine ? ", affine" : ""));
  Noise noise;
  auto model = deformed_grain<Dim>(noise);
  const auto s = settings_for<Dim, S1>(affine);
  const auto& pts = model.points;
  const points::Grain& gr = model.grains[0];
  const mpm::PrescribedNodes<Dim> free_nodes(model.grid.node_count());
  mpm::GrainField<Dim> w;
  mpm::p2g<S1>(w, model.grid, s, pts, gr, free_nodes);
  ASSERT_EQ(w.failure, "");
  ASSERT_GT(w.m.size(), 0u);
  const std::size_t na = w.m.size();
  double m_p = 0, m_abs_v = 0, mp_max = 0;
  Vec<Dim> mx_p = Vec<Dim>::Zero(), mv_p = Vec<Dim>::Zero(), mg = Vec<Dim>::Zero();
  for (std::int64_t p = gr.begin; p < gr.end; ++p) {
    m_p += pts.mass[p];
    mx_p += pts.mass[p] * pts.x[p];
    mv_p += pts.mass[p] * pts.v[p];
    m_abs_v += pts.mass[p] * pts.v[p].norm();
    mg += pts.mass[p] * s.gravity;
    mp_max = std::max(mp_max, pts.mass[p]);
  }
  // The P2G on the node box: every node a point's support touches.
  double m_box = 0, f_abs = 0, m_out = 0;
  Vec<Dim> mx_box = Vec<Dim>::Zero(), mv_box = Vec<Dim>::Zero(), f_box = Vec<Dim>::Zero();
  Vec<Dim> mv_out = Vec<Dim>::Zero();
  std::size_t left_out = 0;
  for (std::size_t b = 0; b < w.box_m.size(); ++b) {
    IVec<Dim> c;
    auto r = static_cast<std::int64_t>(b);
    for (int d = 0; d < Dim; ++d) {
      c[d] = r % w.box_n[d];
      r /= w.box_n[d];
    }
    m_box += w.box_m[b];
    mx_box += w.box_m[b] * model.grid.node_position(c + w.box_lo);
    mv_box += w.box_mv[b];
    f_box += w.box_f[b] + w.box_fext[b];
    f_abs += (w.box_f[b] + w.box_fext[b]).norm();
    if (w.box_to_active[b] < 0 && w.box_m[b] > 0) {
      ++left_out;
      m_out += w.box_m[b];
      mv_out += w.box_mv[b];
    }
  }
  // Partition of unity: sum_I N_I = 1.
  EXPECT_NEAR(m_box, m_p, 1e-13 * m_p);
  // First moment: sum_I N_I x_I = x_p.
  EXPECT_LT((mx_box - mx_p).norm(), 1e-13 * mx_p.norm());
  // Momentum (with the affine term: sum_I N_I (x_I - x_p) = 0).
  EXPECT_LT((mv_box - mv_p).norm(), 1e-12 * m_abs_v);
  // Internal forces at t^n sum to zero (sum_I grad N_I = 0): only gravity is left.
  EXPECT_LT((f_box - mg).norm(), 1e-12 * f_abs);
  EXPECT_GT(f_abs, 1e3 * mg.norm());  // the stresses are not trivial

  // The grain's field: the box nodes above the round-off mass (1e-13 of the heaviest point's,
  // 1e-6 with CPDI: grain_field.cpp), which keep the rest of the mass and momentum exactly.
  const double m_min = (kind_of<S1>() == grid::ShapeKind::kCpdi ? 1e-6 : 1e-13) * mp_max;
  EXPECT_LE(m_out, static_cast<double>(left_out) * m_min);
  double m_I = 0;
  Vec<Dim> mv_I = Vec<Dim>::Zero();
  for (std::size_t a = 0; a < na; ++a) {
    EXPECT_GT(w.m[a], m_min);
    m_I += w.m[a];
    mv_I += w.m[a] * w.v_p2g[a];
  }
  EXPECT_NEAR(m_I + m_out, m_p, 1e-13 * m_p);
  EXPECT_LT((mv_I + mv_out - mv_p).norm(), 1e-12 * m_abs_v);
  EXPECT_EQ(mpm::field_mass(w), m_I);
  // v^{n+1} starts at v^n, the P2G velocities on free nodes.
  EXPECT_LT((mpm::field_momentum(w) - mv_I).norm(), 1e-14 * m_abs_v);

  // Uniform velocity (and, with the affine P2G, any linear field v0 + G x with L_p = G) is
  // transferred exactly to every active node.
  auto moved = model.points;
  const Vec<Dim> v0 = noise.template vec<Dim>();
  const Mat<Dim> G = affine ? Mat<Dim>(400.0 * noise.template mat<Dim>()) : Mat<Dim>::Zero();
  for (std::int64_t p = gr.begin; p < gr.end; ++p) {
    moved.v[p] = v0 + G * moved.x[p];
    moved.L[p] = G;
  }
  mpm::GrainField<Dim> w2;
  mpm::p2g<S1>(w2, model.grid, s, moved, gr, free_nodes);
  ASSERT_EQ(w2.failure, "");
  double worst = 0, scale = 0;
  for (std::size_t a = 0; a < w2.m.size(); ++a) {
    const Vec<Dim> exact = v0 + G * node_x(w2, model.grid, a);
    worst = std::max(worst, (w2.v_p2g[a] - exact).norm());
    scale = std::max(scale, exact.norm());
  }
  EXPECT_LT(worst, 1e-12 * scale);
}

// Tolerance of a reproduced linear field relative to its scale: round-off, or the weights of the
// CPDI nodes left out for their round-off mass (below 1e-6 of a point's each: grain_field.cpp).
template <class S1>
double reproduction_tolerance() {
  return kind_of<S1>() == grid::ShapeKind::kCpdi ? 1e-5 : 1e-12;
}

template <int Dim, class S1>
void check_g2p() {
  SCOPED_TRACE(std::string("Dim ") + std::to_string(Dim) + ", shape " +
               std::to_string(static_cast<int>(kind_of<S1>())));
  Noise noise;
  auto model = deformed_grain<Dim>(noise);
  const auto s = settings_for<Dim, S1>(false);
  const auto& pts = model.points;
  const points::Grain& gr = model.grains[0];
  mpm::GrainField<Dim> w;
  mpm::p2g<S1>(w, model.grid, s, pts, gr, mpm::PrescribedNodes<Dim>(model.grid.node_count()));
  ASSERT_EQ(w.failure, "");
  const double tol = reproduction_tolerance<S1>();
  // Nodal velocities v0 + G x_I and increments d0 + E x_I; FLIP change dv0 on every node.
  const Vec<Dim> v0 = noise.template vec<Dim>(), d0 = 1e-5 * noise.template vec<Dim>();
  const Vec<Dim> dv0 = noise.template vec<Dim>();
  const Mat<Dim> G = 400.0 * noise.template mat<Dim>(), E = 0.01 * noise.template mat<Dim>();
  for (std::size_t a = 0; a < w.m.size(); ++a) {
    const Vec<Dim> x = node_x(w, model.grid, a);
    w.v[a] = v0 + G * x;
    w.du[a] = d0 + E * x;
  }
  double v_err = 0, g_err = 0, x_err = 0, v_scale = 0, x_scale = 0;
  for (std::int64_t i = 0; i < gr.size(); ++i) {
    const std::int64_t p = gr.begin + i;
    const auto pic = mpm::g2p_point<S1>(w, 0.0, pts, p, i, true);
    v_err = std::max(v_err, (pic.v - (v0 + G * pts.x[p])).norm());
    v_scale = std::max(v_scale, (v0 + G * pts.x[p]).norm());
    g_err = std::max(g_err, (pic.grad_v - G).norm());
    x_err = std::max(x_err, (pic.dx - (d0 + E * pts.x[p])).norm());
    x_scale = std::max(x_scale, (d0 + E * pts.x[p]).norm());
  }
  for (std::size_t a = 0; a < w.m.size(); ++a) w.v[a] = w.v_p2g[a] + dv0;
  double f_err = 0;
  for (std::int64_t i = 0; i < gr.size(); ++i) {
    const std::int64_t p = gr.begin + i;
    const auto flip = mpm::g2p_point<S1>(w, 1.0, pts, p, i, false);
    f_err = std::max(f_err, (flip.v - (pts.v[p] + dv0)).norm());
    EXPECT_TRUE(flip.grad_v.isZero(0.0));
  }
  EXPECT_LT(v_err, tol * v_scale);
  EXPECT_LT(g_err, tol * G.norm());
  EXPECT_LT(x_err, tol * x_scale);
  EXPECT_LT(f_err, tol * dv0.norm());
}

}  // namespace

TEST(GrainP2g, Linear2D) {
  check_p2g<2, grid::Linear1D>(false);
  check_p2g<2, grid::Linear1D>(true);
}
TEST(GrainP2g, UGimp2D) {
  check_p2g<2, grid::UGimp1D>(false);
  check_p2g<2, grid::UGimp1D>(true);
}
TEST(GrainP2g, Cpdi2D) {
  check_p2g<2, grid::Cpdi1D>(false);
  check_p2g<2, grid::Cpdi1D>(true);
}
TEST(GrainP2g, AllFamilies3D) {
  for (bool affine : {false, true}) {
    check_p2g<3, grid::Linear1D>(affine);
    check_p2g<3, grid::UGimp1D>(affine);
    check_p2g<3, grid::Cpdi1D>(affine);
  }
}

TEST(GrainG2p, Linear2D) {
  check_g2p<2, grid::Linear1D>();
}
TEST(GrainG2p, UGimp2D) {
  check_g2p<2, grid::UGimp1D>();
}
TEST(GrainG2p, Cpdi2D) {
  check_g2p<2, grid::Cpdi1D>();
}
TEST(GrainG2p, AllFamilies3D) {
  check_g2p<3, grid::Linear1D>();
  check_g2p<3, grid::UGimp1D>();
  check_g2p<3, grid::Cpdi1D>();
}
