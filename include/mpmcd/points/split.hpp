#pragma once
/// Splitting of material points whose CPDI domain has outgrown its window (docs/accuracy.md,
/// "Point splitting"): a point whose current domain F D0 spans more than one cell along an axis
/// becomes two points, each with half the parent's domain along the edge that stretched most
/// (the refinement of Homel, Brannon & Fox 2016 / Ma, Zhang & Huang 2006, for CPDI1 domains).
#include <cstdint>
#include <span>
#include <vector>

#include "mpmcd/core/types.hpp"
#include "mpmcd/points/point_set.hpp"

namespace mpmcd::points {

/// One point to split in two along the half-edge `edge` (a column of its domain).
struct Split {
  std::int64_t point = 0;  ///< point index [-]
  std::int32_t edge = 0;   ///< column of the domain halved [-]
};

/// Sorts splits by point (the order apply_splits needs).
void sort_splits(std::vector<Split>& splits);

/// The points of the grains `which` whose current domain F D0 does not fit the CPDI1 window on
/// cells of size h [m] (grid::fits_cpdi_window), each with the edge to halve: the column of F D0
/// that contributes most to its widest axis. Ascending by point.
template <int Dim>
std::vector<Split> find_splits(const PointSet<Dim>& points, const std::vector<Grain>& grains,
                               std::span<const std::size_t> which, double h);

/// Splits each listed point (ascending, distinct) into two: the parent, at its index's place,
/// becomes the child at x - d/2, the other child (at x + d/2) follows the grain's last point,
/// where d = F D0 e_edge is the current half-edge [m]. Each child has half the mass, volume0,
/// volume and the domain's edge column, the parent's F, stress, history and L, and the velocity
/// of the parent's affine field at its centre, v -/+ L d/2 (mass, momentum, volume and stored
/// energy are kept exactly). Updates the grains' ranges and history offsets. Returns the new
/// index of every old point (a parent: its first child).
template <int Dim>
std::vector<std::int64_t> apply_splits(PointSet<Dim>& points, std::vector<Grain>& grains,
                                       std::span<const Split> splits);

}  // namespace mpmcd::points
