#pragma once
// Private to the mpm module: the per-grain work space of ImplicitSolver (GrainWork: the grain's
// field and what the contact coupling keeps of it) and the helpers shared by its source files
// (docs/architecture.md, "The mpm module's files").
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <utility>
#include <vector>

#include "mpmcd/mpm/grain_field.hpp"
#include "mpmcd/mpm/solver.hpp"

namespace mpmcd::mpm {

/// Per-grain work space: the grain's field (GrainField: transfers, Newton) and the contact
/// coupling's state of it (its compliance group and the response to its slots' impulses).
template <int Dim>
struct ImplicitSolver<Dim>::GrainWork : GrainField<Dim> {
  std::vector<std::int32_t> slots;  // contact slots of this grain (its compliance group)
  bool lumped_group = false;        // its group's response is M^-1 E (no factorisation)
  // A^-1 E B: response of all dofs to unit slot impulses along the slots' basis directions B
  // (slot_basis_, columns slot after slot) [s/kg], column-major in z_store, whose capacity is
  // kept from call to call (the slots, and so Z's columns, change every step: a matrix of a new
  // size would be allocated anew each time)
  std::vector<double> z_store;
  Eigen::Index z_rows = 0, z_cols = 0;  // Z's size
  Eigen::Map<Eigen::MatrixXd> Z() { return {z_store.data(), z_rows, z_cols}; }
  // Makes Z rows x cols, its entries unset (0 with `zero`); z_store grows by a quarter more than
  // it needs when it must grow.
  void resize_z(Eigen::Index rows, Eigen::Index cols, bool zero) {
    const auto n = static_cast<std::size_t>(rows * cols);
    if (n > z_store.capacity()) z_store.reserve(n + n / 4);
    if (zero)
      z_store.assign(n, 0.0);
    else
      z_store.resize(n);
    z_rows = rows;
    z_cols = cols;
  }
  std::vector<Eigen::Index> z_col;  // first column of each slot's directions in Z (size slots + 1)
  bool z_forward = false;           // Z holds Y = L^-1 P E instead (LDL^T: grain_compliance)
  std::int64_t z_factor = -1;       // the factorisation Z and G were computed with (-1: none)
  // The factorisation serves a contact compliance (prepare_factor's `compliance`).
  bool compliance() const { return !slots.empty() && !lumped_group; }
  // The contact impulses changed the velocities by sqrt(dv2) in the mass norm: iterate again.
  void impulses_changed(double dv2) {
    this->converged = false;
    this->solved_once = true;
    this->dv_norm = std::sqrt(dv2);
    this->dv_from_contact = true;
  }
};

namespace detail {
/// Records a Gauss-Seidel outcome in `stats` and returns the sums of the relative impulse change
/// since `old` (the impulses before it), num = sum |P - P_old|^2, den = sum |P|^2 [(N s)^2].
template <int Dim>
std::pair<double, double> impulse_change(const contact::Problem<Dim>& problem,
                                         const std::vector<Vec<Dim>>& old,
                                         const contact::GsResult& r, StepStats& stats) {
  stats.gs_sweeps += r.sweeps;
  stats.gs_error = r.error;
  double num = 0, den = 0;
  for (std::size_t c = 0; c < old.size(); ++c) {
    const auto& ct = problem.contacts[c];
    num += (ct.impulse - old[c]).squaredNorm();
    den += ct.impulse.squaredNorm();
  }
  return {num, den};
}

/// The staggering's relative impulse change sqrt(num / den) from impulse_change's sums, at least 1
/// when Gauss-Seidel did not converge (0 without any change once converged) [-].
inline double relative_change(double num, double den, bool gs_converged) {
  if (num == 0.0) return gs_converged ? 0.0 : 1.0;
  const double change = std::sqrt(num) / std::sqrt(std::max(den, 1e-300));
  return gs_converged ? change : std::max(change, 1.0);
}
}  // namespace detail

}  // namespace mpmcd::mpm
