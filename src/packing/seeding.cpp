// Seeding the grains of a packing with material points (docs/packing.md §8).
#include "mpmcd/packing/seeding.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <tuple>

#include "mpmcd/core/errors.hpp"
#include "mpmcd/points/seeding.hpp"

namespace mpmcd::packing {

namespace {
// Largest number of points seed_packing creates [-].
constexpr double kMaxPoints = 2e8;
}  // namespace

SeededPacking seed_packing(const Packing& packing, const Vec<2>& grid_origin, double cell_size,
                           int points_per_cell) {
  if (packing.dimension != 2)
    throw InputError("", 0, "dimension",
                     fmt::format("a 2D packing (disks) to seed 2D grains, got a {}D packing",
                                 packing.dimension));
  if (!std::isfinite(cell_size) || cell_size <= 0.0)
    throw InputError("", 0, "cell_size", fmt::format("a finite number > 0 [m], got {}", cell_size));
  if (points_per_cell < 1 || points_per_cell > 64)
    throw InputError("", 0, "points_per_cell",
                     fmt::format("an integer in [1, 64], got {}", points_per_cell));
  if (!grid_origin.allFinite()) throw InputError("", 0, "origin", "two finite numbers [m]");
  const double s = points::lattice_spacing(cell_size, points_per_cell);
  double estimate = 0.0;
  for (const auto& d : packing.disks) estimate += std::numbers::pi * d.radius * d.radius / (s * s);
  if (estimate > kMaxPoints)
    throw InputError("", 0, "points_per_cell",
                     fmt::format("at most {:.0e} material points; cell size {} m with {} points "
                                 "per cell would give about {:.3g}",
                                 kMaxPoints, cell_size, points_per_cell, estimate));

  // Every candidate site: lattice index (ix, iy), owner grain, score |x - c| / r (§8, eq. 12).
  struct Site {
    std::int64_t ix, iy;
    double score;
    std::int64_t grain;
    Vec<2> x;
  };
  std::vector<Site> sites;
  sites.reserve(static_cast<std::size_t>(estimate * 1.1) + packing.disks.size());
  for (std::size_t g = 0; g < packing.disks.size(); ++g) {
    const auto& d = packing.disks[g];
    const Vec<2> c(d.x, d.y);
    const auto seeds = points::seed_ball<2>(grid_origin, cell_size, points_per_cell, c, d.radius);
    if (seeds.x.empty())
      throw InputError("", 0, "points_per_cell",
                       fmt::format("at least one material point per grain: disk id {} (radius "
                                   "{:.6g} m) holds no lattice site of spacing {:.6g} m",
                                   d.id, d.radius, s));
    for (const auto& x : seeds.x)
      sites.push_back({std::llround((x[0] - grid_origin[0]) / s - 0.5),
                       std::llround((x[1] - grid_origin[1]) / s - 0.5), (x - c).norm() / d.radius,
                       static_cast<std::int64_t>(g), x});
  }
  // A site claimed by several disks goes to the smallest score, then the lowest grain index.
  std::vector<std::size_t> order(sites.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return std::tie(sites[a].ix, sites[a].iy, sites[a].score, sites[a].grain) <
           std::tie(sites[b].ix, sites[b].iy, sites[b].score, sites[b].grain);
  });
  std::vector<char> keep(sites.size(), 0);
  for (std::size_t k = 0; k < order.size(); ++k) {
    const auto& a = sites[order[k]];
    keep[order[k]] = k == 0 || a.ix != sites[order[k - 1]].ix || a.iy != sites[order[k - 1]].iy;
  }
  // Sites are still grouped by grain (grain-major order); areas rescaled per grain (eq. 13).
  SeededPacking out;
  out.offset.assign(packing.disks.size() + 1, 0);
  for (std::size_t i = 0; i < sites.size(); ++i)
    if (keep[i]) {
      out.x.push_back(sites[i].x);
      out.grain.push_back(sites[i].grain);
      ++out.offset[static_cast<std::size_t>(sites[i].grain) + 1];
    }
  for (std::size_t g = 0; g < packing.disks.size(); ++g) out.offset[g + 1] += out.offset[g];
  out.volume.resize(out.x.size());
  for (std::size_t g = 0; g < packing.disks.size(); ++g) {
    const std::size_t count = out.offset[g + 1] - out.offset[g];
    const auto& d = packing.disks[g];
    if (count == 0)
      throw InputError("", 0, "points_per_cell",
                       fmt::format("at least one material point per grain: every site of disk "
                                   "id {} lies deeper in its neighbours",
                                   d.id));
    const double v = points::ball_measure<2>(d.radius) / static_cast<double>(count);
    std::fill(out.volume.begin() + static_cast<std::ptrdiff_t>(out.offset[g]),
              out.volume.begin() + static_cast<std::ptrdiff_t>(out.offset[g + 1]), v);
  }
  return out;
}

}  // namespace mpmcd::packing
