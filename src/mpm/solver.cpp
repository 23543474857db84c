#include "mpmcd/mpm/solver.hpp"

#include <fmt/format.h>

#include <Eigen/IterativeLinearSolvers>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseLU>
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <tuple>

#include "mpmcd/core/errors.hpp"

namespace mpmcd::mpm {

LinearSolverKind linear_solver_from_string(const std::string& name) {
  if (name == "ldlt") return LinearSolverKind::kLdlt;
  if (name == "lu") return LinearSolverKind::kLu;
  if (name == "cg") return LinearSolverKind::kCg;
  throw InputError("", 0, "solver.linear_solver",
                   "expected \"ldlt\", \"lu\" or \"cg\", got \"" + name + "\"");
}

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
};

template <int Dim>
ImplicitSolver<Dim>::ImplicitSolver(const grid::Grid<Dim>& grid, const Settings<Dim>& settings,
                                    points::PointSet<Dim>& points,
                                    const std::vector<points::Grain>& grains,
                                    std::vector<const materials::Law<Dim>*> laws)
    : grid_(grid), settings_(settings), points_(points), grains_(grains), laws_(std::move(laws)) {
  bc_mask_.assign(static_cast<std::size_t>(grid_.node_count()), 0);
  for (int d = 0; d < Dim; ++d) bc_set_[d].assign(bc_mask_.size(), -1);
}

template <int Dim>
ImplicitSolver<Dim>::~ImplicitSolver() = default;

template <int Dim>
void ImplicitSolver<Dim>::set_boundary_conditions(const std::vector<VelocityBC<Dim>>& bcs) {
  // Clear only the nodes set before (moving node sets are replaced every step).
  for (const auto& old : bcs_)
    for (std::int64_t n : old.nodes) {
      bc_mask_[n] = 0;
      for (int d = 0; d < Dim; ++d) bc_set_[d][n] = -1;
    }
  bcs_ = bcs;
  for (std::size_t s = 0; s < bcs_.size(); ++s)
    for (std::int64_t n : bcs_[s].nodes) {
      bc_mask_[n] |= bcs_[s].mask;
      for (int d = 0; d < Dim; ++d)
        if (bcs_[s].mask & (1u << d)) bc_set_[d][n] = static_cast<std::int32_t>(s);
    }
}

namespace {
// Calls fn with the tag type of the shape-function family (grid::Linear1D, UGimp1D or Cpdi1D).
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

template <class T>
void reset(std::vector<T>& v, std::size_t n, const T& value) {
  v.assign(n, value);
}
}  // namespace

template <int Dim>
template <class S1>
void ImplicitSolver<Dim>::setup_grain(std::size_t g, double dt) {
  using Shape = typename grid::ShapeOf<Dim, S1>::type;
  constexpr int K = Shape::K;
  GrainWork& w = *work_[g];
  const points::Grain& gr = grains_[g];
  const std::int64_t np = gr.size();
  const double h = grid_.cell_size();
  w.K = K;
  w.converged = false;
  w.solved_once = false;
  w.iterations = 0;
  w.solves = 0;
  w.factorizations = 0;
  w.failure.clear();
  w.retryable = true;
  w.fail_point = -1;
  w.history.clear();
  w.factor_in_step = false;
  w.z_factor = -1;
  w.pt_first.resize(np);
  w.pt_N.resize(np * K);
  w.pt_dN.resize(np * K);
  w.pt_node.resize(np * K);
  // Pass 1: shape functions at x^n and the node box of the grain.
  IVec<Dim> lo = IVec<Dim>::Constant(std::numeric_limits<std::int64_t>::max());
  IVec<Dim> hi = IVec<Dim>::Constant(std::numeric_limits<std::int64_t>::min());
  Shape ps;
  for (std::int64_t i = 0; i < np; ++i) {
    const std::int64_t p = gr.begin + i;
    if (!ps.eval(points_.x[p], grid_.origin(), h, gr.half_width,
                 points_.F[p] * points_.domain[p])) {
      w.failure =
          "material point domain spans more than two cells along an axis (stretched over about "
          "twice its size: seed more points per cell)";
      w.fail_point = p;
      return;
    }
    w.pt_first[i] = ps.first;
    for (int a = 0; a < K; ++a) {
      w.pt_N[i * K + a] = ps.N[a];
      w.pt_dN[i * K + a] = ps.dN[a];
    }
    lo = lo.cwiseMin(ps.first);
    hi = hi.cwiseMax(ps.first + IVec<Dim>::Constant(S1::kNodes - 1));
    if ((ps.first.array() < 0).any() ||
        ((ps.first.array() + S1::kNodes - 1) >= grid_.nodes_per_axis().array()).any() ||
        !points_.x[p].allFinite()) {
      w.failure =
          "material point left the grid (or came within the shape-function support of its edge)";
      w.retryable = false;
      w.fail_point = p;
      return;
    }
  }
  if (np == 0) return;
  w.box_lo = lo;
  w.box_n = hi - lo + IVec<Dim>::Ones();
  const std::size_t nb = static_cast<std::size_t>(w.box_n.prod());
  IVec<Dim> stride;
  stride[0] = 1;
  for (int d = 1; d < Dim; ++d) stride[d] = stride[d - 1] * w.box_n[d - 1];
  reset(w.box_m, nb, 0.0);
  reset(w.box_mv, nb, Vec<Dim>(Vec<Dim>::Zero()));
  reset(w.box_f, nb, Vec<Dim>(Vec<Dim>::Zero()));
  reset(w.box_fext, nb, Vec<Dim>(Vec<Dim>::Zero()));
  const bool contact = settings_.contact.enabled;
  const bool affine = settings_.affine;
  if (contact) reset(w.box_gm, nb, Vec<Dim>(Vec<Dim>::Zero()));
  // Pass 2: P2G (method.md §2): m_I = sum N m_p, m_I v_I = sum N m_p v_p,
  // f_I^n = -sum V_p sigma_p grad N_I (seed eq. 5) + sum N m_p g.
  for (std::int64_t i = 0; i < np; ++i) {
    const std::int64_t p = gr.begin + i;
    const IVec<Dim> base = w.pt_first[i] - lo;
    const double mp = points_.mass[p];
    const Vec<Dim> mv = mp * points_.v[p];
    const Mat<Dim> mL = mp * points_.L[p];
    const Vec<Dim> mg = mp * settings_.gravity;
    const Mat<Dim> Vs = points_.volume[p] * points_.sigma[p];
    for (int a = 0; a < K; ++a) {
      IVec<Dim> c = base;
      for (int d = 0; d < Dim; ++d) c[d] += Shape::offset(a, d);
      const std::int64_t b = c.dot(stride);
      const double N = w.pt_N[i * K + a];
      w.box_m[b] += N * mp;
      w.box_mv[b] += N * mv;
      // Affine P2G: + N m_p L_p (x_I - x_p) (Settings::affine).
      if (affine) w.box_mv[b] += N * (mL * (grid_.node_position(c + lo) - points_.x[p]));
      w.box_f[b] -= Vs * w.pt_dN[i * K + a];
      w.box_fext[b] += N * mg;
      if (contact) w.box_gm[b] += mp * w.pt_dN[i * K + a];  // grad m_I = sum m_p grad N_I (§4)
    }
  }
  // Keep the previous step's active set to reuse the sparse pattern when it has not changed.
  w.prev_box_to_active.swap(w.box_to_active);
  const bool same_box = w.pattern_valid && w.prev_box_lo == lo && w.prev_box_n == w.box_n;
  w.prev_box_lo = lo;
  w.prev_box_n = w.box_n;
  reset(w.box_to_active, nb, std::int32_t{-1});
  w.node_global.clear();
  w.node_box.clear();
  w.m.clear();
  w.v_p2g.clear();
  w.f_n.clear();
  w.f_ext.clear();
  w.grad_m.clear();
  // Active nodes carry more than round-off mass (uGIMP tails at a material edge lying on a grid
  // line give weights ~1e-17 that would only make the Newton matrix ill-conditioned).
  double mp_max = 0;
  for (std::int64_t i = 0; i < np; ++i) mp_max = std::max(mp_max, points_.mass[gr.begin + i]);
  // CPDI (docs/accuracy.md): a domain corner just past a grid line gives its far nodes weights
  // down to round-off; such a node's velocity is the ratio of two vanishing forces and, when a
  // wall face rests on it, it spoils the contact problem (measured: the walled block's exact state
  // lost at s = 0.80 with 1e-13; exact to s = 0.5 with 1e-6). The mass left out (below 1e-6 of a
  // point's per node) is the price: momentum drift ~1e-6 instead of round-off.
  const double m_min = (settings_.shape == grid::ShapeKind::kCpdi ? 1e-6 : 1e-13) * mp_max;
  for (std::size_t b = 0; b < nb; ++b) {
    if (!(w.box_m[b] > m_min)) continue;
    w.box_to_active[b] = static_cast<std::int32_t>(w.m.size());
    IVec<Dim> c;
    std::int64_t r = static_cast<std::int64_t>(b);
    for (int d = 0; d < Dim; ++d) {
      c[d] = r % w.box_n[d];
      r /= w.box_n[d];
    }
    w.node_box.push_back(c);
    w.node_global.push_back(grid_.node_index(c + lo));
    w.m.push_back(w.box_m[b]);
    w.v_p2g.push_back(w.box_mv[b] / w.box_m[b]);
    w.f_n.push_back(w.box_f[b] + w.box_fext[b]);
    w.f_ext.push_back(w.box_fext[b]);
    if (contact) w.grad_m.push_back(w.box_gm[b]);
  }
  const std::size_t na = w.m.size();
  for (std::int64_t i = 0; i < np; ++i) {
    const IVec<Dim> base = w.pt_first[i] - lo;
    for (int a = 0; a < K; ++a) {
      IVec<Dim> c = base;
      for (int d = 0; d < Dim; ++d) c[d] += Shape::offset(a, d);
      // A window node with zero weight and gradient (CPDI domains inside fewer cells than the
      // window, uGIMP tails) takes no part: -1 skips it in every loop over the support.
      const bool zero = w.pt_N[i * K + a] == 0.0 && w.pt_dN[i * K + a].isZero(0.0);
      w.pt_node[i * K + a] = zero ? -1 : w.box_to_active[c.dot(stride)];
    }
    // A support node left out for its (near) zero mass may still carry a full gradient: a point
    // exactly on a grid line sees the far node of its cell with N = 0 and grad N = 1/h. Dropping
    // that term breaks sum grad N = 0, so a uniform velocity strains the point (a translated
    // block: J - 1 = 2e-3 after one such step, test Dynamics.TranslatedBlock...). The remaining
    // gradients are corrected to grad N_a - (N_a / sum N) sum grad N over the kept nodes, which
    // restores the partition of unity of the gradients (uniform fields exact).
    Vec<Dim> g_sum = Vec<Dim>::Zero();
    double n_sum = 0;
    bool dropped = false;
    for (int a = 0; a < K; ++a) {
      if (w.pt_node[i * K + a] < 0) {
        dropped = dropped || !w.pt_dN[i * K + a].isZero(0.0);
        continue;
      }
      g_sum += w.pt_dN[i * K + a];
      n_sum += w.pt_N[i * K + a];
    }
    if (dropped && n_sum > 0)
      for (int a = 0; a < K; ++a)
        if (w.pt_node[i * K + a] >= 0) w.pt_dN[i * K + a] -= (w.pt_N[i * K + a] / n_sum) * g_sum;
  }
  // Boundary conditions: prescribed components of v^n (for the increment) and v^{n+1}.
  w.mask.assign(na, 0);
  w.v_n = w.v_p2g;
  for (std::size_t a = 0; a < na; ++a) {
    const std::int64_t n = w.node_global[a];
    const std::uint8_t mk = bc_mask_[n];
    if (!mk) continue;
    w.mask[a] = mk;
    const Vec<Dim> xn = grid_.node_position(w.node_box[a] + lo);
    for (int d = 0; d < Dim; ++d)
      if (mk & (1u << d)) w.v_n[a][d] = bcs_[bc_set_[d][n]].value(xn)[d];
  }
  w.v = w.v_n;  // initial guess: zero acceleration
  // Energy ledger: what the P2G (and the prescribed values) keep of the points' kinetic energy.
  w.kin_points_n = w.kin_grid_n = 0;
  for (std::int64_t i = 0; i < np; ++i)
    w.kin_points_n += 0.5 * points_.mass[gr.begin + i] * points_.v[gr.begin + i].squaredNorm();
  for (std::size_t a = 0; a < na; ++a) w.kin_grid_n += 0.5 * w.m[a] * w.v_n[a].squaredNorm();
  reset(w.f_int, na, Vec<Dim>(Vec<Dim>::Zero()));
  reset(w.f_abs, na, Vec<Dim>(Vec<Dim>::Zero()));
  reset(w.P, na, Vec<Dim>(Vec<Dim>::Zero()));
  if (contact) {
    // Node -> points lists (for the gaps) and the contact mass threshold of this grain.
    double m_sum = 0, v_sum = 0;
    for (std::int64_t i = 0; i < np; ++i) {
      m_sum += points_.mass[gr.begin + i];
      v_sum += points_.volume0[gr.begin + i];
    }
    w.contact_mass = settings_.contact.mass_fraction * m_sum / v_sum * std::pow(h, Dim);
    w.node_pts_start.assign(na + 1, 0);
    for (std::int64_t i = 0; i < np; ++i)
      for (int a = 0; a < K; ++a)
        if (w.pt_node[i * K + a] >= 0 && w.pt_N[i * K + a] > 0)
          ++w.node_pts_start[w.pt_node[i * K + a] + 1];
    for (std::size_t a = 0; a < na; ++a) w.node_pts_start[a + 1] += w.node_pts_start[a];
    w.node_pts.resize(w.node_pts_start[na]);
    std::vector<std::int32_t> fill(w.node_pts_start.begin(), w.node_pts_start.end() - 1);
    for (std::int64_t i = 0; i < np; ++i)
      for (int a = 0; a < K; ++a)
        if (w.pt_node[i * K + a] >= 0 && w.pt_N[i * K + a] > 0)
          w.node_pts[fill[w.pt_node[i * K + a]]++] = static_cast<std::int32_t>(i);
  }
  reset(w.R, na, Vec<Dim>(Vec<Dim>::Zero()));
  reset(w.du, na, Vec<Dim>(Vec<Dim>::Zero()));
  (void)dt;
  // The pattern (stencil, sparse structure, symbolic factorisation) depends only on the active
  // node set: reuse it when unchanged (the usual case at small dt).
  if (same_box && w.box_to_active == w.prev_box_to_active) return;
  w.pattern_valid = true;
  // Stencil of the tangent: node b couples to node a if |c_b - c_a| <= radius per axis.
  w.radius = S1::kNodes - 1;
  const int width = 2 * w.radius + 1;
  w.S = 1;
  for (int d = 0; d < Dim; ++d) w.S *= width;
  w.pair_slot.resize(K * K);
  for (int a = 0; a < K; ++a)
    for (int b = 0; b < K; ++b) {
      int slot = 0, mul = 1;
      for (int d = 0; d < Dim; ++d) {
        slot += (Shape::offset(b, d) - Shape::offset(a, d) + w.radius) * mul;
        mul *= width;
      }
      w.pair_slot[a * K + b] = slot;
    }
  w.stencil_nb.assign(na * w.S, -1);
  for (std::size_t a = 0; a < na; ++a)
    for (int s = 0; s < w.S; ++s) {
      IVec<Dim> c = w.node_box[a];
      int r = s;
      bool inside = true;
      for (int d = 0; d < Dim; ++d) {
        c[d] += r % width - w.radius;
        r /= width;
        if (c[d] < 0 || c[d] >= w.box_n[d]) inside = false;
      }
      if (inside) w.stencil_nb[a * w.S + s] = w.box_to_active[c.dot(stride)];
    }
  w.K_blk.resize(na * w.S);
  // Sparse pattern of the Newton matrix and the map from stencil blocks to stored values.
  std::vector<Eigen::Triplet<double>> trip;
  trip.reserve(na * w.S * Dim * Dim);
  for (std::size_t a = 0; a < na; ++a)
    for (int s = 0; s < w.S; ++s) {
      const std::int32_t b = w.stencil_nb[a * w.S + s];
      if (b < 0) continue;
      for (int i = 0; i < Dim; ++i)
        for (int j = 0; j < Dim; ++j) trip.emplace_back(a * Dim + i, b * Dim + j, 0.0);
    }
  const auto ndof = static_cast<Eigen::Index>(na * Dim);
  w.A.resize(ndof, ndof);
  w.A.setFromTriplets(trip.begin(), trip.end());
  w.A.makeCompressed();
  w.value_index.assign(na * w.S * Dim * Dim, -1);
  const int* outer = w.A.outerIndexPtr();
  const int* inner = w.A.innerIndexPtr();
  for (std::size_t a = 0; a < na; ++a)
    for (int s = 0; s < w.S; ++s) {
      const std::int32_t b = w.stencil_nb[a * w.S + s];
      if (b < 0) continue;
      for (int i = 0; i < Dim; ++i)
        for (int j = 0; j < Dim; ++j) {
          const int col = b * Dim + j, row = static_cast<int>(a) * Dim + i;
          const int* pos = std::lower_bound(inner + outer[col], inner + outer[col + 1], row);
          w.value_index[((a * w.S + s) * Dim + i) * Dim + j] = pos - inner;
        }
    }
  if (settings_.linear_solver == LinearSolverKind::kLdlt) w.ldlt.analyzePattern(w.A);
  if (settings_.linear_solver == LinearSolverKind::kLu) w.lu.analyzePattern(w.A);
}

template <int Dim>
template <class S1>
void ImplicitSolver<Dim>::evaluate_grain(std::size_t g, double dt) {
  using Shape = typename grid::ShapeOf<Dim, S1>::type;
  constexpr int K = Shape::K;
  GrainWork& w = *work_[g];
  const points::Grain& gr = grains_[g];
  const std::int64_t np = gr.size();
  const std::size_t na = w.m.size();
  const double theta = settings_.theta;
  w.tangent_current = w.factor_current = false;
  // Nodal increment du_I = dt [(1 - theta) v_I^n + theta v_I^{n+1}] (method.md §2).
  for (std::size_t a = 0; a < na; ++a) w.du[a] = dt * ((1.0 - theta) * w.v_n[a] + theta * w.v[a]);
  // Kinematics: dF = I + sum du_I (x) grad N_I(x^n), F^{n+1} = dF F^n, V^{n+1} = J V^0.
  for (std::int64_t i = 0; i < np; ++i) {
    const std::int64_t p = gr.begin + i;
    Mat<Dim> dF = Mat<Dim>::Identity();
    for (int a = 0; a < K; ++a) {
      const std::int32_t n = w.pt_node[i * K + a];
      if (n >= 0) dF += w.du[n] * w.pt_dN[i * K + a].transpose();
    }
    F_trial_[p] = dF * points_.F[p];
    const double J = F_trial_[p].determinant();
    J_trial_[p] = J;
    if (!(J > 0.0) || !std::isfinite(J)) {
      w.failure = fmt::format("J = {:.3g} <= 0 (inverted material point)", J);
      w.fail_point = p;
      return;
    }
    dF_inv_T_[p] = dF.inverse().transpose();
  }
  const materials::Law<Dim>& law = *laws_[gr.material];
  const auto off = static_cast<std::size_t>(gr.begin);
  const auto cnt = static_cast<std::size_t>(np);
  const std::size_t hs = static_cast<std::size_t>(law.history_size());
  materials::LawBatch<Dim> batch{
      std::span<const Mat<Dim>>(F_trial_.data() + off, cnt),
      std::span<const double>(points_.history.data() + gr.history_offset, hs * cnt),
      std::span<double>(history_trial_.data() + gr.history_offset, hs * cnt),
      std::span<Mat<Dim>>(sigma_trial_.data() + off, cnt),
      std::span<Tensor4<Dim>>(tangent_.data() + off, cnt),
      {},
      Dim == 2 ? std::span<double>(sigma_zz_trial_.data() + off, cnt) : std::span<double>()};
  law.evaluate(batch);
  // Internal force f_I = -sum V sigma grad_{x^{n+1}} N_I with grad_{x^{n+1}} N = dF^-T grad_{x^n} N
  // (seed eq. 5 at n+1, method.md §2).
  std::fill(w.f_int.begin(), w.f_int.end(), Vec<Dim>::Zero());
  std::fill(w.f_abs.begin(), w.f_abs.end(), Vec<Dim>::Zero());
  for (std::int64_t i = 0; i < np; ++i) {
    const std::int64_t p = gr.begin + i;
    const Mat<Dim>& sig = sigma_trial_[p];
    if (!sig.allFinite()) {
      w.failure = "non-finite stress";
      w.fail_point = p;
      return;
    }
    const Mat<Dim> Vsig_dFinvT = J_trial_[p] * points_.volume0[p] * sig * dF_inv_T_[p];
    for (int a = 0; a < K; ++a) {
      const std::int32_t n = w.pt_node[i * K + a];
      if (n < 0) continue;
      const Vec<Dim> fa = Vsig_dFinvT * w.pt_dN[i * K + a];
      w.f_int[n] -= fa;
      w.f_abs[n] += fa.cwiseAbs();
    }
  }
  // Residual R_I = m_I (v^{n+1} - v^n) - dt [(1 - theta) f^n + theta f^{n+1}] (method.md §2).
  // Reference scale: inertia, nodal forces and the magnitude of the stress contributions, so that
  // the tolerance stays above round-off when large point forces cancel at a node.
  double r2 = 0, mv2 = 0, fn2 = 0, fi2 = 0, fe2 = 0, fa2 = 0, p2 = 0;
  for (std::size_t a = 0; a < na; ++a) {
    // ... - P_I: the contact impulse over the step (method.md §2, §4)
    Vec<Dim> r = w.m[a] * (w.v[a] - w.v_n[a]) -
                 dt * ((1.0 - theta) * w.f_n[a] + theta * (w.f_int[a] + w.f_ext[a])) - w.P[a];
    for (int d = 0; d < Dim; ++d)
      if (w.mask[a] & (1u << d)) r[d] = 0.0;
    w.R[a] = r;
    r2 += r.squaredNorm();
    mv2 += (w.m[a] * w.v_n[a]).squaredNorm();
    fn2 += w.f_n[a].squaredNorm();
    fi2 += w.f_int[a].squaredNorm();
    fe2 += w.f_ext[a].squaredNorm();
    fa2 += w.f_abs[a].squaredNorm();
    p2 += w.P[a].squaredNorm();
  }
  w.res_norm = std::sqrt(r2);
  w.res_ref = std::sqrt(mv2) + std::sqrt(p2) +
              dt * (std::sqrt(fn2) + std::sqrt(fi2) + std::sqrt(fe2) + std::sqrt(fa2));
  if (!std::isfinite(w.res_norm)) {
    w.failure = "non-finite residual";
    return;
  }
  // Velocity scale of the increment test (mass norm): sqrt(sum m max(|v^{n+1}|^2, |v^n|^2)) plus
  // the velocity change the step's forces and impulses can produce, res_ref / sqrt(M) (a body at
  // rest has no velocity scale of its own). The convergence decision is taken in solve_step.
  double vref2 = 0, mass = 0;
  for (std::size_t a = 0; a < na; ++a) {
    vref2 += w.m[a] * std::max(w.v[a].squaredNorm(), w.v_n[a].squaredNorm());
    mass += w.m[a];
  }
  w.vel_ref = std::sqrt(vref2) + (mass > 0 ? w.res_ref / std::sqrt(mass) : 0.0);
  w.evaluated = true;
}

template <int Dim>
template <class S1>
void ImplicitSolver<Dim>::assemble_tangent(std::size_t g) {
  using Shape = typename grid::ShapeOf<Dim, S1>::type;
  constexpr int K = Shape::K;
  GrainWork& w = *work_[g];
  const points::Grain& gr = grains_[g];
  // Tangent blocks K_IJ,ik = sum V g_I,j a_ijkl g_J,l, g = dF^-T grad_{x^n} N (material +
  // geometric, method.md §2), accumulated into the block stencil through the pair -> slot table.
  std::fill(w.K_blk.begin(), w.K_blk.end(), Mat<Dim>::Zero());
  Vec<Dim> gx[K];
  Eigen::Matrix<double, Dim, Dim * Dim> Ma[K];
  for (std::int64_t i = 0; i < gr.size(); ++i) {
    const std::int64_t p = gr.begin + i;
    const double V = J_trial_[p] * points_.volume0[p];
    const Tensor4<Dim>& T = tangent_[p];
    for (int a = 0; a < K; ++a) {
      gx[a] = dF_inv_T_[p] * w.pt_dN[i * K + a];
      if (w.pt_node[i * K + a] < 0) continue;
      // Ma(i, kl) = V sum_j g_j a(ij, kl)
      for (int ii = 0; ii < Dim; ++ii)
        for (int kl = 0; kl < Dim * Dim; ++kl) {
          double acc = 0;
          for (int j = 0; j < Dim; ++j) acc += gx[a][j] * T(ii * Dim + j, kl);
          Ma[a](ii, kl) = V * acc;
        }
    }
    for (int a = 0; a < K; ++a) {
      const std::int32_t na_ = w.pt_node[i * K + a];
      if (na_ < 0) continue;
      Mat<Dim>* row = &w.K_blk[static_cast<std::size_t>(na_) * w.S];
      for (int b = 0; b < K; ++b) {
        if (w.pt_node[i * K + b] < 0) continue;
        Mat<Dim>& blk = row[w.pair_slot[a * K + b]];
        for (int ii = 0; ii < Dim; ++ii)
          for (int k = 0; k < Dim; ++k) {
            double acc = 0;
            for (int l = 0; l < Dim; ++l) acc += Ma[a](ii, k * Dim + l) * gx[b][l];
            blk(ii, k) += acc;
          }
      }
    }
  }
  w.tangent_current = true;
}

template <int Dim>
bool ImplicitSolver<Dim>::factorize_grain(std::size_t g, double dt) {
  GrainWork& w = *work_[g];
  const std::size_t na = w.m.size();
  const double c = settings_.theta * settings_.theta * dt * dt;
  double* val = w.A.valuePtr();
  // Newton matrix dR/dv^{n+1} = M + theta^2 dt^2 K (method.md §2); prescribed rows and columns
  // are replaced by m_I on the diagonal so the matrix stays symmetric positive definite.
  const int center = (w.S - 1) / 2;
  for (std::size_t a = 0; a < na; ++a)
    for (int s = 0; s < w.S; ++s) {
      const std::int32_t b = w.stencil_nb[a * w.S + s];
      if (b < 0) continue;
      const Mat<Dim>& K = w.K_blk[a * w.S + s];
      for (int i = 0; i < Dim; ++i)
        for (int j = 0; j < Dim; ++j) {
          double v = c * K(i, j);
          if (s == center && i == j) v += w.m[a];
          const bool fixed_row = w.mask[a] & (1u << i);
          const bool fixed_col = w.mask[b] & (1u << j);
          if (fixed_row || fixed_col) v = (s == center && i == j) ? w.m[a] : 0.0;
          val[w.value_index[((a * w.S + s) * Dim + i) * Dim + j]] = v;
        }
    }
  bool ok = true;
  switch (settings_.linear_solver) {
    case LinearSolverKind::kLdlt:
      w.ldlt.factorize(w.A);
      ok = w.ldlt.info() == Eigen::Success;
      break;
    case LinearSolverKind::kLu:
      w.lu.factorize(w.A);
      ok = w.lu.info() == Eigen::Success;
      break;
    case LinearSolverKind::kCg:
      w.cg.setTolerance(settings_.cg_tolerance);
      w.cg.setMaxIterations(settings_.cg_max_iterations);
      w.cg.compute(w.A);
      break;
  }
  if (!ok) w.failure = "linear solve failed (singular or indefinite tangent)";
  w.factor_current = ok;
  w.factor_in_step = ok;
  ++w.factor_count;
  ++w.factorizations;
  return ok;
}

template <int Dim>
template <class Rhs>
Eigen::VectorXd ImplicitSolver<Dim>::linear_solve(std::size_t g, const Rhs& rhs) {
  GrainWork& w = *work_[g];
  switch (settings_.linear_solver) {
    case LinearSolverKind::kLdlt:
      return w.ldlt.solve(rhs);
    case LinearSolverKind::kLu:
      return w.lu.solve(rhs);
    case LinearSolverKind::kCg: {
      Eigen::VectorXd x = w.cg.solve(rhs);
      if (w.cg.info() != Eigen::Success) x.setConstant(std::numeric_limits<double>::quiet_NaN());
      return x;
    }
  }
  return {};
}

template <int Dim>
bool ImplicitSolver<Dim>::reuse_factor(const GrainWork& w) const {
  // Modified Newton (Settings::modified_newton): the step's first factorisation serves all its
  // iterations and contact updates, unless the residual stalls (falls by less than half over an
  // iteration), when the tangent is rebuilt.
  if (!settings_.modified_newton || !w.factor_in_step) return false;
  const auto n = w.history.size();
  return n < 2 || w.history[n - 1] < 0.5 * w.history[n - 2];
}

template <int Dim>
void ImplicitSolver<Dim>::solve_grain(std::size_t g, double dt, bool reuse) {
  GrainWork& w = *work_[g];
  const std::size_t na = w.m.size();
  if (!reuse && !factorize_grain(g, dt)) return;
  w.rhs.resize(static_cast<Eigen::Index>(na * Dim));
  for (std::size_t a = 0; a < na; ++a)
    for (int d = 0; d < Dim; ++d) w.rhs[a * Dim + d] = -w.R[a][d];
  w.sol = linear_solve(g, w.rhs);
  w.cg_work = settings_.linear_solver == LinearSolverKind::kCg
                  ? static_cast<double>(w.cg.iterations()) * static_cast<double>(w.A.nonZeros())
                  : static_cast<double>(w.A.nonZeros());
  if (!w.sol.allFinite()) {
    w.failure = "linear solve failed (singular or indefinite tangent)";
    return;
  }
  double dv2 = 0;
  for (std::size_t a = 0; a < na; ++a) {
    const Vec<Dim> dv = w.sol.template segment<Dim>(static_cast<Eigen::Index>(a * Dim));
    w.v[a] += dv;
    dv2 += w.m[a] * dv.squaredNorm();
  }
  w.dv_norm = std::sqrt(dv2);
  w.solved_once = true;
  ++w.solves;
}

template <int Dim>
StepStats ImplicitSolver<Dim>::solve_step(double dt) {
  StepStats stats;
  const std::size_t ng = grains_.size();
  const std::size_t np = points_.size();
  dt_ = dt;
  step_ready_ = false;
  if (work_.size() != ng) {
    work_.clear();
    for (std::size_t g = 0; g < ng; ++g) work_.push_back(std::make_unique<GrainWork>());
  }
  // The grains this rank computes (all of them when serial); ghosts are added by exchange_entries.
  const bool dist = distributed();
  if (owner_.size() != ng) owner_.assign(ng, 0);
  owned_.clear();
  role_.assign(ng, 0);
  for (std::size_t g = 0; g < ng; ++g)
    if (!dist || owner_[g] == comm_->rank()) {
      owned_.push_back(g);
      role_[g] = 1;
    }
  local_ = owned_;
  const std::size_t no = owned_.size();
  F_trial_.resize(np);
  sigma_trial_.resize(np);
  dF_inv_T_.resize(np);
  sigma_zz_trial_.resize(np);
  J_trial_.resize(np);
  tangent_.resize(np);
  history_trial_ = points_.history;
  // This rank's lowest failing grain into stats; true if there is one.
  auto local_failure = [&]() {
    for (std::size_t g : owned_)
      if (!work_[g]->failure.empty()) {
        stats.failure = work_[g]->failure;
        stats.grain = static_cast<std::int64_t>(g);
        stats.point = work_[g]->fail_point;
        stats.retryable = work_[g]->retryable;
        return true;
      }
    return false;
  };
  auto collect_failure = [&]() {
    const bool failed = local_failure();
    return dist ? sync_failure(stats) : failed;
  };
  {
    ScopedStage t(&timers_, "p2g");
    const ThreadedRegion threaded(&timers_, no > 1);
#pragma omp parallel for schedule(dynamic, 1) if (no > 1)
    for (std::size_t i = 0; i < no; ++i) {
      const std::size_t g = owned_[i];
      with_shape(settings_.shape, [&](auto tag) { setup_grain<decltype(tag)>(g, dt); });
    }
  }
  // Work counts (docs/parallel.md): per grain and phase for re-balancing, where P2G, detection
  // and G2P go with the first Newton iteration; per synchronisation for the counted serial
  // fraction (Comm::count_work).
  grain_work_.resize(ng * parallel::kWorkPhases, 0.0);
  double owned_points = 0;
  for (std::size_t g : owned_) {
    phase_work(g, 0) += kSetupWorkWeight * static_cast<double>(grains_[g].size());
    owned_points += static_cast<double>(grains_[g].size());
  }
  if (dist) comm_->count_work(kP2gWorkWeight * owned_points);
  if (collect_failure()) return stats;
  const bool contact = settings_.contact.enabled;
  if (contact && dist) {
    ScopedStage t(&timers_, "comm.entries");
    exchange_entries();
  }
  if (contact) {
    ScopedStage t(&timers_, "contact.detect");
    detect_contacts(dt);
    if (dist) {
      comm_->count_work(kDetectItemWeight * detect_items_);
      ScopedStage tc(&timers_, "contact.detect.comm");
      exchange_requests();
    } else {
      have_contacts_ = !problem_.contacts.empty();
    }
  } else {
    problem_.contacts.clear();
    problem_.slots.clear();
    have_contacts_ = false;
  }
  double impulse_change = 0, ref_scale = 0, vel_scale = 0;
  for (int it = 0; it <= settings_.max_iterations; ++it) {
    {
      ScopedStage t(&timers_, "newton.assemble");
      double units = 0;
      const ThreadedRegion threaded(&timers_, no > 1);
#pragma omp parallel for schedule(dynamic, 1) if (no > 1) reduction(+ : units)
      for (std::size_t i = 0; i < no; ++i) {
        const std::size_t g = owned_[i];
        GrainWork& w = *work_[g];
        if (w.converged || !w.failure.empty()) continue;
        with_shape(settings_.shape, [&](auto tag) { evaluate_grain<decltype(tag)>(g, dt); });
        if (w.failure.empty()) w.iterations = it;
        const auto u = static_cast<double>(grains_[g].size());
        phase_work(g, it) += u;
        units += u;
      }
      if (dist) comm_->count_work(units);
    }
    const bool failed_here = local_failure();
    // Convergence of each evaluated grain: |R| <= tol * reference and |dv|_M <= tol * velocity
    // scale, the references floored at 1e-3 of the largest grain's so that a grain at rest (whose
    // own scales vanish) is judged on the scale of the step, not on round-off.
    for (std::size_t g : owned_) {
      if (!work_[g]->evaluated) continue;
      ref_scale = std::max(ref_scale, work_[g]->res_ref);
      vel_scale = std::max(vel_scale, work_[g]->vel_ref);
    }
    if (dist) {
      // One reduction for the scales (max is exact: the same scales as one process) and the
      // failures: the lowest failing grain over the ranks, as the largest of its negatives.
      constexpr double kNoGrain = 1e300;
      ScopedStage tc(&timers_, "newton.check.comm");
      std::vector<double> sc{ref_scale, vel_scale,
                             failed_here ? -static_cast<double>(stats.grain) : -kNoGrain};
      comm_->max(sc);
      ref_scale = sc[0];
      vel_scale = sc[1];
      if (sc[2] > -kNoGrain && sync_failure(stats, static_cast<std::int64_t>(-sc[2]))) return stats;
    } else if (failed_here) {
      return stats;
    }
    double worst = 0;
    bool all = true;
    for (std::size_t g : owned_) {
      GrainWork& w = *work_[g];
      if (w.evaluated) {
        w.evaluated = false;
        const double ref = std::max(w.res_ref, 1e-3 * ref_scale);
        const double vref = std::max(w.vel_ref, 1e-3 * vel_scale);
        const bool res_ok = w.res_norm <= settings_.residual_tolerance * ref;
        const bool inc_ok = !w.solved_once || w.dv_norm <= settings_.increment_tolerance * vref;
        w.converged = res_ok && inc_ok;
        const double rel = ref > 0 ? w.res_norm / ref : 0.0;
        w.history.push_back(rel);
        worst = std::max(worst, rel);
      }
      all = all && w.converged;
    }
    if (dist) {
      ScopedStage tc(&timers_, "newton.check.comm");
      std::vector<double> r{worst, all ? 0.0 : 1.0};
      comm_->max(r);
      worst = r[0];
      all = r[1] == 0.0;
    }
    stats.residual_history.push_back(worst);
    // Staggered with Newton: the step has converged when the grains have (with the current
    // impulses) and the impulses have stopped changing (method.md §4).
    const bool impulses_ok =
        !have_contacts_ || (it > 0 && impulse_change <= settings_.contact.impulse_tolerance);
    if (all && impulses_ok) {
      stats.converged = true;
      break;
    }
    if (it == settings_.max_iterations) break;
    {
      ScopedStage t(&timers_, "newton.solve");
      double units = 0;
      const ThreadedRegion threaded(&timers_, no > 1);
#pragma omp parallel for schedule(dynamic, 1) if (no > 1) reduction(+ : units)
      for (std::size_t i = 0; i < no; ++i) {
        const std::size_t g = owned_[i];
        GrainWork& w = *work_[g];
        if (w.converged || !w.failure.empty()) continue;
        const bool reuse = reuse_factor(w);
        if (!reuse && !w.tangent_current) {
          with_shape(settings_.shape, [&](auto tag) { assemble_tangent<decltype(tag)>(g); });
        }
        solve_grain(g, dt, reuse);
        const double u = kCgWorkWeight * w.cg_work;
        phase_work(g, it) += u;
        units += u;
      }
      if (dist) comm_->count_work(units);
    }
    if (collect_failure()) return stats;
    if (have_contacts_) {
      ScopedStage t(&timers_, "contact.solve");
      impulse_change = dist ? update_contacts_distributed(stats) : update_contacts(stats);
    }
  }
  for (std::size_t g : owned_) {
    stats.iterations = std::max(stats.iterations, work_[g]->iterations);
    stats.linear_solves += work_[g]->solves;
    stats.factorizations += work_[g]->factorizations;
  }
  if (!stats.converged) {
    for (std::size_t g : owned_)
      if (!work_[g]->converged) {
        stats.grain = static_cast<std::int64_t>(g);
        break;
      }
    if (dist) {
      ScopedStage tc(&timers_, "newton.check.comm");
      std::vector<std::int64_t> gmin{stats.grain < 0 ? std::numeric_limits<std::int64_t>::max()
                                                     : stats.grain};
      comm_->min(gmin);
      stats.grain = gmin[0] == std::numeric_limits<std::int64_t>::max() ? -1 : gmin[0];
    }
    stats.failure =
        fmt::format("Newton did not converge in {} iterations (relative residual {:.3e}",
                    settings_.max_iterations,
                    stats.residual_history.empty() ? 0.0 : stats.residual_history.back());
    if (have_contacts_)
      stats.failure += fmt::format(", relative impulse change {:.3e}, Gauss-Seidel error {:.3e}",
                                   impulse_change, stats.gs_error);
    stats.failure += ")";
    return stats;
  }
  // The state this step commits must be one the next step can start from, and its checkpoint one a
  // restart accepts: a point whose new position would put its shape-function support past the
  // grid's edge fails this step (not retryable), so the last good state keeps every point inside.
  {
    ScopedStage t(&timers_, "g2p");
    const ThreadedRegion threaded(&timers_, no > 1);
#pragma omp parallel for schedule(dynamic, 1) if (no > 1)
    for (std::size_t i = 0; i < no; ++i) {
      const std::size_t g = owned_[i];
      with_shape(settings_.shape, [&](auto tag) { check_next_positions<decltype(tag)>(g); });
    }
  }
  if (collect_failure()) {
    stats.converged = false;
    return stats;
  }
  // Energy ledger of this rank's grains (docs/accuracy.md). M (v - v^n) = dt f + P times
  // (v^n + v)/2 splits the grid's kinetic energy change into the work of the contact impulses,
  // P . (v^n + v)/2, of the internal and of the body forces; the transfers account for the rest
  // of the points' kinetic energy change.
  // Per grain, summed in grain order over the ranks (the same bits on any rank count).
  const double theta = settings_.theta;
  std::vector<double> ledger(4 * grains_.size(), 0.0);
  for (std::size_t g : owned_) {
    const GrainWork& w = *work_[g];
    double kin_grid = 0, work_c = 0, work_int = 0, work_ext = 0;
    for (std::size_t a = 0; a < w.m.size(); ++a) {
      const Vec<Dim> vm = 0.5 * (w.v_n[a] + w.v[a]);
      kin_grid += 0.5 * w.m[a] * w.v[a].squaredNorm();
      if (have_contacts_) work_c += w.P[a].dot(vm);
      work_int += ((1.0 - theta) * (w.f_n[a] - w.f_ext[a]) + theta * w.f_int[a]).dot(vm);
      work_ext += w.f_ext[a].dot(vm);
    }
    ledger[4 * g] = work_c;
    ledger[4 * g + 1] = (w.kin_points_n - w.kin_grid_n) + (kin_grid - w.kin_points);
    ledger[4 * g + 2] = dt * work_int;
    ledger[4 * g + 3] = dt * work_ext;
  }
  if (dist) {
    ScopedStage tc(&timers_, "newton.check.comm");
    comm_->sum(ledger);  // one rank owns each grain: the sum is exact
  }
  for (std::size_t g = 0; g < grains_.size(); ++g) {
    stats.contact_work += ledger[4 * g];
    stats.transfer_loss += ledger[4 * g + 1];
    stats.stress_work += ledger[4 * g + 2];
    stats.body_work += ledger[4 * g + 3];
  }
  // Contact summary: active contacts and the force of the grains on each wall (-P/dt).
  stats.contacts = static_cast<std::int64_t>(problem_.contacts.size());
  // Wall forces per grain and wall, summed in grain order over the ranks (each grain's wall
  // contacts are on its owner's rank, in the serial order): the same bits on any rank count.
  const std::size_t nw = settings_.contact.walls.size();
  std::vector<double> wall_f(grains_.size() * nw * Dim, 0.0);
  previous_.clear();
  for (const auto& c : problem_.contacts) {
    if (c.impulse.dot(c.normal) > 0) ++stats.active_contacts;
    if (c.a < 0) {
      const std::size_t g = static_cast<std::size_t>(problem_.slots[c.b].grain);
      for (int d = 0; d < Dim; ++d) wall_f[(g * nw + c.wall) * Dim + d] -= c.impulse[d] / dt;
    }
    const std::int32_t a = c.a < 0 ? -1 - c.wall : problem_.slots[c.a].grain;
    previous_.push_back({slot_key_[c.b], a, problem_.slots[c.b].grain, c.impulse});
  }
  if (dist) {  // sums over the ranks' contacts, added in rank order
    ScopedStage tc(&timers_, "newton.check.comm");
    std::vector<std::int64_t> n{stats.contacts, stats.active_contacts, stats.linear_solves,
                                stats.factorizations};
    comm_->sum(n);
    std::vector<std::int64_t> it{-stats.iterations};
    comm_->min(it);
    stats.contacts = n[0];
    stats.active_contacts = n[1];
    stats.linear_solves = n[2];
    stats.factorizations = n[3];
    stats.iterations = static_cast<int>(-it[0]);
    if (nw > 0) comm_->sum(wall_f);  // one rank holds each grain's wall contacts: exact
  }
  stats.wall_force.assign(nw, {0.0, 0.0, 0.0});
  for (std::size_t g = 0; g < grains_.size(); ++g)
    for (std::size_t k = 0; k < nw; ++k)
      for (int d = 0; d < Dim; ++d) stats.wall_force[k][d] += wall_f[(g * nw + k) * Dim + d];
  std::sort(previous_.begin(), previous_.end(),
            [](const WarmImpulse<Dim>& x, const WarmImpulse<Dim>& y) {
              return std::tie(x.node, x.a, x.b) < std::tie(y.node, y.a, y.b);
            });
  step_ready_ = true;
  return stats;
}

template <int Dim>
void ImplicitSolver<Dim>::set_warm_start(std::vector<WarmImpulse<Dim>> impulses) {
  previous_ = std::move(impulses);
  sort_unique(previous_);
}

template <int Dim>
void ImplicitSolver<Dim>::sort_unique(std::vector<WarmImpulse<Dim>>& impulses) {
  const auto key = [](const WarmImpulse<Dim>& x) { return std::tie(x.node, x.a, x.b); };
  std::stable_sort(
      impulses.begin(), impulses.end(),
      [&](const WarmImpulse<Dim>& x, const WarmImpulse<Dim>& y) { return key(x) < key(y); });
  // One impulse per contact (the union of several ranks' copies holds each once per rank).
  impulses.erase(std::unique(impulses.begin(), impulses.end(),
                             [&](const WarmImpulse<Dim>& x, const WarmImpulse<Dim>& y) {
                               return key(x) == key(y);
                             }),
                 impulses.end());
}

template <int Dim>
std::int32_t ImplicitSolver<Dim>::slot_of(std::int32_t g, std::int32_t a) {
  const std::int64_t node = work_[g]->node_global[a];
  if (slot_stamp_[node] != stamp_) {
    slot_stamp_[node] = stamp_;
    slot_head_[node] = -1;
  }
  for (std::int32_t s = slot_head_[node]; s >= 0; s = slot_next_[s])
    if (slot_ref_[s].first == g) return s;
  const auto s = static_cast<std::int32_t>(problem_.slots.size());
  const GrainWork& w = *work_[g];
  problem_.slots.push_back({w.m[a], w.v[a], g, node});
  slot_ref_.emplace_back(g, a);
  slot_next_.push_back(slot_head_[node]);
  slot_head_[node] = s;
  slot_node_.push_back(a);
  slot_weight_.push_back(1.0);
  slot_start_.push_back(static_cast<std::int32_t>(slot_node_.size()));
  slot_is_face_.push_back(0);
  slot_key_.push_back(node);
  return s;
}

template <int Dim>
std::int32_t ImplicitSolver<Dim>::face_slot(std::int32_t g, const std::vector<std::int64_t>& pts,
                                            const Vec<Dim>& n, Vec<Dim>& x_face) {
  // The point's domain x_p + D s, s in [-1, 1]^Dim, D = F D0; the face toward the wall (normal
  // n into the domain) is the set of corners minimising s . D^T n. Its velocity is the mean of
  // the corners' velocities interpolated with the linear hat (the same corner kinematics as
  // CPDI): weights w_I = mean over the face corners of N_I(x_c).
  const GrainWork& w = *work_[g];
  const double h = grid_.cell_size();
  std::vector<std::int32_t> nodes;
  std::vector<double> weights;
  int count = 0;
  double total = 0;
  x_face.setZero();
  for (const std::int64_t p : pts) {
    const Mat<Dim> D = points_.F[p] * points_.domain[p];
    const Vec<Dim> dn = D.transpose() * n;
    const double tol = 1e-9 * D.cwiseAbs().maxCoeff();
    Vec<Dim> s;
    for (int d = 0; d < Dim; ++d) s[d] = std::abs(dn[d]) <= tol ? 0.0 : (dn[d] > 0 ? -1.0 : 1.0);
    int free_axes = 0;
    for (int d = 0; d < Dim; ++d) free_axes += s[d] == 0.0;
    const int corners = 1 << free_axes;
    x_face += (points_.x[p] + D * s) / static_cast<double>(pts.size());
    for (int c = 0; c < corners; ++c) {
      Vec<Dim> sc = s;
      for (int d = 0, bit = 0; d < Dim; ++d)
        if (s[d] == 0.0) sc[d] = (c >> bit++) & 1 ? 1.0 : -1.0;
      const Vec<Dim> xi = (points_.x[p] + D * sc - grid_.origin()) / h;
      IVec<Dim> cell;
      Vec<Dim> t;
      for (int d = 0; d < Dim; ++d) {
        cell[d] = static_cast<std::int64_t>(std::floor(xi[d]));
        t[d] = xi[d] - static_cast<double>(cell[d]);
      }
      for (int b = 0; b < (1 << Dim); ++b) {
        double wt = 1.0 / corners;
        IVec<Dim> node = cell - w.box_lo;
        for (int d = 0; d < Dim; ++d) {
          const int up = (b >> d) & 1;
          wt *= up ? t[d] : 1.0 - t[d];
          node[d] += up;
        }
        if (wt == 0.0) continue;
        if ((node.array() < 0).any() || (node.array() >= w.box_n.array()).any()) continue;
        std::int64_t idx = 0, mul = 1;
        for (int d = 0; d < Dim; ++d) {
          idx += node[d] * mul;
          mul *= w.box_n[d];
        }
        const std::int32_t a = w.box_to_active[idx];
        if (a < 0) continue;  // no mass there: the face's weight goes to the other nodes
        int k = 0;
        while (k < count && nodes[k] != a) ++k;
        if (k == count) {
          nodes.push_back(a);
          weights.push_back(0.0);
          ++count;
        }
        weights[k] += wt;
        total += wt;
      }
    }
  }
  if (count == 0 || !(total > 0)) return -1;
  const auto sidx = static_cast<std::int32_t>(problem_.slots.size());
  double inv_mass = 0;
  std::int32_t primary = nodes[0];
  double wmax = 0;
  for (int k = 0; k < count; ++k) {
    weights[k] /= total;
    slot_node_.push_back(nodes[k]);
    slot_weight_.push_back(weights[k]);
    inv_mass += weights[k] * weights[k] / w.m[nodes[k]];
    if (weights[k] > wmax) {
      wmax = weights[k];
      primary = nodes[k];
    }
  }
  slot_start_.push_back(static_cast<std::int32_t>(slot_node_.size()));
  slot_is_face_.push_back(1);
  slot_key_.push_back(-1);
  problem_.slots.push_back({1.0 / inv_mass, Vec<Dim>::Zero(), g, w.node_global[primary]});
  slot_ref_.emplace_back(g, primary);
  slot_next_.push_back(-1);  // not linked to its node: slot_of never returns a face slot
  problem_.slots.back().v_free = slot_velocity(static_cast<std::size_t>(sidx));
  return sidx;
}

template <int Dim>
Vec<Dim> ImplicitSolver<Dim>::slot_velocity(std::size_t s) const {
  const GrainWork& w = *work_[slot_ref_[s].first];
  Vec<Dim> v = Vec<Dim>::Zero();
  for (std::int32_t k = slot_start_[s]; k < slot_start_[s + 1]; ++k)
    v += slot_weight_[k] * w.v[slot_node_[k]];
  return v;
}

template <int Dim>
void ImplicitSolver<Dim>::spread_slot_impulses() {
  // Node slots assign (0 + P = P exactly, so runs without face slots keep their bits), face slots
  // add their weighted impulses.
  for (std::size_t s = 0; s < slot_ref_.size(); ++s)
    for (std::int32_t k = slot_start_[s]; k < slot_start_[s + 1]; ++k)
      work_[slot_ref_[s].first]->P[slot_node_[k]].setZero();
  for (std::size_t s = 0; s < slot_ref_.size(); ++s)
    if (!slot_is_face_[s]) work_[slot_ref_[s].first]->P[slot_ref_[s].second] = slot_P_[s];
  for (std::size_t s = 0; s < slot_ref_.size(); ++s)
    if (slot_is_face_[s])
      for (std::int32_t k = slot_start_[s]; k < slot_start_[s + 1]; ++k)
        work_[slot_ref_[s].first]->P[slot_node_[k]] += slot_weight_[k] * slot_P_[s];
}

template <int Dim>
void ImplicitSolver<Dim>::detect_contacts(double dt) {
  const ContactSettings<Dim>& cs = settings_.contact;
  const double h = grid_.cell_size();
  problem_.dt = dt;
  problem_.slots.clear();
  problem_.contacts.clear();
  slot_ref_.clear();
  slot_next_.clear();
  slot_start_.assign(1, 0);
  slot_node_.clear();
  slot_weight_.clear();
  slot_is_face_.clear();
  slot_key_.clear();
  const auto nn = static_cast<std::size_t>(grid_.node_count());
  if (node_stamp_.size() != nn) {
    node_stamp_.assign(nn, 0);
    slot_stamp_.assign(nn, 0);
    node_head_.assign(nn, -1);
    slot_head_.assign(nn, -1);
  }
  ++stamp_;
  const auto warm = [&](std::int64_t node, std::int32_t a, std::int32_t b) -> Vec<Dim> {
    const WarmImpulse<Dim> key{node, a, b, Vec<Dim>::Zero()};
    auto it = std::lower_bound(previous_.begin(), previous_.end(), key,
                               [](const WarmImpulse<Dim>& x, const WarmImpulse<Dim>& y) {
                                 return std::tie(x.node, x.a, x.b) < std::tie(y.node, y.a, y.b);
                               });
    if (it != previous_.end() && it->node == node && it->a == a && it->b == b) return it->impulse;
    return Vec<Dim>::Zero();
  };
  // Extent of point p's domain (reference half-edges r_i, the columns of `domain`, mapped by F)
  // along the unit vector n: sum_i |n . F r_i| [m] (lp |F^T n|_1 for a lattice square).
  const auto extent = [&](std::int64_t p, const Vec<Dim>& n) {
    return (points_.domain[p].transpose() * (points_.F[p].transpose() * n)).cwiseAbs().sum();
  };
  // 1. Grain fields carrying mass at each node: linked entries per global node.
  struct Entry {
    std::int32_t g, a, next;
  };
  std::vector<Entry> entries;
  std::vector<std::int64_t> shared;
  for (std::size_t g : local_) {
    const GrainWork& w = *work_[g];
    for (std::size_t a = 0; a < w.m.size(); ++a) {
      if (w.m[a] < w.contact_mass) continue;
      const std::int64_t n = w.node_global[a];
      if (node_stamp_[n] != stamp_) {
        node_stamp_[n] = stamp_;
        node_head_[n] = -1;
      }
      const std::int32_t head = node_head_[n];
      if (head >= 0 && entries[head].next < 0) shared.push_back(n);  // second field here
      entries.push_back({static_cast<std::int32_t>(g), static_cast<std::int32_t>(a), head});
      node_head_[n] = static_cast<std::int32_t>(entries.size()) - 1;
    }
  }
  // The rank solving the contacts at node n (docs/parallel.md): the owner of the lowest grain with
  // a field there (partition) or rank 0 (master); every rank sees all the fields at its nodes.
  const bool dist = distributed();
  const int me = dist ? comm_->rank() : 0;
  const auto node_rank = [&](std::int64_t n) {
    if (!dist) return 0;
    if (scheme_ == parallel::Scheme::kMaster) return 0;
    std::int32_t gmin = std::numeric_limits<std::int32_t>::max();
    for (std::int32_t e = node_head_[n]; e >= 0; e = entries[e].next)
      gmin = std::min(gmin, entries[e].g);
    return owner_[gmin];
  };
  // 2. Grain-grain contacts: every pair of fields at a shared node (three grains: three pairs).
  // Normals and gaps per node in parallel (threads), then the contacts in the serial order.
  struct Candidate {
    Entry A, B;
    Vec<Dim> normal;
    double gap;
  };
  std::vector<std::vector<Candidate>> found(shared.size());
  const auto nshared = static_cast<std::int64_t>(shared.size());
  // Work count (Comm::count_work): node fields, pairs and point pairs of the gaps examined here.
  double items = static_cast<double>(entries.size());
  ThreadedRegion threaded(&timers_, nshared > 256);
#pragma omp parallel for schedule(dynamic, 32) if (nshared > 256) reduction(+ : items)
  for (std::int64_t i = 0; i < nshared; ++i) {
    const std::int64_t n = shared[i];
    if (node_rank(n) != me) continue;
    for (std::int32_t e1 = node_head_[n]; e1 >= 0; e1 = entries[e1].next)
      for (std::int32_t e2 = entries[e1].next; e2 >= 0; e2 = entries[e2].next) {
        Entry A = entries[e1], B = entries[e2];
        if (A.g > B.g) std::swap(A, B);
        const GrainWork& wa = *work_[A.g];
        const GrainWork& wb = *work_[B.g];
        items += 1.0 + (wa.node_pts_start[A.a + 1] - wa.node_pts_start[A.a]) *
                           (wb.node_pts_start[B.a + 1] - wb.node_pts_start[B.a]);
        // Normal from A to B (method.md §4). g^X = sum_p m_p grad N_I(x_p) points OUT of grain X
        // (grad N_I at a point points toward the node), i.e. it is minus the gradient of X's mass
        // density, so n ∝ grad rho^B - grad rho^A = g^A - g^B.
        Vec<Dim> normal = wa.grad_m[A.a] - wb.grad_m[B.a];
        const double len = normal.norm();
        if (!(len > 1e-12 * (wa.grad_m[A.a].norm() + wb.grad_m[B.a].norm()))) continue;
        normal /= len;
        double gap = 0;
        if (cs.criterion == GapCriterion::kGap) {
          // Gap near the node: the smallest distance between a point domain of A and one of B
          // in the node's support, |x_q - x_p| minus both domains' extents along x_q - x_p
          // (a projection on the node's normal underestimates it where the normal is tilted).
          gap = std::numeric_limits<double>::infinity();
          for (std::int32_t k = wa.node_pts_start[A.a]; k < wa.node_pts_start[A.a + 1]; ++k) {
            const std::int64_t p = grains_[A.g].begin + wa.node_pts[k];
            for (std::int32_t l = wb.node_pts_start[B.a]; l < wb.node_pts_start[B.a + 1]; ++l) {
              const std::int64_t q = grains_[B.g].begin + wb.node_pts[l];
              const Vec<Dim> d = points_.x[q] - points_.x[p];
              const double len_d = d.norm();
              if (!(len_d > 0)) {
                gap = 0;
                continue;
              }
              const Vec<Dim> e = d / len_d;
              gap = std::min(gap, len_d - extent(p, e) - extent(q, e));
            }
          }
          gap = std::max(0.0, gap);
        }
        found[i].push_back({A, B, normal, gap});
      }
  }
  threaded.done();
  for (std::size_t i = 0; i < shared.size(); ++i)
    for (const Candidate& f : found[i]) {
      contact::Contact<Dim> c;
      c.a = slot_of(f.A.g, f.A.a);
      c.b = slot_of(f.B.g, f.B.a);
      c.normal = f.normal;
      c.gap = f.gap;
      c.friction = cs.friction[grains_[f.A.g].material * cs.materials + grains_[f.B.g].material];
      c.impulse = warm(shared[i], f.A.g, f.B.g);
      problem_.contacts.push_back(c);
    }
  // 3. Grain-wall contacts: grain nodes within wall_range cells of a wall; gap from the points.
  for (std::size_t wi = 0; wi < cs.walls.size(); ++wi) {
    const Wall<Dim>& wall = cs.walls[wi];
    for (std::size_t g : local_) {
      const GrainWork& w = *work_[g];
      if (cs.wall_points) {
        // Face contacts (ContactSettings::wall_points, docs/accuracy.md): per cell column
        // along the wall, the faces of the grain's points nearest the wall in that column (within
        // half a point's extent of the nearest) make one contact on their mean velocity; gap = the
        // mean distance of those faces from the wall (Signorini on the face velocity,
        // u_n + g/dt >= 0, method.md §4). One contact per column keeps the constraints
        // independent (one per face would give two per column of nodes when the material edge
        // lies on a grid line, a singular Delassus operator and a stalling Gauss-Seidel).
        struct Face {
          std::int64_t column, p;
          double dist, ext;
        };
        std::vector<Face> faces;
        for (std::int64_t p = grains_[g].begin; p < grains_[g].end; ++p) {
          const double e = extent(p, wall.normal);
          const double dface = wall.distance(points_.x[p], time_) - e;
          if (dface > cs.wall_range * h) continue;
          // Column index: the cell of the point along the wall's tangent axes.
          const Vec<Dim> xt = points_.x[p] - points_.x[p].dot(wall.normal) * wall.normal;
          std::int64_t column = 0;
          for (int d = 0; d < Dim; ++d)
            column = column * 1000003 + static_cast<std::int64_t>(std::floor(xt[d] / h));
          faces.push_back({column, p, dface, e});
        }
        items += static_cast<double>(faces.size());
        std::sort(faces.begin(), faces.end(), [](const Face& x, const Face& y) {
          return std::tie(x.column, x.dist, x.p) < std::tie(y.column, y.dist, y.p);
        });
        for (std::size_t f0 = 0; f0 < faces.size();) {
          std::size_t f1 = f0;
          std::vector<std::int64_t> pts;
          while (f1 < faces.size() && faces[f1].column == faces[f0].column) {
            if (faces[f1].dist <= faces[f0].dist + 0.5 * faces[f0].ext) pts.push_back(faces[f1].p);
            ++f1;
          }
          f0 = f1;
          Vec<Dim> x_face;
          const std::int32_t sb = face_slot(static_cast<std::int32_t>(g), pts, wall.normal, x_face);
          if (sb < 0) continue;
          // Warm-start key of a face contact: -1 - the grid cell of the mean face centre projected
          // on the wall's plane through the origin (the column: stable while the faces move
          // toward the wall and cross grid lines, when a lost warm start would hurt most).
          const Vec<Dim> xt = x_face - x_face.dot(wall.normal) * wall.normal;
          IVec<Dim> cell;
          for (int d = 0; d < Dim; ++d)
            cell[d] = std::clamp<std::int64_t>(
                static_cast<std::int64_t>(std::floor((xt[d] - grid_.origin()[d]) / h)), 0,
                grid_.cells()[d] - 1);
          slot_key_[sb] = -1 - grid_.node_index(cell);
          contact::Contact<Dim> c;
          c.a = -1;
          c.wall = static_cast<std::int32_t>(wi);
          c.b = sb;
          c.normal = wall.normal;
          c.wall_velocity = wall.velocity;
          c.gap = std::max(0.0, wall.distance(x_face, time_));
          c.friction = wall.friction;
          c.impulse =
              warm(slot_key_[sb], -1 - static_cast<std::int32_t>(wi), static_cast<std::int32_t>(g));
          problem_.contacts.push_back(c);
        }
        continue;
      }
      for (std::size_t a = 0; a < w.m.size(); ++a) {
        if (w.m[a] < w.contact_mass) continue;
        if (dist && node_rank(w.node_global[a]) != me) continue;
        const Vec<Dim> xn = grid_.node_position(grid_.node_coords(w.node_global[a]));
        if (wall.distance(xn, time_) > cs.wall_range * h) continue;
        items += 1.0 + (w.node_pts_start[a + 1] - w.node_pts_start[a]);
        double gap = std::numeric_limits<double>::infinity(), ext = 0;
        for (std::int32_t k = w.node_pts_start[a]; k < w.node_pts_start[a + 1]; ++k) {
          const std::int64_t p = grains_[g].begin + w.node_pts[k];
          const double e = extent(p, wall.normal);
          ext = std::max(ext, e);
          gap = std::min(gap, wall.distance(points_.x[p], time_) - e);
        }
        if (!std::isfinite(gap)) continue;
        // A node inside the grain may approach the wall until one whole point domain (twice the
        // largest half-extent e of its points along n) still fits between it and the wall:
        // gap >= d_node - 2 e. Without the 2 e the points between it and the wall are pushed
        // through by up to e (measured: up to 0.25 h, and the Hertz load sagging); with the
        // points' gap alone the layer down to the first node row would move with the wall.
        gap = std::max(gap, wall.distance(xn, time_) - 2 * ext);
        contact::Contact<Dim> c;
        c.a = -1;
        c.wall = static_cast<std::int32_t>(wi);
        c.b = slot_of(static_cast<std::int32_t>(g), static_cast<std::int32_t>(a));
        c.normal = wall.normal;
        c.wall_velocity = wall.velocity;
        c.gap = std::max(0.0, gap);
        c.friction = wall.friction;
        c.impulse = warm(w.node_global[a], -1 - static_cast<std::int32_t>(wi),
                         static_cast<std::int32_t>(g));
        problem_.contacts.push_back(c);
      }
    }
  }
  detect_items_ = items;
  // Warm start: the grains see the previous step's impulses from the first iteration on.
  std::vector<Vec<Dim>> slot_p(problem_.slots.size(), Vec<Dim>::Zero());
  for (const auto& c : problem_.contacts) {
    slot_p[c.b] += c.impulse;
    if (c.a >= 0) slot_p[c.a] -= c.impulse;
  }
  slot_P_ = slot_p;
  spread_slot_impulses();
  gs_converged_ = true;
  // Compliance groups: one per grain with contact slots when its linear solver is direct. Only
  // slots of contacts that may act in this step join (gap below a quarter cell, or an impulse
  // from the previous step): closing a quarter cell within one step takes a relative speed of
  // h / (4 dt), far above any in a quasi-static run. The other slots (most candidates of a dense
  // packing: their fields overlap a cell before the materials meet) keep the lumped 1/m_I, which
  // still holds them if a fast impact closes their gap.
  for (auto& w : work_) w->slots.clear();
  problem_.groups.clear();
  if (dist) return;  // lumped operator only (set_distribution)
  const bool compliance = cs.grain_compliance && settings_.linear_solver != LinearSolverKind::kCg;
  // A grain with face slots needs a group in any case: its face slots share nodes with each other
  // and with its node slots (lumped groups, G = E^T M^-1 E, when the compliance is not used).
  std::vector<char> has_face(work_.size(), 0);
  for (std::size_t s = 0; s < slot_ref_.size(); ++s)
    if (slot_is_face_[s]) has_face[slot_ref_[s].first] = 1;
  for (std::size_t g = 0; g < work_.size(); ++g) work_[g]->lumped_group = !compliance;
  if (compliance || std::find(has_face.begin(), has_face.end(), 1) != has_face.end()) {
    std::vector<char> near(slot_ref_.size(), 0);
    for (const auto& c : problem_.contacts)
      if (!compliance || c.gap <= 0.25 * h || c.impulse.squaredNorm() > 0) {
        near[c.b] = 1;
        if (c.a >= 0) near[c.a] = 1;
      }
    for (std::size_t s = 0; s < slot_ref_.size(); ++s) {
      if (slot_is_face_[s]) near[s] = 1;
      if (!has_face[slot_ref_[s].first]) near[s] = compliance && near[s];
    }
    for (std::size_t s = 0; s < slot_ref_.size(); ++s)
      if (near[s]) work_[slot_ref_[s].first]->slots.push_back(static_cast<std::int32_t>(s));
    for (std::size_t g = 0; g < work_.size(); ++g) {
      const auto& sl = work_[g]->slots;
      if (sl.empty()) continue;
      const auto gi = static_cast<std::int32_t>(problem_.groups.size());
      contact::Group group;
      group.slots = sl;
      for (std::size_t j = 0; j < sl.size(); ++j) {
        problem_.slots[sl[j]].group = gi;
        problem_.slots[sl[j]].local = static_cast<std::int32_t>(j);
      }
      problem_.groups.push_back(std::move(group));
    }
  }
}

template <int Dim>
void ImplicitSolver<Dim>::grain_compliance(std::size_t g) {
  // Z = A^-1 E (response of the grain's velocities to unit impulses at its slots; A^-1 -> M^-1
  // for a lumped group) and its slot rows G = E^T Z, from the factorisation of the current Newton
  // matrix. Column (j, d) of E is sum_k w_jk e_{a_jk, d} (one node of weight 1 for a node slot).
  GrainWork& w = *work_[g];
  if (!w.lumped_group) {
    if (!reuse_factor(w)) {
      if (!w.tangent_current) {
        with_shape(settings_.shape, [&](auto tag) { assemble_tangent<decltype(tag)>(g); });
      }
      if (!w.factor_current && !factorize_grain(g, dt_)) return;
    }
    // Z and G depend only on the factorisation and the slots (fixed within a step).
    if (w.z_factor == w.factor_count) return;
    w.z_factor = w.factor_count;
  }
  const auto k = static_cast<Eigen::Index>(w.slots.size());
  const auto ndof = static_cast<Eigen::Index>(w.m.size() * Dim);
  Eigen::MatrixXd& G = problem_.groups[problem_.slots[w.slots[0]].group].G;
  // With an LDL^T factorisation P A P^T = L D L^T, G = E^T A^-1 E = Y^T D^-1 Y with
  // Y = L^-1 P E: forward substitutions only, and Y stays sparse because E's columns touch a
  // few nodes (the triangular solve skips zero entries). 4x cheaper than Z = A^-1 E for a CPDI
  // disk (docs/accuracy.md, cost); the velocity response then takes one back substitution.
  w.z_forward = !w.lumped_group && settings_.linear_solver == LinearSolverKind::kLdlt;
  // Column (j, d) of E, without the prescribed components (which do not respond).
  w.Z.setZero(ndof, Dim * k);
  for (Eigen::Index j = 0; j < k; ++j) {
    const std::size_t s = static_cast<std::size_t>(w.slots[j]);
    for (int d = 0; d < Dim; ++d)
      for (std::int32_t q = slot_start_[s]; q < slot_start_[s + 1]; ++q) {
        const std::int32_t a = slot_node_[q];
        if (w.mask[a] & (1u << d)) continue;
        w.Z(a * Dim + d, Dim * j + d) = slot_weight_[q] / (w.lumped_group ? w.m[a] : 1.0);
      }
  }
  if (w.z_forward) {
    w.Z = w.ldlt.permutationP() * w.Z;
    w.ldlt.matrixL().solveInPlace(w.Z);
    G.noalias() = w.Z.transpose() * w.ldlt.vectorD().cwiseInverse().asDiagonal() * w.Z;
    return;
  }
  if (!w.lumped_group)
    for (Eigen::Index c = 0; c < Dim * k; ++c)
      if (w.Z.col(c).squaredNorm() > 0) w.Z.col(c) = linear_solve(g, w.Z.col(c));
  G.resize(Dim * k, Dim * k);
  for (Eigen::Index i = 0; i < k; ++i) {
    const std::size_t s = static_cast<std::size_t>(w.slots[i]);
    G.middleRows(Dim * i, Dim) =
        slot_weight_[slot_start_[s]] * w.Z.middleRows(slot_node_[slot_start_[s]] * Dim, Dim);
    for (std::int32_t q = slot_start_[s] + 1; q < slot_start_[s + 1]; ++q)
      G.middleRows(Dim * i, Dim) += slot_weight_[q] * w.Z.middleRows(slot_node_[q] * Dim, Dim);
  }
}

template <int Dim>
double ImplicitSolver<Dim>::update_contacts(StepStats& stats) {
  // Response of each grain: its compliance group (exact, linearised) or the lumped 1/m_I.
  const auto ngroups = static_cast<std::int64_t>(problem_.groups.size());
  ThreadedRegion threaded(&timers_, ngroups > 1);
#pragma omp parallel for schedule(dynamic, 1) if (ngroups > 1)
  for (std::int64_t gi = 0; gi < ngroups; ++gi)
    grain_compliance(static_cast<std::size_t>(slot_ref_[problem_.groups[gi].slots[0]].first));
  threaded.done();
  for (const auto& w : work_)
    if (!w->failure.empty()) return 1.0;
  // Free velocities: the grains' current iterates without their contact impulses (method.md §4).
  for (std::size_t s = 0; s < slot_ref_.size(); ++s) {
    const GrainWork& w = *work_[slot_ref_[s].first];
    const std::int32_t a = slot_ref_[s].second;
    auto& slot = problem_.slots[s];
    if (!slot_is_face_[s]) slot.mass = w.m[a];
    if (slot.group < 0) {  // a node slot alone at its node (face slots are always grouped)
      slot.v_free = w.v[a] - slot_P_[s] / w.m[a];
    } else {
      const auto& group = problem_.groups[slot.group];
      slot.v_free = slot_is_face_[s] ? slot_velocity(s) : w.v[a];
      for (std::size_t j = 0; j < group.slots.size(); ++j)
        slot.v_free -=
            group.G.template block<Dim, Dim>(Dim * slot.local, Dim * j) * slot_P_[group.slots[j]];
    }
  }
  std::vector<Vec<Dim>> old(problem_.contacts.size());
  for (std::size_t c = 0; c < old.size(); ++c) old[c] = problem_.contacts[c].impulse;
  contact::GsResult r;
  // Debugging (docs/contact.md): MPMCD_WRITE_STALLED_PROBLEM=<folder> writes each problem whose
  // Gauss-Seidel does not converge, as given (warm start), for contact::read_problem.
  static const char* const stalled_dir = std::getenv("MPMCD_WRITE_STALLED_PROBLEM");
  contact::Problem<Dim> given;
  if (stalled_dir) given = problem_;
  {
    ScopedStage t(&timers_, "contact.gs");
    r = contact::solve_gauss_seidel(problem_, gs_settings());
  }
  if (stalled_dir && !r.converged) {
    static int written = 0;
    contact::write_problem(given, fmt::format("{}/stalled_{:04d}.txt", stalled_dir, written++));
  }
  stats.gs_sweeps += r.sweeps;
  stats.gs_error = r.error;
  gs_converged_ = r.converged;
  double num = 0, den = 0;
  std::vector<Vec<Dim>> slot_p(problem_.slots.size(), Vec<Dim>::Zero());
  for (std::size_t c = 0; c < old.size(); ++c) {
    const auto& ct = problem_.contacts[c];
    num += (ct.impulse - old[c]).squaredNorm();
    den += ct.impulse.squaredNorm();
    slot_p[ct.b] += ct.impulse;
    if (ct.a >= 0) slot_p[ct.a] -= ct.impulse;
  }
  // The new impulses enter the grains' residuals; their velocities take the linearised response
  // (v += Z dP, or the lumped v = v_free + P/m), and a grain whose impulses changed iterates again.
  std::vector<double> dv2(work_.size(), -1.0);
  for (std::size_t s = 0; s < slot_ref_.size(); ++s) {
    GrainWork& w = *work_[slot_ref_[s].first];
    const std::int32_t a = slot_ref_[s].second;
    if (slot_p[s] == slot_P_[s] || problem_.slots[s].group >= 0) continue;
    slot_P_[s] = slot_p[s];
    w.P[a] = slot_p[s];
    const Vec<Dim> v_new = problem_.slots[s].v_free + slot_p[s] / w.m[a];
    double& acc = dv2[slot_ref_[s].first];
    acc = std::max(acc, 0.0) + w.m[a] * (v_new - w.v[a]).squaredNorm();
    w.v[a] = v_new;
  }
  for (const auto& group : problem_.groups) {
    const std::int32_t g = slot_ref_[group.slots[0]].first;
    GrainWork& w = *work_[g];
    Eigen::VectorXd dP(Dim * static_cast<Eigen::Index>(group.slots.size()));
    bool changed = false;
    for (std::size_t j = 0; j < group.slots.size(); ++j) {
      const std::int32_t s = group.slots[j];
      const Vec<Dim> d = slot_p[s] - slot_P_[s];
      changed = changed || d != Vec<Dim>::Zero();
      dP.template segment<Dim>(Dim * static_cast<Eigen::Index>(j)) = d;
      slot_P_[s] = slot_p[s];
    }
    if (!changed) continue;
    // dv = A^-1 E dP = Z dP, or P^T L^-T D^-1 Y dP with the forward-only response.
    Eigen::VectorXd dv = w.Z * dP;
    if (w.z_forward) {
      dv = w.ldlt.vectorD().cwiseInverse().asDiagonal() * dv;
      w.ldlt.matrixU().solveInPlace(dv);
      dv = w.ldlt.permutationPinv() * dv;
    }
    double acc = 0;
    for (std::size_t a = 0; a < w.m.size(); ++a) {
      const Vec<Dim> d = dv.template segment<Dim>(static_cast<Eigen::Index>(a * Dim));
      w.v[a] += d;
      acc += w.m[a] * d.squaredNorm();
    }
    dv2[g] = acc;
  }
  if (!problem_.groups.empty()) spread_slot_impulses();
  for (std::size_t g = 0; g < work_.size(); ++g)
    if (dv2[g] >= 0.0) {
      work_[g]->converged = false;
      work_[g]->solved_once = true;
      work_[g]->dv_norm = std::sqrt(dv2[g]);
    }
  if (num == 0.0) return gs_converged_ ? 0.0 : 1.0;
  const double change = std::sqrt(num) / std::sqrt(std::max(den, 1e-300));
  return gs_converged_ ? change : std::max(change, 1.0);
}

template <int Dim>
template <class S1>
typename ImplicitSolver<Dim>::G2P ImplicitSolver<Dim>::g2p_point(const GrainWork& w, std::int64_t p,
                                                                 std::int64_t i) const {
  constexpr int K = grid::ShapeOf<Dim, S1>::type::K;
  const double alpha = settings_.flip;
  Vec<Dim> dx = Vec<Dim>::Zero(), dv = Vec<Dim>::Zero(), vpic = Vec<Dim>::Zero();
  Mat<Dim> grad_v = Mat<Dim>::Zero();
  for (int a = 0; a < K; ++a) {
    const std::int32_t n = w.pt_node[i * K + a];
    if (n < 0) continue;
    const double N = w.pt_N[i * K + a];
    dx += N * w.du[n];
    dv += N * (w.v[n] - w.v_p2g[n]);
    vpic += N * w.v[n];
    if (settings_.affine) grad_v += w.v[n] * w.pt_dN[i * K + a].transpose();
  }
  // v_p = flip (v_p + sum N dv) + (1 - flip) sum N v (method.md §2).
  return {dx, alpha * (points_.v[p] + dv) + (1.0 - alpha) * vpic, grad_v};
}

template <int Dim>
template <class S1>
void ImplicitSolver<Dim>::commit_grain(std::size_t g) {
  const points::Grain& gr = grains_[g];
  const GrainWork& w = *work_[g];
  for (std::int64_t i = 0; i < gr.size(); ++i) {
    const std::int64_t p = gr.begin + i;
    const G2P u = g2p_point<S1>(w, p, i);
    // Velocity gradient at x^{n+1} for the next affine P2G: grad_{x^n} v dF^-1 (Settings::affine).
    if (settings_.affine) points_.L[p] = u.grad_v * dF_inv_T_[p].transpose();
    // G2P: x_p += sum N du (method.md §2).
    points_.x[p] += u.dx;
    points_.v[p] = u.v;
    points_.F[p] = F_trial_[p];
    points_.sigma[p] = sigma_trial_[p];
    if constexpr (Dim == 2) points_.sigma_zz[p] = sigma_zz_trial_[p];
    points_.volume[p] = J_trial_[p] * points_.volume0[p];
  }
}

template <int Dim>
template <class S1>
void ImplicitSolver<Dim>::check_next_positions(std::size_t g) {
  using Shape = typename grid::ShapeOf<Dim, S1>::type;
  GrainWork& w = *work_[g];
  const points::Grain& gr = grains_[g];
  const double h = grid_.cell_size();
  Shape ps;
  w.kin_points = 0;
  for (std::int64_t i = 0; i < gr.size(); ++i) {
    const std::int64_t p = gr.begin + i;
    const G2P u = g2p_point<S1>(w, p, i);  // as commit_grain: the same position and velocity
    w.kin_points += 0.5 * points_.mass[p] * u.v.squaredNorm();
    const Vec<Dim> x = points_.x[p] + u.dx;
    // A domain stretched too far is left to the next step's set-up (a retryable failure there);
    // its position must still lie on the grid.
    const bool off =
        !x.allFinite() ||
        (ps.eval(x, grid_.origin(), h, gr.half_width, F_trial_[p] * points_.domain[p])
             ? ((ps.first.array() < 0).any() ||
                ((ps.first.array() + S1::kNodes - 1) >= grid_.nodes_per_axis().array()).any())
             : !grid_.inside(x, 0.0));
    if (off) {
      w.failure =
          "material point left the grid (or came within the shape-function support of its edge)";
      w.retryable = false;
      w.fail_point = p;
      return;
    }
  }
}

template <int Dim>
void ImplicitSolver<Dim>::commit() {
  if (!step_ready_) throw std::logic_error("ImplicitSolver::commit without a converged step");
  ScopedStage t(&timers_, "g2p");
  const std::size_t no = owned_.size();
  const ThreadedRegion threaded(&timers_, no > 1);
#pragma omp parallel for schedule(dynamic, 1) if (no > 1)
  for (std::size_t i = 0; i < no; ++i) {
    const std::size_t g = owned_[i];
    with_shape(settings_.shape, [&](auto tag) { commit_grain<decltype(tag)>(g); });
  }
  points_.history.swap(history_trial_);
  step_ready_ = false;
}

template <int Dim>
double ImplicitSolver<Dim>::field_mass(std::size_t g) const {
  double m = 0;
  for (double x : work_.at(g)->m) m += x;
  return m;
}

template <int Dim>
Vec<Dim> ImplicitSolver<Dim>::field_momentum(std::size_t g) const {
  Vec<Dim> p = Vec<Dim>::Zero();
  const GrainWork& w = *work_.at(g);
  for (std::size_t a = 0; a < w.m.size(); ++a) p += w.m[a] * w.v[a];
  return p;
}

// ---------------------------------------------------------------------------------------------
// Distributed step (docs/parallel.md).

namespace {
template <class T>
T take(parallel::Buffer& b) {
  return b.get<T>();
}
}  // namespace

template <int Dim>
void ImplicitSolver<Dim>::set_distribution(const parallel::Comm* comm, std::vector<int> owner,
                                           parallel::Scheme scheme) {
  if (owner.size() != grains_.size())
    throw std::invalid_argument("ImplicitSolver::set_distribution: one owner per grain");
  comm_ = comm;
  owner_ = std::move(owner);
  scheme_ = scheme;
  if (distributed() && settings_.contact.enabled && settings_.contact.wall_points)
    throw InputError("", 0, "contact.wall_contact",
                     "wall contact at the points' faces (\"points\") runs on one rank for now: "
                     "use wall_contact = \"nodes\" on several ranks");
  if (distributed() && settings_.contact.enabled && settings_.contact.grain_compliance &&
      settings_.linear_solver != LinearSolverKind::kCg)
    throw InputError("", 0, "contact.delassus",
                     "the grain compliance operator couples all contacts of a grain and is not "
                     "available on more than one rank yet: use delassus = \"lumped\" (or run on "
                     "one rank)");
  // Every rank's warm-start impulses to every rank: the contacts of a node move with its lowest
  // grain, and the new owner must find their impulses (as after a restart, which reads them all).
  if (distributed()) set_warm_start(gather_warm_start());
}

template <int Dim>
std::vector<WarmImpulse<Dim>> ImplicitSolver<Dim>::gather_warm_start() const {
  if (!distributed()) return previous_;
  parallel::Buffer mine;
  for (const auto& w : previous_) {
    mine.put(w.node);
    mine.put(w.a);
    mine.put(w.b);
    for (int d = 0; d < Dim; ++d) mine.put(w.impulse[d]);
  }
  std::vector<WarmImpulse<Dim>> all;
  for (const auto& bytes : comm_->allgather(mine.bytes())) {
    parallel::Buffer b;
    b.bytes() = bytes;
    while (!b.done()) {
      WarmImpulse<Dim> w;
      w.node = b.get<std::int64_t>();
      w.a = b.get<std::int32_t>();
      w.b = b.get<std::int32_t>();
      for (int d = 0; d < Dim; ++d) w.impulse[d] = b.get<double>();
      all.push_back(w);
    }
  }
  sort_unique(all);
  return all;
}

template <int Dim>
std::vector<double> ImplicitSolver<Dim>::take_grain_work() {
  std::vector<double> w(grains_.size() * parallel::kWorkPhases, 0.0);
  grain_work_.resize(w.size(), 0.0);
  w.swap(grain_work_);
  return w;
}

template <int Dim>
double& ImplicitSolver<Dim>::phase_work(std::size_t g, int iteration) {
  return grain_work_[g * parallel::kWorkPhases +
                     static_cast<std::size_t>(std::min(iteration, parallel::kWorkPhases - 1))];
}

template <int Dim>
bool ImplicitSolver<Dim>::sync_failure(StepStats& stats, std::int64_t lowest) {
  // The lowest failing grain over all ranks (reduced here unless given), its message from its
  // owner.
  ScopedStage tc(&timers_, "newton.check.comm");
  constexpr std::int64_t kNone = std::numeric_limits<std::int64_t>::max();
  std::vector<std::int64_t> g{lowest};
  if (lowest < 0) {
    g[0] = stats.failure.empty() ? kNone : stats.grain;
    comm_->min(g);
  }
  if (g[0] == kNone) return false;
  const int root = owner_[static_cast<std::size_t>(g[0])];
  parallel::Buffer b;
  if (comm_->rank() == root) {
    b.put(stats.point);
    b.put(static_cast<std::int32_t>(stats.retryable));
    b.bytes().insert(b.bytes().end(), stats.failure.begin(), stats.failure.end());
  }
  comm_->broadcast(b.bytes(), root);
  stats.grain = g[0];
  stats.point = take<std::int64_t>(b);
  stats.retryable = take<std::int32_t>(b) != 0;
  const std::size_t head = sizeof(std::int64_t) + sizeof(std::int32_t);
  stats.failure.assign(b.bytes().begin() + static_cast<std::ptrdiff_t>(head), b.bytes().end());
  return true;
}

template <int Dim>
void ImplicitSolver<Dim>::exchange_entries() {
  // 1. Node boxes of every grain (each rank sends its own: a few integers per grain).
  const int me = comm_->rank(), np = comm_->size();
  const std::size_t ng = grains_.size();
  const ContactSettings<Dim>& cs = settings_.contact;
  const double h = grid_.cell_size();
  parallel::Buffer mine;
  for (std::size_t g : owned_) {
    const GrainWork& w = *work_[g];
    mine.put(static_cast<std::int32_t>(g));
    std::array<std::int64_t, 2 * Dim> box;
    for (int d = 0; d < Dim; ++d) {
      box[d] = grains_[g].size() > 0 ? w.box_lo[d] : 0;
      box[Dim + d] = grains_[g].size() > 0 ? w.box_lo[d] + w.box_n[d] - 1 : -1;
    }
    mine.put(box);
  }
  const auto all = comm_->allgather(mine.bytes());
  boxes_.assign(ng, {});
  for (int r = 0; r < np; ++r) {
    parallel::Buffer b;
    b.bytes() = all[r];
    while (!b.done()) {
      const auto g = take<std::int32_t>(b);
      boxes_[g] = take<std::array<std::int64_t, 2 * Dim>>(b);
    }
  }
  const auto overlap = [&](std::size_t g1, std::size_t g2) {
    for (int d = 0; d < Dim; ++d)
      if (boxes_[g1][d] > boxes_[g2][Dim + d] || boxes_[g2][d] > boxes_[g1][Dim + d]) return false;
    return true;
  };
  const auto inside = [&](std::size_t g, const IVec<Dim>& c) {
    for (int d = 0; d < Dim; ++d)
      if (c[d] < boxes_[g][d] || c[d] > boxes_[g][Dim + d]) return false;
    return true;
  };
  // 2. Neighbours (symmetric): ranks owning a grain whose box meets one of mine (partition); the
  // master and every other rank (master).
  const bool master = scheme_ == parallel::Scheme::kMaster;
  std::vector<std::vector<std::size_t>> near(ng);  // owned grain -> grains whose boxes meet it
  std::vector<char> is_nb(static_cast<std::size_t>(np), 0);
  for (std::size_t g : owned_)
    for (std::size_t g2 = 0; g2 < ng; ++g2) {
      if (g2 == g || !overlap(g, g2)) continue;
      if (master || owner_[g2] != me) near[g].push_back(g2);
      if (!master && owner_[g2] != me) is_nb[owner_[g2]] = 1;
    }
  if (master)
    for (int r = 0; r < np; ++r) is_nb[r] = me == 0 ? r != 0 : r == 0;
  neighbours_.clear();
  for (int r = 0; r < np; ++r)
    if (is_nb[r]) neighbours_.push_back(r);
  // 3. Each owned grain's contact-capable nodes (mass above the threshold) that another rank may
  // need: inside the box of a grain owned there (partition); inside any other grain's box or
  // within wall range (master, to rank 0). Sent with the points touching them (x, F).
  std::map<int, parallel::Buffer> out;
  for (int r : neighbours_) out[r];
  std::vector<std::int32_t> sel, pts;
  std::vector<char> dest(static_cast<std::size_t>(np));
  // Counted work (Comm::count_work): grain pairs tested above; node-in-box and wall tests, values
  // packed.
  comm_->count_work(kPairTestWeight * static_cast<double>(owned_.size() * ng));
  double tests = 0, items = 0;
  for (std::size_t g : owned_) {
    const GrainWork& w = *work_[g];
    if (master && me == 0) break;
    for (int r : neighbours_) {
      sel.clear();
      for (std::size_t a = 0; a < w.m.size(); ++a) {
        if (w.m[a] < w.contact_mass) continue;
        const IVec<Dim> c = w.node_box[a] + w.box_lo;
        bool send = false;
        for (std::size_t g2 : near[g]) {
          tests += 1;
          if ((master || owner_[g2] == r) && inside(g2, c)) {
            send = true;
            break;
          }
        }
        if (!send && master) {
          const Vec<Dim> xn = grid_.node_position(c);
          tests += static_cast<double>(cs.walls.size());
          for (const auto& wall : cs.walls)
            if (wall.distance(xn, time_) <= cs.wall_range * h) send = true;
        }
        if (send) sel.push_back(static_cast<std::int32_t>(a));
      }
      if (sel.empty()) continue;
      parallel::Buffer& b = out[r];
      b.put(static_cast<std::int32_t>(g));
      b.put(w.contact_mass);
      b.put(static_cast<std::int32_t>(sel.size()));
      pts.clear();
      for (std::int32_t a : sel) {
        b.put(w.node_global[a]);
        b.put(w.m[a]);
        b.put(w.grad_m[a]);
        b.put(static_cast<std::int32_t>(w.node_pts_start[a + 1] - w.node_pts_start[a]));
        for (std::int32_t k = w.node_pts_start[a]; k < w.node_pts_start[a + 1]; ++k) {
          b.put(w.node_pts[k]);
          pts.push_back(w.node_pts[k]);
        }
      }
      std::sort(pts.begin(), pts.end());
      pts.erase(std::unique(pts.begin(), pts.end()), pts.end());
      b.put(static_cast<std::int32_t>(pts.size()));
      for (std::int32_t i : pts) {
        const std::int64_t p = grains_[g].begin + i;
        b.put(i);
        b.put(points_.x[p]);
        b.put(points_.F[p]);
      }
      items += static_cast<double>(sel.size() + 2 * pts.size());
    }
  }
  comm_->count_work(kBoxTestWeight * tests + kExchangeItemWeight * items);
  auto in = comm_->exchange(out, neighbours_);
  // 4. Ghost grains: their sent nodes as a field of this rank (mass, mass gradient, points).
  for (auto& [r, b] : in) {
    while (!b.done()) {
      const auto g = static_cast<std::size_t>(take<std::int32_t>(b));
      GrainWork& w = *work_[g];
      role_[g] = 2;
      w.contact_mass = take<double>(b);
      const auto k = static_cast<std::size_t>(take<std::int32_t>(b));
      w.m.resize(k);
      w.grad_m.resize(k);
      w.node_global.resize(k);
      w.node_pts_start.assign(k + 1, 0);
      w.node_pts.clear();
      for (std::size_t a = 0; a < k; ++a) {
        w.node_global[a] = take<std::int64_t>(b);
        w.m[a] = take<double>(b);
        w.grad_m[a] = take<Vec<Dim>>(b);
        const auto npts = take<std::int32_t>(b);
        for (std::int32_t j = 0; j < npts; ++j) w.node_pts.push_back(take<std::int32_t>(b));
        w.node_pts_start[a + 1] = static_cast<std::int32_t>(w.node_pts.size());
      }
      const auto npts = take<std::int32_t>(b);
      for (std::int32_t j = 0; j < npts; ++j) {
        const std::int64_t p = grains_[g].begin + take<std::int32_t>(b);
        points_.x[p] = take<Vec<Dim>>(b);
        points_.F[p] = take<Mat<Dim>>(b);
      }
      w.v.assign(k, Vec<Dim>::Zero());
      w.P.assign(k, Vec<Dim>::Zero());
      w.mask.assign(k, 0);
      comm_->count_work(kExchangeItemWeight * static_cast<double>(k + w.node_pts.size() + npts));
    }
  }
  local_.clear();
  for (std::size_t g = 0; g < ng; ++g)
    if (role_[g]) local_.push_back(g);
}

template <int Dim>
void ImplicitSolver<Dim>::exchange_requests() {
  // The slots of ghost grains in this rank's contacts: ask their owners for their velocities
  // every iteration, and hand them the warm-start impulse (owners then serve those slots).
  std::vector<std::int64_t> count{static_cast<std::int64_t>(problem_.contacts.size())};
  comm_->sum(count);
  have_contacts_ = count[0] > 0;
  links_.clear();
  std::map<int, parallel::Buffer> out;
  for (int r : neighbours_) {
    links_[r];
    out[r];
  }
  comm_->count_work(kExchangeItemWeight * static_cast<double>(slot_ref_.size()));
  for (std::size_t s = 0; s < slot_ref_.size(); ++s) {
    const auto [g, a] = slot_ref_[s];
    if (role_[g] != 2) continue;
    const int r = owner_[g];
    links_.at(r).ask.push_back(static_cast<std::int32_t>(s));
    parallel::Buffer& b = out.at(r);
    b.put(g);
    b.put(work_[g]->node_global[a]);
    b.put(work_[g]->P[a]);
  }
  auto in = comm_->exchange(out, neighbours_);
  for (auto& [r, b] : in) {
    Link& link = links_.at(r);
    while (!b.done()) {
      const auto g = take<std::int32_t>(b);
      const auto node = take<std::int64_t>(b);
      const Vec<Dim> P = take<Vec<Dim>>(b);
      GrainWork& w = *work_[g];
      const IVec<Dim> c = grid_.node_coords(node) - w.box_lo;
      std::int64_t idx = 0, stride = 1;
      for (int d = 0; d < Dim; ++d) {
        idx += c[d] * stride;
        stride *= w.box_n[d];
      }
      const std::int32_t a = w.box_to_active[static_cast<std::size_t>(idx)];
      w.P[a] = P;
      link.serve.emplace_back(g, a);
    }
  }
  comm_->count_work(kExchangeItemWeight * static_cast<double>(link_sizes().first));
}

template <int Dim>
std::pair<std::size_t, std::size_t> ImplicitSolver<Dim>::link_sizes() const {
  std::size_t serve = 0, ask = 0;
  for (const auto& [r, link] : links_) {
    serve += link.serve.size();
    ask += link.ask.size();
  }
  return {serve, ask};
}

template <int Dim>
double ImplicitSolver<Dim>::update_contacts_distributed(StepStats& stats) {
  // Counted work (Comm::count_work) of the bookkeeping around the solve: slots served to and
  // asked from other ranks, this rank's slots, one pass over its contacts after the solve.
  const auto [n_serve, n_ask] = link_sizes();
  const auto n_slots = static_cast<double>(problem_.slots.size());
  // 1. Velocities of the ghost slots from their owners (boundary data, neighbours only).
  {
    ScopedStage tc(&timers_, "contact.solve.comm");
    std::map<int, parallel::Buffer> out;
    for (const auto& [r, link] : links_) {
      parallel::Buffer& b = out[r];
      for (const auto& [g, a] : link.serve) b.put(work_[g]->v[a]);
    }
    comm_->count_work(kExchangeItemWeight * static_cast<double>(n_serve));
    auto in = comm_->exchange(out, neighbours_);
    for (const auto& [r, link] : links_) {
      parallel::Buffer& b = in.at(r);
      for (std::int32_t s : link.ask) {
        const auto [g, a] = slot_ref_[s];
        work_[g]->v[a] = take<Vec<Dim>>(b);
      }
    }
  }
  // 2. Free velocities (lumped operator) of this rank's slots, as in update_contacts.
  for (std::size_t s = 0; s < slot_ref_.size(); ++s) {
    const GrainWork& w = *work_[slot_ref_[s].first];
    const std::int32_t a = slot_ref_[s].second;
    auto& slot = problem_.slots[s];
    slot.mass = w.m[a];
    slot.v_free = w.v[a] - w.P[a] / w.m[a];
  }
  std::vector<Vec<Dim>> old(problem_.contacts.size());
  for (std::size_t c = 0; c < old.size(); ++c) old[c] = problem_.contacts[c].impulse;
  comm_->count_work(kExchangeItemWeight * (static_cast<double>(n_ask) + n_slots));
  // 3. Gauss-Seidel: each rank on its nodes' contacts (no slot is shared between ranks), the
  // error summed over ranks before every test (partition); all contacts on rank 0 (master).
  contact::GsResult r;
  if (scheme_ == parallel::Scheme::kPartition) {
    // Counted work before each error test: one pass over this rank's contacts for the first
    // test, two (the sweep and its error) for the others.
    double passes = 1;
    const contact::ErrorReduce reduce = [&](double& num, double& den) {
      comm_->count_work(kContactPassWeight * passes *
                        static_cast<double>(problem_.contacts.size()));
      passes = 2;
      ScopedStage tc(&timers_, "contact.solve.comm");
      std::vector<double> v{num, den};
      comm_->sum(v);
      num = v[0];
      den = v[1];
    };
    ScopedStage t(&timers_, "contact.gs");
    r = contact::solve_gauss_seidel(problem_, gs_settings(), reduce);
  } else {
    r.converged = true;  // ranks other than 0 hold no contact
    if (comm_->rank() == 0) {
      ScopedStage t(&timers_, "contact.gs");
      r = contact::solve_gauss_seidel(problem_, gs_settings());
      comm_->count_work(kContactPassWeight * (1.0 + 2.0 * r.sweeps) *
                        static_cast<double>(problem_.contacts.size()));
    }
    ScopedStage tc(&timers_, "contact.solve.comm");
    std::vector<double> v{static_cast<double>(r.sweeps), r.error, r.converged ? 0.0 : 1.0};
    comm_->max(v);
    r.sweeps = static_cast<int>(v[0]);
    r.error = v[1];
    r.converged = v[2] == 0.0;
  }
  stats.gs_sweeps += r.sweeps;
  stats.gs_error = r.error;
  gs_converged_ = r.converged;
  double num = 0, den = 0;
  std::vector<Vec<Dim>> slot_p(problem_.slots.size(), Vec<Dim>::Zero());
  for (std::size_t c = 0; c < old.size(); ++c) {
    const auto& ct = problem_.contacts[c];
    num += (ct.impulse - old[c]).squaredNorm();
    den += ct.impulse.squaredNorm();
    slot_p[ct.b] += ct.impulse;
    if (ct.a >= 0) slot_p[ct.a] -= ct.impulse;
  }
  // 4. New impulses into the grains: own slots here, ghost slots sent back to their owners.
  std::vector<double> dv2(work_.size(), -1.0);
  const auto apply = [&](std::int32_t g, std::int32_t a, const Vec<Dim>& P) {
    GrainWork& w = *work_[g];
    if (P == w.P[a]) return;
    const Vec<Dim> v_free = w.v[a] - w.P[a] / w.m[a];
    w.P[a] = P;
    const Vec<Dim> v_new = v_free + P / w.m[a];
    double& acc = dv2[g];
    acc = std::max(acc, 0.0) + w.m[a] * (v_new - w.v[a]).squaredNorm();
    w.v[a] = v_new;
  };
  for (std::size_t s = 0; s < slot_ref_.size(); ++s)
    if (role_[slot_ref_[s].first] == 1) apply(slot_ref_[s].first, slot_ref_[s].second, slot_p[s]);
  {
    ScopedStage tc(&timers_, "contact.solve.comm");
    std::map<int, parallel::Buffer> out;
    for (const auto& [rk, link] : links_) {
      parallel::Buffer& b = out[rk];
      for (std::int32_t s : link.ask) {
        b.put(slot_p[s]);
        work_[slot_ref_[s].first]->P[slot_ref_[s].second] = slot_p[s];
      }
    }
    comm_->count_work(kExchangeItemWeight * (static_cast<double>(old.size() + n_ask) + n_slots));
    auto in = comm_->exchange(out, neighbours_);
    for (const auto& [rk, link] : links_) {
      parallel::Buffer& b = in.at(rk);
      for (const auto& [g, a] : link.serve) apply(g, a, take<Vec<Dim>>(b));
    }
    comm_->count_work(kExchangeItemWeight * static_cast<double>(n_serve));
    std::vector<double> v{num, den};
    comm_->sum(v);
    num = v[0];
    den = v[1];
  }
  for (std::size_t g : owned_)
    if (dv2[g] >= 0.0) {
      work_[g]->converged = false;
      work_[g]->solved_once = true;
      work_[g]->dv_norm = std::sqrt(dv2[g]);
    }
  if (num == 0.0) return gs_converged_ ? 0.0 : 1.0;
  const double change = std::sqrt(num) / std::sqrt(std::max(den, 1e-300));
  return gs_converged_ ? change : std::max(change, 1.0);
}

template class ImplicitSolver<2>;
template class ImplicitSolver<3>;

}  // namespace mpmcd::mpm
