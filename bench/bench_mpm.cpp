// Material-point updates per second of the implicit MPM step (no contact): P2G, G2P and the whole
// step (P2G + Newton + G2P), for ~200-point Neo-Hookean disks like the paper's compaction grains
// (R = 0.5 mm, h = R/4, 2x2 points per cell, dt = 0.1 us), at 10k and 100k points, 1 and 2 threads,
// with the sparse direct (LDLT) and the Jacobi-CG per-grain solvers; "accurate" = 1 runs the
// large-deformation options (CPDI shape functions, affine P2G, modified Newton: docs/accuracy.md).
// BM_ImplicitStep3D: the same step in 3D (issue 18) on spheres of ~1,000 points (R = 0.5 mm,
// h = R/3, 2^3 points per cell), with the memory per point (heap in use after building the model
// and taking a first step, minus before, over the points: points, grid fields, factorisations).
//   ./build/release/bench/bench_mpm --benchmark_counters_tabular=true
#include <benchmark/benchmark.h>
#include <omp.h>

#include <malloc.h>

#include <cmath>
#include <utility>

#include "mpmcd/materials/law.hpp"
#include "mpmcd/mpm/model.hpp"
#include "mpmcd/mpm/solver.hpp"
#include "mpmcd/points/seeding.hpp"

using namespace mpmcd;

namespace {

// The benchmark's timed loop: steps of 0.1 us, committed; returns (Newton iterations, steps).
template <int Dim>
std::pair<std::int64_t, std::int64_t> timed_steps(benchmark::State& state,
                                                  mpm::ImplicitSolver<Dim>& solver) {
  std::int64_t iterations = 0, steps = 0;
  for (auto _ : state) {
    auto st = solver.solve_step(1e-7);
    if (!st.converged) state.SkipWithError(st.failure.c_str());
    solver.commit();
    iterations += st.iterations;
    ++steps;
  }
  return {iterations, steps};
}

mpm::Model<2> make_disks(std::int64_t target_points) {
  const double R = 0.5e-3, h = R / 4, pitch = 2.4 * R;
  const int ppc = 2;
  const auto per_disk = static_cast<double>(
      points::seed_ball<2>(Vec<2>::Zero(), h, ppc, Vec<2>(R + 2 * h, R + 2 * h), R).x.size());
  const auto ndisks = static_cast<int>(std::ceil(target_points / per_disk));
  const int nx = static_cast<int>(std::ceil(std::sqrt(ndisks)));
  const int ny = (ndisks + nx - 1) / nx;
  mpm::Model<2> m;
  const IVec<2> cells(static_cast<std::int64_t>(std::ceil((nx * pitch + 4 * h) / h)),
                      static_cast<std::int64_t>(std::ceil((ny * pitch + 4 * h) / h)));
  m.grid = grid::Grid<2>(Vec<2>::Zero(), h, cells);
  m.add_material(materials::make_law<2>("neo_hookean", {{"lambda", 3e6}, {"mu", 1.5e6}}), 990.0);
  for (int k = 0; k < ndisks; ++k) {
    const Vec<2> c(2 * h + (k % nx + 0.5) * pitch, 2 * h + (k / nx + 0.5) * pitch);
    auto seeds = points::seed_ball<2>(m.grid.origin(), h, ppc, c, R);
    // a compressive, shearing velocity field so that every step deforms the grains
    m.add_grain(seeds, 0, 0.5 * h / ppc, [&](const Vec<2>& x) {
      const Vec<2> r = x - c;
      return Vec<2>(-200.0 * r[0] + 100.0 * r[1], -300.0 * r[1]);
    });
  }
  return m;
}

void BM_ImplicitStep(benchmark::State& state) {
  const auto target = state.range(0);
  const int threads = static_cast<int>(state.range(1));
  const auto solver_kind = static_cast<mpm::LinearSolverKind>(state.range(2));
  omp_set_num_threads(threads);
  auto model = make_disks(target);
  mpm::Settings<2> s;
  s.theta = 1.0;
  s.linear_solver = solver_kind;
  if (state.range(3) != 0) {
    s.shape = grid::ShapeKind::kCpdi;
    s.affine = true;
    s.modified_newton = true;
  }
  mpm::ImplicitSolver<2> solver(model.grid, s, model.points, model.grains, model.law_ptrs());
  const double np = static_cast<double>(model.points.size());
  const auto [iterations, steps] = timed_steps(state, solver);
  const auto& t = solver.timers().totals();
  const double p2g = t.count("p2g") ? t.at("p2g") : 0, g2p = t.count("g2p") ? t.at("g2p") : 0;
  state.counters["points"] = np;
  state.counters["grains"] = static_cast<double>(model.grains.size());
  state.counters["newton_it"] = static_cast<double>(iterations) / static_cast<double>(steps);
  state.counters["p2g_pts/s"] = np * static_cast<double>(steps) / p2g;
  state.counters["g2p_pts/s"] = np * static_cast<double>(steps) / g2p;
  state.counters["step_pts/s"] =
      benchmark::Counter(np, benchmark::Counter::kIsIterationInvariantRate);
}

// Heap bytes in use by this process [bytes] (glibc mallinfo2: small blocks plus mmapped ones).
double heap_bytes() {
  const struct mallinfo2 mi = mallinfo2();
  return static_cast<double>(mi.uordblks + mi.hblkhd);
}

mpm::Model<3> make_spheres(std::int64_t target_points) {
  const double R = 0.5e-3, h = R / 3, pitch = 2.4 * R;
  const int ppc = 2;
  const auto per_ball = static_cast<double>(
      points::seed_ball<3>(Vec<3>::Zero(), h, ppc, Vec<3>::Constant(R + 2 * h), R).x.size());
  const auto nballs = static_cast<int>(std::ceil(static_cast<double>(target_points) / per_ball));
  const int n = static_cast<int>(std::ceil(std::cbrt(nballs)));
  mpm::Model<3> m;
  const auto cells = static_cast<std::int64_t>(std::ceil((n * pitch + 4 * h) / h));
  m.grid = grid::Grid<3>(Vec<3>::Zero(), h, IVec<3>(cells, cells, cells));
  m.add_material(materials::make_law<3>("neo_hookean", {{"lambda", 3e6}, {"mu", 1.5e6}}), 990.0);
  for (int k = 0; k < nballs; ++k) {
    const Vec<3> c(2 * h + (k % n + 0.5) * pitch, 2 * h + ((k / n) % n + 0.5) * pitch,
                   2 * h + (k / (n * n) + 0.5) * pitch);
    // the compressive, shearing velocity field of the 2D case, with a third component
    m.add_grain(points::seed_ball<3>(m.grid.origin(), h, ppc, c, R), 0, 0.5 * h / ppc,
                [&](const Vec<3>& x) {
                  const Vec<3> r = x - c;
                  return Vec<3>(-200.0 * r[0] + 100.0 * r[1], -300.0 * r[1], -100.0 * r[2]);
                });
  }
  return m;
}

void BM_ImplicitStep3D(benchmark::State& state) {
  const auto target = state.range(0);
  const int threads = static_cast<int>(state.range(1));
  omp_set_num_threads(threads);
  const double heap0 = heap_bytes();
  auto model = make_spheres(target);
  mpm::Settings<3> s;
  s.theta = 1.0;
  s.linear_solver = static_cast<mpm::LinearSolverKind>(state.range(3));
  if (state.range(2) != 0) {
    s.shape = grid::ShapeKind::kCpdi;
    s.affine = true;
  }
  mpm::ImplicitSolver<3> solver(model.grid, s, model.points, model.grains, model.law_ptrs());
  const double np = static_cast<double>(model.points.size());
  solver.solve_step(1e-7);
  solver.commit();
  const double bytes = heap_bytes() - heap0;
  const auto [iterations, steps] = timed_steps(state, solver);
  state.counters["points"] = np;
  state.counters["grains"] = static_cast<double>(model.grains.size());
  state.counters["newton_it"] = static_cast<double>(iterations) / static_cast<double>(steps);
  state.counters["bytes/point"] = bytes / np;
  state.counters["step_pts/s"] =
      benchmark::Counter(np, benchmark::Counter::kIsIterationInvariantRate);
}

}  // namespace

BENCHMARK(BM_ImplicitStep3D)
    ->ArgNames({"points", "threads", "accurate", "solver"})
    ->ArgsProduct({{10000}, {1, 2}, {0, 1}, {0, 2}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

BENCHMARK(BM_ImplicitStep)
    ->ArgNames({"points", "threads", "solver", "accurate"})
    ->ArgsProduct({{10000, 100000}, {1, 2}, {0, 2}, {0}})
    ->ArgsProduct({{10000, 100000}, {1, 2}, {0}, {1}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

BENCHMARK_MAIN();
