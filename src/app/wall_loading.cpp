#include "mpmcd/app/wall_loading.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "mpmcd/app/speed_check.hpp"

namespace mpmcd::app {

namespace {

// The automatic speed limit as a fraction of the grains' slowest P-wave speed (docs/loading.md):
// a fifth of the speed above which a wall is reported as too fast (kFastWallFraction).
constexpr double kAutoSpeedFraction = 0.2 * kFastWallFraction;

// True when x has crossed `target` from the side `start` was on (x == target counts).
bool crossed(double start, double x, double target) {
  return start <= target ? x >= target : x <= target;
}

}  // namespace

template <int Dim>
double WallProgram<Dim>::share(double t) const {
  if (!(ramp > 0.0)) return 1.0;
  return std::clamp((t - t_start) / ramp, 0.0, 1.0);
}

template <int Dim>
WallLoading<Dim>::WallLoading(const io::Config& config, const std::vector<walls::Wall<Dim>>& walls,
                              const mpm::Model<Dim>& model)
    : active_(config.loading.present), section_(&config.loading), walls0_(walls) {
  box_ = analysis::find_box(walls);
  if (box_) box0_ = analysis::box_at(walls, *box_, 0.0);
  eps_time_ = 1e-9 * config.time.dt;
  const std::size_t nw = walls.size();
  state_.programs.assign(nw, WallProgram<Dim>{});
  state_.position.resize(nw);
  for (std::size_t k = 0; k < nw; ++k) state_.position[k] = walls[k].point;
  state_.velocity.assign(nw, Vec<Dim>::Zero());
  state_.force.assign(nw, Vec<Dim>::Zero());
  state_.integral.assign(nw, 0.0);
  pending_.assign(nw, Vec<Dim>::Zero());
  pending_error_.assign(nw, 0.0);
  integral_time_ = config.loading.integral_time;
  if (!active_) return;
  for (const auto& st : config.loading.stages) {
    std::size_t u = 0;
    for (std::size_t k = 0; k < nw; ++k)
      if (walls[k].name == st.until.wall) u = k;
    until_wall_.push_back(u);
  }
  // The grains' densest and stiffest material and slowest wave speed.
  double rho = 0, mp = 0, c_min = std::numeric_limits<double>::infinity();
  const auto c = wave_speeds(model);
  for (const auto& g : model.grains) {
    const auto m = static_cast<std::size_t>(g.material);
    rho = std::max(rho, model.densities[m]);
    mp = std::max(mp, model.laws[m]->wave_modulus());
    c_min = std::min(c_min, c[m]);
  }
  // Δt of the gain: the first step, and the largest one where the stiffness answers (Δt that
  // follows the Newton count grows up to dt_max).
  const double dt = config.time.dt, h = config.grid.cell_size;
  const double dt_max = config.time.largest_dt();
  if (config.loading.gain > 0) {
    gain_ = config.loading.gain;
    gain_source_ = "loading.gain";
  } else if (rho > 0 && mp > 0) {
    // docs/loading.md, "Gain": the servo's loop gain per step stays below one both where the
    // wall's first node row answers by its inertia (stress rho h dv / dt for a velocity change
    // dv) and where the cell next to the wall answers by its stiffness (M_p dt v / h).
    const double limit = std::min(dt / (rho * h), h / (mp * dt_max));
    gain_ = config.loading.gain_fraction * limit;
    gain_source_ = fmt::format(
        "{} min(dt/(rho h), h/(M_p dt{})) with rho = {:.6g} kg/m^3, M_p = {:.6g} Pa, dt = {:.6g} "
        "s{}, h = {:.6g} m",
        config.loading.gain_fraction, dt_max > dt ? "_max" : "", rho, mp, dt,
        dt_max > dt ? fmt::format(", dt_max = {:.6g} s", dt_max) : "", h);
  }
  if (config.loading.max_speed > 0) {
    max_speed_ = config.loading.max_speed;
    speed_source_ = "loading.max_speed";
  } else if (std::isfinite(c_min)) {
    max_speed_ = kAutoSpeedFraction * c_min;
    speed_source_ = fmt::format("{:.3g} c_p, c_p = {:.6g} m/s", kAutoSpeedFraction, c_min);
  }
}

template <int Dim>
std::string WallLoading<Dim>::describe() const {
  return fmt::format(
      "loading: {} stage(s); servo gain g = {:.6g} m/(s Pa) ({}), speed limit {:.6g} m/s ({}){}",
      section_->stages.size(), gain_, gain_source_, max_speed_, speed_source_,
      integral_time_ > 0 ? fmt::format(", integral time {:.6g} s", integral_time_) : "");
}

template <int Dim>
analysis::Box WallLoading<Dim>::box_now() const {
  // walls(t) anchors each wall at its current position at time t: the box at that same t.
  return analysis::box_at(walls(0.0), *box_, 0.0);
}

template <int Dim>
double WallLoading<Dim>::measured_stress(std::size_t k) const {
  if (!box_) return 0.0;
  const analysis::Box box = box_now();
  // sigma = F.n / L (docs/observables.md), F the force of the grains on the wall in the last
  // step (mpm::StepStats::wall_force), L the wall's length between its neighbours.
  return analysis::wall_normal_stress(state_.force[k], walls0_[k].normal,
                                      analysis::wall_length(box, *box_, k));
}

template <int Dim>
analysis::CompactionState WallLoading<Dim>::compaction(double grain_area) const {
  if (!box_) return {};
  return analysis::compaction_state(box_now(), box0_, grain_area, vs0_);
}

template <int Dim>
void WallLoading<Dim>::start(double grain_area) {
  if (!active_) return;
  vs0_ = grain_area;
  begin_stage(0, 0.0, grain_area);
}

template <int Dim>
void WallLoading<Dim>::begin_stage(std::size_t k, double t, double grain_area) {
  state_.stage = static_cast<std::int32_t>(k);
  state_.stage_start = t;
  if (k >= section_->stages.size()) return;
  const io::StageSection& st = section_->stages[k];
  const auto now = compaction(grain_area);
  state_.phi0 = st.until.phi > 0 ? now.phi : 0.0;
  state_.eps0 = now.strain;
  state_.stress0 = st.until.has_stress ? measured_stress(until_wall_[k]) : 0.0;
  for (const io::StageWallSection& e : st.walls) {
    std::size_t w = 0;
    while (walls0_[w].name != e.name) ++w;
    WallProgram<Dim>& prog = state_.programs[w];
    const Vec<Dim> n = walls0_[w].normal;
    const Vec<Dim> v_now = state_.velocity[w];
    Vec<Dim> v_to = Vec<Dim>::Zero();
    if (!e.velocity.empty())
      for (int a = 0; a < Dim; ++a) v_to[a] = e.velocity[static_cast<std::size_t>(a)];
    WallProgram<Dim> next;
    next.t_start = t;
    next.ramp = st.ramp;
    if (e.has_stress) {
      next.control = WallControl::kStress;
      // A wall that becomes a servo starts its integral from zero; one that stays a servo keeps
      // it (the lag it compensates goes on).
      if (prog.control != WallControl::kStress) state_.integral[w] = 0.0;
      // From the target held so far, or from the stress the wall measures if it moved at a
      // prescribed velocity; the slide from the velocity's tangential part.
      next.s_from = prog.control == WallControl::kStress ? prog.stress_at(t) : measured_stress(w);
      next.s_to = e.stress;
      next.v_from = v_now - v_now.dot(n) * n;
      next.v_to = v_to;
    } else {
      next.control = WallControl::kVelocity;
      state_.integral[w] = 0.0;
      next.v_from = v_now;
      next.v_to = v_to;
    }
    prog = next;
  }
}

template <int Dim>
std::vector<walls::Wall<Dim>> WallLoading<Dim>::step_walls(double t, double dt) {
  std::vector<walls::Wall<Dim>> out = walls0_;
  for (std::size_t k = 0; k < out.size(); ++k) {
    const WallProgram<Dim>& prog = state_.programs[k];
    Vec<Dim> v = prog.velocity_at(t + dt);
    pending_error_[k] = 0.0;
    if (prog.control == WallControl::kStress) {
      // The servo (docs/loading.md): v_n = clamp(g (e + I/T_i), +-v_max), e = sigma_measured -
      // sigma_target, positive into the domain, so a wall pressed less than its target advances.
      const Vec<Dim> n = walls0_[k].normal;
      const double e = measured_stress(k) - prog.stress_at(t + dt);
      const double wanted =
          gain_ * (integral_time_ > 0 ? e + state_.integral[k] / integral_time_ : e);
      const double vn = std::clamp(wanted, -max_speed_, max_speed_);
      // Conditional integration (anti-wind-up): not while the speed limit holds the wall.
      if (integral_time_ > 0 && vn == wanted) pending_error_[k] = e;
      v = (v - v.dot(n) * n) + vn * n;
    }
    pending_[k] = v;
    out[k].point = state_.position[k];
    out[k].t0 = t;
    out[k].velocity = v;
  }
  return out;
}

template <int Dim>
void WallLoading<Dim>::committed(const mpm::StepStats& st, double dt) {
  for (std::size_t k = 0; k < pending_.size(); ++k) {
    state_.position[k] += dt * pending_[k];
    state_.velocity[k] = pending_[k];
    state_.integral[k] += dt * pending_error_[k];
    state_.force[k] = Vec<Dim>::Zero();
    if (k < st.wall_force.size())
      for (int a = 0; a < Dim; ++a) state_.force[k][a] = st.wall_force[k][a];
  }
}

template <int Dim>
bool WallLoading<Dim>::needs_area() const {
  if (!active_ || finished()) return false;
  // The current stage's until.phi, or the next one's (whose start records the side of Phi).
  const auto k = static_cast<std::size_t>(state_.stage);
  return section_->stages[k].until.phi > 0 ||
         (k + 1 < section_->stages.size() && section_->stages[k + 1].until.phi > 0);
}

template <int Dim>
std::optional<double> WallLoading<Dim>::stage_end_time() const {
  if (!active_ || finished()) return std::nullopt;
  const auto& u = section_->stages[state_.stage].until;
  if (!(u.time > 0)) return std::nullopt;
  return state_.stage_start + u.time;
}

template <int Dim>
bool WallLoading<Dim>::finished() const {
  return active_ && static_cast<std::size_t>(state_.stage) >= section_->stages.size();
}

template <int Dim>
const std::string& WallLoading<Dim>::stage_name() const {
  const std::size_t k = std::min<std::size_t>(state_.stage, section_->stages.size() - 1);
  return section_->stages[k].name;
}

template <int Dim>
std::optional<std::string> WallLoading<Dim>::advance(double t, double grain_area) {
  if (!active_ || finished()) return std::nullopt;
  const std::size_t k = static_cast<std::size_t>(state_.stage);
  const io::StageSection& st = section_->stages[k];
  if (!st.has_until) return std::nullopt;
  const io::StageUntilSection& u = st.until;
  std::string why;
  const auto now = compaction(grain_area);
  if (u.time > 0 && t - state_.stage_start >= u.time - eps_time_)
    why = fmt::format("until.time reached: {:.9g} s in the stage", t - state_.stage_start);
  else if (u.phi > 0 && crossed(state_.phi0, now.phi, u.phi))
    why = fmt::format("until.phi reached: Phi = {:.6f} (target {})", now.phi, u.phi);
  else if (u.has_strain && crossed(state_.eps0, now.strain, u.strain))
    why = fmt::format("until.strain reached: eps = {:.6f} (target {})", now.strain, u.strain);
  else if (u.has_stress) {
    const double s = measured_stress(until_wall_[k]);
    if (crossed(state_.stress0, s, u.stress))
      why = fmt::format("until.stress reached: wall '{}' stress = {:.6g} Pa (target {} Pa)", u.wall,
                        s, u.stress);
  }
  if (why.empty()) return std::nullopt;
  const std::string line =
      fmt::format("loading stage {} ('{}') ended at t = {:.9g} s: {}", k + 1, st.name, t, why);
  begin_stage(k + 1, t, grain_area);
  return line;
}

template <int Dim>
std::vector<walls::Wall<Dim>> WallLoading<Dim>::walls(double t) const {
  std::vector<walls::Wall<Dim>> out = walls0_;
  for (std::size_t k = 0; k < out.size(); ++k) {
    out[k].point = state_.position[k];
    out[k].t0 = t;
    out[k].velocity = state_.velocity[k];
  }
  return out;
}

template <int Dim>
std::string WallLoading<Dim>::csv_header() const {
  if (!active_) return "";
  std::string h = ",stage";
  for (const auto& w : walls0_)
    h += ",wall_" + w.name + "_vx,wall_" + w.name + "_vy" +
         (Dim == 3 ? ",wall_" + w.name + "_vz" : "") + ",wall_" + w.name + "_target";
  return h;
}

template <int Dim>
std::string WallLoading<Dim>::csv_fields(double t) const {
  if (!active_) return "";
  std::string out =
      fmt::format(",{}", std::min<std::size_t>(state_.stage + 1, section_->stages.size()));
  for (std::size_t k = 0; k < walls0_.size(); ++k) {
    const WallProgram<Dim>& prog = state_.programs[k];
    const double target = prog.control == WallControl::kStress
                              ? prog.stress_at(t)
                              : std::numeric_limits<double>::quiet_NaN();
    if constexpr (Dim == 3)
      out += fmt::format(",{:.12e},{:.12e},{:.12e},{:.12e}", state_.velocity[k][0],
                         state_.velocity[k][1], state_.velocity[k][2], target);
    else
      out += fmt::format(",{:.12e},{:.12e},{:.12e}", state_.velocity[k][0], state_.velocity[k][1],
                         target);
  }
  return out;
}

template <int Dim>
void WallLoading<Dim>::restore(LoadingState<Dim> state) {
  const std::size_t nw = walls0_.size();
  if (state.programs.size() != nw || state.position.size() != nw || state.velocity.size() != nw ||
      state.force.size() != nw || state.integral.size() != nw)
    throw std::invalid_argument(
        fmt::format("loading state for {} walls, the input has {}", state.programs.size(), nw));
  if (state.stage < 0 || static_cast<std::size_t>(state.stage) > section_->stages.size())
    throw std::invalid_argument(
        fmt::format("loading stage {} of {}", state.stage + 1, section_->stages.size()));
  state_ = std::move(state);
}

template struct WallProgram<2>;
template struct WallProgram<3>;
template class WallLoading<2>;
template class WallLoading<3>;

}  // namespace mpmcd::app
