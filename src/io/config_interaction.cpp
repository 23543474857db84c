// The schema of the input, second part: the contact between grains and with walls, the walls and
// their loading, the stop criteria, the outputs and checkpoints (the first part, the model and
// time stepping, is in config.cpp; each key declared once with the member it fills).
#include "mpmcd/contact/law.hpp"
#include "mpmcd/io/config.hpp"
#include "mpmcd/io/schema.hpp"
#include "schema_tables.hpp"

namespace mpmcd::io {

void add_interaction_tables(Schema& s) {
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
       KeySpec::string("face_normals", &ContactSection::face_normals,
                       "grain_contact = \"faces\": the normal of each face contact, \"end\" (the "
                       "face's normal at the Newton iterate's end-of-step configuration, with its "
                       "geometric stiffness in the grain's Newton matrix: the interface pressure "
                       "follows the faces as they turn) or \"start\" (the face's normal at the "
                       "start of the step, held through it); docs/contact.md")
           .one_of({"end", "start"})
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
}

}  // namespace mpmcd::io
