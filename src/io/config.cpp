// The schema of the simulation input: every table and key, declared once with the member of
// io::Config it fills, its type, range, unit, documented default and description. It validates the
// TOML (io/table_reader.cpp), fills the Config (io/config_reader.cpp) and generates docs/input.md
// (io/markdown.cpp). The defaults documented here are read from a default-constructed section, so
// config.hpp stays the single source of defaults.
#include <vector>

#include "law_keys.hpp"
#include "mpmcd/io/config.hpp"
#include "mpmcd/io/load_config.hpp"
#include "mpmcd/io/schema.hpp"
#include "mpmcd/materials/law.hpp"
#include "schema_tables.hpp"

namespace mpmcd::io {

/// KeySpecs of a law's parameters (all required), from the materials registry.
std::vector<KeySpec> law_keys(const materials::LawInfo& law) {
  std::vector<KeySpec> keys;
  for (const auto& p : law.params) {
    KeySpec k = KeySpec::number(p.name, p.unit, p.description).require();
    // The registry writes "> 0" as min = 1e-300 and "no upper bound" as max = 1e300.
    if (p.min > 0.0 && p.min < 1e-200)
      k.greater_than(0.0);
    else
      k.at_least(p.min);
    if (p.max < 1e300) k.at_most(p.max);
    keys.push_back(std::move(k));
  }
  return keys;
}

std::vector<std::string> law_names() {
  std::vector<std::string> names;
  for (const auto& law : materials::law_registry()) names.push_back(law.name);
  return names;
}

namespace {

Schema build_schema() {
  Schema s;
  s.title = "mpmcd input reference";
  s.description =
      "The simulation input is one TOML file in SI units. Unknown keys, wrong types, missing "
      "required keys, values out of range, NaN and Inf are rejected with a message naming the "
      "file, line and key. An integer is accepted where a number is expected, not the reverse. "
      "`Dim` is `simulation.dimension` (arrays marked `Dim` have that many entries).\n\n"
      "This file is generated from the schema in `src/io/config.cpp` "
      "(`mpmcd::io::input_reference_markdown()`); do not edit it by hand.\n\n"
      "Minimal example: `examples/squeezed_disk/squeezed_disk.toml`.";

  s.tables.push_back(
      {"",
       "",
       "The file holds these tables; `[[name]]` tables may be repeated.",
       {KeySpec::subtable("simulation", &Config::simulation, "global settings")
            .defaults("its defaults"),
        KeySpec::subtable("grid", &Config::grid, "the background grid").require(),
        KeySpec::table_array("materials", &Config::materials, "named materials")
            .require()
            .nonempty(),
        KeySpec::table_array("grains", &Config::grains, "the grains").require().nonempty(),
        KeySpec::table_array("boundary", &Config::boundaries, "prescribed nodal velocities")
            .defaults("none"),
        KeySpec::subtable("loads", &Config::loads, "body forces").defaults("its defaults"),
        KeySpec::subtable("time", &Config::time, "time stepping").require(),
        KeySpec::subtable("solver", &Config::solver, "Newton and linear solver")
            .defaults("its defaults"),
        KeySpec::subtable("contact", &Config::contact, "Contact Dynamics").defaults("its defaults"),
        KeySpec::table_array("walls", &Config::walls, "rigid walls").defaults("none"),
        KeySpec::subtable("loading", &Config::loading,
                          "wall loading stages (velocity or stress control)")
            .defaults("none"),
        KeySpec::subtable("stop", &Config::stop, "compaction stop criteria").defaults("none"),
        KeySpec::subtable("output", &Config::output, "output files").defaults("its defaults"),
        KeySpec::subtable("checkpoint", &Config::checkpoint, "restart files")
            .defaults("its defaults")},
       ""});

  s.add_table(&Config::simulation,
              "Global settings. `dimension = 2` is plane strain (grains are disks, rectangles or "
              "packings of disks); `dimension = 3` is 3D (grains are spheres, boxes or packings of "
              "spheres; docs/three_d.md lists what 3D does not have yet).",
              {KeySpec::string("name", &SimulationSection::name,
                               "run name used in output file names (letters, digits, `_ - .`)")
                   .nonempty()
                   .default_of_member(),
               KeySpec::integer("dimension", &SimulationSection::dimension, "",
                                "spatial dimension (2 = plane strain, 3 = 3D)")
                   .at_least(2)
                   .at_most(3)
                   .default_of_member(),
               KeySpec::integer("threads", &SimulationSection::threads, "",
                                "OpenMP threads, 0 = OpenMP default")
                   .at_least(0)
                   .default_of_member()});

  s.add_table(
      &Config::grid,
      "The uniform background grid: `extent / cell_size` cells per axis, a whole number and at "
      "least 2; at most 1e8 nodes in all.",
      {KeySpec::numbers("origin", &GridSection::origin, "Dim", "m", "lower corner of the grid")
           .require(),
       KeySpec::numbers("extent", &GridSection::extent, "Dim", "m",
                        "size of the grid along each axis")
           .require()
           .greater_than(0.0),
       KeySpec::number("cell_size", &GridSection::cell_size, "m", "cell edge length h")
           .require()
           .greater_than(0.0),
       KeySpec::string("shape_function", &GridSection::shape_function, "MPM shape functions")
           .one_of({"linear", "ugimp", "cpdi"})
           .default_of_member(),
       KeySpec::boolean("split_points", &GridSection::split_points,
                        "with `cpdi`: after each step, a point whose domain F D0 spans more than "
                        "one cell along an axis is split in two along its most stretched edge, "
                        "so that every domain fits its 3-node window and the domains keep tiling "
                        "the grain (docs/accuracy.md, \"Point splitting\"); false shrinks such a "
                        "domain to the window instead. No effect with other shape functions")
           .default_of_member()});

  s.add_table(
      &Config::materials, "A named material and its constitutive law. Names are unique.",
      {KeySpec::string("name", &MaterialSection::name, "name referenced by `grains[].material`")
           .require()
           .nonempty(),
       KeySpec::string("law", &MaterialSection::law, "constitutive law (see Constitutive laws)")
           .require()
           .one_of(law_names()),
       KeySpec::number("density", &MaterialSection::density, "kg/m^3", "initial mass density rho0")
           .require()
           .greater_than(0.0)},
      "Besides `name`, `law` and `density`, a `[[materials]]` table holds exactly the "
      "parameters of its law, all required (see Constitutive laws below).");

  s.add_table(
      &Config::grains,
      "One grain, a body seeded with material points, or a packing of grains read from a file. "
      "`disk` (2D) and `sphere` (3D) need `center` and `radius`; `rectangle` (2D) and `box` (3D) "
      "need `min_corner` < `max_corner`; `packing` needs `file` (relative to the input "
      "file's folder, must exist): disks in 2D, spheres in 3D (`# dimension = 3` files). Keys of "
      "other shapes are rejected. A grain must lie inside "
      "the grid with at least one cell of margin on every side (ghost nodes). A sphere is "
      "seeded on the lattice, its points' volumes scaled to the exact 4/3 pi r^3.",
      {KeySpec::string("shape", &GrainSection::shape, "geometry of the grain")
           .require()
           .one_of({"disk", "rectangle", "packing", "sphere", "box"}),
       KeySpec::string("material", &GrainSection::material, "name of a `[[materials]]` entry")
           .require()
           .nonempty(),
       KeySpec::numbers("center", &GrainSection::center, "Dim", "m", "disk or sphere center")
           .with_note("disk, sphere"),
       KeySpec::number("radius", &GrainSection::radius, "m", "disk or sphere radius")
           .greater_than(0.0)
           .with_note("disk, sphere"),
       KeySpec::numbers("min_corner", &GrainSection::min_corner, "Dim", "m", "lower corner")
           .with_note("rectangle, box"),
       KeySpec::numbers("max_corner", &GrainSection::max_corner, "Dim", "m", "upper corner")
           .with_note("rectangle, box"),
       KeySpec::string("file", &GrainSection::file,
                       "packing CSV file, or a packing input (.toml, docs/packing.md) generated "
                       "by DEM when the run starts; relative to the input file's folder")
           .nonempty()
           .with_note("packing"),
       KeySpec::integer("points_per_cell", &GrainSection::points_per_cell, "",
                        "material points per cell along each axis")
           .at_least(1)
           .at_most(8)
           .default_of_member(),
       KeySpec::string(
           "seeding", &GrainSection::seeding,
           "where the points go: `lattice` (grid-aligned sites, spacing h / "
           "points_per_cell) or `polar` (2D disks and packings only: concentric rings of "
           "that spacing, outermost point domains tangent to the circle, "
           "docs/contact.md)")
           .one_of({"lattice", "polar"})
           .defaults(
               "polar for disk and 2D packing, lattice for rectangle, sphere, box and 3D packing"),
       KeySpec::subtable("initial", &GrainSection::initial, "initial velocity field")
           .defaults("at rest")});

  s.add_table(
      &GrainSection::initial,
      "Initial velocity of the grain's points, written after its `[[grains]]` table: "
      "v(x) = velocity + gradient (x - c) + angular_velocity e_z x (x - c) "
      "+ sine_amplitude sin(sine_wavevector . (x - origin) + sine_phase), with c the grain "
      "center and origin the grid origin. All parts default to zero.",
      {KeySpec::numbers("velocity", &InitialVelocity::velocity, "Dim", "m/s", "uniform part")
           .defaults("zeros"),
       KeySpec::numbers("gradient", &InitialVelocity::gradient, "Dim*Dim", "1/s",
                        "velocity gradient L, row-major")
           .defaults("zeros"),
       KeySpec::number("angular_velocity", &InitialVelocity::angular_velocity, "rad/s",
                       "rigid spin about the grain center (2D only)")
           .default_of_member(),
       KeySpec::numbers("sine_amplitude", &InitialVelocity::sine_amplitude, "Dim", "m/s",
                        "amplitude of the sine part")
           .defaults("zeros"),
       KeySpec::numbers("sine_wavevector", &InitialVelocity::sine_wavevector, "Dim", "rad/m",
                        "wave vector k of the sine part")
           .defaults("zeros"),
       KeySpec::number("sine_phase", &InitialVelocity::sine_phase, "rad", "phase of the sine part")
           .default_of_member()});

  s.add_table(
      &Config::boundaries,
      "Prescribed velocity components on a set of grid nodes: a side of the grid (its outermost "
      "row of nodes), all nodes, or the nodes inside a box (`box_min` < `box_max`, containing "
      "at least one node; only with `nodes = \"box\"`). `zmin`, `zmax` and `z` are for 3D.",
      {KeySpec::string("nodes", &BoundarySection::nodes, "the node set")
           .require()
           .one_of({"xmin", "xmax", "ymin", "ymax", "zmin", "zmax", "all", "box"}),
       KeySpec::numbers("box_min", &BoundarySection::box_min, "Dim", "m",
                        "lower corner of the node box")
           .with_note("box"),
       KeySpec::numbers("box_max", &BoundarySection::box_max, "Dim", "m",
                        "upper corner of the node box")
           .with_note("box"),
       KeySpec::strings("fix", &BoundarySection::fix, "prescribed velocity components")
           .require()
           .one_of({"x", "y", "z"})
           .nonempty()
           .distinct(),
       KeySpec::numbers("velocity", &BoundarySection::velocity, "Dim", "m/s",
                        "prescribed velocity (free components ignored)")
           .defaults("zeros"),
       KeySpec::boolean("moving", &BoundarySection::moving,
                        "the box translates with `velocity` (a grid platen): at time t the set "
                        "is the nodes inside [box_min + velocity t, box_max + velocity t]")
           .defaults("false")
           .with_note("box")});

  s.add_table(&Config::loads, "Body forces.",
              {KeySpec::numbers("gravity", &LoadsSection::gravity, "Dim", "m/s^2",
                                "gravitational acceleration")
                   .defaults("zeros")});

  s.add_table(
      &Config::time,
      "Implicit theta-method time stepping. `end_time` >= `dt` and `dt_min` <= `dt`. A failed "
      "step is retried with dt multiplied by `cut_factor`, down to `dt_min`.",
      {KeySpec::number("dt", &TimeSection::dt, "s", "nominal time step")
           .require()
           .greater_than(0.0),
       KeySpec::number("end_time", &TimeSection::end_time, "s",
                       "simulated time at which the run stops")
           .require()
           .greater_than(0.0),
       KeySpec::number("theta", &TimeSection::theta, "", "theta of the theta-method")
           .at_least(0.5)
           .at_most(1.0)
           .default_of_member(),
       KeySpec::number("dt_min", &TimeSection::dt_min, "s", "smallest step allowed after cuts")
           .greater_than(0.0)
           .defaults("dt/1024"),
       KeySpec::number("cut_factor", &TimeSection::cut_factor, "",
                       "factor applied to dt when a step fails")
           .greater_than(0.0)
           .less_than(1.0)
           .default_of_member(),
       KeySpec::integer("recover_steps", &TimeSection::recover_steps, "",
                        "successful steps after which a cut dt is doubled back (control = "
                        "\"newton\": may grow again)")
           .at_least(1)
           .default_of_member(),
       KeySpec::string("control", &TimeSection::control,
                       "\"fixed\": dt, cut on failure and restored; \"newton\": after each step "
                       "dt is scaled by sqrt(target_iterations / Newton iterations), within [0.5, "
                       "1.25], dt_min and dt_max")
           .one_of({"fixed", "newton"})
           .default_of_member(),
       KeySpec::number("dt_max", &TimeSection::dt_max, "s",
                       "largest step, control = \"newton\" only; dt is the first step")
           .greater_than(0.0)
           .defaults("dt"),
       KeySpec::integer("target_iterations", &TimeSection::target_iterations, "",
                        "Newton iterations per step aimed at, control = \"newton\" only; below "
                        "solver.max_iterations")
           .at_least(1)
           .default_of_member()});

  s.add_table(
      &Config::solver, "Newton-Raphson and linear solver settings.",
      {KeySpec::integer("max_iterations", &SolverSection::max_iterations, "",
                        "Newton iterations before the step fails")
           .at_least(1)
           .default_of_member(),
       KeySpec::number("residual_tolerance", &SolverSection::residual_tolerance, "",
                       "relative residual tolerance")
           .greater_than(0.0)
           .default_of_member(),
       KeySpec::number("increment_tolerance", &SolverSection::increment_tolerance, "",
                       "relative velocity-increment tolerance")
           .greater_than(0.0)
           .default_of_member(),
       KeySpec::string("linear_solver", &SolverSection::linear_solver,
                       "sparse direct LDLT, sparse LU, or Jacobi CG")
           .one_of({"ldlt", "lu", "cg"})
           .default_of_member(),
       KeySpec::number("cg_tolerance", &SolverSection::cg_tolerance, "",
                       "relative residual of the CG solve")
           .greater_than(0.0)
           .default_of_member(),
       KeySpec::integer("cg_max_iterations", &SolverSection::cg_max_iterations, "",
                        "CG iteration limit")
           .at_least(1)
           .default_of_member(),
       KeySpec::number("flip", &SolverSection::flip, "",
                       "FLIP fraction of the G2P velocity update (1 FLIP, 0 PIC)")
           .at_least(0.0)
           .at_most(1.0)
           .default_of_member(),
       KeySpec::boolean("affine", &SolverSection::affine,
                        "affine P2G: each point carries its velocity gradient L and gives its "
                        "nodes m N (v + L (x_I - x_p)) (APIC/TPIC), so that linear velocity "
                        "fields cross the grid exactly")
           .default_of_member(),
       KeySpec::boolean("modified_newton", &SolverSection::modified_newton,
                        "modified Newton: factorise the Newton matrix once per step and reuse it "
                        "(and the contact compliance) in later iterations, refactorising when the "
                        "residual stalls above residual_tolerance; same converged answer, fewer "
                        "factorisations")
           .default_of_member(),
       KeySpec::number("dense_fill", &SolverSection::dense_fill, "",
                       "with ldlt, a grain whose sparse factor fills at least this fraction of "
                       "its lower triangle is factorised dense (LL^T, blocked kernels); pays "
                       "for 3D CPDI grains in an MPMCD_NATIVE build (0.5); above 1: never")
           .greater_than(0.0)
           .default_of_member()});

  add_interaction_tables(s);
  return s;
}

}  // namespace

const Schema& config_schema() {
  static const Schema schema = build_schema();
  return schema;
}

}  // namespace mpmcd::io
