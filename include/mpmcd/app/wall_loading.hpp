#pragma once
/// Wall loading in stages ([loading], docs/loading.md): each wall is velocity- or
/// stress-controlled; a stress-controlled wall is a servo, its normal velocity over the next step
/// v_n = clamp(g (e + I/T_i), -v_max, v_max), e = sigma_measured - sigma_target, I the time
/// integral of e (integral_time T_i > 0, else the term is absent), with sigma_measured the normal
/// stress of the wall's force in the last step (mpm::StepStats::wall_force over the wall's length
/// in the box, analysis::wall_normal_stress). Targets go linearly to a stage's values over its ramp
/// and are then held; a stage ends at the first of its `until` conditions. Explicit in the wall
/// velocity: the contact problem of a step sees walls of prescribed velocity, as without loading.
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "mpmcd/analysis/observables.hpp"
#include "mpmcd/core/types.hpp"
#include "mpmcd/io/config.hpp"
#include "mpmcd/mpm/model.hpp"
#include "mpmcd/mpm/settings.hpp"
#include "mpmcd/mpm/solver.hpp"
#include "mpmcd/walls/wall.hpp"

namespace mpmcd::app {

/// How a wall's motion is given.
enum class WallControl : std::int32_t {
  kVelocity = 0,  ///< a prescribed velocity
  kStress = 1,    ///< a target normal stress (servo), with a prescribed slide along the wall
};

/// A wall's program since the stage that last set it: its control and its targets, going
/// linearly from `from` to `to` over [t_start, t_start + ramp] and held after (Dim = 2 or 3).
template <int Dim>
struct WallProgram {
  WallControl control = WallControl::kVelocity;  ///< velocity or stress control
  Vec<Dim> v_from = Vec<Dim>::Zero();  ///< velocity (or slide, stress control) at t_start [m/s]
  Vec<Dim> v_to = Vec<Dim>::Zero();    ///< velocity (or slide) at the ramp's end [m/s]
  double s_from = 0.0;                 ///< target normal stress at t_start [Pa]
  double s_to = 0.0;                   ///< target normal stress at the ramp's end [Pa]
  double t_start = 0.0;                ///< start of the ramp [s]
  double ramp = 0.0;                   ///< duration of the ramp (0: a step) [s]
  /// Share of the ramp done at time t [s]: clamp((t - t_start)/ramp, 0, 1), 1 for ramp 0 [-].
  double share(double t) const;
  /// Target velocity (or slide) at time t [s] [m/s].
  Vec<Dim> velocity_at(double t) const { return v_from + share(t) * (v_to - v_from); }
  /// Target normal stress at time t [s] [Pa].
  double stress_at(double t) const { return s_from + share(t) * (s_to - s_from); }
};

/// What a checkpoint carries of the loading (plain data; app::run_state stores it).
template <int Dim>
struct LoadingState {
  std::int32_t stage = 0;    ///< current stage (== number of stages once all ended) [-]
  double stage_start = 0.0;  ///< time the current stage started [s]
  double phi0 = 0.0;         ///< Φ at the stage start (side of until.phi) [-]
  double eps0 = 0.0;         ///< ε at the stage start (side of until.strain) [-]
  double stress0 = 0.0;      ///< stress of until.wall at the stage start [Pa]
  std::vector<WallProgram<Dim>> programs;  ///< per wall
  std::vector<Vec<Dim>> position;  ///< per wall: a point of its plane at the current time [m]
  std::vector<Vec<Dim>> velocity;  ///< per wall: its velocity in the last step [m/s]
  std::vector<Vec<Dim>>
      force;  ///< per wall: force of the grains on it in the last step [N] (2D: N/m)
  /// Per wall: the servo's integral I of the stress error over time ([loading] integral_time;
  /// 0 when off or while velocity-controlled) [Pa s].
  std::vector<double> integral;
};

/// The walls' motion under [loading] (inactive without it: the walls keep their input velocity).
/// In 3D the box has six walls and a wall's stress is its normal force over its face area.
template <int Dim>
class WallLoading {
 public:
  /// From the input and the walls at t = 0 (the settings'); `model` gives the grains' density,
  /// P-wave modulus M_p and wave speed for the automatic gain and speed limit.
  WallLoading(const io::Config& config, const std::vector<walls::Wall<Dim>>& walls,
              const mpm::Model<Dim>& model);

  /// True when the input has [loading].
  bool active() const { return active_; }
  /// Servo gain g [m/(s Pa)].
  double gain() const { return gain_; }
  /// Speed limit of a stress-controlled wall [m/s].
  double max_speed() const { return max_speed_; }
  /// One line for the log: gain, speed limit and how they were chosen.
  std::string describe() const;

  /// Starts the first stage at t = 0 with the grains' area V_s [m^2] (a new run).
  void start(double grain_area);
  /// The walls for the step [t, t + dt] [s]: each at its position at t, with the velocity of its
  /// program (a servo's from the last step's force). A retried step calls it again.
  std::vector<walls::Wall<Dim>> step_walls(double t, double dt);
  /// The step [t, t + dt] given by the last step_walls has been committed with statistics `st`:
  /// positions advance, the force is kept for the next servo step.
  void committed(const mpm::StepStats& st, double dt);
  /// True when the current stage has an end condition on Φ (the caller then passes V_s).
  bool needs_area() const;
  /// Time at which the current stage ends by `until.time`, if it has one [s].
  std::optional<double> stage_end_time() const;
  /// After a committed step ending at time t [s] with grain area V_s [m^2] (needed only when
  /// needs_area()): ends the current stage if one of its conditions is reached and starts the
  /// next; returns a sentence for the log when a stage ended.
  std::optional<std::string> advance(double t, double grain_area);
  /// True once the last stage has ended.
  bool finished() const;
  /// Name of the current stage (the last one once finished) [-].
  const std::string& stage_name() const;

  /// The walls at time t [s] (after a committed step): the planes the outputs measure.
  std::vector<walls::Wall<Dim>> walls(double t) const;

  /// Extra CSV header, starting with a comma: `stage` and per wall its velocity of the last step
  /// and its target stress ("" when inactive).
  std::string csv_header() const;
  /// The extra CSV fields at time t [s] (after a committed step), starting with a comma.
  std::string csv_fields(double t) const;

  /// The state a checkpoint carries.
  const LoadingState<Dim>& state() const { return state_; }
  /// Continues from a checkpoint's state (a restart). Throws std::invalid_argument if it does
  /// not fit the input (wall count, stage index).
  void restore(LoadingState<Dim> state);

 private:
  // Normal stress of wall k from `force` over its length in the box at the current positions
  // (compression negative) [Pa].
  double measured_stress(std::size_t k) const;
  // The compaction state (Φ with V_s [m^2], ε) at the current positions.
  analysis::CompactionState compaction(double grain_area) const;
  // Starts stage `k` at time t [s].
  void begin_stage(std::size_t k, double t, double grain_area);
  // The box at the walls' current positions.
  analysis::Box box_now() const;

  bool active_ = false;
  const io::LoadingSection* section_ = nullptr;
  std::vector<walls::Wall<Dim>> walls0_;   // the walls at t = 0 (names, normals, friction)
  std::optional<analysis::BoxWalls> box_;  // which walls bound the box
  analysis::Box box0_;                     // the box at t = 0
  std::vector<std::size_t> until_wall_;    // per stage: index of until.wall (or 0)
  double gain_ = 0.0, max_speed_ = 0.0;
  double integral_time_ = 0.0;  // servo integral time T_i (0: off) [s]
  std::string gain_source_, speed_source_;
  double vs0_ = 0.0;       // grain area at t = 0 [m^2]
  double eps_time_ = 0.0;  // time tolerance of until.time [s]
  LoadingState<Dim> state_;
  std::vector<Vec<Dim>> pending_;  // velocities of the step being tried [m/s]
  // Servo walls of the step being tried: the stress error e [Pa] to integrate when committed,
  // 0 for a velocity-controlled wall or one at its speed limit (no wind-up).
  std::vector<double> pending_error_;
};

extern template struct WallProgram<2>;
extern template struct WallProgram<3>;
extern template class WallLoading<2>;
extern template class WallLoading<3>;

}  // namespace mpmcd::app
