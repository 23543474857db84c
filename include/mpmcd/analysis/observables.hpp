#pragma once
/// Observables of the compaction experiment (method.md §6, paper §4; definitions in
/// docs/observables.md): the box formed by four axis-aligned walls, its height, strain and solid
/// fraction Φ (paper eq. (9)), wall stresses, the coordination number Z of the grain contact
/// network and the volume-averaged (Love-Weber) stress of the grains. Pure functions on plain data.
/// The box, Φ, ε, the wall stresses and the Love-Weber stress are given in 2D and 3D (a 3D box has
/// two more walls, normals ±z; the height stays along y), and Z from pair_impulses of a 3D
/// contact problem; the coverage (pixels in 2D, voxels in 3D) and the per-contact impulses too.
#include <cstdint>
#include <functional>
#include <optional>
#include <span>
#include <vector>

#include "mpmcd/contact/problem.hpp"
#include "mpmcd/core/types.hpp"
#include "mpmcd/points/point_set.hpp"
#include "mpmcd/walls/wall.hpp"

namespace mpmcd::analysis {

/// Which of the walls bound an axis-aligned rectangular box (indices into the wall list).
struct BoxWalls {
  std::size_t left = 0;    ///< wall with normal +x [-]
  std::size_t right = 0;   ///< wall with normal -x [-]
  std::size_t bottom = 0;  ///< wall with normal +y [-]
  std::size_t top = 0;     ///< wall with normal -y [-]
  std::size_t front = 0;   ///< wall with normal +z (3D) [-]
  std::size_t back = 0;    ///< wall with normal -z (3D) [-]
};

/// The box at one time.
struct Box {
  double x_min = 0, x_max = 0;  ///< positions of the left and right walls [m]
  double y_min = 0, y_max = 0;  ///< positions of the bottom and top walls [m]
  double z_min = 0, z_max = 0;  ///< positions of the front and back walls (3D) [m]
  int dim = 2;                  ///< spatial dimension of the box [-]
  /// Width x_max - x_min [m].
  double width() const { return x_max - x_min; }
  /// Height h = y_max - y_min [m].
  double height() const { return y_max - y_min; }
  /// Depth z_max - z_min (3D) [m].
  double depth() const { return z_max - z_min; }
  /// Volume V of the box: width h in 2D (per unit thickness) [m^2], width h depth in 3D [m^3].
  double area() const { return dim == 3 ? width() * height() * depth() : width() * height(); }
};

/// The walls form a box when there are exactly 2 Dim of them and their normals are +x, -x, +y,
/// -y (and +z, -z in 3D), each component within 1e-12 of 0 or ±1; nullopt otherwise.
std::optional<BoxWalls> find_box(std::span<const walls::Wall<2>> walls);
/// The 3D box: six walls, normals ±x, ±y, ±z.
std::optional<BoxWalls> find_box(std::span<const walls::Wall<3>> walls);

/// The box bounded by the walls at time t [s]: each wall at walls::Wall::point_at(t).
Box box_at(std::span<const walls::Wall<2>> walls, const BoxWalls& box, double t);
/// The 3D box bounded by the walls at time t [s].
Box box_at(std::span<const walls::Wall<3>> walls, const BoxWalls& box, double t);

/// Measure of wall `k`'s face inside the box: in 2D its length [m] (the width for the bottom and
/// top walls, the height for the left and right walls), in 3D its area [m^2] (the product of the
/// two other extents); 0 if k is not one of the box walls.
double wall_length(const Box& box, const BoxWalls& walls, std::size_t k);

/// The compaction state of paper §4 at one output.
struct CompactionState {
  double height = 0;     ///< box height h [m]
  double strain = 0;     ///< ε = ln(h/h0) (negative in compaction) [-]
  double phi = 0;        ///< solid fraction Φ = Vs/V [-]
  double vs = 0;         ///< grain area Vs = Σ_p V_p [m^2]
  double ln_vs_vs0 = 0;  ///< ln(Vs/Vs0) [-]
};

/// Φ = Vs/V, ε = ln(h/h0), ln(Vs/Vs0) for the box `box` (initial box `box0`) and grain areas vs,
/// vs0 [m^2]. With a constant width, ln(Vs/Vs0) = ln(Φ/Φ0) + ε (paper eq. (9)) to round-off.
CompactionState compaction_state(const Box& box, const Box& box0, double vs, double vs0);

/// Normal stress on a wall [Pa]: σ = F·n / L with F the force of the grains on the wall [N/m in
/// 2D, N in 3D], n its unit normal into the domain and L its length [m] (3D: area [m^2]) in
/// contact with the box. Mechanics convention: negative when the grains push on the wall
/// (compression), like paper eq. (10).
template <int Dim>
double wall_normal_stress(const Vec<Dim>& force_on_wall, const Vec<Dim>& normal, double length);

/// Volume-averaged (Love-Weber) Cauchy stress of the grains over the volume V [m^2 in 2D, m^3 in
/// 3D]: σ̄ = (1/V) Σ_p σ_p V_p with V_p the points' current volume (docs/observables.md) [Pa].
template <int Dim>
Mat<Dim> love_weber_stress(const points::PointSet<Dim>& points, double area);

extern template double wall_normal_stress<2>(const Vec<2>&, const Vec<2>&, double);
extern template double wall_normal_stress<3>(const Vec<3>&, const Vec<3>&, double);
extern template Mat<2> love_weber_stress<2>(const points::PointSet<2>&, double);
extern template Mat<3> love_weber_stress<3>(const points::PointSet<3>&, double);

/// How the point domains cover the box (docs/observables.md, "Coverage"): each point's domain is
/// the parallelogram (3D: parallelepiped) x_p + F_p D_p s, s ∈ [-1, 1]^Dim (D_p its reference
/// half-edge vectors, the CPDI domain; uGIMP's square D_p = l_p I alike), rasterised on square
/// pixels (3D: cubic voxels) whose centres are tested. Measures are areas [m^2] in 2D, volumes
/// [m^3] in 3D.
struct Coverage {
  double covered = 0;  ///< measure inside the box covered by at least one domain [m^2 | m^3]
  double overlap = 0;  ///< measure covered by two or more grains, counted (grains − 1) times
  double outside = 0;  ///< measure outside the box covered by at least one domain [m^2 | m^3]
  /// Measure of the pores: the void regions inside the box (4-connected uncovered pixels, 3D:
  /// 6-connected voxels) that border two grains or a wall [m^2 | m^3].
  double pores = 0;
  /// Measure of the void regions bordered by one grain only: gaps of that grain's domain tiling
  /// (e.g. the slivers between polar seeding's rectangles), solid for Φ [m^2 | m^3].
  double gaps = 0;
  /// Pore size: mean equivalent diameter of the pores, sqrt(4 A_i / π) in 2D, (6 V_i / π)^(1/3)
  /// in 3D, weighted by their measures A_i, V_i [m]; 0 without pores.
  double pore_diameter = 0;
  double pixel = 0;  ///< side of the pixels (voxels) used [m]
};

/// The coverage of the box by the point domains, on pixels of side `pixel` [m] (enlarged so that
/// the raster over the box and the domains holds at most `max_pixels` pixels). Points of a grain
/// must be contiguous (points::PointSet); overlaps of domains of one grain are not counted.
Coverage domain_coverage(const points::PointSet<2>& points, const Box& box, double pixel,
                         std::int64_t max_pixels = std::int64_t{1} << 24);
/// The same in 3D on cubic voxels of side `voxel` [m] (at most `max_voxels` of them), the voids
/// 6-connected.
Coverage domain_coverage(const points::PointSet<3>& points, const Box& box, double voxel,
                         std::int64_t max_voxels = std::int64_t{1} << 24);

/// One grid-node contact reduced to what Z and the contact forces need (Dim = 2 or 3).
template <int Dim>
struct ContactImpulseOf {
  std::int32_t a = -1;                   ///< grain A, or -1 - k for wall k [-]
  std::int32_t b = -1;                   ///< grain B [-]
  double normal_impulse = 0;             ///< P·n, positive in compression [N s/m | N s]
  Vec<Dim> impulse = Vec<Dim>::Zero();   ///< P, impulse of A on B over the step [N s/m | N s]
  Vec<Dim> normal = Vec<Dim>::Zero();    ///< unit normal from A to B [-]
  Vec<Dim> position = Vec<Dim>::Zero();  ///< position of the contact's grid node [m]
};
/// The 2D contact impulse (per unit thickness).
using ContactImpulse = ContactImpulseOf<2>;

/// The contacts of a solved contact problem: grains of the two slots (a = -1 - k for wall k),
/// P·n, P and n (position left 0).
std::vector<ContactImpulse> contact_impulses(const contact::Problem<2>& problem);

/// The same with each contact's position: node_position(slot node index) [m].
std::vector<ContactImpulse> contact_impulses(
    const contact::Problem<2>& problem, const std::function<Vec<2>(std::int64_t)>& node_position);
/// The same in 3D.
std::vector<ContactImpulseOf<3>> contact_impulses(
    const contact::Problem<3>& problem, const std::function<Vec<3>(std::int64_t)>& node_position);

/// Settings of the coordination number.
struct CoordinationSettings {
  /// A grain pair is in contact when its summed normal impulse exceeds this fraction of the
  /// largest summed normal impulse of any grain pair (separates real contacts from the
  /// round-off impulses the Gauss-Seidel tolerance leaves) [-].
  double relative_threshold = 1e-6;
  /// A grain's contacts with walls count when deciding whether it is a rattler (a grain held
  /// between a wall and another grain carries load); they never count as pairs in Z [-].
  bool walls_hold_grains = true;
};

/// The normal impulse of one pair of bodies, summed over its grid-node contacts.
struct PairImpulse {
  std::int32_t a = -1;        ///< body A: a grain, or -1 - k for wall k (a < b) [-]
  std::int32_t b = -1;        ///< grain B [-]
  double normal_impulse = 0;  ///< Σ P·n over the pair's contacts [N s/m]
};

/// Normal impulses summed per pair of bodies (grains (min, max), walls (-1 - k, grain)), sorted
/// by (a, b); contacts naming a grain outside [0, n_grains) or a grain with itself are skipped.
std::vector<PairImpulse> pair_impulses(std::span<const ContactImpulse> contacts,
                                       std::int64_t n_grains);
/// The same for 3D contacts.
std::vector<PairImpulse> pair_impulses(std::span<const ContactImpulseOf<3>> contacts,
                                       std::int64_t n_grains);

/// The same straight from a solved contact problem of any dimension: P·n of each contact
/// (impulse on B along the normal from A to B) summed per pair as above.
template <int Dim>
std::vector<PairImpulse> pair_impulses(const contact::Problem<Dim>& problem, std::int64_t n_grains);

extern template std::vector<PairImpulse> pair_impulses<2>(const contact::Problem<2>&, std::int64_t);
extern template std::vector<PairImpulse> pair_impulses<3>(const contact::Problem<3>&, std::int64_t);

/// The summed normal impulse above which a pair is in contact: settings.relative_threshold times
/// the largest of any pair (grain-grain or grain-wall) [N s/m]; a pair is in contact when its
/// sum exceeds this and 0.
double contact_threshold(std::span<const PairImpulse> pairs, const CoordinationSettings& settings);

/// Coordination of the grain contact network.
struct Coordination {
  double z = 0;                    ///< Z = 2 N_pairs / N_grains over the non-rattlers [-]
  std::int64_t pairs = 0;          ///< grain pairs in contact among the non-rattlers [-]
  std::int64_t grains = 0;         ///< grains kept (at least two contacts) [-]
  std::int64_t rattlers = 0;       ///< grains removed (fewer than two contacts) [-]
  std::int64_t all_pairs = 0;      ///< grain pairs in contact before removing rattlers [-]
  std::int64_t wall_contacts = 0;  ///< grain-wall pairs in contact (not counted in Z) [-]
  std::vector<std::uint8_t> kept;  ///< per grain: 1 if kept, 0 if removed as a rattler [-]
};

/// Coordination number Z (docs/observables.md): contact impulses summed per pair of bodies (all
/// their nodes); a pair is in contact if its sum exceeds the threshold; grains with fewer than two
/// contacts (wall contacts included if settings.walls_hold_grains) are removed repeatedly until
/// none is left (a removed grain's contacts no longer count for its neighbours);
/// Z = 2 N_pairs / N_grains over the rest with N_pairs the grain-grain pairs (walls excluded),
/// 0 if no grain is left. `n_grains` is the number of grains in the system.
Coordination coordination(std::span<const ContactImpulse> contacts, std::int64_t n_grains,
                          const CoordinationSettings& settings = {});

/// The same from the per-pair sums `pairs` (pair_impulses), e.g. of a 3D contact problem.
Coordination coordination_of_pairs(std::span<const PairImpulse> pairs, std::int64_t n_grains,
                                   const CoordinationSettings& settings = {});

}  // namespace mpmcd::analysis
