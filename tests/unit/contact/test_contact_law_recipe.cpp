// The recipe of docs/architecture.md, "Adding a contact law", followed by a test: a law of its own
// (bilateral_contact_law.hpp: no separation, no friction) registered from here is listed and found
// by the registry like the built-in "coulomb", and the Gauss-Seidel sweeps, their error measure,
// the active-set solver and the problem file use it when a problem names it. The expected impulses
// are computed by hand.
#include <gtest/gtest.h>

#include <filesystem>
#include <stdexcept>

#include "bilateral_contact_law.hpp"
#include "mpmcd/contact/active_set.hpp"
#include "mpmcd/contact/law.hpp"
#include "mpmcd/contact/problem.hpp"
#include "mpmcd/core/errors.hpp"

using namespace mpmcd;

namespace {

// Registered before main, as a tool would at start-up: before anything reads the registry.
const bool kRegistered = (contact::register_contact_law(test::bilateral_contact_law()), true);

// Two slots of mass 1 at nodes 0 and 1 with free velocities v0 and v1, no contact yet, law `law`.
contact::Problem<2> two_slots(const std::string& law, const Vec<2>& v0, const Vec<2>& v1) {
  contact::Problem<2> p;
  p.dt = 1e-3;
  p.law = law;
  p.slots.push_back({1.0, v0, 0, 0});
  p.slots.push_back({1.0, v1, 1, 1});
  return p;
}

// A contact without gap of slot a (-1: the wall 0) and slot b, normal n from a to b.
contact::Contact<2> touching(std::int32_t a, std::int32_t b, const Vec<2>& n, double mu = 0) {
  contact::Contact<2> c;
  c.a = a;
  c.b = b;
  c.wall = a < 0 ? 0 : -1;
  c.normal = n;
  c.friction = mu;
  return c;
}

// A wall (normal +y) under slot 0 (v_free (0.3, -1)) under slot 1 (v_free (0, 2)): slot 0
// approaches the wall, slot 1 leaves slot 0.
contact::Problem<2> column(const std::string& law, double mu) {
  auto p = two_slots(law, Vec<2>(0.3, -1.0), Vec<2>(0.0, 2.0));
  p.contacts = {touching(-1, 0, Vec<2>(0, 1), mu), touching(0, 1, Vec<2>(0, 1), mu)};
  return p;
}

// Slot 0 (v_free (0, 1)) between a wall below (normal +y) and slot 1 above (v_free (0, 3),
// normal -y from slot 1 to slot 0): both contacts have slot 0 as B, i.e. one node with two
// contacts (a nodal block for a Signorini law). Both open.
contact::Problem<2> pinched(const std::string& law) {
  auto p = two_slots(law, Vec<2>(0.0, 1.0), Vec<2>(0.0, 3.0));
  p.contacts = {touching(-1, 0, Vec<2>(0, 1)), touching(1, 0, Vec<2>(0, -1))};
  return p;
}

void expect_near(const Vec<2>& got, const Vec<2>& want) {
  EXPECT_NEAR(got[0], want[0], 1e-10) << got.transpose() << " vs " << want.transpose();
  EXPECT_NEAR(got[1], want[1], 1e-10) << got.transpose() << " vs " << want.transpose();
}

}  // namespace

TEST(ContactLawRecipe, RegisteredLawIsListedAfterCoulombAndFoundByName) {
  ASSERT_TRUE(kRegistered);
  const auto& laws = contact::contact_law_registry();
  ASSERT_GE(laws.size(), 2u);
  EXPECT_EQ(laws.front().name, "coulomb");
  EXPECT_TRUE(laws.front().reads("friction"));
  EXPECT_TRUE(laws.front().signorini);
  EXPECT_TRUE(laws.front().active_set);
  EXPECT_EQ(laws.back().name, "test_bilateral");
  EXPECT_FALSE(laws.back().reads("friction"));
  EXPECT_EQ(contact::contact_law_names().back(), "test_bilateral");
  EXPECT_EQ(contact::find_contact_law("test_bilateral").local<2>(), &test::bilateral_solution<2>);
  EXPECT_EQ(contact::find_contact_law("coulomb").local<3>(),
            static_cast<contact::LocalSolver<3>>(&contact::local_solution<3>));

  try {
    contact::find_contact_law("adhesive");
    FAIL() << "an unknown law was found";
  } catch (const InputError& e) {
    EXPECT_EQ(e.key(), "contact.law");
    EXPECT_NE(std::string(e.what()).find("coulomb, test_bilateral"), std::string::npos) << e.what();
  }
  EXPECT_THROW(contact::register_contact_law(test::bilateral_contact_law()), std::invalid_argument);
  contact::ContactLaw no_solver;
  no_solver.name = "no_solver";
  EXPECT_THROW(contact::register_contact_law(no_solver), std::invalid_argument);
}

TEST(ContactLawRecipe, SweepsSolveTheProblemsLaw) {
  // Coulomb (mu = 0.5): the wall stops slot 0 and sticks it (|p_t| = 0.3 <= 0.5 p_n = 0.5), slot 1
  // leaves freely: P_wall = (-0.3, 1), P_01 = 0.
  auto coulomb = column("coulomb", 0.5);
  auto r = contact::solve_gauss_seidel(coulomb, {1e-12, 1000});
  ASSERT_TRUE(r.converged);
  expect_near(coulomb.contacts[0].impulse, Vec<2>(-0.3, 1.0));
  expect_near(coulomb.contacts[1].impulse, Vec<2>(0.0, 0.0));

  // Bilateral: both normal velocities vanish (v_y = 0 for both slots), no tangential impulse.
  // Slot 1: P_01 = m1 (0 - 2) = -2 (pulls slot 1 back); slot 0: P_wall - P_01 = m0 (0 + 1), so
  // P_wall = -1 (the wall pulls too). Slot 0 keeps v_x = 0.3.
  auto bilateral = column("test_bilateral", 0.0);
  r = contact::solve_gauss_seidel(bilateral, {1e-12, 1000});
  ASSERT_TRUE(r.converged) << r.sweeps << " " << r.error;
  expect_near(bilateral.contacts[0].impulse, Vec<2>(0.0, -1.0));
  expect_near(bilateral.contacts[1].impulse, Vec<2>(0.0, -2.0));
  EXPECT_EQ(contact::error(bilateral), r.error);  // the error measure asks the same law

  // The error measure is the law's: Coulomb's answer is far from the bilateral law's.
  auto other = column("test_bilateral", 0.0);
  other.contacts[0].impulse = Vec<2>(0.0, 1.0);
  EXPECT_GT(contact::error(other), 0.5);
  other.law = "coulomb";
  EXPECT_EQ(contact::error(other), 0.0);
}

TEST(ContactLawRecipe, NodeBlocksAndRelaxationKeepToSignoriniLaws) {
  // Coulomb: both contacts open (slot 0 leaves the wall, slot 1 leaves slot 0): no impulse, with
  // or without the nodal block.
  auto coulomb = pinched("coulomb");
  contact::GsSettings gs{1e-12, 1000};
  gs.relaxation = 1.5;
  auto r = contact::solve_gauss_seidel(coulomb, gs);
  ASSERT_TRUE(r.converged);
  expect_near(coulomb.contacts[0].impulse, Vec<2>::Zero());
  expect_near(coulomb.contacts[1].impulse, Vec<2>::Zero());

  // Bilateral: both slots stop. Slot 1 (A of contact 1, gets -P_1): -P_1 = m1 (0 - 3), P_1 =
  // (0, 3) (p_n = -3 along n = -y); slot 0: P_wall + P_1 = m0 (0 - 1), P_wall = (0, -4). The
  // Signorini nodal block and over-relaxation, which keep p_n >= 0, must not be used.
  auto bilateral = pinched("test_bilateral");
  r = contact::solve_gauss_seidel(bilateral, gs);
  ASSERT_TRUE(r.converged) << r.sweeps << " " << r.error;
  expect_near(bilateral.contacts[0].impulse, Vec<2>(0.0, -4.0));
  expect_near(bilateral.contacts[1].impulse, Vec<2>(0.0, 3.0));
}

TEST(ContactLawRecipe, ActiveSetLeavesALawItDoesNotSolveToTheSweeps) {
  auto p = column("test_bilateral", 0.0);
  const auto r = contact::solve_active_set(p, {1e-12, 1000});
  ASSERT_TRUE(r.converged);
  EXPECT_EQ(r.pivots, 0);
  expect_near(p.contacts[0].impulse, Vec<2>(0.0, -1.0));
  expect_near(p.contacts[1].impulse, Vec<2>(0.0, -2.0));
}

TEST(ContactLawRecipe, ProblemFileKeepsTheLaw) {
  const auto dir = std::filesystem::temp_directory_path();
  const std::string path = (dir / "mpmcd_contact_law_recipe.txt").string();
  auto p = column("test_bilateral", 0.0);
  contact::write_problem(p, path);
  EXPECT_EQ(contact::read_problem<2>(path).law, "test_bilateral");
  p.law = "coulomb";  // the default: no law line, as files written before the registry
  contact::write_problem(p, path);
  EXPECT_EQ(contact::read_problem<2>(path).law, "coulomb");
  std::filesystem::remove(path);
}

TEST(ContactLawRecipe, ThreeDimensionalSweepsUseTheLawToo) {
  // One slot (mass 2) leaving a wall (normal +z) at 1 m/s with a tangential velocity: the
  // bilateral law pulls it back, p = -2 (0, 0, 1), and leaves the tangential velocity.
  contact::Problem<3> p;
  p.dt = 1e-3;
  p.law = "test_bilateral";
  p.slots.push_back({2.0, Vec<3>(0.5, -0.2, 1.0), 0, 0});
  contact::Contact<3> c;
  c.b = 0;
  c.wall = 0;
  c.normal = Vec<3>(0, 0, 1);
  p.contacts.push_back(c);
  const auto r = contact::solve_gauss_seidel(p, {1e-12, 100});
  ASSERT_TRUE(r.converged);
  EXPECT_NEAR((p.contacts[0].impulse - Vec<3>(0, 0, -2)).norm(), 0.0, 1e-12);
}
