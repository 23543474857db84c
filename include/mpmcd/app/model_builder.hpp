#pragma once
/// The model of a run built from its validated input (docs/input.md): grid and materials, grains
/// (disks, rectangles, packings) with their initial velocities, the [[boundary]] node sets, the
/// solver settings, and the checks an input can pass only once built (grains inside the grid, no
/// overlapping grains, walls enclosing the grains).
#include <cstddef>
#include <vector>

#include "mpmcd/io/config.hpp"
#include "mpmcd/mpm/model.hpp"
#include "mpmcd/mpm/solver.hpp"
#include "mpmcd/walls/wall.hpp"

namespace mpmcd::app {

/// The grid and the materials of the input, no grains yet (a restart adds the checkpoint's);
/// throws InputError for a material the law registry refuses.
template <int Dim>
mpm::Model<Dim> model_frame(const io::Config& config);

extern template mpm::Model<2> model_frame<2>(const io::Config&);

/// Builds the 2D model (grid, materials, seeded grains, initial velocities) from the input;
/// throws InputError for inputs that pass the schema but cannot be built (e.g. a grain too small
/// to hold one material point).
mpm::Model<2> build_model(const io::Config& config);

/// Node sets and prescribed velocities of the [[boundary]] tables at time t [s] (moving boxes are
/// translated by velocity * t).
std::vector<mpm::VelocityBC<2>> build_boundaries(const io::Config& config,
                                                 const grid::Grid<2>& grid, double t);

/// True when contact is solved: asked for ([contact] enabled) and there is something to touch
/// (more than one of the model's `grains`, or a wall).
bool contact_enabled(const io::Config& config, std::size_t grains);

/// The input's [[walls]] as walls at t = 0 (t0 = 0, the input's velocity), in input order: the one
/// place an io::WallSection becomes a walls::Wall (the contact settings, the observables' box).
std::vector<walls::Wall<2>> input_walls(const io::Config& config);

/// Solver settings from the input and its model (the model's grains decide contact_enabled, its
/// materials' wave speeds the Delassus operator).
mpm::Settings<2> build_settings(const io::Config& config, const mpm::Model<2>& model);

/// Throws InputError if a material point starts outside a wall (walls must enclose the grains).
void check_walls_enclose(const io::Config& config, const mpm::Model<2>& model,
                         const mpm::Settings<2>& settings);

}  // namespace mpmcd::app
