#pragma once
/// The validated simulation input as plain data (SI units). Filled by io::load_config from one
/// TOML file: each key of the schema (io/config.cpp) is bound to the member it fills here, and
/// every key is documented in docs/input.md, generated from that schema. The initial values below
/// are the defaults of absent keys, and the schema documents them from here (the defaults that
/// depend on other keys, e.g. time.dt_min = dt/1024, are set by the reader).
#include <algorithm>
#include <array>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace mpmcd::io {

/// [simulation]: global settings.
struct SimulationSection {
  std::string name = "mpmcd";  ///< run name used in output file names [-]
  int dimension = 2;           ///< spatial dimension (2 = plane strain, 3 = 3D) [-]
  int threads = 0;             ///< OpenMP threads, 0 = OpenMP default [-]
};

/// [grid]: the uniform background grid.
struct GridSection {
  std::vector<double> origin;             ///< lower corner of the grid [m], Dim entries
  std::vector<double> extent;             ///< size of the grid along each axis [m], Dim entries
  double cell_size = 0.0;                 ///< cell edge length h [m]
  std::string shape_function = "linear";  ///< "linear", "ugimp" or "cpdi"
  bool split_points = true;  ///< split points whose CPDI domain outgrows its window [-]
};

/// [[materials]]: a named material, its constitutive law and the law's parameters.
struct MaterialSection {
  std::string name;      ///< name referenced by grains [-]
  std::string law;       ///< law name from the materials registry [-]
  double density = 0.0;  ///< initial mass density rho0 [kg/m^3]
  std::map<std::string, double>
      params;             ///< law parameters by name, SI units (e.g. lambda, mu [Pa])
  std::int64_t line = 0;  ///< line of the table in the input (for later errors)
};

/// Initial velocity field of a grain: v(x) = velocity + gradient (x - center)
///   + sine_amplitude * sin(sine_wavevector . (x - origin) + sine_phase).
struct InitialVelocity {
  std::vector<double> velocity;        ///< uniform part [m/s], Dim entries (default 0)
  std::vector<double> gradient;        ///< velocity gradient L, row-major Dim*Dim [1/s] (default 0)
  double angular_velocity = 0.0;       ///< rigid spin about the grain center (2D) [rad/s]
  std::vector<double> sine_amplitude;  ///< amplitude of the sine part [m/s], Dim entries
  std::vector<double> sine_wavevector;  ///< wave vector k of the sine part [rad/m], Dim entries
  double sine_phase = 0.0;              ///< phase of the sine part [rad]
};

/// [[grains]]: one grain (a body made of material points).
struct GrainSection {
  std::string shape;     ///< "disk", "rectangle", "packing" (2D); "sphere", "box" (3D)
  std::string material;  ///< material name [-]
  std::string file;      ///< packing file (shape "packing"), resolved against the input's folder
  std::vector<double> center;      ///< disk or sphere center [m] (disk, sphere)
  double radius = 0.0;             ///< disk or sphere radius [m] (disk, sphere)
  std::vector<double> min_corner;  ///< lower corner [m] (rectangle, box)
  std::vector<double> max_corner;  ///< upper corner [m] (rectangle, box)
  int points_per_cell = 2;         ///< material points per cell along each axis [-]
  std::string seeding;      ///< "lattice" or "polar" (disks, packings); default polar for disks
  InitialVelocity initial;  ///< initial velocity field
  std::int64_t line = 0;    ///< line of the table in the input
};

/// [[boundary]]: prescribed nodal velocity components on a set of grid nodes.
struct BoundarySection {
  std::string nodes;             ///< "xmin","xmax","ymin","ymax","zmin","zmax","all" or "box"
  std::vector<double> box_min;   ///< lower corner of the node box [m] (nodes = "box")
  std::vector<double> box_max;   ///< upper corner of the node box [m] (nodes = "box")
  std::vector<std::string> fix;  ///< prescribed components: subset of "x","y","z"
  std::vector<double> velocity;  ///< prescribed velocity [m/s], Dim entries (free ones ignored)
  bool moving = false;           ///< box translates with `velocity` (grid platen) [-]
  std::int64_t line = 0;         ///< line of the table in the input
};

/// [loads]: body forces.
struct LoadsSection {
  std::vector<double> gravity;  ///< gravitational acceleration [m/s^2], Dim entries (default 0)
};

/// [time]: implicit theta-method time stepping (method.md §2).
struct TimeSection {
  double dt = 0.0;          ///< nominal time step [s]
  double end_time = 0.0;    ///< simulated time at which the run stops [s]
  double theta = 1.0;       ///< theta of the theta-method, in [0.5, 1] [-]
  double dt_min = 0.0;      ///< smallest step allowed after cuts [s] (default dt/1024)
  double cut_factor = 0.5;  ///< factor applied to dt when a step fails, in (0, 1) [-]
  int recover_steps = 20;   ///< successful steps after which a cut dt may grow again [-]
  /// "fixed" (dt, cut on failure) or "newton" (dt follows the Newton count, docs/robustness.md) [-]
  std::string control = "fixed";
  double dt_max = 0.0;        ///< largest step with control = "newton" [s] (default dt)
  int target_iterations = 6;  ///< Newton iterations per step that control = "newton" aims at [-]

  /// The largest step of the run: dt_max (at least dt) with control = "newton", else dt [s].
  double largest_dt() const { return control == "newton" ? std::max(dt, dt_max) : dt; }
};

/// [solver]: Newton-Raphson and linear solver settings.
struct SolverSection {
  int max_iterations = 25;             ///< Newton iterations before the step is declared failed [-]
  double residual_tolerance = 1e-8;    ///< relative residual tolerance (floor ~1e-10: F near I) [-]
  double increment_tolerance = 1e-8;   ///< relative velocity-increment tolerance [-]
  std::string linear_solver = "ldlt";  ///< "ldlt" (sparse direct), "lu" or "cg" (Jacobi CG)
  double cg_tolerance = 1e-12;         ///< relative residual of the CG solve [-]
  int cg_max_iterations = 1000;        ///< CG iteration limit [-]
  double flip = 1.0;            ///< FLIP fraction of the G2P velocity update (1 = FLIP, 0 = PIC)
  bool affine = false;          ///< affine P2G with the points' velocity gradients (APIC/TPIC)
  bool modified_newton = true;  ///< reuse the step's first factorisation (modified Newton)
  /// Grains whose sparse factor fills at least this fraction of its triangle are factorised
  /// dense (Settings::dense_fill; above 1: never) [-].
  double dense_fill = 2.0;
};

/// [[contact.pairs]]: friction between two materials.
struct ContactPairSection {
  std::vector<std::string> materials;  ///< the two material names (may be equal)
  double friction = 0.0;               ///< Coulomb coefficient mu_f [-]
  std::int64_t line = 0;               ///< line of the table in the input
};

/// [contact]: Contact Dynamics between grains and with walls (method.md §4).
struct ContactSection {
  bool enabled = true;            ///< solve contacts (grain-grain and grain-wall) [-]
  std::string criterion = "gap";  ///< "gap" (points' domains) or "overlap" (support overlap)
  std::string law = "coulomb";    ///< contact law (contact/law.hpp registry name) [-]
  double friction = 0.0;          ///< default grain-grain Coulomb coefficient [-]
  double mass_fraction = 1e-4;    ///< contact node: field mass above this fraction of a cell's [-]
  double tolerance = 1e-8;        ///< Gauss-Seidel error tolerance [-]
  int max_sweeps = 1000;          ///< Gauss-Seidel sweep limit [-]
  double relaxation = 1.0;        ///< over-relaxation of frictionless contacts (projected SOR) [-]
  int relax_after = 0;            ///< Gauss-Seidel sweeps before the over-relaxation starts [-]
  bool node_blocks = true;        ///< solve each node's frictionless contacts together [-]
  double impulse_tolerance = 1e-6;  ///< relative impulse change between Newton iterations [-]
  double wall_range = 1.0;          ///< grain nodes within this many cells of a wall take part [-]
  double gap_horizon = 4.0;  ///< steps within which a grain face's gap must be able to close [-]
  std::string face_normals =
      "start";  ///< grain faces' normals: "end" (at F^{n+1}) or "start" (F^n)
  std::string wall_contact = "nodes";     ///< where walls act: "nodes" or "points" (point faces)
  std::string grain_contact = "nodes";    ///< where grains meet: "nodes" or "faces" (point faces)
  std::string solver = "gauss_seidel";    ///< contact solver: "gauss_seidel" or "active_set" [-]
  std::string delassus = "auto";          ///< "grain" (exact grain compliance), "lumped" or "auto"
  std::vector<ContactPairSection> pairs;  ///< per material-pair friction
};

/// [[walls]]: a rigid plane wall of infinite mass with a prescribed velocity.
struct WallSection {
  std::string name;              ///< name used in the CSV columns [-]
  std::vector<double> point;     ///< a point of the plane at t = 0 [m], Dim entries
  std::vector<double> normal;    ///< normal pointing into the domain (normalised) [-], Dim entries
  std::vector<double> velocity;  ///< prescribed velocity [m/s], Dim entries (default 0)
  double friction = 0.0;         ///< Coulomb coefficient with the grains [-]
  std::int64_t line = 0;         ///< line of the table in the input
};

/// [[loading.stages.walls]]: what one wall does during a stage (docs/loading.md). `velocity`
/// prescribes the wall's whole velocity; `stress` drives its normal motion by the servo toward a
/// target normal stress (then `velocity` may only give a tangential slide).
struct StageWallSection {
  std::string name;              ///< name of a [[walls]] entry [-]
  std::vector<double> velocity;  ///< target velocity [m/s], Dim entries (empty: not given)
  double stress = 0.0;           ///< target normal stress, compression negative [Pa]
  bool has_stress = false;       ///< `stress` was given [-]
  std::int64_t line = 0;         ///< line of the table in the input
};

/// [loading.stages.until]: when a stage ends (the first condition reached; none: at end_time).
/// Φ, ε and the wall stress end the stage when they cross the value from their stage-start side.
struct StageUntilSection {
  double time = 0.0;        ///< stage duration [s] (0: not set)
  double phi = 0.0;         ///< solid fraction Φ to cross [-] (0: not set)
  double strain = 0.0;      ///< ε = ln(h/h0) to cross (compression negative) [-]
  bool has_strain = false;  ///< `strain` was given [-]
  double stress = 0.0;      ///< normal stress of wall `wall` to cross, compression negative [Pa]
  bool has_stress = false;  ///< `stress` was given [-]
  std::string wall;         ///< the wall whose stress `stress` watches [-]
  std::int64_t line = 0;    ///< line of the table in the input
};

/// [[loading.stages]]: one loading stage.
struct StageSection {
  std::string name;                     ///< name shown in the log [-] (default "stage <k>")
  double ramp = 0.0;                    ///< time over which the targets go linearly to theirs [s]
  StageUntilSection until;              ///< end conditions
  bool has_until = false;               ///< an [until] table was given [-]
  std::vector<StageWallSection> walls;  ///< the walls whose control changes
  std::int64_t line = 0;                ///< line of the table in the input
};

/// [loading]: wall motions by stages, velocity- or stress-controlled (replaces the walls'
/// constant velocities when present; docs/loading.md).
struct LoadingSection {
  double gain = 0.0;  ///< servo gain g, v_n = g (σ_measured - σ_target) [m/(s Pa)] (0: auto)
  double gain_fraction = 0.25;       ///< auto gain: this fraction of min(dt/(ρ h), h/(M_p dt)) [-]
  double max_speed = 0.0;            ///< speed limit of a servo wall [m/s] (0: auto)
  double integral_time = 0.0;        ///< servo integral time T_i [s] (0: proportional servo only)
  std::vector<StageSection> stages;  ///< the stages, in order
  bool present = false;              ///< the [loading] table was given [-]
  std::int64_t line = 0;             ///< line of the table in the input
};

/// [stop]: optional stop criteria of a compaction (need four walls forming a box); the run stops
/// at the first one reached or at [time] end_time (docs/observables.md). 0 = not set.
struct StopSection {
  double phi = 0.0;       ///< stop when the solid fraction Φ >= phi [-]
  double strain = 0.0;    ///< stop when |ε| = |ln(h/h0)| >= strain [-]
  double stress = 0.0;    ///< stop when the bottom wall's compressive stress -σ >= stress [Pa]
  std::int64_t line = 0;  ///< line of the table in the input
};

/// [output]: where and how often to write.
struct OutputSection {
  std::string folder = "output";   ///< output folder (created) [-]
  double vtu_interval = 0.0;       ///< simulated time between VTU snapshots [s], 0 = every step
  double csv_interval = 0.0;       ///< simulated time between CSV rows [s], 0 = every step
  bool vtu = true;                 ///< write VTU/PVD files [-]
  double progress_interval = 2.0;  ///< wall time between progress lines [s]
  /// Grain-scale outputs: per-grain and contact-force CSVs at snapshot times, fabric and stress
  /// columns in the CSV time series (docs/observables.md) [-].
  bool grains = false;
};

/// [checkpoint]: when to write restart files (docs/robustness.md). A checkpoint is also written
/// on SIGINT/SIGTERM and on a numerical failure, whatever these settings.
struct CheckpointSection {
  std::int64_t every_steps = 0;  ///< committed steps between checkpoints, 0 = never [-]
  double every_minutes = 30.0;   ///< wall-clock time between checkpoints, 0 = never [min]
  int keep = 2;                  ///< checkpoints kept in the output folder (oldest deleted) [-]
  bool at_end = true;            ///< write one when the run reaches end_time [-]
};

/// The whole validated input.
struct Config {
  std::string source_path;                  ///< path of the TOML file it came from
  std::string source_text;                  ///< its full text (copied to the output folder)
  SimulationSection simulation;             ///< [simulation]: name, dimension, threads
  GridSection grid;                         ///< [grid]: the background grid
  std::vector<MaterialSection> materials;   ///< [[materials]], in input order
  std::vector<GrainSection> grains;         ///< [[grains]], in input order
  std::vector<BoundarySection> boundaries;  ///< [[boundary]], in input order
  LoadsSection loads;                       ///< [loads]: body forces
  TimeSection time;                         ///< [time]: time stepping
  SolverSection solver;                     ///< [solver]: Newton and linear solver
  ContactSection contact;                   ///< [contact]: Contact Dynamics
  std::vector<WallSection> walls;           ///< [[walls]], in input order
  LoadingSection loading;                   ///< [loading]: wall loading stages
  StopSection stop;                         ///< [stop]: compaction stop criteria
  OutputSection output;                     ///< [output]: output files
  CheckpointSection checkpoint;             ///< [checkpoint]: restart files
};

}  // namespace mpmcd::io
