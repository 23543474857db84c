#include "mpmcd/app/energy_ledger.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "mpmcd/core/log.hpp"

namespace mpmcd::app {

template <int Dim>
EnergySums EnergyLedger<Dim>::start(std::size_t walls, const mpm::Diagnostics<Dim>& d0) {
  EnergySums s;
  s.wall_work.assign(walls, 0.0);
  s.energy0 = d0.elastic + d0.kinetic;
  s.kinetic0 = d0.kinetic;
  return s;
}

template <int Dim>
void EnergyLedger<Dim>::add_step(const mpm::StepStats& step,
                                 const std::vector<walls::Wall<Dim>>& walls, double dt) {
  auto& s = sums_;
  double step_work = 0;
  for (std::size_t k = 0; k < s.wall_work.size() && k < step.wall_force.size(); ++k) {
    double power = step.wall_force[k][0] * walls[k].velocity[0];  // F_k . v_k
    for (int d = 1; d < Dim; ++d) power += step.wall_force[k][d] * walls[k].velocity[d];
    const double wk = -power * dt;
    s.wall_work[k] += wk;
    step_work += wk;
  }
  s.contact_dissipation += step_work - step.contact_work;
  s.transfer_dissipation += step.transfer_loss;
  s.stress_work += step.stress_work;
  s.body_work += step.body_work;
}

template <int Dim>
EnergyTerms EnergyLedger<Dim>::terms(const mpm::Diagnostics<Dim>& d) const {
  const auto& s = sums_;
  EnergyTerms l{0, d.elastic + d.kinetic - s.energy0, 0, 0};
  for (const double w : s.wall_work) l.walls += w;
  l.internal = -s.stress_work - (d.elastic - (s.energy0 - s.kinetic0));
  l.rest = l.walls + s.body_work - s.contact_dissipation - s.transfer_dissipation - l.internal -
           l.change;
  return l;
}

template <int Dim>
std::string EnergyLedger<Dim>::csv_header(const io::Config& cfg) {
  std::string h;
  for (const auto& w : cfg.walls) h += ",wall_" + w.name + "_work";
  if (!cfg.walls.empty())
    h += ",body_work,energy_change,contact_dissipation,transfer_dissipation,internal_dissipation,"
         "energy_unaccounted";
  return h;
}

template <int Dim>
std::string EnergyLedger<Dim>::csv_fields(const mpm::Diagnostics<Dim>& d) const {
  std::string f;
  if (!active()) return f;
  for (const double w : sums_.wall_work) f += fmt::format(",{:.12e}", w);
  const EnergyTerms l = terms(d);
  return f + fmt::format(",{:.12e},{:.12e},{:.12e},{:.12e},{:.12e},{:.12e}", sums_.body_work,
                         l.change, sums_.contact_dissipation, sums_.transfer_dissipation,
                         l.internal, l.rest);
}

template <int Dim>
void EnergyLedger<Dim>::report(const mpm::Diagnostics<Dim>& d) const {
  const EnergyTerms l = terms(d);
  constexpr const char* kUnit = Dim == 3 ? "J" : "J/m";  // 2D: per unit thickness
  const double in = l.walls + sums_.body_work;
  const auto pct = [&](double x) { return in != 0 ? 100 * x / std::abs(in) : 0.0; };
  log().info(
      "energy: walls and body forces did {:.6g} {} of work, elastic + kinetic changed by "
      "{:.6g} {}; dissipated by contact {:.3g} %, by the transfers {:.3g} %, in the bulk "
      "(stress work not stored) {:.3g} %; unaccounted {:.3g} % of the work",
      in, kUnit, l.change, kUnit, pct(sums_.contact_dissipation), pct(sums_.transfer_dissipation),
      pct(l.internal), pct(l.rest));
  const double scale = std::max({std::abs(in), std::abs(l.change), 1e-300});
  if (std::abs(l.rest) > kLedgerTolerance * scale)
    log().warn(
        "the energy ledger does not close: {:.6g} {} ({:.3g} % of the work) is unaccounted; "
        "prescribed grid velocities ([[boundary]]) do work the ledger does not count, and loose "
        "Newton or Gauss-Seidel tolerances leave a remainder (docs/accuracy.md)",
        l.rest, kUnit, 100 * std::abs(l.rest) / scale);
}

template class EnergyLedger<2>;
template class EnergyLedger<3>;

}  // namespace mpmcd::app
