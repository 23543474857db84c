#pragma once
/// Material points for the grains of a packing, on one lattice aligned with the background grid
/// (docs/packing.md §8).
#include <cstdint>
#include <vector>

#include "mpmcd/core/types.hpp"
#include "mpmcd/packing/packing.hpp"

namespace mpmcd::packing {

/// Points of all grains, grouped by grain: grain g owns points [offset[g], offset[g + 1]).
template <int Dim>
struct SeededPacking {
  std::vector<Vec<Dim>> x;     ///< point positions [m]
  std::vector<double> volume;  ///< point volumes (2D: areas, volume per unit thickness) [m^Dim]
  std::vector<std::int64_t> grain;  ///< index of the owning disk in Packing::disks [-]
  std::vector<std::size_t> offset;  ///< size disks + 1; points of grain g: offset[g]..[g + 1]
};

/// Seeds every disk (sphere) with mpmcd::points::seed_ball<Dim> (sites origin + (i + 1/2) h / ppc
/// strictly inside it). A site inside two of them (DEM overlaps) goes to the one with the smaller
/// |x - c| / r (ties: lower index); each grain's point volumes are then rescaled so that they sum
/// to its exact measure, pi r^2 or 4/3 pi r^3 (docs/packing.md §8, eq. 12-13). `grid_origin` [m],
/// `cell_size` h [m], `points_per_cell` ppc [-]. Throws InputError ("points_per_cell") when a
/// grain would get no point, ("dimension") when the packing's dimension is not Dim.
template <int Dim>
SeededPacking<Dim> seed_packing(const Packing& packing, const Vec<Dim>& grid_origin,
                                double cell_size, int points_per_cell);

}  // namespace mpmcd::packing
