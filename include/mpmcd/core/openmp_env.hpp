#pragma once
/// How long OpenMP threads spin at a barrier before they sleep (libgomp's GOMP_SPINCOUNT), set for
/// mpmcd's many short parallel regions (docs/parallel.md, "A shared machine").
#include <string>

namespace mpmcd {

/// Spin iterations mpmcd asks of libgomp at each wait before a thread sleeps [-]. libgomp's
/// default, 300,000 (about 0.1-1 ms), makes a thread whose partner waits for a time slice burn
/// its own: with other processes on the cores, a step of the dense compaction on 2 threads took
/// 5x the time of 1 thread (measured, docs/parallel.md).
inline constexpr const char* kGompSpinCount = "10000";

/// Called first in main: unless the user chose a wait policy (OMP_WAIT_POLICY or GOMP_SPINCOUNT
/// set), sets GOMP_SPINCOUNT = kGompSpinCount and executes the program again (libgomp reads its
/// environment once, when it is loaded, before main). Returns only when no restart is needed or
/// it failed (the run then goes on with libgomp's defaults).
void apply_openmp_wait_policy(char** argv);

/// The wait policy in force, for the run's log: "GOMP_SPINCOUNT=<n>", "OMP_WAIT_POLICY=<p>" or
/// "libgomp default".
std::string openmp_wait_policy();

}  // namespace mpmcd
