// Contact detection (contact/detect.hpp) on hand-made grain fields: two grains sharing one node
// and a floor, the contacts' normals, gaps, slots, warm starts and order, and the rank that
// solves a node's contacts.
#include <gtest/gtest.h>

#include <map>
#include <utility>
#include <vector>

#include "mpmcd/contact/detect.hpp"

using namespace mpmcd;

namespace {

// Records the slots detection asks for: node slots once per (grain, node), numbered in order.
class RecordingSlots final : public contact::SlotMaker<2> {
 public:
  std::int32_t node_slot(std::int32_t g, std::int32_t a) override {
    const auto [it, added] = nodes.try_emplace({g, a}, count);
    if (added) ++count;
    return it->second;
  }
  std::int32_t weighted_slot(std::int32_t, const std::vector<std::int32_t>&,
                             const std::vector<double>&) override {
    return count++;
  }
  void set_key(std::int32_t, std::int64_t) override {}
  std::map<std::pair<std::int32_t, std::int32_t>, std::int32_t> nodes;
  std::int32_t count = 0;
};

// Two grains of one point each (half-edge 0.25), at (1.0, 1.5) and (1.8, 1.5), whose fields
// share grid node (1, 1) at (1, 1) (h = 1), their mass gradients pointing out of each grain
// toward the other; a floor at y = 0.
struct TwoGrains {
  grid::Grid<2> grid{Vec<2>::Zero(), 1.0, IVec<2>(4, 4)};
  std::vector<Vec<2>> x{Vec<2>(1.0, 1.5), Vec<2>(1.8, 1.5)};
  std::vector<Mat<2>> F{Mat<2>::Identity(), Mat<2>::Identity()};
  std::vector<Mat<2>> D0{0.25 * Mat<2>::Identity(), 0.25 * Mat<2>::Identity()};
  std::vector<double> m{1.0};
  std::vector<std::int64_t> node{grid.node_index(IVec<2>(1, 1))};
  std::vector<Vec<2>> grad_a{Vec<2>(1, 0)}, grad_b{Vec<2>(-1, 0)}, v{Vec<2>::Zero()};
  std::vector<std::int32_t> start{0, 1}, pts{0};
  std::vector<contact::FieldView<2>> fields;
  std::vector<std::size_t> local{0, 1};
  contact::ContactSettings<2> cs;
  TwoGrains() {
    contact::FieldView<2> f;
    f.contact_mass = 0.5;
    f.m = m;
    f.node_global = node;
    f.v = v;
    f.node_pts_start = start;
    f.node_pts = pts;
    f.begin = 0;
    f.end = 1;
    f.grad_m = grad_a;
    fields.push_back(f);
    f.begin = 1;
    f.end = 2;
    f.grad_m = grad_b;
    fields.push_back(f);
    walls::Wall<2> floor;
    floor.normal = Vec<2>(0, 1);
    cs.walls.push_back(floor);
  }
  contact::DetectInput<2> input(const std::vector<contact::WarmImpulse<2>>& previous) const {
    contact::DetectInput<2> in;
    in.settings = &cs;
    in.grid = &grid;
    in.points = {x, F, D0};
    in.fields = fields;
    in.local = local;
    in.previous = previous;
    in.dt = 1e-3;
    return in;
  }
};

}  // namespace

TEST(ContactDetect, NodeContactsOfTwoGrainsAndAFloor) {
  TwoGrains t;
  const std::int64_t n = t.node[0];
  // Sorted by (node, a, b): the floor's (a = -1 - 0) before the grains'.
  const std::vector<contact::WarmImpulse<2>> previous{{n, -1, 1, Vec<2>(0.0, 0.25)},
                                                      {n, 0, 1, Vec<2>(0.5, 0.0)}};
  contact::Problem<2> problem;
  RecordingSlots slots;
  contact::Detector<2> detector;
  const double items = detector.detect(t.input(previous), problem, slots);
  EXPECT_GT(items, 0.0);
  ASSERT_EQ(problem.contacts.size(), 3u);
  // The grains at the shared node: normal from grain 0 to grain 1, gap 0.8 - 2 x 0.25.
  const auto& c = problem.contacts[0];
  EXPECT_EQ(c.a, 0);
  EXPECT_EQ(c.b, 1);
  EXPECT_TRUE(c.normal.isApprox(Vec<2>(1, 0)));
  EXPECT_NEAR(c.gap, 0.3, 1e-15);
  EXPECT_EQ(c.impulse, Vec<2>(0.5, 0.0));
  // The floor and each grain's node (1 cell from it: within wall_range), in grain order: gap
  // from the points' faces (1.25), not less than the node's distance minus a domain (0.5).
  for (int k = 1; k <= 2; ++k) {
    const auto& w = problem.contacts[static_cast<std::size_t>(k)];
    EXPECT_EQ(w.a, -1);
    EXPECT_EQ(w.wall, 0);
    EXPECT_EQ(w.b, k - 1);  // the grains' node slots, made once
    EXPECT_EQ(w.normal, Vec<2>(0, 1));
    EXPECT_NEAR(w.gap, 1.25, 1e-15);
  }
  EXPECT_EQ(problem.contacts[1].impulse, Vec<2>::Zero());
  EXPECT_EQ(problem.contacts[2].impulse, Vec<2>(0.0, 0.25));
  EXPECT_EQ(slots.count, 2);
  // Overlap criterion: the same contacts, the grains' with gap 0.
  t.cs.criterion = contact::GapCriterion::kOverlap;
  problem.contacts.clear();
  detector.detect(t.input(previous), problem, slots);
  ASSERT_EQ(problem.contacts.size(), 3u);
  EXPECT_EQ(problem.contacts[0].gap, 0.0);
}

TEST(ContactDetect, ANodeIsSolvedByTheOwnerOfItsLowestGrain) {
  TwoGrains t;
  std::vector<int> owner{1, 0};
  contact::Problem<2> problem;
  RecordingSlots slots;
  contact::Detector<2> detector;
  const std::vector<contact::WarmImpulse<2>> none;
  auto in = t.input(none);
  in.ranks = {true, false, 0, owner};
  detector.detect(in, problem, slots);
  EXPECT_TRUE(problem.contacts.empty());  // grain 0's owner, rank 1, solves them
  in.ranks.me = 1;
  detector.detect(in, problem, slots);
  EXPECT_EQ(problem.contacts.size(), 3u);
  problem.contacts.clear();
  in.ranks = {true, true, 0, owner};  // master: rank 0 solves every contact
  detector.detect(in, problem, slots);
  EXPECT_EQ(problem.contacts.size(), 3u);
}
