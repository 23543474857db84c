// Contact detection at x^n (method.md §4, docs/contact.md): the grain-grain and grain-wall
// contacts with their normals, gaps and warm-start impulses, on views of the grains' node fields
// (include/mpmcd/contact/detect.hpp). The contacts at the grains' boundary faces are in
// face_contacts.cpp.
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <tuple>
#include <vector>

#include "mpmcd/contact/detect.hpp"

namespace mpmcd::contact {

template <int Dim>
Vec<Dim> warm_impulse(std::span<const WarmImpulse<Dim>> previous, std::int64_t key, std::int32_t a,
                      std::int32_t b) {
  const WarmImpulse<Dim> k{key, a, b, Vec<Dim>::Zero()};
  auto it = std::lower_bound(previous.begin(), previous.end(), k,
                             [](const WarmImpulse<Dim>& x, const WarmImpulse<Dim>& y) {
                               return std::tie(x.node, x.a, x.b) < std::tie(y.node, y.a, y.b);
                             });
  if (it != previous.end() && it->node == key && it->a == a && it->b == b) return it->impulse;
  return Vec<Dim>::Zero();
}

template <int Dim>
double Detector<Dim>::detect(const DetectInput<Dim>& in, Problem<Dim>& problem,
                             SlotMaker<Dim>& slots) {
  const ContactSettings<Dim>& cs = *in.settings;
  const grid::Grid<Dim>& grid = *in.grid;
  const std::span<const FieldView<Dim>> fields = in.fields;
  const double h = grid.cell_size();
  const auto nn = static_cast<std::size_t>(grid.node_count());
  if (node_stamp_.size() != nn) {
    node_stamp_.assign(nn, 0);
    node_head_.assign(nn, -1);
  }
  ++stamp_;
  const auto warm = [&](std::int64_t node, std::int32_t a, std::int32_t b) {
    return warm_impulse<Dim>(in.previous, node, a, b);
  };
  const DomainsView<Dim>& pts = in.points;
  // 1. Grain fields carrying mass at each node: linked entries per global node.
  struct Entry {
    std::int32_t g, a, next;
  };
  std::vector<Entry> entries;
  std::vector<std::int64_t> shared;
  for (std::size_t g : in.local) {
    const FieldView<Dim>& w = fields[g];
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
  const bool dist = in.ranks.distributed;
  const int me = in.ranks.me;
  const auto node_rank = [&](std::int64_t n) {
    if (!dist) return 0;
    if (in.ranks.master) return 0;
    std::int32_t gmin = std::numeric_limits<std::int32_t>::max();
    for (std::int32_t e = node_head_[n]; e >= 0; e = entries[e].next)
      gmin = std::min(gmin, entries[e].g);
    return in.ranks.owner[gmin];
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
    point_reach_.resize(pts.x.size());
    if (cs.grain_faces) point_dinv_.resize(pts.x.size());
    const auto nl = static_cast<std::int64_t>(in.local.size());
    const ThreadedRegion threaded_reach(in.timers, nl > 1);
#pragma omp parallel for schedule(dynamic, 4) if (nl > 1)
    for (std::int64_t i = 0; i < nl; ++i) {
      const FieldView<Dim>& gr = fields[in.local[static_cast<std::size_t>(i)]];
      for (std::int64_t p = gr.begin; p < gr.end; ++p) {
        const Mat<Dim> D = pts.F[p] * pts.domain[p];
        point_reach_[p] = domain_reach<Dim>(D);
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
    ScopedStage faces(in.timers, "contact.detect.faces");
    items += static_cast<double>(links.size()) + grain_face_contacts(in, links, problem, slots);
  }
  ThreadedRegion threaded(in.timers, nshared > 256);
#pragma omp parallel for schedule(dynamic, 32) if (nshared > 256) reduction(+ : items)
  for (std::int64_t i = 0; i < nshared; ++i) {
    if (cs.grain_faces) continue;
    const std::int64_t n = shared[i];
    if (node_rank(n) != me) continue;
    for (std::int32_t e1 = node_head_[n]; e1 >= 0; e1 = entries[e1].next)
      for (std::int32_t e2 = entries[e1].next; e2 >= 0; e2 = entries[e2].next) {
        Entry A = entries[e1], B = entries[e2];
        if (A.g > B.g) std::swap(A, B);
        const FieldView<Dim>& wa = fields[A.g];
        const FieldView<Dim>& wb = fields[B.g];
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
          gap = std::max(0.0, nearest_gap<Dim>(pts, point_reach_, wa.begin, wa.points_of(A.a),
                                               wb.begin, wb.points_of(B.a)));
        }
        found[i].push_back({A, B, normal, gap, warm(n, A.g, B.g)});
      }
  }
  threaded.done();
  for (std::size_t i = 0; i < shared.size(); ++i)
    for (const Candidate& f : found[i]) {
      Contact<Dim> c;
      c.a = slots.node_slot(f.A.g, f.A.a);
      c.b = slots.node_slot(f.B.g, f.B.a);
      c.normal = f.normal;
      c.gap = f.gap;
      c.friction = cs.friction[fields[f.A.g].material * cs.materials + fields[f.B.g].material];
      c.impulse = f.warm;
      problem.contacts.push_back(c);
    }
  // 3. Grain-wall contacts: grain nodes within wall_range cells of a wall; gap from the points.
  ScopedStage walls_stage(in.timers, "contact.detect.walls");
  // Node walls: each grain's candidates, gaps and warm starts on the threads, then the contacts in
  // the serial order (wall, grain, node).
  struct WallCandidate {
    std::int32_t a;
    double gap;
    Vec<Dim> warm;
  };
  const std::size_t nw = cs.walls.size(), nlocal = in.local.size();
  std::vector<std::vector<WallCandidate>> wall_found(cs.wall_points ? 0 : nw * nlocal);
  if (!cs.wall_points && nw > 0) {
    const auto npairs = static_cast<std::int64_t>(nw * nlocal);
    const ThreadedRegion threaded_walls(in.timers, npairs > 1);
#pragma omp parallel for schedule(dynamic, 4) if (npairs > 1) reduction(+ : items)
    for (std::int64_t k = 0; k < npairs; ++k) {
      const std::size_t wi = static_cast<std::size_t>(k) / nlocal;
      const std::size_t g = in.local[static_cast<std::size_t>(k) % nlocal];
      const walls::Wall<Dim>& wall = cs.walls[wi];
      const FieldView<Dim>& w = fields[g];
      for (std::size_t a = 0; a < w.m.size(); ++a) {
        if (w.m[a] < w.contact_mass) continue;
        if (dist && node_rank(w.node_global[a]) != me) continue;
        const Vec<Dim> xn = grid.node_position(grid.node_coords(w.node_global[a]));
        if (wall.distance(xn, in.time) > cs.wall_range * h) continue;
        items += 1.0 + (w.node_pts_start[a + 1] - w.node_pts_start[a]);
        const double gap = node_wall_gap<Dim>(wall, in.time, xn, pts, w.begin,
                                              w.points_of(static_cast<std::int32_t>(a)));
        if (!std::isfinite(gap)) continue;
        wall_found[static_cast<std::size_t>(k)].push_back(
            {static_cast<std::int32_t>(a), gap,
             warm(w.node_global[a], -1 - static_cast<std::int32_t>(wi),
                  static_cast<std::int32_t>(g))});
      }
    }
  }
  // Face walls: each (wall, grain) pair's faces near the wall on the threads (a pure function of
  // the points), then the contacts in the serial order (wall, grain, column, face) below.
  std::vector<std::vector<WallFace>> wall_face_lists(cs.wall_points ? nw * nlocal : 0);
  if (cs.wall_points && nw > 0) {
    const auto npairs = static_cast<std::int64_t>(nw * nlocal);
    const ThreadedRegion threaded_faces(in.timers, npairs > 1);
#pragma omp parallel for schedule(dynamic, 4) if (npairs > 1)
    for (std::int64_t k = 0; k < npairs; ++k) {
      const std::size_t wi = static_cast<std::size_t>(k) / nlocal;
      const std::size_t g = in.local[static_cast<std::size_t>(k) % nlocal];
      wall_face_lists[static_cast<std::size_t>(k)] = wall_faces<Dim>(
          cs.walls[wi], in.time, pts, fields[g].begin, fields[g].end, cs.wall_range * h, h);
    }
  }
  for (std::size_t wi = 0; wi < cs.walls.size(); ++wi) {
    const walls::Wall<Dim>& wall = cs.walls[wi];
    for (std::size_t li = 0; li < nlocal; ++li) {
      const std::size_t g = in.local[li];
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
        const std::vector<WallFace>& faces = wall_face_lists[wi * nlocal + li];
        items += static_cast<double>(faces.size());
        // One contact on the faces of `face_pts`; `key_of` gives its warm-start key (negative: not
        // a node).
        const auto add_contact = [&](const std::vector<std::int64_t>& face_pts, auto key_of) {
          Vec<Dim> x_face;
          const std::int32_t sb = face_slot<Dim>(fields[g], static_cast<std::int32_t>(g), pts,
                                                 face_pts, wall.normal, x_face, slots);
          if (sb < 0) return;
          const std::int64_t key = key_of(x_face);
          slots.set_key(sb, key);
          Contact<Dim> c;
          c.a = -1;
          c.wall = static_cast<std::int32_t>(wi);
          c.b = sb;
          c.normal = wall.normal;
          c.wall_velocity = wall.velocity;
          c.gap = std::max(0.0, wall.distance(x_face, in.time));
          c.friction = wall.friction;
          c.impulse = warm(key, -1 - static_cast<std::int32_t>(wi), static_cast<std::int32_t>(g));
          problem.contacts.push_back(c);
        };
        // Warm-start key of a column's contact: -1 - the grid cell of the mean face centre
        // projected on the wall's plane through the origin (the column: stable while the faces
        // move toward the wall and cross grid lines, when a lost warm start would hurt most).
        const auto column_key = [&](const Vec<Dim>& x_face) -> std::int64_t {
          const Vec<Dim> xt = x_face - x_face.dot(wall.normal) * wall.normal;
          IVec<Dim> cell;
          for (int d = 0; d < Dim; ++d)
            cell[d] = std::clamp<std::int64_t>(
                static_cast<std::int64_t>(std::floor((xt[d] - grid.origin()[d]) / h)), 0,
                grid.cells()[d] - 1);
          return -1 - grid.node_index(cell);
        };
        std::vector<std::int64_t> surface;
        for (std::size_t f0 = 0; f0 < faces.size();) {
          f0 = column_surface(faces, f0, surface);
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
        Contact<Dim> c;
        c.a = -1;
        c.wall = static_cast<std::int32_t>(wi);
        c.b = slots.node_slot(static_cast<std::int32_t>(g), f.a);
        c.normal = wall.normal;
        c.wall_velocity = wall.velocity;
        c.gap = std::max(0.0, f.gap);
        c.friction = wall.friction;
        c.impulse = f.warm;
        problem.contacts.push_back(c);
      }
    }
  }
  return items;
}

template class Detector<2>;
template class Detector<3>;
template Vec<2> warm_impulse<2>(std::span<const WarmImpulse<2>>, std::int64_t, std::int32_t,
                                std::int32_t);
template Vec<3> warm_impulse<3>(std::span<const WarmImpulse<3>>, std::int64_t, std::int32_t,
                                std::int32_t);

}  // namespace mpmcd::contact
