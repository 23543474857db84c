#include "mpmcd/app/run_state.hpp"

#include <fmt/format.h>

#include "mpmcd/app/model_builder.hpp"
#include "mpmcd/core/errors.hpp"
#include "mpmcd/io/load_config.hpp"

namespace mpmcd::app {

namespace {

// checkpoint::State's flat point-major arrays: a vector per point as its Dim components, a matrix
// per point as its Dim x Dim components row by row (x[p * Dim + a], F[(p * Dim + a) * Dim + b]).
template <int Dim>
std::vector<double> flatten(const std::vector<Vec<Dim>>& in) {
  std::vector<double> out(Dim * in.size());
  for (std::size_t p = 0; p < in.size(); ++p)
    for (int a = 0; a < Dim; ++a) out[p * Dim + a] = in[p][a];
  return out;
}

template <int Dim>
std::vector<double> flatten(const std::vector<Mat<Dim>>& in) {
  std::vector<double> out(Dim * Dim * in.size());
  for (std::size_t p = 0; p < in.size(); ++p)
    for (int a = 0; a < Dim; ++a)
      for (int b = 0; b < Dim; ++b) out[(p * Dim + a) * Dim + b] = in[p](a, b);
  return out;
}

template <int Dim>
Vec<Dim> vec_at(const std::vector<double>& in, std::size_t p) {
  Vec<Dim> v;
  for (int a = 0; a < Dim; ++a) v[a] = in[p * Dim + a];
  return v;
}

template <int Dim>
std::vector<Vec<Dim>> vectors(const std::vector<double>& in, std::size_t n) {
  std::vector<Vec<Dim>> out(n);
  for (std::size_t p = 0; p < n; ++p) out[p] = vec_at<Dim>(in, p);
  return out;
}

template <int Dim>
std::vector<Mat<Dim>> matrices(const std::vector<double>& in, std::size_t n) {
  std::vector<Mat<Dim>> out(n);
  for (std::size_t p = 0; p < n; ++p)
    for (int a = 0; a < Dim; ++a)
      for (int b = 0; b < Dim; ++b) out[p](a, b) = in[(p * Dim + a) * Dim + b];
  return out;
}

}  // namespace

template <int Dim>
checkpoint::State to_checkpoint(const io::Config& cfg, const mpm::Model<Dim>& model,
                                const RunState<Dim>& run, const std::string& reason) {
  checkpoint::State s;
  s.dim = Dim;
  s.input_text = cfg.source_text;
  s.input_path = cfg.source_path;
  s.reason = reason;
  s.step = run.step;
  s.time = run.time;
  s.dt = run.dt;
  s.good_since_cut = run.good_since_cut;
  s.failed_steps = run.failed_steps;
  s.newton_iterations = run.newton_iterations;
  s.next_vtu = run.next_vtu;
  s.next_csv = run.next_csv;
  s.csv_rows = run.csv_rows;
  s.vtu_times = run.vtu_times;
  const auto& p = model.points;
  s.x = flatten<Dim>(p.x);
  s.v = flatten<Dim>(p.v);
  s.L = flatten<Dim>(p.L);
  s.F = flatten<Dim>(p.F);
  s.sigma = flatten<Dim>(p.sigma);
  s.domain = flatten<Dim>(p.domain);
  s.sigma_zz = p.sigma_zz;
  s.mass = p.mass;
  s.volume0 = p.volume0;
  s.volume = p.volume;
  s.grain = p.grain;
  s.history = p.history;
  for (const auto& g : model.grains) {
    s.grain_begin.push_back(g.begin);
    s.grain_end.push_back(g.end);
    s.grain_material.push_back(g.material);
    s.grain_half_width.push_back(g.half_width);
    s.grain_history_offset.push_back(g.history_offset);
  }
  for (const auto& w : run.warm) {
    s.warm_node.push_back(w.node);
    s.warm_a.push_back(w.a);
    s.warm_b.push_back(w.b);
    for (int a = 0; a < Dim; ++a) s.warm_impulse.push_back(w.impulse[a]);
  }
  for (const auto& x : run.wall_points)
    for (int a = 0; a < Dim; ++a) s.wall_point.push_back(x[a]);
  s.ranks = run.ranks;
  s.scheme = run.scheme;
  s.threads = run.threads;
  s.grain_owner.assign(run.grain_owner.begin(), run.grain_owner.end());
  s.grain_work = run.grain_work;
  s.wall_work = run.energy.wall_work;
  s.energy0 = run.energy.energy0;
  s.kinetic0 = run.energy.kinetic0;
  s.contact_dissipation = run.energy.contact_dissipation;
  s.transfer_dissipation = run.energy.transfer_dissipation;
  s.stress_work = run.energy.stress_work;
  s.body_work = run.energy.body_work;
  return s;
}

template <int Dim>
RunState<Dim> run_state_of(const checkpoint::State& s) {
  RunState<Dim> run;
  run.step = s.step;
  run.time = s.time;
  run.dt = s.dt;
  run.good_since_cut = s.good_since_cut;
  run.failed_steps = s.failed_steps;
  run.newton_iterations = s.newton_iterations;
  run.next_vtu = s.next_vtu;
  run.next_csv = s.next_csv;
  run.csv_rows = s.csv_rows;
  run.vtu_times = s.vtu_times;
  run.warm.resize(s.warm_node.size());
  for (std::size_t k = 0; k < run.warm.size(); ++k)
    run.warm[k] = {s.warm_node[k], s.warm_a[k], s.warm_b[k], vec_at<Dim>(s.warm_impulse, k)};
  run.wall_points = vectors<Dim>(s.wall_point, s.wall_point.size() / Dim);
  run.energy.wall_work = s.wall_work;
  run.energy.energy0 = s.energy0;
  run.energy.kinetic0 = s.kinetic0;
  run.energy.contact_dissipation = s.contact_dissipation;
  run.energy.transfer_dissipation = s.transfer_dissipation;
  run.energy.stress_work = s.stress_work;
  run.energy.body_work = s.body_work;
  run.ranks = s.ranks;
  run.scheme = s.scheme;
  run.threads = s.threads;
  run.grain_owner.assign(s.grain_owner.begin(), s.grain_owner.end());
  run.grain_work = s.grain_work;
  return run;
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
  p.x = vectors<Dim>(s.x, n);
  p.v = vectors<Dim>(s.v, n);
  p.L = matrices<Dim>(s.L, n);
  p.F = matrices<Dim>(s.F, n);
  p.sigma = matrices<Dim>(s.sigma, n);
  p.domain = matrices<Dim>(s.domain, n);
  p.sigma_zz = s.sigma_zz;
  p.mass = s.mass;
  p.volume0 = s.volume0;
  p.volume = s.volume;
  p.grain = s.grain;
  p.history = s.history;
  for (std::size_t g = 0; g < s.grain_begin.size(); ++g) {
    points::Grain gr;
    gr.begin = s.grain_begin[g];
    gr.end = s.grain_end[g];
    gr.material = s.grain_material[g];
    gr.half_width = s.grain_half_width[g];
    gr.history_offset = s.grain_history_offset[g];
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
  for (std::size_t k = 0; k < s.warm_node.size(); ++k)
    if (s.warm_node[k] < -model.grid.node_count() || s.warm_node[k] >= model.grid.node_count() ||
        s.warm_b[k] < 0 || s.warm_b[k] >= ng || s.warm_a[k] >= ng || s.warm_a[k] < -nwall)
      throw refuse(
          fmt::format("contact warm-start entry {} names a node or body that does not exist", k));
  if (s.wall_point.size() != Dim * cfg.walls.size())
    throw refuse(fmt::format("{} walls in the checkpoint, {} in the input",
                             s.wall_point.size() / Dim, cfg.walls.size()));
  return model;
}

template checkpoint::State to_checkpoint<2>(const io::Config&, const mpm::Model<2>&,
                                            const RunState<2>&, const std::string&);
template RunState<2> run_state_of<2>(const checkpoint::State&);
template mpm::Model<2> restore_model<2>(const io::Config&, const checkpoint::State&,
                                        const std::string&);

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

RestoredRun restore_from_checkpoint(const std::string& path, const std::string& input) {
  Restart r = load_restart(path, input);
  mpm::Model<2> model = restore_model<2>(r.config, r.state, path);
  mpm::Settings<2> settings = build_settings(r.config);
  RunState<2> run = run_state_of<2>(r.state);
  return RestoredRun{std::move(r.config), std::move(model), std::move(settings), std::move(run),
                     path};
}

}  // namespace mpmcd::app
