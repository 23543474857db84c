// One grain's Newton iteration (evaluate, assemble_tangent, factorize, newton_solve:
// include/mpmcd/mpm/grain_field.hpp) for every shape family in 2D and 3D, on a jittered,
// deformed, stressed and moving Neo-Hookean disk / ball (deformed_grain.hpp):
// - the Newton matrix M + theta^2 dt^2 K applied to a perturbation dv of the nodal velocities
//   against the central difference of the residual, R(v + eps dv) - R(v - eps dv): the error
//   relative to the stiffness part must be small and fall as eps^2;
// - Newton's iterations from v = v^n converge quadratically to round-off.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "deformed_grain.hpp"

using namespace mpmcd;
using namespace mpmcd::test_support;

namespace {

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

template <int Dim, class S1>
void check_newton() {
  SCOPED_TRACE(std::string("Dim ") + std::to_string(Dim) + ", shape " +
               std::to_string(static_cast<int>(kind_of<S1>())));
  Noise noise;
  auto model = deformed_grain<Dim>(noise);
  const auto s = settings_for<Dim, S1>(false);
  const double dt = 1e-5;  // theta dt c / h = 0.78
  const points::Grain& gr = model.grains[0];
  mpm::GrainField<Dim> w;
  mpm::TrialState<Dim> trial;
  trial.start(model.points);
  mpm::p2g<S1>(w, model.grid, s, model.points, gr,
               mpm::PrescribedNodes<Dim>(model.grid.node_count()));
  ASSERT_EQ(w.failure, "");
  std::vector<double> rel;
  for (int it = 0; it < 10; ++it) {
    mpm::evaluate<S1>(w, trial, s, model.points, gr, *model.laws[0], dt);
    ASSERT_EQ(w.failure, "");
    rel.push_back(w.res_norm / w.res_ref);
    if (rel.back() < 1e-13) break;
    mpm::newton_solve(w, trial, s, model.points, gr, *model.laws[0], false, dt, false);
    ASSERT_EQ(w.failure, "");
  }
  std::printf("Dim %d, shape %d: |R| / reference", Dim, static_cast<int>(kind_of<S1>()));
  for (double r : rel) std::printf(" %.3e", r);
  std::printf("\n");
  EXPECT_GT(rel.front(), 1e-2);  // far from the answer at v = v^n
  EXPECT_LT(rel.back(), 1e-13);
  EXPECT_LE(rel.size(), 7u);
  // Quadratic: once in the basin (|R| / reference < 1e-2), each iteration squares the error,
  // until round-off.
  for (std::size_t k = 0; k + 1 < rel.size(); ++k)
    if (rel[k] < 1e-2 && rel[k + 1] > 1e-13) {
      EXPECT_LT(rel[k + 1], 10 * rel[k] * rel[k]);
    }
}

}  // namespace

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

TEST(GrainNewton, ConvergesQuadratically2D) {
  check_newton<2, grid::Linear1D>();
  check_newton<2, grid::UGimp1D>();
  check_newton<2, grid::Cpdi1D>();
}
TEST(GrainNewton, ConvergesQuadratically3D) {
  check_newton<3, grid::Linear1D>();
  check_newton<3, grid::UGimp1D>();
  check_newton<3, grid::Cpdi1D>();
}

TEST(ModifiedNewton, RefactorisesOnAStallAboveTheToleranceOnly) {
  // reuse_factor (the modified Newton's rule, docs/contact.md "A converged residual is not a
  // stall"): keep the step's factorisation while the residual (|R| / reference per iteration)
  // halves, or once it is within residual_tolerance; rebuild the tangent on a stall above it.
  mpm::GrainField<2> w;
  mpm::Settings<2> s;
  s.residual_tolerance = 1e-8;
  w.history = {1e-2, 1e-4};
  EXPECT_FALSE(mpm::reuse_factor(w, s));  // no factorisation in this step yet
  w.factor_in_step = true;
  EXPECT_TRUE(mpm::reuse_factor(w, s));  // falling fast
  w.history = {1e-4, 0.6e-4};
  EXPECT_FALSE(mpm::reuse_factor(w, s));  // a stall above the tolerance
  w.history = {3e-10, 3e-10};
  EXPECT_TRUE(mpm::reuse_factor(w, s));  // converged: at its floor, not stalled
  w.history = {1e-12, 1e-9};
  EXPECT_TRUE(mpm::reuse_factor(w, s));  // risen, but still within the tolerance
  w.history = {1e-12, 2e-8};
  EXPECT_FALSE(mpm::reuse_factor(w, s));  // risen above it
  s.modified_newton = false;
  w.history = {3e-10, 3e-10};
  EXPECT_FALSE(mpm::reuse_factor(w, s));  // full Newton: a new tangent every iteration
}
