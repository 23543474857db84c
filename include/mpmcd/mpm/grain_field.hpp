#pragma once
/// A grain's own nodal field (multi-field MPM, method.md §1) and the stages of the implicit step
/// on it as free functions (method.md §2): p2g, evaluate (kinematics, law, internal force,
/// residual), assemble_tangent, factorize / prepare_factor, linear_solve, newton_solve, g2p_check
/// and g2p_commit. ImplicitSolver calls them grain by grain; each takes what it reads explicitly,
/// so that a test can run one stage on one grain (tests/unit/mpm).
#include <Eigen/Cholesky>
#include <Eigen/IterativeLinearSolvers>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseLU>
#include <cstdint>
#include <string>
#include <vector>

#include "mpmcd/core/types.hpp"
#include "mpmcd/grid/grid.hpp"
#include "mpmcd/grid/shape.hpp"
#include "mpmcd/materials/law.hpp"
#include "mpmcd/mpm/settings.hpp"
#include "mpmcd/points/point_set.hpp"

namespace mpmcd::mpm {

/// Sparse matrix of a grain's Newton system (column-major, doubles).
using SpMat = Eigen::SparseMatrix<double>;

/// Eigen's SimplicialLDLT with the size of its factor L known after the symbolic analysis, and
/// a numeric factorisation that gathers the permuted matrix P A P^T through a map made once per
/// pattern instead of permuting A (a fresh matrix and two passes) at every factorisation.
class SparseLdlt : public Eigen::SimplicialLDLT<SpMat> {
 public:
  /// Non-zeros of L below the diagonal once analyzePattern has run [-].
  Eigen::Index factor_nonzeros() const { return m_matrix.outerIndexPtr()[m_matrix.outerSize()]; }
  /// The map from the upper triangle of P A P^T to A's stored values, for A's pattern after
  /// analyzePattern(A) (Eigen's AMD ordering P); grains factorised dense do without it.
  void map_pattern(const SpMat& A);
  /// Frees the map (factorize_mapped then permutes A as Eigen's factorize does).
  void clear_map() {
    ap_ = SpMat();
    from_a_ = std::vector<int>();
  }
  /// The numeric LDL^T of A (the pattern given to analyzePattern): with the map, the same
  /// arithmetic as Eigen's factorize(A) on the same permuted matrix, so the same bits; without
  /// it, Eigen's factorize(A).
  void factorize_mapped(const SpMat& A);

 private:
  SpMat ap_;                 ///< upper triangle of P A P^T (Eigen's permuted input)
  std::vector<int> from_a_;  ///< ap_'s k-th value is A.valuePtr()[from_a_[k]] (empty: no map)
};

/// Prescribed velocity components per global grid node, from a list of VelocityBC (later sets
/// override earlier ones).
template <int Dim>
class PrescribedNodes {
 public:
  /// A grid of `node_count` nodes [-], none prescribed.
  explicit PrescribedNodes(std::int64_t node_count) {
    mask_.assign(static_cast<std::size_t>(node_count), 0);
    for (int d = 0; d < Dim; ++d) set_[d].assign(mask_.size(), -1);
  }
  /// Replaces the boundary conditions (clears only the nodes the previous sets named).
  void set(const std::vector<VelocityBC<Dim>>& bcs) {
    for (const auto& old : bcs_)
      for (std::int64_t n : old.nodes) {
        mask_[n] = 0;
        for (int d = 0; d < Dim; ++d) set_[d][n] = -1;
      }
    bcs_ = bcs;
    for (std::size_t s = 0; s < bcs_.size(); ++s)
      for (std::int64_t n : bcs_[s].nodes) {
        mask_[n] |= bcs_[s].mask;
        for (int d = 0; d < Dim; ++d)
          if (bcs_[s].mask & (1u << d)) set_[d][n] = static_cast<std::int32_t>(s);
      }
  }
  /// Prescribed components of global node n (bit d: component d) [-].
  std::uint8_t mask(std::int64_t n) const { return mask_[n]; }
  /// Prescribed component d of the velocity of node n at its position x [m] [m/s].
  double value(std::int64_t n, int d, const Vec<Dim>& x) const {
    return bcs_[set_[d][n]].value(x)[d];
  }

 private:
  std::vector<std::uint8_t> mask_;      // per global node: prescribed components
  std::vector<std::int32_t> set_[Dim];  // per component and global node: the BC set giving it
  std::vector<VelocityBC<Dim>> bcs_;
};

/// The trial state of every point at the current Newton iterate (indexed like PointSet; written
/// by evaluate, committed by g2p_commit and the history swap).
template <int Dim>
struct TrialState {
  std::vector<Mat<Dim>> F;            ///< F^{n+1} = dF F^n [-]
  std::vector<Mat<Dim>> sigma;        ///< Cauchy stress at F^{n+1} [Pa]
  std::vector<Mat<Dim>> dF_inv_T;     ///< dF^-T (grad_{x^{n+1}} N = dF^-T grad_{x^n} N) [-]
  std::vector<double> sigma_zz;       ///< out-of-plane stress (2D plane strain) [Pa]
  std::vector<double> J;              ///< det F^{n+1} [-]
  std::vector<double> history;        ///< law history at F^{n+1} (PointSet::history layout)
  std::vector<Tensor4<Dim>> tangent;  ///< spatial tangent a = c + geometric term [Pa]
  /// Sizes the arrays for `points` and copies their committed history (start of a step).
  void start(const points::PointSet<Dim>& points) {
    const std::size_t np = points.size();
    F.resize(np);
    sigma.resize(np);
    dF_inv_T.resize(np);
    sigma_zz.resize(np);
    J.resize(np);
    tangent.resize(np);
    history = points.history;
  }
};

/// A grain's nodal field and work space: the node box its points touch, the active nodes (mass
/// above round-off) with masses, velocities and forces, the shape functions of its points at x^n,
/// the block-stencil tangent, the Newton matrix and its factorisation, the Newton bookkeeping.
/// Buffers are reused from step to step (no allocation per point once sized).
template <int Dim>
struct GrainField {
  IVec<Dim> box_lo, box_n;                       ///< node box [lo, lo + n) (grid coordinates)
  std::vector<std::int32_t> box_to_active;       ///< box node -> active node (-1: no mass)
  std::vector<std::int32_t> prev_box_to_active;  ///< previous step's, for pattern reuse
  IVec<Dim> prev_box_lo = IVec<Dim>::Zero();     ///< previous step's box origin
  IVec<Dim> prev_box_n = IVec<Dim>::Zero();      ///< previous step's box size
  bool pattern_valid = false;  ///< stencil / sparse pattern / symbolic analysis are built
  std::vector<double> box_m;   ///< scratch P2G mass on the box [kg]
  std::vector<Vec<Dim>> box_mv, box_f, box_fext;  ///< scratch P2G momentum and forces on the box
  std::vector<std::int64_t> node_global;          ///< active node -> global node index
  std::vector<IVec<Dim>> node_box;                ///< active node -> box coordinates
  std::vector<double> m;                          ///< lumped mass m_I [kg]
  std::vector<Vec<Dim>> v_p2g;     ///< v_I^n from P2G (FLIP increment reference) [m/s]
  std::vector<Vec<Dim>> v_n;       ///< v_I^n with boundary values [m/s]
  std::vector<Vec<Dim>> v;         ///< current iterate of v_I^{n+1} [m/s]
  std::vector<Vec<Dim>> f_n;       ///< f_I^n, internal + body force at t^n [N]
  std::vector<Vec<Dim>> f_ext;     ///< body force sum N m_p g [N]
  std::vector<Vec<Dim>> f_int;     ///< internal force at the iterate [N]
  std::vector<Vec<Dim>> f_abs;     ///< sum |V sigma g| at the iterate (residual scale) [N]
  std::vector<Vec<Dim>> R;         ///< residual [N s]
  std::vector<Vec<Dim>> du;        ///< nodal increment dt [(1 - theta) v^n + theta v] [m]
  std::vector<std::uint8_t> mask;  ///< prescribed components per active node
  std::vector<Vec<Dim>> P;         ///< contact impulse on each node over the step [N s]
  std::vector<Vec<Dim>> grad_m;    ///< sum m_p grad N_I(x_p): outward mass gradient [kg/m]
  std::vector<Vec<Dim>> box_gm;    ///< scratch for grad_m on the box [kg/m]
  std::vector<std::int32_t> node_pts_start, node_pts;  ///< active node -> its points (CSR)
  double contact_mass = 0;          ///< contact threshold: mass_fraction * a full cell's mass [kg]
  bool tangent_current = false;     ///< K_blk matches v
  bool factor_current = false;      ///< the factorisation matches v
  bool factor_in_step = false;      ///< a factorisation of this step's Newton matrix exists
  bool project_tangent = false;     ///< this step assembles the projected (PSD) tangent
  std::int64_t projections = 0;     ///< factorisations redone projected in the current step
  std::int64_t shrunk_domains = 0;  ///< points whose CPDI domain was shrunk this step
  std::int64_t factor_count = 0;    ///< factorisations so far (identifies the current one)
  double vel_ref = 0;               ///< velocity scale of the increment test [sqrt(kg) m/s]
  bool evaluated = false;           ///< residual evaluated in the current Newton iteration
  std::vector<IVec<Dim>> pt_first;  ///< per point: first support node (grid coordinates)
  std::vector<std::int32_t> pt_node;     ///< per point x K: active node or -1
  std::vector<double> pt_N;              ///< per point x K: weights at x^n [-]
  std::vector<Vec<Dim>> pt_dN;           ///< per point x K: gradients at x^n [1/m]
  int K = 0;                             ///< support size [-]
  int S = 0;                             ///< stencil size [-]
  int radius = 0;                        ///< stencil radius [nodes]
  std::vector<std::int32_t> pair_slot;   ///< K x K: stencil slot of node b seen from node a
  std::vector<std::int32_t> stencil_nb;  ///< active x S: neighbour active node or -1
  std::vector<Mat<Dim>> K_blk;           ///< active x S: tangent blocks K_ab [N/m]
  /// active x S: blocks added to K_blk at each assembly (the face contacts' normal stiffness,
  /// ImplicitSolver::follow_face_normals; empty: none) [N/m]
  std::vector<Mat<Dim>> follower_K;
  SpMat A;                                ///< Newton matrix M + theta^2 dt^2 K [kg]
  std::vector<std::int64_t> value_index;  ///< (active x S x Dim x Dim) -> A.valuePtr() index
  SparseLdlt ldlt;                        ///< LDL^T factorisation (LinearSolverKind::kLdlt)
  /// kLdlt grains with a dense factor (Settings::dense_fill, decided with the pattern): the
  /// factorisations are LL^T of the dense A, L in chol's lower triangle (its upper one is unused)
  bool dense = false;
  bool factor_dense = false;  ///< the current factorisation is chol's (else ldlt's)
  Eigen::MatrixXd chol;       ///< dense Cholesky factor L of A, lower triangle [sqrt(kg)]
  Eigen::SparseLU<SpMat> lu;  ///< LU factorisation (LinearSolverKind::kLu)
  Eigen::ConjugateGradient<SpMat, Eigen::Lower | Eigen::Upper> cg;  ///< CG (kCg)
  Eigen::VectorXd rhs, sol;  ///< the last Newton system's right-hand side and solution
  // Newton bookkeeping.
  bool converged = false;                 ///< converged in the current step
  bool solved_once = false;               ///< a Newton update was applied in the current step
  int iterations = 0;                     ///< Newton iterations of the current step [-]
  std::int64_t solves = 0;                ///< linear solves in the current step [-]
  std::int64_t factorizations = 0;        ///< factorisations in the current step [-]
  std::int64_t dense_factorizations = 0;  ///< of those, dense LL^T ones [-]
  double cg_work = 0;            ///< CG iterations x matrix non-zeros of the last solve [-]
  double res_norm = 0;           ///< |R| [N s]
  double res_ref = 0;            ///< reference scale of |R| [N s]
  double dv_norm = 0;            ///< |dv|_M of the last update [sqrt(kg) m/s]
  bool dv_from_contact = false;  ///< that update was the response to an impulse change
  std::vector<double> history;   ///< |R| / reference per iteration [-]
  std::string failure;           ///< why the grain failed ("" if it did not)
  bool retryable = true;         ///< a smaller dt may cure the failure
  std::int64_t fail_point = -1;  ///< point involved in the failure, -1 if none
  /// Energy ledger terms of the step (StepStats): kinetic energy of the points before the step
  /// and after its G2P, and of the grid field at v^n [J].
  double kin_points_n = 0, kin_points = 0, kin_grid_n = 0;
};

/// P2G of a grain at x^n (method.md §1-2), shape family S1: shape functions of its points, node
/// box, m_I = sum N m_p, m_I v_I = sum N m_p v_p (+ N m_p L_p (x_I - x_p) with Settings::affine),
/// f_I^n = -sum V sigma grad N + sum N m_p g, active nodes, prescribed components of v^n and
/// v^{n+1} (v = v^n: the initial guess), contact views (grad m, node -> points) when contact is
/// enabled, stencil and sparse pattern when the active set changed. Resets the Newton
/// bookkeeping; sets `failure` when a point leaves the grid or its CPDI domain does not fit.
template <class S1, int Dim>
void p2g(GrainField<Dim>& w, const grid::Grid<Dim>& grid, const Settings<Dim>& settings,
         const points::PointSet<Dim>& points, const points::Grain& grain,
         const PrescribedNodes<Dim>& prescribed);

/// One Newton evaluation of a grain at its iterate w.v (method.md §2, newton.assemble): du, F, J
/// and dF^-T of its points into `trial`, the law (stress, tangent, history) at F, f_int, the
/// residual R = M (v - v^n) - dt [(1 - theta) f^n + theta f^{n+1}] - P and its scales [s].
template <class S1, int Dim>
void evaluate(GrainField<Dim>& w, TrialState<Dim>& trial, const Settings<Dim>& settings,
              const points::PointSet<Dim>& points, const points::Grain& grain,
              const materials::Law<Dim>& law, double dt);

/// The residual R = M (v - v^n) - dt [(1 - theta) f^n + theta f^{n+1}] - P of the grain's nodes
/// from the forces of the last evaluate and the current impulses P, and its scales (evaluate's
/// last part; again after the impulses change with the same F) [s].
template <int Dim>
void nodal_residual(GrainField<Dim>& w, const Settings<Dim>& settings, double dt);

/// The tangent blocks K_IJ = sum V g_I a g_J at the last evaluate (K = -d f_int / d du; the
/// projected point tangents when w.project_tangent), plus follower_K when it is not empty.
template <class S1, int Dim>
void assemble_tangent(GrainField<Dim>& w, const TrialState<Dim>& trial,
                      const points::PointSet<Dim>& points, const points::Grain& grain);

/// Fills w.A = M + theta^2 dt^2 K (prescribed rows and columns: m_I on the diagonal) from K_blk
/// and factorises it with Settings::linear_solver; false (and `failure`) if that fails [s].
template <int Dim>
bool factorize(GrainField<Dim>& w, const Settings<Dim>& settings, double dt);

/// Assembles (if stale) and factorises the Newton matrix; when the factorisation serves a contact
/// compliance (`compliance`) and its LDL^T is indefinite, redoes it with the projected tangent
/// (docs/accuracy.md). False on a failed factorisation [s].
template <int Dim>
bool prepare_factor(GrainField<Dim>& w, const TrialState<Dim>& trial, const Settings<Dim>& settings,
                    const points::PointSet<Dim>& points, const points::Grain& grain,
                    const materials::Law<Dim>& law, bool compliance, double dt);

/// A^-1 rhs with the current factorisation (NaN when CG does not converge). Instantiated for
/// Eigen::VectorXd and Eigen::MatrixXd::ColXpr.
template <int Dim, class Rhs>
Eigen::VectorXd linear_solve(GrainField<Dim>& w, const Settings<Dim>& settings, const Rhs& rhs);

/// True if the grain solves with its existing factorisation (Settings::modified_newton).
template <int Dim>
bool reuse_factor(const GrainField<Dim>& w, const Settings<Dim>& settings);

/// The Newton update of a grain (newton.solve): (M + theta^2 dt^2 K) dv = -R, v += dv, with the
/// existing factorisation when `reuse`, else prepare_factor's (arguments as there) [s].
template <int Dim>
void newton_solve(GrainField<Dim>& w, const TrialState<Dim>& trial, const Settings<Dim>& settings,
                  const points::PointSet<Dim>& points, const points::Grain& grain,
                  const materials::Law<Dim>& law, bool compliance, double dt, bool reuse);

/// What the G2P gives a point.
template <int Dim>
struct G2pUpdate {
  Vec<Dim> dx;      ///< position increment sum N du [m]
  Vec<Dim> v;       ///< new velocity flip (v_p + sum N (v - v_p2g)) + (1 - flip) sum N v [m/s]
  Mat<Dim> grad_v;  ///< sum v (x) grad_{x^n} N if asked, else zero [1/s]
};

/// G2P of point p, the i-th of its grain (method.md §2), with FLIP fraction `flip` [-].
template <class S1, int Dim>
G2pUpdate<Dim> g2p_point(const GrainField<Dim>& w, double flip, const points::PointSet<Dim>& points,
                         std::int64_t p, std::int64_t i, bool with_grad);

/// Fails the grain (not retryable) if a point's position after the G2P, x + sum N du, puts its
/// shape-function support past the grid's edge; sums the points' kinetic energy after the G2P
/// (w.kin_points).
template <class S1, int Dim>
void g2p_check(GrainField<Dim>& w, const TrialState<Dim>& trial, const grid::Grid<Dim>& grid,
               const Settings<Dim>& settings, const points::PointSet<Dim>& points,
               const points::Grain& grain);

/// Commits the grain's G2P: positions, velocities (and L with Settings::affine), F, stress,
/// volume from `trial` (the history is swapped by the caller).
template <class S1, int Dim>
void g2p_commit(const GrainField<Dim>& w, const TrialState<Dim>& trial,
                const Settings<Dim>& settings, points::PointSet<Dim>& points,
                const points::Grain& grain);

/// Nodal mass sum_I m_I of the field [kg].
template <int Dim>
double field_mass(const GrainField<Dim>& w);

/// Nodal momentum sum_I m_I v_I of the field at the iterate v [kg m/s].
template <int Dim>
Vec<Dim> field_momentum(const GrainField<Dim>& w);

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

}  // namespace mpmcd::mpm

/// M(D, tag) for the tag of each shape-function family that with_shape dispatches to: explicit
/// instantiations of the per-shape stage templates (one line per family).
#define MPMCD_FOR_EACH_SHAPE(M, D) M(D, grid::Linear1D) M(D, grid::UGimp1D) M(D, grid::Cpdi1D)
