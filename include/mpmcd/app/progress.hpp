#pragma once
/// Progress of a run toward the criterion that will end it (docs/robustness.md, "Progress"): the
/// time limit [time] end_time or a [stop] criterion (Φ, strain, stress). Each criterion's fraction
/// of the way and its ETA, extrapolated from the recent rate of change of its quantity per second
/// of wall-clock time; the one expected to end the run first is reported.
#include <deque>
#include <limits>
#include <optional>
#include <string>

#include "mpmcd/io/config.hpp"

namespace mpmcd::app {

/// The quantities the end criteria follow, at one moment of a run.
struct ProgressSample {
  double wall = 0;               ///< wall-clock time since this invocation started [s]
  double time = 0;               ///< simulated time t [s]
  std::optional<double> phi;     ///< solid fraction Φ of the box (compaction) [-]
  std::optional<double> strain;  ///< |ε| = |ln(h/h0)| of the box [-]
  std::optional<double> stress;  ///< bottom wall's compressive stress -σ [Pa]
};

/// The criterion expected to end the run first, how far the run is toward it and when it is due.
struct ProgressEstimate {
  std::string criterion = "end_time";  ///< "end_time", "stop.phi", "stop.strain" or "stop.stress"
  double target = 0;                   ///< its threshold [s, -, - or Pa]
  double fraction = 0;                 ///< fraction of the way to it, in [0, 1] [-]
  /// Wall-clock time left until it is reached, +inf when no rate is known yet [s].
  double eta = std::numeric_limits<double>::infinity();
};

/// Collects samples and extrapolates. The fraction of each criterion is measured from the start of
/// the run (t = 0, also after a restart): t / end_time, (Φ - Φ0) / (Φ_stop - Φ0), |ε| /
/// strain_stop, -σ / stress_stop. Its ETA is (target - value) / rate, the rate being the change of
/// the value per wall-clock second over the recent window (the last quarter of the wall time
/// elapsed, at least the last two samples); a criterion whose value does not grow has no ETA. The
/// estimate is the criterion with the smallest ETA, end_time when none has one.
class ProgressEstimator {
 public:
  /// `end_time` [s], the [stop] thresholds `stop` (0 = not set) and the solid fraction at t = 0
  /// `phi0` [-] (needed by stop.phi).
  ProgressEstimator(double end_time, const io::StopSection& stop, double phi0);

  /// Adds the sample of the current moment (wall times non-decreasing).
  void add(const ProgressSample& sample);

  /// The estimate from the samples so far (the last one is the current state).
  ProgressEstimate estimate() const;

  /// The samples kept for the rates (the recent window) [-].
  std::size_t samples() const { return samples_.size(); }

 private:
  double end_time_;
  io::StopSection stop_;
  double phi0_;
  std::deque<ProgressSample> samples_;
};

/// A wall-clock duration for the progress line [-]: "42 s", "17.3 min", "5.2 h", "?" if not finite.
std::string format_eta(double seconds);

}  // namespace mpmcd::app
