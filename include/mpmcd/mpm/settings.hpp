#pragma once
/// The inputs of the implicit step: numerical settings, contact settings (with the rigid walls,
/// walls::Wall) and nodal velocity boundary conditions (read by ImplicitSolver and by the
/// grain-field stages).
#include <cstdint>
#include <string>
#include <vector>

#include "mpmcd/contact/problem.hpp"
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

/// When a grain-grain contact switches on (method.md §4).
enum class GapCriterion {
  kGap,      ///< gap from the points' domains: contact when the materials meet
  kOverlap,  ///< pure support overlap: any node where both fields carry mass (about a cell early)
};

/// Contact Dynamics settings (method.md §4).
template <int Dim>
struct ContactSettings {
  bool enabled = false;                         ///< solve contacts between grains and with walls
  GapCriterion criterion = GapCriterion::kGap;  ///< grain-grain gap criterion
  double mass_fraction =
      1e-4;           ///< a field takes part at a node above this fraction of a cell's mass
  int materials = 1;  ///< number of materials (size of the friction matrix)
  std::vector<double> friction = {
      0.0};                             ///< mu_f per material pair, row-major materials x materials
  std::vector<walls::Wall<Dim>> walls;  ///< rigid walls
  std::string law = "coulomb";  ///< contact law of every contact (contact/law.hpp registry name)
  double wall_range = 1.0;      ///< grain nodes within this many cells of a wall are candidates
  /// Where a wall acts (docs/accuracy.md): false = at grain nodes (the node velocity may not
  /// cross the wall), true = at the faces of the points' domains facing the wall (the velocity
  /// of the face, interpolated from the nodes, may not cross it), which holds the material edge,
  /// not a node beyond it, at the wall. Points within wall_range cells of a wall are candidates.
  bool wall_points = false;
  /// Where grains meet (docs/contact.md): false = at shared grid nodes (the two fields'
  /// velocities at a node, along the mass-gradient normal), true = at the material surface: each
  /// boundary face of either grain's points near the other grain against the other grain's
  /// velocity at the face's corners, along the face's normal. One MPI rank only for now.
  bool grain_faces = false;
  /// With grain_faces: a face is a contact only if its gap g <= gap_horizon 2 V dt, V the step's
  /// largest speed (grain nodes, walls) plus |gravity| dt, i.e. if it could close within
  /// gap_horizon steps; 0: every face within wall_range cells [-].
  double gap_horizon = 4.0;
  contact::GsSettings gs;  ///< Gauss-Seidel tolerance and sweep limit
  /// Solve each contact problem by block principal pivoting on the normal impulses
  /// (contact::solve_active_set; frictionless problems, one MPI rank) instead of Gauss-Seidel.
  bool active_set = false;
  double impulse_tolerance = 1e-6;  ///< relative change of impulses between Newton iterations [-]
  /// Delassus operator: true = each grain's exact compliance at its contact nodes from its
  /// factorised Newton matrix (direct linear solvers), false = lumped 1/m_I.
  bool grain_compliance = true;
};

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
