// The fit of paper eq. (10) recovers (c1, c2) from synthetic data generated with eq. (10), without
// and with noise (the standard errors then cover the truth), and Φ_J detection on synthetic runs.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <stdexcept>
#include <vector>

#include "mpmcd/analysis/compaction_fit.hpp"

using namespace mpmcd::analysis;

namespace {

struct Synthetic {
  std::vector<double> phi, z, y;
};

// Eq. (10) on Φ in [0.8, 0.97] with Z rising from 3.6 to 5, plus Gaussian noise of standard
// deviation `noise` times the largest |σ/M_p| (the same at every point, as the least-squares
// standard errors assume).
Synthetic synthetic(double c1, double c2, const GrainModuli& m, double noise, unsigned seed,
                    int n = 60) {
  Synthetic s;
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> gauss(0.0, 1.0);
  for (int i = 0; i < n; ++i) {
    s.phi.push_back(0.80 + 0.17 * i / (n - 1));
    s.z.push_back(3.6 + 1.4 * i / (n - 1));
    s.y.push_back(compaction_law(s.phi.back(), s.z.back(), c1, c2, m));
  }
  const double scale = std::fabs(s.y.back());
  for (auto& y : s.y) y += noise * scale * gauss(rng);
  return s;
}

struct Case {
  double lambda, c1;
};
// The paper's three materials (μ = 1.5 MPa) and their c1; c2 = 0.27.
const Case kPaper[] = {{100e6, 0.01}, {3e6, 0.23}, {0.0, 1.3}};
constexpr double kMu = 1.5e6, kC2 = 0.27;

}  // namespace

TEST(CompactionLaw, Eq10ValuesAndSign) {
  const GrainModuli m = grain_moduli(3e6, 1.5e6);
  const GrainModuli m3 = grain_moduli(3e6, 1.5e6, 3);  // 3D: K_p = λ + 2μ/3
  EXPECT_DOUBLE_EQ(m3.mp, 6e6);
  EXPECT_DOUBLE_EQ(m3.kp, 4e6);
  EXPECT_DOUBLE_EQ(m.mp, 6e6);
  EXPECT_DOUBLE_EQ(m.kp, 4.5e6);
  // -Z Φ / (Z + M/(c1 K)) (ln Φ + c2) by hand: Z = 4, Φ = 0.9, c1 = 0.23, c2 = 0.27.
  const double expect = -4 * 0.9 / (4 + 6.0 / (0.23 * 4.5)) * (std::log(0.9) + 0.27);
  EXPECT_DOUBLE_EQ(compaction_law(0.9, 4, 0.23, 0.27, m), expect);
  EXPECT_LT(expect, 0.0);                                                      // compression
  EXPECT_NEAR(compaction_law(std::exp(-0.27), 4, 0.23, 0.27, m), 0.0, 1e-16);  // σ = 0 at e^-c2
}

TEST(CompactionFit, RecoversC1C2WithoutNoise) {
  for (const auto& pc : kPaper) {
    const GrainModuli m = grain_moduli(pc.lambda, kMu);
    const auto s = synthetic(pc.c1, kC2, m, 0.0, 1);
    const auto fit = fit_compaction_law(s.phi, s.z, s.y, m);
    EXPECT_TRUE(fit.converged);
    EXPECT_NEAR(fit.c1, pc.c1, 1e-6 * pc.c1) << "lambda " << pc.lambda;
    EXPECT_NEAR(fit.c2, kC2, 1e-6 * kC2) << "lambda " << pc.lambda;
    EXPECT_LT(fit.rms, 1e-12);
    EXPECT_EQ(fit.points, s.phi.size());
  }
}

TEST(CompactionFit, WithinOnePercentWithNoiseAndErrorsCoverTheTruth) {
  // Noise of 0.1 % of the largest stress: the fit is within 1 % and within 3 standard errors of
  // the truth, and one standard error covers the truth about as often as it should (68 %).
  for (const auto& pc : kPaper) {
    const GrainModuli m = grain_moduli(pc.lambda, kMu);
    int covered = 0;
    double worst1 = 0, worst2 = 0;
    for (unsigned seed = 1; seed <= 20; ++seed) {
      const auto s = synthetic(pc.c1, kC2, m, 1e-3, seed);
      const auto fit = fit_compaction_law(s.phi, s.z, s.y, m);
      EXPECT_TRUE(fit.converged);
      EXPECT_NEAR(fit.c1, pc.c1, 0.01 * pc.c1) << "lambda " << pc.lambda << " seed " << seed;
      EXPECT_NEAR(fit.c2, kC2, 0.01 * kC2) << "lambda " << pc.lambda << " seed " << seed;
      EXPECT_GT(fit.c1_error, 0.0);
      EXPECT_GT(fit.c2_error, 0.0);
      EXPECT_LT(std::fabs(fit.c1 - pc.c1), 3 * fit.c1_error);
      EXPECT_LT(std::fabs(fit.c2 - kC2), 3 * fit.c2_error);
      worst1 = std::max(worst1, std::fabs(fit.c1 / pc.c1 - 1));
      worst2 = std::max(worst2, std::fabs(fit.c2 / kC2 - 1));
      if (std::fabs(fit.c1 - pc.c1) <= fit.c1_error) ++covered;
      if (std::fabs(fit.c2 - kC2) <= fit.c2_error) ++covered;
    }
    EXPECT_GE(covered, 20) << "lambda " << pc.lambda;  // of 40; 27 expected
    EXPECT_LE(covered, 36) << "lambda " << pc.lambda;  // errors not grossly overestimated
    std::printf(
        "lambda = %g MPa: worst relative error c1 %.2e, c2 %.2e; one standard error "
        "covers the truth in %d of 40 cases\n",
        pc.lambda / 1e6, worst1, worst2, covered);
  }
}

TEST(CompactionFit, RefusesTooFewOrBadPoints) {
  const GrainModuli m = grain_moduli(3e6, kMu);
  const std::vector<double> two = {0.85, 0.9};
  EXPECT_THROW(fit_compaction_law(two, two, two, m), std::invalid_argument);
  const std::vector<double> phi = {0.85, 0.9, -1}, z = {4, 4, 4}, y = {-1e-3, -2e-3, -3e-3};
  EXPECT_THROW(fit_compaction_law(phi, z, y, m), std::invalid_argument);
}

TEST(Jamming, DetectedAfterTheLastUnjammedRow) {
  // Before jamming: zero stress with two dynamic spikes (one above the threshold); from Φ = 0.81
  // on a growing compressive stress.
  std::vector<double> phi, y, z;
  for (int i = 0; i <= 40; ++i) {
    const double p = 0.78 + 0.005 * i;
    phi.push_back(p);
    double s = p >= 0.81 - 1e-12 ? -0.05 * (p - 0.80) : 0.0;
    if (i == 2) s = -5e-3;  // a grain hitting the moving wall: not persistent
    if (i == 3) s = -5e-5;
    y.push_back(s);
    z.push_back(p >= 0.81 - 1e-12 ? 4.0 : 1.0);
  }
  const auto j = detect_jamming(phi, y, z, {1e-4, 0.0});
  ASSERT_TRUE(j.has_value());
  EXPECT_NEAR(phi[*j], 0.81, 1e-12);
  // A criterion on Z as well gives the same row here; a higher Z threshold finds none.
  EXPECT_EQ(detect_jamming(phi, y, z, {1e-4, 3.5}), j);
  EXPECT_FALSE(detect_jamming(phi, y, z, {1e-4, 4.5}).has_value());
  // An unjammed last row: nothing detected.
  y.back() = 0.0;
  EXPECT_FALSE(detect_jamming(phi, y, z).has_value());
}

// The pressure law Φ(P) = Φ_max - (Φ_max - Φ_J) exp(-P/P0) fitted with Φ_J given: exact data
// come back to round-off; data with Gaussian noise of 1e-4 in Φ stay within 3 standard errors.
TEST(PressureLaw, RecoversPhiMaxAndP0) {
  const double phi_j = 0.80, phi_max = 0.985, p0 = 2.0e5;
  std::vector<double> p, phi;
  for (int i = 1; i <= 40; ++i) {
    p.push_back(1e6 * i / 40.0);
    phi.push_back(pressure_law(p.back(), phi_j, phi_max, p0));
  }
  EXPECT_DOUBLE_EQ(pressure_law(0.0, phi_j, phi_max, p0), phi_j);
  const auto exact = fit_pressure_law(p, phi, phi_j);
  EXPECT_NEAR(exact.phi_max, phi_max, 1e-9);
  EXPECT_NEAR(exact.p0 / p0, 1.0, 1e-7);
  EXPECT_LT(exact.rms, 1e-12);
  EXPECT_TRUE(exact.determined);
  // Data still linear in P (P0 far beyond the pressures): Φ_max is not determined.
  std::vector<double> linear;
  for (double v : p) linear.push_back(phi_j + 1e-8 * v);
  EXPECT_FALSE(fit_pressure_law(p, linear, phi_j).determined);
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0.0, 1e-4);
  std::vector<double> noisy = phi;
  for (double& v : noisy) v += noise(rng);
  const auto fit = fit_pressure_law(p, noisy, phi_j);
  std::printf("  noisy: Phi_max %.6f +/- %.1e, P0 %.4g +/- %.2g Pa\n", fit.phi_max,
              fit.phi_max_error, fit.p0, fit.p0_error);
  EXPECT_LT(std::fabs(fit.phi_max - phi_max), 3 * fit.phi_max_error);
  EXPECT_LT(std::fabs(fit.p0 - p0), 3 * fit.p0_error);
  EXPECT_THROW(fit_pressure_law(std::vector<double>{1.0, 2.0}, std::vector<double>{0.8, 0.9}, 0.8),
               std::invalid_argument);
}
