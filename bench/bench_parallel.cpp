// Scaling of the parallel step (docs/parallel.md) on the 300-grain compaction slice
// (bench/slice_300.hpp: DEM packing at phi = 0.78, d in [0.8, 1.2] mm, h = d/8, 2x2 points per
// cell, four walls, the top one down at 2 m/s, dt = 0.1 us, lumped Delassus operator): `warmup`
// steps, then `steps` timed ones. Not a Google Benchmark (it runs under mpirun); rank 0 appends one
// CSV row:
//   mpirun -np 2 build/release/bench/bench_parallel --scheme partition --threads 1 --csv out.csv
// `--rebalance T --rebalance-every N` re-deals as `mpmcd run` does (default 0: never).
// tools/scaling.py runs it over ranks, threads and both schemes. `--cpu-time 1` times the stages
// in thread CPU time: on a shared, oversubscribed machine a rank's work without its waits.
// `--mirror 1` measures the machine's noise floor for the serial fraction: every rank computes
// the whole slice alone (identical work) and the ranks synchronise once per step, so the time one
// rank works alone is only the run-to-run jitter of identical work.
// `--trace FILE` writes every synchronisation of the timed steps (code line, each rank's work
// interval in wall and CPU time, counted units) for tools/serial_ensemble.py.
#include <fmt/format.h>
#include <omp.h>

#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <string>

#include "mpmcd/core/allocator.hpp"
#include "mpmcd/core/openmp_env.hpp"
#include "mpmcd/mpm/solver.hpp"
#include "mpmcd/parallel/distribute.hpp"
#include "slice_300.hpp"

using namespace mpmcd;

int main(int argc, char** argv) {
  apply_openmp_wait_policy(argv);  // as mpmcd: its spin count (may execute this again)
  apply_allocator_policy();        // and its allocator settings
  std::string scheme_name = "partition", csv, trace;
  int threads = 1, warmup = 50, steps = 50, cpu = 0, every = 25, mirror = 0;
  double threshold = 0;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string k = argv[i], v = argv[i + 1];
    if (k == "--scheme")
      scheme_name = v;
    else if (k == "--threads")
      threads = std::stoi(v);
    else if (k == "--warmup")
      warmup = std::stoi(v);
    else if (k == "--steps")
      steps = std::stoi(v);
    else if (k == "--csv")
      csv = v;
    else if (k == "--cpu-time")
      cpu = std::stoi(v);
    else if (k == "--rebalance")
      threshold = std::stod(v);
    else if (k == "--rebalance-every")
      every = std::stoi(v);
    else if (k == "--mirror")
      mirror = std::stoi(v);
    else if (k == "--trace")
      trace = v;
    else {
      std::cerr << "unknown option " << k << "\n";
      return 2;
    }
  }
  const auto& comm = parallel::Comm::world();
  omp_set_num_threads(threads);
  const auto scheme = parallel::scheme_from_string(scheme_name);
  bench::Slice setup = bench::make_slice_300();
  auto& model = setup.model;
  mpm::Settings<2> s;
  s.theta = 1.0;
  s.linear_solver = mpm::LinearSolverKind::kCg;
  s.contact.enabled = true;
  s.contact.grain_compliance = false;
  s.contact.walls = setup.walls;
  mpm::ImplicitSolver<2> solver(model.grid, s, model.points, model.grains, model.law_ptrs());
  if (comm.size() > 1 && mirror == 0)
    solver.set_distribution(
        &comm, parallel::deal_grains(model.points, model.grains, scheme, comm.size()), scheme);
  // --cpu-time 1: stage timers in thread CPU time (a rank's work without waiting for a core).
  solver.timers().set_thread_cpu_time(cpu != 0);
  const double dt = 1e-7;
  int step = 0;
  double contacts = 0, sweeps = 0, iters = 0;
  std::int64_t bytes0 = 0, moved_bytes = 0;  // moved_bytes: re-balancing (grain migration)
  std::chrono::steady_clock::time_point t0;
  for (; step < warmup + steps; ++step) {
    if (step == warmup) {
      comm.barrier();
      solver.timers().clear();
      if (!trace.empty()) comm.trace_syncs(trace);
      comm.record_syncs();
      bytes0 = comm.bytes_sent();
      t0 = std::chrono::steady_clock::now();
    }
    solver.set_time(step * dt);
    const auto st = solver.solve_step(dt);
    if (!st.converged) {
      if (comm.rank() == 0) std::cerr << "step " << step << ": " << st.failure << "\n";
      parallel::Comm::finalize();
      return 3;
    }
    solver.commit();
    if (mirror != 0) comm.barrier();  // the one synchronisation per step of identical work
    // Re-balancing as `mpmcd run` does it (partition scheme), its cost inside the timed steps.
    if (comm.size() > 1 && mirror == 0 && scheme == parallel::Scheme::kPartition && threshold > 0 &&
        (step + 1) % every == 0) {
      mpmcd::ScopedStage ts(&solver.timers(), "rebalance");
      auto owner = solver.owner();
      bool moved = false;
      const std::int64_t before = comm.bytes_sent();
      const double imbalance = parallel::rebalance(comm, model.points, model.grains, owner,
                                                   solver.take_grain_work(), threshold, moved);
      if (moved) solver.set_distribution(&comm, owner, scheme);
      if (step >= warmup) moved_bytes += comm.bytes_sent() - before;
      if (comm.rank() == 0)
        std::cerr << fmt::format("step {}: work imbalance {:.4f}{}\n", step + 1, imbalance,
                                 moved ? ", grains dealt again" : "");
    }
    if (step >= warmup) {
      contacts += static_cast<double>(st.contacts);
      sweeps += static_cast<double>(st.gs_sweeps);
      iters += st.iterations;
    }
  }
  comm.barrier();
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const auto solo = comm.solo_report();
  std::vector<double> bytes{static_cast<double>(comm.bytes_sent() - bytes0),
                            static_cast<double>(moved_bytes)};
  std::vector<double> bytes_max{bytes[0]};
  comm.sum(bytes);
  comm.max(bytes_max);
  // Work of this rank: every top-level stage minus the communication (waiting) inside it; the
  // largest over ranks is the step time of a machine where no rank waits for a core.
  double work = 0;
  for (const auto& [name, t] : solver.timers().totals()) {
    if (name.ends_with(".comm") || name.starts_with("comm.") || name == "contact.gs" ||
        name == kThreadedStage)
      continue;
    const auto it = solver.timers().totals().find(name + ".comm");
    work += t - (it == solver.timers().totals().end() ? 0.0 : it->second);
  }
  std::vector<double> work_max{work};
  comm.max(work_max);
  const auto rows = parallel::stage_report(comm, solver.timers().totals());
  const std::string report = parallel::stage_report_csv(rows, wall, comm.size(), threads, steps,
                                                        bytes[0] / comm.size() / steps, solo);
  if (comm.rank() == 0) {
    // One row: configuration, step time, serial shares (measured at every synchronisation, and
    // the stage-total imbalance that bounds it from below), time per step in which one rank
    // works alone, traffic, then per stage (ms per step): mean time and stage-total imbalance.
    double imbalance = 0;
    const double one = parallel::one_thread_fraction(rows, wall, threads, solo);
    std::string stages;
    for (const auto& r : rows) {
      if (!r.nested) imbalance += r.serial;
      stages +=
          fmt::format(",{}={:.4f}/{:.4f}", r.name, 1e3 * r.mean / steps, 1e3 * r.serial / steps);
    }
    const std::string line = fmt::format(
        "{},{},{},{},{},{:.4f},{:.4f},{:.5f},{:.5f},{:.4f},{:.4f},{:.5f},{:.5f},{:.5f},{:.1f},"
        "{:.1f},{:.1f},{:.1f},{:.2f},{:.2f}{}\n",
        mirror != 0 ? "mirror" : scheme_name, comm.size(), threads, model.points.size(), steps,
        1e3 * wall / steps, 1e3 * work_max[0] / steps, solo.solo_s / wall, imbalance / wall,
        1e3 * solo.solo_s / steps, 1e3 * solo.solo_cpu_s / steps, solo.solo_work_fraction,
        solo.wait_s / wall, one, bytes[0] / comm.size() / steps, bytes_max[0] / steps,
        bytes[1] / comm.size() / steps, contacts / steps, sweeps / steps, iters / steps, stages);
    std::cout << report << line;
    if (!csv.empty()) {
      const bool fresh = !std::filesystem::exists(csv);
      std::ofstream out(csv, std::ios::app);
      if (fresh)
        out << "scheme,ranks,threads,points,steps,step_ms,work_max_ms,serial_fraction,"
               "stage_imbalance_fraction,solo_ms,solo_cpu_ms,counted_serial_fraction,"
               "sync_wait_fraction,one_thread_fraction,"
               "bytes_per_rank_step,bytes_max_rank_step,rebalance_bytes_per_rank_step,"
               "contacts,gs_sweeps,newton_it,stages\n";
      out << line;
    }
  }
  parallel::Comm::finalize();
  return 0;
}
