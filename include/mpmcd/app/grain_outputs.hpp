#pragma once
/// Grain-scale outputs of a run (`[output] grains = true`; docs/observables.md, "Grain-scale
/// outputs"): the per-grain CSV and the contact-force CSV of one snapshot, and the fabric and
/// stress columns of the CSV time series. Wires analysis/grains.hpp to the model and the contact
/// problem.
#include <string>
#include <vector>

#include "mpmcd/analysis/grains.hpp"
#include "mpmcd/contact/problem.hpp"
#include "mpmcd/mpm/model.hpp"

namespace mpmcd::app {

/// The grain-scale state of one committed step: grains, contact pairs and the network of Z.
struct GrainSnapshot {
  std::vector<analysis::GrainState> grains;  ///< per grain: area, centroid, σ̄_g, shape
  std::vector<analysis::PairForce> pairs;    ///< per pair of bodies: force, normal, branch
  analysis::Coordination network;            ///< Z of the same contacts (rattlers marked)
};

/// The grain-scale state of `model` with the solved contacts of `problem` (empty without
/// contact); `hull` false skips the convex hulls (perimeter, circularity).
GrainSnapshot grain_snapshot(const mpm::Model<2>& model, const contact::Problem<2>& problem,
                             bool hull = true);

/// Writes `<path>`: one row per grain at time t [s] (columns in docs/observables.md: stress and
/// its invariants [Pa], area [m^2], centroid [m], second moment [m^4], aspect ratio, orientation
/// [deg], hull perimeter [m], circularity, contacts).
void write_grains_csv(const mpm::Model<2>& model, const GrainSnapshot& snap, double t,
                      const std::string& path);

/// Writes `<path>`: one row per pair of bodies in contact at time t [s] (grain ids, walls as
/// -1 - k, nodes, normal and tangential force [N/m], force, normal, branch vector [m], point [m]).
void write_contact_forces_csv(const GrainSnapshot& snap, double t, const std::string& path);

/// The CSV time-series columns of the grain-scale outputs (starting with a comma): the volume V
/// [m^2], the mean grain stress Σ σ̄_g A_g / V [Pa] and, with contact, the contact stress
/// σ_c [Pa] and the fabric (R, a, direction, N_c).
std::string grain_csv_header(bool contact);

/// The fields of grain_csv_header for `snap` over the area `volume` [m^2] (the box area when the
/// walls form a box, else the grains' area).
std::string grain_csv_fields(const GrainSnapshot& snap, double volume, bool contact);

}  // namespace mpmcd::app
