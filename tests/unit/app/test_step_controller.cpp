// The time-step controller of a run: a failed step cuts Δt by cut_factor, a cut below dt_min is
// refused (the run cannot go on), and recover_steps good steps double a cut Δt back toward the
// nominal one, never above it.
#include <gtest/gtest.h>

#include "mpmcd/app/step_controller.hpp"

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
