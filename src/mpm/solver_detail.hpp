#pragma once
// Private to the mpm module: the per-grain work space of ImplicitSolver (GrainWork) and the
// helpers shared by its source files (docs/architecture.md, "The mpm module's files").
#include <Eigen/IterativeLinearSolvers>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseLU>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "mpmcd/grid/shape.hpp"
#include "mpmcd/mpm/solver.hpp"

namespace mpmcd::mpm {

/// Sparse matrix of a grain's Newton system (column-major, doubles).
using SpMat = Eigen::SparseMatrix<double>;

/// Per-grain work space: the grain's own nodal field on a box of nodes (multi-field, method.md §1),
/// the shape functions of its points at x^n, the block-stencil tangent and its sparse solver.
template <int Dim>
struct ImplicitSolver<Dim>::GrainWork {
  IVec<Dim> box_lo, box_n;                       // node box [lo, lo + n)
  std::vector<std::int32_t> box_to_active;       // box node -> active node (-1: no mass)
  std::vector<std::int32_t> prev_box_to_active;  // previous step's, for pattern reuse
  IVec<Dim> prev_box_lo = IVec<Dim>::Zero(), prev_box_n = IVec<Dim>::Zero();
  bool pattern_valid = false;  // stencil / sparse pattern / symbolic analysis are built
  std::vector<double> box_m;   // scratch P2G accumulators on the box
  std::vector<Vec<Dim>> box_mv, box_f, box_fext;
  std::vector<std::int64_t> node_global;  // active node -> global node index
  std::vector<IVec<Dim>> node_box;        // active node -> box coordinates
  std::vector<double> m;                  // lumped mass m_I [kg]
  std::vector<Vec<Dim>> v_p2g;            // v_I^n from P2G (FLIP increment reference) [m/s]
  std::vector<Vec<Dim>> v_n;              // v_I^n with boundary values [m/s]
  std::vector<Vec<Dim>> v;                // current iterate of v_I^{n+1} [m/s]
  std::vector<Vec<Dim>> f_n, f_ext, f_int, f_abs, R, du;  // f_abs: sum of |V sigma g| (scale)
  std::vector<std::uint8_t> mask;                         // prescribed components
  std::vector<Vec<Dim>> P;       // contact impulse on each node over the step [N s]
  std::vector<Vec<Dim>> grad_m;  // sum m_p grad N_I(x_p): outward mass gradient [kg/m]
  std::vector<Vec<Dim>> box_gm;  // scratch for grad_m on the box
  std::vector<std::int32_t> node_pts_start, node_pts;  // active node -> its points (CSR)
  double contact_mass = 0;          // contact threshold: mass_fraction * a full cell's mass
  std::vector<std::int32_t> slots;  // contact slots of this grain (its compliance group)
  bool lumped_group = false;        // its group's response is M^-1 E (no factorisation)
  Eigen::MatrixXd Z;                // A^-1 E: response of all dofs to unit slot impulses [s/kg]
  bool z_forward = false;           // Z holds Y = L^-1 P E instead (LDL^T: grain_compliance)
  bool tangent_current = false, factor_current = false;  // K_blk / factorisation match v
  bool factor_in_step = false;            // a factorisation of this step's Newton matrix exists
  bool project_tangent = false;           // this step assembles the projected (PSD) tangent
  std::int64_t projections = 0;           // factorisations redone projected in the current step
  std::int64_t shrunk_domains = 0;        // points whose CPDI domain was shrunk this step
  std::int64_t factor_count = 0;          // factorisations so far (identifies the current one)
  std::int64_t z_factor = -1;             // the factorisation Z and G were computed with (-1: none)
  double vel_ref = 0;                     // velocity scale of the increment test [sqrt(kg) m/s]
  bool evaluated = false;                 // residual evaluated in the current Newton iteration
  std::vector<IVec<Dim>> pt_first;        // per point: first support node (box coordinates)
  std::vector<std::int32_t> pt_node;      // per point x K: active node or -1
  std::vector<double> pt_N;               // per point x K: weights at x^n
  std::vector<Vec<Dim>> pt_dN;            // per point x K: gradients at x^n [1/m]
  int K = 0, S = 0, radius = 0;           // support size, stencil size, stencil radius
  std::vector<std::int32_t> pair_slot;    // K x K: stencil slot of node b seen from node a
  std::vector<std::int32_t> stencil_nb;   // active x S: neighbour active node or -1
  std::vector<Mat<Dim>> K_blk;            // active x S: tangent blocks K_ab [N/m]
  SpMat A;                                // Newton matrix M + theta^2 dt^2 K
  std::vector<std::int64_t> value_index;  // (active x S x Dim x Dim) -> A.valuePtr() index
  Eigen::SimplicialLDLT<SpMat> ldlt;
  Eigen::SparseLU<SpMat> lu;
  Eigen::ConjugateGradient<SpMat, Eigen::Lower | Eigen::Upper> cg;
  Eigen::VectorXd rhs, sol;
  // Newton bookkeeping.
  bool converged = false, solved_once = false;
  int iterations = 0;
  std::int64_t solves = 0, factorizations = 0;  // in the current step
  double cg_work = 0;  // CG iterations x matrix non-zeros of the last solve [-]
  double res_norm = 0, res_ref = 0, dv_norm = 0;
  std::vector<double> history;  // |R| / reference per iteration
  std::string failure;
  bool retryable = true;  // a smaller dt may cure the failure
  std::int64_t fail_point = -1;
  // Energy ledger terms of the step (StepStats): kinetic energy of the points before the step and
  // after its G2P, and of the grid field at v^n [J].
  double kin_points_n = 0, kin_points = 0, kin_grid_n = 0;
  // The contact impulses changed the velocities by sqrt(dv2) in the mass norm: iterate again.
  void impulses_changed(double dv2) {
    converged = false;
    solved_once = true;
    dv_norm = std::sqrt(dv2);
  }
};

namespace detail {
/// Calls fn with the tag type of the shape-function family (grid::Linear1D, UGimp1D or Cpdi1D).
template <class Fn>
void with_shape(grid::ShapeKind kind, Fn&& fn) {
  switch (kind) {
    case grid::ShapeKind::kLinear:
      fn(grid::Linear1D{});
      return;
    case grid::ShapeKind::kUGimp:
      fn(grid::UGimp1D{});
      return;
    case grid::ShapeKind::kCpdi:
      fn(grid::Cpdi1D{});
      return;
  }
}

/// Records a Gauss-Seidel outcome in `stats` and returns the sums of the relative impulse change
/// since `old` (the impulses before it), num = sum |P - P_old|^2, den = sum |P|^2 [(N s)^2].
template <int Dim>
std::pair<double, double> impulse_change(const contact::Problem<Dim>& problem,
                                         const std::vector<Vec<Dim>>& old,
                                         const contact::GsResult& r, StepStats& stats) {
  stats.gs_sweeps += r.sweeps;
  stats.gs_error = r.error;
  double num = 0, den = 0;
  for (std::size_t c = 0; c < old.size(); ++c) {
    const auto& ct = problem.contacts[c];
    num += (ct.impulse - old[c]).squaredNorm();
    den += ct.impulse.squaredNorm();
  }
  return {num, den};
}

/// The staggering's relative impulse change sqrt(num / den) from impulse_change's sums, at least 1
/// when Gauss-Seidel did not converge (0 without any change once converged) [-].
inline double relative_change(double num, double den, bool gs_converged) {
  if (num == 0.0) return gs_converged ? 0.0 : 1.0;
  const double change = std::sqrt(num) / std::sqrt(std::max(den, 1e-300));
  return gs_converged ? change : std::max(change, 1.0);
}
}  // namespace detail

}  // namespace mpmcd::mpm

/// M(D, tag) for the tag of each shape-function family that detail::with_shape dispatches to:
/// explicit instantiations of the solver's per-shape member templates (one line per family).
#define MPMCD_FOR_EACH_SHAPE(M, D) M(D, grid::Linear1D) M(D, grid::UGimp1D) M(D, grid::Cpdi1D)
