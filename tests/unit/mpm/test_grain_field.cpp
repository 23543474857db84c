// The grain field's stages on one grain (include/mpmcd/mpm/grain_field.hpp), for every shape
// family, with and without the affine P2G, in 2D and 3D:
// - p2g: partition of unity (sum_I m_I = sum_p m_p), first moment (sum_I m_I x_I = sum_p m_p x_p,
//   which a node put at the wrong place breaks), momentum (sum_I m_I v_I = sum_p m_p v_p) and the
//   internal forces at t^n summing to zero (sum_I f_I^n = sum_p m_p g) over the node box; the
//   grain's field keeps all of it but the round-off masses of the nodes it leaves out; a uniform
//   (linear with the affine P2G) velocity field is transferred exactly;
// - evaluate + assemble_tangent + factorize: the Newton matrix M + theta^2 dt^2 K applied to a
//   perturbation dv of the nodal velocities against the central difference of the residual,
//   R(v + eps dv) - R(v - eps dv), at a deformed, stressed Neo-Hookean state; the error relative
//   to the stiffness part must be small and fall as eps^2.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <type_traits>
#include <vector>

#include "mpmcd/materials/law.hpp"
#include "mpmcd/mpm/grain_field.hpp"
#include "mpmcd/mpm/model.hpp"
#include "mpmcd/points/seeding.hpp"

using namespace mpmcd;

namespace {

template <class S1>
grid::ShapeKind kind_of() {
  if constexpr (std::is_same_v<S1, grid::Linear1D>) return grid::ShapeKind::kLinear;
  if constexpr (std::is_same_v<S1, grid::UGimp1D>) return grid::ShapeKind::kUGimp;
  return grid::ShapeKind::kCpdi;
}

// Uniform deviates in [-1, 1] from a fixed seed.
struct Noise {
  std::mt19937 rng{12345};
  std::uniform_real_distribution<double> u{-1.0, 1.0};
  double operator()() { return u(rng); }
  template <int Dim>
  Vec<Dim> vec() {
    Vec<Dim> x;
    for (int d = 0; d < Dim; ++d) x[d] = u(rng);
    return x;
  }
  template <int Dim>
  Mat<Dim> mat() {
    Mat<Dim> m;
    for (int i = 0; i < Dim; ++i)
      for (int j = 0; j < Dim; ++j) m(i, j) = u(rng);
    return m;
  }
};

constexpr double kH = 1e-3;  // cell size [m]
constexpr int kPpc = 2;      // points per cell and axis

// One Neo-Hookean disk / ball (radius 2.6 h, 2 points per cell and axis, off the grid lines) in
// a deformed, stressed state: positions jittered by 15 % of the spacing, masses varied by 30 %,
// F^n = F0 + 0.03 noise with F0 a shear plus compression, sigma^n = sigma(F^n), V = J V0,
// velocities v_p = v0 + G x + 0.2 noise [m/s], L_p = G + noise [1/s].
template <int Dim>
mpm::Model<Dim> deformed_grain(Noise& noise) {
  mpm::Model<Dim> m;
  m.grid = grid::Grid<Dim>(Vec<Dim>::Zero(), kH, IVec<Dim>::Constant(12));
  m.add_material(materials::make_law<Dim>("neo_hookean", {{"lambda", 3e6}, {"mu", 1.5e6}}), 990.0);
  const Vec<Dim> center = Vec<Dim>::Constant(6.1 * kH) + 0.3 * kH * noise.template vec<Dim>();
  const auto seeds = points::seed_ball<Dim>(m.grid.origin(), kH, kPpc, center, 2.6 * kH);
  m.add_grain(seeds, 0, 0.5 * kH / kPpc, nullptr);
  auto& pts = m.points;
  Mat<Dim> F0 = 0.97 * Mat<Dim>::Identity();
  F0(0, 1) = 0.12;
  F0(Dim - 1, 0) = -0.05;
  const Vec<Dim> v0 = noise.template vec<Dim>();
  const Mat<Dim> G = 300.0 * noise.template mat<Dim>();
  for (std::size_t p = 0; p < pts.size(); ++p) {
    pts.x[p] += 0.15 * (kH / kPpc) * noise.template vec<Dim>();
    pts.mass[p] *= 1.0 + 0.3 * noise();
    pts.F[p] = F0 + 0.03 * noise.template mat<Dim>();
    pts.volume[p] = pts.F[p].determinant() * pts.volume0[p];
    pts.v[p] = v0 + G * (pts.x[p] - center) + 0.2 * noise.template vec<Dim>();
    pts.L[p] = G + 10.0 * noise.template mat<Dim>();
  }
  std::vector<Mat<Dim>> sigma(pts.size());
  std::vector<double> sigma_zz(pts.size());
  materials::LawBatch<Dim> batch{std::span<const Mat<Dim>>(pts.F),
                                 {},
                                 {},
                                 std::span<Mat<Dim>>(sigma),
                                 {},
                                 {},
                                 Dim == 2 ? std::span<double>(sigma_zz) : std::span<double>()};
  m.laws[0]->evaluate(batch);
  for (std::size_t p = 0; p < pts.size(); ++p) {
    pts.sigma[p] = sigma[p];
    pts.sigma_zz[p] = sigma_zz[p];
  }
  return m;
}

template <int Dim, class S1>
mpm::Settings<Dim> settings_for(bool affine) {
  mpm::Settings<Dim> s;
  s.shape = kind_of<S1>();
  s.affine = affine;
  s.gravity = Vec<Dim>::Zero();
  s.gravity[Dim - 1] = -9.81;
  return s;
}

template <int Dim>
Vec<Dim> node_x(const mpm::GrainField<Dim>& w, const grid::Grid<Dim>& grid, std::size_t a) {
  return grid.node_position(w.node_box[a] + w.box_lo);
}

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

// Residual of the grain at nodal velocities v, as one vector [N s].
template <int Dim, class S1>
Eigen::VectorXd residual_at(mpm::GrainField<Dim>& w, mpm::TrialState<Dim>& trial,
                            const mpm::Settings<Dim>& s, const mpm::Model<Dim>& model,
                            const Eigen::VectorXd& v, double dt) {
  const std::size_t na = w.m.size();
  for (std::size_t a = 0; a < na; ++a)
    w.v[a] = v.template segment<Dim>(static_cast<Eigen::Index>(a * Dim));
  mpm::evaluate<S1>(w, trial, s, model.points, model.grains[0], *model.laws[0], dt);
  EXPECT_EQ(w.failure, "");
  Eigen::VectorXd r(static_cast<Eigen::Index>(na * Dim));
  for (std::size_t a = 0; a < na; ++a)
    r.template segment<Dim>(static_cast<Eigen::Index>(a * Dim)) = w.R[a];
  return r;
}

template <int Dim, class S1>
void check_tangent() {
  SCOPED_TRACE(std::string("Dim ") + std::to_string(Dim) + ", shape " +
               std::to_string(static_cast<int>(kind_of<S1>())));
  Noise noise;
  auto model = deformed_grain<Dim>(noise);
  auto s = settings_for<Dim, S1>(false);
  s.theta = 0.6;
  // theta dt c / h = 4.7: the stiffness term theta^2 dt^2 K outweighs M about 20 times.
  const double dt = 1e-4;
  const mpm::PrescribedNodes<Dim> free_nodes(model.grid.node_count());
  mpm::GrainField<Dim> w;
  mpm::TrialState<Dim> trial;
  trial.start(model.points);
  mpm::p2g<S1>(w, model.grid, s, model.points, model.grains[0], free_nodes);
  ASSERT_EQ(w.failure, "");
  const std::size_t na = w.m.size();
  const auto n = static_cast<Eigen::Index>(na * Dim);
  // A non-trivial iterate: v^{n+1} = v^n + 0.3 noise (strain increments of a few per cent).
  Eigen::VectorXd v(n), dv(n), mdv(n);
  for (std::size_t a = 0; a < na; ++a) {
    v.template segment<Dim>(static_cast<Eigen::Index>(a * Dim)) =
        w.v_n[a] + 0.3 * noise.template vec<Dim>();
    const Vec<Dim> d = noise.template vec<Dim>();
    dv.template segment<Dim>(static_cast<Eigen::Index>(a * Dim)) = d;
    mdv.template segment<Dim>(static_cast<Eigen::Index>(a * Dim)) = w.m[a] * d;
  }
  // The Newton matrix at v.
  residual_at<Dim, S1>(w, trial, s, model, v, dt);
  double J_min = 2, J_max = 0;
  for (std::int64_t p = model.grains[0].begin; p < model.grains[0].end; ++p) {
    J_min = std::min(J_min, trial.J[p]);
    J_max = std::max(J_max, trial.J[p]);
  }
  EXPECT_LT(J_min, 0.95);  // a deformed state, not a linearisation about the reference
  mpm::assemble_tangent<S1>(w, trial, model.points, model.grains[0]);
  ASSERT_TRUE(mpm::factorize(w, s, dt)) << w.failure;
  const Eigen::VectorXd Adv = w.A * dv;
  const Eigen::VectorXd Kdv = Adv - mdv;  // theta^2 dt^2 K dv
  ASSERT_GT(Kdv.norm(), 5.0 * mdv.norm());
  std::vector<double> errors;
  for (double eps : {1e-2, 1e-3, 1e-4}) {
    const Eigen::VectorXd rp = residual_at<Dim, S1>(w, trial, s, model, v + eps * dv, dt);
    const Eigen::VectorXd rm = residual_at<Dim, S1>(w, trial, s, model, v - eps * dv, dt);
    const Eigen::VectorXd fd = (rp - rm) / (2 * eps);
    errors.push_back((fd - Adv).norm() / Kdv.norm());
  }
  ::testing::Test::RecordProperty("errors", std::to_string(errors[0]) + " " +
                                                std::to_string(errors[1]) + " " +
                                                std::to_string(errors[2]));
  std::printf("Dim %d, shape %d: relative errors %.3e %.3e %.3e\n", Dim,
              static_cast<int>(kind_of<S1>()), errors[0], errors[1], errors[2]);
  EXPECT_LT(errors[0], 1e-5);
  EXPECT_LT(errors[2], 1e-9);
  // Central differences: the error falls as eps^2 until round-off.
  EXPECT_LT(errors[1], errors[0] / 30);
  EXPECT_LT(errors[2], errors[1] / 30);
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

TEST(GrainTangent, FiniteDifferencesLinear2D) {
  check_tangent<2, grid::Linear1D>();
}
TEST(GrainTangent, FiniteDifferencesUGimp2D) {
  check_tangent<2, grid::UGimp1D>();
}
TEST(GrainTangent, FiniteDifferencesCpdi2D) {
  check_tangent<2, grid::Cpdi1D>();
}
TEST(GrainTangent, FiniteDifferencesAllFamilies3D) {
  check_tangent<3, grid::Linear1D>();
  check_tangent<3, grid::UGimp1D>();
  check_tangent<3, grid::Cpdi1D>();
}
