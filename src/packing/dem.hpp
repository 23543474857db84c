#pragma once
// Private to the packing module: the 2D disk DEM in reduced units (docs/packing.md §2):
// length = mean diameter, stiffness = k_n = 1, mass of a disk of diameter 1 = 1.
#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

#include "mpmcd/packing/packing.hpp"

namespace mpmcd::packing::detail {

/// Contact and damping settings of the DEM (reduced units).
struct DemSettings {
  ContactLaw law = ContactLaw::kLinear;  ///< normal force law (eq. 1, 2)
  double friction = 0.0;                 ///< Coulomb coefficient mu (eq. 4) [-]
  double tangential_ratio = 0.5;         ///< k_t / k_n (eq. 4) [-]
  double damping_ratio = 0.7;            ///< zeta of eq. 3 [-]
  double global_damping = 0.1;           ///< gamma_g of eq. 5 [1/time]
  double skin = 0.3;                     ///< Verlet-list skin [d_mean]
  bool periodic = false;                 ///< periodic cell instead of walls (§2)
};

/// Result of a FIRE energy minimisation (docs/packing.md §4).
struct MinimizeResult {
  std::int64_t steps = 0;        ///< FIRE steps taken
  double energy_per_disk = 0.0;  ///< elastic energy / N at the end [k_n d^2]
  double max_force = 0.0;        ///< largest net force on a disk at the end [k_n d]
  bool converged = false;        ///< a stopping criterion was met before the step limit
};

/// The disk system: structure of arrays, Verlet neighbour list built from cell lists.
class Dem {
 public:
  /// Disks with centers (x, y) and reference radii r0 (radius = scale * r0) in the box
  /// [xlo, xhi] x [ylo, yhi]; masses m = (2 r0)^2 (eq. 6).
  Dem(std::vector<double> x, std::vector<double> y, std::vector<double> r0,
      std::array<double, 4> box, const DemSettings& settings);

  std::size_t size() const { return x_.size(); }
  /// Sets radius = scale * r0 for every disk.
  void set_scale(double scale);
  double scale() const { return scale_; }
  /// Sets the walls {xlo, ylo, xhi, yhi}.
  void set_box(const std::array<double, 4>& box) { box_ = box; }
  const std::array<double, 4>& box() const { return box_; }
  /// Sets the wall velocities {left.x, bottom.y, right.x, top.y} used by the contact damping.
  void set_wall_velocity(const std::array<double, 4>& v) { wall_v_ = v; }

  /// Time step of the damped dynamics: 0.1 sqrt(m_min / k_n) (§2).
  double time_step() const { return dt_; }
  /// One damped velocity-Verlet step of size dt (eq. 7).
  void md_step(double dt);
  /// Recomputes forces and diagnostics at the current state (viscous terms included or not).
  void update_forces(bool viscous);
  /// FIRE minimisation of the elastic energy (frictionless; viscous terms off). Stops when the
  /// largest overlap < overlap_stop, or energy/N < energy_stop, or the largest net force <
  /// force_stop * sqrt(2 energy / N) (a force-balanced state with overlaps).
  MinimizeResult minimize(std::int64_t max_steps, double overlap_stop, double energy_stop,
                          double force_stop);
  /// Sets velocities and spins to zero.
  void zero_velocities();

  /// Largest overlap found by the last force evaluation [d_mean].
  double max_overlap() const { return max_overlap_; }
  /// Elastic energy of the last force evaluation [k_n d^2].
  double energy() const { return energy_; }
  /// Kinetic energy (translation + rotation) [k_n d^2].
  double kinetic_energy() const;
  /// Largest |F| on a disk in the last force evaluation [k_n d].
  double max_force() const;

  const std::vector<double>& x() const { return x_; }
  const std::vector<double>& y() const { return y_; }
  const std::vector<double>& r() const { return r_; }
  /// Positions, for saving/restoring states.
  void get_positions(std::vector<double>& x, std::vector<double>& y) const {
    x = x_;
    y = y_;
  }
  void set_positions(const std::vector<double>& x, const std::vector<double>& y);
  /// Wraps the centers into the periodic cell (no-op with walls).
  void wrap();
  /// Total DEM steps (dynamics + FIRE) done so far.
  std::int64_t steps() const { return steps_; }

 private:
  void build_neighbours();
  void maybe_rebuild();
  void compute_forces(bool viscous, double dt);
  // Minimum-image component of a separation along an axis of period `len` (identity with walls).
  // Valid for |d| < 1.5 len, which wrapping at each list build guarantees.
  double image(double d, double len) const {
    if (!s_.periodic) return d;
    if (d > 0.5 * len) return d - len;
    if (d < -0.5 * len) return d + len;
    return d;
  }

  DemSettings s_;
  std::array<double, 4> box_;
  std::array<double, 4> wall_v_{0.0, 0.0, 0.0, 0.0};
  std::vector<double> x_, y_, vx_, vy_, w_, fx_, fy_, tq_, r0_, r_, m_, im_, ii_;
  double scale_ = 1.0;
  double r0_max_ = 0.0;
  double dt_ = 0.0;
  // Verlet list in CSR form: neighbours j > i of disk i are nb_j_[nb_start_[i] .. [i+1]).
  std::vector<std::int64_t> nb_start_;
  std::vector<std::int32_t> nb_j_;
  std::vector<double> nb_xi_;  // tangential spring elongation per pair (eq. 4)
  std::vector<double> ref_x_, ref_y_;
  double ref_scale_ = 0.0;
  std::vector<std::int32_t> cell_start_, cell_items_;
  double max_overlap_ = 0.0;
  double energy_ = 0.0;
  std::int64_t steps_ = 0;
  bool built_ = false;
};

}  // namespace mpmcd::packing::detail
