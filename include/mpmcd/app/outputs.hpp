#pragma once
/// The files a run writes in its output folder (README, "Outputs"): the CSV time series, the VTU
/// snapshots of the points and of the contacts with their PVD series and per-pair force CSVs, the
/// stamped input copy and the last good state of a failed run. A restart continues them: the CSV
/// is trimmed to the checkpoint's rows and the series list the snapshots written before it.
#include <cstdint>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "mpmcd/checkpoint/checkpoint.hpp"
#include "mpmcd/contact/problem.hpp"
#include "mpmcd/io/config.hpp"
#include "mpmcd/io/vtu.hpp"
#include "mpmcd/mpm/model.hpp"
#include "mpmcd/mpm/solver.hpp"

namespace mpmcd::app {

/// Writes one VTU snapshot of the points at `path` (velocity, full 3x3 stress (2D: with
/// sigma_zz), pressure -tr(sigma)/3, J, mass, volume, grain, domain edges e1..eDim).
template <int Dim>
void write_points_vtu(const mpm::Model<Dim>& model, const std::string& path);

/// Writes the contacts of `problem` as points at their nodes to `vtu_path` (normal, normal and
/// tangential impulse, force, gap, the two bodies; walls as -1 - index) and the force per pair of
/// bodies, sum P / dt, to the CSV `csv_path`.
template <int Dim>
void write_contacts(const mpm::Model<Dim>& model, const contact::Problem<Dim>& problem,
                    const std::string& vtu_path, const std::string& csv_path);

/// Keeps the header and the first `rows` complete rows of the CSV at `path` (drops the rows
/// written after a checkpoint and a torn last line); returns the rows kept [-].
std::int64_t trim_csv(const std::string& path, std::int64_t rows);

/// The output files of one run (rank 0 writes them).
class Outputs {
 public:
  /// Creates the folder `dir` and writes the input copy and the CSV header; `extra_header`:
  /// further CSV columns (CompactionObserver, energy ledger), starting with a comma; `restart`:
  /// the checkpoint a restarted run continues (nullptr: a new run); `history`: the checkpoint's
  /// folder when the restart writes to another folder ("" otherwise), from which the outputs
  /// written before the checkpoint are copied so that the new folder holds the whole run.
  Outputs(const io::Config& config, const std::string& dir, const std::string& extra_header,
          const checkpoint::State* restart, const std::string& history = "");

  /// Restores the contact series of a restart (only runs with contact write it).
  template <int Dim>
  void restore_contacts(const mpm::ImplicitSolver<Dim>& solver);
  /// Appends the CSV row of the committed state at `step`, time t [s], step dt [s]: the step's
  /// statistics `stats`, the diagnostics `d` and the `extra` fields (starting with a comma).
  template <int Dim>
  void csv_row(std::int64_t step, double t, double dt, const mpm::StepStats& stats,
               const mpm::Diagnostics<Dim>& d, const std::string& extra);
  /// Writes the snapshot of time t [s]: the points, and with contact the contacts of `problem`
  /// and the per-pair forces; adds them to the series. With `[output] grains`, also the
  /// per-grain and contact-force CSVs (grain_outputs.hpp), even when `[output] vtu` is off.
  template <int Dim>
  void vtu(const mpm::Model<Dim>& model, const mpm::ImplicitSolver<Dim>& solver,
           const contact::Problem<Dim>& problem, double t);
  /// Writes `<name>_last_good.vtu` of the points of `model`; returns its path.
  template <int Dim>
  std::string last_good(const mpm::Model<Dim>& model);

  /// CSV rows written so far (header excluded) [-].
  std::int64_t csv_rows() const { return csv_rows_; }
  /// Times of the VTU snapshots written so far [s].
  const std::vector<double>& vtu_times() const { return vtu_times_; }
  /// The output folder.
  const std::string& dir() const { return dir_; }

 private:
  // Copies the outputs written up to the checkpoint from its folder `from`: the CSV (trimmed
  // later to the checkpoint's rows) and every snapshot (points, contacts, pairs) it lists.
  void copy_history(const std::string& from, const checkpoint::State& restart);
  // One whole row per write, flushed: a crash leaves complete rows (a torn last line, possible
  // only if the disk fills up, is dropped on restart).
  void write_row(const std::string& row);

  const io::Config& cfg_;
  std::string dir_, csv_path_;
  int dim_ = 2;  // [simulation] dimension: the CSV's momentum and wall-force columns
  std::ofstream csv_;
  std::unique_ptr<io::PvdSeries> pvd_, contacts_pvd_;
  int vtu_count_ = 0;
  std::int64_t csv_rows_ = 0;
  std::vector<double> vtu_times_;
};

}  // namespace mpmcd::app
