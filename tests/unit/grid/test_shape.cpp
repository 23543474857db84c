// Shape functions: partition of unity, linear reproduction (sum x_I N_I = x, sum x_I (x) grad N_I =
// I), zero gradient sum, and gradients against finite differences, for linear and uGIMP.
#include <gtest/gtest.h>

#include <map>
#include <random>

#include "mpmcd/grid/shape.hpp"

using namespace mpmcd;

// Weights of any shape family at x: partition of unity and linear reproduction
// (sum x_I N_I = x_p, sum x_I (x) grad N_I = I to grad_tol).
template <class Shape>
void expect_reproduces_linear_fields(const Shape& ps, const Vec<2>& origin, double h,
                                     const Vec<2>& x, double grad_tol) {
  double sum = 0;
  Vec<2> xr = Vec<2>::Zero();
  Mat<2> grad = Mat<2>::Zero();
  for (int a = 0; a < ps.K; ++a) {
    IVec<2> c = ps.first;
    for (int d = 0; d < 2; ++d) c[d] += ps.offset(a, d);
    const Vec<2> xn = origin + h * c.cast<double>();
    sum += ps.N[a];
    xr += ps.N[a] * xn;
    grad += xn * ps.dN[a].transpose();
  }
  EXPECT_NEAR(sum, 1.0, 1e-14);
  EXPECT_LT((xr - x).norm(), 1e-14);
  EXPECT_LT((grad - Mat<2>::Identity()).norm(), grad_tol);
}

template <class S1>
void check_shape(double lp) {
  const Vec<2> origin(-0.3, 0.1);
  const double h = 0.25;
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(1.0, 3.0);
  for (int trial = 0; trial < 200; ++trial) {
    const Vec<2> x = origin + h * Vec<2>(u(rng), u(rng));
    grid::PointShape<2, S1> ps;
    ps.eval(x, origin, h, lp);
    expect_reproduces_linear_fields(ps, origin, h, x, 1e-13);
    Vec<2> gsum = Vec<2>::Zero();
    for (int a = 0; a < ps.K; ++a) {
      IVec<2> c = ps.first;
      for (int d = 0; d < 2; ++d) c[d] += ps.offset(a, d);
      gsum += ps.dN[a];
      // finite-difference gradient of the same node's weight
      for (int d = 0; d < 2; ++d) {
        Vec<2> xp = x, xm = x;
        const double e = 1e-7 * h;
        xp[d] += e;
        xm[d] -= e;
        grid::PointShape<2, S1> sp, sm;
        sp.eval(xp, origin, h, lp);
        sm.eval(xm, origin, h, lp);
        auto weight = [&](const grid::PointShape<2, S1>& s) {
          for (int b = 0; b < s.K; ++b) {
            IVec<2> cb = s.first;
            for (int dd = 0; dd < 2; ++dd) cb[dd] += s.offset(b, dd);
            if (cb == c) return s.N[b];
          }
          return 0.0;
        };
        EXPECT_NEAR((weight(sp) - weight(sm)) / (2 * e), ps.dN[a][d], 1e-5 / h);
      }
    }
    EXPECT_LT(gsum.norm(), 1e-12 / h);
  }
}

TEST(Shape, LinearPartitionOfUnityAndLinearReproduction) {
  check_shape<grid::Linear1D>(0.0);
}
TEST(Shape, UGimpPartitionOfUnityAndLinearReproduction) {
  check_shape<grid::UGimp1D>(0.25 / 4);
}
TEST(Shape, UGimpHalfWidthHalfCell) {
  check_shape<grid::UGimp1D>(0.25 / 2 * 0.999);
}

// CPDI1 (Sadeghirad et al. 2011): partition of unity, linear reproduction (sum x_I N_I = x_p,
// sum x_I (x) grad N_I = I), and the gradient equal to the mean of the exact gradient of the
// corner interpolant over the parallelogram (midpoint quadrature on a fine sub-grid of it).
TEST(Shape, CpdiPartitionOfUnityLinearReproductionAndMeanGradient) {
  const Vec<2> origin(-0.3, 0.1);
  const double h = 0.25;
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(1.0, 3.0), f(-0.3, 0.3);
  for (int trial = 0; trial < 200; ++trial) {
    const Vec<2> x = origin + h * Vec<2>(u(rng), u(rng));
    Mat<2> D;  // a sheared, stretched, rotated domain of half-edges about h/4
    D << 1 + f(rng), f(rng), f(rng), 1 + f(rng);
    D *= h / 4;
    grid::CpdiShape<2> ps;
    ASSERT_TRUE(ps.eval(x, origin, h, 0.0, D));
    expect_reproduces_linear_fields(ps, origin, h, x, 1e-12);
    // Mean gradient of the bilinear corner interpolant of N_I over the domain, node by node.
    const int m = 40;
    for (int a = 0; a < ps.K; ++a) {
      IVec<2> c = ps.first;
      for (int d = 0; d < 2; ++d) c[d] += ps.offset(a, d);
      const auto hat = [&](const Vec<2>& y) {
        const Vec<2> t = (y - origin) / h - c.cast<double>();
        return std::max(0.0, 1 - std::abs(t[0])) * std::max(0.0, 1 - std::abs(t[1]));
      };
      double Nc[4];
      for (int k = 0; k < 4; ++k)
        Nc[k] = hat(x + D * Vec<2>(k & 1 ? 1.0 : -1.0, k & 2 ? 1.0 : -1.0));
      Vec<2> mean = Vec<2>::Zero();
      for (int i = 0; i < m; ++i)
        for (int j = 0; j < m; ++j) {
          const double s1 = -1 + (2 * i + 1.0) / m, s2 = -1 + (2 * j + 1.0) / m;
          // d/ds of the bilinear interpolant in (s1, s2), mapped by D^-T.
          const Vec<2> ds(
              (-(1 - s2) * Nc[0] + (1 - s2) * Nc[1] - (1 + s2) * Nc[2] + (1 + s2) * Nc[3]) / 4,
              (-(1 - s1) * Nc[0] - (1 + s1) * Nc[1] + (1 - s1) * Nc[2] + (1 + s1) * Nc[3]) / 4);
          mean += D.inverse().transpose() * ds / (m * m);
        }
      EXPECT_LT((mean - ps.dN[a]).norm(), 1e-10 / h) << "node " << a;
    }
  }
}

// Domains that tile a block keep tiling it under a homogeneous F, so sum_p V_p grad N_I = 0 at
// every node whose window does not reach the block's edge, wherever the points sit relative to
// the grid lines: the property that removes the cell-crossing error of a uniform stress.
TEST(Shape, CpdiTiledDomainsGiveNoInteriorForceUnderHomogeneousF) {
  const Vec<2> origin(0.0, 0.0);
  const double h = 0.1;
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> f(-0.25, 0.25);
  for (int trial = 0; trial < 20; ++trial) {
    Mat<2> F;
    F << 1 + f(rng), f(rng), f(rng), 1 + f(rng);
    const Vec<2> shift(0.013 * trial, 0.007 * trial);
    // 24 x 24 points of spacing h/2 in [1, 2.2]^2 before F, mapped about its centre.
    const Vec<2> c(1.6, 1.6);
    std::map<std::pair<std::int64_t, std::int64_t>, Vec<2>> sum;
    std::map<std::pair<std::int64_t, std::int64_t>, double> scale;  // sum of |V grad N|
    for (int i = 0; i < 24; ++i)
      for (int j = 0; j < 24; ++j) {
        const Vec<2> X(1.0 + (i + 0.5) * h / 2, 1.0 + (j + 0.5) * h / 2);
        const Vec<2> x = c + shift + F * (X - c);
        grid::CpdiShape<2> ps;
        ASSERT_TRUE(ps.eval(x, origin, h, 0.0, F * (h / 4 * Mat<2>::Identity())));
        const double V = F.determinant() * h * h / 4;
        for (int a = 0; a < ps.K; ++a) {
          const std::pair<std::int64_t, std::int64_t> key{ps.first[0] + ps.offset(a, 0),
                                                          ps.first[1] + ps.offset(a, 1)};
          sum.try_emplace(key, Vec<2>::Zero());
          sum[key] += V * ps.dN[a];
          scale[key] += V * ps.dN[a].norm();
        }
      }
    // Interior nodes: at least a cell inside the deformed block (its edges map from [1, 2.2]).
    int interior = 0;
    for (const auto& [key, g] : sum) {
      const Vec<2> xn = origin + h * Vec<2>(key.first, key.second);
      const Vec<2> X = c + F.inverse() * (xn - c - shift);
      const double margin = 2.5 * h;
      if ((X.array() < 1.0 + margin).any() || (X.array() > 2.2 - margin).any()) continue;
      ++interior;
      EXPECT_LT(g.norm(), 1e-13 * scale[key]) << "node " << key.first << "," << key.second;
    }
    EXPECT_GT(interior, 4);
  }
}

// A CPDI domain stretched over more than two cells along an axis does not fit the 3-node window
// (eval fails); fit_cpdi_window shrinks it about the point until it does, and the weights of the
// shrunk domain keep the partition of unity and reproduce linear fields exactly. A domain at most
// one cell wide is returned unchanged.
TEST(Shape, CpdiStretchedDomainShrunkToTheWindowStaysConsistent) {
  const Vec<2> origin(-0.3, 0.1);
  const double h = 0.25;
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(1.0, 3.0), f(-0.4, 0.4), g(1.2, 2.5);
  int shrunk = 0;
  for (int trial = 0; trial < 200; ++trial) {
    const Vec<2> x = origin + h * Vec<2>(u(rng), u(rng));
    Mat<2> D;  // half-edges stretched to 0.6-1.25 h along one direction, sheared
    D << g(rng), f(rng), f(rng), 0.5 + f(rng);
    D *= h / 2;
    grid::CpdiShape<2> ps;
    if (ps.eval(x, origin, h, 0.0, D)) continue;  // fits from where it lies
    ++shrunk;
    const Mat<2> Dfit = grid::fit_cpdi_window<2>(D, h);
    EXPECT_LE(Dfit.cwiseAbs().rowwise().sum().maxCoeff(), 0.5 * h);
    EXPECT_LT((Dfit - D * (Dfit(0, 0) / D(0, 0))).norm(), 1e-15);  // the same shape, scaled
    ASSERT_TRUE(ps.eval(x, origin, h, 0.0, Dfit));
    expect_reproduces_linear_fields(ps, origin, h, x, 1e-12);
  }
  EXPECT_GT(shrunk, 100);
  Mat<2> small;
  small << 0.3, 0.1, -0.05, 0.2;
  small *= h;  // half-extents 0.4 h and 0.25 h
  EXPECT_EQ(grid::fit_cpdi_window<2>(small, h), small);
}
