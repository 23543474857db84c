#include "mpmcd/app/speed_check.hpp"

#include <fmt/format.h>

#include <cmath>
#include <limits>

namespace mpmcd::app {

namespace {

std::string material_name(const io::Config& config, std::size_t k) {
  return k < config.materials.size() ? config.materials[k].name : fmt::format("{}", k);
}

}  // namespace

template <int Dim>
std::vector<double> wave_speeds(const mpm::Model<Dim>& model) {
  std::vector<double> c(model.laws.size(), 0.0);
  for (std::size_t k = 0; k < c.size(); ++k)
    c[k] = std::sqrt(model.laws[k]->wave_modulus() / model.densities[k]);
  return c;
}

template <int Dim>
std::optional<std::string> fast_wall_warning(const io::Config& config,
                                             const mpm::Model<Dim>& model) {
  const auto c = wave_speeds(model);
  // The slowest material any grain is made of.
  double c_min = std::numeric_limits<double>::infinity();
  std::size_t slowest = 0;
  for (const auto& g : model.grains)
    if (c[g.material] < c_min) {
      c_min = c[g.material];
      slowest = static_cast<std::size_t>(g.material);
    }
  if (!std::isfinite(c_min)) return std::nullopt;
  std::string walls;
  int fast = 0;
  for (const auto& w : config.walls) {
    const double speed =
        Dim == 2 ? std::hypot(w.velocity.at(0), w.velocity.at(1))
                 : std::hypot(w.velocity.at(0), w.velocity.at(1), w.velocity.at(Dim - 1));
    if (!(speed > kFastWallFraction * c_min)) continue;
    if (++fast <= 3)
      walls += fmt::format("{}'{}' at {:.3g} m/s ({:.3g} c)", fast > 1 ? ", " : "", w.name, speed,
                           speed / c_min);
  }
  if (fast == 0) return std::nullopt;
  if (fast > 3) walls += fmt::format(" and {} more", fast - 3);
  return fmt::format(
      "{} {} {} faster than {} of the grains' elastic wave speed c = sqrt((lambda + 2 mu)/rho) = "
      "{:.4g} m/s (material '{}'): the grains cannot follow quasi-statically, so Phi, the wall "
      "stresses and Z describe an impact, not a compaction (lower the wall speed)",
      fast == 1 ? "wall" : "walls", walls, fast == 1 ? "moves" : "move", kFastWallFraction, c_min,
      material_name(config, slowest));
}

template <int Dim>
std::optional<std::string> fast_point_warning(const io::Config& config,
                                              const mpm::Model<Dim>& model, double t) {
  const auto c = wave_speeds(model);
  const auto& p = model.points;
  std::size_t fastest = 0, count = 0;
  double worst = 0;  // largest |v| / c
  for (const auto& g : model.grains) {
    const double limit = kFastPointFraction * c[g.material];
    for (std::int64_t i = g.begin; i < g.end; ++i) {
      const double speed = p.v[i].norm();
      if (!(speed > limit)) continue;
      ++count;
      if (speed / c[g.material] > worst) {
        worst = speed / c[g.material];
        fastest = static_cast<std::size_t>(i);
      }
    }
  }
  if (count == 0) return std::nullopt;
  const auto& g = model.grains[p.grain[fastest]];
  return fmt::format(
      "at t = {:.6g} s material point {} of grain {} moves at {:.4g} m/s = {:.3g} of the elastic "
      "wave speed c = sqrt((lambda + 2 mu)/rho) = {:.4g} m/s of its material '{}' ({} point(s) "
      "faster than {} c): inertia dominates, the response is not quasi-static (reported once per "
      "run)",
      t, fastest, p.grain[fastest], p.v[fastest].norm(), worst, c[g.material],
      material_name(config, static_cast<std::size_t>(g.material)), count, kFastPointFraction);
}

#define MPMCD_SPEED_CHECK(Dim)                                                        \
  template std::vector<double> wave_speeds<Dim>(const mpm::Model<Dim>&);              \
  template std::optional<std::string> fast_wall_warning<Dim>(const io::Config&,       \
                                                             const mpm::Model<Dim>&); \
  template std::optional<std::string> fast_point_warning<Dim>(const io::Config&,      \
                                                              const mpm::Model<Dim>&, double);
MPMCD_SPEED_CHECK(2)
MPMCD_SPEED_CHECK(3)
#undef MPMCD_SPEED_CHECK

}  // namespace mpmcd::app
