#pragma once
/// The energy ledger of a run (docs/accuracy.md): the work done by each wall on the grains,
/// W_k += -F_k . v_k dt with F_k the grains' force on wall k over the step, and by the body
/// forces, against the change of elastic plus kinetic energy since t = 0. What is lost on the way:
/// contact dissipates D_c += sum_k W_k(step) - W_c(step), W_c the work of all contact impulses on
/// the grains (StepStats::contact_work); the transfers D_t (StepStats::transfer_loss); the stress
/// work on the grid not stored as elastic energy, D_i = -sum W_int - (Psi - Psi_0) (plastic
/// dissipation; for elastic laws, time integration and quadrature). The remainder is the Newton
/// tolerance's (and prescribed grid velocities' work). Written by runs with walls.
#include <string>
#include <vector>

#include "mpmcd/io/config.hpp"
#include "mpmcd/mpm/model.hpp"
#include "mpmcd/mpm/solver.hpp"
#include "mpmcd/walls/wall.hpp"

namespace mpmcd::app {

/// The ledger's running sums since t = 0, what a checkpoint keeps [J] (2D: J/m).
struct EnergySums {
  std::vector<double> wall_work;    ///< work done by each wall on the grains [J]
  double energy0 = 0;               ///< elastic + kinetic energy at t = 0 [J]
  double kinetic0 = 0;              ///< kinetic energy at t = 0 [J]
  double contact_dissipation = 0;   ///< energy dissipated by contact [J]
  double transfer_dissipation = 0;  ///< kinetic energy lost by P2G and G2P [J]
  double stress_work = 0;           ///< work of the internal forces on the grid [J]
  double body_work = 0;             ///< work of the body forces on the grid [J]
};

/// The ledger's terms at the current state [J] (2D: J/m).
struct EnergyTerms {
  double walls = 0;     ///< work of all walls on the grains, sum_k W_k [J]
  double change = 0;    ///< elastic + kinetic energy change since t = 0, E - E0 [J]
  double internal = 0;  ///< internal dissipation D_i [J]
  double rest = 0;      ///< the remainder W + W_body - D_c - D_t - D_i - (E - E0) [J]
};

/// The ledger of one run.
template <int Dim>
class EnergyLedger {
 public:
  /// The sums of a run with `walls` walls starting at t = 0 with the diagnostics `d0`.
  static EnergySums start(std::size_t walls, const mpm::Diagnostics<Dim>& d0);

  /// A ledger going on from `sums` (start, or a checkpoint's).
  explicit EnergyLedger(EnergySums sums) : sums_(std::move(sums)) {}

  /// Adds the committed step of length dt [s] with statistics `step` against `walls`.
  void add_step(const mpm::StepStats& step, const std::vector<walls::Wall<Dim>>& walls, double dt);

  /// The terms at the committed state of diagnostics `d`.
  EnergyTerms terms(const mpm::Diagnostics<Dim>& d) const;

  /// The ledger's CSV columns, starting with a comma, for the walls of `config` ("" without
  /// walls): wall_<name>_work, body_work, energy_change, contact_dissipation,
  /// transfer_dissipation, internal_dissipation, energy_unaccounted.
  static std::string csv_header(const io::Config& config);
  /// The CSV fields of the committed state of diagnostics `d` ("" without walls).
  std::string csv_fields(const mpm::Diagnostics<Dim>& d) const;

  /// Logs the run's balance at diagnostics `d`, and a warning when the remainder exceeds
  /// kLedgerTolerance of the energy scale.
  void report(const mpm::Diagnostics<Dim>& d) const;

  /// True when the run has walls (the ledger is written) [-].
  bool active() const { return !sums_.wall_work.empty(); }
  /// The running sums.
  const EnergySums& sums() const { return sums_; }

 private:
  EnergySums sums_;
};

/// The remainder above which the ledger is said not to close, as a fraction of the energy scale
/// (the work in, or the energy change) [-]: it closes to the solver tolerances, about 1e-8 of
/// the work; more is work from outside it (docs/accuracy.md).
inline constexpr double kLedgerTolerance = 1e-3;

extern template class EnergyLedger<2>;
extern template class EnergyLedger<3>;

}  // namespace mpmcd::app
