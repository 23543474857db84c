// ThreadTuner: the measured choice between the threads and one thread (core/thread_tuner.hpp).
#include <gtest/gtest.h>

#include "mpmcd/core/thread_tuner.hpp"

using mpmcd::ThreadTuner;

namespace {

// Runs n repetitions with the given costs [s per unit]; returns how many ran on the threads.
int run(ThreadTuner& tuner, int n, double threaded_cost, double serial_cost) {
  int on_threads = 0;
  for (int i = 0; i < n; ++i) {
    const bool t = tuner.threaded();
    on_threads += t ? 1 : 0;
    tuner.record(t, t ? threaded_cost : serial_cost);
  }
  return on_threads;
}

}  // namespace

TEST(ThreadTuner, MeasuresBothThenKeepsTheCheaperAndTriesTheOtherRarely) {
  ThreadTuner tuner;
  EXPECT_TRUE(tuner.threaded());  // first the threads
  tuner.record(true, 1.0);
  EXPECT_FALSE(tuner.threaded());  // then one thread
  tuner.record(false, 2.0);
  // Threads cheaper: one-thread trials only every 8, 16, ..., 256 repetitions.
  const int n = 2000;
  const int serial = n - run(tuner, n, 1.0, 2.0);
  EXPECT_GE(serial, 1);
  EXPECT_LE(serial, 15);  // gaps 8+16+32+64+128+256+256+... : about 10 trials in 2,000
  EXPECT_DOUBLE_EQ(tuner.costs()[0], 1.0);
  EXPECT_DOUBLE_EQ(tuner.costs()[1], 2.0);
}

TEST(ThreadTuner, SwitchesWhenTheLoadChanges) {
  ThreadTuner tuner;
  run(tuner, 100, 1.0, 2.0);  // idle machine: threads win
  // Another process takes a core: the threads become 20x slower than one thread. The next trial
  // of one thread (within the longest gap) wins, and from then on one thread is used, the threads
  // tried after 8, 16, 32, ... repetitions.
  run(tuner, ThreadTuner::kMaxGap + 2, 40.0, 2.0);
  EXPECT_GT(tuner.costs()[0], tuner.costs()[1]);
  EXPECT_LE(run(tuner, 200, 40.0, 2.0), 5);
  // The load goes away: the threads win their next trial and are used again.
  run(tuner, ThreadTuner::kMaxGap + 2, 1.0, 2.0);
  EXPECT_GE(run(tuner, 200, 1.0, 2.0), 190);
}
