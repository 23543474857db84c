#pragma once
/// The compaction observables of a run (docs/observables.md): extra CSV columns (box height, ε, Φ,
/// Vs, ln(Vs/Vs0), wall stresses, σ/M_p of the bottom wall, Love-Weber stress, coverage of the
/// box by the point domains, coordination Z)
/// and the [stop] criteria. Wires analysis/ to the model and the solver; used by run_simulation.
/// In 3D (six walls, normals ±x, ±y, ±z) the box columns are h, width, depth, the box volume, ε,
/// Φ, Vs, ln(Vs/Vs0), the wall stresses (force over face area) and the six Love-Weber
/// components, the coverage on cubic voxels of side h/8, and Z (from the per-pair normal
/// impulses); `[output] grains` adds the grain-scale columns in 2D and 3D.
#include <optional>
#include <string>
#include <vector>

#include "mpmcd/analysis/observables.hpp"
#include "mpmcd/io/config.hpp"
#include "mpmcd/mpm/model.hpp"
#include "mpmcd/mpm/solver.hpp"
#include "mpmcd/walls/wall.hpp"

namespace mpmcd::app {

/// Observables of a compaction, measured on the committed state (Dim = 2 or 3).
template <int Dim = 2>
class CompactionObserver {
 public:
  /// Reads the walls, the grains' moduli and the initial box and grain area from the model at
  /// t = 0 (call before the first step).
  CompactionObserver(const io::Config& config, const mpm::Model<Dim>& model);

  /// The extra CSV header, starting with a comma: the box columns if the walls form a box, the
  /// Z columns if contact is on ("" if neither, so runs without walls keep their columns), and
  /// with `[output] grains` the grain-scale columns (grain_csv_header).
  std::string csv_header() const;

  /// The extra CSV fields of the committed state at time t [s], starting with a comma; `step` is
  /// the last converged step (wall forces), `problem` its contact problem (Z).
  std::string csv_fields(const mpm::Model<Dim>& model, const mpm::StepStats& step,
                         const contact::Problem<Dim>& problem, double t) const;

  /// The first [stop] criterion reached by the committed state at time t [s] (a sentence for the
  /// log), or nullopt.
  std::optional<std::string> stop_reason(const mpm::Model<Dim>& model, const mpm::StepStats& step,
                                         double t) const;
  /// The same with the grains' current area V_s [m^2] given (several ranks: the sum over ranks of
  /// grain_areas, so that no rank needs every point).
  std::optional<std::string> stop_reason(double grain_area, const mpm::StepStats& step,
                                         double t) const;

  /// What the progress line shows of the committed state at time t [s].
  struct Now {
    double phi = 0;            ///< solid fraction Φ = Vs/V [-]
    double strain = 0;         ///< |ε| = |ln(h/h0)| [-]
    double bottom_stress = 0;  ///< normal stress on the bottom wall (compression < 0) [Pa]
    double top_stress = 0;     ///< normal stress on the top wall (compression < 0) [Pa]
  };
  /// Φ, |ε| and the bottom and top wall stresses with the grains' area `grain_area` [m^2] (as in
  /// stop_reason); nullopt when the walls do not form a box.
  std::optional<Now> now(double grain_area, const mpm::StepStats& step, double t) const;
  /// Solid fraction Φ0 at t = 0 (V_s0 over the initial box) [-]; 0 without a box.
  double initial_phi() const;
  /// Coordination number Z of the contact network of `problem` [-]; nullopt without contact.
  std::optional<double> coordination(const contact::Problem<Dim>& problem) const;

  /// Current area of each grain, sum of its points' V_p [m^2]; with `owner`, only the grains
  /// with owner[g] == rank (0 for the others).
  static std::vector<double> grain_areas(const mpm::Model<Dim>& model,
                                         const std::vector<int>* owner = nullptr, int rank = 0);
  /// V_s = sum over grains, in grain order, of grain_areas [m^2]: the association every V_s of a
  /// run uses, so that per-grain sums gathered from several ranks give the same bits.
  static double total_area(const std::vector<double>& areas);

  /// Follows walls whose motion is not their input's constant velocity (app::WallLoading): the
  /// box is then that of `walls` (same order as the input's [[walls]]).
  void move_walls(const std::vector<walls::Wall<Dim>>& walls);

  /// Replaces V_s0, the grains' area at t = 0 [m^2] (a restarted run must pass the value of the
  /// original start, e.g. from the first CSV row, since the constructor measures the model it is
  /// given; the box at t = 0 follows from the walls and needs nothing).
  void set_initial_grain_area(double vs0) { vs0_ = vs0; }

  /// The grains' area V_s0 at t = 0 used for ln(V_s/V_s0) [m^2].
  double initial_grain_area() const { return vs0_; }

  /// True when the walls form a box (h, ε, Φ and the stresses are measured).
  bool has_box() const { return box_.has_value(); }

  /// The grains' P-wave modulus M_p (Law::wave_modulus, λ + 2μ) [Pa], or nullopt if the grains'
  /// materials differ in M_p or K_p (docs/observables.md).
  std::optional<double> p_wave_modulus() const { return mp_; }

 private:
  const io::Config& config_;
  std::vector<walls::Wall<Dim>> walls_;
  std::optional<analysis::BoxWalls> box_;
  analysis::Box box0_;
  double vs0_ = 0;
  std::optional<double> mp_;
  bool contact_ = false;
  std::int64_t grains_ = 0;
  double pixel_ = 0;  ///< pixel (3D: voxel) side of the coverage raster, h/8 [m]
};

/// Deduces the dimension from the model.
template <int Dim>
CompactionObserver(const io::Config&, const mpm::Model<Dim>&) -> CompactionObserver<Dim>;

extern template class CompactionObserver<2>;
extern template class CompactionObserver<3>;

}  // namespace mpmcd::app
