// The grain field's transfers (multi-field MPM, method.md §1-2): P2G with the active nodes and the
// sparse pattern of the Newton matrix (p2g), G2P (g2p_point, g2p_commit) and its check of the next
// positions (g2p_check), and the field's diagnostics (include/mpmcd/mpm/grain_field.hpp).
#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "mpmcd/mpm/grain_field.hpp"

namespace mpmcd::mpm {

void SparseLdlt::map_pattern(const SpMat& A) {
  from_a_.clear();
  if (m_P.size() == 0) return;  // no ordering: factorize_mapped is Eigen's factorize
  // A with the positions of its stored values as values, permuted as Eigen's factorize permutes
  // A (SimplicialCholeskyBase::factorize): each value of P A P^T's upper triangle then names the
  // value of A it is copied from.
  SpMat idx = A;
  for (Eigen::Index k = 0; k < idx.nonZeros(); ++k) idx.valuePtr()[k] = static_cast<double>(k);
  ap_.resize(A.rows(), A.cols());
  ap_.selfadjointView<Eigen::Upper>() = idx.selfadjointView<UpLo>().twistedBy(m_P);
  from_a_.resize(static_cast<std::size_t>(ap_.nonZeros()));
  for (std::size_t k = 0; k < from_a_.size(); ++k) from_a_[k] = static_cast<int>(ap_.valuePtr()[k]);
}

void SparseLdlt::factorize_mapped(const SpMat& A) {
  if (from_a_.empty()) {
    factorize(A);
    return;
  }
  const double* a = A.valuePtr();
  double* v = ap_.valuePtr();
  for (std::size_t k = 0; k < from_a_.size(); ++k) v[k] = a[from_a_[k]];
  factorize_preordered<true>(ap_);
}

namespace {
template <class T>
void reset(std::vector<T>& v, std::size_t n, const T& value) {
  v.assign(n, value);
}

// A point whose support lost nodes (weight below the mass cut, node[a] < 0) keeps the
// reproduction of linear fields by the smallest change of its kept weights and gradients
// (docs/accuracy.md, "Dropped support nodes"): with r_a = x_a - x_p over the kept nodes,
// S0 = sum N_a, S1 = sum N_a r_a, S2 = sum N_a r_a r_a^T, g = sum grad N_a, G = sum r_a grad N_a^T,
//   N'_a = N_a (c + b.r_a):          sum N'_a = 1, sum N'_a r_a = 0 (x_p interpolated exactly),
//   grad N'_a = grad N_a + N_a (alpha + B r_a):  sum grad N'_a = 0, sum r_a grad N'_a^T = I,
// i.e. b = -c S2^-1 S1, c = 1 / (S0 - S1.S2^-1 S1); C B^T = I - G + S1 g^T / S0 with
// C = S2 - S1 S1^T / S0, alpha = -(g + B S1) / S0. False (nothing changed) when the kept nodes
// do not span the space (C or S2 singular: a linear-shape point on a grid line), where the
// caller keeps only sum grad N = 0.
template <class Shape, int Dim>
bool restore_linear_completeness(double* N, Vec<Dim>* dN, const std::int32_t* node,
                                 const IVec<Dim>& first, const grid::Grid<Dim>& grid,
                                 const Vec<Dim>& xp) {
  constexpr int K = Shape::K;
  Vec<Dim> r[K];
  double S0 = 0;
  Vec<Dim> S1 = Vec<Dim>::Zero(), g = Vec<Dim>::Zero();
  Mat<Dim> S2 = Mat<Dim>::Zero(), G = Mat<Dim>::Zero();
  for (int a = 0; a < K; ++a) {
    if (node[a] < 0) continue;
    IVec<Dim> c = first;
    for (int d = 0; d < Dim; ++d) c[d] += Shape::offset(a, d);
    r[a] = grid.node_position(c) - xp;
    S0 += N[a];
    S1 += N[a] * r[a];
    S2 += N[a] * r[a] * r[a].transpose();
    g += dN[a];
    G += r[a] * dN[a].transpose();
  }
  const Mat<Dim> C = S2 - S1 * S1.transpose() / S0;
  const double h2 = grid.cell_size() * grid.cell_size();
  // Both moment matrices must be well conditioned on the scale of a cell (h^2 times the weight).
  const Eigen::SelfAdjointEigenSolver<Mat<Dim>> eC(C, Eigen::EigenvaluesOnly);
  const Eigen::SelfAdjointEigenSolver<Mat<Dim>> e2(S2, Eigen::EigenvaluesOnly);
  if (!(eC.eigenvalues()[0] > 1e-6 * h2 * S0) || !(e2.eigenvalues()[0] > 1e-6 * h2 * S0))
    return false;
  const Mat<Dim> Bt = C.ldlt().solve(Mat<Dim>::Identity() - G + S1 * g.transpose() / S0);
  const Mat<Dim> B = Bt.transpose();
  const Vec<Dim> alpha = -(g + B * S1) / S0;
  const Vec<Dim> s2s1 = S2.ldlt().solve(S1);
  const double c = 1.0 / (S0 - S1.dot(s2s1));
  const Vec<Dim> b = -c * s2s1;
  for (int a = 0; a < K; ++a) {
    if (node[a] < 0) continue;
    dN[a] += N[a] * (alpha + B * r[a]);
    N[a] *= c + b.dot(r[a]);
  }
  return true;
}
}  // namespace

template <class S1, int Dim>
void p2g(GrainField<Dim>& w, const grid::Grid<Dim>& grid, const Settings<Dim>& settings,
         const points::PointSet<Dim>& points, const points::Grain& gr,
         const PrescribedNodes<Dim>& prescribed) {
  using Shape = typename grid::ShapeOf<Dim, S1>::type;
  constexpr int K = Shape::K;
  const std::int64_t np = gr.size();
  const double h = grid.cell_size();
  w.K = K;
  w.converged = false;
  w.solved_once = false;
  w.iterations = 0;
  w.solves = 0;
  w.factorizations = 0;
  w.dense_factorizations = 0;
  w.failure.clear();
  w.retryable = true;
  w.fail_point = -1;
  w.history.clear();
  w.factor_in_step = false;
  w.project_tangent = false;
  w.projections = 0;
  w.shrunk_domains = 0;
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
    const Mat<Dim> D = points.F[p] * points.domain[p];
    if (!ps.eval(points.x[p], grid.origin(), h, gr.half_width, D)) {
      // A CPDI domain stretched over more than two cells along an axis: its shape functions use
      // it shrunk to the window (grid::fit_cpdi_window), counted in StepStats::shrunk_domains.
      ++w.shrunk_domains;
      if (!ps.eval(points.x[p], grid.origin(), h, gr.half_width,
                   grid::fit_cpdi_window<Dim>(D, h))) {
        w.failure = "material point domain does not fit the CPDI window";
        w.fail_point = p;
        return;
      }
    }
    w.pt_first[i] = ps.first;
    for (int a = 0; a < K; ++a) {
      w.pt_N[i * K + a] = ps.N[a];
      w.pt_dN[i * K + a] = ps.dN[a];
    }
    lo = lo.cwiseMin(ps.first);
    hi = hi.cwiseMax(ps.first + IVec<Dim>::Constant(S1::kNodes - 1));
    if ((ps.first.array() < 0).any() ||
        ((ps.first.array() + S1::kNodes - 1) >= grid.nodes_per_axis().array()).any() ||
        !points.x[p].allFinite()) {
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
  const bool contact = settings.contact.enabled;
  const bool affine = settings.affine;
  if (contact) reset(w.box_gm, nb, Vec<Dim>(Vec<Dim>::Zero()));
  // Pass 2: P2G (method.md §2): m_I = sum N m_p, m_I v_I = sum N m_p v_p,
  // f_I^n = -sum V_p sigma_p grad N_I (seed eq. 5) + sum N m_p g.
  for (std::int64_t i = 0; i < np; ++i) {
    const std::int64_t p = gr.begin + i;
    const IVec<Dim> base = w.pt_first[i] - lo;
    const double mp = points.mass[p];
    const Vec<Dim> mv = mp * points.v[p];
    const Mat<Dim> mL = mp * points.L[p];
    const Vec<Dim> mg = mp * settings.gravity;
    const Mat<Dim> Vs = points.volume[p] * points.sigma[p];
    for (int a = 0; a < K; ++a) {
      IVec<Dim> c = base;
      for (int d = 0; d < Dim; ++d) c[d] += Shape::offset(a, d);
      const std::int64_t b = c.dot(stride);
      const double N = w.pt_N[i * K + a];
      w.box_m[b] += N * mp;
      w.box_mv[b] += N * mv;
      // Affine P2G: + N m_p L_p (x_I - x_p) (Settings::affine).
      if (affine) w.box_mv[b] += N * (mL * (grid.node_position(c + lo) - points.x[p]));
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
  for (std::int64_t i = 0; i < np; ++i) mp_max = std::max(mp_max, points.mass[gr.begin + i]);
  // CPDI (docs/accuracy.md): a domain corner just past a grid line gives its far nodes weights
  // down to round-off; such a node's velocity is the ratio of two vanishing forces and, when a
  // wall face rests on it, it spoils the contact problem (measured: the walled block's exact state
  // lost at s = 0.80 with 1e-13; exact to s = 0.5 with 1e-6). The mass left out (below 1e-6 of a
  // point's per node) is the price: momentum drift ~1e-6 instead of round-off.
  const double m_min = (settings.shape == grid::ShapeKind::kCpdi ? 1e-6 : 1e-13) * mp_max;
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
    w.node_global.push_back(grid.node_index(c + lo));
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
    if (dropped && n_sum > 0 &&
        !restore_linear_completeness<Shape, Dim>(&w.pt_N[i * K], &w.pt_dN[i * K], &w.pt_node[i * K],
                                                 base + lo, grid, points.x[gr.begin + i]))
      for (int a = 0; a < K; ++a)
        if (w.pt_node[i * K + a] >= 0) w.pt_dN[i * K + a] -= (w.pt_N[i * K + a] / n_sum) * g_sum;
  }
  // Boundary conditions: prescribed components of v^n (for the increment) and v^{n+1}.
  w.mask.assign(na, 0);
  w.v_n = w.v_p2g;
  for (std::size_t a = 0; a < na; ++a) {
    const std::int64_t n = w.node_global[a];
    const std::uint8_t mk = prescribed.mask(n);
    if (!mk) continue;
    w.mask[a] = mk;
    const Vec<Dim> xn = grid.node_position(w.node_box[a] + lo);
    for (int d = 0; d < Dim; ++d)
      if (mk & (1u << d)) w.v_n[a][d] = prescribed.value(n, d, xn);
  }
  w.v = w.v_n;  // initial guess: zero acceleration
  // Energy ledger: what the P2G (and the prescribed values) keep of the points' kinetic energy.
  w.kin_points_n = w.kin_grid_n = 0;
  for (std::int64_t i = 0; i < np; ++i)
    w.kin_points_n += 0.5 * points.mass[gr.begin + i] * points.v[gr.begin + i].squaredNorm();
  for (std::size_t a = 0; a < na; ++a) w.kin_grid_n += 0.5 * w.m[a] * w.v_n[a].squaredNorm();
  reset(w.f_int, na, Vec<Dim>(Vec<Dim>::Zero()));
  reset(w.f_abs, na, Vec<Dim>(Vec<Dim>::Zero()));
  reset(w.P, na, Vec<Dim>(Vec<Dim>::Zero()));
  if (contact) {
    // Node -> points lists (for the gaps) and the contact mass threshold of this grain.
    double m_sum = 0, v_sum = 0;
    for (std::int64_t i = 0; i < np; ++i) {
      m_sum += points.mass[gr.begin + i];
      v_sum += points.volume0[gr.begin + i];
    }
    w.contact_mass = settings.contact.mass_fraction * m_sum / v_sum * std::pow(h, Dim);
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
  // Sparse pattern of the Newton matrix and the map from stencil blocks to stored values, in
  // compressed storage directly: the stencil is symmetric (b couples to a when a couples to b),
  // so column (b, j) holds the rows (a, i) of b's neighbours a, ascending.
  const auto ndof = static_cast<Eigen::Index>(na * Dim);
  std::vector<std::int32_t> nbrs;  // per node, its neighbours ascending, from nbr_start
  std::vector<std::int64_t> nbr_start(na + 1, 0);
  nbrs.reserve(na * w.S);
  for (std::size_t b = 0; b < na; ++b) {
    const auto first = static_cast<std::ptrdiff_t>(nbrs.size());
    for (int s = 0; s < w.S; ++s)
      if (w.stencil_nb[b * w.S + s] >= 0) nbrs.push_back(w.stencil_nb[b * w.S + s]);
    std::sort(nbrs.begin() + first, nbrs.end());
    nbr_start[b + 1] = static_cast<std::int64_t>(nbrs.size());
  }
  w.A.resize(ndof, ndof);
  w.A.resizeNonZeros(static_cast<Eigen::Index>(nbrs.size()) * Dim * Dim);
  int* const outer_w = w.A.outerIndexPtr();
  int* const inner_w = w.A.innerIndexPtr();
  outer_w[0] = 0;
  for (std::size_t b = 0; b < na; ++b) {
    const std::int64_t n = nbr_start[b + 1] - nbr_start[b];
    for (int j = 0; j < Dim; ++j) {
      const std::size_t col = b * Dim + static_cast<std::size_t>(j);
      int at = outer_w[col];
      for (std::int64_t k = nbr_start[b]; k < nbr_start[b + 1]; ++k)
        for (int i = 0; i < Dim; ++i) inner_w[at++] = nbrs[static_cast<std::size_t>(k)] * Dim + i;
      outer_w[col + 1] = outer_w[col] + static_cast<int>(n * Dim);
    }
  }
  std::fill(w.A.valuePtr(), w.A.valuePtr() + w.A.nonZeros(), 0.0);
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
  w.dense = false;
  if (settings.linear_solver == LinearSolverKind::kLdlt) {
    // The symbolic analysis also serves the dense grains (their fallback when A is not positive
    // definite: factorize); the fill of L decides (Settings::dense_fill).
    w.ldlt.analyzePattern(w.A);
    const auto n = static_cast<double>(w.A.rows());
    w.dense =
        w.A.rows() <= settings.dense_max_size &&
        static_cast<double>(w.ldlt.factor_nonzeros()) >= settings.dense_fill * 0.5 * n * (n - 1);
    // Only sparse grains gather P A P^T through the map (a dense one's fallback permutes A).
    if (w.dense)
      w.ldlt.clear_map();
    else
      w.ldlt.map_pattern(w.A);
  }
  if (settings.linear_solver == LinearSolverKind::kLu) w.lu.analyzePattern(w.A);
}

template <class S1, int Dim>
G2pUpdate<Dim> g2p_point(const GrainField<Dim>& w, double flip, const points::PointSet<Dim>& points,
                         std::int64_t p, std::int64_t i, bool with_grad) {
  constexpr int K = grid::ShapeOf<Dim, S1>::type::K;
  const double alpha = flip;
  Vec<Dim> dx = Vec<Dim>::Zero(), dv = Vec<Dim>::Zero(), vpic = Vec<Dim>::Zero();
  Mat<Dim> grad_v = Mat<Dim>::Zero();
  for (int a = 0; a < K; ++a) {
    const std::int32_t n = w.pt_node[i * K + a];
    if (n < 0) continue;
    const double N = w.pt_N[i * K + a];
    dx += N * w.du[n];
    dv += N * (w.v[n] - w.v_p2g[n]);
    vpic += N * w.v[n];
    if (with_grad) grad_v += w.v[n] * w.pt_dN[i * K + a].transpose();
  }
  // v_p = flip (v_p + sum N dv) + (1 - flip) sum N v (method.md §2).
  return {dx, alpha * (points.v[p] + dv) + (1.0 - alpha) * vpic, grad_v};
}

template <class S1, int Dim>
void g2p_commit(const GrainField<Dim>& w, const TrialState<Dim>& trial,
                const Settings<Dim>& settings, points::PointSet<Dim>& points,
                const points::Grain& gr) {
  for (std::int64_t i = 0; i < gr.size(); ++i) {
    const std::int64_t p = gr.begin + i;
    const G2pUpdate<Dim> u = g2p_point<S1>(w, settings.flip, points, p, i, settings.affine);
    // Velocity gradient at x^{n+1} for the next affine P2G: grad_{x^n} v dF^-1 (Settings::affine).
    if (settings.affine) points.L[p] = u.grad_v * trial.dF_inv_T[p].transpose();
    // G2P: x_p += sum N du (method.md §2).
    points.x[p] += u.dx;
    points.v[p] = u.v;
    points.F[p] = trial.F[p];
    points.sigma[p] = trial.sigma[p];
    if constexpr (Dim == 2) points.sigma_zz[p] = trial.sigma_zz[p];
    points.volume[p] = trial.J[p] * points.volume0[p];
  }
}

template <class S1, int Dim>
void g2p_check(GrainField<Dim>& w, const TrialState<Dim>& trial, const grid::Grid<Dim>& grid,
               const Settings<Dim>& settings, const points::PointSet<Dim>& points,
               const points::Grain& gr) {
  using Shape = typename grid::ShapeOf<Dim, S1>::type;
  const double h = grid.cell_size();
  Shape ps;
  w.kin_points = 0;
  for (std::int64_t i = 0; i < gr.size(); ++i) {
    const std::int64_t p = gr.begin + i;
    // g2p_commit's position and velocity
    const G2pUpdate<Dim> u = g2p_point<S1>(w, settings.flip, points, p, i, false);
    w.kin_points += 0.5 * points.mass[p] * u.v.squaredNorm();
    const Vec<Dim> x = points.x[p] + u.dx;
    // A domain stretched too far is left to the next step's set-up (a retryable failure there);
    // its position must still lie on the grid.
    const bool off =
        !x.allFinite() ||
        (ps.eval(x, grid.origin(), h, gr.half_width, trial.F[p] * points.domain[p])
             ? ((ps.first.array() < 0).any() ||
                ((ps.first.array() + S1::kNodes - 1) >= grid.nodes_per_axis().array()).any())
             : !grid.inside(x, 0.0));
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
double field_mass(const GrainField<Dim>& w) {
  double m = 0;
  for (double x : w.m) m += x;
  return m;
}

template <int Dim>
Vec<Dim> field_momentum(const GrainField<Dim>& w) {
  Vec<Dim> p = Vec<Dim>::Zero();
  for (std::size_t a = 0; a < w.m.size(); ++a) p += w.m[a] * w.v[a];
  return p;
}

// The stages defined here, for each dimension and shape family.
#define MPMCD_INSTANTIATE_SHAPE(D, S1)                                                             \
  template void p2g<S1, D>(GrainField<D>&, const grid::Grid<D>&, const Settings<D>&,               \
                           const points::PointSet<D>&, const points::Grain&,                       \
                           const PrescribedNodes<D>&);                                             \
  template G2pUpdate<D> g2p_point<S1, D>(const GrainField<D>&, double, const points::PointSet<D>&, \
                                         std::int64_t, std::int64_t, bool);                        \
  template void g2p_check<S1, D>(GrainField<D>&, const TrialState<D>&, const grid::Grid<D>&,       \
                                 const Settings<D>&, const points::PointSet<D>&,                   \
                                 const points::Grain&);                                            \
  template void g2p_commit<S1, D>(const GrainField<D>&, const TrialState<D>&, const Settings<D>&,  \
                                  points::PointSet<D>&, const points::Grain&);
#define MPMCD_INSTANTIATE(D)                           \
  MPMCD_FOR_EACH_SHAPE(MPMCD_INSTANTIATE_SHAPE, D)     \
  template double field_mass<D>(const GrainField<D>&); \
  template Vec<D> field_momentum<D>(const GrainField<D>&);
MPMCD_INSTANTIATE(2)
MPMCD_INSTANTIATE(3)
#undef MPMCD_INSTANTIATE
#undef MPMCD_INSTANTIATE_SHAPE

}  // namespace mpmcd::mpm
