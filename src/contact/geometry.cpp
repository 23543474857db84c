// The geometry of contact detection on plain views (include/mpmcd/contact/geometry.hpp): points'
// domains, their faces and gaps, grain nodes near walls, hat weights at a grain's nodes.
#include "mpmcd/contact/geometry.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <tuple>

namespace mpmcd::contact {

template <int Dim>
double domain_extent(const Mat<Dim>& F, const Mat<Dim>& D0, const Vec<Dim>& n) {
  return (D0.transpose() * (F.transpose() * n)).cwiseAbs().sum();
}

template <int Dim>
double domain_reach(const Mat<Dim>& D) {
  double r = 0;
  for (int d = 0; d < Dim; ++d) r += D.col(d).norm();
  return r;
}

template <int Dim>
void face_corners(const Vec<Dim>& x, const Mat<Dim>& D, int axis, double sign,
                  std::vector<Vec<Dim>>& corners) {
  for (int c = 0; c < (1 << (Dim - 1)); ++c) {
    Vec<Dim> sc = Vec<Dim>::Zero();
    sc[axis] = sign;
    for (int d = 0, bit = 0; d < Dim; ++d)
      if (d != axis) sc[d] = (c >> bit++) & 1 ? 1.0 : -1.0;
    corners.push_back(x + D * sc);
  }
}

template <int Dim>
Vec<Dim> face_normal(const Mat<Dim>& D, int axis, double sign) {
  const Vec<Dim> m = D.inverse().row(axis).transpose();
  return sign * m / m.norm();
}

template <int Dim>
Mat<Dim> face_normal_derivative(const Vec<Dim>& n, const Vec<Dim>& g) {
  return -(g - n * n.dot(g)) * n.transpose();
}

template <int Dim>
Vec<Dim> face_toward(const Vec<Dim>& x, const Mat<Dim>& D, const Vec<Dim>& n,
                     std::vector<Vec<Dim>>& corners) {
  // Choosing the corners that minimise s . D^T n instead would switch from a face to a single
  // corner, and so change the constraint's nodes and weights, as soon as round-off shears the
  // domain (docs/accuracy.md, "Uniaxial stress").
  const Mat<Dim> m = D.inverse().transpose();  // columns: face normals m_k (unnormalised)
  int axis = 0;
  double best = -1;
  for (int d = 0; d < Dim; ++d) {
    const double align = std::abs(m.col(d).dot(n)) / m.col(d).norm();
    if (align > best) {
      best = align;
      axis = d;
    }
  }
  Vec<Dim> s = Vec<Dim>::Zero();
  s[axis] = m.col(axis).dot(n) > 0 ? -1.0 : 1.0;
  face_corners(x, D, axis, s[axis], corners);
  return x + D * s;
}

namespace {
// pair_gap of p and q whose centres are d = x_q - x_p apart, |d| = len > 0 [m].
template <int Dim>
double gap_along(const DomainsView<Dim>& pts, std::int64_t p, std::int64_t q, const Vec<Dim>& d,
                 double len) {
  const Vec<Dim> e = d / len;
  return len - domain_extent<Dim>(pts.F[p], pts.domain[p], e) -
         domain_extent<Dim>(pts.F[q], pts.domain[q], e);
}
}  // namespace

template <int Dim>
double pair_gap(const DomainsView<Dim>& pts, std::int64_t p, std::int64_t q) {
  const Vec<Dim> d = pts.x[q] - pts.x[p];
  return gap_along(pts, p, q, d, d.norm());
}

template <int Dim>
double nearest_gap(const DomainsView<Dim>& pts, std::span<const double> reach, std::int64_t a0,
                   std::span<const std::int32_t> a, std::int64_t b0,
                   std::span<const std::int32_t> b) {
  // The distance along x_q - x_p, not a projection on a node's normal, which underestimates the
  // gap where the normal is tilted.
  double gap = std::numeric_limits<double>::infinity();
  for (const std::int32_t i : a) {
    const std::int64_t p = a0 + i;
    for (const std::int32_t j : b) {
      const std::int64_t q = b0 + j;
      const Vec<Dim> d = pts.x[q] - pts.x[p];
      const double len_d = d.norm();
      if (!(len_d > 0)) {
        gap = 0;
        continue;
      }
      // The bound with a margin of 1e-12 of the reaches, so that round-off in the bound never
      // skips a pair that would lower the gap.
      const double r = reach[p] + reach[q];
      if (len_d - r > gap + 1e-12 * r) continue;
      gap = std::min(gap, gap_along(pts, p, q, d, len_d));
    }
  }
  return gap;
}

template <int Dim>
double ray_entry(const Vec<Dim>& x_q, const Mat<Dim>& dinv, const Vec<Dim>& x, const Vec<Dim>& nu) {
  constexpr double inf = std::numeric_limits<double>::infinity();
  const Vec<Dim> s0 = dinv * (x - x_q), ds = dinv * nu;
  double t_in = -inf, t_out = inf;
  for (int d = 0; d < Dim; ++d) {
    if (std::abs(ds[d]) < 1e-300) {
      if (std::abs(s0[d]) > 1.0) return inf;
      continue;
    }
    double t1 = (-1.0 - s0[d]) / ds[d], t2 = (1.0 - s0[d]) / ds[d];
    if (t1 > t2) std::swap(t1, t2);
    t_in = std::max(t_in, t1);
    t_out = std::min(t_out, t2);
  }
  return t_in <= t_out && t_out > 0 ? t_in : inf;
}

template <int Dim>
double node_wall_gap(const walls::Wall<Dim>& wall, double t, const Vec<Dim>& x_node,
                     const DomainsView<Dim>& pts, std::int64_t p0,
                     std::span<const std::int32_t> local) {
  double gap = std::numeric_limits<double>::infinity(), ext = 0;
  for (const std::int32_t i : local) {
    const std::int64_t p = p0 + i;
    const double e = domain_extent<Dim>(pts.F[p], pts.domain[p], wall.normal);
    ext = std::max(ext, e);
    gap = std::min(gap, wall.distance(pts.x[p], t) - e);
  }
  if (!std::isfinite(gap)) return gap;
  // Without the 2 e the points between the node and the wall are pushed through by up to e
  // (measured: up to 0.25 h, and the Hertz load sagging); with the points' gap alone the layer
  // down to the first node row would move with the wall.
  return std::max(gap, wall.distance(x_node, t) - 2 * ext);
}

template <int Dim>
std::vector<WallFace> wall_faces(const walls::Wall<Dim>& wall, double t,
                                 const DomainsView<Dim>& pts, std::int64_t begin, std::int64_t end,
                                 double range, double h) {
  std::vector<WallFace> faces;
  for (std::int64_t p = begin; p < end; ++p) {
    const double e = domain_extent<Dim>(pts.F[p], pts.domain[p], wall.normal);
    const double dface = wall.distance(pts.x[p], t) - e;
    if (dface > range) continue;
    // Column index: the cell of the point along the wall's tangent axes.
    const Vec<Dim> xt = pts.x[p] - pts.x[p].dot(wall.normal) * wall.normal;
    std::int64_t column = 0;
    for (int d = 0; d < Dim; ++d)
      column = column * 1000003 + static_cast<std::int64_t>(std::floor(xt[d] / h));
    faces.push_back({column, p, dface, e});
  }
  std::sort(faces.begin(), faces.end(), [](const WallFace& x, const WallFace& y) {
    return std::tie(x.column, x.dist, x.p) < std::tie(y.column, y.dist, y.p);
  });
  return faces;
}

std::size_t column_surface(std::span<const WallFace> faces, std::size_t f0,
                           std::vector<std::int64_t>& surface) {
  std::size_t f1 = f0;
  surface.clear();
  while (f1 < faces.size() && faces[f1].column == faces[f0].column) {
    if (faces[f1].dist <= faces[f0].dist + 0.5 * faces[f0].ext) surface.push_back(faces[f1].p);
    ++f1;
  }
  return f1;
}

template <int Dim>
bool corner_weights(const NodeBoxView<Dim>& box, std::span<const Vec<Dim>> corners, double weight,
                    std::vector<std::int32_t>& nodes, std::vector<double>& weights) {
  nodes.clear();
  weights.clear();
  double total = 0;
  for (const Vec<Dim>& x : corners) {
    const Vec<Dim> xi = (x - box.origin) / box.h;
    IVec<Dim> cell;
    Vec<Dim> t;
    for (int d = 0; d < Dim; ++d) {
      cell[d] = static_cast<std::int64_t>(std::floor(xi[d]));
      t[d] = xi[d] - static_cast<double>(cell[d]);
    }
    for (int b = 0; b < (1 << Dim); ++b) {
      double wt = weight;
      IVec<Dim> node = cell - box.lo;
      for (int d = 0; d < Dim; ++d) {
        const int up = (b >> d) & 1;
        wt *= up ? t[d] : 1.0 - t[d];
        node[d] += up;
      }
      if (wt == 0.0) continue;
      if ((node.array() < 0).any() || (node.array() >= box.n.array()).any()) continue;
      std::int64_t idx = 0, mul = 1;
      for (int d = 0; d < Dim; ++d) {
        idx += node[d] * mul;
        mul *= box.n[d];
      }
      const std::int32_t a = box.box_to_active[static_cast<std::size_t>(idx)];
      if (a < 0) continue;  // no mass there: the position's weight goes to the other nodes
      std::size_t k = 0;
      while (k < nodes.size() && nodes[k] != a) ++k;
      if (k == nodes.size()) {
        nodes.push_back(a);
        weights.push_back(0.0);
      }
      weights[k] += wt;
      total += wt;
    }
  }
  if (nodes.empty() || !(total > 0)) return false;
  for (double& wk : weights) wk /= total;
  return true;
}

#define MPMCD_INSTANTIATE(D)                                                                      \
  template double domain_extent<D>(const Mat<D>&, const Mat<D>&, const Vec<D>&);                  \
  template double domain_reach<D>(const Mat<D>&);                                                 \
  template void face_corners<D>(const Vec<D>&, const Mat<D>&, int, double, std::vector<Vec<D>>&); \
  template Vec<D> face_normal<D>(const Mat<D>&, int, double);                                     \
  template Mat<D> face_normal_derivative<D>(const Vec<D>&, const Vec<D>&);                        \
  template Vec<D> face_toward<D>(const Vec<D>&, const Mat<D>&, const Vec<D>&,                     \
                                 std::vector<Vec<D>>&);                                           \
  template double pair_gap<D>(const DomainsView<D>&, std::int64_t, std::int64_t);                 \
  template double nearest_gap<D>(const DomainsView<D>&, std::span<const double>, std::int64_t,    \
                                 std::span<const std::int32_t>, std::int64_t,                     \
                                 std::span<const std::int32_t>);                                  \
  template double ray_entry<D>(const Vec<D>&, const Mat<D>&, const Vec<D>&, const Vec<D>&);       \
  template double node_wall_gap<D>(const walls::Wall<D>&, double, const Vec<D>&,                  \
                                   const DomainsView<D>&, std::int64_t,                           \
                                   std::span<const std::int32_t>);                                \
  template std::vector<WallFace> wall_faces<D>(const walls::Wall<D>&, double,                     \
                                               const DomainsView<D>&, std::int64_t, std::int64_t, \
                                               double, double);                                   \
  template bool corner_weights<D>(const NodeBoxView<D>&, std::span<const Vec<D>>, double,         \
                                  std::vector<std::int32_t>&, std::vector<double>&);
MPMCD_INSTANTIATE(2)
MPMCD_INSTANTIATE(3)
#undef MPMCD_INSTANTIATE

}  // namespace mpmcd::contact
