// Shape functions: partition of unity, linear reproduction (sum x_I N_I = x, sum x_I (x) grad N_I =
// I), zero gradient sum, and gradients against finite differences, for linear and uGIMP.
#include <gtest/gtest.h>

#include <random>

#include "mpmcd/grid/shape.hpp"

using namespace mpmcd;

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
    double sum = 0;
    Vec<2> xr = Vec<2>::Zero(), gsum = Vec<2>::Zero();
    Mat<2> grad = Mat<2>::Zero();
    for (int a = 0; a < ps.K; ++a) {
      IVec<2> c = ps.first;
      for (int d = 0; d < 2; ++d) c[d] += ps.offset(a, d);
      const Vec<2> xn = origin + h * c.cast<double>();
      sum += ps.N[a];
      xr += ps.N[a] * xn;
      gsum += ps.dN[a];
      grad += xn * ps.dN[a].transpose();
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
    EXPECT_NEAR(sum, 1.0, 1e-14);
    EXPECT_LT((xr - x).norm(), 1e-14);
    EXPECT_LT(gsum.norm(), 1e-12 / h);
    EXPECT_LT((grad - Mat<2>::Identity()).norm(), 1e-13);
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
