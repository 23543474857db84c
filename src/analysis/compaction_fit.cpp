#include "mpmcd/analysis/compaction_fit.hpp"

#include <fmt/format.h>

#include <Eigen/Dense>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

namespace mpmcd::analysis {

GrainModuli grain_moduli(double lambda, double mu) {
  return {lambda + 2 * mu, lambda + mu};  // M_p = λ + 2μ, K_p = λ + μ (2D) (paper §4)
}

double compaction_law(double phi, double z, double c1, double c2, const GrainModuli& m) {
  // Paper eq. (10).
  return -z * phi / (z + m.mp / (c1 * m.kp)) * (std::log(phi) + c2);
}

namespace {

struct Data {
  std::span<const double> phi, z, y;
  double r = 0;  // M_p / K_p
};

// Residuals y - f and the Jacobian of f with respect to (c1, c2) (derivatives of eq. (10)).
double evaluate(const Data& d, double c1, double c2, Eigen::VectorXd& res, Eigen::MatrixXd* jac) {
  const auto n = static_cast<Eigen::Index>(d.phi.size());
  res.resize(n);
  if (jac) jac->resize(n, 2);
  double sse = 0;
  for (Eigen::Index i = 0; i < n; ++i) {
    const auto k = static_cast<std::size_t>(i);
    const double zp = d.z[k] * d.phi[k], den = d.z[k] + d.r / c1, lp = std::log(d.phi[k]) + c2;
    const double f = -zp / den * lp;
    res[i] = d.y[k] - f;
    sse += res[i] * res[i];
    if (jac) {
      (*jac)(i, 0) = -zp * lp * d.r / (c1 * c1 * den * den);  // ∂f/∂c1
      (*jac)(i, 1) = -zp / den;                               // ∂f/∂c2
    }
  }
  return sse;
}

// For a fixed c1 eq. (10) is linear in c2: f = A (ln Φ + c2), A = -Z Φ / (Z + M_p/(c1 K_p)).
double best_c2(const Data& d, double c1) {
  double num = 0, den = 0;
  for (std::size_t i = 0; i < d.phi.size(); ++i) {
    const double a = -d.z[i] * d.phi[i] / (d.z[i] + d.r / c1);
    num += a * (d.y[i] - a * std::log(d.phi[i]));
    den += a * a;
  }
  return den > 0 ? num / den : 0.0;
}

}  // namespace

CompactionFit fit_compaction_law(std::span<const double> phi, std::span<const double> z,
                                 std::span<const double> y, const GrainModuli& moduli) {
  if (phi.size() != z.size() || phi.size() != y.size())
    throw std::invalid_argument("fit_compaction_law: phi, Z and sigma/M_p differ in length");
  if (phi.size() < 3)
    throw std::invalid_argument(
        fmt::format("fit_compaction_law: {} data points, at least 3 needed", phi.size()));
  if (!(moduli.mp > 0) || !(moduli.kp > 0))
    throw std::invalid_argument("fit_compaction_law: M_p and K_p must be positive");
  for (std::size_t i = 0; i < phi.size(); ++i)
    if (!(phi[i] > 0) || !std::isfinite(phi[i]) || !(z[i] >= 0) || !std::isfinite(z[i]) ||
        !std::isfinite(y[i]))
      throw std::invalid_argument(
          fmt::format("fit_compaction_law: bad data point {} (phi {}, Z {}, sigma/M_p {})", i,
                      phi[i], z[i], y[i]));
  const Data d{phi, z, y, moduli.mp / moduli.kp};
  Eigen::VectorXd res;
  Eigen::MatrixXd jac;

  // Start: scan log10 c1 over [-6, 4], c2 solved linearly for each.
  double c1 = 1, c2 = 0, sse = std::numeric_limits<double>::infinity();
  for (int k = 0; k <= 400; ++k) {
    const double c1k = std::pow(10.0, -6.0 + 10.0 * k / 400.0), c2k = best_c2(d, c1k);
    const double s = evaluate(d, c1k, c2k, res, nullptr);
    if (s < sse) {
      sse = s;
      c1 = c1k;
      c2 = c2k;
    }
  }

  // Levenberg-Marquardt (Marquardt's diagonal scaling), c1 kept positive.
  CompactionFit fit;
  double damping = 1e-3;
  sse = evaluate(d, c1, c2, res, &jac);
  for (int it = 0; it < 500; ++it) {
    fit.iterations = it + 1;
    const Eigen::Matrix2d jtj = jac.transpose() * jac;
    const Eigen::Vector2d g = jac.transpose() * res;
    if (g.cwiseAbs().maxCoeff() <=
        1e-15 * std::max(1e-300, std::sqrt(jtj.diagonal().maxCoeff() * sse))) {
      fit.converged = true;
      break;
    }
    bool accepted = false;
    for (int tries = 0; tries < 60 && !accepted; ++tries) {
      Eigen::Matrix2d a = jtj;
      a.diagonal() += damping * jtj.diagonal().cwiseMax(1e-300);
      const Eigen::Vector2d step = a.ldlt().solve(g);
      const double c1n = c1 + step[0], c2n = c2 + step[1];
      Eigen::VectorXd rn;
      const double sn =
          c1n > 0 ? evaluate(d, c1n, c2n, rn, nullptr) : std::numeric_limits<double>::infinity();
      if (sn <= sse) {
        const bool small = std::fabs(step[0]) <= 1e-12 * c1 &&
                           std::fabs(step[1]) <= 1e-12 * (std::fabs(c2) + 1e-12);
        c1 = c1n;
        c2 = c2n;
        const bool stalled = sse - sn <= 1e-15 * sse;
        sse = evaluate(d, c1, c2, res, &jac);
        damping = std::max(damping / 3, 1e-12);
        accepted = true;
        if (small || stalled) fit.converged = true;
      } else {
        damping *= 4;
      }
    }
    if (!accepted) {  // no decrease possible: at a minimum to round-off
      fit.converged = true;
      break;
    }
    if (fit.converged) break;
  }

  // Covariance s^2 (J^T J)^-1 with s^2 = SSE / (n - 2).
  const auto n = static_cast<double>(phi.size());
  const Eigen::Matrix2d jtj = jac.transpose() * jac;
  const double det = jtj(0, 0) * jtj(1, 1) - jtj(0, 1) * jtj(1, 0);
  if (!(std::fabs(det) > 1e-14 * jtj(0, 0) * jtj(1, 1)))
    throw std::invalid_argument(
        "fit_compaction_law: c1 and c2 cannot both be identified from "
        "these data (singular normal matrix)");
  Eigen::Matrix2d inv;
  inv << jtj(1, 1), -jtj(0, 1), -jtj(1, 0), jtj(0, 0);
  const double s2 = sse / (n - 2);
  const Eigen::Matrix2d cov = s2 / det * inv;
  fit.c1 = c1;
  fit.c2 = c2;
  fit.c1_error = std::sqrt(std::max(0.0, cov(0, 0)));
  fit.c2_error = std::sqrt(std::max(0.0, cov(1, 1)));
  fit.correlation =
      fit.c1_error > 0 && fit.c2_error > 0 ? cov(0, 1) / (fit.c1_error * fit.c2_error) : 0.0;
  fit.rms = std::sqrt(sse / n);
  fit.points = phi.size();
  return fit;
}

std::optional<std::size_t> detect_jamming(std::span<const double> phi,
                                          std::span<const double> sigma_over_mp,
                                          std::span<const double> z,
                                          const JammingCriterion& criterion) {
  const std::size_t n = std::min(phi.size(), sigma_over_mp.size());
  auto jammed = [&](std::size_t i) {
    if (!(-sigma_over_mp[i] >= criterion.stress)) return false;
    if (criterion.min_z > 0 && (i >= z.size() || !(z[i] >= criterion.min_z))) return false;
    return true;
  };
  std::size_t first = n;
  while (first > 0 && jammed(first - 1)) --first;
  if (first == n) return std::nullopt;
  return first;
}

}  // namespace mpmcd::analysis
