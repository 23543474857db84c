// Steps of the paper compaction in its dense state, 2D or 3D (issue 16; docs/parallel.md,
// "Dense-state benchmark"): each checkpoint given (a run of examples/paper_compaction stopped near
// Phi = 0.9, made by tools/compaction_checkpoints.sh) is restored as `mpmcd run --restart` restores
// it (app::restore_from_checkpoint: the input stored in the checkpoint, its settings, its warm
// start and time step), then `--warmup` steps are taken untimed and `--steps` timed, as the app's
// loop takes them (boundaries at t + dt, a failed step retried with a cut dt). Per step: wall time
// (the benchmark's time), the share of the wall time of each solver stage (p2g, contact.detect,
// newton.assemble, newton.solve, contact.solve and its pivoting contact.as.pivot, g2p),
// one_thread_fraction (share of the wall time
// on one thread, as `mpmcd run` reports it), contacts, Gauss-Seidel sweeps, Newton iterations.
//   tools/compaction_checkpoints.sh d4
//   build/release/bench/bench_compaction build/compaction_checkpoints/lambda3_d4.h5
//     --benchmark_counters_tabular=true --benchmark_repetitions=3
//     --benchmark_enable_random_interleaving=true          (one command line)
// 3D (docs/three_d.md, "Compaction in 3D"): a checkpoint of examples/compaction_3d, e.g.
//   build/release/mpmcd run examples/compaction_3d/compaction_3d_quick.toml -o build/c3d
//     --stop-after 84                                      (Phi = 0.745; exits 4)
// Checkpoints: the arguments left after Google Benchmark's, else MPMCD_COMPACTION_CHECKPOINTS
// (paths separated by ':'); none: the benchmark is skipped with a message. Own options:
// `--steps N` (5), `--warmup N` (1), `--threads 1,2` (thread counts), `--dense-fill F` (replaces
// the run's [solver] dense_fill, to time the dense grain factorisations). A repetition restores the
// checkpoint again, so repetitions time the same steps; their "min" is the best of them.
#include <benchmark/benchmark.h>
#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <iostream>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "mpmcd/app/compaction_observer.hpp"
#include "mpmcd/app/model_builder.hpp"
#include "mpmcd/app/run_state.hpp"
#include "mpmcd/app/step_controller.hpp"
#include "mpmcd/core/allocator.hpp"
#include "mpmcd/core/openmp_env.hpp"
#include "mpmcd/mpm/solver.hpp"
#include "mpmcd/parallel/distribute.hpp"

using namespace mpmcd;

namespace {

struct Options {
  std::vector<std::string> checkpoints;  // checkpoint files
  int steps = 5;                         // timed steps per repetition
  int warmup = 1;                        // untimed steps after the restore
  std::vector<int> threads{1, 2};        // thread counts
  double dense_fill = -1;                // replaces Settings::dense_fill when >= 0 [-]
};

// The --dense-fill value (negative: the run's own).
double g_dense_fill = -1;

// Splits `text` at `sep` (empty parts dropped).
std::vector<std::string> split(const std::string& text, char sep) {
  std::vector<std::string> parts;
  std::stringstream in(text);
  for (std::string p; std::getline(in, p, sep);)
    if (!p.empty()) parts.push_back(p);
  return parts;
}

// The solver of a restored run, set up as app::detail::Run sets it up on one process, and its
// loop: `step` takes one committed step as Run::go does (dt from the step controller, boundaries
// at t + dt, a failed attempt retried with a cut dt, counted in `retries`).
template <int Dim>
class RestoredStepper {
 public:
  explicit RestoredStepper(app::RestoredRun<Dim>& run)
      : run_(run),
        solver_(run.model.grid, run.settings, run.model.points, run.model.grains,
                run.model.law_ptrs()),
        dt_control_(run.config.time),
        moving_(std::any_of(run.config.boundaries.begin(), run.config.boundaries.end(),
                            [](const auto& b) { return b.moving; })),
        t_(run.state.time) {
    solver_.set_boundary_conditions(app::build_boundaries(run.config, run.model.grid, 0.0));
    dt_control_.restore(run.state.dt, run.state.good_since_cut);
    solver_.set_warm_start(run.warm);
  }

  // One committed step; its stats, or those of the last failed attempt (converged false).
  mpm::StepStats step() {
    for (;;) {
      const double dt = dt_control_.next(run_.config.time.end_time - t_);
      solver_.set_time(t_);
      if (moving_)
        solver_.set_boundary_conditions(
            app::build_boundaries(run_.config, run_.model.grid, t_ + dt));
      mpm::StepStats st = solver_.solve_step(dt);
      if (!st.converged) {
        if (!st.retryable || !dt_control_.cut(dt)) return st;
        ++retries;
        continue;
      }
      solver_.commit();
      dt_control_.succeeded();
      t_ += dt;
      return st;
    }
  }

  mpm::ImplicitSolver<Dim>& solver() { return solver_; }
  double time() const { return t_; }
  int retries = 0;  // failed attempts retried with a cut dt

 private:
  app::RestoredRun<Dim>& run_;
  mpm::ImplicitSolver<Dim> solver_;
  app::StepController dt_control_;
  bool moving_;
  double t_;
};

// Restores `path` (a run of dimension Dim) on `threads` threads and times the steps (one step per
// iteration).
template <int Dim>
void dense_steps(benchmark::State& state, const std::string& path, int threads, int warmup) {
  omp_set_num_threads(threads);
  std::optional<app::RestoredRun<Dim>> restored;
  try {
    restored.emplace(app::restore_from_checkpoint<Dim>(path));
  } catch (const std::exception& e) {
    state.SkipWithError((path + ": " + e.what()).c_str());
    return;
  }
  app::RestoredRun<Dim>& run = *restored;
  if (g_dense_fill >= 0) run.settings.dense_fill = g_dense_fill;
  RestoredStepper<Dim> stepper(run);
  for (int i = 0; i < warmup; ++i)
    if (const auto st = stepper.step(); !st.converged) {
      state.SkipWithError(("warm-up step: " + st.failure).c_str());
      return;
    }
  stepper.solver().timers().clear();
  double contacts = 0, active = 0, sweeps = 0, iters = 0, factorizations = 0, dense = 0,
         projected = 0, wall = 0;
  for (auto _ : state) {
    const auto t0 = std::chrono::steady_clock::now();
    const auto st = stepper.step();
    wall += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (!st.converged) {
      state.SkipWithError(st.failure.c_str());
      break;
    }
    contacts += static_cast<double>(st.contacts);
    active += static_cast<double>(st.active_contacts);
    sweeps += static_cast<double>(st.gs_sweeps);
    iters += st.iterations;
    factorizations += static_cast<double>(st.factorizations);
    dense += static_cast<double>(st.dense_factorizations);
    projected += static_cast<double>(st.projected_factorizations);
  }
  const double steps = std::max<double>(1.0, static_cast<double>(state.iterations()));
  const auto& totals = stepper.solver().timers().totals();
  const auto share = [&](const char* stage) {
    const auto it = totals.find(stage);
    return it == totals.end() || wall <= 0 ? 0.0 : it->second / wall;
  };
  for (const char* stage : {"p2g", "contact.detect", "newton.assemble", "newton.solve",
                            "contact.solve", "contact.as.pivot", "g2p"})
    state.counters[std::string(stage) + "_share"] = share(stage);
  // Every other stage the timers saw (the contact solve's parts: delassus, as.assemble,
  // as.check, law, ...), under the same name.
  for (const auto& [name, secs] : totals)
    if (!state.counters.contains(name + "_share"))
      state.counters[name + "_share"] = share(name.c_str());
  // One process: no synchronisation to wait in, the stage rows are this process's totals.
  std::vector<parallel::StageTime> rows;
  for (const auto& [name, secs] : totals)
    rows.push_back({.name = name, .max = secs, .mean = secs, .min = secs});
  state.counters["one_thread_fraction"] =
      parallel::one_thread_fraction(rows, wall, threads, parallel::Comm::SoloReport{});
  app::CompactionObserver<Dim> observer(run.config, run.model);
  const auto now = observer.now(app::CompactionObserver<Dim>::total_area(
                                    app::CompactionObserver<Dim>::grain_areas(run.model)),
                                {}, stepper.time());
  state.counters["phi"] = now ? now->phi : 0.0;
  state.counters["points"] = static_cast<double>(run.model.points.size());
  // Point-steps per second of the whole step (contact included) [1/s].
  state.counters["point_steps_per_s"] =
      wall > 0 ? static_cast<double>(run.model.points.size()) * steps / wall : 0.0;
  state.counters["contacts"] = contacts / steps;
  state.counters["active"] = active / steps;
  state.counters["gs_sweeps"] = sweeps / steps;
  state.counters["newton_it"] = iters / steps;
  state.counters["factorizations"] = factorizations / steps;
  state.counters["dense_factorizations"] = dense / steps;
  state.counters["projected"] = projected / steps;
  state.counters["retries"] = stepper.retries;
}

// The dense steps of checkpoint `path`, 2D or 3D as its input says.
void BM_DenseSteps(benchmark::State& state, const std::string& path, int threads, int warmup) {
  int dimension = 2;
  try {
    dimension = app::load_restart(path, "").config.simulation.dimension;
  } catch (const std::exception& e) {
    state.SkipWithError((path + ": " + e.what()).c_str());
    return;
  }
  if (dimension == 3)
    dense_steps<3>(state, path, threads, warmup);
  else
    dense_steps<2>(state, path, threads, warmup);
}

// Reads the options left after Google Benchmark's; false (with a message) on a bad one.
bool parse_options(int argc, char** argv, Options& opt) {
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const bool has_value = i + 1 < argc;
    if ((a == "--steps" || a == "--warmup" || a == "--threads" || a == "--dense-fill") &&
        !has_value) {
      std::cerr << a << " needs a value\n";
      return false;
    }
    if (a == "--steps") {
      opt.steps = std::stoi(argv[++i]);
    } else if (a == "--warmup") {
      opt.warmup = std::stoi(argv[++i]);
    } else if (a == "--dense-fill") {
      opt.dense_fill = std::stod(argv[++i]);
    } else if (a == "--threads") {
      opt.threads.clear();
      for (const auto& t : split(argv[++i], ',')) opt.threads.push_back(std::stoi(t));
    } else if (a.starts_with("--")) {
      std::cerr << "unknown option " << a << "\n";
      return false;
    } else {
      opt.checkpoints.push_back(a);
    }
  }
  if (opt.checkpoints.empty())
    if (const char* env = std::getenv("MPMCD_COMPACTION_CHECKPOINTS"))
      opt.checkpoints = split(env, ':');
  return opt.steps > 0 && opt.warmup >= 0 && !opt.threads.empty();
}

}  // namespace

int main(int argc, char** argv) {
  apply_openmp_wait_policy(argv);  // as mpmcd: its spin count (may execute this again)
  apply_allocator_policy();        // and its allocator settings
  benchmark::Initialize(&argc, argv);
  Options opt;
  if (!parse_options(argc, argv, opt)) return 2;
  g_dense_fill = opt.dense_fill;
  if (opt.checkpoints.empty()) {
    const char* why =
        "no checkpoint given: make one with tools/compaction_checkpoints.sh d4, then pass "
        "build/compaction_checkpoints/lambda3_d4.h5 (or set MPMCD_COMPACTION_CHECKPOINTS)";
    std::cerr << "bench_compaction: " << why << "\n";
    benchmark::RegisterBenchmark("BM_DenseSteps/no_checkpoint", [why](benchmark::State& state) {
      state.SkipWithError(why);
    })->Iterations(1);
  }
  for (const auto& path : opt.checkpoints)
    for (const int threads : opt.threads)
      benchmark::RegisterBenchmark(("BM_DenseSteps/" + std::filesystem::path(path).stem().string() +
                                    "/threads:" + std::to_string(threads))
                                       .c_str(),
                                   BM_DenseSteps, path, threads, opt.warmup)
          ->Iterations(opt.steps)
          ->Unit(benchmark::kMillisecond)
          ->UseRealTime()
          ->ComputeStatistics("min", [](const std::vector<double>& v) {
            return *std::min_element(v.begin(), v.end());
          });
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
