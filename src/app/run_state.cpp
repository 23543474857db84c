#include "mpmcd/app/run_state.hpp"

#include <fmt/format.h>

#include <stdexcept>

#include "mpmcd/app/model_builder.hpp"
#include "mpmcd/core/errors.hpp"
#include "mpmcd/io/load_config.hpp"

namespace mpmcd::app {

namespace {

// checkpoint::State's flat point-major arrays: a vector per point as its Dim components, a matrix
// per point as its Dim x Dim components row by row (x[p * Dim + a], F[(p * Dim + a) * Dim + b]);
// per-point scalars and the history as they are. put: model -> checkpoint, take: the reverse
// (`n` points).
template <int Dim>
void put(const std::vector<Vec<Dim>>& in, std::vector<double>& out) {
  out.assign(Dim * in.size(), 0.0);
  for (std::size_t p = 0; p < in.size(); ++p)
    for (int a = 0; a < Dim; ++a) out[p * Dim + a] = in[p][a];
}

template <int Dim>
void put(const std::vector<Mat<Dim>>& in, std::vector<double>& out) {
  out.assign(Dim * Dim * in.size(), 0.0);
  for (std::size_t p = 0; p < in.size(); ++p)
    for (int a = 0; a < Dim; ++a)
      for (int b = 0; b < Dim; ++b) out[(p * Dim + a) * Dim + b] = in[p](a, b);
}

template <typename T>
void put(const std::vector<T>& in, std::vector<T>& out) {
  out = in;
}

template <int Dim>
Vec<Dim> vec_at(const std::vector<double>& in, std::size_t p) {
  Vec<Dim> v;
  for (int a = 0; a < Dim; ++a) v[a] = in[p * Dim + a];
  return v;
}

template <int Dim>
void take(const std::vector<double>& in, std::vector<Vec<Dim>>& out, std::size_t n) {
  out.resize(n);
  for (std::size_t p = 0; p < n; ++p) out[p] = vec_at<Dim>(in, p);
}

template <int Dim>
void take(const std::vector<double>& in, std::vector<Mat<Dim>>& out, std::size_t n) {
  out.resize(n);
  for (std::size_t p = 0; p < n; ++p)
    for (int a = 0; a < Dim; ++a)
      for (int b = 0; b < Dim; ++b) out[p](a, b) = in[(p * Dim + a) * Dim + b];
}

template <typename T>
void take(const std::vector<T>& in, std::vector<T>& out, std::size_t) {
  out = in;
}

// Each field of points::PointSet with the checkpoint array that holds it: f(&PointSet::field,
// &State::array) for every one, listed once for writing and reading.
template <int Dim, typename F>
void for_each_point_field(F&& f) {
  using P = points::PointSet<Dim>;
  using S = checkpoint::State;
  f(&P::x, &S::x);
  f(&P::v, &S::v);
  f(&P::L, &S::L);
  f(&P::F, &S::F);
  f(&P::sigma, &S::sigma);
  f(&P::domain, &S::domain);
  f(&P::sigma_zz, &S::sigma_zz);
  f(&P::mass, &S::mass);
  f(&P::volume0, &S::volume0);
  f(&P::volume, &S::volume);
  f(&P::grain, &S::grain);
  f(&P::history, &S::history);
}

// Each field of points::Grain with the checkpoint array (one entry per grain) that holds it.
template <typename F>
void for_each_grain_field(F&& f) {
  using G = points::Grain;
  using S = checkpoint::State;
  f(&G::begin, &S::grain_begin);
  f(&G::end, &S::grain_end);
  f(&G::material, &S::grain_material);
  f(&G::half_width, &S::grain_half_width);
  f(&G::history_offset, &S::grain_history_offset);
}

// Each of the energy ledger's sums with the checkpoint field that holds it.
template <typename F>
void for_each_energy_field(F&& f) {
  using E = EnergySums;
  using S = checkpoint::State;
  f(&E::wall_work, &S::wall_work);
  f(&E::energy0, &S::energy0);
  f(&E::kinetic0, &S::kinetic0);
  f(&E::contact_dissipation, &S::contact_dissipation);
  f(&E::transfer_dissipation, &S::transfer_dissipation);
  f(&E::stress_work, &S::stress_work);
  f(&E::body_work, &S::body_work);
}

}  // namespace

template <int Dim>
void store_run(const io::Config& cfg, const mpm::Model<Dim>& model,
               const std::vector<mpm::WarmImpulse<Dim>>& warm,
               const std::vector<walls::Wall<Dim>>& walls, checkpoint::State& s) {
  s.dim = Dim;
  s.input_text = cfg.source_text;
  s.input_path = cfg.source_path;
  for_each_point_field<Dim>([&](auto field, auto array) { put(model.points.*field, s.*array); });
  for_each_grain_field([&](auto field, auto array) {
    auto& out = s.*array;
    out.clear();
    for (const auto& g : model.grains) out.push_back(g.*field);
  });
  s.warm_node.clear();
  s.warm_a.clear();
  s.warm_b.clear();
  s.warm_impulse.clear();
  for (const auto& w : warm) {
    s.warm_node.push_back(w.node);
    s.warm_a.push_back(w.a);
    s.warm_b.push_back(w.b);
    for (int a = 0; a < Dim; ++a) s.warm_impulse.push_back(w.impulse[a]);
  }
  s.wall_point.clear();
  for (const auto& w : walls) {
    const Vec<Dim> x = w.point_at(s.time);
    for (int a = 0; a < Dim; ++a) s.wall_point.push_back(x[a]);
  }
}

template <int Dim>
std::vector<mpm::WarmImpulse<Dim>> warm_start_of(const checkpoint::State& s) {
  std::vector<mpm::WarmImpulse<Dim>> warm(s.warm_node.size());
  for (std::size_t k = 0; k < warm.size(); ++k)
    warm[k] = {s.warm_node[k], s.warm_a[k], s.warm_b[k], vec_at<Dim>(s.warm_impulse, k)};
  return warm;
}

namespace {
constexpr std::size_t kLoadingStageValues = 5;  // checkpoint::State::loading_stage
// checkpoint::State::loading_wall, per wall: 4 Dim + 5 since the servo's integral (13 in 2D),
// 4 Dim + 4 before (12, read as an integral of 0).
template <int Dim>
constexpr std::size_t kLoadingWallValues = 4 * Dim + 5;
template <int Dim>
constexpr std::size_t kLoadingWallValuesBefore = 4 * Dim + 4;
}  // namespace

template <int Dim>
void store_loading(const LoadingState<Dim>& l, checkpoint::State& s) {
  s.loading_stage = {static_cast<double>(l.stage), l.stage_start, l.phi0, l.eps0, l.stress0};
  s.loading_control.clear();
  s.loading_wall.clear();
  const auto put_vec = [&](const Vec<Dim>& v) {
    for (int a = 0; a < Dim; ++a) s.loading_wall.push_back(v[a]);
  };
  for (std::size_t k = 0; k < l.programs.size(); ++k) {
    const WallProgram<Dim>& p = l.programs[k];
    s.loading_control.push_back(static_cast<std::int32_t>(p.control));
    put_vec(p.v_from);
    put_vec(p.v_to);
    for (const double x : {p.s_from, p.s_to, p.t_start, p.ramp}) s.loading_wall.push_back(x);
    put_vec(l.velocity[k]);
    put_vec(l.force[k]);
    s.loading_wall.push_back(l.integral[k]);
  }
}

template <int Dim>
LoadingState<Dim> loading_state_of(const checkpoint::State& s) {
  constexpr std::size_t kAll = kLoadingWallValues<Dim>, kBefore = kLoadingWallValuesBefore<Dim>;
  const std::size_t nw = s.loading_control.size();
  if (s.loading_stage.size() != kLoadingStageValues)
    throw std::invalid_argument(
        "the input has [loading], the checkpoint no loading state (written without it)");
  const std::size_t per_wall = nw > 0 && s.loading_wall.size() == nw * kBefore ? kBefore : kAll;
  if (s.loading_wall.size() != nw * per_wall || s.wall_point.size() != Dim * nw)
    throw std::invalid_argument(fmt::format(
        "the checkpoint's loading state has {} values for {} walls, expected {} per wall",
        s.loading_wall.size(), nw, kAll));
  LoadingState<Dim> l;
  l.stage = static_cast<std::int32_t>(s.loading_stage[0]);
  l.stage_start = s.loading_stage[1];
  l.phi0 = s.loading_stage[2];
  l.eps0 = s.loading_stage[3];
  l.stress0 = s.loading_stage[4];
  for (std::size_t k = 0; k < nw; ++k) {
    const double* x = &s.loading_wall[k * per_wall];
    if (s.loading_control[k] != 0 && s.loading_control[k] != 1)
      throw std::invalid_argument(fmt::format("wall {} has control {}", k, s.loading_control[k]));
    WallProgram<Dim> p;
    const auto vec = [&](std::size_t at) {  // the Dim values from x[at]
      Vec<Dim> v;
      for (int a = 0; a < Dim; ++a) v[a] = x[at + static_cast<std::size_t>(a)];
      return v;
    };
    p.control = static_cast<WallControl>(s.loading_control[k]);
    p.v_from = vec(0);
    p.v_to = vec(Dim);
    p.s_from = x[2 * Dim];
    p.s_to = x[2 * Dim + 1];
    p.t_start = x[2 * Dim + 2];
    p.ramp = x[2 * Dim + 3];
    l.programs.push_back(p);
    l.velocity.push_back(vec(2 * Dim + 4));
    l.force.push_back(vec(3 * Dim + 4));
    l.integral.push_back(per_wall > kBefore ? x[4 * Dim + 4] : 0.0);
    l.position.push_back(vec_at<Dim>(s.wall_point, k));
  }
  return l;
}

template void store_loading<2>(const LoadingState<2>&, checkpoint::State&);
template void store_loading<3>(const LoadingState<3>&, checkpoint::State&);
template LoadingState<2> loading_state_of<2>(const checkpoint::State&);
template LoadingState<3> loading_state_of<3>(const checkpoint::State&);

void store_energy(const EnergySums& e, checkpoint::State& s) {
  for_each_energy_field([&](auto sum, auto field) { s.*field = e.*sum; });
}

EnergySums energy_sums_of(const checkpoint::State& s) {
  EnergySums e;
  for_each_energy_field([&](auto sum, auto field) { e.*sum = s.*field; });
  return e;
}

template <int Dim>
mpm::Model<Dim> restore_model(const io::Config& cfg, const checkpoint::State& s,
                              const std::string& path) {
  const auto refuse = [&](const std::string& what) {
    return InputError(path, 0, "", "checkpoint does not fit its input: " + what);
  };
  if (s.dim != Dim) throw refuse(fmt::format("dimension {}", s.dim));
  mpm::Model<Dim> model = model_frame<Dim>(cfg);
  const std::size_t n = s.points();
  auto& p = model.points;
  for_each_point_field<Dim>([&](auto field, auto array) { take(s.*array, p.*field, n); });
  for (std::size_t g = 0; g < s.grain_begin.size(); ++g) {
    points::Grain gr;
    for_each_grain_field([&](auto field, auto array) { gr.*field = (s.*array)[g]; });
    if (gr.material >= static_cast<int>(model.laws.size()))
      throw refuse(fmt::format("grain {} has material {}, the input has {} materials", g,
                               gr.material, model.laws.size()));
    const std::int64_t hs = model.laws[gr.material]->history_size();
    if (gr.history_offset + hs * gr.size() > static_cast<std::int64_t>(p.history.size()))
      throw refuse(fmt::format("grain {}: history shorter than its law needs", g));
    model.grains.push_back(gr);
  }
  for (std::size_t i = 0; i < n; ++i)
    if (!model.grid.inside(p.x[i], 0.0))
      throw refuse(fmt::format("point {} lies outside the grid", i));
  const auto ng = static_cast<std::int32_t>(model.grains.size());
  const auto nwall = static_cast<std::int32_t>(cfg.walls.size());
  // Warm-start keys: a grid node, -1 - a grid cell (face walls) or -1 - a face number
  // point * 2 Dim + 2 axis + side (grain faces, ImplicitSolver::grain_face_contacts).
  const std::int64_t lowest =
      -std::max<std::int64_t>(model.grid.node_count(), 2 * Dim * static_cast<std::int64_t>(n));
  for (std::size_t k = 0; k < s.warm_node.size(); ++k)
    if (s.warm_node[k] < lowest || s.warm_node[k] >= model.grid.node_count() || s.warm_b[k] < 0 ||
        s.warm_b[k] >= ng || s.warm_a[k] >= ng || s.warm_a[k] < -nwall)
      throw refuse(
          fmt::format("contact warm-start entry {} names a node or body that does not exist", k));
  if (s.wall_point.size() != Dim * cfg.walls.size())
    throw refuse(fmt::format("{} walls in the checkpoint, {} in the input",
                             s.wall_point.size() / Dim, cfg.walls.size()));
  return model;
}

template void store_run<2>(const io::Config&, const mpm::Model<2>&,
                           const std::vector<mpm::WarmImpulse<2>>&,
                           const std::vector<walls::Wall<2>>&, checkpoint::State&);
template void store_run<3>(const io::Config&, const mpm::Model<3>&,
                           const std::vector<mpm::WarmImpulse<3>>&,
                           const std::vector<walls::Wall<3>>&, checkpoint::State&);
template mpm::Model<2> restore_model<2>(const io::Config&, const checkpoint::State&,
                                        const std::string&);
template mpm::Model<3> restore_model<3>(const io::Config&, const checkpoint::State&,
                                        const std::string&);
template std::vector<mpm::WarmImpulse<2>> warm_start_of<2>(const checkpoint::State&);
template std::vector<mpm::WarmImpulse<3>> warm_start_of<3>(const checkpoint::State&);

Restart load_restart(const std::string& path, const std::string& input) {
  Restart r;
  r.path = path;
  r.state = checkpoint::read(path);
  if (input.empty()) {
    r.config = io::parse_config(r.state.input_text, r.state.input_path);
  } else {
    r.config = io::load_config(input);
    if (checkpoint::fnv1a(r.config.source_text) != r.state.input_hash)
      throw InputError(input, 0, "",
                       fmt::format("this input is not the one checkpoint '{}' was written from "
                                   "({}); a restart continues the same run: give that input or "
                                   "none (the checkpoint holds it)",
                                   path, r.state.input_path));
  }
  return r;
}

template <int Dim>
RestoredRun<Dim> restore_from_checkpoint(const std::string& path, const std::string& input) {
  Restart r = load_restart(path, input);
  if (r.config.simulation.dimension != Dim)
    throw InputError(path, 0, "simulation.dimension",
                     fmt::format("a {}D run asked of a checkpoint of dimension {}", Dim,
                                 r.config.simulation.dimension));
  mpm::Model<Dim> model = restore_model<Dim>(r.config, r.state, path);
  mpm::Settings<Dim> settings = build_settings(r.config, model);
  std::vector<mpm::WarmImpulse<Dim>> warm = warm_start_of<Dim>(r.state);
  return RestoredRun<Dim>{std::move(r.config), std::move(r.state), std::move(model),
                          std::move(settings), std::move(warm),    path};
}

template RestoredRun<2> restore_from_checkpoint<2>(const std::string&, const std::string&);
template RestoredRun<3> restore_from_checkpoint<3>(const std::string&, const std::string&);

}  // namespace mpmcd::app
