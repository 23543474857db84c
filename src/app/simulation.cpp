#include "mpmcd/app/simulation.hpp"

#include <fmt/format.h>
#include <omp.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <numbers>

#include "mpmcd/app/compaction_observer.hpp"
#include "mpmcd/core/errors.hpp"
#include "mpmcd/core/log.hpp"
#include "mpmcd/io/vtu.hpp"
#include "mpmcd/packing/input.hpp"
#include "mpmcd/packing/packing.hpp"
#include "mpmcd/packing/seeding.hpp"
#include "mpmcd/parallel/distribute.hpp"
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
  if (g.seeding == "polar") {  // each disk on its own rings, strictly inside its circle
    const double s = h / g.points_per_cell;
    double estimate = 0;
    for (const auto& d : pk.disks) estimate += std::numbers::pi * d.radius * d.radius / (s * s);
    if (estimate > 2e8)
      throw InputError(cfg.source_path, g.line, fmt::format("grains[{}].points_per_cell", index),
                       fmt::format("the packing would need about {:.3g} material points (at most "
                                   "2e8): coarsen the grid or lower points_per_cell",
                                   estimate));
    for (const auto& d : pk.disks) {
      const Vec<2> c(d.x, d.y);
      model.add_grain(points::seed_disk_polar(c, d.radius, h / g.points_per_cell), material,
                      0.5 * h / g.points_per_cell,
                      [&](const Vec<2>& x) { return initial_velocity(g.initial, c, x); });
    }
    return;
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
      seeds =
          g.seeding == "polar"
              ? points::seed_disk_polar(center, g.radius, h / g.points_per_cell)
              : points::seed_ball<2>(model.grid.origin(), h, g.points_per_cell, center, g.radius);
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
  // Contact: enabled when asked and there is something to touch (two grains or a wall).
  auto& c = s.contact;
  std::size_t grains = 0;
  for (const auto& g : cfg.grains) grains += g.shape == "packing" ? 2 : 1;
  c.enabled = cfg.contact.enabled && (grains > 1 || !cfg.walls.empty());
  c.criterion =
      cfg.contact.criterion == "overlap" ? mpm::GapCriterion::kOverlap : mpm::GapCriterion::kGap;
  c.mass_fraction = cfg.contact.mass_fraction;
  c.gs.tolerance = cfg.contact.tolerance;
  c.gs.max_sweeps = cfg.contact.max_sweeps;
  c.impulse_tolerance = cfg.contact.impulse_tolerance;
  c.wall_range = cfg.contact.wall_range;
  // Delassus operator: the lumped 1/m_I is accurate when inertia dominates a step (theta c_p dt/h
  // small); otherwise each grain's exact compliance (needs a direct solver) keeps the staggered
  // contact-Newton loop converging in a few iterations.
  double cp = 0;
  for (const auto& m : cfg.materials)
    cp = std::max(cp, std::sqrt((m.params.at("lambda") + 2 * m.params.at("mu")) / m.density));
  const double courant = cfg.time.theta * cp * cfg.time.dt / cfg.grid.cell_size;
  c.grain_compliance =
      cfg.contact.delassus == "grain" || (cfg.contact.delassus == "auto" && courant > 0.1);
  const auto nm = static_cast<int>(cfg.materials.size());
  c.materials = nm;
  c.friction.assign(static_cast<std::size_t>(nm * nm), cfg.contact.friction);
  auto index = [&](const std::string& name) {
    for (int k = 0; k < nm; ++k)
      if (cfg.materials[k].name == name) return k;
    return 0;
  };
  for (const auto& p : cfg.contact.pairs) {
    const int a = index(p.materials[0]), b = index(p.materials[1]);
    c.friction[a * nm + b] = c.friction[b * nm + a] = p.friction;
  }
  for (const auto& w : cfg.walls)
    c.walls.push_back({w.name, vec2(w.point), vec2(w.normal), vec2(w.velocity), w.friction});
  return s;
}

void check_walls_enclose(const io::Config& cfg, const mpm::Model<2>& model,
                         const mpm::Settings<2>& settings) {
  for (std::size_t k = 0; k < settings.contact.walls.size(); ++k) {
    const auto& wall = settings.contact.walls[k];
    for (std::size_t p = 0; p < model.points.size(); ++p)
      if (wall.distance(model.points.x[p], 0.0) < 0.0)
        throw InputError(cfg.source_path, cfg.walls[k].line, fmt::format("walls[{}]", k),
                         fmt::format("wall \"{}\" does not enclose the grains: grain {} has a "
                                     "material point at ({:.6g}, {:.6g}) m on its outer side",
                                     wall.name, model.points.grain[p], model.points.x[p][0],
                                     model.points.x[p][1]));
  }
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
  // `extra_header`: further CSV columns (CompactionObserver), starting with a comma.
  Outputs(const io::Config& cfg, const std::string& dir, const std::string& extra_header)
      : cfg_(cfg), dir_(dir) {
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
            "total_energy,momentum_x,momentum_y,mass,volume,contacts,active_contacts,gs_sweeps";
    for (const auto& w : cfg.walls) csv_ << ",wall_" << w.name << "_fx,wall_" << w.name << "_fy";
    csv_ << extra_header << "\n";
    if (cfg_.output.vtu)
      pvd_ = std::make_unique<io::PvdSeries>(
          (fs::path(dir_) / (cfg.simulation.name + ".pvd")).string());
  }
  void csv_row(std::int64_t step, double t, double dt, const mpm::StepStats& st,
               const mpm::Diagnostics<2>& d, const std::string& extra) {
    csv_ << fmt::format(
        "{},{:.12e},{:.6e},{},{},{:.12e},{:.12e},{:.12e},{:.12e},{:.12e},{:.12e},{:.12e}", step, t,
        dt, st.iterations, st.linear_solves, d.kinetic, d.elastic, d.kinetic + d.elastic,
        d.momentum[0], d.momentum[1], d.mass, d.volume);
    csv_ << fmt::format(",{},{},{}", st.contacts, st.active_contacts, st.gs_sweeps);
    for (std::size_t k = 0; k < cfg_.walls.size(); ++k) {
      const bool have = k < st.wall_force.size();
      csv_ << fmt::format(",{:.12e},{:.12e}", have ? st.wall_force[k][0] : 0.0,
                          have ? st.wall_force[k][1] : 0.0);
    }
    csv_ << extra << "\n";
    csv_.flush();
  }
  void vtu(const mpm::Model<2>& model, const mpm::ImplicitSolver<2>& solver,
           const contact::Problem<2>& problem, double t) {
    if (!pvd_) return;
    const std::string name = fmt::format("{}_{:06d}.vtu", cfg_.simulation.name, vtu_count_);
    write_points_vtu(model, (fs::path(dir_) / name).string());
    pvd_->add(t, name);
    if (solver.settings().contact.enabled) {
      const std::string cname =
          fmt::format("{}_contacts_{:06d}.vtu", cfg_.simulation.name, vtu_count_);
      const std::string pname =
          fmt::format("{}_pairs_{:06d}.csv", cfg_.simulation.name, vtu_count_);
      write_contacts(model, problem, (fs::path(dir_) / cname).string(),
                     (fs::path(dir_) / pname).string());
      if (!contacts_pvd_)
        contacts_pvd_ = std::make_unique<io::PvdSeries>(
            (fs::path(dir_) / (cfg_.simulation.name + "_contacts.pvd")).string());
      contacts_pvd_->add(t, cname);
    }
    ++vtu_count_;
  }
  // Contacts as points at their nodes (normal, impulses, the two bodies; walls as -1 - index),
  // and the per-pair aggregated contact force sum P / dt as a CSV.
  void write_contacts(const mpm::Model<2>& model, const contact::Problem<2>& pb,
                      const std::string& vtu_path, const std::string& csv_path) {
    io::VtuPointCloud vtu(pb.contacts.size());
    auto& normal = vtu.add_array("normal", 3);
    auto& pn = vtu.add_array("normal_impulse", 1);
    auto& pt = vtu.add_array("tangential_impulse", 1);
    auto& force = vtu.add_array("force", 3);
    auto& gap = vtu.add_array("gap", 1);
    auto& body_a = vtu.add_int_array("body_a");
    auto& body_b = vtu.add_int_array("body_b");
    std::map<std::pair<int, int>, Vec<2>> pairs;
    const double inv_dt = pb.dt > 0 ? 1.0 / pb.dt : 0.0;
    for (std::size_t i = 0; i < pb.contacts.size(); ++i) {
      const auto& c = pb.contacts[i];
      const auto& sb = pb.slots[c.b];
      const Vec<2> x = model.grid.node_position(model.grid.node_coords(sb.node));
      vtu.set_position(i, x[0], x[1]);
      normal[3 * i] = c.normal[0];
      normal[3 * i + 1] = c.normal[1];
      pn[i] = c.impulse.dot(c.normal);
      pt[i] = c.impulse[1] * c.normal[0] - c.impulse[0] * c.normal[1];  // along t = e_z x n
      force[3 * i] = c.impulse[0] * inv_dt;
      force[3 * i + 1] = c.impulse[1] * inv_dt;
      gap[i] = c.gap;
      body_a[i] = c.a >= 0 ? pb.slots[c.a].grain : -1 - c.wall;
      body_b[i] = sb.grain;
      // try_emplace with zero: a default-constructed Eigen vector is uninitialised.
      pairs.try_emplace({body_a[i], body_b[i]}, Vec<2>::Zero()).first->second += c.impulse * inv_dt;
    }
    vtu.write(vtu_path);
    std::string text = "body_a,body_b,force_x,force_y\n";
    for (const auto& [key, f] : pairs)
      text += fmt::format("{},{},{:.12e},{:.12e}\n", key.first, key.second, f[0], f[1]);
    io::write_file_atomic(csv_path, text);
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
  std::unique_ptr<io::PvdSeries> pvd_, contacts_pvd_;
  int vtu_count_ = 0;
};

}  // namespace

RunSummary run_simulation(const io::Config& cfg, const RunOptions& opt) {
  RunSummary summary;
  const int threads = opt.threads > 0 ? opt.threads : cfg.simulation.threads;
  if (threads > 0) omp_set_num_threads(threads);
  mpm::Model<2> model = build_model(cfg);  // may throw InputError: before any output
  auto settings = build_settings(cfg);
  check_walls_enclose(cfg, model, settings);  // may throw InputError: before any output
  bool any_moving = false;
  for (const auto& b : cfg.boundaries) any_moving = any_moving || b.moving;

  summary.output_dir = opt.output_dir.empty() ? cfg.output.folder : opt.output_dir;
  if (fs::path(summary.output_dir).is_relative() && opt.output_dir.empty())
    summary.output_dir =
        (fs::path(cfg.source_path).parent_path() / summary.output_dir).lexically_normal().string();
  const CompactionObserver observer(cfg, model);
  // Processes (docs/parallel.md): every rank holds the model and computes its grains; rank 0
  // gathers the state at output times and writes every file.
  const auto& comm = parallel::Comm::world();
  const bool root = comm.rank() == 0;
  if (!root) log().set_level(spdlog::level::off);  // rank 0 reports
  mpm::ImplicitSolver<2> solver(model.grid, settings, model.points, model.grains, model.law_ptrs());
  solver.set_boundary_conditions(build_boundaries(cfg, model.grid, 0.0));
  const parallel::Scheme scheme =
      parallel::scheme_from_string(opt.scheme.empty() ? "partition" : opt.scheme);
  if (comm.size() > 1)
    solver.set_distribution(
        &comm, parallel::deal_grains(model.points, model.grains, scheme, comm.size()), scheme);
  std::unique_ptr<Outputs> out_ptr;  // after every input check: nothing written before
  if (root) out_ptr = std::make_unique<Outputs>(cfg, summary.output_dir, observer.csv_header());
  const bool stop_active = cfg.stop.phi > 0 || cfg.stop.strain > 0 || cfg.stop.stress > 0;
  const auto gather_state = [&](int to) {
    ScopedStage ts(&solver.timers(), "output");
    parallel::gather_points(comm, model.points, model.grains, solver.owner(), to);
  };

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
    const bool csv = force || t >= next_csv - eps, vtu = force || t >= next_vtu - eps;
    if (!csv && !vtu) return;
    if (comm.size() > 1) gather_state(0);
    ScopedStage ts(&solver.timers(), "output");
    const auto problem = parallel::gather_contacts(comm, solver.contact_problem(), 0);
    if (csv) {
      if (root)
        out_ptr->csv_row(summary.steps, t, dt, last, mpm::diagnostics(model),
                         observer.csv_fields(model, last, problem, t));
      next_csv = t + cfg.output.csv_interval;
    }
    if (vtu) {
      if (root) out_ptr->vtu(model, solver, problem, t);
      next_vtu = t + cfg.output.vtu_interval;
    }
  };
  record(true);
  const auto wall0 = std::chrono::steady_clock::now();
  auto last_progress = wall0;
  while (t < t_end - 1e-9 * dt_nominal) {
    const double dt_try = std::min(dt, t_end - t);
    solver.set_time(t);
    if (any_moving) solver.set_boundary_conditions(build_boundaries(cfg, model.grid, t + dt_try));
    mpm::StepStats st = solver.solve_step(dt_try);
    if (!st.converged) {
      ++summary.failed_steps;
      const double dt_new = dt_try * cfg.time.cut_factor;
      if (!st.retryable || dt_new < cfg.time.dt_min) {
        if (comm.size() > 1) gather_state(0);
        const std::string saved = root ? out_ptr->last_good(model) : std::string();
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
    if (comm.size() > 1 && scheme == parallel::Scheme::kPartition && opt.rebalance > 0 &&
        (summary.steps + 1) % 50 == 0) {  // docs/parallel.md: deterministic work weights
      ScopedStage ts(&solver.timers(), "rebalance");
      auto owner = solver.owner();
      bool moved = false;
      const double imbalance = parallel::rebalance(comm, model.points, model.grains, owner,
                                                   solver.take_grain_work(), opt.rebalance, moved);
      if (moved) {
        solver.set_distribution(&comm, owner, scheme);
        log().info("step {}: work imbalance {:.3f} > {}: grains dealt again", summary.steps + 1,
                   imbalance, opt.rebalance);
      }
    }
    t += dt_try;
    ++summary.steps;
    summary.newton_iterations += st.iterations;
    if (dt < dt_nominal && ++good_since_cut >= cfg.time.recover_steps) {
      dt = std::min(dt_nominal, 2 * dt);
      good_since_cut = 0;
      log().info("dt restored to {:.4g} s at t = {:.9g} s", dt, t);
    }
    if (stop_active && comm.size() > 1) gather_state(-1);  // Phi needs every grain's area
    const auto stop = observer.stop_reason(model, st, t);  // [stop] criteria
    record(stop || t >= t_end - 1e-9 * dt_nominal);
    if (stop) {
      log().info("step {}, t = {:.9g} s: {}", summary.steps, t, *stop);
      summary.stop_reason = *stop;
      break;
    }
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
  // Per-stage timers over ranks with the serial shares (docs/parallel.md): <name>_timers.csv.
  std::vector<double> bytes{static_cast<double>(comm.bytes_sent())};
  comm.sum(bytes);
  const auto report = parallel::stage_report(comm, solver.timers().totals());
  const std::string csv = parallel::stage_report_csv(
      report, summary.wall_seconds, comm.size(), omp_get_max_threads(), summary.steps,
      bytes[0] / comm.size() / std::max<std::int64_t>(summary.steps, 1));
  if (root) {
    io::write_file_atomic(
        (fs::path(summary.output_dir) / (cfg.simulation.name + "_timers.csv")).string(), csv);
    log().info("{} rank(s), scheme {}: timers in {}_timers.csv", comm.size(),
               parallel::to_string(scheme), cfg.simulation.name);
  }
  log().info("outputs in {}", summary.output_dir);
  return summary;
}

}  // namespace mpmcd::app
