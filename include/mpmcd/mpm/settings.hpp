#pragma once
/// The inputs of the implicit step: numerical settings, contact settings (contact::ContactSettings,
/// with the rigid walls, walls::Wall) and nodal velocity boundary conditions (read by
/// ImplicitSolver and by the grain-field stages).
#include <cstdint>
#include <string>
#include <vector>

#include "mpmcd/contact/settings.hpp"
#include "mpmcd/core/types.hpp"
#include "mpmcd/grid/shape.hpp"
#include "mpmcd/walls/wall.hpp"

namespace mpmcd::mpm {

/// Linear solver used for each grain's Newton system.
enum class LinearSolverKind {
  kLdlt,  ///< sparse direct LDL^T (Eigen SimplicialLDLT), symmetric tangents
  kLu,    ///< sparse direct LU (Eigen SparseLU), any tangent
  kCg,    ///< Jacobi-preconditioned conjugate gradients (mass-dominated systems, small dt)
};

/// Parses "ldlt" / "lu" / "cg"; throws InputError otherwise.
LinearSolverKind linear_solver_from_string(const std::string& name);

/// The contact settings and gap criterion are the contact module's (contact/settings.hpp).
using contact::ContactSettings;
using contact::GapCriterion;

/// Numerical settings of the implicit step.
template <int Dim>
struct Settings {
  grid::ShapeKind shape = grid::ShapeKind::kLinear;  ///< shape functions
  double theta = 1.0;                                ///< theta in [1/2, 1] (method.md §2) [-]
  int max_iterations = 25;            ///< Newton iterations before the step fails [-]
  double residual_tolerance = 1e-8;   ///< |R| <= tol * (|M v^n| + dt |f|) [-]
  double increment_tolerance = 1e-8;  ///< |dv|_M <= tol * |v|_M (mass norms) [-]
  LinearSolverKind linear_solver = LinearSolverKind::kLdlt;  ///< per-grain linear solver
  double cg_tolerance = 1e-12;                               ///< relative CG residual [-]
  int cg_max_iterations = 1000;                              ///< CG iteration cap [-]
  double flip = 1.0;  ///< FLIP fraction of the G2P velocity update [-]
  /// Affine P2G (APIC, Jiang et al. 2015, with the velocity gradient as the affine matrix, as in
  /// TPIC, Nakamura et al. 2023): m_I v_I = sum N m_p (v_p + L_p (x_I - x_p)), L_p carried by the
  /// points, so that a linear velocity field is transferred exactly whatever the positions.
  bool affine = false;
  /// Modified Newton: factorise the Newton matrix once per step and reuse it (and the contact
  /// compliance computed from it) in the later iterations; refactorised when the residual
  /// stalls. Same converged answer, fewer factorisations (docs/accuracy.md, cost).
  bool modified_newton = true;
  /// With kLdlt, a grain whose sparse factor L fills at least this fraction of its strict lower
  /// triangle (from the symbolic analysis) and whose system has at most dense_max_size unknowns
  /// is factorised dense instead, as LL^T with OpenBLAS's kernels (core/dense_lapack.hpp): the
  /// 3D CPDI grains (fill 0.6-0.7) factorise 4x faster that way; 2D grains at d/8 (fill 0.4)
  /// stay sparse (docs/three_d.md, "Dense grain factorisations"). Off by default (above 1:
  /// never); the 3D examples set 0.5 ([solver] dense_fill): the quick 3D run 168 s against
  /// 219 s with Eigen's SSE2 kernels (2026-11-28) [-].
  double dense_fill = 2.0;
  int dense_max_size = 3000;  ///< largest system factorised dense (n^2 doubles per grain) [-]
  Vec<Dim> gravity = Vec<Dim>::Zero();  ///< body acceleration [m/s^2]
  ContactSettings<Dim> contact;         ///< contact between grains and with walls
};

/// Prescribed velocity components on a set of grid nodes: v(x) = velocity + gradient (x - anchor).
template <int Dim>
struct VelocityBC {
  std::vector<std::int64_t> nodes;       ///< global node indices
  std::uint8_t mask = 0;                 ///< bit d set: component d is prescribed
  Vec<Dim> velocity = Vec<Dim>::Zero();  ///< uniform part [m/s]
  Mat<Dim> gradient = Mat<Dim>::Zero();  ///< velocity gradient [1/s]
  Vec<Dim> anchor = Vec<Dim>::Zero();    ///< point where v = velocity [m]
  /// Prescribed velocity at node position x [m] -> [m/s].
  Vec<Dim> value(const Vec<Dim>& x) const { return velocity + gradient * (x - anchor); }
};

}  // namespace mpmcd::mpm
