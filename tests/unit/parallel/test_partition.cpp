// tests/unit/parallel: dealing grains to ranks (docs/parallel.md).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "mpmcd/parallel/comm.hpp"
#include "mpmcd/parallel/partition.hpp"

using namespace mpmcd::parallel;

namespace {

// 300 grains on a jittered 20 x 15 lattice with point counts in [100, 300].
void lattice(std::vector<std::array<double, 2>>& c, std::vector<double>& w) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> jitter(-0.2, 0.2), count(100, 300);
  for (int j = 0; j < 15; ++j)
    for (int i = 0; i < 20; ++i) {
      c.push_back({i + jitter(rng), j + jitter(rng)});
      w.push_back(std::round(count(rng)));
    }
}

}  // namespace

TEST(Partition, BisectionBalancesTheWeightForAnyPartCount) {
  std::vector<std::array<double, 2>> c;
  std::vector<double> w;
  lattice(c, w);
  for (int parts : {1, 2, 3, 4, 5, 8, 60}) {
    const auto part = bisection(c, w, parts);
    ASSERT_EQ(part.size(), c.size());
    EXPECT_EQ(*std::max_element(part.begin(), part.end()), parts - 1);
    // One grain of at most 300 points in a part of 45,000 / parts: the cut is within a grain.
    const double mean = 300.0 * 200.0 / parts;
    EXPECT_LE(imbalance(part, w, parts), 1.0 + 2 * 300.0 / mean + 1e-12) << parts << " parts";
    EXPECT_EQ(part, bisection(c, w, parts));  // deterministic
  }
}

TEST(Partition, BisectionIsCompactDealingIsNot) {
  std::vector<std::array<double, 2>> c;
  std::vector<double> w;
  lattice(c, w);
  // Compactness: lattice neighbour pairs (distance < 1.5) split between parts.
  const auto cut_pairs = [&](const std::vector<int>& part) {
    int cut = 0;
    for (std::size_t a = 0; a < c.size(); ++a)
      for (std::size_t b = a + 1; b < c.size(); ++b)
        if (std::hypot(c[a][0] - c[b][0], c[a][1] - c[b][1]) < 1.5 && part[a] != part[b]) ++cut;
    return cut;
  };
  const auto rcb = bisection(c, w, 4);
  const auto dealt = deal_by_volume(w, 4);
  EXPECT_LT(cut_pairs(rcb), cut_pairs(dealt) / 5);
  EXPECT_LT(imbalance(dealt, w, 4), 1.01);  // the published dealing balances the volume
}

TEST(Partition, SchemeNames) {
  EXPECT_EQ(scheme_from_string("partition"), Scheme::kPartition);
  EXPECT_EQ(scheme_from_string("master"), Scheme::kMaster);
  EXPECT_EQ(to_string(Scheme::kMaster), "master");
  EXPECT_THROW(scheme_from_string("ring"), std::invalid_argument);
}

TEST(Comm, SerialWithoutMpirunIsOneRank) {
  const Comm& comm = Comm::world();
  EXPECT_EQ(comm.size(), 1);
  EXPECT_EQ(comm.rank(), 0);
  std::vector<double> v{1.5, 2.5};
  comm.sum(v);
  EXPECT_EQ(v[1], 2.5);
  Buffer b;
  b.put(3);
  b.put(4.5);
  EXPECT_EQ(b.get<int>(), 3);
  EXPECT_EQ(b.get<double>(), 4.5);
  EXPECT_TRUE(b.done());
  Comm::finalize();
}
