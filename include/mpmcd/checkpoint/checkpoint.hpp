#pragma once
/// Checkpoint files (HDF5, docs/robustness.md): everything a run needs to continue bitwise, as
/// plain arrays. Written atomically (temporary file, fsync, rename); the first 512 bytes of the
/// file are an HDF5 user block holding a text header with the file size and an FNV-1a checksum of
/// the whole file (header and its padding included), verified before libhdf5 parses anything, so
/// a truncated or corrupted file is refused with an InputError and never loaded.
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace mpmcd::checkpoint {

/// Layout version of the files this build writes and reads [-].
inline constexpr std::int32_t kFormatVersion = 8;

/// Oldest layout version this build still reads (version 6: no wall loading) [-].
inline constexpr std::int32_t kOldestFormatVersion = 6;

/// Size of the text header (HDF5 user block) before the HDF5 data [bytes].
inline constexpr std::size_t kHeaderBytes = 512;

/// FNV-1a 64-bit offset basis (start value of fnv1a) [-].
inline constexpr std::uint64_t kFnvOffset = 14695981039346656037ull;

/// FNV-1a 64-bit hash of `bytes`, continuing from `hash` [-].
std::uint64_t fnv1a(std::string_view bytes, std::uint64_t hash = kFnvOffset);

/// The state of a run after a committed step. Arrays are flat, point-major: x[p * dim + d],
/// F[(p * dim + i) * dim + j]. Units are those of points::PointSet and the input (SI).
struct State {
  // Identity.
  std::int32_t dim = 2;          ///< spatial dimension [-]
  std::string mpmcd_version;     ///< version and git hash of the writer (set by write) [-]
  std::string input_text;        ///< the full input text of the run [-]
  std::string input_path;        ///< path the input was read from (relative paths resolve) [-]
  std::uint64_t input_hash = 0;  ///< fnv1a(input_text) (set by write) [-]
  std::string reason;            ///< why written: "periodic", "end", "signal", "failure" [-]
  // Time stepping.
  std::int64_t step = 0;               ///< committed steps [-]
  double time = 0;                     ///< simulated time t^n [s]
  double dt = 0;                       ///< current (possibly cut) time step [s]
  std::int64_t good_since_cut = 0;     ///< good steps since the last dt cut [-]
  std::int64_t failed_steps = 0;       ///< attempts retried with a smaller dt so far [-]
  std::int64_t newton_iterations = 0;  ///< Newton iterations so far [-]
  // Output counters.
  double next_vtu = 0;            ///< simulated time of the next VTU snapshot [s]
  double next_csv = 0;            ///< simulated time of the next CSV row [s]
  std::int64_t csv_rows = 0;      ///< CSV rows written so far (header excluded) [-]
  std::vector<double> vtu_times;  ///< time of each VTU snapshot written so far [s]
  // Material points (points::PointSet).
  std::vector<double> x;            ///< positions, n x dim [m]
  std::vector<double> v;            ///< velocities, n x dim [m/s]
  std::vector<double> L;            ///< velocity gradients (affine P2G), n x dim x dim [1/s]
  std::vector<double> F;            ///< deformation gradients, n x dim x dim [-]
  std::vector<double> sigma;        ///< Cauchy stresses, n x dim x dim [Pa]
  std::vector<double> domain;       ///< reference domain half-edges (columns), n x dim x dim [m]
  std::vector<double> sigma_zz;     ///< out-of-plane stress (plane strain), n [Pa]
  std::vector<double> mass;         ///< masses, n [kg] (2D: kg/m)
  std::vector<double> volume0;      ///< initial volumes, n [m^dim]
  std::vector<double> volume;       ///< current volumes, n [m^dim]
  std::vector<std::int32_t> grain;  ///< grain of each point, n [-]
  std::vector<double> history;      ///< law history variables (any length) [law units]
  // Grains (points::Grain).
  std::vector<std::int64_t> grain_begin;           ///< first point of each grain [-]
  std::vector<std::int64_t> grain_end;             ///< one past the last point [-]
  std::vector<std::int32_t> grain_material;        ///< material index [-]
  std::vector<double> grain_half_width;            ///< uGIMP half-width [m]
  std::vector<std::int64_t> grain_history_offset;  ///< first history entry [-]
  // Contact warm start: impulses of the last converged step, keyed by (node, body a, grain b).
  std::vector<std::int64_t> warm_node;  ///< global grid node [-]
  std::vector<std::int32_t> warm_a;     ///< body a: grain >= 0, wall -1 - index [-]
  std::vector<std::int32_t> warm_b;     ///< grain b [-]
  std::vector<double> warm_impulse;     ///< impulse on b, count x dim [N s] (2D: N s/m)
  // Walls (their position is point + velocity t; stored to check and inspect).
  std::vector<double> wall_point;   ///< current point of each wall plane, walls x dim [m]
  std::vector<double> wall_work;    ///< work done by each wall on the grains so far [J] (2D: J/m)
  double energy0 = 0;               ///< elastic + kinetic energy at t = 0 [J] (2D: J/m)
  double contact_dissipation = 0;   ///< energy dissipated by contact since t = 0 [J] (2D: J/m)
  double kinetic0 = 0;              ///< kinetic energy at t = 0 [J] (2D: J/m)
  double transfer_dissipation = 0;  ///< kinetic energy lost by P2G and G2P since t = 0 [J]
  double stress_work = 0;  ///< work of the internal forces on the grid since t = 0 [J] (2D: J/m)
  double body_work = 0;    ///< work of the body forces on the grid since t = 0 [J] (2D: J/m)
  // Wall loading ([loading], docs/loading.md; empty without it, and in version 6 files).
  /// Current stage index, its start time [s], and Phi [-], eps [-] and the until-wall stress
  /// [Pa] at its start (5 values) [-].
  std::vector<double> loading_stage;
  /// Per wall, app::WallProgram's control: 0 velocity, 1 stress [-].
  std::vector<std::int32_t> loading_control;
  /// Per wall, 4 dim + 5 values (13 in 2D, 17 in 3D; format 7: 4 dim + 4, no integral): the
  /// program's v_from (dim) [m/s], v_to (dim) [m/s], s_from, s_to [Pa], t_start, ramp [s]; the
  /// velocity of the last step (dim) [m/s]; the force of the grains on it in the last step (dim)
  /// [N] (2D: N/m); the servo integral [Pa s]; its position is wall_point.
  std::vector<double> loading_wall;
  // Distribution (docs/parallel.md): restored when the rank count and scheme are the same.
  std::int32_t ranks = 1;                 ///< MPI ranks of the writing run [-]
  std::string scheme = "partition";       ///< parallel scheme of the writing run [-]
  std::int32_t threads = 1;               ///< OpenMP threads per rank of the writing run [-]
  std::vector<std::int32_t> grain_owner;  ///< rank owning each grain, per grain [-]
  /// Re-balancing work since the last check, grain x parallel::kWorkPhases (grain-major) [-].
  std::vector<double> grain_work;

  /// Number of material points [-].
  std::size_t points() const { return grain.size(); }
};

/// The kHeaderBytes-byte header of a checkpoint whose HDF5 part (everything after the header) is
/// `body`: "MPMCD-CHECKPOINT <version>\nbytes <body size>\nfnv1a64 <16 hex digits>\n" padded
/// with NUL bytes, the digits being the FNV-1a hash of the whole file (this header, padding
/// included, with the 16 digits read as '0', then `body`) [-]. For tests and fuzzing: write()
/// seals its files so.
std::string header_for(std::string_view body);

/// Checksum of the payload (every array and counter, in a fixed order, native bytes) [-].
std::uint64_t payload_checksum(const State& state);

/// Writes `state` to `path` atomically: "<path>.tmp", fsync, rename, fsync of the folder. Sets
/// nothing in `state`; the file records kFormatVersion, the mpmcd version and fnv1a(input_text).
/// Throws std::runtime_error when the file cannot be written.
void write(const State& state, const std::string& path);

/// Reads and validates a checkpoint: header, size and checksum of the file, format version, every
/// dataset present with the right type and size, consistent grains, payload checksum. Throws
/// InputError(path, 0, dataset, what is wrong) for anything else; never returns partial data.
State read(const std::string& path);

/// File name of the checkpoint of run `name` after `step` steps: "<name>_checkpoint_<step>.h5"
/// with the step zero-padded to 9 digits [-].
std::string file_name(const std::string& name, std::int64_t step);

/// Checkpoints of run `name` in `folder` (complete files only, no ".tmp"), oldest step first.
std::vector<std::string> list(const std::string& folder, const std::string& name);

/// Deletes the oldest checkpoints of run `name` in `folder` so that at most `keep` remain, and
/// any leftover "<checkpoint>.tmp" of an interrupted write.
void prune(const std::string& folder, const std::string& name, int keep);

}  // namespace mpmcd::checkpoint
