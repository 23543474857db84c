#pragma once
/// Direct solution of a frictionless contact problem (docs/contact.md, "Active-set solver"): the
/// linear complementarity problem of the normal impulses p_c (P_c = p_c n_c),
///   p >= 0,  w = b + W p >= 0,  p . w = 0,
/// with b_c = n_c . (v_free,B - v_free,A) + g_c / dt the relative normal velocity without impulses
/// and W_cd = n_c . (response of contact c's relative velocity to a unit impulse n_d on contact d)
/// the normal Delassus matrix (method.md §4 without friction), solved by block principal pivoting
/// (Judice & Pires 1994; the primal active-set method finishes when it stalls) with a sparse
/// LDL^T of W on the active set. Unlike Gauss-Seidel its cost does not grow with the
/// conditioning of W: nearly redundant contacts (two grains' faces on one interface) cost nothing
/// more. Redundant ones (W_AA singular) are solved through proximal steps on W + delta I.
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <cstdint>
#include <vector>

#include "mpmcd/contact/problem.hpp"
#include "mpmcd/core/supernodal_llt.hpp"
#include "mpmcd/core/tree_ldlt.hpp"

namespace mpmcd::contact {

/// The frictionless problem's normal quantities.
struct NormalSystem {
  Eigen::VectorXd b;              ///< relative normal velocity without impulses + g/dt [m/s]
  Eigen::SparseMatrix<double> W;  ///< normal Delassus matrix, symmetric [s/kg] (2D: s m/kg)
  Eigen::VectorXd p;              ///< normal impulses of the problem's contacts [N s]
};

/// The normal system of a problem (every contact's friction ignored); without `with_matrix`,
/// only b and p (W left empty). `timers` (may be null) gets its threaded regions' wall time [s].
template <int Dim>
NormalSystem normal_system(const Problem<Dim>& problem, bool with_matrix = true,
                           StageTimers* timers = nullptr);

/// normal_system with W written into `W` (b and p returned, their W left empty), whose storage
/// is reused when it holds enough entries: W of a dense 3D packing is about a gigabyte, and
/// fresh storage would fault its pages in at every assembly.
template <int Dim>
NormalSystem normal_system_into(const Problem<Dim>& problem, Eigen::SparseMatrix<double>& W,
                                StageTimers* timers = nullptr);

/// Column by column as normal_system makes them, W's columns of the contacts that touch a group
/// marked in `stale` (per group: its G changed), written in place into `W`, which must be the
/// problem's W but for those groups (the same contacts, slots and normals); the other columns
/// depend on other groups only and are kept. Returns b and p (its W left empty).
template <int Dim>
NormalSystem refresh_normal_system(const Problem<Dim>& problem, const std::vector<char>& stale,
                                   Eigen::SparseMatrix<double>& W, StageTimers* timers = nullptr);

/// A sparse LDL^T of W_BB + delta I for one base set B of contacts, and what the pivoting's
/// solves on other active sets A near B reuse: A differs from B by the contacts N that entered
/// and R that left, and a solve on A borders the base factorisation with them (a Schur
/// complement of |N| + |R| rows) instead of factorising W_AA + delta I anew.
struct ShiftedFactor {
  double delta = 0;                  ///< the shift delta [s/kg]
  std::vector<std::int32_t> active;  ///< the contacts of B, ascending (empty: nothing factorised)
  Eigen::SparseMatrix<double> Waa;   ///< W restricted to B [s/kg]
  TreeLdlt ldlt;                     ///< LDL^T of Waa + delta I (numeric part on the threads)
  SupernodalLlt llt;                 ///< or its supernodal L L^T (long columns of L)
  bool supernodal = false;           ///< the base is factorised by `llt`, not `ldlt` [-]
  double factor_flops = 0;           ///< sum over L's columns of their count squared [-]
  double factor_nonzeros = 0;        ///< entries of L [-]
  std::vector<std::int32_t> local;   ///< per contact: its index in B, or -1 [-]
  std::vector<std::int32_t> column;  ///< per contact: its column of `solved`, or -1 [-]
  std::vector<std::int32_t> owners;  ///< per column of `solved`: its contact [-]
  /// (W_BB + delta I)^-1 c per contact that entered (c = W_Bn, then [-]) or left (c = e_r, then
  /// [kg/s]) B in a solve since B was factorised.
  Eigen::MatrixXd solved;
};

/// What one solve leaves for the next solve of the same contacts with the same compliances (the
/// Newton iterations of a step between two factorisations of a grain): W and the last
/// factorisation, so that a solve whose active set has not changed assembles and factorises
/// nothing. The caller clears `valid` whenever the contacts or a group's G change.
struct ActiveSetCache {
  bool valid = false;             ///< W and factor describe the problem's current W [-]
  Eigen::SparseMatrix<double> W;  ///< the normal Delassus matrix [s/kg]
  ShiftedFactor factor;           ///< the last factorisation of the pivoting
  /// W was made for the problem's contacts and slots (the caller clears it when they change) [-].
  bool pattern = false;
  /// Since W was made, only the groups marked in `stale` changed their G (compliance_changed):
  /// the next solve makes only their columns again (refresh_normal_system) if the contacts'
  /// normals are still `normals`. Clearing `valid` alone makes W anew [-].
  bool refreshable = false;
  std::vector<char> stale;      ///< per group: its G changed since W was made [-]
  std::vector<double> normals;  ///< the contacts' normals W was made with (Dim per contact) [-]
  /// Marks the groups with changed[g] != 0 as changed: not `valid`, and `refreshable` while W's
  /// pattern holds and the group count is W's.
  void compliance_changed(const std::vector<char>& changed) {
    const bool was_current = valid || refreshable;
    valid = false;
    refreshable = pattern && was_current && stale.size() == changed.size();
    if (!refreshable) return;
    for (std::size_t g = 0; g < changed.size(); ++g) stale[g] = stale[g] || changed[g];
  }
};

/// Solves a problem whose contacts are all frictionless: one Gauss-Seidel sweep from the
/// impulses in `problem` (enough when they are nearly right; skipped when `cache` is valid), then
/// block principal pivoting (above) from the active set it reaches, then checks error(problem)
/// (computed from W) and, if it is above settings.tolerance, continues with Gauss-Seidel sweeps
/// (settings.max_sweeps). A problem with a frictional contact, or whose contact law the pivoting
/// does not solve (ContactLaw::active_set), goes to Gauss-Seidel directly. GsResult::pivots counts
/// the pivoting steps, GsResult::sweeps all Gauss-Seidel sweeps. With a `cache` that is valid, its
/// W and factorisation are used instead of being made again; it is left valid with this solve's.
template <int Dim>
GsResult solve_active_set(Problem<Dim>& problem, const GsSettings& settings,
                          ActiveSetCache* cache = nullptr);

}  // namespace mpmcd::contact
