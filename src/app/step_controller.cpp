#include "mpmcd/app/step_controller.hpp"

#include <algorithm>

namespace mpmcd::app {

StepController::StepController(double dt, double cut_factor, double dt_min,
                               std::int64_t recover_steps)
    : nominal_(dt),
      cut_factor_(cut_factor),
      dt_min_(dt_min),
      recover_steps_(recover_steps),
      dt_(dt) {}

StepController::StepController(const io::TimeSection& time)
    : StepController(time.dt, time.cut_factor, time.dt_min, time.recover_steps) {}

void StepController::restore(double dt, std::int64_t good_since_cut) {
  dt_ = dt;
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

bool StepController::succeeded() {
  if (dt_ < nominal_ && ++good_since_cut_ >= recover_steps_) {
    dt_ = std::min(nominal_, 2 * dt_);
    good_since_cut_ = 0;
    return true;
  }
  return false;
}

}  // namespace mpmcd::app
