#pragma once
// Small builders shared by the verification tests: a model with one material and grains.
#include <cmath>
#include <functional>
#include <string>
#include <type_traits>

#include "mpmcd/materials/law.hpp"
#include "mpmcd/mpm/model.hpp"
#include "mpmcd/mpm/solver.hpp"
#include "mpmcd/points/seeding.hpp"

namespace mpmcd::test_support {

// The paper's gel (method.md §3, lambda = 3 MPa): Lame coefficients [Pa], density [kg/m^3] and
// P-wave speed c_p = sqrt((lambda + 2 mu) / rho) [m/s], shared by the verification tests.
inline constexpr double kLambda = 3e6, kMu = 1.5e6, kRho = 990.0;
inline const double kCp = std::sqrt((kLambda + 2 * kMu) / kRho);

// A model on a grid [0, cells h] with one material of the given law.
template <int Dim>
mpm::Model<Dim> make_model(double h, const IVec<Dim>& cells, const std::string& law, double lambda,
                           double mu, double rho) {
  mpm::Model<Dim> m;
  m.grid = grid::Grid<Dim>(Vec<Dim>::Zero(), h, cells);
  m.add_material(materials::make_law<Dim>(law, {{"lambda", lambda}, {"mu", mu}}), rho);
  return m;
}

// A 2D model on a grid [0, cells*h]^2 with one material of the given law.
inline mpm::Model<2> make_model(double h, int cells_x, int cells_y, const std::string& law,
                                double lambda, double mu, double rho) {
  return make_model<2>(h, IVec<2>(cells_x, cells_y), law, lambda, mu, rho);
}

// Adds a box grain [lo, hi] seeded with ppc^Dim points per cell (Dim from the model).
template <int Dim>
int add_box(mpm::Model<Dim>& m, const std::type_identity_t<Vec<Dim>>& lo,
            const std::type_identity_t<Vec<Dim>>& hi, int ppc,
            const std::type_identity_t<std::function<Vec<Dim>(const Vec<Dim>&)>>& v = {}) {
  const double h = m.grid.cell_size();
  auto seeds = points::seed_box<Dim>(m.grid.origin(), h, ppc, lo, hi);
  return m.add_grain(seeds, 0, 0.5 * h / ppc, v);
}

// Adds a disk (2D) or ball (3D) grain seeded on the lattice with ppc^Dim points per cell and
// initial velocity v(x) [m/s].
template <int Dim>
int add_ball(mpm::Model<Dim>& m, const std::type_identity_t<Vec<Dim>>& c, double r, int ppc,
             const std::type_identity_t<std::function<Vec<Dim>(const Vec<Dim>&)>>& v = {}) {
  const double h = m.grid.cell_size();
  auto seeds = points::seed_ball<Dim>(m.grid.origin(), h, ppc, c, r);
  return m.add_grain(seeds, 0, 0.5 * h / ppc, v);
}

// Adds a disk grain seeded with ppc x ppc points per cell.
inline int add_disk(mpm::Model<2>& m, const Vec<2>& c, double r, int ppc,
                    const std::function<Vec<2>(const Vec<2>&)>& v = {}) {
  return add_ball<2>(m, c, r, ppc, v);
}

// All grid nodes (for kinematic drivers).
inline std::vector<std::int64_t> all_nodes(const grid::Grid<2>& g) {
  std::vector<std::int64_t> n(static_cast<std::size_t>(g.node_count()));
  for (std::size_t i = 0; i < n.size(); ++i) n[i] = static_cast<std::int64_t>(i);
  return n;
}

// Nodes with coordinate along `axis` equal to grid index `index`.
inline std::vector<std::int64_t> plane_nodes(const grid::Grid<2>& g, int axis, std::int64_t index) {
  std::vector<std::int64_t> out;
  for (std::int64_t i = 0; i < g.node_count(); ++i)
    if (g.node_coords(i)[axis] == index) out.push_back(i);
  return out;
}

}  // namespace mpmcd::test_support
