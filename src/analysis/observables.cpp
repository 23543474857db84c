#include "mpmcd/analysis/observables.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <map>
#include <numbers>
#include <utility>

namespace mpmcd::analysis {

namespace {

bool near(double a, double b) {
  return std::fabs(a - b) <= 1e-12;
}

}  // namespace

namespace {

// The box of 2 Dim walls with normals ±e_a (slots: -x, +x... as left, right, bottom, top, front,
// back: normal +x, -x, +y, -y, +z, -z).
template <int Dim>
std::optional<BoxWalls> find_box_of(std::span<const walls::Wall<Dim>> walls) {
  if (walls.size() != 2 * Dim) return std::nullopt;
  int found[2 * Dim];
  std::fill(found, found + 2 * Dim, -1);
  for (std::size_t k = 0; k < walls.size(); ++k) {
    const Vec<Dim>& n = walls[k].normal;
    int slot = -1;
    for (int a = 0; a < Dim; ++a) {
      bool others = true;
      for (int b = 0; b < Dim; ++b)
        if (b != a && !near(n[b], 0)) others = false;
      if (others && near(n[a], 1)) slot = 2 * a;
      if (others && near(n[a], -1)) slot = 2 * a + 1;
    }
    if (slot < 0 || found[slot] >= 0) return std::nullopt;
    found[slot] = static_cast<int>(k);
  }
  BoxWalls b;
  b.left = static_cast<std::size_t>(found[0]);
  b.right = static_cast<std::size_t>(found[1]);
  b.bottom = static_cast<std::size_t>(found[2]);
  b.top = static_cast<std::size_t>(found[3]);
  if constexpr (Dim == 3) {
    b.front = static_cast<std::size_t>(found[4]);
    b.back = static_cast<std::size_t>(found[5]);
  }
  return b;
}

template <int Dim>
Box box_of(std::span<const walls::Wall<Dim>> walls, const BoxWalls& b, double t) {
  Box box;
  box.dim = Dim;
  box.x_min = walls[b.left].point_at(t)[0];
  box.x_max = walls[b.right].point_at(t)[0];
  box.y_min = walls[b.bottom].point_at(t)[1];
  box.y_max = walls[b.top].point_at(t)[1];
  if constexpr (Dim == 3) {
    box.z_min = walls[b.front].point_at(t)[2];
    box.z_max = walls[b.back].point_at(t)[2];
  }
  return box;
}

}  // namespace

std::optional<BoxWalls> find_box(std::span<const walls::Wall<2>> walls) {
  return find_box_of<2>(walls);
}

std::optional<BoxWalls> find_box(std::span<const walls::Wall<3>> walls) {
  return find_box_of<3>(walls);
}

Box box_at(std::span<const walls::Wall<2>> walls, const BoxWalls& b, double t) {
  return box_of<2>(walls, b, t);
}

Box box_at(std::span<const walls::Wall<3>> walls, const BoxWalls& b, double t) {
  return box_of<3>(walls, b, t);
}

double wall_length(const Box& box, const BoxWalls& walls, std::size_t k) {
  if (box.dim == 3) {
    if (k == walls.bottom || k == walls.top) return box.width() * box.depth();
    if (k == walls.left || k == walls.right) return box.height() * box.depth();
    if (k == walls.front || k == walls.back) return box.width() * box.height();
    return 0.0;
  }
  if (k == walls.bottom || k == walls.top) return box.width();
  if (k == walls.left || k == walls.right) return box.height();
  return 0.0;
}

CompactionState compaction_state(const Box& box, const Box& box0, double vs, double vs0) {
  CompactionState s;
  s.height = box.height();
  s.strain = std::log(box.height() / box0.height());  // ε = ln(h/h0) (paper eq. (9))
  s.phi = vs / box.area();                            // Φ = Vs/V (paper §4)
  s.vs = vs;
  s.ln_vs_vs0 = std::log(vs / vs0);
  return s;
}

template <int Dim>
double wall_normal_stress(const Vec<Dim>& force_on_wall, const Vec<Dim>& normal, double length) {
  return force_on_wall.dot(normal) / length;  // σ = F·n / L (docs/observables.md)
}

template <int Dim>
Mat<Dim> love_weber_stress(const points::PointSet<Dim>& points, double area) {
  Mat<Dim> sum = Mat<Dim>::Zero();
  for (std::size_t p = 0; p < points.size(); ++p) sum += points.sigma[p] * points.volume[p];
  return sum / area;  // σ̄ = (1/V) Σ_p σ_p V_p (docs/observables.md)
}

template double wall_normal_stress<2>(const Vec<2>&, const Vec<2>&, double);
template double wall_normal_stress<3>(const Vec<3>&, const Vec<3>&, double);
template Mat<2> love_weber_stress<2>(const points::PointSet<2>&, double);
template Mat<3> love_weber_stress<3>(const points::PointSet<3>&, double);

Coverage domain_coverage(const points::PointSet<2>& points, const Box& box, double pixel,
                         std::int64_t max_pixels) {
  const std::size_t n = points.size();
  // The domains' edges F D (columns) and the raster's extent: the box and every domain.
  std::vector<Mat<2>> edges(n);
  Vec<2> lo(box.x_min, box.y_min), hi(box.x_max, box.y_max);
  for (std::size_t p = 0; p < n; ++p) {
    edges[p] = points.F[p] * points.domain[p];
    const Vec<2> half = edges[p].cwiseAbs().rowwise().sum();  // half the bounding box
    lo = lo.cwiseMin(points.x[p] - half);
    hi = hi.cwiseMax(points.x[p] + half);
  }
  const Vec<2> extent = hi - lo;
  pixel = std::max(pixel, std::sqrt(extent.prod() / static_cast<double>(max_pixels)));
  std::int64_t nx = 0, ny = 0;
  for (;; pixel *= 1.01) {  // the raster over the extent, at most max_pixels
    nx = static_cast<std::int64_t>(std::ceil(extent[0] / pixel)) + 1;
    ny = static_cast<std::int64_t>(std::ceil(extent[1] / pixel)) + 1;
    if (nx * ny <= max_pixels) break;
  }
  std::vector<std::int32_t> last(static_cast<std::size_t>(nx * ny), -1);  // last grain seen
  std::vector<std::uint16_t> grains(last.size(), 0);                      // grains covering
  for (std::size_t p = 0; p < n; ++p) {
    const Mat<2>& e = edges[p];
    const double det = e.determinant();
    if (!(std::fabs(det) > 0)) continue;
    const Mat<2> inv = e.inverse();
    const Vec<2> half = e.cwiseAbs().rowwise().sum();
    const Vec<2> a = (points.x[p] - half - lo) / pixel, b = (points.x[p] + half - lo) / pixel;
    // pixel i covers [lo + i pixel, lo + (i + 1) pixel): its centre lo + (i + 1/2) pixel
    const auto i0 = std::max<std::int64_t>(0, static_cast<std::int64_t>(std::ceil(a[0] - 0.5)));
    const auto i1 =
        std::min<std::int64_t>(nx - 1, static_cast<std::int64_t>(std::floor(b[0] - 0.5)));
    const auto j0 = std::max<std::int64_t>(0, static_cast<std::int64_t>(std::ceil(a[1] - 0.5)));
    const auto j1 =
        std::min<std::int64_t>(ny - 1, static_cast<std::int64_t>(std::floor(b[1] - 0.5)));
    const std::int32_t g = points.grain[p];
    for (std::int64_t j = j0; j <= j1; ++j)
      for (std::int64_t i = i0; i <= i1; ++i) {
        const Vec<2> c =
            lo + pixel * Vec<2>(static_cast<double>(i) + 0.5, static_cast<double>(j) + 0.5);
        const Vec<2> s = inv * (c - points.x[p]);  // c = x_p + F D s
        if (std::fabs(s[0]) > 1.0 || std::fabs(s[1]) > 1.0) continue;
        const auto k = static_cast<std::size_t>(j * nx + i);
        if (last[k] == g) continue;
        last[k] = g;
        if (grains[k] < std::numeric_limits<std::uint16_t>::max()) ++grains[k];
      }
  }
  // Pixels whose centres lo + (i + 1/2) pixel lie in the box: i in [ib[0], ib[1]), j in
  // [jb[0], jb[1]).
  const auto first_inside = [&](double edge, double origin, std::int64_t n) {
    return std::clamp<std::int64_t>(
        static_cast<std::int64_t>(std::ceil((edge - origin) / pixel - 0.5)), 0, n);
  };
  const std::int64_t ib[2] = {first_inside(box.x_min, lo[0], nx),
                              first_inside(box.x_max, lo[0], nx)};
  const std::int64_t jb[2] = {first_inside(box.y_min, lo[1], ny),
                              first_inside(box.y_max, lo[1], ny)};
  const auto in_box = [&](std::int64_t i, std::int64_t j) {
    return i >= ib[0] && i < ib[1] && j >= jb[0] && j < jb[1];
  };
  Coverage out;
  out.pixel = pixel;
  const double area = pixel * pixel;
  std::int64_t inside = 0, beyond = 0, extra = 0;
  for (std::int64_t j = 0; j < ny; ++j)
    for (std::int64_t i = 0; i < nx; ++i) {
      const auto count = grains[static_cast<std::size_t>(j * nx + i)];
      if (count == 0) continue;
      extra += count - 1;
      ++(in_box(i, j) ? inside : beyond);
    }
  // Voids: the 4-connected components of uncovered pixels inside the box (flood fill, visited
  // pixels marked last = -2). A void bordered by one grain only and not by a wall is a gap inside
  // that grain (slivers of the seeding's tiling); the others are pores.
  double weighted = 0, pore_area = 0, gap_area = 0;
  std::vector<std::int64_t> stack;
  for (std::int64_t start = 0; start < nx * ny; ++start) {
    const auto s0 = static_cast<std::size_t>(start);
    if (grains[s0] != 0 || last[s0] == -2 || !in_box(start % nx, start / nx)) continue;
    std::int64_t pixels = 0;
    std::int32_t first = -1;  // a grain bordering the void
    bool pore = false;        // bordered by two grains or by a wall
    last[s0] = -2;
    stack.push_back(start);
    while (!stack.empty()) {
      const std::int64_t k = stack.back();
      stack.pop_back();
      ++pixels;
      const std::int64_t i = k % nx, j = k / nx;
      const std::int64_t next[4][2] = {{i - 1, j}, {i + 1, j}, {i, j - 1}, {i, j + 1}};
      for (const auto& [a, b] : next) {
        if (a < 0 || b < 0 || a >= nx || b >= ny || !in_box(a, b)) {
          pore = true;  // the void reaches a wall
          continue;
        }
        const auto q = static_cast<std::size_t>(b * nx + a);
        if (grains[q] != 0) {  // covered: last[q] is one of its grains
          if (first < 0) first = last[q];
          pore = pore || last[q] != first;
          continue;
        }
        if (last[q] == -2) continue;
        last[q] = -2;
        stack.push_back(b * nx + a);
      }
    }
    const double a = static_cast<double>(pixels) * area;
    if (!pore) {
      gap_area += a;
      continue;
    }
    weighted += a * std::sqrt(4 * a / std::numbers::pi);
    pore_area += a;
  }
  out.pore_diameter = pore_area > 0 ? weighted / pore_area : 0.0;
  out.pores = pore_area;
  out.gaps = gap_area;
  out.covered = static_cast<double>(inside) * area;
  out.outside = static_cast<double>(beyond) * area;
  out.overlap = static_cast<double>(extra) * area;
  return out;
}

std::vector<ContactImpulse> contact_impulses(const contact::Problem<2>& problem) {
  return contact_impulses(problem, {});
}

std::vector<ContactImpulse> contact_impulses(
    const contact::Problem<2>& problem, const std::function<Vec<2>(std::int64_t)>& node_position) {
  std::vector<ContactImpulse> out;
  out.reserve(problem.contacts.size());
  for (const auto& c : problem.contacts) {
    ContactImpulse ci;
    const auto& sb = problem.slots[static_cast<std::size_t>(c.b)];
    ci.a = c.a >= 0 ? problem.slots[static_cast<std::size_t>(c.a)].grain : -1 - c.wall;
    ci.b = sb.grain;
    ci.normal_impulse = c.impulse.dot(c.normal);  // impulse on B along the normal from A to B
    ci.impulse = c.impulse;
    ci.normal = c.normal;
    if (node_position) ci.position = node_position(sb.node);
    out.push_back(ci);
  }
  return out;
}

std::vector<PairImpulse> pair_impulses(std::span<const ContactImpulse> contacts,
                                       std::int64_t n_grains) {
  // Normal impulse summed per pair of bodies over all its contact nodes (walls: a < 0).
  std::map<std::pair<std::int32_t, std::int32_t>, double> sums;
  for (const auto& c : contacts) {
    if (c.b < 0 || c.b >= n_grains || c.a >= n_grains || c.a == c.b) continue;
    sums[{std::min(c.a, c.b), std::max(c.a, c.b)}] += c.normal_impulse;
  }
  std::vector<PairImpulse> out;
  out.reserve(sums.size());
  for (const auto& [key, p] : sums) out.push_back({key.first, key.second, p});
  return out;
}

double contact_threshold(std::span<const PairImpulse> pairs, const CoordinationSettings& settings) {
  double largest = 0;
  for (const auto& p : pairs) largest = std::max(largest, p.normal_impulse);
  return settings.relative_threshold * largest;
}

Coordination coordination(std::span<const ContactImpulse> contacts, std::int64_t n_grains,
                          const CoordinationSettings& settings) {
  return coordination_of_pairs(pair_impulses(contacts, n_grains), n_grains, settings);
}

template <int Dim>
std::vector<PairImpulse> pair_impulses(const contact::Problem<Dim>& problem,
                                       std::int64_t n_grains) {
  // As contact_impulses followed by pair_impulses(contacts): the same sums in the same order.
  std::map<std::pair<std::int32_t, std::int32_t>, double> sums;
  for (const auto& c : problem.contacts) {
    const auto& sb = problem.slots[static_cast<std::size_t>(c.b)];
    const std::int32_t a =
        c.a >= 0 ? problem.slots[static_cast<std::size_t>(c.a)].grain : -1 - c.wall;
    const std::int32_t b = sb.grain;
    if (b < 0 || b >= n_grains || a >= n_grains || a == b) continue;
    sums[{std::min(a, b), std::max(a, b)}] += c.impulse.dot(c.normal);
  }
  std::vector<PairImpulse> out;
  out.reserve(sums.size());
  for (const auto& [key, p] : sums) out.push_back({key.first, key.second, p});
  return out;
}

template std::vector<PairImpulse> pair_impulses<2>(const contact::Problem<2>&, std::int64_t);
template std::vector<PairImpulse> pair_impulses<3>(const contact::Problem<3>&, std::int64_t);

Coordination coordination_of_pairs(std::span<const PairImpulse> pairs, std::int64_t n_grains,
                                   const CoordinationSettings& settings) {
  Coordination out;
  const auto n = static_cast<std::size_t>(std::max<std::int64_t>(n_grains, 0));
  const double threshold = contact_threshold(pairs, settings);
  std::vector<std::pair<std::int32_t, std::int32_t>> edges;
  std::vector<int> degree(n, 0);  // contacts per grain
  for (const auto& p : pairs) {
    if (!(p.normal_impulse > threshold && p.normal_impulse > 0)) continue;
    if (p.a >= 0) {
      edges.emplace_back(p.a, p.b);
    } else {
      ++out.wall_contacts;
      if (settings.walls_hold_grains) ++degree[static_cast<std::size_t>(p.b)];
    }
  }
  out.all_pairs = static_cast<std::int64_t>(edges.size());

  // Remove grains with fewer than two contacts until none is left (rattlers).
  for (const auto& [a, b] : edges) {
    ++degree[static_cast<std::size_t>(a)];
    ++degree[static_cast<std::size_t>(b)];
  }
  std::vector<char> kept(n, 1);
  std::vector<char> edge_alive(edges.size(), 1);
  for (bool changed = true; changed;) {
    changed = false;
    for (std::size_t g = 0; g < kept.size(); ++g)
      if (kept[g] && degree[g] < 2) {
        kept[g] = 0;
        changed = true;
      }
    for (std::size_t e = 0; e < edges.size(); ++e) {
      if (!edge_alive[e]) continue;
      const auto a = static_cast<std::size_t>(edges[e].first);
      const auto b = static_cast<std::size_t>(edges[e].second);
      if (!kept[a] || !kept[b]) {
        edge_alive[e] = 0;
        --degree[a];
        --degree[b];
      }
    }
  }
  out.kept.assign(kept.begin(), kept.end());
  out.grains = std::count(kept.begin(), kept.end(), 1);
  out.rattlers = static_cast<std::int64_t>(kept.size()) - out.grains;
  out.pairs = std::count(edge_alive.begin(), edge_alive.end(), 1);
  out.z = out.grains > 0 ? 2.0 * static_cast<double>(out.pairs) / static_cast<double>(out.grains)
                         : 0.0;  // Z = 2 N_pairs / N_grains (docs/observables.md)
  return out;
}

}  // namespace mpmcd::analysis
