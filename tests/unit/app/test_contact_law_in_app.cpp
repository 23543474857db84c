// A contact law registered by a test (tests/unit/contact/bilateral_contact_law.hpp) is chosen by
// the input's `[contact] law` and reaches the run's contact settings; an input that gives it
// friction (which it does not read) or the active-set solver (which does not solve it) is
// refused, naming the key.
#include <gtest/gtest.h>

#include <string>

#include "../contact/bilateral_contact_law.hpp"
#include "mpmcd/app/model_builder.hpp"
#include "mpmcd/core/errors.hpp"
#include "mpmcd/io/load_config.hpp"

namespace app = mpmcd::app;

namespace {

// Registered before main: before the first input is read (the input schema lists the laws once).
const bool kRegistered =
    (mpmcd::contact::register_contact_law(mpmcd::test::bilateral_contact_law()), true);

// One disk above a floor wall, with the [contact] table `contact`.
mpmcd::io::Config config(const std::string& contact) {
  const std::string text =
      "[grid]\norigin = [0.0, 0.0]\nextent = [0.02, 0.02]\ncell_size = 0.001\n"
      "[[materials]]\nname = \"gel\"\nlaw = \"neo_hookean\"\ndensity = 990.0\n"
      "lambda = 3e6\nmu = 1.5e6\n"
      "[[grains]]\nshape = \"disk\"\nmaterial = \"gel\"\ncenter = [0.01, 0.006]\n"
      "radius = 0.0035\n"
      "[[walls]]\nname = \"floor\"\npoint = [0.0, 0.0012]\nnormal = [0.0, 1.0]\n" +
      contact + "[time]\ndt = 2e-5\nend_time = 1e-3\n";
  return mpmcd::io::parse_config(text, "contact_law_in_app.toml");
}

// The key of the InputError that building the settings of `contact` throws ("" if none).
std::string refused_key(const std::string& contact) {
  const auto cfg = config(contact);
  try {
    app::build_settings(cfg, app::build_model(cfg));
  } catch (const mpmcd::InputError& e) {
    return e.key();
  }
  return "";
}

}  // namespace

TEST(ContactLawInApp, TheInputChoosesTheLawOfTheRun) {
  ASSERT_TRUE(kRegistered);
  const auto coulomb = config("");
  EXPECT_EQ(coulomb.contact.law, "coulomb");  // the default
  EXPECT_EQ(app::build_settings(coulomb, app::build_model(coulomb)).contact.law, "coulomb");
  const auto bilateral = config("[contact]\nlaw = \"test_bilateral\"\n");
  EXPECT_EQ(app::build_settings(bilateral, app::build_model(bilateral)).contact.law,
            "test_bilateral");
}

TEST(ContactLawInApp, FrictionOrTheActiveSetSolverForALawWithoutThemAreRefused) {
  EXPECT_EQ(refused_key("[contact]\nlaw = \"test_bilateral\"\n"), "");
  EXPECT_EQ(refused_key("[contact]\nlaw = \"test_bilateral\"\nfriction = 0.3\n"), "contact.law");
  EXPECT_EQ(refused_key("[contact]\nlaw = \"test_bilateral\"\nsolver = \"active_set\"\n"),
            "contact.solver");
  EXPECT_EQ(refused_key("[contact]\nsolver = \"active_set\"\nfriction = 0.3\n"), "contact.solver");
  EXPECT_EQ(refused_key("[contact]\nfriction = 0.3\n"), "");
}
