#pragma once
/// Seeding shapes with material points on a lattice aligned with the background grid.
#include <vector>

#include "mpmcd/core/types.hpp"

namespace mpmcd::points {

/// Positions [m] and initial volumes [m^Dim] (per unit thickness in 2D) of seeded points.
template <int Dim>
struct Seeds {
  std::vector<Vec<Dim>> x;     ///< point positions [m]
  std::vector<double> volume;  ///< point volumes [m^Dim]
  /// Reference domain of each point: its columns are the half-edge vectors of a parallelogram
  /// (2D) / parallelepiped (3D) [m]. Empty: the grain's lattice square of half-width lp.
  std::vector<Mat<Dim>> domain;
};

/// Lattice spacing of `ppc` points per cell of size `h` [m].
inline double lattice_spacing(double h, int ppc) {
  return h / ppc;
}

/// Seeds a disk (2D) / ball (3D) of `center` [m] and `radius` [m]: lattice sites
/// x = origin + (i + 1/2) h/ppc that lie strictly inside; volumes are scaled so that their sum
/// equals the exact area pi r^2 (volume 4/3 pi r^3). Empty if no site falls inside.
template <int Dim>
Seeds<Dim> seed_ball(const Vec<Dim>& origin, double h, int ppc, const Vec<Dim>& center,
                     double radius);

/// Seeds the box [lo, hi] [m] with the lattice sites inside; volumes scaled to the exact box
/// volume.
template <int Dim>
Seeds<Dim> seed_box(const Vec<Dim>& origin, double h, int ppc, const Vec<Dim>& lo,
                    const Vec<Dim>& hi);

/// Seeds a disk of `center` [m] and `radius` [m] on concentric rings (polar seeding): a central
/// point for the disk of radius dr/2, then rings of mid-radius r_i = i dr, i = 1..n, with
/// dr = radius / (n + 1/2) and n = max(1, round(radius / spacing - 1/2)); ring i holds
/// N_i = round(2 pi i) points (staggered by half a spacing from ring to ring), each with the
/// volume 2 pi r_i dr / N_i of its annular sector and a domain with the half-edges dr/2 e_r and
/// (pi r_i / N_i) e_theta, so the outermost domains are tangent to the circle and the volumes sum
/// to pi r^2 exactly. `spacing` [m] is the target distance between points (h / ppc).
Seeds<2> seed_disk_polar(const Vec<2>& center, double radius, double spacing);

/// Exact measure of a ball of `radius` [m]: pi r^2 in 2D, 4/3 pi r^3 in 3D [m^Dim].
template <int Dim>
double ball_measure(double radius);

}  // namespace mpmcd::points
