#include "mpmcd/analysis/compaction_fit.hpp"

#include <fmt/format.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <utility>
#include <vector>

namespace mpmcd::analysis {

GrainModuli grain_moduli(double lambda, double mu, int dim) {
  if (dim == 3) return {lambda + 2 * mu, lambda + 2 * mu / 3};  // K_p = λ + 2μ/3 in 3D
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

double pressure_law(double pressure, double phi_j, double phi_max, double p0) {
  return phi_max - (phi_max - phi_j) * std::exp(-pressure / p0);  // exponential approach
}

namespace {

// Best Φ_max for a fixed P0 (Φ - Φ_J e = Φ_max (1 - e), e = exp(-P/P0): linear least squares)
// and the sum of squared residuals of Φ.
std::pair<double, double> pressure_law_at(std::span<const double> p, std::span<const double> phi,
                                          double phi_j, double p0) {
  double num = 0, den = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    const double e = std::exp(-p[i] / p0);
    num += (phi[i] - phi_j * e) * (1 - e);
    den += (1 - e) * (1 - e);
  }
  const double phi_max = den > 0 ? num / den : phi_j;
  double sse = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    const double r = phi[i] - pressure_law(p[i], phi_j, phi_max, p0);
    sse += r * r;
  }
  return {phi_max, sse};
}

}  // namespace

PressureLawFit fit_pressure_law(std::span<const double> p, std::span<const double> phi,
                                double phi_j) {
  if (p.size() != phi.size() || p.size() < 3)
    throw std::invalid_argument("the pressure law needs at least 3 (P, Phi) points");
  double p_max = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    if (!std::isfinite(p[i]) || !std::isfinite(phi[i]))
      throw std::invalid_argument("non-finite (P, Phi) point");
    p_max = std::max(p_max, p[i]);
  }
  if (!(p_max > 0) || !std::isfinite(phi_j))
    throw std::invalid_argument("the pressure law needs some P > 0 and a finite Phi_J");
  // Scan of log10 P0 over [log10 P_max - 4, log10 P_max + 3], 10 values per decade.
  const double lo = std::log10(p_max) - 4;
  constexpr int kScan = 71;
  const auto sse_at = [&](double log_p0) {
    return pressure_law_at(p, phi, phi_j, std::pow(10.0, log_p0)).second;
  };
  int best = 0;
  double best_sse = std::numeric_limits<double>::infinity();
  for (int k = 0; k < kScan; ++k) {
    const double s = sse_at(lo + 0.1 * k);
    if (s < best_sse) {
      best_sse = s;
      best = k;
    }
  }
  // Golden-section search on the bracket of the best scan value.
  double a = lo + 0.1 * std::max(best - 1, 0), b = lo + 0.1 * std::min(best + 1, kScan - 1);
  const double g = (std::sqrt(5.0) - 1) / 2;
  double c = b - g * (b - a), d = a + g * (b - a), fc = sse_at(c), fd = sse_at(d);
  while (b - a > 1e-10 * std::max(1.0, std::fabs(a))) {
    if (fc < fd) {
      b = d;
      d = c;
      fd = fc;
      c = b - g * (b - a);
      fc = sse_at(c);
    } else {
      a = c;
      c = d;
      fc = fd;
      d = a + g * (b - a);
      fd = sse_at(d);
    }
  }
  PressureLawFit fit;
  fit.p0 = std::pow(10.0, 0.5 * (a + b));
  auto [phi_max, sse] = pressure_law_at(p, phi, phi_j, fit.p0);
  // J^T J and J^T r at (Φ_max, P0), J_i = (dΦ/dΦ_max, dΦ/dP0) = (1 - e, -(Φ_max - Φ_J) e P/P0²).
  Eigen::Matrix2d jtj;
  Eigen::Vector2d jtr;
  const auto normal_equations = [&](double pm, double q) {
    jtj.setZero();
    jtr.setZero();
    for (std::size_t i = 0; i < p.size(); ++i) {
      const double e = std::exp(-p[i] / q);
      const Eigen::Vector2d j(1 - e, -(pm - phi_j) * e * p[i] / (q * q));
      jtj += j * j.transpose();
      jtr += j * (phi[i] - pressure_law(p[i], phi_j, pm, q));
    }
  };
  // Gauss-Newton polish from the search's point (a function-value search locates a minimum to
  // about sqrt(machine epsilon) only): steps kept while the sum of squares decreases.
  for (int it = 0; it < 50; ++it) {
    normal_equations(phi_max, fit.p0);
    if (!(std::fabs(jtj.determinant()) > 0)) break;
    const Eigen::Vector2d step = jtj.ldlt().solve(jtr);
    const double pm = phi_max + step[0], q = fit.p0 + step[1];
    if (!(q > 0)) break;
    double trial = 0;
    for (std::size_t i = 0; i < p.size(); ++i) {
      const double r = phi[i] - pressure_law(p[i], phi_j, pm, q);
      trial += r * r;
    }
    if (!(trial < sse)) break;
    phi_max = pm;
    fit.p0 = q;
    sse = trial;
  }
  fit.phi_max = phi_max;
  fit.points = p.size();
  fit.determined = best > 0 && best < kScan - 1 && phi_max > phi_j && phi_max <= 1.0;
  fit.rms = std::sqrt(sse / static_cast<double>(p.size()));
  // Covariance s^2 (J^T J)^-1.
  normal_equations(phi_max, fit.p0);
  const double s2 = p.size() > 2 ? sse / static_cast<double>(p.size() - 2) : 0.0;
  if (std::fabs(jtj.determinant()) > 0) {
    const Eigen::Matrix2d cov = s2 * jtj.inverse();
    fit.phi_max_error = std::sqrt(std::max(cov(0, 0), 0.0));
    fit.p0_error = std::sqrt(std::max(cov(1, 1), 0.0));
  }
  return fit;
}

}  // namespace mpmcd::analysis
