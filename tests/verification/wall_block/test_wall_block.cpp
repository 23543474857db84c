// A Neo-Hookean block squeezed between four frictionless walls, loaded as users load it (walls
// and contact, points crossing grid lines), against the closed form of method.md §7: it starts
// with the exact homogeneous velocity v_y = -V (y - y0)/H0 (zero acceleration), so F = diag(1, s)
// at every point and every instant, sigma22 = [mu (s^2 - 1) + lambda ln s] / s, the top wall
// force is -sigma22 times the width, and the elastic energy is the work of the top wall (minus
// the backward-Euler dissipation of the right-endpoint rule, O(dt)). docs/accuracy.md says which
// parts of the method each check needs: CPDI domains that follow F, the affine P2G, and walls that
// act on the points' faces. Variants: uniaxial stress (no side walls) and biaxial (the right wall
// moving left too), each against its own closed form.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <initializer_list>
#include <tuple>

#include "../../support/wall_block.hpp"

using namespace mpmcd;

namespace {

using test_support::BlockResult;
using test_support::Squeeze;

// The driver of tests/support/wall_block.hpp in 2D: the block [0.5, 1.5] mm^2, h = 0.1 mm.
BlockResult squeeze(const Squeeze& c) {
  return test_support::squeeze_block<2>(c);
}

}  // namespace

namespace {
// Uniaxial strain between four face walls for each (lambda, s_end, steps): every point's J and
// sigma22 and the top force within 1e-6 of the closed form, and the energy ledger closing.
void check_uniaxial_strain(std::initializer_list<std::tuple<double, double, int>> cases,
                           bool active_set) {
  for (const auto& [lambda, s_end, steps] : cases) {
    const auto r =
        squeeze({.lambda = lambda, .s_end = s_end, .steps = steps, .active_set = active_set});
    ASSERT_TRUE(r.converged) << r.failure;
    EXPECT_EQ(r.retries, 0);
    if (lambda > 0) {
      EXPECT_GT(r.projected, 0);
    }
    EXPECT_LT(r.worst_J, 1e-6);
    EXPECT_LT(r.worst_sigma, 1e-6);
    EXPECT_LT(r.force_error, 1e-6);
    // Backward Euler stores less than the wall work by dF dd / 2 per step (the right-end force
    // times the travel, against the trapezoid): for a force growing smoothly, half of one
    // step's work at the final force in all (0.35-1.1 % here; seen 0.50 of it for each lambda).
    EXPECT_GT(1.0 - r.energy_ratio, 0.4 * r.last_step_work);
    EXPECT_LT(1.0 - r.energy_ratio, 0.6 * r.last_step_work);
    EXPECT_LE(r.energy_ratio, 1.0 + 1e-9);
    // The faces move with the walls: the contacts do the walls' work and dissipate nothing, so
    // the ledger's contact term (StepStats::contact_work) must vanish to round-off.
    EXPECT_LT(std::abs(r.contact_dissipation), 1e-9);
    // The affine transfers carry the linear velocity field exactly: they lose nothing, and the
    // ledger closes on the bulk term (the stress work backward Euler does not store).
    EXPECT_LT(std::abs(r.transfer_dissipation), 1e-9);
    EXPECT_NEAR(
        r.energy_ratio + r.contact_dissipation + r.transfer_dissipation + r.bulk_dissipation, 1.0,
        1e-9);
  }
}
}  // namespace

// Gauss-Seidel (one contact per cell column of each wall). lambda = 3 and 100 MPa: the
// compressive stress makes the Newton matrix indefinite (the geometric term on rotations,
// docs/accuracy.md), which made Gauss-Seidel diverge and the steps fail from s = 0.75 (3 MPa) and
// s = 0.97 (100 MPa); the projected tangent carries them, without a single half step. With one
// contact per column lambda >= 10 MPa still loses the state near s = 0.81 (an alternating mode of
// the surface nodes along the side walls that the column means do not see): 100 MPa is checked to
// s = 0.85 here, and to s = 0.5 with one contact per face in the next test.
TEST(WallBlock, CpdiAffineFaceWallsKeepTheExactState) {
  check_uniaxial_strain(
      {std::tuple{0.0, 0.5, 333}, std::tuple{3e6, 0.5, 333}, std::tuple{1e8, 0.85, 100}}, false);
}

// The active-set solver makes each face of the surface one contact (docs/accuracy.md, "One
// contact per face"): the stiff block keeps the exact state to half its height. Seen: J within
// 3.0e-13 / 1.2e-13 / 3.5e-13 for lambda = 0, 3, 100 MPa, no half step, two solves per step.
TEST(WallBlock, OneContactPerFaceKeepsTheStiffBlockToHalfItsHeight) {
  check_uniaxial_strain(
      {std::tuple{0.0, 0.5, 333}, std::tuple{3e6, 0.5, 333}, std::tuple{1e8, 0.5, 333}}, true);
}

TEST(WallBlock, EachIngredientIsNeeded) {
  // Without any one of the three parts the exact state is lost within s = 0.8 (docs/accuracy.md).
  test_support::expect_each_ingredient_needed({.lambda = 3e6, .s_end = 0.8, .steps = 60}, squeeze);
}

TEST(WallBlock, ModifiedNewtonKeepsTheExactStateWithFewerFactorisations) {
  // Reusing the step's first factorisation (and the contact compliance made from it) changes
  // only the path to the converged state, not the state: the same closed form to the same
  // tolerance, with at most one factorisation per step (the residual never stalls here).
  const int steps = 133;
  const auto full = squeeze({.lambda = 3e6, .s_end = 0.8, .steps = steps});
  const auto modified =
      squeeze({.lambda = 3e6, .s_end = 0.8, .steps = steps, .modified_newton = true});
  ASSERT_TRUE(full.converged) << full.failure;
  ASSERT_TRUE(modified.converged) << modified.failure;
  EXPECT_LT(modified.worst_J, 1e-6);
  EXPECT_LT(modified.worst_sigma, 1e-6);
  EXPECT_LT(modified.force_error, 1e-6);
  EXPECT_NEAR(modified.energy_ratio, full.energy_ratio, 1e-6);
  // One factorisation per step, and a second where the first was indefinite (projected tangent).
  EXPECT_LE(modified.factorizations, steps + modified.projected + modified.retries * 2);
  EXPECT_LE(2 * modified.factorizations, full.factorizations);
}

// Uniaxial stress for each (lambda, s_end, steps) with the block moved sideways by `offset` [m]:
// every point's J within `j_tol` and sigma22 within 1e-3 of the closed form, |sigma11| below
// 1e-3 of |sigma22|, the wall force within 1e-3, and the energy stored as backward Euler allows.
namespace {
void check_uniaxial_stress(std::initializer_list<std::tuple<double, double, int>> cases,
                           double offset, double j_tol, bool active_set = false) {
  for (const auto& [lambda, s_end, steps] : cases) {
    const auto r = squeeze({.lambda = lambda,
                            .s_end = s_end,
                            .steps = steps,
                            .side_walls = false,
                            .offset = offset,
                            .active_set = active_set});
    ASSERT_TRUE(r.converged) << r.failure;
    if (active_set) {
      EXPECT_EQ(r.retries, 0);
    }
    std::printf("  uniaxial stress: max |sigma11| / |sigma22| = %.2e\n", r.worst_sigma11);
    EXPECT_LT(r.worst_J, j_tol);
    EXPECT_LT(r.worst_sigma, 1e-3);
    EXPECT_LT(r.worst_sigma11, 1e-3);
    EXPECT_LT(r.force_error, 1e-3);
    EXPECT_LE(r.energy_ratio, 1.0 + 1e-9);
    EXPECT_GT(r.energy_ratio, 1.0 - 0.6 * r.last_step_work - 1e-3);
  }
}
}  // namespace

// Uniaxial stress (docs/accuracy.md, "Uniaxial stress"): the block at [2.05, 3.05] mm, its free
// sides half a cell inside the grid's columns, widens across the next columns of cells (a = 1.26
// at s = 0.6 for lambda = 3 MPa, 1.41 at s = 0.7 for 100 MPa) and keeps the exact state (seen:
// sigma22 within 1.4e-8 / 1.1e-5 / 6.1e-5 for lambda = 0, 3, 100 MPa; the inertia of the lateral
// motion). Before the face of a wall contact was chosen by its normal, the state was lost two
// steps after the sides entered the next column (s = 0.818 for 3 MPa, 0.905 for 100 MPa): round-off
// shear turned the faces of the end columns into single corners.
TEST(WallBlock, UniaxialStressWithFreeSidesHalfACellInKeepsTheExactState) {
  check_uniaxial_stress(
      {std::tuple{0.0, 0.5, 333}, std::tuple{3e6, 0.6, 266}, std::tuple{1e8, 0.7, 200}}, 5e-5,
      1e-4);
}

// Open with Gauss-Seidel (docs/accuracy.md, "Uniaxial stress"): with the sides on grid lines
// (they enter the next column in the first step) and one contact per cell column, lambda = 0 is
// exact to 7e-10, lambda = 100 MPa within 5.9e-3 in sigma22 at s = 0.5, lambda = 3 MPa is lost
// (after half-step retries). Run it with --gtest_also_run_disabled_tests; the next test holds it
// with one contact per face.
TEST(WallBlock, DISABLED_UniaxialStressWithFreeSidesKeepsTheExactState) {
  // Top and bottom walls only: the block widens to a(s), mu (a^2 - 1) + lambda ln(a s) = 0
  // (a = 1.28 at s = 0.5 for lambda = 3 MPa), its points crossing grid lines sideways while the
  // top and bottom face contacts change cell columns. Inertia of the lateral motion is below 1e-4
  // of the stress here (rho a'' L^2 / mu), so the quasi-static closed form holds to the
  // tolerances below.
  check_uniaxial_stress(
      {std::tuple{0.0, 0.5, 333}, std::tuple{3e6, 0.5, 333}, std::tuple{1e8, 0.5, 333}}, 0.0, 1e-3);
}

// The same with the active-set solver, one contact per face (docs/accuracy.md, "One contact per
// face"). Seen: J within 1.2e-13 / 3.7e-6 / 3.9e-6 for lambda = 0, 3, 100 MPa at s = 0.5 (the
// inertia of the lateral motion), no half step.
TEST(WallBlock, UniaxialStressWithFreeSidesOnGridLinesKeepsTheExactStateWithOneContactPerFace) {
  check_uniaxial_stress(
      {std::tuple{0.0, 0.5, 333}, std::tuple{3e6, 0.5, 333}, std::tuple{1e8, 0.5, 333}}, 0.0, 1e-4,
      true);
}

// Biaxial (docs/accuracy.md, "Biaxial"): four face walls, the top one down at V and the right one
// left at V2, from the exact homogeneous velocity v = (-V2 (x - x_lo)/W0, -V (y - y_lo)/H0): F =
// diag(a, s) at every instant, a = 1 - V2 t/W0, s = 1 - V t/H0, J = a s. After every step, every
// point's J within 1e-3 and sigma11, sigma22 within 1e-3 of max(|sigma11|, |sigma22|); at the end,
// each within 1e-3 of its own closed form, both moving walls' forces (-sigma22 a W0 on the top,
// -sigma11 s H0 on the right) within 1e-3, and the elastic change equal to both walls' work by
// the trapezoid rule within 1e-3 (backward Euler's right-end work exceeds it by half a step's).
namespace {
void check_biaxial(std::initializer_list<std::tuple<double, double, int>> cases, double side_speed,
                   bool active_set = false) {
  for (const auto& [lambda, s_end, steps] : cases) {
    const auto r = squeeze({.lambda = lambda,
                            .s_end = s_end,
                            .steps = steps,
                            .side_speed = side_speed,
                            .active_set = active_set});
    ASSERT_TRUE(r.converged) << r.failure;
    if (active_set) {
      EXPECT_EQ(r.retries, 0);
    }
    EXPECT_EQ(r.lost_at, 1.0);
    EXPECT_LT(r.worst_J, 1e-3);
    EXPECT_LT(r.worst_sigma, 1e-3);
    EXPECT_LT(r.worst_sigma11, 1e-3);
    EXPECT_LT(r.force_error, 1e-3);
    EXPECT_LT(r.side_force_error, 1e-3);
    EXPECT_NEAR(r.trapezoid_ratio, 1.0, 1e-3);
    EXPECT_LE(r.energy_ratio, 1.0 + 1e-9);
    EXPECT_GT(r.energy_ratio, 1.0 - r.last_step_work);
  }
}
}  // namespace

// The right wall at V2 = V/2 (a = 0.75 at s = 0.5): its face crosses the grid lines x = 1.4 and
// 1.3 mm at s = 0.8 and 0.6, the top face y = 1.4 ... 1.0 mm at s = 0.9 ... 0.5. Seen: exact to
// 5e-11 (lambda = 0), 1.6e-5 in sigma22 (3 MPa, s = 0.5), 2.4e-10 (100 MPa, s = 0.85). lambda = 3
// MPa is exact to 2e-9 through s = 0.70 (across x = 1.4 mm at s = 0.8); from s = 0.614, as the
// right face nears x = 1.3 mm and the top face y = 1.1 mm, Newton stalls (relative residual
// 1.1e-7; with 200 iterations it converges to a state where the top-right corner escapes into the
// right wall) and 95 steps are redone as half steps, which keep it within 1.6e-5. That depends on
// the path of the half steps: kept with 320, 330 and 336 steps, lost with 350 (s = 0.523) and 200
// (s = 0.558); the sanitize build gives the same figures as release (docs/accuracy.md, "Biaxial").
// lambda = 100 MPa is lost near s = 0.82 (the DISABLED_ test below). The default suite checks only
// what needs no half step: lambda = 3 MPa to s = 0.62 (before the stall), lambda = 0 to 0.5 and
// 100 MPa to 0.85; the runs that rely on half steps are in the DISABLED_ test.
TEST(WallBlock, BiaxialBetweenTwoMovingFaceWallsKeepsTheExactState) {
  check_biaxial({std::tuple{0.0, 0.5, 333}, std::tuple{3e6, 0.62, 253}, std::tuple{1e8, 0.85, 100}},
                0.2);
}

// Open (docs/accuracy.md, "Biaxial"): the biaxial cases that lose the state, with the same
// Newton and contact tolerances (1e-12) and the same dt as above (333 steps to s = 0.5). Seen:
// - V2 = V/2, lambda = 100 MPa: first half steps at s = 0.841 (Newton stalls at a relative
//   residual of 6e-11), state lost (by 1e-3) at s = 0.820, before the right face reaches its
//   first grid line; at s = 0.5 J is off by 0.79, sigma22 by 105 %, the top force by 95 %, and
//   the elastic change is 0.10 of the walls' work.
// - V2 = V, lambda = 3 MPa: first half steps at s = 0.817 (both faces nearing grid lines), lost at
//   s = 0.685; at s = 0.5 J off by 0.63, sigma22 by 114 %, top force by 47 %, energy 0.52.
// - V2 = V, lambda = 100 MPa: first half steps at s = 0.920 (Newton diverges, residual 5e-3),
//   lost at s = 0.908; at s = 0.5 J off by 0.82, sigma22 by 101 %.
// - Kept only through half steps, whose path decides (above): V2 = V/2, lambda = 3 MPa to s = 0.5
//   (95 half steps, 1.6e-5 in sigma22), and V2 = V, lambda = 0 (8 half steps from s = 0.512 where
//   both faces cross grid lines together, seen 1.3e-6 in J).
// Run it with --gtest_also_run_disabled_tests (8 minutes on one thread: thousands of half steps).
TEST(WallBlock, DISABLED_BiaxialStiffOrWithEqualSpeedsKeepsTheExactState) {
  check_biaxial({std::tuple{3e6, 0.5, 333}}, 0.2);
  check_biaxial({std::tuple{0.0, 0.5, 333}}, 0.4);
  check_biaxial({std::tuple{1e8, 0.5, 333}}, 0.2);
  check_biaxial({std::tuple{3e6, 0.5, 333}, std::tuple{1e8, 0.5, 333}}, 0.4);
}

// The biaxial cases that Gauss-Seidel loses (above), with the active-set solver and one contact
// per face (docs/accuracy.md, "One contact per face"): lambda = 0, 3, 100 MPa to s = 0.5 with the
// right wall at V/2 and at V, no half step. Seen: J within 8.4e-14 / 7.5e-14 / 1.3e-11 (V/2) and
// 8.0e-14 / 7.4e-14 / 7.6e-12 (V).
TEST(WallBlock, BiaxialAtHalfTheSpeedWithOneContactPerFaceKeepsTheExactState) {
  check_biaxial({std::tuple{0.0, 0.5, 333}, std::tuple{3e6, 0.5, 333}, std::tuple{1e8, 0.5, 333}},
                0.2, true);
}

TEST(WallBlock, BiaxialAtEqualSpeedsWithOneContactPerFaceKeepsTheExactState) {
  check_biaxial({std::tuple{0.0, 0.5, 333}, std::tuple{3e6, 0.5, 333}, std::tuple{1e8, 0.5, 333}},
                0.4, true);
}

namespace {
// The two-grain block kept its exact state with no half step, and the contact between the
// grains did the top wall's work on the lower one without dissipating (the ledger closes).
void expect_exact_two_grains(const BlockResult& r, double lambda) {
  ASSERT_TRUE(r.converged) << "lambda " << lambda << ": " << r.failure;
  EXPECT_EQ(r.retries, 0) << "lambda " << lambda;
  EXPECT_LT(r.worst_J, 1e-6) << "lambda " << lambda;
  EXPECT_LT(r.worst_sigma, 1e-6) << "lambda " << lambda;
  EXPECT_LT(r.force_error, 1e-6) << "lambda " << lambda;
  EXPECT_LT(std::abs(r.contact_dissipation), 1e-9) << "lambda " << lambda;
  EXPECT_LE(r.energy_ratio, 1.0 + 1e-9) << "lambda " << lambda;
  EXPECT_GT(r.energy_ratio, 1.0 - r.last_step_work) << "lambda " << lambda;
}
}  // namespace

// The block pushed by a second grain instead of a wall (issue 14): the same block cut at y = 1 mm
// (a grid line) into two grains, the top wall pushing the upper one, the upper one the lower
// through grain-grain contact on the material surface (contact.grain_contact = "faces"). Both keep
// the homogeneous state F = diag(1, s) of the single block: the contact carries sigma22 exactly.
// Seen: J within 2.2e-11 (lambda = 0, s = 0.5), 1.0e-11 (3 MPa, s = 0.76), 5.6e-12 (100 MPa,
// s = 0.95), no half step. The node contact loses it: J off by 0.19 at s = 0.8 (printed).
TEST(WallBlock, PushedByASecondGrainKeepsTheExactState) {
  for (const auto& [lambda, s_end, steps] :
       {std::tuple{0.0, 0.5, 333}, std::tuple{3e6, 0.76, 160}, std::tuple{1e8, 0.95, 33}}) {
    const auto r = squeeze({.lambda = lambda, .s_end = s_end, .steps = steps, .two_grains = true});
    ASSERT_TRUE(r.converged) << r.failure;
    EXPECT_EQ(r.retries, 0);
    EXPECT_LT(r.worst_J, 1e-6);
    EXPECT_LT(r.worst_sigma, 1e-6);
    EXPECT_LT(r.force_error, 1e-6);
    // The contact between the grains does the top wall's work on the lower grain: it dissipates
    // nothing, and the ledger closes as for one block.
    EXPECT_LT(std::abs(r.contact_dissipation), 1e-9);
    EXPECT_LE(r.energy_ratio, 1.0 + 1e-9);
    EXPECT_GT(r.energy_ratio, 1.0 - r.last_step_work);
  }
  const auto nodes = squeeze(
      {.lambda = 3e6, .s_end = 0.8, .steps = 133, .two_grains = true, .grain_faces = false});
  std::printf("  the same with the node contact (lambda = 3 MPa, s = 0.8): %s, J error %.2e\n",
              nodes.converged ? "converged" : nodes.failure.c_str(), nodes.worst_J);
}

// Open (docs/contact.md): the two-grain block further. Both grains' faces on the interface, two
// per cell against one node row, are redundant constraints, and Gauss-Seidel stops converging to
// the 1e-12 tolerance. Seen: lambda = 3 MPa keeps the state to s = 0.5 (J within 1.8e-10) only
// through 26 steps redone as half steps from s = 0.54 (with 300 steps to s = 0.55 instead of 333
// to 0.5 it fails at s = 0.75); lambda = 100 MPa fails at s = 0.90 (first half step at s = 0.92;
// Gauss-Seidel error stuck at 3e-12, and at 1.1e-10 with tolerances 1e-10).
TEST(WallBlock, DISABLED_PushedByASecondGrainToHalfItsHeight) {
  for (const double lambda : {3e6, 1e8}) {
    const auto r = squeeze({.lambda = lambda, .s_end = 0.5, .steps = 333, .two_grains = true});
    ASSERT_TRUE(r.converged) << r.failure;
    EXPECT_EQ(r.retries, 0);
    EXPECT_LT(r.worst_J, 1e-6);
  }
  // With the active-set solver (passes for lambda = 0 and 3 MPa: the test below).
  const auto r =
      squeeze({.lambda = 1e8, .s_end = 0.5, .steps = 333, .two_grains = true, .active_set = true});
  ASSERT_TRUE(r.converged) << r.failure;
  EXPECT_EQ(r.retries, 0);
  EXPECT_LT(r.worst_J, 1e-6);
}

// The same with the active-set contact solver (contact.solver = "active_set"): the redundant
// faces of the interface cost one or two pivoting steps, and the block keeps its exact state to
// half its height. Seen: J within 9.4e-14 (lambda = 0) and 1.6e-13 (3 MPa), sigma22 within
// 3.1e-13 and 6.9e-13, no half step. lambda = 100 MPa still fails (at s = 0.85 to 0.87), in the
// DISABLED_ test above: the staggering reaches 1e-12 in one iteration and then diverges by a
// factor 1.14-1.38 per iteration (MPMCD_TRACE_NEWTON, 2026-11-27), which a loop preconditioned by
// the projected (positive) Newton matrix does only where the exact one is indefinite on the
// motions the closed contacts leave free (docs/accuracy.md, "It is not a stagnation but a
// divergence"). Beneath it, the committed state itself drifts (2026-12-01): from s = 0.93 on, the
// converged steps' error grows about 1.3x per step (7.5e-14 at s = 0.934, 6.8e-11 at 0.886) in a
// mode at the grain-grain interface, at dt / 2 too. So a better solve (monolithic, Anderson-
// accelerated: tried) will not keep the state; the interface's discretisation must change
// (docs/accuracy.md, "The committed state itself is unstable"). The continuum is stable
// (tests/reference/interface_stability.py); the mode is the interface's antisymmetric wrinkle
// (n = 2 across the width), which a dead interface load would release from s = 0.971, and
// holding the face normals at F^{n+1} over a step's iteration removes its growth (to s = 0.5
// with half steps) but loses lambda = 0 near s = 0.56 (docs/accuracy.md, "The continuum is
// stable; the mode is the interface's antisymmetric wrinkle"). With contact.face_normals = "end"
// (normals at the iterate plus their symmetric stiffness) lambda = 100 MPa keeps the state to
// s = 0.8 and fails at s = 0.62 (the test after the next; docs/contact.md).
TEST(WallBlock, PushedByASecondGrainToHalfItsHeightWithTheActiveSetSolver) {
  for (const double lambda : {0.0, 3e6}) {
    const auto r = squeeze(
        {.lambda = lambda, .s_end = 0.5, .steps = 333, .two_grains = true, .active_set = true});
    expect_exact_two_grains(r, lambda);
  }
}

// The same block with the face contacts' normals at the end of the step (contact.face_normals =
// "end": each Newton iteration takes every grain-grain face normal from its face at the iterate's
// F^{n+1}, with the symmetric part of its stiffness in the face grain's Newton matrix;
// docs/contact.md, "Face normals at the end of the step"). lambda = 0 and 3 MPa keep the state
// to half the height as with the start normals; lambda = 100 MPa, which the start normals lose
// from s = 0.886 (first half steps; the DISABLED_ test above), keeps it to s = 0.8 at the same
// dt. Seen: J within 2.7e-12 / 1.5e-13 (lambda = 0, 3 MPa, s = 0.5) and 1.7e-12 (100 MPa, s = 0.8),
// no half step; with the start normals the last case fails at s = 0.866 after 37 half steps from
// s = 0.884 (printed).
TEST(WallBlock, PushedByASecondGrainWithFaceNormalsAtTheEndOfTheStep) {
  for (const auto& [lambda, s_end, steps] :
       {std::tuple{0.0, 0.5, 333}, std::tuple{3e6, 0.5, 333}, std::tuple{1e8, 0.8, 133}}) {
    const auto r = squeeze({.lambda = lambda,
                            .s_end = s_end,
                            .steps = steps,
                            .two_grains = true,
                            .active_set = true,
                            .face_normals_at_end = true});
    expect_exact_two_grains(r, lambda);
  }
  const auto start =
      squeeze({.lambda = 1e8, .s_end = 0.8, .steps = 133, .two_grains = true, .active_set = true});
  std::printf(
      "  the same with the start normals (lambda = 100 MPa, s = 0.8): %s, %d half steps "
      "from s = %.4f, J error %.2e\n",
      start.converged ? "converged" : start.failure.c_str(), start.retries, start.first_retry_at,
      start.run_worst_J);
}
