// Contact detection at x^n (method.md §4, docs/contact.md): the slots (grain-field nodes, and the
// faces of the points facing a wall) and the grain-grain and grain-wall contacts with their
// normals, gaps and warm-start impulses, then the compliance groups.
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <tuple>
#include <vector>

#include "mpmcd/contact/geometry.hpp"
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
  slot_ref_.clear();
  slot_next_.clear();
  slot_start_.assign(1, 0);
  slot_node_.clear();
  slot_weight_.clear();
  slot_is_face_.clear();
  slot_key_.clear();
  const auto nn = static_cast<std::size_t>(grid_.node_count());
  if (node_stamp_.size() != nn) {
    node_stamp_.assign(nn, 0);
    slot_stamp_.assign(nn, 0);
    node_head_.assign(nn, -1);
    slot_head_.assign(nn, -1);
  }
  ++stamp_;
  const auto warm = [&](std::int64_t node, std::int32_t a, std::int32_t b) {
    return warm_impulse(node, a, b);
  };
  const contact::DomainsView<Dim> pts{points_.x, points_.F, points_.domain};
  // 1. Grain fields carrying mass at each node: linked entries per global node.
  struct Entry {
    std::int32_t g, a, next;
  };
  std::vector<Entry> entries;
  std::vector<std::int64_t> shared;
  for (std::size_t g : local_) {
    const GrainWork& w = *work_[g];
    for (std::size_t a = 0; a < w.m.size(); ++a) {
      if (w.m[a] < w.contact_mass) continue;
      const std::int64_t n = w.node_global[a];
      if (node_stamp_[n] != stamp_) {
        node_stamp_[n] = stamp_;
        node_head_[n] = -1;
      }
      const std::int32_t head = node_head_[n];
      if (head >= 0 && entries[head].next < 0) shared.push_back(n);  // second field here
      entries.push_back({static_cast<std::int32_t>(g), static_cast<std::int32_t>(a), head});
      node_head_[n] = static_cast<std::int32_t>(entries.size()) - 1;
    }
  }
  // The rank solving the contacts at node n (docs/parallel.md): the owner of the lowest grain with
  // a field there (partition) or rank 0 (master); every rank sees all the fields at its nodes.
  const bool dist = distributed();
  const int me = dist ? comm_->rank() : 0;
  const auto node_rank = [&](std::int64_t n) {
    if (!dist) return 0;
    if (scheme_ == parallel::Scheme::kMaster) return 0;
    std::int32_t gmin = std::numeric_limits<std::int32_t>::max();
    for (std::int32_t e = node_head_[n]; e >= 0; e = entries[e].next)
      gmin = std::min(gmin, entries[e].g);
    return owner_[gmin];
  };
  // 2. Grain-grain contacts: every pair of fields at a shared node (three grains: three pairs).
  // Normals and gaps per node in parallel (threads), then the contacts in the serial order.
  struct Candidate {
    Entry A, B;
    Vec<Dim> normal;
    double gap;
    Vec<Dim> warm;  // the previous step's impulse of this contact (warm start)
  };
  std::vector<std::vector<Candidate>> found(shared.size());
  const auto nshared = static_cast<std::int64_t>(shared.size());
  // Reach of each point's domain, sum_i |F r_i| >= extent(p, e) for any unit e [m]: a pair
  // whose distance minus both reaches is not below the gap found so far cannot lower it and is
  // skipped (the same gap, far fewer extents: the point pairs of a CPDI node are most of the
  // detection's time otherwise).
  if (cs.criterion == GapCriterion::kGap || cs.grain_faces) {
    point_reach_.resize(points_.x.size());
    if (cs.grain_faces) point_dinv_.resize(points_.x.size());
    const auto nl = static_cast<std::int64_t>(local_.size());
#pragma omp parallel for schedule(dynamic, 4) if (nl > 1)
    for (std::int64_t i = 0; i < nl; ++i) {
      const points::Grain& gr = grains_[local_[static_cast<std::size_t>(i)]];
      for (std::int64_t p = gr.begin; p < gr.end; ++p) {
        const Mat<Dim> D = points_.F[p] * points_.domain[p];
        point_reach_[p] = contact::domain_reach<Dim>(D);
        if (cs.grain_faces) point_dinv_[p] = D.inverse();
      }
    }
  }
  // Work count (Comm::count_work): node fields, pairs and point pairs of the gaps examined here.
  double items = static_cast<double>(entries.size());
  if (cs.grain_faces) {
    // Contacts at the material surface (grain_face_contacts): the pairs of fields at each shared
    // node tell which grains may touch and where.
    std::vector<std::array<std::int32_t, 4>> links;
    for (const std::int64_t n : shared)
      for (std::int32_t e1 = node_head_[n]; e1 >= 0; e1 = entries[e1].next)
        for (std::int32_t e2 = entries[e1].next; e2 >= 0; e2 = entries[e2].next) {
          Entry A = entries[e1], B = entries[e2];
          if (A.g > B.g) std::swap(A, B);
          links.push_back({A.g, B.g, A.a, B.a});
        }
    ScopedStage faces(&timers_, "contact.detect.faces");
    items += static_cast<double>(links.size()) + grain_face_contacts(links);
  }
  ThreadedRegion threaded(&timers_, nshared > 256);
#pragma omp parallel for schedule(dynamic, 32) if (nshared > 256) reduction(+ : items)
  for (std::int64_t i = 0; i < nshared; ++i) {
    if (cs.grain_faces) continue;
    const std::int64_t n = shared[i];
    if (node_rank(n) != me) continue;
    for (std::int32_t e1 = node_head_[n]; e1 >= 0; e1 = entries[e1].next)
      for (std::int32_t e2 = entries[e1].next; e2 >= 0; e2 = entries[e2].next) {
        Entry A = entries[e1], B = entries[e2];
        if (A.g > B.g) std::swap(A, B);
        const GrainWork& wa = *work_[A.g];
        const GrainWork& wb = *work_[B.g];
        items += 1.0 + (wa.node_pts_start[A.a + 1] - wa.node_pts_start[A.a]) *
                           (wb.node_pts_start[B.a + 1] - wb.node_pts_start[B.a]);
        // Normal from A to B (method.md §4). g^X = sum_p m_p grad N_I(x_p) points OUT of grain X
        // (grad N_I at a point points toward the node), i.e. it is minus the gradient of X's mass
        // density, so n ∝ grad rho^B - grad rho^A = g^A - g^B.
        Vec<Dim> normal = wa.grad_m[A.a] - wb.grad_m[B.a];
        const double len = normal.norm();
        if (!(len > 1e-12 * (wa.grad_m[A.a].norm() + wb.grad_m[B.a].norm()))) continue;
        normal /= len;
        double gap = 0;
        if (cs.criterion == GapCriterion::kGap) {
          // Gap near the node: the smallest distance between a point domain of A and one of B in
          // the node's support.
          gap =
              std::max(0.0, contact::nearest_gap<Dim>(
                                pts, point_reach_, grains_[A.g].begin, detail::node_points(wa, A.a),
                                grains_[B.g].begin, detail::node_points(wb, B.a)));
        }
        found[i].push_back({A, B, normal, gap, warm(n, A.g, B.g)});
      }
  }
  threaded.done();
  for (std::size_t i = 0; i < shared.size(); ++i)
    for (const Candidate& f : found[i]) {
      contact::Contact<Dim> c;
      c.a = slot_of(f.A.g, f.A.a);
      c.b = slot_of(f.B.g, f.B.a);
      c.normal = f.normal;
      c.gap = f.gap;
      c.friction = cs.friction[grains_[f.A.g].material * cs.materials + grains_[f.B.g].material];
      c.impulse = f.warm;
      problem_.contacts.push_back(c);
    }
  // 3. Grain-wall contacts: grain nodes within wall_range cells of a wall; gap from the points.
  ScopedStage walls_stage(&timers_, "contact.detect.walls");
  // Node walls: each grain's candidates, gaps and warm starts on the threads, then the contacts in
  // the serial order (wall, grain, node).
  struct WallCandidate {
    std::int32_t a;
    double gap;
    Vec<Dim> warm;
  };
  const std::size_t nw = cs.walls.size(), nlocal = local_.size();
  std::vector<std::vector<WallCandidate>> wall_found(cs.wall_points ? 0 : nw * nlocal);
  if (!cs.wall_points && nw > 0) {
    const auto npairs = static_cast<std::int64_t>(nw * nlocal);
    const ThreadedRegion threaded_walls(&timers_, npairs > 1);
#pragma omp parallel for schedule(dynamic, 4) if (npairs > 1) reduction(+ : items)
    for (std::int64_t k = 0; k < npairs; ++k) {
      const std::size_t wi = static_cast<std::size_t>(k) / nlocal;
      const std::size_t g = local_[static_cast<std::size_t>(k) % nlocal];
      const walls::Wall<Dim>& wall = cs.walls[wi];
      const GrainWork& w = *work_[g];
      for (std::size_t a = 0; a < w.m.size(); ++a) {
        if (w.m[a] < w.contact_mass) continue;
        if (dist && node_rank(w.node_global[a]) != me) continue;
        const Vec<Dim> xn = grid_.node_position(grid_.node_coords(w.node_global[a]));
        if (wall.distance(xn, time_) > cs.wall_range * h) continue;
        items += 1.0 + (w.node_pts_start[a + 1] - w.node_pts_start[a]);
        const double gap =
            contact::node_wall_gap<Dim>(wall, time_, xn, pts, grains_[g].begin,
                                        detail::node_points(w, static_cast<std::int32_t>(a)));
        if (!std::isfinite(gap)) continue;
        wall_found[static_cast<std::size_t>(k)].push_back(
            {static_cast<std::int32_t>(a), gap,
             warm(w.node_global[a], -1 - static_cast<std::int32_t>(wi),
                  static_cast<std::int32_t>(g))});
      }
    }
  }
  for (std::size_t wi = 0; wi < cs.walls.size(); ++wi) {
    const walls::Wall<Dim>& wall = cs.walls[wi];
    for (std::size_t li = 0; li < nlocal; ++li) {
      const std::size_t g = local_[li];
      if (cs.wall_points) {
        // Face contacts (ContactSettings::wall_points, docs/accuracy.md): per cell column
        // along the wall, the faces of the grain's points nearest the wall in that column (within
        // half a point's extent of the nearest) are the grain's surface there; gap = a face's
        // distance from the wall (Signorini on the face velocity, u_n + g/dt >= 0, method.md §4).
        // With the active-set solver each such face is one contact: as many constraints as the
        // surface has faces, more than the node lines they move, so no combination of the
        // surface nodes escapes them (one contact per column left an alternating mode along the
        // wall free, which compression beyond ~20 mu released: docs/accuracy.md, "One contact
        // per face"); the pivoting tolerates the redundancy. Gauss-Seidel stalls on redundant
        // constraints, so with it the faces of a column make one contact on their mean velocity.
        const bool per_face = cs.active_set;
        const std::vector<contact::WallFace> faces = contact::wall_faces<Dim>(
            wall, time_, pts, grains_[g].begin, grains_[g].end, cs.wall_range * h, h);
        items += static_cast<double>(faces.size());
        // One contact on the faces of `face_pts`; `key_of` gives its warm-start key (negative: not
        // a node).
        const auto add_contact = [&](const std::vector<std::int64_t>& face_pts, auto key_of) {
          Vec<Dim> x_face;
          const std::int32_t sb =
              face_slot(static_cast<std::int32_t>(g), face_pts, wall.normal, x_face);
          if (sb < 0) return;
          slot_key_[sb] = key_of(x_face);
          contact::Contact<Dim> c;
          c.a = -1;
          c.wall = static_cast<std::int32_t>(wi);
          c.b = sb;
          c.normal = wall.normal;
          c.wall_velocity = wall.velocity;
          c.gap = std::max(0.0, wall.distance(x_face, time_));
          c.friction = wall.friction;
          c.impulse =
              warm(slot_key_[sb], -1 - static_cast<std::int32_t>(wi), static_cast<std::int32_t>(g));
          problem_.contacts.push_back(c);
        };
        // Warm-start key of a column's contact: -1 - the grid cell of the mean face centre
        // projected on the wall's plane through the origin (the column: stable while the faces
        // move toward the wall and cross grid lines, when a lost warm start would hurt most).
        const auto column_key = [&](const Vec<Dim>& x_face) -> std::int64_t {
          const Vec<Dim> xt = x_face - x_face.dot(wall.normal) * wall.normal;
          IVec<Dim> cell;
          for (int d = 0; d < Dim; ++d)
            cell[d] = std::clamp<std::int64_t>(
                static_cast<std::int64_t>(std::floor((xt[d] - grid_.origin()[d]) / h)), 0,
                grid_.cells()[d] - 1);
          return -1 - grid_.node_index(cell);
        };
        std::vector<std::int64_t> surface;
        for (std::size_t f0 = 0; f0 < faces.size();) {
          f0 = contact::column_surface(faces, f0, surface);
          if (!per_face) {
            add_contact(surface, column_key);
            continue;
          }
          // A face contact's key: -1 - its point (points keep their index within a run).
          for (const std::int64_t p : surface)
            add_contact(std::vector<std::int64_t>{p}, [p](const Vec<Dim>&) { return -1 - p; });
        }
        continue;
      }
      for (const WallCandidate& f : wall_found[wi * nlocal + li]) {
        contact::Contact<Dim> c;
        c.a = -1;
        c.wall = static_cast<std::int32_t>(wi);
        c.b = slot_of(static_cast<std::int32_t>(g), f.a);
        c.normal = wall.normal;
        c.wall_velocity = wall.velocity;
        c.gap = std::max(0.0, f.gap);
        c.friction = wall.friction;
        c.impulse = f.warm;
        problem_.contacts.push_back(c);
      }
    }
  }
  walls_stage.done();
  detect_items_ = items;
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
      contact::Group group;
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
#define MPMCD_INSTANTIATE(D)                                                    \
  template std::int32_t ImplicitSolver<D>::slot_of(std::int32_t, std::int32_t); \
  template void ImplicitSolver<D>::detect_contacts(double);
MPMCD_INSTANTIATE(2)
MPMCD_INSTANTIATE(3)
#undef MPMCD_INSTANTIATE

}  // namespace mpmcd::mpm
