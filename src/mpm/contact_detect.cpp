// Contact detection at x^n (method.md §4, docs/contact.md): the slots (grain-field nodes, and the
// weighted means of a grain's nodal velocities: faces), the grain-grain and grain-wall contacts
// found by contact::Detector on views of the grain fields, then the compliance groups.
#include <algorithm>
#include <vector>

#include "solver_detail.hpp"

namespace mpmcd::mpm {

template <int Dim>
std::int32_t ImplicitSolver<Dim>::slot_of(std::int32_t g, std::int32_t a) {
  const std::int64_t node = work_[g]->node_global[a];
  if (slot_stamp_[node] != stamp_) {
    slot_stamp_[node] = stamp_;
    slot_head_[node] = -1;
  }
  for (std::int32_t s = slot_head_[node]; s >= 0; s = slot_next_[s])
    if (slot_ref_[s].first == g) return s;
  const auto s = static_cast<std::int32_t>(problem_.slots.size());
  const GrainWork& w = *work_[g];
  problem_.slots.push_back({w.m[a], w.v[a], g, node});
  slot_ref_.emplace_back(g, a);
  slot_next_.push_back(slot_head_[node]);
  slot_head_[node] = s;
  slot_node_.push_back(a);
  slot_weight_.push_back(1.0);
  slot_start_.push_back(static_cast<std::int32_t>(slot_node_.size()));
  slot_is_face_.push_back(0);
  slot_key_.push_back(node);
  return s;
}

template <int Dim>
std::int32_t ImplicitSolver<Dim>::weighted_slot(std::int32_t g,
                                                const std::vector<std::int32_t>& nodes,
                                                const std::vector<double>& weights) {
  // Effective mass 1 / sum w_k^2 / m_k: the lumped response of the mean velocity to an impulse.
  const GrainWork& w = *work_[g];
  const auto sidx = static_cast<std::int32_t>(problem_.slots.size());
  double inv_mass = 0;
  std::int32_t primary = nodes[0];
  double wmax = 0;
  for (std::size_t k = 0; k < nodes.size(); ++k) {
    slot_node_.push_back(nodes[k]);
    slot_weight_.push_back(weights[k]);
    inv_mass += weights[k] * weights[k] / w.m[nodes[k]];
    if (weights[k] > wmax) {
      wmax = weights[k];
      primary = nodes[k];
    }
  }
  slot_start_.push_back(static_cast<std::int32_t>(slot_node_.size()));
  slot_is_face_.push_back(1);
  slot_key_.push_back(-1);
  problem_.slots.push_back({1.0 / inv_mass, Vec<Dim>::Zero(), g, w.node_global[primary]});
  slot_ref_.emplace_back(g, primary);
  slot_next_.push_back(-1);  // not linked to its node: slot_of never returns a face slot
  problem_.slots.back().v_free = slot_velocity(static_cast<std::size_t>(sidx));
  return sidx;
}

// The solver's slots as contact detection makes them (contact::SlotMaker).
template <int Dim>
class ImplicitSolver<Dim>::Slots final : public contact::SlotMaker<Dim> {
 public:
  explicit Slots(ImplicitSolver& solver) : s_(solver) {}
  std::int32_t node_slot(std::int32_t g, std::int32_t a) override { return s_.slot_of(g, a); }
  std::int32_t weighted_slot(std::int32_t g, const std::vector<std::int32_t>& nodes,
                             const std::vector<double>& weights) override {
    return s_.weighted_slot(g, nodes, weights);
  }
  void set_key(std::int32_t s, std::int64_t key) override { s_.slot_key_[s] = key; }

 private:
  ImplicitSolver& s_;
};

template <int Dim>
void ImplicitSolver<Dim>::detect_contacts(double dt) {
  const ContactSettings<Dim>& cs = settings_.contact;
  const double h = grid_.cell_size();
  problem_.dt = dt;
  problem_.law = cs.law;
  problem_.slots.clear();
  problem_.contacts.clear();
  slot_bases_valid_ = false;
  sweep_order_ready_ = false;
  as_cache_.valid = false;
  as_cache_.pattern = false;
  slot_ref_.clear();
  slot_next_.clear();
  slot_start_.assign(1, 0);
  slot_node_.clear();
  slot_weight_.clear();
  slot_is_face_.clear();
  grain_slots_for_ = -1;
  slot_key_.clear();
  const auto nn = static_cast<std::size_t>(grid_.node_count());
  if (slot_stamp_.size() != nn) {
    slot_stamp_.assign(nn, 0);
    slot_head_.assign(nn, -1);
  }
  ++stamp_;
  // The grain fields' contact views at x^n (every grain's: the gap horizon reads all speeds).
  field_views_.resize(work_.size());
  for (std::size_t g = 0; g < work_.size(); ++g) {
    const GrainWork& w = *work_[g];
    field_views_[g] = {grains_[g].begin,
                       grains_[g].end,
                       grains_[g].material,
                       w.contact_mass,
                       w.m,
                       w.node_global,
                       w.grad_m,
                       w.v,
                       w.node_pts_start,
                       w.node_pts,
                       {grid_.origin(), h, w.box_lo, w.box_n, w.box_to_active}};
  }
  contact::DetectInput<Dim> in;
  in.settings = &cs;
  in.grid = &grid_;
  in.points = {points_.x, points_.F, points_.domain};
  in.fields = field_views_;
  in.local = local_;
  in.previous = previous_;
  const bool dist = distributed();
  in.ranks = {dist, scheme_ == parallel::Scheme::kMaster, dist ? comm_->rank() : 0, owner_};
  in.time = time_;
  in.dt = dt_;
  in.gravity = settings_.gravity;
  in.timers = &timers_;
  Slots slots(*this);
  detect_items_ = detector_.detect(in, problem_, slots);
  ScopedStage groups_stage(&timers_, "contact.detect.groups");
  // Warm start: the grains see the previous step's impulses from the first iteration on; a
  // frictionless contact's along its normal of this step (max(0, P . n) n: the impulse it can
  // take, and the directions its slots' compliance is computed on, build_slot_bases).
  for (auto& c : problem_.contacts)
    if (c.friction == 0.0) c.impulse = std::max(0.0, c.impulse.dot(c.normal)) * c.normal;
  slot_P_ = contact::net_impulses(problem_);
  spread_slot_impulses();
  gs_converged_ = true;
  // Compliance groups: one per grain with contact slots when its linear solver is direct. Only
  // slots of contacts that may act in this step join (gap below a quarter cell, or an impulse
  // from the previous step): closing a quarter cell within one step takes a relative speed of
  // h / (4 dt), far above any in a quasi-static run. The other slots (most candidates of a dense
  // packing: their fields overlap a cell before the materials meet) keep the lumped 1/m_I, which
  // still holds them if a fast impact closes their gap.
  for (auto& w : work_) w->slots.clear();
  problem_.groups.clear();
  if (dist) return;  // lumped operator only (set_distribution)
  const bool compliance = cs.grain_compliance && settings_.linear_solver != LinearSolverKind::kCg;
  // A grain with face slots needs a group in any case: its face slots share nodes with each other
  // and with its node slots (lumped groups, G = E^T M^-1 E, when the compliance is not used).
  std::vector<char> has_face(work_.size(), 0);
  for (std::size_t s = 0; s < slot_ref_.size(); ++s)
    if (slot_is_face_[s]) has_face[slot_ref_[s].first] = 1;
  for (std::size_t g = 0; g < work_.size(); ++g) work_[g]->lumped_group = !compliance;
  if (compliance || std::find(has_face.begin(), has_face.end(), 1) != has_face.end()) {
    std::vector<char> near(slot_ref_.size(), 0);
    for (const auto& c : problem_.contacts)
      if (!compliance || c.gap <= 0.25 * h || c.impulse.squaredNorm() > 0) {
        near[c.b] = 1;
        if (c.a >= 0) near[c.a] = 1;
      }
    for (std::size_t s = 0; s < slot_ref_.size(); ++s) {
      if (slot_is_face_[s]) near[s] = 1;
      if (!has_face[slot_ref_[s].first]) near[s] = compliance && near[s];
    }
    for (std::size_t s = 0; s < slot_ref_.size(); ++s)
      if (near[s]) work_[slot_ref_[s].first]->slots.push_back(static_cast<std::int32_t>(s));
    for (std::size_t g = 0; g < work_.size(); ++g) {
      const auto& sl = work_[g]->slots;
      if (sl.empty()) continue;
      const auto gi = static_cast<std::int32_t>(problem_.groups.size());
      contact::Group<Dim> group;
      group.slots = sl;
      for (std::size_t j = 0; j < sl.size(); ++j) {
        problem_.slots[sl[j]].group = gi;
        problem_.slots[sl[j]].local = static_cast<std::int32_t>(j);
      }
      problem_.groups.push_back(std::move(group));
    }
  }
}

// The members defined here (the class is instantiated in solver.cpp).
#define MPMCD_INSTANTIATE(D)                                                       \
  template std::int32_t ImplicitSolver<D>::slot_of(std::int32_t, std::int32_t);    \
  template std::int32_t ImplicitSolver<D>::weighted_slot(                          \
      std::int32_t, const std::vector<std::int32_t>&, const std::vector<double>&); \
  template void ImplicitSolver<D>::detect_contacts(double);
MPMCD_INSTANTIATE(2)
MPMCD_INSTANTIATE(3)
#undef MPMCD_INSTANTIATE

}  // namespace mpmcd::mpm
