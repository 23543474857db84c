#pragma once
/// Initial packings of polydisperse disks (2D) or spheres (3D) in a rectangular box: plain data,
/// the DEM generator (docs/packing.md §1-§4), the CSV packing file (§6) and its VTU view. All
/// lengths in metres.
#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace mpmcd::packing {

/// One rigid disk (2D) or sphere (3D) of a packing.
struct Disk {
  std::int64_t id = 0;  ///< identifier, unique within a packing [-]
  double x = 0.0;       ///< center abscissa [m]
  double y = 0.0;       ///< center ordinate [m]
  double radius = 0.0;  ///< radius [m]
  double z = 0.0;       ///< center third coordinate (3D packings; 0 in 2D) [m]
};

/// A packing: disks in the box [xmin, xmax] x [ymin, ymax] (2D), or spheres in the box
/// [xmin, xmax] x [ymin, ymax] x [zmin, zmax] (3D).
struct Packing {
  double xmin = 0.0;        ///< left wall [m]
  double ymin = 0.0;        ///< bottom wall [m]
  double xmax = 0.0;        ///< right wall [m]
  double ymax = 0.0;        ///< top wall [m]
  std::uint64_t seed = 0;   ///< seed of the generator that made it (0 if unknown) [-]
  bool periodic = false;    ///< true: the box is a periodic cell (disks may cross its sides)
  std::vector<Disk> disks;  ///< the disks, in file order
  int dimension = 2;        ///< 2: disks in the x-y plane, 3: spheres [-]
  double zmin = 0.0;        ///< lower z wall (3D) [m]
  double zmax = 0.0;        ///< upper z wall (3D) [m]
};

/// How the target packing fraction is reached (docs/packing.md §3).
enum class PackingMethod {
  kGrow,   ///< fixed walls, radii grow by a uniform factor
  kWalls,  ///< fixed radii, the four walls move inward
  kJam,    ///< frictionless quasi-static compression until jammed (target_phi unused)
};

/// Normal contact force law (docs/packing.md eq. 1 and 2).
enum class ContactLaw {
  kLinear,  ///< f_n = k_n delta
  kHertz,   ///< f_n = k_n delta sqrt(R* delta) / d_mean
};

/// Parameters of generate_packing: plain data, SI units. Defaults are those of docs/packing.md §5.
struct PackingParams {
  int dimension = 2;              ///< 2: disks, 3: spheres [-]
  std::int64_t count = 300;       ///< number of disks when `diameters` is empty [-]
  double diameter_min = 0.0;      ///< smallest diameter of the uniform distribution [m]
  double diameter_max = 0.0;      ///< largest diameter of the uniform distribution [m]
  std::vector<double> diameters;  ///< explicit diameters [m]; if non-empty, replaces count/min/max
  /// Box {xmin, ymin, xmax, ymax} [m]. If set, the diameters are scaled by one common factor so
  /// that the packing fraction is reached in this box; if unset, the diameters are kept and the
  /// box (of `aspect_ratio`, lower corner `origin`) follows from the packing fraction.
  std::optional<std::array<double, 4>> box;
  /// Box extent along z {zmin, zmax} [m] in 3D when `box` is set (the x-y part is `box`).
  std::array<double, 2> box_z{0.0, 0.0};
  /// Box width / height when `box` is unset [-]; in 3D width = x and y extents, height = z.
  double aspect_ratio = 1.0;
  std::array<double, 2> origin{0.0, 0.0};  ///< lower-left corner when `box` is unset [m]
  double origin_z = 0.0;                   ///< lower z of the box in 3D when `box` is unset [m]
  double target_phi = 0.78;  ///< disk area / box area (3D: volumes) to reach (grow, walls) [-]
  PackingMethod method = PackingMethod::kGrow;   ///< protocol
  ContactLaw contact_law = ContactLaw::kLinear;  ///< normal force law
  double friction = 0.0;    ///< Coulomb coefficient between grains (eq. 4, 4') [-]
  bool periodic = false;    ///< periodic cell instead of rigid walls (not with method kWalls)
  std::uint64_t seed = 42;  ///< seed of the std::mt19937_64 generator [-]
  // Numerical settings, in reduced units: length d_mean, stiffness k_n, mass of a disk of
  // diameter d_mean (docs/packing.md §2).
  double initial_phi = 0.2;               ///< packing fraction of the random initial state [-]
  std::int64_t growth_steps = 20000;      ///< time steps of the growth / wall motion stage [-]
  std::int64_t max_relax_steps = 400000;  ///< time-step limit of the relaxation stage [-]
  double overlap_tolerance = 1e-5;        ///< relaxed when every overlap < this * d_mean [-]
  double damping_ratio = 0.7;             ///< normal contact damping ratio zeta (eq. 3) [-]
  double global_damping = 0.1;            ///< background drag rate (eq. 5) [sqrt(k_n / m)]
  double jam_start_phi = 0.80;            ///< packing fraction where the jam search starts [-]
  double jam_phi_tolerance = 1e-4;        ///< width of the final jamming bracket (jam) [-]
};

/// What generate_packing measured.
struct PackingReport {
  double phi = 0.0;             ///< achieved packing fraction: disk area / box area [-]
  double max_overlap = 0.0;     ///< largest overlap (disk-disk or disk-wall) / mean diameter [-]
  double mean_diameter = 0.0;   ///< mean diameter of the output disks [m]
  double diameter_scale = 1.0;  ///< factor applied to the requested diameters (box given) [-]
  double jamming_phi = 0.0;     ///< jamming packing fraction (jam method, else 0) [-]
  std::int64_t steps = 0;       ///< total DEM time steps (all stages) [-]
  bool relaxed = false;         ///< overlaps below tolerance (grow, walls) / bracket found (jam)
  double wall_seconds = 0.0;    ///< wall-clock time of the generation [s]
};

/// Default jam_start_phi of a 3D packing input (spheres jam near 0.64) [-].
inline constexpr double kJamStartPhi3D = 0.55;

/// Largest number of disks any reader or the generator accepts [-].
inline constexpr std::int64_t kMaxDisks = 1'000'000;

/// Generates a packing with the DEM of docs/packing.md; reproducible from params.seed. Throws
/// InputError (key names the PackingParams field) when the parameters are inconsistent.
Packing generate_packing(const PackingParams& params);
/// Same, and fills `report` with the achieved packing fraction, overlaps, jamming fraction.
Packing generate_packing(const PackingParams& params, PackingReport& report);

/// Packing fraction: sum of disk areas pi r^2 / box area (3D: sphere volumes 4/3 pi r^3 / box
/// volume) [-].
double packing_fraction(const Packing& packing);
/// Mean disk diameter [m] (0 for an empty packing).
double mean_diameter(const Packing& packing);
/// Largest overlap between two disks (spheres) or one and a wall [m] (0 if none), by cell lists.
double max_overlap(const Packing& packing);

/// Writes the CSV packing file of docs/packing.md §6 (17 significant digits), atomically; a 3D
/// packing adds `# dimension = 3`, a six-number box and a z column.
void write_packing_csv(const Packing& packing, const std::string& path);
/// Reads a CSV packing file; throws InputError(file, line, column, expectation) on bad content.
/// Without a `# box =` comment the box is the bounding box of the disks. 3D when the file says
/// `# dimension = 3` or (without a dimension line) its header has a z column.
Packing read_packing_csv(const std::string& path);
/// Parses the text of a CSV packing file; `path` names it in messages (throws InputError).
Packing parse_packing_csv(std::string_view text, const std::string& path);
/// Writes a VTU point cloud: points = centers [m], arrays radius [m], diameter [m], id [-].
void write_packing_vtu(const Packing& packing, const std::string& path);
/// One-line summary: grains, achieved phi, largest overlap / mean diameter.
std::string summary_line(const Packing& packing);

}  // namespace mpmcd::packing
