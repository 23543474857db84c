#pragma once
// Private to the packing module: the disk (2D) and sphere (3D) DEM in reduced units
// (docs/packing.md §2): length = mean diameter, stiffness = k_n = 1, mass of a grain of diameter
// 1 = 1.
#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

#include "mpmcd/packing/packing.hpp"

namespace mpmcd::packing::detail {

/// Contact and damping settings of the DEM (reduced units).
struct DemSettings {
  ContactLaw law = ContactLaw::kLinear;  ///< normal force law (eq. 1, 2)
  double friction = 0.0;                 ///< Coulomb coefficient mu (eq. 4, 3D: eq. 4') [-]
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
  double max_force = 0.0;        ///< largest net force on a grain at the end [k_n d]
  bool converged = false;        ///< a stopping criterion was met before the step limit
};

/// Dim-th root: sqrt in 2D, cbrt in 3D (radius scale for a packing fraction ratio, eq. 9) [-].
template <int Dim>
double dim_root(double v) {
  if constexpr (Dim == 2)
    return std::sqrt(v);
  else
    return std::cbrt(v);
}

/// The grain system in Dim = 2 (disks) or 3 (spheres): structure of arrays (one vector per axis),
/// Verlet neighbour list built from cell lists. With friction, a tangential spring per neighbour
/// pair and a spin per grain (a scalar in 2D, a 3-vector in 3D; eq. 4, 4').
template <int Dim>
class Dem {
 public:
  static_assert(Dim == 2 || Dim == 3);
  /// Rotational degrees of freedom of a grain: 1 (spin about z) in 2D, 3 in 3D [-].
  static constexpr int kRot = Dim == 2 ? 1 : 3;
  /// Components of a tangential spring: 1 (along t = (-n_y, n_x)) in 2D, 3 (a vector) in 3D [-].
  static constexpr int kSpring = Dim == 2 ? 1 : 3;
  /// Coordinates, one vector per axis [d_mean].
  using Coords = std::array<std::vector<double>, Dim>;
  /// Angular velocities, one vector per rotational component [1/time].
  using Spins = std::array<std::vector<double>, kRot>;
  /// Walls {lo_0, .., lo_{Dim-1}, hi_0, .., hi_{Dim-1}} [d_mean] (2D: {xlo, ylo, xhi, yhi}).
  using Box = std::array<double, 2 * Dim>;

  /// Grains with centers x and reference radii r0 (radius = scale * r0) in the box; masses
  /// m = (2 r0)^Dim (eq. 6).
  Dem(Coords x, std::vector<double> r0, Box box, const DemSettings& settings);

  std::size_t size() const { return r_.size(); }
  /// Sets radius = scale * r0 for every grain.
  void set_scale(double scale);
  double scale() const { return scale_; }
  /// Sets the walls.
  void set_box(const Box& box) { box_ = box; }
  const Box& box() const { return box_; }
  /// Sets the wall velocities (normal component of each wall, order of Box) for the damping.
  void set_wall_velocity(const Box& v) { wall_v_ = v; }

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
  /// Largest |F| on a grain in the last force evaluation [k_n d].
  double max_force() const;

  /// Centers along axis a [d_mean].
  const std::vector<double>& x(int a) const { return x_[a]; }
  /// Current radii [d_mean].
  const std::vector<double>& r() const { return r_; }
  /// Velocities along axis a [d_mean/time].
  const std::vector<double>& v(int a) const { return v_[a]; }
  /// Sets the velocities [d_mean/time].
  void set_velocities(const Coords& v) { v_ = v; }
  /// Angular velocity component c (2D: the spin about z; 3D: about x, y, z) [1/time].
  const std::vector<double>& spin(int c) const { return w_[c]; }
  /// Sets the angular velocities [1/time].
  void set_spins(const Spins& w) { w_ = w; }
  /// Net forces along axis a of the last force evaluation [k_n d_mean].
  const std::vector<double>& f(int a) const { return f_[a]; }
  /// Mass of grain i (eq. 6) [mass of a grain of diameter d_mean].
  double mass(std::size_t i) const { return m_[i]; }
  /// Moment of inertia of grain i (eq. 6) [mass d_mean^2].
  double inertia(std::size_t i) const { return 1.0 / ii_[i]; }
  /// Positions, for saving/restoring states.
  void get_positions(Coords& x) const { x = x_; }
  void set_positions(const Coords& x);
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
  double length(int a) const { return box_[Dim + a] - box_[a]; }

  DemSettings s_;
  Box box_;
  Box wall_v_{};
  Coords x_, v_, f_;
  Spins w_, tq_;  // angular velocity and torque (used with friction only)
  std::vector<double> r0_, r_, m_, im_, ii_;
  double scale_ = 1.0;
  double r0_max_ = 0.0;
  double dt_ = 0.0;
  // Verlet list in CSR form: neighbours j > i of grain i are nb_j_[nb_start_[i] .. [i+1]).
  std::vector<std::int64_t> nb_start_;
  std::vector<std::int32_t> nb_j_;
  std::vector<double> nb_xi_;  // tangential spring per pair, kSpring components each (eq. 4, 4')
  Coords ref_x_;
  double ref_scale_ = 0.0;
  std::vector<std::int32_t> cell_start_, cell_items_;
  double max_overlap_ = 0.0;
  double energy_ = 0.0;
  std::int64_t steps_ = 0;
  bool built_ = false;
};

extern template class Dem<2>;
extern template class Dem<3>;

}  // namespace mpmcd::packing::detail
