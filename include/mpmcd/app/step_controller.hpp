#pragma once
/// The time step of a run (docs/robustness.md, "Numerical failure" and "Δt from the Newton
/// count"): a failed attempt is retried from the same state with Δt cut by cut_factor, but never
/// below dt_min. With the fixed control, after recover_steps good steps at a cut Δt, Δt is
/// doubled back, up to the nominal Δt. With the Newton control, after each good step Δt is
/// scaled by sqrt(target / Newton iterations), within [1/2, 5/4], dt_min and dt_max; it grows
/// only once recover_steps good steps have passed since the last cut.
#include <cstdint>

#include "mpmcd/io/config.hpp"

namespace mpmcd::app {

/// Δt cut on failure, recovered after good steps, or scaled by the Newton count.
class StepController {
 public:
  /// Nominal (first) step `dt` [s], `cut_factor` in (0, 1) applied on failure [-], smallest
  /// step `dt_min` [s], good steps `recover_steps` after a cut before Δt grows [-]; with
  /// `target_iterations` > 0 [-] Δt follows the Newton count up to `dt_max` [s] (>= dt).
  StepController(double dt, double cut_factor, double dt_min, std::int64_t recover_steps,
                 int target_iterations = 0, double dt_max = 0.0);
  /// The same from the input's [time] table.
  explicit StepController(const io::TimeSection& time);

  /// Continues at step `dt` [s] with `good_since_cut` good steps since the last cut [-] (a
  /// restart; the values its checkpoint holds), at most the largest step.
  void restore(double dt, std::int64_t good_since_cut);

  /// The step to try when `remaining` [s] of simulated time are left: Δt, or less to land on the
  /// end [s].
  double next(double remaining) const;
  /// The attempt with step `tried` [s] failed: cuts Δt to cut_factor * tried and returns true, or
  /// returns false and changes nothing when that would be below dt_min (the run cannot go on).
  bool cut(double tried);
  /// A step of length `taken` [s] (default: Δt) converged in `iterations` Newton iterations [-]:
  /// the fixed control counts it while Δt is cut and after recover_steps such steps doubles Δt
  /// (at most the nominal Δt); the Newton control scales Δt (a step shortened to land on an end
  /// leaves it). Returns true when Δt changed.
  bool succeeded(int iterations = 0, double taken = 0.0);

  /// The current step Δt [s].
  double dt() const { return dt_; }
  /// The nominal step [s] (the first step of the Newton control).
  double nominal() const { return nominal_; }
  /// The largest step [s] (the nominal one with the fixed control).
  double dt_max() const { return dt_max_; }
  /// The smallest step allowed [s].
  double dt_min() const { return dt_min_; }
  /// True when Δt follows the Newton count.
  bool adaptive() const { return target_ > 0; }
  /// Good steps since the last cut, counted while Δt is below the nominal one (fixed control) or
  /// up to recover_steps (Newton control) [-].
  std::int64_t good_since_cut() const { return good_since_cut_; }

  /// Smallest and largest factor of one Newton-control change [-].
  static constexpr double kMinFactor = 0.5, kMaxFactor = 1.25;

 private:
  double nominal_, cut_factor_, dt_min_;
  std::int64_t recover_steps_;
  int target_;
  double dt_max_;
  double dt_;
  std::int64_t good_since_cut_;
};

}  // namespace mpmcd::app
