// One Newton iteration of a grain (method.md §2): kinematics, law and residual (evaluate), the
// consistent tangent (assemble_tangent), the Newton matrix and its factorisation (factorize,
// prepare_factor), the linear solve, the modified-Newton reuse of a factorisation and the update
// (newton_solve) (include/mpmcd/mpm/grain_field.hpp).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <span>

#include "mpmcd/core/dense_lapack.hpp"
#include "mpmcd/mpm/grain_field.hpp"

namespace mpmcd::mpm {

template <int Dim>
void nodal_residual(GrainField<Dim>& w, const Settings<Dim>& settings, double dt) {
  const std::size_t na = w.m.size();
  const double theta = settings.theta;
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
  // rest has no velocity scale of its own). The convergence decision is the caller's
  // (ImplicitSolver::solve_step).
  double vref2 = 0, mass = 0;
  for (std::size_t a = 0; a < na; ++a) {
    vref2 += w.m[a] * std::max(w.v[a].squaredNorm(), w.v_n[a].squaredNorm());
    mass += w.m[a];
  }
  w.vel_ref = std::sqrt(vref2) + (mass > 0 ? w.res_ref / std::sqrt(mass) : 0.0);
}

template <class S1, int Dim>
void evaluate(GrainField<Dim>& w, TrialState<Dim>& trial, const Settings<Dim>& settings,
              const points::PointSet<Dim>& points, const points::Grain& gr,
              const materials::Law<Dim>& law, double dt) {
  using Shape = typename grid::ShapeOf<Dim, S1>::type;
  constexpr int K = Shape::K;
  const std::int64_t np = gr.size();
  const std::size_t na = w.m.size();
  const double theta = settings.theta;
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
    trial.F[p] = dF * points.F[p];
    const double J = trial.F[p].determinant();
    trial.J[p] = J;
    if (!(J > 0.0) || !std::isfinite(J)) {
      w.failure = fmt::format("J = {:.3g} <= 0 (inverted material point)", J);
      w.fail_point = p;
      return;
    }
    trial.dF_inv_T[p] = dF.inverse().transpose();
  }
  const auto off = static_cast<std::size_t>(gr.begin);
  const auto cnt = static_cast<std::size_t>(np);
  const std::size_t hs = static_cast<std::size_t>(law.history_size());
  materials::LawBatch<Dim> batch{
      std::span<const Mat<Dim>>(trial.F.data() + off, cnt),
      std::span<const double>(points.history.data() + gr.history_offset, hs * cnt),
      std::span<double>(trial.history.data() + gr.history_offset, hs * cnt),
      std::span<Mat<Dim>>(trial.sigma.data() + off, cnt),
      std::span<Tensor4<Dim>>(trial.tangent.data() + off, cnt),
      {},
      Dim == 2 ? std::span<double>(trial.sigma_zz.data() + off, cnt) : std::span<double>()};
  law.evaluate(batch);
  // Internal force f_I = -sum V sigma grad_{x^{n+1}} N_I with grad_{x^{n+1}} N = dF^-T grad_{x^n} N
  // (seed eq. 5 at n+1, method.md §2).
  std::fill(w.f_int.begin(), w.f_int.end(), Vec<Dim>::Zero());
  std::fill(w.f_abs.begin(), w.f_abs.end(), Vec<Dim>::Zero());
  for (std::int64_t i = 0; i < np; ++i) {
    const std::int64_t p = gr.begin + i;
    const Mat<Dim>& sig = trial.sigma[p];
    if (!sig.allFinite()) {
      w.failure = "non-finite stress";
      w.fail_point = p;
      return;
    }
    const Mat<Dim> Vsig_dFinvT = trial.J[p] * points.volume0[p] * sig * trial.dF_inv_T[p];
    for (int a = 0; a < K; ++a) {
      const std::int32_t n = w.pt_node[i * K + a];
      if (n < 0) continue;
      const Vec<Dim> fa = Vsig_dFinvT * w.pt_dN[i * K + a];
      w.f_int[n] -= fa;
      w.f_abs[n] += fa.cwiseAbs();
    }
  }
  nodal_residual(w, settings, dt);
  if (!w.failure.empty()) return;
  w.evaluated = true;
}

namespace {

// The tangent a_ijkl of a point as a symmetric Dim^2 x Dim^2 matrix, with its negative
// eigenvalues set to zero (projected Newton, Teran et al. 2005): returns `a` itself when it is
// positive semi-definite, else the projection, written to `scratch`.
template <int Dim>
const Tensor4<Dim>& projected(const Tensor4<Dim>& a, Tensor4<Dim>& scratch) {
  const Eigen::SelfAdjointEigenSolver<Tensor4<Dim>> es(a);
  if (es.eigenvalues()[0] >= 0) return a;
  scratch = es.eigenvectors() * es.eigenvalues().cwiseMax(0.0).asDiagonal() *
            es.eigenvectors().transpose();
  return scratch;
}

}  // namespace

template <class S1, int Dim>
void assemble_tangent(GrainField<Dim>& w, const TrialState<Dim>& trial,
                      const points::PointSet<Dim>& points, const points::Grain& gr) {
  using Shape = typename grid::ShapeOf<Dim, S1>::type;
  constexpr int K = Shape::K;
  // Tangent blocks K_IJ,ik = sum V g_I,j a_ijkl g_J,l, g = dF^-T grad_{x^n} N (material +
  // geometric, method.md §2), accumulated into the block stencil through the pair -> slot table.
  // With project_tangent each point's a is first projected onto the positive semi-definite
  // matrices (prepare_factor).
  std::fill(w.K_blk.begin(), w.K_blk.end(), Mat<Dim>::Zero());
  Vec<Dim> gx[K];
  Eigen::Matrix<double, Dim, Dim * Dim> Ma[K];
  Tensor4<Dim> Tp;  // the projected tangent of the current point
  for (std::int64_t i = 0; i < gr.size(); ++i) {
    const std::int64_t p = gr.begin + i;
    const double V = trial.J[p] * points.volume0[p];
    const Tensor4<Dim>& T =
        w.project_tangent ? projected<Dim>(trial.tangent[p], Tp) : trial.tangent[p];
    for (int a = 0; a < K; ++a) {
      gx[a] = trial.dF_inv_T[p] * w.pt_dN[i * K + a];
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
  if (!w.follower_K.empty())
    for (std::size_t k = 0; k < w.K_blk.size(); ++k) w.K_blk[k] += w.follower_K[k];
  w.tangent_current = true;
}

namespace {

// A = L L^T into w.chol (a dense grain, Settings::dense_fill): A's lower triangle copied in, then
// LAPACK's blocked in-place Cholesky (core/dense_lapack.hpp). False when A is not positive
// definite.
template <int Dim>
bool dense_cholesky(GrainField<Dim>& w) {
  const Eigen::Index n = w.A.rows();
  if (w.chol.rows() != n) w.chol.resize(n, n);
  for (Eigen::Index c = 0; c < n; ++c) {
    w.chol.col(c).tail(n - c).setZero();
    for (SpMat::InnerIterator it(w.A, c); it; ++it)
      if (it.row() >= c) w.chol(it.row(), c) = it.value();
  }
  return dense::cholesky_in_place(w.chol);
}

}  // namespace

template <int Dim>
bool factorize(GrainField<Dim>& w, const Settings<Dim>& settings, double dt) {
  const std::size_t na = w.m.size();
  const double c = settings.theta * settings.theta * dt * dt;
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
  switch (settings.linear_solver) {
    case LinearSolverKind::kLdlt:
      w.factor_dense = w.dense && dense_cholesky(w);
      if (!w.factor_dense) {
        // Sparse LDL^T, also for a dense grain whose A is not positive definite.
        w.ldlt.factorize_mapped(w.A);
        ok = w.ldlt.info() == Eigen::Success;
      }
      break;
    case LinearSolverKind::kLu:
      w.lu.factorize(w.A);
      ok = w.lu.info() == Eigen::Success;
      break;
    case LinearSolverKind::kCg:
      w.cg.setTolerance(settings.cg_tolerance);
      w.cg.setMaxIterations(settings.cg_max_iterations);
      w.cg.compute(w.A);
      break;
  }
  if (!ok) w.failure = "linear solve failed (singular or indefinite tangent)";
  w.factor_current = ok;
  w.factor_in_step = ok;
  ++w.factor_count;
  ++w.factorizations;
  if (w.factor_dense) ++w.dense_factorizations;
  return ok;
}

template <int Dim>
bool prepare_factor(GrainField<Dim>& w, const TrialState<Dim>& trial, const Settings<Dim>& settings,
                    const points::PointSet<Dim>& points, const points::Grain& grain,
                    const materials::Law<Dim>& law, bool compliance, double dt) {
  if (w.factor_current) return true;
  const auto assemble = [&] {
    with_shape(settings.shape,
               [&](auto tag) { assemble_tangent<decltype(tag)>(w, trial, points, grain); });
  };
  if (!w.tangent_current) assemble();
  if (!factorize(w, settings, dt)) return false;
  // Under compression the geometric term delta_ik sigma_jl makes a point's tangent indefinite
  // (on rotations), and modes that strain no point (edge nodes of a block, rigid rotation) then
  // give M + theta^2 dt^2 K negative eigenvalues once dt^2 |sigma| / h^2 exceeds the nodal
  // density: the contact compliance E^T A^-1 E is indefinite and Gauss-Seidel diverges
  // (docs/accuracy.md). A grain whose factorisation gives a compliance then uses the projected
  // tangent for the step; the Newton iterations still converge to the same state, linearly. A
  // grain without contact keeps the exact tangent (quadratic convergence).
  if (w.project_tangent || !compliance || settings.linear_solver != LinearSolverKind::kLdlt ||
      !law.symmetric_tangent() || w.factor_dense || (w.ldlt.vectorD().array() > 0).all())
    return true;
  w.project_tangent = true;
  ++w.projections;
  assemble();
  return factorize(w, settings, dt);
}

template <int Dim, class Rhs>
Eigen::VectorXd linear_solve(GrainField<Dim>& w, const Settings<Dim>& settings, const Rhs& rhs) {
  switch (settings.linear_solver) {
    case LinearSolverKind::kLdlt: {
      if (!w.factor_dense) return w.ldlt.solve(rhs);
      Eigen::VectorXd x = rhs;  // L^-T L^-1 rhs
      dense::cholesky_solve(w.chol, x);
      return x;
    }
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
bool reuse_factor(const GrainField<Dim>& w, const Settings<Dim>& settings) {
  // Modified Newton (Settings::modified_newton): the step's first factorisation serves all its
  // iterations and contact updates, unless the residual stalls (falls by less than half over an
  // iteration) above the tolerance, when the tangent is rebuilt. A residual that has converged
  // (|R| / reference <= residual_tolerance, the test of the step's loop) stays at its floor while
  // the grain iterates for its increment or for the other grains' impulses: a new tangent cannot
  // lower it (in the dense d/8 paper state, 180 of 480 factorisations per step were of such
  // grains, their residuals 1e-12 to 3e-10 unchanged; docs/contact.md, "A converged residual is
  // not a stall").
  if (!settings.modified_newton || !w.factor_in_step) return false;
  const auto n = w.history.size();
  return n < 2 || w.history[n - 1] < 0.5 * w.history[n - 2] ||
         w.history[n - 1] <= settings.residual_tolerance;
}

template <int Dim>
void newton_solve(GrainField<Dim>& w, const TrialState<Dim>& trial, const Settings<Dim>& settings,
                  const points::PointSet<Dim>& points, const points::Grain& grain,
                  const materials::Law<Dim>& law, bool compliance, double dt, bool reuse) {
  const std::size_t na = w.m.size();
  if (!reuse && !prepare_factor(w, trial, settings, points, grain, law, compliance, dt)) return;
  w.rhs.resize(static_cast<Eigen::Index>(na * Dim));
  for (std::size_t a = 0; a < na; ++a)
    for (int d = 0; d < Dim; ++d) w.rhs[a * Dim + d] = -w.R[a][d];
  w.sol = linear_solve(w, settings, w.rhs);
  w.cg_work = settings.linear_solver == LinearSolverKind::kCg
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
  w.dv_from_contact = false;
  w.solved_once = true;
  ++w.solves;
}

// The stages defined here, for each dimension and shape family; linear_solve for the Newton update
// and for the columns of the contact compliance (ImplicitSolver::grain_compliance).
#define MPMCD_INSTANTIATE_SHAPE(D, S1)                                              \
  template void evaluate<S1, D>(GrainField<D>&, TrialState<D>&, const Settings<D>&, \
                                const points::PointSet<D>&, const points::Grain&,   \
                                const materials::Law<D>&, double);                  \
  template void assemble_tangent<S1, D>(GrainField<D>&, const TrialState<D>&,       \
                                        const points::PointSet<D>&, const points::Grain&);
#define MPMCD_INSTANTIATE(D)                                                                    \
  MPMCD_FOR_EACH_SHAPE(MPMCD_INSTANTIATE_SHAPE, D)                                              \
  template void nodal_residual<D>(GrainField<D>&, const Settings<D>&, double);                  \
  template bool factorize<D>(GrainField<D>&, const Settings<D>&, double);                       \
  template bool prepare_factor<D>(GrainField<D>&, const TrialState<D>&, const Settings<D>&,     \
                                  const points::PointSet<D>&, const points::Grain&,             \
                                  const materials::Law<D>&, bool, double);                      \
  template Eigen::VectorXd linear_solve<D, Eigen::VectorXd>(GrainField<D>&, const Settings<D>&, \
                                                            const Eigen::VectorXd&);            \
  template Eigen::VectorXd linear_solve<D, Eigen::Map<Eigen::MatrixXd>::ColXpr>(                \
      GrainField<D>&, const Settings<D>&, const Eigen::Map<Eigen::MatrixXd>::ColXpr&);          \
  template bool reuse_factor<D>(const GrainField<D>&, const Settings<D>&);                      \
  template void newton_solve<D>(GrainField<D>&, const TrialState<D>&, const Settings<D>&,       \
                                const points::PointSet<D>&, const points::Grain&,               \
                                const materials::Law<D>&, bool, double, bool);
MPMCD_INSTANTIATE(2)
MPMCD_INSTANTIATE(3)
#undef MPMCD_INSTANTIATE
#undef MPMCD_INSTANTIATE_SHAPE

}  // namespace mpmcd::mpm
