// The time-step controller of a run: a failed step cuts Δt by cut_factor, a cut below dt_min is
// refused (the run cannot go on), and recover_steps good steps double a cut Δt back toward the
// nominal one, never above it.
#include <gtest/gtest.h>

#include "mpmcd/app/step_controller.hpp"

#include <cmath>

using mpmcd::app::StepController;

TEST(StepController, StartsAtTheNominalStepAndLandsOnTheEnd) {
  const StepController c(1e-3, 0.5, 1e-5, 3);
  EXPECT_EQ(c.dt(), 1e-3);
  EXPECT_EQ(c.nominal(), 1e-3);
  EXPECT_EQ(c.next(1.0), 1e-3);
  EXPECT_EQ(c.next(4e-4), 4e-4);  // the last step ends on end_time
}

TEST(StepController, CutsOnFailure) {
  StepController c(1e-3, 0.25, 1e-5, 3);
  ASSERT_TRUE(c.cut(c.next(1.0)));
  EXPECT_EQ(c.dt(), 0.25e-3);
  EXPECT_EQ(c.good_since_cut(), 0);
  ASSERT_TRUE(c.cut(4e-4));  // from the step tried (shortened to reach the end), not from Δt
  EXPECT_EQ(c.dt(), 1e-4);
}

TEST(StepController, RestoresAfterRecoverStepsGoodSteps) {
  StepController c(1e-3, 0.25, 1e-5, 3);
  ASSERT_TRUE(c.cut(1e-3));
  ASSERT_TRUE(c.cut(c.dt()));  // 1/16 of the nominal step
  EXPECT_EQ(c.dt(), 1e-3 / 16);
  EXPECT_FALSE(c.succeeded());
  EXPECT_FALSE(c.succeeded());
  EXPECT_EQ(c.good_since_cut(), 2);
  EXPECT_TRUE(c.succeeded());  // the third: doubled
  EXPECT_EQ(c.dt(), 1e-3 / 8);
  EXPECT_EQ(c.good_since_cut(), 0);
  for (int k = 0; k < 3 * 3; ++k) c.succeeded();  // three more doublings: back to nominal
  EXPECT_EQ(c.dt(), 1e-3);
  for (int k = 0; k < 10; ++k) EXPECT_FALSE(c.succeeded());  // never above nominal
  EXPECT_EQ(c.dt(), 1e-3);
  EXPECT_EQ(c.good_since_cut(), 0);  // good steps at the nominal step are not counted
}

TEST(StepController, DoublingStopsAtTheNominalStep) {
  StepController c(1e-3, 0.6, 1e-5, 1);
  ASSERT_TRUE(c.cut(1e-3));
  EXPECT_TRUE(c.succeeded());
  EXPECT_EQ(c.dt(), 1e-3);  // min(nominal, 2 * 0.6e-3)
}

TEST(StepController, RefusesACutBelowDtMin) {
  StepController c(1e-3, 0.5, 2e-4, 3);
  ASSERT_TRUE(c.cut(1e-3));
  ASSERT_TRUE(c.cut(c.dt()));
  EXPECT_EQ(c.dt(), 2.5e-4);
  c.succeeded();
  EXPECT_FALSE(c.cut(c.dt()));  // 1.25e-4 < dt_min: refused, nothing changes
  EXPECT_EQ(c.dt(), 2.5e-4);
  EXPECT_EQ(c.good_since_cut(), 1);
}

TEST(StepController, RestoreContinuesACutStep) {
  StepController c(1e-3, 0.5, 1e-5, 2);
  c.restore(2.5e-4, 1);
  EXPECT_EQ(c.dt(), 2.5e-4);
  EXPECT_TRUE(c.succeeded());
  EXPECT_EQ(c.dt(), 5e-4);
}

TEST(StepController, ReadsTheTimeTable) {
  mpmcd::io::TimeSection t;
  t.dt = 2e-3;
  t.cut_factor = 0.5;
  t.dt_min = 1e-3;
  t.recover_steps = 1;
  StepController c(t);
  EXPECT_EQ(c.dt(), 2e-3);
  EXPECT_EQ(c.dt_min(), 1e-3);
  EXPECT_TRUE(c.cut(2e-3));
  EXPECT_FALSE(c.cut(1e-3));
  EXPECT_TRUE(c.succeeded());
  EXPECT_EQ(c.dt(), 2e-3);
}

// The Newton control (time.control = "newton"): Δt is scaled by sqrt(target / iterations) within
// [1/2, 5/4], dt_min and dt_max.
TEST(StepController, NewtonControlScalesTheStepByTheIterationCount) {
  StepController c(1e-3, 0.5, 1e-5, 3, 6, 4e-3);
  ASSERT_TRUE(c.adaptive());
  EXPECT_EQ(c.dt_max(), 4e-3);
  EXPECT_EQ(c.good_since_cut(), 3);    // no cut yet: free to grow from the first step
  EXPECT_FALSE(c.succeeded(6, 1e-3));  // on target
  EXPECT_EQ(c.dt(), 1e-3);
  EXPECT_TRUE(c.succeeded(24, 1e-3));  // sqrt(6/24) = 0.5
  EXPECT_DOUBLE_EQ(c.dt(), 0.5e-3);
  EXPECT_TRUE(c.succeeded(100, 0.5e-3));  // sqrt(0.06), bounded to 0.5
  EXPECT_DOUBLE_EQ(c.dt(), 0.25e-3);
  EXPECT_TRUE(c.succeeded(4, 0.25e-3));  // sqrt(1.5)
  EXPECT_DOUBLE_EQ(c.dt(), 0.25e-3 * std::sqrt(1.5));
  const double before = c.dt();
  EXPECT_TRUE(c.succeeded(1, before));  // sqrt(6), bounded to 5/4
  EXPECT_DOUBLE_EQ(c.dt(), 1.25 * before);
  for (int k = 0; k < 40; ++k) c.succeeded(1, c.dt());  // never above dt_max
  EXPECT_EQ(c.dt(), 4e-3);
  for (int k = 0; k < 40; ++k) c.succeeded(25, c.dt());  // never below dt_min
  EXPECT_EQ(c.dt(), 1e-5);
}

TEST(StepController, NewtonControlIgnoresAStepShortenedToLandOnAnEnd) {
  StepController c(1e-3, 0.5, 1e-5, 3, 6, 4e-3);
  EXPECT_FALSE(c.succeeded(1, c.next(2e-4)));  // the last bit before end_time
  EXPECT_FALSE(c.succeeded(20, 2e-4));
  EXPECT_EQ(c.dt(), 1e-3);
}

TEST(StepController, NewtonControlGrowsOnlyRecoverStepsAfterACut) {
  StepController c(1e-3, 0.5, 1e-5, 3, 6, 4e-3);
  ASSERT_TRUE(c.cut(1e-3));
  EXPECT_EQ(c.good_since_cut(), 0);
  EXPECT_FALSE(c.succeeded(1, 0.5e-3));  // few iterations, but just after a cut
  EXPECT_TRUE(c.succeeded(24, 0.5e-3));  // shrinking is never held back
  EXPECT_DOUBLE_EQ(c.dt(), 0.25e-3);
  EXPECT_TRUE(c.succeeded(1, 0.25e-3));  // the third good step since the cut: grows again
  EXPECT_DOUBLE_EQ(c.dt(), 1.25 * 0.25e-3);
  EXPECT_EQ(c.good_since_cut(), 3);  // counted up to recover_steps only
}

TEST(StepController, ReadsTheNewtonControlFromTheTimeTable) {
  mpmcd::io::TimeSection t;
  t.dt = 1e-3;
  t.dt_min = 1e-5;
  t.recover_steps = 2;
  t.dt_max = 2e-3;
  EXPECT_FALSE(StepController(t).adaptive());  // control = "fixed": dt_max is not used
  EXPECT_EQ(StepController(t).dt_max(), 1e-3);
  t.control = "newton";
  t.target_iterations = 4;
  StepController c(t);
  ASSERT_TRUE(c.adaptive());
  EXPECT_TRUE(c.succeeded(1, 1e-3));
  EXPECT_DOUBLE_EQ(c.dt(), 1.25e-3);
  EXPECT_TRUE(c.succeeded(16, c.dt()));  // sqrt(4/16)
  EXPECT_DOUBLE_EQ(c.dt(), 0.625e-3);
}
