#include "mpmcd/analysis/grains.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include <Eigen/Eigenvalues>

#include "mpmcd/contact/problem.hpp"

namespace mpmcd::analysis {

namespace {

// z component of (b - a) × (c - a): positive when a, b, c turn counter-clockwise.
double cross(const Vec<2>& a, const Vec<2>& b, const Vec<2>& c) {
  return (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
}

// Convex hull of `pts` by Andrew's monotone chain (Andrew 1979), in place: the hull's vertices
// counter-clockwise in pts[0, returned count). Sorts pts.
std::size_t convex_hull(std::vector<Vec<2>>& pts, std::vector<Vec<2>>& hull) {
  const std::size_t n = pts.size();
  if (n < 3) return 0;
  std::sort(pts.begin(), pts.end(), [](const Vec<2>& a, const Vec<2>& b) {
    return a[0] < b[0] || (a[0] == b[0] && a[1] < b[1]);
  });
  hull.resize(2 * n);
  std::size_t k = 0;
  for (std::size_t i = 0; i < n; ++i) {  // lower hull
    while (k >= 2 && cross(hull[k - 2], hull[k - 1], pts[i]) <= 0) --k;
    hull[k++] = pts[i];
  }
  for (std::size_t i = n - 1, t = k + 1; i-- > 0;) {  // upper hull
    while (k >= t && cross(hull[k - 2], hull[k - 1], pts[i]) <= 0) --k;
    hull[k++] = pts[i];
  }
  return k - 1;  // the last vertex repeats the first
}

// Symmetric part of m.
template <int Dim>
Mat<Dim> sym(const Mat<Dim>& m) {
  return 0.5 * (m + m.transpose());
}

// grain_state in Dim dimensions (the corners of the 2D hull only when Dim = 2).
template <int Dim>
GrainStateOf<Dim> state_of(const points::PointSet<Dim>& points, std::int64_t begin,
                           std::int64_t end, std::vector<Vec<2>>* corners) {
  GrainStateOf<Dim> g;
  Vec<Dim> first = Vec<Dim>::Zero();
  Mat<Dim> sigma = Mat<Dim>::Zero();
  double szz = 0;
  for (std::int64_t p = begin; p < end; ++p) {
    const auto i = static_cast<std::size_t>(p);
    const double v = points.volume[i];
    g.area += v;  // A_g = Σ V_p
    first += v * points.x[i];
    sigma += v * points.sigma[i];
    if constexpr (Dim == 2) szz += v * points.sigma_zz[i];
  }
  if (!(g.area > 0)) return g;
  g.centroid = first / g.area;  // x_g = Σ V_p x_p / A_g
  g.stress = sigma / g.area;    // σ̄_g = Σ σ_p V_p / Σ V_p (docs/observables.md)
  g.stress_zz = szz / g.area;
  // Second moment about x_g: the points' parallel-axis terms plus each domain's own moment
  // (V/3) Σ_k e_k⊗e_k (∫ s_i s_j ds / ∫ ds = δ_ij/3 on [-1, 1]^Dim).
  if (corners) corners->clear();
  for (std::int64_t p = begin; p < end; ++p) {
    const auto i = static_cast<std::size_t>(p);
    const Vec<Dim> d = points.x[i] - g.centroid;
    const Mat<Dim> e = points.F[i] * points.domain[i];
    g.moment += points.volume[i] * (d * d.transpose() + e * e.transpose() / 3.0);
    if constexpr (Dim == 2) {
      if (!corners) continue;
      const Vec<2> e1 = e.col(0), e2 = e.col(1);
      corners->push_back(points.x[i] + e1 + e2);
      corners->push_back(points.x[i] + e1 - e2);
      corners->push_back(points.x[i] - e1 + e2);
      corners->push_back(points.x[i] - e1 - e2);
    }
  }
  return g;
}

// Eigenvalues of a symmetric 3x3 tensor, ascending.
Vec<3> eigenvalues(const Mat<3>& m) {
  return Eigen::SelfAdjointEigenSolver<Mat<3>>(sym<3>(m), Eigen::EigenvaluesOnly).eigenvalues();
}

}  // namespace

GrainState grain_state(const points::PointSet<2>& points, std::int64_t begin, std::int64_t end,
                       std::vector<Vec<2>>* corners) {
  return state_of<2>(points, begin, end, corners);
}

GrainStateOf<3> grain_state(const points::PointSet<3>& points, std::int64_t begin,
                            std::int64_t end) {
  return state_of<3>(points, begin, end, nullptr);
}

std::vector<GrainState> grain_states(const points::PointSet<2>& points,
                                     std::span<const points::Grain> grains, bool hull) {
  std::vector<GrainState> out(grains.size());
  const auto n = static_cast<std::int64_t>(grains.size());
#pragma omp parallel if (n > 1)
  {
    std::vector<Vec<2>> corners, chain;  // per thread, reused across grains
#pragma omp for schedule(dynamic, 1)
    for (std::int64_t g = 0; g < n; ++g) {
      const auto& gr = grains[static_cast<std::size_t>(g)];
      GrainState s = grain_state(points, gr.begin, gr.end, hull ? &corners : nullptr);
      if (hull) {
        const std::size_t k = convex_hull(corners, chain);
        for (std::size_t i = 0; i < k; ++i) {  // shoelace area and edge lengths
          const Vec<2>& a = chain[i];
          const Vec<2>& b = chain[(i + 1) % k];
          s.hull_area += 0.5 * (a[0] * b[1] - b[0] * a[1]);
          s.hull_perimeter += (b - a).norm();
        }
      }
      out[static_cast<std::size_t>(g)] = s;
    }
  }
  return out;
}

std::vector<GrainStateOf<3>> grain_states(const points::PointSet<3>& points,
                                          std::span<const points::Grain> grains) {
  std::vector<GrainStateOf<3>> out(grains.size());
  const auto n = static_cast<std::int64_t>(grains.size());
#pragma omp parallel for schedule(dynamic, 1) if (n > 1)
  for (std::int64_t g = 0; g < n; ++g) {
    const auto& gr = grains[static_cast<std::size_t>(g)];
    out[static_cast<std::size_t>(g)] = grain_state(points, gr.begin, gr.end);
  }
  return out;
}

double mean_stress(const Mat<2>& s) {
  return 0.5 * (s(0, 0) + s(1, 1));  // σ_m = tr σ / 2 (in-plane)
}

double deviator_norm(const Mat<2>& s) {
  const Mat<2> dev = s - mean_stress(s) * Mat<2>::Identity();  // s = σ - σ_m I
  return std::sqrt((dev.array() * dev.array()).sum());         // |s| = sqrt(s:s)
}

double von_mises(const Mat<2>& s, double szz) {
  const double m = (s(0, 0) + s(1, 1) + szz) / 3.0;  // tr σ3 / 3
  const double dx = s(0, 0) - m, dy = s(1, 1) - m, dz = szz - m;
  // σ_vM = sqrt(3/2 S:S), S = σ3 - tr(σ3)/3 I (the off-diagonal σxy counted twice)
  return std::sqrt(1.5 * (dx * dx + dy * dy + dz * dz + 2 * s(0, 1) * s(1, 0)));
}

double mean_stress(const Mat<3>& s) {
  return s.trace() / 3.0;  // σ_m = tr σ / 3
}

double deviator_norm(const Mat<3>& s) {
  const Mat<3> dev = s - mean_stress(s) * Mat<3>::Identity();  // s = σ - σ_m I
  return std::sqrt((dev.array() * dev.array()).sum());         // |s| = sqrt(s:s)
}

Principal principal(const Mat<2>& m) {
  const double c = 0.5 * (m(0, 0) + m(1, 1));
  const double d = 0.5 * (m(0, 0) - m(1, 1)), o = 0.5 * (m(0, 1) + m(1, 0));
  const double r = std::hypot(d, o);  // Mohr's circle: eigenvalues c ± r
  Principal p;
  p.major = c + r;
  p.minor = c - r;
  double a = 0.5 * std::atan2(o, d) * 180.0 / std::numbers::pi;  // in (-90, 90]
  if (a <= -90.0) a += 180.0;
  p.angle = a;
  return p;
}

double aspect_ratio(const Mat<2>& moment) {
  const Principal p = principal(moment);
  return p.minor > 0 ? std::sqrt(p.major / p.minor) : 0.0;  // a/b of the equivalent ellipse
}

double aspect_ratio(const Mat<3>& moment) {
  const Vec<3> l = eigenvalues(moment);            // ascending
  return l[0] > 0 ? std::sqrt(l[2] / l[0]) : 0.0;  // a/c of the equivalent ellipsoid
}

double circularity(double area, double perimeter) {
  return perimeter > 0 ? 4.0 * std::numbers::pi * area / (perimeter * perimeter) : 0.0;
}

namespace {

template <int Dim>
std::vector<PairForceOf<Dim>> forces_of(std::span<const ContactImpulseOf<Dim>> contacts, double dt,
                                        std::span<const GrainStateOf<Dim>> grains,
                                        const CoordinationSettings& settings) {
  const auto n_grains = static_cast<std::int64_t>(grains.size());
  const auto sums = pair_impulses(contacts, n_grains);  // the pairs of Z, sorted by (a, b)
  const double threshold = contact_threshold(sums, settings);
  std::vector<PairForceOf<Dim>> out(sums.size());
  for (std::size_t k = 0; k < sums.size(); ++k) {
    out[k].a = sums[k].a;
    out[k].b = sums[k].b;
    out[k].normal_impulse = sums[k].normal_impulse;
    out[k].in_contact = sums[k].normal_impulse > threshold && sums[k].normal_impulse > 0;
  }
  const auto find = [&](std::int32_t a, std::int32_t b) {
    const auto it = std::lower_bound(out.begin(), out.end(), std::pair{a, b},
                                     [](const PairForceOf<Dim>& p, const std::pair<int, int>& key) {
                                       return std::pair{p.a, p.b} < key;
                                     });
    return static_cast<std::size_t>(it - out.begin());
  };
  std::vector<Vec<Dim>> weighted(out.size(), Vec<Dim>::Zero());  // Σ p_n n and Σ p_n x per pair
  std::vector<Vec<Dim>> at(out.size(), Vec<Dim>::Zero());
  for (const auto& c : contacts) {
    if (c.b < 0 || c.b >= n_grains || c.a >= n_grains || c.a == c.b) continue;
    // A pair stored as (min, max): the impulse of a contact named (b, a) is reversed.
    const bool flip = c.a > c.b;
    const std::size_t k = find(std::min(c.a, c.b), std::max(c.a, c.b));
    const double sign = flip ? -1.0 : 1.0;
    out[k].force += sign * contact::impulse_force<Dim>(c.impulse, dt);  // f = P/Δt
    ++out[k].nodes;
    weighted[k] += c.normal_impulse * sign * c.normal;
    at[k] += c.normal_impulse * c.position;
  }
  for (std::size_t k = 0; k < out.size(); ++k) {
    PairForceOf<Dim>& p = out[k];
    const double norm = weighted[k].norm();
    p.normal = norm > 0 ? Vec<Dim>(weighted[k] / norm) : Vec<Dim>::Zero();
    p.normal_force = p.force.dot(p.normal);
    if constexpr (Dim == 2)
      p.tangential_force = p.force.dot(Vec<2>(-p.normal[1], p.normal[0]));  // t = e_z × n
    else
      p.tangential_force = (p.force - p.normal_force * p.normal).norm();  // |F - f_n n|
    p.point = p.normal_impulse != 0 ? Vec<Dim>(at[k] / p.normal_impulse) : Vec<Dim>::Zero();
    const Vec<Dim>& xb = grains[static_cast<std::size_t>(p.b)].centroid;
    p.branch = xb - (p.a >= 0 ? grains[static_cast<std::size_t>(p.a)].centroid : p.point);
  }
  return out;
}

template <int Dim>
Mat<Dim> contact_stress_of(std::span<const PairForceOf<Dim>> pairs, double volume) {
  Mat<Dim> sum = Mat<Dim>::Zero();
  for (const auto& p : pairs)
    if (p.in_contact) sum += p.force * p.branch.transpose();
  return -sym<Dim>(sum) / volume;  // σ_c = -(1/V) Σ F ⊗ ℓ (tension positive; docs/observables.md)
}

template <int Dim>
Mat<Dim> grain_stress_of(std::span<const GrainStateOf<Dim>> grains, double volume) {
  Mat<Dim> sum = Mat<Dim>::Zero();
  for (const auto& g : grains) sum += g.area * g.stress;
  return sum / volume;  // Σ_g σ̄_g A_g / V
}

// R = (1/N_c) Σ n⊗n over the grain-grain pairs in contact between kept grains; the anisotropy
// and angle are left to the caller.
template <int Dim>
FabricOf<Dim> fabric_of(std::span<const PairForceOf<Dim>> pairs,
                        std::span<const std::uint8_t> kept) {
  FabricOf<Dim> f;
  for (const auto& p : pairs) {
    if (!p.in_contact || p.a < 0) continue;
    if (!kept.empty() &&
        (!kept[static_cast<std::size_t>(p.a)] || !kept[static_cast<std::size_t>(p.b)]))
      continue;
    f.tensor += p.normal * p.normal.transpose();
    ++f.contacts;
  }
  if (f.contacts > 0) f.tensor /= static_cast<double>(f.contacts);  // R = (1/N_c) Σ n⊗n
  return f;
}

}  // namespace

std::vector<PairForce> pair_forces(std::span<const ContactImpulse> contacts, double dt,
                                   std::span<const GrainState> grains,
                                   const CoordinationSettings& settings) {
  return forces_of<2>(contacts, dt, grains, settings);
}

std::vector<PairForceOf<3>> pair_forces(std::span<const ContactImpulseOf<3>> contacts, double dt,
                                        std::span<const GrainStateOf<3>> grains,
                                        const CoordinationSettings& settings) {
  return forces_of<3>(contacts, dt, grains, settings);
}

Mat<2> contact_stress(std::span<const PairForce> pairs, double volume) {
  return contact_stress_of<2>(pairs, volume);
}

Mat<3> contact_stress(std::span<const PairForceOf<3>> pairs, double volume) {
  return contact_stress_of<3>(pairs, volume);
}

Mat<2> mean_grain_stress(std::span<const GrainState> grains, double volume) {
  return grain_stress_of<2>(grains, volume);
}

Mat<3> mean_grain_stress(std::span<const GrainStateOf<3>> grains, double volume) {
  return grain_stress_of<3>(grains, volume);
}

Fabric fabric(std::span<const PairForce> pairs, std::span<const std::uint8_t> kept) {
  Fabric f = fabric_of<2>(pairs, kept);
  if (f.contacts == 0) return f;
  const Principal r = principal(f.tensor);
  f.anisotropy = 2.0 * (r.major - r.minor);  // a = 2 (R_1 - R_2) (Cantor et al. 2018)
  f.angle = r.angle;
  return f;
}

FabricOf<3> fabric(std::span<const PairForceOf<3>> pairs, std::span<const std::uint8_t> kept) {
  FabricOf<3> f = fabric_of<3>(pairs, kept);
  if (f.contacts == 0) return f;
  const Vec<3> r = eigenvalues(f.tensor);  // ascending
  f.anisotropy = 2.5 * (r[2] - r[0]);      // a = (5/2) (R_1 - R_3) (Azéma et al. 2013)
  return f;
}

Histogram histogram(std::span<const double> values, int bins, double lo, double hi) {
  Histogram h;
  if (bins < 1 || !(hi > lo)) return h;
  const double width = (hi - lo) / bins;
  h.edges.resize(static_cast<std::size_t>(bins) + 1);
  for (int i = 0; i <= bins; ++i) h.edges[static_cast<std::size_t>(i)] = lo + i * width;
  h.counts.assign(static_cast<std::size_t>(bins), 0);
  for (const double v : values) {
    if (!(v >= lo && v <= hi)) {
      ++h.outside;
      continue;
    }
    const auto i = std::min<std::int64_t>(static_cast<std::int64_t>((v - lo) / width), bins - 1);
    ++h.counts[static_cast<std::size_t>(i)];
  }
  const auto n = static_cast<double>(values.size());
  h.density.resize(h.counts.size());
  for (std::size_t i = 0; i < h.counts.size(); ++i)
    h.density[i] = n > 0 ? static_cast<double>(h.counts[i]) / (n * width) : 0.0;
  return h;
}

}  // namespace mpmcd::analysis
