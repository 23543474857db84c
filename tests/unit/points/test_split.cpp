// Point splitting (points/split.hpp): which domains are too wide for the CPDI1 window, and the two
// children that replace a point keep its mass, momentum, volume and stored state and tile its
// domain.
#include <gtest/gtest.h>

#include <vector>

#include "mpmcd/grid/shape.hpp"
#include "mpmcd/points/split.hpp"

using namespace mpmcd;

namespace {
// Two grains on cells of h = 1: grain 0 has three points (two history doubles each), grain 1 two
// points (no history). Domains are squares of half-edge 0.25 (2 points per cell).
template <int Dim>
void make(points::PointSet<Dim>& pts, std::vector<points::Grain>& grains) {
  const Mat<Dim> dom = 0.25 * Mat<Dim>::Identity();
  for (int p = 0; p < 5; ++p) {
    Vec<Dim> x = Vec<Dim>::Constant(0.1 * p);
    x[0] = 3.0 + p;
    pts.add(x, Vec<Dim>::Constant(0.5 - 0.1 * p), 2.0 + p, 0.25 + 0.01 * p, dom, p < 3 ? 0 : 1);
    pts.L.back() = Mat<Dim>::Constant(0.3 + p);
    pts.sigma.back() = Mat<Dim>::Constant(7.0 + p);
  }
  pts.history = {10, 11, 20, 21, 30, 31};
  grains = {{0, 3, 0, 0.25, 0}, {3, 5, 0, 0.25, 6}};
}

template <int Dim>
void check_split() {
  points::PointSet<Dim> pts;
  std::vector<points::Grain> grains;
  make(pts, grains);
  // Point 1 stretched 2.4x along x (0.5 * 2.4 = 1.2 cells wide), point 4 sheared so that its
  // second edge (0.25 (1.5, 1)) spans most of its widest axis x (0.25 + 0.375 = 0.625 > 0.5).
  pts.F[1](0, 0) = 2.4;
  pts.F[4](0, 1) = 1.5;
  pts.F[0](0, 0) = 1.99;  // 0.995 of a cell: fits
  const std::vector<std::size_t> all{0, 1};
  const auto splits = points::find_splits(pts, grains, all, 1.0);
  ASSERT_EQ(splits.size(), 2u);
  EXPECT_EQ(splits[0].point, 1);
  EXPECT_EQ(splits[0].edge, 0);
  EXPECT_EQ(splits[1].point, 4);
  EXPECT_EQ(splits[1].edge, 1);
  // Only the grains asked for are searched.
  const std::vector<std::size_t> second{1};
  EXPECT_EQ(points::find_splits(pts, grains, second, 1.0).size(), 1u);

  const auto old = pts;
  const auto index = points::apply_splits(pts, grains, std::span<const points::Split>(splits));
  ASSERT_EQ(pts.size(), 7u);
  EXPECT_EQ(index, (std::vector<std::int64_t>{0, 1, 2, 4, 5}));
  // Grain 0: points 0, 1-, 2, 1+; grain 1: 3, 4-, 4+; history follows its points.
  EXPECT_EQ(grains[0].begin, 0);
  EXPECT_EQ(grains[0].end, 4);
  EXPECT_EQ(grains[1].begin, 4);
  EXPECT_EQ(grains[1].end, 7);
  EXPECT_EQ(grains[1].history_offset, 8);
  EXPECT_EQ(pts.history, (std::vector<double>{10, 11, 20, 21, 30, 31, 20, 21}));
  const std::vector<std::int64_t> from{0, 1, 2, 1, 3, 4, 4};
  double m = 0, m_old = 0, v0 = 0, v0_old = 0, vol = 0, vol_old = 0;
  Vec<Dim> p = Vec<Dim>::Zero(), p_old = Vec<Dim>::Zero(), mx = Vec<Dim>::Zero(),
           mx_old = Vec<Dim>::Zero();
  for (std::size_t q = 0; q < pts.size(); ++q) {
    const auto o = static_cast<std::size_t>(from[q]);
    EXPECT_EQ(pts.grain[q], old.grain[o]);
    EXPECT_EQ(pts.F[q], old.F[o]);
    EXPECT_EQ(pts.sigma[q], old.sigma[o]);
    EXPECT_EQ(pts.L[q], old.L[o]);
    // Every domain now fits the window.
    EXPECT_TRUE(grid::fits_cpdi_window<Dim>(pts.F[q] * pts.domain[q], 1.0)) << q;
    m += pts.mass[q];
    v0 += pts.volume0[q];
    vol += pts.volume[q];
    p += pts.mass[q] * pts.v[q];
    mx += pts.mass[q] * pts.x[q];
  }
  for (std::size_t o = 0; o < old.size(); ++o) {
    m_old += old.mass[o];
    v0_old += old.volume0[o];
    vol_old += old.volume[o];
    p_old += old.mass[o] * old.v[o];
    mx_old += old.mass[o] * old.x[o];
  }
  EXPECT_DOUBLE_EQ(m, m_old);
  EXPECT_DOUBLE_EQ(v0, v0_old);
  EXPECT_DOUBLE_EQ(vol, vol_old);
  EXPECT_LT((p - p_old).norm(), 1e-14);
  EXPECT_LT((mx - mx_old).norm(), 1e-13);
  // The children of point 4 tile its parallelogram: centres x -/+ d/2 with d = F D0 e_1, half
  // that edge, the other edge kept; their velocities follow the parent's affine field.
  const Vec<Dim> d = 0.5 * old.F[4] * old.domain[4].col(1);
  for (int c = 0; c < 2; ++c) {
    const std::size_t q = c == 0 ? 5 : 6;
    const double s = c == 0 ? -1.0 : 1.0;
    EXPECT_LT((pts.x[q] - (old.x[4] + s * d)).norm(), 1e-15);
    EXPECT_LT((pts.v[q] - (old.v[4] + s * old.L[4] * d)).norm(), 1e-14);
    EXPECT_LT((pts.domain[q].col(1) - 0.5 * old.domain[4].col(1)).norm(), 1e-15);
    EXPECT_EQ(pts.domain[q].col(0), old.domain[4].col(0));
    EXPECT_DOUBLE_EQ(pts.mass[q], 0.5 * old.mass[4]);
  }
  // Nothing to split: the identity numbering and the same points.
  const auto again = points::find_splits(pts, grains, all, 1.0);
  EXPECT_TRUE(again.empty());
  const auto same = points::apply_splits(pts, grains, std::span<const points::Split>(again));
  EXPECT_EQ(same, (std::vector<std::int64_t>{0, 1, 2, 3, 4, 5, 6}));
  EXPECT_EQ(pts.size(), 7u);
}
}  // namespace

TEST(PointSplitting, TwoChildrenTileTheDomainAndKeepMassMomentumVolumeAndStateIn2D) {
  check_split<2>();
}

TEST(PointSplitting, TwoChildrenTileTheDomainAndKeepMassMomentumVolumeAndStateIn3D) {
  check_split<3>();
}

TEST(PointSplitting, RefusesUnsortedSplits) {
  points::PointSet<2> pts;
  std::vector<points::Grain> grains;
  make(pts, grains);
  const std::vector<points::Split> bad{{3, 0}, {1, 0}};
  EXPECT_THROW(points::apply_splits(pts, grains, std::span<const points::Split>(bad)),
               std::invalid_argument);
}
