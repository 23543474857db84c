#pragma once
/// Measured choice between the threads and one thread for a loop repeated many times with little
/// work per repetition (the Gauss-Seidel sweeps: one OpenMP region per colour).
#include <algorithm>
#include <array>

namespace mpmcd {

/// Chooses, repetition by repetition, whether a fine-grained threaded loop runs on the threads or
/// on one thread, from the measured cost of each. On an idle machine the threads win; when other
/// processes share the cores, a thread waiting for a time slice at each of many region ends makes
/// the threaded loop up to 20x slower than one thread (docs/parallel.md, "A shared machine breaks
/// the threaded step"). Only usable where both choices give the same bits (the loop's result does
/// not depend on the thread count), so the choice changes the speed, never the answer.
///
/// Each choice's cost is an exponential mean (weight 1/2) of the cost per unit of work [s],
/// restarted at each trial. The cheaper one is used; the other is tried again after `explore_every`
/// repetitions, a gap that doubles (to kMaxGap) each time the trial loses and returns to kMinGap
/// when it wins, so that a change of load is noticed while a losing choice costs at most about
/// 1/kMaxGap of the time.
class ThreadTuner {
 public:
  /// Whether the next repetition runs on the threads (the first repetitions measure both).
  bool threaded() {
    if (cost_[1] < 0) return trial(true);
    if (cost_[0] < 0) return trial(false);
    const bool best = cost_[1] <= cost_[0];
    if (++since_trial_ >= gap_) return trial(!best);
    return best;
  }

  /// Records the cost [s per unit of work] of a repetition run on the threads or not.
  void record(bool threaded, double cost) {
    double& c = cost_[threaded ? 1 : 0];
    // A trial's cost replaces the old mean, measured under a load that may have gone.
    c = c < 0 || trying_ ? cost : 0.5 * (c + cost);
    if (trying_) {
      trying_ = false;
      const bool won =
          cost_[threaded ? 1 : 0] < cost_[threaded ? 0 : 1] || cost_[threaded ? 0 : 1] < 0;
      gap_ = won ? kMinGap : std::min(2 * gap_, kMaxGap);
    }
  }

  /// Mean cost of the threads and of one thread [s per unit of work]; negative if not measured.
  std::array<double, 2> costs() const { return {cost_[1], cost_[0]}; }

  static constexpr int kMinGap = 8;    ///< repetitions between trials after a win [-]
  static constexpr int kMaxGap = 256;  ///< longest gap between trials [-]

 private:
  bool trial(bool threaded) {
    since_trial_ = 0;
    trying_ = true;
    return threaded;
  }

  std::array<double, 2> cost_{-1.0, -1.0};  // [one thread, threads] [s per unit of work]
  int gap_ = kMinGap;
  int since_trial_ = 0;
  bool trying_ = false;
};

}  // namespace mpmcd
