// Seeding the grains of a packing with material points (docs/packing.md §8).
#include "mpmcd/packing/seeding.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <tuple>

#include "mpmcd/core/errors.hpp"
#include "mpmcd/points/seeding.hpp"

namespace mpmcd::packing {

namespace {
// Largest number of points seed_packing creates [-].
constexpr double kMaxPoints = 2e8;

// Center of a disk (2D) or sphere (3D) [m].
template <int Dim>
Vec<Dim> center_of(const Disk& d) {
  if constexpr (Dim == 2)
    return Vec<2>(d.x, d.y);
  else
    return Vec<3>(d.x, d.y, d.z);
}
}  // namespace

template <int Dim>
SeededPacking<Dim> seed_packing(const Packing& packing, const Vec<Dim>& grid_origin,
                                double cell_size, int points_per_cell) {
  if (packing.dimension != Dim)
    throw InputError("", 0, "dimension",
                     fmt::format("a {}D packing ({}) to seed {}D grains, got a {}D packing", Dim,
                                 Dim == 2 ? "disks" : "spheres", Dim, packing.dimension));
  if (!std::isfinite(cell_size) || cell_size <= 0.0)
    throw InputError("", 0, "cell_size", fmt::format("a finite number > 0 [m], got {}", cell_size));
  if (points_per_cell < 1 || points_per_cell > 64)
    throw InputError("", 0, "points_per_cell",
                     fmt::format("an integer in [1, 64], got {}", points_per_cell));
  if (!grid_origin.allFinite())
    throw InputError("", 0, "origin", fmt::format("{} finite numbers [m]", Dim));
  constexpr const char* kNoun = Dim == 2 ? "disk" : "sphere";
  const double s = points::lattice_spacing(cell_size, points_per_cell);
  double estimate = 0.0;
  for (const auto& d : packing.disks)
    estimate += points::ball_measure<Dim>(d.radius) / std::pow(s, Dim);
  if (estimate > kMaxPoints)
    throw InputError("", 0, "points_per_cell",
                     fmt::format("at most {:.0e} material points; cell size {} m with {} points "
                                 "per cell would give about {:.3g}",
                                 kMaxPoints, cell_size, points_per_cell, estimate));

  // Every candidate site: lattice index (ix, iy, iz; iz = 0 in 2D), owner grain, score
  // |x - c| / r (§8, eq. 12).
  struct Site {
    std::array<std::int64_t, 3> index;
    double score;
    std::int64_t grain;
    Vec<Dim> x;
  };
  std::vector<Site> sites;
  sites.reserve(static_cast<std::size_t>(estimate * 1.1) + packing.disks.size());
  for (std::size_t g = 0; g < packing.disks.size(); ++g) {
    const auto& d = packing.disks[g];
    const Vec<Dim> c = center_of<Dim>(d);
    const auto seeds = points::seed_ball<Dim>(grid_origin, cell_size, points_per_cell, c, d.radius);
    if (seeds.x.empty())
      throw InputError("", 0, "points_per_cell",
                       fmt::format("at least one material point per grain: {} id {} (radius "
                                   "{:.6g} m) holds no lattice site of spacing {:.6g} m",
                                   kNoun, d.id, d.radius, s));
    for (const auto& x : seeds.x) {
      std::array<std::int64_t, 3> index{0, 0, 0};
      for (int a = 0; a < Dim; ++a) index[a] = std::llround((x[a] - grid_origin[a]) / s - 0.5);
      sites.push_back({index, (x - c).norm() / d.radius, static_cast<std::int64_t>(g), x});
    }
  }
  // A site claimed by several disks goes to the smallest score, then the lowest grain index.
  std::vector<std::size_t> order(sites.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return std::tie(sites[a].index, sites[a].score, sites[a].grain) <
           std::tie(sites[b].index, sites[b].score, sites[b].grain);
  });
  std::vector<char> keep(sites.size(), 0);
  for (std::size_t k = 0; k < order.size(); ++k) {
    const auto& a = sites[order[k]];
    keep[order[k]] = k == 0 || a.index != sites[order[k - 1]].index;
  }
  // Sites are still grouped by grain (grain-major order); volumes rescaled per grain (eq. 13).
  SeededPacking<Dim> out;
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
                       fmt::format("at least one material point per grain: every site of {} "
                                   "id {} lies deeper in its neighbours",
                                   kNoun, d.id));
    const double v = points::ball_measure<Dim>(d.radius) / static_cast<double>(count);
    std::fill(out.volume.begin() + static_cast<std::ptrdiff_t>(out.offset[g]),
              out.volume.begin() + static_cast<std::ptrdiff_t>(out.offset[g + 1]), v);
  }
  return out;
}

template SeededPacking<2> seed_packing<2>(const Packing&, const Vec<2>&, double, int);
template SeededPacking<3> seed_packing<3>(const Packing&, const Vec<3>&, double, int);

}  // namespace mpmcd::packing
