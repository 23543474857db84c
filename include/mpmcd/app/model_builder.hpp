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
extern template mpm::Model<3> model_frame<3>(const io::Config&);

/// Builds the model (grid, materials, seeded grains, initial velocities) of a dimension-Dim input
/// (2D: disks, rectangles, packings; 3D: spheres and boxes, lattice-seeded with the exact
/// volume); throws InputError for inputs that pass the schema but cannot be built (e.g. a grain
/// too small to hold one material point, overlapping grains).
template <int Dim = 2>
mpm::Model<Dim> build_model(const io::Config& config);

/// Node sets and prescribed velocities of the [[boundary]] tables at time t [s] (moving boxes are
/// translated by velocity * t).
template <int Dim>
std::vector<mpm::VelocityBC<Dim>> build_boundaries(const io::Config& config,
                                                   const grid::Grid<Dim>& grid, double t);

/// True when contact is solved: asked for ([contact] enabled) and there is something to touch
/// (more than one of the model's `grains`, or a wall).
bool contact_enabled(const io::Config& config, std::size_t grains);

/// The input's [[walls]] as walls at t = 0 (t0 = 0, the input's velocity), in input order: the one
/// place an io::WallSection becomes a walls::Wall (the contact settings, the observables' box).
template <int Dim = 2>
std::vector<walls::Wall<Dim>> input_walls(const io::Config& config);

/// Solver settings from the input and its model (the model's grains decide contact_enabled, its
/// materials' wave speeds the Delassus operator).
template <int Dim>
mpm::Settings<Dim> build_settings(const io::Config& config, const mpm::Model<Dim>& model);

/// Throws InputError if a material point starts outside a wall (walls must enclose the grains).
template <int Dim>
void check_walls_enclose(const io::Config& config, const mpm::Model<Dim>& model,
                         const mpm::Settings<Dim>& settings);

extern template mpm::Model<2> build_model<2>(const io::Config&);
extern template mpm::Model<3> build_model<3>(const io::Config&);
extern template std::vector<mpm::VelocityBC<2>> build_boundaries<2>(const io::Config&,
                                                                    const grid::Grid<2>&, double);
extern template std::vector<mpm::VelocityBC<3>> build_boundaries<3>(const io::Config&,
                                                                    const grid::Grid<3>&, double);
extern template std::vector<walls::Wall<2>> input_walls<2>(const io::Config&);
extern template std::vector<walls::Wall<3>> input_walls<3>(const io::Config&);
extern template mpm::Settings<2> build_settings<2>(const io::Config&, const mpm::Model<2>&);
extern template mpm::Settings<3> build_settings<3>(const io::Config&, const mpm::Model<3>&);
extern template void check_walls_enclose<2>(const io::Config&, const mpm::Model<2>&,
                                            const mpm::Settings<2>&);
extern template void check_walls_enclose<3>(const io::Config&, const mpm::Model<3>&,
                                            const mpm::Settings<3>&);

}  // namespace mpmcd::app
