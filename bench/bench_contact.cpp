// Cost of contact in a packing of 300 Neo-Hookean disks (paper setup: DEM packing at phi = 0.78,
// diameters uniform in [0.8, 1.2] mm, ~8 cells per mean diameter, 2x2 points per cell, four walls,
// the top one moving down at 2 m/s, dt = 0.1 us): time of contact detection per step, of one
// Gauss-Seidel sweep per contact, and the share of the step spent in contact, for the grain
// compliance (LDLT) and the lumped (CG) Delassus operators, 1 and 2 threads, and the compliance
// with modified Newton (Settings::modified_newton, "modified" = 1), also with CPDI shape functions
// and affine P2G ("cpdi_affine" = 1); and one Gauss-Seidel
// solve of a synthetic lumped problem on 1 and 2 threads (BM_GaussSeidelNodes); the active set's
// LDL^T on the threads (BM_TreeLdlt) and against the supernodal Cholesky (BM_ActiveSetFactor).
//   ./build/release/bench/bench_contact --benchmark_counters_tabular=true
#include <benchmark/benchmark.h>
#include <omp.h>

#include "../tests/support/contact_problems.hpp"
#include "../tests/support/sparse_matrices.hpp"
#include "mpmcd/core/dense_lapack.hpp"
#include "mpmcd/core/supernodal_llt.hpp"
#include "mpmcd/core/tree_ldlt.hpp"
#include "mpmcd/mpm/solver.hpp"
#include "slice_300.hpp"

using namespace mpmcd;

namespace {

void BM_ContactPacking(benchmark::State& state) {
  const auto kind = static_cast<mpm::LinearSolverKind>(state.range(0));
  omp_set_num_threads(static_cast<int>(state.range(1)));
  bench::Slice setup = bench::make_slice_300();
  auto& model = setup.model;
  mpm::Settings<2> s;
  s.theta = 1.0;
  s.linear_solver = kind;
  s.modified_newton = state.range(2) != 0;
  if (state.range(3) != 0) {  // the large-deformation options (docs/accuracy.md)
    s.shape = grid::ShapeKind::kCpdi;
    s.affine = true;
  }
  s.contact.enabled = true;
  s.contact.walls = setup.walls;
  mpm::ImplicitSolver<2> solver(model.grid, s, model.points, model.grains, model.law_ptrs());
  const double dt = 1e-7;
  // Bring the packing into contact first (not timed): 200 steps of the top wall moving down.
  int step = 0;
  for (; step < 200; ++step) {
    solver.set_time(step * dt);
    const auto st = solver.solve_step(dt);
    if (!st.converged) {
      state.SkipWithError(("warm-up step " + std::to_string(step) + ": " + st.failure).c_str());
      return;
    }
    solver.commit();
  }
  solver.timers().clear();
  double contacts = 0, active = 0, sweeps = 0, iters = 0, steps = 0;
  for (auto _ : state) {
    solver.set_time(step * dt);
    const auto st = solver.solve_step(dt);
    if (!st.converged) state.SkipWithError(st.failure.c_str());
    solver.commit();
    ++step;
    contacts += static_cast<double>(st.contacts);
    active += static_cast<double>(st.active_contacts);
    sweeps += static_cast<double>(st.gs_sweeps);
    iters += st.iterations;
    steps += 1;
  }
  const auto& t = solver.timers().totals();
  auto get = [&](const char* k) { return t.count(k) ? t.at(k) : 0.0; };
  double total = 0;
  for (const auto& [name, secs] : t)
    if (name != "contact.gs") total += secs;  // contact.gs is inside contact.solve
  state.counters["points"] = static_cast<double>(model.points.size());
  state.counters["contacts"] = contacts / steps;
  state.counters["active"] = active / steps;
  state.counters["newton_it"] = iters / steps;
  state.counters["gs_sweeps"] = sweeps / steps;
  state.counters["detect_ms"] = 1e3 * get("contact.detect") / steps;
  state.counters["sweep_ns_per_contact"] =
      1e9 * get("contact.gs") / std::max(1.0, sweeps * contacts / steps);
  state.counters["contact_share"] = (get("contact.detect") + get("contact.solve")) / total;
}

// One Gauss-Seidel solve (3 sweeps, 4 error evaluations, copy of the problem included) of a
// synthetic lumped problem: 1,300 nodes with three grain fields in mutual contact and a wall
// contact each (5,200 contacts, tests/support/contact_problems.hpp). The nodes are independent
// problems, swept on the threads.
void BM_GaussSeidelNodes(benchmark::State& state) {
  omp_set_num_threads(static_cast<int>(state.range(0)));
  const auto base = test_support::many_node_problem(1300);
  for (auto _ : state) {
    auto p = base;
    benchmark::DoNotOptimize(contact::solve_gauss_seidel(p, {1e-8, 3}));
  }
  state.counters["contacts"] = static_cast<double>(base.contacts.size());
}

// The active set's factorisation (mpmcd::TreeLdlt, docs/parallel.md) of a Delassus-like matrix
// on an n x n grid with diagonals (tests/support/sparse_matrices.hpp; n = 72: 5,184 rows as the
// closed contacts of the dense d/8 paper state, but a quarter of its factor's non-zeros, so the
// ordering weighs more here): ordering, analysis and numeric LDL^T, split for `ways` workers
// (1: Eigen's SimplicialLDLT loop) on `threads` threads. The real W_AA: bench_compaction.
void BM_TreeLdlt(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0)), ways = static_cast<int>(state.range(1));
  omp_set_num_threads(static_cast<int>(state.range(2)));
  const Eigen::SparseMatrix<double> A = test_support::grid_matrix(n, n, 1e-3, 7);
  TreeLdlt ldlt;
  ldlt.setShift(1e-9);
  for (auto _ : state) {
    ldlt.compute_on_threads(A, ways, 1000);
    benchmark::DoNotOptimize(ldlt.vectorD().data());
  }
  state.counters["rows"] = static_cast<double>(A.rows());
  state.counters["L_nonzeros"] = static_cast<double>(ldlt.matrixL().nestedExpression().nonZeros());
  state.counters["top_rows"] = static_cast<double>(ldlt.top_rows());
  state.counters["split_speedup"] = ldlt.split_speedup();
}

// The active set's two factorisations of W_AA + delta I (docs/contact.md, "The supernodal
// factorisation") on a dense-block matrix like a packing's (grain_blocks_matrix: `groups` grains
// in a row of `per_grain` contacts of their own and a third as many shared with the next, every
// pair on a grain coupled at rank 3; a few large grains give the long columns of a dense 3D
// packing's factor, many small ones the 2D case), the ordering and analysis included: `supernodal`
// 0 is TreeLdlt split for 2 ways, 1 CHOLMOD's supernodal Cholesky with TreeLdlt's order (OpenBLAS
// on one thread), on `threads` threads. Counters: rows, L's entries and its mean column
// (multiply-adds over entries).
void BM_ActiveSetFactor(benchmark::State& state) {
  const int groups = static_cast<int>(state.range(0)), per = static_cast<int>(state.range(1));
  const bool supernodal = state.range(2) != 0;
  omp_set_num_threads(static_cast<int>(state.range(3)));
  const Eigen::SparseMatrix<double> A =
      test_support::grain_blocks_matrix(groups, per, per / 3, 3, 1e-4, 7);
  TreeLdlt ldlt;
  SupernodalLlt llt;
  ldlt.setShift(1e-9);
  for (auto _ : state) {
    ldlt.analyze(A);
    if (supernodal) {
      if (!llt.compute(A, 1e-9, ldlt.order().data())) state.SkipWithError("not SPD");
    } else {
      ldlt.factorize_analyzed(2, 1000);
      benchmark::DoNotOptimize(ldlt.vectorD().data());
    }
  }
  const double nnz = static_cast<double>(ldlt.matrixL().nestedExpression().nonZeros());
  state.counters["rows"] = static_cast<double>(A.rows());
  state.counters["L_nonzeros"] = nnz;
  state.counters["mean_column"] = ldlt.symbolic_flops() / nnz;
}

// The dense top's kernel (dense::cholesky_upper_on_threads, blocks of 96 rows) on an n x n SPD
// matrix, copy included, on `threads` threads; the counter GFlops is n^3 / 3 over the time, and
// the label OpenBLAS's kernels (docs/parallel.md, "The top rows as a dense Schur complement").
void BM_DenseTopCholesky(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  omp_set_num_threads(static_cast<int>(state.range(1)));
  const Eigen::MatrixXd R = Eigen::MatrixXd::Random(n, n);
  const Eigen::MatrixXd A = R * R.transpose() + n * Eigen::MatrixXd::Identity(n, n);
  Eigen::MatrixXd U(n, n);
  for (auto _ : state) {
    U = A;
    if (!dense::cholesky_upper_on_threads(U.data(), n)) state.SkipWithError("not SPD");
    benchmark::DoNotOptimize(U.data());
  }
  state.counters["GFlops"] = benchmark::Counter(static_cast<double>(n) * n * n / 3e9,
                                                benchmark::Counter::kIsIterationInvariantRate);
  state.SetLabel(dense::kernels());
}

}  // namespace

BENCHMARK(BM_DenseTopCholesky)
    ->ArgNames({"n", "threads"})
    ->Args({500, 1})
    ->Args({500, 2})
    ->Args({1000, 1})
    ->Args({1000, 2})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

BENCHMARK(BM_TreeLdlt)
    ->ArgNames({"n", "ways", "threads"})
    ->Args({72, 1, 1})
    ->Args({72, 2, 1})
    ->Args({72, 2, 2})
    ->Args({72, 4, 2})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

BENCHMARK(BM_ActiveSetFactor)
    ->ArgNames({"groups", "per_grain", "supernodal", "threads"})
    ->Args({160, 120, 0, 2})
    ->Args({160, 120, 1, 2})
    ->Args({24, 720, 0, 2})
    ->Args({24, 720, 1, 2})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

BENCHMARK(BM_GaussSeidelNodes)
    ->ArgNames({"threads"})
    ->Arg(1)
    ->Arg(2)
    ->Unit(benchmark::kMillisecond);

BENCHMARK(BM_ContactPacking)
    ->ArgNames({"solver", "threads", "modified", "cpdi_affine"})
    ->ArgsProduct({{0, 2}, {1, 2}, {0}, {0}})
    ->ArgsProduct({{0}, {1, 2}, {1}, {0, 1}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MinTime(5.0);

BENCHMARK_MAIN();
