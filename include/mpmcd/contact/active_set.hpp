#pragma once
/// Direct solution of a frictionless contact problem (docs/contact.md, "Active-set solver"): the
/// linear complementarity problem of the normal impulses p_c (P_c = p_c n_c),
///   p >= 0,  w = b + W p >= 0,  p . w = 0,
/// with b_c = n_c . (v_free,B - v_free,A) + g_c / dt the relative normal velocity without impulses
/// and W_cd = n_c . (response of contact c's relative velocity to a unit impulse n_d on contact d)
/// the normal Delassus matrix (method.md §4 without friction), solved by block principal pivoting
/// (Judice & Pires 1994, with Murty's single-pivot rule as the finite fallback) with a sparse
/// LDL^T of W on the active set. Unlike Gauss-Seidel its cost does not grow with the
/// conditioning of W: nearly redundant contacts (two grains' faces on one interface) cost nothing
/// more. Redundant ones (W_AA singular) are solved through proximal steps on W + delta I.
#include <Eigen/SparseCore>

#include "mpmcd/contact/problem.hpp"

namespace mpmcd::contact {

/// The frictionless problem's normal quantities.
struct NormalSystem {
  Eigen::VectorXd b;              ///< relative normal velocity without impulses + g/dt [m/s]
  Eigen::SparseMatrix<double> W;  ///< normal Delassus matrix, symmetric [s/kg] (2D: s m/kg)
  Eigen::VectorXd p;              ///< normal impulses of the problem's contacts [N s]
};

/// The normal system of a problem (every contact's friction ignored).
template <int Dim>
NormalSystem normal_system(const Problem<Dim>& problem);

/// Solves a problem whose contacts are all frictionless: up to 10 Gauss-Seidel sweeps from the
/// impulses in `problem` (enough when they are nearly right), then block principal pivoting
/// (above) from the active set they reach, then checks error(problem) and, if it is above
/// settings.tolerance, continues with Gauss-Seidel sweeps (settings.max_sweeps). A problem with
/// a frictional contact goes to Gauss-Seidel directly. GsResult::pivots counts the pivoting
/// steps, GsResult::sweeps all Gauss-Seidel sweeps.
template <int Dim>
GsResult solve_active_set(Problem<Dim>& problem, const GsSettings& settings);

}  // namespace mpmcd::contact
