// ThreadedRegion: the time of OpenMP regions that run on several threads (one-thread share of the
// timer report, docs/parallel.md).
#include <gtest/gtest.h>
#include <omp.h>

#include <cmath>

#include "mpmcd/core/timer.hpp"

namespace {

// Some work for every thread of a region [-].
double spin(int iterations) {
  double s = 0;
  for (int i = 0; i < iterations; ++i) s += std::sqrt(static_cast<double>(i));
  return s;
}

double threaded_time(const mpmcd::StageTimers& t) {
  const auto it = t.totals().find(mpmcd::kThreadedStage);
  return it == t.totals().end() ? 0.0 : it->second;
}

}  // namespace

TEST(ThreadedRegion, CountsOnlyRegionsOnSeveralThreads) {
  const int saved = omp_get_max_threads();
  mpmcd::StageTimers t;
  volatile double sink = 0;
  omp_set_num_threads(2);
  {
    const mpmcd::ThreadedRegion r(&t, true);
#pragma omp parallel
    sink = sink + spin(200000);
  }
  const double two = threaded_time(t);
  EXPECT_GT(two, 0.0);
  {
    const mpmcd::ThreadedRegion r(&t, false);  // the region's if() is false: one thread
    sink = sink + spin(200000);
  }
  EXPECT_EQ(threaded_time(t), two);
  omp_set_num_threads(1);
  {
    const mpmcd::ThreadedRegion r(&t, true);  // one thread available
#pragma omp parallel
    sink = sink + spin(200000);
  }
  EXPECT_EQ(threaded_time(t), two);
  omp_set_num_threads(saved);
}

TEST(ThreadedRegion, DoneStopsTheClock) {
  mpmcd::StageTimers t;
  omp_set_num_threads(2);
  mpmcd::ThreadedRegion r(&t, true);
  r.done();
  const double after = threaded_time(t);
  volatile double sink = spin(2000000);
  (void)sink;
  EXPECT_EQ(threaded_time(t), after);  // nothing added after done(), nor by the destructor
}

TEST(ThreadedRegion, NoTimersNoStage) {
  const mpmcd::ThreadedRegion r(nullptr, true);
  SUCCEED();
}
