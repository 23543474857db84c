#include "mpmcd/app/model_builder.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <numbers>

#include "mpmcd/app/speed_check.hpp"
#include "mpmcd/contact/law.hpp"
#include "mpmcd/core/errors.hpp"
#include "mpmcd/core/log.hpp"
#include "mpmcd/packing/input.hpp"
#include "mpmcd/packing/overlap.hpp"
#include "mpmcd/packing/packing.hpp"
#include "mpmcd/packing/seeding.hpp"
#include "mpmcd/points/seeding.hpp"

namespace mpmcd::app {

namespace fs = std::filesystem;

namespace {

// The Dim components of an input array (checked by the schema to have Dim entries).
template <int Dim>
Vec<Dim> vec_of(const std::vector<double>& v) {
  Vec<Dim> out;
  for (int a = 0; a < Dim; ++a) out[a] = v.at(static_cast<std::size_t>(a));
  return out;
}

// v(x) = velocity + gradient (x - c) + omega e_z x (x - c) + A sin(k . x + phase) (InitialVelocity;
// the spin is 2D only, refused by the input in 3D)
template <int Dim>
Vec<Dim> initial_velocity(const io::InitialVelocity& iv, const Vec<Dim>& c, const Vec<Dim>& x) {
  Vec<Dim> v = Vec<Dim>::Zero();
  if (iv.velocity.size() == Dim) v += vec_of<Dim>(iv.velocity);
  if (iv.gradient.size() == Dim * Dim) {
    Mat<Dim> L;
    for (int a = 0; a < Dim; ++a)
      for (int b = 0; b < Dim; ++b) L(a, b) = iv.gradient[static_cast<std::size_t>(a * Dim + b)];
    v += L * (x - c);
  }
  if constexpr (Dim == 2) {
    const Vec<2> r = x - c;
    v += iv.angular_velocity * Vec<2>(-r[1], r[0]);
  }
  if (iv.sine_amplitude.size() == Dim && iv.sine_wavevector.size() == Dim)
    v += vec_of<Dim>(iv.sine_amplitude) *
         std::sin(vec_of<Dim>(iv.sine_wavevector).dot(x) + iv.sine_phase);
  return v;
}

// Grain outlines for the overlap check, and what each one is (grain index, packing disk id or -1).
struct Outlines {
  std::vector<packing::Outline> shapes;
  std::vector<std::pair<std::size_t, std::int64_t>> owner;
};

// A 3D grain for the overlap check: a box or a sphere, with what it is.
struct Solid3 {
  Vec<3> lo, hi;          // box corners [m] (a sphere: its center in lo and hi)
  double radius = 0.0;    // sphere radius, 0 for a box [m]
  std::int64_t id = -1;   // sphere id in a packing file, -1 for a [[grains]] sphere or box [-]
  std::size_t grain = 0;  // index of its [[grains]] entry [-]
};

// Center of a packing's disk (2D) or sphere (3D) [m].
template <int Dim>
Vec<Dim> disk_center(const packing::Disk& d) {
  if constexpr (Dim == 2)
    return Vec<2>(d.x, d.y);
  else
    return Vec<3>(d.x, d.y, d.z);
}

// "[a, b] x [c, d] (x [e, f])" of a box [lo, hi] [m].
template <int Dim>
std::string box_text(const Vec<Dim>& lo, const Vec<Dim>& hi) {
  std::vector<std::string> sides;
  for (int a = 0; a < Dim; ++a) sides.push_back(fmt::format("[{:.6g}, {:.6g}]", lo[a], hi[a]));
  return fmt::format("{}", fmt::join(sides, " x "));
}

// Refuses a packing input whose box cannot fit inside the grid (one cell of margin) before the
// DEM runs (issue 17: 20,000 disks took 18 s to be refused). The box is known when given; else
// its smallest possible size follows from the smallest grains at the target packing fraction
// (grow, walls) or at Phi = 1 (jam, whose final Phi is found by the run), with the box shapes of
// packing::generate_packing (3D: W x W x H, W / H = aspect_ratio).
template <int Dim>
void check_packing_box(const packing::PackingParams& p, const grid::Grid<Dim>& grid,
                       const io::Config& cfg, std::size_t index) {
  const auto& g = cfg.grains[index];
  const double h = grid.cell_size();
  const Vec<Dim> lo = grid.origin().array() + h, hi = grid.upper().array() - h;
  Vec<Dim> b0, b1;
  if (p.box) {
    b0.template head<2>() = Vec<2>((*p.box)[0], (*p.box)[1]);
    b1.template head<2>() = Vec<2>((*p.box)[2], (*p.box)[3]);
    if constexpr (Dim == 3) b0[2] = p.box_z[0], b1[2] = p.box_z[1];
  } else {
    double measure = 0;  // smallest possible grain area (3D: volume) [m^Dim]
    if (!p.diameters.empty())
      for (const double d : p.diameters) measure += points::ball_measure<Dim>(0.5 * d);
    else
      measure = static_cast<double>(p.count) * points::ball_measure<Dim>(0.5 * p.diameter_min);
    const double phi = p.method == packing::PackingMethod::kJam ? 1.0 : p.target_phi;
    const double a = p.aspect_ratio;
    b0.template head<2>() = Vec<2>(p.origin[0], p.origin[1]);
    if constexpr (Dim == 2) {
      b1 = b0 + Vec<2>(std::sqrt(measure / phi * a), std::sqrt(measure / phi / a));
    } else {
      b0[2] = p.origin_z;
      const double height = std::cbrt(measure / phi / (a * a));
      b1 = b0 + Vec<3>(a * height, a * height, height);
    }
  }
  if ((b0.array() < lo.array()).any() || (b1.array() > hi.array()).any())
    throw InputError(g.file, 0, "packing",
                     fmt::format("the packing box {} m{} must lie inside the grid with one cell "
                                 "of margin, {} m (grains[{}], {}:{}); checked before the DEM "
                                 "runs",
                                 box_text<Dim>(b0, b1), p.box ? "" : " (at least)",
                                 box_text<Dim>(lo, hi), index, cfg.source_path, g.line));
}

// Every disk (sphere) of a packing file or input becomes a grain: on polar rings (2D) or on the
// lattice (points from packing::seed_packing, which gives a lattice site shared by two
// overlapping grains to one of them only). Their outlines go to the overlap check.
template <int Dim>
void add_packing_grains(mpm::Model<Dim>& model, const io::Config& cfg, std::size_t index,
                        int material, Outlines& outlines, std::vector<Solid3>& solids3d) {
  const auto& g = cfg.grains[index];
  constexpr const char* kNoun = Dim == 2 ? "disk" : "sphere";
  const auto wrong_dimension = [&](int got) {
    return fmt::format(
        "a {}D run (grains[{}], {}:{}) needs a packing of {}s (dimension = {}), "
        "got dimension = {}: set [simulation] dimension = {} to run it",
        Dim, index, cfg.source_path, g.line, kNoun, Dim, got, got);
  };
  packing::Packing pk;
  if (fs::path(g.file).extension() == ".toml") {  // a packing input: generate it now (seeded DEM)
    const auto input = packing::load_packing_input(g.file);
    if (input.params.dimension != Dim)
      throw InputError(g.file, 0, "packing.dimension", wrong_dimension(input.params.dimension));
    check_packing_box<Dim>(input.params, model.grid, cfg, index);
    pk = packing::generate_packing(input.params);
    log().info("generated from {}: {}", g.file, packing::summary_line(pk));
  } else {
    pk = packing::read_packing_csv(g.file);
    if (pk.dimension != Dim)
      throw InputError(g.file, 0, "dimension", wrong_dimension(pk.dimension));
  }
  const double h = model.grid.cell_size();
  const Vec<Dim> lo = model.grid.origin().array() + h, hi = model.grid.upper().array() - h;
  for (const auto& d : pk.disks) {
    const Vec<Dim> c = disk_center<Dim>(d);
    if (((c.array() - d.radius) < lo.array()).any() || ((c.array() + d.radius) > hi.array()).any())
      throw InputError(
          g.file, 0, fmt::format("{} {}", kNoun, d.id),
          fmt::format("the {} (center {:.6g} m, radius {:.6g} m) must lie inside the "
                      "grid with one cell of margin (grains[{}], {}:{})",
                      kNoun, fmt::join(c, " "), d.radius, index, cfg.source_path, g.line));
    if constexpr (Dim == 2) {
      outlines.shapes.push_back({d.x, d.y, 0.0, 0.0, d.radius});
      outlines.owner.emplace_back(index, d.id);
    } else {
      solids3d.push_back({c, c, d.radius, d.id, index});
    }
  }
  if constexpr (Dim == 2) {
    if (g.seeding == "polar") {  // each disk on its own rings, strictly inside its circle
      const double s = h / g.points_per_cell;
      double estimate = 0;
      for (const auto& d : pk.disks) estimate += std::numbers::pi * d.radius * d.radius / (s * s);
      if (estimate > 2e8)
        throw InputError(cfg.source_path, g.line, fmt::format("grains[{}].points_per_cell", index),
                         fmt::format("the packing would need about {:.3g} material points (at "
                                     "most 2e8): coarsen the grid or lower points_per_cell",
                                     estimate));
      for (const auto& d : pk.disks) {
        const Vec<2> c(d.x, d.y);
        model.add_grain(points::seed_disk_polar(c, d.radius, h / g.points_per_cell), material,
                        0.5 * h / g.points_per_cell,
                        [&](const Vec<2>& x) { return initial_velocity(g.initial, c, x); });
      }
      return;
    }
  }
  const auto seeded = packing::seed_packing<Dim>(pk, model.grid.origin(), h, g.points_per_cell);
  for (std::size_t k = 0; k < pk.disks.size(); ++k) {
    points::Seeds<Dim> seeds;
    seeds.x.assign(seeded.x.begin() + seeded.offset[k], seeded.x.begin() + seeded.offset[k + 1]);
    seeds.volume.assign(seeded.volume.begin() + seeded.offset[k],
                        seeded.volume.begin() + seeded.offset[k + 1]);
    const Vec<Dim> c = disk_center<Dim>(pk.disks[k]);
    model.add_grain(seeds, material, 0.5 * h / g.points_per_cell,
                    [&](const Vec<Dim>& x) { return initial_velocity<Dim>(g.initial, c, x); });
  }
}

// Grains may touch but not overlap (docs/robustness.md): their common area would be counted twice
// in the volume and Phi. Names both grains (a packing's disk by its id) and the overlap.
void check_no_overlap(const io::Config& cfg, const Outlines& outlines) {
  const auto o = packing::find_overlap(outlines.shapes, packing::kOverlapTolerance);
  if (!o) return;
  const auto describe = [&](std::size_t k) {
    const auto [i, id] = outlines.owner[k];
    const auto& g = cfg.grains[i];
    return id >= 0 ? fmt::format("disk id {} of {} (grains[{}], line {})", id, g.file, i, g.line)
                   : fmt::format("grains[{}] (line {})", i, g.line);
  };
  const std::size_t later = outlines.owner[o->second].first;
  throw InputError(
      cfg.source_path, cfg.grains[later].line, fmt::format("grains[{}]", later),
      fmt::format("grains that touch but do not overlap (up to {:g} of the smaller one's "
                  "diameter or side): {} overlaps {} by {:.6g} m = {:.3g} of the smaller size "
                  "(their common area would be counted twice in the volume and Phi)",
                  packing::kOverlapTolerance, describe(o->second), describe(o->first), o->depth,
                  o->depth / o->size));
}

// The 3D grains (spheres, boxes and packings' spheres, in input order) may touch but not overlap:
// the depth of a pair's overlap, above packing::kOverlapTolerance of the smaller one's size, is
// refused as check_no_overlap does in 2D. Sort and sweep along x: pairs whose x ranges meet.
void check_no_overlap_3d(const io::Config& cfg, const std::vector<Solid3>& solids) {
  const auto size = [](const Solid3& s) {
    return s.radius > 0 ? 2 * s.radius : (s.hi - s.lo).minCoeff();
  };
  const auto lower = [](const Solid3& s) { return s.radius > 0 ? s.lo[0] - s.radius : s.lo[0]; };
  const auto upper = [](const Solid3& s) { return s.radius > 0 ? s.lo[0] + s.radius : s.hi[0]; };
  const auto describe = [&](const Solid3& s) {
    const auto& g = cfg.grains[s.grain];
    return s.id >= 0 ? fmt::format("sphere id {} of {} (grains[{}], line {})", s.id, g.file,
                                   s.grain, g.line)
                     : fmt::format("grains[{}] (line {})", s.grain, g.line);
  };
  std::vector<std::size_t> order(solids.size());
  for (std::size_t k = 0; k < order.size(); ++k) order[k] = k;
  std::sort(order.begin(), order.end(),
            [&](std::size_t a, std::size_t b) { return lower(solids[a]) < lower(solids[b]); });
  for (std::size_t oj = 0; oj < order.size(); ++oj)
    for (std::size_t oi = oj + 1; oi < order.size(); ++oi) {
      // i after j in input order, so that the message names the later grain's line
      std::size_t i = order[oj], j = order[oi];
      if (lower(solids[j]) > upper(solids[i])) break;
      if (j < i) std::swap(i, j);
      const Solid3 &a = solids[i], &b = solids[j];
      double depth = 0;  // how far the two interpenetrate [m]
      if (a.radius > 0 && b.radius > 0) {
        depth = a.radius + b.radius - (a.lo - b.lo).norm();
      } else if (a.radius > 0 || b.radius > 0) {
        const Solid3& ball = a.radius > 0 ? a : b;
        const Solid3& box = a.radius > 0 ? b : a;
        const Vec<3> c = ball.lo;
        const Vec<3> nearest = c.cwiseMax(box.lo).cwiseMin(box.hi);
        const bool inside = ((c.array() > box.lo.array()) && (c.array() < box.hi.array())).all();
        depth = inside ? ball.radius : ball.radius - (c - nearest).norm();
      } else {
        depth = (a.hi.cwiseMin(b.hi) - a.lo.cwiseMax(b.lo)).minCoeff();
      }
      const double smaller = std::min(size(a), size(b));
      if (depth > packing::kOverlapTolerance * smaller)
        throw InputError(
            cfg.source_path, cfg.grains[b.grain].line, fmt::format("grains[{}]", b.grain),
            fmt::format("grains that touch but do not overlap (up to {:g} of the smaller one's "
                        "diameter or side): {} overlaps {} by {:.6g} m = {:.3g} of the smaller "
                        "size (their common volume would be counted twice in the volume and Phi)",
                        packing::kOverlapTolerance, describe(b), describe(a), depth,
                        depth / smaller));
    }
}

}  // namespace

template <int Dim>
mpm::Model<Dim> model_frame(const io::Config& cfg) {
  mpm::Model<Dim> model;
  const double h = cfg.grid.cell_size;
  Vec<Dim> origin;
  IVec<Dim> cells;
  for (int d = 0; d < Dim; ++d) {
    origin[d] = cfg.grid.origin.at(d);
    cells[d] = static_cast<std::int64_t>(std::llround(cfg.grid.extent[d] / h));
  }
  model.grid = grid::Grid<Dim>(origin, h, cells);
  for (const auto& m : cfg.materials) {
    try {
      model.add_material(materials::make_law<Dim>(m.law, m.params), m.density);
    } catch (const InputError& e) {
      throw InputError(cfg.source_path, m.line, "materials." + e.key(), e.what());
    }
  }
  return model;
}

template mpm::Model<2> model_frame<2>(const io::Config&);
template mpm::Model<3> model_frame<3>(const io::Config&);

template <int Dim>
mpm::Model<Dim> build_model(const io::Config& cfg) {
  if (cfg.simulation.dimension != Dim)
    throw InputError(
        cfg.source_path, 0, "simulation.dimension",
        fmt::format("a {}D model asked of a dimension {} input", Dim, cfg.simulation.dimension));
  mpm::Model<Dim> model = model_frame<Dim>(cfg);
  const double h = cfg.grid.cell_size;
  Outlines outlines;             // 2D
  std::vector<Solid3> solids3d;  // 3D
  for (std::size_t i = 0; i < cfg.grains.size(); ++i) {
    const auto& g = cfg.grains[i];
    int material = -1;
    for (std::size_t k = 0; k < cfg.materials.size(); ++k)
      if (cfg.materials[k].name == g.material) material = static_cast<int>(k);
    points::Seeds<Dim> seeds;
    Vec<Dim> center;
    if (g.shape == "disk" || g.shape == "sphere") {  // the input allows each in its dimension
      center = vec_of<Dim>(g.center);
      if constexpr (Dim == 2) {
        outlines.shapes.push_back({center[0], center[1], 0.0, 0.0, g.radius});
        if (g.seeding == "polar")
          seeds = points::seed_disk_polar(center, g.radius, h / g.points_per_cell);
      } else {
        solids3d.push_back({center, center, g.radius, -1, i});
      }
      if (g.seeding != "polar")
        seeds = points::seed_ball<Dim>(model.grid.origin(), h, g.points_per_cell, center, g.radius);
    } else if (g.shape == "rectangle" || g.shape == "box") {
      const Vec<Dim> lo = vec_of<Dim>(g.min_corner), hi = vec_of<Dim>(g.max_corner);
      center = 0.5 * (lo + hi);
      if constexpr (Dim == 2)
        outlines.shapes.push_back({lo[0], lo[1], hi[0], hi[1], 0.0});
      else
        solids3d.push_back({lo, hi, 0.0, -1, i});
      seeds = points::seed_box<Dim>(model.grid.origin(), h, g.points_per_cell, lo, hi);
    } else if (g.shape == "packing") {
      add_packing_grains<Dim>(model, cfg, i, material, outlines, solids3d);
      continue;
    } else {
      throw InputError(cfg.source_path, g.line, fmt::format("grains[{}].shape", i),
                       "unknown shape \"" + g.shape + "\"");
    }
    outlines.owner.emplace_back(i, -1);
    if (seeds.x.empty())
      throw InputError(cfg.source_path, g.line, fmt::format("grains[{}]", i),
                       "the grain is too small to hold a material point at this cell size and "
                       "points_per_cell: refine the grid or raise points_per_cell");
    model.add_grain(seeds, material, 0.5 * h / g.points_per_cell,
                    [&](const Vec<Dim>& x) { return initial_velocity<Dim>(g.initial, center, x); });
  }
  if constexpr (Dim == 2)
    check_no_overlap(cfg, outlines);
  else
    check_no_overlap_3d(cfg, solids3d);
  return model;
}

template mpm::Model<2> build_model<2>(const io::Config&);
template mpm::Model<3> build_model<3>(const io::Config&);

template <int Dim>
std::vector<mpm::VelocityBC<Dim>> build_boundaries(const io::Config& cfg,
                                                   const grid::Grid<Dim>& grid, double t) {
  std::vector<mpm::VelocityBC<Dim>> out;
  const auto& n = grid.nodes_per_axis();
  const double h = grid.cell_size();
  for (const auto& b : cfg.boundaries) {
    mpm::VelocityBC<Dim> bc;
    for (const auto& f : b.fix)
      bc.mask |= static_cast<std::uint8_t>(1u << (f == "x" ? 0 : f == "y" ? 1 : 2));
    bc.velocity = vec_of<Dim>(b.velocity);
    IVec<Dim> lo = IVec<Dim>::Zero(), hi = n - IVec<Dim>::Ones();
    if (b.nodes == "xmin") hi[0] = 0;
    if (b.nodes == "xmax") lo[0] = n[0] - 1;
    if (b.nodes == "ymin") hi[1] = 0;
    if (b.nodes == "ymax") lo[1] = n[1] - 1;
    if constexpr (Dim == 3) {
      if (b.nodes == "zmin") hi[2] = 0;
      if (b.nodes == "zmax") lo[2] = n[2] - 1;
    }
    if (b.nodes == "box") {
      const Vec<Dim> shift = b.moving ? Vec<Dim>(t * bc.velocity) : Vec<Dim>::Zero();
      for (int d = 0; d < Dim; ++d) {
        const double a = (b.box_min[d] + shift[d] - grid.origin()[d]) / h;
        const double z = (b.box_max[d] + shift[d] - grid.origin()[d]) / h;
        lo[d] = std::max<std::int64_t>(0, static_cast<std::int64_t>(std::ceil(a - 1e-9)));
        hi[d] = std::min<std::int64_t>(n[d] - 1, static_cast<std::int64_t>(std::floor(z + 1e-9)));
      }
    }
    if constexpr (Dim == 2) {
      for (std::int64_t j = lo[1]; j <= hi[1]; ++j)
        for (std::int64_t i = lo[0]; i <= hi[0]; ++i) bc.nodes.push_back(grid.node_index({i, j}));
    } else {
      for (std::int64_t k = lo[2]; k <= hi[2]; ++k)
        for (std::int64_t j = lo[1]; j <= hi[1]; ++j)
          for (std::int64_t i = lo[0]; i <= hi[0]; ++i)
            bc.nodes.push_back(grid.node_index({i, j, k}));
    }
    out.push_back(std::move(bc));
  }
  return out;
}

template std::vector<mpm::VelocityBC<2>> build_boundaries<2>(const io::Config&,
                                                             const grid::Grid<2>&, double);
template std::vector<mpm::VelocityBC<3>> build_boundaries<3>(const io::Config&,
                                                             const grid::Grid<3>&, double);

bool contact_enabled(const io::Config& cfg, std::size_t grains) {
  return cfg.contact.enabled && (grains > 1 || !cfg.walls.empty());
}

template <int Dim>
std::vector<walls::Wall<Dim>> input_walls(const io::Config& cfg) {
  std::vector<walls::Wall<Dim>> out;
  for (const auto& w : cfg.walls)
    out.push_back(
        {w.name, vec_of<Dim>(w.point), vec_of<Dim>(w.normal), vec_of<Dim>(w.velocity), w.friction});
  return out;
}

template std::vector<walls::Wall<2>> input_walls<2>(const io::Config&);
template std::vector<walls::Wall<3>> input_walls<3>(const io::Config&);

template <int Dim>
mpm::Settings<Dim> build_settings(const io::Config& cfg, const mpm::Model<Dim>& model) {
  mpm::Settings<Dim> s;
  s.shape = grid::shape_kind_from_string(cfg.grid.shape_function);
  s.theta = cfg.time.theta;
  s.max_iterations = cfg.solver.max_iterations;
  s.residual_tolerance = cfg.solver.residual_tolerance;
  s.increment_tolerance = cfg.solver.increment_tolerance;
  s.linear_solver = mpm::linear_solver_from_string(cfg.solver.linear_solver);
  s.cg_tolerance = cfg.solver.cg_tolerance;
  s.cg_max_iterations = cfg.solver.cg_max_iterations;
  s.flip = cfg.solver.flip;
  s.affine = cfg.solver.affine;
  s.modified_newton = cfg.solver.modified_newton;
  s.dense_fill = cfg.solver.dense_fill;
  if (cfg.loads.gravity.size() == Dim) s.gravity = vec_of<Dim>(cfg.loads.gravity);
  auto& c = s.contact;
  c.enabled = contact_enabled(cfg, model.grains.size());
  c.criterion =
      cfg.contact.criterion == "overlap" ? mpm::GapCriterion::kOverlap : mpm::GapCriterion::kGap;
  c.mass_fraction = cfg.contact.mass_fraction;
  c.gs.tolerance = cfg.contact.tolerance;
  c.gs.max_sweeps = cfg.contact.max_sweeps;
  c.gs.relaxation = cfg.contact.relaxation;
  c.gs.relax_after = cfg.contact.relax_after;
  c.gs.node_blocks = cfg.contact.node_blocks;
  c.impulse_tolerance = cfg.contact.impulse_tolerance;
  c.wall_range = cfg.contact.wall_range;
  c.gap_horizon = cfg.contact.gap_horizon;
  c.wall_points = cfg.contact.wall_contact == "points";
  c.grain_faces = cfg.contact.grain_contact == "faces";
  c.face_normals_at_end = cfg.contact.face_normals == "end";
  c.active_set = cfg.contact.solver == "active_set";
  // Delassus operator: the lumped 1/m_I is accurate when inertia dominates a step (theta c_p dt/h
  // small); otherwise each grain's exact compliance (needs a direct solver) keeps the staggered
  // contact-Newton loop converging in a few iterations. Judged at the largest step of the run.
  double cp = 0;
  for (const double c_k : wave_speeds(model)) cp = std::max(cp, c_k);
  const double courant = cfg.time.theta * cp * cfg.time.largest_dt() / cfg.grid.cell_size;
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
  c.walls = input_walls<Dim>(cfg);
  c.law = cfg.contact.law;
  const contact::ContactLaw& law = contact::find_contact_law(c.law);
  if (c.active_set && !law.active_set)
    throw InputError(cfg.source_path, 0, "contact.solver",
                     fmt::format("solver = \"active_set\" does not solve the contact law \"{}\": "
                                 "use solver = \"gauss_seidel\"",
                                 law.name));
  // The active-set solver solves the normal impulses only, and a law may read no friction at
  // all: refuse friction rather than drop it.
  if (c.active_set || !law.reads("friction")) {
    const auto refuse = [&](std::int64_t line, const std::string& where) {
      if (c.active_set)
        throw InputError(cfg.source_path, line, "contact.solver",
                         fmt::format("solver = \"active_set\" solves frictionless contacts "
                                     "only, but {} has friction: use solver = \"gauss_seidel\"",
                                     where));
      throw InputError(
          cfg.source_path, line, "contact.law",
          fmt::format("contact law \"{}\" has no friction, but {} has friction", law.name, where));
    };
    if (cfg.contact.friction != 0.0) refuse(0, "the default grain pair (contact.friction)");
    for (const auto& p : cfg.contact.pairs)
      if (p.friction != 0.0) refuse(p.line, "a [[contact.pairs]] entry");
    for (const auto& w : cfg.walls)
      if (w.friction != 0.0) refuse(w.line, fmt::format("wall \"{}\"", w.name));
  }
  return s;
}

template mpm::Settings<2> build_settings<2>(const io::Config&, const mpm::Model<2>&);
template mpm::Settings<3> build_settings<3>(const io::Config&, const mpm::Model<3>&);

template <int Dim>
void check_walls_enclose(const io::Config& cfg, const mpm::Model<Dim>& model,
                         const mpm::Settings<Dim>& settings) {
  for (std::size_t k = 0; k < settings.contact.walls.size(); ++k) {
    const auto& wall = settings.contact.walls[k];
    for (std::size_t p = 0; p < model.points.size(); ++p)
      if (wall.distance(model.points.x[p], 0.0) < 0.0)
        throw InputError(
            cfg.source_path, cfg.walls[k].line, fmt::format("walls[{}]", k),
            fmt::format("wall \"{}\" does not enclose the grains: grain {} has a "
                        "material point at ({:.6g}) m on its outer side",
                        wall.name, model.points.grain[p],
                        fmt::join(model.points.x[p].data(), model.points.x[p].data() + Dim, ", ")));
  }
}

template void check_walls_enclose<2>(const io::Config&, const mpm::Model<2>&,
                                     const mpm::Settings<2>&);
template void check_walls_enclose<3>(const io::Config&, const mpm::Model<3>&,
                                     const mpm::Settings<3>&);

}  // namespace mpmcd::app
