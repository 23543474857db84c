#include "mpmcd/app/simulation.hpp"

#include <fmt/format.h>
#include <omp.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>

#include "mpmcd/core/errors.hpp"
#include "mpmcd/core/log.hpp"
#include "mpmcd/io/vtu.hpp"
#include "mpmcd/packing/input.hpp"
#include "mpmcd/packing/packing.hpp"
#include "mpmcd/packing/seeding.hpp"
#include "mpmcd/points/seeding.hpp"
#include "mpmcd/version.hpp"

namespace mpmcd::app {

namespace fs = std::filesystem;

namespace {

Vec<2> vec2(const std::vector<double>& v) {
  return Vec<2>(v.at(0), v.at(1));
}

// v(x) = velocity + gradient (x - c) + omega e_z x (x - c) + A sin(k . x + phase) (InitialVelocity)
Vec<2> initial_velocity(const io::InitialVelocity& iv, const Vec<2>& c, const Vec<2>& x) {
  Vec<2> v = Vec<2>::Zero();
  if (iv.velocity.size() == 2) v += vec2(iv.velocity);
  if (iv.gradient.size() == 4) {
    Mat<2> L;
    L << iv.gradient[0], iv.gradient[1], iv.gradient[2], iv.gradient[3];
    v += L * (x - c);
  }
  const Vec<2> r = x - c;
  v += iv.angular_velocity * Vec<2>(-r[1], r[0]);
  if (iv.sine_amplitude.size() == 2 && iv.sine_wavevector.size() == 2)
    v += vec2(iv.sine_amplitude) * std::sin(vec2(iv.sine_wavevector).dot(x) + iv.sine_phase);
  return v;
}

// Every disk of a packing file becomes a grain (points from packing::seed_packing, which gives a
// lattice site shared by two overlapping disks to one of them only).
void add_packing_grains(mpm::Model<2>& model, const io::Config& cfg, std::size_t index,
                        int material) {
  const auto& g = cfg.grains[index];
  packing::Packing pk;
  if (fs::path(g.file).extension() == ".toml") {  // a packing input: generate it now (seeded DEM)
    pk = packing::generate_packing(packing::load_packing_input(g.file).params);
    log().info("generated from {}: {}", g.file, packing::summary_line(pk));
  } else {
    pk = packing::read_packing_csv(g.file);
  }
  const double h = model.grid.cell_size();
  const Vec<2> lo = model.grid.origin().array() + h, hi = model.grid.upper().array() - h;
  for (const auto& d : pk.disks) {
    const Vec<2> c(d.x, d.y);
    if (((c.array() - d.radius) < lo.array()).any() || ((c.array() + d.radius) > hi.array()).any())
      throw InputError(g.file, 0, fmt::format("disk {}", d.id),
                       fmt::format("the disk (center {:.6g} {:.6g} m, radius {:.6g} m) must lie "
                                   "inside the grid with one cell of margin (grains[{}], {}:{})",
                                   d.x, d.y, d.radius, index, cfg.source_path, g.line));
  }
  const auto seeded = packing::seed_packing(pk, model.grid.origin(), h, g.points_per_cell);
  for (std::size_t k = 0; k < pk.disks.size(); ++k) {
    points::Seeds<2> seeds;
    seeds.x.assign(seeded.x.begin() + seeded.offset[k], seeded.x.begin() + seeded.offset[k + 1]);
    seeds.volume.assign(seeded.volume.begin() + seeded.offset[k],
                        seeded.volume.begin() + seeded.offset[k + 1]);
    const Vec<2> c(pk.disks[k].x, pk.disks[k].y);
    model.add_grain(seeds, material, 0.5 * h / g.points_per_cell,
                    [&](const Vec<2>& x) { return initial_velocity(g.initial, c, x); });
  }
}

}  // namespace

mpm::Model<2> build_model(const io::Config& cfg) {
  mpm::Model<2> model;
  const double h = cfg.grid.cell_size;
  IVec<2> cells;
  for (int d = 0; d < 2; ++d)
    cells[d] = static_cast<std::int64_t>(std::llround(cfg.grid.extent[d] / h));
  model.grid = grid::Grid<2>(vec2(cfg.grid.origin), h, cells);
  for (const auto& m : cfg.materials) {
    try {
      model.add_material(materials::make_law<2>(m.law, m.params), m.density);
    } catch (const InputError& e) {
      throw InputError(cfg.source_path, m.line, "materials." + e.key(), e.what());
    }
  }
  for (std::size_t i = 0; i < cfg.grains.size(); ++i) {
    const auto& g = cfg.grains[i];
    int material = -1;
    for (std::size_t k = 0; k < cfg.materials.size(); ++k)
      if (cfg.materials[k].name == g.material) material = static_cast<int>(k);
    points::Seeds<2> seeds;
    Vec<2> center;
    if (g.shape == "disk") {
      center = vec2(g.center);
      seeds = points::seed_ball<2>(model.grid.origin(), h, g.points_per_cell, center, g.radius);
    } else if (g.shape == "rectangle") {
      const Vec<2> lo = vec2(g.min_corner), hi = vec2(g.max_corner);
      center = 0.5 * (lo + hi);
      seeds = points::seed_box<2>(model.grid.origin(), h, g.points_per_cell, lo, hi);
    } else if (g.shape == "packing") {
      add_packing_grains(model, cfg, i, material);
      continue;
    } else {
      throw InputError(cfg.source_path, g.line, fmt::format("grains[{}].shape", i),
                       "unknown shape \"" + g.shape + "\"");
    }
    if (seeds.x.empty())
      throw InputError(cfg.source_path, g.line, fmt::format("grains[{}]", i),
                       "the grain is too small to hold a material point at this cell size and "
                       "points_per_cell: refine the grid or raise points_per_cell");
    model.add_grain(seeds, material, 0.5 * h / g.points_per_cell,
                    [&](const Vec<2>& x) { return initial_velocity(g.initial, center, x); });
  }
  return model;
}

std::vector<mpm::VelocityBC<2>> build_boundaries(const io::Config& cfg, const grid::Grid<2>& grid,
                                                 double t) {
  std::vector<mpm::VelocityBC<2>> out;
  const auto& n = grid.nodes_per_axis();
  const double h = grid.cell_size();
  for (const auto& b : cfg.boundaries) {
    mpm::VelocityBC<2> bc;
    for (const auto& f : b.fix) bc.mask |= static_cast<std::uint8_t>(1u << (f == "x" ? 0 : 1));
    bc.velocity = vec2(b.velocity);
    IVec<2> lo = IVec<2>::Zero(), hi = n - IVec<2>::Ones();
    if (b.nodes == "xmin") hi[0] = 0;
    if (b.nodes == "xmax") lo[0] = n[0] - 1;
    if (b.nodes == "ymin") hi[1] = 0;
    if (b.nodes == "ymax") lo[1] = n[1] - 1;
    if (b.nodes == "box") {
      const Vec<2> shift = b.moving ? Vec<2>(t * bc.velocity) : Vec<2>::Zero();
      for (int d = 0; d < 2; ++d) {
        const double a = (b.box_min[d] + shift[d] - grid.origin()[d]) / h;
        const double z = (b.box_max[d] + shift[d] - grid.origin()[d]) / h;
        lo[d] = std::max<std::int64_t>(0, static_cast<std::int64_t>(std::ceil(a - 1e-9)));
        hi[d] = std::min<std::int64_t>(n[d] - 1, static_cast<std::int64_t>(std::floor(z + 1e-9)));
      }
    }
    for (std::int64_t j = lo[1]; j <= hi[1]; ++j)
      for (std::int64_t i = lo[0]; i <= hi[0]; ++i) bc.nodes.push_back(grid.node_index({i, j}));
    out.push_back(std::move(bc));
  }
  return out;
}

mpm::Settings<2> build_settings(const io::Config& cfg) {
  mpm::Settings<2> s;
  s.shape = grid::shape_kind_from_string(cfg.grid.shape_function);
  s.theta = cfg.time.theta;
  s.max_iterations = cfg.solver.max_iterations;
  s.residual_tolerance = cfg.solver.residual_tolerance;
  s.increment_tolerance = cfg.solver.increment_tolerance;
  s.linear_solver = mpm::linear_solver_from_string(cfg.solver.linear_solver);
  s.cg_tolerance = cfg.solver.cg_tolerance;
  s.cg_max_iterations = cfg.solver.cg_max_iterations;
  s.flip = cfg.solver.flip;
  if (cfg.loads.gravity.size() == 2) s.gravity = vec2(cfg.loads.gravity);
  return s;
}

namespace {

// Writes one VTU snapshot of the points.
void write_points_vtu(const mpm::Model<2>& model, const std::string& path) {
  const auto& p = model.points;
  io::VtuPointCloud vtu(p.size());
  auto& vel = vtu.add_array("velocity", 3);
  auto& sig = vtu.add_array("stress", 9);
  auto& pres = vtu.add_array("pressure", 1);
  auto& jac = vtu.add_array("J", 1);
  auto& mass = vtu.add_array("mass", 1);
  auto& vol = vtu.add_array("volume", 1);
  auto& grain = vtu.add_int_array("grain");
  for (std::size_t i = 0; i < p.size(); ++i) {
    vtu.set_position(i, p.x[i][0], p.x[i][1]);
    vel[3 * i] = p.v[i][0];
    vel[3 * i + 1] = p.v[i][1];
    const Mat<2>& s = p.sigma[i];
    const double s3[9] = {s(0, 0), s(0, 1), 0, s(1, 0), s(1, 1), 0, 0, 0, p.sigma_zz[i]};
    for (int k = 0; k < 9; ++k) sig[9 * i + k] = s3[k];
    pres[i] = -(s(0, 0) + s(1, 1) + p.sigma_zz[i]) / 3.0;  // p = -tr(sigma)/3 (plane strain)
    jac[i] = p.F[i].determinant();
    mass[i] = p.mass[i];
    vol[i] = p.volume[i];
    grain[i] = p.grain[i];
  }
  vtu.write(path);
}

class Outputs {
 public:
  Outputs(const io::Config& cfg, const std::string& dir) : cfg_(cfg), dir_(dir) {
    fs::create_directories(dir_);
    // Input copy, stamped with the version that ran it.
    io::write_file_atomic(
        (fs::path(dir_) / "input.toml").string(),
        fmt::format("# run by mpmcd {} ({}) from {}\n", kVersion, kGitHash, cfg.source_path) +
            cfg.source_text);
    csv_path_ = (fs::path(dir_) / (cfg.simulation.name + ".csv")).string();
    csv_.open(csv_path_, std::ios::trunc);
    if (!csv_) throw std::runtime_error("cannot open " + csv_path_);
    csv_ << "step,time,dt,newton_iterations,linear_solves,kinetic_energy,elastic_energy,"
            "total_energy,momentum_x,momentum_y,mass,volume\n";
    if (cfg_.output.vtu)
      pvd_ = std::make_unique<io::PvdSeries>(
          (fs::path(dir_) / (cfg.simulation.name + ".pvd")).string());
  }
  void csv_row(std::int64_t step, double t, double dt, const mpm::StepStats& st,
               const mpm::Diagnostics<2>& d) {
    csv_ << fmt::format(
        "{},{:.12e},{:.6e},{},{},{:.12e},{:.12e},{:.12e},{:.12e},{:.12e},{:.12e},{:.12e}\n", step,
        t, dt, st.iterations, st.linear_solves, d.kinetic, d.elastic, d.kinetic + d.elastic,
        d.momentum[0], d.momentum[1], d.mass, d.volume);
    csv_.flush();
  }
  void vtu(const mpm::Model<2>& model, double t) {
    if (!pvd_) return;
    const std::string name = fmt::format("{}_{:06d}.vtu", cfg_.simulation.name, vtu_count_++);
    write_points_vtu(model, (fs::path(dir_) / name).string());
    pvd_->add(t, name);
  }
  std::string last_good(const mpm::Model<2>& model) {
    const std::string path = (fs::path(dir_) / (cfg_.simulation.name + "_last_good.vtu")).string();
    write_points_vtu(model, path);
    return path;
  }

 private:
  const io::Config& cfg_;
  std::string dir_, csv_path_;
  std::ofstream csv_;
  std::unique_ptr<io::PvdSeries> pvd_;
  int vtu_count_ = 0;
};

}  // namespace

RunSummary run_simulation(const io::Config& cfg, const RunOptions& opt) {
  RunSummary summary;
  const int threads = opt.threads > 0 ? opt.threads : cfg.simulation.threads;
  if (threads > 0) omp_set_num_threads(threads);
  mpm::Model<2> model = build_model(cfg);  // may throw InputError: before any output
  auto settings = build_settings(cfg);
  bool any_moving = false;
  for (const auto& b : cfg.boundaries) any_moving = any_moving || b.moving;

  summary.output_dir = opt.output_dir.empty() ? cfg.output.folder : opt.output_dir;
  if (fs::path(summary.output_dir).is_relative() && opt.output_dir.empty())
    summary.output_dir =
        (fs::path(cfg.source_path).parent_path() / summary.output_dir).lexically_normal().string();
  Outputs out(cfg, summary.output_dir);
  mpm::ImplicitSolver<2> solver(model.grid, settings, model.points, model.grains, model.law_ptrs());
  solver.set_boundary_conditions(build_boundaries(cfg, model.grid, 0.0));

  log().info("mpmcd {} ({}): {} grains, {} material points, grid {}x{} cells of {} m, {} threads",
             kVersion, kGitHash, model.grains.size(), model.points.size(), model.grid.cells()[0],
             model.grid.cells()[1], model.grid.cell_size(), omp_get_max_threads());
  const double dt_nominal = cfg.time.dt, t_end = cfg.time.end_time;
  double t = 0, dt = dt_nominal;
  int good_since_cut = 0;
  double next_vtu = 0, next_csv = 0;
  mpm::StepStats last;
  auto record = [&](bool force) {
    const double eps = 1e-9 * dt_nominal;
    if (force || t >= next_csv - eps) {
      out.csv_row(summary.steps, t, dt, last, mpm::diagnostics(model));
      next_csv = t + cfg.output.csv_interval;
    }
    if (force || t >= next_vtu - eps) {
      out.vtu(model, t);
      next_vtu = t + cfg.output.vtu_interval;
    }
  };
  record(true);
  const auto wall0 = std::chrono::steady_clock::now();
  auto last_progress = wall0;
  while (t < t_end - 1e-9 * dt_nominal) {
    const double dt_try = std::min(dt, t_end - t);
    if (any_moving) solver.set_boundary_conditions(build_boundaries(cfg, model.grid, t + dt_try));
    mpm::StepStats st = solver.solve_step(dt_try);
    if (!st.converged) {
      ++summary.failed_steps;
      const double dt_new = dt_try * cfg.time.cut_factor;
      if (!st.retryable || dt_new < cfg.time.dt_min) {
        const std::string saved = out.last_good(model);
        log().error("last good state (t = {:.9g} s) written to {}", t, saved);
        throw NumericalError(st.retryable ? fmt::format("{}; dt cut down to dt_min = {:.3g} s "
                                                        "did not help",
                                                        st.failure, cfg.time.dt_min)
                                          : st.failure,
                             summary.steps + 1, t, st.grain, st.point);
      }
      log().warn("step {} at t = {:.9g} s failed ({}), retrying with dt = {:.4g} s",
                 summary.steps + 1, t, st.failure, dt_new);
      dt = dt_new;
      good_since_cut = 0;
      continue;
    }
    solver.commit();
    last = st;
    t += dt_try;
    ++summary.steps;
    summary.newton_iterations += st.iterations;
    if (dt < dt_nominal && ++good_since_cut >= cfg.time.recover_steps) {
      dt = std::min(dt_nominal, 2 * dt);
      good_since_cut = 0;
      log().info("dt restored to {:.4g} s at t = {:.9g} s", dt, t);
    }
    record(t >= t_end - 1e-9 * dt_nominal);
    const auto now = std::chrono::steady_clock::now();
    if (std::chrono::duration<double>(now - last_progress).count() >=
        cfg.output.progress_interval) {
      last_progress = now;
      const double wall = std::chrono::duration<double>(now - wall0).count();
      const double rate = summary.steps / wall;
      const double eta = (t_end - t) / dt_nominal / std::max(rate, 1e-30);
      log().info("step {:>7}  t = {:.6e} s ({:5.1f}%)  newton {}  {:.1f} steps/s  ETA {:.0f} s",
                 summary.steps, t, 100 * t / t_end, st.iterations, rate, eta);
    }
  }
  summary.time = t;
  summary.wall_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  std::string timers;
  for (const auto& [name, secs] : solver.timers().totals())
    timers += fmt::format(" {} {:.2f} s", name, secs);
  log().info("done: {} steps ({} retried) to t = {:.6g} s in {:.2f} s wall;{}", summary.steps,
             summary.failed_steps, t, summary.wall_seconds, timers);
  log().info("outputs in {}", summary.output_dir);
  return summary;
}

}  // namespace mpmcd::app
