// The local Signorini-Coulomb solution, the Gauss-Seidel solver and the problem file round trip.
#include <gtest/gtest.h>
#include <omp.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>

#include "../../support/contact_problems.hpp"
#include "mpmcd/contact/problem.hpp"
#include "mpmcd/core/errors.hpp"

using namespace mpmcd;
using contact::local_solution;

TEST(LocalSolver, OpenStickSlide) {
  const Vec<2> n(0, 1);
  const double w = 2.0;
  // separating: open
  EXPECT_EQ(local_solution<2>(Vec<2>(0.3, 1.0), w, n, 0.0, 0.5), Vec<2>::Zero());
  // approaching slower than the gap allows: open
  EXPECT_EQ(local_solution<2>(Vec<2>(0.0, -1.0), w, n, 1.5, 0.5), Vec<2>::Zero());
  // approaching, small tangential velocity: stick, u = u_free + w P = 0
  Vec<2> u(0.1, -1.0);
  Vec<2> P = local_solution<2>(u, w, n, 0.0, 0.5);
  EXPECT_LT((u + w * P).norm(), 1e-15);
  // gap: u_n + g/dt = 0 after the impulse
  P = local_solution<2>(Vec<2>(0.0, -1.0), w, n, 0.25, 0.5);
  EXPECT_NEAR((Vec<2>(0.0, -1.0) + w * P).dot(n) + 0.25, 0.0, 1e-15);
  // large tangential velocity: slide on the cone, p_t opposes u_t
  u = Vec<2>(3.0, -1.0);
  P = local_solution<2>(u, w, n, 0.0, 0.5);
  EXPECT_NEAR(P[1], 0.5, 1e-15);
  EXPECT_NEAR(P[0], -0.5 * 0.5, 1e-15);
  EXPECT_GT((u + w * P)[0], 0.0);  // still sliding the same way
  // frictionless: never a tangential impulse
  P = local_solution<2>(Vec<2>(3.0, -1.0), w, n, 0.0, 0.0);
  EXPECT_EQ(P[0], 0.0);
}

// 3D with an anisotropic Delassus block W (a grain's exact compliance is not w I): open,
// frictionless (u_n + g/dt = 0 after, the impulse along n), stick (u = 0 after, inside the cone)
// and slide (u_n = 0, on the cone, the tangential impulse opposite to the tangential velocity it
// leaves), each checked on u = u_free + W P. The tr(W)/3 approximation used before 2026-11-26
// left the frictionless case approaching at -0.31 (p_n 0.46 instead of 0.67).
TEST(LocalSolver, ThreeDimensionalIsExactForAnAnisotropicDelassusBlock) {
  Mat<3> W;
  W << 3.0, 1.0, 0.5, 1.0, 2.0, 0.3, 0.5, 0.3, 1.5;
  const Vec<3> n(0, 0, 1);
  const double mu = 0.3;
  EXPECT_EQ(local_solution<3>(Vec<3>(0.2, 0.1, 0.5), W, n, 0.0, mu), Vec<3>::Zero());
  const auto normal_velocity = [&](const Vec<3>& uf, const Vec<3>& P, double g) {
    return (uf + W * P).dot(n) + g;
  };
  // frictionless, with a gap: u_n + g/dt = 0, P along n
  Vec<3> uf(0.2, -0.1, -1.0);
  Vec<3> P = local_solution<3>(uf, W, n, 0.25, 0.0);
  EXPECT_NEAR(normal_velocity(uf, P, 0.25), 0.0, 1e-15);
  EXPECT_NEAR(P.dot(n), 0.75 / 1.5, 1e-15);
  EXPECT_EQ((P - P.dot(n) * n).norm(), 0.0);
  // stick: the whole relative velocity cancelled, inside the cone
  P = local_solution<3>(uf, W, n, 0.0, mu);
  EXPECT_LT((uf + W * P).norm(), 1e-14);
  EXPECT_LE((P - P.dot(n) * n).norm(), mu * P.dot(n));
  // slide: on the cone, against the tangential velocity left
  uf = Vec<3>(2.0, 1.0, -1.0);
  P = local_solution<3>(uf, W, n, 0.0, mu);
  const Vec<3> u = uf + W * P;
  const Vec<3> pt = P - P.dot(n) * n, ut = u - u.dot(n) * n;
  EXPECT_NEAR(u.dot(n), 0.0, 1e-14);
  EXPECT_GT(P.dot(n), 0.0);
  EXPECT_NEAR(pt.norm(), mu * P.dot(n), 1e-13);
  EXPECT_NEAR(pt.dot(ut) / (pt.norm() * ut.norm()), -1.0, 1e-12);
  // a lumped block w I gives the closed forms of the isotropic case
  P = local_solution<3>(Vec<3>(3.0, 0.0, -1.0), 2.0, n, 0.0, 0.5);
  EXPECT_NEAR(P[2], 0.5, 1e-15);
  EXPECT_NEAR(P[0], -0.25, 1e-15);
}

namespace {
// A column of 5 stacked "nodes" pressed on a wall: slot k above slot k-1, wall below slot 0.
contact::Problem<2> stack(double mu) {
  contact::Problem<2> p;
  p.dt = 1e-3;
  for (int k = 0; k < 5; ++k) p.slots.push_back({1.0 + k, Vec<2>(0.2 * k, -1.0 - k), k, k});
  contact::Contact<2> c;
  c.a = -1;
  c.b = 0;
  c.wall = 0;
  c.normal = Vec<2>(0, 1);
  c.friction = mu;
  p.contacts.push_back(c);
  for (int k = 1; k < 5; ++k) {
    c.a = k - 1;
    c.b = k;
    c.wall = -1;
    p.contacts.push_back(c);
  }
  return p;
}
}  // namespace

TEST(NetImpulses, EachSlotGetsItsContactsAsBMinusItsContactsAsA) {
  // In the stack, contact k acts on slot k (B) and, for k > 0, against slot k - 1 (A).
  auto p = stack(0.0);
  for (std::size_t k = 0; k < p.contacts.size(); ++k)
    p.contacts[k].impulse = Vec<2>(0.5 * k, 1.0 + k);
  const auto net = contact::net_impulses(p);
  ASSERT_EQ(net.size(), p.slots.size());
  for (std::size_t k = 0; k < 4; ++k)
    EXPECT_EQ(net[k], p.contacts[k].impulse - p.contacts[k + 1].impulse);
  EXPECT_EQ(net[4], p.contacts[4].impulse);
}

TEST(GaussSeidel, StackOnWallConvergesToNoPenetration) {
  for (double mu : {0.0, 0.3}) {
    auto p = stack(mu);
    auto r = contact::solve_gauss_seidel(p, {1e-12, 10000});
    ASSERT_TRUE(r.converged) << r.sweeps << " " << r.error;
    std::printf("  stack, mu = %.1f: %d sweeps, error %.2e\n", mu, r.sweeps, r.error);
    // all normal velocities >= 0 (no approach), total vertical momentum absorbed by the wall
    std::vector<Vec<2>> v;
    for (const auto& s : p.slots) v.push_back(s.v_free);
    for (const auto& c : p.contacts) {
      v[c.b] += c.impulse / p.slots[c.b].mass;
      if (c.a >= 0) v[c.a] -= c.impulse / p.slots[c.a].mass;
    }
    for (const auto& c : p.contacts) {
      const double un = (v[c.b] - (c.a >= 0 ? v[c.a] : Vec<2>::Zero())).dot(c.normal);
      EXPECT_GT(un, -1e-9);
      EXPECT_GE(c.impulse[1], 0.0);
      EXPECT_LE(std::abs(c.impulse[0]), mu * c.impulse[1] + 1e-12);
    }
    EXPECT_EQ(contact::error(p), r.error);
  }
}

TEST(GaussSeidel, GroupsColouredOnThreadsGiveTheSameImpulsesBitForBit) {
  // The 400-node problem with compliance groups: slot k of node n belongs to grain
  // 3 (n % 40) + k, whose exact-like response G = M^-1 + a random SPD coupling moves all its
  // slots. Nodes of one grain triple conflict, others do not: multicolour Gauss-Seidel sweeps
  // each colour's nodes on the threads. 1 and 2 threads: the same sweeps, error and impulses.
  const auto grouped = [] {
    auto p = test_support::many_node_problem(400);
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    p.groups.resize(120);
    for (std::size_t s = 0; s < p.slots.size(); ++s) {
      const int n = static_cast<int>(s) / 3, k = static_cast<int>(s) % 3;
      auto& g = p.groups[3 * (n % 40) + k];
      p.slots[s].group = 3 * (n % 40) + k;
      p.slots[s].local = static_cast<std::int32_t>(g.slots.size());
      g.slots.push_back(static_cast<std::int32_t>(s));
    }
    for (auto& g : p.groups) {
      const auto m = static_cast<Eigen::Index>(2 * g.slots.size());
      Eigen::MatrixXd R(m, m);
      for (Eigen::Index i = 0; i < m; ++i)
        for (Eigen::Index j = 0; j < m; ++j) R(i, j) = u(rng);
      Eigen::MatrixXd G = 0.05 * R * R.transpose() / static_cast<double>(m);
      for (std::size_t j = 0; j < g.slots.size(); ++j)
        G.block<2, 2>(2 * j, 2 * j) += Mat<2>::Identity() / p.slots[g.slots[j]].mass;
      g.set_full(G);
    }
    return p;
  };
  const int saved = omp_get_max_threads();
  std::vector<contact::Problem<2>> solved;
  std::vector<contact::GsResult> results;
  for (int threads : {1, 2}) {
    omp_set_num_threads(threads);
    auto p = grouped();
    results.push_back(contact::solve_gauss_seidel(p, {1e-10, 10000}));
    solved.push_back(std::move(p));
  }
  omp_set_num_threads(saved);
  ASSERT_TRUE(results[0].converged) << results[0].sweeps << " " << results[0].error;
  EXPECT_EQ(results[0].sweeps, results[1].sweeps);
  EXPECT_EQ(results[0].error, results[1].error);
  for (std::size_t c = 0; c < solved[0].contacts.size(); ++c)
    EXPECT_EQ(solved[0].contacts[c].impulse, solved[1].contacts[c].impulse) << "contact " << c;
  std::printf("  grouped problem: %d sweeps to %.1e\n", results[0].sweeps, results[0].error);
}

TEST(GaussSeidel, NodesSweptOnThreadsGiveTheSameImpulsesBitForBit) {
  // 4,000 contacts (above the threading threshold) at 1,000 independent nodes: with the lumped
  // operator each node's contacts are swept in their serial order, the nodes on the threads; the
  // error is summed in contact order. 1 and 2 threads: the same sweeps, error and impulses.
  const int saved = omp_get_max_threads();
  std::vector<contact::Problem<2>> solved;
  std::vector<contact::GsResult> results;
  for (int threads : {1, 2}) {
    omp_set_num_threads(threads);
    auto p = test_support::many_node_problem(1000);
    results.push_back(contact::solve_gauss_seidel(p, {1e-10, 10000}));
    solved.push_back(std::move(p));
  }
  omp_set_num_threads(saved);
  ASSERT_TRUE(results[0].converged) << results[0].sweeps << " " << results[0].error;
  EXPECT_GT(results[0].sweeps, 2);
  EXPECT_EQ(results[0].sweeps, results[1].sweeps);
  EXPECT_EQ(results[0].error, results[1].error);
  int active = 0;
  for (std::size_t c = 0; c < solved[0].contacts.size(); ++c) {
    EXPECT_EQ(solved[0].contacts[c].impulse, solved[1].contacts[c].impulse) << "contact " << c;
    active += solved[0].contacts[c].impulse.squaredNorm() > 0;
  }
  EXPECT_GT(active, 1000);  // the sweeps did work at many nodes
  // A node alone gives its contacts the same impulses: the nodes are independent problems.
  auto one = test_support::many_node_problem(1000);
  contact::Problem<2> node5;
  node5.dt = one.dt;
  for (int k = 0; k < 3; ++k) node5.slots.push_back(one.slots[15 + k]);
  for (int c : {15, 16, 17, 3005}) {
    auto ct = one.contacts[c];
    ct.a = ct.a < 0 ? -1 : ct.a - 15;
    ct.b -= 15;
    node5.contacts.push_back(ct);
  }
  const auto r5 = contact::solve_gauss_seidel(node5, {1e-14, 10000});
  ASSERT_TRUE(r5.converged);
  int k = 0;
  for (int c : {15, 16, 17, 3005})
    EXPECT_NEAR((node5.contacts[k++].impulse - solved[0].contacts[c].impulse).norm(), 0.0,
                1e-6 * solved[0].contacts[c].impulse.norm() + 1e-300)
        << "contact " << c;
}

TEST(GaussSeidel, ReplayedProblemGivesTheSameImpulses) {
  auto p = stack(0.3);
  const auto path = (std::filesystem::temp_directory_path() / "mpmcd_contact_problem.txt").string();
  contact::write_problem(p, path);  // warm start = 0
  auto r1 = contact::solve_gauss_seidel(p, {1e-10, 10000});
  auto q = contact::read_problem<2>(path);
  auto r2 = contact::solve_gauss_seidel(q, {1e-10, 10000});
  ASSERT_TRUE(r1.converged && r2.converged);
  double norm = 0, diff = 0;
  for (std::size_t c = 0; c < p.contacts.size(); ++c) {
    diff += (p.contacts[c].impulse - q.contacts[c].impulse).squaredNorm();
    norm += p.contacts[c].impulse.squaredNorm();
  }
  EXPECT_LE(std::sqrt(diff / norm), 1e-10);
}

// A compliance group on its slots' contact directions (contact::Group): one slot with a single
// normal (a frictionless face slot), one with all Dim directions. Its blocks are B_i Gr_ij B_j^T,
// the same after a write and a read (file v2), and a v1 file with the full matrix reads back as
// a group with B = I and the same blocks.
TEST(ProblemFile, GroupsOnContactDirectionsKeepTheirBlocks) {
  contact::Problem<3> p;
  p.dt = 1e-6;
  for (int s = 0; s < 2; ++s) {
    contact::Slot<3> sl;
    sl.mass = 1.0 + s;
    sl.group = 0;
    sl.local = s;
    p.slots.push_back(sl);
  }
  contact::Group<3> g;
  g.slots = {0, 1};
  const Vec<3> n = Vec<3>(1.0, -2.0, 0.5).normalized();
  g.basis = {Mat<3>::Zero(), Mat<3>::Identity()};
  g.basis[0].col(0) = n;
  g.col = {0, 1, 4};
  Eigen::MatrixXd R = Eigen::MatrixXd::Random(4, 4);
  g.Gr = R * R.transpose() + Eigen::MatrixXd::Identity(4, 4);
  p.groups.push_back(g);
  Eigen::MatrixXd B = Eigen::MatrixXd::Zero(6, 4);  // the slots' directions, block-diagonal
  B.block<3, 1>(0, 0) = n;
  B.block<3, 3>(3, 1) = Mat<3>::Identity();
  const Eigen::MatrixXd G = B * g.Gr * B.transpose();
  EXPECT_LE((g.full() - G).norm(), 1e-14 * G.norm());
  EXPECT_EQ(g.rank(0), 1);
  EXPECT_EQ(g.rank(1), 3);
  const Vec<3> u(0.3, 0.1, -0.7), w(-0.2, 0.4, 0.9);
  EXPECT_NEAR(g.bilinear(0, u, 1, w), u.dot(g.block(0, 1) * w), 1e-14);
  EXPECT_NEAR(g.bilinear(1, w, 0, u), w.dot(g.block(1, 0) * u), 1e-14);
  const auto dir = std::filesystem::temp_directory_path();
  const auto path = (dir / "mpmcd_group_v2.txt").string();
  contact::write_problem(p, path);
  const auto q = contact::read_problem<3>(path);
  ASSERT_EQ(q.groups.size(), 1u);
  EXPECT_EQ(q.groups[0].col, g.col);
  EXPECT_EQ((q.groups[0].Gr - g.Gr).norm(), 0.0);
  EXPECT_EQ((q.groups[0].full() - g.full()).norm(), 0.0);
  // A v1 file: the group's full 6 x 6 matrix after its slot line.
  std::ofstream v1(dir / "mpmcd_group_v1.txt");
  v1 << "# mpmcd contact problem v1\ndim 3\ndt 1e-6\nslots 2\n1 0 0 0 -1 -1 0 0\n2 0 0 0 -1 -1 0 "
        "1\n"
     << "contacts 0\ngroups 1\n2 0 1\n";
  v1.precision(17);
  for (Eigen::Index i = 0; i < 6; ++i) {
    for (Eigen::Index j = 0; j < 6; ++j) v1 << (j ? " " : "") << G(i, j);
    v1 << "\n";
  }
  v1.close();
  const auto r = contact::read_problem<3>((dir / "mpmcd_group_v1.txt").string());
  ASSERT_EQ(r.groups.size(), 1u);
  EXPECT_EQ(r.groups[0].rank(0), 3);
  EXPECT_EQ((r.groups[0].full() - G).norm(), 0.0);
}

TEST(ProblemFile, CorruptFilesAreRefusedWithAClearError) {
  const auto dir = std::filesystem::temp_directory_path();
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"", "unexpected end of file"},
      {"dim 3\n", "expected 2"},
      {"dim 2\ndt -1\n", "dt > 0"},
      {"dim 2\ndt 1e-3\nslots 999999999999\n", "corrupt file"},
      {"dim 2\ndt 1e-3\nslots 1\n1.0 x 0 0 0 -1 -1\n", "malformed numbers"},
      {"dim 2\ndt 1e-3\nslots 1\n1.0 0 0 0 0 -1 -1\ncontacts 1\n-1 5 0 0 1 0 0 0 0 0 0\n",
       "slot index out of range"},
      {"dim 2\ndt 1e-3\nslots 1\n1.0 0 0 0 0 -1 -1\ncontacts 0\n", "unexpected end of file"},
      {"# mpmcd contact problem v2\ndim 2\ndt 1e-3\nslots 1\n1.0 0 0 0 0 0 0\ncontacts 0\n"
       "groups 1\n1 0\n3 1 0 0 1\n",
       "expected a rank in [1, 2]"},
  };
  for (std::size_t i = 0; i < cases.size(); ++i) {
    const auto path = (dir / ("mpmcd_bad_problem_" + std::to_string(i) + ".txt")).string();
    std::ofstream(path) << cases[i].first;
    try {
      contact::read_problem<2>(path);
      ADD_FAILURE() << "case " << i << " accepted";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(cases[i].second), std::string::npos)
          << "case " << i << ": " << e.what();
    }
  }
}

namespace {
// A light field X (mass 1e-3) pinched at one node between two heavy fields Y and Z that move
// toward each other, with contacts X-Y, X-Z and Y-Z: pushing X from both sides barely moves it,
// so two of the three contacts are nearly redundant and plain Gauss-Seidel crawls (the triple
// nodes of a dense packing, docs/contact.md).
contact::Problem<2> pinched_node(double friction) {
  contact::Problem<2> p;
  p.dt = 1e-7;
  const auto slot = [&](double m, Vec<2> v) {
    contact::Slot<2> s;
    s.mass = m;
    s.v_free = v;
    s.node = 0;
    p.slots.push_back(s);
  };
  slot(1e-3, Vec<2>(0, 0));     // X
  slot(1.0, Vec<2>(1.0, 0.1));  // Y, moving +x
  slot(1.0, Vec<2>(-1.0, 0));   // Z, moving -x
  const auto contact = [&](int a, int b, Vec<2> n) {
    contact::Contact<2> c;
    c.a = a;
    c.b = b;
    c.normal = n.normalized();
    c.friction = friction;
    p.contacts.push_back(c);
  };
  contact(1, 0, Vec<2>(0.86, 0.51));    // Y pushes X
  contact(2, 0, Vec<2>(-0.89, -0.46));  // Z pushes X
  contact(1, 2, Vec<2>(0.87, 0.49));    // Y pushes Z
  return p;
}
}  // namespace

namespace {
// The slots' end-of-step velocities v_free + (net impulse)/m of two solutions of one lumped
// problem agree in the mass norm sqrt(m) |v| to 1e-7.
void expect_same_velocities(const contact::Problem<2>& p, const contact::Problem<2>& q) {
  const auto np = contact::net_impulses(p), nq = contact::net_impulses(q);
  for (std::size_t s = 0; s < p.slots.size(); ++s) {
    const Vec<2> vp = p.slots[s].v_free + np[s] / p.slots[s].mass;
    const Vec<2> vq = q.slots[s].v_free + nq[s] / q.slots[s].mass;
    EXPECT_LT(std::sqrt(p.slots[s].mass) * (vp - vq).norm(), 1e-7) << "slot " << s;
  }
}
}  // namespace

TEST(GaussSeidel, OverRelaxationAndNodeBlocksSolvePinchedNodesFasterToTheSameVelocities) {
  contact::GsSettings plain;
  plain.tolerance = 1e-10;
  plain.max_sweeps = 100000;
  plain.node_blocks = false;  // one contact at a time
  contact::GsSettings sor = plain;
  sor.relaxation = 1.8;
  auto p1 = pinched_node(0.0), p2 = pinched_node(0.0);
  const auto r1 = contact::solve_gauss_seidel(p1, plain);
  const auto r2 = contact::solve_gauss_seidel(p2, sor);
  std::printf("  plain Gauss-Seidel %d sweeps, projected SOR (omega 1.8) %d sweeps\n", r1.sweeps,
              r2.sweeps);
  ASSERT_TRUE(r1.converged);
  ASSERT_TRUE(r2.converged);
  EXPECT_LT(2 * r2.sweeps, r1.sweeps);
  // The same end-of-step velocities in the mass norm sqrt(m) |v| (the impulses may split
  // differently between near-redundant contacts; v of the light field is 1/m-sensitive).
  expect_same_velocities(p1, p2);
  // Nodal blocks: the three contacts of the node solved together, exactly, in one sweep (the error
  // is measured before and after it), to the same velocities.
  contact::GsSettings blocks = plain;
  blocks.node_blocks = true;
  auto p3 = pinched_node(0.0);
  const auto r3 = contact::solve_gauss_seidel(p3, blocks);
  std::printf("  nodal blocks %d sweep(s), error %.2e\n", r3.sweeps, r3.error);
  ASSERT_TRUE(r3.converged);
  EXPECT_LE(r3.sweeps, 2);
  expect_same_velocities(p1, p3);
  // Frictional contacts are not relaxed: the same sweeps and impulses as plain Gauss-Seidel.
  auto f1 = pinched_node(0.3), f2 = pinched_node(0.3);
  const auto q1 = contact::solve_gauss_seidel(f1, plain);
  const auto q2 = contact::solve_gauss_seidel(f2, sor);
  EXPECT_EQ(q1.sweeps, q2.sweeps);
  for (std::size_t c = 0; c < f1.contacts.size(); ++c)
    EXPECT_EQ(f1.contacts[c].impulse, f2.contacts[c].impulse);
}
