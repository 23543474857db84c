// DEM packing of N polydisperse disks (diameters uniform in [0.8, 1.2] mm) to phi = 0.78 by
// radius growth (docs/packing.md §7). Reports wall seconds; targets: 300 disks < 5 s,
// 10,000 disks < 2 min on the 2-core development machine.
#include <benchmark/benchmark.h>

#include "mpmcd/core/log.hpp"
#include "mpmcd/packing/packing.hpp"

namespace {

void BM_PackGrow(benchmark::State& state) {
  mpmcd::setup_logging(mpmcd::Verbosity::kQuiet);
  mpmcd::packing::PackingParams p;
  p.count = state.range(0);
  p.diameter_min = 0.8e-3;
  p.diameter_max = 1.2e-3;
  p.target_phi = 0.78;
  p.seed = 42;
  mpmcd::packing::PackingReport report;
  for (auto _ : state) {
    auto packing = mpmcd::packing::generate_packing(p, report);
    benchmark::DoNotOptimize(packing.disks.data());
  }
  state.counters["phi"] = report.phi;
  state.counters["max_overlap_per_d"] = report.max_overlap;
  state.counters["dem_steps"] = static_cast<double>(report.steps);
  state.counters["relaxed"] = report.relaxed ? 1.0 : 0.0;
}

}  // namespace

BENCHMARK(BM_PackGrow)->Arg(300)->Unit(benchmark::kSecond)->UseRealTime()->Iterations(3);
BENCHMARK(BM_PackGrow)->Arg(10000)->Unit(benchmark::kSecond)->UseRealTime()->Iterations(1);

BENCHMARK_MAIN();
