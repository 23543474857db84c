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

namespace {

// The coverage raster of domain_coverage in Dim dimensions (docs/observables.md, "Coverage"):
// pixels (voxels) indexed k = i + n_x (j + n_y l), the voids 2 Dim-connected.
template <int Dim>
Coverage coverage_of(const points::PointSet<Dim>& points, const Box& box, double pixel,
                     std::int64_t max_pixels) {
  const std::size_t n = points.size();
  // The domains' edges F D (columns) and the raster's extent: the box and every domain.
  std::vector<Mat<Dim>> edges(n);
  Vec<Dim> box_lo, box_hi;
  box_lo[0] = box.x_min, box_lo[1] = box.y_min, box_hi[0] = box.x_max, box_hi[1] = box.y_max;
  if constexpr (Dim == 3) box_lo[2] = box.z_min, box_hi[2] = box.z_max;
  Vec<Dim> lo = box_lo, hi = box_hi;
  for (std::size_t p = 0; p < n; ++p) {
    edges[p] = points.F[p] * points.domain[p];
    const Vec<Dim> half = edges[p].cwiseAbs().rowwise().sum();  // half the bounding box
    lo = lo.cwiseMin(points.x[p] - half);
    hi = hi.cwiseMax(points.x[p] + half);
  }
  const Vec<Dim> extent = hi - lo;
  const double per_pixel = extent.prod() / static_cast<double>(max_pixels);
  pixel = std::max(pixel, Dim == 3 ? std::cbrt(per_pixel) : std::sqrt(per_pixel));
  std::int64_t size[Dim], stride[Dim], total = 1;
  for (;; pixel *= 1.01) {  // the raster over the extent, at most max_pixels
    total = 1;
    for (int a = 0; a < Dim; ++a) {
      size[a] = static_cast<std::int64_t>(std::ceil(extent[a] / pixel)) + 1;
      stride[a] = total;
      total *= size[a];
    }
    if (total <= max_pixels) break;
  }
  std::vector<std::int32_t> last(static_cast<std::size_t>(total), -1);  // last grain seen
  std::vector<std::uint16_t> grains(last.size(), 0);                    // grains covering
  for (std::size_t p = 0; p < n; ++p) {
    const Mat<Dim>& e = edges[p];
    const double det = e.determinant();
    if (!(std::fabs(det) > 0)) continue;
    const Mat<Dim> inv = e.inverse();
    const Vec<Dim> half = e.cwiseAbs().rowwise().sum();
    const Vec<Dim> a = (points.x[p] - half - lo) / pixel, b = (points.x[p] + half - lo) / pixel;
    // pixel i covers [lo + i pixel, lo + (i + 1) pixel): its centre lo + (i + 1/2) pixel
    std::int64_t from[Dim], to[Dim], at[Dim];
    bool empty = false;
    for (int d = 0; d < Dim; ++d) {
      from[d] = std::max<std::int64_t>(0, static_cast<std::int64_t>(std::ceil(a[d] - 0.5)));
      to[d] =
          std::min<std::int64_t>(size[d] - 1, static_cast<std::int64_t>(std::floor(b[d] - 0.5)));
      at[d] = from[d];
      empty = empty || from[d] > to[d];
    }
    if (empty) continue;
    const std::int32_t g = points.grain[p];
    for (int d = 0; d < Dim;) {  // every pixel of the domain's bounding box, i fastest
      Vec<Dim> c;
      std::int64_t k = 0;
      for (int q = 0; q < Dim; ++q) {
        c[q] = static_cast<double>(at[q]) + 0.5;
        k += at[q] * stride[q];
      }
      c = lo + pixel * c;
      const Vec<Dim> s = inv * (c - points.x[p]);  // c = x_p + F D s
      bool in = true;
      for (int q = 0; q < Dim; ++q) in = in && !(std::fabs(s[q]) > 1.0);
      const auto kk = static_cast<std::size_t>(k);
      if (in && last[kk] != g) {
        last[kk] = g;
        if (grains[kk] < std::numeric_limits<std::uint16_t>::max()) ++grains[kk];
      }
      for (d = 0; d < Dim && ++at[d] > to[d]; ++d) at[d] = from[d];  // the next pixel
    }
  }
  // Pixels whose centres lo + (i + 1/2) pixel lie in the box: i in [inside[a][0], inside[a][1])
  // along each axis a.
  std::int64_t inside[Dim][2];
  for (int d = 0; d < Dim; ++d)
    for (int side = 0; side < 2; ++side)
      inside[d][side] = std::clamp<std::int64_t>(
          static_cast<std::int64_t>(std::ceil(((side ? box_hi : box_lo)[d] - lo[d]) / pixel - 0.5)),
          0, size[d]);
  const auto coords = [&](std::int64_t k, std::int64_t* c) {
    for (int d = 0; d < Dim; ++d) c[d] = (k / stride[d]) % size[d];
  };
  const auto in_box = [&](const std::int64_t* c) {
    for (int d = 0; d < Dim; ++d)
      if (c[d] < inside[d][0] || c[d] >= inside[d][1]) return false;
    return true;
  };
  Coverage out;
  out.pixel = pixel;
  const double measure = Dim == 3 ? pixel * pixel * pixel : pixel * pixel;
  std::int64_t covered = 0, beyond = 0, extra = 0;
  std::int64_t c[Dim];
  for (std::int64_t k = 0; k < total; ++k) {
    const auto count = grains[static_cast<std::size_t>(k)];
    if (count == 0) continue;
    extra += count - 1;
    coords(k, c);
    ++(in_box(c) ? covered : beyond);
  }
  // Voids: the 2 Dim-connected components of uncovered pixels inside the box (flood fill,
  // visited pixels marked last = -2). A void bordered by one grain only and not by a wall is a
  // gap inside that grain (slivers of the seeding's tiling); the others are pores.
  double weighted = 0, pore_measure = 0, gap_measure = 0;
  std::vector<std::int64_t> stack;
  for (std::int64_t start = 0; start < total; ++start) {
    const auto s0 = static_cast<std::size_t>(start);
    if (grains[s0] != 0 || last[s0] == -2) continue;
    coords(start, c);
    if (!in_box(c)) continue;
    std::int64_t pixels = 0;
    std::int32_t first = -1;  // a grain bordering the void
    bool pore = false;        // bordered by two grains or by a wall
    last[s0] = -2;
    stack.push_back(start);
    while (!stack.empty()) {
      const std::int64_t k = stack.back();
      stack.pop_back();
      ++pixels;
      coords(k, c);
      for (int d = 0; d < Dim; ++d)
        for (const std::int64_t step : {-1, 1}) {  // the neighbours -e_d, +e_d
          c[d] += step;
          const bool wall = !in_box(c);  // (outside the raster is outside the box)
          c[d] -= step;
          if (wall) {
            pore = true;  // the void reaches a wall
            continue;
          }
          const std::int64_t next = k + step * stride[d];
          const auto q = static_cast<std::size_t>(next);
          if (grains[q] != 0) {  // covered: last[q] is one of its grains
            if (first < 0) first = last[q];
            pore = pore || last[q] != first;
            continue;
          }
          if (last[q] == -2) continue;
          last[q] = -2;
          stack.push_back(next);
        }
    }
    const double v = static_cast<double>(pixels) * measure;
    if (!pore) {
      gap_measure += v;
      continue;
    }
    // equivalent diameter: sqrt(4 A / π) of a disk, (6 V / π)^(1/3) of a sphere
    weighted +=
        v * (Dim == 3 ? std::cbrt(6 * v / std::numbers::pi) : std::sqrt(4 * v / std::numbers::pi));
    pore_measure += v;
  }
  out.pore_diameter = pore_measure > 0 ? weighted / pore_measure : 0.0;
  out.pores = pore_measure;
  out.gaps = gap_measure;
  out.covered = static_cast<double>(covered) * measure;
  out.outside = static_cast<double>(beyond) * measure;
  out.overlap = static_cast<double>(extra) * measure;
  return out;
}

}  // namespace

Coverage domain_coverage(const points::PointSet<2>& points, const Box& box, double pixel,
                         std::int64_t max_pixels) {
  return coverage_of<2>(points, box, pixel, max_pixels);
}

Coverage domain_coverage(const points::PointSet<3>& points, const Box& box, double voxel,
                         std::int64_t max_voxels) {
  return coverage_of<3>(points, box, voxel, max_voxels);
}

std::vector<ContactImpulse> contact_impulses(const contact::Problem<2>& problem) {
  return contact_impulses(problem, {});
}

namespace {

template <int Dim>
std::vector<ContactImpulseOf<Dim>> impulses_of(
    const contact::Problem<Dim>& problem,
    const std::function<Vec<Dim>(std::int64_t)>& node_position) {
  std::vector<ContactImpulseOf<Dim>> out;
  out.reserve(problem.contacts.size());
  for (const auto& c : problem.contacts) {
    ContactImpulseOf<Dim> ci;
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

template <int Dim>
std::vector<PairImpulse> pair_sums(std::span<const ContactImpulseOf<Dim>> contacts,
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

}  // namespace

std::vector<ContactImpulse> contact_impulses(
    const contact::Problem<2>& problem, const std::function<Vec<2>(std::int64_t)>& node_position) {
  return impulses_of<2>(problem, node_position);
}

std::vector<ContactImpulseOf<3>> contact_impulses(
    const contact::Problem<3>& problem, const std::function<Vec<3>(std::int64_t)>& node_position) {
  return impulses_of<3>(problem, node_position);
}

std::vector<PairImpulse> pair_impulses(std::span<const ContactImpulse> contacts,
                                       std::int64_t n_grains) {
  return pair_sums<2>(contacts, n_grains);
}

std::vector<PairImpulse> pair_impulses(std::span<const ContactImpulseOf<3>> contacts,
                                       std::int64_t n_grains) {
  return pair_sums<3>(contacts, n_grains);
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
