// Loader of the simulation input (one TOML file, SI units): the schema of every table, the
// generic checks of io/schema.cpp, then the checks across keys (grid size, grains inside the grid,
// material references, time-step bounds, ...). The defaults documented in the schema are read from
// a default-constructed Config, so config.hpp stays the single source of defaults.
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "mpmcd/core/errors.hpp"
#include "mpmcd/io/load_config.hpp"
#include "mpmcd/io/schema.hpp"
#include "mpmcd/materials/law.hpp"

namespace mpmcd::io {

namespace {

constexpr double kMaxNodes = 1e8;                     // largest grid accepted [-]
constexpr std::uintmax_t kMaxFileBytes = 16u << 20u;  // largest input file accepted [bytes]
constexpr const char* kAxes[] = {"x", "y", "z"};

std::string num(double v) {
  return fmt::format("{}", v);
}
std::string str(const std::string& s) {
  return "\"" + s + "\"";
}
std::string boolean_text(bool b) {
  return b ? "true" : "false";
}

std::string vec_text(const std::vector<double>& v) {
  std::string out = "[";
  for (std::size_t i = 0; i < v.size(); ++i) out += (i ? ", " : "") + num(v[i]);
  return out + "]";
}

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

Schema build_schema() {
  const Config d{};
  const GrainSection dg{};
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
       {KeySpec::subtable("simulation", "simulation", "global settings").defaults("its defaults"),
        KeySpec::subtable("grid", "grid", "the background grid").require(),
        KeySpec::table_array("materials", "materials[]", "named materials").require().nonempty(),
        KeySpec::table_array("grains", "grains[]", "the grains").require().nonempty(),
        KeySpec::table_array("boundary", "boundary[]", "prescribed nodal velocities")
            .defaults("none"),
        KeySpec::subtable("loads", "loads", "body forces").defaults("its defaults"),
        KeySpec::subtable("time", "time", "time stepping").require(),
        KeySpec::subtable("solver", "solver", "Newton and linear solver").defaults("its defaults"),
        KeySpec::subtable("contact", "contact", "Contact Dynamics").defaults("its defaults"),
        KeySpec::table_array("walls", "walls[]", "rigid walls").defaults("none"),
        KeySpec::subtable("stop", "stop", "compaction stop criteria").defaults("none"),
        KeySpec::subtable("output", "output", "output files").defaults("its defaults"),
        KeySpec::subtable("checkpoint", "checkpoint", "restart files").defaults("its defaults")},
       ""});

  s.tables.push_back(
      {"simulation",
       "[simulation]",
       "Global settings. Only `dimension = 2` (plane strain) is supported for now; 3 is planned "
       "and rejected with a message.",
       {KeySpec::string("name", "run name used in output file names (letters, digits, `_ - .`)")
            .nonempty()
            .defaults(str(d.simulation.name)),
        KeySpec::integer("dimension", "", "spatial dimension (2 = plane strain)")
            .at_least(2)
            .at_most(3)
            .with_note("3 not yet supported")
            .defaults(num(d.simulation.dimension)),
        KeySpec::integer("threads", "", "OpenMP threads, 0 = OpenMP default")
            .at_least(0)
            .defaults(num(d.simulation.threads))},
       ""});

  s.tables.push_back(
      {"grid",
       "[grid]",
       "The uniform background grid: `extent / cell_size` cells per axis, a whole number and at "
       "least 2; at most 1e8 nodes in all.",
       {KeySpec::numbers("origin", "Dim", "m", "lower corner of the grid").require(),
        KeySpec::numbers("extent", "Dim", "m", "size of the grid along each axis")
            .require()
            .greater_than(0.0),
        KeySpec::number("cell_size", "m", "cell edge length h").require().greater_than(0.0),
        KeySpec::string("shape_function", "MPM shape functions")
            .one_of({"linear", "ugimp", "cpdi"})
            .defaults(str(d.grid.shape_function))},
       ""});

  s.tables.push_back(
      {"materials[]",
       "[[materials]]",
       "A named material and its constitutive law. Names are unique.",
       {KeySpec::string("name", "name referenced by `grains[].material`").require().nonempty(),
        KeySpec::string("law", "constitutive law (see Constitutive laws)")
            .require()
            .one_of(law_names()),
        KeySpec::number("density", "kg/m^3", "initial mass density rho0")
            .require()
            .greater_than(0.0)},
       "Besides `name`, `law` and `density`, a `[[materials]]` table holds exactly the "
       "parameters of its law, all required (see Constitutive laws below)."});

  s.tables.push_back(
      {"grains[]",
       "[[grains]]",
       "One grain, a body seeded with material points, or a packing of grains read from a file. "
       "`disk` needs `center` and `radius`; `rectangle` needs `min_corner` < `max_corner`; "
       "`packing` needs `file` (relative to the input file's folder, must exist). Keys of other "
       "shapes are rejected. A disk or rectangle must lie inside the grid with at least one cell "
       "of margin on every side (ghost nodes).",
       {KeySpec::string("shape", "geometry of the grain")
            .require()
            .one_of({"disk", "rectangle", "packing"}),
        KeySpec::string("material", "name of a `[[materials]]` entry").require().nonempty(),
        KeySpec::numbers("center", "Dim", "m", "disk center").with_note("disk"),
        KeySpec::number("radius", "m", "disk radius").greater_than(0.0).with_note("disk"),
        KeySpec::numbers("min_corner", "Dim", "m", "lower corner").with_note("rectangle"),
        KeySpec::numbers("max_corner", "Dim", "m", "upper corner").with_note("rectangle"),
        KeySpec::string("file",
                        "packing CSV file, or a packing input (.toml, docs/packing.md) generated "
                        "by DEM when the run starts; relative to the input file's folder")
            .nonempty()
            .with_note("packing"),
        KeySpec::integer("points_per_cell", "", "material points per cell along each axis")
            .at_least(1)
            .at_most(8)
            .defaults(num(dg.points_per_cell)),
        KeySpec::string("seeding",
                        "where the points go: `lattice` (grid-aligned sites, spacing h / "
                        "points_per_cell) or `polar` (disks only: concentric rings of that "
                        "spacing, outermost point domains tangent to the circle, docs/contact.md)")
            .one_of({"lattice", "polar"})
            .defaults("polar for disk and packing, lattice for rectangle"),
        KeySpec::subtable("initial", "grains[].initial", "initial velocity field")
            .defaults("at rest")},
       ""});

  s.tables.push_back(
      {"grains[].initial",
       "[grains.initial]",
       "Initial velocity of the grain's points, written after its `[[grains]]` table: "
       "v(x) = velocity + gradient (x - c) + angular_velocity e_z x (x - c) "
       "+ sine_amplitude sin(sine_wavevector . (x - origin) + sine_phase), with c the grain "
       "center and origin the grid origin. All parts default to zero.",
       {KeySpec::numbers("velocity", "Dim", "m/s", "uniform part").defaults("zeros"),
        KeySpec::numbers("gradient", "Dim*Dim", "1/s", "velocity gradient L, row-major")
            .defaults("zeros"),
        KeySpec::number("angular_velocity", "rad/s", "rigid spin about the grain center (2D)")
            .defaults(num(InitialVelocity{}.angular_velocity)),
        KeySpec::numbers("sine_amplitude", "Dim", "m/s", "amplitude of the sine part")
            .defaults("zeros"),
        KeySpec::numbers("sine_wavevector", "Dim", "rad/m", "wave vector k of the sine part")
            .defaults("zeros"),
        KeySpec::number("sine_phase", "rad", "phase of the sine part")
            .defaults(num(InitialVelocity{}.sine_phase))},
       ""});

  s.tables.push_back(
      {"boundary[]",
       "[[boundary]]",
       "Prescribed velocity components on a set of grid nodes: a side of the grid (its outermost "
       "row of nodes), all nodes, or the nodes inside a box (`box_min` < `box_max`, containing "
       "at least one node; only with `nodes = \"box\"`). `zmin`, `zmax` and `z` are for 3D.",
       {KeySpec::string("nodes", "the node set")
            .require()
            .one_of({"xmin", "xmax", "ymin", "ymax", "zmin", "zmax", "all", "box"}),
        KeySpec::numbers("box_min", "Dim", "m", "lower corner of the node box").with_note("box"),
        KeySpec::numbers("box_max", "Dim", "m", "upper corner of the node box").with_note("box"),
        KeySpec::strings("fix", "prescribed velocity components")
            .require()
            .one_of({"x", "y", "z"})
            .nonempty()
            .distinct(),
        KeySpec::numbers("velocity", "Dim", "m/s", "prescribed velocity (free components ignored)")
            .defaults("zeros"),
        KeySpec::boolean("moving",
                         "the box translates with `velocity` (a grid platen): at time t the set "
                         "is the nodes inside [box_min + velocity t, box_max + velocity t]")
            .defaults("false")
            .with_note("box")},
       ""});

  s.tables.push_back({"loads",
                      "[loads]",
                      "Body forces.",
                      {KeySpec::numbers("gravity", "Dim", "m/s^2", "gravitational acceleration")
                           .defaults("zeros")},
                      ""});

  s.tables.push_back(
      {"time",
       "[time]",
       "Implicit theta-method time stepping. `end_time` >= `dt` and `dt_min` <= `dt`. A failed "
       "step is retried with dt multiplied by `cut_factor`, down to `dt_min`.",
       {KeySpec::number("dt", "s", "nominal time step").require().greater_than(0.0),
        KeySpec::number("end_time", "s", "simulated time at which the run stops")
            .require()
            .greater_than(0.0),
        KeySpec::number("theta", "", "theta of the theta-method")
            .at_least(0.5)
            .at_most(1.0)
            .defaults(num(d.time.theta)),
        KeySpec::number("dt_min", "s", "smallest step allowed after cuts")
            .greater_than(0.0)
            .defaults("dt/1024"),
        KeySpec::number("cut_factor", "", "factor applied to dt when a step fails")
            .greater_than(0.0)
            .less_than(1.0)
            .defaults(num(d.time.cut_factor)),
        KeySpec::integer("recover_steps", "",
                         "successful steps after which a cut dt is doubled back")
            .at_least(1)
            .defaults(num(d.time.recover_steps))},
       ""});

  s.tables.push_back(
      {"solver",
       "[solver]",
       "Newton-Raphson and linear solver settings.",
       {KeySpec::integer("max_iterations", "", "Newton iterations before the step fails")
            .at_least(1)
            .defaults(num(d.solver.max_iterations)),
        KeySpec::number("residual_tolerance", "", "relative residual tolerance")
            .greater_than(0.0)
            .defaults(num(d.solver.residual_tolerance)),
        KeySpec::number("increment_tolerance", "", "relative velocity-increment tolerance")
            .greater_than(0.0)
            .defaults(num(d.solver.increment_tolerance)),
        KeySpec::string("linear_solver", "sparse direct LDLT, sparse LU, or Jacobi CG")
            .one_of({"ldlt", "lu", "cg"})
            .defaults(str(d.solver.linear_solver)),
        KeySpec::number("cg_tolerance", "", "relative residual of the CG solve")
            .greater_than(0.0)
            .defaults(num(d.solver.cg_tolerance)),
        KeySpec::integer("cg_max_iterations", "", "CG iteration limit")
            .at_least(1)
            .defaults(num(d.solver.cg_max_iterations)),
        KeySpec::number("flip", "", "FLIP fraction of the G2P velocity update (1 FLIP, 0 PIC)")
            .at_least(0.0)
            .at_most(1.0)
            .defaults(num(d.solver.flip)),
        KeySpec::boolean("affine",
                         "affine P2G: each point carries its velocity gradient L and gives its "
                         "nodes m N (v + L (x_I - x_p)) (APIC/TPIC), so that linear velocity "
                         "fields cross the grid exactly")
            .defaults(boolean_text(d.solver.affine)),
        KeySpec::boolean("modified_newton",
                         "modified Newton: factorise the Newton matrix once per step and reuse it "
                         "(and the contact compliance) in later iterations, refactorising when the "
                         "residual stalls; same converged answer, fewer factorisations")
            .defaults(boolean_text(d.solver.modified_newton))},
       ""});

  s.tables.push_back(
      {"contact",
       "[contact]",
       "Contact Dynamics between grains and with walls (method.md §4): Signorini non-penetration "
       "and Coulomb friction, solved by nonlinear Gauss-Seidel staggered with the Newton "
       "iterations. Candidates are grid nodes where two grain fields carry more than "
       "`mass_fraction` of a full cell's mass, and grain nodes within `wall_range` cells of a "
       "wall.",
       {KeySpec::boolean("enabled", "solve contacts").defaults(boolean_text(d.contact.enabled)),
        KeySpec::string("criterion",
                        "grain-grain switch-on: \"gap\" (from the points' domains: when the "
                        "materials meet) or \"overlap\" (any shared node: about a cell early)")
            .one_of({"gap", "overlap"})
            .defaults(str(d.contact.criterion)),
        KeySpec::number("friction", "", "default grain-grain Coulomb coefficient mu_f")
            .at_least(0.0)
            .defaults(num(d.contact.friction)),
        KeySpec::number("mass_fraction", "", "threshold of a field's nodal mass, in full cells")
            .greater_than(0.0)
            .at_most(1.0)
            .defaults(num(d.contact.mass_fraction)),
        KeySpec::number("tolerance", "", "Gauss-Seidel error tolerance")
            .greater_than(0.0)
            .defaults(num(d.contact.tolerance)),
        KeySpec::integer("max_sweeps", "", "Gauss-Seidel sweep limit")
            .at_least(1)
            .defaults(num(d.contact.max_sweeps)),
        KeySpec::number("relaxation", "",
                        "over-relaxation omega of the frictionless contacts' Gauss-Seidel updates "
                        "(projected SOR): 1 = plain Gauss-Seidel; up to 1.9 speeds up packings "
                        "where several grains meet at one node (docs/contact.md)")
            .at_least(1.0)
            .less_than(2.0)
            .defaults(num(d.contact.relaxation)),
        KeySpec::integer("relax_after", "", "Gauss-Seidel sweeps before the over-relaxation starts")
            .at_least(0)
            .defaults(num(d.contact.relax_after)),
        KeySpec::boolean("node_blocks",
                         "solve the frictionless contacts of each node (2 to 6) together and "
                         "exactly (nodal block Gauss-Seidel) instead of one by one: for nodes "
                         "where a light field is pinched between grains (docs/contact.md)")
            .defaults(boolean_text(d.contact.node_blocks)),
        KeySpec::number("impulse_tolerance", "",
                        "relative change of impulses between Newton iterations")
            .greater_than(0.0)
            .defaults(num(d.contact.impulse_tolerance)),
        KeySpec::number("wall_range", "", "grain nodes within this many cells of a wall")
            .greater_than(0.0)
            .at_most(3.0)
            .defaults(num(d.contact.wall_range)),
        KeySpec::string("wall_contact",
                        "where a wall acts: \"nodes\" (a grain node's velocity may not cross "
                        "it) or \"points\" (the velocity of each point domain's face toward it, "
                        "interpolated from the nodes, may not cross it: holds the material edge at "
                        "the wall; one MPI rank only for now; docs/accuracy.md)")
            .one_of({"nodes", "points"})
            .defaults(str(d.contact.wall_contact)),
        KeySpec::string("delassus",
                        "contact compliance: \"grain\" (each grain's exact linearised response "
                        "from its factorised Newton matrix; direct solvers), \"lumped\" (1/m_I), "
                        "or \"auto\" (grain when theta c_p dt / h > 0.1 and the solver is direct)")
            .one_of({"auto", "grain", "lumped"})
            .defaults(str(d.contact.delassus)),
        KeySpec::table_array("pairs", "contact.pairs[]", "friction per pair of materials")
            .defaults("none")},
       ""});

  s.tables.push_back(
      {"contact.pairs[]",
       "[[contact.pairs]]",
       "Friction between two materials (overrides `contact.friction`).",
       {KeySpec::strings("materials", "the two material names").require(),
        KeySpec::number("friction", "", "Coulomb coefficient mu_f").require().at_least(0.0)},
       ""});

  s.tables.push_back(
      {"walls[]",
       "[[walls]]",
       "A rigid plane wall of infinite mass: the plane through `point` + `velocity` t with "
       "`normal` pointing into the domain. Every grain must start inside every wall.",
       {KeySpec::string("name", "name used in the CSV columns (letters, digits, `_ -`)")
            .require()
            .nonempty(),
        KeySpec::numbers("point", "Dim", "m", "a point of the plane at t = 0").require(),
        KeySpec::numbers("normal", "Dim", "", "normal into the domain (normalised)").require(),
        KeySpec::numbers("velocity", "Dim", "m/s", "prescribed velocity").defaults("zeros"),
        KeySpec::number("friction", "", "Coulomb coefficient with the grains")
            .at_least(0.0)
            .defaults("0")},
       ""});

  s.tables.push_back(
      {"stop",
       "[stop]",
       "Stop criteria of a compaction (docs/observables.md): the run stops at the first criterion "
       "reached, or at `time.end_time`, and logs which. They need four walls forming a box "
       "(normals +x, -x, +y, -y). Checked after every step.",
       {KeySpec::number("phi", "", "stop when the solid fraction Phi = Vs/V reaches this")
            .greater_than(0.0)
            .at_most(1.0)
            .defaults("none"),
        KeySpec::number("strain", "", "stop when |eps| = |ln(h/h0)| reaches this")
            .greater_than(0.0)
            .defaults("none"),
        KeySpec::number("stress", "Pa",
                        "stop when the bottom wall's compressive stress -sigma reaches this")
            .greater_than(0.0)
            .defaults("none")},
       ""});

  s.tables.push_back(
      {"output",
       "[output]",
       "Where and how often to write. An interval of 0 means every step.",
       {KeySpec::string("folder", "output folder (created)")
            .nonempty()
            .defaults(str(d.output.folder)),
        KeySpec::number("vtu_interval", "s", "simulated time between VTU snapshots")
            .at_least(0.0)
            .defaults(num(d.output.vtu_interval)),
        KeySpec::number("csv_interval", "s", "simulated time between CSV rows")
            .at_least(0.0)
            .defaults(num(d.output.csv_interval)),
        KeySpec::boolean("vtu", "write VTU/PVD files").defaults(boolean_text(d.output.vtu)),
        KeySpec::number("progress_interval", "s", "wall time between progress lines")
            .greater_than(0.0)
            .defaults(num(d.output.progress_interval))},
       ""});

  s.tables.push_back(
      {"checkpoint",
       "[checkpoint]",
       "Restart files `<name>_checkpoint_<step>.h5` (HDF5) in the output folder; "
       "`mpmcd run --restart <file>` continues a run bitwise (docs/robustness.md). A checkpoint is "
       "also written when the run is interrupted (SIGINT, SIGTERM) and when it stops on a "
       "numerical failure (the last good step), whatever these keys say.",
       {KeySpec::integer("every_steps", "", "committed steps between checkpoints, 0 = never")
            .at_least(0)
            .defaults(num(d.checkpoint.every_steps)),
        KeySpec::number("every_minutes", "min", "wall-clock time between checkpoints, 0 = never")
            .at_least(0.0)
            .at_most(525600.0)
            .defaults(num(d.checkpoint.every_minutes)),
        KeySpec::integer("keep", "", "checkpoints kept (the oldest are deleted)")
            .at_least(1)
            .at_most(1000)
            .defaults(num(d.checkpoint.keep)),
        KeySpec::boolean("at_end", "write a checkpoint when the run reaches `end_time`")
            .defaults(boolean_text(d.checkpoint.at_end))},
       ""});
  return s;
}

/// Reads the whole input once the TOML is parsed.
class ConfigReader {
 public:
  ConfigReader(const toml::table& root, const std::string& source_name)
      : root_(root), schema_(config_schema()), source_(source_name) {
    ctx_.file = source_name;
    ctx_.schema = &schema_;
  }

  Config read() {
    Config c;
    TableReader r(root_, schema_.table(""), ctx_, "", 0);
    read_simulation(r, c);
    read_grid(r, c);
    read_materials(r, c);
    read_grains(r, c);
    read_boundaries(r, c);
    if (const toml::table* t = r.subtable("loads")) {
      TableReader l(*t, schema_.table("loads"), ctx_, "loads", line_of(*t));
      l.read("gravity", c.loads.gravity);
    }
    if (c.loads.gravity.empty()) c.loads.gravity.assign(dim_, 0.0);
    read_time(r, c);
    read_solver(r, c);
    read_contact(r, c);
    read_walls(r, c);
    read_stop(r, c);
    read_output(r, c);
    read_checkpoint(r, c);
    return c;
  }

 private:
  /// The reader of sub-table `key` of `parent`; an empty table if absent.
  TableReader sub(const TableReader& parent, std::string_view key, const std::string& path) {
    const toml::table* t = parent.subtable(key);
    if (!t) return TableReader(empty_, schema_.table(path), ctx_, std::string(key), 0);
    return TableReader(*t, schema_.table(path), ctx_, parent.key_path(key), line_of(*t));
  }

  void read_simulation(const TableReader& root, Config& c) {
    TableReader r = sub(root, "simulation", "simulation");
    r.read("name", c.simulation.name);
    r.read("dimension", c.simulation.dimension);
    r.read("threads", c.simulation.threads);
    for (char ch : c.simulation.name)
      if (!(std::isalnum(static_cast<unsigned char>(ch)) || ch == '_' || ch == '-' || ch == '.'))
        r.fail("name", fmt::format("expected letters, digits, '_', '-' or '.' only (it names "
                                   "output files), got \"{}\"",
                                   c.simulation.name));
    if (c.simulation.dimension == 3)
      r.fail("dimension",
             "dimension 3 is not yet supported (3D is planned); use dimension = 2 (plane strain)");
    dim_ = static_cast<std::size_t>(c.simulation.dimension);
    ctx_.lengths = {{"Dim", dim_}, {"Dim*Dim", dim_ * dim_}};
  }

  void read_grid(const TableReader& root, Config& c) {
    TableReader r = sub(root, "grid", "grid");
    GridSection& g = c.grid;
    r.read("origin", g.origin);
    r.read("extent", g.extent);
    r.read("cell_size", g.cell_size);
    r.read("shape_function", g.shape_function);
    double nodes = 1.0;
    for (std::size_t a = 0; a < dim_; ++a) nodes *= std::floor(g.extent[a] / g.cell_size) + 1.0;
    if (!(nodes <= kMaxNodes))
      r.fail("cell_size",
             fmt::format("the grid would have {:.3g} nodes, more than the limit of {:.0e}; use "
                         "larger cells or a smaller extent",
                         nodes, kMaxNodes));
    for (std::size_t a = 0; a < dim_; ++a) {
      const double n = g.extent[a] / g.cell_size;
      if (n < 2.0 - 1e-9)
        r.fail("extent", fmt::format("expected at least 2 cells along {} (extent >= 2 cell_size "
                                     "= {} m), got {} m = {:.6g} cells",
                                     kAxes[a], num(2 * g.cell_size), num(g.extent[a]), n));
      if (std::fabs(n - std::round(n)) > 1e-6 * std::max(1.0, n))
        r.fail("extent",
               fmt::format("expected a whole number of cells along {}: extent {} m / cell_size {} "
                           "m = {:.6g} cells",
                           kAxes[a], num(g.extent[a]), num(g.cell_size), n));
    }
  }

  void read_materials(const TableReader& root, Config& c) {
    const auto tables = root.table_array("materials");
    std::map<std::string, std::int64_t> seen;  // name -> line
    for (std::size_t i = 0; i < tables.size(); ++i) {
      const toml::table& t = *tables[i];
      const std::string path = fmt::format("materials[{}]", i);
      const std::int64_t line = line_of(t);
      // The law decides which other keys the table has, so it is checked first.
      const toml::node* law_node = t.get("law");
      if (!law_node)
        throw InputError(source_, line, path + ".law",
                         "missing required key (one of " +
                             fmt::format("{}", fmt::join(law_names(), ", ")) + ")");
      const auto law = law_node->value_exact<std::string>();
      if (!law)
        throw InputError(source_, line_of(*law_node), path + ".law",
                         fmt::format("expected one of {}, got {}", fmt::join(law_names(), ", "),
                                     describe_node(*law_node)));
      std::vector<KeySpec> extra;
      {
        for (const auto& info : materials::law_registry())
          if (info.name == *law) extra = law_keys(info);
        if (extra.empty()) {
          std::string msg = fmt::format("unknown law \"{}\", expected one of {}", *law,
                                        fmt::join(law_names(), ", "));
          if (const std::string near = nearest_name(*law, law_names()); !near.empty())
            msg += fmt::format(" (did you mean \"{}\"?)", near);
          throw InputError(source_, line_of(*law_node), path + ".law", msg);
        }
      }
      TableReader r(t, schema_.table("materials[]"), ctx_, path, line, extra);
      MaterialSection m;
      m.line = line;
      r.read("name", m.name);
      r.read("law", m.law);
      r.read("density", m.density);
      for (const auto& k : extra) r.read(k.name, m.params[k.name]);
      if (auto [it, inserted] = seen.emplace(m.name, r.line("name")); !inserted)
        r.fail("name", fmt::format("duplicate material name \"{}\" (first defined on line {})",
                                   m.name, it->second));
      c.materials.push_back(std::move(m));
    }
  }

  void read_grains(const TableReader& root, Config& c) {
    const auto tables = root.table_array("grains");
    std::vector<std::string> names;
    for (const auto& m : c.materials) names.push_back(m.name);
    for (std::size_t i = 0; i < tables.size(); ++i) {
      const toml::table& t = *tables[i];
      TableReader r(t, schema_.table("grains[]"), ctx_, fmt::format("grains[{}]", i), line_of(t));
      GrainSection g;
      g.line = r.line();
      r.read("shape", g.shape);
      r.read("material", g.material);
      r.read("center", g.center);
      r.read("radius", g.radius);
      r.read("min_corner", g.min_corner);
      r.read("max_corner", g.max_corner);
      r.read("file", g.file);
      r.read("points_per_cell", g.points_per_cell);
      r.read("seeding", g.seeding);
      if (g.seeding.empty()) g.seeding = g.shape == "rectangle" ? "lattice" : "polar";
      if (g.shape == "rectangle" && g.seeding == "polar")
        r.fail("seeding", "polar seeding is for disks and packings, not for shape \"rectangle\"");
      if (std::find(names.begin(), names.end(), g.material) == names.end()) {
        std::string msg =
            fmt::format("unknown material \"{}\", defined: {}", g.material, fmt::join(names, ", "));
        if (const std::string near = nearest_name(g.material, names); !near.empty())
          msg += fmt::format(" (did you mean \"{}\"?)", near);
        r.fail("material", msg);
      }
      check_shape_keys(r, g.shape);
      if (g.shape == "disk") {
        std::vector<double> lo(dim_), hi(dim_);
        for (std::size_t a = 0; a < dim_; ++a) {
          lo[a] = g.center[a] - g.radius;
          hi[a] = g.center[a] + g.radius;
        }
        check_inside_grid(
            r, c.grid,
            fmt::format("disk (center {}, radius {} m)", vec_text(g.center), num(g.radius)), lo,
            hi);
      } else if (g.shape == "rectangle") {
        for (std::size_t a = 0; a < dim_; ++a)
          if (!(g.min_corner[a] < g.max_corner[a]))
            r.fail("max_corner",
                   fmt::format("expected max_corner > min_corner along {}, got {} <= {}", kAxes[a],
                               num(g.max_corner[a]), num(g.min_corner[a])));
        check_inside_grid(
            r, c.grid,
            fmt::format("rectangle {} to {}", vec_text(g.min_corner), vec_text(g.max_corner)),
            g.min_corner, g.max_corner);
      } else {
        const std::filesystem::path folder = std::filesystem::path(source_).parent_path();
        const std::filesystem::path file = (folder / g.file).lexically_normal();
        std::error_code ec;
        const auto st = std::filesystem::status(file, ec);
        if (std::filesystem::is_directory(st))
          r.fail("file", fmt::format("a packing file (CSV) or packing input (TOML), but \"{}\" "
                                     "(\"{}\", relative to the input file's folder) is a "
                                     "directory",
                                     g.file, file.string()));
        if (!std::filesystem::is_regular_file(st))
          r.fail("file", fmt::format("packing file \"{}\" not found (looked for \"{}\", relative "
                                     "to the input file's folder)",
                                     g.file, file.string()));
        g.file = file.string();
      }
      if (const toml::table* it = r.subtable("initial")) {
        TableReader v(*it, schema_.table("grains[].initial"), ctx_, r.key_path("initial"),
                      line_of(*it));
        v.read("velocity", g.initial.velocity);
        v.read("gradient", g.initial.gradient);
        v.read("angular_velocity", g.initial.angular_velocity);
        v.read("sine_amplitude", g.initial.sine_amplitude);
        v.read("sine_wavevector", g.initial.sine_wavevector);
        v.read("sine_phase", g.initial.sine_phase);
      }
      auto zeros = [](std::vector<double>& v, std::size_t n) {
        if (v.empty()) v.assign(n, 0.0);
      };
      zeros(g.initial.velocity, dim_);
      zeros(g.initial.gradient, dim_ * dim_);
      zeros(g.initial.sine_amplitude, dim_);
      zeros(g.initial.sine_wavevector, dim_);
      c.grains.push_back(std::move(g));
    }
  }

  /// Each shape has its keys: required for it, rejected for the others.
  static void check_shape_keys(const TableReader& r, const std::string& shape) {
    static const std::map<std::string, std::vector<std::string>> keys = {
        {"disk", {"center", "radius"}},
        {"rectangle", {"min_corner", "max_corner"}},
        {"packing", {"file"}}};
    for (const auto& [s, names] : keys)
      for (const auto& k : names) {
        if (s == shape && !r.has(k))
          r.fail(k, fmt::format("missing required key for shape \"{}\"", shape));
        if (s != shape && r.has(k))
          r.fail(k, fmt::format("key is only for shape \"{}\", not for shape \"{}\"", s, shape));
      }
  }

  /// The box [lo, hi] must lie in the grid shrunk by one cell on every side.
  void check_inside_grid(const TableReader& r, const GridSection& g, const std::string& what,
                         const std::vector<double>& lo, const std::vector<double>& hi) const {
    const double tol = 1e-9 * g.cell_size;
    for (std::size_t a = 0; a < dim_; ++a) {
      const double min = g.origin[a] + g.cell_size;
      const double max = g.origin[a] + g.extent[a] - g.cell_size;
      if (lo[a] < min - tol || hi[a] > max + tol)
        r.fail_table(fmt::format(
            "{} must lie inside the grid with one cell of margin (ghost nodes): {} from {} to "
            "{} m allowed, but it spans {} to {} m",
            what, kAxes[a], num(min), num(max), num(lo[a]), num(hi[a])));
    }
  }

  void read_boundaries(const TableReader& root, Config& c) {
    const auto tables = root.table_array("boundary");
    for (std::size_t i = 0; i < tables.size(); ++i) {
      const toml::table& t = *tables[i];
      TableReader r(t, schema_.table("boundary[]"), ctx_, fmt::format("boundary[{}]", i),
                    line_of(t));
      BoundarySection b;
      b.line = r.line();
      r.read("nodes", b.nodes);
      r.read("box_min", b.box_min);
      r.read("box_max", b.box_max);
      r.read("fix", b.fix);
      r.read("velocity", b.velocity);
      r.read("moving", b.moving);
      if (b.velocity.empty()) b.velocity.assign(dim_, 0.0);
      if (dim_ < 3 && (b.nodes == "zmin" || b.nodes == "zmax"))
        r.fail("nodes", fmt::format("\"{}\" exists only in 3D (dimension = 3)", b.nodes));
      for (const auto& f : b.fix)
        if (dim_ < 3 && f == "z") r.fail("fix", "component \"z\" exists only in 3D");
      if (b.nodes == "box") {
        if (!r.has("box_min")) r.fail("box_min", "missing required key for nodes = \"box\"");
        if (!r.has("box_max")) r.fail("box_max", "missing required key for nodes = \"box\"");
        const GridSection& g = c.grid;
        for (std::size_t a = 0; a < dim_; ++a) {
          if (!(b.box_min[a] < b.box_max[a]))
            r.fail("box_max", fmt::format("expected box_max > box_min along {}, got {} <= {}",
                                          kAxes[a], num(b.box_max[a]), num(b.box_min[a])));
          const double n = std::round(g.extent[a] / g.cell_size);
          const double first =
              std::max(0.0, std::ceil((b.box_min[a] - g.origin[a]) / g.cell_size - 1e-9));
          const double last =
              std::min(n, std::floor((b.box_max[a] - g.origin[a]) / g.cell_size + 1e-9));
          if (first > last)
            r.fail_table(fmt::format("the box {} to {} contains no grid node (along {})",
                                     vec_text(b.box_min), vec_text(b.box_max), kAxes[a]));
        }
      } else {
        for (const char* k : {"box_min", "box_max", "moving"})
          if (r.has(k)) r.fail(k, "key is only for nodes = \"box\"");
      }
      c.boundaries.push_back(std::move(b));
    }
  }

  void read_time(const TableReader& root, Config& c) {
    TableReader r = sub(root, "time", "time");
    TimeSection& t = c.time;
    r.read("dt", t.dt);
    r.read("end_time", t.end_time);
    r.read("theta", t.theta);
    t.dt_min = t.dt / 1024.0;
    r.read("dt_min", t.dt_min);
    r.read("cut_factor", t.cut_factor);
    r.read("recover_steps", t.recover_steps);
    if (!(t.end_time >= t.dt))
      r.fail("end_time",
             fmt::format("expected end_time >= dt = {} s, got {}", num(t.dt), num(t.end_time)));
    if (!(t.dt_min <= t.dt))
      r.fail("dt_min",
             fmt::format("expected 0 < dt_min <= dt = {} s, got {}", num(t.dt), num(t.dt_min)));
  }

  void read_solver(const TableReader& root, Config& c) {
    TableReader r = sub(root, "solver", "solver");
    SolverSection& s = c.solver;
    r.read("max_iterations", s.max_iterations);
    r.read("residual_tolerance", s.residual_tolerance);
    r.read("increment_tolerance", s.increment_tolerance);
    r.read("linear_solver", s.linear_solver);
    r.read("cg_tolerance", s.cg_tolerance);
    r.read("cg_max_iterations", s.cg_max_iterations);
    r.read("flip", s.flip);
    r.read("affine", s.affine);
    r.read("modified_newton", s.modified_newton);
  }

  void read_contact(const TableReader& root, Config& c) {
    TableReader r = sub(root, "contact", "contact");
    ContactSection& k = c.contact;
    r.read("enabled", k.enabled);
    r.read("criterion", k.criterion);
    r.read("friction", k.friction);
    r.read("mass_fraction", k.mass_fraction);
    r.read("tolerance", k.tolerance);
    r.read("max_sweeps", k.max_sweeps);
    r.read("relaxation", k.relaxation);
    r.read("relax_after", k.relax_after);
    r.read("node_blocks", k.node_blocks);
    r.read("impulse_tolerance", k.impulse_tolerance);
    r.read("wall_range", k.wall_range);
    r.read("wall_contact", k.wall_contact);
    r.read("delassus", k.delassus);
    const auto tables = r.table_array("pairs");
    for (std::size_t i = 0; i < tables.size(); ++i) {
      const toml::table& t = *tables[i];
      TableReader q(t, schema_.table("contact.pairs[]"), ctx_, fmt::format("contact.pairs[{}]", i),
                    line_of(t));
      ContactPairSection pair;
      pair.line = q.line();
      q.read("materials", pair.materials);
      q.read("friction", pair.friction);
      if (pair.materials.size() != 2)
        q.fail("materials",
               fmt::format("expected 2 material names, got {}", pair.materials.size()));
      for (const auto& m : pair.materials) {
        bool known = false;
        for (const auto& mat : c.materials) known = known || mat.name == m;
        if (!known) q.fail("materials", fmt::format("unknown material \"{}\"", m));
      }
      k.pairs.push_back(std::move(pair));
    }
  }

  void read_walls(const TableReader& root, Config& c) {
    const auto tables = root.table_array("walls");
    for (std::size_t i = 0; i < tables.size(); ++i) {
      const toml::table& t = *tables[i];
      TableReader r(t, schema_.table("walls[]"), ctx_, fmt::format("walls[{}]", i), line_of(t));
      WallSection w;
      w.line = r.line();
      r.read("name", w.name);
      r.read("point", w.point);
      r.read("normal", w.normal);
      r.read("velocity", w.velocity);
      r.read("friction", w.friction);
      if (w.velocity.empty()) w.velocity.assign(dim_, 0.0);
      for (char ch : w.name)
        if (!std::isalnum(static_cast<unsigned char>(ch)) && ch != '_' && ch != '-')
          r.fail("name", fmt::format("\"{}\": only letters, digits, '_' and '-'", w.name));
      for (const auto& other : c.walls)
        if (other.name == w.name) r.fail("name", fmt::format("duplicate wall name \"{}\"", w.name));
      double len = 0;
      for (double x : w.normal) len += x * x;
      len = std::sqrt(len);
      if (!(len > 0)) r.fail("normal", "expected a non-zero normal");
      for (double& x : w.normal) x /= len;
      c.walls.push_back(std::move(w));
    }
  }

  void read_stop(const TableReader& root, Config& c) {
    if (!root.subtable("stop")) return;
    TableReader r = sub(root, "stop", "stop");
    StopSection& s = c.stop;
    s.line = r.line();
    r.read("phi", s.phi);
    r.read("strain", s.strain);
    r.read("stress", s.stress);
    // The criteria are measured on the box of four axis-aligned walls (analysis::find_box).
    int axes[4] = {0, 0, 0, 0};  // +x, -x, +y, -y
    for (const auto& w : c.walls)
      for (int k = 0; k < 4; ++k) {
        const double nx = k < 2 ? (k == 0 ? 1.0 : -1.0) : 0.0;
        const double ny = k < 2 ? 0.0 : (k == 2 ? 1.0 : -1.0);
        if (std::fabs(w.normal[0] - nx) <= 1e-12 && std::fabs(w.normal[1] - ny) <= 1e-12) ++axes[k];
      }
    const bool box =
        c.walls.size() == 4 && axes[0] == 1 && axes[1] == 1 && axes[2] == 1 && axes[3] == 1;
    if (!box && (s.phi > 0 || s.strain > 0 || s.stress > 0))
      r.fail_table(
          fmt::format("stop criteria need four [[walls]] forming a box (normals +x, -x, "
                      "+y, -y), got {} walls",
                      c.walls.size()));
  }

  void read_output(const TableReader& root, Config& c) {
    TableReader r = sub(root, "output", "output");
    OutputSection& o = c.output;
    r.read("folder", o.folder);
    r.read("vtu_interval", o.vtu_interval);
    r.read("csv_interval", o.csv_interval);
    r.read("vtu", o.vtu);
    r.read("progress_interval", o.progress_interval);
  }

  void read_checkpoint(const TableReader& root, Config& c) {
    TableReader r = sub(root, "checkpoint", "checkpoint");
    CheckpointSection& k = c.checkpoint;
    r.read("every_steps", k.every_steps);
    r.read("every_minutes", k.every_minutes);
    r.read("keep", k.keep);
    r.read("at_end", k.at_end);
  }

  const toml::table& root_;
  const Schema& schema_;
  std::string source_;
  CheckContext ctx_;
  std::size_t dim_ = 2;
  toml::table empty_;
};

}  // namespace

const Schema& config_schema() {
  static const Schema schema = build_schema();
  return schema;
}

Config parse_config(std::string_view text, const std::string& source_name) {
  if (text.find_first_not_of(" \t\r\n") == std::string_view::npos)
    throw InputError(source_name, 0, "",
                     "the file is empty; expected a TOML simulation input (see docs/input.md)");
  if (const auto nul = text.find('\0'); nul != std::string_view::npos) {
    const auto line = 1 + std::count(text.begin(), text.begin() + static_cast<long>(nul), '\n');
    throw InputError(source_name, line, "", "binary data (a NUL byte): expected a TOML text file");
  }
  toml::table root;
  try {
    root = toml::parse(text, std::string_view(source_name));
  } catch (const toml::parse_error& e) {
    throw InputError(source_name, static_cast<std::int64_t>(e.source().begin.line), "",
                     fmt::format("TOML syntax error: {}", e.description()));
  }
  Config c = ConfigReader(root, source_name).read();
  c.source_path = source_name;
  c.source_text = std::string(text);
  return c;
}

Config load_config(const std::string& path) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::file_status st = fs::status(path, ec);
  if (ec || !fs::exists(st))
    throw InputError(path, 0, "", "cannot read the input file: no such file");
  if (fs::is_directory(st))
    throw InputError(path, 0, "", "cannot read the input file: it is a directory");
  if (!fs::is_regular_file(st))
    throw InputError(path, 0, "", "cannot read the input file: not a regular file");
  const std::uintmax_t size = fs::file_size(path, ec);
  if (ec) throw InputError(path, 0, "", "cannot read the input file: " + ec.message());
  if (size > kMaxFileBytes)
    throw InputError(path, 0, "",
                     fmt::format("the file is too large ({} bytes; an input file has at most {} "
                                 "bytes): is it really the TOML input?",
                                 size, kMaxFileBytes));
  std::ifstream in(path, std::ios::binary);
  if (!in)
    throw InputError(path, 0, "",
                     fmt::format("cannot read the input file: {}", std::strerror(errno)));
  std::ostringstream buffer;
  buffer << in.rdbuf();
  if (in.bad()) throw InputError(path, 0, "", "cannot read the input file: read error");
  return parse_config(buffer.str(), path);
}

std::string input_reference_markdown() {
  std::string md = schema_markdown(config_schema());
  md += "\n## Constitutive laws\n\n";
  md +=
      "`materials[].law` is one of the laws below; the `[[materials]]` table then holds "
      "exactly that law's parameters (all required).\n";
  for (const auto& law : materials::law_registry()) {
    md += fmt::format("\n### `{}`\n\n{}\n\n", law.name, law.description);
    md += "| parameter | type | range | unit | description |\n|---|---|---|---|---|\n";
    for (const auto& k : law_keys(law))
      md += fmt::format("| `{}` | {} | {} | {} | {} |\n", k.name, type_text(k),
                        markdown_cell(range_text(k)), markdown_cell(k.unit),
                        markdown_cell(k.description));
  }
  return md;
}

}  // namespace mpmcd::io
