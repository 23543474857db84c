// parallel::Comm on any number of ranks (docs/parallel.md): run alone (one rank, every call a
// local no-op) as unit/parallel/CommOnOneRank and under mpirun -np 2 as mpi_2ranks_comm. Every
// expectation is written for a rank count R, so the same file checks both.
#include <gtest/gtest.h>

#include <cstdint>
#include <map>
#include <vector>

#include "mpmcd/parallel/comm.hpp"

using mpmcd::parallel::Buffer;
using mpmcd::parallel::Comm;

namespace {

// MPI is finalised once, after every test.
class CommEnvironment : public ::testing::Environment {
 public:
  void TearDown() override { Comm::finalize(); }
};

// A value of rank r whose sum over three or more ranks depends on the order of the additions in
// double: 1, 1e16, -1e16, then 0.5 r (in rank order (1 + 1e16) - 1e16 = 0, where an MPI
// reduction tree may give (1e16 - 1e16) + 1 = 1).
double order_sensitive(int r) {
  if (r == 0) return 1.0;
  if (r == 1) return 1e16;
  if (r == 2) return -1e16;
  return 0.5 * r;
}

}  // namespace

TEST(CommOnAnyRanks, RankAndSizeAgree) {
  const Comm& comm = Comm::world();
  const int R = comm.size();
  ASSERT_GE(R, 1);
  ASSERT_GE(comm.rank(), 0);
  ASSERT_LT(comm.rank(), R);
  std::vector<std::int64_t> one{1, comm.rank()};
  comm.sum(one);
  EXPECT_EQ(one[0], R);
  EXPECT_EQ(one[1], static_cast<std::int64_t>(R) * (R - 1) / 2);
}

TEST(CommOnAnyRanks, SumAddsInRankOrderBitForBit) {
  const Comm& comm = Comm::world();
  const int R = comm.size();
  std::vector<double> v{order_sensitive(comm.rank()), 0.1 * (comm.rank() + 1)};
  comm.sum(v);
  double expect0 = 0, expect1 = 0;  // the rank-order sums, as one process adds them
  for (int r = 0; r < R; ++r) {
    expect0 += order_sensitive(r);
    expect1 += 0.1 * (r + 1);
  }
  EXPECT_EQ(v[0], expect0);
  EXPECT_EQ(v[1], expect1);
}

TEST(CommOnAnyRanks, MaxAndMinOverRanks) {
  const Comm& comm = Comm::world();
  const int R = comm.size();
  std::vector<double> mx{static_cast<double>(comm.rank()), -static_cast<double>(comm.rank())};
  comm.max(mx);
  EXPECT_EQ(mx[0], R - 1);
  EXPECT_EQ(mx[1], 0.0);
  std::vector<std::int64_t> mn{comm.rank() + 5, -comm.rank()};
  comm.min(mn);
  EXPECT_EQ(mn[0], 5);
  EXPECT_EQ(mn[1], -(R - 1));
}

TEST(CommOnAnyRanks, AllgatherAndBroadcastCarryEveryRanksBytes) {
  const Comm& comm = Comm::world();
  const int R = comm.size();
  // Rank r sends r + 1 bytes of value r (different sizes per rank).
  const std::vector<char> mine(static_cast<std::size_t>(comm.rank() + 1),
                               static_cast<char>(comm.rank()));
  const auto all = comm.allgather(mine);
  ASSERT_EQ(static_cast<int>(all.size()), R);
  for (int r = 0; r < R; ++r)
    EXPECT_EQ(all[r], std::vector<char>(static_cast<std::size_t>(r + 1), static_cast<char>(r)));
  const int root = R - 1;
  std::vector<char> bytes;
  if (comm.rank() == root) bytes = {'m', 'p', 'm'};
  comm.broadcast(bytes, root);
  EXPECT_EQ(bytes, (std::vector<char>{'m', 'p', 'm'}));
}

TEST(CommOnAnyRanks, RingExchangeDeliversTypedBuffers) {
  const Comm& comm = Comm::world();
  const int R = comm.size();
  if (R < 2) {
    // One rank: no neighbour; nothing is sent or received.
    const auto in = comm.exchange({}, {});
    EXPECT_TRUE(in.empty());
    EXPECT_EQ(comm.bytes_sent(), 0);
    return;
  }
  const int next = (comm.rank() + 1) % R, prev = (comm.rank() + R - 1) % R;
  std::map<int, Buffer> out;
  out[next].put(comm.rank());
  out[next].put(2.5 * comm.rank());
  const std::int64_t sent_before = comm.bytes_sent();
  auto in = comm.exchange(out, {prev});
  ASSERT_EQ(in.size(), 1u);
  Buffer& b = in.at(prev);
  EXPECT_EQ(b.get<int>(), prev);
  EXPECT_EQ(b.get<double>(), 2.5 * prev);
  EXPECT_TRUE(b.done());
  EXPECT_GE(comm.bytes_sent() - sent_before,
            static_cast<std::int64_t>(sizeof(int) + sizeof(double)));
}

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  ::testing::AddGlobalTestEnvironment(new CommEnvironment);
  return RUN_ALL_TESTS();
}

// Comm::alone() is this process by itself whatever the job's rank count (the serial solver's
// comm): every collective leaves the values as they are, exchanges receive nothing, and it does
// not count bytes or messages.
TEST(CommOnAnyRanks, AloneIsOneRankOnAnyRankCount) {
  const Comm& alone = Comm::alone();
  EXPECT_EQ(alone.size(), 1);
  EXPECT_EQ(alone.rank(), 0);
  EXPECT_EQ(&alone, &Comm::alone());
  std::vector<double> d{1.5, -2.0};
  alone.sum(d);
  alone.max(d);
  EXPECT_EQ(d, (std::vector<double>{1.5, -2.0}));
  std::vector<std::int64_t> i{3, -4};
  alone.sum(i);
  alone.min(i);
  EXPECT_EQ(i, (std::vector<std::int64_t>{3, -4}));
  const std::vector<char> mine{'a', 'b'};
  const auto all = alone.allgather(mine);
  ASSERT_EQ(all.size(), 1u);
  EXPECT_EQ(all[0], mine);
  std::vector<char> bytes{'x'};
  alone.broadcast(bytes, 0);
  EXPECT_EQ(bytes, std::vector<char>{'x'});
  EXPECT_TRUE(alone.exchange({}, {}).empty());
  alone.barrier();
  EXPECT_EQ(alone.bytes_sent(), 0);
  EXPECT_EQ(alone.messages_sent(), 0);
}

// gather: every rank's bytes at the root, indexed by rank, the root's own included; nothing
// elsewhere. Each root in turn.
TEST(CommOnAnyRanks, GatherGivesTheRootEveryRanksBytes) {
  const Comm& comm = Comm::world();
  const int R = comm.size();
  const std::vector<char> mine(static_cast<std::size_t>(comm.rank() + 1),
                               static_cast<char>('a' + comm.rank()));
  for (int root = 0; root < R; ++root) {
    const auto all = comm.gather(mine, root);
    if (comm.rank() != root) {
      EXPECT_TRUE(all.empty());
      continue;
    }
    ASSERT_EQ(all.size(), static_cast<std::size_t>(R));
    for (int r = 0; r < R; ++r)
      EXPECT_EQ(all[static_cast<std::size_t>(r)],
                std::vector<char>(static_cast<std::size_t>(r + 1), static_cast<char>('a' + r)));
  }
}
