#pragma once
/// Warnings for runs driven too fast to mean anything (docs/robustness.md, "Runs driven faster than
/// the grains can follow"): a wall, or a material point, moving faster than a fraction of the
/// grains' elastic wave speed c = sqrt(M/ρ), M = λ + 2μ (materials::Law::wave_modulus).
#include <optional>
#include <string>
#include <vector>

#include "mpmcd/io/config.hpp"
#include "mpmcd/mpm/model.hpp"

namespace mpmcd::app {

/// Fraction of the grains' elastic wave speed c above which a wall's speed is reported [-]: at
/// 0.1 c a grain is crossed by its own compression wave only ten times while a wall moves by its
/// size, so the stresses no longer follow the walls quasi-statically.
inline constexpr double kFastWallFraction = 0.1;

/// Fraction of its material's wave speed c above which a material point's speed is reported [-].
/// Higher than the walls' fraction: in a compaction grains are squeezed sideways and rearrange
/// faster than the wall moves (the quick compaction example, wall at 0.026 c, has points up to
/// 0.11 c; at lambda = 0, wall at 0.036 c, up to 0.13 c).
inline constexpr double kFastPointFraction = 0.5;

/// Elastic (P-)wave speed c = sqrt(M/ρ) of each material of the model [m/s].
template <int Dim>
std::vector<double> wave_speeds(const mpm::Model<Dim>& model);

/// The warning for the walls whose speed |velocity| exceeds kFastWallFraction times the smallest
/// wave speed of the materials the grains are made of (naming each such wall, its speed and that
/// material), or nullopt.
template <int Dim>
std::optional<std::string> fast_wall_warning(const io::Config& config,
                                             const mpm::Model<Dim>& model);

/// The warning for the fastest material point whose speed |v| exceeds kFastPointFraction times the
/// wave speed of its grain's material at time t [s] (naming the point, its grain and the speeds,
/// and how many points are that fast), or nullopt. O(points).
template <int Dim>
std::optional<std::string> fast_point_warning(const io::Config& config,
                                              const mpm::Model<Dim>& model, double t);

extern template std::vector<double> wave_speeds<2>(const mpm::Model<2>&);
extern template std::vector<double> wave_speeds<3>(const mpm::Model<3>&);
extern template std::optional<std::string> fast_wall_warning<2>(const io::Config&,
                                                                const mpm::Model<2>&);
extern template std::optional<std::string> fast_wall_warning<3>(const io::Config&,
                                                                const mpm::Model<3>&);
extern template std::optional<std::string> fast_point_warning<2>(const io::Config&,
                                                                 const mpm::Model<2>&, double);
extern template std::optional<std::string> fast_point_warning<3>(const io::Config&,
                                                                 const mpm::Model<3>&, double);

}  // namespace mpmcd::app
