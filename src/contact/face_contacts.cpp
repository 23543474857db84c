// Contacts at the faces of the points' domains (docs/accuracy.md, docs/contact.md): the slot of
// the faces of a grain's points facing a wall, and the grain-grain contacts between a grain's
// boundary faces and the other grain's material (include/mpmcd/contact/detect.hpp).
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <tuple>
#include <vector>

#include "mpmcd/contact/detect.hpp"

namespace mpmcd::contact {

template <int Dim>
std::int32_t face_slot(const FieldView<Dim>& field, std::int32_t g, const DomainsView<Dim>& points,
                       const std::vector<std::int64_t>& pts, const Vec<Dim>& n, Vec<Dim>& x_face,
                       SlotMaker<Dim>& slots) {
  // The face of each point's domain toward the wall (face_toward: all 2^(Dim-1) corners of one
  // face). Its velocity is the mean of the corners' velocities interpolated with the linear hat
  // (the same corner kinematics as CPDI): weights w_I = mean over the face corners of N_I(x_c).
  constexpr int corners = 1 << (Dim - 1);
  std::vector<Vec<Dim>> xs;
  xs.reserve(pts.size() * corners);
  x_face.setZero();
  for (const std::int64_t p : pts) {
    const Mat<Dim> D = points.F[p] * points.domain[p];
    x_face += face_toward<Dim>(points.x[p], D, n, xs) / static_cast<double>(pts.size());
  }
  std::vector<std::int32_t> nodes;
  std::vector<double> weights;
  if (!corner_weights<Dim>(field.box, xs, 1.0 / corners, nodes, weights)) return -1;
  return slots.weighted_slot(g, nodes, weights);
}

template <int Dim>
double Detector<Dim>::grain_face_contacts(const DetectInput<Dim>& in,
                                          std::vector<std::array<std::int32_t, 4>>& links,
                                          Problem<Dim>& problem, SlotMaker<Dim>& slots) {
  // Grain-grain contacts at the material surface (ContactSettings::grain_faces, docs/contact.md):
  // for each pair of grains A < B whose fields share nodes, every boundary face of either
  // grain's points there (no other domain of its grain just beyond it) whose outward normal
  // meets a domain of the other grain within wall_range cells makes one contact: the mean
  // velocity of the face's corners in its grain's field against the other grain's velocity at
  // the same corners, along the face's normal, with the distance to the other grain's domains
  // along that normal as the gap (Signorini on the relative velocity of the material surface,
  // u_n + g/dt >= 0, method.md §4). Both grains' faces take part (two passes): with the faces of
  // one grain only, the other grain's corners enter it between them (mirror test: 0.72-0.80 of
  // the wall's force at d/4 instead of 0.94-0.99). The constraints are then redundant where the
  // two surfaces meet, which Gauss-Seidel tolerates at the price of more sweeps (docs/contact.md).
  const ContactSettings<Dim>& cs = *in.settings;
  const grid::Grid<Dim>& grid = *in.grid;
  const std::span<const FieldView<Dim>> fields = in.fields;
  const DomainsView<Dim>& points = in.points;
  const double h = grid.cell_size(), range = cs.wall_range * h;
  constexpr int corners = 1 << (Dim - 1);
  std::sort(links.begin(), links.end());
  const IVec<Dim>& ncell = grid.cells();
  const auto cell_of = [&](const Vec<Dim>& x) {
    IVec<Dim> c;
    for (int d = 0; d < Dim; ++d)
      c[d] = static_cast<std::int64_t>(std::floor((x[d] - grid.origin()[d]) / h));
    return c;
  };
  const auto key_of = [&](const IVec<Dim>& c) -> std::int64_t {  // -1 outside the grid
    std::int64_t k = 0, mul = 1;
    for (int d = 0; d < Dim; ++d) {
      if (c[d] < 0 || c[d] >= ncell[d]) return -1;
      k += c[d] * mul;
      mul *= ncell[d];
    }
    return k;
  };
  // Each grain's points by the cell of their centre: a table over the box of cells its centres
  // occupy (offsets, then the points of each cell in ascending order), for the grains of the
  // links, made on the threads before the search.
  struct CellTable {
    IVec<Dim> lo, n;                  // first cell and cell counts of the box
    std::vector<std::int32_t> start;  // per box cell (x fastest): offset into pts
    std::vector<std::int64_t> pts;    // the points, cell by cell
    double max_reach = 0;             // the largest reach of its points [m]
  };
  std::vector<CellTable> by_cell(fields.size());
  {
    std::vector<std::int32_t> involved;
    for (const auto& l : links) {
      involved.push_back(l[0]);
      involved.push_back(l[1]);
    }
    std::sort(involved.begin(), involved.end());
    involved.erase(std::unique(involved.begin(), involved.end()), involved.end());
    const auto ni = static_cast<std::int64_t>(involved.size());
    const ThreadedRegion threaded(in.timers, ni > 1);
#pragma omp parallel for schedule(dynamic, 1) if (ni > 1)
    for (std::int64_t i = 0; i < ni; ++i) {
      const std::int32_t g = involved[static_cast<std::size_t>(i)];
      CellTable& t = by_cell[static_cast<std::size_t>(g)];
      const std::int64_t b = fields[g].begin, e = fields[g].end;
      std::vector<std::int64_t> box(static_cast<std::size_t>(e - b));
      IVec<Dim> lo = IVec<Dim>::Constant(std::numeric_limits<std::int64_t>::max());
      IVec<Dim> hi = IVec<Dim>::Constant(std::numeric_limits<std::int64_t>::min());
      for (std::int64_t p = b; p < e; ++p) {
        const IVec<Dim> c = cell_of(points.x[p]);
        lo = lo.cwiseMin(c);
        hi = hi.cwiseMax(c);
        t.max_reach = std::max(t.max_reach, point_reach_[p]);
      }
      t.lo = lo;
      t.n = hi - lo + IVec<Dim>::Ones();
      std::int64_t cells = 1;
      for (int d = 0; d < Dim; ++d) cells *= t.n[d];
      t.start.assign(static_cast<std::size_t>(cells) + 1, 0);
      for (std::int64_t p = b; p < e; ++p) {
        const IVec<Dim> c = cell_of(points.x[p]) - lo;
        std::int64_t k = 0, mul = 1;
        for (int d = 0; d < Dim; ++d) {
          k += c[d] * mul;
          mul *= t.n[d];
        }
        box[static_cast<std::size_t>(p - b)] = k;
        ++t.start[static_cast<std::size_t>(k) + 1];
      }
      for (std::size_t k = 0; k + 1 < t.start.size(); ++k) t.start[k + 1] += t.start[k];
      t.pts.resize(static_cast<std::size_t>(e - b));
      std::vector<std::int32_t> fill(t.start.begin(), t.start.end() - 1);
      for (std::int64_t p = b; p < e; ++p)
        t.pts[static_cast<std::size_t>(fill[static_cast<std::size_t>(box[p - b])]++)] = p;
    }
  }
  // Calls f(q) for the points q of grain g whose centre is within r cells (per axis) of x's
  // cell, cell by cell (x fastest) and in ascending order within a cell; cells outside the grid
  // hold none.
  const auto near = [&](std::int32_t g, const Vec<Dim>& x, int r, auto&& f) {
    const CellTable& t = by_cell[static_cast<std::size_t>(g)];
    const IVec<Dim> c0 = cell_of(x);
    IVec<Dim> off = IVec<Dim>::Constant(-r);
    while (true) {
      const IVec<Dim> c = c0 + off;
      if (key_of(c) >= 0) {
        std::int64_t k = 0, mul = 1;
        bool inside = true;
        for (int d = 0; d < Dim && inside; ++d) {
          const std::int64_t cd = c[d] - t.lo[d];
          inside = cd >= 0 && cd < t.n[d];
          k += cd * mul;
          mul *= t.n[d];
        }
        if (inside)
          for (std::int32_t j = t.start[static_cast<std::size_t>(k)];
               j < t.start[static_cast<std::size_t>(k) + 1]; ++j)
            f(t.pts[static_cast<std::size_t>(j)]);
      }
      int d = 0;
      while (d < Dim && off[d] == r) off[d++] = -r;
      if (d == Dim) break;
      ++off[d];
    }
  };
  // One face that makes a contact, found on the threads and turned into slots and a contact in
  // the serial order afterwards.
  struct Hit {
    std::int64_t key;  // warm-start key: -1 - the face's number (point, axis, side)
    Vec<Dim> normal;
    double gap;
    std::vector<std::int32_t> nodes_x, nodes_y;
    std::vector<double> weights_x, weights_y;
  };
  // The passes: grain X's boundary faces at the pair's shared nodes (links[i][col], i in
  // [i0, i1), are X's active nodes there) against grain Y; each pair A < B gives (A, B) then
  // (B, A).
  struct Pass {
    std::int32_t X, Y;
    int col;
    std::size_t i0, i1;
  };
  std::vector<Pass> passes;
  for (std::size_t i0 = 0; i0 < links.size();) {
    const std::int32_t A = links[i0][0], B = links[i0][1];
    std::size_t i1 = i0;
    while (i1 < links.size() && links[i1][0] == A && links[i1][1] == B) ++i1;
    passes.push_back({A, B, 2, i0, i1});
    passes.push_back({B, A, 3, i0, i1});
    i0 = i1;
  }
  // Faces farther than the gap that the step's largest approach speed could close within
  // gap_horizon steps cannot touch in this step (their constraint is inactive at the solution)
  // and are left out: a quarter of the faces in the dense paper state at d/8, half in the dilute
  // one, and 26-34 % of the step time (docs/contact.md).
  double cut = range;
  if (cs.gap_horizon > 0) {
    double speed = 0;
    for (const FieldView<Dim>& w : fields)
      for (const Vec<Dim>& v : w.v) speed = std::max(speed, v.norm());
    for (const walls::Wall<Dim>& wall : cs.walls) speed = std::max(speed, wall.velocity.norm());
    speed += in.gravity.norm() * in.dt;
    cut = std::min(range, cs.gap_horizon * 2.0 * speed * in.dt);
  }
  // |x - y| <= r, tested first on the squares with a margin of 1e-12 (no sqrt for the points far
  // beyond r, the most of those the searches meet), then exactly as |x - y| <= r.
  const auto within = [](const Vec<Dim>& x, const Vec<Dim>& y, double r) {
    const double d2 = (x - y).squaredNorm();
    return d2 <= r * r * (1.0 + 1e-12) && std::sqrt(d2) <= r;
  };
  // The passes of each grain X, done together on one thread: whether a face of X is interior
  // depends on X alone, so it is decided once per point for all of X's passes, first with the
  // domain that held the probe last step (interior_hint_, checked as the search checks it: a
  // different domain that holds it gives the same answer), then by the search.
  std::vector<std::vector<std::size_t>> passes_of;  // per X in order of first pass: its passes
  {
    std::vector<std::int32_t> slot_of(fields.size(), -1);
    for (std::size_t pi = 0; pi < passes.size(); ++pi) {
      std::int32_t& sx = slot_of[static_cast<std::size_t>(passes[pi].X)];
      if (sx < 0) {
        sx = static_cast<std::int32_t>(passes_of.size());
        passes_of.emplace_back();
      }
      passes_of[static_cast<std::size_t>(sx)].push_back(pi);
    }
  }
  if (interior_hint_.size() != points.x.size()) {
    std::array<std::int64_t, 2 * Dim> none;
    none.fill(-1);
    interior_hint_.assign(points.x.size(), none);
  }
  std::vector<std::vector<Hit>> hits(passes.size());
  double items = 0;
  const auto ngroups = static_cast<std::int64_t>(passes_of.size());
  {
    const ThreadedRegion threaded(in.timers, ngroups > 1);
#pragma omp parallel for schedule(dynamic, 1) if (ngroups > 1) reduction(+ : items)
    for (std::int64_t gi = 0; gi < ngroups; ++gi) {
      const std::vector<std::size_t>& mine = passes_of[static_cast<std::size_t>(gi)];
      const std::int32_t X = passes[mine.front()].X;
      const FieldView<Dim>& wx = fields[X];
      // X's points at each pass's shared nodes (ascending), and their union.
      std::vector<std::vector<std::int64_t>> zones(mine.size());
      std::vector<std::int64_t> all;
      for (std::size_t j = 0; j < mine.size(); ++j) {
        const Pass& ps = passes[mine[j]];
        std::vector<std::int64_t>& zone = zones[j];
        for (std::size_t i = ps.i0; i < ps.i1; ++i)
          for (std::int32_t k = wx.node_pts_start[links[i][ps.col]];
               k < wx.node_pts_start[links[i][ps.col] + 1]; ++k)
            zone.push_back(wx.begin + wx.node_pts[k]);
        std::sort(zone.begin(), zone.end());
        zone.erase(std::unique(zone.begin(), zone.end()), zone.end());
        all.insert(all.end(), zone.begin(), zone.end());
      }
      std::sort(all.begin(), all.end());
      all.erase(std::unique(all.begin(), all.end()), all.end());
      // Interior faces of those points, bit 2 k + side: another domain of X holds the point half
      // a domain beyond the face (searched among X's centres within a cell of it).
      std::vector<std::uint8_t> interior(all.size(), 0);
      for (std::size_t u = 0; u < all.size(); ++u) {
        const std::int64_t p = all[u];
        const Mat<Dim> D = points.F[p] * points.domain[p];
        const Mat<Dim>& Dinv = point_dinv_[p];
        const auto holds = [&](std::int64_t q, const Vec<Dim>& xt) {
          return q != p && within(points.x[q], xt, point_reach_[q]) &&
                 (point_dinv_[q] * (xt - points.x[q])).cwiseAbs().maxCoeff() <= 1.0;
        };
        for (int k = 0; k < Dim; ++k)
          for (const int side : {0, 1}) {
            const double sign = side ? 1.0 : -1.0;
            const Vec<Dim> m = Dinv.row(k).transpose();
            const double len = m.norm();
            const Vec<Dim> nu = sign * m / len;
            const Vec<Dim> xf = points.x[p] + sign * D.col(k);
            const Vec<Dim> xt = xf + 0.5 / len * nu;
            std::int64_t& hint = interior_hint_[p][static_cast<std::size_t>(2 * k + side)];
            bool in = false;
            if (hint >= wx.begin && hint < wx.end) {
              // The search only sees centres within one cell of xt's cell (per axis).
              const IVec<Dim> dc = cell_of(points.x[hint]) - cell_of(xt);
              in = dc.cwiseAbs().maxCoeff() <= 1 && holds(hint, xt);
            }
            if (!in) {
              hint = -1;
              near(X, xt, 1, [&](std::int64_t q) {
                if (!in && holds(q, xt)) {
                  in = true;
                  hint = q;
                }
              });
            }
            if (in) interior[u] |= static_cast<std::uint8_t>(1u << (2 * k + side));
          }
      }
      std::vector<Vec<Dim>> xs;
      xs.reserve(corners);
      Hit hit;
      for (std::size_t j = 0; j < mine.size(); ++j) {
        const std::size_t pi = mine[j];
        const std::int32_t Y = passes[pi].Y;
        // Cells searched around a face centre for Y's domains: those within max reach + cut of
        // it (at most the 2 cells searched before; usually 1 of them, a third of the points).
        const double y_reach = by_cell[static_cast<std::size_t>(Y)].max_reach;
        const int gap_radius = static_cast<int>(std::min(2.0, std::ceil((y_reach + cut) / h)));
        std::size_t u = 0;
        for (const std::int64_t p : zones[j]) {
          while (all[u] != p) ++u;  // both ascending, zones[j] within all
          const Mat<Dim> D = points.F[p] * points.domain[p];
          const Mat<Dim>& Dinv = point_dinv_[p];
          for (int k = 0; k < Dim; ++k)
            for (const int side : {0, 1}) {
              items += 1;
              if (interior[u] & (1u << (2 * k + side))) continue;
              // Face s_k = sign: outward normal sign D^-T e_k, at 1/|D^-T e_k| from the centre.
              const double sign = side ? 1.0 : -1.0;
              const Vec<Dim> m = Dinv.row(k).transpose();
              const double len = m.norm();
              const Vec<Dim> nu = sign * m / len;
              const Vec<Dim> xf = points.x[p] + sign * D.col(k);
              // Only domains within `cut` of the face centre can give a gap <= cut (their reach
              // bounds them), and once the face is inside one (gap <= 0) the gap is 0.
              double gap = std::numeric_limits<double>::infinity();
              near(Y, xf, gap_radius, [&](std::int64_t q) {
                if (gap > 0.0 && within(points.x[q], xf, point_reach_[q] + cut))
                  gap = std::min(gap, ray_entry<Dim>(points.x[q], point_dinv_[q], xf, nu));
              });
              if (!(gap <= cut)) continue;
              xs.clear();
              face_corners<Dim>(points.x[p], D, k, sign, xs);
              if (!corner_weights<Dim>(fields[X].box, xs, 1.0, hit.nodes_x, hit.weights_x) ||
                  !corner_weights<Dim>(fields[Y].box, xs, 1.0, hit.nodes_y, hit.weights_y))
                continue;
              hit.key = -1 - (p * 2 * Dim + 2 * k + side);
              hit.normal = nu;
              hit.gap = std::max(0.0, gap);
              hits[pi].push_back(hit);
            }
        }
      }
    }
  }
  // The slots and contacts in the order of the passes (the same problem for any thread count).
  for (std::size_t pi = 0; pi < passes.size(); ++pi) {
    const std::int32_t X = passes[pi].X, Y = passes[pi].Y;
    for (const Hit& hit : hits[pi]) {
      Contact<Dim> c;
      c.a = slots.weighted_slot(X, hit.nodes_x, hit.weights_x);
      c.b = slots.weighted_slot(Y, hit.nodes_y, hit.weights_y);
      slots.set_key(c.b, hit.key);
      c.normal = hit.normal;
      c.gap = hit.gap;
      c.friction = cs.friction[fields[X].material * cs.materials + fields[Y].material];
      c.impulse = warm_impulse<Dim>(in.previous, hit.key, X, Y);
      problem.contacts.push_back(c);
    }
  }
  return items;
}

#define MPMCD_INSTANTIATE(D)                                                                   \
  template std::int32_t face_slot<D>(const FieldView<D>&, std::int32_t, const DomainsView<D>&, \
                                     const std::vector<std::int64_t>&, const Vec<D>&, Vec<D>&, \
                                     SlotMaker<D>&);                                           \
  template double Detector<D>::grain_face_contacts(const DetectInput<D>&,                      \
                                                   std::vector<std::array<std::int32_t, 4>>&,  \
                                                   Problem<D>&, SlotMaker<D>&);
MPMCD_INSTANTIATE(2)
MPMCD_INSTANTIATE(3)
#undef MPMCD_INSTANTIATE

}  // namespace mpmcd::contact
