#pragma once
/// Uniform background grid (method.md §1): cells of edge h, nodes at origin + i h, reset every
/// step.
#include <cmath>
#include <cstdint>

#include "mpmcd/core/types.hpp"

namespace mpmcd::grid {

/// A uniform grid of `cells` cells per axis, i.e. cells + 1 nodes per axis; node (0,..) at
/// `origin`.
template <int Dim>
class Grid {
 public:
  Grid() = default;
  /// `origin` [m]: position of node (0, ..., 0); `h` [m]: cell size; `cells`: cells per axis.
  Grid(const Vec<Dim>& origin, double h, const IVec<Dim>& cells)
      : origin_(origin), h_(h), cells_(cells) {
    nodes_ = cells_.array() + 1;
    stride_[0] = 1;
    for (int d = 1; d < Dim; ++d) stride_[d] = stride_[d - 1] * nodes_[d - 1];
  }
  const Vec<Dim>& origin() const { return origin_; }          ///< position of node 0 [m]
  double cell_size() const { return h_; }                     ///< cell edge h [m]
  const IVec<Dim>& cells() const { return cells_; }           ///< cells per axis
  const IVec<Dim>& nodes_per_axis() const { return nodes_; }  ///< nodes per axis (cells + 1)
  /// Upper corner of the grid [m].
  Vec<Dim> upper() const { return origin_ + h_ * cells_.template cast<double>(); }
  /// Total number of nodes.
  std::int64_t node_count() const { return nodes_.prod(); }
  /// Flat index of node coordinates (x fastest).
  std::int64_t node_index(const IVec<Dim>& c) const { return c.dot(stride_); }
  /// Integer coordinates of a flat node index.
  IVec<Dim> node_coords(std::int64_t index) const {
    IVec<Dim> c;
    for (int d = 0; d < Dim; ++d) {
      c[d] = index % nodes_[d];
      index /= nodes_[d];
    }
    return c;
  }
  /// Position of the node with integer coordinates c [m].
  Vec<Dim> node_position(const IVec<Dim>& c) const {
    return origin_ + h_ * c.template cast<double>();
  }
  /// True if x [m] lies at least `margin` cells inside the grid boundary.
  bool inside(const Vec<Dim>& x, double margin_cells) const {
    for (int d = 0; d < Dim; ++d) {
      const double xi = (x[d] - origin_[d]) / h_;
      if (!(xi >= margin_cells && xi <= static_cast<double>(cells_[d]) - margin_cells))
        return false;
    }
    return true;
  }

 private:
  Vec<Dim> origin_ = Vec<Dim>::Zero();
  double h_ = 1.0;
  IVec<Dim> cells_ = IVec<Dim>::Ones();
  IVec<Dim> nodes_ = IVec<Dim>::Constant(2);
  IVec<Dim> stride_ = IVec<Dim>::Ones();
};

}  // namespace mpmcd::grid
