#include "mpmcd/app/progress.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <functional>

namespace mpmcd::app {

namespace {

// The rates are taken over the last quarter of the wall time elapsed.
constexpr double kWindow = 0.25;
// Samples kept at most (a run printing every step keeps a bounded history).
constexpr std::size_t kMaxSamples = 4096;

using Value = std::function<std::optional<double>(const ProgressSample&)>;

}  // namespace

ProgressEstimator::ProgressEstimator(double end_time, const io::StopSection& stop, double phi0)
    : end_time_(end_time), stop_(stop), phi0_(phi0) {}

void ProgressEstimator::add(const ProgressSample& sample) {
  samples_.push_back(sample);
  // Keep one sample at or before the window's start, so that a rate over the window exists.
  const double cut = (1.0 - kWindow) * sample.wall;
  while (samples_.size() > 2 && samples_[1].wall <= cut) samples_.pop_front();
  while (samples_.size() > kMaxSamples) samples_.pop_front();
}

ProgressEstimate ProgressEstimator::estimate() const {
  ProgressEstimate best;
  best.target = end_time_;
  if (samples_.empty()) return best;
  const ProgressSample& now = samples_.back();
  const double window_start = (1.0 - kWindow) * now.wall;
  // Fraction and ETA of one criterion: value v from v0 (its value at t = 0) to target.
  const auto evaluate = [&](const std::string& name, double target, double v0, const Value& value) {
    ProgressEstimate e;
    e.criterion = name;
    e.target = target;
    const auto v = value(now);
    if (!v) return e;
    e.fraction = target > v0 ? std::clamp((*v - v0) / (target - v0), 0.0, 1.0) : 1.0;
    // The oldest sample inside the window, else the latest one before it.
    const ProgressSample* from = nullptr;
    for (const auto& s : samples_) {
      if (s.wall >= now.wall || !value(s)) continue;
      if (s.wall >= window_start) {
        from = &s;
        break;
      }
      from = &s;
    }
    if (!from) return e;
    const double rate = (*v - *value(*from)) / (now.wall - from->wall);
    if (rate > 0 && std::isfinite(rate)) e.eta = std::max(0.0, (target - *v) / rate);
    return e;
  };
  best = evaluate("end_time", end_time_, 0.0, [](const ProgressSample& s) { return s.time; });
  std::vector<ProgressEstimate> stops;
  if (stop_.phi > 0)
    stops.push_back(evaluate("stop.phi", stop_.phi, phi0_, [](const auto& s) { return s.phi; }));
  if (stop_.strain > 0)
    stops.push_back(
        evaluate("stop.strain", stop_.strain, 0.0, [](const auto& s) { return s.strain; }));
  if (stop_.stress > 0)
    stops.push_back(
        evaluate("stop.stress", stop_.stress, 0.0, [](const auto& s) { return s.stress; }));
  for (const auto& e : stops)
    if (e.eta < best.eta) best = e;
  return best;
}

std::string format_eta(double seconds) {
  if (!std::isfinite(seconds)) return "?";
  if (seconds < 120) return fmt::format("{:.0f} s", seconds);
  if (seconds < 7200) return fmt::format("{:.1f} min", seconds / 60);
  return fmt::format("{:.1f} h", seconds / 3600);
}

}  // namespace mpmcd::app
