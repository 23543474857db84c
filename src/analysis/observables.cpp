#include "mpmcd/analysis/observables.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <utility>

namespace mpmcd::analysis {

namespace {

bool near(double a, double b) {
  return std::fabs(a - b) <= 1e-12;
}

}  // namespace

std::optional<BoxWalls> find_box(std::span<const Plane> walls) {
  if (walls.size() != 4) return std::nullopt;
  int found[4] = {-1, -1, -1, -1};  // left, right, bottom, top
  for (std::size_t k = 0; k < walls.size(); ++k) {
    const Vec<2>& n = walls[k].normal;
    int slot = -1;
    if (near(n[1], 0) && near(n[0], 1)) slot = 0;
    if (near(n[1], 0) && near(n[0], -1)) slot = 1;
    if (near(n[0], 0) && near(n[1], 1)) slot = 2;
    if (near(n[0], 0) && near(n[1], -1)) slot = 3;
    if (slot < 0 || found[slot] >= 0) return std::nullopt;
    found[slot] = static_cast<int>(k);
  }
  BoxWalls b;
  b.left = static_cast<std::size_t>(found[0]);
  b.right = static_cast<std::size_t>(found[1]);
  b.bottom = static_cast<std::size_t>(found[2]);
  b.top = static_cast<std::size_t>(found[3]);
  return b;
}

Box box_at(std::span<const Plane> walls, const BoxWalls& b, double t) {
  auto at = [&](std::size_t k, int axis) {
    return walls[k].point[axis] + t * walls[k].velocity[axis];
  };
  Box box;
  box.x_min = at(b.left, 0);
  box.x_max = at(b.right, 0);
  box.y_min = at(b.bottom, 1);
  box.y_max = at(b.top, 1);
  return box;
}

double wall_length(const Box& box, const BoxWalls& walls, std::size_t k) {
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

double wall_normal_stress(const Vec<2>& force_on_wall, const Vec<2>& normal, double length) {
  return force_on_wall.dot(normal) / length;  // σ = F·n / L (docs/observables.md)
}

Mat<2> love_weber_stress(const points::PointSet<2>& points, double area) {
  Mat<2> sum = Mat<2>::Zero();
  for (std::size_t p = 0; p < points.size(); ++p) sum += points.sigma[p] * points.volume[p];
  return sum / area;  // σ̄ = (1/V) Σ_p σ_p V_p (docs/observables.md)
}

std::vector<ContactImpulse> contact_impulses(const contact::Problem<2>& problem) {
  std::vector<ContactImpulse> out;
  out.reserve(problem.contacts.size());
  for (const auto& c : problem.contacts) {
    ContactImpulse ci;
    ci.a = c.a >= 0 ? problem.slots[static_cast<std::size_t>(c.a)].grain : -1 - c.wall;
    ci.b = problem.slots[static_cast<std::size_t>(c.b)].grain;
    ci.normal_impulse = c.impulse.dot(c.normal);  // impulse on B along the normal from A to B
    out.push_back(ci);
  }
  return out;
}

Coordination coordination(std::span<const ContactImpulse> contacts, std::int64_t n_grains,
                          const CoordinationSettings& settings) {
  Coordination out;
  // Normal impulse summed per pair of bodies over all its contact nodes (walls: a < 0).
  const auto n = static_cast<std::size_t>(std::max<std::int64_t>(n_grains, 0));
  std::map<std::pair<std::int32_t, std::int32_t>, double> pairs, walls;
  for (const auto& c : contacts) {
    if (c.b < 0 || c.b >= n_grains || c.a >= n_grains || c.a == c.b) continue;
    if (c.a < 0)
      walls[{c.a, c.b}] += c.normal_impulse;
    else
      pairs[{std::min(c.a, c.b), std::max(c.a, c.b)}] += c.normal_impulse;
  }
  double largest = 0;
  for (const auto& [key, p] : pairs) largest = std::max(largest, p);
  for (const auto& [key, p] : walls) largest = std::max(largest, p);
  const double threshold = settings.relative_threshold * largest;
  std::vector<std::pair<std::int32_t, std::int32_t>> edges;
  for (const auto& [key, p] : pairs)
    if (p > threshold && p > 0) edges.push_back(key);
  out.all_pairs = static_cast<std::int64_t>(edges.size());
  std::vector<int> degree(n, 0);  // contacts per grain
  for (const auto& [key, p] : walls)
    if (p > threshold && p > 0) {
      ++out.wall_contacts;
      if (settings.walls_hold_grains) ++degree[static_cast<std::size_t>(key.second)];
    }

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
  out.grains = std::count(kept.begin(), kept.end(), 1);
  out.rattlers = static_cast<std::int64_t>(kept.size()) - out.grains;
  out.pairs = std::count(edge_alive.begin(), edge_alive.end(), 1);
  out.z = out.grains > 0 ? 2.0 * static_cast<double>(out.pairs) / static_cast<double>(out.grains)
                         : 0.0;  // Z = 2 N_pairs / N_grains (docs/observables.md)
  return out;
}

}  // namespace mpmcd::analysis
