// app/ never names a law's parameters: a run of grains made of a test-only law with parameters of
// its own (tests/unit/materials/quadratic_volume_law.hpp, registered from here) is built, gets its
// solver settings and its compaction observables (M_p as the law answers it). Contact is decided
// once (app::contact_enabled) for the solver settings and the observables' Z columns.
#include <gtest/gtest.h>

#include <string>

#include "../materials/quadratic_volume_law.hpp"
#include "mpmcd/app/compaction_observer.hpp"
#include "mpmcd/app/model_builder.hpp"
#include "mpmcd/io/load_config.hpp"

namespace app = mpmcd::app;

namespace {

// Registered before main: before the first input is read (the input schema lists the laws once).
const bool kRegistered =
    (mpmcd::materials::register_law(mpmcd::test::quadratic_volume_law()), true);

// `disks` disks (1 or 2), the first of "soft", the second of `material_b` ("soft": G = 1.5 MPa,
// kappa = 3 MPa; "same": the same values; "stiff": kappa = 6 MPa), the walls `walls` and the
// [contact] table `contact`.
mpmcd::io::Config config(const std::string& material_b, const std::string& walls,
                         const std::string& contact = "", int disks = 2) {
  std::string text =
      "[grid]\norigin = [0.0, 0.0]\nextent = [0.02, 0.02]\ncell_size = 0.001\n"
      "[[materials]]\nname = \"soft\"\nlaw = \"test_quadratic_volume\"\ndensity = 990.0\n"
      "G = 1.5e6\nkappa = 3e6\n"
      "[[materials]]\nname = \"same\"\nlaw = \"test_quadratic_volume\"\ndensity = 990.0\n"
      "G = 1.5e6\nkappa = 3e6\n"
      "[[materials]]\nname = \"stiff\"\nlaw = \"test_quadratic_volume\"\ndensity = 990.0\n"
      "G = 1.5e6\nkappa = 6e6\n"
      "[[grains]]\nshape = \"disk\"\nmaterial = \"soft\"\ncenter = [0.006, 0.006]\n"
      "radius = 0.0035\n";
  if (disks > 1)
    text += "[[grains]]\nshape = \"disk\"\nmaterial = \"" + material_b +
            "\"\ncenter = [0.014, 0.006]\nradius = 0.0035\n";
  return mpmcd::io::parse_config(text + walls + contact + "[time]\ndt = 2e-5\nend_time = 1e-3\n",
                                 "law_in_app.toml");
}

// Four walls forming a box, the top one moving down.
const std::string kBox =
    "[[walls]]\nname = \"bottom\"\npoint = [0.0, 0.0012]\nnormal = [0.0, 1.0]\n"
    "[[walls]]\nname = \"top\"\npoint = [0.0, 0.0188]\nnormal = [0.0, -1.0]\n"
    "velocity = [0.0, -0.5]\n"
    "[[walls]]\nname = \"left\"\npoint = [0.0012, 0.0]\nnormal = [1.0, 0.0]\n"
    "[[walls]]\nname = \"right\"\npoint = [0.0188, 0.0]\nnormal = [-1.0, 0.0]\n";

bool has(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

}  // namespace

TEST(LawInApp, ALawOfOtherParametersRunsThroughTheApp) {
  ASSERT_TRUE(kRegistered);
  const auto cfg = config("same", kBox);
  const auto model = app::build_model(cfg);
  ASSERT_EQ(model.grains.size(), 2u);
  const auto settings = app::build_settings(cfg, model);  // wave speeds from the laws
  EXPECT_TRUE(settings.contact.enabled);
  const app::CompactionObserver observer(cfg, model);
  ASSERT_TRUE(observer.has_box());
  ASSERT_TRUE(observer.p_wave_modulus().has_value());  // two names, the same moduli
  EXPECT_EQ(*observer.p_wave_modulus(), 3e6 + 2 * 1.5e6);
  EXPECT_TRUE(has(observer.csv_header(), ",sigma_bottom_over_Mp"));
}

TEST(LawInApp, GrainsOfDifferentModuliHaveNoMp) {
  const auto cfg = config("stiff", kBox);
  const app::CompactionObserver observer(cfg, app::build_model(cfg));
  EXPECT_FALSE(observer.p_wave_modulus().has_value());
  EXPECT_FALSE(has(observer.csv_header(), "sigma_bottom_over_Mp"));
}

TEST(LawInApp, ContactIsDecidedOnceForSolverAndObservables) {
  const std::string wall =
      "[[walls]]\nname = \"floor\"\npoint = [0.0, 0.0012]\nnormal = [0.0, 1.0]\n";
  const std::string off = "[contact]\nenabled = false\n";
  struct Case {
    mpmcd::io::Config cfg;
    bool contact;
  };
  const Case cases[] = {{config("soft", "", "", 1), false},   // one grain, nothing to touch
                        {config("soft", wall, "", 1), true},  // one grain and a wall
                        {config("soft", ""), true},           // two grains
                        {config("soft", kBox, off), false}};  // not asked
  for (const auto& c : cases) {
    const auto model = app::build_model(c.cfg);
    EXPECT_EQ(app::contact_enabled(c.cfg, model.grains.size()), c.contact);
    EXPECT_EQ(app::build_settings(c.cfg, model).contact.enabled, c.contact);
    EXPECT_EQ(has(app::CompactionObserver(c.cfg, model).csv_header(), ",Z,"), c.contact);
  }
}
