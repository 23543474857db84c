#pragma once
/// The rigid plane wall: the one type of a wall for the contact (mpm), the box and its
/// observables (analysis), the loading and the outputs (app). The input's [[walls]] records
/// (io::WallSection) become walls in one place, app::input_walls.
#include <string>

#include "mpmcd/core/types.hpp"

namespace mpmcd::walls {

/// A rigid wall: the plane through `point` + velocity (t - t0) with unit `normal` pointing into
/// the domain; it takes part in contact as a body of infinite mass. A wall whose velocity changes
/// (app::WallLoading: stages, servo) is re-anchored at each step: point = its position at t0 = t^n.
template <int Dim>
struct Wall {
  std::string name;                      ///< name used in outputs [-]
  Vec<Dim> point = Vec<Dim>::Zero();     ///< a point of the plane at time t0 [m]
  Vec<Dim> normal = Vec<Dim>::Zero();    ///< unit normal into the domain [-]
  Vec<Dim> velocity = Vec<Dim>::Zero();  ///< prescribed velocity [m/s]
  double friction = 0.0;                 ///< Coulomb coefficient with every grain [-]
  double t0 = 0.0;                       ///< time at which the plane passes through `point` [s]
  /// How far the plane has moved from `point` at time t [s]: velocity (t - t0) [m]; the one
  /// place a wall's motion is computed (point_at, distance).
  Vec<Dim> displacement(double t) const { return (t - t0) * velocity; }
  /// A point of the plane at time t [s]: point + displacement(t) [m].
  Vec<Dim> point_at(double t) const { return point + displacement(t); }
  /// Signed distance of x [m] from the wall at time t [s] (positive inside the domain) [m].
  double distance(const Vec<Dim>& x, double t) const {
    return (x - point - displacement(t)).dot(normal);
  }
};

}  // namespace mpmcd::walls
