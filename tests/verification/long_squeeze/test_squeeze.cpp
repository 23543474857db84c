// A nearly incompressible Neo-Hookean disk (R = 5 mm, mu = 1.5 MPa, lambda = 100 MPa,
// rho = 990 kg/m^3, polar seeding) squeezed to 50 % of its diameter between two rigid
// frictionless walls (bottom fixed, top moving down at 1 m/s = 0.026 c_s), no gravity, theta = 1,
// linear shapes, 2 points per cell and axis, c_p dt / h = 0.25. Force-displacement curves at 8, 12
// and 18 cells per diameter, the relative L2 difference between successive resolutions (must
// decrease), and the area change against the static identity for the Neo-Hookean law (below),
// within 5 % at the finest grid for Delta/D >= 0.2. Long (about 2 minutes on an idle machine).
#include <gtest/gtest.h>

#include "../../support/contact_builders.hpp"

using namespace mpmcd;
using namespace mpmcd::test_support;

TEST(SqueezeLong, HalfDiameterConvergesUnderRefinementAndKeepsItsArea) {
  const std::vector<int> resolutions = {8, 12, 18};
  std::vector<SqueezeResult> runs;
  SqueezeSetup su;
  su.lambda = 100e6;
  su.wall_speed = 1.0;
  su.courant = 0.25;
  su.final_approach = 0.5 * 2 * su.radius;
  su.samples = 40;
  su.polar = true;
  for (int cpd : resolutions) {
    su.cells_per_diameter = cpd;
    runs.push_back(run_squeeze(su));
    const auto& r = runs.back();
    std::printf("  D/h = %d: h = %.3e m, dt = %.3e s, %lld points, %lld steps (%lld cut), %.1f s\n",
                cpd, r.h, r.dt, static_cast<long long>(r.points), static_cast<long long>(r.steps),
                static_cast<long long>(r.cuts), r.seconds);
    ASSERT_TRUE(r.ok) << r.failure;
  }
  // Curves on a common grid of Delta/D.
  std::printf("  %8s", "Delta/D");
  for (int cpd : resolutions) std::printf("  P(D/h=%2d) [N/m]", cpd);
  std::printf("\n");
  const double D = 2 * su.radius;
  std::vector<double> num(resolutions.size() - 1, 0.0), den(resolutions.size() - 1, 0.0);
  for (int k = 1; k <= 20; ++k) {
    const double x = 0.025 * k;
    std::printf("  %8.3f", x);
    std::vector<double> p;
    for (const auto& r : runs) {
      p.push_back(load_at(r, x * D));
      std::printf("  %16.1f", p.back());
    }
    std::printf("\n");
    for (std::size_t i = 0; i + 1 < p.size(); ++i) {
      num[i] += std::pow(p[i + 1] - p[i], 2);
      den[i] += std::pow(p[i + 1], 2);
    }
  }
  std::vector<double> l2;
  for (std::size_t i = 0; i < num.size(); ++i) {
    l2.push_back(std::sqrt(num[i] / den[i]));
    std::printf("  relative L2 difference D/h = %d -> %d: %.4f\n", resolutions[i],
                resolutions[i + 1], l2.back());
  }
  for (std::size_t i = 0; i + 1 < l2.size(); ++i) EXPECT_LT(l2[i + 1], l2[i]);
  // Area change against the static identity (virial, frictionless walls): for the Neo-Hookean
  // law tau = lambda ln J I + mu (b - I) (paper eq. 8) and int sigma dA = int tau dA0,
  //   lambda <ln J> = -P H / (2 A0) - (mu / 2) <b_xx + b_yy - 2>,  <.> = int . dA0 / A0,
  // so the grain's area change is set by lambda and the load it carries.
  for (std::size_t i = 0; i < runs.size(); ++i) {
    const auto& r = runs[i];
    for (double x : {0.1, 0.2, 0.3, 0.4, 0.5}) {
      const auto it = std::min_element(
          r.curve.begin(), r.curve.end(), [&](const SqueezeSample& a, const SqueezeSample& b) {
            return std::abs(a.delta - x * D) < std::abs(b.delta - x * D);
          });
      const double dA = it->volume / r.volume0 - 1;
      const double H = r.diameter - it->delta;
      const double predicted =
          (-SqueezeResult::load(*it) * H / (2 * r.volume0) - 0.5 * su.mu * it->mean_shear) /
          su.lambda;
      std::printf(
          "  D/h = %2d, Delta/D = %.3f: P = %9.1f N/m, dA/A = %+.4f %%, <ln J> = %+.4f %%, "
          "identity %+.4f %% (ratio %.3f), pen/h = %.3f\n",
          resolutions[i], it->delta / D, SqueezeResult::load(*it), 100 * dA, 100 * it->mean_ln_j,
          100 * predicted, it->mean_ln_j / predicted, it->penetration / r.h);
      if (i + 1 == runs.size() && x >= 0.2) {
        EXPECT_NEAR(it->mean_ln_j / predicted, 1.0, 0.05) << "Delta/D = " << x;
      }
      if (i + 1 == runs.size() && x == 0.5)
        std::printf("  issue's figure |dA/A| < 1 %% at 50 %% squeeze: %s (|dA/A| = %.3f %%)\n",
                    std::abs(dA) < 0.01 ? "met" : "not met", 100 * std::abs(dA));
    }
  }
}
