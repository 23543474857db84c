// The recipe of docs/architecture.md, "Adding a material law", followed by a test: a law of its own
// parameters (quadratic_volume_law.hpp) registered from here is listed, created and validated by
// the registry like the built-in laws, answers its moduli from its parameters, and takes part in
// every test that loops over the registry (test_laws.cpp: tangent against finite differences).
#include <gtest/gtest.h>

#include <stdexcept>

#include "mpmcd/core/errors.hpp"
#include "mpmcd/materials/law.hpp"
#include "quadratic_volume_law.hpp"

using namespace mpmcd;

namespace {

// Registered before main, as a tool would at start-up: before anything reads the registry.
const bool kRegistered = (materials::register_law(test::quadratic_volume_law()), true);

const materials::LawParams kParams = {{"G", 1.5e6}, {"kappa", 3e6}};

}  // namespace

TEST(LawRecipe, RegisteredLawIsListedAfterTheBuiltInOnes) {
  ASSERT_TRUE(kRegistered);
  const auto& laws = materials::law_registry();
  ASSERT_GE(laws.size(), 4u);
  EXPECT_EQ(laws.front().name, "neo_hookean");
  EXPECT_EQ(laws.back().name, "test_quadratic_volume");
  EXPECT_EQ(laws.back().params.size(), 2u);
}

TEST(LawRecipe, RegistryCreatesTheLawAndItAnswersItsModuli) {
  const auto law2 = materials::make_law<2>("test_quadratic_volume", kParams);
  EXPECT_EQ(law2->name(), "test_quadratic_volume");
  EXPECT_EQ(law2->wave_modulus(), 3e6 + 2 * 1.5e6);  // M = kappa + 2 G
  EXPECT_EQ(law2->bulk_modulus(), 3e6 + 1.5e6);      // 2D plane strain: K = kappa + G
  EXPECT_EQ(law2->shear_modulus(), 1.5e6);
  const auto law3 = materials::make_law<3>("test_quadratic_volume", kParams);
  EXPECT_DOUBLE_EQ(law3->bulk_modulus(), 3e6 + 2 * 1.5e6 / 3);  // 3D: K = kappa + 2G/3

  // Small strain: sigma = kappa tr(eps) I + 2 G eps, the moduli it answers.
  Mat<2> F = Mat<2>::Identity();
  F(1, 1) = 1 - 1e-7;  // uniaxial strain: sigma_22 = -M 1e-7
  Mat<2> sigma;
  materials::LawBatch<2> b{{&F, 1}, {}, {}, {&sigma, 1}, {}, {}, {}};
  law2->evaluate(b);
  EXPECT_NEAR(sigma(1, 1), -law2->wave_modulus() * 1e-7, 1e-6 * law2->wave_modulus() * 1e-7);
}

TEST(LawRecipe, RegistryValidatesTheLawsOwnParameters) {
  EXPECT_THROW(materials::make_law<2>("test_quadratic_volume", {{"G", 1.0}}), InputError);
  EXPECT_THROW(materials::make_law<2>("test_quadratic_volume", {{"G", 1.0}, {"kappa", -1.0}}),
               InputError);
  EXPECT_THROW(materials::make_law<2>("test_quadratic_volume", {{"lambda", 1.0}, {"mu", 1.0}}),
               InputError);
  EXPECT_THROW(materials::register_law(test::quadratic_volume_law()), std::invalid_argument);
  materials::LawInfo no_factory;
  no_factory.name = "no_factory";
  EXPECT_THROW(materials::register_law(no_factory), std::invalid_argument);
}
