#include "mpmcd/app/grain_outputs.hpp"

#include <fmt/format.h>

#include <cmath>

#include "mpmcd/io/vtu.hpp"

namespace mpmcd::app {

GrainSnapshot grain_snapshot(const mpm::Model<2>& model, const contact::Problem<2>& problem,
                             bool hull) {
  GrainSnapshot s;
  s.grains = analysis::grain_states(model.points, model.grains, hull);
  const auto contacts = analysis::contact_impulses(problem, [&](std::int64_t node) {
    return model.grid.node_position(model.grid.node_coords(node));
  });
  const auto n = static_cast<std::int64_t>(model.grains.size());
  s.pairs = analysis::pair_forces(contacts, problem.dt, s.grains);
  s.network = analysis::coordination(contacts, n);
  return s;
}

void write_grains_csv(const mpm::Model<2>& model, const GrainSnapshot& snap, double t,
                      const std::string& path) {
  // Contacts per grain by the rule of Z (all pairs in contact, before rattlers are removed).
  std::vector<int> grain_contacts(snap.grains.size(), 0), wall_contacts(snap.grains.size(), 0);
  for (const auto& p : snap.pairs) {
    if (!p.in_contact) continue;
    if (p.a >= 0) {
      ++grain_contacts[static_cast<std::size_t>(p.a)];
      ++grain_contacts[static_cast<std::size_t>(p.b)];
    } else {
      ++wall_contacts[static_cast<std::size_t>(p.b)];
    }
  }
  std::string text =
      "time,grain,material,points,area,x,y,sxx,syy,sxy,szz,mean_stress,pressure,deviator_norm,q,"
      "von_mises,Ixx,Iyy,Ixy,aspect_ratio,orientation,hull_area,perimeter,circularity,solidity,"
      "grain_contacts,wall_contacts,rattler\n";
  for (std::size_t g = 0; g < snap.grains.size(); ++g) {
    const auto& s = snap.grains[g];
    const auto& gr = model.grains[g];
    const double sm = analysis::mean_stress(s.stress), dev = analysis::deviator_norm(s.stress);
    const analysis::Principal axes = analysis::principal(s.moment);
    const bool rattler = !snap.network.kept.empty() && !snap.network.kept[g];
    text += fmt::format(
        "{:.12e},{},{},{},{:.12e},{:.12e},{:.12e},{:.12e},{:.12e},{:.12e},{:.12e},{:.12e},{:.12e},"
        "{:.12e},{:.12e},{:.12e},{:.12e},{:.12e},{:.12e},{:.12e},{:.6f},{:.12e},{:.12e},{:.12e},"
        "{:.12e},{},{},{}\n",
        t, g, gr.material, gr.size(), s.area, s.centroid[0], s.centroid[1], s.stress(0, 0),
        s.stress(1, 1), 0.5 * (s.stress(0, 1) + s.stress(1, 0)), s.stress_zz, sm, -sm, dev,
        dev / std::sqrt(2.0), analysis::von_mises(s.stress, s.stress_zz), s.moment(0, 0),
        s.moment(1, 1), s.moment(0, 1), analysis::aspect_ratio(s.moment), axes.angle, s.hull_area,
        s.hull_perimeter, analysis::circularity(s.hull_area, s.hull_perimeter),
        s.hull_area > 0 ? s.area / s.hull_area : 0.0, grain_contacts[g], wall_contacts[g],
        rattler ? 1 : 0);
  }
  io::write_file_atomic(path, text);
}

void write_contact_forces_csv(const GrainSnapshot& snap, double t, const std::string& path) {
  std::string text = "time,a,b,nodes,fn,ft,fx,fy,nx,ny,lx,ly,px,py\n";
  for (const auto& p : snap.pairs) {
    if (!p.in_contact) continue;
    text += fmt::format(
        "{:.12e},{},{},{},{:.12e},{:.12e},{:.12e},{:.12e},{:.12e},{:.12e},{:.12e},{:.12e},{:.12e},"
        "{:.12e}\n",
        t, p.a, p.b, p.nodes, p.normal_force, p.tangential_force, p.force[0], p.force[1],
        p.normal[0], p.normal[1], p.branch[0], p.branch[1], p.point[0], p.point[1]);
  }
  io::write_file_atomic(path, text);
}

std::string grain_csv_header(bool contact) {
  std::string h = ",stress_volume,grain_sxx,grain_syy,grain_sxy";
  if (contact)
    h += ",contact_sxx,contact_syy,contact_sxy,fabric_rxx,fabric_ryy,fabric_rxy,fabric_a,"
         "fabric_angle,fabric_contacts";
  return h;
}

std::string grain_csv_fields(const GrainSnapshot& snap, double volume, bool contact) {
  const Mat<2> g = analysis::mean_grain_stress(snap.grains, volume);
  std::string out =
      fmt::format(",{:.12e},{:.12e},{:.12e},{:.12e}", volume, g(0, 0), g(1, 1), g(0, 1));
  if (contact) {
    const Mat<2> c = analysis::contact_stress(snap.pairs, volume);
    const analysis::Fabric f = analysis::fabric(snap.pairs, snap.network.kept);
    out += fmt::format(",{:.12e},{:.12e},{:.12e},{:.12e},{:.12e},{:.12e},{:.12e},{:.6f},{}",
                       c(0, 0), c(1, 1), c(0, 1), f.tensor(0, 0), f.tensor(1, 1), f.tensor(0, 1),
                       f.anisotropy, f.angle, f.contacts);
  }
  return out;
}

}  // namespace mpmcd::app
