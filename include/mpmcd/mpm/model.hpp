#pragma once
/// A model: grid, materials, grains made of material points. Built from the input or by hand
/// (tests).
#include <functional>
#include <memory>
#include <vector>

#include "mpmcd/core/types.hpp"
#include "mpmcd/grid/grid.hpp"
#include "mpmcd/materials/law.hpp"
#include "mpmcd/points/point_set.hpp"
#include "mpmcd/points/seeding.hpp"

namespace mpmcd::mpm {

/// Everything that defines the simulated system (not the numerics).
template <int Dim>
struct Model {
  grid::Grid<Dim> grid;                                    ///< background grid
  std::vector<std::unique_ptr<materials::Law<Dim>>> laws;  ///< law of each material
  std::vector<double> densities;                           ///< rho0 of each material [kg/m^3]
  points::PointSet<Dim> points;                            ///< all material points
  std::vector<points::Grain> grains;                       ///< grains (contiguous point ranges)

  /// Adds a material; returns its index.
  int add_material(std::unique_ptr<materials::Law<Dim>> law, double density) {
    laws.push_back(std::move(law));
    densities.push_back(density);
    return static_cast<int>(laws.size()) - 1;
  }
  /// Adds a grain from seeded points; `half_width` [m] = half the seeding spacing (uGIMP lp, and
  /// the points' square domain when the seeds carry none); `velocity(x)` gives the initial
  /// velocity [m/s]. Returns the grain index.
  int add_grain(const points::Seeds<Dim>& seeds, int material, double half_width,
                const std::function<Vec<Dim>(const Vec<Dim>&)>& velocity) {
    points::Grain g;
    g.begin = static_cast<std::int64_t>(points.size());
    g.material = material;
    g.half_width = half_width;
    g.history_offset = static_cast<std::int64_t>(points.history.size());
    const auto gi = static_cast<std::int32_t>(grains.size());
    for (std::size_t i = 0; i < seeds.x.size(); ++i)
      points.add(
          seeds.x[i], velocity ? velocity(seeds.x[i]) : Vec<Dim>::Zero(),
          densities[material] * seeds.volume[i], seeds.volume[i],
          seeds.domain.empty() ? Mat<Dim>(half_width * Mat<Dim>::Identity()) : seeds.domain[i], gi);
    g.end = static_cast<std::int64_t>(points.size());
    // Velocity gradient of the initial field by central differences over 1e-3 of the point's
    // half-width (exact to round-off for the affine parts), for the affine P2G.
    if (velocity)
      for (std::int64_t p = g.begin; p < g.end; ++p) {
        const double e = 1e-3 * half_width;
        for (int d = 0; d < Dim; ++d) {
          Vec<Dim> xp = points.x[p], xm = points.x[p];
          xp[d] += e;
          xm[d] -= e;
          points.L[p].col(d) = (velocity(xp) - velocity(xm)) / (2 * e);
        }
      }
    const std::size_t hs = static_cast<std::size_t>(laws[material]->history_size());
    const std::size_t h0 = points.history.size();
    points.history.resize(h0 + hs * seeds.x.size());
    laws[material]->init_history(
        std::span<double>(points.history.data() + h0, hs * seeds.x.size()));
    grains.push_back(g);
    return gi;
  }
  /// Non-owning law pointers in material order (for the solver).
  std::vector<const materials::Law<Dim>*> law_ptrs() const {
    std::vector<const materials::Law<Dim>*> out;
    for (const auto& l : laws) out.push_back(l.get());
    return out;
  }
};

/// Global diagnostics of the committed point state.
template <int Dim>
struct Diagnostics {
  double mass = 0;                       ///< total mass [kg] (2D: per unit thickness)
  Vec<Dim> momentum = Vec<Dim>::Zero();  ///< total momentum [kg m/s]
  double kinetic = 0;                    ///< kinetic energy 1/2 sum m v^2 [J]
  double elastic = 0;                    ///< stored energy sum V0 W(F) [J]
  double volume = 0;                     ///< total current volume sum J V0 [m^Dim]
};

/// Computes the diagnostics (one law evaluation per grain for the stored energy).
template <int Dim>
Diagnostics<Dim> diagnostics(const Model<Dim>& model);

extern template Diagnostics<2> diagnostics<2>(const Model<2>&);
extern template Diagnostics<3> diagnostics<3>(const Model<3>&);

}  // namespace mpmcd::mpm
