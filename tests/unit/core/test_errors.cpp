#include <gtest/gtest.h>

#include "mpmcd/core/errors.hpp"

using mpmcd::InputError;
using mpmcd::NumericalError;

TEST(Errors, InputErrorNamesFileLineKeyAndExpectation) {
  InputError e("case.toml", 12, "grid.cell_size", "expected a number > 0, got -1");
  EXPECT_STREQ(e.what(), "case.toml:12: key 'grid.cell_size': expected a number > 0, got -1");
  EXPECT_EQ(e.line(), 12);
  EXPECT_EQ(e.key(), "grid.cell_size");
}

TEST(Errors, NumericalErrorNamesStepGrainAndPoint) {
  NumericalError e("J <= 0", 17, 1.5e-6, 3, 42);
  EXPECT_STREQ(e.what(), "J <= 0 (step 17, t = 1.5e-06 s, grain 3, point 42)");
}
