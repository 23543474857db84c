// Overlap check of grain outlines at input (docs/robustness.md, "Overlapping grains").
#include "mpmcd/packing/overlap.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <unordered_map>

namespace mpmcd::packing {

namespace {

struct Box {
  double lo[2], hi[2];
};

Box bounds(const Outline& o) {
  if (o.radius > 0.0)
    return {{o.x0 - o.radius, o.y0 - o.radius}, {o.x0 + o.radius, o.y0 + o.radius}};
  return {{o.x0, o.y0}, {o.x1, o.y1}};
}

double size_of(const Outline& o) {
  return o.radius > 0.0 ? 2.0 * o.radius : std::min(o.x1 - o.x0, o.y1 - o.y0);
}

// Penetration depth of a disk into a rectangle [m] (> 0: they overlap).
double disk_rectangle(const Outline& d, const Outline& r) {
  const double qx = std::clamp(d.x0, r.x0, r.x1), qy = std::clamp(d.y0, r.y0, r.y1);
  if (qx == d.x0 && qy == d.y0)  // centre inside: the disk must move this far to get out
    return d.radius + std::min({d.x0 - r.x0, r.x1 - d.x0, d.y0 - r.y0, r.y1 - d.y0});
  return d.radius - std::hypot(d.x0 - qx, d.y0 - qy);
}

// Penetration depth of two outlines [m] (> 0: they overlap).
double depth(const Outline& a, const Outline& b) {
  const bool da = a.radius > 0.0, db = b.radius > 0.0;
  if (da && db) return a.radius + b.radius - std::hypot(a.x0 - b.x0, a.y0 - b.y0);
  if (da) return disk_rectangle(a, b);
  if (db) return disk_rectangle(b, a);
  const double ox = std::min(a.x1, b.x1) - std::max(a.x0, b.x0);
  const double oy = std::min(a.y1, b.y1) - std::max(a.y0, b.y0);
  return ox > 0.0 && oy > 0.0 ? std::min(ox, oy) : -1.0;
}

}  // namespace

std::optional<Overlap> find_overlap(const std::vector<Outline>& outlines, double tolerance) {
  const std::size_t n = outlines.size();
  if (n < 2) return std::nullopt;
  // Cell width: the largest disk diameter (the largest outline without disks). Outlines wider
  // than a cell are "big" and compared with every other outline.
  double w = 0.0, wmax = 0.0;
  double x_lo = std::numeric_limits<double>::infinity(), y_lo = x_lo;
  std::vector<Box> box(n);
  for (std::size_t i = 0; i < n; ++i) {
    box[i] = bounds(outlines[i]);
    const double extent = std::max(box[i].hi[0] - box[i].lo[0], box[i].hi[1] - box[i].lo[1]);
    if (outlines[i].radius > 0.0) w = std::max(w, extent);
    wmax = std::max(wmax, extent);
    x_lo = std::min(x_lo, box[i].lo[0]);
    y_lo = std::min(y_lo, box[i].lo[1]);
  }
  if (!(w > 0.0)) w = wmax;
  if (!(w > 0.0) || !std::isfinite(w)) return std::nullopt;
  std::optional<Overlap> best;
  const auto consider = [&](std::size_t i, std::size_t j) {
    const std::size_t a = std::min(i, j), b = std::max(i, j);
    if (best && (b > best->second || (b == best->second && a >= best->first))) return;
    const double d = depth(outlines[a], outlines[b]);
    const double s = std::min(size_of(outlines[a]), size_of(outlines[b]));
    if (d > tolerance * s) best = Overlap{a, b, d, s};
  };
  std::vector<std::size_t> big;
  std::unordered_map<std::uint64_t, std::vector<std::size_t>> cells;
  const auto cell = [&](std::int64_t ix, std::int64_t iy) {
    return (static_cast<std::uint64_t>(ix) << 32) ^ static_cast<std::uint64_t>(iy & 0xffffffff);
  };
  std::vector<std::int64_t> cx(n, 0), cy(n, 0);
  for (std::size_t i = 0; i < n; ++i) {
    const double extent = std::max(box[i].hi[0] - box[i].lo[0], box[i].hi[1] - box[i].lo[1]);
    if (extent > w) {
      big.push_back(i);
      continue;
    }
    cx[i] = static_cast<std::int64_t>(std::floor((box[i].lo[0] - x_lo) / w));
    cy[i] = static_cast<std::int64_t>(std::floor((box[i].lo[1] - y_lo) / w));
    cells[cell(cx[i], cy[i])].push_back(i);
  }
  // Two small outlines that overlap have lower corners less than w apart: neighbouring cells.
  for (const auto& [key, members] : cells) {
    const std::size_t i0 = members.front();
    for (std::int64_t dy = -1; dy <= 1; ++dy)
      for (std::int64_t dx = -1; dx <= 1; ++dx) {
        const auto it = cells.find(cell(cx[i0] + dx, cy[i0] + dy));
        if (it == cells.end()) continue;
        for (const std::size_t i : members)
          for (const std::size_t j : it->second)
            if (i < j) consider(i, j);
      }
  }
  for (const std::size_t i : big)
    for (std::size_t j = 0; j < n; ++j)
      if (j != i) consider(i, j);
  return best;
}

std::optional<Overlap> find_sphere_overlap(const Packing& packing, double tolerance) {
  const auto& s = packing.disks;
  const std::size_t n = s.size();
  if (n < 2) return std::nullopt;
  // Cells of the largest diameter w, keyed by the cell of each sphere's lower corner: two
  // overlapping spheres have lower corners less than w apart along each axis.
  double w = 0.0,
         lo[3] = {std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(),
                  std::numeric_limits<double>::infinity()};
  for (const auto& d : s) {
    w = std::max(w, 2.0 * d.radius);
    lo[0] = std::min(lo[0], d.x - d.radius);
    lo[1] = std::min(lo[1], d.y - d.radius);
    lo[2] = std::min(lo[2], d.z - d.radius);
  }
  if (!(w > 0.0) || !std::isfinite(w)) return std::nullopt;
  const auto key = [](std::int64_t ix, std::int64_t iy, std::int64_t iz) {
    return (static_cast<std::uint64_t>(ix & 0x1fffff) << 42) ^
           (static_cast<std::uint64_t>(iy & 0x1fffff) << 21) ^
           static_cast<std::uint64_t>(iz & 0x1fffff);
  };
  std::vector<std::array<std::int64_t, 3>> c(n);
  std::unordered_map<std::uint64_t, std::vector<std::size_t>> cells;
  for (std::size_t i = 0; i < n; ++i) {
    const double corner[3] = {s[i].x - s[i].radius, s[i].y - s[i].radius, s[i].z - s[i].radius};
    for (int a = 0; a < 3; ++a)
      c[i][a] = static_cast<std::int64_t>(std::floor((corner[a] - lo[a]) / w));
    cells[key(c[i][0], c[i][1], c[i][2])].push_back(i);
  }
  std::optional<Overlap> best;
  for (std::size_t i = 0; i < n; ++i)
    for (std::int64_t dz = -1; dz <= 1; ++dz)
      for (std::int64_t dy = -1; dy <= 1; ++dy)
        for (std::int64_t dx = -1; dx <= 1; ++dx) {
          const auto it = cells.find(key(c[i][0] + dx, c[i][1] + dy, c[i][2] + dz));
          if (it == cells.end()) continue;
          for (const std::size_t j : it->second) {
            if (j <= i) continue;
            // Keep the pair first in (second, first) order.
            if (best && (j > best->second || (j == best->second && i >= best->first))) continue;
            const double depth = s[i].radius + s[j].radius -
                                 std::sqrt((s[i].x - s[j].x) * (s[i].x - s[j].x) +
                                           (s[i].y - s[j].y) * (s[i].y - s[j].y) +
                                           (s[i].z - s[j].z) * (s[i].z - s[j].z));
            const double size = 2.0 * std::min(s[i].radius, s[j].radius);
            if (depth > tolerance * size) best = Overlap{i, j, depth, size};
          }
        }
  return best;
}

std::optional<Overlap> find_grain_overlap(const Packing& packing, double tolerance) {
  if (packing.dimension == 3) return find_sphere_overlap(packing, tolerance);
  return find_overlap(disk_outlines(packing), tolerance);
}

std::vector<Outline> disk_outlines(const Packing& packing) {
  std::vector<Outline> out;
  out.reserve(packing.disks.size());
  for (const auto& d : packing.disks) out.push_back({d.x, d.y, 0.0, 0.0, d.radius});
  return out;
}

}  // namespace mpmcd::packing
