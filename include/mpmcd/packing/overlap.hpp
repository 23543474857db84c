#pragma once
/// Overlap check of grain outlines at input (docs/robustness.md, "Overlapping grains"): two grains
/// may touch but not overlap, or their common area is counted twice in volume and Phi.
#include <cstddef>
#include <optional>
#include <vector>

#include "mpmcd/packing/packing.hpp"

namespace mpmcd::packing {

/// Largest overlap two grains may have at input, as a fraction of the smaller one's size (its
/// diameter, or a rectangle's shorter side) [-]: touching grains and relaxed DEM packings
/// (overlaps below 2e-4 of a diameter) pass, overlapping ones are refused.
inline constexpr double kOverlapTolerance = 1e-3;

/// A grain outline: a disk (radius > 0, centre (x0, y0)) or an axis-aligned rectangle (radius 0,
/// [x0, x1] x [y0, y1]) [m].
struct Outline {
  double x0 = 0.0;      ///< disk centre abscissa, or rectangle left side [m]
  double y0 = 0.0;      ///< disk centre ordinate, or rectangle bottom side [m]
  double x1 = 0.0;      ///< rectangle right side (unused for a disk) [m]
  double y1 = 0.0;      ///< rectangle top side (unused for a disk) [m]
  double radius = 0.0;  ///< disk radius, 0 for a rectangle [m]
};

/// Two overlapping outlines: their indices (first < second), how deep they overlap and the
/// smaller one's size.
struct Overlap {
  std::size_t first = 0;   ///< index of the earlier outline [-]
  std::size_t second = 0;  ///< index of the later outline [-]
  double depth = 0.0;      ///< penetration depth (disks: r_a + r_b - distance) [m]
  double size = 0.0;       ///< smaller of the two sizes (diameter or shorter side) [m]
};

/// The overlapping pair with depth > tolerance * size that comes first in (second, first) order,
/// or none. Cell lists of the disk size: O(n) for a packing; larger rectangles are compared with
/// every outline.
std::optional<Overlap> find_overlap(const std::vector<Outline>& outlines, double tolerance);

/// The disks of a packing as outlines, in order.
std::vector<Outline> disk_outlines(const Packing& packing);

/// The overlapping pair of spheres of a 3D packing with depth r_a + r_b - |c_a - c_b| > tolerance
/// * smaller diameter that comes first in (second, first) order, or none; cell lists of the
/// largest diameter, periodic images not compared (as find_overlap).
std::optional<Overlap> find_sphere_overlap(const Packing& packing, double tolerance);

/// The overlapping pair of a packing of either dimension: find_overlap(disk_outlines(packing))
/// in 2D, find_sphere_overlap in 3D.
std::optional<Overlap> find_grain_overlap(const Packing& packing, double tolerance);

}  // namespace mpmcd::packing
