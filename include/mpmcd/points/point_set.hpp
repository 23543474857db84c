#pragma once
/// Material points as a structure of arrays, grouped by grain (method.md §1).
#include <cstdint>
#include <vector>

#include "mpmcd/core/types.hpp"

namespace mpmcd::points {

/// A grain: a contiguous range of points sharing one material (a body with its own nodal field).
struct Grain {
  std::int64_t begin = 0;           ///< first point index
  std::int64_t end = 0;             ///< one past the last point index
  int material = 0;                 ///< index into the material list
  double half_width = 0.0;          ///< uGIMP particle half-width lp (half the seeding spacing) [m]
  std::int64_t history_offset = 0;  ///< first history double of this grain in PointSet::history
  /// Number of points.
  std::int64_t size() const { return end - begin; }
};

/// Committed state of all material points, structure of arrays, points of a grain contiguous.
template <int Dim>
struct PointSet {
  std::vector<Vec<Dim>> x;          ///< position [m]
  std::vector<Vec<Dim>> v;          ///< velocity [m/s]
  std::vector<Mat<Dim>> L;          ///< velocity gradient carried for the affine P2G [1/s]
  std::vector<Mat<Dim>> F;          ///< deformation gradient [-]
  std::vector<Mat<Dim>> sigma;      ///< Cauchy stress (in-plane part) [Pa]
  std::vector<double> sigma_zz;     ///< out-of-plane Cauchy stress in plane strain (2D) [Pa]
  std::vector<double> mass;         ///< mass [kg] (per unit thickness in 2D: kg/m)
  std::vector<double> volume0;      ///< initial volume [m^Dim]
  std::vector<double> volume;       ///< current volume J * volume0 [m^Dim]
  std::vector<Mat<Dim>> domain;     ///< reference domain half-edge vectors (columns) [m]
  std::vector<std::int32_t> grain;  ///< grain index
  std::vector<double> history;  ///< law history variables, per grain blocks (Grain::history_offset)

  /// Number of points.
  std::size_t size() const { return x.size(); }
  /// Calls f on each per-point array that a committed step changes, in this fixed order: x, v,
  /// L, F, sigma, sigma_zz, volume (what a grain's owner sends to the other ranks: the one list
  /// of them, parallel/distribute.cpp). `Set` is PointSet<Dim> or const PointSet<Dim>.
  template <class Set, class Fn>
  static void for_each_state_field(Set& set, Fn&& f) {
    f(set.x);
    f(set.v);
    f(set.L);
    f(set.F);
    f(set.sigma);
    f(set.sigma_zz);
    f(set.volume);
  }
  /// Calls f on every per-point array (one entry per point; `history`, per grain blocks, is not
  /// one): the state fields of for_each_state_field, then mass, volume0, domain, grain.
  template <class Set, class Fn>
  static void for_each_point_field(Set& set, Fn&& f) {
    for_each_state_field(set, f);
    f(set.mass);
    f(set.volume0);
    f(set.domain);
    f(set.grain);
  }
  /// Appends a point with F = I and zero stress; `dom` holds its reference domain's half-edge
  /// vectors as columns [m].
  void add(const Vec<Dim>& pos, const Vec<Dim>& vel, double m, double vol, const Mat<Dim>& dom,
           std::int32_t g) {
    x.push_back(pos);
    v.push_back(vel);
    L.push_back(Mat<Dim>::Zero());
    F.push_back(Mat<Dim>::Identity());
    sigma.push_back(Mat<Dim>::Zero());
    sigma_zz.push_back(0.0);
    mass.push_back(m);
    volume0.push_back(vol);
    volume.push_back(vol);
    domain.push_back(dom);
    grain.push_back(g);
  }
};

}  // namespace mpmcd::points
