// Loading valid inputs: the example, defaults, every optional table, lines and paths.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "mpmcd/core/errors.hpp"
#include "mpmcd/io/load_config.hpp"

using mpmcd::io::Config;
using mpmcd::io::load_config;
using mpmcd::io::parse_config;

namespace {

const std::string kExample =
    std::string(MPMCD_TEST_DIR) + "/full_input.toml";  // a frozen copy: examples evolve

/// A small valid input (lines 1..22); tests append tables to it.
const std::string kMinimal = R"(# minimal input
[grid]
origin = [-1, 0]
extent = [2, 1.5]
cell_size = 0.25

[[materials]]
name = "soft"
law = "linear_elastic"
density = 1000
lambda = 1e5
mu = 2e5

[[grains]]
shape = "rectangle"
material = "soft"
min_corner = [-0.5, 0.25]
max_corner = [0.5, 1.0]

[time]
dt = 1e-3
end_time = 1
)";

std::string message_of(const std::string& text) {
  try {
    (void)parse_config(text, "case.toml");
  } catch (const mpmcd::InputError& e) {
    return e.what();
  }
  return "no error";
}

}  // namespace

TEST(LoadConfig, ExampleLoadsWithEveryValue) {
  const Config c = load_config(kExample);
  EXPECT_EQ(c.source_path, kExample);
  EXPECT_NE(c.source_text.find("[[materials]]"), std::string::npos);

  EXPECT_EQ(c.simulation.name, "squeezed_disk");
  EXPECT_EQ(c.simulation.dimension, 2);
  EXPECT_EQ(c.simulation.threads, 0);

  EXPECT_EQ(c.grid.origin, (std::vector<double>{0.0, 0.0}));
  EXPECT_EQ(c.grid.extent, (std::vector<double>{0.02, 0.02}));
  EXPECT_DOUBLE_EQ(c.grid.cell_size, 0.0005);
  EXPECT_EQ(c.grid.shape_function, "linear");

  ASSERT_EQ(c.materials.size(), 1u);
  const auto& m = c.materials[0];
  EXPECT_EQ(m.name, "rubber");
  EXPECT_EQ(m.law, "neo_hookean");
  EXPECT_DOUBLE_EQ(m.density, 990.0);
  ASSERT_EQ(m.params.size(), 2u);
  EXPECT_DOUBLE_EQ(m.params.at("mu"), 1.5e6);
  EXPECT_DOUBLE_EQ(m.params.at("lambda"), 3.0e6);
  EXPECT_EQ(m.line, 13);

  ASSERT_EQ(c.grains.size(), 1u);
  const auto& g = c.grains[0];
  EXPECT_EQ(g.shape, "disk");
  EXPECT_EQ(g.material, "rubber");
  EXPECT_EQ(g.center, (std::vector<double>{0.01, 0.0055}));
  EXPECT_DOUBLE_EQ(g.radius, 0.005);
  EXPECT_TRUE(g.min_corner.empty());
  EXPECT_TRUE(g.max_corner.empty());
  EXPECT_TRUE(g.file.empty());
  EXPECT_EQ(g.points_per_cell, 2);
  EXPECT_EQ(g.initial.velocity, (std::vector<double>{0.0, 0.0}));
  EXPECT_EQ(g.initial.gradient, (std::vector<double>{0.0, 0.0, 0.0, 0.0}));
  EXPECT_EQ(g.initial.angular_velocity, 0.0);
  EXPECT_EQ(g.initial.sine_amplitude, (std::vector<double>{0.0, 0.0}));
  EXPECT_EQ(g.initial.sine_wavevector, (std::vector<double>{0.0, 0.0}));
  EXPECT_EQ(g.initial.sine_phase, 0.0);
  EXPECT_EQ(g.line, 21);

  ASSERT_EQ(c.boundaries.size(), 2u);
  EXPECT_EQ(c.boundaries[0].nodes, "ymax");
  EXPECT_EQ(c.boundaries[0].fix, (std::vector<std::string>{"y"}));
  EXPECT_EQ(c.boundaries[0].velocity, (std::vector<double>{0.0, -0.5}));
  EXPECT_TRUE(c.boundaries[0].box_min.empty());
  EXPECT_EQ(c.boundaries[0].line, 29);
  EXPECT_EQ(c.boundaries[1].nodes, "ymin");
  EXPECT_EQ(c.boundaries[1].fix, (std::vector<std::string>{"x", "y"}));
  EXPECT_EQ(c.boundaries[1].velocity, (std::vector<double>{0.0, 0.0}));
  EXPECT_EQ(c.boundaries[1].line, 34);

  EXPECT_EQ(c.loads.gravity, (std::vector<double>{0.0, 0.0}));

  EXPECT_DOUBLE_EQ(c.time.dt, 1e-5);
  EXPECT_DOUBLE_EQ(c.time.end_time, 5e-3);
  EXPECT_DOUBLE_EQ(c.time.theta, 1.0);
  EXPECT_DOUBLE_EQ(c.time.dt_min, 1e-5 / 1024);
  EXPECT_DOUBLE_EQ(c.time.cut_factor, 0.5);
  EXPECT_EQ(c.time.recover_steps, 20);

  const mpmcd::io::SolverSection solver_defaults{};
  EXPECT_EQ(c.solver.max_iterations, solver_defaults.max_iterations);
  EXPECT_EQ(c.solver.residual_tolerance, solver_defaults.residual_tolerance);
  EXPECT_EQ(c.solver.increment_tolerance, solver_defaults.increment_tolerance);
  EXPECT_EQ(c.solver.linear_solver, "ldlt");
  EXPECT_EQ(c.solver.cg_tolerance, solver_defaults.cg_tolerance);
  EXPECT_EQ(c.solver.cg_max_iterations, solver_defaults.cg_max_iterations);
  EXPECT_EQ(c.solver.flip, 1.0);

  EXPECT_EQ(c.output.folder, "output");
  EXPECT_DOUBLE_EQ(c.output.vtu_interval, 2.5e-4);
  EXPECT_DOUBLE_EQ(c.output.csv_interval, 2.5e-4);
  EXPECT_TRUE(c.output.vtu);
  EXPECT_DOUBLE_EQ(c.output.progress_interval, 2.0);
}

TEST(LoadConfig, DefaultsOfAMinimalInput) {
  const Config c = parse_config(kMinimal, "dir/minimal.toml");
  EXPECT_EQ(c.source_path, "dir/minimal.toml");
  EXPECT_EQ(c.source_text, kMinimal);
  EXPECT_EQ(c.simulation.name, "mpmcd");
  EXPECT_EQ(c.grid.origin, (std::vector<double>{-1.0, 0.0}));  // integers accepted as numbers
  EXPECT_TRUE(c.boundaries.empty());
  EXPECT_EQ(c.loads.gravity, (std::vector<double>{0.0, 0.0}));
  EXPECT_EQ(c.grains[0].min_corner, (std::vector<double>{-0.5, 0.25}));
  EXPECT_EQ(c.grains[0].max_corner, (std::vector<double>{0.5, 1.0}));
  EXPECT_DOUBLE_EQ(c.time.dt_min, 1e-3 / 1024);
  EXPECT_EQ(c.materials[0].line, 7);
  EXPECT_EQ(c.grains[0].line, 14);
}

TEST(LoadConfig, EveryOptionalTable) {
  const std::string text = kMinimal + R"(dt_min = 1e-6
theta = 0.5
cut_factor = 0.25
recover_steps = 3

[[grains]]
shape = "disk"
material = "soft"
center = [0, 0.75]
radius = 0.25
points_per_cell = 3
initial = { angular_velocity = 2.0 }

[[grains]]
shape = "disk"
material = "hard"
center = [0.25, 0.75]
radius = 0.5

[grains.initial]
velocity = [1, -2]
gradient = [0.1, 0.2, 0.3, 0.4]
sine_amplitude = [0.5, 0]
sine_wavevector = [3.14, 0]
sine_phase = 1.5

[[materials]]
name = "hard"
law = "saint_venant_kirchhoff"
density = 2500.5
lambda = 0
mu = 1e9

[[boundary]]
nodes = "box"
box_min = [-1, 0]
box_max = [-0.75, 1.5]
fix = ["y", "x"]
velocity = [0.5, 0]

[[boundary]]
nodes = "all"
fix = ["x"]

[simulation]
name = "run-1.b"
dimension = 2
threads = 4

[loads]
gravity = [0, -9.81]

[solver]
max_iterations = 7
residual_tolerance = 1e-8
increment_tolerance = 1e-6
linear_solver = "cg"
cg_tolerance = 1e-9
cg_max_iterations = 50
flip = 0

[output]
folder = "out/run"
vtu_interval = 0
csv_interval = 0.5
vtu = false
progress_interval = 10
)";
  const Config c = parse_config(text, "case.toml");
  EXPECT_DOUBLE_EQ(c.time.dt_min, 1e-6);
  EXPECT_DOUBLE_EQ(c.time.theta, 0.5);
  EXPECT_DOUBLE_EQ(c.time.cut_factor, 0.25);
  EXPECT_EQ(c.time.recover_steps, 3);
  ASSERT_EQ(c.grains.size(), 3u);
  EXPECT_EQ(c.grains[1].points_per_cell, 3);
  EXPECT_DOUBLE_EQ(c.grains[1].initial.angular_velocity, 2.0);
  EXPECT_EQ(c.grains[1].initial.velocity, (std::vector<double>{0.0, 0.0}));
  EXPECT_EQ(c.grains[2].material, "hard");
  EXPECT_EQ(c.grains[2].initial.velocity, (std::vector<double>{1.0, -2.0}));
  EXPECT_EQ(c.grains[2].initial.gradient, (std::vector<double>{0.1, 0.2, 0.3, 0.4}));
  EXPECT_EQ(c.grains[2].initial.sine_amplitude, (std::vector<double>{0.5, 0.0}));
  EXPECT_EQ(c.grains[2].initial.sine_wavevector, (std::vector<double>{3.14, 0.0}));
  EXPECT_DOUBLE_EQ(c.grains[2].initial.sine_phase, 1.5);
  ASSERT_EQ(c.materials.size(), 2u);
  EXPECT_EQ(c.materials[1].law, "saint_venant_kirchhoff");
  EXPECT_DOUBLE_EQ(c.materials[1].density, 2500.5);
  EXPECT_DOUBLE_EQ(c.materials[1].params.at("lambda"), 0.0);
  ASSERT_EQ(c.boundaries.size(), 2u);
  EXPECT_EQ(c.boundaries[0].box_min, (std::vector<double>{-1.0, 0.0}));
  EXPECT_EQ(c.boundaries[0].box_max, (std::vector<double>{-0.75, 1.5}));
  EXPECT_EQ(c.boundaries[0].fix, (std::vector<std::string>{"y", "x"}));
  EXPECT_EQ(c.boundaries[0].velocity, (std::vector<double>{0.5, 0.0}));
  EXPECT_EQ(c.boundaries[1].nodes, "all");
  EXPECT_EQ(c.simulation.name, "run-1.b");
  EXPECT_EQ(c.simulation.threads, 4);
  EXPECT_EQ(c.loads.gravity, (std::vector<double>{0.0, -9.81}));
  EXPECT_EQ(c.solver.max_iterations, 7);
  EXPECT_DOUBLE_EQ(c.solver.residual_tolerance, 1e-8);
  EXPECT_DOUBLE_EQ(c.solver.increment_tolerance, 1e-6);
  EXPECT_EQ(c.solver.linear_solver, "cg");
  EXPECT_DOUBLE_EQ(c.solver.cg_tolerance, 1e-9);
  EXPECT_EQ(c.solver.cg_max_iterations, 50);
  EXPECT_EQ(c.solver.flip, 0.0);
  EXPECT_EQ(c.output.folder, "out/run");
  EXPECT_EQ(c.output.vtu_interval, 0.0);
  EXPECT_DOUBLE_EQ(c.output.csv_interval, 0.5);
  EXPECT_FALSE(c.output.vtu);
  EXPECT_DOUBLE_EQ(c.output.progress_interval, 10.0);
}

TEST(LoadConfig, PackingFileIsResolvedAgainstTheInputFolder) {
  const std::string text = kMinimal + R"(
[[grains]]
shape = "packing"
material = "soft"
file = "data/packing_placeholder.txt"
)";
  const std::string source = std::string(MPMCD_TEST_DIR) + "/case.toml";
  const Config c = parse_config(text, source);
  ASSERT_EQ(c.grains.size(), 2u);
  EXPECT_EQ(c.grains[1].file, std::string(MPMCD_TEST_DIR) + "/data/packing_placeholder.txt");
  EXPECT_TRUE(std::filesystem::exists(c.grains[1].file));
}

TEST(LoadConfig, MessagesNameFileLineKeyAndExpectation) {
  // The message format of the brief: file:line: key '...': expected ..., got ...
  std::string text = kMinimal;
  text.replace(text.find("cell_size = 0.25"), 16, "cell_size = -1");
  EXPECT_EQ(message_of(text),
            "case.toml:5: key 'grid.cell_size': expected a finite number > 0 [m], got -1");
  // An integer where a number is expected is fine, a float where an integer is expected is not.
  EXPECT_EQ(message_of(kMinimal + "\n[solver]\nmax_iterations = 3.0\n"),
            "case.toml:25: key 'solver.max_iterations': expected an integer >= 1, got the float "
            "3.0");
  // Unknown keys: the nearest known name is suggested.
  EXPECT_EQ(message_of(kMinimal + "\n[output]\nvtu_intervall = 1\n"),
            "case.toml:25: key 'output.vtu_intervall': unknown key, did you mean 'vtu_interval'?");
  EXPECT_EQ(message_of(kMinimal + "\n[[boundaries]]\nnodes = \"all\"\n"),
            "case.toml:24: key 'boundaries': unknown key, did you mean 'boundary'?");
  // Keys of one shape are refused on another.
  EXPECT_EQ(message_of(kMinimal + "radius = 1\n"),
            "case.toml:23: key 'time.radius': unknown key here: 'radius' is a key of [[grains]]");
}

TEST(LoadConfig, GrainsMayTouchTheOneCellMargin) {
  std::string text = kMinimal;
  text.replace(text.find("min_corner = [-0.5, 0.25]"), 25, "min_corner = [-0.75, 0.25]");
  EXPECT_NO_THROW((void)parse_config(text, "case.toml"));
  text.replace(text.find("min_corner = [-0.75, 0.25]"), 26, "min_corner = [-0.76, 0.25]");
  EXPECT_NE(message_of(text).find("case.toml:14: key 'grains[0]': rectangle [-0.76, 0.25] to "
                                  "[0.5, 1] must lie inside the grid with one cell of margin"),
            std::string::npos)
      << message_of(text);
}

// [loading] (docs/loading.md): every key reaches its member; inline and [[...]] tables alike;
// stage names default to "stage <k>"; the walls without a constant velocity get zeros.
TEST(LoadConfig, LoadingStagesFillTheirSections) {
  const std::string walls = R"(
[[walls]]
name = "bottom"
point = [0, 0.1]
normal = [0, 1]
[[walls]]
name = "top"
point = [0, 1.2]
normal = [0, -1]
[[walls]]
name = "left"
point = [-0.75, 0]
normal = [1, 0]
[[walls]]
name = "right"
point = [0.75, 0]
normal = [-1, 0]
[loading]
gain = 2e-6
max_speed = 0.5
[[loading.stages]]
name = "iso"
ramp = 1e-3
until = { time = 2e-3, phi = 0.9 }
walls = [{ name = "left", stress = -1e5 }, { name = "right", stress = -1e5 }]
[[loading.stages]]
[loading.stages.until]
strain = -0.1
stress = -2e5
wall = "top"
[[loading.stages.walls]]
name = "top"
velocity = [0, -0.1]
[[loading.stages.walls]]
name = "left"
stress = -1e5
velocity = [0, 0.2]
)";
  const Config c = parse_config(kMinimal + walls, "case.toml");
  const auto& l = c.loading;
  EXPECT_TRUE(l.present);
  EXPECT_EQ(l.gain, 2e-6);
  EXPECT_EQ(l.gain_fraction, 0.25);
  EXPECT_EQ(l.max_speed, 0.5);
  ASSERT_EQ(l.stages.size(), 2u);
  EXPECT_EQ(l.stages[0].name, "iso");
  EXPECT_EQ(l.stages[0].ramp, 1e-3);
  EXPECT_TRUE(l.stages[0].has_until);
  EXPECT_EQ(l.stages[0].until.time, 2e-3);
  EXPECT_EQ(l.stages[0].until.phi, 0.9);
  EXPECT_FALSE(l.stages[0].until.has_strain);
  ASSERT_EQ(l.stages[0].walls.size(), 2u);
  EXPECT_EQ(l.stages[0].walls[1].name, "right");
  EXPECT_TRUE(l.stages[0].walls[1].has_stress);
  EXPECT_EQ(l.stages[0].walls[1].stress, -1e5);
  EXPECT_TRUE(l.stages[0].walls[1].velocity.empty());
  EXPECT_EQ(l.stages[1].name, "stage 2");
  EXPECT_TRUE(l.stages[1].until.has_strain);
  EXPECT_EQ(l.stages[1].until.strain, -0.1);
  EXPECT_TRUE(l.stages[1].until.has_stress);
  EXPECT_EQ(l.stages[1].until.wall, "top");
  EXPECT_FALSE(l.stages[1].walls[0].has_stress);
  EXPECT_EQ(l.stages[1].walls[0].velocity, (std::vector<double>{0, -0.1}));
  // Stress with a slide along the wall (normal component 0) is accepted.
  EXPECT_TRUE(l.stages[1].walls[1].has_stress);
  EXPECT_EQ(l.stages[1].walls[1].velocity, (std::vector<double>{0, 0.2}));
  EXPECT_EQ(c.walls[1].velocity, (std::vector<double>{0, 0}));
  EXPECT_FALSE(parse_config(kMinimal, "case.toml").loading.present);
}
