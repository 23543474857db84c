#pragma once
// Drivers shared by the 2D and 3D verification tests: the whole grid moved by a prescribed affine
// velocity field (kinematics), a grain's mean velocity, and the head-on impact of two grains run
// until they separate (contact), each written once for any dimension.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "mpmcd/mpm/model.hpp"
#include "mpmcd/mpm/solver.hpp"

namespace mpmcd::test_support {

// Drives every node with du = (dF - I)(x - c) per step (theta = 1, so v = du / dt), `steps`
// steps of dt [s], with the given shape family, FLIP fraction and affine P2G.
template <int Dim>
void drive_affine(mpm::Model<Dim>& model, grid::ShapeKind shape, const Mat<Dim>& dF,
                  const Vec<Dim>& c, int steps, double dt = 1e-3, double flip = 1.0,
                  bool affine = false) {
  mpm::Settings<Dim> s;
  s.shape = shape;
  s.affine = affine;
  s.theta = 1.0;
  s.flip = flip;
  mpm::ImplicitSolver<Dim> solver(model.grid, s, model.points, model.grains, model.law_ptrs());
  mpm::VelocityBC<Dim> bc;
  bc.nodes.resize(static_cast<std::size_t>(model.grid.node_count()));
  for (std::size_t i = 0; i < bc.nodes.size(); ++i) bc.nodes[i] = static_cast<std::int64_t>(i);
  bc.mask = (1u << Dim) - 1;
  bc.gradient = (dF - Mat<Dim>::Identity()) / dt;
  bc.anchor = c;
  solver.set_boundary_conditions({bc});
  for (int k = 0; k < steps; ++k) {
    auto stats = solver.solve_step(dt);
    ASSERT_TRUE(stats.converged) << stats.failure;
    solver.commit();
  }
}

// Largest deviations of every point from the homogeneous state x = c + F (X - c), F, sigma [Pa]
// (X the points' initial positions [m]): |F_p - F|, |sigma_p - sigma| / |sigma| and |x_p - x| [m].
struct HomogeneousError {
  double F = 0, sigma = 0, x = 0;  ///< [-], [-], [m]
};
template <int Dim>
HomogeneousError homogeneous_error(const mpm::Model<Dim>& model, const std::vector<Vec<Dim>>& X,
                                   const Vec<Dim>& c, const Mat<Dim>& F, const Mat<Dim>& sigma) {
  HomogeneousError e;
  for (std::size_t p = 0; p < model.points.size(); ++p) {
    e.F = std::max(e.F, (model.points.F[p] - F).norm());
    e.sigma = std::max(e.sigma, (model.points.sigma[p] - sigma).norm() / sigma.norm());
    e.x = std::max(e.x, (model.points.x[p] - (c + F * (X[p] - c))).norm());
  }
  return e;
}

// Mean velocity of grain g [m/s].
template <int Dim>
Vec<Dim> grain_velocity(const mpm::Model<Dim>& m, int g) {
  Vec<Dim> p = Vec<Dim>::Zero();
  double mass = 0;
  for (auto i = m.grains[g].begin; i < m.grains[g].end; ++i) {
    p += m.points.mass[i] * m.points.v[i];
    mass += m.points.mass[i];
  }
  return p / mass;
}

// What a head-on impact along x showed.
template <int Dim>
struct Impact {
  int steps = 0;             ///< steps taken until separation (max_steps: did not separate) [-]
  bool touched = false;      ///< a contact was active at some step [-]
  double va = 0, vb = 0;     ///< final mean x velocities of grains 0 and 1 [m/s]
  double worst_p = 0;        ///< largest |momentum - initial| over one grain's momentum [-]
  double min_gap = 1e9;      ///< smallest gap between the grains' domains along x [m]
  double e_max = 0;          ///< largest kinetic + elastic energy seen [J or J/m]
  mpm::Diagnostics<Dim> d0;  ///< diagnostics at the start
  mpm::Diagnostics<Dim> d1;  ///< diagnostics at the end
};

// Runs grains 0 (left, moving +x) and 1 (right, moving -x) with steps of dt [s] until they have
// touched, no contact is active and they move apart, or max_steps; `p_one` [kg m/s] is one
// grain's momentum (the scale of the drift). Material overlap: the right edge of grain 0's point
// domains against the left edge of grain 1's, along x.
template <int Dim>
Impact<Dim> head_on_impact(mpm::Model<Dim>& model, mpm::ImplicitSolver<Dim>& solver, double dt,
                           int max_steps, double p_one) {
  Impact<Dim> r;
  r.d0 = mpm::diagnostics(model);
  int k = 0;
  for (; k < max_steps; ++k) {
    solver.set_time(k * dt);
    auto st = solver.solve_step(dt);
    EXPECT_TRUE(st.converged) << "step " << k << ": " << st.failure;
    if (!st.converged) break;
    solver.commit();
    r.touched = r.touched || st.active_contacts > 0;
    const auto d = mpm::diagnostics(model);
    r.worst_p = std::max(r.worst_p, (d.momentum - r.d0.momentum).norm() / p_one);
    r.e_max = std::max(r.e_max, d.kinetic + d.elastic);
    double right_a = -1e9, left_b = 1e9;
    for (auto i = model.grains[0].begin; i < model.grains[0].end; ++i)
      right_a = std::max(right_a, model.points.x[i][0] + model.grains[0].half_width *
                                                             std::abs(model.points.F[i](0, 0)));
    for (auto i = model.grains[1].begin; i < model.grains[1].end; ++i)
      left_b = std::min(left_b, model.points.x[i][0] -
                                    model.grains[1].half_width * std::abs(model.points.F[i](0, 0)));
    r.min_gap = std::min(r.min_gap, left_b - right_a);
    if (r.touched && st.active_contacts == 0 && grain_velocity(model, 0)[0] < 0 &&
        grain_velocity(model, 1)[0] > 0)
      break;
  }
  r.steps = k;
  r.d1 = mpm::diagnostics(model);
  r.va = grain_velocity(model, 0)[0];
  r.vb = grain_velocity(model, 1)[0];
  return r;
}

// The head-on impact's checks: the grains touched and separated within max_steps, moving apart,
// the total momentum kept to round-off (1e-12 of one grain's), no material interpenetration
// beyond half a cell h [m], and no energy created.
template <int Dim>
void expect_clean_separation(const Impact<Dim>& r, double h, int max_steps) {
  EXPECT_TRUE(r.touched);
  EXPECT_LT(r.steps, max_steps) << "the grains did not separate";
  EXPECT_LT(r.va, 0.0);
  EXPECT_GT(r.vb, 0.0);
  EXPECT_LT(r.worst_p, 1e-12);
  EXPECT_GT(r.min_gap, -0.5 * h) << "interpenetration beyond half a cell";
  EXPECT_LE(r.d1.kinetic + r.d1.elastic, r.e_max * (1 + 1e-9));
}

}  // namespace mpmcd::test_support
