// The schema of the simulation input: every table and key, declared once with the member of
// io::Config it fills, its type, range, unit, documented default and description. It validates the
// TOML (io/table_reader.cpp), fills the Config (io/config_reader.cpp) and generates docs/input.md
// (io/markdown.cpp). The defaults documented here are read from a default-constructed section, so
// config.hpp stays the single source of defaults.
#include <vector>

#include "law_keys.hpp"
#include "mpmcd/contact/law.hpp"
#include "mpmcd/io/config.hpp"
#include "mpmcd/io/load_config.hpp"
#include "mpmcd/io/schema.hpp"
#include "mpmcd/materials/law.hpp"

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
                        "residual stalls; same converged answer, fewer factorisations")
           .default_of_member()});

  s.add_table(
      &Config::contact,
      "Contact Dynamics between grains and with walls (method.md §4): Signorini non-penetration "
      "and Coulomb friction, solved by nonlinear Gauss-Seidel staggered with the Newton "
      "iterations. Candidates are grid nodes where two grain fields carry more than "
      "`mass_fraction` of a full cell's mass, and grain nodes within `wall_range` cells of a "
      "wall.",
      {KeySpec::boolean("enabled", &ContactSection::enabled, "solve contacts").default_of_member(),
       KeySpec::string("criterion", &ContactSection::criterion,
                       "grain-grain switch-on: \"gap\" (from the points' domains: when the "
                       "materials meet) or \"overlap\" (any shared node: about a cell early)")
           .one_of({"gap", "overlap"})
           .default_of_member(),
       KeySpec::string("law", &ContactSection::law,
                       "contact law of every contact, from the contact-law registry "
                       "(contact/law.hpp): \"coulomb\" = Signorini non-penetration and Coulomb "
                       "friction with the coefficients `friction`, `[[contact.pairs]]` and the "
                       "walls' `friction` (docs/contact.md)")
           .one_of(contact::contact_law_names())
           .default_of_member(),
       KeySpec::number("friction", &ContactSection::friction, "",
                       "default grain-grain Coulomb coefficient mu_f")
           .at_least(0.0)
           .default_of_member(),
       KeySpec::number("mass_fraction", &ContactSection::mass_fraction, "",
                       "threshold of a field's nodal mass, in full cells")
           .greater_than(0.0)
           .at_most(1.0)
           .default_of_member(),
       KeySpec::number("tolerance", &ContactSection::tolerance, "", "Gauss-Seidel error tolerance")
           .greater_than(0.0)
           .default_of_member(),
       KeySpec::integer("max_sweeps", &ContactSection::max_sweeps, "", "Gauss-Seidel sweep limit")
           .at_least(1)
           .default_of_member(),
       KeySpec::number("relaxation", &ContactSection::relaxation, "",
                       "over-relaxation omega of the frictionless contacts' Gauss-Seidel updates "
                       "(projected SOR): 1 = plain Gauss-Seidel; up to 1.9 speeds up packings "
                       "where several grains meet at one node (docs/contact.md)")
           .at_least(1.0)
           .less_than(2.0)
           .default_of_member(),
       KeySpec::integer("relax_after", &ContactSection::relax_after, "",
                        "Gauss-Seidel sweeps before the over-relaxation starts")
           .at_least(0)
           .default_of_member(),
       KeySpec::boolean("node_blocks", &ContactSection::node_blocks,
                        "solve the frictionless contacts of each node (2 to 6) together and "
                        "exactly (nodal block Gauss-Seidel) instead of one by one: for nodes "
                        "where a light field is pinched between grains (docs/contact.md)")
           .default_of_member(),
       KeySpec::number("impulse_tolerance", &ContactSection::impulse_tolerance, "",
                       "relative change of impulses between Newton iterations")
           .greater_than(0.0)
           .default_of_member(),
       KeySpec::number("wall_range", &ContactSection::wall_range, "",
                       "grain nodes within this many cells of a wall")
           .greater_than(0.0)
           .at_most(3.0)
           .default_of_member(),
       KeySpec::number("gap_horizon", &ContactSection::gap_horizon, "",
                       "grain_contact = \"faces\": a face becomes a contact only if its gap "
                       "could close within this many steps at twice the step's largest speed "
                       "(grain nodes, walls, plus gravity dt); farther faces cannot touch in "
                       "the step. 0: every face within `wall_range` cells (docs/contact.md)")
           .at_least(0.0)
           .default_of_member(),
       KeySpec::string("wall_contact", &ContactSection::wall_contact,
                       "where a wall acts: \"nodes\" (a grain node's velocity may not cross "
                       "it) or \"points\" (the velocity of each point domain's face toward it, "
                       "interpolated from the nodes, may not cross it: holds the material edge at "
                       "the wall; one MPI rank only for now; docs/accuracy.md)")
           .one_of({"nodes", "points"})
           .default_of_member(),
       KeySpec::string("grain_contact", &ContactSection::grain_contact,
                       "where grains meet: \"nodes\" (the two fields' velocities at each shared "
                       "grid node) or \"faces\" (the boundary faces of one grain's points against "
                       "the other grain's velocity there: contact on the material surface; one MPI "
                       "rank only for now; docs/contact.md)")
           .one_of({"nodes", "faces"})
           .default_of_member(),
       KeySpec::string("solver", &ContactSection::solver,
                       "contact solver: \"gauss_seidel\" (nonlinear Gauss-Seidel, any friction) "
                       "or \"active_set\" (frictionless only: the normal impulses' complementarity "
                       "problem by block principal pivoting with a sparse LDL^T, whose cost does "
                       "not grow with near-redundant contacts such as grain_contact = \"faces\"; "
                       "one MPI rank only for now; docs/contact.md)")
           .one_of({"gauss_seidel", "active_set"})
           .default_of_member(),
       KeySpec::string("delassus", &ContactSection::delassus,
                       "contact compliance: \"grain\" (each grain's exact linearised response "
                       "from its factorised Newton matrix; direct solvers), \"lumped\" (1/m_I), "
                       "or \"auto\" (grain when theta c_p dt / h > 0.1 and the solver is direct)")
           .one_of({"auto", "grain", "lumped"})
           .default_of_member(),
       KeySpec::table_array("pairs", &ContactSection::pairs, "friction per pair of materials")
           .defaults("none")});

  s.add_table(
      &ContactSection::pairs, "Friction between two materials (overrides `contact.friction`).",
      {KeySpec::strings("materials", &ContactPairSection::materials, "the two material names")
           .require(),
       KeySpec::number("friction", &ContactPairSection::friction, "", "Coulomb coefficient mu_f")
           .require()
           .at_least(0.0)});

  s.add_table(
      &Config::walls,
      "A rigid plane wall of infinite mass: the plane through `point` + `velocity` t with "
      "`normal` pointing into the domain. Every grain must start inside every wall.",
      {KeySpec::string("name", &WallSection::name,
                       "name used in the CSV columns (letters, digits, `_ -`)")
           .require()
           .nonempty(),
       KeySpec::numbers("point", &WallSection::point, "Dim", "m", "a point of the plane at t = 0")
           .require(),
       KeySpec::numbers("normal", &WallSection::normal, "Dim", "",
                        "normal into the domain (normalised)")
           .require(),
       KeySpec::numbers("velocity", &WallSection::velocity, "Dim", "m/s", "prescribed velocity")
           .defaults("zeros"),
       KeySpec::number("friction", &WallSection::friction, "",
                       "Coulomb coefficient with the grains")
           .at_least(0.0)
           .default_of_member()});

  s.add_table(
      &Config::loading,
      "Wall motions in stages (docs/loading.md), instead of the walls' constant velocities: each "
      "stage sets, for the walls it lists, a target velocity or a target normal stress, reached "
      "linearly over `ramp` and then held, until one of its end conditions. A stress-controlled "
      "wall moves along its normal at v_n = clamp(gain (sigma_measured - sigma_target), "
      "-max_speed, max_speed) (a servo; sigma_measured from the wall force of the last step over "
      "the wall's length (3D: area) between its neighbours, as the `wall_<name>_stress` column), "
      "so it needs the four walls of a box (six in 3D). With `[loading]`, `walls[].velocity` must "
      "be absent or "
      "zero; the walls start at rest.",
      {KeySpec::number("gain", &LoadingSection::gain, "m/(s Pa)",
                       "servo gain g (speed per stress error)")
           .greater_than(0.0)
           .defaults("gain_fraction min(dt/(rho h), h/(M_p dt))"),
       KeySpec::number("gain_fraction", &LoadingSection::gain_fraction, "",
                       "the automatic gain as a fraction of the step's stability limit "
                       "min(dt/(rho h), h/(M_p dt)) (rho, M_p: the densest and stiffest grain "
                       "material, dt = time.dt, h = grid.cell_size; with time.control = "
                       "\"newton\" the second dt is time.dt_max)")
           .greater_than(0.0)
           .at_most(1.0)
           .default_of_member(),
       KeySpec::number("max_speed", &LoadingSection::max_speed, "m/s",
                       "speed limit of a stress-controlled wall")
           .greater_than(0.0)
           .defaults("0.02 c_p (the grains' slowest P-wave speed)"),
       KeySpec::number("integral_time", &LoadingSection::integral_time, "s",
                       "integral time T_i of the servo: v_n = clamp(gain (e + I/T_i)), I the "
                       "time integral of the stress error e while the wall is stress-controlled "
                       "and not at its speed limit; removes the lag v/gain of a servo following "
                       "a moving sample (docs/loading.md, \"Integral action\"); 0: off")
           .at_least(0.0)
           .default_of_member(),
       KeySpec::table_array("stages", &LoadingSection::stages, "the loading stages, in order")
           .require()
           .nonempty()});

  s.add_table(
      &LoadingSection::stages,
      "One loading stage. The walls it does not list keep their control and target (a ramp in "
      "progress goes on). Every stage but the last needs an end condition (`until`); the run "
      "ends when the last stage ends (or at `time.end_time`).",
      {KeySpec::string("name", &StageSection::name, "name shown in the log")
           .nonempty()
           .defaults("stage <k>"),
       KeySpec::number("ramp", &StageSection::ramp, "s",
                       "time over which the listed walls' targets go linearly from their values "
                       "at the stage start (a stress target from the previous target, or from the "
                       "measured stress for a wall that was velocity-controlled) to the stage's; "
                       "0 = at once (a step)")
           .at_least(0.0)
           .default_of_member(),
       KeySpec::subtable("until", &StageSection::until, "end conditions").defaults("none"),
       KeySpec::table_array("walls", &StageSection::walls, "the walls whose control changes")
           .defaults("none")});

  s.add_table(
      &StageSection::until,
      "End conditions of a stage, checked after every step; the first reached ends it. Phi, "
      "eps and a wall stress end it when they cross the value from the side they were on at the "
      "stage start (so a stage may load or unload). Phi, eps and stresses are those of the CSV "
      "(docs/observables.md) and need the four walls of a box (six in 3D).",
      {KeySpec::number("time", &StageUntilSection::time, "s", "duration of the stage")
           .greater_than(0.0)
           .defaults("none"),
       KeySpec::number("phi", &StageUntilSection::phi, "", "solid fraction Phi = Vs/V to cross")
           .greater_than(0.0)
           .at_most(1.0)
           .defaults("none"),
       KeySpec::number("strain", &StageUntilSection::strain, "",
                       "eps = ln(h/h0) to cross (compression negative)")
           .defaults("none"),
       KeySpec::number("stress", &StageUntilSection::stress, "Pa",
                       "normal stress of wall `wall` to cross (compression negative)")
           .less_than(0.0)
           .defaults("none"),
       KeySpec::string("wall", &StageUntilSection::wall, "the wall whose stress `stress` watches")
           .nonempty()
           .with_note("with stress")});

  s.add_table(
      &StageSection::walls,
      "What one wall does from this stage on: `velocity` (its whole velocity), or `stress` (its "
      "normal motion by the servo; `velocity` may then add a slide along the wall, its normal "
      "component zero).",
      {KeySpec::string("name", &StageWallSection::name, "name of a `[[walls]]` entry")
           .require()
           .nonempty(),
       KeySpec::numbers("velocity", &StageWallSection::velocity, "Dim", "m/s", "target velocity")
           .defaults("none"),
       KeySpec::number("stress", &StageWallSection::stress, "Pa",
                       "target normal stress (compression negative, as `wall_<name>_stress`)")
           .less_than(0.0)
           .defaults("none")});

  s.add_table(
      &Config::stop,
      "Stop criteria of a compaction (docs/observables.md): the run stops at the first criterion "
      "reached, or at `time.end_time`, and logs which. They need four walls forming a box "
      "(normals +x, -x, +y, -y; in 3D six, with +z, -z). Checked after every step.",
      {KeySpec::number("phi", &StopSection::phi, "",
                       "stop when the solid fraction Phi = Vs/V reaches this")
           .greater_than(0.0)
           .at_most(1.0)
           .defaults("none"),
       KeySpec::number("strain", &StopSection::strain, "",
                       "stop when |eps| = |ln(h/h0)| reaches this")
           .greater_than(0.0)
           .defaults("none"),
       KeySpec::number("stress", &StopSection::stress, "Pa",
                       "stop when the bottom wall's compressive stress -sigma reaches this")
           .greater_than(0.0)
           .defaults("none")});

  s.add_table(
      &Config::output, "Where and how often to write. An interval of 0 means every step.",
      {KeySpec::string("folder", &OutputSection::folder, "output folder (created)")
           .nonempty()
           .default_of_member(),
       KeySpec::number("vtu_interval", &OutputSection::vtu_interval, "s",
                       "simulated time between VTU snapshots")
           .at_least(0.0)
           .default_of_member(),
       KeySpec::number("csv_interval", &OutputSection::csv_interval, "s",
                       "simulated time between CSV rows")
           .at_least(0.0)
           .default_of_member(),
       KeySpec::boolean("vtu", &OutputSection::vtu, "write VTU/PVD files").default_of_member(),
       KeySpec::number("progress_interval", &OutputSection::progress_interval, "s",
                       "wall time between progress lines")
           .greater_than(0.0)
           .default_of_member(),
       KeySpec::boolean("grains", &OutputSection::grains,
                        "grain-scale outputs: `<name>_grains_<n>.csv` (per-grain stress, shape, "
                        "contacts) and `<name>_forces_<n>.csv` (contact forces per pair) at every "
                        "snapshot time (vtu_interval), fabric and stress columns in the CSV "
                        "(docs/observables.md); in 3D with full symmetric tensors")
           .default_of_member()});

  s.add_table(
      &Config::checkpoint,
      "Restart files `<name>_checkpoint_<step>.h5` (HDF5) in the output folder; "
      "`mpmcd run --restart <file>` continues a run bitwise (docs/robustness.md). A checkpoint is "
      "also written when the run is interrupted (SIGINT, SIGTERM) and when it stops on a "
      "numerical failure (the last good step), whatever these keys say.",
      {KeySpec::integer("every_steps", &CheckpointSection::every_steps, "",
                        "committed steps between checkpoints, 0 = never")
           .at_least(0)
           .default_of_member(),
       KeySpec::number("every_minutes", &CheckpointSection::every_minutes, "min",
                       "wall-clock time between checkpoints, 0 = never")
           .at_least(0.0)
           .at_most(525600.0)
           .default_of_member(),
       KeySpec::integer("keep", &CheckpointSection::keep, "",
                        "checkpoints kept (the oldest are deleted)")
           .at_least(1)
           .at_most(1000)
           .default_of_member(),
       KeySpec::boolean("at_end", &CheckpointSection::at_end,
                        "write a checkpoint when the run reaches `end_time`")
           .default_of_member()});
  return s;
}

}  // namespace

const Schema& config_schema() {
  static const Schema schema = build_schema();
  return schema;
}

}  // namespace mpmcd::io
