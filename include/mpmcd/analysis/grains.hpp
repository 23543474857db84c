#pragma once
/// Grain-scale observables (docs/observables.md, "Grain-scale outputs"; issue 19): each grain's
/// volume-averaged Cauchy stress and its invariants, its shape from its material points (area,
/// centroid, second moment of area, convex hull), the contact forces per pair of bodies with
/// their normals and branch vectors, the fabric tensor, the granular stress from the contact
/// forces and histograms of the force and pressure distributions. Pure functions on plain data
/// (2D plane strain: areas per unit thickness [m^2], forces per unit thickness [N/m]; 3D:
/// volumes [m^3], forces [N]). The types are templates on Dim (2 or 3) with 2D aliases; the
/// convex hull and the in-plane invariants are 2D only.
#include <cstdint>
#include <span>
#include <vector>

#include "mpmcd/analysis/observables.hpp"
#include "mpmcd/core/types.hpp"
#include "mpmcd/points/point_set.hpp"

namespace mpmcd::analysis {

/// What the material points of one grain say about it (Dim = 2 or 3; in 3D "area" is the volume).
template <int Dim>
struct GrainStateOf {
  double area = 0;                       ///< A_g = Σ_p V_p (current volumes) [m^2 | m^3]
  Vec<Dim> centroid = Vec<Dim>::Zero();  ///< x_g = Σ_p V_p x_p / A_g [m]
  Mat<Dim> stress = Mat<Dim>::Zero();    ///< σ̄_g = Σ_p σ_p V_p / A_g (2D: in-plane) [Pa]
  double stress_zz = 0;                  ///< Σ_p σzz_p V_p / A_g (2D plane strain; 3D: 0) [Pa]
  Mat<Dim> moment = Mat<Dim>::Zero();    ///< second moment about x_g [m^4 | m^5]
  double hull_area = 0;       ///< area of the convex hull of the domains' corners (2D) [m^2]
  double hull_perimeter = 0;  ///< perimeter of that hull (2D) [m]
};
/// The 2D grain state.
using GrainState = GrainStateOf<2>;

/// The state of the grain made of points [begin, end) of `points`: area, centroid, σ̄_g (the
/// volume average of the points' Cauchy stresses, Love-Weber on one grain), the second moment of
/// area I = Σ_p [V_p (x_p - x_g)⊗(x_p - x_g) + (V_p/3) Σ_k e_k⊗e_k] (e_k = F_p D_p's columns:
/// the point's parallelogram domain, whose own moment about its centre is (V/3) Σ_k e_k⊗e_k), and
/// the convex hull (Andrew's monotone chain) of the 4 corners x_p ± e_1 ± e_2 of every domain.
/// The corners are left in `corners` (a scratch buffer, reused: no allocation per point once it
/// is large enough; nullptr: not collected); grain_states makes the hull of them.
GrainState grain_state(const points::PointSet<2>& points, std::int64_t begin, std::int64_t end,
                       std::vector<Vec<2>>* corners);
/// The same in 3D: volume, centroid, σ̄_g and the second moment (the parallelepiped's own moment
/// is (V/3) Σ_k e_k⊗e_k too: ∫ s_i s_j ds / ∫ ds = δ_ij/3 on [-1, 1]³) [m^5]; no hull.
GrainStateOf<3> grain_state(const points::PointSet<3>& points, std::int64_t begin,
                            std::int64_t end);

/// grain_state of every grain (OpenMP over grains). `hull` false skips the convex hulls
/// (hull_area, hull_perimeter left 0) for the cheap per-row quantities.
std::vector<GrainState> grain_states(const points::PointSet<2>& points,
                                     std::span<const points::Grain> grains, bool hull = true);
/// grain_state of every grain in 3D (OpenMP over grains).
std::vector<GrainStateOf<3>> grain_states(const points::PointSet<3>& points,
                                          std::span<const points::Grain> grains);

/// Mean in-plane stress σ_m = (σxx + σyy)/2, tension positive [Pa]; the 2D pressure of the
/// granular literature is P = -σ_m.
double mean_stress(const Mat<2>& sigma);

/// Norm of the in-plane deviator s = σ - σ_m I: |s| = sqrt(s:s) [Pa]. The 2D deviatoric stress
/// q = (σ1 - σ2)/2 of Cantor et al. is |s|/√2.
double deviator_norm(const Mat<2>& sigma);

/// von Mises stress of the full plane-strain tensor (σ in-plane, σzz out of plane):
/// σ_vM = sqrt(3/2 S:S), S = σ3 - tr(σ3)/3 I [Pa].
double von_mises(const Mat<2>& sigma, double sigma_zz);

/// Mean stress σ_m = tr σ / 3 of a 3D tensor, tension positive (the pressure is -σ_m) [Pa].
double mean_stress(const Mat<3>& sigma);

/// Norm of the deviator of a 3D tensor: |s| = sqrt(s:s), s = σ - σ_m I [Pa]; the von Mises
/// stress (the triaxial q) is sqrt(3/2) |s|.
double deviator_norm(const Mat<3>& sigma);

/// Principal axes of a symmetric 2x2 tensor.
struct Principal {
  double major = 0;  ///< larger eigenvalue [units of the tensor]
  double minor = 0;  ///< smaller eigenvalue [units of the tensor]
  double angle = 0;  ///< angle of the major eigenvector from +x, in (-90, 90] [deg]
};

/// Eigenvalues and major direction of a symmetric 2x2 tensor (closed form).
Principal principal(const Mat<2>& m);

/// Aspect ratio of a grain from its second moment of area: sqrt(I_major / I_minor) [-] (a/b for
/// an ellipse of semi-axes a >= b, L/W for an L x W rectangle); 0 if I_minor <= 0.
double aspect_ratio(const Mat<2>& moment);

/// Aspect ratio of a 3D grain from its second moment: sqrt(I_max / I_min) of the eigenvalues
/// [-] (a/c for an ellipsoid of semi-axes a >= b >= c); 0 if I_min <= 0.
double aspect_ratio(const Mat<3>& moment);

/// Circularity 4π A / P² of a closed outline of area A [m^2] and perimeter P [m] [-] (1 for a
/// circle, π/4 for a square); 0 if P <= 0.
double circularity(double area, double perimeter);

/// The force of one contact pair of bodies, summed over its grid-node contacts (Dim = 2 or 3).
template <int Dim>
struct PairForceOf {
  std::int32_t a = -1;                 ///< body A: a grain, or -1 - k for wall k [-]
  std::int32_t b = -1;                 ///< body B: a grain (a < b when both are grains) [-]
  std::int32_t nodes = 0;              ///< grid-node contacts of the pair [-]
  double normal_impulse = 0;           ///< Σ P·n over its nodes (what Z thresholds) [N s/m | N s]
  Vec<Dim> force = Vec<Dim>::Zero();   ///< F = Σ P/Δt, force of A on B [N/m | N]
  Vec<Dim> normal = Vec<Dim>::Zero();  ///< unit normal from A to B: Σ p_n n / |Σ p_n n| [-]
  double normal_force = 0;             ///< f_n = F·n, positive in compression [N/m | N]
  /// 2D: f_t = F·t, t = e_z × n; 3D: |F - f_n n| >= 0 [N/m | N].
  double tangential_force = 0;
  Vec<Dim> point = Vec<Dim>::Zero();   ///< contact point Σ p_n x_I / Σ p_n (grid nodes x_I) [m]
  Vec<Dim> branch = Vec<Dim>::Zero();  ///< ℓ: A's centroid (wall: the contact point) to B's [m]
  bool in_contact = false;             ///< p_n above the threshold of Z (docs/observables.md) [-]
};
/// The 2D pair force (per unit thickness).
using PairForce = PairForceOf<2>;

/// The contact forces per pair of bodies of a solved contact problem: each grid-node contact's
/// force P/Δt (contact::impulse_force) summed per pair (a, b), with `contacts` from
/// contact_impulses(problem, node_position) and the grains' centroids. A pair is in contact by
/// the rule of Z (pair_impulses, contact_threshold). Sorted by (a, b); walls first.
std::vector<PairForce> pair_forces(std::span<const ContactImpulse> contacts, double dt,
                                   std::span<const GrainState> grains,
                                   const CoordinationSettings& settings = {});
/// The same in 3D.
std::vector<PairForceOf<3>> pair_forces(std::span<const ContactImpulseOf<3>> contacts, double dt,
                                        std::span<const GrainStateOf<3>> grains,
                                        const CoordinationSettings& settings = {});

/// Granular stress from the contact forces (Love-Weber / Christoffersen et al. 1981, Cantor et
/// al. 2018 eq. (3), tension positive): σ_c = -(1/V) Σ_c F_c ⊗ ℓ_c over the pairs in contact
/// (grain-grain and grain-wall), symmetric part, V [m^2] [Pa]. In static equilibrium (uniform
/// body force allowed) it equals Σ_g σ̄_g A_g / V.
Mat<2> contact_stress(std::span<const PairForce> pairs, double volume);
/// The same in 3D, V [m^3] [Pa].
Mat<3> contact_stress(std::span<const PairForceOf<3>> pairs, double volume);

/// Volume average of the grain stresses Σ_g σ̄_g A_g / V over the area V [m^2] [Pa].
Mat<2> mean_grain_stress(std::span<const GrainState> grains, double volume);
/// The same in 3D over the volume V [m^3] [Pa].
Mat<3> mean_grain_stress(std::span<const GrainStateOf<3>> grains, double volume);

/// The fabric of the grain contact network (Dim = 2 or 3).
template <int Dim>
struct FabricOf {
  Mat<Dim> tensor = Mat<Dim>::Zero();  ///< R = (1/N_c) Σ_c n_c⊗n_c [-]
  std::int64_t contacts = 0;           ///< N_c, grain-grain pairs counted [-]
  double anisotropy = 0;               ///< 2D: a = 2 (R_1 - R_2); 3D: a = (5/2) (R_1 - R_3) [-]
  double angle = 0;  ///< 2D: direction of R_1's eigenvector from +x, (-90, 90] [deg]
};
/// The 2D fabric.
using Fabric = FabricOf<2>;

/// Fabric tensor R = (1/N_c) Σ n⊗n over the grain-grain pairs in contact between grains that
/// `kept` marks (the network of Z, rattlers removed; empty `kept`: every grain), its 2D
/// anisotropy a = 2 (R_1 - R_2) (Rothenburg and Bathurst 1989; Cantor et al. 2018) and
/// direction. Zero without contacts.
Fabric fabric(std::span<const PairForce> pairs, std::span<const std::uint8_t> kept = {});
/// The same in 3D: a = (5/2) (R_1 - R_3) with R_1 >= R_2 >= R_3 its eigenvalues (Azéma, Radjai
/// and Dubois 2013; 0 for an isotropic network, the 3D analogue of 2 (R_1 - R_2)); no angle.
FabricOf<3> fabric(std::span<const PairForceOf<3>> pairs, std::span<const std::uint8_t> kept = {});

/// A histogram as a probability density.
struct Histogram {
  std::vector<double> edges;         ///< bin edges, bins + 1 values [units of the data]
  std::vector<double> density;       ///< count / (n width), integrates to 1 over [lo, hi] [1/units]
  std::vector<std::int64_t> counts;  ///< values per bin [-]
  std::int64_t outside = 0;          ///< values outside [lo, hi] [-]
};

/// Histogram of `values` on `bins` equal bins over [lo, hi] (the last bin closed), as counts and
/// probability density count / (n width) with n the number of values (those outside included).
Histogram histogram(std::span<const double> values, int bins, double lo, double hi);

}  // namespace mpmcd::analysis
