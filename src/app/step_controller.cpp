#include "mpmcd/app/step_controller.hpp"

#include <algorithm>
#include <cmath>

namespace mpmcd::app {

StepController::StepController(double dt, double cut_factor, double dt_min,
                               std::int64_t recover_steps, int target_iterations, double dt_max)
    : nominal_(dt),
      cut_factor_(cut_factor),
      dt_min_(dt_min),
      recover_steps_(recover_steps),
      target_(target_iterations),
      dt_max_(target_iterations > 0 ? std::max(dt, dt_max) : dt),
      dt_(dt),
      good_since_cut_(target_iterations > 0 ? recover_steps : 0) {}  // no cut yet

StepController::StepController(const io::TimeSection& time)
    : StepController(time.dt, time.cut_factor, time.dt_min, time.recover_steps,
                     time.control == "newton" ? time.target_iterations : 0, time.largest_dt()) {}

void StepController::restore(double dt, std::int64_t good_since_cut) {
  dt_ = std::min(dt, dt_max_);  // an input changed between the runs may lower the largest step
  good_since_cut_ = good_since_cut;
}

double StepController::next(double remaining) const {
  return std::min(dt_, remaining);
}

bool StepController::cut(double tried) {
  const double dt = tried * cut_factor_;
  if (dt < dt_min_) return false;
  dt_ = dt;
  good_since_cut_ = 0;
  return true;
}

bool StepController::succeeded(int iterations, double taken) {
  if (!adaptive()) {
    if (dt_ < nominal_ && ++good_since_cut_ >= recover_steps_) {
      dt_ = std::min(nominal_, 2 * dt_);
      good_since_cut_ = 0;
      return true;
    }
    return false;
  }
  if (good_since_cut_ < recover_steps_) ++good_since_cut_;
  if (taken > 0 && taken < dt_) return false;  // shortened to land on an end: no information
  // The Newton count grows with Δt (about as Δt^1.4 in dense 3D packings, docs/three_d.md): the
  // square root moves Δt part of the way toward the target count, the bounds keep one change
  // small and let a cut Δt settle before it grows.
  double factor = std::sqrt(static_cast<double>(target_) / std::max(iterations, 1));
  factor = std::clamp(factor, kMinFactor, kMaxFactor);
  if (factor > 1 && good_since_cut_ < recover_steps_) factor = 1;
  const double dt = std::clamp(dt_ * factor, dt_min_, dt_max_);
  const bool changed = dt != dt_;
  dt_ = dt;
  return changed;
}

}  // namespace mpmcd::app
