#pragma once
/// The 300-grain compaction slice shared by bench_contact and bench_parallel (paper setup): DEM
/// packing at phi = 0.78 of 300 disks with diameters uniform in [0.8, 1.2] mm (seed 42), h = d/8,
/// 2x2 points per cell, Neo-Hookean lambda = 3 MPa, mu = 1.5 MPa, 990 kg/m^3, four walls, the top
/// one moving down at 2 m/s.
#include <vector>

#include "mpmcd/materials/law.hpp"
#include "mpmcd/mpm/model.hpp"
#include "mpmcd/mpm/solver.hpp"
#include "mpmcd/packing/packing.hpp"
#include "mpmcd/packing/seeding.hpp"
#include "mpmcd/walls/wall.hpp"

namespace mpmcd::bench {

/// The model and its four walls.
struct Slice {
  mpm::Model<2> model;                ///< grid, material, 300 grains
  std::vector<walls::Wall<2>> walls;  ///< bottom, top (moving down at 2 m/s), left, right
};

/// Builds the slice (about 1 s: the DEM packing and the seeding).
inline Slice make_slice_300() {
  packing::PackingParams pp;
  pp.count = 300;
  pp.diameter_min = 0.8e-3;
  pp.diameter_max = 1.2e-3;
  pp.target_phi = 0.78;
  pp.seed = 42;
  const packing::Packing pk = packing::generate_packing(pp);
  Slice s;
  const double h = packing::mean_diameter(pk) / 8;
  const Vec<2> origin(pk.xmin - 2 * h, pk.ymin - 2 * h);
  const IVec<2> cells(static_cast<std::int64_t>((pk.xmax - pk.xmin) / h) + 5,
                      static_cast<std::int64_t>((pk.ymax - pk.ymin) / h) + 5);
  s.model.grid = grid::Grid<2>(origin, h, cells);
  s.model.add_material(materials::make_law<2>("neo_hookean", {{"lambda", 3e6}, {"mu", 1.5e6}}),
                       990.0);
  const auto seeded = packing::seed_packing(pk, origin, h, 2);
  for (std::size_t k = 0; k < pk.disks.size(); ++k) {
    points::Seeds<2> seeds;
    seeds.x.assign(seeded.x.begin() + seeded.offset[k], seeded.x.begin() + seeded.offset[k + 1]);
    seeds.volume.assign(seeded.volume.begin() + seeded.offset[k],
                        seeded.volume.begin() + seeded.offset[k + 1]);
    s.model.add_grain(seeds, 0, 0.25 * h, {});
  }
  s.walls = {{"bottom", Vec<2>(0, pk.ymin), Vec<2>(0, 1), Vec<2>::Zero(), 0.0},
             {"top", Vec<2>(0, pk.ymax), Vec<2>(0, -1), Vec<2>(0, -2.0), 0.0},
             {"left", Vec<2>(pk.xmin, 0), Vec<2>(1, 0), Vec<2>::Zero(), 0.0},
             {"right", Vec<2>(pk.xmax, 0), Vec<2>(-1, 0), Vec<2>::Zero(), 0.0}};
  return s;
}

}  // namespace mpmcd::bench
