// The active-set (block principal pivoting) solver of frictionless contact problems against
// Gauss-Seidel, on redundant contacts and on problems with grain compliance groups.
#include <gtest/gtest.h>

#include <random>

#include "../../support/contact_problems.hpp"
#include "mpmcd/contact/active_set.hpp"
#include "mpmcd/contact/problem.hpp"

using namespace mpmcd;

namespace {

// Two grains, each one compliance group of `n` slots with a random SPD compliance G = B B^T /
// n + c I, pressed together: contact k joins slot k of grain 0 (A) to slot k of grain 1 (B),
// with normals near (0, 1), and every `redundant`-th contact is doubled (same slots, the normal
// turned by `tilt` [rad]: W singular when 0, nearly so when small). Grain 0 also rests on a wall
// at each slot.
contact::Problem<2> two_grain_problem(int n, int redundant, unsigned seed, double tilt = 0) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  contact::Problem<2> p;
  p.dt = 1e-6;
  for (int g = 0; g < 2; ++g) {
    contact::Group<2> group;
    Eigen::MatrixXd B(2 * n, 2 * n);
    for (Eigen::Index i = 0; i < B.size(); ++i) B.data()[i] = u(rng) - 0.5;
    const Eigen::MatrixXd G =
        B * B.transpose() / n + 0.05 * Eigen::MatrixXd::Identity(2 * n, 2 * n);
    for (int k = 0; k < n; ++k) {
      contact::Slot<2> s;
      s.mass = 1.0;
      s.v_free = Vec<2>(0.1 * (u(rng) - 0.5), g == 0 ? 0.3 - 0.8 * u(rng) : 0.5 - 1.5 * u(rng));
      s.grain = g;
      s.node = 100 * g + k;
      s.group = g;
      s.local = k;
      group.slots.push_back(static_cast<std::int32_t>(p.slots.size()));
      p.slots.push_back(s);
    }
    group.set_full(G);
    p.groups.push_back(group);
  }
  for (int k = 0; k < n; ++k) {
    contact::Contact<2> c;
    c.a = k;
    c.b = n + k;
    const double th = 0.2 * (u(rng) - 0.5);
    c.normal = Vec<2>(std::sin(th), std::cos(th)) * -1.0;  // from A (below) to B (above)
    c.normal = -c.normal;
    c.gap = 0.2 * p.dt * u(rng);
    p.contacts.push_back(c);
    if (redundant > 0 && k % redundant == 0) {
      contact::Contact<2> twin = c;
      if (tilt != 0) twin.normal = Vec<2>(std::sin(th + tilt), std::cos(th + tilt));
      p.contacts.push_back(twin);
    }
    contact::Contact<2> w;
    w.a = -1;
    w.b = k;
    w.wall = 0;
    w.normal = Vec<2>(0.0, 1.0);
    p.contacts.push_back(w);
  }
  return p;
}

// The largest violation of p >= 0, w >= 0 and p w = 0, as an impulse (w_c / W_cc), relative to
// the largest impulse.
double complementarity_violation(const contact::Problem<2>& p) {
  const contact::NormalSystem sys = contact::normal_system(p);
  const Eigen::VectorXd w = sys.b + sys.W * sys.p;
  double worst = 0;
  const double scale = sys.p.cwiseAbs().maxCoeff();
  for (Eigen::Index c = 0; c < sys.p.size(); ++c) {
    const double wc = w[c] / sys.W.coeff(c, c);
    worst = std::max({worst, -sys.p[c], -wc, std::min(std::abs(sys.p[c]), std::abs(wc))});
  }
  return worst / scale;
}

// Solver settings of these tests: tolerance 1e-12, sweeps unbounded in practice.
contact::GsSettings tight() {
  contact::GsSettings s;
  s.tolerance = 1e-12;
  s.max_sweeps = 100000;
  return s;
}

// The problem solved by both solvers to 1e-12.
struct BothSolved {
  contact::Problem<2> direct, sweeps;  // solved by solve_active_set, by solve_gauss_seidel
  contact::GsResult rd, rg;            // their outcomes
};
BothSolved solve_both(const contact::Problem<2>& p) {
  BothSolved b{p, p, {}, {}};
  const contact::GsSettings s = tight();
  b.rd = contact::solve_active_set(b.direct, s);
  b.rg = contact::solve_gauss_seidel(b.sweeps, s);
  return b;
}

// The slots' net impulses of two solutions of one problem agree within `rel` of the largest.
void expect_same_net_impulses(const contact::Problem<2>& x, const contact::Problem<2>& y,
                              double rel) {
  const auto a = contact::net_impulses(x), b = contact::net_impulses(y);
  double scale = 0;
  for (const auto& v : b) scale = std::max(scale, v.norm());
  for (std::size_t k = 0; k < a.size(); ++k)
    EXPECT_NEAR((a[k] - b[k]).norm(), 0.0, rel * scale) << "slot " << k;
}

}  // namespace

TEST(ActiveSet, NormalSystemGivesTheGaussSeidelVelocities) {
  // b + W p is the relative normal velocity (+ g/dt) that the sweeps see, for any impulses.
  auto p = two_grain_problem(6, 0, 3);
  std::mt19937 rng(5);
  for (auto& c : p.contacts) c.impulse = c.normal * std::uniform_real_distribution<>(0, 1)(rng);
  const auto sys = contact::normal_system(p);
  const Eigen::VectorXd w = sys.b + sys.W * sys.p;
  const auto net = contact::net_impulses(p);
  for (std::size_t c = 0; c < p.contacts.size(); ++c) {
    const auto& k = p.contacts[c];
    // Slot velocities v_s = v_free + sum over the group's slots G_st P_t.
    auto velocity = [&](std::int32_t s) {
      Vec<2> v = p.slots[s].v_free;
      const auto& g = p.groups[p.slots[s].group];
      for (const std::int32_t t : g.slots)
        v += g.block(static_cast<std::size_t>(p.slots[s].local),
                     static_cast<std::size_t>(p.slots[t].local)) *
             net[t];
      return v;
    };
    const Vec<2> va = k.a >= 0 ? velocity(k.a) : k.wall_velocity;
    const double expect = k.normal.dot(velocity(k.b) - va) + k.gap / p.dt;
    EXPECT_NEAR(w[static_cast<Eigen::Index>(c)], expect, 1e-12 * (1 + std::abs(expect)));
  }
  EXPECT_NEAR((sys.W - Eigen::SparseMatrix<double>(sys.W.transpose())).norm(), 0.0,
              1e-14 * sys.W.norm());
}

TEST(ActiveSet, SolvesWhatGaussSeidelSolvesInFewPivots) {
  for (unsigned seed : {1u, 2u, 3u}) {
    const auto [direct, sweeps, rd, rg] = solve_both(two_grain_problem(20, 0, seed));
    ASSERT_TRUE(rd.converged);
    ASSERT_TRUE(rg.converged);
    // Gauss-Seidel alone needs 58 to 120 sweeps here: the solver's first sweep does not
    // suffice, the pivoting does, and no sweep follows it.
    EXPECT_GT(rg.sweeps, 10);
    EXPECT_EQ(rd.sweeps, 1);
    EXPECT_GE(rd.pivots, 1);
    EXPECT_LE(rd.pivots, 10);
    EXPECT_LT(complementarity_violation(direct), 1e-10);
    // A positive-definite W: one solution, the same impulses.
    for (std::size_t c = 0; c < direct.contacts.size(); ++c)
      EXPECT_NEAR((direct.contacts[c].impulse - sweeps.contacts[c].impulse).norm(), 0.0,
                  1e-8 * direct.contacts[c].impulse.norm() + 1e-14)
          << "seed " << seed << " contact " << c;
  }
}

TEST(ActiveSet, RedundantContactsNeedNoSweepAfterThePivoting) {
  // Doubled contacts: W singular, the impulses not unique; the velocities are. Block pivoting
  // with the shifted factorisation meets the tolerance without a sweep after its first one.
  const auto [direct, sweeps, rd, rg] = solve_both(two_grain_problem(20, 3, 7));
  ASSERT_TRUE(rd.converged);
  EXPECT_EQ(rd.sweeps, 1);
  EXPECT_GE(rd.pivots, 1);
  EXPECT_LT(complementarity_violation(direct), 1e-10);
  // Same slot velocities as Gauss-Seidel where it converged.
  if (rg.converged) {
    const auto a = contact::net_impulses(direct), b = contact::net_impulses(sweeps);
    for (std::size_t s2 = 0; s2 < a.size(); ++s2)
      EXPECT_NEAR((a[s2] - b[s2]).norm(), 0.0, 1e-7 * (a[s2].norm() + b[s2].norm()) + 1e-14);
  }
}

TEST(ActiveSet, FrictionGoesToGaussSeidel) {
  // many_node_problem has friction: no pivoting, the Gauss-Seidel answer bit for bit.
  auto direct = test_support::many_node_problem(50);
  auto sweeps = direct;
  contact::GsSettings s;
  const auto rd = contact::solve_active_set(direct, s);
  const auto rg = contact::solve_gauss_seidel(sweeps, s);
  EXPECT_EQ(rd.pivots, 0);
  EXPECT_EQ(rd.sweeps, rg.sweeps);
  for (std::size_t c = 0; c < direct.contacts.size(); ++c)
    EXPECT_EQ(direct.contacts[c].impulse, sweeps.contacts[c].impulse);
}

TEST(ActiveSet, CachedMatrixAndFactorisationGiveTheSameImpulses) {
  // The Newton iterations of a step solve the same contacts and compliances with new free
  // velocities: a valid cache keeps W and the last factorisation of W_AA + delta I, and must
  // give what a solve from scratch gives. With the cache the solve pivots from the warm start
  // without a sweep first, so redundant contacts may share their load otherwise: the grains'
  // (slots') net impulses, which the problem fixes, must agree to round-off.
  const auto base = two_grain_problem(20, 3, 11);
  const contact::GsSettings s = tight();
  contact::ActiveSetCache cache;
  auto first = base;
  const auto r1 = contact::solve_active_set(first, s, &cache);
  ASSERT_TRUE(r1.converged);
  ASSERT_TRUE(cache.valid);
  ASSERT_GE(r1.pivots, 1);
  const Eigen::SparseMatrix<double> W = cache.W;
  // The next iterate: free velocities moved by 1e-3 of their size, warm start from the answer.
  auto next = first;
  std::mt19937 rng(13);
  std::uniform_real_distribution<double> u(-1e-3, 1e-3);
  for (auto& slot : next.slots) slot.v_free += Vec<2>(u(rng), u(rng)) * slot.v_free.norm();
  auto scratch = next;
  const auto rc = contact::solve_active_set(next, s, &cache);
  const auto rs = contact::solve_active_set(scratch, s);
  ASSERT_TRUE(rc.converged);
  ASSERT_TRUE(rs.converged);
  EXPECT_EQ(rc.sweeps, 0);  // no sweep before the pivoting, none after
  EXPECT_GE(rc.pivots, 1);
  EXPECT_LT(complementarity_violation(next), 1e-10);
  expect_same_net_impulses(next, scratch, 1e-10);
  // The cached W is the one the problem gives (the compliances did not change).
  EXPECT_EQ((cache.W - W).norm(), 0.0);
  EXPECT_EQ((cache.W - contact::normal_system(next).W).norm(), 0.0);
  // A changed compliance with the cache cleared, as the caller does: the new W is used.
  auto stiffer = next;
  for (auto& g : stiffer.groups) g.Gr *= 0.5;
  cache.valid = false;
  auto stiffer_scratch = stiffer;
  contact::solve_active_set(stiffer, s, &cache);
  contact::solve_active_set(stiffer_scratch, s);
  for (std::size_t c = 0; c < stiffer.contacts.size(); ++c)
    EXPECT_EQ(stiffer.contacts[c].impulse, stiffer_scratch.contacts[c].impulse) << "contact " << c;
}

namespace {
// `base` solved once with `cache` (left valid by the solve), its impulses the answer.
contact::Problem<2> solved_with_cache(const contact::Problem<2>& base, const contact::GsSettings& s,
                                      contact::ActiveSetCache& cache) {
  auto solved = base;
  EXPECT_TRUE(contact::solve_active_set(solved, s, &cache).converged);
  return solved;
}

// Opens two contacts of a solved two_grain_problem and closes two: the first two loaded wall
// contacts' slots lifted off the wall, the gaps of two open grain-grain contacts closed; false
// if it found fewer.
bool open_two_close_two(contact::Problem<2>& p) {
  int lifted = 0, closed = 0;
  for (auto& c : p.contacts) {
    const double pn = c.impulse.dot(c.normal);
    if (c.a < 0 && pn > 0 && lifted < 2) {
      p.slots[c.b].v_free[1] += 5.0;
      ++lifted;
    } else if (c.a >= 0 && pn == 0 && closed < 2) {
      c.gap = -2.0 * p.dt;
      ++closed;
    }
  }
  return lifted == 2 && closed == 2;
}
}  // namespace

TEST(ActiveSet, ColumnsOfChangedGroupsMadeAgainGiveTheMatrixMadeAnew) {
  // A Newton iteration in which one grain factorises anew changes that group's G only: the
  // cache then makes again only the columns of the contacts on that group
  // (refresh_normal_system), which must give W bit for bit as made anew, and the solve the same
  // impulses as one without the cache. Changed normals make W anew.
  const contact::GsSettings s = tight();
  contact::ActiveSetCache cache;
  const auto first = solved_with_cache(two_grain_problem(20, 3, 17), s, cache);
  ASSERT_TRUE(cache.valid && cache.pattern);
  auto next = first;
  next.groups[1].Gr *= 0.7;
  next.groups[1].Gr(0, 0) += 0.01;  // not a multiple of the old one
  cache.compliance_changed({0, 1});
  EXPECT_FALSE(cache.valid);
  EXPECT_TRUE(cache.refreshable);
  auto scratch = next;
  ASSERT_TRUE(contact::solve_active_set(next, s, &cache).converged);
  ASSERT_TRUE(contact::solve_active_set(scratch, s).converged);
  const Eigen::SparseMatrix<double> fresh = contact::normal_system(next).W;
  ASSERT_EQ(cache.W.nonZeros(), fresh.nonZeros());
  for (Eigen::Index k = 0; k < fresh.nonZeros(); ++k) {
    EXPECT_EQ(cache.W.innerIndexPtr()[k], fresh.innerIndexPtr()[k]);
    EXPECT_EQ(cache.W.valuePtr()[k], fresh.valuePtr()[k]) << "entry " << k;
  }
  // Grain 1's columns did change: W is not the first one.
  EXPECT_GT((cache.W - contact::normal_system(first).W).norm(), 0.0);
  for (std::size_t c = 0; c < next.contacts.size(); ++c)
    EXPECT_EQ(next.contacts[c].impulse, scratch.contacts[c].impulse) << "contact " << c;
  // A turned normal and a changed group: W made anew, with the new normal.
  auto turned = next;
  turned.contacts[0].normal = Vec<2>(0.1, 1.0).normalized();
  turned.groups[0].Gr *= 0.9;
  cache.compliance_changed({1, 0});
  ASSERT_TRUE(contact::solve_active_set(turned, s, &cache).converged);
  EXPECT_EQ((cache.W - contact::normal_system(turned).W).norm(), 0.0);
  // Clearing `valid` alone (not through compliance_changed) also makes W anew.
  auto softer = turned;
  for (auto& g : softer.groups) g.Gr *= 2.0;
  cache.valid = false;
  EXPECT_FALSE(cache.refreshable);
  ASSERT_TRUE(contact::solve_active_set(softer, s, &cache).converged);
  EXPECT_EQ((cache.W - contact::normal_system(softer).W).norm(), 0.0);
}

TEST(ActiveSet, BorderedSolveMatchesAFreshFactorisation) {
  // Contacts entering and leaving the factorised set: the solve borders the kept factorisation
  // (a Schur complement of the changed contacts) instead of factorising anew, and must reach the
  // solution a solve without the cache reaches.
  const auto base = two_grain_problem(60, 4, 17);
  const contact::GsSettings s = tight();
  contact::ActiveSetCache cache;
  auto first = solved_with_cache(base, s, cache);
  auto next = first;
  ASSERT_TRUE(open_two_close_two(next));
  auto scratch = next;
  const auto rc = contact::solve_active_set(next, s, &cache);
  const auto rs = contact::solve_active_set(scratch, s);
  ASSERT_TRUE(rc.converged);
  ASSERT_TRUE(rs.converged);
  EXPECT_FALSE(cache.factor.owners.empty());  // bordered columns were made
  EXPECT_EQ(rc.sweeps, 0);  // pivoting from the warm start (no sweep first), no sweep after
  EXPECT_LT(complementarity_violation(next), 1e-10);
  expect_same_net_impulses(next, scratch, 1e-9);
}

TEST(ActiveSet, ThePrimalMethodAloneSolvesTheSameProblems) {
  // GsSettings::block_pivots = 0: the primal active-set method (the fallback when the block
  // pivoting cycles) solves from the warm start without any block pivot: the same impulses as
  // Gauss-Seidel where W is positive definite, the same slot impulses where contacts are doubled.
  contact::GsSettings s = tight();
  s.block_pivots = 0;
  for (int redundant : {0, 3}) {
    for (unsigned seed : {1u, 2u, 7u}) {
      const auto p = two_grain_problem(20, redundant, seed);
      auto primal = p, sweeps = p;
      const auto rp = contact::solve_active_set(primal, s);
      const auto rg = contact::solve_gauss_seidel(sweeps, tight());
      ASSERT_TRUE(rp.converged) << "seed " << seed << " redundant " << redundant;
      EXPECT_EQ(rp.sweeps, 1);  // the first sweep only: the primal method met the tolerance
      EXPECT_GE(rp.pivots, 1);
      EXPECT_LT(complementarity_violation(primal), 1e-10);
      if (rg.converged) expect_same_net_impulses(primal, sweeps, 1e-7);
    }
  }
}

TEST(ActiveSet, NearlyRedundantContactsNeedFewPivots) {
  // Every contact doubled with its normal turned by 1e-2 to 1e-6 rad: W_AA nearly singular. Block
  // flips then trade the twins' impulses back and forth with a few contacts infeasible; once
  // their number stops falling the primal method finishes. Seen: at most 14 pivots per problem
  // (Murty's one-at-a-time rule, used before: up to 123).
  for (const double tilt : {1e-2, 1e-4, 1e-6}) {
    for (unsigned seed = 1; seed <= 20; ++seed) {
      auto p = two_grain_problem(40, 1, seed, tilt);
      const auto r = contact::solve_active_set(p, tight());
      ASSERT_TRUE(r.converged) << "tilt " << tilt << " seed " << seed;
      EXPECT_LE(r.pivots, 20) << "tilt " << tilt << " seed " << seed;
      EXPECT_LT(complementarity_violation(p), 1e-10) << "tilt " << tilt << " seed " << seed;
    }
  }
}

TEST(ActiveSet, OneNearlyMasslessSlotDoesNotSlowTheOthers) {
  // The nearly redundant problems above plus one lumped slot of 1e-9 the others' mass on a
  // wall: its W_cc is 1e9 times theirs (in dense 3D packings a face contact on a nearly empty
  // node's slot had 1e7 times the median, docs/contact.md "The proximal shift"). A shift scaled
  // by the largest W_cc slowed the proximal steps of all the others by that factor, the pivoting
  // stopped with a violation above the tolerance and Gauss-Seidel swept after it; the shift now
  // follows the bulk of the diagonal, and the pivoting alone meets the tolerance.
  for (const double tilt : {1e-2, 1e-4}) {
    for (unsigned seed = 1; seed <= 10; ++seed) {
      auto p = two_grain_problem(40, 1, seed, tilt);
      contact::Slot<2> light;
      light.mass = 1e-9;
      light.v_free = Vec<2>(0.0, -0.2);
      light.grain = 2;
      light.node = 999;
      p.slots.push_back(light);
      contact::Contact<2> w;
      w.a = -1;
      w.b = static_cast<std::int32_t>(p.slots.size()) - 1;
      w.wall = 0;
      w.normal = Vec<2>(0.0, 1.0);
      p.contacts.push_back(w);
      const auto r = contact::solve_active_set(p, tight());
      ASSERT_TRUE(r.converged) << "tilt " << tilt << " seed " << seed;
      EXPECT_EQ(r.sweeps, 1) << "tilt " << tilt << " seed " << seed;
      EXPECT_LT(complementarity_violation(p), 1e-10) << "tilt " << tilt << " seed " << seed;
    }
  }
}

namespace {
// Sets MPMCD_SUPERNODAL (the factorisation's choice: "0" TreeLdlt, "1" supernodal) for a scope,
// unset after.
class ForcedFactorisation {
 public:
  explicit ForcedFactorisation(const char* value) { set(value); }
  void set(const char* value) const { setenv("MPMCD_SUPERNODAL", value, 1); }
  ~ForcedFactorisation() { unsetenv("MPMCD_SUPERNODAL"); }
  ForcedFactorisation(const ForcedFactorisation&) = delete;
  ForcedFactorisation& operator=(const ForcedFactorisation&) = delete;
};
}  // namespace

TEST(ActiveSet, SupernodalFactorisationGivesTheImpulsesOfTheSimplicialOne) {
  // Two grains of 300 slots each with a dense compliance: W is dense (675 contacts, 470 active)
  // and its factor's columns long, as in the dense 3D packings where the solver takes the
  // supernodal factorisation (CHOLMOD; docs/contact.md, "The supernodal factorisation"), forced
  // here (this problem is below the size the rule wants); then a bordered solve on that
  // factorisation (two contacts opened, two closed). Both must give the impulses of the
  // simplicial LDL^T (TreeLdlt, forced).
  const auto base = two_grain_problem(300, 4, 23);
  const contact::GsSettings s = tight();
  contact::ActiveSetCache cache;
  const ForcedFactorisation supernodal("1");
  const auto first = solved_with_cache(base, s, cache);
  EXPECT_TRUE(cache.factor.supernodal);
  EXPECT_LT(complementarity_violation(first), 1e-10);
  auto simplicial = base;
  contact::ActiveSetCache simplicial_cache;
  supernodal.set("0");
  ASSERT_TRUE(contact::solve_active_set(simplicial, s, &simplicial_cache).converged);
  EXPECT_FALSE(simplicial_cache.factor.supernodal);
  supernodal.set("1");
  expect_same_net_impulses(first, simplicial, 1e-9);

  auto next = first;
  ASSERT_TRUE(open_two_close_two(next));
  auto scratch = next;
  const auto rc = contact::solve_active_set(next, s, &cache);
  ASSERT_TRUE(rc.converged);
  EXPECT_TRUE(cache.factor.supernodal);
  EXPECT_FALSE(cache.factor.owners.empty());  // bordered columns were made
  supernodal.set("0");
  ASSERT_TRUE(contact::solve_active_set(scratch, s).converged);
  EXPECT_LT(complementarity_violation(next), 1e-10);
  expect_same_net_impulses(next, scratch, 1e-9);
}
