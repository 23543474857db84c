#pragma once
/// The time step of a run (docs/robustness.md, "Numerical failure"): a failed attempt is retried
/// from the same state with Δt cut by cut_factor, but never below dt_min; after recover_steps good
/// steps at a cut Δt, Δt is doubled back, up to the nominal Δt.
#include <cstdint>

#include "mpmcd/io/config.hpp"

namespace mpmcd::app {

/// Δt cut on failure and recovery after good steps.
class StepController {
 public:
  /// Nominal step `dt` [s], `cut_factor` in (0, 1) applied on failure [-], smallest step
  /// `dt_min` [s], good steps `recover_steps` after which a cut Δt is doubled back [-].
  StepController(double dt, double cut_factor, double dt_min, std::int64_t recover_steps);
  /// The same from the input's [time] table.
  explicit StepController(const io::TimeSection& time);

  /// Continues at step `dt` [s] with `good_since_cut` good steps since the last cut [-] (a
  /// restart; the values its checkpoint holds).
  void restore(double dt, std::int64_t good_since_cut);

  /// The step to try when `remaining` [s] of simulated time are left: Δt, or less to land on the
  /// end [s].
  double next(double remaining) const;
  /// The attempt with step `tried` [s] failed: cuts Δt to cut_factor * tried and returns true, or
  /// returns false and changes nothing when that would be below dt_min (the run cannot go on).
  bool cut(double tried);
  /// A step succeeded: counts it while Δt is cut; after recover_steps such steps doubles Δt (at
  /// most the nominal Δt) and returns true (Δt restored), else returns false.
  bool succeeded();

  /// The current step Δt [s].
  double dt() const { return dt_; }
  /// The nominal step [s].
  double nominal() const { return nominal_; }
  /// The smallest step allowed [s].
  double dt_min() const { return dt_min_; }
  /// Good steps since the last cut, counted while Δt is below the nominal one [-].
  std::int64_t good_since_cut() const { return good_since_cut_; }

 private:
  double nominal_, cut_factor_, dt_min_;
  std::int64_t recover_steps_;
  double dt_;
  std::int64_t good_since_cut_ = 0;
};

}  // namespace mpmcd::app
