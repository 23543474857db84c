#pragma once
/// How long OpenMP threads spin at a barrier before they sleep (libgomp's GOMP_SPINCOUNT), set for
/// mpmcd's many short parallel regions (docs/parallel.md, "A shared machine").
#include <string>

namespace mpmcd {

/// Spin iterations mpmcd asks of libgomp at each wait before a thread sleeps [-]. libgomp's
/// default, 300,000 iterations of a pause loop (milliseconds), makes a thread whose partner waits
/// for a time slice burn its own. Measured on this 2-core machine with bench_compaction (2 threads
/// against 1, docs/parallel.md): under a load of 8, d/4 steps took 731 / 201 / 151 ms with spin
/// 300,000 / 10,000 / 1,000 against 144 ms on 1 thread; with one other busy process, d/4 515 /
/// 119 / 95 ms and d/8 873 / 456 / 434 ms against 87-92 and 415-437 ms on 1 thread; with a core
/// free, 1,000 gave d/8 in 239 ms against 391 ms on 1 thread.
inline constexpr const char* kGompSpinCount = "1000";

/// Called first in main: unless the user chose a wait policy (OMP_WAIT_POLICY or GOMP_SPINCOUNT
/// set), sets GOMP_SPINCOUNT = kGompSpinCount and executes the program again (libgomp reads its
/// environment once, when it is loaded, before main). Returns only when no restart is needed or
/// it failed (the run then goes on with libgomp's defaults).
void apply_openmp_wait_policy(char** argv);

/// The wait policy in force, for the run's log: "GOMP_SPINCOUNT=<n>", "OMP_WAIT_POLICY=<p>" or
/// "libgomp default".
std::string openmp_wait_policy();

}  // namespace mpmcd
