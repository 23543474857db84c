#include "mpmcd/app/grain_outputs.hpp"

#include <fmt/format.h>

#include <cmath>

#include "mpmcd/io/vtu.hpp"

namespace mpmcd::app {

template <int Dim>
std::string symmetric_fields(const Mat<Dim>& m) {
  if constexpr (Dim == 3)
    return fmt::format(",{:.12e},{:.12e},{:.12e},{:.12e},{:.12e},{:.12e}", m(0, 0), m(1, 1),
                       m(2, 2), m(0, 1), m(0, 2), m(1, 2));
  else
    return fmt::format(",{:.12e},{:.12e},{:.12e}", m(0, 0), m(1, 1), m(0, 1));
}

template <int Dim>
std::string symmetric_names(const std::string& prefix) {
  std::string h;
  for (const char* c : Dim == 3 ? std::vector<const char*>{"xx", "yy", "zz", "xy", "xz", "yz"}
                                : std::vector<const char*>{"xx", "yy", "xy"})
    h += "," + prefix + c;
  return h;
}

template <int Dim>
GrainSnapshot<Dim> grain_snapshot(const mpm::Model<Dim>& model,
                                  const contact::Problem<Dim>& problem, bool hull) {
  GrainSnapshot<Dim> s;
  if constexpr (Dim == 2)
    s.grains = analysis::grain_states(model.points, model.grains, hull);
  else
    s.grains = analysis::grain_states(model.points, model.grains);
  const auto contacts = analysis::contact_impulses(problem, [&](std::int64_t node) {
    return model.grid.node_position(model.grid.node_coords(node));
  });
  const auto n = static_cast<std::int64_t>(model.grains.size());
  s.pairs = analysis::pair_forces(contacts, problem.dt, s.grains);
  s.network = analysis::coordination_of_pairs(analysis::pair_impulses(contacts, n), n);
  return s;
}

template <int Dim>
void write_grains_csv(const mpm::Model<Dim>& model, const GrainSnapshot<Dim>& snap, double t,
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
      Dim == 3 ? "time,grain,material,points,volume,x,y,z,sxx,syy,szz,sxy,sxz,syz,mean_stress,"
                 "pressure,deviator_norm,von_mises,Ixx,Iyy,Izz,Ixy,Ixz,Iyz,aspect_ratio,"
                 "grain_contacts,wall_contacts,rattler\n"
               : "time,grain,material,points,area,x,y,sxx,syy,sxy,szz,mean_stress,pressure,"
                 "deviator_norm,q,von_mises,Ixx,Iyy,Ixy,aspect_ratio,orientation,hull_area,"
                 "perimeter,circularity,solidity,grain_contacts,wall_contacts,rattler\n";
  for (std::size_t g = 0; g < snap.grains.size(); ++g) {
    const auto& s = snap.grains[g];
    const auto& gr = model.grains[g];
    const double sm = analysis::mean_stress(s.stress), dev = analysis::deviator_norm(s.stress);
    const bool rattler = !snap.network.kept.empty() && !snap.network.kept[g];
    if constexpr (Dim == 3) {
      const Mat<3> sigma = 0.5 * (s.stress + s.stress.transpose());
      text += fmt::format("{:.12e},{},{},{},{:.12e},{:.12e},{:.12e},{:.12e}", t, g, gr.material,
                          gr.size(), s.area, s.centroid[0], s.centroid[1], s.centroid[2]);
      text += symmetric_fields<3>(sigma);
      // von Mises σ_vM = sqrt(3/2 s:s) = sqrt(3/2) |s|
      text += fmt::format(",{:.12e},{:.12e},{:.12e},{:.12e}", sm, -sm, dev, std::sqrt(1.5) * dev);
      text += symmetric_fields<3>(s.moment);
      text += fmt::format(",{:.12e},{},{},{}\n", analysis::aspect_ratio(s.moment),
                          grain_contacts[g], wall_contacts[g], rattler ? 1 : 0);
    } else {
      const analysis::Principal axes = analysis::principal(s.moment);
      text += fmt::format(
          "{:.12e},{},{},{},{:.12e},{:.12e},{:.12e},{:.12e},{:.12e},{:.12e},{:.12e},{:.12e},"
          "{:.12e},{:.12e},{:.12e},{:.12e},{:.12e},{:.12e},{:.12e},{:.12e},{:.6f},{:.12e},"
          "{:.12e},{:.12e},{:.12e},{},{},{}\n",
          t, g, gr.material, gr.size(), s.area, s.centroid[0], s.centroid[1], s.stress(0, 0),
          s.stress(1, 1), 0.5 * (s.stress(0, 1) + s.stress(1, 0)), s.stress_zz, sm, -sm, dev,
          dev / std::sqrt(2.0), analysis::von_mises(s.stress, s.stress_zz), s.moment(0, 0),
          s.moment(1, 1), s.moment(0, 1), analysis::aspect_ratio(s.moment), axes.angle, s.hull_area,
          s.hull_perimeter, analysis::circularity(s.hull_area, s.hull_perimeter),
          s.hull_area > 0 ? s.area / s.hull_area : 0.0, grain_contacts[g], wall_contacts[g],
          rattler ? 1 : 0);
    }
  }
  io::write_file_atomic(path, text);
}

template <int Dim>
void write_contact_forces_csv(const GrainSnapshot<Dim>& snap, double t, const std::string& path) {
  std::string text = Dim == 3 ? "time,a,b,nodes,fn,ft,fx,fy,fz,nx,ny,nz,lx,ly,lz,px,py,pz\n"
                              : "time,a,b,nodes,fn,ft,fx,fy,nx,ny,lx,ly,px,py\n";
  for (const auto& p : snap.pairs) {
    if (!p.in_contact) continue;
    text += fmt::format("{:.12e},{},{},{},{:.12e},{:.12e}", t, p.a, p.b, p.nodes, p.normal_force,
                        p.tangential_force);
    for (const Vec<Dim>* v : {&p.force, &p.normal, &p.branch, &p.point})
      for (int a = 0; a < Dim; ++a) text += fmt::format(",{:.12e}", (*v)[a]);
    text += "\n";
  }
  io::write_file_atomic(path, text);
}

template <int Dim>
std::string grain_csv_header(bool contact) {
  std::string h = ",stress_volume" + symmetric_names<Dim>("grain_s");
  if (contact) {
    h += symmetric_names<Dim>("contact_s") + symmetric_names<Dim>("fabric_r") + ",fabric_a";
    if constexpr (Dim == 2) h += ",fabric_angle";
    h += ",fabric_contacts";
  }
  return h;
}

template <int Dim>
std::string grain_csv_fields(const GrainSnapshot<Dim>& snap, double volume, bool contact) {
  const Mat<Dim> g = analysis::mean_grain_stress(snap.grains, volume);
  std::string out = fmt::format(",{:.12e}", volume) + symmetric_fields<Dim>(g);
  if (contact) {
    const Mat<Dim> c = analysis::contact_stress(snap.pairs, volume);
    const auto f = analysis::fabric(snap.pairs, snap.network.kept);
    out += symmetric_fields<Dim>(c) + symmetric_fields<Dim>(f.tensor) +
           fmt::format(",{:.12e}", f.anisotropy);
    if constexpr (Dim == 2) out += fmt::format(",{:.6f}", f.angle);
    out += fmt::format(",{}", f.contacts);
  }
  return out;
}

template std::string symmetric_fields<2>(const Mat<2>&);
template std::string symmetric_fields<3>(const Mat<3>&);
template std::string symmetric_names<2>(const std::string&);
template std::string symmetric_names<3>(const std::string&);
template GrainSnapshot<2> grain_snapshot<2>(const mpm::Model<2>&, const contact::Problem<2>&, bool);
template GrainSnapshot<3> grain_snapshot<3>(const mpm::Model<3>&, const contact::Problem<3>&, bool);
template void write_grains_csv<2>(const mpm::Model<2>&, const GrainSnapshot<2>&, double,
                                  const std::string&);
template void write_grains_csv<3>(const mpm::Model<3>&, const GrainSnapshot<3>&, double,
                                  const std::string&);
template void write_contact_forces_csv<2>(const GrainSnapshot<2>&, double, const std::string&);
template void write_contact_forces_csv<3>(const GrainSnapshot<3>&, double, const std::string&);
template std::string grain_csv_header<2>(bool);
template std::string grain_csv_header<3>(bool);
template std::string grain_csv_fields<2>(const GrainSnapshot<2>&, double, bool);
template std::string grain_csv_fields<3>(const GrainSnapshot<3>&, double, bool);

}  // namespace mpmcd::app
