#pragma once
/// Wall-clock stage timers: accumulate seconds per named stage.
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

 private:
  std::map<std::string, double> totals_;
};

/// RAII scope that adds its lifetime [s] to a stage of a StageTimers (no-op if timers is null).
class ScopedStage {
 public:
  /// Starts timing stage `name` into `timers`.
  ScopedStage(StageTimers* timers, const char* name)
      : timers_(timers), name_(name), start_(std::chrono::steady_clock::now()) {}
  ~ScopedStage() {
    if (timers_)
      timers_->add(
          name_, std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count());
  }
  ScopedStage(const ScopedStage&) = delete;
  ScopedStage& operator=(const ScopedStage&) = delete;

 private:
  StageTimers* timers_;
  const char* name_;
  std::chrono::steady_clock::time_point start_;
};

}  // namespace mpmcd
