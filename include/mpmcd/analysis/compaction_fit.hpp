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
  double kp = 0;  ///< bulk modulus K_p = λ + μ in 2D (plane strain), λ + 2μ/3 in 3D [Pa]
};

/// Moduli of a Neo-Hookean grain from its Lamé coefficients λ, μ [Pa] (paper §4) in `dim` = 2 or
/// 3 dimensions (K_p as materials::Law::bulk_modulus).
GrainModuli grain_moduli(double lambda, double mu, int dim = 2);

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

/// Exponential approach of the solid fraction to Φ_max under the pressure P [Pa] (the compaction
/// law of the isotropic compactions of soft grains, Cantor et al. 2020, Cárdenas-Barrantes et al.
/// 2021, in its exponential form; docs/observables.md): Φ(P) = Φ_max - (Φ_max - Φ_J) exp(-P/P0)
/// [-], Φ_J the solid fraction at jamming (P = 0), P0 > 0 [Pa].
double pressure_law(double pressure, double phi_j, double phi_max, double p0);

/// Result of fitting the pressure law.
struct PressureLawFit {
  double phi_max = 0;        ///< fitted Φ_max [-]
  double p0 = 0;             ///< fitted P0 [Pa]
  double phi_max_error = 0;  ///< standard error of Φ_max from s^2 (J^T J)^-1 [-]
  double p0_error = 0;       ///< standard error of P0 [Pa]
  double rms = 0;            ///< RMS residual of Φ [-]
  std::size_t points = 0;    ///< data points fitted [-]
  /// The data determine the law: the best P0 of the scan is inside it (not at either end: at
  /// the upper end the data are still linear in P, far from Φ_max) and Φ_J < Φ_max <= 1 [-].
  bool determined = false;
};

/// Fits (Φ_max, P0) of pressure_law with Φ_J given to (P, Φ) by least squares: for a fixed P0 the
/// law is linear in Φ_max (closed form), so the sum of squares is minimised over log P0 by a scan
/// (10 values per decade from 1e-4 to 1e3 times the largest P) refined by golden-section search
/// to a relative 1e-10 and polished by Gauss-Newton on (Φ_max, P0). Needs at least 3 points with
/// finite values and some P > 0; throws std::invalid_argument otherwise.
PressureLawFit fit_pressure_law(std::span<const double> pressure, std::span<const double> phi,
                                double phi_j);

}  // namespace mpmcd::analysis
