#include "mpmcd/app/outputs.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <map>
#include <stdexcept>

#include "mpmcd/app/grain_outputs.hpp"
#include "mpmcd/core/log.hpp"
#include "mpmcd/io/output_folder.hpp"
#include "mpmcd/version.hpp"

namespace mpmcd::app {

namespace fs = std::filesystem;

template <int Dim>
void write_points_vtu(const mpm::Model<Dim>& model, const std::string& path) {
  const auto& p = model.points;
  io::VtuPointCloud vtu(p.size());
  auto& vel = vtu.add_array("velocity", 3);
  auto& sig = vtu.add_array("stress", 9);
  auto& pres = vtu.add_array("pressure", 1);
  auto& jac = vtu.add_array("J", 1);
  auto& mass = vtu.add_array("mass", 1);
  auto& vol = vtu.add_array("volume", 1);
  auto& grain = vtu.add_int_array("grain");
  // The point's current domain x + e1 s1 + e2 s2 (+ e3 s3 in 3D), s in [-1, 1]^Dim: e1, e2, e3
  // the columns of F D (the CPDI domain, also for linear shapes; the one
  // analysis::domain_coverage rasterises in 2D).
  std::vector<std::vector<double>*> edges;
  for (int k = 0; k < Dim; ++k)
    edges.push_back(&vtu.add_array(fmt::format("domain_e{}", k + 1), 3));
  for (std::size_t i = 0; i < p.size(); ++i) {
    const Mat<Dim>& s = p.sigma[i];
    if constexpr (Dim == 2) {
      vtu.set_position(i, p.x[i][0], p.x[i][1]);
      const double s3[9] = {s(0, 0), s(0, 1), 0, s(1, 0), s(1, 1), 0, 0, 0, p.sigma_zz[i]};
      for (int k = 0; k < 9; ++k) sig[9 * i + k] = s3[k];
      pres[i] = -(s(0, 0) + s(1, 1) + p.sigma_zz[i]) / 3.0;  // p = -tr(sigma)/3 (plane strain)
    } else {
      vtu.set_position(i, p.x[i][0], p.x[i][1], p.x[i][2]);
      for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) sig[9 * i + 3 * a + b] = s(a, b);
      pres[i] = -s.trace() / 3.0;  // p = -tr(sigma)/3
    }
    for (int a = 0; a < Dim; ++a) vel[3 * i + a] = p.v[i][a];
    jac[i] = p.F[i].determinant();
    mass[i] = p.mass[i];
    vol[i] = p.volume[i];
    grain[i] = p.grain[i];
    const Mat<Dim> e = p.F[i] * p.domain[i];
    for (int c = 0; c < Dim; ++c)
      for (int k = 0; k < Dim; ++k) (*edges[c])[3 * i + k] = e(k, c);
  }
  vtu.write(path);
}

std::int64_t trim_csv(const std::string& path, std::int64_t rows) {
  std::ifstream in(path, std::ios::binary);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::size_t end = 0;
  std::int64_t kept = -1;  // the header is line 0
  while (kept < rows) {
    const std::size_t nl = text.find('\n', end);
    if (nl == std::string::npos) break;
    end = nl + 1;
    ++kept;
  }
  io::write_file_atomic(path, text.substr(0, end));
  return std::max<std::int64_t>(kept, 0);
}

template <int Dim>
void write_contacts(const mpm::Model<Dim>& model, const contact::Problem<Dim>& pb,
                    const std::string& vtu_path, const std::string& csv_path) {
  io::VtuPointCloud vtu(pb.contacts.size());
  auto& normal = vtu.add_array("normal", 3);
  auto& pn = vtu.add_array("normal_impulse", 1);
  auto& pt = vtu.add_array("tangential_impulse", 1);
  auto& force = vtu.add_array("force", 3);
  auto& gap = vtu.add_array("gap", 1);
  auto& body_a = vtu.add_int_array("body_a");
  auto& body_b = vtu.add_int_array("body_b");
  std::map<std::pair<int, int>, Vec<Dim>> pairs;
  const double inv_dt = pb.dt > 0 ? 1.0 / pb.dt : 0.0;
  for (std::size_t i = 0; i < pb.contacts.size(); ++i) {
    const auto& c = pb.contacts[i];
    const auto& sb = pb.slots[c.b];
    const Vec<Dim> x = model.grid.node_position(model.grid.node_coords(sb.node));
    vtu.set_position(i, x[0], x[1], Dim == 3 ? x[Dim - 1] : 0.0);
    for (int a = 0; a < Dim; ++a) normal[3 * i + a] = c.normal[a];
    pn[i] = c.impulse.dot(c.normal);
    if constexpr (Dim == 2)
      pt[i] = c.impulse[1] * c.normal[0] - c.impulse[0] * c.normal[1];  // along t = e_z x n
    else
      pt[i] = (c.impulse - pn[i] * c.normal).norm();  // 3D: the tangential part's magnitude
    // The contact's force on body b [N/m], P/dt as contact::impulse_force but multiplied by 1/dt:
    // its quotient differs in the last bit, and these files stay as they were written before.
    const Vec<Dim> f = c.impulse * inv_dt;
    for (int a = 0; a < Dim; ++a) force[3 * i + a] = f[a];
    gap[i] = c.gap;
    body_a[i] = c.a >= 0 ? pb.slots[c.a].grain : -1 - c.wall;
    body_b[i] = sb.grain;
    // try_emplace with an explicit zero: Eigen vectors are not zero-initialised.
    pairs.try_emplace({body_a[i], body_b[i]}, Vec<Dim>::Zero()).first->second += f;
  }
  vtu.write(vtu_path);
  std::string text =
      Dim == 3 ? "body_a,body_b,force_x,force_y,force_z\n" : "body_a,body_b,force_x,force_y\n";
  for (const auto& [key, f] : pairs) {
    text += fmt::format("{},{},{:.12e},{:.12e}", key.first, key.second, f[0], f[1]);
    text += Dim == 3 ? fmt::format(",{:.12e}\n", f[Dim - 1]) : "\n";
  }
  io::write_file_atomic(csv_path, text);
}

template void write_points_vtu<2>(const mpm::Model<2>&, const std::string&);
template void write_points_vtu<3>(const mpm::Model<3>&, const std::string&);
template void write_contacts<2>(const mpm::Model<2>&, const contact::Problem<2>&,
                                const std::string&, const std::string&);
template void write_contacts<3>(const mpm::Model<3>&, const contact::Problem<3>&,
                                const std::string&, const std::string&);

Outputs::Outputs(const io::Config& cfg, const std::string& dir, const std::string& extra_header,
                 const checkpoint::State* restart, const std::string& history)
    : cfg_(cfg), dir_(dir), dim_(cfg.simulation.dimension) {
  fs::create_directories(dir_);
  if (restart && !history.empty()) copy_history(history, *restart);
  // Input copy, stamped with the version that ran it.
  io::write_file_atomic(
      (fs::path(dir_) / "input.toml").string(),
      fmt::format("# run by mpmcd {} ({}) from {}\n", kVersion, kGitHash, cfg.source_path) +
          cfg.source_text);
  csv_path_ = (fs::path(dir_) / (cfg.simulation.name + ".csv")).string();
  std::string header =
      "step,time,dt,newton_iterations,linear_solves,kinetic_energy,elastic_energy,"
      "total_energy,momentum_x,momentum_y";
  if (dim_ == 3) header += ",momentum_z";
  header += ",mass,volume,contacts,active_contacts,gs_sweeps";
  for (const auto& w : cfg.walls) {
    header += ",wall_" + w.name + "_fx,wall_" + w.name + "_fy";
    if (dim_ == 3) header += ",wall_" + w.name + "_fz";
  }
  header += extra_header + "\n";
  if (restart && fs::exists(csv_path_)) {
    csv_rows_ = trim_csv(csv_path_, restart->csv_rows);
    if (csv_rows_ < restart->csv_rows)
      log().warn("{} holds {} of the {} rows written before the checkpoint", csv_path_, csv_rows_,
                 restart->csv_rows);
    csv_rows_ = restart->csv_rows;
    csv_.open(csv_path_, std::ios::binary | std::ios::app);
  } else {
    if (restart) log().warn("{} is missing: it restarts at step {}", csv_path_, restart->step);
    csv_rows_ = restart ? restart->csv_rows : 0;
    csv_.open(csv_path_, std::ios::binary | std::ios::trunc);
    write_row(header);
  }
  if (!csv_) throw std::runtime_error("cannot open " + csv_path_);
  if (cfg_.output.vtu)
    pvd_ =
        std::make_unique<io::PvdSeries>((fs::path(dir_) / (cfg.simulation.name + ".pvd")).string());
  if (restart && pvd_) {  // the series so far: file names follow from the snapshot index
    int missing = 0;
    for (const double t : restart->vtu_times) {
      // Only snapshots that are in this folder: a series never lists a missing file.
      const std::string name = fmt::format("{}_{:06d}.vtu", cfg_.simulation.name, vtu_count_);
      if (fs::exists(fs::path(dir_) / name))
        pvd_->restore(t, name);
      else
        ++missing;
      vtu_times_.push_back(t);
      ++vtu_count_;
    }
    if (missing > 0)
      log().warn(
          "{} of the {} snapshots written before the checkpoint are not in {}: the .pvd "
          "series lists the {} that are",
          missing, vtu_count_, dir_, vtu_count_ - missing);
  }
}

void Outputs::copy_history(const std::string& from, const checkpoint::State& restart) {
  const std::string& name = cfg_.simulation.name;
  std::vector<std::string> files{name + ".csv"};
  for (std::size_t k = 0; k < restart.vtu_times.size(); ++k)
    for (const char* f : {"{}_{:06d}.vtu", "{}_contacts_{:06d}.vtu", "{}_pairs_{:06d}.csv",
                          "{}_grains_{:06d}.csv", "{}_forces_{:06d}.csv"})
      files.push_back(fmt::format(fmt::runtime(f), name, k));
  int copied = 0;
  for (const auto& f : files) {
    const fs::path src = fs::path(from) / f, dst = fs::path(dir_) / f;
    std::error_code ec;
    if (!fs::is_regular_file(src, ec)) continue;
    const fs::path tmp = dst.string() + ".tmp";  // atomic, as every output
    fs::copy_file(src, tmp, fs::copy_options::overwrite_existing, ec);
    if (!ec) fs::rename(tmp, dst, ec);
    if (ec)
      throw std::runtime_error(
          fmt::format("cannot copy '{}' to '{}': {}", src.string(), dst.string(), ec.message()));
    ++copied;
  }
  log().info("restart into {}: copied {} files written before the checkpoint from {}", dir_, copied,
             from);
}

template <int Dim>
void Outputs::restore_contacts(const mpm::ImplicitSolver<Dim>& solver) {
  if (!pvd_ || !solver.settings().contact.enabled) return;
  contacts_pvd_ = std::make_unique<io::PvdSeries>(
      (fs::path(dir_) / (cfg_.simulation.name + "_contacts.pvd")).string());
  for (std::size_t k = 0; k < vtu_times_.size(); ++k) {
    const std::string name = fmt::format("{}_contacts_{:06d}.vtu", cfg_.simulation.name, k);
    if (fs::exists(fs::path(dir_) / name)) contacts_pvd_->restore(vtu_times_[k], name);
  }
}

template <int Dim>
void Outputs::csv_row(std::int64_t step, double t, double dt, const mpm::StepStats& st,
                      const mpm::Diagnostics<Dim>& d, const std::string& extra) {
  std::string row = fmt::format("{},{:.12e},{:.6e},{},{},{:.12e},{:.12e},{:.12e},{:.12e},{:.12e}",
                                step, t, dt, st.iterations, st.linear_solves, d.kinetic, d.elastic,
                                d.kinetic + d.elastic, d.momentum[0], d.momentum[1]);
  if constexpr (Dim == 3) row += fmt::format(",{:.12e}", d.momentum[2]);
  row += fmt::format(",{:.12e},{:.12e}", d.mass, d.volume);
  row += fmt::format(",{},{},{}", st.contacts, st.active_contacts, st.gs_sweeps);
  for (std::size_t k = 0; k < cfg_.walls.size(); ++k) {
    const bool have = k < st.wall_force.size();
    row += fmt::format(",{:.12e},{:.12e}", have ? st.wall_force[k][0] : 0.0,
                       have ? st.wall_force[k][1] : 0.0);
    if constexpr (Dim == 3) row += fmt::format(",{:.12e}", have ? st.wall_force[k][2] : 0.0);
  }
  row += extra + "\n";
  write_row(row);
  ++csv_rows_;
}

template <int Dim>
void Outputs::vtu(const mpm::Model<Dim>& model, const mpm::ImplicitSolver<Dim>& solver,
                  const contact::Problem<Dim>& problem, double t) {
  if (cfg_.output.grains) {  // grain-scale files at every snapshot time, with or without VTU
    const auto snap = grain_snapshot(model, problem);
    const std::string gname = fmt::format("{}_grains_{:06d}.csv", cfg_.simulation.name, vtu_count_);
    write_grains_csv(model, snap, t, (fs::path(dir_) / gname).string());
    if (solver.settings().contact.enabled) {
      const std::string fname =
          fmt::format("{}_forces_{:06d}.csv", cfg_.simulation.name, vtu_count_);
      write_contact_forces_csv(snap, t, (fs::path(dir_) / fname).string());
    }
  }
  if (!pvd_) {
    if (cfg_.output.grains) {  // the snapshot index still counts the grain files
      vtu_times_.push_back(t);
      ++vtu_count_;
    }
    return;
  }
  const std::string name = fmt::format("{}_{:06d}.vtu", cfg_.simulation.name, vtu_count_);
  write_points_vtu(model, (fs::path(dir_) / name).string());
  if (solver.settings().contact.enabled) {
    const std::string cname =
        fmt::format("{}_contacts_{:06d}.vtu", cfg_.simulation.name, vtu_count_);
    const std::string pname = fmt::format("{}_pairs_{:06d}.csv", cfg_.simulation.name, vtu_count_);
    write_contacts(model, problem, (fs::path(dir_) / cname).string(),
                   (fs::path(dir_) / pname).string());
    if (!contacts_pvd_)
      contacts_pvd_ = std::make_unique<io::PvdSeries>(
          (fs::path(dir_) / (cfg_.simulation.name + "_contacts.pvd")).string());
    contacts_pvd_->add(t, cname);
  }
  pvd_->add(t, name);  // last: a series lists only snapshots whose files are complete
  vtu_times_.push_back(t);
  ++vtu_count_;
}

template <int Dim>
std::string Outputs::last_good(const mpm::Model<Dim>& model) {
  const std::string path = (fs::path(dir_) / (cfg_.simulation.name + "_last_good.vtu")).string();
  write_points_vtu(model, path);
  return path;
}

#define MPMCD_OUTPUTS(Dim)                                                                 \
  template void Outputs::restore_contacts<Dim>(const mpm::ImplicitSolver<Dim>&);           \
  template void Outputs::csv_row<Dim>(std::int64_t, double, double, const mpm::StepStats&, \
                                      const mpm::Diagnostics<Dim>&, const std::string&);   \
  template void Outputs::vtu<Dim>(const mpm::Model<Dim>&, const mpm::ImplicitSolver<Dim>&, \
                                  const contact::Problem<Dim>&, double);                   \
  template std::string Outputs::last_good<Dim>(const mpm::Model<Dim>&);
MPMCD_OUTPUTS(2)
MPMCD_OUTPUTS(3)
#undef MPMCD_OUTPUTS

void Outputs::write_row(const std::string& row) {
  csv_.write(row.data(), static_cast<std::streamsize>(row.size()));
  csv_.flush();
  if (!csv_)
    throw std::runtime_error(fmt::format("cannot write '{}': {}", csv_path_,
                                         std::strerror(errno)));  // e.g. no space left
}

}  // namespace mpmcd::app
