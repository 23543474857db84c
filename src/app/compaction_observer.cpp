#include "mpmcd/app/compaction_observer.hpp"

#include <fmt/format.h>

#include <cmath>
#include <set>

#include "mpmcd/app/grain_outputs.hpp"
#include "mpmcd/app/model_builder.hpp"
#include "mpmcd/core/log.hpp"

namespace mpmcd::app {

namespace {

// Σ_{p in g} vol_p of each grain g (zero for grains another rank owns when `owner` is given).
template <int Dim>
std::vector<double> per_grain_sums(const mpm::Model<Dim>& model, const std::vector<double>& vol,
                                   const std::vector<int>* owner, int rank) {
  std::vector<double> sums(model.grains.size(), 0.0);
  for (std::size_t g = 0; g < sums.size(); ++g) {
    if (owner && (*owner)[g] != rank) continue;
    for (std::int64_t p = model.grains[g].begin; p < model.grains[g].end; ++p) sums[g] += vol[p];
  }
  return sums;
}

// Vs = Σ_g Σ_{p in g} V_p (current volumes).
template <int Dim>
double grain_area(const mpm::Model<Dim>& model) {
  return CompactionObserver<Dim>::total_area(CompactionObserver<Dim>::grain_areas(model));
}

// Vs0 = Σ_g Σ_{p in g} V0_p: the initial grain area, also after a restart (equal bit for bit to
// grain_area at t = 0, where V_p = V0_p: the same association).
template <int Dim>
double reference_grain_area(const mpm::Model<Dim>& model) {
  return CompactionObserver<Dim>::total_area(
      per_grain_sums(model, model.points.volume0, nullptr, 0));
}

// Z of the contact network of `problem` among `grains` grains: in 2D through the per-contact
// impulses (the association every 2D output has used), in 3D from the per-pair sums.
template <int Dim>
analysis::Coordination coordination_of(const contact::Problem<Dim>& problem, std::int64_t grains) {
  if constexpr (Dim == 2)
    return analysis::coordination(analysis::contact_impulses(problem), grains);
  else
    return analysis::coordination_of_pairs(analysis::pair_impulses(problem, grains), grains);
}

template <int Dim>
Vec<Dim> force_on(const mpm::StepStats& step, std::size_t k) {
  Vec<Dim> f = Vec<Dim>::Zero();  // before the first step
  if (k < step.wall_force.size())
    for (int a = 0; a < Dim; ++a) f[a] = step.wall_force[k][a];
  return f;
}

}  // namespace

template <int Dim>
CompactionObserver<Dim>::CompactionObserver(const io::Config& config, const mpm::Model<Dim>& model)
    : config_(config), walls_(input_walls<Dim>(config)) {
  box_ = analysis::find_box(walls_);
  if (box_) box0_ = analysis::box_at(walls_, *box_, 0.0);
  vs0_ = reference_grain_area(model);
  grains_ = static_cast<std::int64_t>(model.grains.size());
  pixel_ = model.grid.cell_size() / 8;
  contact_ = contact_enabled(config, model.grains.size());
  // M_p of the grains' material, as its law answers it (λ + 2μ for the laws of λ and μ): defined
  // when the materials of all grains have the same M_p and K_p, i.e. the same λ and μ for those
  // laws (docs/observables.md).
  std::set<std::pair<double, double>> moduli;
  for (const auto& g : model.grains) {
    const auto& law = *model.laws[static_cast<std::size_t>(g.material)];
    moduli.insert({law.wave_modulus(), law.bulk_modulus()});
  }
  if (moduli.size() == 1) mp_ = moduli.begin()->first;
  if (box_ && !mp_)
    log().info(
        "sigma_bottom_over_Mp not written: the grains' materials do not share one P-wave and "
        "bulk modulus (M_p, K_p)");
  if (!box_ && !config.walls.empty())
    log().info(Dim == 3
                   ? "h, eps, phi and wall stresses not written: the walls do not form a box (six "
                     "walls with normals +x, -x, +y, -y, +z, -z)"
                   : "h, eps, phi and wall stresses not written: the walls do not form a box (four "
                     "walls with normals +x, -x, +y, -y)");
}

template <int Dim>
void CompactionObserver<Dim>::move_walls(const std::vector<walls::Wall<Dim>>& walls) {
  for (std::size_t k = 0; k < walls_.size() && k < walls.size(); ++k) walls_[k] = walls[k];
}

template <int Dim>
std::string CompactionObserver<Dim>::csv_header() const {
  std::string h;
  if (box_ && Dim == 3) {
    h += ",h,width,depth,box_volume,eps,phi,Vs,ln_Vs_Vs0";
    for (const auto& w : config_.walls) h += ",wall_" + w.name + "_stress";
    if (mp_) h += ",sigma_bottom_over_Mp";
  } else if (box_) {
    h += ",h,width,box_area,eps,phi,Vs,ln_Vs_Vs0";
    for (const auto& w : config_.walls) h += ",wall_" + w.name + "_stress";
    if (mp_) h += ",sigma_bottom_over_Mp";
  }
  if (box_)
    h += symmetric_names<Dim>("lw_s") +
         ",phi_geometric,overlap_over_Vs,outside_over_Vs,pore_diameter";
  // without a box: Vs is the `volume` column already
  if (contact_) h += ",Z,Z_pairs,Z_grains,rattlers";
  if (config_.output.grains) h += grain_csv_header<Dim>(contact_);
  return h;
}

template <int Dim>
std::string CompactionObserver<Dim>::csv_fields(const mpm::Model<Dim>& model,
                                                const mpm::StepStats& step,
                                                const contact::Problem<Dim>& problem,
                                                double t) const {
  std::string out;
  if (box_) {
    const double vs = grain_area(model);
    const analysis::Box box = analysis::box_at(walls_, *box_, t);
    const auto s = analysis::compaction_state(box, box0_, vs, vs0_);
    if constexpr (Dim == 3)
      out +=
          fmt::format(",{:.17g},{:.17g},{:.17g},{:.17g},{:.17g},{:.17g},{:.17g},{:.17g}", s.height,
                      box.width(), box.depth(), box.area(), s.strain, s.phi, s.vs, s.ln_vs_vs0);
    else
      out += fmt::format(",{:.17g},{:.17g},{:.17g},{:.17g},{:.17g},{:.17g},{:.17g}", s.height,
                         box.width(), box.area(), s.strain, s.phi, s.vs, s.ln_vs_vs0);
    double bottom = 0;
    for (std::size_t k = 0; k < walls_.size(); ++k) {
      const double sigma = analysis::wall_normal_stress(force_on<Dim>(step, k), walls_[k].normal,
                                                        analysis::wall_length(box, *box_, k));
      if (k == box_->bottom) bottom = sigma;
      out += fmt::format(",{:.12e}", sigma);
    }
    if (mp_) out += fmt::format(",{:.12e}", bottom / *mp_);
    const Mat<Dim> lw = analysis::love_weber_stress(model.points, box.area());
    out += symmetric_fields<Dim>(lw);
    const auto c = analysis::domain_coverage(model.points, box, pixel_);
    out += fmt::format(",{:.8e},{:.8e},{:.8e},{:.8e}", 1.0 - c.pores / box.area(), c.overlap / vs,
                       c.outside / vs, c.pore_diameter);
  }
  if (contact_) {
    const auto z = coordination_of(problem, grains_);
    out += fmt::format(",{:.17g},{},{},{}", z.z, z.pairs, z.grains, z.rattlers);
  }
  if (config_.output.grains) {  // V: the box's volume, else the grains' (docs/observables.md)
    const auto snap = grain_snapshot(model, problem, false);
    const double volume = box_ ? analysis::box_at(walls_, *box_, t).area() : grain_area(model);
    out += grain_csv_fields(snap, volume, contact_);
  }
  return out;
}

template <int Dim>
std::optional<typename CompactionObserver<Dim>::Now> CompactionObserver<Dim>::now(
    double grain_area, const mpm::StepStats& step, double t) const {
  if (!box_) return std::nullopt;
  const analysis::Box box = analysis::box_at(walls_, *box_, t);
  const auto s = analysis::compaction_state(box, box0_, grain_area, vs0_);
  const auto stress = [&](std::size_t k) {
    return analysis::wall_normal_stress(force_on<Dim>(step, k), walls_[k].normal,
                                        analysis::wall_length(box, *box_, k));
  };
  return Now{s.phi, std::fabs(s.strain), stress(box_->bottom), stress(box_->top)};
}

template <int Dim>
double CompactionObserver<Dim>::initial_phi() const {
  return box_ && box0_.area() > 0 ? vs0_ / box0_.area() : 0.0;
}

template <int Dim>
std::optional<double> CompactionObserver<Dim>::coordination(
    const contact::Problem<Dim>& problem) const {
  if (!contact_) return std::nullopt;
  return coordination_of(problem, grains_).z;
}

template <int Dim>
std::vector<double> CompactionObserver<Dim>::grain_areas(const mpm::Model<Dim>& model,
                                                         const std::vector<int>* owner, int rank) {
  return per_grain_sums(model, model.points.volume, owner, rank);
}

template <int Dim>
double CompactionObserver<Dim>::total_area(const std::vector<double>& areas) {
  double vs = 0;
  for (double a : areas) vs += a;
  return vs;
}

template <int Dim>
std::optional<std::string> CompactionObserver<Dim>::stop_reason(const mpm::Model<Dim>& model,
                                                                const mpm::StepStats& step,
                                                                double t) const {
  return stop_reason(grain_area(model), step, t);
}

template <int Dim>
std::optional<std::string> CompactionObserver<Dim>::stop_reason(double grain_area,
                                                                const mpm::StepStats& step,
                                                                double t) const {
  const auto& c = config_.stop;
  if (!box_ || (c.phi <= 0 && c.strain <= 0 && c.stress <= 0)) return std::nullopt;
  const analysis::Box box = analysis::box_at(walls_, *box_, t);
  const auto s = analysis::compaction_state(box, box0_, grain_area, vs0_);
  if (c.phi > 0 && s.phi >= c.phi)
    return fmt::format("stop.phi reached: Phi = {:.6f} >= {}", s.phi, c.phi);
  if (c.strain > 0 && std::fabs(s.strain) >= c.strain)
    return fmt::format("stop.strain reached: |eps| = {:.6f} >= {}", std::fabs(s.strain), c.strain);
  if (c.stress > 0) {
    const double sigma = analysis::wall_normal_stress(
        force_on<Dim>(step, box_->bottom), walls_[box_->bottom].normal,
        Dim == 3 ? analysis::wall_length(box, *box_, box_->bottom) : box.width());
    if (-sigma >= c.stress)
      return fmt::format("stop.stress reached: bottom wall stress -sigma = {:.6g} Pa >= {} Pa",
                         -sigma, c.stress);
  }
  return std::nullopt;
}

template class CompactionObserver<2>;
template class CompactionObserver<3>;

}  // namespace mpmcd::app
