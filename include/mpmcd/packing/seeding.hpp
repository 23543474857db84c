#pragma once
/// Material points for the grains of a packing, on one lattice aligned with the background grid
/// (docs/packing.md §8).
#include <cstdint>
#include <vector>

#include "mpmcd/core/types.hpp"
#include "mpmcd/packing/packing.hpp"

namespace mpmcd::packing {

/// Points of all grains, grouped by grain: grain g owns points [offset[g], offset[g + 1]).
struct SeededPacking {
  std::vector<Vec<2>> x;            ///< point positions [m]
  std::vector<double> volume;       ///< point areas (volume per unit thickness) [m^2]
  std::vector<std::int64_t> grain;  ///< index of the owning disk in Packing::disks [-]
  std::vector<std::size_t> offset;  ///< size disks + 1; points of grain g: offset[g]..[g + 1]
};

/// Seeds every disk with mpmcd::points::seed_ball<2> (sites origin + (i + 1/2) h / ppc strictly
/// inside the disk). A site inside two disks (DEM overlaps) goes to the disk with the smaller
/// |x - c| / r (ties: lower index); each grain's point areas are then rescaled so that they sum
/// to its disk area pi r^2. `grid_origin` [m], `cell_size` h [m], `points_per_cell` ppc [-].
/// Throws InputError ("points_per_cell") when a disk would get no point, ("dimension") for a 3D
/// packing.
SeededPacking seed_packing(const Packing& packing, const Vec<2>& grid_origin, double cell_size,
                           int points_per_cell);

}  // namespace mpmcd::packing
