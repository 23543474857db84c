#pragma once
/// The compaction law of paper eq. (10), its fit by nonlinear least squares on (c1, c2), and the
/// detection of the jamming solid fraction Φ_J (docs/observables.md, "Analysis").
#include <cstddef>
#include <optional>
#include <span>

namespace mpmcd::analysis {

/// Elastic moduli of the grains entering eq. (10).
struct GrainModuli {
  double mp = 0;  ///< P-wave modulus M_p = λ + 2μ [Pa]
  double kp = 0;  ///< 2D bulk modulus K_p = λ + μ [Pa]
};

/// Moduli of a Neo-Hookean grain from its Lamé coefficients λ, μ [Pa] (paper §4).
GrainModuli grain_moduli(double lambda, double mu);

/// Paper eq. (10): σ/M_p = -Z Φ / (Z + M_p/(c1 K_p)) (ln Φ + c2) [-]; negative in compression
/// (mechanics convention) for Φ > exp(-c2). phi, z [-]; c1 > 0, c2 [-].
double compaction_law(double phi, double z, double c1, double c2, const GrainModuli& moduli);

/// Result of fitting eq. (10).
struct CompactionFit {
  double c1 = 0;           ///< fitted c1 [-]
  double c2 = 0;           ///< fitted c2 [-]
  double c1_error = 0;     ///< standard error of c1 from s^2 (J^T J)^-1 [-]
  double c2_error = 0;     ///< standard error of c2 [-]
  double correlation = 0;  ///< correlation coefficient of (c1, c2) [-]
  double rms = 0;          ///< RMS residual of σ/M_p [-]
  std::size_t points = 0;  ///< data points fitted [-]
  int iterations = 0;      ///< Levenberg-Marquardt iterations [-]
  bool converged = false;  ///< relative step and gradient below tolerance [-]
};

/// Fits (c1, c2) of eq. (10) to y = σ/M_p at (Φ, Z) by Levenberg-Marquardt started from the best
/// point of a scan of log c1 (c2 solved linearly for each c1); needs at least 3 points, Φ in (0,
/// 1], Z > 0, finite data; throws std::invalid_argument otherwise or if no positive c1 fits.
CompactionFit fit_compaction_law(std::span<const double> phi, std::span<const double> z,
                                 std::span<const double> y, const GrainModuli& moduli);

/// How Φ_J is detected.
struct JammingCriterion {
  /// Jammed rows carry a compressive bottom-wall stress -σ/M_p >= this value [-].
  double stress = 1e-4;
  /// Jammed rows also have Z >= this value (0: no condition on Z) [-].
  double min_z = 0.0;
};

/// Index of the first row from which every later row (rows in time order) is jammed per the
/// criterion, i.e. the row after the last unjammed one; Φ_J = phi[index]. nullopt if the last row
/// is not jammed. `z` may be empty when criterion.min_z = 0.
std::optional<std::size_t> detect_jamming(std::span<const double> phi,
                                          std::span<const double> sigma_over_mp,
                                          std::span<const double> z,
                                          const JammingCriterion& criterion = {});

}  // namespace mpmcd::analysis
