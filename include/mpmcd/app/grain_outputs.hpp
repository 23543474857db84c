#pragma once
/// Grain-scale outputs of a run (`[output] grains = true`; docs/observables.md, "Grain-scale
/// outputs"): the per-grain CSV and the contact-force CSV of one snapshot, and the fabric and
/// stress columns of the CSV time series. Wires analysis/grains.hpp to the model and the contact
/// problem, in 2D (plane strain) and 3D (full symmetric tensors xx, yy, zz, xy, xz, yz).
#include <string>
#include <vector>

#include "mpmcd/analysis/grains.hpp"
#include "mpmcd/contact/problem.hpp"
#include "mpmcd/mpm/model.hpp"

namespace mpmcd::app {

/// The grain-scale state of one committed step: grains, contact pairs and the network of Z.
template <int Dim = 2>
struct GrainSnapshot {
  std::vector<analysis::GrainStateOf<Dim>> grains;  ///< per grain: volume, centroid, σ̄_g, shape
  std::vector<analysis::PairForceOf<Dim>> pairs;    ///< per pair of bodies: force, normal, branch
  analysis::Coordination network;                   ///< Z of the same contacts (rattlers marked)
};

/// The grain-scale state of `model` with the solved contacts of `problem` (empty without
/// contact); `hull` false skips the convex hulls (perimeter, circularity; 2D only).
template <int Dim>
GrainSnapshot<Dim> grain_snapshot(const mpm::Model<Dim>& model,
                                  const contact::Problem<Dim>& problem, bool hull = true);

/// Writes `<path>`: one row per grain at time t [s] (columns in docs/observables.md: stress and
/// its invariants [Pa], area [m^2] (3D: volume [m^3]), centroid [m], second moment [m^4] (3D:
/// [m^5]), aspect ratio; in 2D also orientation [deg], hull perimeter [m], circularity; contacts).
template <int Dim>
void write_grains_csv(const mpm::Model<Dim>& model, const GrainSnapshot<Dim>& snap, double t,
                      const std::string& path);

/// Writes `<path>`: one row per pair of bodies in contact at time t [s] (grain ids, walls as
/// -1 - k, nodes, normal and tangential force [N/m] (3D: [N]), force, normal, branch vector [m],
/// point [m]).
template <int Dim>
void write_contact_forces_csv(const GrainSnapshot<Dim>& snap, double t, const std::string& path);

/// The CSV time-series columns of the grain-scale outputs (starting with a comma): the volume V
/// [m^2] (3D: [m^3]), the mean grain stress Σ σ̄_g A_g / V [Pa] and, with contact, the contact
/// stress σ_c [Pa] and the fabric (R, a, in 2D its direction, N_c).
template <int Dim>
std::string grain_csv_header(bool contact);

/// The fields of grain_csv_header for `snap` over the measure `volume` [m^2] (3D: [m^3]; the
/// box's when the walls form a box, else the grains').
template <int Dim>
std::string grain_csv_fields(const GrainSnapshot<Dim>& snap, double volume, bool contact);

/// The components of a symmetric tensor `m` (its upper triangle) as CSV fields ",{:.12e}" each:
/// xx, yy, xy in 2D; xx, yy, zz, xy, xz, yz in 3D [units of m].
template <int Dim>
std::string symmetric_fields(const Mat<Dim>& m);

/// The CSV header names of symmetric_fields with `prefix` (",<prefix>xx,<prefix>yy,...").
template <int Dim>
std::string symmetric_names(const std::string& prefix);

}  // namespace mpmcd::app
