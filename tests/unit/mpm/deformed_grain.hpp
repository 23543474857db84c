#pragma once
// A grain for the stage tests of tests/unit/mpm: one Neo-Hookean disk (2D) or ball (3D) in a
// deformed, stressed, moving state, and small helpers.
#include <random>
#include <span>
#include <type_traits>
#include <vector>

#include "mpmcd/materials/law.hpp"
#include "mpmcd/mpm/grain_field.hpp"
#include "mpmcd/mpm/model.hpp"
#include "mpmcd/points/seeding.hpp"

namespace mpmcd::test_support {

/// The ShapeKind of shape family S1.
template <class S1>
grid::ShapeKind kind_of() {
  if constexpr (std::is_same_v<S1, grid::Linear1D>) return grid::ShapeKind::kLinear;
  if constexpr (std::is_same_v<S1, grid::UGimp1D>) return grid::ShapeKind::kUGimp;
  return grid::ShapeKind::kCpdi;
}

/// Uniform deviates in [-1, 1] from a fixed seed.
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

inline constexpr double kH = 1e-3;  ///< cell size [m]
inline constexpr int kPpc = 2;      ///< points per cell and axis [-]

/// One Neo-Hookean disk / ball (radius 2.6 h, 2 points per cell and axis, off the grid lines) in
/// a deformed, stressed state: positions jittered by 15 % of the spacing, masses varied by 30 %,
/// F^n = F0 + 0.03 noise with F0 a shear plus compression, sigma^n = sigma(F^n), V = J V0,
/// velocities v_p = v0 + G x + 0.2 noise [m/s], L_p = G + noise [1/s].
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

/// Settings of shape family S1 with gravity (-9.81 m/s^2 along the last axis).
template <int Dim, class S1>
mpm::Settings<Dim> settings_for(bool affine) {
  mpm::Settings<Dim> s;
  s.shape = kind_of<S1>();
  s.affine = affine;
  s.gravity = Vec<Dim>::Zero();
  s.gravity[Dim - 1] = -9.81;
  return s;
}

/// Position of active node a of field w [m].
template <int Dim>
Vec<Dim> node_x(const mpm::GrainField<Dim>& w, const grid::Grid<Dim>& grid, std::size_t a) {
  return grid.node_position(w.node_box[a] + w.box_lo);
}

}  // namespace mpmcd::test_support
