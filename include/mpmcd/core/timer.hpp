#pragma once
/// Wall-clock stage timers: accumulate seconds per named stage.
#include <omp.h>
#include <time.h>

#include <chrono>
#include <map>
#include <string>

namespace mpmcd {

/// Accumulated wall time per stage name [s]. Not thread-safe: use from the thread driving the step.
class StageTimers {
 public:
  /// Adds `seconds` [s] to stage `name`.
  void add(const std::string& name, double seconds) { totals_[name] += seconds; }
  /// Total time of each stage so far [s].
  const std::map<std::string, double>& totals() const { return totals_; }
  /// Resets all stages to zero.
  void clear() { totals_.clear(); }
  /// Measure CPU time of the calling thread instead of wall time (benchmarks on a shared,
  /// oversubscribed machine: a rank's work without the time it waits for a core) [-].
  void set_thread_cpu_time(bool on) { cpu_ = on; }
  /// The current reading of the clock in use [s].
  double now() const {
    if (cpu_) {
      timespec ts{};
      clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
      return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
    }
    return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch())
        .count();
  }

 private:
  std::map<std::string, double> totals_;
  bool cpu_ = false;
};

/// RAII scope that adds its lifetime [s] to a stage of a StageTimers (no-op if timers is null).
class ScopedStage {
 public:
  /// Starts timing stage `name` into `timers`.
  ScopedStage(StageTimers* timers, const char* name)
      : timers_(timers), name_(name), start_(timers ? timers->now() : 0.0) {}
  ~ScopedStage() { done(); }
  /// Adds the time so far and stops (the destructor then adds nothing).
  void done() {
    if (timers_) timers_->add(name_, timers_->now() - start_);
    timers_ = nullptr;
  }
  ScopedStage(const ScopedStage&) = delete;
  ScopedStage& operator=(const ScopedStage&) = delete;

 private:
  StageTimers* timers_;
  const char* name_;
  double start_;
};

/// Name of the stage that ThreadedRegion fills: wall time in OpenMP regions that ran on more
/// than one thread (nested in the other stages; docs/parallel.md, one-thread share).
inline constexpr const char* kThreadedStage = "threads";

/// RAII around one OpenMP region, constructed just before its `#pragma omp parallel` with the
/// region's `if` condition: adds the region's wall time [s] to stage kThreadedStage of `timers`
/// when the region runs on more than one thread (no-op if timers is null).
class ThreadedRegion {
 public:
  /// Starts timing if `parallel` holds, more than one thread is available and no region is open.
  ThreadedRegion(StageTimers* timers, bool parallel)
      : stage_(parallel && timers && omp_get_max_threads() > 1 && !omp_in_parallel() ? timers
                                                                                     : nullptr,
               kThreadedStage) {}
  /// Stops timing now (the region has ended; the rest of the scope runs on one thread).
  void done() { stage_.done(); }

 private:
  ScopedStage stage_;
};

}  // namespace mpmcd
