#pragma once
/// The contact settings of a step (method.md §4, docs/contact.md): where grains meet each other and
/// the walls, the gap criterion, friction, the contact law and its solver. Read by contact
/// detection (contact/detect.hpp) and by the coupling in mpm::ImplicitSolver.
#include <string>
#include <vector>

#include "mpmcd/contact/problem.hpp"
#include "mpmcd/walls/wall.hpp"

namespace mpmcd::contact {

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
  /// With grain_faces: true = each grain-grain face contact's normal is its face's normal at the
  /// Newton iterate's F^{n+1}, updated every iteration, with the symmetric part of its
  /// derivative (the interface pressure's geometric stiffness) in the face grain's Newton matrix;
  /// false = the face's normal at F^n, held through the step (docs/contact.md, "Face normals at
  /// the end of the step").
  bool face_normals_at_end = false;
  GsSettings gs;  ///< Gauss-Seidel tolerance and sweep limit
  /// Solve each contact problem by block principal pivoting on the normal impulses
  /// (solve_active_set, frictionless problems, one MPI rank) instead of Gauss-Seidel.
  bool active_set = false;
  double impulse_tolerance = 1e-6;  ///< relative change of impulses between Newton iterations [-]
  /// Delassus operator: true = each grain's exact compliance at its contact nodes from its
  /// factorised Newton matrix (direct linear solvers), false = lumped 1/m_I.
  bool grain_compliance = true;
};

}  // namespace mpmcd::contact
